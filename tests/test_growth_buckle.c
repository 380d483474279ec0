/* Self-weight buckling (Taylor-Hell §6.3): Greenhill's constant from the discrete column by
 * bisection on the length, its convergence with the segment count (second order for the
 * staggered discretisation, first order for the seeds' chain), the six woods of Table 6.1 within
 * one segment, and the stability factor's meaning (a pushed column returns upright below it, not
 * above, under the nonlinear solver). */
#include "mech_testlib.h"

/* (9/4) j^2, j the first zero of J_{-1/3} (computed to 30 digits with mpmath) */
#define GREENHILL_EXACT 7.83734743894348

static double alpha_of(const cbm_buckle_def *d, double L)
{
    double w = d->density * PI * d->radius * d->radius * d->gravity;
    double ei = d->youngs_modulus * PI * pow(d->radius, 4) / 4.0;
    return w * L * L * L / ei;
}

TEST(growth_greenhill_constant_converges)
{
    cbm_context *ctx = test_ctx();
    cbm_buckle_def d = cbm_buckle_def_default();
    d.youngs_modulus = 8.77e9;
    d.density = 745;
    d.radius = 0.05;
    const size_t ns[] = {10, 20, 40, 80, 160};
    for (int disc = 0; disc < 2; disc++) {
        d.discretization = disc ? CBM_MECH_CHAIN : CBM_MECH_STAGGERED;
        double err[5];
        for (int k = 0; k < 5; k++) {
            double L;
            CHECK_OK(cbm_mech_buckle_length(ctx, &d, ns[k], 1e-10, &L));
            double a = alpha_of(&d, L);
            err[k] = a - GREENHILL_EXACT;
            printf("%s n=%4zu L_cr=%.9f alpha=%.9f err=%+.3e\n",
                   cbm_mech_discretization_name(d.discretization), ns[k], L, a, err[k]);
            if (k) {
                double order = log(fabs(err[k - 1] / err[k])) / log(2.0);
                printf("   observed order %.3f\n", order);
                if (disc == 0)
                    CHECK(order > 1.9 && order < 2.1);
                else if (k >= 2) /* first order, reached from below */
                    CHECK(order > 0.9 && order < 1.1);
            }
        }
        if (disc == 0) {
            /* second order: 160 segments within 1e-4 of Greenhill's constant */
            CHECK(fabs(err[4]) < 1e-4 * GREENHILL_EXACT);
            /* Richardson extrapolation of the last two to 1e-6 */
            double rich = GREENHILL_EXACT + (4.0 * err[4] - err[3]) / 3.0;
            printf("   Richardson %.9f\n", rich);
            CHECK_NEAR(rich, GREENHILL_EXACT, 1e-6 * GREENHILL_EXACT);
        } else {
            CHECK(fabs(err[4]) < 2e-2 * GREENHILL_EXACT);
        }
    }
    test_ctx_end(ctx);
}

/* Taylor-Hell Table 6.1: six woods, r = 0.05 m, 0.1 m segments, g = 9.81; the thesis' model
 * buckled within one segment of the predicted length. Predicted = first 0.1 m multiple at or
 * above the continuous Greenhill length (digest §4). */
TEST(growth_table_6_1_six_woods)
{
    cbm_context *ctx = test_ctx();
    static const struct {
        const char *name;
        double e_gpa, rho, thesis_model, thesis_predicted;
    } woods[] = {
        {"yellow poplar", 10.38, 427, 23.1, 23.0}, {"apple", 8.77, 745, 18.1, 18.1},
        {"black willow", 5.03, 408, 18.4, 18.4},   {"black oak", 11.31, 669, 20.4, 20.4},
        {"yellow birch", 14.53, 668, 22.1, 22.2},  {"silver maple", 6.22, 506, 18.3, 18.4},
    };
    for (int k = 0; k < 6; k++) {
        cbm_buckle_def d = cbm_buckle_def_default();
        d.youngs_modulus = woods[k].e_gpa * 1e9;
        d.density = woods[k].rho;
        d.radius = 0.05;
        d.segment = 0.1;
        d.gravity = 9.81;
        cbm_buckle_result r;
        CHECK_OK(cbm_mech_buckle(ctx, &d, &r));
        double predicted = ceil(r.greenhill_length / 0.1 - 1e-9) * 0.1;
        printf("%-14s buckles at %.1f m (thesis model %.1f, predicted %.1f), Greenhill %.4f m, "
               "factor %.5f / %.5f, %zu passes\n",
               woods[k].name, r.buckling_length, woods[k].thesis_model, predicted,
               r.greenhill_length, r.last_stable_factor, r.growth_factor, r.passes);
        CHECK_NEAR(predicted, woods[k].thesis_predicted, 1e-9);
        CHECK(fabs(r.buckling_length - predicted) <= 0.1 + 1e-9);
        CHECK(fabs(r.buckling_length - woods[k].thesis_model) <= 0.1 + 1e-9);
        CHECK(r.growth_factor >= 1.0 && r.last_stable_factor < 1.0);
        CHECK_EQ_INT(r.segments, (long)lround(r.buckling_length / 0.1));
    }
    test_ctx_end(ctx);
}

