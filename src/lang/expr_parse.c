/* Expressions and statements of the cpfg dialect, parsed into a flat node array (evaluated by
 * cpfg_code.c, which compiles them to the register code of lc_code.h).
 *
 * The grammar follows cpfg's (lsys_input.y): from lowest to highest precedence `?:` (right),
 * `||`, `&&`, `== !=` (also `<>`), `< <= > >=`, `+ -`, `* / %`, `^` (power, left-associative
 * as in cpfg, so 2^3^2 = 64), unary `-`, `!`. Trigonometric functions take and give degrees.
 * Statements: assignment to a variable or an array element, `if`/`else`, `while`, `do ...
 * while`, calls, blocks. A name is a formal parameter of the production being compiled or
 * else a global variable of the model (cpfg keeps one symbol table per L-system); reading a
 * global that is never assigned anywhere is an error. Nodes refer to their children by index,
 * so a compiled model is a few contiguous arrays. Built-in functions come from the one table
 * of both dialects (lang/builtins.h).
 */
#include "lang/lang.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

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
    cbm__node nd = {
        .op = OP_STR, .child1 = -1, .child2 = -1, .child3 = -1, .next = -1, .slot = (int32_t)off};
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

static int32_t binary_node(cbm__compiler *c, int op, int32_t a, int32_t b)
{
    if (a < 0 || b < 0)
        return -1;
    cbm__node n = {
        .op = (uint8_t)op, .child1 = a, .child2 = b, .child3 = -1, .next = -1, .slot = -1};
    return add_node(c, n);
}

int32_t cbm__node_num(cbm__compiler *c, double v)
{
    cbm__node n = {
        .op = OP_NUM, .child1 = -1, .child2 = -1, .child3 = -1, .next = -1, .slot = -1, .value = v};
    return add_node(c, n);
}

bool cbm__node_const(const cbm__compiler *c, int32_t i, double *v)
{
    if (i < 0)
        return false;
    const cbm__node *n = &c->nodes.data[i];
    if (n->op == OP_NUM) {
        *v = n->value;
        return true;
    }
    double a, b;
    if (n->op == OP_NEG && cbm__node_const(c, n->child1, &a)) {
        *v = -a;
        return true;
    }
    if (n->op >= OP_ADD && n->op <= OP_DIV && cbm__node_const(c, n->child1, &a) &&
        cbm__node_const(c, n->child2, &b)) {
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
        const cbm__builtin *fn = cbm__builtin_find(t, len, c->dialect ? c->dialect : CBM__CPFG);
        if (fn) {
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
            if (fn->fn == FN_PRINTF ? !check_printf(c, start, first, n) : !no_strings(c, first))
                return -1;
            if (fn->arity >= 0 && n != fn->arity) {
                cbm__cerr(c, start, "%s() takes %d argument%s, %d given", fn->name, fn->arity,
                          fn->arity == 1 ? "" : "s", n);
                return -1;
            }
            cbm__node nd = {.op = OP_CALL,
                            .fn = (uint8_t)fn->fn,
                            .child1 = first,
                            .child2 = -1,
                            .child3 = -1,
                            .next = -1,
                            .slot = n};
            return add_node(c, nd);
        }
        for (int i = 0; i < c->nformals; i++)
            if (c->formal_len[i] == len && !memcmp(c->formals[i], t, len)) {
                cbm__node nd = {.op = OP_PARAM,
                                .child1 = -1,
                                .child2 = -1,
                                .child3 = -1,
                                .next = -1,
                                .slot = i};
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
            cbm__node nd = {
                .op = OP_ARRAY, .child1 = idx, .child2 = -1, .child3 = -1, .next = -1, .slot = ai};
            return add_node(c, nd);
        }
        int32_t g = global_slot(c, t, len, false, start);
        if (g < 0)
            return -1;
        cbm__node nd = {
            .op = OP_GLOBAL, .child1 = -1, .child2 = -1, .child3 = -1, .next = -1, .slot = g};
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
        r = binary_node(c, OP_NEG, parse_unary(c, nl), 0);
    } else if (ch == '+') {
        c->pos++;
        r = parse_unary(c, nl);
    } else if (ch == '!' && c->text[c->pos + 1] != '=') {
        c->pos++;
        r = binary_node(c, OP_NOT, parse_unary(c, nl), 0);
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
        left = binary_node(c, op, left, parse_binary(c, nl, level + 1));
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
    int32_t n = binary_node(c, OP_COND, cond, a);
    if (n >= 0 && b >= 0) {
        c->nodes.data[n].child3 = b;
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

static int32_t parse_statement_inner(cbm__compiler *c, bool *ok);

/* A statement; if, while and do nest (an else-if chain is as deep as it is long). */
static int32_t parse_statement(cbm__compiler *c, bool *ok)
{
    if (!deeper(c)) {
        *ok = false;
        return -1;
    }
    int32_t r = parse_statement_inner(c, ok);
    c->depth--;
    return r;
}

static int32_t parse_statement_inner(cbm__compiler *c, bool *ok)
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
                       .child1 = cond,
                       .child2 = body,
                       .child3 = other,
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
        cbm__node n = {
            .op = OP_DO, .child1 = cond, .child2 = body, .child3 = -1, .next = -1, .slot = -1};
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
                    cbm__node n = {.op = OP_ASSIGN_PARAM,
                                   .child1 = val,
                                   .child2 = -1,
                                   .child3 = -1,
                                   .next = -1,
                                   .slot = i};
                    return add_node(c, n);
                }
            if (ai >= 0) {
                if (count != c->arrays.data[ai].ndims) {
                    cbm__cerr(c, start, "array '%s' needs %d index%s", c->arrays.data[ai].name,
                              c->arrays.data[ai].ndims, c->arrays.data[ai].ndims == 1 ? "" : "es");
                    *ok = false;
                    return -1;
                }
                cbm__node n = {.op = OP_ASSIGN_ARRAY,
                               .child1 = val,
                               .child2 = idx,
                               .child3 = -1,
                               .next = -1,
                               .slot = ai};
                return add_node(c, n);
            }
            int32_t g = global_slot(c, t, len, true, start);
            cbm__node n = {
                .op = OP_ASSIGN, .child1 = val, .child2 = -1, .child3 = -1, .next = -1, .slot = g};
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
        cbm__node seq = {
            .op = OP_SEQ, .child1 = s, .child2 = -1, .child3 = -1, .next = -1, .slot = -1};
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
