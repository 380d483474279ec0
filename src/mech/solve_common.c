/* The two passes shared by every statics solver, their tangent (forward-mode) linearisation, and
 * the solve entry point.
 *
 * DESIGN (Jirasek et al. 2000 §Mech eqs. 1-22; Taylor-Hell 2005 §6.1-6.2, eqs. 6.3, 6.14-6.24,
 * 6.35-6.37).
 *
 * Frames. Segment i is a rigid rod with orientation quaternion q_i: H = q e_x (heading, along
 * the segment), L = q e_y, U = q e_z (U along the long semi-axis a of the section). World y is
 * up. The frame is obtained by composing rotations from the base outward:
 *     q_i = q_parent * B_i * exp(d_i Omega_i)
 * where q_parent is the parent's frame (the plant's base orientation for a root), B_i the fixed
 * branching rotation (divergence about H, deviation about the spun U, roll about the new H:
 * Taylor-Hell 6.2, applied as exact quaternions, the "text" version of erratum 8 with the
 * rotation rate of the joint itself), and exp(r) the rotation by the rotation vector r given in
 * LOCAL components. Because a rotation leaves its own axis fixed, the components of
 * d_i Omega_i are the same in the frames before and after the joint, so Omega_i (current) and the
 * rest rate are both stored in LOCAL (H, L, U) components and never need co-rotation (this fixes
 * erratum 10 of the Taylor-Hell digest, where they were kept in world components).
 *
 * Where Omega lives: Omega_i is the rotation rate of the joint at the PROXIMAL node of segment
 * i; the joint bends over the length d_i:
 *   staggered (default, second order): d_i = (l_parent + l_i)/2 for the first child of a node
 *     (the continuation), l_i/2 for a root (the clamp) and for lateral children. The joint is a
 *     series spring of the two half segments: compliance d/C = l_p/(2 C_p) + l_i/(2 C_i) and
 *     rest rotation d rest = (l_p rest_p + l_i rest_i)/2, per local component. Each segment's
 *     weight acts at its centroid. Segment headings then approximate the tangent at segment
 *     midpoints and node positions P_child = P_parent + l_parent H_parent are the midpoint rule
 *     of P' = H: error O(h^2).
 *   chain (the seeds, first order): d_i = l_i with C_i and rest_i; the segment's mass at its
 *     distal end.
 *
 * Forward pass (base to tip, topological order): q_i as above (exp by a short series for small
 * angles, exact otherwise; renormalised), proximal node P_i = P_parent + l_parent H_parent.
 *
 * Backward pass (tip to base): with F_c and M_c of the children already added into segment i's
 * accumulators,
 *     F_i = sum_c F_c + f_tip,i + w_i          (w_i = m'_i l_i g, f_tip = m_point g + tip force)
 *     M_i = sum_c M_c + H_i x (l_i (sum_c F_c + f_tip,i) + lever_i w_i) + tip moment
 * (moment about the proximal node of all loads carried; lever = l/2 staggered, l chain). This is
 * the recursion 6.15/6.20 with the sum over children 6.37; it equals the direct sum 6.14 (a test
 * checks it). The equilibrium of joint i (Jirasek eq. 16 with eq. 12) is
 *     R_i(Omega) = C_i (Omega_i - rest_i) - M_i^local = 0,      M^local = (M.H, M.L, M.U),
 * componentwise with C = (C_H, C_L, C_U) (errata 3 and 8: I_L = pi a^3 b/4 resists bending
 * about L).
 *
 * Residual and stopping: relative residual = max_i |R_i| / max_i |M_i| (the characteristic
 * moment; if every moment is 0, max_i |C_i (Omega_i - rest_i)|, and 0 if that is 0 too).
 *
 * Solvers (solve_relax.c, solve_newton.c) use these two passes; one pass = one forward + one
 * backward sweep, counted the same way for both, including the tangent sweeps of Newton.
 *
 * Tangent passes (Jacobian-vector products for Newton-Krylov): perturbing Omega by v, the world
 * rotation of frame i is dth_i = dth_parent + R_i J_r(d_i Omega_i) d_i v_i (J_r the right
 * Jacobian of SO(3)); loads are dead (fixed in world), so dM_i = sum_c dM_c + (dth_i x H_i) x
 * (l_i (F_i - w_i) + lever_i w_i), and dR_i = C_i v_i - R_i^T (dM_i - dth_i x M_i). The result is
 * the exact derivative of the discrete residual (a test compares it with finite differences).
 *
 * Ground contact (Jirasek et al. 2000 §2.8, penalty form): with a ground plane at height y0 and
 * stiffness k, the distal node X_i = P_i + l_i H_i of every segment below the plane receives the
 * upward force k (y0 - X_i.y), added to f_tip,i in the backward pass, so the contact force is a
 * function of the current Omega inside every solver: the relaxation's fixed point and the Newton
 * residual both include it. Its tangent: the nodes move by dP_i = dP_parent + l_parent
 * (dth_parent x H_parent), the contact force changes by -k dX_i.y, and these force changes are
 * carried down like the loads (dF_i = sum_c dF_c + df_c,i; dM_i gains H_i x l_i (sum_c dF_c +
 * df_c,i)), so the tangent stays the exact derivative. The tree factorisation (solve_tree.c)
 * carries the same contact stiffness, so the fast solver's step stays exact. During the load
 * continuation (load_scale < 1) k is scaled with the loads: lambda = 0 is then exact at the
 * rest state even where that reaches below the ground.
 *
 * Organ-organ contact (contact.c, Jirasek §2.8 and Fig. 6): at the start of the backward pass
 * the touching pairs of organ spheres (centred at distal nodes) are found on a hashed grid and
 * their penalty forces added at the two nodes like tip forces; the tangent adds their changes
 * into the same force accumulators (dfc) from the nodes' displacements, so it stays exact.
 */
#include "mech/mech_internal.h"
#include "mech/fem_internal.h"
#include "mech/sweep_internal.h"
#include "core/vecmath.h"

#include <math.h>

/* ---- workspace ----
 * Every array of cbm__mech_work lives in one block of the plant's arena (core/arena.c): the
 * layout below computes the block's size, one allocation takes it, and the arrays are carved
 * from it in a fixed order. The block is replaced only when the plant outgrows it (more
 * segments, a larger Krylov dimension, a ground appearing under a fast solve), never inside a
 * solve's iteration; its contents do not outlive a solve (the state is Omega, in the plant). */

