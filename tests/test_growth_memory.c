/* Growth memory: tropism rest curvature of new segments (Taylor-Hell 6.8-6.12), shape memory of
 * new rings (6.29-6.34 = Jirasek eq. 24) and its limits, the pipe model (4.1-4.3, 8.17). */
#include "mech_testlib.h"
#include "core/vecmath.h"
#include "mech/growth_internal.h"

static cbm_growth_def weightless_wood(void)
{
    cbm_growth_def g = cbm_growth_def_default();
    g.youngs_juvenile = g.youngs_adult = 2e7;
    g.shear_ratio = 1.0 / 2.6;
    g.density = 0.0; /* rings add no load */
    return g;
}

static double tip_shift(const cbm_plant *p, cbm_vec3 t0)
{
    cbm_vec3 t = rod_tip(p);
    return v3_norm(v3_sub(t, t0));
}

/* A ring added under unchanged load leaves the shape unchanged: to round-off for the chain
 * (one joint per segment), to O(h^2) for the staggered discretisation (a joint spans two half
 * segments whose moments differ by O(h)). */
TEST(growth_ring_under_unchanged_load_keeps_shape)
{
    cbm_context *ctx = test_ctx();
    cbm_growth_def g = weightless_wood();
    cbm_solve_def sd = cbm_solve_def_default();
    sd.tolerance = 1e-13;
    double prev = 0.0;
    for (int disc = 0; disc < 2; disc++) {
        for (int n = 20; n <= 80; n *= 2) {
            cbm_mech_discretization dz = disc ? CBM_MECH_CHAIN : CBM_MECH_STAGGERED;
            cbm_plant *p = make_rod(ctx, n, 1.0, radius_uniform, 2e7, 800, 0.3, dz);
            CHECK_OK(cbm_plant_solve(p, &sd, NULL));
            cbm_vec3 t0 = rod_tip(p);
            for (size_t i = 0; i < (size_t)n; i++) {
                bool rw = true;
                CHECK_OK(cbm_plant_add_growth_ring(p, i, 0.013, 0.013, &g, &rw));
                CHECK(!rw);
            }
            cbm_segment_state s0;
            CHECK_OK(cbm_plant_segment(p, 0, &s0));
            CHECK_EQ_INT(s0.ring_count, 2);
            CHECK_OK(cbm_plant_solve(p, &sd, NULL));
            double d = tip_shift(p, t0);
            printf("%s n=%d: tip moved %.3e m (tip deflection %.3f m)\n",
                   cbm_mech_discretization_name(dz), n, d, 1.0 * cos(0.3) - t0.x);
            if (disc) {
                CHECK(d < 1e-12);
            } else {
                CHECK(d < 2e-3);
                if (n > 20) {
                    double order = log(prev / d) / log(2.0);
                    printf("   observed order %.2f\n", order);
                    CHECK(order > 1.8 && order < 2.3);
                }
                prev = d;
            }
            cbm_plant_destroy(p);
        }
    }
    test_ctx_end(ctx);
}

/* Radial growth under a constant load freezes the curvature: with each ring the rest rate moves
 * to the current one (|Omega - rest| shrinks as C / (C + C'), eq. 24), the shape stays. */
