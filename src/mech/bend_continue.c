/* cambium: continuation of the bend rod's equilibria in a parameter (docs/bend.md,
 * "Continuation"), and of any plant with one clamp in its base angle or gravity
 * (cbm_plant_continue; the rod is the plant its spec builds): natural-parameter steps with warm
 * starts and step halving, the stability of every equilibrium, folds located by bisection on the
 * parameter and the jump past each fold.
 *
 * Why natural-parameter steps and not arclength: the question a user asks of a plant is what it
 * does when the parameter moves one way (a clamp turned slowly, a load raised), and that is the
 * stable branch up to its fold, then the jump. At a fold the branch turns back in the parameter,
 * so a forward step finds no nearby equilibrium: the warm-started solver either fails or (its
 * transient path creeps like an overdamped motion) snaps through to another branch, which shows
 * as a large turn of the tip. Either way the step is halved, and the halving is a bisection of
 * the bracket [last equilibrium, failed parameter] down to min_step: the fold is located to
 * that width, and its lowest eigenvalue goes to 0 with the width (an O(sqrt) approach). */
#include "cambium/bend.h"
#include "core/core.h"
#include "core/vecmath.h"
#include "mech/mech_internal.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

cbm_bend_continuation_def cbm_bend_continuation_def_default(void)
{
    cbm_bend_continuation_def d;
    memset(&d, 0, sizeof d);
    d.param = CBM_BEND_PARAM_ANGLE;
    d.steps = 60;
    d.max_turn_deg = 10.0;
    d.min_step = 1e-7;
    d.method = CBM_BEND_CONTINUE_ARCLENGTH;
    d.max_points = 100000;
    d.switch_at = 1;
    return d;
}

void cbm_bend_branch_free(cbm_bend_branch *b)
{
    if (!b)
        return;
    free(b->points);
    free(b->folds);
    memset(b, 0, sizeof *b);
}

/* What a parameter change touches: the spec's loads and the rod's segment lengths at the
 * start (the length parameter scales them all alike). */
typedef struct param_ctx {
    const cbm_bend_spec *spec;
    cbm_bend_param which;
    double *len0; /* segment lengths as built (length parameter only) */
    size_t n;     /* their number: the rod's segments never change in a continuation */
    double l0;    /* their sum */
} param_ctx;

/* What the trace needs beyond the parameter: the solve settings, the length that scales the
 * continuity test and the metric, the segment whose tip is reported, and the bend spec when the
 * plant is a bend rod (its loads give the moment scale; NULL for any other plant). */
typedef struct cont_cfg {
    const cbm_bend_spec *spec;
    cbm_solve_def sd;
    double length;
    size_t tip;
} cont_cfg;

static cbm_status set_param(const param_ctx *c, cbm_plant *p, double v)
{
    size_t n = cbm_plant_segment_count(p);
    switch (c->which) {
    case CBM_BEND_PARAM_ANGLE: {
        const cbm_vec3 *pos = cbm_plant_positions(p);
        cbm_vec3 base = pos ? pos[0] : v3(0, 0, 0);
        cbm_plant_set_base(p, base, cbm_mech_clamp_orientation(v * CBM_PI / 180.0));
        return CBM_OK;
    }
    case CBM_BEND_PARAM_GRAVITY:
        cbm_plant_set_gravity(p, v3(0, -v, 0));
        return CBM_OK;
    case CBM_BEND_PARAM_DENSITY:
        for (size_t i = 0; i < n; i++)
            for (size_t k = 0; k < cbm_plant_ring_count(p, i); k++) {
                cbm_ring r;
                CBM_TRY(cbm_plant_get_ring(p, i, k, &r));
                r.density = v;
                CBM_TRY(cbm_plant_set_ring(p, i, k, &r));
            }
        return CBM_OK;
    case CBM_BEND_PARAM_TIP_LOAD:
        return cbm_plant_set_load(p, n - 1, c->spec->tip_mass, v3(0, -v, 0),
                                  v3(0, 0, c->spec->tip_moment));
    case CBM_BEND_PARAM_LENGTH:
        for (size_t i = 0; i < c->n; i++)
            CBM_TRY(cbm_plant_set_length(p, i, c->len0[i] * (v / c->l0)));
        return CBM_OK;
    }
    return CBM_E_INVALID;
}

/* The solve settings (the spec's, or the caller's for a plant), and the equilibrium at the
 * sweep's start: both traces begin there. */
static cbm_status start_solve(cbm_context *ctx, const cont_cfg *cfg,
                              const cbm_bend_continuation_def *d, const param_ctx *pc, cbm_plant *p,
                              cbm_solve_def *sd, cbm_solve_stats *ss)
{
    *sd = cfg->sd;
    CBM_TRY(set_param(pc, p, d->from));
    cbm_status st = cbm_plant_solve(p, sd, ss);
    cbm__mech_work_current(p); /* the workspace is read below (solve_order.c) */
    if (st == CBM_E_NOT_CONVERGED)
        return cbm__fail(ctx, st, "bend continuation: no equilibrium at the start %g", d->from);
    return st;
}

/* The lowest eigenvalue of S^-1 J on the S-orthogonal complement of g (NaN if none found):
 * shifted inverse iteration as cbm__mech_lowest_mode, each iterate deflated. */
static cbm_status inverse_iteration(cbm_plant *p, const cbm_vec3 *g, double gg, bool nearest,
                                    cbm_vec3 *mode, double *lambda);

static cbm_status lowest_without(cbm_plant *p, const cbm_vec3 *g, double gg, double *lambda)
{
    return inverse_iteration(p, g, gg, false, NULL, lambda);
}

/* Shifted inverse iteration with the tree factorisation: the lowest eigenvalue of S^-1 J (the
 * shift raised until every pivot is positive definite, as cbm__mech_lowest_mode), or with
 * `nearest` the one nearest 0 (no shift: the mode whose eigenvalue crosses 0 at a bifurcation,
 * whatever lies below it). Each iterate is deflated of g when g != NULL. The eigenvector goes
 * to mode (S-normalised) when mode != NULL. */
