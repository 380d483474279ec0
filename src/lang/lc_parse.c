/* The L+C dialect's front end: lexing, declarations (types, structs, modules, globals,
 * functions), typed expressions and statements, productions and the sections of the file,
 * compiled into an lc_model (lang/lc.h). Every expression is type-checked and coerced here,
 * so the evaluator never looks at a type it has not been told. */
#include "lang/lc.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* ---- compiler state ---- */
typedef struct lc_local {
    const char *name;
    size_t len;
    int type, slot;
} lc_local;

typedef struct lc_parser {
    lc_model *model;    /* what the parser builds */
    cbm__compiler *cur; /* the cursor: position, line and messages (lang/compiler.c) */
    const char *text;   /* the model's text */
    CBM_ARRAY(lc_local) vars;
    int frame_size; /* the doubles of the locals in scope */
    int frame_max;  /* the most of them at once: the frame of the body or function */
    int ret_type;   /* in a function */
    bool in_prod;   /* produce allowed */
    int in_switch;
    int depth;
} lc_parser;

static const char *const TURTLE[][3] = {
    /* lpfg name, cpfg symbol, parameter types ("f" float, "i" int, "" none) */
    {"F", "F", "f"},           {"f", "f", "f"},
    {"G", "G", "f"},           {"g", "g", "f"},
    {"Left", "+", "f"},        {"Right", "-", "f"},
    {"Up", "^", "f"},          {"Down", "&", "f"},
    {"RollL", "\\", "f"},      {"RollR", "/", "f"},
    {"TurnAround", "|", ""},   {"SB", "[", ""},
    {"EB", "]", ""},           {"SetWidth", "!", "f"},
    {"IncColor", "'", ""},     {"DecColor", ",", ""},
    {"SetColor", "", "i"},     {"Cut", "%", ""},
    {"SP", "{", ""},           {"EP", "}", ""},
    {"PP", ".", ""},           {"Sphere", "", "f"},
    {"Sphere0", "", ""},       {"Circle", "", "f"},
    {"Circle0", "", ""},       {"Surface", "", "if"},
    {"StartGC", "", ""},       {"PointGC", "", ""},
    {"EndGC", "", ""},         {"SetHead", "", "ffffff"},
    {"RollToVert", "", ""},    {"ScaleContour", "", "ff"},
    {"LineRel3d", "", "v"},    {"LineTo3d", "", "v"},
    {"MoveRel3d", "", "v"},    {"MoveTo3d", "", "v"},
    {"Label", "", "i"},        {"IncWidth", "#", ""},
    {"DecWidth", "", ""},      {"CurrentContour", "", "i"},
    {"SetTropism", "", "fff"}, {"Elasticity", "", "f"},
    {"ContourSides", "", "i"},
};

/* ---------------------------------------------------------------- lexing */
static void skip(lc_parser *L)
{
    const char *t = L->text;
    size_t p = L->cur->pos;
    while (t[p] && isspace((unsigned char)t[p]))
        p++;
    L->cur->pos = p;
}

static bool peek(lc_parser *L, const char *s)
{
    skip(L);
    return !strncmp(L->text + L->cur->pos, s, strlen(s));
}

static bool accept(lc_parser *L, const char *s)
{
    if (!peek(L, s))
        return false;
    L->cur->pos += strlen(s);
    return true;
}

static bool is_ident_start(int ch)
{
    return isalpha(ch) || ch == '_';
}

static bool is_ident_char(int ch)
{
    return isalnum(ch) || ch == '_';
}

/* identifier at the position (not consumed): its length, 0 if none */
static size_t ident(lc_parser *L)
{
    skip(L);
    const char *s = L->text + L->cur->pos;
    if (!is_ident_start((unsigned char)s[0]))
        return 0;
    size_t n = 1;
    while (is_ident_char((unsigned char)s[n]))
        n++;
    return n;
}

static bool accept_kw(lc_parser *L, const char *kw)
{
    size_t n = ident(L);
    if (n != strlen(kw) || strncmp(L->text + L->cur->pos, kw, n))
        return false;
    L->cur->pos += n;
    return true;
}

static void describe(lc_parser *L, char *buf, size_t n)
{
    const char *s = L->text + L->cur->pos;
    if (!*s) {
        snprintf(buf, n, "end of file");
        return;
    }
    size_t k = ident(L);
    if (k)
        snprintf(buf, n, "'%.*s'", (int)(k > 40 ? 40 : k), s);
    else
        snprintf(buf, n, "'%c'", *s);
}

static bool fatal(lc_parser *L)
{
    return L->cur->fatal || (L->cur->status != CBM_OK && L->cur->status != CBM_E_SYNTAX);
}

static void expected(lc_parser *L, const char *what)
{
    char buf[64];
    skip(L);
    describe(L, buf, sizeof buf);
    size_t pos = L->cur->pos;
    while (pos > 0 && !L->text[pos]) /* at the end: point at the last character */
        pos--;
    cbm__cerr(L->cur, pos, "expected %s, found %s", what, buf);
}

static bool expect(lc_parser *L, const char *s)
{
    if (accept(L, s))
        return true;
    char what[16];
    snprintf(what, sizeof what, "'%s'", s);
    expected(L, what);
    return false;
}

/* Skips to after the next `;` or the end of the next balanced `{...}` at this level. */
static void recover(lc_parser *L)
{
    const char *t = L->text;
    size_t p = L->cur->pos;
    int level = 0;
    while (t[p]) {
        char ch = t[p++];
        if (ch == '{' || ch == '(')
            level++;
        else if (ch == '}' || ch == ')') {
            if (--level <= 0 && ch == '}')
                break;
            if (level < 0)
                level = 0;
        } else if (ch == ';' && level == 0)
            break;
    }
    L->cur->pos = p;
}

/* Statement-level recovery: skips to after the next `;` or balanced block, but stops before a
 * `}` that closes the enclosing block. */
static void recover_stmt(lc_parser *L)
{
    const char *t = L->text;
    size_t p = L->cur->pos;
    int level = 0;
    while (t[p]) {
        char ch = t[p];
        if (ch == '}' && level == 0)
            break;
        p++;
        if (ch == '{' || ch == '(')
            level++;
        else if (ch == '}' || ch == ')') {
            if (level > 0)
                level--;
            if (level == 0 && ch == '}')
                break;
        } else if (ch == ';' && level == 0)
            break;
    }
    L->cur->pos = p;
}

/* ---------------------------------------------------------------- tables */
static int find_type(lc_parser *L, const char *s, size_t n)
{
    for (size_t i = 1; i < L->model->types.len; i++) {
        const char *nm = L->model->types.data[i].name;
        if (strlen(nm) == n && !strncmp(nm, s, n))
            return (int)i;
    }
    if (n == 6 && !strncmp(s, "double", 6))
        return T_DOUBLE;
    return -1;
}

static int find_mod(const lc_model *lp, const char *s, size_t n)
{
    for (size_t i = 0; i < lp->mods.len; i++) {
        const char *nm = lp->mods.data[i].name;
        if (strlen(nm) == n && !strncmp(nm, s, n))
            return (int)i;
    }
    return -1;
}

static cbm_status add_type(lc_model *lp, cbm_context *ctx, const char *name, int size)
{
    lc_type t;
    memset(&t, 0, sizeof t);
    t.name = cbm__strdup(ctx, name);
    t.size = size;
    if (!t.name)
        return CBM_E_NOMEM;
    if (CBM_ARRAY_PUSH(ctx, lp->types, t) != CBM_OK) {
        cbm__strfree(ctx, t.name);
        return CBM_E_NOMEM;
    }
    return CBM_OK;
}

/* Allocates a symbol code for a module name: its cpfg turtle character, its own character for
 * one-character names, else a free code. */
static int alloc_code(lc_model *lp, const char *name, const char *want)
{
    if (want && want[0] && lp->bycode[(unsigned char)want[0]] < 0)
        return (unsigned char)want[0];
    static const char RESERVED[] = "FfGg+-^&\\/|[]!';%{}.#@~?$";
    if (!name[1] && isalnum((unsigned char)name[0]) && !strchr(RESERVED, name[0]) &&
        lp->bycode[(unsigned char)name[0]] < 0)
        return (unsigned char)name[0];
    for (int pass = 0; pass < 2; pass++)
        for (int c = pass ? 1 : 33; c < (pass ? 33 : 127); c++)
            if (lp->bycode[c] < 0 && !strchr(RESERVED, c) && !(c == ' ') &&
                !(isalnum(c) && lp->mods.len < 40))
                return c;
    for (int c = 1; c < 127; c++)
        if (lp->bycode[c] < 0)
            return c;
    return -1;
}

static int add_mod(lc_parser *L, const char *name, size_t len, const int *ptypes, int np,
                   const char *want, size_t pos)
{
    lc_model *lp = L->model;
    lc_module m;
    memset(&m, 0, sizeof m);
    int code = alloc_code(lp, len == 1 ? (char[2]){name[0], 0} : "xx", want);
    if (code < 0) {
        cbm__cerr(L->cur, pos, "too many module types (at most 126)");
        return -1;
    }
    m.name = cbm__alloc(L->cur->ctx, len + 1);
    if (!m.name) {
        L->cur->status = CBM_E_NOMEM;
        L->cur->fatal = true;
        return -1;
    }
    memcpy(m.name, name, len);
    m.name[len] = 0;
    m.code = (uint8_t)code;
    m.nparams = np;
    for (int i = 0; i < np; i++) {
        m.ptype[i] = ptypes[i];
        m.size += lc_type_size(lp, ptypes[i]);
    }
    if (m.size > MAXSZ) {
        cbm__cerr(L->cur, pos, "module '%s' has more than %d scalar parameters", m.name, MAXSZ);
        m.size = MAXSZ;
    }
    if (CBM_ARRAY_PUSH(L->cur->ctx, lp->mods, m) != CBM_OK) {
        cbm__strfree(L->cur->ctx, m.name);
        L->cur->status = CBM_E_NOMEM;
        L->cur->fatal = true;
        return -1;
    }
    lp->bycode[code] = (int16_t)(lp->mods.len - 1);
    return (int)lp->mods.len - 1;
}

static int32_t add_node(lc_parser *L, lc_node n)
{
    if (fatal(L))
        return -1;
    n.pos = (int32_t)(L->cur->pos < INT32_MAX ? L->cur->pos : INT32_MAX);
    if (CBM_ARRAY_PUSH(L->cur->ctx, L->model->nodes, n) != CBM_OK) {
        L->cur->status = CBM_E_NOMEM;
        L->cur->fatal = true;
        return -1;
    }
    return (int32_t)L->model->nodes.len - 1;
}

static lc_node blank_node(int op, int type)
{
    lc_node n;
    memset(&n, 0, sizeof n);
    n.op = (uint8_t)op;
    n.type = (int16_t)type;
    n.child1 = n.child2 = n.child3 = n.child4 = n.next = -1;
    return n;
}

#define ND(i) (L->model->nodes.data[i])

/* Appends node e to the chain first..last (linked through `next`). */
static void chain(lc_parser *L, int32_t *first, int32_t *last, int32_t e)
{
    if (*last >= 0)
        ND(*last).next = e;
    else
        *first = e;
    *last = e;
}

