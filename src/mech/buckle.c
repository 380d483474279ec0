/* Self-weight buckling of a vertical column (Taylor-Hell 2005 §6.3, Table 6.1; Greenhill 1881).
 *
 * Protocol (§6.3): a perfectly vertical column clamped at its base is grown segment by segment;
 * each segment is given a small rotation rate (a lateral push) and the relaxation is run; the
 * buckling length is the first length at which the column does not return upright.
 *
 * Here the push is infinitesimal, which makes the protocol exact and cheap. Around the straight
 * equilibrium the relaxation with alpha = 1 (Taylor-Hell 6.24) maps a perturbation dOmega to
 * K dOmega with K = C^-1 dM/dOmega (the moment of the self-weight about each joint changes as
 * the frames above it rotate; dM/dOmega is the solver's own tangent, cbm__mech_jvp, exact for
 * the discrete model). The perturbation dies out, i.e. the column returns upright, iff the
 * largest eigenvalue lambda of K is below 1 (for alpha < 1 the factor is 1 - alpha + alpha
 * lambda: the same test). Iterating the relaxation from the push is the power iteration for
 * lambda: each pass multiplies the perturbation by K, and the ratio of successive norms
 * converges to lambda at the rate of lambda_2 / lambda_1 (about 0.14 for the self-weighted
 * column, whose critical loads are 7.837, 55.98, ... EI / L^3). The loads are conservative, so
 * the eigenvalues are real; the push has a component along every bending mode. The factor
 * grows with length, so the first failing segment count is found by doubling and bisection
 * instead of trying every count; the continuous critical length for n segments by bisection on
 * the length.
 *
 * Greenhill: a uniform vertical column of weight q per length buckles under its own weight at
 * q L^3 / (E I) = 7.8373 (the first zero of J_{-1/3}: (9/4) j^2 with j = 1.8663), so
 * L_cr = (7.837 E I / q)^(1/3), q = rho pi r^2 g, I = pi r^4 / 4.
 */
#include "mech/growth_internal.h"
#include "core/vecmath.h"

#include <math.h>

#define GREENHILL 7.837

cbm_buckle_def cbm_buckle_def_default(void)
{
    cbm_buckle_def d;
    memset(&d, 0, sizeof d);
    d.youngs_modulus = 10e9;
    d.density = 600.0;
    d.radius = 0.05;
    d.segment = 0.1;
    d.gravity = 9.81;
    d.max_segments = 100000;
    d.discretization = CBM_MECH_STAGGERED;
    return d;
}

cbm_status cbm_plant_stability_factor(cbm_plant *p, double *factor, size_t *passes)
{
    if (factor)
        *factor = NAN;
    if (passes)
        *passes = 0;
    if (!p || !factor)
        return CBM_E_INVALID;
    CBM_TRY(cbm_plant_evaluate(p, NULL));
    size_t n = p->n;
    cbm_vec3 *v = cbm__alloc(p->ctx, 2 * n * sizeof *v);
    if (!v)
        return CBM_E_NOMEM;
    cbm_vec3 *kv = v + n;
    /* the push: the same small rotation rate on every segment, in both bending directions and in
     * twist; only directions matter (the problem is linear) */
    for (size_t i = 0; i < n; i++)
        v[i] = v3(0.25, 1.0, 0.5);
    size_t lim = cbm_context_limits(p->ctx)->max_passes;
    size_t maxit = lim && lim < 2000 ? lim : 2000;
    double lam = 0.0, prev = -1.0;
    size_t it = 0;
    cbm_status s = CBM_E_NOT_CONVERGED;
    const cbm_vec3 *cj = p->work.cj;
    for (it = 1; it <= maxit; it++) {
        cbm__mech_jvp(p, v, kv);
        double nv = 0.0, nk = 0.0;
        for (size_t i = 0; i < n; i++) {
            /* J v = C v - dM v, so K v = C^-1 dM v = v - C^-1 J v */
            kv[i] = v3(v[i].x - kv[i].x / cj[i].x, v[i].y - kv[i].y / cj[i].y,
                       v[i].z - kv[i].z / cj[i].z);
            nv += v3_norm2(v[i]);
            nk += v3_norm2(kv[i]);
        }
        if (!isfinite(nk)) {
            s = cbm__fail(p->ctx, CBM_E_NONFINITE, "stability: perturbation is not finite");
            break;
        }
        if (nk == 0.0) {
            lam = 0.0;
            s = CBM_OK;
            break;
        }
        lam = sqrt(nk / nv);
        double sc = 1.0 / sqrt(nk);
        for (size_t i = 0; i < n; i++)
            v[i] = v3_scale(kv[i], sc);
        /* the decision is lambda against 1: settle to 1e-12 of max(lambda, 1) */
        if (fabs(lam - prev) <= 1e-12 * (lam > 1.0 ? lam : 1.0) && it > 2) {
            s = CBM_OK;
            break;
        }
        prev = lam;
    }
    cbm__free(p->ctx, v, 2 * n * sizeof *v);
    if (passes)
        *passes = it < maxit ? it : maxit;
    if (s == CBM_E_NOT_CONVERGED)
        return cbm__fail(p->ctx, s, "stability: power iteration did not settle in %zu passes",
                         maxit);
    if (s == CBM_OK)
        *factor = lam;
    return s;
}

