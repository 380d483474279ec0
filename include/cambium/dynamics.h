/* cambium: small oscillations of a plant about its static equilibrium (issue 11): natural
 * frequencies and mode shapes, and time-stepped motion under impulses and point loads.
 *
 * The model is the statics' own segment model (cbm_plant): rigid segments joined by 3-DOF
 * elastic joints with the joint rigidities the solver uses (rings, staggered or chain
 * discretisation), each segment a uniform elliptical rod (mass per length from the rings, rotary
 * inertia of the solid outer ellipse), point masses (leaves, fruit) at the distal nodes. The
 * coordinates are the small rotations q_k (world components) of every joint about its node,
 * applied to everything the joint carries. About the equilibrium the motion obeys
 *     M q'' + C q' + K q = f(t),
 * K = joint stiffness R diag(C_joint / d) R^T plus the geometric stiffness of the dead loads
 * (weights of the segments and point masses, tip forces) at the equilibrium (an upright stem
 * sways slower than without gravity, a hanging one faster), M the mass matrix of the segments
 * and point masses. Every product and every solve with K + c M costs O(n) (a tree elimination
 * of 6x6 spatial blocks, src/mech/dyn_tree.c). Design, derivation and limits: docs/dynamics.md.
 *
 * The plant must be at equilibrium (after cbm_plant_solve) when an analysis is created (its state
 * is read, not recomputed: after an edit, solve or evaluate first); the analysis keeps its own
 * copy of everything it needs and does not see later edits.
 */
#ifndef CAMBIUM_DYNAMICS_H
#define CAMBIUM_DYNAMICS_H

#include "cambium/base.h"
#include "cambium/mech.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Natural frequencies (Hz, ascending) of the plant about its current equilibrium: the lowest
/// `count` eigenvalues of K phi = omega^2 M phi by shift-invert Lanczos (docs/dynamics.md).
/// freqs_hz[0..count) receive the frequencies; shapes (optional, count x 3n doubles, mode after
/// mode) receive the mass-normalised mode shapes (joint rotations, world, rad). If the plant has
/// fewer than count degrees of freedom (3 per segment), the rest of freqs_hz is NAN.
/// CBM_E_INVALID for count 0, an empty plant or a massless segment; CBM_E_RUNTIME if the
/// equilibrium is unstable (K not positive definite: a column past its buckling length);
/// CBM_E_NOT_CONVERGED if the Ritz values did not converge.
CBM_API cbm_status cbm_plant_modes(const cbm_plant *plant, size_t count, double *freqs_hz,
                                   double *shapes);

/// How a motion integrates (docs/dynamics.md, "Modal reduction").
typedef enum cbm_motion_method {
    /// All 3n joint rotations: O(n) per step (the default).
    CBM_MOTION_FULL = 0,
    /// The lowest K modes only (computed once at creation, O(K n)): O(K) per step without wind,
    /// with gusts O(K^3) (with a gust field of G grid points O(K^2 G + K^3)); the forces are
    /// projected on the modes, the wind's drag linearised
    /// about the still plant (quasi-steady, with its aerodynamic damping); the full shape is
    /// rebuilt only when asked (cbm_motion_rotations, cbm_motion_displacement). An approximation:
    /// the truncated modes' response is dropped (docs/dynamics.md states its error).
    CBM_MOTION_MODAL
} cbm_motion_method;

/// Time stepping (Newmark's average acceleration: implicit, unconditionally stable, second
/// order, energy-conserving without damping).
typedef struct cbm_motion_def {
    double dt;            ///< s (> 0); default 1e-3
    double damping_ratio; ///< zeta of Rayleigh damping, exact at the two lowest modes; default 0
    /// Rayleigh coefficients added to those of damping_ratio: C += alpha M + beta K
    double rayleigh_alpha;    ///< 1/s, default 0
    double rayleigh_beta;     ///< s, default 0
    cbm_motion_method method; ///< default CBM_MOTION_FULL
    /// CBM_MOTION_MODAL: the number of modes K (0: from mode_cut_hz); at most 3n. Default 0.
    size_t modes;
    /// CBM_MOTION_MODAL with modes 0: every mode below this frequency (Hz, > 0). Default 0.
    double mode_cut_hz;
    /// CBM_MOTION_MODAL: add the truncated modes' quasi-static response to the load (the
    /// mode-acceleration method, docs/dynamics.md "Static correction") to the rebuilt shape
    /// (cbm_motion_rotations, cbm_motion_displacement); O(n) an output, not a step. Default false.
    bool static_correction;
} cbm_motion_def;