static cbm_status inverse_iteration(cbm_plant *p, const cbm_vec3 *g, double gg, bool nearest,
                                    cbm_vec3 *mode, double *lambda)
{
    cbm__mech_work *w = &p->work;
    const size_t n = p->n;
    *lambda = NAN;
    double mu = 0.0;
    if (nearest) {
        if (cbm__mech_tree_factor(p, 0.0, NULL) != 0)
            return CBM_OK; /* a singular pivot: exactly on the bifurcation */
    }
    size_t passes = 0;
    if (!nearest && !cbm__mech_shift_until_definite(p, &mu, &passes))
        return CBM_OK;
    cbm_vec3 *v = malloc(3 * n * sizeof *v);
    if (!v)
        return CBM_E_NOMEM;
    cbm_vec3 *b = v + n, *x = b + n;
    for (size_t i = 0; i < n; i++)
        v[i] = v3(0.01 / w->cj[i].x, 1.0 / w->cj[i].y, 0.01 / w->cj[i].z);
    double theta = NAN;
    bool ok = true;
    cbm__mech_inverse_def d = {.mu = mu, .g = g, .gg = gg, .max_it = 300};
    cbm__mech_inverse_iteration(p, &d, v, b, x, &theta, &ok);
    if (mode)
        memcpy(mode, v, n * sizeof *mode);
    free(v);
    *lambda = theta - mu;
    return CBM_OK;
}

/* The zero mode of a symmetry (docs/bend.md "Stability along a branch"). A round rod clamped
 * along gravity, without rest curvature or tip moment, has a circle of equilibria: the shape
 * turned about the vertical through the base. Turning every joint's frame by phi about its own
 * heading H (the base frame with it, which is the turn about the vertical when the clamp is
 * vertical) maps Omega_i to R_H(phi) Omega_i, so the circle's tangent is
 *     g_i = H x Omega_i = (0, -Omega_U, Omega_L)   (local H, L, U).
 * *has: J g = 0 to 1e-8 of the S-weighted norms (an equilibrium to the solver's tolerance is
 * equivariant to that order; a clamp a few 1e-7 rad off the vertical is not, and its mode out of
 * the plane is a real one), so g is such a mode. Then *lambda2 is the lowest eigenvalue of
 * S^-1 J off g: the state is stable, up to the neutral turn, iff lambda2 >= 0. Scratch:
 * work.step (g) and work.tmp. */
static cbm_status symmetry_mode(cbm_plant *p, bool *has, double *lambda2)
{
    cbm__mech_work *w = &p->work;
    const size_t n = p->n;
    cbm_vec3 *g = w->step, *jg = w->tmp;
    *has = false;
    *lambda2 = NAN;
    for (size_t i = 0; i < n; i++)
        g[i] = v3(0.0, -p->omega[i].z, p->omega[i].y);
    double gg = cbm__mech_sdot(p, g, g);
    if (!(gg > 0.0)) /* a straight rod: no circle, its zero modes are bucklings */
        return CBM_OK;
    cbm__mech_jvp(p, g, jg);
    double r = 0.0;
    for (size_t i = 0; i < n; i++) {
        const cbm_vec3 c = w->cj[i], v = jg[i];
        r += v.x * v.x / c.x + v.y * v.y / c.y + v.z * v.z / c.z;
    }
    if (!(r <= 1e-16 * gg))
        return CBM_OK;
    *has = true;
    return lowest_without(p, g, gg, lambda2);
}

/* the branch point of the plant's current (solved) state; prev_deg unwraps the tip angle */
static cbm_status read_point(cbm_plant *p, size_t tip_seg, double param, double prev_deg,
                             cbm_bend_branch_point *o)
{
    cbm_segment_state tip, base;
    CBM_TRY(cbm_plant_segment(p, tip_seg, &tip));
    CBM_TRY(cbm_plant_segment(p, 0, &base));
    cbm_quat q;
    CBM_TRY(cbm_plant_distal_frame(p, tip_seg, &q));
    cbm_vec3 h = q_rotate(q, v3(1, 0, 0));
    double a = atan2(h.y, h.x) * 180.0 / CBM_PI;
    if (isfinite(prev_deg))
        a += 360.0 * round((prev_deg - a) / 360.0);
    cbm_stability sb;
    cbm_status st = cbm_plant_stability(p, &sb);
    if (st != CBM_OK && st != CBM_E_NOT_CONVERGED)
        return st;
    memset(o, 0, sizeof *o);
    o->param = param;
    o->tip_angle_deg = a;
    o->tip_x = tip.distal.x - base.proximal.x;
    o->tip_y = tip.distal.y - base.proximal.y;
    o->tip_z = tip.distal.z - base.proximal.z;
    /* The pivots' inertia is exact for a symmetric D J; off the plane of a bent state it is a
     * reading of it (cambium/mech.h), and it may count a zero mode as negative by rounding.
     * The count is therefore checked against the eigenvalues: none below 0 means no unstable
     * mode; a symmetry's zero mode (the only negative one by rounding) is not one when every
     * eigenvalue off it is >= 0. A real eigenvalue just below 0 (a column a hair past its
     * buckling load) still counts. */
    double l2 = NAN;
    size_t count = sb.unstable_modes;
    if (st == CBM_OK)
        CBM_TRY(symmetry_mode(p, &o->symmetry_mode, &l2));
    if (count > 0 && isfinite(sb.lowest_eigenvalue) && sb.lowest_eigenvalue >= 0.0)
        count = 0;
    else if (count > 0 && o->symmetry_mode && isfinite(l2) && l2 >= 0.0)
        count = 0;
    o->unstable_modes = count;
    o->lowest_eigenvalue = sb.lowest_eigenvalue;
    o->energy = sb.energy;
    return CBM_OK;
}

typedef struct growbuf {
    cbm_bend_branch *b;
    size_t cap_p, cap_f;
} growbuf;

static cbm_status push_point(growbuf *g, const cbm_bend_branch_point *pt)
{
    cbm_bend_branch *b = g->b;
    if (b->n_points == g->cap_p) {
        size_t c = g->cap_p ? 2 * g->cap_p : 64;
        void *np = realloc(b->points, c * sizeof *b->points);
        if (!np)
            return CBM_E_NOMEM;
        b->points = np;
        g->cap_p = c;
    }
    b->points[b->n_points++] = *pt;
    return CBM_OK;
}

static cbm_status push_fold(growbuf *g, const cbm_bend_fold *f)
{
    cbm_bend_branch *b = g->b;
    if (b->n_folds == g->cap_f) {
        size_t c = g->cap_f ? 2 * g->cap_f : 8;
        void *np = realloc(b->folds, c * sizeof *b->folds);
        if (!np)
            return CBM_E_NOMEM;
        b->folds = np;
        g->cap_f = c;
    }
    b->folds[b->n_folds++] = *f;
    return CBM_OK;
}

