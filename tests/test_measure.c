/* The forester's measures (cambium/measure.h) on hand-made tables whose answers are known:
 * height, breast-height diameter, crown, buckling height, pipe exponent, branch angles, stress
 * quantiles; branch intersections on crossing, touching, adjacent and looping configurations,
 * and the spatial grid against the exhaustive pair test. */
#include "test.h"
#include "mech_testlib.h"

#include <stdlib.h>
#include <string.h>

static cbm_measure_segment seg(int64_t parent, bool lateral, cbm_vec3 p0, cbm_vec3 p1, double r0,
                               double r1)
{
    return (cbm_measure_segment){parent, lateral, p0, p1, r0, r1, NAN, NAN, NAN};
}

static cbm_vec3 V(double x, double y, double z)
{
    return (cbm_vec3){x, y, z};
}

static size_t count_pairs(cbm_context *ctx, const cbm_measure_segment *s, size_t n,
                          unsigned char *flags, size_t *segs)
{
    size_t ni = 0, np = 0;
    CHECK_OK(cbm_measure_intersections(ctx, s, n, &ni, &np, flags));
    if (segs)
        *segs = ni;
    return np;
}

/* Two roots crossing at right angles, axes 5 cm apart, radii 10 cm: they meet. */
TEST(intersections_crossing)
{
    cbm_context *ctx = test_ctx();
    cbm_measure_segment s[3] = {
        seg(-1, false, V(-1, 1, 0), V(1, 1, 0), 0.1, 0.1),
        seg(-1, false, V(0, 0, 0.05), V(0, 2, 0.05), 0.1, 0.1),
        seg(-1, false, V(5, 0, 0), V(5, 1, 0), 0.1, 0.1), /* far away */
    };
    unsigned char fl[3];
    size_t ni = 0;
    CHECK_EQ_INT(count_pairs(ctx, s, 3, fl, &ni), 1);
    CHECK_EQ_INT(ni, 2);
    CHECK(fl[0] && fl[1] && !fl[2]);
    test_ctx_end(ctx);
}

/* Parallel tubes at a distance d of radii 0.1 and 0.05: they meet iff d < 0.15 (touching is not
 * meeting); cones meet by the radii interpolated at the closest points. */
TEST(intersections_touching)
{
    cbm_context *ctx = test_ctx();
    const double d[] = {0.3, 0.15 + 1e-9, 0.15 - 1e-9, 0.01};
    const int want[] = {0, 0, 1, 1};
    for (int k = 0; k < 4; k++) {
        cbm_measure_segment s[2] = {seg(-1, false, V(0, 0, 0), V(0, 1, 0), 0.1, 0.1),
                                    seg(-1, false, V(d[k], 0, 0), V(d[k], 1, 0), 0.05, 0.05)};
        CHECK_MSG((int)count_pairs(ctx, s, 2, NULL, NULL) == want[k], "distance %.10g", d[k]);
    }
    /* a cone from r 0.2 at y=0 to 0 at y=2 beside a thin rod at x = 0.12 crossing it at y=1.5
     * (cone radius 0.05 there) misses; at y=0.5 (radius 0.15) it meets */
    cbm_measure_segment c[2] = {seg(-1, false, V(0, 0, 0), V(0, 2, 0), 0.2, 0.0),
                                seg(-1, false, V(0.12, 1.5, -1), V(0.12, 1.5, 1), 0.01, 0.01)};
    CHECK_EQ_INT(count_pairs(ctx, c, 2, NULL, NULL), 0);
    c[1].p0.y = c[1].p1.y = 0.5;
    CHECK_EQ_INT(count_pairs(ctx, c, 2, NULL, NULL), 1);
    /* zero radii (lines) never meet, even crossing */
    cbm_measure_segment z[2] = {seg(-1, false, V(-1, 0, 0), V(1, 0, 0), 0, 0),
                                seg(-1, false, V(0, -1, 0), V(0, 1, 0), 0, 0)};
    CHECK_EQ_INT(count_pairs(ctx, z, 2, NULL, NULL), 0);
    test_ctx_end(ctx);
}

