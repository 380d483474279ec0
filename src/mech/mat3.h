/* 3x3 products of the tree factorisation (solve_tree.c), row-major, two columns at a time.
 *
 * Entry (i, j) of a b is (a_i0 b_0j + a_i1 b_1j) + a_i2 b_2j in every form below: the same
 * operations in the same order as the scalar reference (cbm__m3_mul_ref), so the same bits. A
 * row's columns 0 and 1 are one two-wide vector (a_i0 broadcast times row 0 of b's first two
 * columns, and so on), its column 2 a scalar: 15 arithmetic instructions a row where the scalar
 * form takes 15 a row and three times the loads. GCC's vector extensions: SSE2 on x86-64, the
 * same in scalar form elsewhere; -ffp-contract=off keeps the products unfused in both. */
#ifndef CBM_MECH_MAT3_H
#define CBM_MECH_MAT3_H

#include "cambium/base.h"

#include <string.h>

typedef double cbm__v2 __attribute__((vector_size(16)));

static inline cbm__v2 cbm__v2_load(const double *p)
{
    cbm__v2 v;
    memcpy(&v, p, sizeof v);
    return v;
}

static inline void cbm__v2_store(double *p, cbm__v2 v)
{
    memcpy(p, &v, sizeof v);
}

static inline cbm__v2 cbm__v2_splat(double x)
{
    cbm__v2 v = {x, x};
    return v;
}

