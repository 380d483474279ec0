/* The fast solver's pipeline of named stages (solve_newton.c): the statistics name the stage that
 * converged, each stage is reached by the case it exists for, the context counts solves by stage,
 * and the workspace is one allocation. */
#include "mech_testlib.h"
#include "mech/mech_internal.h"

#include <string.h>

/* A heavy horizontal cantilever: w L^3 / EI = load (15: a large deflection). */
static cbm_plant *heavy_rod(cbm_context *ctx, double load, double angle)
{
    double L = 1, r = 0.01, rho = 1000, w = rho * PI * r * r * 9.81, EI = w / load;
    double E = EI / (PI * r * r * r * r / 4);
    return make_rod(ctx, 100, L, radius_uniform, E, rho, angle, CBM_MECH_STAGGERED);
}

TEST(mech_stage_names)
{
    /* every stage has its own name; out of range is "unknown" */
    for (int a = 0; a < CBM_SOLVE_STAGE_COUNT; a++) {
        const char *na = cbm_solve_stage_name((cbm_solve_stage)a);
        CHECK(na != NULL && strlen(na) > 0 && strcmp(na, "unknown") != 0);
        if (!na)
            continue;
        for (int b = 0; b < a; b++)
            CHECK(strcmp(na, cbm_solve_stage_name((cbm_solve_stage)b)) != 0);
    }
    CHECK(strcmp(cbm_solve_stage_name(CBM_SOLVE_STAGE_NEWTON), "newton") == 0);
    CHECK(strcmp(cbm_solve_stage_name(CBM_SOLVE_STAGE_LOAD_PATH), "load-path") == 0);
    CHECK(strcmp(cbm_solve_stage_name(CBM_SOLVE_STAGE_COUNT), "unknown") == 0);
    CHECK(strcmp(cbm_solve_stage_name((cbm_solve_stage)-1), "unknown") == 0);
}

/* Small deflection from rest: Newton at the full load converges on its own. A large one (the
 * first step beyond the trust radius) goes to the load continuation from rest. The relaxation
 * solver reports its own stage; a solve that runs out of passes reports none. */
TEST(mech_stage_cold_starts)
{
    cbm_context *ctx = test_ctx();
    cbm_solve_def sd = cbm_solve_def_default();
    sd.tolerance = 1e-10;
    cbm_solve_stats st;

    cbm_plant *p = heavy_rod(ctx, 0.01, 0);
    CHECK_OK(cbm_plant_solve(p, &sd, &st));
    CHECK_EQ_INT(st.stage, CBM_SOLVE_STAGE_NEWTON);
    CHECK_EQ_INT(st.continuation_steps, 1);
    cbm_plant_destroy(p);

    p = heavy_rod(ctx, 15, 0);
    CHECK_OK(cbm_plant_solve(p, &sd, &st));
    CHECK_EQ_INT(st.stage, CBM_SOLVE_STAGE_LOAD_PATH);
    CHECK(st.continuation_steps > 2);
    cbm_plant_destroy(p);

    p = heavy_rod(ctx, 1, 0);
    cbm_solve_def rd = sd;
    rd.solver = CBM_MECH_RELAX;
    rd.alpha = 0.5;
    CHECK_OK(cbm_plant_solve(p, &rd, &st));
    CHECK_EQ_INT(st.stage, CBM_SOLVE_STAGE_RELAX);
    cbm_plant_destroy(p);

    p = heavy_rod(ctx, 15, 0);
    cbm_solve_def bd = sd;
    bd.max_passes = 8;
    CHECK_STATUS(cbm_plant_solve(p, &bd, &st), CBM_E_NOT_CONVERGED);
    CHECK_EQ_INT(st.stage, CBM_SOLVE_STAGE_NONE);
    cbm_context_clear_errors(ctx);
    cbm_plant_destroy(p);

    /* the context counted the five solves by stage */
    size_t counts[CBM_SOLVE_STAGE_COUNT];
    cbm_solve_stage_counts(ctx, counts);
    CHECK_EQ_INT(counts[CBM_SOLVE_STAGE_NEWTON], 1);
    CHECK_EQ_INT(counts[CBM_SOLVE_STAGE_LOAD_PATH], 1);
    CHECK_EQ_INT(counts[CBM_SOLVE_STAGE_RELAX], 1);
    CHECK_EQ_INT(counts[CBM_SOLVE_STAGE_NONE], 1);
    CHECK_EQ_INT(counts[CBM_SOLVE_STAGE_TRANSIENT], 0);
    test_ctx_end(ctx);
}

/* A stem clamped 20 degrees off the vertical under a tip mass growing by 60 % per warm-started
 * solve (the snap-through of the solver tests): with the default warm path the transient stage
 * carries it over the fold, with the quasi-static warm path the mass path does. */