/* A fat trunk of short segments with a fork of fat siblings and a lateral at 45 degrees: every
 * overlap is at a junction (parent/child, siblings, the lateral inside the trunk's wood), none
 * counts. */
TEST(intersections_adjacent_excluded)
{
    cbm_context *ctx = test_ctx();
    cbm_measure_segment s[8];
    double r = 0.1, h = 0.05; /* segments shorter than the radius */
    s[0] = seg(-1, false, V(0, 0, 0), V(0, h, 0), r, r);
    s[1] = seg(0, false, V(0, h, 0), V(0, 2 * h, 0), r, r);
    s[2] = seg(1, false, V(0, 2 * h, 0), V(0, 3 * h, 0), r, r);
    s[3] = seg(2, false, V(0, 3 * h, 0), V(0, 4 * h, 0), r, r);
    /* a lateral at 45 degrees from the top of s[1], two segments, radius 0.05 */
    double c = sqrt(0.5) * 0.1;
    s[4] = seg(1, true, V(0, 2 * h, 0), V(c, 2 * h + c, 0), 0.05, 0.05);
    s[5] = seg(4, false, V(c, 2 * h + c, 0), V(2 * c, 2 * h + 2 * c, 0), 0.05, 0.05);
    /* a fork at the top: two fat siblings 20 degrees apart */
    double sx = sin(10 * PI / 180) * 0.3, sy = cos(10 * PI / 180) * 0.3;
    s[6] = seg(3, false, V(0, 4 * h, 0), V(sx, 4 * h + sy, 0), 0.08, 0.08);
    s[7] = seg(3, true, V(0, 4 * h, 0), V(-sx, 4 * h + sy, 0), 0.08, 0.08);
    unsigned char fl[8];
    CHECK_EQ_INT(count_pairs(ctx, s, 8, fl, NULL), 0);
    /* the same tubes with no tree between them (all roots) do meet */
    for (int i = 0; i < 8; i++)
        s[i].parent = -1;
    CHECK(count_pairs(ctx, s, 8, fl, NULL) >= 8);
    test_ctx_end(ctx);
}

/* A limb that leaves the trunk, climbs, and turns back through the trunk 1 m above its junction
 * counts; the trunk segment it passes and the limb's crossing segment are flagged. */
TEST(intersections_loop_through)
{
    cbm_context *ctx = test_ctx();
    cbm_measure_segment s[16];
    size_t n = 0;
    for (int k = 0; k < 10; k++, n++) /* trunk 0..2 m, radius 5 cm */
        s[n] = seg(k - 1, false, V(0, 0.2 * k, 0), V(0, 0.2 * (k + 1), 0), 0.05, 0.05);
    /* limb from the top of s[1] (0.4 m): out to x = 0.6, up to 1.5 m, back across to x = -0.6 */
    s[n++] = seg(1, true, V(0, 0.4, 0), V(0.6, 0.6, 0), 0.02, 0.02);         /* 10 */
    s[n++] = seg(10, false, V(0.6, 0.6, 0), V(0.6, 1.5, 0), 0.02, 0.02);     /* 11 */
    s[n++] = seg(11, false, V(0.6, 1.5, 0), V(-0.6, 1.5, 0.01), 0.02, 0.02); /* 12 */
    unsigned char fl[16];
    size_t ni = 0;
    CHECK_EQ_INT(count_pairs(ctx, s, n, fl, &ni), 1);
    CHECK_EQ_INT(ni, 2);
    CHECK(fl[12] && fl[7]); /* the trunk segment from 1.4 to 1.6 m */
    for (size_t i = 0; i < n; i++)
        if (i != 12 && i != 7)
            CHECK_MSG(!fl[i], "segment %zu flagged", i);
    test_ctx_end(ctx);
}

/* Stems clamped at one point (the stems of a spur, separate roots of the table) join there:
 * three thin stems leaving one base point at 15 degrees from one another overlap at it, which
 * is their junction; the same stems with their bases 2 cm apart do not join, and the two that
 * overlap there count. */