static void restore(cbm_plant *p, const cbm_vec3 *saved, size_t n)
{
    for (size_t i = 0; i < n; i++)
        (void)cbm_plant_set_omega(p, i, saved[i]);
}

static cbm_status check_spec(cbm_context *ctx, const cbm_bend_spec *s)
{
    if (s->solver != CBM_MECH_NEWTON)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "bend continuation: needs solver = fast (the stability count comes from "
                         "its tree factorisation)");
    if (s->steps > 0 || s->duration > 0)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "bend continuation: a spec with growth `steps` or a motion `duration` "
                         "cannot be continued");
    return CBM_OK;
}

static cbm_status check_def(cbm_context *ctx, const cbm_bend_continuation_def *d)
{
    if (!(isfinite(d->from) && isfinite(d->to)) || d->from == d->to)
        return cbm__fail(ctx, CBM_E_INVALID, "bend continuation: FROM and TO must differ");
    if (d->param == CBM_BEND_PARAM_ANGLE && (fabs(d->from) > 360 || fabs(d->to) > 360))
        return cbm__fail(ctx, CBM_E_INVALID, "bend continuation: angle must be -360 .. 360");
    if (d->param == CBM_BEND_PARAM_GRAVITY && (d->from < 0 || d->to < 0))
        return cbm__fail(ctx, CBM_E_INVALID, "bend continuation: gravity must be >= 0");
    if (d->param == CBM_BEND_PARAM_DENSITY && (d->from <= 0 || d->to <= 0))
        return cbm__fail(ctx, CBM_E_INVALID, "bend continuation: density must be > 0");
    if (d->param == CBM_BEND_PARAM_LENGTH && (d->from <= 0 || d->to <= 0))
        return cbm__fail(ctx, CBM_E_INVALID, "bend continuation: length must be > 0");
    if (d->param != CBM_BEND_PARAM_ANGLE && d->param != CBM_BEND_PARAM_GRAVITY &&
        d->param != CBM_BEND_PARAM_DENSITY && d->param != CBM_BEND_PARAM_TIP_LOAD &&
        d->param != CBM_BEND_PARAM_LENGTH)
        return cbm__fail(ctx, CBM_E_INVALID, "bend continuation: unknown parameter");
    if (d->method != CBM_BEND_CONTINUE_ARCLENGTH && d->method != CBM_BEND_CONTINUE_NATURAL)
        return cbm__fail(ctx, CBM_E_INVALID, "bend continuation: unknown method");
    if (d->method == CBM_BEND_CONTINUE_ARCLENGTH && d->max_points < 2)
        return cbm__fail(ctx, CBM_E_INVALID, "bend continuation: max_points must be >= 2");
    if (d->switch_at < 0)
        return cbm__fail(ctx, CBM_E_INVALID, "bend continuation: switch_at must be >= 0");
    if (d->steps < 1 || d->steps > 10000000)
        return cbm__fail(ctx, CBM_E_INVALID, "bend continuation: STEPS must be 1 .. 10^7");
    if (!(d->max_turn_deg > 0 && d->max_turn_deg <= 180) || !(d->min_step > 0 && d->min_step < 1))
        return cbm__fail(ctx, CBM_E_INVALID,
                         "bend continuation: max_turn_deg must be in (0, 180], min_step in (0, 1)");
    return CBM_OK;
}

static cbm_status trace(cbm_context *ctx, const cont_cfg *cfg, const cbm_bend_continuation_def *d,
                        const param_ctx *pc, cbm_plant *p, growbuf *g, cbm_vec3 *saved)
{
    size_t n = cbm_plant_segment_count(p);
    cbm_solve_def sd;
    cbm_solve_stats ss;
    cbm_status st = start_solve(ctx, cfg, d, pc, p, &sd, &ss);
    if (st != CBM_OK)
        return st;
    cbm_bend_branch_point cur;
    CBM_TRY(read_point(p, cfg->tip, d->from, NAN, &cur));
    CBM_TRY(push_point(g, &cur));
    sd.push_unstable = false; /* follow the branch, stable or not */
    const double range = d->to - d->from, dir = range > 0 ? 1.0 : -1.0;
    const double h0 = range / (double)d->steps, hmin = fabs(range) * d->min_step;
    double h = h0;
    double pv = d->from;
    while (dir * (d->to - pv) > 0.5 * hmin) {
        double step = dir * fmin(fabs(h), fabs(d->to - pv));
        double pn = pv + step;
        if (dir * (d->to - pn) < 0.5 * hmin)
            pn = d->to; /* land on TO exactly */
        memcpy(saved, cbm_plant_omegas(p), n * sizeof *saved);
        CBM_TRY(set_param(pc, p, pn));
        st = cbm_plant_solve(p, &sd, &ss);
        cbm__mech_work_current(p); /* the workspace is read below (solve_order.c) */
        if (st != CBM_OK && st != CBM_E_NOT_CONVERGED)
            return st;
        cbm_bend_branch_point np;
        memset(&np, 0, sizeof np);
        bool conv = st == CBM_OK;
        if (conv)
            CBM_TRY(read_point(p, cfg->tip, pn, cur.tip_angle_deg, &np));
        /* continuity: the tip turns in the plane and moves (also out of it) by at most what a
         * turn of max_turn_deg of the whole rod would give */
        bool cont = conv && fabs(np.tip_angle_deg - cur.tip_angle_deg) <= d->max_turn_deg &&
                    hypot(hypot(np.tip_x - cur.tip_x, np.tip_y - cur.tip_y),
                          np.tip_z - cur.tip_z) <= cfg->length * d->max_turn_deg * CBM_PI / 180.0;
        /* a state that gains (or loses) a symmetry's zero mode has left the branch at a
         * bifurcation: the straight column past Greenhill's load, which the solver leaves for
         * the circle of buckled states, all neutral in the turn about the vertical */
        bool same = cont && np.unstable_modes == cur.unstable_modes &&
                    np.symmetry_mode == cur.symmetry_mode;
        if (same) {
            CBM_TRY(push_point(g, &np));
            cur = np;
            pv = pn;
            h = dir * fmin(2.0 * fabs(h), fabs(h0)); /* grow back after a halving */
            continue;
        }
        if (fabs(step) > hmin) { /* bisect: retry from the last equilibrium with half the step */
            restore(p, saved, n);
            CBM_TRY(set_param(pc, p, pv));
            h = 0.5 * step;
            continue;
        }
        cbm_bend_fold f;
        memset(&f, 0, sizeof f);
        f.at = cur;
        f.bracket = fabs(pn - pv);
        if (cont) { /* the branch goes on, its stability changed (a bifurcation point) */
            f.fold = false;
            CBM_TRY(push_fold(g, &f));
            CBM_TRY(push_point(g, &np));
            cur = np;
            pv = pn;
            h = h0;
            continue;
        }
        /* a fold: jump from the last equilibrium, solved just past it with the push */
        f.fold = true;
        restore(p, saved, n);
        double pj = pv + dir * fmax(hmin, 1e-3 * fabs(h0));
        if (dir * (pj - d->to) > 0)
            pj = d->to;
        CBM_TRY(set_param(pc, p, pj));
        cbm_solve_def jd = sd;
        jd.push_unstable = true;
        st = cbm_plant_solve(p, &jd, &ss);
        cbm__mech_work_current(p); /* the workspace is read below (solve_order.c) */
        if (st != CBM_OK && st != CBM_E_NOT_CONVERGED)
            return st;
        if (st == CBM_E_NOT_CONVERGED) {
            CBM_TRY(push_fold(g, &f));
            return cbm__fail(ctx, st, "bend continuation: no equilibrium past the fold at %.9g",
                             pv);
        }
        CBM_TRY(read_point(p, cfg->tip, pj, cur.tip_angle_deg, &np));
        np.jumped = true;
        f.has_jump = true;
        f.jump = np;
        CBM_TRY(push_fold(g, &f));
        CBM_TRY(push_point(g, &np));
        cur = np;
        pv = pj;
        h = h0;
    }
    return CBM_OK;
}

