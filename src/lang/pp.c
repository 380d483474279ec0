/* The preprocessor of model files, as the C preprocessor that cpfg runs before parsing.
 *
 * Pass 1 removes C comments (block and line comments) keeping newlines, so line numbers stay
 * true. Pass 2 goes line by line (joining backslash continuations): directives #define (object-
 * and function-like), #undef, #include "file" (relative to the including file), #ifdef,
 * #ifndef, #if N, #else, #endif; other lines get their macros expanded and are appended to the
 * output, one output line per input line, with a map back to (file, line) for diagnostics.
 * Expansion rescans the replacement with the macro itself disabled (C's rule against
 * recursion), arguments are expanded before substitution; the nesting is bounded by
 * max_expr_depth so no input can recurse without end. Names given on the command line
 * (-D NAME=VALUE) are locked: the file's own #define of that name is ignored, which is how
 * parameter studies override a model's constants.
 */
#define _XOPEN_SOURCE 700
#include "lang/lang.h"

#include <ctype.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>

typedef struct macro {
    char *name;
    char **params;
    int nparams; /* -1: object-like */
    char *body;
    bool locked, active;
    bool known; /* locked (-D) and defined, tested or used by the model */
} macro;

typedef CBM_ARRAY(char) sbuf;

/* What one macro expansion counts toward max_pp_bytes besides the text it makes: macros that
 * expand to little but many times (#define A1 A0 A0, A0 empty) are bounded in time too. */
#define EXPANSION_COST 64

typedef struct pp_state {
    cbm__pp *pp;
    CBM_ARRAY(macro) macros;
    int include_depth;
    cbm_status status;
    bool limit_reported;      /* the expansion limit's error was given */
    size_t work;              /* macro expansions so far, times EXPANSION_COST bytes */
    const macro *used_define; /* a -D macro expanded in the line being processed */
} pp_state;

static bool is_id0(int c)
{
    return isalpha(c) || c == '_';
}
static bool is_id(int c)
{
    return isalnum(c) || c == '_';
}

static void buf_append(pp_state *st, sbuf *b, const char *s, size_t n)
{
    if (st->status != CBM_OK)
        return;
    /* any buffer of the expansion (the text, a macro's replacement or argument) stays within
     * max_pp_bytes: macros that double (#define A1 A0 A0 ...) stop here, not at the memory */
    if (b->len + n + 1 > cbm_context_limits(st->pp->ctx)->max_pp_bytes) {
        st->status = CBM_E_LIMIT;
        return;
    }
    if (CBM_ARRAY_RESERVE(st->pp->ctx, *b, b->len + n + 1) != CBM_OK) {
        st->status = CBM_E_NOMEM;
        return;
    }
    if (n > 0) { /* s may be NULL then (memcpy wants valid pointers even for 0 bytes) */
        /* reserved above: b->data is set */
        // NOLINTNEXTLINE(clang-analyzer-core.NonNullParamChecker)
        memcpy(b->data + b->len, s, n);
    }
    b->len += n;
    b->data[b->len] = 0;
}

static char *copy_text(cbm_context *ctx, const char *s, size_t n)
{
    char *d = cbm__alloc(ctx, n + 1);
    if (d) {
        memcpy(d, s, n);
        d[n] = 0;
    }
    return d;
}

static macro *find_macro(pp_state *st, const char *name, size_t n)
{
    for (size_t i = 0; i < st->macros.len; i++) {
        macro *m = &st->macros.data[i];
        if (strlen(m->name) == n && !memcmp(m->name, name, n))
            return m;
    }
    return NULL;
}

static void free_macro(cbm_context *ctx, macro *m)
{
    cbm__strfree(ctx, m->name);
    cbm__strfree(ctx, m->body);
    for (int i = 0; i < m->nparams; i++)
        cbm__strfree(ctx, m->params[i]);
    if (m->params)
        cbm__free(ctx, m->params, (size_t)m->nparams * sizeof(char *));
    memset(m, 0, sizeof *m);
}

