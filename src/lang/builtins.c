/* The one table of built-in functions of both dialects (lang/builtins.h). Trigonometry is the
 * same name in both, in degrees in the cpfg dialect (cpfg) and radians in the L+C one (C's). */
#include "lang/builtins.h"

#include <string.h>

#define B  (CBM__CPFG | CBM__LC)
#define CP CBM__CPFG
#define LC CBM__LC

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
    {"log10", FN_LOG10, 1, LC},
    {"pow", FN_POW, 2, LC},
    {"floor", FN_FLOOR, 1, B},
    {"ceil", FN_CEIL, 1, B},
    {"sign", FN_SIGN, 1, CP},
    {"sqrt", FN_SQRT, 1, B},
    {"trunc", FN_TRUNC, 1, CP},
    {"fabs", FN_FABS, 1, B},
    {"abs", FN_FABS, 1, LC},
    {"fmod", FN_FMOD, 2, LC},
    {"min", FN_MIN, 2, LC},
    {"max", FN_MAX, 2, LC},
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
    {"Gravity", FN_GRAVITY, 3, LC},
    {"Ground", FN_GROUND, 3, LC},
    {"Contact", FN_CONTACT, 2, LC},
    {"Tropism", FN_TROPISM, 4, LC},
    {"PipeModel", FN_PIPEMODEL, 2, LC},
    {"Wood", FN_WOOD, 5, LC},
    {"RingRate", FN_RINGRATE, 2, LC},
    {"Solver", FN_SOLVER, 3, LC},
    {"SolverMethod", FN_SOLVERMETHOD, 1, LC},
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
