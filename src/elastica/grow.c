/* A growing elastica under control (Tresierras 2009, ch. 3; include/cambium/elastica_growth.h).
 *
 * The rod is a row of equal cells, each a piece of the elastica (rod.c) with constant radius, D,
 * weight per length and kappa^g. A time step (split into `substeps` equilibria) does:
 *   1. tip growth: Delta L / h new cells of radius R0 at the tip, straight or with the
 *      preferred-angle law (3.34) kappa_o^g = (theta^d - theta_tip) / Delta L; the law of
 *      evolution does not act on them in the step they are made (D_{n-1} = 0, §2.11 step 4);
 *   2. lateral accretion and remodeling: new radii (taper law), E(t), hence D and the weight;
 *   3. evolution of kappa^g on every older cell with the present mean curvature kappa_{n-1} of the
 *      last equilibrium (the composite-rod law (3.16)/(3.18)/(3.26)), or kept where D fell (§3.7);
 *   4. the new equilibrium, followed from the last one by Newton on the tip angle (the Jacobi
 *      field gives d theta_base / d theta_tip); if the followed equilibrium is gone (a fold) or
 *      unstable, the rod jumps to the lowest-energy stable equilibrium at the clamp angle.
 * With one substep this is the discrete recursion (3.18); more substeps integrate the continuous
 * form (3.30) by explicit Euler in time: K^c += Delta D (kappa + kappa^c).
 *
 * The inverse problem (§3.6.2) with a static present configuration: the node angles of every
 * cell that existed before the substep are held. The new tip cells take their equilibrium with
 * their base clamped at the held tip angle; then, from the tip to the base, each held cell's
 * kappa^g is the one for which the cell, integrated backward from its held distal angle with the
 * moment and force carried from beyond, ends at its held proximal angle (a scalar root, found by
 * secant steps). The kappa^c that the evolution law needs for that kappa^g is (3.33) in discrete
 * form: kappa^c = (D_n kappa^g_n - D_{n-1} kappa^g_{n-1} - D_n Delta kappa_I) / Delta D - kappa.
 */
#include "cambium/elastica_growth.h"
#include "elastica_internal.h"

#include <math.h>

cbm_elastica_growth_def cbm_elastica_growth_def_default(void)
{
    cbm_elastica_growth_def d;
    memset(&d, 0, sizeof d);
    d.length0 = 1.0;
    d.cells = 100;
    d.tip_growth = 0.1;
    d.steps = 2;
    d.dt = 1.0;
    d.substeps = 1;
    d.theta_base = 0.5 * CBM_PI;
    d.radius0 = 1.05;
    d.layer = 0.01;
    d.taper = CBM_ELASTICA_TAPER_LINEAR;
    d.stiffness_ratio = 1.0;
    d.stiffness_tau = 1.0;
    d.youngs = 1.0;
    d.youngs_final = 1.0;
    d.youngs_tau = 0.0;
    d.density = 4.231;
    d.gravity = 1.0;
    d.law = CBM_ELASTICA_LAW_GROWTH;
    d.control = CBM_ELASTICA_CONTROL_GIVEN;
    d.side = 1;
    return d;
}

void cbm_elastica_growth_destroy(cbm_context *ctx, cbm_elastica_growth *g)
{
    if (!g)
        return;
    for (size_t k = 0; k < g->n_frames; k++)
        cbm__free(ctx, g->frames[k].cells, g->frames[k].n_cells * sizeof *g->frames[k].cells);
    cbm__free(ctx, g->frames, g->n_frames * sizeof *g->frames);
    cbm__free(ctx, g, sizeof *g);
}

/* the growing rod's cells */
typedef struct cell {
    double R, Rstart;         /* radius now, at the start of the step */
    double D, Dprev, w, load; /* load: point force at the distal end */
    double kg, kg0, born;     /* kappa^g, kappa_o^g, birth time */
    double ass, aas, ai;      /* int Ddot (kappa - kappa_o^g), int Ddot kappa^c, int D dkappa_I */
    double kI;                /* kappa_I^g at the last update */
    double kappa, kc;         /* mean present curvature; kappa^c of the last update */
    double theta, x, y;       /* distal end */
} cell;

