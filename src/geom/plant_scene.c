/* A plant's branches as continuous generalized cylinders, one per axis.
 *
 * Each segment is its own part (its stress, age, reaction wood), drawn as a tube between two
 * rings; consecutive segments of an axis (a segment and its continuation child) share the ring
 * at their node, point for point, so an axis has no seam, gap, step or collar:
 *   - the node ring's heading is the mean of the two segments' headings, and its section the
 *     mean of the two segments' sections (radius by radius, below), so the girth tapers
 *     linearly from node to node where the pipe model changes it;
 *   - ring vertex k lies at the polar angle 2 pi k / sides about a reference direction carried
 *     along the axis by the minimal rotation (parallel transport) from the axis's first ring, so
 *     that vertex k of one ring joins vertex k of the next without twist, whatever the
 *     segments' own rolls (an elliptical section turning with its segment's frame no longer
 *     twists the tube into a ribbon or pinches it where the frames differ by a quarter turn);
 *   - a section is an ellipse, semi-axis a along the segment's U and b along its L: the radius
 *     at polar direction d is 1 / sqrt((d.U / a)^2 + (d.L / b)^2), so the ellipse is drawn in
 *     place, in the segment's own orientation, at any reference.
 * A lateral (or a root) starts with its own section at its proximal node, on its parent's axis,
 * inside the parent, open (no disc); tips are closed with a flat cap, as is a root's base.
 * Normals are those of the ring's curve (its tangent crossed with the axis). */
#include "geom_internal.h"

#include "../core/vecmath.h"
#include "cambium/mech.h"

#include <math.h>

/* The unit vector v turned by the rotation that takes unit a to unit b along the shortest way
 * (Rodrigues); a half turn (a = -b) about any axis normal to a. */
static cbm_vec3 min_rotate(cbm_vec3 v, cbm_vec3 a, cbm_vec3 b)
{
    cbm_vec3 k = v3_cross(a, b);
    double c = v3_dot(a, b), s = v3_norm(k);
    if (s < 1e-12) {
        if (c > 0.0)
            return v;
        cbm_vec3 n = fabs(a.x) < 0.9 ? v3(1, 0, 0) : v3(0, 1, 0);
        n = v3_normalize(v3_sub(n, v3_scale(a, v3_dot(n, a))));
        return v3_sub(v3_scale(n, 2.0 * v3_dot(v, n)), v); /* half turn about n */
    }
    k = v3_scale(k, 1.0 / s);
    return v3_add(v3_add(v3_scale(v, c), v3_scale(v3_cross(k, v), s)),
                  v3_scale(k, v3_dot(k, v) * (1.0 - c)));
}

/* R made normal to unit h and unit; any normal vector when R is (nearly) along h. */
static cbm_vec3 normal_to(cbm_vec3 r, cbm_vec3 h)
{
    cbm_vec3 q = v3_sub(r, v3_scale(h, v3_dot(r, h)));
    if (v3_norm(q) < 1e-9) {
        q = fabs(h.x) < 0.9 ? v3(1, 0, 0) : v3(0, 1, 0);
        q = v3_sub(q, v3_scale(h, v3_dot(q, h)));
    }
    return v3_normalize(q);
}

/* Radius of segment st's elliptical section in the unit direction d. */
static double ellipse_radius(const cbm_segment_state *st, cbm_vec3 d)
{
    double x = v3_dot(d, st->frame.u), y = v3_dot(d, st->frame.l), n = hypot(x, y);
    double a = st->a, b = st->b;
    if (n < 1e-12 || a <= 0.0 || b <= 0.0)
        return fmax(0.0, fmin(a, b));
    x /= n;
    y /= n;
    return 1.0 / sqrt((x / a) * (x / a) + (y / b) * (y / b));
}

/* A ring: centre c, axis h, reference direction r (normal to h), section the mean of the
 * sections of s0 and s1 (s1 may be NULL). Points and normals into pts, nrm (sides each). */
static void make_ring(cbm_vec3 c, cbm_vec3 h, cbm_vec3 r, const cbm_segment_state *s0,
                      const cbm_segment_state *s1, int sides, cbm_vec3 *pts, cbm_vec3 *nrm)
{
    cbm_vec3 q = v3_cross(r, h); /* L-like: the ring runs from r towards q */
    for (int k = 0; k < sides; k++) {
        double t = 2.0 * CBM_PI * k / sides;
        cbm_vec3 d = v3_add(v3_scale(r, cos(t)), v3_scale(q, sin(t)));
        double rad = ellipse_radius(s0, d);
        if (s1)
            rad = 0.5 * (rad + ellipse_radius(s1, d));
        pts[k] = v3_madd(c, d, rad);
    }
    for (int k = 0; k < sides; k++) {
        cbm_vec3 tg = v3_sub(pts[(k + 1) % sides], pts[(k + sides - 1) % sides]);
        cbm_vec3 n = v3_cross(h, tg);
        double nn = v3_norm(n);
        double t = 2.0 * CBM_PI * k / sides;
        nrm[k] = nn > 1e-15 ? v3_scale(n, 1.0 / nn)
                            : v3_add(v3_scale(r, cos(t)), v3_scale(q, sin(t))); /* zero radius */
    }
}

