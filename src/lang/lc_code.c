/* The L+C dialect's register code (lc_code.h): the compiler from the typed node array of a
 * function to instructions, and the loop that runs them. */
#include "lang/lc_code.h"

#include "lang/builtins.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* ---------------------------------------------------------------- runtime */
void cbm__lc_error(lc_vm *vm, cbm_status s, const char *msg)
{
    if (vm->err == CBM_OK) {
        vm->err = s;
        vm->err_pos = vm->stmt_pos;
        snprintf(vm->errmsg, sizeof vm->errmsg, "%s", msg);
    }
}

bool cbm__lc_spend(lc_vm *vm, bool loop)
{
    if (--vm->ops < 0) {
        cbm__lc_error(vm, CBM_E_LIMIT,
                      "more productions applied, function calls and loop iterations in one step "
                      "than the limit (--max-operations)");
        return false;
    }
    if (loop && --vm->budget < 0) {
        cbm__lc_error(vm, CBM_E_LIMIT,
                      "more loop iterations in one step than the limit (--max-loop-iterations)");
        return false;
    }
    return true;
}

double cbm__lc_bin_scalar(int op, int t, double a, double b, lc_vm *vm)
{
    double r;
    if (t == T_INT && op <= B_REM) { /* C int arithmetic: 32 bits, wrapping on overflow */
        long long x = (long long)lc_c_int(a), y = (long long)lc_c_int(b);
        switch (op) {
        case B_ADD:
            return lc_wrap_int(x + y);
        case B_SUB:
            return lc_wrap_int(x - y);
        case B_MUL:
            return lc_wrap_int(x * y);
        default:
            if (y == 0) {
                cbm__lc_error(vm, CBM_E_RUNTIME,
                              op == B_DIV ? "integer division by zero"
                                          : "integer remainder by zero");
                return 0;
            }
            return lc_wrap_int(op == B_DIV ? x / y : x % y);
        }
    }
    switch (op) {
    case B_ADD:
        r = a + b;
        break;
    case B_SUB:
        r = a - b;
        break;
    case B_MUL:
        r = a * b;
        break;
    case B_DIV:
        r = a / b;
        break;
    case B_REM: {
        long long d = cbm__to_ll(b);
        if (d == 0) {
            cbm__lc_error(vm, CBM_E_RUNTIME, "integer remainder by zero");
            return 0;
        }
        return (double)(cbm__to_ll(a) % d);
    }
    case B_LT:
        return a < b;
    case B_GT:
        return a > b;
    case B_LE:
        return a <= b;
    case B_GE:
        return a >= b;
    case B_EQ:
        return a == b;
    default:
        return a != b;
    }
    return lc_conv_scalar(t, r);
}

static double step_incdec(const lc_ins *ip, double *p)
{
    double old = *p;
    *p = lc_conv_scalar(ip->type, *p + ((ip->subop & 1) ? -1 : 1));
    return ip->subop >= 2 ? old : *p;
}

/* A loop iteration: one operation and one iteration from the budgets */
#define SPEND_ONE()                                                                                \
    do {                                                                                           \
        if (vm->ops > 0 && vm->budget > 0) {                                                       \
            vm->ops--;                                                                             \
            vm->budget--;                                                                          \
        } else { /* a limit is reached: cbm__lc_spend says which */                                \
            vm->stmt_pos = at;                                                                     \
            (void)cbm__lc_spend(vm, true);                                                         \
            return 0;                                                                              \
        }                                                                                          \
    } while (0)

bool cbm__lc_stateless(const lc_program *p, size_t f)
{
    const lc_fcode *fc = &p->fn[f];
    for (size_t i = 0; i < fc->ins.len; i++)
        switch (fc->ins.data[i].op) {
        case O_GLD:
        case O_GST:
        case O_INC:
        case O_GINC:
        case O_SPEND:
        case O_JNZS:
        case O_JMPS:
        case O_JLT:
        case O_JGT:
        case O_JLE:
        case O_JGE:
        case O_JEQ:
        case O_JNE:
        case O_CALL:
        case O_PLD:
        case O_PST:
        case O_WSPEND:
        case O_HOST:
            return false;
        default:
            break;
        }
    return fc->compiled;
}

double cbm__lc_run(const lc_program *p, int f, double *fr, lc_vm *vm)
{
    if (cbm__lc_native_has(p, f)) /* the same function as native code (lc_native.c) */
        return cbm__lc_native_run(p, f, fr, vm);
    const lc_ins *code = p->fn[f].ins.data, *ip = code;
    double *glob = vm->glob;
    int32_t at = vm->stmt_pos;
    for (;; ip++) {
        at = ip->stmt_pos >= 0 ? ip->stmt_pos : at;
        switch (ip->op) {
        case O_NOP:
            break;
        case O_CONST:
            fr[ip->dst] = ip->imm;
            break;
        case O_MOV:
            fr[ip->dst] = fr[ip->src1];
            break;
        case O_GLD:
            fr[ip->dst] = glob[ip->src1];
            break;
        case O_GST:
            glob[ip->dst] = fr[ip->src1];
            break;
        case O_NEG:
            fr[ip->dst] = -fr[ip->src1];
            break;
        case O_NOT:
            fr[ip->dst] = fr[ip->src1] == 0;
            break;
        case O_BOOL:
            fr[ip->dst] = fr[ip->src1] != 0;
            break;
        case O_CONV:
            fr[ip->dst] = lc_conv_scalar(ip->type, fr[ip->src1]);
            break;
        case O_ADDD:
            fr[ip->dst] = fr[ip->src1] + fr[ip->src2];
            break;
        case O_SUBD:
            fr[ip->dst] = fr[ip->src1] - fr[ip->src2];
            break;
        case O_MULD:
            fr[ip->dst] = fr[ip->src1] * fr[ip->src2];
            break;
        case O_DIVD:
            fr[ip->dst] = fr[ip->src1] / fr[ip->src2];
            break;
        case O_ADDF:
            fr[ip->dst] = (double)(float)(fr[ip->src1] + fr[ip->src2]);
            break;
        case O_SUBF:
            fr[ip->dst] = (double)(float)(fr[ip->src1] - fr[ip->src2]);
            break;
        case O_MULF:
            fr[ip->dst] = (double)(float)(fr[ip->src1] * fr[ip->src2]);
            break;
        case O_DIVF:
            fr[ip->dst] = (double)(float)(fr[ip->src1] / fr[ip->src2]);
            break;
        case O_ADDI:
            fr[ip->dst] =
                lc_wrap_int((long long)lc_c_int(fr[ip->src1]) + (long long)lc_c_int(fr[ip->src2]));
            break;
        case O_SUBI:
            fr[ip->dst] =
                lc_wrap_int((long long)lc_c_int(fr[ip->src1]) - (long long)lc_c_int(fr[ip->src2]));
            break;
        case O_MULI:
            fr[ip->dst] =
                lc_wrap_int((long long)lc_c_int(fr[ip->src1]) * (long long)lc_c_int(fr[ip->src2]));
            break;
        case O_LT:
            fr[ip->dst] = fr[ip->src1] < fr[ip->src2];
            break;
        case O_GT:
            fr[ip->dst] = fr[ip->src1] > fr[ip->src2];
            break;
        case O_LE:
            fr[ip->dst] = fr[ip->src1] <= fr[ip->src2];
            break;
        case O_GE:
            fr[ip->dst] = fr[ip->src1] >= fr[ip->src2];
            break;
        case O_EQ:
            fr[ip->dst] = fr[ip->src1] == fr[ip->src2];
            break;
        case O_NE:
            fr[ip->dst] = fr[ip->src1] != fr[ip->src2];
            break;
        case O_DIVI:
        case O_REMI: {
            long long x = (long long)lc_c_int(fr[ip->src1]), y = (long long)lc_c_int(fr[ip->src2]);
            if (y == 0) {
                vm->stmt_pos = at;
                cbm__lc_error(vm, CBM_E_RUNTIME,
                              ip->op == O_DIVI ? "integer division by zero"
                                               : "integer remainder by zero");
                return 0;
            }
            fr[ip->dst] = lc_wrap_int(ip->op == O_DIVI ? x / y : x % y);
            break;
        }
        case O_JNLT:
            if (!(fr[ip->src1] < fr[ip->src2]))
                ip = code + ip->dst - 1;
            break;
        case O_JNGT:
            if (!(fr[ip->src1] > fr[ip->src2]))
                ip = code + ip->dst - 1;
            break;
        case O_JNLE:
            if (!(fr[ip->src1] <= fr[ip->src2]))
                ip = code + ip->dst - 1;
            break;
        case O_JNGE:
            if (!(fr[ip->src1] >= fr[ip->src2]))
                ip = code + ip->dst - 1;
            break;
        case O_JNEQ:
            if (!(fr[ip->src1] == fr[ip->src2]))
                ip = code + ip->dst - 1;
            break;
        case O_JNNE:
            if (!(fr[ip->src1] != fr[ip->src2]))
                ip = code + ip->dst - 1;
            break;
        case O_JLT:
            if (fr[ip->src1] < fr[ip->src2]) {
                SPEND_ONE();
                ip = code + ip->dst - 1;
            }
            break;
        case O_JGT:
            if (fr[ip->src1] > fr[ip->src2]) {
                SPEND_ONE();
                ip = code + ip->dst - 1;
            }
            break;
        case O_JLE:
            if (fr[ip->src1] <= fr[ip->src2]) {
                SPEND_ONE();
                ip = code + ip->dst - 1;
            }
            break;
        case O_JGE:
            if (fr[ip->src1] >= fr[ip->src2]) {
                SPEND_ONE();
                ip = code + ip->dst - 1;
            }
            break;
        case O_JEQ:
            if (fr[ip->src1] == fr[ip->src2]) {
                SPEND_ONE();
                ip = code + ip->dst - 1;
            }
            break;
        case O_JNE:
            if (fr[ip->src1] != fr[ip->src2]) {
                SPEND_ONE();
                ip = code + ip->dst - 1;
            }
            break;
        case O_SIN:
            fr[ip->dst] = sin(fr[ip->src1]);
            break;
        case O_COS:
            fr[ip->dst] = cos(fr[ip->src1]);
            break;
        case O_SQRT:
            fr[ip->dst] = sqrt(fr[ip->src1]);
            break;
        case O_EXP:
            fr[ip->dst] = exp(fr[ip->src1]);
            break;
        case O_BIN:
            vm->stmt_pos = at;
            fr[ip->dst] = cbm__lc_bin_scalar(ip->subop, ip->type, fr[ip->src1], fr[ip->src2], vm);
            if (vm->err != CBM_OK)
                return 0;
            break;
        case O_INC:
            fr[ip->dst] = step_incdec(ip, fr + ip->src1);
            break;
        case O_GINC:
            fr[ip->dst] = step_incdec(ip, glob + ip->src1);
            break;
        case O_MATH1:
            fr[ip->dst] =
                lc_conv_scalar(ip->type, cbm__builtin_math(ip->subop, fr[ip->src1], 0, false));
            break;
        case O_MATH2:
            fr[ip->dst] = lc_conv_scalar(
                ip->type, cbm__builtin_math(ip->subop, fr[ip->src1], fr[ip->src2], false));
            break;
        case O_JMP:
            ip = code + ip->src1 - 1;
            break;
        case O_JZ:
            if (fr[ip->src1] == 0)
                ip = code + ip->src2 - 1;
            break;
        case O_JNZ:
            if (fr[ip->src1] != 0)
                ip = code + ip->src2 - 1;
            break;
        case O_SPEND:
            SPEND_ONE();
            break;
        case O_JNZS:
            if (fr[ip->src1] != 0) {
                SPEND_ONE();
                ip = code + ip->src2 - 1;
            }
            break;
        case O_JMPS:
            SPEND_ONE();
            ip = code + ip->src1 - 1;
            break;
        case O_CALL: {
            const lc_fcode *cf = &p->fn[ip->src1];
            double *nf = fr + ip->src2;
            vm->stmt_pos = at;
            if (vm->call_depth >= vm->max_call_depth ||
                (size_t)(nf - vm->stack) + (size_t)cf->nreg + 1 > vm->stack_cap) {
                cbm__lc_error(vm, CBM_E_LIMIT,
                              "function calls nested too deeply (--max-call-depth)");
                return 0;
            }
            if (!cbm__lc_spend(vm, false))
                return 0;
            vm->call_depth++;
            double r = cbm__lc_run(p, ip->src1, nf, vm);
            vm->call_depth--;
            if (vm->err != CBM_OK)
                return 0;
            if (cf->rsize) /* a run result, left in the callee's frame */
                memcpy(fr + ip->dst, nf + cf->rslot, (size_t)cf->rsize * sizeof(double));
            else
                fr[ip->dst] = r;
            break;
        }
        case O_PROD:
            vm->stmt_pos = at;
            if (!vm->produce(vm->host, ip->dst, fr + ip->src1))
                return 0;
            break;
        case O_DONE:
            return 1;
        /* the cpfg dialect (lang/cpfg_code.c) */
        case O_PLD:
            fr[ip->dst] = vm->par[ip->src1];
            break;
        case O_PST:
            vm->par[ip->dst] = fr[ip->src1];
            break;
        case O_CMATH:
            fr[ip->dst] = cbm__builtin_math(ip->subop, fr[ip->src1], fr[ip->src2], true);
            break;
        case O_WSPEND:
            if (--vm->budget < 0) {
                vm->stmt_pos = at;
                cbm__lc_error(vm, CBM_E_LIMIT,
                              "while loops ran for more iterations in one step than the limit "
                              "(--max-loop-iterations, --max-operations)");
                return 0;
            }
            break;
        case O_HOST:
            vm->stmt_pos = at;
            fr[ip->dst] = vm->host_call(vm, ip, fr);
            if (vm->err != CBM_OK)
                return 0;
            break;
        case O_RET:
            return fr[ip->src1];
        default: /* O_RET0 */
            return 0;
        }
    }
}

