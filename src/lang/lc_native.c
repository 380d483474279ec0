/* The L+C dialect's compiled functions as native code (lc_code.h): the register code of every
 * compiled function translated to C, one C statement per instruction and the registers as
 * locals, compiled by the system C compiler into a shared object, cached under the hash of its
 * source and loaded with dlopen.
 *
 * Why: the register code's dispatch costs several times the arithmetic it runs, so models whose
 * functions compute (bench/lc/compute.l) stayed slower than lpfg, whose models are C++. The
 * translation keeps the register code's semantics exactly, because it is the register code:
 * - arithmetic: each instruction is one C expression rounded as the loop rounds it (doubles,
 *   float32 results through (double)(float), ints in 32 bits with the wrap), compiled without
 *   contraction (no fused multiply-add), without vectorization (GCC 12's SLP vectorizer drops
 *   float round trips, lang/lc.h) and without built-ins (no constant folding of sin with
 *   another library than the one the loop calls); the rarer operators (O_BIN, the math
 *   built-ins other than sin, cos, sqrt, exp) call back into this file's functions;
 * - budgets, call depth and frame stack: the loop's checks in the same places, on the same
 *   lc_vm (through the pointers of struct lc_rt), so limits stop a run at the same operation;
 * - messages: each instruction that starts a statement sets `at`, and every error passes it
 *   back, so a runtime error names the same file:line:col.
 * Any failure (no compiler, an unwritable cache, a corrupt cached file) leaves the register
 * code in place: native code is an acceleration, never a requirement. */
#define _POSIX_C_SOURCE 200809L

#include "lang/builtins.h"
#include "lang/lc_code.h"

#include <dlfcn.h>
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <math.h>
#include <spawn.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>
#include <time.h>
#include <signal.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

/* The runtime the native code sees: declared once here and pasted into the generated source
 * as text (LC_STR), so both sides always agree on its layout. */
#define LC_RT_STRUCT                                                                               \
    struct lc_rt {                                                                                 \
        double *glob;                                                                              \
        long *ops, *budget;                                                                        \
        int *call_depth;                                                                           \
        int max_call_depth;                                                                        \
        int failed;                                                                                \
        double *stack;                                                                             \
        size_t stack_cap;                                                                          \
        void *vm;                                                                                  \
        void (*limit)(struct lc_rt *, int32_t);                                                    \
        int (*spend_call)(struct lc_rt *, int32_t);                                                \
        void (*fault)(struct lc_rt *, int32_t, int);                                               \
        double (*math)(int, double, double);                                                       \
        double (*bin)(struct lc_rt *, int32_t, int, int, double, double);                          \
        int (*prod)(struct lc_rt *, int32_t, int, const double *);                                 \
        double (*host)(struct lc_rt *, int32_t, int, int, int32_t, double *);                      \
    };
LC_RT_STRUCT
#define LC_STR_(...) #__VA_ARGS__
#define LC_STR(...)  LC_STR_(__VA_ARGS__)

typedef double (*lc_native_fn)(double *fr, struct lc_rt *R, int32_t at);

struct lc_native {
    void *so;
    lc_native_fn const *fn; /* by function index, NULL: not compiled */
};

/* what fault() reports */
enum { F_DIV, F_REM, F_DEEP };

/* ---------------------------------------------------------------- the runtime's calls */
static void rt_limit(struct lc_rt *R, int32_t at)
{
    lc_vm *vm = R->vm;
    vm->stmt_pos = at;
    (void)cbm__lc_spend(vm, true);
    R->failed = 1;
}

static int rt_spend_call(struct lc_rt *R, int32_t at)
{
    lc_vm *vm = R->vm;
    vm->stmt_pos = at;
    if (cbm__lc_spend(vm, false))
        return 1;
    R->failed = 1;
    return 0;
}

