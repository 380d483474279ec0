/* Mechanics inside the L+C dialect (src/lsys/mechlang.c): the language route against the native
 * cbm_plant route, the shipped Jirasek models (S-shaped branch, cherries), state kept through
 * rewriting, the plant kept between operations against a new build for each, declaration errors,
 * determinism, out-of-memory. */
#include "lsys/lsys_internal.h"
#include "lsys_util.h"

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

static const char CHAIN[] =
    "#include <lpfgall.h>\n"
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
        d.lateral = i == 2; /* bracketed before the continuing segment 3 */
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
    cbm_lsys *ls = lsys_from_text(ctx, "chain.l", CHAIN);
    CHECK_OK(cbm_lsys_step(ls));
    double g[8][MS];
    int sym = lsys_symbol(ls, "I");
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

/* The path of models/<name> (a static buffer: the next call overwrites it). */
static const char *model_path(const char *name)
{
    static char p[2048];
    snprintf(p, sizeof p, "%s/models/%s", test_source_dir(), name);
    return p;
}

static cbm_status load_model(cbm_context *ctx, const char *name, cbm_lsys **ls)
{
    return load(ctx, model_path(name), NULL, ls);
}

/* models/<name> loaded and reset, both checked at the caller's line (lsys_from_text reads the
 * file when there is no text). */
#define model_reset(ctx, name) lsys_from_text((ctx), model_path(name), NULL)

