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

typedef struct result {
    size_t n, passes, newton, krylov;
    double residual;
    cbm_vec3 *omega, *moment, *pos;
} result;

static result solve_with(size_t n, double E, double leaf, bool chain, int threads, bool fuse)
{
    result r = {0};
    cbm__mech_newton_fuse(fuse);
    cbm__mech_tree_min_segments(0);
    cbm_context *ctx = NULL;
    CHECK_OK(cbm_context_create(NULL, &ctx));
    cbm_plant *p = random_tree(ctx, n, E, leaf, chain);
    if (p) {
        cbm_solve_def d = cbm_solve_def_default();
        d.warm_start = false;
        d.threads = threads;
        cbm_solve_stats st;
        CHECK_OK(cbm_plant_solve(p, &d, &st));
        r.n = p->n;
        r.passes = st.passes;
        r.newton = st.newton_steps;
        r.krylov = st.krylov_iterations;
        r.residual = st.residual;
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
    cbm__mech_newton_fuse(true);
    return r;
}

static void result_free(result *r)
{
    free(r->omega);
    free(r->moment);
    free(r->pos);
}

/* The solves with 2 and 3 threads (fused evaluations), then with 1 and 2 threads without the
 * fused evaluations (solve_newton.c, evaluate_as), against the serial fused one. */
static void check_same(size_t n, double E, double leaf, bool chain)
{
    result one = solve_with(n, E, leaf, chain, 1, true);
    CHECK(one.n == n && one.passes > 0);
    for (int t = 2; t <= 5; t++) {
        bool fuse = t <= 3;
        int threads = fuse ? t : t - 3;
        result r = solve_with(n, E, leaf, chain, threads, fuse);
        CHECK(r.n == n);
        CHECK_EQ_INT(r.passes, one.passes);
        CHECK_EQ_INT(r.newton, one.newton);
        CHECK_EQ_INT(r.krylov, one.krylov);
        CHECK(memcmp(&r.residual, &one.residual, sizeof r.residual) == 0);
        if (r.omega && one.omega) {
            CHECK_MSG(!memcmp(r.omega, one.omega, n * sizeof *r.omega),
                      "%d threads, fused %d: Omega differs", threads, fuse);
            CHECK_MSG(!memcmp(r.moment, one.moment, n * sizeof *r.moment),
                      "%d threads, fused %d: moments differ", threads, fuse);
            CHECK_MSG(!memcmp(r.pos, one.pos, n * sizeof *r.pos),
                      "%d threads, fused %d: positions differ", threads, fuse);
        }
        result_free(&r);
    }
    result_free(&one);
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