static cbm_status check_def(cbm_context *ctx, const cbm_buckle_def *d)
{
    const char *bad = NULL;
    if (!(isfinite(d->youngs_modulus) && d->youngs_modulus > 0.0))
        bad = "E must be positive";
    else if (!(isfinite(d->shear_modulus) && d->shear_modulus >= 0.0))
        bad = "G must be >= 0";
    else if (!(isfinite(d->density) && d->density > 0.0))
        bad = "density must be positive";
    else if (!(isfinite(d->radius) && d->radius > 0.0))
        bad = "radius must be positive";
    else if (!(isfinite(d->segment) && d->segment > 0.0))
        bad = "segment length must be positive";
    else if (!(isfinite(d->gravity) && d->gravity > 0.0))
        bad = "gravity must be positive";
    if (bad)
        return cbm__fail(ctx, CBM_E_INVALID, "buckle: %s", bad);
    return CBM_OK;
}

/* A straight vertical column of n segments of length h. */
static cbm_status column(cbm_context *ctx, const cbm_buckle_def *d, size_t n, double h,
                         cbm_plant **out)
{
    cbm_plant_def pd = cbm_plant_def_default();
    pd.gravity = v3(0.0, -d->gravity, 0.0);
    pd.base_orientation = cbm_mech_clamp_orientation(0.5 * CBM_PI);
    pd.discretization = d->discretization;
    pd.capacity = n;
    CBM_TRY(cbm_plant_create(ctx, &pd, out));
    cbm_segment_def sd = cbm_segment_def_default();
    sd.length = h;
    sd.core.youngs_modulus = d->youngs_modulus;
    sd.core.shear_modulus = d->shear_modulus > 0.0 ? d->shear_modulus : d->youngs_modulus / 16.0;
    sd.core.density = d->density;
    sd.core.a = sd.core.b = d->radius;
    for (size_t i = 0; i < n; i++) {
        sd.parent = (int64_t)i - 1;
        cbm_status s = cbm_plant_add_segment(*out, &sd, NULL);
        if (s != CBM_OK) {
            cbm_plant_destroy(*out);
            *out = NULL;
            return s;
        }
    }
    return CBM_OK;
}

static cbm_status column_factor(cbm_context *ctx, const cbm_buckle_def *d, size_t n, double *f,
                                size_t *passes)
{
    cbm_plant *p = NULL;
    CBM_TRY(column(ctx, d, n, d->segment, &p));
    size_t np = 0;
    cbm_status s = cbm_plant_stability_factor(p, f, &np);
    *passes += np;
    cbm_plant_destroy(p);
    return s;
}