TEST(intersections_roots_at_one_point)
{
    cbm_context *ctx = test_ctx();
    cbm_measure_segment s[6];
    double r = 0.002, l = 0.03;
    for (int k = 0; k < 3; k++) {
        double a = (double)(k - 1) * 15 * PI / 180;
        cbm_vec3 d = V(sin(a) * l, cos(a) * l, 0);
        s[2 * k] = seg(-1, false, V(0, 0, 0), d, r, r);
        s[2 * k + 1] = seg(2 * k, false, d, V(2 * d.x, 2 * d.y, 0), r, r);
    }
    unsigned char fl[6];
    CHECK_EQ_INT(count_pairs(ctx, s, 6, fl, NULL), 0);
    /* the middle stem's base moved 2 cm down along its own line: it now grows through the
     * others' bases (no common point) */
    s[2].p0 = V(0, -0.02, 0);
    CHECK(count_pairs(ctx, s, 6, fl, NULL) >= 2);
    CHECK(fl[2]);
    test_ctx_end(ctx);
}

/* Siblings that leave a thick axis's end close together overlap in the knot of that node (the
 * ball of the largest radius there): a trunk of radius 6 cm carries two fronds of radius 3 mm
 * 8 degrees apart, cut in 1 cm segments; they overlap up to 4.3 cm out, inside the knot, and do not
 * count. A frond that curls back and crosses the other 9 cm out counts: the knot ends at R. */
TEST(intersections_knot_of_a_node)
{
    cbm_context *ctx = test_ctx();
    enum { NS = 12 };
    cbm_measure_segment s[1 + 2 * NS + 2];
    size_t n = 0;
    s[n++] = seg(-1, false, V(0, 0, 0), V(0, 0.25, 0), 0.06, 0.06);
    for (int f = 0; f < 2; f++) {
        double a = (f ? 34.0 : 26.0) * PI / 180; /* from the vertical, 8 degrees apart */
        cbm_vec3 d = V(sin(a) * 0.01, cos(a) * 0.01, 0);
        for (int k = 0; k < NS; k++, n++)
            s[n] = seg(k ? (int64_t)n - 1 : 0, k == 0, V(d.x * k, 0.25 + d.y * k, 0),
                       V(d.x * (k + 1), 0.25 + d.y * (k + 1), 0), 0.003, 0.003);
    }
    unsigned char fl[1 + 2 * NS + 2];
    CHECK_EQ_INT(count_pairs(ctx, s, n, fl, NULL), 0);
    /* without the thick trunk (the fronds are roots at one point, radius 3 mm) the knot is 3 mm
     * and the overlap counts */
    cbm_measure_segment t[2 * NS];
    for (size_t i = 1; i < n; i++) {
        t[i - 1] = s[i];
        t[i - 1].parent = s[i].parent > 0 ? s[i].parent - 1 : -1;
    }
    CHECK(count_pairs(ctx, t, n - 1, NULL, NULL) >= 2);
    /* the first frond's tip turns across the second 20 cm out: counts */
    cbm_vec3 tip = s[NS].p1;
    s[n] = seg((int64_t)NS, false, tip, V(0.15, 0.36, 0.001), 0.003, 0.003);
    n++;
    s[n] = seg((int64_t)n - 1, false, s[n - 1].p1, V(-0.02, 0.30, 0.001), 0.003, 0.003);
    n++;
    CHECK(count_pairs(ctx, s, n, fl, NULL) >= 1);
    CHECK(fl[n - 1] || fl[n - 2]);
    test_ctx_end(ctx);
}

static double rnd(unsigned *state)
{
    *state = *state * 1103515245u + 12345u;
    return (double)(*state >> 8) / (double)(1u << 24);
}

/* The grid finds exactly the pairs the exhaustive test finds, over random tubes of mixed sizes
 * (a few long and fat ones among many small ones). */
