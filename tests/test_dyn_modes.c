/* Natural frequencies of the segment model (src/mech/dyn_*.c): cantilevers against Euler-Bernoulli
 * theory, the effect of gravity on upright and hanging stems, a tip mass, and the tree operators
 * against each other (docs/validation.md, "Dynamics"). */
#include "dyn_testlib.h"
#include "cambium/dynamics.h"

#include "core/vecmath.h"
#include "mech/dyn_internal.h"

/* shear modulus of the rods below: 0 = E / 2.6 */
static double rod_shear = 0.0;

static cbm_plant *rod_s(cbm_context *ctx, int n, double L, double r, double elev, double g,
                        double tip_mass, double E, bool solve)
{
    return dyn_rod(ctx, n, L, r, elev, g, tip_mass, E, rod_shear, solve);
}

static cbm_plant *rod(cbm_context *ctx, int n, double L, double r, double elev, double g,
                      double tip_mass, double E)
{
    return rod_s(ctx, n, L, r, elev, g, tip_mass, E, true);
}

static const double beta_l[4] = {1.875104068711961, 4.694091132974175, 7.854757438237613,
                                 10.99554073487547};

/* Euler-Bernoulli frequency (Hz) of mode k of the uniform cantilever of radius r, length L */
static double eb_hz(int k, double L, double r)
{
    double c = 0.5 * r * sqrt(1e10 / 600.0); /* sqrt(EI / (rho A)) */
    return beta_l[k] * beta_l[k] / (2.0 * PI * L * L) * c;
}

/* Uniform cantilever without gravity: a round rod has each bending frequency twice (two planes);
 * the error against Euler-Bernoulli falls 4x per halving of the segments (second order). The rod
 * is thin (L / r = 1000) so that rotary inertia (Rayleigh's correction, ~(beta r / 2L)^2 / 2,
 * 1.5e-5 for mode 4) stays below the tolerances. */
TEST(cantilever_second_order)
{
    cbm_context *ctx = test_ctx();
    double L = 1.0, r = 0.001;
    double err[3][4];
    int ns[3] = {25, 50, 100};
    for (int t = 0; t < 3; t++) {
        cbm_plant *p = rod(ctx, ns[t], L, r, 0.0, 0.0, 0.0, 1e10);
        double f[8];
        CHECK_OK(cbm_plant_modes(p, 8, f, NULL));
        for (int k = 0; k < 4; k++) {
            CHECK_REL(f[2 * k], f[2 * k + 1], 1e-8);
            err[t][k] = fabs(f[2 * k] / eb_hz(k, L, r) - 1.0);
        }
        cbm_plant_destroy(p);
    }
    for (int k = 0; k < 4; k++) {
        double o1 = log2(err[0][k] / err[1][k]), o2 = log2(err[1][k] / err[2][k]);
        printf("mode %d: rel errors %.3g %.3g %.3g, orders %.3f %.3f\n", k + 1, err[0][k],
               err[1][k], err[2][k], o1, o2);
        CHECK(o2 > 1.9);
    }
    CHECK(err[2][0] < 1e-4);
    CHECK(err[2][3] < 2e-3);
    test_ctx_end(ctx);
}

/* The tree operators: the solve inverts the product (K + c M) v, and K, M are symmetric, on a
 * branched plant under gravity with point masses. */
TEST(operators_consistent)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = dyn_branched(ctx, 30);
    cbm__dyn dy;
    CHECK_OK(cbm__dyn_build(p, &dy));
    size_t N = 90;
    double v[90], w[90], y[90], x[90], kv[90], kw[90], mv[90], mw[90];
    for (size_t i = 0; i < N; i++) {
        v[i] = sin(1.0 + 0.7 * (double)i);
        w[i] = cos(0.3 + 1.3 * (double)i);
    }
    cbm__dyn_apply(&dy, 1.0, 0.0, v, kv);
    cbm__dyn_apply(&dy, 1.0, 0.0, w, kw);
    cbm__dyn_apply(&dy, 0.0, 1.0, v, mv);
    cbm__dyn_apply(&dy, 0.0, 1.0, w, mw);
    double a = 0, b = 0, c = 0, e = 0, sk = 0, sm = 0;
    for (size_t i = 0; i < N; i++) {
        a += w[i] * kv[i];
        b += v[i] * kw[i];
        c += w[i] * mv[i];
        e += v[i] * mw[i];
        sk += fabs(w[i] * kv[i]);
        sm += fabs(w[i] * mv[i]);
    }
    CHECK_NEAR(a, b, 1e-12 * sk);
    CHECK_NEAR(c, e, 1e-12 * sm);
    CHECK_EQ_INT(cbm__dyn_factor(&dy, 1.0, 250.0), 0);
    cbm__dyn_apply(&dy, 1.0, 250.0, v, y);
    cbm__dyn_solve(&dy, y, x);
    for (size_t i = 0; i < N; i++)
        CHECK_NEAR(x[i], v[i], 1e-9);
    cbm__dyn_free(&dy);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* A hanging rod of negligible rigidity is the heavy chain: omega_k = (j_0k / 2) sqrt(g / L)
 * (Bernoulli 1732; j_0k the zeros of J_0). Only the geometric stiffness of the weight holds it. */
