/* The fast statics solver: inexact Newton-Krylov on the joint equilibrium
 *     R(Omega) = C (Omega - rest) - M_local(Omega) = 0      (3 unknowns per segment),
 * with the same forward and backward passes as the relaxation (solve_common.c).
 *
 * THE PIPELINE. cbm__mech_solve_newton runs named stages over one workspace (the plant's
 * cbm__mech_work, one arena block, reserved before the solve: no stage allocates). Each stage
 * starts from the state the one before left and returns DONE (converged at the full load),
 * LARGE (the first Newton step was beyond the trust radius: far from equilibrium), STALL,
 * BUDGET (the pass budget ran out) or NONFINITE. A stage runs only while the result is LARGE or
 * STALL; the one that returns DONE is reported in cbm_solve_stats.stage (enum cbm_solve_stage,
 * named by cbm_solve_stage_name), and the context counts solves by that stage.
 *
 *   stage           runs when                              why
 *   newton          always                                 near equilibrium (small loads, or a
 *                                                          warm start under small changes)
 *                                                          Newton converges quadratically
 *   transient       warm start, tree preconditioner, no    follows the creep of the plant under
 *                   ground, warm_path TRANSIENT (default)  its new loads and passes limit points
 *                                                          (snap-through) in tens of steps
 *   mass-path       warm start whose point masses changed  the quasi-static loading path from
 *                   (warm_path MASS_PATH, or after a       the current equilibrium, point
 *                   stalled transient, which restores the  masses from the balanced ones to the
 *                   start state)                           new ones
 *   load-path       still unresolved (cold starts far      continuation of every load from the
 *                   from equilibrium, stalls above)        rest state (exact at lambda = 0): the
 *                                                          equilibrium on the loading path
 *   relax-bursts    the load path stalled at small         the seeds' relaxation passes between
 *                   increments                             Newton attempts, last resort
 *   (leave_consistent: after a failure, a state evaluated at the full load for the caller)
 *   stability       converged, tree preconditioner         Newton also converges to unstable
 *                                                          equilibria; push off them along the
 *                                                          soft mode and solve again; then the
 *                                                          unstable modes are counted (stats)
 *                                                          and, with push_unstable, the state
 *                                                          pushed along the unstable mode
 *
 * The stages share newton_level (Newton iterations at one load level: tree_step,
 * fgmres_trust, line_search, plain_step_retry), transient() and from_masses(). The order is
 * that of the cost and of the physics: a stage that follows a loading path is taken only when
 * the direct one failed, and the paths from the current state (transient, masses) before the
 * one from rest (which forgets the plant's history, e.g. a snapped-through twig).
 *
 * THE METHODS.
 *
 * - Linear solves: restarted flexible GMRES (Saad & Schultz 1986; Saad 1993), modified
 *   Gram-Schmidt, Givens rotations, RIGHT-preconditioned, either by the elastic stiffness
 *   S = diag(C) (J S^-1 = I - K S^-1, K the load stiffness: close to the identity for moderate
 *   loads) or, by default, by the exact O(n) factorisation of the Newton matrix of the tree
 *   (solve_tree.c). The exact factorisation makes the preconditioned operator the identity,
 *   so GMRES would return P^-1 (-R) after one iteration: the step is taken directly (factor and
 *   solve fused into one pass), and FGMRES with the factorisation as preconditioner is used
 *   only when a joint's pivot block was singular and had to be regularised.
 * - Ground contact (solve_common.c): the factorisation carries the contact stiffness too, so
 *   the step is direct with a ground as without. Organ-organ contact (contact.c) couples two
 *   paths, which it cannot carry: while a pair touches, it preconditions FGMRES, with a
 *   low-rank correction for the pairs' normal stiffness (cbm__mech_pairs_precond).
 * - Jacobian-vector products: the exact tangent (forward-mode) linearisation of the two passes,
 *   cbm__mech_jvp; each product costs one pass (forward + backward tangent sweep) and is counted.
 * - Forcing terms: Eisenstat & Walker (1996) choice 2 (gamma 0.9, exponent 2), at most 0.1.
 * - Globalisation, in three layers:
 *   1. a trust region on rotations: a Newton step is scaled so that no frame turns by more than
 *      MAX_TURN rad (the linearisation of a large rotation overshoots);
 *   2. backtracking line search (Armijo, c = 1e-4, halving up to 12 times) on the merit
 *      |d C^-1 R|_2, the unbalanced rotation of each joint in radians, so that thin twigs and
 *      the trunk weigh alike;
 *   3. load continuation when the start is far from equilibrium (the first full Newton step
 *      would turn a frame by more than MAX_TURN) or Newton stalls (line search fails, or six
 *      heavily damped steps in a row): the loads are scaled by lambda from the rest state
 *      (lambda = 0 is exact there), first increment MAX_TURN / (rotation of the first step),
 *      doubled after an easy level (<= 4 Newton steps), halved after a stall; intermediate
 *      levels solved to 1e-3. This follows the loading path, so the equilibrium reached is the
 *      one the relaxation reaches from rest when several exist (an inclined heavy rod can also
 *      rest curled back over its base);
 *   3a. before that, from a warm start (Omega away from the rest state), by default
 *      (CBM_MECH_WARM_TRANSIENT, no ground contact): pseudo-transient continuation (Kelley &
 *      Keyes 1998; see transient() below), implicit Euler steps of the damped motion
 *      S dOmega/dt = -R from the current state with the O(n) factorisation of J + sigma S.
 *      It follows the creep of the plant under its new loads and passes limit points (a twig
 *      snapping through under new fruit) in tens of steps where the line search on the merit
 *      crawls for hundreds (the merit must rise on the way over the fold). Newton is tried
 *      first and hands over after a heavily cut step or 8 steps. If the transient stalls, the
 *      start state is restored and the quasi-static paths below are taken;
 *   3b. with CBM_MECH_WARM_MASS_PATH, or after a stalled transient, from a warm start whose
 *      point masses changed since the last converged solve: continuation over the point masses
 *      only, from the balanced ones to the new ones (from_masses), which follows the
 *      quasi-static loading path from the current equilibrium;
 *   4. last resort: bursts of 25 relaxation passes (alpha 0.1, halved when a burst does not
 *      help) between Newton attempts at the full load.
 * Stability: where a pivot block of the factorisation is not positive definite, the step is
 * that of J + mu C (Levenberg-Marquardt; mu from 0.1, or a quarter of the last shift needed,
 * times 4 until every pivot is positive definite). From a warm start, a shifted step that
 * finds no decrease and whose slope on the merit is not clearly negative is followed by the
 * plain Newton step (the pivot test fires away from equilibria too); from rest the stall
 * hands over to the continuation. From a warm start the plain step is taken unshifted whenever
 * it descends the total potential energy (slope sum_i d_i R_i . s_i, no tip moments): the pivot
 * test reads the unsymmetric Newton matrix and also fires at stable hanging equilibria of soft
 * stems. After convergence the unmodified factorisation is checked; an equilibrium the solver
 * comes back to after a push along the soft mode is reported stable; if no equilibrium is found
 * from the pushed state, the one found before is kept (with its unstable joints reported).
 * All vectors are in the plant's workspace, allocated before the iteration starts.
 *
 * THE SWEEPS OF A NEWTON STEP (tree factorisation; no ground, no organ pairs). An evaluation is
 * a forward sweep (frames, nodes, base to tips) and a backward sweep that also factorises the
 * Newton matrix and runs the backward half of the step's solve J x = -R (evaluate_as,
 * cbm__mech_backward_factor). Where that factorisation is exact and stable (no singular pivot,
 * none not positive definite) the step is known to be the direct, unshifted Newton step before
 * it is solved, so one forward sweep (fused_step, cbm__mech_tree_step_fused) finishes the solve
 * at each segment, takes the step (work.step), moves Omega by the full step and sets the frame
 * and node there: the line search's first trial (lam = 1), whose evaluation is then its
 * backward sweep alone. The trust region's largest frame turn is the sweep's maximum; where it
 * cuts the step (lam0 < 1, or the first step beyond it: LARGE), Omega is restored from the
 * copy the sweep kept (work.tmp) and the path is the one of the step apart. A converged solve
 * of the 10^6 tree (evaluate, step, evaluate, the stability stage's factorisation taken from
 * the last evaluation) is so a prepare and four sweeps, where a step apart takes five and three
 * loops over the vectors (the copy of the step, its largest turn, Omega += step). The passes are
 * counted as before: the step's solve and the trial's evaluation are one pass each. Where the
 * step is solved apart (a shift, FGMRES, the transient's steps, ground, organ pairs), the
 * solve's result becomes work.step by the two vectors swapping places, not by a copy.
 */
