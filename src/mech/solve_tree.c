/* Exact O(n) solution of the Newton system of the statics on a tree: the preconditioner of the
 * fast solver's GMRES.
 *
 * The linearised equilibrium of joint i (tangent of the two passes, see solve_common.c) is
 *     S_i v_i - R_i^T dM_i - R_i^T [M_i]x dth_i = b_i,
 *     dth_i = dth_parent + a_i v_i,            a_i = R_i J_r(d_i Omega_i) d_i,
 *     dM_i  = sum_children dM_c + G_i dth_i,   G_i = [V_i]x [H_i]x,
 * with V_i = l_i (F_i - w_i) + lever_i w_i the lever-weighted load of the segment. Each subtree
 * responds linearly to the rotation of its parent's frame: dM_i = Phi_i dth_parent + psi_i.
 * Condensing from the tips (the same recursion as the articulated-body algorithm of robot
 * dynamics, here for statics):
 *     W_i = G_i + sum_c Phi_c,          Q_i = R_i^T (W_i + [M_i]x),      D_i = S_i - Q_i a_i,
 *     Phi_i = W_i (I + a_i D_i^-1 Q_i), psi_i = W_i a_i D_i^-1 u_i + w_i,
 *     u_i = b_i + R_i^T w_i,            w_i = sum_c psi_c,
 * then from the base: v_i = D_i^-1 (u_i + Q_i dth_parent), dth_i = dth_parent + a_i v_i.
 * The factorisation (Phi, D^-1, Q, a, W a D^-1) depends on the state only and is computed once
 * per Newton step (one backward sweep); each solve is one backward and one forward sweep, i.e.
 * one pass. If a D_i is singular (an unstable equilibrium at a buckling load) it is replaced by
 * S_i there, which keeps the preconditioner usable and GMRES does the rest.
 *
 * Ground contact (solve_common.c): the distal node X_i of a segment below the ground carries a
 * spring, d f_i = -k_i n n^T dX_i, and dX_i = dX_parent + B_i dth_i with B_i = -l_i [H_i]x, so
 * a subtree now also responds to the displacement x of its proximal node and passes a force
 * change down: dM_i = Phi_i dth_parent + Gamma_i x + psi_i, dF_i = Lambda_i dth_parent + Xi_i x
 * + chi_i. With the children's blocks summed into Gamma, Lambda, Xi (and psi, chi):
 *     Xi' = sum Xi_c - k_i n n^T,   Z = sum Lambda_c + Xi' B,   Y = sum Gamma_c - B Xi',
 *     W_i = G_i + sum Phi_c + (sum Gamma_c) B - B Z,   P_i = R_i^T Y,
 *     D_i, Q_i as above;  the joint: v_i = D_i^-1 (u_i + Q_i dth_parent + P_i x),
 *     Phi_i = W (I + a D^-1 Q), Gamma_i = W a D^-1 P + Y,
 *     Lambda_i = Z (I + a D^-1 Q), Xi_i = Z a D^-1 P + Xi',
 *     m0 = sum psi_c - B sum chi_c,  u_i = b_i + R_i^T m0,
 *     psi_i = W a D^-1 u_i + m0,     chi_i = Z a D^-1 u_i + sum chi_c,
 * and forward: dX_i = x + B_i dth_i. This is K_c = sum_i J_i^T k_i J_i (J_i: the node's
 * position against every joint on its path) condensed like the lever-arm terms of the loads.
 * The contact blocks are zero off the paths from contact nodes to the root, which are the only
 * segments that compute them (work.fact). Cost with contact: about twice the 3x3 products on
 * those paths; none without.
 *
 * Speed: the factorisation is most of a growth run's time (52 % of the 10-year fruit tree before
 * the 3x3 loops were unrolled and Q, a and W a D^-1 written in place; 38 % after, same
 * arithmetic in the same order, so the same results to the bit). The 3x3 products run two
 * columns at a time (mat3.h, the same operations per entry), R^T enters through transposed
 * products instead of a copy, the fused sweep hands its frame over (cbm__mech_factor_one's
 * frame) and J_r is formed in the fewest operations that give its bits (cbm__m3_jr).
 *
 * Stability: for a conservative load the Newton matrix is (nearly) symmetric and the D_i are
 * the pivots of its block elimination, so the equilibrium is stable when every D_i has a
 * positive definite symmetric part (Sylvester's criterion); the count of those that do not is
 * returned. With mu > 0 the factorisation is that of J + mu S exactly (S only enters the
 * pivots), the Levenberg-Marquardt shift the fast solver uses to descend to stable states.
 */
#define _POSIX_C_SOURCE 200809L
#include "mech/mech_internal.h"
#include "mech/mat3.h"
#include "mech/sweep_internal.h"
#include "core/vecmath.h"

#include <math.h>
#include <pthread.h>
#include <string.h>
#include <unistd.h>

typedef struct m3 {
    double m[9]; /* row-major */
} m3;

static inline m3 skew(cbm_vec3 v)
{
    m3 r = {{0, -v.z, v.y, v.z, 0, -v.x, -v.y, v.x, 0}};
    return r;
}

