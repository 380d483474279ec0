/* cambium: a tree measured as a forester would measure it.
 *
 * The measures work on a table of tubes, one row per segment (cbm_measure_segment): the
 * mechanical plant's segments (cbm_measure_plant fills the table), the rows of a segments.csv
 * (docs/formats.md), or the turtle's segments of an L-system model. From it: height, trunk
 * diameter at breast height (1.3 m) or at the base of a shorter tree, crown width and crown base,
 * the safety against self-buckling (McMahon's elastic similarity), the exponent of the pipe
 * model at forks (Leonardo's rule), the insertion angles of the laterals, the distribution of
 * the stress ratio, and the tubes that pass through one another (branch intersections).
 * docs/models.md ("Measured realism") says what each is and where real trees stand.
 */
#ifndef CAMBIUM_MEASURE_H
#define CAMBIUM_MEASURE_H

#include "cambium/base.h"
#include "cambium/mech.h"

#ifdef __cplusplus
extern "C" {
#endif

/// One segment: a tube (a truncated cone) from p0 to p1. y is up.
typedef struct cbm_measure_segment {
    int64_t parent; ///< index of the parent segment (lower than this one), -1 for a root
    /// starts a lateral axis at its parent's distal node; false: continues the parent's axis
    /// (a root starts an axis either way)
    bool lateral;
    cbm_vec3 p0, p1; ///< proximal and distal points, m
    /// tube radius at p0 and p1, m (an elliptical section: the mean semi-axis (a + b) / 2)
    double r0, r1;
    double youngs_modulus; ///< structural E of the section, Pa; NaN = unknown
    double density;        ///< of the fresh wood, kg/m^3; NaN = unknown
    double stress_ratio;   ///< peak bending stress / modulus of rupture; NaN = unknown
} cbm_measure_segment;

typedef struct cbm_measure_def {
    double breast_height; ///< m above the base where the trunk diameter is taken (1.3)
    double gravity;       ///< m/s^2, for the buckling height (9.81)
    /// a lateral branch starts the crown when its subtree holds at least this fraction of the
    /// tree's axis length (0.05): twigs low on the trunk do not lower the crown base
    double crown_branch_fraction;
} cbm_measure_def;

/// Defaults: breast height 1.3 m, gravity 9.81 m/s^2, crown branches of 5 % of the axis length.
CBM_API cbm_measure_def cbm_measure_def_default(void);

/// Quantiles of a sample (NaN when count is 0).
typedef struct cbm_measure_quantiles {
    size_t count;
    double min, q10, q25, median, q75, q90, max;
} cbm_measure_quantiles;

typedef struct cbm_tree_measures {
    size_t segments;
    size_t axes;   ///< roots and laterals (each starts an axis)
    int max_order; ///< branch order of the deepest axis (0: the trunk alone)
    double height; ///< m, highest point of any segment above the base (the lowest root point)
    /// m, the lowest point of any segment end (world y, not above the base: below 0 a segment
    /// ends below the ground of a plant rooted at the origin)
    double lowest;
    double total_length; ///< m, sum of the segment lengths
    /// m: trunk diameter (2 r, interpolated along the segment) at breast height, or at the
    /// base when the trunk does not reach it (then diameter_at_base). The trunk is the first
    /// root and, at every node, its thickest child (the continuation on a tie): the main stem
    /// a forester follows through a fork.
    double diameter;
    bool diameter_at_base;
    double base_diameter; ///< m, of the first trunk segment at its proximal end
    /// m: largest horizontal extent of the segment ends along x or along z (as the growth
    /// summary's crown width)
    double crown_width;
    /// m above the base: the lowest node of the trunk where a lateral branch holding at least
    /// crown_branch_fraction of the axis length leaves; NaN without one
    double crown_base_height;
    /// Self-buckling (McMahon 1973): H_cr = 0.79 (E / (rho g))^(1/3) D^(2/3) with D = diameter
    /// and E, rho the medians over the trunk segments up to where D is taken. NaN when the
    /// table has no wood properties.
    double trunk_modulus;   ///< Pa
    double trunk_density;   ///< kg/m^3
    double buckling_height; ///< m, H_cr
    double buckling_ratio;  ///< height / H_cr (real trees: about 1/4)
    size_t forks;           ///< nodes with two or more children
    /// forks where no exponent exists (a child as thick as its parent, or a zero diameter)
    size_t forks_unsolved;
    cbm_measure_quantiles pipe_exponent; ///< a with D_parent^a = sum D_child^a, per fork
    cbm_measure_quantiles branch_angle;  ///< rad, lateral's direction to its parent's
    cbm_measure_quantiles stress_ratio;  ///< over the segments with a known ratio
    double stress_above_half;            ///< fraction of those with ratio > 0.5
    size_t intersecting;                 ///< segments whose tube meets a non-adjacent one
    double intersecting_fraction;        ///< intersecting / segments
    size_t intersecting_pairs;           ///< pairs of non-adjacent segments that meet
} cbm_tree_measures;

/// Measures a table of n segments (parents before children). CBM_E_INVALID (naming the row)
/// for a parent out of range or not before its child, or a non-finite point or radius.
CBM_API cbm_status cbm_measure_segments(cbm_context *ctx, const cbm_measure_def *def,
                                        const cbm_measure_segment *seg, size_t n,
                                        cbm_tree_measures *out);

/// The table of a mechanical plant at its current state (after a solve or cbm_plant_evaluate):
/// radius (a + b) / 2, E = sqrt(EI_L EI_U) / (pi a^2 b^2 / 4), density = mass per length / area,
/// the stress ratio; a child whose branch order differs from its parent's is lateral (as the
/// segments table, which has the orders, says it). *out receives an array of
/// cbm_plant_segment_count rows allocated with the context's allocator; release it with
/// cbm_measure_table_free.
CBM_API cbm_status cbm_measure_plant_table(cbm_context *ctx, const cbm_plant *plant,
                                           cbm_measure_segment **out, size_t *n);
CBM_API void cbm_measure_table_free(cbm_context *ctx, cbm_measure_segment *table, size_t n);

/// cbm_measure_plant_table then cbm_measure_segments.
CBM_API cbm_status cbm_measure_plant(cbm_context *ctx, const cbm_measure_def *def,
                                     const cbm_plant *plant, cbm_tree_measures *out);

/// Branch intersections alone. Two segments meet when the distance between their axes is below
/// the sum of their radii at the closest points. Adjacent pairs never count: segments that
/// share a node (parent and child, siblings) and, more generally, pairs whose path along the
/// tree between their nearest ends is no longer than the sum of their largest radii (they meet
/// inside the junction's wood). A uniform spatial grid finds the candidate pairs: O(n) for a
/// tree of comparable segments. flags (optional, n entries) receives 1 for every intersecting
/// segment, 0 otherwise; *pairs (optional) the number of intersecting pairs.
CBM_API cbm_status cbm_measure_intersections(cbm_context *ctx, const cbm_measure_segment *seg,
                                             size_t n, size_t *intersecting, size_t *pairs,
                                             unsigned char *flags);

#ifdef __cplusplus
}
#endif
#endif
