/* The continuous elastica (docs/elastica.md, docs/validation.md "Elastica"): the heavy
 * cantilever table and the folds, jump targets and multiple solutions derived in the Tresierras
 * digest (independent RK4 shooting, 2000 steps), Greenhill's alpha_c = (9/4) j_{-1/3}^2 as the
 * bifurcation of the S-curve family, the rigid limit (4.8), the exact circle of a two-piece rod
 * under a tip moment, the two stability tests against each other, the discontinuity equivalence
 * (2.26) and the four stable states of Fig. 5.4. */
#include "test.h"

#include <string.h>

#define DEG (180.0 / 3.14159265358979323846)

typedef struct rod1 {
    cbm_elastica_piece pc;
    cbm_elastica_rod rod;
} rod1;

static void uniform(rod1 *r, double alpha)
{
    r->pc = cbm_elastica_piece_default();
    r->pc.w0 = r->pc.w1 = alpha;
    r->rod = cbm_elastica_rod_default();
    r->rod.pieces = &r->pc;
    r->rod.n_pieces = 1;
}

static cbm_elastica_scurve *curve(cbm_context *ctx, const rod1 *r)
{
    cbm_elastica_scurve *sc = NULL;
    CHECK_OK(cbm_elastica_scurve_compute(ctx, &r->rod, NULL, &sc));
    return sc;
}

/* digest §4 [derived] table: horizontal clamp, free tip */
TEST(elastica_heavy_cantilever_table)
{
    cbm_context *ctx = test_ctx();
    const double t[4][6] = {{1, -9.460, -0.4969, 0.9912, -0.1235, -0.0249},
                            {5, -39.935, -2.2269, 0.8467, -0.4959, -0.5580},
                            {10, -60.312, -3.7422, 0.6564, -0.7002, -1.8321},
                            {15, -70.750, -4.8561, 0.5296, -0.7860, -3.4251}};
    for (int i = 0; i < 4; i++) {
        rod1 r;
        uniform(&r, t[i][0]);
        cbm_elastica_scurve *sc = curve(ctx, &r);
        cbm_elastica_state eq[8];
        size_t n = 0;
        CHECK_OK(cbm_elastica_equilibria(ctx, &r.rod, sc, 0.0, eq, 8, &n));
        CHECK_EQ_INT((int)n, 1);
        CHECK_NEAR(eq[0].theta_tip * DEG, t[i][1], 2e-3);
        CHECK_NEAR(eq[0].curvature_base, t[i][2], 1e-4);
        CHECK_NEAR(eq[0].tip_x, t[i][3], 1e-4);
        CHECK_NEAR(eq[0].tip_y, t[i][4], 1e-4);
        CHECK_NEAR(eq[0].energy, t[i][5], 1e-4);
        CHECK_EQ_INT(eq[0].index, 0);
        /* small-deflection limit at alpha = 1: delta / L = alpha / 8 within the nonlinearity */
        if (i == 0)
            CHECK_NEAR(-eq[0].tip_y, 0.125, 2e-3);
        cbm_elastica_scurve_destroy(ctx, sc);
    }
    test_ctx_end(ctx);
}

