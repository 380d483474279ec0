/* The library's own generator: xoshiro256** (Blackman & Vigna 2018) seeded through splitmix64.
 * Fast, 256 bits of state, identical on every platform; all randomness of a run comes from a
 * generator seeded from the context, never from rand(). */
#include "core.h"

#include <math.h>

static uint64_t splitmix64(uint64_t *x)
{
    uint64_t z = (*x += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

void cbm__rng_seed(cbm_rng *r, uint64_t seed)
{
    uint64_t x = seed;
    for (int i = 0; i < 4; i++)
        r->s[i] = splitmix64(&x);
}

static uint64_t rotl(uint64_t x, int k)
{
    return (x << k) | (x >> (64 - k));
}

uint64_t cbm__rng_next(cbm_rng *r)
{
    uint64_t *s = r->s;
    uint64_t result = rotl(s[1] * 5, 7) * 9;
    uint64_t t = s[1] << 17;
    s[2] ^= s[0];
    s[3] ^= s[1];
    s[1] ^= s[2];
    s[0] ^= s[3];
    s[2] ^= t;
    s[3] = rotl(s[3], 45);
    return result;
}

double cbm__rng_uniform(cbm_rng *r)
{
    return (double)(cbm__rng_next(r) >> 11) * 0x1.0p-53;
}

double cbm__rng_normal(cbm_rng *r)
{
    double u, v, s;
    do {
        u = 2.0 * cbm__rng_uniform(r) - 1.0;
        v = 2.0 * cbm__rng_uniform(r) - 1.0;
        s = u * u + v * v;
    } while (s >= 1.0 || s == 0.0);
    return u * sqrt(-2.0 * log(s) / s);
}
