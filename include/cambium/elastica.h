/* cambium: the continuous planar elastica of a growing stem (Tresierras 2009, ch. 2 and 4) and of
 * branched plants (ch. 5): every equilibrium of a clamped rod under its own weight, found by
 * shooting from the tip over the tip angle, the S-curve (base angle, base curvature, energy) with
 * its folds (jumping points), stable and unstable arcs, jump targets and the hysteresis of a
 * base-angle sweep; and the equilibria of a tree of such rods. docs/elastica.md has the
 * equations, the numerics and the file formats.
 *
 * Units are whatever the caller uses consistently (SI in the `elastica` command's dimensional
 * mode; L = D = 1 and a weight per length alpha in its non-dimensional mode). Angles are radians
 * here (degrees only in the spec and the outputs of the command). Angles are measured from the
 * horizontal, counter-clockwise positive; y is up; gravity acts along -y.
 *
 *     cbm_elastica_piece pc = cbm_elastica_piece_default(); // L = 1, D = 1, w = 0
 *     pc.w0 = pc.w1 = 15;                                   // alpha = w L^3 / D = 15
 *     cbm_elastica_rod rod = cbm_elastica_rod_default();
 *     rod.pieces = &pc, rod.n_pieces = 1;
 *     cbm_elastica_scurve *sc;
 *     cbm_elastica_scurve_compute(ctx, &rod, NULL, &sc);    // theta_tip over [-90, 270] deg
 *     ... sc->folds[k].theta_base, sc->folds[k].target ...
 *     cbm_elastica_scurve_destroy(ctx, sc);
 */
#ifndef CAMBIUM_ELASTICA_H
#define CAMBIUM_ELASTICA_H

#include "cambium/base.h"
#include "cambium/bend.h"

