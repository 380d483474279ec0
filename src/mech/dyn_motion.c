/* Time stepping of the linearised motion about the equilibrium, M q'' + C q' + K q = f(t), by
 * Newmark's average-acceleration rule (the trapezoidal rule: gamma = 1/2, beta = 1/4). It is
 * implicit, unconditionally stable and second order, and for an undamped linear system it
 * conserves 1/2 q'.M q' + 1/2 q.K q exactly (to round-off) whatever dt, which the tests check.
 * Each step is one solve with the factorised effective matrix K_eff = (1 + 2 beta_R / dt) K +
 * (4 / dt^2 + 2 alpha_R / dt) M (tree.c, factorised once) and two products with M and K: O(n).
 * Damping: Rayleigh, C = alpha_R M + beta_R K, from a damping ratio matched at the two lowest
 * modes (alpha_R = 2 zeta w1 w2 / (w1 + w2), beta_R = 2 zeta / (w1 + w2)), plus any explicit
 * coefficients. */
#include "mech/dyn_internal.h"
#include "core/vecmath.h"
#include "mech/mech_internal.h"

#include <math.h>
#include <string.h>

cbm_motion_def cbm_motion_def_default(void)
{
    cbm_motion_def d = {1e-3, 0.0, 0.0, 0.0, CBM_MOTION_FULL, 0, 0.0, false};
    return d;
}

void cbm_motion_destroy(cbm_motion *m)
{
    if (!m)
        return;
    cbm_context *ctx = m->d.ctx;
    size_t b = m->nq * sizeof(double);
    cbm__free(ctx, m->q, b);
    cbm__free(ctx, m->v, b);
    cbm__free(ctx, m->a, b);
    cbm__free(ctx, m->f, b);
    cbm__free(ctx, m->w1, b);
    cbm__free(ctx, m->w2, b);
    cbm__free(ctx, m->y, b);
    cbm__free(ctx, m->g, b);
    cbm__free(ctx, m->g2, b);
    cbm__free(ctx, m->rhs, b);
    cbm__free(ctx, m->wb, 2 * b);
    size_t ns = m->d.n;
    cbm__free(ctx, m->gam, 6 * ns * sizeof(double));
    cbm__free(ctx, m->zs, 6 * ns * sizeof(double));
    cbm__free(ctx, m->zw, 6 * ns * sizeof(double));
    cbm__free(ctx, m->thw, 3 * ns * sizeof(double));
    cbm__drag_free(ctx, &m->drag);
    cbm__modal_free(ctx, m->modal, m->nq);
    cbm__dyn_free(&m->d);
    cbm__free(ctx, m, sizeof *m);
}

static cbm_status refactor(cbm_motion *m)
{
    m->zw_valid = false; /* called after every change of the state outside a step */
    double dt = m->dt;
    size_t r =
        cbm__dyn_factor(&m->d, 1.0 + 2.0 * m->beta / dt, 4.0 / (dt * dt) + 2.0 * m->alpha / dt);
    if (r == (size_t)-1)
        return cbm__fail(m->d.ctx, CBM_E_RUNTIME,
                         "motion: the effective stiffness is singular (dt too long for an "
                         "unstable equilibrium)");
    return CBM_OK;
}

/* The twists of the next step's right-hand side vectors from the current state: zw of
 * w1 = a0 q + a1 v + a (the product with M), thw the rotations of w2 = beta (2 q / dt + v) (the
 * product with K). One forward sweep; the fused step keeps them current itself. */
static void rhs_twists(cbm_motion *m, double a0, double a1)
{
    const cbm__dyn *d = &m->d;
    double b2 = 2.0 * m->beta / m->dt;
    for (size_t k = 0; k < d->n; k++) {
        int64_t pa = d->parent[k];
        double *zk = m->zw + 6 * k, *tk = m->thw + 3 * k;
        const double *q = m->q + 3 * k, *v = m->v + 3 * k, *a = m->a + 3 * k;
        double w[3] = {a0 * q[0] + a1 * v[0] + a[0], a0 * q[1] + a1 * v[1] + a[1],
                       a0 * q[2] + a1 * v[2] + a[2]};
        if (pa >= 0) {
            memcpy(zk, m->zw + 6 * pa, 6 * sizeof(double));
            memcpy(tk, m->thw + 3 * pa, 3 * sizeof(double));
        } else {
            memset(zk, 0, 6 * sizeof(double));
            memset(tk, 0, 3 * sizeof(double));
        }
        cbm__dyn_sq(d->x + k, w, zk);
        for (int i = 0; i < 3; i++)
            tk[i] += b2 * q[i] + m->beta * v[i];
        m->gam[6 * k] = m->gam[6 * k + 1] = m->gam[6 * k + 2] = 0.0;
        m->gam[6 * k + 3] = m->gam[6 * k + 4] = m->gam[6 * k + 5] = 0.0;
    }
    m->zw_valid = true;
}

