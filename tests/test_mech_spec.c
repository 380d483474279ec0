/* The bend spec reader and job: every key parsed, errors with line and column, consistency
 * checks, the growth driver, and the replay of the fuzz corpus (tests/fuzz/corpus/spec). */
#define _POSIX_C_SOURCE 200809L
#include "test.h"
#include "cambium/bend.h"
#define CBM_FUZZ_NO_MAIN
#include "fuzz/fuzz_spec.c"

#include <stdlib.h>
#include <string.h>

TEST(mech_spec_every_key)
{
    test_diags s;
    cbm_context *ctx = test_diag_ctx(&s);
    CHECK(ctx != NULL);
    const char *text = "# all keys\n"
                       "length = 2.5   # m\n"
                       "segments = 64\n"
                       "radius = 0.03\n"
                       "radius_base = 0.04\n"
                       "radius_tip = 0.01\n"
                       "aspect = 0.8\n"
                       "E = 9e9\n"
                       "G = 6e8\n"
                       "density = 550\n"
                       "gravity = 9.8\n"
                       "angle = -15\n"
                       "tip_load = 2\n"
                       "tip_mass = 0.5\n"
                       "tip_moment = -0.25\n"
                       "rest_curvature = 0.1\n"
                       "tropism = 0.02\n"
                       "modulus_of_rupture = 6e7\n"
                       "solver = relax\n"
                       "tolerance = 1e-9\n"
                       "alpha = 0.25\n"
                       "max_passes = 5000\n"
                       "krylov_dim = 30\n"
                       "discretization = chain\n"
                       "steps = 4\n"
                       "length_initial = 1\n"
                       "radius_final = 0.05\n";
    cbm_bend_spec sp;
    CHECK_OK(cbm_bend_spec_parse(ctx, text, strlen(text), "all.spec", &sp));
    CHECK_NEAR(sp.length, 2.5, 0);
    CHECK_EQ_INT(sp.segments, 64);
    CHECK_NEAR(sp.radius, 0.03, 0);
    CHECK_NEAR(sp.radius_base, 0.04, 0);
    CHECK_NEAR(sp.radius_tip, 0.01, 0);
    CHECK_NEAR(sp.aspect, 0.8, 0);
    CHECK_NEAR(sp.youngs_modulus, 9e9, 0);
    CHECK_NEAR(sp.shear_modulus, 6e8, 0);
    CHECK_NEAR(sp.density, 550, 0);
    CHECK_NEAR(sp.gravity, 9.8, 0);
    CHECK_NEAR(sp.angle, -15, 0);
    CHECK_NEAR(sp.tip_load, 2, 0);
    CHECK_NEAR(sp.tip_mass, 0.5, 0);
    CHECK_NEAR(sp.tip_moment, -0.25, 0);
    CHECK_NEAR(sp.rest_curvature, 0.1, 0);
    CHECK_NEAR(sp.tropism, 0.02, 0);
    CHECK_NEAR(sp.modulus_of_rupture, 6e7, 0);
    CHECK(sp.solver == CBM_MECH_RELAX);
    CHECK_NEAR(sp.tolerance, 1e-9, 0);
    CHECK_NEAR(sp.alpha, 0.25, 0);
    CHECK_EQ_INT(sp.max_passes, 5000);
    CHECK_EQ_INT(sp.krylov_dim, 30);
    CHECK(sp.discretization == CBM_MECH_CHAIN);
    CHECK_EQ_INT(sp.steps, 4);
    CHECK_NEAR(sp.length_initial, 1, 0);
    CHECK_NEAR(sp.radius_final, 0.05, 0);
    CHECK_EQ_INT(s.count, 0);
    /* fast and newton are the same solver */
    CHECK_OK(cbm_bend_spec_parse(ctx, "solver = newton", 15, "x", &sp));
    CHECK(sp.solver == CBM_MECH_NEWTON);
    CHECK_OK(cbm_bend_spec_parse(ctx, "solver=fast\r\n", 13, "x", &sp));
    CHECK(sp.solver == CBM_MECH_NEWTON);
    /* empty spec: the defaults */
    CHECK_OK(cbm_bend_spec_parse(ctx, "", 0, "x", &sp));
    CHECK_EQ_INT(sp.segments, 100);
    CHECK_EQ_INT(cbm_context_bytes(ctx), 0);
    cbm_context_destroy(ctx);
}

