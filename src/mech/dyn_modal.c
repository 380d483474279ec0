/* Modal reduction of the motion (CBM_MOTION_MODAL; docs/dynamics.md, "Modal reduction"): the
 * motion is sought in the span of the lowest K modes, q = sum_r eta_r phi_r with the
 * mass-normalised shapes of cbm_plant_modes (phi_r^T M phi_s = delta_rs, phi_r^T K phi_s =
 * w_r^2 delta_rs). Projected on them, M q'' + C q' + K q = f becomes K uncoupled oscillators
 *     eta_r'' + c_r eta_r' + w_r^2 eta_r = phi_r^T f,   c_r = alpha + beta w_r^2
 * (Rayleigh damping is diagonal in the modes), integrated by the same Newmark rule as the full
 * motion (motion.c): with all 3n modes the two agree to round-off, and without damping the
 * modal energy 1/2 |eta'|^2 + 1/2 sum w_r^2 eta_r^2 is conserved exactly. A step costs O(K),
 * independent of the plant's size, which is how large trees are animated in graphics and wind
 * engineering (Shinya and Fournier 1992, Stam 1997, Diener et al. 2009).
 *
 * The loads are projected once where they can be: a point force F at a node gives phi_r^T f =
 * F . u_r(node) (the node's displacement in mode r, O(depth) per mode); the base's acceleration
 * a gives sum_i a_i phi_r^T g_i with g_i the fictitious force of a unit acceleration along axis i
 * (three sweeps, once). The wind's drag 1/2 rho C_d A |w| w (w the air's velocity relative to the
 * moving segment, normal to it) depends on the full velocity field; it is linearised about the
 * still plant in the mean wind (quasi-steady: g(t, v) ~ s|s| g_mean + |s| (G v + G_b v_base)
 * with s(t) = U_ref(t) / U_ref the gust factor, exact in s because the drag is homogeneous of
 * degree 2 in the velocities and the gusts are uniform over the plant). Its projections phi^T
 * g_mean, phi^T G phi (the aerodynamic damping, which couples the modes) and phi^T G_b are found
 * once by central differences of the drag (2K + 7 drag evaluations); a gust field, whose factor
 * differs from grid point to grid point, is projected per grid point ("Gust field" below). The
 * truncated modes' quasi-static response can be added at output ("Static correction" below).
 * The error of the reduction (the truncated modes' response, and for wind the linearisation) is
 * measured against the full motion in tests/test_dyn_modal.c and stated in docs/dynamics.md. */
#include "core/vecmath.h"
#include "mech/dyn_internal.h"
#include "mech/mech_internal.h"

#include <math.h>
#include <string.h>

#define MODAL_PI 3.14159265358979323846

/* What a plain modal motion does without: the gust field's projections per grid point (below,
 * "Gust field") and the static correction's vectors ("Static correction"). */
struct cbm__modal_ext {
    /* the gust field's ng grid points; the pair (j, j + off[o]) of neighbours in one cell */
    size_t ng;
    int32_t off[5];
    bool slot_ok[5];       /* the offset is not an earlier one's (a grid one point wide) */
    double *pl;            /* ng x 5 x k: the pairs' shares of the projected mean load */
    double *caf;           /* ng x k x k: the grid points' shares of ca */
    double *cbf;           /* ng x k x 3: and of cb */
    double *sg;            /* ng: the gust factors s_j at t_f */
    double *ld, *cd, *cbd; /* k, k x k, k x 3: the load, damping and base terms at t_f */
    double t_f;            /* NAN: none */
    /* the static correction: the loads of the current time in full (forces of the last step,
     * fc; those added for the next, fp), the base's generalised forces per unit acceleration
     * (gbf, 3 x 3n), and the correction cq itself (stale with the rebuilt shape) */
    bool sc, fc_any, fp_any, gbf_valid, c_stale;
    double *fc, *fp, *gbf, *cq;
    cbm_motion *self; /* the motion, writable: the correction is a cache the const readers fill */
};

static void field_free(cbm_context *ctx, struct cbm__modal_ext *x, size_t k)
{
    size_t ng = x->ng, b = sizeof(double);
    cbm__free(ctx, x->pl, ng * 5 * k * b);
    cbm__free(ctx, x->caf, ng * k * k * b);
    cbm__free(ctx, x->cbf, ng * 3 * k * b);
    cbm__free(ctx, x->sg, ng * b);
    cbm__free(ctx, x->ld, k * b);
    cbm__free(ctx, x->cd, k * k * b);
    cbm__free(ctx, x->cbd, 3 * k * b);
    x->pl = x->caf = x->cbf = x->sg = x->ld = x->cd = x->cbd = NULL;
    x->ng = 0;
}

void cbm__modal_free(cbm_context *ctx, cbm__modal *md, size_t nq)
{
    if (!md)
        return;
    size_t k = md->k, b = k * sizeof(double);
    cbm__free(ctx, md->phi, k * nq * sizeof(double));
    cbm__free(ctx, md->w, b);
    cbm__free(ctx, md->fhz, b);
    cbm__free(ctx, md->eta, b);
    cbm__free(ctx, md->ed, b);
    cbm__free(ctx, md->edd, b);
    cbm__free(ctx, md->p, b);
    cbm__free(ctx, md->cr, b);
    cbm__free(ctx, md->gb, 3 * b);
    cbm__free(ctx, md->pw, b);
    cbm__free(ctx, md->ca, k * b);
    cbm__free(ctx, md->cb, 3 * b);
    cbm__free(ctx, md->a, k * b);
    cbm__free(ctx, md->r, b);
    cbm__free(ctx, md->qbuf, nq * sizeof(double));
    if (md->x) {
        field_free(ctx, md->x, k);
        cbm__free(ctx, md->x->fc, nq * sizeof(double));
        cbm__free(ctx, md->x->fp, nq * sizeof(double));
        cbm__free(ctx, md->x->gbf, 3 * nq * sizeof(double));
        cbm__free(ctx, md->x->cq, nq * sizeof(double));
        cbm__free(ctx, md->x, sizeof *md->x);
    }
    cbm__free(ctx, md, sizeof *md);
}

