/* The S-curve of a rod (Tresierras 2009, §4.3): the map theta_tip -> (theta_base, base
 * curvature, energy) traced by backward shooting, its folds (jumping points, (4.10)), the
 * equilibria at a given base angle, the jump targets and a quasi-static base-angle sweep.
 *
 * Every equilibrium of the rod has exactly one tip angle modulo 2 pi (the backward initial value
 * problem from the free tip is unique), so one period of theta_tip traces all of them and the
 * equilibria at a base angle are the roots of theta_base(theta_tip) = theta_b + 2 pi k.
 *
 * Step control (the "adaptive theta_tip step" of ch. 6): the Jacobi field gives the exact
 * derivatives d theta_base / d theta_tip and d m_base / d theta_tip at every point, so the step
 * is ds / |d(theta_base, L m_base / D(0)) / d theta_tip|, bounded, and a step whose chord is over
 * twice ds is halved. Near a fold theta_base barely moves while the curvature does, so the curve
 * is sampled evenly in arc length rather than in theta_tip.
 *
 * Stability: each point carries the Morse index of the second variation (the Sturm count of the
 * Jacobi field, rod.c) and the sign of d theta_base / d theta_tip, the fold structure: the index
 * changes by one at each fold, so its parity is that sign ((-1)^index = sign eta(0), a stable
 * point has a positive slope). The tests check the two against each other.
 */
#include "elastica_internal.h"

#include <math.h>
#include <stdlib.h>

cbm_elastica_scan_def cbm_elastica_scan_def_default(void)
{
    cbm_elastica_scan_def d;
    d.theta_tip_min = -0.5 * CBM_PI;
    d.theta_tip_max = 1.5 * CBM_PI;
    d.ds = 0.02;
    d.max_step = 2.0 * CBM_PI / 180.0;
    d.min_step = 1e-7;
    d.max_points = 0;
    return d;
}

static cbm_status shoot(cbm_context *ctx, const cbm_elastica_rod *rod, double t,
                        cbm_elastica_state *st)
{
    double y[EL_N];
    int z = 0;
    cbm_status s = cbm__el_integrate(rod, t, 0.0, y, &z, NULL, NULL, 0);
    if (s != CBM_OK)
        return cbm__fail(ctx, s, "elastica: integration failed at theta_tip = %.9g deg",
                         t * 180.0 / CBM_PI);
    cbm__el_state(rod, t, y, z, st);
    return CBM_OK;
}

/* arc-length speed of the curve in (theta_base, L m / D0) per unit theta_tip */
static double speed(const cbm_elastica_state *s, double L, double D0)
{
    double a = s->dbase_dtip, b = s->dmoment_dtip * L / D0;
    return sqrt(a * a + b * b);
}

static double chord(const cbm_elastica_state *a, const cbm_elastica_state *b, double L, double D0)
{
    double p = b->theta_base - a->theta_base, q = (b->moment_base - a->moment_base) * L / D0;
    return sqrt(p * p + q * q);
}

/* Root of eta(0) (a fold) between a and b (eta of opposite signs): Illinois false position. */
static cbm_status refine_fold(cbm_context *ctx, const cbm_elastica_rod *rod,
                              const cbm_elastica_state *a, const cbm_elastica_state *b,
                              cbm_elastica_state *out)
{
    double ta = a->theta_tip, tb = b->theta_tip, fa = a->dbase_dtip, fb = b->dbase_dtip;
    cbm_elastica_state st = *a;
    int side = 0;
    for (int it = 0; it < 200; it++) {
        double t = (fa * tb - fb * ta) / (fa - fb);
        if (!(t > fmin(ta, tb) && t < fmax(ta, tb)))
            t = 0.5 * (ta + tb);
        cbm_status s = shoot(ctx, rod, t, &st);
        if (s != CBM_OK)
            return s;
        double f = st.dbase_dtip;
        if (fabs(f) < 1e-12 || fabs(tb - ta) < 1e-14)
            break;
        if ((f > 0) == (fa > 0)) {
            ta = t, fa = f;
            if (side == -1)
                fb *= 0.5;
            side = -1;
        } else {
            tb = t, fb = f;
            if (side == 1)
                fa *= 0.5;
            side = 1;
        }
    }
    *out = st;
    return CBM_OK;
}