TEST(mech_spec_errors)
{
    test_diags s;
    cbm_context *ctx = test_diag_ctx(&s);
    CHECK(ctx != NULL);
    const char *text = "length = 1\n"
                       "  colour = red\n"
                       "E = 1e9 2\n"
                       "density =\n"
                       "= 4\n"
                       "gravity = 1e999\n"
                       "steps = 1.5\n";
    cbm_bend_spec sp = cbm_bend_spec_default();
    sp.length = 42;
    CHECK_STATUS(cbm_bend_spec_parse(ctx, text, strlen(text), "e.spec", &sp), CBM_E_SEMANTIC);
    CHECK_NEAR(sp.length, 42, 0); /* untouched on failure */
    CHECK(strstr(s.text, "e.spec:2:3: unknown key 'colour'"));
    CHECK(strstr(s.text, "e.spec:3:9: unexpected text after the value of 'E'"));
    CHECK(strstr(s.text, "e.spec:4:10: missing value for 'density'"));
    CHECK(strstr(s.text, "e.spec:5:1: expected a key"));
    CHECK(strstr(s.text, "e.spec:6:11: 'gravity' expects a finite number"));
    CHECK(strstr(s.text, "e.spec:7:9: 'steps' expects a whole number"));
    CHECK_EQ_INT(s.count, 6);
    /* consistency */
    s.text[0] = 0;
    const char *t2 = "length = 1\nlength_initial = 2\nsteps = 3\n";
    CHECK_STATUS(cbm_bend_spec_parse(ctx, t2, strlen(t2), "c.spec", &sp), CBM_E_SEMANTIC);
    CHECK(strstr(s.text, "length_initial (2) must not exceed length (1)"));
    const char *t3 = "radius_final = 0.1\n";
    CHECK_STATUS(cbm_bend_spec_parse(ctx, t3, strlen(t3), "c.spec", &sp), CBM_E_SEMANTIC);
    /* segment limit from the context */
    cbm_limits lim = *cbm_context_limits(ctx);
    lim.max_segments = 10;
    cbm_context_set_limits(ctx, &lim);
    CHECK_STATUS(cbm_bend_spec_parse(ctx, "segments = 11", 13, "l.spec", &sp), CBM_E_LIMIT);
    CHECK_EQ_INT(cbm_context_bytes(ctx), 0);
    cbm_context_destroy(ctx);
}

TEST(mech_bend_job_static_and_growth)
{
    cbm_context *ctx = test_ctx();
    const char *text = "length = 1\nsegments = 30\nradius = 0.005\nE = 5e9\ndensity = 700\n"
                       "angle = 10\nsteps = 6\nlength_initial = 0.4\nradius_final = 0.012\n";
    cbm_bend_spec sp;
    CHECK_OK(cbm_bend_spec_parse(ctx, text, strlen(text), "g.spec", &sp));
    cbm_plant *p = NULL;
    cbm_bend_result r;
    CHECK_OK(cbm_bend_run(ctx, &sp, &p, &r));
    CHECK_EQ_INT(r.steps_done, 6);
    CHECK_EQ_INT(cbm_plant_segment_count(p), 30);
    cbm_segment_state st;
    CHECK_OK(cbm_plant_segment(p, 0, &st));
    CHECK_EQ_INT(st.ring_count, 7); /* core + one ring per step */
    CHECK_NEAR(st.a, 0.005 + 0.007, 1e-15);
    cbm_bend_node nodes[31];
    CHECK_OK(cbm_bend_nodes(p, nodes, 31));
    CHECK_NEAR(nodes[30].s, 1.0, 1e-12);
    CHECK_NEAR(nodes[0].angle_deg, 10.0, 1e-9);
    CHECK(nodes[30].y < nodes[30].x * tan(10 * 3.14159265358979 / 180)); /* it sags */
    /* shape memory: the same final rod solved statically (no memory) sags more */
    cbm_plant_destroy(p);
    const char *t2 = "length = 1\nsegments = 30\nradius = 0.012\nE = 5e9\ndensity = 700\n"
                     "angle = 10\n";
    CHECK_OK(cbm_bend_spec_parse(ctx, t2, strlen(t2), "s.spec", &sp));
    CHECK_OK(cbm_bend_run(ctx, &sp, &p, &r));
    cbm_bend_node n2[31];
    CHECK_OK(cbm_bend_nodes(p, n2, 31));
    printf("grown tip y %.6g, static tip y %.6g\n", nodes[30].y, n2[30].y);
    cbm_plant_destroy(p);
    CHECK_STATUS(cbm_bend_nodes(p = NULL, n2, 31), CBM_E_INVALID);
    test_ctx_end(ctx);
}

