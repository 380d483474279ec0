/* cambium: writing scenes to files people can open.
 *
 * cbm_scene_write picks the format from the path's extension: .obj (with a .mtl beside it),
 * .ply (binary little-endian), .glb (glTF 2.0 binary, with an animation when frames are given),
 * .png (shaded rendering through Embree ray casting), .svg (projection, painter's algorithm),
 * .csv (one row per part). Every writer goes through cbm_out: no partial file is ever left, and
 * disk errors come back as CBM_E_IO with the path in the context's last error.
 *
 * Axes and units everywhere: metres, y up (as in glTF and lpfg). docs/formats.md says what each
 * file holds.
 */
#ifndef CAMBIUM_WRITE_H
#define CAMBIUM_WRITE_H

#include "cambium/base.h"
#include "cambium/geom.h"
#include "cambium/mech.h"
#include "cambium/turtle.h"

#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

/// Where the camera looks from (PNG, SVG). Front looks along -z, side along -x (from +x), top
/// along -y; iso from (+1, +0.8, +1) towards the plant; vector uses view_dir.
typedef enum cbm_camera_view {
    CBM_VIEW_FRONT,
    CBM_VIEW_SIDE,
    CBM_VIEW_TOP,
    CBM_VIEW_ISO,
    CBM_VIEW_VECTOR
} cbm_camera_view;

/// What the colour of a part shows.
typedef enum cbm_color_by {
    CBM_COLOR_MATERIAL,   ///< the part's own colour
    CBM_COLOR_STRESS,     ///< bending stress / modulus of rupture, 0..1 (above 1 saturates)
    CBM_COLOR_AGE,        ///< wood age, years
    CBM_COLOR_REACTION,   ///< fraction of reaction wood, 0..1
    CBM_COLOR_ORDER,      ///< branch order, one colour per order
    CBM_COLOR_STRESS_MPA, ///< bending stress in MPa (range from the data unless set)
    CBM_COLOR_LIGHT,      ///< leaves: relative light (cbm_part.light; 0 to the largest unless set)
    CBM_COLOR_COUNT
} cbm_color_by;

typedef struct cbm_write_options {
    int width, height;     ///< picture size, pixels (PNG, SVG)
    cbm_camera_view view;  ///< camera direction (PNG, SVG)
    cbm_vec3 view_dir;     ///< with CBM_VIEW_VECTOR: direction the camera looks along
    float background[4];   ///< linear RGBA; alpha 0 gives a transparent PNG / no SVG backdrop
    cbm_color_by color_by; ///< colouring of every writer (vertex colours, materials, pixels)
    double range_min;      ///< colour-bar range of the quantity; NaN: from the data (age) or
    double range_max;      ///< the natural range (stress ratio and reaction wood 0..1)
    bool ground;           ///< false drops ground parts; true (PNG) adds a ground plane
                           ///< under the plant when the scene has none
    bool legend;           ///< colour bar with its range when colouring by a quantity (PNG/SVG)
    bool shadows;          ///< sun shadows (PNG)
    int ao_samples;        ///< ambient-occlusion rays per pixel, 0 = none (PNG)
    int supersample;       ///< n x n samples per pixel, 1..4 (PNG)
    int threads;           ///< render threads, 0 = one per processor (PNG)
    /// Animation (.glb): frame_count scenes (growth steps), shown frame_time seconds each; one
    /// node per frame made visible in turn by a STEP scale animation. NULL/0: no animation.
    const cbm_scene *const *frames;
    size_t frame_count;
    double frame_time; ///< s
} cbm_write_options;

/// 800 x 800, iso view, white background, material colours, ground, legend, shadows, 4 AO
/// rays, 2 x 2 supersampling, threads from the machine, no frames, frame_time 0.5 s.
CBM_API cbm_write_options cbm_write_options_default(void);

/// Writes the scene in the format named by the path's extension (.obj .ply .glb .png .svg .csv).
/// opts may be NULL (defaults). For .glb with opts->frames set, scene may be NULL and the file
/// holds the animation. CBM_E_UNSUPPORTED for another extension.
CBM_API cbm_status cbm_scene_write(cbm_context *ctx, const cbm_scene *scene, const char *path,
                                   const cbm_write_options *opts);

/// Writes the scene in the named format ("obj", "ply", "glb", "png", "svg", "csv") whatever the
/// path's extension, e.g. to a device or a pipe ("/dev/stdout").
CBM_API cbm_status cbm_scene_write_as(cbm_context *ctx, const cbm_scene *scene, const char *path,
                                      const char *format, const cbm_write_options *opts);

/// Wavefront OBJ with normals, vertex colours (x y z r g b) and a .mtl file beside it (same
/// name, extension .mtl), one material per organ and colour.
CBM_API cbm_status cbm_write_obj(cbm_context *ctx, const cbm_scene *scene, const char *path,
                                 const cbm_write_options *opts);