/* ---- pseudo-arclength ----
 *
 * The branch is the curve R(Omega, lambda) = 0 in the space of the joints' rotation rates and
 * the parameter, measured by the metric
 *     |(dOmega, dlambda)|^2 = sum_i c_i |dOmega_i|^2 + (sigma dlambda)^2,   c_i = d_i L,
 * (d_i the joint's dual length, L the rod's length: sum_i c_i |dOmega_i|^2 is L times the
 * integral of the change of curvature squared, the square of a turn in radians for a uniform
 * bend, whatever the segment count), sigma = pi/180 for an angle in degrees and 1/|to - from|
 * otherwise. From an equilibrium u = (Omega, lambda) with unit tangent t, the predictor
 * u + ds t is corrected by Newton on
 *     R(Omega, lambda) = 0,   <t, u - u_pred> = 0
 * by bordering: J a = R and J b = dR/dlambda (one tree factorisation, two exact O(n) solves;
 * dR/dlambda by a central difference), then
 *     dlambda = (<t, a> - N) / (sigma^2 t_lambda - <t, b>),   dOmega = -a - b dlambda.
 * The bordered matrix stays regular at a fold, where J is singular, so Newton goes round it.
 * The tangent at the new point is (-b, 1) normalised, oriented like the last one; a fold is a
 * change of sign of its parameter component. */

typedef struct arc {
    cbm_context *ctx;
    const cont_cfg *cfg;
    const cbm_bend_continuation_def *d;
    const param_ctx *pc;
    cbm_plant *p;
    size_t n;
    double sigma, tol, range;
    double *c;                          /* n: metric weights */
    cbm_vec3 *res, *rl, *va, *vb, *tmp; /* n each */
    growbuf *g;
    bool switched; /* the branch was left at a bifurcation already */
    long n_bif;    /* bifurcations met so far */
    /* the branch lies in the rod's plane (x-y; bending about each joint's L axis only): the
     * updates keep it there (see plane()) */
    bool planar;
    double m_ref; /* N m, the loads' moment scale over the range (moment_scale) */
} arc;

/* A bend rod is loaded in its plane, so its planar states form an invariant set: a branch that
 * starts in the plane stays in it, and only rounding moves it out. That matters where the
 * branch has a zero mode out of the plane: a round column's buckled states are a circle of
 * copies turned about the vertical, and Newton's updates, amplified along that mode, let the
 * continuation wander round it. Dropping the out-of-plane components (twist H and bending
 * about U) of every update and tangent keeps the branch in the plane; the stability count
 * still comes from the full 3-D tangent. */
static void plane(const arc *a, cbm_vec3 *v)
{
    if (!a->planar)
        return;
    for (size_t i = 0; i < a->n; i++)
        v[i].x = v[i].z = 0.0;
}

/* an equilibrium of the branch with its tangent */
typedef struct arc_point {
    cbm_vec3 *om, *t; /* n each */
    double lam, tl;
    cbm_bend_branch_point pt;
} arc_point;

static void arc_point_copy(const arc *a, arc_point *dst, const arc_point *src)
{
    memcpy(dst->om, src->om, a->n * sizeof *dst->om);
    memcpy(dst->t, src->t, a->n * sizeof *dst->t);
    dst->lam = src->lam;
    dst->tl = src->tl;
    dst->pt = src->pt;
}

static double mdot(const arc *a, const cbm_vec3 *x, const cbm_vec3 *y)
{
    double s = 0.0;
    for (size_t i = 0; i < a->n; i++)
        s += a->c[i] * v3_dot(x[i], y[i]);
    return s;
}

static void put_omega(arc *a, const cbm_vec3 *om)
{
    memcpy(a->p->omega, om, a->n * sizeof *om);
}

/* R(Omega, lam) into out (the plant's current Omega); *relres its relative size */
static cbm_status eval_at(arc *a, double lam, cbm_vec3 *out, double *relres)
{
    cbm_plant *p = a->p;
    CBM_TRY(set_param(a->pc, p, lam));
    p->load_scale = 1.0;
    cbm__mech_prepare(p);
    cbm__mech_forward(p);
    double mmax = 0.0;
    double r = cbm__mech_backward(p, 0.0, out, &mmax, NULL);
    if (!isfinite(r))
        return cbm__mech_report_nonfinite(p);
    /* relative to the larger of the moments present and the load's scale: a straight column
     * carries no moment, and its residual's rounding is then no reason to iterate */
    if (relres)
        *relres = cbm__mech_relres(r, fmax(mmax, a->m_ref), NULL);
    return CBM_OK;
}