/* ---------------------------------------------------------------- compiler */
typedef struct codegen {
    cbm_context *ctx;
    const lc_model *model;
    const lc_program *program;
    lc_fcode *code;     /* the function being written */
    int frame_size;     /* the locals' registers */
    int temp_top;       /* the next free temporary */
    int32_t pending_at; /* the statement whose first instruction is still to come */
    size_t label_at;    /* instructions before a label bound last (jumps land there) */
    bool fail;          /* not compilable (or out of memory: out_of_memory) */
    bool out_of_memory;
    bool is_body;           /* a production body: produce, and return gives no value */
    int loops;              /* enclosing loops */
    int switches;           /* enclosing switches (break leaves the innermost loop or switch) */
    int32_t break_jumps;    /* the chain of jumps to patch at the innermost loop's end */
    int32_t continue_jumps; /* the chain of jumps to patch at its step */
    lc_ins scratch;         /* what instr_at() gives after running out of memory */
    /* the constants, each in a register of its own after the locals, loaded on entry */
    double consts[64];
    int nconsts;
    int temp_base; /* the first temporary */
} codegen;

static const lc_node *node(const codegen *g, int32_t ni)
{
    return &g->model->nodes.data[ni];
}

static int32_t emit(codegen *g, int op, int dst, int src1, int src2)
{
    lc_ins x;
    memset(&x, 0, sizeof x);
    x.op = (uint8_t)op;
    x.dst = dst;
    x.src1 = src1;
    x.src2 = src2;
    x.stmt_pos = g->pending_at;
    g->pending_at = -1;
    if (CBM_ARRAY_PUSH(g->ctx, g->code->ins, x) != CBM_OK) {
        g->fail = g->out_of_memory = true;
        return -1;
    }
    return (int32_t)g->code->ins.len - 1;
}

static lc_ins *instr_at(codegen *g, int32_t i)
{
    return i >= 0 && !g->out_of_memory ? &g->code->ins.data[i] : &g->scratch;
}

/* The position where the next instruction goes, as a jump target: a statement started before
 * it gets its own instruction, so that a jump to here does not set its position. */
static int32_t label_here(codegen *g)
{
    if (g->pending_at >= 0)
        emit(g, O_NOP, 0, 0, 0);
    g->label_at = g->code->ins.len;
    return (int32_t)g->code->ins.len;
}

/* Patches a chain of jumps (linked through their target field) to target. */
static void patch_jumps(codegen *g, int32_t chain, int32_t target)
{
    while (chain >= 0 && !g->out_of_memory) {
        lc_ins *x = instr_at(g, chain);
        int32_t *f = x->op >= O_JNLT && x->op <= O_JNE ? &x->dst
                     : x->op == O_JMP                  ? &x->src1
                                                       : &x->src2;
        chain = *f;
        *f = target;
    }
}

static int new_temp(codegen *g)
{
    int r = g->temp_top++;
    if (g->temp_top > g->code->nreg)
        g->code->nreg = g->temp_top;
    return r;
}

/* n consecutive temporaries (a run for a value of several doubles) */
static int new_temps(codegen *g, int n)
{
    int r = g->temp_top;
    g->temp_top += n;
    if (g->temp_top > g->code->nreg)
        g->code->nreg = g->temp_top;
    return r;
}

/* Whether evaluating ni may change a variable (so that an operand read before it must be
 * copied first). Conservative: anything but pure scalar arithmetic counts. */
static bool may_write(const codegen *g, int32_t ni)
{
    if (ni < 0)
        return false;
    const lc_node *n = node(g, ni);
    switch (n->op) {
    case N_NUM:
    case N_LOCAL:
    case N_GLOBAL:
        return false;
    case N_FIELD:
    case N_NEG:
    case N_NOT:
    case N_CAST:
        return may_write(g, n->child1);
    case N_BIN:
    case N_AND:
    case N_OR:
    case N_COMMA:
        return may_write(g, n->child1) || may_write(g, n->child2);
    case N_COND:
        return may_write(g, n->child1) || may_write(g, n->child2) || may_write(g, n->child3);
    case N_CALLB:
        if (n->fn < FN_MATH_END) {
            for (int32_t x = n->child1; x >= 0; x = node(g, x)->next)
                if (may_write(g, x))
                    return true;
            return false;
        }
        return true;
    default:
        return true;
    }
}

static int compile_scalar(codegen *g, int32_t ni, int hint);
static int compile_value(codegen *g, int32_t ni, int dst);

/* The left operand of a comma: compiled for its effects into temporaries that are then given
 * back, a scalar (or void) into one register, a vector or struct into a run of its size. */
static void compile_for_effect(codegen *g, int32_t ni)
{
    int save = g->temp_top;
    const lc_node *a = node(g, ni);
    if (lc_is_scalar(a->type) || a->type == T_VOID)
        (void)compile_scalar(g, ni, new_temp(g));
    else
        (void)compile_value(g, ni, new_temps(g, lc_type_size(g->model, a->type)));
    g->temp_top = save;
}

/* The register of constant v (loaded on entry), or v loaded into hint when there are many. */
static int const_reg(codegen *g, double v, int hint)
{
    for (int c = 0; c < g->nconsts; c++) {
        /* the same bits, not the same value: -0.0 and 0.0 are different constants */
        uint64_t a, b;
        memcpy(&a, &g->consts[c], sizeof a);
        memcpy(&b, &v, sizeof b);
        if (a == b)
            return g->frame_size + c;
    }
    if (g->nconsts < (int)(sizeof g->consts / sizeof g->consts[0])) {
        g->consts[g->nconsts] = v;
        return g->frame_size + g->nconsts++;
    }
    int32_t i = emit(g, O_CONST, hint, 0, 0);
    instr_at(g, i)->imm = v;
    return hint;
}

