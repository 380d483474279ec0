/* The plant data structure: segments struct-of-arrays in topological order, a pool of rings per
 * segment, the section aggregates the solvers use, queries, subtree removal and the scene
 * export.
 *
 * Section aggregates: for rings k = 0..n-1
 * (innermost first) with outer semi-axes (a_k, b_k) and inner semi-axes (a_{k-1}, b_{k-1})
 * (0 for the core), the ring's second moments are the differences of the solid-ellipse values
 *   I_L = pi a^3 b / 4 (bending about L; U is along the long semi-axis a: Taylor-Hell 8.9-8.10,
 *   erratum 3 of the digest: the thesis' code swapped them), I_U = pi a b^3 / 4,
 *   J = pi a^3 b^3 / (a^2 + b^2) (torsion constant of an ellipse),
 * so C = sum_k (G_k J_k, E_k I_L,k, E_k I_U,k) (Taylor-Hell 6.25-6.28, 6.33-6.34), and the rest
 * rotation rate is the rigidity-weighted mean, per local component c in {H, L, U},
 *   rest_c = sum_k C_k,c rest_k,c / sum_k C_k,c,
 * which is the closed form of the incremental averaging of Jirasek eq. 24 = Taylor-Hell
 * 6.29-6.31 (adding ring k with rest rate r_k to a core of rigidity C and rest rate R gives
 * (C R + C_k r_k) / (C + C_k)). The mass per length is sum_k density_k * ring area. The plant
 * keeps the sums C, sum_k C_k rest_k, the mass per length and the outer area per segment, so a
 * new outer ring (cbm_plant_add_ring, once per segment and growth step) adds its own terms in
 * O(1); replacing a ring or ageing the wood (which changes E of old rings) recomputes the sums
 * over all rings. Both paths run the same function in the same order of operations, so the
 * incremental sums are bit for bit those of a full recompute.
 *
 * Rings live in one pool; each segment owns a run of ring_cap slots starting at ring_first, of
 * which the first ring_count hold its rings (innermost first). A ring added to a full run grows
 * the run in place if it ends the pool, else moves it to the end of the pool with twice the
 * capacity, into a hole of that capacity if there is one (free lists per capacity class) or at
 * the end of the pool: amortised O(1) copies per ring, no allocation beyond the pool's geometric
 * growth (by half). The runs of removed segments become holes too. The pool is compacted (runs in
 * segment order, capacities kept) when more than half of it is holes.
 */
#include "mech/mech_internal.h"
#include "mech/fem_internal.h"
#include "core/vecmath.h"

#include <math.h>
#include <stdio.h>

/* ---- small helpers ---- */

const char *cbm_mech_discretization_name(cbm_mech_discretization d)
{
    return d == CBM_MECH_CHAIN ? "chain" : "staggered";
}

/* One row per solver: adding a method is one row (its name first, then its aliases). */
static const struct {
    cbm_mech_solver solver;
    const char *names[4];
} solver_table[] = {
    {CBM_MECH_RELAX, {"relax", "relaxation"}},
    {CBM_MECH_NEWTON, {"fast", "newton", "newton-krylov"}},
    {CBM_MECH_APPROX, {"approx", "approximative"}},
    {CBM_MECH_FEM, {"fem"}},
};
#define SOLVER_ROWS (sizeof solver_table / sizeof solver_table[0])
_Static_assert(SOLVER_ROWS == CBM_MECH_SOLVER_COUNT, "one row per solver");

const char *cbm_mech_solver_name(cbm_mech_solver s)
{
    for (size_t i = 0; i < SOLVER_ROWS; i++)
        if (solver_table[i].solver == s)
            return solver_table[i].names[0];
    return NULL;
}

bool cbm_mech_solver_parse(const char *name, cbm_mech_solver *out)
{
    if (!name || !out)
        return false;
    for (size_t i = 0; i < SOLVER_ROWS; i++)
        for (size_t k = 0; k < 4 && solver_table[i].names[k]; k++)
            if (!strcmp(name, solver_table[i].names[k])) {
                *out = solver_table[i].solver;
                return true;
            }
    return false;
}

size_t cbm_mech_solver_names(char *buf, size_t size)
{
    size_t w = 0;
    for (size_t i = 0; i < SOLVER_ROWS; i++) {
        const char *n = solver_table[i].names[0];
        int k = snprintf(buf && w < size ? buf + w : NULL, buf && w < size ? size - w : 0, "%s%s",
                         i ? ", " : "", n);
        w += k > 0 ? (size_t)k : 0;
    }
    return w;
}

void cbm_mech_ellipse_moments(double a, double b, double *i_l, double *i_u, double *j)
{
    double a2 = a * a, b2 = b * b;
    if (i_l)
        *i_l = CBM_PI * a2 * a * b / 4.0;
    if (i_u)
        *i_u = CBM_PI * a * b2 * b / 4.0;
    if (j)
        *j = (a2 + b2) > 0.0 ? CBM_PI * a2 * a * b2 * b / (a2 + b2) : 0.0;
}

