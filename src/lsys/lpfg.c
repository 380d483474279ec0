/* The L+C-style (lpfg) dialect of the L-system engine: the host of a compiled model (lang/lc.h,
 * compiled by lang/lc_parse.c, run as register code or native code, lang/lc_code.h) and its
 * derivation over the packed module string.
 *
 * Derivation (one step): StartEach; the string is scanned left to right (Forward(), default) or
 * right to left (Backward()); for each module the productions of the active group whose
 * predecessor and contexts match are tried in order, and the first whose body executes
 * `produce` rewrites the module (a body that ends without producing passes to the next
 * production; no production: the module is copied). The new context `<<` / `>>` reads the
 * string being produced (already rewritten neighbours); in Backward mode the output is built
 * reversed and turned around at the end of the step, so the new right context is a left walk
 * of the partial output. Then a separate decomposition pass (recursive to `maximum depth`),
 * then EndEach; End after the last step. The interpretation rules produce the image the turtle
 * reads (cbm_lsys_apply_homomorphism). Context scanning follows lpfg's scanners: going right,
 * branches the pattern does not enter are skipped and a pattern `EB()` skips to the end of the
 * current branch; going left, `[` is climbed out of and whole branches are skipped;
 * `ignore:`/`consider:` modules are passed over.
 */
#include "lang/lc.h"
#include "lang/lc_code.h"
#include "lsys/lsys_internal.h"
#include "lsys/mechlang_internal.h"

#include <ctype.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

typedef struct lpfg lpfg;
struct lpfg {
    lc_model m;       /* the compiled model (lang/lc.h) */
    lc_vm vm;         /* globals, frames, budgets, the first runtime error (lang/lc_code.h) */
    lc_program prog;  /* the functions compiled to register code */
    double *ret;      /* where `return v;` writes v (in a function) */
    cbm__crand crand; /* rand(): the C library's random() */
    bool backward;
    int group;
    lstr *out;     /* where produce appends */
    bool produced; /* produce executed */
    int prod_ix;
    cbm__walk scan[LC_CTX_N];
    lstr succ;
    CBM_ARRAY(lstr) scratch;
    bool nonfinite_warned;
    cbm__mechlang mech; /* mechanics: declarations and settings */
    /* models with mechanics: the module of the string each module of the interpretation came
     * from (empty: the interpretation is the string itself) */
    CBM_ARRAY(size_t) origin;
    bool rewriting; /* inside a derivation pass: mechanics calls are refused */
    /* the axiom's string, when its code reads nothing of the run (keep_axiom): reset copies it
     * and the code is freed (a 400000-module axiom's code is 12.5 MB, its string 0.4 MB) */
    lstr axiom;
    bool axiom_kept;
};

/* ---------------------------------------------------------------- evaluation */
static void rt_error(lpfg *lp, cbm_status s, const char *msg)
{
    cbm__lc_error(&lp->vm, s, msg);
}

static bool spend_operation(lpfg *lp, bool loop)
{
    return cbm__lc_spend(&lp->vm, loop);
}

static bool match_context(cbm_lsys *ls, int k, int32_t first, int32_t n, double *fr);

/* The mechanics built-ins (lsys/mechlang.c) over the current string, at their na arguments
 * (at most 6; 0 for a missing one); the result to out[0]. */
