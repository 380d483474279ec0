/* Generalized cylinders (@Gs @Gc(n) @Ge(n), cpfg manual "Generalized cylinders"): cubic Hermite
 * curves between control points, n bands each, rings of contours resampled by arc length and
 * carried along by the minimal rotation of U. */
#include "turtle_internal.h"

#include <stdio.h>

/* ---- generalized cylinders ---- */

/* cpfg's minimal rotation of a frame: U follows the rotation taking prev_h to h (by
 * asin |h x prev_h|), then turns by -beta about h; L = H x U. */
void cbm__turtle_adjust_frame(cbm_vec3 h, cbm_vec3 prev_h, cbm_vec3 prev_u, double beta,
                              cbm_vec3 *u, cbm_vec3 *l)
{
    cbm_vec3 r = v3_cross(h, prev_h);
    double len = v3_norm(r);
    cbm_vec3 up = prev_u;
    if (len > 0.0) {
        double a = asin(len > 1.0 ? 1.0 : len);
        up = cbm__turtle_rot_axis(up, v3_scale(r, -1.0 / len), a);
    }
    if (beta != 0.0)
        up = cbm__turtle_rot_axis(up, h, -beta);
    *u = up;
    *l = v3_cross(h, up);
}

/* Angle by which g2's up must turn about its heading to follow g1 without twist (cpfg). */
double cbm__turtle_twist_angle(const gcpt *g1, const gcpt *g2)
{
    cbm_vec3 up = g1->u;
    cbm_vec3 r = v3_cross(g2->h, g1->h);
    double len = v3_norm(r);
    if (len > 0.000001)
        up = cbm__turtle_rot_axis(up, v3_scale(r, -1.0 / len), asin(len > 1.0 ? 1.0 : len));
    double c = v3_norm(v3_cross(g2->u, up));
    double angle = asin(c > 1.0 ? 1.0 : c);
    if (v3_dot(g2->u, up) < 0.0)
        angle = CBM_PI - angle;
    if (v3_dot(g2->l, up) < 0.0)
        angle = -angle;
    return angle;
}

/* Uniform cubic B-spline of the contour's control points at parameter tt (indices wrap). */
static void contour_eval(const cbm__contour *c, float tt, float out[3])
{
    int num = (int)(c->pts.len / 3);
    int first = (int)floorf(tt);
    float u = tt - (float)first;
    float b[4] = {(1 - u) * (1 - u) * (1 - u) / 6.0f, (3 * u * u * u - 6 * u * u + 4) / 6.0f,
                  (-3 * u * u * u + 3 * u * u + 3 * u + 1) / 6.0f, u * u * u / 6.0f};
    out[0] = out[1] = out[2] = 0.0f;
    if (num == 0) /* no control points: the origin */
        return;
    for (int i = 0; i < 4; i++) {
        int k = ((first + i) % num + num) % num;
        for (int d = 0; d < 3; d++)
            out[d] += b[i] * (float)c->pts.data[3 * k + d];
    }
}

/* Points of contour `contour` (0: the unit circle) resampled at `sides` equal arc lengths (as
 * cpfg: arc length tabulated at 10 points per knot interval, closed contours rotated so their
 * first point lies on +x); sides + 1 points, the last equal to the first when closed. */
