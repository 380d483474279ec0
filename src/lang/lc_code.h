/* The register code, the one evaluator of both dialects: the L+C dialect's functions, production
 * bodies, blocks, global initialisers, axiom and header expressions (lang/lc.h, compiled by
 * lc_code.c) and the cpfg dialect's roots (compiled by cpfg_code.c), and the loop that runs it
 * (cbm__lc_run, lc_code.c). lc_native.c translates the L+C program to C for the system's cc.
 *
 * Why a register code under native code: the run needs no compiler, no temporary files, no
 * dlopen and no cache to keep valid, so it behaves the same on every machine and under ASan,
 * and native code, when it is there, computes the same bits by construction. A function's
 * locals and parameters are registers of its frame (their slots), temporaries follow them; an
 * instruction names its registers, so `s += sin(x * i) / i` is three instructions.
 *
 * Arithmetic is lpfg's compiled C++ on x86-64 (cbm__lc_bin_scalar): int operations in 32 bits
 * with the wrap, float results rounded to float32, lpfg's messages for division by zero, and
 * the budgets of cbm_limits (a loop iteration and a call each spend one operation, the call
 * depth is bounded). A runtime error reports the position of the statement being executed.
 *
 * Every function compiles (switch too). Its parameters and result may be scalars or runs
 * (structs, vectors, quaternions, frames), its parameters references (T& x: the caller copies
 * the parameter's run back to the variable after the call). What acts on the run's state
 * (random numbers, contexts, the mechanics, printf) is a host call (O_HOST). docs/design.md,
 * "The language", says more. */
#ifndef CBM_LANG_LC_CODE_H
#define CBM_LANG_LC_CODE_H

#include "lang/lc.h"

struct lc_ins;

/* The runtime state of a run: globals, the frame stack, the budgets and the first runtime
 * error. */
typedef struct lc_vm {
    double *glob;
    double *stack;
    size_t stack_cap, sp;
    int call_depth, max_call_depth;
    long budget; /* loop iterations left in this step (limits.max_loop_iterations) */
    long ops;    /* calls and loop iterations left in this step (limits.max_operations) */
    cbm_status err;
    char errmsg[160];
    int32_t stmt_pos; /* text offset of the statement being executed (runtime messages) */
    int32_t err_pos;  /* where the first runtime error happened, -1: unknown */
    /* `produce` of a compiled production body: appends module sm (an index of the model's
     * sms) with its parameters v (the module's size in doubles) to the string being produced;
     * false after reporting an error (a parameter not finite, out of memory) */
    bool (*produce)(void *ud, int sm, const double *v);
    void *host; /* the ud of produce, and the host of host_call */
    /* the cpfg dialect (lang/cpfg_code.c): the production's formal parameters (O_PLD, O_PST)
     * and the host's built-ins, arrays and printf (O_HOST: ip->subop says which, ip->imm is the
     * node whose position a runtime error names; the result goes to fr[ip->dst]) */
    double *par;
    double (*host_call)(struct lc_vm *vm, const struct lc_ins *ip, double *fr);
} lc_vm;

/* The instructions (lc_code.c runs them, lc_native.c translates them to C). */
enum {
    O_NOP, /* sets the statement position only */
    O_CONST,
    O_MOV,
    O_GLD, /* dst = glob[src1] */
    O_GST, /* glob[dst] = src1 */
    O_NEG,
    O_NOT,
    O_BOOL, /* dst = src1 != 0 */
    O_CONV, /* dst = conv(type, src1) */
    O_ADDD,
    O_SUBD,
    O_MULD,
    O_DIVD,
    O_ADDF,
    O_SUBF,
    O_MULF,
    O_DIVF,
    O_ADDI,
    O_SUBI,
    O_MULI,
    O_LT,
    O_GT,
    O_LE,
    O_GE,
    O_EQ,
    O_NE,
    O_DIVI,
    O_REMI,
    O_BIN,   /* dst = cbm__lc_bin_scalar(operator subop, type, src1, src2): the other operators
              * and types */
    O_INC,   /* ++/-- on local src1: subop the mode, type the type, dst the value */
    O_GINC,  /* the same on global src1 */
    O_MATH1, /* dst = conv(type, math subop(src1)) */
    O_MATH2, /* dst = conv(type, math subop(src1, src2)) */
    O_JMP,   /* to src1 */
    O_JZ,    /* to src2 if src1 == 0 */
    O_JNZ,   /* to src2 if src1 != 0 */
    O_SPEND, /* a loop iteration */
    O_JNZS,  /* a loop's test at its bottom: spends an iteration and jumps to src2 if src1 != 0 */
    O_JMPS,  /* the same without a test (for (;;)): to src1 */
    O_CALL,  /* dst = function src1 on the frame at register src2 (a run result: its run to
              * dst..) */
    O_RET,   /* the value of src1 */
    O_RET0,
    /* a comparison and the jump on its falsehood in one (if, while, for): to dst unless
     * src1 op src2 */
    O_JNLT,
    O_JNGT,
    O_JNLE,
    O_JNGE,
    O_JNEQ,
    O_JNNE,
    /* the same, jumping when it holds: the test at the bottom of a loop, which spends the
     * iteration it starts */
    O_JLT,
    O_JGT,
    O_JLE,
    O_JGE,
    O_JEQ,
    O_JNE,
    /* math built-ins of double result called directly */
    O_SIN,
    O_COS,
    O_SQRT,
    O_EXP,
    /* production bodies */
    O_PROD, /* appends module sm dst with its parameters in registers src1.. (vm->produce) */
    O_DONE, /* `produce` ends the body: the production applied (the run returns 1) */
    /* the cpfg dialect (lang/cpfg_code.c) */
    O_PLD,    /* dst = vm->par[src1] */
    O_PST,    /* vm->par[dst] = src1 */
    O_CMATH,  /* dst = math built-in subop(src1, src2) with trigonometry in degrees */
    O_WSPEND, /* an iteration of a while loop from vm->budget (the cpfg message) */
    O_HOST    /* dst = vm->host_call(ip, fr); also the L+C dialect's random numbers, func,
               * Forward/Backward, UseGroup/CurrentGroup, stop, printf and the mechanics and
               * light built-ins: subop the built-in, its src2 (scalar) arguments in registers
               * src1.., imm the call's node (lsys/lpfg.c lpfg_host); subop LC_HOST_CONTEXT:
               * the context (InLeftContext ...) of node imm matched, its formals bound in the
               * frame fr */
};