static void call_mech(cbm_lsys *ls, const lc_node *n, const double *arg, int na, double *out)
{
    lpfg *lp = ls->lp;
    out[0] = 0; /* every path that stops on an error leaves a defined value */
    double a[6] = {0, 0, 0, 0, 0, 0};
    na = na < 6 ? na : 6;
    memcpy(a, arg, (size_t)na * sizeof(double));
    cbm__mechlang *m = &lp->mech;
    char msg[128];
    switch ((cbm__fn)n->fn) {
    case FN_GRAVITY:
        m->gravity = (cbm_vec3){a[0], a[1], a[2]};
        return;
    case FN_GROUND:
        if (!isfinite(a[0]) || !(a[1] >= 0) || !isfinite(a[1]) || !(a[2] >= 0) || !isfinite(a[2])) {
            rt_error(lp, CBM_E_INVALID,
                     "Ground(height y0 m, stiffness k >= 0 N/m, smoothing >= 0 m)");
            return;
        }
        m->ground_y = a[0];
        m->ground_k = a[1];
        m->ground_s = a[2];
        return;
    case FN_CONTACT:
        if (!(a[0] >= 0) || !isfinite(a[0]) || !(a[1] >= 0) || !isfinite(a[1])) {
            rt_error(lp, CBM_E_INVALID, "Contact(stiffness k >= 0 N/m, smoothing >= 0 m)");
            return;
        }
        m->contact_k = a[0];
        m->contact_s = a[1];
        return;
    case FN_TROPISM:
        m->tropism.direction = (cbm_vec3){a[0], a[1], a[2]};
        m->tropism.strength = a[3];
        return;
    case FN_PIPEMODEL:
        if (!(a[0] > 0) || !(a[1] >= 0))
            rt_error(lp, CBM_E_INVALID, "PipeModel(exponent > 0, leaf area >= 0 m^2)");
        m->growth.pipe_exponent = a[0];
        m->growth.leaf_area = a[1];
        return;
    case FN_WOOD:
        if (!(a[0] > 0) || !(a[1] >= a[0]) || !(a[2] >= 0) || !(a[3] >= 0) || !(a[4] >= 0)) {
            rt_error(lp, CBM_E_INVALID,
                     "Wood(E_juvenile > 0, E_adult >= E_juvenile, adult age >= 0, density >= 0, "
                     "modulus of rupture >= 0)");
            return;
        }
        m->growth.youngs_juvenile = a[0];
        m->growth.youngs_adult = a[1];
        m->growth.adult_age = a[2];
        m->growth.density = a[3];
        m->growth.modulus_of_rupture = a[4];
        return;
    case FN_RINGRATE:
        if (!(a[0] > 0 && a[0] <= 1) || !(a[1] >= 0) || !isfinite(a[1])) {
            rt_error(lp, CBM_E_INVALID, "RingRate(kappa in (0, 1], min_ring >= 0 m)");
            return;
        }
        m->growth.pipe_rate = a[0];
        m->growth.min_ring = a[1];
        return;
    case FN_SOLVER:
        if (!(a[0] > 0) || !isfinite(a[0]) || !(a[1] >= 0) || !(a[1] <= 1e12) ||
            !(a[2] == 0 || a[2] == 1)) {
            rt_error(lp, CBM_E_INVALID,
                     "Solver(tolerance > 0, max passes >= 0 (0: the context's limit), go on 0 or "
                     "1)");
            return;
        }
        m->solve.tolerance = a[0];
        m->solve.max_passes = (size_t)a[1];
        m->go_on = a[2] == 1;
        return;
    case FN_SOLVERMETHOD: {
        /* the value of cbm_mech_solver: 0 relax, 1 fast, 2 approx, ... (docs/methods.md) */
        if (!(a[0] >= 0) || !(a[0] < CBM_MECH_SOLVER_COUNT) || a[0] != floor(a[0])) {
            char names[64], why[150];
            cbm_mech_solver_names(names, sizeof names);
            snprintf(why, sizeof why, "SolverMethod(n): n is 0 .. %d, in the order %s",
                     CBM_MECH_SOLVER_COUNT - 1, names);
            rt_error(lp, CBM_E_INVALID, why);
            return;
        }
        /* a method imposed by the caller (cbm_lsys_def.solver) wins over the model's */
        if (ls->solver_override < 0)
            m->solve.solver = (cbm_mech_solver)(int)a[0];
        return;
    }
    case FN_APPROXLOAD:
        /* the value of cbm_approx_load: 0 the thesis's tip load, 1 calibrated (L+C's default,
         * mechlang.c; docs/methods.md) */
        if (!(a[0] == CBM_APPROX_LOAD_TIP || a[0] == CBM_APPROX_LOAD_CALIBRATED)) {
            rt_error(lp, CBM_E_INVALID,
                     "ApproxLoad(n): n is 0 (thesis: the tip load) or 1 "
                     "(calibrated, the default)");
            return;
        }
        m->solve.approx_load = (cbm_approx_load)(int)a[0];
        return;
    case FN_SOLVERTHREADS:
        /* cbm_solve_def.threads of every later Equilibrium(): results never depend on it */
        if (!(a[0] >= 0 && a[0] <= 1024 && a[0] == floor(a[0]))) {
            rt_error(lp, CBM_E_INVALID,
                     "SolverThreads(n): n is a whole number 0 .. 1024 (0: one per processor)");
            return;
        }
        m->solve.threads = (int)a[0];
        return;
    case FN_REACTION:
        if (!(a[0] >= 0) || !(a[1] >= 0 && a[1] <= 1) || !(a[2] >= 0) || !(a[3] >= 0)) {
            rt_error(lp, CBM_E_INVALID,
                     "ReactionWood(threshold >= 0 rad/m, beta in [0, 1], increment >= 0 m, "
                     "E_reaction >= 0 Pa)");
            return;
        }
        m->growth.reaction_threshold = a[0];
        m->growth.reaction_beta = a[1];
        m->growth.reaction_increment = a[2];
        m->growth.reaction_youngs = a[3];
        return;
    case FN_SWAYMODES:
        /* the modal motion of the next Sway()s (docs/language.md, docs/dynamics.md) */
        if (!(a[0] >= 0 && a[0] <= 1e9 && a[0] == floor(a[0])) || !(a[1] == 0 || a[1] == 1) ||
            (a[0] == 0 && a[1] == 1)) {
            rt_error(lp, CBM_E_INVALID,
                     "SwayModes(K: 0 (the full motion) or the number of modes, static "
                     "correction: 0 or 1 (with K > 0))");
            return;
        }
        m->dyn_args[7] = a[0];
        m->dyn_args[8] = a[1];
        return;
    case FN_REACTIONBOUND:
        /* the largest a/b reaction wood makes (docs/growth.md): real stems stay within 1.5 */
        if (!(isfinite(a[0]) && (a[0] == 0 || a[0] >= 1))) {
            rt_error(lp, CBM_E_INVALID, "ReactionBound(max a/b: 0 (no bound) or >= 1)");
            return;
        }
        m->growth.reaction_max_aspect = a[0];
        return;
    default:
        break;
    }
    if (lp->rewriting) {
        rt_error(lp, CBM_E_INVALID,
                 "mechanics operations are refused during a derivation pass; call them in "
                 "Start, StartEach, EndEach or End");
        return;
    }
    if (n->fn == FN_LIGHT) {
        /* the leaves' light (lightlang.c); the string's structure is unchanged */
        if (!(a[0] >= 0 && a[0] <= CBM_SKY_SOC && a[0] == floor(a[0])) ||
            !(a[1] >= 1 && a[1] <= 16 && a[1] == floor(a[1]))) {
            rt_error(lp, CBM_E_INVALID,
                     "Light(sky, samples): sky 0 dome, 1 field, 2 uniform overcast, 3 standard "
                     "overcast; samples 1..16");
            return;
        }
        cbm_status s =
            cbm__lightlang_run(ls->ctx, m, &ls->cur, (int)a[0], (int)a[1], out, msg, sizeof msg);
        if (s != CBM_OK) {
            char full[160];
            snprintf(full, sizeof full, "Light(): %s", msg);
            rt_error(lp, s, full);
            out[0] = 0;
        }
        ls->homo_valid = false;
        return;
    }
    if (n->fn == FN_FREQUENCY && !(a[0] >= 1 && a[0] <= 1000 && a[0] == floor(a[0]))) {
        rt_error(lp, CBM_E_INVALID, "Frequency(k): k must be an integer 1..1000");
        return;
    }
    if (n->fn == FN_SWAY) {
        if (!(a[0] > 0 && a[1] > 0 && a[1] <= a[0] && a[0] / a[1] <= 1e7 && a[2] >= 0 &&
              a[3] >= 0 && isfinite(a[0]) && isfinite(a[2]) && isfinite(a[3]))) {
            rt_error(lp, CBM_E_INVALID,
                     "Sway(duration s > 0, 0 < dt <= duration (at most 1e7 steps), wind m/s "
                     ">= 0, gust intensity >= 0)");
            return;
        }
        if (na == 6 && !(a[4] >= 0 && a[5] >= 0 && isfinite(a[4]) && isfinite(a[5]))) {
            rt_error(lp, CBM_E_INVALID,
                     "SwayDrag(duration, dt, wind, gust, gust coherence decay >= 0, leaf area "
                     ">= 0 m^2/kg)");
            return;
        }
        memcpy(m->dyn_args, a, 6 * sizeof(double));
        m->dyn_args[6] = na == 6 ? 1.0 : 0.0;
    }
    int op = n->fn == FN_EQUILIBRIUM ? CBM__ML_EQUILIBRIUM
             : n->fn == FN_ADDRINGS  ? CBM__ML_RINGS
             : n->fn == FN_AGEWOOD   ? CBM__ML_AGE
             : n->fn == FN_STABILITY ? CBM__ML_STABILITY
             : n->fn == FN_FREQUENCY ? CBM__ML_FREQUENCY
             : n->fn == FN_SWAY      ? CBM__ML_SWAY
                                     : CBM__ML_BREAK;
    double r = 0;
    cbm_status s =
        cbm__mechlang_run(ls->ctx, m, &ls->cur, op, a[0], &r, msg, sizeof msg, &ls->mech_time);
    if (s != CBM_OK) {
        char full[160];
        snprintf(full, sizeof full, "%s(): %s",
                 n->fn == FN_EQUILIBRIUM ? "Equilibrium"
                 : n->fn == FN_ADDRINGS  ? "AddRings"
                 : n->fn == FN_AGEWOOD   ? "AgeWood"
                 : n->fn == FN_STABILITY ? "Stability"
                 : n->fn == FN_FREQUENCY ? "Frequency"
                 : n->fn == FN_SWAY      ? (na == 6 ? "SwayDrag" : "Sway")
                                         : "Break",
                 msg);
        rt_error(lp, s, full);
        return;
    }
    ls->homo_valid = false;
    out[0] = r;
}

/* printf (node n) with its arguments' values v (a string argument's is unused: its text is the
 * node's) to the context's output sink. */
static void print(cbm_lsys *ls, const lc_node *n, const double *v)
{
    lpfg *lp = ls->lp;
    cbm__fmt_arg args[CBM__FMT_MAX_ARGS];
    int k = 0;
    const char *strings = ls->comp.strings.data;
    for (int32_t x = n->child1; x >= 0 && k < CBM__FMT_MAX_ARGS;
         x = lp->m.nodes.data[x].next, k++) {
        const lc_node *an = &lp->m.nodes.data[x];
        args[k].s = an->op == N_STR ? strings + an->slot : NULL;
        args[k].v = an->op == N_STR ? 0 : v[k];
    }
    cbm__fmt_print(ls->ctx, strings + n->slot, args, k);
}

/* The built-ins that act on the run's state (random numbers, func, derivation control, stop)
 * at arguments a (0 for a missing one), converted to the node's type (O_HOST through
 * lpfg_host). */
static double host_builtin(cbm_lsys *ls, const lc_node *n, const double *a)
{
    lpfg *lp = ls->lp;
    double r = 0;
    switch ((cbm__fn)n->fn) {
    case FN_RAN:
        r = cbm__rand48_next(&ls->ev.rnd.r48) * a[0];
        break;
    case FN_NRAN: {
        double v, f;
        cbm__random_normal(&ls->ev.rnd, &v, &f);
        r = a[0] + a[1] * v * f;
        break;
    }
    case FN_DRAND:
        r = cbm__rand48_next(&ls->ev.rnd.r48);
        break;
    case FN_RAND:
        r = cbm__crand_next(&lp->crand);
        break;
    case FN_SRAND: {
        long long s = cbm__to_ll(a[0]);
        cbm__crand_seed(&lp->crand, (uint32_t)s);
        cbm__random_seed(&ls->ev.rnd, s);
        break;
    }
    case FN_FUNC:
        if (!ls->func)
            rt_error(lp, CBM_E_RUNTIME,
                     "func(name, x) needs function files (.func or .fset) on the command line");
        else
            r = ls->func(ls->func_ud, lp->m.funcids.data[n->slot - 1], a[0]);
        break;
    case FN_FORWARD:
        lp->backward = false;
        break;
    case FN_BACKWARD:
        lp->backward = true;
        break;
    case FN_USEGROUP:
        lp->group = (int)cbm__to_ll(a[0]);
        break;
    case FN_CURGROUP:
        r = lp->group;
        break;
    case FN_STOP:
        ls->ev.stopped = true;
        break;
    default:
        break;
    }
    return lc_conv_scalar(n->type == T_VOID ? T_DOUBLE : n->type, r);
}

