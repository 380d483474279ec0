/* cambium: light interception by ray casting over every plant of a scene (docs/light.md).
 *
 * The leaves of all plants (planar quads or triangles) and any occluders (stems, as triangles)
 * form one ray-casting scene; both faces of every leaf and occluder stop light. Each leaf is
 * sampled at a stratified set of points; from each point one ray goes towards each light source
 * of the sky (a sector of a discretised sky, a light of the thesis's dome or field, the sun).
 * A leaf's result is its intercepted light in m² of unshaded horizontal leaf: a horizontal,
 * unshaded leaf of 1 m² receives 1.0 under every sky (the role of Oberländer's maxLightSquare,
 * 2020, §5.5). Axes: metres, y up (as everywhere in cambium). */
#ifndef CAMBIUM_LIGHT_H
#define CAMBIUM_LIGHT_H

#include "cambium/base.h"
#include "cambium/geom.h"

#ifdef __cplusplus
extern "C" {
#endif

/// One leaf: a planar quad, counter-clockwise seen from above (its upper face's normal is
/// (p1 - p0) x (p2 - p0) and points up); a triangle repeats p[2] as p[3]. Positions in m.
/// `plant` says which plant it belongs to (carried for the caller; every leaf shades every other).
typedef struct cbm_light_leaf {
    cbm_vec3 p[4];
    uint32_t plant;
} cbm_light_leaf;

/// The skies. DOME and FIELD are the two skies of Oberländer (2020, §5.5.1-2): a dome of
/// directional lights aimed at a focal point, zenith lights stronger; a field of the same lights
/// spread over a rectangle at one height (a stand). UOC and SOC are the CIE uniform overcast and
/// standard overcast skies (radiance L(θ) ∝ 1 and ∝ (1 + 2 cos θ)/3), discretised into sectors.
typedef enum cbm_sky_kind { CBM_SKY_DOME, CBM_SKY_FIELD, CBM_SKY_UOC, CBM_SKY_SOC } cbm_sky_kind;

/// How a FIELD treats its edges.
typedef enum cbm_light_edge {
    CBM_LIGHT_EDGE_OPEN,     ///< light only enters through the field's rectangle at its height
    CBM_LIGHT_EDGE_PERIODIC, ///< the rectangle tiles the plane: a ray leaving a side re-enters
                             ///< through the opposite side (an endless stand of copies)
} cbm_light_edge;

typedef struct cbm_light_def {
    cbm_sky_kind sky;
    /* ---- the sky's discretisation (all skies but the sun) ---- */
    int rings;    ///< zenith-angle rings of the hemisphere, >= 1 (6)
    int azimuths; ///< azimuth sectors per ring, >= 1 (12); the dome and field add a zenith light
    /* ---- direct light ---- */
    double direct_fraction; ///< share of the horizontal irradiance from the sun, 0..1 (0)
    cbm_vec3 sun;           ///< direction towards the sun (any length, y > 0); (0.3, 0.8, 0.2)
    /* ---- the thesis's dome: beams of finite width aimed at the focal point ---- */
    cbm_vec3 focus;     ///< m, the dome's focal point (0, 0, 0)
    double dome_radius; ///< m, radius of each light's beam around the focus; 0: unbounded (0)
    /* ---- the thesis's field ---- */
    /// m, the rectangle in (x, z), also the tile of a periodic stand. Unset (min == max): for
    /// open edges the scene's bounding rectangle widened until every leaf gets every light; for
    /// periodic edges the scene's bounding rectangle (0, 0)
    double field_min[2], field_max[2];
    double field_height; ///< m, height of the lights; <= the scene's top: just above it (0)
    cbm_light_edge edge; ///< (CBM_LIGHT_EDGE_OPEN)
    /* ---- sampling ---- */
    int samples;    ///< sample points per leaf side: samples² points per leaf, 1..16 (1)
    bool two_sided; ///< a leaf takes light on both faces (true); false: the upper face only
    double max_light_square; ///< the light of a horizontal unshaded 1 m² leaf in the sky's units;
                             ///< the results are divided by it. 0: the exact value of the sky
                             ///< (results in m² of unshaded horizontal leaf) (0)
    int threads;             ///< 0: one per processor (at most 64); results never depend on it
    uint64_t seed;           ///< jitter of the sample points (1)
} cbm_light_def;

/// The defaults given in parentheses above.
CBM_API cbm_light_def cbm_light_def_default(void);

typedef struct cbm_light_stats {
    size_t rays;      ///< occlusion rays cast
    double seconds;   ///< wall-clock time of the call
    size_t sources;   ///< directional sources of the sky (sectors, lights, sun)
    double total;     ///< sum of absorbed over all leaves, m²
    double leaf_area; ///< sum of the leaves' one-sided areas, m²
} cbm_light_stats;

/// One directional source of a sky: `dir` towards the sky (unit, y > 0), `irradiance` on a
/// surface normal to dir, scaled so that the sources' horizontal irradiance sums to 1.
typedef struct cbm_light_source {
    cbm_vec3 dir;
    double irradiance;
} cbm_light_source;

/// The sources of def's sky (sectors, dome or field lights, and the sun when direct_fraction > 0).
/// *out is allocated from ctx (release with cbm_light_sources_free); *n its length.
CBM_API cbm_status cbm_light_sources(cbm_context *ctx, const cbm_light_def *def,
                                     cbm_light_source **out, size_t *n);
CBM_API void cbm_light_sources_free(cbm_context *ctx, cbm_light_source *s, size_t n);

/// absorbed[i]: light intercepted by leaf i in m² of unshaded horizontal leaf equivalent (a
/// horizontal unshaded 1 m² leaf receives 1.0). occluders: 3 vertices per triangle (stems), may
/// be NULL/0. absorbed has n_leaves entries (caller's); stats may be NULL. Deterministic for a
/// seed, whatever the number of threads.
CBM_API cbm_status cbm_light_intercept(cbm_context *ctx, const cbm_light_def *def,
                                       const cbm_light_leaf *leaves, size_t n_leaves,
                                       const cbm_vec3 *occluders, size_t n_occluder_triangles,
                                       double *absorbed, cbm_light_stats *stats);

/// The thesis's calibration of maxLightSquare (§5.5): the light (in the sky's units, before
/// division by def->max_light_square) that a horizontal 1 m x 1 m leaf alone at `at` receives.
/// Under UOC, SOC and an unbounded dome it is 1 anywhere; a bounded dome gives less away from
/// its focus, an open field less near its edges.
CBM_API cbm_status cbm_light_calibrate(cbm_context *ctx, const cbm_light_def *def, cbm_vec3 at,
                                       double *max_light_square);

/// The light of the leaves of a writer's scene (geom.h): the triangles of the parts whose organ
/// is CBM_ORGAN_LEAF are the leaves (each turned to face up), those of every other part but the
/// ground occlude. Sets each leaf part's `light` to its intercepted light over its one-sided
/// area (1 = unshaded horizontal), for `color_by = CBM_COLOR_LIGHT`. part_light and part_area
/// (optional, cbm_scene_part_count entries, caller's) receive each part's intercepted light in
/// m² and its leaf area in m² (0 for other parts); *n_leaf_triangles (optional) the leaves cast.
CBM_API cbm_status cbm_light_scene(cbm_context *ctx, const cbm_light_def *def, cbm_scene *scene,
                                   double *part_light, double *part_area, size_t *n_leaf_triangles,
                                   cbm_light_stats *stats);

#ifdef __cplusplus
}
#endif
#endif
