/* The L+C (lpfg) dialect: the six lpfg models of ../shared/oracles/vlab against lpfg's strings
 * (ref/final.params.txt, struct parameters written raw[..] there and {..} by us), the models of
 * tests/lpfg/ against the expectations in their comments:
 *   // expect after N: MODULES                 (one-line form of -o x.str, space separated)
 *   // expect interpretation after N: MODULES
 * and error messages. */
#define _POSIX_C_SOURCE 200809L
#include "lsys/lsys_internal.h"
#include "lsys_util.h"

#include "cambium/io.h"

#include <dirent.h>
#include <errno.h>
#ifdef __GLIBC__
#include <gnu/libc-version.h>
#endif
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

/* The string (or its interpretation) as `-o x.str` writes it, lines joined with sep. */
static char *lpfg_string(cbm_context *ctx, cbm_lsys *ls, bool interp, char sep)
{
    char path[256];
    snprintf(path, sizeof path, "/tmp/cbm_test_lpfg_%d.str", (int)getpid());
    cbm_out *o = NULL;
    if (cbm_out_open(ctx, path, &o) != CBM_OK)
        return NULL;
    if (interp && cbm_lsys_apply_homomorphism(ls) != CBM_OK) {
        cbm_out_abort(o);
        return NULL;
    }
    cbm_status s = cbm_lsys_write_str(ls, interp, o);
    if (s == CBM_OK)
        s = cbm_out_commit(o);
    else
        cbm_out_abort(o);
    char *t = s == CBM_OK ? read_text(path, false) : NULL;
    remove(path);
    if (t && sep != '\n') {
        size_t n = strlen(t);
        while (n && t[n - 1] == '\n')
            t[--n] = 0;
        for (char *p = t; *p; p++)
            if (*p == '\n')
                *p = sep;
    }
    return t;
}

static const char *oracle_dir(void)
{
    static char path[2048];
    snprintf(path, sizeof path, "%s/../shared/oracles/vlab", test_source_dir());
    return path;
}

/* lpfg's final.params.txt with raw[...] written as {...} */
static char *reference(const char *folder)
{
    char p[4096];
    snprintf(p, sizeof p, "%s/%s/ref/final.params.txt", oracle_dir(), folder);
    char *t = read_text(p, false);
    if (!t)
        return NULL;
    char *w = t;
    for (char *r = t; *r;) {
        if (!strncmp(r, "raw[", 4)) {
            *w++ = '{';
            r += 4;
        } else if (*r == ']') {
            *w++ = '}';
            r++;
        } else
            *w++ = *r++;
    }
    *w = 0;
    return t;
}

static void run_oracle(const char *folder)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s/model/lsystem.l", oracle_dir(), folder);
    if (test_skip_without_oracles())
        return;
    char *ref = reference(folder);
    CHECK_MSG(ref != NULL, "cannot read the reference of %s", path);
    if (!ref)
        return;
    cbm_context *ctx = test_ctx();
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = path;
    cbm_lsys *ls = NULL;
    cbm_status s = cbm_lsys_load(ctx, &def, &ls);
    CHECK_MSG(s == CBM_OK, "%s: %s", folder, cbm_context_last_error(ctx));
    if (s == CBM_OK) {
        CHECK_OK(cbm_lsys_reset(ls));
        int n = cbm_lsys_derivation_length(ls);
        CHECK(n > 0);
        for (int i = 0; i < n; i++)
            CHECK_OK(cbm_lsys_step(ls));
        char *got = lpfg_string(ctx, ls, false, '\n');
        CHECK(got != NULL);
        if (got) {
            CHECK_MSG(!strcmp(got, ref), "%s: the string differs from lpfg's", folder);
            if (strcmp(got, ref)) {
                size_t k = 0;
                while (got[k] && got[k] == ref[k])
                    k++;
                printf("  first difference at byte %zu: ours '%.40s' lpfg '%.40s'\n", k, got + k,
                       ref + k);
            }
        }
        free(got);
        cbm_lsys_destroy(ls);
    }
    free(ref);
    test_ctx_end(ctx);
}

TEST(lpfg_oracle_quadratic_koch)
{
    run_oracle("lpfg-quadratic-koch");
}
TEST(lpfg_oracle_compound_param)
{
    run_oracle("lpfg-compound-param");
}
TEST(lpfg_oracle_hormone_up)
{
    run_oracle("lpfg-hormone-up");
}
TEST(lpfg_oracle_sympodial)
{
    run_oracle("lpfg-sympodial");
}
TEST(lpfg_oracle_newcontext)
{
    run_oracle("lpfg-newcontext");
}
TEST(lpfg_oracle_innewcontext)
{
    run_oracle("lpfg-innewcontext");
}

static void run_model(const char *name)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/tests/lpfg/%s", test_source_dir(), name);
    char *src = read_text(path, false);
    CHECK_MSG(src != NULL, "cannot read %s", path);
    if (!src)
        return;
    cbm_context *ctx = test_ctx();
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = path;
    cbm_lsys *ls = NULL;
    cbm_status s = cbm_lsys_load(ctx, &def, &ls);
    CHECK_MSG(s == CBM_OK, "%s: %s", name, cbm_context_last_error(ctx));
    int checked = 0;
    if (s == CBM_OK) {
        CHECK_OK(cbm_lsys_reset(ls));
        int step = 0;
        for (char *l = src; l && *l; l = strchr(l, '\n'), l = l ? l + 1 : NULL) {
            bool interp = !strncmp(l, "// expect interpretation after ", 31);
            if (strncmp(l, "// expect after ", 16) && !interp)
                continue;
            char *p = l + (interp ? 31 : 16);
            int want = (int)strtol(p, &p, 10);
            p += 2;
            char *end = strchr(p, '\n');
            size_t n = end ? (size_t)(end - p) : strlen(p);
            while (step < want) {
                CHECK_OK(cbm_lsys_step(ls));
                step++;
            }
            if (interp)
                CHECK(cbm_lsys_has_homomorphism(ls));
            char *got = lpfg_string(ctx, ls, interp, ' ');
            CHECK(got != NULL);
            if (got) {
                CHECK_MSG(strlen(got) == n && !strncmp(got, p, n),
                          "%s after %d: got '%s', expected '%.*s'", name, want, got, (int)n, p);
            }
            free(got);
            checked++;
        }
        cbm_lsys_destroy(ls);
    }
    CHECK_MSG(checked > 0, "%s states no expectation", name);
    free(src);
    test_ctx_end(ctx);
}

TEST(lpfg_forward_signal)
{
    run_model("forward-signal.l");
}
TEST(lpfg_backward_sum)
{
    run_model("backward-sum.l");
}
TEST(lpfg_struct_functions)
{
    run_model("struct-functions.l");
}
TEST(lpfg_random_host)
{
    run_model("random-host.l");
}
TEST(lpfg_switch)
{
    run_model("switch.l");
}
TEST(lpfg_groups_globals)
{
    run_model("groups-globals.l");
}
TEST(lpfg_struct_vectors)
{
    run_model("struct-vectors.l");
}
TEST(lpfg_two_branch_context)
{
    run_model("two-branch-context.l");
}
TEST(lpfg_decomposition_interpretation)
{
    run_model("decomposition-interp.l");
}

TEST(lpfg_c_library)
{
    run_model("c-library.l");
}

TEST(lpfg_taylor_hell_constructs)
{
    run_model("taylor-hell-constructs.l");
}
TEST(lpfg_frames_globals)
{
    run_model("frames-globals.l");
}

