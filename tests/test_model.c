/* cbm_model: the L-system joined with its side files and the turtle. Query modules filled before
 * a step (a production sees the turtle's position), func(id, x) from function files and its error
 * without them, side-file errors, the interpretation's scene and record, and allocation failure
 * at every point of a load-derive-interpret run (no leak, a clean status). The cpfg models are
 * checked through the same pipeline in test_run_oracle.c and test_lsys_oracles.c. */
#include "test.h"

#include <string.h>

#define LSYS CBM_TEST_SOURCE_DIR "/tests/lsys/"

static cbm_model *load_text(cbm_context *ctx, const char *text, const char *const *sides,
                            size_t nside, cbm_status *st)
{
    cbm_model_def def = {cbm_lsys_def_default(), sides, nside};
    def.lsys.path = "test.l";
    def.lsys.text = text;
    cbm_model *m = NULL;
    *st = cbm_model_load(ctx, &def, &m);
    return m;
}

/* The string as text, cpfg notation without wrapping. */
static void string_of(cbm_model *m, char *buf, size_t n)
{
    cbm_lsys *ls = cbm_model_lsys(m);
    cbm_lsys_cursor c;
    cbm_lsys_cursor_begin(ls, false, &c);
    size_t k = 0;
    buf[0] = 0;
    while (cbm_lsys_cursor_next(ls, false, &c) && k + 64 < n) {
        k += (size_t)snprintf(buf + k, n - k, "%c", c.symbol);
        for (int i = 0; i < c.nparams; i++)
            k += (size_t)snprintf(buf + k, n - k, "%c%g", i ? ',' : '(', c.params[i]);
        if (c.nparams)
            k += (size_t)snprintf(buf + k, n - k, ")");
    }
}

TEST(query_before_step)
{
    cbm_context *ctx = test_ctx();
    cbm_status st;
    /* A's new parameter is the y of the query on its left, which only the turtle can give
     * (F(1) from the origin along the initial heading +y) */
    cbm_model *m = load_text(ctx,
                             "Lsystem: 1\nderivation length: 2\nAxiom: F(1)?P(0,0,0)A(0)\n"
                             "?P(x,y,z) < A(n) --> F(1)A(y)\nendlsystem\n",
                             NULL, 0, &st);
    CHECK_OK(st);
    if (m) {
        CHECK_OK(cbm_model_reset(m));
        CHECK(cbm_model_has_queries(m));
        CHECK_OK(cbm_model_step(m));
        char s[512];
        string_of(m, s, sizeof s);
        CHECK_MSG(!strcmp(s, "F(1)?P(0,1,0)F(1)A(1)"), "after step 1: %s", s);
        CHECK_OK(cbm_model_step(m));
        cbm_scene *scene = NULL;
        CHECK_OK(cbm_scene_create(ctx, &scene));
        cbm_turtle *t = NULL;
        CHECK_OK(cbm_model_interpret(m, scene, true, &t));
        CHECK_EQ_INT((int)cbm_turtle_prim_count(t), 2); /* two segments */
        cbm_vec3 lo, hi;
        CHECK(cbm_turtle_box(t, &lo, &hi));
        CHECK_NEAR(hi.y, 2.0, 1e-12);
        CHECK(cbm_scene_triangle_count(scene) > 0);
        cbm_turtle_destroy(t);
        cbm_scene_destroy(scene);
        cbm_model_destroy(m);
    }
    test_ctx_end(ctx);
}

TEST(func_needs_function_files)
{
    cbm_context *ctx = test_ctx();
    cbm_status st;
    const char *text = "Lsystem: 1\nderivation length: 1\nAxiom: A(0)\n"
                       "A(n) --> B(func(1,0.5))\nendlsystem\n";
    cbm_model *m = load_text(ctx, text, NULL, 0, &st);
    CHECK_OK(st);
    if (m) {
        CHECK_OK(cbm_model_reset(m));
        CHECK(cbm_model_step(m) != CBM_OK);
        CHECK(strstr(cbm_context_last_error(ctx), "func") != NULL);
        cbm_model_destroy(m);
    }
    /* with a function file: its value at 0.5 */
    const char *func = CBM_TEST_SOURCE_DIR "/../shared/oracles/vlab/cpfg-lilac/model/elas.func";
    FILE *f = fopen(func, "rb");
    if (f) {
        fclose(f);
        cbm_context_clear_errors(ctx);
        m = load_text(ctx, text, &func, 1, &st);
        CHECK_OK(st);
        if (m) {
            CHECK_OK(cbm_model_reset(m));
            CHECK_OK(cbm_model_step(m));
            cbm_lsys_cursor c;
            cbm_lsys_cursor_begin(cbm_model_lsys(m), false, &c);
            CHECK(cbm_lsys_cursor_next(cbm_model_lsys(m), false, &c));
            CHECK_EQ_INT(c.symbol, 'B');
            CHECK_NEAR(c.params[0],
                       cbm_funcset_value(cbm_view_functions(cbm_model_view(m)), 1, 0.5), 1e-12);
            cbm_model_summary sm;
            cbm_model_describe(m, &sm);
            CHECK_EQ_INT(sm.functions, 1);
            CHECK_EQ_INT((int)sm.productions, 1);
            CHECK_EQ_INT(sm.derivation_length, 1);
            cbm_model_destroy(m);
        }
    }
    test_ctx_end(ctx);
}