typedef struct grower {
    cbm_context *ctx;
    const cbm_elastica_growth_def *d;
    double h;
    size_t n, cap;
    cell *c;
    cbm_elastica_piece *pc;
    double *loads;
    double *th, *px, *py; /* node samples, cap + 1 */
    double theta_tip;     /* of the current equilibrium */
    cbm_elastica_state st;
    bool jumped;
    double hold_error;
} grower;

static double youngs_at(const cbm_elastica_growth_def *d, double t)
{
    if (d->youngs_tau <= 0.0)
        return d->youngs;
    return d->youngs_final + (d->youngs - d->youngs_final) * exp(-t / d->youngs_tau);
}

static double field(cbm_elastica_field_fn fn, void *ud, double constant, double s, double t)
{
    return fn ? fn(ud, s, t) : constant;
}

static double induced_at(const cbm_elastica_growth_def *d, double s, double t)
{
    return d->induced_fn ? d->induced_fn(d->induced_ud, s, t) : d->induced_rate * t;
}

static cbm_status check_def(cbm_context *ctx, const cbm_elastica_growth_def *d, double *h)
{
    const char *bad = NULL;
    if (!(isfinite(d->length0) && d->length0 > 0))
        bad = "length0 must be positive";
    else if (d->cells < 1 || d->cells > 1000000)
        bad = "cells must be in 1 .. 10^6";
    else if (!(isfinite(d->tip_growth) && d->tip_growth >= 0))
        bad = "tip_growth must be >= 0";
    else if (d->steps > 100000)
        bad = "steps must be at most 10^5";
    else if (!(isfinite(d->dt) && d->dt > 0))
        bad = "dt must be positive";
    else if (d->substeps < 1 || d->substeps > 10000)
        bad = "substeps must be in 1 .. 10^4";
    else if (!isfinite(d->theta_base))
        bad = "theta_base must be finite";
    else if (!(isfinite(d->radius0) && d->radius0 > 0))
        bad = "radius0 must be positive";
    else if (!(isfinite(d->layer) && d->layer >= 0))
        bad = "layer must be >= 0";
    else if (d->taper != CBM_ELASTICA_TAPER_LINEAR && d->taper != CBM_ELASTICA_TAPER_UNIFORM &&
             d->taper != CBM_ELASTICA_TAPER_STEP)
        bad = "taper is not a cbm_elastica_taper";
    else if (!(isfinite(d->stiffness_ratio) && d->stiffness_ratio >= 1.0 &&
               isfinite(d->stiffness_tau) && d->stiffness_tau > 0))
        bad = "stiffness_ratio must be >= 1 and stiffness_tau positive";
    else if (!(isfinite(d->youngs) && d->youngs > 0 && isfinite(d->youngs_final) &&
               d->youngs_final > 0 && isfinite(d->youngs_tau) && d->youngs_tau >= 0))
        bad = "youngs and youngs_final must be positive, youngs_tau >= 0";
    else if (!(isfinite(d->density) && d->density >= 0 && isfinite(d->gravity) && d->gravity >= 0))
        bad = "density and gravity must be >= 0";
    else if (!(isfinite(d->segment_load) && d->segment_load >= 0))
        bad = "segment_load must be >= 0";
    else if (d->segment_load > 0 && d->tip_growth == 0)
        bad = "segment_load is per tip_growth of length: tip_growth must be positive";
    else if (!isfinite(d->tip_load) || !isfinite(d->rest_curvature0) ||
             !isfinite(d->preferred_angle) || !isfinite(d->control_curvature) ||
             !isfinite(d->induced_rate))
        bad = "tip_load, rest_curvature0, preferred_angle, control_curvature and induced_rate "
              "must be finite";
    else if (d->law != CBM_ELASTICA_LAW_GROWTH && d->law != CBM_ELASTICA_LAW_REMODEL &&
             d->law != CBM_ELASTICA_LAW_NONE)
        bad = "law is not a cbm_elastica_law";
    else if (d->control != CBM_ELASTICA_CONTROL_GIVEN && d->control != CBM_ELASTICA_CONTROL_STATIC)
        bad = "control is not a cbm_elastica_control";
    else if (d->control == CBM_ELASTICA_CONTROL_STATIC && d->law != CBM_ELASTICA_LAW_GROWTH)
        bad = "the inverse problem (control static) needs the growth law (kappa^c is its unknown)";
    if (bad)
        return cbm__fail(ctx, CBM_E_INVALID, "elastica growth: %s", bad);
    *h = d->length0 / (double)d->cells;
    double q = d->tip_growth / *h;
    if (fabs(q - nearbyint(q)) > 1e-9 * (q > 1 ? q : 1))
        return cbm__fail(ctx, CBM_E_INVALID,
                         "elastica growth: tip_growth (%g) must be a whole number of cells "
                         "(length0 / cells = %g)",
                         d->tip_growth, *h);
    double total = (double)d->cells + (double)d->steps * nearbyint(q);
    if (total > 1e6)
        return cbm__fail(ctx, CBM_E_INVALID, "elastica growth: more than 10^6 cells at the end");
    return CBM_OK;
}