TEST(intersections_grid_matches_all_pairs)
{
    cbm_context *ctx = test_ctx();
    enum { N = 400 };
    cbm_measure_segment *s = calloc(N, sizeof *s);
    unsigned st = 7;
    for (int i = 0; i < N; i++) {
        cbm_vec3 a = V(rnd(&st), rnd(&st), rnd(&st));
        double len = i % 50 == 0 ? 0.8 : 0.05 * rnd(&st);
        cbm_vec3 d = V(rnd(&st) - 0.5, rnd(&st) - 0.5, rnd(&st) - 0.5);
        double nd = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
        cbm_vec3 b = V(a.x + len * d.x / nd, a.y + len * d.y / nd, a.z + len * d.z / nd);
        double r = i % 97 == 0 ? 0.1 : 0.004 + 0.01 * rnd(&st);
        s[i] = seg(-1, false, a, b, r, r * 0.7);
    }
    unsigned char fl[N], brute[N] = {0};
    size_t ni = 0, np = count_pairs(ctx, s, N, fl, &ni);
    size_t bp = 0;
    for (int i = 0; i < N; i++)
        for (int j = i + 1; j < N; j++) {
            cbm_measure_segment two[2] = {s[i], s[j]};
            if (count_pairs(ctx, two, 2, NULL, NULL)) {
                bp++;
                brute[i] = brute[j] = 1;
            }
        }
    CHECK_EQ_INT(np, bp);
    CHECK(np > 20); /* the sample does exercise the narrow phase */
    CHECK(!memcmp(fl, brute, N));
    free(s);
    test_ctx_end(ctx);
}

/* A tree whose every measure is known by hand. Trunk: 4 vertical segments of 0.5 m, radius
 * tapering linearly 0.10 -> 0.06 m (the second from 0.085); at its top a fork into two children of
 * diameter D / sqrt(2) (pipe exponent exactly 2) at +-30 degrees; at 0.5 m a lateral at 45 degrees
 * of diameter 0.05 with D_parent = 0.18: exponent of (0.18; 0.17, 0.05) by bisection. */