#include "mech/mech_internal.h"
#include "core/vecmath.h"

#include <math.h>

#ifndef MAX_TURN
#define MAX_TURN 0.5
#endif
/* pseudo-transient continuation: largest frame rotation of one step (rad), the relative
 * residual below which the time step may grow without bound (Newton's end game), the step
 * budget */
#define PTC_TURN      0.25
#define PTC_FAR       1e-3
#define PTC_MAX_STEPS 400

typedef struct newton_krylov {
    cbm_plant *p;
    size_t n3; /* 3 n */
    size_t max_passes;
    cbm_solve_stats *st;
    double rel;  /* relative residual of the current state */
    double norm; /* |R|_2 of the current state */
    double rmax, mmax;
    bool tree;         /* tree preconditioner */
    double max_turn;   /* largest frame rotation of one Newton step, rad */
    double first_turn; /* largest frame rotation of the first full Newton step, rad */
    double mu;         /* shift of the last shifted step */
    double mu_hint;    /* the shift the last unstable configuration needed */
    bool plain;        /* take the plain Newton step when a shifted one does not descend */
    bool conservative; /* no tip moments: the loads have a potential energy */
    bool handover;     /* warm start with the transient path: hand over early when Newton crawls */
    /* the pipeline (see the top of the file) */
    double tol;            /* the tolerance of the solve */
    int m;                 /* Krylov dimension */
    bool transient_path;   /* the pseudo-transient stage is on the pipeline */
    cbm_solve_stage stage; /* the stage running (the one that converged once r is NK_DONE) */
    const char *why;       /* why the solve failed, where a stage knows it */
    bool fuse;             /* evaluations fuse the factorisation (cbm__mech_backward_factor) */
    bool push;             /* push an unstable equilibrium off to a stable one */
    bool want_eig;         /* compute the lowest eigenvalue of a stable equilibrium too */
    bool confirm;          /* confirm the pivots' unstable modes by the lowest eigenvalue */
} newton_krylov;

/* the fused evaluations (evaluate_as) and the fused Newton step (tree_step); tests switch them
 * off to compare the bits */
static bool fuse_on = true;
static bool step_fuse_on = true;

void cbm__mech_newton_fuse(bool on)
{
    fuse_on = on;
}

void cbm__mech_newton_fuse_step(bool on)
{
    step_fuse_on = on;
}

/* a . b over the plant's 3 n components, summed in the plant's order (solve_order.c) */
static double dot(const cbm_plant *p, const double *a, const double *b)
{
    double s = 0.0;
    for (size_t k = 0; k < p->n; k++) {
        size_t i = 3 * cbm__mech_at(p, k);
        s += a[i] * b[i];
        s += a[i + 1] * b[i + 1];
        s += a[i + 2] * b[i + 2];
    }
    return s;
}

/* Evaluates R at the current Omega into work.res; false if non-finite. With factor (and
 * k->fuse) the backward sweep also factorises the Newton matrix there and runs the backward
 * half of the Newton step's solve (cbm__mech_backward_factor), for the solve that usually
 * follows (residual_solve, or the factorisation of stage_stability) to finish in its forward
 * half: a pass less, the same bits. Where no such solve follows (a line search's rejected
 * trial, the last evaluation of a continuation level) that work is lost. */
static bool evaluate_sweeps(newton_krylov *k, bool factor, bool forward)
{
    cbm_plant *p = k->p;
    if (forward)
        cbm__mech_forward_eval(p);
    double ss = 0.0;
    double r = factor && k->fuse ? cbm__mech_backward_factor(p, p->work.res, &k->mmax, &ss)
                                 : cbm__mech_backward(p, 0.0, p->work.res, &k->mmax, &ss);
    k->st->passes++;
    if (!isfinite(r))
        return false;
    k->rmax = r;
    k->norm = sqrt(ss);
    k->rel = cbm__mech_relres(r, k->mmax, &k->st->char_moment);
    return true;
}

static bool evaluate_as(newton_krylov *k, bool factor)
{
    return evaluate_sweeps(k, factor, true);
}

static bool evaluate(newton_krylov *k)
{
    return evaluate_as(k, false);
}

/* (J + mu S) work.tmp = -res by the tree factorisation (work.step = -res, the right-hand
 * side): after a fused evaluation at mu = 0 its forward half alone (work.step untouched). Returns
 * the singular pivots, *nonpd those not positive definite. */
static size_t residual_solve(newton_krylov *k, double mu, size_t *nonpd)
{
    cbm_plant *p = k->p;
    cbm__mech_work *w = &p->work;
    size_t sing = 0;
    if (mu == 0.0 && cbm__mech_tree_solve_fused(p, &sing, nonpd))
        return sing; /* the fused sweep read -res itself: step is not needed */
    double *step = (double *)w->step;
    const double *res = (const double *)w->res;
    for (size_t q = 0; q < k->n3; q++)
        step[q] = -res[q];
    return cbm__mech_tree_solve(p, w->step, w->tmp, mu, nonpd);
}

/* z = P^-1 v (the preconditioner) */
static void precond(newton_krylov *k, const double *v, double *z)
{
    cbm_plant *p = k->p;
    if (k->tree) {
        cbm__mech_tree_apply(p, (const cbm_vec3 *)v, (cbm_vec3 *)z);
        k->st->passes++;
        if (cbm__mech_pairs_active(p)) /* touching organ pairs: low-rank correction */
            k->st->passes += cbm__mech_pairs_precond(p, z);
        return;
    }
    const cbm_vec3 *cj = p->work.cj;
    for (size_t i = 0; i < p->n; i++) {
        z[3 * i] = v[3 * i] / cj[i].x;
        z[3 * i + 1] = v[3 * i + 1] / cj[i].y;
        z[3 * i + 2] = v[3 * i + 2] / cj[i].z;
    }
}