CBM_PRINTF(5, 6)
static void pp_error(pp_state *st, int file, int line, int col, const char *fmt, ...)
{
    st->pp->errors++;
    va_list ap;
    va_start(ap, fmt);
    cbm__vdiag(st->pp->ctx, CBM_ERROR, st->pp->files.data[file], line, col, fmt, ap);
    va_end(ap);
}

/* Defines a macro from the text after "#define" (name, optional (params), body). */
static void define(pp_state *st, const char *s, bool locked, int file, int line)
{
    cbm_context *ctx = st->pp->ctx;
    const char *p = s;
    while (*p == ' ' || *p == '\t')
        p++;
    if (!is_id0((unsigned char)*p)) {
        pp_error(st, file, line, (int)(p - s) + 1, "%s", "expected a macro name after #define");
        return;
    }
    const char *name = p;
    while (is_id((unsigned char)*p))
        p++;
    size_t nlen = (size_t)(p - name);
    macro m = {0};
    m.nparams = -1;
    m.locked = locked;
    if (*p == '(') {
        m.nparams = 0;
        p++;
        for (;;) {
            while (*p == ' ' || *p == '\t')
                p++;
            if (*p == ')' && m.nparams == 0) {
                p++;
                break;
            }
            if (!is_id0((unsigned char)*p)) {
                pp_error(st, file, line, 1, "%s", "expected a parameter name in the #define");
                free_macro(ctx, &m);
                return;
            }
            const char *a = p;
            while (is_id((unsigned char)*p))
                p++;
            char **np = cbm__realloc(ctx, m.params, (size_t)m.nparams * sizeof(char *),
                                     (size_t)(m.nparams + 1) * sizeof(char *));
            char *pn = copy_text(ctx, a, (size_t)(p - a));
            if (!np || !pn) {
                char **arr = np ? np : m.params;
                for (int i = 0; i < m.nparams; i++)
                    cbm__strfree(ctx, arr[i]);
                cbm__free(ctx, arr, (size_t)(m.nparams + (np ? 1 : 0)) * sizeof(char *));
                m.params = NULL;
                m.nparams = 0;
                cbm__strfree(ctx, pn);
                free_macro(ctx, &m);
                st->status = CBM_E_NOMEM;
                return;
            }
            m.params = np;
            m.params[m.nparams++] = pn;
            while (*p == ' ' || *p == '\t')
                p++;
            if (*p == ',') {
                p++;
                continue;
            }
            if (*p == ')') {
                p++;
                break;
            }
            pp_error(st, file, line, 1, "%s", "expected ',' or ')' in the #define parameters");
            free_macro(ctx, &m);
            return;
        }
    }
    while (*p == ' ' || *p == '\t')
        p++;
    size_t blen = strlen(p);
    while (blen && isspace((unsigned char)p[blen - 1]))
        blen--;
    m.name = copy_text(ctx, name, nlen);
    m.body = copy_text(ctx, p, blen);
    if (!m.name || !m.body) {
        free_macro(ctx, &m);
        st->status = CBM_E_NOMEM;
        return;
    }
    macro *old = find_macro(st, name, nlen);
    if (old) {
        if (old->locked && !locked) {
            old->known = true;
            free_macro(ctx, &m);
            return;
        }
        free_macro(ctx, old);
        *old = m;
        return;
    }
    if (CBM_ARRAY_PUSH(ctx, st->macros, m) != CBM_OK) {
        free_macro(ctx, &m);
        st->status = CBM_E_NOMEM;
    }
}

static void expand(pp_state *st, const char *s, size_t n, sbuf *out, int depth, int file, int line);