static inline m3 mmul(const double *a, const double *b)
{
    m3 r;
    cbm__m3_mul(r.m, a, b);
    /* written whole by the vector stores, which cppcheck does not follow */
    // cppcheck-suppress uninitvar
    return r;
}

/* out = a b (out must not alias a or b) */
static inline void mmul_to(double *restrict out, const double *a, const double *b)
{
    cbm__m3_mul(out, a, b);
}

static inline cbm_vec3 mvec(const double *a, cbm_vec3 v)
{
    return v3(a[0] * v.x + a[1] * v.y + a[2] * v.z, a[3] * v.x + a[4] * v.y + a[5] * v.z,
              a[6] * v.x + a[7] * v.y + a[8] * v.z);
}

/* Inverse; false if singular relative to `scale` (a typical entry^3). */
static inline bool minv(const double *a, double scale, double *out)
{
    double c0 = a[4] * a[8] - a[5] * a[7], c1 = a[5] * a[6] - a[3] * a[8],
           c2 = a[3] * a[7] - a[4] * a[6];
    double det = a[0] * c0 + a[1] * c1 + a[2] * c2;
    if (!(fabs(det) > 1e-13 * scale) || !isfinite(det) || det == 0.0)
        return false;
    double id = 1.0 / det;
    out[0] = c0 * id;
    out[1] = (a[2] * a[7] - a[1] * a[8]) * id;
    out[2] = (a[1] * a[5] - a[2] * a[4]) * id;
    out[3] = c1 * id;
    out[4] = (a[0] * a[8] - a[2] * a[6]) * id;
    out[5] = (a[2] * a[3] - a[0] * a[5]) * id;
    out[6] = c2 * id;
    out[7] = (a[1] * a[6] - a[0] * a[7]) * id;
    out[8] = (a[0] * a[4] - a[1] * a[3]) * id;
    return true;
}

/* R (local to world) as a row-major matrix: columns H, L, U. */
static inline m3 rotation_matrix(cbm_quat q)
{
    double xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
    double xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
    double wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
    m3 r = {{1.0 - 2.0 * (yy + zz), 2.0 * (xy - wz), 2.0 * (xz + wy), 2.0 * (xy + wz),
             1.0 - 2.0 * (xx + zz), 2.0 * (yz - wx), 2.0 * (xz - wy), 2.0 * (yz + wx),
             1.0 - 2.0 * (xx + yy)}};
    return r;
}

typedef cbm__mech_fsweep sweep;

static void forward_solve(cbm_plant *p, cbm_vec3 *out);
static void forward_step(cbm_plant *p, double *turn2);
static void forward_all(cbm_plant *p, cbm_vec3 *out, int t, double *turn2);
static inline __attribute__((always_inline)) void
solve_back(const sweep *sw, size_t i, const double *R, const double *wad, bool act, bool defer);

/* Number of negative eigenvalues of the symmetric part of a 3x3 block: its characteristic
 * polynomial has only real roots, so by Descartes' rule the negative ones are the sign changes
 * of (1, trace, sum of the principal 2x2 minors, determinant) (zeros skipped: zero eigenvalues
 * are critical, not unstable). Summed over the pivots this is the inertia of the matrix
 * (Sylvester's law: the block elimination is a congruence when the matrix is symmetric). */
static size_t sym_negative(const double *d)
{
    double a = d[0], b = 0.5 * (d[1] + d[3]), c = 0.5 * (d[2] + d[6]);
    double e = d[4], f = 0.5 * (d[5] + d[7]), g = d[8];
    double co[4] = {1.0, a + e + g, a * e - b * b + a * g - c * c + e * g - f * f,
                    a * (e * g - f * f) - b * (b * g - f * c) + c * (b * f - e * c)};
    /* a coefficient at rounding level is zero: an eigenvalue within 1e-9 of the block's scale
     * of 0 is neutral (the rotation of a round column's bent shape about the vertical), not
     * unstable */
    double sc = fabs(a) + fabs(e) + fabs(g), tol = 1e-9 * sc;
    size_t changes = 0;
    double last = 1.0;
    for (int k = 1; k < 4; k++, tol *= sc)
        if (fabs(co[k]) > tol) {
            changes += (co[k] > 0.0) != (last > 0.0);
            last = co[k];
        }
    return changes;
}

/* Is the symmetric part of the 3x3 block positive definite (Sylvester's criterion)? */
static inline bool sym_pd(const double *d)
{
    double a = d[0], b = 0.5 * (d[1] + d[3]), c = 0.5 * (d[2] + d[6]);
    double e = d[4], f = 0.5 * (d[5] + d[7]), g = d[8];
    double m2 = a * e - b * b;
    double m3d = a * (e * g - f * f) - b * (b * g - f * c) + c * (b * f - e * c);
    return a > 0.0 && m2 > 0.0 && m3d > 0.0;
}

static inline void madd(double *a, const double *b)
{
#pragma GCC unroll 9
    for (int k = 0; k < 9; k++)
        a[k] += b[k];
}