/* The rod of the first `n` cells (from `first`). */
static cbm_elastica_rod make_rod(grower *g, size_t first, size_t n, double tip_load)
{
    for (size_t i = first; i < first + n; i++) {
        cbm_elastica_piece *p = &g->pc[i];
        p->length = g->h;
        p->D0 = p->D1 = g->c[i].D;
        p->w0 = p->w1 = g->c[i].w;
        p->rest_curvature = g->c[i].kg;
        g->loads[i] = g->c[i].load;
    }
    cbm_elastica_rod r = cbm_elastica_rod_default();
    r.pieces = g->pc + first;
    r.n_pieces = n;
    r.tip_force = tip_load;
    r.piece_loads = g->loads + first;
    return r;
}

/* Newton on the tip angle from `guess` to the equilibrium with base angle `target`; false if it
 * does not converge to a stable equilibrium. */
static bool follow(cbm_context *ctx, const cbm_elastica_rod *rod, double target, double guess,
                   cbm_elastica_state *out)
{
    double t = guess;
    cbm_elastica_state st;
    if (cbm_elastica_shoot(ctx, rod, t, &st) != CBM_OK)
        return false;
    double r = st.theta_base - target;
    for (int it = 0; it < 80; it++) {
        if (fabs(r) < 1e-12) {
            *out = st;
            return st.index == 0;
        }
        if (!(fabs(st.dbase_dtip) > 1e-12))
            return false;
        double step = -r / st.dbase_dtip;
        if (fabs(step) > 0.3)
            step = step > 0 ? 0.3 : -0.3;
        bool ok = false;
        for (int half = 0; half < 30 && !ok; half++, step *= 0.5) {
            cbm_elastica_state nx;
            if (cbm_elastica_shoot(ctx, rod, t + step, &nx) != CBM_OK)
                continue;
            double nr = nx.theta_base - target;
            if (fabs(nr) < fabs(r) || fabs(nr) < 1e-12) {
                t += step, st = nx, r = nr, ok = true;
            }
        }
        if (!ok)
            return false;
    }
    return false;
}

/* Every equilibrium of one period of the tip angle; the lowest-energy stable one (ties: the
 * def's side). */
static cbm_status choose(cbm_context *ctx, const cbm_elastica_rod *rod, double target,
                         double centre, int side, cbm_elastica_state *out)
{
    cbm_elastica_scan_def sd = cbm_elastica_scan_def_default();
    sd.theta_tip_min = centre - CBM_PI;
    sd.theta_tip_max = centre + CBM_PI;
    cbm_elastica_scurve *sc = NULL;
    cbm_status s = cbm_elastica_scurve_compute(ctx, rod, &sd, &sc);
    if (s != CBM_OK)
        return s;
    enum { MAXE = 64 };
    cbm_elastica_state eq[MAXE];
    size_t n = 0;
    s = cbm_elastica_equilibria(ctx, rod, sc, target, eq, MAXE, &n);
    cbm_elastica_scurve_destroy(ctx, sc);
    if (s != CBM_OK)
        return s;
    if (n > MAXE)
        n = MAXE;
    bool have = false;
    for (size_t k = 0; k < n; k++) {
        if (eq[k].index != 0)
            continue;
        double tol = 1e-9 * (1.0 + fabs(eq[k].energy));
        bool better = !have || eq[k].energy < out->energy - tol;
        if (have && fabs(eq[k].energy - out->energy) <= tol)
            better = side >= 0 ? eq[k].tip_x > out->tip_x : eq[k].tip_x < out->tip_x;
        if (better)
            *out = eq[k], have = true;
    }
    if (!have)
        return cbm__fail(ctx, CBM_E_NOT_CONVERGED,
                         "elastica growth: no stable equilibrium at the clamp angle");
    return CBM_OK;
}

