/* Geometry of the whole pipeline against cpfg: model file -> our derivation (float32 mode, as
 * cpfg) -> our homomorphism -> our turtle, compared with cpfg's ref/final.ray.gz (cylinders,
 * cones, polygons, spheres, discs, surfaces and generalized-cylinder triangles, in order) and the
 * bounding box of ref/final.vv, for the 14 cpfg models of ../shared/oracles/vlab.
 * Tolerances as the turtle's own oracle test (which feeds cpfg's strings instead of ours):
 * points and radii within 1e-5 * (1 + |value|) + 1e-5 * scale, where scale is the largest extent
 * of the box (the .ray file prints 6 significant digits); box within 1e-4 * scale.
 */
#define _POSIX_C_SOURCE 200809L
#include "oracle_geometry.h"

#include <stdlib.h>
#include <string.h>

static void run_model(const oracle_model *md, bool compare_prims)
{
    if (test_skip_without_oracles())
        return;
    char lpath[1024], vpath[1024], cpath[1024];
    cbm_context *ctx = test_ctx();
    snprintf(lpath, sizeof lpath, ORACLE "%s/model/%s", md->dir, md->lfile);
    snprintf(vpath, sizeof vpath, ORACLE "%s/model/%s", md->dir, md->view);
    snprintf(cpath, sizeof cpath, ORACLE "%s/model/%s", md->dir, md->colors);
    const char *sides[2] = {vpath, cpath};
    cbm_model_def def = {cbm_lsys_def_default(), sides, 2};
    def.lsys.path = lpath;
    def.lsys.float32 = true;
    def.lsys.ignore_seed = true; /* cpfg's batch mode */
    cbm_model *mdl = NULL;
    CHECK_OK(cbm_model_load(ctx, &def, &mdl));
    if (!mdl) {
        test_ctx_end(ctx);
        return;
    }
    CHECK_OK(cbm_model_reset(mdl));
    cbm_lsys *ls = cbm_model_lsys(mdl);
    for (int k = 0; k < cbm_lsys_derivation_length(ls) && !cbm_lsys_stopped(ls); k++)
        CHECK_OK(cbm_model_step(mdl));
    size_t nmod = cbm_lsys_module_count(ls);

    cbm_scene *scene = NULL;
    CHECK_OK(cbm_scene_create(ctx, &scene));
    cbm_turtle *t = NULL;
    CHECK_OK(cbm_model_interpret(mdl, scene, true, &t));
    if (t) {
        oracle_check_geometry(md, t, scene, nmod, compare_prims);
        CHECK(cbm_scene_triangle_count(scene) > 0);
        cbm_turtle_destroy(t);
    }
    cbm_scene_destroy(scene);
    cbm_model_destroy(mdl);
    test_ctx_end(ctx);
}

TEST(quadratic_koch)
{
    run_model(oracle_cpfg_model("quadratic_koch"), true);
}

TEST(compound_homo)
{
    run_model(oracle_cpfg_model("compound_homo"), true);
}

TEST(compound_param)
{
    run_model(oracle_cpfg_model("compound_param"), true);
}

TEST(continuous_decomp)
{
    run_model(oracle_cpfg_model("continuous_decomp"), true);
}

TEST(florigen_param)
{
    run_model(oracle_cpfg_model("florigen_param"), true);
}

TEST(hormone_up)
{
    run_model(oracle_cpfg_model("hormone_up"), true);
}

TEST(monopodial)
{
    run_model(oracle_cpfg_model("monopodial"), true);
}

TEST(sympodial)
{
    run_model(oracle_cpfg_model("sympodial"), true);
}

TEST(random_moss)
{
    run_model(oracle_cpfg_model("random_moss"), true);
}

TEST(weeping_birch)
{
    run_model(oracle_cpfg_model("weeping_birch"), true);
}

/* Every primitive: the spheres and cylinders of its homomorphism too, which cpfg's strings
 * alone cannot give. */
TEST(query_position)
{
    run_model(oracle_cpfg_model("query_position"), true);
}

TEST(leaf_rnd)
{
    run_model(oracle_cpfg_model("leaf_rnd"), true);
}

TEST(tropisms)
{
    run_model(oracle_cpfg_model("tropisms"), true);
}

TEST(lilac)
{
    run_model(oracle_cpfg_model("lilac"), true);
}
