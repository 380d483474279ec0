/* The spring pass of the built-in tree models: the fate of every bud by acropetal resource
 * allocation (Taylor-Hell 2005 §4.3, eqs. 4.8-4.19; relay bias eq. 7.1; Borchert-Honda).
 *
 * One pass over the segments in index order (parents before children). The base receives
 * V = (K a_base)^d (4.12). At every node the vigour V of the parent is split between its lateral
 * child l and its continuation c (the children that take resources: aborted buds take none):
 *   g = A_l^(P/2) / (A_l^(P/2) + A_c^(P/2))          girth share by the pipe model (4.9-4.11,
 *                                                     area form 8.17)
 *   p = g f(h_l) [Phi_l]                              acrotony (4.13) and, with relay_bias, the
 *                                                     height/orientation bias of eq. 7.1
 *   p' = fairness(p, F), V_l = p' V, V_c = V - V_l    (4.18-4.19 as coded; 4.14)
 * so V_l + V_c = V exactly before sinks. A lateral bud still undecided shoots if V_l exceeds
 * shoot_vigour; it then makes n = max(1, int(f(V_l) max_buds)) nodes (4.15) and becomes a sink:
 * the continuation loses min(V_c, zeta n V_l) (4.16). A bud that does not shoot stays dormant
 * for `dormancy` years (decided again each spring), then aborts; either way its share returns to
 * the continuation (it takes no resources, the listing's takesVigour). A
 * terminal bud is decided on the vigour its shoot passes on to it. This single simultaneous
 * split is the physically consistent form; the listing's spring pass (listing_vigour) instead
 * gives every bud of a shoot the shoot's vigour times f(h) (the girth ratio is 1 there, digest
 * erratum 5) without reducing the continuation except by sinks.
 *
 * Phi (7.1) = ((y_bud - y_0) / (y_max - y_0)) (H_bud . up), clamped to >= 0, where y_0 is the
 * height of the start of the parent axis (a chain of continuations from a lateral or the base)
 * and y_max the highest point along it (a forward max then a backward broadcast, as A.2 does).
 * It favours upward buds high on a bent parent: relay shoots.
 */
#include "tree/tree_internal.h"
#include "core/vecmath.h"

#include <math.h>

double cbm_tree_fairness(double p, double f)
{
    if (p > 0.5)
        p = 1.0 - f * (1.0 - p);
    else if (p < 0.5)
        p = f * p;
    return p < 0.0 ? 0.0 : (p > 1.0 ? 1.0 : p);
}

static cbm_vec3 distal(const tree_plant *p, size_t i)
{
    return v3_madd(p->pos[i], q_rotate(p->q[i], v3(1, 0, 0)), p->len[i]);
}

static int buds_for(const cbm_tree *t, double v)
{
    double f = cbm_tree_func_eval(&t->def.numbuds_vigour, v) * (double)t->def.max_buds;
    int n = f < 1.0 ? 1 : (f > 1e6 ? 1000000 : (int)f);
    return n;
}

/* Decides an undecided bud on segment j with vigour v; returns the sink it makes. */
static double decide(cbm_tree *t, size_t j, double v, bool relay)
{
    tree_seg *s = &t->seg.data[j];
    s->flags &= (uint8_t)~SEG_BUD;
    if (v > t->def.shoot_vigour) {
        int n = buds_for(t, v);
        s->flags |= SEG_APEX;
        s->count = 0;
        s->nodes = n;
        t->cur.shoots++;
        t->cur.relay_shoots += relay;
        return t->def.sink * (double)n * v;
    }
    /* a bud that does not shoot waits as a dormant bud (a spur) for `dormancy` years, decided
     * again each spring (it takes no resources: its share returns to the axis); then it aborts */
    if (t->year - s->bud_year <= t->def.dormancy) {
        s->flags |= SEG_BUD;
        return -1.0;
    }
    s->flags |= SEG_ABORTED;
    s->nleaf = 0;
    return -1.0;
}

