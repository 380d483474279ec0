/* The language of the models, both dialects (src/lang/):
 *
 *   pp.c          the preprocessor: a model file becomes one text with C comments removed,
 *                 #include files inserted and #define macros (with arguments) expanded, plus a
 *                 line map back to the original files;
 *   compiler.c    the cursor over that text shared by both parsers, and file:line:col messages;
 *   expr_parse.c  cpfg-dialect expressions and statement blocks into a flat node array;
 *   cpfg_code.c   their evaluation: compiled to the register code of lc_code.h and run by its
 *                 loop, the one evaluator of both dialects;
 *   lc.h, lc_parse.c  the L+C dialect's typed front end and its compiled model (run by
 *                 lsys/lpfg.c); mechsegment.h the layout of its built-in MechSegment;
 *   lc_code.h, lc_code.c  the register code both dialects compile to, the L+C compiler to it
 *                 and the loop that runs it (cbm__lc_run);
 *   lc_native.c   that code translated to C, compiled by the system's cc and cached;
 *   builtins.c, builtins.h  the one table of built-in functions of both dialects, and the math
 *                 ones;
 *   random.c, random.h  the random generators and distributions of both dialects;
 *   format.c      printf of models.
 */
#ifndef CBM_LANG_H
#define CBM_LANG_H

#include "core/core.h"
#include "lang/builtins.h"
#include "lang/random.h"

/* ---- preprocessor ---- */
typedef struct cbm__pp_line {
    int file;   /* index into files */
    int line;   /* 1-based line in that file */
    int define; /* the line expands a -D NAME=VALUE: its text's index in files, else -1 */
} cbm__pp_line;

typedef struct cbm__pp {
    cbm_context *ctx;
    CBM_ARRAY(char) text;          /* NUL-terminated expanded text */
    CBM_ARRAY(cbm__pp_line) lines; /* one entry per line of text */
    CBM_ARRAY(char *) files;       /* file names (owned) */
    size_t errors;
    bool lpfg_lib; /* a built-in library header (<lpfgall.h>, ...) was included */
} cbm__pp;

/// Preprocesses `text` (or the file `path` when text is NULL). defines: "NAME=VALUE" strings
/// that override the file's own #define of the same name. Errors are reported as diagnostics
/// and counted in pp->errors; the status is CBM_OK unless memory or limits failed.
cbm_status cbm__pp_run(cbm_context *ctx, const char *path, const char *text,
                       const char *const *defines, size_t ndefines, cbm__pp *pp);
void cbm__pp_free(cbm__pp *pp);

/* ---- expressions ---- */
typedef enum cbm__op {
    OP_NUM,
    OP_PARAM,
    OP_GLOBAL,
    OP_ARRAY, /* value, formal parameter, global, array element */
    OP_NEG,
    OP_NOT,
    OP_ADD,
    OP_SUB,
    OP_MUL,
    OP_DIV,
    OP_REM,
    OP_POW,
    OP_LT,
    OP_GT,
    OP_LE,
    OP_GE,
    OP_EQ,
    OP_NE,
    OP_AND,
    OP_OR,
    OP_COND,
    OP_COMMA,
    OP_CALL,
    /* statements */
    OP_ASSIGN,
    OP_ASSIGN_PARAM,
    OP_ASSIGN_ARRAY,
    OP_IF,
    OP_WHILE,
    OP_DO,
    OP_SEQ,
    OP_NOP,
    OP_STR /* a string literal (printf's arguments only): slot is its offset in strings */
} cbm__op;

/* One node. Its children are indices into the node array (-1: none), in the order the
 * construct reads: child1 and child2 the operands of an operator; child1, child2, child3 the
 * condition, the `then` and the `else` of OP_COND and OP_IF; child1 the condition and child2
 * the body of OP_WHILE and OP_DO; child1 the value and child2 the index of an assignment;
 * child1 the first argument of OP_CALL and the first index of OP_ARRAY (the others follow as a
 * chain through `next`); child1 the first statement of OP_SEQ. */
typedef struct cbm__node {
    uint8_t op, fn;                 /* fn: the built-in of OP_CALL (FN_..., builtins.h) */
    int32_t child1, child2, child3; /* above */
    int32_t next;                   /* next argument or next statement */
    int32_t slot;                   /* parameter index, global or array index */
    double value;                   /* the number of OP_NUM */
} cbm__node;

typedef struct cbm__array {
    char *name;
    int ndims;
    int dims[4];
    double *data;
    size_t count;
} cbm__array;

typedef struct cbm__ecode cbm__ecode; /* cpfg_code.c: the register code of the roots run */

/* The evaluation environment shared by a model. */
typedef struct cbm__eval {
    cbm_context *ctx;
    const cbm__node *nodes;
    const char *strings; /* the compiler's string literals (printf) */
    double *globals;
    cbm__array *arrays;
    double *params;    /* formal parameters of the production being applied (assignable) */
    cbm__random rnd;   /* erand48 stream of ran, nran, bran, biran (cpfg main_xsubi) */
    long while_budget; /* iterations left for while loops in this evaluation */
    double (*func)(void *ud, int id, double x);
    void *func_ud;
    cbm_status error; /* first runtime error */
    const char *error_msg;
    int32_t error_node; /* node of the first runtime error, -1: none known */
    bool stopped;
    cbm__ecode *code; /* compiled on first use of each root; cbm__eval_free releases it */
} cbm__eval;