static void stem_steps(cbm_mech_warm_path path, size_t seen[CBM_SOLVE_STAGE_COUNT])
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = clamped_plant(ctx, PI / 2 - 20 * PI / 180);
    for (int i = 0; i < 8; i++) {
        cbm_segment_def d = cbm_segment_def_default();
        d.parent = i - 1;
        d.length = 0.02;
        d.core.youngs_modulus = 3e8;
        d.core.shear_modulus = 3e8 / 16;
        d.core.density = 1000;
        d.core.a = d.core.b = 0.001;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    cbm_solve_def sd = cbm_solve_def_default();
    sd.warm_path = path;
    sd.warm_start = true;
    memset(seen, 0, CBM_SOLVE_STAGE_COUNT * sizeof *seen);
    double m = 0.0003;
    for (int step = 0; step < 12; step++, m *= 1.6) {
        CHECK_OK(cbm_plant_set_load(p, 7, m, (cbm_vec3){0, 0, 0}, (cbm_vec3){0, 0, 0}));
        cbm_solve_stats st;
        CHECK_OK(cbm_plant_solve(p, &sd, &st));
        CHECK(st.stage > CBM_SOLVE_STAGE_NONE && st.stage < CBM_SOLVE_STAGE_RELAX);
        seen[st.stage]++;
    }
    size_t counts[CBM_SOLVE_STAGE_COUNT];
    cbm_solve_stage_counts(ctx, counts);
    for (int s = 0; s < CBM_SOLVE_STAGE_COUNT; s++)
        CHECK_EQ_INT(counts[s], seen[s]);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

TEST(mech_stage_warm_paths)
{
    size_t seen[CBM_SOLVE_STAGE_COUNT];
    stem_steps(CBM_MECH_WARM_TRANSIENT, seen);
    printf("transient warm path: newton %zu, transient %zu, mass-path %zu, load-path %zu, "
           "stability %zu\n",
           seen[CBM_SOLVE_STAGE_NEWTON], seen[CBM_SOLVE_STAGE_TRANSIENT],
           seen[CBM_SOLVE_STAGE_MASS_PATH], seen[CBM_SOLVE_STAGE_LOAD_PATH],
           seen[CBM_SOLVE_STAGE_STABILITY]);
    CHECK(seen[CBM_SOLVE_STAGE_NEWTON] > 0);
    CHECK(seen[CBM_SOLVE_STAGE_TRANSIENT] > 0);
    CHECK_EQ_INT(seen[CBM_SOLVE_STAGE_MASS_PATH], 0);
    stem_steps(CBM_MECH_WARM_MASS_PATH, seen);
    printf("mass warm path: newton %zu, transient %zu, mass-path %zu, load-path %zu, "
           "stability %zu\n",
           seen[CBM_SOLVE_STAGE_NEWTON], seen[CBM_SOLVE_STAGE_TRANSIENT],
           seen[CBM_SOLVE_STAGE_MASS_PATH], seen[CBM_SOLVE_STAGE_LOAD_PATH],
           seen[CBM_SOLVE_STAGE_STABILITY]);
    CHECK(seen[CBM_SOLVE_STAGE_MASS_PATH] > 0);
    CHECK_EQ_INT(seen[CBM_SOLVE_STAGE_TRANSIENT], 0);
}

/* The workspace is one block: a solve that has to grow it (more segments) allocates once for
 * it, and the solves after that not at all. */
TEST(mech_stage_workspace_one_allocation)
{
    size_t calls = 0;
    cbm_context *ctx = test_counting_ctx(&calls);
    CHECK(ctx != NULL);
    cbm_plant *p = heavy_rod(ctx, 1, 0);
    cbm_solve_def sd = cbm_solve_def_default();
    CHECK_OK(cbm_plant_solve(p, &sd, NULL));
    size_t c0 = calls;
    CHECK_OK(cbm_plant_solve(p, &sd, NULL));
    CHECK_EQ_INT(calls - c0, 0);
    /* one more segment: the solve replaces the workspace block, one allocation (the counter
     * counts allocations, not releases) */
    cbm_segment_def d = cbm_segment_def_default();
    d.parent = 99;
    d.length = 0.01;
    CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    c0 = calls;
    CHECK_OK(cbm_plant_solve(p, &sd, NULL));
    CHECK_EQ_INT(calls - c0, 1);
    CHECK_EQ_INT(p->work.cap, 150);
    /* ... which grew by half: the next segments fit without another allocation */
    d.parent = 100;
    CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    c0 = calls;
    CHECK_OK(cbm_plant_solve(p, &sd, NULL));
    CHECK_EQ_INT(calls - c0, 0);
    cbm_plant_destroy(p);
    CHECK_EQ_INT(cbm_context_bytes(ctx), 0);
    cbm_context_destroy(ctx);
}
