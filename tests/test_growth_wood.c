/* Wood: ageing (Taylor-Hell 8.2) and the structural modulus (8.1, 8.5-8.6), reaction wood
 * (8.7-8.25): detection, ring material, ovalisation, and the righting of a lean over years. */
#include "mech_testlib.h"
#include "core/vecmath.h"

static cbm_growth_def wood(void)
{
    cbm_growth_def g = cbm_growth_def_default();
    g.youngs_juvenile = 1e9;
    g.youngs_adult = 2e9;
    g.adult_age = 10.0;
    g.shear_ratio = 1.0 / 16.0;
    return g;
}

/* E of every ring rises linearly from E_juv to E_adult over adult_age years and stops there;
 * G keeps its ratio; the structural modulus C_L / I_L is the I-weighted mean of the rings' E. */
TEST(growth_wood_ageing_rate_and_structural_modulus)
{
    cbm_context *ctx = test_ctx();
    cbm_growth_def g = wood();
    cbm_plant *p = make_rod(ctx, 3, 0.3, radius_uniform, 1e9, 600, PI / 2, CBM_MECH_STAGGERED);
    for (size_t i = 0; i < 3; i++) {
        cbm_ring r;
        CHECK_OK(cbm_plant_get_ring(p, i, 0, &r));
        r.shear_modulus = 1e9 / 16;
        CHECK_OK(cbm_plant_set_ring(p, i, 0, &r));
    }
    CHECK_OK(cbm_plant_solve(p, NULL, NULL));
    for (int year = 1; year <= 14; year++) {
        /* a new ring each year on segment 0, then everything ages a year */
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(p, 0, &s));
        CHECK_OK(cbm_plant_add_growth_ring(p, 0, s.a + 0.001, s.b + 0.001, &g, NULL));
        CHECK_OK(cbm_plant_age_wood(p, &g, 1.0));
        CHECK_OK(cbm_plant_solve(p, NULL, NULL));
    }
    /* the core of segment 1 is 14 years old: adult since year 10 */
    cbm_ring r;
    CHECK_OK(cbm_plant_get_ring(p, 1, 0, &r));
    CHECK_REL(r.youngs_modulus, 2e9, 1e-14);
    CHECK_REL(r.shear_modulus, 2e9 / 16, 1e-14);
    CHECK_REL(r.age, 14.0, 1e-14);
    /* ring k of segment 0 (k = 1..14) was laid down in year k and is 15 - k years old */
    cbm_segment_state s;
    CHECK_OK(cbm_plant_segment(p, 0, &s));
    CHECK_EQ_INT(s.ring_count, 15);
    double num = 0.0, i_in = 0.0;
    for (size_t k = 0; k < 15; k++) {
        CHECK_OK(cbm_plant_get_ring(p, 0, k, &r));
        double age = k == 0 ? 14.0 : 15.0 - (double)k;
        double e = fmin(2e9, 1e9 + age * 1e8);
        CHECK_REL(r.youngs_modulus, e, 1e-13);
        CHECK_REL(r.shear_modulus / r.youngs_modulus, 1.0 / 16, 1e-13);
        double il;
        cbm_mech_ellipse_moments(r.a, r.b, &il, NULL, NULL);
        num += r.youngs_modulus * (il - i_in);
        i_in = il;
    }
    double es, gs;
    CHECK_OK(cbm_plant_structural_modulus(p, 0, &es, &gs));
    CHECK_REL(es, num / i_in, 1e-12);
    CHECK_REL(es * i_in, s.rigidity.y, 1e-12);
    CHECK(es > 1e9 && es < 2e9);
    CHECK_REL(gs, es / 16, 1e-12); /* circles: J = 2 I and G/E = 1/16 in every ring */
    printf("segment 0 after 14 years: structural E = %.4g Pa (juvenile 1e9, adult 2e9)\n", es);
    cbm_plant_destroy(p);

    /* the listing's core ageing: merge to the structural modulus, then + dt (Ea - Ej)/T */
    p = make_rod(ctx, 1, 0.1, radius_uniform, 1e9, 600, PI / 2, CBM_MECH_STAGGERED);
    CHECK_OK(cbm_plant_solve(p, NULL, NULL));
    g.ageing = CBM_AGEING_CORE;
    g.youngs_juvenile = 1.5e9; /* a stiffer new ring */
    CHECK_OK(cbm_plant_add_growth_ring(p, 0, 0.012, 0.012, &g, NULL));
    CHECK_OK(cbm_plant_structural_modulus(p, 0, &es, NULL));
    CHECK_OK(cbm_plant_segment(p, 0, &s));
    cbm_vec3 rest = s.rest_rate;
    CHECK_OK(cbm_plant_age_wood(p, &g, 2.0));
    double es2;
    CHECK_OK(cbm_plant_structural_modulus(p, 0, &es2, NULL));
    CHECK_EQ_INT(cbm_plant_ring_count(p, 0), 1);
    CHECK_REL(es2, es + 2.0 * (2e9 - 1.5e9) / 10.0, 1e-12);
    CHECK_OK(cbm_plant_segment(p, 0, &s));
    CHECK(v3_norm(v3_sub(s.rest_rate, rest)) <= 1e-12 * (1 + v3_norm(rest)));
    CHECK_OK(cbm_plant_age_wood(p, &g, 100.0));
    CHECK_OK(cbm_plant_structural_modulus(p, 0, &es2, NULL));
    CHECK_REL(es2, 2e9, 1e-14);
    CHECK_STATUS(cbm_plant_age_wood(p, &g, -1.0), CBM_E_INVALID);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Detection and material of reaction wood on one loaded segment. */