/* the joint arrays: one element per segment */
#define WORK_ARRAYS(X)                                                                             \
    X(dual)                                                                                        \
    X(cj)                                                                                          \
    X(rj)                                                                                          \
    X(wown)                                                                                        \
    X(lever)                                                                                       \
    X(ftip)                                                                                        \
    X(mtip)                                                                                        \
    X(res) X(step) X(save) X(start) X(dth) X(dm) X(dpos) X(dfc) X(tmp) X(tpart) X(best) X(zz) X(kin)
/* the tree factorisation: 9 doubles per segment each (with a Krylov workspace) */
#define TREE_ARRAYS(X) X(fdinv) X(fq) X(fa) X(fwad) X(fw)
/* the tree factorisation with ground contact: 9 doubles per segment each (fcap segments) */
#define GROUND_ARRAYS(X) X(fgam) X(flam) X(fxi) X(fp) X(fzad)

static size_t round16(size_t n)
{
    n = (n + 15u) & ~(size_t)15u;
    return n ? n : 16; /* the arena's rounding (an empty request takes 16 bytes) */
}

/* Sizes of the arrays for cap segments, kc Krylov vectors (0 = none) and fcap segments with
 * ground contact (0 = none), in carving order; *count receives their number. The arena rounds
 * each to 16 bytes; the sum is the block. */
typedef struct work_shape {
    size_t cap, fcap;
    int kc;
} work_shape;

static size_t work_bytes(work_shape sh)
{
    const cbm__mech_work *w = NULL;
    size_t total = 0;
#define SIZE(f) total += round16(sh.cap * sizeof *w->f);
    WORK_ARRAYS(SIZE)
#undef SIZE
    if (sh.kc > 0) {
        total += 2 * round16((size_t)sh.kc * sh.cap * sizeof(cbm_vec3));        /* basis, zbasis */
        total += round16((size_t)sh.kc * (size_t)(sh.kc + 3) * sizeof(double)); /* hess */
        total += 5 * round16(9 * sh.cap * sizeof(double));                      /* TREE_ARRAYS */
    }
    if (sh.fcap > 0)
        total += 5 * round16(9 * sh.fcap * sizeof(double)) + round16(sh.fcap); /* + fact */
    return total;
}

/* Carves the arrays from the arena, whose first block holds work_bytes(sh): no allocation
 * beyond that block. */
static void work_carve(cbm__mech_work *w, work_shape sh)
{
    cbm__arena *a = &w->arena;
#define CARVE(f) w->f = cbm__arena_alloc(a, sh.cap * sizeof *w->f);
    WORK_ARRAYS(CARVE)
#undef CARVE
    if (sh.kc > 0) {
        w->basis = cbm__arena_alloc(a, (size_t)sh.kc * sh.cap * sizeof(cbm_vec3));
        w->zbasis = cbm__arena_alloc(a, (size_t)sh.kc * sh.cap * sizeof(cbm_vec3));
        w->hess = cbm__arena_alloc(a, (size_t)sh.kc * (size_t)(sh.kc + 3) * sizeof(double));
#define CARVE9(f) w->f = cbm__arena_alloc(a, 9 * sh.cap * sizeof(double));
        TREE_ARRAYS(CARVE9)
#undef CARVE9
    }
    if (sh.fcap > 0) {
#define CARVE9(f) w->f = cbm__arena_alloc(a, 9 * sh.fcap * sizeof(double));
        GROUND_ARRAYS(CARVE9)
#undef CARVE9
        w->fact = cbm__arena_alloc(a, sh.fcap);
    }
    w->cap = sh.cap;
    w->krylov_cap = sh.kc;
    w->fcap = sh.fcap;
}

void cbm__mech_work_free(cbm_plant *p)
{
    cbm__arena_destroy(&p->work.arena);
    memset(&p->work, 0, sizeof p->work);
}

/* Ensures room for the plant's segments and krylov_dim (0: keep what is held); the tree
 * factorisation's ground arrays come with a Krylov workspace once the plant has a ground. */
static cbm_status work_reserve(cbm_plant *p, int krylov_dim)
{
    cbm__mech_work *w = &p->work;
    work_shape sh = {w->cap, w->fcap, w->krylov_cap};
    int kc = krylov_dim > 0 ? krylov_dim + 1 : 0;
    /* a growing plant adds a few segments per step: grow by half again, so the block is
     * replaced O(log n) times over a run instead of at every solve */
    if (p->n > sh.cap)
        sh.cap = p->n > sh.cap + sh.cap / 2 ? p->n : sh.cap + sh.cap / 2;
    if (kc > sh.kc)
        sh.kc = kc;
    if (p->ground && sh.kc > 0)
        sh.fcap = sh.cap;
    else if (sh.fcap > 0)
        sh.fcap = sh.cap;
    if (sh.cap == w->cap && sh.kc == w->krylov_cap && sh.fcap == w->fcap && w->arena.head)
        return CBM_OK;
    cbm_context *ctx = p->ctx;
    cbm__mech_work_free(p);
    size_t bytes = work_bytes(sh);
    cbm__arena_init(&w->arena, ctx, bytes);
    if (!cbm__arena_alloc(&w->arena, bytes)) { /* the one allocation: the whole block */
        memset(w, 0, sizeof *w);
        return CBM_E_NOMEM;
    }
    cbm__arena_reset(&w->arena); /* keeps the block, empty, for the carving */
    work_carve(w, sh);
    return CBM_OK;
}

cbm_status cbm__mech_work_reserve(cbm_plant *p, int krylov_dim)
{
    CBM_TRY(work_reserve(p, krylov_dim));
    return cbm__mech_pairs_reserve(p);
}

/* ---- prepare ---- */

/* The joint arrays of segments [lo, hi); returns whether one of them has a tip moment (read
 * here anyway: the fast solver's test for conservative loads needs no loop of its own). In the
 * solve's depth-first order (solve_order.c) the segment at place i is the plant's map[i]: its
 * length, parent and axis flag are in the order, its rigidity, rest rate, masses and tip loads in
 * the plant's own arrays, read there through the map (they are not gathered: the prepare is their
 * only reader in a solve), each place's lines fetched CBM__ORDER_AHEAD places ahead as in the
 * gather. map NULL: the plant's numbering. Always inlined, so that each caller has a loop of its
 * own and the plant's numbering keeps its code. */