/* O_HOST's subop for a context (N_INCTX): the host matches it and binds its formals in the frame */
#define LC_HOST_CONTEXT 0xFFFF
/* the most (scalar) arguments of an O_HOST call (printf's, the mechanics built-ins') */
#define LC_HOST_MAXARGS 16

/* One instruction. Its fields, by one convention for every opcode (the enum above says which
 * each uses):
 *   op        the opcode (O_...);
 *   type      the type a result is converted to (T_INT, T_FLOAT ...: O_CONV, O_MATH*, O_INC) or
 *             computed in (O_BIN);
 *   subop     which variant of the opcode: the operator (O_BIN, a B_* of lc.h), the built-in
 *             (O_MATH*, O_CMATH, O_HOST: a FN_* of builtins.h, or LC_HOST_CONTEXT), the mode of
 *             O_INC (bit 0: decrement, >= 2: postfix);
 *   dst       the destination register (a frame slot), or the global, parameter or module
 *             written, or the target of a fused compare-and-jump;
 *   src1      the first operand register, or the global, parameter or function read, or a
 *             jump's target;
 *   src2      the second operand register, or a conditional jump's target, or an argument
 *             count;
 *   stmt_pos  the statement that starts at this instruction, as its dialect locates it (runtime
 *             messages name it): its text offset (L+C), or its node (cpfg: the node a
 *             runtime error names, also O_HOST's array); -1: none;
 *   imm       an immediate constant (O_CONST's value; the L+C dialect's O_HOST: its node). */
typedef struct lc_ins {
    uint8_t op, type;
    uint16_t subop;
    int32_t dst, src1, src2;
    int32_t stmt_pos;
    double imm;
} lc_ins;

typedef struct lc_fcode {
    CBM_ARRAY(lc_ins) ins;
    int fsize;     /* the locals (and parameters, formals) the frame holds on entry */
    int nreg;      /* frame doubles: locals, then temporaries */
    bool compiled; /* false: could not be compiled (the model is refused) or has no body */
    /* a function over runs: its parameters' doubles (a struct or vector parameter is a run of
     * registers, from register 0 in order); a result of several doubles (rsize, 0: a scalar or
     * void) is left in the run of the callee's frame at rslot (after its locals, so that its
     * reference parameters, copied back by the caller after the call, are still whole) */
    int npd, rslot, rsize;
    bool refs; /* a reference parameter: the caller copies its run back to the argument */
} lc_fcode;

/* The register code of a model's functions, by function index, then of its production bodies:
 * those of the main rules from body0[0], of the decomposition rules from body0[1], of the
 * interpretation rules from body0[2], each by production index; then the four blocks (Start,
 * StartEach, EndEach, End) from block0, compiled as bodies without produce; then what runs
 * once (init0, axiom, expr0). */
typedef struct lc_native lc_native; /* lc_native.c */

enum { LC_MAIN, LC_DECOMP, LC_INTERP };
enum { LC_X_DECOMP_DEPTH, LC_X_INTERP_DEPTH, LC_X_DLEN, LC_X_N };

