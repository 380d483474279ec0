/* The spatially correlated gust field (src/mech/dyn_gust.c) and the drag of leaves and fruit
 * apart (dyn_drag.c, dyn_wind.c), against their targets (docs/validation.md, "Dynamics: gust
 * field, leaves and fruit"). */
#include "dyn_testlib.h"
#include "cambium/dynamics.h"

#include "core/vecmath.h"
#include "mech/dyn_internal.h"

#include <stdlib.h>

#define TWO_PI_T 6.283185307179586

/* A field over two points 2 m apart vertically, the wind along +x: the grid is exactly the two
 * points (nx 1, ny 2), so the values at the points are the grid's (no interpolation). */
static void two_point_field(cbm_context *ctx, double a, uint64_t seed, double U, cbm__gust *out)
{
    cbm_wind_def w = cbm_wind_def_default();
    cbm_gust_def g = cbm_gust_def_default();
    g.intensity = 0.2;
    g.coherence_decay = a;
    g.grid = 2;
    g.seed = seed;
    g.f_max = 4.0;     /* below the records' Nyquist frequency (5 Hz): no aliasing */
    g.harmonics = 100; /* 8 % apart: 3 DFT bins of a 300 s record from 0.25 Hz up */
    cbm_vec3 pts[2] = {v3(0, 1, 0), v3(0, 3, 0)};
    CHECK_OK(cbm__gust_build(ctx, &g, &w, U, out));
    CHECK_OK(cbm__gust_field_build(ctx, &g, U, v3(1, 0, 0), pts, 2, out));
}

/* index of the grid point nearest p (the test's points are grid points) */
static int32_t grid_point(const cbm__gust *g, cbm_vec3 p)
{
    int32_t idx[4];
    double wt[4];
    cbm__gust_field_weights(g, p, idx, wt);
    int32_t best = idx[0];
    double bw = wt[0];
    for (int k = 1; k < 4; k++)
        if (wt[k] > bw)
            bw = wt[k], best = idx[k];
    CHECK(bw > 1.0 - 1e-12);
    return best;
}

/* The point spectrum and the coherence of the field between two points r = 2 m apart, over 40
 * seeds. Two estimates: (1) from the realisation's harmonics (the spectrum of an infinitely long
 * record: the power of harmonic k at point j is |A_jk|^2 / 2, the co-spectrum Re(A_1k A_2k*) /
 * 2), in bands of a factor 1.5 in frequency; (2) from records of 300 s sampled at 10 Hz through
 * the field's evaluation (Hann-windowed DFT on the record's bins over the same bands). Targets:
 * the band's power sum amp_k^2 / 2 (exact at the first point, whose harmonics carry the series'
 * own phases; at the second, its mean over the phases) and the power-weighted mean of
 * exp(-a f_k r / U). Tolerances: 4 standard deviations of the estimates over nu = seeds x
 * harmonics in the band independent phases, (1 - gamma^2) / sqrt(nu) for the co-coherence and
 * sqrt(2 / nu) for a band power (at least 0.03, for the DFT's leakage at the band's edges). */