static cbm_status contour_points(cbm_turtle *t, int contour, int sides, const double **out)
{
    for (size_t i = 0; i < t->ccache.len; i++)
        if (t->ccache.data[i].contour == contour && t->ccache.data[i].sides == sides) {
            *out = t->cpts.data + t->ccache.data[i].off;
            return CBM_OK;
        }
    size_t off = t->cpts.len;
    CBM_TRY(CBM_ARRAY_RESERVE(t->ctx, t->cpts, off + 3 * (size_t)(sides + 1)));
    double *p = t->cpts.data + off;
    const cbm__contour *c = contour > 0 && (size_t)contour <= t->view->contours.len
                                ? &t->view->contours.data[contour - 1]
                                : NULL;
    if (!c) {
        float step = (float)(2.0 * CBM_PI) / (float)sides, angle = 0.0f;
        for (int i = 0; i < sides; i++) {
            p[3 * i] = (float)cos(angle);
            p[3 * i + 1] = (float)sin(angle);
            p[3 * i + 2] = 0.0;
            angle += step;
        }
        for (int d = 0; d < 3; d++)
            p[3 * sides + d] = p[d];
    } else {
        const int n = 10;
        int num = (int)(c->pts.len / 3);
        int segments = c->closed ? num : num - 3;
        if (segments < 1)
            segments = 1;
        float *len = cbm__alloc(t->ctx, (size_t)(segments * n) * sizeof(float));
        if (!len)
            return CBM_E_NOMEM;
        float last[3], act[3], total = 0.0f, invn = 1.0f / (float)n;
        contour_eval(c, 0.0f, last);
        for (int i = 0; i < segments; i++) {
            float tt = (float)i;
            for (int j = 0; j < n; j++, tt += invn) {
                contour_eval(c, tt, act);
                float dx = last[0] - act[0], dy = last[1] - act[1];
                total += sqrtf(dx * dx + dy * dy);
                len[i * n + j] = total;
                memcpy(last, act, sizeof last);
            }
        }
        float rot[2][2] = {{1, 0}, {0, 1}};
        if (c->closed) {
            contour_eval(c, 0.0f, act);
            float dx = last[0] - act[0], dy = last[1] - act[1];
            total += sqrtf(dx * dx + dy * dy);
            float q = act[0] * act[0] + act[1] * act[1];
            if (q >= 0.000000001f) {
                float inv = 1.0f / sqrtf(q);
                rot[0][0] = act[0] * inv;
                rot[0][1] = -act[1] * inv;
                rot[1][0] = -rot[0][1];
                rot[1][1] = rot[0][0];
            }
        }
        float step = total / (float)sides, target = 0.0f, eps = 1e-10f / step;
        int j = 0, last_j = segments * n - 1;
        int npts = c->closed ? sides : sides + 1;
        for (int i = 0; i < npts; i++) {
            float tt;
            if (i == 0) {
                while (j < last_j && len[j] < eps)
                    j++;
                tt = 0.0f;
            } else {
                while (j < last_j && len[j] < target)
                    j++;
                int j2 = j - 1;
                while (j2 > 0 && len[j] - len[j2] <= eps)
                    j2--;
                if (j2 < 0)
                    j2 = 0;
                float d = len[j] - len[j2];
                tt = (float)j2 / (float)n + (d > 0.0f ? (target - len[j2]) / d / (float)n : 0.0f);
            }
            contour_eval(c, tt, act);
            p[3 * i] = act[0] * rot[0][0] + act[1] * rot[1][0];
            p[3 * i + 1] = act[0] * rot[0][1] + act[1] * rot[1][1];
            p[3 * i + 2] = act[2];
            target += step;
        }
        if (c->closed)
            for (int d = 0; d < 3; d++)
                p[3 * sides + d] = p[d];
        cbm__free(t->ctx, len, (size_t)(segments * n) * sizeof(float));
    }
    t->cpts.len = off + 3 * (size_t)(sides + 1);
    ccache cc = {contour, sides, off};
    CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->ccache, cc));
    *out = t->cpts.data + off;
    return CBM_OK;
}

gcpt cbm__turtle_gc_snapshot(const tstate *s)
{
    gcpt g;
    memset(&g, 0, sizeof g);
    g.pos = s->pos;
    g.h = s->h;
    g.l = s->l;
    g.u = s->u;
    g.width = s->width;
    g.tan[0] = s->tan[0];
    g.tan[1] = s->tan[1];
    memcpy(g.rtan, s->rtan, sizeof g.rtan);
    g.rtan_scale = s->rtan_scale;
    g.contour = s->contour;
    g.sides = s->sides;
    return g;
}

/* One ring: contour points mixed (1-mix, mix) between the two contours, scaled by radius and
 * placed at P + x U - y L + z H * zscale, as cpfg's make_contour. */