/* B = -l [H]x: the displacement of the distal node per rotation of the segment's frame */
static inline m3 node_lever(cbm_vec3 h, double l)
{
    m3 b = skew(h);
    for (int k = 0; k < 9; k++)
        b.m[k] *= -l;
    return b;
}

/* The contact terms of segment i before its pivot (see the comment at the top): from the
 * accumulated Gamma, Lambda, Xi of its children and its own contact stiffness, adds
 * Gamma B - B Z to W and returns Xi' (in *xi), Z and Y. */
static void contact_pre(const cbm_plant *p, size_t i, cbm_vec3 h, double *W, m3 *xi, m3 *z, m3 *y)
{
    const cbm__mech_work *w = &p->work;
    m3 B = node_lever(h, p->len[i]);
    memcpy(xi->m, w->fxi + 9 * i, sizeof xi->m);
    double kc;
    (void)cbm__mech_contact(p, i, h, &kc);
    xi->m[4] += kc; /* d force.y / d height of the node (<= 0) */
    m3 xb = mmul(xi->m, B.m);
    const double *lam = w->flam + 9 * i, *gam = w->fgam + 9 * i;
    for (int k = 0; k < 9; k++)
        z->m[k] = lam[k] + xb.m[k];
    m3 gb = mmul(gam, B.m), bz = mmul(B.m, z->m), bx = mmul(B.m, xi->m);
    for (int k = 0; k < 9; k++) {
        W[k] += gb.m[k] - bz.m[k];
        y->m[k] = gam[k] - bx.m[k];
    }
}

/* The factorisation of segment i (its children's Phi, and with ground their Gamma, Lambda and
 * Xi, are in its accumulators) and, with sw->b, the backward half of the solve there. With
 * defer (a subtree a thread sweeps, see "Threads" below) Phi is left in fw[i] and psi in dm[i]
 * for the sweep of the top to add into the parent, in the serial order. */
void cbm__mech_factor_one(sweep *sw, size_t i, bool defer, const double *frame)
{
    cbm_plant *p = sw->p;
    cbm__mech_work *w = &p->work;
    const bool ground = sw->ground;
    const double mu = sw->mu;
    /* R = [H L U]; R^T enters through the transposed products (cbm__m3_mul_tn) */
    m3 Rq;
    if (!frame) {
        Rq = rotation_matrix(p->q[i]);
        frame = Rq.m;
    }
    const double *R = frame;
    if (sw->only_solve) {
        solve_back(sw, i, R, w->fwad + 9 * i, ground && w->fact[i], defer);
        return;
    }
    {
        cbm_vec3 h = v3(R[0], R[3], R[6]);
        cbm_vec3 V = v3_add(v3_scale(v3_sub(p->force[i], w->wown[i]), p->len[i]),
                            v3_scale(w->wown[i], w->lever[i]));
        /* G = [V]x [H]x = H V^T - (V.H) I; W = the children's Phi (none: zero) + G */
        double *W = w->fw + 9 * i;
        double vh = v3_dot(V, h);
        const double hv[3] = {h.x, h.y, h.z}, vv[3] = {V.x, V.y, V.z};
        const uint8_t kin = w->kin[i];
        const bool leaf = !(kin & CBM__KIN_CHILDREN);
#pragma GCC unroll 9
        for (int r0 = 0; r0 < 3; r0++)
#pragma GCC unroll 9
            for (int c0 = 0; c0 < 3; c0++)
                W[3 * r0 + c0] =
                    (leaf ? 0.0 : W[3 * r0 + c0]) + (hv[r0] * vv[c0] - (r0 == c0 ? vh : 0.0));
        const bool act = ground && w->fact[i];
        m3 Xi, Z, Y;
        if (act)
            contact_pre(p, i, h, W, &Xi, &Z, &Y);
        m3 WM = skew(p->moment[i]);
#pragma GCC unroll 9
        for (int k = 0; k < 9; k++)
            WM.m[k] += W[k];
        double *Q = w->fq + 9 * i;
        cbm__m3_mul_tn(Q, R, WM.m);
        /* a = R J_r(r) d */
        double d = w->dual[i];
        cbm_vec3 r = v3_scale(p->omega[i], d);
        double t2 = v3_norm2(r), c1, c2;
        cbm__mech_jr_coeffs(t2, &c1, &c2);
        /* J = I - c1 [r]x + c2 [r]x^2 (cbm__m3_jr) */
        m3 J;
        cbm__m3_jr(J.m, r, t2, c1, c2);
        double *A = w->fa + 9 * i;
        cbm__m3_mul_scale(A, R, J.m, d);
        /* D = S - Q a: the negated product, S added on the diagonal */
        m3 D;
        cbm__m3_mul_neg(D.m, Q, A);
        cbm_vec3 c = w->cj[i];
        D.m[0] += (1.0 + mu) * c.x;
        D.m[4] += (1.0 + mu) * c.y;
        D.m[8] += (1.0 + mu) * c.z;
        double *Di = w->fdinv + 9 * i;
        if (!sym_pd(D.m)) {
            sw->nonpd++; /* the subtree condensed here has lost its stiffness: unstable */
            sw->negative += sym_negative(D.m);
        }
        if (!minv(D.m, c.x * c.y * c.z, Di)) {
            sw->singular++;
            memset(Di, 0, 9 * sizeof(double));
            Di[0] = 1.0 / c.x;
            Di[4] = 1.0 / c.y;
            Di[8] = 1.0 / c.z;
        }
        /* W a D^-1 stays in a local: it is stored (fwad) with ground contact only, and
         * otherwise computed again from W (kept in fw), a and D^-1 when a solve alone needs it
         * (wad_all), with the same products: 72 bytes a segment less to write per sweep */
        m3 AD = mmul(A, Di), WADm;
        double *WAD = ground ? w->fwad + 9 * i : WADm.m;
        mmul_to(WAD, W, AD.m);
        /* Phi = W (I + A D^-1 Q) = W + (W A D^-1) Q */
        m3 Phi;
        cbm__m3_mul_add(Phi.m, WAD, Q, W);
        int64_t pa = p->parent[i];
        if (defer) /* for the sweep of the top; W stays */
            memcpy(w->fwad + 9 * i, Phi.m, sizeof Phi.m);
        else if (pa >= 0)
            cbm__kin_add9(w->fw + 9 * (size_t)pa, Phi.m, (kin & CBM__KIN_FIRST) != 0);
        if (act) {
            /* Gamma = W a D^-1 P + Y, Lambda = Z + (Z a D^-1) Q, Xi = (Z a D^-1) P + Xi' */
            m3 P, ZAD = mmul(Z.m, AD.m);
            cbm__m3_mul_tn(P.m, R, Y.m);
            m3 gam = mmul(WAD, P.m), lam = mmul(ZAD.m, Q), xi = mmul(ZAD.m, P.m);
            memcpy(w->fp + 9 * i, P.m, sizeof P.m);
            memcpy(w->fzad + 9 * i, ZAD.m, sizeof ZAD.m);
            if (pa >= 0) {
                madd(gam.m, Y.m);
                madd(lam.m, Z.m);
                madd(xi.m, Xi.m);
                madd(w->fgam + 9 * (size_t)pa, gam.m);
                madd(w->flam + 9 * (size_t)pa, lam.m);
                madd(w->fxi + 9 * (size_t)pa, xi.m);
            }
        }
        if (sw->b && sw->out)
            solve_back(sw, i, R, WAD, act, defer);
    }
}

