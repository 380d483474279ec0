/* Expressions and statements of the cpfg dialect: parsing into a flat node array, and
 * evaluation.
 *
 * The grammar follows cpfg's (lsys_input.y): from lowest to highest precedence `?:` (right),
 * `||`, `&&`, `== !=` (also `<>`), `< <= > >=`, `+ -`, `* / %`, `^` (power, left-associative
 * as in cpfg, so 2^3^2 = 64), unary `-`, `!`. Trigonometric functions take and give degrees.
 * Statements: assignment to a variable or an array element, `if`/`else`, `while`, `do ...
 * while`, calls, blocks. A name is a formal parameter of the production being compiled or
 * else a global variable of the model (cpfg keeps one symbol table per L-system); reading a
 * global that is never assigned anywhere is an error. Nodes refer to their children by index,
 * so a compiled model is a few contiguous arrays; evaluation is a recursive walk whose depth
 * is bounded by the parser's max_expr_depth. `while` loops share an iteration budget so that
 * no model can hang the derivation.
 *
 * Random functions follow cpfg (utility.c): ran(x) = x * erand48, nran(m, s) the polar
 * Box-Muller method of Numerical Recipes producing values in pairs, bran(a, b) Cheng's beta
 * generator, biran(n, p) n coin flips, srand(s) resets the erand48 state to
 * {0x330E, s & 0xFFFF, s >> 16} and the pair cache.
 */
#include "lang/lang.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define DEG (3.14159265358979323846 / 180.0)

/* ---- rand48: X' = (a X + c) mod 2^48, a = 0x5DEECE66D, c = 0xB (POSIX) ---- */
void cbm__rand48_seed16(cbm__rand48 *r, uint16_t x0, uint16_t x1, uint16_t x2)
{
    r->x = (uint64_t)x0 | ((uint64_t)x1 << 16) | ((uint64_t)x2 << 32);
}

double cbm__rand48_next(cbm__rand48 *r)
{
    r->x = (r->x * 0x5DEECE66Dull + 0xBull) & 0xFFFFFFFFFFFFull;
    return ldexp((double)r->x, -48);
}

/* ---- compiler infrastructure ---- */
cbm_status cbm__compiler_init(cbm__compiler *c, cbm_context *ctx, cbm__pp *pp)
{
    memset(c, 0, sizeof *c);
    c->ctx = ctx;
    c->pp = pp;
    c->text = pp->text.data;
    c->status = CBM_OK;
    c->map.data = pp->lines.data;
    c->map.len = pp->lines.len;
    c->map.cap = pp->lines.cap;
    c->files.data = pp->files.data;
    c->files.len = pp->files.len;
    c->files.cap = pp->files.cap;
    memset(&pp->lines, 0, sizeof pp->lines);
    memset(&pp->files, 0, sizeof pp->files);
    size_t zero = 0;
    CBM_TRY(CBM_ARRAY_PUSH(ctx, c->line_start, zero));
    for (size_t i = 0; c->text[i]; i++)
        if (c->text[i] == '\n') {
            size_t s = i + 1;
            CBM_TRY(CBM_ARRAY_PUSH(ctx, c->line_start, s));
        }
    return CBM_OK;
}

void cbm__compiler_free(cbm__compiler *c)
{
    for (size_t i = 0; i < c->files.len; i++)
        cbm__strfree(c->ctx, c->files.data[i]);
    CBM_ARRAY_FREE(c->ctx, c->files);
    CBM_ARRAY_FREE(c->ctx, c->map);
    CBM_ARRAY_FREE(c->ctx, c->node_pos);
    for (size_t i = 0; i < c->globals.len; i++)
        cbm__strfree(c->ctx, c->globals.data[i]);
    CBM_ARRAY_FREE(c->ctx, c->globals);
    CBM_ARRAY_FREE(c->ctx, c->global_use);
    CBM_ARRAY_FREE(c->ctx, c->global_set);
    CBM_ARRAY_FREE(c->ctx, c->line_start);
    CBM_ARRAY_FREE(c->ctx, c->nodes);
    for (size_t i = 0; i < c->arrays.len; i++) {
        cbm__strfree(c->ctx, c->arrays.data[i].name);
        cbm__free(c->ctx, c->arrays.data[i].data, c->arrays.data[i].count * sizeof(double));
    }
    CBM_ARRAY_FREE(c->ctx, c->arrays);
    CBM_ARRAY_FREE(c->ctx, c->strings);
}

/* The index of the preprocessed line holding text position pos (binary search of line_start;
 * 0 when there are no lines). */