static cbm_status push_ring(cbm_turtle *t, cbm_vec3 P, cbm_vec3 h, cbm_vec3 u, cbm_vec3 l,
                            double radius, const double *c1, const double *c2, double mix,
                            double zscale, int sides)
{
    for (int k = 0; k <= sides; k++) {
        double x = radius * (c1[3 * k] * (1 - mix) + c2[3 * k] * mix);
        double y = radius * (c1[3 * k + 1] * (1 - mix) + c2[3 * k + 1] * mix);
        double z = radius * (c1[3 * k + 2] * (1 - mix) + c2[3 * k + 2] * mix);
        cbm_vec3 q =
            v3_add(v3_add(P, v3_scale(u, x)), v3_add(v3_scale(l, -y), v3_scale(h, z * zscale)));
        CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->ringv, q));
    }
    /* normals of the ring's curve (its tangent crossed with the heading, outwards), so that
     * the rings a control point shares between two connections, and the first and last point
     * of a closed contour, get the same normal: the cylinder is shaded without seams */
    const cbm_vec3 *q = t->ringv.data + t->ringv.len - (size_t)(sides + 1);
    bool closed = v3_norm(v3_sub(q[0], q[sides])) <= 1e-12 * (1.0 + radius);
    for (int k = 0; k <= sides; k++) {
        int a = k > 0 ? k - 1 : closed ? sides - 1 : 0;
        int b = k < sides ? k + 1 : closed ? 1 : sides;
        cbm_vec3 n = v3_cross(v3_sub(q[b], q[a]), h);
        cbm_vec3 out = v3_sub(q[k], P);
        if (v3_dot(n, out) < 0)
            n = v3_neg(n);
        double nn = v3_norm(n);
        if (nn > 1e-300)
            n = v3_scale(n, 1.0 / nn);
        else
            n = v3_norm(out) > 1e-300 ? v3_normalize(out) : u;
        CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->ringn, n));
    }
    return CBM_OK;
}

/* cpfg's band of a generalized cylinder from the ring state g1 to g2 (cpfg's
 * interpolate_connection): the spine is the cubic a0 + a1 t + a2 t^2 + a3 t^3 given by `bsp`
 * (a uniform cubic B-spline segment) or, when bsp is NULL, the Hermite cubic with tangents
 * H1 |P2-P1| tan1 and H2 |P2-P1| tan0; `rings` bands, radius and contour interpolated, each ring's
 * U carried from g1 by the minimal rotation (and `twist` when "twist of cylinders" is on). */
