/* Breakage (Taylor-Hell 8.26-8.27): a horizontal self-weighted branch grown segment by segment
 * breaks at the length where the root stress M a / I with M = w L^2 / 2 reaches the modulus of
 * rupture; what a broken segment carries goes with it and is reported; a thick base moves the
 * break to a thinner segment (Fig. 8.8b); the rest of the tree springs back. */
#include "mech_testlib.h"
#include "core/vecmath.h"

TEST(growth_branch_breaks_at_predicted_length)
{
    cbm_context *ctx = test_ctx();
    const double r = 0.01, rho = 600, g = 9.81, mor = 1e6, h = 0.01;
    /* sigma = (w L^2 / 2) r / (pi r^4 / 4), w = rho pi r^2 g  =>  L* = sqrt(MOR r / (2 rho g)) */
    double lstar = sqrt(mor * r / (2 * rho * g));
    size_t want = (size_t)ceil(lstar / h);
    cbm_plant *p = clamped_plant(ctx, 0.0);
    cbm_segment_def d = cbm_segment_def_default();
    d.length = h;
    d.core.youngs_modulus = 1e11; /* stiff: small deflection */
    d.core.shear_modulus = 1e11 / 16;
    d.core.density = rho;
    d.core.a = d.core.b = r;
    d.core.modulus_of_rupture = mor;
    size_t broke_at = 0, nb = 0, nrm = 0, idx[4];
    for (size_t n = 1; n <= 200 && !broke_at; n++) {
        d.parent = (int64_t)n - 2;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
        CHECK_OK(cbm_plant_solve(p, NULL, NULL));
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(p, 0, &s));
        /* the solver's own root moment against w L^2 / 2 */
        double L = (double)n * h, w = rho * PI * r * r * g;
        CHECK_REL(s.stress, (w * L * L / 2) * r / (PI * pow(r, 4) / 4), 1e-6);
        CHECK_OK(cbm_plant_break(p, idx, 4, &nb, &nrm));
        if (nb) {
            broke_at = n;
            CHECK_EQ_INT(nb, 1);
            CHECK_EQ_INT(idx[0], 0);
            CHECK_EQ_INT(nrm, n);
            CHECK_EQ_INT(cbm_plant_segment_count(p), 0);
        }
    }
    printf("predicted L* = %.5f m -> breaks at %zu segments of %.2f m; broke at %zu\n", lstar, want,
           h, broke_at);
    CHECK_EQ_INT(broke_at, want);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* A vertical trunk (never breaks: MOR 0) with a horizontal branch carrying a twig and a fruit
 * that grows until the branch breaks at its base: the branch and the twig are removed and
 * reported, the trunk springs back upright. */
TEST(growth_breakage_removes_what_it_carries)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = clamped_plant(ctx, PI / 2);
    cbm_segment_def d = cbm_segment_def_default();
    d.core.youngs_modulus = 1e10;
    d.core.a = d.core.b = 0.02;
    add_axis(p, &d, 5); /* trunk 0..4 */
    d.core.a = d.core.b = 0.005;
    d.core.modulus_of_rupture = 5e7;
    d.parent = 2; /* branch 5, 6, 7 from the third trunk segment */
    d.deviation = PI / 2;
    CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    d.deviation = 0;
    d.parent = 5;
    CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    d.parent = 6;
    CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    d.parent = 6; /* twig 8 on segment 6 */
    d.deviation = 0.5;
    d.core.a = d.core.b = 0.003;
    CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    d.parent = 2; /* trunk segment 9, a lateral continuing upward (never breaks) */
    d.deviation = 0;
    d.core.modulus_of_rupture = 0;
    CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    CHECK_OK(cbm_plant_solve(p, NULL, NULL));
    cbm_segment_state s4;
    CHECK_OK(cbm_plant_segment(p, 4, &s4));
    double bent_x = hypot(s4.distal.x, s4.distal.z);
    /* a fruit growing on the branch tip until it breaks */
    size_t nb = 0, nrm = 0, idx[4];
    double m = 0;
    for (int k = 0; k < 400 && !nb; k++) {
        m += 0.01;
        CHECK_OK(cbm_plant_set_load(p, 7, m, v3(0, 0, 0), v3(0, 0, 0)));
        CHECK_OK(cbm_plant_solve(p, NULL, NULL));
        CHECK_OK(cbm_plant_segment(p, 4, &s4));
        bent_x = hypot(s4.distal.x, s4.distal.z);
        CHECK_OK(cbm_plant_break(p, idx, 4, &nb, &nrm));
    }
    printf("fruit of %.2f kg broke segment %zu, removing %zu segments\n", m, idx[0], nrm);
    CHECK_EQ_INT(nb, 1);
    CHECK_EQ_INT(idx[0], 5);
    CHECK_EQ_INT(nrm, 4); /* 5, 6, 7 and the twig 8 */
    CHECK_EQ_INT(cbm_plant_segment_count(p), 6);
    /* topological arrays compacted: the old segment 9 is now 5, still on the trunk */
    CHECK_EQ_INT(cbm_plant_parents(p)[5], 2);
    CHECK_OK(cbm_plant_solve(p, NULL, NULL));
    CHECK_OK(cbm_plant_segment(p, 4, &s4));
    double after = hypot(s4.distal.x, s4.distal.z);
    printf("trunk top off the vertical: loaded %.3e m, after the break %.3e m\n", bent_x, after);
    CHECK(bent_x > 1e-4);
    CHECK(after < 1e-12); /* springs back upright */
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* A thick base moves the break to a thinner segment (Fig. 8.8b): the stress M a / I ~ M / a^3
 * is largest where the section is thin although the moment is largest at the base. */