cbm_quat cbm_mech_clamp_orientation(double elevation)
{
    /* identity maps (x, y, z) to (H, L, U); we want H = (c, s, 0), L = (0, 0, -1),
     * U = (-s, c, 0): a rotation by +pi/2 about x (takes y to z and z to -y) ... composed:
     * first rotate about x by -pi/2 (y -> -z, z -> y), then about z by the elevation. */
    cbm_quat rx = q_axis_angle(v3(1, 0, 0), -0.5 * CBM_PI);
    cbm_quat rz = q_axis_angle(v3(0, 0, 1), elevation);
    return q_normalize(q_mul(rz, rx));
}

cbm_ring cbm_ring_default(void)
{
    cbm_ring r;
    memset(&r, 0, sizeof r);
    r.youngs_modulus = 10e9;
    r.shear_modulus = 10e9 / 16.0;
    r.density = 600.0;
    r.a = r.b = 0.01;
    return r;
}

cbm_segment_def cbm_segment_def_default(void)
{
    cbm_segment_def d;
    memset(&d, 0, sizeof d);
    d.parent = -1;
    d.length = 0.1;
    d.core = cbm_ring_default();
    d.order = -1;
    return d;
}

cbm_plant_def cbm_plant_def_default(void)
{
    cbm_plant_def d;
    memset(&d, 0, sizeof d);
    d.gravity = v3(0.0, -9.81, 0.0);
    d.base_orientation = q_identity();
    d.discretization = CBM_MECH_STAGGERED;
    return d;
}

/* ---- storage ---- */

/* Every per-segment array, with its element size, for growth and removal. */
// clang-format off
#define PLANT_ARRAYS(X)                                                                            \
    X(parent) X(order) X(cont) X(nchild) X(fchild) X(len) X(branch) X(ring_first) X(ring_count)  \
    X(ring_cap) X(outer) X(rig) X(rigr) X(rest) X(mpl) X(area) X(ea) X(omega) X(pmass) X(tipf) X(tipm) X(q) X(pos) X(force)          \
    X(moment) X(pmass0)                                                                            \
    X(cmass) X(crad)
// clang-format on

static cbm_status plant_reserve(cbm_plant *p, size_t need)
{
    if (need <= p->cap)
        return CBM_OK;
    size_t nc = p->cap ? p->cap : 16;
    while (nc < need)
        nc += nc / 2 + 16;
    cbm_context *ctx = p->ctx;
    /* table of every per-segment array; on failure the arrays already grown are shrunk back so
     * the byte accounting stays exact */
    void **ptr[32];
    size_t esz[32];
    int k = 0;
#define ENTRY(f)                                                                                   \
    ptr[k] = (void **)&p->f;                                                                       \
    esz[k] = sizeof *p->f;                                                                         \
    k++;
    PLANT_ARRAYS(ENTRY)
#undef ENTRY
    ptr[k] = (void **)&p->angles;
    esz[k] = 3 * sizeof(double);
    k++;
    for (int j = 0; j < k; j++) {
        void *np = cbm__realloc(ctx, *ptr[j], p->cap * esz[j], nc * esz[j]);
        if (!np) {
            for (int r = 0; r < j; r++) {
                void *sp = cbm__realloc(ctx, *ptr[r], nc * esz[r], p->cap * esz[r]);
                if (sp || p->cap == 0)
                    *ptr[r] = sp;
            }
            return CBM_E_NOMEM;
        }
        *ptr[j] = np;
    }
    p->cap = nc;
    return CBM_OK;
}

cbm_status cbm_plant_create(cbm_context *ctx, const cbm_plant_def *def, cbm_plant **out)
{
    if (!ctx || !out)
        return CBM_E_INVALID;
    *out = NULL;
    cbm_plant_def d = def ? *def : cbm_plant_def_default();
    if (!v3_isfinite(d.gravity) || !v3_isfinite(d.base_position))
        return cbm__fail(ctx, CBM_E_INVALID, "plant: gravity and base position must be finite");
    cbm_plant *p = cbm__calloc(ctx, 1, sizeof *p);
    if (!p)
        return CBM_E_NOMEM;
    p->ctx = ctx;
    p->gravity = d.gravity;
    p->base_pos = d.base_position;
    double qn =
        d.base_orientation.w * d.base_orientation.w + d.base_orientation.x * d.base_orientation.x +
        d.base_orientation.y * d.base_orientation.y + d.base_orientation.z * d.base_orientation.z;
    p->base_q = (qn > 0.0 && isfinite(qn)) ? q_normalize(d.base_orientation) : q_identity();
    p->disc = d.discretization == CBM_MECH_CHAIN ? CBM_MECH_CHAIN : CBM_MECH_STAGGERED;
    p->load_scale = 1.0;
    p->mass_path = 1.0;
    if (d.capacity) {
        size_t lim = cbm_context_limits(ctx)->max_segments;
        size_t c = d.capacity < lim ? d.capacity : lim;
        if (plant_reserve(p, c) != CBM_OK) {
            cbm_plant_destroy(p);
            return CBM_E_NOMEM;
        }
    }
    *out = p;
    return CBM_OK;
}