/* Node angles and positions of the equilibrium with tip angle t; cell curvatures. */
static cbm_status sample(grower *g, const cbm_elastica_rod *rod, double t)
{
    cbm_status s = cbm_elastica_shape(g->ctx, rod, t, g->n + 1, g->px, g->py, g->th);
    if (s != CBM_OK)
        return s;
    for (size_t i = 0; i < g->n; i++) {
        cell *c = &g->c[i];
        c->kappa = (g->th[i + 1] - g->th[i]) / g->h;
        c->theta = g->th[i + 1];
        c->x = g->px[i + 1];
        c->y = g->py[i + 1];
    }
    return CBM_OK;
}

/* The equilibrium of the whole rod, followed from the current one (or chosen at t = 0). */
static cbm_status equilibrium(grower *g, bool initial)
{
    const cbm_elastica_growth_def *d = g->d;
    cbm_elastica_rod rod = make_rod(g, 0, g->n, d->tip_load);
    cbm_elastica_state st = {0};
    g->jumped = false;
    if (initial || !follow(g->ctx, &rod, d->theta_base, g->theta_tip, &st)) {
        cbm_status s = choose(g->ctx, &rod, d->theta_base, initial ? d->theta_base : g->theta_tip,
                              d->side, &st);
        if (s != CBM_OK)
            return s;
        g->jumped = !initial;
    }
    g->st = st;
    g->theta_tip = st.theta_tip;
    return sample(g, &rod, st.theta_tip);
}

/* One backward integration of a single cell from its distal end (angle, moment, force) with
 * kappa^g = k: the base values. */
static cbm_status cell_back(grower *g, size_t i, double k, double th, double m, double P,
                            double yb[EL_N])
{
    cbm_elastica_piece p = g->pc[i];
    p.rest_curvature = k;
    double load = g->c[i].load;
    cbm_elastica_rod r = cbm_elastica_rod_default();
    r.pieces = &p;
    r.n_pieces = 1;
    r.tip_force = P;
    r.tip_moment = m;
    r.piece_loads = &load;
    return cbm__el_integrate(&r, th, 0.0, yb, NULL, NULL, NULL, 0);
}

/* The inverse problem for one substep: kappa^g of the held cells [0, nh) that keeps their node
 * angles `target` (nh + 1 values); the new cells [nh, n) take their own equilibrium. */
static cbm_status hold(grower *g, size_t nh, const double *target)
{
    const cbm_elastica_growth_def *d = g->d;
    double th = target[nh], m = 0.0, P = d->tip_load;
    (void)make_rod(g, 0, g->n, d->tip_load); /* the held cells' pieces (D, w) */
    if (nh < g->n) {
        cbm_elastica_rod tip = make_rod(g, nh, g->n - nh, d->tip_load);
        cbm_elastica_state st;
        if (!follow(g->ctx, &tip, th, th, &st)) {
            cbm_status s = choose(g->ctx, &tip, th, th, d->side, &st);
            if (s != CBM_OK)
                return s;
        }
        double yb[EL_N];
        cbm_status s = cbm__el_integrate(&tip, st.theta_tip, 0.0, yb, NULL, NULL, NULL, 0);
        if (s != CBM_OK)
            return cbm__fail(g->ctx, s, "elastica growth: integration of the new tip failed");
        m = yb[EL_M];
        P = yb[EL_P];
        g->theta_tip = st.theta_tip;
    } else {
        g->theta_tip = target[g->n];
    }
    for (size_t i = nh; i-- > 0;) {
        /* theta_base(k) is nearly th - h (k + mean m / D): secant steps from that slope */
        double k0 = g->c[i].kg, yb[EL_N];
        CBM_TRY(cell_back(g, i, k0, th, m, P, yb));
        double f0 = yb[EL_THETA] - target[i], k1 = k0 + f0 / g->h;
        for (int it = 0; it < 50 && fabs(f0) > 1e-14; it++) {
            CBM_TRY(cell_back(g, i, k1, th, m, P, yb));
            double f1 = yb[EL_THETA] - target[i];
            if (f1 == f0)
                break;
            double k2 = k1 - f1 * (k1 - k0) / (f1 - f0);
            k0 = k1, f0 = f1, k1 = k2;
        }
        g->c[i].kg = k0;
        g->pc[i].rest_curvature = k0;
        CBM_TRY(cell_back(g, i, k0, th, m, P, yb));
        th = yb[EL_THETA], m = yb[EL_M], P = yb[EL_P];
    }
    return CBM_OK;
}

