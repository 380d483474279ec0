/* The skies of the light pass as sets of directional sources (docs/light.md).
 *
 * UOC and SOC (the CIE uniform overcast sky, radiance L ∝ 1, and standard overcast sky,
 * L(θ) ∝ (1 + 2 cos θ)/3, θ the zenith angle; Moon and Spencer 1942) are cut into `rings`
 * equal bands of zenith angle and `azimuths` equal sectors per band (every other band turned by
 * half a sector, so the sources do not line up in meridians). A sector becomes one source whose
 * vector is the sector's radiance-weighted vector integral V = ∫ L(d) d dΩ: direction V/|V|,
 * irradiance |V|. A surface of normal n that sees the whole sector then receives n·V from it,
 * exactly; the only discretisation error is in the sectors a tilted leaf's horizon cuts. The
 * integrals in θ are 8-point Gauss-Legendre per band (the integrands are smooth; error far
 * below 1e-12), those in azimuth closed-form.
 *
 * DOME and FIELD are the skies of Oberländer (2020, §5.5.1-2), whose numbers the thesis does not
 * give [reconstruction, docs/light.md]: one zenith light and `rings` rings of `azimuths` lights
 * at the centres of equal zenith-angle bands, each light's irradiance its cell's solid angle
 * times L(θ) = (1 + cos θ)/2 (the zenith lights "slightly stronger": twice the horizon's).
 * They are point-like directional lights, not sector integrals; the two skies share the
 * directions and differ in where the light enters (src/light/light.c).
 *
 * The sun (direct_fraction f > 0) is one more source. All diffuse sources are scaled so that
 * their horizontal irradiance Σ E_k d_k.y is 1 - f, the sun's so that its is f: a horizontal
 * unshaded leaf receives exactly 1 in every sky. */
#include "light_internal.h"

#include "../core/vecmath.h"

#include <math.h>

static double radiance(cbm_sky_kind sky, double theta)
{
    switch (sky) {
    case CBM_SKY_SOC:
        return (1.0 + 2.0 * cos(theta)) / 3.0;
    case CBM_SKY_DOME:
    case CBM_SKY_FIELD:
        return 0.5 * (1.0 + cos(theta));
    case CBM_SKY_UOC:
    default:
        return 1.0;
    }
}

/* ∫_{t0}^{t1} L(θ) sin²θ dθ and ∫ L(θ) cosθ sinθ dθ, 8-point Gauss-Legendre */
static void band_integrals(cbm_sky_kind sky, double t0, double t1, double *a, double *b)
{
    static const double x[4] = {0.1834346424956498, 0.5255324099163290, 0.7966664774136267,
                                0.9602898564975363};
    static const double w[4] = {0.3626837833783620, 0.3137066458778873, 0.2223810344533745,
                                0.1012285362903763};
    double c = 0.5 * (t0 + t1), h = 0.5 * (t1 - t0);
    *a = *b = 0.0;
    for (int k = 0; k < 4; k++)
        for (int s = -1; s <= 1; s += 2) {
            double t = c + s * h * x[k], l = radiance(sky, t) * w[k] * h;
            *a += l * sin(t) * sin(t);
            *b += l * cos(t) * sin(t);
        }
}

size_t cbm__light_source_count(const cbm_light_def *d)
{
    size_t n = (size_t)d->rings * (size_t)d->azimuths;
    if (d->sky == CBM_SKY_DOME || d->sky == CBM_SKY_FIELD)
        n += 1;
    if (d->direct_fraction >= 1.0)
        n = 0; /* the sun alone */
    if (d->direct_fraction > 0)
        n += 1;
    return n;
}

void cbm__light_fill_sources(const cbm_light_def *d, cbm_light_source *out)
{
    size_t n = 0;
    const double half_pi = 0.5 * CBM_PI;
    if (d->direct_fraction >= 1.0) {
        /* the sun alone */
    } else if (d->sky == CBM_SKY_UOC || d->sky == CBM_SKY_SOC) {
        double dt = half_pi / d->rings, dp = 2.0 * CBM_PI / d->azimuths;
        for (int i = 0; i < d->rings; i++) {
            double a, b;
            band_integrals(d->sky, i * dt, (i + 1) * dt, &a, &b);
            double shift = (i % 2) ? 0.5 * dp : 0.0;
            for (int j = 0; j < d->azimuths; j++) {
                double p0 = j * dp + shift, p1 = p0 + dp;
                cbm_vec3 v = v3(a * (sin(p1) - sin(p0)), b * dp, a * (cos(p0) - cos(p1)));
                double e = v3_norm(v);
                out[n].dir = v3_scale(v, 1.0 / e);
                out[n].irradiance = e;
                n++;
            }
        }
    } else {
        /* a zenith cap of half a band, then `rings` bands centred on i * dt */
        double dt = half_pi / (d->rings + 0.5), dp = 2.0 * CBM_PI / d->azimuths;
        double cap = 2.0 * CBM_PI * (1.0 - cos(0.5 * dt));
        out[n].dir = v3(0, 1, 0);
        out[n].irradiance = cap * radiance(d->sky, 0.0);
        n++;
        for (int i = 1; i <= d->rings; i++) {
            double t = i * dt, t0 = t - 0.5 * dt, t1 = fmin(t + 0.5 * dt, half_pi);
            double omega = dp * (cos(t0) - cos(t1));
            double shift = (i % 2) ? 0.5 * dp : 0.0;
            for (int j = 0; j < d->azimuths; j++) {
                double p = (j + 0.5) * dp + shift;
                out[n].dir = v3(sin(t) * cos(p), cos(t), sin(t) * sin(p));
                out[n].irradiance = omega * radiance(d->sky, t);
                n++;
            }
        }
    }
    /* normalise the diffuse part's horizontal irradiance to 1 - f */
    double f = d->direct_fraction, h = 0.0;
    for (size_t k = 0; k < n; k++)
        h += out[k].irradiance * out[k].dir.y;
    for (size_t k = 0; k < n; k++)
        out[k].irradiance *= (1.0 - f) / h; /* n == 0 when f == 1 */
    if (f > 0) {
        cbm_vec3 s = v3_normalize(d->sun);
        out[n].dir = s;
        out[n].irradiance = f / s.y;
        n++;
    }
    CBM_ASSERT(n == cbm__light_source_count(d));
}