/* Root of theta_base(t) = target between a and b (bracketing): Newton with the exact slope,
 * falling back on bisection when a step leaves the bracket. */
static cbm_status refine_root(cbm_context *ctx, const cbm_elastica_rod *rod,
                              const cbm_elastica_state *a, const cbm_elastica_state *b,
                              double target, cbm_elastica_state *out)
{
    double ta = a->theta_tip, tb = b->theta_tip;
    double fa = a->theta_base - target;
    if (fa == 0) {
        *out = *a;
        return CBM_OK;
    }
    if (b->theta_base - target == 0) {
        *out = *b;
        return CBM_OK;
    }
    cbm_elastica_state st = fabs(fa) < fabs(b->theta_base - target) ? *a : *b;
    double t = st.theta_tip;
    for (int it = 0; it < 200; it++) {
        double f = st.theta_base - target;
        if (fabs(f) < 1e-13)
            break;
        double tn = st.dbase_dtip != 0 ? t - f / st.dbase_dtip : NAN;
        if (!(tn > fmin(ta, tb) && tn < fmax(ta, tb)) || it > 60)
            tn = 0.5 * (ta + tb);
        cbm_status s = shoot(ctx, rod, tn, &st);
        if (s != CBM_OK)
            return s;
        t = tn;
        double fn = st.theta_base - target;
        if ((fn > 0) == (fa > 0))
            ta = t, fa = fn;
        else
            tb = t;
        if (fabs(tb - ta) < 1e-15)
            break;
    }
    *out = st;
    return CBM_OK;
}

static int cmp_state_tip(const void *a, const void *b)
{
    double x = ((const cbm_elastica_state *)a)->theta_tip;
    double y = ((const cbm_elastica_state *)b)->theta_tip;
    return (x > y) - (x < y);
}

/* All roots, growing a context-allocated array. */
static cbm_status find_equilibria(cbm_context *ctx, const cbm_elastica_rod *rod,
                                  const cbm_elastica_scurve *sc, double theta_b,
                                  cbm_elastica_state **out, size_t *n, size_t *cap)
{
    const double tp = 2.0 * CBM_PI;
    *n = 0;
    for (size_t i = 0; i + 1 < sc->n_points; i++) {
        const cbm_elastica_state *a = &sc->points[i], *b = &sc->points[i + 1];
        double lo = fmin(a->theta_base, b->theta_base), hi = fmax(a->theta_base, b->theta_base);
        double k0 = ceil((lo - theta_b) / tp), k1 = floor((hi - theta_b) / tp);
        /* an integer counter: k0 and k1 are whole numbers of turns */
        for (long m = 0; m <= (long)(k1 - k0); m++) {
            const double k = k0 + (double)m;
            double target = theta_b + k * tp;
            /* a root exactly at the right end is found with the next interval */
            if (target == b->theta_base && i + 2 < sc->n_points)
                continue;
            cbm_elastica_state r = {0};
            cbm_status s = refine_root(ctx, rod, a, b, target, &r);
            if (s != CBM_OK)
                return s;
            if (k != 0) { /* the same configuration turned by whole turns */
                s = shoot(ctx, rod, r.theta_tip - k * tp, &r);
                if (s != CBM_OK)
                    return s;
            }
            bool dup = false;
            for (size_t j = 0; j < *n; j++)
                if (fabs((*out)[j].theta_tip - r.theta_tip) < 1e-7)
                    dup = true;
            if (dup)
                continue;
            if (*n == *cap) {
                size_t nc = *cap ? 2 * *cap : 8;
                cbm_elastica_state *p =
                    cbm__realloc(ctx, *out, *cap * sizeof **out, nc * sizeof **out);
                if (!p)
                    return CBM_E_NOMEM;
                *out = p, *cap = nc;
            }
            (*out)[(*n)++] = r;
        }
    }
    if (*n > 1)
        qsort(*out, *n, sizeof **out, cmp_state_tip);
    return CBM_OK;
}

