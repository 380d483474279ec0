/* Random numbers of both dialects (lang/random.h). */
#include "lang/random.h"

#include <math.h>

void cbm__rand48_seed16(cbm__rand48 *r, uint16_t x0, uint16_t x1, uint16_t x2)
{
    r->x = (uint64_t)x0 | ((uint64_t)x1 << 16) | ((uint64_t)x2 << 32);
}

double cbm__rand48_next(cbm__rand48 *r)
{
    r->x = (r->x * 0x5DEECE66Dull + 0xBull) & 0xFFFFFFFFFFFFull;
    return ldexp((double)r->x, -48);
}

void cbm__random_seed(cbm__random *r, long long s)
{
    cbm__rand48_seed16(&r->r48, 0x330E, (uint16_t)(s & 0xFFFF), (uint16_t)((s >> 16) & 0xFFFF));
    r->normal_have = 0;
}

void cbm__random_normal(cbm__random *r, double *v, double *f)
{
    if (r->normal_have) {
        r->normal_have = 0;
        *v = r->normal_cached;
        *f = 1;
        return;
    }
    double v1, v2, rsq;
    do {
        v1 = 2.0 * cbm__rand48_next(&r->r48) - 1.0;
        v2 = 2.0 * cbm__rand48_next(&r->r48) - 1.0;
        rsq = v1 * v1 + v2 * v2;
    } while (rsq >= 1.0 || rsq == 0.0);
    double fac = sqrt(-2.0 * log(rsq) / rsq);
    r->normal_cached = v1 * fac;
    r->normal_have = 1;
    *v = v2;
    *f = fac;
}

bool cbm__random_beta(cbm__random *r, double a, double b, double *out)
{
    double s = a + b, lambda;
    double mn = a < b ? a : b;
    if (mn <= 1)
        lambda = mn;
    else
        lambda = sqrt((2 * a * b - s) / (s - 2));
    double u = a + lambda, U1, U2, V, Ym;
    long guard = 0;
    do {
        do {
            U1 = cbm__rand48_next(&r->r48);
        } while (U1 == 0);
        do {
            U2 = cbm__rand48_next(&r->r48);
        } while (U2 == 0);
        V = (1 / lambda) * log(U1 / (1 - U1));
        Ym = a * exp(V);
        if (++guard > 1000000 || !(lambda > 0)) {
            *out = 0;
            return false;
        }
    } while (s * log(s / (b + Ym)) + u * V - log(4) < log(U1 * U1 * U2));
    *out = Ym / (b + Ym);
    return true;
}

int cbm__random_binomial(cbm__random *r, int n, double p)
{
    int j = 0;
    for (int i = 1; i <= n; i++)
        j += cbm__rand48_next(&r->r48) <= p;
    return j;
}

static uint32_t crand_step(cbm__crand *c)
{
    uint32_t v = c->r[(c->pos + 34 - 31) % 34] + c->r[(c->pos + 34 - 3) % 34];
    c->r[c->pos] = v;
    c->pos = (c->pos + 1) % 34;
    return v;
}

void cbm__crand_seed(cbm__crand *c, uint32_t seed)
{
    int32_t r = (int32_t)(seed ? seed : 1);
    c->r[0] = (uint32_t)r;
    for (int i = 1; i < 31; i++) {
        int32_t hi = r / 127773, lo = r % 127773;
        r = 16807 * lo - 2836 * hi;
        if (r < 0)
            r += 2147483647;
        c->r[i] = (uint32_t)r;
    }
    for (int i = 31; i < 34; i++)
        c->r[i] = c->r[i - 31];
    c->pos = 0;
    for (int i = 34; i < 344; i++)
        crand_step(c);
}

double cbm__crand_next(cbm__crand *c)
{
    return (double)(crand_step(c) >> 1);
}