/// Defaults: dt 1e-3 s, no damping.
CBM_API cbm_motion_def cbm_motion_def_default(void);

typedef struct cbm_motion cbm_motion;

/// A motion about the plant's current equilibrium, at rest (q = 0). Copies what it needs.
CBM_API cbm_status cbm_motion_create(const cbm_plant *plant, const cbm_motion_def *def,
                                     cbm_motion **out);
CBM_API void cbm_motion_destroy(cbm_motion *m);

/// Starts from the linear static deflection under a force (N, world) at the distal node of seg
/// (K q = f), at rest; the force is released at t = 0.
CBM_API cbm_status cbm_motion_start_deflected(cbm_motion *m, size_t seg, cbm_vec3 force);

/// Adds a force (N, world) at the distal node of seg to the load of the next step only (an
/// impulse of force * dt; call before each step for a sustained tug).
CBM_API cbm_status cbm_motion_add_force(cbm_motion *m, size_t seg, cbm_vec3 force);

/// One time step of dt. The forces added since the last step act at the new time.
CBM_API cbm_status cbm_motion_step(cbm_motion *m);

/// Time (s), kinetic energy 1/2 q'.M q' and potential energy 1/2 q.K q (J, about the
/// equilibrium) of the current state; any pointer may be NULL.
CBM_API void cbm_motion_state(cbm_motion *m, double *t, double *kinetic, double *potential);

/// The time step (s) of the motion.
CBM_API double cbm_motion_dt(const cbm_motion *m);

/// Current displacement (world, m) of the distal node of seg from the equilibrium.
CBM_API cbm_status cbm_motion_displacement(const cbm_motion *m, size_t seg, cbm_vec3 *out);

/// The joint rotations q (3n doubles, world, rad) of the current state; valid until the next
/// step.
CBM_API const double *cbm_motion_rotations(const cbm_motion *m);

/* ---- wind (docs/dynamics.md, "Wind") ---- */

/// Vertical profile of the mean wind speed.
typedef enum cbm_wind_profile {
    CBM_WIND_LOG,    ///< U(z) = U_ref ln((z - d) / z0) / ln((z_ref - d) / z0), 0 below d + z0
    CBM_WIND_POWER,  ///< U(z) = U_ref (z / z_ref)^exponent, 0 at and below the base
    CBM_WIND_UNIFORM ///< U(z) = U_ref
} cbm_wind_profile;