/* One Newmark step without drag or base motion in two sweeps over the tree instead of six (the
 * products M w1 and K w2 of the right-hand side, the solve's elimination and back-substitution,
 * and the state update): the products' wrenches are summed up the tree in the same backward
 * sweep as the elimination's (tree.c: u_k = b_k - S^T sum psi_c with b = f + M w1 + K w2, one
 * carried sum Gamma = W - psi per segment), and the forward sweep that back-substitutes q1 also
 * updates v, a and builds the twists of the next step's w1, w2. The same arithmetic as the
 * general path in another order: the two agree to round-off (tests/test_dyn_loads.c). */
/* Newmark's update of one coordinate to the new rotation qn; returns the component of the next
 * step's w1 = a0 q + a1 v + a. nm: a0, a1, c0, c1, dt / 2. */
static inline double newmark(double qn, double *q, double *v, double *a, const double *nm,
                             double *nan_check)
{
    double an = nm[2] * (qn - *q) - nm[3] * *v - *a;
    double vn = *v + nm[4] * (*a + an);
    *v = vn;
    *a = an;
    *q = qn;
    *nan_check += 0.0 * qn;
    return nm[0] * qn + nm[1] * vn + an;
}

/* GCC at -O2 (the project's build) schedules this loop about 20 % slower than at -O3 without
 * vectorisation (measured with bench_dyn at 2,500 segments, where the step is in the cache and
 * compute-bound: docs/performance.md); CMakeLists.txt compiles this file so with GCC.
 * Vectorisation stays off (it was slower, and lanes would not change the arithmetic anyway: no
 * reassociation, -ffp-contract=off), so the results are the same to the bit. */
