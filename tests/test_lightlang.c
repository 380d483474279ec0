/* Light() of the L+C dialect (src/lsys/lightlang.c, docs/language.md "Light"): a leaf under
 * another leaf gets less light than the one above it, the unshaded one gets its area, the
 * numbers are the C API's (cbm_light_intercept) on the same quads bit for bit, and misuse
 * stops the run naming file:line:col. */
#include "test.h"

#include "cambium/light.h"
#include "cambium/lsys.h"
#include "lang/mechsegment.h"
#include "lsys_util.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* Two upright 0.1 m segments, a 0.01 m^2 leaf on each node, and a third leaf on a lateral
 * reaching out 45 degrees from the first node (under the top leaf only in part). */
#define MODEL                                                                                      \
    "#include <lpfgall.h>\n"                                                                       \
    "derivation length: 1;\n"                                                                      \
    "module I(MechSegment);\n"                                                                     \
    "module Lf(double, double);\n"                                                                 \
    "mechanics: I;\n"                                                                              \
    "light: Lf(area, light);\n"                                                                    \
    "double total;\n"                                                                              \
    "MechSegment S() { MechSegment s; s.length = 0.1; s.a = 0.01; "                                \
    "s.b = 0.01; s.E = 1e12; s.density = 1; return s; }\n"                                         \
    "EndEach: { Equilibrium(); total = Light(%d, 4); }\n"                                          \
    "Axiom: I(S()) Lf(0.01, -1) SB Left(45) I(S()) Lf(0.01, -1) EB "                               \
    "I(S()) Lf(0.01, -1);\n"

/* The leaves' light after one step under sky, and the quads Light() cast (built here the way
 * docs/language.md says from the segments the string holds). */
static int run_model(cbm_context *ctx, int sky, double light[3], cbm_light_leaf quads[3])
{
    char src[1200];
    snprintf(src, sizeof src, MODEL, sky);
    int n = 0;
    cbm_lsys *ls = lsys_from_text(ctx, "light.l", src);
    if (!ls)
        return 0;
    CHECK_OK(cbm_lsys_step(ls));
    cbm_lsys_cursor c;
    double seg[MS_SIZE] = {0}, stack[4][MS_SIZE];
    int depth = 0;
    cbm_lsys_cursor_begin(ls, false, &c);
    while (cbm_lsys_cursor_next(ls, false, &c)) {
        if (c.symbol == '[' && depth < 4)
            memcpy(stack[depth++], seg, sizeof seg);
        else if (c.symbol == ']' && depth > 0)
            memcpy(seg, stack[--depth], sizeof seg);
        else if (c.nparams == MS_SIZE)
            memcpy(seg, c.params, sizeof seg);
        else if (c.nparams == 2 && n < 3) {
            light[n] = c.params[1];
            cbm_vec3 h = {seg[MS_H], seg[MS_H + 1], seg[MS_H + 2]};
            cbm_vec3 m = {seg[MS_POS] + seg[MS_LENGTH] * h.x,
                          seg[MS_POS + 1] + seg[MS_LENGTH] * h.y,
                          seg[MS_POS + 2] + seg[MS_LENGTH] * h.z};
            double hl = sqrt(h.x * h.x + h.z * h.z);
            cbm_vec3 e1 = hl > 1e-9 ? (cbm_vec3){h.x / hl, 0, h.z / hl} : (cbm_vec3){1, 0, 0};
            cbm_vec3 e2 = {e1.z, 0, -e1.x};
            double a = 0.5 * sqrt(c.params[0]);
            const double s1[4] = {-1, 1, 1, -1}, s2[4] = {-1, -1, 1, 1};
            for (int q = 0; q < 4; q++)
                quads[n].p[q] = (cbm_vec3){m.x + a * (s1[q] * e1.x + s2[q] * e2.x), m.y,
                                           m.z + a * (s1[q] * e1.z + s2[q] * e2.z)};
            quads[n].plant = 0;
            n++;
        }
    }
    cbm_lsys_destroy(ls);
    return n;
}

TEST(lightlang_shade_equals_api)
{
    cbm_context *ctx = test_ctx();
    for (int sky = 0; sky < 4; sky++) {
        double light[3] = {-1, -1, -1};
        cbm_light_leaf q[3];
        int n = run_model(ctx, sky, light, q);
        CHECK_EQ_INT(n, 3);
        if (n != 3)
            continue;
        /* the top leaf (the last) above the first: the first is shaded */
        printf("sky %d: lower %.6g, lateral %.6g, top %.6g m^2\n", sky, light[0], light[1],
               light[2]);
        CHECK(light[0] > 0 && light[0] < 0.9 * light[2]);
        CHECK(light[1] > light[0]);
        if (sky != CBM_SKY_FIELD) /* an open field gives a little less near its edges */
            CHECK_NEAR(light[2], 0.01, 1e-12);
        cbm_light_def def = cbm_light_def_default();
        def.sky = (cbm_sky_kind)sky;
        def.samples = 4;
        double api[3];
        CHECK_OK(cbm_light_intercept(ctx, &def, q, 3, NULL, 0, api, NULL));
        for (int i = 0; i < 3; i++)
            CHECK(api[i] == light[i]);
    }
    test_ctx_end(ctx);
}

/* Misuse: each line stops the run (or the load) with a message naming the place. */
TEST(lightlang_errors)
{
    const struct {
        const char *decl, *call, *want;
        bool at_load;
    } bad[] = {
        {"light: Lf(area, light);", "Light(4, 1);", "light.l:7:12: EndEach: Light(sky, samples)",
         false},
        {"light: Lf(area, light);", "Light(2, 0);", "light.l:7:12: EndEach: Light(sky, samples)",
         false},
        {"", "Light(2, 1);", "light.l:7:12: EndEach: Light(): no leaf module declared", false},
        {"light: Lf(area);", "", "light.l:6:15: leaf module 'Lf' needs", true},
        {"light: Lf(area, colour);", "", "light.l:6:17: unknown role 'colour'", true},
        {"light: Lf(area, light, _);", "", "light.l:6:24: module 'Lf' has 2", true},
    };
    for (size_t j = 0; j < sizeof bad / sizeof bad[0]; j++) {
        test_diags g;
        cbm_context *dc = test_diag_ctx(&g);
        CHECK(dc != NULL);
        char src[800];
        snprintf(src, sizeof src,
                 "#include <lpfgall.h>\nderivation length: 1;\nmodule I(MechSegment);\n"
                 "module Lf(double, double); MechSegment S() { MechSegment s; s.length = 0.1; "
                 "s.a = 0.01; s.b = 0.01; s.E = 1e10; s.density = 1; return s; }\n"
                 "mechanics: I;\n%s\n"
                 "EndEach: { %s }\nAxiom: I(S()) Lf(0.01, 0);\n",
                 bad[j].decl, bad[j].call);
        cbm_lsys_def def = cbm_lsys_def_default();
        def.text = src;
        def.path = "light.l";
        cbm_lsys *ls = NULL;
        cbm_status s = cbm_lsys_load(dc, &def, &ls);
        if (bad[j].at_load)
            CHECK(s != CBM_OK);
        else {
            CHECK_OK(s);
            if (ls) {
                CHECK_OK(cbm_lsys_reset(ls));
                CHECK(cbm_lsys_step(ls) != CBM_OK);
            }
        }
        printf("%-28s %-14s -> %s", bad[j].decl, bad[j].call, g.text);
        CHECK_MSG(strstr(g.text, bad[j].want) != NULL, "want '%s'", bad[j].want);
        cbm_lsys_destroy(ls);
        test_ctx_end(dc);
    }
}