/* the moment scale of the loads at parameter value v: (weight + tip force) L + tip moment; a
 * plant that is no bend rod: its weight times the length (point loads are not counted: the
 * scale is only a floor under the moments present) */
static cbm_status moment_scale(arc *a, double v, double *m)
{
    CBM_TRY(set_param(a->pc, a->p, v));
    const cbm_bend_spec *s = a->cfg->spec;
    if (!s) {
        double g = sqrt(v3_norm2(cbm_plant_gravity(a->p)));
        *m = cbm_plant_total_mass(a->p) * g * a->cfg->length;
        return CBM_OK;
    }
    double g = a->d->param == CBM_BEND_PARAM_GRAVITY ? v : s->gravity;
    double tl = a->d->param == CBM_BEND_PARAM_TIP_LOAD ? v : s->tip_load;
    double len = a->d->param == CBM_BEND_PARAM_LENGTH ? v : s->length;
    *m = (cbm_plant_total_mass(a->p) * fabs(g) + fabs(tl)) * len + fabs(s->tip_moment);
    return CBM_OK;
}

/* at (Omega, lam): res = R, rl = dR/dlambda, and the tree factorisation of J */
static cbm_status linearise(arc *a, double lam, double *relres)
{
    double h = 1e-6 * fmax(fabs(lam), a->range);
    CBM_TRY(eval_at(a, lam + h, a->rl, NULL));
    CBM_TRY(eval_at(a, lam - h, a->tmp, NULL));
    for (size_t i = 0; i < a->n; i++)
        a->rl[i] = v3_scale(v3_sub(a->rl[i], a->tmp[i]), 0.5 / h);
    CBM_TRY(eval_at(a, lam, a->res, relres));
    size_t nonpd = 0;
    cbm__mech_tree_factor(a->p, 0.0, &nonpd);
    return CBM_OK;
}

/* the unit tangent at x (an equilibrium in the plant): (-J^-1 dR/dlambda, 1) normalised,
 * oriented along prev (or along the sweep's direction without one) */
static cbm_status tangent(arc *a, arc_point *x, const arc_point *prev, double dir)
{
    put_omega(a, x->om);
    CBM_TRY(linearise(a, x->lam, NULL));
    cbm__mech_tree_apply(a->p, a->rl, a->vb);
    plane(a, a->vb);
    double nrm = sqrt(mdot(a, a->vb, a->vb) + a->sigma * a->sigma);
    double sgn = 1.0;
    if (prev) {
        double dot = a->sigma * a->sigma * prev->tl;
        for (size_t i = 0; i < a->n; i++)
            dot -= a->c[i] * v3_dot(a->vb[i], prev->t[i]);
        sgn = dot < 0.0 ? -1.0 : 1.0;
    } else
        sgn = dir;
    for (size_t i = 0; i < a->n; i++)
        x->t[i] = v3_scale(a->vb[i], -sgn / nrm);
    x->tl = sgn / nrm;
    if (!isfinite(x->tl) || !isfinite(nrm))
        return cbm__mech_report_nonfinite(a->p);
    return CBM_OK;
}

/* Newton from the predictor base + ds t (t, tl: the hyperplane's normal) to an equilibrium on
 * the hyperplane; the result in x (om, lam; the plant holds it). false if it did not converge
 * in 12 iterations or went astray (a joint turning by more than 0.5 rad in one update). */
static cbm_status correct(arc *a, const arc_point *base, const cbm_vec3 *t, double tl, double ds,
                          arc_point *x, int *iters, bool *ok)
{
    const size_t n = a->n;
    for (size_t i = 0; i < n; i++)
        x->om[i] = v3_add(base->om[i], v3_scale(t[i], ds));
    x->lam = base->lam + ds * tl;
    const double lam_p = x->lam;
    *ok = false;
    bool tiny = false;
    for (int it = 0; it <= 12; it++) {
        *iters = it;
        put_omega(a, x->om);
        double rr = INFINITY;
        CBM_TRY(linearise(a, x->lam, &rr));
        if (rr <= a->tol || tiny) {
            *ok = true;
            return CBM_OK;
        }
        if (it == 12)
            break;
        cbm__mech_tree_apply(a->p, a->res, a->va);
        cbm__mech_tree_apply(a->p, a->rl, a->vb);
        plane(a, a->va);
        plane(a, a->vb);
        /* N = <t, u - u_pred> with u_pred = base + ds t: Omega's part against base + ds t */
        double nn = a->sigma * a->sigma * tl * (x->lam - lam_p);
        for (size_t i = 0; i < n; i++)
            nn += a->c[i] * v3_dot(t[i], v3_sub(x->om[i], v3_add(base->om[i], v3_scale(t[i], ds))));
        double ta = mdot(a, t, a->va), tb = mdot(a, t, a->vb);
        double den = a->sigma * a->sigma * tl - tb;
        if (!isfinite(den) || den == 0.0)
            return CBM_OK;
        double dl = (ta - nn) / den;
        double big = 0.0, sz = 0.0;
        const double *dual = a->p->work.dual;
        for (size_t i = 0; i < n; i++) {
            cbm_vec3 dv = v3_scale(v3_add(a->va[i], v3_scale(a->vb[i], dl)), -1.0);
            x->om[i] = v3_add(x->om[i], dv);
            double turn = dual[i] * sqrt(v3_norm2(dv));
            big = fmax(big, turn);
            sz += a->c[i] * v3_norm2(dv);
        }
        x->lam += dl;
        if (!isfinite(x->lam) || !(big <= 0.5))
            return CBM_OK;
        /* an update far below the tolerance's scale: converged where the relative residual
         * cannot say so (a straight column: no moments to compare with) */
        tiny = sqrt(sz + a->sigma * a->sigma * dl * dl) < 1e-12;
    }
    return CBM_OK;
}

/* Corrects from base by ds along base's tangent and reads the point (stability included);
 * *ok false when Newton failed or the tip jumped (another branch). */

static cbm_status step_to(arc *a, const arc_point *base, double ds, arc_point *x, int *iters,
                          bool *ok)
{
    CBM_TRY(correct(a, base, base->t, base->tl, ds, x, iters, ok));
    if (!*ok)
        return CBM_OK;
    CBM_TRY(read_point(a->p, a->cfg->tip, x->lam, base->pt.tip_angle_deg, &x->pt));
    const cbm_bend_branch_point *u = &base->pt, *v = &x->pt;
    double turn = a->d->max_turn_deg;
    *ok = fabs(v->tip_angle_deg - u->tip_angle_deg) <= turn &&
          hypot(hypot(v->tip_x - u->tip_x, v->tip_y - u->tip_y), v->tip_z - u->tip_z) <=
              a->cfg->length * turn * CBM_PI / 180.0;
    if (*ok)
        CBM_TRY(tangent(a, x, base, 1.0));
    return CBM_OK;
}