static bool fused_step(cbm_motion *m, double a0, double a1, double c0, double c1)
{
    const double nm[5] = {a0, a1, c0, c1, 0.5 * m->dt};
    const cbm__dyn *d = &m->d;
    size_t n = d->n;
    double dt = m->dt, beta = m->beta, b2 = 2.0 * beta / dt;
    bool damp = beta > 0.0, forced = m->forced;
    double *u = d->u, nan_check = 0.0; /* stays 0 unless some q is not finite */
    /* from the tips; each segment's carried sum and force are cleared once read, so that the
     * forward sweep need not touch them */
    for (size_t k = n; k-- > 0;) {
        if (k >= CBM__AHEAD)
            CBM__DYN_AHEAD(d->parent, n, k - CBM__AHEAD, m->gam);
        /* T = the children's carried sums + P z */
        double t[6], uk[3];
        double *gk = m->gam + 6 * k;
        cbm__dyn_pz(d->pc + 10 * k, m->zw + 6 * k, gk, t);
        memset(gk, 0, 6 * sizeof(double));
        cbm__dyn_stw(d->x + k, t, uk);
        if (forced)
            for (int i = 0; i < 3; i++) {
                uk[i] += m->f[3 * k + i];
                m->f[3 * k + i] = 0.0;
            }
        int64_t pa = d->parent[k];
        if (damp) {
            const double *q = m->q + 3 * k, *v = m->v + 3 * k, *ak = d->ak + 9 * k,
                         *g = d->geo + 9 * k;
            double w[3] = {b2 * q[0] + beta * v[0], b2 * q[1] + beta * v[1],
                           b2 * q[2] + beta * v[2]};
            double th[3] = {0, 0, 0};
            if (pa >= 0)
                memcpy(th, m->thw + 3 * pa, sizeof th);
            for (int i = 0; i < 3; i++) {
                uk[i] += ak[3 * i] * w[0] + ak[3 * i + 1] * w[1] + ak[3 * i + 2] * w[2] +
                         g[i] * th[0] + g[3 + i] * th[1] + g[6 + i] * th[2];
                t[i] += g[3 * i] * w[0] + g[3 * i + 1] * w[1] + g[3 * i + 2] * w[2];
            }
        }
        /* the elimination's step as in tree.c (cbm__dyn_solve): D^-1 u kept, the rest passed on */
        double *sk = u + 3 * k, lts[6];
        cbm__dyn_dinv_u(d->dinv + 9 * k, uk, sk);
        if (pa < 0)
            continue;
        cbm__dyn_lt_s(d->dl + 18 * k, uk, lts);
        double *gp = m->gam + 6 * pa;
        for (int j = 0; j < 6; j++)
            gp[j] += t[j] - lts[j];
    }
    /* from the base: q1, then v, a and the twists of the next step's right-hand side */
    for (size_t k = 0; k < n; k++) {
        int64_t pa = d->parent[k];
        double *zs = m->zs + 6 * k, *zw = m->zw + 6 * k, *th = m->thw + 3 * k, qn[3];
        CBM__DYN_AHEAD(d->parent, n, k + CBM__AHEAD, m->zs);
        CBM__DYN_AHEAD(d->parent, n, k + CBM__AHEAD, m->zw);
        if (pa >= 0) {
            const double *zp = m->zs + 6 * pa;
            cbm__dyn_back_sub(d->dl + 18 * k, u + 3 * k, zp, qn);
            memcpy(zs, zp, 6 * sizeof(double));
            memcpy(zw, m->zw + 6 * pa, 6 * sizeof(double));
            if (damp)
                memcpy(th, m->thw + 3 * pa, 3 * sizeof(double));
        } else {
            memcpy(qn, u + 3 * k, sizeof qn);
            memset(zs, 0, 6 * sizeof(double));
            memset(zw, 0, 6 * sizeof(double));
            if (damp)
                memset(th, 0, 3 * sizeof(double));
        }
        double *q = m->q + 3 * k, *v = m->v + 3 * k, *a = m->a + 3 * k;
        double w0 = newmark(qn[0], q, v, a, nm, &nan_check);
        double w1 = newmark(qn[1], q + 1, v + 1, a + 1, nm, &nan_check);
        double w2 = newmark(qn[2], q + 2, v + 2, a + 2, nm, &nan_check);
        if (damp)
            for (int i = 0; i < 3; i++)
                th[i] += b2 * q[i] + beta * v[i];
        cbm__dyn_sq3(d->x + k, qn[0], qn[1], qn[2], zs);
        cbm__dyn_sq3(d->x + k, w0, w1, w2, zw);
    }
    m->forced = false;
    return nan_check == 0.0;
}