/* The factor decides what the nonlinear relaxation does with a finite push (the thesis'
 * protocol itself): two segments short of the buckling length the pushed column relaxes back
 * upright; two segments beyond it, it settles bent. */
static double relax_tip_offset(cbm_context *ctx, size_t n, const cbm_buckle_def *d)
{
    cbm_plant *p = clamped_plant(ctx, PI / 2);
    cbm_segment_def sd = cbm_segment_def_default();
    sd.length = d->segment;
    sd.core.youngs_modulus = d->youngs_modulus;
    sd.core.shear_modulus = d->youngs_modulus / 16;
    sd.core.density = d->density;
    sd.core.a = sd.core.b = d->radius;
    sd.omega = (cbm_vec3){0, 1e-3, 0};
    for (size_t i = 0; i < n; i++) {
        sd.parent = (int64_t)i - 1;
        CHECK_OK(cbm_plant_add_segment(p, &sd, NULL));
    }
    cbm_solve_def so = cbm_solve_def_default();
    so.solver = CBM_MECH_RELAX;
    so.alpha = 1.0;
    so.max_passes = 20000;
    so.tolerance = 1e-6;
    cbm_status s = cbm_plant_solve(p, &so, NULL);
    (void)s; /* near the critical length the relaxation is slow: the offset tells */
    cbm_vec3 t = rod_tip(p);
    cbm_plant_destroy(p);
    return sqrt(t.x * t.x + t.z * t.z);
}

TEST(growth_buckling_factor_matches_relaxation)
{
    cbm_context *ctx = test_ctx();
    cbm_buckle_def d = cbm_buckle_def_default();
    d.youngs_modulus = 8.77e9;
    d.density = 745;
    d.segment = 0.5; /* coarse column: 37 segments, fast */
    cbm_buckle_result r;
    CHECK_OK(cbm_mech_buckle(ctx, &d, &r));
    double below = relax_tip_offset(ctx, r.segments - 2, &d);
    double above = relax_tip_offset(ctx, r.segments + 2, &d);
    printf("buckling at %zu segments; tip offset after relaxing a push: %zu -> %.3e m, %zu -> "
           "%.3e m\n",
           r.segments, r.segments - 2, below, r.segments + 2, above);
    CHECK(below < 1e-4);
    CHECK(above > 0.1);
    test_ctx_end(ctx);
}

TEST(growth_buckle_errors)
{
    cbm_context *ctx = test_ctx();
    cbm_buckle_def d = cbm_buckle_def_default();
    cbm_buckle_result r;
    d.radius = -1;
    CHECK_STATUS(cbm_mech_buckle(ctx, &d, &r), CBM_E_INVALID);
    CHECK(strstr(cbm_context_last_error(ctx), "radius") != NULL);
    d = cbm_buckle_def_default();
    d.density = NAN;
    CHECK_STATUS(cbm_mech_buckle(ctx, &d, &r), CBM_E_INVALID);
    d = cbm_buckle_def_default();
    d.max_segments = 50; /* the 10 GPa column needs ~200 */
    CHECK_STATUS(cbm_mech_buckle(ctx, &d, &r), CBM_E_LIMIT);
    test_ctx_end(ctx);
}

/* The protocol literally: one column grown a segment at a time, the push followed after each
 * segment; the factor rises with every segment and first reaches 1 at the count the bisection
 * of cbm_mech_buckle finds. */
TEST(growth_buckle_sequential_growth_agrees)
{
    cbm_context *ctx = test_ctx();
    cbm_buckle_def d = cbm_buckle_def_default();
    d.youngs_modulus = 8.77e9;
    d.density = 745;
    cbm_buckle_result r;
    CHECK_OK(cbm_mech_buckle(ctx, &d, &r));
    cbm_plant *p = clamped_plant(ctx, PI / 2);
    cbm_segment_def sd = cbm_segment_def_default();
    sd.length = d.segment;
    sd.core.youngs_modulus = d.youngs_modulus;
    sd.core.shear_modulus = d.youngs_modulus / 16;
    sd.core.density = d.density;
    sd.core.a = sd.core.b = d.radius;
    double prev = 0.0;
    size_t first = 0;
    for (size_t n = 1; n <= r.segments + 5; n++) {
        sd.parent = (int64_t)n - 2;
        CHECK_OK(cbm_plant_add_segment(p, &sd, NULL));
        double f;
        CHECK_OK(cbm_plant_stability_factor(p, &f, NULL));
        CHECK(f > prev);
        prev = f;
        if (!first && f >= 1.0)
            first = n;
    }
    printf("grown one segment at a time: first failure at %zu segments (bisection: %zu)\n", first,
           r.segments);
    CHECK_EQ_INT(first, r.segments);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}