/* O_HOST of the register code (lc_vm.host_call): built-in node ip->imm at its ip->src2
 * arguments in registers ip->src1.. */
static double lpfg_host(lc_vm *vm, const lc_ins *ip, double *fr)
{
    cbm_lsys *ls = vm->host;
    lpfg *lp = ls->lp;
    const lc_node *n = &lp->m.nodes.data[(int32_t)ip->imm];
    const double *arg = fr + ip->src1;
    if (ip->subop == LC_HOST_CONTEXT) /* InLeftContext ...: the formals bound in the frame */
        return match_context(ls, n->fn, n->child1, n->child2, fr);
    if (n->fn == FN_PRINTF) {
        print(ls, n, arg);
        return 0;
    }
    if (n->fn >= FN_EQUILIBRIUM && n->fn <= FN_REACTIONBOUND) {
        double out = 0;
        call_mech(ls, n, arg, ip->src2, &out);
        return out;
    }
    double a[2] = {0, 0};
    for (int i = 0; i < ip->src2 && i < 2; i++)
        a[i] = arg[i];
    return host_builtin(ls, n, a);
}

/* ---------------------------------------------------------------- the module string */
/* appends module `code` with its np parameters p to s */
static cbm_status push_module(cbm_context *ctx, lstr *s, int code, const double *p, int np)
{
    CBM_TRY(cbm__lstr_room(ctx, s, 1, 1, (size_t)np));
    s->sym[s->n++] = (uint8_t)(code | (np ? LSYS_PARAM_BIT : 0));
    if (np) {
        s->pc[s->npm++] = (uint8_t)np;
        double *d = (double *)s->par + s->npar;
        for (int q = 0; q < np; q++) /* a parameter or two: a loop, not a library call */
            d[q] = p[q];
        s->npar += (size_t)np;
    }
    return CBM_OK;
}

/* position after the last module (dir +1), or at the last module (dir -1: logical start) */
static cbm__walk walk_end(const lstr *s, int dir)
{
    if (dir > 0)
        return cbm__walk_at(s, s->n, s->npm, s->npar, 1);
    cbm__walk w = cbm__walk_at(s, s->n, s->npm, s->npar, -1);
    if (s->n)
        cbm__walk_prev_in_memory(&w);
    else
        w.mod = -1;
    return w;
}

/* The bracket table of the string a right context walks (generate_pass sets them; outside it
 * they describe no string and the walks scan). */
static cbm__brackets *brackets_of(cbm_lsys *ls, const cbm__walk *w)
{
    return &ls->brackets[w->dir > 0 ? 0 : 1];
}

/* Moves w (reading rightwards) to the next module a right context sees, which must be `code`:
 * modules not considered are passed over, branches the pattern does not enter are skipped, a
 * pattern EB() first goes to the end of the current branch. */
static bool accept_right(cbm_lsys *ls, cbm__walk *w, int code)
{
    const lpfg *lp = ls->lp;
    int sbc = lp->m.mods.data[lp->m.sb_module].code, ebc = lp->m.mods.data[lp->m.eb_module].code;
    if (!cbm__walk_inside(w))
        return false;
    if (code == ebc && !cbm__walk_to_branch_end(ls->ctx, brackets_of(ls, w), w, sbc, ebc))
        return false;
    while (cbm__walk_inside(w) && cbm__walk_symbol(w) != code) {
        int c = cbm__walk_symbol(w);
        if (!lp->m.considered[c])
            cbm__walk_forward(w);
        else if (c == sbc) {
            if (!cbm__walk_skip_branch(ls->ctx, brackets_of(ls, w), w, sbc, ebc))
                return false;
            cbm__walk_forward(w);
        } else
            break;
    }
    return cbm__walk_inside(w) && cbm__walk_symbol(w) == code;
}

/* Moves w (reading leftwards) to the previous module a left context sees, which must be
 * `code`: modules not considered and SBs are passed over (a branch is climbed out of), whole
 * branches are skipped. */
static bool accept_left(const lpfg *lp, cbm__walk *w, int code)
{
    int sbc = lp->m.mods.data[lp->m.sb_module].code, ebc = lp->m.mods.data[lp->m.eb_module].code;
    if (!cbm__walk_backward(w))
        return false;
    while (cbm__walk_inside(w) && cbm__walk_symbol(w) != code) {
        int c = cbm__walk_symbol(w);
        if (!lp->m.considered[c] || c == sbc) {
            if (!cbm__walk_backward(w))
                return false;
        } else if (c == ebc) {
            if (!cbm__walk_backward(w) || !cbm__walk_to_branch_start(w, sbc, ebc) ||
                !cbm__walk_backward(w))
                return false;
        } else
            break;
    }
    return cbm__walk_inside(w) && cbm__walk_symbol(w) == code;
}

static void bind_formals(cbm_lsys *ls, const cbm__walk *w, int32_t formals, double *fr)
{
    lpfg *lp = ls->lp;
    if (!(w->s->sym[w->mod] & LSYS_PARAM_BIT))
        return;
    const double *p = (const double *)w->s->par + w->param;
    for (int32_t f = formals; f >= 0; f = lp->m.nodes.data[f].next) {
        const lc_node *x = &lp->m.nodes.data[f];
        int sz = lc_type_size(&lp->m, x->type);
        memcpy(fr + x->slot, p, (size_t)sz * sizeof(double));
        p += sz;
    }
}

/* Matches pattern [first, first+n) of context k from the scanner's position; on success the
 * scanner moves past it and the formals are bound. */
static bool match_context(cbm_lsys *ls, int k, int32_t first, int32_t n, double *fr)
{
    lpfg *lp = ls->lp;
    cbm__walk w = lp->scan[k];
    if (!w.s)
        return false;
    if (k == LC_CTX_RIGHT || k == LC_CTX_NEW_RIGHT) {
        for (int32_t i = 0; i < n; i++) {
            const lc_modref *m = &lp->m.sms.data[first + i];
            if (!accept_right(ls, &w, lp->m.mods.data[m->mod].code))
                return false;
            cbm__walk_forward(&w);
        }
        /* bind after the whole pattern matched */
        cbm__walk b = lp->scan[k];
        for (int32_t i = 0; i < n; i++) {
            const lc_modref *m = &lp->m.sms.data[first + i];
            accept_right(ls, &b, lp->m.mods.data[m->mod].code);
            bind_formals(ls, &b, m->args, fr);
            cbm__walk_forward(&b);
        }
    } else {
        for (int32_t i = n; i-- > 0;) {
            const lc_modref *m = &lp->m.sms.data[first + i];
            if (!accept_left(lp, &w, lp->m.mods.data[m->mod].code))
                return false;
        }
        cbm__walk b = lp->scan[k];
        for (int32_t i = n; i-- > 0;) {
            const lc_modref *m = &lp->m.sms.data[first + i];
            accept_left(lp, &b, lp->m.mods.data[m->mod].code);
            bind_formals(ls, &b, m->args, fr);
        }
    }
    lp->scan[k] = w;
    return true;
}

/* A parameter of a produced module is infinite or NaN (division by zero, overflow): an error
 * at the argument's expression, or with limits.allow_nonfinite a warning (once per run) and
 * the value is kept. Returns whether to go on. */