/* W a D^-1 of every segment from W (fw), a and D^-1, the products of cbm__mech_factor_one: the
 * same bits as the sweep computed (it keeps them only with ground contact). */
static void wad_all(cbm_plant *p)
{
    cbm__mech_work *w = &p->work;
    for (size_t i = 0; i < p->n; i++) {
        m3 AD = mmul(w->fa + 9 * i, w->fdinv + 9 * i);
        mmul_to(w->fwad + 9 * i, w->fw + 9 * i, AD.m);
    }
    w->fwad_ok = true;
}

/* ---- Threads
 * Disjoint subtrees are independent in both sweeps: a thread can condense one from its tips
 * while another condenses another; only what a subtree hands to its parent meets the rest. So
 * the tree is split into the "top" (segments carrying more than a sixteenth of the tree per
 * thread) and the subtrees hanging from it ("roots": a segment outside the top whose parent is in
 * it), dealt to the threads in index order, each to the least loaded (by segments). The backward
 * sweep runs each thread over its subtrees (in decreasing index, as the serial sweep), the roots
 * keeping what they hand down (Phi in fw, psi in dm); then one sweep over the top, again in
 * decreasing index, adds a root's hand-down where the serial sweep would have and factors the
 * top's segments. Every accumulator so receives the same terms in the same order as in the serial
 * sweep, so the results are the same to the bit for any number of threads. The forward sweep
 * runs the top first, then the subtrees in parallel. A chain (no branch carries a small part of
 * the tree) and a plant with ground contact stay serial. Entry per segment in tpart: bits 0-27
 * the subtree size, then the thread (0: top) and the root bit. */
#define PART_SIZE   CBM__PART_SIZE
#define PART_SHIFT  CBM__PART_SHIFT
#define PART_ROOT   CBM__PART_ROOT
#define MAX_THREADS 7

static size_t tree_min_segments = 50000;

void cbm__mech_tree_min_segments(size_t min_segments)
{
    tree_min_segments = min_segments;
}

