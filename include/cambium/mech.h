/* cambium: statics of a branching plant of rigid segments (Jirasek et al. 2000; Taylor-Hell 2005,
 * ch. 6 and 8).
 *
 * A plant is a tree of segments stored struct-of-arrays in topological order: a segment's parent
 * always has a smaller index; any number of children per node. Each segment is a rigid rod of
 * given length with an elliptical section (semi-axes a >= b, U along a) made of a stack of rings
 * (innermost first), each ring with its own Young's modulus, shear modulus, density, outer
 * semi-axes, rest rotation rate, age and reaction-wood fraction. The solver uses per-segment
 * aggregates derived from the rings (kept as running sums: a new outer ring adds its terms in
 * O(1), replacing a ring or ageing the wood recomputes them):
 *   rigidities C = (C_H, C_L, C_U) = sum over rings of (G J, E I_L, E I_U), with
 *   I_L = pi a^3 b / 4 (bending about L: U is along a), I_U = pi a b^3 / 4,
 *   J = pi a^3 b^3 / (a^2 + b^2) (ellipse), ring values = outer minus inner;
 *   mass per length = sum of density * ring area;
 *   rest rotation rate = rigidity-weighted mean of the rings' rest rates, per local component
 *   (Jirasek eq. 24 = Taylor-Hell 6.29-6.34 in closed form).
 *
 * Frames: a segment's orientation is the unit quaternion q with H = q e_x, L = q e_y, U = q e_z
 * (world axes; y is up, gravity by default 9.81 m/s^2 along -y). The rotation rates Omega
 * (current) and rest Omega (unloaded) are stored in LOCAL (H, L, U) components. The frame of
 * segment i is q_i = q_parent * B_i * exp(d_i Omega_i) where B_i is the fixed branching rotation
 * (divergence about H, deviation about U, roll about H; Taylor-Hell 6.2) and d_i the length over
 * which the joint at the proximal end of i bends (see the discretisations below). Roots use the
 * plant's base orientation in place of q_parent. See src/mech/solve_common.c for the full design.
 *
 * Everything is allocated through the context; limits.max_segments and limits.max_passes apply.
 */
#ifndef CAMBIUM_MECH_H
#define CAMBIUM_MECH_H

#include "cambium/approx.h"
#include "cambium/base.h"
#include "cambium/geom.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cbm_plant cbm_plant;

/// How a segment's weight and the bending of a joint are placed along the rod.
typedef enum cbm_mech_discretization {
    /// Default, second order: each segment's weight at its centroid; the joint at the proximal
    /// end of a segment bends over the dual length (half of the parent + half of the segment; the
    /// clamp joint and the first joint of a lateral branch over half the segment).
    CBM_MECH_STAGGERED,
    /// The seeds' first-order chain: each segment's mass at its distal end, the joint at its
    /// proximal end bending over the full segment length with the segment's rigidity.
    CBM_MECH_CHAIN
} cbm_mech_discretization;

/// Name ("staggered", "chain") of a discretisation.
CBM_API const char *cbm_mech_discretization_name(cbm_mech_discretization d);

/// One ring (growth layer) of a segment's section.
typedef struct cbm_ring {
    double youngs_modulus;     ///< E, Pa (> 0)
    double shear_modulus;      ///< G, Pa (> 0)
    double density;            ///< kg/m^3 (>= 0)
    double a;                  ///< outer semi-axis along U, m (>= b, >= inner ring's a)
    double b;                  ///< outer semi-axis along L, m (> 0, >= inner ring's b)
    cbm_vec3 rest_rate;        ///< rest rotation rate of this ring, local (H, L, U), rad/m
    double modulus_of_rupture; ///< Pa; 0 = unknown (no stress ratio)
    double age;                ///< years since the ring was laid down
    double reaction;           ///< reaction-wood fraction of this ring, 0..1
} cbm_ring;

/// A ring with neutral defaults: E = 10 GPa, G = E/16, density 600 kg/m^3, a = b = 0.01 m,
/// straight at rest, MOR 0, age 0, no reaction wood.
CBM_API cbm_ring cbm_ring_default(void);

/// A new segment.
typedef struct cbm_segment_def {
    int64_t parent;    ///< index of the parent segment, -1 for a root (clamped at the base)
    double length;     ///< m (> 0)
    double divergence; ///< spin about the parent's H before the deviation, rad (Taylor-Hell 6.2)
    double deviation;  ///< rotation about the spun U (turns H towards L), rad
    double roll;       ///< spin about the new H after the deviation, rad
    cbm_ring core;     ///< the first (innermost) ring; more rings with cbm_plant_add_ring
    cbm_vec3 omega;    ///< initial current rotation rate, local, rad/m (usually = rest rate)
    double point_mass; ///< kg at the distal end (leaves, fruit, any load)
    /// m: radius of the organ (fruit) centred at the distal node for organ-organ contact
    /// (cbm_plant_set_contact); 0 = none (the default)
    double contact_radius;
    cbm_vec3 tip_force;  ///< N, world, at the distal end (dead load)
    cbm_vec3 tip_moment; ///< N m, world, at the distal end (dead load)
    int32_t order;       ///< branch order; -1 = automatic (root 0, the continuation keeps the
                         ///< parent's order, laterals parent + 1)
    bool lateral; ///< starts a lateral axis even as its parent's first child (a bracketed branch
                  ///< written before the continuing axis, as in L-system strings); false: the
                  ///< parent's first child continues its axis
} cbm_segment_def;

/// Defaults: root, length 0.1 m, no branching angles, cbm_ring_default() core, no loads.
CBM_API cbm_segment_def cbm_segment_def_default(void);

typedef struct cbm_plant_def {
    cbm_vec3 gravity;                       ///< m/s^2, default (0, -9.81, 0)
    cbm_vec3 base_position;                 ///< m, proximal node of the roots
    cbm_quat base_orientation;              ///< frame of the clamp: H = q e_x, L = q e_y, U = q e_z
    cbm_mech_discretization discretization; ///< default CBM_MECH_STAGGERED
    size_t capacity;                        ///< segments to reserve (0 = grow on demand)
} cbm_plant_def;

