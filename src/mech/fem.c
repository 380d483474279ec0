/* The incremental finite-element method (Guertler 2018 sec. 2.2, after Fourcaud & Lac 2003) as a
 * solver of the plant: one 3-D Euler-Bernoulli two-node beam (12 DOF) per segment, from the
 * distal node of its parent (the clamp for a root) to its own distal node; the section is the
 * segment's stack of rings (each ring's E, G or G = shear_ratio E, density, semi-axes).
 *
 * A step solves K dq = dF once: K the linear stiffness of every ring in the current orientation
 * (eqs. 2.51, 2.71-2.75, 2.89), dF the load increment (the consistent weight of new wood 2.76,
 * point loads, the maturation strain of new wood 2.78-2.82). Nothing is re-applied: the stress
 * of earlier steps stays in the path, which is how a ring laid on a bent branch memorises its
 * shape (Jirasek eq. 24 in the linear limit, docs/methods.md).
 *
 * Nodes are the segments' distal nodes (6 DOF each, world components); the clamp's DOF are
 * removed. The stiffness couples a node only to its parent's node, so eliminating the nodes from
 * the highest index down (children before parents: topological order) creates no fill. The Schur
 * block a subtree would add to its parent's pivot is the stiffness of a part free at its far end,
 * exactly zero, so every pivot is its element's k22 and only the loads are condensed (the wrench
 * carried to the parent). One step is O(n) time and memory (6x6 Cholesky per node), whatever the
 * branching; no library needed (docs/methods.md says why).
 *
 * Geometry: only orientations are state (as in the thesis, which keeps only angles). Each
 * segment turns by the rotation of its chord, H x (dx_distal - dx_proximal) / L, plus the mean
 * twist of its two nodes about H; positions are rebuilt from the frames, so the nodes move by the
 * FE translations to first order. Omega is then recovered from the frames (q = q_parent B
 * exp(d Omega)) and the plant evaluated. */
#include "mech/fem_internal.h"

#include "core/vecmath.h"

#include <math.h>
#include <string.h>

cbm_fem_def cbm_fem_def_default(void)
{
    cbm_fem_def d;
    memset(&d, 0, sizeof d);
    d.increments = 20;
    d.axial = CBM_FEM_AXIAL_FORMULA;
    return d;
}

cbm_fem_growth cbm_fem_growth_default(void)
{
    cbm_fem_growth g;
    memset(&g, 0, sizeof g);
    g.wood = cbm_ring_default();
    g.direction = v3(0, 1, 0);
    return g;
}

static cbm_status check_def(cbm_context *ctx, const cbm_fem_def *d)
{
    if (d->increments < 1 || d->increments > 10000000)
        return cbm__fail(ctx, CBM_E_INVALID, "fem: increments must be in 1..1e7");
    if (!(isfinite(d->shear_ratio) && d->shear_ratio >= 0.0))
        return cbm__fail(ctx, CBM_E_INVALID, "fem: shear_ratio must be >= 0 (0 = the rings' G)");
    if (!(d->sigma >= 0.0 && d->sigma <= 1.0))
        return cbm__fail(ctx, CBM_E_INVALID, "fem: sigma must be in [0, 1]");
    if (!isfinite(d->phi) || !isfinite(d->strain_min) || !isfinite(d->strain_max))
        return cbm__fail(ctx, CBM_E_INVALID, "fem: phi, strain_min and strain_max must be finite");
    if (d->axial != CBM_FEM_AXIAL_FORMULA && d->axial != CBM_FEM_AXIAL_LISTING)
        return cbm__fail(ctx, CBM_E_INVALID, "fem: unknown axial variant");
    return CBM_OK;
}

/* ---- workspace: one block per call ---- */

typedef struct fem_ws {
    size_t n;
    cbm_quat *q;  /* frames of the FE geometry */
    double *sec;  /* 4 per segment: EA, GJ, EI_L, EI_U */
    double *dm;   /* 36 per node: pivot block, then its Cholesky factor */
    double *ym;   /* 36 per node: D^-1 k21 */
    double *f;    /* 6 per node: load, then D^-1 (load) */
    double *x;    /* 6 per node: solution */
    double *lw;   /* kg/m of line load per segment */
    double *pm;   /* kg at the distal node */
    double *ma;   /* sum E dA of the straining rings (maturation) */
    double *mr;   /* sum E d(r^3) of the straining rings */
    cbm_vec3 *tf; /* tip force */
    cbm_vec3 *tm; /* tip moment */
    size_t bytes;
} fem_ws;