void cbm_plant_destroy(cbm_plant *p)
{
    if (!p)
        return;
    cbm_context *ctx = p->ctx;
#define FREE(f) cbm__free(ctx, p->f, p->cap * sizeof *p->f);
    PLANT_ARRAYS(FREE)
#undef FREE
    cbm__free(ctx, p->angles, p->cap * 3 * sizeof(double));
    CBM_ARRAY_FREE(ctx, p->rings);
    cbm__mech_order_free(p);
    cbm__mech_work_free(p);
    cbm__mech_pairs_free(p);
    cbm__fem_free(p);
    cbm__free(ctx, p, sizeof *p);
}

/* ---- sections ---- */

static cbm_status check_ring(cbm_plant *p, const cbm_ring *r, const cbm_ring *inner,
                             const char *what, size_t seg)
{
    const char *bad = NULL;
    if (!(isfinite(r->youngs_modulus) && r->youngs_modulus > 0.0))
        bad = "Young's modulus must be positive";
    else if (!(isfinite(r->shear_modulus) && r->shear_modulus > 0.0))
        bad = "shear modulus must be positive";
    else if (!(isfinite(r->density) && r->density >= 0.0))
        bad = "density must be >= 0";
    else if (!(isfinite(r->b) && r->b > 0.0 && isfinite(r->a) && r->a >= r->b))
        bad = "semi-axes must satisfy a >= b > 0";
    else if (!v3_isfinite(r->rest_rate))
        bad = "rest rotation rate must be finite";
    else if (!(isfinite(r->modulus_of_rupture) && r->modulus_of_rupture >= 0.0))
        bad = "modulus of rupture must be >= 0";
    else if (!isfinite(r->age))
        bad = "age must be finite";
    else if (!(isfinite(r->reaction) && r->reaction >= 0.0 && r->reaction <= 1.0))
        bad = "reaction-wood fraction must be in [0, 1]";
    else if (inner && (r->a < inner->a || r->b < inner->b))
        bad = "a ring must enclose the ring inside it";
    if (bad)
        return cbm__fail(p->ctx, CBM_E_INVALID, "segment %zu: %s: %s", seg, what, bad);
    return CBM_OK;
}

/* Solid-ellipse values of a ring's outer boundary: (I_L, I_U, J, area). */
static void ellipse_values(const cbm_ring *r, double v[4])
{
    cbm_mech_ellipse_moments(r->a, r->b, &v[0], &v[1], &v[2]);
    v[3] = CBM_PI * r->a * r->b;
}

/* Adds ring r, whose inner boundary has the solid-ellipse values in[4] (zeros for the core), to
 * the running sums of segment i; out[4] receives r's own outer values. The full recompute and
 * the incremental update of cbm_plant_add_ring both go through here, in the same order of
 * operations, so the two agree to the last bit. */
static void section_add(cbm_plant *p, size_t i, const double in[4], const cbm_ring *r,
                        double out[4])
{
    ellipse_values(r, out);
    cbm_vec3 ck = v3(r->shear_modulus * (out[2] - in[2]), r->youngs_modulus * (out[0] - in[0]),
                     r->youngs_modulus * (out[1] - in[1]));
    p->rig[i] = v3_add(p->rig[i], ck);
    p->rigr[i] = v3_add(p->rigr[i], v3_mul(ck, r->rest_rate));
    p->mpl[i] += r->density * (out[3] - in[3]);
    p->ea[i] += r->youngs_modulus * (out[3] - in[3]);
    p->area[i] = out[3];
}

/* The rigidity-weighted rest rate from the sums, and the outer ring's copy. */
static void section_rest(cbm_plant *p, size_t i)
{
    const cbm_ring *o = p->rings.data + p->ring_first[i] + p->ring_count[i] - 1;
    p->outer[i] = (cbm__outer){o->a, o->b, o->modulus_of_rupture};
    cbm_vec3 c = p->rig[i], cr = p->rigr[i];
    p->rest[i] =
        v3(c.x > 0 ? cr.x / c.x : 0.0, c.y > 0 ? cr.y / c.y : 0.0, c.z > 0 ? cr.z / c.z : 0.0);
}

/* Full recompute of segment i's aggregates over all of its rings (after a ring was replaced or
 * the wood aged). */
static void update_section(cbm_plant *p, size_t i)
{
    const cbm_ring *r = p->rings.data + p->ring_first[i];
    size_t nr = p->ring_count[i];
    double v[2][4] = {{0.0, 0.0, 0.0, 0.0}, {0.0, 0.0, 0.0, 0.0}};
    p->rig[i] = p->rigr[i] = v3(0, 0, 0);
    p->mpl[i] = 0.0;
    p->ea[i] = 0.0;
    p->area[i] = 0.0;
    for (size_t k = 0; k < nr; k++)
        section_add(p, i, v[k & 1], &r[k], v[(k + 1) & 1]);
    section_rest(p, i);
}

