/* cambium: the force-applying approximative bending of one branch (Gürtler 2018, §2.1 and §3.1,
 * after de Reffye's AMAPlesson 7; "Method A"), its conversion from physical parameters (§5,
 * eqs. 5.1-5.2) and the phenotype distance of two branch shapes (eqs. 5.3-5.7). docs/methods.md
 * has the equations, both modes and what the method leaves out; docs/validation.md its error
 * against the exact elastica.
 *
 * The branch is a homogeneous conic Euler-Bernoulli rod clamped at an angle t0 from the UPWARD
 * vertical whose whole weight is replaced by one vertical force at its tip. The arc length counts
 * segments (the branch is `disc` segments long) and K0 = h sqrt(F / EI) per segment (h the
 * segment length, EI at the base: the listing's convention, in which the increment of the
 * profile is dtheta = sqrt(2) K0 sqrt(cos(t0 + theta) - cos(t0 + omega)) ds).
 *
 * The result is the listing's array of disc + 1 angles in degrees: res[0] = t0 (absolute) and
 * res[k] (k = 1..disc) the rotation between segment k-1 and segment k, so that segment k
 * (0-based) points at t0 + res[1] + ... + res[k+1] from the upward vertical. */
#ifndef CAMBIUM_APPROX_H
#define CAMBIUM_APPROX_H

#include "cambium/base.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Which version of the angle generator.
typedef enum cbm_approx_mode {
    /// Default: the tip angle omega is the accurate root of the exact condition (2.26) (elliptic
    /// integrals, to 1e-12 rad), the profile is the elastica of that condition in closed form
    /// (Jacobi's functions of the conic arc length), increments stop at the tip angle (no held
    /// increment), no cancellation near t0 = 90 degrees.
    CBM_APPROX_CORRECTED,
    /// The listing of §3.1 step by step, with its quirks q1-q6 (digest §2.1.2): the linearised
    /// closed form or the coarse bisection (eps = 0.17 rad) for omega, the left Riemann sum of
    /// the profile, the last increment held once omega is reached, no bending at exactly 90
    /// degrees. Only its two endless loops are cut (they would never change the result).
    CBM_APPROX_THESIS
} cbm_approx_mode;

/// "corrected" or "thesis"; NULL if out of range.
CBM_API const char *cbm_approx_mode_name(cbm_approx_mode m);
/// Parses "corrected" or "thesis". false if unknown.
CBM_API bool cbm_approx_mode_parse(const char *name, cbm_approx_mode *out);

/// How omega was found.
typedef enum cbm_approx_route {
    CBM_APPROX_ROUTE_NONE,        ///< no bending (K0 = 0, t0 = 180, or t0 = 0 below buckling)
    CBM_APPROX_ROUTE_CLOSED,      ///< thesis: closed form (2.31)
    CBM_APPROX_ROUTE_CLOSED_COSH, ///< thesis: closed form with cosh past 90 degrees (2.32)
    CBM_APPROX_ROUTE_BISECTION,   ///< thesis: the listing's coarse bisection
    CBM_APPROX_ROUTE_ROOT,        ///< corrected: accurate root of (2.26)
    /// corrected: the small-load series, where (K0 disc / (1 - coni))^2 <= 0.02 (no root, no
    /// evaluation; docs/methods.md)
    CBM_APPROX_ROUTE_SERIES
} cbm_approx_route;

/// "none", "closed", "closed-cosh", "bisection", "root", "series"; "unknown" out of range.
CBM_API const char *cbm_approx_route_name(cbm_approx_route r);

/// The generator's inputs, GetRotationAnglesApprox(disc, t0, K0, coni, p).
typedef struct cbm_approx_def {
    long disc;            ///< number of segments (>= 1)
    double t0;            ///< initial angle from the upward vertical, degrees, [0, 180]
    double k0;            ///< K0 = h sqrt(F/EI), per segment (>= 0)
    double coni;          ///< conicity 1 - r_end / r_start, [0, 1)
    double p;             ///< relative position where the bending reverses, [0, 1]; 1 = never
    cbm_approx_mode mode; ///< default CBM_APPROX_CORRECTED
} cbm_approx_def;

/// Defaults: disc 100, t0 90, K0 0, coni 0, p 1, corrected.
CBM_API cbm_approx_def cbm_approx_def_default(void);

/// What the generator did.
typedef struct cbm_approx_info {
    double omega;           ///< degrees, the tip deflection it aimed at
    double omega_linear;    ///< degrees, the linearised closed form (2.31)-(2.32), stable form
    double tip_angle;       ///< degrees from the vertical: t0 + sum of the increments
    cbm_approx_route route; ///< how omega was found
    int evaluations;        ///< evaluations of the length condition (root or bisection)
} cbm_approx_info;