/* A grow-only buffer kept in the plant: *buf holds at least `need` bytes afterwards. */
static cbm_status keep_buffer(cbm_plant *p, void **buf, size_t *have, size_t need)
{
    if (*have >= need)
        return CBM_OK;
    size_t want = need + need / 2; /* room for the elements of the next growth steps */
    void *b = cbm__alloc(p->ctx, want);
    if (!b)
        return CBM_E_NOMEM;
    if (*buf)
        cbm__free(p->ctx, *buf, *have);
    *buf = b;
    *have = want;
    return CBM_OK;
}

void cbm__fem_free(cbm_plant *p)
{
    if (p->fem_ws)
        cbm__free(p->ctx, p->fem_ws, p->fem_ws_bytes);
    if (p->fem_snap)
        cbm__free(p->ctx, p->fem_snap, p->fem_snap_bytes);
    p->fem_ws = p->fem_snap = NULL;
    p->fem_ws_bytes = p->fem_snap_bytes = 0;
}

/* Carves the workspace for the plant's n segments from its kept buffer. Every array is written
 * before it is read (dm and f are cleared per step), so nothing is cleared here. */
static cbm_status ws_alloc(cbm_plant *p, fem_ws *w)
{
    size_t n = p->n;
    size_t nd = n * (4 + 4 + 36 + 36 + 6 + 6 + 4 + 6);
    memset(w, 0, sizeof *w);
    CBM_TRY(keep_buffer(p, &p->fem_ws, &p->fem_ws_bytes, nd * sizeof(double)));
    double *b = p->fem_ws;
    w->n = n;
    w->bytes = nd * sizeof(double);
    w->q = (cbm_quat *)b;
    b += 4 * n;
    w->sec = b;
    b += 4 * n;
    w->dm = b;
    b += 36 * n;
    w->ym = b;
    b += 36 * n;
    w->f = b;
    b += 6 * n;
    w->x = b;
    b += 6 * n;
    w->lw = b;
    w->pm = b + n;
    w->ma = b + 2 * n;
    w->mr = b + 3 * n;
    b += 4 * n;
    w->tf = (cbm_vec3 *)b;
    w->tm = (cbm_vec3 *)(b + 3 * n);
    return CBM_OK;
}

static void ws_free(cbm_plant *p, fem_ws *w)
{
    (void)p;
    memset(w, 0, sizeof *w);
}

/* ---- sections ---- */

/* Rigidities of the layered section (2.73-2.75 for ellipses): every ring's outer minus inner. */
static void sections(const cbm_plant *p, const cbm_fem_def *d, double *sec)
{
    if (d->shear_ratio == 0.0) {
        /* the plant's running sums: O(1) per segment however many rings it has */
        for (size_t i = 0; i < p->n; i++) {
            sec[4 * i] = p->ea[i];
            sec[4 * i + 1] = p->rig[i].x;
            sec[4 * i + 2] = p->rig[i].y;
            sec[4 * i + 3] = p->rig[i].z;
        }
        return;
    }
    /* G = shear_ratio E: GJ needs every ring (O(rings)) */
    for (size_t i = 0; i < p->n; i++) {
        const cbm_ring *r = p->rings.data + p->ring_first[i];
        double ea = 0, gj = 0, eil = 0, eiu = 0, a0 = 0, b0 = 0, il0 = 0, iu0 = 0, j0 = 0;
        for (size_t k = 0; k < p->ring_count[i]; k++) {
            double il, iu, j;
            cbm_mech_ellipse_moments(r[k].a, r[k].b, &il, &iu, &j);
            double e = r[k].youngs_modulus;
            double g = d->shear_ratio > 0.0 ? d->shear_ratio * e : r[k].shear_modulus;
            ea += e * CBM_PI * (r[k].a * r[k].b - a0 * b0);
            eil += e * (il - il0);
            eiu += e * (iu - iu0);
            gj += g * (j - j0);
            a0 = r[k].a;
            b0 = r[k].b;
            il0 = il;
            iu0 = iu;
            j0 = j;
        }
        sec[4 * i] = ea;
        sec[4 * i + 1] = gj;
        sec[4 * i + 2] = eil;
        sec[4 * i + 3] = eiu;
    }
}

