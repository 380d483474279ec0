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
 * One coherent series is the default: the energetic gusts are tens of metres long (L ~ 50 m at
 * 10 m height), larger than the crowns cambium grows. The crown-scale decorrelation of the
 * faster gusts (which lessens the response of the higher modes) is the field below, asked for by
 * a coherence decay a > 0.
 *
 * The field: Veers' method (Veers 1988, Sandia SAND88-0152; Shinozuka & Jan 1972) on a grid of P
 * points in the plane normal to the wind over the plant's extent. At each harmonic frequency f_k
 * the cross-spectral matrix is S(f_k) C(f_k) with Davenport's coherence C_jl = exp(-a f_k r_jl /
 * U_ref) (Davenport 1961; r_jl the points' distance across the wind) and the same point spectrum
 * S everywhere (homogeneous turbulence). With C = L L^T (Cholesky) and independent phases
 * theta_lk, u'_j(t) = sum_k amp_k sum_l L_jl cos(omega_k t + theta_lk) has the point spectrum S
 * at every point and the cross-spectrum S C between points, in the ensemble of phases (Veers).
 * The phases of l = 0 are the series' own: with a -> 0, C -> 1 1^T, L = (1 0 ... 0) and every
 * point carries the uniform series (tested). The segments take the field bilinearly interpolated
 * from the grid's four nearest points (which lowers the variance between points where the grid is
 * coarse against the coherence length U / (a f): the grid should be fine at the frequencies that
 * matter, docs/dynamics.md). Separations along the wind are not decorrelated (projected out). */
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
    g.coherence_decay = 0.0;
    g.grid = 6;
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
    size_t bp = (size_t)(g->np > 0 ? g->np : 0) * sizeof(double);
    cbm__free(ctx, g->are, b / sizeof(double) * bp);
    cbm__free(ctx, g->aim, b / sizeof(double) * bp);
    cbm__free(ctx, g->gv, bp);
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
    if (!(gd->coherence_decay >= 0.0) || !isfinite(gd->coherence_decay) ||
        (gd->coherence_decay > 0.0 && (gd->grid < 2 || gd->grid > 16)))
        return cbm__fail(ctx, CBM_E_INVALID,
                         "gust: coherence_decay must be >= 0 and grid 2..16 with a field");
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

/* The grid's axes: ex horizontal across the wind, ey the vertical with its part along the wind
 * removed (the wind is horizontal in practice: then ey is y). */
static void field_axes(cbm_vec3 dir, cbm_vec3 *ex, cbm_vec3 *ey)
{
    cbm_vec3 up = {0, 1, 0};
    cbm_vec3 lat = {up.y * dir.z - up.z * dir.y, up.z * dir.x - up.x * dir.z,
                    up.x * dir.y - up.y * dir.x};
    double nl = sqrt(lat.x * lat.x + lat.y * lat.y + lat.z * lat.z);
    if (!(nl > 1e-9)) /* a vertical wind: any horizontal axis */
        lat = (cbm_vec3){1, 0, 0}, nl = 1.0;
    *ex = (cbm_vec3){lat.x / nl, lat.y / nl, lat.z / nl};
    double du = up.x * dir.x + up.y * dir.y + up.z * dir.z;
    cbm_vec3 v = {up.x - du * dir.x, up.y - du * dir.y, up.z - du * dir.z};
    double nv = sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    *ey = nv > 1e-9 ? (cbm_vec3){v.x / nv, v.y / nv, v.z / nv}
                    : (cbm_vec3){dir.y * ex->z - dir.z * ex->y, dir.z * ex->x - dir.x * ex->z,
                                 dir.x * ex->y - dir.y * ex->x};
}