/* The radius of cell i at the end of the fraction `phi` of step k (time t), length L_k. */
static double radius_at(const grower *g, const cell *c, size_t i, double phi, double t, double Lk,
                        double t0)
{
    const cbm_elastica_growth_def *d = g->d;
    switch (d->taper) {
    case CBM_ELASTICA_TAPER_LINEAR: {
        double sm = ((double)i + 0.5) * g->h, f = 1.0 - sm / Lk;
        return c->Rstart + phi * d->layer * (f > 0 ? f : 0);
    }
    case CBM_ELASTICA_TAPER_UNIFORM:
        return c->Rstart + (c->born < t0 ? phi * d->layer : 0.0);
    case CBM_ELASTICA_TAPER_STEP:
    default: {
        double f =
            1.0 + (d->stiffness_ratio - 1.0) * (1.0 - exp(-(t - c->born) / d->stiffness_tau));
        return d->radius0 * pow(f, 0.25);
    }
    }
}

static void set_material(grower *g, cell *c, double t)
{
    const cbm_elastica_growth_def *d = g->d;
    double a = CBM_PI * c->R * c->R;
    c->D = youngs_at(d, t) * a * c->R * c->R / 4.0;
    c->w = d->density * a * d->gravity +
           (d->segment_load > 0 && !d->segment_load_point ? d->segment_load / d->tip_growth : 0.0);
}

/* point loads: F_N at the distal end of every Delta L of length */
static void set_load(grower *g, size_t i)
{
    const cbm_elastica_growth_def *d = g->d;
    g->c[i].load = 0.0;
    if (d->segment_load > 0 && d->segment_load_point) {
        size_t per = (size_t)nearbyint(d->tip_growth / g->h);
        if ((i + 1) % per == 0)
            g->c[i].load = d->segment_load;
    }
}

static cbm_status record(grower *g, cbm_elastica_growth_frame *f, double t)
{
    f->time = t;
    f->length = (double)g->n * g->h;
    f->theta_tip = g->st.theta_tip;
    f->tip_x = g->st.tip_x;
    f->tip_y = g->st.tip_y;
    f->strain_base = g->st.strain_base;
    f->moment_base = g->st.moment_base;
    f->stiffness_base = g->c[0].D;
    f->energy = g->st.energy;
    f->index = g->st.index;
    f->jumped = g->jumped;
    f->hold_error = g->hold_error;
    f->n_cells = g->n;
    f->cells = cbm__alloc(g->ctx, g->n * sizeof *f->cells);
    if (!f->cells) {
        f->n_cells = 0;
        return CBM_E_NOMEM;
    }
    double tg = g->d->theta_base, xg = 0, yg = 0, h = g->h;
    for (size_t i = 0; i < g->n; i++) {
        const cell *c = &g->c[i];
        cbm_elastica_growth_cell *o = &f->cells[i];
        /* the growth configuration: arcs of constant curvature kappa^g from the same clamp */
        double u = 0.5 * c->kg * h, sinc = fabs(u) < 1e-8 ? 1.0 - u * u / 6 : sin(u) / u;
        xg += h * cos(tg + u) * sinc;
        yg += h * sin(tg + u) * sinc;
        tg += c->kg * h;
        o->s = ((double)i + 0.5) * h;
        o->x = c->x, o->y = c->y, o->theta = c->theta;
        o->xg = xg, o->yg = yg;
        o->kappa = c->kappa, o->kappa_g = c->kg, o->kappa_c = c->kc;
        o->stiffness = c->D, o->weight = c->w, o->radius = c->R;
        o->k_ss = c->ass / c->D, o->k_as = c->aas / c->D, o->k_i = c->ai / c->D;
        o->kappa_o_g = c->kg0;
        o->born = c->born;
    }
    return CBM_OK;
}

