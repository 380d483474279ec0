/* The cpfg dialect's expressions and statements (expr_parse.c's node arrays) compiled to the
 * register code of lang/lc_code.h and run by its loop, cbm__lc_run: one evaluator for both
 * dialects.
 *
 * A root (a condition, a successor's parameter, a pre/post-condition block, a Start block, a
 * global's value ...) is compiled on its first evaluation into a function of its own, kept by
 * the environment (cbm__eval.code) under the root's node and kind (expression or statement
 * chain), and run from then on. Its registers are temporaries only; the cpfg dialect has no
 * locals: a formal parameter is read and written where the matcher bound it (O_PLD, O_PST on
 * vm->par), a global in the globals (O_GLD, O_GST on vm->glob). What the dialect adds to the
 * register code is that, its math built-ins with trigonometry in degrees (O_CMATH, also `%`
 * as fmod and `^` as pow), the while loops' budget with the cpfg message (O_WSPEND), and the
 * host calls of O_HOST: array elements (an index checked at a time, as cpfg does), the random
 * numbers through the one random module (lang/random.h: ran(x) = x * erand48, nran(m, s) the
 * polar Box-Muller pairs, bran(a, b) Cheng's beta, biran(n, p) n coin flips spending n
 * iterations of the budget, srand(s)), the growth curves, func(id, x), stop() and printf.
 *
 * Semantics are the tree walker's that this replaced: operands left to right, `&&`, `||` and
 * `?:` short-circuit with results 0 or 1, a NaN is true, a statement chain does not start
 * while an error is pending. A runtime error stops the run at once (the walker went on to the
 * end of the expression, whose value was then discarded), and names the node the walker named:
 * the call, the array element or assignment, the while loop. The instruction that can fail
 * carries that node in its `stmt_pos`, so vm->err_pos is the node, not a text offset as in the
 * L+C dialect.
 */
#include "lang/lang.h"
#include "lang/lc_code.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* A root's function, and the one instruction of a function that is a single load (a constant,
 * a parameter, a global) and its return, so that the run finds it without two indirections */
typedef struct entry {
    int32_t fn_plus_one; /* function index + 1, 0: none yet */
    uint8_t load;        /* O_CONST, O_PLD or O_GLD: the function is that load; else 0 */
    int32_t operand;     /* the load's parameter or global */
    double value;        /* the load's constant */
} entry;

struct cbm__ecode {
    CBM_ARRAY(lc_fcode) fn;
    CBM_ARRAY(entry) entry; /* by 2 * root + (statement chain) */
    double *frame;          /* the registers of the run (frame_cap doubles) */
    size_t frame_cap;
    size_t ins, runs;
    lc_vm vm;
    char msg[160]; /* the message of the error handed to the environment */
};

/* host calls besides the built-ins (ip->subop beyond FN_COUNT) */
enum { H_AIDX = FN_COUNT + 1, H_ALOAD, H_ASTORE };

/* ---------------------------------------------------------------- compiler */
typedef struct codegen {
    cbm_context *ctx;
    const cbm__node *nodes;
    lc_fcode *code; /* the function being written */
    int temp_top;   /* the next free register */
    bool out_of_memory;
} codegen;

static size_t emit(codegen *c, int op, int dst, int src1, int src2, int subop, int32_t node,
                   double imm)
{
    lc_ins in = {.op = (uint8_t)op,
                 .subop = (uint16_t)subop,
                 .dst = dst,
                 .src1 = src1,
                 .src2 = src2,
                 .stmt_pos = node,
                 .imm = imm};
    if (CBM_ARRAY_PUSH(c->ctx, c->code->ins, in) != CBM_OK) {
        c->out_of_memory = true;
        return 0;
    }
    return c->code->ins.len - 1;
}

/* The jump at instruction j lands at the next instruction to come (O_JMP: src1, O_JZ/O_JNZ:
 * src2). */
static void jump_lands_here(codegen *c, size_t j)
{
    if (c->out_of_memory)
        return;
    lc_ins *in = &c->code->ins.data[j];
    if (in->op == O_JMP)
        in->src1 = (int32_t)c->code->ins.len;
    else
        in->src2 = (int32_t)c->code->ins.len;
}

static int new_register(codegen *c)
{
    int r = c->temp_top++;
    if (c->temp_top > c->code->nreg)
        c->code->nreg = c->temp_top;
    return r;
}

static void compile_stmts(codegen *c, int32_t i);
static void compile_expr(codegen *c, int32_t i, int d);