TEST(growth_radial_growth_freezes_curvature)
{
    cbm_context *ctx = test_ctx();
    cbm_growth_def g = weightless_wood();
    cbm_solve_def sd = cbm_solve_def_default();
    sd.tolerance = 1e-13;
    int n = 30;
    cbm_plant *p = make_rod(ctx, n, 1.0, radius_uniform, 2e7, 800, 0.0, CBM_MECH_CHAIN);
    CHECK_OK(cbm_plant_set_load(p, n - 1, 0.02, (cbm_vec3){0, 0, 0}, (cbm_vec3){0, 0, 0}));
    CHECK_OK(cbm_plant_solve(p, &sd, NULL));
    cbm_vec3 t0 = rod_tip(p);
    double dev0 = 0.0;
    for (int i = 0; i < n; i++) {
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(p, (size_t)i, &s));
        dev0 = fmax(dev0, v3_norm(v3_sub(s.omega, s.rest_rate)));
    }
    double dev = dev0;
    for (int year = 1; year <= 8; year++) {
        double r = 0.01 * (1.0 + 0.15 * year);
        for (int i = 0; i < n; i++)
            CHECK_OK(cbm_plant_add_growth_ring(p, (size_t)i, r, r, &g, NULL));
        CHECK_OK(cbm_plant_solve(p, &sd, NULL));
        double d = 0.0;
        for (int i = 0; i < n; i++) {
            cbm_segment_state s;
            CHECK_OK(cbm_plant_segment(p, (size_t)i, &s));
            d = fmax(d, v3_norm(v3_sub(s.omega, s.rest_rate)));
        }
        /* the previous ratio C / (C + C') bounds the decrease: C ~ r^4 */
        double rp = 0.01 * (1.0 + 0.15 * (year - 1));
        double ratio = pow(rp / r, 4);
        printf("year %d: max |Omega - rest| = %.4e (ratio %.4f, C/(C+C') %.4f), tip moved %.2e\n",
               year, d, d / dev, ratio, tip_shift(p, t0));
        CHECK_NEAR(d / dev, ratio, 1e-6);
        CHECK(tip_shift(p, t0) < 1e-12);
        dev = d;
    }
    CHECK(dev < 0.05 * dev0);
    /* unloading now springs back only to the frozen shape: the tip stays close to the loaded
     * position (the rest shape memorised the sag) */
    CHECK_OK(cbm_plant_set_load(p, n - 1, 0.0, (cbm_vec3){0, 0, 0}, (cbm_vec3){0, 0, 0}));
    CHECK_OK(cbm_plant_solve(p, &sd, NULL));
    CHECK(fabs(rod_tip(p).y - t0.y) < 0.06 * fabs(t0.y));
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Limits of eq. 24 on one segment: a ring of negligible rigidity keeps the rest rate; a ring
 * much stiffer than the core takes the rest rate to the memorised rate; in between the
 * rigidity-weighted mean per component (torsion weighted by GJ, bending by EI_L and EI_U). */
TEST(growth_eq24_limits)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = make_rod(ctx, 1, 0.1, radius_uniform, 1e9, 0, 0.0, CBM_MECH_CHAIN);
    CHECK_OK(cbm_plant_set_load(p, 0, 0, (cbm_vec3){0, 0, 0}, (cbm_vec3){0.3, 0.2, -0.5}));
    CHECK_OK(cbm_plant_solve(p, NULL, NULL));
    cbm_segment_state s;
    CHECK_OK(cbm_plant_segment(p, 0, &s));
    cbm_vec3 om = s.rate, r0 = s.rest_rate, c0 = s.rigidity;
    CHECK(v3_norm(v3_sub(om, r0)) > 1e-3);
    cbm_growth_def g = cbm_growth_def_default();
    g.youngs_juvenile = g.youngs_adult = 1e9;
    g.shear_ratio = 1 / 2.6;
    g.density = 0;
    g.memory = CBM_MEMORY_JOINT; /* the chain: the joint rate is the segment rate */
    /* C' -> 0: a ring 1e-9 of the radius thick */
    CHECK_OK(cbm_plant_add_growth_ring(p, 0, 0.01 * (1 + 1e-9), 0.01 * (1 + 1e-9), &g, NULL));
    CHECK_OK(cbm_plant_segment(p, 0, &s));
    CHECK(v3_norm(v3_sub(s.rest_rate, r0)) < 1e-8 * v3_norm(v3_sub(om, r0)));
    /* in between: the exact weighted mean */
    cbm_vec3 c1 = s.rigidity, r1 = s.rest_rate;
    CHECK_OK(cbm_plant_add_growth_ring(p, 0, 0.012, 0.012, &g, NULL));
    CHECK_OK(cbm_plant_segment(p, 0, &s));
    cbm_vec3 cr = v3_sub(s.rigidity, c1);
    CHECK_REL(s.rest_rate.x, (c1.x * r1.x + cr.x * om.x) / (c1.x + cr.x), 1e-12);
    CHECK_REL(s.rest_rate.y, (c1.y * r1.y + cr.y * om.y) / (c1.y + cr.y), 1e-12);
    CHECK_REL(s.rest_rate.z, (c1.z * r1.z + cr.z * om.z) / (c1.z + cr.z), 1e-12);
    /* C' >> C: a ring 100 times the radius: rest -> Omega to (C / C')  ~ 1e-8 */
    cbm_vec3 r2 = s.rest_rate;
    CHECK_OK(cbm_plant_add_growth_ring(p, 0, 1.0, 1.0, &g, NULL));
    CHECK_OK(cbm_plant_segment(p, 0, &s));
    CHECK(v3_norm(v3_sub(s.rest_rate, om)) < 1e-7 * v3_norm(v3_sub(om, r2)));
    (void)c0;
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Tropism (6.8-6.12): a new segment on a horizontal parent with an upward tropism F gets the
 * rest rate (l_p x F) / C that turns it upward; the direction is settable; strength 0 = none. */
