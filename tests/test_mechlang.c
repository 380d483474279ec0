/* Mechanics inside the L+C dialect (src/lsys/mechlang.c): the language route against the native
 * cbm_plant route, the shipped Jirasek models (S-shaped branch, cherries), state kept through
 * rewriting, declaration errors, determinism, out-of-memory. */
#include "test.h"

#include "cambium/lsys.h"
#include "cambium/mech.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MS 26 /* doubles of a MechSegment */
#define PI 3.14159265358979323846

static cbm_status load(cbm_context *ctx, const char *path, const char *text, cbm_lsys **ls)
{
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = path;
    def.text = text;
    return cbm_lsys_load(ctx, &def, ls);
}

/* The MechSegments of the current string (module symbol `sym`, segment at parameter 0). */
static size_t segments(const cbm_lsys *ls, int sym, double (*out)[MS], size_t max)
{
    cbm_lsys_cursor c;
    size_t n = 0;
    cbm_lsys_cursor_begin(ls, false, &c);
    while (cbm_lsys_cursor_next(ls, false, &c))
        if (c.symbol == sym && c.nparams >= MS) {
            if (n < max)
                memcpy(out[n], c.params, sizeof out[n]);
            n++;
        }
    return n;
}

static int symbol_of(const cbm_lsys *ls, const char *name)
{
    for (int s = 1; s < 128; s++) {
        const char *m = cbm_lsys_module_name(ls, s);
        if (m && !strcmp(m, name))
            return s;
    }
    return -1;
}

static const char CHAIN[] = "#include <lpfgall.h>\n"
                            "derivation length: 1;\n"
                            "module I(MechSegment);\n"
                            "module Fruit(double);\n"
                            "mechanics: I;\n"
                            "mass: Fruit;\n"
                            "MechSegment S(double len, double r)\n"
                            "{\n"
                            "    MechSegment s;\n"
                            "    s.length = len; s.a = r; s.b = r; s.E = 2e9; s.density = 800;\n"
                            "    return s;\n"
                            "}\n"
                            "Axiom: I(S(0.2, 0.01)) Right(30) I(S(0.15, 0.008))\n"
                            "       SB RollR(70) Right(25) RollL(10) I(S(0.1, 0.005)) Fruit(0.05) EB\n"
                            "       I(S(0.15, 0.006)) Fruit(0.02);\n"
                            "EndEach: { Equilibrium(); }\n";

/* the same chain with cbm_plant; returns the distal node of the last segment */
static cbm_status native_chain(cbm_context *ctx, cbm_vec3 *tip, cbm_vec3 *branch_tip)
{
    cbm_plant_def pd = cbm_plant_def_default();
    double h = sqrt(0.5);
    pd.base_orientation = (cbm_quat){0, h, h, 0}; /* H = +y, L = +x, U = -z */
    cbm_plant *p = NULL;
    cbm_status s0 = cbm_plant_create(ctx, &pd, &p);
    if (s0 != CBM_OK)
        return s0;
    double len[] = {0.2, 0.15, 0.1, 0.15}, r[] = {0.01, 0.008, 0.005, 0.006};
    int64_t par[] = {-1, 0, 1, 1};
    double div[] = {0, 0, -70, 0}, dev[] = {0, 30, 25, 0}, roll[] = {0, 0, 10, 0};
    double mass[] = {0, 0, 0.05, 0.02};
    cbm_status s = CBM_OK;
    for (int i = 0; i < 4 && s == CBM_OK; i++) {
        cbm_segment_def d = cbm_segment_def_default();
        d.parent = par[i];
        d.length = len[i];
        d.divergence = div[i] * PI / 180;
        d.deviation = dev[i] * PI / 180;
        d.roll = roll[i] * PI / 180;
        d.core.youngs_modulus = 2e9;
        d.core.shear_modulus = 2e9 / 16;
        d.core.density = 800;
        d.core.a = d.core.b = r[i];
        d.point_mass = mass[i];
        s = cbm_plant_add_segment(p, &d, NULL);
    }
    cbm_solve_stats st;
    cbm_solve_def sd = cbm_solve_def_default();
    if (s == CBM_OK)
        s = cbm_plant_solve(p, &sd, &st);
    cbm_segment_state a, b;
    if (s == CBM_OK)
        s = cbm_plant_segment(p, 3, &a);
    if (s == CBM_OK)
        s = cbm_plant_segment(p, 2, &b);
    if (s == CBM_OK) {
        *tip = a.distal;
        *branch_tip = b.distal;
    }
    cbm_plant_destroy(p);
    return s;
}

static cbm_vec3 tip_of(const double *g)
{
    return (cbm_vec3){g[13] + g[0] * g[16], g[14] + g[0] * g[17], g[15] + g[0] * g[18]};
}

TEST(mechlang_language_and_native_agree)
{
    cbm_context *ctx = test_ctx();
    cbm_lsys *ls = NULL;
    CHECK_OK(load(ctx, "chain.l", CHAIN, &ls));
    CHECK_OK(cbm_lsys_reset(ls));
    CHECK_OK(cbm_lsys_step(ls));
    double g[8][MS];
    int sym = symbol_of(ls, "I");
    CHECK(sym > 0);
    CHECK_EQ_INT(segments(ls, sym, g, 8), 4);
    cbm_vec3 tip = {0, 0, 0}, btip = {0, 0, 0};
    CHECK_OK(native_chain(ctx, &tip, &btip));
    cbm_vec3 lt = tip_of(g[3]), lb = tip_of(g[2]);
    double scale = 0.6;
    CHECK_NEAR(lt.x, tip.x, 1e-9 * scale);
    CHECK_NEAR(lt.y, tip.y, 1e-9 * scale);
    CHECK_NEAR(lt.z, tip.z, 1e-9 * scale);
    CHECK_NEAR(lb.x, btip.x, 1e-9 * scale);
    CHECK_NEAR(lb.y, btip.y, 1e-9 * scale);
    CHECK_NEAR(lb.z, btip.z, 1e-9 * scale);
    /* it did bend: the tip is below the unloaded one */
    CHECK(tip.y < 0.2 + 0.3 * cos(PI / 6) - 1e-4);
    CHECK(fabs(g[3][10]) + fabs(g[3][11]) + fabs(g[3][12]) > 0);
    /* carried mass of the base: wood + fruit */
    CHECK(g[0][24] > 0.07);
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}