TEST(growth_reaction_wood_ring)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = make_rod(ctx, 1, 0.2, radius_uniform, 1e9, 0, 0.0, CBM_MECH_CHAIN);
    CHECK_OK(cbm_plant_set_load(p, 0, 0.0, (cbm_vec3){0, -2.0, 0}, (cbm_vec3){0, 0, 0}));
    CHECK_OK(cbm_plant_solve(p, NULL, NULL));
    cbm_segment_state s;
    CHECK_OK(cbm_plant_segment(p, 0, &s));
    double dev = v3_norm(v3_sub(s.rate, s.rest_rate));
    cbm_growth_def g = wood();
    g.reaction_beta = 0.3;
    /* below the threshold: normal wood */
    g.reaction_threshold = 1.01 * dev;
    bool rw = true;
    CHECK_OK(cbm_plant_add_growth_ring(p, 0, 0.011, 0.011, &g, &rw));
    CHECK(!rw);
    cbm_ring r;
    CHECK_OK(cbm_plant_get_ring(p, 0, 1, &r));
    CHECK(r.reaction == 0.0 && r.youngs_modulus == 1e9);
    CHECK_OK(cbm_plant_solve(p, NULL, NULL));
    /* above: E_ring = (E_rw + E_juv)/2 with E_rw = E_adult, rest = (1 - beta) Omega + beta rest */
    CHECK_OK(cbm_plant_segment(p, 0, &s));
    g.reaction_threshold = 0.5 * v3_norm(v3_sub(s.rate, s.rest_rate));
    CHECK_OK(cbm_plant_add_growth_ring(p, 0, 0.012, 0.011, &g, &rw));
    CHECK(rw);
    CHECK_OK(cbm_plant_get_ring(p, 0, 2, &r));
    CHECK_REL(r.youngs_modulus, 1.5e9, 1e-15);
    CHECK_REL(r.shear_modulus, 1.5e9 / 16, 1e-15);
    CHECK(r.reaction == 0.5);
    cbm_vec3 want = v3_add(v3_scale(s.rate, 0.7), v3_scale(s.rest_rate, 0.3));
    CHECK(v3_norm(v3_sub(r.rest_rate, want)) < 1e-12 * v3_norm(want));
    /* the section: I_L = pi a^3 b / 4 for the ellipse (a along U), rings outer minus inner */
    cbm_segment_state s2;
    CHECK_OK(cbm_plant_segment(p, 0, &s2));
    double cl =
        1e9 * PI * pow(0.011, 4) / 4 + 1.5e9 * PI * (pow(0.012, 3) * 0.011 - pow(0.011, 4)) / 4;
    CHECK_REL(s2.rigidity.y, cl, 1e-12);
    double cu =
        1e9 * PI * pow(0.011, 4) / 4 + 1.5e9 * PI * (0.012 * pow(0.011, 3) - pow(0.011, 4)) / 4;
    CHECK_REL(s2.rigidity.z, cu, 1e-12);
    CHECK(s2.reaction > 0.0 && s2.reaction < 0.5);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* A stem grown upright (its rest shape curves from 30 degrees at the clamp to vertical at the
 * tip, as tropism leaves it) that leans under its weight and a fruit, with pipe-model growth
 * for some years: tip elevation per year. The equilibrium position of reaction wood is the rest
 * shape (8.7), so righting means moving back towards it. */
