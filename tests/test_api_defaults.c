/* Every definition struct of the public API has its cbm_*_def_default() (tests/cli/api_defaults.sh
 * checks the headers for it); these check the two added last: what they hold and that they mean
 * what a NULL definition or the documented defaults mean. */
#include "test.h"
#include "cambium/cambium.h"

#include <string.h>

TEST(api_model_def_default_loads_a_model)
{
    cbm_model_def d = cbm_model_def_default();
    cbm_lsys_def l = cbm_lsys_def_default();
    CHECK(memcmp(&d.lsys, &l, sizeof l) == 0);
    CHECK(d.side_files == NULL);
    CHECK_EQ_INT(d.side_count, 0);
    CHECK_EQ_INT(l.solver, -1); /* the model's own SolverMethod() */
    cbm_context *ctx = test_ctx();
    d.lsys.path = "koch.l";
    d.lsys.text = "Lsystem: 1\nderivation length: 2\nAxiom: F-F-F-F\n"
                  "F --> F+F-F-FF+F+F-F\nendlsystem\n";
    cbm_model *m = NULL;
    d.lsys.solver = CBM_MECH_SOLVER_COUNT; /* no such method: refused, nothing loaded */
    CHECK(cbm_model_load(ctx, &d, &m) == CBM_E_INVALID && m == NULL);
    d.lsys.solver = -1;
    CHECK_OK(cbm_model_load(ctx, &d, &m));
    CHECK_OK(cbm_model_reset(m));
    CHECK_OK(cbm_model_step(m));
    /* F-F-F-F after one step: four F of 14 modules each and the three - */
    CHECK_EQ_INT(cbm_lsys_module_count(cbm_model_lsys(m)), 4 * 14 + 3);
    cbm_model_destroy(m);
    test_ctx_end(ctx);
}

TEST(api_turtle_def_default_is_null_def)
{
    cbm_turtle_def d = cbm_turtle_def_default();
    CHECK(d.record);
    cbm_context *ctx = test_ctx();
    cbm_view *v = NULL;
    CHECK_OK(cbm_view_create(ctx, &v));
    cbm_tmodule mods[3] = {{"F", 0, NULL}, {"+", 0, NULL}, {"F", 0, NULL}};
    cbm_turtle *a = NULL, *b = NULL, *c = NULL;
    CHECK_OK(cbm_turtle_interpret(ctx, v, &d, mods, 3, NULL, &a));
    CHECK_OK(cbm_turtle_interpret(ctx, v, NULL, mods, 3, NULL, &b));
    d.record = false;
    CHECK_OK(cbm_turtle_interpret(ctx, v, &d, mods, 3, NULL, &c));
    CHECK_EQ_INT(cbm_turtle_prim_count(a), 2);
    CHECK_EQ_INT(cbm_turtle_prim_count(b), 2);
    CHECK_EQ_INT(cbm_turtle_prim_count(c), 0);
    cbm_turtle_destroy(a);
    cbm_turtle_destroy(b);
    cbm_turtle_destroy(c);
    cbm_view_destroy(v);
    test_ctx_end(ctx);
}
