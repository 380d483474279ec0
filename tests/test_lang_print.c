/* printf in models (both dialects) through the context's output sink, its compile-time checks
 * with locations, and the C int semantics of the L+C dialect (32-bit wrap, out-of-range casts). */
#include "lsys_util.h"
#include "test.h"

#include <cambium/lsys.h>
#include <stdio.h>
#include <string.h>

typedef struct captured {
    char text[4096];
    size_t n;
    int calls;
    char diags[4096];
} captured;

#define CHECK_STR(got, want)                                                                       \
    CHECK_MSG(strcmp((got), (want)) == 0, "got:\n%s\nwant:\n%s", (got), (want))

static void on_output(void *ud, const char *text, size_t n)
{
    captured *c = ud;
    if (c->n + n < sizeof c->text) {
        memcpy(c->text + c->n, text, n);
        c->n += n;
        c->text[c->n] = 0;
    }
    c->calls++;
}

static void on_diag(void *ud, const cbm_diagnostic *d)
{
    captured *c = ud;
    size_t n = strlen(c->diags);
    snprintf(c->diags + n, sizeof c->diags - n, "%s:%d:%d: %s\n", d->file ? d->file : "?", d->line,
             d->col, d->message);
}

static cbm_context *capture_ctx(captured *c)
{
    memset(c, 0, sizeof *c);
    cbm_context_def def = cbm_context_def_default();
    def.output = on_output;
    def.output_ud = c;
    def.diag = on_diag;
    def.diag_ud = c;
    cbm_context *ctx = NULL;
    if (cbm_context_create(&def, &ctx) != CBM_OK)
        return NULL;
    return ctx;
}

/* loads `text` as model m.l, runs `steps` steps; the status of the load */
static cbm_status run_model(cbm_context *ctx, const char *text, int steps)
{
    cbm_lsys *ls = NULL;
    cbm_status s = lsys_derive(ctx, "m.l", text, steps, &ls);
    cbm_lsys_destroy(ls);
    return s;
}

TEST(print_cpfg_dialect)
{
    captured c;
    cbm_context *ctx = capture_ctx(&c);
    CHECK(ctx != NULL);
    if (!ctx)
        return;
    CHECK_OK(run_model(ctx,
                       "Lsystem: 1\n"
                       "derivation length: 2\n"
                       "axiom: A(1)\n"
                       "A(x) : {printf(\"x=%g d=%d w=[%5.2f] h=%x %% s=%s c=%c\\n\", x, x*2.7, "
                       "x/3, -1, \"yes\", 64+x);} --> A(x+1)\n"
                       "endlsystem\n",
                       2));
    CHECK_STR(c.text, "x=1 d=2 w=[ 0.33] h=ffffffff % s=yes c=A\n"
                      "x=2 d=5 w=[ 0.67] h=ffffffff % s=yes c=B\n");
    CHECK_STR(c.diags, "");
    cbm_context_destroy(ctx);
}

TEST(print_lpfg_dialect_in_blocks_productions_and_functions)
{
    captured c;
    cbm_context *ctx = capture_ctx(&c);
    CHECK(ctx != NULL);
    if (!ctx)
        return;
    CHECK_OK(run_model(ctx,
                       "#include <lpfgall.h>\n"
                       "#include <stdio.h>\n"
                       "derivation length: 2;\n"
                       "module A(int, float);\n"
                       "int total;\n"
                       "void show(int v) { printf(\"f(%03d)\", v); }\n"
                       "Start: { total = 0; Printf(\"start\\n\"); }\n"
                       "EndEach: { printf(\"\\ttotal=%d (%.2e) %s\\n\", total, total / 3.0, "
                       "\"ok\"); }\n"
                       "End: { printf(\"end\\x21\\n\"); }\n"
                       "Axiom: A(1, 0.5) A(10, 0.25);\n"
                       "A(i, f): { total = total + i; show(i); printf(\" %-6.3f|\\n\", f); "
                       "produce A(i+1, f*2); }\n",
                       2));
    CHECK_STR(c.text, "start\n"
                      "f(001) 0.500 |\nf(010) 0.250 |\n\ttotal=11 (3.67e+00) ok\n"
                      "f(002) 1.000 |\nf(011) 0.500 |\n\ttotal=24 (8.00e+00) ok\n"
                      "end!\n");
    CHECK_STR(c.diags, "");
    cbm_context_destroy(ctx);
}

TEST(print_without_a_sink_is_discarded)
{
    cbm_context *ctx = test_ctx();
    CHECK_OK(run_model(ctx,
                       "#include <lpfgall.h>\nderivation length: 3;\nmodule A(int);\n"
                       "Axiom: A(1);\nA(i): { printf(\"%d\\n\", i); produce A(i+1); }\n",
                       3));
    test_ctx_end(ctx);
}

static void expect_print_error(const char *text, const char *want)
{
    captured c;
    cbm_context *ctx = capture_ctx(&c);
    CHECK(ctx != NULL);
    if (!ctx)
        return;
    CHECK_STATUS(run_model(ctx, text, 1), CBM_E_SYNTAX);
    CHECK_MSG(strstr(c.diags, want) != NULL, "want '%s' in:\n%s", want, c.diags);
    CHECK_STR(c.text, "");
    cbm_context_destroy(ctx);
}

