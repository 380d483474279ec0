/* Validation of the statics against closed forms and independent references (docs/validation.md):
 * exact discretisation factors of the staggered and chain discretisations, small-deflection
 * cantilevers (horizontal, inclined, tapered), the exact circle under a tip moment, the
 * large-deflection elastica with a tip load (Mattiasson 1981 table) and under self-weight
 * (shooting reference), and the observed convergence orders. */
#include "mech_testlib.h"

static const double g0 = 9.81;

static double solve_tip_y(cbm_context *ctx, int n, double L, radius_fn rf, double E, double rho,
                          double elev, cbm_mech_discretization disc, double P, cbm_vec3 *tipo)
{
    cbm_plant *p = make_rod(ctx, n, L, rf, E, rho, elev, disc);
    if (P != 0.0)
        CHECK_OK(
            cbm_plant_set_load(p, (size_t)n - 1, 0.0, (cbm_vec3){0, -P, 0}, (cbm_vec3){0, 0, 0}));
    cbm_solve_def sd = cbm_solve_def_default();
    sd.tolerance = 1e-13;
    cbm_solve_stats st;
    CHECK_OK(cbm_plant_solve(p, &sd, &st));
    cbm_vec3 t = rod_tip(p);
    if (tipo)
        *tipo = t;
    cbm_plant_destroy(p);
    return t.y;
}

/* Linearised discrete sums (derived in docs/validation.md): tip deflection / continuum value. */
TEST(mech_discretisation_factors)
{
    cbm_context *ctx = test_ctx();
    double L = 1.0, r = 0.01, rho = 1000.0;
    double I = PI * r * r * r * r / 4, A = PI * r * r;
    double E = 1e17; /* alpha = wL^3/EI ~ 1e-8: geometric nonlinearity below 1e-15 relative */
    double w = rho * A * g0, P = 0.5 * w * L;
    int ns[] = {1, 2, 3, 7, 40};
    for (size_t k = 0; k < sizeof ns / sizeof *ns; k++) {
        double N = ns[k];
        double dw = w * L * L * L * L / (8 * E * I), dp = P * L * L * L / (3 * E * I);
        double yw =
            solve_tip_y(ctx, ns[k], L, radius_uniform, E, rho, 0, CBM_MECH_STAGGERED, 0, NULL);
        CHECK_REL(-yw / dw, 1.0 + 1.0 / (N * N), 1e-10);
        double yp =
            solve_tip_y(ctx, ns[k], L, radius_uniform, E, 0.0, 0, CBM_MECH_STAGGERED, P, NULL);
        CHECK_REL(-yp / dp, 1.0 + 0.5 / (N * N), 1e-10);
        double cw = solve_tip_y(ctx, ns[k], L, radius_uniform, E, rho, 0, CBM_MECH_CHAIN, 0, NULL);
        CHECK_REL(-cw / dw, 1.0 + 10.0 / (3 * N) + 3.0 / (N * N) + 2.0 / (3 * N * N * N), 1e-10);
        double cp = solve_tip_y(ctx, ns[k], L, radius_uniform, E, 0.0, 0, CBM_MECH_CHAIN, P, NULL);
        CHECK_REL(-cp / dp, 1.0 + 1.5 / N + 0.5 / (N * N), 1e-10);
    }
    test_ctx_end(ctx);
}

static double taper(double s, double L)
{
    return 0.02 * (1.0 - 0.6 * s / L);
}

/* Linear (small-deflection) tip deflection of a cantilever by the unit-load method, Simpson's
 * rule with 20000 intervals: delta = int_0^L M(s) (L - s) / EI(s) ds with M the moment of the
 * transverse load (weight per length w(s) = rho A(s) g cos(elev), tip load P cos(elev)). */
static double linear_deflection(double L, radius_fn rf, double E, double rho, double elev, double P)
{
    int n = 20000;
    double h = L / n, sum = 0;
    for (int i = 0; i <= n; i++) {
        double s = i * h;
        /* M(s) = int_s^L w(t)(t - s) dt + P (L - s), inner Simpson */
        int m = 400;
        double hh = (L - s) / m, ms = 0;
        for (int j = 0; m > 0 && j <= m && hh > 0; j++) {
            double t = s + j * hh, rr = rf(t, L);
            double f = rho * PI * rr * rr * g0 * (t - s);
            ms += f * (j == 0 || j == m ? 1 : (j % 2 ? 4 : 2));
        }
        ms *= hh / 3;
        double M = (ms + P * (L - s)) * cos(elev);
        double rr = rf(s, L), EI = E * PI * rr * rr * rr * rr / 4;
        double f = M * (L - s) / EI;
        sum += f * (i == 0 || i == n ? 1 : (i % 2 ? 4 : 2));
    }
    return sum * h / 3;
}