/* Flexible GMRES (Saad 1993) for J x = -res with right preconditioning: the preconditioned
 * vectors z_j = P^-1 v_j are kept, so the step is sum g_j z_j without a further solve. The step
 * goes to work.step. Returns false when the pass budget ran out. */
static bool gmres(newton_krylov *k, double eta, int m)
{
    cbm_plant *p = k->p;
    cbm__mech_work *w = &p->work;
    size_t n3 = k->n3;
    double *V = (double *)w->basis;
    double *Z = (double *)w->zbasis;
    double *H = w->hess;                  /* (m+1) x m, column-major: H[j*(m+1) + i] */
    double *cs = H + (size_t)(m + 1) * m; /* m */
    double *sn = cs + m;                  /* m */
    double *g = sn + m;                   /* m + 1 */
    double *x = (double *)w->step;
    memset(x, 0, n3 * sizeof *x);
    const double *res = (const double *)w->res;
    /* the 2-norm of the right-hand side (k->norm is the merit, a scaled norm) */
    double bnorm = sqrt(dot(p, res, res));
    if (bnorm == 0.0)
        return true;
    double target = eta * bnorm;
    double beta = bnorm;
    for (size_t i = 0; i < n3; i++)
        V[i] = -res[i] / beta;
    for (int cycle = 0; cycle < 4; cycle++) {
        memset(g, 0, (size_t)(m + 1) * sizeof *g);
        g[0] = beta;
        int j = 0;
        for (; j < m; j++) {
            if (k->st->passes + 3 >= k->max_passes)
                return false;
            double *vj = V + (size_t)j * n3, *vn = V + (size_t)(j + 1) * n3;
            double *zj = Z + (size_t)j * n3;
            precond(k, vj, zj);
            cbm__mech_jvp(p, (const cbm_vec3 *)zj, (cbm_vec3 *)vn);
            k->st->passes++;
            k->st->krylov_iterations++;
            double *hc = H + (size_t)j * (m + 1);
            for (int i = 0; i <= j; i++) {
                double *vi = V + (size_t)i * n3;
                double h = dot(p, vn, vi);
                hc[i] = h;
                for (size_t q = 0; q < n3; q++)
                    vn[q] -= h * vi[q];
            }
            double hn = sqrt(dot(p, vn, vn));
            hc[j + 1] = hn;
            if (hn > 0.0)
                for (size_t q = 0; q < n3; q++)
                    vn[q] /= hn;
            for (int i = 0; i < j; i++) {
                double a = hc[i], b = hc[i + 1];
                hc[i] = cs[i] * a + sn[i] * b;
                hc[i + 1] = -sn[i] * a + cs[i] * b;
            }
            double a = hc[j], b = hc[j + 1], r = hypot(a, b);
            cs[j] = r > 0.0 ? a / r : 1.0;
            sn[j] = r > 0.0 ? b / r : 0.0;
            hc[j] = r;
            hc[j + 1] = 0.0;
            g[j + 1] = -sn[j] * g[j];
            g[j] = cs[j] * g[j];
            if (fabs(g[j + 1]) <= target || hn == 0.0) {
                j++;
                break;
            }
        }
        /* back substitution: coefficients into g[0..j-1] */
        for (int i = j - 1; i >= 0; i--) {
            double s = g[i];
            for (int c = i + 1; c < j; c++)
                s -= H[(size_t)c * (m + 1) + i] * g[c];
            double d = H[(size_t)i * (m + 1) + i];
            g[i] = d != 0.0 ? s / d : 0.0;
        }
        for (int i = 0; i < j; i++) {
            const double *zi = Z + (size_t)i * n3;
            for (size_t q = 0; q < n3; q++)
                x[q] += g[i] * zi[q];
        }
        /* the Arnoldi estimate says converged: done. Otherwise restart from the true residual
         * -res - J x of the linear system. */
        if (j < m || k->st->passes + 2 >= k->max_passes)
            break;
        cbm__mech_jvp(p, (const cbm_vec3 *)x, (cbm_vec3 *)V);
        k->st->passes++;
        for (size_t q = 0; q < n3; q++)
            V[q] = -res[q] - V[q];
        beta = sqrt(dot(p, V, V));
        if (beta <= target || beta == 0.0)
            break;
        for (size_t q = 0; q < n3; q++)
            V[q] /= beta;
    }
    return true;
}

/* What an iteration or a stage ended with. NK_LARGE: the first Newton step was larger than the
 * trust radius (far from equilibrium: a continuation stage follows); NK_CONTINUE (internal to
 * one Newton iteration): the step is ready, go on. */
typedef enum { NK_DONE, NK_STALL, NK_BUDGET, NK_NONFINITE, NK_LARGE, NK_CONTINUE } nk_result;

/* The largest world rotation of a frame under the full step of the last tree solve (its
 * forward sweep left the rotations in work.dth), rad. */
static double largest_turn(const cbm_plant *p)
{
    double tmax = 0.0;
    for (size_t i = 0; i < p->n; i++) {
        double t = v3_norm2(p->work.dth[i]);
        if (t > tmax)
            tmax = t;
    }
    return sqrt(tmax);
}

/* Does the step d of the shifted system (J + mu C) d = -R clearly descend the merit
 * |d C^-1 R|^2 / 2, i.e. is its slope at most -0.1 |d C^-1 R|^2? The slope needs no pass:
 * J d = -R - mu C d. */
static bool shifted_descends(const newton_krylov *k, const double *d, double mu)
{
    const cbm_plant *p = k->p;
    const cbm__mech_work *w = &p->work;
    const double *res = (const double *)w->res;
    double rr = 0.0, slope = 0.0;
    for (size_t o = 0; o < p->n; o++) { /* the sums in the plant's order (solve_order.c) */
        size_t i = cbm__mech_at(p, o);
        const double c[3] = {w->cj[i].x, w->cj[i].y, w->cj[i].z};
        for (int j = 0; j < 3; j++) {
            double z = w->dual[i] / c[j], r = res[3 * i + j];
            rr += z * z * r * r;
            slope += z * z * r * (-r - mu * c[j] * d[3 * i + j]);
        }
    }
    return slope <= -0.1 * rr;
}

/* The slope of the total potential energy along d, with the right Jacobian of each joint
 * rotation taken as the identity: sum_i d_i R_i . d_i, J/1. The potential (elastic
 * sum_i d_i/2 sum_c C_c (Omega_c - rest_c)^2 plus -f . x of every dead load) has the gradient
 * d_i (C_i (Omega_i - rest_i) - J_r(d_i Omega_i)^T M_i^local), which is d_i R_i up to J_r; the
 * stable equilibria are its minima. No pass: R is that of the current state. */
static double energy_slope(const newton_krylov *k, const double *d)
{
    const cbm_plant *p = k->p;
    const double *res = (const double *)p->work.res;
    double s = 0.0;
    for (size_t o = 0; o < p->n; o++) { /* the sum in the plant's order (solve_order.c) */
        size_t i = cbm__mech_at(p, o);
        s += p->work.dual[i] * (res[3 * i] * d[3 * i] + res[3 * i + 1] * d[3 * i + 1] +
                                res[3 * i + 2] * d[3 * i + 2]);
    }
    return s;
}

