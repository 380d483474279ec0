/* The parts of a model's scene name the module that drew them (a segment: the F that opened it),
 * and in L+C models with mechanics the parts drawn by a mechanical segment's module carry its
 * stress and age, through the interpretation rules, so pictures can be coloured by stress. */
#include "test.h"

#include "cambium/geom.h"
#include "cambium/lsys.h"
#include "cambium/model.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static cbm_model *load(cbm_context *ctx, const char *path, const char *text)
{
    cbm_model_def def = {cbm_lsys_def_default(), NULL, 0};
    def.lsys.path = path;
    def.lsys.text = text;
    cbm_model *m = NULL;
    CHECK_OK(cbm_model_load(ctx, &def, &m));
    return m;
}

TEST(model_parts_name_the_module_that_drew_them)
{
    cbm_context *ctx = test_ctx();
    /* modules: 0 F, 1 +, 2 F, 3 [, 4 -, 5 F, 6 ], 7 F, 8 @O */
    cbm_model *m = load(ctx, "p.l",
                        "Lsystem: 1\nderivation length: 0\naxiom: F(1)+(30)F(1)[-(40)F(2)]F(1)"
                        "@O(0.5)\nendlsystem\n");
    cbm_scene *sc = NULL;
    CHECK_OK(cbm_scene_create(ctx, &sc));
    if (m && sc) {
        CHECK_OK(cbm_model_reset(m));
        CHECK_OK(cbm_model_interpret(m, sc, false, NULL));
        const cbm_part *p = cbm_scene_parts(sc);
        size_t n = cbm_scene_part_count(sc);
        CHECK_EQ_INT(n, 5);
        const int64_t want[5] = {0, 2, 5, 7, 8};
        for (size_t i = 0; i < n && i < 5; i++)
            CHECK_MSG(p[i].segment == want[i], "part %zu: module %lld, want %lld", i,
                      (long long)p[i].segment, (long long)want[i]);
    }
    cbm_scene_destroy(sc);
    cbm_model_destroy(m);
    test_ctx_end(ctx);
}

TEST(model_parts_carry_the_mechanics)
{
    cbm_context *ctx = test_ctx();
    char path[2048];
    snprintf(path, sizeof path, "%s/models/jirasek-hanging.l", test_source_dir());
    cbm_model *m = load(ctx, path, NULL);
    cbm_scene *sc = NULL;
    CHECK_OK(cbm_scene_create(ctx, &sc));
    if (m && sc) {
        cbm_lsys *ls = cbm_model_lsys(m);
        CHECK_OK(cbm_model_reset(m));
        for (int i = 0; i < cbm_lsys_derivation_length(ls); i++)
            CHECK_OK(cbm_model_step(m));
        CHECK_OK(cbm_model_interpret(m, sc, false, NULL));
        /* the stresses of the segments, in string order */
        double stress[256];
        size_t ns = 0;
        int sym = -1;
        for (int s = 1; s < 128; s++)
            if (cbm_lsys_module_name(ls, s) && !strcmp(cbm_lsys_module_name(ls, s), "I"))
                sym = s;
        cbm_lsys_cursor c;
        cbm_lsys_cursor_begin(ls, false, &c);
        while (cbm_lsys_cursor_next(ls, false, &c))
            if (c.symbol == sym && ns < 256)
                stress[ns++] = c.params[22];
        /* every branch part carries the stress of one segment, in order; leaves carry none */
        const cbm_part *p = cbm_scene_parts(sc);
        size_t k = 0, leaves = 0;
        for (size_t i = 0; i < cbm_scene_part_count(sc); i++) {
            if (p[i].organ == CBM_ORGAN_BRANCH && isfinite(p[i].stress)) {
                if (k < ns)
                    CHECK_NEAR(p[i].stress, stress[k], 1e-6);
                CHECK(p[i].age >= 0);
                k++;
            } else if (p[i].organ == CBM_ORGAN_LEAF) {
                CHECK(!isfinite(p[i].stress));
                leaves++;
            }
        }
        CHECK(ns > 20);
        CHECK_EQ_INT(k, ns);
        CHECK(leaves > 0);
        CHECK(stress[0] > 1e5); /* the base carries the plant */
    }
    cbm_scene_destroy(sc);
    cbm_model_destroy(m);
    test_ctx_end(ctx);
}
