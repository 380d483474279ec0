/* The tree factorisation and solve split a branched plant over threads (solve_tree.c,
 * "Threads"): the results must be the same to the bit for any number of threads, and with or
 * without the fast solver's evaluations fused with the factorisation (solve_newton.c). A random
 * tree (each segment continues its predecessor with probability 0.8, else branches off a random
 * earlier one: bench_mech's `tree`, bench/random_tree.h) is solved from rest with 1, 2 and 3
 * threads, the split forced even for this size, and every angle, moment, position and
 * statistic compared bit for bit; a chain, which stays serial, too. */
#include "test.h"

#include "cambium/lsys.h"
#include "lsys_util.h"
#include "cambium/ober.h"
#include "cambium/tree.h"
#include "mech/mech_internal.h"
#include "random_tree.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* The benches' random tree (bench/random_tree.h) with seed 11; a chain leans at 0.3 rad. */
static cbm_plant *random_tree(cbm_context *ctx, size_t n, double E, double leaf, bool chain)
{
    random_tree_def d = random_tree_def_default();
    d.n = d.capacity = n;
    d.E = E;
    d.leaf = leaf;
    d.seed = 11;
    d.chain = chain;
    if (chain)
        d.base_angle = 0.3;
    cbm_plant *p = random_tree_create(ctx, &d);
    CHECK(p != NULL);
    return p;
}

/* The solve's depth-first order (solve_order.c) forced on (every size, one thread too) or off,
 * and back to its defaults. */
static void order_force(bool on)
{
    cbm__mech_order_min_segments(on ? 0 : SIZE_MAX);
    cbm__mech_order_serial(on);
}

static void order_default(void)
{
    cbm__mech_order_min_segments(50000);
    cbm__mech_order_serial(false);
}

typedef struct result {
    cbm_status status;
    size_t n, passes, newton, krylov;
    size_t fused, restored; /* Newton steps fused with the line search's first trial; restored */
    double residual;
    cbm_vec3 *omega, *moment, *pos;
} result;

/* What the fast solver fuses (solve_newton.c): nothing; the evaluations with the factorisation
 * (evaluate_as); those and a direct Newton step with the line search's first trial (tree_step,
 * the default). */
enum { FUSE_NONE, FUSE_EVAL, FUSE_ALL };

/* The pass budget of solve_with's solves (cbm_solve_def.max_passes); with 0, the default, every
 * solve must converge, otherwise its status is kept for the comparison. */
static size_t solve_max_passes = 0;

static result solve_with(size_t n, double E, double leaf, bool chain, int threads, int fuse,
                         bool sorted)
{
    result r = {0};
    cbm__mech_newton_fuse(fuse != FUSE_NONE);
    cbm__mech_newton_fuse_step(fuse == FUSE_ALL);
    cbm__mech_tree_min_segments(0);
    order_force(sorted);
    cbm_context *ctx = NULL;
    CHECK_OK(cbm_context_create(NULL, &ctx));
    cbm_plant *p = random_tree(ctx, n, E, leaf, chain);
    if (p) {
        cbm_solve_def d = cbm_solve_def_default();
        d.warm_start = false;
        d.threads = threads;
        cbm_solve_stats st;
        d.max_passes = solve_max_passes;
        r.status = cbm_plant_solve(p, &d, &st);
        if (solve_max_passes == 0)
            CHECK_OK(r.status);
        r.n = p->n;
        r.passes = st.passes;
        r.newton = st.newton_steps;
        r.krylov = st.krylov_iterations;
        r.residual = st.residual;
        const size_t *count = cbm__context_counters_read(ctx);
        r.fused = count[CBM__MECH_COUNT_STEP_FUSED];
        r.restored = count[CBM__MECH_COUNT_STEP_RESTORED];
        r.omega = malloc(n * sizeof *r.omega);
        r.moment = malloc(n * sizeof *r.moment);
        r.pos = malloc(n * sizeof *r.pos);
        memcpy(r.omega, p->omega, n * sizeof *r.omega);
        memcpy(r.moment, p->moment, n * sizeof *r.moment);
        memcpy(r.pos, p->pos, n * sizeof *r.pos);
        cbm_plant_destroy(p);
    }
    cbm_context_destroy(ctx);
    cbm__mech_tree_min_segments(50000); /* the default */
    order_default();
    cbm__mech_newton_fuse(true);
    cbm__mech_newton_fuse_step(true);
    return r;
}

static void result_free(result *r)
{
    free(r->omega);
    free(r->moment);
    free(r->pos);
}

/* The solves with 2 and 3 threads (fused evaluations), then with 1 and 2 threads without the
 * fused evaluations (solve_newton.c, evaluate_as), against the serial fused one; each in the
 * plant's numbering and in the solve's depth-first order (solve_order.c), forced for this size. */