/* Backtracking line search (Armijo, c = 1e-4, halving up to 12 times) along work.step from
 * length lam: NK_DONE with the accepted length in *out and the state evaluated there, or
 * NK_STALL with the unmoved state evaluated again. With moved (lam = 1), the fused Newton step
 * (tree_step) has set the first trial's Omega and frames already: its evaluation is the
 * backward sweep alone. */
static nk_result line_search(newton_krylov *k, double lam, double *out, bool moved)
{
    cbm_plant *p = k->p;
    double *om = (double *)p->omega;
    const double *step = (const double *)p->work.step;
    double f0 = k->norm;
    for (int ls = 0; ls < 12; ls++) {
        bool first_moved = moved && ls == 0;
        if (!first_moved)
            for (size_t q = 0; q < k->n3; q++)
                om[q] += lam * step[q];
        if (k->st->passes + 1 >= k->max_passes)
            return NK_BUDGET;
        bool fin = evaluate_sweeps(k, true, !first_moved);
        if (fin && k->norm <= (1.0 - 1e-4 * lam) * f0) {
            *out = lam;
            return NK_DONE;
        }
        for (size_t q = 0; q < k->n3; q++)
            om[q] -= lam * step[q];
        lam *= 0.5;
    }
    if (!evaluate_as(k, true)) /* restore the state of the unmoved Omega */
        return NK_NONFINITE;
    return NK_STALL;
}

/* The trust region on rotations: the step length that limits the largest frame rotation tmax of
 * the full step to max_turn radians (the linearisation of a large rotation overshoots). */
static double trust_for_turn(newton_krylov *k, int it, double tmax)
{
    if (it == 0)
        k->first_turn = tmax;
    return tmax > k->max_turn ? k->max_turn / tmax : 1.0;
}

/* trust_for_turn with the largest turn the forward sweep of the last tree solve or tangent pass
 * left in work.dth */
static double trust_length(newton_krylov *k, int it)
{
    return trust_for_turn(k, it, largest_turn(k->p));
}

/* The fused Newton step (cbm__mech_tree_step_fused): where the fused evaluation's
 * factorisation is exact and stable (no singular pivot, none not positive definite, no organ
 * pairs), the step is known to be direct and unshifted before it is solved, so its forward
 * sweep also moves Omega by the full step and sets the frames there, the line search's first
 * trial (lam = 1). Only the trust region is known after the sweep: where it cuts the step
 * (lam0 < 1, or NK_LARGE), Omega is restored from work.tmp, the bits before the sweep, and the
 * path is that of the step apart (the frames of the trial are not read: every path evaluates
 * first). Returns false where the conditions do not hold (the caller solves apart). */
static bool fused_step(newton_krylov *k, int it, bool abort_large, double *lam0, bool *moved,
                       nk_result *r)
{
    cbm_plant *p = k->p;
    const cbm__mech_work *w = &p->work;
    /* the line search's first trial must run (its budget check, after this solve's pass); the
     * factorisation's conditions are cbm__mech_tree_step_fused's */
    if (!step_fuse_on || !k->fuse || cbm__mech_pairs_active(p) ||
        k->st->passes + 2 >= k->max_passes)
        return false;
    double turn = 0.0;
    if (!cbm__mech_tree_step_fused(p, &turn))
        return false;
    k->st->passes++;
    size_t *count = cbm__context_counters(p->ctx);
    count[CBM__MECH_COUNT_STEP_FUSED]++;
    *lam0 = trust_for_turn(k, it, turn);
    *moved = !(*lam0 < 1.0);
    if (!*moved) {
        memcpy(p->omega, w->tmp, p->n * sizeof *p->omega);
        count[CBM__MECH_COUNT_STEP_RESTORED]++;
    }
    *r = it == 0 && abort_large && *lam0 < 1.0 ? NK_LARGE : NK_CONTINUE;
    return true;
}

/* work.step = work.tmp, the solve's result: the two vectors swap places (no reader takes tmp
 * for the step's copy after this). */
static void take_tmp_as_step(cbm__mech_work *w)
{
    cbm_vec3 *t = w->step;
    w->step = w->tmp;
    w->tmp = t;
}

/* The step of one Newton iteration by the tree factorisation (work.step), with the
 * Levenberg-Marquardt shift where the configuration is unstable. *direct: the factorisation was
 * exact (no singular pivot, no touching organ pairs), so the step is the Newton step and needs
 * no FGMRES; *shifted: it is the step of J + mu S; *lam0: the trust region's length; *moved:
 * the fused step (fused_step) has set the line search's first trial (lam0 = 1).
 * NK_CONTINUE, or NK_BUDGET, or NK_LARGE (first step beyond the trust radius, abort_large). */
static nk_result tree_step(newton_krylov *k, int it, bool abort_large, bool *direct, bool *shifted,
                           double *lam0, bool *moved)
{
    cbm_plant *p = k->p;
    cbm__mech_work *w = &p->work;
    *moved = false;
    nk_result fr = NK_CONTINUE;
    if (fused_step(k, it, abort_large, lam0, moved, &fr)) {
        *direct = true;
        *shifted = false;
        return fr;
    }
    /* factor and solve J step = -res in one pass; trusted when no pivot was singular (the
     * factorisation is then exact and GMRES would stop after one iteration with this very
     * step); otherwise the factorisation preconditions FGMRES */
    size_t nonpd = 0;
    size_t sing = residual_solve(k, 0.0, &nonpd);
    k->st->passes++;
    /* from a warm start, a plain Newton step that descends the potential energy is taken even
     * where the pivot test fires: the test reads the symmetric part of pivots of the
     * unsymmetric Newton matrix (dead loads, large joint rotations), and it also fires at the
     * stable equilibrium of a soft hanging chain or a twig that snapped through, where the
     * shifted steps converge only linearly (a rate of about 0.8 per step). A step that descends
     * the energy heads for a minimum, not for a balanced unstable state; the check after
     * convergence still applies. */
    if (nonpd > 0 && sing == 0 && k->plain && k->conservative &&
        energy_slope(k, (const double *)w->tmp) < 0.0)
        nonpd = 0;
    /* an unstable configuration: Newton would head for the unstable equilibrium; shift by mu S
     * (Levenberg-Marquardt) until every pivot is positive definite, which gives a descent
     * towards a stable one */
    double mu = 0.0;
    /* start a quarter below the shift the last step needed (Levenberg-Marquardt memory: an
     * unstable region usually persists over several steps) */
    double m0 = k->mu_hint > 0.4 ? 0.25 * k->mu_hint : 0.1;
    for (double m1 = m0; nonpd > 0 && m1 < 1e8; m1 *= 4.0) {
        if (k->st->passes + 3 >= k->max_passes)
            return NK_BUDGET;
        mu = m1;
        k->mu = mu;
        sing = residual_solve(k, mu, &nonpd);
        k->st->passes++;
    }
    take_tmp_as_step(w);
    /* touching organ pairs couple two paths, which the factorisation does not hold: it then
     * preconditions FGMRES (contact.c) */
    *direct = sing == 0 && !cbm__mech_pairs_active(p);
    *shifted = mu > 0.0 && *direct;
    if (mu > 0.0)
        k->mu_hint = mu;
    *lam0 = trust_length(k, it);
    if (it == 0 && abort_large && *lam0 < 1.0 && (*direct || !cbm__mech_pairs_active(p)))
        return NK_LARGE; /* far from equilibrium: follow the load path instead */
    return NK_CONTINUE;
}

