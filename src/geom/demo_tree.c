/* A synthetic tree for trying the writers and measuring them: breadth-first growth from a
 * queue of buds, so any segment count gives a complete-looking crown. Each branch has 10
 * segments; every segment but the last carries a lateral bud turned 137.5 degrees (golden
 * angle) around the axis from the previous one and 50 degrees out; axes bend towards the
 * horizontal with order, lengths shrink by 0.62 and radii by 0.65 per order (pipe-model-like).
 * The quantities are smooth made-up fields (stress ratio rising towards branch bases and with
 * horizontality, age from the number of segments above, reaction wood from inclination): they
 * exercise the colour maps, they are not mechanics. */
#include "cambium/write.h"

#include "../core/core.h"
#include "../core/vecmath.h"

#include <math.h>

typedef struct bud {
    cbm_vec3 pos;
    cbm_frame f;
    double radius, length;
    int order;
    int64_t parent;
} bud;

#define SEGS_PER_BRANCH 10

static cbm_frame turn(cbm_frame f, cbm_vec3 axis, double angle)
{
    return frame_orthonormalize(frame_rotate(q_axis_angle(axis, angle), f));
}

static cbm_section section_at(cbm_vec3 c, cbm_frame f, double r, int order)
{
    cbm_section s;
    s.center = c;
    s.frame = f;
    s.a = r;
    s.b = order == 0 ? r : 0.8 * r; /* laterals are flattened vertically */
    return s;
}

static cbm_status add_leaf(cbm_scene *s, cbm_vec3 base, cbm_frame f, double len)
{
    cbm_part p = cbm_part_default();
    p.organ = CBM_ORGAN_LEAF;
    p.color[0] = 0.16f;
    p.color[1] = 0.42f;
    p.color[2] = 0.10f;
    CBM_TRY(cbm_scene_begin_part(s, &p, NULL));
    /* blade in the H-L plane, tilted up a little */
    cbm_vec3 h = v3_normalize(v3_add(f.h, v3(0, 0.3, 0))), l = v3_normalize(f.l);
    cbm_vec3 pts[6];
    const double t[6] = {0, 0.25, 0.6, 1.0, 0.6, 0.25}, w[6] = {0, 0.28, 0.3, 0, -0.3, -0.28};
    for (int k = 0; k < 6; k++)
        pts[k] = v3_add(base, v3_add(v3_scale(h, t[k] * len), v3_scale(l, w[k] * len)));
    return cbm_scene_add_polygon(s, pts, 6);
}

