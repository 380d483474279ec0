/* The one table of built-in functions of both dialects (lang/builtins.h). Trigonometry is the
 * same name in both, in degrees in the cpfg dialect (cpfg) and radians in the L+C one (C's). */
#include "lang/builtins.h"

#include <math.h>
#include <string.h>

#define B  (CBM__CPFG | CBM__LC)
#define CP CBM__CPFG
#define LC CBM__LC
#define TR CBM__TREE

static const cbm__builtin BUILTINS[] = {
    {"sin", FN_SIN, 1, B},
    {"cos", FN_COS, 1, B},
    {"tan", FN_TAN, 1, B},
    {"asin", FN_ASIN, 1, B},
    {"acos", FN_ACOS, 1, B},
    {"atan", FN_ATAN, 1, B},
    {"atan2", FN_ATAN2, 2, B},
    {"exp", FN_EXP, 1, B},
    {"log", FN_LOG, 1, B},
    {"log10", FN_LOG10, 1, LC | TR},
    {"pow", FN_POW, 2, LC | TR},
    {"floor", FN_FLOOR, 1, B},
    {"ceil", FN_CEIL, 1, B},
    {"sign", FN_SIGN, 1, CP},
    {"sqrt", FN_SQRT, 1, B},
    {"trunc", FN_TRUNC, 1, CP},
    {"fabs", FN_FABS, 1, B},
    {"abs", FN_FABS, 1, LC | TR},
    {"fmod", FN_FMOD, 2, LC | TR},
    {"min", FN_MIN, 2, LC | TR},
    {"max", FN_MAX, 2, LC | TR},
    {"hossfeld", FN_HOSSFELD, 4, TR},
    {"hossfeld_inc", FN_HOSSFELD_INC, 4, TR},
    {"gompertz", FN_GOMPERTZ, 4, TR},
    {"gompertz_inc", FN_GOMPERTZ_INC, 4, TR},
    {"logistic", FN_LOGISTIC, 4, TR},
    {"logistic_inc", FN_LOGISTIC_INC, 4, TR},
    {"monomolecular", FN_MONOMOLECULAR, 4, TR},
    {"monomolecular_inc", FN_MONOMOLECULAR_INC, 4, TR},
    {"bertalanffy", FN_BERTALANFFY, 3, TR},
    {"bertalanffy_inc", FN_BERTALANFFY_INC, 3, TR},
    {"richards", FN_RICHARDS, 4, TR},
    {"richards_inc", FN_RICHARDS_INC, 4, TR},
    {"levakovic", FN_LEVAKOVIC, 4, TR},
    {"levakovic_inc", FN_LEVAKOVIC_INC, 4, TR},
    {"korf", FN_KORF, 4, TR},
    {"korf_inc", FN_KORF_INC, 4, TR},
    {"ran", FN_RAN, 1, B},
    {"nran", FN_NRAN, 2, B},
    {"nrand", FN_NRAN, 2, LC},
    {"bran", FN_BRAN, 2, CP},
    {"biran", FN_BIRAN, 2, CP},
    {"srand", FN_SRAND, 1, B},
    {"rand", FN_RAND, 0, LC},
    {"drand48", FN_DRAND, 0, LC},
    {"func", FN_FUNC, 2, B},
    {"printf", FN_PRINTF, -1, B},
    {"Printf", FN_PRINTF, -1, LC},
    {"stop", FN_STOP, -1, CP},
    {"stop", FN_STOP, 0, LC},
    {"Stop", FN_STOP, 0, LC},
    {"Forward", FN_FORWARD, 0, LC},
    {"Backward", FN_BACKWARD, 0, LC},
    {"UseGroup", FN_USEGROUP, 1, LC},
    {"CurrentGroup", FN_CURGROUP, 0, LC},
    {"Length", FN_LENGTH, 1, LC},
    {"Magnitude", FN_LENGTH, 1, LC},
    {"Normalize", FN_NORMALIZE, 1, LC},
    {"Normalized", FN_NORMALIZE, 1, LC},
    {"DotProd", FN_DOT, 2, LC},
    {"CrossProd", FN_CROSS, 2, LC},
    {"MakeQuaternion", FN_MAKEQ, 2, LC},
    {"VecRotate", FN_VECROT, 3, LC},
    {"ToLocal", FN_TOLOCAL, 2, LC},
    {"ToWorld", FN_TOWORLD, 2, LC},
    {"Equilibrium", FN_EQUILIBRIUM, 0, LC},
    {"AddRings", FN_ADDRINGS, 0, LC},
    {"AgeWood", FN_AGEWOOD, 1, LC},
    {"Break", FN_BREAK, 0, LC},
    {"Stability", FN_STABILITY, 0, LC},
    {"Frequency", FN_FREQUENCY, 1, LC},
    {"Sway", FN_SWAY, 4, LC},
    {"SwayDrag", FN_SWAY, 6, LC},
    {"SwayModes", FN_SWAYMODES, 2, LC},
    {"Light", FN_LIGHT, 2, LC},
    {"Gravity", FN_GRAVITY, 3, LC},
    {"Ground", FN_GROUND, 3, LC},
    {"Contact", FN_CONTACT, 2, LC},
    {"Tropism", FN_TROPISM, 4, LC},
    {"PipeModel", FN_PIPEMODEL, 2, LC},
    {"Wood", FN_WOOD, 5, LC},
    {"RingRate", FN_RINGRATE, 2, LC},
    {"Solver", FN_SOLVER, 3, LC},
    {"SolverMethod", FN_SOLVERMETHOD, 1, LC},
    {"ApproxLoad", FN_APPROXLOAD, 1, LC},
    {"SolverThreads", FN_SOLVERTHREADS, 1, LC},
    {"ReactionWood", FN_REACTION, 4, LC},
    {"ReactionBound", FN_REACTIONBOUND, 1, LC},
    {"RAND_MAX", FN_NONE, 0, LC},
};