cbm_status cbm_motion_create(const cbm_plant *plant, const cbm_motion_def *def, cbm_motion **out)
{
    if (!out)
        return CBM_E_INVALID;
    *out = NULL;
    if (!plant)
        return CBM_E_INVALID;
    cbm_motion_def md = def ? *def : cbm_motion_def_default();
    cbm_context *ctx = plant->ctx;
    if (!(md.dt > 0.0) || !isfinite(md.dt))
        return cbm__fail(ctx, CBM_E_INVALID, "motion: dt = %g must be positive", md.dt);
    if (!(md.damping_ratio >= 0.0) || !isfinite(md.damping_ratio) || !(md.rayleigh_alpha >= 0.0) ||
        !(md.rayleigh_beta >= 0.0) || !isfinite(md.rayleigh_alpha) || !isfinite(md.rayleigh_beta))
        return cbm__fail(ctx, CBM_E_INVALID,
                         "motion: damping_ratio and the Rayleigh coefficients must be >= 0");
    if (md.method != CBM_MOTION_FULL && md.method != CBM_MOTION_MODAL)
        return cbm__fail(ctx, CBM_E_INVALID, "motion: unknown method %d", (int)md.method);
    bool modal = md.method == CBM_MOTION_MODAL;
    if (md.static_correction && !modal)
        return cbm__fail(ctx, CBM_E_INVALID, "motion: static_correction is for the modal method");
    double alpha = md.rayleigh_alpha, beta = md.rayleigh_beta;
    if (md.damping_ratio > 0.0 && !modal) {
        double f[2];
        CBM_TRY(cbm_plant_modes(plant, 2, f, NULL));
        double w1 = 2.0 * 3.14159265358979323846 * f[0];
        double w2 = isfinite(f[1]) ? 2.0 * 3.14159265358979323846 * f[1] : w1;
        alpha += 2.0 * md.damping_ratio * w1 * w2 / (w1 + w2);
        beta += 2.0 * md.damping_ratio / (w1 + w2);
    }
    cbm_motion *m = cbm__calloc(ctx, 1, sizeof *m);
    if (!m)
        return CBM_E_NOMEM;
    cbm_status st = cbm__dyn_build(plant, &m->d);
    if (st != CBM_OK) {
        cbm__free(ctx, m, sizeof *m);
        return st;
    }
    m->d.ctx = ctx;
    m->nq = 3 * m->d.n;
    m->dt = md.dt;
    m->alpha = alpha;
    m->beta = beta;
    m->q = cbm__calloc(ctx, m->nq, sizeof(double));
    m->v = cbm__calloc(ctx, m->nq, sizeof(double));
    m->a = cbm__calloc(ctx, m->nq, sizeof(double));
    m->f = cbm__calloc(ctx, m->nq, sizeof(double));
    m->w1 = cbm__calloc(ctx, m->nq, sizeof(double));
    m->w2 = cbm__calloc(ctx, m->nq, sizeof(double));
    m->y = cbm__calloc(ctx, m->nq, sizeof(double));
    m->g = cbm__calloc(ctx, m->nq, sizeof(double));
    m->g2 = cbm__calloc(ctx, m->nq, sizeof(double));
    m->rhs = cbm__calloc(ctx, m->nq, sizeof(double));
    m->wb = cbm__calloc(ctx, 2 * m->nq, sizeof(double));
    size_t ns = m->d.n;
    m->gam = cbm__calloc(ctx, 6 * ns, sizeof(double));
    m->zs = cbm__calloc(ctx, 6 * ns, sizeof(double));
    m->zw = cbm__calloc(ctx, 6 * ns, sizeof(double));
    m->thw = cbm__calloc(ctx, 3 * ns, sizeof(double));
    if (!m->q || !m->v || !m->a || !m->f || !m->w1 || !m->w2 || !m->y || !m->g || !m->g2 ||
        !m->rhs || !m->wb || !m->gam || !m->zs || !m->zw || !m->thw) {
        cbm_motion_destroy(m);
        return CBM_E_NOMEM;
    }
    /* the modal motion needs no factorisation: its modes come from their own Lanczos run */
    st = modal ? cbm__modal_create(plant, m, md.modes, md.mode_cut_hz, md.damping_ratio,
                                   md.static_correction)
               : refactor(m);
    if (st != CBM_OK) {
        cbm_motion_destroy(m);
        return st;
    }
    *out = m;
    return CBM_OK;
}

cbm_status cbm_motion_start_deflected(cbm_motion *m, size_t seg, cbm_vec3 force)
{
    if (!m || seg >= m->d.n || !v3_isfinite(force))
        return CBM_E_INVALID;
    if (m->modal)
        return cbm__modal_start_deflected(m, seg, force);
    size_t n = m->nq;
    memset(m->w1, 0, n * sizeof(double));
    cbm__dyn_point_force(&m->d, seg, force, m->w1);
    size_t r = cbm__dyn_factor(&m->d, 1.0, 0.0);
    if (r != 0) {
        refactor(m);
        return cbm__fail(m->d.ctx, CBM_E_RUNTIME,
                         "motion: the equilibrium is unstable, no static deflection");
    }
    cbm__dyn_solve(&m->d, m->w1, m->q);
    /* released at t = 0: M a = -K q = -f */
    for (size_t i = 0; i < n; i++)
        m->w1[i] = -m->w1[i];
    cbm__dyn_factor(&m->d, 0.0, 1.0);
    cbm__dyn_solve(&m->d, m->w1, m->a);
    memset(m->v, 0, n * sizeof(double));
    m->t = 0.0;
    return refactor(m);
}

cbm_status cbm_motion_add_force(cbm_motion *m, size_t seg, cbm_vec3 force)
{
    if (!m || seg >= m->d.n || !v3_isfinite(force))
        return CBM_E_INVALID;
    if (m->modal)
        return cbm__modal_add_force(m, seg, force);
    cbm__dyn_point_force(&m->d, seg, force, m->f);
    m->forced = true;
    return CBM_OK;
}

/* The fictitious force of the base's acceleration a in its frame: -m a at every mass, that is the
 * wrench -P_k (0, a) of every body (P_k its spatial inertia about the origin). */
