/* cambium: Gürtler's incremental finite-element branch as his listing computes it (Gürtler 2018
 * §2.2 and §3.2, getRotationAnglesFE; digest 001 §2.2.3-2.2.6): one planar chain of n_FE beam
 * elements grown one element and one ring per step, assembled densely, solved either free-free by
 * the pseudo-inverse of a singular value decomposition (the thesis: no support condition, D3) or
 * clamped at the base, each element's angle updated by the rotation of its FIRST node (D8).
 *
 * This is the thesis-compatible path, kept to reproduce and explain the thesis's results. The FEM
 * of plants (CBM_MECH_FEM, cbm_plant_fem_grow in cambium/mech.h) is the corrected method: 3-D,
 * branched, clamped, O(n) per step, chord rotations. This path costs O(n_FE^4) in all, like the
 * thesis's (a dense SVD per step), and is meant for n_FE up to a few dozen. docs/methods.md
 * ("The thesis-compatible path") has the equations and docs/validation.md what it reproduces.
 *
 * Angles are degrees from the UPWARD vertical; units as the caller chooses (the thesis used
 * unscaled MPa and micro-strains: only rho grav / E and the geometry matter, D7). */
#ifndef CAMBIUM_FEM_THESIS_H
#define CAMBIUM_FEM_THESIS_H

#include "cambium/base.h"
#include "cambium/mech.h"

