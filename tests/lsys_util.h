/* Helpers of the L-system tests: loading a model, formatting strings in memory, comparing with
 * cpfg's string files (exactly, or with a relative tolerance on the numbers). */
#ifndef CBM_TEST_LSYS_UTIL_H
#define CBM_TEST_LSYS_UTIL_H

#include "test.h"

#include "cambium/lsys.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct tbuf {
    char *s;
    size_t n, cap;
} tbuf;

static inline void tb_put(tbuf *b, const char *s, size_t n)
{
    if (b->n + n + 1 > b->cap) {
        size_t cap = (b->n + n + 1) * 2;
        char *s2 = realloc(b->s, cap);
        if (!s2) {
            fprintf(stderr, "tb_put: out of memory\n");
            abort();
        }
        b->s = s2;
        b->cap = cap;
    }
    memcpy(b->s + b->n, s, n);
    b->n += n;
    b->s[b->n] = 0;
}

/* Loads models/<name> of the repository, with one -D NAME=VALUE when define is not NULL. */
static inline cbm_status lsys_load_shipped(cbm_context *ctx, const char *name, const char *define,
                                           cbm_lsys **ls)
{
    char path[2048];
    snprintf(path, sizeof path, "%s/models/%s", test_source_dir(), name);
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = path;
    def.defines = define ? &define : NULL;
    def.define_count = define ? 1 : 0;
    return cbm_lsys_load(ctx, &def, ls);
}

/* The settings of model `text`, named `path` in its messages, the others at their defaults. */
static inline cbm_lsys_def lsys_text_def(const char *path, const char *text)
{
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = path;
    def.text = text;
    return def;
}

/* The model of def loaded and reset to its axiom, each checked at the caller's line; NULL when
 * either failed (the test has failed then). lsys_from_text: the model `text`, named `path` in
 * its messages, with the other settings at their defaults. */
#define lsys_from_def(ctx, def) lsys_load_reset_at((ctx), (def), __FILE__, __LINE__)
#define lsys_from_text(ctx, path, text)                                                            \
    lsys_text_reset_at((ctx), (path), (text), __FILE__, __LINE__)
static inline cbm_lsys *lsys_load_reset_at(cbm_context *ctx, const cbm_lsys_def *def,
                                           const char *file, int line)
{
    cbm_lsys *ls = NULL;
    cbm_status s = cbm_lsys_load(ctx, def, &ls);
    if (s == CBM_OK) {
        s = cbm_lsys_reset(ls);
        if (s != CBM_OK) {
            cbm_test_fail(file, line, "%s: reset: %s: %s", def->path, cbm_status_name(s),
                          cbm_context_last_error(ctx));
            cbm_lsys_destroy(ls);
            return NULL;
        }
    } else {
        cbm_test_fail(file, line, "%s: %s: %s", def->path, cbm_status_name(s),
                      cbm_context_last_error(ctx));
    }
    return ls;
}

static inline cbm_lsys *lsys_text_reset_at(cbm_context *ctx, const char *path, const char *text,
                                           const char *file, int line)
{
    cbm_lsys_def def = lsys_text_def(path, text);
    return lsys_load_reset_at(ctx, &def, file, line);
}

/* The model of def loaded into a new context whose diagnostics go to *g (test_diag_ctx): the
 * status of the load, unchecked (for tests that expect errors). *ctx receives the context, which
 * the caller destroys; when it cannot be made, the test fails at the caller's line, *ctx is NULL
 * and CBM_E_NOMEM is returned. *ls receives the model (NULL when the load failed). */
#define lsys_load_diags(g, def, ctx, ls)                                                           \
    lsys_load_diags_at((g), (def), (ctx), (ls), __FILE__, __LINE__)