static bool nonfinite(cbm_lsys *ls, int32_t pos, const char *module)
{
    lpfg *lp = ls->lp;
    if (!cbm_context_limits(ls->ctx)->allow_nonfinite) {
        char msg[160];
        snprintf(msg, sizeof msg,
                 "a parameter of %.60s is not a finite number (--allow-nonfinite keeps it)",
                 module);
        rt_error(lp, CBM_E_RUNTIME, msg);
        lp->vm.err_pos = pos;
        return false;
    }
    if (!lp->nonfinite_warned) {
        lp->nonfinite_warned = true;
        const char *file;
        int line, col;
        cbm__compiler_locate(&ls->comp, (size_t)pos, &file, &line, &col);
        cbm__diag(ls->ctx, CBM_WARNING, file, line, col,
                  "a parameter of %s is not a finite number (kept: --allow-nonfinite; further "
                  "ones are not reported)",
                  module);
    }
    return true;
}

/* `produce` of a compiled body (lc_vm.produce): module sm with its parameters v, computed and
 * converted by the register code; checked and appended as produce() does. */
static bool produce_compiled(void *ud, int smi, const double *v)
{
    cbm_lsys *ls = ud;
    lpfg *lp = ls->lp;
    const lc_modref *sm = &lp->m.sms.data[smi];
    const lc_module *m = &lp->m.mods.data[sm->mod];
    int off = 0, a = 0;
    for (int32_t x = sm->args; x >= 0; x = lp->m.nodes.data[x].next, a++) {
        int sz = lc_type_size(&lp->m, m->ptype[a]);
        for (int q = 0; q < sz; q++)
            if (!isfinite(v[off + q]) && !nonfinite(ls, lp->m.nodes.data[x].pos, m->name))
                return false;
        off += sz;
    }
    cbm_status s = push_module(ls->ctx, lp->out, m->code, v, m->size);
    if (s != CBM_OK) {
        rt_error(lp, s, "out of memory");
        return false;
    }
    return true;
}

/* ---------------------------------------------------------------- derivation */
/* The execution budgets of a step (and of the Start block, global initialisers and axiom). */
static void set_budgets(cbm_lsys *ls)
{
    const cbm_limits *lim = cbm_context_limits(ls->ctx);
    ls->lp->vm.budget = ls->loop_budget > 0 ? ls->loop_budget : lim->max_loop_iterations;
    ls->lp->vm.max_call_depth = lim->max_call_depth;
    ls->lp->vm.ops = lim->max_operations;
}

static cbm_status run_error(cbm_lsys *ls, const char *what)
{
    lpfg *lp = ls->lp;
    cbm_status s = lp->vm.err;
    lp->vm.err = CBM_OK;
    if (lp->vm.err_pos >= 0)
        return cbm__compiler_fail(&ls->comp, s, (size_t)lp->vm.err_pos, "%s: %s", what,
                                  lp->vm.errmsg);
    return cbm__fail(ls->ctx, s, "%s: %s", what, lp->vm.errmsg);
}

/* Runs fn[f] of the program (a block, a global's initialiser, the axiom, an expression of the
 * header: each compiled when the model was loaded, lpfg_parse checks it) on the stack; its
 * value. */
static double run_root(cbm_lsys *ls, size_t f)
{
    lpfg *lp = ls->lp;
    lp->vm.sp = (size_t)lp->prog.fn[f].nreg;
    double r = cbm__lc_run(&lp->prog, (int)f, lp->vm.stack, &lp->vm);
    lp->vm.sp = 0;
    return r;
}

static cbm_status run_block(cbm_lsys *ls, int which)
{
    static const char *const NAMES[] = {"Start", "StartEach", "EndEach", "End"};
    lpfg *lp = ls->lp;
    if (lp->m.blocks[which] < 0)
        return CBM_OK;
    (void)run_root(ls, lp->prog.block0 + (size_t)which);
    return lp->vm.err != CBM_OK ? run_error(ls, NAMES[which]) : CBM_OK;
}

/* Tries the productions of `set` on the module at (i, j, k) of src; produced modules go to
 * out. nxt: the partial new string (new context), NULL outside the generative pass. Returns the
 * number of modules the predecessor covers (0: none applied); going Backward the module at i is
 * the last of them, else the first. */
static int try_rewrite(cbm_lsys *ls, const lc_rules *set, const lstr *src, size_t i, size_t j,
                       size_t k, const lstr *nxt, lstr *out)
{
    lpfg *lp = ls->lp;
    int m = lp->m.bycode[src->sym[i] & 0x7f];
    bool back = nxt && lp->backward;
    int which = set == &lp->m.main ? LC_MAIN : set == &lp->m.decomp ? LC_DECOMP : LC_INTERP;
    /* the productions of the active group first, then those of group 0 (as lpfg) */
    for (int pass = lp->group != 0 ? 0 : 1; pass < 2; pass++)
        for (size_t p = 0; p < set->prods.len; p++) {
            const lc_production *pr = &set->prods.data[p];
            int32_t np = pr->pred.n;
            int32_t anchor = back ? np - 1 : 0;
            if (lp->m.sms.data[pr->pred.first + anchor].mod != m ||
                pr->group != (pass == 0 ? lp->group : 0))
                continue;
            double *fr = lp->vm.stack;
            lp->vm.sp = (size_t)pr->fsize;
            cbm__walk first = cbm__walk_at(src, i, j, k, 1);
            bool ok = true;
            for (int32_t a = 0; a < anchor && ok; a++) {
                if (first.mod == 0)
                    ok = false;
                else
                    cbm__walk_prev_in_memory(&first);
            }
            cbm__walk w = first;
            for (int32_t a = 0; a < np && ok; a++) {
                const lc_modref *pm = &lp->m.sms.data[pr->pred.first + a];
                if (!cbm__walk_inside(&w) ||
                    cbm__walk_symbol(&w) != lp->m.mods.data[pm->mod].code) {
                    ok = false;
                    break;
                }
                bind_formals(ls, &w, pm->args, fr);
                cbm__walk_next_in_memory(&w);
            }
            if (!ok)
                continue;
            lp->scan[LC_CTX_LEFT] = first;
            lp->scan[LC_CTX_RIGHT] = w;
            memset(&lp->scan[LC_CTX_NEW_LEFT], 0, sizeof(cbm__walk));
            memset(&lp->scan[LC_CTX_NEW_RIGHT], 0, sizeof(cbm__walk));
            if (nxt && !lp->backward)
                lp->scan[LC_CTX_NEW_LEFT] = cbm__walk_at(nxt, nxt->n, nxt->npm, nxt->npar, 1);
            else if (nxt)
                lp->scan[LC_CTX_NEW_RIGHT] = walk_end(nxt, -1);
            for (int c = 0; c < LC_CTX_N && ok; c++)
                if (pr->context[c].n)
                    ok = match_context(ls, c, pr->context[c].first, pr->context[c].n, fr);
            if (!ok)
                continue;
            size_t n0 = out->n, npm0 = out->npm, npar0 = out->npar;
            lp->out = out;
            lp->produced = false;
            /* a production applied is an operation: a decomposition that doubles to its
             * maximum depth stops at the budget */
            lp->vm.stmt_pos = (int32_t)(pr->pos < INT32_MAX ? pr->pos : INT32_MAX);
            if (!spend_operation(lp, false))
                return 0;
            int bi = cbm__lc_body(&lp->prog, which, p);
            if (bi >= 0 && lp->prog.fn[bi].compiled) { /* the register (or native) code */
                lp->vm.sp = (size_t)lp->prog.fn[bi].nreg;
                lp->produced = cbm__lc_run(&lp->prog, bi, fr, &lp->vm) != 0;
            } /* else no body: nothing produced */
            if (lp->vm.err != CBM_OK)
                return 0;
            if (lp->produced)
                return np;
            out->n = n0, out->npm = npm0, out->npar = npar0;
        }
    return 0;
}

static cbm_status copy_module_at(cbm_context *ctx, const lstr *src, size_t i, size_t j, size_t k,
                                 lstr *dst)
{
    lpos p = {i, j, k};
    return cbm__lstr_copy_module(ctx, src, &p, dst);
}

static cbm_status check_size(cbm_lsys *ls, const lstr *s)
{
    if (s->n > cbm_context_limits(ls->ctx)->max_modules)
        return cbm__fail(ls->ctx, CBM_E_LIMIT, "the string would exceed %zu modules (max_modules)",
                         cbm_context_limits(ls->ctx)->max_modules);
    return CBM_OK;
}