#define LP "#include <lpfgall.h>\nmodule A(int);\nAxiom: A(1);\n" /* lines 1-3 */
#define CP "Lsystem: 1\naxiom: A(1)\n"                            /* lines 1-2 */

TEST(print_format_errors_with_locations)
{
    expect_print_error(LP "A(i): { printf(\"%d %d\\n\", i); produce A(i); }\n",
                       "m.l:4:9: printf: the format has 2 conversions, 1 argument given");
    expect_print_error(LP "A(i): { printf(\"%d\\n\", i, i); produce A(i); }\n",
                       "m.l:4:9: printf: the format has 1 conversion, 2 arguments given");
    expect_print_error(LP "A(i): { printf(\"%n\", i); produce A(i); }\n",
                       "m.l:4:9: printf: %n is not supported");
    expect_print_error(LP "A(i): { printf(\"%*d\", 3, i); produce A(i); }\n",
                       "m.l:4:9: printf: '*' widths are not supported");
    expect_print_error(LP "A(i): { printf(\"%q\", i); produce A(i); }\n",
                       "m.l:4:9: printf: unknown conversion '%q'");
    expect_print_error(LP "A(i): { printf(\"%d\", \"x\"); produce A(i); }\n",
                       "m.l:4:22: printf: argument 2 is a string; only %s prints a string");
    expect_print_error(LP "A(i): { printf(\"%s\", i); produce A(i); }\n",
                       "m.l:4:22: printf: argument 2 of %s must be a string literal");
    expect_print_error(LP "A(i): { V3f v; printf(\"%f\", v); produce A(i); }\n",
                       "m.l:4:29: printf: argument 2 is not a number");
    expect_print_error(LP "A(i): { printf(i); produce A(i); }\n",
                       "m.l:4:9: printf needs a format string as its first argument");
    expect_print_error(LP "A(i): { printf(\"%d, i); produce A(i); }\n",
                       "m.l:4:16: unterminated string");
    expect_print_error(LP "A(i): { printf(\"%500d\", i); produce A(i); }\n",
                       "m.l:4:9: printf: a width or precision above 200");
    expect_print_error(CP "A(x) : {printf(\"%d %d\", x);} --> A(x)\nendlsystem\n",
                       "m.l:3:9: printf: the format has 2 conversions, 1 argument given");
    expect_print_error(CP "A(x) : {printf(x);} --> A(x)\nendlsystem\n",
                       "m.l:3:9: printf needs a format string as its first argument");
    expect_print_error(CP "A(x) : {y = sin(\"x\");} --> A(x)\nendlsystem\n", "m.l:3:");
}

static cbm_status oom_print(cbm_context *ctx, void *ud)
{
    (void)ud;
    return run_model(ctx,
                     "#include <lpfgall.h>\nderivation length: 2;\nmodule A(int);\n"
                     "Axiom: A(1);\nA(i): { printf(\"%d %s\\n\", i, \"a longer literal\"); "
                     "produce A(i+1); }\n",
                     2);
}

TEST(print_out_of_memory)
{
    CHECK(test_oom_loop(oom_print, NULL) > 3);
}

/* the parameters of the single module of the string after `steps` steps */
static int module_params(cbm_context *ctx, const char *text, double *out, int max)
{
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = "m.l";
    def.text = text;
    cbm_lsys *ls = NULL;
    if (cbm_lsys_load(ctx, &def, &ls) != CBM_OK)
        return -1;
    int n = -1;
    if (cbm_lsys_reset(ls) == CBM_OK) {
        cbm_lsys_cursor c;
        cbm_lsys_cursor_begin(ls, false, &c);
        if (cbm_lsys_cursor_next(ls, false, &c)) {
            n = c.nparams < max ? c.nparams : max;
            memcpy(out, c.params, (size_t)n * sizeof *out);
        }
    }
    cbm_lsys_destroy(ls);
    return n;
}

TEST(lpfg_int_is_a_32_bit_c_int)
{
    cbm_context *ctx = test_ctx();
    double v[8];
    int n =
        module_params(ctx,
                      "#include <lpfgall.h>\nmodule A(int, int, int, int, int, int, int, int);\n"
                      "Axiom: A((int)3e9, (int)-2.7, 2147483647 + 1, 65536 * 65536 + 7,\n"
                      "  -2147483647 - 1, (int)(0.0/0.0), (-2147483647 - 1) / -1, 7 % -3);\n",
                      v, 8);
    CHECK_EQ_INT(n, 8);
    if (n == 8) {
        CHECK(v[0] == -2147483648.0); /* out of range: INT_MIN, as x86-64's cvttsd2si */
        CHECK(v[1] == -2.0);          /* toward zero */
        CHECK(v[2] == -2147483648.0); /* wraps */
        CHECK(v[3] == 7.0);           /* 2^32 + 7 wraps to 7 */
        CHECK(v[4] == -2147483648.0);
        CHECK(v[5] == -2147483648.0); /* NaN */
        CHECK(v[6] == -2147483648.0); /* INT_MIN / -1 wraps (C traps; the model goes on) */
        CHECK(v[7] == 1.0);
    }
    test_ctx_end(ctx);
}