TEST(growth_tropism_rest_curvature)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = make_rod(ctx, 1, 0.2, radius_uniform, 1e9, 0, 0.0, CBM_MECH_CHAIN);
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    cbm_tropism t = cbm_tropism_default();
    t.strength = 0.5;
    cbm_segment_def d = cbm_segment_def_default();
    d.parent = 0;
    d.length = 0.1;
    d.core.youngs_modulus = 1e9;
    d.core.shear_modulus = 1e9 / 2.6;
    d.core.a = d.core.b = 0.01;
    size_t k;
    CHECK_OK(cbm_plant_grow_segment(p, &d, &t, &k));
    cbm_segment_state s;
    CHECK_OK(cbm_plant_segment(p, k, &s));
    /* world torque l_p x F = 0.2 (1,0,0) x 0.5 (0,1,0) = (0, 0, 0.1); L = -z in the clamp frame */
    double ei = 1e9 * PI * 1e-8 / 4;
    CHECK_NEAR(s.rest_rate.x, 0.0, 1e-15);
    CHECK_REL(s.rest_rate.y, -0.1 / ei, 1e-12);
    CHECK_NEAR(s.rest_rate.z, 0.0, 1e-15);
    CHECK(v3_norm(v3_sub(s.omega, s.rest_rate)) == 0.0);
    /* unloaded (no gravity), the new segment turns upward */
    cbm_plant_set_gravity(p, (cbm_vec3){0, 0, 0});
    CHECK_OK(cbm_plant_solve(p, NULL, NULL));
    CHECK_OK(cbm_plant_segment(p, k, &s));
    CHECK(s.frame.h.y > 0.0);
    /* another direction: towards +z */
    t.direction = (cbm_vec3){0, 0, 2};
    CHECK_OK(cbm_plant_grow_segment(p, &d, &t, &k));
    CHECK_OK(cbm_plant_segment(p, k, &s));
    CHECK(fabs(s.rest_rate.y) < 1e-12 && fabs(s.rest_rate.z) > 0);
    /* strength 0: straight */
    t.strength = 0;
    CHECK_OK(cbm_plant_grow_segment(p, &d, &t, &k));
    CHECK_OK(cbm_plant_segment(p, k, &s));
    CHECK(v3_norm(s.rest_rate) == 0.0);
    /* bad direction */
    t.strength = 1;
    t.direction = (cbm_vec3){0, 0, 0};
    CHECK_STATUS(cbm_plant_grow_segment(p, &d, &t, NULL), CBM_E_INVALID);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* A stem grown segment by segment with an upward tropism ends higher than one without (the
 * S-shape of Fig. 6.7 needs gravity; here both sag under it). */
TEST(growth_tropism_raises_growing_stem)
{
    cbm_context *ctx = test_ctx();
    double tip_y[2];
    for (int k = 0; k < 2; k++) {
        cbm_plant *p = clamped_plant(ctx, 0.5);
        cbm_tropism t = cbm_tropism_default();
        t.strength = k ? 0.5 : 0.0;
        cbm_segment_def d = cbm_segment_def_default();
        d.length = 0.05;
        d.core.youngs_modulus = 1e9;
        d.core.a = d.core.b = 0.004;
        for (int i = 0; i < 20; i++) {
            d.parent = i - 1;
            CHECK_OK(cbm_plant_grow_segment(p, &d, &t, NULL));
            CHECK_OK(cbm_plant_solve(p, NULL, NULL));
        }
        tip_y[k] = rod_tip(p).y;
        cbm_plant_destroy(p);
    }
    printf("tip height without tropism %.4f m, with %.4f m\n", tip_y[0], tip_y[1]);
    CHECK(tip_y[1] > tip_y[0] + 0.05);
    test_ctx_end(ctx);
}