/* out = a b, the scalar reference (out must not alias a or b) */
static inline void cbm__m3_mul_ref(double *restrict out, const double *a, const double *b)
{
#pragma GCC unroll 9
    for (int i = 0; i < 3; i++)
#pragma GCC unroll 9
        for (int j = 0; j < 3; j++)
            out[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
}

/* out = a b, two columns at a time: the reference's bits (out must not alias a or b) */
static inline void cbm__m3_mul(double *restrict out, const double *a, const double *b)
{
    const cbm__v2 b0 = cbm__v2_load(b), b1 = cbm__v2_load(b + 3), b2 = cbm__v2_load(b + 6);
    const double b02 = b[2], b12 = b[5], b22 = b[8];
#pragma GCC unroll 3
    for (int i = 0; i < 3; i++) {
        const double x = a[3 * i], y = a[3 * i + 1], z = a[3 * i + 2];
        cbm__v2 r = cbm__v2_splat(x) * b0 + cbm__v2_splat(y) * b1 + cbm__v2_splat(z) * b2;
        out[3 * i + 2] = x * b02 + y * b12 + z * b22;
        cbm__v2_store(out + 3 * i, r);
    }
}

/* The product's row i, columns 0-1 in *lo and column 2 in *hi: the reference's operations */
static inline void cbm__m3_row(const double *ai, const double *b, cbm__v2 *lo, double *hi)
{
    const double x = ai[0], y = ai[1], z = ai[2];
    *lo = cbm__v2_splat(x) * cbm__v2_load(b) + cbm__v2_splat(y) * cbm__v2_load(b + 3) +
          cbm__v2_splat(z) * cbm__v2_load(b + 6);
    *hi = x * b[2] + y * b[5] + z * b[8];
}

/* out = (a b) s, each entry the reference's product times s (out must not alias a or b) */
static inline void cbm__m3_mul_scale(double *restrict out, const double *a, const double *b,
                                     double s)
{
#pragma GCC unroll 3
    for (int i = 0; i < 3; i++) {
        cbm__v2 lo;
        double hi;
        cbm__m3_row(a + 3 * i, b, &lo, &hi);
        cbm__v2_store(out + 3 * i, lo * cbm__v2_splat(s));
        out[3 * i + 2] = hi * s;
    }
}

/* out = -(a b), each entry the reference's product negated (out must not alias a or b) */
static inline void cbm__m3_mul_neg(double *restrict out, const double *a, const double *b)
{
#pragma GCC unroll 3
    for (int i = 0; i < 3; i++) {
        cbm__v2 lo;
        double hi;
        cbm__m3_row(a + 3 * i, b, &lo, &hi);
        cbm__v2_store(out + 3 * i, -lo);
        out[3 * i + 2] = -hi;
    }
}

/* out = a b + c, each entry the reference's product plus c's (out must not alias a, b or c) */
static inline void cbm__m3_mul_add(double *restrict out, const double *a, const double *b,
                                   const double *c)
{
#pragma GCC unroll 3
    for (int i = 0; i < 3; i++) {
        cbm__v2 lo;
        double hi;
        cbm__m3_row(a + 3 * i, b, &lo, &hi);
        cbm__v2_store(out + 3 * i, lo + cbm__v2_load(c + 3 * i));
        out[3 * i + 2] = hi + c[3 * i + 2];
    }
}

/* out = a^T b, entry (i, j) = (a_0i b_0j + a_1i b_1j) + a_2i b_2j: the bits of the product of
 * the transposed copy, without the copy (out must not alias a or b) */
static inline void cbm__m3_mul_tn(double *restrict out, const double *a, const double *b)
{
    const cbm__v2 b0 = cbm__v2_load(b), b1 = cbm__v2_load(b + 3), b2 = cbm__v2_load(b + 6);
    const double b02 = b[2], b12 = b[5], b22 = b[8];
#pragma GCC unroll 3
    for (int i = 0; i < 3; i++) {
        const double x = a[i], y = a[3 + i], z = a[6 + i];
        cbm__v2 r = cbm__v2_splat(x) * b0 + cbm__v2_splat(y) * b1 + cbm__v2_splat(z) * b2;
        out[3 * i + 2] = x * b02 + y * b12 + z * b22;
        cbm__v2_store(out + 3 * i, r);
    }
}

/* a^T v, component i = (a_0i v_x + a_1i v_y) + a_2i v_z; components 0 and 1 are one vector
 * (a's rows are the columns of a^T) */
static inline cbm_vec3 cbm__m3_vec_t(const double *a, cbm_vec3 v)
{
    cbm__v2 r = cbm__v2_load(a) * cbm__v2_splat(v.x) + cbm__v2_load(a + 3) * cbm__v2_splat(v.y) +
                cbm__v2_load(a + 6) * cbm__v2_splat(v.z);
    cbm_vec3 o = {r[0], r[1], a[2] * v.x + a[5] * v.y + a[8] * v.z};
    return o;
}

/* The right Jacobian of SO(3) at the rotation vector r, J = I - c1 [r]x + c2 [r]x^2 with
 * [r]x^2 = r r^T - t2 I (t2 = |r|^2, c1 and c2 from cbm__mech_jr_coeffs), as the reference
 * writes it entry by entry: J_rc = (id - c1 [r]x_rc) + c2 (r_r r_c - id t2), id = 1 on the
 * diagonal, 0 off it. */
static inline void cbm__m3_jr_ref(double *J, cbm_vec3 r, double t2, double c1, double c2)
{
    const double sr[9] = {0, -r.z, r.y, r.z, 0, -r.x, -r.y, r.x, 0};
    const double rv[3] = {r.x, r.y, r.z};
    for (int r0 = 0; r0 < 3; r0++)
        for (int c0 = 0; c0 < 3; c0++) {
            double id = r0 == c0 ? 1.0 : 0.0;
            J[3 * r0 + c0] = id - c1 * sr[3 * r0 + c0] + c2 * (rv[r0] * rv[c0] - id * t2);
        }
}

/* The same bits in the fewest operations: t2 >= +0 and c1 >= 0 (a sum of squares, and
 * (1 - cos t) / t2 or its series), so c1 * 0 = +0, 1 - c1 * 0 = 1, 0 * t2 = +0, x - (+0) = x
 * and 1 * t2 = t2; c1 (-x) = -(c1 x) (rounding is symmetric) and 0 - (-k) = 0 + k (IEEE
 * subtraction adds the negation); r_r r_c = r_c r_r. A t2 that is not finite makes c1 and c2,
 * and so every entry, NaN in both forms. 36 operations instead of 63. */
static inline void cbm__m3_jr(double *J, cbm_vec3 r, double t2, double c1, double c2)
{
    const double kx = c1 * r.x, ky = c1 * r.y, kz = c1 * r.z;
    const double xy = c2 * (r.x * r.y), xz = c2 * (r.x * r.z), yz = c2 * (r.y * r.z);
    J[0] = 1.0 + c2 * (r.x * r.x - t2);
    J[1] = (0.0 + kz) + xy;
    J[2] = (0.0 - ky) + xz;
    J[3] = (0.0 - kz) + xy;
    J[4] = 1.0 + c2 * (r.y * r.y - t2);
    J[5] = (0.0 + kx) + yz;
    J[6] = (0.0 + ky) + xz;
    J[7] = (0.0 - kx) + yz;
    J[8] = 1.0 + c2 * (r.z * r.z - t2);
}

#endif
