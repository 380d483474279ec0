/* The branches of a plant as continuous generalized cylinders (cbm_plant_to_scene): an axis
 * has no seam, gap or twist at its nodes, its girth never pinches to zero, and a lateral starts
 * inside its parent. */
#include "test.h"

#include "cambium/geom.h"
#include "cambium/mech.h"

#include <math.h>
#include <string.h>

enum { SIDES = 8 };

/* A trunk of 6 segments with elliptical sections (a = 2b) and a roll of 1.3 rad at every node
 * (the old drawing joined vertex k of one frame to vertex k of the next: a twisted ribbon), and
 * laterals with their own rolls. */
static cbm_plant *rolled_plant(cbm_context *ctx)
{
    cbm_plant *p = NULL;
    CHECK_OK(cbm_plant_create(ctx, NULL, &p));
    if (!p)
        return NULL;
    cbm_plant_set_base(p, (cbm_vec3){0, 0, 0}, cbm_mech_clamp_orientation(1.2));
    const int64_t parents[] = {-1, 0, 1, 2, 3, 4, 1, 6, 3, 8};
    for (size_t i = 0; i < sizeof parents / sizeof parents[0]; i++) {
        cbm_segment_def d = cbm_segment_def_default();
        d.parent = parents[i];
        d.length = 0.1;
        d.core.a = 0.03 - 0.002 * (double)i;
        d.core.b = 0.5 * d.core.a;
        bool lateral = parents[i] >= 0 && i != (size_t)parents[i] + 1;
        d.deviation = lateral ? 0.8 : 0.05;
        d.roll = 1.3;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    return p;
}

static cbm_vec3 vtx(const cbm_scene *sc, size_t k)
{
    const float *f = cbm_scene_vertices(sc)[k].p;
    return (cbm_vec3){f[0], f[1], f[2]};
}

static cbm_vec3 sub(cbm_vec3 a, cbm_vec3 b)
{
    return (cbm_vec3){a.x - b.x, a.y - b.y, a.z - b.z};
}

static double norm(cbm_vec3 a)
{
    return sqrt(a.x * a.x + a.y * a.y + a.z * a.z);
}

static double dot(cbm_vec3 a, cbm_vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

TEST(plant_axes_are_continuous)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = rolled_plant(ctx);
    cbm_scene *sc = NULL;
    CHECK_OK(cbm_scene_create(ctx, &sc));
    if (!p || !sc) {
        cbm_plant_destroy(p);
        cbm_scene_destroy(sc);
        test_ctx_end(ctx);
        return;
    }
    CHECK_OK(cbm_plant_to_scene(p, sc, SIDES));
    size_t n = cbm_plant_segment_count(p);
    CHECK_EQ_INT(cbm_scene_part_count(sc), n);
    /* vertices of segment i: its proximal ring, a cap (centre + ring) at a root's base, its
     * distal ring, a cap at a tip */
    size_t r0[16], r1[16], at = 0;
    cbm_segment_state st[16];
    for (size_t i = 0; i < n && i < 16; i++) {
        CHECK_OK(cbm_plant_segment(p, i, &st[i]));
        r0[i] = at;
        at += SIDES + (st[i].parent < 0 ? SIDES + 1 : 0);
        r1[i] = at;
        at += SIDES + (st[i].child_count == 0 ? SIDES + 1 : 0);
    }
    CHECK_EQ_INT(cbm_scene_vertex_count(sc), at);
    for (size_t i = 0; i < n && i < 16; i++) {
        cbm_vec3 c0 = st[i].proximal, c1 = st[i].distal;
        int64_t pa = st[i].parent;
        bool continues = pa >= 0 && st[i].continuation;
        for (int k = 0; k < SIDES; k++) {
            cbm_vec3 a = vtx(sc, r0[i] + (size_t)k), b = vtx(sc, r1[i] + (size_t)k);
            /* no gap: a continuation's first ring is its parent's last, point for point */
            if (continues) {
                cbm_vec3 q = vtx(sc, r1[pa] + (size_t)k);
                CHECK_MSG(a.x == q.x && a.y == q.y && a.z == q.z,
                          "segment %zu vertex %d: %g %g %g vs its parent's %g %g %g", i, k, a.x,
                          a.y, a.z, q.x, q.y, q.z);
            }
            /* no pinching: every radius at least the thinner semi-axis around */
            double lo = 0.9 * st[i].b * (continues ? fmin(1.0, st[pa].b / st[i].b) : 1.0);
            CHECK_MSG(norm(sub(a, c0)) > lo && norm(sub(b, c1)) > 0.9 * fmin(st[i].b, 0.015),
                      "segment %zu vertex %d: radii %g %g", i, k, norm(sub(a, c0)),
                      norm(sub(b, c1)));
            /* no twist: vertex k of the two rings points the same way (the headings differ by
             * little here; a 1.3 rad roll left uncorrected would give cos 1.3 = 0.27) */
            double cs = dot(sub(a, c0), sub(b, c1)) / (norm(sub(a, c0)) * norm(sub(b, c1)));
            CHECK_MSG(cs > 0.9, "segment %zu vertex %d twists: cos %g", i, k, cs);
            /* a lateral starts inside its parent */
            if (pa >= 0 && !continues)
                CHECK_MSG(norm(sub(a, c0)) <= fmax(st[pa].a, st[pa].b) + 1e-6,
                          "lateral %zu pokes out of its parent: %g", i, norm(sub(a, c0)));
        }
    }
    /* the ellipse is drawn in the segment's own orientation: at the tip (no averaging) the
     * widest point is a along U, the narrowest b along L */
    for (size_t i = 0; i < n && i < 16; i++) {
        if (st[i].child_count != 0)
            continue;
        double wu = 0, wl = 0;
        for (int k = 0; k < SIDES; k++) {
            cbm_vec3 d = sub(vtx(sc, r1[i] + (size_t)k), st[i].distal);
            wu = fmax(wu, fabs(dot(d, st[i].frame.u)));
            wl = fmax(wl, fabs(dot(d, st[i].frame.l)));
        }
        /* 8 vertices at angles of their own: within the sampling */
        CHECK_NEAR(wu, st[i].a, 0.15 * st[i].a);
        CHECK_NEAR(wl, st[i].b, 0.15 * st[i].b);
        CHECK(wu > 1.5 * wl);
    }
    cbm_scene_destroy(sc);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}
