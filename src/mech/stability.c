/* Stability of an equilibrium of the discrete plant: the number of unstable modes and the
 * lowest eigenvalue of the tangent stiffness (docs/bend.md, "Stability"; docs/validation.md).
 *
 * The equilibrium R(Omega) = C (Omega - rest) - M_local(Omega) = 0 (solve_common.c) is, for
 * dead loads, the stationarity of the total potential energy
 *     V = sum_i d_i (Omega_i - rest_i) . C_i (Omega_i - rest_i) / 2 - sum of F . x (dead forces)
 * up to the right Jacobian of each joint rotation: grad V = D (R + O(d |Omega| |M|)) with D the
 * joints' dual lengths, exactly so for bending about a fixed axis (a planar rod). Its Hessian at
 * the equilibrium is then D J, J = dR/dOmega the solvers' tangent, and the equilibrium is stable
 * iff D J is positive definite. The tree factorisation (solve_tree.c) is a block elimination of
 * J from the tips; scaling the rows of joint i by d_i > 0 scales its pivot block by d_i, so the
 * pivots of D J are d_i D_i and, D J symmetric, its inertia is the sum of the inertias of the
 * symmetric 3x3 pivots (Sylvester's law of inertia: block LDL^T is a congruence). That count,
 * work.fneg, costs nothing beyond the factorisation the fast solver does anyway; it is the exact
 * number of unstable modes where D J is symmetric (checked against a dense eigen-decomposition
 * in tests/test_mech_stability.c) and an O(d |Omega|) reading of it otherwise.
 *
 * The lowest eigenvalue of the generalised problem J v = lambda S v (S = diag C, so lambda = 1
 * for an unloaded plant, 0 at a buckling load, < 0 unstable) comes from shifted inverse
 * iteration with the same O(n) factorisation: mu >= 0 is raised until every pivot of J + mu S is
 * positive definite, then v <- (J + mu S)^-1 S v converges to the eigenvalue of J + mu S nearest
 * 0, i.e. lambda_min + mu, at the rate (lambda_1 + mu) / (lambda_2 + mu). Its eigenvector is the
 * direction the fast solver pushes an unstable equilibrium along (solve_newton.c, stage
 * "stability"). For an unsymmetric tangent it is the real eigenvalue of S^-1 J that decides
 * whether the overdamped motion C dOmega/dt = -R leaves the equilibrium.
 */
#include "mech/mech_internal.h"
#include "core/vecmath.h"

#include <math.h>

double cbm__mech_energy(const cbm_plant *p)
{
    const cbm__mech_work *w = &p->work;
    double e = 0.0;
    for (size_t k = 0; k < p->n; k++) { /* the sum in the plant's order (solve_order.c) */
        size_t i = cbm__mech_at(p, k);
        cbm_vec3 dv = v3_sub(p->omega[i], w->rj[i]);
        cbm_vec3 c = w->cj[i];
        e += 0.5 * w->dual[i] * (c.x * dv.x * dv.x + c.y * dv.y * dv.y + c.z * dv.z * dv.z);
        cbm_vec3 h = q_h(p->q[i]);
        cbm_vec3 xc = v3_add(p->pos[i], v3_scale(h, w->lever[i]));
        cbm_vec3 xd = v3_add(p->pos[i], v3_scale(h, p->len[i]));
        e -= v3_dot(w->wown[i], xc) + v3_dot(w->ftip[i], xd);
        if (p->ground) {
            /* the penalty's potential: its force k d^2 / (2 s), then k (d - s/2) */
            double depth = p->ground_y - xd.y, s = p->ground_s, kg = p->ground_k * p->load_scale;
            if (depth > 0.0)
                e += depth < s ? kg * depth * depth * depth / (6.0 * s)
                               : kg * (0.5 * depth * depth - 0.5 * s * depth + s * s / 6.0);
        }
    }
    return e;
}

double cbm__mech_mode_turn(cbm_plant *p, const cbm_vec3 *v)
{
    cbm__mech_jvp(p, v, p->work.tmp);
    double t = 0.0;
    for (size_t i = 0; i < p->n; i++)
        t = fmax(t, v3_norm2(p->work.dth[i]));
    return sqrt(t);
}

double cbm__mech_sdot(const cbm_plant *p, const cbm_vec3 *a, const cbm_vec3 *b)
{
    const cbm_vec3 *c = p->work.cj;
    double s = 0.0;
    for (size_t k = 0; k < p->n; k++) { /* the sum in the plant's order (solve_order.c) */
        size_t i = cbm__mech_at(p, k);
        s += c[i].x * a[i].x * b[i].x + c[i].y * a[i].y * b[i].y + c[i].z * a[i].z * b[i].z;
    }
    return s;
}

void cbm__mech_deflate(const cbm_plant *p, const cbm_vec3 *g, double gg, cbm_vec3 *v)
{
    double f = cbm__mech_sdot(p, g, v) / gg;
    for (size_t i = 0; i < p->n; i++)
        v[i] = v3_sub(v[i], v3_scale(g[i], f));
}

bool cbm__mech_shift_until_definite(cbm_plant *p, double *mu, size_t *passes)
{
    *mu = 0.0;
    for (;;) {
        size_t nonpd = 0;
        size_t sing = cbm__mech_tree_factor(p, *mu, &nonpd);
        ++*passes;
        if (sing == 0 && nonpd == 0)
            return true;
        *mu = *mu < 0.05 ? 0.05 : 2.0 * *mu;
        if (*mu > 1e6)
            return false;
    }
}