/* The lowest modes below cut_hz: asks for 8, 16, 32, ... until the last one is at or above the
 * cut or all 3n are there (each try a new Lanczos run). *count receives how many lie below the
 * cut (at least 1); freqs and shapes are allocated for *cap modes. */
static cbm_status modes_below(const cbm_plant *plant, size_t nq, double cut_hz, size_t *count,
                              size_t *cap, double **freqs, double **shapes)
{
    cbm_context *ctx = plant->ctx;
    size_t c = nq < 8 ? nq : 8;
    for (;;) {
        double *f = cbm__calloc(ctx, c, sizeof(double));
        double *s = cbm__calloc(ctx, c * nq, sizeof(double));
        if (!f || !s) {
            cbm__free(ctx, f, c * sizeof(double));
            cbm__free(ctx, s, c * nq * sizeof(double));
            return CBM_E_NOMEM;
        }
        cbm_status st = cbm_plant_modes(plant, c, f, s);
        if (st != CBM_OK || f[c - 1] >= cut_hz || c == nq) {
            if (st == CBM_OK) {
                size_t below = 0;
                while (below < c && f[below] < cut_hz)
                    below++;
                *count = below > 0 ? below : 1;
            }
            *cap = c;
            *freqs = f;
            *shapes = s;
            return st;
        }
        cbm__free(ctx, f, c * sizeof(double));
        cbm__free(ctx, s, c * nq * sizeof(double));
        c = 2 * c < nq ? 2 * c : nq;
    }
}

cbm_status cbm__modal_create(const cbm_plant *plant, cbm_motion *m, size_t count, double cut_hz,
                             double damping_ratio, bool static_correction)
{
    cbm_context *ctx = plant->ctx;
    size_t nq = m->nq;
    if (count == 0 && !(cut_hz > 0.0 && isfinite(cut_hz)))
        return cbm__fail(ctx, CBM_E_INVALID,
                         "motion: the modal method needs modes > 0 or mode_cut_hz > 0");
    if (count > nq)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "motion: modes = %zu is more than the plant's %zu degrees of freedom",
                         count, nq);
    double *f = NULL, *s = NULL;
    size_t cap = count;
    if (count > 0) {
        f = cbm__calloc(ctx, count, sizeof(double));
        s = cbm__calloc(ctx, count * nq, sizeof(double));
        cbm_status st = (f && s) ? cbm_plant_modes(plant, count, f, s) : CBM_E_NOMEM;
        if (st != CBM_OK) {
            cbm__free(ctx, f, count * sizeof(double));
            cbm__free(ctx, s, count * nq * sizeof(double));
            return st;
        }
    } else {
        cbm_status st = modes_below(plant, nq, cut_hz, &count, &cap, &f, &s);
        if (st != CBM_OK) {
            cbm__free(ctx, f, cap * sizeof(double));
            cbm__free(ctx, s, cap * nq * sizeof(double));
            return st;
        }
    }
    cbm__modal *md = cbm__calloc(ctx, 1, sizeof *md);
    if (!md) {
        cbm__free(ctx, f, cap * sizeof(double));
        cbm__free(ctx, s, cap * nq * sizeof(double));
        return CBM_E_NOMEM;
    }
    size_t k = count;
    md->k = k;
    md->phi = cbm__calloc(ctx, k * nq, sizeof(double));
    md->w = cbm__calloc(ctx, k, sizeof(double));
    md->fhz = cbm__calloc(ctx, k, sizeof(double));
    md->eta = cbm__calloc(ctx, k, sizeof(double));
    md->ed = cbm__calloc(ctx, k, sizeof(double));
    md->edd = cbm__calloc(ctx, k, sizeof(double));
    md->p = cbm__calloc(ctx, k, sizeof(double));
    md->cr = cbm__calloc(ctx, k, sizeof(double));
    md->gb = cbm__calloc(ctx, 3 * k, sizeof(double));
    md->pw = cbm__calloc(ctx, k, sizeof(double));
    md->ca = cbm__calloc(ctx, k * k, sizeof(double));
    md->cb = cbm__calloc(ctx, 3 * k, sizeof(double));
    md->a = cbm__calloc(ctx, k * k, sizeof(double));
    md->r = cbm__calloc(ctx, k, sizeof(double));
    md->qbuf = cbm__calloc(ctx, nq, sizeof(double));
    md->x = cbm__calloc(ctx, 1, sizeof *md->x);
    m->modal = md; /* freed with m from here on */
    bool ok = md->phi && md->w && md->fhz && md->eta && md->ed && md->edd && md->p && md->cr &&
              md->gb && md->pw && md->ca && md->cb && md->a && md->r && md->qbuf && md->x;
    if (ok) {
        memcpy(md->phi, s, k * nq * sizeof(double));
        memcpy(md->fhz, f, k * sizeof(double));
    }
    cbm__free(ctx, f, cap * sizeof(double));
    cbm__free(ctx, s, cap * nq * sizeof(double));
    if (!ok)
        return CBM_E_NOMEM;
    for (size_t r = 0; r < k; r++) {
        if (!isfinite(md->fhz[r]))
            return cbm__fail(ctx, CBM_E_RUNTIME, "motion: mode %zu has no frequency", r + 1);
        md->w[r] = 2.0 * MODAL_PI * md->fhz[r];
    }
    if (damping_ratio > 0.0) {
        /* as cbm_motion_create does for the full motion, from the same two lowest modes */
        double w1 = md->w[0], w2 = k > 1 ? md->w[1] : w1;
        m->alpha += 2.0 * damping_ratio * w1 * w2 / (w1 + w2);
        m->beta += 2.0 * damping_ratio / (w1 + w2);
    }
    for (size_t r = 0; r < k; r++)
        md->cr[r] = m->alpha + m->beta * md->w[r] * md->w[r];
    md->s_last = NAN;
    md->q_stale = md->x->c_stale = true;
    md->x->t_f = NAN;
    if (static_correction) {
        struct cbm__modal_ext *x = md->x;
        x->sc = x->c_stale = true;
        x->self = m;
        x->fc = cbm__calloc(ctx, nq, sizeof(double));
        x->fp = cbm__calloc(ctx, nq, sizeof(double));
        x->gbf = cbm__calloc(ctx, 3 * nq, sizeof(double));
        x->cq = cbm__calloc(ctx, nq, sizeof(double));
        if (!x->fc || !x->fp || !x->gbf || !x->cq)
            return CBM_E_NOMEM;
        /* K^-1 by the statics' tree factorisation, kept: the modal motion factorises nothing
         * else */
        if (cbm__dyn_factor(&m->d, 1.0, 0.0) != 0)
            return cbm__fail(ctx, CBM_E_INVALID,
                             "motion: static_correction needs a stable equilibrium (the "
                             "stiffness is not positive definite)");
    }
    return CBM_OK;
}