const cbm__builtin *cbm__builtin_find(const char *s, size_t n, int dialect)
{
    for (size_t i = 0; i < sizeof BUILTINS / sizeof BUILTINS[0]; i++)
        if ((BUILTINS[i].dialects & dialect) && strlen(BUILTINS[i].name) == n &&
            !memcmp(BUILTINS[i].name, s, n))
            return &BUILTINS[i];
    return NULL;
}

/* The growth functions of forest yield science and their increments (derivatives in t), as
 * Oberlaender (2020, Fig. 13) tabulates them after Pretzsch; the table's Gompertz increment
 * a b c e^(-b e^(-ct)) lacks the factor e^(-ct) of the derivative and is corrected here. */
double cbm__builtin_growth(int fn, const double *v)
{
    const double t = v[0], a = v[1], b = v[2], c = v[3];
    switch ((cbm__fn)fn) {
    case FN_HOSSFELD: /* t^c / (b + t^c / a) */
        return pow(t, c) / (b + pow(t, c) / a);
    case FN_HOSSFELD_INC: {
        double d = b + pow(t, c) / a;
        return b * c * pow(t, c - 1) / (d * d);
    }
    case FN_GOMPERTZ: /* a e^(-b e^(-ct)) */
        return a * exp(-b * exp(-c * t));
    case FN_GOMPERTZ_INC:
        return a * b * c * exp(-c * t) * exp(-b * exp(-c * t));
    case FN_LOGISTIC: /* a / (1 + c e^(-bt)) */
        return a / (1 + c * exp(-b * t));
    case FN_LOGISTIC_INC: {
        double d = 1 + c * exp(-b * t);
        return a * b * c * exp(-b * t) / (d * d);
    }
    case FN_MONOMOLECULAR: /* a (1 - c e^(-bt)) */
        return a * (1 - c * exp(-b * t));
    case FN_MONOMOLECULAR_INC:
        return a * b * c * exp(-b * t);
    case FN_BERTALANFFY: /* a (1 - e^(-bt))^3 */
        return a * pow(1 - exp(-b * t), 3);
    case FN_BERTALANFFY_INC:
        return 3 * a * b * exp(-b * t) * pow(1 - exp(-b * t), 2);
    case FN_RICHARDS: /* Chapman-Richards a (1 - e^(-bt))^c */
        return a * pow(1 - exp(-b * t), c);
    case FN_RICHARDS_INC:
        return a * b * c * exp(-b * t) * pow(1 - exp(-b * t), c - 1);
    case FN_LEVAKOVIC: /* Levakovic III a (t^2 / (b + t^2))^c */
        return a * pow(t * t / (b + t * t), c);
    case FN_LEVAKOVIC_INC: /* 2 b c y / (t (b + t^2)) */
        return 2 * b * c * a * pow(t * t / (b + t * t), c) / (t * (b + t * t));
    case FN_KORF: /* a e^(-b t^-c) */
        return a * exp(-b * pow(t, -c));
    case FN_KORF_INC:
        return a * b * c * pow(t, -c - 1) * exp(-b * pow(t, -c));
    default:
        return 0;
    }
}
