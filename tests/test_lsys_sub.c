/* cpfg sub-L-systems (cpfg manual 7.2) beyond the golden models of tests/lsys/sublsys-*.l:
 * errors with their file:line:col, a call to a missing L-system found when deriving, the
 * turtle's scale inside ?(id, s) ... $ (lengths, widths, nesting) and @D @Di @Dd and the view's
 * "initial scale:", query modules that a ?(id) does not shadow, an unmatched $, a stochastic
 * sub-L-system's draws, and allocation
 * failure at every point of a run with sub-L-systems. Geometry is checked against values worked
 * by hand from the rules: a length or a width given as a parameter is multiplied by the product
 * of the scales of the open sub-L-systems. */
#include "lsys_util.h"

#include <math.h>
#include <stdio.h>

static cbm_status load_text(cbm_context *ctx, const char *text, cbm_lsys **ls)
{
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = "sub.l";
    def.text = text;
    return cbm_lsys_load(ctx, &def, ls);
}

TEST(errors_name_the_place)
{
    test_diags g;
    cbm_context *ctx = test_diag_ctx(&g);
    cbm_lsys *ls = NULL;
    cbm_status s = load_text(ctx,
                             "Lsystem: 1\n"               /* 1 */
                             "derivation length: 2\n"     /* 2 */
                             "Axiom: A?(7,1)B$\n"         /* 3: no L-system 7 */
                             "A --> ?(2)C$?(1)A$\n"       /* 4: 2 and 1 exist */
                             "Lsystem: 2\n"               /* 5: no endlsystem before */
                             "Axiom: C\n"                 /* 6 */
                             "endlsystem\n"               /* 7 */
                             "Lsystem: 2\n"               /* 8: a second 2 */
                             "Axiom: C\n"                 /* 9 */
                             "endlsystem\n"               /* 10 */
                             "Lsystem: leaf\n"            /* 11: not a number */
                             "C --> D\n"                  /* 12: production before axiom */
                             "endlsystem\n"               /* 13: no axiom (11) */
                             "Lsystem: 3\n"               /* 14 */
                             "Axiom: C\n"                 /* 15 */
                             "C(x) --> ?(4, x)C(x)$\n"    /* 16: no L-system 4 */
                             "C > * : * --> ?(5 - 2)C$\n" /* 17: 3 exists; `> *` empty */
                             "* < C --> D\n"              /* 18: empty left context */
                             "* C --> D\n",               /* 19: '*' not a context */
                             &ls);
    CHECK_STATUS(s, CBM_E_SYNTAX);
    CHECK(ls == NULL);
    CHECK_MSG(strstr(g.text, "sub.l:3:9: ?(7, ...) calls a sub-L-system, but no L-system of the "
                             "file is labelled 7"),
              "%s", g.text);
    CHECK_MSG(strstr(g.text, "sub.l:5:1: expected 'endlsystem' at the end of the L-system"), "%s",
              g.text);
    CHECK_MSG(strstr(g.text, "sub.l:8:10: a second L-system labelled 2"), "%s", g.text);
    CHECK_MSG(strstr(g.text, "sub.l:11:10: the label of a sub-L-system must be a number"), "%s",
              g.text);
    CHECK_MSG(strstr(g.text, "sub.l:12:1: expected a header item"), "%s", g.text);
    CHECK_MSG(strstr(g.text, "sub.l:11:1: the L-system has no axiom:"), "%s", g.text);
    CHECK_MSG(strstr(g.text, "sub.l:16:10: ?(4, ...) calls a sub-L-system"), "%s", g.text);
    CHECK_MSG(strstr(g.text, "sub.l:19:1: expected a predecessor module, found '*'"), "%s", g.text);
    CHECK_MSG(!strstr(g.text, "sub.l:4:") && !strstr(g.text, "sub.l:17:") &&
                  !strstr(g.text, "sub.l:18:"),
              "%s", g.text);
    /* the file ends before the last L-system does */
    CHECK_MSG(strstr(g.text, "sub.l:14:1: expected 'endlsystem' at the end of the L-system (the "
                             "file ends first)"),
              "%s", g.text);
    CHECK_EQ_INT(g.count, 10); /* 9 and the summary */
    cbm_context_destroy(ctx);
}

TEST(missing_lsystem_found_when_deriving)
{
    /* the label is a parameter: known only when the step runs */
    test_diags g;
    cbm_context *ctx = test_diag_ctx(&g);
    cbm_lsys *ls = NULL;
    CHECK_OK(load_text(ctx,
                       "Lsystem: 1\nderivation length: 3\nAxiom: A(2)\n"
                       "A(x) --> ?(x)B$A(x+5)\nendlsystem\n"
                       "Lsystem: 2\nAxiom: B\nB --> BB\nendlsystem\n",
                       &ls));
    CHECK_OK(cbm_lsys_reset(ls));
    CHECK_OK(cbm_lsys_step(ls));
    CHECK_OK(cbm_lsys_step(ls)); /* ?(2)B$ is derived: B --> BB; ?(7)B$ is new */
    CHECK_STATUS(cbm_lsys_step(ls), CBM_E_RUNTIME);
    CHECK_MSG(strstr(g.text, "step 3: ?(7, ...) calls a sub-L-system, but no L-system of the "
                             "file is labelled 7"),
              "%s", g.text);
    CHECK_EQ_INT(cbm_lsys_steps_done(ls), 2);
    tbuf b = {0};
    format_string(ls, false, false, &b);
    CHECK_MSG(!strcmp(b.s, "?(2)BB$?(7)B$A(12)"), "%s", b.s);
    tb_free(&b);
    cbm_lsys_destroy(ls);
    cbm_context_destroy(ctx);
}

