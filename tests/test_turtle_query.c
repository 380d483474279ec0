/* cpfg's quaternion query ?Q(x,y,z,w): cpfg's matrix-to-quaternion conversion applied to the
 * matrix whose rows are the turtle's H, L, U, vector part first. Checked against frames worked
 * by hand that take each branch of the conversion, against the first branch's formula for a
 * general frame, and through a model whose production reads the value (the environmental
 * interpretation before each step). */
#include "test.h"

#include "lsys_model/model_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The values ?Q(0,0,0,0) receives after the modules of `pre` (names and one parameter each). */
static void query_after(const char *const *pre, const double *par, size_t n, double q[4],
                        cbm_vec3 fr[3])
{
    cbm_context *ctx = test_ctx();
    cbm_view *view = NULL;
    CHECK_OK(cbm_view_create(ctx, &view));
    cbm_tmodule m[16];
    double p[16][4];
    memset(p, 0, sizeof p);
    size_t k = 0;
    for (size_t i = 0; i < n; i++) {
        p[k][0] = par[i];
        m[k] = (cbm_tmodule){pre[i], 1, p[k]};
        k++;
    }
    m[k] = (cbm_tmodule){"?", 0, p[k]};
    k++;
    size_t qi = k++;
    m[qi] = (cbm_tmodule){"Q", 4, p[qi]};
    cbm_turtle *t = NULL;
    CHECK_OK(cbm_turtle_interpret(ctx, view, NULL, m, k, NULL, &t));
    memcpy(q, p[qi], 4 * sizeof(double));
    if (t)
        cbm_turtle_state(t, NULL, &fr[0], &fr[1], &fr[2], NULL, NULL);
    cbm_turtle_destroy(t);
    cbm_view_destroy(view);
    test_ctx_end(ctx);
}

TEST(hand_worked_frames)
{
    cbm_vec3 fr[3];
    double q[4];
    /* H = +y, L = -x, U = -z: trace -1, so w = 0; x^2 = -(L.y + U.z)/2 = 1/2, y = H.y / 2x */
    query_after(NULL, NULL, 0, q, fr);
    const double h = sqrt(0.5);
    CHECK_NEAR(q[0], h, 1e-15);
    CHECK_NEAR(q[1], h, 1e-15);
    CHECK_NEAR(q[2], 0, 1e-15);
    CHECK_NEAR(q[3], 0, 1e-15);
    /* +(90): H = -x, L = -y, U = -z: w = 0, x^2 = 1, y = H.y / 2 = 0, z = H.z / 2 = 0 */
    const char *turn[1] = {"+"};
    const double ninety[1] = {90};
    query_after(turn, ninety, 1, q, fr);
    CHECK_NEAR(q[0], 1, 1e-15);
    CHECK_NEAR(q[1], 0, 1e-15);
    CHECK_NEAR(q[2], 0, 1e-15);
    CHECK_NEAR(q[3], 0, 1e-15);
    /* &(90): H = -z, L = -x, U = -y: trace 0, w = 1/2, x = (L.z - U.y)/2 = 1/2,
     * y = (U.x - H.z)/2 = 1/2, z = (H.y - L.x)/2 = 1/2 */
    const char *pitch[1] = {"&"};
    query_after(pitch, ninety, 1, q, fr);
    for (int i = 0; i < 4; i++)
        CHECK_NEAR(q[i], 0.5, 1e-15);
    /* +(90)/(90): H = -x, L = -z, U = +y: trace -1 and L.y + U.z = 0, so w = x = 0,
     * y^2 = (1 - U.z)/2 = 1/2, z = L.z / 2y = -sqrt(1/2) */
    const char *roll[2] = {"+", "/"};
    const double nn[2] = {90, 90};
    query_after(roll, nn, 2, q, fr);
    CHECK_NEAR(q[0], 0, 1e-15);
    CHECK_NEAR(q[1], h, 1e-15);
    CHECK_NEAR(q[2], -h, 1e-15);
    CHECK_NEAR(q[3], 0, 1e-15);
}

TEST(general_frame)
{
    /* a frame with no zero entry and 1 + trace = 0.22: the first branch, from the rows H, L, U */
    const char *mods[3] = {"&", "/", "+"};
    const double ang[3] = {80, 20, 15};
    cbm_vec3 f[3] = {{0}};
    double q[4] = {0};
    query_after(mods, ang, 3, q, f);
    double w = sqrt(0.25 * (1.0 + f[0].x + f[1].y + f[2].z));
    CHECK(w > 0.1);
    CHECK_NEAR(q[3], w, 1e-15);
    CHECK_NEAR(q[0], (f[1].z - f[2].y) / (4 * w), 1e-15);
    CHECK_NEAR(q[1], (f[2].x - f[0].z) / (4 * w), 1e-15);
    CHECK_NEAR(q[2], (f[0].y - f[1].x) / (4 * w), 1e-15);
    /* cpfg's frame is left-handed (L = H x U), so the four numbers are not a unit quaternion in
     * general (as cpfg gives them) */
    double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    CHECK(fabs(n - 1.0) > 1e-3);
}