static void replay_spec(const char *path, const uint8_t *data, size_t size, void *ud)
{
    (void)path;
    (void)ud;
    cbm_fuzz_spec(data, size);
}

TEST(mech_spec_corpus_replay)
{
    char dir[1024];
    snprintf(dir, sizeof dir, "%s/tests/fuzz/corpus/spec", test_source_dir());
    int n = test_replay_dir(dir, false, replay_spec, NULL);
    printf("replayed %d corpus files\n", n);
    CHECK(n >= 14);
}

/* The node table of a tip-moment problem: uniform curvature M/EI at every node, moment M,
 * stress M r / I, and the tangent angle kappa s (an exact circle, staggered). */
TEST(mech_bend_nodes_tip_moment)
{
    cbm_context *ctx = test_ctx();
    const char *text = "length = 1\nsegments = 32\nradius = 0.01\nE = 1e9\ngravity = 0\n"
                       "tip_moment = 3.9269908169872414\ntolerance = 1e-13\n";
    /* EI = 1e9 * pi 1e-8 / 4 = 7.853981633974483; M = EI/2 -> kappa = 0.5 /m */
    cbm_bend_spec sp;
    CHECK_OK(cbm_bend_spec_parse(ctx, text, strlen(text), "m.spec", &sp));
    cbm_plant *p = NULL;
    cbm_bend_result r;
    CHECK_OK(cbm_bend_run(ctx, &sp, &p, &r));
    cbm_bend_node nd[33];
    CHECK_OK(cbm_bend_nodes(p, nd, 33));
    double I = 3.14159265358979323846 * 1e-8 / 4;
    for (int j = 0; j <= 32; j++) {
        CHECK_NEAR(nd[j].curvature, 0.5, 1e-10);
        CHECK_NEAR(nd[j].moment, 3.9269908169872414, 1e-10);
        CHECK_NEAR(nd[j].stress, 3.9269908169872414 * 0.01 / I, 1e-3);
        CHECK_NEAR(nd[j].angle_deg, 0.5 * nd[j].s * 180 / 3.14159265358979323846, 1e-8);
    }
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Same input, same bytes: two solves of a grown rod give bit-identical node tables. */
TEST(mech_bend_deterministic)
{
    cbm_context *ctx = test_ctx();
    const char *text = "segments = 40\nradius = 0.003\nE = 1e9\nangle = 30\nsteps = 5\n"
                       "length_initial = 0.3\nradius_final = 0.008\ntropism = 0.01\n";
    cbm_bend_spec sp;
    CHECK_OK(cbm_bend_spec_parse(ctx, text, strlen(text), "d.spec", &sp));
    cbm_bend_node a[41], b[41];
    for (int k = 0; k < 2; k++) {
        cbm_plant *p = NULL;
        cbm_bend_result r;
        CHECK_OK(cbm_bend_run(ctx, &sp, &p, &r));
        CHECK_OK(cbm_bend_nodes(p, k ? b : a, 41));
        cbm_plant_destroy(p);
    }
    CHECK(memcmp(a, b, sizeof a) == 0);
    test_ctx_end(ctx);
}