/* Substitutes the arguments into the body of a function-like macro. */
static void substitute(pp_state *st, const macro *m, sbuf *args, sbuf *out)
{
    const char *p = m->body;
    while (*p) {
        if (is_id0((unsigned char)*p)) {
            const char *a = p;
            while (is_id((unsigned char)*p))
                p++;
            int k = -1;
            for (int i = 0; i < m->nparams; i++)
                if (strlen(m->params[i]) == (size_t)(p - a) && !memcmp(m->params[i], a, p - a))
                    k = i;
            if (k >= 0)
                buf_append(st, out, args[k].data ? args[k].data : "", args[k].len);
            else
                buf_append(st, out, a, (size_t)(p - a));
        } else if (isdigit((unsigned char)*p)) {
            const char *a = p;
            while (is_id((unsigned char)*p) || *p == '.')
                p++;
            buf_append(st, out, a, (size_t)(p - a));
        } else {
            buf_append(st, out, p, 1);
            p++;
        }
    }
}

/* The expansion exceeded max_pp_bytes: one error, at the outermost macro when known. */
static void limit_error(pp_state *st, int file, int line, int col, const char *macro_name)
{
    st->limit_reported = true;
    size_t mb = cbm_context_limits(st->pp->ctx)->max_pp_bytes >> 20;
    if (macro_name)
        pp_error(st, file, line, col,
                 "the expansion of macro '%s' makes the model larger than %zu MB (--max-expansion)",
                 macro_name, mb);
    else
        pp_error(st, file, line, col,
                 "the preprocessed model is larger than %zu MB (--max-expansion)", mb);
}

static void expand(pp_state *st, const char *s, size_t n, sbuf *out, int depth, int file, int line)
{
    cbm_context *ctx = st->pp->ctx;
    if (depth > cbm_context_limits(ctx)->max_expr_depth) {
        pp_error(st, file, line, 1, "%s", "macro expansion nested too deeply");
        return;
    }
    size_t i = 0;
    while (i < n && st->status == CBM_OK) {
        unsigned char c = (unsigned char)s[i];
        if (is_id0(c)) {
            size_t a = i;
            while (i < n && is_id((unsigned char)s[i]))
                i++;
            macro *m = find_macro(st, s + a, i - a);
            if (m)
                m->known = true;
            if (!m || m->active) {
                buf_append(st, out, s + a, i - a);
                continue;
            }
            if (m->locked && !st->used_define)
                st->used_define = m;
            st->work += EXPANSION_COST;
            if (st->work > cbm_context_limits(ctx)->max_pp_bytes) {
                st->status = CBM_E_LIMIT;
                if (depth == 0 && !st->limit_reported)
                    limit_error(st, file, line, (int)a + 1, m->name);
                return;
            }
            sbuf rep = {0};
            if (m->nparams < 0) {
                buf_append(st, &rep, m->body, strlen(m->body));
            } else {
                size_t j = i;
                while (j < n && (s[j] == ' ' || s[j] == '\t'))
                    j++;
                if (j >= n || s[j] != '(') { /* a function-like macro name without arguments */
                    buf_append(st, out, s + a, i - a);
                    continue;
                }
                j++;
                int np = 1;
                size_t starts[64], ends[64];
                starts[0] = j;
                int level = 0;
                bool closed = false;
                for (; j < n; j++) {
                    if (s[j] == '(')
                        level++;
                    else if (s[j] == ')') {
                        if (level == 0) {
                            closed = true;
                            break;
                        }
                        level--;
                    } else if (s[j] == ',' && level == 0) {
                        if (np >= 64)
                            break;
                        ends[np - 1] = j;
                        starts[np++] = j + 1;
                    }
                }
                if (!closed) {
                    pp_error(st, file, line, (int)a + 1, "unterminated arguments of macro '%s'",
                             m->name);
                    return;
                }
                ends[np - 1] = j;
                if (m->nparams == 0 && np == 1) { /* X() takes one empty argument */
                    bool blank = true;
                    for (size_t q = starts[0]; q < j; q++)
                        blank = blank && (s[q] == ' ' || s[q] == '\t');
                    if (blank)
                        np = 0;
                }
                if (np != m->nparams) {
                    pp_error(st, file, line, (int)a + 1, "wrong number of arguments to macro '%s'",
                             m->name);
                    i = j + 1;
                    continue;
                }
                sbuf args[64];
                memset(args, 0, sizeof args);
                for (int k = 0; k < np; k++) {
                    const char *as = s + starts[k];
                    size_t al = ends[k] - starts[k];
                    while (al && isspace((unsigned char)*as))
                        as++, al--;
                    while (al && isspace((unsigned char)as[al - 1]))
                        al--;
                    buf_append(st, &args[k], "", 0);
                    expand(st, as, al, &args[k], depth + 1, file, line);
                }
                substitute(st, m, args, &rep);
                for (int k = 0; k < np; k++)
                    CBM_ARRAY_FREE(ctx, args[k]);
                i = j + 1;
            }
            m->active = true;
            if (rep.data)
                expand(st, rep.data, rep.len, out, depth + 1, file, line);
            m->active = false;
            CBM_ARRAY_FREE(ctx, rep);
            if (st->status == CBM_E_LIMIT && depth == 0 && !st->limit_reported)
                limit_error(st, file, line, (int)a + 1, m->name);
        } else if (isdigit(c) || (c == '.' && i + 1 < n && isdigit((unsigned char)s[i + 1]))) {
            size_t a = i;
            while (i < n &&
                   (is_id((unsigned char)s[i]) || s[i] == '.' ||
                    ((s[i] == '+' || s[i] == '-') && (s[i - 1] == 'e' || s[i - 1] == 'E'))))
                i++;
            buf_append(st, out, s + a, i - a);
        } else if (c == '"') {
            size_t a = i++;
            while (i < n && s[i] != '"' && s[i] != '\n')
                i += (s[i] == '\\' && i + 1 < n) ? 2 : 1;
            if (i < n && s[i] == '"')
                i++;
            buf_append(st, out, s + a, i - a);
        } else {
            buf_append(st, out, s + i, 1);
            i++;
        }
    }
}

