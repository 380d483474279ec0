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

struct cbm_motion {
    cbm__dyn d;
    size_t nq;
    double dt, t, alpha, beta;
    double *q, *v, *a, *f, *w1, *w2, *y;
};

cbm_motion_def cbm_motion_def_default(void)
{
    cbm_motion_def d = {1e-3, 0.0, 0.0, 0.0};
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
    cbm__dyn_free(&m->d);
    cbm__free(ctx, m, sizeof *m);
}

static cbm_status refactor(cbm_motion *m)
{
    double dt = m->dt;
    size_t r =
        cbm__dyn_factor(&m->d, 1.0 + 2.0 * m->beta / dt, 4.0 / (dt * dt) + 2.0 * m->alpha / dt);
    if (r == (size_t)-1)
        return cbm__fail(m->d.ctx, CBM_E_RUNTIME,
                         "motion: the effective stiffness is singular (dt too long for an "
                         "unstable equilibrium)");
    return CBM_OK;
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
    double alpha = md.rayleigh_alpha, beta = md.rayleigh_beta;
    if (md.damping_ratio > 0.0) {
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
    if (!m->q || !m->v || !m->a || !m->f || !m->w1 || !m->w2 || !m->y) {
        cbm_motion_destroy(m);
        return CBM_E_NOMEM;
    }
    st = refactor(m);
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
    cbm__dyn_point_force(&m->d, seg, force, m->f);
    return CBM_OK;
}

cbm_status cbm_motion_step(cbm_motion *m)
{
    if (!m)
        return CBM_E_INVALID;
    size_t n = m->nq;
    double dt = m->dt, c0 = 4.0 / (dt * dt), c1 = 4.0 / dt;
    double a0 = c0 + 2.0 * m->alpha / dt, a1 = c1 + m->alpha;
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
    /* f now holds the right-hand side; the new q into w1 */
    cbm__dyn_solve(&m->d, m->f, m->w1);
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
    m->t += dt;
    if (!finite)
        return cbm__fail(m->d.ctx, CBM_E_NONFINITE, "motion: non-finite state at t = %g s", m->t);
    return CBM_OK;
}

void cbm_motion_state(cbm_motion *m, double *t, double *kinetic, double *potential)
{
    if (!m)
        return;
    size_t n = m->nq;
    if (t)
        *t = m->t;
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
    *out = cbm__dyn_node_disp(&m->d, m->q, seg);
    return CBM_OK;
}

const double *cbm_motion_rotations(const cbm_motion *m)
{
    return m ? m->q : NULL;
}
