/* cambium: the scene, the geometry a plant produces for the writers.
 *
 * A scene is a triangle mesh (positions and normals in metres, y up) whose triangles belong to
 * parts. A part is one organ instance (a branch segment, a leaf, a fruit, ...) with the data the
 * writers colour by or keep as per-segment attributes (order, stress ratio, age, reaction wood).
 * Producers (the turtle, the built-in tree models) open a part, then add tubes (generalized
 * cylinders with elliptical sections), spheres, polygons or ready meshes to it.
 *
 * A scene may also hold lines: segments drawn a given number of pixels wide whatever the zoom
 * (cpfg's `line style: pixel`), kept as two points, a width and a part (32 bytes) instead of a
 * tessellated tube. Only the picture writers (.png, .svg) draw them; the mesh writers refuse a
 * scene with lines. A producer draws lines only when the scene is in line mode
 * (cbm_scene_set_line_mode), which whoever writes the outputs chooses.
 */
#ifndef CAMBIUM_GEOM_H
#define CAMBIUM_GEOM_H

#include "cambium/base.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum cbm_organ {
    CBM_ORGAN_BRANCH,
    CBM_ORGAN_LEAF,
    CBM_ORGAN_FRUIT,
    CBM_ORGAN_FLOWER,
    CBM_ORGAN_BUD,
    CBM_ORGAN_GROUND,
    CBM_ORGAN_OTHER,
    CBM_ORGAN_COUNT
} cbm_organ;

/// Name of an organ kind ("branch", "leaf", ...).
CBM_API const char *cbm_organ_name(cbm_organ o);

/// What a part is. Unknown quantities are NaN (e.g. stress of a cpfg model without mechanics).
typedef struct cbm_part {
    cbm_organ organ;
    int32_t order;        ///< branch order (trunk 0), -1 if unknown
    int64_t segment;      ///< mechanical segment id or module index, -1 if none
    int64_t parent;       ///< parent segment id, -1 if none
    int32_t material;     ///< colour-map / material index, -1 if none
    float color[4];       ///< linear RGBA in [0,1]
    double stress_ratio;  ///< bending stress / modulus of rupture
    double stress;        ///< bending stress, Pa
    double age;           ///< wood age, years
    double reaction_wood; ///< fraction of reaction wood in the section, 0..1
    double light;         ///< leaves: intercepted light / one-sided area (1 = unshaded
                          ///< horizontal; cbm_light_scene, docs/light.md)
} cbm_part;

/// A part with neutral defaults: branch, order -1, no ids, grey, NaN quantities.
CBM_API cbm_part cbm_part_default(void);

typedef struct cbm_scene_vertex {
    float p[3]; ///< position, m
    float n[3]; ///< unit normal
} cbm_scene_vertex;

/// A cross-section of a generalized cylinder: centre, frame (H along the axis, U along the
/// semi-axis a, L along the semi-axis b).
typedef struct cbm_section {
    cbm_vec3 center; ///< m
    cbm_frame frame;
    double a; ///< semi-axis along U, m
    double b; ///< semi-axis along L, m
} cbm_section;

typedef struct cbm_scene cbm_scene;

CBM_API cbm_status cbm_scene_create(cbm_context *ctx, cbm_scene **out);
CBM_API void cbm_scene_destroy(cbm_scene *scene);
/// Removes all geometry and parts; keeps the memory.
CBM_API void cbm_scene_clear(cbm_scene *scene);

/// Starts a new part; later geometry belongs to it. *id (optional) receives its index.
CBM_API cbm_status cbm_scene_begin_part(cbm_scene *scene, const cbm_part *part, uint32_t *id);

/// Starts a part like cbm_scene_begin_part, except that in instancing mode, when a part of the
/// scene (the current one, or any begun before: a hash table finds it) equals `part` but for
/// its segment id, no part is stored: the tube instances added next point to that part and keep
/// `part->segment` as their own (cbm_scene_instance.segment), triangles share it too and keep
/// their segment id in cbm_scene_triangle_segments, and lines and placed shapes store the part
/// first as cbm_scene_begin_part would have. This spares a part record (88 bytes) per
/// instanced segment, also where branches of a few orders alternate along the string. For
/// producers that do not change their parts after adding them (the part may be shared by other
/// segments' instances).
CBM_API cbm_status cbm_scene_begin_part_shared(cbm_scene *scene, const cbm_part *part);