static void rt_fault(struct lc_rt *R, int32_t at, int what)
{
    lc_vm *vm = R->vm;
    vm->stmt_pos = at;
    if (what == F_DEEP)
        cbm__lc_error(vm, CBM_E_LIMIT, "function calls nested too deeply (--max-call-depth)");
    else
        cbm__lc_error(vm, CBM_E_RUNTIME,
                      what == F_DIV ? "integer division by zero" : "integer remainder by zero");
    R->failed = 1;
}

static double rt_math(int fn, double a, double b)
{
    return cbm__builtin_math(fn, a, b, false);
}

static double rt_bin(struct lc_rt *R, int32_t at, int op, int t, double a, double b)
{
    lc_vm *vm = R->vm;
    vm->stmt_pos = at;
    double r = cbm__lc_bin_scalar(op, t, a, b, vm);
    if (vm->err != CBM_OK)
        R->failed = 1;
    return r;
}

static int rt_prod(struct lc_rt *R, int32_t at, int sm, const double *v)
{
    lc_vm *vm = R->vm;
    vm->stmt_pos = at;
    if (vm->produce(vm->host, sm, v))
        return 1;
    R->failed = 1;
    return 0;
}

/* O_HOST: the register code's instruction rebuilt around the arguments' copy v, so that the
 * host (vm->host_call) sees what the loop would give it */
static double rt_host(struct lc_rt *R, int32_t at, int fn, int nargs, int32_t node, double *v)
{
    lc_vm *vm = R->vm;
    lc_ins x;
    memset(&x, 0, sizeof x);
    x.op = O_HOST;
    x.subop = (uint16_t)fn;
    x.src2 = nargs;
    x.imm = (double)node;
    x.stmt_pos = at;
    vm->stmt_pos = at;
    double r = vm->host_call(vm, &x, v);
    if (vm->err != CBM_OK)
        R->failed = 1;
    return r;
}

double cbm__lc_native_run(const lc_program *p, int f, double *fr, lc_vm *vm)
{
    struct lc_rt R = {vm->glob,
                      &vm->ops,
                      &vm->budget,
                      &vm->call_depth,
                      vm->max_call_depth,
                      vm->err != CBM_OK,
                      vm->stack,
                      vm->stack_cap,
                      vm,
                      rt_limit,
                      rt_spend_call,
                      rt_fault,
                      rt_math,
                      rt_bin,
                      rt_prod,
                      rt_host};
    return p->native->fn[f](fr, &R, vm->stmt_pos);
}

/* ---------------------------------------------------------------- the C source */
typedef struct c_source {
    cbm_context *ctx;
    CBM_ARRAY(char) text; /* the C text written so far */
    bool out_of_memory;
} c_source;