TEST(unmatched_dollar_is_passed_over)
{
    /* a $ with no sub-L-system open leaves the main L-system current */
    cbm_context *ctx = test_ctx();
    cbm_lsys *ls = NULL;
    CHECK_OK(load_text(ctx,
                       "Lsystem: 1\nderivation length: 1\nAxiom: $A?(2)A$$A\nA --> B\n"
                       "endlsystem\nLsystem: 2\nAxiom: A\nA --> C\nendlsystem\n",
                       &ls));
    CHECK_OK(cbm_lsys_reset(ls));
    CHECK_OK(cbm_lsys_step(ls));
    tbuf b = {0};
    format_string(ls, false, false, &b);
    CHECK_MSG(!strcmp(b.s, "$B?(2)C$$B"), "%s", b.s);
    tb_free(&b);
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

TEST(stochastic_sub_lsystem_draws_for_its_own_modules)
{
    /* L-system 2 is stochastic (X : 1, Y : 9: X when 10 d <= 1), 1 is not: one drand48() draw
     * per module of L-system 2 ($ included), none for L-system 1's. From the default state the
     * draws are 3.9e-14, 0.00099, 0.0416, 0.177, 0.365, 0.0913, 0.0923: the four B give XXXY,
     * $ takes 0.365, the next two B give XX. */
    cbm_context *ctx = test_ctx();
    cbm_lsys *ls = NULL;
    CHECK_OK(load_text(ctx,
                       "Lsystem: 1\nderivation length: 1\nAxiom: BA?(2)BBBB$B?(2)BB$\n"
                       "B --> Z\nendlsystem\n"
                       "Lsystem: 2\nAxiom: B\nB --> X : 1\nB --> Y : 9\nendlsystem\n",
                       &ls));
    CHECK_OK(cbm_lsys_reset(ls));
    CHECK_OK(cbm_lsys_step(ls));
    tbuf b = {0};
    format_string(ls, false, false, &b);
    CHECK_MSG(!strcmp(b.s, "ZA?(2)XXXY$Z?(2)XX$"), "%s", b.s);
    tb_free(&b);
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

/* ---- the turtle's scale ---- */

static cbm_model *load_model(cbm_context *ctx, const char *text, const char *view_text)
{
    char vpath[4096];
    const char *sides[1] = {vpath};
    size_t nside = 0;
    if (view_text) {
        snprintf(vpath, sizeof vpath, "%s/sub.v", test_tmp_dir());
        FILE *f = fopen(vpath, "wb");
        CHECK(f != NULL);
        if (!f)
            return NULL;
        fputs(view_text, f);
        fclose(f);
        nside = 1;
    }
    cbm_model_def def = {cbm_lsys_def_default(), sides, nside};
    def.lsys.path = "sub.l";
    def.lsys.text = text;
    cbm_model *m = NULL;
    CHECK_OK(cbm_model_load(ctx, &def, &m));
    return m;
}

/* The segments drawn by the model's axiom: lengths along +y and start radii. */
static size_t segments(cbm_context *ctx, const char *text, const char *view, double *len,
                       double *r0, size_t max, double *final_width)
{
    cbm_model *m = load_model(ctx, text, view);
    if (!m)
        return 0;
    CHECK_OK(cbm_model_reset(m));
    cbm_turtle *t = NULL;
    CHECK_OK(cbm_model_interpret(m, NULL, true, &t));
    size_t n = 0;
    if (t) {
        const cbm_prim *p = cbm_turtle_prims(t);
        for (size_t i = 0; i < cbm_turtle_prim_count(t) && n < max; i++) {
            if (p[i].kind != CBM_PRIM_CYLINDER)
                continue;
            len[n] = p[i].p1.y - p[i].p0.y;
            r0[n++] = p[i].r0;
        }
        cbm_turtle_state(t, NULL, NULL, NULL, NULL, final_width, NULL);
        cbm_turtle_destroy(t);
    }
    cbm_model_destroy(m);
    return n;
}

TEST(sub_lsystem_scales_lengths_and_widths)
{
    /* width 1 (the view's default), scale 1. ?(2,0.5): scale 0.5, width 1 * 0.5 / 1 = 0.5;
     * F(1) is 0.5 long; !(2) sets 2 * 0.5 = 1; ?(3,0.5): scale 0.25, width 0.5; F(1): 0.25;
     * $: scale 0.5, width 1; F(1): 0.5; $: scale 1, width 2; F(1): 1. Brackets keep the scale
     * they saved: [?(2,0.5)F] then F(1) at scale 1. */
    cbm_context *ctx = test_ctx();
    double len[16], r0[16], w = 0;
    size_t n = segments(ctx,
                        "Lsystem: 1\nAxiom: F(1)?(2,0.5)F(1)!(2)?(3,0.5)F(1)$F(1)$F(1)"
                        "[?(2,4)]F(1)\nendlsystem\n"
                        "Lsystem: 2\nAxiom: F\nendlsystem\nLsystem: 3\nAxiom: F\nendlsystem\n",
                        NULL, len, r0, 16, &w);
    const double want_len[6] = {1, 0.5, 0.25, 0.5, 1, 1};
    const double want_r0[6] = {0.5, 0.25, 0.25, 0.5, 1, 1};
    CHECK_EQ_INT((long)n, 6);
    for (size_t i = 0; i < n && i < 6; i++) {
        CHECK_NEAR(len[i], want_len[i], 1e-12);
        CHECK_NEAR(r0[i], want_r0[i], 1e-7);
    }
    CHECK_NEAR(w, 2.0, 1e-7);
    test_ctx_end(ctx);
}

TEST(scale_commands_and_initial_scale)
{
    /* @D(2): F(1) is 2; @Di(3): 6; @Dd(2): 3; @Di without parameter: the view's scale
     * multiplier 1.5: 4.5; with "initial scale: 2", ?(2,0.5) inside gives 1 (2 * 0.5) and $
     * returns to 2, not to the @D scale (cpfg's sub-L-system stack). */
    cbm_context *ctx = test_ctx();
    double len[16], r0[16], w = 0;
    size_t n = segments(ctx,
                        "Lsystem: 1\nAxiom: F(1)@D(2)F(1)@Di(3)F(1)@Dd(2)F(1)@DiF(1)"
                        "?(2,0.5)F(1)$F(1)\nendlsystem\nLsystem: 2\nAxiom: F\nendlsystem\n",
                        "initial scale: 2\nscale multiplier: 1.5\n", len, r0, 16, &w);
    const double want[7] = {2, 2, 6, 3, 4.5, 1, 2};
    CHECK_EQ_INT((long)n, 7);
    for (size_t i = 0; i < n && i < 7; i++)
        CHECK_NEAR(len[i], want[i], 1e-12);
    test_ctx_end(ctx);
}

TEST(a_call_is_not_a_query)
{
    /* ?(2,0.5) is followed by B(5), whose image is C(6): neither is a query module; the query
     * ?P after $ receives the position 1 (F(2) at scale 0.5) and B keeps its parameter */
    cbm_context *ctx = test_ctx();
    cbm_model *m =
        load_model(ctx,
                   "Lsystem: 1\nderivation length: 1\nAxiom: ?(2,0.5)B(5)F(2)$?P(0,0,0)\n"
                   "homomorphism\nB(x) --> C(x+1)\nendlsystem\n"
                   "Lsystem: 2\nAxiom: B(1)\nhomomorphism\nB(x) --> C(x+1)\nendlsystem\n",
                   NULL);
    if (m) {
        CHECK_OK(cbm_model_reset(m));
        CHECK_OK(cbm_model_step(m));
        CHECK_OK(cbm_model_interpret(m, NULL, false, NULL));
        tbuf b = {0};
        format_string(cbm_model_lsys(m), false, false, &b);
        CHECK_MSG(!strcmp(b.s, "?(2,0.5)B(5)F(2)$?P(0,1,0)"), "%s", b.s);
        tb_free(&b);
        cbm_model_destroy(m);
    }
    test_ctx_end(ctx);
}

/* ---- out of memory ---- */
static cbm_status oom_run(cbm_context *ctx, void *ud)
{
    const char *text = "Lsystem: 1\nderivation length: 3\nAxiom: A(1)\n"
                       "A(x) --> I?(2,0.5)B(x)$A(x+1)\nhomomorphism\nI --> F\nendlsystem\n"
                       "Lsystem: 2\nignore: +\nAxiom: B(1)\nStartEach: {n = n + 1;}\n"
                       "B(x) --> +C(x)?(3)D$\nC(x) --> C(x+n)\n"
                       "decomposition\nC(x) --> E(x)\nhomomorphism\nseed: 3\nE(x) --> F(ran(x))\n"
                       "endlsystem\nLsystem: 3\nAxiom: D\nD --> DD\nendlsystem\n";
    return lsys_derive_homomorphism(ctx, "oom.l", text, 3, ud);
}

/* Every allocation failed in turn; the last run, without a failure, derived the three steps and
 * the strings a run with memory enough derives. */
TEST(out_of_memory_at_every_allocation)
{
    /* I ?(2,0.5) + E(1) ?(3) D D $ $ I ?(2,0.5) + E(2) ?(3) D $ $ I ?(2,0.5) B(3) $ A(4) */
    lsys_check_out_of_memory(oom_run, 3, 22);
}