static double dotn(const double *a, const double *b, size_t n)
{
    double s = 0.0;
    for (size_t i = 0; i < n; i++)
        s += a[i] * b[i];
    return s;
}

/* out[r] = phi_r^T g for a generalised force g (3n). */
static void project(const cbm__modal *md, size_t nq, const double *g, double *out)
{
    for (size_t r = 0; r < md->k; r++)
        out[r] = dotn(md->phi + r * nq, g, nq);
}

/* Drops the forces in full of the static correction (a start drops the pending projected ones). */
static void drop_forces(cbm_motion *m)
{
    struct cbm__modal_ext *x = m->modal->x;
    if (x->fc_any)
        memset(x->fc, 0, m->nq * sizeof(double));
    if (x->fp_any)
        memset(x->fp, 0, m->nq * sizeof(double));
    x->fc_any = x->fp_any = false;
}

static void add_projected_force(cbm_motion *m, size_t seg, cbm_vec3 force)
{
    cbm__modal *md = m->modal;
    for (size_t r = 0; r < md->k; r++)
        md->p[r] += v3_dot(force, cbm__dyn_node_disp(&m->d, md->phi + r * m->nq, seg));
}

cbm_status cbm__modal_add_force(cbm_motion *m, size_t seg, cbm_vec3 force)
{
    add_projected_force(m, seg, force);
    struct cbm__modal_ext *x = m->modal->x;
    if (x->sc) {
        cbm__dyn_point_force(&m->d, seg, force, x->fp);
        x->fp_any = true;
    }
    return CBM_OK;
}

/* gb: the projections of the base's fictitious force -m a per unit acceleration along x, y, z
 * (the wrench -P_k (0, e_i) of every body, as motion.c's base_force). */
static void base_projections(cbm_motion *m)
{
    cbm__modal *md = m->modal;
    size_t n = m->d.n, nq = m->nq;
    for (int i = 0; i < 3; i++) {
        for (size_t k = 0; k < n; k++) {
            const double *pb = m->d.body + 36 * k;
            for (int j = 0; j < 6; j++)
                m->wb[6 * k + j] = -pb[6 * j + 3 + i];
        }
        memset(m->y, 0, nq * sizeof(double));
        cbm__dyn_wrench_force(&m->d, m->wb, m->y);
        for (size_t r = 0; r < md->k; r++)
            md->gb[3 * r + i] = dotn(md->phi + r * nq, m->y, nq);
        if (md->x->sc)
            memcpy(md->x->gbf + (size_t)i * nq, m->y, nq * sizeof(double));
    }
    md->gb_valid = md->x->gbf_valid = true;
}

/* The gust factor s(t) = U_ref(t) / U_ref of the drag nd (1 without a mean speed: then there
 * is no drag to scale). */
static double gust_factor(const cbm__drag *nd, double t)
{
    if (!(nd->u_ref > 0.0))
        return 1.0;
    return 1.0 + (nd->gust.n > 0 ? cbm__gust_at(&nd->gust, t) : 0.0) / nd->u_ref;
}

/* The linearised drag's projected force at gust factor s for modal rates ed and base velocity
 * vb: s|s| pw + |s| (cb vb - ca ed), into out (k). */
static void wind_load(const cbm__modal *md, double s, const double *ed, cbm_vec3 vb, double *out)
{
    size_t k = md->k;
    double as = fabs(s);
    for (size_t r = 0; r < k; r++) {
        const double *cb = md->cb + 3 * r;
        out[r] = s * as * md->pw[r] +
                 as * (cb[0] * vb.x + cb[1] * vb.y + cb[2] * vb.z - dotn(md->ca + r * k, ed, k));
    }
}

/* The central differences of the drag along the modes step a 1e-4 fraction of the wind (or
 * 1 m/s), vref, at the plant's farthest node, reach (at least 1 mm): the drag is smooth there
 * but for |w| w at w = 0, where the central difference of a function odd in the step is exact.
 * Mode ph's step scales it by the mode's largest component. */
static void fd_setup(const cbm_motion *m, const cbm__drag *nd, double *vref, double *reach)
{
    double h = 0.0;
    for (size_t i = 0; i < m->d.n; i++)
        h = fmax(h, v3_norm(m->d.e[i]));
    *vref = 1e-4 * fmax(nd->u_ref, 1.0);
    *reach = fmax(h, 1e-3);
}