/* VecRotate returns a new value (its argument unchanged), as do Normalize(v), v.Normalized(),
 * CrossProd and DotProd; v.Normalize() changes v; copies and by-value parameters are copies */
TEST(lpfg_vector_value_semantics)
{
    run_model("value-semantics.l");
}

TEST(lpfg_consider)
{
    run_model("consider.l");
}

/* func(name, x): names numbered in order of first use, evaluated by the function set */
static double fake_func(void *ud, int id, double x)
{
    (void)ud;
    return id * 100 + x;
}

TEST(lpfg_func_by_name)
{
    cbm_context *ctx = test_ctx();
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = "f.l";
    def.text = "#include <lpfgall.h>\nderivation length: 1;\nmodule A(float);\nAxiom: A(2);\n"
               "A(x) : { produce A(func(beta, x)) A(func(alpha, x / 2)) A(func(beta, 0)); }\n";
    cbm_lsys *ls = NULL;
    CHECK_OK(cbm_lsys_load(ctx, &def, &ls));
    if (ls) {
        const char *const *names = NULL;
        CHECK(cbm_lsys_func_names(ls, &names) == 2);
        CHECK(names && !strcmp(names[0], "beta") && !strcmp(names[1], "alpha"));
        CHECK_OK(cbm_lsys_reset(ls));
        CHECK(cbm_lsys_step(ls) == CBM_E_RUNTIME); /* no function set */
        cbm_lsys_set_func(ls, fake_func, NULL);
        CHECK_OK(cbm_lsys_reset(ls));
        CHECK_OK(cbm_lsys_step(ls));
        char *got = lpfg_string(ctx, ls, false, ' ');
        CHECK_MSG(got && !strcmp(got, "A(102) A(201) A(100)"), "%s", got ? got : "(null)");
        free(got);
        /* the function set's own order: alpha is its function 7, beta its function 3 */
        int ids[2] = {3, 7};
        CHECK_STATUS(cbm_lsys_set_func_ids(ls, ids, 1), CBM_E_INVALID);
        CHECK_OK(cbm_lsys_set_func_ids(ls, ids, 2));
        CHECK_OK(cbm_lsys_reset(ls));
        CHECK_OK(cbm_lsys_step(ls));
        got = lpfg_string(ctx, ls, false, ' ');
        CHECK_MSG(got && !strcmp(got, "A(302) A(701) A(300)"), "%s", got ? got : "(null)");
        free(got);
        cbm_lsys_destroy(ls);
    }
    test_ctx_end(ctx);
}

TEST(lpfg_in_left_context)
{
    run_model("in-left-context.l");
}

TEST(lpfg_group0_cut_nproduce)
{
    run_model("group0-cut-nproduce.l");
}

TEST(lpfg_cut_forward_backward)
{
    run_model("cut-forward-backward.l");
}

static void expect_error(const char *text, const char *where, const char *what)
{
    cbm_context *ctx = test_ctx();
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = "m.l";
    def.text = text;
    cbm_lsys *ls = NULL;
    cbm_status s = cbm_lsys_load(ctx, &def, &ls);
    CHECK(s == CBM_E_SYNTAX);
    CHECK(ls == NULL);
    (void)where;
    (void)what;
    test_ctx_end(ctx);
}

TEST(lpfg_errors)
{
    expect_error("#include <lpfgall.h>\nmodule A(int);\nAxiom: A(1, 2);\n", "m.l:3:", "");
    expect_error("#include <lpfgall.h>\nmodule A(int);\nAxiom: A(1);\nA(x) : { produce B(); }\n",
                 "m.l:4:", "");
    expect_error("#include <lpfgall.h>\nmodule A(int);\nAxiom: A(1);\nA(x) : { y = 2; }\n",
                 "m.l:4:", "");
    expect_error("#include <lpfgall.h>\nmodule A(int);\nAxiom: A(1);\nA(x) : { if (x) {\n",
                 "m.l:4:", "");
    expect_error("#include <lpfgall.h>\nstruct P { float a; };\nmodule A(P);\nAxiom: A(1);\n",
                 "m.l:4:", "");
}

TEST(lpfg_errors_with_locations)
{
    const cbm_lsys_def def = lsys_text_def(
        "m.l", "#include <lpfgall.h>\n"                       /* 1 */
               "struct P { float a; };\n"                     /* 2 */
               "module A(int);\n"                             /* 3 */
               "module C(P);\n"                               /* 4 */
               "Axiom: A(1, 2);\n"                            /* 5: too many parameters */
               "A(x) : { produce B(); }\n"                    /* 6: unknown module */
               "A(x) : { y = 2; produce A(x); }\n"            /* 7: unknown name */
               "C(p) : { p.b = 1; produce C(p); }\n"          /* 8: no field */
               "A(x) : { V3f v; v = v + 1; produce A(x); }\n" /* 9: invalid operands */
               "A(x) : { produce A(x) }\n");                  /* 10: missing ; */
    test_diags g;
    cbm_context *ctx;
    cbm_lsys *ls;
    CHECK_STATUS(lsys_load_diags(&g, &def, &ctx, &ls), CBM_E_SYNTAX);
    CHECK(ls == NULL);
    CHECK_MSG(g.count >= 6, "%d diagnostics:\n%s", g.count, g.text);
    CHECK_MSG(strstr(g.text, "m.l:5:8: module A has 1 parameter, 2 given"), "%s", g.text);
    CHECK_MSG(strstr(g.text, "m.l:6:18: unknown module 'B'"), "%s", g.text);
    CHECK_MSG(strstr(g.text, "m.l:7:10: unknown name 'y'"), "%s", g.text);
    CHECK_MSG(strstr(g.text, "m.l:8:11: no field 'b' in P"), "%s", g.text);
    CHECK_MSG(strstr(g.text, "m.l:9:23: invalid operands to '+' (V3f and int)"), "%s", g.text);
    CHECK_MSG(strstr(g.text, "m.l:10:23: expected ';', found '}'"), "%s", g.text);
    cbm_context_destroy(ctx);
}

/* A declaration whose initialiser fails is one error: the variable is declared all the same, so
 * its uses later in the body are not reported as unknown names too. */
TEST(lpfg_failed_declaration_is_one_error)
{
    const cbm_lsys_def def =
        lsys_text_def("m.l", "#include <lpfgall.h>\n"                                      /* 1 */
                             "module A(float);\n"                                          /* 2 */
                             "Axiom: A(1);\n"                                              /* 3 */
                             "A(x) : { double y = zzz + 1; y = y * 2; produce A(y); }\n"); /* 4 */
    test_diags g;
    cbm_context *ctx;
    cbm_lsys *ls;
    CHECK_STATUS(lsys_load_diags(&g, &def, &ctx, &ls), CBM_E_SYNTAX);
    CHECK(ls == NULL);
    CHECK_MSG(g.count == 2 && strstr(g.text, ": 1 error in the model"), "%d diagnostics:\n%s",
              g.count, g.text);
    CHECK_MSG(strstr(g.text, "m.l:4:21: unknown name 'zzz'"), "%s", g.text);
    CHECK_MSG(!strstr(g.text, "'y'"), "%s", g.text);
    cbm_context_destroy(ctx);
}

/* Functions compiled to register code against the same statements in a production body (the
 * tree walker): every B module of tests/lpfg/compiled-functions.l equals the C module after
 * it, bit for bit as written; fib by recursion gives the Fibonacci numbers. */
