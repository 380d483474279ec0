/* Geometry of a built-in tree for the writers (Taylor-Hell 2005 A.1 interpretation rules):
 * the branches as elliptical generalized cylinders (cbm_plant_to_scene), each leaf as an
 * ovate blade of length leaf_scale sqrt(m / leaf_density) in the plane of the bud's heading and
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
            double side = d->leaf_scale * sqrt(s->leaf / d->leaf_density);
            /* in the plane of H and the horizontal perpendicular to it */
            cbm_vec3 w = v3_cross(v3(0, 1, 0), h);
            double wn = v3_norm(w);
            w = wn > 1e-9 ? v3_scale(w, 1.0 / wn) : q_rotate(p->q[i], v3(0, 1, 0));
            /* an ovate blade along H: half-width 0.3 side sin(pi t)^0.75 (1 - 0.35 t) at
             * t = 0 (base) .. 1 (pointed tip) */
            enum { K = 9 };
            cbm_vec3 pts[2 * K];
            pts[0] = e;
            pts[K] = v3_madd(e, h, side);
            for (int k = 1; k < K; k++) {
                double u = (double)k / K;
                double hw = 0.3 * side * pow(sin(CBM_PI * u), 0.75) * (1.0 - 0.35 * u);
                cbm_vec3 c = v3_madd(e, h, u * side);
                pts[k] = v3_madd(c, w, hw);
                pts[2 * K - k] = v3_madd(c, w, -hw);
            }
            CBM_TRY(cbm_scene_add_polygon(scene, pts, 2 * K));
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