/* Incremental update after ring k = ring_count - 1 was appended: O(1). */
static void section_append(cbm_plant *p, size_t i)
{
    const cbm_ring *r = p->rings.data + p->ring_first[i] + p->ring_count[i] - 1;
    double in[4], out[4];
    ellipse_values(r - 1, in);
    section_add(p, i, in, r, out);
    section_rest(p, i);
}

static cbm_quat branch_quat(double div, double dev, double roll)
{
    cbm_quat a = q_axis_angle(v3(1, 0, 0), div);
    cbm_quat b = q_axis_angle(v3(0, 0, 1), dev);
    cbm_quat c = q_axis_angle(v3(1, 0, 0), roll);
    return q_normalize(q_mul(q_mul(a, b), c));
}

static cbm_status check_seg(const cbm_plant *p, size_t seg)
{
    if (seg >= p->n)
        return cbm__fail(p->ctx, CBM_E_INVALID, "segment %zu does not exist (plant has %zu)", seg,
                         p->n);
    return CBM_OK;
}

/* Rebuilds the pool in segment order into a fresh array; every run keeps its capacity. */
static cbm_status rebuild_rings(cbm_plant *p)
{
    cbm_context *ctx = p->ctx;
    size_t cap = p->ring_held ? p->ring_held : 1;
    cbm_ring *nd = cbm__alloc(ctx, cap * sizeof *nd);
    if (!nd)
        return CBM_E_NOMEM;
    size_t w = 0;
    for (size_t i = 0; i < p->n; i++) {
        memcpy(nd + w, p->rings.data + p->ring_first[i], p->ring_count[i] * sizeof *nd);
        p->ring_first[i] = w;
        w += p->ring_cap[i];
    }
    CBM_ARRAY_FREE(ctx, p->rings);
    p->rings.data = nd;
    p->rings.len = w;
    p->rings.cap = cap;
    memset(p->ring_free, 0, sizeof p->ring_free);
    return CBM_OK;
}

/* Room for `need` slots in the pool, growing it by half (not doubling: the pool is the largest
 * array of a grown tree). */
static cbm_status pool_reserve(cbm_plant *p, size_t need)
{
    size_t cap = p->rings.cap;
    if (need <= cap)
        return CBM_OK;
    size_t nc = cap + cap / 2 + 64;
    if (nc < need)
        nc = need + need / 4;
    if (nc > SIZE_MAX / sizeof(cbm_ring))
        return CBM_E_NOMEM;
    cbm_ring *nd =
        cbm__realloc(p->ctx, p->rings.data, cap * sizeof(cbm_ring), nc * sizeof(cbm_ring));
    if (!nd)
        return CBM_E_NOMEM;
    p->rings.data = nd;
    p->rings.cap = nc;
    return CBM_OK;
}

/* Capacity class of a run: capacities are 1 or a power of two >= 4. */
static int ring_class(size_t cap)
{
    int c = 0;
    while (cap > 1) {
        cap >>= 1;
        c++;
    }
    return c;
}

/* The run [start, start + cap) becomes a hole, reusable by a run of the same capacity. */
static void push_hole(cbm_plant *p, size_t start, size_t cap)
{
    int c = ring_class(cap);
    size_t next = p->ring_free[c];
    memcpy((void *)&p->rings.data[start], &next, sizeof next);
    p->ring_free[c] = start + 1;
}

/* A hole of capacity cap, or SIZE_MAX if there is none. */
static size_t pop_hole(cbm_plant *p, size_t cap)
{
    int c = ring_class(cap);
    size_t head = p->ring_free[c];
    if (head == 0)
        return SIZE_MAX;
    size_t next;
    memcpy(&next, (const void *)&p->rings.data[head - 1], sizeof next);
    p->ring_free[c] = next;
    return head - 1;
}

static void maybe_compact(cbm_plant *p)
{
    if (p->rings.len > 64 && 2 * p->ring_held < p->rings.len) {
        (void)rebuild_rings(p); /* on NOMEM the holes simply stay */
    }
}

/* Makes room for one more ring in segment seg's run: a full run at the end of the pool grows in
 * place; any other full run moves, with twice its capacity, into a hole of that capacity or to
 * the end of the pool, and its old slots become a hole. Each ring is thus copied O(1) times on
 * average, and holes are reused before the pool grows. */
static cbm_status ring_room(cbm_plant *p, size_t seg)
{
    size_t f = p->ring_first[seg], c = p->ring_count[seg], cap = p->ring_cap[seg];
    if (c < cap)
        return CBM_OK;
    size_t nc = cap < 2 ? 4 : 2 * cap;
    if (f + cap == p->rings.len) {
        if (pool_reserve(p, f + nc) != CBM_OK)
            return CBM_E_NOMEM;
        p->rings.len = f + nc;
    } else {
        size_t start = pop_hole(p, nc);
        if (start == SIZE_MAX) {
            if (pool_reserve(p, p->rings.len + nc) != CBM_OK)
                return CBM_E_NOMEM;
            start = p->rings.len;
            p->rings.len += nc;
        }
        memcpy(p->rings.data + start, p->rings.data + f, c * sizeof(cbm_ring));
        push_hole(p, f, cap);
        p->ring_first[seg] = start;
    }
    p->ring_cap[seg] = nc;
    p->ring_held += nc - cap;
    return CBM_OK;
}