static inline __attribute__((always_inline)) bool prepare_range(cbm_plant *p, size_t lo, size_t hi,
                                                                const uint32_t *restrict map)
{
    bool tip_moment = false;
    cbm__mech_work *w = &p->work;
    double s = p->load_scale;
    cbm_vec3 g = v3_scale(p->gravity, s);
    bool stag = p->disc == CBM_MECH_STAGGERED;
    const cbm_vec3 *restrict rig = p->rig, *restrict rest = p->rest;
    const cbm_vec3 *restrict tipf = p->tipf, *restrict tipm = p->tipm;
    const double *restrict mpl = p->mpl, *restrict pmass = p->pmass, *restrict pmass0 = p->pmass0;
    const bool tips = p->tip_loads; /* else every tip load is +0.0: not read */
    for (size_t i = lo; i < hi; i++) {
        size_t si = i;
        if (map) {
            si = map[i];
            if (i + CBM__ORDER_AHEAD < hi) {
                size_t a = map[i + CBM__ORDER_AHEAD];
                __builtin_prefetch(&rig[a], 0, 3);
                __builtin_prefetch(&rest[a], 0, 3);
                if (tips) {
                    __builtin_prefetch(&tipf[a], 0, 3);
                    __builtin_prefetch(&tipm[a], 0, 3);
                }
                __builtin_prefetch(&mpl[a], 0, 3);
                __builtin_prefetch(&pmass[a], 0, 3);
            }
        }
        double l = p->len[i];
        int64_t pa = p->parent[i];
        w->wown[i] = v3_scale(g, mpl[si] * l);
        double pm =
            p->mass_path == 1.0 ? pmass[si] : pmass0[si] + p->mass_path * (pmass[si] - pmass0[si]);
        cbm_vec3 tf = v3(0, 0, 0), tm = v3(0, 0, 0); /* the same bits as +0.0 read */
        if (tips) {
            tf = tipf[si];
            tm = tipm[si];
        }
        w->ftip[i] = v3_add(v3_scale(g, pm), v3_scale(tf, s));
        w->mtip[i] = v3_scale(tm, s);
        tip_moment = tip_moment || !(tm.x == 0.0 && tm.y == 0.0 && tm.z == 0.0);
        if (!stag) {
            w->dual[i] = l;
            w->cj[i] = rig[si];
            w->rj[i] = rest[si];
            w->lever[i] = l;
        } else if (pa < 0 || !(p->cont[i] & 1)) {
            w->dual[i] = 0.5 * l;
            w->cj[i] = rig[si];
            w->rj[i] = rest[si];
            w->lever[i] = 0.5 * l;
        } else {
            size_t sp = map ? map[pa] : (size_t)pa;
            double lp = p->len[pa];
            double d = 0.5 * (lp + l);
            cbm_vec3 cp = rig[sp], ci = rig[si];
            cbm_vec3 rp = rest[sp], ri = rest[si];
            w->dual[i] = d;
            w->cj[i] =
                v3(d / (0.5 * lp / cp.x + 0.5 * l / ci.x), d / (0.5 * lp / cp.y + 0.5 * l / ci.y),
                   d / (0.5 * lp / cp.z + 0.5 * l / ci.z));
            w->rj[i] = v3_scale(v3_add(v3_scale(rp, 0.5 * lp), v3_scale(ri, 0.5 * l)), 1.0 / d);
            w->lever[i] = 0.5 * l;
        }
        p->cmass[i] = mpl[si] * l + pmass[si];
    }
    return tip_moment;
}

/* prepare_range over [lo, hi) in the numbering the solve runs in */
static bool prepare_some(cbm_plant *p, size_t lo, size_t hi)
{
    if (p->sorder.active)
        return prepare_range(p, lo, hi, p->sorder.ord);
    return prepare_range(p, lo, hi, NULL);
}

typedef struct prep_job {
    cbm_plant *p;
    size_t lo, hi;   /* the joint arrays of these segments */
    uint32_t me;     /* then the carried masses of this thread's subtrees */
    bool tip_moment; /* one of [lo, hi) has a tip moment */
} prep_job;

static void prepare_job(void *arg)
{
    prep_job *j = arg;
    j->tip_moment = prepare_some(j->p, j->lo, j->hi);
}

static void cmass_job(void *arg)
{
    prep_job *j = arg;
    cbm_plant *p = j->p;
    const uint32_t *restrict part = p->work.tpart;
    for (size_t i = p->n; i-- > 0;) {
        uint32_t e = part[i];
        if (cbm__part_thread(e) == j->me && !(e & CBM__PART_ROOT) && p->parent[i] >= 0)
            p->cmass[p->parent[i]] += p->cmass[i];
    }
}

/* work.kin from the topology (see CBM__KIN_CHILDREN): in decreasing index, the first child met
 * of a parent is its child of highest index, the one a backward sweep reaches first. */
static void kin_compute(cbm_plant *p)
{
    uint8_t *restrict kin = p->work.kin;
    const int64_t *restrict par = p->parent;
    memset(kin, 0, p->n);
    for (size_t i = p->n; i-- > 0;) {
        int64_t pa = par[i];
        if (pa >= 0 && !(kin[pa] & CBM__KIN_CHILDREN)) {
            kin[pa] |= CBM__KIN_CHILDREN;
            kin[i] |= CBM__KIN_FIRST;
        }
    }
}

void cbm__mech_prepare(cbm_plant *p)
{
    const size_t n = p->n;
    cbm__mech_fused_clear(p);
    p->work.stale = false;
    kin_compute(p);
    int t = cbm__mech_tree_split(p);
    if (t <= 1) {
        p->work.tip_moment = prepare_some(p, 0, n);
        /* carried mass (independent of the shape) */
        for (size_t i = n; i-- > 0;)
            if (p->parent[i] >= 0)
                p->cmass[p->parent[i]] += p->cmass[i];
    } else {
        /* each segment's joint arrays alone: in ranges; the carried masses as the backward
         * sweep (cbm__mech_backward), the same sums in the same order */
        prep_job jobs[8];
        for (int k = 0; k < t; k++)
            jobs[k] = (prep_job){p, n * (size_t)k / (size_t)t, n * (size_t)(k + 1) / (size_t)t,
                                 (uint32_t)k + 1, false};
        cbm__mech_run_threads(t, prepare_job, jobs, sizeof *jobs);
        p->work.tip_moment = false;
        for (int k = 0; k < t; k++)
            p->work.tip_moment = p->work.tip_moment || jobs[k].tip_moment;
        cbm__mech_run_threads(t, cmass_job, jobs, sizeof *jobs);
        const uint32_t *part = p->work.tpart;
        for (size_t i = n; i-- > 0;) {
            uint32_t e = part[i];
            if ((cbm__part_thread(e) == 0 || (e & CBM__PART_ROOT)) && p->parent[i] >= 0)
                p->cmass[p->parent[i]] += p->cmass[i];
        }
    }
    cbm__mech_pairs_prepare(p);
}

