/* cambium: Oberlaender's parametric tree (B.Sc. thesis, Goettingen 2020), a built-in model family
 * beside the fruit tree: a generic model of European monopodial trees configured without
 * programming by the 24 parameters of the thesis's Table 3, several of which are formulas
 * ("lambdas") evaluated on the tree, a shoot or a bud.
 *
 * The unit of growth is the annual shoot: one cylinder per axis per year with nodes at regular
 * distances, lateral buds and leaves at the nodes, an apical bud at the tip, and a gravitropism
 * joint (the thesis's Angle = GroIMP RV) in front of every shoot whose strength starts at
 * orientationLambda and grows each year by bendingLambda. One step is one year: tree level
 * (aggregates, baseLengthLambda, carbonTaxLambda), shoot level (carbon, sprouting, new shoots
 * from the buds of last year's shoots, pipe-model radii, bending, proventitious shoots), then
 * leaf death and the pruning of shoots without leaves or children. A stand holds one or more
 * trees (seeds with germination timers). Lengths in parameter files and formulas are in cm as
 * in the thesis (Table 3); every output (geometry, the report) is SI. docs/models.md
 * ("Oberlaender's parametric tree") documents the parameters, the formulas and every
 * reconstruction; src/tree/ober_grow.c the algorithm.
 */
#ifndef CAMBIUM_OBER_H
#define CAMBIUM_OBER_H

#include "cambium/base.h"
#include "cambium/geom.h"
#include "cambium/mech.h"

