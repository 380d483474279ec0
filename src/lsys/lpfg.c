/* The L+C-style (lpfg) dialect of the L-system engine: parser, typed compiler, evaluator and
 * derivation.
 *
 * A model in this dialect declares its modules with typed parameters (`module A(int, float);`),
 * may declare structs, globals and functions, and writes productions whose successors are
 * produced by C-like bodies (`A(t) : { if (t > 0) produce B(t - 1); }`), after Karwowski and
 * Prusinkiewicz's L+C (2003) as implemented by lpfg. It compiles into the same engine as the
 * cpfg dialect: module names are mapped to the one-byte symbols of the packed module string
 * (turtle modules to the cpfg turtle characters, `SB`/`EB` to `[`/`]`), and every parameter,
 * including struct and vector fields, is one packed double, so a struct parameter costs no
 * allocation.
 *
 * Values are typed at compile time (int, float, double, bool, V3f, V3d, structs); a value of
 * any type is a run of doubles (its scalar fields in declaration order). Arithmetic follows C's
 * usual conversions: int operations truncate, float results are rounded to float32 after each
 * operation (as C does with FLT_EVAL_METHOD 0), so parameters match lpfg's float32 bit for bit.
 *
 * Derivation (one step): StartEach; the string is scanned left to right (Forward(), default) or
 * right to left (Backward()); for each module the productions of the active group whose
 * predecessor and contexts match are tried in order, and the first whose body executes
 * `produce` rewrites the module (a body that ends without producing passes to the next
 * production; no production: the module is copied). The new context `<<` / `>>` reads the
 * string being produced (already rewritten neighbours); in Backward mode the output is built
 * reversed and turned around at the end of the step, so the new right context is a left walk
 * of the partial output. Then a separate decomposition pass (recursive to `maximum depth`),
 * then EndEach; End after the last step. The interpretation rules produce the image the turtle
 * reads (cbm_lsys_apply_homomorphism). Context scanning follows lpfg's scanners: going right,
 * branches the pattern does not enter are skipped and a pattern `EB()` skips to the end of the
 * current branch; going left, `[` is climbed out of and whole branches are skipped;
 * `ignore:`/`consider:` modules are passed over.
 */
#include "lsys/lsys_internal.h"
#include "lsys/mechlang.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

/* ---- types ---- */
enum {
    T_VOID,
    T_INT,
    T_FLOAT,
    T_DOUBLE,
    T_BOOL,
    T_V3F,
    T_V3D,
    T_QUAT,
    T_TVEC,
    T_LOCVEC,
    T_MSEG, /* MechSegment (lsys/mechlang.h) */
    T_NBUILTIN
};
#define MAXF   16 /* parameters per module or function */
#define MAXFLD 64 /* fields per struct (the listing's InternodeData has 35) */
#define MAXSZ  255

typedef struct ltype {
    char *name;
    int size;
    int nf;
    int ftype[MAXFLD];
    int foff[MAXFLD];
    char *fname[MAXFLD];
} ltype;

typedef struct lmod {
    char *name;
    uint8_t code;
    int np, size;
    int ptype[MAXF];
} lmod;

/* nodes */
enum {
    N_NUM,
    N_LOCAL,
    N_GLOBAL,
    N_FIELD, /* a: base value, slot: offset */
    N_NEG,
    N_NOT,
    N_CAST,
    N_BIN,
    N_AND,
    N_OR,
    N_COND,
    N_ASSIGN, /* a: lvalue, b: value, fn: operator (0 for =) */
    N_INCDEC, /* a: lvalue, fn: 0 ++x, 1 --x, 2 x++, 3 x-- */
    N_CALLB,
    N_CALLU,
    N_CTOR, /* args a: fields of type */
    N_INCTX,
    N_COMMA,
    N_STR, /* a string literal, printf's arguments only: slot is its offset in the strings */
    S_EXPR,
    S_DECL,
    S_IF,
    S_WHILE,
    S_DO,
    S_FOR,
    S_RETURN,
    S_BREAK,
    S_CONTINUE,
    S_PRODUCE,
    S_BLOCK,
    S_SWITCH, /* a: value, b: body */
    S_CASE,   /* a: label value, -1 for default */
    S_NOP
};

enum { B_ADD, B_SUB, B_MUL, B_DIV, B_REM, B_LT, B_GT, B_LE, B_GE, B_EQ, B_NE };

typedef enum {
    F_SIN,
    F_COS,
    F_TAN,
    F_ASIN,
    F_ACOS,
    F_ATAN,
    F_ATAN2,
    F_EXP,
    F_LOG,
    F_LOG10,
    F_POW,
    F_SQRT,
    F_FABS,
    F_FLOOR,
    F_CEIL,
    F_FMOD,
    F_MIN,
    F_MAX,
    F_RAN,
    F_NRAN,
    F_SRAND,
    F_RAND,
    F_DRAND,
    F_FUNC,
    F_PRINTF,
    F_FORWARD,
    F_BACKWARD,
    F_USEGROUP,
    F_LENGTH,
    F_NORMALIZE,
    F_STOP,
    F_CURGROUP,
    F_DOT,
    F_CROSS,
    F_MAKEQ,
    F_VECROT,
    F_TOLOCAL,
    F_TOWORLD,
    F_EQUILIBRIUM,
    F_ADDRINGS,
    F_AGEWOOD,
    F_BREAK,
    F_STABILITY,
    F_GRAVITY,
    F_GROUND,
    F_CONTACT,
    F_TROPISM,
    F_PIPEMODEL,
    F_WOOD,
    F_RINGRATE,
    F_SOLVER,
    F_REACTION,
    F_NONE
} bfn;

typedef struct bdef {
    const char *name;
    bfn fn;
    int arity; /* -1: any */
} bdef;

static const bdef BUILTINS[] = {{"sin", F_SIN, 1},
                                {"cos", F_COS, 1},
                                {"tan", F_TAN, 1},
                                {"asin", F_ASIN, 1},
                                {"acos", F_ACOS, 1},
                                {"atan", F_ATAN, 1},
                                {"atan2", F_ATAN2, 2},
                                {"exp", F_EXP, 1},
                                {"log", F_LOG, 1},
                                {"log10", F_LOG10, 1},
                                {"pow", F_POW, 2},
                                {"sqrt", F_SQRT, 1},
                                {"fabs", F_FABS, 1},
                                {"abs", F_FABS, 1},
                                {"floor", F_FLOOR, 1},
                                {"ceil", F_CEIL, 1},
                                {"fmod", F_FMOD, 2},
                                {"min", F_MIN, 2},
                                {"max", F_MAX, 2},
                                {"ran", F_RAN, 1},
                                {"nrand", F_NRAN, 2},
                                {"nran", F_NRAN, 2},
                                {"srand", F_SRAND, 1},
                                {"rand", F_RAND, 0},
                                {"drand48", F_DRAND, 0},
                                {"func", F_FUNC, 2},
                                {"printf", F_PRINTF, -1},
                                {"Printf", F_PRINTF, -1},
                                {"Forward", F_FORWARD, 0},
                                {"Backward", F_BACKWARD, 0},
                                {"UseGroup", F_USEGROUP, 1},
                                {"Length", F_LENGTH, 1},
                                {"Magnitude", F_LENGTH, 1},
                                {"Normalize", F_NORMALIZE, 1},
                                {"Normalized", F_NORMALIZE, 1},
                                {"Stop", F_STOP, 0},
                                {"stop", F_STOP, 0},
                                {"CurrentGroup", F_CURGROUP, 0},
                                {"DotProd", F_DOT, 2},
                                {"CrossProd", F_CROSS, 2},
                                {"MakeQuaternion", F_MAKEQ, 2},
                                {"VecRotate", F_VECROT, 3},
                                {"ToLocal", F_TOLOCAL, 2},
                                {"ToWorld", F_TOWORLD, 2},
                                {"Equilibrium", F_EQUILIBRIUM, 0},
                                {"AddRings", F_ADDRINGS, 0},
                                {"AgeWood", F_AGEWOOD, 1},
                                {"Break", F_BREAK, 0},
                                {"Stability", F_STABILITY, 0},
                                {"Gravity", F_GRAVITY, 3},
                                {"Ground", F_GROUND, 3},
                                {"Contact", F_CONTACT, 2},
                                {"Tropism", F_TROPISM, 4},
                                {"PipeModel", F_PIPEMODEL, 2},
                                {"Wood", F_WOOD, 5},
                                {"RingRate", F_RINGRATE, 2},
                                {"Solver", F_SOLVER, 3},
                                {"ReactionWood", F_REACTION, 4},
                                {"RAND_MAX", F_NONE, 0}};

typedef struct xn {
    uint8_t op, fn;
    int16_t type;
    int32_t a, b, c, d, next;
    int32_t slot;
    int32_t pos; /* text offset where the parser made it, for runtime messages */
    double v;
} xn;

/* a successor or context pattern: modules with their argument chains */
typedef struct lsm {
    int mod;
    int32_t args; /* chain of expressions (successor) or of lvalues (pattern) */
} lsm;

typedef struct lpat {
    int32_t first, n; /* in lp->sms */
} lpat;

enum { CX_LC, CX_NLC, CX_NRC, CX_RC, CX_N };

typedef struct lprod {
    int mod;       /* predecessor */
    lpat pred;     /* strict predecessor: one module or several adjacent ones */
    lpat cx[CX_N]; /* contexts (n = 0: none); formals in args */
    int32_t body;
    int fsize; /* frame doubles */
    int group;
    size_t pos;
} lprod;

typedef struct lfunc {
    char *name;
    int ret;
    int np;
    int ptype[MAXF];
    bool pref[MAXF]; /* reference parameter (T& x): copied back to the argument */
    int32_t body;
    int fsize;
    size_t pos;
} lfunc;

typedef struct lset {
    CBM_ARRAY(lprod) prods;
    int depth;
    bool present;
} lset;

typedef struct lgvar {
    char *name;
    int type, slot;
    int32_t init;
} lgvar;

/* a walker over a packed string: dir +1 reads it left to right, -1 right to left */
typedef struct walk {
    const lstr *s;
    ptrdiff_t i;
    size_t j, k;
    int dir;
} walk;

/* The bracket matching of a string walked by a right context: for every SB (in the order of the
 * string) the walk position of its EB, so that skipping a branch is a jump, not a scan, and
 * right contexts stay linear in the bracket depth. Extended lazily up to the string's end: the
 * current string is fixed during a step, the new string only grows. */
typedef struct brtab {
    const lstr *s; /* the string it describes, NULL: none */
    int dir;       /* the walks it serves: +1 the current string, -1 the new (reversed) one */
    walk at;       /* the scan: modules before it.i are in the table */
    CBM_ARRAY(size_t) open; /* index of every SB, increasing */
    CBM_ARRAY(walk) close;  /* the EB matching it; i = -1: none */
    CBM_ARRAY(walk) stack;  /* the brackets waiting for their match */
} brtab;

typedef struct lpfg lpfg;
struct lpfg {
    CBM_ARRAY(ltype) types;
    CBM_ARRAY(lmod) mods;
    int16_t bycode[128];
    CBM_ARRAY(xn) nodes;
    CBM_ARRAY(lsm) sms;
    CBM_ARRAY(lfunc) funcs;
    CBM_ARRAY(lgvar) gvars;
    CBM_ARRAY(char *) funcnames;
    CBM_ARRAY(int) funcids; /* the function-set id of each name (cbm_lsys_set_func_ids) */
    int nglobal;            /* doubles */
    lset main, decomp, interp;
    lpat axiom;
    int32_t blocks[4]; /* Start, StartEach, EndEach, End */
    int block_fsize[4];
    int32_t dlen_expr;
    bool considered[128];
    int sb, eb; /* module indices of SB, EB */
    /* run state */
    double *glob;
    double *stack;
    size_t stack_cap, sp;
    int call_depth;
    double *ret;     /* where `return v;` writes v (in a function) */
    uint32_t gr[34]; /* rand(): the state of the C library's random() (glibc TYPE_3) */
    int gpos;
    bool backward;
    int group;
    lstr *out;     /* where produce appends */
    bool produced; /* produce executed */
    int prod_ix;
    walk scan[CX_N];
    brtab brk[2]; /* during generate: [0] the current string, [1] the new one going Backward */
    lstr succ;
    CBM_ARRAY(lstr) scratch;
    cbm_status err;
    char errmsg[160];
    int32_t at;      /* text offset of the statement being executed (runtime messages) */
    int32_t err_pos; /* where the first runtime error happened, -1: unknown */
    long budget;     /* loop iterations left in this step (limits.max_loop_iterations) */
    long ops;        /* calls and loop iterations left in this step (limits.max_operations) */
    bool nonfinite_warned;
    cbm__mechlang mech; /* mechanics: declarations and settings */
    /* models with mechanics: the module of the string each module of the interpretation came
     * from (empty: the interpretation is the string itself) */
    CBM_ARRAY(size_t) origin;
    bool rewriting; /* inside a derivation pass: mechanics calls are refused */
};

/* ---- compiler state ---- */
typedef struct lvar {
    const char *name;
    size_t len;
    int type, slot;
} lvar;

typedef struct lc {
    cbm_lsys *ls;
    lpfg *lp;
    cbm__compiler *c;
    const char *t;
    CBM_ARRAY(lvar) vars;
    int fsize, fmax;
    int ret_type; /* in a function */
    bool in_prod; /* produce allowed */
    int in_switch;
    int depth;
} lc;

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

/* ---------------------------------------------------------------- small helpers */
static int tsize(const lpfg *lp, int t)
{
    return lp->types.data[t].size;
}

static bool is_scalar(int t)
{
    return t >= T_INT && t <= T_BOOL;
}

static bool is_vec(int t)
{
    return t == T_V3F || t == T_V3D;
}

/* A value converted to a C int as lpfg's compiled C does on x86-64: truncated toward zero, and
 * the "integer indefinite" INT_MIN for NaN and values outside the 32-bit range (cvttsd2si). */
static double c_int(double v)
{
    if (!(v > -2147483649.0 && v < 2147483648.0))
        return -2147483648.0;
    return (double)(int32_t)v;
}

/* The 32-bit two's-complement wrap of an exact integer result (int arithmetic that overflows). */
static double wrap_int(long long r)
{
    return (double)(int32_t)(uint32_t)(unsigned long long)r;
}

static double conv_scalar(int t, double v)
{
    switch (t) {
    case T_INT:
        return c_int(v);
    case T_FLOAT:
        return (double)(float)v;
    case T_BOOL:
        return v != 0;
    default:
        return v;
    }
}

/* Rounds a value of type t in place (float fields to float32, ints truncated). */
static void conv_value(const lpfg *lp, int t, double *v)
{
    if (is_scalar(t)) {
        v[0] = conv_scalar(t, v[0]);
        return;
    }
    if (t == T_V3F) {
        /* through a volatile: GCC 12's SLP vectorizer drops pairs of adjacent
         * double -> float -> double round trips at -O2 (the components lost their rounding) */
        for (int i = 0; i < 3; i++) {
            volatile float f = (float)v[i];
            v[i] = (double)f;
        }
        return;
    }
    if (t == T_V3D)
        return;
    const ltype *ty = &lp->types.data[t];
    for (int f = 0; f < ty->nf; f++)
        conv_value(lp, ty->ftype[f], v + ty->foff[f]);
}

/* ---------------------------------------------------------------- lexing */
static void skip(lc *L)
{
    const char *t = L->t;
    size_t p = L->c->pos;
    while (t[p] && isspace((unsigned char)t[p]))
        p++;
    L->c->pos = p;
}

static bool peek(lc *L, const char *s)
{
    skip(L);
    return !strncmp(L->t + L->c->pos, s, strlen(s));
}

static bool accept(lc *L, const char *s)
{
    if (!peek(L, s))
        return false;
    L->c->pos += strlen(s);
    return true;
}

static bool isid0(int ch)
{
    return isalpha(ch) || ch == '_';
}

static bool isid(int ch)
{
    return isalnum(ch) || ch == '_';
}

/* identifier at the position (not consumed): its length, 0 if none */
static size_t ident(lc *L)
{
    skip(L);
    const char *s = L->t + L->c->pos;
    if (!isid0((unsigned char)s[0]))
        return 0;
    size_t n = 1;
    while (isid((unsigned char)s[n]))
        n++;
    return n;
}

static bool accept_kw(lc *L, const char *kw)
{
    size_t n = ident(L);
    if (n != strlen(kw) || strncmp(L->t + L->c->pos, kw, n))
        return false;
    L->c->pos += n;
    return true;
}