/* Rewrites src into out with a decomposition-like set, recursively to set->depth. */
static cbm_status decompose(cbm_lsys *ls, const lc_rules *set, const lstr *src, lstr *out,
                            int level)
{
    lpfg *lp = ls->lp;
    lstr *tmp = &lp->scratch.data[level];
    size_t j = 0, k = 0;
    /* the interpretation of a model with mechanics records where its modules came from */
    bool track = level == 0 && set == &lp->m.interp && lp->mech.seg_code >= 0;
    for (size_t i = 0; i < src->n; i++) {
        size_t from = out->n, source = i;
        tmp->n = tmp->npm = tmp->npar = 0;
        int done = level < set->depth ? try_rewrite(ls, set, src, i, j, k, NULL, tmp) : 0;
        if (lp->vm.err != CBM_OK)
            return lp->vm.err;
        for (int extra = 1; extra < done; extra++) { /* further predecessor modules */
            if (src->sym[i] & LSYS_PARAM_BIT)
                k += src->pc[j++];
            i++;
        }
        if (done) {
            if (level + 1 < set->depth)
                CBM_TRY(decompose(ls, set, tmp, out, level + 1));
            else
                CBM_TRY(cbm__lstr_append(ls->ctx, out, tmp, false));
        } else
            CBM_TRY(copy_module_at(ls->ctx, src, i, j, k, out));
        CBM_TRY(check_size(ls, out));
        for (size_t o = from; track && o < out->n; o++)
            CBM_TRY(CBM_ARRAY_PUSH(ls->ctx, lp->origin, source));
        if (src->sym[i] & LSYS_PARAM_BIT)
            k += src->pc[j++];
    }
    return CBM_OK;
}

static cbm_status decompose_cur(cbm_lsys *ls)
{
    lpfg *lp = ls->lp;
    if (!lp->m.decomp.present || !lp->m.decomp.prods.len)
        return CBM_OK;
    ls->next.n = ls->next.npm = ls->next.npar = 0;
    cbm_status s = decompose(ls, &lp->m.decomp, &ls->cur, &ls->next, 0);
    if (s != CBM_OK)
        return lp->vm.err != CBM_OK ? run_error(ls, "decomposition") : s;
    lstr t = ls->cur;
    ls->cur = ls->next;
    ls->next = t;
    return CBM_OK;
}

/* ---- the step: the step loop of lsys_internal.h with the L+C dialect's hooks ---- */

/* The state of the generative pass. */
typedef struct lpfg_pass {
    cbm_lsys *ls;
    bool back; /* Backward(): the string is read right to left, the output built reversed */
    size_t cut, sb, eb; /* the codes of Cut, SB and EB */
} lpfg_pass;

/* p to the next module in the pass's direction; going Backward, the parameters of a module are
 * at (j, k) as going Forward, and before the first module i is SIZE_MAX (the loop's end) */
static inline void pass_next(const lpfg_pass *ps, const lstr *s, lpos *p)
{
    if (!ps->back)
        cbm__pos_next(s, p);
    else if (p->mod-- > 0 && (s->sym[p->mod] & LSYS_PARAM_BIT))
        p->param -= s->pc[--p->pmod];
}

/* The production of the module at *p (the first module of its predecessor, the last going
 * Backward). Going Forward the successor is produced in place at the end of the new string (a
 * body that does not produce truncates it back); Backward it is produced apart and reversed
 * into it. Going Forward, a Cut is not rewritten by the productions (lpfg): it drops the rest
 * of its branch, up to the EB that closes it (copied next) or the end of the string. */
static cbm_status lpfg_rewrite(void *d, lpos *p, size_t c, bool *applied)
{
    lpfg_pass *ps = d;
    cbm_lsys *ls = ps->ls;
    lpfg *lp = ls->lp;
    const lstr *src = &ls->cur;
    *applied = true;
    if (!ps->back && c == ps->cut) {
        cbm__walk w = cbm__walk_at(src, p->mod, p->pmod, p->param, 1);
        cbm__walk_find_closing(&w, (int)ps->sb, (int)ps->eb, true);
        p->mod = (size_t)w.mod, p->pmod = w.pmod, p->param = w.param;
        return CBM_OK;
    }
    lstr *succ = &lp->succ;
    succ->n = succ->npm = succ->npar = 0;
    int done = try_rewrite(ls, &lp->m.main, src, p->mod, p->pmod, p->param, &ls->next,
                           ps->back ? succ : &ls->next);
    if (lp->vm.err != CBM_OK)
        return lp->vm.err;
    *applied = done > 0;
    if (!done)
        return CBM_OK;
    if (ps->back)
        CBM_TRY(cbm__lstr_append(ls->ctx, &ls->next, succ, true));
    pass_next(ps, src, p);
    for (int a = 1; a < done; a++) /* further predecessor modules */
        pass_next(ps, src, p);
    return CBM_OK;
}

/* A module no production rewrites: copied. */
static cbm_status lpfg_unmatched(void *d, lpos *p, size_t c)
{
    (void)c;
    const lpfg_pass *ps = d;
    const lstr *src = &ps->ls->cur;
    CBM_TRY(copy_module_at(ps->ls->ctx, src, p->mod, p->pmod, p->param, &ps->ls->next));
    pass_next(ps, src, p);
    return CBM_OK;
}

static cbm_status lpfg_after(void *d, const lpos *from, const lpos *p)
{
    (void)from, (void)p;
    const lpfg_pass *ps = d;
    return check_size(ps->ls, &ps->ls->next);
}

static const cbm__step_hooks LPFG_STEP = {lpfg_rewrite, lpfg_unmatched, lpfg_after};

static cbm_status generate_pass(cbm_lsys *ls)
{
    lpfg *lp = ls->lp;
    lstr *nxt = &ls->next, *succ = &lp->succ;
    nxt->n = nxt->npm = nxt->npar = 0;
    lpfg_pass ps = {.ls = ls,
                    .back = lp->backward,
                    .cut = lp->m.mods.data[cbm__lc_find_module(&lp->m, "Cut", 3)].code,
                    .sb = lp->m.mods.data[lp->m.sb_module].code,
                    .eb = lp->m.mods.data[lp->m.eb_module].code};
    lpos start = {0, 0, 0};
    if (ps.back) { /* from the last module */
        start = (lpos){ls->cur.n, ls->cur.npm, ls->cur.npar};
        pass_next(&ps, &ls->cur, &start);
    }
    CBM_TRY(cbm__step_loop(&LPFG_STEP, &ps, &ls->cur, start));
    if (ps.back) { /* the output was built reversed */
        succ->n = succ->npm = succ->npar = 0;
        CBM_TRY(cbm__lstr_append(ls->ctx, succ, nxt, true));
        lstr t = *nxt;
        *nxt = *succ;
        *succ = t;
    }
    lstr t = ls->cur;
    ls->cur = ls->next;
    ls->next = t;
    return CBM_OK;
}

/* The derivation pass, with the bracket tables of the strings its right contexts walk */
static cbm_status generate(cbm_lsys *ls)
{
    const lpfg *lp = ls->lp;
    uint8_t sbc = (uint8_t)lp->m.mods.data[lp->m.sb_module].code;
    uint8_t ebc = (uint8_t)lp->m.mods.data[lp->m.eb_module].code;
    cbm__brackets_start(&ls->brackets[0], &ls->cur, 1, sbc, ebc);
    cbm__brackets_start(&ls->brackets[1], &ls->next, -1, sbc, ebc);
    cbm_status s = generate_pass(ls);
    ls->brackets[0].s = ls->brackets[1].s = NULL;
    return s;
}

