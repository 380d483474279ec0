#define _XOPEN_SOURCE 700
/* Unit tests of the language front end and the engine: the rand48 generator against the C
 * library, diagnostics with recovery, #include and -D, limits, out-of-memory behaviour, and
 * stochastic choice. */
#include "lsys_util.h"

#include "lang/lang.h"

#include <math.h>

/* ---- helpers ---- */
static cbm_status load_text(cbm_context *ctx, const char *text, bool float32, cbm_lsys **ls)
{
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = "test.l";
    def.text = text;
    def.float32 = float32;
    return cbm_lsys_load(ctx, &def, ls);
}

/* Derives `text` for n steps and returns the string (caller frees), NULL on failure. */
static char *derive_text(cbm_context *ctx, const char *text, int n)
{
    cbm_lsys *ls = NULL;
    cbm_status s = lsys_derive(ctx, "test.l", text, n, &ls);
    tbuf b = {0};
    if (s == CBM_OK)
        format_string(ls, false, false, &b);
    cbm_lsys_destroy(ls);
    return b.s;
}

/* ---- the generator ---- */
TEST(rand48_matches_the_c_library)
{
    cbm__rand48 r;
    srand48(12345);
    cbm__rand48_seed16(&r, 0x330E, 12345 & 0xFFFF, 12345 >> 16);
    for (int i = 0; i < 1000; i++)
        CHECK(cbm__rand48_next(&r) == drand48());
    unsigned short x[3] = {0x330E, 7, 3};
    cbm__rand48_seed16(&r, 0x330E, 7, 3);
    for (int i = 0; i < 1000; i++)
        CHECK(cbm__rand48_next(&r) == erand48(x));
}

TEST(random_functions_follow_cpfg)
{
    cbm_context *ctx = test_ctx();
    /* nran before any srand returns its mean (cpfg's pair cache starts full); ran draws from
     * erand48 with state {0x330E, 0, 0}; srand(5) restarts it */
    char *s = derive_text(ctx,
                          "Lsystem: 1\nderivation length: 0\n"
                          "Axiom: A(nran(3,1), ran(1)) B(srand(5), ran(2), ran(2))\nendlsystem\n",
                          0);
    CHECK(s != NULL);
    unsigned short x[3] = {0x330E, 0, 0};
    double r0 = erand48(x);
    unsigned short y[3] = {0x330E, 5, 0};
    double r1 = 2 * erand48(y), r2 = 2 * erand48(y);
    char want[256];
    snprintf(want, sizeof want, "A(3,%g)B(0,%g,%g)", r0, r1, r2);
    CHECK_MSG(s && !strcmp(s, want), "got %s, expected %s", s ? s : "(null)", want);
    free(s);
    test_ctx_end(ctx);
}