/* The trust region from an FGMRES step with touching organ pairs (the factorisation's own step
 * ignores what it lacks): one tangent pass. NK_CONTINUE or NK_LARGE as in tree_step. */
static nk_result fgmres_trust(newton_krylov *k, int it, bool abort_large, double *lam0)
{
    cbm_plant *p = k->p;
    cbm__mech_jvp(p, p->work.step, p->work.tmp);
    k->st->passes++;
    *lam0 = trust_length(k, it);
    if (it == 0 && abort_large && *lam0 < 1.0)
        return NK_LARGE;
    return NK_CONTINUE;
}

/* The plain-step retry after a shifted step found no decrease from a warm start. The pivot test
 * is a sign of instability at an equilibrium only: away from one (a warm start under new loads)
 * the load stiffness of dead loads is not symmetric, the test also fires where a stable
 * equilibrium is near, and the shifted step need not descend the merit (its slope is known:
 * J d = -R - mu C d). The plain Newton step is tried instead; the stability check after
 * convergence handles an unstable equilibrium. (From rest the stall hands over to the load
 * continuation, the loading path.) Returns the line search's result, *lam0 and *lam updated. */
static nk_result plain_step_retry(newton_krylov *k, double eta, int m, double *lam0, double *lam)
{
    cbm_plant *p = k->p;
    cbm__mech_work *w = &p->work;
    if (k->st->passes + 3 >= k->max_passes)
        return NK_BUDGET;
    size_t nonpd = 0;
    size_t sing = residual_solve(k, 0.0, &nonpd);
    k->st->passes++;
    take_tmp_as_step(w);
    if (sing == 0 && !cbm__mech_pairs_active(p)) {
        double tmax = largest_turn(p);
        *lam0 = tmax > k->max_turn ? k->max_turn / tmax : 1.0;
    } else if (!gmres(k, eta, m))
        return NK_BUDGET;
    *lam = *lam0;
    return line_search(k, *lam0, lam, false);
}

/* Newton iterations at the current load level until rel < tol: the step (tree_step, or FGMRES),
 * the trust region, the line search (with plain_step_retry), the forcing term. */
static nk_result newton_level(newton_krylov *k, double tol, int m, bool abort_large)
{
    cbm_plant *p = k->p;
    if (!evaluate_as(k, true))
        return NK_NONFINITE;
    double eta = 0.1, prev = k->norm;
    int small = 0;
    for (int it = 0; it < 60; it++) {
        if (k->rel < tol)
            return NK_DONE;
        if (k->st->passes + 3 >= k->max_passes)
            return NK_BUDGET;
        bool direct = false, shifted = false, moved = false;
        double lam0 = 1.0;
        nk_result r = NK_CONTINUE;
        if (k->tree)
            r = tree_step(k, it, abort_large, &direct, &shifted, &lam0, &moved);
        if (r != NK_CONTINUE)
            return r;
        if (!direct && !gmres(k, eta, m))
            return NK_BUDGET;
        if (!direct && k->tree && cbm__mech_pairs_active(p))
            r = fgmres_trust(k, it, abort_large, &lam0);
        if (r != NK_CONTINUE)
            return r;
        k->st->newton_steps++;
        double lam = lam0;
        nk_result ls = line_search(k, lam0, &lam, moved);
        /* (work.step is read where it is now: the solves swap it with work.tmp) */
        if (ls == NK_STALL && shifted && k->plain &&
            !shifted_descends(k, (const double *)p->work.step, k->mu))
            ls = plain_step_retry(k, eta, m, &lam0, &lam);
        if (ls != NK_DONE)
            return ls;
        /* the transient path takes over from a crawling Newton (it passes folds in tens of
         * steps where the line search needs hundreds) */
        if (k->handover && (lam < 0.125 * lam0 || it >= 8))
            return NK_STALL;
        /* slow progress (heavily damped steps again and again): let the caller globalise */
        small = lam <= 1.0 / 16.0 ? small + 1 : 0;
        if (small >= 6)
            return NK_STALL;
        /* Eisenstat-Walker choice 2 */
        double ratio = k->norm / prev;
        double e = 0.9 * ratio * ratio, safe = 0.9 * eta * eta;
        if (safe > 0.1 && safe > e)
            e = safe;
        eta = e < 0.1 ? e : 0.1;
        if (eta < 1e-6)
            eta = 1e-6;
        prev = k->norm;
    }
    return NK_STALL;
}

/* Pseudo-transient continuation (Kelley & Keyes 1998; Coffey, Kelley & Keyes 2003) from the
 * current state: implicit Euler steps of the damped motion S dOmega/dt = -R (S = diag(C) of the
 * joints, the metric of the seeds' relaxation, whose passes are explicit Euler steps of the same
 * motion), (J + sigma S) d = -R with sigma = 1/dt, solved by the tree factorisation of J + sigma S
 * (solve_tree.c). The motion follows the plant creeping under its new loads: where a twig has
 * passed a limit point it swings through to the equilibrium an overdamped motion reaches
 * (hanging), without the merit having to decrease. Step control:
 *   - sigma starts at 1 (dt of the elastic relaxation time: S^-1 J = I for light loads) and
 *     falls with the residual (switched evolution relaxation, sigma_k = sigma_k-1 |R_k|/|R_k-1|)
 *     or with the step's largest frame rotation t, whichever falls faster, sigma *= min(|R_k| /
 *     |R_k-1|, t / PTC_TURN), so that steps grow to the trust radius; the end game is Newton's,
 *     quadratic;
 *   - the step is scaled so that no frame turns by more than PTC_TURN rad, and while a step had
 *     to be scaled and the relative residual is above PTC_FAR (a large motion) sigma stays >= 1,
 *     so that such steps are damped-motion steps, not Newton jumps into another basin;
 *   - where a pivot block of J + sigma S is not positive definite (or singular) sigma is
 *     raised (x4) before the step is taken, unless the loads are conservative and the step
 *     descends the potential energy (the pivot test also fires at stable hanging states, see
 *     newton_level);
 *   - a step that makes the state non-finite, or the merit more than 4 times larger and above
 *     PTC_TURN rad, is undone and sigma raised (x4) (near an unstable equilibrium the merit
 *     grows from tiny values as the motion leaves it; that is no reason to stop it).
 * The potential energy itself is no merit here: the residual is its gradient only up to the
 * right Jacobian of each joint rotation (R_i = C (Omega - rest) - M_local, the gradient is
 * d_i (C (Omega - rest) - J_r^T M_local)); on the fruit tree, states with relative residuals of
 * 1e-2 exist where -S^-1 R ascends the energy, and an energy test then stalls the motion.
 * One step costs one factor-and-solve pass and one evaluation pass. */
