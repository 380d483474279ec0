/* The drag of the wind on the moving plant (issue 11). On each segment, at its midpoint c,
 * F = 1/2 rho C_d (a + b) l |w_n| w_n with w = u(c, t) - v(c) the velocity of the air relative to
 * the segment and w_n its part normal to the axis (the cross-flow principle: the axial part
 * gives only skin friction); on the organs at the distal node e (leaves, fruit: the point
 * masses), 1/2 rho C_d,organ A |w| w with w = u(e, t) - v(e). Because the structure's velocity is
 * subtracted, the drag of a swaying branch in wind opposes its motion relative to the air: the
 * aerodynamic damping (rho C_d D U per length for small motions in a mean wind U) follows from
 * the same formula with no separate coefficient.
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
    return CBM_OK;
}

void cbm__drag_force(cbm__drag *g, const cbm__dyn *d, double t, const double *v, cbm_vec3 vb,
                     double *f)
{
    size_t n = g->n;
    double ut = g->u_ref + (g->gust.n > 0 ? cbm__gust_at(&g->gust, t) : 0.0);
    cbm__dyn_twists(d, v, g->z);
    for (size_t i = 0; i < n; i++) {
        const double *z = g->z + 6 * i;
        cbm_vec3 om = v3(z[0], z[1], z[2]), v0 = v3_add(v3(z[3], z[4], z[5]), vb);
        double *w = g->w + 6 * i;
        cbm_vec3 c = g->c[i], h = g->h[i];
        cbm_vec3 rel = v3_sub(v3_scale(g->dir, ut * g->uc[i]), v3_add(v0, v3_cross(om, c)));
        cbm_vec3 rn = v3_madd(rel, h, -v3_dot(rel, h));
        cbm_vec3 F = v3_scale(rn, g->kw[i] * v3_norm(rn));
        cbm_vec3 M = v3_cross(c, F);
        if (g->ko[i] > 0.0) {
            cbm_vec3 e = d->e[i];
            cbm_vec3 ro = v3_sub(v3_scale(g->dir, ut * g->ue[i]), v3_add(v0, v3_cross(om, e)));
            cbm_vec3 Fo = v3_scale(ro, g->ko[i] * v3_norm(ro));
            F = v3_add(F, Fo);
            M = v3_add(M, v3_cross(e, Fo));
        }
        w[0] = M.x;
        w[1] = M.y;
        w[2] = M.z;
        w[3] = F.x;
        w[4] = F.y;
        w[5] = F.z;
    }
    memset(f, 0, 3 * n * sizeof(double));
    cbm__dyn_wrench_force(d, g->w, f);
}