TEST(summary_hand_made_tree)
{
    cbm_context *ctx = test_ctx();
    cbm_measure_segment s[8];
    size_t n = 0;
    for (int k = 0; k < 4; k++) {
        s[n] = seg(k ? (int64_t)n - 1 : -1, false, V(0, 0.5 * k, 0), V(0, 0.5 * (k + 1), 0),
                   0.10 - 0.01 * k, 0.10 - 0.01 * (k + 1));
        s[n].youngs_modulus = 10e9;
        s[n].density = 600 + 100 * k; /* median over the trunk up to 1.3 m: 700 */
        s[n].stress_ratio = 0.1 * (k + 1);
        n++;
    }
    /* the continuation above the lateral is thinner (0.17 m), the lateral 0.05 m, at 45 degrees
     * from the top of segment 0 (0.5 m) */
    s[1].r0 = 0.085;
    double c = sqrt(0.5);
    s[n++] = seg(0, true, V(0, 0.5, 0), V(c, 0.5 + c, 0), 0.025, 0.025);
    /* fork at 2 m: two children of radius 0.06 / sqrt(2), at +-30 degrees, 1 m long */
    double rc = 0.06 / sqrt(2.0), sx = 0.5, sy = sqrt(3.0) / 2;
    s[n++] = seg(3, false, V(0, 2, 0), V(sx, 2 + sy, 0), rc, rc);
    s[n++] = seg(3, true, V(0, 2, 0), V(-sx, 2 + sy, 0), rc, rc);
    for (size_t i = 4; i < n; i++)
        s[i].stress_ratio = 0.5 + 0.1 * (double)(i - 3); /* 0.6 0.7 0.8 */
    cbm_tree_measures m;
    cbm_measure_def def = cbm_measure_def_default();
    CHECK_OK(cbm_measure_segments(ctx, &def, s, n, &m));
    CHECK_EQ_INT(m.segments, 7);
    CHECK_EQ_INT(m.axes, 3); /* the trunk, the lateral, the fork's lateral */
    CHECK_EQ_INT(m.max_order, 1);
    CHECK_NEAR(m.height, 2 + sy, 1e-12);
    CHECK_NEAR(m.total_length, 2 + 1 + 1 + 1, 1e-12);
    /* 1.3 m lies in segment 2 (1.0..1.5 m), 60 % along: r = 0.08 - 0.6 * 0.01 = 0.074 */
    CHECK(!m.diameter_at_base);
    CHECK_NEAR(m.diameter, 0.148, 1e-12);
    CHECK_NEAR(m.base_diameter, 0.2, 1e-12);
    CHECK_NEAR(m.crown_width, sx + c, 1e-12); /* x from -0.5 (fork) to 0.7071 (lateral) */
    CHECK_NEAR(m.trunk_modulus, 10e9, 1e-3);
    CHECK_NEAR(m.trunk_density, 700, 1e-9);
    double hcr = 0.79 * cbrt(10e9 / (700 * 9.81)) * pow(0.148, 2.0 / 3.0);
    CHECK_REL(m.buckling_height, hcr, 1e-12);
    CHECK_REL(m.buckling_ratio, (2 + sy) / hcr, 1e-12);
    /* the crown starts where the 45-degree lateral leaves: 1 m of 5 m axis length >= 5 % */
    CHECK_NEAR(m.crown_base_height, 0.5, 1e-12);
    /* forks: at 0.5 m (0.18 -> 0.17 + 0.05) and at 2 m (0.12 -> 2 x 0.12/sqrt 2) */
    CHECK_EQ_INT(m.forks, 2);
    CHECK_EQ_INT(m.forks_unsolved, 0);
    CHECK_EQ_INT(m.pipe_exponent.count, 2);
    double x1 = 0.17 / 0.18, x2 = 0.05 / 0.18, a1 = m.pipe_exponent.min;
    CHECK_NEAR(pow(x1, a1) + pow(x2, a1), 1.0, 1e-9);
    CHECK_NEAR(m.pipe_exponent.max, 2.0, 1e-9);
    /* branch angles: the 45-degree lateral and the fork's lateral at 30 degrees */
    CHECK_EQ_INT(m.branch_angle.count, 2);
    CHECK_NEAR(m.branch_angle.min, PI / 6, 1e-12);
    CHECK_NEAR(m.branch_angle.max, PI / 4, 1e-12);
    CHECK_NEAR(m.branch_angle.median, (PI / 6 + PI / 4) / 2, 1e-12);
    /* stress ratios 0.1 0.2 0.3 0.4 0.6 0.7 0.8: median 0.4, 3 of 7 above 0.5 */
    CHECK_EQ_INT(m.stress_ratio.count, 7);
    CHECK_NEAR(m.stress_ratio.median, 0.4, 1e-12);
    CHECK_NEAR(m.stress_ratio.q25, 0.25, 1e-12);
    CHECK_NEAR(m.stress_ratio.q90, 0.74, 1e-12); /* 0.7 + 0.4 (0.8 - 0.7) */
    CHECK_NEAR(m.stress_above_half, 3.0 / 7.0, 1e-12);
    CHECK_EQ_INT(m.intersecting, 0);
    /* the lowest point: the trunk's base; a lateral hanging below the ground lowers it */
    CHECK_NEAR(m.lowest, 0.0, 1e-15);
    s[n - 1].p1 = V(-sx, -0.25, 0);
    CHECK_OK(cbm_measure_segments(ctx, &def, s, n, &m));
    CHECK_NEAR(m.lowest, -0.25, 1e-15);
    CHECK_NEAR(m.height, 2 + sy, 1e-12); /* from the base: the root's proximal end */
    test_ctx_end(ctx);
}

/* A tree shorter than breast height gets its base diameter; a table without wood properties
 * has no buckling height; a child as thick as its parent leaves its fork unsolved. */
TEST(summary_short_tree_and_unknowns)
{
    cbm_context *ctx = test_ctx();
    cbm_measure_segment s[3] = {seg(-1, false, V(0, 0, 0), V(0, 0.5, 0), 0.02, 0.01),
                                seg(0, false, V(0, 0.5, 0), V(0, 1.0, 0), 0.01, 0.01),
                                seg(0, true, V(0, 0.5, 0), V(0.3, 0.8, 0), 0.01, 0.01)};
    cbm_tree_measures m;
    CHECK_OK(cbm_measure_segments(ctx, NULL, s, 3, &m));
    CHECK(m.diameter_at_base);
    CHECK_NEAR(m.diameter, 0.04, 1e-15);
    CHECK(isnan(m.buckling_height) && isnan(m.buckling_ratio));
    CHECK_EQ_INT(m.forks, 1);
    CHECK_EQ_INT(m.forks_unsolved, 1);
    CHECK_EQ_INT(m.pipe_exponent.count, 0);
    CHECK(isnan(m.pipe_exponent.median));
    CHECK_EQ_INT(m.stress_ratio.count, 0);
    CHECK(isnan(m.stress_above_half));
    /* an empty table */
    CHECK_OK(cbm_measure_segments(ctx, NULL, NULL, 0, &m));
    CHECK_EQ_INT(m.segments, 0);
    CHECK(isnan(m.height));
    test_ctx_end(ctx);
}