static nk_result transient(newton_krylov *k, double tol)
{
    cbm_plant *p = k->p;
    cbm__mech_work *w = &p->work;
    size_t n3 = k->n3;
    double *om = (double *)p->omega;
    if (!evaluate(k))
        return NK_NONFINITE;
    double sigma = 1.0;
    for (int it = 0; it < PTC_MAX_STEPS; it++) {
        if (k->rel < tol)
            return NK_DONE;
        if (k->st->passes + 4 >= k->max_passes)
            return NK_BUDGET;
        double s = sigma;
        for (;;) {
            size_t nonpd = 0;
            size_t sing = residual_solve(k, s, &nonpd);
            k->st->passes++;
            if (sing == 0 &&
                (nonpd == 0 || (k->conservative && energy_slope(k, (const double *)w->tmp) < 0.0)))
                break;
            s = s < 0.01 ? 0.01 : 4.0 * s;
            if (s > 1e8)
                return NK_STALL;
            if (k->st->passes + 4 >= k->max_passes)
                return NK_BUDGET;
        }
        sigma = s;
        take_tmp_as_step(w);
        const double *step = (const double *)w->step;
        /* the forward sweep of the solve left the frame rotations of the full step in dth */
        double turn = largest_turn(p);
        double lam = turn > PTC_TURN ? PTC_TURN / turn : 1.0;
        double prev = k->norm;
        for (size_t q = 0; q < n3; q++)
            om[q] += lam * step[q];
        bool fin = evaluate(k);
        k->st->newton_steps++;
        if (!fin || (k->norm > 4.0 * prev && k->norm > PTC_TURN)) {
            for (size_t q = 0; q < n3; q++)
                om[q] -= lam * step[q];
            if (!evaluate(k))
                return NK_NONFINITE;
            sigma = sigma < 0.01 ? 0.01 : 4.0 * sigma;
            continue;
        }
        double f = k->norm / prev, g = turn / PTC_TURN;
        sigma *= f < g ? f : g;
        if (k->rel > PTC_FAR && lam < 1.0 && sigma < 1.0)
            sigma = 1.0;
        if (sigma < 1e-12)
            sigma = 0.0;
    }
    return NK_STALL;
}

/* Load continuation from the current state: the point masses go from those the start state
 * balances (the last converged solve; 0 on segments added since) to the new ones, m(lambda) =
 * m0 + lambda (m - m0), every other load at full value. For a local change on a grown plant
 * (fruit and leaves appearing and growing) this follows the physical loading path from the
 * current equilibrium instead of re-bending the whole plant from rest. Step control as in the
 * continuation from rest. */
static nk_result from_masses(newton_krylov *k, double tol, int m, double dl)
{
    cbm_plant *p = k->p;
    cbm__mech_work *w = &p->work;
    size_t n = p->n;
    memcpy(w->save, p->omega, n * sizeof *w->save);
    double done = 0.0;
    nk_result r = NK_STALL;
    for (;;) {
        double lam = done + dl < 1.0 ? done + dl : 1.0;
        memcpy(p->omega, w->save, n * sizeof *p->omega);
        p->mass_path = lam;
        cbm__mech_prepare(p);
        k->st->continuation_steps++;
        size_t ns = k->st->newton_steps;
        r = newton_level(k, lam < 1.0 ? (tol > 1e-3 ? tol : 1e-3) : tol, m, false);
        if (r == NK_DONE) {
            if (lam >= 1.0)
                break;
            done = lam;
            memcpy(w->save, p->omega, n * sizeof *w->save);
            if (k->st->newton_steps - ns <= 4)
                dl *= 2.0;
        } else if (r == NK_STALL) {
            dl *= 0.5;
            if (dl < 1.0 / 256)
                break;
        } else
            break;
    }
    p->mass_path = 1.0;
    cbm__mech_prepare(p);
    return r;
}

/* ---- the stages (see the pipeline at the top of the file) ---- */

static bool unresolved(nk_result r)
{
    return r == NK_LARGE || r == NK_STALL;
}

/* The first load increment of a continuation: the one that turns the largest frame by about
 * max_turn when the full step was too large (NK_LARGE), else a quarter; in [1/64, 1/2]. */
static double first_increment(const newton_krylov *k, nk_result r)
{
    double dl = r == NK_LARGE && k->first_turn > 0 ? k->max_turn / k->first_turn : 0.25;
    return dl < 1.0 / 64 ? 1.0 / 64 : (dl > 0.5 ? 0.5 : dl);
}

/* Stage "newton": Newton at the full load from the start state (the rest state, or the last
 * equilibrium on a warm start). With the tree factorisation it gives up at once when the first
 * step is beyond the trust radius (NK_LARGE), and on the transient path it hands over early
 * when the steps crawl. */
static nk_result stage_newton(newton_krylov *k)
{
    cbm_plant *p = k->p;
    k->stage = CBM_SOLVE_STAGE_NEWTON;
    if (k->transient_path)
        memcpy(p->work.start, p->omega, p->n * sizeof *p->work.start);
    k->handover = k->transient_path;
    nk_result r = newton_level(k, k->tol, k->m, k->tree);
    k->handover = false;
    return r;
}

/* Stage "transient": pseudo-transient continuation from the warm start (transient()). A stall
 * restores the start state for the quasi-static stages. */
static nk_result stage_transient(newton_krylov *k)
{
    cbm_plant *p = k->p;
    k->stage = CBM_SOLVE_STAGE_TRANSIENT;
    k->st->continuation_steps++;
    nk_result r = transient(k, k->tol);
    if (r == NK_STALL) /* the quasi-static paths below, from the start state */
        memcpy(p->omega, p->work.start, p->n * sizeof *p->omega);
    return r;
}

/* Stage "mass-path": continuation over the point masses from the warm start (from_masses()).
 * A budget that ran out with passes to spare (the steps of one level) counts as a stall, so
 * the load path may still try. */
static nk_result stage_mass_path(newton_krylov *k, nk_result r)
{
    k->stage = CBM_SOLVE_STAGE_MASS_PATH;
    r = from_masses(k, k->tol, k->m, first_increment(k, r));
    if (r == NK_BUDGET && k->st->passes + 3 < k->max_passes)
        r = NK_STALL;
    return r;
}

/* Stage "load-path": load continuation from the rest state (lambda = 0 is exact there): the
 * loads are scaled by lambda, the increment doubled after an easy level (<= 4 Newton steps) and
 * halved after a stall; intermediate levels are solved to 1e-3. The equilibrium reached is the
 * one on the loading path, as with the relaxation. */