/* ---------------------------------------------------------------- types in declarations */
/* Parses a type name (with optional `const`/`struct`); -1 if there is none (nothing consumed) */
static int parse_type(lc_parser *L)
{
    size_t save = L->cur->pos;
    accept_kw(L, "const");
    accept_kw(L, "struct");
    size_t n = ident(L);
    if (n) {
        int t = find_type(L, L->text + L->cur->pos, n);
        if (t >= 0) {
            L->cur->pos += n;
            return t;
        }
    }
    L->cur->pos = save;
    return -1;
}

static int declare_local(lc_parser *L, const char *name, size_t len, int type)
{
    lc_local v = {name, len, type, L->frame_size};
    L->frame_size += lc_type_size(L->model, type);
    if (L->frame_size > L->frame_max)
        L->frame_max = L->frame_size;
    if (CBM_ARRAY_PUSH(L->cur->ctx, L->vars, v) != CBM_OK) {
        L->cur->status = CBM_E_NOMEM;
        L->cur->fatal = true;
    }
    return v.slot;
}

/* ---------------------------------------------------------------- expressions */
static int32_t expr(lc_parser *L);
static int32_t comma_expr(lc_parser *L);
static int32_t assign_expr(lc_parser *L);

static int32_t num_node(lc_parser *L, double v, int type)
{
    lc_node n = blank_node(N_NUM, type);
    n.value = v;
    return add_node(L, n);
}

/* Converts expression e to type t (implicit conversion), reporting a mismatch at pos. */
static int32_t coerce(lc_parser *L, int32_t e, int t, size_t pos)
{
    if (e < 0)
        return -1;
    int et = ND(e).type;
    if (et == t)
        return e;
    if (lc_is_scalar(et) && lc_is_scalar(t)) {
        lc_node n = blank_node(N_CAST, t);
        n.child1 = e;
        return add_node(L, n);
    }
    if (lc_is_vec(et) && lc_is_vec(t)) {
        lc_node n = blank_node(N_CAST, t);
        n.child1 = e;
        return add_node(L, n);
    }
    cbm__cerr(L->cur, pos, "cannot convert %s to %s", L->model->types.data[et].name,
              L->model->types.data[t].name);
    return -1;
}

/* Parses `(args)` after a callee at '(' into a chain; returns count (-1 on error). */
static int parse_args(lc_parser *L, int32_t *first)
{
    *first = -1;
    int32_t last = -1;
    int n = 0;
    if (!expect(L, "("))
        return -1;
    if (accept(L, ")"))
        return 0;
    do {
        skip(L);
        size_t start = L->cur->pos;
        int32_t e = assign_expr(L);
        if (e < 0)
            return -1;
        /* the argument's position is its first character (a produced parameter that is not
         * finite is named there), not where its parse ended */
        ND(e).pos = (int32_t)(start < INT32_MAX ? start : INT32_MAX);
        chain(L, first, &last, e);
        n++;
    } while (accept(L, ","));
    if (!expect(L, ")"))
        return -1;
    return n;
}

/* printf(format, args...): the format is a string literal checked against its arguments, which
 * are numbers or string literals (for %s). */
static int32_t printf_call(lc_parser *L, size_t pos)
{
    cbm__compiler *c = L->cur;
    if (!expect(L, "("))
        return -1;
    skip(L);
    size_t fmt;
    if (L->text[c->pos] != '"') {
        cbm__cerr(c, pos, "printf needs a format string as its first argument");
        return -1;
    }
    if (!cbm__string_lit(c, &fmt))
        return -1;
    uint8_t kinds[CBM__FMT_MAX_ARGS];
    char err[128];
    int nconv = cbm__fmt_scan(c->strings.data + fmt, kinds, CBM__FMT_MAX_ARGS, err, sizeof err);
    if (nconv < 0) {
        cbm__cerr(c, pos, "%s", err);
        return -1;
    }
    int32_t first = -1, last = -1;
    int n = 0;
    while (accept(L, ",")) {
        skip(L);
        size_t apos = c->pos;
        int32_t e;
        bool str = L->text[c->pos] == '"';
        if (str) {
            size_t off;
            if (!cbm__string_lit(c, &off))
                return -1;
            lc_node x = blank_node(N_STR, T_VOID);
            x.slot = (int32_t)off;
            e = add_node(L, x);
        } else {
            e = assign_expr(L);
        }
        if (e < 0)
            return -1;
        if (!str && !lc_is_scalar(ND(e).type)) {
            cbm__cerr(
                c, apos,
                "printf: argument %d is not a number (print a vector or struct by its fields)",
                n + 2);
            return -1;
        }
        if (n < nconv && str != (kinds[n] == CBM__FMT_STR)) {
            cbm__cerr(c, apos, "printf: argument %d %s", n + 2,
                      str ? "is a string; only %s prints a string"
                          : "of %s must be a string literal");
            return -1;
        }
        chain(L, &first, &last, e);
        n++;
    }
    if (!expect(L, ")"))
        return -1;
    if (n != nconv) {
        cbm__cerr(c, pos, "printf: the format has %d conversion%s, %d argument%s given", nconv,
                  nconv == 1 ? "" : "s", n, n == 1 ? "" : "s");
        return -1;
    }
    lc_node x = blank_node(N_CALLB, T_INT);
    x.fn = FN_PRINTF;
    x.slot = (int32_t)fmt;
    x.child1 = first;
    return add_node(L, x);
}

/* brace initializer `{a, b, ...}` for a value of type t */
static int32_t brace_init(lc_parser *L, int t)
{
    size_t pos = L->cur->pos;
    if (!expect(L, "{"))
        return -1;
    const lc_type *ty = &L->model->types.data[t];
    int nf = lc_is_vec(t) ? 3 : ty->nfields;
    if (lc_is_scalar(t)) {
        int32_t e = coerce(L, assign_expr(L), t, pos);
        expect(L, "}");
        return e;
    }
    int32_t first = -1, last = -1;
    for (int f = 0; f < nf; f++) {
        if (f && !expect(L, ","))
            return -1;
        int ft = lc_is_vec(t) ? (t == T_V3F ? T_FLOAT : T_DOUBLE) : ty->ftype[f];
        size_t p = L->cur->pos;
        int32_t e = peek(L, "{") ? brace_init(L, ft) : coerce(L, assign_expr(L), ft, p);
        if (e < 0)
            return -1;
        chain(L, &first, &last, e);
    }
    if (!expect(L, "}"))
        return -1;
    lc_node n = blank_node(N_CTOR, t);
    n.child1 = first;
    return add_node(L, n);
}

static lc_local *find_var(lc_parser *L, const char *s, size_t n)
{
    for (size_t i = L->vars.len; i-- > 0;)
        if (L->vars.data[i].len == n && !strncmp(L->vars.data[i].name, s, n))
            return &L->vars.data[i];
    return NULL;
}

static lc_global *find_gvar(lc_parser *L, const char *s, size_t n)
{
    for (size_t i = 0; i < L->model->gvars.len; i++) {
        lc_global *g = &L->model->gvars.data[i];
        if (strlen(g->name) == n && !strncmp(g->name, s, n))
            return g;
    }
    return NULL;
}

static int pattern(lc_parser *L, lc_pattern *p, bool declare);
static bool is_lvalue(lc_parser *L, int32_t e);