static size_t line_index(const cbm__compiler *c, size_t pos)
{
    size_t lo = 0, hi = c->line_start.len;
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (c->line_start.data[mid] <= pos)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

void cbm__cerr(cbm__compiler *c, size_t pos, const char *fmt, ...)
{
    c->errors++;
    if (c->errors >= cbm_context_limits(c->ctx)->max_diagnostics) {
        c->fatal = true;
        if (c->status == CBM_OK)
            c->status = CBM_E_SYNTAX;
    }
    const char *file;
    int line, col;
    cbm__compiler_locate(c, pos, &file, &line, &col);
    va_list ap;
    va_start(ap, fmt);
    cbm__vdiag(c->ctx, CBM_ERROR, file, line, col, fmt, ap);
    va_end(ap);
    /* the line expands a value given on the command line: say so, the error may be there */
    size_t lo = line_index(c, pos);
    if (lo < c->map.len && c->map.data[lo].define >= 0)
        cbm__diag(c->ctx, CBM_NOTE, file, line, col, "the line uses the command line's %s",
                  c->files.data[c->map.data[lo].define]);
}

void cbm__compiler_locate(const cbm__compiler *c, size_t pos, const char **file, int *line,
                          int *col)
{
    *file = NULL;
    *line = *col = 0;
    if (!c->line_start.len)
        return;
    size_t lo = line_index(c, pos);
    if (lo < c->map.len) {
        *file = c->files.data[c->map.data[lo].file];
        *line = c->map.data[lo].line;
    } else if (c->map.len) { /* the end of the text: after the last line */
        *file = c->files.data[c->map.data[c->map.len - 1].file];
        *line = c->map.data[c->map.len - 1].line;
    } else if (c->files.len) { /* an empty file */
        *file = c->files.data[0];
        *line = 1;
    }
    *col = (int)(pos - c->line_start.data[lo]) + 1;
}

size_t cbm__node_pos(const cbm__compiler *c, int32_t node)
{
    return node >= 0 && (size_t)node < c->node_pos.len ? (size_t)c->node_pos.data[node] : 0;
}

cbm_status cbm__compiler_fail(const cbm__compiler *c, cbm_status s, size_t pos, const char *fmt,
                              ...)
{
    const char *file;
    int line, col;
    cbm__compiler_locate(c, pos, &file, &line, &col);
    va_list ap;
    va_start(ap, fmt);
    cbm__vdiag(c->ctx, CBM_ERROR, file, line, col, fmt, ap);
    va_end(ap);
    return s;
}

void cbm__skip(cbm__compiler *c, bool nl)
{
    for (;;) {
        char ch = c->text[c->pos];
        if (ch == ' ' || ch == '\t' || ch == '\r')
            c->pos++;
        else if (ch == '\n' && (nl || c->text[c->pos + 1] == '\t'))
            c->pos++;
        else
            return;
    }
}

static const char *describe(const cbm__compiler *c, char *buf)
{
    char ch = c->text[c->pos];
    if (ch == 0)
        return "end of file";
    if (ch == '\n')
        return "end of line";
    if (!strncmp(c->text + c->pos, "-->", 3))
        return "'-->'";
    if (isprint((unsigned char)ch))
        snprintf(buf, 16, "'%c'", ch);
    else
        snprintf(buf, 16, "byte 0x%02x", (unsigned char)ch);
    return buf;
}

static void expected(cbm__compiler *c, const char *what)
{
    char buf[16];
    cbm__cerr(c, c->pos, "expected %s, found %s", what, describe(c, buf));
}

static int32_t add_node(cbm__compiler *c, cbm__node n)
{
    if (c->status != CBM_OK && c->status != CBM_E_SYNTAX)
        return -1;
    int32_t at = (int32_t)(c->pos < INT32_MAX ? c->pos : INT32_MAX);
    if (CBM_ARRAY_PUSH(c->ctx, c->nodes, n) != CBM_OK ||
        CBM_ARRAY_PUSH(c->ctx, c->node_pos, at) != CBM_OK) {
        c->status = CBM_E_NOMEM;
        c->fatal = true;
        return -1;
    }
    return (int32_t)c->nodes.len - 1;
}

bool cbm__string_lit(cbm__compiler *c, size_t *off)
{
    size_t start = c->pos++;
    size_t body = c->pos;
    while (c->text[c->pos] && c->text[c->pos] != '"' && c->text[c->pos] != '\n')
        c->pos += c->text[c->pos] == '\\' && c->text[c->pos + 1] ? 2 : 1;
    if (c->text[c->pos] != '"') {
        cbm__cerr(c, start, "unterminated string");
        return false;
    }
    size_t n = c->pos++ - body;
    *off = c->strings.len;
    if ((c->status = CBM_ARRAY_RESERVE(c->ctx, c->strings, *off + n + 1)) != CBM_OK) {
        c->fatal = true;
        return false;
    }
    c->strings.len = *off + cbm__unescape(c->text + body, n, c->strings.data + *off);
    c->strings.data[c->strings.len++] = 0;
    return true;
}

/* A string literal at the cursor (a printf argument), as an OP_STR node. */
static int32_t string_literal(cbm__compiler *c)
{
    size_t off;
    if (!cbm__string_lit(c, &off))
        return -1;
    cbm__node nd = {.op = OP_STR, .a = -1, .b = -1, .c = -1, .next = -1, .slot = (int32_t)off};
    return add_node(c, nd);
}

static bool no_strings(cbm__compiler *c, int32_t first)
{
    for (int32_t i = first; i >= 0; i = c->nodes.data[i].next)
        if (c->nodes.data[i].op == OP_STR) {
            cbm__cerr(c, c->pos, "a string is only an argument of printf");
            return false;
        }
    return true;
}

/* printf(format, args...): the format is a string literal whose conversions match the arguments. */
static bool check_printf(cbm__compiler *c, size_t pos, int32_t first, int nargs)
{
    if (first < 0 || c->nodes.data[first].op != OP_STR) {
        cbm__cerr(c, pos, "printf needs a format string as its first argument");
        return false;
    }
    uint8_t kinds[CBM__FMT_MAX_ARGS];
    char err[128];
    int n = cbm__fmt_scan(c->strings.data + c->nodes.data[first].slot, kinds, CBM__FMT_MAX_ARGS,
                          err, sizeof err);
    if (n < 0) {
        cbm__cerr(c, pos, "%s", err);
        return false;
    }
    if (n != nargs - 1) {
        cbm__cerr(c, pos, "printf: the format has %d conversion%s, %d argument%s given", n,
                  n == 1 ? "" : "s", nargs - 1, nargs - 1 == 1 ? "" : "s");
        return false;
    }
    int k = 0;
    for (int32_t i = c->nodes.data[first].next; i >= 0; i = c->nodes.data[i].next, k++)
        if ((c->nodes.data[i].op == OP_STR) != (kinds[k] == CBM__FMT_STR)) {
            cbm__cerr(c, pos, "printf: argument %d %s", k + 2,
                      kinds[k] == CBM__FMT_STR ? "of %s must be a string literal"
                                               : "is a string; only %s prints a string");
            return false;
        }
    return true;
}

static int32_t node2(cbm__compiler *c, int op, int32_t a, int32_t b)
{
    if (a < 0 || b < 0)
        return -1;
    cbm__node n = {.op = (uint8_t)op, .a = a, .b = b, .c = -1, .next = -1, .slot = -1};
    return add_node(c, n);
}

int32_t cbm__node_num(cbm__compiler *c, double v)
{
    cbm__node n = {.op = OP_NUM, .a = -1, .b = -1, .c = -1, .next = -1, .slot = -1, .v = v};
    return add_node(c, n);
}

bool cbm__node_const(const cbm__compiler *c, int32_t i, double *v)
{
    if (i < 0)
        return false;
    const cbm__node *n = &c->nodes.data[i];
    if (n->op == OP_NUM) {
        *v = n->v;
        return true;
    }
    double a, b;
    if (n->op == OP_NEG && cbm__node_const(c, n->a, &a)) {
        *v = -a;
        return true;
    }
    if (n->op >= OP_ADD && n->op <= OP_DIV && cbm__node_const(c, n->a, &a) &&
        cbm__node_const(c, n->b, &b)) {
        *v = n->op == OP_ADD ? a + b : n->op == OP_SUB ? a - b : n->op == OP_MUL ? a * b : a / b;
        return true;
    }
    return false;
}

static bool match(cbm__compiler *c, const char *s, bool nl)
{
    cbm__skip(c, nl);
    size_t n = strlen(s);
    if (strncmp(c->text + c->pos, s, n) != 0)
        return false;
    c->pos += n;
    return true;
}

static int32_t global_slot(cbm__compiler *c, const char *name, size_t len, bool assign, size_t pos)
{
    for (size_t i = 0; i < c->globals.len; i++)
        if (strlen(c->globals.data[i]) == len && !memcmp(c->globals.data[i], name, len)) {
            if (assign)
                c->global_set.data[i] = 1;
            return (int32_t)i;
        }
    char *d = cbm__alloc(c->ctx, len + 1);
    if (!d) {
        c->status = CBM_E_NOMEM;
        c->fatal = true;
        return -1;
    }
    memcpy(d, name, len);
    d[len] = 0;
    uint8_t set = assign;
    int32_t use = (int32_t)pos;
    if (CBM_ARRAY_PUSH(c->ctx, c->globals, d) != CBM_OK ||
        CBM_ARRAY_PUSH(c->ctx, c->global_set, set) != CBM_OK ||
        CBM_ARRAY_PUSH(c->ctx, c->global_use, use) != CBM_OK) {
        if (c->globals.len == 0 || c->globals.data[c->globals.len - 1] != d)
            cbm__strfree(c->ctx, d);
        c->status = CBM_E_NOMEM;
        c->fatal = true;
        return -1;
    }
    return (int32_t)c->globals.len - 1;
}

void cbm__check_globals(cbm__compiler *c)
{
    for (size_t i = 0; i < c->globals.len; i++)
        if (!c->global_set.data[i] && strcmp(c->globals.data[i], "Q") != 0)
            cbm__cerr(c, (size_t)c->global_use.data[i],
                      "undefined name '%s' (not a parameter of the predecessor, a #define, or "
                      "a variable assigned anywhere)",
                      c->globals.data[i]);
}

static int find_array(const cbm__compiler *c, const char *name, size_t len)
{
    for (size_t i = 0; i < c->arrays.len; i++)
        if (strlen(c->arrays.data[i].name) == len && !memcmp(c->arrays.data[i].name, name, len))
            return (int)i;
    return -1;
}

static const struct {
    const char *name;
    int fn, nargs;
} FUNCS[] = {
    {"sin", FN_SIN, 1},   {"cos", FN_COS, 1},        {"tan", FN_TAN, 1},     {"asin", FN_ASIN, 1},
    {"acos", FN_ACOS, 1}, {"atan", FN_ATAN, 1},      {"atan2", FN_ATAN2, 2}, {"exp", FN_EXP, 1},
    {"log", FN_LOG, 1},   {"floor", FN_FLOOR, 1},    {"ceil", FN_CEIL, 1},   {"sign", FN_SIGN, 1},
    {"sqrt", FN_SQRT, 1}, {"trunc", FN_TRUNC, 1},    {"fabs", FN_FABS, 1},   {"ran", FN_RAN, 1},
    {"nran", FN_NRAN, 2}, {"bran", FN_BRAN, 2},      {"biran", FN_BIRAN, 2}, {"srand", FN_SRAND, 1},
    {"func", FN_FUNC, 2}, {"printf", FN_PRINTF, -1}, {"stop", FN_STOP, -1}};

static int32_t parse_ternary(cbm__compiler *c, bool nl);

/* Parses `[e1][e2]...` indices (at '['), returns the chain. */
static int32_t parse_indices(cbm__compiler *c, bool nl, int *count)
{
    int32_t first = -1, last = -1;
    *count = 0;
    while (match(c, "[", nl)) {
        int32_t e = parse_ternary(c, true);
        if (e < 0)
            return -1;
        if (!match(c, "]", true)) {
            expected(c, "']'");
            return -1;
        }
        if (last >= 0)
            c->nodes.data[last].next = e;
        else
            first = e;
        last = e;
        (*count)++;
    }
    return first;
}

static int32_t parse_primary(cbm__compiler *c, bool nl)
{
    cbm__skip(c, nl);
    size_t start = c->pos;
    const char *t = c->text + c->pos;
    if (isdigit((unsigned char)*t) || (*t == '.' && isdigit((unsigned char)t[1]))) {
        char *end;
        double v = strtod(t, &end);
        c->pos += (size_t)(end - t);
        return cbm__node_num(c, v);
    }
    if (*t == '(') {
        c->pos++;
        int32_t e = parse_ternary(c, nl);
        if (e < 0)
            return -1;
        if (!match(c, ")", nl)) {
            expected(c, "')'");
            return -1;
        }
        return e;
    }
    if (isalpha((unsigned char)*t) || *t == '_') {
        while (isalnum((unsigned char)c->text[c->pos]) || c->text[c->pos] == '_')
            c->pos++;
        size_t len = c->pos - start;
        for (size_t i = 0; i < sizeof FUNCS / sizeof FUNCS[0]; i++) {
            if (strlen(FUNCS[i].name) != len || memcmp(FUNCS[i].name, t, len))
                continue;
            if (!match(c, "(", nl)) {
                expected(c, "'(' after a function name");
                return -1;
            }
            int32_t first = -1, last = -1;
            int n = 0;
            cbm__skip(c, nl);
            if (c->text[c->pos] != ')') {
                for (;;) {
                    int32_t a;
                    cbm__skip(c, nl);
                    if (c->text[c->pos] == '"')
                        a = string_literal(c);
                    else
                        a = parse_ternary(c, nl);
                    if (a < 0)
                        return -1;
                    if (last >= 0)
                        c->nodes.data[last].next = a;
                    else
                        first = a;
                    last = a;
                    n++;
                    if (!match(c, ",", nl))
                        break;
                }
            }
            if (!match(c, ")", nl)) {
                expected(c, "')' or ',' in the arguments");
                return -1;
            }
            if (FUNCS[i].fn == FN_PRINTF ? !check_printf(c, start, first, n)
                                         : !no_strings(c, first))
                return -1;
            if (FUNCS[i].nargs >= 0 && n != FUNCS[i].nargs) {
                cbm__cerr(c, start, "%s() takes %d argument%s, %d given", FUNCS[i].name,
                          FUNCS[i].nargs, FUNCS[i].nargs == 1 ? "" : "s", n);
                return -1;
            }
            cbm__node nd = {.op = OP_CALL,
                            .fn = (uint8_t)FUNCS[i].fn,
                            .a = first,
                            .b = -1,
                            .c = -1,
                            .next = -1,
                            .slot = n};
            return add_node(c, nd);
        }
        for (int i = 0; i < c->nformals; i++)
            if (c->formal_len[i] == len && !memcmp(c->formals[i], t, len)) {
                cbm__node nd = {.op = OP_PARAM, .a = -1, .b = -1, .c = -1, .next = -1, .slot = i};
                return add_node(c, nd);
            }
        int ai = find_array(c, t, len);
        if (ai >= 0) {
            int count;
            int32_t idx = parse_indices(c, nl, &count);
            if (count != c->arrays.data[ai].ndims) {
                cbm__cerr(c, start, "array '%s' has %d dimension%s, %d index%s given",
                          c->arrays.data[ai].name, c->arrays.data[ai].ndims,
                          c->arrays.data[ai].ndims == 1 ? "" : "s", count, count == 1 ? "" : "es");
                return -1;
            }
            cbm__node nd = {.op = OP_ARRAY, .a = idx, .b = -1, .c = -1, .next = -1, .slot = ai};
            return add_node(c, nd);
        }
        int32_t g = global_slot(c, t, len, false, start);
        if (g < 0)
            return -1;
        cbm__node nd = {.op = OP_GLOBAL, .a = -1, .b = -1, .c = -1, .next = -1, .slot = g};
        return add_node(c, nd);
    }
    expected(c, "an expression");
    return -1;
}

/* One more level of nesting (parentheses, operators of a chain, ?:, else if, blocks): false
 * after reporting that the limit is exceeded (the depth is then unchanged). Parsing and
 * evaluation recurse once per level, so this bounds both. */
static bool deeper(cbm__compiler *c)
{
    if (++c->depth > cbm_context_limits(c->ctx)->max_expr_depth) {
        cbm__cerr(c, c->pos,
                  "expression or statement nested too deeply (limit %d, --max-expr-depth)",
                  cbm_context_limits(c->ctx)->max_expr_depth);
        c->fatal = true;
        c->depth--;
        return false;
    }
    return true;
}

static int32_t parse_unary(cbm__compiler *c, bool nl)
{
    cbm__skip(c, nl);
    if (!deeper(c))
        return -1;
    int32_t r;
    char ch = c->text[c->pos];
    if (ch == '-' && c->text[c->pos + 1] != '-') {
        c->pos++;
        r = node2(c, OP_NEG, parse_unary(c, nl), 0);
    } else if (ch == '+') {
        c->pos++;
        r = parse_unary(c, nl);
    } else if (ch == '!' && c->text[c->pos + 1] != '=') {
        c->pos++;
        r = node2(c, OP_NOT, parse_unary(c, nl), 0);
    } else {
        r = parse_primary(c, nl);
    }
    c->depth--;
    return r;
}

/* binary levels, lowest first */
static int32_t parse_binary(cbm__compiler *c, bool nl, int level)
{
    static const struct {
        const char *tok;
        int op;
        int level;
    } OPS[] = {{"||", OP_OR, 0}, {"&&", OP_AND, 1}, {"==", OP_EQ, 2}, {"!=", OP_NE, 2},
               {"<>", OP_NE, 2}, {"<=", OP_LE, 3},  {">=", OP_GE, 3}, {"<", OP_LT, 3},
               {">", OP_GT, 3},  {"+", OP_ADD, 4},  {"-", OP_SUB, 4}, {"*", OP_MUL, 5},
               {"/", OP_DIV, 5}, {"%", OP_REM, 5},  {"^", OP_POW, 6}};
    if (level > 6)
        return parse_unary(c, nl);
    int32_t left = parse_binary(c, nl, level + 1);
    int chain = 0;
    for (;;) {
        if (left < 0) {
            c->depth -= chain;
            return -1;
        }
        cbm__skip(c, nl);
        const char *t = c->text + c->pos;
        if (t[0] == '-' && t[1] == '-' && t[2] == '>') {
            c->depth -= chain;
            return left; /* the arrow of a production */
        }
        int op = -1;
        size_t n = 0;
        for (size_t i = 0; i < sizeof OPS / sizeof OPS[0]; i++)
            if (OPS[i].level == level && !strncmp(t, OPS[i].tok, strlen(OPS[i].tok))) {
                op = OPS[i].op;
                n = strlen(OPS[i].tok);
                break;
            }
        if (op < 0 ||
            ((op == OP_LT || op == OP_GT) && (t[1] == '=' || (op == OP_LT && t[1] == '>')))) {
            c->depth -= chain;
            return left;
        }
        /* a chain a+b+c... is a left-deep tree evaluated recursively: each operator nests */
        if (!deeper(c)) {
            c->depth -= chain;
            return -1;
        }
        chain++;
        c->pos += n;
        left = node2(c, op, left, parse_binary(c, nl, level + 1));
    }
}

static int32_t parse_cond(cbm__compiler *c, bool nl)
{
    int32_t cond = parse_binary(c, nl, 0);
    if (cond < 0)
        return -1;
    if (!match(c, "?", nl))
        return cond;
    int32_t a = parse_ternary(c, true);
    if (a < 0)
        return -1;
    if (!match(c, ":", true)) {
        expected(c, "':' of the conditional expression");
        return -1;
    }
    int32_t b = parse_ternary(c, nl);
    int32_t n = node2(c, OP_COND, cond, a);
    if (n >= 0 && b >= 0) {
        c->nodes.data[n].c = b;
        return n;
    }
    return -1;
}

/* An expression: `?:` chains (a ? b : c ? d : ...) nest like parentheses. The node gets the
 * position where the expression starts, for runtime messages about its value. */
static int32_t parse_ternary(cbm__compiler *c, bool nl)
{
    cbm__skip(c, nl);
    size_t start = c->pos;
    if (!deeper(c))
        return -1;
    int32_t r = parse_cond(c, nl);
    c->depth--;
    if (r >= 0 && (size_t)r < c->node_pos.len)
        c->node_pos.data[r] = (int32_t)(start < INT32_MAX ? start : INT32_MAX);
    return r;
}

int32_t cbm__parse_expr(cbm__compiler *c, bool nl)
{
    return parse_ternary(c, nl);
}

/* ---- statements ---- */
static void recover(cbm__compiler *c)
{
    int level = 0;
    while (c->text[c->pos]) {
        char ch = c->text[c->pos];
        if (ch == '{')
            level++;
        if (ch == '}') {
            if (level == 0)
                return;
            level--;
        }
        c->pos++;
        if (ch == ';' && level == 0)
            return;
    }
}

static int32_t parse_statement(cbm__compiler *c, bool *ok);

static int32_t parse_body(cbm__compiler *c, bool *ok)
{
    cbm__skip(c, true);
    if (c->text[c->pos] == '{')
        return cbm__parse_block(c, ok);
    return parse_statement(c, ok);
}

/* "( condition )" of if, while and do: the condition's node, or -1 after reporting what was
 * expected and skipping to a recovery point. */
static int32_t parse_paren_cond(cbm__compiler *c, bool *ok, const char *open_what)
{
    if (!match(c, "(", true)) {
        expected(c, open_what);
        *ok = false;
        recover(c);
        return -1;
    }
    int32_t cond = parse_ternary(c, true);
    if (cond < 0 || !match(c, ")", true)) {
        if (cond >= 0)
            expected(c, "')'");
        *ok = false;
        recover(c);
        return -1;
    }
    return cond;
}

static int32_t parse_statement1(cbm__compiler *c, bool *ok);

/* A statement; if, while and do nest (an else-if chain is as deep as it is long). */
static int32_t parse_statement(cbm__compiler *c, bool *ok)
{
    if (!deeper(c)) {
        *ok = false;
        return -1;
    }
    int32_t r = parse_statement1(c, ok);
    c->depth--;
    return r;
}

static int32_t parse_statement1(cbm__compiler *c, bool *ok)
{
    cbm__skip(c, true);
    size_t start = c->pos;
    const char *t = c->text + c->pos;
    if (*t == ';') {
        c->pos++;
        return -1;
    }
    if (*t == '{')
        return cbm__parse_block(c, ok);
    size_t len = 0;
    while (isalnum((unsigned char)t[len]) || t[len] == '_')
        len++;
#define KW(w) (len == strlen(w) && !memcmp(t, w, len))
    if (KW("if") || KW("while")) {
        bool is_if = KW("if");
        c->pos += len;
        int32_t cond = parse_paren_cond(c, ok, is_if ? "'(' after if" : "'(' after while");
        if (cond < 0)
            return -1;
        int32_t body = parse_body(c, ok);
        int32_t other = -1;
        if (is_if) {
            size_t save = c->pos;
            cbm__skip(c, true);
            if (!strncmp(c->text + c->pos, "else", 4) &&
                !isalnum((unsigned char)c->text[c->pos + 4])) {
                c->pos += 4;
                other = parse_body(c, ok);
            } else {
                c->pos = save;
            }
        }
        cbm__node n = {.op = (uint8_t)(is_if ? OP_IF : OP_WHILE),
                       .a = cond,
                       .b = body,
                       .c = other,
                       .next = -1,
                       .slot = -1};
        return add_node(c, n);
    }
    if (KW("do")) {
        c->pos += len;
        int32_t body = parse_body(c, ok);
        cbm__skip(c, true);
        if (strncmp(c->text + c->pos, "while", 5) != 0) {
            expected(c, "'while' after the body of do");
            *ok = false;
            recover(c);
            return -1;
        }
        c->pos += 5;
        int32_t cond = parse_paren_cond(c, ok, "'('");
        if (cond < 0)
            return -1;
        match(c, ";", true);
        cbm__node n = {.op = OP_DO, .a = cond, .b = body, .c = -1, .next = -1, .slot = -1};
        return add_node(c, n);
    }
#undef KW
    /* assignment? name [indices] = expr ; */
    if (len > 0 && !isdigit((unsigned char)*t)) {
        size_t save = c->pos;
        c->pos += len;
        int ai = find_array(c, t, len);
        int count = 0;
        int32_t idx = -1;
        if (ai >= 0) {
            idx = parse_indices(c, true, &count);
        }
        cbm__skip(c, true);
        if (c->text[c->pos] == '=' && c->text[c->pos + 1] != '=') {
            c->pos++;
            int32_t val = parse_ternary(c, true);
            if (val < 0) {
                *ok = false;
                recover(c);
                return -1;
            }
            if (!match(c, ";", true)) {
                expected(c, "';' after the assignment");
                *ok = false;
                recover(c);
                return -1;
            }
            for (int i = 0; i < c->nformals; i++)
                if (c->formal_len[i] == len && !memcmp(c->formals[i], t, len)) {
                    /* as in cpfg, a parameter may be changed before the successor uses it */
                    cbm__node n = {
                        .op = OP_ASSIGN_PARAM, .a = val, .b = -1, .c = -1, .next = -1, .slot = i};
                    return add_node(c, n);
                }
            if (ai >= 0) {
                if (count != c->arrays.data[ai].ndims) {
                    cbm__cerr(c, start, "array '%s' needs %d index%s", c->arrays.data[ai].name,
                              c->arrays.data[ai].ndims, c->arrays.data[ai].ndims == 1 ? "" : "es");
                    *ok = false;
                    return -1;
                }
                cbm__node n = {
                    .op = OP_ASSIGN_ARRAY, .a = val, .b = idx, .c = -1, .next = -1, .slot = ai};
                return add_node(c, n);
            }
            int32_t g = global_slot(c, t, len, true, start);
            cbm__node n = {.op = OP_ASSIGN, .a = val, .b = -1, .c = -1, .next = -1, .slot = g};
            return g < 0 ? -1 : add_node(c, n);
        }
        c->pos = save;
    }
    int32_t e = parse_ternary(c, true);
    if (e < 0) {
        *ok = false;
        recover(c);
        return -1;
    }
    if (!match(c, ";", true)) {
        cbm__skip(c, true);
        if (c->text[c->pos] != '}') { /* cpfg accepts a last statement without ';' */
            expected(c, "';' after the statement");
            *ok = false;
            recover(c);
            return -1;
        }
    }
    return e;
}

int32_t cbm__parse_block(cbm__compiler *c, bool *ok)
{
    *ok = true;
    if (!match(c, "{", true)) {
        expected(c, "'{'");
        *ok = false;
        return -1;
    }
    if (!deeper(c)) {
        *ok = false;
        return -1;
    }
    int32_t first = -1, last = -1;
    for (;;) {
        cbm__skip(c, true);
        if (c->text[c->pos] == '}') {
            c->pos++;
            break;
        }
        if (!c->text[c->pos] || c->fatal) {
            expected(c, "'}' closing the block");
            *ok = false;
            break;
        }
        bool sok = true;
        int32_t s = parse_statement(c, &sok);
        if (!sok)
            *ok = false;
        if (s < 0)
            continue;
        /* wrap expressions and nested chains in a sequence node so `next` is free */
        cbm__node seq = {.op = OP_SEQ, .a = s, .b = -1, .c = -1, .next = -1, .slot = -1};
        int32_t w = add_node(c, seq);
        if (w < 0)
            break;
        if (last >= 0)
            c->nodes.data[last].next = w;
        else
            first = w;
        last = w;
    }
    c->depth--;
    return first;
}

bool cbm__parse_define_block(cbm__compiler *c)
{
    if (!match(c, "{", true)) {
        expected(c, "'{' after define:");
        return false;
    }
    bool ok = true;
    for (;;) {
        cbm__skip(c, true);
        const char *t = c->text + c->pos;
        if (*t == '}') {
            c->pos++;
            return ok;
        }
        if (!*t || c->fatal) {
            expected(c, "'}' closing the define block");
            return false;
        }
        if (*t == ';') {
            c->pos++;
            continue;
        }
        if (strncmp(t, "array", 5) != 0 || isalnum((unsigned char)t[5])) {
            expected(c, "'array' declaration");
            ok = false;
            recover(c);
            continue;
        }
        c->pos += 5;
        for (;;) { /* array a[n][m] = {...}, b[k] ... ; */
            cbm__skip(c, true);
            size_t start = c->pos;
            while (isalnum((unsigned char)c->text[c->pos]) || c->text[c->pos] == '_')
                c->pos++;
            size_t len = c->pos - start;
            if (len == 0 || isdigit((unsigned char)c->text[start])) {
                expected(c, "an array name");
                ok = false;
                recover(c);
                break;
            }
            cbm__array a = {0};
            size_t count = 1;
            bool aok = true;
            while (match(c, "[", true)) {
                int32_t e = parse_ternary(c, true);
                double v = 0;
                if (e < 0 || !cbm__node_const(c, e, &v) || v < 1 || v > 1e7 || a.ndims >= 4) {
                    if (e >= 0)
                        cbm__cerr(c, start,
                                  "array '%.*s': each size must be a constant "
                                  "from 1 to 10^7, at most 4 dimensions",
                                  (int)len, c->text + start);
                    aok = false;
                    break;
                }
                a.dims[a.ndims++] = (int)v;
                count *= (size_t)v;
                if (!match(c, "]", true)) {
                    expected(c, "']'");
                    aok = false;
                    break;
                }
            }
            if (aok && (a.ndims == 0 || count > 10000000)) {
                cbm__cerr(c, start, "array '%.*s' needs its sizes, at most 10^7 elements", (int)len,
                          c->text + start);
                aok = false;
            }
            if (!aok) {
                ok = false;
                recover(c);
                break;
            }
            a.name = cbm__alloc(c->ctx, len + 1);
            a.data = cbm__calloc(c->ctx, count, sizeof(double));
            if (!a.name || !a.data) {
                cbm__free(c->ctx, a.name, len + 1);
                cbm__free(c->ctx, a.data, count * sizeof(double));
                c->status = CBM_E_NOMEM;
                c->fatal = true;
                return false;
            }
            memcpy(a.name, c->text + start, len);
            a.name[len] = 0;
            a.count = count;
            if (CBM_ARRAY_PUSH(c->ctx, c->arrays, a) != CBM_OK) {
                cbm__strfree(c->ctx, a.name);
                cbm__free(c->ctx, a.data, count * sizeof(double));
                c->status = CBM_E_NOMEM;
                c->fatal = true;
                return false;
            }
            cbm__array *ar = &c->arrays.data[c->arrays.len - 1];
            if (match(c, "=", true)) {
                if (!match(c, "{", true)) {
                    expected(c, "'{' with the initial values");
                    ok = false;
                    recover(c);
                    break;
                }
                size_t k = 0;
                for (;;) {
                    cbm__skip(c, true);
                    if (c->text[c->pos] == '{' || c->text[c->pos] == '}') { /* nested braces */
                        c->pos++;
                        continue;
                    }
                    if (c->text[c->pos] == ',') {
                        c->pos++;
                        continue;
                    }
                    if (c->text[c->pos] == ';' || !c->text[c->pos])
                        break;
                    int32_t e = parse_ternary(c, true);
                    double v;
                    if (e < 0 || !cbm__node_const(c, e, &v)) {
                        if (e >= 0)
                            cbm__cerr(c, c->pos, "array initial values must be constants");
                        ok = false;
                        recover(c);
                        return ok;
                    }
                    if (k >= ar->count) {
                        cbm__cerr(c, c->pos, "too many initial values for array '%s' (%zu)",
                                  ar->name, ar->count);
                        ok = false;
                        recover(c);
                        return ok;
                    }
                    ar->data[k++] = v;
                }
            }
            if (match(c, ",", true))
                continue;
            if (!match(c, ";", true)) {
                expected(c, "';' after the array declaration");
                ok = false;
                recover(c);
            }
            break;
        }
    }
}

/* ---- evaluation ---- */
static double nran(cbm__eval *e, double mean, double sd)
{
    if (e->nran_have == 0) {
        double v1, v2, rsq;
        do {
            v1 = 2.0 * cbm__rand48_next(&e->ran) - 1.0;
            v2 = 2.0 * cbm__rand48_next(&e->ran) - 1.0;
            rsq = v1 * v1 + v2 * v2;
        } while (rsq >= 1.0 || rsq == 0.0);
        double fac = sqrt(-2.0 * log(rsq) / rsq);
        e->nran_cached = v1 * fac;
        e->nran_have = 1;
        return v2 * fac * sd + mean;
    }
    e->nran_have = 0;
    return e->nran_cached * sd + mean;
}

static double bran(cbm__eval *e, double a, double b)
{
    double s = a + b, lambda;
    double mn = a < b ? a : b;
    if (mn <= 1)
        lambda = mn;
    else
        lambda = sqrt((2 * a * b - s) / (s - 2));
    double u = a + lambda, U1, U2, V, Ym;
    long guard = 0;
    do {
        do {
            U1 = cbm__rand48_next(&e->ran);
        } while (U1 == 0);
        do {
            U2 = cbm__rand48_next(&e->ran);
        } while (U2 == 0);
        V = (1 / lambda) * log(U1 / (1 - U1));
        Ym = a * exp(V);
        if (++guard > 1000000 || !(lambda > 0)) {
            e->error = CBM_E_RUNTIME;
            e->error_msg = "bran(a, b): the parameters must be positive";
            return 0;
        }
    } while (s * log(s / (b + Ym)) + u * V - log(4) < log(U1 * U1 * U2));
    return Ym / (b + Ym);
}

static void print(cbm__eval *e, const cbm__node *n)
{
    cbm__fmt_arg a[CBM__FMT_MAX_ARGS];
    int k = 0;
    const char *fmt = e->strings ? e->strings + e->nodes[n->a].slot : "";
    for (int32_t i = e->nodes[n->a].next; i >= 0 && k < CBM__FMT_MAX_ARGS;
         i = e->nodes[i].next, k++) {
        const cbm__node *x = &e->nodes[i];
        a[k].s = x->op == OP_STR && e->strings ? e->strings + x->slot : NULL;
        a[k].v = x->op == OP_STR ? 0 : cbm__eval_expr(e, i);
    }
    cbm__fmt_print(e->ctx, fmt, a, k);
}

static double call(cbm__eval *e, const cbm__node *n)
{
    if (n->fn == FN_PRINTF) {
        print(e, n);
        return 0;
    }
    double a[8] = {0};
    int k = 0;
    for (int32_t i = n->a; i >= 0 && k < 8; i = e->nodes[i].next)
        a[k++] = cbm__eval_expr(e, i);
    switch (n->fn) {
    case FN_SIN:
        return sin(a[0] * DEG);
    case FN_COS:
        return cos(a[0] * DEG);
    case FN_TAN:
        return tan(a[0] * DEG);
    case FN_ASIN:
        return asin(a[0]) / DEG;
    case FN_ACOS:
        return acos(a[0]) / DEG;
    case FN_ATAN:
        return atan(a[0]) / DEG;
    case FN_ATAN2:
        return atan2(a[0], a[1]) / DEG;
    case FN_EXP:
        return exp(a[0]);
    case FN_LOG:
        return log(a[0]);
    case FN_FLOOR:
        return floor(a[0]);
    case FN_CEIL:
        return ceil(a[0]);
    case FN_SIGN:
        return a[0] > 0 ? 1 : a[0] < 0 ? -1 : 0;
    case FN_SQRT:
        return sqrt(a[0]);
    case FN_TRUNC:
        return trunc(a[0]);
    case FN_FABS:
        return fabs(a[0]);
    case FN_RAN:
        return cbm__rand48_next(&e->ran) * a[0];
    case FN_NRAN:
        return nran(e, a[0], a[1]);
    case FN_BRAN:
        return bran(e, a[0], a[1]);
    case FN_BIRAN: {
        double n2 = a[0];
        if (!(n2 < 1e8) || !(n2 > -1e8)) {
            e->error = CBM_E_RUNTIME;
            e->error_msg = "biran(n, p): n is too large";
            return 0;
        }
        /* n draws: operations of the step's budget like loop iterations */
        if (n2 > 0 && (e->while_budget -= (long)n2) < 0) {
            e->error = CBM_E_LIMIT;
            e->error_msg = "biran(n, p) draws more than the step's limit of operations "
                           "(--max-loop-iterations, --max-operations)";
            return 0;
        }
        int j = 0;
        for (int i = 1; i <= (int)n2; i++)
            j += cbm__rand48_next(&e->ran) <= a[1];
        return j;
    }
    case FN_SRAND: {
        long long s = cbm__to_ll(a[0]);
        cbm__rand48_seed16(&e->ran, 0x330E, (uint16_t)(s & 0xFFFF), (uint16_t)((s >> 16) & 0xFFFF));
        e->nran_have = 0;
        return 0;
    }
    case FN_FUNC:
        if (!e->func) {
            e->error = CBM_E_RUNTIME;
            e->error_msg = "func(id, x) needs function files (.func or .fset) on the command line";
            return 0;
        }
        return e->func(e->func_ud,
                       (int)cbm__to_ll(a[0] > 1e9    ? 1e9
                                       : a[0] < -1e9 ? -1e9
                                                     : a[0]),
                       a[1]);
    case FN_STOP:
        e->stopped = true;
        return 0;
    default:
        return 0; /* printf: the library does not print */
    }
}

static double *array_elem(cbm__eval *e, const cbm__node *n, int32_t idx)
{
    cbm__array *ar = &e->arrays[n->slot];
    size_t off = 0;
    int d = 0;
    for (int32_t i = idx; i >= 0; i = e->nodes[i].next, d++) {
        double v = cbm__eval_expr(e, i);
        if (!(v >= 0 && v < ar->dims[d])) {
            if (e->error == CBM_OK) {
                e->error = CBM_E_RUNTIME;
                e->error_msg = "array index out of range";
                e->error_node = (int32_t)(n - e->nodes);
            }
            return NULL;
        }
        off = off * (size_t)ar->dims[d] + (size_t)v;
    }
    return &ar->data[off];
}

double cbm__eval_expr(cbm__eval *e, int32_t i)
{
    const cbm__node *n = &e->nodes[i];
    switch ((cbm__op)n->op) {
    case OP_NUM:
        return n->v;
    case OP_PARAM:
        return e->params[n->slot];
    case OP_GLOBAL:
        return e->globals[n->slot];
    case OP_ARRAY: {
        double *p = array_elem(e, n, n->a);
        return p ? *p : 0;
    }
    case OP_NEG:
        return -cbm__eval_expr(e, n->a);
    case OP_NOT:
        return !cbm__eval_expr(e, n->a);
    case OP_ADD:
        return cbm__eval_expr(e, n->a) + cbm__eval_expr(e, n->b);
    case OP_SUB:
        return cbm__eval_expr(e, n->a) - cbm__eval_expr(e, n->b);
    case OP_MUL:
        return cbm__eval_expr(e, n->a) * cbm__eval_expr(e, n->b);
    case OP_DIV:
        return cbm__eval_expr(e, n->a) / cbm__eval_expr(e, n->b);
    case OP_REM:
        return fmod(cbm__eval_expr(e, n->a), cbm__eval_expr(e, n->b));
    case OP_POW:
        return pow(cbm__eval_expr(e, n->a), cbm__eval_expr(e, n->b));
    case OP_LT:
        return cbm__eval_expr(e, n->a) < cbm__eval_expr(e, n->b);
    case OP_GT:
        return cbm__eval_expr(e, n->a) > cbm__eval_expr(e, n->b);
    case OP_LE:
        return cbm__eval_expr(e, n->a) <= cbm__eval_expr(e, n->b);
    case OP_GE:
        return cbm__eval_expr(e, n->a) >= cbm__eval_expr(e, n->b);
    case OP_EQ:
        return cbm__eval_expr(e, n->a) == cbm__eval_expr(e, n->b);
    case OP_NE:
        return cbm__eval_expr(e, n->a) != cbm__eval_expr(e, n->b);
    case OP_AND:
        return cbm__eval_expr(e, n->a) && cbm__eval_expr(e, n->b);
    case OP_OR:
        return cbm__eval_expr(e, n->a) || cbm__eval_expr(e, n->b);
    case OP_COND:
        return cbm__eval_expr(e, n->a) ? cbm__eval_expr(e, n->b) : cbm__eval_expr(e, n->c);
    case OP_CALL: {
        double r = call(e, n);
        if (e->error != CBM_OK && e->error_node < 0)
            e->error_node = i;
        return r;
    }
    default:
        cbm__eval_stmt(e, i);
        return 0;
    }
}

void cbm__eval_stmt(cbm__eval *e, int32_t i)
{
    for (; i >= 0 && e->error == CBM_OK; i = e->nodes[i].next) {
        const cbm__node *n = &e->nodes[i];
        switch ((cbm__op)n->op) {
        case OP_SEQ:
            cbm__eval_stmt(e, n->a);
            break;
        case OP_ASSIGN:
            e->globals[n->slot] = cbm__eval_expr(e, n->a);
            break;
        case OP_ASSIGN_PARAM:
            e->params[n->slot] = cbm__eval_expr(e, n->a);
            break;
        case OP_ASSIGN_ARRAY: {
            double v = cbm__eval_expr(e, n->a);
            double *p = array_elem(e, n, n->b);
            if (p)
                *p = v;
            break;
        }
        case OP_IF:
            if (cbm__eval_expr(e, n->a))
                cbm__eval_stmt(e, n->b);
            else if (n->c >= 0)
                cbm__eval_stmt(e, n->c);
            break;
        case OP_WHILE:
        case OP_DO:
            if (n->op == OP_DO)
                cbm__eval_stmt(e, n->b);
            while (e->error == CBM_OK && cbm__eval_expr(e, n->a)) {
                if (--e->while_budget < 0) {
                    e->error = CBM_E_LIMIT;
                    e->error_msg = "while loops ran for more iterations in one step than the "
                                   "limit (--max-loop-iterations, --max-operations)";
                    e->error_node = i;
                    return;
                }
                cbm__eval_stmt(e, n->b);
            }
            break;
        default:
            (void)cbm__eval_expr(e, i);
            break;
        }
        if (n->op != OP_SEQ && n->op < OP_ASSIGN)
            return; /* a bare expression is not part of a chain */
    }
}