typedef struct lc_program {
    lc_fcode *fn;
    size_t n;
    size_t body0[3];
    size_t block0; /* the Start, StartEach, EndEach and End blocks, from fn[block0] */
    /* run once: each global's initialiser from fn[init0] (by global; empty when it has none),
     * then the axiom (fn[init0 + globals], a body that produces without ending), then the
     * expressions of the decomposition's and the interpretation's maximum depth and of the
     * derivation length (fn[expr0 + LC_X_...], each returning its value) */
    size_t init0, axiom, expr0;
    /* fn[axiom] holds the axiom's modules [axiom_from, axiom_from + axiom_count): all of them,
     * or the first LC_AXIOM_PART of a longer one (cbm__lc_codegen_axiom compiles the others) */
    int32_t axiom_from, axiom_count;
    bool xpresent[LC_X_N]; /* which of the expressions the model has */
    lc_native *native;     /* the compiled functions as native code (lc_native.c), NULL: none */
} lc_program;

/* Compiles every function, production body, block and root that can be compiled; CBM_E_NOMEM
 * only (what cannot be compiled is marked so: lsys/lpfg.c refuses the model).
 *
 * A production body compiles when its statements do (as a function's) and its values are
 * scalars or runs of them: a struct or vector local, global, field, constructor, assignment or
 * conditional is copied register by register, and `produce`/`nproduce` writes each module from
 * a run of registers through vm->produce. Vector arithmetic of V3f and V3d, their conversions
 * and Dot, Cross, Length and Normalize, quaternion, frame and LocVec arithmetic, MakeQuaternion,
 * VecRotate, ToLocal and ToWorld are instructions over the components. Random numbers, contexts,
 * printf and the mechanics built-ins are host calls (O_HOST). The run of a body returns 1 when it
 * produced (the production applied), 0 when it ended without. The blocks compile as bodies. */
cbm_status cbm__lc_codegen(cbm_context *ctx, const lc_model *m, lc_program *p);

/* The most modules of the axiom compiled at once by cbm__lc_codegen: lsys/lpfg.c runs a longer
 * axiom part by part when its code reads nothing of the run, keeping its string, so that its
 * whole code (32 bytes a module) never exists; otherwise it compiles it whole. */
#define LC_AXIOM_PART 4096

/* Compiles the axiom's modules [from, from + count) into fn[p->axiom], in place of what it held;
 * CBM_E_NOMEM only (fn[p->axiom].compiled says whether it compiled). */
cbm_status cbm__lc_codegen_axiom(cbm_context *ctx, const lc_model *m, lc_program *p, int32_t from,
                                 int32_t count);
void cbm__lc_program_free(cbm_context *ctx, lc_program *p);

/* The production body p of rule set `set` (LC_MAIN ...): its index in p->fn, -1: none. */
static inline int cbm__lc_body(const lc_program *p, int set, size_t prod)
{
    size_t end = set == LC_INTERP ? p->block0 : p->body0[set + 1];
    return p->fn && p->body0[set] + prod < end ? (int)(p->body0[set] + prod) : -1;
}

/* Runs compiled function f on the frame fr (its parameters in their slots, room for nreg
 * doubles); the result (0 for void). After a runtime error vm->err is set and the result is
 * meaningless. */
double cbm__lc_run(const lc_program *p, int f, double *fr, lc_vm *vm);

/* Whether fn[f] reads or writes nothing of a run's state but its own frame and what it
 * produces: no global, function call, host call (random numbers, contexts, the mechanics),
 * loop or budget. Its result is then the same on every run (lsys/lpfg.c keeps such an axiom's
 * string rather than its code). */
bool cbm__lc_stateless(const lc_program *p, size_t f);

/* Native code (lc_native.c): the compiled functions translated to C, compiled by the system C
 * compiler into a shared object cached in cache_dir under the hash of its source, and loaded;
 * cbm__lc_run then runs them natively with the same arithmetic, budgets and messages. false
 * (the register code stays) when there is nothing to compile, no compiler, or anything fails;
 * why goes to *why (a static string). */
bool cbm__lc_native_load(cbm_context *ctx, const lc_model *m, lc_program *p, const char *cache_dir,
                         const char **why);
void cbm__lc_native_free(cbm_context *ctx, lc_program *p);
/* Whether fn[f] runs as native code (the roots that run once never do: lc_native.c). */
bool cbm__lc_native_has(const lc_program *p, int f);
double cbm__lc_native_run(const lc_program *p, int f, double *fr, lc_vm *vm);

/* The first runtime error of a run wins; its position is vm->stmt_pos. */
void cbm__lc_error(lc_vm *vm, cbm_status s, const char *msg);
/* No error on record and no statement located: the state before a run whose first runtime
 * error is to be reported. */
static inline void cbm__lc_error_clear(lc_vm *vm)
{
    vm->err = CBM_OK;
    vm->stmt_pos = vm->err_pos = -1;
}
/* Takes one operation (a call, a production applied or a loop iteration) from the step's
 * budgets; false after reporting the limit. */
bool cbm__lc_spend(lc_vm *vm, bool loop);
/* a op b for scalars computed in type t (C's int, float or double arithmetic, comparisons). */
double cbm__lc_bin_scalar(int op, int t, double a, double b, lc_vm *vm);

#endif
