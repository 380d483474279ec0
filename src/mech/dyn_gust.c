/* The gust series of the wind in time (issue 11): one longitudinal turbulence component u'(t),
 * the same over the whole plant, synthesised by the spectral representation (Shinozuka):
 * u'(t) = sum_k sqrt(2 S(n_k) dn_k) cos(2 pi n_k t + phase_k), phases uniform from the seeded
 * generator, frequencies n_k at the centres of N log-spaced bins over [f_min, f_max] (log spacing
 * puts harmonics where the spectrum has its energy, at a few hundredths of a hertz, and where the
 * plant responds, a few hertz, with a few hundred terms; incommensurate frequencies keep the series
 * from repeating within a run). The spectrum is the normalised one of EN 1991-1-4, Annex B,
 * n S(n) / sigma^2 = 6.8 f_L / (1 + 10.2 f_L)^(5/3), f_L = n L / U_ref, a von Karman-type
 * spectrum with the -5/3 inertial range, whose integral over all n is exactly sigma^2; its
 * integral over the band, 1 / (1 + 10.2 a)^(2/3) - 1 / (1 + 10.2 b)^(2/3) of sigma^2 with a, b
 * the band's ends in f_L, is what the synthesis reproduces (the tests check it).
 *
 * Why one coherent series and not a field: the energetic gusts are tens of metres long (L ~ 50 m
 * at 10 m height), larger than the crowns cambium grows; the crown-scale decorrelation that a
 * field would add (and that reduces the response of the higher modes) is left out and said so in
 * docs/dynamics.md. */
#include "mech/dyn_internal.h"
#include "mech/mech_internal.h"

#include <math.h>
#include <string.h>

#define TWO_PI 6.283185307179586476925

cbm_gust_def cbm_gust_def_default(void)
{
    cbm_gust_def g;
    memset(&g, 0, sizeof g);
    g.intensity = 0.0;
    g.length_scale = 0.0;
    g.f_min = 0.002;
    g.f_max = 20.0;
    g.harmonics = 400;
    g.seed = 1;
    return g;
}

double cbm__gust_length(const cbm_gust_def *g, const cbm_wind_def *w)
{
    if (g->length_scale > 0.0)
        return g->length_scale;
    /* EN 1991-1-4 (B.1): L(z) = L_t (z / z_t)^alpha, L_t = 300 m, z_t = 200 m,
     * alpha = 0.67 + 0.05 ln z0 (z0 in m), z at least z_min ~ 1 m */
    double z0 = w->profile == CBM_WIND_LOG && w->roughness > 0.0 ? w->roughness : 0.05;
    double z = w->reference_height > 1.0 ? w->reference_height : 1.0;
    return 300.0 * pow(z / 200.0, 0.67 + 0.05 * log(z0));
}

double cbm__gust_spectrum(const cbm_gust_def *g, double sigma, double length, double u_ref,
                          double f)
{
    (void)g;
    double fl = f * length / u_ref;
    return sigma * sigma * 6.8 * (length / u_ref) / pow(1.0 + 10.2 * fl, 5.0 / 3.0);
}

void cbm__gust_free(cbm_context *ctx, cbm__gust *g)
{
    if (!g)
        return;
    size_t b = (size_t)(g->n > 0 ? g->n : 0) * sizeof(double);
    cbm__free(ctx, g->amp, b);
    cbm__free(ctx, g->omega, b);
    cbm__free(ctx, g->phase, b);
    memset(g, 0, sizeof *g);
}

cbm_status cbm__gust_build(cbm_context *ctx, const cbm_gust_def *gd, const cbm_wind_def *w,
                           double u_ref, cbm__gust *out)
{
    memset(out, 0, sizeof *out);
    if (!gd)
        return CBM_OK;
    if (!(gd->intensity >= 0.0) || !isfinite(gd->intensity) || !(gd->length_scale >= 0.0) ||
        !isfinite(gd->length_scale) || !(gd->f_min > 0.0) || !(gd->f_max > gd->f_min) ||
        !isfinite(gd->f_max) || gd->harmonics < 1 || gd->harmonics > 1000000)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "gust: intensity and length_scale must be >= 0, 0 < f_min < f_max and "
                         "harmonics 1..1000000");
    if (gd->intensity == 0.0 || u_ref == 0.0)
        return CBM_OK;
    size_t n = (size_t)gd->harmonics;
    out->amp = cbm__alloc(ctx, n * sizeof(double));
    out->omega = cbm__alloc(ctx, n * sizeof(double));
    out->phase = cbm__alloc(ctx, n * sizeof(double));
    out->n = gd->harmonics;
    if (!out->amp || !out->omega || !out->phase) {
        cbm__gust_free(ctx, out);
        return CBM_E_NOMEM;
    }
    double u = fabs(u_ref), sigma = gd->intensity * u, len = cbm__gust_length(gd, w);
    double span = log(gd->f_max / gd->f_min);
    cbm_rng rng;
    cbm__rng_seed(&rng, gd->seed);
    for (size_t k = 0; k < n; k++) {
        double f = gd->f_min * exp(span * ((double)k + 0.5) / (double)n);
        double df = f * span / (double)n; /* the bin's width, to first order in span / n */
        out->amp[k] = sqrt(2.0 * cbm__gust_spectrum(gd, sigma, len, u, f) * df);
        out->omega[k] = TWO_PI * f;
        out->phase[k] = TWO_PI * cbm__rng_uniform(&rng);
    }
    return CBM_OK;
}

double cbm__gust_at(const cbm__gust *g, double t)
{
    double s = 0.0;
    for (int32_t k = 0; k < g->n; k++)
        s += g->amp[k] * cos(g->omega[k] * t + g->phase[k]);
    return s;
}