TEST(mech_small_deflection_cantilevers)
{
    cbm_context *ctx = test_ctx();
    double L = 2.0, rho = 700.0, E = 1e15;
    struct {
        radius_fn rf;
        double elev, P;
        const char *what;
    } cases[] = {
        {radius_uniform, 0.0, 0.0, "uniform, horizontal, self-weight"},
        {radius_uniform, 0.0, 3.0, "uniform, horizontal, tip load"},
        {radius_uniform, 30 * PI / 180, 0.0, "uniform, inclined 30 deg, self-weight"},
        {taper, 0.0, 0.0, "tapered, horizontal, self-weight"},
        {taper, -20 * PI / 180, 3.0, "tapered, inclined -20 deg, tip load + weight"},
    };
    for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
        double ref = linear_deflection(L, cases[c].rf, E, rho, cases[c].elev, cases[c].P);
        double err[3];
        int ns[3] = {20, 40, 80};
        for (int k = 0; k < 3; k++) {
            cbm_vec3 t;
            solve_tip_y(ctx, ns[k], L, cases[c].rf, E, rho, cases[c].elev, CBM_MECH_STAGGERED,
                        cases[c].P, &t);
            /* transverse deflection: component along -(-sin e, cos e) = the clamp's -U */
            double d = t.x * sin(cases[c].elev) - t.y * cos(cases[c].elev);
            err[k] = fabs(d - ref) / ref;
        }
        double o1 = log2(err[0] / err[1]), o2 = log2(err[1] / err[2]);
        printf("%s: ref %.9g rel err %.3g %.3g %.3g orders %.3f %.3f\n", cases[c].what, ref, err[0],
               err[1], err[2], o1, o2);
        CHECK_MSG(err[2] < 1e-3, "%s: error %.3g", cases[c].what, err[2]);
        CHECK_MSG(o2 > 1.9 && o2 < 2.1, "%s: order %.3f", cases[c].what, o2);
    }
    test_ctx_end(ctx);
}

/* A tip moment bends the rod into an exact circle: in the staggered discretisation every node
 * lies on the circle of radius h / (2 sin(kappa h / 2)) tangent to the clamp at the base. */
TEST(mech_tip_moment_circle)
{
    cbm_context *ctx = test_ctx();
    int n = 64;
    double L = 1.0, E = 1e9, r = 0.01, EI = E * PI * r * r * r * r / 4;
    double kappa = 1.5 * PI / L; /* three quarters of a turn */
    for (int disc = 0; disc < 2; disc++) {
        cbm_plant *p =
            make_rod(ctx, n, L, radius_uniform, E, 0.0, 0.0, (cbm_mech_discretization)disc);
        cbm_plant_set_gravity(p, (cbm_vec3){0, 0, 0});
        CHECK_OK(cbm_plant_set_load(p, (size_t)n - 1, 0.0, (cbm_vec3){0, 0, 0},
                                    (cbm_vec3){0, 0, kappa * EI}));
        cbm_solve_def sd = cbm_solve_def_default();
        sd.tolerance = 1e-13;
        cbm_solve_stats st;
        CHECK_OK(cbm_plant_solve(p, &sd, &st));
        double h = L / n;
        if (disc == CBM_MECH_STAGGERED) {
            double R = h / (2 * sin(kappa * h / 2));
            for (int i = 0; i < n; i++) {
                cbm_segment_state s;
                CHECK_OK(cbm_plant_segment(p, (size_t)i, &s));
                double d = hypot(s.distal.x, s.distal.y - R);
                CHECK_NEAR(d, R, 1e-12 * R);
                CHECK_REL(s.omega.y, -kappa, 1e-11); /* about L = -z: ccw is -L */
            }
            CHECK_REL(R, 1 / kappa, 1.0 / (n * n));
            /* tip angle: the distal frame of the last segment has turned by kappa L */
            cbm_quat q;
            CHECK_OK(cbm_plant_distal_frame(p, (size_t)n - 1, &q));
            double hx = 1 - 2 * (q.y * q.y + q.z * q.z), hy = 2 * (q.x * q.y + q.w * q.z);
            double ang = atan2(hy, hx);
            CHECK_NEAR(ang, -PI / 2, 1e-11); /* 270 degrees = -90 */
        } else {
            /* chain: nodes on the circle of radius h/(2 sin(kappa h/2)) through the base, but the
             * first chord is already turned by kappa h: the centre is rotated by kappa h / 2 */
            double R = h / (2 * sin(kappa * h / 2));
            double cx = -R * sin(kappa * h / 2), cy = R * cos(kappa * h / 2);
            for (int i = 0; i < n; i++) {
                cbm_segment_state s;
                CHECK_OK(cbm_plant_segment(p, (size_t)i, &s));
                CHECK_NEAR(hypot(s.distal.x - cx, s.distal.y - cy), R, 1e-12 * R);
            }
        }
        cbm_plant_destroy(p);
    }
    test_ctx_end(ctx);
}