/// Defaults: gravity (0,-9.81,0), base at the origin with identity orientation (H = +x,
/// L = +y, U = +z), staggered discretisation.
CBM_API cbm_plant_def cbm_plant_def_default(void);

CBM_API cbm_status cbm_plant_create(cbm_context *ctx, const cbm_plant_def *def, cbm_plant **out);
/// Releases the plant and its solver workspace. NULL is allowed.
CBM_API void cbm_plant_destroy(cbm_plant *plant);

/// Base orientation of a clamp whose heading is elevated `elevation` rad above the horizontal
/// +x axis, bending in the x-y plane: H = (cos e, sin e, 0), U = (-sin e, cos e, 0), L = (0,0,-1).
CBM_API cbm_quat cbm_mech_clamp_orientation(double elevation);

/* ---- building and editing ---- */

/// Appends a segment; *index (optional) receives its index. CBM_E_INVALID (naming the field)
/// for a bad parent, length, ring or load; CBM_E_LIMIT beyond limits.max_segments.
CBM_API cbm_status cbm_plant_add_segment(cbm_plant *plant, const cbm_segment_def *def,
                                         size_t *index);
/// Adds an outer ring to a segment (it must enclose the current outer ring). Aggregates update
/// in O(1) whatever the number of rings; no allocation beyond the ring pool's amortised growth.
CBM_API cbm_status cbm_plant_add_ring(cbm_plant *plant, size_t seg, const cbm_ring *ring);
/// Replaces ring k (0 = innermost) of a segment; semi-axes must stay nested. Aggregates update.
CBM_API cbm_status cbm_plant_set_ring(cbm_plant *plant, size_t seg, size_t k, const cbm_ring *ring);
/// Copies ring k of a segment into *out.
/// Replaces all of segment seg's rings by the one ring `ring` (for instance their equivalent
/// ring): the section, mass and rest rate follow from it as for a new segment with that core.
CBM_API cbm_status cbm_plant_replace_rings(cbm_plant *plant, size_t seg, const cbm_ring *ring);
CBM_API cbm_status cbm_plant_get_ring(const cbm_plant *plant, size_t seg, size_t k, cbm_ring *out);
CBM_API size_t cbm_plant_ring_count(const cbm_plant *plant, size_t seg);
CBM_API cbm_status cbm_plant_set_length(cbm_plant *plant, size_t seg, double length);
/// Point mass (kg), tip force (N, world) and tip moment (N m, world) at the distal end.
CBM_API cbm_status cbm_plant_set_load(cbm_plant *plant, size_t seg, double point_mass,
                                      cbm_vec3 tip_force, cbm_vec3 tip_moment);
/// Current rotation rate (local, rad/m); the next solve starts from it when warm-started.
CBM_API cbm_status cbm_plant_set_omega(cbm_plant *plant, size_t seg, cbm_vec3 omega);
CBM_API cbm_status cbm_plant_set_branching(cbm_plant *plant, size_t seg, double divergence,
                                           double deviation, double roll);
CBM_API void cbm_plant_set_gravity(cbm_plant *plant, cbm_vec3 gravity);
/// Ground contact by penalty (Jirasek et al. 2000 §2.8): a horizontal plane at height y0 (m,
/// world y) pushes every distal node below it up with the force k * depth (N; k in N/m per metre
/// of penetration, depth = y0 - y). With smoothing s > 0 (m) the force starts as k d^2 / (2 s)
/// for depths d below s and is k (d - s/2) beyond, continuous with its stiffness (this helps
/// Newton where many nodes touch and leave the ground). The force depends on the shape, so both
/// solvers carry it inside their iteration (the Newton tangent includes the contact stiffness).
/// k = 0 removes the ground (the default: no ground). CBM_E_INVALID for a non-finite y0 or a
/// negative or non-finite k or smoothing.
CBM_API cbm_status cbm_plant_set_ground(cbm_plant *plant, double y0, double k, double smoothing);
/// true if the plant has a ground plane; *y0, *k and *smoothing (optional) receive it.
CBM_API bool cbm_plant_ground(const cbm_plant *plant, double *y0, double *k, double *smoothing);
/// Upward contact force (N) on the distal node of `seg` at the current state (valid after a
/// solve or cbm_plant_evaluate); 0 without ground or above it.
CBM_API double cbm_plant_contact_force(const cbm_plant *plant, size_t seg);
/// Organ-organ contact by penalty (Jirasek et al. 2000 §2.8, Fig. 6: fruits in a bunch): every
/// segment with a contact radius r > 0 carries a sphere of radius r centred at its distal node
/// (a fruit drawn centred at the end of its stalk). Two spheres a, b whose centres are closer
/// than r_a + r_b push each other apart along the line of centres, at the two distal nodes, with
/// the force k * overlap (N; k in N/m per metre of overlap, overlap = r_a + r_b - distance),
/// smoothed over the first `smoothing` m of overlap like the ground (k d^2 / (2 s), then
/// k (d - s/2)). Spheres on the same segment path are not exempt: every overlapping pair counts.
/// Pairs are found in O(n) per evaluation by a uniform grid hashed over the spheres; the forces
/// are part of every evaluation, so the relaxation's fixed point and the Newton residual include
/// them (the fast solver's tangent holds the pair stiffness; its O(n) tree factorisation, which
/// cannot, preconditions FGMRES while spheres touch, with a low-rank correction for the pairs'
/// normal stiffness when at most 32 pairs touch; the fast solver then keeps at least 60 Krylov
/// vectors). k = 0 removes the contact (the default).
/// CBM_E_INVALID for a negative or non-finite k or smoothing.
CBM_API cbm_status cbm_plant_set_contact(cbm_plant *plant, double k, double smoothing);
/// true if organ contact is on; *k and *smoothing (optional) receive it.
CBM_API bool cbm_plant_contact(const cbm_plant *plant, double *k, double *smoothing);
/// Contact radius (m, >= 0; 0 = no sphere) of the organ at the distal node of `seg`.
CBM_API cbm_status cbm_plant_set_contact_radius(cbm_plant *plant, size_t seg, double radius);
/// Sum of the organ-contact forces (N, world) on the distal node of `seg` at the current state
/// (valid after a solve or cbm_plant_evaluate); zero without contact.
CBM_API cbm_vec3 cbm_plant_organ_contact_force(const cbm_plant *plant, size_t seg);
/// Organ contacts at the current state (valid after a solve or cbm_plant_evaluate).
typedef struct cbm_contact_stats {
    size_t spheres;     ///< segments with a contact radius
    size_t pairs;       ///< overlapping pairs
    double max_overlap; ///< m, largest overlap r_a + r_b - distance (0 if none)
    double max_force;   ///< N, largest pair force
} cbm_contact_stats;
CBM_API cbm_status cbm_plant_contact_stats(const cbm_plant *plant, cbm_contact_stats *out);
CBM_API void cbm_plant_set_base(cbm_plant *plant, cbm_vec3 position, cbm_quat orientation);
CBM_API void cbm_plant_set_discretization(cbm_plant *plant, cbm_mech_discretization d);
CBM_API cbm_mech_discretization cbm_plant_discretization(const cbm_plant *plant);
/// Removes segment `seg` and everything it carries (breakage, pruning), keeping topological
/// order (indices of later segments shift down). *removed (optional) receives the count. If the
/// removed segment was its parent's continuation, the next remaining child becomes it.
CBM_API cbm_status cbm_plant_remove_subtree(cbm_plant *plant, size_t seg, size_t *removed);