#ifdef __cplusplus
extern "C" {
#endif

/// How the chain is held.
typedef enum cbm_fem_support {
    /// The listing: no degree of freedom is fixed; K is the singular free-free matrix and the
    /// step takes the minimum-norm least-squares solution through the SVD, singular values below
    /// Commons-Math's threshold max(m sigma_max 2^-52, sqrt(2^-1022)) treated as zero (D3).
    CBM_FEM_SUPPORT_FREE,
    /// All six DOF of the base node fixed (what the listing's comment says it meant).
    CBM_FEM_SUPPORT_CLAMPED
} cbm_fem_support;

/// "free" or "clamped"; NULL if out of range.
CBM_API const char *cbm_fem_support_name(cbm_fem_support s);
/// Parses "free" or "clamped". false if unknown.
CBM_API bool cbm_fem_support_parse(const char *name, cbm_fem_support *out);

/// Inputs of getRotationAnglesFE(n_FE, n_GU, t0, rho, E, grav, Le, r_start, r_end, sigma, phi, a,
/// b, primaryTropism, extraLoads) and the listing's choices (digest D2-D5, D8).
typedef struct cbm_fem_thesis_def {
    long n_fe;             ///< elements = growth steps = rings of the base element (2..1000)
    double t0;             ///< initial angle from the upward vertical, degrees, [0, 180]
    double rho;            ///< density (> = 0)
    double youngs_modulus; ///< E (> 0); G = shear_ratio E
    double grav;           ///< gravity (>= 0)
    double le;             ///< element length (> 0)
    double r_start;        ///< base radius after n_fe steps (> 0)
    double r_end;          ///< tip radius: the core of every new element (> 0, <= r_start)
    double sigma;          ///< reaction sensitivity (>= 0)
    double phi;            ///< reaction direction, degrees (the listing: d = phi - beta)
    double a;              ///< smallest maturation strain (the listing uses micro-strains as is)
    double b;              ///< largest maturation strain
    bool primary_tropism;  ///< every new element starts at t0 (else at the tip's angle)
    /// n_fe masses, element i's extra load spread over the n_fe steps (D1); NULL = none
    const double *extra_loads;
    cbm_fem_support support; ///< default CBM_FEM_SUPPORT_FREE (the listing)
    /// the listing's stiffness with k(4,8) = 0 (not symmetric, D2); false: the symmetric element
    bool printed_stiffness;
    /// +1: beta += theta_y of the first node (the listing, which lifts a clamped branch, D4);
    /// -1: beta -= theta_y (sags)
    int update_sign;
    cbm_fem_axial axial; ///< axial resultant; default CBM_FEM_AXIAL_LISTING (D5)
    double shear_ratio;  ///< G / E; default 1/3 (the listing)
} cbm_fem_thesis_def;

/// The listing as printed: n_fe 10, t0 60, rho 2, E 800, grav 9.81, le 0.1, radii 0.05, sigma 0,
/// phi 60, a -200, b 2000, no primary tropism, free support, printed stiffness, update_sign +1,
/// axial listing, shear_ratio 1/3 (digest §2.2.6's first case).
CBM_API cbm_fem_thesis_def cbm_fem_thesis_def_default(void);

/// What the run did.
typedef struct cbm_fem_thesis_info {
    double tip_angle;     ///< degrees: the last element's angle
    long rank_deficiency; ///< singular values treated as zero in the last step (free; else 0)
    double smallest_kept; ///< smallest singular value kept, relative to the largest (free)
    double residual;      ///< |K dq - dF| / |dF| of the last step (the part the SVD drops)
    long sweeps;          ///< Jacobi sweeps of the last step's SVD (free)
} cbm_fem_thesis_info;

/// Runs the n_fe growth steps and writes each element's final angle, base to tip, into
/// beta[0..n_fe-1] (degrees from the upward vertical; n_beta >= n_fe). The thesis's Akima
/// resampling to n_GU output angles is left to the caller. CBM_E_INVALID naming the field for a
/// value out of range; CBM_E_NONFINITE if a step gives a non-finite angle or the clamped system is
/// singular; CBM_E_NOMEM. info may be NULL.
CBM_API cbm_status cbm_fem_thesis_angles(cbm_context *ctx, const cbm_fem_thesis_def *def,
                                         double *beta, size_t n_beta, cbm_fem_thesis_info *info);

/// Akima's (1970) interpolation through (x[i], y[i]), i < n (n >= 5, x strictly increasing, all
/// finite), evaluated at the m abscissae xq into yq (xq outside [x[0], x[n-1]] continues the end
/// cubic). A piecewise cubic Hermite curve: the slope at an interior point x[i] (2 <= i <= n-3) is
/// Akima's weighted mean of the chords on either side, (w[i+1] d[i-1] + w[i-1] d[i]) / (w[i+1] +
/// w[i-1]) with d[i] the chord slope of [x[i], x[i+1]] and w[i] = |d[i] - d[i-1]|, and where both
/// weights vanish the chords' mean weighted by the neighbouring interval lengths; the two slopes
/// at each end are those of the parabola through the three end points (the end rule of the
/// library the thesis used). It reproduces straight lines exactly, stays flat beside a step, and
/// is O(h^2) for smooth data. CBM_E_INVALID for n < 5, a non-increasing x, a non-finite value.
CBM_API cbm_status cbm_akima(cbm_context *ctx, const double *x, const double *y, size_t n,
                             const double *xq, double *yq, size_t m);

/// The thesis's output step (digest §2.2.4, "Output"): the Akima spline A through the n_fe
/// element angles beta[i] at i / (n_fe - 1), read at the n_gu abscissae j / (n_gu - 1):
/// out[j] = A(j / (n_gu - 1)), ABSOLUTE degrees from the upward vertical, base to tip (the
/// listing returns out[0] and then the increments out[j] - out[j-1]). n_fe >= 5, n_gu >= n_fe
/// (the listing raises a smaller n_gu to n_fe; here the caller does). CBM_E_INVALID otherwise.
CBM_API cbm_status cbm_fem_thesis_resample(cbm_context *ctx, const double *beta, size_t n_fe,
                                           double *out, size_t n_gu);

/// Which finite-element method `bend` uses with solver = fem (cbm_bend_spec.fem_path).
typedef enum cbm_fem_path {
    /// Default: the plant FEM (cbm_fem_def; 3-D, clamped, the spec's loads and growth)
    CBM_FEM_PATH_CLAMPED,
    /// cbm_fem_thesis_angles on n_FE = fem_elements elements, resampled by cbm_fem_thesis_resample
    /// to the spec's segments (n_GU) and posed as the rod's shape (docs/bend.md)
    CBM_FEM_PATH_THESIS
} cbm_fem_path;

#ifdef __cplusplus
}
#endif
#endif