cbm_status cbm__lpfg_step(cbm_lsys *ls)
{
    lpfg *lp = ls->lp;
    if (ls->steps >= (int)cbm_context_limits(ls->ctx)->max_steps)
        return cbm__fail(ls->ctx, CBM_E_LIMIT, "more than %zu derivation steps (max_steps)",
                         cbm_context_limits(ls->ctx)->max_steps);
    set_budgets(ls);
    CBM_TRY(run_block(ls, 1));
    lp->rewriting = true;
    cbm_status s = generate(ls);
    if (s == CBM_OK)
        s = decompose_cur(ls);
    lp->rewriting = false;
    if (s != CBM_OK) {
        char what[48];
        snprintf(what, sizeof what, "step %d", ls->steps + 1);
        if (lp->vm.err != CBM_OK)
            return run_error(ls, what);
        if (s == CBM_E_NOMEM && cbm_context_limits(ls->ctx)->max_bytes)
            return cbm__fail(ls->ctx, CBM_E_LIMIT,
                             "%s: the string would exceed the memory limit of %zu bytes", what,
                             cbm_context_limits(ls->ctx)->max_bytes);
        return s;
    }
    ls->steps++;
    ls->homo_valid = false;
    CBM_TRY(run_block(ls, 2));
    if (ls->steps == ls->derivation_length)
        CBM_TRY(run_block(ls, 3));
    return CBM_OK;
}

/* The mechanics settings at their defaults with the model's declarations (the kept plant, if
 * any, freed first by the caller), and the caller's bending method if it imposes one. */
static void mech_declare(cbm_lsys *ls)
{
    lpfg *lp = ls->lp;
    const lc_mech_decl *d = &lp->m.mech_decl;
    cbm_lsys_sway_fn fn = lp->mech.sway_fn; /* the caller's observer outlives a reset */
    void *ud = lp->mech.sway_ud;
    cbm__mechlang_init(&lp->mech);
    if (ls->solver_override >= 0)
        lp->mech.solve.solver = (cbm_mech_solver)ls->solver_override;
    lp->mech.sway_fn = fn;
    lp->mech.sway_ud = ud;
    lp->mech.seg_code = d->seg_code;
    lp->mech.seg_off = d->seg_off;
    memcpy(lp->mech.mass_off, d->mass_off, sizeof d->mass_off);
    memcpy(lp->mech.radius_off, d->radius_off, sizeof d->radius_off);
    memcpy(lp->mech.light_area_off, d->light_area_off, sizeof d->light_area_off);
    memcpy(lp->mech.light_out_off, d->light_out_off, sizeof d->light_out_off);
}

cbm_status cbm__lpfg_reset(cbm_lsys *ls)
{
    lpfg *lp = ls->lp;
    memset(lp->vm.glob, 0, (size_t)(lp->m.nglobal + 1) * sizeof(double));
    cbm__lc_error_clear(&lp->vm);
    lp->nonfinite_warned = false;
    set_budgets(ls);
    lp->backward = false;
    lp->group = 0;
    lp->vm.call_depth = 0;
    ls->steps = 0;
    ls->homo_valid = false;
    ls->ev.stopped = false;
    cbm__rand48_seed16(&ls->ev.rnd.r48, 0x330E, 0, 0);
    ls->ev.rnd.normal_have = 0;
    cbm__crand_seed(&lp->crand, 1);
    /* mechanics settings back to their defaults; the declarations stay */
    cbm__mechlang_free(ls->ctx, &lp->mech);
    mech_declare(ls);
    ls->cur.n = ls->cur.npm = ls->cur.npar = 0;
    for (size_t g = 0; g < lp->m.gvars.len; g++) {
        const lc_global *v = &lp->m.gvars.data[g];
        lp->vm.stmt_pos = -1;
        if (v->init >= 0)
            (void)run_root(ls, lp->prog.init0 + g);
        if (lp->vm.err != CBM_OK)
            return run_error(ls, lp->m.gvars.data[g].name);
    }
    CBM_TRY(run_block(ls, 0));
    ls->cur.n = ls->cur.npm = ls->cur.npar = 0;
    lp->out = &ls->cur;
    lp->vm.stmt_pos = -1;
    if (lp->axiom_kept)
        CBM_TRY(cbm__lstr_append(ls->ctx, &ls->cur, &lp->axiom, false));
    else
        (void)run_root(ls, lp->prog.axiom);
    if (lp->vm.err != CBM_OK)
        return run_error(ls, "axiom");
    return decompose_cur(ls);
}

cbm_status cbm__lpfg_interpretation(cbm_lsys *ls)
{
    lpfg *lp = ls->lp;
    ls->homo_str.n = ls->homo_str.npm = ls->homo_str.npar = 0;
    lp->origin.len = 0;
    set_budgets(ls);
    cbm_status s;
    if (!lp->m.interp.present || !lp->m.interp.prods.len)
        s = cbm__lstr_append(ls->ctx, &ls->homo_str, &ls->cur, false);
    else {
        lp->rewriting = true;
        s = decompose(ls, &lp->m.interp, &ls->cur, &ls->homo_str, 0);
        lp->rewriting = false;
    }
    if (s != CBM_OK && lp->vm.err != CBM_OK)
        return run_error(ls, "interpretation");
    if (s == CBM_OK)
        ls->homo_valid = true;
    return s;
}

/* ---------------------------------------------------------------- output */
/* Through the buffered writer of write.c (cbm__strw): a line per module, as the cpfg dialect's
 * writer, so that a string of 10^7 modules is not a locked stdio call per character. */
static const double *write_value(cbm__strw *w, const lpfg *lp, int t, const double *v)
{
    if (t == T_INT || t == T_BOOL) {
        cbm__strw_lld(w, cbm__to_ll(v[0]));
        return v + 1;
    }
    if (lc_is_scalar(t)) {
        /* a whole number below 10^9 (the parameters of most strings) is what "%.9g" prints of
         * it, its digits; -0 keeps its sign through printf */
        if (v[0] == (double)(long long)(v[0] < 1e9 && v[0] > -1e9 ? v[0] : 0.5) &&
            !(v[0] == 0 && signbit(v[0])))
            cbm__strw_lld(w, (long long)v[0]);
        else
            cbm__strw_g9(w, v[0]);
        return v + 1;
    }
    cbm__strw_char(w, '{');
    int nf = lc_is_vec(t) ? 3 : lp->m.types.data[t].nfields;
    for (int i = 0; i < nf; i++) {
        if (i)
            cbm__strw_char(w, ',');
        v = write_value(w, lp, lc_is_vec(t) ? T_DOUBLE : lp->m.types.data[t].ftype[i], v);
    }
    cbm__strw_char(w, '}');
    return v;
}

cbm_status cbm__lpfg_write_str(const cbm_lsys *ls, bool homomorphism, cbm_out *o)
{
    const lpfg *lp = ls->lp;
    cbm_lsys_cursor c;
    cbm_lsys_cursor_begin(ls, homomorphism, &c);
    cbm__strw *w = cbm__strw_open(ls->ctx, cbm_out_stream(o));
    if (!w)
        return CBM_E_NOMEM;
    size_t namelen[128] = {0};
    for (int code = 0; code < 128; code++)
        if (lp->m.bycode[code] >= 0)
            namelen[code] = strlen(lp->m.mods.data[lp->m.bycode[code]].name);
    while (cbm_lsys_cursor_next(ls, homomorphism, &c)) {
        const lc_module *m = &lp->m.mods.data[lp->m.bycode[c.symbol & 0x7f]];
        cbm__strw_bytes(w, m->name, namelen[c.symbol & 0x7f]);
        if (m->nparams) {
            const double *v = c.params;
            for (int i = 0; i < m->nparams; i++) {
                cbm__strw_char(w, i ? ',' : '(');
                v = write_value(w, lp, m->ptype[i], v);
            }
            cbm__strw_char(w, ')');
        }
        cbm__strw_char(w, '\n');
    }
    return cbm__strw_close(w);
}

const char *cbm__lpfg_module_name(const cbm_lsys *ls, int symbol)
{
    if (!ls->lp || symbol <= 0 || symbol > 127 || ls->lp->m.bycode[symbol] < 0)
        return NULL;
    return ls->lp->m.mods.data[ls->lp->m.bycode[symbol]].name;
}

