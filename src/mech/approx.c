/* Method A, the force-applying approximative bending of one branch (Gürtler 2018 §2.1, §3.1;
 * digest 001 §2.1): the angle generator in its thesis-compatible and corrected modes, the
 * conversion from physical parameters (5.1-5.2) and the phenotype distance (5.3-5.7).
 *
 * Notation: angles from the upward vertical; psi = t0 + theta is the tangent's angle at arc
 * length s, omega the tip's extra deflection, K0^2 = F/EI per segment^2 (the listing's
 * convention). The exact first integral of the tip-loaded elastica is
 *     (dpsi/ds)^2 = 2 K0^2 (cos psi - cos(t0 + omega)),
 * and the length condition (2.11)/(2.26) in the conic arc length sigma = s / (1 - s/H) (H the
 * length of the full cone, so sigma(disc) = disc / (1 - coni)) is, with k = sin((t0+omega)/2)
 * and sin phi0 = sin(t0/2) / k (the substitution sin(psi/2) = k sin phi),
 *     K0 sigma(disc) = K(k) - F(phi0, k),
 * K and F Legendre's complete and incomplete elliptic integrals of the first kind (Carlson's RF
 * here). Its solution is Jacobi's sin(psi/2) = k sn(F(phi0, k) + K0 sigma, k^2), and the same
 * condition read from the tip is sin(t0/2) = k cd(K0 sigma(disc), k^2). The corrected mode finds
 * omega from the latter by the secant method started at the linearised omega (a few evaluations
 * of sn, cn, dn by series and duplication, no elliptic integral), falling back on the former by
 * bisection and Illinois when it does not converge or t0 = 0; it fills the profile from the
 * closed form by the addition theorem, one step per segment (docs/performance.md, "Method A";
 * until 2026-11 it was RK4 of the pendulum psi'' = -K0^2 sin psi, docs/validation.md has what
 * moved). The conic model itself (2.24-2.27: the cylinder's first integral with the local
 * K) is the thesis's; it is not the exact elastica of a cone (docs/validation.md measures it). */
#include "cambium/approx.h"
#include "core/core.h"
#include "mech/approx_internal.h"

#include <math.h>
#include <string.h>

#define RAD (180.0 / 3.14159265358979323846)
#define PI  3.14159265358979323846

const char *cbm_approx_mode_name(cbm_approx_mode m)
{
    switch (m) {
    case CBM_APPROX_CORRECTED:
        return "corrected";
    case CBM_APPROX_THESIS:
        return "thesis";
    }
    return NULL;
}

bool cbm_approx_mode_parse(const char *name, cbm_approx_mode *out)
{
    if (!name || !out)
        return false;
    if (!strcmp(name, "corrected"))
        *out = CBM_APPROX_CORRECTED;
    else if (!strcmp(name, "thesis"))
        *out = CBM_APPROX_THESIS;
    else
        return false;
    return true;
}

const char *cbm_approx_route_name(cbm_approx_route r)
{
    static const char *const names[] = {"none",      "closed", "closed-cosh",
                                        "bisection", "root",   "series"};
    if ((unsigned)r >= sizeof names / sizeof names[0])
        return "unknown";
    return names[r];
}

cbm_approx_def cbm_approx_def_default(void)
{
    cbm_approx_def d;
    memset(&d, 0, sizeof d);
    d.disc = 100;
    d.t0 = 90.0;
    d.p = 1.0;
    d.mode = CBM_APPROX_CORRECTED;
    return d;
}

cbm_approx_rod cbm_approx_rod_default(void)
{
    cbm_approx_rod r;
    memset(&r, 0, sizeof r);
    r.youngs_modulus = 1e10;
    r.density = 600.0;
    r.gravity = 9.81;
    r.length = 1.0;
    r.radius_base = r.radius_tip = 0.01;
    r.disc = 100;
    r.force = -1.0;
    return r;
}

/* The linearised omega from c = cos t0 and s = sin t0 (the root below has them from the half
 * angle without two more transcendental calls). */
static double omega_linear_cs(double c, double s, double kh)
{
    if (!(kh > 0.0) || s == 0.0)
        return 0.0;
    if (fabs(c) < 1e-300)
        return s * 0.5 * kh * kh;
    double x = kh * sqrt(fabs(c));
    if (c > 0.0) {
        double cx = cos(x);
        if (!(cx > 0.0))
            return INFINITY; /* at or past the buckling argument pi/2 */
        double h = sin(0.5 * x);
        return s * 2.0 * h * h / (c * cx);
    }
    /* cos(i x) = cosh x: omega = s (cosh x - 1) / (|c| cosh x), no cancellation either */
    double h = sinh(0.5 * x);
    return s * 2.0 * h * h / (-c * cosh(x));
}

double cbm_approx_omega_linear(double t0, double kh)
{
    return omega_linear_cs(cos(t0), sin(t0), kh);
}

/* ---- the thesis's listing ---- */

/* The listing's bisection (step 5): omega to within eps = 0.17 rad on [0, pi - t0], with ~10
 * coarse steps of its Riemann sum. The inner loop ends as soon as its abscissa passes h: from
 * there on the outcome (b = w) can no longer change, and with K0 = 0 the listing's loop never
 * ends (q5). */
static double thesis_bisection(double t0r, double k0, double h, double dx, int *evals)
{
    double a = 0.0, b = PI - t0r, w = 0.0;
    const double eps = 0.17;
    while (b - a > eps) {
        w = 0.5 * (a + b);
        double t = 0.0, x = 1.0;
        double cw = cos(t0r + w); /* loop-invariant: once per trial, same bits */
        do {
            double dt = dx * sqrt(2.0) * k0 * sqrt(fabs(cos(t0r + t) - cw));
            t += dt;
            x += dx;
        } while (t < w && x < h);
        (*evals)++;
        if (x < h - dx)
            a = w;
        else
            b = w;
    }
    return 0.5 * (a + b);
}