TEST(lpfg_compiled_functions_match_tree_walker)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/tests/lpfg/compiled-functions.l", test_source_dir());
    cbm_context *ctx = test_ctx();
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = path;
    cbm_lsys *ls = NULL;
    cbm_status s = cbm_lsys_load(ctx, &def, &ls);
    CHECK_MSG(s == CBM_OK, "%s", cbm_context_last_error(ctx));
    if (s == CBM_OK) {
        CHECK_OK(cbm_lsys_reset(ls));
        for (int i = 0; i < 6; i++)
            CHECK_OK(cbm_lsys_step(ls));
        char *got = lpfg_string(ctx, ls, false, '\n');
        CHECK(got != NULL);
        int pairs = 0, fibs = 0;
        const int fib[] = {0, 1, 1, 2, 3, 5, 8, 13, 21};
        char *prev = NULL;
        for (char *l = got ? strtok(got, "\n") : NULL; l; l = strtok(NULL, "\n")) {
            if (l[0] == 'C') {
                CHECK_MSG(prev && prev[0] == 'B' && !strcmp(prev + 1, l + 1),
                          "function gave %s, production body %s", prev ? prev : "-", l);
                pairs++;
            } else if (l[0] == 'B' && prev && prev[0] == 'C') {
                int a = -1, b = -1;
                CHECK(sscanf(l, "B(%d,%d,", &a, &b) == 2);
                int k = 5 - fibs; /* the newest modules come first */
                CHECK_MSG(k >= 0 && a == fib[k + 3] && b == fib[k], "fib: %s", l);
                fibs++;
            }
            prev = l;
        }
        CHECK_MSG(pairs == 6 && fibs == 6, "%d pairs, %d fib modules", pairs, fibs);
        free(got);
        cbm_lsys_destroy(ls);
    }
    test_ctx_end(ctx);
}

/* A runtime error inside a compiled function names the statement where it happened, as the
 * tree walker does; a loop there spends the step's budget. */
TEST(lpfg_compiled_function_errors)
{
    test_diags g;
    cbm_context *ctx = test_diag_ctx(&g);
    CHECK(ctx != NULL);
    if (!ctx)
        return;
    cbm_lsys_def def = lsys_text_def("m.l", "#include <lpfgall.h>\nmodule A(int);\n" /* 1, 2 */
                                            "int f(int n) {\n"                       /* 3 */
                                            "    int d = n - 1;\n"                   /* 4 */
                                            "    return 10 / d; }\n"                 /* 5: 10 / 0 */
                                            "Axiom: A(1);\nA(x) : { produce A(f(x)); }\n");
    cbm_lsys *ls = lsys_from_def(ctx, &def);
    if (ls) {
        CHECK_STATUS(cbm_lsys_step(ls), CBM_E_RUNTIME);
        CHECK_MSG(strstr(g.text, "m.l:5:5: ") && strstr(g.text, "integer division by zero"), "%s",
                  g.text);
        cbm_lsys_destroy(ls);
    }
    def.text = "#include <lpfgall.h>\nmodule A(int);\n"
               "int f(int n) { while (n > 0) n = n + 1; return n; }\n"
               "Axiom: A(1);\nA(x) : { produce A(f(x)); }\n";
    def.max_loop_iterations = 1000;
    ls = lsys_from_def(ctx, &def);
    if (ls) {
        CHECK_STATUS(cbm_lsys_step(ls), CBM_E_LIMIT);
        CHECK_MSG(strstr(g.text, "more loop iterations in one step than the limit"), "%s", g.text);
        cbm_lsys_destroy(ls);
    }
    cbm_context_destroy(ctx);
}

/* The string after `steps` steps of model path (or text) with the functions in the register
 * code (native false) or as native code compiled into the test's directory; NULL when native
 * code is asked and cannot be had (*why says why). */
static char *run_functions(cbm_context *ctx, const char *path, const char *text, int steps,
                           bool native, const char **why)
{
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = path;
    def.text = text;
    cbm_lsys *ls = NULL;
    cbm_status s = cbm_lsys_load(ctx, &def, &ls);
    CHECK_MSG(s == CBM_OK, "%s: %s", path, cbm_context_last_error(ctx));
    if (s != CBM_OK)
        return NULL;
    char *got = NULL;
    if (!native || cbm_lsys_compile_native(ls, test_tmp_dir(), why)) {
        CHECK_OK(cbm_lsys_reset(ls));
        for (int i = 0; i < steps; i++)
            CHECK_OK(cbm_lsys_step(ls));
        got = lpfg_string(ctx, ls, false, '\n');
    }
    cbm_lsys_destroy(ls);
    return got;
}

/* Native code (lang/lc_native.c) gives the register code's strings byte for byte: int wrap,
 * division, float rounding, loops, ++/--, globals, math built-ins, recursion
 * (compiled-functions.l), a 400-term series (bench/lc/compute.l, 12 steps), and conversions to
 * int of NaN, the infinities and the values at and beyond int32's ends (native-int-edges.l);
 * loading it a second time takes the cached object. */
TEST(lpfg_native_matches_register_code)
{
    static const struct {
        const char *file;
        int steps;
    } models[] = {{"tests/lpfg/compiled-functions.l", 6},
                  {"bench/lc/compute.l", 12},
                  {"tests/lpfg/native-int-edges.l", 1}};
    cbm_context *ctx = test_ctx();
    for (size_t k = 0; k < sizeof models / sizeof models[0]; k++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", test_source_dir(), models[k].file);
        const char *why = NULL;
        char *code = run_functions(ctx, path, NULL, models[k].steps, false, NULL);
        char *native = run_functions(ctx, path, NULL, models[k].steps, true, &why);
        if (!native && why && strstr(why, "compiler")) {
            free(code);
            test_skip("no C compiler (cc) for native code");
            break;
        }
        CHECK_MSG(native != NULL, "%s: %s", models[k].file, why ? why : "no string");
        CHECK_MSG(code && native && !strcmp(code, native), "%s: native code differs",
                  models[k].file);
        char *again = run_functions(ctx, path, NULL, models[k].steps, true, &why);
        CHECK_MSG(again && native && !strcmp(again, native), "%s: cached object differs",
                  models[k].file);
        free(code);
        free(native);
        free(again);
    }
    test_ctx_end(ctx);
}

/* A hung C compiler does not hang the run: a `cc` that sleeps is killed after CBM_CC_TIMEOUT
 * seconds (with the children of its process group), native code is refused with a reason that
 * says so, and the functions keep the register code (the string is the register code's). */
TEST(lpfg_native_cc_timeout)
{
    cbm_context *ctx = test_ctx();
    char dir[4096], cc[4200], path[4096], env[16384];
    snprintf(dir, sizeof dir, "%s/fakecc", test_tmp_dir());
    CHECK(mkdir(dir, 0700) == 0 || errno == EEXIST);
    snprintf(cc, sizeof cc, "%s/cc", dir);
    FILE *f = fopen(cc, "w");
    CHECK(f != NULL);
    if (f) {
        fputs("#!/bin/sh\nsleep 60\n", f);
        CHECK(fclose(f) == 0);
    }
    CHECK(chmod(cc, 0755) == 0);
    const char *old = getenv("PATH");
    static char saved[8192]; /* setenv may free the old value */
    snprintf(saved, sizeof saved, "%s", old ? old : "/usr/bin:/bin");
    snprintf(env, sizeof env, "%s:%s", dir, saved);
    CHECK(setenv("PATH", env, 1) == 0);
    CHECK(setenv("CBM_CC_TIMEOUT", "0.5", 1) == 0);
    snprintf(path, sizeof path, "%s/tests/lpfg/compiled-functions.l", test_source_dir());
    const char *why = NULL;
    char *code = run_functions(ctx, path, NULL, 6, false, NULL);
    char *native = run_functions(ctx, path, NULL, 6, true, &why);
    CHECK_MSG(native == NULL, "native code from a compiler that never finishes");
    CHECK_MSG(why && strstr(why, "timed out"), "%s", why ? why : "no reason");
    CHECK(code != NULL);
    free(code);
    free(native);
    /* the real compiler again for the tests after this one (they would skip native code) */
    CHECK(setenv("PATH", saved, 1) == 0);
    CHECK(unsetenv("CBM_CC_TIMEOUT") == 0);
    test_ctx_end(ctx);
}

