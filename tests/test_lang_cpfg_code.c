/* The cpfg dialect on the register code (lang/cpfg_code.c): expressions and statement blocks
 * compiled and run by cbm__lc_run give the values C computes for them (so an instruction that
 * computed something else fails here), every root evaluated is compiled, and runtime errors
 * name the node the tree walker named. */
#include "test.h"

#include "lang/lang.h"

#include <math.h>
#include <stdlib.h>

typedef struct src {
    cbm__pp pp;
    cbm__compiler c;
} src;

static const char *const FORMALS[] = {"x", "y"};
static const size_t FORMAL_LEN[] = {1, 1};

/* Preprocesses text and readies the compiler at its start with the formals x, y. */
static bool open_src(cbm_context *ctx, const char *text, src *s)
{
    memset(s, 0, sizeof *s);
    if (cbm__pp_run(ctx, "t.l", text, NULL, 0, &s->pp) != CBM_OK || s->pp.errors)
        return false;
    if (cbm__compiler_init(&s->c, ctx, &s->pp) != CBM_OK)
        return false;
    s->c.formals = FORMALS;
    s->c.formal_len = FORMAL_LEN;
    s->c.nformals = 2;
    return true;
}

static void close_src(src *s)
{
    cbm__compiler_free(&s->c);
    cbm__pp_free(&s->pp);
}

static void eval_init(cbm__eval *e, cbm_context *ctx, src *s, double *globals, double *params)
{
    memset(e, 0, sizeof *e);
    e->ctx = ctx;
    e->nodes = s->c.nodes.data;
    e->strings = s->c.strings.data;
    e->arrays = s->c.arrays.data;
    e->globals = globals;
    e->params = params;
    e->error_node = -1;
    e->while_budget = 1000;
    cbm__random_seed(&e->rnd, 7);
}

TEST(cpfg_expressions_on_the_register_code)
{
    cbm_context *ctx = test_ctx();
    const double x = 2, y = -7.5, d = 3.14159265358979323846 / 180.0;
    struct {
        const char *text;
        double want;
    } cases[] = {
        {"1 + 2 * 3 - 4 / 8", 1 + 2 * 3 - 4.0 / 8},
        {"x * y - y / x + (x - y)", x * y - y / x + (x - y)},
        {"y % x", fmod(y, x)},
        {"2 ^ 3 ^ 2", pow(pow(2, 3), 2)},
        {"sin(30) + cos(x) * tan(y)", sin(30 * d) + cos(x * d) * tan(y * d)},
        {"asin(0.5) + acos(0.25) + atan(x) + atan2(y, x)",
         asin(0.5) / d + acos(0.25) / d + atan(x) / d + atan2(y, x) / d},
        {"exp(x) + log(x) + sqrt(x) + floor(y) + ceil(y) + trunc(y) + sign(y)",
         exp(x) + log(x) + sqrt(x) + floor(y) + ceil(y) + trunc(y) - 1},
        {"-x + !x + !0", -x + 0 + 1},
        {"(x < y) + (x > y) * 2 + (x <= 2) * 4 + (x >= 3) * 8 + (x == 2) * 16 + (y != y) * 32",
         0 + 2 + 4 + 0 + 16 + 0},
        {"(x && y) * 1 + (x && 0) * 2 + (0 || y) * 4 + (0 || 0) * 8 + (y && y) * 16", 1 + 4 + 16},
        {"x > 1 ? y : x", y},
        {"x < 1 ? y : x + 1", x + 1},
    };
    size_t n = sizeof cases / sizeof cases[0];
    for (size_t i = 0; i < n; i++) {
        src s;
        CHECK(open_src(ctx, cases[i].text, &s));
        int32_t root = cbm__parse_expr(&s.c, false);
        CHECK_MSG(root >= 0 && !s.c.errors, "%s does not parse", cases[i].text);
        double g[4] = {0}, par[2] = {x, y};
        cbm__eval e;
        eval_init(&e, ctx, &s, g, par);
        double v = root >= 0 ? cbm__eval_expr(&e, root) : NAN;
        CHECK_MSG(v == cases[i].want, "%s = %.17g, expected %.17g", cases[i].text, v,
                  cases[i].want);
        /* a second run reuses the compiled root */
        CHECK(root < 0 || cbm__eval_expr(&e, root) == v);
        size_t roots, ins, runs;
        cbm__eval_stats(&e, &roots, &ins, &runs);
        CHECK_MSG(roots == 1 && runs == 2 && ins >= 2, "%s: %zu roots, %zu instructions, %zu runs",
                  cases[i].text, roots, ins, runs);
        CHECK(e.error == CBM_OK);
        cbm__eval_free(&e);
        close_src(&s);
    }
    test_ctx_end(ctx);
}