/* Maturation coefficients of rings k0.. of segment i: each ring as the annulus of equal area
 * (r = sqrt(a b); exact for round sections). */
static void maturation_rings(const cbm_plant *p, size_t i, size_t k0, double *ma, double *mr)
{
    const cbm_ring *r = p->rings.data + p->ring_first[i];
    double sa = 0, sr = 0;
    for (size_t k = k0; k < p->ring_count[i]; k++) {
        double r1 = sqrt(r[k].a * r[k].b);
        double r0 = k > 0 ? sqrt(r[k - 1].a * r[k - 1].b) : 0.0;
        sa += r[k].youngs_modulus * CBM_PI * (r1 * r1 - r0 * r0);
        sr += r[k].youngs_modulus * (r1 * r1 * r1 - r0 * r0 * r0);
    }
    *ma = sa;
    *mr = sr;
}

/* ---- small dense algebra ---- */

/* Cholesky of a symmetric 6x6 (row-major, lower part used) in place; false if not positive. */
static bool chol6(double *a)
{
    for (int j = 0; j < 6; j++) {
        double s = a[6 * j + j];
        for (int k = 0; k < j; k++)
            s -= a[6 * j + k] * a[6 * j + k];
        if (!(s > 0.0))
            return false;
        double l = sqrt(s);
        a[6 * j + j] = l;
        for (int i = j + 1; i < 6; i++) {
            double t = a[6 * i + j];
            for (int k = 0; k < j; k++)
                t -= a[6 * i + k] * a[6 * j + k];
            a[6 * i + j] = t / l;
        }
    }
    return true;
}

/* Solves L L^T x = b in place (L from chol6). */
static void chol6_solve(const double *l, double *b)
{
    for (int i = 0; i < 6; i++) {
        double t = b[i];
        for (int k = 0; k < i; k++)
            t -= l[6 * i + k] * b[k];
        b[i] = t / l[6 * i + i];
    }
    for (int i = 6; i-- > 0;) {
        double t = b[i];
        for (int k = i + 1; k < 6; k++)
            t -= l[6 * k + i] * b[k];
        b[i] = t / l[6 * i + i];
    }
}

/* out = T a T^T with T = blockdiag(R, R), R = [h l u] (columns): local 6x6 to world. */
static void rot6(const double r[9], const double *a, double *out)
{
    double t[36];
    /* t = a T^T: t[i][j] = sum_k a[i][k] T[j][k] */
    for (int i = 0; i < 6; i++)
        for (int bj = 0; bj < 2; bj++)
            for (int j = 0; j < 3; j++) {
                double s = 0;
                for (int k = 0; k < 3; k++)
                    s += a[6 * i + 3 * bj + k] * r[3 * j + k];
                t[6 * i + 3 * bj + j] = s;
            }
    for (int bi = 0; bi < 2; bi++)
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 6; j++) {
                double s = 0;
                for (int k = 0; k < 3; k++)
                    s += r[3 * i + k] * t[6 * (3 * bi + k) + j];
                out[6 * (3 * bi + i) + j] = s;
            }
}

/* The element's three 6x6 blocks in world components (k11 proximal, k12 proximal rows x distal
 * columns, k22 distal): the standard symmetric 3-D frame element (Guertler 2.71 with the
 * symmetric entry his listing lacks, D2), local axes x = H, y = L, z = U, theta_y = -dw/dx. */