static double greenhill(const cbm_buckle_def *d)
{
    double q = d->density * CBM_PI * d->radius * d->radius * d->gravity;
    double ei = d->youngs_modulus * CBM_PI * pow(d->radius, 4) / 4.0;
    return cbrt(GREENHILL * ei / q);
}

cbm_status cbm_mech_buckle(cbm_context *ctx, const cbm_buckle_def *def, cbm_buckle_result *out)
{
    if (!ctx || !def || !out)
        return CBM_E_INVALID;
    memset(out, 0, sizeof *out);
    CBM_TRY(check_def(ctx, def));
    out->greenhill_length = greenhill(def);
    size_t maxn = def->max_segments ? def->max_segments : 100000;
    size_t lim = cbm_context_limits(ctx)->max_segments;
    if (lim && maxn > lim)
        maxn = lim;
    /* lo stands (factor < 1), hi falls; start the doubling at one segment */
    size_t lo = 0, hi = 1;
    double flo = 0.0, fhi = 0.0;
    for (;;) {
        CBM_TRY(column_factor(ctx, def, hi, &fhi, &out->passes));
        if (fhi >= 1.0)
            break;
        lo = hi;
        flo = fhi;
        if (hi >= maxn)
            return cbm__fail(ctx, CBM_E_LIMIT,
                             "buckle: the column still stands at %zu segments (%.6g m)", hi,
                             (double)hi * def->segment);
        hi = 2 * hi < maxn ? 2 * hi : maxn;
    }
    while (hi - lo > 1) {
        size_t mid = lo + (hi - lo) / 2;
        double fm;
        CBM_TRY(column_factor(ctx, def, mid, &fm, &out->passes));
        if (fm >= 1.0) {
            hi = mid;
            fhi = fm;
        } else {
            lo = mid;
            flo = fm;
        }
    }
    out->segments = hi;
    out->buckling_length = (double)hi * def->segment;
    out->growth_factor = fhi;
    out->last_stable_factor = flo;
    return CBM_OK;
}

cbm_status cbm_mech_buckle_length(cbm_context *ctx, const cbm_buckle_def *def, size_t n,
                                  double rel_tol, double *length)
{
    if (!ctx || !def || !length || n == 0)
        return CBM_E_INVALID;
    *length = NAN;
    CBM_TRY(check_def(ctx, def));
    if (!(rel_tol > 0.0 && rel_tol < 0.1))
        return cbm__fail(ctx, CBM_E_INVALID, "buckle: relative tolerance must be in (0, 0.1)");
    double l0 = greenhill(def);
    cbm_plant *p = NULL;
    CBM_TRY(column(ctx, def, n, l0 / (double)n, &p));
    double lo = 0.0, hi = 0.0, L = l0;
    cbm_status s = CBM_OK;
    /* bracket the critical length, then bisect on it */
    for (int k = 0; k < 200 && s == CBM_OK; k++) {
        double f;
        for (size_t i = 0; i < n && s == CBM_OK; i++)
            s = cbm_plant_set_length(p, i, L / (double)n);
        if (s == CBM_OK)
            s = cbm_plant_stability_factor(p, &f, NULL);
        if (s != CBM_OK)
            break;
        if (f >= 1.0)
            hi = L;
        else
            lo = L;
        if (hi == 0.0)
            L *= 1.5;
        else if (lo == 0.0)
            L /= 1.5;
        else if (hi - lo <= rel_tol * hi)
            break;
        else
            L = 0.5 * (lo + hi);
    }
    cbm_plant_destroy(p);
    CBM_TRY(s);
    if (!(lo > 0.0 && hi > 0.0 && hi - lo <= rel_tol * hi))
        return cbm__fail(ctx, CBM_E_NOT_CONVERGED, "buckle: bisection did not bracket the length");
    *length = 0.5 * (lo + hi);
    return CBM_OK;
}