TEST(a_production_reads_the_quaternion)
{
    /* before step 1 the turtle fills ?Q after +(90) with (1,0,0,0): A becomes B */
    cbm_context *ctx = test_ctx();
    cbm_model_def def = {cbm_lsys_def_default(), NULL, 0};
    def.lsys.path = "q.l";
    def.lsys.text = "Lsystem: 1\nderivation length: 1\nconsider: ?Q\nAxiom: +(90)A?Q(0,0,0,0)\n"
                    "A > ?Q(x,y,z,w) : x > 0.99 && w < 0.01 --> B\nendlsystem\n";
    cbm_model *m = NULL;
    CHECK_OK(cbm_model_load(ctx, &def, &m));
    if (m) {
        CHECK_OK(cbm_model_reset(m));
        CHECK(cbm_model_has_queries(m));
        CHECK_OK(cbm_model_step(m));
        cbm_lsys *ls = cbm_model_lsys(m);
        cbm_lsys_cursor c;
        cbm_lsys_cursor_begin(ls, false, &c);
        char syms[8] = {0};
        int n = 0;
        while (cbm_lsys_cursor_next(ls, false, &c) && n < 7)
            syms[n++] = (char)c.symbol;
        CHECK_MSG(!strcmp(syms, "+B?Q"), "%s", syms);
        cbm_model_destroy(m);
    }
    test_ctx_end(ctx);
}

/* The string after each of `steps` steps of model text (symbols and parameters with 17 digits)
 * and the status and message of the step that stopped, if one did: the query pass passing over
 * the branches no query depends on (pass_over) or interpreting every module. */
static char *query_run(const char *text, int steps, bool pass_over)
{
    cbm_context *ctx = test_ctx();
    cbm_model_def def = {cbm_lsys_def_default(), NULL, 0};
    def.lsys.path = "pass-over.l";
    def.lsys.text = text;
    cbm_model *m = NULL;
    CHECK_OK(cbm_model_load(ctx, &def, &m));
    size_t cap = 1 << 16, len = 0;
    char *out = calloc(cap, 1);
    if (!m || !out) {
        cbm_model_destroy(m);
        test_ctx_end(ctx);
        return out;
    }
    cbm__model_set_pass_over(m, pass_over);
    cbm_status s = cbm_model_reset(m);
    for (int k = 0; k < steps && s == CBM_OK; k++) {
        s = cbm_model_step(m);
        cbm_lsys *ls = cbm_model_lsys(m);
        cbm_lsys_cursor c;
        cbm_lsys_cursor_begin(ls, false, &c);
        while (s == CBM_OK && cbm_lsys_cursor_next(ls, false, &c) && len + 512 < cap) {
            len += (size_t)snprintf(out + len, cap - len, "%c", c.symbol);
            for (int i = 0; i < c.nparams; i++)
                len +=
                    (size_t)snprintf(out + len, cap - len, "%c%.17g", i ? ',' : '(', c.params[i]);
            if (c.nparams)
                len += (size_t)snprintf(out + len, cap - len, ")");
        }
        len += (size_t)snprintf(out + len, cap - len, "\n");
    }
    if (s != CBM_OK)
        snprintf(out + len, cap - len, "status %d: %s", (int)s, cbm_context_last_error(ctx));
    cbm_model_destroy(m);
    test_ctx_end(ctx);
    return out;
}

/* The per-step query pass passes over the branches that hold no query and act only on the
 * turtle's state (src/lsys_model/model.c, pass_over_branch): the strings, the query values and
 * the errors are those of the pass that interprets every module. Decorations beside queries,
 * nested in branches that hold one, longer than the read-ahead; a move that overflows in a branch
 * without a query (an error either way: F is not passed over); `$` in a branch, which changes the
 * sub-L-systems' scale stack (brackets do not restore it: a later `$` finds it popped); unknown
 * symbols, `@` commands, colours and widths. */
TEST(query_pass_passes_over_branches)
{
    static const char *const models[] = {
        "Lsystem: 1\nderivation length: 6\nconsider: ?P\n"
        "Axiom: [;(1)@M(1,2,0)@c(0.3)] A?P(0,0)\n"
        "A > ?P(x,y) : y < 4 --> F(1)[+(30)[;(3)@O(0.5)]B?P(0,0)][-(30),(2)!(0.2)C[/(9)@v]]"
        "A?P(0,0)\n"
        "B > ?P(x,y) : x > -10 --> F(0.5)[&(20)@vD#]B?P(0,0)\n"
        "C --> [^(5)|\\(3)'(2)E[X[Y[Z]]]]C\nendlsystem\n",
        "Lsystem: 1\nderivation length: 3\nconsider: ?P\n"
        "Axiom: [+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)"
        "+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)+(1)] F(1) A?P(0,0)\n"
        "A > ?P(x,y) : y > 0.5 --> [-(90)-(90)-(90)] F(2) A ?P(0,0)\nendlsystem\n",
        "Lsystem: 1\nderivation length: 2\nconsider: ?P\n"
        "Axiom: [;(1)@O(2)X][F(1e308)F(1e308)] A?P(0,0)\nA --> A\nendlsystem\n",
        "Lsystem: 1\nderivation length: 2\nconsider: ?P\n"
        "Axiom: ?(2,0.5)[$]$F(1)A?P(0,0)\nA > ?P(x,y) : y > 0.75 --> B\nendlsystem\n"
        "Lsystem: 2\nAxiom: X\nendlsystem\n",
    };
    static const int steps[] = {6, 3, 2, 2};
    for (size_t k = 0; k < sizeof models / sizeof models[0]; k++) {
        char *on = query_run(models[k], steps[k], true);
        char *off = query_run(models[k], steps[k], false);
        CHECK_MSG(on && off && !strcmp(on, off), "model %zu: passing over gives\n%s\nnot\n%s", k,
                  on ? on : "", off ? off : "");
        if (k == 2)
            CHECK_MSG(on && strstr(on, "no longer finite"), "model 2: %s", on ? on : "");
        free(on);
        free(off);
    }
}