TEST(gust_field_spectrum_and_coherence)
{
    cbm_context *ctx = test_ctx();
    const double U = 10.0, a = 10.0, r = 2.0, T = 300.0, fs = 10.0;
    const int seeds = 40, nsamp = (int)(T * fs);
    /* bands of 8 harmonics from the harmonic nearest f (Hz), their edges halfway between
     * harmonics in the log grid; the record's estimate is checked where the harmonics next to
     * an edge are 3 DFT bins or more from it (the Hann window's main lobe is 2 bins wide each
     * side: no harmonic then straddles an edge), printed elsewhere */
    enum { NB = 4, KB = 8 };
    const double centres[NB] = {0.12, 0.37, 1.1, 2.4};
    double lo[NB], hi[NB];
    int k0[NB];
    bool rec_ok[NB];
    {
        cbm_gust_def g0 = cbm_gust_def_default();
        g0.f_max = 4.0;
        g0.harmonics = 100;
        double span = log(g0.f_max / g0.f_min);
        for (int b = 0; b < NB; b++) {
            k0[b] = (int)floor(g0.harmonics * log(centres[b] / g0.f_min) / span) - KB / 2;
            lo[b] = g0.f_min * exp(span * k0[b] / g0.harmonics);
            hi[b] = g0.f_min * exp(span * (k0[b] + KB) / g0.harmonics);
            rec_ok[b] = 0.5 * lo[b] * (exp(span / g0.harmonics) - 1.0) * T >= 3.0;
        }
    }
    double p1[NB] = {0}, p2[NB] = {0}, c12[NB] = {0}, tp[NB] = {0}, tc[NB] = {0};
    double d1[NB] = {0}, d2[NB] = {0}, dc[NB] = {0}, sw2[NB] = {0};
    int nu[NB] = {0};
    double *u1 = malloc((size_t)nsamp * sizeof *u1), *u2 = malloc((size_t)nsamp * sizeof *u2);
    CHECK(u1 && u2);
    for (int s = 1; s <= seeds; s++) {
        cbm__gust g;
        two_point_field(ctx, a, (uint64_t)s, U, &g);
        CHECK(g.np == 2 && g.nx == 1 && g.ny == 2);
        int32_t j1 = grid_point(&g, v3(0, 1, 0)), j2 = grid_point(&g, v3(0, 3, 0));
        CHECK(j1 != j2);
        for (int b = 0; b < NB; b++)
            for (int k = k0[b]; k < k0[b] + KB; k++) {
                double f = g.omega[k] / TWO_PI_T;
                double ar1 = g.are[(size_t)k * 2 + (size_t)j1],
                       ai1 = g.aim[(size_t)k * 2 + (size_t)j1];
                double ar2 = g.are[(size_t)k * 2 + (size_t)j2],
                       ai2 = g.aim[(size_t)k * 2 + (size_t)j2];
                p1[b] += 0.5 * (ar1 * ar1 + ai1 * ai1);
                p2[b] += 0.5 * (ar2 * ar2 + ai2 * ai2);
                c12[b] += 0.5 * (ar1 * ar2 + ai1 * ai2);
                double pk = 0.5 * g.amp[k] * g.amp[k];
                tp[b] += pk;
                tc[b] += pk * exp(-a * f * r / U);
                sw2[b] += pk * pk;
                nu[b]++;
            }
        /* the record */
        for (int i = 0; i < nsamp; i++) {
            const double *gv = cbm__gust_field_at(&g, i / fs);
            u1[i] = gv[j1];
            u2[i] = gv[j2];
        }
        for (int b = 0; b < NB; b++) {
            if (!rec_ok[b])
                continue;
            int m0 = (int)ceil(lo[b] * T), m1 = (int)ceil(hi[b] * T);
            for (int m = m0; m < m1; m++) {
                double x1r = 0, x1i = 0, x2r = 0, x2i = 0, w2 = 0;
                for (int i = 0; i < nsamp; i++) {
                    double hw = 0.5 - 0.5 * cos(TWO_PI_T * i / nsamp);
                    double ph = TWO_PI_T * (double)m * i / nsamp, co = cos(ph), si = sin(ph);
                    x1r += hw * u1[i] * co, x1i -= hw * u1[i] * si;
                    x2r += hw * u2[i] * co, x2i -= hw * u2[i] * si;
                    w2 += hw * hw;
                }
                /* one-sided power in the bin: 2 |X|^2 / (sum w^2 fs) x (1 / T) */
                double sc = 2.0 / (w2 * fs) / T;
                d1[b] += sc * (x1r * x1r + x1i * x1i);
                d2[b] += sc * (x2r * x2r + x2i * x2i);
                dc[b] += sc * (x1r * x2r + x1i * x2i);
            }
        }
        /* the same seed gives the same field */
        if (s == 1) {
            cbm__gust h;
            two_point_field(ctx, a, 1, U, &h);
            bool same = true;
            for (size_t k = 0; k < (size_t)g.n * 2; k++)
                same = same && g.are[k] == h.are[k] && g.aim[k] == h.aim[k];
            CHECK(same);
            cbm__gust_free(ctx, &h);
        }
        cbm__gust_free(ctx, &g);
    }
    for (int b = 0; b < NB; b++) {
        double f0 = sqrt(lo[b] * hi[b]), gam = tc[b] / tp[b];
        /* independent phases, seeds x harmonics, weighted by the harmonics' powers (Kish) */
        double v = tp[b] * tp[b] / sw2[b];
        /* the second point's power per harmonic is 1 + 2 L_10 L_11 cos(dtheta) of the mean, of
         * variance 2 L_10^2 L_11^2 <= 1/2 */
        double tol_c = 4.0 * (1.0 - gam * gam) / sqrt(v), tol_p = 4.0 * sqrt(0.5 / v);
        double coh = c12[b] / sqrt(p1[b] * p2[b]), cohd = dc[b] / sqrt(d1[b] * d2[b]);
        printf("band %.3f-%.3f Hz (%d harmonics a seed, nu %.0f): power at 1 %.5f, at 2 %.5f, "
               "record %.5f %.5f%s, target %.5f; co-coherence %.4f, record %.4f, target %.4f "
               "(exp(-a f r / U) at %.3f Hz: %.4f), tolerances %.3f %.3f\n",
               lo[b], hi[b], nu[b] / seeds, v, p1[b] / seeds, p2[b] / seeds, d1[b] / seeds,
               d2[b] / seeds, rec_ok[b] ? "" : " (not checked)", tp[b] / seeds, coh, cohd, gam, f0,
               exp(-a * f0 * r / U), tol_p, tol_c);
        CHECK_REL(p1[b], tp[b], 1e-12); /* the first point: exact */
        CHECK(fabs(p2[b] / tp[b] - 1.0) < tol_p);
        CHECK(fabs(coh - gam) < tol_c);
        if (rec_ok[b]) {
            CHECK(fabs(d1[b] / tp[b] - 1.0) < 0.02); /* the first point: leakage only */
            CHECK(fabs(d2[b] / tp[b] - 1.0) < tol_p);
            CHECK(fabs(cohd - gam) < tol_c);
        }
        /* the target is not trivially met: full coherence is far */
        CHECK(1.0 - gam > 2.0 * tol_c);
        CHECK(fabs(gam - exp(-a * f0 * r / U)) < 0.02);
    }
    free(u1);
    free(u2);
    test_ctx_end(ctx);
}