TEST(lpfg_runtime_limits)
{
    cbm_context *ctx = test_ctx();
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = "loop.l";
    def.text = "#include <lpfgall.h>\nmodule A(int);\nAxiom: A(1);\n"
               "A(x) : { while (x > 0) x = x + 1; produce A(x); }\n";
    def.max_loop_iterations = 1000;
    cbm_lsys *ls = lsys_from_def(ctx, &def);
    if (ls) {
        CHECK(cbm_lsys_step(ls) == CBM_E_LIMIT);
        cbm_lsys_destroy(ls);
    }
    def.text = "#include <lpfgall.h>\nmodule A(int);\nint f(int n) { return f(n + 1); }\n"
               "Axiom: A(1);\nA(x) : { produce A(f(x)); }\n";
    ls = lsys_from_def(ctx, &def);
    if (ls) {
        CHECK(cbm_lsys_step(ls) == CBM_E_LIMIT);
        cbm_lsys_destroy(ls);
    }
    test_ctx_end(ctx);
}

/* A struct of many fields (the listing's InternodeData has 35): 64 are allowed, 65 refused. */
static char *big_struct(int fields)
{
    size_t cap = 4096 + 16 * (size_t)fields;
    char *t = malloc(cap);
    if (!t)
        return NULL;
    size_t n =
        (size_t)snprintf(t, cap, "#include <lpfgall.h>\nderivation length: 2;\nstruct Big {");
    for (int i = 0; i < fields; i++)
        n += (size_t)snprintf(t + n, cap - n, " double f%d;", i);
    snprintf(t + n, cap - n,
             " };\nmodule A(Big);\nAxiom: A(Big());\n"
             "A(b) : { b.f%d = b.f0 + 7; b.f0 = 1; produce A(b); }\n",
             fields - 1);
    return t;
}

TEST(lpfg_struct_many_fields)
{
    cbm_context *ctx = test_ctx();
    char *t = big_struct(64);
    CHECK(t != NULL);
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = "big.l";
    def.text = t;
    cbm_lsys *ls = lsys_from_def(ctx, &def);
    CHECK_OK(cbm_lsys_step(ls));
    CHECK_OK(cbm_lsys_step(ls));
    cbm_lsys_cursor c;
    cbm_lsys_cursor_begin(ls, false, &c);
    CHECK(cbm_lsys_cursor_next(ls, false, &c));
    CHECK_EQ_INT(c.nparams, 64);
    CHECK_NEAR(c.params[0], 1, 0);
    CHECK_NEAR(c.params[63], 8, 0);
    cbm_lsys_destroy(ls);
    free(t);
    t = big_struct(65);
    def.text = t;
    ls = NULL;
    CHECK(cbm_lsys_load(ctx, &def, &ls) == CBM_E_SYNTAX);
    CHECK(ls == NULL);
    free(t);
    cbm_context_clear_errors(ctx);
    test_ctx_end(ctx);
}

/* ---- production bodies in the register code (lang/lc_code.h) ---- */

enum { BY_CODE, BY_NATIVE };

/* The string (and, when the model has one, its interpretation) after `steps` steps (at most;
 * fewer when the model stops) in the register code or native code; NULL when native code
 * cannot be had (*why). *compiled and *total: the bodies compiled, of all. */
static char *run_bodies(cbm_context *ctx, const char *path, int steps, int by, const char **why,
                        size_t *compiled, size_t *total)
{
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = path;
    cbm_lsys *ls = NULL;
    cbm_status s = cbm_lsys_load(ctx, &def, &ls);
    CHECK_MSG(s == CBM_OK, "%s: %s", path, cbm_context_last_error(ctx));
    if (s != CBM_OK)
        return NULL;
    cbm__lpfg_bodies(ls, compiled, total);
    char *got = NULL;
    if (by != BY_NATIVE || cbm_lsys_compile_native(ls, test_tmp_dir(), why)) {
        CHECK_OK(cbm_lsys_reset(ls));
        if (steps < 0)
            steps = cbm_lsys_derivation_length(ls);
        for (int i = 0; i < steps && !cbm_lsys_stopped(ls); i++)
            CHECK_OK(cbm_lsys_step(ls));
        got = lpfg_string(ctx, ls, false, '\n');
        if (got && cbm_lsys_has_homomorphism(ls)) {
            char *img = lpfg_string(ctx, ls, true, '\n');
            size_t a = strlen(got), b = img ? strlen(img) : 0;
            char *both = realloc(got, a + b + 2);
            if (both) {
                both[a] = '|';
                memcpy(both + a + 1, img ? img : "", b + 1);
                got = both;
            }
            free(img);
        }
    }
    cbm_lsys_destroy(ls);
    return got;
}

/* FNV-1a (64 bits) of a string: the digests of lpfg_bodies_match_walker */
static uint64_t digest(const char *t)
{
    uint64_t h = 0xcbf29ce484222325ull;
    for (; t && *t; t++)
        h = (h ^ (unsigned char)*t) * 0x100000001b3ull;
    return h;
}

/* The C library the walker's digests were recorded with (gnu_get_libc_version). */
#define WALKER_LIBC "glibc 2.36"

static const char *libc_name(void)
{
#ifdef __GLIBC__
    static char name[64];
    snprintf(name, sizeof name, "glibc %s", gnu_get_libc_version());
    return name;
#else
    return "a C library other than glibc";
#endif
}

/* The register code and native code give the strings and interpretations of the tree walker
 * they replaced, byte for byte: every model of tests/lpfg, every L+C model of models/ (16 steps
 * of the buckling column, 48 of the fruit trees), compute.l and the six lpfg oracle models (with
 * ../shared). The walker's string (and interpretation) of each is kept as its FNV-1a digest,
 * recorded on 2026-11-27 by this test while the walker still ran (commit 0224ed7, where the
 * test compared them in full); native code is compared with the register code in full. Every
 * production body compiles (the counts are checked, so that a body that stops compiling is
 * seen). A digest that changes is a change of output: say why before recording the new one.
 * The beech's and the spruce's digests are of the models as changed on 2026-11-27 (tension wood,
 * self-pruning, a seedling shoot without laterals): the walker of commit 0224ed7, run on the new
 * model files, gave these digests and equalled its register code in full.
 *
 * libm: the digests are exact, so they hold for the C library they were recorded with
 * (WALKER_LIBC). A libm correct to 1 ULP that rounds otherwise changes the strings of 13 of the
 * 37 models (marked `libm`): those of models/ but the buckling column, whose mechanics (bending,
 * the frames' rotations) go through sincos, atan2, pow ... in double and feed the next steps,
 * and taylor-hell-constructs.l, where a rotation by a right angle leaves a 0 or a -0 by the last
 * bit of cos. The other 24 (the L+C test models, compute.l, the buckling column and the six
 * oracle models) do not change: their values through libm are rounded to float before they are
 * written or used. tests/cli/libm_ulp.sh runs this test with every transcendental result of
 * libm moved by 1 ULP (tests/cli/libm_ulp_shim.c, CBM_LIBM_MOVED=1): then a marked model must
 * differ from its digest (the move is felt) and every other one must still match, so the marks
 * are checked both ways. Under another C library a marked model's mismatch is not a failure but
 * a note naming both libraries (native code is still compared with the register code in full);
 * any other mismatch is a failure everywhere. */