typedef enum ev_kind { EV_FOLD, EV_STAB } ev_kind;

static bool has_event(ev_kind k, const arc_point *a0, const arc_point *x)
{
    if (k == EV_FOLD) /* a tangent along a mode (tl = 0, just after a switch) has no side */
        return (a0->tl > 0.0 && x->tl < 0.0) || (a0->tl < 0.0 && x->tl > 0.0);
    return x->pt.unstable_modes != a0->pt.unstable_modes;
}

/* Bisection of the step from cur: lo (no event yet) and hi (past it) with |hi - lo| in the
 * parameter below min_step of the range, or the step below 1e-12 of ds. */
static cbm_status refine(arc *a, const arc_point *cur, const arc_point *nxt, double ds, ev_kind k,
                         arc_point *lo, arc_point *hi, arc_point *mid)
{
    arc_point_copy(a, lo, cur);
    arc_point_copy(a, hi, nxt);
    double slo = 0.0, shi = ds;
    const double want = a->d->min_step * a->range;
    while (fabs(hi->lam - lo->lam) > want && shi - slo > 1e-12 * ds) {
        double sm = 0.5 * (slo + shi);
        int it = 0;
        bool ok = false;
        CBM_TRY(step_to(a, cur, sm, mid, &it, &ok));
        if (!ok)
            break; /* the bracket stays as it is */
        if (has_event(k, cur, mid)) {
            arc_point_copy(a, hi, mid);
            shi = sm;
        } else {
            arc_point_copy(a, lo, mid);
            slo = sm;
        }
    }
    return CBM_OK;
}

/* the jump target of a fold at lo: the rod solved just past it with the push */
static cbm_status jump_from(arc *a, const arc_point *lo, double dir, cbm_bend_fold *f)
{
    cbm_solve_def sd = a->cfg->sd;
    sd.push_unstable = true;
    put_omega(a, lo->om);
    double pj = lo->lam + dir * fmax(a->d->min_step * a->range, 1e-3 * a->range / a->d->steps);
    CBM_TRY(set_param(a->pc, a->p, pj));
    cbm_solve_stats ss;
    cbm_status st = cbm_plant_solve(a->p, &sd, &ss);
    cbm__mech_work_current(a->p); /* the workspace is read below (solve_order.c) */
    if (st != CBM_OK && st != CBM_E_NOT_CONVERGED)
        return st;
    if (st == CBM_OK) {
        CBM_TRY(read_point(a->p, a->cfg->tip, pj, lo->pt.tip_angle_deg, &f->jump));
        f->jump.jumped = true;
        f->has_jump = true;
    }
    return CBM_OK;
}

/* Leaves the branch at lo along the lowest mode (a bifurcation): lo's tangent becomes the
 * mode (parameter component 0), its sign the one that moves the tip towards +x (+z). */
static cbm_status switch_at(arc *a, arc_point *lo)
{
    put_omega(a, lo->om);
    CBM_TRY(eval_at(a, lo->lam, a->res, NULL));
    double lam = NAN;
    /* on a stable branch the mode crossing 0 is the lowest; past an earlier bifurcation it is
     * the one nearest 0, with the earlier modes below it */
    if (lo->pt.unstable_modes == 0)
        (void)cbm__mech_lowest_mode(a->p, a->va, &lam);
    else
        CBM_TRY(inverse_iteration(a->p, NULL, 0.0, true, a->va, &lam));
    if (!isfinite(lam))
        return cbm__fail(a->ctx, CBM_E_NOT_CONVERGED,
                         "bend continuation: no lowest mode at the bifurcation %.9g", lo->lam);
    /* a mode in the plane (to rounding: a round column's pair of modes resolves towards the
     * plane to 1 %) is followed in the plane; one mostly out of it in 3-D */
    size_t n = a->n;
    double out = 0.0, all = mdot(a, a->va, a->va);
    for (size_t i = 0; i < n; i++)
        out += a->c[i] * (a->va[i].x * a->va[i].x + a->va[i].z * a->va[i].z);
    if (out > 0.1 * all)
        a->planar = false;
    plane(a, a->va);
    /* the tip's displacement along the mode, by a small trial */
    cbm_vec3 x0 = v3(lo->pt.tip_x, lo->pt.tip_y, lo->pt.tip_z);
    double nrm = sqrt(mdot(a, a->va, a->va));
    for (size_t i = 0; i < n; i++)
        a->tmp[i] = v3_add(lo->om[i], v3_scale(a->va[i], 1e-6 / nrm));
    put_omega(a, a->tmp);
    CBM_TRY(eval_at(a, lo->lam, a->res, NULL));
    cbm_segment_state tip, base;
    CBM_TRY(cbm_plant_segment(a->p, a->cfg->tip, &tip));
    CBM_TRY(cbm_plant_segment(a->p, 0, &base));
    cbm_vec3 dx = v3_sub(v3_sub(tip.distal, base.proximal), x0);
    double side = fabs(dx.x) >= fabs(dx.z) ? dx.x : dx.z;
    double sgn = side < 0.0 ? -1.0 : 1.0;
    for (size_t i = 0; i < n; i++)
        lo->t[i] = v3_scale(a->va[i], sgn / nrm);
    lo->tl = 0.0;
    put_omega(a, lo->om);
    return CBM_OK;
}

