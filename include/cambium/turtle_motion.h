/* cambium: the motion of a model's drawn parts over a derivation, recorded from the turtle.
 *
 * A model whose string describes a moving structure (Taylor-Hell's linked pendula,
 * models/taylor-hell-pendula.l: one pass per step, the same links in every step) draws the same
 * parts at every recorded step, only placed elsewhere. A cbm_turtle_motion keeps, per recorded
 * frame, each part's placement: segments (cylinders, cones, generalized-cylinder pieces) by their
 * two ends, spheres by their centre. It writes them as a table (one row per part per frame) and
 * as an animated glTF in which every part is a rigid node whose translation and rotation are
 * keyed per frame (docs/formats.md, "Motion"). Polygons, discs and surfaces are not recorded.
 */
#ifndef CAMBIUM_TURTLE_MOTION_H
#define CAMBIUM_TURTLE_MOTION_H

#include "cambium/turtle.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cbm_turtle_motion cbm_turtle_motion;

CBM_API cbm_status cbm_turtle_motion_create(cbm_context *ctx, cbm_turtle_motion **out);
CBM_API void cbm_turtle_motion_destroy(cbm_turtle_motion *m);

/// Records one frame from a turtle's primitive record (cbm_turtle_interpret with record on) at
/// time_s (s, increasing) after derivation step `step`. The first frame fixes the parts; later
/// frames must draw the same number of segments and spheres in the same order (CBM_E_INVALID
/// otherwise, naming the frame). `scene` (may be NULL) is the same interpretation drawn into a
/// scene: the first frame takes the parts' colours from it (grey without).
CBM_API cbm_status cbm_turtle_motion_add_frame(cbm_turtle_motion *m, const cbm_turtle *turtle,
                                               const cbm_scene *scene, double time_s, long step);
/// A segment of a frame given directly rather than drawn by a turtle (the sway of a grown tree,
/// cambium grow --sway): it starts at p0 and runs along its frame's H (frame e_x) for length,
/// radii r0 to r1, colour rgba (taken from the first frame).
typedef struct cbm_motion_part {
    cbm_vec3 p0;
    cbm_quat frame;
    double length, r0, r1;
    float rgba[4];
} cbm_motion_part;

/// Records one frame of `count` segments at time_s (increasing); the first frame fixes the parts,
/// later ones must give as many (CBM_E_INVALID otherwise).
CBM_API cbm_status cbm_turtle_motion_add_parts(cbm_turtle_motion *m, const cbm_motion_part *parts,
                                               size_t count, double time_s, long step);
CBM_API size_t cbm_turtle_motion_frame_count(const cbm_turtle_motion *m);
/// Parts per frame (segments and spheres).
CBM_API size_t cbm_turtle_motion_part_count(const cbm_turtle_motion *m);
/// Ends of part `part` in frame `frame` (a sphere: its centre twice), model units.
CBM_API bool cbm_turtle_motion_part(const cbm_turtle_motion *m, size_t frame, size_t part,
                                    cbm_vec3 *p0, cbm_vec3 *p1);

/// CSV, one row per part per frame: frame,step,time_s,part,kind,x0,y0,z0,x1,y1,z1 (kind
/// `segment` or `sphere`; a sphere's centre in both points).
CBM_API cbm_status cbm_turtle_motion_write_csv(const cbm_turtle_motion *m, const char *path);
/// glTF 2.0 binary: one node per part with its mesh built in the part's own frame, animated by
/// translation and rotation channels (LINEAR) over the frame times; the static pose is frame 0.
CBM_API cbm_status cbm_turtle_motion_write_glb(const cbm_turtle_motion *m, const char *path);

#ifdef __cplusplus
}
#endif
#endif
