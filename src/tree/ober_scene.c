/* Geometry of Oberlaender's parametric tree for the writers and the light pass: each annual
 * shoot a cylinder of its pipe-model radius (the thesis draws one Cylinder per shoot), each
 * living leaf a horizontal rectangle leafL x leafW facing up (the thesis's Parallelogram
 * "oriented toward the top") beside its node: its long side points away from the axis in the
 * horizontal direction of its bud, starting at the shoot's surface. Scene units are metres. */
#include "tree/ober_internal.h"
#include "core/vecmath.h"

#include <math.h>

bool cbm__ober_leaf_quad(const cbm_ober_stand *s, size_t bi, cbm_vec3 q[4])
{
    const ober_bud *b = &s->buds.data[bi];
    const ober_shoot *h = &s->shoots.data[b->shoot];
    if (b->apical || h->leaves <= 0)
        return false;
    const cbm_ober_def *d = &s->def;
    double a = b->head * CBM_PI / 180.0;
    cbm_vec3 p = v3_madd(h->base, h->H, h->len * b->node / h->nodes);
    cbm_vec3 r = v3_add(v3_scale(h->L, cos(a)), v3_scale(h->U, sin(a)));
    cbm_vec3 dh = v3(r.x, 0, r.z);
    double n = v3_norm(dh);
    if (n < 1e-9) { /* the bud points straight up or down: any horizontal will do */
        dh = v3(h->H.x, 0, h->H.z);
        n = v3_norm(dh);
        if (n < 1e-9)
            dh = v3(1, 0, 0), n = 1;
    }
    dh = v3_scale(dh, 1.0 / n);
    cbm_vec3 w = v3_cross(v3(0, 1, 0), dh); /* horizontal, across the leaf */
    cbm_vec3 c0 = v3_madd(p, dh, h->radius), c1 = v3_madd(p, dh, h->radius + d->leaf_length);
    double hw = 0.5 * d->leaf_width;
    /* counter-clockwise seen from above: (q1 - q0) x (q3 - q0) points up */
    q[0] = v3_scale(v3_madd(c0, w, -hw), 0.01);
    q[1] = v3_scale(v3_madd(c1, w, -hw), 0.01);
    q[2] = v3_scale(v3_madd(c1, w, hw), 0.01);
    q[3] = v3_scale(v3_madd(c0, w, hw), 0.01);
    return true;
}

cbm_status cbm_ober_to_scene(const cbm_ober_stand *s, cbm_scene *scene, int sides, bool ground)
{
    if (!s || !scene)
        return CBM_E_INVALID;
    if (sides < 3)
        sides = 12;
    double lo = 0, hi = 0;
    for (size_t i = 0; i < s->shoots.len; i++) {
        const ober_shoot *h = &s->shoots.data[i];
        cbm_part part = cbm_part_default();
        part.organ = CBM_ORGAN_BRANCH;
        part.segment = (int64_t)i;
        part.parent = h->parent;
        part.order = h->order;
        part.age = h->age;
        /* bark: linear RGB of a grey-brown */
        part.color[0] = 0.16f, part.color[1] = 0.11f, part.color[2] = 0.07f, part.color[3] = 1;
        CBM_TRY(cbm_scene_begin_part(scene, &part, NULL));
        cbm_frame f = {h->H, h->L, h->U};
        double r = 0.01 * h->radius;
        cbm_section s0 = {v3_scale(h->base, 0.01), f, r, r};
        cbm_section s1 = {v3_scale(h->tip, 0.01), f, r, r};
        CBM_TRY(cbm_scene_add_tube(scene, &s0, &s1, sides, false));
        lo = fmin(lo, fmin(s0.center.x, s0.center.z));
        hi = fmax(hi, fmax(s1.center.x, s1.center.z));
    }
    for (size_t b = 0; b < s->buds.len; b++) {
        cbm_vec3 q[4];
        if (!cbm__ober_leaf_quad(s, b, q))
            continue;
        const ober_shoot *h = &s->shoots.data[s->buds.data[b].shoot];
        cbm_part part = cbm_part_default();
        part.organ = CBM_ORGAN_LEAF;
        part.segment = s->buds.data[b].shoot;
        part.order = h->order;
        part.color[0] = 0.05f, part.color[1] = 0.25f, part.color[2] = 0.03f, part.color[3] = 1;
        CBM_TRY(cbm_scene_begin_part(scene, &part, NULL));
        CBM_TRY(cbm_scene_add_polygon(scene, q, 4));
        for (int k = 0; k < 4; k++)
            lo = fmin(lo, fmin(q[k].x, q[k].z)), hi = fmax(hi, fmax(q[k].x, q[k].z));
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