static void base_force(cbm_motion *m, cbm_vec3 a, double *f)
{
    size_t n = m->d.n;
    double av[3] = {a.x, a.y, a.z};
    for (size_t k = 0; k < n; k++) {
        const double *pb = m->d.body + 36 * k;
        double *w = m->wb + 6 * k;
        for (int i = 0; i < 6; i++)
            w[i] = -(pb[6 * i + 3] * av[0] + pb[6 * i + 4] * av[1] + pb[6 * i + 5] * av[2]);
    }
    cbm__dyn_wrench_force(&m->d, m->wb, f);
}

static double max_abs_diff(const double *a, const double *b, size_t n, double *scale)
{
    double d = 0.0, s = 0.0;
    for (size_t i = 0; i < n; i++) {
        double x = fabs(a[i] - b[i]), y = fabs(b[i]);
        d = x > d ? x : d;
        s = y > s ? y : s;
    }
    *scale = s;
    return d;
}

/* Drag makes the step's equation nonlinear in the new velocity: M a1 + C v1 + K q1 = f(t1) +
 * g(t1, v1). It is solved by fixed-point iteration on g: predict v1 = v0 + dt a0, evaluate g,
 * solve the linear Newmark step (the factorised K_eff), take v1 from it, re-evaluate g, until g
 * changes by less than 1e-10 of its size. The map contracts with the factor (dg/dv) dt / (2 m),
 * about rho C_d D |w| dt / (2 m') per length (1e-2 for a 2 mm twig in a 30 m/s wind at dt =
 * 1 ms): a few iterations, each one tree solve and two sweeps. */
#define DRAG_TOL      1e-10
#define DRAG_MAX_ITER 100

cbm_status cbm_motion_step(cbm_motion *m)
{
    if (!m)
        return CBM_E_INVALID;
    if (m->modal)
        return cbm__modal_step(m);
    size_t n = m->nq;
    double dt = m->dt, c0 = 4.0 / (dt * dt), c1 = 4.0 / dt;
    double a0 = c0 + 2.0 * m->alpha / dt, a1 = c1 + m->alpha;
    if (!m->wind && !m->base_moves) {
        if (!m->zw_valid)
            rhs_twists(m, a0, a1);
        bool finite = fused_step(m, a0, a1, c0, c1);
        m->t += dt;
        if (!finite)
            return cbm__fail(m->d.ctx, CBM_E_NONFINITE, "motion: non-finite state at t = %g s",
                             m->t);
        return CBM_OK;
    }
    m->zw_valid = false;
    for (size_t i = 0; i < n; i++) {
        m->w1[i] = a0 * m->q[i] + a1 * m->v[i] + m->a[i];
        m->w2[i] = m->beta * (2.0 / dt * m->q[i] + m->v[i]);
    }
    cbm__dyn_apply(&m->d, 0.0, 1.0, m->w1, m->y);
    for (size_t i = 0; i < n; i++)
        m->f[i] += m->y[i];
    if (m->beta > 0.0) {
        cbm__dyn_apply(&m->d, 1.0, 0.0, m->w2, m->y);
        for (size_t i = 0; i < n; i++)
            m->f[i] += m->y[i];
    }
    /* the base: trapezoidal rule as for q (Newmark's average acceleration) */
    cbm_vec3 ba1 = m->ba_next, bv1 = m->bv, bd1 = m->bd;
    if (m->base_moves) {
        base_force(m, ba1, m->f);
        bv1 = v3_add(m->bv, v3_scale(v3_add(m->ba, ba1), 0.5 * dt));
        bd1 = v3_add(v3_madd(m->bd, m->bv, dt), v3_scale(v3_add(m->ba, ba1), 0.25 * dt * dt));
    }
    /* f now holds the right-hand side; the new q into w1 */
    m->iters = 0;
    if (!m->wind)
        cbm__dyn_solve(&m->d, m->f, m->w1);
    else {
        double t1 = m->t + dt;
        for (size_t i = 0; i < n; i++)
            m->y[i] = m->v[i] + dt * m->a[i];
        cbm__drag_force(&m->drag, &m->d, t1, m->y, bv1, m->g);
        bool done = false;
        while (!done && m->iters < DRAG_MAX_ITER) {
            m->iters++;
            for (size_t i = 0; i < n; i++)
                m->rhs[i] = m->f[i] + m->g[i];
            cbm__dyn_solve(&m->d, m->rhs, m->w1);
            for (size_t i = 0; i < n; i++)
                m->y[i] = 2.0 / dt * (m->w1[i] - m->q[i]) - m->v[i];
            cbm__drag_force(&m->drag, &m->d, t1, m->y, bv1, m->g2);
            double scale, diff = max_abs_diff(m->g, m->g2, n, &scale);
            double *sw = m->g;
            m->g = m->g2;
            m->g2 = sw;
            done = diff <= DRAG_TOL * scale || !(scale > 0.0);
            if (!isfinite(diff))
                break;
        }
        if (!done)
            return cbm__fail(m->d.ctx, CBM_E_NOT_CONVERGED,
                             "motion: the drag iteration did not converge at t = %g s (the "
                             "wind's damping is too strong for dt = %g s: reduce dt)",
                             t1, dt);
    }
    bool finite = true;
    for (size_t i = 0; i < n; i++) {
        double qn = m->w1[i];
        double an = c0 * (qn - m->q[i]) - c1 * m->v[i] - m->a[i];
        m->v[i] += 0.5 * dt * (m->a[i] + an);
        m->a[i] = an;
        m->q[i] = qn;
        m->f[i] = 0.0;
        finite = finite && isfinite(qn);
    }
    m->forced = false;
    m->ba = ba1;
    m->bv = bv1;
    m->bd = bd1;
    m->ba_next = v3(0, 0, 0);
    m->t += dt;
    if (!finite)
        return cbm__fail(m->d.ctx, CBM_E_NONFINITE, "motion: non-finite state at t = %g s", m->t);
    return CBM_OK;
}