TEST(lpfg_bodies_match_walker)
{
    static const struct {
        const char *file;
        int steps;
        bool oracle;
        size_t compiled, total; /* bodies compiled, of all */
        uint64_t walker;        /* FNV-1a of the tree walker's string */
        bool libm;              /* the string depends on the last bit of libm's results */
    } models[] = {
        {"tests/lpfg/backward-sum.l", 1, false, 1, 1, 0x636148b3c40e52f3ull, false},
        {"tests/lpfg/c-library.l", 1, false, 5, 5, 0xbe4c72fc751a7861ull, false},
        {"tests/lpfg/compiled-functions.l", 6, false, 1, 1, 0x6b1bce1b44283208ull, false},
        {"tests/lpfg/consider.l", 1, false, 2, 2, 0x9cec3097fcc5a9acull, false},
        {"tests/lpfg/decomposition-interp.l", 2, false, 3, 3, 0x086cabb490f6f5fbull, false},
        {"tests/lpfg/forward-signal.l", 1, false, 1, 1, 0xef8e5efa7586fe2cull, false},
        {"tests/lpfg/frames-globals.l", 1, false, 1, 1, 0xebe54a5dee959efdull, false},
        {"tests/lpfg/group0-cut-nproduce.l", 2, false, 3, 3, 0x58028d972a24e5c4ull, false},
        {"tests/lpfg/groups-globals.l", 3, false, 6, 6, 0x6f3048df2048ced9ull, false},
        {"tests/lpfg/in-left-context.l", 1, false, 1, 1, 0x234f8794e73689eaull, false},
        {"tests/lpfg/struct-vectors.l", 1, false, 1, 1, 0x418268ecc95b2f97ull, false},
        {"tests/lpfg/struct-functions.l", 1, false, 1, 1, 0x4115168b8a178191ull, false},
        {"tests/lpfg/random-host.l", 4, false, 1, 1, 0x4594857202edae2cull, false},
        {"tests/lpfg/switch.l", 1, false, 1, 1, 0xbfc6c2ca5111ba85ull, false},
        {"tests/lpfg/taylor-hell-constructs.l", 3, false, 7, 7, 0xcf41e9a094cf8069ull, true},
        {"tests/lpfg/two-branch-context.l", 1, false, 3, 3, 0x06a007f4db3f61d7ull, false},
        {"tests/lpfg/value-semantics.l", 1, false, 2, 2, 0x3fdc420cee86b4c6ull, false},
        {"bench/lc/compute.l", 12, false, 1, 1, 0x7c4f37d8ef7624dcull, false},
        {"models/taylor-hell-fruit-tree.l", 48, false, 30, 30, 0x1dcb444add576cc7ull, true},
        {"models/taylor-hell-fruit-tree-thesis.l", 48, false, 30, 30, 0x63f27669ce498918ull, true},
        {"models/taylor-hell-buckling.l", 16, false, 3, 3, 0x758eba90458e467cull, false},
        {"models/taylor-hell-pendula.l", -1, false, 7, 7, 0x5381c86a1abfb944ull, true},
        {"models/guertler-beech.l", -1, false, 8, 8, 0xf33583c99f81aeacull, true},
        {"models/guertler-spruce.l", -1, false, 6, 6, 0xdc9a7832e44a3fcbull, true},
        {"models/guertler-sympodial.l", -1, false, 3, 3, 0x784fb1b0f78a574eull, true},
        {"models/jirasek-cherries.l", -1, false, 6, 6, 0xed2f8dd2f8551b71ull, true},
        {"models/jirasek-cycad.l", -1, false, 7, 7, 0x7af350788f91958full, true},
        {"models/jirasek-grapes.l", -1, false, 7, 7, 0x9e6efeeec0d57a4dull, true},
        {"models/jirasek-ground.l", -1, false, 3, 3, 0xb99415bce2b1dfd3ull, true},
        {"models/jirasek-hanging.l", -1, false, 5, 5, 0xeafb967de01390b1ull, true},
        {"models/jirasek-s-branch.l", -1, false, 3, 3, 0x8cff6b7a5bdfce49ull, true},
        {"lpfg-compound-param", -1, true, 4, 4, 0x71d77e84992dc413ull, false},
        {"lpfg-hormone-up", -1, true, 4, 4, 0x71fc0ed36f27cf31ull, false},
        {"lpfg-innewcontext", -1, true, 3, 3, 0x23b9675e310367eeull, false},
        {"lpfg-newcontext", -1, true, 6, 6, 0x0e8ae3a8d35e3599ull, false},
        {"lpfg-quadratic-koch", -1, true, 1, 1, 0xb9872a76c168e6b4ull, false},
        {"lpfg-sympodial", -1, true, 6, 6, 0x4ff15def2f9ff352ull, false},
    };
    /* tests/cli/libm_ulp.sh: libm's results are moved by 1 ULP */
    const char *mv = getenv("CBM_LIBM_MOVED");
    bool moved = mv && !strcmp(mv, "1");
    cbm_context *ctx = test_ctx();
    bool native_ok = true;
    for (size_t k = 0; k < sizeof models / sizeof models[0]; k++) {
        char path[4096];
        if (models[k].oracle) {
            if (test_skip_without_oracles())
                continue;
            snprintf(path, sizeof path, "%s/%s/model/lsystem.l", oracle_dir(), models[k].file);
        } else
            snprintf(path, sizeof path, "%s/%s", test_source_dir(), models[k].file);
        const char *why = NULL;
        size_t compiled = 0, total = 0;
        char *code = run_bodies(ctx, path, models[k].steps, BY_CODE, NULL, &compiled, &total);
        CHECK_MSG(compiled == models[k].compiled && total == models[k].total,
                  "%s: %zu of %zu production bodies compiled (expected %zu of %zu)", models[k].file,
                  compiled, total, models[k].compiled, models[k].total);
        bool same = code && digest(code) == models[k].walker;
        if (moved && models[k].libm)
            CHECK_MSG(!same,
                      "%s: marked libm, but its string does not change when libm's results "
                      "move by 1 ULP: unmark it",
                      models[k].file);
        else if (!same && models[k].libm && strcmp(libc_name(), WALKER_LIBC) != 0)
            fprintf(stderr,
                    "note: %s: the string differs from the tree walker's (digest 0x%016llx, the "
                    "walker's 0x%016llx); this model's string depends on the last bit of libm's "
                    "results and the digest was recorded with %s, this is %s\n",
                    models[k].file, (unsigned long long)digest(code),
                    (unsigned long long)models[k].walker, WALKER_LIBC, libc_name());
        else
            CHECK_MSG(same,
                      "%s: the register code's string differs from the tree walker's (digest "
                      "0x%016llx, the walker's 0x%016llx; recorded with %s, this is %s%s)",
                      models[k].file, (unsigned long long)digest(code),
                      (unsigned long long)models[k].walker, WALKER_LIBC, libc_name(),
                      moved ? "; libm's results moved by 1 ULP: if only libm can explain it, "
                              "mark the model libm"
                            : "");
        char *native =
            native_ok ? run_bodies(ctx, path, models[k].steps, BY_NATIVE, &why, &compiled, &total)
                      : NULL;
        if (!native && why && strstr(why, "compiler"))
            native_ok = false; /* no cc: the register code is still checked */
        else if (native_ok && !(compiled == 0 && !native && why && strstr(why, "no function")))
            CHECK_MSG(native && code && !strcmp(code, native),
                      "%s: native code's string differs from the register code's (%s)",
                      models[k].file, why ? why : "");
        free(code);
        free(native);
    }
    test_ctx_end(ctx);
}