/* Whether instruction op computes a value into its register dst (the others use dst otherwise). */
static bool computes(int op)
{
    return (op >= O_CONST && op <= O_CONV && op != O_GST) || (op >= O_ADDD && op <= O_MATH2) ||
           op == O_CALL || (op >= O_SIN && op <= O_EXP);
}

/* Moves the value of register r into d (nothing when it is there). A value just computed into
 * a temporary is computed into d instead when no jump lands between. */
static void emit_move(codegen *g, int d, int r)
{
    if (d == r || g->fail)
        return;
    size_t len = g->code->ins.len;
    if (r >= g->temp_base && len > 0 && g->label_at != len) {
        lc_ins *last = &g->code->ins.data[len - 1];
        if (last->dst == r && computes(last->op) && g->pending_at < 0) {
            last->dst = d;
            return;
        }
    }
    emit(g, O_MOV, d, r, 0);
}

/* A binary operator on scalars, as the tree walker chooses its arithmetic type. */
static int scalar_bin_opcode(int fn, int t, int *ty)
{
    *ty = t;
    if (fn >= B_LT)
        return O_LT + (fn - B_LT);
    if (t == T_DOUBLE && fn <= B_DIV)
        return O_ADDD + fn;
    if (t == T_FLOAT && fn <= B_DIV)
        return O_ADDF + fn;
    if (t == T_INT && fn <= B_MUL)
        return O_ADDI + fn;
    if (t == T_INT && fn <= B_REM)
        return fn == B_DIV ? O_DIVI : O_REMI;
    return O_BIN;
}

/* The first double of variable or field ni (a field of a field of a variable ...), -1: ni is
 * no such place. */
static int place(const codegen *g, int32_t ni, bool *global)
{
    const lc_node *l = node(g, ni);
    if (l->op == N_LOCAL || l->op == N_GLOBAL) {
        *global = l->op == N_GLOBAL;
        return l->slot;
    }
    if (l->op != N_FIELD)
        return -1;
    int base = place(g, l->child1, global);
    return base < 0 ? -1 : base + l->slot;
}

static int lvalue(const codegen *g, int32_t ni, bool *global)
{
    if (!lc_is_scalar(node(g, ni)->type))
        return -1;
    return place(g, ni, global);
}

/* An expression the register code has no translation for: the function does not compile (the
 * model is refused when it is loaded, lsys/lpfg.c check_compiled). */
static int unsupported(codegen *g, int dst)
{
    g->fail = true;
    return dst;
}

/* The built-ins that act on the run's state, called through the host (O_HOST, vm->host_call):
 * random numbers (the one stream of lang/random.c, drawn in the walker's order), func, the
 * derivation's direction and group, stop, printf, and the mechanics and light built-ins
 * (lsys/mechlang.c, lightlang.c: settings and operations on the whole string). */
static bool host_fn(int fn)
{
    switch (fn) {
    case FN_RAN:
    case FN_NRAN:
    case FN_DRAND:
    case FN_RAND:
    case FN_SRAND:
    case FN_FUNC:
    case FN_FORWARD:
    case FN_BACKWARD:
    case FN_USEGROUP:
    case FN_CURGROUP:
    case FN_STOP:
    case FN_PRINTF:
        return true;
    default:
        return fn >= FN_EQUILIBRIUM && fn <= FN_REACTIONBOUND;
    }
}

/* Built-in ni of host_fn: its scalar arguments left to right into a run of temporaries (a
 * string of printf has its register, unused: the host reads the node), then O_HOST with the
 * node in k, whose value the host converts to the node's type as the walker does. */
static int compile_host_call(codegen *g, int32_t ni, int dst)
{
    const lc_node *n = node(g, ni);
    int na = 0;
    for (int32_t x = n->child1; x >= 0; x = node(g, x)->next, na++)
        if ((!lc_is_scalar(node(g, x)->type) && node(g, x)->op != N_STR) || na == LC_HOST_MAXARGS) {
            g->fail = true;
            return dst;
        }
    int save = g->temp_top;
    int base = new_temps(g, na);
    int i = 0;
    for (int32_t x = n->child1; x >= 0; x = node(g, x)->next, i++) {
        if (node(g, x)->op == N_STR)
            continue;
        int s2 = g->temp_top;
        emit_move(g, base + i, compile_scalar(g, x, base + i));
        g->temp_top = s2;
    }
    lc_ins *x = instr_at(g, emit(g, O_HOST, dst, base, na));
    x->subop = (uint16_t)n->fn;
    x->imm = (double)ni;
    g->temp_top = save;
    return dst;
}

static int compile_call(codegen *g, int32_t ni, int dst);
static bool vec_bin(codegen *g, int32_t ni, int dst);
static bool vec_builtin(codegen *g, int32_t ni, int dst);
static bool frame_bin(codegen *g, int32_t ni, int dst);
static bool frame_builtin(codegen *g, int32_t ni, int dst);
static int field_of(codegen *g, int32_t ni, int dst, int sz);

/* Compiles expression ni; returns the register holding its value: a variable's own register,
 * or hint (a temporary of the caller) where it computed it. */
static int compile_scalar(codegen *g, int32_t ni, int hint)
{
    if (g->fail)
        return hint;
    const lc_node *n = node(g, ni);
    bool scalar = lc_is_scalar(n->type);
    switch (n->op) {
    case N_NUM:
        return const_reg(g, n->value, hint);
    case N_LOCAL:
        if (!scalar)
            break;
        return n->slot;
    case N_GLOBAL:
        if (!scalar)
            break;
        emit(g, O_GLD, hint, n->slot, 0);
        return hint;
    case N_FIELD: {
        bool global;
        int slot = scalar ? place(g, ni, &global) : -1;
        if (slot < 0 && scalar)
            return field_of(g, ni, hint, 1);
        if (slot < 0)
            break;
        if (!global)
            return slot;
        emit(g, O_GLD, hint, slot, 0);
        return hint;
    }
    case N_NEG:
    case N_NOT:
    case N_CAST: {
        if (!scalar || !lc_is_scalar(node(g, n->child1)->type))
            break;
        if (n->op == N_CAST && node(g, n->child1)->op == N_NUM) { /* a converted number: a number */
            lc_node k = *node(g, n->child1);
            k.value = lc_conv_scalar(n->type, k.value);
            return const_reg(g, k.value, hint);
        }
        int r = compile_scalar(g, n->child1, hint);
        int32_t i = emit(g, n->op == N_NEG ? O_NEG : n->op == N_NOT ? O_NOT : O_CONV, hint, r, 0);
        instr_at(g, i)->type = (uint8_t)n->type;
        return hint;
    }
    case N_BIN: {
        int ta = node(g, n->child1)->type, tb = node(g, n->child2)->type;
        if (!lc_is_scalar(ta) || !lc_is_scalar(tb)) {
            if (scalar && vec_bin(g, ni, hint)) /* a dot product */
                return hint;
            break;
        }
        int ra = compile_scalar(g, n->child1, new_temp(g));
        if (ra < g->frame_size &&
            may_write(g, n->child2)) { /* read before the right operand runs */
            int t = new_temp(g);
            emit(g, O_MOV, t, ra, 0);
            ra = t;
        }
        int rb = compile_scalar(g, n->child2, new_temp(g));
        int ct = n->type == T_BOOL ? lc_arith_type(ta, tb) : n->type;
        if (n->type == T_BOOL && ct == T_INT) /* compare ints exactly */
            ct = T_DOUBLE;
        int ty;
        int op = scalar_bin_opcode(n->fn, ct, &ty);
        int32_t i = emit(g, op, hint, ra, rb);
        instr_at(g, i)->type = (uint8_t)ty;
        instr_at(g, i)->subop = n->fn;
        return hint;
    }
    case N_AND:
    case N_OR: {
        int r = compile_scalar(g, n->child1, new_temp(g));
        emit(g, O_BOOL, hint, r, 0);
        int32_t j = emit(g, n->op == N_AND ? O_JZ : O_JNZ, 0, hint, -1);
        r = compile_scalar(g, n->child2, new_temp(g));
        emit(g, O_BOOL, hint, r, 0);
        patch_jumps(g, j, label_here(g));
        return hint;
    }
    case N_COND: {
        if (!scalar)
            break;
        int r = compile_scalar(g, n->child1, new_temp(g));
        int32_t jelse = emit(g, O_JZ, 0, r, -1);
        emit_move(g, hint, compile_scalar(g, n->child2, hint));
        int32_t jend = emit(g, O_JMP, 0, -1, 0);
        patch_jumps(g, jelse, label_here(g));
        emit_move(g, hint, compile_scalar(g, n->child3, hint));
        patch_jumps(g, jend, label_here(g));
        return hint;
    }
    case N_COMMA: {
        if (!scalar)
            break;
        compile_for_effect(g, n->child1);
        return compile_scalar(g, n->child2, hint);
    }
    case N_ASSIGN: {
        bool global;
        int slot = lvalue(g, n->child1, &global);
        if (!scalar || slot < 0)
            break;
        int r = compile_scalar(g, n->child2, hint);
        if (global) {
            emit(g, O_GST, slot, r, 0);
            return r;
        }
        emit_move(g, slot, r);
        return slot;
    }
    case N_INCDEC: {
        bool global;
        int slot = lvalue(g, n->child1, &global);
        if (slot < 0)
            break;
        int32_t i = emit(g, global ? O_GINC : O_INC, hint, slot, 0);
        instr_at(g, i)->type = (uint8_t)n->type;
        instr_at(g, i)->subop = n->fn;
        return hint;
    }
    case N_CALLB: {
        if (host_fn(n->fn))
            return compile_host_call(g, ni, hint);
        if (n->fn >= FN_MATH_END) {
            if (scalar && vec_builtin(g, ni, hint)) /* Dot, Length */
                return hint;
            break;
        }
        for (int32_t x = n->child1; x >= 0; x = node(g, x)->next)
            if (!lc_is_scalar(node(g, x)->type))
                return unsupported(g, hint);
        int r[2] = {-1, -1}, na = 0;
        for (int32_t x = n->child1; x >= 0 && na < 2; x = node(g, x)->next, na++) {
            if (!lc_is_scalar(node(g, x)->type)) {
                g->fail = true;
                return hint;
            }
            r[na] = compile_scalar(g, x, new_temp(g));
            if (na == 0 && r[0] < g->frame_size && node(g, x)->next >= 0 &&
                may_write(g, node(g, x)->next)) {
                int t = new_temp(g);
                emit(g, O_MOV, t, r[0], 0);
                r[0] = t;
            }
        }
        if (na == 0) { /* no argument: both are 0 */
            r[0] = new_temp(g);
            int32_t i = emit(g, O_CONST, r[0], 0, 0);
            instr_at(g, i)->imm = 0;
        }
        int t = n->type == T_VOID ? T_DOUBLE : n->type;
        int op = na == 2 ? O_MATH2 : O_MATH1;
        if (t == T_DOUBLE && na == 1) /* cbm__builtin_math's radian ones, without its switch */
            op = n->fn == FN_SIN    ? O_SIN
                 : n->fn == FN_COS  ? O_COS
                 : n->fn == FN_SQRT ? O_SQRT
                 : n->fn == FN_EXP  ? O_EXP
                                    : op;
        int32_t i = emit(g, op, hint, r[0], r[1]);
        instr_at(g, i)->type = (uint8_t)t;
        instr_at(g, i)->subop = n->fn;
        return hint;
    }
    case N_CALLU:
        if (!scalar && n->type != T_VOID)
            break;
        return compile_call(g, ni, hint);
    case N_INCTX: { /* the host matches the context and binds its formals in the frame */
        lc_ins *x = instr_at(g, emit(g, O_HOST, hint, 0, 0));
        x->subop = LC_HOST_CONTEXT;
        x->imm = (double)ni;
        return hint;
    }
    default:
        break;
    }
    if (!scalar && n->type != T_VOID) { /* not a scalar where one is read */
        g->fail = true;
        return hint;
    }
    return unsupported(g, hint);
}