static double fd_step(const double *ph, size_t nq, double vref, double reach)
{
    double pmax = 0.0;
    for (size_t i = 0; i < nq; i++)
        pmax = fmax(pmax, fabs(ph[i]));
    return vref / (pmax * reach);
}

/* The projections of the drag nd linearised about the still plant in its mean wind. */
static void wind_projections(cbm_motion *m, cbm__drag *nd)
{
    cbm__modal *md = m->modal;
    size_t k = md->k, nq = m->nq;
    int32_t ng = nd->gust.n;
    nd->gust.n = 0; /* the mean wind */
    cbm_vec3 zero = v3(0, 0, 0);
    memset(m->y, 0, nq * sizeof(double));
    cbm__drag_force(nd, &m->d, 0.0, m->y, zero, m->g);
    project(md, nq, m->g, md->pw);
    /* central differences along each mode (fd_step) */
    double vref, reach;
    fd_setup(m, nd, &vref, &reach);
    for (size_t c = 0; c < k; c++) {
        const double *ph = md->phi + c * nq;
        double eps = fd_step(ph, nq, vref, reach);
        for (size_t i = 0; i < nq; i++)
            m->y[i] = eps * ph[i];
        cbm__drag_force(nd, &m->d, 0.0, m->y, zero, m->g);
        for (size_t i = 0; i < nq; i++)
            m->y[i] = -eps * ph[i];
        cbm__drag_force(nd, &m->d, 0.0, m->y, zero, m->g2);
        for (size_t i = 0; i < nq; i++)
            m->g[i] = (m->g[i] - m->g2[i]) / (2.0 * eps);
        for (size_t r = 0; r < k; r++)
            md->ca[r * k + c] = -dotn(md->phi + r * nq, m->g, nq);
    }
    for (size_t r = 0; r < k; r++) /* G is symmetric; the differences nearly so */
        for (size_t c = r + 1; c < k; c++) {
            double avg = 0.5 * (md->ca[r * k + c] + md->ca[c * k + r]);
            md->ca[r * k + c] = md->ca[c * k + r] = avg;
        }
    memset(m->y, 0, nq * sizeof(double));
    for (int i = 0; i < 3; i++) {
        cbm_vec3 e = v3(i == 0 ? vref : 0.0, i == 1 ? vref : 0.0, i == 2 ? vref : 0.0);
        cbm__drag_force(nd, &m->d, 0.0, m->y, e, m->g);
        cbm__drag_force(nd, &m->d, 0.0, m->y, v3_scale(e, -1.0), m->g2);
        for (size_t j = 0; j < nq; j++)
            m->g[j] = (m->g[j] - m->g2[j]) / (2.0 * vref);
        for (size_t r = 0; r < k; r++)
            md->cb[3 * r + i] = dotn(md->phi + r * nq, m->g, nq);
    }
    nd->gust.n = ng;
    md->s_last = NAN;
}

/* Gust field (cbm_gust_def.coherence_decay > 0): the air speed at a drag point p is U_ref u(p)
 * s_p(t), s_p = sum_a w_pa s_a the bilinear interpolation of the gust factors s_j = 1 + u'_j /
 * U_ref of the grid's points (gust.c). Linearised as for one series, point by point, the drag is
 *     g(t, v) ~ sum_p (s_p|s_p| g_p + |s_p| (G_p v + G_bp v_base)),
 * and with s_p > 0 (a gust that does not reverse the wind, as the series' s|s| assumes too)
 *     s_p^2 = sum_a sum_b w_pa w_pb s_a s_b,   |s_p| = sum_a w_pa |s_a|,
 * exact, so the projected load is a sum over pairs of neighbouring grid points (one cell: the
 * offsets 0, 1, nx - 1, nx, nx + 1) of s_j s_l times the pair's share of phi^T g_mean, and the
 * damping and base terms sums over the grid points of |s_j| times their shares of ca and cb.
 * The shares are found once: phi_r^T f for f the generalised force of the wrenches W_p equals
 * sum_p Z_rp . W_p (virtual work), Z_rp the twist of segment p in mode r, so the per-segment
 * wrenches of the mean wind and their central differences (as wind_projections) are split by
 * the drag points' weights. The step then costs O(k G) for the load and O(k^2 G + k^3) for the
 * damping matrix, G the grid's points, for O(n k^2) once (and k twists of 6n doubles while the
 * shares are made). For s_a of both signs within a cell the pair's s_a s_b becomes (s_a|s_b| +
 * s_b|s_a|) / 2, which is s|s| when the two are equal (the uniform limit). */

static double dot6(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2] + a[3] * b[3] + a[4] * b[4] + a[5] * b[5];
}

/* the slot of the grid offset dj >= 0 within one cell, or -1 */
static int field_slot(const struct cbm__modal_ext *x, int32_t dj)
{
    for (int o = 0; o < 5; o++)
        if (x->off[o] == dj)
            return o;
    return -1;
}

/* Adds the weighted wrenches ww (wood, at the midpoints) and wo (organs, at the distal nodes) of
 * every segment, projected on the modes' twists zt, to the grid points' shares: to the pairs of
 * pl with weight w_a w_b (pl != NULL), else to dst (ng x k x stride, column col) with w_a times
 * sign. */