/* ---- queries (valid after a solve or cbm_plant_evaluate) ---- */

CBM_API size_t cbm_plant_segment_count(const cbm_plant *plant);
CBM_API cbm_vec3 cbm_plant_gravity(const cbm_plant *plant);

/// Everything about one segment.
typedef struct cbm_segment_state {
    int64_t parent;    ///< -1 for a root
    int32_t order;     ///< branch order
    bool continuation; ///< first child of its parent (its joint includes half the parent)
    size_t child_count;
    double length; ///< m
    double a, b;   ///< outer semi-axes, m
    size_t ring_count;
    double area;            ///< section area, m^2
    double mass_per_length; ///< kg/m
    cbm_vec3 rigidity;      ///< (C_H, C_L, C_U) = (sum GJ, sum EI_L, sum EI_U), N m^2
    cbm_vec3 rest_rate;     ///< rigidity-weighted rest rotation rate, local, rad/m
    cbm_vec3 omega;         ///< current rotation rate of the joint at the proximal end, local
    /// current rotation rate of the segment's own material, local, rad/m: the mean over its two
    /// halves, rest + C^-1 (M_proximal + M_distal)/2 (staggered; M_distal is the continuation
    /// joint's moment or the tip moment), Omega itself for the chain. This is the "current
    /// Omega" a new ring memorises (Taylor-Hell 6.32): with it a ring added under unchanged load
    /// leaves the shape unchanged up to O(h^2).
    cbm_vec3 rate;
    double point_mass;     ///< kg at the distal end
    double contact_radius; ///< m, organ sphere at the distal node (0: none)
    cbm_vec3 tip_force;    ///< N, world
    cbm_vec3 tip_moment;   ///< N m, world
    cbm_quat orientation;  ///< frame of the segment (H = q e_x, L = q e_y, U = q e_z)
    cbm_frame frame;       ///< the same frame as vectors
    cbm_vec3 proximal;     ///< m, proximal node
    cbm_vec3 distal;       ///< m, distal node
    double carried_mass;   ///< kg: own wood + point mass + everything distal
    cbm_vec3 force;        ///< N, world: total load carried through the proximal joint
    cbm_vec3 moment;       ///< N m, world: moment of all carried loads about the proximal node
    cbm_vec3 moment_local; ///< the same in the segment's (H, L, U) components
    double stress;         ///< Pa, peak bending stress at the proximal joint (M a / I, ellipse)
    double stress_ratio;   ///< stress / modulus of rupture of the outer ring (NaN if MOR = 0)
    double age;            ///< years, age of the oldest ring
    double reaction;       ///< area fraction of reaction wood in the section, 0..1
} cbm_segment_state;

CBM_API cbm_status cbm_plant_segment(const cbm_plant *plant, size_t seg, cbm_segment_state *out);

/// Raw struct-of-arrays views (length cbm_plant_segment_count), valid until the next edit.
CBM_API const int64_t *cbm_plant_parents(const cbm_plant *plant);
CBM_API const cbm_quat *cbm_plant_orientations(const cbm_plant *plant);
/// Proximal node of each segment; the distal node is proximal + length * H.
CBM_API const cbm_vec3 *cbm_plant_positions(const cbm_plant *plant);
CBM_API const cbm_vec3 *cbm_plant_omegas(const cbm_plant *plant);
/// Moment about the proximal node, world components.
CBM_API const cbm_vec3 *cbm_plant_moments(const cbm_plant *plant);

/// Total mass of the plant (wood + point masses), kg.
CBM_API double cbm_plant_total_mass(const cbm_plant *plant);

/// Frame of the continuum tangent at the distal node of `seg`: the segment's frame turned by the
/// bending of the segment's distal half (second-order accurate node angle in the staggered
/// discretisation; the segment frame itself for the chain).
CBM_API cbm_status cbm_plant_distal_frame(const cbm_plant *plant, size_t seg, cbm_quat *out);

/* ---- solving ---- */