cbm_status cbm__tree_spring(cbm_tree *t)
{
    const tree_plant view = tree_plant_of(t->plant), *p = &view;
    size_t n = p->n;
    if (n == 0)
        return CBM_OK;
    const cbm_tree_def *d = &t->def;
    size_t *lat = cbm__alloc(t->ctx, n * sizeof *lat);
    size_t *cont = cbm__alloc(t->ctx, n * sizeof *cont);
    double *y0 = cbm__alloc(t->ctx, n * sizeof *y0);
    double *ym = cbm__alloc(t->ctx, n * sizeof *ym);
    uint8_t *live = cbm__alloc(t->ctx, n);
    if (!lat || !cont || !y0 || !ym || !live) {
        cbm__free(t->ctx, live, n);
        cbm__free(t->ctx, lat, n * sizeof *lat);
        cbm__free(t->ctx, cont, n * sizeof *cont);
        cbm__free(t->ctx, y0, n * sizeof *y0);
        cbm__free(t->ctx, ym, n * sizeof *ym);
        return CBM_E_NOMEM;
    }
    tree_seg *sg = t->seg.data;
    for (size_t i = 0; i < n; i++)
        lat[i] = cont[i] = SIZE_MAX;
    for (size_t j = 0; j < n; j++) {
        int64_t pa = p->parent[j];
        bool lateral = pa < 0 || (sg[j].flags & SEG_LATERAL);
        if (pa >= 0) {
            if (lateral)
                lat[pa] = j;
            else
                cont[pa] = j;
        }
        /* axis start height and forward max of the distal heights along the axis */
        double yd = distal(p, j).y;
        y0[j] = lateral ? p->pos[j].y : y0[pa];
        ym[j] = lateral ? yd : (ym[pa] > yd ? ym[pa] : yd);
    }
    for (size_t j = n; j-- > 0;)
        if (cont[j] != SIZE_MAX)
            ym[j] = ym[cont[j]];
    /* live[j]: the subtree of j holds a bud that can shoot (undecided or dormant, above the
     * ground). With bud_routing a child whose subtree has none takes no resources, as an
     * aborted bud: vigour is not poured into dead branches or tips lying on the ground */
    for (size_t j = n; j-- > 0;) {
        if (!d->bud_routing) {
            live[j] = !(sg[j].flags & SEG_ABORTED);
            continue;
        }
        live[j] = (sg[j].flags & (SEG_BUD | SEG_APEX)) && distal(p, j).y >= d->bud_length;
        if (lat[j] != SIZE_MAX && live[lat[j]])
            live[j] = 1;
        if (cont[j] != SIZE_MAX && live[cont[j]])
            live[j] = 1;
    }
    const double hp = 0.5 * d->pipe_exponent;
    {
        double a0 = p->outer[0].a;
        sg[0].vigour = pow(d->vigour_k * a0, d->vigour_d);
        sg[0].sink = 0.0;
        sg[0].share = 0.0;
    }
    const cbm_vec3 up = v3(0, 1, 0);
    for (size_t i = 0; i < n; i++) {
        double v = sg[i].vigour;
        sg[i].sink = 0.0;
        sg[i].share = 0.0;
        size_t l = lat[i], c = cont[i];
        bool tl = l != SIZE_MAX && live[l];
        bool tc = c != SIZE_MAX && live[c];
        double vl = 0.0, vc = 0.0;
        if (tl && tc) {
            double f = cbm_tree_func_eval(&d->vigour_height, sg[l].h);
            double g = 1.0;
            if (!(d->listing_vigour && (sg[l].flags & SEG_BUD))) {
                double al = pow(p->area[l], hp), ac = pow(p->area[c], hp);
                g = al + ac > 0.0 ? al / (al + ac) : 0.5;
            }
            double pr = g * f;
            if (d->relay_bias) {
                double phi = 0.0;
                if (ym[i] > y0[i]) {
                    double hb = (distal(p, l).y - y0[i]) / (ym[i] - y0[i]);
                    double o = v3_dot(q_rotate(p->q[l], v3(1, 0, 0)), up);
                    phi = (hb > 0.0 ? (hb > 1.0 ? 1.0 : hb) : 0.0) * (o > 0.0 ? o : 0.0);
                }
                pr *= phi;
            }
            double sh = cbm_tree_fairness(pr, d->fairness);
            vl = sh * v;
            vc = d->listing_vigour && (sg[l].flags & SEG_BUD) ? v : v - vl;
            sg[i].share = sh;
        } else if (tl) {
            vl = v;
            sg[i].share = 1.0;
        } else if (tc) {
            vc = v;
        }
        if (tl && (sg[l].flags & SEG_BUD)) {
            bool relay = v3_dot(q_rotate(p->q[i], v3(1, 0, 0)), up) < 0.0;
            double sink = decide(t, l, vl, relay);
            if (sink < 0.0) {
                if (!d->listing_vigour)
                    vc += vl; /* the aborted bud's share stays on the axis */
                vl = 0.0;
                sg[i].share = 0.0;
            } else if (tc) {
                sink = sink < vc ? sink : vc;
                vc -= sink;
                sg[i].sink = sink;
            }
        }
        if (l != SIZE_MAX)
            sg[l].vigour = vl;
        if (c != SIZE_MAX) {
            sg[c].vigour = vc;
            if (tc && (sg[c].flags & SEG_BUD)) /* terminal bud */
                (void)decide(t, c, vc, v3_dot(q_rotate(p->q[i], v3(1, 0, 0)), up) < 0.0);
        }
    }
    cbm__free(t->ctx, lat, n * sizeof *lat);
    cbm__free(t->ctx, cont, n * sizeof *cont);
    cbm__free(t->ctx, y0, n * sizeof *y0);
    cbm__free(t->ctx, ym, n * sizeof *ym);
    cbm__free(t->ctx, live, n);
    return CBM_OK;
}