static void element_blocks(double len, const double *sec, const double r[9], double *k11,
                           double *k12, double *k22)
{
    double ea = sec[0] / len, gj = sec[1] / len;
    double eiy = sec[2], eiz = sec[3]; /* about L (w bending), about U (v bending) */
    double l2 = len * len, l3 = l2 * len;
    double a11[36] = {0}, a12[36] = {0}, a22[36] = {0};
#define A(m, i, j) m[6 * (i) + (j)]
    A(a11, 0, 0) = A(a22, 0, 0) = ea;
    A(a12, 0, 0) = -ea;
    A(a11, 3, 3) = A(a22, 3, 3) = gj;
    A(a12, 3, 3) = -gj;
    /* v (1) with theta_z (5) */
    A(a11, 1, 1) = A(a22, 1, 1) = 12 * eiz / l3;
    A(a12, 1, 1) = -12 * eiz / l3;
    A(a11, 1, 5) = A(a11, 5, 1) = 6 * eiz / l2;
    A(a22, 1, 5) = A(a22, 5, 1) = -6 * eiz / l2;
    A(a12, 1, 5) = 6 * eiz / l2;
    A(a12, 5, 1) = -6 * eiz / l2;
    A(a11, 5, 5) = A(a22, 5, 5) = 4 * eiz / len;
    A(a12, 5, 5) = 2 * eiz / len;
    /* w (2) with theta_y (4) */
    A(a11, 2, 2) = A(a22, 2, 2) = 12 * eiy / l3;
    A(a12, 2, 2) = -12 * eiy / l3;
    A(a11, 2, 4) = A(a11, 4, 2) = -6 * eiy / l2;
    A(a22, 2, 4) = A(a22, 4, 2) = 6 * eiy / l2;
    A(a12, 2, 4) = -6 * eiy / l2;
    A(a12, 4, 2) = 6 * eiy / l2;
    A(a11, 4, 4) = A(a22, 4, 4) = 4 * eiy / len;
    A(a12, 4, 4) = 2 * eiy / len;
#undef A
    rot6(r, a11, k11);
    rot6(r, a12, k12);
    rot6(r, a22, k22);
}

static void frame_of(cbm_quat q, cbm_vec3 *h, cbm_vec3 *l, cbm_vec3 *u)
{
    *h = q_rotate(q, v3(1, 0, 0));
    *l = q_rotate(q, v3(0, 1, 0));
    *u = q_rotate(q, v3(0, 0, 1));
}

static void add3(double *v, cbm_vec3 a)
{
    v[0] += a.x;
    v[1] += a.y;
    v[2] += a.z;
}

/* ---- one linear increment ---- */

/* Loads of element i (scaled): proximal and distal node force and moment, world. */
static void element_loads(const cbm_plant *p, const fem_ws *w, const cbm_fem_def *d, size_t i,
                          double s, cbm_vec3 h, cbm_vec3 uax, double fp[6], double fd[6])
{
    double len = p->len[i];
    cbm_vec3 g = p->gravity;
    memset(fp, 0, 6 * sizeof *fp);
    memset(fd, 0, 6 * sizeof *fd);
    if (w->lw[i] != 0.0) {
        /* consistent load of a uniform line load (2.76): half the weight at each node, end
         * moments +-q L^2 / 12 */
        cbm_vec3 qv = v3_scale(g, w->lw[i] * s);
        cbm_vec3 half = v3_scale(qv, 0.5 * len);
        cbm_vec3 m = v3_scale(v3_cross(h, qv), len * len / 12.0);
        add3(fp, half);
        add3(fp + 3, m);
        add3(fd, half);
        add3(fd + 3, v3_neg(m));
    }
    if (d->sigma > 0.0 && (w->ma[i] != 0.0 || w->mr[i] != 0.0)) {
        double a = d->strain_min, b = d->strain_max, sg = d->sigma;
        double nax = d->axial == CBM_FEM_AXIAL_LISTING ? w->ma[i] * sg * (a + 0.5 * (b - a))
                                                       : w->ma[i] * (a + 0.5 * sg * (b - a));
        /* the section's upper side: "up" (against gravity) across the segment */
        double g2 = v3_norm2(g);
        cbm_vec3 up = g2 > 0.0 ? v3_scale(g, -1.0 / sqrt(g2)) : v3(0, 1, 0);
        cbm_vec3 u = v3_sub(up, v3_scale(h, v3_dot(up, h)));
        if (v3_norm(u) < 1e-9)
            u = uax;
        u = v3_normalize(u);
        cbm_vec3 wv = v3_cross(h, u);
        double psi = b >= 0.0 ? d->phi + CBM_PI : d->phi; /* 2.63 */
        cbm_vec3 e = v3_add(v3_scale(u, cos(psi)), v3_scale(wv, sin(psi)));
        /* M = -int E alpha (H x s) dA over the ring = -(pi/6) E sigma (b - a) d(r^3) H x e
         * (2.81-2.82 in vector form) */
        cbm_vec3 m = v3_scale(v3_cross(h, e), -(CBM_PI / 6.0) * sg * (b - a) * w->mr[i] * s);
        add3(fp, v3_scale(h, -nax * s));
        add3(fp + 3, v3_neg(m));
        add3(fd, v3_scale(h, nax * s));
        add3(fd + 3, m);
    }
    add3(fd, v3_add(v3_scale(g, w->pm[i] * s), v3_scale(w->tf[i], s)));
    add3(fd + 3, v3_scale(w->tm[i], s));
}