typedef enum cbm_mech_solver {
    CBM_MECH_RELAX,  ///< the seeds' relaxation (Taylor-Hell 6.24; Jirasek eqs. 17-21)
    CBM_MECH_NEWTON, ///< Newton-Krylov: O(n) tree factorisation or stiffness-preconditioned GMRES
    /// Gürtler's force-applying approximative method (Method A, cambium/approx.h): one closed
    /// angle generator per axis, no equilibrium iteration (src/mech/solve_approx.c,
    /// docs/methods.md says what it leaves out)
    CBM_MECH_APPROX,
    /// incremental finite elements (Guertler 2018 sec. 2.2 after Fourcaud & Lac 2003): the load
    /// in cbm_fem_def.increments linear steps on the current geometry (src/mech/fem.c)
    CBM_MECH_FEM,
    CBM_MECH_SOLVER_COUNT ///< number of solvers (not a solver)
} cbm_mech_solver;

/// Name of a solver ("relax", "fast", "approx", "fem"); NULL for a value out of range.
CBM_API const char *cbm_mech_solver_name(cbm_mech_solver s);
/// Parses a solver's name or alias ("relax", "relaxation", "fast", "newton", "newton-krylov",
/// "approx", "fem", ...; case-sensitive). false if unknown.
CBM_API bool cbm_mech_solver_parse(const char *name, cbm_mech_solver *out);
/// Writes the solvers' names, comma-separated ("relax, fast, approx"), into buf (size bytes,
/// NUL-terminated, truncated if short; buf may be NULL with size 0); returns the full length.
CBM_API size_t cbm_mech_solver_names(char *buf, size_t size);

/// Preconditioner of the fast solver's GMRES (right preconditioning).
typedef enum cbm_mech_precond {
    /// Default: the exact Newton matrix of the tree factorised in O(n) by condensing subtrees
    /// from the tips (like the articulated-body recursion); GMRES then needs one iteration.
    CBM_MECH_PRECOND_TREE,
    /// The elastic stiffness S = diag(C_H, C_L, C_U) of every joint.
    CBM_MECH_PRECOND_STIFFNESS
} cbm_mech_precond;

/// How the fast solver reaches the equilibrium from a warm start (the previous equilibrium under
/// changed loads or a changed plant) when plain Newton steps do not get there: the first step
/// would turn a frame by more than 0.5 rad, or the line search stalls (for the transient path
/// also: a step cut below 1/8, or 8 steps without convergence).
typedef enum cbm_mech_warm_path {
    /// Default: pseudo-transient continuation, implicit Euler steps of the damped motion
    /// C dOmega/dt = -R from the current state: the plant creeps under its new loads and ends
    /// in the equilibrium an overdamped motion reaches (a twig past a limit point snaps through
    /// to hanging). With the tree preconditioner and without ground contact; otherwise as
    /// CBM_MECH_WARM_MASS_PATH.
    CBM_MECH_WARM_TRANSIENT,
    /// Quasi-static continuation over the point masses, from those the start state balances to
    /// the new ones, then over all loads from the rest state (the fast solver before the
    /// transient path existed; slow where a twig passes a limit point).
    CBM_MECH_WARM_MASS_PATH
} cbm_mech_warm_path;

/// Which resultant of the maturation strain stretches an element (Guertler's deviation D5).
typedef enum cbm_fem_axial {
    /// Default, the thesis's eq. 2.79: N = E dA (a + sigma (b - a) / 2), the hoop mean of 2.62.
    CBM_FEM_AXIAL_FORMULA,
    /// The thesis's listing: N = E dA sigma (a + (b - a) / 2) (no stretch at sigma = 0).
    CBM_FEM_AXIAL_LISTING
} cbm_fem_axial;

/// The incremental finite-element method (solver CBM_MECH_FEM, cbm_plant_fem_grow): 3-D
/// Euler-Bernoulli two-node beams, one per segment, layered sections from the segment's rings,
/// clamped roots, an O(n) tree factorisation per step (src/mech/fem.c, docs/methods.md).
typedef struct cbm_fem_def {
    /// cbm_plant_solve: the full load is applied in this many equal increments, each a linear
    /// solve on the geometry the previous ones left (>= 1; default 20)
    size_t increments;
    /// G / E of every ring (Guertler: 1/3); 0 (default) = each ring's own shear modulus
    double shear_ratio;
    /// reaction sensitivity sigma in [0, 1] of new wood's maturation strain (2.62); default 0
    double sigma;
    /// rad, reaction direction phi: the hoop angle of the reacting side, measured in the section
    /// about H from its upper side (the part of "up" across the segment), eq. 2.63; default 0
    double phi;
    double strain_min; ///< a of eq. 2.62, dimensionless strain (1 microstrain = 1e-6); default 0
    /// b of eq. 2.62: b >= 0 compression wood (psi = phi + pi, the side opposite phi expands);
    /// b < 0 tension wood (psi = phi, that side contracts); default 0
    double strain_max;
    cbm_fem_axial axial; ///< default CBM_FEM_AXIAL_FORMULA
} cbm_fem_def;

/// Defaults as documented per field.
CBM_API cbm_fem_def cbm_fem_def_default(void);

