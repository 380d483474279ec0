/* The L+C dialect's compiled model (lc_parse.c builds it; src/lsys runs it).
 *
 * A model in this dialect declares its modules with typed parameters (`module A(int, float);`),
 * may declare structs, globals and functions, and writes productions whose successors are
 * produced by C-like bodies (`A(t) : { if (t > 0) produce B(t - 1); }`), after Karwowski and
 * Prusinkiewicz's L+C (2003) as implemented by lpfg. Module names are mapped to the one-byte
 * symbols of the packed module string (turtle modules to the cpfg turtle characters, `SB`/`EB`
 * to `[`/`]`), and every parameter, including struct and vector fields, is one packed double, so
 * a struct parameter costs no allocation.
 *
 * Values are typed at compile time (int, float, double, bool, V3f, V3d, structs); a value of
 * any type is a run of doubles (its scalar fields in declaration order). Arithmetic follows C's
 * usual conversions: int operations truncate, float results are rounded to float32 after each
 * operation (as C does with FLT_EVAL_METHOD 0), so parameters match lpfg's float32 bit for bit.
 * The conversions are here (static inline) because the compiler folds with them and the
 * evaluator applies them.
 */
#ifndef CBM_LANG_LC_H
#define CBM_LANG_LC_H

#include "lang/lang.h"
#include "lang/mechsegment.h"

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
    T_MSEG, /* MechSegment (lsys/mechlang_internal.h) */
    T_NBUILTIN
};
#define MAXF   16 /* parameters per module or function */
#define MAXFLD 64 /* fields per struct (the listing's InternodeData has 35) */
#define MAXSZ  255

typedef struct lc_type {
    char *name;
    int size;
    int nfields; /* fields: their types, offsets (doubles) and names below */
    int ftype[MAXFLD];
    int foff[MAXFLD];
    char *fname[MAXFLD];
} lc_type;

typedef struct lc_module {
    char *name;
    uint8_t code;
    int nparams, size; /* parameters, and their doubles */
    int ptype[MAXF];
} lc_module;

/* The kinds of node (lc_node.op): expressions N_, statements S_. A node's children are indices
 * in the node array (-1: none), in the order the construct reads: the operands of an operator;
 * the condition, `then` and `else` of N_COND and S_IF; the condition and body of S_WHILE and
 * S_DO; init, condition, step and body of S_FOR (child1 .. child4); the value of S_EXPR,
 * S_RETURN and a declaration's initialiser; the others below. */
enum {
    N_NUM,
    N_LOCAL,
    N_GLOBAL,
    N_FIELD, /* child1: the base value, slot: the field's offset */
    N_NEG,
    N_NOT,
    N_CAST,
    N_BIN,
    N_AND,
    N_OR,
    N_COND,
    N_ASSIGN, /* child1: the lvalue, child2: the value, fn: the operator (0 for =) */
    N_INCDEC, /* child1: the lvalue, fn: 0 ++x, 1 --x, 2 x++, 3 x-- */
    N_CALLB,
    N_CALLU,
    N_CTOR, /* child1: the chain of arguments, the fields of its type */
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
    S_SWITCH, /* child1: the value, child2: the body */
    S_CASE,   /* child1: the label's value, -1 for default */
    S_NOP
};

enum { B_ADD, B_SUB, B_MUL, B_DIV, B_REM, B_LT, B_GT, B_LE, B_GE, B_EQ, B_NE };

typedef struct lc_node {
    uint8_t op, fn;
    int16_t type;
    int32_t child1, child2, child3, child4, next;
    int32_t slot;
    int32_t pos;  /* text offset where the parser made it, for runtime messages */
    double value; /* the number of N_NUM */
} lc_node;

/* a successor or context pattern: modules with their argument chains */
typedef struct lc_modref {
    int mod;
    int32_t args; /* chain of expressions (successor) or of lvalues (pattern) */
} lc_modref;

typedef struct lc_pattern {
    int32_t first, n; /* in lp->sms */
} lc_pattern;

/* The contexts of a production, by index in lc_production.context: the left context (`<`), the
 * new left context (`<<`, matched on the string being produced), the new right context (`>>`)
 * and the right context (`>`). */
enum { LC_CTX_LEFT, LC_CTX_NEW_LEFT, LC_CTX_NEW_RIGHT, LC_CTX_RIGHT, LC_CTX_N };

typedef struct lc_production {
    int mod;                      /* predecessor */
    lc_pattern pred;              /* strict predecessor: one module or several adjacent ones */
    lc_pattern context[LC_CTX_N]; /* contexts (n = 0: none); formals in args */
    int32_t body;
    int fsize; /* frame doubles */
    int group;
    size_t pos;
} lc_production;