/* ---- the passes ---- */

static inline void q_frame(cbm_quat q, cbm_vec3 *h, cbm_vec3 *l, cbm_vec3 *u)
{
    double xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
    double xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
    double wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
    *h = v3(1.0 - 2.0 * (yy + zz), 2.0 * (xy + wz), 2.0 * (xz - wy));
    *l = v3(2.0 * (xy - wz), 1.0 - 2.0 * (xx + zz), 2.0 * (yz + wx));
    *u = v3(2.0 * (xz + wy), 2.0 * (yz - wx), 1.0 - 2.0 * (xx + yy));
}

double cbm__mech_contact(const cbm_plant *p, size_t i, cbm_vec3 h, double *stiff)
{
    double depth = p->ground_y - (p->pos[i].y + p->len[i] * h.y);
    if (!p->ground || !(depth > 0.0)) {
        if (stiff)
            *stiff = 0.0;
        return 0.0;
    }
    double s = p->ground_s, k = p->ground_k * p->load_scale;
    if (depth < s) {
        /* smoothed onset: k d^2 / (2 s), continuous in force and stiffness */
        if (stiff)
            *stiff = -k * depth / s;
        return 0.5 * k * depth * depth / s;
    }
    if (stiff)
        *stiff = -k;
    return k * (depth - 0.5 * s);
}

/* ---- the passes over threads ----
 * A branched plant of many segments is swept by several threads with the split of the tree
 * factorisation (solve_tree.c, "Threads"): the forward sweep does the top (the segments carrying
 * much of the tree) first, then each thread its subtrees; the backward sweep runs each thread
 * over its subtrees, a subtree's root keeping its force and moment instead of adding them into
 * its parent, then one sweep over the top in decreasing index adds them where the serial sweep
 * would have. Every accumulator so receives the same terms in the same order, the maxima do not
 * depend on the order, and the line search's merit is summed from per-joint terms (work.zz) in
 * the serial order afterwards: the results are the same to the bit for any number of threads. */

typedef struct pass_job {
    cbm_plant *p;
    uint32_t me; /* the thread's number in the split (1 ..) */
    bool clear;  /* forward: zero the forces and moments too */
    /* backward: the settings and what the thread's share found */
    double alpha;
    cbm_vec3 *res;
    double rmax, mmax, emax, sum, ss;
    /* the fused factorisation (cbm__mech_backward_factor), the thread's own counts; or none */
    cbm__mech_fsweep fs;
    bool fuse;
} pass_job;

static void forward_job(void *arg)
{
    pass_job *j = arg;
    cbm_plant *p = j->p;
    const uint32_t *restrict part = p->work.tpart;
    const int64_t *par = p->parent;
    const double *q = (const double *)p->q, *pos = (const double *)p->pos;
    for (size_t i = 0; i < p->n; i++) {
        CBM__PREFETCH_PARENT_FWD(par, i, p->n, q, 4);
        CBM__PREFETCH_PARENT_FWD(par, i, p->n, pos, 3);
        CBM__PREFETCH_PARENT_FWD(par, i, p->n, p->len, 1);
        if (cbm__part_thread(part[i]) == j->me)
            cbm__mech_forward_seg(p, i, j->clear);
    }
}

static void forward_impl(cbm_plant *p, bool clear)
{
    const size_t n = p->n;
    cbm__mech_fused_clear(p);
    int t = cbm__mech_tree_split(p);
    if (t <= 1) {
        const int64_t *par = p->parent;
        const double *q = (const double *)p->q, *pos = (const double *)p->pos;
        for (size_t i = 0; i < n; i++) {
            CBM__PREFETCH_PARENT_FWD(par, i, n, q, 4);
            CBM__PREFETCH_PARENT_FWD(par, i, n, pos, 3);
            /* the parent's length too: half of this sweep's time waited on it (perf) */
            CBM__PREFETCH_PARENT_FWD(par, i, n, p->len, 1);
            cbm__mech_forward_seg(p, i, clear);
        }
        return;
    }
    const uint32_t *part = p->work.tpart;
    for (size_t i = 0; i < n; i++)
        if (cbm__part_thread(part[i]) == 0)
            cbm__mech_forward_seg(p, i, clear);
    pass_job jobs[8];
    for (int k = 0; k < t; k++)
        jobs[k] = (pass_job){.p = p, .me = (uint32_t)k + 1, .clear = clear};
    cbm__mech_run_threads(t, forward_job, jobs, sizeof *jobs);
}

void cbm__mech_forward(cbm_plant *p)
{
    forward_impl(p, true);
}

void cbm__mech_forward_eval(cbm_plant *p)
{
    forward_impl(p, false);
}

/* Backward sweep at segment i (its children's force and moment are in its accumulators): its
 * force, moment and residual; adds them into its parent's unless `defer`; the merit's term goes
 * to *zz; with frame, R = [H L U] there for the fused factorisation. Inlined into the sweeps
 * (GCC left it a call: 35 instructions a segment more, 2 % of a sweep at 10^3-10^4). */