static void field_split(const cbm__modal *md, const cbm__drag *nd, const double *zt,
                        const double *ww, const double *wo, double *pl, double *dst, size_t stride,
                        size_t col, double sign, double *e)
{
    const struct cbm__modal_ext *x = md->x;
    size_t k = md->k, n = nd->n;
    for (size_t i = 0; i < n; i++)
        for (int pt = 0; pt < 2; pt++) {
            const double *W = (pt ? wo : ww) + 6 * i;
            if (W[0] == 0.0 && W[1] == 0.0 && W[2] == 0.0 && W[3] == 0.0 && W[4] == 0.0 &&
                W[5] == 0.0)
                continue;
            const int32_t *idx = nd->gi + 8 * i + 4 * pt;
            const double *wt = nd->gw + 8 * i + 4 * pt;
            for (size_t r = 0; r < k; r++)
                e[r] = sign * dot6(zt + 6 * (r * n + i), W);
            for (int a = 0; a < 4; a++) {
                if (wt[a] == 0.0)
                    continue;
                if (!pl) {
                    double *d = dst + (size_t)idx[a] * k * stride + col;
                    for (size_t r = 0; r < k; r++)
                        d[r * stride] += wt[a] * e[r];
                    continue;
                }
                for (int b = 0; b < 4; b++) {
                    if (wt[b] == 0.0)
                        continue;
                    int32_t j = idx[a] < idx[b] ? idx[a] : idx[b];
                    int o = field_slot(x, idx[a] < idx[b] ? idx[b] - idx[a] : idx[a] - idx[b]);
                    if (o < 0)
                        continue; /* not one cell's: the weights never pair such points */
                    double *d = pl + ((size_t)j * 5 + (size_t)o) * k, wab = wt[a] * wt[b];
                    for (size_t r = 0; r < k; r++)
                        d[r] += wab * e[r];
                }
            }
        }
}

/* The shares of the drag nd's gust field (none when it has no field). */
static cbm_status field_projections(cbm_motion *m, cbm__drag *nd)
{
    cbm__modal *md = m->modal;
    struct cbm__modal_ext *x = md->x;
    cbm_context *ctx = m->d.ctx;
    size_t k = md->k, nq = m->nq, n = m->d.n;
    field_free(ctx, x, k);
    x->t_f = NAN;
    if (nd->gust.n == 0 || nd->gust.np == 0)
        return CBM_OK;
    size_t ng = (size_t)nd->gust.np, b = sizeof(double);
    x->ng = ng;
    x->pl = cbm__calloc(ctx, ng * 5 * k, b);
    x->caf = cbm__calloc(ctx, ng * k * k, b);
    x->cbf = cbm__calloc(ctx, ng * 3 * k, b);
    x->sg = cbm__calloc(ctx, ng, b);
    x->ld = cbm__calloc(ctx, k, b);
    x->cd = cbm__calloc(ctx, k * k, b);
    x->cbd = cbm__calloc(ctx, 3 * k, b);
    double *zt = cbm__alloc(ctx, k * 6 * n * b), *wk = cbm__alloc(ctx, 24 * n * b);
    if (!x->pl || !x->caf || !x->cbf || !x->sg || !x->ld || !x->cd || !x->cbd || !zt || !wk) {
        cbm__free(ctx, zt, k * 6 * n * b);
        cbm__free(ctx, wk, 24 * n * b);
        field_free(ctx, x, k);
        return CBM_E_NOMEM;
    }
    int32_t nx = nd->gust.nx;
    int32_t off[5] = {0, 1, nx - 1, nx, nx + 1};
    for (int o = 0; o < 5; o++) {
        x->off[o] = off[o];
        x->slot_ok[o] = field_slot(x, off[o]) == o;
    }
    for (size_t r = 0; r < k; r++)
        cbm__dyn_twists(&m->d, md->phi + r * nq, zt + 6 * n * r);
    double *ww = wk, *wo = wk + 6 * n, *ww2 = wk + 12 * n, *wo2 = wk + 18 * n;
    cbm_vec3 zero = v3(0, 0, 0);
    memset(m->y, 0, nq * sizeof(double));
    cbm__drag_wrenches(nd, &m->d, m->y, zero, ww, wo);
    field_split(md, nd, zt, ww, wo, x->pl, NULL, 0, 0, 1.0, md->r);
    /* the damping's and the base's shares by central differences along each mode (fd_step) */
    double vref, reach;
    fd_setup(m, nd, &vref, &reach);
    for (size_t c = 0; c < k; c++) {
        const double *ph = md->phi + c * nq;
        double eps = fd_step(ph, nq, vref, reach);
        for (size_t i = 0; i < nq; i++)
            m->y[i] = eps * ph[i];
        cbm__drag_wrenches(nd, &m->d, m->y, zero, ww, wo);
        for (size_t i = 0; i < nq; i++)
            m->y[i] = -eps * ph[i];
        cbm__drag_wrenches(nd, &m->d, m->y, zero, ww2, wo2);
        for (size_t i = 0; i < 6 * n; i++) {
            ww[i] = (ww[i] - ww2[i]) / (2.0 * eps);
            wo[i] = (wo[i] - wo2[i]) / (2.0 * eps);
        }
        field_split(md, nd, zt, ww, wo, NULL, x->caf, k, c, -1.0, md->r);
    }
    for (size_t j = 0; j < ng; j++) { /* each share is symmetric; the differences nearly so */
        double *ca = x->caf + j * k * k;
        for (size_t r = 0; r < k; r++)
            for (size_t c = r + 1; c < k; c++) {
                double avg = 0.5 * (ca[r * k + c] + ca[c * k + r]);
                ca[r * k + c] = ca[c * k + r] = avg;
            }
    }
    memset(m->y, 0, nq * sizeof(double));
    for (int i = 0; i < 3; i++) {
        cbm_vec3 e = v3(i == 0 ? vref : 0.0, i == 1 ? vref : 0.0, i == 2 ? vref : 0.0);
        cbm__drag_wrenches(nd, &m->d, m->y, e, ww, wo);
        cbm__drag_wrenches(nd, &m->d, m->y, v3_scale(e, -1.0), ww2, wo2);
        for (size_t j = 0; j < 6 * n; j++) {
            ww[j] = (ww[j] - ww2[j]) / (2.0 * vref);
            wo[j] = (wo[j] - wo2[j]) / (2.0 * vref);
        }
        field_split(md, nd, zt, ww, wo, NULL, x->cbf, 3, (size_t)i, 1.0, md->r);
    }
    cbm__free(ctx, zt, k * 6 * n * b);
    cbm__free(ctx, wk, 24 * n * b);
    return CBM_OK;
}