static int32_t call_expr(lc_parser *L, const char *s, size_t n, size_t pos)
{
    lc_model *lp = L->model;
    /* In*Context(pattern) */
    static const char *const CTXF[] = {"InLeftContext", "InNewLeftContext", "InNewRightContext",
                                       "InRightContext"};
    for (int k = 0; k < LC_CTX_N; k++)
        if (strlen(CTXF[k]) == n && !strncmp(s, CTXF[k], n)) {
            lc_pattern p = {0, 0};
            if (!expect(L, "("))
                return -1;
            if (pattern(L, &p, false) < 0)
                return -1;
            if (!expect(L, ")"))
                return -1;
            if (!L->in_prod) {
                cbm__cerr(L->cur, pos, "%s is only allowed in a production", CTXF[k]);
                return -1;
            }
            lc_node x = blank_node(N_INCTX, T_BOOL);
            x.fn = (uint8_t)k;
            x.child1 = p.first;
            x.child2 = p.n;
            return add_node(L, x);
        }
    /* vector and struct constructors */
    int t = find_type(L, s, n);
    if (t >= 0) {
        int32_t args;
        int na = parse_args(L, &args);
        if (na < 0)
            return -1;
        if (lc_is_scalar(t) && na == 1)
            return coerce(L, args, t, pos);
        if (lc_is_vec(t) && (na == 3 || na == 0)) {
            int ft = t == T_V3F ? T_FLOAT : T_DOUBLE;
            int32_t first = -1, last = -1;
            for (int i = 0; i < 3; i++) {
                int32_t e;
                if (na == 0)
                    e = num_node(L, 0, ft);
                else {
                    e = args;
                    args = ND(args).next;
                    ND(e).next = -1;
                    e = coerce(L, e, ft, pos);
                }
                if (e < 0)
                    return -1;
                chain(L, &first, &last, e);
            }
            lc_node x = blank_node(N_CTOR, t);
            x.child1 = first;
            return add_node(L, x);
        }
        if (lp->types.data[t].nfields > 0 && na == 0) { /* Name(): a zero value */
            lc_node x = blank_node(N_CTOR, t);
            return add_node(L, x);
        }
        if (lp->types.data[t].nfields > 0 &&
            na == lp->types.data[t].nfields) { /* Name(f1, f2, ...) */
            int32_t first = -1, last = -1;
            for (int i = 0; i < na; i++) {
                int32_t e = args;
                args = ND(args).next;
                ND(e).next = -1;
                e = coerce(L, e, lp->types.data[t].ftype[i], pos);
                if (e < 0)
                    return -1;
                chain(L, &first, &last, e);
            }
            lc_node x = blank_node(N_CTOR, t);
            x.child1 = first;
            return add_node(L, x);
        }
        cbm__cerr(L->cur, pos, "wrong number of arguments to %s()", lp->types.data[t].name);
        return -1;
    }
    if (n == 4 && !strncmp(s, "func", 4)) { /* func(name, x) */
        if (!expect(L, "("))
            return -1;
        size_t k = ident(L);
        if (!k) {
            expected(L, "a function name");
            return -1;
        }
        const char *fname = L->text + L->cur->pos;
        L->cur->pos += k;
        size_t id = 0;
        for (; id < lp->funcnames.len; id++)
            if (strlen(lp->funcnames.data[id]) == k && !strncmp(lp->funcnames.data[id], fname, k))
                break;
        if (id == lp->funcnames.len) {
            char *nm = cbm__alloc(L->cur->ctx, k + 1);
            if (!nm || CBM_ARRAY_PUSH(L->cur->ctx, lp->funcnames, nm) != CBM_OK) {
                if (nm)
                    cbm__free(L->cur->ctx, nm, k + 1);
                L->cur->status = CBM_E_NOMEM;
                L->cur->fatal = true;
                return -1;
            }
            memcpy(nm, fname, k);
            nm[k] = 0;
        }
        if (!expect(L, ","))
            return -1;
        int32_t x = coerce(L, assign_expr(L), T_DOUBLE, L->cur->pos);
        if (x < 0 || !expect(L, ")"))
            return -1;
        lc_node c = blank_node(N_CALLB, T_DOUBLE);
        c.fn = FN_FUNC;
        c.child1 = x;
        c.slot = (int32_t)id + 1;
        return add_node(L, c);
    }
    for (size_t i = 0; i < lp->funcs.len; i++) {
        lc_function *f = &lp->funcs.data[i];
        if (strlen(f->name) != n || strncmp(f->name, s, n))
            continue;
        int32_t args;
        int na = parse_args(L, &args);
        if (na < 0)
            return -1;
        if (na != f->nparams) {
            cbm__cerr(L->cur, pos, "%s() takes %d argument%s, %d given", f->name, f->nparams,
                      f->nparams == 1 ? "" : "s", na);
            return -1;
        }
        int32_t first = -1, last = -1;
        for (int a = 0; a < na; a++) {
            int32_t e = args;
            args = ND(e).next;
            ND(e).next = -1;
            if (f->pref[a] && (!is_lvalue(L, e) || ND(e).type != f->ptype[a])) {
                cbm__cerr(L->cur, pos, "argument %d of %s() must be a variable of type %s", a + 1,
                          f->name, lp->types.data[f->ptype[a]].name);
                return -1;
            }
            e = coerce(L, e, f->ptype[a], pos);
            if (e < 0)
                return -1;
            chain(L, &first, &last, e);
        }
        lc_node c = blank_node(N_CALLU, f->ret_type);
        c.child1 = first;
        c.slot = (int32_t)i;
        return add_node(L, c);
    }
    const cbm__builtin *b = cbm__builtin_find(s, n, CBM__LC);
    if (b) {
        int32_t args = -1;
        int na;
        if (b->fn == FN_PRINTF)
            return printf_call(L, pos);
        na = parse_args(L, &args);
        if (na < 0)
            return -1;
        if (b->arity >= 0 && na != b->arity) {
            cbm__cerr(L->cur, pos, "%s() takes %d argument%s, %d given", b->name, b->arity,
                      b->arity == 1 ? "" : "s", na);
            return -1;
        }
        int rt = T_DOUBLE;
        if (b->fn == FN_TOLOCAL || b->fn == FN_TOWORLD) {
            int t0 = ND(args).type, t1 = ND(ND(args).next).type;
            if (t1 != T_TVEC || (b->fn == FN_TOLOCAL ? !lc_is_vec(t0) : t0 != T_LOCVEC)) {
                cbm__cerr(L->cur, pos, "%s() takes a %s and a TurtleVec", b->name,
                          b->fn == FN_TOLOCAL ? "vector" : "LocVec");
                return -1;
            }
            rt = b->fn == FN_TOLOCAL ? T_LOCVEC : T_V3F;
        } else if (b->fn == FN_DOT || b->fn == FN_CROSS || b->fn == FN_MAKEQ ||
                   b->fn == FN_VECROT) {
            int t0 = ND(args).type, t1 = ND(ND(args).next).type;
            bool ok = lc_is_vec(t1);
            if (b->fn == FN_VECROT) {
                ok = ok && (lc_is_vec(t0) || t0 == T_TVEC) &&
                     lc_is_scalar(ND(ND(ND(args).next).next).type);
                rt = t0;
            } else if (b->fn == FN_MAKEQ) {
                ok = lc_is_vec(t0) && lc_is_scalar(t1);
                rt = T_QUAT;
            } else {
                ok = ok && lc_is_vec(t0);
                rt = b->fn == FN_DOT ? (t0 == T_V3D || t1 == T_V3D ? T_DOUBLE : T_FLOAT)
                                     : (t0 == T_V3D || t1 == T_V3D ? T_V3D : T_V3F);
            }
            if (!ok) {
                cbm__cerr(L->cur, pos, "invalid arguments to %s()%s", b->name,
                          b->fn == FN_VECROT ? " (a vector or TurtleVec, an axis, an angle)" : "");
                return -1;
            }
        } else if (b->fn == FN_LENGTH || b->fn == FN_NORMALIZE) {
            int at = ND(args).type;
            if (!lc_is_vec(at) && !(b->fn == FN_NORMALIZE && at == T_TVEC)) {
                cbm__cerr(L->cur, pos, "%s() needs a vector", b->name);
                return -1;
            }
            rt = b->fn == FN_NORMALIZE ? at : (at == T_V3F ? T_FLOAT : T_DOUBLE);
        } else {
            for (int32_t a = args; a >= 0; a = ND(a).next)
                if (!lc_is_scalar(ND(a).type)) {
                    cbm__cerr(L->cur, pos, "%s() needs numbers", b->name);
                    return -1;
                }
            if (b->fn >= FN_EQUILIBRIUM && b->fn <= FN_REACTIONBOUND && L->in_prod) {
                cbm__cerr(L->cur, pos,
                          "%s() changes the whole string: call it in Start, StartEach, EndEach "
                          "or End",
                          b->name);
                return -1;
            }
            if (b->fn == FN_FORWARD || b->fn == FN_BACKWARD || b->fn == FN_USEGROUP ||
                b->fn == FN_SRAND || b->fn == FN_STOP || b->fn == FN_AGEWOOD ||
                b->fn == FN_GRAVITY || b->fn == FN_GROUND || b->fn == FN_CONTACT ||
                b->fn == FN_TROPISM || b->fn == FN_PIPEMODEL || b->fn == FN_WOOD ||
                b->fn == FN_RINGRATE || b->fn == FN_SOLVER || b->fn == FN_SOLVERMETHOD ||
                b->fn == FN_REACTION || b->fn == FN_REACTIONBOUND || b->fn == FN_SWAYMODES ||
                b->fn == FN_APPROXLOAD || b->fn == FN_SOLVERTHREADS)
                rt = T_VOID;
            else if (b->fn == FN_EQUILIBRIUM || b->fn == FN_ADDRINGS || b->fn == FN_BREAK)
                rt = T_INT;
            else if (b->fn == FN_STABILITY || b->fn == FN_FREQUENCY || b->fn == FN_SWAY ||
                     b->fn == FN_LIGHT)
                rt = T_DOUBLE;
            else if (b->fn == FN_CURGROUP || b->fn == FN_RAND)
                rt = T_INT;
            else if ((b->fn == FN_MIN || b->fn == FN_MAX || b->fn == FN_FABS) && args >= 0)
                rt = b->arity == 2 ? lc_arith_type(ND(args).type, ND(ND(args).next).type)
                                   : (ND(args).type == T_BOOL ? T_INT : ND(args).type);
        }
        lc_node c = blank_node(N_CALLB, rt);
        c.fn = (uint8_t)b->fn;
        c.child1 = args;
        return add_node(L, c);
    }
    cbm__cerr(L->cur, pos, "unknown function '%.*s'", (int)n, s);
    return -1;
}

/* One more level of nesting (operators of a chain, ?:, assignments): false after reporting that
 * the limit is exceeded. Parsing and evaluation recurse once per level. */
static bool deeper(lc_parser *L)
{
    if (++L->depth > cbm_context_limits(L->cur->ctx)->max_expr_depth) {
        L->depth--;
        cbm__cerr(L->cur, L->cur->pos,
                  "expression or statement nested too deeply (limit %d, --max-expr-depth)",
                  cbm_context_limits(L->cur->ctx)->max_expr_depth);
        L->cur->fatal = true;
        return false;
    }
    return true;
}

static int32_t primary(lc_parser *L)
{
    skip(L);
    size_t pos = L->cur->pos;
    const char *s = L->text + pos;
    if (!deeper(L))
        return -1;
    int32_t r = -1;
    if (isdigit((unsigned char)s[0]) || (s[0] == '.' && isdigit((unsigned char)s[1]))) {
        char *end;
        double v = strtod(s, &end);
        bool isf = false;
        for (const char *q = s; q < end; q++)
            if (*q == '.' || *q == 'e' || *q == 'E')
                isf = true;
        int t = isf ? T_DOUBLE : T_INT;
        if (*end == 'f' || *end == 'F') {
            t = T_FLOAT;
            v = (float)v;
            end++;
        }
        L->cur->pos = (size_t)(end - L->text);
        r = num_node(L, v, t);
    } else if (s[0] == '(') {
        L->cur->pos++;
        size_t save = L->cur->pos;
        int t = parse_type(L);
        if (t >= 0 && accept(L, ")")) { /* cast */
            int32_t e = primary(L);
            if (e >= 0) {
                lc_node n = blank_node(N_CAST, t);
                n.child1 = e;
                if (!(lc_is_scalar(t) && lc_is_scalar(ND(e).type)) && ND(e).type != t) {
                    cbm__cerr(L->cur, pos, "invalid cast");
                    r = -1;
                } else
                    r = add_node(L, n);
            }
        } else {
            L->cur->pos = save;
            r = expr(L);
            if (r >= 0 && !expect(L, ")"))
                r = -1;
        }
    } else if (s[0] == '-' || s[0] == '!' || s[0] == '+') {
        L->cur->pos++;
        if (s[0] == '-' && s[1] == '-') {
            L->cur->pos++;
            int32_t e = primary(L);
            lc_node n = blank_node(N_INCDEC, e >= 0 ? ND(e).type : 0);
            n.child1 = e;
            n.fn = 1;
            r = e >= 0 ? add_node(L, n) : -1;
        } else if (s[0] == '+' && s[1] == '+') {
            L->cur->pos++;
            int32_t e = primary(L);
            lc_node n = blank_node(N_INCDEC, e >= 0 ? ND(e).type : 0);
            n.child1 = e;
            n.fn = 0;
            r = e >= 0 ? add_node(L, n) : -1;
        } else {
            int32_t e = primary(L);
            if (e >= 0 && s[0] == '+')
                r = e;
            else if (e >= 0) {
                int et = ND(e).type;
                if (s[0] == '!' && !lc_is_scalar(et))
                    cbm__cerr(L->cur, pos, "'!' needs a number");
                else if (s[0] == '-' && !lc_is_scalar(et) && !lc_is_vec(et))
                    cbm__cerr(L->cur, pos, "'-' needs a number or a vector");
                else {
                    lc_node n = blank_node(s[0] == '-' ? N_NEG : N_NOT,
                                           s[0] == '!' ? T_BOOL : (et == T_BOOL ? T_INT : et));
                    n.child1 = e;
                    r = add_node(L, n);
                }
            }
        }
        L->depth--;
        return r;
    } else if (is_ident_start((unsigned char)s[0])) {
        size_t n = ident(L);
        L->cur->pos += n;
        skip(L);
        if (n == 4 && !strncmp(s, "true", 4))
            r = num_node(L, 1, T_BOOL);
        else if (n == 5 && !strncmp(s, "false", 5))
            r = num_node(L, 0, T_BOOL);
        else if (n == 8 && !strncmp(s, "RAND_MAX", 8))
            r = num_node(L, 2147483647, T_INT);
        else if ((n == 4 && !strncmp(s, "M_PI", 4)))
            r = num_node(L, 3.14159265358979323846, T_DOUBLE);
        else if (L->text[L->cur->pos] == '(')
            r = call_expr(L, s, n, pos);
        else {
            lc_local *v = find_var(L, s, n);
            lc_global *g = v ? NULL : find_gvar(L, s, n);
            if (v) {
                lc_node x = blank_node(N_LOCAL, v->type);
                x.slot = v->slot;
                r = add_node(L, x);
            } else if (g) {
                lc_node x = blank_node(N_GLOBAL, g->type);
                x.slot = g->slot;
                r = add_node(L, x);
            } else
                cbm__cerr(L->cur, pos, "unknown name '%.*s'", (int)n, s);
        }
    } else {
        expected(L, "an expression");
    }
    /* postfix: .field, .method(), ++, -- */
    for (;;) {
        if (r < 0)
            break;
        skip(L);
        size_t p2 = L->cur->pos;
        if (L->text[p2] == '.' && !isdigit((unsigned char)L->text[p2 + 1])) {
            L->cur->pos++;
            size_t n = ident(L);
            const char *f = L->text + L->cur->pos;
            if (!n) {
                expected(L, "a field name");
                r = -1;
                break;
            }
            L->cur->pos += n;
            int t = ND(r).type;
            if (peek(L, "(") && lc_is_vec(t)) { /* v.Length(), v.Normalize() */
                int32_t none;
                if (parse_args(L, &none) != 0) {
                    r = -1;
                    break;
                }
                bool len =
                    (n == 6 && !strncmp(f, "Length", 6)) || (n == 9 && !strncmp(f, "Magnitude", 9));
                bool nor = (n == 9 && !strncmp(f, "Normalize", 9)) ||
                           (n == 10 && !strncmp(f, "Normalized", 10));
                if (!len && !nor) {
                    cbm__cerr(L->cur, p2, "unknown vector method '%.*s'", (int)n, f);
                    r = -1;
                    break;
                }
                lc_node c = blank_node(N_CALLB, len ? (t == T_V3F ? T_FLOAT : T_DOUBLE) : t);
                c.fn = (uint8_t)(len ? FN_LENGTH : FN_NORMALIZE);
                c.child1 = r;
                if (nor && n == 9 && (ND(r).op == N_LOCAL || ND(r).op == N_GLOBAL)) {
                    /* v.Normalize() normalizes v in place */
                    int32_t cn = add_node(L, c);
                    lc_node as = blank_node(N_ASSIGN, t);
                    lc_node lv = ND(r);
                    int32_t l2 = add_node(L, lv);
                    as.child1 = l2;
                    as.child2 = cn;
                    r = add_node(L, as);
                } else
                    r = add_node(L, c);
                continue;
            }
            int off = -1, ft = -1;
            if (lc_is_vec(t)) {
                if (n == 1 && (f[0] == 'x' || f[0] == 'y' || f[0] == 'z')) {
                    off = f[0] - 'x';
                    ft = t == T_V3F ? T_FLOAT : T_DOUBLE;
                }
            } else if (L->model->types.data[t].nfields > 0) {
                const lc_type *ty = &L->model->types.data[t];
                for (int k = 0; k < ty->nfields; k++)
                    if (strlen(ty->fname[k]) == n && !strncmp(ty->fname[k], f, n)) {
                        off = ty->foff[k];
                        ft = ty->ftype[k];
                    }
            }
            if (off < 0) {
                cbm__cerr(L->cur, p2, "no field '%.*s' in %s", (int)n, f,
                          L->model->types.data[t].name);
                r = -1;
                break;
            }
            if (ND(r).op == N_LOCAL || ND(r).op == N_GLOBAL) {
                ND(r).slot += off;
                ND(r).type = (int16_t)ft;
            } else {
                lc_node x = blank_node(N_FIELD, ft);
                x.child1 = r;
                x.slot = off;
                r = add_node(L, x);
            }
        } else if (!strncmp(L->text + p2, "++", 2) || !strncmp(L->text + p2, "--", 2)) {
            L->cur->pos += 2;
            lc_node x = blank_node(N_INCDEC, ND(r).type);
            x.child1 = r;
            x.fn = L->text[p2] == '+' ? 2 : 3;
            r = add_node(L, x);
        } else
            break;
    }
    L->depth--;
    return r;
}