static cbm_status fem_step(cbm_plant *p, fem_ws *w, const cbm_fem_def *d, double s, double *maxrot)
{
    size_t n = p->n;
    memset(w->f, 0, 6 * n * sizeof *w->f);
    for (size_t i = n; i-- > 0;) {
        cbm_vec3 h, l, u;
        frame_of(w->q[i], &h, &l, &u);
        double r[9] = {h.x, l.x, u.x, h.y, l.y, u.y, h.z, l.z, u.z};
        double k11[36], k12[36], k22[36], fp[6], fd[6]; /* k11 is not needed (see below) */
        element_blocks(p->len[i], w->sec + 4 * i, r, k11, k12, k22);
        element_loads(p, w, d, i, s, h, u, fp, fd);
        /* the pivot is k22 alone: what a child's subtree adds to it, k11 - k12 D^-1 k21, is the
         * stiffness of a part free at its far end, exactly zero (a clamped tree is statically
         * determinate). Forming it would only add round-off, which the chain transports with
         * growing lever arms until a pivot of a 10^5-element chain loses definiteness. */
        double *di = w->dm + 36 * i, *fi = w->f + 6 * i;
        memcpy(di, k22, sizeof k22);
        for (int k = 0; k < 6; k++)
            fi[k] += fd[k];
        if (!chol6(di))
            return cbm__fail(p->ctx, CBM_E_NONFINITE,
                             "fem: the stiffness of segment %zu is not positive definite "
                             "(zero or non-finite rigidity)",
                             i);
        chol6_solve(di, fi); /* y_i = D^-1 f_i */
        int64_t pa = p->parent[i];
        if (pa < 0)
            continue; /* the clamp takes the proximal half */
        double *yi = w->ym + 36 * i;
        /* Y = D^-1 k21, k21 = k12^T: column c of Y solves with row c of k12 */
        for (int c = 0; c < 6; c++) {
            double col[6];
            for (int k = 0; k < 6; k++)
                col[k] = k12[6 * c + k];
            chol6_solve(di, col);
            for (int k = 0; k < 6; k++)
                yi[6 * k + c] = col[k];
        }
        double *fpa = w->f + 6 * (size_t)pa;
        for (int a = 0; a < 6; a++) {
            double t = 0;
            for (int k = 0; k < 6; k++)
                t += k12[6 * a + k] * fi[k];
            fpa[a] += fp[a] - t;
        }
    }
    /* back substitution, parents first: x_i = y_i - Y_i x_parent */
    double mr = 0.0;
    for (size_t i = 0; i < n; i++) {
        double *xi = w->x + 6 * i;
        memcpy(xi, w->f + 6 * i, 6 * sizeof *xi);
        int64_t pa = p->parent[i];
        const double *xp = pa >= 0 ? w->x + 6 * (size_t)pa : NULL;
        if (xp) {
            const double *yi = w->ym + 36 * i;
            for (int a = 0; a < 6; a++)
                for (int k = 0; k < 6; k++)
                    xi[a] -= yi[6 * a + k] * xp[k];
        }
        /* the segment turns with its chord, and twists by its nodes' mean twist */
        cbm_vec3 h = q_h(w->q[i]);
        cbm_vec3 du = v3(xi[0], xi[1], xi[2]);
        cbm_vec3 th = v3(xi[3], xi[4], xi[5]);
        if (xp) {
            du = v3_sub(du, v3(xp[0], xp[1], xp[2]));
            th = v3_scale(v3_add(th, v3(xp[3], xp[4], xp[5])), 0.5);
        } else {
            th = v3_scale(th, 0.5);
        }
        cbm_vec3 rot =
            v3_add(v3_scale(v3_cross(h, du), 1.0 / p->len[i]), v3_scale(h, v3_dot(th, h)));
        if (!v3_isfinite(rot))
            return cbm__fail(p->ctx, CBM_E_NONFINITE, "fem: segment %zu: non-finite rotation", i);
        double a = v3_norm(rot);
        if (a > mr)
            mr = a;
        w->q[i] = q_normalize(q_mul(q_from_rotvec(rot), w->q[i]));
    }
    *maxrot = mr;
    return CBM_OK;
}