cbm_status cbm_motion_set_wind(cbm_motion *m, const cbm_wind_def *wind, double u_ref,
                               const cbm_gust_def *gust)
{
    if (!m || !wind)
        return CBM_E_INVALID;
    cbm__drag nd;
    CBM_TRY(cbm__drag_build(&m->d, wind, u_ref, gust, &nd));
    if (m->modal) {
        cbm_status st = cbm__modal_set_wind(m, &nd);
        cbm__drag_free(m->d.ctx, &m->drag);
        m->drag = nd;
        m->wind = true;
        return st;
    }
    size_t n = m->nq;
    /* keep the acceleration consistent with the new load: a += M^-1 (g_new - g_old) */
    if (m->wind)
        cbm__drag_force(&m->drag, &m->d, m->t, m->v, m->bv, m->g2);
    else
        memset(m->g2, 0, n * sizeof(double));
    cbm__drag_force(&nd, &m->d, m->t, m->v, m->bv, m->g);
    cbm__drag_free(m->d.ctx, &m->drag);
    m->drag = nd;
    m->wind = true;
    for (size_t i = 0; i < n; i++)
        m->rhs[i] = m->g[i] - m->g2[i];
    cbm__dyn_factor(&m->d, 0.0, 1.0);
    cbm__dyn_solve(&m->d, m->rhs, m->y);
    for (size_t i = 0; i < n; i++)
        m->a[i] += m->y[i];
    return refactor(m);
}

double cbm_motion_wind_at(const cbm_motion *m, double t)
{
    if (!m || !m->wind)
        return 0.0;
    return m->drag.u_ref + (m->drag.gust.n > 0 ? cbm__gust_at(&m->drag.gust, t) : 0.0);
}

cbm_status cbm_motion_start_wind_static(cbm_motion *m)
{
    if (!m)
        return CBM_E_INVALID;
    if (!m->wind)
        return cbm__fail(m->d.ctx, CBM_E_INVALID, "motion: no wind set to start from");
    if (m->modal)
        return cbm__modal_start_wind_static(m);
    size_t n = m->nq;
    memset(m->v, 0, n * sizeof(double));
    m->bv = m->ba = m->bd = v3(0, 0, 0);
    int32_t ng = m->drag.gust.n;
    m->drag.gust.n = 0; /* the mean wind */
    cbm__drag_force(&m->drag, &m->d, 0.0, m->v, m->bv, m->g2);
    m->drag.gust.n = ng;
    cbm__drag_force(&m->drag, &m->d, 0.0, m->v, m->bv, m->g);
    size_t r = cbm__dyn_factor(&m->d, 1.0, 0.0);
    if (r != 0) {
        refactor(m);
        return cbm__fail(m->d.ctx, CBM_E_RUNTIME,
                         "motion: the equilibrium is unstable, no static deflection");
    }
    cbm__dyn_solve(&m->d, m->g2, m->q);
    /* at rest in the mean wind's deflection: M a = g(0) - K q = g(0) - g_mean */
    for (size_t i = 0; i < n; i++)
        m->rhs[i] = m->g[i] - m->g2[i];
    cbm__dyn_factor(&m->d, 0.0, 1.0);
    cbm__dyn_solve(&m->d, m->rhs, m->a);
    m->t = 0.0;
    return refactor(m);
}