/* The element offset of array node i (an ARRAY or ASSIGN_ARRAY node) with its indices from
 * chain idx into a new register: an index checked at a time, as cpfg does. */
static int array_offset(codegen *c, int32_t i, int32_t idx)
{
    int o = new_register(c);
    emit(c, O_CONST, o, 0, 0, 0, -1, 0.0);
    int k = 0;
    for (int32_t j = idx; j >= 0; j = c->nodes[j].next, k++) {
        int r = new_register(c);
        compile_expr(c, j, r);
        emit(c, O_HOST, o, r, k, H_AIDX, i, 0.0);
        c->temp_top = r;
    }
    return o;
}

static bool binary_math(int fn)
{
    return fn == FN_ATAN2 || fn == FN_POW || fn == FN_FMOD || fn == FN_MIN || fn == FN_MAX;
}

/* Expression node i into register d (temporaries above c->temp_top, which is above d). */
static void compile_expr(codegen *c, int32_t i, int d)
{
    const cbm__node *n = &c->nodes[i];
    int save = c->temp_top;
    int r;
    switch ((cbm__op)n->op) {
    case OP_NUM:
        emit(c, O_CONST, d, 0, 0, 0, -1, n->value);
        break;
    case OP_PARAM:
        emit(c, O_PLD, d, n->slot, 0, 0, -1, 0.0);
        break;
    case OP_GLOBAL:
        emit(c, O_GLD, d, n->slot, 0, 0, -1, 0.0);
        break;
    case OP_ARRAY: {
        int o = array_offset(c, i, n->child1);
        emit(c, O_HOST, d, o, 0, H_ALOAD, i, 0.0);
        break;
    }
    case OP_NEG:
    case OP_NOT:
        compile_expr(c, n->child1, d);
        emit(c, n->op == OP_NEG ? O_NEG : O_NOT, d, d, 0, 0, -1, 0.0);
        break;
    case OP_ADD:
    case OP_SUB:
    case OP_MUL:
    case OP_DIV:
    case OP_REM:
    case OP_POW:
    case OP_LT:
    case OP_GT:
    case OP_LE:
    case OP_GE:
    case OP_EQ:
    case OP_NE: {
        static const uint8_t ops[] = {
            [OP_ADD] = O_ADDD,  [OP_SUB] = O_SUBD,  [OP_MUL] = O_MULD, [OP_DIV] = O_DIVD,
            [OP_REM] = O_CMATH, [OP_POW] = O_CMATH, [OP_LT] = O_LT,    [OP_GT] = O_GT,
            [OP_LE] = O_LE,     [OP_GE] = O_GE,     [OP_EQ] = O_EQ,    [OP_NE] = O_NE};
        compile_expr(c, n->child1, d);
        r = new_register(c);
        compile_expr(c, n->child2, r);
        emit(c, ops[n->op], d, d, r,
             n->op == OP_REM   ? FN_FMOD
             : n->op == OP_POW ? FN_POW
                               : 0,
             -1, 0.0);
        break;
    }
    case OP_AND:
    case OP_OR: {
        compile_expr(c, n->child1, d);
        emit(c, O_BOOL, d, d, 0, 0, -1, 0.0);
        size_t j = emit(c, n->op == OP_AND ? O_JZ : O_JNZ, 0, d, 0, 0, -1, 0.0);
        compile_expr(c, n->child2, d);
        emit(c, O_BOOL, d, d, 0, 0, -1, 0.0);
        jump_lands_here(c, j);
        break;
    }
    case OP_COND: {
        compile_expr(c, n->child1, d);
        size_t jz = emit(c, O_JZ, 0, d, 0, 0, -1, 0.0);
        compile_expr(c, n->child2, d);
        size_t jmp = emit(c, O_JMP, 0, 0, 0, 0, -1, 0.0);
        jump_lands_here(c, jz);
        compile_expr(c, n->child3, d);
        jump_lands_here(c, jmp);
        break;
    }
    case OP_CALL: {
        /* the arguments left to right into a run of registers: at most 8 (16 for printf,
         * whose string arguments take a register each but no code), as the walker read them */
        int base = c->temp_top, k = 0;
        int32_t j = n->child1, max = 8;
        if (n->fn == FN_PRINTF) {
            j = j >= 0 ? c->nodes[j].next : -1; /* after the format */
            max = CBM__FMT_MAX_ARGS;
        }
        for (; j >= 0 && k < max; j = c->nodes[j].next, k++) {
            r = new_register(c);
            if (c->nodes[j].op != OP_STR)
                compile_expr(c, j, r);
        }
        if (n->fn < FN_MATH_END) {
            /* the walker passed 0 for a missing argument; one-argument functions ignore b */
            while (k < (binary_math(n->fn) ? 2 : 1)) {
                r = new_register(c);
                emit(c, O_CONST, r, 0, 0, 0, -1, 0.0);
                k++;
            }
            emit(c, O_CMATH, d, base, k >= 2 ? base + 1 : base, n->fn, -1, 0.0);
        } else {
            emit(c, O_HOST, d, base, k, n->fn, i, 0.0);
        }
        break;
    }
    case OP_ASSIGN:
    case OP_ASSIGN_PARAM:
    case OP_ASSIGN_ARRAY:
    case OP_IF:
    case OP_WHILE:
    case OP_DO:
    case OP_SEQ:
        /* a statement where an expression is asked: the walker ran its chain and gave 0 */
        compile_stmts(c, i);
        emit(c, O_CONST, d, 0, 0, 0, -1, 0.0);
        break;
    default: /* OP_COMMA, OP_NOP, OP_STR: not made by the parser where a value is read */
        emit(c, O_CONST, d, 0, 0, 0, -1, 0.0);
        break;
    }
    c->temp_top = save;
}