static inline __attribute__((always_inline)) void backward_seg(cbm_plant *p, size_t i, pass_job *j,
                                                               bool ground, bool pairs, bool defer,
                                                               double *zz, double *frame)
{
    const cbm__mech_work *w = &p->work;
    cbm_vec3 *restrict f = p->force;
    cbm_vec3 *restrict m = p->moment;
    cbm_vec3 h, l, u;
    q_frame(p->q[i], &h, &l, &u);
    if (frame) {
        /* R = [H L U] row-major, for the fused factorisation (cbm__mech_factor_one) */
        frame[0] = h.x, frame[1] = l.x, frame[2] = u.x;
        frame[3] = h.y, frame[4] = l.y, frame[5] = u.y;
        frame[6] = h.z, frame[7] = l.z, frame[8] = u.z;
    }
    const uint8_t kin = w->kin[i];
    /* the children's sums (none: zero, the accumulators need no clearing: work.kin) */
    const bool leaf = !(kin & CBM__KIN_CHILDREN);
    const cbm_vec3 zero = v3(0, 0, 0);
    cbm_vec3 fd = v3_add(leaf ? zero : f[i], w->ftip[i]);
    if (ground)
        fd.y += cbm__mech_contact(p, i, h, NULL);
    if (pairs)
        fd = v3_add(fd, p->contacts.fnode[i]);
    cbm_vec3 wo = w->wown[i];
    double li = p->len[i];
    cbm_vec3 arm = v3_add(v3_scale(fd, li), v3_scale(wo, w->lever[i]));
    cbm_vec3 mi = v3_add(v3_add(leaf ? zero : m[i], v3_cross(h, arm)), w->mtip[i]);
    cbm_vec3 fi = v3_add(fd, wo);
    f[i] = fi;
    m[i] = mi;
    int64_t pa = p->parent[i];
    if (pa >= 0 && !defer) {
        bool first = (kin & CBM__KIN_FIRST) != 0;
        cbm__kin_add3(&f[pa], fi, first);
        cbm__kin_add3(&m[pa], mi, first);
    }
    cbm_vec3 ml = v3(v3_dot(mi, h), v3_dot(mi, l), v3_dot(mi, u));
    cbm_vec3 c = w->cj[i], o = p->omega[i], r0 = w->rj[i];
    cbm_vec3 e = v3(c.x * (o.x - r0.x), c.y * (o.y - r0.y), c.z * (o.z - r0.z));
    cbm_vec3 r = v3_sub(e, ml);
    double rn = v3_norm2(r), mn = v3_norm2(mi), en = v3_norm2(e);
    j->sum += rn + mn;
    {
        /* merit of the line search: the unbalanced rotation of each joint (rad),
         * d C^-1 r, so that every joint weighs alike whatever its size */
        double dj = w->dual[i];
        cbm_vec3 z = v3(dj * r.x / c.x, dj * r.y / c.y, dj * r.z / c.z);
        *zz = v3_norm2(z);
    }
    if (rn > j->rmax)
        j->rmax = rn;
    if (mn > j->mmax)
        j->mmax = mn;
    if (en > j->emax)
        j->emax = en;
    if (j->res)
        j->res[i] = r;
    if (j->alpha > 0.0) {
        double alpha = j->alpha;
        cbm_vec3 t = v3(r0.x + ml.x / c.x, r0.y + ml.y / c.y, r0.z + ml.z / c.z);
        p->omega[i] = v3_add(v3_scale(o, 1.0 - alpha), v3_scale(t, alpha));
    }
}

static void backward_job(void *arg)
{
    pass_job *j = arg;
    cbm_plant *p = j->p;
    const uint32_t *restrict part = p->work.tpart;
    double *restrict zz = p->work.zz;
    const bool ground = p->ground;
    const bool pairs = p->contacts.on && p->contacts.cap >= p->n;
    const int64_t *par = p->parent;
    double *f = (double *)p->force, *m = (double *)p->moment;
    double *fw = p->work.fw, *dm = (double *)p->work.dm;
    for (size_t i = p->n; i-- > 0;) {
        CBM__PREFETCH_PARENT_BWD(par, i, f, 3);
        CBM__PREFETCH_PARENT_BWD(par, i, m, 3);
        if (j->fuse) {
            CBM__PREFETCH_PARENT_BWD(par, i, fw, 9);
            CBM__PREFETCH_PARENT_BWD(par, i, dm, 3);
        }
        uint32_t e = part[i];
        if (cbm__part_thread(e) == j->me) {
            bool defer = (e & CBM__PART_ROOT) != 0;
            double R[9];
            backward_seg(p, i, j, ground, pairs, defer, &zz[i], j->fuse ? R : NULL);
            if (j->fuse)
                cbm__mech_factor_one(&j->fs, i, defer, R);
        }
    }
}

/* The backward sweep; with fuse, the tree factorisation (mu = 0) and the backward half of the
 * solve J x = -res fused into it: at each segment, right after its force, moment and residual,
 * the factorisation's step of that segment (its inputs are complete there, its children having
 * been swept before it), so every array receives the same terms in the same order as in the
 * sweeps apart. */
static double backward_impl(cbm_plant *p, double alpha, cbm_vec3 *res, double *mmax_out,
                            double *sumsq_out, bool fuse)
{
    const size_t n = p->n;
    cbm__mech_work *w = &p->work;
    const bool ground = p->ground;
    /* organ-organ contact (contact.c): the pair forces at the distal nodes of this shape */
    const bool pairs = p->contacts.on && p->contacts.cap >= p->n;
    if (pairs)
        cbm__mech_pairs_eval(p);
    cbm__mech_fused_clear(p);
    pass_job all = {.p = p, .alpha = alpha, .res = res, .fuse = fuse};
    if (fuse)
        all.fs = (cbm__mech_fsweep){.p = p, .b = res, .out = w->tmp, .neg_b = true};
    double ss = 0.0;
    int t = cbm__mech_tree_split(p);
    if (fuse) {
        cbm__mech_factor_clear(p, true);
        w->fwad_ok = false; /* not stored by the sweep (cbm__mech_factor_one) */
    }
    if (t <= 1) {
        const bool sorted = p->sorder.active;
        const int64_t *par = p->parent;
        double *f = (double *)p->force, *m = (double *)p->moment;
        double *fw = w->fw, *dm = (double *)w->dm;
        for (size_t i = n; i-- > 0;) {
            CBM__PREFETCH_PARENT_BWD(par, i, f, 3);
            CBM__PREFETCH_PARENT_BWD(par, i, m, 3);
            double z2;
            if (fuse) {
                CBM__PREFETCH_PARENT_BWD(par, i, fw, 9);
                CBM__PREFETCH_PARENT_BWD(par, i, dm, 3);
                double R[9];
                backward_seg(p, i, &all, ground, pairs, false, &z2, R);
                cbm__mech_factor_one(&all.fs, i, false, R);
            } else {
                backward_seg(p, i, &all, ground, pairs, false, &z2, NULL);
            }
            if (sorted)
                w->zz[i] = z2;
            else
                ss += z2;
        }
        if (sorted) /* the plant's order of the sum */
            for (size_t k = n; k-- > 0;)
                ss += w->zz[p->sorder.at[k]];
    } else {
        pass_job jobs[8];
        for (int k = 0; k < t; k++) {
            jobs[k] = all;
            jobs[k].me = (uint32_t)k + 1;
        }
        cbm__mech_run_threads(t, backward_job, jobs, sizeof *jobs);
        /* the top, adding each subtree's root where the serial sweep would have */
        const uint32_t *part = w->tpart;
        double *zz = w->zz;
        cbm_vec3 *f = p->force, *m = p->moment;
        for (size_t i = n; i-- > 0;) {
            uint32_t e = part[i];
            if (cbm__part_thread(e) == 0) {
                double R[9];
                backward_seg(p, i, &all, ground, pairs, false, &zz[i], fuse ? R : NULL);
                if (fuse)
                    cbm__mech_factor_one(&all.fs, i, false, R);
            } else if (e & CBM__PART_ROOT) {
                int64_t pa = p->parent[i];
                bool first = (w->kin[i] & CBM__KIN_FIRST) != 0;
                cbm__kin_add3(&f[pa], f[i], first);
                cbm__kin_add3(&m[pa], m[i], first);
                if (fuse) {
                    /* Phi (cbm__mech_factor_one), kept in fwad */
                    cbm__kin_add9(w->fw + 9 * (size_t)pa, w->fwad + 9 * i, first);
                    cbm__kin_add3(&w->dm[pa], w->dm[i], first);
                }
            }
        }
        for (int k = 0; k < t; k++) {
            all.sum += jobs[k].sum;
            all.rmax = jobs[k].rmax > all.rmax ? jobs[k].rmax : all.rmax;
            all.mmax = jobs[k].mmax > all.mmax ? jobs[k].mmax : all.mmax;
            all.emax = jobs[k].emax > all.emax ? jobs[k].emax : all.emax;
            all.fs.singular += jobs[k].fs.singular;
            all.fs.nonpd += jobs[k].fs.nonpd;
            all.fs.negative += jobs[k].fs.negative;
        }
        for (size_t k = n; k-- > 0;) /* the serial order of the sum */
            ss += zz[cbm__mech_at(p, k)];
    }
    if (!isfinite(all.sum))
        return NAN;
    if (fuse) {
        w->fready = w->fhalf = true;
        w->fsing = all.fs.singular;
        w->fnonpd = all.fs.nonpd;
        w->fneg = all.fs.negative;
    }
    double mmax = all.mmax == 0.0 ? all.emax : all.mmax;
    *mmax_out = sqrt(mmax);
    if (sumsq_out)
        *sumsq_out = ss;
    return sqrt(all.rmax);
}