static void check_same(size_t n, double E, double leaf, bool chain)
{
    result one = solve_with(n, E, leaf, chain, 1, FUSE_ALL, false);
    CHECK(one.n == n && one.passes > 0);
    for (int v = 2; v <= 11; v++) {
        int t = v <= 5 ? v : v - 5; /* 2 .. 5, then 1 .. 5 in the depth-first order */
        bool sorted = v > 5;
        bool fuse = t <= 3;
        int threads = fuse ? t : t - 3;
        result r = solve_with(n, E, leaf, chain, threads, fuse ? FUSE_ALL : FUSE_NONE, sorted);
        CHECK(r.n == n);
        CHECK_EQ_INT(r.passes, one.passes);
        CHECK_EQ_INT(r.newton, one.newton);
        CHECK_EQ_INT(r.krylov, one.krylov);
        CHECK(memcmp(&r.residual, &one.residual, sizeof r.residual) == 0);
        if (r.omega && one.omega) {
            CHECK_MSG(!memcmp(r.omega, one.omega, n * sizeof *r.omega),
                      "%d threads, fused %d, sorted %d: Omega differs", threads, fuse, sorted);
            CHECK_MSG(!memcmp(r.moment, one.moment, n * sizeof *r.moment),
                      "%d threads, fused %d, sorted %d: moments differ", threads, fuse, sorted);
            CHECK_MSG(!memcmp(r.pos, one.pos, n * sizeof *r.pos),
                      "%d threads, fused %d, sorted %d: positions differ", threads, fuse, sorted);
        }
        result_free(&r);
    }
    result_free(&one);
}

/* Two solves the same to the bit: statistics, Omega, moments, positions. */
static void check_same_result(const result *a, const result *b, const char *what)
{
    CHECK(a->n == b->n && a->n > 0);
    CHECK_MSG(a->status == b->status, "%s: status %d and %d", what, (int)a->status, (int)b->status);
    CHECK_EQ_INT(a->passes, b->passes);
    CHECK_EQ_INT(a->newton, b->newton);
    CHECK_EQ_INT(a->krylov, b->krylov);
    CHECK_MSG(memcmp(&a->residual, &b->residual, sizeof a->residual) == 0, "%s: residual", what);
    if (a->omega && b->omega && a->n == b->n) {
        CHECK_MSG(!memcmp(a->omega, b->omega, a->n * sizeof *a->omega), "%s: Omega differs", what);
        CHECK_MSG(!memcmp(a->moment, b->moment, a->n * sizeof *a->moment), "%s: moments differ",
                  what);
        CHECK_MSG(!memcmp(a->pos, b->pos, a->n * sizeof *a->pos), "%s: positions differ", what);
    }
}

/* The fused Newton step (solve_newton.c, fused_step): the solve's forward sweep also takes the
 * full step and sets the frames of the line search's first trial; where the trust region cuts
 * the step, Omega is restored. From rest, a tree under heavy leaves is far from equilibrium (the
 * first step is beyond the trust radius: restored, then the load path, whose steps are cut now
 * and then), a light one is not: each solve with the fused step against the same solve without
 * it (the evaluations fused in both), serial and over 2 threads in the depth-first order, and
 * the counts say that both the kept and the restored steps were taken. */
TEST(fused_step_same_bits_kept_and_restored)
{
    const struct {
        double E, leaf;
    } cases[] = {{1e10, 0.005}, {3e8, 0.02}, {3e8, 0.2}};
    size_t fused = 0, restored = 0;
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++)
        for (int threads = 1; threads <= 2; threads++) {
            bool sorted = threads == 2;
            result a =
                solve_with(6000, cases[c].E, cases[c].leaf, false, threads, FUSE_EVAL, sorted);
            result b =
                solve_with(6000, cases[c].E, cases[c].leaf, false, threads, FUSE_ALL, sorted);
            char what[96];
            snprintf(what, sizeof what, "E %g, leaf %g, %d threads", cases[c].E, cases[c].leaf,
                     threads);
            printf("%s: %zu passes, %zu Newton steps, %zu fused, %zu restored\n", what, b.passes,
                   b.newton, b.fused, b.restored);
            CHECK_EQ_INT(a.fused, 0);
            CHECK(b.fused > 0);
            check_same_result(&a, &b, what);
            fused += b.fused;
            restored += b.restored;
            result_free(&a);
            result_free(&b);
        }
    CHECK(restored > 0);
    CHECK(fused > restored);
}

/* The same with every pass budget up to convergence, a light tree (Newton from rest, 6 passes)
 * and a heavy one (the load path, about 20): the budget runs out before, at and after fused
 * steps, kept or restored, in the newton stage (whose failed state is left as it is) and on the
 * load path (made consistent after), and the failed solves leave the same state, statistics
 * and status with the fused step as without. */