/* The statement chain from i: a bare expression ends it. */
static void compile_stmts(codegen *c, int32_t i)
{
    for (; i >= 0 && !c->out_of_memory; i = c->nodes[i].next) {
        const cbm__node *n = &c->nodes[i];
        int save = c->temp_top, r;
        switch ((cbm__op)n->op) {
        case OP_SEQ:
            compile_stmts(c, n->child1);
            break;
        case OP_ASSIGN:
        case OP_ASSIGN_PARAM:
            r = new_register(c);
            compile_expr(c, n->child1, r);
            emit(c, n->op == OP_ASSIGN ? O_GST : O_PST, n->slot, r, 0, 0, -1, 0.0);
            break;
        case OP_ASSIGN_ARRAY: {
            r = new_register(c);
            compile_expr(c, n->child1, r); /* the value first, then the indices */
            int o = array_offset(c, i, n->child2);
            emit(c, O_HOST, o, o, r, H_ASTORE, i, 0.0);
            break;
        }
        case OP_IF: {
            r = new_register(c);
            compile_expr(c, n->child1, r);
            size_t jz = emit(c, O_JZ, 0, r, 0, 0, -1, 0.0);
            c->temp_top = save;
            compile_stmts(c, n->child2);
            if (n->child3 >= 0) {
                size_t jmp = emit(c, O_JMP, 0, 0, 0, 0, -1, 0.0);
                jump_lands_here(c, jz);
                compile_stmts(c, n->child3);
                jump_lands_here(c, jmp);
            } else {
                jump_lands_here(c, jz);
            }
            break;
        }
        case OP_WHILE:
        case OP_DO: {
            if (n->op == OP_DO)
                compile_stmts(c, n->child2);
            int32_t test = (int32_t)c->code->ins.len;
            r = new_register(c);
            compile_expr(c, n->child1, r);
            size_t jz = emit(c, O_JZ, 0, r, 0, 0, -1, 0.0);
            c->temp_top = save;
            emit(c, O_WSPEND, 0, 0, 0, 0, i, 0.0);
            compile_stmts(c, n->child2);
            emit(c, O_JMP, 0, test, 0, 0, -1, 0.0);
            jump_lands_here(c, jz);
            break;
        }
        default:
            r = new_register(c);
            compile_expr(c, i, r);
            break;
        }
        c->temp_top = save;
        if (n->op != OP_SEQ && n->op < OP_ASSIGN)
            return; /* a bare expression is not part of a chain */
    }
}

/* Compiles root `root` (an expression, or a statement chain when stmt) into a new function;
 * its index, -1 when out of memory. */
static int compile(cbm__eval *e, int32_t root, bool stmt)
{
    cbm__ecode *ec = e->code;
    lc_fcode z = {0};
    if (CBM_ARRAY_PUSH(e->ctx, ec->fn, z) != CBM_OK)
        return -1;
    codegen c = {.ctx = e->ctx, .nodes = e->nodes, .code = &ec->fn.data[ec->fn.len - 1]};
    c.code->compiled = true;
    if (stmt) {
        compile_stmts(&c, root);
        emit(&c, O_RET0, 0, 0, 0, 0, -1, 0.0);
    } else {
        int r = new_register(&c);
        compile_expr(&c, root, r);
        emit(&c, O_RET, 0, r, 0, 0, -1, 0.0);
    }
    if (!c.out_of_memory && (size_t)c.code->nreg + 1 > ec->frame_cap) {
        size_t cap = (size_t)c.code->nreg + 16;
        double *f =
            cbm__realloc(e->ctx, ec->frame, ec->frame_cap * sizeof(double), cap * sizeof(double));
        if (f) {
            ec->frame = f;
            ec->frame_cap = cap;
        } else {
            c.out_of_memory = true;
        }
    }
    if (c.out_of_memory) {
        CBM_ARRAY_FREE(e->ctx, c.code->ins);
        ec->fn.len--;
        return -1;
    }
    ec->ins += c.code->ins.len;
    return (int)(ec->fn.len - 1);
}