size_t cbm__mech_inverse_iteration(cbm_plant *p, const cbm__mech_inverse_def *d, cbm_vec3 *v,
                                   cbm_vec3 *b, cbm_vec3 *x, double *theta, bool *ok)
{
    const cbm__mech_work *w = &p->work;
    const size_t n = p->n;
    size_t passes = 0;
    *theta = NAN;
    *ok = true;
    if (d->g)
        cbm__mech_deflate(p, d->g, d->gg, v);
    double nv = sqrt(cbm__mech_sdot(p, v, v));
    if (!(nv > 0.0))
        return passes;
    for (size_t i = 0; i < n; i++)
        v[i] = v3_scale(v[i], 1.0 / nv);
    for (int it = 0; it < d->max_it; it++) {
        /* x = (J + mu S)^-1 S v */
        for (size_t i = 0; i < n; i++)
            b[i] = v3(w->cj[i].x * v[i].x, w->cj[i].y * v[i].y, w->cj[i].z * v[i].z);
        cbm__mech_tree_apply(p, b, x);
        passes++;
        if (d->g)
            cbm__mech_deflate(p, d->g, d->gg, x);
        /* Rayleigh quotient of the shifted inverse: (x.S x) / (v.S x) = 1 / theta */
        double xs = cbm__mech_sdot(p, x, x), vx = cbm__mech_sdot(p, v, x);
        if (!(xs > 0.0) || !isfinite(xs)) {
            *ok = false;
            return passes;
        }
        double th = vx / xs; /* eigenvalue of S^-1 (J + mu S) */
        double nx = sqrt(xs);
        double change = 0.0;
        for (size_t k = 0; k < n; k++) { /* the sum in the plant's order (solve_order.c) */
            size_t i = cbm__mech_at(p, k);
            cbm_vec3 nvi = v3_scale(x[i], (vx < 0.0 ? -1.0 : 1.0) / nx);
            cbm_vec3 dv = v3_sub(nvi, v[i]);
            change +=
                w->cj[i].x * dv.x * dv.x + w->cj[i].y * dv.y * dv.y + w->cj[i].z * dv.z * dv.z;
            v[i] = nvi;
        }
        bool settled = isfinite(*theta) && fabs(th - *theta) <= 1e-12 * (fabs(th) + d->mu) &&
                       sqrt(change) < 1e-6;
        *theta = th;
        if (settled)
            break;
    }
    return passes;
}

size_t cbm__mech_lowest_mode(cbm_plant *p, cbm_vec3 *mode, double *lambda)
{
    cbm__mech_work *w = &p->work;
    const size_t n = p->n;
    size_t passes = 0;
    *lambda = NAN;
    /* the shift: every pivot of J + mu S positive definite (then J + mu S is, for D J
     * symmetric, and inverse iteration finds the lowest eigenvalue) */
    double mu = 0.0;
    if (!cbm__mech_shift_until_definite(p, &mu, &passes))
        return passes;
    /* start: a fixed, deliberately unequal mix of the components of every joint, S-normalised
     * (deterministic): a degenerate pair of modes (a round column buckles in any plane) then
     * resolves (to 1 %) towards bending about L, the vertical plane of a clamp from
     * cbm_mech_clamp_orientation */
    cbm_vec3 *v = w->tmp, *b = w->step;
    for (size_t i = 0; i < n; i++)
        v[i] = v3(0.01 / w->cj[i].x, 1.0 / w->cj[i].y, 0.01 / w->cj[i].z);
    double theta = NAN;
    bool ok = true;
    cbm__mech_inverse_def d = {.mu = mu, .max_it = 200};
    passes += cbm__mech_inverse_iteration(p, &d, v, b, mode, &theta, &ok);
    if (!ok)
        return passes;
    memcpy(mode, v, n * sizeof *mode);
    *lambda = theta - mu;
    return passes;
}

cbm_status cbm_plant_stability(cbm_plant *p, cbm_stability *out)
{
    if (!p || !out)
        return CBM_E_INVALID;
    memset(out, 0, sizeof *out);
    out->lowest_eigenvalue = NAN;
    if (p->n == 0)
        return cbm__fail(p->ctx, CBM_E_INVALID, "stability: the plant has no segments");
    /* the tree factorisation's arrays come with a Krylov workspace */
    CBM_TRY(cbm__mech_work_reserve(p, p->work.krylov_cap > 1 ? p->work.krylov_cap - 1 : 1));
    double res = 0.0;
    CBM_TRY(cbm_plant_evaluate(p, &res));
    out->residual = res;
    out->energy = cbm__mech_energy(p);
    size_t nonpd = 0;
    cbm__mech_tree_factor(p, 0.0, &nonpd);
    out->unstable_modes = p->work.fneg;
    double lam = NAN;
    out->passes = 1 + cbm__mech_lowest_mode(p, p->work.save, &lam);
    out->lowest_eigenvalue = lam;
    if (!isfinite(lam))
        return cbm__fail(p->ctx, CBM_E_NOT_CONVERGED,
                         "stability: no shift made the tangent positive definite");
    return CBM_OK;
}
