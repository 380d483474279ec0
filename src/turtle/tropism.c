/* Tropisms (ABOP section 2.2, cpfg's "tropism:" movements): the heading bent towards the
 * tropism directions after or before each move, U carried along by the minimal rotation. */
#include "turtle_internal.h"

#include <stdio.h>

/* ---- tropisms ---- */

/* ABOP tropism after a move: two rotations towards T (cpfg's "bend"). */
void cbm__turtle_bend(cbm_turtle *t)
{
    tstate *s = &t->cur;
    double e = s->elasticity;
    if (e == 0.0)
        return;
    cbm_vec3 T = t->view->tropism_dir;
    /* sin(alpha) is clamped to [-1, 1] (cpfg gives NaN when e |T.U| > 1) */
    double bc = fmax(-1.0, fmin(1.0, e * v3_dot(T, s->u)));
    double bs = sqrt(1.0 - bc * bc);
    cbm__turtle_rotate_pair(&s->h, &s->u, bc, bs);
    bc = fmax(-1.0, fmin(1.0, e * v3_dot(T, s->l)));
    bs = sqrt(1.0 - bc * bc);
    cbm__turtle_rotate_pair(&s->h, &s->l, bc, bs);
}

/* Rotate v about the unit axis n by angle (right hand). */
cbm_vec3 cbm__turtle_rot_axis(cbm_vec3 v, cbm_vec3 n, double angle)
{
    return q_rotate(q_axis_angle(n, angle), v);
}

/* U follows H by the minimal rotation from the previous heading; L = H x U. */
void cbm__turtle_adjust_up_and_left(tstate *s)
{
    cbm_vec3 r = v3_cross(s->prev_h, s->h);
    double len = v3_norm(r);
    if (len > 0.000001) {
        if (len > 1.0)
            len = 1.0;
        double angle = asin(len);
        if (v3_dot(s->h, s->prev_h) < 0)
            angle = CBM_PI - angle;
        s->u = cbm__turtle_rot_axis(s->prev_u, v3_scale(r, 1.0 / v3_norm(r)), angle);
    }
    s->l = v3_cross(s->h, s->u);
}

void cbm__turtle_movements(cbm_turtle *t)
{
    const cbm_view *v = t->view;
    if (v->nmov == 0)
        return;
    tstate *s = &t->cur;
    cbm_vec3 V = v3(0, 0, 0), tw = v3(0, 0, 0);
    for (int i = 0; i < v->nmov; i++) {
        const cbm__movement *m = &v->mov[i];
        double e = s->mov_e[i];
        if (m->torque) {
            tw = v3_madd(tw, m->dir, e);
            continue;
        }
        V = v3_madd(V, m->dir, m->cos_g * e);
        if (m->sin_g != 0.0) {
            cbm_vec3 hx = v3_cross(s->h, m->dir);
            double len = v3_norm(hx);
            if (len < 0.0000001) {
                hx = s->l;
                len = 1.0;
            }
            V = v3_madd(V, v3_cross(m->dir, hx), m->sin_g * e / len);
        }
    }
    cbm_vec3 rv = v3_cross(s->h, V);
    double len = v3_norm(rv);
    if (len >= 0.000001) {
        double a = len > 1.0 ? 1.0 : len;
        s->h = v3_normalize(cbm__turtle_rot_axis(s->h, v3_scale(rv, 1.0 / len), a));
        cbm__turtle_adjust_up_and_left(s);
    }
    double twl = v3_norm(tw);
    if (twl > 0.0) {
        /* torque: roll U about H by the angle |U x D| (capped at 1 rad), D the torque direction
         * projected normal to H, in the sense of cpfg's code: away from D (its comment says
         * towards; the code's quaternion rotates by the opposite angle), so U settles at -D */
        cbm_vec3 dn = v3_scale(tw, 1.0 / twl);
        cbm_vec3 c = v3_cross(s->h, dn);
        if (v3_dot(c, c) > 0.00000001) {
            cbm_vec3 D = v3_scale(v3_cross(c, s->h), twl);
            cbm_vec3 ax = v3_cross(s->u, D);
            double al = v3_norm(ax);
            if (al >= 0.0000001) {
                s->u = cbm__turtle_rot_axis(s->u, v3_scale(ax, 1.0 / al), al > 1.0 ? -1.0 : -al);
                s->l = v3_cross(s->h, s->u);
            }
            s->prev_h = s->h;
            s->prev_u = s->u;
        }
    }
}