typedef struct binop {
    const char *s;
    int prec, op;
} binop;

static const binop BINOPS[] = {{"||", 1, -2},   {"&&", 2, -1},   {"==", 3, B_EQ}, {"!=", 3, B_NE},
                               {"<=", 4, B_LE}, {">=", 4, B_GE}, {"<", 4, B_LT},  {">", 4, B_GT},
                               {"+", 5, B_ADD}, {"-", 5, B_SUB}, {"*", 6, B_MUL}, {"/", 6, B_DIV},
                               {"%", 6, B_REM}};

static const binop *peek_binop(lc_parser *L)
{
    skip(L);
    const char *s = L->text + L->cur->pos;
    for (size_t i = 0; i < sizeof BINOPS / sizeof BINOPS[0]; i++) {
        size_t n = strlen(BINOPS[i].s);
        if (strncmp(s, BINOPS[i].s, n))
            continue;
        /* not an assignment operator, not >>, <<, ++, -- */
        if (s[n] == '=' && n == 1 && !strchr("<>", s[0]))
            return NULL;
        if (n == 1 && (s[1] == s[0]) && strchr("<>+-", s[0]))
            return NULL;
        if ((s[0] == '<' || s[0] == '>') && n == 2 && s[1] == s[0])
            return NULL;
        return &BINOPS[i];
    }
    return NULL;
}

static int32_t binary(lc_parser *L, int32_t a, const binop *op, int32_t b, size_t pos)
{
    if (a < 0 || b < 0)
        return -1;
    int ta = ND(a).type, tb = ND(b).type;
    lc_node n = blank_node(N_BIN, 0);
    n.child1 = a;
    n.child2 = b;
    n.fn = (uint8_t)op->op;
    if (op->op < 0) {
        if (!lc_is_scalar(ta) || !lc_is_scalar(tb)) {
            cbm__cerr(L->cur, pos, "'%s' needs numbers", op->s);
            return -1;
        }
        n.op = op->op == -2 ? N_OR : N_AND;
        n.type = T_BOOL;
        return add_node(L, n);
    }
    if (lc_is_scalar(ta) && lc_is_scalar(tb)) {
        n.type = (int16_t)(op->op >= B_LT ? T_BOOL : lc_arith_type(ta, tb));
        if (op->op == B_REM && n.type != T_INT) {
            cbm__cerr(L->cur, pos, "'%%' needs integers (use fmod)");
            return -1;
        }
        return add_node(L, n);
    }
    int vt = lc_is_vec(ta) ? ta : tb;
    if (lc_is_vec(ta) && lc_is_vec(tb)) {
        vt = (ta == T_V3D || tb == T_V3D) ? T_V3D : T_V3F;
        if (op->op == B_ADD || op->op == B_SUB || op->op == B_REM) {
            n.type = (int16_t)vt;
            return add_node(L, n);
        }
        if (op->op == B_MUL) { /* dot product */
            n.type = vt == T_V3F ? T_FLOAT : T_DOUBLE;
            return add_node(L, n);
        }
    } else if (lc_is_vec(ta) && lc_is_scalar(tb) && (op->op == B_MUL || op->op == B_DIV)) {
        n.type = (int16_t)vt;
        return add_node(L, n);
    } else if (lc_is_scalar(ta) && lc_is_vec(tb) && op->op == B_MUL) {
        n.type = (int16_t)vt;
        return add_node(L, n);
    }
    if ((ta == T_LOCVEC || tb == T_LOCVEC) && op->op <= B_DIV &&
        (ta == tb || lc_is_scalar(ta) || lc_is_scalar(tb)) &&
        !(lc_is_scalar(ta) && op->op != B_MUL)) {
        n.type = T_LOCVEC; /* componentwise, numbers broadcast */
        return add_node(L, n);
    }
    if (ta == T_QUAT && op->op == B_MUL && (tb == T_QUAT || lc_is_vec(tb) || tb == T_TVEC)) {
        n.type = (int16_t)tb; /* composition, or rotation of a vector or a frame */
        return add_node(L, n);
    }
    cbm__cerr(L->cur, pos, "invalid operands to '%s' (%s and %s)", op->s,
              L->model->types.data[ta].name, L->model->types.data[tb].name);
    return -1;
}

static int32_t binary_expr(lc_parser *L, int minprec)
{
    int32_t a = primary(L);
    int chain = 0; /* a+b+c... is a left-deep tree: each operator nests */
    for (;;) {
        const binop *op = peek_binop(L);
        if (!op || op->prec < minprec || a < 0) {
            L->depth -= chain;
            return a;
        }
        if (!deeper(L)) {
            L->depth -= chain;
            return -1;
        }
        chain++;
        size_t pos = L->cur->pos;
        L->cur->pos += strlen(op->s);
        int32_t b = binary_expr(L, op->prec + 1);
        a = binary(L, a, op, b, pos);
    }
}

static int32_t ternary_inner(lc_parser *L);

static int32_t ternary(lc_parser *L)
{
    if (!deeper(L))
        return -1;
    int32_t r = ternary_inner(L);
    L->depth--;
    return r;
}

static int32_t ternary_inner(lc_parser *L)
{
    int32_t c = binary_expr(L, 1);
    if (c < 0 || !accept(L, "?"))
        return c;
    size_t pos = L->cur->pos;
    int32_t a = assign_expr(L);
    if (a < 0 || !expect(L, ":"))
        return -1;
    int32_t b = ternary(L);
    if (b < 0)
        return -1;
    int ta = ND(a).type, tb = ND(b).type;
    int t = ta;
    if (lc_is_scalar(ta) && lc_is_scalar(tb))
        t = lc_arith_type(ta, tb);
    else if (ta != tb) {
        cbm__cerr(L->cur, pos, "the branches of '?:' have different types");
        return -1;
    }
    lc_node n = blank_node(N_COND, t);
    n.child1 = c;
    n.child2 = coerce(L, a, t, pos);
    n.child3 = coerce(L, b, t, pos);
    return add_node(L, n);
}

static bool is_lvalue(lc_parser *L, int32_t e)
{
    return e >= 0 && (ND(e).op == N_LOCAL || ND(e).op == N_GLOBAL);
}

static int32_t assign_expr(lc_parser *L)
{
    size_t pos = L->cur->pos;
    int32_t l = ternary(L);
    if (l < 0)
        return -1;
    skip(L);
    static const char *const AOPS[] = {"=", "+=", "-=", "*=", "/=", "%="};
    static const int ABIN[] = {-1, B_ADD, B_SUB, B_MUL, B_DIV, B_REM};
    for (int k = 5; k >= 0; k--) {
        size_t n = strlen(AOPS[k]);
        if (strncmp(L->text + L->cur->pos, AOPS[k], n) ||
            (k == 0 && L->text[L->cur->pos + 1] == '='))
            continue;
        if (!is_lvalue(L, l)) {
            cbm__cerr(L->cur, pos, "the left side of '%s' is not assignable", AOPS[k]);
            return -1;
        }
        L->cur->pos += n;
        size_t p2 = L->cur->pos;
        if (!deeper(L))
            return -1;
        int32_t r = assign_expr(L);
        L->depth--;
        if (r < 0)
            return -1;
        int lt = ND(l).type;
        if (k > 0) { /* l op= r  is  l = l op r */
            lc_node cp = ND(l);
            int32_t l2 = add_node(L, cp);
            binop bo = {AOPS[k], 0, ABIN[k]};
            r = binary(L, l2, &bo, r, p2);
            if (r < 0)
                return -1;
        }
        lc_node x = blank_node(N_ASSIGN, lt);
        x.child1 = l;
        x.child2 = (lt >= T_NBUILTIN) ? r : coerce(L, r, lt, p2);
        if (x.child2 >= 0 && ND(x.child2).type != lt) {
            cbm__cerr(L->cur, p2, "cannot assign %s to %s",
                      L->model->types.data[ND(x.child2).type].name, L->model->types.data[lt].name);
            return -1;
        }
        return x.child2 >= 0 ? add_node(L, x) : -1;
    }
    return l;
}