cbm_status cbm_plant_to_scene(const cbm_plant *p, cbm_scene *scene, int sides)
{
    if (!p || !scene || sides < 3 || sides > 1024)
        return CBM_E_INVALID;
    size_t n = cbm_plant_segment_count(p);
    if (n == 0)
        return CBM_OK;
    cbm_context *ctx = cbm__scene_context(scene);
    /* per segment: its state, its continuation child, the heading and reference direction of
     * its distal ring; the two rings being drawn */
    cbm_segment_state *st = cbm__alloc(ctx, n * sizeof *st);
    int64_t *cont = cbm__alloc(ctx, n * sizeof *cont);
    cbm_vec3 *dh = cbm__alloc(ctx, 2 * n * sizeof *dh), *dr = dh ? dh + n : NULL;
    cbm_vec3 *ring = cbm__alloc(ctx, 4 * (size_t)sides * sizeof *ring);
    cbm_status s = st && cont && dh && ring ? CBM_OK : CBM_E_NOMEM;
    for (size_t i = 0; i < n && s == CBM_OK; i++) {
        s = cbm_plant_segment(p, i, &st[i]);
        cont[i] = -1;
    }
    for (size_t i = 0; i < n && s == CBM_OK; i++) {
        int64_t pa = st[i].parent;
        if (pa >= 0 && (size_t)pa < i && st[i].continuation)
            cont[pa] = (int64_t)i;
    }
    cbm_vec3 *p0 = ring, *n0 = ring ? ring + sides : NULL, *p1 = ring ? ring + 2 * sides : NULL;
    cbm_vec3 *n1 = ring ? ring + 3 * sides : NULL;
    for (size_t i = 0; i < n && s == CBM_OK; i++) {
        const cbm_segment_state *g = &st[i];
        int64_t pa = g->parent;
        bool continues = pa >= 0 && (size_t)pa < i && cont[pa] == (int64_t)i;
        /* proximal ring: the parent's distal ring, or the segment's own section */
        cbm_vec3 h0, r0;
        if (continues) {
            h0 = dh[pa];
            r0 = dr[pa];
            make_ring(g->proximal, h0, r0, &st[pa], g, sides, p0, n0);
        } else {
            h0 = g->frame.h;
            r0 = normal_to(g->frame.u, h0);
            make_ring(g->proximal, h0, r0, g, NULL, sides, p0, n0);
        }
        /* distal ring: shared with the continuation child */
        int64_t c = cont[i];
        cbm_vec3 h1 = g->frame.h;
        if (c >= 0) {
            cbm_vec3 m = v3_add(g->frame.h, st[c].frame.h);
            h1 = v3_norm(m) > 1e-9 ? v3_normalize(m) : g->frame.h;
        }
        cbm_vec3 r1 = normal_to(min_rotate(r0, h0, h1), h1);
        dh[i] = h1;
        dr[i] = r1;
        make_ring(g->distal, h1, r1, g, c >= 0 ? &st[c] : NULL, sides, p1, n1);
        cbm_part part = cbm_part_default();
        part.organ = CBM_ORGAN_BRANCH;
        part.order = g->order;
        part.segment = (int64_t)i;
        part.parent = pa;
        part.stress = g->stress;
        part.stress_ratio = g->stress_ratio;
        part.age = g->age;
        part.reaction_wood = g->reaction;
        /* bark */
        part.color[0] = 0.42f, part.color[1] = 0.30f, part.color[2] = 0.20f, part.color[3] = 1;
        s = cbm_scene_begin_part(scene, &part, NULL);
        /* caps: a root's base and a tip; a lateral's base is open inside its parent */
        if (s == CBM_OK)
            s = cbm__scene_tube_begin_caps(scene, sides, pa < 0, g->child_count == 0);
        if (s == CBM_OK)
            s = cbm_scene_tube_ring_points(scene, g->proximal, h0, p0, n0);
        if (s == CBM_OK)
            s = cbm_scene_tube_ring_points(scene, g->distal, h1, p1, n1);
        if (s == CBM_OK)
            s = cbm_scene_tube_end(scene);
    }
    cbm__free(ctx, ring, ring ? 4 * (size_t)sides * sizeof *ring : 0);
    cbm__free(ctx, dh, dh ? 2 * n * sizeof *dh : 0);
    cbm__free(ctx, cont, cont ? n * sizeof *cont : 0);
    cbm__free(ctx, st, st ? n * sizeof *st : 0);
    return s;
}