TEST(growth_break_at_thin_segment)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = clamped_plant(ctx, 0.0);
    cbm_segment_def d = cbm_segment_def_default();
    d.core.youngs_modulus = 1e10;
    d.core.modulus_of_rupture = 3e7;
    for (int i = 0; i < 6; i++) {
        d.parent = i - 1;
        d.core.a = d.core.b = i < 3 ? 0.02 : 0.006;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    size_t nb = 0, nrm = 0, idx[2];
    double m = 0;
    for (int k = 0; k < 1000 && !nb; k++) {
        m += 0.005;
        CHECK_OK(cbm_plant_set_load(p, 5, m, v3(0, 0, 0), v3(0, 0, 0)));
        CHECK_OK(cbm_plant_solve(p, NULL, NULL));
        CHECK_OK(cbm_plant_break(p, idx, 2, &nb, &nrm));
    }
    printf("fruit of %.3f kg broke segment %zu (removed %zu)\n", m, idx[0], nrm);
    CHECK_EQ_INT(nb, 1);
    CHECK_EQ_INT(idx[0], 3);
    CHECK_EQ_INT(nrm, 3);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Fig. 8.9: a horizontal branch whose fruit grows each step, with reaction wood. With a low
 * modulus of rupture it breaks before the reaction wood can act; with a high one the reaction
 * wood forms and it does not break. */
static void fruit_season(cbm_context *ctx, double mor, size_t *broken, size_t *rw_rings)
{
    cbm_plant *p = clamped_plant(ctx, 0.2);
    cbm_segment_def d = cbm_segment_def_default();
    d.length = 0.05;
    d.core.youngs_modulus = 1e9;
    d.core.shear_modulus = 1e9 / 16;
    d.core.density = 700;
    d.core.modulus_of_rupture = mor;
    for (int i = 0; i < 10; i++) {
        d.parent = i - 1;
        d.core.a = d.core.b = 0.004 * sqrt(10.0 - i);
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    cbm_growth_def g = cbm_growth_def_default();
    g.youngs_juvenile = 1e9;
    g.youngs_adult = 2e9;
    g.density = 700;
    g.modulus_of_rupture = mor;
    g.reaction_threshold = 0.05;
    g.reaction_beta = 0.3;
    g.reaction_increment = 0.0005;
    *broken = *rw_rings = 0;
    for (int k = 1; k <= 20 && cbm_plant_segment_count(p) == 10; k++) {
        CHECK_OK(cbm_plant_set_load(p, 9, 0.01 * k, v3(0, 0, 0), v3(0, 0, 0)));
        CHECK_OK(cbm_plant_solve(p, NULL, NULL));
        size_t nb = 0;
        CHECK_OK(cbm_plant_break(p, NULL, 0, &nb, NULL));
        *broken += nb;
        if (nb)
            break;
        cbm_growth_stats gs;
        CHECK_OK(cbm_plant_grow_rings(p, &g, &gs));
        *rw_rings += gs.reaction_rings;
    }
    cbm_plant_destroy(p);
}

TEST(growth_breakage_or_reaction_wood)
{
    cbm_context *ctx = test_ctx();
    size_t b_lo, rw_lo, b_hi, rw_hi;
    fruit_season(ctx, 6e5, &b_lo, &rw_lo);
    fruit_season(ctx, 1e8, &b_hi, &rw_hi);
    printf("MOR 0.6 MPa: %zu breaks, %zu reaction rings; MOR 100 MPa: %zu breaks, %zu reaction "
           "rings\n",
           b_lo, rw_lo, b_hi, rw_hi);
    CHECK_EQ_INT(b_lo, 1);
    CHECK_EQ_INT(b_hi, 0);
    CHECK(rw_hi > rw_lo);
    test_ctx_end(ctx);
}
