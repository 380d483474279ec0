/* Helpers shared by the mechanics tests: building rods and the independent reference solution
 * of the planar elastica (shooting with RK4 + bisection). Header-only, static functions. */
#ifndef CBM_MECH_TESTLIB_H
#define CBM_MECH_TESTLIB_H

#include "test.h"
#include "cambium/mech.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

/* A new plant without segments, clamped at `elev` rad above the horizontal; NULL (the test has
 * failed) when it cannot be made. */
static inline cbm_plant *clamped_plant(cbm_context *ctx, double elev)
{
    cbm_plant_def pd = cbm_plant_def_default();
    pd.base_orientation = cbm_mech_clamp_orientation(elev);
    cbm_plant *p = NULL;
    CHECK_OK(cbm_plant_create(ctx, &pd, &p));
    return p;
}

/* Appends n segments of *d to p, each the child of the segment added before it (the first, the
 * child of the plant's last segment: the root on an empty plant). */
static inline void add_axis(cbm_plant *p, cbm_segment_def *d, int n)
{
    for (int i = 0; i < n; i++) {
        d->parent = (int64_t)cbm_plant_segment_count(p) - 1;
        CHECK_OK(cbm_plant_add_segment(p, d, NULL));
    }
}

/* A straight rod of n equal segments clamped at `elev` rad above the horizontal, radius given by
 * radius(s) at each segment's centroid (taper), optional tip force/moment. */
typedef double (*radius_fn)(double s, double L);

static inline double radius_uniform(double s, double L)
{
    (void)s;
    (void)L;
    return 0.01;
}

static inline cbm_plant *make_rod(cbm_context *ctx, int n, double L, radius_fn rf, double E,
                                  double rho, double elev, cbm_mech_discretization disc)
{
    cbm_plant_def pd = cbm_plant_def_default();
    pd.base_orientation = cbm_mech_clamp_orientation(elev);
    pd.discretization = disc;
    cbm_plant *p = NULL;
    CHECK_OK(cbm_plant_create(ctx, &pd, &p));
    if (!p)
        return NULL;
    cbm_segment_def d = cbm_segment_def_default();
    d.length = L / n;
    d.core.youngs_modulus = E;
    d.core.shear_modulus = E / 2.6;
    d.core.density = rho;
    for (int i = 0; i < n; i++) {
        d.parent = i - 1;
        d.core.a = d.core.b = rf(((double)i + 0.5) * L / n, L);
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    return p;
}

static inline cbm_vec3 rod_tip(const cbm_plant *p)
{
    cbm_segment_state s;
    memset(&s, 0, sizeof s);
    CHECK_OK(cbm_plant_segment(p, cbm_plant_segment_count(p) - 1, &s));
    return s.distal;
}

/* Planar elastica, clamped at angle th0, uniform weight w per length (downward), tip load P
 * (downward), tip moment Mt (counter-clockwise), rigidity EI, length L:
 *   theta' = M / EI,  M' = (w (L - s) + P) cos(theta),  x' = cos theta,  y' = sin theta,
 * with M(L) = Mt. Shooting on M(0) by bisection, RK4 with `steps` steps. Returns the tip
 * position and angle. */
typedef struct elastica {
    double x, y, theta, m0;
} elastica;

static inline void el_rhs(double s, const double *u, double *du, double w, double P, double EI,
                          double L)
{
    du[0] = u[1] / EI;
    du[1] = (w * (L - s) + P) * cos(u[0]);
    du[2] = cos(u[0]);
    du[3] = sin(u[0]);
}

static inline elastica el_integrate(double m0, double th0, double w, double P, double EI, double L,
                                    int steps)
{
    double u[4] = {th0, m0, 0, 0}, k1[4], k2[4], k3[4], k4[4], t[4];
    double h = L / steps;
    for (int i = 0; i < steps; i++) {
        double s = i * h;
        el_rhs(s, u, k1, w, P, EI, L);
        for (int j = 0; j < 4; j++)
            t[j] = u[j] + 0.5 * h * k1[j];
        el_rhs(s + 0.5 * h, t, k2, w, P, EI, L);
        for (int j = 0; j < 4; j++)
            t[j] = u[j] + 0.5 * h * k2[j];
        el_rhs(s + 0.5 * h, t, k3, w, P, EI, L);
        for (int j = 0; j < 4; j++)
            t[j] = u[j] + h * k3[j];
        el_rhs(s + h, t, k4, w, P, EI, L);
        for (int j = 0; j < 4; j++)
            u[j] += h / 6.0 * (k1[j] + 2 * k2[j] + 2 * k3[j] + k4[j]);
    }
    elastica e = {u[2], u[3], u[0], u[1]};
    return e;
}

static inline elastica elastica_solve(double th0, double w, double P, double Mt, double EI,
                                      double L, int steps)
{
    /* M(L) - Mt is increasing in M(0); bracket by the rigid-rod moments */
    double span = w * L * L / 2 + P * L + fabs(Mt);
    double lo = -span - 1e-300, hi = span + 1e-300;
    for (int it = 0; it < 200 && hi - lo > 1e-15 * span; it++) {
        double mid = 0.5 * (lo + hi);
        elastica e = el_integrate(mid, th0, w, P, EI, L, steps);
        if (e.m0 - Mt > 0)
            hi = mid;
        else
            lo = mid;
    }
    elastica e = el_integrate(0.5 * (lo + hi), th0, w, P, EI, L, steps);
    e.m0 = 0.5 * (lo + hi);
    return e;
}

#endif