static double dot3(cbm_vec3 a, cbm_vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

cbm_status cbm__gust_field_build(cbm_context *ctx, const cbm_gust_def *gd, double u_ref,
                                 cbm_vec3 dir, const cbm_vec3 *pts, size_t npts, cbm__gust *out)
{
    if (!gd || !(gd->coherence_decay > 0.0) || out->n == 0 || npts == 0)
        return CBM_OK;
    field_axes(dir, &out->ex, &out->ey);
    double s0 = INFINITY, s1 = -INFINITY, r0 = INFINITY, r1 = -INFINITY;
    for (size_t i = 0; i < npts; i++) {
        double s = dot3(pts[i], out->ex), r = dot3(pts[i], out->ey);
        s0 = s < s0 ? s : s0, s1 = s > s1 ? s : s1;
        r0 = r < r0 ? r : r0, r1 = r > r1 ? r : r1;
    }
    /* points along the longer side, the same spacing (rounded up) along the other */
    double ext = s1 - s0 > r1 - r0 ? s1 - s0 : r1 - r0;
    double h = ext > 1e-9 ? ext / (gd->grid - 1) : 1.0;
    int32_t nx = s1 - s0 > 1e-9 ? (int32_t)ceil((s1 - s0) / h - 1e-9) + 1 : 1;
    int32_t ny = r1 - r0 > 1e-9 ? (int32_t)ceil((r1 - r0) / h - 1e-9) + 1 : 1;
    out->nx = nx, out->ny = ny;
    out->hx = nx > 1 ? (s1 - s0) / (nx - 1) : 1.0;
    out->hy = ny > 1 ? (r1 - r0) / (ny - 1) : 1.0;
    out->o = (cbm_vec3){s0 * out->ex.x + r0 * out->ey.x, s0 * out->ex.y + r0 * out->ey.y,
                        s0 * out->ex.z + r0 * out->ey.z};
    size_t np = (size_t)nx * (size_t)ny, nk = (size_t)out->n;
    out->np = (int32_t)np;
    out->are = cbm__alloc(ctx, nk * np * sizeof(double));
    out->aim = cbm__alloc(ctx, nk * np * sizeof(double));
    out->gv = cbm__alloc(ctx, np * sizeof(double));
    double *c = cbm__alloc(ctx, (np * np + 2 * np) * sizeof(double));
    if (!out->are || !out->aim || !out->gv || !c) {
        cbm__free(ctx, c, (np * np + 2 * np) * sizeof(double));
        return CBM_E_NOMEM; /* the caller frees out */
    }
    double *cph = c + np * np, *sph = cph + np;
    /* the phases of l >= 1 after the series' own (drawn by cbm__gust_build from the same seed) */
    cbm_rng rng;
    cbm__rng_seed(&rng, gd->seed);
    for (size_t k = 0; k < nk; k++)
        (void)cbm__rng_uniform(&rng);
    double a = gd->coherence_decay / fabs(u_ref);
    for (size_t k = 0; k < nk; k++) {
        double f = out->omega[k] / TWO_PI;
        /* C = L L^T in place (lower triangle), positive semi-definite: a pivot that vanishes
         * against 1 (points coherent to round-off) gives a zero column */
        for (size_t j = 0; j < np; j++) {
            int32_t jx = (int32_t)(j % (size_t)nx), jy = (int32_t)(j / (size_t)nx);
            for (size_t l = 0; l <= j; l++) {
                int32_t lx = (int32_t)(l % (size_t)nx), ly = (int32_t)(l / (size_t)nx);
                double dx = (jx - lx) * out->hx, dy = (jy - ly) * out->hy;
                c[j * np + l] = exp(-a * f * sqrt(dx * dx + dy * dy));
            }
        }
        for (size_t j = 0; j < np; j++) {
            double d = c[j * np + j];
            for (size_t m = 0; m < j; m++)
                d -= c[j * np + m] * c[j * np + m];
            double ljj = d > 1e-12 ? sqrt(d) : 0.0;
            c[j * np + j] = ljj;
            for (size_t i = j + 1; i < np; i++) {
                double v = c[i * np + j];
                for (size_t m = 0; m < j; m++)
                    v -= c[i * np + m] * c[j * np + m];
                c[i * np + j] = ljj > 0.0 ? v / ljj : 0.0;
            }
        }
        for (size_t l = 0; l < np; l++) {
            double th = l == 0 ? out->phase[k] : TWO_PI * cbm__rng_uniform(&rng);
            cph[l] = cos(th), sph[l] = sin(th);
        }
        /* amp_k sum_l L_jl e^(i theta_lk): u'_j = sum_k Re(A_jk e^(i omega_k t)) */
        for (size_t j = 0; j < np; j++) {
            double re = 0.0, im = 0.0;
            for (size_t l = 0; l <= j; l++)
                re += c[j * np + l] * cph[l], im += c[j * np + l] * sph[l];
            out->are[k * np + j] = out->amp[k] * re;
            out->aim[k * np + j] = out->amp[k] * im;
        }
    }
    cbm__free(ctx, c, (np * np + 2 * np) * sizeof(double));
    out->have = false;
    return CBM_OK;
}

const double *cbm__gust_field_at(cbm__gust *g, double t)
{
    if (g->have && g->t_last == t)
        return g->gv;
    size_t np = (size_t)g->np;
    memset(g->gv, 0, np * sizeof(double));
    for (size_t k = 0; k < (size_t)g->n; k++) {
        double co = cos(g->omega[k] * t), si = sin(g->omega[k] * t);
        const double *ar = g->are + k * np, *ai = g->aim + k * np;
        for (size_t j = 0; j < np; j++)
            g->gv[j] += ar[j] * co - ai[j] * si;
    }
    g->t_last = t;
    g->have = true;
    return g->gv;
}

void cbm__gust_field_weights(const cbm__gust *g, cbm_vec3 p, int32_t idx[4], double wt[4])
{
    cbm_vec3 d = {p.x - g->o.x, p.y - g->o.y, p.z - g->o.z};
    double s = g->nx > 1 ? dot3(d, g->ex) / g->hx : 0.0,
           r = g->ny > 1 ? dot3(d, g->ey) / g->hy : 0.0;
    s = s < 0.0 ? 0.0 : s > g->nx - 1 ? g->nx - 1 : s;
    r = r < 0.0 ? 0.0 : r > g->ny - 1 ? g->ny - 1 : r;
    int32_t i0 = (int32_t)s, j0 = (int32_t)r;
    i0 = i0 >= g->nx - 1 ? (g->nx > 1 ? g->nx - 2 : 0) : i0;
    j0 = j0 >= g->ny - 1 ? (g->ny > 1 ? g->ny - 2 : 0) : j0;
    int32_t i1 = g->nx > 1 ? i0 + 1 : i0, j1 = g->ny > 1 ? j0 + 1 : j0;
    double fs = g->nx > 1 ? s - i0 : 0.0, fr = g->ny > 1 ? r - j0 : 0.0;
    idx[0] = j0 * g->nx + i0, wt[0] = (1 - fs) * (1 - fr);
    idx[1] = j0 * g->nx + i1, wt[1] = fs * (1 - fr);
    idx[2] = j1 * g->nx + i0, wt[2] = (1 - fs) * fr;
    idx[3] = j1 * g->nx + i1, wt[3] = fs * fr;
}