static int32_t expr(lc_parser *L)
{
    skip(L);
    size_t start = L->cur->pos;
    int32_t a = comma_expr(L);
    if (a >= 0)
        ND(a).pos = (int32_t)(start < INT32_MAX ? start : INT32_MAX);
    return a;
}

static int32_t comma_expr(lc_parser *L)
{
    int32_t a = assign_expr(L);
    while (a >= 0 && accept(L, ",")) {
        int32_t b = assign_expr(L);
        if (b < 0)
            return -1;
        lc_node n = blank_node(N_COMMA, ND(b).type);
        n.child1 = a;
        n.child2 = b;
        a = add_node(L, n);
    }
    return a;
}

/* ---------------------------------------------------------------- modules, patterns */
/* `Name(args) Name(args) ...` up to `;` (successor) */
static int succ_list(lc_parser *L, lc_pattern *p)
{
    lc_model *lp = L->model;
    p->first = (int32_t)lp->sms.len;
    p->n = 0;
    for (;;) {
        size_t n = ident(L);
        if (!n)
            break;
        size_t pos = L->cur->pos;
        int m = find_mod(lp, L->text + pos, n);
        if (m < 0) {
            cbm__cerr(L->cur, pos, "unknown module '%.*s' (declare it with `module`)", (int)n,
                      L->text + pos);
            return -1;
        }
        L->cur->pos += n;
        int32_t args = -1;
        int na = 0;
        if (peek(L, "("))
            na = parse_args(L, &args);
        if (na < 0)
            return -1;
        const lc_module *md = &lp->mods.data[m];
        if (na != md->nparams) {
            cbm__cerr(L->cur, pos, "module %s has %d parameter%s, %d given", md->name, md->nparams,
                      md->nparams == 1 ? "" : "s", na);
            return -1;
        }
        int32_t first = -1, last = -1;
        for (int a = 0; a < na; a++) {
            int32_t e = args;
            args = ND(e).next;
            ND(e).next = -1;
            int32_t at = ND(e).pos; /* the argument's first character */
            e = coerce(L, e, md->ptype[a], pos);
            if (e < 0)
                return -1;
            ND(e).pos = at;
            chain(L, &first, &last, e);
        }
        lc_modref sm = {m, first};
        if (CBM_ARRAY_PUSH(L->cur->ctx, lp->sms, sm) != CBM_OK) {
            L->cur->status = CBM_E_NOMEM;
            L->cur->fatal = true;
            return -1;
        }
        p->n++;
    }
    return 0;
}

/* A context or predecessor pattern: `Name(f1, f2) ...`; declare: formal names become new
 * locals; else they name existing variables (In*Context). */
static int pattern(lc_parser *L, lc_pattern *p, bool declare)
{
    lc_model *lp = L->model;
    p->first = (int32_t)lp->sms.len;
    p->n = 0;
    for (;;) {
        size_t n = ident(L);
        if (!n)
            break;
        size_t pos = L->cur->pos;
        int m = find_mod(lp, L->text + pos, n);
        if (m < 0) {
            if (p->n && declare)
                break;
            cbm__cerr(L->cur, pos, "unknown module '%.*s'", (int)n, L->text + pos);
            return -1;
        }
        L->cur->pos += n;
        const lc_module *md = &lp->mods.data[m];
        int32_t first = -1, last = -1;
        int na = 0;
        if (accept(L, "(")) {
            if (!accept(L, ")")) {
                do {
                    size_t k = ident(L);
                    size_t fp = L->cur->pos;
                    if (!k) {
                        expected(L, "a parameter name");
                        return -1;
                    }
                    L->cur->pos += k;
                    if (na >= md->nparams) {
                        na++;
                        continue;
                    }
                    lc_node x = blank_node(N_LOCAL, md->ptype[na]);
                    if (declare)
                        x.slot = declare_local(L, L->text + fp, k, md->ptype[na]);
                    else {
                        lc_local *v = find_var(L, L->text + fp, k);
                        if (!v) {
                            cbm__cerr(L->cur, fp, "unknown variable '%.*s'", (int)k, L->text + fp);
                            return -1;
                        }
                        if (v->type != md->ptype[na]) {
                            cbm__cerr(L->cur, fp, "'%.*s' has type %s, module %s wants %s", (int)k,
                                      L->text + fp, lp->types.data[v->type].name, md->name,
                                      lp->types.data[md->ptype[na]].name);
                            return -1;
                        }
                        x.slot = v->slot;
                    }
                    int32_t e = add_node(L, x);
                    if (e < 0)
                        return -1;
                    chain(L, &first, &last, e);
                    na++;
                } while (accept(L, ","));
                if (!expect(L, ")"))
                    return -1;
            }
        }
        if (na != md->nparams) {
            cbm__cerr(L->cur, pos, "module %s has %d parameter%s, the pattern names %d", md->name,
                      md->nparams, md->nparams == 1 ? "" : "s", na);
            return -1;
        }
        lc_modref sm = {m, first};
        if (CBM_ARRAY_PUSH(L->cur->ctx, lp->sms, sm) != CBM_OK) {
            L->cur->status = CBM_E_NOMEM;
            L->cur->fatal = true;
            return -1;
        }
        p->n++;
    }
    return 0;
}

/* ---------------------------------------------------------------- statements */
static int32_t statement(lc_parser *L);

static int32_t block(lc_parser *L)
{
    if (!expect(L, "{"))
        return -1;
    size_t nvars = L->vars.len;
    int fs = L->frame_size;
    int32_t first = -1, last = -1;
    bool ok = true;
    while (!accept(L, "}")) {
        if (!L->text[L->cur->pos] || fatal(L)) {
            expected(L, "'}'");
            return -1;
        }
        size_t before = L->cur->pos;
        int32_t s = statement(L);
        if (s < 0) {
            ok = false;
            if (fatal(L))
                return -1;
            if (L->cur->pos == before) /* always make progress */
                recover_stmt(L);
            if (L->cur->pos == before && L->text[L->cur->pos] != '}')
                L->cur->pos++;
            continue;
        }
        chain(L, &first, &last, s);
        while (ND(last).next >= 0)
            last = ND(last).next;
    }
    L->vars.len = nvars;
    L->frame_size = fs;
    lc_node b = blank_node(S_BLOCK, 0);
    b.child1 = first;
    return ok ? add_node(L, b) : -1;
}

/* declaration statement after its type: `a = 1, b, c = {..};` */
static int32_t declaration(lc_parser *L, int t)
{
    int32_t first = -1, last = -1;
    do {
        size_t n = ident(L);
        size_t pos = L->cur->pos;
        if (!n) {
            expected(L, "a variable name");
            recover_stmt(L);
            return -1;
        }
        L->cur->pos += n;
        int32_t init = -1;
        if (accept(L, "=")) {
            size_t p2 = L->cur->pos;
            init = peek(L, "{") ? brace_init(L, t) : assign_expr(L);
            if (init >= 0 && t < T_NBUILTIN)
                init = coerce(L, init, t, p2);
            if (init >= 0 && ND(init).type != t) {
                cbm__cerr(L->cur, p2, "cannot initialize %s with %s", L->model->types.data[t].name,
                          L->model->types.data[ND(init).type].name);
                init = -1;
            }
            if (init < 0) { /* declared all the same, so that its uses are no second error */
                declare_local(L, L->text + pos, n, t);
                recover_stmt(L);
                return -1;
            }
        }
        lc_node d = blank_node(S_DECL, t);
        d.slot = declare_local(L, L->text + pos, n, t);
        d.child1 = init;
        int32_t s = add_node(L, d);
        if (s < 0)
            return -1;
        chain(L, &first, &last, s);
    } while (accept(L, ","));
    if (!expect(L, ";")) {
        recover_stmt(L);
        return -1;
    }
    return first;
}

static int32_t statement(lc_parser *L)
{
    skip(L);
    size_t pos = L->cur->pos;
    if (!deeper(L))
        return -1;
    int32_t r = -1;
    int t;
    if (peek(L, "{")) {
        r = block(L);
    } else if (accept(L, ";")) {
        r = add_node(L, blank_node(S_NOP, 0));
    } else if (accept_kw(L, "if")) {
        lc_node n = blank_node(S_IF, 0);
        if (expect(L, "(")) {
            n.child1 = coerce(L, expr(L), T_BOOL, pos);
            if (n.child1 >= 0 && expect(L, ")")) {
                n.child2 = statement(L);
                if (accept_kw(L, "else"))
                    n.child3 = statement(L);
                if (n.child2 >= 0)
                    r = add_node(L, n);
            }
        }
    } else if (accept_kw(L, "while")) {
        lc_node n = blank_node(S_WHILE, 0);
        if (expect(L, "(")) {
            n.child1 = coerce(L, expr(L), T_BOOL, pos);
            if (n.child1 >= 0 && expect(L, ")")) {
                n.child2 = statement(L);
                if (n.child2 >= 0)
                    r = add_node(L, n);
            }
        }
    } else if (accept_kw(L, "do")) {
        lc_node n = blank_node(S_DO, 0);
        n.child2 = statement(L);
        if (n.child2 >= 0 && accept_kw(L, "while") && expect(L, "(")) {
            n.child1 = coerce(L, expr(L), T_BOOL, pos);
            if (n.child1 >= 0 && expect(L, ")") && expect(L, ";"))
                r = add_node(L, n);
        } else if (n.child2 >= 0)
            expected(L, "'while'");
    } else if (accept_kw(L, "for")) {
        size_t nvars = L->vars.len;
        int fs = L->frame_size;
        lc_node n = blank_node(S_FOR, 0);
        bool ok = expect(L, "(");
        if (ok && !accept(L, ";")) {
            int ty = parse_type(L);
            if (ty >= 0)
                n.child1 = declaration(L, ty);
            else {
                int32_t e = expr(L);
                if (e >= 0) {
                    lc_node s = blank_node(S_EXPR, 0);
                    s.child1 = e;
                    n.child1 = add_node(L, s);
                }
                ok = e >= 0 && expect(L, ";");
            }
            ok = ok && n.child1 >= 0;
        }
        if (ok && !accept(L, ";")) {
            n.child2 = coerce(L, expr(L), T_BOOL, pos);
            ok = n.child2 >= 0 && expect(L, ";");
        }
        if (ok && !accept(L, ")")) {
            n.child3 = expr(L);
            ok = n.child3 >= 0 && expect(L, ")");
        }
        if (ok) {
            n.child4 = statement(L);
            if (n.child4 >= 0)
                r = add_node(L, n);
        }
        L->vars.len = nvars;
        L->frame_size = fs;
    } else if (accept_kw(L, "return")) {
        lc_node n = blank_node(S_RETURN, L->in_prod ? T_VOID : L->ret_type);
        if (!peek(L, ";")) {
            if (L->ret_type == T_VOID || L->in_prod) {
                cbm__cerr(L->cur, pos, "return with a value here");
                recover_stmt(L);
                L->depth--;
                return -1;
            }
            n.child1 = coerce(L, expr(L), L->ret_type, pos);
            if (n.child1 < 0 && L->ret_type >= T_NBUILTIN)
                n.child1 = -1;
        } else if (L->ret_type != T_VOID && !L->in_prod) {
            cbm__cerr(L->cur, pos, "return needs a value");
        }
        if (expect(L, ";"))
            r = add_node(L, n);
    } else if (accept_kw(L, "switch")) {
        lc_node n = blank_node(S_SWITCH, 0);
        if (expect(L, "(")) {
            n.child1 = coerce(L, expr(L), T_DOUBLE, pos);
            if (n.child1 >= 0 && expect(L, ")")) {
                L->in_switch++;
                n.child2 = statement(L);
                L->in_switch--;
                if (n.child2 >= 0)
                    r = add_node(L, n);
            }
        }
    } else if (L->in_switch && (accept_kw(L, "case") || accept_kw(L, "default"))) {
        lc_node n = blank_node(S_CASE, 0);
        bool dflt = L->text[pos] == 'd';
        if (!dflt)
            n.child1 = coerce(L, expr(L), T_DOUBLE, pos);
        if ((dflt || n.child1 >= 0) && expect(L, ":"))
            r = add_node(L, n);
    } else if (accept_kw(L, "break")) {
        if (expect(L, ";"))
            r = add_node(L, blank_node(S_BREAK, 0));
    } else if (accept_kw(L, "continue")) {
        if (expect(L, ";"))
            r = add_node(L, blank_node(S_CONTINUE, 0));
    } else if (peek(L, "nproduce") || accept_kw(L, "produce")) {
        bool partial = accept_kw(L, "nproduce");
        if (!L->in_prod) {
            cbm__cerr(L->cur, pos, "produce outside a production");
            recover_stmt(L);
        } else {
            lc_pattern p;
            if (succ_list(L, &p) == 0 && expect(L, ";")) {
                lc_node n = blank_node(S_PRODUCE, 0);
                n.child1 = p.first;
                n.child2 = p.n;
                n.fn = partial;
                r = add_node(L, n);
            } else
                recover_stmt(L);
        }
    } else if ((t = parse_type(L)) >= 0) {
        r = declaration(L, t);
    } else {
        int32_t e = expr(L);
        if (e >= 0 && expect(L, ";")) {
            lc_node s = blank_node(S_EXPR, 0);
            s.child1 = e;
            r = add_node(L, s);
        } else if (!fatal(L))
            recover_stmt(L);
    }
    L->depth--;
    if (r >= 0)
        ND(r).pos = (int32_t)(pos < INT32_MAX ? pos : INT32_MAX);
    return r;
}