/// Mean wind and drag: on wood, 1/2 rho C_d (a + b) l |v_n| v_n with v_n the wind's component
/// normal to the segment; on the organs at the distal nodes (leaves, fruit: the point masses),
/// 1/2 rho C_d A |U| U with A = point mass * organ_area_per_kg. Heights z are above the base.
typedef struct cbm_wind_def {
    cbm_vec3 direction;       ///< horizontal direction the wind blows to; default (1, 0, 0)
    cbm_wind_profile profile; ///< default CBM_WIND_LOG
    double reference_height;  ///< z_ref, m, where the speed is U_ref; default 10
    double roughness;         ///< z0, m (log profile); default 0.1
    double displacement;      ///< d, m (log profile); default 0
    double exponent;          ///< power-law exponent; default 1/7
    double air_density;       ///< kg/m^3; default 1.226
    double drag_wood;         ///< C_d of the segments (cylinders); default 1.0
    double drag_organs;       ///< C_d of the organs; default 0.5
    double organ_area_per_kg; ///< m^2 of drag area per kg of point mass; default 0 (none)
    /* Leaves and fruit apart (docs/dynamics.md, "Drag of leaves and fruit"), at the distal
     * nodes, in addition to the lumped organ drag above (set organ_area_per_kg 0 with them):
     * leaves as flat plates that reconfigure, 1/2 rho C_d A |w| w (|w| / U_0)^B above U_0;
     * fruit as one sphere a node, A = pi r^2 with r from the fruit's mass and density. */
    const double *leaf_area;  ///< per segment: one-sided leaf area at its distal node, m^2
                              ///< (read while the drag is built, not kept); NULL: no leaf drag
    const double *fruit_mass; ///< per segment: fruit at its distal node, kg; NULL: no fruit drag
    double drag_leaf;         ///< C_d of a leaf, a flat plate across the flow; default 1.17
    double leaf_vogel;        ///< Vogel exponent B (drag ~ U^(2+B) above U_0); default -2/3
    double leaf_vogel_speed;  ///< U_0, m/s, where reconfiguration starts; default 5
    double drag_fruit;        ///< C_d of a fruit (a sphere); default 0.47
    double fruit_density;     ///< kg/m^3; default 800
} cbm_wind_def;

/// Defaults as documented per field.
CBM_API cbm_wind_def cbm_wind_def_default(void);

/// Mean wind speed (m/s) at height z above the base for reference speed u_ref.
CBM_API double cbm_wind_speed(const cbm_wind_def *def, double u_ref, double z);

/// Critical wind speed of one axis: the reference speed U_ref at which the static drag of the
/// mean wind plus the weight (the equilibrium's moments) brings the peak bending stress of some
/// segment of the axis to its modulus of rupture (geometry of the equilibrium held fixed).
typedef struct cbm_wind_critical {
    size_t first;   ///< first segment of the axis (the stem's root or the branch's base)
    int32_t order;  ///< 0 for the stem, 1 for a first-order branch
    double speed;   ///< m/s; 0 if it already breaks under its weight, INFINITY if never,
                    ///< NAN if no segment has a modulus of rupture
    size_t weakest; ///< the segment that reaches it first
    double height;  ///< m above the base of that segment's proximal node
} cbm_wind_critical;

/// One row for the stem (the segments of order 0) and one per first-order branch (an order-1
/// segment on an order-0 parent, with everything it carries), in segment order, into
/// out[0..max); *count receives the number of rows (may exceed max: then only max are stored).
/// The plant must be at equilibrium.
CBM_API cbm_status cbm_plant_critical_wind(const cbm_plant *plant, const cbm_wind_def *def,
                                           cbm_wind_critical *out, size_t max, size_t *count);

/* ---- loads in time: wind drag with gusts, base motion (docs/dynamics.md, "Loads in time") ---- */

/// Gusts: one longitudinal turbulence series u'(t) for the whole plant (spatially coherent),
/// synthesised from the EN 1991-1-4 (Annex B) spectrum n S(n) / sigma^2 = 6.8 f_L / (1 +
/// 10.2 f_L)^(5/3), f_L = n L / U_ref, as a sum of harmonics at log-spaced frequencies with
/// seeded random phases. The wind at height z is U(z) (1 + u'(t) / U_ref) along the direction.
/// With coherence_decay > 0, u'(p, t) is a field with the same spectrum at every point and
/// Davenport's coherence between points (docs/dynamics.md, "Gust field").
typedef struct cbm_gust_def {
    double intensity;    ///< sigma_u / U_ref; default 0 (steady wind)
    double length_scale; ///< L, m; default 0: EN 1991-1-4's 300 (z_ref / 200)^(0.67 + 0.05 ln z0)
    double f_min, f_max; ///< Hz, band of the harmonics; default 0.002 and 20
    int32_t harmonics;   ///< default 400
    uint64_t seed;       ///< default 1
    /// Davenport's decay constant a of the coherence exp(-a f r / U_ref) between points r apart
    /// across the wind; > 0 makes the gusts a spatially correlated field (Veers' method on a grid
    /// over the crown, interpolated to the segments, docs/dynamics.md "Gust field"); default 0:
    /// one series for the whole plant (the limit of infinite coherence length)
    double coherence_decay;
    /// grid points of the field along the crown's longer side across the wind (2..16); default 6
    int32_t grid;
} cbm_gust_def;

