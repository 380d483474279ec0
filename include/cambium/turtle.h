/* cambium: the turtle interpretation of cpfg/ABOP strings, and the side files that configure it.
 *
 * A view (cbm_view) holds the settings of a cpfg view file (angle increment, initial width, line
 * style, tropisms, contour sides, ...) and the side files it names or that are added to it:
 * function files (.func), surfaces (.s), contours (.con), a colour map (.map) or materials (.mat).
 * cbm_turtle_interpret runs a string given as a list of modules (name + parameters; cpfg's
 * one-character modules such as "@" "M" are combined as cpfg does) through the turtle into a
 * scene, and keeps a record of the primitives in cpfg's .ray terms (cylinders and cones with end
 * points and radii, polygons, spheres, discs, surfaces, generalized-cylinder triangles) and
 * cpfg's view-volume box. docs/turtle.md lists the commands and settings.
 * Lengths are in the model's units (cpfg has none; read them as metres), angles in degrees in the
 * files and parameters, as cpfg.
 */
#ifndef CAMBIUM_TURTLE_H
#define CAMBIUM_TURTLE_H

#include "cambium/geom.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cbm_view cbm_view;
typedef struct cbm_funcset cbm_funcset;
typedef struct cbm_turtle cbm_turtle;

/// A view with cpfg's defaults (angle 45 degrees, width 1, colour 128, pixel lines, 8 sides).
CBM_API cbm_status cbm_view_create(cbm_context *ctx, cbm_view **out);
/// Reads a cpfg view file into a new view. Side files it names (function:, surface:, contour:)
/// are read relative to the view file's directory. Unknown or display-only settings are kept
/// silently; malformed known settings are errors naming file:line.
CBM_API cbm_status cbm_view_load(cbm_context *ctx, const char *path, cbm_view **out);
CBM_API void cbm_view_destroy(cbm_view *view);
/// Adds a function file (.func, cpfg "fver 1 1" or "range:" format). Functions are numbered
/// from 1 in the order they are added, as cpfg's func(id, x). samples <= 2: the file's own.
CBM_API cbm_status cbm_view_add_function(cbm_view *view, const char *path, int samples);
/// Adds a predefined surface (.s, cpfg's bicubic patch format) drawn by ~id, scaled so that the
/// file's SIZE becomes `size` (cpfg's view-file size).
CBM_API cbm_status cbm_view_add_surface(cbm_view *view, char id, const char *path, double size);
/// Adds a contour (.con) selected by @#(id) for generalized cylinders.
CBM_API cbm_status cbm_view_add_contour(cbm_view *view, int id, const char *path);
/// Reads a colour map (.map: 256 RGB byte triples) giving the colour of each index.
CBM_API cbm_status cbm_view_load_colormap(cbm_view *view, const char *path);
/// Reads a material file (.mat: records of index + 14 bytes); the diffuse colour is used.
CBM_API cbm_status cbm_view_load_materials(cbm_view *view, const char *path);
/// Reads a side file chosen by its extension (.v .func .fset .s .con .map .mat), as cpfg's
/// command line.
CBM_API cbm_status cbm_view_load_side_file(cbm_view *view, const char *path);
/// The functions of the view (never NULL).
CBM_API const cbm_funcset *cbm_view_functions(const cbm_view *view);
/// Adds the functions of a function gallery (.fset, lpfg's and cpfg's "function set"), in order.
CBM_API cbm_status cbm_view_add_function_set(cbm_view *view, const char *path);
/// The id (1-based) of the function named `name` (the file's "name:"), 0 if none.
CBM_API int cbm_funcset_find(const cbm_funcset *fs, const char *name);
/// The value of the view's function id at x, with the view (cbm_view *) as user data, for an
/// expression evaluator's callback, e.g. cbm_lsys_set_func(ls, cbm_view_func_callback, view).
CBM_API double cbm_view_func_callback(void *view, int id, double x);
/// Number of functions in the set.
CBM_API int cbm_funcset_count(const cbm_funcset *fs);
/// Value of function id (1-based) at x in [0, 1] (clamped). 0 for an unknown id.
CBM_API double cbm_funcset_value(const cbm_funcset *fs, int id, double x);

