/* Random numbers of both dialects, one module (random.c): the generators their peers draw from
 * and the distributions built on them, so that a model makes the same choices as under cpfg or
 * lpfg.
 *
 *   rand48   the POSIX 48-bit LCG of drand48/erand48: ran, nran, bran, biran, drand48 and the
 *            choice of stochastic productions;
 *   crand    the C library's rand()/random() (glibc's additive feedback generator), the rand()
 *            of L+C models compiled in C.
 */
#ifndef CBM_LANG_RANDOM_H
#define CBM_LANG_RANDOM_H

#include <stdbool.h>
#include <stdint.h>

typedef struct cbm__rand48 {
    uint64_t x; /* 48-bit state */
} cbm__rand48;
void cbm__rand48_seed16(cbm__rand48 *r, uint16_t x0, uint16_t x1, uint16_t x2);
/// The next value in [0, 1): X' = (a X + c) mod 2^48, a = 0x5DEECE66D, c = 0xB, X' / 2^48.
double cbm__rand48_next(cbm__rand48 *r);

/// The stream of a model's random functions: erand48 and the pair cache of the normal deviates.
typedef struct cbm__random {
    cbm__rand48 r48;
    int normal_have; /* 0: the next normal deviate draws a pair, else the cached one is given */
    double normal_cached;
} cbm__random;

/// srand(s) of both dialects: erand48's state {0x330E, s & 0xFFFF, s >> 16}, no cached deviate.
void cbm__random_seed(cbm__random *r, long long s);

/// The next standard normal deviate of the polar (Box-Muller) method, which makes them in
/// pairs (Numerical Recipes' gasdev, as cpfg and lpfg do), as two factors whose product is the
/// deviate (a cached one: the deviate and 1), so that each dialect scales it in its peer's order
/// of operations: cpfg v * f * sd + mean, lpfg mean + sd * v * f.
void cbm__random_normal(cbm__random *r, double *v, double *f);

/// Cheng's generator of a beta(a, b) variate (cpfg's bran); false when a or b is not positive.
bool cbm__random_beta(cbm__random *r, double a, double b, double *out);

/// The number of successes of n Bernoulli(p) draws (cpfg's biran; n is checked by the caller).
int cbm__random_binomial(cbm__random *r, int n, double p);

/// glibc's random(): r[i] = r[i-3] + r[i-31] after a Lehmer initialisation, 310 values
/// discarded. Seeded by cbm__crand_seed before use.
typedef struct cbm__crand {
    uint32_t r[34];
    int pos;
} cbm__crand;
void cbm__crand_seed(cbm__crand *c, uint32_t seed);
/// rand(): the next value in [0, RAND_MAX].
double cbm__crand_next(cbm__crand *c);

#endif