cbm_status cbm__lpfg_mech_fields(const cbm_lsys *ls, bool homomorphism, const double ***out,
                                 size_t *n)
{
    const lpfg *lp = ls->lp;
    *out = NULL;
    *n = 0;
    if (!lp || lp->mech.seg_code < 0 || ls->cur.f32)
        return CBM_OK;
    /* the MechSegment of every module of the string, NULL for other modules */
    size_t nc = ls->cur.n;
    const double **seg = cbm__calloc(ls->ctx, nc ? nc : 1, sizeof *seg);
    if (!seg)
        return CBM_E_NOMEM;
    size_t j = 0, k = 0;
    const double *par = ls->cur.par;
    for (size_t i = 0; i < nc; i++) {
        int np = (ls->cur.sym[i] & LSYS_PARAM_BIT) ? ls->cur.pc[j++] : 0;
        if ((ls->cur.sym[i] & 0x7f) == lp->mech.seg_code && np >= lp->mech.seg_off + MS_SIZE)
            seg[i] = par + k + lp->mech.seg_off;
        k += (size_t)np;
    }
    if (!homomorphism || !lp->origin.len) {
        *out = seg;
        *n = nc;
        return CBM_OK;
    }
    /* through the interpretation's origins */
    size_t nh = lp->origin.len;
    const double **img = cbm__calloc(ls->ctx, nh, sizeof *img);
    if (!img) {
        cbm__free(ls->ctx, (void *)seg, (nc ? nc : 1) * sizeof *seg);
        return CBM_E_NOMEM;
    }
    for (size_t i = 0; i < nh; i++)
        img[i] = lp->origin.data[i] < nc ? seg[lp->origin.data[i]] : NULL;
    cbm__free(ls->ctx, (void *)seg, (nc ? nc : 1) * sizeof *seg);
    *out = img;
    *n = nh;
    return CBM_OK;
}

void cbm__lpfg_describe(const cbm_lsys *ls, cbm_model_summary *out)
{
    const lpfg *lp = ls->lp;
    out->lc_dialect = true;
    out->mechanics = cbm_lsys_has_mechanics(ls);
    out->productions = lp->m.main.prods.len;
    out->decompositions = lp->m.decomp.present ? lp->m.decomp.prods.len : 0;
    out->homomorphisms = lp->m.interp.present ? lp->m.interp.prods.len : 0;
    out->decomposition_depth = lp->m.decomp.present ? lp->m.decomp.depth : 0;
    out->homomorphism_depth = lp->m.interp.present ? lp->m.interp.depth : 0;
    out->modules_declared = lp->m.mods.len;
}

void cbm__lpfg_bodies(const cbm_lsys *ls, size_t *compiled, size_t *total)
{
    const lc_program *p = &ls->lp->prog;
    *compiled = *total = 0;
    if (!p->fn)
        return;
    for (size_t f = p->body0[LC_MAIN]; f < p->block0; f++) {
        *compiled += p->fn[f].compiled;
        ++*total;
    }
}

bool cbm_lsys_compile_native(cbm_lsys *ls, const char *cache_dir, const char **why)
{
    const char *dummy;
    if (!why)
        why = &dummy;
    if (!ls || !ls->lp) {
        *why = "native code is for the L+C dialect's functions";
        return false;
    }
    return cbm__lc_native_load(ls->ctx, &ls->lp->m, &ls->lp->prog, cache_dir, why);
}

bool cbm_lsys_has_mechanics(const cbm_lsys *ls)
{
    return ls && ls->lp && ls->lp->mech.seg_code >= 0;
}

void cbm_lsys_set_sway_observer(cbm_lsys *ls, cbm_lsys_sway_fn fn, void *ud)
{
    if (!ls || !ls->lp)
        return;
    ls->lp->mech.sway_fn = fn;
    ls->lp->mech.sway_ud = ud;
}

cbm_status cbm_lsys_mech_plant(cbm_lsys *ls, cbm_plant **out)
{
    if (!ls || !out)
        return CBM_E_INVALID;
    *out = NULL;
    if (!cbm_lsys_has_mechanics(ls))
        return cbm__fail(
            ls->ctx, CBM_E_INVALID,
            "the model declares no mechanical segments (`mechanics:` in an L+C model)");
    char msg[256];
    cbm_status s = cbm__mechlang_plant(ls->ctx, &ls->lp->mech, &ls->cur, out, msg, sizeof msg);
    if (s != CBM_OK)
        return cbm__fail(ls->ctx, s, "%s", msg);
    return CBM_OK;
}

/* ---------------------------------------------------------------- load / free */
void cbm__lpfg_mech_keep(cbm_lsys *ls, bool keep)
{
    if (!ls->lp)
        return;
    if (!keep)
        cbm__mechlang_free(ls->ctx, &ls->lp->mech);
    ls->lp->mech.keep = keep;
}

void cbm__lpfg_free(cbm_lsys *ls)
{
    lpfg *lp = ls->lp;
    if (!lp)
        return;
    cbm_context *ctx = ls->ctx;
    cbm__mechlang_free(ctx, &lp->mech);
    CBM_ARRAY_FREE(ctx, lp->origin);
    cbm__free(ctx, lp->vm.glob, (size_t)(lp->m.nglobal + 1) * sizeof(double));
    cbm__lc_model_free(ctx, &lp->m);
    cbm__free(ctx, lp->vm.stack, lp->vm.stack_cap * sizeof(double));
    cbm__lc_program_free(ctx, &lp->prog);
    cbm__lstr_free(ctx, &lp->succ);
    cbm__lstr_free(ctx, &lp->axiom);
    for (size_t i = 0; i < lp->scratch.len; i++)
        cbm__lstr_free(ctx, &lp->scratch.data[i]);
    CBM_ARRAY_FREE(ctx, lp->scratch);
    cbm__free(ctx, lp, sizeof *lp);
    ls->lp = NULL;
}

/* Every function with a body, production body, block, initialiser, the axiom and the header's
 * expressions must have compiled: there is no other evaluator. What did not is named at its
 * position (the register code's limits: 256 cases in a switch, 65535 doubles in a frame). */
static cbm_status check_compiled(cbm_lsys *ls)
{
    const lpfg *lp = ls->lp;
    const lc_model *m = &lp->m;
    const lc_program *p = &lp->prog;
    for (size_t f = 0; f < p->n; f++) {
        if (p->fn[f].compiled)
            continue;
        const char *what = NULL;
        size_t pos = 0;
        if (f < m->funcs.len) {
            if (m->funcs.data[f].body >= 0)
                what = "function", pos = m->funcs.data[f].pos;
        } else if (f < p->block0) {
            const lc_rules *set = f < p->body0[LC_DECOMP]   ? &m->main
                                  : f < p->body0[LC_INTERP] ? &m->decomp
                                                            : &m->interp;
            int k = set == &m->main ? LC_MAIN : set == &m->decomp ? LC_DECOMP : LC_INTERP;
            const lc_production *pr = &set->prods.data[f - p->body0[k]];
            if (pr->body >= 0)
                what = "production", pos = pr->pos;
        } else if (f < p->init0) {
            int32_t b = m->blocks[f - p->block0];
            if (b >= 0)
                what = "block", pos = (size_t)m->nodes.data[b].pos;
        } else if (f < p->axiom) {
            int32_t e = m->gvars.data[f - p->init0].init;
            if (e >= 0)
                what = "initialiser", pos = (size_t)m->nodes.data[e].pos;
        } else if (f == p->axiom)
            what = "axiom";
        else if (p->xpresent[f - p->expr0])
            what = "expression";
        if (what)
            return cbm__compiler_fail(&ls->comp, CBM_E_LIMIT, pos,
                                      "this %s cannot be compiled to the register code (more "
                                      "than 256 cases in a switch, or a frame of more than "
                                      "65535 doubles)",
                                      what);
    }
    return CBM_OK;
}

/* lc_vm.produce while keep_axiom runs the axiom: the module appended to lp->out when its
 * parameters are finite; otherwise false, and the axiom is left to reset, which reports the
 * parameter (or warns, --allow-nonfinite) on every run as before. */
