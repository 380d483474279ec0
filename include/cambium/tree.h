/* cambium: built-in tree models driven by parameter files — the general fruit tree of
 * Taylor-Hell (2005, appendix A.1) and the wild and crooked trembling aspen of its chapter 7,
 * grown natively on the statics engine (cambium/mech.h).
 *
 * A tree is a cbm_plant plus, per segment, the model's state (buds, apices, leaves, fruit,
 * vigour). It grows in growth steps; each step adds one node to every active apex (summer), or
 * sheds leaves and fruit (winter), then solves the static equilibrium with the fast solver
 * (warm-started), breaks what exceeds the modulus of rupture and lays pipe-model rings (with
 * reaction wood). A year is summer steps until every apex has made its nodes, winter steps until
 * the leaves and fruit are gone and the rings have caught up, the ageing of the wood, the
 * shedding of unproductive branches, and one spring pass that decides the fate of every bud by
 * resource allocation. docs/models.md describes the
 * model, every parameter and the options; src/tree/fruit_tree.c the algorithm.
 *
 * Units: SI; angles are radians in cbm_tree_def and degrees in parameter files. All randomness
 * comes from one generator seeded by cbm_tree_def.seed.
 */
#ifndef CAMBIUM_TREE_H
#define CAMBIUM_TREE_H

#include "cambium/base.h"
#include "cambium/geom.h"
#include "cambium/mech.h"