static nk_result stage_load_path(newton_krylov *k, nk_result r)
{
    cbm_plant *p = k->p;
    cbm__mech_work *w = &p->work;
    cbm_solve_stats *st = k->st;
    double tol = k->tol;
    k->stage = CBM_SOLVE_STAGE_LOAD_PATH;
    double done = 0.0;
    double dl = first_increment(k, r);
    for (size_t i = 0; i < p->n; i++)
        w->save[i] = w->rj[i];
    for (;;) {
        double lam = done + dl < 1.0 ? done + dl : 1.0;
        memcpy(p->omega, w->save, p->n * sizeof *p->omega);
        p->load_scale = lam;
        cbm__mech_prepare(p);
        st->continuation_steps++;
        size_t ns = st->newton_steps;
        r = newton_level(k, lam < 1.0 ? (tol > 1e-3 ? tol : 1e-3) : tol, k->m, false);
        if (r == NK_DONE) {
            if (lam >= 1.0)
                break;
            done = lam;
            memcpy(w->save, p->omega, p->n * sizeof *p->omega);
            if (st->newton_steps - ns <= 4)
                dl *= 2.0;
        } else if (r == NK_STALL) {
            dl *= 0.5;
            if (dl < 1e-4) {
                k->why = "Newton stalled even with small load steps";
                break;
            }
        } else
            break;
    }
    return r;
}

/* Stage "relax-bursts", the last resort: bursts of 25 relaxation passes (the seeds' iteration,
 * alpha 0.1, halved when a burst does not help) between Newton attempts at the full load, from
 * the furthest state the load path reached; at most 8 bursts. */
static nk_result stage_relax_bursts(newton_krylov *k)
{
    cbm_plant *p = k->p;
    cbm_solve_stats *st = k->st;
    k->stage = CBM_SOLVE_STAGE_RELAX_BURSTS;
    p->load_scale = 1.0;
    cbm__mech_prepare(p);
    double ra = 0.1;
    nk_result r = NK_STALL;
    for (int burst = 0; r == NK_STALL && burst < 8; burst++) {
        double before = k->norm;
        for (int it = 0; it < 25 && st->passes + 2 < k->max_passes; it++) {
            cbm__mech_forward_eval(p);
            double mm;
            double rr = cbm__mech_backward(p, ra, NULL, &mm, NULL);
            st->passes++;
            if (!isfinite(rr))
                break;
        }
        r = newton_level(k, k->tol, k->m, false);
        if (r == NK_STALL && !(k->norm < before))
            ra *= 0.5;
        st->continuation_steps++;
    }
    return r;
}

/* After the quasi-static stages failed: a consistent state at the full load for the caller to
 * read. */
static nk_result leave_consistent(newton_krylov *k, nk_result r)
{
    k->p->load_scale = 1.0;
    cbm__mech_prepare(k->p);
    if (r != NK_NONFINITE && !evaluate(k))
        r = NK_NONFINITE;
    return r;
}

/* The motion off an unstable equilibrium after a push along its unstable mode: implicit Euler
 * steps of the damped motion S dOmega/dt = -R with a time step 1/sigma, sigma at least
 * sigma_min (twice the magnitude of the unstable eigenvalue, so that J + sigma S is positive
 * definite along the mode and every step moves further away from the saddle instead of back
 * to it, as the adaptive sigma of transient() does near it), each turning no frame by more
 * than PTC_TURN; once the unshifted tangent has no negative pivot eigenvalue (the basin of a
 * stable equilibrium, convex there) Newton finishes. */
static nk_result leave_unstable(newton_krylov *k, double sigma_min)
{
    cbm_plant *p = k->p;
    cbm__mech_work *w = &p->work;
    size_t n3 = k->n3;
    double *om = (double *)p->omega;
    for (int it = 0; it < PTC_MAX_STEPS; it++) {
        if (!evaluate_as(k, true)) /* factorised below */
            return NK_NONFINITE;
        if (k->rel < k->tol)
            return NK_DONE; /* an equilibrium: the caller reads its stability */
        if (k->st->passes + 4 >= k->max_passes)
            return NK_BUDGET;
        size_t nonpd = 0;
        cbm__mech_tree_factor(p, 0.0, &nonpd);
        k->st->passes++;
        if (w->fneg == 0)
            return newton_level(k, k->tol, k->m, false);
        double s = sigma_min;
        for (;;) {
            size_t sing = residual_solve(k, s, &nonpd);
            k->st->passes++;
            if (sing == 0 && nonpd == 0)
                break;
            s *= 2.0;
            if (s > 1e8 || k->st->passes + 4 >= k->max_passes)
                return NK_STALL;
        }
        double turn = largest_turn(p);
        double lam = turn > PTC_TURN ? PTC_TURN / turn : 1.0;
        const double *d = (const double *)w->tmp;
        for (size_t q = 0; q < n3; q++)
            om[q] += lam * d[q];
        k->st->newton_steps++;
    }
    return NK_STALL;
}

/* The unstable modes of the converged state (stability.c): the inertia of the Hessian's tree
 * pivots, confirmed by the lowest eigenvalue of S^-1 J (a count it does not confirm is the pivot
 * test misreading an unsymmetric tangent, see stage_stability, and is reported as 0). Where the
 * state is unstable and k->push is set, the plant is pushed along the unstable mode both ways
 * (largest frame turn 0.1 rad), each push relaxed by the damped motion (leave_unstable()), and the
 * stable equilibrium of least total potential energy kept; if neither push ends stable the
 * equilibrium found is kept and reported. The diagnosis of a stable state costs one
 * factorisation (not counted in `passes`, so that stable solves report what they did before),
 * none when `factored` says the workspace already holds the unmodified factorisation of this
 * very state (stage_stability's last one, nothing moved since: the same bits, one sweep less);
 * the pushes are counted. */
static nk_result stability_modes(newton_krylov *k, bool factored)
{
    cbm_plant *p = k->p;
    cbm__mech_work *w = &p->work;
    cbm_solve_stats *st = k->st;
    if (!factored) {
        size_t nonpd = 0;
        cbm__mech_tree_factor(p, 0.0, &nonpd);
    }
    size_t modes = w->fneg;
    st->unstable_modes = 0;
    st->lowest_eigenvalue = NAN;
    if (modes == 0 && !k->want_eig)
        return NK_DONE;
    if (!k->confirm) { /* the pivots' count, unconfirmed (cbm_solve_def.confirm_modes) */
        st->unstable_modes = modes;
        return NK_DONE;
    }
    double lam = NAN;
    (void)cbm__mech_lowest_mode(p, w->start, &lam);
    st->lowest_eigenvalue = lam;
    if (modes == 0 || !(lam < 0.0))
        return NK_DONE;
    st->unstable_modes = modes;
    if (!k->push)
        return NK_DONE;
    memcpy(w->save, p->omega, p->n * sizeof *w->save);
    double turn = cbm__mech_mode_turn(p, w->start);
    double eps = turn > 0.0 ? 0.1 / turn : 0.0;
    double best_e = INFINITY;
    size_t best_modes = modes, best_nonpd = st->unstable_joints;
    double best_lam = lam;
    for (int sign = 1; sign >= -1 && eps > 0.0; sign -= 2) {
        for (size_t i = 0; i < p->n; i++)
            p->omega[i] = v3_add(w->save[i], v3_scale(w->start[i], sign * eps));
        st->continuation_steps++;
        nk_result tr = leave_unstable(k, 2.0 * -lam);
        if (tr != NK_DONE)
            continue;
        size_t np = 0;
        cbm__mech_tree_factor(p, 0.0, &np);
        st->passes++;
        if (w->fneg != 0) {
            /* confirmed by the lowest eigenvalue only (as for the reported count) */
            double l2 = NAN;
            (void)cbm__mech_lowest_mode(p, w->res, &l2); /* res: scratch here */
            if (!(l2 >= 0.0))
                continue;
        }
        double e = cbm__mech_energy(p);
        if (e < best_e) {
            best_e = e;
            best_modes = 0;
            best_nonpd = np;
            memcpy(w->best, p->omega, p->n * sizeof *w->best);
        }
    }
    if (best_modes == 0) {
        memcpy(p->omega, w->best, p->n * sizeof *p->omega);
        k->stage = CBM_SOLVE_STAGE_STABILITY;
        best_lam = NAN;
        if (k->want_eig) {
            if (!evaluate(k))
                return NK_NONFINITE;
            (void)cbm__mech_lowest_mode(p, w->start, &best_lam);
        }
    } else
        memcpy(p->omega, w->save, p->n * sizeof *p->omega);
    st->unstable_modes = best_modes;
    st->unstable_joints = best_nonpd;
    st->lowest_eigenvalue = best_lam;
    return evaluate(k) ? NK_DONE : NK_NONFINITE;
}

