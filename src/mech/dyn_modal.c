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
 * once by central differences of the drag (2K + 7 drag evaluations). The error of the reduction
 * (the truncated modes' response, and for wind the linearisation) is measured against the full
 * motion in tests/test_dyn_modal.c and stated in docs/dynamics.md. */
#include "core/vecmath.h"
#include "mech/dyn_internal.h"
#include "mech/mech_internal.h"

#include <math.h>
#include <string.h>

#define MODAL_PI 3.14159265358979323846

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
                             double damping_ratio)
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
    m->modal = md; /* freed with m from here on */
    bool ok = md->phi && md->w && md->fhz && md->eta && md->ed && md->edd && md->p && md->cr &&
              md->gb && md->pw && md->ca && md->cb && md->a && md->r && md->qbuf;
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
    md->q_stale = true;
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

cbm_status cbm__modal_add_force(cbm_motion *m, size_t seg, cbm_vec3 force)
{
    cbm__modal *md = m->modal;
    for (size_t r = 0; r < md->k; r++)
        md->p[r] += v3_dot(force, cbm__dyn_node_disp(&m->d, md->phi + r * m->nq, seg));
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
    }
    md->gb_valid = true;
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

/* The projections of the drag nd linearised about the still plant in its mean wind. */
static void wind_projections(cbm_motion *m, cbm__drag *nd)
{
    cbm__modal *md = m->modal;
    size_t k = md->k, nq = m->nq, n = m->d.n;
    int32_t ng = nd->gust.n;
    nd->gust.n = 0; /* the mean wind */
    cbm_vec3 zero = v3(0, 0, 0);
    memset(m->y, 0, nq * sizeof(double));
    cbm__drag_force(nd, &m->d, 0.0, m->y, zero, m->g);
    project(md, nq, m->g, md->pw);
    /* central differences, the steps scaled to a 1e-4 fraction of the wind (or 1 m/s) at the
     * plant's farthest node: the drag is smooth there but for |w| w at w = 0, where the central
     * difference of a function odd in the step is exact */
    double h = 0.0;
    for (size_t i = 0; i < n; i++)
        h = fmax(h, v3_norm(m->d.e[i]));
    double vref = 1e-4 * fmax(nd->u_ref, 1.0);
    for (size_t c = 0; c < k; c++) {
        const double *ph = md->phi + c * nq;
        double pmax = 0.0;
        for (size_t i = 0; i < nq; i++)
            pmax = fmax(pmax, fabs(ph[i]));
        double eps = vref / (pmax * fmax(h, 1e-3));
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

cbm_status cbm__modal_set_wind(cbm_motion *m, cbm__drag *nd)
{
    cbm__modal *md = m->modal;
    size_t k = md->k;
    /* keep the acceleration consistent with the new load, as the full motion does */
    if (md->wind)
        wind_load(md, gust_factor(&m->drag, m->t), md->ed, m->bv, md->r);
    else
        memset(md->r, 0, k * sizeof(double));
    for (size_t r = 0; r < k; r++)
        md->edd[r] -= md->r[r];
    wind_projections(m, nd);
    md->wind = true;
    wind_load(md, gust_factor(nd, m->t), md->ed, m->bv, md->r);
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
        wind_load(md, gust_factor(&m->drag, m->t), md->ed, m->bv, md->edd);
    else
        memset(md->edd, 0, k * sizeof(double));
    for (size_t r = 0; r < k; r++)
        md->edd[r] -= md->cr[r] * md->ed[r] + md->w[r] * md->w[r] * md->eta[r];
    memset(md->p, 0, k * sizeof(double));
    md->q_stale = true;
}

cbm_status cbm__modal_start_deflected(cbm_motion *m, size_t seg, cbm_vec3 force)
{
    cbm__modal *md = m->modal;
    /* K q = f in the modes: eta_r = phi_r^T f / w_r^2, released at t = 0 */
    memset(md->p, 0, md->k * sizeof(double));
    cbm__modal_add_force(m, seg, force);
    for (size_t r = 0; r < md->k; r++) {
        md->eta[r] = md->p[r] / (md->w[r] * md->w[r]);
        md->ed[r] = 0.0;
        md->edd[r] = -md->p[r];
        md->p[r] = 0.0;
    }
    m->t = 0.0;
    md->q_stale = true;
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
    if (md->wind) {
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
            const double *ca = md->ca + r * k;
            double s = 0.0;
            for (size_t c = 0; c < k; c++)
                s += ca[c] * (2.0 / dt * md->eta[c] + md->ed[c]);
            x[r] += as * s;
        }
        if (as != md->s_last) {
            for (size_t r = 0; r < k; r++)
                for (size_t c = 0; c < k; c++)
                    md->a[r * k + c] = 2.0 / dt * as * md->ca[r * k + c];
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
    md->q_stale = true;
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

cbm_vec3 cbm__modal_displacement(const cbm_motion *m, size_t seg)
{
    const cbm__modal *md = m->modal;
    cbm_vec3 u = v3(0, 0, 0);
    for (size_t r = 0; r < md->k; r++)
        u = v3_madd(u, cbm__dyn_node_disp(&m->d, md->phi + r * m->nq, seg), md->eta[r]);
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
        md->q_stale = false;
    }
    return md->qbuf;
}
