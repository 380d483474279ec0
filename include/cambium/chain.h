/* cambium: the one-dimensional mass-spring chain of Taylor-Hell (2005) §9.2, the first step of her
 * dynamics chapter, in its two forms: inertial (every particle seen from the wall) and
 * non-inertial (particle i seen from particle i-1, with the fictitious force -m_i a_{i-1}).
 *
 * Link i is spring i with particle i at its distal end; spring 0 is attached to a fixed wall at
 * x = 0. Spring i pulls particle i with -k_i (l_i - rest_i) and pushes particle i+1 with the
 * opposite force; each particle is damped by -b v_i (v_i seen from the wall). Both forms advance
 * the same state with the same Euler scheme, so they give the same motion up to round-off (the
 * thesis' claim, held by tests/test_dyn_chain.c).
 */
#ifndef CAMBIUM_CHAIN_H
#define CAMBIUM_CHAIN_H

#include "cambium/base.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Which frames the chain's equations are written in (Taylor-Hell §9.2.1 and §9.2.2).
typedef enum cbm_chain_form {
    CBM_CHAIN_INERTIAL,    ///< eqs. 9.6-9.14: world accelerations, l_i += dt (v_i - v_{i-1})
    CBM_CHAIN_NONINERTIAL, ///< eqs. 9.15-9.20: relative accelerations summed from the wall
} cbm_chain_form;

/// Time stepping of velocities and lengths.
typedef enum cbm_chain_scheme {
    /// explicit Euler as the thesis' text writes it: lengths move with the old velocities
    CBM_CHAIN_EXPLICIT_EULER,
    /// semi-implicit (symplectic) Euler, as the thesis' A.4 listing does for the pendula:
    /// velocities first, then lengths with the new velocities
    CBM_CHAIN_SEMI_IMPLICIT_EULER,
} cbm_chain_scheme;

/// A chain of n links. The arrays are the caller's and are read only by cbm_chain_create.
typedef struct cbm_chain_def {
    size_t n;               ///< links (springs = particles), >= 1
    const double *k;        ///< N/m, stiffness of spring i (n values, > 0)
    const double *rest;     ///< m, rest length of spring i (n values)
    const double *mass;     ///< kg, mass of particle i (n values, > 0)
    const double *length;   ///< m, initial length of spring i (NULL: the rest lengths)
    const double *velocity; ///< m/s, initial velocity of particle i seen from the wall (NULL: 0)
    double damping;         ///< b, N s/m, on each particle's velocity seen from the wall (>= 0)
    double dt;              ///< s, time step (> 0)
    cbm_chain_form form;
    cbm_chain_scheme scheme;
} cbm_chain_def;

/// Defaults: no links yet (set n, k, rest, mass), no damping, dt = 1e-3 s, inertial form,
/// explicit Euler.
CBM_API cbm_chain_def cbm_chain_def_default(void);

typedef struct cbm_chain cbm_chain;

/// Checks the definition (errors name the field) and copies it with its initial state.
CBM_API cbm_status cbm_chain_create(cbm_context *ctx, const cbm_chain_def *def, cbm_chain **out);
CBM_API void cbm_chain_destroy(cbm_chain *chain);

/// Advances `steps` time steps. CBM_E_NONFINITE if a value overflows (an unstable dt).
CBM_API cbm_status cbm_chain_step(cbm_chain *chain, size_t steps);

/// Time since the start, s (steps * dt).
CBM_API double cbm_chain_time(const cbm_chain *chain);
/// Positions of the particles, m from the wall (x_i = l_0 + ... + l_i), n values into x.
CBM_API void cbm_chain_positions(const cbm_chain *chain, double *x);
/// Velocities of the particles seen from the wall, m/s, n values into v.
CBM_API void cbm_chain_velocities(const cbm_chain *chain, double *v);
/// Kinetic plus spring energy, J.
CBM_API double cbm_chain_energy(const cbm_chain *chain);

#ifdef __cplusplus
}
#endif
#endif