TEST(fused_step_same_bits_when_the_budget_runs_out)
{
    const struct {
        double E, leaf;
        size_t last;
    } cases[] = {{1e10, 0.005, 8}, {3e8, 0.2, 22}};
    size_t failed = 0, solves = 0;
    for (size_t c = 0; c < 2; c++)
        for (size_t budget = 2; budget <= cases[c].last; budget++) {
            solve_max_passes = budget;
            result a = solve_with(2000, cases[c].E, cases[c].leaf, false, 1, FUSE_EVAL, false);
            result b = solve_with(2000, cases[c].E, cases[c].leaf, false, 1, FUSE_ALL, false);
            solve_max_passes = 0;
            char what[64];
            snprintf(what, sizeof what, "E %g, budget %zu", cases[c].E, budget);
            check_same_result(&a, &b, what);
            failed += b.status != CBM_OK;
            solves++;
            result_free(&a);
            result_free(&b);
        }
    printf("%zu of %zu budgets ran out\n", failed, solves);
    CHECK(failed >= 8 && failed < solves);
}

TEST(tree_solve_same_bits_any_thread_count)
{
    check_same(20000, 1e10, 0.005, false);
}

TEST(soft_tree_solve_same_bits_any_thread_count)
{
    check_same(20000, 3e8, 0.02, false);
}

TEST(chain_solve_same_bits_any_thread_count)
{
    check_same(3000, 1e10, 0.0, true);
}

/* The thread count is a setting of the solve (cbm_solve_def.threads) and of a bend spec; a
 * negative count is refused with a message naming it. */
TEST(thread_count_setting)
{
    cbm_solve_def d = cbm_solve_def_default();
    CHECK_EQ_INT(d.threads, 0);
    cbm_context *ctx = NULL;
    CHECK_OK(cbm_context_create(NULL, &ctx));
    cbm_plant *p = random_tree(ctx, 50, 1e10, 0.005, false);
    d.threads = -1;
    CHECK(cbm_plant_solve(p, &d, NULL) == CBM_E_INVALID);
    CHECK(strstr(cbm_context_last_error(ctx), "threads") != NULL);
    d.threads = 2;
    CHECK_OK(cbm_plant_solve(p, &d, NULL));
    cbm_plant_destroy(p);
    const char *spec = "segments = 10\nthreads = 3\n";
    cbm_bend_spec s;
    CHECK_OK(cbm_bend_spec_parse(ctx, spec, strlen(spec), "t.spec", &s));
    CHECK_EQ_INT(s.threads, 3);
    const char *bad = "threads = -2\n";
    CHECK(cbm_bend_spec_parse(ctx, bad, strlen(bad), "t.spec", &s) != CBM_OK);
    cbm_context_destroy(ctx);
}

/* Bit for bit, two plants' Omega, moments and distal nodes (false on different sizes). */
static bool same_plant_bits(const cbm_plant *a, const cbm_plant *b)
{
    if (!a || !b || a->n != b->n || a->n == 0)
        return false;
    size_t n = a->n;
    return !memcmp(a->omega, b->omega, n * sizeof *a->omega) &&
           !memcmp(a->moment, b->moment, n * sizeof *a->moment) &&
           !memcmp(a->pos, b->pos, n * sizeof *a->pos);
}

/* The built-in trees set the thread count with the tree parameter solve_threads (`cambium grow
 * -D solve_threads=N`): it reaches every equilibrium (the plant's setting after the run), the
 * split over threads is forced for this size, and the grown tree is the same to the bit with 1
 * and 2 threads. A bad value is refused naming the parameter. */
TEST(tree_model_solve_threads_same_bits)
{
    cbm__mech_tree_min_segments(0);
    cbm_context *ctx = NULL;
    CHECK_OK(cbm_context_create(NULL, &ctx));
    cbm_tree *t[3] = {NULL, NULL, NULL};
    for (int k = 0; k < 3 && ctx; k++) {
        cbm_tree_def d;
        CHECK_OK(cbm_tree_def_builtin(ctx, "fruit-tree", &d));
        CHECK_OK(cbm_tree_def_set(ctx, &d, "solve_threads", k == 1 ? "2" : "1"));
        d.years = 6;
        cbm__mech_newton_fuse(k != 2); /* the third without the fused evaluations */
        CHECK_OK(cbm_tree_create(ctx, &d, &t[k]));
        if (t[k])
            CHECK_OK(cbm_tree_run(t[k]));
        cbm__mech_newton_fuse(true);
    }
    const cbm_plant *p1 = t[0] ? cbm_tree_plant(t[0]) : NULL;
    const cbm_plant *p2 = t[1] ? cbm_tree_plant(t[1]) : NULL;
    CHECK(p1 && p2);
    if (p1 && p2) {
        /* the split of the last equilibrium, cached in the workspace (solve_tree.c) */
        printf("fruit tree, 6 years: %zu segments; threads %d and %d, split into %d and %d\n",
               p1->n, p1->threads, p2->threads, p1->work.tsplit, p2->work.tsplit);
        CHECK_EQ_INT(p1->threads, 1);
        CHECK_EQ_INT(p2->threads, 2);
        CHECK_EQ_INT(p2->work.tsplit, 2);
        CHECK(same_plant_bits(p1, p2));
    }
    const cbm_plant *p3 = t[2] ? cbm_tree_plant(t[2]) : NULL;
    CHECK_MSG(same_plant_bits(p1, p3), "the fused evaluations changed the grown tree");
    cbm_tree_destroy(t[0]);
    cbm_tree_destroy(t[1]);
    cbm_tree_destroy(t[2]);
    cbm_tree_def d = cbm_tree_def_default();
    CHECK(cbm_tree_def_set(ctx, &d, "solve_threads", "-1") == CBM_E_INVALID);
    CHECK(strstr(cbm_context_last_error(ctx), "solve_threads") != NULL);
    CHECK(cbm_tree_def_set(ctx, &d, "solve_threads", "1.5") == CBM_E_INVALID);
    cbm_context_destroy(ctx);
    cbm__mech_tree_min_segments(50000);
}

