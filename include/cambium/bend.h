/* cambium: the `bend` workbench job: one branch or rod described by a small spec file, solved
 * for static equilibrium, optionally grown step by step. The spec format and every key are
 * documented in docs/bend.md.
 *
 * Spec: plain text, one `key = value` per line, `#` starts a comment, SI units, angles in
 * degrees. Unknown keys, repeated keys and bad values are errors reported as
 * `FILE:line:col: error: message` through the context's diagnostics.
 */
#ifndef CAMBIUM_BEND_H
#define CAMBIUM_BEND_H

#include "cambium/base.h"
#include "cambium/mech.h"
#include "cambium/fem_thesis.h"

#ifdef __cplusplus
extern "C" {
#endif

/// A parsed bend spec (SI units; angle in degrees as written).
typedef struct cbm_bend_spec {
    double length;         ///< m, final length of the rod
    long segments;         ///< number of segments of the final rod
    double radius;         ///< m, uniform radius (semi-axis a) when no taper is given
    double radius_base;    ///< m, radius at the base for a linear taper (0 = radius)
    double radius_tip;     ///< m, radius at the tip for a linear taper (0 = radius)
    double aspect;         ///< b / a of the elliptical section (a vertical), (0, 1]
    double youngs_modulus; ///< E, Pa
    double shear_modulus;  ///< G, Pa (0 = E / 16, a typical wood ratio)
    double density;        ///< kg/m^3
    double gravity;        ///< m/s^2, acting along -y
    double angle;          ///< elevation of the clamped base above the horizontal, degrees
    double tip_load;       ///< N, downward force at the tip
    double tip_mass;       ///< kg at the tip
    double tip_moment;     ///< N m at the tip, counter-clockwise in the x-y plane (lifts the tip)
    double rest_curvature; ///< 1/m, uniform rest curvature in the bending plane (+ = upward)
    double tropism;        ///< N, strength of the upward tropism force of new segments (0 = none)
    double modulus_of_rupture; ///< Pa, for the stress ratio and breakage (0 = none)
    cbm_mech_solver solver;
    double tolerance; ///< relative residual
    double alpha;     ///< relaxation factor
    long max_passes;  ///< 0 = the context's limit
    int krylov_dim;   ///< GMRES restart length
    cbm_mech_discretization discretization;
    long steps;            ///< growth steps, 0 = static
    double length_initial; ///< m, length at step 0 (primary growth up to `length`), 0 = length
    double radius_final;   ///< m, radius after the last step (secondary growth), 0 = none
    long push_unstable; ///< 1 (default): push an unstable equilibrium to a stable one; 0: keep it
    long threads;       ///< threads of the statics' sweeps (cbm_solve_def.threads): 0 = one per CPU
    /* solver = approx (Method A, cambium/approx.h) */
    cbm_approx_mode approx_mode; ///< corrected (default) or thesis
    double approx_p;             ///< relative position of the bending reversal, [0, 1]; 1 = none
    double approx_force;         ///< tip force / carried weight (> 0); 1 = the thesis
    cbm_approx_load approx_load; ///< thesis (default: the tip load) or calibrated (growth's)
    /* motion about the equilibrium (cambium/dynamics.h, docs/bend.md "Motion") */
    double duration;         ///< s of motion after the static solve; 0 = static only
    double dt;               ///< s, time step; 0 = 1/20 of the period of the 6th mode
    double damping_ratio;    ///< zeta of Rayleigh damping at the two lowest modes, [0, 1)
    double impulse_time;     ///< s, time at which impulse_force acts (for one step)
    double impulse_force;    ///< N, downward at the tip for one step; 0 = none
    double initial_tip_load; ///< N, downward: start from the deflection under it, released at 0
    int motion;              ///< 0 full (default), 1 modal (cbm_motion_method's values)
    long motion_modes;       ///< motion = modal: the lowest K modes (0: from motion_cut_hz)
    double motion_cut_hz;    ///< motion = modal, motion_modes 0: every mode below (Hz)
    long static_correction;  ///< motion = modal: 1 adds the truncated modes' static response
    /// rad/m, kappa^c of the rings of secondary growth: each is moulded on the current rate plus
    /// this curvature towards the vertical (Tresierras 2009 (3.14); docs/growth.md); 0 = none
    double control_curvature;
    /* the incremental FEM (solver = fem; cbm_fem_def, docs/bend.md "solver = fem") */
    long fem_increments;     ///< load increments of the static solve (default 20)
    double fem_shear_ratio;  ///< G / E in the elements (0 = the spec's G)
    double fem_sigma;        ///< reaction sensitivity of the maturation strain, [0, 1]
    double fem_phi;          ///< reaction direction, degrees from the upper side
    double fem_strain_min;   ///< a (strain)
    double fem_strain_max;   ///< b (strain)
    cbm_fem_axial fem_axial; ///< axial maturation resultant: formula or listing
    /* the thesis-compatible FE path (solver = fem, fem_path = thesis; docs/bend.md) */
    cbm_fem_path fem_path;       ///< clamped (default: the plant FEM) or thesis
    long fem_elements;           ///< n_FE of the thesis path, 5 .. segments (default 10)
    cbm_fem_support fem_support; ///< free (default: the listing's pseudo-inverse) or clamped
    long fem_primary_tropism;    ///< 1: every new element starts at the clamp's angle
    int fem_update;              ///< 0 listing (default: beta += theta_y, lifts), 1 sagging
    int fem_stiffness;           ///< 0 printed (default: the listing's K, D2), 1 symmetric
} cbm_bend_spec;

/// Defaults: length 1, 100 segments, radius 0.01, aspect 1, E 1e10, density 600, gravity 9.81,
/// angle 0, no loads, fast solver, tolerance 1e-8, alpha 0.5, Krylov 20, staggered, static.
CBM_API cbm_bend_spec cbm_bend_spec_default(void);

/// Parses spec text (`len` bytes, need not be NUL-terminated). `file` names the spec in
/// messages. On error returns CBM_E_SYNTAX (malformed line) or CBM_E_SEMANTIC (unknown key, bad
/// or inconsistent value) after reporting every problem found as a diagnostic.
CBM_API cbm_status cbm_bend_spec_parse(cbm_context *ctx, const char *text, size_t len,
                                       const char *file, cbm_bend_spec *out);

/// Builds the rod of the spec at its initial state (length_initial, radius) without solving.
CBM_API cbm_status cbm_bend_build(cbm_context *ctx, const cbm_bend_spec *spec, cbm_plant **out);

/// What cbm_bend_run did.
typedef struct cbm_bend_result {
    cbm_solve_stats stats;  ///< of the last solve; passes summed over all growth steps
    long steps_done;        ///< growth steps completed
    size_t broken_segments; ///< segments removed by breakage (stress above the MOR)
} cbm_bend_result;

/// Builds, grows (if steps > 0) and solves. *out receives the plant (also on
/// CBM_E_NOT_CONVERGED, so its state can be reported); the caller destroys it.
CBM_API cbm_status cbm_bend_run(cbm_context *ctx, const cbm_bend_spec *spec, cbm_plant **out,
                                cbm_bend_result *result);

/// One row of the node table, from base to tip.
typedef struct cbm_bend_node {
    double s;         ///< m, arc length from the base
    double x, y, z;   ///< m (x horizontal away from the base in the bending plane, y up)
    double angle_deg; ///< elevation of the tangent above the horizontal, degrees
    double curvature; ///< 1/m, in-plane, counter-clockwise positive
    double moment;    ///< N m, bending moment of the loads beyond the node, ccw positive
    double stress;    ///< Pa, peak bending stress at the node
} cbm_bend_node;

/// Fills n_nodes = segment count + 1 rows (for a single unbranched rod).
CBM_API cbm_status cbm_bend_nodes(const cbm_plant *plant, cbm_bend_node *nodes, size_t n_nodes);

/* ---- continuation of the rod's equilibria in a parameter (docs/bend.md, "Continuation") ---- */

/// The parameter a continuation varies.
typedef enum cbm_bend_param {
    CBM_BEND_PARAM_ANGLE,    ///< the clamp's elevation, degrees (any angle, not only -90 .. 90)
    CBM_BEND_PARAM_GRAVITY,  ///< the gravitational acceleration, m/s^2 (the load of the weight)
    CBM_BEND_PARAM_DENSITY,  ///< the wood's density, kg/m^3 (the weight, not the tip mass)
    CBM_BEND_PARAM_TIP_LOAD, ///< the downward tip force, N
    CBM_BEND_PARAM_LENGTH    ///< the rod's length, m (every segment scaled alike)
} cbm_bend_param;

/// How the branch is followed.
typedef enum cbm_bend_continuation_method {
    /// pseudo-arclength: predictor along the branch's tangent, Newton on the equilibrium bordered
    /// by the arclength condition; goes round folds onto the unstable arcs (default)
    CBM_BEND_CONTINUE_ARCLENGTH,
    /// natural-parameter steps: the parameter only moves forward; at a fold the rod jumps
    CBM_BEND_CONTINUE_NATURAL
} cbm_bend_continuation_method;

/// Why an arclength continuation stopped.
typedef enum cbm_bend_branch_end {
    CBM_BEND_END_TO,   ///< the branch reached `to` (always so for the natural method)
    CBM_BEND_END_FROM, ///< the branch turned back and left the range at `from`
    CBM_BEND_END_LIMIT ///< max_points equilibria were traced (a closed branch, or a long one)
} cbm_bend_branch_end;

/// How to follow the branch from `from` to `to` with warm starts.
typedef struct cbm_bend_continuation_def {
    cbm_bend_param param; ///< default CBM_BEND_PARAM_ANGLE
    double from, to;      ///< the parameter's range (degrees or m/s^2); from != to
    long steps;           ///< equal steps of the range (>= 1; default 60)
    /// a step whose tip turns by more than this (degrees) has left the branch (default 10)
    double max_turn_deg;
    /// the bisection stops when the step is below this fraction of |to - from| (default 1e-7)
    double min_step;
    cbm_bend_continuation_method method; ///< default CBM_BEND_CONTINUE_ARCLENGTH
    /// arclength only: where the branch followed loses stability without a fold (a
    /// bifurcation: a straight column past Greenhill's load), leave it along the lowest mode
    /// onto the bifurcating branch (its side: the tip moving towards +x, or +z when the mode
    /// is out of the plane) and follow that one (default false)
    bool switch_branch;
    /// with switch_branch: the bifurcation met along the trace to leave at, counted from 1
    /// (default 1, the first); 0 leaves at every one met, on the new branches too. At the k-th
    /// the mode followed is the one whose eigenvalue crosses 0 there (the k-th buckling mode of
    /// a column), not the lowest
    long switch_at;
    /// arclength only: the most equilibria traced before stopping (default 100000)
    size_t max_points;
} cbm_bend_continuation_def;

CBM_API cbm_bend_continuation_def cbm_bend_continuation_def_default(void);

/// One equilibrium of the branch.
typedef struct cbm_bend_branch_point {
    double param;               ///< the parameter's value
    double tip_angle_deg;       ///< in-plane angle of the tip tangent, continuous along the branch
    double tip_x, tip_y, tip_z; ///< m, relative to the base
    size_t unstable_modes;      ///< negative eigenvalues of the energy's Hessian
    double lowest_eigenvalue;   ///< lowest eigenvalue of S^-1 J (0 at a fold)
    /// the state has the zero mode of a symmetry (a round rod clamped along gravity turned about
    /// the vertical); it is not counted in unstable_modes, whatever sign rounding gave it
    bool symmetry_mode;
    double energy; ///< J, total potential energy
    bool jumped;   ///< reached by a jump from a fold, not along the branch
} cbm_bend_branch_point;

/// An event on the branch: a fold (the branch cannot be continued with the parameter going
/// forward) or a change of the number of unstable modes along it.
typedef struct cbm_bend_fold {
    bool fold;                  ///< true: a fold; false: a change of stability along the branch
    cbm_bend_branch_point at;   ///< the last equilibrium before the event (within the bracket)
    double bracket;             ///< the event lies in [at.param, at.param + bracket]
    bool has_jump;              ///< fold only: a jump target was found
    cbm_bend_branch_point jump; ///< fold only: the equilibrium reached just past the fold
    bool switched; ///< stability change only: the continuation left here onto the new branch
    /// stability change only: a bifurcation (the count rose without a fold), numbered from 1 in
    /// the order met; 0 for other events
    long bifurcation;
} cbm_bend_fold;

/// A traced branch (owned; release with cbm_bend_branch_free).
typedef struct cbm_bend_branch {
    cbm_bend_branch_point *points; ///< in the order they were reached
    size_t n_points;
    cbm_bend_fold *folds;
    size_t n_folds;
    cbm_bend_branch_end end; ///< why the continuation stopped
} cbm_bend_branch;

/// Solves the spec's rod at def->from (the spec's push_unstable applies to this first solve),
/// then follows its equilibria.
///
/// Arclength (default): steps of equal length in (Omega, parameter) along the branch's tangent,
/// each corrected by Newton on the equilibrium bordered by the arclength condition (the tree
/// factorisation solves both right-hand sides exactly); the step halves when Newton fails or
/// the tip turns by more than max_turn_deg. A fold (the tangent's parameter component changes
/// sign) and a change of the number of unstable modes are located by bisection of the step;
/// at a fold the jump target (the equilibrium reached just past it with the push) is reported
/// and the branch is followed round the fold onto its unstable arc. It stops when the
/// parameter reaches `to` (landing on it exactly), leaves the range at `from`, or after
/// max_points equilibria (out->end says which).
///
/// Natural (CBM_BEND_CONTINUE_NATURAL): steps from def->from to def->to: each step is warm-started
/// from the last equilibrium without any push; a step that does not converge, turns the tip by more
/// than max_turn_deg or changes the number of unstable modes is halved. When a step below min_step
/// still fails, the fold is located (bisection on the parameter) and the rod jumps: it is solved
/// just past the fold with push_unstable, and the branch continues from the equilibrium it reaches.
/// Needs the fast solver, no growth steps and no motion. On failure *out is empty.
CBM_API cbm_status cbm_bend_continue(cbm_context *ctx, const cbm_bend_spec *spec,
                                     const cbm_bend_continuation_def *def, cbm_bend_branch *out);

/* ---- the same for any plant (docs/bend.md, "Continuation of a branched plant") ---- */

/// How to continue a plant built by the caller.
typedef struct cbm_plant_continuation_def {
    /// the trace; param CBM_BEND_PARAM_ANGLE (the clamp's elevation, degrees, about the base's
    /// position) or CBM_BEND_PARAM_GRAVITY (|g| along -y) only: the others mean something for a
    /// bend spec's rod only
    cbm_bend_continuation_def cont;
    cbm_solve_def solve; ///< the solver must be CBM_MECH_NEWTON (the default here)
    /// the segment whose distal tip the branch points report; SIZE_MAX (default): the main
    /// axis's tip (cbm_plant_main_tip)
    size_t tip_segment;
    /// m: scales the continuity test and the metric (a rod's L); 0 (default): the main axis's
    /// length
    double length;
} cbm_plant_continuation_def;

CBM_API cbm_plant_continuation_def cbm_plant_continuation_def_default(void);

/// The tip segment of the main axis: from the root, each segment's continuation child (its
/// first child) in turn; SIZE_MAX for an empty plant.
CBM_API size_t cbm_plant_main_tip(const cbm_plant *plant);

/// cbm_bend_continue for a plant with one root (segment 0) and any branching, which the caller
/// builds (rest state, loads, rings): the same methods, stability count, fold and bifurcation
/// events. The plant is changed: it is left at the last state traced, with the parameter's
/// last value set. cbm_bend_continue is this with the plant its spec builds.
CBM_API cbm_status cbm_plant_continue(cbm_context *ctx, cbm_plant *plant,
                                      const cbm_plant_continuation_def *def, cbm_bend_branch *out);
CBM_API void cbm_bend_branch_free(cbm_bend_branch *branch);

#ifdef __cplusplus
}
#endif
#endif