/* Fig. 4.6 jumping points and jump targets at alpha = 15 (digest, derived) */
TEST(elastica_folds_alpha15)
{
    cbm_context *ctx = test_ctx();
    rod1 r;
    uniform(&r, 15);
    cbm_elastica_scurve *sc = curve(ctx, &r);
    CHECK_EQ_INT((int)sc->n_folds, 2);
    if (sc->n_folds == 2) {
        const cbm_elastica_fold *a = &sc->folds[0], *b = &sc->folds[1];
        CHECK_NEAR(a->at.theta_base * DEG, 116.41, 0.01);
        CHECK_NEAR(a->at.theta_tip * DEG, 11.46, 0.01);
        CHECK_NEAR(a->at.curvature_base, -3.210, 1e-3);
        CHECK_NEAR(a->at.energy, 8.021, 1e-3);
        CHECK_NEAR(b->at.theta_base * DEG, 180 - 116.41, 0.01);
        CHECK_NEAR(b->at.curvature_base, 3.210, 1e-3);
        CHECK(a->has_target && b->has_target);
        CHECK_NEAR(a->target.theta_tip * DEG, 230.44, 0.01);
        CHECK_NEAR(a->target.curvature_base, 6.167, 1e-3);
        CHECK_NEAR(a->target.tip_x, -0.7733, 1e-4);
        CHECK_NEAR(a->target.tip_y, -0.3722, 1e-4);
        CHECK_NEAR(a->target.energy, 2.934, 1e-3);
        CHECK_EQ_INT(a->target.index, 0);
        CHECK_NEAR(b->target.curvature_base, -6.167, 1e-3);
    }
    /* vertical clamp: two stable bent states and the unstable column */
    cbm_elastica_state eq[8];
    size_t n = 0;
    CHECK_OK(cbm_elastica_equilibria(ctx, &r.rod, sc, 0.5 * 3.14159265358979323846, eq, 8, &n));
    CHECK_EQ_INT((int)n, 3);
    if (n == 3) {
        CHECK_NEAR(eq[0].theta_tip * DEG, -35.89, 0.01);
        CHECK_NEAR(eq[0].curvature_base, -5.750, 1e-3);
        CHECK_NEAR(eq[0].energy, 5.711, 1e-3);
        CHECK_NEAR(eq[1].energy, 7.5, 1e-9);
        CHECK_EQ_INT(eq[0].index + eq[1].index + eq[2].index, 1);
        CHECK_EQ_INT(eq[1].index, 1);
    }
    /* hysteresis: sweeping up jumps at 116.41 deg, down at 63.59 deg */
    cbm_elastica_jump j[4];
    size_t np = 0, nj = 0;
    CHECK_OK(cbm_elastica_sweep(ctx, &r.rod, sc, -3.14159265358979323846 / 2,
                                1.5 * 3.14159265358979323846, NULL, 0, &np, j, 4, &nj));
    CHECK_EQ_INT((int)nj, 1);
    if (nj >= 1)
        CHECK_NEAR(j[0].from.theta_base * DEG, 116.41, 0.01);
    CHECK_OK(cbm_elastica_sweep(ctx, &r.rod, sc, 1.5 * 3.14159265358979323846,
                                -3.14159265358979323846 / 2, NULL, 0, &np, j, 4, &nj));
    CHECK_EQ_INT((int)nj, 1);
    if (nj >= 1) {
        CHECK_NEAR(j[0].from.theta_base * DEG, 63.59, 0.01);
        CHECK_NEAR(j[0].to.curvature_base, -6.167, 1e-3);
    }
    cbm_elastica_scurve_destroy(ctx, sc);
    test_ctx_end(ctx);
}

/* Fig. 4.1: alpha = 8, vertical clamp: exactly three solutions (digest, derived) */
TEST(elastica_three_solutions_alpha8)
{
    cbm_context *ctx = test_ctx();
    rod1 r;
    uniform(&r, 8);
    cbm_elastica_scurve *sc = curve(ctx, &r);
    cbm_elastica_state eq[8];
    size_t n = 0;
    CHECK_OK(cbm_elastica_equilibria(ctx, &r.rod, sc, 0.5 * 3.14159265358979323846, eq, 8, &n));
    CHECK_EQ_INT((int)n, 3);
    if (n == 3) {
        CHECK_NEAR(eq[0].theta_tip * DEG, 65.71, 0.01);
        CHECK_NEAR(eq[2].theta_tip * DEG, 114.29, 0.01);
        CHECK_NEAR(eq[0].curvature_base, -0.9290, 1e-4);
        CHECK_NEAR(eq[0].tip_x, 0.2982, 1e-4);
        CHECK_NEAR(eq[0].tip_y, 0.9461, 1e-4);
        CHECK_NEAR(eq[0].energy, 3.9985, 1e-4);
        CHECK_NEAR(eq[1].energy, 4.0, 1e-9);
        CHECK_EQ_INT(eq[0].index, 0);
        CHECK_EQ_INT(eq[1].index, 1);
        CHECK_EQ_INT(eq[2].index, 0);
    }
    /* the folds of alpha = 8 (digest: 90.14 deg, theta_tip 75.95, kappa -0.538) */
    CHECK_EQ_INT((int)sc->n_folds, 2);
    if (sc->n_folds == 2) {
        CHECK_NEAR(sc->folds[0].at.theta_base * DEG, 90.14, 0.01);
        CHECK_NEAR(sc->folds[0].at.theta_tip * DEG, 75.95, 0.01);
        CHECK_NEAR(sc->folds[0].at.curvature_base, -0.538, 1e-3);
    }
    cbm_elastica_scurve_destroy(ctx, sc);
    test_ctx_end(ctx);
}