/* Two vectors the same to the bit. */
static bool same_vec_bits(cbm_vec3 a, cbm_vec3 b)
{
    const double x[6] = {a.x, a.y, a.z, b.x, b.y, b.z};
    uint64_t u[6];
    memcpy(u, x, sizeof u);
    return u[0] == u[3] && u[1] == u[4] && u[2] == u[5];
}

/* The Oberlaender trees take the same parameter (`cambium grow ober-* -D solve_threads=N`): it
 * reaches mechanicsFeedback's equilibria (the grown shoots the same to the bit with 1 and 2
 * threads, the split forced) and cbm_ober_mechanics' (the solved plant's setting, its split and
 * its bits). A bad value is refused naming the parameter, with the fruit tree's range. */
TEST(ober_solve_threads_same_bits)
{
    cbm__mech_tree_min_segments(0);
    cbm_context *ctx = NULL;
    CHECK_OK(cbm_context_create(NULL, &ctx));
    cbm_ober_stand *s[2] = {NULL, NULL};
    cbm_plant *p[2] = {NULL, NULL};
    for (int k = 0; k < 2 && ctx; k++) {
        cbm_ober_def d;
        CHECK_OK(cbm_ober_def_builtin(ctx, "ober-troll", &d));
        CHECK_OK(cbm_ober_def_set(ctx, &d, "maxOrder", "2", NULL));
        CHECK_OK(cbm_ober_def_set(ctx, &d, "mechanicsFeedback", "1", NULL));
        CHECK_OK(cbm_ober_def_set(ctx, &d, "solve_threads", k == 0 ? "1" : "2", NULL));
        CHECK_EQ_INT(d.solve_threads, k + 1);
        d.years = 6;
        CHECK_OK(cbm_ober_create(ctx, &d, &s[k]));
        if (!s[k])
            continue;
        CHECK_OK(cbm_ober_run(s[k]));
        cbm_ober_mech_def md = cbm_ober_mech_def_default();
        cbm_ober_mech_result r;
        CHECK_OK(cbm_ober_mechanics(s[k], 0, &md, &r, &p[k]));
    }
    size_t n = s[0] && s[1] ? cbm_ober_shoot_count(s[0]) : 0;
    CHECK(n > 20 && cbm_ober_shoot_count(s[1]) == n);
    for (size_t i = 0; i < n; i++) {
        cbm_ober_shoot a, b;
        CHECK_OK(cbm_ober_shoot_info(s[0], i, &a));
        CHECK_OK(cbm_ober_shoot_info(s[1], i, &b));
        CHECK_MSG(same_vec_bits(a.base, b.base) && same_vec_bits(a.tip, b.tip), "shoot %zu differs",
                  i);
    }
    CHECK(p[0] && p[1]);
    if (p[0] && p[1]) {
        printf("ober-troll, 6 years, mechanicsFeedback: %zu shoots, %zu segments; threads %d and "
               "%d, split into %d and %d\n",
               n, p[0]->n, p[0]->threads, p[1]->threads, p[0]->work.tsplit, p[1]->work.tsplit);
        CHECK_EQ_INT(p[0]->threads, 1);
        CHECK_EQ_INT(p[1]->threads, 2);
        CHECK_EQ_INT(p[1]->work.tsplit, 2);
        CHECK(same_plant_bits(p[0], p[1]));
    }
    for (int k = 0; k < 2; k++) {
        cbm_plant_destroy(p[k]);
        cbm_ober_destroy(s[k]);
    }
    cbm_ober_def d = cbm_ober_def_default();
    CHECK_EQ_INT(d.solve_threads, 0);
    static const char *const bad[] = {"-1", "1.5", "1025", "two"};
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        CHECK_MSG(cbm_ober_def_set(ctx, &d, "solve_threads", bad[i], NULL) == CBM_E_INVALID,
                  "solve_threads = %s accepted", bad[i]);
        CHECK_MSG(strstr(cbm_context_last_error(ctx), "solve_threads") != NULL, "%s",
                  cbm_context_last_error(ctx));
    }
    CHECK_EQ_INT(d.solve_threads, 0);
    d.solve_threads = -1;
    CHECK(cbm_ober_def_check(ctx, &d) == CBM_E_INVALID);
    CHECK(strstr(cbm_context_last_error(ctx), "solve_threads") != NULL);
    cbm_context_destroy(ctx);
    cbm__mech_tree_min_segments(50000);
}

