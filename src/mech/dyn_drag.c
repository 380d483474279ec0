/* The drag of the wind on the moving plant (issue 11). On each segment, at its midpoint c,
 * F = 1/2 rho C_d (a + b) l |w_n| w_n with w = u(c, t) - v(c) the velocity of the air relative to
 * the segment and w_n its part normal to the axis (the cross-flow principle: the axial part
 * gives only skin friction); on the organs at the distal node e (leaves, fruit: the point
 * masses), 1/2 rho C_d,organ A |w| w with w = u(e, t) - v(e). Because the structure's velocity is
 * subtracted, the drag of a swaying branch in wind opposes its motion relative to the air: the
 * aerodynamic damping (rho C_d D U per length for small motions in a mean wind U) follows from
 * the same formula with no separate coefficient.
 *
 * Leaves and fruit apart (cbm_wind_def's leaf_area and fruit_mass): a fruit is a sphere, 1/2 rho
 * C_d pi r^2 |w| w; a leaf a flat plate across the flow that reconfigures (rolls into a cone,
 * streams with the wind) above U_0, its drag 1/2 rho C_d A |w| w (|w| / U_0)^B, B the Vogel
 * exponent (docs/dynamics.md, "Drag of leaves and fruit", with sources).
 *
 * With a gust field (cbm_gust_def.coherence_decay > 0) each drag point takes the field's value
 * interpolated from the grid (gust.c), the same for all the fixed-point iterations of a step.
 *
 * The motion is linear, so the geometry (c, e, the axes) is that of the equilibrium; v comes from
 * the joint rates by one forward sweep (the twists) and the forces go back to the joints by one
 * backward sweep of the wrenches: O(n) per evaluation. */
#include "mech/dyn_internal.h"
#include "core/vecmath.h"
#include "mech/mech_internal.h"

#include <math.h>
#include <string.h>

void cbm__drag_free(cbm_context *ctx, cbm__drag *g)
{
    if (!g || !ctx)
        return;
    size_t n = g->n;
    cbm__free(ctx, g->c, n * sizeof *g->c);
    cbm__free(ctx, g->h, n * sizeof *g->h);
    cbm__free(ctx, g->kw, n * sizeof(double));
    cbm__free(ctx, g->ko, n * sizeof(double));
    cbm__free(ctx, g->uc, n * sizeof(double));
    cbm__free(ctx, g->ue, n * sizeof(double));
    cbm__free(ctx, g->z, 6 * n * sizeof(double));
    cbm__free(ctx, g->w, 6 * n * sizeof(double));
    cbm__free(ctx, g->gi, 8 * n * sizeof(int32_t));
    cbm__free(ctx, g->gw, 8 * n * sizeof(double));
    cbm__free(ctx, g->leaf, n * sizeof(double));
    cbm__free(ctx, g->fruit, n * sizeof(double));
    cbm__gust_free(ctx, &g->gust);
    memset(g, 0, sizeof *g);
}

cbm_status cbm__drag_build(const cbm__dyn *d, const cbm_wind_def *wind, double u_ref,
                           const cbm_gust_def *gust, cbm__drag *g)
{
    memset(g, 0, sizeof *g);
    cbm_context *ctx = d->ctx;
    CBM_TRY(cbm__wind_check(ctx, wind));
    if (!isfinite(u_ref))
        return cbm__fail(ctx, CBM_E_INVALID, "wind: the speed %g m/s is not finite", u_ref);
    size_t n = d->n;
    g->n = n;
    g->c = cbm__alloc(ctx, n * sizeof *g->c);
    g->h = cbm__alloc(ctx, n * sizeof *g->h);
    g->kw = cbm__alloc(ctx, n * sizeof(double));
    g->ko = cbm__alloc(ctx, n * sizeof(double));
    g->uc = cbm__alloc(ctx, n * sizeof(double));
    g->ue = cbm__alloc(ctx, n * sizeof(double));
    g->z = cbm__alloc(ctx, 6 * n * sizeof(double));
    g->w = cbm__alloc(ctx, 6 * n * sizeof(double));
    if (!g->c || !g->h || !g->kw || !g->ko || !g->uc || !g->ue || !g->z || !g->w) {
        cbm__drag_free(ctx, g);
        return CBM_E_NOMEM;
    }
    cbm_status st = cbm__gust_build(ctx, gust, wind, u_ref, &g->gust);
    if (st != CBM_OK) {
        cbm__drag_free(ctx, g);
        return st;
    }
    g->dir = v3_normalize(wind->direction);
    g->u_ref = u_ref;
    double half_rho = 0.5 * wind->air_density;
    if (wind->leaf_area || wind->fruit_mass) {
        st = cbm__wind_organs(ctx, wind, n, &g->leaf, &g->fruit);
        if (st != CBM_OK) {
            cbm__drag_free(ctx, g);
            return st;
        }
        g->vogel = wind->leaf_vogel;
        g->vogel_speed = wind->leaf_vogel_speed;
    }
    for (size_t i = 0; i < n; i++) {
        cbm_vec3 ax = v3_sub(d->e[i], d->x[i]);
        double l = v3_norm(ax);
        g->h[i] = l > 0.0 ? v3_scale(ax, 1.0 / l) : v3(0, 0, 0);
        g->c[i] = v3_madd(d->x[i], ax, 0.5);
        g->kw[i] = half_rho * wind->drag_wood * d->width[i] * l;
        g->ko[i] = half_rho * wind->drag_organs * wind->organ_area_per_kg * d->pmass[i];
        /* heights above the base: positions are relative to it, y up */
        g->uc[i] = cbm_wind_speed(wind, 1.0, g->c[i].y);
        g->ue[i] = cbm_wind_speed(wind, 1.0, d->e[i].y);
    }
    if (g->gust.n > 0 && gust && gust->coherence_decay > 0.0) {
        cbm_vec3 *pts = cbm__alloc(ctx, 2 * n * sizeof *pts);
        g->gi = cbm__alloc(ctx, 8 * n * sizeof(int32_t));
        g->gw = cbm__alloc(ctx, 8 * n * sizeof(double));
        st = pts && g->gi && g->gw ? CBM_OK : CBM_E_NOMEM;
        if (st == CBM_OK) {
            memcpy(pts, g->c, n * sizeof *pts);
            memcpy(pts + n, d->e, n * sizeof *pts);
            st = cbm__gust_field_build(ctx, gust, u_ref, g->dir, pts, 2 * n, &g->gust);
        }
        cbm__free(ctx, pts, 2 * n * sizeof *pts);
        if (st != CBM_OK) {
            cbm__drag_free(ctx, g);
            return st;
        }
        for (size_t i = 0; i < n; i++) {
            cbm__gust_field_weights(&g->gust, g->c[i], g->gi + 8 * i, g->gw + 8 * i);
            cbm__gust_field_weights(&g->gust, d->e[i], g->gi + 8 * i + 4, g->gw + 8 * i + 4);
        }
    }
    return CBM_OK;
}