/* Greenhill: the inverted column's d theta_base / d theta_tip changes sign at alpha_c; the
 * S-curves below have no fold, those above have two near 90 degrees. Reference: (9/4) j^2 with
 * j = 1.86635086 the first zero of J_{-1/3} (A&S tables), 7.83735. */
TEST(elastica_greenhill_bifurcation)
{
    cbm_context *ctx = test_ctx();
    double lo = 7.0, hi = 9.0;
    for (int it = 0; it < 50; it++) {
        double a = 0.5 * (lo + hi);
        rod1 r;
        uniform(&r, a);
        cbm_elastica_state st;
        CHECK_OK(cbm_elastica_shoot(ctx, &r.rod, 0.5 * 3.14159265358979323846, &st));
        if (st.dbase_dtip > 0)
            lo = a;
        else
            hi = a;
    }
    CHECK_NEAR(0.5 * (lo + hi), 2.25 * 1.86635086 * 1.86635086, 1e-6);
    CHECK_NEAR(0.5 * (lo + hi), CBM_ELASTICA_ALPHA_CRITICAL, 1e-4);
    printf("alpha_c = %.7f\n", 0.5 * (lo + hi));
    const double fam[] = {0.01, 5, 7.8, 7.845, 7.9, 30};
    const int folds[] = {0, 0, 0, 2, 2, 2};
    for (int i = 0; i < 6; i++) {
        rod1 r;
        uniform(&r, fam[i]);
        cbm_elastica_scurve *sc = curve(ctx, &r);
        CHECK_EQ_INT((int)sc->n_folds, folds[i]);
        if (fam[i] == 7.9 && sc->n_folds == 2)
            CHECK_NEAR(sc->folds[0].at.theta_base * DEG, 90.03, 0.01);
        if (fam[i] == 30 && sc->n_folds == 2) { /* Fig. 4.4a, digest derived */
            CHECK_NEAR(sc->folds[0].at.theta_base * DEG, 162.12, 0.01);
            CHECK_NEAR(sc->folds[0].at.theta_tip * DEG, -30.48, 0.01);
            CHECK_NEAR(sc->folds[0].at.curvature_base, -3.234, 1e-3);
            cbm_elastica_state eq[8];
            size_t n = 0;
            CHECK_OK(
                cbm_elastica_equilibria(ctx, &r.rod, sc, 0.5 * 3.14159265358979323846, eq, 8, &n));
            CHECK_EQ_INT((int)n, 3);
            if (n == 3) {
                CHECK_NEAR(eq[0].theta_tip * DEG, -72.17, 0.01);
                CHECK_NEAR(eq[0].curvature_base, -9.590, 1e-3);
                CHECK_NEAR(eq[0].energy, 5.147, 1e-3);
                CHECK_NEAR(eq[1].energy, 15.0, 1e-9);
            }
        }
        if (fam[i] == 0.01) /* Fig. 4.4c: the rigid limit (4.8), -(alpha/2) cos theta_base */
            for (int k = 0; k < 3; k++) {
                cbm_elastica_state eq[4];
                size_t n = 0;
                double tb = k * 30 / DEG;
                CHECK_OK(cbm_elastica_equilibria(ctx, &r.rod, sc, tb, eq, 4, &n));
                CHECK_EQ_INT((int)n, 1);
                /* first order in alpha: the O(alpha^2) rest is below 1e-3 relative */
                CHECK_NEAR(eq[0].curvature_base, -0.005 * cos(tb), 5e-6);
                const double dig[] = {-0.005000, -0.004332, -0.002502}; /* digest, derived */
                CHECK_NEAR(eq[0].curvature_base, dig[k], 1e-6);
            }
        /* the two stability tests agree: stable (Sturm index 0) points rise, index parity is
         * the sign of d theta_base / d theta_tip */
        int bad = 0;
        for (size_t k = 0; k < sc->n_points; k++) {
            const cbm_elastica_state *s = &sc->points[k];
            if (fabs(s->dbase_dtip) < 1e-6)
                continue;
            if ((s->index % 2 == 1) != (s->dbase_dtip < 0))
                bad++;
        }
        CHECK_EQ_INT(bad, 0);
        cbm_elastica_scurve_destroy(ctx, sc);
    }
    test_ctx_end(ctx);
}