static cbm_status substep(grower *g, size_t k, size_t j, size_t cps)
{
    const cbm_elastica_growth_def *d = g->d;
    double t0 = (double)(k - 1) * d->dt, ms = (double)d->substeps;
    double tprev = t0 + (double)(j - 1) * d->dt / ms, t1 = t0 + (double)j * d->dt / ms;
    size_t nh = g->n; /* cells that existed before this substep */
    if (j == 1) {
        for (size_t i = 0; i < g->n; i++)
            g->c[i].Rstart = g->c[i].R;
        double k0 = 0.0;
        if (d->preferred && d->tip_growth > 0)
            k0 = (d->preferred_angle - g->theta_tip) / d->tip_growth;
        for (size_t q = 0; q < cps; q++) {
            size_t i = g->n++;
            cell *c = &g->c[i];
            memset(c, 0, sizeof *c);
            c->R = c->Rstart = d->radius0;
            c->kg = c->kg0 = k0;
            c->born = t0;
            c->kI = induced_at(d, ((double)i + 0.5) * g->h, t0);
            set_load(g, i);
        }
    }
    double Lk = (double)g->n * g->h, phi = (double)j / ms;
    double *target = NULL;
    if (d->control == CBM_ELASTICA_CONTROL_STATIC) {
        target = cbm__alloc(g->ctx, (nh + 1) * sizeof *target);
        if (!target)
            return CBM_E_NOMEM;
        target[0] = d->theta_base;
        for (size_t i = 0; i < nh; i++)
            target[i + 1] = g->c[i].theta;
    }
    cbm_status s = CBM_OK;
    double *kgold = cbm__alloc(g->ctx, (nh + 1) * sizeof *kgold);
    if (!kgold) {
        cbm__free(g->ctx, target, target ? (nh + 1) * sizeof *target : 0);
        return CBM_E_NOMEM;
    }
    for (size_t i = 0; i < g->n; i++) {
        cell *c = &g->c[i];
        c->Dprev = i < nh ? c->D : 0.0;
        c->R = radius_at(g, c, i, phi, t1, Lk, t0);
        set_material(g, c, t1);
    }
    for (size_t i = 0; i < nh; i++) {
        cell *c = &g->c[i];
        double sm = ((double)i + 0.5) * g->h, dD = c->D - c->Dprev;
        double kI = induced_at(d, sm, t1), dkI = kI - c->kI;
        kgold[i] = c->kg;
        c->kc = 0.0;
        if (d->law == CBM_ELASTICA_LAW_NONE)
            continue;
        c->kI = kI;
        if (dD > 0) {
            double kc = 0.0;
            if (d->law == CBM_ELASTICA_LAW_GROWTH && d->control == CBM_ELASTICA_CONTROL_GIVEN)
                kc = field(d->control_fn, d->control_ud, d->control_curvature, sm, t1);
            /* the composite rod: the old rod and a layer moulded on kappa + kappa^c (3.16) */
            c->kg = (c->Dprev * c->kg + dD * (c->kappa + kc)) / c->D + dkI;
            c->kc = kc;
            c->ass += dD * (c->kappa - c->kg0);
            c->aas += dD * kc;
        } else {
            c->kg += dkI; /* the decreasing-stiffness rule: kappa^g kept (§3.7) */
        }
        c->ai += c->D * dkI;
    }
    if (d->control == CBM_ELASTICA_CONTROL_STATIC) {
        s = hold(g, nh, target);
        for (size_t i = 0; s == CBM_OK && i < nh; i++) {
            cell *c = &g->c[i];
            double sm = ((double)i + 0.5) * g->h, dD = c->D - c->Dprev;
            double dkI = induced_at(d, sm, t1) - induced_at(d, sm, tprev);
            double need = c->D * c->kg - c->Dprev * kgold[i] - c->D * dkI;
            /* undo the forward update's kappa^c = 0 sums, then book the solved kappa^c */
            double kc;
            if (dD > 0) {
                kc = need / dD - c->kappa;
            } else if (fabs(c->kg - kgold[i] - dkI) <=
                       1e-9 * (fabs(c->kg) + fabs(kgold[i])) + 1e-12 / g->h) {
                kc = 0.0;
            } else {
                s = cbm__fail(g->ctx, CBM_E_RUNTIME,
                              "elastica growth: no kappa^c holds the rod at s = %g: D does not "
                              "rise there (kappa^c is indeterminate, (3.32))",
                              sm);
                break;
            }
            c->kc = kc;
            if (dD > 0)
                c->aas += dD * kc;
        }
    }
    cbm__free(g->ctx, kgold, (nh + 1) * sizeof *kgold);
    if (s == CBM_OK) {
        s = equilibrium(g, false);
        if (s == CBM_OK && target) {
            g->hold_error = 0;
            for (size_t i = 0; i < nh; i++) {
                double e = fabs(g->c[i].theta - target[i + 1]);
                if (e > g->hold_error)
                    g->hold_error = e;
            }
        }
    }
    if (target)
        cbm__free(g->ctx, target, (nh + 1) * sizeof *target);
    return s;
}