static cbm_status arc_trace(arc *a, arc_point *cur, arc_point *nxt, arc_point *lo, arc_point *hi,
                            arc_point *mid)
{
    const cbm_bend_continuation_def *d = a->d;
    const double dir = d->to > d->from ? 1.0 : -1.0;
    const double dsmax = a->sigma * a->range / (double)d->steps, dsmin = dsmax * d->min_step;
    double ds = dsmax;
    cbm_bend_branch *b = a->g->b;
    for (;;) {
        if (b->n_points >= d->max_points) {
            b->end = CBM_BEND_END_LIMIT;
            return CBM_OK;
        }
        int it = 0;
        bool ok = false;
        CBM_TRY(step_to(a, cur, ds, nxt, &it, &ok));
        if (!ok) {
            ds *= 0.5;
            if (ds < dsmin)
                return cbm__fail(a->ctx, CBM_E_NOT_CONVERGED,
                                 "bend continuation: the branch cannot be followed beyond %.9g "
                                 "(tip angle %.6g deg)",
                                 cur->lam, cur->pt.tip_angle_deg);
            continue;
        }
        /* the range's ends: land on the end crossed, by Newton at the fixed parameter from the
         * interpolated state */
        bool past_to = dir * (nxt->lam - d->to) >= 0.0,
             past_from = dir * (nxt->lam - d->from) < 0.0;
        if (past_to || past_from) {
            double end = past_to ? d->to : d->from;
            double f = (end - cur->lam) / (nxt->lam - cur->lam);
            for (size_t i = 0; i < a->n; i++) {
                mid->om[i] = v3_add(cur->om[i], v3_scale(v3_sub(nxt->om[i], cur->om[i]), f));
                mid->t[i] = v3(0, 0, 0);
            }
            mid->lam = end;
            mid->tl = 0.0;
            mid->pt = cur->pt;
            /* the hyperplane lambda = end: t = (0, 1 / sigma) */
            memset(lo->t, 0, a->n * sizeof *lo->t);
            CBM_TRY(correct(a, mid, lo->t, 1.0 / a->sigma, 0.0, hi, &it, &ok));
            if (ok) {
                CBM_TRY(read_point(a->p, a->cfg->tip, end, cur->pt.tip_angle_deg, &hi->pt));
                CBM_TRY(push_point(a->g, &hi->pt));
            }
            b->end = past_to ? CBM_BEND_END_TO : CBM_BEND_END_FROM;
            return CBM_OK;
        }
        bool fold = has_event(EV_FOLD, cur, nxt), stab = has_event(EV_STAB, cur, nxt);
        if (fold || stab) {
            ev_kind k = fold ? EV_FOLD : EV_STAB;
            CBM_TRY(refine(a, cur, nxt, ds, k, lo, hi, mid));
            cbm_bend_fold f;
            memset(&f, 0, sizeof f);
            f.fold = fold;
            f.at = lo->pt;
            f.bracket = fabs(hi->lam - lo->lam);
            if (fold)
                CBM_TRY(jump_from(a, lo, cur->tl > 0.0 ? 1.0 : -1.0, &f));
            /* a bifurcation: the count rises without a fold; the chosen one is taken (every
             * one with switch_at 0), the others are reported */
            bool bif = !fold && nxt->pt.unstable_modes > cur->pt.unstable_modes;
            f.bifurcation = bif ? ++a->n_bif : 0;
            bool sw = bif && d->switch_branch &&
                      (d->switch_at == 0 || (f.bifurcation == d->switch_at && !a->switched));
            a->switched = a->switched || sw;
            f.switched = sw;
            CBM_TRY(push_fold(a->g, &f));
            if (lo->lam != cur->lam || lo->pt.tip_angle_deg != cur->pt.tip_angle_deg)
                CBM_TRY(push_point(a->g, &lo->pt));
            if (sw) {
                CBM_TRY(switch_at(a, lo));
                arc_point_copy(a, cur, lo);
                ds = dsmax;
                continue;
            }
            if (hi->lam != nxt->lam || hi->pt.tip_angle_deg != nxt->pt.tip_angle_deg)
                CBM_TRY(push_point(a->g, &hi->pt));
        }
        CBM_TRY(push_point(a->g, &nxt->pt));
        arc_point_copy(a, cur, nxt);
        ds = it <= 3 ? fmin(2.0 * ds, dsmax) : it >= 7 ? 0.5 * ds : ds;
    }
}

static cbm_status trace_arclength(cbm_context *ctx, const cont_cfg *cfg,
                                  const cbm_bend_continuation_def *d, const param_ctx *pc,
                                  cbm_plant *p, growbuf *g)
{
    cbm_solve_def sd;
    cbm_solve_stats ss;
    cbm_status st = start_solve(ctx, cfg, d, pc, p, &sd, &ss);
    if (st != CBM_OK)
        return st;
    const size_t n = cbm_plant_segment_count(p);
    arc a = {.ctx = ctx, .cfg = cfg, .d = d, .pc = pc, .p = p, .n = n, .g = g};
    a.range = fabs(d->to - d->from);
    a.sigma = d->param == CBM_BEND_PARAM_ANGLE ? CBM_PI / 180.0 : 1.0 / a.range;
    a.tol = cfg->sd.tolerance;
    {
        double m0 = 0.0, m1 = 0.0;
        st = moment_scale(&a, d->to, &m1);
        if (st == CBM_OK)
            st = moment_scale(&a, d->from, &m0);
        if (st != CBM_OK)
            return st;
        a.m_ref = fmax(m0, m1);
    }
    {
        const cbm_vec3 *om = cbm_plant_omegas(p);
        double in = 0.0, out = 0.0;
        for (size_t i = 0; i < n; i++) {
            in = fmax(in, fabs(om[i].y));
            out = fmax(out, fmax(fabs(om[i].x), fabs(om[i].z)));
        }
        a.planar = out <= 1e-9 * (in + 1.0 / cfg->length);
    }
    if (n == 0) /* a spec builds at least one segment */
        return CBM_E_INVALID;
    /* one block: c, then 5 work vectors and 5 points of 2 vectors each */
    double *c = malloc(n * sizeof *c);
    cbm_vec3 *blk = malloc(15 * n * sizeof *blk);
    if (!c || !blk) {
        free(c);
        free(blk);
        return CBM_E_NOMEM;
    }
    const double *dual = p->work.dual;
    for (size_t i = 0; i < n; i++)
        c[i] = dual[i] * cfg->length;
    a.c = c;
    a.res = blk, a.rl = blk + n, a.va = blk + 2 * n, a.vb = blk + 3 * n, a.tmp = blk + 4 * n;
    arc_point pts[5];
    for (int k = 0; k < 5; k++) {
        memset(&pts[k], 0, sizeof pts[k]);
        pts[k].om = blk + (5 + 2 * k) * n;
        pts[k].t = blk + (6 + 2 * k) * n;
    }
    arc_point *cur = &pts[0];
    memcpy(cur->om, cbm_plant_omegas(p), n * sizeof *cur->om);
    cur->lam = d->from;
    st = read_point(a.p, cfg->tip, d->from, NAN, &cur->pt);
    if (st == CBM_OK)
        st = push_point(g, &cur->pt);
    if (st == CBM_OK)
        st = tangent(&a, cur, NULL, d->to > d->from ? 1.0 : -1.0);
    if (st == CBM_OK)
        st = arc_trace(&a, cur, &pts[1], &pts[2], &pts[3], &pts[4]);
    free(c);
    free(blk);
    return st;
}