TEST(hanging_chain)
{
    cbm_context *ctx = test_ctx();
    double L = 1.0, g = 9.81;
    /* straight down is the equilibrium (no moment anywhere); torsion kept stiff so that the
     * pendulum modes are the lowest */
    rod_shear = 1e10;
    cbm_plant *p = rod_s(ctx, 200, L, 0.001, -PI / 2, g, 0.0, 1e3, false);
    rod_shear = 0.0;
    double f[4];
    CHECK_OK(cbm_plant_modes(p, 4, f, NULL));
    double j0[2] = {2.404825557695773, 5.520078110286311};
    for (int k = 0; k < 2; k++) {
        double ref = 0.5 * j0[k] * sqrt(g / L) / (2.0 * PI);
        printf("chain mode %d: %.9g Hz, %.9g Hz, reference %.9g Hz\n", k + 1, f[2 * k],
               f[2 * k + 1], ref);
        CHECK_REL(f[2 * k], ref, 2e-3);
        CHECK_REL(f[2 * k + 1], ref, 2e-3);
    }
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Gravity: hanging, the stem is stiffer than without gravity; upright, softer, down to zero at
 * Greenhill's self-weight buckling length (7.837 EI / q)^(1/3), beyond which the equilibrium is
 * unstable and modes refuses it. */
TEST(gravity_upright_hanging)
{
    cbm_context *ctx = test_ctx();
    double r = 0.005, E = 1e10, q = 600 * PI * r * r * 9.81;
    double lcr = cbrt(7.837 * E * PI * r * r * r * r / 4.0 / q);
    double f0[2], fu[2], fh[2], fn[2];
    int n = 100;
    double L = 0.9 * lcr;
    cbm_plant *p = rod(ctx, n, L, r, 0.0, 0.0, 0.0, E);
    CHECK_OK(cbm_plant_modes(p, 2, f0, NULL));
    cbm_plant_destroy(p);
    p = rod(ctx, n, L, r, PI / 2, 9.81, 0.0, E);
    CHECK_OK(cbm_plant_modes(p, 2, fu, NULL));
    cbm_plant_destroy(p);
    p = rod(ctx, n, L, r, -PI / 2, 9.81, 0.0, E);
    CHECK_OK(cbm_plant_modes(p, 2, fh, NULL));
    cbm_plant_destroy(p);
    p = rod(ctx, n, 0.999 * lcr, r, PI / 2, 9.81, 0.0, E);
    CHECK_OK(cbm_plant_modes(p, 2, fn, NULL));
    cbm_plant_destroy(p);
    printf("L = 0.9 Lcr: no gravity %.6g Hz, upright %.6g Hz, hanging %.6g Hz; at 0.999 Lcr "
           "upright %.6g Hz\n",
           f0[0], fu[0], fh[0], fn[0]);
    CHECK(fu[0] < 0.8 * f0[0]);
    CHECK(fh[0] > 1.1 * f0[0]);
    CHECK(fn[0] < 0.1 * f0[0]);
    /* the straight column beyond it (the solver would find the stable bent state) */
    p = rod_s(ctx, n, 1.02 * lcr, r, PI / 2, 9.81, 0.0, E, false);
    if (p) {
        CHECK_STATUS(cbm_plant_modes(p, 2, fn, NULL), CBM_E_RUNTIME);
        cbm_plant_destroy(p);
    }
    test_ctx_end(ctx);
}

/* frequency equation of a cantilever with a tip point mass ratio mu = M / (m L):
 * 1 + cos b cosh b + mu b (cos b sinh b - sin b cosh b) = 0 */
static double tipmass_eq(double b, double mu)
{
    return 1.0 + cos(b) * cosh(b) + mu * b * (cos(b) * sinh(b) - sin(b) * cosh(b));
}

TEST(tip_mass)
{
    cbm_context *ctx = test_ctx();
    double L = 1.0, r = 0.001, m = 600 * PI * r * r * L;
    double mu = 0.5;
    double lo = 0.5, hi = 1.875;
    for (int it = 0; it < 200; it++) {
        double mid = 0.5 * (lo + hi);
        if ((tipmass_eq(lo, mu) > 0) == (tipmass_eq(mid, mu) > 0))
            lo = mid;
        else
            hi = mid;
    }
    double b = 0.5 * (lo + hi);
    double ref = b * b / (2.0 * PI * L * L) * 0.5 * r * sqrt(1e10 / 600.0);
    cbm_plant *p = rod(ctx, 100, L, r, 0.0, 0.0, mu * m, 1e10);
    double f[2];
    CHECK_OK(cbm_plant_modes(p, 2, f, NULL));
    printf("tip mass ratio %.2g: beta L = %.9f, %.9g Hz, reference %.9g Hz\n", mu, b, f[0], ref);
    CHECK_REL(f[0], ref, 2e-4);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Newmark's average acceleration conserves the energy of the undamped linear system to
 * round-off over long runs; a tip impulse adds exactly the work it does. */
TEST(motion_energy_conserved)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = rod(ctx, 40, 1.0, 0.01, 0.5, 9.81, 0.02, 1e10);
    cbm_motion_def md = cbm_motion_def_default();
    md.dt = 2e-3;
    cbm_motion *m = NULL;
    CHECK_OK(cbm_motion_create(p, &md, &m));
    CHECK_OK(cbm_motion_start_deflected(m, 39, v3(0, -2.0, 0.5)));
    double k0, u0;
    cbm_motion_state(m, NULL, &k0, &u0);
    CHECK(u0 > 0 && k0 == 0.0);
    double emax = 0.0;
    for (int s = 0; s < 20000; s++) {
        CHECK_OK(cbm_motion_step(m));
        if (s % 97 == 0 || s == 19999) {
            double k, u;
            cbm_motion_state(m, NULL, &k, &u);
            emax = fmax(emax, fabs(k + u - u0) / u0);
        }
    }
    printf("relative energy drift over 20000 steps: %.3g\n", emax);
    CHECK(emax < 1e-11);
    cbm_motion_destroy(m);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Damped free decay: the logarithmic decrement of the tip's swing is 2 pi zeta / sqrt(1 - zeta^2)
 * at the first mode (where the Rayleigh damping is matched). */
TEST(motion_damped_decay)
{
    cbm_context *ctx = test_ctx();
    double zeta = 0.05;
    cbm_plant *p = rod(ctx, 40, 1.0, 0.01, 0.0, 0.0, 0.0, 1e10);
    double f[2];
    CHECK_OK(cbm_plant_modes(p, 2, f, NULL));
    cbm_motion_def md = cbm_motion_def_default();
    md.dt = 1.0 / (f[0] * 400.0);
    md.damping_ratio = zeta;
    cbm_motion *m = NULL;
    CHECK_OK(cbm_motion_create(p, &md, &m));
    CHECK_OK(cbm_motion_start_deflected(m, 39, v3(0, -1.0, 0)));
    /* successive maxima of the tip's downward... upward swing */
    double prev = 0, cur = 0, peaks[8];
    int np = 0;
    cbm_vec3 u;
    for (int s = 0; s < 400 * 9 && np < 8; s++) {
        CHECK_OK(cbm_motion_step(m));
        CHECK_OK(cbm_motion_displacement(m, 39, &u));
        double y = -u.y;
        if (s > 1 && cur > prev && cur > y && cur > 0)
            peaks[np++] = cur;
        prev = cur;
        cur = y;
    }
    CHECK(np >= 4);
    double ref = 2.0 * PI * zeta / sqrt(1.0 - zeta * zeta);
    if (np >= 4) {
        double dec = log(peaks[1] / peaks[3]) / 2.0;
        printf("log decrement %.6f, reference %.6f\n", dec, ref);
        CHECK_REL(dec, ref, 0.02);
    }
    cbm_motion_destroy(m);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Tapered rod (truncated cone, radius r0 at the base to r1 at the tip): the first two bending
 * frequencies against an independent solution of (EI w'')'' = rho A omega^2 w, clamped-free, by
 * RK4 shooting (two base solutions, the tip's 2x2 determinant bisected in omega). */
typedef struct cone {
    double L, r0, r1, E, rho;
} cone;

static void cone_rhs(const cone *c, double x, const double *y, double w2, double *dy)
{
    double r = c->r0 + (c->r1 - c->r0) * x / c->L;
    double ei = c->E * PI * r * r * r * r / 4.0, ra = c->rho * PI * r * r;
    dy[0] = y[1];
    dy[1] = y[2] / ei;
    dy[2] = y[3];
    dy[3] = ra * w2 * y[0];
}

static double cone_det(const cone *c, double omega)
{
    double tip[2][4];
    for (int s = 0; s < 2; s++) {
        double y[4] = {0, 0, s == 0 ? 1.0 : 0.0, s == 1 ? 1.0 : 0.0};
        int n = 4000;
        double h = c->L / n, w2 = omega * omega;
        for (int i = 0; i < n; i++) {
            double x = i * h, k1[4], k2[4], k3[4], k4[4], t[4];
            cone_rhs(c, x, y, w2, k1);
            for (int j = 0; j < 4; j++)
                t[j] = y[j] + 0.5 * h * k1[j];
            cone_rhs(c, x + 0.5 * h, t, w2, k2);
            for (int j = 0; j < 4; j++)
                t[j] = y[j] + 0.5 * h * k2[j];
            cone_rhs(c, x + 0.5 * h, t, w2, k3);
            for (int j = 0; j < 4; j++)
                t[j] = y[j] + h * k3[j];
            cone_rhs(c, x + h, t, w2, k4);
            for (int j = 0; j < 4; j++)
                y[j] += h / 6.0 * (k1[j] + 2 * k2[j] + 2 * k3[j] + k4[j]);
        }
        memcpy(tip[s], y, sizeof y);
    }
    return tip[0][2] * tip[1][3] - tip[0][3] * tip[1][2];
}

TEST(tapered_rod)
{
    cbm_context *ctx = test_ctx();
    cone c = {1.0, 0.002, 0.0006, 1e10, 600};
    /* the reference: the first two sign changes of the determinant over omega */
    double ref[2];
    int found = 0;
    double prev = cone_det(&c, 1.0), w = 1.0;
    while (found < 2 && w < 2000.0) {
        double w1 = w * 1.01, d1 = cone_det(&c, w1);
        if ((d1 > 0) != (prev > 0)) {
            double lo = w, hi = w1, dlo = prev;
            for (int it = 0; it < 60; it++) {
                double mid = 0.5 * (lo + hi), dm = cone_det(&c, mid);
                if ((dm > 0) == (dlo > 0)) {
                    lo = mid;
                    dlo = dm;
                } else
                    hi = mid;
            }
            ref[found++] = 0.5 * (lo + hi) / (2.0 * PI);
        }
        w = w1;
        prev = d1;
    }
    CHECK_EQ_INT(found, 2);
    cbm_plant_def pd = cbm_plant_def_default();
    pd.gravity = v3(0, 0, 0);
    cbm_plant *p = NULL;
    CHECK_OK(cbm_plant_create(ctx, &pd, &p));
    int n = 100;
    cbm_segment_def d = cbm_segment_def_default();
    d.length = c.L / n;
    d.core.youngs_modulus = c.E;
    d.core.shear_modulus = c.E / 2.6;
    d.core.density = c.rho;
    for (int i = 0; i < n; i++) {
        d.parent = i - 1;
        d.core.a = d.core.b = c.r0 + (c.r1 - c.r0) * (i + 0.5) / n;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    cbm_solve_def sd = cbm_solve_def_default();
    CHECK_OK(cbm_plant_solve(p, &sd, NULL));
    double f[4];
    CHECK_OK(cbm_plant_modes(p, 4, f, NULL));
    printf("tapered rod: %.9g / %.9g Hz, reference %.9g / %.9g Hz\n", f[0], f[2], ref[0], ref[1]);
    if (found == 2) {
        CHECK_REL(f[0], ref[0], 5e-4);
        CHECK_REL(f[2], ref[1], 1e-3);
    }
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Critical wind speed: an upright stiff cylinder in a uniform wind breaks at its base when
 * 1/2 rho C_d D U^2 L^2 / 2 * 32 / (pi D^3) = MOR (exact for the staggered model: the drag of
 * each segment acts at its centroid); a horizontal stiff branch in a wind across it adds the
 * weight's moment at right angles: sqrt(M_w^2 + M_g^2) 32 / (pi D^3) = MOR. */
TEST(critical_wind)
{
    cbm_context *ctx = test_ctx();
    double L = 5.0, r = 0.05, mor = 40e6;
    cbm_plant *p = clamped_plant(ctx, PI / 2);
    cbm_segment_def d = cbm_segment_def_default();
    d.length = L / 50;
    d.core.youngs_modulus = 1e16;
    d.core.shear_modulus = 1e16;
    d.core.density = 600;
    d.core.a = d.core.b = r;
    d.core.modulus_of_rupture = mor;
    for (int i = 0; i < 50; i++) {
        d.parent = i - 1;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    /* a horizontal branch from the top of the stem (along -x); the wind blows along +z */
    double lb = 1.0, rb = 0.01;
    d.core.a = d.core.b = rb;
    d.length = lb / 20;
    for (int i = 0; i < 20; i++) {
        d.parent = i == 0 ? 49 : 50 + i - 1;
        d.lateral = i == 0;
        d.deviation = i == 0 ? PI / 2 : 0.0;
        d.divergence = i == 0 ? PI / 2 : 0.0;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    cbm_solve_def sd = cbm_solve_def_default();
    CHECK_OK(cbm_plant_solve(p, &sd, NULL));
    cbm_wind_def wd = cbm_wind_def_default();
    wd.profile = CBM_WIND_UNIFORM;
    wd.direction = v3(0, 0, 1);
    cbm_wind_critical rows[4];
    size_t nr = 0;
    CHECK_OK(cbm_plant_critical_wind(p, &wd, rows, 4, &nr));
    CHECK_EQ_INT(nr, 2);
    double q = 0.5 * 1.226 * 1.0 * 2 * r; /* drag per length per U^2 on the stem */
    /* the stem: the branch's drag (its axis is across the wind) adds at the stem's top */
    double qb = 0.5 * 1.226 * 1.0 * 2 * rb;
    double mstem = q * L * L / 2 + qb * lb * L;
    /* the stem's weight moment: the branch's weight at lever lb / 2, at right angles to the
     * wind moment */
    double wb = 600 * PI * rb * rb * lb * 9.81;
    double mg = wb * lb / 2;
    double sstem = (pow(mor * PI * pow(2 * r, 3) / 32, 2) - mg * mg) / (mstem * mstem);
    double ustem = sqrt(sqrt(sstem));
    double mgb = wb * lb / 2, mwb = qb * lb * lb / 2;
    double zb = mor * PI * pow(2 * rb, 3) / 32;
    double ubranch = sqrt(sqrt(zb * zb - mgb * mgb) / mwb);
    printf("critical wind: stem %.9g m/s (reference %.9g), branch %.9g m/s (reference %.9g)\n",
           rows[0].speed, ustem, rows[1].speed, ubranch);
    CHECK_EQ_INT(rows[0].order, 0);
    CHECK_EQ_INT(rows[0].weakest, 0);
    CHECK_EQ_INT(rows[1].order, 1);
    CHECK_EQ_INT(rows[1].first, 50);
    CHECK_EQ_INT(rows[1].weakest, 50);
    CHECK_REL(rows[0].speed, ustem, 1e-6);
    CHECK_REL(rows[1].speed, ubranch, 1e-6);
    /* log profile: slower at the stem's centroids than U_ref at 10 m, so a higher U_ref */
    wd = cbm_wind_def_default();
    wd.direction = v3(0, 0, 1);
    CHECK_OK(cbm_plant_critical_wind(p, &wd, rows, 4, &nr));
    CHECK(rows[0].speed > ustem);
    CHECK_NEAR(cbm_wind_speed(&wd, 10.0, 10.0), 10.0, 1e-12);
    CHECK_NEAR(cbm_wind_speed(&wd, 10.0, 0.05), 0.0, 0.0);
    wd.roughness = 0;
    CHECK_STATUS(cbm_plant_critical_wind(p, &wd, rows, 4, &nr), CBM_E_INVALID);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* The HWIND model's published worked example (Peltola et al.; the example output for Scots pine
 * at the stand edge): height 20 m, dbh 20 cm, crown 8 m deep of 74.49 kg and 19.84 m^2
 * projected area, stem 248.32 kg, MOR 39.1 MPa; HWIND: stem breakage at a mean canopy-top wind
 * of 16.30 m/s with a gust factor of 3.55 on the mean load. Our static critical wind of the same
 * tree (a paraboloid stem, diameter d0 sqrt(1 - z/H) through the dbh, density matched to the stem
 * mass, the crown's mass and area spread over the top 8 m, C_d 1 on the stem and 0.29 on the crown,
 * a log profile with z0 = 1.2 m referred to the top) is a mean speed without gusts; the figures are
 * compared in docs/validation.md. The check only holds it between HWIND's mean speed and twice its
 * gust-equivalent speed 16.30 sqrt(3.55) = 30.7 m/s. */
TEST(critical_wind_hwind_pine)
{
    cbm_context *ctx = test_ctx();
    double H = 20.0, dbh = 0.20, d0 = dbh / sqrt(1.0 - 1.3 / H);
    int n = 200, ncrown = 80;
    double vol = PI * d0 * d0 / 4.0 * H / 2.0, rho = 248.32 / vol;
    cbm_plant *p = clamped_plant(ctx, PI / 2);
    cbm_segment_def d = cbm_segment_def_default();
    d.length = H / n;
    d.core.youngs_modulus = 7e9;
    d.core.shear_modulus = 7e9 / 16;
    d.core.density = rho;
    d.core.modulus_of_rupture = 39.1e6;
    for (int i = 0; i < n; i++) {
        d.parent = i - 1;
        /* the radius at the segment's middle keeps its mass that of the paraboloid's slice (the
         * area is linear in z) */
        d.core.a = d.core.b = d0 / 2 * sqrt(1 - (i + 0.5) / n);
        d.point_mass = i >= n - ncrown ? 74.49 / ncrown : 0.0;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    cbm_solve_def sd = cbm_solve_def_default();
    CHECK_OK(cbm_plant_solve(p, &sd, NULL));
    cbm_vec3 tip = rod_tip(p);
    printf("tip at (%.4g, %.4g, %.4g) m\n", tip.x, tip.y, tip.z);
    cbm_wind_def wd = cbm_wind_def_default();
    wd.reference_height = H;
    wd.roughness = 1.2;
    wd.drag_wood = 1.0;
    wd.drag_organs = 0.29;
    wd.organ_area_per_kg = 19.84 / 74.49;
    cbm_wind_critical row;
    size_t nr = 0;
    CHECK_OK(cbm_plant_critical_wind(p, &wd, &row, 1, &nr));
    CHECK_EQ_INT(nr, 1);
    double gust = 16.30 * sqrt(3.55);
    printf("HWIND Scots pine: our static critical mean wind %.4g m/s at %.3g m (HWIND 16.30 m/s "
           "mean, %.4g m/s gust-equivalent)\n",
           row.speed, row.height, gust);
    CHECK(row.speed > 16.30 && row.speed < 2 * gust);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* All the modes at once (count = 3n, the number of degrees of freedom, and more): Lanczos reaches
 * an invariant subspace (repeated frequencies of a round rod, or the whole space) and restarts
 * M-orthogonally. Oracles: each pair satisfies K phi = lambda M phi (residual 1e-8 of |K phi|),
 * the shapes are M-orthonormal (1e-9), and no eigenvalue is missing or doubled: sum lambda =
 * trace(M^-1 K) and sum lambda^2 = trace((M^-1 K)^2) (1e-8); frequencies past 3n are NAN. */
static void check_all_modes(cbm_context *ctx, cbm_plant *p)
{
    cbm__dyn dy;
    CHECK_OK(cbm__dyn_build(p, &dy));
    size_t N = 3 * dy.n, extra = 2;
    double *f = calloc(N + extra, sizeof *f), *ph = calloc((N + extra) * N, sizeof *ph);
    double *a = calloc(N * N, sizeof *a), *e = calloc(N, sizeof *e), *y = calloc(N, sizeof *y);
    double *ky = calloc(N, sizeof *ky), *my = calloc(N, sizeof *my);
    CHECK(f && ph && a && e && y && ky && my);
    CHECK_OK(cbm_plant_modes(p, N + extra, f, ph));
    for (size_t i = N; i < N + extra; i++)
        CHECK(isnan(f[i]));
    double s1 = 0.0, s2 = 0.0;
    for (size_t i = 0; i < N; i++) {
        CHECK(isfinite(f[i]) && f[i] > 0.0);
        if (i > 0)
            CHECK(f[i] >= f[i - 1]);
        double lam = pow(2.0 * PI * f[i], 2);
        s1 += lam;
        s2 += lam * lam;
        const double *phi = ph + i * N;
        cbm__dyn_apply(&dy, 1.0, 0.0, phi, ky);
        cbm__dyn_apply(&dy, 0.0, 1.0, phi, my);
        double r = 0.0, k2 = 0.0;
        for (size_t k = 0; k < N; k++) {
            r += pow(ky[k] - lam * my[k], 2);
            k2 += ky[k] * ky[k];
        }
        CHECK(sqrt(r) <= 1e-8 * sqrt(k2));
        for (size_t j = 0; j <= i; j++) {
            double m = 0.0;
            for (size_t k = 0; k < N; k++)
                m += ph[j * N + k] * my[k];
            CHECK_NEAR(m, i == j ? 1.0 : 0.0, 1e-9);
        }
    }
    /* A = M^-1 K column by column */
    for (size_t c = 0; c < N; c++) {
        memset(e, 0, N * sizeof *e);
        e[c] = 1.0;
        cbm__dyn_apply(&dy, 1.0, 0.0, e, ky);
        CHECK_EQ_INT(cbm__dyn_factor(&dy, 0.0, 1.0), 0);
        cbm__dyn_solve(&dy, ky, y);
        for (size_t r = 0; r < N; r++)
            a[r * N + c] = y[r];
    }
    double t1 = 0.0, t2 = 0.0;
    for (size_t i = 0; i < N; i++) {
        t1 += a[i * N + i];
        for (size_t k = 0; k < N; k++)
            t2 += a[i * N + k] * a[k * N + i];
    }
    printf("%zu modes: %.6g .. %.6g Hz; sum lambda %.12g (trace %.12g), sum lambda^2 %.12g "
           "(trace %.12g)\n",
           N, f[0], f[N - 1], s1, t1, s2, t2);
    CHECK_REL(s1, t1, 1e-8);
    CHECK_REL(s2, t2, 1e-8);
    free(f);
    free(ph);
    free(a);
    free(e);
    free(y);
    free(ky);
    free(my);
    cbm__dyn_free(&dy);
    (void)ctx;
}

/* No mode missed in a cluster. An upright round stem of 10 segments with two whorls of four
 * identical round laterals (6 segments each, 90 degrees apart) under gravity: the symmetry makes
 * exact pairs and near-clusters of frequencies. The lowest 12 (a basis of at most 66 columns for
 * 174 degrees of freedom, so the early stop is the path taken) must be the lowest 12 of the whole
 * spectrum (count = 3n: every direction, checked by all_modes' traces), to 1e-9; a mode the
 * Krylov space never saw would shift every frequency after it by one place. */
TEST(cluster_no_mode_missed)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = clamped_plant(ctx, 0.5 * PI);
    cbm_segment_def d = cbm_segment_def_default();
    d.length = 0.1;
    d.core.a = d.core.b = 0.02;
    int64_t id = 0;
    for (int i = 0; i < 10; i++) {
        d.parent = i - 1;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    d.core.a = d.core.b = 0.008;
    d.length = 0.08;
    id = 10;
    for (int whorl = 0; whorl < 2; whorl++)
        for (int b = 0; b < 4; b++)
            for (int k = 0; k < 6; k++) {
                cbm_segment_def l = d;
                l.parent = k == 0 ? (whorl == 0 ? 4 : 7) : id - 1;
                l.lateral = k == 0;
                l.deviation = k == 0 ? 0.8 : 0.0;
                l.divergence = k == 0 ? 0.5 * PI * b : 0.0;
                l.point_mass = k == 5 ? 0.02 : 0.0;
                CHECK_OK(cbm_plant_add_segment(p, &l, NULL));
                id++;
            }
    cbm_solve_def sd = cbm_solve_def_default();
    CHECK_OK(cbm_plant_solve(p, &sd, NULL));
    size_t N = 3 * (size_t)id, k = 12;
    double *all = calloc(N, sizeof *all), f[12];
    CHECK(all != NULL);
    CHECK_OK(cbm_plant_modes(p, N, all, NULL));
    CHECK_OK(cbm_plant_modes(p, k, f, NULL));
    int pairs = 0;
    for (size_t i = 0; i < k; i++) {
        CHECK_REL(f[i], all[i], 1e-9);
        if (i > 0 && fabs(all[i] - all[i - 1]) <= 1e-9 * all[i])
            pairs++;
    }
    printf("lowest %zu of %zu: %.6g .. %.6g Hz, %d repeated\n", k, N, f[0], f[k - 1], pairs);
    CHECK(pairs >= 2); /* the case has the multiplicities it is meant to test */
    free(all);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Partial reorthogonalisation (dyn_modes.c) against the full Gram-Schmidt pass at every step,
 * the same Lanczos run otherwise: a branched plant of 2,000 segments (6,000 degrees of freedom),
 * the lowest 10 and 30 modes. The run must skip the sweep at some steps and sweep at others (both
 * paths taken); the frequencies agree with the full run's to 1e-10, each pair satisfies K phi =
 * lambda M phi (residual 1e-8 of |K phi|) and the shapes are M-orthonormal (1e-9), as all_modes
 * asks of the full spectrum. */
TEST(partial_reorthogonalisation)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = dyn_branched(ctx, 2000);
    cbm__dyn dy;
    CHECK_OK(cbm__dyn_build(p, &dy));
    size_t N = 3 * dy.n;
    const size_t counts[2] = {10, 30};
    for (int t = 0; t < 2; t++) {
        size_t k = counts[t], steps = 0, sweeps = 0, fsteps = 0, fsweeps = 0;
        double *f = calloc(k, sizeof *f), *ff = calloc(k, sizeof *ff);
        double *ph = calloc(k * N, sizeof *ph), *ky = calloc(N, sizeof *ky);
        double *my = calloc(k * N, sizeof *my);
        CHECK(f && ff && ph && ky && my);
        CHECK_OK(cbm__plant_modes(p, k, f, ph, false, &steps, &sweeps));
        CHECK_OK(cbm__plant_modes(p, k, ff, NULL, true, &fsteps, &fsweeps));
        printf("%zu modes: %zu steps, %zu of them swept (full: %zu steps, %zu swept); %.6g .. "
               "%.6g Hz\n",
               k, steps, sweeps, fsteps, fsweeps, f[0], f[k - 1]);
        CHECK(sweeps > 0 && sweeps < steps);
        CHECK_EQ_INT(fsweeps, fsteps);
        double emax = 0.0, omax = 0.0, fmaxd = 0.0;
        for (size_t i = 0; i < k; i++) {
            CHECK_REL(f[i], ff[i], 1e-10);
            fmaxd = fmax(fmaxd, fabs(f[i] - ff[i]) / ff[i]);
            double lam = pow(2.0 * PI * f[i], 2);
            const double *phi = ph + i * N;
            cbm__dyn_apply(&dy, 1.0, 0.0, phi, ky);
            cbm__dyn_apply(&dy, 0.0, 1.0, phi, my + i * N);
            double r = 0.0, k2 = 0.0;
            for (size_t q = 0; q < N; q++) {
                r += pow(ky[q] - lam * my[i * N + q], 2);
                k2 += ky[q] * ky[q];
            }
            emax = fmax(emax, sqrt(r / k2));
            CHECK(sqrt(r) <= 1e-8 * sqrt(k2));
            for (size_t j = 0; j <= i; j++) {
                double m = 0.0;
                for (size_t q = 0; q < N; q++)
                    m += ph[j * N + q] * my[i * N + q];
                omax = fmax(omax, fabs(m - (i == j ? 1.0 : 0.0)));
                CHECK_NEAR(m, i == j ? 1.0 : 0.0, 1e-9);
            }
        }
        printf("  frequencies to %.3g of the full run's, residual at most %.3g of |K phi|, "
               "M-orthonormal to %.3g\n",
               fmaxd, emax, omax);
        free(f);
        free(ff);
        free(ph);
        free(ky);
        free(my);
    }
    cbm__dyn_free(&dy);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

TEST(all_modes)
{
    cbm_context *ctx = test_ctx();
    /* a round horizontal rod without gravity: every bending frequency twice */
    cbm_plant *p = rod(ctx, 4, 1.0, 0.01, 0.0, 0.0, 0.0, 1e10);
    check_all_modes(ctx, p);
    cbm_plant_destroy(p);
    /* a branched plant under gravity with point masses */
    cbm_plant_def pd = cbm_plant_def_default();
    pd.base_orientation = cbm_mech_clamp_orientation(1.2);
    CHECK_OK(cbm_plant_create(ctx, &pd, &p));
    cbm_segment_def d = cbm_segment_def_default();
    d.core.a = 0.02;
    d.core.b = 0.015;
    for (int i = 0; i < 7; i++) {
        d.parent = i == 0 ? -1 : (i % 3 == 0 ? i / 2 : i - 1);
        d.lateral = i % 3 == 0 && i > 0;
        d.deviation = d.lateral ? 0.6 : 0.05;
        d.divergence = 2.4 * i;
        d.point_mass = i % 4 == 0 ? 0.05 : 0.0;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    cbm_solve_def sd = cbm_solve_def_default();
    CHECK_OK(cbm_plant_solve(p, &sd, NULL));
    check_all_modes(ctx, p);
    /* one segment: three degrees of freedom */
    cbm_plant_destroy(p);
    p = rod(ctx, 1, 0.1, 0.01, 0.3, 9.81, 0.01, 1e10);
    check_all_modes(ctx, p);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}