static void compile_stmts(codegen *g, int32_t ni);

/* Copies the run of n registers (or globals: from_global) at r to the run at d. */
static void copy_run(codegen *g, int d, int r, int n, bool from_global)
{
    for (int i = 0; i < n && (d != r || from_global); i++)
        emit(g, from_global ? O_GLD : O_MOV, d + i, r + i, 0);
}

/* Rounds the run of a value of type t at register r in place, as lc_conv_value. */
static void conv_run(codegen *g, int t, int r)
{
    if (lc_is_scalar(t)) {
        if (t != T_DOUBLE)
            instr_at(g, emit(g, O_CONV, r, r, 0))->type = (uint8_t)t;
        return;
    }
    if (t == T_V3F) {
        for (int i = 0; i < 3; i++)
            instr_at(g, emit(g, O_CONV, r + i, r + i, 0))->type = T_FLOAT;
        return;
    }
    if (t == T_V3D)
        return;
    const lc_type *ty = &g->model->types.data[t];
    for (int f = 0; f < ty->nfields; f++)
        conv_run(g, ty->ftype[f], r + ty->foff[f]);
}

/* Compiles expression ni of any type: the first register of the run holding its value (a
 * local's own run, or dst, a run of the caller of the value's size). Scalars are compile_scalar's;
 * the values of several doubles are copied: variables, fields, constructors, assignments,
 * conditionals. */
static int compile_value(codegen *g, int32_t ni, int dst)
{
    if (g->fail)
        return dst;
    const lc_node *n = node(g, ni);
    if (lc_is_scalar(n->type))
        return compile_scalar(g, ni, dst);
    int sz = lc_type_size(g->model, n->type);
    switch (n->op) {
    case N_LOCAL:
    case N_GLOBAL:
    case N_FIELD: {
        bool global;
        int slot = place(g, ni, &global);
        if (slot < 0)
            break;
        if (!global)
            return slot;
        copy_run(g, dst, slot, sz, true);
        return dst;
    }
    case N_CTOR: {
        if (n->child1 < 0) {
            for (int i = 0; i < sz; i++)
                instr_at(g, emit(g, O_CONST, dst + i, 0, 0))->imm = 0;
            return dst;
        }
        int off = 0;
        for (int32_t x = n->child1; x >= 0; x = node(g, x)->next) {
            int xs = lc_type_size(g->model, node(g, x)->type);
            if (off + xs > sz) {
                g->fail = true;
                return dst;
            }
            int save = g->temp_top;
            int r = compile_value(g, x, dst + off);
            copy_run(g, dst + off, r, xs, false);
            g->temp_top = save;
            off += xs;
        }
        return dst;
    }
    case N_ASSIGN: {
        bool global;
        int slot = place(g, n->child1, &global);
        if (slot < 0 || lc_type_size(g->model, node(g, n->child1)->type) != sz)
            break;
        int r = compile_value(g, n->child2, dst);
        for (int i = 0; i < sz; i++)
            emit(g, global ? O_GST : O_MOV, slot + i, r + i, 0);
        return r;
    }
    case N_COND: {
        int r = compile_scalar(g, n->child1, new_temp(g));
        int32_t jelse = emit(g, O_JZ, 0, r, -1);
        copy_run(g, dst, compile_value(g, n->child2, dst), sz, false);
        int32_t jend = emit(g, O_JMP, 0, -1, 0);
        patch_jumps(g, jelse, label_here(g));
        copy_run(g, dst, compile_value(g, n->child3, dst), sz, false);
        patch_jumps(g, jend, label_here(g));
        return dst;
    }
    case N_CALLU:
        return compile_call(g, ni, dst);
    case N_BIN:
        if (vec_bin(g, ni, dst) || frame_bin(g, ni, dst))
            return dst;
        break;
    case N_CAST: /* V3d to V3f and back: the components, rounded as the walker's ev */
        if (lc_type_size(g->model, node(g, n->child1)->type) != sz)
            break;
        copy_run(g, dst, compile_value(g, n->child1, dst), sz, false);
        conv_run(g, n->type, dst);
        return dst;
    case N_CALLB:
        if (vec_builtin(g, ni, dst) || frame_builtin(g, ni, dst))
            return dst;
        break;
    case N_NEG: { /* each component negated, as ev */
        if (lc_type_size(g->model, node(g, n->child1)->type) != sz)
            break;
        int r = compile_value(g, n->child1, dst);
        for (int i = 0; i < sz; i++)
            emit(g, O_NEG, dst + i, r + i, 0);
        return dst;
    }
    case N_COMMA: {
        compile_for_effect(g, n->child1);
        return compile_value(g, n->child2, dst);
    }
    default:
        break;
    }
    if (n->op == N_FIELD) /* a field of a value that is no variable: the value, then the field */
        return field_of(g, ni, dst, sz);
    return unsupported(g, dst);
}

/* Vector arithmetic on V3f and V3d as the tree walker's ev (and its Dot and Cross) computes
 * it: both operands whole (the left first), the components in doubles, then the result of type
 * `type` rounded (V3f components to float32): of two vectors +, -, % (cross) and otherwise *
 * (dot, a scalar); a vector times (otherwise divided by) a scalar; a scalar times a vector. The
 * result to the run at dst; false (nothing emitted) when it is no such operation. */
static bool vec_op(codegen *g, int32_t ia, int32_t ib, int fn, int type, int dst)
{
    int ta = node(g, ia)->type, tb = node(g, ib)->type;
    bool va = lc_is_vec(ta), vb = lc_is_vec(tb);
    if ((!va && !lc_is_scalar(ta)) || (!vb && !lc_is_scalar(tb)) || (!va && !vb))
        return false;
    bool dot = va && vb && fn != B_ADD && fn != B_SUB && fn != B_REM;
    if (dot ? !lc_is_scalar(type) : !lc_is_vec(type))
        return false;
    int save = g->temp_top;
    int ra = va ? compile_value(g, ia, new_temps(g, 3)) : compile_scalar(g, ia, new_temp(g));
    if (ra < g->frame_size && may_write(g, ib)) { /* read before the right operand runs */
        int t = new_temps(g, va ? 3 : 1);
        copy_run(g, t, ra, va ? 3 : 1, false);
        ra = t;
    }
    int rb = vb ? compile_value(g, ib, new_temps(g, 3)) : compile_scalar(g, ib, new_temp(g));
    /* into temporaries when dst is a variable's run, which an operand may be */
    int r = dst < g->temp_base ? new_temps(g, 3) : dst;
    if (dot) {
        int t = new_temp(g);
        emit(g, O_MULD, r, ra, rb);
        emit(g, O_MULD, t, ra + 1, rb + 1);
        emit(g, O_ADDD, r, r, t);
        emit(g, O_MULD, t, ra + 2, rb + 2);
        emit(g, O_ADDD, r, r, t);
    } else if (va && vb && fn == B_REM) {
        int t = new_temp(g);
        for (int i = 0; i < 3; i++) {
            int j = (i + 1) % 3, k = (i + 2) % 3;
            emit(g, O_MULD, r + i, ra + j, rb + k);
            emit(g, O_MULD, t, ra + k, rb + j);
            emit(g, O_SUBD, r + i, r + i, t);
        }
    } else
        for (int i = 0; i < 3; i++) {
            int op = va && vb ? (fn == B_ADD ? O_ADDD : O_SUBD)
                     : va     ? (fn == B_MUL ? O_MULD : O_DIVD)
                              : O_MULD;
            emit(g, op, r + i, va ? ra + i : ra, vb ? rb + i : rb);
        }
    copy_run(g, dst, r, dot ? 1 : 3, false);
    conv_run(g, type, dst);
    g->temp_top = save;
    return true;
}