TEST(stochastic_choice_draws_drand48_per_module)
{
    /* three equiprobable productions; one drand48 per module, in the string's order */
    cbm_context *ctx = test_ctx();
    const char *model = "Lsystem: 1\nderivation length: 1\nAxiom: FFFFFFFFFFFFFFFFFFFFxF\n"
                        "F --> A : 1\nF --> B : 1\nF --> C : 2\nendlsystem\n";
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = "s.l";
    def.text = model;
    def.seed = 99;
    cbm_lsys *ls = lsys_from_def(ctx, &def);
    CHECK_OK(cbm_lsys_step(ls));
    tbuf got = {0};
    format_string(ls, false, false, &got);
    srand48(99);
    char want[64] = {0};
    const char *ax = "FFFFFFFFFFFFFFFFFFFFxF";
    for (int i = 0; ax[i]; i++) {
        double r = drand48();
        if (ax[i] != 'F') {
            want[i] = ax[i];
            continue;
        }
        float sc = (float)(4.0f * r) - 1.0f; /* the model's sc -= 1, then once more */
        want[i] = sc <= 0 ? 'A' : sc - 1.0f <= 0 ? 'B' : 'C';
    }
    CHECK_MSG(!strcmp(got.s, want), "got %s, expected %s", got.s, want);
    tb_free(&got);
    /* frequencies over a long string */
    cbm_lsys_destroy(ls);
    ls = NULL;
    def.text = "Lsystem: 1\nderivation length: 12\nAxiom: F\nF --> FF : 1\nF --> A : 0\n"
               "endlsystem\n";
    ls = lsys_from_def(ctx, &def);
    for (int i = 0; i < 12; i++)
        CHECK_OK(cbm_lsys_step(ls));
    CHECK_EQ_INT(cbm_lsys_module_count(ls), 4096); /* probability 0 never chosen */
    cbm_lsys_destroy(ls);
    ls = NULL;
    def.text = "Lsystem: 1\nderivation length: 1\nAxiom: F\nF --> G : 1\nendlsystem\n";
    CHECK_OK(cbm_lsys_load(ctx, &def, &ls));
    cbm_lsys_destroy(ls);
    ls = NULL;
    def.text = "Lsystem: 1\nderivation length: 1\n"
               "Axiom: FFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFF\n"
               "F --> FFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFFF\n"
               "endlsystem\n";
    CHECK_OK(cbm_lsys_load(ctx, &def, &ls));
    cbm_lsys_destroy(ls);
    ls = NULL;
    def.text = "Lsystem: 1\nderivation length: 7\nAxiom: F\nF --> FA : 1\nF --> FB : 3\n"
               "endlsystem\n";
    ls = lsys_from_def(ctx, &def);
    int na = 0, nb = 0;
    for (int i = 0; i < 7; i++)
        CHECK_OK(cbm_lsys_step(ls));
    cbm_lsys_cursor c;
    cbm_lsys_cursor_begin(ls, false, &c);
    while (cbm_lsys_cursor_next(ls, false, &c)) {
        na += c.symbol == 'A';
        nb += c.symbol == 'B';
    }
    CHECK_EQ_INT(na + nb, 7);
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

TEST(stochastic_frequencies)
{
    cbm_context *ctx = test_ctx();
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = "f.l";
    def.text =
        "Lsystem: 1\nderivation length: 1\nAxiom: X\nX --> F(0)F(0)F(0)F(0)F(0)F(0)F(0)F(0)\n"
        "F(n) --> A : 1\nF(n) --> B : 3\nendlsystem\n";
    def.seed = 7;
    int a = 0, b = 0;
    for (int rep = 0; rep < 500; rep++) {
        cbm_lsys *ls = NULL;
        def.seed = rep;
        ls = lsys_from_def(ctx, &def);
        CHECK_OK(cbm_lsys_step(ls));
        CHECK_OK(cbm_lsys_step(ls));
        cbm_lsys_cursor c;
        cbm_lsys_cursor_begin(ls, false, &c);
        while (cbm_lsys_cursor_next(ls, false, &c)) {
            a += c.symbol == 'A';
            b += c.symbol == 'B';
        }
        cbm_lsys_destroy(ls);
    }
    CHECK_EQ_INT(a + b, 4000);
    /* P(A) = 1/4: 1000 expected, standard deviation 27 */
    CHECK_MSG(a > 880 && a < 1120, "%d A of 4000", a);
    test_ctx_end(ctx);
}

/* ---- diagnostics ---- */
TEST(several_errors_with_locations)
{
    test_diags g;
    cbm_context *ctx = test_diag_ctx(&g);
    cbm_lsys *ls = NULL;
    cbm_status s = load_text(ctx,
                             "Lsystem: 1\n"
                             "derivation length: 3\n"
                             "Axiom: A(1\n"       /* 3: missing ) */
                             "A(x) --> B(x+)\n"   /* 4: expression expected */
                             "B(y) : y > --> C\n" /* 5: expression expected */
                             "C => D\n"           /* 6: arrow expected */
                             "D(x) --> E(zz)\n"   /* 7: undefined name */
                             "endlsystem\n",
                             false, &ls);
    CHECK_STATUS(s, CBM_E_SYNTAX);
    CHECK(ls == NULL);
    CHECK_MSG(g.count >= 5, "%d diagnostics:\n%s", g.count, g.text);
    CHECK_MSG(strstr(g.text, "test.l:3:") && strstr(g.text, "expected ',' or ')'"), "%s", g.text);
    CHECK_MSG(strstr(g.text, "test.l:4:14: expected an expression, found ')'"), "%s", g.text);
    CHECK_MSG(strstr(g.text, "test.l:5:12: expected an expression, found '-->'"), "%s", g.text);
    CHECK_MSG(strstr(g.text, "test.l:6:7: expected '-->'"), "%s", g.text);
    CHECK_MSG(strstr(g.text, "test.l:7:") && strstr(g.text, "undefined name 'zz'"), "%s", g.text);
    cbm_context_destroy(ctx);
}

TEST(errors_in_headers_and_blocks)
{
    test_diags g;
    cbm_context *ctx = test_diag_ctx(&g);
    cbm_lsys *ls = NULL;
    CHECK_STATUS(load_text(ctx, "A --> B\n", false, &ls), CBM_E_SYNTAX);
    CHECK_MSG(strstr(g.text, "test.l:1:1: expected 'Lsystem:'"), "%s", g.text);
    cbm_context_destroy(ctx);
    ctx = test_diag_ctx(&g);
    CHECK_STATUS(load_text(ctx,
                           "Lsystem: 1\nStart: {x = 1 y = 2;}\nderivation length: 1+\n"
                           "Axiom: A\nA --> B\n",
                           false, &ls),
                 CBM_E_SYNTAX);
    CHECK_MSG(strstr(g.text, "test.l:2:") && strstr(g.text, "';'"), "%s", g.text);
    CHECK_MSG(strstr(g.text, "test.l:3:"), "%s", g.text);
    CHECK_MSG(strstr(g.text, "expected 'endlsystem'"), "%s", g.text);
    cbm_context_destroy(ctx);
    ctx = test_diag_ctx(&g);
    CHECK_STATUS(load_text(ctx,
                           "#define F(x) x\n#bogus\nLsystem: 1\nAxiom: A(F(1,2))\nendlsystem\n",
                           false, &ls),
                 CBM_E_SYNTAX);
    CHECK_MSG(strstr(g.text, "test.l:2:") && strstr(g.text, "unknown directive"), "%s", g.text);
    CHECK_MSG(strstr(g.text, "wrong number of arguments to macro 'F'"), "%s", g.text);
    cbm_context_destroy(ctx);
}

TEST(include_and_command_line_defines)
{
    char dir[2048], a[4096], b[4096];
    snprintf(dir, sizeof dir, "%s", test_tmp_dir());
    snprintf(a, sizeof a, "%s/main.l", dir);
    snprintf(b, sizeof b, "%s/consts.h", dir);
    FILE *f = fopen(b, "w");
    CHECK(f != NULL);
    if (!f)
        return;
    fputs("#define N 2\n#define LEN 5\n", f);
    fclose(f);
    f = fopen(a, "w");
    fputs("#include \"consts.h\"\nLsystem: 1\nderivation length: N\nAxiom: A(LEN)\n"
          "A(x) --> A(x+1)\nendlsystem\n",
          f);
    fclose(f);
    cbm_context *ctx = test_ctx();
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = a;
    const char *defs[] = {"LEN=10"};
    def.defines = defs;
    def.define_count = 1;
    cbm_lsys *ls = NULL;
    CHECK_OK(cbm_lsys_load(ctx, &def, &ls));
    if (ls) {
        CHECK_EQ_INT(cbm_lsys_derivation_length(ls), 2);
        CHECK_OK(cbm_lsys_reset(ls));
        CHECK_OK(cbm_lsys_step(ls));
        CHECK_OK(cbm_lsys_step(ls));
        tbuf got = {0};
        format_string(ls, false, false, &got);
        CHECK_MSG(!strcmp(got.s, "A(12)"), "%s", got.s);
        tb_free(&got);
        cbm_lsys_destroy(ls);
    }
    /* an include that is missing is an error at the directive */
    test_diags g;
    cbm_context *c2 = test_diag_ctx(&g);
    ls = NULL;
    CHECK_STATUS(
        load_text(c2, "#include \"nope.h\"\nLsystem: 1\nAxiom: A\nendlsystem\n", false, &ls),
        CBM_E_SYNTAX);
    CHECK_MSG(strstr(g.text, "test.l:1:") && strstr(g.text, "nope.h"), "%s", g.text);
    cbm_context_destroy(c2);
    test_ctx_end(ctx);
}

/* ---- limits ---- */
TEST(module_limit_keeps_the_last_complete_step)
{
    cbm_context *ctx = test_ctx();
    cbm_limits lim = *cbm_context_limits(ctx);
    lim.max_modules = 1000;
    cbm_context_set_limits(ctx, &lim);
    cbm_lsys *ls = NULL;
    CHECK_OK(load_text(ctx, "Lsystem: 1\nderivation length: 20\nAxiom: F\nF --> FF\nendlsystem\n",
                       false, &ls));
    CHECK_OK(cbm_lsys_reset(ls));
    cbm_status s = CBM_OK;
    int done = 0;
    while (s == CBM_OK && done < 20) {
        s = cbm_lsys_step(ls);
        if (s == CBM_OK)
            done++;
    }
    CHECK_STATUS(s, CBM_E_LIMIT);
    CHECK_EQ_INT(done, 9);
    CHECK_EQ_INT(cbm_lsys_module_count(ls), 512);
    CHECK(strstr(cbm_context_last_error(ctx), "1000 modules") != NULL);
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

TEST(memory_limit_stops_with_a_message)
{
    cbm_context *ctx = test_ctx();
    cbm_limits lim = *cbm_context_limits(ctx);
    lim.max_bytes = 1 << 20;
    cbm_context_set_limits(ctx, &lim);
    cbm_lsys *ls = NULL;
    CHECK_OK(load_text(ctx,
                       "Lsystem: 1\nderivation length: 40\nAxiom: F(1)\nF(x) --> F(x)F(x)\n"
                       "endlsystem\n",
                       false, &ls));
    CHECK_OK(cbm_lsys_reset(ls));
    cbm_status s = CBM_OK;
    for (int i = 0; i < 40 && s == CBM_OK; i++)
        s = cbm_lsys_step(ls);
    CHECK_STATUS(s, CBM_E_LIMIT);
    CHECK(strstr(cbm_context_last_error(ctx), "memory limit") != NULL);
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

/* ---- pages of the current string handed back during a step ---- */

/* Derives `text` n steps twice, once as is and once with a production with a left context that
 * never applies (Q never occurs), which keeps every page of the current string, and checks the
 * strings are the same module by module, parameters bit for bit. */
static void check_release_same(const char *text, int n, bool float32, size_t max_bytes)
{
    cbm_context *ctx = test_ctx();
    cbm_limits lim = *cbm_context_limits(ctx);
    lim.max_bytes = max_bytes;
    cbm_context_set_limits(ctx, &lim);
    char keep[1024];
    const char *end = strstr(text, "endlsystem");
    CHECK(end != NULL && (size_t)(end - text) + 64 < sizeof keep);
    snprintf(keep, sizeof keep, "%.*sQ < Q --> Q\n%s", (int)(end - text), text, end);
    cbm_lsys *a = NULL, *b = NULL;
    CHECK_OK(load_text(ctx, text, float32, &a));
    CHECK_OK(load_text(ctx, keep, float32, &b));
    CHECK_OK(cbm_lsys_reset(a));
    CHECK_OK(cbm_lsys_reset(b));
    for (int i = 0; i < n; i++) {
        CHECK_OK(cbm_lsys_step(a));
        CHECK_OK(cbm_lsys_step(b));
    }
    CHECK(cbm_lsys_module_count(a) > ((size_t)1 << 20));
    CHECK_EQ_INT(cbm_lsys_module_count(a), cbm_lsys_module_count(b));
    CHECK_EQ_INT(cbm_lsys_param_count(a), cbm_lsys_param_count(b));
    cbm_lsys_cursor ca, cb;
    cbm_lsys_cursor_begin(a, false, &ca);
    cbm_lsys_cursor_begin(b, false, &cb);
    size_t diff = 0;
    while (cbm_lsys_cursor_next(a, false, &ca)) {
        if (!cbm_lsys_cursor_next(b, false, &cb) || ca.symbol != cb.symbol ||
            ca.nparams != cb.nparams ||
            (ca.nparams && memcmp(ca.params, cb.params, (size_t)ca.nparams * sizeof(double)) != 0))
            diff++;
    }
    CHECK_EQ_INT(diff, 0);
    cbm_lsys_destroy(a);
    cbm_lsys_destroy(b);
    test_ctx_end(ctx);
}

static const char KOCH[] = "Lsystem: 1\nderivation length: 7\nAxiom: -F\n"
                           "F --> F+F-F-FF+F+F-F\nendlsystem\n";
static const char FIG28[] =
    "#define d1 94.74\n#define d2 132.63\n#define a 18.95\n#define lr 1.109\n#define vr 1.732\n"
    "Lsystem: 1\nderivation length: 11\nAxiom: !(1)F(200)/(45)A\n"
    "A --> !(vr)F(50)[&(a)F(50)A]/(d1)[&(a)F(50)A]/(d2)[&(a)F(50)A]\n"
    "F(l) --> F(l*lr)\n!(w) --> !(w*vr)\nendlsystem\n";

TEST(released_pages_leave_the_string_unchanged)
{
    check_release_same(KOCH, 7, false, 0);
    check_release_same(FIG28, 11, false, 0);
    check_release_same(FIG28, 11, true, 0);
    /* under a byte limit far above the step's bound, and one close to it */
    check_release_same(FIG28, 11, false, (size_t)1 << 30);
    check_release_same(FIG28, 11, false, (size_t)80 << 20);
}

/* With sub-L-systems: the bounds take the productions of every L-system */
static const char KOCHSUB[] = "Lsystem: 1\nderivation length: 7\nAxiom: ?(1)-F$\n"
                              "F --> F+F-F-FF+F+F-F\nendlsystem\n";
static const char FIG28SUB[] =
    "#define d1 94.74\n#define d2 132.63\n#define a 18.95\n#define lr 1.109\n#define vr 1.732\n"
    "Lsystem: 1\nderivation length: 11\nAxiom: !(1)F(200)/(45)A\n"
    "A --> !(vr)F(50)?(2,0.5)[&(a)F(50)A]$/(d1)[&(a)F(50)A]/(d2)[&(a)F(50)A]\n"
    "F(l) --> F(l*lr)\n!(w) --> !(w*vr)\nendlsystem\n"
    "Lsystem: 2\nAxiom: A\nA --> F(50)[&(a)F(50)A]/(d1)[&(a)F(50)?(1)A$]/(d2)[&(a)F(50)A]\n"
    "F(l) --> F(l*1.2)\nendlsystem\n";

TEST(released_pages_with_sub_lsystems)
{
    check_release_same(KOCHSUB, 7, false, 0);
    check_release_same(FIG28SUB, 11, false, 0);
    check_release_same(FIG28SUB, 11, true, (size_t)1 << 30);
}

/* Derives `text` (its X(a) fails at step 20, after 2^19 F's were passed) under a byte limit;
 * released: the string is emptied by the failure, else the string of step 19 is kept. */
static void check_runtime_error(const char *text, size_t max_bytes, bool released)
{
    cbm_context *ctx = test_ctx();
    cbm_limits lim = *cbm_context_limits(ctx);
    lim.max_bytes = max_bytes;
    cbm_context_set_limits(ctx, &lim);
    cbm_lsys *ls = NULL;
    CHECK_OK(load_text(ctx, text, false, &ls));
    CHECK_OK(cbm_lsys_reset(ls));
    for (int i = 0; i < 19; i++)
        CHECK_OK(cbm_lsys_step(ls));
    CHECK_EQ_INT(cbm_lsys_module_count(ls), ((size_t)1 << 19) + 1);
    cbm_status s = cbm_lsys_step(ls);
    CHECK(s != CBM_OK && s != CBM_E_LIMIT);
    CHECK(strstr(cbm_context_last_error(ctx), "func") != NULL);
    CHECK_EQ_INT(cbm_lsys_module_count(ls), released ? 0 : ((size_t)1 << 19) + 1);
    CHECK_EQ_INT(cbm_lsys_steps_done(ls), 19);
    /* reset starts over */
    CHECK_OK(cbm_lsys_reset(ls));
    CHECK_OK(cbm_lsys_step(ls));
    CHECK_EQ_INT(cbm_lsys_module_count(ls), 3);
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

TEST(runtime_error_after_released_pages_empties_the_string)
{
    static const char text[] = "Lsystem: 1\nderivation length: 20\nAxiom: FX(0)\nF --> FF\n"
                               "X(a) : a > 18 --> X(func(1, a))\nX(a) --> X(a + 1)\n"
                               "B --> BBBBBBBB(1,2,3,4,5,6,7,8)\nendlsystem\n";
    static const char keep[] = "Lsystem: 1\nderivation length: 20\nAxiom: FX(0)\nF --> FF\n"
                               "X(a) : a > 18 --> X(func(1, a))\nX(a) --> X(a + 1)\n"
                               "B --> BBBBBBBB(1,2,3,4,5,6,7,8)\nQ < Q --> Q\nendlsystem\n";
    check_runtime_error(text, 0, true);
    check_runtime_error(keep, 0, false); /* a left context keeps the string */
    /* the bound by the longest successor (B's, 8 modules and 8 parameters a module) is over
     * 80 MB; by symbol (no B in the string) about 7 MB */
    check_runtime_error(text, (size_t)24 << 20, true);
    /* both over the limit: kept */
    check_runtime_error(text, (size_t)5 << 20, false);
}

TEST(expression_depth_and_loops_are_bounded)
{
    test_diags g;
    cbm_context *ctx = test_diag_ctx(&g);
    char model[4096], open[301], close[301];
    memset(open, '(', 300);
    memset(close, ')', 300);
    open[300] = close[300] = 0;
    snprintf(model, sizeof model, "Lsystem: 1\nAxiom: A(%s1%s)\nendlsystem\n", open, close);
    cbm_lsys *ls = NULL;
    CHECK_STATUS(load_text(ctx, model, false, &ls), CBM_E_SYNTAX);
    CHECK_MSG(strstr(g.text, "nested too deeply"), "%s", g.text);
    cbm_context_destroy(ctx);
    ctx = test_ctx();
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = "loop.l";
    def.text = "Lsystem: 1\nderivation length: 1\nAxiom: A\n"
               "A : {x=0; while (1) {x=x+1;}} --> B\nendlsystem\n";
    def.max_loop_iterations = 1000000;
    ls = lsys_from_def(ctx, &def);
    CHECK_STATUS(cbm_lsys_step(ls), CBM_E_LIMIT);
    CHECK(strstr(cbm_context_last_error(ctx), "while loop") != NULL);
    cbm_lsys_destroy(ls);
    /* macros that expand into themselves stop (C's rule), mutual recursion too */
    ls = NULL;
    CHECK_OK(
        load_text(ctx, "#define X Y\n#define Y X\nLsystem: 1\nAxiom: A\nendlsystem\n", false, &ls));
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

TEST(step_limit)
{
    cbm_context *ctx = test_ctx();
    cbm_limits lim = *cbm_context_limits(ctx);
    lim.max_steps = 3;
    cbm_context_set_limits(ctx, &lim);
    cbm_lsys *ls = NULL;
    test_diags g;
    cbm_context *c2 = test_diag_ctx(&g);
    cbm_context_set_limits(c2, &lim);
    CHECK_STATUS(
        load_text(c2, "Lsystem: 1\nderivation length: 5\nAxiom: A\nendlsystem\n", false, &ls),
        CBM_E_SYNTAX);
    CHECK_MSG(strstr(g.text, "derivation length must be between 0 and 3"), "%s", g.text);
    cbm_context_destroy(c2);
    CHECK_OK(
        load_text(ctx, "Lsystem: 1\nderivation length: 3\nAxiom: A\nendlsystem\n", false, &ls));
    CHECK_OK(cbm_lsys_reset(ls));
    for (int i = 0; i < 3; i++)
        CHECK_OK(cbm_lsys_step(ls));
    CHECK_STATUS(cbm_lsys_step(ls), CBM_E_LIMIT);
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

/* ---- out of memory ---- */
static cbm_status oom_run(cbm_context *ctx, void *ud)
{
    const char *text =
        "#define R(x) (x*2)\nLsystem: 1\ndefine: {array t[3] = {1,2,3};}\n"
        "derivation length: 3\nignore: +\nAxiom: A(1)\n"
        "B(x) < A(y) : {z=t[1];} y > 0 --> A(R(y)+z)[+B(y)]\n"
        "A(y) --> B(y)A(y)\n"
        "decomposition\nmaximum depth: 2\nB(x) --> C(x)\nhomomorphism\nC(x) --> F(x)\n"
        "endlsystem\n";
    return lsys_derive_homomorphism(ctx, "oom.l", text, 3, ud);
}

/* Every allocation failed in turn; the last run, without a failure, derived the three steps and
 * the strings a run with memory enough derives. */
TEST(out_of_memory_at_every_allocation)
{
    /* C(1) C(1) C(1) A(1): a B decomposed to C before the A at every step; F(1) F(1) F(1) A(1) */
    lsys_check_out_of_memory(oom_run, 3, 4);
}

/* ---- environmental interpretation hook (query modules) ---- */
static cbm_status fill_queries(void *ud, cbm_lsys *ls)
{
    int *calls = ud;
    (*calls)++;
    cbm_lsys_cursor c;
    int prev = 0, k = 0;
    cbm_lsys_cursor_begin(ls, true, &c);
    while (cbm_lsys_cursor_next(ls, true, &c)) {
        if (prev == '?' && c.symbol == 'P') {
            CBM_TRY(cbm_lsys_cursor_set_param(ls, &c, 0, 10.0 * *calls + k));
            CBM_TRY(cbm_lsys_cursor_set_param(ls, &c, 1, -1));
            if (c.params[0] != 10.0 * *calls + k ||
                cbm_lsys_cursor_set_param(ls, &c, 2, 0) == CBM_OK)
                return CBM_E_INTERNAL;
            k++;
        }
        prev = c.symbol;
    }
    return CBM_OK;
}

TEST(query_modules_are_filled_before_each_step)
{
    /* the interpreter sees the homomorphic image (A --> XF); the values it gives the image's
     * query module go to the string's */
    cbm_context *ctx = test_ctx();
    cbm_lsys *ls = NULL;
    CHECK_OK(load_text(ctx,
                       "Lsystem: 1\nderivation length: 2\nconsider: ?P\nAxiom: A?P(0,0)\n"
                       "A > ?P(x,y) : x > 15 --> B(x,y)\n"
                       "homomorphism\nA --> XF\nendlsystem\n",
                       false, &ls));
    int calls = 0;
    cbm_lsys_set_interpreter(ls, fill_queries, &calls);
    CHECK_OK(cbm_lsys_reset(ls));
    CHECK_OK(cbm_lsys_step(ls)); /* P = (10, -1): not yet */
    CHECK_OK(cbm_lsys_step(ls)); /* P = (20, -1): A -> B */
    CHECK_EQ_INT(calls, 2);
    CHECK_OK(cbm_lsys_interpret(ls));
    CHECK_EQ_INT(calls, 3);
    tbuf got = {0};
    format_string(ls, false, false, &got);
    CHECK_MSG(!strcmp(got.s, "B(20,-1)?P(30,-1)"), "%s", got.s);
    tb_free(&got);
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}