cbm_status cbm_elastica_equilibria(cbm_context *ctx, const cbm_elastica_rod *rod,
                                   const cbm_elastica_scurve *sc, double theta_base,
                                   cbm_elastica_state *out, size_t max, size_t *n)
{
    if (!ctx || !sc || !n || (max && !out) || !isfinite(theta_base))
        return CBM_E_INVALID;
    cbm_status s = cbm__el_check(ctx, rod);
    if (s != CBM_OK)
        return s;
    cbm_elastica_state *all = NULL;
    size_t na = 0, cap = 0;
    s = find_equilibria(ctx, rod, sc, theta_base, &all, &na, &cap);
    if (s == CBM_OK) {
        for (size_t i = 0; i < na && i < max; i++)
            out[i] = all[i];
        *n = na;
    }
    cbm__free(ctx, all, cap * sizeof *all);
    return s;
}

/* The lowest-energy equilibrium at the fold's base angle other than the fold itself. */
static cbm_status jump_target(cbm_context *ctx, const cbm_elastica_rod *rod,
                              const cbm_elastica_scurve *sc, const cbm_elastica_state *fold,
                              bool *has, cbm_elastica_state *target)
{
    cbm_elastica_state *all = NULL;
    size_t na = 0, cap = 0;
    *has = false;
    cbm_status s = find_equilibria(ctx, rod, sc, fold->theta_base, &all, &na, &cap);
    const double tp = 2.0 * CBM_PI;
    for (size_t i = 0; s == CBM_OK && i < na; i++) {
        double d = remainder(all[i].theta_tip - fold->theta_tip, tp);
        if (fabs(d) < 1e-4) /* the fold (a double root) or its neighbour */
            continue;
        if (!*has || all[i].energy < target->energy) {
            *target = all[i];
            *has = true;
        }
    }
    cbm__free(ctx, all, cap * sizeof *all);
    return s;
}

void cbm_elastica_scurve_destroy(cbm_context *ctx, cbm_elastica_scurve *sc)
{
    if (!sc)
        return;
    cbm__free(ctx, sc->points, sc->n_points * sizeof *sc->points);
    cbm__free(ctx, sc->folds, sc->n_folds * sizeof *sc->folds);
    cbm__free(ctx, sc, sizeof *sc);
}

