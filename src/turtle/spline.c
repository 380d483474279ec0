/* cpfg's spline cylinders {(n[,r]) ... }(n) (cpfg's InitializeSpline, SetControlPoint,
 * FinishSpline): control points at F, f and `.`; n = 1, 2 join them with Hermite pieces (2 closes
 * back to the first point), n = 3, 4 with uniform cubic B-spline pieces (4 closes). */
#include "turtle_internal.h"

#include <stdio.h>

/* ---- cpfg's spline cylinders {(n) ... }(n) ---- */

/* The index below which the spline records belong to enclosing branches. */
static size_t spline_level(const cbm_turtle *t)
{
    return t->stack.len ? (size_t)t->stack.data[t->stack.len - 1].spl_mark : 0;
}

/* {(n, r): a spline cylinder of kind n (1 open Hermite, 2 closed Hermite, 3 open B-spline,
 * 4 closed B-spline) with r rings per band (4 when r <= 0 or absent). Other n are ignored, as
 * cpfg. A spline already open in this branch is restarted. */
cbm_status cbm__turtle_spline_open(cbm_turtle *t, const double *params, int nparams)
{
    tstate *s = &t->cur;
    int kind = cbm__to_int(params[0]);
    if (kind < 1 || kind > 4)
        return CBM_OK; /* cpfg: "Parameter following { is above 4", ignored */
    spline sp;
    memset(&sp, 0, sizeof sp);
    sp.closed = (kind - 1) % 2 == 1;
    sp.bspline = (kind - 1) / 2 == 1;
    int rings = nparams > 1 ? cbm__to_int(params[1]) : 0;
    sp.rings = rings <= 0 ? 4 : rings > MAX_RINGS ? MAX_RINGS : rings;
    if (s->spl >= 0 && (size_t)s->spl + 1 == t->splines.len && (size_t)s->spl >= spline_level(t)) {
        t->splines.data[s->spl] = sp;
        return CBM_OK;
    }
    CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->splines, sp));
    s->spl = (int)t->splines.len - 1;
    return CBM_OK;
}

/* Unit vector along d, or `dflt` (with its frame kept) when d is (nearly) null, then U and L
 * carried from (prev_h, prev_u) by the minimal rotation turned by beta: cpfg's frame of a
 * B-spline ring at a knot. */
static void knot_frame(gcpt *g, cbm_vec3 d, double beta)
{
    double n = v3_norm(d);
    if (n > 0.0000001) {
        cbm_vec3 ph = g->h, pu = g->u;
        g->h = v3_scale(d, 1.0 / n);
        cbm__turtle_adjust_frame(g->h, ph, pu, beta, &g->u, &g->l);
    }
}

/* A control point p (F, f, or . outside a polygon) of the open spline; `rings` bands (0: the
 * spline's default). Hermite: a band from the previous control point (cpfg's generalized
 * cylinder). B-spline: once four control points P0..P3 are known, the band of the uniform cubic
 * B-spline between the knots (P0 + 4 P1 + P2) / 6 and (P1 + 4 P2 + P3) / 6, with tangents
 * (P2 - P0) / 2 and (P3 - P1) / 2, the ring states (width, contour, tangent parameters, frame)
 * those of P1 and P2 (cpfg's SetControlPoint and interpolate_connection). */
cbm_status cbm__turtle_spline_point(cbm_turtle *t, gcpt p, int rings)
{
    tstate *s = &t->cur;
    spline *sp = &t->splines.data[s->spl];
    if (rings == 0)
        rings = sp->rings;
    else if (rings < 1)
        rings = 1; /* cpfg: a single band */
    if (rings > MAX_RINGS)
        rings = MAX_RINGS;
    if (!sp->bspline) {
        if (sp->num++ == 0) {
            sp->tu = p;
            if (sp->closed)
                sp->first[sp->nfirst++] = p;
            return CBM_OK;
        }
        gcpt g1 = sp->tu, g2 = p;
        double twist = 0.0;
        if (t->view->gc_twist)
            twist = cbm__turtle_twist_angle(&g1, &g2);
        else
            cbm__turtle_adjust_frame(g2.h, g1.h, g1.u, 0.0, &g2.u, &g2.l);
        sp->tu = g2;
        return cbm__turtle_gc_segment(t, &g1, &g2, rings, NULL, twist);
    }
    if (sp->num < 3) {
        sp->win[sp->num] = p;
        if (sp->closed)
            sp->first[sp->nfirst++] = p;
        sp->num++;
        return CBM_OK;
    }
    cbm_vec3 P0 = sp->win[0].pos, P1 = sp->win[1].pos, P2 = sp->win[2].pos, P3 = p.pos;
    cbm_vec3 a[4];
    a[0] = v3_scale(v3_add(v3_add(P0, v3_scale(P1, 4.0)), P2), 1.0 / 6.0);
    a[1] = v3_scale(v3_sub(P2, P0), 0.5);
    a[2] = v3_scale(v3_add(v3_sub(P0, v3_scale(P1, 2.0)), P2), 0.5);
    a[3] = v3_scale(v3_add(v3_sub(v3_scale(v3_sub(P1, P2), 3.0), P0), P3), 1.0 / 6.0);
    gcpt g1 = sp->tu;
    if (sp->num == 3) {
        g1 = sp->win[1];
        g1.pos = a[0];
        knot_frame(&g1, a[1], 0.0);
    }
    gcpt raw = p;
    double twist = 0.0;
    if (t->view->gc_twist)
        twist = cbm__turtle_twist_angle(&g1, &raw);
    else
        cbm__turtle_adjust_frame(raw.h, g1.h, g1.u, 0.0, &raw.u, &raw.l);
    gcpt g2 = sp->win[2];
    g2.pos = v3_scale(v3_add(v3_add(P1, v3_scale(P2, 4.0)), P3), 1.0 / 6.0);
    knot_frame(&g2, v3_scale(v3_sub(P3, P1), 0.5), twist);
    sp->win[0] = sp->win[1];
    sp->win[1] = sp->win[2];
    sp->win[2] = p;
    sp->num++;
    /* cpfg: a band too short to draw leaves the control point itself as the next start */
    sp->tu = v3_norm(v3_sub(g2.pos, g1.pos)) < 0.00001 ? raw : g2;
    return cbm__turtle_gc_segment(t, &g1, &g2, rings, a, twist);
}

/* }(n), n != 0: the spline ends; a closed one is closed by feeding again its first control
 * points (1 for Hermite, 3 for B-spline, cyclically when it has fewer), as cpfg. */
cbm_status cbm__turtle_spline_close(cbm_turtle *t)
{
    tstate *s = &t->cur;
    if (s->spl < 0)
        return CBM_OK; /* cpfg: "Spline is already finished or hasn't been started", ignored */
    spline *sp = &t->splines.data[s->spl];
    if (sp->closed && sp->nfirst > 0) {
        int nfeed = sp->bspline ? 3 : 1, nfirst = sp->nfirst;
        gcpt first[3];
        memcpy(first, sp->first, sizeof first);
        for (int i = 0; i < nfeed; i++)
            CBM_TRY(cbm__turtle_spline_point(t, first[i % nfirst], 0));
    }
    if ((size_t)s->spl + 1 == t->splines.len && (size_t)s->spl >= spline_level(t))
        t->splines.len--;
    s->spl = -1;
    return CBM_OK;
}
