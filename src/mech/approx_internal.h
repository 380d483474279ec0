/* Method A's two roots of the length condition, exposed to its tests (src/mech/approx.c). Not
 * part of the public API. */
#ifndef CAMBIUM_MECH_APPROX_INTERNAL_H
#define CAMBIUM_MECH_APPROX_INTERNAL_H

#include "cambium/approx.h"

#include <stdbool.h>

/// The tip deflection omega (rad) of the corrected mode from the clamp angle t0 (rad, upward
/// vertical) and the length K0 sigma_end, by the elliptic integrals' gap K(k) - F(phi0, k),
/// bisection then Illinois to 1e-13 (the reference; the generator's root until 2026-11 and its
/// fall-back since). *evals counts the evaluations.
double cbm__approx_omega_reference(double t0, double target, int *evals);

/// The same omega by the secant method on sin(t0/2) = k cd(target, k^2) (the generator's root).
/// false if it did not converge; *evals counts the evaluations.
bool cbm__approx_omega_fast(double t0, double target, int *evals, double *out);

/// The corrected mode's profile of one axis by the small-load series, with sin t0 > 0 and cos t0
/// given instead of d->t0 (a plant has them from its frame without a transcendental call):
/// false, res untouched, where (K0 sigma_end)^2 is past the series' range, K0 = 0 or sin t0 = 0
/// (then cbm_approx_angles). Fills res[1..disc] only; d is not validated (the caller's is).
bool cbm__approx_series(const cbm_approx_def *d, double sin_t0, double cos_t0, double *res);

/// The corrected mode without the series (the elliptic root and profile at every load), for the
/// tests that bound the series; omega in degrees.
void cbm__approx_angles_elliptic(const cbm_approx_def *d, double *res, double *omega);

#endif