/* Rotation vector of a unit quaternion (|angle| <= pi). */
cbm_vec3 cbm__fem_q_log(cbm_quat q)
{
    if (q.w < 0.0) {
        q.w = -q.w;
        q.x = -q.x;
        q.y = -q.y;
        q.z = -q.z;
    }
    cbm_vec3 v = v3(q.x, q.y, q.z);
    double s = v3_norm(v);
    if (s < 1e-12)
        return v3_scale(v, 2.0 / q.w);
    return v3_scale(v, 2.0 * atan2(s, q.w) / s);
}

/* Omega from the FE frames (q = q_parent B exp(dual Omega)), then a full evaluation. */
static cbm_status store_frames(cbm_plant *p, const fem_ws *w, double *residual)
{
    const double *dual = p->work.dual;
    for (size_t i = 0; i < p->n; i++) {
        int64_t pa = p->parent[i];
        cbm_quat qa = pa < 0 ? p->base_q : w->q[pa];
        qa = q_mul(qa, p->branch[i]);
        p->omega[i] = v3_scale(cbm__fem_q_log(q_mul(q_conj(qa), w->q[i])), 1.0 / dual[i]);
    }
    return cbm_plant_evaluate(p, residual);
}

/* Frames of the current Omega into the workspace (prepare + forward sweep). */
static cbm_status current_frames(cbm_plant *p, fem_ws *w)
{
    CBM_TRY(cbm__mech_work_reserve(p, 0));
    p->load_scale = 1.0;
    cbm__mech_prepare(p);
    cbm__mech_forward(p);
    memcpy(w->q, p->q, p->n * sizeof *w->q);
    return CBM_OK;
}

/* ---- the solver: the full load in increments from the rest shape ---- */

cbm_status cbm__mech_solve_fem(cbm_plant *p, const cbm_fem_def *d, cbm_solve_stats *st)
{
    CBM_TRY(check_def(p->ctx, d));
    fem_ws w;
    CBM_TRY(ws_alloc(p, &w));
    cbm_status s = cbm__mech_work_reserve(p, 0);
    if (s == CBM_OK) {
        p->load_scale = 1.0;
        cbm__mech_prepare(p);
        for (size_t i = 0; i < p->n; i++)
            p->omega[i] = p->work.rj[i]; /* the rest shape carries no load */
        cbm__mech_forward(p);
        memcpy(w.q, p->q, p->n * sizeof *w.q);
        sections(p, d, w.sec);
        for (size_t i = 0; i < p->n; i++) {
            w.lw[i] = p->mpl[i];
            w.pm[i] = p->pmass[i];
            w.tf[i] = p->tipf[i];
            w.tm[i] = p->tipm[i];
            maturation_rings(p, i, 0, &w.ma[i], &w.mr[i]);
        }
        double sc = 1.0 / (double)d->increments, mr = 0.0;
        for (size_t k = 0; k < d->increments && s == CBM_OK; k++)
            s = fem_step(p, &w, d, sc, &mr);
        double res = NAN;
        if (s == CBM_OK)
            s = store_frames(p, &w, &res);
        st->passes = d->increments;
        st->residual = res;
        st->continuation_steps = d->increments;
        st->stage = s == CBM_OK ? CBM_SOLVE_STAGE_FEM : CBM_SOLVE_STAGE_NONE;
        double mm = 0.0;
        for (size_t i = 0; i < p->n; i++)
            mm = fmax(mm, v3_norm(p->moment[i]));
        st->char_moment = mm > 0.0 ? mm : 1.0;
    }
    ws_free(p, &w);
    return s;
}