/* ---- building ---- */

/* Links segment i (parent already linked) to its parent: it continues the parent's axis if it is
 * a root, or the parent has no continuation yet and i is not declared lateral (cont bit 1). */
static void link_child(cbm_plant *p, size_t i)
{
    int64_t pa = p->parent[i];
    bool lat = (p->cont[i] & 2) != 0;
    p->cont[i] = (uint8_t)((lat ? 2 : 0) | ((pa < 0 || (!lat && p->fchild[pa] < 0)) ? 1 : 0));
    if (pa >= 0) {
        if (p->cont[i] & 1)
            p->fchild[pa] = (int64_t)i;
        p->nchild[pa]++;
    }
}

/* v is +0.0 in every component (not -0.0, whose sign a sum may keep) */
static bool v3_plus_zero(cbm_vec3 v)
{
    return v.x == 0.0 && !signbit(v.x) && v.y == 0.0 && !signbit(v.y) && v.z == 0.0 &&
           !signbit(v.z);
}

/* p->tip_loads after a tip force f and moment m are written: set for anything but +0.0, never
 * cleared (solve_common.c, prepare_range) */
static void note_tip_loads(cbm_plant *p, cbm_vec3 f, cbm_vec3 m)
{
    p->tip_loads = p->tip_loads || !v3_plus_zero(f) || !v3_plus_zero(m);
}

cbm_status cbm_plant_add_segment(cbm_plant *p, const cbm_segment_def *def, size_t *index)
{
    if (!p || !def)
        return CBM_E_INVALID;
    size_t i = p->n;
    if (def->parent < -1 || (def->parent >= 0 && (size_t)def->parent >= p->n))
        return cbm__fail(p->ctx, CBM_E_INVALID,
                         "segment %zu: parent %lld is not an existing segment", i,
                         (long long)def->parent);
    if (!(isfinite(def->length) && def->length > 0.0))
        return cbm__fail(p->ctx, CBM_E_INVALID, "segment %zu: length must be positive", i);
    if (!isfinite(def->divergence) || !isfinite(def->deviation) || !isfinite(def->roll))
        return cbm__fail(p->ctx, CBM_E_INVALID, "segment %zu: branching angles must be finite", i);
    if (!(isfinite(def->point_mass) && def->point_mass >= 0.0) || !v3_isfinite(def->tip_force) ||
        !v3_isfinite(def->tip_moment) || !v3_isfinite(def->omega))
        return cbm__fail(p->ctx, CBM_E_INVALID,
                         "segment %zu: loads and rotation rate must be finite (point mass >= 0)",
                         i);
    if (!(isfinite(def->contact_radius) && def->contact_radius >= 0.0))
        return cbm__fail(p->ctx, CBM_E_INVALID,
                         "segment %zu: contact radius must be finite and >= 0 (m)", i);
    CBM_TRY(check_ring(p, &def->core, NULL, "core ring", i));
    size_t lim = cbm_context_limits(p->ctx)->max_segments;
    if (lim && i + 1 > lim)
        return cbm__fail(p->ctx, CBM_E_LIMIT, "plant: more than %zu segments (limits.max_segments)",
                         lim);
    if (plant_reserve(p, i + 1) != CBM_OK)
        return CBM_E_NOMEM;
    if (pool_reserve(p, p->rings.len + 1) != CBM_OK)
        return CBM_E_NOMEM;
    p->rings.data[p->rings.len++] = def->core;
    p->ring_held++;
    p->ring_first[i] = p->rings.len - 1;
    p->ring_count[i] = 1;
    p->ring_cap[i] = 1;
    int64_t par = def->parent;
    p->parent[i] = par;
    p->work.tsplit = 0;      /* the threads' split is for the old topology */
    p->sorder.valid = false; /* and the solve's order */
    p->cont[i] = def->lateral && par >= 0 ? 2 : 0;
    p->nchild[i] = 0;
    p->fchild[i] = -1;
    link_child(p, i);
    p->order[i] =
        def->order >= 0 ? def->order : (par < 0 ? 0 : p->order[par] + ((p->cont[i] & 1) ? 0 : 1));
    p->len[i] = def->length;
    p->angles[3 * i] = def->divergence;
    p->angles[3 * i + 1] = def->deviation;
    p->angles[3 * i + 2] = def->roll;
    p->branch[i] = branch_quat(def->divergence, def->deviation, def->roll);
    p->omega[i] = def->omega;
    p->pmass[i] = def->point_mass;
    p->pmass0[i] = 0.0;
    p->crad[i] = def->contact_radius;
    p->tipf[i] = def->tip_force;
    p->tipm[i] = def->tip_moment;
    note_tip_loads(p, def->tip_force, def->tip_moment);
    p->q[i] = q_identity();
    p->pos[i] = p->base_pos;
    p->force[i] = p->moment[i] = v3(0, 0, 0);
    p->cmass[i] = 0.0;
    p->n = i + 1;
    update_section(p, i);
    if (index)
        *index = i;
    return CBM_OK;
}

