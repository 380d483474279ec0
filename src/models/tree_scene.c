/* Geometry of a built-in tree for the writers (Taylor-Hell 2005 A.1 interpretation rules):
 * the branches as elliptical generalized cylinders (cbm_plant_to_scene), each leaf as an
 * ovate blade of length leaf_scale sqrt(m / leaf_density) (a spur: nleaf blades of m / nleaf
 * spread around its heading) in the plane of the bud's heading and
 * its horizontal (the listing's SetHead + RollToVert + Surface), each fruit as a sphere of volume m
 * / fruit_density hanging from its node, and optionally a ground square. */
#include "models/tree_internal.h"
#include "core/vecmath.h"

#include <math.h>

cbm_status cbm_tree_to_scene(const cbm_tree *t, cbm_scene *scene, int sides, bool ground)
{
    if (!t || !scene)
        return CBM_E_INVALID;
    const cbm_plant *p = t->plant;
    CBM_TRY(cbm_plant_to_scene(p, scene, sides));
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
            part.color[0] = 0.13f, part.color[1] = 0.45f, part.color[2] = 0.1f, part.color[3] = 1;
            CBM_TRY(cbm_scene_begin_part(scene, &part, NULL));
            /* a spur's rosette: nleaf blades of a share of the mass each, spread 40 deg around
             * the bud's heading */
            int nl = s->nleaf > 1 ? s->nleaf : 1;
            double side = d->leaf_scale * sqrt(s->leaf / nl / d->leaf_density);
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
                /* in the plane of H and the horizontal perpendicular to it */
                cbm_vec3 w = v3_cross(v3(0, 1, 0), hk);
                double wn = v3_norm(w);
                w = wn > 1e-9 ? v3_scale(w, 1.0 / wn) : w0;
                /* an ovate blade along H: half-width 0.3 side sin(pi t)^0.75 (1 - 0.35 t) at
                 * t = 0 (base) .. 1 (pointed tip) */
                enum { K = 9 };
                cbm_vec3 pts[2 * K];
                pts[0] = e;
                pts[K] = v3_madd(e, hk, side);
                for (int q = 1; q < K; q++) {
                    double u = (double)q / K;
                    double hw = 0.3 * side * pow(sin(CBM_PI * u), 0.75) * (1.0 - 0.35 * u);
                    cbm_vec3 c = v3_madd(e, hk, u * side);
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
            CBM_TRY(cbm_scene_add_sphere(scene, v3(e.x, e.y - r, e.z), r, 16));
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