/* ---- growth ---- */

cbm_status cbm__fem_snap_take(cbm_plant *p, cbm__fem_snap *s)
{
    memset(s, 0, sizeof *s);
    size_t n = p->n;
    s->n = n;
    if (n == 0)
        return CBM_OK;
    size_t per = 2 * sizeof(double) + sizeof(size_t) + 2 * sizeof(cbm_vec3);
    CBM_TRY(keep_buffer(p, &p->fem_snap, &p->fem_snap_bytes, n * per));
    char *b = p->fem_snap; /* every part a multiple of 8 bytes: each stays aligned */
    s->tipf = (cbm_vec3 *)(void *)b;
    s->tipm = (cbm_vec3 *)(void *)(b + n * sizeof(cbm_vec3));
    s->mpl = (double *)(void *)(b + 2 * n * sizeof(cbm_vec3));
    s->pmass = (double *)(void *)(b + 2 * n * sizeof(cbm_vec3) + n * sizeof(double));
    s->rings = (size_t *)(void *)(b + 2 * n * sizeof(cbm_vec3) + 2 * n * sizeof(double));
    memcpy(s->mpl, p->mpl, n * sizeof *s->mpl);
    memcpy(s->pmass, p->pmass, n * sizeof *s->pmass);
    memcpy(s->rings, p->ring_count, n * sizeof *s->rings);
    memcpy(s->tipf, p->tipf, n * sizeof *s->tipf);
    memcpy(s->tipm, p->tipm, n * sizeof *s->tipm);
    return CBM_OK;
}

void cbm__fem_snap_free(cbm_plant *p, cbm__fem_snap *s)
{
    (void)p; /* the buffer stays with the plant for the next step */
    memset(s, 0, sizeof *s);
}

cbm_status cbm__fem_increment(cbm_plant *p, const cbm_fem_def *d, const cbm__fem_snap *sn,
                              cbm_fem_stats *stats)
{
    CBM_TRY(check_def(p->ctx, d));
    if (p->n == 0)
        return cbm__fail(p->ctx, CBM_E_INVALID, "fem: the plant has no segments");
    fem_ws w;
    CBM_TRY(ws_alloc(p, &w));
    cbm_status s = current_frames(p, &w);
    double mr = 0.0;
    if (s == CBM_OK) {
        sections(p, d, w.sec);
        for (size_t i = 0; i < p->n; i++) {
            bool old = i < sn->n;
            w.lw[i] = p->mpl[i] - (old ? sn->mpl[i] : 0.0);
            w.pm[i] = p->pmass[i] - (old ? sn->pmass[i] : 0.0);
            w.tf[i] = old ? v3_sub(p->tipf[i], sn->tipf[i]) : p->tipf[i];
            w.tm[i] = old ? v3_sub(p->tipm[i], sn->tipm[i]) : p->tipm[i];
            maturation_rings(p, i, old ? sn->rings[i] : 0, &w.ma[i], &w.mr[i]);
        }
        s = fem_step(p, &w, d, 1.0, &mr);
    }
    if (s == CBM_OK)
        s = store_frames(p, &w, NULL);
    if (stats) {
        stats->increments = 1;
        stats->elements = p->n;
        stats->max_rotation = mr;
    }
    ws_free(p, &w);
    return s;
}

/* Length over which the joint of a new continuation segment bends (solve_common.c, prepare). */
static double new_dual(const cbm_plant *p, size_t parent, double len)
{
    return p->disc == CBM_MECH_CHAIN ? len : 0.5 * (p->len[parent] + len);
}