/// Generalized cylinder: begin, then one ring per section (each ring is joined to the previous
/// one with `sides` quads), then end. `caps` closes the two ends with flat discs.
CBM_API cbm_status cbm_scene_tube_begin(cbm_scene *scene, int sides, bool caps);
CBM_API cbm_status cbm_scene_tube_ring(cbm_scene *scene, const cbm_section *sec);
CBM_API cbm_status cbm_scene_tube_end(cbm_scene *scene);
/// A ring of `sides` given points and outward normals (any section shape), in the order of
/// cbm_scene_tube_ring's (from U towards L = U x H, clockwise seen from +axis); centre and axis
/// place the caps.
CBM_API cbm_status cbm_scene_tube_ring_points(cbm_scene *scene, cbm_vec3 center, cbm_vec3 axis,
                                              const cbm_vec3 *pts, const cbm_vec3 *nrm);
/// One straight piece between two sections (begin, two rings, end).
CBM_API cbm_status cbm_scene_add_tube(cbm_scene *scene, const cbm_section *s0,
                                      const cbm_section *s1, int sides, bool caps);
CBM_API cbm_status cbm_scene_add_sphere(cbm_scene *scene, cbm_vec3 center, double radius,
                                        int slices);
/// Planar or nearly planar polygon, convex or not (ear clipping); normal by Newell's method.
CBM_API cbm_status cbm_scene_add_polygon(cbm_scene *scene, const cbm_vec3 *pts, size_t n);
/// A ready triangle mesh; normals may be NULL (then computed from the faces).
CBM_API cbm_status cbm_scene_add_mesh(cbm_scene *scene, const cbm_vec3 *pos, const cbm_vec3 *nrm,
                                      size_t nverts, const uint32_t *tri, size_t ntri);

/// A line: two points, a width in pixels of the picture, its part.
typedef struct cbm_scene_line {
    float p0[3], p1[3]; ///< ends, m
    float width;        ///< pixels (at least 1 when drawn)
    uint32_t part;      ///< index of the part
} cbm_scene_line;

/// Line mode: producers draw their pixel lines as lines (true) or as tubes (false, the default).
/// Set it only when every output of the scene is a picture. Kept by cbm_scene_clear.
CBM_API void cbm_scene_set_line_mode(cbm_scene *scene, bool lines);
CBM_API bool cbm_scene_line_mode(const cbm_scene *scene);
/// Adds a line of `width` pixels between p0 and p1 (m) to the current part.
CBM_API cbm_status cbm_scene_add_line(cbm_scene *scene, cbm_vec3 p0, cbm_vec3 p1, double width);
CBM_API size_t cbm_scene_line_count(const cbm_scene *scene);
CBM_API const cbm_scene_line *cbm_scene_lines(const cbm_scene *scene);

/// A straight tube of elliptical sections, the end one the start one scaled, kept as an instance
/// of one unit cylinder or frustum instead of triangles (a scene in instancing mode): the .glb
/// writer writes it as such (EXT_mesh_gpu_instancing). The scene keeps its instances encoded,
/// the fields equal to the previous instance's left out (14 bytes for a segment continuing the
/// previous one in its frame, width and part, at most 62), where the triangles of an 8-sided
/// tube take ~1.1 kB; cbm_scene_instance_read gives them back as this record.
typedef struct cbm_scene_instance {
    float p0[3], p1[3]; ///< the axis's ends, m
    float u[3];         ///< unit U of the sections, perpendicular to the axis (L = U x H)
    float a, b;         ///< semi-axes along U and L at p0, m
    float taper;        ///< the section at p1 over the one at p0 (1: a cylinder)
    uint32_t part;      ///< index of the part
    int32_t sides;      ///< sides of the rings it stands for
    float segment;      ///< its segment id as the .glb writes it (float; -1 if none): the part's,
                        ///< or its own when it shares the part (cbm_scene_begin_part_shared)
} cbm_scene_instance;

/// Instancing mode: cbm_scene_add_tube keeps straight uncapped tubes whose end section is the
/// start one scaled as instances (false, the default: as triangles). Set it only when every output
/// of the scene is a .glb; the other writers refuse a scene with instances. Kept by
/// cbm_scene_clear.
CBM_API void cbm_scene_set_instancing(cbm_scene *scene, bool on);
CBM_API bool cbm_scene_instancing(const cbm_scene *scene);
CBM_API size_t cbm_scene_instance_count(const cbm_scene *scene);
/// Where a reader of the instances is (cbm_scene_instance_read): start with one zeroed
/// (`cbm_scene_instance_cursor c = {0};`); its fields are the reader's.
typedef struct cbm_scene_instance_cursor {
    size_t next;             ///< index of the instance that follows the one read last
    size_t offset;           ///< its place in the scene's encoding
    cbm_scene_instance last; ///< the instance read last
} cbm_scene_instance_cursor;
/// Instance i (< cbm_scene_instance_count) into *out, bit for bit as it was added. Reading in
/// increasing order costs a few nanoseconds an instance; a jump back or far ahead starts from a
/// fully written instance at most 255 before i. A cursor is valid for one scene until it
/// changes; readers of the same scene use cursors of their own.
CBM_API cbm_status cbm_scene_instance_read(const cbm_scene *scene, size_t i,
                                           cbm_scene_instance_cursor *cursor,
                                           cbm_scene_instance *out);