static bool vec_bin(codegen *g, int32_t ni, int dst)
{
    const lc_node *n = node(g, ni);
    return vec_op(g, n->child1, n->child2, n->fn, n->type, dst);
}

/* The vector built-ins Dot, Cross, Length and Normalize of V3f and V3d as call_builtin computes
 * them (Normalize of a zero vector: zeros); false (nothing emitted) for the others. */
static bool vec_builtin(codegen *g, int32_t ni, int dst)
{
    const lc_node *n = node(g, ni);
    int32_t x = n->child1;
    if (x < 0 || !lc_is_vec(node(g, x)->type))
        return false;
    int32_t x1 = node(g, x)->next;
    if (n->fn == FN_DOT || n->fn == FN_CROSS)
        return x1 >= 0 && lc_is_vec(node(g, x1)->type) &&
               vec_op(g, x, x1, n->fn == FN_DOT ? B_MUL : B_REM, n->type, dst);
    if (!(n->fn == FN_LENGTH && lc_is_scalar(n->type)) &&
        !(n->fn == FN_NORMALIZE && lc_is_vec(n->type)))
        return false;
    int save = g->temp_top;
    int rv = compile_value(g, x, new_temps(g, 3));
    int l = new_temp(g), t = new_temp(g);
    emit(g, O_MULD, l, rv, rv);
    emit(g, O_MULD, t, rv + 1, rv + 1);
    emit(g, O_ADDD, l, l, t);
    emit(g, O_MULD, t, rv + 2, rv + 2);
    emit(g, O_ADDD, l, l, t);
    emit(g, O_SQRT, l, l, 0);
    if (n->fn == FN_LENGTH) {
        copy_run(g, dst, l, 1, false);
        conv_run(g, n->type, dst);
        g->temp_top = save;
        return true;
    }
    int r = dst < g->temp_base ? new_temps(g, 3) : dst;
    int32_t jzero = emit(g, O_JNGT, -1, l, const_reg(g, 0.0, t));
    for (int i = 0; i < 3; i++)
        emit(g, O_DIVD, r + i, rv + i, l);
    int32_t jend = emit(g, O_JMP, 0, -1, 0);
    patch_jumps(g, jzero, label_here(g));
    for (int i = 0; i < 3; i++)
        instr_at(g, emit(g, O_CONST, r + i, 0, 0))->imm = 0;
    patch_jumps(g, jend, label_here(g));
    copy_run(g, dst, r, 3, false);
    conv_run(g, n->type, dst);
    g->temp_top = save;
    return true;
}

/* ---- quaternions, frames (TurtleVec) and LocVec, as the tree walker's ev and call_builtin
 * compute them: the operands whole into temporaries first (left to right), the components in
 * doubles with C's order of operations, the result copied to dst and rounded to its type. */

/* The run of value x (of sz doubles) in fresh temporaries, so that no later write changes it. */
static int arg_run(codegen *g, int32_t x, int sz)
{
    int t = new_temps(g, sz);
    if (sz == 1)
        emit_move(g, t, compile_scalar(g, x, t));
    else
        copy_run(g, t, compile_value(g, x, t), sz, false);
    return t;
}

/* r[0..2] = u x v, as the walker's cross products: u1 v2 - u2 v1 ...; t a temporary */
static void cross3(codegen *g, int r, int u, int v, int t)
{
    for (int i = 0; i < 3; i++) {
        int j = (i + 1) % 3, k = (i + 2) % 3;
        emit(g, O_MULD, r + i, u + j, v + k);
        emit(g, O_MULD, t, u + k, v + j);
        emit(g, O_SUBD, r + i, r + i, t);
    }
}

/* d = u0 w0 + u1 w1 + u2 w2 (left to right); t a temporary other than d */
static void dot3(codegen *g, int d, int u, int w, int t)
{
    emit(g, O_MULD, d, u, w);
    emit(g, O_MULD, t, u + 1, w + 1);
    emit(g, O_ADDD, d, d, t);
    emit(g, O_MULD, t, u + 2, w + 2);
    emit(g, O_ADDD, d, d, t);
}

/* d = (l > 0 ? l : 1) */
static void positive_or_one(codegen *g, int d, int l)
{
    int k = new_temp(g);
    int32_t j = emit(g, O_JNGT, -1, l, const_reg(g, 0.0, k));
    emit(g, O_MOV, d, l, 0);
    int32_t e = emit(g, O_JMP, 0, -1, 0);
    patch_jumps(g, j, label_here(g));
    emit_move(g, d, const_reg(g, 1.0, k));
    patch_jumps(g, e, label_here(g));
}

/* The result run r of sz doubles to dst, rounded to type t. */
static void store_result(codegen *g, int dst, int r, int sz, int t)
{
    copy_run(g, dst, r, sz, false);
    conv_run(g, t, dst);
}

/* Field ni of a value that is no variable (a call's result ...): the value into temporaries,
 * then its field's doubles to dst, as ev. */
static int field_of(codegen *g, int32_t ni, int dst, int sz)
{
    const lc_node *n = node(g, ni);
    int save = g->temp_top;
    int bs = lc_type_size(g->model, node(g, n->child1)->type);
    if (n->slot + sz > bs) {
        g->fail = true;
        return dst;
    }
    int r = arg_run(g, n->child1, bs);
    copy_run(g, dst, r + n->slot, sz, false);
    g->temp_top = save;
    return dst;
}

/* The Hamilton product's terms: out[i] = sum of sign * q[qi] * b[bi], in the walker's order */
static const signed char HAMILTON[4][4][3] = {
    {{0, 0, 1}, {1, 1, -1}, {2, 2, -1}, {3, 3, -1}},
    {{0, 1, 1}, {1, 0, 1}, {2, 3, 1}, {3, 2, -1}},
    {{0, 2, 1}, {1, 3, -1}, {2, 0, 1}, {3, 1, 1}},
    {{0, 3, 1}, {1, 2, 1}, {2, 1, -1}, {3, 0, 1}},
};

/* Quaternion times quaternion (Hamilton), quaternion times vector or TurtleVec (each vector
 * rotated: v + 2w (u x v) + 2 u x (u x v)), LocVec arithmetic (+, -, *, / by components, a
 * scalar operand broadcast); false (nothing emitted) for the others. */
static bool frame_bin(codegen *g, int32_t ni, int dst)
{
    const lc_node *n = node(g, ni);
    int ta = node(g, n->child1)->type, tb = node(g, n->child2)->type;
    int sa = lc_type_size(g->model, ta), sb = lc_type_size(g->model, tb);
    int sz = lc_type_size(g->model, n->type);
    int save = g->temp_top;
    if (n->type == T_LOCVEC) {
        if ((sa != 1 && sa != 3) || (sb != 1 && sb != 3) || sz != 3)
            return false;
        int a = arg_run(g, n->child1, sa), b = arg_run(g, n->child2, sb), r = new_temps(g, 3);
        int op = n->fn == B_ADD   ? O_ADDD
                 : n->fn == B_SUB ? O_SUBD
                 : n->fn == B_MUL ? O_MULD
                                  : O_DIVD;
        for (int i = 0; i < 3; i++)
            emit(g, op, r + i, a + (sa == 1 ? 0 : i), b + (sb == 1 ? 0 : i));
        store_result(g, dst, r, 3, n->type);
        g->temp_top = save;
        return true;
    }
    if (ta != T_QUAT)
        return false;
    if (tb == T_QUAT) {
        if (sa != 4 || sb != 4 || sz != 4)
            return false;
        int q = arg_run(g, n->child1, 4), b = arg_run(g, n->child2, 4), r = new_temps(g, 4),
            t = new_temp(g);
        for (int i = 0; i < 4; i++)
            for (int k = 0; k < 4; k++) {
                const signed char *h = HAMILTON[i][k];
                emit(g, O_MULD, k ? t : r + i, q + h[0], b + h[1]);
                if (k)
                    emit(g, h[2] > 0 ? O_ADDD : O_SUBD, r + i, r + i, t);
            }
        store_result(g, dst, r, 4, n->type);
        g->temp_top = save;
        return true;
    }
    int nv = tb == T_TVEC ? 3 : 1;
    if (sa != 4 || sb != 3 * nv || sz != 3 * nv || (tb != T_TVEC && !lc_is_vec(tb)))
        return false;
    int q = arg_run(g, n->child1, 4), b = arg_run(g, n->child2, sb), r = new_temps(g, sz);
    int t = new_temps(g, 3), c = new_temps(g, 3), x = new_temp(g), two = new_temp(g);
    two = const_reg(g, 2.0, two);
    for (int v = 0; v < nv; v++) {
        int p = b + 3 * v;
        cross3(g, t, q + 1, p, x);
        for (int i = 0; i < 3; i++)
            emit(g, O_MULD, t + i, two, t + i);
        cross3(g, c, q + 1, t, x);
        for (int i = 0; i < 3; i++) {
            emit(g, O_MULD, x, q, t + i);
            emit(g, O_ADDD, r + 3 * v + i, p + i, x);
            emit(g, O_ADDD, r + 3 * v + i, r + 3 * v + i, c + i);
        }
    }
    store_result(g, dst, r, sz, n->type);
    g->temp_top = save;
    return true;
}

/* MakeQuaternion, VecRotate (Rodrigues' rotation of a vector or of each vector of a
 * TurtleVec), ToLocal, ToWorld and Normalize of a TurtleVec; false (nothing emitted) for the
 * others. */