/* The trace of any plant p (its segment count fixed; p is left at the last state traced):
 * the common path of cbm_bend_continue and cbm_plant_continue. */
static cbm_status trace_plant(cbm_context *ctx, const cont_cfg *cfg,
                              const cbm_bend_continuation_def *def, cbm_plant *p,
                              cbm_bend_branch *out)
{
    size_t n = cbm_plant_segment_count(p);
    param_ctx pc = {cfg->spec, def->param, NULL, n, 0.0};
    cbm_vec3 *saved = malloc(n * sizeof *saved);
    pc.len0 = malloc(n * sizeof *pc.len0);
    growbuf g = {out, 0, 0};
    cbm_status st = CBM_E_NOMEM;
    if (saved && pc.len0) {
        st = CBM_OK;
        for (size_t i = 0; i < n && st == CBM_OK; i++) {
            cbm_segment_state s;
            st = cbm_plant_segment(p, i, &s);
            pc.len0[i] = st == CBM_OK ? s.length : 0.0;
            pc.l0 += pc.len0[i];
        }
    }
    if (st == CBM_OK)
        st = def->method == CBM_BEND_CONTINUE_NATURAL ? trace(ctx, cfg, def, &pc, p, &g, saved)
                                                      : trace_arclength(ctx, cfg, def, &pc, p, &g);
    free(saved);
    free(pc.len0);
    if (st != CBM_OK)
        cbm_bend_branch_free(out);
    return st;
}

cbm_status cbm_bend_continue(cbm_context *ctx, const cbm_bend_spec *spec,
                             const cbm_bend_continuation_def *def, cbm_bend_branch *out)
{
    if (!ctx || !spec || !def || !out)
        return CBM_E_INVALID;
    memset(out, 0, sizeof *out);
    CBM_TRY(check_spec(ctx, spec));
    CBM_TRY(check_def(ctx, def));
    cbm_plant *p = NULL;
    CBM_TRY(cbm_bend_build(ctx, spec, &p));
    size_t n = cbm_plant_segment_count(p);
    cont_cfg cfg = {.spec = spec, .sd = cbm_solve_def_default(), .length = spec->length};
    cfg.sd.solver = spec->solver;
    cfg.sd.tolerance = spec->tolerance;
    cfg.sd.max_passes = (size_t)spec->max_passes;
    cfg.sd.krylov_dim = spec->krylov_dim;
    cfg.sd.push_unstable = spec->push_unstable != 0;
    cfg.sd.threads = (int)spec->threads;
    cfg.tip = n - 1;
    cbm_status st = trace_plant(ctx, &cfg, def, p, out);
    cbm_plant_destroy(p);
    return st;
}

cbm_plant_continuation_def cbm_plant_continuation_def_default(void)
{
    cbm_plant_continuation_def d;
    memset(&d, 0, sizeof d);
    d.cont = cbm_bend_continuation_def_default();
    d.solve = cbm_solve_def_default();
    d.solve.solver = CBM_MECH_NEWTON;
    d.tip_segment = SIZE_MAX;
    return d;
}

size_t cbm_plant_main_tip(const cbm_plant *p)
{
    size_t n = cbm_plant_segment_count(p);
    const int64_t *par = cbm_plant_parents(p);
    if (n == 0 || !par)
        return SIZE_MAX;
    /* topological order: the continuation child of the axis' last segment comes after it */
    size_t last = 0;
    for (size_t i = 1; i < n; i++) {
        cbm_segment_state s;
        if (par[i] == (int64_t)last && cbm_plant_segment(p, i, &s) == CBM_OK && s.continuation)
            last = i;
    }
    return last;
}

cbm_status cbm_plant_continue(cbm_context *ctx, cbm_plant *plant,
                              const cbm_plant_continuation_def *def, cbm_bend_branch *out)
{
    if (!ctx || !plant || !def || !out)
        return CBM_E_INVALID;
    memset(out, 0, sizeof *out);
    size_t n = cbm_plant_segment_count(plant);
    if (n == 0)
        return cbm__fail(ctx, CBM_E_INVALID, "plant continuation: the plant has no segment");
    if (def->solve.solver != CBM_MECH_NEWTON)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "plant continuation: needs the Newton solver (the stability count comes "
                         "from its tree factorisation)");
    if (def->cont.param != CBM_BEND_PARAM_ANGLE && def->cont.param != CBM_BEND_PARAM_GRAVITY)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "plant continuation: only the base angle and gravity can be continued "
                         "in a plant built by the caller");
    const int64_t *par = cbm_plant_parents(plant);
    for (size_t i = 1; i < n; i++)
        if (par[i] < 0)
            return cbm__fail(ctx, CBM_E_INVALID,
                             "plant continuation: segment %zu is a second root (one clamp only)",
                             i);
    if (par[0] >= 0)
        return cbm__fail(ctx, CBM_E_INVALID, "plant continuation: segment 0 is not the root");
    if (def->tip_segment != SIZE_MAX && def->tip_segment >= n)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "plant continuation: tip_segment %zu is beyond the %zu segments",
                         def->tip_segment, n);
    if (!(def->length >= 0.0) || !isfinite(def->length))
        return cbm__fail(ctx, CBM_E_INVALID, "plant continuation: length must be >= 0");
    CBM_TRY(check_def(ctx, &def->cont));
    cont_cfg cfg = {.spec = NULL, .sd = def->solve, .length = def->length};
    cfg.tip = def->tip_segment == SIZE_MAX ? cbm_plant_main_tip(plant) : def->tip_segment;
    if (cfg.length == 0.0) /* the main axis's length: the rod's L of a single rod */
        for (int64_t i = (int64_t)cbm_plant_main_tip(plant); i >= 0; i = par[i]) {
            cbm_segment_state s;
            CBM_TRY(cbm_plant_segment(plant, (size_t)i, &s));
            cfg.length += s.length;
        }
    return trace_plant(ctx, &cfg, &def->cont, plant, out);
}