/* Fig. 2: the heading goes below the horizontal and the tip comes back above it. */
TEST(mechlang_jirasek_s_branch)
{
    cbm_context *ctx = test_ctx();
    cbm_lsys *ls = model_reset(ctx, "jirasek-s-branch.l");
    for (int i = 0; i < cbm_lsys_derivation_length(ls); i++)
        CHECK_OK(cbm_lsys_step(ls));
    static double g[64][MS];
    size_t n = segments(ls, lsys_symbol(ls, "I"), g, 64);
    CHECK_EQ_INT(n, 30);
    double lowest = 1;
    size_t lo = 0;
    for (size_t i = 0; i < n; i++)
        if (g[i][17] < lowest) {
            lowest = g[i][17];
            lo = i;
        }
    CHECK(g[0][17] > 0.1);     /* leaves the base above the horizontal */
    CHECK(lowest < -0.3);      /* sags well below it */
    CHECK(g[n - 1][17] > 0.1); /* the tip turns back up */
    CHECK(lo > 3 && lo < n - 3);
    /* pipe model: the base is thicker than the tip, by sqrt(n) */
    CHECK_REL(g[0][1], 0.002 * sqrt(30.0), 1e-9);
    CHECK_REL(g[n - 1][1], 0.002, 1e-9);
    /* its mechanics time: one Equilibrium() and one AddRings() per step (no time is asserted,
     * only that each kind was counted); reset starts the count over */
    cbm_lsys_mech_timing mt = cbm_lsys_mech_time(ls);
    CHECK_EQ_INT(mt.operations, 2 * cbm_lsys_derivation_length(ls));
    CHECK(mt.passes >= (size_t)cbm_lsys_derivation_length(ls));
    CHECK(mt.equilibrium >= mt.solve && mt.solve >= 0.0 && mt.rings >= 0.0 && mt.other == 0.0);
    CHECK_OK(cbm_lsys_reset(ls));
    mt = cbm_lsys_mech_time(ls);
    CHECK(mt.operations == 0 && mt.passes == 0 && mt.equilibrium == 0.0);
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

/* Fig. 5: the stem tip's elevation decreases at every step as the cherries grow. */
TEST(mechlang_jirasek_cherries)
{
    cbm_context *ctx = test_ctx();
    cbm_lsys *ls = model_reset(ctx, "jirasek-cherries.l");
    double prev[3] = {2, 2, 2};
    static double g[64][MS];
    for (int i = 0; i < cbm_lsys_derivation_length(ls); i++) {
        CHECK_OK(cbm_lsys_step(ls));
        size_t n = segments(ls, lsys_symbol(ls, "I"), g, 64);
        CHECK_EQ_INT(n, 24);
        for (int s = 0; s < 3; s++) {
            double hy = g[8 * s + 7][17];
            CHECK_MSG(hy < prev[s], "step %d stem %d: %g after %g", i + 1, s, hy, prev[s]);
            prev[s] = hy;
        }
    }
    CHECK(prev[0] < -0.5 && prev[1] < -0.5 && prev[2] < -0.5);
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

/* A production that copies a segment keeps its Omega and rings: a second equilibrium after the
 * rewrite finds the state it was given (no change), and the rings laid before the rewrite are
 * still there (section and rest rate). */
TEST(mechlang_state_survives_rewriting)
{
    static const char M[] = "#include <lpfgall.h>\n"
                            "derivation length: 2;\n"
                            "module I(MechSegment);\n"
                            "module A(int);\n"
                            "mechanics: I;\n"
                            "int step;\n"
                            "MechSegment S()\n"
                            "{\n"
                            "    MechSegment s;\n"
                            "    s.length = 0.1; s.a = 0.003; s.b = 0.003; s.E = 1e9;\n"
                            "    s.density = 900; s.age = -1;\n"
                            "    return s;\n"
                            "}\n"
                            "Start: { Tropism(0, 1, 0, 0.5); PipeModel(2, 3e-5); }\n"
                            "EndEach: { step = step + 1; if (step == 1) { AddRings(); }\n"
                            "           Equilibrium(); }\n"
                            "Axiom: Down(60) I(S()) I(S()) I(S()) A(0);\n"
                            "I(s) : { produce I(s); }\n"
                            "A(n) : { produce A(n + 1); }\n";
    cbm_context *ctx = test_ctx();
    cbm_lsys *ls = lsys_from_text(ctx, "rewrite.l", M);
    CHECK_OK(cbm_lsys_step(ls));
    double a[4][MS], b[4][MS];
    int sym = lsys_symbol(ls, "I");
    CHECK_EQ_INT(segments(ls, sym, a, 4), 3);
    CHECK(a[0][1] > 0.003 * 1.0001); /* thickened by the pipe model */
    CHECK(a[2][25] == 0);            /* new segments got their rest rate and age 0 */
    CHECK(fabs(a[2][8]) > 0);
    CHECK_OK(cbm_lsys_step(ls));
    CHECK_EQ_INT(segments(ls, sym, b, 4), 3);
    for (int i = 0; i < 3; i++)
        for (int f = 0; f < MS; f++)
            CHECK_NEAR(b[i][f], a[i][f], 1e-9 * (fabs(a[i][f]) + 1e-6));
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

/* ReactionWood: a leaning segment lays reaction wood in AddRings (a grows by the increment). */
static const char RW[] = "#include <lpfgall.h>\n"
                         "derivation length: 1;\n"
                         "module I(MechSegment);\n"
                         "mechanics: I;\n"
                         "int rings;\n"
                         "MechSegment S()\n"
                         "{\n"
                         "    MechSegment s;\n"
                         "    s.length = 0.2; s.a = 0.003; s.b = 0.003; s.E = 1e9;\n"
                         "    s.density = 900;\n"
                         "    return s;\n"
                         "}\n"
                         "Axiom: Down(80) I(S()) I(S()) I(S());\n";

TEST(mechlang_reaction_wood)
{
    static const char *const END[] = {
        "EndEach: { Equilibrium(); rings = AddRings(); }\n",
        "EndEach: { Equilibrium(); ReactionWood(0.01, 0.5, 0.001, 0); rings = AddRings(); }\n"};
    double a[2][4][MS];
    for (int k = 0; k < 2; k++) {
        char text[1024];
        snprintf(text, sizeof text, "%s%s", RW, END[k]);
        cbm_context *ctx = test_ctx();
        cbm_lsys *ls = lsys_from_text(ctx, "rw.l", text);
        CHECK_OK(cbm_lsys_step(ls));
        CHECK_EQ_INT(segments(ls, lsys_symbol(ls, "I"), a[k], 4), 3);
        cbm_lsys_destroy(ls);
        test_ctx_end(ctx);
    }
    /* leaning under load: the base bends; reaction wood adds 1 mm to a */
    CHECK(fabs(a[0][0][11]) > 0.01);
    /* without reaction wood nothing thickens (no leaf area, equal children); with it the tip
     * gains the increment and the pipe model carries the larger areas down */
    for (int i = 0; i < 3; i++)
        CHECK_NEAR(a[0][i][1], 0.003, 1e-15);
    CHECK_NEAR(a[1][2][1], 0.004, 1e-12);
    CHECK(a[1][1][1] > a[1][2][1] && a[1][0][1] > a[1][1][1]);
}

/* AgeWood: the modulus rises from E_juvenile towards E_adult (core ageing, Taylor-Hell 8.2). */
TEST(mechlang_age_wood)
{
    char text[2048];
    snprintf(text, sizeof text, "%s%s", RW,
             "EndEach: { Wood(1e9, 2e9, 10, 900, 0); AgeWood(4); AgeWood(1); Equilibrium(); }\n");
    cbm_context *ctx = test_ctx();
    cbm_lsys *ls = lsys_from_text(ctx, "age.l", text);
    CHECK_OK(cbm_lsys_step(ls));
    double g[4][MS];
    CHECK_EQ_INT(segments(ls, lsys_symbol(ls, "I"), g, 4), 3);
    for (int i = 0; i < 3; i++) {
        CHECK_REL(g[i][3], 1.5e9, 1e-12); /* 1 GPa + 5 years x (2 - 1) GPa / 10 years */
        CHECK_NEAR(g[i][25], 5, 1e-12);
    }
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

/* Breakage: the segment over its modulus of rupture goes with the rest of its branch. */
TEST(mechlang_break)
{
    static const char M[] = "#include <lpfgall.h>\n"
                            "derivation length: 1;\n"
                            "module I(MechSegment);\n"
                            "module Fruit(double);\n"
                            "mechanics: I;\n"
                            "mass: Fruit;\n"
                            "int broken;\n"
                            "MechSegment S(double r, double mor)\n"
                            "{\n"
                            "    MechSegment s;\n"
                            "    s.length = 0.1; s.a = r; s.b = r; s.E = 1e10;\n"
                            "    s.density = 600; s.mor = mor;\n"
                            "    return s;\n"
                            "}\n"
                            "EndEach: { Equilibrium(); broken = Break(); Equilibrium(); }\n"
                            "Axiom: I(S(0.02, 5e7)) SB Down(90) I(S(0.004, 1e6)) I(S(0.004, 5e7))\n"
                            "       Fruit(1) EB I(S(0.02, 5e7)) Fruit(0.1);\n";
    cbm_context *ctx = test_ctx();
    cbm_lsys *ls = lsys_from_text(ctx, "break.l", M);
    CHECK_OK(cbm_lsys_step(ls));
    double g[4][MS];
    int sym = lsys_symbol(ls, "I");
    CHECK_EQ_INT(segments(ls, sym, g, 4), 2);
    CHECK_EQ_INT(cbm_lsys_module_count(ls), 6); /* I [ Down ] I Fruit */
    CHECK(g[0][24] > 0.2 && g[0][24] < 0.3);    /* the broken branch's load is gone */
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

static void check_error(const char *text, const char *want)
{
    test_diags g;
    cbm_context *ctx = test_diag_ctx(&g);
    CHECK(ctx != NULL);
    if (!ctx)
        return;
    cbm_lsys *ls = NULL;
    CHECK_STATUS(load(ctx, "bad.l", text, &ls), CBM_E_SYNTAX);
    CHECK_MSG(strstr(g.text, want) != NULL, "message '%s' lacks '%s'", g.text, want);
    cbm_lsys_destroy(ls);
    cbm_context_destroy(ctx);
}

TEST(mechlang_declaration_errors)
{
    check_error("#include <lpfgall.h>\nmodule I(V3f);\nmechanics: I;\nAxiom: I(V3f(0,0,0));\n",
                "bad.l:3:12: mechanical module 'I' needs a MechSegment parameter");
    check_error("#include <lpfgall.h>\nmodule I(MechSegment);\nmodule Fr(V3f);\nmechanics: I;\n"
                "mass: Fr;\nAxiom: I(MechSegment());\n",
                "bad.l:5:7: the first parameter of point-mass module 'Fr' must be a number");
    check_error("#include <lpfgall.h>\nmodule I(MechSegment);\nmechanics: J;\n", "bad.l:3:12:");
    check_error(
        "#include <lpfgall.h>\nmodule I(MechSegment);\nmechanics: I;\nAxiom: I(MechSegment());\n"
        "I(s) : { Equilibrium(); produce I(s); }\n",
        "bad.l:5:10: Equilibrium() changes the whole string");
}

TEST(mechlang_runtime_errors)
{
    /* a zero length is refused with the segment named */
    static const char M[] =
        "#include <lpfgall.h>\nderivation length: 1;\nmodule I(MechSegment);\n"
        "mechanics: I;\nAxiom: I(MechSegment());\nEndEach: { Equilibrium(); }\n";
    cbm_context *ctx = test_ctx();
    cbm_lsys *ls = lsys_from_text(ctx, "zero.l", M);
    CHECK(cbm_lsys_step(ls) != CBM_OK);
    const char *msg = cbm_context_last_error(ctx);
    CHECK_MSG(strstr(msg, "mechanical segment 1: length must be > 0") != NULL, "%s", msg);
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

static cbm_status run_text(cbm_context *ctx, const char *path, const char *text, double *out,
                           size_t max, size_t *n)
{
    cbm_lsys *ls = NULL;
    cbm_status s = text ? load(ctx, path, text, &ls) : load_model(ctx, path, &ls);
    if (s == CBM_OK)
        s = cbm_lsys_reset(ls);
    while (s == CBM_OK && cbm_lsys_steps_done(ls) < cbm_lsys_derivation_length(ls))
        s = cbm_lsys_step(ls);
    if (s == CBM_OK && out) {
        cbm_lsys_cursor c;
        *n = 0;
        cbm_lsys_cursor_begin(ls, false, &c);
        while (cbm_lsys_cursor_next(ls, false, &c))
            for (int i = 0; i < c.nparams && *n < max; i++)
                out[(*n)++] = c.params[i];
    }
    cbm_lsys_destroy(ls);
    return s;
}

/* Fig. 3: the laterals hang well below the horizontal and their tips turn back up. */
TEST(mechlang_jirasek_hanging)
{
    cbm_context *ctx = test_ctx();
    cbm_lsys *ls = model_reset(ctx, "jirasek-hanging.l");
    for (int i = 0; i < cbm_lsys_derivation_length(ls); i++)
        CHECK_OK(cbm_lsys_step(ls));
    int sym = lsys_symbol(ls, "I"), sb = lsys_symbol(ls, "SB"), eb = lsys_symbol(ls, "EB");
    cbm_lsys_cursor c;
    cbm_lsys_cursor_begin(ls, false, &c);
    int depth = 0, laterals = 0;
    double lowest = 1, last = 1;
    while (cbm_lsys_cursor_next(ls, false, &c)) {
        if (c.symbol == sb) {
            depth++;
            lowest = last = 1;
        } else if (c.symbol == eb) {
            depth--;
            laterals++;
            CHECK_MSG(lowest < -0.6, "lateral %d: lowest heading %g", laterals, lowest);
            CHECK_MSG(last > lowest + 0.05, "lateral %d: tip %g, lowest %g", laterals, last,
                      lowest);
        } else if (c.symbol == sym && depth > 0) {
            last = c.params[17];
            lowest = last < lowest ? last : lowest;
        } else if (c.symbol == sym) {
            CHECK(c.params[17] > 0.9); /* the stem stands */
        }
    }
    CHECK_EQ_INT(laterals, 3);
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

TEST(mechlang_deterministic)
{
    cbm_context *ctx = test_ctx();
    static double a[20000], b[20000];
    size_t na = 0, nb = 0;
    CHECK_OK(run_text(ctx, "jirasek-hanging.l", NULL, a, 20000, &na));
    CHECK_OK(run_text(ctx, "jirasek-hanging.l", NULL, b, 20000, &nb));
    CHECK(na > 1000);
    CHECK_EQ_INT(na, nb);
    CHECK(memcmp(a, b, na * sizeof a[0]) == 0);
    test_ctx_end(ctx);
}

static cbm_status oom_chain(cbm_context *ctx, void *ud)
{
    (void)ud;
    return run_text(ctx, "chain.l", CHAIN, NULL, 0, NULL);
}

static cbm_status oom_growth(cbm_context *ctx, void *ud)
{
    (void)ud;
    char text[2048];
    snprintf(text, sizeof text, "%s%s", RW,
             "EndEach: { Equilibrium(); ReactionWood(0.01, 0.5, 0.001, 0); AddRings();\n"
             "           AgeWood(1); Equilibrium(); Break(); }\n");
    return run_text(ctx, "rw.l", text, NULL, 0, NULL);
}

TEST(mechlang_oom)
{
    CHECK(test_oom_loop(oom_chain, NULL) > 10);
    CHECK(test_oom_loop(oom_growth, NULL) > 10);
}

/* RingRate(kappa, min_ring): a segment that carries the pipe area of a section twice its radius
 * reaches kappa of the way there in one AddRings(); an increment thinner than min_ring waits. */
static double ring_after(cbm_context *ctx, const char *rate, double *rings)
{
    char t[1024];
    snprintf(t, sizeof t,
             "#include <lpfgall.h>\nderivation length: 2;\nmodule I(MechSegment);\n"
             "module R(double);\nmechanics: I;\ndouble n;\n"
             "MechSegment S() { MechSegment s; s.length = 0.1; s.a = 0.01; s.b = 0.01;\n"
             "  s.E = 1e9; s.density = 500; return s; }\n"
             "Start: { PipeModel(2, M_PI * 0.02 * 0.02); %s n = -1; }\n"
             "Axiom: I(S()) R(0);\nEndEach: { if (n < 0) n = AddRings(); }\n"
             "R(x) : { produce R(n); }\n",
             rate);
    cbm_lsys *ls = NULL;
    double a = -1;
    if (load(ctx, "rings.l", t, &ls) == CBM_OK && cbm_lsys_reset(ls) == CBM_OK &&
        cbm_lsys_step(ls) == CBM_OK && cbm_lsys_step(ls) == CBM_OK) {
        cbm_lsys_cursor c;
        cbm_lsys_cursor_begin(ls, false, &c);
        if (cbm_lsys_cursor_next(ls, false, &c))
            a = c.params[1];
        if (cbm_lsys_cursor_next(ls, false, &c))
            *rings = c.params[0];
    }
    cbm_lsys_destroy(ls);
    return a;
}

TEST(mechlang_ring_rate)
{
    cbm_context *ctx = test_ctx();
    double rings = -1;
    CHECK_NEAR(ring_after(ctx, "", &rings), 0.02, 1e-15); /* default kappa 1 */
    CHECK_NEAR(rings, 1, 0);
    CHECK_NEAR(ring_after(ctx, "RingRate(0.6, 0);", &rings), 0.01 + 0.6 * 0.01, 1e-15);
    CHECK_NEAR(rings, 1, 0);
    CHECK_NEAR(ring_after(ctx, "RingRate(0.6, 0.007);", &rings), 0.01, 0); /* 6 mm < 7 mm */
    CHECK_NEAR(rings, 0, 0);
    CHECK(ring_after(ctx, "RingRate(0, 0);", &rings) < 0); /* kappa must be in (0, 1] */
    const char *msg = cbm_context_last_error(ctx);
    CHECK_MSG(strstr(msg, "RingRate(kappa in (0, 1]") != NULL, "%s", msg);
    cbm_context_clear_errors(ctx);
    test_ctx_end(ctx);
}

/* Solver(tolerance, max passes, go on): with one pass allowed a bent chain does not converge;
 * the derivation stops, or with go on = 1 keeps the best state and Equilibrium() returns minus
 * the passes. */
static cbm_status solve_with(cbm_context *ctx, const char *solver, double *r)
{
    char t[1024];
    snprintf(t, sizeof t,
             "#include <lpfgall.h>\nderivation length: 2;\nmodule I(MechSegment);\n"
             "module R(double);\nmechanics: I;\ndouble r;\n"
             "MechSegment S() { MechSegment s; s.length = 0.5; s.a = 0.01; s.b = 0.01;\n"
             "  s.E = 1e9; s.density = 800; return s; }\n"
             "Start: { %s r = 0; }\n"
             "Axiom: Right(80) I(S()) I(S()) I(S()) R(0);\nEndEach: { r = Equilibrium(); }\n"
             "R(x) : { produce R(r); }\n",
             solver);
    cbm_lsys *ls = NULL;
    cbm_status s = load(ctx, "solver.l", t, &ls);
    if (s == CBM_OK)
        s = cbm_lsys_reset(ls);
    if (s == CBM_OK)
        s = cbm_lsys_step(ls);
    if (s == CBM_OK)
        s = cbm_lsys_step(ls);
    if (s == CBM_OK) {
        cbm_lsys_cursor c;
        cbm_lsys_cursor_begin(ls, false, &c);
        while (cbm_lsys_cursor_next(ls, false, &c))
            if (c.nparams == 1)
                *r = c.params[0];
    }
    cbm_lsys_destroy(ls);
    return s;
}

TEST(mechlang_solver_settings)
{
    cbm_context *ctx = test_ctx();
    double r = 0;
    CHECK_OK(solve_with(ctx, "", &r));
    CHECK(r > 1); /* converged, in some passes */
    CHECK(solve_with(ctx, "Solver(1e-12, 1, 0);", &r) == CBM_E_NOT_CONVERGED);
    cbm_context_clear_errors(ctx);
    r = 0;
    CHECK_OK(solve_with(ctx, "Solver(1e-12, 1, 1);", &r));
    CHECK(r < 0 && r >= -2);
    CHECK(solve_with(ctx, "Solver(0, 1, 1);", &r) == CBM_E_INVALID);
    const char *msg = cbm_context_last_error(ctx);
    CHECK_MSG(strstr(msg, "Solver(tolerance > 0") != NULL, "%s", msg);
    cbm_context_clear_errors(ctx);
    test_ctx_end(ctx);
}

/* Every operation kind several times per step without rewriting in between (the kept plant) and
 * after rewriting, with settings changed between operations, elliptical sections (the equivalent
 * ring keeps C_U only for circles), new segments (tropism), ageing and a Break() that cuts. */
static const char KEEP[] =
    "#include <lpfgall.h>\n"
    "derivation length: 6;\n"
    "module I(MechSegment);\n"
    "module A(int);\n"
    "module Fruit(double);\n"
    "mechanics: I;\n"
    "mass: Fruit;\n"
    "double st;\n"
    "int broken;\n"
    "MechSegment S(double len, double a, double b, double mor)\n"
    "{\n"
    "    MechSegment s;\n"
    "    s.length = len; s.a = a; s.b = b; s.E = 2e9; s.density = 800; s.mor = mor;\n"
    "    s.age = -1;\n"
    "    return s;\n"
    "}\n"
    "Start: { Tropism(0.3, 1, 0, 0.02); }\n"
    "EndEach: {\n"
    "    Equilibrium(); AddRings(); Equilibrium(); st = Stability(); AgeWood(0.5);\n"
    "    Gravity(0, -12, 0); Equilibrium(); Gravity(0, -9.81, 0);\n"
    "    Ground(-0.05, 1e4, 0.001); Equilibrium(); Stability(); Ground(0, 0, 0);\n"
    "    broken = broken + Break(); Equilibrium(); AddRings(); Break(); Equilibrium();\n"
    "}\n"
    "Axiom: I(S(0.2, 0.012, 0.009, 0)) Right(30) I(S(0.15, 0.008, 0.006, 0))\n"
    "       SB RollR(70) Right(25) I(S(0.1, 0.004, 0.003, 5e6)) Fruit(0.05) EB\n"
    "       I(S(0.15, 0.006, 0.006, 0)) Fruit(0.02) A(3);\n"
    "production:\n"
    "Fruit(m) : { produce Fruit(m * 1.3); }\n"
    "A(n) : { if (n > 0) produce SB Down(40) I(S(0.05, 0.003, 0.002, 0)) Fruit(0.01) EB A(n - 1); "
    "}\n";

/* Organ contact: three berries on stems 6.8 mm apart at the tips, radius 4 mm, swelling. */
static const char KEEPC[] =
    "#include <lpfgall.h>\n"
    "derivation length: 4;\n"
    "module I(MechSegment);\n"
    "module Grape(double, double);\n"
    "mechanics: I;\n"
    "mass: Grape(mass, radius);\n"
    "MechSegment S(double len, double r)\n"
    "{\n"
    "    MechSegment s;\n"
    "    s.length = len; s.a = r; s.b = r; s.E = 2e8; s.density = 1000;\n"
    "    return s;\n"
    "}\n"
    "Start: { Contact(5000, 0.0002); }\n"
    "EndEach: {\n"
    "    Equilibrium(); AddRings(); Equilibrium(); Gravity(0, -11, 0); Equilibrium();\n"
    "    Gravity(0, -9.81, 0); Equilibrium(); Break(); Equilibrium();\n"
    "}\n"
    "Axiom: Down(160) I(S(0.012, 0.0015)) SB Down(20) I(S(0.01, 0.0005)) Grape(0.0003, 0.004) EB\n"
    "       SB Up(20) I(S(0.01, 0.0005)) Grape(0.0003, 0.004) EB\n"
    "       I(S(0.01, 0.0005)) Grape(0.0003, 0.004);\n"
    "production:\n"
    "Grape(m, r) : { produce Grape(m * 1.4, r * 1.12); }\n";

/* Runs `text` (or the model file `path`) with the plant kept or not; every parameter of the
 * string after each step into out (n doubles), the timing in *mt. */
static cbm_status run_keep(cbm_context *ctx, const char *path, const char *text, bool keep,
                           double *out, size_t max, size_t *n, cbm_lsys_mech_timing *mt,
                           size_t *modules)
{
    cbm_lsys *ls = NULL;
    cbm_status s = text ? load(ctx, path, text, &ls) : load_model(ctx, path, &ls);
    if (s == CBM_OK)
        s = cbm_lsys_reset(ls);
    if (s == CBM_OK)
        cbm__lpfg_mech_keep(ls, keep);
    *n = 0;
    while (s == CBM_OK && cbm_lsys_steps_done(ls) < cbm_lsys_derivation_length(ls)) {
        s = cbm_lsys_step(ls);
        cbm_lsys_cursor c;
        cbm_lsys_cursor_begin(ls, false, &c);
        while (s == CBM_OK && cbm_lsys_cursor_next(ls, false, &c))
            for (int i = 0; i < c.nparams && *n < max; i++)
                out[(*n)++] = c.params[i];
    }
    if (s == CBM_OK) {
        *mt = cbm_lsys_mech_time(ls);
        *modules = cbm_lsys_module_count(ls);
    }
    cbm_lsys_destroy(ls);
    return s;
}

/* A kept plant gives the state a new build gives, bit for bit, after the same calls. */
static void check_keep(const char *path, const char *text, size_t min_kept)
{
    cbm_context *ctx = test_ctx();
    static double a[200000], b[200000];
    size_t na = 0, nb = 0, ma = 0, mb = 0;
    cbm_lsys_mech_timing ta = {0}, tb = {0};
    CHECK_OK(run_keep(ctx, path, text, true, a, 200000, &na, &ta, &ma));
    CHECK_OK(run_keep(ctx, path, text, false, b, 200000, &nb, &tb, &mb));
    CHECK(na > 50 && na < 200000);
    CHECK_EQ_INT(na, nb);
    CHECK_EQ_INT(ma, mb);
    CHECK(memcmp(a, b, na * sizeof a[0]) == 0);
    CHECK_EQ_INT(ta.operations, tb.operations);
    CHECK_EQ_INT(ta.passes, tb.passes);
    CHECK(ta.kept >= min_kept);
    CHECK_EQ_INT(tb.kept, 0);
    test_ctx_end(ctx);
}

TEST(mechlang_kept_plant_matches_rebuild)
{
    /* 13 operations a step; the ones after an operation that changed only results reuse the
     * plant; a Gravity/Ground change or a cut rebuilds */
    check_keep("keep.l", KEEP, 20);
    check_keep("keepc.l", KEEPC, 12);
    /* the shipped models: AddRings() then Equilibrium() each step */
    check_keep("jirasek-hanging.l", NULL, 20);
}

TEST(mechlang_kept_plant_break_cuts)
{
    /* the model above cuts its fruit branch in some step (the kept plant is dropped then) */
    cbm_context *ctx = test_ctx();
    cbm_lsys *ls = lsys_from_text(ctx, "keep.l", KEEP);
    while (cbm_lsys_steps_done(ls) < cbm_lsys_derivation_length(ls))
        CHECK_OK(cbm_lsys_step(ls));
    double g[8][MS];
    size_t n = segments(ls, lsys_symbol(ls, "I"), g, 8);
    CHECK(n >= 4 && n < 7); /* 4 in the axiom, 3 laterals grown */
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}