/* Removes comments, keeping newlines and string literals. */
static cbm_status strip_comments(cbm_context *ctx, const char *src, char **out, size_t *size,
                                 int *open_line, int *open_col)
{
    *open_line = 0;
    int line = 1;
    size_t line_start = 0;
    size_t n = strlen(src);
    *size = n + 1;
    char *d = cbm__alloc(ctx, n + 1);
    if (!d)
        return CBM_E_NOMEM;
    size_t o = 0;
    for (size_t i = 0; i < n;) {
        if (src[i] == '/' && src[i + 1] == '*') {
            int l0 = line, c0 = (int)(i - line_start) + 1;
            d[o++] = ' ';
            i += 2;
            while (i < n && !(src[i] == '*' && src[i + 1] == '/')) {
                if (src[i] == '\n') {
                    d[o++] = '\n';
                    line++;
                    line_start = i + 1;
                }
                i++;
            }
            if (i >= n) { /* the rest of the file would silently vanish */
                *open_line = l0;
                *open_col = c0;
            }
            i = i < n ? i + 2 : n;
        } else if (src[i] == '/' && src[i + 1] == '/') {
            while (i < n && src[i] != '\n')
                i++;
        } else if (src[i] == '"') {
            d[o++] = src[i++];
            while (i < n && src[i] != '"' && src[i] != '\n') {
                if (src[i] == '\\' && i + 1 < n)
                    d[o++] = src[i++];
                d[o++] = src[i++];
            }
            if (i < n && src[i] == '"')
                d[o++] = src[i++];
        } else if (src[i] == '\r') {
            i++;
        } else {
            if (src[i] == '\n') {
                line++;
                line_start = i + 1;
            }
            d[o++] = src[i++];
        }
    }
    d[o] = 0;
    *out = d;
    return CBM_OK;
}

/* Why a file could not be read: what read_file found. */
typedef struct read_err {
    const char *why; /* "not a regular file", ... (CBM_E_IO) */
    int line, col;   /* of a NUL byte (CBM_E_SYNTAX) */
} read_err;

/* Reads a model or included file. Only a regular file: a FIFO or a device would block or never
 * end. A NUL byte is an error at its line and column (the text is a C string). */