static bool frame_builtin(codegen *g, int32_t ni, int dst)
{
    const lc_node *n = node(g, ni);
    int32_t x = n->child1;
    if (x < 0)
        return false;
    int32_t x1 = node(g, x)->next;
    int sz = lc_type_size(g->model, n->type);
    int s0 = lc_type_size(g->model, node(g, x)->type);
    int save = g->temp_top;
    switch (n->fn) {
    case FN_MAKEQ: {
        if (s0 != 3 || x1 < 0 || sz != 4)
            return false;
        int u = arg_run(g, x, 3), ang = arg_run(g, x1, 1), r = new_temps(g, 4);
        int l = new_temp(g), t = new_temp(g), h = new_temp(g), sn = new_temp(g);
        dot3(g, l, u, u, t);
        emit(g, O_SQRT, l, l, 0);
        emit(g, O_DIVD, h, ang, const_reg(g, 2.0, t));
        emit(g, O_SIN, sn, h, 0);
        positive_or_one(g, t, l);
        emit(g, O_DIVD, sn, sn, t);
        emit(g, O_COS, r, h, 0);
        for (int i = 0; i < 3; i++)
            emit(g, O_MULD, r + 1 + i, u + i, sn);
        store_result(g, dst, r, 4, n->type);
        break;
    }
    case FN_VECROT: {
        int32_t x2 = x1 >= 0 ? node(g, x1)->next : -1;
        int nv = n->type == T_TVEC ? 3 : 1;
        if (x2 < 0 || s0 != 3 * nv || sz != s0 || lc_type_size(g->model, node(g, x1)->type) != 3)
            return false;
        int u = arg_run(g, x, s0), w = arg_run(g, x1, 3), ang = arg_run(g, x2, 1);
        int r = new_temps(g, sz), ax = new_temps(g, 3), cr = new_temps(g, 3);
        int l = new_temp(g), t = new_temp(g), c = new_temp(g), sn = new_temp(g), omc = new_temp(g),
            d = new_temp(g);
        dot3(g, l, w, w, t);
        emit(g, O_SQRT, l, l, 0);
        positive_or_one(g, t, l);
        for (int i = 0; i < 3; i++)
            emit(g, O_DIVD, ax + i, w + i, t);
        emit(g, O_COS, c, ang, 0);
        emit(g, O_SIN, sn, ang, 0);
        emit(g, O_SUBD, omc, const_reg(g, 1.0, t), c);
        for (int v = 0; v < nv; v++) {
            int p = u + 3 * v;
            dot3(g, d, ax, p, t);
            cross3(g, cr, ax, p, t);
            for (int i = 0; i < 3; i++) {
                int o = r + 3 * v + i;
                emit(g, O_MULD, o, p + i, c);
                emit(g, O_MULD, t, cr + i, sn);
                emit(g, O_ADDD, o, o, t);
                emit(g, O_MULD, t, ax + i, d);
                emit(g, O_MULD, t, t, omc);
                emit(g, O_ADDD, o, o, t);
            }
        }
        store_result(g, dst, r, sz, n->type);
        break;
    }
    case FN_TOLOCAL:
    case FN_TOWORLD: {
        if (s0 != 3 || x1 < 0 || lc_type_size(g->model, node(g, x1)->type) != 9 || sz != 3)
            return false;
        int v = arg_run(g, x, 3), f = arg_run(g, x1, 9), r = new_temps(g, 3), t = new_temp(g);
        for (int i = 0; i < 3; i++)
            for (int k = 0; k < 3; k++) {
                int fk = n->fn == FN_TOLOCAL ? f + 3 * i + k : f + 3 * k + i;
                emit(g, O_MULD, k ? t : r + i, v + k, fk);
                if (k)
                    emit(g, O_ADDD, r + i, r + i, t);
            }
        store_result(g, dst, r, 3, n->type);
        break;
    }
    case FN_NORMALIZE: {
        if (n->type != T_TVEC || s0 != 9 || sz != 9)
            return false;
        int u = arg_run(g, x, 9), r = new_temps(g, 9), l = new_temp(g), t = new_temp(g);
        for (int v = 0; v < 3; v++) {
            int p = u + 3 * v;
            dot3(g, l, p, p, t);
            emit(g, O_SQRT, l, l, 0);
            int32_t jz = emit(g, O_JNGT, -1, l, const_reg(g, 0.0, t));
            for (int i = 0; i < 3; i++)
                emit(g, O_DIVD, r + p - u + i, p + i, l);
            int32_t je = emit(g, O_JMP, 0, -1, 0);
            patch_jumps(g, jz, label_here(g));
            for (int i = 0; i < 3; i++)
                instr_at(g, emit(g, O_CONST, r + p - u + i, 0, 0))->imm = 0;
            patch_jumps(g, je, label_here(g));
        }
        store_result(g, dst, r, 9, n->type);
        break;
    }
    default:
        return false;
    }
    g->temp_top = save;
    return true;
}

/* A call of user function ni, as the tree walker's call_user: the arguments computed in order
 * into a run of temporaries (the callee's frame: each parameter a run of its size), the call,
 * then each reference parameter's run copied back to its variable in the order of the
 * parameters; a scalar result to dst, a run result copied from the callee's frame to the run at
 * dst by O_CALL. */
static int compile_call(codegen *g, int32_t ni, int dst)
{
    const lc_node *n = node(g, ni);
    const lc_function *f = &g->model->funcs.data[n->slot];
    const lc_fcode *cf = &g->program->fn[n->slot];
    bool ok = cf->compiled;
    int a = 0;
    for (int32_t x = n->child1; x >= 0 && ok; x = node(g, x)->next, a++) {
        const lc_node *xn = node(g, x);
        ok = a < f->nparams &&
             lc_type_size(g->model, xn->type) == lc_type_size(g->model, f->ptype[a]) &&
             (!f->pref[a] || xn->op == N_LOCAL || xn->op == N_GLOBAL);
    }
    if (!ok || a != f->nparams)
        return unsupported(g, dst);
    int save = g->temp_top;
    int base = new_temps(g, cf->npd);
    int off = 0;
    a = 0;
    for (int32_t x = n->child1; x >= 0; x = node(g, x)->next, a++) {
        int xs = lc_type_size(g->model, f->ptype[a]);
        int s2 = g->temp_top;
        if (lc_is_scalar(node(g, x)->type))
            emit_move(g, base + off, compile_scalar(g, x, base + off));
        else
            copy_run(g, base + off, compile_value(g, x, base + off), xs, false);
        g->temp_top = s2;
        off += xs;
    }
    if (off != cf->npd) {
        g->fail = true;
        return dst;
    }
    emit(g, O_CALL, dst, n->slot, base);
    off = 0;
    a = 0;
    for (int32_t x = n->child1; x >= 0 && cf->refs; x = node(g, x)->next, a++) {
        int xs = lc_type_size(g->model, f->ptype[a]);
        const lc_node *xn = node(g, x);
        for (int i = 0; i < xs && f->pref[a]; i++)
            emit(g, xn->op == N_GLOBAL ? O_GST : O_MOV, xn->slot + i, base + off + i, 0);
        off += xs;
    }
    g->temp_top = save;
    return dst;
}

/* `produce` (or `nproduce`) of the modules [first, first + n) of the model's sms: each
 * module's parameters computed into a run of temporaries and appended; `produce` ends the
 * body. */
static void compile_produce(codegen *g, const lc_node *n)
{
    for (int32_t i = 0; i < n->child2 && !g->fail; i++) {
        const lc_modref *sm = &g->model->sms.data[n->child1 + i];
        const lc_module *mod = &g->model->mods.data[sm->mod];
        int save = g->temp_top;
        int base = new_temps(g, mod->size);
        int off = 0, a = 0;
        for (int32_t x = sm->args; x >= 0; x = node(g, x)->next, a++) {
            int xs = a < mod->nparams ? lc_type_size(g->model, mod->ptype[a]) : -1;
            if (xs != lc_type_size(g->model, node(g, x)->type) || off + xs > mod->size) {
                g->fail = true;
                return;
            }
            int s2 = g->temp_top;
            g->pending_at = node(g, x)->pos; /* a runtime error names the argument */
            int r = compile_value(g, x, base + off);
            copy_run(g, base + off, r, xs, false);
            g->temp_top = s2;
            off += xs;
        }
        if (off != mod->size) {
            g->fail = true;
            return;
        }
        emit(g, O_PROD, n->child1 + i, base, 0);
        g->temp_top = save;
    }
    if (!n->fn)
        emit(g, O_DONE, 0, 0, 0);
}

/* Compiles condition c into a temporary: the register of its value, and in *cmp the comparison
 * that computed it last into that temporary, which the caller may turn into a compare-and-jump
 * (NULL when there is none, or a jump may land on the instruction after it). */
static int compile_condition(codegen *g, int32_t c, lc_ins **cmp)
{
    int save = g->temp_top;
    int t = new_temp(g);
    int r = compile_scalar(g, c, t);
    g->temp_top = save;
    *cmp = NULL;
    size_t len = g->code->ins.len;
    if (!g->fail && r == t && len > 0 && g->label_at != len && g->pending_at < 0) {
        lc_ins *last = &g->code->ins.data[len - 1];
        if (last->dst == t && last->op >= O_LT && last->op <= O_NE)
            *cmp = last;
    }
    return r;
}

/* Compiles condition c and a jump taken when it is false (to patch); a comparison computed
 * last into its temporary becomes a compare-and-jump. */
static int32_t jump_false(codegen *g, int32_t c)
{
    lc_ins *cmp;
    int r = compile_condition(g, c, &cmp);
    if (cmp) {
        cmp->op = (uint8_t)(O_JNLT + (cmp->op - O_LT));
        cmp->dst = -1;
        return (int32_t)g->code->ins.len - 1;
    }
    return emit(g, O_JZ, 0, r, -1);
}

/* Compiles condition c and a jump to target taken when it holds. */
static void jump_true(codegen *g, int32_t c, int32_t target)
{
    lc_ins *cmp;
    int r = compile_condition(g, c, &cmp);
    if (cmp) {
        cmp->op = (uint8_t)(O_JLT + (cmp->op - O_LT));
        cmp->dst = target;
        return;
    }
    emit(g, O_JNZS, 0, r, target);
}