/* ---------------------------------------------------------------- top level */
static int32_t const_int(lc_parser *L, const char *what)
{
    size_t pos = L->cur->pos;
    int32_t e = expr(L);
    if (e < 0)
        return -1;
    if (!lc_is_scalar(ND(e).type)) {
        cbm__cerr(L->cur, pos, "%s must be a number", what);
        return -1;
    }
    return e;
}

static void parse_struct(lc_parser *L, size_t pos)
{
    lc_model *lp = L->model;
    size_t n = ident(L);
    if (!n) {
        expected(L, "a struct name");
        recover(L);
        return;
    }
    char name[64];
    snprintf(name, sizeof name, "%.*s", (int)(n < 63 ? n : 63), L->text + L->cur->pos);
    if (find_type(L, L->text + L->cur->pos, n) >= 0) {
        cbm__cerr(L->cur, L->cur->pos, "type '%s' is already defined", name);
        recover(L);
        return;
    }
    L->cur->pos += n;
    lc_type ty;
    memset(&ty, 0, sizeof ty);
    if (!expect(L, "{")) {
        recover(L);
        return;
    }
    while (!accept(L, "}")) {
        int ft = parse_type(L);
        if (ft < 0) {
            expected(L, "a field type");
            recover(L);
            goto fail;
        }
        do {
            size_t k = ident(L);
            if (!k) {
                expected(L, "a field name");
                recover(L);
                goto fail;
            }
            if (ty.nfields >= MAXFLD) {
                cbm__cerr(L->cur, L->cur->pos, "more than %d fields in struct %s", MAXFLD, name);
                recover(L);
                goto fail;
            }
            char *fn = cbm__alloc(L->cur->ctx, k + 1);
            if (!fn) {
                L->cur->status = CBM_E_NOMEM;
                L->cur->fatal = true;
                goto fail;
            }
            memcpy(fn, L->text + L->cur->pos, k);
            fn[k] = 0;
            L->cur->pos += k;
            ty.fname[ty.nfields] = fn;
            ty.ftype[ty.nfields] = ft;
            ty.foff[ty.nfields] = ty.size;
            ty.size += lc_type_size(lp, ft);
            ty.nfields++;
        } while (accept(L, ","));
        if (!expect(L, ";")) {
            recover(L);
            goto fail;
        }
    }
    accept(L, ";");
    if (ty.size > MAXSZ) {
        cbm__cerr(L->cur, pos, "struct %s is too large (more than %d numbers)", name, MAXSZ);
        goto fail;
    }
    ty.name = cbm__strdup(L->cur->ctx, name);
    if (!ty.name || CBM_ARRAY_PUSH(L->cur->ctx, lp->types, ty) != CBM_OK) {
        cbm__strfree(L->cur->ctx, ty.name);
        L->cur->status = CBM_E_NOMEM;
        L->cur->fatal = true;
        goto fail;
    }
    return;
fail:
    for (int i = 0; i < ty.nfields; i++)
        cbm__strfree(L->cur->ctx, ty.fname[i]);
}

static void parse_module_decl(lc_parser *L)
{
    do {
        size_t n = ident(L);
        size_t pos = L->cur->pos;
        if (!n) {
            expected(L, "a module name");
            recover(L);
            return;
        }
        L->cur->pos += n;
        int pt[MAXF], np = 0;
        if (expect(L, "(") && !accept(L, ")")) {
            do {
                int t = parse_type(L);
                if (t < 0) {
                    expected(L, "a parameter type");
                    recover(L);
                    return;
                }
                if (np >= MAXF) {
                    cbm__cerr(L->cur, pos, "more than %d parameters", MAXF);
                    recover(L);
                    return;
                }
                pt[np++] = t;
                size_t k = ident(L); /* optional parameter name */
                if (k && find_type(L, L->text + L->cur->pos, k) < 0)
                    L->cur->pos += k;
            } while (accept(L, ","));
            if (!expect(L, ")")) {
                recover(L);
                return;
            }
        }
        int m = find_mod(L->model, L->text + pos, n);
        if (m >= 0) {
            cbm__cerr(L->cur, pos, "module '%.*s' is already declared", (int)n, L->text + pos);
            continue;
        }
        add_mod(L, L->text + pos, n, pt, np, NULL, pos);
    } while (accept(L, ","));
    if (!expect(L, ";"))
        recover(L);
}

static void symbol_list(lc_parser *L, bool consider)
{
    lc_model *lp = L->model;
    if (consider)
        for (int i = 0; i < 128; i++)
            lp->considered[i] = false;
    for (;;) {
        size_t n = ident(L);
        if (!n)
            break;
        int m = find_mod(lp, L->text + L->cur->pos, n);
        if (m < 0)
            cbm__cerr(L->cur, L->cur->pos, "unknown module '%.*s'", (int)n, L->text + L->cur->pos);
        else
            lp->considered[lp->mods.data[m].code] = consider;
        L->cur->pos += n;
        accept(L, ",");
    }
    if (!expect(L, ";"))
        recover(L);
}

/* The roles a declaration gives a module's parameters, `mass: Grape(mass, radius)` or
 * `light: Leaf(area, light)`: two role names and `_` (not used), in parameter order. */
typedef struct {
    const char *kind;    /* the module's kind, for messages */
    const char *role[2]; /* the role names */
} decl_roles;

/* `mass` (kg) and `radius` (m, the organ's contact sphere) of a point mass (lsys/mechlang.c). */
static const decl_roles mass_roles = {"point-mass", {"mass", "radius"}};
/* `area` (m^2, a number the model sets) and `light` (a number Light() writes) of a leaf
 * (lsys/lightlang.c). */
static const decl_roles light_roles = {"leaf", {"area", "light"}};

/* The module name that opens an entry of a declaration list (`mechanics:`, `mass:`, `light:`),
 * its position in *pos: the module's index, -1 for an unknown module (reported, the name
 * skipped) or -2 when no name is there (reported, the declaration skipped). */
static int decl_module(lc_parser *L, size_t *pos)
{
    size_t n = ident(L);
    *pos = L->cur->pos;
    if (!n) {
        expected(L, "a module name");
        recover(L);
        return -2;
    }
    int m = find_mod(L->model, L->text + *pos, n);
    L->cur->pos += n;
    if (m < 0)
        cbm__cerr(L->cur, *pos, "unknown module '%.*s'", (int)n, L->text + *pos);
    return m;
}

/* The roles of module md's parameters after its `(`, through the `)`: the offsets (in doubles)
 * of the parameters with r's two roles into off[0] and off[1] (-1: absent; each role a number,
 * given once). false after an error. */
static bool parse_roles(lc_parser *L, const lc_module *md, const decl_roles *r, int off[2])
{
    lc_model *lp = L->model;
    int at = 0;
    off[0] = off[1] = -1;
    for (int k = 0;; k++) {
        size_t n = ident(L), pos = L->cur->pos;
        if (!n) {
            char what[48];
            snprintf(what, sizeof what, "%s, %s or _", r->role[0], r->role[1]);
            expected(L, what);
            return false;
        }
        L->cur->pos += n;
        int *dst = NULL;
        for (int j = 0; j < 2; j++)
            if (strlen(r->role[j]) == n && !strncmp(L->text + pos, r->role[j], n))
                dst = &off[j];
        if (!dst && !(n == 1 && L->text[pos] == '_')) {
            cbm__cerr(L->cur, pos, "unknown role '%.*s' of a %s parameter (%s, %s or _)", (int)n,
                      L->text + pos, r->kind, r->role[0], r->role[1]);
            return false;
        }
        if (k >= md->nparams) {
            cbm__cerr(L->cur, pos, "module '%s' has %d parameter%s", md->name, md->nparams,
                      md->nparams == 1 ? "" : "s");
            return false;
        }
        if (dst && *dst >= 0) {
            cbm__cerr(L->cur, pos, "'%.*s' given twice", (int)n, L->text + pos);
            return false;
        }
        if (dst && !lc_is_scalar(md->ptype[k])) {
            cbm__cerr(L->cur, pos, "parameter %d of '%s' must be a number to be its %.*s, not %s",
                      k + 1, md->name, (int)n, L->text + pos, lp->types.data[md->ptype[k]].name);
            return false;
        }
        if (dst)
            *dst = at;
        at += lc_type_size(lp, md->ptype[k]);
        if (!accept(L, ","))
            break;
    }
    return expect(L, ")");
}

/* `mechanics: Module;` (its MechSegment parameter is the segment) and `mass: A, B;` (the first
 * parameter, a number, is a point mass in kg), or with roles `mass: Grape(mass, radius);` (see
 * mass_roles). */