static cbm_status thesis_angles(cbm_context *ctx, const cbm_approx_def *d, double *res,
                                cbm_approx_info *info)
{
    long disc = d->disc;
    double dx = (double)disc / 10.0;
    double h = (double)disc / (1.0 - d->coni);
    double t0r = d->t0 / RAD, c = cos(t0r), s = sin(t0r), k0 = d->k0;
    double w = -1.0;
    info->route = CBM_APPROX_ROUTE_BISECTION;
    if (d->coni == 0.0) {
        if (c > 0.0) {
            double x = k0 * h * sqrt(c);
            w = s * (1.0 - cos(x)) / (c * cos(x));
            info->route = CBM_APPROX_ROUTE_CLOSED;
        } else {
            double x = k0 * h * sqrt(fabs(c));
            double ch = (exp(-x) + exp(x)) / 2.0;
            w = s * (1.0 - ch) / (c * ch);
            info->route = CBM_APPROX_ROUTE_CLOSED_COSH;
        }
    }
    /* Java's sqrt of a negative number is NaN and NaN > 0.8 is false: the test is silently off
     * past 90 degrees; C's sqrt behaves the same */
    if (d->coni > 0.0 || k0 * h * sqrt(c) * 2.0 / PI > 0.8 || fabs(w) > 0.8 || w < 0.0) {
        if (k0 == 0.0) {
            w = 0.0; /* the listing loops for ever here (q5); no load bends nothing */
            info->route = CBM_APPROX_ROUTE_NONE;
        } else {
            w = thesis_bisection(t0r, k0, h, dx, &info->evaluations);
            info->route = CBM_APPROX_ROUTE_BISECTION;
        }
    }
    info->omega = w * RAD;
    double t = 0.0, t1 = 0.0, cw = cos(w + t0r);
    res[0] = d->t0;
    for (long i = 0; i < disc; i++) {
        if (t < w) {
            double q = 1.0 - d->coni * (double)(i + 1) / (double)disc;
            t1 = k0 / (q * q) * sqrt(2.0 * (cos(t + t0r) - cw));
            if ((double)i > (double)disc * d->p)
                t1 = -t1;
            t += t1;
        }
        res[i + 1] = t1 * RAD; /* q1: held once t >= w */
        if (!isfinite(res[i + 1]))
            return cbm__fail(ctx, CBM_E_NONFINITE,
                             "approx (thesis mode): the profile became NaN at segment %ld "
                             "(t0 + omega past 180 degrees: the closed form or the reversal "
                             "aims past the hanging direction)",
                             i);
    }
    return CBM_OK;
}

/* ---- the corrected generator ---- */

/* Carlson's symmetric elliptic integral R_F(x, y, z) by the duplication theorem; the fifth-order
 * series once the arguments agree to 0.0025 leaves a relative error below 1e-16. */
static double carlson_rf(double x, double y, double z)
{
    for (int it = 0; it < 200; it++) {
        double sx = sqrt(x), sy = sqrt(y), sz = sqrt(z);
        double lam = sx * (sy + sz) + sy * sz;
        x = 0.25 * (x + lam);
        y = 0.25 * (y + lam);
        z = 0.25 * (z + lam);
        double m = (x + y + z) / 3.0;
        double ex = (m - x) / m, ey = (m - y) / m, ez = (m - z) / m;
        if (fmax(fabs(ex), fmax(fabs(ey), fabs(ez))) < 0.0025) {
            double e2 = ex * ey - ez * ez, e3 = ex * ey * ez;
            return (1.0 + (e2 / 24.0 - 0.1 - 3.0 * e3 / 44.0) * e2 + e3 / 14.0) / sqrt(m);
        }
    }
    return NAN;
}

/* K(k) - F(phi0, k) - target for omega (rad): the length, in units of 1/K0, a rod needs to
 * reach the tip deflection omega from t0, minus the length it has. Every difference of
 * cosines is written as a product of sines (no cancellation near omega = 0). */
static double length_gap(double t0, double omega, double target)
{
    double psi = t0 + omega;
    double k = sin(0.5 * psi);
    double s0 = sin(0.5 * t0);
    double c0 = cos(0.5 * t0);
    double cpsi = cos(0.5 * psi);
    double kk = cpsi * cpsi; /* 1 - k^2 */
    double full = carlson_rf(0.0, kk, 1.0);
    double part = 0.0;
    if (s0 > 0.0) {
        double sphi = s0 / k;
        /* cos^2 phi0 = (k^2 - sin^2(t0/2)) / k^2 = sin(omega/2) sin(t0 + omega/2) / k^2 */
        double cphi2 = sin(0.5 * omega) * sin(t0 + 0.5 * omega) / (k * k);
        if (cphi2 < 0.0)
            cphi2 = 0.0;
        part = sphi * carlson_rf(cphi2, c0 * c0, 1.0);
    }
    return full - part - target;
}

/* omega (rad) with K0 sigma_end = K(k) - F(phi0, k): bisection on [0, pi - t0] (the gap rises
 * from -target, or pi/2 - target at t0 = 0, to +infinity) until the bracket is finite and
 * narrow, then Illinois to 1e-13. */