cbm_status cbm__turtle_gc_segment(cbm_turtle *t, const gcpt *g1p, const gcpt *g2p, int rings,
                                  const cbm_vec3 *bsp, double twist)
{
    tstate *s = &t->cur;
    gcpt g1 = *g1p, g2 = *g2p;
    double len = v3_norm(v3_sub(g2.pos, g1.pos));
    if (len < 0.00001)
        return CBM_OK;
    cbm_vec3 R1, c2, c3;
    if (bsp) {
        R1 = bsp[1];
        c2 = bsp[2];
        c3 = bsp[3];
    } else {
        R1 = v3_scale(g1.h, len * g1.tan[1]);
        cbm_vec3 R2 = v3_scale(g2.h, len * g2.tan[0]);
        cbm_vec3 d = v3_sub(g1.pos, g2.pos);
        c2 = v3_sub(v3_sub(v3_scale(d, -3.0), v3_scale(R1, 2.0)), R2);
        c3 = v3_add(v3_add(v3_scale(d, 2.0), R1), R2);
    }
    double dr = 0.5 * (g2.width - g1.width);
    /* the radius along the segment: a Hermite curve in (t, r) from (0, w1/2) to (1, w2/2) with
     * the radius tangents of the two control points (linear when they are zero) */
    double rt0[2] = {g1.rtan[1][0], g1.rtan[1][1]}, rt1[2] = {g2.rtan[0][0], g2.rtan[0][1]};
    if (g2.rtan_scale) {
        rt0[1] *= len;
        rt1[1] *= len;
    }
    if (rt0[0] == 0.0 && rt0[1] == 0.0) {
        rt0[0] = 1.0;
        rt0[1] = dr;
    }
    if (rt1[0] == 0.0 && rt1[1] == 0.0) {
        rt1[0] = 1.0;
        rt1[1] = dr;
    }
    double ta = 3 - 2 * rt0[0] - rt1[0], tb = -2 + rt0[0] + rt1[0];
    double ra = 3 * dr - 2 * rt0[1] - rt1[1], rb = -2 * dr + rt0[1] + rt1[1];
    int sides = g1.sides;
    bool cyl = cbm__turtle_line_style(t) == CBM__LS_CYLINDER;
    const double *k1 = NULL, *k2 = NULL;
    if (cyl) {
        CBM_TRY(contour_points(t, g1.contour, sides, &k1));
        CBM_TRY(contour_points(t, g2.contour, sides, &k2));
    }
    t->ringv.len = 0;
    t->ringn.len = 0;
    cbm_vec3 prev = g1.pos;
    for (int i = 0; i <= rings; i++) {
        double r = (double)i / rings;
        double tt = ((tb * r + ta) * r + rt0[0]) * r;
        cbm_vec3 P, H, U, L;
        double radius;
        if (i == 0) {
            P = g1.pos;
            H = g1.h;
            U = g1.u;
            L = g1.l;
            radius = 0.5 * g1.width;
        } else if (i == rings) {
            P = g2.pos;
            H = g2.h;
            U = g2.u;
            L = g2.l;
            radius = 0.5 * g2.width;
        } else {
            P = v3_add(v3_add(g1.pos, v3_scale(R1, tt)),
                       v3_add(v3_scale(c2, tt * tt), v3_scale(c3, tt * tt * tt)));
            H = v3_normalize(v3_add(R1, v3_add(v3_scale(c2, 2 * tt), v3_scale(c3, 3 * tt * tt))));
            cbm__turtle_adjust_frame(H, g1.h, g1.u, twist * tt, &U, &L);
            radius = 0.5 * g1.width + ((rb * r + ra) * r + rt0[1]) * r;
        }
        if (cyl) {
            double zs = i == 0 ? g1.tan[1] : i == rings ? g2.tan[0] : 1.0 / len;
            CBM_TRY(push_ring(t, P, H, U, L, radius, k1, k2, i == rings ? 1.0 : tt, zs, sides));
        } else if (i > 0) {
            /* pixel and polygon lines: cpfg draws the spine as segments */
            CBM_TRY(cbm__turtle_emit_segment(t, prev, P, g1.width, i == rings ? g2.width : g1.width,
                                             s->color, H, U));
            cbm__turtle_box_add(t, P);
        }
        prev = P;
    }
    if (!cyl)
        return CBM_OK;
    /* the bands, in cpfg's triangle order */
    uint32_t w = (uint32_t)sides + 1;
    t->ringt.len = 0;
    for (int i = 1; i <= rings; i++) {
        uint32_t a = (uint32_t)(i - 1) * w, b = (uint32_t)i * w;
        for (uint32_t k = 1; k <= (uint32_t)sides; k++) {
            uint32_t tri[6] = {b + k - 1, b + k, a + k - 1, a + k - 1, b + k, a + k};
            for (int m = 0; m < 6; m++)
                CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->ringt, tri[m]));
        }
    }
    for (size_t i = 0; i < t->ringv.len; i++)
        cbm__turtle_box_add(t, t->ringv.data[i]);
    if (t->record) {
        cbm_prim pr;
        memset(&pr, 0, sizeof pr);
        pr.kind = CBM_PRIM_GCYL;
        pr.color = s->color;
        pr.p0 = g1.pos;
        pr.p1 = g2.pos;
        pr.r0 = g1.width / 2;
        pr.r1 = g2.width / 2;
        pr.frame.h = g1.h;
        pr.frame.l = g1.l;
        pr.frame.u = g1.u;
        pr.first = t->pts.len;
        pr.count = t->ringt.len;
        for (size_t i = 0; i < t->ringt.len; i++)
            CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->pts, t->ringv.data[t->ringt.data[i]]));
        CBM_TRY(cbm__turtle_push_prim(t, &pr));
    }
    if (t->scene) {
        cbm_part part = cbm__turtle_make_part(t, CBM_ORGAN_BRANCH, s->color);
        CBM_TRY(cbm_scene_begin_part(t->scene, &part, NULL));
        CBM_TRY(cbm_scene_add_mesh(t->scene, t->ringv.data, t->ringn.data, t->ringv.len,
                                   t->ringt.data, t->ringt.len / 3));
        /* lpfg's turtle: each connection closed at its end, so that an axis which stops (a
         * branch broken off above a node, a leader taken over by a thinner lateral) shows bark,
         * not the inside of the tube; where the cylinder goes on, the disc lies inside it */
        if (t->lpfg && sides >= 3)
            CBM_TRY(cbm_scene_add_polygon(
                t->scene, t->ringv.data + t->ringv.len - (size_t)(sides + 1), (size_t)sides));
    }
    return CBM_OK;
}

/* cpfg's segment from a generalized cylinder's last control point to the turtle (@Gc, @Ge):
 * a Hermite band; then the turtle becomes the last control point. */
cbm_status cbm__turtle_gc_connect(cbm_turtle *t, int rings)
{
    tstate *s = &t->cur;
    gcpt g1 = s->gc, g2 = cbm__turtle_gc_snapshot(s);
    double twist = 0.0;
    if (t->view->gc_twist)
        twist = cbm__turtle_twist_angle(&g1, &g2);
    else
        cbm__turtle_adjust_frame(g2.h, g1.h, g1.u, 0.0, &g2.u, &g2.l);
    s->gc = g2;
    return cbm__turtle_gc_segment(t, &g1, &g2, rings, NULL, twist);
}