cbm_status cbm_scene_demo_tree(cbm_context *ctx, cbm_scene *s, size_t segments, int sides,
                               bool ground, uint64_t seed)
{
    if (!ctx || !s || sides < 3 || sides > 64 || segments > 10000000)
        return CBM_E_INVALID;
    CBM_ARRAY(bud) q = {0};
    cbm_rng rng;
    cbm__rng_seed(&rng, seed);
    cbm_status st = CBM_OK;
    if (ground) {
        cbm_part g = cbm_part_default();
        g.organ = CBM_ORGAN_GROUND;
        g.color[0] = 0.45f;
        g.color[1] = 0.42f;
        g.color[2] = 0.34f;
        const cbm_vec3 sq[4] = {v3(-0.8, 0, -0.8), v3(-0.8, 0, 0.8), v3(0.8, 0, 0.8),
                                v3(0.8, 0, -0.8)};
        CBM_TRY(cbm_scene_begin_part(s, &g, NULL));
        CBM_TRY(cbm_scene_add_polygon(s, sq, 4));
    }
    /* total height ~ 1 m: trunk of 10 segments, laterals add a little */
    bud root = {v3(0, 0, 0), {v3(0, 1, 0), v3(-1, 0, 0), v3(0, 0, 1)}, 0.025, 0.075, 0, -1};
    if ((st = CBM_ARRAY_PUSH(ctx, q, root)) != CBM_OK)
        return st;
    size_t head = 0, made = 0, tips = 0;
    int64_t next_id = 0;
    while (head < q.len && made < segments && st == CBM_OK) {
        bud b = q.data[head++];
        cbm_vec3 pos = b.pos;
        cbm_frame f = b.f;
        double r = b.radius;
        int64_t parent = b.parent;
        double phyllo = 2.0 * CBM_PI * cbm__rng_uniform(&rng);
        for (int k = 0; k < SEGS_PER_BRANCH && made < segments && st == CBM_OK; k++) {
            /* bend laterals towards the horizontal, then a little down */
            if (b.order > 0) {
                cbm_vec3 axis = v3_cross(f.h, v3(0, -1, 0));
                if (v3_norm(axis) > 1e-9)
                    f = turn(f, v3_normalize(axis), 0.012 * (1 + b.order));
            } else {
                f = turn(f, f.h, 0.3);
            }
            double r1 = r * (1.0 - 0.5 / SEGS_PER_BRANCH);
            cbm_vec3 end = v3_madd(pos, f.h, b.length);
            double incl = asin(fmax(-1.0, fmin(1.0, f.h.y))); /* rad above horizontal */
            cbm_part p = cbm_part_default();
            p.organ = CBM_ORGAN_BRANCH;
            p.order = b.order;
            p.segment = next_id;
            p.parent = parent;
            p.color[0] = 0.36f;
            p.color[1] = 0.25f;
            p.color[2] = 0.16f;
            p.age = (double)(SEGS_PER_BRANCH - k) * (4 - (b.order < 4 ? b.order : 3)) * 0.5;
            p.stress_ratio = fmin(1.2, (1.0 - (double)k / SEGS_PER_BRANCH) *
                                           (0.25 + 0.6 * cos(incl)) * (0.4 + 0.25 * b.order));
            p.stress = p.stress_ratio * 50e6;
            p.reaction_wood = b.order == 0 ? 0.0 : fmin(1.0, fabs(incl - 0.6) / 1.2);
            st = cbm_scene_begin_part(s, &p, NULL);
            if (st == CBM_OK) {
                cbm_section s0 = section_at(pos, f, r, b.order);
                cbm_section s1 = section_at(end, f, r1, b.order);
                st = cbm_scene_add_tube(s, &s0, &s1, sides, k == SEGS_PER_BRANCH - 1);
            }
            if (st != CBM_OK)
                break;
            made++;
            /* lateral bud at the end of the segment */
            if (k < SEGS_PER_BRANCH - 1) {
                phyllo += 137.5 * CBM_PI / 180.0;
                cbm_frame lf = turn(f, f.h, phyllo);
                lf = turn(lf, lf.l, -50.0 * CBM_PI / 180.0 * (0.8 + 0.4 * cbm__rng_uniform(&rng)));
                bud c = {end, lf, 0.65 * r1, 0.62 * b.length, b.order + 1, next_id};
                st = CBM_ARRAY_PUSH(ctx, q, c);
            } else {
                tips++;
                if (b.order >= 2)
                    st = add_leaf(s, end, f, 2.5 * b.length);
                if (st == CBM_OK && tips % 7 == 3) {
                    cbm_part fr = cbm_part_default();
                    fr.organ = CBM_ORGAN_FRUIT;
                    fr.parent = next_id;
                    fr.color[0] = 0.75f;
                    fr.color[1] = 0.08f;
                    fr.color[2] = 0.05f;
                    st = cbm_scene_begin_part(s, &fr, NULL);
                    double fr_r = fmax(0.6 * b.length, 4 * r1);
                    if (st == CBM_OK)
                        st = cbm_scene_add_sphere(s, v3_madd(end, v3(0, -1, 0), fr_r), fr_r, 10);
                }
            }
            parent = next_id++;
            pos = end;
            r = r1;
        }
    }
    CBM_ARRAY_FREE(ctx, q);
    return st;
}