static cbm_status read_file(cbm_context *ctx, const char *path, char **out, read_err *re)
{
    memset(re, 0, sizeof *re);
    struct stat stt;
    if (!path || stat(path, &stt) != 0) {
        re->why = "cannot open it";
        return CBM_E_IO;
    }
    if (!S_ISREG(stt.st_mode)) {
        re->why = "not a regular file";
        return CBM_E_IO;
    }
    FILE *f = fopen(path, "rb");
    if (!f) {
        re->why = "cannot open it";
        return CBM_E_IO;
    }
    sbuf b = {0};
    char tmp[65536];
    size_t k;
    cbm_status s = CBM_OK;
    while ((k = fread(tmp, 1, sizeof tmp, f)) > 0) {
        if (CBM_ARRAY_RESERVE(ctx, b, b.len + k + 1) != CBM_OK) {
            s = CBM_E_NOMEM;
            break;
        }
        memcpy(b.data + b.len, tmp, k);
        b.len += k;
    }
    if (ferror(f) && s == CBM_OK) {
        re->why = "read error";
        s = CBM_E_IO;
    }
    fclose(f);
    if (s == CBM_OK && CBM_ARRAY_RESERVE(ctx, b, b.len + 1) != CBM_OK)
        s = CBM_E_NOMEM;
    const char *nul = s == CBM_OK && b.len ? memchr(b.data, 0, b.len) : NULL;
    if (nul) {
        re->line = re->col = 1;
        for (const char *q = b.data; q < nul; q++) {
            re->col = *q == '\n' ? 1 : re->col + 1;
            re->line += *q == '\n';
        }
        s = CBM_E_SYNTAX;
    }
    if (s != CBM_OK) {
        CBM_ARRAY_FREE(ctx, b);
        return s;
    }
    b.data[b.len] = 0;
    /* hand over exactly strlen+1 bytes so cbm__strfree can release it */
    char *d = copy_text(ctx, b.data, b.len);
    CBM_ARRAY_FREE(ctx, b);
    if (!d)
        return CBM_E_NOMEM;
    *out = d;
    return CBM_OK;
}

/* Whether path is inside the folder of the model (the first file) once links and ".." are
 * resolved: #include reads the model's own files, not any file of the machine. */
static bool include_allowed(const cbm__pp *pp, const char *path)
{
    char root[PATH_MAX], real[PATH_MAX], dir[PATH_MAX];
    const char *model = pp->files.data[0];
    const char *slash = strrchr(model, '/');
    if (!slash || !strcmp(model, "<model>"))
        snprintf(dir, sizeof dir, ".");
    else if (slash == model)
        snprintf(dir, sizeof dir, "/");
    else
        snprintf(dir, sizeof dir, "%.*s", (int)(slash - model), model);
    if (!realpath(dir, root) || !realpath(path, real))
        return false;
    size_t n = strlen(root);
    if (n == 1) /* the model is in / */
        return true;
    return !strncmp(real, root, n) && real[n] == '/';
}

static void emit_line(pp_state *st, const char *s, size_t n, int file, int line)
{
    cbm__pp *pp = st->pp;
    buf_append(st, (sbuf *)&pp->text, s, n);
    buf_append(st, (sbuf *)&pp->text, "\n", 1);
    cbm__pp_line l = {file, line, -1};
    if (st->used_define && st->status == CBM_OK) {
        /* errors on this line will say which -D it expands (kept with the file names) */
        const macro *m = st->used_define;
        size_t dn = strlen(m->name) + strlen(m->body) + 5;
        char *d = cbm__alloc(pp->ctx, dn);
        if (d)
            snprintf(d, dn, "-D %s=%s", m->name, m->body);
        if (!d || CBM_ARRAY_PUSH(pp->ctx, pp->files, d) != CBM_OK) {
            cbm__free(pp->ctx, d, dn);
            st->status = CBM_E_NOMEM;
        } else {
            l.define = (int)pp->files.len - 1;
        }
        st->used_define = NULL;
    }
    if (st->status == CBM_OK && CBM_ARRAY_PUSH(pp->ctx, pp->lines, l) != CBM_OK)
        st->status = CBM_E_NOMEM;
    if (st->status == CBM_E_LIMIT && !st->limit_reported)
        limit_error(st, file, line, 1, NULL);
}