/// PLY binary little-endian: position, normal, RGBA, and per-vertex part data (stress ratio,
/// age, reaction wood, order, segment, part); faces carry their part index.
CBM_API cbm_status cbm_write_ply(cbm_context *ctx, const cbm_scene *scene, const char *path,
                                 const cbm_write_options *opts);
/// glTF 2.0 binary: one node per organ kind (per branch order for branches), normals, colours,
/// materials, custom attributes _STRESS_RATIO, _AGE, _REACTION_WOOD, _ORDER, _SEGMENT.
/// With opts->frames: one node per frame and a STEP animation of their visibility.
CBM_API cbm_status cbm_write_glb(cbm_context *ctx, const cbm_scene *scene, const char *path,
                                 const cbm_write_options *opts);
/// A growth animation built frame by frame (for `--every K` in long runs: each frame's geometry
/// is copied into the animation at once, so one scene can be refilled for the next step).
/// Written as cbm_write_glb writes frames. The options (copied at creation) give the colour
/// mode, ground and frame_time (> 0 s).
typedef struct cbm_animation cbm_animation;
CBM_API cbm_status cbm_animation_create(cbm_context *ctx, const cbm_write_options *opts,
                                        cbm_animation **out);
/// Adds the scene as the next frame; CBM_E_UNSUPPORTED for a scene holding pixel lines.
CBM_API cbm_status cbm_animation_add_frame(cbm_animation *anim, const cbm_scene *scene);
CBM_API size_t cbm_animation_frame_count(const cbm_animation *anim);
/// Writes the .glb; afterwards the animation takes no more frames (CBM_E_INVALID).
CBM_API cbm_status cbm_animation_write(cbm_animation *anim, const char *path);
CBM_API void cbm_animation_destroy(cbm_animation *anim);

/// PNG picture (8-bit RGBA) of the scene ray cast with Embree.
CBM_API cbm_status cbm_write_png(cbm_context *ctx, const cbm_scene *scene, const char *path,
                                 const cbm_write_options *opts);
/// SVG projection: shaded triangles sorted back to front.
CBM_API cbm_status cbm_write_svg(cbm_context *ctx, const cbm_scene *scene, const char *path,
                                 const cbm_write_options *opts);
/// CSV, one row per part: id, segment, parent, organ, order, material, stress, stress ratio, age,
/// reaction wood, colour, triangle count, centroid.
CBM_API cbm_status cbm_write_parts_csv(cbm_context *ctx, const cbm_scene *scene, const char *path,
                                       const cbm_write_options *opts);

/* ---- the mechanical plant: tables and scene ----
 * The plant must have been solved or evaluated (cbm_plant_solve, cbm_plant_evaluate), so that
 * positions, loads and stresses are current. */

/// One CSV row per segment: id, parent, order, proximal and distal points (m), semi-axes a, b
/// (m), length (m), E of the outer ring (Pa), rigidities EI_L, EI_U (N m^2), carried mass (kg),
/// moment at the proximal joint in local (H, L, U) components (N m; L and U bend, H twists),
/// bending moment magnitude (N m), stress (Pa), stress / MOR, Omega and rest Omega (local,
/// rad/m), age (years), reaction wood fraction.
CBM_API cbm_status cbm_write_segments_csv(cbm_context *ctx, const cbm_plant *plant,
                                          const char *path);
/// The plant as an OpenAlea multiscale tree graph (MTG coding file, FORM-A): scales plant (P),
/// axis (A), segment (S); '<' joins a segment to its continuation, '+' starts a lateral axis;
/// per-segment features as in the CSV. Loads with openalea.mtg's read_mtg.
CBM_API cbm_status cbm_write_mtg(cbm_context *ctx, const cbm_plant *plant, const char *path);
/* ---- the turtle's segments (plain L-system models) ----
 * From a turtle interpreted with its record on (cbm_turtle_interpret, cbm_model_interpret). Each
 * segment (CYLINDER, GCYL primitive) is a row; its parent is the last segment drawn before it on
 * its branch path, and it starts a lateral axis when a `[` was opened since (cbm_prim.parent,
 * .lateral). Lengths in the model's units. */

/// The turtle's segments as an OpenAlea MTG coding file (FORM-A, scales P, A, S, as
/// cbm_write_mtg): features id, order (axis level), module (index in the interpreted string),
/// color (index), x0 y0 z0 x1 y1 z1 (start and end points), width0 width1 (diameters at the
/// start and the end), length. No segments: a valid file with no plant.
CBM_API cbm_status cbm_write_turtle_mtg(cbm_context *ctx, const cbm_turtle *turtle,
                                        const char *path);