/* The split for n segments into tpart; returns the threads (1: serial). */
static int split_compute(cbm_plant *p, int t)
{
    const size_t n = p->n;
    if (t < 2 || n < tree_min_segments || n < 2 || n > PART_SIZE || !p->work.tpart)
        return 1;
    uint32_t *part = p->work.tpart;
    const int64_t *par = p->parent;
    for (size_t i = 0; i < n; i++)
        part[i] = 1;
    for (size_t i = n; i-- > 1;)
        if (par[i] >= 0)
            part[par[i]] += part[i];
    size_t limit = n / (16 * (size_t)t), top = 0;
    size_t load[MAX_THREADS + 1] = {0};
    for (size_t i = 0; i < n; i++) {
        uint32_t sz = part[i] & PART_SIZE;
        int64_t pa = par[i];
        if (sz > limit) {
            top++; /* thread 0 */
            continue;
        }
        uint32_t pp = pa >= 0 ? part[pa] : 0;
        if (pa >= 0 && (pp >> PART_SHIFT & 7u) != 0) {
            part[i] |= pp & (7u << PART_SHIFT); /* its parent's thread */
            continue;
        }
        int best = 1;
        for (int k = 2; k <= t; k++)
            if (load[k] < load[best])
                best = k;
        load[best] += sz;
        /* a root of the plant (a forest's small tree) hands nothing to a parent: its thread
         * sweeps it whole, the top's sweep never meets it */
        part[i] |= ((uint32_t)best << PART_SHIFT) | (pa >= 0 ? PART_ROOT : 0u);
    }
    return top * 4 > n ? 1 : t; /* mostly a chain: the threads would wait on the top */
}

static int processors = 1;
static pthread_once_t processors_once = PTHREAD_ONCE_INIT;

static void processors_count(void)
{
    long np = sysconf(_SC_NPROCESSORS_ONLN);
    processors = np > 0 ? (int)(np < 64 ? np : 64) : 1;
}

int cbm__mech_tree_threads(const cbm_plant *p)
{
    if (p->n < tree_min_segments || p->n < 2)
        return 1;
    int t = p->threads;
    if (t <= 0) {
        pthread_once(&processors_once, processors_count); /* sysconf reads files: once */
        t = processors;
    }
    return t > MAX_THREADS ? MAX_THREADS : t;
}

int cbm__mech_tree_split(cbm_plant *p)
{
    cbm__mech_work *w = &p->work;
    if (p->n < tree_min_segments || p->n < 2)
        return 1; /* before anything else: the small plants of a growth run pay nothing */
    int t = cbm__mech_tree_threads(p);
    if (w->tsplit > 0 && w->tsplit_req == t && w->tsplit_min == tree_min_segments &&
        w->tsplit_sorted == p->sorder.active)
        return w->tsplit;
    w->tsplit = split_compute(p, t);
    w->tsplit_req = t;
    w->tsplit_min = tree_min_segments;
    w->tsplit_sorted = p->sorder.active;
    return w->tsplit;
}

typedef struct run_arg {
    void (*fn)(void *);
    void *arg;
} run_arg;

static void *run_one(void *arg)
{
    run_arg *r = arg;
    r->fn(r->arg);
    return NULL;
}

void cbm__mech_run_threads(int t, void (*fn)(void *), void *args, size_t size)
{
    pthread_t th[MAX_THREADS];
    run_arg ra[MAX_THREADS];
    bool started[MAX_THREADS] = {false};
    if (t > MAX_THREADS)
        t = MAX_THREADS;
    for (int k = 1; k < t; k++) {
        ra[k] = (run_arg){fn, (char *)args + (size_t)k * size};
        started[k] = pthread_create(&th[k], NULL, run_one, &ra[k]) == 0;
    }
    fn(args);
    for (int k = 1; k < t; k++) {
        if (started[k])
            pthread_join(th[k], NULL);
        else
            fn((char *)args + (size_t)k * size);
    }
}

typedef struct tree_job {
    sweep sw;
    int thread;
    bool forward;
    bool step;    /* forward: the Newton step's fused sweep (forward_step_one) */
    double turn2; /* with step: the largest |dth|^2 of the thread's segments */
} tree_job;

static void forward_one(cbm_plant *p, size_t i, cbm_vec3 *out, bool ground);
static void forward_step_one(cbm_plant *p, size_t i, double *turn2);

static void tree_job_run(void *arg)
{
    tree_job *j = arg;
    cbm_plant *p = j->sw.p;
    const uint32_t *part = p->work.tpart;
    const uint32_t me = (uint32_t)j->thread;
    const int64_t *par = p->parent;
    const double *dth = (const double *)p->work.dth;
    if (j->forward && j->step) {
        const double *q = (const double *)p->q, *pos = (const double *)p->pos;
        for (size_t i = 0; i < p->n; i++) {
            CBM__PREFETCH_PARENT_FWD(par, i, p->n, dth, 3);
            CBM__PREFETCH_PARENT_FWD(par, i, p->n, q, 4);
            CBM__PREFETCH_PARENT_FWD(par, i, p->n, pos, 3);
            CBM__PREFETCH_PARENT_FWD(par, i, p->n, p->len, 1);
            if ((part[i] >> PART_SHIFT & 7u) == me)
                forward_step_one(p, i, &j->turn2);
        }
        return;
    }
    if (j->forward) {
        for (size_t i = 0; i < p->n; i++) {
            CBM__PREFETCH_PARENT_FWD(par, i, p->n, dth, 3);
            if ((part[i] >> PART_SHIFT & 7u) == me)
                forward_one(p, i, j->sw.out, false);
        }
        return;
    }
    double *fw = p->work.fw, *dm = (double *)p->work.dm;
    const bool solve = j->sw.b && j->sw.out;
    for (size_t i = p->n; i-- > 0;) {
        if (!j->sw.only_solve)
            CBM__PREFETCH_PARENT_BWD(par, i, fw, 9);
        if (solve)
            CBM__PREFETCH_PARENT_BWD(par, i, dm, 3);
        if ((part[i] >> PART_SHIFT & 7u) == me)
            cbm__mech_factor_one(&j->sw, i, (part[i] & PART_ROOT) != 0, NULL);
    }
}