cbm_status cbm_plant_add_ring(cbm_plant *p, size_t seg, const cbm_ring *ring)
{
    if (!p || !ring)
        return CBM_E_INVALID;
    CBM_TRY(check_seg(p, seg));
    size_t c = p->ring_count[seg];
    CBM_TRY(check_ring(p, ring, &p->rings.data[p->ring_first[seg] + c - 1], "new ring", seg));
    if (ring_room(p, seg) != CBM_OK)
        return CBM_E_NOMEM;
    p->rings.data[p->ring_first[seg] + c] = *ring;
    p->ring_count[seg] = c + 1;
    section_append(p, seg);
    maybe_compact(p);
    return CBM_OK;
}

cbm_status cbm_plant_set_ring(cbm_plant *p, size_t seg, size_t k, const cbm_ring *ring)
{
    if (!p || !ring)
        return CBM_E_INVALID;
    CBM_TRY(check_seg(p, seg));
    size_t f = p->ring_first[seg], c = p->ring_count[seg];
    if (k >= c)
        return cbm__fail(p->ctx, CBM_E_INVALID, "segment %zu: ring %zu does not exist (%zu rings)",
                         seg, k, c);
    CBM_TRY(check_ring(p, ring, k > 0 ? &p->rings.data[f + k - 1] : NULL, "ring", seg));
    if (k + 1 < c && (ring->a > p->rings.data[f + k + 1].a || ring->b > p->rings.data[f + k + 1].b))
        return cbm__fail(p->ctx, CBM_E_INVALID,
                         "segment %zu: ring %zu must stay inside the ring around it", seg, k);
    p->rings.data[f + k] = *ring;
    update_section(p, seg);
    return CBM_OK;
}

cbm_status cbm_plant_replace_rings(cbm_plant *p, size_t seg, const cbm_ring *ring)
{
    if (!p || !ring)
        return CBM_E_INVALID;
    CBM_TRY(check_seg(p, seg));
    CBM_TRY(check_ring(p, ring, NULL, "ring", seg));
    /* the run keeps its capacity: the slots stay the segment's for later rings */
    p->rings.data[p->ring_first[seg]] = *ring;
    p->ring_count[seg] = 1;
    update_section(p, seg);
    return CBM_OK;
}

cbm_status cbm_plant_get_ring(const cbm_plant *p, size_t seg, size_t k, cbm_ring *out)
{
    if (!p || !out)
        return CBM_E_INVALID;
    CBM_TRY(check_seg(p, seg));
    if (k >= p->ring_count[seg])
        return cbm__fail(p->ctx, CBM_E_INVALID, "segment %zu: ring %zu does not exist", seg, k);
    *out = p->rings.data[p->ring_first[seg] + k];
    return CBM_OK;
}

size_t cbm_plant_ring_count(const cbm_plant *p, size_t seg)
{
    return (p && seg < p->n) ? p->ring_count[seg] : 0;
}

cbm_status cbm_plant_set_length(cbm_plant *p, size_t seg, double length)
{
    if (!p)
        return CBM_E_INVALID;
    CBM_TRY(check_seg(p, seg));
    if (!(isfinite(length) && length > 0.0))
        return cbm__fail(p->ctx, CBM_E_INVALID, "segment %zu: length must be positive", seg);
    p->len[seg] = length;
    return CBM_OK;
}

cbm_status cbm_plant_set_load(cbm_plant *p, size_t seg, double point_mass, cbm_vec3 tip_force,
                              cbm_vec3 tip_moment)
{
    if (!p)
        return CBM_E_INVALID;
    CBM_TRY(check_seg(p, seg));
    if (!(isfinite(point_mass) && point_mass >= 0.0) || !v3_isfinite(tip_force) ||
        !v3_isfinite(tip_moment))
        return cbm__fail(p->ctx, CBM_E_INVALID,
                         "segment %zu: loads must be finite (point mass >= 0)", seg);
    p->pmass[seg] = point_mass;
    p->tipf[seg] = tip_force;
    p->tipm[seg] = tip_moment;
    note_tip_loads(p, tip_force, tip_moment);
    return CBM_OK;
}

cbm_status cbm_plant_set_omega(cbm_plant *p, size_t seg, cbm_vec3 omega)
{
    if (!p)
        return CBM_E_INVALID;
    CBM_TRY(check_seg(p, seg));
    if (!v3_isfinite(omega))
        return cbm__fail(p->ctx, CBM_E_INVALID, "segment %zu: rotation rate must be finite", seg);
    p->omega[seg] = omega;
    return CBM_OK;
}

cbm_status cbm_plant_set_branching(cbm_plant *p, size_t seg, double div, double dev, double roll)
{
    if (!p)
        return CBM_E_INVALID;
    CBM_TRY(check_seg(p, seg));
    if (!isfinite(div) || !isfinite(dev) || !isfinite(roll))
        return cbm__fail(p->ctx, CBM_E_INVALID, "segment %zu: branching angles must be finite",
                         seg);
    p->angles[3 * seg] = div;
    p->angles[3 * seg + 1] = dev;
    p->angles[3 * seg + 2] = roll;
    p->branch[seg] = branch_quat(div, dev, roll);
    return CBM_OK;
}

