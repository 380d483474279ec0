/* Loads in time on the linearised dynamics (src/mech/dyn_motion.c, dyn_drag.c, dyn_gust.c): wind
 * drag with the relative velocity, the gust synthesis, and prescribed base motion, against closed
 * forms (docs/validation.md, "Dynamics: loads in time"). */
#include "dyn_testlib.h"
#include "cambium/dynamics.h"

#include "core/vecmath.h"
#include "mech/dyn_internal.h"

#include <stdlib.h>

#define RHO_W 600.0
#define E_W   1e10

/* a straight horizontal rod (along +x) of n segments, radius r, no gravity, solved */
static cbm_plant *hrod(cbm_context *ctx, int n, double L, double r)
{
    return dyn_rod(ctx, n, L, r, 0.0, 0.0, 0.0, E_W, 0.0, true);
}

/* uniform wind across the rod (along +z), C_d 1 */
static cbm_wind_def cross_wind(void)
{
    cbm_wind_def w = cbm_wind_def_default();
    w.direction = v3(0, 0, 1);
    w.profile = CBM_WIND_UNIFORM;
    return w;
}

/* Steady uniform wind: from rest, with damping, the tip settles at the static deflection of the
 * uniform load q = 1/2 rho C_d (2r) U^2, q L^4 / (8 E I) (Euler-Bernoulli); the direct start from
 * the mean wind's static deflection gives the same. */