/* Everything compiles: a body with a context and a switch, a function, a Start block, a
 * global's initialiser; a function the register code cannot hold (a switch of more than 256
 * cases) refuses the model at load, named at its position, as there is no other evaluator. */
TEST(lpfg_everything_compiles)
{
    static const char *const text =
        "#include <lpfgall.h>\nmodule A(int);\nmodule B(int);\nint g = 0;\n"
        "int twice(int x) { switch (x) { case 0: return 0; default: return 2 * x; } }\n"
        "Start: { g = twice(drand48() < 2); }\n"
        "Axiom: B(1) A(0);\n"
        "A(x) : { int y = 0; if (InLeftContext(B(y))) produce A(twice(y) + g); }\n";
    cbm_context *ctx = test_ctx();
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = "m.l";
    def.text = text;
    cbm_lsys *ls = NULL;
    CHECK_OK(cbm_lsys_load(ctx, &def, &ls));
    size_t b = 9, bt = 9;
    cbm__lpfg_bodies(ls, &b, &bt);
    CHECK_MSG(b == 1 && bt == 1, "bodies %zu of %zu", b, bt);
    CHECK_OK(cbm_lsys_reset(ls));
    CHECK_OK(cbm_lsys_step(ls));
    char *got = lpfg_string(ctx, ls, false, ' ');
    CHECK_MSG(got && !strcmp(got, "B(1) A(4)"), "got '%s'", got ? got : "");
    free(got);
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
    /* 257 cases */
    size_t cap = 16384, n = 0;
    char *big = malloc(cap);
    CHECK(big != NULL);
    if (!big)
        return;
    n += (size_t)snprintf(big + n, cap - n,
                          "#include <lpfgall.h>\nmodule A(int);\nint f(int x)\n{\n"
                          "    switch (x) {");
    for (int c = 0; c < 257; c++)
        n += (size_t)snprintf(big + n, cap - n, " case %d: return %d;", c, c);
    snprintf(big + n, cap - n, " }\n    return 0;\n}\nAxiom: A(1);\nA(x) : { produce A(f(x)); }\n");
    test_diags g;
    ctx = test_diag_ctx(&g);
    CHECK(ctx != NULL);
    if (ctx) {
        def.text = big;
        ls = NULL;
        CHECK_STATUS(cbm_lsys_load(ctx, &def, &ls), CBM_E_LIMIT);
        CHECK(ls == NULL);
        CHECK_MSG(strstr(g.text, "m.l:3:") && strstr(g.text, "this function cannot be compiled"),
                  "%s", g.text);
        cbm_context_destroy(ctx);
    }
    free(big);
}

/* One step of model text in the register code or native code:
 * its status and diagnostics in *g, the string after it in *str (the caller frees it);
 * CBM_E_UNSUPPORTED when native code cannot be had. */
static cbm_status body_step(const char *text, int by, test_diags *g, char **str, size_t *compiled)
{
    *str = NULL;
    cbm_lsys_def def = lsys_text_def("m.l", text);
    def.max_loop_iterations = 1000;
    cbm_context *ctx;
    cbm_lsys *ls;
    cbm_status s = lsys_load_diags(g, &def, &ctx, &ls);
    if (!ctx)
        return s;
    CHECK_OK(s);
    const char *why = NULL;
    size_t total = 0;
    if (s == CBM_OK)
        cbm__lpfg_bodies(ls, compiled, &total);
    if (s == CBM_OK && by == BY_NATIVE && !cbm_lsys_compile_native(ls, test_tmp_dir(), &why)) {
        CHECK_MSG(why && (strstr(why, "compiler") || (!*compiled && strstr(why, "no function"))),
                  "%s", why ? why : "?");
        s = CBM_E_UNSUPPORTED;
    } else if (s == CBM_OK) {
        CHECK_OK(cbm_lsys_reset(ls));
        s = cbm_lsys_step(ls);
        if (s == CBM_OK)
            *str = lpfg_string(ctx, ls, false, ' ');
    }
    cbm_lsys_destroy(ls);
    cbm_context_destroy(ctx);
    return s;
}

/* body_step without the string: the status and the diagnostics of one step. */
static cbm_status step_diags(const char *text, int by, test_diags *g)
{
    char *str = NULL;
    size_t compiled = 0;
    cbm_status s = body_step(text, by, g, &str, &compiled);
    free(str);
    return s;
}

/* Native code stops at the same statement with the same message as the register code: a
 * division by zero names its line and column, loops spend the step's budget, recursion is
 * bounded by the call depth. */
TEST(lpfg_native_errors)
{
    static const struct {
        const char *text, *where, *what;
        cbm_status status;
    } cases[] = {
        {"#include <lpfgall.h>\nmodule A(int);\n"
         "int f(int n) {\n"
         "    int d = n - 1;\n"
         "    return 10 % d; }\n"
         "Axiom: A(1);\nA(x) : { produce A(f(x)); }\n",
         "m.l:5:5: ", "integer remainder by zero", CBM_E_RUNTIME},
        {"#include <lpfgall.h>\nmodule A(int);\n"
         "int f(int n) { while (n > 0) n = n + 1; return n; }\n"
         "Axiom: A(1);\nA(x) : { produce A(f(x)); }\n",
         "m.l:3:", "more loop iterations in one step than the limit", CBM_E_LIMIT},
        {"#include <lpfgall.h>\nmodule A(int);\nint f(int n) { return f(n + 1); }\n"
         "Axiom: A(1);\nA(x) : { produce A(f(x)); }\n",
         "m.l:3:", "function calls nested too deeply", CBM_E_LIMIT},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        test_diags code, native;
        CHECK_STATUS(step_diags(cases[k].text, BY_CODE, &code), cases[k].status);
        cbm_status s = step_diags(cases[k].text, BY_NATIVE, &native);
        if (s == CBM_E_UNSUPPORTED) {
            test_skip("no C compiler (cc) for native code");
            return;
        }
        CHECK_STATUS(s, cases[k].status);
        CHECK_MSG(strstr(code.text, cases[k].where) && strstr(code.text, cases[k].what), "%s",
                  code.text);
        CHECK_MSG(!strcmp(code.text, native.text), "register code: %s\nnative code: %s", code.text,
                  native.text);
    }
}

/* Errors in compiled production bodies stop at the statement and with the message the tree
 * walker gave (checked against it while it ran), in the register code and in native code alike;
 * an error inside a produced module's argument names the argument's first character (the walker
 * named the produce statement, or for a parameter that is not finite the argument's end: its
 * closing parenthesis), where the faulty expression is, as a compiler would point at it:
 * a division by zero, a parameter that is not finite, the loop budget,
 * the call depth of a compiled function called from the body, an error in compiled functions
 * with struct parameters (one a reference) and vector arithmetic, an error inside quaternion
 * arithmetic, an error in a compiled switch, func() without function files (a host call,
 * O_HOST), an error in a compiled EndEach block, a mechanics call's error (a host call). A body
 * with a switch compiles (counted) and gives the walker's string. */