TEST(cpfg_random_numbers_from_the_one_module)
{
    cbm_context *ctx = test_ctx();
    src s;
    CHECK(open_src(ctx, "ran(3) + ran(1) * 0 - nran(1, 2) * 0", &s));
    int32_t root = cbm__parse_expr(&s.c, false);
    CHECK(root >= 0);
    double g[1] = {0}, par[2] = {0, 0};
    cbm__eval e;
    eval_init(&e, ctx, &s, g, par);
    cbm__random ref;
    cbm__random_seed(&ref, 7);
    for (int k = 0; k < 5; k++) {
        double r0 = cbm__rand48_next(&ref.r48) * 3;
        double r1 = cbm__rand48_next(&ref.r48) * 1;
        double v, f;
        cbm__random_normal(&ref, &v, &f);
        double want = r0 + r1 * 0 - (v * f * 2 + 1) * 0;
        CHECK_MSG(cbm__eval_expr(&e, root) == want, "draw %d", k);
    }
    CHECK(!memcmp(&e.rnd.r48, &ref.r48, sizeof ref.r48));
    cbm__eval_free(&e);
    close_src(&s);
    test_ctx_end(ctx);
}

/* Statements: globals, parameters, arrays, if/else, while and do loops. */
TEST(cpfg_statements_on_the_register_code)
{
    cbm_context *ctx = test_ctx();
    src s;
    CHECK(open_src(ctx,
                   "{ array a[3][2] = {1, 2, 3, 4, 5, 6}; }\n"
                   "{ s = 0; i = 0; while (i < 5) { s = s + i * a[i % 3][1]; i = i + 1; }\n"
                   "  do { i = i - 2; } while (i > 0);\n"
                   "  if (s > 100) t = 1; else if (s > 10) t = 2; else t = 3;\n"
                   "  a[2][0] = s; x = x + a[2][0]; y = y * -1; }\n",
                   &s));
    CHECK(cbm__parse_define_block(&s.c));
    bool ok = true;
    cbm__skip(&s.c, true);
    int32_t root = cbm__parse_block(&s.c, &ok);
    CHECK(ok && root >= 0 && !s.c.errors);
    CHECK(s.c.globals.len == 3);
    double g[3] = {0}, par[2] = {1, 2};
    cbm__eval e;
    eval_init(&e, ctx, &s, g, par);
    cbm__eval_stmt(&e, root);
    CHECK(e.error == CBM_OK);
    /* s = 0*2 + 1*4 + 2*6 + 3*2 + 4*4 = 38; i: 5, 3, 1, -1 */
    double sum = 0 * 2 + 1 * 4 + 2 * 6 + 3 * 2 + 4 * 4;
    CHECK_MSG(g[0] == sum && g[1] == -1 && g[2] == 2, "s %g i %g t %g", g[0], g[1], g[2]);
    CHECK(s.c.arrays.data[0].data[4] == sum && par[0] == 1 + sum && par[1] == -2);
    /* iterations: 5 of the while loop, 2 of the do loop's (its body's first run is free) */
    CHECK_MSG(e.while_budget == 1000 - 7, "budget %ld", e.while_budget);
    /* nothing runs while an error is pending */
    e.error = CBM_E_RUNTIME;
    cbm__eval_stmt(&e, root);
    CHECK(g[1] == -1);
    cbm__eval_free(&e);
    close_src(&s);
    test_ctx_end(ctx);
}

TEST(cpfg_runtime_errors_name_the_walkers_node)
{
    cbm_context *ctx = test_ctx();
    src s;
    CHECK(open_src(ctx,
                   "{ array a[2] = {1, 2}; }\n"
                   "{ v = 1 + a[x]; }\n"
                   "{ while (1) { v = v + 1; } }\n"
                   "{ v = 2 * bran(-1, 1); }\n",
                   &s));
    CHECK(cbm__parse_define_block(&s.c));
    int32_t blocks[3];
    for (int k = 0; k < 3; k++) {
        bool ok = true;
        cbm__skip(&s.c, true);
        blocks[k] = cbm__parse_block(&s.c, &ok);
        CHECK(ok && blocks[k] >= 0);
    }
    double g[1] = {0}, par[2] = {2, 0};
    cbm__eval e;
    eval_init(&e, ctx, &s, g, par);
    const char *want[3] = {"array index out of range", "while loops ran", "bran(a, b)"};
    const uint8_t op[3] = {OP_ARRAY, OP_WHILE, OP_CALL};
    for (int k = 0; k < 3; k++) {
        e.error = CBM_OK;
        e.error_node = -1;
        e.while_budget = 50;
        cbm__eval_stmt(&e, blocks[k]);
        CHECK_MSG(e.error != CBM_OK && e.error_msg && strstr(e.error_msg, want[k]), "block %d: %s",
                  k, e.error_msg ? e.error_msg : "(none)");
        CHECK_MSG(e.error_node >= 0 && e.nodes[e.error_node].op == op[k], "block %d: node %d", k,
                  (int)e.error_node);
    }
    CHECK(g[0] == 50); /* the loop stopped at its budget: 50 iterations ran */
    cbm__eval_free(&e);
    close_src(&s);
    test_ctx_end(ctx);
}