static void append_c(c_source *s, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void append_c(c_source *s, const char *fmt, ...)
{
    va_list ap, ap2;
    va_start(ap, fmt);
    va_copy(ap2, ap);
    int n = vsnprintf(NULL, 0, fmt, ap);
    va_end(ap);
    if (n < 0 || s->out_of_memory ||
        CBM_ARRAY_RESERVE(s->ctx, s->text, s->text.len + (size_t)n + 1) != CBM_OK)
        s->out_of_memory = true;
    else {
        (void)vsnprintf(s->text.data + s->text.len, (size_t)n + 1, fmt, ap2);
        s->text.len += (size_t)n;
    }
    va_end(ap2);
}

/* The helpers are lang/lc.h's lc_c_int and lc_wrap_int. cint, the conversion to int of every
 * int operation, is lc_c_int's text where the target has no SSE2; with SSE2 (every x86-64) it is
 * the instruction CVTTSD2SI, which truncates toward zero and gives 0x80000000 (INT32_MIN) for NaN
 * and for every value whose truncation is outside int32: exactly lc_c_int's result for every
 * double, without its two comparisons (bench/lc/compute.l's loop: 616 M instructions to 563 M;
 * test lpfg_native_matches_register_code, tests/lpfg/native-int-edges.l). The intrinsic is
 * defined for every input, unlike C's (int32_t) of an out-of-range double. */
static const char prelude[] =
    "#include <math.h>\n#include <stddef.h>\n#include <stdint.h>\n" LC_STR(
        LC_RT_STRUCT) "\n"
                      "#if defined(__SSE2__)\n#include <emmintrin.h>\n"
                      "static double cint(double v) { return "
                      "(double)_mm_cvttsd_si32(_mm_set_sd(v)); }\n"
                      "#else\n"
                      "static double cint(double v) { if (!(v > -2147483649.0 && v < "
                      "2147483648.0)) "
                      "return -2147483648.0; return (double)(int32_t)v; }\n"
                      "#endif\n"
                      "static double wrap(long long r) { return "
                      "(double)(int32_t)(uint32_t)(unsigned long long)r; "
                      "}\n"
                      "static double kbits(uint64_t b) { union { uint64_t u; double d; } x; x.u = "
                      "b; return x.d; "
                      "}\n"
                      "#define SPEND(at) do { if (*R_ops > 0 && *R_budget > 0) { --*R_ops; "
                      "--*R_budget; } "
                      "else { R->limit(R, at); return 0; } } while (0)\n";

/* "%s" of a value of register text e converted to type t, as lc_conv_scalar */
static void put_conv(c_source *s, int t, const char *e)
{
    switch (t) {
    case T_INT:
        append_c(s, "cint(%s)", e);
        break;
    case T_FLOAT:
        append_c(s, "(double)(float)(%s)", e);
        break;
    case T_BOOL:
        append_c(s, "(double)(%s != 0)", e);
        break;
    default:
        append_c(s, "(%s)", e);
        break;
    }
}

static void put_const(c_source *s, int d, double k)
{
    uint64_t b;
    memcpy(&b, &k, sizeof b);
    append_c(s, "r%d = kbits(0x%016" PRIx64 "u);", d, b);
}

static const char *const cmp_c[] = {"<", ">", "<=", ">=", "==", "!="};

/* Before a function over runs returns: its run result and its reference parameters stored
 * to its frame, where the caller reads them (the registers are C locals). */
static void put_frame_out(c_source *s, const lc_program *p, const lc_model *m, int f)
{
    if ((size_t)f >= m->funcs.len)
        return;
    const lc_function *fn = &m->funcs.data[f];
    const lc_fcode *fc = &p->fn[f];
    for (int i = 0; i < fc->rsize; i++)
        append_c(s, "fr[%d] = r%d; ", fc->rslot + i, fc->rslot + i);
    for (int i = 0, off = 0; i < fn->nparams && fc->refs; i++) {
        int sz = lc_type_size(m, fn->ptype[i]);
        for (int k = 0; k < sz && fn->pref[i]; k++)
            append_c(s, "fr[%d] = r%d; ", off + k, off + k);
        off += sz;
    }
}

static void put_ins(c_source *s, const lc_program *p, const lc_model *m, int f, const lc_ins *x)
{
    char a[64], g[48];
    snprintf(a, sizeof a, "r%d", x->src1);
    switch (x->op) {
    case O_NOP:
        append_c(s, ";");
        break;
    case O_CONST:
        put_const(s, x->dst, x->imm);
        break;
    case O_MOV:
        append_c(s, "r%d = r%d;", x->dst, x->src1);
        break;
    case O_GLD:
        append_c(s, "r%d = R->glob[%d];", x->dst, x->src1);
        break;
    case O_GST:
        append_c(s, "R->glob[%d] = r%d;", x->dst, x->src1);
        break;
    case O_NEG:
        append_c(s, "r%d = -r%d;", x->dst, x->src1);
        break;
    case O_NOT:
        append_c(s, "r%d = (double)(r%d == 0);", x->dst, x->src1);
        break;
    case O_BOOL:
        append_c(s, "r%d = (double)(r%d != 0);", x->dst, x->src1);
        break;
    case O_CONV:
        append_c(s, "r%d = ", x->dst);
        put_conv(s, x->type, a);
        append_c(s, ";");
        break;
    case O_ADDD:
    case O_SUBD:
    case O_MULD:
    case O_DIVD:
        append_c(s, "r%d = r%d %c r%d;", x->dst, x->src1, "+-*/"[x->op - O_ADDD], x -> src2);
        break;
    case O_ADDF:
    case O_SUBF:
    case O_MULF:
    case O_DIVF:
        append_c(s, "r%d = (double)(float)(r%d %c r%d);", x->dst, x->src1, "+-*/"[x->op - O_ADDF],
                 x -> src2);
        break;
    case O_ADDI:
    case O_SUBI:
    case O_MULI:
        append_c(s, "r%d = wrap((long long)cint(r%d) %c (long long)cint(r%d));", x->dst, x->src1,
                 "+-*"[x->op - O_ADDI], x -> src2);
        break;
    case O_LT:
    case O_GT:
    case O_LE:
    case O_GE:
    case O_EQ:
    case O_NE:
        append_c(s, "r%d = (double)(r%d %s r%d);", x->dst, x->src1, cmp_c[x->op - O_LT], x->src2);
        break;
    case O_DIVI:
    case O_REMI:
        append_c(s,
                 "{ long long x = (long long)cint(r%d), y = (long long)cint(r%d); if (y == 0) { "
                 "R->fault(R, at, %d); return 0; } r%d = wrap(x %c y); }",
                 x->src1, x->src2, x->op == O_DIVI ? F_DIV : F_REM, x->dst,
                 x->op == O_DIVI ? '/' : '%');
        break;
    case O_JNLT:
    case O_JNGT:
    case O_JNLE:
    case O_JNGE:
    case O_JNEQ:
    case O_JNNE:
        append_c(s, "if (!(r%d %s r%d)) goto L%d;", x->src1, cmp_c[x->op - O_JNLT], x->src2,
                 x->dst);
        break;
    case O_JLT:
    case O_JGT:
    case O_JLE:
    case O_JGE:
    case O_JEQ:
    case O_JNE:
        append_c(s, "if (r%d %s r%d) { SPEND(at); goto L%d; }", x->src1, cmp_c[x->op - O_JLT],
                 x->src2, x->dst);
        break;
    case O_SIN:
    case O_COS:
    case O_SQRT:
    case O_EXP: {
        static const char *const name[] = {"sin", "cos", "sqrt", "exp"};
        append_c(s, "r%d = %s(r%d);", x->dst, name[x->op - O_SIN], x->src1);
        break;
    }
    case O_BIN:
        append_c(s, "r%d = R->bin(R, at, %d, %d, r%d, r%d); if (R->failed) return 0;", x->dst,
                 x->subop, x->type, x->src1, x->src2);
        break;
    case O_INC:
    case O_GINC:
        if (x->op == O_INC)
            snprintf(g, sizeof g, "r%d", x->src1);
        else
            snprintf(g, sizeof g, "R->glob[%d]", x->src1);
        append_c(s, "{ double o = %s; %s = ", g, g);
        snprintf(a, sizeof a, "%s + %d", g, (x->subop & 1) ? -1 : 1);
        put_conv(s, x->type, a);
        append_c(s, "; r%d = %s; }", x->dst, x->subop >= 2 ? "o" : g);
        break;
    case O_MATH1:
    case O_MATH2:
        snprintf(g, sizeof g, "R->math(%d, r%d, %s%d)", x->subop, x->src1,
                 x->op == O_MATH2 ? "r" : "", x->op == O_MATH2 ? x->src2 : 0);
        append_c(s, "r%d = ", x->dst);
        put_conv(s, x->type, g);
        append_c(s, ";");
        break;
    case O_JMP:
        append_c(s, "goto L%d;", x->src1);
        break;
    case O_JZ:
        append_c(s, "if (r%d == 0) goto L%d;", x->src1, x->src2);
        break;
    case O_JNZ:
        append_c(s, "if (r%d != 0) goto L%d;", x->src1, x->src2);
        break;
    case O_SPEND:
        append_c(s, "SPEND(at);");
        break;
    case O_JNZS:
        append_c(s, "if (r%d != 0) { SPEND(at); goto L%d; }", x->src1, x->src2);
        break;
    case O_JMPS:
        append_c(s, "SPEND(at); goto L%d;", x->src1);
        break;
    case O_CALL: {
        /* the arguments are in the caller's registers b..; the callee's frame is fr + b as in
         * the loop, so the frame stack and its limit are the same */
        const lc_function *cf = &m->funcs.data[x->src1];
        const lc_fcode *cc = &p->fn[x->src1];
        append_c(s, "{ double *nf = fr + %d;", x->src2);
        for (int i = 0; i < cc->npd; i++)
            append_c(s, " nf[%d] = r%d;", i, x->src2 + i);
        append_c(s,
                 " if (*R->call_depth >= R->max_call_depth || (size_t)(nf - R->stack) + %d + 1 > "
                 "R->stack_cap) { R->fault(R, at, %d); return 0; }"
                 " if (!R->spend_call(R, at)) return 0;"
                 " ++*R->call_depth; double v = f%d(nf, R, at); --*R->call_depth;"
                 " if (R->failed) return 0;",
                 cc->nreg, F_DEEP, x->src1);
        /* a run result and the reference parameters come back through the callee's frame */
        for (int i = 0; i < cc->rsize; i++)
            append_c(s, " r%d = nf[%d];", x->dst + i, cc->rslot + i);
        if (!cc->rsize)
            append_c(s, " r%d = v;", x->dst);
        for (int i = 0, off = 0; i < cf->nparams; i++) {
            int sz = lc_type_size(m, cf->ptype[i]);
            for (int k = 0; k < sz && cf->pref[i]; k++)
                append_c(s, " r%d = nf[%d];", x->src2 + off + k, off + k);
            off += sz;
        }
        append_c(s, " }");
        break;
    }
    case O_PROD: { /* the module's parameters from its run of registers */
        int size = m->mods.data[m->sms.data[x->dst].mod].size;
        if (!size) {
            append_c(s, "if (!R->prod(R, at, %d, 0)) return 0;", x->dst);
            break;
        }
        append_c(s, "{ double v[%d] = {", size);
        for (int i = 0; i < size; i++)
            append_c(s, "%sr%d", i ? ", " : "", x->src1 + i);
        append_c(s, "}; if (!R->prod(R, at, %d, v)) return 0; }", x->dst);
        break;
    }
    case O_DONE:
        append_c(s, "return 1;");
        break;
    case O_HOST: /* the L+C host's built-ins (random numbers, func, ...): node k */
        if (x->subop == LC_HOST_CONTEXT) { /* binds formals in the frame (put_function) */
            append_c(s, "r%d = R->host(R, at, %d, 0, %d, fr); if (R->failed) return 0;", x->dst,
                     x->subop, (int)x->imm);
            break;
        }
        append_c(s, "{ double v[%d] = {0};", x->src2 > 0 ? x->src2 : 1);
        for (int i = 0; i < x->src2; i++)
            append_c(s, " v[%d] = r%d;", i, x->src1 + i);
        append_c(s, " r%d = R->host(R, at, %d, %d, %d, v); if (R->failed) return 0; }", x->dst,
                 x->subop, x->src2, (int)x->imm);
        break;
    case O_RET:
        put_frame_out(s, p, m, f);
        append_c(s, "return r%d;", x->src1);
        break;
    case O_RET0:
        put_frame_out(s, p, m, f);
        append_c(s, "return 0;");
        break;
    default: /* the cpfg dialect's instructions, never in an L+C program: a compile error, so
              * a program that had one would keep running on the register code */
        append_c(s, "\n#error \"instruction %d has no native translation\"\n", (int)x->op);
        break;
    }
}

static void put_function(c_source *s, const lc_program *p, const lc_model *m, int f)
{
    const lc_fcode *fc = &p->fn[f];
    int fsize = fc->fsize;
    append_c(s, "static double f%d(double *fr, struct lc_rt *R, int32_t at)\n{\n", f);
    /* the locals start as the frame holds them (the loop reads the frame itself); where the
     * host matches a context (binding its formals) it writes them there, so they stay in the
     * frame */
    bool in_frame = false;
    for (size_t i = 0; i < fc->ins.len; i++)
        in_frame =
            in_frame || (fc->ins.data[i].op == O_HOST && fc->ins.data[i].subop == LC_HOST_CONTEXT);
    for (int r = 0; r < fc->nreg; r++)
        append_c(s,
                 r >= fsize  ? "    double r%d = 0;\n"
                 : !in_frame ? "    double r%d = fr[%d];\n"
                             : "#define r%d fr[%d]\n",
                 r, r);
    /* the budget counters' addresses in locals: R is reloaded after every call (sin, cos, the
     * host's), these stay in registers (SPEND) */
    append_c(s, "    long *const R_ops = R->ops, *const R_budget = R->budget;\n");
    append_c(s, "    (void)fr; (void)R; (void)at; (void)R_ops; (void)R_budget;\n");
    for (size_t i = 0; i < fc->ins.len; i++) {
        const lc_ins *x = &fc->ins.data[i];
        append_c(s, "L%zu:", i);
        if (x->stmt_pos >= 0)
            append_c(s, " at = %d;", (int)x->stmt_pos);
        append_c(s, " ");
        put_ins(s, p, m, f, x);
        append_c(s, "\n");
    }
    append_c(s, "L%zu: return 0;\n}\n", fc->ins.len);
    for (int r = 0; in_frame && r < fsize; r++)
        append_c(s, "#undef r%d\n", r);
}

/* ---------------------------------------------------------------- compile, cache, load */
static const char *const cc_flags[] = {"-O2",
                                       "-fPIC",
                                       "-shared",
                                       "-fno-builtin",
                                       "-ffp-contract=off",
                                       "-fno-fast-math",
                                       "-fno-tree-vectorize",
                                       "-fno-tree-slp-vectorize",
                                       "-w"};
#define N_CC_FLAGS (sizeof cc_flags / sizeof cc_flags[0])

static uint64_t fnv1a(uint64_t h, const char *t, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        h ^= (unsigned char)t[i];
        h *= 1099511628211ULL;
    }
    return h;
}

