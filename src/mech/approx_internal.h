/* Method A's two roots of the length condition, exposed to its tests (src/mech/approx.c). Not
 * part of the public API. */
#ifndef CAMBIUM_MECH_APPROX_INTERNAL_H
#define CAMBIUM_MECH_APPROX_INTERNAL_H

#include <stdbool.h>

/// The tip deflection omega (rad) of the corrected mode from the clamp angle t0 (rad, upward
/// vertical) and the length K0 sigma_end, by the elliptic integrals' gap K(k) - F(phi0, k),
/// bisection then Illinois to 1e-13 (the reference; the generator's root until 2026-11 and its
/// fall-back since). *evals counts the evaluations.
double cbm__approx_omega_reference(double t0, double target, int *evals);

/// The same omega by the secant method on sin(t0/2) = k cd(target, k^2) (the generator's root).
/// false if it did not converge; *evals counts the evaluations.
bool cbm__approx_omega_fast(double t0, double target, int *evals, double *out);

#endif