#ifdef __cplusplus
extern "C" {
#endif

/// One piece of a rod, base to tip. Within a piece the stiffness D and the weight per length w
/// follow a linear radius taper: D^(1/4) and w^(1/2) are linear in s (constant when D0 == D1 and
/// w0 == w1). D, w and the rest curvature may jump between pieces.
typedef struct cbm_elastica_piece {
    double length;         ///< > 0
    double D0, D1;         ///< flexural rigidity EI at the start and the end of the piece, > 0
    double w0, w1;         ///< weight per length rho g at the start and the end, >= 0
    double rest_curvature; ///< kappa^g, the curvature of the unloaded piece (ccw positive)
} cbm_elastica_piece;

/// A rod clamped at its base (s = 0), loaded at its tip by a vertical dead force and a moment.
typedef struct cbm_elastica_rod {
    const cbm_elastica_piece *pieces; ///< n_pieces, base to tip (not copied)
    size_t n_pieces;
    double tip_force;  ///< downward force at the tip (n_l; negative pulls up)
    double tip_moment; ///< moment applied at the tip, counter-clockwise positive
    /// n_pieces downward point forces, one at the distal end of each piece (fruit, foliage
    /// lumped at a growth segment's tip); NULL: none. Single rods only (plants ignore it).
    const double *piece_loads;
} cbm_elastica_rod;

CBM_API cbm_elastica_piece cbm_elastica_piece_default(void); ///< length 1, D 1, w 0, straight
CBM_API cbm_elastica_rod cbm_elastica_rod_default(void);     ///< no pieces, no tip loads

/// The equilibrium with a given tip angle: one backward integration from the tip (s = L) to the
/// base, with the Jacobi field eta = d theta / d theta_tip integrated alongside.
typedef struct cbm_elastica_state {
    double theta_tip, theta_base; ///< rad
    double moment_base;           ///< D(0) nu(0), the bending moment at the clamp
    double curvature_base;        ///< kappa(0) = nu(0) + kappa^g(0)
    double strain_base;           ///< nu(0) = kappa(0) - kappa^g(0)
    double tip_x, tip_y;          ///< tip position relative to the base
    double energy;                ///< V: strain + weight potential (base height 0) - M theta_tip
    double dbase_dtip;            ///< d theta_base / d theta_tip = eta(0); 0 at a fold
    double dmoment_dtip;          ///< d moment_base / d theta_tip
    int index;                    ///< Morse index of the second variation (Sturm count), 0 stable
} cbm_elastica_state;

/// Integrates one equilibrium from the tip angle. CBM_E_INVALID for a bad rod.
CBM_API cbm_status cbm_elastica_shoot(cbm_context *ctx, const cbm_elastica_rod *rod,
                                      double theta_tip, cbm_elastica_state *out);

/// The shape of the equilibrium with tip angle theta_tip at n >= 2 points equally spaced in arc
/// length from the base (x, y relative to the base; any of x, y, theta may be NULL).
CBM_API cbm_status cbm_elastica_shape(cbm_context *ctx, const cbm_elastica_rod *rod,
                                      double theta_tip, size_t n, double *x, double *y,
                                      double *theta);

/// How an S-curve is traced: theta_tip from min to max with steps adapted so that consecutive
/// points are about `ds` apart in the plane (theta_base in rad, curvature_base * L).
typedef struct cbm_elastica_scan_def {
    double theta_tip_min, theta_tip_max; ///< rad; default -pi/2 .. 3 pi/2 (one full period)
    double ds;                           ///< target arc-length step (default 0.02)
    double max_step, min_step;           ///< bounds of the theta_tip step, rad (2 deg, 1e-7)
    size_t max_points;                   ///< 0: 200000
} cbm_elastica_scan_def;

CBM_API cbm_elastica_scan_def cbm_elastica_scan_def_default(void);

/// A fold (jumping point, d theta_base / d theta_tip = 0) and where the rod jumps from it: the
/// lowest-energy other equilibrium at the same base angle (modulo 360 degrees).
typedef struct cbm_elastica_fold {
    cbm_elastica_state at;     ///< the fold, refined to |dbase_dtip| < 1e-9
    bool has_target;           ///< false when the fold is the only equilibrium at its angle
    cbm_elastica_state target; ///< theta_tip shifted so that target.theta_base == at.theta_base
} cbm_elastica_fold;

/// A traced S-curve (owned; release with cbm_elastica_scurve_destroy).
typedef struct cbm_elastica_scurve {
    cbm_elastica_state *points; ///< in order of increasing theta_tip
    size_t n_points;
    cbm_elastica_fold *folds; ///< in order of increasing theta_tip
    size_t n_folds;
    double length;         ///< L of the rod (sum of the pieces)
    double stiffness_base; ///< D(0), the unit of moment * L used for the arc length
} cbm_elastica_scurve;

/// Traces the S-curve of the rod (def NULL: defaults), finds and refines its folds and their jump
/// targets. CBM_E_LIMIT when max_points is not enough.
CBM_API cbm_status cbm_elastica_scurve_compute(cbm_context *ctx, const cbm_elastica_rod *rod,
                                               const cbm_elastica_scan_def *def,
                                               cbm_elastica_scurve **out);
CBM_API void cbm_elastica_scurve_destroy(cbm_context *ctx, cbm_elastica_scurve *sc);

/// Every equilibrium on the traced curve whose base angle is theta_base modulo 2 pi (roots of
/// theta_base(theta_tip) bracketed by the samples, refined by safeguarded Newton to 1e-12 rad),
/// each reported with theta_tip shifted so that its base angle is exactly theta_base. With one
/// full period of theta_tip traced these are all the equilibria of the rod. Fills up to `max`
/// states in order of increasing theta_tip and sets *n to the number found (which may exceed
/// max).
CBM_API cbm_status cbm_elastica_equilibria(cbm_context *ctx, const cbm_elastica_rod *rod,
                                           const cbm_elastica_scurve *sc, double theta_base,
                                           cbm_elastica_state *out, size_t max, size_t *n);

/// One event of a quasi-static base-angle sweep.
typedef struct cbm_elastica_jump {
    cbm_elastica_state from, to; ///< the fold and the equilibrium it jumps to
} cbm_elastica_jump;

/// A quasi-static sweep of the clamp angle from `from` to `to` (rad; either direction): starts
/// on the lowest-energy equilibrium at `from`, follows it along the curve while it stays stable,
/// and at a fold jumps to the lowest-energy equilibrium at that angle. Writes the path (base
/// angle, state) as at most max_path states and the jumps (up to max_jumps), with their counts.
/// Sweeping up and then down shows the hysteresis.
CBM_API cbm_status cbm_elastica_sweep(cbm_context *ctx, const cbm_elastica_rod *rod,
                                      const cbm_elastica_scurve *sc, double from, double to,
                                      cbm_elastica_state *path, size_t max_path, size_t *n_path,
                                      cbm_elastica_jump *jumps, size_t max_jumps, size_t *n_jumps);

/* ---- branched plants (Tresierras ch. 5) ---- */

/// One branch of a plant: a rod (its pieces) whose base sits at its parent's tip, turned by
/// `offset` from the parent's tip tangent (5.3). Branch 0 is the base branch (parent -1),
/// clamped; every other branch has a parent with a smaller index.
typedef struct cbm_elastica_branch {
    int parent;                       ///< index of the parent branch; -1 for branch 0
    double offset;                    ///< rad, theta_base(child) = theta_tip(parent) + offset
    const cbm_elastica_piece *pieces; ///< base to tip (not copied)
    size_t n_pieces;
    double tip_force;  ///< extra downward force at the branch's tip (fruit)
    double tip_moment; ///< extra moment at the branch's tip
} cbm_elastica_branch;

/// One equilibrium of a plant: each branch's tip and base angle, base moment, and the whole
/// plant's energy and Morse index (discrete second variation of the whole tree).
typedef struct cbm_elastica_plant_state {
    double *theta_tip;     ///< per branch, rad
    double *theta_base;    ///< per branch, rad
    double *moment_base;   ///< per branch
    double *tip_x, *tip_y; ///< per branch, tip position relative to the plant's base
    double energy;         ///< V of the whole plant
    int index;             ///< Morse index (0 stable)
    int branch_index0;     ///< Morse index of the base branch alone with its tip loads as dead
} cbm_elastica_plant_state;

typedef struct cbm_elastica_plant_def {
    cbm_elastica_scan_def scan; ///< the theta_tip scan of every branch (one full period default)
    size_t hessian_elements;    ///< elements per branch of the stability test (default 400)
    size_t max_states;          ///< 0: 4096; more equilibria is CBM_E_LIMIT
} cbm_elastica_plant_def;

CBM_API cbm_elastica_plant_def cbm_elastica_plant_def_default(void);

/// The equilibria of a plant at one base angle (rad), by composite S-curves passed upstream
/// and reconstruction downstream; *out (n_out states, each with n_branches entries) is released
/// with cbm_elastica_plant_states_destroy.
CBM_API cbm_status cbm_elastica_plant_equilibria(cbm_context *ctx,
                                                 const cbm_elastica_branch *branches,
                                                 size_t n_branches,
                                                 const cbm_elastica_plant_def *def,
                                                 double theta_base, cbm_elastica_plant_state **out,
                                                 size_t *n_out);
CBM_API void cbm_elastica_plant_states_destroy(cbm_context *ctx, cbm_elastica_plant_state *s,
                                               size_t n, size_t n_branches);

/* ---- the spec of the `elastica` command (docs/elastica.md) ---- */

/// The most branches a spec may add to its base rod.
#define CBM_ELASTICA_MAX_BRANCHES 63

/// One `branch = ...` line of a spec.
typedef struct cbm_elastica_branch_spec {
    int parent;            ///< 0: the base rod; k: the k-th branch line
    double offset;         ///< degrees
    double length;         ///< m (dimensional) or in units of the base length; 0: the base's
    double radius;         ///< m, dimensional mode; 0: the base's radius
    double radius_tip;     ///< m, dimensional mode; 0: = radius
    double stiffness;      ///< D / D(base), non-dimensional mode (default 1)
    double weight;         ///< w / w(base), non-dimensional mode (default 1)
    double rest_curvature; ///< kappa^g
    double tip_load;       ///< downward force at the branch's tip
    double tip_mass;       ///< kg at the tip (dimensional mode)
    double tip_moment;     ///< moment at the branch's tip
} cbm_elastica_branch_spec;

/// A parsed elastica spec: the keys of `bend` (docs/bend.md) read by its own reader, with
/// `alpha` (the non-dimensional load rho g L^3 / D, which makes the problem non-dimensional),
/// `angle` over any angle, `theta_tip_min`, `theta_tip_max`, `sweep_min`, `sweep_max` (degrees)
/// and `branch` lines.
typedef struct cbm_elastica_spec {
    cbm_bend_spec bend; ///< geometry, material and loads (dimensional mode)
    bool dimensionless; ///< alpha given: L = D = 1, w = alpha, loads non-dimensional
    double alpha;       ///< rho g L^3 / D
    bool has_angle;     ///< `angle` given
    double angle;       ///< clamp angle, degrees
    double theta_tip_min, theta_tip_max; ///< degrees (default -90, 270)
    double sweep_min, sweep_max;         ///< degrees (default -90, 270)
    size_t n_branches;
    cbm_elastica_branch_spec branches[CBM_ELASTICA_MAX_BRANCHES];
    /* growth under control (steps > 0; include/cambium/elastica_growth.h) */
    bool grows;                            ///< bend's `steps` > 0
    int taper, law;                        ///< cbm_elastica_taper, cbm_elastica_law
    bool control_static;                   ///< `control = static`: the inverse problem
    double control_curvature;              ///< `control = K`, 1/m
    double stiffness_ratio, stiffness_tau; ///< taper step
    bool has_youngs_final, has_preferred;
    double youngs_final, youngs_tau, segment_load, segment_load_point, preferred_angle;
    double induced_rate, substeps, step_time, side;
} cbm_elastica_spec;

/// Parses a spec; every error reported as FILE:line:col (docs/elastica.md). CBM_E_SYNTAX or
/// CBM_E_SEMANTIC.
CBM_API cbm_status cbm_elastica_spec_parse(cbm_context *ctx, const char *text, size_t len,
                                           const char *file, cbm_elastica_spec *out);

/// The rods of a parsed spec: pieces[0] and branches[0] are the base rod, then one per branch
/// line (arrays of 1 + spec->n_branches). *length_ref and *stiffness_ref receive the base's L and
/// D(0), the units of the non-dimensional outputs.
CBM_API cbm_status cbm_elastica_spec_plant(const cbm_elastica_spec *spec,
                                           cbm_elastica_piece *pieces,
                                           cbm_elastica_branch *branches, double *length_ref,
                                           double *stiffness_ref);

/// Greenhill's critical alpha = (9/4) j_{-1/3}^2 = 7.83735 of the heavy vertical column.
#define CBM_ELASTICA_ALPHA_CRITICAL 7.8373

#ifdef __cplusplus
}
#endif
#endif