typedef struct cbm_solve_def {
    cbm_mech_solver solver;          ///< default CBM_MECH_NEWTON
    double tolerance;                ///< relative residual to reach, default 1e-8
    double alpha;                    ///< relaxation factor in (0, 1], default 0.5 (relax only)
    size_t max_passes;               ///< 0 = limits.max_passes of the context
    int krylov_dim;                  ///< GMRES restart length, default 10 (Newton only)
    cbm_mech_precond preconditioner; ///< default CBM_MECH_PRECOND_TREE (Newton only)
    bool warm_start;              ///< start from the current Omega (default true); else from rest
    cbm_mech_warm_path warm_path; ///< default CBM_MECH_WARM_TRANSIENT (Newton only)
    /// true: an unstable equilibrium the fast solver (tree factorisation) converged to is pushed
    /// along its unstable mode (both ways) and the plant relaxed to the stable equilibrium of
    /// least energy (`bend` asks for this). Default false: the equilibrium found is kept, so
    /// that existing runs give the same results (continuation and studies of unstable states
    /// want this too). Either way cbm_solve_stats.unstable_modes says what was returned.
    bool push_unstable;
    /// also compute cbm_solve_stats.lowest_eigenvalue when the equilibrium is stable (shifted
    /// inverse iteration, tens of O(n) passes not counted in `passes`); default false
    bool eigenvalue;
    /// true (default): where the pivots count unstable modes, confirm them by the lowest
    /// eigenvalue (shifted inverse iteration, tens of O(n) passes not counted in `passes`), as
    /// cbm_solve_stats.unstable_modes says. false: unstable_modes is the pivots' count
    /// unconfirmed and lowest_eigenvalue NaN, for callers that do not read them (the built-in
    /// tree models' and the L-system's growth: a quarter of a growth run's time went there).
    /// The equilibrium returned is the same to the bit either way; push_unstable and eigenvalue
    /// confirm whatever this says.
    bool confirm_modes;
    /// threads of the sweeps over a branched plant of 50,000 segments or more (fast solver and
    /// relaxation): 0 = one per processor (the default), 1 = serial; at most 7 are used. The
    /// results are the same to the bit for any count. Also used by the plant's later evaluations.
    int threads;
    /* Method A (CBM_MECH_APPROX) only */
    cbm_approx_mode approx_mode; ///< default CBM_APPROX_CORRECTED
    double approx_p;             ///< relative position of the bending reversal, [0, 1]; default 1
    /// tip force = this times the weight an axis carries (> 0); default 1, the thesis's whole
    /// weight at the tip (3/8 matches the small deflection of a uniform rod's tip)
    double approx_force_factor;
    /// how an axis's load enters the generator; default CBM_APPROX_LOAD_TIP (the thesis)
    cbm_approx_load approx_load;
    cbm_fem_def fem; ///< settings of CBM_MECH_FEM; default cbm_fem_def_default()
} cbm_solve_def;

CBM_API cbm_solve_def cbm_solve_def_default(void);

/// The stage of the statics solver that reached the tolerance (docs/design.md, "The fast solver's
/// stages"): the fast solver runs its stages in this order, each only when the ones before it
/// did not converge.
typedef enum cbm_solve_stage {
    CBM_SOLVE_STAGE_NONE = 0,     ///< "none": not converged
    CBM_SOLVE_STAGE_NEWTON,       ///< "newton": Newton at the full load from the start state
    CBM_SOLVE_STAGE_TRANSIENT,    ///< "transient": pseudo-transient continuation (warm start)
    CBM_SOLVE_STAGE_MASS_PATH,    ///< "mass-path": continuation over the point masses (warm)
    CBM_SOLVE_STAGE_LOAD_PATH,    ///< "load-path": load continuation from the rest state
    CBM_SOLVE_STAGE_RELAX_BURSTS, ///< "relax-bursts": relaxation bursts between Newton attempts
    CBM_SOLVE_STAGE_STABILITY,    ///< "stability": re-solved after a push off an unstable state
    CBM_SOLVE_STAGE_RELAX,        ///< "relax": the relaxation solver (CBM_MECH_RELAX)
    CBM_SOLVE_STAGE_FEM,          ///< "fem": the incremental FEM's increments (CBM_MECH_FEM)
    CBM_SOLVE_STAGE_COUNT
} cbm_solve_stage;

/// The stage's name as in the enum's comments ("newton", "load-path", ...); "unknown" if out of
/// range.
CBM_API const char *cbm_solve_stage_name(cbm_solve_stage stage);

/// Solves through the context so far, by the stage that converged (counts[CBM_SOLVE_STAGE_NONE]:
/// the solves that did not converge); for --timing-style reports over many solves.
CBM_API void cbm_solve_stage_counts(const cbm_context *ctx, size_t counts[CBM_SOLVE_STAGE_COUNT]);

/// What a solve did.
typedef struct cbm_solve_stats {
    size_t passes;             ///< forward + backward sweeps (also the tangent sweeps of Newton)
    double residual;           ///< max_i |C (Omega_i - rest_i) - M_i| / characteristic moment
    double char_moment;        ///< N m, the characteristic moment (max_i |M_i|, >0)
    size_t newton_steps;       ///< Newton iterations (0 for relax)
    size_t krylov_iterations;  ///< total GMRES iterations
    size_t continuation_steps; ///< load steps taken by the globalisation (1 = full load at once)
    /// joints where the final equilibrium is unstable (pivot block of the tree factorisation
    /// not positive definite); fast solver with the tree preconditioner only, else 0
    size_t unstable_joints;
    cbm_solve_stage stage; ///< the stage that reached the tolerance; CBM_SOLVE_STAGE_NONE if none
    /// unstable modes of the returned equilibrium: the negative eigenvalues of the Hessian of
    /// the total potential energy, D J (D the joints' dual lengths, J the tangent), counted by
    /// Sylvester's law of inertia on the pivots of its O(n) tree factorisation (exact where D J
    /// is symmetric: planar bending under dead loads; src/mech/stability.c). Both solvers; 0 if
    /// the solve did not converge. A count the tangent's lowest eigenvalue does not confirm
    /// (lambda >= 0: a misreading of an unsymmetric tangent) is reported as 0.
    size_t unstable_modes;
    /// lowest eigenvalue lambda of J v = lambda S v (S = diag of the joint rigidities: 1 for an
    /// unloaded plant, 0 at a buckling load, < 0 unstable); computed when unstable_modes > 0
    /// or cbm_solve_def.eigenvalue is set, else NaN
    double lowest_eigenvalue;
} cbm_solve_stats;