static double corrected_omega(double t0, double target, int *evals, cbm_approx_route *route)
{
    double lo = 0.0, hi = PI - t0;
    double glo = t0 > 0.0 ? -target : 0.5 * PI - target;
    *route = CBM_APPROX_ROUTE_ROOT;
    if (!(glo < 0.0) || !(hi > 0.0)) {
        *route = CBM_APPROX_ROUTE_NONE; /* hanging, or upright below the buckling load */
        return 0.0;
    }
    double ghi = INFINITY;
    for (int i = 0; i < 200 && (!isfinite(ghi) || hi - lo > 0.05); i++) {
        double m = 0.5 * (lo + hi);
        double g = length_gap(t0, m, target);
        (*evals)++;
        if (g < 0.0) {
            lo = m;
            glo = g;
        } else {
            hi = m;
            ghi = g;
        }
        if (hi - lo < 1e-15)
            break;
    }
    int side = 0;
    for (int i = 0; i < 100 && hi - lo > 1e-13; i++) {
        double m = (lo * ghi - hi * glo) / (ghi - glo);
        if (!(m > lo && m < hi))
            m = 0.5 * (lo + hi);
        double g = length_gap(t0, m, target);
        (*evals)++;
        if (g == 0.0)
            return m;
        if (g < 0.0) {
            lo = m;
            glo = g;
            if (side == -1)
                ghi *= 0.5;
            side = -1;
        } else {
            hi = m;
            ghi = g;
            if (side == 1)
                glo *= 0.5;
            side = 1;
        }
    }
    return 0.5 * (lo + hi);
}

/* Jacobi's elliptic functions sn, cn, dn of (u, m = k^2), u >= 0: the Maclaurin series to u^9
 * at u / 2^j <= 1/32 (their nearest pole is at i K'(m), |K'| >= pi/2, so the first omitted term
 * is below 1e-16 relative), then j duplications. No transcendental call: ~5 duplications for
 * u ~ 1 cost less than one sine. Absolute error ~1e-15 for u up to K(m) below m = 0.99, growing
 * with u where m -> 1 (the root below checks what it finds). */
typedef struct jacobi3 {
    double sn, cn, dn;
} jacobi3;

static jacobi3 jacobi(double u, double m, double mc)
{
    int j = 0;
    double v = u;
    while (v > 0.03125 && j < 1100) {
        v *= 0.5;
        j++;
    }
    double v2 = v * v, m2 = m * m, m3 = m2 * m, m4 = m2 * m2;
    jacobi3 r;
    r.sn = v * (1.0 - v2 * ((1.0 + m) * (1.0 / 6.0) -
                            v2 * ((1.0 + 14.0 * m + m2) * (1.0 / 120.0) -
                                  v2 * ((1.0 + 135.0 * m + 135.0 * m2 + m3) * (1.0 / 5040.0) -
                                        v2 * (1.0 + 1228.0 * m + 5478.0 * m2 + 1228.0 * m3 + m4) *
                                            (1.0 / 362880.0)))));
    r.cn = 1.0 - v2 * (0.5 - v2 * ((1.0 + 4.0 * m) * (1.0 / 24.0) -
                                   v2 * ((1.0 + 44.0 * m + 16.0 * m2) * (1.0 / 720.0) -
                                         v2 * (1.0 + 408.0 * m + 912.0 * m2 + 64.0 * m3) *
                                             (1.0 / 40320.0))));
    r.dn =
        1.0 - m * v2 *
                  (0.5 - v2 * ((4.0 + m) * (1.0 / 24.0) -
                               v2 * ((16.0 + 44.0 * m + m2) * (1.0 / 720.0) -
                                     v2 * (64.0 + 912.0 * m + 408.0 * m2 + m3) * (1.0 / 40320.0))));
    /* the duplication in forms without cancellation as m -> 1 (mc = 1 - m given, not formed):
     * 1 - m s^4 = c^2 (1 + s^2) + mc s^4, d^2 - m s^2 c^2 = c^2 d^2 + mc s^2, and
     * c^2 - s^2 d^2 = c^4 - mc s^4 (small only where cn itself is) */
    for (; j > 0; j--) {
        double s = r.sn, c = r.cn, d = r.dn, s2 = s * s, c2 = c * c;
        double den = 1.0 / (c2 * (1.0 + s2) + mc * s2 * s2);
        r.sn = 2.0 * s * c * d * den;
        r.cn = (c2 * c2 - mc * s2 * s2) * den;
        r.dn = (c2 * d * d + mc * s2) * den;
    }
    return r;
}

/* The addition theorem: the functions of a + b from those of a and b. */
static inline jacobi3 jacobi_add(jacobi3 a, jacobi3 b, double m, double mc)
{
    /* 1 - m sa^2 sb^2 = ca^2 + sa^2 cb^2 + mc sa^2 sb^2, a sum of positive terms */
    double sa2 = a.sn * a.sn, sb2 = b.sn * b.sn;
    double den = 1.0 / (a.cn * a.cn + sa2 * b.cn * b.cn + mc * sa2 * sb2);
    jacobi3 r;
    r.sn = (a.sn * b.cn * b.dn + b.sn * a.cn * a.dn) * den;
    r.cn = (a.cn * b.cn - a.sn * a.dn * b.sn * b.dn) * den;
    r.dn = (a.dn * b.dn - m * a.sn * a.cn * b.sn * b.cn) * den;
    return r;
}

/* K(k) from k' = sqrt(1 - k^2) by the arithmetic-geometric mean, pi / (2 AGM(1, k')). */
static double complete_k(double kc)
{
    double a = 1.0, b = kc;
    for (int i = 0; i < 40 && fabs(a - b) > 1e-15 * a; i++) {
        double c = 0.5 * (a + b);
        b = sqrt(a * b);
        a = c;
    }
    return PI / (a + b);
}