/* Runs the sweep's share of threads 1..t and adds up their counts; with turn2 (a forward
 * sweep), the Newton step's fused sweep, *turn2 raised to the threads' largest |dth|^2. */
static void tree_parallel(const sweep *sw, int t, bool forward, size_t *singular, size_t *nonpd,
                          size_t *negative, double *turn2)
{
    tree_job jobs[MAX_THREADS];
    memset(jobs, 0, sizeof jobs);
    for (int k = 0; k < t; k++) {
        jobs[k].sw = *sw;
        jobs[k].sw.singular = jobs[k].sw.nonpd = jobs[k].sw.negative = 0;
        jobs[k].thread = k + 1;
        jobs[k].forward = forward;
        jobs[k].step = turn2 != NULL;
    }
    cbm__mech_run_threads(t, tree_job_run, jobs, sizeof *jobs);
    for (int k = 0; k < t; k++) {
        *singular += jobs[k].sw.singular;
        *nonpd += jobs[k].sw.nonpd;
        *negative += jobs[k].sw.negative;
        if (turn2 && jobs[k].turn2 > *turn2) /* a maximum: the same whatever the order */
            *turn2 = jobs[k].turn2;
    }
}

/* The backward sweep of sw over the plant, then (with out) the forward sweep: serial, or split
 * over threads (see "Threads"). */
static void sweeps(sweep *sw)
{
    cbm_plant *p = sw->p;
    cbm__mech_work *w = &p->work;
    const size_t n = p->n;
    int t = sw->ground ? 1 : cbm__mech_tree_split(p);
    if (t <= 1) {
        const int64_t *par = p->parent;
        double *fw = w->fw, *dm = (double *)w->dm;
        const bool solve = sw->b && sw->out;
        for (size_t i = n; i-- > 0;) {
            if (!sw->only_solve)
                CBM__PREFETCH_PARENT_BWD(par, i, fw, 9);
            if (solve)
                CBM__PREFETCH_PARENT_BWD(par, i, dm, 3);
            cbm__mech_factor_one(sw, i, false, NULL);
        }
    } else {
        tree_parallel(sw, t, false, &sw->singular, &sw->nonpd, &sw->negative, NULL);
        const uint32_t *part = w->tpart;
        const bool solve = sw->b && sw->out;
        for (size_t i = n; i-- > 0;) {
            uint32_t e = part[i];
            if ((e >> PART_SHIFT & 7u) == 0) {
                cbm__mech_factor_one(sw, i, false, NULL);
            } else if (e & PART_ROOT) {
                int64_t pa = p->parent[i]; /* in the top */
                bool first = (w->kin[i] & CBM__KIN_FIRST) != 0;
                if (!sw->only_solve) /* Phi, kept in fwad */
                    cbm__kin_add9(w->fw + 9 * (size_t)pa, w->fwad + 9 * i, first);
                if (solve)
                    cbm__kin_add3(&w->dm[pa], w->dm[i], first);
            }
        }
    }
    if (sw->b && sw->out)
        forward_all(p, sw->out, t, NULL);
}

/* The forward half of the solve into out, serial or over t threads; with turn2, the Newton
 * step's fused sweep instead (forward_step_one: out is work.tmp), the largest |dth|^2 into
 * *turn2. */
static void forward_all(cbm_plant *p, cbm_vec3 *out, int t, double *turn2)
{
    if (t <= 1) {
        if (turn2)
            forward_step(p, turn2);
        else
            forward_solve(p, out);
        return;
    }
    const uint32_t *part = p->work.tpart;
    for (size_t i = 0; i < p->n; i++)
        if ((part[i] >> PART_SHIFT & 7u) == 0) {
            if (turn2)
                forward_step_one(p, i, turn2);
            else
                forward_one(p, i, out, false);
        }
    sweep sw = {.p = p, .out = out};
    size_t none = 0;
    tree_parallel(&sw, t, true, &none, &none, &none, turn2);
}

void cbm__mech_factor_clear(cbm_plant *p, bool solving)
{
    /* W and psi need no clearing (work.kin); the ground's force accumulators are still cleared,
     * read with ground contact only */
    cbm__mech_work *w = &p->work;
    if (solving && p->ground && w->fcap >= p->n)
        memset(w->dfc, 0, p->n * sizeof *w->dfc);
}

/* The factorisation; with b != NULL also the backward half of the solve J out = b (fused, so a
 * factor-and-solve is one backward and one forward sweep). Returns the number of joints whose
 * D was singular and replaced by S. */