cbm_status cbm_elastica_scurve_compute(cbm_context *ctx, const cbm_elastica_rod *rod,
                                       const cbm_elastica_scan_def *def, cbm_elastica_scurve **out)
{
    if (!ctx || !out)
        return CBM_E_INVALID;
    *out = NULL;
    cbm_status s = cbm__el_check(ctx, rod);
    if (s != CBM_OK)
        return s;
    cbm_elastica_scan_def d = def ? *def : cbm_elastica_scan_def_default();
    if (!(d.theta_tip_max > d.theta_tip_min) || !isfinite(d.theta_tip_min) ||
        !isfinite(d.theta_tip_max) || !(d.ds > 0) || !(d.max_step > 0) || !(d.min_step > 0) ||
        d.min_step > d.max_step)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "elastica: the scan needs theta_tip_min < theta_tip_max and positive "
                         "steps");
    size_t maxp = d.max_points ? d.max_points : 200000;
    double L = cbm__el_length(rod), D0 = rod->pieces[0].D0;

    cbm_elastica_scurve *sc = cbm__alloc(ctx, sizeof *sc);
    if (!sc)
        return CBM_E_NOMEM;
    memset(sc, 0, sizeof *sc);
    sc->length = L;
    sc->stiffness_base = D0;
    size_t cap = 0, fcap = 0;
    cbm_elastica_state cur = {0};
    s = shoot(ctx, rod, d.theta_tip_min, &cur);
    while (s == CBM_OK) {
        if (sc->n_points == cap) {
            size_t nc = cap ? 2 * cap : 256;
            if (nc > maxp)
                nc = maxp;
            if (nc == cap) {
                s = cbm__fail(ctx, CBM_E_LIMIT, "elastica: the S-curve needs more than %zu points",
                              maxp);
                break;
            }
            cbm_elastica_state *p = cbm__realloc(ctx, sc->points, cap * sizeof *p, nc * sizeof *p);
            if (!p) {
                s = CBM_E_NOMEM;
                break;
            }
            sc->points = p, cap = nc;
        }
        sc->points[sc->n_points++] = cur;
        if (cur.theta_tip >= d.theta_tip_max)
            break;
        double v = speed(&cur, L, D0);
        double h = v > 0 ? d.ds / v : d.max_step;
        h = h > d.max_step ? d.max_step : h < d.min_step ? d.min_step : h;
        cbm_elastica_state next = {0};
        while (true) {
            double t = cur.theta_tip + h;
            if (t > d.theta_tip_max || d.theta_tip_max - t < 1e-3 * h)
                t = d.theta_tip_max;
            s = shoot(ctx, rod, t, &next);
            if (s != CBM_OK || chord(&cur, &next, L, D0) <= 2 * d.ds || h <= d.min_step)
                break;
            h *= 0.5;
        }
        cur = next;
    }
    size_t npts_alloc = cap;
    /* folds */
    for (size_t i = 0; s == CBM_OK && i + 1 < sc->n_points; i++) {
        const cbm_elastica_state *a = &sc->points[i], *b = &sc->points[i + 1];
        if ((a->dbase_dtip > 0) == (b->dbase_dtip > 0) || a->dbase_dtip == 0)
            continue;
        cbm_elastica_fold f;
        memset(&f, 0, sizeof f);
        s = refine_fold(ctx, rod, a, b, &f.at);
        if (s != CBM_OK)
            break;
        if (sc->n_folds == fcap) {
            size_t nc = fcap ? 2 * fcap : 8;
            cbm_elastica_fold *p = cbm__realloc(ctx, sc->folds, fcap * sizeof *p, nc * sizeof *p);
            if (!p) {
                s = CBM_E_NOMEM;
                break;
            }
            sc->folds = p, fcap = nc;
        }
        sc->folds[sc->n_folds++] = f;
    }
    /* jump targets need the whole curve */
    for (size_t k = 0; s == CBM_OK && k < sc->n_folds; k++)
        s = jump_target(ctx, rod, sc, &sc->folds[k].at, &sc->folds[k].has_target,
                        &sc->folds[k].target);
    /* exact-size blocks, so that the destroyer frees what it was given */
    if (s == CBM_OK && (npts_alloc != sc->n_points || fcap != sc->n_folds)) {
        cbm_elastica_state *p = cbm__alloc(ctx, sc->n_points * sizeof *p);
        cbm_elastica_fold *f = sc->n_folds ? cbm__alloc(ctx, sc->n_folds * sizeof *f) : NULL;
        if (!p || (sc->n_folds && !f)) {
            cbm__free(ctx, p, sc->n_points * sizeof *p);
            cbm__free(ctx, f, sc->n_folds * sizeof *f);
            s = CBM_E_NOMEM;
        } else {
            memcpy(p, sc->points, sc->n_points * sizeof *p);
            if (sc->n_folds)
                memcpy(f, sc->folds, sc->n_folds * sizeof *f);
            cbm__free(ctx, sc->points, npts_alloc * sizeof *p);
            cbm__free(ctx, sc->folds, fcap * sizeof *f);
            sc->points = p, sc->folds = f;
            npts_alloc = sc->n_points, fcap = sc->n_folds;
        }
    }
    if (s != CBM_OK) {
        sc->n_points = npts_alloc, sc->n_folds = fcap;
        cbm_elastica_scurve_destroy(ctx, sc);
        return s;
    }
    *out = sc;
    return CBM_OK;
}