/* A small tree: trunk 0-1-2, laterals on 0 and 1, sub-lateral. */
static cbm_plant *small_tree(cbm_context *ctx, double aspect)
{
    cbm_plant *p = clamped_plant(ctx, PI / 2);
    static const int64_t par[] = {-1, 0, 1, 0, 1, 4, 3};
    static const double rad[] = {0.004, 0.004, 0.004, 0.003, 0.003, 0.002, 0.002};
    for (int i = 0; i < 7; i++) {
        cbm_segment_def d = cbm_segment_def_default();
        d.parent = par[i];
        d.deviation = (i == 3 || i == 4) ? 0.7 : 0.0;
        d.core.a = rad[i];
        d.core.b = rad[i] * aspect;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    CHECK_OK(cbm_plant_solve(p, NULL, NULL));
    return p;
}

static double seg_area(const cbm_plant *p, size_t i)
{
    cbm_segment_state s;
    CHECK_OK(cbm_plant_segment(p, i, &s));
    return PI * s.a * s.b;
}

/* Pipe model: P = 2 conserves area at every node; P = 2.5 gives r_p^P = sum r_c^P for circles
 * (the area form 8.17 reproduces the radius form 4.1); ellipses keep b/a; kappa < 1 reaches the
 * fraction 4.3 of the way; girth never decreases; leaf_area gives Jirasek's count identity. */
TEST(growth_pipe_model_identities)
{
    cbm_context *ctx = test_ctx();
    static const int64_t par[] = {-1, 0, 1, 0, 1, 4, 3};
    /* circle limit of the ellipse formulas (8.9-8.11): I = pi r^4 / 4, J = pi r^4 / 2 */
    double il, iu, jj;
    cbm_mech_ellipse_moments(0.03, 0.03, &il, &iu, &jj);
    CHECK_REL(il, PI * pow(0.03, 4) / 4, 1e-15);
    CHECK_REL(iu, PI * pow(0.03, 4) / 4, 1e-15);
    CHECK_REL(jj, PI * pow(0.03, 4) / 2, 1e-15);
    /* P = 2, kappa = 1, with ellipses of aspect 0.7 */
    cbm_plant *p = small_tree(ctx, 0.7);
    cbm_growth_def g = cbm_growth_def_default();
    cbm_growth_stats gs;
    CHECK_OK(cbm_plant_grow_rings(p, &g, &gs));
    printf("P=2: %zu rings, largest increment %.3e m\n", gs.rings_added, gs.max_increment);
    CHECK_EQ_INT(gs.rings_added, 2);
    for (size_t i = 0; i < 7; i++) {
        double sum = 0;
        int nc = 0;
        for (size_t c = 0; c < 7; c++)
            if (par[c] == (int64_t)i) {
                sum += seg_area(p, c);
                nc++;
            }
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(p, i, &s));
        CHECK_REL(s.b / s.a, 0.7, 1e-12);
        if (nc)
            CHECK(seg_area(p, i) >= sum * (1 - 1e-12));
        if (nc && s.ring_count > 1)
            CHECK_REL(seg_area(p, i), sum, 1e-12);
    }
    cbm_plant_destroy(p);
    /* P = 2.5 on circles: radius form */
    p = small_tree(ctx, 1.0);
    g.pipe_exponent = 2.5;
    CHECK_OK(cbm_plant_grow_rings(p, &g, NULL));
    for (size_t i = 0; i < 7; i++) {
        double sum = 0;
        for (size_t c = 0; c < 7; c++)
            if (par[c] == (int64_t)i) {
                cbm_segment_state s;
                CHECK_OK(cbm_plant_segment(p, c, &s));
                sum += pow(s.a, 2.5);
            }
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(p, i, &s));
        if (s.ring_count > 1)
            CHECK_REL(pow(s.a, 2.5), sum, 1e-12);
    }
    /* girth never decreases: thin the goal (fewer children) and grow again */
    double a_before[7];
    for (size_t i = 0; i < 7; i++) {
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(p, i, &s));
        a_before[i] = s.a;
    }
    size_t rm;
    CHECK_OK(cbm_plant_remove_subtree(p, 4, &rm));
    CHECK_EQ_INT(rm, 2);
    CHECK_OK(cbm_plant_solve(p, NULL, NULL));
    CHECK_OK(cbm_plant_grow_rings(p, &g, &gs));
    CHECK_EQ_INT(gs.rings_added, 0);
    for (size_t i = 0; i < 4; i++) {
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(p, i, &s));
        CHECK(s.a >= a_before[i]);
    }
    cbm_plant_destroy(p);
    /* kappa = 0.4: a' = a + 0.4 (a_goal - a) */
    p = small_tree(ctx, 1.0);
    g = cbm_growth_def_default();
    g.pipe_rate = 0.4;
    double a1 = 0.004;
    CHECK_OK(cbm_plant_grow_rings(p, &g, NULL));
    cbm_segment_state s1;
    CHECK_OK(cbm_plant_segment(p, 1, &s1));
    double goal1 = sqrt(0.004 * 0.004 + 0.003 * 0.003); /* children 2 and 4 */
    CHECK_REL(s1.a, a1 + 0.4 * (goal1 - a1), 1e-12);
    cbm_plant_destroy(p);
    /* leaf_area: an unbranched stem of n equal internodes grows to area A0 * (n - j) */
    p = make_rod(ctx, 6, 0.6, radius_uniform, 1e9, 600, PI / 2, CBM_MECH_STAGGERED);
    CHECK_OK(cbm_plant_solve(p, NULL, NULL));
    g = cbm_growth_def_default();
    g.leaf_area = PI * 1e-4;
    CHECK_OK(cbm_plant_grow_rings(p, &g, &gs));
    CHECK_EQ_INT(gs.rings_added, 5);
    for (size_t j = 0; j < 6; j++)
        CHECK_REL(seg_area(p, j), PI * 1e-4 * (double)(6 - j), 1e-12);
    /* bad definitions are named */
    g.pipe_rate = 1.5;
    CHECK_STATUS(cbm_plant_grow_rings(p, &g, NULL), CBM_E_INVALID);
    CHECK(strstr(cbm_context_last_error(ctx), "pipe_rate") != NULL);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