static inline cbm_status lsys_load_diags_at(test_diags *g, const cbm_lsys_def *def,
                                            cbm_context **ctx, cbm_lsys **ls, const char *file,
                                            int line)
{
    *ls = NULL;
    *ctx = test_diag_ctx(g);
    if (!*ctx) {
        cbm_test_fail(file, line, "no context for the diagnostics");
        return CBM_E_NOMEM;
    }
    return cbm_lsys_load(*ctx, def, ls);
}

/* The model `text`, named `path` in its messages, loaded, reset and derived `steps` steps,
 * stopping at the first failure: its status (unchecked: for tests that expect failures, out of
 * memory among them). *ls receives the model (NULL when the load failed); the caller destroys
 * it. */
static inline cbm_status lsys_derive(cbm_context *ctx, const char *path, const char *text,
                                     int steps, cbm_lsys **ls)
{
    cbm_lsys_def def = lsys_text_def(path, text);
    *ls = NULL;
    cbm_status s = cbm_lsys_load(ctx, &def, ls);
    if (s == CBM_OK)
        s = cbm_lsys_reset(*ls);
    for (int i = 0; i < steps && s == CBM_OK; i++)
        s = cbm_lsys_step(*ls);
    return s;
}

/* What a run of lsys_derive_homomorphism derived: the steps, and the modules of the string and
 * of its homomorphism (0 where it failed before). */
typedef struct lsys_derived {
    int steps;
    size_t modules, homomorphism_modules;
} lsys_derived;

/* lsys_derive, then the homomorphism applied, the model released: the first failure's status
 * (unchecked: for the out-of-memory loops), and what was derived in *out (may be NULL), so that
 * the loops can check that their last run, the one without a failure, derived the whole. */
static inline cbm_status lsys_derive_homomorphism(cbm_context *ctx, const char *path,
                                                  const char *text, int steps, lsys_derived *out)
{
    cbm_lsys *ls = NULL;
    cbm_status s = lsys_derive(ctx, path, text, steps, &ls);
    lsys_derived d = {0, 0, 0};
    if (ls) {
        d.steps = cbm_lsys_steps_done(ls);
        d.modules = cbm_lsys_module_count(ls);
    }
    if (s == CBM_OK)
        s = cbm_lsys_apply_homomorphism(ls);
    if (s == CBM_OK)
        d.homomorphism_modules = cbm_lsys_homomorphism_module_count(ls);
    cbm_lsys_destroy(ls);
    if (out)
        *out = d;
    return s;
}

/* The out-of-memory loop over run (a test_oom_fn whose ud is an lsys_derived, calling
 * lsys_derive_homomorphism): every allocation failed in turn; the last run, without a failure,
 * derived what a run with memory enough derives, which is `steps` steps and `modules` modules in
 * the string and in its homomorphism. */
static inline void lsys_check_out_of_memory(test_oom_fn run, int steps, size_t modules)
{
    lsys_derived last, whole;
    int runs = test_oom_loop(run, &last);
    CHECK(runs > 20);
    cbm_context *ctx = test_ctx();
    CHECK_OK(run(ctx, &whole));
    test_ctx_end(ctx);
    CHECK_EQ_INT(whole.steps, steps);
    CHECK_EQ_INT(whole.modules, modules);
    CHECK_EQ_INT(whole.homomorphism_modules, modules);
    CHECK_EQ_INT(last.steps, whole.steps);
    CHECK_EQ_INT(last.modules, whole.modules);
    CHECK_EQ_INT(last.homomorphism_modules, whole.homomorphism_modules);
}

/* The symbol of the L+C module called `name`, -1 if none. */
static inline int lsys_symbol(const cbm_lsys *ls, const char *name)
{
    for (int s = 1; s < 128; s++) {
        const char *m = cbm_lsys_module_name(ls, s);
        if (m && !strcmp(m, name))
            return s;
    }
    return -1;
}

static inline void tb_free(tbuf *b)
{
    free(b->s);
    memset(b, 0, sizeof *b);
}

/* The string as cpfg -str (without the line wrapping) when exact_fmt is false (%g), or one
 * module per line with %.9g when true. */