/* The field's load (ld), damping (cd) and base (cbd) terms at time t (kept for the last t). */
static void field_terms(cbm__modal *md, cbm__drag *nd, double t)
{
    struct cbm__modal_ext *x = md->x;
    if (x->t_f == t)
        return;
    size_t k = md->k, ng = x->ng;
    const double *gv = cbm__gust_field_at(&nd->gust, t);
    for (size_t j = 0; j < ng; j++)
        x->sg[j] = 1.0 + gv[j] / nd->u_ref;
    memset(x->ld, 0, k * sizeof(double));
    memset(x->cd, 0, k * k * sizeof(double));
    memset(x->cbd, 0, 3 * k * sizeof(double));
    for (size_t j = 0; j < ng; j++) {
        double sj = x->sg[j], aj = fabs(sj);
        for (int o = 0; o < 5; o++) {
            size_t l = j + (size_t)x->off[o];
            if (!x->slot_ok[o] || x->off[o] < 0 || l >= ng)
                continue;
            double sl = x->sg[l], sjl = 0.5 * (sj * fabs(sl) + sl * aj);
            const double *pl = x->pl + (j * 5 + (size_t)o) * k;
            for (size_t r = 0; r < k; r++)
                x->ld[r] += sjl * pl[r];
        }
        const double *ca = x->caf + j * k * k, *cb = x->cbf + j * 3 * k;
        for (size_t i = 0; i < k * k; i++)
            x->cd[i] += aj * ca[i];
        for (size_t i = 0; i < 3 * k; i++)
            x->cbd[i] += aj * cb[i];
    }
    x->t_f = t;
}

/* The linearised drag's projected force at time t for the modal rates ed and base velocity vb
 * into out (k), with or without a field. */
static void wind_load_at(cbm__modal *md, cbm__drag *nd, double t, const double *ed, cbm_vec3 vb,
                         double *out)
{
    struct cbm__modal_ext *x = md->x;
    if (x->ng == 0) {
        wind_load(md, gust_factor(nd, t), ed, vb, out);
        return;
    }
    size_t k = md->k;
    field_terms(md, nd, t);
    for (size_t r = 0; r < k; r++) {
        const double *cb = x->cbd + 3 * r;
        out[r] = x->ld[r] + cb[0] * vb.x + cb[1] * vb.y + cb[2] * vb.z - dotn(x->cd + r * k, ed, k);
    }
}

cbm_status cbm__modal_set_wind(cbm_motion *m, cbm__drag *nd)
{
    cbm__modal *md = m->modal;
    size_t k = md->k;
    /* keep the acceleration consistent with the new load, as the full motion does */
    if (md->wind)
        wind_load_at(md, &m->drag, m->t, md->ed, m->bv, md->r);
    else
        memset(md->r, 0, k * sizeof(double));
    for (size_t r = 0; r < k; r++)
        md->edd[r] -= md->r[r];
    wind_projections(m, nd);
    CBM_TRY(field_projections(m, nd));
    md->wind = true;
    wind_load_at(md, nd, m->t, md->ed, m->bv, md->r);
    for (size_t r = 0; r < k; r++)
        md->edd[r] += md->r[r];
    return CBM_OK;
}

/* eta'' from the equation of motion at time t with the pending loads cleared: the wind's load
 * at (t, eta', base velocity) - (C eta' + w^2 eta). */
static void modal_acceleration(cbm_motion *m)
{
    cbm__modal *md = m->modal;
    size_t k = md->k;
    if (md->wind)
        wind_load_at(md, &m->drag, m->t, md->ed, m->bv, md->edd);
    else
        memset(md->edd, 0, k * sizeof(double));
    for (size_t r = 0; r < k; r++)
        md->edd[r] -= md->cr[r] * md->ed[r] + md->w[r] * md->w[r] * md->eta[r];
    memset(md->p, 0, k * sizeof(double));
    drop_forces(m);
    md->q_stale = md->x->c_stale = true;
}

cbm_status cbm__modal_start_deflected(cbm_motion *m, size_t seg, cbm_vec3 force)
{
    cbm__modal *md = m->modal;
    /* K q = f in the modes: eta_r = phi_r^T f / w_r^2, released at t = 0 */
    memset(md->p, 0, md->k * sizeof(double));
    drop_forces(m);
    add_projected_force(m, seg, force);
    for (size_t r = 0; r < md->k; r++) {
        md->eta[r] = md->p[r] / (md->w[r] * md->w[r]);
        md->ed[r] = 0.0;
        md->edd[r] = -md->p[r];
        md->p[r] = 0.0;
    }
    m->t = 0.0;
    md->q_stale = md->x->c_stale = true;
    return CBM_OK;
}