static void process(pp_state *st, const char *src, int file);

static void include(pp_state *st, const char *arg, int file, int line)
{
    cbm_context *ctx = st->pp->ctx;
    while (*arg == ' ' || *arg == '\t')
        arg++;
    char close = *arg == '"' ? '"' : *arg == '<' ? '>' : 0;
    const char *e = close ? strchr(arg + 1, close) : NULL;
    if (!e) {
        pp_error(st, file, line, 1, "%s", "expected \"file\" after #include");
        return;
    }
    /* the built-in library of the L+C dialect and the C headers its models include */
    static const char *const BUILTIN[] = {
        "lpfgall.h", "lpfg.h",      "lsys.h", "math.h",       "cmath",  "stdlib.h", "stdio.h",
        "string.h",  "vectorlib.h", "V3f.h",  "quaternion.h", "vector", "memory.h", "stdmods.h"};
    for (size_t b = 0; b < sizeof BUILTIN / sizeof BUILTIN[0]; b++)
        if ((size_t)(e - arg - 1) == strlen(BUILTIN[b]) &&
            !strncmp(arg + 1, BUILTIN[b], strlen(BUILTIN[b]))) {
            st->pp->lpfg_lib = true;
            return;
        }
    if (st->include_depth >= 16) {
        pp_error(st, file, line, 1, "%s", "#include nested too deeply");
        return;
    }
    const char *cur = st->pp->files.data[file];
    const char *slash = strrchr(cur, '/');
    size_t dl = (arg[1] != '/' && slash) ? (size_t)(slash - cur + 1) : 0;
    size_t fl = (size_t)(e - arg - 1);
    char *path = cbm__alloc(ctx, dl + fl + 1);
    if (!path) {
        st->status = CBM_E_NOMEM;
        return;
    }
    memcpy(path, cur, dl);
    memcpy(path + dl, arg + 1, fl);
    path[dl + fl] = 0;
    char *text = NULL;
    read_err re;
    struct stat stt;
    cbm_status s = CBM_E_IO;
    if (stat(path, &stt) == 0 && !include_allowed(st->pp, path)) {
        pp_error(st, file, line, 1,
                 "#include \"%s\": outside the model's folder (a model includes its own files)",
                 path);
        cbm__strfree(ctx, path);
        return;
    }
    s = read_file(ctx, path, &text, &re);
    if (s != CBM_OK) {
        if (s == CBM_E_NOMEM)
            st->status = s;
        else if (s == CBM_E_SYNTAX)
            pp_error(st, file, line, 1, "included file '%s' has a NUL byte at line %d, column %d",
                     path, re.line, re.col);
        else
            pp_error(st, file, line, 1, "cannot read included file '%s': %s", path, re.why);
        cbm__strfree(ctx, path);
        return;
    }
    if (CBM_ARRAY_PUSH(ctx, st->pp->files, path) != CBM_OK) {
        cbm__strfree(ctx, path);
        cbm__strfree(ctx, text);
        st->status = CBM_E_NOMEM;
        return;
    }
    st->include_depth++;
    process(st, text, (int)st->pp->files.len - 1);
    st->include_depth--;
    cbm__strfree(ctx, text);
}