TEST(wind_steady_converges_to_static_drag)
{
    cbm_context *ctx = test_ctx();
    double L = 1.0, r = 0.01, U = 20.0;
    cbm_plant *p = hrod(ctx, 40, L, r);
    cbm_motion_def md = cbm_motion_def_default();
    md.damping_ratio = 0.1;
    cbm_motion *m = NULL;
    CHECK_OK(cbm_motion_create(p, &md, &m));
    cbm_wind_def w = cross_wind();
    CHECK_OK(cbm_motion_set_wind(m, &w, U, NULL));
    cbm_vec3 u;
    int maxit = 0;
    for (int s = 0; s < 3000; s++) {
        CHECK_OK(cbm_motion_step(m));
        maxit = cbm_motion_drag_iterations(m) > maxit ? cbm_motion_drag_iterations(m) : maxit;
    }
    CHECK_OK(cbm_motion_displacement(m, 39, &u));
    double EI = E_W * PI * pow(r, 4) / 4.0, q = 0.5 * w.air_density * 2.0 * r * U * U;
    double ref = q * pow(L, 4) / (8.0 * EI);
    printf("tip %.6e m, q L^4 / 8EI %.6e m, drag iterations <= %d\n", u.z, ref, maxit);
    CHECK_REL(u.z, ref, 2e-3);
    CHECK(fabs(u.x) < 1e-3 * ref && fabs(u.y) < 1e-3 * ref);
    CHECK(maxit >= 2 && maxit < 20);
    cbm_vec3 u2;
    CHECK_OK(cbm_motion_start_wind_static(m));
    CHECK_OK(cbm_motion_displacement(m, 39, &u2));
    CHECK_REL(u2.z, u.z, 1e-6);
    /* at rest in the static deflection it stays there */
    for (int s = 0; s < 100; s++)
        CHECK_OK(cbm_motion_step(m));
    CHECK_OK(cbm_motion_displacement(m, 39, &u));
    CHECK_REL(u.z, u2.z, 1e-9);
    cbm_motion_destroy(m);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Drag damping in a mean wind: for motions small against U, 1/2 rho C_d D (U - v)^2 = const -
 * rho C_d D U v, a damping per length c = rho C_d D U; on a uniform rod it is proportional to
 * the mass, so the first mode decays with zeta = c / (2 omega_1 m') exactly (no coupling). No
 * structural damping: the decay is the drag's alone. Started from the mean wind's deflection plus
 * a small multiple of the first mode shape (in the wind's plane). */
TEST(wind_drag_damping_small_amplitude)
{
    cbm_context *ctx = test_ctx();
    double L = 1.0, r = 0.01, U = 20.0;
    int n = 40;
    cbm_plant *p = hrod(ctx, n, L, r);
    double f[2], *shapes = malloc(2 * 3 * (size_t)n * sizeof(double));
    CHECK_OK(cbm_plant_modes(p, 2, f, shapes));
    double w1 = 2.0 * PI * f[0];
    /* the mode in the x-z plane: rotations about y; a combination of the degenerate pair */
    double *phi = malloc(3 * (size_t)n * sizeof(double)),
           *q0 = malloc(3 * (size_t)n * sizeof(double));
    double ay = shapes[3 * (n - 1) + 1], by = shapes[3 * n + 3 * (n - 1) + 1];
    double az = shapes[3 * (n - 1) + 2], bz = shapes[3 * n + 3 * (n - 1) + 2];
    /* c1 a + c2 b with zero z-rotation at the tip: c1 = bz, c2 = -az */
    bool pure = fabs(az) + fabs(bz) < 1e-12 * (fabs(ay) + fabs(by));
    for (int i = 0; i < 3 * n; i++)
        phi[i] = pure ? shapes[fabs(ay) > fabs(by) ? i : 3 * n + i]
                      : bz * shapes[i] - az * shapes[3 * n + i];
    cbm_motion_def md = cbm_motion_def_default();
    md.dt = 1.0 / (f[0] * 200.0);
    cbm_motion *m = NULL;
    CHECK_OK(cbm_motion_create(p, &md, &m));
    cbm_wind_def w = cross_wind();
    CHECK_OK(cbm_motion_set_wind(m, &w, U, NULL));
    CHECK_OK(cbm_motion_start_wind_static(m));
    cbm_vec3 us;
    CHECK_OK(cbm_motion_displacement(m, n - 1, &us));
    const double *qs = cbm_motion_rotations(m);
    /* scale: a tip amplitude of 2 mm (tip speed ~ 0.15 m/s, < 1 % of U) */
    double tip = 0.0;
    for (int k = 0; k < n; k++)
        tip += phi[3 * k + 1] * (L - (double)k * L / n); /* dz = -q_y (x_tip - x_k) */
    double sc = 2e-3 / fabs(tip);
    for (int i = 0; i < 3 * n; i++)
        q0[i] = qs[i] + sc * phi[i];
    CHECK_OK(cbm_motion_start_state(m, q0, NULL));
    double prev = 0, cur = 0, peaks[16];
    int np = 0;
    cbm_vec3 u;
    for (int s = 0; s < 200 * 14 && np < 16; s++) {
        CHECK_OK(cbm_motion_step(m));
        CHECK_OK(cbm_motion_displacement(m, n - 1, &u));
        double y = fabs(u.z - us.z);
        if (s > 1 && cur > prev && cur > y)
            peaks[np++] = cur;
        prev = cur;
        cur = y;
    }
    /* |dev| peaks twice per period */
    CHECK(np >= 13);
    double mpl = RHO_W * PI * r * r, c = w.air_density * 2.0 * r * U;
    double zeta_ref = c / (2.0 * w1 * mpl);
    if (np >= 13) {
        double dec = log(peaks[1] / peaks[13]) / 6.0; /* six periods */
        double zeta = dec / sqrt(4.0 * PI * PI + dec * dec);
        printf("drag damping ratio %.6f, closed form %.6f\n", zeta, zeta_ref);
        CHECK_REL(zeta, zeta_ref, 0.02);
    }
    free(shapes);
    free(phi);
    free(q0);
    cbm_motion_destroy(m);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* In still air drag only dissipates: the energy of a released rod never grows, and it falls. */
TEST(wind_still_air_dissipates)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = hrod(ctx, 30, 1.0, 0.005);
    cbm_motion_def md = cbm_motion_def_default();
    cbm_motion *m = NULL;
    CHECK_OK(cbm_motion_create(p, &md, &m));
    CHECK_OK(cbm_motion_start_deflected(m, 29, v3(0, 0, 0.5)));
    cbm_wind_def w = cross_wind();
    CHECK_OK(cbm_motion_set_wind(m, &w, 0.0, NULL));
    double k, u, e0, eprev;
    cbm_motion_state(m, NULL, &k, &u);
    e0 = eprev = k + u;
    bool mono = true;
    for (int s = 0; s < 2000; s++) {
        CHECK_OK(cbm_motion_step(m));
        cbm_motion_state(m, NULL, &k, &u);
        mono = mono && k + u <= eprev * (1.0 + 1e-12);
        eprev = k + u;
    }
    printf("energy after 2 s in still air: %.4f of the start\n", eprev / e0);
    CHECK(mono);
    CHECK(eprev < 0.99 * e0);
    cbm_motion_destroy(m);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* The gust synthesis: its variance (sum of amp^2 / 2) is the spectrum's integral over the band,
 * sigma^2 (1 / (1 + 10.2 a)^(2/3) - 1 / (1 + 10.2 b)^(2/3)) with a, b the band's ends in n L / U;
 * the same seed gives the same series, another seed another one. */
TEST(gust_variance_and_seed)
{
    cbm_context *ctx = test_ctx();
    cbm_wind_def w = cbm_wind_def_default();
    cbm_gust_def g = cbm_gust_def_default();
    g.intensity = 0.2;
    double U = 15.0, L = cbm__gust_length(&g, &w);
    CHECK_REL(L, 300.0 * pow(10.0 / 200.0, 0.67 + 0.05 * log(0.1)), 1e-12);
    cbm__gust a, b, c;
    CHECK_OK(cbm__gust_build(ctx, &g, &w, U, &a));
    CHECK_OK(cbm__gust_build(ctx, &g, &w, U, &b));
    g.seed = 2;
    CHECK_OK(cbm__gust_build(ctx, &g, &w, U, &c));
    double var = 0.0;
    for (int k = 0; k < a.n; k++)
        var += 0.5 * a.amp[k] * a.amp[k];
    double sigma = 0.2 * U, fa = g.f_min * L / U, fb = g.f_max * L / U;
    double ref =
        sigma * sigma * (pow(1.0 + 10.2 * fa, -2.0 / 3.0) - pow(1.0 + 10.2 * fb, -2.0 / 3.0));
    printf("gust variance %.5f, band integral %.5f (sigma^2 %.5f)\n", var, ref, sigma * sigma);
    CHECK_REL(var, ref, 1e-3);
    CHECK(var > 0.9 * sigma * sigma);
    bool same = true, differ = false;
    for (double t = 0.0; t < 10.0; t += 0.37) {
        same = same && cbm__gust_at(&a, t) == cbm__gust_at(&b, t);
        differ = differ || cbm__gust_at(&a, t) != cbm__gust_at(&c, t);
    }
    CHECK(same && differ);
    cbm__gust_free(ctx, &a);
    cbm__gust_free(ctx, &b);
    cbm__gust_free(ctx, &c);
    test_ctx_end(ctx);
}

/* Base-excited resonance: a uniform cantilever whose base moves with acceleration A sin(w1 t)
 * across it, damping ratio zeta at the first mode, settles at a relative tip amplitude
 * Gamma_1 phi_1(L) A / (2 zeta w1^2), Gamma_1 phi_1(L) = 2 sigma_1 / beta_1 * 2 = 1.56598 for the
 * Euler-Bernoulli cantilever (sigma_1 = 0.734096, beta_1 L = 1.875104), the higher modes'
 * quasi-static share below 0.1 %. The base's displacement integrates to -A / w1^2 sin(w1 t) + v0 t
 * terms: its amplitude is checked too. */
TEST(base_motion_resonance)
{
    cbm_context *ctx = test_ctx();
    double L = 1.0, r = 0.01, zeta = 0.02, A = 0.5;
    int n = 40;
    cbm_plant *p = hrod(ctx, n, L, r);
    double f[2];
    CHECK_OK(cbm_plant_modes(p, 2, f, NULL));
    double w1 = 2.0 * PI * f[0];
    cbm_motion_def md = cbm_motion_def_default();
    md.dt = 1.0 / (f[0] * 200.0);
    md.damping_ratio = zeta;
    cbm_motion *m = NULL;
    CHECK_OK(cbm_motion_create(p, &md, &m));
    int steps = (int)(12.0 / md.dt), last = (int)(1.0 / md.dt);
    double amp = 0.0;
    cbm_vec3 u;
    for (int s = 1; s <= steps; s++) {
        CHECK_OK(cbm_motion_base_acceleration(m, v3(0, 0, A * sin(w1 * s * md.dt))));
        CHECK_OK(cbm_motion_step(m));
        if (s > steps - last) {
            CHECK_OK(cbm_motion_displacement(m, n - 1, &u));
            amp = fmax(amp, fabs(u.z));
        }
    }
    double beta1 = 1.875104068711961, sig = (sinh(beta1) - sin(beta1)) / (cosh(beta1) + cos(beta1));
    double gp = 4.0 * sig / beta1;
    double ref = gp * A / (2.0 * zeta * w1 * w1);
    printf("resonant tip amplitude %.6e m, closed form %.6e m (Gamma phi(L) = %.5f)\n", amp, ref,
           gp);
    CHECK_REL(gp, 1.56598, 1e-5);
    CHECK_REL(amp, ref, 0.01);
    /* the base's displacement: A sin(w t) from rest integrates to A/w^2 (w t - sin(w t)) */
    cbm_vec3 bd = cbm_motion_base_displacement(m);
    double T = steps * md.dt, bref = A / (w1 * w1) * (w1 * T - sin(w1 * T));
    CHECK_REL(bd.z, bref, 1e-3);
    cbm_motion_destroy(m);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Bad input: a wind with a zero direction, a gust with f_min >= f_max, a non-finite speed. */
TEST(wind_bad_input)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = hrod(ctx, 5, 1.0, 0.01);
    cbm_motion *m = NULL;
    CHECK_OK(cbm_motion_create(p, NULL, &m));
    cbm_wind_def w = cross_wind();
    w.direction = v3(0, 0, 0);
    CHECK_STATUS(cbm_motion_set_wind(m, &w, 10.0, NULL), CBM_E_INVALID);
    w = cross_wind();
    cbm_gust_def g = cbm_gust_def_default();
    g.intensity = 0.1;
    g.f_min = 5.0;
    g.f_max = 1.0;
    CHECK_STATUS(cbm_motion_set_wind(m, &w, 10.0, &g), CBM_E_INVALID);
    CHECK_STATUS(cbm_motion_set_wind(m, &w, NAN, NULL), CBM_E_INVALID);
    CHECK_STATUS(cbm_motion_start_wind_static(m), CBM_E_INVALID);
    CHECK_STATUS(cbm_motion_base_acceleration(m, v3(NAN, 0, 0)), CBM_E_INVALID);
    /* nothing changed: the motion still steps */
    CHECK_OK(cbm_motion_step(m));
    cbm_motion_destroy(m);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* The fused two-sweep step (no drag, no base motion) against the general six-sweep step (forced
 * by a zero base acceleration before each step, which adds nothing to the load): the same
 * arithmetic in another order, so the same motion to round-off (1e-10 of the largest rotation
 * over 400 steps: the right-hand side sums terms 4 q / dt^2 a million times the result's; seen
 * 3e-13 without and 1.3e-11 with a start from a state exciting every mode), with Rayleigh damping
 * (both coefficients), impulses and tugs, on a branched plant under gravity with point masses, and
 * after a restart from a given state. */
TEST(fused_step_matches_general_step)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = dyn_branched(ctx, 40);
    for (int variant = 0; variant < 3; variant++) {
        cbm_motion_def md = cbm_motion_def_default();
        md.dt = 2e-3;
        md.damping_ratio = variant == 1 ? 0.05 : 0.0;
        md.rayleigh_alpha = variant == 2 ? 0.7 : 0.0;
        cbm_motion *fm = NULL, *gm = NULL;
        CHECK_OK(cbm_motion_create(p, &md, &fm));
        CHECK_OK(cbm_motion_create(p, &md, &gm));
        if (!fm || !gm)
            break;
        if (variant == 2) {
            /* a restart from a state: the fused step rebuilds its carried twists */
            double q[120], v[120];
            for (int i = 0; i < 120; i++) {
                q[i] = 1e-3 * sin(0.3 * i);
                v[i] = 1e-2 * cos(0.7 * i);
            }
            CHECK_OK(cbm_motion_start_state(fm, q, v));
            CHECK_OK(cbm_motion_start_state(gm, q, v));
        }
        double maxq = 0.0, maxd = 0.0;
        for (int s = 0; s < 400; s++) {
            if (s == 0 || s == 150) {
                CHECK_OK(cbm_motion_add_force(fm, 39, v3(0, -50, 10)));
                CHECK_OK(cbm_motion_add_force(gm, 39, v3(0, -50, 10)));
            }
            if (s >= 200 && s < 260) {
                CHECK_OK(cbm_motion_add_force(fm, 20, v3(3, 0, -2)));
                CHECK_OK(cbm_motion_add_force(gm, 20, v3(3, 0, -2)));
            }
            CHECK_OK(cbm_motion_base_acceleration(gm, v3(0, 0, 0)));
            CHECK_OK(cbm_motion_step(fm));
            CHECK_OK(cbm_motion_step(gm));
            const double *qf = cbm_motion_rotations(fm), *qg = cbm_motion_rotations(gm);
            for (int i = 0; i < 120; i++) {
                maxq = fmax(maxq, fabs(qg[i]));
                maxd = fmax(maxd, fabs(qf[i] - qg[i]));
            }
        }
        double ef, eg, kf, kg;
        cbm_motion_state(fm, NULL, &kf, &ef);
        cbm_motion_state(gm, NULL, &kg, &eg);
        printf("variant %d: largest rotation %.4g rad, largest difference %.3g rad; energies "
               "%.9g / %.9g J\n",
               variant, maxq, maxd, kf + ef, kg + eg);
        CHECK(maxq > 1e-5);
        CHECK(maxd <= 1e-10 * maxq);
        CHECK_REL(kf + ef, kg + eg, 1e-9);
        cbm_motion_destroy(fm);
        cbm_motion_destroy(gm);
    }
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}
