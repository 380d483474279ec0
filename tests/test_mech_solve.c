/* Checks of the plant data structure and the solvers on branched trees: torque recursion against
 * the direct sum (Taylor-Hell oracle 3), mass conservation, the tangent passes against finite
 * differences, both solvers at the same equilibrium, rings and section aggregates, subtree
 * removal, errors (non-convergence, NaN, bad input, limits), no allocation in the solver loop,
 * out-of-memory behaviour. */
#include "mech_testlib.h"
#include "mech/mech_internal.h"
#include "cambium/tree.h"

/* A random tree: each new segment picks a random existing parent (biased to recent ones), random
 * branching angles, radius shrinking with depth, point masses and tip forces on some. */
static cbm_plant *random_tree(cbm_context *ctx, size_t n, double E)
{
    cbm_plant *p = clamped_plant(ctx, PI / 2);
    if (!p)
        return NULL;
    for (size_t i = 0; i < n; i++) {
        cbm_segment_def d = cbm_segment_def_default();
        if (i > 0) {
            double u = cbm_context_uniform(ctx);
            size_t back = (size_t)(u * u * u * (double)i);
            d.parent = (int64_t)(i - 1 - back);
            d.divergence = 2.4 * (double)i;
            d.deviation = (cbm_context_uniform(ctx) - 0.5) * 1.5;
            d.roll = -d.divergence;
        }
        d.length = 0.05 + 0.1 * cbm_context_uniform(ctx);
        d.core.youngs_modulus = E;
        d.core.shear_modulus = E / 2.6;
        d.core.a = 0.02 * (1.0 + 0.5 * cbm_context_uniform(ctx)) / (1.0 + 0.02 * (double)i);
        d.core.b = d.core.a * (0.7 + 0.3 * cbm_context_uniform(ctx));
        d.core.rest_rate = (cbm_vec3){0.1 * (cbm_context_uniform(ctx) - 0.5),
                                      0.5 * (cbm_context_uniform(ctx) - 0.5),
                                      0.5 * (cbm_context_uniform(ctx) - 0.5)};
        d.omega = d.core.rest_rate;
        if (cbm_context_uniform(ctx) < 0.3)
            d.point_mass = 0.05 * cbm_context_uniform(ctx);
        if (cbm_context_uniform(ctx) < 0.1)
            d.tip_force = (cbm_vec3){0.1, -0.2, 0.05};
        if (cbm_context_uniform(ctx) < 0.1)
            d.tip_moment = (cbm_vec3){0.001, 0.002, -0.001};
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    return p;
}

static bool in_subtree(const cbm_plant *p, size_t root, size_t j)
{
    const int64_t *par = cbm_plant_parents(p);
    while (j > root && par[j] >= 0)
        j = (size_t)par[j];
    return j == root;
}

TEST(mech_torque_recursion_equals_direct_sum)
{
    cbm_context *ctx = test_ctx();
    for (int disc = 0; disc < 2; disc++) {
        cbm_plant *p = random_tree(ctx, 120, 1e9);
        cbm_plant_set_discretization(p, (cbm_mech_discretization)disc);
        /* arbitrary rotation rates: the identity holds for any configuration */
        for (size_t i = 0; i < 120; i++)
            CHECK_OK(cbm_plant_set_omega(p, i,
                                         (cbm_vec3){0.3 * sin((double)i), cos(0.7 * (double)i),
                                                    0.5 * sin(1.3 * (double)i)}));
        CHECK_OK(cbm_plant_evaluate(p, NULL));
        cbm_vec3 g = cbm_plant_gravity(p);
        double total = 0;
        for (size_t i = 0; i < 120; i++) {
            cbm_segment_state si;
            CHECK_OK(cbm_plant_segment(p, i, &si));
            cbm_vec3 M = {0, 0, 0}, F = {0, 0, 0};
            double mass = 0;
            for (size_t j = i; j < 120; j++) {
                if (!in_subtree(p, i, j))
                    continue;
                cbm_segment_state s;
                CHECK_OK(cbm_plant_segment(p, j, &s));
                double wm = s.mass_per_length * s.length;
                double frac = disc == CBM_MECH_STAGGERED ? 0.5 : 1.0;
                cbm_vec3 c = {s.proximal.x + frac * s.length * s.frame.h.x,
                              s.proximal.y + frac * s.length * s.frame.h.y,
                              s.proximal.z + frac * s.length * s.frame.h.z};
                cbm_vec3 fw = {g.x * wm, g.y * wm, g.z * wm};
                cbm_vec3 ft = {g.x * s.point_mass + s.tip_force.x,
                               g.y * s.point_mass + s.tip_force.y,
                               g.z * s.point_mass + s.tip_force.z};
                cbm_vec3 rc = {c.x - si.proximal.x, c.y - si.proximal.y, c.z - si.proximal.z};
                cbm_vec3 rt = {s.distal.x - si.proximal.x, s.distal.y - si.proximal.y,
                               s.distal.z - si.proximal.z};
                /* direct sum (Taylor-Hell 6.14): sum of r x F plus applied moments */
                M.x += rc.y * fw.z - rc.z * fw.y + rt.y * ft.z - rt.z * ft.y + s.tip_moment.x;
                M.y += rc.z * fw.x - rc.x * fw.z + rt.z * ft.x - rt.x * ft.z + s.tip_moment.y;
                M.z += rc.x * fw.y - rc.y * fw.x + rt.x * ft.y - rt.y * ft.x + s.tip_moment.z;
                F.x += fw.x + ft.x;
                F.y += fw.y + ft.y;
                F.z += fw.z + ft.z;
                mass += wm + s.point_mass;
            }
            double sc = 1e-12 * (fabs(M.x) + fabs(M.y) + fabs(M.z) + 1e-9);
            CHECK_NEAR(si.moment.x, M.x, sc);
            CHECK_NEAR(si.moment.y, M.y, sc);
            CHECK_NEAR(si.moment.z, M.z, sc);
            CHECK_NEAR(si.force.y, F.y, 1e-12 * fabs(F.y) + 1e-15);
            CHECK_REL(si.carried_mass, mass, 1e-13);
            if (si.parent < 0)
                total += si.carried_mass;
        }
        CHECK_REL(total, cbm_plant_total_mass(p), 1e-13);
        cbm_plant_destroy(p);
    }
    test_ctx_end(ctx);
}

TEST(mech_tangent_matches_finite_differences)
{
    cbm_context *ctx = test_ctx();
    size_t n = 60;
    cbm_plant *p = random_tree(ctx, n, 1e7);
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    CHECK_OK(cbm__mech_work_reserve(p, 1));
    cbm__mech_prepare(p);
    cbm_vec3 *v = calloc(n, sizeof *v), *jv = calloc(n, sizeof *jv), *rp = calloc(n, sizeof *rp),
             *rm = calloc(n, sizeof *rm), *om = calloc(n, sizeof *om);
    for (size_t i = 0; i < n; i++) {
        v[i] = (cbm_vec3){sin(3.0 * (double)i), cos(5.0 * (double)i), sin(7.0 * (double)i + 1)};
        om[i] = p->omega[i];
    }
    double mm;
    cbm__mech_forward(p);
    cbm__mech_backward(p, 0.0, NULL, &mm, NULL);
    cbm__mech_jvp(p, v, jv);
    double eps = 1e-6, maxd = 0, maxj = 0;
    for (int sgn = -1; sgn <= 1; sgn += 2) {
        for (size_t i = 0; i < n; i++)
            p->omega[i] = (cbm_vec3){om[i].x + sgn * eps * v[i].x, om[i].y + sgn * eps * v[i].y,
                                     om[i].z + sgn * eps * v[i].z};
        cbm__mech_forward(p);
        cbm__mech_backward(p, 0.0, sgn < 0 ? rm : rp, &mm, NULL);
    }
    for (size_t i = 0; i < n; i++) {
        double fd[3] = {(rp[i].x - rm[i].x) / (2 * eps), (rp[i].y - rm[i].y) / (2 * eps),
                        (rp[i].z - rm[i].z) / (2 * eps)};
        double a[3] = {jv[i].x, jv[i].y, jv[i].z};
        for (int k = 0; k < 3; k++) {
            if (fabs(fd[k] - a[k]) > maxd)
                maxd = fabs(fd[k] - a[k]);
            if (fabs(a[k]) > maxj)
                maxj = fabs(a[k]);
        }
    }
    printf("tangent vs central differences: max diff %.3g, max |Jv| %.3g\n", maxd, maxj);
    CHECK(maxd < 1e-7 * maxj);
    free(v);
    free(jv);
    free(rp);
    free(rm);
    free(om);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* The O(n) tree factorisation inverts the tangent operator exactly: solve(J v) = v. */
TEST(mech_tree_factorisation_inverts_tangent)
{
    cbm_context *ctx = test_ctx();
    size_t n = 150;
    cbm_plant *p = random_tree(ctx, n, 1e6); /* soft: large geometric stiffness */
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    CHECK_OK(cbm__mech_work_reserve(p, 2));
    cbm__mech_prepare(p);
    double mm;
    cbm__mech_forward(p);
    cbm__mech_backward(p, 0.0, NULL, &mm, NULL);
    cbm_vec3 *v = calloc(n, sizeof *v), *jv = calloc(n, sizeof *jv),
             *back = calloc(n, sizeof *back);
    for (size_t i = 0; i < n; i++)
        v[i] = (cbm_vec3){sin(1.0 + (double)i), cos(2.0 * (double)i), sin(0.3 * (double)i)};
    cbm__mech_jvp(p, v, jv);
    CHECK_EQ_INT(cbm__mech_tree_solve(p, jv, back, 0.0, NULL), 0);
    double md = 0, mv = 0;
    for (size_t i = 0; i < n; i++) {
        md = fmax(md,
                  fabs(back[i].x - v[i].x) + fabs(back[i].y - v[i].y) + fabs(back[i].z - v[i].z));
        mv = fmax(mv, fabs(v[i].x) + fabs(v[i].y) + fabs(v[i].z));
    }
    printf("tree solve of J v: max error %.3g (|v| %.3g)\n", md, mv);
    CHECK(md < 1e-9 * mv);
    /* factor + apply (the preconditioner of FGMRES) gives the same */
    cbm__mech_tree_factor(p, 0.0, NULL);
    cbm__mech_tree_apply(p, jv, back);
    md = 0;
    for (size_t i = 0; i < n; i++)
        md = fmax(md,
                  fabs(back[i].x - v[i].x) + fabs(back[i].y - v[i].y) + fabs(back[i].z - v[i].z));
    CHECK(md < 1e-9 * mv);
    free(v);
    free(jv);
    free(back);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

TEST(mech_solvers_same_equilibrium)
{
    cbm_context *ctx = test_ctx();
    size_t n = 200;
    cbm_plant *a = random_tree(ctx, n, 3e8);
    cbm_plant *b = random_tree(ctx, n, 3e8); /* different random draw: rebuild a's copy below */
    cbm_plant_destroy(b);
    cbm_context_seed(ctx, 1);
    a = (cbm_plant_destroy(a), random_tree(ctx, n, 3e8));
    cbm_context_seed(ctx, 1);
    b = random_tree(ctx, n, 3e8);
    cbm_solve_def sd = cbm_solve_def_default();
    sd.tolerance = 1e-10;
    cbm_solve_stats sa, sb;
    CHECK_OK(cbm_plant_solve(a, &sd, &sa));
    sd.solver = CBM_MECH_RELAX;
    sd.alpha = 0.7;
    CHECK_OK(cbm_plant_solve(b, &sd, &sb));
    /* the stiffness-preconditioned GMRES reaches it too */
    cbm_context_seed(ctx, 1);
    cbm_plant *c0 = random_tree(ctx, n, 3e8);
    cbm_solve_def sk = cbm_solve_def_default();
    sk.tolerance = 1e-10;
    sk.preconditioner = CBM_MECH_PRECOND_STIFFNESS;
    cbm_solve_stats sc;
    CHECK_OK(cbm_plant_solve(c0, &sk, &sc));
    CHECK(sc.krylov_iterations > 0);
    cbm_vec3 ta = rod_tip(a), tc0 = rod_tip(c0);
    CHECK_NEAR(ta.x, tc0.x, 1e-9);
    CHECK_NEAR(ta.y, tc0.y, 1e-9);
    CHECK_NEAR(ta.z, tc0.z, 1e-9);
    cbm_plant_destroy(c0);
    printf("branched tree of %zu: fast %zu passes (%zu Newton, %zu Krylov), relax %zu passes; "
           "residuals %.3g %.3g\n",
           n, sa.passes, sa.newton_steps, sa.krylov_iterations, sb.passes, sa.residual,
           sb.residual);
    CHECK(sa.residual < 1e-10 && sb.residual < 1e-10);
    double dmax = 0, size = 0;
    for (size_t i = 0; i < n; i++) {
        cbm_segment_state x, y;
        CHECK_OK(cbm_plant_segment(a, i, &x));
        CHECK_OK(cbm_plant_segment(b, i, &y));
        double d =
            hypot(hypot(x.distal.x - y.distal.x, x.distal.y - y.distal.y), x.distal.z - y.distal.z);
        if (d > dmax)
            dmax = d;
        double s = hypot(hypot(x.distal.x, x.distal.y), x.distal.z);
        if (s > size)
            size = s;
    }
    printf("max node distance between the two equilibria %.3g (tree size %.3g)\n", dmax, size);
    CHECK(dmax < 1e-8 * size);
    cbm_plant_destroy(a);
    cbm_plant_destroy(b);

    /* a large deflection (alpha = 15 heavy cantilever) needs the globalisation */
    double L = 1, r = 0.01, rho = 1000, w = rho * PI * r * r * 9.81, EI = w / 15.0;
    double E = EI / (PI * r * r * r * r / 4);
    cbm_plant *c = make_rod(ctx, 100, L, radius_uniform, E, rho, 0, CBM_MECH_STAGGERED);
    cbm_plant *d = make_rod(ctx, 100, L, radius_uniform, E, rho, 0, CBM_MECH_STAGGERED);
    sd = cbm_solve_def_default();
    sd.tolerance = 1e-11;
    CHECK_OK(cbm_plant_solve(c, &sd, &sa));
    sd.solver = CBM_MECH_RELAX;
    sd.alpha = 0.5;
    CHECK_OK(cbm_plant_solve(d, &sd, &sb));
    cbm_vec3 tc = rod_tip(c), td = rod_tip(d);
    printf("alpha 15: fast (%.12f, %.12f) %zu passes, relax (%.12f, %.12f) %zu passes\n", tc.x,
           tc.y, sa.passes, td.x, td.y, sb.passes);
    CHECK_NEAR(tc.x, td.x, 1e-9);
    CHECK_NEAR(tc.y, td.y, 1e-9);
    cbm_plant_destroy(c);
    cbm_plant_destroy(d);
    test_ctx_end(ctx);
}

/* An inclined heavy rod (60 deg, w L^3 / EI = 50, tip load) has several equilibria; the fast
 * solver follows the loading path and reaches the one the relaxation reaches from rest. */
TEST(mech_fast_follows_loading_path)
{
    cbm_context *ctx = test_ctx();
    double L = 1, r = 0.01, rho = 1000, w = rho * PI * r * r * 9.81, EI = w / 50.0;
    double E = EI / (PI * r * r * r * r / 4);
    for (int load = 0; load < 2; load++) {
        cbm_plant *a = make_rod(ctx, 200, L, radius_uniform, E, rho, PI / 3, CBM_MECH_STAGGERED);
        cbm_plant *b = make_rod(ctx, 200, L, radius_uniform, E, rho, PI / 3, CBM_MECH_STAGGERED);
        if (load) {
            CHECK_OK(cbm_plant_set_load(a, 199, 0, (cbm_vec3){0, -0.5, 0}, (cbm_vec3){0, 0, 0}));
            CHECK_OK(cbm_plant_set_load(b, 199, 0, (cbm_vec3){0, -0.5, 0}, (cbm_vec3){0, 0, 0}));
        }
        cbm_solve_def sd = cbm_solve_def_default();
        sd.tolerance = 1e-10;
        cbm_solve_stats sa, sb;
        CHECK_OK(cbm_plant_solve(a, &sd, &sa));
        sd.solver = CBM_MECH_RELAX;
        sd.alpha = 0.1;
        CHECK_OK(cbm_plant_solve(b, &sd, &sb));
        cbm_vec3 ta = rod_tip(a), tb = rod_tip(b);
        printf("inclined heavy rod, tip load %d: fast (%.9f, %.9f) %zu passes, relax (%.9f, "
               "%.9f) %zu passes\n",
               load, ta.x, ta.y, sa.passes, tb.x, tb.y, sb.passes);
        CHECK(ta.x > 0.2);
        CHECK_NEAR(ta.x, tb.x, 1e-7);
        CHECK_NEAR(ta.y, tb.y, 1e-7);
        cbm_plant_destroy(a);
        cbm_plant_destroy(b);
    }
    test_ctx_end(ctx);
}

/* Near Greenhill's self-buckling load (w L^3 / EI = 7.5 < 7.837) the relaxation's contraction
 * factor tends to 1; the fast solver needs at least 10x fewer passes than the relaxation at its
 * best factor (pass counts are deterministic). */
TEST(mech_fast_near_buckling)
{
    cbm_context *ctx = test_ctx();
    double L = 1, r = 0.01, rho = 1000, w = rho * PI * r * r * 9.81, EI = w / 7.5;
    double E = EI / (PI * r * r * r * r / 4);
    size_t best = (size_t)-1, fast = 0;
    cbm_vec3 tf = {0, 0, 0}, tr = {0, 0, 0};
    for (int k = 0; k < 8; k++) {
        cbm_plant *p = make_rod(ctx, 100, L, radius_uniform, E, rho, PI / 2, CBM_MECH_STAGGERED);
        for (size_t i = 0; i < 100; i++) {
            cbm_ring g;
            CHECK_OK(cbm_plant_get_ring(p, i, 0, &g));
            g.rest_rate = (cbm_vec3){0, -0.01, 0};
            CHECK_OK(cbm_plant_set_ring(p, i, 0, &g));
            CHECK_OK(cbm_plant_set_omega(p, i, g.rest_rate));
        }
        cbm_solve_def sd = cbm_solve_def_default();
        cbm_solve_stats st;
        if (k == 0) {
            CHECK_OK(cbm_plant_solve(p, &sd, &st));
            fast = st.passes;
            tf = rod_tip(p);
        } else {
            sd.solver = CBM_MECH_RELAX;
            sd.alpha = 0.3 + 0.1 * k;
            CHECK_OK(cbm_plant_solve(p, &sd, &st));
            if (st.passes < best) {
                best = st.passes;
                tr = rod_tip(p);
            }
        }
        cbm_plant_destroy(p);
    }
    printf("near-critical column: fast %zu passes, best relaxation %zu passes; tips %.9f %.9f\n",
           fast, best, tf.x, tr.x);
    CHECK(fast * 10 <= best);
    CHECK_NEAR(tf.x, tr.x, 1e-6 * fabs(tf.x));
    test_ctx_end(ctx);
}

/* Floppy random trees with several equilibria: Newton alone can converge to an unstable one (a
 * branch balanced upright). The fast solver checks the pivots of its tree factorisation, shifts
 * unstable configurations (J + mu S) and must end on the stable equilibrium the relaxation
 * reaches from rest. These three trees did end on unstable equilibria before that check. */
static cbm_plant *floppy_tree(cbm_context *ctx, int trial)
{
    double E = pow(10, 5.5 + 4.5 * ((trial * 37) % 60) / 60.0);
    size_t n = 50 + (size_t)((trial * 53) % 400);
    cbm_context_seed(ctx, 100 + (uint64_t)trial);
    cbm_plant *p = clamped_plant(ctx, (trial % 5) * 0.4);
    for (size_t i = 0; i < n; i++) {
        cbm_segment_def d = cbm_segment_def_default();
        if (i > 0) {
            double u = cbm_context_uniform(ctx);
            d.parent = u < 0.75 ? (int64_t)i - 1 : (int64_t)(cbm_context_uniform(ctx) * (double)i);
            if (d.parent != (int64_t)i - 1) {
                d.divergence = 2.4 * (double)i;
                d.deviation = 0.3 + 0.8 * cbm_context_uniform(ctx);
            }
        }
        d.length = 0.02;
        d.core.youngs_modulus = E;
        d.core.shear_modulus = E / 16;
        d.core.a = 0.004 * (1 + cbm_context_uniform(ctx));
        d.core.b = d.core.a * (0.6 + 0.4 * cbm_context_uniform(ctx));
        if (cbm_context_uniform(ctx) < 0.2)
            d.point_mass = 0.01 * cbm_context_uniform(ctx);
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    return p;
}

TEST(mech_fast_reaches_stable_equilibrium)
{
    cbm_context *ctx = test_ctx();
    const int trials[] = {17, 19, 40};
    for (int t = 0; t < 3; t++) {
        cbm_plant *a = floppy_tree(ctx, trials[t]);
        cbm_plant *b = floppy_tree(ctx, trials[t]);
        cbm_solve_def sd = cbm_solve_def_default();
        sd.tolerance = 1e-9;
        cbm_solve_stats sa, sb;
        CHECK_OK(cbm_plant_solve(a, &sd, &sa));
        CHECK_EQ_INT(sa.unstable_joints, 0);
        sd.solver = CBM_MECH_RELAX;
        sd.alpha = 0.1;
        CHECK_OK(cbm_plant_solve(b, &sd, &sb));
        double dmax = 0;
        for (size_t i = 0; i < cbm_plant_segment_count(a); i++) {
            cbm_segment_state x, y;
            CHECK_OK(cbm_plant_segment(a, i, &x));
            CHECK_OK(cbm_plant_segment(b, i, &y));
            dmax = fmax(dmax, fabs(x.distal.x - y.distal.x) + fabs(x.distal.y - y.distal.y) +
                                  fabs(x.distal.z - y.distal.z));
        }
        printf("floppy tree %d: fast %zu passes, relax %zu passes, max node distance %.3g m\n",
               trials[t], sa.passes, sb.passes, dmax);
        CHECK(dmax < 1e-6);
        cbm_plant_destroy(a);
        cbm_plant_destroy(b);
    }
    test_ctx_end(ctx);
}

TEST(mech_rings_and_sections)
{
    cbm_context *ctx = test_ctx();
    double il, iu, j;
    cbm_mech_ellipse_moments(0.02, 0.01, &il, &iu, &j);
    CHECK_REL(il, PI * 8e-6 * 0.01 / 4, 1e-15); /* pi a^3 b / 4: bending about L */
    CHECK_REL(iu, PI * 0.02 * 1e-6 / 4, 1e-15);
    CHECK_REL(j, PI * 8e-6 * 1e-6 / (4e-4 + 1e-4), 1e-15);
    cbm_mech_ellipse_moments(0.01, 0.01, &il, &iu, &j);
    CHECK_REL(j, 2 * il, 1e-15); /* circle: J = 2I */
    cbm_plant *p = NULL;
    CHECK_OK(cbm_plant_create(ctx, NULL, &p));
    cbm_segment_def d = cbm_segment_def_default();
    d.core.a = d.core.b = 0.01;
    d.core.youngs_modulus = 1e9;
    d.core.rest_rate = (cbm_vec3){0, 2.0, 0};
    CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    CHECK_OK(cbm_plant_add_segment(p, &d, NULL)); /* a second root */
    cbm_ring r = d.core;
    r.a = 0.02;
    r.b = 0.015;
    r.youngs_modulus = 2e9;
    r.rest_rate = (cbm_vec3){0, -1.0, 0};
    CHECK_OK(cbm_plant_add_ring(p, 0, &r));
    cbm_segment_state s;
    CHECK_OK(cbm_plant_segment(p, 0, &s));
    double il0, il1;
    cbm_mech_ellipse_moments(0.01, 0.01, &il0, NULL, NULL);
    cbm_mech_ellipse_moments(0.02, 0.015, &il1, NULL, NULL);
    double c0 = 1e9 * il0, c1 = 2e9 * (il1 - il0);
    CHECK_REL(s.rigidity.y, c0 + c1, 1e-14);
    CHECK_REL(s.rest_rate.y, (c0 * 2.0 - c1) / (c0 + c1), 1e-14); /* Jirasek eq. 24 */
    CHECK_REL(s.mass_per_length, 600 * PI * 0.02 * 0.015, 1e-14);
    CHECK_EQ_INT(s.ring_count, 2);
    CHECK_NEAR(s.a, 0.02, 0);
    /* nesting is enforced */
    r.a = 0.015;
    CHECK_STATUS(cbm_plant_add_ring(p, 0, &r), CBM_E_INVALID);
    r.a = 0.001;
    r.b = 0.002; /* a < b */
    CHECK_STATUS(cbm_plant_add_ring(p, 1, &r), CBM_E_INVALID);
    /* many rings on alternating segments exercise the pool relocation and compaction */
    for (int k = 0; k < 200; k++) {
        cbm_ring q = d.core;
        q.a = q.b = 0.02 + 0.0001 * k;
        CHECK_OK(cbm_plant_add_ring(p, (size_t)(k % 2), &q));
    }
    CHECK_EQ_INT(cbm_plant_ring_count(p, 0), 102);
    CHECK_EQ_INT(cbm_plant_ring_count(p, 1), 101);
    cbm_ring got;
    CHECK_OK(cbm_plant_get_ring(p, 1, 100, &got));
    CHECK_NEAR(got.a, 0.02 + 0.0001 * 199, 1e-15);
    CHECK_OK(cbm_plant_get_ring(p, 0, 1, &got));
    CHECK_NEAR(got.b, 0.015, 0);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Shape memory (Jirasek §5 oracle 7): a ring whose rest rate is the current Omega, added with
 * no new load, leaves the equilibrium unchanged (its weight is set to zero here). */
TEST(mech_ring_under_unchanged_load_keeps_shape)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = make_rod(ctx, 40, 1.0, radius_uniform, 2e7, 800, 0.3, CBM_MECH_STAGGERED);
    cbm_solve_def sd = cbm_solve_def_default();
    sd.tolerance = 1e-12;
    CHECK_OK(cbm_plant_solve(p, &sd, NULL));
    cbm_vec3 t0 = rod_tip(p);
    for (size_t i = 0; i < 40; i++) {
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(p, i, &s));
        cbm_ring r;
        CHECK_OK(cbm_plant_get_ring(p, i, 0, &r));
        r.a = r.b = 0.015;
        r.density = 0;
        /* the segment's own curvature: rest + M/C at the segment (joint of the segment) */
        r.rest_rate = s.rate;
        CHECK_OK(cbm_plant_add_ring(p, i, &r));
    }
    /* the ring memorises the segment's mean rate (both halves); the halves' moments differ by
     * O(h), the errors cancel across each joint to O(h^2) */
    cbm_solve_stats st;
    CHECK_OK(cbm_plant_solve(p, &sd, &st));
    cbm_vec3 t1 = rod_tip(p);
    printf("tip before (%.9f %.9f) after (%.9f %.9f)\n", t0.x, t0.y, t1.x, t1.y);
    CHECK_NEAR(t1.y, t0.y, 1e-3 * fabs(t0.y));
    CHECK_NEAR(t1.x, t0.x, 1e-3 * fabs(t0.x));
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

TEST(mech_remove_subtree)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = random_tree(ctx, 50, 1e9);
    double m0 = cbm_plant_total_mass(p);
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    cbm_segment_state s;
    CHECK_OK(cbm_plant_segment(p, 10, &s));
    size_t removed = 0;
    CHECK_OK(cbm_plant_remove_subtree(p, 10, &removed));
    CHECK_EQ_INT(cbm_plant_segment_count(p), 50 - removed);
    CHECK_REL(cbm_plant_total_mass(p), m0 - s.carried_mass, 1e-12);
    const int64_t *par = cbm_plant_parents(p);
    for (size_t i = 0; i < cbm_plant_segment_count(p); i++)
        CHECK(par[i] < (int64_t)i);
    CHECK_OK(cbm_plant_solve(p, NULL, NULL));
    CHECK_STATUS(cbm_plant_remove_subtree(p, 1000, NULL), CBM_E_INVALID);
    CHECK_OK(cbm_plant_remove_subtree(p, 0, &removed));
    CHECK_EQ_INT(cbm_plant_segment_count(p), 0);
    CHECK_STATUS(cbm_plant_solve(p, NULL, NULL), CBM_E_INVALID);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

TEST(mech_errors)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = make_rod(ctx, 30, 1.0, radius_uniform, 1e6, 1000, 0, CBM_MECH_STAGGERED);
    /* non-convergence: results readable, residual reported */
    cbm_solve_def sd = cbm_solve_def_default();
    sd.solver = CBM_MECH_RELAX;
    sd.alpha = 0.05;
    sd.max_passes = 10;
    cbm_solve_stats st;
    CHECK_STATUS(cbm_plant_solve(p, &sd, &st), CBM_E_NOT_CONVERGED);
    CHECK(st.passes <= 10 && st.residual > 1e-8 && isfinite(st.residual));
    CHECK(strstr(cbm_context_last_error(ctx), "residual") != NULL);
    sd.solver = CBM_MECH_NEWTON;
    sd.max_passes = 4;
    CHECK_STATUS(cbm_plant_solve(p, &sd, &st), CBM_E_NOT_CONVERGED);
    CHECK(st.residual > 0 && isfinite(st.residual));
    CHECK(strstr(cbm_context_last_error(ctx), "pass budget ran out") != NULL);
    /* context limit on passes */
    cbm_limits lim = *cbm_context_limits(ctx);
    cbm_limits small = lim;
    small.max_passes = 3;
    cbm_context_set_limits(ctx, &small);
    sd.max_passes = 0;
    CHECK_STATUS(cbm_plant_solve(p, &sd, &st), CBM_E_NOT_CONVERGED);
    CHECK(st.passes <= 4);
    small = lim;
    small.max_segments = 30;
    cbm_context_set_limits(ctx, &small);
    cbm_segment_def d = cbm_segment_def_default();
    CHECK_STATUS(cbm_plant_add_segment(p, &d, NULL), CBM_E_LIMIT);
    cbm_context_set_limits(ctx, &lim);
    /* NaN: an overflowing load names the segment */
    CHECK_OK(cbm_plant_set_load(p, 29, 1e308, (cbm_vec3){0, 0, 0}, (cbm_vec3){0, 0, 0}));
    sd = cbm_solve_def_default();
    CHECK_STATUS(cbm_plant_solve(p, &sd, &st), CBM_E_NONFINITE);
    CHECK(strstr(cbm_context_last_error(ctx), "segment") != NULL);
    /* bad input */
    d.length = -1;
    CHECK_STATUS(cbm_plant_add_segment(p, &d, NULL), CBM_E_INVALID);
    d = cbm_segment_def_default();
    d.parent = 99;
    CHECK_STATUS(cbm_plant_add_segment(p, &d, NULL), CBM_E_INVALID);
    d.parent = -1;
    d.core.youngs_modulus = NAN;
    CHECK_STATUS(cbm_plant_add_segment(p, &d, NULL), CBM_E_INVALID);
    CHECK_STATUS(cbm_plant_set_omega(p, 0, (cbm_vec3){INFINITY, 0, 0}), CBM_E_INVALID);
    sd.tolerance = 0;
    CHECK_STATUS(cbm_plant_solve(p, &sd, &st), CBM_E_INVALID);
    sd = cbm_solve_def_default();
    sd.solver = CBM_MECH_RELAX;
    sd.alpha = 1.5;
    CHECK_STATUS(cbm_plant_solve(p, &sd, &st), CBM_E_INVALID);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* No allocation inside the solver loop (a counting allocator). */
TEST(mech_no_allocation_in_solver_loop)
{
    size_t calls = 0;
    cbm_context *ctx = test_counting_ctx(&calls);
    CHECK(ctx != NULL);
    cbm_plant *p = make_rod(ctx, 100, 1.0, radius_uniform, 1e8, 1000, 0, CBM_MECH_STAGGERED);
    for (int solver = 0; solver < 2; solver++) {
        cbm_solve_def sd = cbm_solve_def_default();
        sd.solver = (cbm_mech_solver)solver;
        sd.warm_start = false;
        sd.max_passes = 6;
        size_t c0 = calls;
        (void)cbm_plant_solve(p, &sd, NULL); /* may allocate the workspace once */
        size_t first = calls - c0;
        CHECK(first <= 40);
        c0 = calls;
        sd.max_passes = 5000;
        CHECK_OK(cbm_plant_solve(p, &sd, NULL)); /* hundreds of passes, no allocation */
        CHECK_EQ_INT(calls - c0, 0);
    }
    cbm_plant_destroy(p);
    CHECK_EQ_INT(cbm_context_bytes(ctx), 0);
    cbm_context_destroy(ctx);
}

static cbm_status oom_case(cbm_context *ctx, void *ud)
{
    (void)ud;
    cbm_plant *p = NULL;
    cbm_status s = cbm_plant_create(ctx, NULL, &p);
    if (s)
        return s;
    cbm_segment_def d = cbm_segment_def_default();
    for (int i = 0; i < 40 && !s; i++) {
        d.parent = i - 1;
        s = cbm_plant_add_segment(p, &d, NULL);
    }
    cbm_ring r = d.core;
    r.a = r.b = 0.02;
    for (int i = 0; i < 40 && !s; i++)
        s = cbm_plant_add_ring(p, (size_t)(i * 7 % 40), &r);
    if (!s)
        s = cbm_plant_solve(p, NULL, NULL);
    size_t rm;
    if (!s)
        s = cbm_plant_remove_subtree(p, 20, &rm);
    if (!s) {
        cbm_scene *sc = NULL;
        s = cbm_scene_create(ctx, &sc);
        if (!s)
            s = cbm_plant_to_scene(p, sc, 6);
        cbm_scene_destroy(sc);
    }
    cbm_plant_destroy(p);
    return s;
}

TEST(mech_out_of_memory)
{
    int runs = test_oom_loop(oom_case, NULL);
    CHECK(runs > 10);
}

TEST(mech_scene_export)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = random_tree(ctx, 30, 1e9);
    CHECK_OK(cbm_plant_solve(p, NULL, NULL));
    cbm_scene *sc = NULL;
    CHECK_OK(cbm_scene_create(ctx, &sc));
    CHECK_OK(cbm_plant_to_scene(p, sc, 8));
    CHECK_EQ_INT(cbm_scene_part_count(sc), 30);
    const cbm_part *parts = cbm_scene_parts(sc);
    CHECK_EQ_INT(parts[0].segment, 0);
    CHECK_EQ_INT(parts[0].order, 0);
    CHECK(parts[5].stress > 0);
    CHECK(cbm_scene_triangle_count(sc) > 30 * 16);
    CHECK_STATUS(cbm_plant_to_scene(p, sc, 2), CBM_E_INVALID);
    cbm_scene_destroy(sc);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* A warm start under new point masses (fruit appearing on a grown plant): the fast solver
 * continues from the current equilibrium with the point masses going from the balanced ones
 * to the new ones, instead of re-bending the whole plant from rest, and ends on the stable
 * equilibrium the relaxation reaches from the same start. */
TEST(mech_fast_warm_start_new_masses)
{
    cbm_context *ctx = test_ctx();
    const int trials[] = {6, 19, 38};
    for (int t = 0; t < 3; t++) {
        cbm_plant *pl[2];
        cbm_solve_stats st[2];
        for (int k = 0; k < 2; k++) {
            cbm_plant *a = floppy_tree(ctx, trials[t]);
            size_t n = cbm_plant_segment_count(a);
            double *pm = calloc(n, sizeof *pm);
            for (size_t i = 0; i < n; i++) {
                cbm_segment_state x;
                CHECK_OK(cbm_plant_segment(a, i, &x));
                pm[i] = x.point_mass;
                CHECK_OK(cbm_plant_set_load(a, i, 0.0, (cbm_vec3){0, 0, 0}, (cbm_vec3){0, 0, 0}));
            }
            cbm_solve_def sd = cbm_solve_def_default();
            sd.tolerance = 1e-9;
            CHECK_OK(cbm_plant_solve(a, &sd, NULL));
            for (size_t i = 0; i < n; i++)
                CHECK_OK(cbm_plant_set_load(a, i, pm[i], (cbm_vec3){0, 0, 0}, (cbm_vec3){0, 0, 0}));
            free(pm);
            if (k == 1) {
                sd.solver = CBM_MECH_RELAX;
                sd.alpha = 0.1;
            }
            CHECK_OK(cbm_plant_solve(a, &sd, &st[k]));
            pl[k] = a;
        }
        double dmax = 0;
        for (size_t i = 0; i < cbm_plant_segment_count(pl[0]); i++) {
            cbm_segment_state x, y;
            CHECK_OK(cbm_plant_segment(pl[0], i, &x));
            CHECK_OK(cbm_plant_segment(pl[1], i, &y));
            dmax = fmax(dmax, fabs(x.distal.x - y.distal.x) + fabs(x.distal.y - y.distal.y) +
                                  fabs(x.distal.z - y.distal.z));
        }
        printf("floppy tree %d, masses added: fast %zu passes (%zu levels), relax %zu passes, "
               "max node distance %.3g m\n",
               trials[t], st[0].passes, st[0].continuation_steps, st[1].passes, dmax);
        CHECK_EQ_INT(st[0].unstable_joints, 0);
        CHECK(st[0].passes <= 40); /* 45-55 passes through the continuation from rest */
        CHECK(dmax < 1e-6);
        cbm_plant_destroy(pl[0]);
        cbm_plant_destroy(pl[1]);
    }
    test_ctx_end(ctx);
}

/* A stem clamped 20 degrees off the vertical, pointing up, under a tip mass that starts at m0 and
 * grows by the factor `growth` per step (Jirasek Fig. 5, with a soft green stem): the stem folds
 * over and snaps through to hanging. Each step is a warm start from the last equilibrium. Every
 * solve must converge in a bounded number of passes, and the last one must agree with the
 * relaxation from rest under the final mass (which descends to a stable state). The pivot test of
 * the tree factorisation fires at these hanging equilibria (it reads the unsymmetric Newton
 * matrix); the solver must find that a push along the soft mode comes back and report them stable.
 */
static void snap_through_path(double E, double r, double len, double alpha, double m0,
                              double growth, size_t max_step_passes, cbm_mech_warm_path path,
                              double *tip_y)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *pl[2];
    size_t total = 0, worst = 0;
    for (int k = 0; k < 2; k++) {
        cbm_plant_def pd = cbm_plant_def_default();
        pd.base_orientation = cbm_mech_clamp_orientation(PI / 2 - 20 * PI / 180);
        CHECK_OK(cbm_plant_create(ctx, &pd, &pl[k]));
        for (int i = 0; i < 8; i++) {
            cbm_segment_def d = cbm_segment_def_default();
            d.parent = i - 1;
            d.length = len;
            d.core.youngs_modulus = E;
            d.core.shear_modulus = E / 16;
            d.core.density = 1000;
            d.core.a = r;
            d.core.b = r;
            CHECK_OK(cbm_plant_add_segment(pl[k], &d, NULL));
        }
    }
    cbm_solve_def sd = cbm_solve_def_default();
    sd.warm_path = path;
    double m = m0;
    for (int step = 0; step < 12; step++, m *= growth) {
        CHECK_OK(cbm_plant_set_load(pl[0], 7, m, (cbm_vec3){0, 0, 0}, (cbm_vec3){0, 0, 0}));
        cbm_solve_stats st;
        sd.warm_start = true;
        CHECK_OK(cbm_plant_solve(pl[0], &sd, &st));
        CHECK_EQ_INT(st.unstable_joints, 0);
        total += st.passes;
        worst = st.passes > worst ? st.passes : worst;
    }
    m /= growth;
    CHECK_OK(cbm_plant_set_load(pl[1], 7, m, (cbm_vec3){0, 0, 0}, (cbm_vec3){0, 0, 0}));
    sd.warm_start = false;
    sd.solver = CBM_MECH_RELAX;
    sd.alpha = alpha;
    cbm_solve_stats sr;
    CHECK_OK(cbm_plant_solve(pl[1], &sd, &sr));
    double dmax = 0;
    for (size_t i = 0; i < 8; i++) {
        cbm_segment_state x, y;
        CHECK_OK(cbm_plant_segment(pl[0], i, &x));
        CHECK_OK(cbm_plant_segment(pl[1], i, &y));
        dmax = fmax(dmax, fabs(x.distal.x - y.distal.x) + fabs(x.distal.y - y.distal.y) +
                              fabs(x.distal.z - y.distal.z));
        if (i == 7)
            *tip_y = x.distal.y;
    }
    printf("snap-through E %.3g r %.3g: fast %zu passes in 12 steps (at most %zu), relax %zu "
           "passes, tip height %.4f m, max node distance %.3g m\n",
           E, r, total, worst, sr.passes, *tip_y, dmax);
    CHECK(worst <= max_step_passes);
    CHECK(dmax < 1e-6);
    cbm_plant_destroy(pl[0]);
    cbm_plant_destroy(pl[1]);
    test_ctx_end(ctx);
}

static void snap_through(double E, double r, double len, double alpha, size_t max_step_passes,
                         double *tip_y)
{
    snap_through_path(E, r, len, alpha, 0.0005, 1.35, max_step_passes, CBM_MECH_WARM_TRANSIENT,
                      tip_y);
}

/* Fruit appearing at once and growing by 60 % per step (the fruit tree's fruit appears at a third
 * of its goal mass): larger load steps than above. Both warm paths (the transient, default, and
 * the quasi-static mass path) must reach the stable hanging state the relaxation reaches from
 * rest, within a bounded number of passes per step. */
TEST(mech_fast_snap_through_sudden_fruit)
{
    double y[2];
    for (int path = 0; path < 2; path++) {
        snap_through_path(3e8, 0.001, 0.02, 0.02, 0.0003, 1.6, 70,
                          path ? CBM_MECH_WARM_MASS_PATH : CBM_MECH_WARM_TRANSIENT, &y[path]);
        CHECK(y[path] < 0.0);
    }
    CHECK_NEAR(y[0], y[1], 1e-9);
}

TEST(mech_fast_snap_through_twig)
{
    double y;
    snap_through(3e8, 0.001, 0.02, 0.02, 40, &y); /* 393 before */
    CHECK(y < 0.0);                               /* hanging below the clamp */
}

TEST(mech_fast_soft_hanging_chain)
{
    double y;
    snap_through(1e8, 0.0004, 0.004, 0.02, 150, &y); /* did not converge before */
    CHECK(y < 0.0);
}

/* The fruit-fold workload: the first four years of the fruit-tree model (Taylor-Hell 2005, A.1),
 * whose summer steps put fruit on 2 mm twigs of E = 0.6 MPa that pass a limit point and snap
 * through to hanging. Every equilibrium must converge, and all of them together within 4,000
 * passes. The quasi-static mass path (the fast solver's warm path before the transient one)
 * took 5,601 passes here (3,118 in year 3 alone); the transient path takes 2,178. */
TEST(mech_fast_fruit_fold_passes)
{
    cbm_context *ctx = test_ctx();
    cbm_tree_def d;
    CHECK_OK(cbm_tree_def_builtin(ctx, "fruit-tree-thesis", &d));
    d.years = 4;
    cbm_tree *t = NULL;
    CHECK_OK(cbm_tree_create(ctx, &d, &t));
    CHECK_OK(cbm_tree_run(t));
    size_t passes = 0, unconverged = 0, fruit = 0;
    for (int y = 1; y <= 4; y++) {
        const cbm_tree_summary *s = cbm_tree_summary_of(t, y);
        printf("year %d: %zu segments, %zu fruit, %zu passes, %zu unconverged\n", y, s->segments,
               s->fruit, s->passes, s->unconverged);
        passes += s->passes;
        unconverged += s->unconverged;
        fruit += s->fruit;
    }
    printf("fruit fold: %zu passes in four years\n", passes);
    CHECK(fruit > 0);
    CHECK_EQ_INT(unconverged, 0);
    CHECK(passes <= 4000);
    cbm_tree_destroy(t);
    test_ctx_end(ctx);
}