#ifdef __cplusplus
extern "C" {
#endif

/// Control points of a graphically defined function (cpfg's func), evaluated piecewise linearly
/// between the points and held constant beyond the first and the last.
#define CBM_TREE_FUNC_MAX 16
typedef struct cbm_tree_func {
    int n;                       ///< number of points (>= 1)
    double x[CBM_TREE_FUNC_MAX]; ///< increasing abscissae
    double y[CBM_TREE_FUNC_MAX];
} cbm_tree_func;

/// Value of a graphical function at x (piecewise linear, clamped at the ends).
CBM_API double cbm_tree_func_eval(const cbm_tree_func *f, double x);

/// Which form of the tree the parameters describe (Taylor-Hell ch. 7: one switch).
typedef enum cbm_tree_form {
    CBM_TREE_GENERAL, ///< the general fruit tree of appendix A.1
    CBM_TREE_WILD,    ///< wild-type aspen: E x stiffness_factor, tropism x tropism_factor
    /// crooked aspen: base E and tropism, no reaction wood (beta = 0), deviation x
    /// deviation_factor, tropism fading late in each shoot
    CBM_TREE_CROOKED
} cbm_tree_form;

/// Every parameter of the model. Names in parameter files are the field names.
typedef struct cbm_tree_def {
    uint64_t seed; ///< generator seed (thesis SEED 1484127)
    int years;     ///< years grown by cbm_tree_run (END_YEAR 10)
    cbm_tree_form form;
    /* architecture */
    double internode_length; ///< m, LEN0 0.055
    double bud_length;       ///< m, lateral bud internode and ground threshold, BUDLENGTH 0.008
    double radius;           ///< m, radius of every new internode, RADIUS0 0.002
    double bud_radius;       ///< m, radius of a new lateral bud internode (0 = radius, thesis)
    int max_buds;            ///< nodes of the most vigorous annual shoot, MAXBUDS 21
    int first_buds;          ///< nodes of the first trunk shoot (MAXBUDS/2 = 10)
    double phyllotaxis;      ///< rad, divergence between successive buds, SPIRAL 137.5 deg
    double elevation;        ///< rad, initial heading above the horizontal (90 = VERTICAL)
    cbm_tree_func numbuds_vigour;   ///< n / max_buds as a function of vigour V (4.15)
    cbm_tree_func angle_min_height; ///< minimum deviation / 100 deg as a function of h (A.1)
    cbm_tree_func angle_max_height; ///< maximum deviation / 100 deg as a function of h (A.1)
    cbm_tree_func vigour_height;    ///< acrotony modulation f(h) of the lateral share (4.13)
    /* resources */
    double vigour_k;     ///< K of the base supply (K a)^d, 1/m (800)
    double vigour_d;     ///< d of the base supply (1.1)
    double shoot_vigour; ///< bud-shoot threshold on V (SHOOT_VIGOUR 0.03)
    double sink;         ///< zeta of the sink V_parent -= V zeta n (4.16; 1/4)
    double fairness;     ///< F in [0, 1] (4.18-4.19; 1 = fair)
    int years_to_shed;   ///< years without radial growth before a branch is shed (0 = never)
    /// m: each winter the branches on the leader (the axis of the first shoot and its terminal
    /// buds) below this height are pruned, the clear trunk of a trained orchard tree (0 = none)
    double clear_trunk;
    /// years a lateral or terminal bud that did not shoot stays dormant (a spur) and is decided
    /// again each spring (0 = it aborts at once, the thesis); dormant buds regrow a broken axis
    int dormancy;
    bool relay_bias;     ///< the height/orientation bias Phi of eq. 7.1 on lateral shares
    bool listing_vigour; ///< listing: spring shares = h only (erratum 5), along-shoot budget
    /// resources go only to children whose subtree holds a bud that can shoot (above the
    /// ground); 0 = every child but an aborted bud takes its share (the thesis)
    bool bud_routing;
    /// continuations keep the frame of their stem (the stem does not twist, so the phyllotactic
    /// spiral goes on round it) and only laterals are rolled U up (Fig. 8.4); 0 = every new
    /// segment rolled U up (the thesis), which on a nearly vertical shoot makes the divergence's
    /// reference flip with the shoot's slight lean, putting every other bud on one side
    bool stem_frame;
    /* mechanics and wood */
    double youngs_juvenile;     ///< Pa, E_JUV 6e5 (crooked and general; wild x stiffness_factor)
    double youngs_juvenile_sd;  ///< relative sd of the per-shoot juvenile E (1/6)
    double youngs_adult;        ///< Pa, E_ADULT 1.587e8
    double adult_age;           ///< years from juvenile to adult wood (ADULT - GETS_ADULT = 19/12)
    double shear_ratio;         ///< G / E (1/16 for wood; the listing's G = 2E is unphysical)
    double density;             ///< kg/m^3, DENSITY 77.9
    double modulus_of_rupture;  ///< Pa, MOR 2.9e5 (0 = no breakage)
    double tropism;             ///< N, TROP 8e-4, towards +y
    double pipe_exponent;       ///< P, PIPE 2
    double ring_rate;           ///< kappa, RADIUS_GOAL 0.6
    double min_ring;            ///< m, EPSILON 1e-8: thinner increments are not rings
    double reaction_threshold;  ///< rad/m, xi = DEVIATION_FROM_EP 0.3 (<= 0: no reaction wood)
    double reaction_beta;       ///< beta = REACT_ALPHA 0.3 (8.25)
    double reaction_increment;  ///< m, RW_INCREMENT 0.001 (8.20)
    double reaction_max_aspect; ///< largest a/b reaction wood makes (0 = unbounded, thesis)
    /// lean (rad) from the set-point at which the reaction increment is full; smaller leans lay
    /// less, as sin(lean) (0 = the fixed increment, thesis)
    double reaction_full_lean;
    double growth_steps_per_year; ///< growth steps a year of ageing spans (2.8 MAXBUDS = 58.8)
    cbm_mech_discretization discretization; ///< staggered (default) or the listing's chain
    cbm_ring_memory memory;                 ///< segment rate (default) or the listing's joint rate
    cbm_ageing ageing;                      ///< per ring (default) or the listing's merged core
    double solve_tolerance;                 ///< relative residual of each equilibrium (1e-6)
    /// solver passes per equilibrium at most (400); a step that needs more goes on from the best
    /// iterate (counted in cbm_tree_summary.unconverged) and the next step continues from it
    int solve_max_passes;
    /// threads of each equilibrium's sweeps (cbm_solve_def.threads; 0, the default: one per
    /// processor); the results are the same to the bit for any number
    int solve_threads;
    /// the bending method of every equilibrium (default fast; relax, approx: docs/methods.md)
    cbm_mech_solver solver;
    /// with solver = approx, how an axis's load enters the generator (default calibrated: the
    /// thesis's tip load buckles tapered stems in growth; docs/methods.md, "In growth")
    cbm_approx_load approx_load;
    /* leaves and fruit */
    bool leaves;         ///< LEAVES 1
    double leaf_mass;    ///< kg, mean goal mass LEAF_MASS 2e-6 (sd mean/2)
    double leaf_density; ///< kg/m^2, leaf size sqrt(m / leaf_density), LEAF_DENSITY 0.095
    /// drawing only: leaf side = leaf_scale sqrt(m / leaf_density) (the listing scales a
    /// predefined leaf surface of unstated size by sqrt(m / leaf_density)); 8
    double leaf_scale;
    double fruit_mass;      ///< kg, mean goal mass FRUIT_MASS 0.01 (sd mean/2)
    double fruit_density;   ///< kg/m^3, FRUIT_DENSITY 300
    double fruit_prob;      ///< FRUIT_PROB 0.27
    int spur_leaves;        ///< leaves a dormant bud (spur) bears each summer (0, thesis)
    double spur_fruit_prob; ///< probability a spur sets a fruit in a summer (0, thesis)
    int first_fruit_year;   ///< first year with fruit (3; the listing fruits from year 1)
    double organ_rate;      ///< fraction of the leaf/fruit goal reached per step, 0.9
    double leaf_drop;       ///< probability a leaf falls per winter step (0.5)
    double fruit_drop;      ///< probability a fruit falls per winter step (0.5)
    /* crooked / wild switch (ch. 7) */
    double stiffness_factor; ///< wild E = factor x E (3)
    double tropism_factor;   ///< wild tropism = factor x tropism (5)
    double deviation_factor; ///< crooked deviation = factor x deviation (2)
    double tropism_fade;     ///< crooked: tropism fades linearly from this fraction of a shoot's
                             ///< nodes to zero at its last node (2/3; erratum 7)
    /* limits */
    int max_winter_steps; ///< winter steps at most (rings may still be growing) (40)
} cbm_tree_def;

/// The general fruit tree with real apple wood and organs (the built-in `fruit-tree`,
/// documented in docs/models.md; the thesis' values are the built-in `fruit-tree-thesis`).
CBM_API cbm_tree_def cbm_tree_def_default(void);

/// Sets one parameter from text (`name`, `value` as in a parameter file; angles in degrees;
/// functions as "x:y x:y ..."). CBM_E_NOT_FOUND for an unknown name, CBM_E_INVALID for a bad
/// value, with a message in the context's last error.
CBM_API cbm_status cbm_tree_def_set(cbm_context *ctx, cbm_tree_def *def, const char *name,
                                    const char *value);

/// Checks every parameter's range; CBM_E_INVALID naming the parameter.
CBM_API cbm_status cbm_tree_def_check(cbm_context *ctx, const cbm_tree_def *def);

/// Reads a parameter file (`name = value`, `func NAME = x:y ...`, `#` comments) over *def
/// (start from cbm_tree_def_default()). Errors are diagnostics `file:line:col: error: ...`;
/// returns CBM_E_SYNTAX (or CBM_E_IO) after reporting them. `name` is used in the messages.
CBM_API cbm_status cbm_tree_def_parse(cbm_context *ctx, cbm_tree_def *def, const char *text,
                                      size_t len, const char *name);
/// cbm_tree_def_parse on a file's contents.
CBM_API cbm_status cbm_tree_def_read(cbm_context *ctx, cbm_tree_def *def, const char *path);

/// Writes every parameter in parameter-file syntax into buf (NUL-terminated, truncated to size);
/// returns the length needed.
CBM_API size_t cbm_tree_def_format(const cbm_tree_def *def, char *buf, size_t size);

/// Names of the built-in models ("fruit-tree", "poplar-wild", "poplar-crooked", ...), NULL
/// terminated.
CBM_API const char *const *cbm_tree_builtin_names(void);
/// The built-in model's parameters (the same as the shipped models/NAME.tree).
CBM_API cbm_status cbm_tree_def_builtin(cbm_context *ctx, const char *name, cbm_tree_def *out);

typedef struct cbm_tree cbm_tree;

/// Year-by-year summary (also the running totals of the current year).
typedef struct cbm_tree_summary {
    int year;           ///< 1-based
    size_t segments;    ///< at the end of the year
    double height;      ///< m, highest point at the end of summer (loaded)
    double crown_width; ///< m, largest horizontal extent at the end of summer
    /// m, mean height at the end of summer of the branch tips that are still there once the
    /// leaves and fruit have fallen (all tips until then)
    double tip_height_loaded;
    double tip_height_unloaded; ///< m, mean height of the same tips once leaves and fruit fell
    size_t leaves;              ///< leaves at the end of summer (a spur's rosette counts each)
    size_t fruit;               ///< fruit at the end of summer
    size_t breaks;              ///< branches broken this year
    size_t removed;             ///< segments lost this year (breakage, shedding, ground)
    size_t shed;                ///< branches shed as unproductive this year
    size_t reaction_segments;   ///< segments that laid reaction wood this year
    size_t shoots;              ///< buds that shot in the spring before this summer
    size_t relay_shoots;        ///< of which from a pendulous parent (parent heading below level)
    double lean;                ///< deg from vertical of the first-year trunk (chord), NaN if lost
    double base_diameter;       ///< m, 2 sqrt(a b) of the lowest segment at the end of the year
    size_t growth_steps;        ///< growth steps of this year
    size_t passes;              ///< equilibrium passes (solver sweeps) of this year
    size_t newton_steps;
    size_t unconverged;   ///< equilibria left above the tolerance (pass budget spent)
    double seconds;       ///< wall-clock seconds spent on this year
    double seconds_solve; ///< of which equilibrium
    double seconds_rings; ///< of which rings and ageing
} cbm_tree_summary;

/// Creates the tree (one internode and an apex). The definition is checked and copied.
CBM_API cbm_status cbm_tree_create(cbm_context *ctx, const cbm_tree_def *def, cbm_tree **out);
CBM_API void cbm_tree_destroy(cbm_tree *tree);

/// The season a growth step belongs to.
typedef enum cbm_tree_season { CBM_TREE_SUMMER, CBM_TREE_WINTER } cbm_tree_season;

/// One growth step (a summer node or a winter step; the spring pass runs between winter and the
/// next summer). *year_done (optional) is set when the step completed a year.
CBM_API cbm_status cbm_tree_step(cbm_tree *tree, bool *year_done);
/// Steps to the end of the current year.
CBM_API cbm_status cbm_tree_year(cbm_tree *tree);
/// Grows def.years years (from wherever the tree is, up to that year).
CBM_API cbm_status cbm_tree_run(cbm_tree *tree);

/// Years completed.
CBM_API int cbm_tree_years(const cbm_tree *tree);
CBM_API cbm_tree_season cbm_tree_current_season(const cbm_tree *tree);
/// Summary of completed year k (1-based); NULL beyond.
CBM_API const cbm_tree_summary *cbm_tree_summary_of(const cbm_tree *tree, int year);
/// Running summary of the current (incomplete) year.
CBM_API const cbm_tree_summary *cbm_tree_summary_current(const cbm_tree *tree);

/// The mechanical plant (solved after every step). Borrowed; do not add or remove segments.
CBM_API const cbm_plant *cbm_tree_plant(const cbm_tree *tree);

/// What the model knows about one segment.
typedef struct cbm_tree_segment {
    bool lateral_bud;     ///< a lateral bud internode
    bool bud;             ///< carries an undecided bud
    bool aborted;         ///< an aborted bud (takes no resources)
    bool apex;            ///< carries a growing apex
    int count;            ///< node number in its annual shoot (1-based)
    double h;             ///< count / nodes of the shoot
    double vigour;        ///< resources received in the last spring pass
    double sink;          ///< resources taken from the continuation at this node (4.16)
    double lateral_share; ///< share of this node's vigour given to the lateral (after F)
    double leaf_mass;     ///< kg (all the leaves of the node)
    double fruit_mass;    ///< kg
    int leaves;           ///< leaves at the node (a spur's rosette: spur_leaves)
    bool dormant;         ///< a bud that did not shoot and waits (a spur)
} cbm_tree_segment;

CBM_API cbm_status cbm_tree_segment_info(const cbm_tree *tree, size_t seg, cbm_tree_segment *out);

/// The fairness transform of a lateral share p in [0, 1] (4.18-4.19 as the listing codes it):
/// p > 1/2 -> 1 - F (1 - p), p < 1/2 -> F p, clamped to [0, 1].
CBM_API double cbm_tree_fairness(double p, double fairness);

/// Appends the tree to a scene: branches (cbm_plant_to_scene), leaves (ovate blades on
/// petioles at their nodes) and fruit (spheres on stalks below their nodes), and a ground square
/// if `ground` (src/tree/tree_scene.c gives the shapes).
CBM_API cbm_status cbm_tree_to_scene(const cbm_tree *tree, cbm_scene *scene, int sides,
                                     bool ground);

#ifdef __cplusplus
}
#endif
#endif