/* A loop with its test at the bottom: init; jump to the test; top: body; step; test: spend
 * and jump to top when it holds (a do loop spends its first iteration before top). The order
 * of evaluation is exec's (test, spend, body, step). */
static void compile_loop(codegen *g, const lc_node *n)
{
    int32_t outer_breaks = g->break_jumps, outer_continues = g->continue_jumps;
    g->break_jumps = g->continue_jumps = -1;
    g->loops++;
    if (n->op == S_FOR && n->child1 >= 0)
        compile_stmts(g, n->child1);
    int32_t c = n->op == S_FOR ? n->child2 : n->child1;
    if (c >= 0 && !lc_is_scalar(node(g, c)->type)) {
        g->fail = true;
        return;
    }
    int32_t to_test = n->op != S_DO && c >= 0 ? emit(g, O_JMP, 0, -1, 0) : -1;
    if (n->op == S_DO || c < 0)
        emit(g, O_SPEND, 0, 0, 0);
    int32_t top = label_here(g);
    compile_stmts(g, n->op == S_FOR ? n->child4 : n->child2);
    patch_jumps(g, g->continue_jumps, label_here(g));
    int save = g->temp_top;
    if (n->op == S_FOR && n->child3 >= 0) {
        if (!lc_is_scalar(node(g, n->child3)->type))
            g->fail = true;
        else
            (void)compile_scalar(g, n->child3, new_temp(g));
    }
    g->temp_top = save;
    patch_jumps(g, to_test, label_here(g));
    if (c >= 0)
        jump_true(g, c, top);
    else
        emit(g, O_JMPS, 0, top, 0);
    patch_jumps(g, g->break_jumps, label_here(g));
    g->loops--;
    g->break_jumps = outer_breaks;
    g->continue_jumps = outer_continues;
}

static void compile_stmt(codegen *g, int32_t ni);

/* Compiles the statement chain from ni, as exec runs it. */
static void compile_stmts(codegen *g, int32_t ni)
{
    for (; ni >= 0 && !g->fail; ni = node(g, ni)->next)
        compile_stmt(g, ni);
}

/* switch as exec runs it: the value once, then the labels of the cases of its body's chain
 * (the cases directly in it: a case nested deeper is no target, as in exec) compared with it
 * in their order up to the first equal one, whose case is jumped to; else the default (the
 * last one), else the end. The body runs from there through the chain; break leaves it,
 * continue goes to the enclosing loop. */
#define LC_MAX_CASES 256
static void compile_switch(codegen *g, const lc_node *n)
{
    if (!lc_is_scalar(node(g, n->child1)->type)) {
        g->fail = true;
        return;
    }
    int32_t body = node(g, n->child2)->op == S_BLOCK ? node(g, n->child2)->child1 : n->child2;
    int32_t jump[LC_MAX_CASES];
    int nc = 0;
    int32_t dflt = -1; /* the default's case node */
    int v = new_temp(g);
    emit_move(g, v, compile_scalar(g, n->child1, v));
    for (int32_t c = body; c >= 0 && !g->fail; c = node(g, c)->next) {
        const lc_node *cn = node(g, c);
        if (cn->op != S_CASE)
            continue;
        if (cn->child1 < 0) {
            dflt = c;
            continue;
        }
        if (nc == LC_MAX_CASES || !lc_is_scalar(node(g, cn->child1)->type)) {
            g->fail = true;
            return;
        }
        int save = g->temp_top;
        int t = new_temp(g);
        int r = compile_scalar(g, cn->child1, t);
        emit(g, O_EQ, t, v, r);
        jump[nc++] = emit(g, O_JNZ, 0, t, -1);
        g->temp_top = save;
    }
    if (g->fail)
        return;
    int32_t jd = emit(g, O_JMP, 0, -1, 0); /* to the default, or past the body */
    int32_t outer_breaks = g->break_jumps;
    g->break_jumps = -1;
    g->switches++;
    int k = 0;
    for (int32_t c = body; c >= 0 && !g->fail; c = node(g, c)->next) {
        const lc_node *cn = node(g, c);
        if (cn->op == S_CASE) {
            int32_t at = label_here(g);
            if (cn->child1 >= 0 && k < nc) /* the same cases as above, in order: k < nc */
                patch_jumps(g, jump[k++], at);
            if (c == dflt) {
                patch_jumps(g, jd, at);
                jd = -1;
            }
        } else
            compile_stmt(g, c);
    }
    g->switches--;
    int32_t end = label_here(g);
    patch_jumps(g, jd, end);
    patch_jumps(g, g->break_jumps, end);
    g->break_jumps = outer_breaks;
}

/* Compiles statement ni. */
static void compile_stmt(codegen *g, int32_t ni)
{
    {
        const lc_node *n = node(g, ni);
        g->pending_at = n->pos; /* exec sets the position at every statement */
        int save = g->temp_top;
        switch (n->op) {
        case S_EXPR: {
            const lc_node *e = node(g, n->child1);
            if (lc_is_scalar(e->type) || e->type == T_VOID)
                (void)compile_scalar(g, n->child1, new_temp(g));
            else
                (void)compile_value(g, n->child1, new_temps(g, lc_type_size(g->model, e->type)));
            break;
        }
        case S_DECL:
            if (!lc_is_scalar(n->type)) { /* into its run, then rounded as exec does */
                int sz = lc_type_size(g->model, n->type);
                if (n->child1 >= 0) {
                    copy_run(g, n->slot, compile_value(g, n->child1, n->slot), sz, false);
                    conv_run(g, n->type, n->slot);
                } else
                    for (int i = 0; i < sz; i++)
                        instr_at(g, emit(g, O_CONST, n->slot + i, 0, 0))->imm = 0;
            } else if (n->child1 >= 0) {
                int r = compile_scalar(g, n->child1, new_temp(g));
                if (n->type == T_DOUBLE)
                    emit_move(g, n->slot, r);
                else
                    instr_at(g, emit(g, O_CONV, n->slot, r, 0))->type = (uint8_t)n->type;
            } else
                instr_at(g, emit(g, O_CONST, n->slot, 0, 0))->imm = 0;
            break;
        case S_BLOCK:
            compile_stmts(g, n->child1);
            break;
        case S_IF: {
            if (!lc_is_scalar(node(g, n->child1)->type)) {
                g->fail = true;
                break;
            }
            int32_t jelse = jump_false(g, n->child1);
            compile_stmts(g, n->child2);
            if (n->child3 >= 0) {
                int32_t jend = emit(g, O_JMP, 0, -1, 0);
                patch_jumps(g, jelse, label_here(g));
                compile_stmts(g, n->child3);
                patch_jumps(g, jend, label_here(g));
            } else
                patch_jumps(g, jelse, label_here(g));
            break;
        }
        case S_WHILE:
        case S_DO:
        case S_FOR:
            compile_loop(g, n);
            break;
        case S_RETURN:
            if (g->is_body) { /* a body's return: its value is dropped, nothing produced */
                if (n->child1 >= 0 && lc_is_scalar(node(g, n->child1)->type))
                    (void)compile_scalar(g, n->child1, new_temp(g));
                else if (n->child1 >= 0)
                    (void)compile_value(
                        g, n->child1,
                        new_temps(g, lc_type_size(g->model, node(g, n->child1)->type)));
                emit(g, O_RET0, 0, 0, 0);
            } else if (n->child1 < 0)
                emit(g, O_RET0, 0, 0, 0);
            else if (!lc_is_scalar(n->type)) { /* the run result, rounded as exec does */
                int sz = lc_type_size(g->model, n->type);
                if (sz != g->code->rsize) {
                    g->fail = true;
                    break;
                }
                copy_run(g, g->code->rslot, compile_value(g, n->child1, new_temps(g, sz)), sz,
                         false);
                conv_run(g, n->type, g->code->rslot);
                emit(g, O_RET0, 0, 0, 0);
            } else {
                int r = compile_scalar(g, n->child1, new_temp(g));
                if (n->type != T_DOUBLE) {
                    int t = new_temp(g);
                    instr_at(g, emit(g, O_CONV, t, r, 0))->type = (uint8_t)n->type;
                    r = t;
                }
                emit(g, O_RET, 0, r, 0);
            }
            break;
        case S_SWITCH:
            compile_switch(g, n);
            break;
        case S_CASE: /* a case not directly in its switch's body: no target, as in exec */
            break;
        case S_BREAK:
        case S_CONTINUE:
            if (!g->loops && (n->op == S_CONTINUE || !g->switches)) {
                g->fail = true;
                break;
            }
            if (n->op == S_BREAK)
                g->break_jumps = emit(g, O_JMP, 0, g->break_jumps, 0);
            else
                g->continue_jumps = emit(g, O_JMP, 0, g->continue_jumps, 0);
            break;
        case S_NOP:
            break;
        case S_PRODUCE:
            if (!g->is_body)
                g->fail = true;
            else
                compile_produce(g, n);
            break;
        default:
            g->fail = true;
            break;
        }
        g->temp_top = save;
    }
}

/* What compile_code compiles: statements, a global's initialiser, the axiom, an expression. */
enum { ROOT_STMTS, ROOT_INIT, ROOT_AXIOM, ROOT_EXPR };

/* Initialiser ni of type `type` stored into the globals from slot: a struct's braces (or
 * Name(...)) field by field, each stored before the next is computed, as C++ initialises an
 * aggregate in place (a field's initialiser that reads the global being initialised sees the
 * fields before it, and zero after them); any other value computed whole into temporaries,
 * rounded to its type and stored (a constructor's arguments, V3f(...), are evaluated before it
 * runs, so they see the global as it was: zero, as reset leaves it). */