/* A binary tree of 2^9 - 1 axes grown by L+C, an equilibrium after every step. */
static cbm_plant *lc_tree(cbm_context *ctx, const char *start, cbm_lsys **out)
{
    char src[1200];
    snprintf(src, sizeof src,
             "#include <lpfgall.h>\n"
             "derivation length: 8;\n"
             "module I(MechSegment);\n"
             "module A(int);\n"
             "module Fruit(double);\n"
             "mechanics: I;\n"
             "mass: Fruit(mass);\n"
             "MechSegment S(double a) { MechSegment s; s.length = 0.05; s.a = a; s.b = a; "
             "s.E = 1e9; s.density = 800; return s; }\n"
             "Start: { %s }\n"
             "EndEach: { Equilibrium(); }\n"
             "Axiom: Left(30) A(0);\n"
             "A(k) : { produce I(S(0.004 / (1 + k))) I(S(0.004 / (1 + k))) "
             "SB Right(40) A(k + 1) EB SB Left(35) A(k + 1) EB Fruit(0.01); }\n",
             start);
    cbm_lsys_def def = cbm_lsys_def_default();
    def.text = src;
    def.path = "threads.l";
    cbm_lsys *ls = NULL;
    cbm_plant *p = NULL;
    CHECK_OK(cbm_lsys_load(ctx, &def, &ls));
    if (ls) {
        CHECK_OK(cbm_lsys_reset(ls));
        for (int k = 0; k < 8; k++)
            CHECK_OK(cbm_lsys_step(ls));
        CHECK_OK(cbm_lsys_mech_plant(ls, &p));
    }
    *out = ls;
    return p;
}

/* L+C sets the thread count with SolverThreads(n) (0: one per processor): the same bits with 1
 * and 2 threads, the split forced; a bad n stops the run naming the place. */
TEST(lc_solver_threads_same_bits)
{
    cbm__mech_tree_min_segments(0);
    cbm_context *ctx = NULL;
    CHECK_OK(cbm_context_create(NULL, &ctx));
    cbm_lsys *l1 = NULL, *l2 = NULL;
    cbm_plant *p1 = lc_tree(ctx, "SolverThreads(1);", &l1);
    cbm_plant *p2 = lc_tree(ctx, "SolverThreads(2);", &l2);
    CHECK(p1 && p2);
    if (p1 && p2) {
        /* the plants returned are new (not solved); the shape splits over 2 threads */
        p2->threads = 2;
        printf("L+C tree: %zu segments, split into %d\n", p1->n, cbm__mech_tree_split(p2));
        CHECK_EQ_INT(cbm__mech_tree_split(p2), 2);
        CHECK(same_plant_bits(p1, p2));
    }
    cbm_plant_destroy(p1);
    cbm_plant_destroy(p2);
    cbm_lsys_destroy(l1);
    cbm_lsys_destroy(l2);
    cbm_context_destroy(ctx);
    cbm__mech_tree_min_segments(50000);
    const char *bad[] = {"SolverThreads(-1);", "SolverThreads(1.5);", "SolverThreads(2000);"};
    for (int j = 0; j < 3; j++)
        lc_check_start_error(bad[j], "SolverThreads(n)");
}

/* The solve's depth-first order (solve_order.c) does not depend on how the plant is numbered:
 * the random tree in its generator's numbering, solved in that order, and the same tree numbered
 * depth-first (which that order leaves as it is) give the same Omega, moments and positions to
 * the bit, segment for segment, with the same statistics. (The sums over all segments, which
 * follow each plant's numbering, only decide the line search's acceptance here.) */