/* ---------------------------------------------------------------- host calls */
static double host_call(lc_vm *vm, const lc_ins *ip, double *fr)
{
    cbm__eval *e = vm->host;
    switch (ip->subop) {
    case H_AIDX: {
        const cbm__array *ar = &e->arrays[e->nodes[ip->stmt_pos].slot];
        double v = fr[ip->src1];
        if (!(v >= 0 && v < ar->dims[ip->src2])) {
            cbm__lc_error(vm, CBM_E_RUNTIME, "array index out of range");
            return 0;
        }
        return (double)((size_t)fr[ip->dst] * (size_t)ar->dims[ip->src2] + (size_t)v);
    }
    case H_ALOAD:
        return e->arrays[e->nodes[ip->stmt_pos].slot].data[(size_t)fr[ip->src1]];
    case H_ASTORE:
        e->arrays[e->nodes[ip->stmt_pos].slot].data[(size_t)fr[ip->src1]] = fr[ip->src2];
        return fr[ip->src1];
    case FN_PRINTF: {
        cbm__fmt_arg args[CBM__FMT_MAX_ARGS];
        int32_t f = e->nodes[ip->stmt_pos].child1;
        const char *fmt = e->strings && f >= 0 ? e->strings + e->nodes[f].slot : "";
        int k = 0;
        for (int32_t j = f >= 0 ? e->nodes[f].next : -1; j >= 0 && k < ip->src2;
             j = e->nodes[j].next, k++) {
            bool s = e->nodes[j].op == OP_STR;
            args[k].s = s && e->strings ? e->strings + e->nodes[j].slot : NULL;
            args[k].v = s ? 0 : fr[ip->src1 + k];
        }
        cbm__fmt_print(e->ctx, fmt, args, k);
        return 0;
    }
    default:
        break;
    }
    double a[8] = {0};
    for (int k = 0; k < ip->src2 && k < 8; k++)
        a[k] = fr[ip->src1 + k];
    if (ip->subop > FN_MATH_END && ip->subop < FN_GROWTH_END)
        return cbm__builtin_growth(ip->subop, a);
    switch (ip->subop) {
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
            cbm__lc_error(vm, CBM_E_RUNTIME, "bran(a, b): the parameters must be positive");
            return 0;
        }
        return r;
    }
    case FN_BIRAN: {
        double n = a[0];
        if (!(n < 1e8) || !(n > -1e8)) {
            cbm__lc_error(vm, CBM_E_RUNTIME, "biran(n, p): n is too large");
            return 0;
        }
        /* n draws: operations of the step's budget like loop iterations */
        if (n > 0 && (vm->budget -= (long)n) < 0) {
            cbm__lc_error(vm, CBM_E_LIMIT,
                          "biran(n, p) draws more than the step's limit of operations "
                          "(--max-loop-iterations, --max-operations)");
            return 0;
        }
        return cbm__random_binomial(&e->rnd, (int)n, a[1]);
    }
    case FN_SRAND:
        cbm__random_seed(&e->rnd, cbm__to_ll(a[0]));
        return 0;
    case FN_FUNC:
        if (!e->func) {
            cbm__lc_error(vm, CBM_E_RUNTIME,
                          "func(id, x) needs function files (.func or .fset) on the command line");
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
        return 0; /* built-ins of the other dialect: the parser does not let them in */
    }
}

/* ---------------------------------------------------------------- running */
static double out_of_memory(cbm__eval *e, int32_t root)
{
    if (e->error == CBM_OK) {
        e->error = CBM_E_NOMEM;
        e->error_msg = "out of memory compiling an expression";
        e->error_node = root;
    }
    return 0;
}

/* The function of root `slot` (2 * node + statement chain), compiled now if it is not yet;
 * -1 when out of memory. Out of line: the run's path stays short. */