static void describe(lc *L, char *buf, size_t n)
{
    const char *s = L->t + L->c->pos;
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

static bool fatal(lc *L)
{
    return L->c->fatal || (L->c->status != CBM_OK && L->c->status != CBM_E_SYNTAX);
}

static void expected(lc *L, const char *what)
{
    char buf[64];
    skip(L);
    describe(L, buf, sizeof buf);
    size_t pos = L->c->pos;
    while (pos > 0 && !L->t[pos]) /* at the end: point at the last character */
        pos--;
    cbm__cerr(L->c, pos, "expected %s, found %s", what, buf);
}

static bool expect(lc *L, const char *s)
{
    if (accept(L, s))
        return true;
    char what[16];
    snprintf(what, sizeof what, "'%s'", s);
    expected(L, what);
    return false;
}

/* Skips to after the next `;` or the end of the next balanced `{...}` at this level. */
static void recover(lc *L)
{
    const char *t = L->t;
    size_t p = L->c->pos;
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
    L->c->pos = p;
}

/* Statement-level recovery: skips to after the next `;` or balanced block, but stops before a
 * `}` that closes the enclosing block. */
static void recover_stmt(lc *L)
{
    const char *t = L->t;
    size_t p = L->c->pos;
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
    L->c->pos = p;
}

/* ---------------------------------------------------------------- tables */
static int find_type(lc *L, const char *s, size_t n)
{
    for (size_t i = 1; i < L->lp->types.len; i++) {
        const char *nm = L->lp->types.data[i].name;
        if (strlen(nm) == n && !strncmp(nm, s, n))
            return (int)i;
    }
    if (n == 6 && !strncmp(s, "double", 6))
        return T_DOUBLE;
    return -1;
}

static int find_mod(const lpfg *lp, const char *s, size_t n)
{
    for (size_t i = 0; i < lp->mods.len; i++) {
        const char *nm = lp->mods.data[i].name;
        if (strlen(nm) == n && !strncmp(nm, s, n))
            return (int)i;
    }
    return -1;
}

static cbm_status add_type(lpfg *lp, cbm_context *ctx, const char *name, int size)
{
    ltype t;
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
static int alloc_code(lpfg *lp, const char *name, const char *want)
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

static int add_mod(lc *L, const char *name, size_t len, const int *ptypes, int np, const char *want,
                   size_t pos)
{
    lpfg *lp = L->lp;
    lmod m;
    memset(&m, 0, sizeof m);
    int code = alloc_code(lp, len == 1 ? (char[2]){name[0], 0} : "xx", want);
    if (code < 0) {
        cbm__cerr(L->c, pos, "too many module types (at most 126)");
        return -1;
    }
    m.name = cbm__alloc(L->c->ctx, len + 1);
    if (!m.name) {
        L->c->status = CBM_E_NOMEM;
        L->c->fatal = true;
        return -1;
    }
    memcpy(m.name, name, len);
    m.name[len] = 0;
    m.code = (uint8_t)code;
    m.np = np;
    for (int i = 0; i < np; i++) {
        m.ptype[i] = ptypes[i];
        m.size += tsize(lp, ptypes[i]);
    }
    if (m.size > MAXSZ) {
        cbm__cerr(L->c, pos, "module '%s' has more than %d scalar parameters", m.name, MAXSZ);
        m.size = MAXSZ;
    }
    if (CBM_ARRAY_PUSH(L->c->ctx, lp->mods, m) != CBM_OK) {
        cbm__strfree(L->c->ctx, m.name);
        L->c->status = CBM_E_NOMEM;
        L->c->fatal = true;
        return -1;
    }
    lp->bycode[code] = (int16_t)(lp->mods.len - 1);
    return (int)lp->mods.len - 1;
}

static int32_t node(lc *L, xn n)
{
    if (fatal(L))
        return -1;
    n.pos = (int32_t)(L->c->pos < INT32_MAX ? L->c->pos : INT32_MAX);
    if (CBM_ARRAY_PUSH(L->c->ctx, L->lp->nodes, n) != CBM_OK) {
        L->c->status = CBM_E_NOMEM;
        L->c->fatal = true;
        return -1;
    }
    return (int32_t)L->lp->nodes.len - 1;
}

static xn mk(int op, int type)
{
    xn n;
    memset(&n, 0, sizeof n);
    n.op = (uint8_t)op;
    n.type = (int16_t)type;
    n.a = n.b = n.c = n.d = n.next = -1;
    return n;
}

#define ND(i) (L->lp->nodes.data[i])

/* Appends node e to the chain first..last (linked through `next`). */
static void chain(lc *L, int32_t *first, int32_t *last, int32_t e)
{
    if (*last >= 0)
        ND(*last).next = e;
    else
        *first = e;
    *last = e;
}

/* ---------------------------------------------------------------- types in declarations */
/* Parses a type name (with optional `const`/`struct`); -1 if there is none (nothing consumed) */
static int parse_type(lc *L)
{
    size_t save = L->c->pos;
    accept_kw(L, "const");
    accept_kw(L, "struct");
    size_t n = ident(L);
    if (n) {
        int t = find_type(L, L->t + L->c->pos, n);
        if (t >= 0) {
            L->c->pos += n;
            return t;
        }
    }
    L->c->pos = save;
    return -1;
}

static int declare_local(lc *L, const char *name, size_t len, int type)
{
    lvar v = {name, len, type, L->fsize};
    L->fsize += tsize(L->lp, type);
    if (L->fsize > L->fmax)
        L->fmax = L->fsize;
    if (CBM_ARRAY_PUSH(L->c->ctx, L->vars, v) != CBM_OK) {
        L->c->status = CBM_E_NOMEM;
        L->c->fatal = true;
    }
    return v.slot;
}

/* ---------------------------------------------------------------- expressions */
static int32_t expr(lc *L);
static int32_t expr1(lc *L);
static int32_t assign_expr(lc *L);

static int arith_type(int a, int b)
{
    if (a == T_DOUBLE || b == T_DOUBLE)
        return T_DOUBLE;
    if (a == T_FLOAT || b == T_FLOAT)
        return T_FLOAT;
    return T_INT;
}

static int32_t num(lc *L, double v, int type)
{
    xn n = mk(N_NUM, type);
    n.v = v;
    return node(L, n);
}

/* Converts expression e to type t (implicit conversion), reporting a mismatch at pos. */
static int32_t coerce(lc *L, int32_t e, int t, size_t pos)
{
    if (e < 0)
        return -1;
    int et = ND(e).type;
    if (et == t)
        return e;
    if (is_scalar(et) && is_scalar(t)) {
        xn n = mk(N_CAST, t);
        n.a = e;
        return node(L, n);
    }
    if (is_vec(et) && is_vec(t)) {
        xn n = mk(N_CAST, t);
        n.a = e;
        return node(L, n);
    }
    cbm__cerr(L->c, pos, "cannot convert %s to %s", L->lp->types.data[et].name,
              L->lp->types.data[t].name);
    return -1;
}

/* Parses `(args)` after a callee at '(' into a chain; returns count (-1 on error). */
static int parse_args(lc *L, int32_t *first)
{
    *first = -1;
    int32_t last = -1;
    int n = 0;
    if (!expect(L, "("))
        return -1;
    if (accept(L, ")"))
        return 0;
    do {
        int32_t e = assign_expr(L);
        if (e < 0)
            return -1;
        chain(L, first, &last, e);
        n++;
    } while (accept(L, ","));
    if (!expect(L, ")"))
        return -1;
    return n;
}

/* printf(format, args...): the format is a string literal checked against its arguments, which
 * are numbers or string literals (for %s). */
static int32_t printf_call(lc *L, size_t pos)
{
    cbm__compiler *c = L->c;
    if (!expect(L, "("))
        return -1;
    skip(L);
    size_t fmt;
    if (L->t[c->pos] != '"') {
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
        bool str = L->t[c->pos] == '"';
        if (str) {
            size_t off;
            if (!cbm__string_lit(c, &off))
                return -1;
            xn x = mk(N_STR, T_VOID);
            x.slot = (int32_t)off;
            e = node(L, x);
        } else {
            e = assign_expr(L);
        }
        if (e < 0)
            return -1;
        if (!str && !is_scalar(ND(e).type)) {
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
    xn x = mk(N_CALLB, T_INT);
    x.fn = F_PRINTF;
    x.slot = (int32_t)fmt;
    x.a = first;
    return node(L, x);
}

/* brace initializer `{a, b, ...}` for a value of type t */
static int32_t brace_init(lc *L, int t)
{
    size_t pos = L->c->pos;
    if (!expect(L, "{"))
        return -1;
    const ltype *ty = &L->lp->types.data[t];
    int nf = is_vec(t) ? 3 : ty->nf;
    if (is_scalar(t)) {
        int32_t e = coerce(L, assign_expr(L), t, pos);
        expect(L, "}");
        return e;
    }
    int32_t first = -1, last = -1;
    for (int f = 0; f < nf; f++) {
        if (f && !expect(L, ","))
            return -1;
        int ft = is_vec(t) ? (t == T_V3F ? T_FLOAT : T_DOUBLE) : ty->ftype[f];
        size_t p = L->c->pos;
        int32_t e = peek(L, "{") ? brace_init(L, ft) : coerce(L, assign_expr(L), ft, p);
        if (e < 0)
            return -1;
        chain(L, &first, &last, e);
    }
    if (!expect(L, "}"))
        return -1;
    xn n = mk(N_CTOR, t);
    n.a = first;
    return node(L, n);
}

static lvar *find_var(lc *L, const char *s, size_t n)
{
    for (size_t i = L->vars.len; i-- > 0;)
        if (L->vars.data[i].len == n && !strncmp(L->vars.data[i].name, s, n))
            return &L->vars.data[i];
    return NULL;
}

static lgvar *find_gvar(lc *L, const char *s, size_t n)
{
    for (size_t i = 0; i < L->lp->gvars.len; i++) {
        lgvar *g = &L->lp->gvars.data[i];
        if (strlen(g->name) == n && !strncmp(g->name, s, n))
            return g;
    }
    return NULL;
}

static int pattern(lc *L, lpat *p, bool declare);
static bool is_lvalue(lc *L, int32_t e);

static int32_t call_expr(lc *L, const char *s, size_t n, size_t pos)
{
    lpfg *lp = L->lp;
    /* In*Context(pattern) */
    static const char *const CTXF[] = {"InLeftContext", "InNewLeftContext", "InNewRightContext",
                                       "InRightContext"};
    for (int k = 0; k < CX_N; k++)
        if (strlen(CTXF[k]) == n && !strncmp(s, CTXF[k], n)) {
            lpat p = {0, 0};
            if (!expect(L, "("))
                return -1;
            if (pattern(L, &p, false) < 0)
                return -1;
            if (!expect(L, ")"))
                return -1;
            if (!L->in_prod) {
                cbm__cerr(L->c, pos, "%s is only allowed in a production", CTXF[k]);
                return -1;
            }
            xn x = mk(N_INCTX, T_BOOL);
            x.fn = (uint8_t)k;
            x.a = p.first;
            x.b = p.n;
            return node(L, x);
        }
    /* vector and struct constructors */
    int t = find_type(L, s, n);
    if (t >= 0) {
        int32_t args;
        int na = parse_args(L, &args);
        if (na < 0)
            return -1;
        if (is_scalar(t) && na == 1)
            return coerce(L, args, t, pos);
        if (is_vec(t) && (na == 3 || na == 0)) {
            int ft = t == T_V3F ? T_FLOAT : T_DOUBLE;
            int32_t first = -1, last = -1;
            for (int i = 0; i < 3; i++) {
                int32_t e;
                if (na == 0)
                    e = num(L, 0, ft);
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
            xn x = mk(N_CTOR, t);
            x.a = first;
            return node(L, x);
        }
        if (lp->types.data[t].nf > 0 && na == 0) { /* Name(): a zero value */
            xn x = mk(N_CTOR, t);
            return node(L, x);
        }
        if (lp->types.data[t].nf > 0 && na == lp->types.data[t].nf) { /* Name(f1, f2, ...) */
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
            xn x = mk(N_CTOR, t);
            x.a = first;
            return node(L, x);
        }
        cbm__cerr(L->c, pos, "wrong number of arguments to %s()", lp->types.data[t].name);
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
        const char *fname = L->t + L->c->pos;
        L->c->pos += k;
        size_t id = 0;
        for (; id < lp->funcnames.len; id++)
            if (strlen(lp->funcnames.data[id]) == k && !strncmp(lp->funcnames.data[id], fname, k))
                break;
        if (id == lp->funcnames.len) {
            char *nm = cbm__alloc(L->c->ctx, k + 1);
            if (!nm || CBM_ARRAY_PUSH(L->c->ctx, lp->funcnames, nm) != CBM_OK) {
                if (nm)
                    cbm__free(L->c->ctx, nm, k + 1);
                L->c->status = CBM_E_NOMEM;
                L->c->fatal = true;
                return -1;
            }
            memcpy(nm, fname, k);
            nm[k] = 0;
        }
        if (!expect(L, ","))
            return -1;
        int32_t x = coerce(L, assign_expr(L), T_DOUBLE, L->c->pos);
        if (x < 0 || !expect(L, ")"))
            return -1;
        xn c = mk(N_CALLB, T_DOUBLE);
        c.fn = F_FUNC;
        c.a = x;
        c.slot = (int32_t)id + 1;
        return node(L, c);
    }
    for (size_t i = 0; i < lp->funcs.len; i++) {
        lfunc *f = &lp->funcs.data[i];
        if (strlen(f->name) != n || strncmp(f->name, s, n))
            continue;
        int32_t args;
        int na = parse_args(L, &args);
        if (na < 0)
            return -1;
        if (na != f->np) {
            cbm__cerr(L->c, pos, "%s() takes %d argument%s, %d given", f->name, f->np,
                      f->np == 1 ? "" : "s", na);
            return -1;
        }
        int32_t first = -1, last = -1;
        for (int a = 0; a < na; a++) {
            int32_t e = args;
            args = ND(e).next;
            ND(e).next = -1;
            if (f->pref[a] && (!is_lvalue(L, e) || ND(e).type != f->ptype[a])) {
                cbm__cerr(L->c, pos, "argument %d of %s() must be a variable of type %s", a + 1,
                          f->name, lp->types.data[f->ptype[a]].name);
                return -1;
            }
            e = coerce(L, e, f->ptype[a], pos);
            if (e < 0)
                return -1;
            chain(L, &first, &last, e);
        }
        xn c = mk(N_CALLU, f->ret);
        c.a = first;
        c.slot = (int32_t)i;
        return node(L, c);
    }
    for (size_t i = 0; i < sizeof BUILTINS / sizeof BUILTINS[0]; i++) {
        const bdef *b = &BUILTINS[i];
        if (strlen(b->name) != n || strncmp(b->name, s, n))
            continue;
        int32_t args = -1;
        int na;
        if (b->fn == F_PRINTF)
            return printf_call(L, pos);
        na = parse_args(L, &args);
        if (na < 0)
            return -1;
        if (b->arity >= 0 && na != b->arity) {
            cbm__cerr(L->c, pos, "%s() takes %d argument%s, %d given", b->name, b->arity,
                      b->arity == 1 ? "" : "s", na);
            return -1;
        }
        int rt = T_DOUBLE;
        if (b->fn == F_TOLOCAL || b->fn == F_TOWORLD) {
            int t0 = ND(args).type, t1 = ND(ND(args).next).type;
            if (t1 != T_TVEC || (b->fn == F_TOLOCAL ? !is_vec(t0) : t0 != T_LOCVEC)) {
                cbm__cerr(L->c, pos, "%s() takes a %s and a TurtleVec", b->name,
                          b->fn == F_TOLOCAL ? "vector" : "LocVec");
                return -1;
            }
            rt = b->fn == F_TOLOCAL ? T_LOCVEC : T_V3F;
        } else if (b->fn == F_DOT || b->fn == F_CROSS || b->fn == F_MAKEQ || b->fn == F_VECROT) {
            int t0 = ND(args).type, t1 = ND(ND(args).next).type;
            bool ok = is_vec(t1);
            if (b->fn == F_VECROT) {
                ok = ok && (is_vec(t0) || t0 == T_TVEC) &&
                     is_scalar(ND(ND(ND(args).next).next).type);
                rt = t0;
            } else if (b->fn == F_MAKEQ) {
                ok = is_vec(t0) && is_scalar(t1);
                rt = T_QUAT;
            } else {
                ok = ok && is_vec(t0);
                rt = b->fn == F_DOT ? (t0 == T_V3D || t1 == T_V3D ? T_DOUBLE : T_FLOAT)
                                    : (t0 == T_V3D || t1 == T_V3D ? T_V3D : T_V3F);
            }
            if (!ok) {
                cbm__cerr(L->c, pos, "invalid arguments to %s()%s", b->name,
                          b->fn == F_VECROT ? " (a vector or TurtleVec, an axis, an angle)" : "");
                return -1;
            }
        } else if (b->fn == F_LENGTH || b->fn == F_NORMALIZE) {
            int at = ND(args).type;
            if (!is_vec(at) && !(b->fn == F_NORMALIZE && at == T_TVEC)) {
                cbm__cerr(L->c, pos, "%s() needs a vector", b->name);
                return -1;
            }
            rt = b->fn == F_NORMALIZE ? at : (at == T_V3F ? T_FLOAT : T_DOUBLE);
        } else {
            for (int32_t a = args; a >= 0; a = ND(a).next)
                if (!is_scalar(ND(a).type)) {
                    cbm__cerr(L->c, pos, "%s() needs numbers", b->name);
                    return -1;
                }
            if (b->fn >= F_EQUILIBRIUM && b->fn <= F_REACTION && L->in_prod) {
                cbm__cerr(L->c, pos,
                          "%s() changes the whole string: call it in Start, StartEach, EndEach "
                          "or End",
                          b->name);
                return -1;
            }
            if (b->fn == F_FORWARD || b->fn == F_BACKWARD || b->fn == F_USEGROUP ||
                b->fn == F_SRAND || b->fn == F_STOP || b->fn == F_AGEWOOD || b->fn == F_GRAVITY ||
                b->fn == F_GROUND || b->fn == F_CONTACT || b->fn == F_TROPISM ||
                b->fn == F_PIPEMODEL || b->fn == F_WOOD || b->fn == F_RINGRATE ||
                b->fn == F_SOLVER || b->fn == F_REACTION)
                rt = T_VOID;
            else if (b->fn == F_EQUILIBRIUM || b->fn == F_ADDRINGS || b->fn == F_BREAK)
                rt = T_INT;
            else if (b->fn == F_STABILITY)
                rt = T_DOUBLE;
            else if (b->fn == F_CURGROUP || b->fn == F_RAND)
                rt = T_INT;
            else if ((b->fn == F_MIN || b->fn == F_MAX || b->fn == F_FABS) && args >= 0)
                rt = b->arity == 2 ? arith_type(ND(args).type, ND(ND(args).next).type)
                                   : (ND(args).type == T_BOOL ? T_INT : ND(args).type);
        }
        xn c = mk(N_CALLB, rt);
        c.fn = (uint8_t)b->fn;
        c.a = args;
        return node(L, c);
    }
    cbm__cerr(L->c, pos, "unknown function '%.*s'", (int)n, s);
    return -1;
}

/* One more level of nesting (operators of a chain, ?:, assignments): false after reporting that
 * the limit is exceeded. Parsing and evaluation recurse once per level. */
static bool deeper(lc *L)
{
    if (++L->depth > cbm_context_limits(L->c->ctx)->max_expr_depth) {
        L->depth--;
        cbm__cerr(L->c, L->c->pos,
                  "expression or statement nested too deeply (limit %d, --max-expr-depth)",
                  cbm_context_limits(L->c->ctx)->max_expr_depth);
        L->c->fatal = true;
        return false;
    }
    return true;
}

static int32_t primary(lc *L)
{
    skip(L);
    size_t pos = L->c->pos;
    const char *s = L->t + pos;
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
        L->c->pos = (size_t)(end - L->t);
        r = num(L, v, t);
    } else if (s[0] == '(') {
        L->c->pos++;
        size_t save = L->c->pos;
        int t = parse_type(L);
        if (t >= 0 && accept(L, ")")) { /* cast */
            int32_t e = primary(L);
            if (e >= 0) {
                xn n = mk(N_CAST, t);
                n.a = e;
                if (!(is_scalar(t) && is_scalar(ND(e).type)) && ND(e).type != t) {
                    cbm__cerr(L->c, pos, "invalid cast");
                    r = -1;
                } else
                    r = node(L, n);
            }
        } else {
            L->c->pos = save;
            r = expr(L);
            if (r >= 0 && !expect(L, ")"))
                r = -1;
        }
    } else if (s[0] == '-' || s[0] == '!' || s[0] == '+') {
        L->c->pos++;
        if (s[0] == '-' && s[1] == '-') {
            L->c->pos++;
            int32_t e = primary(L);
            xn n = mk(N_INCDEC, e >= 0 ? ND(e).type : 0);
            n.a = e;
            n.fn = 1;
            r = e >= 0 ? node(L, n) : -1;
        } else if (s[0] == '+' && s[1] == '+') {
            L->c->pos++;
            int32_t e = primary(L);
            xn n = mk(N_INCDEC, e >= 0 ? ND(e).type : 0);
            n.a = e;
            n.fn = 0;
            r = e >= 0 ? node(L, n) : -1;
        } else {
            int32_t e = primary(L);
            if (e >= 0 && s[0] == '+')
                r = e;
            else if (e >= 0) {
                int et = ND(e).type;
                if (s[0] == '!' && !is_scalar(et))
                    cbm__cerr(L->c, pos, "'!' needs a number");
                else if (s[0] == '-' && !is_scalar(et) && !is_vec(et))
                    cbm__cerr(L->c, pos, "'-' needs a number or a vector");
                else {
                    xn n = mk(s[0] == '-' ? N_NEG : N_NOT,
                              s[0] == '!' ? T_BOOL : (et == T_BOOL ? T_INT : et));
                    n.a = e;
                    r = node(L, n);
                }
            }
        }
        L->depth--;
        return r;
    } else if (isid0((unsigned char)s[0])) {
        size_t n = ident(L);
        L->c->pos += n;
        skip(L);
        if (n == 4 && !strncmp(s, "true", 4))
            r = num(L, 1, T_BOOL);
        else if (n == 5 && !strncmp(s, "false", 5))
            r = num(L, 0, T_BOOL);
        else if (n == 8 && !strncmp(s, "RAND_MAX", 8))
            r = num(L, 2147483647, T_INT);
        else if ((n == 4 && !strncmp(s, "M_PI", 4)))
            r = num(L, 3.14159265358979323846, T_DOUBLE);
        else if (L->t[L->c->pos] == '(')
            r = call_expr(L, s, n, pos);
        else {
            lvar *v = find_var(L, s, n);
            lgvar *g = v ? NULL : find_gvar(L, s, n);
            if (v) {
                xn x = mk(N_LOCAL, v->type);
                x.slot = v->slot;
                r = node(L, x);
            } else if (g) {
                xn x = mk(N_GLOBAL, g->type);
                x.slot = g->slot;
                r = node(L, x);
            } else
                cbm__cerr(L->c, pos, "unknown name '%.*s'", (int)n, s);
        }
    } else {
        expected(L, "an expression");
    }
    /* postfix: .field, .method(), ++, -- */
    for (;;) {
        if (r < 0)
            break;
        skip(L);
        size_t p2 = L->c->pos;
        if (L->t[p2] == '.' && !isdigit((unsigned char)L->t[p2 + 1])) {
            L->c->pos++;
            size_t n = ident(L);
            const char *f = L->t + L->c->pos;
            if (!n) {
                expected(L, "a field name");
                r = -1;
                break;
            }
            L->c->pos += n;
            int t = ND(r).type;
            if (peek(L, "(") && is_vec(t)) { /* v.Length(), v.Normalize() */
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
                    cbm__cerr(L->c, p2, "unknown vector method '%.*s'", (int)n, f);
                    r = -1;
                    break;
                }
                xn c = mk(N_CALLB, len ? (t == T_V3F ? T_FLOAT : T_DOUBLE) : t);
                c.fn = (uint8_t)(len ? F_LENGTH : F_NORMALIZE);
                c.a = r;
                if (nor && n == 9 && (ND(r).op == N_LOCAL || ND(r).op == N_GLOBAL)) {
                    /* v.Normalize() normalizes v in place */
                    int32_t cn = node(L, c);
                    xn as = mk(N_ASSIGN, t);
                    xn lv = ND(r);
                    int32_t l2 = node(L, lv);
                    as.a = l2;
                    as.b = cn;
                    r = node(L, as);
                } else
                    r = node(L, c);
                continue;
            }
            int off = -1, ft = -1;
            if (is_vec(t)) {
                if (n == 1 && (f[0] == 'x' || f[0] == 'y' || f[0] == 'z')) {
                    off = f[0] - 'x';
                    ft = t == T_V3F ? T_FLOAT : T_DOUBLE;
                }
            } else if (L->lp->types.data[t].nf > 0) {
                const ltype *ty = &L->lp->types.data[t];
                for (int k = 0; k < ty->nf; k++)
                    if (strlen(ty->fname[k]) == n && !strncmp(ty->fname[k], f, n)) {
                        off = ty->foff[k];
                        ft = ty->ftype[k];
                    }
            }
            if (off < 0) {
                cbm__cerr(L->c, p2, "no field '%.*s' in %s", (int)n, f, L->lp->types.data[t].name);
                r = -1;
                break;
            }
            if (ND(r).op == N_LOCAL || ND(r).op == N_GLOBAL) {
                ND(r).slot += off;
                ND(r).type = (int16_t)ft;
            } else {
                xn x = mk(N_FIELD, ft);
                x.a = r;
                x.slot = off;
                r = node(L, x);
            }
        } else if (!strncmp(L->t + p2, "++", 2) || !strncmp(L->t + p2, "--", 2)) {
            L->c->pos += 2;
            xn x = mk(N_INCDEC, ND(r).type);
            x.a = r;
            x.fn = L->t[p2] == '+' ? 2 : 3;
            r = node(L, x);
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

static const binop *peek_binop(lc *L)
{
    skip(L);
    const char *s = L->t + L->c->pos;
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

static int32_t binary(lc *L, int32_t a, const binop *op, int32_t b, size_t pos)
{
    if (a < 0 || b < 0)
        return -1;
    int ta = ND(a).type, tb = ND(b).type;
    xn n = mk(N_BIN, 0);
    n.a = a;
    n.b = b;
    n.fn = (uint8_t)op->op;
    if (op->op < 0) {
        if (!is_scalar(ta) || !is_scalar(tb)) {
            cbm__cerr(L->c, pos, "'%s' needs numbers", op->s);
            return -1;
        }
        n.op = op->op == -2 ? N_OR : N_AND;
        n.type = T_BOOL;
        return node(L, n);
    }
    if (is_scalar(ta) && is_scalar(tb)) {
        n.type = (int16_t)(op->op >= B_LT ? T_BOOL : arith_type(ta, tb));
        if (op->op == B_REM && n.type != T_INT) {
            cbm__cerr(L->c, pos, "'%%' needs integers (use fmod)");
            return -1;
        }
        return node(L, n);
    }
    int vt = is_vec(ta) ? ta : tb;
    if (is_vec(ta) && is_vec(tb)) {
        vt = (ta == T_V3D || tb == T_V3D) ? T_V3D : T_V3F;
        if (op->op == B_ADD || op->op == B_SUB || op->op == B_REM) {
            n.type = (int16_t)vt;
            return node(L, n);
        }
        if (op->op == B_MUL) { /* dot product */
            n.type = vt == T_V3F ? T_FLOAT : T_DOUBLE;
            return node(L, n);
        }
    } else if (is_vec(ta) && is_scalar(tb) && (op->op == B_MUL || op->op == B_DIV)) {
        n.type = (int16_t)vt;
        return node(L, n);
    } else if (is_scalar(ta) && is_vec(tb) && op->op == B_MUL) {
        n.type = (int16_t)vt;
        return node(L, n);
    }
    if ((ta == T_LOCVEC || tb == T_LOCVEC) && op->op <= B_DIV &&
        (ta == tb || is_scalar(ta) || is_scalar(tb)) && !(is_scalar(ta) && op->op != B_MUL)) {
        n.type = T_LOCVEC; /* componentwise, numbers broadcast */
        return node(L, n);
    }
    if (ta == T_QUAT && op->op == B_MUL && (tb == T_QUAT || is_vec(tb) || tb == T_TVEC)) {
        n.type = (int16_t)tb; /* composition, or rotation of a vector or a frame */
        return node(L, n);
    }
    cbm__cerr(L->c, pos, "invalid operands to '%s' (%s and %s)", op->s, L->lp->types.data[ta].name,
              L->lp->types.data[tb].name);
    return -1;
}

static int32_t binexpr(lc *L, int minprec)
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
        size_t pos = L->c->pos;
        L->c->pos += strlen(op->s);
        int32_t b = binexpr(L, op->prec + 1);
        a = binary(L, a, op, b, pos);
    }
}

static int32_t ternary1(lc *L);

static int32_t ternary(lc *L)
{
    if (!deeper(L))
        return -1;
    int32_t r = ternary1(L);
    L->depth--;
    return r;
}

static int32_t ternary1(lc *L)
{
    int32_t c = binexpr(L, 1);
    if (c < 0 || !accept(L, "?"))
        return c;
    size_t pos = L->c->pos;
    int32_t a = assign_expr(L);
    if (a < 0 || !expect(L, ":"))
        return -1;
    int32_t b = ternary(L);
    if (b < 0)
        return -1;
    int ta = ND(a).type, tb = ND(b).type;
    int t = ta;
    if (is_scalar(ta) && is_scalar(tb))
        t = arith_type(ta, tb);
    else if (ta != tb) {
        cbm__cerr(L->c, pos, "the branches of '?:' have different types");
        return -1;
    }
    xn n = mk(N_COND, t);
    n.a = c;
    n.b = coerce(L, a, t, pos);
    n.c = coerce(L, b, t, pos);
    return node(L, n);
}

static bool is_lvalue(lc *L, int32_t e)
{
    return e >= 0 && (ND(e).op == N_LOCAL || ND(e).op == N_GLOBAL);
}

static int32_t assign_expr(lc *L)
{
    size_t pos = L->c->pos;
    int32_t l = ternary(L);
    if (l < 0)
        return -1;
    skip(L);
    static const char *const AOPS[] = {"=", "+=", "-=", "*=", "/=", "%="};
    static const int ABIN[] = {-1, B_ADD, B_SUB, B_MUL, B_DIV, B_REM};
    for (int k = 5; k >= 0; k--) {
        size_t n = strlen(AOPS[k]);
        if (strncmp(L->t + L->c->pos, AOPS[k], n) || (k == 0 && L->t[L->c->pos + 1] == '='))
            continue;
        if (!is_lvalue(L, l)) {
            cbm__cerr(L->c, pos, "the left side of '%s' is not assignable", AOPS[k]);
            return -1;
        }
        L->c->pos += n;
        size_t p2 = L->c->pos;
        if (!deeper(L))
            return -1;
        int32_t r = assign_expr(L);
        L->depth--;
        if (r < 0)
            return -1;
        int lt = ND(l).type;
        if (k > 0) { /* l op= r  is  l = l op r */
            xn cp = ND(l);
            int32_t l2 = node(L, cp);
            binop bo = {AOPS[k], 0, ABIN[k]};
            r = binary(L, l2, &bo, r, p2);
            if (r < 0)
                return -1;
        }
        xn x = mk(N_ASSIGN, lt);
        x.a = l;
        x.b = (lt >= T_NBUILTIN) ? r : coerce(L, r, lt, p2);
        if (x.b >= 0 && ND(x.b).type != lt) {
            cbm__cerr(L->c, p2, "cannot assign %s to %s", L->lp->types.data[ND(x.b).type].name,
                      L->lp->types.data[lt].name);
            return -1;
        }
        return x.b >= 0 ? node(L, x) : -1;
    }
    return l;
}

static int32_t expr(lc *L)
{
    skip(L);
    size_t start = L->c->pos;
    int32_t a = expr1(L);
    if (a >= 0)
        ND(a).pos = (int32_t)(start < INT32_MAX ? start : INT32_MAX);
    return a;
}

static int32_t expr1(lc *L)
{
    int32_t a = assign_expr(L);
    while (a >= 0 && accept(L, ",")) {
        int32_t b = assign_expr(L);
        if (b < 0)
            return -1;
        xn n = mk(N_COMMA, ND(b).type);
        n.a = a;
        n.b = b;
        a = node(L, n);
    }
    return a;
}

/* ---------------------------------------------------------------- modules, patterns */
/* `Name(args) Name(args) ...` up to `;` (successor) */
static int succ_list(lc *L, lpat *p)
{
    lpfg *lp = L->lp;
    p->first = (int32_t)lp->sms.len;
    p->n = 0;
    for (;;) {
        size_t n = ident(L);
        if (!n)
            break;
        size_t pos = L->c->pos;
        int m = find_mod(lp, L->t + pos, n);
        if (m < 0) {
            cbm__cerr(L->c, pos, "unknown module '%.*s' (declare it with `module`)", (int)n,
                      L->t + pos);
            return -1;
        }
        L->c->pos += n;
        int32_t args = -1;
        int na = 0;
        if (peek(L, "("))
            na = parse_args(L, &args);
        if (na < 0)
            return -1;
        const lmod *md = &lp->mods.data[m];
        if (na != md->np) {
            cbm__cerr(L->c, pos, "module %s has %d parameter%s, %d given", md->name, md->np,
                      md->np == 1 ? "" : "s", na);
            return -1;
        }
        int32_t first = -1, last = -1;
        for (int a = 0; a < na; a++) {
            int32_t e = args;
            args = ND(e).next;
            ND(e).next = -1;
            e = coerce(L, e, md->ptype[a], pos);
            if (e < 0)
                return -1;
            chain(L, &first, &last, e);
        }
        lsm sm = {m, first};
        if (CBM_ARRAY_PUSH(L->c->ctx, lp->sms, sm) != CBM_OK) {
            L->c->status = CBM_E_NOMEM;
            L->c->fatal = true;
            return -1;
        }
        p->n++;
    }
    return 0;
}

/* A context or predecessor pattern: `Name(f1, f2) ...`; declare: formal names become new
 * locals; else they name existing variables (In*Context). */
static int pattern(lc *L, lpat *p, bool declare)
{
    lpfg *lp = L->lp;
    p->first = (int32_t)lp->sms.len;
    p->n = 0;
    for (;;) {
        size_t n = ident(L);
        if (!n)
            break;
        size_t pos = L->c->pos;
        int m = find_mod(lp, L->t + pos, n);
        if (m < 0) {
            if (p->n && declare)
                break;
            cbm__cerr(L->c, pos, "unknown module '%.*s'", (int)n, L->t + pos);
            return -1;
        }
        L->c->pos += n;
        const lmod *md = &lp->mods.data[m];
        int32_t first = -1, last = -1;
        int na = 0;
        if (accept(L, "(")) {
            if (!accept(L, ")")) {
                do {
                    size_t k = ident(L);
                    size_t fp = L->c->pos;
                    if (!k) {
                        expected(L, "a parameter name");
                        return -1;
                    }
                    L->c->pos += k;
                    if (na >= md->np) {
                        na++;
                        continue;
                    }
                    xn x = mk(N_LOCAL, md->ptype[na]);
                    if (declare)
                        x.slot = declare_local(L, L->t + fp, k, md->ptype[na]);
                    else {
                        lvar *v = find_var(L, L->t + fp, k);
                        if (!v) {
                            cbm__cerr(L->c, fp, "unknown variable '%.*s'", (int)k, L->t + fp);
                            return -1;
                        }
                        if (v->type != md->ptype[na]) {
                            cbm__cerr(L->c, fp, "'%.*s' has type %s, module %s wants %s", (int)k,
                                      L->t + fp, lp->types.data[v->type].name, md->name,
                                      lp->types.data[md->ptype[na]].name);
                            return -1;
                        }
                        x.slot = v->slot;
                    }
                    int32_t e = node(L, x);
                    if (e < 0)
                        return -1;
                    chain(L, &first, &last, e);
                    na++;
                } while (accept(L, ","));
                if (!expect(L, ")"))
                    return -1;
            }
        }
        if (na != md->np) {
            cbm__cerr(L->c, pos, "module %s has %d parameter%s, the pattern names %d", md->name,
                      md->np, md->np == 1 ? "" : "s", na);
            return -1;
        }
        lsm sm = {m, first};
        if (CBM_ARRAY_PUSH(L->c->ctx, lp->sms, sm) != CBM_OK) {
            L->c->status = CBM_E_NOMEM;
            L->c->fatal = true;
            return -1;
        }
        p->n++;
    }
    return 0;
}

/* ---------------------------------------------------------------- statements */
static int32_t statement(lc *L);

static int32_t block(lc *L)
{
    if (!expect(L, "{"))
        return -1;
    size_t nvars = L->vars.len;
    int fs = L->fsize;
    int32_t first = -1, last = -1;
    bool ok = true;
    while (!accept(L, "}")) {
        if (!L->t[L->c->pos] || fatal(L)) {
            expected(L, "'}'");
            return -1;
        }
        size_t before = L->c->pos;
        int32_t s = statement(L);
        if (s < 0) {
            ok = false;
            if (fatal(L))
                return -1;
            if (L->c->pos == before) /* always make progress */
                recover_stmt(L);
            if (L->c->pos == before && L->t[L->c->pos] != '}')
                L->c->pos++;
            continue;
        }
        chain(L, &first, &last, s);
        while (ND(last).next >= 0)
            last = ND(last).next;
    }
    L->vars.len = nvars;
    L->fsize = fs;
    xn b = mk(S_BLOCK, 0);
    b.a = first;
    return ok ? node(L, b) : -1;
}

/* declaration statement after its type: `a = 1, b, c = {..};` */
static int32_t declaration(lc *L, int t)
{
    int32_t first = -1, last = -1;
    do {
        size_t n = ident(L);
        size_t pos = L->c->pos;
        if (!n) {
            expected(L, "a variable name");
            recover_stmt(L);
            return -1;
        }
        L->c->pos += n;
        int32_t init = -1;
        if (accept(L, "=")) {
            size_t p2 = L->c->pos;
            init = peek(L, "{") ? brace_init(L, t) : assign_expr(L);
            if (init >= 0 && t < T_NBUILTIN)
                init = coerce(L, init, t, p2);
            if (init >= 0 && ND(init).type != t) {
                cbm__cerr(L->c, p2, "cannot initialize %s with %s", L->lp->types.data[t].name,
                          L->lp->types.data[ND(init).type].name);
                init = -1;
            }
            if (init < 0) {
                recover_stmt(L);
                return -1;
            }
        }
        xn d = mk(S_DECL, t);
        d.slot = declare_local(L, L->t + pos, n, t);
        d.a = init;
        int32_t s = node(L, d);
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

static int32_t statement(lc *L)
{
    skip(L);
    size_t pos = L->c->pos;
    if (!deeper(L))
        return -1;
    int32_t r = -1;
    int t;
    if (peek(L, "{")) {
        r = block(L);
    } else if (accept(L, ";")) {
        r = node(L, mk(S_NOP, 0));
    } else if (accept_kw(L, "if")) {
        xn n = mk(S_IF, 0);
        if (expect(L, "(")) {
            n.a = coerce(L, expr(L), T_BOOL, pos);
            if (n.a >= 0 && expect(L, ")")) {
                n.b = statement(L);
                if (accept_kw(L, "else"))
                    n.c = statement(L);
                if (n.b >= 0)
                    r = node(L, n);
            }
        }
    } else if (accept_kw(L, "while")) {
        xn n = mk(S_WHILE, 0);
        if (expect(L, "(")) {
            n.a = coerce(L, expr(L), T_BOOL, pos);
            if (n.a >= 0 && expect(L, ")")) {
                n.b = statement(L);
                if (n.b >= 0)
                    r = node(L, n);
            }
        }
    } else if (accept_kw(L, "do")) {
        xn n = mk(S_DO, 0);
        n.b = statement(L);
        if (n.b >= 0 && accept_kw(L, "while") && expect(L, "(")) {
            n.a = coerce(L, expr(L), T_BOOL, pos);
            if (n.a >= 0 && expect(L, ")") && expect(L, ";"))
                r = node(L, n);
        } else if (n.b >= 0)
            expected(L, "'while'");
    } else if (accept_kw(L, "for")) {
        size_t nvars = L->vars.len;
        int fs = L->fsize;
        xn n = mk(S_FOR, 0);
        bool ok = expect(L, "(");
        if (ok && !accept(L, ";")) {
            int ty = parse_type(L);
            if (ty >= 0)
                n.a = declaration(L, ty);
            else {
                int32_t e = expr(L);
                if (e >= 0) {
                    xn s = mk(S_EXPR, 0);
                    s.a = e;
                    n.a = node(L, s);
                }
                ok = e >= 0 && expect(L, ";");
            }
            ok = ok && n.a >= 0;
        }
        if (ok && !accept(L, ";")) {
            n.b = coerce(L, expr(L), T_BOOL, pos);
            ok = n.b >= 0 && expect(L, ";");
        }
        if (ok && !accept(L, ")")) {
            n.c = expr(L);
            ok = n.c >= 0 && expect(L, ")");
        }
        if (ok) {
            n.d = statement(L);
            if (n.d >= 0)
                r = node(L, n);
        }
        L->vars.len = nvars;
        L->fsize = fs;
    } else if (accept_kw(L, "return")) {
        xn n = mk(S_RETURN, L->in_prod ? T_VOID : L->ret_type);
        if (!peek(L, ";")) {
            if (L->ret_type == T_VOID || L->in_prod) {
                cbm__cerr(L->c, pos, "return with a value here");
                recover_stmt(L);
                L->depth--;
                return -1;
            }
            n.a = coerce(L, expr(L), L->ret_type, pos);
            if (n.a < 0 && L->ret_type >= T_NBUILTIN)
                n.a = -1;
        } else if (L->ret_type != T_VOID && !L->in_prod) {
            cbm__cerr(L->c, pos, "return needs a value");
        }
        if (expect(L, ";"))
            r = node(L, n);
    } else if (accept_kw(L, "switch")) {
        xn n = mk(S_SWITCH, 0);
        if (expect(L, "(")) {
            n.a = coerce(L, expr(L), T_DOUBLE, pos);
            if (n.a >= 0 && expect(L, ")")) {
                L->in_switch++;
                n.b = statement(L);
                L->in_switch--;
                if (n.b >= 0)
                    r = node(L, n);
            }
        }
    } else if (L->in_switch && (accept_kw(L, "case") || accept_kw(L, "default"))) {
        xn n = mk(S_CASE, 0);
        bool dflt = L->t[pos] == 'd';
        if (!dflt)
            n.a = coerce(L, expr(L), T_DOUBLE, pos);
        if ((dflt || n.a >= 0) && expect(L, ":"))
            r = node(L, n);
    } else if (accept_kw(L, "break")) {
        if (expect(L, ";"))
            r = node(L, mk(S_BREAK, 0));
    } else if (accept_kw(L, "continue")) {
        if (expect(L, ";"))
            r = node(L, mk(S_CONTINUE, 0));
    } else if (peek(L, "nproduce") || accept_kw(L, "produce")) {
        bool partial = accept_kw(L, "nproduce");
        if (!L->in_prod) {
            cbm__cerr(L->c, pos, "produce outside a production");
            recover_stmt(L);
        } else {
            lpat p;
            if (succ_list(L, &p) == 0 && expect(L, ";")) {
                xn n = mk(S_PRODUCE, 0);
                n.a = p.first;
                n.b = p.n;
                n.fn = partial;
                r = node(L, n);
            } else
                recover_stmt(L);
        }
    } else if ((t = parse_type(L)) >= 0) {
        r = declaration(L, t);
    } else {
        int32_t e = expr(L);
        if (e >= 0 && expect(L, ";")) {
            xn s = mk(S_EXPR, 0);
            s.a = e;
            r = node(L, s);
        } else if (!fatal(L))
            recover_stmt(L);
    }
    L->depth--;
    if (r >= 0)
        ND(r).pos = (int32_t)(pos < INT32_MAX ? pos : INT32_MAX);
    return r;
}

/* ---------------------------------------------------------------- top level */
static int32_t const_int(lc *L, const char *what)
{
    size_t pos = L->c->pos;
    int32_t e = expr(L);
    if (e < 0)
        return -1;
    if (!is_scalar(ND(e).type)) {
        cbm__cerr(L->c, pos, "%s must be a number", what);
        return -1;
    }
    return e;
}

static void parse_struct(lc *L, size_t pos)
{
    lpfg *lp = L->lp;
    size_t n = ident(L);
    if (!n) {
        expected(L, "a struct name");
        recover(L);
        return;
    }
    char name[64];
    snprintf(name, sizeof name, "%.*s", (int)(n < 63 ? n : 63), L->t + L->c->pos);
    if (find_type(L, L->t + L->c->pos, n) >= 0) {
        cbm__cerr(L->c, L->c->pos, "type '%s' is already defined", name);
        recover(L);
        return;
    }
    L->c->pos += n;
    ltype ty;
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
            if (ty.nf >= MAXFLD) {
                cbm__cerr(L->c, L->c->pos, "more than %d fields in struct %s", MAXFLD, name);
                recover(L);
                goto fail;
            }
            char *fn = cbm__alloc(L->c->ctx, k + 1);
            if (!fn) {
                L->c->status = CBM_E_NOMEM;
                L->c->fatal = true;
                goto fail;
            }
            memcpy(fn, L->t + L->c->pos, k);
            fn[k] = 0;
            L->c->pos += k;
            ty.fname[ty.nf] = fn;
            ty.ftype[ty.nf] = ft;
            ty.foff[ty.nf] = ty.size;
            ty.size += tsize(lp, ft);
            ty.nf++;
        } while (accept(L, ","));
        if (!expect(L, ";")) {
            recover(L);
            goto fail;
        }
    }
    accept(L, ";");
    if (ty.size > MAXSZ) {
        cbm__cerr(L->c, pos, "struct %s is too large (more than %d numbers)", name, MAXSZ);
        goto fail;
    }
    ty.name = cbm__strdup(L->c->ctx, name);
    if (!ty.name || CBM_ARRAY_PUSH(L->c->ctx, lp->types, ty) != CBM_OK) {
        cbm__strfree(L->c->ctx, ty.name);
        L->c->status = CBM_E_NOMEM;
        L->c->fatal = true;
        goto fail;
    }
    return;
fail:
    for (int i = 0; i < ty.nf; i++)
        cbm__strfree(L->c->ctx, ty.fname[i]);
}

static void parse_module_decl(lc *L)
{
    do {
        size_t n = ident(L);
        size_t pos = L->c->pos;
        if (!n) {
            expected(L, "a module name");
            recover(L);
            return;
        }
        L->c->pos += n;
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
                    cbm__cerr(L->c, pos, "more than %d parameters", MAXF);
                    recover(L);
                    return;
                }
                pt[np++] = t;
                size_t k = ident(L); /* optional parameter name */
                if (k && find_type(L, L->t + L->c->pos, k) < 0)
                    L->c->pos += k;
            } while (accept(L, ","));
            if (!expect(L, ")")) {
                recover(L);
                return;
            }
        }
        int m = find_mod(L->lp, L->t + pos, n);
        if (m >= 0) {
            cbm__cerr(L->c, pos, "module '%.*s' is already declared", (int)n, L->t + pos);
            continue;
        }
        add_mod(L, L->t + pos, n, pt, np, NULL, pos);
    } while (accept(L, ","));
    if (!expect(L, ";"))
        recover(L);
}

static void symbol_list(lc *L, bool consider)
{
    lpfg *lp = L->lp;
    if (consider)
        for (int i = 0; i < 128; i++)
            lp->considered[i] = false;
    for (;;) {
        size_t n = ident(L);
        if (!n)
            break;
        int m = find_mod(lp, L->t + L->c->pos, n);
        if (m < 0)
            cbm__cerr(L->c, L->c->pos, "unknown module '%.*s'", (int)n, L->t + L->c->pos);
        else
            lp->considered[lp->mods.data[m].code] = consider;
        L->c->pos += n;
        accept(L, ",");
    }
    if (!expect(L, ";"))
        recover(L);
}

/* The roles of a point-mass module's parameters, `mass: Grape(mass, radius)`: `mass` (kg),
 * `radius` (m, the organ's contact sphere) or `_` (not used), in parameter order. Offsets (in
 * doubles) into *moff and *roff (-1: absent). false after an error. */
static bool mass_roles(lc *L, const lmod *md, int *moff, int *roff)
{
    lpfg *lp = L->lp;
    int off = 0;
    for (int k = 0;; k++) {
        size_t n = ident(L), pos = L->c->pos;
        if (!n) {
            expected(L, "mass, radius or _");
            return false;
        }
        L->c->pos += n;
        int *dst = NULL;
        if (n == 4 && !strncmp(L->t + pos, "mass", 4))
            dst = moff;
        else if (n == 6 && !strncmp(L->t + pos, "radius", 6))
            dst = roff;
        else if (!(n == 1 && L->t[pos] == '_')) {
            cbm__cerr(L->c, pos,
                      "unknown role '%.*s' of a point-mass parameter (mass, radius or _)", (int)n,
                      L->t + pos);
            return false;
        }
        if (k >= md->np) {
            cbm__cerr(L->c, pos, "module '%s' has %d parameter%s", md->name, md->np,
                      md->np == 1 ? "" : "s");
            return false;
        }
        if (dst && *dst >= 0) {
            cbm__cerr(L->c, pos, "'%.*s' given twice", (int)n, L->t + pos);
            return false;
        }
        if (dst && !is_scalar(md->ptype[k])) {
            cbm__cerr(L->c, pos, "parameter %d of '%s' must be a number to be its %.*s, not %s",
                      k + 1, md->name, (int)n, L->t + pos, lp->types.data[md->ptype[k]].name);
            return false;
        }
        if (dst)
            *dst = off;
        off += tsize(lp, md->ptype[k]);
        if (!accept(L, ","))
            break;
    }
    if (!expect(L, ")"))
        return false;
    if (*moff < 0) {
        cbm__cerr(L->c, L->c->pos - 1, "point-mass module '%s' needs a 'mass' parameter", md->name);
        return false;
    }
    return true;
}

/* `mechanics: Module;` (its MechSegment parameter is the segment) and `mass: A, B;` (the first
 * parameter, a number, is a point mass in kg), or with roles `mass: Grape(mass, radius);` (see
 * mass_roles). */
static void mech_decl(lc *L, bool mass)
{
    lpfg *lp = L->lp;
    for (;;) {
        size_t n = ident(L), pos = L->c->pos;
        if (!n) {
            expected(L, "a module name");
            recover(L);
            return;
        }
        int m = find_mod(lp, L->t + pos, n);
        L->c->pos += n;
        if (m < 0) {
            cbm__cerr(L->c, pos, "unknown module '%.*s'", (int)n, L->t + pos);
        } else {
            const lmod *md = &lp->mods.data[m];
            int off = 0, found = -1, roff = -1;
            if (mass && accept(L, "(")) {
                int moff = -1;
                if (!mass_roles(L, md, &moff, &roff)) {
                    recover(L);
                    return;
                }
                lp->mech.mass_off[md->code] = moff;
                lp->mech.radius_off[md->code] = roff;
                if (!accept(L, ","))
                    break;
                continue;
            }
            for (int i = 0; i < md->np && found < 0; i++) {
                if (mass ? i == 0 && is_scalar(md->ptype[i]) : md->ptype[i] == T_MSEG)
                    found = off;
                off += tsize(lp, md->ptype[i]);
            }
            if (found < 0 && mass)
                cbm__cerr(L->c, pos,
                          "the first parameter of point-mass module '%s' must be a number "
                          "(its mass, kg)%s%s",
                          md->name, md->np ? ", not " : "",
                          md->np ? lp->types.data[md->ptype[0]].name : "");
            else if (found < 0)
                cbm__cerr(L->c, pos, "mechanical module '%s' needs a MechSegment parameter",
                          md->name);
            else if (!mass && lp->mech.seg_code >= 0 && lp->mech.seg_code != md->code)
                cbm__cerr(L->c, pos, "only one module can carry the mechanical segment");
            else if (mass) {
                lp->mech.mass_off[md->code] = found;
                lp->mech.radius_off[md->code] = -1;
            } else {
                lp->mech.seg_code = md->code;
                lp->mech.seg_off = found;
            }
        }
        if (!accept(L, ","))
            break;
    }
    if (!expect(L, ";"))
        recover(L);
}

/* `pred-with-contexts : { body }` */
static void parse_production(lc *L, lset *set, int group)
{
    lpfg *lp = L->lp;
    size_t pos = L->c->pos;
    lprod pr;
    memset(&pr, 0, sizeof pr);
    pr.pos = pos;
    pr.group = group;
    L->vars.len = 0;
    L->fsize = L->fmax = 0;
    L->in_prod = true;
    L->ret_type = T_VOID;
    lpat pats[5];
    int npats = 0;
    int ops[5];
    for (;;) {
        if (npats == 5) {
            cbm__cerr(L->c, L->c->pos, "too many context parts");
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
        const char *s = L->t + L->c->pos;
        if (s[0] == '<' && s[1] == '<')
            ops[npats - 1] = 1, L->c->pos += 2;
        else if (s[0] == '<')
            ops[npats - 1] = 0, L->c->pos += 1;
        else if (s[0] == '>' && s[1] == '>')
            ops[npats - 1] = 2, L->c->pos += 2;
        else if (s[0] == '>')
            ops[npats - 1] = 3, L->c->pos += 1;
        else if (s[0] == ':') {
            ops[npats - 1] = -1;
            L->c->pos++;
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
        int k = ops[ip] == 0 ? CX_LC : CX_NLC;
        if (pr.cx[k].n) {
            cbm__cerr(L->c, pos, "two %s contexts", k == CX_LC ? "left" : "new left");
            recover(L);
            return;
        }
        pr.cx[k] = pats[ip++];
    }
    if (ip >= npats) {
        cbm__cerr(L->c, pos, "production without a predecessor");
        recover(L);
        return;
    }
    pr.mod = lp->sms.data[pats[ip].first].mod;
    pr.pred = pats[ip];
    int prev = ops[ip];
    for (int k = ip + 1; k < npats; k++) {
        int cx = prev == 2 ? CX_NRC : prev == 3 ? CX_RC : -1;
        if (cx < 0 || pr.cx[cx].n) {
            cbm__cerr(L->c, pos, "misplaced context");
            recover(L);
            return;
        }
        pr.cx[cx] = pats[k];
        prev = ops[k];
    }
    if (pr.cx[CX_NLC].n && pr.cx[CX_NRC].n) {
        cbm__cerr(L->c, pos, "a production cannot have both new left and new right context");
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
    pr.fsize = L->fmax;
    L->in_prod = false;
    if (pr.body < 0)
        return;
    if (CBM_ARRAY_PUSH(L->c->ctx, set->prods, pr) != CBM_OK) {
        L->c->status = CBM_E_NOMEM;
        L->c->fatal = true;
    }
}

static void parse_function(lc *L, int rt, size_t pos)
{
    lpfg *lp = L->lp;
    size_t n = ident(L);
    lfunc f;
    memset(&f, 0, sizeof f);
    f.ret = rt;
    f.pos = pos;
    f.name = cbm__alloc(L->c->ctx, n + 1);
    if (!f.name) {
        L->c->status = CBM_E_NOMEM;
        L->c->fatal = true;
        return;
    }
    memcpy(f.name, L->t + L->c->pos, n);
    f.name[n] = 0;
    L->c->pos += n;
    L->vars.len = 0;
    L->fsize = L->fmax = 0;
    expect(L, "(");
    if (!accept(L, ")") && !accept_kw(L, "void")) {
        do {
            int t = parse_type(L);
            bool ref = t >= 0 && accept(L, "&");
            size_t k = t >= 0 ? ident(L) : 0;
            if (t < 0 || !k || f.np >= MAXF) {
                expected(L, "a parameter (type and name)");
                recover(L);
                cbm__strfree(L->c->ctx, f.name);
                return;
            }
            f.pref[f.np] = ref;
            f.ptype[f.np++] = t;
            declare_local(L, L->t + L->c->pos, k, t);
            L->c->pos += k;
        } while (accept(L, ","));
        expect(L, ")");
    } else
        accept(L, ")");
    /* register before the body: recursion */
    f.body = -1;
    if (CBM_ARRAY_PUSH(L->c->ctx, lp->funcs, f) != CBM_OK) {
        cbm__strfree(L->c->ctx, f.name);
        L->c->status = CBM_E_NOMEM;
        L->c->fatal = true;
        return;
    }
    size_t fi = lp->funcs.len - 1;
    L->ret_type = rt;
    L->in_prod = false;
    int32_t b = block(L);
    lp->funcs.data[fi].body = b;
    lp->funcs.data[fi].fsize = L->fmax;
    L->ret_type = T_VOID;
}

static void parse_global(lc *L, int t)
{
    lpfg *lp = L->lp;
    L->vars.len = 0;
    L->fsize = L->fmax = 0;
    do {
        size_t n = ident(L);
        if (!n) {
            expected(L, "a name");
            recover(L);
            return;
        }
        size_t pos = L->c->pos;
        if (find_gvar(L, L->t + pos, n)) {
            cbm__cerr(L->c, pos, "'%.*s' is already defined", (int)n, L->t + pos);
            recover(L);
            return;
        }
        L->c->pos += n;
        int32_t init = -1;
        if (accept(L, "=")) {
            size_t p2 = L->c->pos;
            init = peek(L, "{") ? brace_init(L, t) : assign_expr(L);
            if (init >= 0 && t < T_NBUILTIN)
                init = coerce(L, init, t, p2);
            if (init < 0) {
                recover(L);
                return;
            }
        }
        lgvar g = {NULL, t, lp->nglobal, init};
        g.name = cbm__alloc(L->c->ctx, n + 1);
        if (!g.name || CBM_ARRAY_PUSH(L->c->ctx, lp->gvars, g) != CBM_OK) {
            if (g.name)
                cbm__free(L->c->ctx, g.name, n + 1);
            L->c->status = CBM_E_NOMEM;
            L->c->fatal = true;
            return;
        }
        memcpy(g.name, L->t + pos, n);
        g.name[n] = 0;
        lp->nglobal += tsize(lp, t);
    } while (accept(L, ","));
    if (!expect(L, ";"))
        recover(L);
}

static bool label(lc *L, const char *kw)
{
    size_t save = L->c->pos;
    skip(L);
    const char *s = L->t + L->c->pos;
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
            L->c->pos = save;
            return false;
        }
        i++, k++;
    }
    if (isid((unsigned char)s[i])) {
        L->c->pos = save;
        return false;
    }
    L->c->pos += i;
    skip(L);
    if (L->t[L->c->pos] != ':') {
        L->c->pos = save;
        return false;
    }
    L->c->pos++;
    return true;
}

static cbm_status setup_builtins(lc *L)
{
    lpfg *lp = L->lp;
    cbm_context *ctx = L->c->ctx;
    static const char *const TN[] = {"void",      "int",    "float",      "double",
                                     "bool",      "V3f",    "V3d",        "Quaternion",
                                     "TurtleVec", "LocVec", "MechSegment"};
    static const int TS[] = {0, 1, 1, 1, 1, 3, 3, 4, 9, 3, MS_SIZE};
    for (int i = 0; i < T_NBUILTIN; i++)
        CBM_TRY(add_type(lp, ctx, TN[i], TS[i]));
    /* Quaternion {w, x, y, z} (double), TurtleVec {H, L, U} (V3f): built-in structs */
    static const char *const QF[] = {"w", "x", "y", "z"}, *const TF[] = {"H", "L", "U"};
    ltype *q = &lp->types.data[T_QUAT], *tv = &lp->types.data[T_TVEC];
    for (int i = 0; i < 4; i++) {
        q->fname[i] = cbm__strdup(ctx, QF[i]);
        q->ftype[i] = T_DOUBLE;
        q->foff[i] = i;
        q->nf++;
        if (!q->fname[i])
            return CBM_E_NOMEM;
    }
    ltype *lv = &lp->types.data[T_LOCVEC];
    static const char *const LF[] = {"h", "l", "u"};
    for (int i = 0; i < 3; i++) {
        lv->fname[i] = cbm__strdup(ctx, LF[i]);
        lv->ftype[i] = T_FLOAT;
        lv->foff[i] = i;
        lv->nf++;
        if (!lv->fname[i])
            return CBM_E_NOMEM;
    }
    for (int i = 0; i < 3; i++) {
        tv->fname[i] = cbm__strdup(ctx, TF[i]);
        tv->ftype[i] = T_V3F;
        tv->foff[i] = 3 * i;
        tv->nf++;
        if (!tv->fname[i])
            return CBM_E_NOMEM;
    }
    /* MechSegment: the fields at the offsets of lsys/mechlang.h */
    static const char *const MF[] = {
        "length", "a",   "b", "E", "G",      "density",      "mor",          "rest",
        "omega",  "pos", "H", "U", "stress", "stress_ratio", "carried_mass", "age"};
    static const int MO[] = {MS_LENGTH, MS_A,     MS_B,       MS_E,   MS_G, MS_DENSITY,
                             MS_MOR,    MS_REST,  MS_OMEGA,   MS_POS, MS_H, MS_U,
                             MS_STRESS, MS_RATIO, MS_CARRIED, MS_AGE};
    ltype *ms = &lp->types.data[T_MSEG];
    for (int i = 0; i < 16; i++) {
        ms->fname[i] = cbm__strdup(ctx, MF[i]);
        ms->ftype[i] = (MO[i] == MS_REST || MO[i] == MS_OMEGA || MO[i] == MS_POS || MO[i] == MS_H ||
                        MO[i] == MS_U)
                           ? T_V3D
                           : T_DOUBLE;
        ms->foff[i] = MO[i];
        ms->nf++;
        if (!ms->fname[i])
            return CBM_E_NOMEM;
    }
    cbm__mechlang_init(&lp->mech);
    for (int i = 0; i < 128; i++) {
        lp->bycode[i] = -1;
        lp->considered[i] = true;
    }
    for (size_t i = 0; i < sizeof TURTLE / sizeof TURTLE[0]; i++) {
        int pt[MAXF], np = 0;
        for (const char *p = TURTLE[i][2]; *p; p++)
            pt[np++] = *p == 'i' ? T_INT : *p == 'v' ? T_V3F : T_FLOAT;
        if (add_mod(L, TURTLE[i][0], strlen(TURTLE[i][0]), pt, np, TURTLE[i][1], 0) < 0)
            return L->c->status != CBM_OK ? L->c->status : CBM_E_NOMEM;
    }
    /* V3f and its synonyms */
    lp->sb = find_mod(lp, "SB", 2);
    lp->eb = find_mod(lp, "EB", 2);
    return CBM_OK;
}

static void parse_block_item(lc *L, int which)
{
    L->vars.len = 0;
    L->fsize = L->fmax = 0;
    L->in_prod = false;
    L->ret_type = T_VOID;
    int32_t b = block(L);
    if (b >= 0) {
        L->lp->blocks[which] = b;
        L->lp->block_fsize[which] = L->fmax;
    }
}

static void parse_top(lc *L)
{
    lpfg *lp = L->lp;
    lset *set = &lp->main;
    int group = 0;
    for (;;) {
        skip(L);
        if (fatal(L) || !L->t[L->c->pos])
            return;
        size_t pos = L->c->pos;
        int t;
        if (label(L, "derivation length")) {
            lp->dlen_expr = const_int(L, "derivation length");
            if (!expect(L, ";"))
                recover(L);
        } else if (label(L, "Axiom")) {
            L->vars.len = 0;
            L->fsize = L->fmax = 0;
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
            size_t p2 = L->c->pos;
            int32_t e = const_int(L, "group");
            if (e >= 0 && ND(e).op == N_NUM && !(fabs(ND(e).v) <= 2147483647.0))
                cbm__cerr(L->c, p2, "group %g is out of range (an int)", ND(e).v);
            else if (e >= 0 && ND(e).op == N_NUM)
                group = (int)ND(e).v;
            else if (e >= 0)
                cbm__cerr(L->c, p2, "group needs a number");
            expect(L, ":");
        } else if (accept_kw(L, "endgroup")) {
            group = 0;
            accept(L, ";");
        } else if (accept_kw(L, "module")) {
            parse_module_decl(L);
        } else if (accept_kw(L, "struct") && !peek(L, "{")) {
            size_t save = L->c->pos;
            size_t n = ident(L);
            L->c->pos += n;
            bool def = peek(L, "{");
            L->c->pos = save;
            if (def)
                parse_struct(L, pos);
            else {
                L->c->pos = pos;
                t = parse_type(L);
                if (t < 0) {
                    expected(L, "a struct name");
                    recover(L);
                } else
                    parse_global(L, t);
            }
        } else if (accept_kw(L, "typedef")) {
            cbm__cerr(L->c, pos, "typedef is not supported; declare `struct Name { ... };`");
            recover(L);
        } else if ((t = parse_type(L)) >= 0 || accept_kw(L, "void")) {
            if (t < 0)
                t = T_VOID;
            size_t n = ident(L);
            size_t save = L->c->pos;
            L->c->pos += n;
            bool fn = n && peek(L, "(");
            L->c->pos = save;
            if (fn)
                parse_function(L, t, pos);
            else if (t == T_VOID) {
                expected(L, "a function");
                recover(L);
            } else
                parse_global(L, t);
        } else {
            size_t n = ident(L);
            if (n && find_mod(lp, L->t + L->c->pos, n) >= 0)
                parse_production(L, set, group);
            else {
                expected(L, "a module declaration, a production or a section");
                recover(L);
            }
        }
    }
}

/* ---------------------------------------------------------------- evaluation */
static void rt_error(lpfg *lp, cbm_status s, const char *msg)
{
    if (lp->err == CBM_OK) {
        lp->err = s;
        lp->err_pos = lp->at;
        snprintf(lp->errmsg, sizeof lp->errmsg, "%s", msg);
    }
}

/* Takes one operation (a call or a loop iteration) from the step's budgets; false after
 * reporting the limit. */
static bool spend(lpfg *lp, bool loop)
{
    if (--lp->ops < 0) {
        rt_error(lp, CBM_E_LIMIT,
                 "more productions applied, function calls and loop iterations in one step "
                 "than the limit (--max-operations)");
        return false;
    }
    if (loop && --lp->budget < 0) {
        rt_error(lp, CBM_E_LIMIT,
                 "more loop iterations in one step than the limit (--max-loop-iterations)");
        return false;
    }
    return true;
}

static double *lv_ptr(lpfg *lp, const xn *n, double *fr)
{
    return n->op == N_LOCAL ? fr + n->slot : lp->glob + n->slot;
}

static void ev(cbm_lsys *ls, int32_t ni, double *fr, double *out);
static int exec(cbm_lsys *ls, int32_t ni, double *fr);
static bool ctx_match(cbm_lsys *ls, int k, int32_t first, int32_t n, double *fr);

static double evs(cbm_lsys *ls, int32_t ni, double *fr)
{
    double v[MAXSZ + 1];
    ev(ls, ni, fr, v);
    return v[0];
}

static double bin_scalar(int op, int t, double a, double b, lpfg *lp)
{
    double r;
    if (t == T_INT && op <= B_REM) { /* C int arithmetic: 32 bits, wrapping on overflow */
        long long x = (long long)c_int(a), y = (long long)c_int(b);
        switch (op) {
        case B_ADD:
            return wrap_int(x + y);
        case B_SUB:
            return wrap_int(x - y);
        case B_MUL:
            return wrap_int(x * y);
        default:
            if (y == 0) {
                rt_error(lp, CBM_E_RUNTIME,
                         op == B_DIV ? "integer division by zero" : "integer remainder by zero");
                return 0;
            }
            return wrap_int(op == B_DIV ? x / y : x % y);
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
        if (t == T_INT) {
            long long d = cbm__to_ll(b);
            if (d == 0) {
                rt_error(lp, CBM_E_RUNTIME, "integer division by zero");
                return 0;
            }
            /* C integer division, as the L+C dialect means it */
            // NOLINTNEXTLINE(bugprone-integer-division)
            return (double)(cbm__to_ll(a) / d);
        }
        r = a / b;
        break;
    case B_REM: {
        long long d = cbm__to_ll(b);
        if (d == 0) {
            rt_error(lp, CBM_E_RUNTIME, "integer remainder by zero");
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
    return conv_scalar(t, r);
}

/* rand()/srand() as the C library lpfg models are compiled with (glibc's random(): additive
 * feedback r[i] = r[i-3] + r[i-31] after a Lehmer initialisation, 310 values discarded), so a
 * model that draws with rand() % 100 makes the same choices as under lpfg. */
static uint32_t glibc_next(lpfg *lp)
{
    uint32_t v = lp->gr[(lp->gpos + 34 - 31) % 34] + lp->gr[(lp->gpos + 34 - 3) % 34];
    lp->gr[lp->gpos] = v;
    lp->gpos = (lp->gpos + 1) % 34;
    return v;
}

static void glibc_srand(lpfg *lp, uint32_t seed)
{
    int32_t r = (int32_t)(seed ? seed : 1);
    lp->gr[0] = (uint32_t)r;
    for (int i = 1; i < 31; i++) {
        int32_t hi = r / 127773, lo = r % 127773;
        r = 16807 * lo - 2836 * hi;
        if (r < 0)
            r += 2147483647;
        lp->gr[i] = (uint32_t)r;
    }
    for (int i = 31; i < 34; i++)
        lp->gr[i] = lp->gr[i - 31];
    lp->gpos = 0;
    for (int i = 34; i < 344; i++)
        glibc_next(lp);
}

static double glibc_rand(lpfg *lp)
{
    return (double)(glibc_next(lp) >> 1);
}

/* nrand: the polar method with values in pairs, from the erand48 stream */
static double nrand(cbm__eval *e, double m, double s)
{
    if (e->nran_have) {
        e->nran_have = 0;
        return m + s * e->nran_cached;
    }
    double v1, v2, r;
    do {
        v1 = 2 * cbm__rand48_next(&e->ran) - 1;
        v2 = 2 * cbm__rand48_next(&e->ran) - 1;
        r = v1 * v1 + v2 * v2;
    } while (r >= 1 || r == 0);
    double f = sqrt(-2 * log(r) / r);
    e->nran_cached = v1 * f;
    e->nran_have = 1;
    return m + s * v2 * f;
}

/* The mechanics built-ins (lsys/mechlang.c) over the current string. */
static void call_mech(cbm_lsys *ls, const xn *n, double *fr, double *out)
{
    lpfg *lp = ls->lp;
    double a[5] = {0, 0, 0, 0, 0};
    int na = 0;
    for (int32_t x = n->a; x >= 0 && na < 5; x = lp->nodes.data[x].next)
        a[na++] = evs(ls, x, fr);
    if (lp->err != CBM_OK)
        return;
    cbm__mechlang *m = &lp->mech;
    char msg[128];
    switch ((bfn)n->fn) {
    case F_GRAVITY:
        m->gravity = (cbm_vec3){a[0], a[1], a[2]};
        return;
    case F_GROUND:
        if (!isfinite(a[0]) || !(a[1] >= 0) || !isfinite(a[1]) || !(a[2] >= 0) || !isfinite(a[2])) {
            rt_error(lp, CBM_E_INVALID,
                     "Ground(height y0 m, stiffness k >= 0 N/m, smoothing >= 0 m)");
            return;
        }
        m->ground_y = a[0];
        m->ground_k = a[1];
        m->ground_s = a[2];
        return;
    case F_CONTACT:
        if (!(a[0] >= 0) || !isfinite(a[0]) || !(a[1] >= 0) || !isfinite(a[1])) {
            rt_error(lp, CBM_E_INVALID, "Contact(stiffness k >= 0 N/m, smoothing >= 0 m)");
            return;
        }
        m->contact_k = a[0];
        m->contact_s = a[1];
        return;
    case F_TROPISM:
        m->tropism.direction = (cbm_vec3){a[0], a[1], a[2]};
        m->tropism.strength = a[3];
        return;
    case F_PIPEMODEL:
        if (!(a[0] > 0) || !(a[1] >= 0))
            rt_error(lp, CBM_E_INVALID, "PipeModel(exponent > 0, leaf area >= 0 m^2)");
        m->growth.pipe_exponent = a[0];
        m->growth.leaf_area = a[1];
        return;
    case F_WOOD:
        if (!(a[0] > 0) || !(a[1] >= a[0]) || !(a[2] >= 0) || !(a[3] >= 0) || !(a[4] >= 0)) {
            rt_error(lp, CBM_E_INVALID,
                     "Wood(E_juvenile > 0, E_adult >= E_juvenile, adult age >= 0, density >= 0, "
                     "modulus of rupture >= 0)");
            return;
        }
        m->growth.youngs_juvenile = a[0];
        m->growth.youngs_adult = a[1];
        m->growth.adult_age = a[2];
        m->growth.density = a[3];
        m->growth.modulus_of_rupture = a[4];
        return;
    case F_RINGRATE:
        if (!(a[0] > 0 && a[0] <= 1) || !(a[1] >= 0) || !isfinite(a[1])) {
            rt_error(lp, CBM_E_INVALID, "RingRate(kappa in (0, 1], min_ring >= 0 m)");
            return;
        }
        m->growth.pipe_rate = a[0];
        m->growth.min_ring = a[1];
        return;
    case F_SOLVER:
        if (!(a[0] > 0) || !isfinite(a[0]) || !(a[1] >= 0) || !(a[1] <= 1e12) ||
            !(a[2] == 0 || a[2] == 1)) {
            rt_error(lp, CBM_E_INVALID,
                     "Solver(tolerance > 0, max passes >= 0 (0: the context's limit), go on 0 or "
                     "1)");
            return;
        }
        m->solve.tolerance = a[0];
        m->solve.max_passes = (size_t)a[1];
        m->go_on = a[2] == 1;
        return;
    case F_REACTION:
        if (!(a[0] >= 0) || !(a[1] >= 0 && a[1] <= 1) || !(a[2] >= 0) || !(a[3] >= 0)) {
            rt_error(lp, CBM_E_INVALID,
                     "ReactionWood(threshold >= 0 rad/m, beta in [0, 1], increment >= 0 m, "
                     "E_reaction >= 0 Pa)");
            return;
        }
        m->growth.reaction_threshold = a[0];
        m->growth.reaction_beta = a[1];
        m->growth.reaction_increment = a[2];
        m->growth.reaction_youngs = a[3];
        return;
    default:
        break;
    }
    if (lp->rewriting) {
        rt_error(lp, CBM_E_INVALID,
                 "mechanics operations are refused during a derivation pass; call them in "
                 "Start, StartEach, EndEach or End");
        return;
    }
    int op = n->fn == F_EQUILIBRIUM ? CBM__ML_EQUILIBRIUM
             : n->fn == F_ADDRINGS  ? CBM__ML_RINGS
             : n->fn == F_AGEWOOD   ? CBM__ML_AGE
             : n->fn == F_STABILITY ? CBM__ML_STABILITY
                                    : CBM__ML_BREAK;
    double r = 0;
    cbm_status s =
        cbm__mechlang_run(ls->ctx, m, &ls->cur, op, a[0], &r, msg, sizeof msg, &ls->mech_time);
    if (s != CBM_OK) {
        char full[160];
        snprintf(full, sizeof full, "%s(): %s",
                 n->fn == F_EQUILIBRIUM ? "Equilibrium"
                 : n->fn == F_ADDRINGS  ? "AddRings"
                 : n->fn == F_AGEWOOD   ? "AgeWood"
                 : n->fn == F_STABILITY ? "Stability"
                                        : "Break",
                 msg);
        rt_error(lp, s, full);
        return;
    }
    ls->homo_valid = false;
    out[0] = r;
}

static void call_builtin(cbm_lsys *ls, const xn *n, double *fr, double *out)
{
    lpfg *lp = ls->lp;
    if (n->fn == F_PRINTF) {
        cbm__fmt_arg args[CBM__FMT_MAX_ARGS];
        int k = 0;
        const char *strings = ls->comp.strings.data;
        for (int32_t x = n->a; x >= 0 && k < CBM__FMT_MAX_ARGS; x = lp->nodes.data[x].next, k++) {
            const xn *an = &lp->nodes.data[x];
            args[k].s = an->op == N_STR ? strings + an->slot : NULL;
            args[k].v = an->op == N_STR ? 0 : evs(ls, x, fr);
        }
        cbm__fmt_print(ls->ctx, strings + n->slot, args, k);
        out[0] = 0;
        return;
    }
    double a[2] = {0, 0};
    int32_t x = n->a;
    if (n->fn == F_DOT || n->fn == F_CROSS || n->fn == F_MAKEQ || n->fn == F_VECROT) {
        double u[9], w[3], ang = 0;
        int32_t x1 = lp->nodes.data[x].next;
        ev(ls, x, fr, u);
        ev(ls, x1, fr, w);
        if (n->fn == F_VECROT)
            ang = evs(ls, lp->nodes.data[x1].next, fr);
        else if (n->fn == F_MAKEQ)
            ang = w[0];
        if (n->fn == F_DOT)
            out[0] = u[0] * w[0] + u[1] * w[1] + u[2] * w[2];
        else if (n->fn == F_CROSS) {
            out[0] = u[1] * w[2] - u[2] * w[1];
            out[1] = u[2] * w[0] - u[0] * w[2];
            out[2] = u[0] * w[1] - u[1] * w[0];
        } else if (n->fn == F_MAKEQ) {
            double l = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
            double sn = sin(ang / 2) / (l > 0 ? l : 1);
            out[0] = cos(ang / 2);
            for (int i = 0; i < 3; i++)
                out[i + 1] = u[i] * sn;
        } else { /* Rodrigues' rotation of each vector about the unit axis; like lpfg, a new
                  * value: the argument is not changed (it may be any expression) */
            double l = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
            double ax[3] = {w[0] / (l > 0 ? l : 1), w[1] / (l > 0 ? l : 1), w[2] / (l > 0 ? l : 1)};
            double c = cos(ang), sn = sin(ang);
            int nv = n->type == T_TVEC ? 3 : 1;
            for (int v = 0; v < nv; v++) {
                double *p = u + 3 * v, d = ax[0] * p[0] + ax[1] * p[1] + ax[2] * p[2];
                double cr[3] = {ax[1] * p[2] - ax[2] * p[1], ax[2] * p[0] - ax[0] * p[2],
                                ax[0] * p[1] - ax[1] * p[0]};
                for (int i = 0; i < 3; i++)
                    out[3 * v + i] = p[i] * c + cr[i] * sn + ax[i] * d * (1 - c);
            }
        }
        conv_value(lp, n->type, out);
        return;
    }
    if (n->fn == F_TOLOCAL || n->fn == F_TOWORLD) {
        double v[3], f[9];
        ev(ls, x, fr, v);
        ev(ls, lp->nodes.data[x].next, fr, f);
        for (int i = 0; i < 3; i++)
            out[i] = n->fn == F_TOLOCAL
                         ? v[0] * f[3 * i] + v[1] * f[3 * i + 1] + v[2] * f[3 * i + 2]
                         : v[0] * f[i] + v[1] * f[3 + i] + v[2] * f[6 + i];
        conv_value(lp, n->type, out);
        return;
    }
    if (n->fn == F_NORMALIZE && n->type == T_TVEC) {
        ev(ls, x, fr, out);
        for (int v = 0; v < 3; v++) {
            double *p = out + 3 * v, l = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
            for (int i = 0; i < 3; i++)
                p[i] = l > 0 ? p[i] / l : 0;
        }
        conv_value(lp, n->type, out);
        return;
    }
    if (n->fn == F_LENGTH || n->fn == F_NORMALIZE) {
        double v[3];
        ev(ls, x, fr, v);
        double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
        if (n->fn == F_LENGTH)
            out[0] = conv_scalar(n->type, l);
        else {
            for (int i = 0; i < 3; i++)
                out[i] = l > 0 ? v[i] / l : 0;
            conv_value(lp, n->type, out);
        }
        return;
    }
    if (n->fn >= F_EQUILIBRIUM && n->fn <= F_REACTION) {
        call_mech(ls, n, fr, out);
        return;
    }
    for (int i = 0; i < 2 && x >= 0; i++, x = lp->nodes.data[x].next)
        a[i] = evs(ls, x, fr);
    double r = 0;
    switch ((bfn)n->fn) {
    case F_SIN:
        r = sin(a[0]);
        break;
    case F_COS:
        r = cos(a[0]);
        break;
    case F_TAN:
        r = tan(a[0]);
        break;
    case F_ASIN:
        r = asin(a[0]);
        break;
    case F_ACOS:
        r = acos(a[0]);
        break;
    case F_ATAN:
        r = atan(a[0]);
        break;
    case F_ATAN2:
        r = atan2(a[0], a[1]);
        break;
    case F_EXP:
        r = exp(a[0]);
        break;
    case F_LOG:
        r = log(a[0]);
        break;
    case F_LOG10:
        r = log10(a[0]);
        break;
    case F_POW:
        r = pow(a[0], a[1]);
        break;
    case F_SQRT:
        r = sqrt(a[0]);
        break;
    case F_FABS:
        r = fabs(a[0]);
        break;
    case F_FLOOR:
        r = floor(a[0]);
        break;
    case F_CEIL:
        r = ceil(a[0]);
        break;
    case F_FMOD:
        r = fmod(a[0], a[1]);
        break;
    case F_MIN:
        r = a[0] < a[1] ? a[0] : a[1];
        break;
    case F_MAX:
        r = a[0] > a[1] ? a[0] : a[1];
        break;
    case F_RAN:
        r = cbm__rand48_next(&ls->ev.ran) * a[0];
        break;
    case F_NRAN:
        r = nrand(&ls->ev, a[0], a[1]);
        break;
    case F_DRAND:
        r = cbm__rand48_next(&ls->ev.ran);
        break;
    case F_RAND:
        r = glibc_rand(lp);
        break;
    case F_SRAND: {
        long long s = cbm__to_ll(a[0]);
        glibc_srand(lp, (uint32_t)s);
        cbm__rand48_seed16(&ls->ev.ran, 0x330E, (uint16_t)(s & 0xFFFF),
                           (uint16_t)((s >> 16) & 0xFFFF));
        ls->ev.nran_have = 0;
        break;
    }
    case F_FUNC:
        if (!ls->func)
            rt_error(lp, CBM_E_RUNTIME,
                     "func(name, x) needs function files (.func or .fset) on the command line");
        else
            r = ls->func(ls->func_ud, lp->funcids.data[n->slot - 1], a[0]);
        break;
    case F_FORWARD:
        lp->backward = false;
        break;
    case F_BACKWARD:
        lp->backward = true;
        break;
    case F_USEGROUP:
        lp->group = (int)cbm__to_ll(a[0]);
        break;
    case F_CURGROUP:
        r = lp->group;
        break;
    case F_STOP:
        ls->ev.stopped = true;
        break;
    default:
        break;
    }
    out[0] = conv_scalar(n->type == T_VOID ? T_DOUBLE : n->type, r);
}

static void call_user(cbm_lsys *ls, const xn *n, double *fr, double *out)
{
    lpfg *lp = ls->lp;
    const lfunc *f = &lp->funcs.data[n->slot];
    if (lp->call_depth >= cbm_context_limits(ls->ctx)->max_call_depth ||
        lp->sp + (size_t)f->fsize + 1 > lp->stack_cap) {
        rt_error(lp, CBM_E_LIMIT, "function calls nested too deeply (--max-call-depth)");
        memset(out, 0, (size_t)tsize(lp, f->ret) * sizeof(double));
        return;
    }
    if (!spend(lp, false)) {
        memset(out, 0, (size_t)tsize(lp, f->ret) * sizeof(double));
        return;
    }
    double *nf = lp->stack + lp->sp;
    size_t save = lp->sp;
    lp->sp += (size_t)f->fsize;
    int off = 0;
    int i = 0;
    for (int32_t x = n->a; x >= 0; x = lp->nodes.data[x].next, i++) {
        ev(ls, x, fr, nf + off);
        off += tsize(lp, f->ptype[i]);
    }
    lp->call_depth++;
    double *saved = lp->ret;
    int32_t at = lp->at;
    memset(out, 0, (size_t)tsize(lp, f->ret) * sizeof(double));
    lp->ret = out;
    exec(ls, f->body, nf);
    lp->at = at;
    off = 0;
    i = 0;
    for (int32_t x = n->a; x >= 0; x = lp->nodes.data[x].next, i++) {
        int sz = tsize(lp, f->ptype[i]);
        if (f->pref[i])
            memcpy(lv_ptr(lp, &lp->nodes.data[x], fr), nf + off, (size_t)sz * sizeof(double));
        off += sz;
    }
    lp->ret = saved;
    lp->call_depth--;
    lp->sp = save;
}

static void ev(cbm_lsys *ls, int32_t ni, double *fr, double *out)
{
    lpfg *lp = ls->lp;
    const xn *n = &lp->nodes.data[ni];
    switch (n->op) {
    case N_NUM:
        out[0] = n->v;
        return;
    case N_LOCAL:
    case N_GLOBAL:
        memcpy(out, lv_ptr(lp, n, fr), (size_t)tsize(lp, n->type) * sizeof(double));
        return;
    case N_FIELD: {
        double tmp[MAXSZ + 1];
        ev(ls, n->a, fr, tmp);
        memcpy(out, tmp + n->slot, (size_t)tsize(lp, n->type) * sizeof(double));
        return;
    }
    case N_NEG: {
        ev(ls, n->a, fr, out);
        for (int i = 0; i < tsize(lp, n->type); i++)
            out[i] = -out[i];
        return;
    }
    case N_NOT:
        out[0] = evs(ls, n->a, fr) == 0;
        return;
    case N_CAST:
        ev(ls, n->a, fr, out);
        conv_value(lp, n->type, out);
        return;
    case N_BIN: {
        int ta = lp->nodes.data[n->a].type, tb = lp->nodes.data[n->b].type;
        if (is_scalar(ta) && is_scalar(tb)) {
            double a = evs(ls, n->a, fr), b = evs(ls, n->b, fr);
            int ct = n->type == T_BOOL ? arith_type(ta, tb) : n->type;
            if (n->type == T_BOOL && ct == T_INT) /* compare ints exactly */
                ct = T_DOUBLE;
            out[0] = bin_scalar(n->fn, ct, a, b, lp);
            return;
        }
        if (n->type == T_LOCVEC) {
            double a[3], b[3];
            ev(ls, n->a, fr, a);
            ev(ls, n->b, fr, b);
            for (int i = 0; i < 3; i++) {
                double x = a[is_scalar(ta) ? 0 : i], y = b[is_scalar(tb) ? 0 : i];
                out[i] = n->fn == B_ADD   ? x + y
                         : n->fn == B_SUB ? x - y
                         : n->fn == B_MUL ? x * y
                                          : x / y;
            }
            conv_value(lp, n->type, out);
            return;
        }
        if (ta == T_QUAT) {
            double q[4], b[9];
            ev(ls, n->a, fr, q);
            ev(ls, n->b, fr, b);
            if (tb == T_QUAT) { /* Hamilton product */
                out[0] = q[0] * b[0] - q[1] * b[1] - q[2] * b[2] - q[3] * b[3];
                out[1] = q[0] * b[1] + q[1] * b[0] + q[2] * b[3] - q[3] * b[2];
                out[2] = q[0] * b[2] - q[1] * b[3] + q[2] * b[0] + q[3] * b[1];
                out[3] = q[0] * b[3] + q[1] * b[2] - q[2] * b[1] + q[3] * b[0];
            } else { /* v' = v + 2w (u x v) + 2 u x (u x v), u = (x, y, z) */
                int nv = tb == T_TVEC ? 3 : 1;
                for (int v = 0; v < nv; v++) {
                    const double *p = b + 3 * v, *u = q + 1;
                    double t[3] = {2 * (u[1] * p[2] - u[2] * p[1]), 2 * (u[2] * p[0] - u[0] * p[2]),
                                   2 * (u[0] * p[1] - u[1] * p[0])};
                    double c[3] = {u[1] * t[2] - u[2] * t[1], u[2] * t[0] - u[0] * t[2],
                                   u[0] * t[1] - u[1] * t[0]};
                    for (int i = 0; i < 3; i++)
                        out[3 * v + i] = p[i] + q[0] * t[i] + c[i];
                }
            }
            conv_value(lp, n->type, out);
            return;
        }
        double a[3], b[3];
        ev(ls, n->a, fr, a);
        ev(ls, n->b, fr, b);
        if (is_vec(ta) && is_vec(tb)) {
            if (n->fn == B_ADD)
                for (int i = 0; i < 3; i++)
                    out[i] = a[i] + b[i];
            else if (n->fn == B_SUB)
                for (int i = 0; i < 3; i++)
                    out[i] = a[i] - b[i];
            else if (n->fn == B_REM) {
                out[0] = a[1] * b[2] - a[2] * b[1];
                out[1] = a[2] * b[0] - a[0] * b[2];
                out[2] = a[0] * b[1] - a[1] * b[0];
            } else
                out[0] = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        } else if (is_vec(ta)) {
            for (int i = 0; i < 3; i++)
                out[i] = n->fn == B_MUL ? a[i] * b[0] : a[i] / b[0];
        } else {
            for (int i = 0; i < 3; i++)
                out[i] = a[0] * b[i];
        }
        conv_value(lp, n->type, out);
        return;
    }
    case N_AND:
        out[0] = evs(ls, n->a, fr) != 0 && evs(ls, n->b, fr) != 0;
        return;
    case N_OR:
        out[0] = evs(ls, n->a, fr) != 0 || evs(ls, n->b, fr) != 0;
        return;
    case N_COND:
        ev(ls, evs(ls, n->a, fr) != 0 ? n->b : n->c, fr, out);
        return;
    case N_COMMA:
        ev(ls, n->a, fr, out);
        ev(ls, n->b, fr, out);
        return;
    case N_ASSIGN: {
        const xn *l = &lp->nodes.data[n->a];
        int sz = tsize(lp, n->type);
        ev(ls, n->b, fr, out); /* of the lvalue's type (coerced at compile time) */
        memcpy(lv_ptr(lp, l, fr), out, (size_t)sz * sizeof(double));
        return;
    }
    case N_INCDEC: {
        double *p = lv_ptr(lp, &lp->nodes.data[n->a], fr);
        double old = *p;
        *p = conv_scalar(n->type, *p + ((n->fn & 1) ? -1 : 1));
        out[0] = n->fn >= 2 ? old : *p;
        return;
    }
    case N_CALLB:
        call_builtin(ls, n, fr, out);
        return;
    case N_CALLU:
        call_user(ls, n, fr, out);
        return;
    case N_CTOR: {
        int off = 0;
        if (n->a < 0)
            memset(out, 0, (size_t)tsize(lp, n->type) * sizeof(double));
        for (int32_t x = n->a; x >= 0; x = lp->nodes.data[x].next) {
            ev(ls, x, fr, out + off);
            off += tsize(lp, lp->nodes.data[x].type);
        }
        return;
    }
    case N_INCTX:
        out[0] = ctx_match(ls, n->fn, n->a, n->b, fr);
        return;
    default:
        out[0] = 0;
        return;
    }
}

/* ---------------------------------------------------------------- the module string */
static cbm_status room(cbm_context *ctx, lstr *s, size_t nsym, size_t npm, size_t npar)
{
    if (s->n + nsym > s->cap)
        CBM_TRY(cbm__grow(ctx, (void **)&s->sym, &s->cap, 1, s->n + nsym));
    if (s->npm + npm > s->pccap)
        CBM_TRY(cbm__grow(ctx, (void **)&s->pc, &s->pccap, 1, s->npm + npm));
    if (s->npar + npar > s->parcap)
        CBM_TRY(cbm__grow(ctx, &s->par, &s->parcap, sizeof(double), s->npar + npar));
    return CBM_OK;
}

static cbm_status push_mod(cbm_context *ctx, lstr *s, int code, const double *p, int np)
{
    CBM_TRY(room(ctx, s, 1, 1, (size_t)np));
    s->sym[s->n++] = (uint8_t)(code | (np ? LSYS_PARAM_BIT : 0));
    if (np) {
        s->pc[s->npm++] = (uint8_t)np;
        memcpy((double *)s->par + s->npar, p, (size_t)np * sizeof(double));
        s->npar += (size_t)np;
    }
    return CBM_OK;
}

/* appends the modules of src [from i] to dst, reversed when rev */
static cbm_status append_str(cbm_context *ctx, lstr *dst, const lstr *src, bool rev)
{
    if (!src->n)
        return CBM_OK;
    CBM_TRY(room(ctx, dst, src->n, src->npm, src->npar));
    if (!rev) {
        memcpy(dst->sym + dst->n, src->sym, src->n);
        if (src->npm)
            memcpy(dst->pc + dst->npm, src->pc, src->npm);
        if (src->npar)
            memcpy((double *)dst->par + dst->npar, src->par, src->npar * sizeof(double));
        dst->n += src->n;
        dst->npm += src->npm;
        dst->npar += src->npar;
        return CBM_OK;
    }
    size_t j = src->npm, k = src->npar;
    for (size_t i = src->n; i-- > 0;) {
        uint8_t s = src->sym[i];
        dst->sym[dst->n++] = s;
        if (s & LSYS_PARAM_BIT) {
            uint8_t np = src->pc[--j];
            k -= np;
            dst->pc[dst->npm++] = np;
            memcpy((double *)dst->par + dst->npar, (const double *)src->par + k,
                   np * sizeof(double));
            dst->npar += np;
        }
    }
    return CBM_OK;
}

/* walker */
static inline bool w_ok(const walk *w)
{
    return w->i >= 0 && (size_t)w->i < w->s->n;
}

static inline int w_code(const walk *w)
{
    return w->s->sym[w->i] & 0x7f;
}

static inline void w_phys_next(walk *w)
{
    if (w->s->sym[w->i] & LSYS_PARAM_BIT)
        w->k += w->s->pc[w->j++];
    w->i++;
}

static inline void w_phys_prev(walk *w)
{
    w->i--;
    if (w->i >= 0 && (w->s->sym[w->i] & LSYS_PARAM_BIT))
        w->k -= w->s->pc[--w->j];
}

/* logical steps; false when leaving the string */
static inline bool w_adv(walk *w)
{
    if (!w_ok(w))
        return false;
    if (w->dir > 0)
        w_phys_next(w);
    else
        w_phys_prev(w);
    return w_ok(w);
}

static inline bool w_back(walk *w)
{
    if (w->dir > 0) {
        if (w->i <= 0) {
            w->i = -1;
            return false;
        }
        if (w->i > (ptrdiff_t)w->s->n)
            return false;
        w_phys_prev(w);
    } else {
        if (w->i >= (ptrdiff_t)w->s->n - 1) {
            w->i = (ptrdiff_t)w->s->n;
            return false;
        }
        if (w->i < 0) { /* before the logical start: re-enter at the physical end */
            return false;
        }
        w_phys_next(w);
    }
    return true;
}

static walk walk_at(const lstr *s, size_t i, size_t j, size_t k, int dir)
{
    walk w = {s, (ptrdiff_t)i, j, k, dir};
    return w;
}

/* position after the last module (dir +1), or at the last module (dir -1: logical start) */
static walk walk_end(const lstr *s, int dir)
{
    if (dir > 0)
        return walk_at(s, s->n, s->npm, s->npar, 1);
    walk w = walk_at(s, s->n, s->npm, s->npar, -1);
    if (s->n)
        w_phys_prev(&w);
    else
        w.i = -1;
    return w;
}

/* Walks to the bracket that closes the current nesting level: forward to its ']' (opener '['),
 * or backward to its '[' (opener ']'). Brackets opened on the way are skipped whole. */
static bool find_closing(walk *w, int opener, int closer, bool forward)
{
    int depth = 0;
    while (w_ok(w)) {
        int c = w_code(w);
        if (c == opener)
            depth++;
        else if (c == closer) {
            if (depth == 0)
                return true;
            depth--;
        }
        if (!(forward ? w_adv(w) : w_back(w)))
            return false;
    }
    return false;
}

/* Scans t's string up to its end; false when memory refuses (the table is then dropped and
 * the walks scan). Going forward an SB waits for its EB; in the reversed new string an EB comes
 * first and waits for the SB appended later. */
static bool brtab_extend(cbm_context *ctx, brtab *t, int sbc, int ebc)
{
    walk *p = &t->at;
    while ((size_t)p->i < t->s->n) {
        int c = w_code(p);
        walk none = *p;
        none.i = -1;
        bool ok = true;
        if (c == sbc) {
            walk m = none;
            if (t->dir < 0 && t->stack.len)
                m = t->stack.data[--t->stack.len];
            ok = CBM_ARRAY_PUSH(ctx, t->open, (size_t)p->i) == CBM_OK &&
                 CBM_ARRAY_PUSH(ctx, t->close, m) == CBM_OK;
            if (ok && t->dir > 0) {
                walk ord = none; /* the SB's order in `open` */
                ord.i = (ptrdiff_t)t->open.len - 1;
                ok = CBM_ARRAY_PUSH(ctx, t->stack, ord) == CBM_OK;
            }
        } else if (c == ebc) {
            if (t->dir < 0)
                ok = CBM_ARRAY_PUSH(ctx, t->stack, *p) == CBM_OK;
            else if (t->stack.len)
                t->close.data[t->stack.data[--t->stack.len].i] = *p;
        }
        if (!ok) {
            t->s = NULL;
            return false;
        }
        w_phys_next(p);
    }
    return true;
}

/* w is at an SB: the EB that matches it, through the table; false: no table for this walk. */
static bool brtab_jump(lpfg *lp, cbm_context *ctx, walk *w, int sbc, int ebc)
{
    brtab *t = &lp->brk[w->dir > 0 ? 0 : 1];
    if (!t->s || t->s != w->s || t->dir != w->dir || !brtab_extend(ctx, t, sbc, ebc))
        return false;
    size_t lo = 0, hi = t->open.len;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (t->open.data[mid] < (size_t)w->i)
            lo = mid + 1;
        else
            hi = mid;
    }
    if (lo == t->open.len || t->open.data[lo] != (size_t)w->i)
        return false;
    *w = t->close.data[lo];
    return true;
}

static void brtab_start(lpfg *lp, int k, const lstr *s, int dir)
{
    brtab *t = &lp->brk[k];
    t->s = s;
    t->dir = dir;
    t->at = walk_at(s, 0, 0, 0, dir);
    t->open.len = t->close.len = t->stack.len = 0;
}

static void brtab_free(cbm_context *ctx, brtab *t)
{
    CBM_ARRAY_FREE(ctx, t->open);
    CBM_ARRAY_FREE(ctx, t->close);
    CBM_ARRAY_FREE(ctx, t->stack);
    t->s = NULL;
}

/* w is at an SB: moves it to the EB that closes the branch; false when there is none */
static bool skip_branch(const cbm_lsys *ls, walk *w, int sbc, int ebc)
{
    walk at = *w;
    if (brtab_jump(ls->lp, ls->ctx, w, sbc, ebc))
        return w->i >= 0; /* i = -1: unmatched, the walk leaves the string */
    *w = at;
    w_adv(w);
    return find_closing(w, sbc, ebc, true);
}

/* find_closing forward, jumping over the branches inside through the bracket table */
static bool find_eob(const cbm_lsys *ls, walk *w, int sbc, int ebc)
{
    while (w_ok(w)) {
        int c = w_code(w);
        if (c == ebc)
            return true;
        if (c == sbc && !skip_branch(ls, w, sbc, ebc))
            return false;
        if (!w_adv(w))
            return false;
    }
    return false;
}

static bool find_bob(walk *w, int sbc, int ebc)
{
    return find_closing(w, ebc, sbc, false);
}

static bool accept_right(const cbm_lsys *ls, walk *w, int code)
{
    const lpfg *lp = ls->lp;
    int sbc = lp->mods.data[lp->sb].code, ebc = lp->mods.data[lp->eb].code;
    if (!w_ok(w))
        return false;
    if (code == ebc && !find_eob(ls, w, sbc, ebc))
        return false;
    while (w_ok(w) && w_code(w) != code) {
        int c = w_code(w);
        if (!lp->considered[c])
            w_adv(w);
        else if (c == sbc) {
            if (!skip_branch(ls, w, sbc, ebc))
                return false;
            w_adv(w);
        } else
            break;
    }
    return w_ok(w) && w_code(w) == code;
}

static bool accept_left(const lpfg *lp, walk *w, int code)
{
    int sbc = lp->mods.data[lp->sb].code, ebc = lp->mods.data[lp->eb].code;
    if (!w_back(w))
        return false;
    while (w_ok(w) && w_code(w) != code) {
        int c = w_code(w);
        if (!lp->considered[c] || c == sbc) {
            if (!w_back(w))
                return false;
        } else if (c == ebc) {
            if (!w_back(w) || !find_bob(w, sbc, ebc) || !w_back(w))
                return false;
        } else
            break;
    }
    return w_ok(w) && w_code(w) == code;
}

static void bind(cbm_lsys *ls, const walk *w, int32_t formals, double *fr)
{
    lpfg *lp = ls->lp;
    if (!(w->s->sym[w->i] & LSYS_PARAM_BIT))
        return;
    const double *p = (const double *)w->s->par + w->k;
    for (int32_t f = formals; f >= 0; f = lp->nodes.data[f].next) {
        const xn *x = &lp->nodes.data[f];
        int sz = tsize(lp, x->type);
        memcpy(fr + x->slot, p, (size_t)sz * sizeof(double));
        p += sz;
    }
}

/* Matches pattern [first, first+n) of context k from the scanner's position; on success the
 * scanner moves past it and the formals are bound. */
static bool ctx_match(cbm_lsys *ls, int k, int32_t first, int32_t n, double *fr)
{
    lpfg *lp = ls->lp;
    walk w = lp->scan[k];
    if (!w.s)
        return false;
    if (k == CX_RC || k == CX_NRC) {
        for (int32_t i = 0; i < n; i++) {
            const lsm *m = &lp->sms.data[first + i];
            if (!accept_right(ls, &w, lp->mods.data[m->mod].code))
                return false;
            w_adv(&w);
        }
        /* bind after the whole pattern matched */
        walk b = lp->scan[k];
        for (int32_t i = 0; i < n; i++) {
            const lsm *m = &lp->sms.data[first + i];
            accept_right(ls, &b, lp->mods.data[m->mod].code);
            bind(ls, &b, m->args, fr);
            w_adv(&b);
        }
    } else {
        for (int32_t i = n; i-- > 0;) {
            const lsm *m = &lp->sms.data[first + i];
            if (!accept_left(lp, &w, lp->mods.data[m->mod].code))
                return false;
        }
        walk b = lp->scan[k];
        for (int32_t i = n; i-- > 0;) {
            const lsm *m = &lp->sms.data[first + i];
            accept_left(lp, &b, lp->mods.data[m->mod].code);
            bind(ls, &b, m->args, fr);
        }
    }
    lp->scan[k] = w;
    return true;
}

/* A parameter of a produced module is infinite or NaN (division by zero, overflow): an error
 * at the argument's expression, or with limits.allow_nonfinite a warning (once per run) and
 * the value is kept. Returns whether to go on. */
static bool nonfinite(cbm_lsys *ls, int32_t pos, const char *module)
{
    lpfg *lp = ls->lp;
    if (!cbm_context_limits(ls->ctx)->allow_nonfinite) {
        char msg[160];
        snprintf(msg, sizeof msg,
                 "a parameter of %.60s is not a finite number (--allow-nonfinite keeps it)",
                 module);
        rt_error(lp, CBM_E_RUNTIME, msg);
        lp->err_pos = pos;
        return false;
    }
    if (!lp->nonfinite_warned) {
        lp->nonfinite_warned = true;
        const char *file;
        int line, col;
        cbm__compiler_locate(&ls->comp, (size_t)pos, &file, &line, &col);
        cbm__diag(ls->ctx, CBM_WARNING, file, line, col,
                  "a parameter of %s is not a finite number (kept: --allow-nonfinite; further "
                  "ones are not reported)",
                  module);
    }
    return true;
}

static cbm_status produce(cbm_lsys *ls, int32_t first, int32_t n, double *fr)
{
    lpfg *lp = ls->lp;
    lstr *out = lp->out;
    for (int32_t i = 0; i < n; i++) {
        const lsm *sm = &lp->sms.data[first + i];
        const lmod *m = &lp->mods.data[sm->mod];
        double v[MAXSZ + 1];
        int off = 0, a = 0;
        /* the arguments were converted to the parameter types at compile time, and every value
         * of a static type is representable in it (results are rounded where computed) */
        for (int32_t x = sm->args; x >= 0; x = lp->nodes.data[x].next, a++) {
            ev(ls, x, fr, v + off);
            int sz = tsize(lp, m->ptype[a]);
            for (int q = 0; q < sz; q++)
                if (!isfinite(v[off + q]) && !nonfinite(ls, lp->nodes.data[x].pos, m->name))
                    return lp->err;
            off += sz;
        }
        CBM_TRY(push_mod(ls->ctx, out, m->code, v, m->size));
    }
    return CBM_OK;
}

enum { X_NORMAL, X_BREAK, X_CONTINUE, X_RETURN };

static int exec(cbm_lsys *ls, int32_t ni, double *fr)
{
    lpfg *lp = ls->lp;
    for (; ni >= 0; ni = lp->nodes.data[ni].next) {
        if (lp->err != CBM_OK)
            return X_RETURN;
        const xn *n = &lp->nodes.data[ni];
        lp->at = n->pos;
        double tmp[MAXSZ + 1];
        int r;
        switch (n->op) {
        case S_EXPR:
            ev(ls, n->a, fr, tmp);
            break;
        case S_DECL:
            if (n->a >= 0) {
                ev(ls, n->a, fr, fr + n->slot);
                conv_value(lp, n->type, fr + n->slot);
            } else
                memset(fr + n->slot, 0, (size_t)tsize(lp, n->type) * sizeof(double));
            break;
        case S_BLOCK:
            r = exec(ls, n->a, fr);
            if (r != X_NORMAL)
                return r;
            break;
        case S_IF:
            if (evs(ls, n->a, fr) != 0)
                r = exec(ls, n->b, fr);
            else
                r = n->c >= 0 ? exec(ls, n->c, fr) : X_NORMAL;
            if (r != X_NORMAL)
                return r;
            break;
        case S_WHILE:
        case S_DO:
        case S_FOR: {
            if (n->op == S_FOR && n->a >= 0)
                exec(ls, n->a, fr);
            bool first = n->op == S_DO;
            for (;;) {
                if (!first) {
                    int32_t c = n->op == S_FOR ? n->b : n->a;
                    if (c >= 0 && evs(ls, c, fr) == 0)
                        break;
                }
                first = false;
                if (!spend(lp, true))
                    return X_RETURN;
                r = exec(ls, n->op == S_FOR ? n->d : n->b, fr);
                if (r == X_BREAK)
                    break;
                if (r == X_RETURN)
                    return r;
                if (lp->err != CBM_OK)
                    return X_RETURN;
                if (n->op == S_FOR && n->c >= 0)
                    ev(ls, n->c, fr, tmp);
                if (n->op == S_DO && evs(ls, n->a, fr) == 0)
                    break;
                if (n->op == S_DO)
                    first = true;
            }
            break;
        }
        case S_RETURN:
            if (n->a >= 0) {
                ev(ls, n->a, fr, tmp);
                conv_value(lp, n->type, tmp);
                if (lp->ret)
                    memcpy(lp->ret, tmp, (size_t)tsize(lp, n->type) * sizeof(double));
            }
            return X_RETURN;
        case S_SWITCH: {
            double v = evs(ls, n->a, fr);
            int32_t body = lp->nodes.data[n->b].op == S_BLOCK ? lp->nodes.data[n->b].a : n->b;
            int32_t hit = -1, dflt = -1;
            for (int32_t c = body; c >= 0 && hit < 0; c = lp->nodes.data[c].next) {
                const xn *cn = &lp->nodes.data[c];
                if (cn->op != S_CASE)
                    continue;
                if (cn->a < 0)
                    dflt = c;
                else if (evs(ls, cn->a, fr) == v)
                    hit = c;
            }
            if (hit < 0)
                hit = dflt;
            r = hit >= 0 ? exec(ls, hit, fr) : X_NORMAL;
            if (r == X_RETURN || r == X_CONTINUE)
                return r;
            break;
        }
        case S_BREAK:
            return X_BREAK;
        case S_CONTINUE:
            return X_CONTINUE;
        case S_PRODUCE: {
            cbm_status s = produce(ls, n->a, n->b, fr);
            if (s != CBM_OK)
                rt_error(lp, s, "out of memory");
            if (n->fn) /* nproduce: part of the successor, the body goes on */
                break;
            lp->produced = true;
            return X_RETURN;
        }
        default:
            break;
        }
    }
    return X_NORMAL;
}

/* ---------------------------------------------------------------- derivation */
/* The execution budgets of a step (and of the Start block, global initialisers and axiom). */
static void budgets(cbm_lsys *ls)
{
    const cbm_limits *lim = cbm_context_limits(ls->ctx);
    ls->lp->budget = ls->loop_budget > 0 ? ls->loop_budget : lim->max_loop_iterations;
    ls->lp->ops = lim->max_operations;
}

static cbm_status run_error(cbm_lsys *ls, const char *what)
{
    lpfg *lp = ls->lp;
    cbm_status s = lp->err;
    lp->err = CBM_OK;
    if (lp->err_pos >= 0)
        return cbm__compiler_fail(&ls->comp, s, (size_t)lp->err_pos, "%s: %s", what, lp->errmsg);
    return cbm__fail(ls->ctx, s, "%s: %s", what, lp->errmsg);
}

static cbm_status run_block(cbm_lsys *ls, int which)
{
    static const char *const NAMES[] = {"Start", "StartEach", "EndEach", "End"};
    lpfg *lp = ls->lp;
    if (lp->blocks[which] < 0)
        return CBM_OK;
    lp->sp = (size_t)lp->block_fsize[which];
    lp->ret = NULL;
    exec(ls, lp->blocks[which], lp->stack);
    return lp->err != CBM_OK ? run_error(ls, NAMES[which]) : CBM_OK;
}

/* Tries the productions of `set` on the module at (i, j, k) of src; produced modules go to
 * out. nxt: the partial new string (new context), NULL outside the generative pass. Returns the
 * number of modules the predecessor covers (0: none applied); going Backward the module at i is
 * the last of them, else the first. */
static int try_rewrite(cbm_lsys *ls, const lset *set, const lstr *src, size_t i, size_t j, size_t k,
                       const lstr *nxt, lstr *out)
{
    lpfg *lp = ls->lp;
    int m = lp->bycode[src->sym[i] & 0x7f];
    bool back = nxt && lp->backward;
    /* the productions of the active group first, then those of group 0 (as lpfg) */
    for (int pass = lp->group != 0 ? 0 : 1; pass < 2; pass++)
        for (size_t p = 0; p < set->prods.len; p++) {
            const lprod *pr = &set->prods.data[p];
            int32_t np = pr->pred.n;
            int32_t anchor = back ? np - 1 : 0;
            if (lp->sms.data[pr->pred.first + anchor].mod != m ||
                pr->group != (pass == 0 ? lp->group : 0))
                continue;
            double *fr = lp->stack;
            lp->sp = (size_t)pr->fsize;
            lp->ret = NULL;
            walk first = walk_at(src, i, j, k, 1);
            bool ok = true;
            for (int32_t a = 0; a < anchor && ok; a++) {
                if (first.i == 0)
                    ok = false;
                else
                    w_phys_prev(&first);
            }
            walk w = first;
            for (int32_t a = 0; a < np && ok; a++) {
                const lsm *pm = &lp->sms.data[pr->pred.first + a];
                if (!w_ok(&w) || w_code(&w) != lp->mods.data[pm->mod].code) {
                    ok = false;
                    break;
                }
                bind(ls, &w, pm->args, fr);
                w_phys_next(&w);
            }
            if (!ok)
                continue;
            lp->scan[CX_LC] = first;
            lp->scan[CX_RC] = w;
            memset(&lp->scan[CX_NLC], 0, sizeof(walk));
            memset(&lp->scan[CX_NRC], 0, sizeof(walk));
            if (nxt && !lp->backward)
                lp->scan[CX_NLC] = walk_at(nxt, nxt->n, nxt->npm, nxt->npar, 1);
            else if (nxt)
                lp->scan[CX_NRC] = walk_end(nxt, -1);
            for (int c = 0; c < CX_N && ok; c++)
                if (pr->cx[c].n)
                    ok = ctx_match(ls, c, pr->cx[c].first, pr->cx[c].n, fr);
            if (!ok)
                continue;
            size_t n0 = out->n, npm0 = out->npm, npar0 = out->npar;
            lp->out = out;
            lp->produced = false;
            /* a production applied is an operation: a decomposition that doubles to its
             * maximum depth stops at the budget */
            lp->at = (int32_t)(pr->pos < INT32_MAX ? pr->pos : INT32_MAX);
            if (!spend(lp, false))
                return 0;
            exec(ls, pr->body, fr);
            if (lp->err != CBM_OK)
                return 0;
            if (lp->produced)
                return np;
            out->n = n0, out->npm = npm0, out->npar = npar0;
        }
    return 0;
}

static cbm_status copy_at(cbm_context *ctx, const lstr *src, size_t i, size_t j, size_t k,
                          lstr *dst)
{
    int np = (src->sym[i] & LSYS_PARAM_BIT) ? src->pc[j] : 0;
    /* a string without parameters has no parameter array (NULL + 0 is undefined) */
    return push_mod(ctx, dst, src->sym[i] & 0x7f, np ? (const double *)src->par + k : NULL, np);
}

static cbm_status check_size(cbm_lsys *ls, const lstr *s)
{
    if (s->n > cbm_context_limits(ls->ctx)->max_modules)
        return cbm__fail(ls->ctx, CBM_E_LIMIT, "the string would exceed %zu modules (max_modules)",
                         cbm_context_limits(ls->ctx)->max_modules);
    return CBM_OK;
}

/* Rewrites src into out with a decomposition-like set, recursively to set->depth. */
static cbm_status decompose(cbm_lsys *ls, const lset *set, const lstr *src, lstr *out, int level)
{
    lpfg *lp = ls->lp;
    lstr *tmp = &lp->scratch.data[level];
    size_t j = 0, k = 0;
    /* the interpretation of a model with mechanics records where its modules came from */
    bool track = level == 0 && set == &lp->interp && lp->mech.seg_code >= 0;
    for (size_t i = 0; i < src->n; i++) {
        size_t from = out->n, source = i;
        tmp->n = tmp->npm = tmp->npar = 0;
        int done = level < set->depth ? try_rewrite(ls, set, src, i, j, k, NULL, tmp) : 0;
        if (lp->err != CBM_OK)
            return lp->err;
        for (int extra = 1; extra < done; extra++) { /* further predecessor modules */
            if (src->sym[i] & LSYS_PARAM_BIT)
                k += src->pc[j++];
            i++;
        }
        if (done) {
            if (level + 1 < set->depth)
                CBM_TRY(decompose(ls, set, tmp, out, level + 1));
            else
                CBM_TRY(append_str(ls->ctx, out, tmp, false));
        } else
            CBM_TRY(copy_at(ls->ctx, src, i, j, k, out));
        CBM_TRY(check_size(ls, out));
        for (size_t o = from; track && o < out->n; o++)
            CBM_TRY(CBM_ARRAY_PUSH(ls->ctx, lp->origin, source));
        if (src->sym[i] & LSYS_PARAM_BIT)
            k += src->pc[j++];
    }
    return CBM_OK;
}

static cbm_status decompose_cur(cbm_lsys *ls)
{
    lpfg *lp = ls->lp;
    if (!lp->decomp.present || !lp->decomp.prods.len)
        return CBM_OK;
    ls->next.n = ls->next.npm = ls->next.npar = 0;
    cbm_status s = decompose(ls, &lp->decomp, &ls->cur, &ls->next, 0);
    if (s != CBM_OK)
        return lp->err != CBM_OK ? run_error(ls, "decomposition") : s;
    lstr t = ls->cur;
    ls->cur = ls->next;
    ls->next = t;
    return CBM_OK;
}

static cbm_status generate_pass(cbm_lsys *ls)
{
    lpfg *lp = ls->lp;
    const lstr *src = &ls->cur;
    lstr *nxt = &ls->next;
    lstr *succ = &lp->succ;
    nxt->n = nxt->npm = nxt->npar = 0;
    bool back = lp->backward;
    size_t n = src->n;
    size_t j = back ? src->npm : 0, k = back ? src->npar : 0;
    int cutc = lp->mods.data[find_mod(lp, "Cut", 3)].code;
    int sbc = lp->mods.data[lp->sb].code, ebc = lp->mods.data[lp->eb].code;
    for (size_t c = 0; c < n; c++) {
        size_t i = back ? n - 1 - c : c;
        if (back && (src->sym[i] & LSYS_PARAM_BIT))
            k -= src->pc[--j];
        if (!back && (src->sym[i] & 0x7f) == cutc) { /* Cut: the rest of the branch goes */
            int depth = 0;
            for (; c < n; c++, i++) {
                int sc = src->sym[i] & 0x7f;
                if (sc == sbc)
                    depth++;
                else if (sc == ebc && depth-- == 0)
                    break;
                if (src->sym[i] & LSYS_PARAM_BIT)
                    k += src->pc[j++];
            }
            if (c < n)
                c--; /* the closing EB is copied by the next iteration */
            continue;
        }
        succ->n = succ->npm = succ->npar = 0;
        int done = try_rewrite(ls, &lp->main, src, i, j, k, nxt, succ);
        if (lp->err != CBM_OK)
            return lp->err;
        for (int extra = 1; extra < done; extra++) { /* further predecessor modules */
            if (back) {
                i--;
                if (src->sym[i] & LSYS_PARAM_BIT)
                    k -= src->pc[--j];
            } else {
                if (src->sym[i] & LSYS_PARAM_BIT)
                    k += src->pc[j++];
                i++;
            }
            c++;
        }
        if (done)
            CBM_TRY(append_str(ls->ctx, nxt, succ, back));
        else
            CBM_TRY(copy_at(ls->ctx, src, i, j, k, nxt));
        CBM_TRY(check_size(ls, nxt));
        if (!back && (src->sym[i] & LSYS_PARAM_BIT))
            k += src->pc[j++];
    }
    if (back) { /* the output was built reversed */
        succ->n = succ->npm = succ->npar = 0;
        CBM_TRY(append_str(ls->ctx, succ, nxt, true));
        lstr t = *nxt;
        *nxt = *succ;
        *succ = t;
    }
    lstr t = ls->cur;
    ls->cur = ls->next;
    ls->next = t;
    return CBM_OK;
}

/* The derivation pass, with the bracket tables of the strings its right contexts walk */
static cbm_status generate(cbm_lsys *ls)
{
    lpfg *lp = ls->lp;
    brtab_start(lp, 0, &ls->cur, 1);
    brtab_start(lp, 1, &ls->next, -1);
    cbm_status s = generate_pass(ls);
    lp->brk[0].s = lp->brk[1].s = NULL;
    return s;
}

cbm_status cbm__lpfg_step(cbm_lsys *ls)
{
    lpfg *lp = ls->lp;
    if (ls->steps >= (int)cbm_context_limits(ls->ctx)->max_steps)
        return cbm__fail(ls->ctx, CBM_E_LIMIT, "more than %zu derivation steps (max_steps)",
                         cbm_context_limits(ls->ctx)->max_steps);
    budgets(ls);
    CBM_TRY(run_block(ls, 1));
    lp->rewriting = true;
    cbm_status s = generate(ls);
    if (s == CBM_OK)
        s = decompose_cur(ls);
    lp->rewriting = false;
    if (s != CBM_OK) {
        char what[48];
        snprintf(what, sizeof what, "step %d", ls->steps + 1);
        if (lp->err != CBM_OK)
            return run_error(ls, what);
        if (s == CBM_E_NOMEM && cbm_context_limits(ls->ctx)->max_bytes)
            return cbm__fail(ls->ctx, CBM_E_LIMIT,
                             "%s: the string would exceed the memory limit of %zu bytes", what,
                             cbm_context_limits(ls->ctx)->max_bytes);
        return s;
    }
    ls->steps++;
    ls->homo_valid = false;
    CBM_TRY(run_block(ls, 2));
    if (ls->steps == ls->derivation_length)
        CBM_TRY(run_block(ls, 3));
    return CBM_OK;
}

cbm_status cbm__lpfg_reset(cbm_lsys *ls)
{
    lpfg *lp = ls->lp;
    memset(lp->glob, 0, (size_t)(lp->nglobal + 1) * sizeof(double));
    lp->err = CBM_OK;
    lp->at = lp->err_pos = -1;
    lp->nonfinite_warned = false;
    budgets(ls);
    lp->backward = false;
    lp->group = 0;
    lp->call_depth = 0;
    ls->steps = 0;
    ls->homo_valid = false;
    ls->ev.stopped = false;
    cbm__rand48_seed16(&ls->ev.ran, 0x330E, 0, 0);
    ls->ev.nran_have = 0;
    glibc_srand(lp, 1);
    { /* mechanics settings back to their defaults; the declarations stay */
        cbm__mechlang_free(ls->ctx, &lp->mech);
        cbm__mechlang m = lp->mech;
        cbm__mechlang_init(&lp->mech);
        lp->mech.seg_code = m.seg_code;
        lp->mech.seg_off = m.seg_off;
        memcpy(lp->mech.mass_off, m.mass_off, sizeof m.mass_off);
        memcpy(lp->mech.radius_off, m.radius_off, sizeof m.radius_off);
    }
    ls->cur.n = ls->cur.npm = ls->cur.npar = 0;
    for (size_t g = 0; g < lp->gvars.len; g++) {
        const lgvar *v = &lp->gvars.data[g];
        lp->sp = 0;
        lp->ret = NULL;
        if (v->init >= 0) {
            ev(ls, v->init, lp->stack, lp->glob + v->slot);
            conv_value(lp, v->type, lp->glob + v->slot);
        }
        if (lp->err != CBM_OK)
            return run_error(ls, lp->gvars.data[g].name);
    }
    CBM_TRY(run_block(ls, 0));
    ls->cur.n = ls->cur.npm = ls->cur.npar = 0;
    lp->sp = 0;
    lp->out = &ls->cur;
    cbm_status ps = produce(ls, lp->axiom.first, lp->axiom.n, lp->stack);
    if (lp->err != CBM_OK)
        return run_error(ls, "axiom");
    CBM_TRY(ps);
    return decompose_cur(ls);
}

cbm_status cbm__lpfg_interpretation(cbm_lsys *ls)
{
    lpfg *lp = ls->lp;
    ls->homo_str.n = ls->homo_str.npm = ls->homo_str.npar = 0;
    lp->origin.len = 0;
    budgets(ls);
    cbm_status s;
    if (!lp->interp.present || !lp->interp.prods.len)
        s = append_str(ls->ctx, &ls->homo_str, &ls->cur, false);
    else {
        lp->rewriting = true;
        s = decompose(ls, &lp->interp, &ls->cur, &ls->homo_str, 0);
        lp->rewriting = false;
    }
    if (s != CBM_OK && lp->err != CBM_OK)
        return run_error(ls, "interpretation");
    if (s == CBM_OK)
        ls->homo_valid = true;
    return s;
}

/* ---------------------------------------------------------------- output */
static const double *write_value(FILE *f, const lpfg *lp, int t, const double *v)
{
    if (t == T_INT || t == T_BOOL) {
        fprintf(f, "%lld", cbm__to_ll(v[0]));
        return v + 1;
    }
    if (is_scalar(t)) {
        fprintf(f, "%.9g", v[0]);
        return v + 1;
    }
    putc('{', f);
    int nf = is_vec(t) ? 3 : lp->types.data[t].nf;
    for (int i = 0; i < nf; i++) {
        if (i)
            putc(',', f);
        v = write_value(f, lp, is_vec(t) ? T_DOUBLE : lp->types.data[t].ftype[i], v);
    }
    putc('}', f);
    return v;
}

cbm_status cbm__lpfg_write_str(const cbm_lsys *ls, bool homomorphism, cbm_out *o)
{
    const lpfg *lp = ls->lp;
    cbm_lsys_cursor c;
    cbm_lsys_cursor_begin(ls, homomorphism, &c);
    FILE *f = cbm_out_stream(o);
    while (cbm_lsys_cursor_next(ls, homomorphism, &c)) {
        const lmod *m = &lp->mods.data[lp->bycode[c.symbol & 0x7f]];
        fputs(m->name, f);
        if (m->np) {
            const double *v = c.params;
            for (int i = 0; i < m->np; i++) {
                putc(i ? ',' : '(', f);
                v = write_value(f, lp, m->ptype[i], v);
            }
            putc(')', f);
        }
        putc('\n', f);
    }
    return ferror(f) ? CBM_E_IO : CBM_OK;
}

const char *cbm__lpfg_module_name(const cbm_lsys *ls, int symbol)
{
    if (!ls->lp || symbol <= 0 || symbol > 127 || ls->lp->bycode[symbol] < 0)
        return NULL;
    return ls->lp->mods.data[ls->lp->bycode[symbol]].name;
}

cbm_status cbm__lpfg_mech_fields(const cbm_lsys *ls, bool homomorphism, const double ***out,
                                 size_t *n)
{
    const lpfg *lp = ls->lp;
    *out = NULL;
    *n = 0;
    if (!lp || lp->mech.seg_code < 0 || ls->cur.f32)
        return CBM_OK;
    /* the MechSegment of every module of the string, NULL for other modules */
    size_t nc = ls->cur.n;
    const double **seg = cbm__calloc(ls->ctx, nc ? nc : 1, sizeof *seg);
    if (!seg)
        return CBM_E_NOMEM;
    size_t j = 0, k = 0;
    const double *par = ls->cur.par;
    for (size_t i = 0; i < nc; i++) {
        int np = (ls->cur.sym[i] & LSYS_PARAM_BIT) ? ls->cur.pc[j++] : 0;
        if ((ls->cur.sym[i] & 0x7f) == lp->mech.seg_code && np >= lp->mech.seg_off + MS_SIZE)
            seg[i] = par + k + lp->mech.seg_off;
        k += (size_t)np;
    }
    if (!homomorphism || !lp->origin.len) {
        *out = seg;
        *n = nc;
        return CBM_OK;
    }
    /* through the interpretation's origins */
    size_t nh = lp->origin.len;
    const double **img = cbm__calloc(ls->ctx, nh, sizeof *img);
    if (!img) {
        cbm__free(ls->ctx, (void *)seg, (nc ? nc : 1) * sizeof *seg);
        return CBM_E_NOMEM;
    }
    for (size_t i = 0; i < nh; i++)
        img[i] = lp->origin.data[i] < nc ? seg[lp->origin.data[i]] : NULL;
    cbm__free(ls->ctx, (void *)seg, (nc ? nc : 1) * sizeof *seg);
    *out = img;
    *n = nh;
    return CBM_OK;
}

void cbm__lpfg_describe(const cbm_lsys *ls, size_t *prods, size_t *decomp, size_t *interp,
                        int *decomp_depth, int *interp_depth, size_t *modules)
{
    const lpfg *lp = ls->lp;
    *prods = lp->main.prods.len;
    *decomp = lp->decomp.present ? lp->decomp.prods.len : 0;
    *interp = lp->interp.present ? lp->interp.prods.len : 0;
    *decomp_depth = lp->decomp.present ? lp->decomp.depth : 0;
    *interp_depth = lp->interp.present ? lp->interp.depth : 0;
    *modules = lp->mods.len;
}

bool cbm_lsys_has_mechanics(const cbm_lsys *ls)
{
    return ls && ls->lp && ls->lp->mech.seg_code >= 0;
}

cbm_status cbm_lsys_mech_plant(cbm_lsys *ls, cbm_plant **out)
{
    if (!ls || !out)
        return CBM_E_INVALID;
    *out = NULL;
    if (!cbm_lsys_has_mechanics(ls))
        return cbm__fail(
            ls->ctx, CBM_E_INVALID,
            "the model declares no mechanical segments (`mechanics:` in an L+C model)");
    char msg[256];
    cbm_status s = cbm__mechlang_plant(ls->ctx, &ls->lp->mech, &ls->cur, out, msg, sizeof msg);
    if (s != CBM_OK)
        return cbm__fail(ls->ctx, s, "%s", msg);
    return CBM_OK;
}

/* ---------------------------------------------------------------- load / free */
bool cbm__lpfg_detect(const cbm__pp *pp)
{
    if (pp->lpfg_lib)
        return true;
    const char *t = pp->text.data;
    for (const char *p = t; (p = strstr(p, "produce")) != NULL; p += 7)
        if ((p == t || !isid((unsigned char)p[-1])) && !isid((unsigned char)p[7]))
            return true;
    for (const char *p = t; (p = strstr(p, "module")) != NULL; p += 6)
        if ((p == t || p[-1] == '\n') && (p[6] == ' ' || p[6] == '\t'))
            return true;
    return false;
}

static void free_set(cbm_context *ctx, lset *s)
{
    CBM_ARRAY_FREE(ctx, s->prods);
}

void cbm__lpfg_mech_keep(cbm_lsys *ls, bool keep)
{
    if (!ls->lp)
        return;
    if (!keep)
        cbm__mechlang_free(ls->ctx, &ls->lp->mech);
    ls->lp->mech.keep = keep;
}

void cbm__lpfg_free(cbm_lsys *ls)
{
    lpfg *lp = ls->lp;
    if (!lp)
        return;
    cbm_context *ctx = ls->ctx;
    brtab_free(ctx, &lp->brk[0]);
    brtab_free(ctx, &lp->brk[1]);
    for (size_t i = 0; i < lp->types.len; i++) {
        cbm__strfree(ctx, lp->types.data[i].name);
        for (int f = 0; f < lp->types.data[i].nf; f++)
            cbm__strfree(ctx, lp->types.data[i].fname[f]);
    }
    CBM_ARRAY_FREE(ctx, lp->types);
    for (size_t i = 0; i < lp->mods.len; i++)
        cbm__strfree(ctx, lp->mods.data[i].name);
    CBM_ARRAY_FREE(ctx, lp->mods);
    for (size_t i = 0; i < lp->funcs.len; i++)
        cbm__strfree(ctx, lp->funcs.data[i].name);
    CBM_ARRAY_FREE(ctx, lp->funcs);
    for (size_t i = 0; i < lp->gvars.len; i++)
        cbm__strfree(ctx, lp->gvars.data[i].name);
    CBM_ARRAY_FREE(ctx, lp->gvars);
    for (size_t i = 0; i < lp->funcnames.len; i++)
        cbm__strfree(ctx, lp->funcnames.data[i]);
    CBM_ARRAY_FREE(ctx, lp->funcnames);
    CBM_ARRAY_FREE(ctx, lp->funcids);
    cbm__mechlang_free(ctx, &lp->mech);
    CBM_ARRAY_FREE(ctx, lp->nodes);
    CBM_ARRAY_FREE(ctx, lp->origin);
    CBM_ARRAY_FREE(ctx, lp->sms);
    free_set(ctx, &lp->main);
    free_set(ctx, &lp->decomp);
    free_set(ctx, &lp->interp);
    cbm__free(ctx, lp->glob, (size_t)(lp->nglobal + 1) * sizeof(double));
    cbm__free(ctx, lp->stack, lp->stack_cap * sizeof(double));
    cbm__lstr_free(ctx, &lp->succ);
    for (size_t i = 0; i < lp->scratch.len; i++)
        cbm__lstr_free(ctx, &lp->scratch.data[i]);
    CBM_ARRAY_FREE(ctx, lp->scratch);
    cbm__free(ctx, lp, sizeof *lp);
    ls->lp = NULL;
}

static int eval_depth(cbm_lsys *ls, lset *s, int dflt)
{
    if (s->depth <= -2) {
        int32_t e = -2 - s->depth;
        ls->lp->sp = 0;
        double v = evs(ls, e, ls->lp->stack);
        return !(v >= 0) ? 0 : v > 1e6 ? 1000000 : (int)v; /* NaN: 0 */
    }
    return dflt;
}

cbm_status cbm__lpfg_parse(cbm_lsys *ls, const cbm__pp *pp)
{
    cbm_context *ctx = ls->ctx;
    lpfg *lp = cbm__calloc(ctx, 1, sizeof *lp);
    if (!lp)
        return CBM_E_NOMEM;
    ls->lp = lp;
    /* parameters are stored as doubles; float parameters are rounded to float32 by their type */
    ls->cur.f32 = ls->next.f32 = ls->homo_str.f32 = ls->succ.f32 = false;
    ls->float32 = false;
    for (int i = 0; i < 4; i++)
        lp->blocks[i] = -1;
    lp->dlen_expr = -1;
    lc L;
    memset(&L, 0, sizeof L);
    L.ls = ls;
    L.lp = lp;
    L.c = &ls->comp;
    L.t = pp->text.data;
    cbm_status s = setup_builtins(&L);
    if (s == CBM_OK) {
        parse_top(&L);
        s = ls->comp.status;
    }
    CBM_ARRAY_FREE(ctx, L.vars);
    if (s == CBM_OK && ls->comp.errors)
        s = CBM_E_SYNTAX;
    if (s == CBM_E_SYNTAX)
        return cbm__fail(ctx, s, "%zu error%s in the model", ls->comp.errors,
                         ls->comp.errors == 1 ? "" : "s");
    if (s != CBM_OK)
        return s;
    for (size_t i = 0; i < lp->funcnames.len; i++) { /* by default the order of first use */
        int id = (int)i + 1;
        CBM_TRY(CBM_ARRAY_PUSH(ctx, lp->funcids, id));
    }
    lp->stack_cap = 1u << 16;
    lp->stack = cbm__calloc(ctx, lp->stack_cap, sizeof(double));
    lp->glob = cbm__calloc(ctx, (size_t)lp->nglobal + 1, sizeof(double));
    if (!lp->stack || !lp->glob)
        return CBM_E_NOMEM;
    for (size_t i = 0; i < lp->main.prods.len; i++)
        if ((size_t)lp->main.prods.data[i].fsize + 1 > lp->stack_cap)
            return cbm__fail(ctx, CBM_E_LIMIT, "a production has too many local variables");
    int maxd = cbm_context_limits(ctx)->max_decomp_depth;
    lp->decomp.depth = eval_depth(ls, &lp->decomp, 1);
    lp->interp.depth = eval_depth(ls, &lp->interp, 1);
    if (lp->decomp.depth > maxd || lp->interp.depth > maxd)
        return cbm__fail(ctx, CBM_E_LIMIT, "maximum depth exceeds the limit of %d", maxd);
    int depth = lp->decomp.depth > lp->interp.depth ? lp->decomp.depth : lp->interp.depth;
    for (int i = 0; i <= depth; i++) {
        lstr z;
        memset(&z, 0, sizeof z);
        CBM_TRY(CBM_ARRAY_PUSH(ctx, lp->scratch, z));
    }
    ls->derivation_length = 0;
    if (lp->dlen_expr >= 0) {
        lp->sp = 0;
        double v = evs(ls, lp->dlen_expr, lp->stack);
        ls->derivation_length = v < 0 ? 0 : v > 1e9 ? 1000000000 : (int)v;
    }
    return CBM_OK;
}

size_t cbm__lpfg_func_names(const cbm_lsys *ls, const char *const **names)
{
    *names = (const char *const *)ls->lp->funcnames.data;
    return ls->lp->funcnames.len;
}

cbm_status cbm__lpfg_set_func_ids(cbm_lsys *ls, const int *ids, size_t n)
{
    lpfg *lp = ls->lp;
    if (n != lp->funcnames.len || (n && !ids))
        return CBM_E_INVALID;
    for (size_t i = 0; i < n; i++)
        lp->funcids.data[i] = ids[i];
    return CBM_OK;
}

bool cbm__lpfg_has_interpretation(const cbm_lsys *ls)
{
    return ls->lp->interp.present && ls->lp->interp.prods.len > 0;
}