/// Bytes the scene's encoding of its instances takes (without the unused capacity).
CBM_API size_t cbm_scene_instance_bytes(const cbm_scene *scene);

/// A ready mesh kept once in the scene (a shape: a predefined surface, e.g. a petal) and placed
/// many times, each placement an affine map of it: the .glb writer writes the shape once and each
/// placement as an instance (translation, rotation, scale), where the triangles would copy its
/// vertices each time.
typedef struct cbm_scene_placement {
    float o[3];             ///< where the shape's origin goes, m
    float x[3], y[3], z[3]; ///< images of the shape's axes (the linear map's columns, orthogonal)
    uint32_t part;          ///< index of the part
    uint32_t shape;         ///< index of the shape
} cbm_scene_placement;

/// The shape of key `key` (the caller's name for one mesh, e.g. a surface's address) added since
/// the scene was created or cleared: *id receives its index; false if none.
CBM_API bool cbm_scene_find_shape(const cbm_scene *scene, uint64_t key, uint32_t *id);
/// Keeps a mesh (unit normals given) as shape `key`; *id receives its index.
CBM_API cbm_status cbm_scene_add_shape(cbm_scene *scene, uint64_t key, const cbm_vec3 *pos,
                                       const cbm_vec3 *nrm, size_t nverts, const uint32_t *tri,
                                       size_t ntri, uint32_t *id);
/// Places shape `shape` in the current part: vertex q goes to o + x q.x + y q.y + z q.z, normal n
/// to the normalised inverse transpose of (x y z) times n. In instancing mode with orthogonal,
/// non-zero x, y, z it is kept as a placement; otherwise its triangles are added.
CBM_API cbm_status cbm_scene_place_shape(cbm_scene *scene, uint32_t shape, cbm_vec3 o, cbm_vec3 x,
                                         cbm_vec3 y, cbm_vec3 z);
CBM_API size_t cbm_scene_shape_count(const cbm_scene *scene);
/// The mesh of a shape: 3 floats a vertex for positions and normals, 3 indices a triangle.
CBM_API cbm_status cbm_scene_shape_mesh(const cbm_scene *scene, uint32_t shape, const float **pos,
                                        const float **nrm, size_t *nverts, const uint32_t **tri,
                                        size_t *ntri);
CBM_API size_t cbm_scene_placement_count(const cbm_scene *scene);
CBM_API const cbm_scene_placement *cbm_scene_placements(const cbm_scene *scene);

CBM_API size_t cbm_scene_vertex_count(const cbm_scene *scene);
CBM_API const cbm_scene_vertex *cbm_scene_vertices(const cbm_scene *scene);
CBM_API size_t cbm_scene_triangle_count(const cbm_scene *scene);
/// 3 vertex indices per triangle.
CBM_API const uint32_t *cbm_scene_triangles(const cbm_scene *scene);
/// The part of each triangle.
CBM_API const uint32_t *cbm_scene_triangle_parts(const cbm_scene *scene);
/// The segment id of each triangle as the .glb writes it (a float, -1 if none), or NULL when
/// every triangle's is its part's. Triangles added after cbm_scene_begin_part_shared found a
/// part of another segment (instancing mode) share that part and keep their own segment id
/// here: 4 bytes a triangle instead of an 88-byte part a segment.
CBM_API const float *cbm_scene_triangle_segments(const cbm_scene *scene);
CBM_API size_t cbm_scene_part_count(const cbm_scene *scene);
CBM_API const cbm_part *cbm_scene_parts(const cbm_scene *scene);
/// Mutable access, e.g. to fill stress after a solve.
CBM_API cbm_part *cbm_scene_part(cbm_scene *scene, uint32_t id);
/// Axis-aligned bounds of all vertices, line ends, instances (their ends widened by their
/// larger semi-axis) and placements (the placed box of their shape); false if the scene is empty.
CBM_API bool cbm_scene_bounds(const cbm_scene *scene, cbm_vec3 *lo, cbm_vec3 *hi);

#ifdef __cplusplus
}
#endif
#endif