static void process(pp_state *st, const char *raw, int file)
{
    cbm_context *ctx = st->pp->ctx;
    char *src = NULL;
    size_t src_size = 0;
    int open_line, open_col;
    if (strip_comments(ctx, raw, &src, &src_size, &open_line, &open_col) != CBM_OK) {
        st->status = CBM_E_NOMEM;
        return;
    }
    if (open_line)
        pp_error(st, file, open_line, open_col, "%s", "unterminated comment: '/*' without '*/'");
    /* conditional stack: each level is "taking lines" or not */
    bool take[64];
    bool seen_else[64];
    int level = 0;
    take[0] = true;
    int line = 1;
    const char *p = src;
    sbuf logical = {0};
    while (*p && st->status == CBM_OK) {
        /* one logical line, joining backslash continuations */
        logical.len = 0;
        int first = line, extra = 0;
        for (;;) {
            const char *e = strchr(p, '\n');
            size_t n = e ? (size_t)(e - p) : strlen(p);
            bool cont = n > 0 && p[n - 1] == '\\';
            buf_append(st, &logical, p, cont ? n - 1 : n);
            p += n + (e ? 1 : 0);
            if (!cont || !*p)
                break;
            extra++;
        }
        if (!logical.data)
            buf_append(st, &logical, "", 0);
        if (st->status != CBM_OK)
            break;
        line = first + extra + 1;
        const char *q = logical.data;
        while (*q == ' ' || *q == '\t')
            q++;
        bool active = take[level];
        if (*q == '#') {
            q++;
            while (*q == ' ' || *q == '\t')
                q++;
            const char *d = q;
            while (isalpha((unsigned char)*q))
                q++;
            size_t dn = (size_t)(q - d);
#define IS(w) (dn == strlen(w) && !memcmp(d, w, dn))
            if (IS("ifdef") || IS("ifndef") || IS("if")) {
                bool v = false;
                while (*q == ' ' || *q == '\t')
                    q++;
                if (IS("if")) {
                    sbuf ex = {0};
                    expand(st, q, strlen(q), &ex, 0, file, first);
                    char *endp = NULL;
                    long val = ex.data ? strtol(ex.data, &endp, 0) : 0;
                    if (!ex.data || endp == ex.data)
                        pp_error(st, file, first, 1, "%s", "#if expects an integer constant");
                    v = val != 0;
                    CBM_ARRAY_FREE(ctx, ex);
                } else {
                    const char *a = q;
                    while (is_id((unsigned char)*q))
                        q++;
                    macro *m = find_macro(st, a, (size_t)(q - a));
                    if (m)
                        m->known = true;
                    v = m != NULL;
                    if (IS("ifndef"))
                        v = !v;
                }
                if (level >= 63) {
                    pp_error(st, file, first, 1, "%s", "conditionals nested too deeply");
                } else {
                    level++;
                    take[level] = active && v;
                    seen_else[level] = false;
                }
            } else if (IS("else")) {
                if (level == 0 || seen_else[level])
                    pp_error(st, file, first, 1, "%s", "#else without #if");
                else {
                    seen_else[level] = true;
                    take[level] = take[level - 1] && !take[level];
                }
            } else if (IS("endif")) {
                if (level == 0)
                    pp_error(st, file, first, 1, "%s", "#endif without #if");
                else
                    level--;
            } else if (!active) {
            } else if (IS("define")) {
                define(st, q, false, file, first);
            } else if (IS("undef")) {
                while (*q == ' ' || *q == '\t')
                    q++;
                const char *a = q;
                while (is_id((unsigned char)*q))
                    q++;
                macro *m = find_macro(st, a, (size_t)(q - a));
                if (m)
                    m->known = true;
                if (m && !m->locked) {
                    free_macro(ctx, m);
                    *m = st->macros.data[--st->macros.len];
                }
            } else if (IS("include")) {
                emit_line(st, "", 0, file, first);
                include(st, q, file, first);
                for (int k = 0; k < extra; k++)
                    emit_line(st, "", 0, file, first + k + 1);
                continue;
            } else if (dn == 0 || isdigit((unsigned char)*d)) {
                /* "# 12 file" line markers and empty directives are ignored */
            } else {
                pp_error(st, file, first, (int)(d - logical.data) + 1, "unknown directive '#%s'",
                         dn < 20 ? d : "?");
            }
#undef IS
            emit_line(st, "", 0, file, first);
        } else if (active) {
            sbuf ex = {0};
            buf_append(st, &ex, "", 0);
            expand(st, logical.data, logical.len, &ex, 0, file, first);
            emit_line(st, ex.data ? ex.data : "", ex.len, file, first);
            CBM_ARRAY_FREE(ctx, ex);
        } else {
            emit_line(st, "", 0, file, first);
        }
        for (int k = 0; k < extra; k++)
            emit_line(st, "", 0, file, first + k + 1);
    }
    if (level != 0 && st->status == CBM_OK)
        pp_error(st, file, line, 1, "%s", "missing #endif");
    CBM_ARRAY_FREE(ctx, logical);
    cbm__free(ctx, src, src_size);
}