cbm_status cbm_elastica_grow(cbm_context *ctx, const cbm_elastica_growth_def *d,
                             cbm_elastica_growth **out)
{
    if (!ctx || !d || !out)
        return CBM_E_INVALID;
    *out = NULL;
    double h = 0;
    CBM_TRY(check_def(ctx, d, &h));
    size_t cps = (size_t)nearbyint(d->tip_growth / h);
    grower g;
    memset(&g, 0, sizeof g);
    g.ctx = ctx;
    g.d = d;
    g.h = h;
    g.cap = d->cells + d->steps * cps;
    cbm_elastica_growth *res = cbm__calloc(ctx, 1, sizeof *res);
    g.c = cbm__calloc(ctx, g.cap, sizeof *g.c);
    g.pc = cbm__calloc(ctx, g.cap, sizeof *g.pc);
    g.loads = cbm__calloc(ctx, g.cap, sizeof *g.loads);
    g.th = cbm__alloc(ctx, (g.cap + 1) * sizeof *g.th);
    g.px = cbm__alloc(ctx, (g.cap + 1) * sizeof *g.px);
    g.py = cbm__alloc(ctx, (g.cap + 1) * sizeof *g.py);
    cbm_status s = CBM_E_NOMEM;
    if (res && g.c && g.pc && g.loads && g.th && g.px && g.py) {
        res->frames = cbm__calloc(ctx, d->steps + 1, sizeof *res->frames);
        res->cell_length = h;
        s = res->frames ? CBM_OK : CBM_E_NOMEM;
    }
    if (s == CBM_OK) {
        res->n_frames = d->steps + 1;
        g.n = d->cells;
        for (size_t i = 0; i < g.n; i++) {
            cell *c = &g.c[i];
            c->R = c->Rstart = d->radius0;
            c->kg = c->kg0 = d->rest_curvature0;
            c->kI = induced_at(d, ((double)i + 0.5) * h, 0.0);
            set_material(&g, c, 0.0);
            set_load(&g, i);
        }
        s = equilibrium(&g, true);
        if (s == CBM_OK)
            s = record(&g, &res->frames[0], 0.0);
    }
    for (size_t k = 1; s == CBM_OK && k <= d->steps; k++) {
        for (size_t j = 1; s == CBM_OK && j <= d->substeps; j++)
            s = substep(&g, k, j, j == 1 ? cps : 0);
        if (s == CBM_OK)
            s = record(&g, &res->frames[k], (double)k * d->dt);
    }
    cbm__free(ctx, g.c, g.cap * sizeof *g.c);
    cbm__free(ctx, g.pc, g.cap * sizeof *g.pc);
    cbm__free(ctx, g.loads, g.cap * sizeof *g.loads);
    cbm__free(ctx, g.th, (g.cap + 1) * sizeof *g.th);
    cbm__free(ctx, g.px, (g.cap + 1) * sizeof *g.px);
    cbm__free(ctx, g.py, (g.cap + 1) * sizeof *g.py);
    if (s != CBM_OK) {
        cbm_elastica_growth_destroy(ctx, res);
        return s;
    }
    *out = res;
    return CBM_OK;
}