/* The uniform series is the limit of infinite coherence length: with a -> 0 every grid point
 * carries the series (the first column of L is 1 and its phases are the series'), at a 1e-12
 * to round-off, and the largest difference shrinks with a. */
TEST(gust_field_uniform_limit)
{
    cbm_context *ctx = test_ctx();
    const double U = 12.0;
    cbm_wind_def w = cbm_wind_def_default();
    cbm_gust_def g = cbm_gust_def_default();
    g.intensity = 0.2;
    g.grid = 4;
    cbm_vec3 pts[3] = {v3(0, 0.5, -1.5), v3(0, 4, 1.5), v3(2, 2, 0)};
    double prev = INFINITY, sigma = 0.2 * U;
    const double as[5] = {1e-30, 1e-12, 1e-4, 1e-2, 1.0};
    double diffs[5];
    for (int q = 0; q < 5; q++) {
        g.coherence_decay = as[q];
        cbm__gust s;
        CHECK_OK(cbm__gust_build(ctx, &g, &w, U, &s));
        CHECK_OK(cbm__gust_field_build(ctx, &g, U, v3(1, 0, 0), pts, 3, &s));
        CHECK(s.np == 16);
        double mx = 0.0;
        for (double t = 0.0; t < 200.0; t += 0.731) {
            const double *gv = cbm__gust_field_at(&s, t);
            double u = cbm__gust_at(&s, t);
            for (int j = 0; j < s.np; j++)
                mx = fmax(mx, fabs(gv[j] - u));
        }
        diffs[q] = mx / sigma;
        cbm__gust_free(ctx, &s);
    }
    printf("max |u'_j - u'| / sigma over 16 points, a = 1e-30 %.3g, 1e-12 %.3g, 1e-4 %.3g, "
           "1e-2 %.3g, 1 %.3g\n",
           diffs[0], diffs[1], diffs[2], diffs[3], diffs[4]);
    /* below the pivot's cut-off: the series itself, to round-off */
    CHECK(diffs[0] < 1e-12);
    /* 1 - C_jl ~ a f r / U, so the points' own parts grow as sqrt(a): < 3 sqrt(a) here (f r / U
     * <= 20 x 4.7 / 12), and they grow with a */
    for (int q = 1; q < 5; q++) {
        CHECK(diffs[q] < 3.0 * sqrt(as[q]));
        CHECK(diffs[q] > diffs[q - 1]);
    }
    (void)prev;
    CHECK(diffs[4] > 0.1);
    /* a = 0: no field, the series (bit for bit the drag of before) */
    g.coherence_decay = 0.0;
    cbm__gust s;
    CHECK_OK(cbm__gust_build(ctx, &g, &w, U, &s));
    CHECK_OK(cbm__gust_field_build(ctx, &g, U, v3(1, 0, 0), pts, 3, &s));
    CHECK(s.np == 0);
    cbm__gust_free(ctx, &s);
    test_ctx_end(ctx);
}