void cbm_plant_set_gravity(cbm_plant *p, cbm_vec3 g)
{
    if (p && v3_isfinite(g))
        p->gravity = g;
}

cbm_status cbm_plant_set_ground(cbm_plant *p, double y0, double k, double smoothing)
{
    if (!p)
        return CBM_E_INVALID;
    if (!isfinite(y0))
        return cbm__fail(p->ctx, CBM_E_INVALID, "ground: height y0 must be finite");
    if (!(isfinite(k) && k >= 0.0))
        return cbm__fail(p->ctx, CBM_E_INVALID, "ground: stiffness k must be finite and >= 0");
    if (!(isfinite(smoothing) && smoothing >= 0.0))
        return cbm__fail(p->ctx, CBM_E_INVALID, "ground: smoothing must be finite and >= 0 (m)");
    p->ground_s = smoothing;
    p->ground = k > 0.0;
    p->ground_y = y0;
    p->ground_k = k;
    return CBM_OK;
}

bool cbm_plant_ground(const cbm_plant *p, double *y0, double *k, double *smoothing)
{
    if (!p || !p->ground)
        return false;
    if (y0)
        *y0 = p->ground_y;
    if (k)
        *k = p->ground_k;
    if (smoothing)
        *smoothing = p->ground_s;
    return true;
}

double cbm_plant_contact_force(const cbm_plant *p, size_t seg)
{
    if (!p || seg >= p->n || !p->ground)
        return 0.0;
    return cbm__mech_contact(p, seg, q_rotate(p->q[seg], v3(1, 0, 0)), NULL);
}

void cbm_plant_set_base(cbm_plant *p, cbm_vec3 position, cbm_quat q)
{
    if (!p || !v3_isfinite(position))
        return;
    double qn = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
    if (!(qn > 0.0 && isfinite(qn)))
        return;
    p->base_pos = position;
    p->base_q = q_normalize(q);
}

void cbm_plant_set_discretization(cbm_plant *p, cbm_mech_discretization d)
{
    if (p)
        p->disc = d == CBM_MECH_CHAIN ? CBM_MECH_CHAIN : CBM_MECH_STAGGERED;
}

cbm_mech_discretization cbm_plant_discretization(const cbm_plant *p)
{
    return p->disc;
}

cbm_status cbm_plant_remove_subtree(cbm_plant *p, size_t seg, size_t *removed)
{
    if (!p)
        return CBM_E_INVALID;
    CBM_TRY(check_seg(p, seg));
    size_t n = p->n, m = n - seg;
    /* map[i - seg] = new index of old segment i, or -1 if removed */
    int64_t *map = cbm__alloc(p->ctx, m * sizeof *map);
    if (!map)
        return CBM_E_NOMEM;
    size_t w = seg, nrm = 0;
    for (size_t i = seg; i < n; i++) {
        int64_t pa = p->parent[i];
        bool rm = (i == seg) || (pa >= (int64_t)seg && map[pa - (int64_t)seg] < 0);
        if (rm) {
            map[i - seg] = -1;
            nrm++;
            p->ring_held -= p->ring_cap[i];
            push_hole(p, p->ring_first[i], p->ring_cap[i]);
            continue;
        }
        map[i - seg] = (int64_t)w;
        if (pa >= (int64_t)seg)
            pa = map[pa - (int64_t)seg];
#define MOVE(f) p->f[w] = p->f[i];
        PLANT_ARRAYS(MOVE)
#undef MOVE
        p->angles[3 * w] = p->angles[3 * i];
        p->angles[3 * w + 1] = p->angles[3 * i + 1];
        p->angles[3 * w + 2] = p->angles[3 * i + 2];
        p->parent[w] = pa;
        w++;
    }
    cbm__free(p->ctx, map, m * sizeof *map);
    p->n = w;
    p->work.tsplit = 0;      /* the threads' split is for the old topology */
    p->sorder.valid = false; /* and the solve's order */
    /* recompute child counts and continuation flags */
    for (size_t i = 0; i < w; i++) {
        p->nchild[i] = 0;
        p->fchild[i] = -1;
    }
    for (size_t i = 0; i < w; i++)
        link_child(p, i);
    maybe_compact(p);
    if (removed)
        *removed = nrm;
    return CBM_OK;
}

/* ---- queries ---- */

size_t cbm_plant_segment_count(const cbm_plant *p)
{
    return p ? p->n : 0;
}

cbm_vec3 cbm_plant_gravity(const cbm_plant *p)
{
    return p->gravity;
}

const int64_t *cbm_plant_parents(const cbm_plant *p)
{
    return p->parent;
}
const cbm_quat *cbm_plant_orientations(const cbm_plant *p)
{
    return p->q;
}
const cbm_vec3 *cbm_plant_positions(const cbm_plant *p)
{
    return p->pos;
}
const cbm_vec3 *cbm_plant_omegas(const cbm_plant *p)
{
    return p->omega;
}
const cbm_vec3 *cbm_plant_moments(const cbm_plant *p)
{
    return p->moment;
}