/* mkdir -p */
static bool make_dirs(const char *dir)
{
    char path[4096];
    size_t n = strlen(dir);
    if (n == 0 || n >= sizeof path)
        return false;
    memcpy(path, dir, n + 1);
    for (size_t i = 1; i <= n; i++) {
        if (path[i] != '/' && path[i] != '\0')
            continue;
        char c = path[i];
        path[i] = '\0';
        if (mkdir(path, 0700) != 0 && errno != EEXIST)
            return false;
        path[i] = c;
    }
    struct stat st;
    return stat(dir, &st) == 0 && S_ISDIR(st.st_mode);
}

/* seconds a cc run may take before it is killed (a hung compiler must not hang a run: the
   caller falls back to the register code); CBM_CC_TIMEOUT overrides it, for the test */
static double cc_timeout_s(void)
{
    const char *e = getenv("CBM_CC_TIMEOUT");
    char *end = NULL;
    double t = e ? strtod(e, &end) : 0.0;
    return e && end != e && t > 0.0 && t <= 3600.0 ? t : 120.0;
}

static double monotonic_seconds(void)
{
    struct timespec ts;
    (void)clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* cc FLAGS -o so c -lm, its output discarded; true when it succeeded, *timed_out when it
   was killed for running longer than cc_timeout_s() */
static bool run_cc(const char *c_path, const char *so_path, bool *timed_out)
{
    *timed_out = false;
    /* posix_spawn takes char *const argv[]: the words are copied into one writable buffer */
    char words[8192], *argv[N_CC_FLAGS + 7];
    size_t k = 0, used = 0;
    const char *w[N_CC_FLAGS + 6];
    w[k++] = "cc";
    for (size_t i = 0; i < N_CC_FLAGS; i++)
        w[k++] = cc_flags[i];
    w[k++] = "-o";
    w[k++] = so_path;
    w[k++] = c_path;
    w[k++] = "-lm";
    for (size_t i = 0; i < k; i++) {
        size_t n = strlen(w[i]) + 1;
        if (used + n > sizeof words)
            return false;
        argv[i] = memcpy(words + used, w[i], n);
        used += n;
    }
    argv[k] = NULL;
    posix_spawn_file_actions_t fa;
    if (posix_spawn_file_actions_init(&fa) != 0)
        return false;
    bool ok = posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0) == 0 &&
              posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0) == 0 &&
              posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0) == 0;
    /* cc in a process group of its own, so that a timeout kills its cc1/as/ld children too */
    posix_spawnattr_t at;
    bool at_ok = posix_spawnattr_init(&at) == 0;
    ok = ok && at_ok && posix_spawnattr_setflags(&at, POSIX_SPAWN_SETPGROUP) == 0 &&
         posix_spawnattr_setpgroup(&at, 0) == 0;
    pid_t pid;
    ok = ok && posix_spawnp(&pid, "cc", &fa, &at, argv, environ) == 0;
    posix_spawn_file_actions_destroy(&fa);
    if (at_ok)
        posix_spawnattr_destroy(&at);
    if (!ok)
        return false;
    int st;
    double deadline = monotonic_seconds() + cc_timeout_s();
    for (;;) {
        pid_t r = waitpid(pid, &st, WNOHANG);
        if (r == pid)
            break;
        if (r < 0 && errno != EINTR)
            return false;
        if (monotonic_seconds() > deadline) {
            (void)kill(-pid, SIGKILL);
            while (waitpid(pid, &st, 0) < 0 && errno == EINTR)
                ;
            *timed_out = true;
            return false;
        }
        struct timespec nap = {0, 10 * 1000 * 1000};
        (void)nanosleep(&nap, NULL);
    }
    return WIFEXITED(st) && WEXITSTATUS(st) == 0;
}