TEST(lpfg_bodies_errors)
{
    static const struct {
        const char *text, *where, *what;
        cbm_status status;
        size_t compiled;
    } cases[] = {
        {"#include <lpfgall.h>\nmodule A(int);\nAxiom: A(1);\n"
         "A(x) : {\n"
         "    int d = x - 1;\n"
         "    produce A(10 / d); }\n",
         "m.l:6:15: ", "integer division by zero", CBM_E_RUNTIME, 1},
        {"#include <lpfgall.h>\nmodule A(int, double);\nAxiom: A(1, 0);\n"
         "A(x, y) : {\n"
         "    nproduce A(x, y);\n"
         "    produce A(x + 1, 1 / y); }\n",
         "m.l:6:22: ", "is not a finite number", CBM_E_RUNTIME, 1},
        {"#include <lpfgall.h>\nmodule A(int);\nAxiom: A(1);\n"
         "A(x) : {\n"
         "    while (x > 0)\n"
         "        x = x + 1;\n"
         "    produce A(x); }\n",
         "m.l:6:9: ", "more loop iterations in one step than the limit", CBM_E_LIMIT, 1},
        {"#include <lpfgall.h>\nmodule A(int);\nint f(int n) { return f(n + 1); }\n"
         "Axiom: A(1);\n"
         "A(x) : { produce A(f(x)); }\n",
         "m.l:3:16: ", "nested too deeply", CBM_E_LIMIT, 1},
        {"#include <lpfgall.h>\nstruct P { int a; };\nmodule A(int);\n"
         "int g(P p) { return 7 % p.a; }\n"
         "Axiom: A(1);\n"
         "A(x) : { P p; p.a = x - 1; produce A(g(p)); }\n",
         "m.l:4:14: ", "integer remainder by zero", CBM_E_RUNTIME, 1},
        {"#include <lpfgall.h>\nstruct P { int a; V3d v; };\nmodule A(int);\n"
         "void h(P &p, int d) { p.v = p.v * 2.0; p.a = 7 / d; }\n"
         "Axiom: A(1);\n"
         "A(x) : { P p; h(p, x - 1); produce A(p.a); }\n",
         "m.l:4:40: ", "integer division by zero", CBM_E_RUNTIME, 1},
        {"#include <lpfgall.h>\nmodule A(int);\n"
         "int g(int a) { int r = 0; switch (a) { case 5: r = 1; break; default: r = 7 % a; } "
         "return r; }\n"
         "Axiom: A(1);\n"
         "A(x) : { produce A(g(x - 1)); }\n",
         "m.l:3:71: ", "integer remainder by zero", CBM_E_RUNTIME, 1},
        {"#include <lpfgall.h>\nmodule A(int);\nAxiom: A(1);\n"
         "A(x) : { Quaternion q = MakeQuaternion(V3f(0, 0, 1), 7 % (x - 1)); produce A(x); }\n",
         "m.l:4:10: ", "integer remainder by zero", CBM_E_RUNTIME, 1},
        {"#include <lpfgall.h>\nmodule A(int);\nAxiom: A(1);\n"
         "A(x) : {\n"
         "    switch (x) { case 0: break; case 1: x = 3 / (x - 1); }\n"
         "    produce A(x); }\n",
         "m.l:5:41: ", "integer division by zero", CBM_E_RUNTIME, 1},
        {"#include <lpfgall.h>\nmodule A(double);\nAxiom: A(1);\n"
         "A(x) : {\n"
         "    double y = drand48();\n"
         "    produce A(y + func(F, x)); }\n",
         "m.l:6:15: ", "needs function files", CBM_E_RUNTIME, 1},
        {"#include <lpfgall.h>\nmodule A(int);\nint z = 0;\nAxiom: A(1);\n"
         "A(x) : { produce A(x + 1); }\n"
         "EndEach: {\n"
         "    z = drand48() < 2 ? 7 / z : 0; }\n",
         "m.l:7:5: ", "integer division by zero", CBM_E_RUNTIME, 1},
        {"#include <lpfgall.h>\nmodule A(int);\nAxiom: A(1);\n"
         "A(x) : { produce A(x + 1); }\n"
         "EndEach: {\n"
         "    Ground(0, -1, 0); }\n",
         "m.l:6:5: ", "Ground(height y0 m, stiffness k >= 0", CBM_E_INVALID, 1},
        {"#include <lpfgall.h>\nmodule A(int);\nAxiom: A(1) A(2) A(3);\n"
         "A(x) : {\n"
         "    switch (x) {\n"
         "    case 1: produce A(10);\n"
         "    case 2: break;\n"
         "    default: produce A(x * x);\n"
         "    }\n"
         "    produce A(-x); }\n",
         "A(10) A(-2) A(9)", NULL, CBM_OK, 1},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        test_diags code, native;
        char *sc = NULL, *sn = NULL;
        size_t compiled = 9;
        CHECK_STATUS(body_step(cases[k].text, BY_CODE, &code, &sc, &compiled), cases[k].status);
        CHECK_MSG(compiled == cases[k].compiled, "case %zu: %zu bodies compiled", k, compiled);
        if (cases[k].what) /* an error: where and what */
            CHECK_MSG(strstr(code.text, cases[k].where) && strstr(code.text, cases[k].what),
                      "case %zu: %s", k, code.text);
        else /* the string */
            CHECK_MSG(sc && !strcmp(sc, cases[k].where), "case %zu: '%s'", k, sc ? sc : "");
        cbm_status s = body_step(cases[k].text, BY_NATIVE, &native, &sn, &compiled);
        if (s != CBM_E_UNSUPPORTED) {
            CHECK_STATUS(s, cases[k].status);
            CHECK_MSG(!strcmp(code.text, native.text), "register code: %s\nnative code: %s",
                      code.text, native.text);
            CHECK_MSG((!sc && !sn) || (sc && sn && !strcmp(sc, sn)), "case %zu: '%s' / '%s'", k,
                      sc ? sc : "", sn ? sn : "");
        }
        free(sc);
        free(sn);
    }
}

/* Runtime errors of what runs once, compiled as roots of the program: a global's initialiser
 * (named by the global, at the initialiser's first character) and an argument of the axiom (at
 * the argument's first character, as a produced parameter's; both named the expression's end
 * before, the axiom's at the module's closing parenthesis). */