/* A rod of two pieces of different stiffness under a tip moment alone: each piece is a circular
 * arc, theta_tip - theta_base = M (L1 / D1 + L2 / D2), exactly. */
TEST(elastica_piecewise_moment)
{
    cbm_context *ctx = test_ctx();
    cbm_elastica_piece pc[2] = {cbm_elastica_piece_default(), cbm_elastica_piece_default()};
    pc[0].length = 0.3, pc[0].D0 = pc[0].D1 = 2.0;
    pc[1].length = 0.7, pc[1].D0 = pc[1].D1 = 0.5, pc[1].rest_curvature = 0.4;
    cbm_elastica_rod rod = cbm_elastica_rod_default();
    rod.pieces = pc, rod.n_pieces = 2, rod.tip_moment = 0.8;
    cbm_elastica_state st;
    CHECK_OK(cbm_elastica_shoot(ctx, &rod, 1.0, &st));
    CHECK_NEAR(1.0 - st.theta_base, 0.8 * (0.3 / 2.0 + 0.7 / 0.5) + 0.4 * 0.7, 1e-10);
    CHECK_NEAR(st.moment_base, 0.8, 1e-12);
    CHECK_NEAR(st.energy, 0.5 * 0.8 * 0.8 * (0.3 / 2.0 + 0.7 / 0.5) - 0.8 * 1.0, 1e-10);
    test_ctx_end(ctx);
}

static cbm_status plant_eq(cbm_context *ctx, const cbm_elastica_branch *b, size_t nb, double tb,
                           cbm_elastica_plant_state **out, size_t *n)
{
    cbm_elastica_plant_def d = cbm_elastica_plant_def_default();
    return cbm_elastica_plant_equilibria(ctx, b, nb, &d, tb, out, n);
}

/* (2.26): a rod cut in two collinear branches is the same rod; the discrete second variation of
 * the plant agrees with the Sturm count of the rod. */
TEST(elastica_branch_equivalence)
{
    cbm_context *ctx = test_ctx();
    cbm_elastica_piece half = cbm_elastica_piece_default();
    half.length = 0.5, half.w0 = half.w1 = 15;
    cbm_elastica_branch b[2];
    memset(b, 0, sizeof b);
    b[0].parent = -1, b[0].pieces = &half, b[0].n_pieces = 1;
    b[1].parent = 0, b[1].pieces = &half, b[1].n_pieces = 1;
    cbm_elastica_plant_state *ps = NULL;
    size_t n = 0;
    CHECK_OK(plant_eq(ctx, b, 2, 0.5 * 3.14159265358979323846, &ps, &n));
    rod1 r;
    uniform(&r, 15);
    cbm_elastica_scurve *sc = curve(ctx, &r);
    cbm_elastica_state eq[8];
    size_t ne = 0;
    CHECK_OK(cbm_elastica_equilibria(ctx, &r.rod, sc, 0.5 * 3.14159265358979323846, eq, 8, &ne));
    CHECK_EQ_INT((int)n, (int)ne);
    for (size_t i = 0; i < n && i < ne; i++) {
        /* match by the tip angle of the outer branch */
        size_t k = 0;
        while (k < ne && fabs(eq[k].theta_tip - ps[i].theta_tip[1]) > 1e-6)
            k++;
        CHECK(k < ne);
        if (k == ne)
            continue;
        CHECK_NEAR(ps[i].moment_base[0], eq[k].moment_base, 1e-7);
        CHECK_NEAR(ps[i].tip_x[1], eq[k].tip_x, 1e-8);
        CHECK_NEAR(ps[i].tip_y[1], eq[k].tip_y, 1e-8);
        CHECK_NEAR(ps[i].energy, eq[k].energy, 1e-7);
        CHECK_EQ_INT(ps[i].index, eq[k].index);
    }
    cbm_elastica_plant_states_destroy(ctx, ps, n, 2);
    cbm_elastica_scurve_destroy(ctx, sc);
    test_ctx_end(ctx);
}