/* The same length condition seen from the tip. The profile is sin(psi/2) = k sn(u, k^2) with
 * u = K(k) at the tip (psi' = 0) and u = K(k) - K0 sigma_end at the base, so the condition is
 * sin(t0/2) = k cd(K0 sigma_end), here multiplied by dn: k cn(T) - sin(t0/2) dn(T), T =
 * K0 sigma_end. Smooth in omega (the gap above goes as sqrt(omega)); negative at omega = 0,
 * (1 - sin(t0/2)) sech T > 0 at the hanging direction. Its other roots, with T > K(k), are the
 * inflected shapes that wind past a free end; the caller keeps out of them. */
static double tip_residual(double t0, double s0, double omega, double target)
{
    double k = sin(0.5 * (t0 + omega)), kc = cos(0.5 * (t0 + omega));
    jacobi3 j = jacobi(target, k * k, kc * kc);
    return k * j.cn - s0 * j.dn;
}

/* omega (rad) from tip_residual by the secant method, started at the linearised omega (2.31),
 * inside a bracket kept by sign: a trial with K(k) <= T (only possible for T >= pi/2, since K
 * >= pi/2) lies below the physical root and is bisected away. Stops when the step falls below
 * 1e-13 rad. false if it does not converge in 60 evaluations (the caller then takes the
 * elliptic-integral root); ~6 evaluations of ~5 duplications each in the plants' range. */
static bool omega_fast(double t0, double s0, double c0, double target, int *evals, double *out)
{
    double lo = 0.0, hi = PI - t0;
    bool check_k = target >= 0.5 * PI;
    /* cos t0 = (c0 - s0)(c0 + s0) and sin t0 = 2 s0 c0 from the half angle's */
    double x0 = omega_linear_cs((c0 - s0) * (c0 + s0), 2.0 * s0 * c0, target);
    if (!(x0 > 0.0 && x0 < hi))
        x0 = 0.5 * hi;
    int n = 0;
    while (check_k && complete_k(cos(0.5 * (t0 + x0))) <= target && n < 60) {
        lo = x0;
        x0 = 0.5 * (lo + hi);
        n++;
    }
    double k = sin(0.5 * (t0 + x0)), kc = cos(0.5 * (t0 + x0)), m = k * k;
    jacobi3 j0 = jacobi(target, m, kc * kc);
    double g0 = k * j0.cn - s0 * j0.dn;
    n++;
    if (g0 < 0.0)
        lo = x0;
    else
        hi = x0;
    /* The second point: a Newton step with the derivative of the residual from the leading
     * terms in T of cn and dn in m, dcn/dm ~ T^4/6, ddn/dm ~ -T^2/2 + (2 + m) T^4/12, with dk =
     * kc/2 domega and dm = k kc domega: close where the linearised omega is (T small), and the
     * bracket guards the rest. Failing that, 10 % below the linearised omega (which
     * overestimates) or above it if it was short. */
    double t2 = target * target, t4 = t2 * t2;
    double dg =
        0.5 * kc * j0.cn + k * kc * (k * t4 / 6.0 - s0 * (-0.5 * t2 + (2.0 + m) * t4 / 12.0));
    double x1 = dg > 0.0 ? x0 - g0 / dg : NAN;
    if (!(x1 > lo && x1 < hi) || x1 == x0)
        x1 = g0 > 0.0 ? 0.9 * x0 : fmin(1.1 * x0, 0.5 * (x0 + hi));
    while (n < 60) {
        n++;
        if (check_k && complete_k(cos(0.5 * (t0 + x1))) <= target) {
            lo = x1;
            x1 = 0.5 * (lo + hi);
            continue;
        }
        double g1 = tip_residual(t0, s0, x1, target);
        if (g1 == 0.0) {
            *evals += n;
            *out = x1;
            return true;
        }
        if (g1 < 0.0)
            lo = x1;
        else
            hi = x1;
        double x2 = x1 - g1 * (x1 - x0) / (g1 - g0);
        if (!(x2 > lo && x2 < hi))
            x2 = 0.5 * (lo + hi);
        double step = fabs(x2 - x1);
        x0 = x1;
        g0 = g1;
        x1 = x2;
        if (step < 1e-13 || hi - lo < 1e-13) {
            *evals += n;
            *out = x2;
            return true;
        }
    }
    *evals += n;
    return false;
}

bool cbm__approx_omega_fast(double t0, double target, int *evals, double *out)
{
    return omega_fast(t0, sin(0.5 * t0), cos(0.5 * t0), target, evals, out);
}

double cbm__approx_omega_reference(double t0, double target, int *evals)
{
    cbm_approx_route route;
    return corrected_omega(t0, target, evals, &route);
}

/* atan(y / x) for x > 0: the Maclaurin series to t^13 where |t| <= 1/16 (the first omitted
 * term is below 5e-19 relative; a segment's half increment is that small unless the axis has a
 * handful of segments under a large load), atan2 otherwise. */
static inline double atan_small(double y, double x)
{
    if (!(fabs(y) <= 0.0625 * x))
        return atan2(y, x);
    double t = y / x, t2 = t * t, t4 = t2 * t2;
    /* Estrin's pairs: half the dependent multiplications of Horner's rule; the reciprocals as
     * constants (a division by 3.0 is not turned into a multiplication without -ffast-math,
     * and four of them were half the time of this function) */
    double a = 1.0 - t2 * (1.0 / 3.0), b = 1.0 / 5.0 - t2 * (1.0 / 7.0);
    double c = 1.0 / 9.0 - t2 * (1.0 / 11.0);
    double q = a + t4 * (b + t4 * (c + t4 * (1.0 / 13.0)));
    return t * q;
}