/// Stability of the plant's current state (call after a solve): what cbm_solve_stats reports,
/// computed on demand for any state.
typedef struct cbm_stability {
    size_t unstable_modes;    ///< inertia of the Hessian's tree pivots (see cbm_solve_stats)
    double lowest_eigenvalue; ///< lowest eigenvalue of S^-1 J (shifted inverse iteration)
    double energy;            ///< J, total potential energy (strain - work of dead forces)
    double residual;          ///< relative residual of the state (an equilibrium if small)
    size_t passes;            ///< O(n) factor or solve passes used
} cbm_stability;

/// Fills *out for the plant's current Omega (evaluated first). CBM_E_NOT_CONVERGED if no shift
/// made the tangent positive definite (the eigenvalue is then NaN, the count still set).
CBM_API cbm_status cbm_plant_stability(cbm_plant *plant, cbm_stability *out);

/// Brings the plant to static equilibrium. Results (frames, positions, moments, stresses) are
/// always readable afterwards. CBM_E_NOT_CONVERGED if the tolerance is not reached within the
/// pass budget (stats still filled, residual reported); CBM_E_NONFINITE with a message naming
/// the segment if a NaN or infinity appears; CBM_E_INVALID for an empty plant or zero rigidity.
/// No allocation happens inside the iteration (the workspace is kept in the plant).
CBM_API cbm_status cbm_plant_solve(cbm_plant *plant, const cbm_solve_def *def,
                                   cbm_solve_stats *stats);

/// One forward and one backward pass with the current Omega, no update: frames, positions,
/// masses, forces, moments and stresses. *residual (optional) receives the relative residual.
CBM_API cbm_status cbm_plant_evaluate(cbm_plant *plant, double *residual);

/// Emits one part per segment into the scene: a tube with elliptical end sections (U along a),
/// organ branch, order, segment and parent ids, stress, stress/MOR ratio, age, reaction wood.
/// Each axis is one continuous generalized cylinder: a segment and its continuation share the
/// ring at their node (docs/formats.md). Point masses are not drawn. `sides` 3..1024.
CBM_API cbm_status cbm_plant_to_scene(const cbm_plant *plant, cbm_scene *scene, int sides);

/* ---- section helpers (exact formulas for a solid ellipse) ---- */

/// Second moments of area of a solid ellipse with semi-axes a (along U) and b (along L), m^4:
/// *i_l = pi a^3 b / 4 (about L), *i_u = pi a b^3 / 4 (about U), *j = pi a^3 b^3 / (a^2 + b^2).
CBM_API void cbm_mech_ellipse_moments(double a, double b, double *i_l, double *i_u, double *j);

/* ---- growth: primary growth with tropism, pipe-model rings with shape memory, wood ageing,
 * reaction wood, breakage, self-weight buckling (src/mech/growth.c, wood.c, breakage.c,
 * buckle.c; Taylor-Hell 2005 ch. 4.1, 6.1.5, 6.3, 8; Jirasek et al. 2000 eq. 24) ---- */

/// Tropism of new segments (Taylor-Hell 6.8-6.12): a force F = strength * direction applied at
/// the parent's link gives the torque l_parent x F; the new segment's rest rotation rate is that
/// torque divided by its own rigidity, componentwise in its local frame.
typedef struct cbm_tropism {
    cbm_vec3 direction; ///< world, normalised internally; default (0, 1, 0) (negative geotropism)
    double strength;    ///< N (the thesis' TROP); 0 = no tropism
} cbm_tropism;

/// Defaults: direction (0, 1, 0), strength 0.
CBM_API cbm_tropism cbm_tropism_default(void);

/// Which current rotation rate a new ring memorises as its rest rate (Taylor-Hell 6.32 / 8.24).
typedef enum cbm_ring_memory {
    /// Default: the segment's own material rate (cbm_segment_state.rate), so that a ring added
    /// under unchanged load leaves the shape unchanged (exactly for the chain discretisation, to
    /// O(h^2) for the staggered one).
    CBM_MEMORY_SEGMENT,
    /// The listing's Ring_omega_e = Omega: the rotation rate of the segment's proximal joint.
    CBM_MEMORY_JOINT
} cbm_ring_memory;

/// How wood ages (Taylor-Hell 8.2-8.6).
typedef enum cbm_ageing {
    /// Default: every ring keeps its own modulus, E_k = min(E_adult, E_juv + age_k (E_adult -
    /// E_juv) / adult_age) (8.2 applied ring by ring; the structural modulus 8.5 is then an
    /// output, cbm_plant_structural_modulus).
    CBM_AGEING_RINGS,
    /// The listing: the rings of a segment are first merged into a core of the structural
    /// moduli E = C_L / I_L, G = C_H / J (8.1, 8.5-8.6), which then rises by dt (E_adult -
    /// E_juv) / adult_age until E_adult (8.2); the rest rate is kept.
    CBM_AGEING_CORE
} cbm_ageing;