TEST(order_scrambled_against_depth_first_same_bits)
{
    cbm_context *ctx = NULL;
    CHECK_OK(cbm_context_create(NULL, &ctx));
    cbm_plant *p[2] = {NULL, NULL};
    cbm_solve_stats st[2];
    for (int k = 0; k < 2 && ctx; k++) {
        random_tree_def d = random_tree_def_default();
        d.n = d.capacity = 20000;
        d.leaf = 0.01;
        d.seed = 5;
        d.depth_first = k == 1;
        p[k] = random_tree_create(ctx, &d);
        CHECK(p[k] != NULL);
        if (!p[k])
            continue;
        order_force(true);
        cbm_solve_def sd = cbm_solve_def_default();
        sd.warm_start = false;
        sd.threads = 1;
        CHECK_OK(cbm_plant_solve(p[k], &sd, &st[k]));
        order_default();
    }
    if (p[0] && p[1]) {
        const cbm__mech_order *o = &p[0]->sorder;
        CHECK(o->valid && !o->identity && !o->active);
        CHECK(p[1]->sorder.valid && p[1]->sorder.identity);
        CHECK_EQ_INT(st[0].passes, st[1].passes);
        CHECK_EQ_INT(st[0].newton_steps, st[1].newton_steps);
        CHECK(memcmp(&st[0].residual, &st[1].residual, sizeof st[0].residual) == 0);
        size_t bad = 0;
        for (size_t k = 0; k < p[1]->n && o->valid; k++) {
            size_t i = o->ord[k];
            bad += !same_vec_bits(p[0]->omega[i], p[1]->omega[k]) ||
                   !same_vec_bits(p[0]->moment[i], p[1]->moment[k]) ||
                   !same_vec_bits(p[0]->pos[i], p[1]->pos[k]) ||
                   !same_vec_bits(p[0]->force[i], p[1]->force[k]);
        }
        CHECK_MSG(bad == 0, "%zu segments differ", bad);
    }
    cbm_plant_destroy(p[0]);
    cbm_plant_destroy(p[1]);
    cbm_context_destroy(ctx);
}

/* A forest of random trees whose laterals start anywhere before them (roots every 997
 * segments), with an LCG of its own. */
static cbm_plant *forest(cbm_context *ctx, size_t n)
{
    cbm_plant *p = NULL;
    CHECK_OK(cbm_plant_create(ctx, NULL, &p));
    uint64_t r = 12345;
    for (size_t i = 0; i < n && p; i++) {
        r = r * 6364136223846793005u + 1442695040888963407u;
        double u = (double)(r >> 11) / 9007199254740992.0;
        cbm_segment_def s = cbm_segment_def_default();
        s.length = 0.02;
        s.core.a = s.core.b = 0.01;
        s.core.youngs_modulus = 1e10;
        s.core.shear_modulus = 1e10 / 16;
        s.core.density = 700;
        s.parent = i % 997 == 0 ? -1
                   : u < 0.8    ? (int64_t)i - 1
                                : (int64_t)(u * 1.25 * (double)i) % (int64_t)i;
        if (s.parent >= 0 && s.parent != (int64_t)i - 1)
            s.deviation = 0.6;
        s.divergence = 2.4 * (double)i;
        s.point_mass = 0.002;
        CHECK_OK(cbm_plant_add_segment(p, &s, NULL));
    }
    return p;
}

/* The order follows the plant between solves: a forest solved in the depth-first order and in
 * its own numbering stays the same to the bit after loads change, segments are added (the order
 * is computed again) and a subtree is removed, each followed by a warm solve; and after the
 * solve the workspace is in the plant's numbering again (a stability probe reads it). */
TEST(order_follows_edits_same_bits)
{
    cbm_context *ctx = NULL;
    CHECK_OK(cbm_context_create(NULL, &ctx));
    cbm_plant *p[2] = {forest(ctx, 6000), forest(ctx, 6000)};
    cbm_solve_def sd = cbm_solve_def_default();
    sd.threads = 2;
    cbm__mech_tree_min_segments(0);
    for (int step = 0; step < 4 && p[0] && p[1]; step++) {
        for (int k = 0; k < 2; k++) {
            if (step == 1)
                CHECK_OK(
                    cbm_plant_set_load(p[k], 4321, 0.5, (cbm_vec3){0, 0, 0}, (cbm_vec3){0, 0, 0}));
            if (step == 2)
                for (size_t j = 0; j < 300; j++) {
                    cbm_segment_def s = cbm_segment_def_default();
                    s.parent = (int64_t)(j * 7919 % p[k]->n);
                    s.length = 0.02;
                    s.core.a = s.core.b = 0.004;
                    s.deviation = 0.5;
                    CHECK_OK(cbm_plant_add_segment(p[k], &s, NULL));
                }
            if (step == 3)
                CHECK_OK(cbm_plant_remove_subtree(p[k], 2500, NULL));
            order_force(k == 0);
            CHECK_OK(cbm_plant_solve(p[k], &sd, NULL));
            order_default();
        }
        CHECK_MSG(p[0]->sorder.valid && !p[0]->sorder.identity && !p[0]->sorder.active,
                  "step %d: the order was not used", step);
        CHECK_MSG(same_plant_bits(p[0], p[1]), "step %d: the solves differ", step);
        /* the workspace after the solve, renewed for a reader outside a solve, is the one the
         * solve in the plant's numbering leaves */
        CHECK(p[0]->work.stale && !p[1]->work.stale);
        cbm__mech_work_current(p[0]);
        size_t n = p[0]->n;
        const cbm__mech_work *w0 = &p[0]->work, *w1 = &p[1]->work;
        CHECK_MSG(!p[0]->work.stale && !memcmp(w0->dual, w1->dual, n * sizeof *w0->dual) &&
                      !memcmp(w0->cj, w1->cj, n * sizeof *w0->cj) &&
                      !memcmp(w0->rj, w1->rj, n * sizeof *w0->rj) &&
                      !memcmp(w0->wown, w1->wown, n * sizeof *w0->wown) &&
                      !memcmp(w0->kin, w1->kin, n * sizeof *w0->kin) &&
                      !memcmp(p[0]->cmass, p[1]->cmass, n * sizeof *p[0]->cmass),
                  "step %d: the workspace differs after the solve", step);
        double r[2];
        CHECK_OK(cbm_plant_evaluate(p[0], &r[0]));
        CHECK_OK(cbm_plant_evaluate(p[1], &r[1]));
        CHECK(memcmp(&r[0], &r[1], sizeof r[0]) == 0);
    }
    cbm__mech_tree_min_segments(50000);
    cbm_plant_destroy(p[0]);
    cbm_plant_destroy(p[1]);
    cbm_context_destroy(ctx);
}