double cbm__mech_backward(cbm_plant *p, double alpha, cbm_vec3 *res, double *mmax_out,
                          double *sumsq_out)
{
    return backward_impl(p, alpha, res, mmax_out, sumsq_out, false);
}

double cbm__mech_backward_factor(cbm_plant *p, cbm_vec3 *res, double *mmax, double *sumsq)
{
    /* the fused sweep knows neither the ground's nor the organ pairs' terms of the
     * factorisation: those evaluate alone */
    bool fuse = res && !p->ground && !p->contacts.on && p->work.fdinv && p->work.krylov_cap > 0;
    return backward_impl(p, 0.0, res, mmax, sumsq, fuse);
}

double cbm__mech_relres(double rmax, double mmax, double *char_moment)
{
    if (char_moment)
        *char_moment = mmax;
    if (rmax == 0.0)
        return 0.0;
    return mmax > 0.0 ? rmax / mmax : INFINITY;
}

cbm_status cbm__mech_report_nonfinite(cbm_plant *p)
{
    for (size_t k = 0; k < p->n; k++) {
        size_t i = cbm__mech_at(p, k); /* the first in the plant's order, named by its number */
        const char *what = NULL;
        if (!v3_isfinite(p->omega[i]))
            what = "rotation rate";
        else if (!v3_isfinite(p->pos[i]))
            what = "position";
        else if (!isfinite(p->q[i].w + p->q[i].x + p->q[i].y + p->q[i].z))
            what = "orientation";
        else if (!v3_isfinite(p->force[i]))
            what = "force";
        else if (!v3_isfinite(p->moment[i]))
            what = "moment";
        if (what)
            return cbm__fail(p->ctx, CBM_E_NONFINITE, "segment %zu: the %s became NaN or infinite",
                             k, what);
    }
    return cbm__fail(p->ctx, CBM_E_NONFINITE, "the residual became NaN or infinite");
}

void cbm__mech_jvp(cbm_plant *p, const cbm_vec3 *v, cbm_vec3 *out)
{
    cbm__mech_work *w = &p->work;
    w->fhalf = false; /* dm and perhaps tmp are written; the factorisation stays */
    const size_t n = p->n;
    const int64_t *restrict par = p->parent;
    const double *restrict dual = w->dual;
    const cbm_vec3 *restrict om = p->omega;
    const cbm_quat *restrict q = p->q;
    cbm_vec3 *restrict dth = w->dth;
    cbm_vec3 *restrict dm = w->dm;
    cbm_vec3 *restrict dpos = w->dpos;
    cbm_vec3 *restrict dfc = w->dfc;
    /* node displacements and force changes: for the ground and for organ pairs */
    const bool ground = p->ground || cbm__mech_pairs_active(p);
    for (size_t i = 0; i < n; i++) {
        cbm_vec3 r = v3_scale(om[i], dual[i]);
        cbm_vec3 x = v3_scale(v[i], dual[i]);
        double t2 = v3_norm2(r), c1, c2;
        cbm__mech_jr_coeffs(t2, &c1, &c2);
        cbm_vec3 rx = v3_cross(r, x);
        cbm_vec3 jx = v3_add(v3_sub(x, v3_scale(rx, c1)), v3_scale(v3_cross(r, rx), c2));
        cbm_vec3 wj = q_rotate(q[i], jx);
        int64_t pa = par[i];
        dth[i] = pa < 0 ? wj : v3_add(dth[pa], wj);
        dm[i] = v3(0, 0, 0);
        if (ground) {
            /* the proximal node moves with the rotation of every frame below it */
            dpos[i] = pa < 0
                          ? v3(0, 0, 0)
                          : v3_add(dpos[pa], v3_scale(v3_cross(dth[pa], q_h(q[pa])), p->len[pa]));
            dfc[i] = v3(0, 0, 0);
        }
    }
    /* the pair force changes enter dfc at both nodes before the sweep carries them down */
    cbm__mech_pairs_jvp(p, dpos, dth, dfc);
    const double *restrict len = p->len;
    const double *restrict lever = w->lever;
    const cbm_vec3 *restrict wown = w->wown;
    const cbm_vec3 *restrict cj = w->cj;
    const cbm_vec3 *restrict f = p->force;
    const cbm_vec3 *restrict m = p->moment;
    for (size_t i = n; i-- > 0;) {
        cbm_vec3 h, l, u;
        q_frame(q[i], &h, &l, &u);
        cbm_vec3 arm = v3_add(v3_scale(v3_sub(f[i], wown[i]), len[i]), v3_scale(wown[i], lever[i]));
        cbm_vec3 dh = v3_cross(dth[i], h);
        cbm_vec3 dmi = v3_add(dm[i], v3_cross(dh, arm));
        int64_t pa = par[i];
        if (ground) {
            /* contact forces follow the nodes: dF = sum_c dF_c + k_c dy of the distal node,
             * acting at the distal node (lever l_i H_i) */
            double kc;
            cbm_vec3 dfd = dfc[i];
            (void)cbm__mech_contact(p, i, h, &kc);
            if (kc != 0.0)
                dfd.y += kc * (dpos[i].y + len[i] * dh.y);
            dmi = v3_add(dmi, v3_cross(h, v3_scale(dfd, len[i])));
            if (pa >= 0)
                dfc[pa] = v3_add(dfc[pa], dfd);
        }
        dm[i] = dmi;
        if (pa >= 0)
            dm[pa] = v3_add(dm[pa], dmi);
        cbm_vec3 z = v3_sub(dmi, v3_cross(dth[i], m[i]));
        cbm_vec3 c = cj[i];
        out[i] = v3(c.x * v[i].x - v3_dot(z, h), c.y * v[i].y - v3_dot(z, l),
                    c.z * v[i].z - v3_dot(z, u));
    }
}