static void store_init(codegen *g, int32_t ni, int type, int slot)
{
    const lc_node *n = node(g, ni);
    if (type >= T_NBUILTIN && n->op == N_CTOR && n->child1 >= 0) {
        const lc_type *ty = &g->model->types.data[type];
        int nf = 0;
        for (int32_t x = n->child1; x >= 0; x = node(g, x)->next)
            nf++;
        if (nf == ty->nfields) {
            int f = 0;
            for (int32_t x = n->child1; x >= 0 && !g->fail; x = node(g, x)->next, f++)
                store_init(g, x, ty->ftype[f], slot + ty->foff[f]);
            return;
        }
    }
    int sz = lc_type_size(g->model, type);
    int save = g->temp_top;
    int t = new_temps(g, sz);
    copy_run(g, t, compile_value(g, ni, t), sz, false);
    conv_run(g, type, t);
    for (int i = 0; i < sz; i++)
        emit(g, O_GST, slot + i, t + i, 0);
    g->temp_top = save;
}

/* The root of kind ROOT_INIT (global number `body`), ROOT_AXIOM or ROOT_EXPR (node `body`) on a
 * frame of no locals: the initialiser's value computed into temporaries, rounded to the global's
 * type and stored, as reset stores it; the axiom's modules produced (as nproduce: the run goes on);
 * the expression's value returned. */
static void compile_root(codegen *g, int kind, int32_t body)
{
    if (kind == ROOT_INIT) {
        const lc_global *v = &g->model->gvars.data[body];
        g->pending_at = node(g, v->init)->pos; /* a runtime error names the initialiser */
        store_init(g, v->init, v->type, v->slot);
    } else if (kind == ROOT_AXIOM) {
        lc_node n;
        memset(&n, 0, sizeof n);
        n.op = S_PRODUCE;
        n.child1 = g->model->axiom.first + g->program->axiom_from;
        n.child2 = g->program->axiom_count;
        n.fn = 1;
        compile_produce(g, &n);
    } else {
        if (!lc_is_scalar(node(g, body)->type)) {
            g->fail = true;
            return;
        }
        int t = new_temp(g);
        emit(g, O_RET, 0, compile_scalar(g, body, t), 0);
    }
}

/* Compiles the statements `body` (or the root of another kind) with fsize doubles of locals
 * into p->fn[f]; false when they cannot be compiled. */
static bool compile_code(cbm_context *ctx, const lc_model *m, lc_program *p, int f, int32_t body,
                         int fsize, bool is_body, int kind, bool *nomem)
{
    lc_fcode *fc = &p->fn[f];
    fc->ins.len = 0;
    fc->fsize = fsize;
    /* twice: the first pass finds the constants, the second loads them on entry */
    codegen g;
    double consts[64] = {0};
    int nconsts = 0;
    for (int pass = 0; pass < 2; pass++) {
        fc->ins.len = 0;
        memset(&g, 0, sizeof g);
        g.ctx = ctx;
        g.model = m;
        g.program = p;
        g.code = fc;
        g.is_body = is_body;
        g.frame_size = fsize;
        g.pending_at = -1;
        g.label_at = (size_t)-1;
        g.break_jumps = g.continue_jumps = -1;
        g.nconsts = nconsts;
        memcpy(g.consts, consts, sizeof consts);
        g.temp_base = g.temp_top = fsize + nconsts;
        fc->nreg = g.temp_top;
        for (int c = 0; c < nconsts; c++)
            instr_at(&g, emit(&g, O_CONST, fsize + c, 0, 0))->imm = consts[c];
        if (kind == ROOT_STMTS)
            compile_stmts(&g, body);
        else
            compile_root(&g, kind, body);
        for (int i = 0; i < fc->rsize; i++) /* falling off the end: a result of zeros */
            instr_at(&g, emit(&g, O_CONST, fc->rslot + i, 0, 0))->imm = 0;
        emit(&g, O_RET0, 0, 0, 0);
        if (g.fail)
            break;
        nconsts = g.nconsts;
        memcpy(consts, g.consts, sizeof consts);
    }
    *nomem = g.out_of_memory;
    return !g.fail;
}

/* Compiles function f into p->fn[f]; false when it cannot be compiled. */
static bool compile_function(cbm_context *ctx, const lc_model *m, lc_program *p, int f, bool *nomem)
{
    const lc_function *fn = &m->funcs.data[f];
    p->fn[f].ins.len = 0;
    if (fn->body < 0)
        return false;
    /* the run result's registers count as locals (after the function's own) */
    return compile_code(ctx, m, p, f, fn->body, fn->fsize + p->fn[f].rsize, false, ROOT_STMTS,
                        nomem);
}

cbm_status cbm__lc_codegen(cbm_context *ctx, const lc_model *m, lc_program *p)
{
    memset(p, 0, sizeof *p);
    const lc_rules *sets[3] = {&m->main, &m->decomp, &m->interp};
    size_t nfunc = m->funcs.len, n = nfunc;
    for (int k = 0; k < 3; k++) {
        p->body0[k] = n;
        n += sets[k]->prods.len;
    }
    p->block0 = n;
    n += 4;
    p->init0 = n;
    n += m->gvars.len;
    p->axiom = n++;
    p->expr0 = n;
    n += LC_X_N;
    p->fn = cbm__calloc(ctx, n, sizeof *p->fn);
    if (!p->fn)
        return CBM_E_NOMEM;
    p->n = n;
    /* every function is assumed compiled, and those that cannot be, with their callers, are
     * taken out until nothing changes */
    for (size_t f = 0; f < nfunc; f++) {
        const lc_function *fn = &m->funcs.data[f];
        lc_fcode *fc = &p->fn[f];
        fc->compiled = true;
        for (int i = 0; i < fn->nparams; i++) {
            fc->npd += lc_type_size(m, fn->ptype[i]);
            fc->refs = fc->refs || fn->pref[i];
        }
        fc->rslot = fn->fsize;
        fc->rsize = fn->ret_type == T_VOID || lc_is_scalar(fn->ret_type)
                        ? 0
                        : lc_type_size(m, fn->ret_type);
    }
    for (bool changed = true; changed;) {
        changed = false;
        for (size_t f = 0; f < nfunc; f++) {
            if (!p->fn[f].compiled)
                continue;
            bool nomem = false;
            if (!compile_function(ctx, m, p, (int)f, &nomem)) {
                if (nomem)
                    return CBM_E_NOMEM;
                p->fn[f].compiled = false;
                changed = true;
            }
        }
    }
    /* then the production bodies, which call the compiled functions */
    for (int k = 0; k < 3; k++)
        for (size_t q = 0; q < sets[k]->prods.len; q++) {
            const lc_production *pr = &sets[k]->prods.data[q];
            size_t f = p->body0[k] + q;
            bool nomem = false;
            p->fn[f].compiled = pr->body >= 0 && compile_code(ctx, m, p, (int)f, pr->body,
                                                              pr->fsize, true, ROOT_STMTS, &nomem);
            if (nomem)
                return CBM_E_NOMEM;
            if (!p->fn[f].compiled)
                p->fn[f].ins.len = 0;
        }
    /* the blocks: statements on a frame of their own, as bodies that produce nothing */
    for (int b = 0; b < 4; b++) {
        size_t f = p->block0 + (size_t)b;
        bool nomem = false;
        p->fn[f].compiled =
            m->blocks[b] >= 0 && compile_code(ctx, m, p, (int)f, m->blocks[b], m->block_fsize[b],
                                              true, ROOT_STMTS, &nomem);
        if (nomem)
            return CBM_E_NOMEM;
        if (!p->fn[f].compiled)
            p->fn[f].ins.len = 0;
    }
    /* what runs once: the globals' initialisers, the axiom, the depths and derivation length */
    const int32_t expr[LC_X_N] = {m->decomp.depth <= -2 ? -2 - m->decomp.depth : -1,
                                  m->interp.depth <= -2 ? -2 - m->interp.depth : -1, m->dlen_expr};
    for (int x = 0; x < LC_X_N; x++)
        p->xpresent[x] = expr[x] >= 0;
    p->axiom_from = 0;
    p->axiom_count = m->axiom.n < LC_AXIOM_PART ? m->axiom.n : LC_AXIOM_PART;
    for (size_t f = p->init0; f < p->n; f++) {
        int kind = f < p->axiom ? ROOT_INIT : f == p->axiom ? ROOT_AXIOM : ROOT_EXPR;
        int32_t r = kind == ROOT_INIT    ? (int32_t)(f - p->init0)
                    : kind == ROOT_AXIOM ? 0
                                         : expr[f - p->expr0];
        if ((kind == ROOT_INIT && m->gvars.data[r].init < 0) || r < 0)
            continue;
        bool nomem = false;
        p->fn[f].compiled = compile_code(ctx, m, p, (int)f, r, 0, true, kind, &nomem);
        if (nomem)
            return CBM_E_NOMEM;
        if (!p->fn[f].compiled)
            p->fn[f].ins.len = 0;
    }
    return CBM_OK;
}

cbm_status cbm__lc_codegen_axiom(cbm_context *ctx, const lc_model *m, lc_program *p, int32_t from,
                                 int32_t count)
{
    p->axiom_from = from;
    p->axiom_count = count;
    bool nomem = false;
    lc_fcode *fc = &p->fn[p->axiom];
    fc->compiled = compile_code(ctx, m, p, (int)p->axiom, 0, 0, true, ROOT_AXIOM, &nomem);
    if (!fc->compiled)
        fc->ins.len = 0;
    return nomem ? CBM_E_NOMEM : CBM_OK;
}

void cbm__lc_program_free(cbm_context *ctx, lc_program *p)
{
    cbm__lc_native_free(ctx, p);
    for (size_t f = 0; f < p->n; f++)
        CBM_ARRAY_FREE(ctx, p->fn[f].ins);
    cbm__free(ctx, p->fn, p->n * sizeof *p->fn);
    memset(p, 0, sizeof *p);
}