cbm_status cbm__modal_start_state(cbm_motion *m, const double *q, const double *v)
{
    cbm__modal *md = m->modal;
    size_t nq = m->nq;
    /* eta = phi^T M q: the M-orthogonal projection on the modes */
    const double *src[2] = {q, v};
    double *dst[2] = {md->eta, md->ed};
    for (int j = 0; j < 2; j++) {
        if (!src[j]) {
            memset(dst[j], 0, md->k * sizeof(double));
            continue;
        }
        for (size_t i = 0; i < nq; i++)
            if (!isfinite(src[j][i]))
                return cbm__fail(m->d.ctx, CBM_E_INVALID, "motion: start state %zu not finite", i);
        cbm__dyn_apply(&m->d, 0.0, 1.0, src[j], m->y);
        project(md, nq, m->y, dst[j]);
    }
    m->bv = m->ba = m->bd = m->ba_next = v3(0, 0, 0);
    m->t = 0.0;
    modal_acceleration(m);
    return CBM_OK;
}

cbm_status cbm__modal_start_wind_static(cbm_motion *m)
{
    cbm__modal *md = m->modal;
    for (size_t r = 0; r < md->k; r++) {
        md->eta[r] = md->pw[r] / (md->w[r] * md->w[r]);
        md->ed[r] = 0.0;
    }
    m->bv = m->ba = m->bd = v3(0, 0, 0);
    m->t = 0.0;
    modal_acceleration(m);
    return CBM_OK;
}

/* In-place Cholesky factorisation of the symmetric positive definite k x k matrix a (lower
 * triangle); false if a pivot is not positive. */
static bool cholesky(double *a, size_t k)
{
    for (size_t j = 0; j < k; j++) {
        double d = a[j * k + j];
        for (size_t l = 0; l < j; l++)
            d -= a[j * k + l] * a[j * k + l];
        if (!(d > 0.0))
            return false;
        d = sqrt(d);
        a[j * k + j] = d;
        for (size_t i = j + 1; i < k; i++) {
            double s = a[i * k + j];
            for (size_t l = 0; l < j; l++)
                s -= a[i * k + l] * a[j * k + l];
            a[i * k + j] = s / d;
        }
    }
    return true;
}

static void cholesky_solve(const double *a, size_t k, double *x)
{
    for (size_t i = 0; i < k; i++) {
        double s = x[i];
        for (size_t l = 0; l < i; l++)
            s -= a[i * k + l] * x[l];
        x[i] = s / a[i * k + i];
    }
    for (size_t i = k; i-- > 0;) {
        double s = x[i];
        for (size_t l = i + 1; l < k; l++)
            s -= a[l * k + i] * x[l];
        x[i] = s / a[i * k + i];
    }
}

cbm_status cbm__modal_step(cbm_motion *m)
{
    cbm__modal *md = m->modal;
    size_t k = md->k;
    double dt = m->dt, c0 = 4.0 / (dt * dt), c1 = 4.0 / dt, t1 = m->t + dt;
    struct cbm__modal_ext *xs = md->x;
    if (xs->sc) { /* the forces added for this step become the load of its end */
        if (xs->fc_any)
            memset(xs->fc, 0, m->nq * sizeof(double));
        xs->fc_any = xs->fp_any;
        if (xs->fp_any) {
            double *sw = xs->fc;
            xs->fc = xs->fp;
            xs->fp = sw;
            xs->fp_any = false;
        }
    }
    /* the base: trapezoidal rule as for q (motion.c) */
    cbm_vec3 ba1 = m->ba_next, bv1 = m->bv, bd1 = m->bd;
    if (m->base_moves) {
        if (!md->gb_valid)
            base_projections(m);
        for (size_t r = 0; r < k; r++)
            md->p[r] +=
                md->gb[3 * r] * ba1.x + md->gb[3 * r + 1] * ba1.y + md->gb[3 * r + 2] * ba1.z;
        bv1 = v3_add(m->bv, v3_scale(v3_add(m->ba, ba1), 0.5 * dt));
        bd1 = v3_add(v3_madd(m->bd, m->bv, dt), v3_scale(v3_add(m->ba, ba1), 0.25 * dt * dt));
    }
    /* the right-hand side: p + (c0 eta + c1 eta' + eta'') + C (2 eta / dt + eta'), C the
     * diagonal Rayleigh damping plus, with wind, |s| ca */
    double as = 0.0;
    struct cbm__modal_ext *xf = md->x;
    const double *cd = md->ca; /* the wind's damping matrix at t1 over |s| (as) */
    if (md->wind && xf->ng > 0) {
        field_terms(md, &m->drag, t1);
        as = 1.0;
        cd = xf->cd;
        for (size_t r = 0; r < k; r++) {
            const double *cb = xf->cbd + 3 * r;
            md->p[r] += xf->ld[r] + cb[0] * bv1.x + cb[1] * bv1.y + cb[2] * bv1.z;
        }
    } else if (md->wind) {
        double s = gust_factor(&m->drag, t1);
        as = fabs(s);
        for (size_t r = 0; r < k; r++) {
            const double *cb = md->cb + 3 * r;
            md->p[r] += s * as * md->pw[r] + as * (cb[0] * bv1.x + cb[1] * bv1.y + cb[2] * bv1.z);
        }
    }
    double *x = md->r;
    for (size_t r = 0; r < k; r++)
        x[r] = md->p[r] + c0 * md->eta[r] + c1 * md->ed[r] + md->edd[r] +
               md->cr[r] * (2.0 / dt * md->eta[r] + md->ed[r]);
    if (md->wind && as > 0.0) {
        for (size_t r = 0; r < k; r++) {
            const double *ca = cd + r * k;
            double s = 0.0;
            for (size_t c = 0; c < k; c++)
                s += ca[c] * (2.0 / dt * md->eta[c] + md->ed[c]);
            x[r] += as * s;
        }
        if (as != md->s_last || xf->ng > 0) { /* a field changes the matrix every step */
            for (size_t r = 0; r < k; r++)
                for (size_t c = 0; c < k; c++)
                    md->a[r * k + c] = 2.0 / dt * as * cd[r * k + c];
            for (size_t r = 0; r < k; r++)
                md->a[r * k + r] += c0 + 2.0 / dt * md->cr[r] + md->w[r] * md->w[r];
            if (!cholesky(md->a, k))
                return cbm__fail(m->d.ctx, CBM_E_RUNTIME,
                                 "motion: the modal step's matrix is not positive definite at "
                                 "t = %g s",
                                 t1);
            md->s_last = as;
        }
        cholesky_solve(md->a, k, x);
    } else
        for (size_t r = 0; r < k; r++)
            x[r] /= c0 + 2.0 / dt * md->cr[r] + md->w[r] * md->w[r];
    bool finite = true;
    for (size_t r = 0; r < k; r++) {
        double qn = x[r];
        double an = c0 * (qn - md->eta[r]) - c1 * md->ed[r] - md->edd[r];
        md->ed[r] += 0.5 * dt * (md->edd[r] + an);
        md->edd[r] = an;
        md->eta[r] = qn;
        md->p[r] = 0.0;
        finite = finite && isfinite(qn);
    }
    m->ba = ba1;
    m->bv = bv1;
    m->bd = bd1;
    m->ba_next = v3(0, 0, 0);
    m->t = t1;
    md->q_stale = md->x->c_stale = true;
    if (!finite)
        return cbm__fail(m->d.ctx, CBM_E_NONFINITE, "motion: non-finite state at t = %g s", m->t);
    return CBM_OK;
}