/* The rigidities, rest rates, masses and tip loads are not gathered into the depth-first order:
 * the prepare reads them from the plant's own arrays through the order's map (solve_order.c).
 * Edited between warm solves on a plant whose topology stays (tip forces and moments on every
 * fifth segment, then point masses there, then a ring of growth on every segment: its rigidity,
 * mass per length and, by the shape memory, rest rate), the forest solved in the depth-first order
 * stays the same to the bit as the one solved in its own numbering, and each edit moves the
 * equilibrium (a solve that read the loads or sections of before would differ). */
TEST(order_reads_edited_sections_and_loads)
{
    cbm_context *ctx = NULL;
    CHECK_OK(cbm_context_create(NULL, &ctx));
    cbm_plant *p[2] = {forest(ctx, 6000), forest(ctx, 6000)};
    cbm_solve_def sd = cbm_solve_def_default();
    sd.threads = 2;
    cbm_growth_def gd = cbm_growth_def_default();
    cbm__mech_tree_min_segments(0);
    cbm_vec3 *before = p[0] ? malloc(p[0]->n * sizeof *before) : NULL;
    CHECK(before != NULL);
    for (int step = 0; step < 4 && p[0] && p[1] && before; step++) {
        for (int k = 0; k < 2; k++) {
            /* tip loads alone, then point masses (the forest's own, and more), then rings */
            for (size_t i = 3; i < p[k]->n && (step == 1 || step == 2); i += 5)
                CHECK_OK(cbm_plant_set_load(p[k], i,
                                            step == 1 ? p[k]->pmass[i] : 0.001 * (double)(i % 7),
                                            (cbm_vec3){0.002 * (double)(i % 3), 0, 0.001},
                                            (cbm_vec3){0, 0, 1e-5 * (double)(i % 4)}));
            if (step == 3)
                CHECK_OK(cbm_plant_grow_rings(p[k], &gd, NULL));
            order_force(k == 0);
            CHECK_OK(cbm_plant_solve(p[k], &sd, NULL));
            order_default();
        }
        CHECK_MSG(p[0]->sorder.valid && !p[0]->sorder.identity && !p[0]->sorder.active,
                  "step %d: the order was not used", step);
        CHECK_MSG(same_plant_bits(p[0], p[1]), "step %d: the solves differ", step);
        if (step > 0)
            CHECK_MSG(memcmp(before, p[0]->omega, p[0]->n * sizeof *before) != 0,
                      "step %d: the edit did not move the equilibrium", step);
        memcpy(before, p[0]->omega, p[0]->n * sizeof *before);
    }
    cbm__mech_tree_min_segments(50000);
    free(before);
    cbm_plant_destroy(p[0]);
    cbm_plant_destroy(p[1]);
    cbm_context_destroy(ctx);
}

/* The prepare reads no tip loads on a plant that never had one (prepare_range, p->tip_loads):
 * every writer of a tip force or moment notes it, -0.0 too (its sign may survive a sum); a zero
 * load leaves it unset. */