static void mech_decl(lc_parser *L, bool mass)
{
    lc_model *lp = L->model;
    for (;;) {
        size_t pos;
        int m = decl_module(L, &pos);
        if (m == -2)
            return;
        if (m >= 0) {
            const lc_module *md = &lp->mods.data[m];
            int off = 0, found = -1;
            if (mass && accept(L, "(")) {
                int roff[2];
                if (!parse_roles(L, md, &mass_roles, roff)) {
                    recover(L);
                    return;
                }
                if (roff[0] < 0) {
                    cbm__cerr(L->cur, L->cur->pos - 1,
                              "point-mass module '%s' needs a 'mass' parameter", md->name);
                    recover(L);
                    return;
                }
                lp->mech_decl.mass_off[md->code] = roff[0];
                lp->mech_decl.radius_off[md->code] = roff[1];
                if (!accept(L, ","))
                    break;
                continue;
            }
            for (int i = 0; i < md->nparams && found < 0; i++) {
                if (mass ? i == 0 && lc_is_scalar(md->ptype[i]) : md->ptype[i] == T_MSEG)
                    found = off;
                off += lc_type_size(lp, md->ptype[i]);
            }
            if (found < 0 && mass)
                cbm__cerr(L->cur, pos,
                          "the first parameter of point-mass module '%s' must be a number "
                          "(its mass, kg)%s%s",
                          md->name, md->nparams ? ", not " : "",
                          md->nparams ? lp->types.data[md->ptype[0]].name : "");
            else if (found < 0)
                cbm__cerr(L->cur, pos, "mechanical module '%s' needs a MechSegment parameter",
                          md->name);
            else if (!mass && lp->mech_decl.seg_code >= 0 && lp->mech_decl.seg_code != md->code)
                cbm__cerr(L->cur, pos, "only one module can carry the mechanical segment");
            else if (mass) {
                lp->mech_decl.mass_off[md->code] = found;
                lp->mech_decl.radius_off[md->code] = -1;
            } else {
                lp->mech_decl.seg_code = md->code;
                lp->mech_decl.seg_off = found;
            }
        }
        if (!accept(L, ","))
            break;
    }
    if (!expect(L, ";"))
        recover(L);
}

/* `light: Leaf(area, light), ...;`: the roles of a leaf module's parameters (see light_roles);
 * both roles are needed. */
static void light_decl(lc_parser *L)
{
    lc_model *lp = L->model;
    for (;;) {
        size_t pos;
        int m = decl_module(L, &pos), off[2];
        if (m < 0) {
            if (m == -1)
                recover(L);
            return;
        }
        const lc_module *md = &lp->mods.data[m];
        if (!expect(L, "(") || !parse_roles(L, md, &light_roles, off)) {
            recover(L);
            return;
        }
        if (off[0] < 0 || off[1] < 0) {
            cbm__cerr(L->cur, L->cur->pos - 1,
                      "leaf module '%s' needs an 'area' and a 'light' parameter", md->name);
            recover(L);
            return;
        }
        lp->mech_decl.light_area_off[md->code] = off[0];
        lp->mech_decl.light_out_off[md->code] = off[1];
        if (!accept(L, ","))
            break;
    }
    if (!expect(L, ";"))
        recover(L);
}

/* `pred-with-contexts : { body }` */
static void parse_production(lc_parser *L, lc_rules *set, int group)
{
    lc_model *lp = L->model;
    size_t pos = L->cur->pos;
    lc_production pr;
    memset(&pr, 0, sizeof pr);
    pr.pos = pos;
    pr.group = group;
    L->vars.len = 0;
    L->frame_size = L->frame_max = 0;
    L->in_prod = true;
    L->ret_type = T_VOID;
    lc_pattern pats[5];
    int npats = 0;
    int ops[5];
    for (;;) {
        if (npats == 5) {
            cbm__cerr(L->cur, L->cur->pos, "too many context parts");
            recover(L);
            return;
        }
        if (pattern(L, &pats[npats], true) < 0) {
            recover(L);
            return;
        }
        if (pats[npats].n == 0) {
            expected(L, "a module");
            recover(L);
            return;
        }
        npats++;
        skip(L);
        const char *s = L->text + L->cur->pos;
        if (s[0] == '<' && s[1] == '<')
            ops[npats - 1] = 1, L->cur->pos += 2;
        else if (s[0] == '<')
            ops[npats - 1] = 0, L->cur->pos += 1;
        else if (s[0] == '>' && s[1] == '>')
            ops[npats - 1] = 2, L->cur->pos += 2;
        else if (s[0] == '>')
            ops[npats - 1] = 3, L->cur->pos += 1;
        else if (s[0] == ':') {
            ops[npats - 1] = -1;
            L->cur->pos++;
            break;
        } else {
            expected(L, "'<', '<<', '>>', '>' or ':'");
            recover(L);
            return;
        }
    }
    /* pattern k is followed by operator ops[k]: left contexts precede the predecessor */
    int ip = 0;
    while (ip < npats && (ops[ip] == 0 || ops[ip] == 1)) {
        int k = ops[ip] == 0 ? LC_CTX_LEFT : LC_CTX_NEW_LEFT;
        if (pr.context[k].n) {
            cbm__cerr(L->cur, pos, "two %s contexts", k == LC_CTX_LEFT ? "left" : "new left");
            recover(L);
            return;
        }
        pr.context[k] = pats[ip++];
    }
    if (ip >= npats) {
        cbm__cerr(L->cur, pos, "production without a predecessor");
        recover(L);
        return;
    }
    pr.mod = lp->sms.data[pats[ip].first].mod;
    pr.pred = pats[ip];
    int prev = ops[ip];
    for (int k = ip + 1; k < npats; k++) {
        int cx = prev == 2 ? LC_CTX_NEW_RIGHT : prev == 3 ? LC_CTX_RIGHT : -1;
        if (cx < 0 || pr.context[cx].n) {
            cbm__cerr(L->cur, pos, "misplaced context");
            recover(L);
            return;
        }
        pr.context[cx] = pats[k];
        prev = ops[k];
    }
    if (pr.context[LC_CTX_NEW_LEFT].n && pr.context[LC_CTX_NEW_RIGHT].n) {
        cbm__cerr(L->cur, pos, "a production cannot have both new left and new right context");
        recover(L);
        return;
    }
    skip(L);
    if (!peek(L, "{")) {
        expected(L, "'{' (the production's body)");
        recover(L);
        return;
    }
    pr.body = block(L);
    pr.fsize = L->frame_max;
    L->in_prod = false;
    if (pr.body < 0)
        return;
    if (CBM_ARRAY_PUSH(L->cur->ctx, set->prods, pr) != CBM_OK) {
        L->cur->status = CBM_E_NOMEM;
        L->cur->fatal = true;
    }
}

static void parse_function(lc_parser *L, int rt, size_t pos)
{
    lc_model *lp = L->model;
    size_t n = ident(L);
    lc_function f;
    memset(&f, 0, sizeof f);
    f.ret_type = rt;
    f.pos = pos;
    f.name = cbm__alloc(L->cur->ctx, n + 1);
    if (!f.name) {
        L->cur->status = CBM_E_NOMEM;
        L->cur->fatal = true;
        return;
    }
    memcpy(f.name, L->text + L->cur->pos, n);
    f.name[n] = 0;
    L->cur->pos += n;
    L->vars.len = 0;
    L->frame_size = L->frame_max = 0;
    expect(L, "(");
    if (!accept(L, ")") && !accept_kw(L, "void")) {
        do {
            int t = parse_type(L);
            bool ref = t >= 0 && accept(L, "&");
            size_t k = t >= 0 ? ident(L) : 0;
            if (t < 0 || !k || f.nparams >= MAXF) {
                expected(L, "a parameter (type and name)");
                recover(L);
                cbm__strfree(L->cur->ctx, f.name);
                return;
            }
            f.pref[f.nparams] = ref;
            f.ptype[f.nparams++] = t;
            declare_local(L, L->text + L->cur->pos, k, t);
            L->cur->pos += k;
        } while (accept(L, ","));
        expect(L, ")");
    } else
        accept(L, ")");
    /* register before the body: recursion */
    f.body = -1;
    if (CBM_ARRAY_PUSH(L->cur->ctx, lp->funcs, f) != CBM_OK) {
        cbm__strfree(L->cur->ctx, f.name);
        L->cur->status = CBM_E_NOMEM;
        L->cur->fatal = true;
        return;
    }
    size_t fi = lp->funcs.len - 1;
    L->ret_type = rt;
    L->in_prod = false;
    int32_t b = block(L);
    lp->funcs.data[fi].body = b;
    lp->funcs.data[fi].fsize = L->frame_max;
    L->ret_type = T_VOID;
}

static void parse_global(lc_parser *L, int t)
{
    lc_model *lp = L->model;
    L->vars.len = 0;
    L->frame_size = L->frame_max = 0;
    do {
        size_t n = ident(L);
        if (!n) {
            expected(L, "a name");
            recover(L);
            return;
        }
        size_t pos = L->cur->pos;
        if (find_gvar(L, L->text + pos, n)) {
            cbm__cerr(L->cur, pos, "'%.*s' is already defined", (int)n, L->text + pos);
            recover(L);
            return;
        }
        L->cur->pos += n;
        /* declared before its initialiser, as C++'s point of declaration: the initialiser may
         * read the global (zero then, on every run: reset zeroes the globals first) */
        lc_global g = {NULL, t, lp->nglobal, -1};
        g.name = cbm__alloc(L->cur->ctx, n + 1);
        if (!g.name || CBM_ARRAY_PUSH(L->cur->ctx, lp->gvars, g) != CBM_OK) {
            if (g.name)
                cbm__free(L->cur->ctx, g.name, n + 1);
            L->cur->status = CBM_E_NOMEM;
            L->cur->fatal = true;
            return;
        }
        memcpy(g.name, L->text + pos, n);
        g.name[n] = 0;
        lp->nglobal += lc_type_size(lp, t);
        if (accept(L, "=")) {
            skip(L);
            size_t p2 = L->cur->pos;
            int32_t init = peek(L, "{") ? brace_init(L, t) : assign_expr(L);
            if (init >= 0 && t < T_NBUILTIN)
                init = coerce(L, init, t, p2);
            if (init < 0) {
                recover(L);
                return;
            }
            /* a runtime error of the initialiser names its first character */
            ND(init).pos = (int32_t)(p2 < INT32_MAX ? p2 : INT32_MAX);
            lp->gvars.data[lp->gvars.len - 1].init = init;
        }
    } while (accept(L, ","));
    if (!expect(L, ";"))
        recover(L);
}

static bool label(lc_parser *L, const char *kw)
{
    size_t save = L->cur->pos;
    skip(L);
    const char *s = L->text + L->cur->pos;
    size_t i = 0, k = 0;
    while (kw[k] != '\0') {
        if (kw[k] == ' ') {
            while (s[i] == ' ' || s[i] == '\t')
                i++;
            k++;
            continue;
        }
        char a = s[i], b = kw[k];
        if (k == 0 ? tolower((unsigned char)a) != tolower((unsigned char)b) : a != b) {
            L->cur->pos = save;
            return false;
        }
        i++, k++;
    }
    if (is_ident_char((unsigned char)s[i])) {
        L->cur->pos = save;
        return false;
    }
    L->cur->pos += i;
    skip(L);
    if (L->text[L->cur->pos] != ':') {
        L->cur->pos = save;
        return false;
    }
    L->cur->pos++;
    return true;
}

