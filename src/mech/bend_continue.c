/* cambium: continuation of the bend rod's equilibria in a parameter (docs/bend.md,
 * "Continuation"): natural-parameter steps with warm starts and step halving, the stability of
 * every equilibrium, folds located by bisection on the parameter and the jump past each fold.
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

static void set_param(cbm_plant *p, cbm_bend_param which, double v)
{
    if (which == CBM_BEND_PARAM_ANGLE) {
        const cbm_vec3 *pos = cbm_plant_positions(p);
        cbm_vec3 base = pos ? pos[0] : v3(0, 0, 0);
        cbm_plant_set_base(p, base, cbm_mech_clamp_orientation(v * CBM_PI / 180.0));
    } else
        cbm_plant_set_gravity(p, v3(0, -v, 0));
}

/* the branch point of the plant's current (solved) state; prev_deg unwraps the tip angle */
static cbm_status read_point(cbm_plant *p, double param, double prev_deg, cbm_bend_branch_point *o)
{
    size_t n = cbm_plant_segment_count(p);
    cbm_segment_state tip, base;
    CBM_TRY(cbm_plant_segment(p, n - 1, &tip));
    CBM_TRY(cbm_plant_segment(p, 0, &base));
    cbm_quat q;
    CBM_TRY(cbm_plant_distal_frame(p, n - 1, &q));
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
    o->unstable_modes = sb.unstable_modes;
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

static cbm_status check_def(cbm_context *ctx, const cbm_bend_spec *s,
                            const cbm_bend_continuation_def *d)
{
    if (s->solver != CBM_MECH_NEWTON)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "bend continuation: needs solver = fast (the stability count comes from "
                         "its tree factorisation)");
    if (s->steps > 0 || s->duration > 0)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "bend continuation: a spec with growth `steps` or a motion `duration` "
                         "cannot be continued");
    if (!(isfinite(d->from) && isfinite(d->to)) || d->from == d->to)
        return cbm__fail(ctx, CBM_E_INVALID, "bend continuation: FROM and TO must differ");
    if (d->param == CBM_BEND_PARAM_ANGLE && (fabs(d->from) > 360 || fabs(d->to) > 360))
        return cbm__fail(ctx, CBM_E_INVALID, "bend continuation: angle must be -360 .. 360");
    if (d->param == CBM_BEND_PARAM_GRAVITY && (d->from < 0 || d->to < 0))
        return cbm__fail(ctx, CBM_E_INVALID, "bend continuation: gravity must be >= 0");
    if (d->param != CBM_BEND_PARAM_ANGLE && d->param != CBM_BEND_PARAM_GRAVITY)
        return cbm__fail(ctx, CBM_E_INVALID, "bend continuation: unknown parameter");
    if (d->steps < 1 || d->steps > 10000000)
        return cbm__fail(ctx, CBM_E_INVALID, "bend continuation: STEPS must be 1 .. 10^7");
    if (!(d->max_turn_deg > 0 && d->max_turn_deg <= 180) || !(d->min_step > 0 && d->min_step < 1))
        return cbm__fail(ctx, CBM_E_INVALID,
                         "bend continuation: max_turn_deg must be in (0, 180], min_step in (0, 1)");
    return CBM_OK;
}

static cbm_status trace(cbm_context *ctx, const cbm_bend_spec *spec,
                        const cbm_bend_continuation_def *d, cbm_plant *p, growbuf *g,
                        cbm_vec3 *saved)
{
    size_t n = cbm_plant_segment_count(p);
    cbm_solve_def sd = cbm_solve_def_default();
    sd.solver = spec->solver;
    sd.tolerance = spec->tolerance;
    sd.max_passes = (size_t)spec->max_passes;
    sd.krylov_dim = spec->krylov_dim;
    sd.push_unstable = spec->push_unstable != 0;
    set_param(p, d->param, d->from);
    cbm_solve_stats ss;
    cbm_status st = cbm_plant_solve(p, &sd, &ss);
    if (st != CBM_OK)
        return st == CBM_E_NOT_CONVERGED
                   ? cbm__fail(ctx, st, "bend continuation: no equilibrium at the start %g",
                               d->from)
                   : st;
    cbm_bend_branch_point cur;
    CBM_TRY(read_point(p, d->from, NAN, &cur));
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
        set_param(p, d->param, pn);
        st = cbm_plant_solve(p, &sd, &ss);
        if (st != CBM_OK && st != CBM_E_NOT_CONVERGED)
            return st;
        cbm_bend_branch_point np;
        memset(&np, 0, sizeof np);
        bool conv = st == CBM_OK;
        if (conv)
            CBM_TRY(read_point(p, pn, cur.tip_angle_deg, &np));
        /* continuity: the tip turns in the plane and moves (also out of it) by at most what a
         * turn of max_turn_deg of the whole rod would give */
        bool cont = conv && fabs(np.tip_angle_deg - cur.tip_angle_deg) <= d->max_turn_deg &&
                    hypot(hypot(np.tip_x - cur.tip_x, np.tip_y - cur.tip_y),
                          np.tip_z - cur.tip_z) <= spec->length * d->max_turn_deg * CBM_PI / 180.0;
        bool same = cont && np.unstable_modes == cur.unstable_modes;
        if (same) {
            CBM_TRY(push_point(g, &np));
            cur = np;
            pv = pn;
            h = dir * fmin(2.0 * fabs(h), fabs(h0)); /* grow back after a halving */
            continue;
        }
        if (fabs(step) > hmin) { /* bisect: retry from the last equilibrium with half the step */
            restore(p, saved, n);
            set_param(p, d->param, pv);
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
        set_param(p, d->param, pj);
        cbm_solve_def jd = sd;
        jd.push_unstable = true;
        st = cbm_plant_solve(p, &jd, &ss);
        if (st != CBM_OK && st != CBM_E_NOT_CONVERGED)
            return st;
        if (st == CBM_E_NOT_CONVERGED) {
            CBM_TRY(push_fold(g, &f));
            return cbm__fail(ctx, st, "bend continuation: no equilibrium past the fold at %.9g",
                             pv);
        }
        CBM_TRY(read_point(p, pj, cur.tip_angle_deg, &np));
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

cbm_status cbm_bend_continue(cbm_context *ctx, const cbm_bend_spec *spec,
                             const cbm_bend_continuation_def *def, cbm_bend_branch *out)
{
    if (!ctx || !spec || !def || !out)
        return CBM_E_INVALID;
    memset(out, 0, sizeof *out);
    CBM_TRY(check_def(ctx, spec, def));
    cbm_plant *p = NULL;
    CBM_TRY(cbm_bend_build(ctx, spec, &p));
    size_t n = cbm_plant_segment_count(p);
    cbm_vec3 *saved = malloc(n * sizeof *saved);
    growbuf g = {out, 0, 0};
    cbm_status st = saved ? trace(ctx, spec, def, p, &g, saved) : CBM_E_NOMEM;
    free(saved);
    cbm_plant_destroy(p);
    if (st != CBM_OK)
        cbm_bend_branch_free(out);
    return st;
}