static size_t factor(cbm_plant *p, const cbm_vec3 *b, cbm_vec3 *out, double mu, size_t *nonpd_out)
{
    cbm__mech_work *w = &p->work;
    const size_t n = p->n;
    const bool ground = p->ground && w->fcap >= n;
    if (!b && mu == 0.0 && w->fready) {
        /* the fused evaluation of this very state factorised it already: the same bits */
        w->fhalf = false;
        if (nonpd_out)
            *nonpd_out = w->fnonpd;
        return w->fsing;
    }
    cbm__mech_fused_clear(p);
    cbm__mech_factor_clear(p, b && out);
    if (ground) {
        memset(w->fact, 0, n);
        for (size_t i = 0; i < n; i++) {
            double kc;
            cbm_vec3 h = q_h(p->q[i]);
            (void)cbm__mech_contact(p, i, h, &kc);
            /* mark the path to the root; only marked segments read or receive the contact
             * accumulators, so only theirs need clearing */
            for (int64_t j = (int64_t)i; kc != 0.0 && j >= 0 && !w->fact[j]; j = p->parent[j]) {
                w->fact[j] = 1;
                memset(w->fgam + 9 * j, 0, 9 * sizeof(double));
                memset(w->flam + 9 * j, 0, 9 * sizeof(double));
                memset(w->fxi + 9 * j, 0, 9 * sizeof(double));
            }
        }
    }
    sweep sw = {.p = p, .b = b, .out = out, .mu = mu, .ground = ground};
    w->fwad_ok = ground;
    sweeps(&sw);
    if (nonpd_out)
        *nonpd_out = sw.nonpd;
    w->fneg = sw.negative;
    return sw.singular;
}

bool cbm__mech_tree_solve_fused(cbm_plant *p, size_t *singular, size_t *nonpd)
{
    cbm__mech_work *w = &p->work;
    if (!w->fready || !w->fhalf)
        return false;
    w->fhalf = false;
    forward_all(p, w->tmp, cbm__mech_tree_split(p), NULL);
    *singular = w->fsing;
    if (nonpd)
        *nonpd = w->fnonpd;
    return true;
}

bool cbm__mech_tree_step_fused(cbm_plant *p, double *turn)
{
    cbm__mech_work *w = &p->work;
    if (!w->fready || !w->fhalf || w->fsing != 0 || w->fnonpd != 0 || p->ground)
        return false;
    double turn2 = 0.0;
    forward_all(p, w->tmp, cbm__mech_tree_split(p), &turn2);
    cbm__mech_fused_clear(p); /* the frames moved: the factorisation is of the state before */
    *turn = sqrt(turn2);
    return true;
}

size_t cbm__mech_tree_factor(cbm_plant *p, double mu, size_t *nonpd)
{
    return factor(p, NULL, NULL, mu, nonpd);
}

size_t cbm__mech_tree_solve(cbm_plant *p, const cbm_vec3 *b, cbm_vec3 *out, double mu,
                            size_t *nonpd)
{
    return factor(p, b, out, mu, nonpd);
}

size_t cbm__mech_tree_perturb_unstable(cbm_plant *p, double angle)
{
    /* after an unmodified factorisation: push every joint whose pivot block is not positive
     * definite along D^-1 (1,1,1) (one step of inverse iteration towards the soft mode), by
     * `angle` rad over the joint's length */
    cbm__mech_work *w = &p->work;
    size_t k = 0;
    cbm__mech_fused_clear(p); /* Omega moves */
    for (size_t i = 0; i < p->n; i++) {
        double d[9];
        const double *di = w->fdinv + 9 * i;
        if (minv(di, 0.0, d) && sym_pd(d))
            continue;
        cbm_vec3 v = mvec(di, v3(1, 1, 1));
        double nv = v3_norm(v);
        if (!(nv > 0.0) || !isfinite(nv))
            v = v3(0, 1, 0), nv = 1.0;
        p->omega[i] = v3_add(p->omega[i], v3_scale(v, angle / (nv * w->dual[i])));
        k++;
    }
    return k;
}

void cbm__mech_tree_apply(cbm_plant *p, const cbm_vec3 *b, cbm_vec3 *out)
{
    cbm__mech_work *w = &p->work;
    const size_t n = p->n;
    const bool ground = p->ground && w->fcap >= n;
    w->fhalf = false; /* dm and perhaps tmp are written; the factorisation stays */
    if (!w->fwad_ok)
        wad_all(p);
    if (ground) /* psi needs no clearing (work.kin) */
        memset(w->dfc, 0, n * sizeof *w->dfc);
    sweep sw = {.p = p, .b = b, .out = out, .ground = ground, .only_solve = true};
    sweeps(&sw);
}

/* The backward half of a solve at segment i: from psi and chi of its children (accumulated in
 * work.dm and work.dfc), u_i into out[i], and its own psi and chi added into its parent's (with
 * defer psi is left in dm[i] instead, for the sweep of the top; never with ground contact). */