static cbm_status oom_growth(cbm_context *ctx, void *ud)
{
    (void)ud;
    cbm_plant *p = NULL;
    cbm_plant_def pd = cbm_plant_def_default();
    cbm_status s = cbm_plant_create(ctx, &pd, &p);
    if (s != CBM_OK)
        return s;
    cbm_segment_def d = cbm_segment_def_default();
    cbm_tropism t = cbm_tropism_default();
    t.strength = 0.01;
    for (int i = 0; i < 5 && s == CBM_OK; i++) {
        d.parent = i - 1;
        d.core.a = d.core.b = 0.01 - 0.001 * i;
        s = cbm_plant_grow_segment(p, &d, &t, NULL);
    }
    if (s == CBM_OK)
        s = cbm_plant_solve(p, NULL, NULL);
    cbm_growth_def g = cbm_growth_def_default();
    g.leaf_area = 1e-5;
    if (s == CBM_OK)
        s = cbm_plant_grow_rings(p, &g, NULL);
    size_t nb;
    if (s == CBM_OK)
        s = cbm_plant_break(p, NULL, 0, &nb, NULL);
    g.ageing = CBM_AGEING_CORE;
    g.adult_age = 5;
    if (s == CBM_OK)
        s = cbm_plant_age_wood(p, &g, 1.0);
    cbm_plant_destroy(p);
    if (s != CBM_OK)
        return s;
    cbm_buckle_def bd = cbm_buckle_def_default();
    bd.segment = 5.0; /* a few segments */
    cbm_buckle_result br;
    return cbm_mech_buckle(ctx, &bd, &br);
}

TEST(growth_out_of_memory)
{
    CHECK(test_oom_loop(oom_growth, NULL) > 0);
}

/* The upright roll (Taylor-Hell Fig. 8.4): after the roll U is perpendicular to H, as close to
 * up as possible (U . up = |up - (up . H) H|), a horizontal heading gets U = (0, 1, 0), and a
 * vertical heading needs no roll. */
TEST(growth_upright_roll)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = clamped_plant(ctx, PI / 2);
    cbm_segment_def d = cbm_segment_def_default();
    CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    double roll = 1.0;
    d.parent = 0;
    CHECK_OK(cbm_plant_upright_roll(p, &d, &roll)); /* vertical heading */
    CHECK(roll == 0.0);
    for (int k = 0; k < 12; k++) {
        d.divergence = 0.7 * k;
        d.deviation = k == 6 ? -PI / 2 : 0.15 * k - 0.8; /* k = 6: horizontal */
        CHECK_OK(cbm_plant_upright_roll(p, &d, &roll));
        d.roll = roll;
        size_t i;
        CHECK_OK(cbm_plant_add_segment(p, &d, &i));
        CHECK_OK(cbm_plant_evaluate(p, NULL));
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(p, i, &s));
        cbm_vec3 h = s.frame.h, u = s.frame.u;
        CHECK_NEAR(v3_dot(u, h), 0.0, 1e-12);
        cbm_vec3 up = {0, 1, 0};
        double best = v3_norm(v3_sub(up, v3_scale(h, v3_dot(up, h))));
        CHECK_NEAR(v3_dot(u, up), best, 1e-12);
        if (k == 6) {
            CHECK_NEAR(h.y, 0.0, 1e-12);
            CHECK_NEAR(u.y, 1.0, 1e-12);
        }
        d.roll = 0;
    }
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* The rates a ring memorises, computed for the whole plant at once (O(n)), are the per-segment
 * query's rate (CBM_MEMORY_SEGMENT) and omega (CBM_MEMORY_JOINT), on a branched tree with tip
 * moments, for both discretisations. */
