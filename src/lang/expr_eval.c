/* Evaluation of the cpfg dialect's compiled expressions and statements (expr_parse.c): a
 * recursive walk of the node array whose depth is bounded by the parser's max_expr_depth;
 * `while` loops share an iteration budget so that no model can hang the derivation.
 *
 * Random functions follow cpfg (utility.c), through lang/random.h: ran(x) = x * erand48,
 * nran(m, s) the polar Box-Muller method producing values in pairs, bran(a, b) Cheng's beta
 * generator, biran(n, p) n coin flips, srand(s) resets the erand48 state to
 * {0x330E, s & 0xFFFF, s >> 16} and the pair cache.
 */
#include "lang/lang.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

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
    if (n->fn < FN_MATH_END)
        return cbm__builtin_math(n->fn, a[0], a[1], true);
    if (n->fn > FN_MATH_END && n->fn < FN_GROWTH_END)
        return cbm__builtin_growth(n->fn, a);
    switch (n->fn) {
    case FN_RAN:
        return cbm__rand48_next(&e->rnd.r48) * a[0];
    case FN_NRAN: {
        double v, f;
        cbm__random_normal(&e->rnd, &v, &f);
        return v * f * a[1] + a[0];
    }
    case FN_BRAN: {
        double r;
        if (!cbm__random_beta(&e->rnd, a[0], a[1], &r)) {
            e->error = CBM_E_RUNTIME;
            e->error_msg = "bran(a, b): the parameters must be positive";
        }
        return r;
    }
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
        return cbm__random_binomial(&e->rnd, (int)n2, a[1]);
    }
    case FN_SRAND: {
        cbm__random_seed(&e->rnd, cbm__to_ll(a[0]));
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