/* Fig. 5.4: two bistable free-end branches (alpha = 10 each) on a stiff base at 90 degrees:
 * nine equilibria, of which four are stable, (L,L), (L,R), (R,L), (R,R). */
TEST(elastica_branched_four_states)
{
    cbm_context *ctx = test_ctx();
    cbm_elastica_piece base = cbm_elastica_piece_default(), twig = base;
    base.w0 = base.w1 = 0.2;
    twig.D0 = twig.D1 = 0.02, twig.w0 = twig.w1 = 0.2;
    cbm_elastica_branch b[3];
    memset(b, 0, sizeof b);
    b[0].parent = -1, b[0].pieces = &base, b[0].n_pieces = 1;
    b[1].parent = 0, b[1].pieces = &twig, b[1].n_pieces = 1;
    b[2] = b[1];
    cbm_elastica_plant_state *ps = NULL;
    size_t n = 0;
    CHECK_OK(plant_eq(ctx, b, 3, 0.5 * 3.14159265358979323846, &ps, &n));
    CHECK_EQ_INT((int)n, 9);
    int stable = 0, lr[4] = {0, 0, 0, 0};
    for (size_t i = 0; i < n; i++)
        if (ps[i].index == 0) {
            stable++;
            /* which way each branch leans: its tip left or right of its base */
            int l1 = ps[i].tip_x[1] < ps[i].tip_x[0], l2 = ps[i].tip_x[2] < ps[i].tip_x[0];
            lr[2 * l1 + l2]++;
        }
    CHECK_EQ_INT(stable, 4);
    for (int k = 0; k < 4; k++)
        CHECK_EQ_INT(lr[k], 1);
    cbm_elastica_plant_states_destroy(ctx, ps, n, 3);
    test_ctx_end(ctx);
}

TEST(elastica_spec_errors)
{
    cbm_context *ctx = test_ctx();
    cbm_elastica_spec sp;
    const char *good = "alpha = 15\nangle = 200\nbranch = parent 0 offset 10 stiffness 0.5\n";
    CHECK_OK(cbm_elastica_spec_parse(ctx, good, strlen(good), "g.spec", &sp));
    CHECK(sp.dimensionless && sp.has_angle && sp.angle == 200 && sp.n_branches == 1);
    const char *bad[] = {"alpha = 15\nradius = 0.01\n",
                         "branch = parent 3\n",
                         "alpha = 1\nbranch = parent 0 radius 0.1\n",
                         "angle = x\n",
                         "theta_tip_min = 10\ntheta_tip_max = 0\n",
                         "alpha = 2\nalpha = 3\n",
                         "branch = parent 0 colour 3\n",
                         "alpha = 15\nsteps = 3\n", /* growth is dimensional */
                         "steps = 3\nbranch = parent 0\n",
                         "taper = step\n" /* a growth key without steps */};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        cbm_status s = cbm_elastica_spec_parse(ctx, bad[i], strlen(bad[i]), "b.spec", &sp);
        CHECK(s == CBM_E_SEMANTIC || s == CBM_E_SYNTAX);
    }
    cbm_context_clear_errors(ctx);
    test_ctx_end(ctx);
}