/* Stage "stability", after convergence with the tree factorisation: Newton converges to
 * unstable equilibria too (a branch balanced upright). The unmodified factorisation is checked
 * at the solution; where a pivot block is not positive definite, the joint is pushed along its
 * soft mode and the level solved again with the modified factorisation, which descends to a
 * stable equilibrium (up to 3 pushes). The converged stage becomes "stability" when a push
 * ends at another equilibrium. */
static nk_result stage_stability(newton_krylov *k)
{
    cbm_plant *p = k->p;
    cbm__mech_work *w = &p->work;
    cbm_solve_stats *st = k->st;
    nk_result r = NK_DONE;
    bool factored = false; /* the workspace holds the factorisation of the current state */
    for (int attempt = 0; attempt < 4; attempt++) {
        size_t nonpd = 0;
        cbm__mech_tree_factor(p, 0.0, &nonpd);
        st->passes++;
        st->unstable_joints = nonpd;
        if (nonpd == 0 || attempt == 3 || st->passes + 4 >= k->max_passes) {
            factored = true;
            break;
        }
        memcpy(w->save, p->omega, p->n * sizeof *w->save);
        cbm__mech_tree_perturb_unstable(p, 0.05);
        st->continuation_steps++;
        r = newton_level(k, k->tol, k->m, false);
        if (r != NK_DONE) {
            /* no equilibrium found from the pushed state: keep the one found before */
            memcpy(p->omega, w->save, p->n * sizeof *p->omega);
            r = evaluate(k) ? NK_DONE : NK_NONFINITE;
            break;
        }
        /* back at the same equilibrium (every joint within 1e-6 rad of it) after a push of
         * 0.05 rad along the soft mode: the steps descend the energy there (plain ones only
         * where they do), so this is a minimum along that mode and the pivot test misread the
         * unsymmetric Newton matrix (large joint rotations under heavy dead loads) */
        double back = 0.0;
        for (size_t i = 0; i < p->n; i++) {
            cbm_vec3 dv = v3_sub(p->omega[i], w->save[i]);
            double a = w->dual[i] * fmax(fabs(dv.x), fmax(fabs(dv.y), fabs(dv.z)));
            back = a > back ? a : back;
        }
        if (back < 1e-6) {
            st->unstable_joints = 0;
            break;
        }
        k->stage = CBM_SOLVE_STAGE_STABILITY;
    }
    if (r == NK_DONE)
        r = stability_modes(k, factored);
    return r;
}

/* The solve's status from the pipeline's result, with the reason of a failure. */
static cbm_status finish(newton_krylov *k, nk_result r)
{
    cbm_plant *p = k->p;
    cbm_solve_stats *st = k->st;
    if (r == NK_NONFINITE)
        return cbm__mech_report_nonfinite(p);
    st->residual = k->rel;
    if (r == NK_DONE) {
        st->stage = k->stage;
        return CBM_OK;
    }
    const char *why = k->why;
    if (r == NK_BUDGET || st->passes + 4 >= k->max_passes)
        why = "the pass budget ran out";
    else if (!why && r == NK_STALL && st->continuation_steps == 1)
        why = "Newton stalled";
    else if (!why)
        why = "Newton stalled; neither load continuation nor relaxation bursts reached the "
              "tolerance";
    return cbm__fail(p->ctx, CBM_E_NOT_CONVERGED,
                     "fast solver: relative residual %.3g after %zu passes (tolerance %.3g): %s",
                     k->rel, st->passes, k->tol, why);
}

/* Have the point masses changed since the last converged solve? */
static bool masses_changed(const cbm_plant *p)
{
    for (size_t i = 0; i < p->n; i++)
        if (p->pmass0[i] != p->pmass[i])
            return true;
    return false;
}

/* The pipeline (see the top of the file). */
cbm_status cbm__mech_solve_newton(cbm_plant *p, const cbm_solve_def *def, size_t max_passes,
                                  cbm_solve_stats *st)
{
    newton_krylov k;
    memset(&k, 0, sizeof k);
    k.p = p;
    k.n3 = 3 * p->n;
    k.max_passes = max_passes;
    k.st = st;
    k.tree = def->preconditioner == CBM_MECH_PRECOND_TREE;
    k.max_turn = MAX_TURN;
    k.conservative = !p->work.tip_moment; /* cbm_plant_solve prepared the workspace */
    k.m = def->krylov_dim;
    k.tol = def->tolerance;
    k.push = def->push_unstable;
    k.want_eig = def->eigenvalue;
    k.confirm = def->confirm_modes || k.push || k.want_eig;
    k.stage = CBM_SOLVE_STAGE_NONE;
    cbm__mech_work *w = &p->work;

    p->load_scale = 1.0; /* cbm_plant_solve prepared the joint arrays at this load */
    st->continuation_steps = 1;
    k.fuse = k.tree && fuse_on;
    /* a start away from the rest state is a warm start (the previous equilibrium under
     * changed loads) */
    k.plain = false;
    for (size_t i = 0; i < p->n && !k.plain && !w->at_rest; i++)
        k.plain = p->omega[i].x != w->rj[i].x || p->omega[i].y != w->rj[i].y ||
                  p->omega[i].z != w->rj[i].z;
    w->at_rest = false; /* this solve's: a solve again (organ pairs) starts where it ended */
    /* the transient path from a warm start (the factorisation solves J + sigma S; with ground
     * contact it lacks the contact stiffness) */
    k.transient_path = k.plain && k.tree && !p->ground && def->warm_path == CBM_MECH_WARM_TRANSIENT;

    nk_result r = stage_newton(&k);
    if (unresolved(r) && k.transient_path)
        r = stage_transient(&k);
    if (unresolved(r) && k.plain && masses_changed(p))
        r = stage_mass_path(&k, r);
    if (unresolved(r)) {
        r = stage_load_path(&k, r);
        if (r == NK_STALL)
            r = stage_relax_bursts(&k);
        if (r != NK_DONE)
            r = leave_consistent(&k, r);
    }
    p->load_scale = 1.0;
    if (r == NK_DONE && k.tree)
        r = stage_stability(&k);
    cbm__mech_fused_clear(p); /* nothing outside the solve reads the fused factorisation */
    return finish(&k, r);
}
