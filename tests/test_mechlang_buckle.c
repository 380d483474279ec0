/* Taylor-Hell's buckling column (§6.3, Table 6.1) through the L+C dialect:
 * models/taylor-hell-buckling.l grows, pushes and relaxes a vertical column in the language and
 * asks Stability(); for the six woods of Table 6.1 the language's buckling length must lie within
 * one segment (0.1 m) of the predicted length (the first 0.1 m multiple at or above Greenhill's
 * L_G = (7.837 E I / q)^(1/3)) and equal the native protocol's (cbm_mech_buckle, `cambium
 * buckle`), with the same stability factor. Also: Stability() in a production does not load
 * (the message names file:line:col, checked in the CLI output by hand). */
#include "lsys_util.h"

#include "cambium/lsys.h"
#include "cambium/mech.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define MS 26 /* doubles of a MechSegment */
#define PI 3.14159265358979323846

static const struct wood {
    const char *name;
    double e, rho;
} WOODS[] = {{"yellow poplar", 10.38e9, 427}, {"apple", 8.77e9, 745},
             {"black willow", 5.03e9, 408},   {"black oak", 11.31e9, 669},
             {"yellow birch", 14.53e9, 668},  {"silver maple", 6.22e9, 506}};

TEST(mechlang_buckle_table_6_1)
{
    cbm_context *ctx = test_ctx();
    char path[2048];
    snprintf(path, sizeof path, "%s/models/taylor-hell-buckling.l", test_source_dir());
    for (size_t w = 0; w < sizeof WOODS / sizeof WOODS[0]; w++) {
        char de[64], dr[64];
        snprintf(de, sizeof de, "E_WOOD=%.17g", WOODS[w].e);
        snprintf(dr, sizeof dr, "DENSITY=%.17g", WOODS[w].rho);
        const char *defs[] = {de, dr};
        cbm_lsys_def def = cbm_lsys_def_default();
        def.path = path;
        def.defines = defs;
        def.define_count = 2;
        cbm_lsys *ls = lsys_from_def(ctx, &def);
        int steps = cbm_lsys_derivation_length(ls);
        for (int i = 0; i < steps && !cbm_lsys_stopped(ls); i++)
            CHECK_OK(cbm_lsys_step(ls));
        CHECK(cbm_lsys_stopped(ls));
        /* the apex: Apex(segments, buckling length, stability factor); the segments below it */
        int apex = lsys_symbol(ls, "Apex"), seg = lsys_symbol(ls, "S");
        double ap[3] = {0, 0, 0}, top[MS] = {0}, below[MS] = {0};
        size_t nseg = 0;
        cbm_lsys_cursor c;
        cbm_lsys_cursor_begin(ls, false, &c);
        while (cbm_lsys_cursor_next(ls, false, &c)) {
            if (c.symbol == apex && c.nparams == 3)
                memcpy(ap, c.params, sizeof ap);
            if (c.symbol == seg && c.nparams >= MS) {
                if (nseg)
                    memcpy(below, top, sizeof below);
                memcpy(top, c.params, sizeof top);
                nseg++;
            }
        }
        double len = ap[1];
        /* predicted: the first 0.1 m multiple >= Greenhill's length */
        double r = 0.05, ei = WOODS[w].e * PI * pow(r, 4) / 4;
        double q = WOODS[w].rho * PI * r * r * 9.81, lg = cbrt(7.837 * ei / q);
        double predicted = ceil(lg / 0.1 - 1e-9) * 0.1;
        CHECK_MSG(fabs(len - predicted) <= 0.1 + 1e-9, "%s: language %.1f m, predicted %.1f m",
                  WOODS[w].name, len, predicted);
        CHECK_EQ_INT(nseg, (size_t)ap[0]);
        CHECK_NEAR(len, (double)nseg * 0.1, 1e-9);
        /* the native protocol: the same length and the same factor */
        cbm_buckle_def bd = cbm_buckle_def_default();
        bd.youngs_modulus = WOODS[w].e;
        bd.density = WOODS[w].rho;
        cbm_buckle_result br;
        CHECK_OK(cbm_mech_buckle(ctx, &bd, &br));
        CHECK_MSG(fabs(len - br.buckling_length) < 1e-9, "%s: language %.1f m, native %.1f m",
                  WOODS[w].name, len, br.buckling_length);
        CHECK(ap[2] >= 1.0);
        CHECK_REL(ap[2], br.growth_factor, 1e-6);
        /* one segment shorter, the pushed column came back upright: its top on the axis */
        double tx = below[13] + below[0] * below[16], tz = below[15] + below[0] * below[18];
        CHECK(below[14] > 0.9 * (len - 0.2)); /* it stands */
        CHECK(sqrt(tx * tx + tz * tz) < 1e-6);
        cbm_lsys_destroy(ls);
    }
    test_ctx_end(ctx);
}

TEST(mechlang_buckle_stability_refused_in_production)
{
    cbm_context *ctx = test_ctx();
    static const char TEXT[] = "#include <lpfgall.h>\n"
                               "derivation length: 1;\n"
                               "module S(MechSegment);\n"
                               "module A();\n"
                               "mechanics: S;\n"
                               "double f;\n"
                               "Axiom: A;\n"
                               "A : { f = Stability(); produce A; }\n";
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = "inline.l";
    def.text = TEXT;
    cbm_lsys *ls = NULL;
    CHECK(cbm_lsys_load(ctx, &def, &ls) != CBM_OK);
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

/* the buckling model on a soft column (about 12 segments) under failing allocations: every run
 * returns CBM_OK or CBM_E_NOMEM and releases every byte */
static cbm_status oom_column(cbm_context *ctx, void *ud)
{
    (void)ud;
    char path[2048];
    snprintf(path, sizeof path, "%s/models/taylor-hell-buckling.l", test_source_dir());
    const char *defs[] = {"E_WOOD=2e6", "DENSITY=500"};
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = path;
    def.defines = defs;
    def.define_count = 2;
    cbm_lsys *ls = NULL;
    cbm_status s = cbm_lsys_load(ctx, &def, &ls);
    if (s == CBM_OK)
        s = cbm_lsys_reset(ls);
    for (int i = 0; s == CBM_OK && i < 200 && !cbm_lsys_stopped(ls); i++)
        s = cbm_lsys_step(ls);
    if (s == CBM_OK && !cbm_lsys_stopped(ls))
        s = CBM_E_INTERNAL; /* the soft column must buckle */
    cbm_lsys_destroy(ls);
    return s;
}

TEST(mechlang_buckle_oom)
{
    CHECK(test_oom_loop(oom_column, NULL) > 10);
}