cbm_status cbm_motion_start_state(cbm_motion *m, const double *q, const double *v)
{
    if (!m)
        return CBM_E_INVALID;
    if (m->modal)
        return cbm__modal_start_state(m, q, v);
    size_t n = m->nq;
    for (size_t i = 0; i < n; i++) {
        m->q[i] = q ? q[i] : 0.0;
        m->v[i] = v ? v[i] : 0.0;
        if (!isfinite(m->q[i]) || !isfinite(m->v[i]))
            return cbm__fail(m->d.ctx, CBM_E_INVALID, "motion: start state %zu not finite", i);
    }
    m->bv = m->ba = m->bd = m->ba_next = v3(0, 0, 0);
    m->t = 0.0;
    /* M a = g(0, v) - K q - C v, C = alpha M + beta K */
    if (m->wind)
        cbm__drag_force(&m->drag, &m->d, 0.0, m->v, m->bv, m->rhs);
    else
        memset(m->rhs, 0, n * sizeof(double));
    for (size_t i = 0; i < n; i++)
        m->w2[i] = m->q[i] + m->beta * m->v[i];
    cbm__dyn_apply(&m->d, 1.0, 0.0, m->w2, m->y);
    for (size_t i = 0; i < n; i++)
        m->rhs[i] -= m->y[i];
    cbm__dyn_apply(&m->d, 0.0, m->alpha, m->v, m->y);
    for (size_t i = 0; i < n; i++)
        m->rhs[i] -= m->y[i];
    cbm__dyn_factor(&m->d, 0.0, 1.0);
    cbm__dyn_solve(&m->d, m->rhs, m->a);
    return refactor(m);
}

cbm_status cbm_motion_base_acceleration(cbm_motion *m, cbm_vec3 acc)
{
    if (!m || !v3_isfinite(acc))
        return CBM_E_INVALID;
    m->ba_next = acc;
    m->base_moves = true;
    return CBM_OK;
}

cbm_vec3 cbm_motion_base_displacement(const cbm_motion *m)
{
    return m ? m->bd : v3(0, 0, 0);
}

int cbm_motion_drag_iterations(const cbm_motion *m)
{
    return m ? m->iters : 0;
}

void cbm_motion_state(cbm_motion *m, double *t, double *kinetic, double *potential)
{
    if (!m)
        return;
    size_t n = m->nq;
    if (t)
        *t = m->t;
    if (m->modal) {
        cbm__modal_energies(m, kinetic, potential);
        return;
    }
    if (kinetic) {
        cbm__dyn_apply(&m->d, 0.0, 1.0, m->v, m->y);
        double s = 0.0;
        for (size_t i = 0; i < n; i++)
            s += m->v[i] * m->y[i];
        *kinetic = 0.5 * s;
    }
    if (potential) {
        cbm__dyn_apply(&m->d, 1.0, 0.0, m->q, m->y);
        double s = 0.0;
        for (size_t i = 0; i < n; i++)
            s += m->q[i] * m->y[i];
        *potential = 0.5 * s;
    }
}

cbm_status cbm_motion_displacement(const cbm_motion *m, size_t seg, cbm_vec3 *out)
{
    if (!m || !out || seg >= m->d.n)
        return CBM_E_INVALID;
    *out = m->modal ? cbm__modal_displacement(m, seg) : cbm__dyn_node_disp(&m->d, m->q, seg);
    return CBM_OK;
}

const double *cbm_motion_rotations(const cbm_motion *m)
{
    if (m && m->modal) /* rebuilt on demand from the modal coordinates (a cache: not a change
                        * of the motion's state) */
        return cbm__modal_rotations(m);
    return m ? m->q : NULL;
}

size_t cbm_motion_modes(const cbm_motion *m, const double **freqs_hz)
{
    if (freqs_hz)
        *freqs_hz = m && m->modal ? m->modal->fhz : NULL;
    return m && m->modal ? m->modal->k : 0;
}

double cbm_motion_dt(const cbm_motion *m)
{
    return m ? m->dt : 0.0;
}