cbm_status cbm__pp_run(cbm_context *ctx, const char *path, const char *text,
                       const char *const *defines, size_t ndefines, cbm__pp *pp)
{
    memset(pp, 0, sizeof *pp);
    pp->ctx = ctx;
    pp_state st = {.pp = pp, .status = CBM_OK};
    char *name = cbm__strdup(ctx, path ? path : "<model>");
    if (!name || CBM_ARRAY_PUSH(ctx, pp->files, name) != CBM_OK) {
        cbm__strfree(ctx, name);
        cbm__pp_free(pp);
        return CBM_E_NOMEM;
    }
    for (size_t i = 0; i < ndefines && st.status == CBM_OK; i++) {
        /* NAME=VALUE -> "NAME VALUE" */
        const char *eq = strchr(defines[i], '=');
        size_t n = strlen(defines[i]);
        char *d = cbm__alloc(ctx, n + 3);
        if (!d) {
            st.status = CBM_E_NOMEM;
            break;
        }
        if (eq) {
            memcpy(d, defines[i], n + 1);
            d[eq - defines[i]] = ' ';
        } else {
            memcpy(d, defines[i], n);
            memcpy(d + n, " 1", 3);
        }
        define(&st, d, true, 0, 0);
        cbm__free(ctx, d, n + 3);
    }
    char *owned = NULL;
    if (st.status == CBM_OK && !text) {
        read_err re;
        cbm_status s = read_file(ctx, path, &owned, &re);
        if (s != CBM_OK) {
            for (size_t i = 0; i < st.macros.len; i++)
                free_macro(ctx, &st.macros.data[i]);
            CBM_ARRAY_FREE(ctx, st.macros);
            if (s == CBM_E_SYNTAX)
                cbm__diag(ctx, CBM_ERROR, path, re.line, re.col,
                          "a NUL byte (the model is a text file)");
            cbm__pp_free(pp);
            if (s == CBM_E_IO)
                return cbm__fail(ctx, s, "%s: cannot read the model file: %s", path, re.why);
            return s;
        }
        text = owned;
    }
    if (st.status == CBM_OK)
        process(&st, text, 0);
    /* a -D name the model never defines, tests nor uses is a mistake (a misspelt parameter
     * would otherwise be ignored silently) */
    for (size_t i = 0; i < st.macros.len && st.status == CBM_OK; i++)
        if (st.macros.data[i].locked && !st.macros.data[i].known)
            pp_error(&st, 0, 0, 0, "-D %s: the model does not define %s", st.macros.data[i].name,
                     st.macros.data[i].name);
    cbm__strfree(ctx, owned);
    for (size_t i = 0; i < st.macros.len; i++)
        free_macro(ctx, &st.macros.data[i]);
    CBM_ARRAY_FREE(ctx, st.macros);
    if (st.status == CBM_OK && !pp->text.data)
        buf_append(&st, (sbuf *)&pp->text, "", 0);
    if (st.status != CBM_OK) {
        cbm__pp_free(pp);
        return st.status;
    }
    return CBM_OK;
}

void cbm__pp_free(cbm__pp *pp)
{
    for (size_t i = 0; i < pp->files.len; i++)
        cbm__strfree(pp->ctx, pp->files.data[i]);
    CBM_ARRAY_FREE(pp->ctx, pp->files);
    CBM_ARRAY_FREE(pp->ctx, pp->text);
    CBM_ARRAY_FREE(pp->ctx, pp->lines);
}
