/* The 3x3 helpers of the tree factorisation (src/mech/mat3.h) against their scalar reference
 * forms, bit for bit: the two-column products (plain, scaled, negated, plus a matrix), the
 * transposed product and vector, and the right Jacobian of SO(3). Inputs of every magnitude,
 * both signed zeros, subnormals and infinities; NaN only where both forms must agree that it is
 * NaN (its payload is not compared). */
#include "test.h"
#include "mech/mech_internal.h"
#include "mech/mat3.h"

#include <string.h>

/* xorshift64*: a generator of its own, so the inputs do not depend on the context's */
static uint64_t rng_state = 0x9e3779b97f4a7c15u;

static uint64_t rng_next(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return rng_state * 0x2545f4914f6cdd1du;
}

static double rng_unit(void)
{
    return (double)(rng_next() >> 11) * 0x1.0p-53;
}

/* a double of random sign and magnitude 1e-310 .. 1e300, now and then an exact zero of either
 * sign, one, or (with special) an infinity */
static double rng_value(bool special)
{
    uint64_t k = rng_next() % 32;
    double s = (rng_next() & 1) ? -1.0 : 1.0;
    if (k == 0)
        return s * 0.0;
    if (k == 1)
        return s;
    if (k == 2 && special)
        return s * INFINITY;
    if (k == 3)
        return s * 1e-310 * rng_unit(); /* subnormal */
    double e = k < 20 ? 4.0 * (rng_unit() - 0.5) : 600.0 * (rng_unit() - 0.5);
    return s * (0.5 + rng_unit()) * pow(10.0, e);
}

static void rng_matrix(double *m, bool special)
{
    for (int k = 0; k < 9; k++)
        m[k] = rng_value(special);
}

/* the same bits, or NaN in both (payloads may differ) */
static bool same(double a, double b)
{
    if (isnan(a) || isnan(b))
        return isnan(a) && isnan(b);
    uint64_t ua, ub;
    memcpy(&ua, &a, sizeof ua);
    memcpy(&ub, &b, sizeof ub);
    return ua == ub;
}

static int count_differing(const double *a, const double *b, int n)
{
    int d = 0;
    for (int k = 0; k < n; k++)
        d += !same(a[k], b[k]);
    return d;
}

static void transpose(double *t, const double *a)
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            t[3 * j + i] = a[3 * i + j];
}

TEST(mat3_products_match_scalar_bits)
{
    int bad = 0;
    for (int n = 0; n < 200000; n++) {
        double a[9], b[9], ref[9], vec[9], at[9];
        bool special = n % 4 == 3;
        rng_matrix(a, special);
        rng_matrix(b, special);
        cbm__m3_mul_ref(ref, a, b);
        cbm__m3_mul(vec, a, b);
        bad += count_differing(ref, vec, 9);
        /* the product scaled, negated, plus a third matrix: the reference's product, then
         * the one operation per entry */
        double c[9], s = rng_value(special), want[9];
        rng_matrix(c, special);
        cbm__m3_mul_ref(ref, a, b);
        for (int k = 0; k < 9; k++)
            want[k] = ref[k] * s;
        cbm__m3_mul_scale(vec, a, b, s);
        bad += count_differing(want, vec, 9);
        for (int k = 0; k < 9; k++)
            want[k] = -ref[k];
        cbm__m3_mul_neg(vec, a, b);
        bad += count_differing(want, vec, 9);
        for (int k = 0; k < 9; k++)
            want[k] = ref[k] + c[k];
        cbm__m3_mul_add(vec, a, b, c);
        bad += count_differing(want, vec, 9);
        /* a^T b against the product of the transposed copy */
        transpose(at, a);
        cbm__m3_mul_ref(ref, at, b);
        cbm__m3_mul_tn(vec, a, b);
        bad += count_differing(ref, vec, 9);
        /* a^T v against the scalar product of the transposed copy, row by row */
        cbm_vec3 v = {rng_value(special), rng_value(special), rng_value(special)};
        cbm_vec3 o = cbm__m3_vec_t(a, v);
        double got[3] = {o.x, o.y, o.z};
        for (int i = 0; i < 3; i++)
            want[i] = at[3 * i] * v.x + at[3 * i + 1] * v.y + at[3 * i + 2] * v.z;
        bad += count_differing(want, got, 3);
    }
    CHECK_EQ_INT(bad, 0);
}

TEST(mat3_products_are_products)
{
    /* not only the reference's bits: the reference is the product (exact small integers) */
    const double a[9] = {1, 2, 3, 4, 5, 6, 7, 8, 10}, b[9] = {-1, 0, 2, 3, 1, -2, 0, 4, 1};
    const double ab[9] = {5, 14, 1, 11, 29, 4, 17, 48, 8};
    const double atb[9] = {11, 32, 1, 13, 37, 2, 15, 46, 4};
    double o[9];
    cbm__m3_mul(o, a, b);
    CHECK_EQ_INT(count_differing(o, ab, 9), 0);
    cbm__m3_mul_tn(o, a, b);
    CHECK_EQ_INT(count_differing(o, atb, 9), 0);
    cbm_vec3 v = cbm__m3_vec_t(a, (cbm_vec3){1, -1, 2});
    CHECK(v.x == 11.0 && v.y == 13.0 && v.z == 17.0);
}

TEST(mat3_right_jacobian_matches_reference_bits)
{
    int bad = 0, cases = 0;
    for (int n = 0; n < 200000; n++) {
        /* rotation vectors from 1e-12 rad to 100 rad, a component now and then exactly zero
         * of either sign (the ones where the sign of a zero could differ) */
        double mag = pow(10.0, 14.0 * rng_unit() - 12.0);
        double c[3];
        for (int k = 0; k < 3; k++) {
            uint64_t z = rng_next() % 8;
            c[k] = z == 0 ? 0.0 : z == 1 ? -0.0 : mag * (2.0 * rng_unit() - 1.0);
        }
        if (n % 1000 == 0) /* the series' edge: t2 near 1e-4 */
            c[0] = 1e-2 * (1.0 + 1e-3 * (rng_unit() - 0.5)), c[1] = c[2] = 0.0;
        cbm_vec3 r = {c[0], c[1], c[2]};
        double t2 = r.x * r.x + r.y * r.y + r.z * r.z, c1, c2;
        cbm__mech_jr_coeffs(t2, &c1, &c2);
        double ref[9], fast[9];
        cbm__m3_jr_ref(ref, r, t2, c1, c2);
        cbm__m3_jr(fast, r, t2, c1, c2);
        bad += count_differing(ref, fast, 9);
        cases++;
    }
    /* not finite: NaN in both forms */
    const double odd[] = {INFINITY, -INFINITY, NAN, 1e200};
    for (int k = 0; k < 4; k++) {
        cbm_vec3 r = {odd[k], 0.5, -0.0};
        double t2 = r.x * r.x + r.y * r.y + r.z * r.z, c1, c2;
        cbm__mech_jr_coeffs(t2, &c1, &c2);
        double ref[9], fast[9];
        cbm__m3_jr_ref(ref, r, t2, c1, c2);
        cbm__m3_jr(fast, r, t2, c1, c2);
        bad += count_differing(ref, fast, 9);
    }
    CHECK_EQ_INT(bad, 0);
    CHECK_EQ_INT(cases, 200000);
}