/* cbm_model_describe: the counts of every L-system of a cpfg file (sub-L-systems summed, the
 * deepest homomorphism, stochastic from any of them, blocks), and an L+C model's own rules and
 * declared modules. */
TEST(describe_counts_both_dialects)
{
    cbm_context *ctx = test_ctx();
    cbm_status st;
    cbm_model *m = load_text(ctx,
                             "#define STEPS 4\n"
                             "Lsystem: 1\nderivation length: STEPS\nAxiom: A?(2,1)\n"
                             "A --> AB\nB --> A\nhomomorphism\nmaximum depth: 2\nB --> F\n"
                             "endlsystem\n"
                             "Lsystem: 2\nStart: {x = 1;}\nAxiom: C\nC --> CC : 0.5\n"
                             "C --> D : 0.5\ndecomposition\nmaximum depth: 3\nD --> EE\n"
                             "homomorphism\nmaximum depth: 5\nE --> F\nC --> F\nendlsystem\n",
                             NULL, 0, &st);
    CHECK_OK(st);
    if (m) {
        cbm_model_summary sm;
        cbm_model_describe(m, &sm);
        CHECK_EQ_INT(sm.lsystems, 2);
        CHECK_EQ_INT((int)sm.productions, 4);
        CHECK_EQ_INT((int)sm.decompositions, 1);
        CHECK_EQ_INT((int)sm.homomorphisms, 3);
        CHECK_EQ_INT(sm.decomposition_depth, 3);
        CHECK_EQ_INT(sm.homomorphism_depth, 5);
        CHECK(sm.stochastic);     /* from the second L-system */
        CHECK(!sm.has_start_end); /* the Start: of a sub-L-system is not the file's */
        CHECK(!sm.lc_dialect && !sm.mechanics);
        CHECK_EQ_INT(sm.derivation_length, 4);
        CHECK_EQ_INT((int)sm.modules_declared, 0);
        cbm_model_destroy(m);
    }
    m = load_text(ctx,
                  "#include <lpfgall.h>\nmodule A(int);\nmodule B();\nderivation length: 3;\n"
                  "Axiom: A(1);\nA(n) : { produce A(n + 1) B(); }\n"
                  "interpretation:\nmaximum depth: 2;\nB() : { produce F(1); }\n",
                  NULL, 0, &st);
    CHECK_OK(st);
    if (m) {
        cbm_model_summary sm;
        cbm_model_describe(m, &sm);
        CHECK(sm.lc_dialect && !sm.mechanics);
        CHECK_EQ_INT(sm.lsystems, 1);
        CHECK_EQ_INT((int)sm.productions, 1);
        CHECK_EQ_INT((int)sm.homomorphisms, 1);
        CHECK_EQ_INT(sm.homomorphism_depth, 2);
        CHECK_EQ_INT((int)sm.decompositions, 0);
        CHECK_EQ_INT(sm.derivation_length, 3);
        CHECK(sm.modules_declared > 2); /* A and B with the turtle's modules */
        CHECK(!sm.stochastic && !sm.has_start_end);
        cbm_model_destroy(m);
    }
    test_ctx_end(ctx);
}

TEST(side_file_errors)
{
    cbm_context *ctx = test_ctx();
    cbm_status st;
    const char *missing = "/nonexistent/dir/plant.v";
    cbm_model *m = load_text(ctx, "Lsystem: 1\nAxiom: F\nendlsystem\n", &missing, 1, &st);
    CHECK(m == NULL);
    CHECK(st != CBM_OK);
    CHECK(strstr(cbm_context_last_error(ctx), "plant.v") != NULL);
    const char *odd = LSYS "abop-2.8a.l";
    m = load_text(ctx, "Lsystem: 1\nAxiom: F\nendlsystem\n", &odd, 1, &st);
    CHECK(m == NULL);
    CHECK(st == CBM_E_UNSUPPORTED);
    test_ctx_end(ctx);
}

/* Every allocation of a run may fail: a clean status and no leak each time. */
static cbm_status oom_run(cbm_context *ctx, void *ud)
{
    (void)ud;
    const char *sides[] = {LSYS "abop-2.8a.v"};
    cbm_model_def def = {cbm_lsys_def_default(), sides, 1};
    def.lsys.path = LSYS "abop-2.8a.l";
    cbm_model *m = NULL;
    cbm_status ls = cbm_model_load(ctx, &def, &m);
    if (ls != CBM_OK)
        return ls;
    cbm_scene *scene = NULL;
    cbm_turtle *t = NULL;
    cbm_status s = cbm_model_reset(m);
    for (int k = 0; k < 3 && s == CBM_OK; k++)
        s = cbm_model_step(m);
    if (s == CBM_OK)
        s = cbm_scene_create(ctx, &scene);
    if (s == CBM_OK)
        s = cbm_model_interpret(m, scene, true, &t);
    cbm_turtle_destroy(t);
    cbm_scene_destroy(scene);
    cbm_model_destroy(m);
    return s;
}

TEST(allocation_failures)
{
    CHECK(test_oom_loop(oom_run, NULL) > 10);
}