/* The profile in closed form: with k = sin((t0 + omega)/2) and m = k^2, sin(psi/2) = k sn(u),
 * cos(psi/2) = dn(u), u = u0 + K0 sigma, where sn(u0) = sin(t0/2)/k, cn(u0) = cos phi0 and
 * dn(u0) = cos(t0/2) are known without F(phi0, k). The midpoints follow each other by the
 * addition theorem (one step of the functions per segment, a constant one on a cylinder), and
 * each increment of psi is one atan2 of the half-angle difference (no cancellation). */
/* One RK4 step of theta'' = -K0^2 sin(t0 + theta) over dsig. */
static void pendulum_step(double t0, double k2, double dsig, double *th, double *om)
{
    double x = *th, v = *om;
    double a1 = -k2 * sin(t0 + x);
    double x2 = x + 0.5 * dsig * v, v2 = v + 0.5 * dsig * a1;
    double a2 = -k2 * sin(t0 + x2);
    double x3 = x + 0.5 * dsig * v2, v3 = v + 0.5 * dsig * a2;
    double a3 = -k2 * sin(t0 + x3);
    double x4 = x + dsig * v3, v4 = v + dsig * a3;
    double a4 = -k2 * sin(t0 + x4);
    *th = x + dsig / 6.0 * (v + 2.0 * v2 + 2.0 * v3 + v4);
    *om = v + dsig / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
}

/* Integrates the pendulum from sigma0 to sigma1 in steps of at most hmax. */
static void pendulum(double t0, double k2, double hmax, double sigma0, double sigma1, double *th,
                     double *om)
{
    double span = sigma1 - sigma0;
    if (!(span > 0.0))
        return;
    long n = (long)ceil(span / hmax);
    if (n < 1)
        n = 1;
    double ds = span / (double)n;
    for (long i = 0; i < n; i++)
        pendulum_step(t0, k2, ds, th, om);
}

/* The profile by RK4 of the pendulum (the corrected mode's profile until 2026-11), kept for the
 * one case the closed form cannot hold: t0 + omega rounds to 180 degrees in double precision,
 * so that k' (and K(k)) no longer carry the length. */
static void pendulum_profile(const cbm_approx_def *d, double t0, double w, double *res)
{
    long disc = d->disc;
    double k0 = d->k0;
    /* sigma of the arc length s (segments) on the cone of length H = disc / coni */
    double inv_h = d->coni / (double)disc;
    double k2 = k0 * k0;
    double hmax = 0.05 / k0;
    /* psi'(0) = sqrt(2) K0 sqrt(cos t0 - cos(t0 + w)) = 2 K0 sqrt(sin(w/2) sin(t0 + w/2)) */
    double th = 0.0, om = 2.0 * k0 * sqrt(fmax(0.0, sin(0.5 * w) * sin(t0 + 0.5 * w)));
    double sig = 0.0, prev_mid = 0.0;
    for (long i = 0; i < disc; i++) {
        double smid = (double)i + 0.5;
        double sigmid = smid / (1.0 - smid * inv_h);
        pendulum(t0, k2, hmax, sig, sigmid, &th, &om);
        /* the profile stops at the tip angle: past it the first integral has no real root;
         * and it never turns back (RK4 past the tip of a rod hanging at round-off swung back
         * before 2026-11, by up to -22 degrees in one increment) */
        double mid = fmin(fmax(th, prev_mid), w);
        double inc = mid - prev_mid;
        prev_mid = mid;
        if ((double)i > (double)disc * d->p)
            inc = -inc;
        res[i + 1] = inc * RAD;
        double snode = (double)(i + 1);
        double signode = snode / (1.0 - snode * inv_h);
        pendulum(t0, k2, hmax, sigmid, signode, &th, &om);
        sig = signode;
    }
}

/* ---- the small-load series (the corrected mode where K0 sigma_end is small) ---- */

/* theta = psi - t0 solves theta'' = -eps sin(t0 + theta) on x = sigma / sigma_end in [0, 1],
 * theta(0) = 0, theta'(1) = 0, eps = (K0 sigma_end)^2: the same boundary-value problem the
 * elliptic functions solve. Its expansion theta = sum_n eps^n a_n(x) (a_n a polynomial of degree
 * 2n in x whose coefficients are polynomials in S = sin t0 and C = cos t0, each found from the
 * previous ones by integrating twice; derived with a computer algebra system) is taken to n = 6
 * and gathered into one polynomial theta(x) = sum_j c_j x^j, j = 1..12. The Green operator of
 * this problem has sup-norm 1/2 and |d sin| <= 1, so the Picard map is a contraction with
 * constant eps/2 and the terms fall like (eps/2)^n: at eps <= SERIES_EPS the first omitted
 * term is of order 1e-14 rad, below the elliptic root's own 1e-13 (approx_series_vs_elliptic
 * in tests/test_approx.c measures 1.2e-13 rad between the two on a grid of t0, eps, disc and
 * coni; docs/validation.md states the tolerance). No transcendental call, no root: on trees
 * of short, lightly loaded axes this is most axes (docs/performance.md, "Method A"). */
#define SERIES_EPS 0.02