/// One module of a string: its name ("F", "@Gs", "?P", or cpfg's single symbols "@", "~", ...)
/// and its parameters.
typedef struct cbm_tmodule {
    const char *name;
    int nparams;
    double *params; ///< query modules (?P ?H ?L ?U) are written back here
} cbm_tmodule;

/// Kinds of primitives, in cpfg's .ray terms.
typedef enum cbm_prim_kind {
    CBM_PRIM_CYLINDER, ///< p0 -> p1, radii r0 (start), r1 (end; r1 != r0: a cone)
    CBM_PRIM_POLYGON,  ///< points[first .. first+count)
    CBM_PRIM_SPHERE,   ///< centre p0, radius r0
    CBM_PRIM_DISC,     ///< centre p0, radius r0, normal p1 (the turtle's up)
    CBM_PRIM_SURFACE,  ///< predefined surface `id` at p0, scale r0; points: its placed vertices
    CBM_PRIM_GCYL      ///< a generalized-cylinder piece p0 -> p1 (radii r0, r1); points: its
                       ///< triangles' corners, 3 per triangle, in cpfg's order
} cbm_prim_kind;

typedef struct cbm_prim {
    cbm_prim_kind kind;
    int color; ///< colour index
    cbm_vec3 p0, p1;
    double r0, r1;
    size_t first, count; ///< range in cbm_turtle_points
    char id;             ///< surface id
    cbm_frame frame;     ///< the turtle's H, L, U where the primitive starts (cpfg: L = H x U)
    /// CYLINDER and GCYL (the segments): the segment drawn last before this one on its branch
    /// path (index in cbm_turtle_prims), -1 for none (a root) and for the other kinds
    int64_t parent;
    /// a `[` opened since the parent segment: this segment starts a lateral axis (false: it
    /// continues the parent's axis, or has no parent)
    bool lateral;
    int64_t module; ///< index (0-based) of the module that drew it in the interpreted string
} cbm_prim;

/// Options of one interpretation.
typedef struct cbm_turtle_def {
    bool record; ///< keep the primitive record (cbm_turtle_prims)
} cbm_turtle_def;

/// Defaults: record on (what a NULL def means).
CBM_API cbm_turtle_def cbm_turtle_def_default(void);

/// Interprets modules[0..n) with the view into scene (may be NULL). def may be NULL (record on).
/// *out receives the turtle with its record, to read with the accessors below and release with
/// cbm_turtle_destroy. On failure *out is NULL and the context holds the message.
CBM_API cbm_status cbm_turtle_interpret(cbm_context *ctx, const cbm_view *view,
                                        const cbm_turtle_def *def, cbm_tmodule *modules, size_t n,
                                        cbm_scene *scene, cbm_turtle **out);
CBM_API void cbm_turtle_destroy(cbm_turtle *t);
CBM_API size_t cbm_turtle_prim_count(const cbm_turtle *t);
/// Segments drawn into the scene in cpfg's pixel line style (lines in a scene in line mode,
/// tubes otherwise; lpfg's turtle draws none): when non-zero, a picture in line mode differs.
CBM_API size_t cbm_turtle_pixel_segments(const cbm_turtle *t);
CBM_API const cbm_prim *cbm_turtle_prims(const cbm_turtle *t);
CBM_API const cbm_vec3 *cbm_turtle_points(const cbm_turtle *t);
/// cpfg's view-volume box: the turtle's positions where segments end, sphere and disc extents,
/// surface and generalized-cylinder vertices. false if nothing was drawn or visited.
CBM_API bool cbm_turtle_box(const cbm_turtle *t, cbm_vec3 *lo, cbm_vec3 *hi);
/// The turtle's current frame and position (after the pass).
CBM_API void cbm_turtle_state(const cbm_turtle *t, cbm_vec3 *pos, cbm_vec3 *h, cbm_vec3 *l,
                              cbm_vec3 *u, double *width, int *color);

#ifdef __cplusplus
}
#endif
#endif