TEST(lpfg_root_errors)
{
    static const struct {
        const char *text, *where, *what;
    } cases[] = {
        {"#include <lpfgall.h>\nmodule A(int);\nint z = 1;\nint g = 7 / (z - 1);\n"
         "Axiom: A(g);\nA(x) : { produce A(x); }\n",
         "m.l:4:9: ", "g: integer division by zero"},
        {"#include <lpfgall.h>\nmodule A(int);\nint z = 1;\n"
         "Axiom: A(1) A(7 % (z - 1));\nA(x) : { produce A(x); }\n",
         "m.l:4:15: ", "axiom: integer remainder by zero"},
        {"#include <lpfgall.h>\nmodule A(int);\nmodule B(int, float);\nint z = 1;\n"
         "Axiom: A(1) B(z,   (z - 1) + 7 / (z - 1));\nA(x) : { produce A(x); }\n",
         "m.l:5:20: ", "axiom: integer division by zero"}, /* converted to float */
        {"#include <lpfgall.h>\nmodule A(int);\nmodule B(int, double);\nint z = 1;\n"
         "Axiom: A(1) B(z, z / (z - 1.0));\nA(x) : { produce A(x); }\n",
         "m.l:5:18: ", "axiom: a parameter of B is not a finite number"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        const cbm_lsys_def def = lsys_text_def("m.l", cases[k].text);
        test_diags g;
        cbm_context *ctx;
        cbm_lsys *ls;
        cbm_status s = lsys_load_diags(&g, &def, &ctx, &ls);
        if (!ctx)
            return;
        CHECK_OK(s);
        CHECK_STATUS(cbm_lsys_reset(ls), CBM_E_RUNTIME);
        CHECK_MSG(strstr(g.text, cases[k].where) && strstr(g.text, cases[k].what), "case %zu: %s",
                  k, g.text);
        cbm_lsys_destroy(ls);
        cbm_context_destroy(ctx);
    }
}

/* A global's initialiser may read the global itself (C++'s point of declaration is before the
 * initialiser; it was an unknown name here before): a scalar reads zero, a struct's braces
 * initialise it in place field by field (p.b reads the p.a just stored), a constructor's
 * arguments read it before it runs (v.x is zero), a later global reads the earlier ones and a
 * global without initialiser is zero. The values are those g++ 12 and clang++ 14 give for the
 * same declarations (V3d a class with a constructor). A step changes every global; after a reset
 * the run starts as a new lpfg process would (zeros, then the initialisers in order): the same
 * axiom and the same string after two steps. */
TEST(lpfg_globals_read_themselves)
{
    static const char *const text =
        "#include <lpfgall.h>\n"
        "struct P { double a; double b; int n; };\n"
        "module Q(double, double, double, int, double, double, double, int, double);\n"
        "double g = g + 1;\n"
        "P p = {g + 1, p.a * 10, p.n + 3};\n"
        "V3d v = V3d(v.x + 1, v.x + g, p.b);\n"
        "int count;\n"
        "double h = g + p.b + count;\n"
        "Axiom: Q(g, p.a, p.b, p.n, v.x, v.y, v.z, count, h);\n"
        "Q(a, b, c, n, x, y, z, k, e) : {\n"
        "    g = g + 100; p.a = p.a + 1; p.b = -p.b; p.n = p.n * 2; v = v * 3.0;\n"
        "    count = count + 1; h = -h;\n"
        "    produce Q(g, p.a, p.b, p.n, v.x, v.y, v.z, count, h); }\n";
    static const char *const axiom = "Q(1,2,20,3,1,1,20,0,21)";
    static const char *const after2 = "Q(201,4,20,12,9,9,180,2,21)";
    cbm_context *ctx = test_ctx();
    cbm_lsys_def def = lsys_text_def("m.l", text);
    cbm_lsys *ls = NULL;
    cbm_status s = cbm_lsys_load(ctx, &def, &ls);
    CHECK_MSG(s == CBM_OK, "%s", cbm_context_last_error(ctx));
    for (int run = 0; run < 2 && s == CBM_OK; run++) {
        CHECK_OK(cbm_lsys_reset(ls));
        char *got = lpfg_string(ctx, ls, false, ' ');
        CHECK_MSG(got && !strcmp(got, axiom), "run %d: axiom '%s', expected '%s'", run,
                  got ? got : "", axiom);
        free(got);
        CHECK_OK(cbm_lsys_step(ls));
        CHECK_OK(cbm_lsys_step(ls));
        got = lpfg_string(ctx, ls, false, ' ');
        CHECK_MSG(got && !strcmp(got, after2), "run %d: after 2 steps '%s', expected '%s'", run,
                  got ? got : "", after2);
        free(got);
    }
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

/* The text of a model whose axiom is n times `A(1, -1.5 / 4) B`, then `A(last, 0)`. */
static char *long_axiom(int n, const char *last)
{
    size_t cap = (size_t)n * 20 + 512, len = 0;
    char *t = malloc(cap);
    if (!t)
        return NULL;
    len += (size_t)snprintf(t, cap,
                            "#include <lpfgall.h>\nmodule A(int, float);\nmodule B();\n"
                            "int g = 3;\nAxiom:");
    for (int i = 0; i < n; i++)
        len += (size_t)snprintf(t + len, cap - len, " A(1, -1.5 / 4) B");
    snprintf(t + len, cap - len, " A(%s, 0);\nA(x, y) : { produce A(x + 1, y); }\n", last);
    return t;
}

/* An axiom whose code reads nothing of the run is kept as its string, compiled and run at load
 * LC_AXIOM_PART modules at a time: the whole code of 50001 modules (an O_PROD each, 32 bytes,
 * and the loads of their parameters) never exists, so the library's peak while loading is lower
 * by more than 64 bytes a module (it was 13.2 MB against 20.5 MB, 145 bytes a module, when
 * written) than for the same axiom ending with a module that reads a global (compiled whole and
 * run at every reset). Both give the same string at every reset and
 * after a step; a reset after steps gives the axiom again. An axiom whose run fails at load
 * (a parameter that is not finite) keeps its code: every reset reports it at its argument. */
TEST(lpfg_axiom_kept_as_string)
{
    enum { N = 25000 };
    size_t peak[2] = {0, 0};
    char *str[2][2] = {{NULL, NULL}, {NULL, NULL}};
    for (int k = 0; k < 2; k++) {
        char *text = long_axiom(N, k == 0 ? "3" : "g");
        CHECK(text != NULL);
        if (!text)
            continue; /* the comparisons below fail on the missing strings */
        cbm_context *ctx = test_ctx();
        cbm_lsys_def def = lsys_text_def("m.l", text);
        cbm_lsys *ls = NULL;
        CHECK_OK(cbm_lsys_load(ctx, &def, &ls));
        peak[k] = cbm_context_peak_bytes(ctx);
        for (int run = 0; run < 2 && ls; run++) {
            CHECK_OK(cbm_lsys_reset(ls));
            char *axiom = lpfg_string(ctx, ls, false, ' ');
            CHECK_OK(cbm_lsys_step(ls));
            free(str[k][1]);
            str[k][1] = lpfg_string(ctx, ls, false, ' ');
            if (run == 0)
                str[k][0] = axiom;
            else {
                CHECK_MSG(axiom && str[k][0] && !strcmp(axiom, str[k][0]),
                          "axiom %d: the second reset gives another string", k);
                free(axiom);
            }
        }
        cbm_lsys_destroy(ls);
        test_ctx_end(ctx);
        free(text);
    }
    for (int i = 0; i < 2; i++)
        CHECK_MSG(str[0][i] && str[1][i] && !strcmp(str[0][i], str[1][i]),
                  "%s: the kept axiom's string differs from the compiled one's",
                  i ? "after a step" : "axiom");
    CHECK_MSG(str[0][0] && !strncmp(str[0][0], "A(1,-0.375) B A(1,-0.375) B", 27) &&
                  strstr(str[0][0], "B A(3,0)"),
              "%.60s", str[0][0] ? str[0][0] : "");
    CHECK_MSG(peak[0] + (size_t)(2 * N + 1) * 64 < peak[1],
              "peak while loading: %zu bytes with the axiom kept, %zu compiled whole", peak[0],
              peak[1]);
    for (int k = 0; k < 2; k++)
        for (int i = 0; i < 2; i++)
            free(str[k][i]);
    /* a parameter that is not finite: reported at every reset */
    test_diags g;
    cbm_context *ctx;
    cbm_lsys *ls;
    const cbm_lsys_def def = lsys_text_def(
        "m.l", "#include <lpfgall.h>\nmodule A(int, float);\nAxiom: A(1, 0) A(2, 1 / 0.0);\n");
    cbm_status s = lsys_load_diags(&g, &def, &ctx, &ls);
    if (!ctx)
        return;
    CHECK_OK(s);
    for (int run = 0; run < 2 && s == CBM_OK; run++) {
        g.count = 0;
        g.text[0] = 0;
        CHECK_STATUS(cbm_lsys_reset(ls), CBM_E_RUNTIME);
        CHECK_MSG(strstr(g.text, "m.l:3:21: ") && strstr(g.text, "axiom: a parameter of A"),
                  "reset %d: %s", run, g.text);
    }
    cbm_lsys_destroy(ls);
    cbm_context_destroy(ctx);
}
