/* Private pieces of the elastica: the backward integrator shared by the single rod, the S-curve
 * and the branched plant. */
#ifndef CBM_ELASTICA_INTERNAL_H
#define CBM_ELASTICA_INTERNAL_H

#include "cambium/elastica.h"
#include "core/core.h"
#include "core/vecmath.h"

/* The integrated state, s increasing; integrated from s = L down to 0. */
enum { EL_THETA, EL_M, EL_P, EL_X, EL_Y, EL_V, EL_ETA, EL_ZETA, EL_N };

/// Properties of a rod at s (s in [0, L]); `k` is the piece (for the right side of a jump).
double cbm__el_stiffness(const cbm_elastica_piece *pc, double t);
double cbm__el_weight(const cbm_elastica_piece *pc, double t);

/// Checks the rod: every piece with length > 0, D > 0, w >= 0, all finite.
cbm_status cbm__el_check(cbm_context *ctx, const cbm_elastica_rod *rod);

/// Integrates from the tip (theta_tip, moment tip_moment, distal weight tip_force, Jacobi
/// eta = 1, zeta = d tip moment / d theta_tip = dmoment) to the base. If `sample` is given it
/// is called at n_sample points equally spaced in s from 0 to L (any order) with the state.
typedef void (*cbm__el_sample_fn)(void *ud, size_t i, double s, const double *y);
cbm_status cbm__el_integrate(const cbm_elastica_rod *rod, double theta_tip, double dmoment,
                             double y_base[EL_N], int *zeros, cbm__el_sample_fn sample, void *ud,
                             size_t n_sample);

/// Fills a state from the integrated base values.
void cbm__el_state(const cbm_elastica_rod *rod, double theta_tip, const double *y, int zeros,
                   cbm_elastica_state *out);

double cbm__el_length(const cbm_elastica_rod *rod);

#endif