static bool produce_kept(void *ud, int smi, const double *v)
{
    cbm_lsys *ls = ud;
    lpfg *lp = ls->lp;
    const lc_module *m = &lp->m.mods.data[lp->m.sms.data[smi].mod];
    for (int q = 0; q < m->size; q++)
        if (!isfinite(v[q])) {
            rt_error(lp, CBM_E_RUNTIME, "not finite");
            return false;
        }
    if (push_module(ls->ctx, lp->out, m->code, v, m->size) != CBM_OK) {
        rt_error(lp, CBM_E_NOMEM, "out of memory");
        return false;
    }
    return true;
}

/* An axiom whose code reads nothing of the run (no global, random number or call: its
 * arguments are constants, or arithmetic on them) gives the same string on every run: it is run
 * once here into lp->axiom, which reset copies, and its code is freed. A long one is compiled
 * and run LC_AXIOM_PART modules at a time, so that its whole code is never held (the hostile
 * corpus's 400000 modules: 12.5 MB). Otherwise, or when its run fails (an error, a parameter
 * that is not finite, the memory limit), the axiom is compiled whole and every reset runs it
 * and reports its errors, as before. */
static cbm_status keep_axiom(cbm_lsys *ls)
{
    lpfg *lp = ls->lp;
    lc_program *p = &lp->prog;
    const int32_t total = lp->m.axiom.n;
    bool kept = true;
    cbm_status s = CBM_OK;
    set_budgets(ls);
    lp->vm.produce = produce_kept;
    lp->out = &lp->axiom;
    for (int32_t from = 0; kept && from < total; from += LC_AXIOM_PART) {
        int32_t count = total - from < LC_AXIOM_PART ? total - from : LC_AXIOM_PART;
        if (from != p->axiom_from || count != p->axiom_count)
            s = cbm__lc_codegen_axiom(ls->ctx, &lp->m, p, from, count);
        kept = s == CBM_OK && p->fn[p->axiom].compiled && cbm__lc_stateless(p, p->axiom) &&
               (size_t)p->fn[p->axiom].nreg + 1 <= lp->vm.stack_cap;
        if (kept) {
            cbm__lc_error_clear(&lp->vm);
            (void)run_root(ls, p->axiom);
            kept = lp->vm.err == CBM_OK;
        }
    }
    lp->vm.produce = produce_compiled;
    lp->out = NULL;
    cbm__lc_error_clear(&lp->vm);
    CBM_TRY(s);
    if (kept) {
        CBM_ARRAY_FREE(ls->ctx, p->fn[p->axiom].ins);
        lp->axiom_kept = true;
        return CBM_OK;
    }
    cbm__lstr_free(ls->ctx, &lp->axiom);
    if (p->axiom_from != 0 || p->axiom_count != total)
        CBM_TRY(cbm__lc_codegen_axiom(ls->ctx, &lp->m, p, 0, total));
    return CBM_OK;
}

static int eval_depth(cbm_lsys *ls, lc_rules *s, int dflt, int which)
{
    if (s->depth <= -2) {
        double v = run_root(ls, ls->lp->prog.expr0 + (size_t)which);
        return !(v >= 0) ? 0 : v > 1e6 ? 1000000 : (int)v; /* NaN: 0 */
    }
    return dflt;
}

cbm_status cbm__lpfg_parse(cbm_lsys *ls, const cbm__pp *pp)
{
    cbm_context *ctx = ls->ctx;
    lpfg *lp = cbm__calloc(ctx, 1, sizeof *lp);
    if (!lp)
        return CBM_E_NOMEM;
    ls->lp = lp;
    /* parameters are stored as doubles; float parameters are rounded to float32 by their type */
    ls->cur.f32 = ls->next.f32 = ls->homo_str.f32 = ls->succ.f32 = false;
    ls->float32 = false;
    cbm_status s = cbm__lc_compile(&ls->comp, pp->text.data, &lp->m);
    mech_declare(ls);
    if (s == CBM_OK && ls->comp.errors)
        s = CBM_E_SYNTAX;
    if (s == CBM_E_SYNTAX)
        return cbm__fail(ctx, s, "%zu error%s in the model", ls->comp.errors,
                         ls->comp.errors == 1 ? "" : "s");
    if (s != CBM_OK)
        return s;
    for (size_t i = 0; i < lp->m.funcnames.len; i++) { /* by default the order of first use */
        int id = (int)i + 1;
        CBM_TRY(CBM_ARRAY_PUSH(ctx, lp->m.funcids, id));
    }
    CBM_TRY(cbm__lc_codegen(ctx, &lp->m, &lp->prog));
    lp->vm.max_call_depth = cbm_context_limits(ctx)->max_call_depth;
    lp->vm.stack_cap = 1u << 16;
    lp->vm.produce = produce_compiled;
    lp->vm.host = ls;
    lp->vm.host_call = lpfg_host;
    lp->vm.stack = cbm__calloc(ctx, lp->vm.stack_cap, sizeof(double));
    lp->vm.glob = cbm__calloc(ctx, (size_t)lp->m.nglobal + 1, sizeof(double));
    if (!lp->vm.stack || !lp->vm.glob)
        return CBM_E_NOMEM;
    CBM_TRY(keep_axiom(ls));
    for (size_t f = lp->prog.body0[LC_MAIN]; f < lp->prog.n; f++) /* a body's frame: the stack */
        if ((size_t)lp->prog.fn[f].nreg + 1 > lp->vm.stack_cap)
            lp->prog.fn[f].compiled = false;
    CBM_TRY(check_compiled(ls));
    for (size_t i = 0; i < lp->m.main.prods.len; i++)
        if ((size_t)lp->m.main.prods.data[i].fsize + 1 > lp->vm.stack_cap)
            return cbm__fail(ctx, CBM_E_LIMIT, "a production has too many local variables");
    int maxd = cbm_context_limits(ctx)->max_decomp_depth;
    lp->m.decomp.depth = eval_depth(ls, &lp->m.decomp, 1, LC_X_DECOMP_DEPTH);
    lp->m.interp.depth = eval_depth(ls, &lp->m.interp, 1, LC_X_INTERP_DEPTH);
    if (lp->m.decomp.depth > maxd || lp->m.interp.depth > maxd)
        return cbm__fail(ctx, CBM_E_LIMIT, "maximum depth exceeds the limit of %d", maxd);
    int depth = lp->m.decomp.depth > lp->m.interp.depth ? lp->m.decomp.depth : lp->m.interp.depth;
    for (int i = 0; i <= depth; i++) {
        lstr z;
        memset(&z, 0, sizeof z);
        CBM_TRY(CBM_ARRAY_PUSH(ctx, lp->scratch, z));
    }
    ls->derivation_length = 0;
    if (lp->m.dlen_expr >= 0) {
        double v = run_root(ls, lp->prog.expr0 + LC_X_DLEN);
        ls->derivation_length = v < 0 ? 0 : v > 1e9 ? 1000000000 : (int)v;
    }
    return CBM_OK;
}

size_t cbm__lpfg_func_names(const cbm_lsys *ls, const char *const **names)
{
    *names = (const char *const *)ls->lp->m.funcnames.data;
    return ls->lp->m.funcnames.len;
}

cbm_status cbm__lpfg_set_func_ids(cbm_lsys *ls, const int *ids, size_t n)
{
    lpfg *lp = ls->lp;
    if (n != lp->m.funcnames.len || (n && !ids))
        return CBM_E_INVALID;
    for (size_t i = 0; i < n; i++)
        lp->m.funcids.data[i] = ids[i];
    return CBM_OK;
}

bool cbm__lpfg_has_interpretation(const cbm_lsys *ls)
{
    return ls->lp->m.interp.present && ls->lp->m.interp.prods.len > 0;
}

/* The step protocol of the L+C dialect (lsys_internal.h). */
const cbm__dialect cbm__lpfg_dialect = {.reset = cbm__lpfg_reset,
                                        .step = cbm__lpfg_step,
                                        .interpret = cbm__lpfg_interpretation,
                                        .has_interpretation = cbm__lpfg_has_interpretation,
                                        .write_str = cbm__lpfg_write_str,
                                        .describe = cbm__lpfg_describe,
                                        .func_names = cbm__lpfg_func_names,
                                        .set_func_ids = cbm__lpfg_set_func_ids};