static void series_coefs(double S, double C, double e, double c[13])
{
    double C2 = C * C, C3 = C2 * C, C4 = C2 * C2, C5 = C4 * C;
    double e1 = e, e2 = e * e, e3 = e2 * e, e4 = e2 * e2, e5 = e4 * e, e6 = e3 * e3;
    c[0] = 0.0;
    c[1] = S * e1 *
           (1 + e * ((1.0 / 3.0) * C +
                     e * ((1.0 / 5.0) * C2 - 1.0 / 15.0 +
                          e * ((46.0 / 315.0) * C3 - 29.0 / 315.0 * C +
                               e * ((67.0 / 567.0) * C4 - 103.0 / 945.0 * C2 + 4.0 / 315.0 +
                                    e * ((5297.0 / 51975.0) * C5 - 3854.0 / 31185.0 * C3 +
                                         (529.0 / 17325.0) * C))))));
    c[2] = S * e1 * (-1.0 / 2.0);
    c[3] = S * e2 *
           (-1.0 / 6.0 * C +
            e * (-1.0 / 18.0 * C2 +
                 e * (-1.0 / 30.0 * C3 + (1.0 / 90.0) * C +
                      e * (-23.0 / 945.0 * C4 + (29.0 / 1890.0) * C2 +
                           e * (-67.0 / 3402.0 * C5 + (103.0 / 5670.0) * C3 - 2.0 / 945.0 * C)))));
    c[4] = S * e2 *
           ((1.0 / 24.0) * C +
            e * (1.0 / 24.0 - 1.0 / 24.0 * C2 +
                 e * (-1.0 / 36.0 * C3 + (1.0 / 36.0) * C +
                      e * (-23.0 / 1080.0 * C4 + (29.0 / 1080.0) * C2 - 1.0 / 180.0 +
                           e * (-67.0 / 3780.0 * C5 + (103.0 / 3780.0) * C3 - 1.0 / 105.0 * C)))));
    c[5] = S * e3 *
           ((1.0 / 30.0) * C2 - 1.0 / 40.0 +
            e * ((1.0 / 360.0) * C3 +
                 e * (-1.0 / 600.0 * C4 + (1.0 / 900.0) * C2 + 1.0 / 600.0 +
                      e * (-11.0 / 3780.0 * C5 + (103.0 / 37800.0) * C3 + (1.0 / 1575.0) * C))));
    c[6] = S * e3 *
           (1.0 / 240.0 - 1.0 / 180.0 * C2 +
            e * ((11.0 / 720.0) * C3 - 11.0 / 720.0 * C +
                 e * ((19.0 / 2160.0) * C4 - 1.0 / 135.0 * C2 - 1.0 / 720.0 +
                      e * ((193.0 / 32400.0) * C5 - 199.0 / 32400.0 * C3 + (1.0 / 5400.0) * C))));
    c[7] = S * e4 *
           (-17.0 / 2520.0 * C3 + (11.0 / 1680.0) * C +
            e * ((11.0 / 3780.0) * C4 - 1.0 / 168.0 * C2 + 1.0 / 336.0 +
                 e * ((13.0 / 3600.0) * C5 - 113.0 / 18900.0 * C3 + (59.0 / 25200.0) * C)));
    c[8] = S * e4 *
           ((17.0 / 20160.0) * C3 - 11.0 / 13440.0 * C +
            e * (-1.0 / 224.0 * C4 + (43.0 / 6720.0) * C2 - 13.0 / 6720.0 +
                 e * (-1.0 / 640.0 * C5 + (29.0 / 20160.0) * C3 + (1.0 / 8064.0) * C)));
    c[9] = S * e5 *
           ((31.0 / 22680.0) * C4 - 19.0 / 10080.0 * C2 + 1.0 / 1920.0 +
            e * (-113.0 / 68040.0 * C5 + (67.0 / 20160.0) * C3 - 67.0 / 40320.0 * C));
    c[10] = S * e5 *
            (-31.0 / 226800.0 * C4 + (19.0 / 100800.0) * C2 - 1.0 / 19200.0 +
             e * ((67.0 / 56700.0) * C5 - 3827.0 / 1814400.0 * C3 + (187.0 / 201600.0) * C));
    c[11] = S * e6 * (-691.0 / 2494800.0 * C5 + (403.0 / 831600.0) * C3 - 307.0 / 1478400.0 * C);
    c[12] =
        S * e6 * ((691.0 / 29937600.0) * C5 - 403.0 / 9979200.0 * C3 + (307.0 / 17740800.0) * C);
}

/* The increments of the profile at the segments' midpoints (as corrected_angles sets them) from
 * the series; returns omega = theta(1) (rad). S = sin t0 and C = cos t0 come from the caller
 * (a plant has them as a cross and a dot product of unit vectors). */
static double series_angles(const cbm_approx_def *d, double S, double C, double e, double *res)
{
    double c[13];
    series_coefs(S, C, e, c);
    long disc = d->disc;
    double sig_end = (double)disc / (1.0 - d->coni);
    double inv_end = 1.0 / sig_end, inv_h = d->coni / (double)disc;
    double prev = 0.0;
    for (long i = 0; i < disc; i++) {
        double smid = (double)i + 0.5;
        double x = (d->coni == 0.0 ? smid : smid / (1.0 - smid * inv_h)) * inv_end;
        double th = c[12];
        for (int j = 11; j >= 1; j--)
            th = th * x + c[j];
        th *= x;
        double inc = th - prev;
        prev = th;
        if ((double)i > (double)disc * d->p)
            inc = -inc;
        res[i + 1] = inc * RAD;
    }
    double w = 0.0;
    for (int j = 12; j >= 1; j--)
        w += c[j];
    return w;
}

#define FROM_TIP 12.0

