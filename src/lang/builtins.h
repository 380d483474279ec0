/* The built-in functions of both dialects: one table (builtins.c) of names, arities and the
 * dialects that know them, and the evaluation of the pure math functions.
 *
 * To add a built-in: an FN_ value here (mechanics ones between FN_EQUILIBRIUM and
 * FN_REACTIONBOUND), a row of the table, and its evaluation: in cbm__builtin_math when it is a
 * function of its numbers alone, else in the evaluator of the dialect (lang/cpfg_code.c,
 * lsys/lpfg.c) and, for the L+C dialect, its argument and result types in lang/lc_parse.c
 * (call_expr).
 */
#ifndef CBM_LANG_BUILTINS_H
#define CBM_LANG_BUILTINS_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>

typedef enum cbm__fn {
    /* math: cbm__builtin_math */
    FN_SIN,
    FN_COS,
    FN_TAN,
    FN_ASIN,
    FN_ACOS,
    FN_ATAN,
    FN_ATAN2,
    FN_EXP,
    FN_LOG,
    FN_LOG10,
    FN_POW,
    FN_FLOOR,
    FN_CEIL,
    FN_SIGN,
    FN_SQRT,
    FN_TRUNC,
    FN_FABS,
    FN_FMOD,
    FN_MIN,
    FN_MAX,
    FN_MATH_END, /* not a function: the end of the math ones */
    /* growth functions of forestry (tree parameter formulas only): cbm__builtin_growth, the
     * growth y(t) and its increment y'(t) of each, arguments (t, a, b, c) */
    FN_HOSSFELD,
    FN_HOSSFELD_INC,
    FN_GOMPERTZ,
    FN_GOMPERTZ_INC,
    FN_LOGISTIC,
    FN_LOGISTIC_INC,
    FN_MONOMOLECULAR,
    FN_MONOMOLECULAR_INC,
    FN_BERTALANFFY, /* (t, a, b) */
    FN_BERTALANFFY_INC,
    FN_RICHARDS,
    FN_RICHARDS_INC,
    FN_LEVAKOVIC,
    FN_LEVAKOVIC_INC,
    FN_KORF,
    FN_KORF_INC,
    FN_GROWTH_END, /* not a function: the end of the growth ones */
    /* random numbers (lang/random.h) */
    FN_RAN,
    FN_NRAN,
    FN_BRAN,
    FN_BIRAN,
    FN_SRAND,
    FN_RAND,
    FN_DRAND,
    /* the environment */
    FN_FUNC,
    FN_PRINTF,
    FN_STOP,
    /* L+C: derivation control and vectors */
    FN_FORWARD,
    FN_BACKWARD,
    FN_USEGROUP,
    FN_CURGROUP,
    FN_LENGTH,
    FN_NORMALIZE,
    FN_DOT,
    FN_CROSS,
    FN_MAKEQ,
    FN_VECROT,
    FN_TOLOCAL,
    FN_TOWORLD,
    /* L+C: mechanics (lsys/mechlang.c), FN_EQUILIBRIUM .. FN_REACTIONBOUND */
    FN_EQUILIBRIUM,
    FN_ADDRINGS,
    FN_AGEWOOD,
    FN_BREAK,
    FN_STABILITY,
    FN_FREQUENCY,
    FN_SWAY,
    FN_SWAYMODES,
    FN_LIGHT, /* the light of the declared leaves (lsys/lightlang.c) */
    FN_GRAVITY,
    FN_GROUND,
    FN_CONTACT,
    FN_TROPISM,
    FN_PIPEMODEL,
    FN_WOOD,
    FN_RINGRATE,
    FN_SOLVER,
    FN_SOLVERMETHOD,
    FN_APPROXLOAD,
    FN_SOLVERTHREADS,
    FN_REACTION,
    FN_REACTIONBOUND,
    FN_NONE, /* a reserved name (RAND_MAX is a constant) */
    FN_COUNT
} cbm__fn;

/* dialect bits; CBM__TREE: the formulas of tree parameter files (src/tree/ober_*.c), which are
 * cpfg-dialect expressions that also know the growth functions and pow, min, max, abs, fmod */
enum { CBM__CPFG = 1, CBM__LC = 2, CBM__TREE = 4 };

typedef struct cbm__builtin {
    const char *name;
    cbm__fn fn;
    int arity;    /* -1: any */
    int dialects; /* CBM__CPFG | CBM__LC */
} cbm__builtin;

/// The built-in named s[0..n) in a dialect (CBM__CPFG or CBM__LC), NULL if none.
const cbm__builtin *cbm__builtin_find(const char *s, size_t n, int dialect);

/// The value of a math built-in (fn < FN_MATH_END) at a, b (b unused by one-argument ones).
/// degrees: the cpfg dialect's trigonometry, which takes and gives degrees.
static inline double cbm__builtin_math(int fn, double a, double b, bool degrees)
{
    const double deg = degrees ? 3.14159265358979323846 / 180.0 : 1.0;
    switch ((cbm__fn)fn) {
    case FN_SIN:
        return degrees ? sin(a * deg) : sin(a);
    case FN_COS:
        return degrees ? cos(a * deg) : cos(a);
    case FN_TAN:
        return degrees ? tan(a * deg) : tan(a);
    case FN_ASIN:
        return degrees ? asin(a) / deg : asin(a);
    case FN_ACOS:
        return degrees ? acos(a) / deg : acos(a);
    case FN_ATAN:
        return degrees ? atan(a) / deg : atan(a);
    case FN_ATAN2:
        return degrees ? atan2(a, b) / deg : atan2(a, b);
    case FN_EXP:
        return exp(a);
    case FN_LOG:
        return log(a);
    case FN_LOG10:
        return log10(a);
    case FN_POW:
        return pow(a, b);
    case FN_FLOOR:
        return floor(a);
    case FN_CEIL:
        return ceil(a);
    case FN_SIGN:
        return a > 0 ? 1 : a < 0 ? -1 : 0;
    case FN_SQRT:
        return sqrt(a);
    case FN_TRUNC:
        return trunc(a);
    case FN_FABS:
        return fabs(a);
    case FN_FMOD:
        return fmod(a, b);
    case FN_MIN:
        return a < b ? a : b;
    case FN_MAX:
        return a > b ? a : b;
    default:
        return 0;
    }
}

/// The value of a growth function (FN_HOSSFELD <= fn < FN_GROWTH_END) at its arguments
/// a[0] = t, a[1..3] = the curve's a, b, c (Pretzsch's table in Oberlaender 2020, Fig. 13, with
/// the Gompertz increment corrected).
double cbm__builtin_growth(int fn, const double *a);

#endif