static void lean_years(cbm_context *ctx, double threshold, double beta, int years, double *elev)
{
    const int n = 20;
    const double a0 = 0.003;
    cbm_plant *p = clamped_plant(ctx, 30.0 * PI / 180.0);
    cbm_segment_def d = cbm_segment_def_default();
    d.length = 0.1;
    d.core.youngs_modulus = 1e9;
    d.core.shear_modulus = 1e9 / 16;
    d.core.density = 600;
    for (int i = 0; i < n; i++) {
        d.parent = i - 1;
        d.core.a = d.core.b = a0 * sqrt((double)(n - i)); /* pipe-model taper */
        /* counter-clockwise rest curvature (L = -z): 60 degrees over the 2 m stem */
        d.core.rest_rate = v3(0.0, -(PI / 3.0) / 2.0, 0.0);
        d.omega = d.core.rest_rate;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    CHECK_OK(cbm_plant_set_load(p, (size_t)n - 1, 0.1, v3(0, 0, 0), v3(0, 0, 0)));
    cbm_growth_def g = cbm_growth_def_default();
    g.youngs_juvenile = 1e9;
    g.youngs_adult = 2e9;
    g.shear_ratio = 1.0 / 16;
    g.density = 600;
    g.reaction_threshold = threshold;
    g.reaction_beta = beta;
    g.reaction_increment = 0.0005;
    cbm_solve_def sd = cbm_solve_def_default();
    sd.tolerance = 1e-10;
    for (int y = 0; y <= years; y++) {
        CHECK_OK(cbm_plant_solve(p, &sd, NULL));
        cbm_quat q;
        CHECK_OK(cbm_plant_distal_frame(p, (size_t)n - 1, &q));
        cbm_vec3 h = q_rotate(q, v3(1, 0, 0));
        elev[y] = atan2(h.y, sqrt(h.x * h.x + h.z * h.z)) * 180.0 / PI;
        g.leaf_area = PI * a0 * a0 * (1.0 + 0.25 * (y + 1)); /* more leaves each year */
        CHECK_OK(cbm_plant_grow_rings(p, &g, NULL));
    }
    cbm_plant_destroy(p);
}

TEST(growth_reaction_wood_rights_a_lean)
{
    cbm_context *ctx = test_ctx();
    enum { Y = 10 };
    double none[Y + 1], rw[Y + 1], beta0[Y + 1];
    lean_years(ctx, INFINITY, 0.0, Y, none);
    lean_years(ctx, 0.005, 0.5, Y, rw);
    lean_years(ctx, 0.005, 0.0, Y, beta0);
    for (int y = 0; y <= Y; y++)
        printf("year %2d: tip elevation %.3f deg without reaction wood, %.3f with (beta 0.5), "
               "%.3f with beta 0\n",
               y, none[y], rw[y], beta0[y]);
    CHECK_NEAR(rw[0], none[0], 1e-12);
    /* with reaction wood the tip rises year after year (until the deviation falls below the
     * threshold xi) and ends well above where it started, below the rest shape's 90 degrees */
    for (int y = 1; y <= Y; y++)
        CHECK(rw[y] >= rw[y - 1] - 0.01);
    CHECK(rw[1] > rw[0] + 1.0);
    CHECK(rw[Y] > rw[0] + 4.0 && rw[Y] < 90.0);
    CHECK(90.0 - rw[Y] < 0.6 * (90.0 - rw[0]));
    /* without it the lean is frozen and the added wood only adds weight: no righting */
    CHECK(none[Y] <= none[0] + 1e-9);
    /* beta = 0: stiffer, ovalised rings but no growth strain: no righting either */
    CHECK(beta0[Y] <= beta0[0] + 1e-9);
    test_ctx_end(ctx);
}

/* The increment follows the lean (reaction_full_lean > 0): a horizontal cantilever of three
 * segments bent down by a tip load leans more from its set-point (its straight rest shape) the
 * further out a segment is, theta_i = sum_{j<i} |Omega_j| l + |Omega_i| l / 2 (one plane, one
 * sign of curvature), and segment i lays increment x min(1, sin theta_i / sin full). With the
 * fixed increment (the old law, full lean 0) all three lay the same. */
TEST(growth_reaction_increment_follows_lean)
{
    cbm_context *ctx = test_ctx();
    for (int pass = 0; pass < 2; pass++) {
        cbm_plant *p = make_rod(ctx, 3, 0.6, radius_uniform, 1e9, 0, 0.0, CBM_MECH_STAGGERED);
        CHECK_OK(cbm_plant_set_load(p, 2, 0.0, (cbm_vec3){0, -10.0, 0}, (cbm_vec3){0, 0, 0}));
        CHECK_OK(cbm_plant_solve(p, NULL, NULL));
        double theta[3], a0[3], sum = 0.0;
        for (size_t i = 0; i < 3; i++) {
            cbm_segment_state s;
            CHECK_OK(cbm_plant_segment(p, i, &s));
            double turn = v3_norm(v3_sub(s.rate, s.rest_rate)) * s.length;
            theta[i] = sum + 0.5 * turn;
            sum += turn;
            a0[i] = s.a;
        }
        /* about 4, 10 and 13 deg: the first two below the full lean, the tip beyond it */
        CHECK(theta[0] > 0.02 && theta[2] < 0.8 && theta[0] < theta[1] && theta[1] < theta[2]);
        cbm_growth_def g = wood();
        g.pipe_rate = 1e-12; /* no pipe-model growth: a grows by the reaction increment alone */
        g.reaction_threshold = 0.0;
        g.reaction_increment = 1e-3;
        const double full = 0.2;
        g.reaction_full_lean = pass ? full : 0.0;
        CHECK_OK(cbm_plant_grow_rings(p, &g, NULL));
        for (size_t i = 0; i < 3; i++) {
            cbm_segment_state s;
            CHECK_OK(cbm_plant_segment(p, i, &s));
            double dose = sin(theta[i]) / sin(full);
            double want = 1e-3 * (pass ? (dose < 1.0 ? dose : 1.0) : 1.0);
            printf("full lean %.1f: segment %zu lean %.4f rad, increment %.4g m (want %.4g)\n",
                   g.reaction_full_lean, i, theta[i], s.a - a0[i], want);
            CHECK_REL(s.a - a0[i], want, 1e-6);
        }
        cbm_plant_destroy(p);
    }
    test_ctx_end(ctx);
}

/* Bad input is named and changes nothing. */
TEST(growth_errors)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = make_rod(ctx, 2, 0.2, radius_uniform, 1e9, 600, 0.0, CBM_MECH_STAGGERED);
    CHECK_OK(cbm_plant_solve(p, NULL, NULL));
    cbm_growth_def g = wood();
    CHECK_STATUS(cbm_plant_add_growth_ring(p, 7, 0.02, 0.02, &g, NULL), CBM_E_INVALID);
    CHECK(strstr(cbm_context_last_error(ctx), "segment 7") != NULL);
    CHECK_STATUS(cbm_plant_add_growth_ring(p, 0, 0.005, 0.005, &g, NULL), CBM_E_INVALID);
    CHECK(strstr(cbm_context_last_error(ctx), "enclose") != NULL);
    CHECK_EQ_INT(cbm_plant_ring_count(p, 0), 1);
    static const struct {
        const char *field;
        int which;
    } bad[] = {{"pipe_exponent", 0}, {"youngs_adult", 1}, {"reaction_beta", 2},
               {"shear_ratio", 3},   {"leaf_area", 4},    {"reaction_threshold", 5}};
    for (int k = 0; k < 6; k++) {
        cbm_growth_def b = wood();
        switch (bad[k].which) {
        case 0:
            b.pipe_exponent = 0;
            break;
        case 1:
            b.youngs_adult = 0.5 * b.youngs_juvenile;
            break;
        case 2:
            b.reaction_beta = 1.5;
            break;
        case 3:
            b.shear_ratio = NAN;
            break;
        case 4:
            b.leaf_area = -1;
            break;
        default:
            b.reaction_threshold = NAN;
            break;
        }
        CHECK_STATUS(cbm_plant_grow_rings(p, &b, NULL), CBM_E_INVALID);
        CHECK(strstr(cbm_context_last_error(ctx), bad[k].field) != NULL);
    }
    CHECK_EQ_INT(cbm_plant_ring_count(p, 0), 1);
    double e;
    CHECK_STATUS(cbm_plant_structural_modulus(p, 9, &e, NULL), CBM_E_INVALID);
    cbm_segment_def d = cbm_segment_def_default();
    d.parent = 5;
    double roll;
    CHECK_STATUS(cbm_plant_upright_roll(p, &d, &roll), CBM_E_INVALID);
    cbm_tropism t = cbm_tropism_default();
    t.strength = 0.1;
    CHECK_STATUS(cbm_plant_grow_segment(p, &d, &t, NULL), CBM_E_INVALID);
    CHECK(strstr(cbm_context_last_error(ctx), "parent") != NULL);
    CHECK_EQ_INT(cbm_plant_segment_count(p), 2);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}