/* Large-deflection elastica with a vertical tip load on a horizontal cantilever: tip position
 * against Mattiasson (1981, Int. J. Numer. Meth. Eng. 17, Table 1; the elliptic-integral solution
 * of Bisshopp & Drucker 1945), v/L and (L - u)/L for P L^2 / EI = 1, 2, 5, 10, and against the
 * shooting reference. */
TEST(mech_elastica_tip_load)
{
    cbm_context *ctx = test_ctx();
    struct {
        double k, v, du;
    } tab[] = {{1.0, 0.30172, 0.05643},
               {2.0, 0.49346, 0.16064},
               {5.0, 0.71379, 0.38763},
               {10.0, 0.81061, 0.55500}};
    double L = 1.0, E = 1e9, r = 0.01, EI = E * PI * r * r * r * r / 4;
    for (size_t c = 0; c < sizeof tab / sizeof *tab; c++) {
        double P = tab[c].k * EI / (L * L);
        elastica ref = elastica_solve(0.0, 0.0, P, 0.0, EI, L, 4000);
        CHECK_NEAR(-ref.y / L, tab[c].v, 6e-6);
        CHECK_NEAR(1 - ref.x / L, tab[c].du, 6e-6);
        double e[2];
        int ns[2] = {100, 200};
        cbm_vec3 t = {0, 0, 0};
        for (int k = 0; k < 2; k++) {
            solve_tip_y(ctx, ns[k], L, radius_uniform, E, 0.0, 0.0, CBM_MECH_STAGGERED, P, &t);
            e[k] = hypot(t.x - ref.x, t.y - ref.y) / L;
        }
        printf("PL^2/EI = %g: tip (%.6f, %.6f), reference (%.6f, %.6f), errors %.3g %.3g, "
               "order %.3f\n",
               tab[c].k, t.x, t.y, ref.x, ref.y, e[0], e[1], log2(e[0] / e[1]));
        CHECK(e[1] < 2e-5);
        CHECK(log2(e[0] / e[1]) > 1.9);
    }
    test_ctx_end(ctx);
}

/* Heavy elastica (self-weight) on a horizontal cantilever, alpha = w L^3 / EI = 1, 5, 10, 15:
 * the shooting reference, the values of the Jirasek digest (§2.4, 4 digits), and the convergence
 * order of both discretisations. */
TEST(mech_elastica_self_weight)
{
    cbm_context *ctx = test_ctx();
    struct {
        double alpha, x, y;
    } tab[] = {
        {1, 0.9912, -0.1235}, {5, 0.8467, -0.4959}, {10, 0.6564, -0.7002}, {15, 0.5296, -0.7860}};
    double L = 1.0, r = 0.01, rho = 1000.0, w = rho * PI * r * r * g0;
    for (size_t c = 0; c < sizeof tab / sizeof *tab; c++) {
        double EI = w * L * L * L / tab[c].alpha, E = EI / (PI * r * r * r * r / 4);
        elastica ref = elastica_solve(0.0, w, 0.0, 0.0, EI, L, 4000);
        CHECK_NEAR(ref.x, tab[c].x, 6e-5);
        CHECK_NEAR(ref.y, tab[c].y, 6e-5);
        for (int disc = 0; disc < 2; disc++) {
            double e[3];
            int ns[3] = {50, 100, 200};
            cbm_vec3 t = {0, 0, 0};
            for (int k = 0; k < 3; k++) {
                solve_tip_y(ctx, ns[k], L, radius_uniform, E, rho, 0.0,
                            (cbm_mech_discretization)disc, 0.0, &t);
                e[k] = hypot(t.x - ref.x, t.y - ref.y);
            }
            double o = log2(e[1] / e[2]);
            printf("alpha %g %s: tip(200) (%.6f, %.6f) ref (%.6f, %.6f) err %.3g %.3g %.3g "
                   "order %.3f\n",
                   tab[c].alpha, disc ? "chain" : "staggered", t.x, t.y, ref.x, ref.y, e[0], e[1],
                   e[2], o);
            if (disc == CBM_MECH_STAGGERED) {
                CHECK(e[2] < 1e-4);
                CHECK(o > 1.9 && o < 2.1);
            } else {
                CHECK(o > 0.9 && o < 1.1);
            }
        }
    }
    test_ctx_end(ctx);
}