typedef struct lc_function {
    char *name;
    int ret_type; /* the type of the result (T_VOID: none) */
    int nparams;
    int ptype[MAXF];
    bool pref[MAXF]; /* reference parameter (T& x): copied back to the argument */
    int32_t body;
    int fsize;
    size_t pos;
} lc_function;

typedef struct lc_rules {
    CBM_ARRAY(lc_production) prods;
    int depth;
    bool present;
} lc_rules;

typedef struct lc_global {
    char *name;
    int type, slot;
    int32_t init;
} lc_global;

/* The mechanics declarations of a model (`mechanics: M;`, `mass: A, B;`); the runtime copies
 * them into its mechanics settings (lsys/mechlang_internal.h). */
typedef struct lc_mech_decl {
    int seg_code;        /* module code carrying the MechSegment, -1: none declared */
    int seg_off;         /* double offset of its MechSegment parameter */
    int mass_off[128];   /* per module code: double offset of the mass parameter, -1: not a mass */
    int radius_off[128]; /* per code: double offset of the contact radius (m), -1: none */
    /* `light: Leaf(area, light)`: per code the offsets of the leaf's area (m^2) and of the
     * parameter Light() writes (-1: not a leaf; lsys/lightlang.c) */
    int light_area_off[128], light_out_off[128];
} lc_mech_decl;

/* A compiled model: types, modules, the node array of every expression and statement, the
 * rule sets and the blocks. Immutable after cbm__lc_compile except funcids. */
typedef struct lc_model {
    CBM_ARRAY(lc_type) types;
    CBM_ARRAY(lc_module) mods;
    int16_t bycode[128];
    CBM_ARRAY(lc_node) nodes;
    CBM_ARRAY(lc_modref) sms;
    CBM_ARRAY(lc_function) funcs;
    CBM_ARRAY(lc_global) gvars;
    CBM_ARRAY(char *) funcnames;
    CBM_ARRAY(int) funcids; /* the function-set id of each name (cbm_lsys_set_func_ids) */
    int nglobal;            /* doubles */
    lc_rules main, decomp, interp;
    lc_pattern axiom;
    int32_t blocks[4]; /* Start, StartEach, EndEach, End */
    int block_fsize[4];
    int32_t dlen_expr;
    bool considered[128];
    int sb_module, eb_module; /* module indices of SB, EB */
    lc_mech_decl mech_decl;
} lc_model;

static inline int lc_type_size(const lc_model *lp, int t)
{
    return lp->types.data[t].size;
}

static inline bool lc_is_scalar(int t)
{
    return t >= T_INT && t <= T_BOOL;
}

static inline bool lc_is_vec(int t)
{
    return t == T_V3F || t == T_V3D;
}

/* A value converted to a C int as lpfg's compiled C does on x86-64: truncated toward zero, and
 * the "integer indefinite" INT_MIN for NaN and values outside the 32-bit range (cvttsd2si). */
static inline double lc_c_int(double v)
{
    if (!(v > -2147483649.0 && v < 2147483648.0))
        return -2147483648.0;
    return (double)(int32_t)v;
}

/* The 32-bit two's-complement wrap of an exact integer result (int arithmetic that overflows). */
static inline double lc_wrap_int(long long r)
{
    return (double)(int32_t)(uint32_t)(unsigned long long)r;
}

static inline double lc_conv_scalar(int t, double v)
{
    switch (t) {
    case T_INT:
        return lc_c_int(v);
    case T_FLOAT:
        return (double)(float)v;
    case T_BOOL:
        return v != 0;
    default:
        return v;
    }
}

/* Rounds a value of type t in place (float fields to float32, ints truncated). */
static inline void lc_conv_value(const lc_model *lp, int t, double *v)
{
    if (lc_is_scalar(t)) {
        v[0] = lc_conv_scalar(t, v[0]);
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
    const lc_type *ty = &lp->types.data[t];
    for (int f = 0; f < ty->nfields; f++)
        lc_conv_value(lp, ty->ftype[f], v + ty->foff[f]);
}

static inline int lc_arith_type(int a, int b)
{
    if (a == T_DOUBLE || b == T_DOUBLE)
        return T_DOUBLE;
    if (a == T_FLOAT || b == T_FLOAT)
        return T_FLOAT;
    return T_INT;
}

/// Whether a preprocessed text is written in the L+C dialect (a library header, `produce`, or a
/// line starting with `module`).
bool cbm__lc_detect(const cbm__pp *pp);
/// Compiles the preprocessed text (c's text) into m (zeroed by the caller). Errors are reported
/// through c and counted in c->errors; the status is CBM_OK unless memory or limits failed.
cbm_status cbm__lc_compile(cbm__compiler *c, const char *text, lc_model *m);
void cbm__lc_model_free(cbm_context *ctx, lc_model *m);
/// Index of the module named s[0..n), -1 if none.
int cbm__lc_find_module(const lc_model *m, const char *s, size_t n);

#endif
