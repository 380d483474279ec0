/* Declared laterals (cbm_segment_def.lateral): a branch added before the segment that continues
 * its parent's axis, as L-system strings write it (I [I ...] I). The equilibrium must not depend
 * on the order in which the children were added, the continuation keeps the parent's order, and
 * the continuation survives the removal of its lateral sibling. */
#include "mech_testlib.h"

/* A horizontal main axis of 6 segments with a lateral at node 2 (after segment 2): the lateral
 * is added before the continuation (declared) or after it (automatic). Returns the plant. */
static cbm_plant *axis_with_lateral(cbm_context *ctx, bool lateral_first)
{
    cbm_plant *p = clamped_plant(ctx, 0.2);
    if (!p)
        return NULL;
    cbm_segment_def d = cbm_segment_def_default();
    d.length = 0.1;
    d.core.youngs_modulus = 2e8;
    d.core.shear_modulus = 2e8 / 2.6;
    d.core.density = 700;
    d.core.a = d.core.b = 0.006;
    /* main axis segments 0..2 */
    for (int i = 0; i < 3; i++) {
        d.parent = i - 1;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    cbm_segment_def lat = d;
    lat.parent = 2;
    lat.divergence = 0.7;
    lat.deviation = 0.9;
    lat.core.a = lat.core.b = 0.004;
    lat.point_mass = 0.03;
    lat.lateral = lateral_first;
    cbm_segment_def cont = d;
    cont.parent = 2;
    if (lateral_first) /* the lateral is 3, the continuation 4 */
        CHECK_OK(cbm_plant_add_segment(p, &lat, NULL));
    CHECK_OK(cbm_plant_add_segment(p, &cont, NULL));
    if (!lateral_first) /* the continuation is 3, the lateral 4 */
        CHECK_OK(cbm_plant_add_segment(p, &lat, NULL));
    int64_t c_ix = lateral_first ? 4 : 3;
    /* the rest of the main axis, then a second lateral segment */
    for (int i = 0; i < 2; i++) {
        d.parent = i == 0 ? c_ix : 5;
        d.point_mass = i == 1 ? 0.02 : 0;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL)); /* 5, 6 */
    }
    return p;
}

TEST(mech_lateral_order_of_children_does_not_matter)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *a = axis_with_lateral(ctx, false), *b = axis_with_lateral(ctx, true);
    CHECK(a && b);
    if (a && b) {
        cbm_solve_def sd = cbm_solve_def_default();
        sd.tolerance = 1e-12;
        cbm_solve_stats st;
        CHECK_OK(cbm_plant_solve(a, &sd, &st));
        CHECK_OK(cbm_plant_solve(b, &sd, &st));
        /* a: 0 1 2 | 3 = continuation, 4 = lateral; b: 3 = lateral, 4 = continuation */
        const int map[7] = {0, 1, 2, 4, 3, 5, 6};
        for (int i = 0; i < 7; i++) {
            cbm_segment_state sa, sb;
            CHECK_OK(cbm_plant_segment(a, (size_t)i, &sa));
            CHECK_OK(cbm_plant_segment(b, (size_t)map[i], &sb));
            CHECK_NEAR(sa.distal.x, sb.distal.x, 1e-12);
            CHECK_NEAR(sa.distal.y, sb.distal.y, 1e-12);
            CHECK_NEAR(sa.distal.z, sb.distal.z, 1e-12);
            CHECK_EQ_INT(sa.order, sb.order);
            CHECK_EQ_INT(sa.continuation, sb.continuation);
        }
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(b, 3, &s));
        CHECK(!s.continuation);
        CHECK_EQ_INT(s.order, 1);
        CHECK_OK(cbm_plant_segment(b, 4, &s));
        CHECK(s.continuation);
        CHECK_EQ_INT(s.order, 0);
        /* removing the lateral keeps the continuation */
        size_t removed = 0;
        CHECK_OK(cbm_plant_remove_subtree(b, 3, &removed));
        CHECK_EQ_INT(removed, 1);
        CHECK_OK(cbm_plant_segment(b, 3, &s));
        CHECK(s.continuation);
        CHECK_EQ_INT(s.order, 0);
    }
    cbm_plant_destroy(a);
    cbm_plant_destroy(b);
    test_ctx_end(ctx);
}