cbm_status cbm_plant_fem_grow(cbm_plant *p, const cbm_fem_def *def, const cbm_fem_growth *g,
                              cbm_fem_stats *stats)
{
    if (stats)
        memset(stats, 0, sizeof *stats);
    if (!p || !g)
        return CBM_E_INVALID;
    cbm_fem_def d = def ? *def : cbm_fem_def_default();
    CBM_TRY(check_def(p->ctx, &d));
    if (!(isfinite(g->ring_thickness) && g->ring_thickness >= 0.0))
        return cbm__fail(p->ctx, CBM_E_INVALID, "fem growth: ring_thickness must be >= 0");
    if (!(isfinite(g->tip_length) && g->tip_length >= 0.0))
        return cbm__fail(p->ctx, CBM_E_INVALID, "fem growth: tip_length must be >= 0");
    if (g->tip_length > 0.0 && !(isfinite(g->tip_radius) && g->tip_radius > 0.0))
        return cbm__fail(p->ctx, CBM_E_INVALID, "fem growth: tip_radius must be positive");
    if (g->primary_tropism && !(v3_isfinite(g->direction) && v3_norm(g->direction) > 0.0))
        return cbm__fail(p->ctx, CBM_E_INVALID, "fem growth: direction must be a non-zero vector");
    if (p->n == 0)
        return cbm__fail(p->ctx, CBM_E_INVALID, "fem growth: the plant has no segments");
    size_t n0 = p->n;
    if (g->added_mass)
        for (size_t i = 0; i < n0; i++)
            if (!(isfinite(g->added_mass[i]) && p->pmass[i] + g->added_mass[i] >= 0.0))
                return cbm__fail(p->ctx, CBM_E_INVALID,
                                 "fem growth: added_mass[%zu] is not finite or makes the point "
                                 "mass negative",
                                 i);
    /* frames of the current shape (new tips continue them) */
    CBM_TRY(cbm__mech_work_reserve(p, 0));
    p->load_scale = 1.0;
    cbm__mech_prepare(p);
    cbm__mech_forward(p);
    cbm__fem_snap sn;
    CBM_TRY(cbm__fem_snap_take(p, &sn));
    cbm_status s = CBM_OK;
    size_t rings = 0, tips = 0;
    /* secondary growth: a ring on every segment, stress-free on the current shape */
    for (size_t i = 0; i < n0 && s == CBM_OK && g->ring_thickness > 0.0; i++) {
        const cbm_ring *o = p->rings.data + p->ring_first[i] + p->ring_count[i] - 1;
        cbm_ring r = g->wood;
        r.a = o->a + g->ring_thickness;
        r.b = o->b + g->ring_thickness;
        r.rest_rate = p->omega[i];
        r.age = 0.0;
        r.reaction = 0.0;
        s = cbm_plant_add_ring(p, i, &r);
        rings++;
    }
    for (size_t i = 0; i < n0 && s == CBM_OK && g->added_mass; i++)
        p->pmass[i] += g->added_mass[i];
    /* primary growth: a new element at every tip of the plant before the step */
    for (size_t i = 0; i < n0 && s == CBM_OK && g->tip_length > 0.0; i++) {
        if (p->nchild[i] != 0)
            continue;
        cbm_segment_def sd = cbm_segment_def_default();
        sd.parent = (int64_t)i;
        sd.length = g->tip_length;
        sd.core = g->wood;
        sd.core.a = sd.core.b = g->tip_radius;
        sd.core.rest_rate = v3(0, 0, 0);
        sd.core.age = 0.0;
        sd.core.reaction = 0.0;
        if (g->primary_tropism) {
            /* the joint turns the parent's heading onto the direction over its dual length */
            cbm_quat qa = p->q[i];
            cbm_vec3 h = q_h(qa), dir = v3_normalize(g->direction);
            cbm_vec3 ax = v3_cross(h, dir);
            double sn2 = v3_norm(ax), c = v3_dot(h, dir);
            cbm_vec3 rw = sn2 > 1e-15 ? v3_scale(ax, atan2(sn2, c) / sn2) : v3(0, 0, 0);
            if (sn2 <= 1e-15 && c < 0.0) /* straight back: turn about U */
                rw = v3_scale(q_rotate(qa, v3(0, 0, 1)), CBM_PI);
            cbm_vec3 rl = q_rotate(q_conj(qa), rw);
            sd.core.rest_rate = v3_scale(rl, 1.0 / new_dual(p, i, g->tip_length));
        }
        sd.omega = sd.core.rest_rate;
        s = cbm_plant_add_segment(p, &sd, NULL);
        tips++;
    }
    if (s == CBM_OK)
        s = cbm__fem_increment(p, &d, &sn, stats);
    cbm__fem_snap_free(p, &sn);
    if (stats) {
        stats->rings_added = rings;
        stats->tips_added = tips;
    }
    return s;
}