/// Secondary growth and wood: the pipe model (4.1-4.3, 8.17), the wood of new rings, ageing
/// (8.2), reaction wood (8.7-8.25).
typedef struct cbm_growth_def {
    double pipe_exponent; ///< P (> 0): parent area^(P/2) = sum of children's area^(P/2); default 2
    double pipe_rate;     ///< kappa in (0, 1]: fraction of the goal reached per step; default 1
    double min_ring;      ///< m: thinner increments of a are skipped (thesis EPSILON), 1e-9
    /// m^2: pipe area of the leaf or bud every segment carries itself (the lateral of 4.1 at
    /// every node); with P = 2 a segment's goal area is then leaf_area times the number of
    /// segments at or beyond it (Jirasek §SecGrowth). Default 0 (only children count).
    double leaf_area;
    double youngs_juvenile;    ///< E_juv, Pa, modulus of new wood; default 10 GPa
    double youngs_adult;       ///< E_adult, Pa (>= E_juv); default = youngs_juvenile
    double adult_age;          ///< years from E_juv to E_adult; default 0 = no ageing
    double shear_ratio;        ///< G / E of new wood (> 0); default 1/16
    double density;            ///< kg/m^3 of new wood; default 600
    double modulus_of_rupture; ///< Pa, of new wood; 0 = unknown
    cbm_ring_memory memory;    ///< default CBM_MEMORY_SEGMENT
    cbm_ageing ageing;         ///< default CBM_AGEING_RINGS
    /// reaction wood: a new ring is reaction wood if |Omega - rest| > threshold (rad/m, 8.7-8.8);
    /// default INFINITY = never
    double reaction_threshold;
    double reaction_beta;      ///< beta in [0, 1]: ring rest = (1-beta) Omega + beta rest (8.25)
    double reaction_increment; ///< m added to a after the pipe computation (8.20); default 0.001
    double reaction_youngs;    ///< E_rw, Pa; E_ring = (E_rw + E_juv)/2 (8.23); 0 = youngs_adult
    /// largest aspect a/b a reaction-wood ring may give the section (>= 1; 0 = no bound, the
    /// thesis): beyond it the ring's area (a + increment) b is laid at this aspect, so the
    /// section grows rounder instead of into a ribbon (docs/growth.md); default 0
    double reaction_max_aspect;
    /// rad: with > 0, the reaction-wood increment responds to the stimulus: it is
    /// reaction_increment x min(1, sin(theta) / sin(reaction_full_lean)), theta the angle by which
    /// the segment's heading has left its set-point (the heading its rest shape gives it),
    /// accumulated from the base (docs/growth.md); 0 = the fixed increment of 8.20 (default)
    double reaction_full_lean;
    /// kappa^c, the control curvature of Tresierras (2009, (3.14)): a new ring is moulded on
    /// the segment's current rate plus this rate, local components (twist about H, bending
    /// about L, bending about U), rad/m. An asymmetric residual growth stress (tension wood) in
    /// one number per direction; default 0 (the ring is moulded on the present shape)
    cbm_vec3 control_rate;
    /// kappa^c as a curvature that turns the axis towards the vertical (up = -gravity), rad/m,
    /// added to control_rate (gravitropic control; negative turns down; nothing on a vertical
    /// segment); default 0. docs/growth.md relates it to the elastica's law
    double control_up;
} cbm_growth_def;

/// Defaults as documented per field.
CBM_API cbm_growth_def cbm_growth_def_default(void);

/// Appends a segment whose rest rotation rate (and initial Omega) is set by the tropism
/// (6.8-6.12): tau = l_parent H_parent x F in world (a root uses its own length and the base
/// heading), then rest = (tau.H / C_H, tau.L / C_L, tau.U / C_U) in the new segment's frame
/// before bending (parent frame times branching rotation), C from def->core. The rest rate of
/// def->core is replaced; def->omega is ignored. Frames of the parent must be current (after a
/// solve or cbm_plant_evaluate). `tropism` NULL = none.
CBM_API cbm_status cbm_plant_grow_segment(cbm_plant *plant, const cbm_segment_def *def,
                                          const cbm_tropism *tropism, size_t *index);

/// Roll (rad, about the new heading) that turns the U axis of a segment about to be added with
/// `def` (parent frame, divergence, deviation) as close as possible to "up" (against gravity), so
/// that U x H spans the vertical plane of H and the long semi-axis a lies in the plane of a
/// vertical lean (Taylor-Hell §8.4.2, Fig. 8.4: U = H x (up x H)); 0 when H is vertical. Put it
/// in def->roll. Frames of the parent must be current.
CBM_API cbm_status cbm_plant_upright_roll(const cbm_plant *plant, const cbm_segment_def *def,
                                          double *roll);

/// What a growth step did.
typedef struct cbm_growth_stats {
    size_t rings_added;    ///< rings laid down
    size_t reaction_rings; ///< of which reaction wood
    double max_increment;  ///< m, largest increase of a semi-axis a
} cbm_growth_stats;

/// Lays a new ring on segment `seg` with outer semi-axes (a, b) (>= the current ones), wood of
/// `def`, and rest rate from shape memory (6.29-6.32, Jirasek eq. 24) or, if the segment leans
/// (|Omega - rest| > threshold), reaction wood (8.20-8.25). *reaction (optional) says which.
/// State (frames, moments) must be current (after a solve).
CBM_API cbm_status cbm_plant_add_growth_ring(cbm_plant *plant, size_t seg, double a, double b,
                                             const cbm_growth_def *def, bool *reaction);

/// One secondary-growth step of the whole plant, tip to base: the goal area of a segment is
/// (leaf_area^(P/2) + sum_c area_c^(P/2))^(2/P) over its children c after their growth (8.17;
/// radius form 4.1-4.2 for circles); a' = a + kappa (a_goal - a) (4.3) keeping b/a (8.18-8.19),
/// plus the reaction-wood increment when the segment leans; girth never decreases. Each
/// increase is one ring (cbm_plant_add_growth_ring). State must be current (after a solve).
CBM_API cbm_status cbm_plant_grow_rings(cbm_plant *plant, const cbm_growth_def *def,
                                        cbm_growth_stats *stats);

/// Ages all wood by dt years (8.2; see cbm_ageing).
CBM_API cbm_status cbm_plant_age_wood(cbm_plant *plant, const cbm_growth_def *def, double dt);

/// Structural moduli of a segment (8.1, 8.5-8.6): E = C_L / I_L, G = C_H / J of the outer
/// ellipse, Pa.
CBM_API cbm_status cbm_plant_structural_modulus(const cbm_plant *plant, size_t seg, double *e,
                                                double *g);

/// Breakage (Taylor-Hell 8.26-8.27): every segment whose peak bending stress at its proximal
/// joint (cbm_segment_state.stress, M a / I for the ellipse) exceeds the modulus of rupture of
/// its outer ring (rings with MOR 0 never break) is removed with everything it carries; a broken
/// segment inside an already broken subtree is not counted separately. The indices (before
/// removal, increasing) of the segments that broke go to broken[0..max_broken) (may be NULL);
/// *n_broken and *n_removed (optional) receive the counts. State must be current (after a
/// solve); re-solve afterwards.
CBM_API cbm_status cbm_plant_break(cbm_plant *plant, size_t *broken, size_t max_broken,
                                   size_t *n_broken, size_t *n_removed);