cbm_status cbm_elastica_sweep(cbm_context *ctx, const cbm_elastica_rod *rod,
                              const cbm_elastica_scurve *sc, double from, double to,
                              cbm_elastica_state *path, size_t max_path, size_t *n_path,
                              cbm_elastica_jump *jumps, size_t max_jumps, size_t *n_jumps)
{
    if (!ctx || !sc || !n_path || !n_jumps || (max_path && !path) || (max_jumps && !jumps) ||
        !isfinite(from) || !isfinite(to))
        return CBM_E_INVALID;
    cbm_status s = cbm__el_check(ctx, rod);
    if (s != CBM_OK)
        return s;
    *n_path = *n_jumps = 0;
    double L = sc->length, D0 = sc->stiffness_base, ds = 0.02, hmax = 2.0 * CBM_PI / 180;
    cbm_elastica_state *eq = NULL;
    size_t ne = 0, cap = 0;
    s = find_equilibria(ctx, rod, sc, from, &eq, &ne, &cap);
    if (s == CBM_OK && (ne == 0 || !eq))
        s = cbm__fail(ctx, CBM_E_NOT_FOUND, "elastica: no equilibrium at the sweep's start");
    cbm_elastica_state cur = {0};
    if (s == CBM_OK && eq) {
        cur = eq[0];
        for (size_t i = 1; i < ne; i++)
            if (eq[i].energy < cur.energy)
                cur = eq[i];
    }
    double dir = to >= from ? 1.0 : -1.0;
#define PUSH(st)                                                                                   \
    do {                                                                                           \
        if (*n_path < max_path)                                                                    \
            path[*n_path] = (st);                                                                  \
        ++*n_path;                                                                                 \
    } while (0)
    if (s == CBM_OK)
        PUSH(cur);
    for (long iter = 0; s == CBM_OK && iter < 2000000; iter++) {
        if (dir * (cur.theta_base - to) >= 0)
            break;
        double v = speed(&cur, L, D0);
        double h = v > 0 ? ds / v : hmax;
        h = h > hmax ? hmax : h < 1e-7 ? 1e-7 : h;
        double sgn = dir * (cur.dbase_dtip >= 0 ? 1.0 : -1.0);
        cbm_elastica_state next = {0};
        s = shoot(ctx, rod, cur.theta_tip + sgn * h, &next);
        if (s != CBM_OK)
            break;
        if ((next.dbase_dtip > 0) != (cur.dbase_dtip > 0) && cur.dbase_dtip != 0) {
            cbm_elastica_jump j;
            s = refine_fold(ctx, rod, &cur, &next, &j.from);
            if (s != CBM_OK)
                break;
            if (dir * (j.from.theta_base - to) >= 0) { /* the end comes before the fold */
                s = refine_root(ctx, rod, &cur, &j.from, to, &next);
                if (s == CBM_OK)
                    PUSH(next);
                break;
            }
            PUSH(j.from);
            bool has = false;
            s = jump_target(ctx, rod, sc, &j.from, &has, &j.to);
            if (s != CBM_OK)
                break;
            if (!has) {
                s = cbm__fail(ctx, CBM_E_NOT_FOUND,
                              "elastica: no equilibrium to jump to from the fold at %.6g deg",
                              j.from.theta_base * 180 / CBM_PI);
                break;
            }
            /* the same base angle, not a whole turn away: shift the target's tip angle */
            double k = round((j.to.theta_base - j.from.theta_base) / (2 * CBM_PI));
            if (k != 0) {
                s = shoot(ctx, rod, j.to.theta_tip - k * 2 * CBM_PI, &j.to);
                if (s != CBM_OK)
                    break;
            }
            if (*n_jumps < max_jumps)
                jumps[*n_jumps] = j;
            ++*n_jumps;
            cur = j.to;
            PUSH(cur);
            continue;
        }
        if (dir * (next.theta_base - to) >= 0) {
            cbm_elastica_state e;
            s = refine_root(ctx, rod, &cur, &next, to, &e);
            if (s == CBM_OK)
                PUSH(e);
            break;
        }
        cur = next;
        PUSH(cur);
    }
#undef PUSH
    cbm__free(ctx, eq, cap * sizeof *eq);
    return s;
}