/// The same rows as a CSV table: id,parent,lateral,order,module,color,x0,y0,z0,x1,y1,z1,width0,
/// width1,length (parent -1: a root; lateral 1: starts a lateral axis).
CBM_API cbm_status cbm_write_turtle_segments_csv(cbm_context *ctx, const cbm_turtle *turtle,
                                                 const char *path);

/// Writes a plant by extension: .csv (segments table), .mtg, or any scene format (the plant
/// through cbm_plant_to_scene with `sides` sides, then cbm_scene_write).
CBM_API cbm_status cbm_write_plant(cbm_context *ctx, const cbm_plant *plant, const char *path,
                                   const cbm_write_options *opts, int sides);

/// A rendered picture in memory: 8-bit sRGB RGBA, row-major from the top. Owned by the caller,
/// released with cbm_image_destroy.
typedef struct cbm_image {
    cbm_context *ctx;
    int width, height;
    uint8_t *rgba;
} cbm_image;

/// Renders the scene as cbm_write_png would, into *out.
CBM_API cbm_status cbm_render(cbm_context *ctx, const cbm_scene *scene,
                              const cbm_write_options *opts, cbm_image **out);
/// A new w x h picture (1..32768 each), every pixel transparent black.
CBM_API cbm_status cbm_image_create(cbm_context *ctx, int w, int h, cbm_image **out);
CBM_API void cbm_image_destroy(cbm_image *img);
/// Reads an 8-bit RGB or RGBA PNG (e.g. a stored reference picture) into an RGBA image.
CBM_API cbm_status cbm_image_read_png(cbm_context *ctx, const char *path, cbm_image **out);
/// Writes an image as PNG through cbm_out.
CBM_API cbm_status cbm_image_write_png(cbm_context *ctx, const cbm_image *img, const char *path);

/// The colour (linear RGBA) a writer gives a part under the options' colour mode.
CBM_API void cbm_part_color(const cbm_part *part, const cbm_write_options *opts, float rgba[4]);

/* ---- a synthetic tree, to try the writers and measure them ---- */

/// Adds a deterministic synthetic tree to the scene: `segments` branch segments (each one part,
/// a tube with elliptical sections and `sides` sides) branching in a phyllotactic spiral, with
/// made-up but smooth stress ratio, age and reaction wood; a leaf (polygon) at each branch tip of
/// the highest orders, a fruit (sphere) at every seventh tip, and a ground square when `ground`.
/// About 1 m tall whatever the segment count. `seed` varies the angles.
/// ctx must be the scene's context.
CBM_API cbm_status cbm_scene_demo_tree(cbm_context *ctx, cbm_scene *scene, size_t segments,
                                       int sides, bool ground, uint64_t seed);

/* ---- JSON writer (run.json summaries, glTF) ----
 * Builds a document in memory; inside an object every value takes a key, inside an array the
 * key is NULL. Errors are sticky and come back from cbm_json_write_file / cbm_json_text.
 * Non-finite numbers are written as null. */
typedef struct cbm_json cbm_json;

CBM_API cbm_status cbm_json_create(cbm_context *ctx, cbm_json **out);
CBM_API void cbm_json_destroy(cbm_json *j);
CBM_API void cbm_json_begin_object(cbm_json *j, const char *key);
CBM_API void cbm_json_end_object(cbm_json *j);
CBM_API void cbm_json_begin_array(cbm_json *j, const char *key);
CBM_API void cbm_json_end_array(cbm_json *j);
CBM_API void cbm_json_number(cbm_json *j, const char *key, double v);
CBM_API void cbm_json_int(cbm_json *j, const char *key, int64_t v);
CBM_API void cbm_json_string(cbm_json *j, const char *key, const char *s);
CBM_API void cbm_json_bool(cbm_json *j, const char *key, bool v);
CBM_API void cbm_json_null(cbm_json *j, const char *key);
/// The text so far (NUL-terminated, owned by j); CBM_E_INVALID if the nesting is not closed or a
/// key was missing or misplaced.
CBM_API cbm_status cbm_json_text(cbm_json *j, const char **text, size_t *len);
/// Writes the complete document (plus a newline) through cbm_out.
CBM_API cbm_status cbm_json_write_file(cbm_json *j, const char *path);

/* ---- progress of long runs ----
 * The library formats, the tool prints (only when stderr is a terminal). */
typedef struct cbm_progress {
    size_t step, steps; ///< derivation steps done / planned
    size_t modules;     ///< modules in the current string
    size_t passes;      ///< equilibrium passes of the current step
    double elapsed;     ///< s since the start
} cbm_progress;

/// One line (no newline) of at most `width` characters: a bar, step k/n, modules, equilibrium
/// passes (when non-zero) and the time left estimated from the rate so far. Returns the line's
/// length.
CBM_API size_t cbm_progress_format(const cbm_progress *p, int width, char *buf, size_t size);

#ifdef __cplusplus
}
#endif
#endif