/// Fills res[0..disc] (n_res >= disc + 1). CBM_E_INVALID naming the parameter for a value out of
/// range; CBM_E_NONFINITE if the thesis mode's profile becomes NaN (its reversal past the
/// hanging direction). info may be NULL.
CBM_API cbm_status cbm_approx_angles(cbm_context *ctx, const cbm_approx_def *def, double *res,
                                     size_t n_res, cbm_approx_info *info);

/// Linearised tip deflection (2.31)-(2.32), radians, in the stable form 1 - cos x = 2 sin^2(x/2)
/// (and 2 sinh^2 past 90 degrees): omega = tan t0 (1 - cos x)/cos x, x = K0 h sqrt(cos t0), with
/// its limit K0^2 h^2 / 2 at t0 = 90 degrees. `kh` = K0 times the (effective) length. Infinite
/// at and past the buckling argument x = pi/2.
CBM_API double cbm_approx_omega_linear(double t0_rad, double kh);

/// How an axis of a plant is loaded when solver = approx bends it (cbm_solve_def.approx_load).
typedef enum cbm_approx_load {
    /// Default, the thesis: everything the axis carries as one force at its tip, K0 and coni from
    /// the base rigidity and the axis's linear taper. A tapered upright axis (a stem) then puts
    /// the whole tree's weight on its thinnest part and buckles (docs/validation.md).
    CBM_APPROX_LOAD_TIP,
    /// K0 such that the generator's small-load tip rotation, (K0 disc)^2 / 2, equals the axis's
    /// own linear one as a horizontal cantilever: the integral of M/EI over the axis, M the
    /// moment of its own wood, point masses and laterals where they hang, EI each segment's; coni
    /// 0 (the calibration holds the taper). The same shape family, with the right stiffness.
    CBM_APPROX_LOAD_CALIBRATED
} cbm_approx_load;

/// Which K0 the conversion returns.
typedef enum cbm_approx_k0_convention {
    /// Default: the listing's K0 = h sqrt(F/EI) (its generator multiplies by sqrt 2 itself).
    CBM_APPROX_K0_LISTING,
    /// Chapter 5's eq. 5.2 as printed, K0 = h sqrt(2F/EI): sqrt 2 too large for the listing's
    /// generator (the thesis's comparisons used it; digest §2.1.3).
    CBM_APPROX_K0_CHAPTER5
} cbm_approx_k0_convention;

/// A uniform or linearly tapered round rod in physical units.
typedef struct cbm_approx_rod {
    double youngs_modulus; ///< E, Pa (> 0)
    double density;        ///< kg/m^3 (>= 0)
    double gravity;        ///< m/s^2 (>= 0)
    double length;         ///< m (> 0)
    double radius_base;    ///< m (> 0)
    double radius_tip;     ///< m (> 0, <= radius_base)
    long disc;             ///< segments (>= 1)
    /// N, the tip force; < 0 (default): eq. 5.2's weight of a cylinder of the base radius,
    /// grav rho pi L r_base^2
    double force;
} cbm_approx_rod;

/// Defaults: E 1e10, density 600, gravity 9.81, length 1, radii 0.01, 100 segments, force 5.2.
CBM_API cbm_approx_rod cbm_approx_rod_default(void);

/// coni = 1 - r_tip / r_base (5.1) and K0 (5.2) per segment: h sqrt(F / (E pi r_base^4 / 4))
/// times sqrt 2 in the chapter-5 convention, h = length / disc. CBM_E_INVALID naming the field.
CBM_API cbm_status cbm_approx_params(cbm_context *ctx, const cbm_approx_rod *rod,
                                     cbm_approx_k0_convention conv, double *k0, double *coni);

/// Phenotype distance of Gürtler eqs. 5.3-5.7 from polyline A (na points) to polyline B (nb
/// points), 2-D or 3-D (dim 2 or 3, points packed): d_i = the smallest distance from A_i to a
/// point of B, and the result is the trapezoid integral of d over the index i, sum over
/// i = 1..na-1 of (d_i + d_(i+1))/2 (m x index; not symmetric in A and B). d (optional) receives
/// the na distances. 0 for na < 2. CBM_E_INVALID for nb == 0 or a bad dim.
CBM_API cbm_status cbm_approx_phenotype_distance(const double *a, size_t na, const double *b,
                                                 size_t nb, int dim, double *d, double *out);

#ifdef __cplusplus
}
#endif
#endif