static inline __attribute__((always_inline)) void
solve_back(const sweep *sw, size_t i, const double *R, const double *wad, bool act, bool defer)
{
    const cbm_vec3 *b = sw->b;
    cbm_vec3 *out = sw->out;
    if (!b || !out)
        return; /* no right-hand side: nothing to solve (callers pass both) */
    cbm_plant *p = sw->p;
    cbm__mech_work *w = &p->work;
    const uint8_t kin = w->kin[i];
    /* sum of the children's psi (+ the contact term below) */
    cbm_vec3 m0 = (kin & CBM__KIN_CHILDREN) ? w->dm[i] : v3(0, 0, 0);
    cbm_vec3 f0 = act ? w->dfc[i] : v3(0, 0, 0);
    if (act) {
        /* m0 = sum psi - B sum chi = sum psi + l H x sum chi */
        cbm_vec3 h = v3(R[0], R[3], R[6]);
        m0 = v3_add(m0, v3_scale(v3_cross(h, f0), p->len[i]));
    }
    cbm_vec3 bi = sw->neg_b ? v3_scale(b[i], -1.0) : b[i];
    cbm_vec3 ui = v3_add(bi, cbm__m3_vec_t(R, m0));
    out[i] = ui;
    int64_t pa = p->parent[i];
    if (pa < 0)
        return;
    cbm_vec3 psi = v3_add(mvec(wad, ui), m0);
    if (defer) {
        w->dm[i] = psi; /* not read again */
        return;
    }
    cbm__kin_add3(&w->dm[pa], psi, (kin & CBM__KIN_FIRST) != 0);
    if (act) {
        cbm_vec3 chi = v3_add(mvec(w->fzad + 9 * i, ui), f0);
        w->dfc[pa] = v3_add(w->dfc[pa], chi);
    }
}

/* The forward half of the solve at segment i (its parent's dth, and dX with ground, known). */
static void forward_one(cbm_plant *p, size_t i, cbm_vec3 *out, bool ground)
{
    cbm__mech_work *w = &p->work;
    cbm_vec3 *dth = w->dth, *dx = w->dpos; /* dpos: displacement of the distal node here */
    int64_t pa = p->parent[i];
    cbm_vec3 tp = pa >= 0 ? dth[pa] : v3(0, 0, 0);
    cbm_vec3 rhs = v3_add(out[i], mvec(w->fq + 9 * i, tp));
    const bool act = ground && w->fact[i];
    cbm_vec3 xp = v3(0, 0, 0);
    if (act) {
        xp = pa >= 0 ? dx[pa] : v3(0, 0, 0);
        rhs = v3_add(rhs, mvec(w->fp + 9 * i, xp));
    }
    cbm_vec3 v = mvec(w->fdinv + 9 * i, rhs);
    out[i] = v;
    dth[i] = v3_add(tp, mvec(w->fa + 9 * i, v));
    if (act) {
        /* dX_i = dX_parent + l_i dth_i x H_i */
        cbm_vec3 h = q_h(p->q[i]);
        dx[i] = v3_add(xp, v3_scale(v3_cross(dth[i], h), p->len[i]));
    }
}

static void forward_solve(cbm_plant *p, cbm_vec3 *out)
{
    const bool ground = p->ground && p->work.fcap >= p->n;
    const int64_t *par = p->parent;
    const double *dth = (const double *)p->work.dth;
    for (size_t i = 0; i < p->n; i++) {
        CBM__PREFETCH_PARENT_FWD(par, i, p->n, dth, 3);
        forward_one(p, i, out, ground);
    }
}

/* The Newton step's fused sweep at segment i (its parent done; no ground: the fused
 * evaluation has none): the forward half of the solve (as forward_one: v_i from u_i in
 * work.tmp, dth_i), the step v_i into work.step, the old Omega_i into work.tmp (for a
 * restore), Omega_i + 1.0 v_i (the line search's first trial, its very arithmetic) and the
 * forward sweep of the evaluation there (cbm__mech_forward_seg, forces and moments left for
 * the backward sweep). *turn2: the largest |dth|^2 so far (largest_turn's maximum). */
static void forward_step_one(cbm_plant *p, size_t i, double *turn2)
{
    cbm__mech_work *w = &p->work;
    forward_one(p, i, w->tmp, false); /* v_i over u_i in tmp, dth_i */
    cbm_vec3 v = w->tmp[i];
    w->step[i] = v;
    double t = v3_norm2(w->dth[i]);
    if (t > *turn2)
        *turn2 = t;
    cbm_vec3 o = p->omega[i];
    w->tmp[i] = o;
    p->omega[i] = v3_add(o, v3_scale(v, 1.0));
    cbm__mech_forward_seg(p, i, false);
}

static void forward_step(cbm_plant *p, double *turn2)
{
    const int64_t *par = p->parent;
    const size_t n = p->n;
    const double *dth = (const double *)p->work.dth;
    const double *q = (const double *)p->q, *pos = (const double *)p->pos;
    for (size_t i = 0; i < n; i++) {
        CBM__PREFETCH_PARENT_FWD(par, i, n, dth, 3);
        CBM__PREFETCH_PARENT_FWD(par, i, n, q, 4);
        CBM__PREFETCH_PARENT_FWD(par, i, n, pos, 3);
        CBM__PREFETCH_PARENT_FWD(par, i, n, p->len, 1);
        forward_step_one(p, i, turn2);
    }
}