/* ---- entry points ---- */

static cbm_status check_plant(cbm_plant *p)
{
    if (p->n == 0)
        return cbm__fail(p->ctx, CBM_E_INVALID, "plant: no segments to solve");
    for (size_t i = 0; i < p->n; i++) {
        cbm_vec3 c = p->rig[i];
        if (!(c.x > 0.0 && c.y > 0.0 && c.z > 0.0 && isfinite(c.x + c.y + c.z)))
            return cbm__fail(p->ctx, CBM_E_INVALID, "segment %zu: rigidity is zero or not finite",
                             i);
        if (!v3_isfinite(p->omega[i]))
            return cbm__fail(p->ctx, CBM_E_NONFINITE, "segment %zu: rotation rate is not finite",
                             i);
    }
    return CBM_OK;
}

cbm_solve_def cbm_solve_def_default(void)
{
    cbm_solve_def d;
    memset(&d, 0, sizeof d);
    d.solver = CBM_MECH_NEWTON;
    d.tolerance = 1e-8;
    d.alpha = 0.5;
    d.krylov_dim = 10;
    d.preconditioner = CBM_MECH_PRECOND_TREE;
    d.warm_start = true;
    d.threads = 0; /* one per processor */
    d.confirm_modes = true;
    d.approx_mode = CBM_APPROX_CORRECTED;
    d.approx_p = 1.0;
    d.approx_force_factor = 1.0;
    d.fem = cbm_fem_def_default();
    return d;
}

const char *cbm_solve_stage_name(cbm_solve_stage stage)
{
    static const char *const names[CBM_SOLVE_STAGE_COUNT] = {
        [CBM_SOLVE_STAGE_NONE] = "none",
        [CBM_SOLVE_STAGE_NEWTON] = "newton",
        [CBM_SOLVE_STAGE_TRANSIENT] = "transient",
        [CBM_SOLVE_STAGE_MASS_PATH] = "mass-path",
        [CBM_SOLVE_STAGE_LOAD_PATH] = "load-path",
        [CBM_SOLVE_STAGE_RELAX_BURSTS] = "relax-bursts",
        [CBM_SOLVE_STAGE_STABILITY] = "stability",
        [CBM_SOLVE_STAGE_RELAX] = "relax",
        [CBM_SOLVE_STAGE_FEM] = "fem",
    };
    if ((unsigned)stage >= (unsigned)CBM_SOLVE_STAGE_COUNT)
        return "unknown";
    return names[stage];
}

void cbm_solve_stage_counts(const cbm_context *ctx, size_t counts[CBM_SOLVE_STAGE_COUNT])
{
    _Static_assert(CBM_SOLVE_STAGE_COUNT <= CBM__CONTEXT_COUNTERS, "room for the stage counts");
    memcpy(counts, cbm__context_counters_read(ctx), CBM_SOLVE_STAGE_COUNT * sizeof *counts);
}

cbm_status cbm_plant_evaluate(cbm_plant *p, double *residual)
{
    if (!p)
        return CBM_E_INVALID;
    CBM_TRY(check_plant(p));
    CBM_TRY(cbm__mech_work_reserve(p, 0));
    p->load_scale = 1.0;
    cbm__mech_prepare(p);
    cbm__mech_forward_eval(p);
    double mmax = 0.0;
    double r = cbm__mech_backward(p, 0.0, NULL, &mmax, NULL);
    if (p->contacts.npairs > p->contacts.pcap) {
        /* more touching organ pairs than room: grow it (outside any iteration) and redo */
        CBM_TRY(cbm__mech_work_reserve(p, 0));
        cbm__mech_prepare(p);
        cbm__mech_forward_eval(p);
        r = cbm__mech_backward(p, 0.0, NULL, &mmax, NULL);
    }
    if (!isfinite(r))
        return cbm__mech_report_nonfinite(p);
    if (residual)
        *residual = cbm__mech_relres(r, mmax, NULL);
    return CBM_OK;
}

/* The unstable modes of an equilibrium the relaxation (or the fast solver without the tree
 * factorisation) reached (stability.c), with the tree factorisation the workspace was reserved
 * with (cbm_plant_solve); nothing is pushed. */
static cbm_status diagnose_stability(cbm_plant *p, const cbm_solve_def *d, cbm_solve_stats *st)
{
    cbm__mech_work *w = &p->work;
    CBM_TRY(cbm__mech_work_reserve(p, w->krylov_cap > 1 ? w->krylov_cap - 1 : 1));
    cbm__mech_prepare(p);
    cbm__mech_forward(p);
    double mm = 0.0;
    if (!isfinite(cbm__mech_backward(p, 0.0, NULL, &mm, NULL)))
        return cbm__mech_report_nonfinite(p);
    size_t nonpd = 0;
    cbm__mech_tree_factor(p, 0.0, &nonpd);
    size_t modes = w->fneg;
    st->unstable_modes = 0;
    st->lowest_eigenvalue = NAN;
    if (modes > 0 && !d->confirm_modes && !d->push_unstable && !d->eigenvalue) {
        st->unstable_modes = modes; /* unconfirmed (cbm_solve_def.confirm_modes) */
    } else if (modes > 0 || d->eigenvalue) {
        double lam = NAN;
        (void)cbm__mech_lowest_mode(p, w->save, &lam);
        st->lowest_eigenvalue = lam;
        if (modes > 0 && lam < 0.0)
            st->unstable_modes = modes;
    }
    return CBM_OK;
}