void cbm__modal_energies(const cbm_motion *m, double *kinetic, double *potential)
{
    const cbm__modal *md = m->modal;
    double ek = 0.0, ep = 0.0;
    for (size_t r = 0; r < md->k; r++) {
        ek += md->ed[r] * md->ed[r];
        ep += md->w[r] * md->w[r] * md->eta[r] * md->eta[r];
    }
    if (kinetic)
        *kinetic = 0.5 * ek;
    if (potential)
        *potential = 0.5 * ep;
}

/* Static correction (the mode-acceleration method; Williams 1945, Cornwell, Craig & Johnson
 * 1983): the truncated modes answer a load that varies slowly against their periods
 * quasi-statically, with sum_{r > k} phi_r phi_r^T f / w_r^2 = K^-1 f - sum_{r <= k} phi_r
 * phi_r^T f / w_r^2. Added to the modal shape at output, it costs one O(n) tree solve (the
 * factorisation of K kept from the creation) and the load f of the current time in full: the
 * forces of the last step, the base's fictitious forces, and the wind's drag on the still plant
 * at this time (the quasi-steady load whose projection drives the modes; its velocity terms, the
 * aerodynamic damping, act on the kept modes only). With all 3n modes it vanishes to round-off. */
static void static_correction(cbm_motion *m)
{
    cbm__modal *md = m->modal;
    struct cbm__modal_ext *x = md->x;
    size_t nq = m->nq;
    double *f = x->cq;
    if (md->wind) {
        memset(m->y, 0, nq * sizeof(double));
        for (size_t r = 0; r < md->k; r++) {
            const double *ph = md->phi + r * nq;
            double e = md->ed[r];
            for (size_t i = 0; i < nq; i++)
                m->y[i] += e * ph[i];
        }
        cbm__drag_force(&m->drag, &m->d, m->t, m->y, m->bv, f);
    } else
        memset(f, 0, nq * sizeof(double));
    if (x->fc_any)
        for (size_t i = 0; i < nq; i++)
            f[i] += x->fc[i];
    if (x->gbf_valid && (m->ba.x != 0.0 || m->ba.y != 0.0 || m->ba.z != 0.0)) {
        const double a[3] = {m->ba.x, m->ba.y, m->ba.z};
        for (int j = 0; j < 3; j++)
            for (size_t i = 0; i < nq; i++)
                f[i] += a[j] * x->gbf[(size_t)j * nq + i];
    }
    for (size_t r = 0; r < md->k; r++) /* the kept modes' static share, before the solve */
        md->r[r] = dotn(md->phi + r * nq, f, nq) / (md->w[r] * md->w[r]);
    cbm__dyn_solve(&m->d, f, f);
    for (size_t r = 0; r < md->k; r++) {
        const double *ph = md->phi + r * nq;
        double c = md->r[r];
        for (size_t i = 0; i < nq; i++)
            f[i] -= c * ph[i];
    }
    x->c_stale = false;
}

cbm_vec3 cbm__modal_displacement(const cbm_motion *m, size_t seg)
{
    const cbm__modal *md = m->modal;
    cbm_vec3 u = v3(0, 0, 0);
    for (size_t r = 0; r < md->k; r++)
        u = v3_madd(u, cbm__dyn_node_disp(&m->d, md->phi + r * m->nq, seg), md->eta[r]);
    if (md->x->sc) {
        if (md->x->c_stale)
            static_correction(md->x->self);
        u = v3_add(u, cbm__dyn_node_disp(&m->d, md->x->cq, seg));
    }
    return u;
}

const double *cbm__modal_rotations(const cbm_motion *m)
{
    cbm__modal *md = m->modal;
    size_t nq = m->nq;
    if (md->q_stale) {
        memset(md->qbuf, 0, nq * sizeof(double));
        for (size_t r = 0; r < md->k; r++) {
            const double *ph = md->phi + r * nq;
            double e = md->eta[r];
            for (size_t i = 0; i < nq; i++)
                md->qbuf[i] += e * ph[i];
        }
        if (md->x->sc) {
            if (md->x->c_stale)
                static_correction(md->x->self);
            for (size_t i = 0; i < nq; i++)
                md->qbuf[i] += md->x->cq[i];
        }
        md->q_stale = false;
    }
    return md->qbuf;
}