/* ---- the compiler: a cursor over the preprocessed text plus the node array ---- */
typedef struct cbm__compiler {
    cbm_context *ctx;
    const cbm__pp *pp;
    const char *text;
    size_t pos;
    CBM_ARRAY(size_t) line_start; /* offset of each line of text */
    /* the preprocessor's map back to the files, taken over from it so that runtime errors
     * (after the preprocessed text is gone) still name file:line:col */
    CBM_ARRAY(cbm__pp_line) map;
    CBM_ARRAY(char *) files;
    CBM_ARRAY(cbm__node) nodes;
    CBM_ARRAY(int32_t) node_pos;   /* text offset of each node (where it starts), for messages */
    CBM_ARRAY(char *) globals;     /* global variable names */
    CBM_ARRAY(int32_t) global_use; /* first use (a position) of a global that is only read */
    CBM_ARRAY(uint8_t) global_set; /* the global is assigned somewhere */
    CBM_ARRAY(cbm__array) arrays;
    CBM_ARRAY(char) strings;    /* NUL-terminated string literals, one after the other */
    const char *const *formals; /* names of the production's formal parameters */
    const size_t *formal_len;
    int nformals;
    int dialect; /* builtins known (CBM__CPFG ...); 0 = the cpfg dialect's */
    int depth;
    size_t errors;
    bool fatal; /* out of memory or too many errors: stop parsing */
    cbm_status status;
} cbm__compiler;

/// Takes over the preprocessor's line map and file names (pp keeps its text).
cbm_status cbm__compiler_init(cbm__compiler *c, cbm_context *ctx, cbm__pp *pp);
void cbm__compiler_free(cbm__compiler *c);
/// File, line and column of a text offset (file NULL when unknown).
void cbm__compiler_locate(const cbm__compiler *c, size_t pos, const char **file, int *line,
                          int *col);
/// Text offset of a node, 0 when unknown.
size_t cbm__node_pos(const cbm__compiler *c, int32_t node);
/// Reports a runtime error at a text offset ("file:line:col: error: what: msg") and returns s.
cbm_status cbm__compiler_fail(const cbm__compiler *c, cbm_status s, size_t pos, const char *fmt,
                              ...) CBM_PRINTF(4, 5);
/// Error at a text offset, "file:line:col: error: ...".
void cbm__cerr(cbm__compiler *c, size_t pos, const char *fmt, ...) CBM_PRINTF(3, 4);
/// Skips blanks; newlines too when `nl` (inside parentheses or braces), and always a newline
/// followed by a tab (cpfg's continuation line).
void cbm__skip(cbm__compiler *c, bool nl);
/// Expression: returns a node index, -1 after an error (reported).
int32_t cbm__parse_expr(cbm__compiler *c, bool nl);
/// `{ statements }` starting at '{': returns the first statement node (chain), -1 if empty or on
/// error (then *ok is false).
int32_t cbm__parse_block(cbm__compiler *c, bool *ok);
/// Declares `array name[d1][d2] = {...};` statements of a define: block (at '{').
bool cbm__parse_define_block(cbm__compiler *c);
/// Checks that every global that is read is assigned somewhere (reports the rest).
void cbm__check_globals(cbm__compiler *c);
int32_t cbm__node_num(cbm__compiler *c, double v);
/// Constant value of a node if it has no variables and no calls.
bool cbm__node_const(const cbm__compiler *c, int32_t n, double *v);

/// The value of expression n (a statement chain runs and gives 0). The root is compiled to the
/// register code (lang/lc_code.h) on its first evaluation and run by cbm__lc_run; a runtime
/// error sets e->error, e->error_msg and e->error_node.
double cbm__eval_expr(cbm__eval *e, int32_t n);
/// Releases the compiled code of an environment (e->code; nothing else of e).
void cbm__eval_free(cbm__eval *e);
/// Roots compiled (expressions and statement chains), their instructions, and runs so far.
void cbm__eval_stats(const cbm__eval *e, size_t *roots, size_t *ins, size_t *runs);

/// A value converted to an integer without undefined behaviour: NaN gives 0, values beyond
/// +-2^62 are clamped, the rest truncated toward zero as C does.
static inline long long cbm__to_ll(double v)
{
    if (!(v == v))
        return 0;
    if (v > 4.6e18)
        return 4600000000000000000LL;
    if (v < -4.6e18)
        return -4600000000000000000LL;
    return (long long)v;
}
/// Runs the statement chain n (a bare expression ends it), compiled as cbm__eval_expr's roots;
/// nothing runs while e->error is set.
void cbm__eval_stmt(cbm__eval *e, int32_t n);

/* ---- printf of models (format.c) ---- */
enum { CBM__FMT_INT, CBM__FMT_UINT, CBM__FMT_REAL, CBM__FMT_CHAR, CBM__FMT_STR };
#define CBM__FMT_MAX_ARGS 16
/// Reads the string literal at c->pos (on its opening quote), decodes it into c->strings and
/// gives its offset there; false after an error (reported).
bool cbm__string_lit(cbm__compiler *c, size_t *off);
/// Decodes the body of a C string literal (escapes \n \t \xHH \ooo ...) into out (at least n
/// bytes); returns the decoded length.
size_t cbm__unescape(const char *s, size_t n, char *out);
/// Checks a decoded printf format: writes the kind (CBM__FMT_*) of each conversion and returns
/// their number, or -1 with a message in err.
int cbm__fmt_scan(const char *fmt, uint8_t *kinds, int max, char *err, size_t errn);
typedef struct cbm__fmt_arg {
    double v;
    const char *s; /* the argument of a %s conversion */
} cbm__fmt_arg;
/// Formats a checked format with its arguments and sends the text to the context's output.
void cbm__fmt_print(cbm_context *ctx, const char *fmt, const cbm__fmt_arg *args, int nargs);

#endif