static inline void format_string(const cbm_lsys *ls, bool homo, bool exact_fmt, tbuf *b)
{
    cbm_lsys_cursor c;
    char tmp[64];
    cbm_lsys_cursor_begin(ls, homo, &c);
    tb_put(b, "", 0);
    while (cbm_lsys_cursor_next(ls, homo, &c)) {
        char ch = (char)c.symbol;
        tb_put(b, &ch, 1);
        for (int i = 0; i < c.nparams; i++) {
            int k = snprintf(tmp, sizeof tmp, exact_fmt ? "%c%.9g" : "%c%g", i ? ',' : '(',
                             c.params[i]);
            tb_put(b, tmp, (size_t)k);
        }
        if (c.nparams)
            tb_put(b, ")", 1);
        if (exact_fmt)
            tb_put(b, "\n", 1);
    }
}

/* Reads a file; with join, newlines are removed (cpfg's 70-column wrapping). NULL if absent. */
static inline char *read_text(const char *path, bool join)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    tbuf b = {0};
    tb_put(&b, "", 0);
    char buf[65536];
    size_t k;
    while ((k = fread(buf, 1, sizeof buf, f)) > 0) {
        if (!join) {
            tb_put(&b, buf, k);
            continue;
        }
        for (size_t i = 0; i < k; i++)
            if (buf[i] != '\n' && buf[i] != '\r')
                tb_put(&b, buf + i, 1);
    }
    fclose(f);
    return b.s;
}

static inline bool numch(char c)
{
    return (c >= '0' && c <= '9') || c == '.' || c == '-' || c == '+' || c == 'e' || c == 'E';
}

/* Compares two strings, numbers inside parentheses within rel (relative) or abs_tol.
 * Returns the offset of the first difference in a, or (size_t)-1 when equal. */
static inline size_t compare_tol(const char *a, const char *b, double rel, double abs_tol)
{
    size_t i = 0, j = 0;
    int depth = 0;
    while (a[i] && b[j]) {
        if (depth > 0 && numch(a[i]) && numch(b[j]) && a[i] != 'e' && a[i] != 'E') {
            char *ea, *eb;
            double x = strtod(a + i, &ea), y = strtod(b + j, &eb);
            if (ea == a + i || eb == b + j)
                return i;
            double d = x - y;
            if (d < 0)
                d = -d;
            double m = (x < 0 ? -x : x) > (y < 0 ? -y : y) ? (x < 0 ? -x : x) : (y < 0 ? -y : y);
            if (d > abs_tol && d > rel * m)
                return i;
            i = (size_t)(ea - a);
            j = (size_t)(eb - b);
            continue;
        }
        if (a[i] != b[j])
            return i;
        if (a[i] == '(')
            depth++;
        if (a[i] == ')')
            depth--;
        i++, j++;
    }
    return a[i] == b[j] ? (size_t)-1 : i;
}

/* A control-block built-in given a bad argument: loads `Start: { stmt }` in a one-module L+C
 * model "bad.l", requires the reset to fail with a message at bad.l:4:10 that contains want. */
static inline void lc_check_start_error(const char *stmt, const char *want)
{
    char src[400];
    snprintf(src, sizeof src,
             "#include <lpfgall.h>\nderivation length: 1;\nmodule A();\n"
             "Start: { %s }\nAxiom: A;\n",
             stmt);
    test_diags g;
    cbm_context *dc;
    cbm_lsys *ls;
    cbm_lsys_def def = lsys_text_def("bad.l", src);
    CHECK_OK(lsys_load_diags(&g, &def, &dc, &ls));
    if (ls)
        CHECK_STATUS(cbm_lsys_reset(ls), CBM_E_INVALID);
    printf("%-20s -> %s", stmt, g.text);
    CHECK(!strncmp(g.text, "bad.l:4:10: ", 12) && strstr(g.text, want));
    cbm_lsys_destroy(ls);
    test_ctx_end(dc);
}

#endif