/* ---- leaves and fruit apart ---- */

#define RHO_AIR 1.226
#define MOR_W   50e6

/* a straight horizontal cantilever along +x of n segments, radius r, no gravity, wood of MOR
 * 50 MPa, solved */
static cbm_plant *organ_rod(cbm_context *ctx, int n, double L, double r)
{
    cbm_plant_def pd = cbm_plant_def_default();
    pd.base_orientation = cbm_mech_clamp_orientation(0.0);
    pd.gravity = v3(0, 0, 0);
    cbm_plant *p = NULL;
    CHECK_OK(cbm_plant_create(ctx, &pd, &p));
    cbm_segment_def d = cbm_segment_def_default();
    d.length = L / n;
    d.core.youngs_modulus = 1e10;
    d.core.shear_modulus = 1e10 / 2.6;
    d.core.density = 600;
    d.core.a = d.core.b = r;
    d.core.modulus_of_rupture = MOR_W;
    for (int i = 0; i < n; i++) {
        d.parent = i - 1;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    cbm_solve_def sd = cbm_solve_def_default();
    CHECK_OK(cbm_plant_solve(p, &sd, NULL));
    return p;
}

/* uniform wind along +z, across the rod, no drag on the wood: only the organs' */
static cbm_wind_def organ_wind(const double *leaf_area, const double *fruit_mass)
{
    cbm_wind_def w = cbm_wind_def_default();
    w.direction = v3(0, 0, 1);
    w.profile = CBM_WIND_UNIFORM;
    w.drag_wood = 0.0;
    w.leaf_area = leaf_area;
    w.fruit_mass = fruit_mass;
    return w;
}

/* The static deflection under the mean wind's drag of a rod with only fruit (a 150 g apple at the
 * tip, density 800: r = (3 m / (4 pi rho))^(1/3) = 3.5506 cm) or only leaves (0.05 m^2 at the tip),
 * against the deflection under the hand-computed force at the tip: fruit 1/2 rho 0.47 pi r^2 U^2;
 * leaves 1/2 rho 1.17 A U^2 below U_0 = 5 m/s and 1/2 rho 1.17 A U^2 (U / U_0)^(-2/3) above.
 * The motion's two starts solve the same K q = f, so they agree to round-off. */
TEST(organ_drag_fruit_only_leaves_only)
{
    cbm_context *ctx = test_ctx();
    int n = 20;
    cbm_plant *p = organ_rod(ctx, n, 1.0, 0.01);
    double *leaf = calloc((size_t)n, sizeof *leaf), *fruit = calloc((size_t)n, sizeof *fruit);
    CHECK(leaf && fruit);
    fruit[n - 1] = 0.150;
    leaf[n - 1] = 0.05;
    double rf = cbrt(3.0 * 0.150 / (4.0 * PI * 800.0));
    CHECK(fabs(rf - 0.035506) < 1e-6);
    const double speeds[3] = {3.0, 5.0, 20.0};
    for (int c = 0; c < 2; c++) {
        for (int s = 0; s < 3; s++) {
            double U = speeds[s];
            cbm_wind_def w = c == 0 ? organ_wind(NULL, fruit) : organ_wind(leaf, NULL);
            double F = c == 0 ? 0.5 * RHO_AIR * 0.47 * PI * rf * rf * U * U
                              : 0.5 * RHO_AIR * 1.17 * 0.05 * U * U *
                                    (U > 5.0 ? pow(U / 5.0, -2.0 / 3.0) : 1.0);
            cbm_motion *m = NULL;
            cbm_motion_def md = cbm_motion_def_default();
            CHECK_OK(cbm_motion_create(p, &md, &m));
            CHECK_OK(cbm_motion_set_wind(m, &w, U, NULL));
            CHECK_OK(cbm_motion_start_wind_static(m));
            cbm_vec3 uw, uf;
            CHECK_OK(cbm_motion_displacement(m, (size_t)n - 1, &uw));
            CHECK_OK(cbm_motion_start_deflected(m, (size_t)n - 1, v3(0, 0, F)));
            CHECK_OK(cbm_motion_displacement(m, (size_t)n - 1, &uf));
            printf("%s only, U %4.1f m/s: tip force %.6f N, tip %.6e m (by the force %.6e m)\n",
                   c == 0 ? "fruit" : "leaves", U, F, uw.z, uf.z);
            CHECK(uf.z > 0.0);
            CHECK_REL(uw.z, uf.z, 1e-12);
            CHECK(fabs(uw.x) + fabs(uw.y) < 1e-9 * uw.z);
            cbm_motion_destroy(m);
        }
    }
    /* moving with the air: no drag; against it, the relative speed counts (the fruit's drag in
     * a step is checked through the motion's drag damping in test_dyn_loads) */
    free(leaf);
    free(fruit);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* The critical wind of the rod with only fruit or only leaves at its tip: the root's moment F L
 * reaches MOR I / r at U = sqrt(MOR I / (r L k)) for a drag k U^2 (fruit; leaves below U_0) and
 * at U_0 (MOR I / (r L k U_0^2))^(1 / (2 + B)) above U_0 (the leaves' fixed point), k = 1/2 rho
 * C_d A. The discrete root moment is the exact F L (a tip force), so to the solver's tolerance.
 * Areas chosen so that the leaves' answer lies above U_0. */
TEST(organ_drag_critical_wind)
{
    cbm_context *ctx = test_ctx();
    int n = 10;
    double L = 1.0, r = 0.005;
    cbm_plant *p = organ_rod(ctx, n, L, r);
    double *leaf = calloc((size_t)n, sizeof *leaf), *fruit = calloc((size_t)n, sizeof *fruit);
    CHECK(leaf && fruit);
    fruit[n - 1] = 0.150;
    leaf[n - 1] = 0.05;
    double Mr = MOR_W * PI * pow(r, 4) / 4.0 / r; /* the root's moment at rupture, N m */
    double rf = cbrt(3.0 * 0.150 / (4.0 * PI * 800.0));
    double kf = 0.5 * RHO_AIR * 0.47 * PI * rf * rf, kl = 0.5 * RHO_AIR * 1.17 * 0.05;
    double ref_f = sqrt(Mr / (L * kf)),
           ref_l = 5.0 * pow(Mr / (L * kl * 25.0), 1.0 / (2.0 - 2.0 / 3.0));
    double ref_l_rigid = sqrt(Mr / (L * kl));
    cbm_wind_critical row[2];
    size_t cnt = 0;
    cbm_wind_def w = organ_wind(NULL, fruit);
    CHECK_OK(cbm_plant_critical_wind(p, &w, row, 2, &cnt));
    CHECK(cnt == 1);
    printf("fruit only: critical %.6f m/s (hand %.6f), weakest segment %zu\n", row[0].speed, ref_f,
           row[0].weakest);
    CHECK_REL(row[0].speed, ref_f, 1e-6);
    CHECK(row[0].weakest == 0);
    w = organ_wind(leaf, NULL);
    CHECK_OK(cbm_plant_critical_wind(p, &w, row, 2, &cnt));
    printf("leaves only: critical %.6f m/s (hand %.6f; rigid plates %.6f)\n", row[0].speed, ref_l,
           ref_l_rigid);
    CHECK(ref_l > 5.0);
    CHECK_REL(row[0].speed, ref_l, 1e-6);
    w.leaf_vogel = 0.0; /* plates that keep their shape */
    CHECK_OK(cbm_plant_critical_wind(p, &w, row, 2, &cnt));
    CHECK_REL(row[0].speed, ref_l_rigid, 1e-6);
    /* bad organ data */
    leaf[3] = -1.0;
    w = organ_wind(leaf, NULL);
    CHECK_STATUS(cbm_plant_critical_wind(p, &w, row, 2, &cnt), CBM_E_INVALID);
    leaf[3] = 0.0;
    w.leaf_vogel = -2.5;
    CHECK_STATUS(cbm_plant_critical_wind(p, &w, row, 2, &cnt), CBM_E_INVALID);
    w = organ_wind(NULL, fruit);
    w.fruit_density = 0.0;
    CHECK_STATUS(cbm_plant_critical_wind(p, &w, row, 2, &cnt), CBM_E_INVALID);
    free(leaf);
    free(fruit);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* The field in a motion: a horizontal rod across a gusty wind; with a coherence decay of 1e-30
 * the field is the series at every segment, so the motion is that of the series (to round-off);
 * with a = 10 it differs; the same seed gives the same motion bit for bit. */
TEST(gust_field_in_motion)
{
    cbm_context *ctx = test_ctx();
    int n = 20;
    cbm_plant *p = organ_rod(ctx, n, 1.0, 0.01);
    const double as[4] = {0.0, 1e-30, 10.0, 10.0};
    double tip[4];
    for (int q = 0; q < 4; q++) {
        cbm_motion_def md = cbm_motion_def_default();
        md.damping_ratio = 0.05;
        cbm_motion *m = NULL;
        CHECK_OK(cbm_motion_create(p, &md, &m));
        cbm_wind_def w = cbm_wind_def_default();
        w.direction = v3(0, 0, 1);
        w.profile = CBM_WIND_UNIFORM;
        cbm_gust_def g = cbm_gust_def_default();
        g.intensity = 0.3;
        g.coherence_decay = as[q];
        CHECK_OK(cbm_motion_set_wind(m, &w, 15.0, &g));
        CHECK_OK(cbm_motion_start_wind_static(m));
        double s = 0.0;
        for (int k = 0; k < 400; k++) {
            CHECK_OK(cbm_motion_step(m));
            cbm_vec3 u;
            CHECK_OK(cbm_motion_displacement(m, (size_t)n - 1, &u));
            s += fabs(u.z);
        }
        tip[q] = s;
        cbm_motion_destroy(m);
    }
    printf("sum |tip| over 400 steps: series %.12e, a 1e-30 %.12e, a 10 %.12e (again %.12e)\n",
           tip[0], tip[1], tip[2], tip[3]);
    CHECK_REL(tip[1], tip[0], 1e-12);
    CHECK(fabs(tip[2] / tip[0] - 1.0) > 1e-4);
    CHECK(tip[2] == tip[3]);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}