static void corrected_angles(const cbm_approx_def *d, double *res, cbm_approx_info *info,
                             bool series)
{
    long disc = d->disc;
    double t0 = d->t0 / RAD, k0 = d->k0;
    double sig_end = (double)disc / (1.0 - d->coni);
    double w = 0.0;
    double s0 = sin(0.5 * t0), c0 = cos(0.5 * t0);
    info->route = CBM_APPROX_ROUTE_NONE;
    if (series && k0 > 0.0 && t0 > 0.0 && t0 < PI && k0 * sig_end * k0 * sig_end <= SERIES_EPS) {
        double target = k0 * sig_end;
        res[0] = d->t0;
        w = series_angles(d, 2.0 * s0 * c0, (c0 - s0) * (c0 + s0), target * target, res);
        info->route = CBM_APPROX_ROUTE_SERIES;
        info->omega = w * RAD;
        return;
    }
    if (k0 > 0.0) {
        double target = k0 * sig_end;
        bool fast = t0 > 0.0 && t0 < PI && omega_fast(t0, s0, c0, target, &info->evaluations, &w);
        if (fast)
            info->route = CBM_APPROX_ROUTE_ROOT;
        else
            w = corrected_omega(t0, target, &info->evaluations, &info->route);
    }
    info->omega = w * RAD;
    res[0] = d->t0;
    if (w == 0.0) {
        for (long i = 1; i <= disc; i++)
            res[i] = 0.0;
        return;
    }
    /* k = sin((t0 + omega)/2) and k' by the addition theorem from the half angles (one sincos
     * instead of four calls); k' so formed is a difference, so where it is small (near the
     * hanging direction, where the profile depends on its last digits) it is taken directly */
    double sw = sin(0.5 * w), cw = cos(0.5 * w);
    double k = s0 * cw + c0 * sw, kc = c0 * cw - s0 * sw;
    if (kc < 0.25) {
        k = sin(0.5 * (t0 + w));
        kc = cos(0.5 * (t0 + w));
    }
    double m = k * k, mc = kc * kc;
    /* cos^2 phi0 = sin(omega/2) sin(t0 + omega/2) / k^2 (no cancellation), sin(t0 + omega/2) =
     * sin(t0/2 + (t0 + omega)/2) = s0 k' + c0 k, a sum of positive terms */
    double cphi2 = fmax(0.0, sw * (s0 * kc + c0 * k)) / m;
    jacobi3 cur = {s0 / k, sqrt(cphi2), c0};
    double prev_s = s0, prev_c = c0; /* sin and cos of the previous psi/2 */
    double inv_h = d->coni / (double)disc;
    jacobi3 step = {0.0, 1.0, 1.0};
    if (d->coni == 0.0)
        step = jacobi(k0, m, mc);
    /* Past a length of FROM_TIP / K0 the additions from the base would carry the decaying
     * solution forward (near the hanging direction cn and dn fall like sech u and their
     * rounding errors grow like cosh^2 u; at K0 sigma_end = 45 the profile wrapped by 360
     * degrees): each midpoint is then taken from the tip instead, sin(psi/2) = k cd(x),
     * cos(psi/2) = k' nd(x), x = K0 (sigma_end - sigma), one evaluation per segment (to 1.5e-7
     * degrees at 15; below 12 the additions hold 3e-10, tests/test_approx.c). */
    bool from_tip = k0 * sig_end > FROM_TIP;
    if (from_tip && complete_k(kc) <= k0 * sig_end) {
        pendulum_profile(d, t0, w, res);
        return;
    }
    double sig = 0.0;
    for (long i = 0; i < disc; i++) {
        double smid = (double)i + 0.5;
        double sigmid = d->coni == 0.0 ? smid : smid / (1.0 - smid * inv_h);
        double hs, hc;
        if (from_tip) {
            jacobi3 x = jacobi(k0 * (sig_end - sigmid), m, mc);
            hs = k * x.cn / x.dn;
            hc = kc / x.dn;
            /* at the limit of double precision (t0 + omega rounds to 180 degrees, K(k) < T) x
             * can pass the quarter period and psi below t0: hold t0 there */
            if (!(hs * c0 - hc * s0 >= 0.0)) {
                hs = s0;
                hc = c0;
            }
        } else {
            if (i > 0 && d->coni == 0.0)
                cur = jacobi_add(cur, step, m, mc);
            else
                cur = jacobi_add(cur, jacobi(k0 * (sigmid - sig), m, mc), m, mc);
            hs = k * cur.sn;
            hc = cur.dn;
        }
        sig = sigmid;
        double inc = 2.0 * atan_small(hs * prev_c - hc * prev_s, hc * prev_c + hs * prev_s);
        prev_s = hs;
        prev_c = hc;
        if ((double)i > (double)disc * d->p)
            inc = -inc;
        res[i + 1] = inc * RAD;
    }
}