TEST(growth_rates_match_segment_query)
{
    cbm_context *ctx = test_ctx();
    for (int disc = 0; disc < 2; disc++) {
        cbm_plant_def pd = cbm_plant_def_default();
        pd.base_orientation = cbm_mech_clamp_orientation(PI / 2);
        pd.discretization = disc ? CBM_MECH_CHAIN : CBM_MECH_STAGGERED;
        cbm_plant *p = NULL;
        CHECK_OK(cbm_plant_create(ctx, &pd, &p));
        for (int i = 0; i < 60; i++) {
            cbm_segment_def d = cbm_segment_def_default();
            if (i > 0) {
                double u = cbm_context_uniform(ctx);
                d.parent = (int64_t)(i - 1 - (int)(u * u * u * i));
                d.divergence = 2.4 * i;
                d.deviation = cbm_context_uniform(ctx) - 0.5;
            }
            d.core.youngs_modulus = 2e8;
            d.core.a = 0.01 / (1 + 0.05 * i);
            d.core.b = 0.8 * d.core.a;
            if (i % 7 == 3)
                d.tip_moment = (cbm_vec3){0.001, -0.002, 0.0005};
            CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
        }
        CHECK_OK(cbm_plant_solve(p, NULL, NULL));
        cbm_vec3 r[60], o[60];
        CHECK_OK(cbm__growth_rates(p, CBM_MEMORY_SEGMENT, r));
        CHECK_OK(cbm__growth_rates(p, CBM_MEMORY_JOINT, o));
        for (size_t i = 0; i < 60; i++) {
            cbm_segment_state s;
            CHECK_OK(cbm_plant_segment(p, i, &s));
            CHECK(v3_norm(v3_sub(r[i], s.rate)) <= 1e-12 * (1 + v3_norm(s.rate)));
            CHECK(v3_norm(v3_sub(o[i], s.omega)) == 0.0);
        }
        cbm_plant_destroy(p);
    }
    test_ctx_end(ctx);
}

/* Fig. 6.7: self-weight, negative geotropism and radial growth give an S-shaped stem: the old,
 * thick base part has memorised its sag and leans away, the young distal part turns back up. The
 * elevation of the stem along its length first falls, then rises to the tip. */
TEST(growth_s_shaped_stem)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = clamped_plant(ctx, 70.0 * PI / 180.0);
    const double a0 = 0.002;
    cbm_tropism t = cbm_tropism_default();
    t.strength = 0.05;
    cbm_growth_def g = cbm_growth_def_default();
    g.youngs_juvenile = g.youngs_adult = 1e8;
    g.density = 700;
    g.leaf_area = PI * a0 * a0;
    cbm_segment_def d = cbm_segment_def_default();
    d.length = 0.05;
    d.core.youngs_modulus = 1e8;
    d.core.shear_modulus = 1e8 / 16;
    d.core.density = 700;
    d.core.a = d.core.b = a0;
    const int n = 40;
    for (int i = 0; i < n; i++) {
        d.parent = i - 1;
        CHECK_OK(cbm_plant_grow_segment(p, &d, &t, NULL));
        CHECK_OK(cbm_plant_solve(p, NULL, NULL));
        CHECK_OK(cbm_plant_grow_rings(p, &g, NULL));
        CHECK_OK(cbm_plant_solve(p, NULL, NULL));
    }
    double el[40], lo = 1e9;
    int imin = 0;
    for (int i = 0; i < n; i++) {
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(p, (size_t)i, &s));
        el[i] = asin(s.frame.h.y) * 180.0 / PI;
        if (el[i] < lo) {
            lo = el[i];
            imin = i;
        }
    }
    printf("elevation: base %.1f deg, lowest %.1f deg at segment %d, tip %.1f deg\n", el[0], lo,
           imin, el[n - 1]);
    CHECK(imin > 2 && imin < n - 3);
    CHECK(el[0] > lo + 5.0);
    CHECK(el[n - 1] > lo + 5.0);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}