TEST(summary_bad_tables)
{
    test_diags g;
    cbm_context *ctx = test_diag_ctx(&g);
    cbm_measure_segment s[2] = {seg(-1, false, V(0, 0, 0), V(0, 1, 0), 0.1, 0.1),
                                seg(1, false, V(0, 1, 0), V(0, 2, 0), 0.1, 0.1)};
    cbm_tree_measures m;
    CHECK_STATUS(cbm_measure_segments(ctx, NULL, s, 2, &m), CBM_E_INVALID);
    CHECK(strstr(cbm_context_last_error(ctx), "segment 1") != NULL);
    s[1].parent = 0;
    s[1].p1.x = NAN;
    CHECK_STATUS(cbm_measure_segments(ctx, NULL, s, 2, &m), CBM_E_INVALID);
    s[1].p1.x = 0;
    s[1].r0 = -1;
    CHECK_STATUS(cbm_measure_intersections(ctx, s, 2, NULL, NULL, NULL), CBM_E_INVALID);
    test_ctx_end(ctx);
}

/* The mechanical plant's table: E and density come back from the rings, the radius from the
 * semi-axes, the laterals from the plant's links. */
TEST(summary_of_a_plant)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = clamped_plant(ctx, PI / 2);
    cbm_segment_def d = cbm_segment_def_default();
    d.length = 0.5;
    d.core.youngs_modulus = 8e9;
    d.core.density = 750;
    d.core.a = 0.03;
    d.core.b = 0.02;
    d.core.modulus_of_rupture = 50e6;
    for (int k = 0; k < 4; k++) {
        d.parent = k - 1;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    d.parent = 1;
    d.lateral = true;
    d.deviation = PI / 4;
    d.core.a = d.core.b = 0.01;
    CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    double res = 0;
    CHECK_OK(cbm_plant_evaluate(p, &res));
    cbm_tree_measures m;
    CHECK_OK(cbm_measure_plant(ctx, NULL, p, &m));
    CHECK_EQ_INT(m.segments, 5);
    CHECK_EQ_INT(m.axes, 2);
    CHECK_NEAR(m.base_diameter, 0.05, 1e-12); /* a + b */
    CHECK_REL(m.trunk_modulus, 8e9, 1e-9);
    CHECK_REL(m.trunk_density, 750, 1e-9);
    CHECK_NEAR(m.branch_angle.median, PI / 4, 1e-6);
    CHECK_EQ_INT(m.stress_ratio.count, 5);
    CHECK(m.stress_ratio.max > 0 && m.stress_ratio.max < 0.5);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

static cbm_status oom_measure(cbm_context *ctx, void *ud)
{
    (void)ud;
    cbm_measure_segment s[6];
    for (int k = 0; k < 6; k++)
        s[k] = seg(k - 1, false, V(0.01 * k, k, 0), V(0.01 * (k + 1), k + 1, 0), 0.1, 0.1);
    s[5] = seg(-1, false, V(-1, 2.5, 0), V(1, 2.5, 0), 0.1, 0.1); /* crosses the trunk */
    cbm_tree_measures m;
    cbm_status st = cbm_measure_segments(ctx, NULL, s, 6, &m);
    if (st == CBM_OK && m.intersecting_pairs != 1)
        return CBM_E_INTERNAL;
    return st;
}

TEST(summary_allocation_failures)
{
    CHECK(test_oom_loop(oom_measure, NULL) > 3);
}