double cbm_plant_total_mass(const cbm_plant *p)
{
    double m = 0.0;
    for (size_t i = 0; i < p->n; i++)
        m += p->mpl[i] * p->len[i] + p->pmass[i];
    return m;
}

static cbm_frame quat_frame(cbm_quat q)
{
    cbm_frame f = {q_rotate(q, v3(1, 0, 0)), q_rotate(q, v3(0, 1, 0)), q_rotate(q, v3(0, 0, 1))};
    return f;
}

/* Moment at the distal node of segment i carried by its distal half (world): the continuation
 * child's joint moment, or the tip moment at a free end. */
static cbm_vec3 distal_moment(const cbm_plant *p, size_t i)
{
    int64_t c = p->fchild[i];
    if (c >= 0)
        return p->moment[c]; /* the continuation joint's moment, about this node */
    return v3_scale(p->tipm[i], p->load_scale);
}

cbm_vec3 cbm__plant_segment_rate(const cbm_plant *p, size_t i)
{
    if (p->disc == CBM_MECH_CHAIN)
        return p->omega[i];
    cbm_frame f = quat_frame(p->q[i]);
    cbm_vec3 m = v3_scale(v3_add(p->moment[i], distal_moment(p, i)), 0.5);
    cbm_vec3 ml = frame_to_local(f, m), c = p->rig[i], r = p->rest[i];
    return v3(r.x + ml.x / c.x, r.y + ml.y / c.y, r.z + ml.z / c.z);
}

cbm_status cbm_plant_segment(const cbm_plant *p, size_t i, cbm_segment_state *o)
{
    if (!p || !o)
        return CBM_E_INVALID;
    CBM_TRY(check_seg(p, i));
    memset(o, 0, sizeof *o);
    const cbm_ring *r = p->rings.data + p->ring_first[i];
    size_t nr = p->ring_count[i];
    o->parent = p->parent[i];
    o->order = p->order[i];
    o->continuation = (p->cont[i] & 1) != 0;
    o->child_count = p->nchild[i];
    o->length = p->len[i];
    o->a = r[nr - 1].a;
    o->b = r[nr - 1].b;
    o->ring_count = nr;
    o->area = p->area[i];
    o->mass_per_length = p->mpl[i];
    o->rigidity = p->rig[i];
    o->rest_rate = p->rest[i];
    o->omega = p->omega[i];
    o->point_mass = p->pmass[i];
    o->contact_radius = p->crad[i];
    o->tip_force = p->tipf[i];
    o->tip_moment = p->tipm[i];
    o->orientation = p->q[i];
    o->frame = quat_frame(p->q[i]);
    o->proximal = p->pos[i];
    o->distal = v3_madd(p->pos[i], o->frame.h, p->len[i]);
    o->carried_mass = p->cmass[i];
    o->force = p->force[i];
    o->moment = p->moment[i];
    o->moment_local = frame_to_local(o->frame, p->moment[i]);
    double il, iu;
    cbm_mech_ellipse_moments(o->a, o->b, &il, &iu, NULL);
    double sl = o->moment_local.y * o->a / il, su = o->moment_local.z * o->b / iu;
    o->stress = sqrt(sl * sl + su * su);
    double mor = r[nr - 1].modulus_of_rupture;
    o->stress_ratio = mor > 0.0 ? o->stress / mor : NAN;
    double age = 0.0, rw = 0.0, a0 = 0.0;
    for (size_t k = 0; k < nr; k++) {
        if (r[k].age > age)
            age = r[k].age;
        double ar = CBM_PI * r[k].a * r[k].b;
        rw += r[k].reaction * (ar - a0);
        a0 = ar;
    }
    o->age = age;
    o->rate = cbm__plant_segment_rate(p, i);
    o->reaction = a0 > 0.0 ? rw / a0 : 0.0;
    return CBM_OK;
}

cbm_status cbm_plant_distal_frame(const cbm_plant *p, size_t i, cbm_quat *out)
{
    if (!p || !out)
        return CBM_E_INVALID;
    CBM_TRY(check_seg(p, i));
    cbm_quat q = p->q[i];
    if (p->disc == CBM_MECH_STAGGERED) {
        /* the distal half of the segment bends with the segment's own rest rate plus the
         * compliance times the moment at the distal node (the continuation child's moment,
         * or the tip moment at a free end) */
        cbm_frame f = quat_frame(q);
        cbm_vec3 md = distal_moment(p, i);
        cbm_vec3 ml = frame_to_local(f, md);
        cbm_vec3 c = p->rig[i];
        cbm_vec3 w =
            v3(p->rest[i].x + ml.x / c.x, p->rest[i].y + ml.y / c.y, p->rest[i].z + ml.z / c.z);
        q = q_normalize(q_mul(q, q_from_rotvec(v3_scale(w, 0.5 * p->len[i]))));
    }
    *out = q;
    return CBM_OK;
}
