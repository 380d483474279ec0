/* Private pieces shared by the writers, one concept per file: options.c (defaults), write.c
 * (dispatch by format), camera.c (the camera fitted to a scene), color_by.c (the quantity of each
 * colour mode, its range and legend title, part colours), colormap.c (the maps, linear to sRGB),
 * parts.c (the part filter, ground on/off, and the vertex-to-part maps), png/ (the renderer and
 * the picture files). */
#ifndef CBM_IO_WRITERS_H
#define CBM_IO_WRITERS_H

#include "cambium/write.h"

#include "../core/core.h"

/// Orthographic camera: a point p projects to pixel ((p - center).right * scale + width / 2,
/// height / 2 - (p - center).up * scale); depth grows along dir (away from the viewer).
typedef struct cbm__camera {
    cbm_vec3 dir, right, up; /* orthonormal, dir = right x up reversed: right x up = -dir */
    cbm_vec3 center;         /* m, maps to the centre of the drawing area */
    double scale;            /* pixels per metre */
    double cx, cy;           /* pixel position of center */
    double depth_min;        /* smallest depth of the scene along dir (m, from center) */
} cbm__camera;

/// Fits an orthographic camera so the kept parts (ground excluded) fill `fill` (0..1) of a
/// draw area of w x h pixels whose centre is at (cx, cy). False if nothing is drawn.
bool cbm__camera_fit(cbm__camera *cam, const cbm_scene *scene, const cbm_write_options *o, double w,
                     double h, double cx, double cy, double fill);
/// The camera's unit viewing direction for the options.
cbm_vec3 cbm__view_direction(const cbm_write_options *o);

/// Whether a part is written under the options (ground parts are dropped when ground is off).
bool cbm__part_kept(const cbm_part *p, const cbm_write_options *o);
/// The part each vertex belongs to (from the triangles; unused vertices get UINT32_MAX).
/// *out has cbm_scene_vertex_count entries, released with cbm__free(ctx, p, n * 4).
cbm_status cbm__vertex_parts(cbm_context *ctx, const cbm_scene *s, uint32_t **out);

/// The quantity shown by a colour mode for a part (NaN if unknown) and its range.
double cbm__part_quantity(const cbm_part *p, cbm_color_by by);
void cbm__color_range(const cbm_scene *s, const cbm_write_options *o, double *lo, double *hi);
/// The colour map of a quantity mode at t in [0, 1], linear RGB.
void cbm__colormap(cbm_color_by by, double t, float rgb[3]);
/// Colour of a part with a precomputed range.
void cbm__part_color_range(const cbm_part *p, const cbm_write_options *o, double lo, double hi,
                           float rgba[4]);
/// Title of the colour bar of a mode ("stress / MOR", ...).
const char *cbm__color_title(cbm_color_by by);
/// The highest branch order among the scene's branch parts, at most 15 (the order legend's rows).
int cbm__legend_max_order(const cbm_scene *s);

/// Per-part display colours under the options (linear RGBA, 4 floats per part), and the
/// colour range used. Released with cbm__free(ctx, c, 4 * nparts * sizeof(float)).
cbm_status cbm__part_colors(cbm_context *ctx, const cbm_scene *s, const cbm_write_options *o,
                            float **out, double *lo, double *hi);
/// Kept-vertex remap: new index of each vertex (UINT32_MAX if dropped) and the count kept.
cbm_status cbm__vertex_remap(cbm_context *ctx, const cbm_scene *s, const cbm_write_options *o,
                             const uint32_t *vpart, uint32_t **out, size_t *kept);
/// The unit quaternion of the rotation whose matrix has columns c0, c1, c2 (a right frame).
cbm_quat cbm__quat_of_columns(cbm_vec3 c0, cbm_vec3 c1, cbm_vec3 c2);
/// Default options when opts is NULL.
const cbm_write_options *cbm__opts(const cbm_write_options *o, cbm_write_options *def);

/// A zeroed w x h picture.
cbm_status cbm__image_create(cbm_context *ctx, int w, int h, cbm_image **out);

/// linear -> sRGB 8-bit
uint8_t cbm__srgb8(double linear);

/// A tree of rows for the MTG writer: each row is one segment (S) with its parent row (-1: a
/// root, which starts a plant P; parents come before their children), whether it continues the
/// parent's axis ('<') or starts a lateral axis ('+A'), and its features.
typedef struct cbm__mtg_table {
    const char *comment;         ///< the file's first line, after "# "
    size_t rows;                 ///< segments
    const int64_t *parent;       ///< per row: the parent row, -1 for a root
    const uint8_t *continuation; ///< per row: 1 continues the parent's axis, 0 lateral
    const char *const *features; ///< feature names (at most 32)
    size_t nfeatures, nint;      ///< features; the first nint are INT, the others REAL
    /// Fills values[0..nfeatures) for row i (non-finite: an empty cell).
    cbm_status (*row)(const void *user, size_t i, double *values);
    const void *user;
    /// Optional, per row: the number of the plant (P<n>) a root row starts; NULL numbers the
    /// plants 1, 2, ... in the order of their roots.
    const int64_t *plant;
} cbm__mtg_table;

/// Writes the table as an MTG coding file (FORM-A, scales P, A, S) through cbm_out.
cbm_status cbm__write_mtg_table(cbm_context *ctx, const cbm__mtg_table *t, const char *path);

#endif