/* the gust field's value at the 4 grid points idx with weights wt */
static inline double field_value(const double *gv, const int32_t *idx, const double *wt)
{
    return wt[0] * gv[idx[0]] + wt[1] * gv[idx[1]] + wt[2] * gv[idx[2]] + wt[3] * gv[idx[3]];
}

/* The drag wrenches of segment i (moment about the origin, force; 6 each) for the air speeds
 * ut at its midpoint and ute at its distal node, its twist z and the base velocity vb: wood's at
 * the midpoint into ww, the organs' at the distal node into wo; false (wo untouched) when the
 * segment carries no organ drag. */
static inline bool seg_wrenches(const cbm__drag *g, const cbm__dyn *d, size_t i, double ut,
                                double ute, const double *z, cbm_vec3 vb, double *ww, double *wo)
{
    cbm_vec3 om = v3(z[0], z[1], z[2]), v0 = v3_add(v3(z[3], z[4], z[5]), vb);
    cbm_vec3 c = g->c[i], h = g->h[i];
    cbm_vec3 rel = v3_sub(v3_scale(g->dir, ut * g->uc[i]), v3_add(v0, v3_cross(om, c)));
    cbm_vec3 rn = v3_madd(rel, h, -v3_dot(rel, h));
    cbm_vec3 F = v3_scale(rn, g->kw[i] * v3_norm(rn));
    cbm_vec3 M = v3_cross(c, F);
    ww[0] = M.x, ww[1] = M.y, ww[2] = M.z, ww[3] = F.x, ww[4] = F.y, ww[5] = F.z;
    double kf = g->fruit ? g->fruit[i] : 0.0, kl = g->leaf ? g->leaf[i] : 0.0;
    if (!(g->ko[i] > 0.0 || kf > 0.0 || kl > 0.0))
        return false;
    cbm_vec3 e = d->e[i];
    cbm_vec3 ro = v3_sub(v3_scale(g->dir, ute * g->ue[i]), v3_add(v0, v3_cross(om, e)));
    double wn = v3_norm(ro);
    double k = g->ko[i] + kf + kl * cbm__leaf_reconfiguration(g->vogel, g->vogel_speed, wn);
    cbm_vec3 Fo = v3_scale(ro, k * wn);
    cbm_vec3 Mo = v3_cross(e, Fo);
    wo[0] = Mo.x, wo[1] = Mo.y, wo[2] = Mo.z, wo[3] = Fo.x, wo[4] = Fo.y, wo[5] = Fo.z;
    return true;
}

void cbm__drag_force(cbm__drag *g, const cbm__dyn *d, double t, const double *v, cbm_vec3 vb,
                     double *f)
{
    size_t n = g->n;
    const double *gv = g->gust.n > 0 && g->gust.np > 0 ? cbm__gust_field_at(&g->gust, t) : NULL;
    double ut = g->u_ref + (g->gust.n > 0 && !gv ? cbm__gust_at(&g->gust, t) : 0.0), ute = ut;
    cbm__dyn_twists(d, v, g->z);
    for (size_t i = 0; i < n; i++) {
        if (gv) {
            ut = g->u_ref + field_value(gv, g->gi + 8 * i, g->gw + 8 * i);
            ute = g->u_ref + field_value(gv, g->gi + 8 * i + 4, g->gw + 8 * i + 4);
        }
        double *w = g->w + 6 * i, wo[6];
        if (seg_wrenches(g, d, i, ut, ute, g->z + 6 * i, vb, w, wo))
            for (int j = 0; j < 6; j++)
                w[j] += wo[j];
    }
    memset(f, 0, 3 * n * sizeof(double));
    cbm__dyn_wrench_force(d, g->w, f);
}

void cbm__drag_wrenches(cbm__drag *g, const cbm__dyn *d, const double *v, cbm_vec3 vb, double *ww,
                        double *wo)
{
    cbm__dyn_twists(d, v, g->z);
    for (size_t i = 0; i < g->n; i++)
        if (!seg_wrenches(g, d, i, g->u_ref, g->u_ref, g->z + 6 * i, vb, ww + 6 * i, wo + 6 * i))
            memset(wo + 6 * i, 0, 6 * sizeof(double));
}