cbm_status cbm_approx_angles(cbm_context *ctx, const cbm_approx_def *d, double *res, size_t n_res,
                             cbm_approx_info *info)
{
    cbm_approx_info inf;
    memset(&inf, 0, sizeof inf);
    if (info)
        *info = inf;
    if (!d || !res)
        return cbm__fail(ctx, CBM_E_INVALID, "approx: no definition or result array");
    if (d->disc < 1 || d->disc > 100000000)
        return cbm__fail(ctx, CBM_E_INVALID, "approx: disc must be in 1..1e8 (got %ld)", d->disc);
    if (n_res < (size_t)d->disc + 1)
        return cbm__fail(ctx, CBM_E_INVALID, "approx: the result needs disc + 1 = %ld entries",
                         d->disc + 1);
    if (!(d->t0 >= 0.0 && d->t0 <= 180.0))
        return cbm__fail(ctx, CBM_E_INVALID, "approx: t0 must be in [0, 180] degrees");
    if (!(d->k0 >= 0.0) || !isfinite(d->k0))
        return cbm__fail(ctx, CBM_E_INVALID, "approx: K0 must be finite and >= 0");
    if (!(d->coni >= 0.0 && d->coni < 1.0))
        return cbm__fail(ctx, CBM_E_INVALID,
                         "approx: coni must be in [0, 1) (coni = 1 divides by zero, q4)");
    if (!(d->p >= 0.0 && d->p <= 1.0))
        return cbm__fail(ctx, CBM_E_INVALID, "approx: p must be in [0, 1]");
    double sig_end = (double)d->disc / (1.0 - d->coni);
    if (info) /* only reported: the plants' axes (info NULL) skip its four calls */
        inf.omega_linear = cbm_approx_omega_linear(d->t0 / RAD, d->k0 * sig_end) * RAD;
    cbm_status s = CBM_OK;
    if (d->mode == CBM_APPROX_THESIS)
        s = thesis_angles(ctx, d, res, &inf);
    else if (d->mode == CBM_APPROX_CORRECTED)
        corrected_angles(d, res, &inf, true);
    else
        return cbm__fail(ctx, CBM_E_INVALID, "approx: unknown mode %d", (int)d->mode);
    double tip = 0.0;
    for (long i = 0; i <= d->disc; i++)
        tip += res[i];
    inf.tip_angle = tip;
    if (info)
        *info = inf;
    return s;
}

bool cbm__approx_series(const cbm_approx_def *d, double sin_t0, double cos_t0, double *res)
{
    double t = d->k0 * (double)d->disc / (1.0 - d->coni);
    if (!(d->k0 > 0.0) || !(t * t <= SERIES_EPS) || !(sin_t0 > 0.0))
        return false;
    (void)series_angles(d, sin_t0, cos_t0, t * t, res);
    return true;
}

void cbm__approx_angles_elliptic(const cbm_approx_def *d, double *res, double *omega)
{
    cbm_approx_info inf;
    memset(&inf, 0, sizeof inf);
    corrected_angles(d, res, &inf, false);
    *omega = inf.omega;
}

/* ---- conversion (5.1-5.2) ---- */

cbm_status cbm_approx_params(cbm_context *ctx, const cbm_approx_rod *r,
                             cbm_approx_k0_convention conv, double *k0, double *coni)
{
    if (!r)
        return cbm__fail(ctx, CBM_E_INVALID, "approx: no rod");
    if (!(r->youngs_modulus > 0.0) || !isfinite(r->youngs_modulus))
        return cbm__fail(ctx, CBM_E_INVALID, "approx rod: youngs_modulus must be > 0");
    if (!(r->density >= 0.0) || !isfinite(r->density))
        return cbm__fail(ctx, CBM_E_INVALID, "approx rod: density must be >= 0");
    if (!(r->gravity >= 0.0) || !isfinite(r->gravity))
        return cbm__fail(ctx, CBM_E_INVALID, "approx rod: gravity must be >= 0");
    if (!(r->length > 0.0) || !isfinite(r->length))
        return cbm__fail(ctx, CBM_E_INVALID, "approx rod: length must be > 0");
    if (!(r->radius_base > 0.0) || !isfinite(r->radius_base))
        return cbm__fail(ctx, CBM_E_INVALID, "approx rod: radius_base must be > 0");
    if (!(r->radius_tip > 0.0 && r->radius_tip <= r->radius_base))
        return cbm__fail(ctx, CBM_E_INVALID,
                         "approx rod: radius_tip must be in (0, radius_base] (the method has no "
                         "inverse taper)");
    if (r->disc < 1)
        return cbm__fail(ctx, CBM_E_INVALID, "approx rod: disc must be >= 1");
    if (!isfinite(r->force))
        return cbm__fail(ctx, CBM_E_INVALID, "approx rod: force must be finite");
    if (conv != CBM_APPROX_K0_LISTING && conv != CBM_APPROX_K0_CHAPTER5)
        return cbm__fail(ctx, CBM_E_INVALID, "approx: unknown K0 convention %d", (int)conv);
    double rb = r->radius_base;
    double f = r->force >= 0.0 ? r->force : r->gravity * r->density * PI * r->length * rb * rb;
    double ei = r->youngs_modulus * PI * rb * rb * rb * rb / 4.0;
    double h = r->length / (double)r->disc;
    double k = h * sqrt(f / ei);
    if (conv == CBM_APPROX_K0_CHAPTER5)
        k *= sqrt(2.0);
    if (k0)
        *k0 = k;
    if (coni)
        *coni = 1.0 - r->radius_tip / rb;
    return CBM_OK;
}

/* ---- phenotype distance (5.3-5.7) ---- */

cbm_status cbm_approx_phenotype_distance(const double *a, size_t na, const double *b, size_t nb,
                                         int dim, double *d, double *out)
{
    if (out)
        *out = 0.0;
    if ((dim != 2 && dim != 3) || nb == 0 || !b || (na > 0 && !a))
        return CBM_E_INVALID;
    double sum = 0.0, prev = 0.0;
    for (size_t i = 0; i < na; i++) {
        double best = INFINITY;
        const double *p = a + (size_t)dim * i;
        for (size_t k = 0; k < nb; k++) {
            const double *q = b + (size_t)dim * k;
            double dx = p[0] - q[0], dy = p[1] - q[1], dz = dim == 3 ? p[2] - q[2] : 0.0;
            double e = dx * dx + dy * dy + dz * dz;
            if (e < best)
                best = e;
        }
        best = sqrt(best);
        if (d)
            d[i] = best;
        if (i > 0)
            sum += 0.5 * (prev + best);
        prev = best;
    }
    if (out)
        *out = sum;
    return CBM_OK;
}