/// Defaults as documented per field.
CBM_API cbm_gust_def cbm_gust_def_default(void);

/// Wind on a motion from the next step on: drag 1/2 rho C_d A |v_rel| v_rel with the velocity of
/// the air relative to the moving segment (normal to its axis) and organ, so that the drag also
/// damps; the mean speed u_ref (m/s at the wind's reference height) with its profile; gust may be
/// NULL (steady). The geometry is the equilibrium's (the motion is linear); the drag at the step's
/// end is found by fixed-point iteration on the Newmark step (docs/dynamics.md).
CBM_API cbm_status cbm_motion_set_wind(cbm_motion *m, const cbm_wind_def *wind, double u_ref,
                                       const cbm_gust_def *gust);

/// The reference speed U_ref (1 + u'(t) / U_ref) of the wind at time t (s): the gust series.
CBM_API double cbm_motion_wind_at(const cbm_motion *m, double t);

/// Starts at rest from the linear static deflection under the drag of the mean wind (K q = f)
/// at t = 0; the wind must be set.
CBM_API cbm_status cbm_motion_start_wind_static(cbm_motion *m);

/// Prescribed base motion: the base's translational acceleration (world, m/s^2) at the time of
/// the next step (call before each step; 0 when not called). The motion is solved in the base's
/// frame (the fictitious force -m a on every mass), the base's velocity and displacement are
/// integrated by the same trapezoidal rule from rest; cbm_motion_displacement stays relative to
/// the base.
CBM_API cbm_status cbm_motion_base_acceleration(cbm_motion *m, cbm_vec3 acc);

/// The base's current displacement (world, m) from its start.
CBM_API cbm_vec3 cbm_motion_base_displacement(const cbm_motion *m);

/// Starts at time 0 from joint rotations q and rates v (3n doubles each, world, rad and rad/s;
/// NULL: zero), e.g. a mode shape; the acceleration follows from the equation of motion with the
/// wind (if set) at those rates.
CBM_API cbm_status cbm_motion_start_state(cbm_motion *m, const double *q, const double *v);

/// Fixed-point iterations the last step's drag took (0 without wind).
CBM_API int cbm_motion_drag_iterations(const cbm_motion *m);

/// The number of modes a CBM_MOTION_MODAL motion integrates (0 for CBM_MOTION_FULL); freqs_hz
/// (optional) receives a pointer to their frequencies (Hz, ascending), valid while m lives.
CBM_API size_t cbm_motion_modes(const cbm_motion *m, const double **freqs_hz);

/* ---- the bend workbench's motion (docs/bend.md, "Motion") ---- */

/// One row of a bend motion: time, tip position (world, m), kinetic and potential energy (J,
/// about the equilibrium).
typedef struct cbm_motion_row {
    double t, tip_x, tip_y, tip_z, kinetic, potential;
} cbm_motion_row;

/// Called once per row (t = 0, then after every step); a non-OK return stops the run with it.
typedef cbm_status (*cbm_motion_row_fn)(void *user, const cbm_motion_row *row);

struct cbm_bend_spec;

/// The motion a bend spec asks for (duration, dt, damping_ratio, impulse_time, impulse_force,
/// initial_tip_load) of the solved rod `plant` about its equilibrium; the tip is the distal node
/// of the last segment. *dt_used (optional) receives the step (the spec's dt, or 1/20 of the
/// period of the 6th mode when 0).
CBM_API cbm_status cbm_bend_motion(const cbm_plant *plant, const struct cbm_bend_spec *spec,
                                   cbm_motion_row_fn row, void *user, double *dt_used);

#ifdef __cplusplus
}
#endif
#endif