static cbm_status setup_builtins(lc_parser *L)
{
    lc_model *lp = L->model;
    cbm_context *ctx = L->cur->ctx;
    static const char *const TN[] = {"void",      "int",    "float",      "double",
                                     "bool",      "V3f",    "V3d",        "Quaternion",
                                     "TurtleVec", "LocVec", "MechSegment"};
    static const int TS[] = {0, 1, 1, 1, 1, 3, 3, 4, 9, 3, MS_SIZE};
    for (int i = 0; i < T_NBUILTIN; i++)
        CBM_TRY(add_type(lp, ctx, TN[i], TS[i]));
    /* Quaternion {w, x, y, z} (double), TurtleVec {H, L, U} (V3f): built-in structs */
    static const char *const QF[] = {"w", "x", "y", "z"}, *const TF[] = {"H", "L", "U"};
    lc_type *q = &lp->types.data[T_QUAT], *tv = &lp->types.data[T_TVEC];
    for (int i = 0; i < 4; i++) {
        q->fname[i] = cbm__strdup(ctx, QF[i]);
        q->ftype[i] = T_DOUBLE;
        q->foff[i] = i;
        q->nfields++;
        if (!q->fname[i])
            return CBM_E_NOMEM;
    }
    lc_type *lv = &lp->types.data[T_LOCVEC];
    static const char *const LF[] = {"h", "l", "u"};
    for (int i = 0; i < 3; i++) {
        lv->fname[i] = cbm__strdup(ctx, LF[i]);
        lv->ftype[i] = T_FLOAT;
        lv->foff[i] = i;
        lv->nfields++;
        if (!lv->fname[i])
            return CBM_E_NOMEM;
    }
    for (int i = 0; i < 3; i++) {
        tv->fname[i] = cbm__strdup(ctx, TF[i]);
        tv->ftype[i] = T_V3F;
        tv->foff[i] = 3 * i;
        tv->nfields++;
        if (!tv->fname[i])
            return CBM_E_NOMEM;
    }
    /* MechSegment: the fields at the offsets of lsys/mechlang_internal.h */
    static const char *const MF[] = {
        "length", "a",   "b", "E", "G",      "density",      "mor",          "rest",
        "omega",  "pos", "H", "U", "stress", "stress_ratio", "carried_mass", "age"};
    static const int MO[] = {MS_LENGTH, MS_A,     MS_B,       MS_E,   MS_G, MS_DENSITY,
                             MS_MOR,    MS_REST,  MS_OMEGA,   MS_POS, MS_H, MS_U,
                             MS_STRESS, MS_RATIO, MS_CARRIED, MS_AGE};
    lc_type *ms = &lp->types.data[T_MSEG];
    for (int i = 0; i < 16; i++) {
        ms->fname[i] = cbm__strdup(ctx, MF[i]);
        ms->ftype[i] = (MO[i] == MS_REST || MO[i] == MS_OMEGA || MO[i] == MS_POS || MO[i] == MS_H ||
                        MO[i] == MS_U)
                           ? T_V3D
                           : T_DOUBLE;
        ms->foff[i] = MO[i];
        ms->nfields++;
        if (!ms->fname[i])
            return CBM_E_NOMEM;
    }
    lp->mech_decl.seg_code = -1;
    for (int i = 0; i < 128; i++)
        lp->mech_decl.mass_off[i] = lp->mech_decl.radius_off[i] = -1;
    for (int i = 0; i < 128; i++)
        lp->mech_decl.light_area_off[i] = lp->mech_decl.light_out_off[i] = -1;
    for (int i = 0; i < 128; i++) {
        lp->bycode[i] = -1;
        lp->considered[i] = true;
    }
    for (size_t i = 0; i < sizeof TURTLE / sizeof TURTLE[0]; i++) {
        int pt[MAXF], np = 0;
        for (const char *p = TURTLE[i][2]; *p; p++)
            pt[np++] = *p == 'i' ? T_INT : *p == 'v' ? T_V3F : T_FLOAT;
        if (add_mod(L, TURTLE[i][0], strlen(TURTLE[i][0]), pt, np, TURTLE[i][1], 0) < 0)
            return L->cur->status != CBM_OK ? L->cur->status : CBM_E_NOMEM;
    }
    /* V3f and its synonyms */
    lp->sb_module = find_mod(lp, "SB", 2);
    lp->eb_module = find_mod(lp, "EB", 2);
    return CBM_OK;
}

static void parse_block_item(lc_parser *L, int which)
{
    L->vars.len = 0;
    L->frame_size = L->frame_max = 0;
    L->in_prod = false;
    L->ret_type = T_VOID;
    int32_t b = block(L);
    if (b >= 0) {
        L->model->blocks[which] = b;
        L->model->block_fsize[which] = L->frame_max;
    }
}

static void parse_top(lc_parser *L)
{
    lc_model *lp = L->model;
    lc_rules *set = &lp->main;
    int group = 0;
    for (;;) {
        skip(L);
        if (fatal(L) || !L->text[L->cur->pos])
            return;
        size_t pos = L->cur->pos;
        int t;
        if (label(L, "derivation length")) {
            lp->dlen_expr = const_int(L, "derivation length");
            if (!expect(L, ";"))
                recover(L);
        } else if (label(L, "Axiom")) {
            L->vars.len = 0;
            L->frame_size = L->frame_max = 0;
            if (succ_list(L, &lp->axiom) < 0 || !expect(L, ";"))
                recover(L);
        } else if (label(L, "ignore")) {
            symbol_list(L, false);
        } else if (label(L, "consider")) {
            symbol_list(L, true);
        } else if (label(L, "mechanics")) {
            mech_decl(L, false);
        } else if (label(L, "mass")) {
            mech_decl(L, true);
        } else if (label(L, "light")) {
            light_decl(L);
        } else if (label(L, "Start")) {
            parse_block_item(L, 0);
        } else if (label(L, "StartEach")) {
            parse_block_item(L, 1);
        } else if (label(L, "EndEach")) {
            parse_block_item(L, 2);
        } else if (label(L, "End")) {
            parse_block_item(L, 3);
        } else if (label(L, "decomposition")) {
            set = &lp->decomp;
            set->present = true;
            group = 0;
        } else if (label(L, "interpretation")) {
            set = &lp->interp;
            set->present = true;
            group = 0;
        } else if (label(L, "production") || label(L, "productions")) {
            set = &lp->main;
            group = 0;
        } else if (label(L, "maximum depth")) {
            int32_t e = const_int(L, "maximum depth");
            if (e >= 0) {
                set->depth = -2 - e; /* evaluated at load */
            }
            if (!expect(L, ";"))
                recover(L);
        } else if (accept_kw(L, "group")) {
            size_t p2 = L->cur->pos;
            int32_t e = const_int(L, "group");
            if (e >= 0 && ND(e).op == N_NUM && !(fabs(ND(e).value) <= 2147483647.0))
                cbm__cerr(L->cur, p2, "group %g is out of range (an int)", ND(e).value);
            else if (e >= 0 && ND(e).op == N_NUM)
                group = (int)ND(e).value;
            else if (e >= 0)
                cbm__cerr(L->cur, p2, "group needs a number");
            expect(L, ":");
        } else if (accept_kw(L, "endgroup")) {
            group = 0;
            accept(L, ";");
        } else if (accept_kw(L, "module")) {
            parse_module_decl(L);
        } else if (accept_kw(L, "struct") && !peek(L, "{")) {
            size_t save = L->cur->pos;
            size_t n = ident(L);
            L->cur->pos += n;
            bool def = peek(L, "{");
            L->cur->pos = save;
            if (def)
                parse_struct(L, pos);
            else {
                L->cur->pos = pos;
                t = parse_type(L);
                if (t < 0) {
                    expected(L, "a struct name");
                    recover(L);
                } else
                    parse_global(L, t);
            }
        } else if (accept_kw(L, "typedef")) {
            cbm__cerr(L->cur, pos, "typedef is not supported; declare `struct Name { ... };`");
            recover(L);
        } else if ((t = parse_type(L)) >= 0 || accept_kw(L, "void")) {
            if (t < 0)
                t = T_VOID;
            size_t n = ident(L);
            size_t save = L->cur->pos;
            L->cur->pos += n;
            bool fn = n && peek(L, "(");
            L->cur->pos = save;
            if (fn)
                parse_function(L, t, pos);
            else if (t == T_VOID) {
                expected(L, "a function");
                recover(L);
            } else
                parse_global(L, t);
        } else {
            size_t n = ident(L);
            if (n && find_mod(lp, L->text + L->cur->pos, n) >= 0)
                parse_production(L, set, group);
            else {
                expected(L, "a module declaration, a production or a section");
                recover(L);
            }
        }
    }
}

/* ---------------------------------------------------------------- entry points */
bool cbm__lc_detect(const cbm__pp *pp)
{
    if (pp->lpfg_lib)
        return true;
    const char *t = pp->text.data;
    for (const char *p = t; (p = strstr(p, "produce")) != NULL; p += 7)
        if ((p == t || !is_ident_char((unsigned char)p[-1])) && !is_ident_char((unsigned char)p[7]))
            return true;
    for (const char *p = t; (p = strstr(p, "module")) != NULL; p += 6)
        if ((p == t || p[-1] == '\n') && (p[6] == ' ' || p[6] == '\t'))
            return true;
    return false;
}

int cbm__lc_find_module(const lc_model *m, const char *s, size_t n)
{
    return find_mod(m, s, n);
}

cbm_status cbm__lc_compile(cbm__compiler *c, const char *text, lc_model *m)
{
    for (int i = 0; i < 4; i++)
        m->blocks[i] = -1;
    m->dlen_expr = -1;
    lc_parser L;
    memset(&L, 0, sizeof L);
    L.model = m;
    L.cur = c;
    L.text = text;
    cbm_status s = setup_builtins(&L);
    if (s == CBM_OK) {
        parse_top(&L);
        s = c->status;
    }
    CBM_ARRAY_FREE(c->ctx, L.vars);
    return s;
}

void cbm__lc_model_free(cbm_context *ctx, lc_model *m)
{
    for (size_t i = 0; i < m->types.len; i++) {
        cbm__strfree(ctx, m->types.data[i].name);
        for (int f = 0; f < m->types.data[i].nfields; f++)
            cbm__strfree(ctx, m->types.data[i].fname[f]);
    }
    CBM_ARRAY_FREE(ctx, m->types);
    for (size_t i = 0; i < m->mods.len; i++)
        cbm__strfree(ctx, m->mods.data[i].name);
    CBM_ARRAY_FREE(ctx, m->mods);
    for (size_t i = 0; i < m->funcs.len; i++)
        cbm__strfree(ctx, m->funcs.data[i].name);
    CBM_ARRAY_FREE(ctx, m->funcs);
    for (size_t i = 0; i < m->gvars.len; i++)
        cbm__strfree(ctx, m->gvars.data[i].name);
    CBM_ARRAY_FREE(ctx, m->gvars);
    for (size_t i = 0; i < m->funcnames.len; i++)
        cbm__strfree(ctx, m->funcnames.data[i]);
    CBM_ARRAY_FREE(ctx, m->funcnames);
    CBM_ARRAY_FREE(ctx, m->funcids);
    CBM_ARRAY_FREE(ctx, m->nodes);
    CBM_ARRAY_FREE(ctx, m->sms);
    CBM_ARRAY_FREE(ctx, m->main.prods);
    CBM_ARRAY_FREE(ctx, m->decomp.prods);
    CBM_ARRAY_FREE(ctx, m->interp.prods);
}