TEST(tip_loads_noted)
{
    cbm_context *ctx = NULL;
    CHECK_OK(cbm_context_create(NULL, &ctx));
    for (int k = 0; k < 3 && ctx; k++) {
        cbm_plant *p = NULL;
        CHECK_OK(cbm_plant_create(ctx, NULL, &p));
        if (!p)
            continue;
        cbm_segment_def s = cbm_segment_def_default();
        CHECK_OK(cbm_plant_add_segment(p, &s, NULL));
        CHECK_OK(cbm_plant_set_load(p, 0, 0.1, (cbm_vec3){0, 0, 0}, (cbm_vec3){0, 0, 0}));
        CHECK(!p->tip_loads);
        if (k == 0)
            CHECK_OK(cbm_plant_set_load(p, 0, 0.0, (cbm_vec3){-0.0, 0, 0}, (cbm_vec3){0, 0, 0}));
        if (k == 1)
            CHECK_OK(cbm_plant_set_load(p, 0, 0.0, (cbm_vec3){0, 0, 0}, (cbm_vec3){0, 0, 1e-3}));
        if (k == 2) {
            s.parent = 0;
            s.tip_force = (cbm_vec3){0, -1, 0};
            CHECK_OK(cbm_plant_add_segment(p, &s, NULL));
        }
        CHECK_MSG(p->tip_loads, "case %d: the tip load was not noted", k);
        cbm_plant_destroy(p);
    }
    cbm_context_destroy(ctx);
}

/* The sums over all segments follow the plant's numbering in the depth-first order too: the line
 * search's merit of one evaluation, the total potential energy and the S-weighted product of the
 * stability probes, computed on the arrays in that order (entered by hand, as cbm_plant_solve
 * does), are the same to the bit as in the plant's order; and the Krylov solver's dot products,
 * whose values steer every step it takes with the stiffness preconditioner, give the same solve. */
TEST(order_sums_in_plant_order)
{
    cbm_context *ctx = NULL;
    CHECK_OK(cbm_context_create(NULL, &ctx));
    cbm_plant *p = random_tree(ctx, 5000, 3e8, 0.02, false);
    for (int k = 0; k < 2 && p; k++) {
        double ss[2], e[2], sd[2], mm;
        for (int sorted = 0; sorted < 2; sorted++) {
            order_force(sorted);
            CHECK_OK(cbm__mech_work_reserve(p, 10));
            CHECK_OK(cbm__mech_order_enter(p, true));
            CHECK(p->sorder.active == (sorted == 1));
            cbm__mech_prepare(p);
            cbm__mech_forward_eval(p);
            double r = k == 0 ? cbm__mech_backward(p, 0.0, p->work.res, &mm, &ss[sorted])
                              : cbm__mech_backward_factor(p, p->work.res, &mm, &ss[sorted]);
            CHECK(isfinite(r));
            e[sorted] = cbm__mech_energy(p);
            sd[sorted] = cbm__mech_sdot(p, p->pos, p->pos);
            cbm__mech_order_leave(p);
            order_default();
        }
        CHECK_MSG(memcmp(&ss[0], &ss[1], sizeof ss[0]) == 0, "merit %.17g against %.17g", ss[0],
                  ss[1]);
        CHECK_MSG(memcmp(&e[0], &e[1], sizeof e[0]) == 0, "energy %.17g against %.17g", e[0], e[1]);
        CHECK_MSG(memcmp(&sd[0], &sd[1], sizeof sd[0]) == 0, "S product %.17g against %.17g", sd[0],
                  sd[1]);
        /* a bent state for the second round */
        cbm_solve_def d = cbm_solve_def_default();
        d.max_passes = 3;
        (void)cbm_plant_solve(p, &d, NULL);
    }
    cbm_plant_destroy(p);
    result r[2];
    cbm_plant *q[2] = {NULL, NULL};
    for (int sorted = 0; sorted < 2; sorted++) {
        q[sorted] = random_tree(ctx, 5000, 3e8, 0.02, false);
        cbm_solve_def d = cbm_solve_def_default();
        d.warm_start = false;
        d.preconditioner = CBM_MECH_PRECOND_STIFFNESS;
        d.max_passes = 60;
        cbm_solve_stats st = {0};
        order_force(sorted);
        cbm_status s = q[sorted] ? cbm_plant_solve(q[sorted], &d, &st) : CBM_E_NOMEM;
        order_default();
        CHECK(s == CBM_OK || s == CBM_E_NOT_CONVERGED);
        r[sorted].krylov = st.krylov_iterations;
        r[sorted].residual = st.residual;
    }
    printf("stiffness preconditioner: %zu Krylov iterations\n", r[0].krylov);
    CHECK(r[0].krylov > 5);
    CHECK_EQ_INT(r[0].krylov, r[1].krylov);
    CHECK(memcmp(&r[0].residual, &r[1].residual, sizeof r[0].residual) == 0);
    CHECK(same_plant_bits(q[0], q[1]));
    cbm_plant_destroy(q[0]);
    cbm_plant_destroy(q[1]);
    cbm_context_destroy(ctx);
}