/* A dimensional bend spec is the same rod as alpha = rho g A L^3 / (E I). */
TEST(elastica_dimensional_mode)
{
    cbm_context *ctx = test_ctx();
    const char *txt = "length = 2\nradius = 0.01\nE = 7.85e7\ndensity = 1000\nangle = 30\n";
    cbm_elastica_spec sp;
    CHECK_OK(cbm_elastica_spec_parse(ctx, txt, strlen(txt), "d.spec", &sp));
    cbm_elastica_piece pc[1];
    cbm_elastica_branch br[1];
    double L = 0, D = 0;
    CHECK_OK(cbm_elastica_spec_plant(&sp, pc, br, &L, &D));
    double A = 3.14159265358979323846 * 1e-4, I = 3.14159265358979323846 * 1e-8 / 4;
    double alpha = 1000 * 9.81 * A * 8 / (7.85e7 * I);
    CHECK_NEAR(pc[0].w0 * L * L * L / D, alpha, 1e-9 * alpha);
    cbm_elastica_rod rd = cbm_elastica_rod_default();
    rd.pieces = pc, rd.n_pieces = 1;
    cbm_elastica_scurve *sc = NULL;
    CHECK_OK(cbm_elastica_scurve_compute(ctx, &rd, NULL, &sc));
    rod1 r;
    uniform(&r, alpha);
    cbm_elastica_scurve *sc1 = curve(ctx, &r);
    cbm_elastica_state a[4], b[4];
    size_t na = 0, nb = 0;
    CHECK_OK(cbm_elastica_equilibria(ctx, &rd, sc, 30 / DEG, a, 4, &na));
    CHECK_OK(cbm_elastica_equilibria(ctx, &r.rod, sc1, 30 / DEG, b, 4, &nb));
    CHECK_EQ_INT((int)na, (int)nb);
    CHECK(na >= 1);
    for (size_t i = 0; i < na && i < nb && i < 4; i++) {
        CHECK_NEAR(a[i].theta_tip, b[i].theta_tip, 1e-9);
        CHECK_NEAR(a[i].tip_x / L, b[i].tip_x, 1e-9);
        CHECK_NEAR(a[i].tip_y / L, b[i].tip_y, 1e-9);
        CHECK_NEAR(a[i].curvature_base * L, b[i].curvature_base, 1e-9);
        CHECK_NEAR(a[i].energy * L / D, b[i].energy, 1e-9);
        CHECK_EQ_INT(a[i].index, b[i].index);
    }
    cbm_elastica_scurve_destroy(ctx, sc);
    cbm_elastica_scurve_destroy(ctx, sc1);
    test_ctx_end(ctx);
}

/* Fig. 5.7's 7-branch plant (examples/elastica/fig5_7.spec): four bistable free-end branches
 * give 3^4 equilibria, 2^4 of them stable, and each one's Morse index is the number of free-end
 * branches in their (unstable) middle state, i.e. near their own base angle. */
TEST(elastica_seven_branch_plant)
{
    cbm_context *ctx = test_ctx();
    FILE *f = fopen(CBM_TEST_SOURCE_DIR "/examples/elastica/fig5_7.spec", "rb");
    CHECK(f != NULL);
    if (!f) {
        test_ctx_end(ctx);
        return;
    }
    char txt[4096];
    size_t len = fread(txt, 1, sizeof txt, f);
    fclose(f);
    cbm_elastica_spec sp;
    CHECK_OK(cbm_elastica_spec_parse(ctx, txt, len, "fig5_7.spec", &sp));
    CHECK_EQ_INT((int)sp.n_branches, 6);
    cbm_elastica_piece pc[7];
    cbm_elastica_branch br[7];
    CHECK_OK(cbm_elastica_spec_plant(&sp, pc, br, NULL, NULL));
    cbm_elastica_plant_state *ps = NULL;
    size_t n = 0;
    CHECK_OK(plant_eq(ctx, br, 7, sp.angle / DEG, &ps, &n));
    CHECK_EQ_INT((int)n, 81);
    /* each free-end branch's tip, relative to its base, takes three clustered values over the
     * 81 states: bent one way (the least), bent the other (the greatest), and the middle */
    double lo[7], hi[7];
    for (int b = 3; b < 7; b++) {
        lo[b] = 10, hi[b] = -10;
        for (size_t i = 0; i < n; i++) {
            double d = remainder(ps[i].theta_tip[b] - ps[i].theta_base[b], 2 * 3.14159265358979);
            lo[b] = fmin(lo[b], d), hi[b] = fmax(hi[b], d);
        }
    }
    int stable = 0, rule = 0;
    for (size_t i = 0; i < n; i++) {
        stable += ps[i].index == 0;
        int middle = 0;
        for (int b = 3; b < 7; b++) {
            double d = remainder(ps[i].theta_tip[b] - ps[i].theta_base[b], 2 * 3.14159265358979);
            middle += d > lo[b] + 20 / DEG && d < hi[b] - 20 / DEG;
        }
        rule += middle == ps[i].index;
    }
    CHECK_EQ_INT(stable, 16);
    CHECK_EQ_INT(rule, (int)n);
    cbm_elastica_plant_states_destroy(ctx, ps, n, 7);
    test_ctx_end(ctx);
}