cbm_status cbm_plant_solve(cbm_plant *p, const cbm_solve_def *def, cbm_solve_stats *stats)
{
    cbm_solve_stats st;
    memset(&st, 0, sizeof st);
    st.lowest_eigenvalue = NAN;
    if (stats)
        *stats = st;
    if (!p)
        return CBM_E_INVALID;
    cbm_solve_def d = def ? *def : cbm_solve_def_default();
    if ((unsigned)d.solver >= (unsigned)CBM_MECH_SOLVER_COUNT)
        return cbm__fail(p->ctx, CBM_E_INVALID, "solve: unknown solver %d", (int)d.solver);
    if (!(isfinite(d.tolerance) && d.tolerance > 0.0))
        return cbm__fail(p->ctx, CBM_E_INVALID, "solve: tolerance must be positive");
    if (d.solver == CBM_MECH_RELAX && !(isfinite(d.alpha) && d.alpha > 0.0 && d.alpha <= 1.0))
        return cbm__fail(p->ctx, CBM_E_INVALID, "solve: alpha must be in (0, 1]");
    if (d.solver == CBM_MECH_NEWTON && (d.krylov_dim < 1 || d.krylov_dim > 500))
        return cbm__fail(p->ctx, CBM_E_INVALID, "solve: krylov_dim must be in 1..500");
    if (d.threads < 0)
        return cbm__fail(p->ctx, CBM_E_INVALID,
                         "solve: threads must be >= 0 (0: one per processor)");
    p->threads = d.threads;
    CBM_TRY(check_plant(p));
    if (d.solver == CBM_MECH_APPROX) { /* no iteration: its own pass (solve_approx.c) */
        CBM_TRY(cbm__mech_work_reserve(p, 1));
        p->load_scale = 1.0;
        p->mass_path = 1.0;
        cbm__mech_prepare(p);
        cbm_status sa = cbm__mech_solve_approx(p, &d, &st);
        if (stats)
            *stats = st;
        return sa;
    }
    if (d.solver == CBM_MECH_FEM) {
        /* the incremental FEM is no equilibrium iteration: its own path (fem.c) */
        cbm_status sf = cbm__mech_solve_fem(p, &d.fem, &st);
        p->load_scale = 1.0;
        if (sf == CBM_OK)
            memcpy(p->pmass0, p->pmass, p->n * sizeof *p->pmass0);
        cbm__context_counters(p->ctx)[sf == CBM_OK ? st.stage : CBM_SOLVE_STAGE_NONE]++;
        if (stats)
            *stats = st;
        return sf;
    }
    /* touching organ pairs leave a part of rank up to three per pair to FGMRES (contact.c): a
     * short restart stagnates there */
    if (p->contacts.on && d.krylov_dim < CBM__CONTACT_KRYLOV)
        d.krylov_dim = CBM__CONTACT_KRYLOV;
    size_t lim = cbm_context_limits(p->ctx)->max_passes;
    size_t maxp = d.max_passes ? d.max_passes : lim;
    if (lim && maxp > lim)
        maxp = lim;
    if (maxp < 2)
        maxp = 2;
    /* the relaxation too: the tree factorisation diagnoses its equilibrium's stability */
    CBM_TRY(cbm__mech_work_reserve(p, d.solver == CBM_MECH_NEWTON ? d.krylov_dim : 1));
    /* a large plant is solved in the depth-first order (solve_order.c), left below */
    CBM_TRY(cbm__mech_order_enter(p, d.warm_start));
    p->load_scale = 1.0;
    cbm__mech_prepare(p);
    /* a cold start: Omega is the rest state, bit for bit where no rest rate is NaN (the fast
     * solver's test for a warm start, Omega != rest somewhere, then needs no loop of its own) */
    p->work.at_rest = false;
    if (!d.warm_start) {
        bool nan = false;
        for (size_t i = 0; i < p->n; i++) {
            cbm_vec3 r = p->work.rj[i];
            p->omega[i] = r;
            nan = nan || isnan(r.x) || isnan(r.y) || isnan(r.z);
        }
        p->work.at_rest = !nan;
    }
    cbm_status s = d.solver == CBM_MECH_RELAX ? cbm__mech_solve_relax(p, &d, maxp, &st)
                                              : cbm__mech_solve_newton(p, &d, maxp, &st);
    /* an evaluation found more touching organ pairs than the workspace held (contact.c): grow
     * it and solve again from the state reached (no allocation inside an iteration) */
    for (int again = 0; again < 4 && p->contacts.on && p->contacts.npairs > p->contacts.pcap;
         again++) {
        size_t passes = st.passes;
        p->load_scale = 1.0;
        p->mass_path = 1.0;
        CBM_TRY(cbm__mech_work_reserve(p, d.solver == CBM_MECH_NEWTON ? d.krylov_dim : 1));
        cbm__mech_prepare(p);
        memset(&st, 0, sizeof st);
        s = d.solver == CBM_MECH_RELAX ? cbm__mech_solve_relax(p, &d, maxp, &st)
                                       : cbm__mech_solve_newton(p, &d, maxp, &st);
        st.passes += passes;
    }
    p->load_scale = 1.0;
    p->mass_path = 1.0;
    cbm__mech_order_leave(p);
    st.lowest_eigenvalue = s == CBM_OK ? st.lowest_eigenvalue : NAN;
    if (s == CBM_OK && !(d.solver == CBM_MECH_NEWTON && d.preconditioner == CBM_MECH_PRECOND_TREE))
        s = diagnose_stability(p, &d, &st);
    if (s == CBM_OK) /* the point masses this Omega balances */
        memcpy(p->pmass0, p->pmass, p->n * sizeof *p->pmass0);
    cbm__context_counters(p->ctx)[s == CBM_OK ? st.stage : CBM_SOLVE_STAGE_NONE]++;
    if (stats)
        *stats = st;
    return s;
}