/// Self-weight buckling of a vertical column (Taylor-Hell §6.3, Greenhill).
typedef struct cbm_buckle_def {
    double youngs_modulus;                  ///< E, Pa
    double shear_modulus;                   ///< G, Pa; 0 = E / 16
    double density;                         ///< kg/m^3
    double radius;                          ///< m
    double segment;                         ///< m, segment length of the grown column
    double gravity;                         ///< m/s^2; default 9.81
    size_t max_segments;                    ///< give up beyond this many segments; default 100000
    cbm_mech_discretization discretization; ///< default staggered
} cbm_buckle_def;

/// Defaults: E 10 GPa, G = E/16, density 600, radius 0.05, segment 0.1, gravity 9.81.
CBM_API cbm_buckle_def cbm_buckle_def_default(void);

typedef struct cbm_buckle_result {
    size_t segments;           ///< segments of the first column that does not return upright
    double buckling_length;    ///< m, segments * segment
    double greenhill_length;   ///< m, (7.837 E I / q)^(1/3), q = density pi r^2 g
    double growth_factor;      ///< decay factor of the perturbation at the buckling length (>= 1)
    double last_stable_factor; ///< the same one segment shorter (< 1)
    size_t passes;             ///< linearised passes used in all
} cbm_buckle_result;

/// Growth factor per pass of a small perturbation of the plant's current equilibrium under the
/// relaxation with alpha = 1: the spectral radius of K = C^-1 dM/dOmega (dM/dOmega the solvers'
/// tangent), found by power iteration from a fixed push of every segment; the push dies out iff
/// the factor is < 1. For a column under compression every eigenvalue of K is >= 0 and this is
/// the physical stability (the column returns upright); where a load is in tension (a hanging
/// chain) K can have negative eigenvalues and a factor >= 1 then only says that the alpha = 1
/// relaxation oscillates. The plant is evaluated at its current Omega (call after a solve).
/// *passes (optional) receives the linearised passes used.
CBM_API cbm_status cbm_plant_stability_factor(cbm_plant *plant, double *factor, size_t *passes);

/// Taylor-Hell's protocol: a vertical column grown one segment at a time, perturbed, until the
/// perturbation no longer decays; bisection over the segment count (the factor grows with
/// length). CBM_E_LIMIT if the column still stands at max_segments.
CBM_API cbm_status cbm_mech_buckle(cbm_context *ctx, const cbm_buckle_def *def,
                                   cbm_buckle_result *out);

/// Critical length of a vertical self-weighted column of n equal segments (continuous length,
/// bisection to relative tolerance rel_tol): the length at which the stability factor is 1.
CBM_API cbm_status cbm_mech_buckle_length(cbm_context *ctx, const cbm_buckle_def *def, size_t n,
                                          double rel_tol, double *length);

/* ---- incremental finite elements: growth (src/mech/fem.c; Guertler 2018 sec. 2.2) ---- */

/// One growth step of the incremental FEM (cbm_plant_fem_grow).
typedef struct cbm_fem_growth {
    /// m added to both semi-axes of every existing segment as one new ring (secondary growth);
    /// 0 = none
    double ring_thickness;
    /// wood of new rings and new tip cores: E, G, density, modulus of rupture (a, b, rest rate,
    /// age and reaction are set by the step); default cbm_ring_default()
    cbm_ring wood;
    double tip_length; ///< m, a new element continues every axis tip (primary growth); 0 = none
    double tip_radius; ///< m, radius of a new element's core (> 0 with tip_length > 0)
    /// new elements point along `direction` (world; Guertler's primaryTropism) instead of
    /// continuing their parent's heading
    bool primary_tropism;
    cbm_vec3 direction; ///< world, normalised internally; default (0, 1, 0)
    /// kg added this step to each existing segment's point mass (extra loads: leaves, fruit),
    /// segment_count entries, or NULL
    const double *added_mass;
} cbm_fem_growth;

/// Defaults: no ring, cbm_ring_default() wood, no primary growth, direction (0, 1, 0).
CBM_API cbm_fem_growth cbm_fem_growth_default(void);

/// What an FEM step did.
typedef struct cbm_fem_stats {
    size_t increments;   ///< linear solves (cbm_plant_solve: fem.increments; growth: 1)
    size_t elements;     ///< elements (segments) at the end
    size_t rings_added;  ///< rings laid down (growth)
    size_t tips_added;   ///< elements added (growth)
    double max_rotation; ///< rad, largest rotation of an element in the last increment
} cbm_fem_stats;

/// One growth step of the incremental FEM on the plant's current geometry (Guertler 2018 sec.
/// 2.2.4, Fourcaud & Lac 2003): secondary growth (a ring of `ring_thickness` on every existing
/// segment, stress-free on the current shape: its rest rate is the segment's current Omega),
/// primary growth (a new element at every axis tip), then ONE linear solve of the load increment
/// of the step: the weight of the new rings and new elements, the maturation strain of the new
/// wood (def->sigma, phi, a, b) and the weight of added_mass, on the stiffness of all rings in
/// the current orientation. The element rotations are accumulated into the frames and Omega;
/// the plant is evaluated (positions, moments) at the end. Nothing already applied is re-applied:
/// the deformation of earlier steps is memorised. def NULL = cbm_fem_def_default().
/// CBM_E_INVALID naming the field for bad settings; CBM_E_NONFINITE if the solve fails.
CBM_API cbm_status cbm_plant_fem_grow(cbm_plant *plant, const cbm_fem_def *def,
                                      const cbm_fem_growth *growth, cbm_fem_stats *stats);

#ifdef __cplusplus
}
#endif
#endif