static __attribute__((noinline)) int first_run(cbm__eval *e, int32_t root, bool stmt)
{
    cbm__ecode *ec = e->code;
    if (!ec) {
        ec = e->code = cbm__calloc(e->ctx, 1, sizeof *ec);
        if (!ec)
            return -1;
        ec->vm.host_call = host_call;
    }
    size_t slot = 2 * (size_t)root + stmt;
    if (slot >= ec->entry.len) {
        if (CBM_ARRAY_RESERVE(e->ctx, ec->entry, slot + 1) != CBM_OK)
            return -1;
        memset(ec->entry.data + ec->entry.len, 0,
               (slot + 1 - ec->entry.len) * sizeof *ec->entry.data);
        ec->entry.len = slot + 1;
    }
    entry *en = &ec->entry.data[slot];
    if (en->fn_plus_one == 0) {
        int f = compile(e, root, stmt);
        if (f < 0)
            return -1;
        en->fn_plus_one = f + 1;
        const lc_fcode *fc = &ec->fn.data[f];
        const lc_ins *in = fc->ins.data;
        if (fc->ins.len == 2 && (in->op == O_CONST || in->op == O_PLD || in->op == O_GLD)) {
            en->load = in->op;
            en->operand = in->src1;
            en->value = in->imm;
        }
    }
    return en->fn_plus_one - 1;
}

/* An error of the run goes to the environment unless one is pending there. */
static __attribute__((noinline)) double run_failed(cbm__eval *e)
{
    cbm__ecode *ec = e->code;
    lc_vm *vm = &ec->vm;
    if (e->error == CBM_OK) {
        e->error = vm->err;
        memcpy(ec->msg, vm->errmsg, sizeof ec->msg);
        e->error_msg = ec->msg;
        e->error_node = vm->err_pos;
    }
    vm->err = CBM_OK;
    return 0;
}

/* Function f on the loop. */
static __attribute__((noinline)) double run_code(cbm__eval *e, cbm__ecode *ec, int f)
{
    lc_vm *vm = &ec->vm;
    vm->host = e;
    vm->glob = e->globals;
    vm->par = e->params;
    vm->budget = e->while_budget;
    vm->stmt_pos = -1;
    const lc_program p = {.fn = ec->fn.data, .n = ec->fn.len};
    double v = cbm__lc_run(&p, f, ec->frame, vm);
    e->while_budget = vm->budget;
    return vm->err == CBM_OK ? v : run_failed(e);
}

static inline __attribute__((always_inline)) double run_root(cbm__eval *e, int32_t root, bool stmt)
{
    cbm__ecode *ec = e->code;
    size_t slot = 2 * (size_t)root + stmt;
    if (!ec || slot >= ec->entry.len || ec->entry.data[slot].fn_plus_one == 0) {
        if (first_run(e, root, stmt) < 0)
            return out_of_memory(e, root);
        ec = e->code;
    }
    ec->runs++;
    const entry *en = &ec->entry.data[slot];
    /* a function of one load (a constant, a parameter, a global) and its return, most of a
     * successor's parameters: that instruction is run here, without entering the loop */
    switch (en->load) {
    case O_CONST:
        return en->value;
    case O_PLD:
        return e->params[en->operand];
    case O_GLD:
        return e->globals[en->operand];
    default:
        return run_code(e, ec, en->fn_plus_one - 1);
    }
}

double cbm__eval_expr(cbm__eval *e, int32_t n)
{
    return run_root(e, n, false);
}

void cbm__eval_stmt(cbm__eval *e, int32_t n)
{
    if (n >= 0 && e->error == CBM_OK)
        (void)run_root(e, n, true);
}

void cbm__eval_free(cbm__eval *e)
{
    cbm__ecode *ec = e->code;
    if (!ec)
        return;
    for (size_t i = 0; i < ec->fn.len; i++)
        CBM_ARRAY_FREE(e->ctx, ec->fn.data[i].ins);
    CBM_ARRAY_FREE(e->ctx, ec->fn);
    CBM_ARRAY_FREE(e->ctx, ec->entry);
    cbm__free(e->ctx, ec->frame, ec->frame_cap * sizeof(double));
    cbm__free(e->ctx, ec, sizeof *ec);
    e->code = NULL;
}

void cbm__eval_stats(const cbm__eval *e, size_t *roots, size_t *ins, size_t *runs)
{
    const cbm__ecode *ec = e->code;
    *roots = ec ? ec->fn.len : 0;
    *ins = ec ? ec->ins : 0;
    *runs = ec ? ec->runs : 0;
}
