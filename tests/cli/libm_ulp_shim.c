/* A stand-in for another C library's libm, for tests/cli/libm_ulp.sh: preloaded
 * (LD_PRELOAD), it moves the result of each transcendental function of libm by one unit in the
 * last place (up), as a libm whose functions are correct to 1 ULP but round otherwise may. It
 * calls the real function (dlsym(RTLD_NEXT)) and returns nextafter(result, +inf). sqrt and the
 * arithmetic are exact in IEEE 754 and are not moved. Built by the script with the system's cc;
 * not part of the library. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <math.h>

#define MOVE1(f)                                                                                   \
    double f(double x)                                                                             \
    {                                                                                              \
        static double (*real)(double);                                                             \
        if (!real)                                                                                 \
            real = (double (*)(double))dlsym(RTLD_NEXT, #f);                                       \
        return nextafter(real(x), INFINITY);                                                       \
    }
#define MOVE2(f)                                                                                   \
    double f(double x, double y)                                                                   \
    {                                                                                              \
        static double (*real)(double, double);                                                     \
        if (!real)                                                                                 \
            real = (double (*)(double, double))dlsym(RTLD_NEXT, #f);                               \
        return nextafter(real(x, y), INFINITY);                                                    \
    }
#define MOVE1F(f)                                                                                  \
    float f(float x)                                                                               \
    {                                                                                              \
        static float (*real)(float);                                                               \
        if (!real)                                                                                 \
            real = (float (*)(float))dlsym(RTLD_NEXT, #f);                                         \
        return nextafterf(real(x), INFINITY);                                                      \
    }

MOVE1(sin)
MOVE1(cos)
MOVE1(tan)
MOVE1(asin)
MOVE1(acos)
MOVE1(atan)
MOVE1(sinh)
MOVE1(cosh)
MOVE1(tanh)
MOVE1(exp)
MOVE1(exp2)
MOVE1(expm1)
MOVE1(log)
MOVE1(log2)
MOVE1(log10)
MOVE1(log1p)
MOVE1(cbrt)
MOVE2(atan2)
MOVE2(pow)
MOVE2(hypot)
MOVE1F(sinf)
MOVE1F(cosf)
MOVE1F(tanf)
MOVE1F(expf)
MOVE1F(logf)

/* (not sin and cos: the compiler would turn the pair back into a call of sincos) */
void sincos(double x, double *s, double *c)
{
    static void (*real)(double, double *, double *);
    if (!real)
        real = (void (*)(double, double *, double *))dlsym(RTLD_NEXT, "sincos");
    real(x, s, c);
    *s = nextafter(*s, INFINITY);
    *c = nextafter(*c, INFINITY);
}

void sincosf(float x, float *s, float *c)
{
    static void (*real)(float, float *, float *);
    if (!real)
        real = (void (*)(float, float *, float *))dlsym(RTLD_NEXT, "sincosf");
    real(x, s, c);
    *s = nextafterf(*s, INFINITY);
    *c = nextafterf(*c, INFINITY);
}