#ifdef __cplusplus
extern "C" {
#endif

#define CBM_OBER_ORDERS      8   ///< per-order formula slots (orders 0..7; the last repeats)
#define CBM_OBER_LIST_MAX    16  ///< entries of numberNewShoots_0, shootPoss, shootangle
#define CBM_OBER_FORMULA_MAX 400 ///< characters of one formula
#define CBM_OBER_TREES_MAX   400 ///< trees of a stand

/// One formula of a parameter file: an expression of the model language (cpfg dialect, docs/
/// language.md) over the variables of the thesis's Table 2, and where it was written, so that
/// the errors found when it is compiled name the file, line and column.
typedef struct cbm_ober_formula {
    char text[CBM_OBER_FORMULA_MAX]; ///< the expression ("" = not set)
    char file[96];                   ///< where it was written (a file, a built-in, "-D NAME")
    int line, col;                   ///< 1-based position of text[0] there
} cbm_ober_formula;

/// Every parameter. Names in parameter files are the thesis's (maxOrder, baseLengthLambda, ...),
/// listed in docs/models.md.
typedef struct cbm_ober_def {
    uint64_t seed; ///< generator seed
    int years;     ///< years grown by cbm_ober_run
    /* Table 3, in its order */
    int max_order;                ///< maxOrder
    cbm_ober_formula base_length; ///< baseLengthLambda (tree): cm/year -> baseLength
    cbm_ober_formula carbon_tax;  ///< carbonTaxLambda (tree) -> carbonTax
    int n_specific_length;        ///< slots set (order k uses slot min(k, n - 1))
    cbm_ober_formula specific_length[CBM_OBER_ORDERS]; ///< specificLengthLambda[order] (bud), cm
    int n_num_nodes;
    cbm_ober_formula num_nodes[CBM_OBER_ORDERS];   ///< numNodeLambda[order] (bud), >= 1
    cbm_ober_formula sprouting;                    ///< sproutingPossibilityLambda (shoot), bool
    cbm_ober_formula proventitious;                ///< proventitiosShootLambda (sleeping bud)
    cbm_ober_formula apical_split;                 ///< apicalSplitLambda (apical bud): a fork
    cbm_ober_formula short_shoot;                  ///< shortShootLambda (bud)
    double possibility_node_0, possibility_node_x; ///< a node bears growing buds if U < value
    double possibility_bud_0, possibility_bud_y;   ///< a bud grows if U < value, else sleeps
    int n_new_shoots;
    double number_new_shoots_0[CBM_OBER_LIST_MAX]; ///< P(k buds per trunk node), index k
    int n_shoot_poss;
    double shoot_poss[CBM_OBER_LIST_MAX]; ///< deg, head angle of each bud of a branch node
    int n_shoot_angle;
    double shoot_angle[CBM_OBER_LIST_MAX]; ///< deg, insertion angle, index order - 1
    double leaf_length, leaf_width;        ///< cm (leafL, leafW)
    int leaf_die_age;                      ///< years a leaf lives (1 = deciduous)
    double pipe_size;                      ///< cm, radius R_p of one pipe
    cbm_ober_formula orientation;          ///< orientationLambda (bud): joint strength
    cbm_ober_formula bending;              ///< bendingLambda (shoot): yearly increment
    double offset_0, offset_x;             ///< deg, head rotation between successive nodes
    /* beyond Table 3 (docs/models.md says why) */
    double initial_length; ///< cm, the seedling's trunk (0 = specificLengthLambda[0] at age 1)
    double fork_angle;     ///< deg, each arm of a fork from the axis
    int seed_stems;        ///< seedStems: trunks a seed makes (Listing 14: 5), each its own axis
    double seed_stem_head; ///< seedStemHead, deg: trunk k turned by k times this about the vertical
    double seed_stem_tilt; ///< seedStemTilt, deg: each trunk's tilt from the vertical (0: upright)
    bool pipe_all_leaves;  ///< pipe model counts all living leaves (0: this year's new ones)
    bool carbon_sum;       ///< shoot carbon is the sum of its leaves' (0: their mean)
    bool light;            ///< leaf carbon from ray-cast light (0: every leaf unshaded, 1)
    int sky;               ///< cbm_sky_kind of the light pass (0 dome, 1 field, 2 UOC, 3 SOC)
    int light_rings, light_azimuths; ///< the sky's sectors (cbm_light_def rings, azimuths)
    int light_samples;               ///< sample points per leaf side (cbm_light_def samples)
    bool light_stems; ///< the shoots shade too, each a hexagonal prism of its radius (0: leaves)
    /* mechanics in the growth (docs/models.md, "Mechanics"): every year each tree's statics
     * bends its shoots, the new wood memorises the bend, and the bent tree grows on and is lit */
    bool mech_feedback;    ///< mechanicsFeedback (0: the kinematic shape alone)
    double mech_e;         ///< mechE, Pa: green wood's Young's modulus (8e9)
    double mech_density;   ///< mechDensity, kg/m^3: green wood (800)
    double mech_leaf_mass; ///< mechLeafMass, kg/m^2 of leaf (0.2)
    /// solve_threads: threads of each equilibrium's sweeps, mechanicsFeedback's and
    /// cbm_ober_mechanics' (cbm_solve_def.threads; 0, the default: one per processor)
    int solve_threads;
    /* the stand */
    int stand_x, stand_y; ///< trees on a grid of stand_x by stand_y (1 x 1: one tree)
    double spacing;       ///< m between neighbouring trees of the grid
    double jitter;        ///< m, random displacement of each tree from its grid point
    int stagger;          ///< years: germination timers drawn uniformly in 0..stagger
} cbm_ober_def;

/// Defaults: a single Rauh tree (whorled, orthotropic) of the thesis's Table 4 with the
/// statistical Cryptomeria height curve (docs/models.md gives every value and why).
CBM_API cbm_ober_def cbm_ober_def_default(void);

/// Sets one parameter from text as in a parameter file (`name`, `value`; formulas as
/// expressions, lists as `{a, b, ...}`, `name[k]` a per-order slot). `origin` names the source
/// in later messages (NULL: "-D name"). CBM_E_NOT_FOUND for an unknown name, CBM_E_INVALID for
/// a bad value, with a message in the context's last error.
CBM_API cbm_status cbm_ober_def_set(cbm_context *ctx, cbm_ober_def *def, const char *name,
                                    const char *value, const char *origin);

/// Checks every value and compiles every formula; CBM_E_INVALID naming the parameter, or
/// CBM_E_SYNTAX after reporting formula errors as `file:line:col: error: ...`.
CBM_API cbm_status cbm_ober_def_check(cbm_context *ctx, const cbm_ober_def *def);

/// Reads a parameter file (`family = oberlaender`, then `name = value` lines, `#` comments)
/// over *def. Errors are diagnostics `file:line:col: error: ...`; CBM_E_SYNTAX after reporting.
CBM_API cbm_status cbm_ober_def_parse(cbm_context *ctx, cbm_ober_def *def, const char *text,
                                      size_t len, const char *name);
CBM_API cbm_status cbm_ober_def_read(cbm_context *ctx, cbm_ober_def *def, const char *path);

/// True when a parameter file's text declares `family = oberlaender` (its first setting).
CBM_API bool cbm_ober_text_is_family(const char *text, size_t len);

/// Writes every parameter in parameter-file syntax into buf (NUL-terminated, truncated);
/// returns the length needed.
CBM_API size_t cbm_ober_def_format(const cbm_ober_def *def, char *buf, size_t size);

/// Built-in parameter sets (ober-massart, ober-attims, ober-rauh, ober-troll,
/// ober-cryptomeria, ober-carbon), NULL terminated; the same as the shipped models/NAME.tree.
CBM_API const char *const *cbm_ober_builtin_names(void);
CBM_API cbm_status cbm_ober_def_builtin(cbm_context *ctx, const char *name, cbm_ober_def *out);

typedef struct cbm_ober_stand cbm_ober_stand;

/// The per-tree, per-year report (thesis getInfo(), digest section 5).
typedef struct cbm_ober_report {
    int year;               ///< stand year (1-based)
    int age;                ///< tree age in years (0 = not germinated)
    double height;          ///< m, highest point above the tree's base
    size_t leaves;          ///< living leaves
    size_t shoots;          ///< living annual shoots
    size_t shoots_order[4]; ///< of which order 0, 1, 2, >= 3
    size_t new_shoots;      ///< shoots made this year
    size_t proventitious;   ///< of which from sleeping buds
    size_t forks;           ///< apical splits this year
    size_t removed;         ///< shoots pruned this year (no leaves, no children)
    double wood_volume;     ///< m^3, sum of pi r^2 len over the shoots
    double trunk_volume;    ///< m^3, the order-0 shoots'
    double base_diameter;   ///< m, of the first trunk shoot
    double carbon_tax;      ///< carbonTax of this year
    double carbon_mean;     ///< carbonMean: mean carbon of the leaves
    double base_length;     ///< cm, baseLength of this year
    size_t light_rays;      ///< rays of the stand's light pass this year (0 without light)
    double light_seconds;   ///< its wall-clock time
} cbm_ober_report;

/// Creates a stand: def.stand_x x def.stand_y seeds (timers 0..stagger); trees with timer 0
/// germinate in the first step. The definition is checked, its formulas compiled and copied.
CBM_API cbm_status cbm_ober_create(cbm_context *ctx, const cbm_ober_def *def, cbm_ober_stand **out);
CBM_API void cbm_ober_destroy(cbm_ober_stand *stand);
/// One year of every tree of the stand.
CBM_API cbm_status cbm_ober_year(cbm_ober_stand *stand);
/// Grows def.years years from wherever the stand is.
CBM_API cbm_status cbm_ober_run(cbm_ober_stand *stand);
CBM_API int cbm_ober_years(const cbm_ober_stand *stand);
CBM_API size_t cbm_ober_tree_count(const cbm_ober_stand *stand);
/// Report of tree `tree` for completed year `year` (1-based); NULL beyond.
CBM_API const cbm_ober_report *cbm_ober_report_of(const cbm_ober_stand *stand, size_t tree,
                                                  int year);
/// Position of a tree's base, m (y up).
CBM_API cbm_vec3 cbm_ober_tree_position(const cbm_ober_stand *stand, size_t tree);

/// One annual shoot as the model knows it (lengths in m, angles in degrees).
typedef struct cbm_ober_shoot {
    size_t tree;
    int64_t parent; ///< index of the mother shoot, -1 for a seedling's
    int order, trend, age, nodes;
    bool lateral;       ///< grew from a lateral bud (else the apical continuation or a fork)
    bool short_shoot;   ///< a short shoot (no lateral buds)
    bool proventitious; ///< grew from a sleeping bud
    double position;    ///< p of the bud it grew from (1 = apical)
    double length, radius;
    double tropism;     ///< strength of its joint (orientation + the yearly bending)
    double carbon;      ///< shoot carbon of the last step
    int leaves;         ///< living leaves
    int buds;           ///< lateral buds made (growing or sleeping)
    int active_buds;    ///< of which made growing (fertile node and bud, order <= maxOrder)
    cbm_vec3 base, tip; ///< m, world, y up
} cbm_ober_shoot;

CBM_API size_t cbm_ober_shoot_count(const cbm_ober_stand *stand);
CBM_API cbm_status cbm_ober_shoot_info(const cbm_ober_stand *stand, size_t i, cbm_ober_shoot *out);

/// Appends the stand to a scene: each shoot a cylinder (12 sides or `sides`), each living leaf
/// a horizontal green rectangle at its node, and a ground square if `ground`.
CBM_API cbm_status cbm_ober_to_scene(const cbm_ober_stand *stand, cbm_scene *scene, int sides,
                                     bool ground);

/// Writes the stand as one OpenAlea MTG coding file (FORM-A, docs/formats.md): one plant P<n>
/// per tree (n = tree index + 1; trees without shoots are absent), its annual shoots as segments
/// S in axes A, with the shoot's features (m, y up). Nothing is left at path on failure.
CBM_API cbm_status cbm_ober_write_mtg(cbm_context *ctx, const cbm_ober_stand *stand,
                                      const char *path);

/// The statics on a tree (docs/models.md, "Mechanics"): wood and leaf loads.
typedef struct cbm_ober_mech_def {
    double youngs_modulus;     ///< Pa, green wood along the grain (default 8e9)
    double density;            ///< kg/m^3, green wood (default 800)
    double leaf_mass_per_area; ///< kg/m^2, fresh leaf (default 0.2)
    double gravity;            ///< m/s^2 (default 9.81; 0 keeps the rest shape)
} cbm_ober_mech_def;
CBM_API cbm_ober_mech_def cbm_ober_mech_def_default(void);

/// How the statics' shape of a tree differs from the kinematic shape (the joint's).
typedef struct cbm_ober_mech_result {
    size_t tree, shoots, segments;
    double mass;                ///< kg, wood and leaves
    bool converged;             ///< the solver reached its tolerance
    double residual;            ///< its relative residual
    double max_tip_difference;  ///< m, max over shoots of |tip (statics) - tip (joint)|
    double mean_tip_difference; ///< m, its mean over the shoots
    size_t max_shoot;           ///< the shoot (stand index) of the max
    double max_sag;             ///< m, max |tip (statics) - tip (rest shape, no joint)|
    double max_joint;           ///< m, max |tip (joint) - tip (rest shape)|
    double kinematic_height, mechanical_height; ///< m, above the tree's base
} cbm_ober_mech_result;

/// Makes tree `tree` of the stand a mechanical plant (each shoot one segment per node, the
/// pipe-model radius, the shape without the gravitropism joint as the rest shape, leaves as point
/// masses), solves its statics under gravity and compares the shoot tips with the kinematic
/// shape. On a tree grown with mechanicsFeedback the rest shape also carries the bends the
/// wood memorised (docs/models.md). The solve runs on the stand's solve_threads. *plant_out
/// (optional) receives the solved plant (the caller destroys it).
CBM_API cbm_status cbm_ober_mechanics(const cbm_ober_stand *stand, size_t tree,
                                      const cbm_ober_mech_def *def, cbm_ober_mech_result *out,
                                      cbm_plant **plant_out);

#ifdef __cplusplus
}
#endif
#endif