/* dlopen so and check that it is the object of this key with n functions */
static void *open_so(const char *so_path, const char *key, size_t n, lc_native_fn const **fn)
{
    void *so = dlopen(so_path, RTLD_NOW | RTLD_LOCAL);
    if (!so)
        return NULL;
    const char *k = dlsym(so, "cbm_lc_key");
    const int *count = dlsym(so, "cbm_lc_count");
    void *table = dlsym(so, "cbm_lc_table");
    if (!k || !count || !table || strcmp(k, key) != 0 || *count != (int)n) {
        dlclose(so);
        return NULL;
    }
    memcpy(fn, &table, sizeof table); /* POSIX: data and function pointers convert */
    return so;
}

/* Whether fn[f] is translated: compiled, and no root that runs once (a global's initialiser,
 * the axiom, an expression of the header), which the register code runs as fast as it matters
 * and whose size (an axiom of 400000 modules) would only cost the C compiler's time. */
static bool translated(const lc_program *p, size_t f)
{
    return f < p->init0 && p->fn[f].compiled;
}

bool cbm__lc_native_has(const lc_program *p, int f)
{
    return p->native && p->native->fn[f];
}

bool cbm__lc_native_load(cbm_context *ctx, const lc_model *m, lc_program *p, const char *cache_dir,
                         const char **why)
{
    *why = NULL;
    if (p->native)
        return true;
    size_t ncompiled = 0;
    for (size_t f = 0; f < p->n; f++)
        ncompiled += translated(p, f);
    if (!ncompiled || !cache_dir) {
        *why = "no function or production body of the model compiles to native code";
        return false;
    }
    c_source s = {ctx, {NULL, 0, 0}, false};
    append_c(&s, "%s", prelude);
    for (size_t f = 0; f < p->n; f++)
        if (translated(p, f))
            append_c(&s, "static double f%zu(double *fr, struct lc_rt *R, int32_t at);\n", f);
    for (size_t f = 0; f < p->n; f++)
        if (translated(p, f))
            put_function(&s, p, m, (int)f);
    uint64_t h = fnv1a(14695981039346656037ULL, s.text.data ? s.text.data : "", s.text.len);
    for (size_t i = 0; i < N_CC_FLAGS; i++)
        h = fnv1a(h, cc_flags[i], strlen(cc_flags[i]) + 1);
    char key[17];
    snprintf(key, sizeof key, "%016" PRIx64, h);
    append_c(&s, "const char cbm_lc_key[] = \"%s\";\nconst int cbm_lc_count = %zu;\n", key, p->n);
    append_c(&s, "double (*const cbm_lc_table[%zu])(double *, struct lc_rt *, int32_t) = {", p->n);
    for (size_t f = 0; f < p->n; f++)
        append_c(&s, translated(p, f) ? "f%zu," : "0,", f);
    append_c(&s, "};\n");
    bool ok = false;
    char so_path[4096], tmp_so[4096], c_path[4096];
    long pid = (long)getpid();
    if (s.out_of_memory) {
        *why = "out of memory";
        goto done;
    }
    if ((size_t)snprintf(so_path, sizeof so_path, "%s/lc-%s.so", cache_dir, key) >=
            sizeof so_path ||
        (size_t)snprintf(tmp_so, sizeof tmp_so, "%s/lc-%s.%ld.so", cache_dir, key, pid) >=
            sizeof tmp_so ||
        (size_t)snprintf(c_path, sizeof c_path, "%s/lc-%s.%ld.c", cache_dir, key, pid) >=
            sizeof c_path) {
        *why = "the cache directory's path is too long";
        goto done;
    }
    lc_native_fn const *fn = NULL;
    void *so = access(so_path, R_OK) == 0 ? open_so(so_path, key, p->n, &fn) : NULL;
    if (!so) { /* not cached (or not usable): compile it */
        if (!make_dirs(cache_dir)) {
            *why = "the cache directory cannot be created";
            goto done;
        }
        FILE *c = fopen(c_path, "w");
        bool written = c && fwrite(s.text.data, 1, s.text.len, c) == s.text.len;
        if (c && fclose(c) != 0)
            written = false;
        if (!written) {
            *why = "the C source cannot be written to the cache directory";
            (void)unlink(c_path);
            goto done;
        }
        bool timed_out = false;
        bool built = run_cc(c_path, tmp_so, &timed_out);
        (void)unlink(c_path);
        /* rename is atomic: a concurrent run sees the old object, the new one or none */
        if (!built || rename(tmp_so, so_path) != 0) {
            *why = timed_out ? "the C compiler (cc) timed out (CBM_CC_TIMEOUT)"
                             : "the C compiler (cc) is missing or failed";
            (void)unlink(tmp_so);
            goto done;
        }
        so = open_so(so_path, key, p->n, &fn);
        if (!so) {
            *why = "the compiled object cannot be loaded";
            goto done;
        }
    }
    p->native = cbm__calloc(ctx, 1, sizeof *p->native);
    if (!p->native) {
        dlclose(so);
        *why = "out of memory";
        goto done;
    }
    p->native->so = so;
    p->native->fn = fn;
    ok = true;
done:
    CBM_ARRAY_FREE(ctx, s.text);
    return ok;
}

void cbm__lc_native_free(cbm_context *ctx, lc_program *p)
{
    if (!p->native)
        return;
    dlclose(p->native->so);
    cbm__free(ctx, p->native, sizeof *p->native);
    p->native = NULL;
}
