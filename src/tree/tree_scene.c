/* Geometry of a built-in tree for the writers (Taylor-Hell 2005 A.1 interpretation rules):
 * the branches as continuous elliptical generalized cylinders (cbm_plant_to_scene); each leaf
 * on its petiole at its node (a spur: nleaf leaves of m / nleaf each, their petioles spread 40 deg
 * around the bud's heading), the end of its bud internode: the petiole (0.3 of the blade's
 * length, 0.025 of it across) goes on along the bud's heading, then an ovate blade of length
 * 1.5 side and width 0.6 of its length, side = leaf_scale sqrt(m / leaf_density), so that the
 * blade's area is about side^2 (the leaf's area m / leaf_density times leaf_scale^2), in the
 * plane of the bud's heading and its horizontal (the listing's SetHead + RollToVert + Surface),
 * half-width 0.3 length sin(pi u^0.8) at u = 0 (base) .. 1 (tip): widest at 0.42 of its length,
 * round at the base, pointed at the tip (an apple leaf: ovate-elliptic); each fruit a sphere of
 * volume m / fruit_density on a stalk of 0.7 of its radius hanging from its node; and
 * optionally a ground square. */
#include "tree/tree_internal.h"
#include "core/vecmath.h"

#include <math.h>

cbm_status cbm_tree_to_scene(const cbm_tree *t, cbm_scene *scene, int sides, bool ground)
{
    if (!t || !scene)
        return CBM_E_INVALID;
    CBM_TRY(cbm_plant_to_scene(t->plant, scene, sides));
    const tree_plant v = tree_plant_of(t->plant), *p = &v;
    const cbm_tree_def *d = &t->def;
    double lo = 0.0, hi = 0.0;
    for (size_t i = 0; i < t->seg.len; i++) {
        const tree_seg *s = &t->seg.data[i];
        cbm_vec3 h = q_rotate(p->q[i], v3(1, 0, 0));
        cbm_vec3 e = v3_madd(p->pos[i], h, p->len[i]);
        lo = fmin(lo, fmin(e.x, e.z));
        hi = fmax(hi, fmax(e.x, e.z));
        if (s->leaf > 0.0) {
            cbm_part part = cbm_part_default();
            part.organ = CBM_ORGAN_LEAF;
            part.segment = (int64_t)i;
            part.parent = p->parent[i];
            part.order = p->order[i];
            /* apple leaves: dark green above (linear RGB of sRGB (45, 105, 35)) */
            part.color[0] = 0.026f, part.color[1] = 0.141f, part.color[2] = 0.017f;
            part.color[3] = 1;
            CBM_TRY(cbm_scene_begin_part(scene, &part, NULL));
            /* a spur's rosette: nleaf leaves of a share of the mass each, their petioles
             * spread 40 deg around the bud's heading */
            int nl = s->nleaf > 1 ? s->nleaf : 1;
            double len = 1.5 * d->leaf_scale * sqrt(s->leaf / nl / d->leaf_density);
            cbm_vec3 w0 = v3_cross(v3(0, 1, 0), h);
            double w0n = v3_norm(w0);
            w0 = w0n > 1e-9 ? v3_scale(w0, 1.0 / w0n) : q_rotate(p->q[i], v3(0, 1, 0));
            cbm_vec3 v0 = v3_cross(h, w0);
            for (int k = 0; k < nl; k++) {
                cbm_vec3 hk = h;
                if (nl > 1) {
                    double ph = 2.0 * CBM_PI * k / nl, sp = 40.0 * CBM_PI / 180.0;
                    hk = v3_add(
                        v3_scale(h, cos(sp)),
                        v3_scale(v3_add(v3_scale(w0, cos(ph)), v3_scale(v0, sin(ph))), sin(sp)));
                }
                /* the blade's plane: H and the horizontal perpendicular to it */
                cbm_vec3 w = v3_cross(v3(0, 1, 0), hk);
                double wn = v3_norm(w);
                w = wn > 1e-9 ? v3_scale(w, 1.0 / wn) : w0;
                cbm_vec3 up = v3_cross(hk, w);          /* the petiole's section: round */
                cbm_vec3 b = v3_madd(e, hk, 0.3 * len); /* the blade's base */
                cbm_section s0 = {e, {hk, w, up}, 0.0125 * len, 0.0125 * len};
                cbm_section s1 = {b, {hk, w, up}, 0.0125 * len, 0.0125 * len};
                CBM_TRY(cbm_scene_add_tube(scene, &s0, &s1, 6, false));
                enum { K = 12 };
                cbm_vec3 pts[2 * K];
                pts[0] = b;
                pts[K] = v3_madd(b, hk, len);
                for (int q = 1; q < K; q++) {
                    double u = (double)q / K;
                    double hw = 0.3 * len * sin(CBM_PI * pow(u, 0.8));
                    cbm_vec3 c = v3_madd(b, hk, u * len);
                    pts[q] = v3_madd(c, w, hw);
                    pts[2 * K - q] = v3_madd(c, w, -hw);
                }
                CBM_TRY(cbm_scene_add_polygon(scene, pts, 2 * K));
            }
        }
        if (s->fruit > 0.0) {
            cbm_part part = cbm_part_default();
            part.organ = CBM_ORGAN_FRUIT;
            part.segment = (int64_t)i;
            part.parent = p->parent[i];
            part.order = p->order[i];
            part.color[0] = 0.75f, part.color[1] = 0.08f, part.color[2] = 0.05f, part.color[3] = 1;
            CBM_TRY(cbm_scene_begin_part(scene, &part, NULL));
            double r = cbrt(0.75 / CBM_PI * s->fruit / d->fruit_density);
            /* the stalk, straight down from the node, then the fruit below it */
            cbm_frame down = {v3(0, -1, 0), v3(1, 0, 0), v3(0, 0, 1)}; /* L = U x H */
            cbm_section s0 = {e, down, 0.05 * r, 0.05 * r};
            cbm_section s1 = {v3(e.x, e.y - 0.8 * r, e.z), down, 0.05 * r, 0.05 * r};
            CBM_TRY(cbm_scene_add_tube(scene, &s0, &s1, 6, false));
            CBM_TRY(cbm_scene_add_sphere(scene, v3(e.x, e.y - 1.7 * r, e.z), r, 16));
        }
    }
    if (ground) {
        cbm_part part = cbm_part_default();
        part.organ = CBM_ORGAN_GROUND;
        part.color[0] = 0.35f, part.color[1] = 0.3f, part.color[2] = 0.22f, part.color[3] = 1;
        CBM_TRY(cbm_scene_begin_part(scene, &part, NULL));
        double g = 1.2 * fmax(fabs(lo), fabs(hi)) + 0.1;
        cbm_vec3 pts[4] = {v3(-g, 0, -g), v3(-g, 0, g), v3(g, 0, g), v3(g, 0, -g)};
        CBM_TRY(cbm_scene_add_polygon(scene, pts, 4));
    }
    return CBM_OK;
}
