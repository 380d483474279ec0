/* Ground contact by penalty inside the solvers (Jirasek et al. 2000 §2.8): the tangent with the
 * contact stiffness against finite differences; an inclined cantilever whose tip rests on the
 * ground against the closed form of a cantilever on a spring support (the propped cantilever,
 * reaction 3/8 w L, in the stiff limit); penetration bounded by force / k; both solvers at the
 * same equilibrium; a flexible axis lying on the ground; no ground by default; Ground() in the
 * L+C dialect; the O(n) tree factorisation with the contact stiffness (it inverts the exact
 * tangent; Newton converges quadratically with it); a cycad-like rosette, relaxation and fast
 * solver; the shipped models jirasek-ground.l (a parameter sweep: converges, smooth, no
 * sinking) and jirasek-cycad.l. */
#include "lsys_util.h"
#include "mech_testlib.h"
#include "mech/mech_internal.h"
#include "core/vecmath.h"

/* A rod of n segments, clamped at `elev` rad (negative: pointing down) at height y_base. */
static cbm_plant *rod_at(cbm_context *ctx, int n, double L, double r, double E, double elev,
                         double y_base)
{
    cbm_plant_def pd = cbm_plant_def_default();
    pd.base_orientation = cbm_mech_clamp_orientation(elev);
    pd.base_position = v3(0.0, y_base, 0.0);
    cbm_plant *p = NULL;
    CHECK_OK(cbm_plant_create(ctx, &pd, &p));
    if (!p)
        return NULL;
    cbm_segment_def d = cbm_segment_def_default();
    d.length = L / n;
    d.core.youngs_modulus = E;
    d.core.shear_modulus = E / 2.6;
    d.core.density = 600.0;
    d.core.a = d.core.b = r;
    for (int i = 0; i < n; i++) {
        d.parent = i - 1;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    return p;
}

static double min_node_height(const cbm_plant *p)
{
    double y = INFINITY;
    for (size_t i = 0; i < cbm_plant_segment_count(p); i++) {
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(p, i, &s));
        if (s.distal.y < y)
            y = s.distal.y;
    }
    return y;
}

TEST(contact_default_none_and_errors)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = rod_at(ctx, 4, 1.0, 0.01, 1e10, 0.0, 0.0);
    CHECK(!cbm_plant_ground(p, NULL, NULL, NULL));
    CHECK_STATUS(cbm_plant_set_ground(p, NAN, 1e3, 0.0), CBM_E_INVALID);
    CHECK_STATUS(cbm_plant_set_ground(p, 0.0, -1.0, 0.0), CBM_E_INVALID);
    CHECK_STATUS(cbm_plant_set_ground(p, 0.0, INFINITY, 0.0), CBM_E_INVALID);
    CHECK_OK(cbm_plant_set_ground(p, -0.5, 2e3, 0.0));
    double y0 = 0, k = 0;
    CHECK(cbm_plant_ground(p, &y0, &k, NULL));
    CHECK(y0 == -0.5 && k == 2e3);
    CHECK_OK(cbm_plant_set_ground(p, -0.5, 0.0, 0.0));
    CHECK(!cbm_plant_ground(p, NULL, NULL, NULL));
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* The tangent with contact is the exact derivative of the residual. */
TEST(contact_tangent_matches_finite_differences)
{
    cbm_context *ctx = test_ctx();
    const int n = 30;
    cbm_plant *p = rod_at(ctx, n, 2.0, 0.004, 1e9, 0.1, 0.05);
    /* bend it so that a stretch of nodes is well below the ground, some above */
    for (int i = 0; i < n; i++)
        CHECK_OK(cbm_plant_set_omega(p, (size_t)i, v3(0.01 * i, 0.02, -0.4 + 0.03 * i)));
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    /* the ground halfway between the lowest and the highest node */
    double lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < n; i++) {
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(p, (size_t)i, &s));
        lo = s.distal.y < lo ? s.distal.y : lo;
        hi = s.distal.y > hi ? s.distal.y : hi;
    }
    CHECK_OK(cbm_plant_set_ground(p, 0.5 * (lo + hi), 5e3, 0.0));
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    size_t below = 0;
    for (int i = 0; i < n; i++)
        below += cbm_plant_contact_force(p, (size_t)i) > 0.0;
    printf("nodes in contact: %zu of %d\n", below, n);
    CHECK(below >= 3 && below + 3 <= (size_t)n);
    CHECK_OK(cbm__mech_work_reserve(p, 1));
    cbm__mech_prepare(p);
    cbm_vec3 *v = calloc(n, sizeof *v), *jv = calloc(n, sizeof *jv), *rp = calloc(n, sizeof *rp),
             *rm = calloc(n, sizeof *rm), *om = calloc(n, sizeof *om);
    for (int i = 0; i < n; i++) {
        v[i] = v3(sin(3.0 * i), cos(5.0 * i), sin(7.0 * i + 1));
        om[i] = p->omega[i];
    }
    double mm;
    cbm__mech_forward(p);
    cbm__mech_backward(p, 0.0, NULL, &mm, NULL);
    cbm__mech_jvp(p, v, jv);
    double eps = 1e-7, maxd = 0, maxj = 0;
    for (int sgn = -1; sgn <= 1; sgn += 2) {
        for (int i = 0; i < n; i++)
            p->omega[i] = v3_add(om[i], v3_scale(v[i], sgn * eps));
        cbm__mech_forward(p);
        cbm__mech_backward(p, 0.0, sgn < 0 ? rm : rp, &mm, NULL);
    }
    for (int i = 0; i < n; i++) {
        cbm_vec3 fd = v3_scale(v3_sub(rp[i], rm[i]), 0.5 / eps);
        double dd = v3_norm(v3_sub(fd, jv[i]));
        if (dd > maxd)
            maxd = dd;
        if (v3_norm(jv[i]) > maxj)
            maxj = v3_norm(jv[i]);
    }
    printf("tangent with contact vs central differences: max diff %.3g, max |Jv| %.3g\n", maxd,
           maxj);
    CHECK(maxd < 1e-6 * maxj);
    free(v);
    free(jv);
    free(rp);
    free(rm);
    free(om);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* A small branched tree (a trunk leaning over, laterals every third node, drooping), bent so
 * that part of it lies below the plane halfway up. */
static cbm_plant *bent_tree(cbm_context *ctx, int n)
{
    cbm_plant *p = clamped_plant(ctx, 0.3);
    if (!p)
        return NULL;
    for (int i = 0; i < n; i++) {
        cbm_segment_def d = cbm_segment_def_default();
        d.length = 0.06 + 0.01 * sin(1.7 * i);
        d.core.youngs_modulus = 2e8;
        d.core.shear_modulus = 2e8 / 2.6;
        d.core.density = 700.0;
        d.core.a = 0.006 * (1.0 - 0.4 * i / n);
        d.core.b = 0.8 * d.core.a;
        if (i > 0) {
            d.parent = i % 3 == 0 ? i - 3 : i - 1;
            if (i % 3 == 0) {
                d.divergence = 2.4 * i;
                d.deviation = 0.7;
            }
        }
        d.omega = v3(0.3 * sin(0.9 * i), -0.6 + 0.2 * cos(1.3 * i), 0.4 * sin(2.1 * i));
        if (i % 4 == 1)
            d.point_mass = 0.01;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    double lo = INFINITY, hi = -INFINITY;
    for (int i = 0; i < n; i++) {
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(p, (size_t)i, &s));
        lo = s.distal.y < lo ? s.distal.y : lo;
        hi = s.distal.y > hi ? s.distal.y : hi;
    }
    CHECK_OK(cbm_plant_set_ground(p, lo + 0.25 * (hi - lo), 1e3, 0.001));
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    return p;
}

/* The O(n) tree factorisation carries the contact stiffness: it inverts the exact tangent
 * (which the previous test checks against finite differences) on a branched tree with many
 * nodes below the ground, directly and as the preconditioner's apply, also shifted. */
TEST(contact_tree_factorisation_inverts_tangent)
{
    cbm_context *ctx = test_ctx();
    const int n = 90;
    cbm_plant *p = bent_tree(ctx, n);
    size_t below = 0;
    for (int i = 0; i < n; i++)
        below += cbm_plant_contact_force(p, (size_t)i) > 0.0;
    printf("nodes in contact: %zu of %d\n", below, n);
    CHECK(below >= 10 && below + 10 <= (size_t)n);
    CHECK_OK(cbm__mech_work_reserve(p, 2));
    cbm__mech_prepare(p);
    double mm;
    cbm__mech_forward(p);
    cbm__mech_backward(p, 0.0, NULL, &mm, NULL);
    cbm_vec3 *v = calloc(n, sizeof *v), *jv = calloc(n, sizeof *jv),
             *back = calloc(n, sizeof *back), *res = calloc(n, sizeof *res);
    for (int i = 0; i < n; i++)
        v[i] = v3(sin(1.0 + i), cos(2.0 * i), sin(0.3 * i));
    cbm__mech_jvp(p, v, jv);
    double mv = 0;
    for (int i = 0; i < n; i++)
        mv = fmax(mv, fabs(v[i].x) + fabs(v[i].y) + fabs(v[i].z));
    for (int pass = 0; pass < 2; pass++) {
        if (pass == 0)
            CHECK_EQ_INT(cbm__mech_tree_solve(p, jv, back, 0.0, NULL), 0);
        else {
            cbm__mech_tree_factor(p, 0.0, NULL);
            cbm__mech_tree_apply(p, jv, back);
        }
        double md = 0, br = 0, bj = 0;
        for (int i = 0; i < n; i++)
            md = fmax(md, fabs(back[i].x - v[i].x) + fabs(back[i].y - v[i].y) +
                              fabs(back[i].z - v[i].z));
        /* backward error: J back against J v */
        cbm__mech_jvp(p, back, res);
        for (int i = 0; i < n; i++) {
            br = fmax(br, v3_norm(v3_sub(res[i], jv[i])));
            bj = fmax(bj, v3_norm(jv[i]));
        }
        printf(
            "tree %s of J v with contact: max error %.3g (|v| %.3g), backward %.3g (|Jv| %.3g)\n",
            pass ? "factor + apply" : "solve", md, mv, br, bj);
        CHECK(md < 1e-9 * mv);
    }
    /* the shifted factorisation is that of J + mu S: (J + mu S)^-1 (J v + mu S v) = v */
    const double mu = 0.3;
    for (int i = 0; i < n; i++) {
        cbm_vec3 c = p->work.cj[i];
        jv[i] = v3_add(jv[i], v3(mu * c.x * v[i].x, mu * c.y * v[i].y, mu * c.z * v[i].z));
    }
    CHECK_EQ_INT(cbm__mech_tree_solve(p, jv, back, mu, NULL), 0);
    double md = 0;
    for (int i = 0; i < n; i++)
        md = fmax(md,
                  fabs(back[i].x - v[i].x) + fabs(back[i].y - v[i].y) + fabs(back[i].z - v[i].z));
    printf("shifted (mu %.1f): max error %.3g\n", mu, md);
    CHECK(md < 1e-9 * mv);
    free(v);
    free(jv);
    free(back);
    free(res);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* A cantilever clamped at theta below the horizontal, its unloaded tip exactly on the ground.
 * Small deflection, inextensible: the tip reaction R (vertical) against the weight w per length
 * is that of a cantilever on a spring of stiffness k cos^2 theta across the rod,
 *     R = (3/8) w L / (1 + 3 EI / (k cos^2 theta L^3)),
 * which tends to the propped cantilever's 3/8 w L as k grows. */
TEST(contact_propped_cantilever)
{
    cbm_context *ctx = test_ctx();
    const double L = 1.0, r = 0.01, E = 1e10, th = 0.2;
    const double EI = E * PI * pow(r, 4) / 4.0;
    const double w = 600.0 * PI * r * r * 9.81;
    const double ks[3] = {1e3, 1e5, 1e7};
    double prev_err = INFINITY;
    for (int j = 0; j < 3; j++) {
        cbm_plant *p = rod_at(ctx, 40, L, r, E, -th, L * sin(th));
        CHECK_OK(cbm_plant_set_ground(p, 0.0, ks[j], 0.0));
        cbm_solve_stats st;
        CHECK_OK(cbm_plant_solve(p, NULL, &st));
        size_t n = cbm_plant_segment_count(p);
        double R = 0.0;
        for (size_t i = 0; i < n; i++)
            R += cbm_plant_contact_force(p, i);
        double Rt = cbm_plant_contact_force(p, n - 1);
        double spring = 0.375 * w * L / (1.0 + 3.0 * EI / (ks[j] * cos(th) * cos(th) * L * L * L));
        double err = fabs(R / (0.375 * w * L) - 1.0);
        double depth = -min_node_height(p);
        printf("k %.0e N/m: tip reaction %.6f N (spring closed form %.6f, propped 3/8 wL %.6f), "
               "rel. error to 3/8 wL %.2e, depth %.3e m (R/k %.3e), %zu Newton steps, %zu "
               "passes\n",
               ks[j], R, spring, 0.375 * w * L, err, depth, R / ks[j], st.newton_steps, st.passes);
        CHECK(Rt == R); /* only the tip touches */
        CHECK_REL(R, spring, 2e-3);
        CHECK(err < prev_err);
        prev_err = err;
        CHECK_REL(depth, R / ks[j], 1e-9);
        CHECK(st.newton_steps <= 12);
        cbm_plant_destroy(p);
    }
    CHECK(prev_err < 3e-3);
    test_ctx_end(ctx);
}

/* Relaxation and Newton reach the same equilibrium with contact. */
TEST(contact_solvers_agree)
{
    cbm_context *ctx = test_ctx();
    const double L = 1.0, th = 0.2;
    cbm_plant *a = rod_at(ctx, 20, L, 0.01, 1e10, -th, L * sin(th));
    cbm_plant *b = rod_at(ctx, 20, L, 0.01, 1e10, -th, L * sin(th));
    CHECK_OK(cbm_plant_set_ground(a, 0.0, 1e3, 0.0));
    CHECK_OK(cbm_plant_set_ground(b, 0.0, 1e3, 0.0));
    cbm_solve_def rd = cbm_solve_def_default();
    rd.solver = CBM_MECH_RELAX;
    rd.alpha = 0.1;
    rd.tolerance = 1e-10;
    rd.max_passes = 20000;
    cbm_solve_stats sa, sb;
    CHECK_OK(cbm_plant_solve(a, &rd, &sa));
    cbm_solve_def nd = cbm_solve_def_default();
    nd.tolerance = 1e-10;
    CHECK_OK(cbm_plant_solve(b, &nd, &sb));
    size_t n = cbm_plant_segment_count(a);
    double ra = cbm_plant_contact_force(a, n - 1), rb = cbm_plant_contact_force(b, n - 1);
    cbm_vec3 ta = rod_tip(a), tb = rod_tip(b);
    printf("relax: R %.9f N in %zu passes; fast: R %.9f N in %zu passes (%zu Newton steps)\n", ra,
           sa.passes, rb, sb.passes, sb.newton_steps);
    CHECK(ra > 0.0);
    CHECK_REL(ra, rb, 1e-6);
    CHECK(v3_norm(v3_sub(ta, tb)) < 1e-9);
    cbm_plant_destroy(a);
    cbm_plant_destroy(b);
    test_ctx_end(ctx);
}

/* A long flexible axis clamped horizontally 5 cm above the ground (w L^4 / 8 EI = 1.3 m): it
 * sags onto the ground and a quarter or more of it lies there; the solve converges from rest
 * (through the load continuation) and no node sinks deeper than the ground's force over k. */
TEST(contact_axis_lies_on_ground)
{
    cbm_context *ctx = test_ctx();
    const int n = 60;
    const double L = 2.0, r = 0.006, k = 1e4;
    cbm_plant *p = rod_at(ctx, n, L, r, 1e9, 0.0, 0.05);
    CHECK_OK(cbm_plant_set_ground(p, 0.0, k, 0.0));
    cbm_solve_stats st;
    cbm_status s = cbm_plant_solve(p, NULL, &st);
    CHECK_OK(s);
    size_t touching = 0;
    double rsum = 0.0;
    for (int i = 0; i < n; i++) {
        double f = cbm_plant_contact_force(p, (size_t)i);
        touching += f > 0.0;
        rsum += f;
    }
    double weight = 600.0 * PI * r * r * L * 9.81;
    double depth = -min_node_height(p);
    printf("axis on the ground: %zu of %d nodes touch, ground carries %.4f of %.4f N, depth %.3e "
           "m (segment weight / k %.3e), %zu Newton steps, %zu continuation steps, %zu passes, "
           "residual %.2e\n",
           touching, n, rsum, weight, depth, weight / n / k, st.newton_steps, st.continuation_steps,
           st.passes, st.residual);
    CHECK(touching >= (size_t)n / 4);
    CHECK(rsum > 0.3 * weight && rsum < weight);
    CHECK(depth > 0.0 && depth <= rsum / k);
    CHECK(st.residual < 1e-8);
    CHECK(st.newton_steps <= 400);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Newton with the contact stiffness in the factorisation converges quadratically: from the
 * equilibrium of the axis lying on the ground (17 nodes touching) with every joint pushed by
 * up to 2 %, full Newton steps of the tree solve, relative residual per step; then the
 * solver's own count from the same start. */
TEST(contact_newton_quadratic)
{
    cbm_context *ctx = test_ctx();
    const int n = 60;
    cbm_plant *p = rod_at(ctx, n, 2.0, 0.006, 1e9, 0.0, 0.05);
    CHECK_OK(cbm_plant_set_ground(p, 0.0, 1e4, 0.0));
    cbm_solve_def d = cbm_solve_def_default();
    d.tolerance = 1e-10;
    CHECK_OK(cbm_plant_solve(p, &d, NULL));
    cbm_vec3 *eq = calloc(n, sizeof *eq), *b = calloc(n, sizeof *b), *s = calloc(n, sizeof *s);
    for (int i = 0; i < n; i++) {
        eq[i] = p->omega[i];
        p->omega[i] = v3_add(eq[i], v3(0.0, 0.0, 0.02 * sin(1.3 * i) * (fabs(eq[i].z) + 0.1)));
    }
    size_t touch = 0;
    for (int i = 0; i < n; i++)
        touch += cbm_plant_contact_force(p, (size_t)i) > 0.0;
    CHECK_OK(cbm__mech_work_reserve(p, 1));
    cbm__mech_prepare(p);
    double rel[8], mm = 0;
    int steps = 0;
    for (; steps < 8; steps++) {
        cbm__mech_forward(p);
        double r = cbm__mech_backward(p, 0.0, b, &mm, NULL);
        rel[steps] = cbm__mech_relres(r, mm, NULL);
        printf("step %d: relative residual %.3e\n", steps, rel[steps]);
        if (rel[steps] < 1e-10)
            break;
        for (int i = 0; i < n; i++)
            b[i] = v3_scale(b[i], -1.0);
        CHECK_EQ_INT(cbm__mech_tree_solve(p, b, s, 0.0, NULL), 0);
        for (int i = 0; i < n; i++)
            p->omega[i] = v3_add(p->omega[i], s[i]);
    }
    printf("%zu nodes touching; converged in %d full Newton steps\n", touch, steps);
    CHECK(steps <= 4);
    CHECK(rel[0] > 1e-3);
    /* quadratic: each step squares the error (up to a constant) down to the round-off floor
     * (about 1e-11 here) */
    for (int k = 1; k <= steps && k < 8; k++)
        CHECK(rel[k] < 30.0 * rel[k - 1] * rel[k - 1] || rel[k] < 1e-10);
    double dmax = 0;
    for (int i = 0; i < n; i++)
        dmax = fmax(dmax, v3_norm(v3_sub(p->omega[i], eq[i])) * 2.0 / n);
    printf("back at the equilibrium: max joint rotation difference %.2e rad\n", dmax);
    CHECK(dmax < 1e-8);
    /* the solver from the same pushed start: the same few steps, no Krylov iterations */
    for (int i = 0; i < n; i++)
        p->omega[i] = v3_add(eq[i], v3(0.0, 0.0, 0.02 * sin(1.3 * i) * (fabs(eq[i].z) + 0.1)));
    cbm_solve_stats st;
    CHECK_OK(cbm_plant_solve(p, &d, &st));
    printf("solver: %zu Newton steps, %zu passes, %zu Krylov iterations\n", st.newton_steps,
           st.passes, st.krylov_iterations);
    CHECK(st.newton_steps <= 5);
    CHECK(st.krylov_iterations == 0);
    free(eq);
    free(b);
    free(s);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* The language route: Ground(y0, k, smoothing) in Start holds up a soft horizontal rod that
 * would otherwise hang far below y0. Returns the lowest distal node (m) or NAN on error. */
#include "cambium/lsys.h"

static double language_lowest(cbm_context *ctx, const char *ground)
{
    char text[1200];
    snprintf(text, sizeof text,
             "#include <lpfgall.h>\n"
             "derivation length: 1;\n"
             "module I(MechSegment);\n"
             "mechanics: I;\n"
             "MechSegment S()\n"
             "{\n"
             "    MechSegment s;\n"
             "    s.length = 0.05; s.a = 0.002; s.b = 0.002; s.E = 1e9; s.density = 900;\n"
             "    s.age = 0;\n"
             "    return s;\n"
             "}\n"
             "Start: { %s }\n"
             "EndEach: { Equilibrium(); }\n"
             "Axiom: Down(90) I(S()) I(S()) I(S()) I(S()) I(S()) I(S()) I(S()) I(S()) I(S())"
             " I(S()) I(S()) I(S()) I(S()) I(S()) I(S()) I(S()) I(S()) I(S()) I(S()) I(S());\n",
             ground);
    double low = NAN;
    cbm_lsys *ls = lsys_from_text(ctx, "ground.l", text);
    if (!ls)
        return NAN;
    CHECK_OK(cbm_lsys_step(ls));
    cbm_lsys_cursor c;
    cbm_lsys_cursor_begin(ls, false, &c);
    int count = 0;
    while (cbm_lsys_cursor_next(ls, false, &c))
        if (c.symbol == 'I' && c.nparams >= 26) {
            double y = c.params[14] + c.params[0] * c.params[17];
            low = count++ == 0 || y < low ? y : low;
        }
    CHECK_EQ_INT(count, 20);
    cbm_lsys_destroy(ls);
    return low;
}

TEST(contact_language_ground)
{
    cbm_context *ctx = test_ctx();
    double free_low = language_lowest(ctx, "");
    double on_ground = language_lowest(ctx, "Ground(-0.1, 1e3, 0);");
    double smooth = language_lowest(ctx, "Ground(-0.1, 1e4, 0.0005);");
    printf("lowest node: free %.4f m, on the ground at -0.1 m: %.6f m (smoothed %.6f m)\n",
           free_low, on_ground, smooth);
    CHECK(free_low < -0.3);
    CHECK(on_ground < -0.1 && on_ground > -0.1 - 2e-4);
    CHECK(smooth < -0.1 && smooth > -0.1 - 1e-3);
    test_ctx_end(ctx);
}

/* A cycad-like rosette through the API (the structure of models/jirasek-cycad.l): a stiff
 * trunk, eight fronds of 14 internodes (0.87 m, radius 3.3 mm tapering to half, E 2 GPa) with
 * leaflet masses (0.1 kg per m), leaving the crown at 55 to 90 degrees from the vertical, the
 * ground at the trunk's foot (k = 1e3 N/m, smoothing 2 mm). */
static cbm_plant *rosette(cbm_context *ctx)
{
    cbm_plant *p = clamped_plant(ctx, PI / 2);
    if (!p)
        return NULL;
    cbm_segment_def d = cbm_segment_def_default();
    d.length = 0.125;
    d.core.youngs_modulus = 5e9;
    d.core.shear_modulus = 5e9 / 2.6;
    d.core.density = 900.0;
    d.core.a = d.core.b = 0.06;
    for (int i = 0; i < 2; i++) {
        d.parent = i - 1;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    for (int f = 0; f < 8; f++)
        for (int j = 0; j < 14; j++) {
            cbm_segment_def e = cbm_segment_def_default();
            e.parent = j == 0 ? 1 : (int64_t)cbm_plant_segment_count(p) - 1;
            if (j == 0) {
                e.divergence = 2.39996 * f;
                e.deviation = (55.0 + 5.0 * f) * PI / 180.0;
            }
            e.length = 0.062;
            e.core.youngs_modulus = 2e9;
            e.core.shear_modulus = 2e9 / 2.6;
            e.core.density = 700.0;
            e.core.a = e.core.b = 0.0033 * (1.0 - 0.5 * j / 14.0);
            e.point_mass = 0.1 * 0.062;
            CHECK_OK(cbm_plant_add_segment(p, &e, NULL));
        }
    CHECK_OK(cbm_plant_set_ground(p, 0.0, 1e3, 0.002));
    return p;
}

/* Relaxation (from rest) and fast solver reach the same equilibrium with the same nodes on the
 * ground. The relaxation's gain must stay below about 2 / (1 + sum over a frond's joints of
 * k L_j^2 d_j / C_j) (L_j the lever of the contact about joint j): alpha = 0.002 here; with 0.05
 * it does not settle. */
TEST(contact_rosette_solvers_agree)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *a = rosette(ctx), *b = rosette(ctx);
    cbm_solve_def rd = cbm_solve_def_default();
    rd.solver = CBM_MECH_RELAX;
    rd.alpha = 0.002;
    rd.tolerance = 1e-9;
    rd.max_passes = 50000;
    cbm_solve_stats sa, sb;
    cbm_solve_def nd = cbm_solve_def_default();
    nd.tolerance = 1e-9;
    CHECK_OK(cbm_plant_solve(b, &nd, &sb));
    cbm_status st = cbm_plant_solve(a, &rd, &sa);
    size_t n = cbm_plant_segment_count(a), ta = 0, tb = 0;
    double dmax = 0.0, fa = 0.0, fb = 0.0, depth = 0.0, fmx = 0.0;
    for (size_t i = 0; i < n; i++) {
        cbm_segment_state x, y;
        fmx = fmax(fmx, cbm_plant_contact_force(b, i));
        CHECK_OK(cbm_plant_segment(a, i, &x));
        CHECK_OK(cbm_plant_segment(b, i, &y));
        dmax = fmax(dmax, v3_norm(v3_sub(x.distal, y.distal)));
        ta += cbm_plant_contact_force(a, i) > 0.0;
        tb += cbm_plant_contact_force(b, i) > 0.0;
        fa += cbm_plant_contact_force(a, i);
        fb += cbm_plant_contact_force(b, i);
        depth = fmax(depth, -y.distal.y);
    }
    printf("rosette: relax %s %zu passes (residual %.2e), fast %zu passes (%zu Newton steps, %zu "
           "continuation steps); %zu / %zu nodes on the ground carrying %.6f / %.6f N, depth "
           "%.2e m, max node distance %.2e m\n",
           cbm_status_name(st), sa.passes, sa.residual, sb.passes, sb.newton_steps,
           sb.continuation_steps, ta, tb, fa, fb, depth, dmax);
    CHECK_OK(st);
    CHECK(tb >= 4);
    CHECK(ta == tb);
    CHECK_REL(fa, fb, 1e-5);
    CHECK(dmax < 1e-6);
    /* the deepest node: the largest node force over k plus half the smoothing depth */
    CHECK(depth > 0.0 && depth <= fmx / 1e3 + 0.001 + 1e-12);
    cbm_plant_destroy(a);
    cbm_plant_destroy(b);
    test_ctx_end(ctx);
}

/* Every allocation of a solve with a ground (the contact blocks of the factorisation) may fail:
 * the error comes back and nothing leaks. */
static cbm_status oom_case(cbm_context *ctx, void *ud)
{
    (void)ud;
    cbm_plant_def pd = cbm_plant_def_default();
    pd.base_orientation = cbm_mech_clamp_orientation(0.0);
    pd.base_position = v3(0.0, 0.05, 0.0);
    cbm_plant *p = NULL;
    cbm_status s = cbm_plant_create(ctx, &pd, &p);
    if (s)
        return s;
    cbm_segment_def d = cbm_segment_def_default();
    d.length = 0.05;
    d.core.youngs_modulus = 1e9;
    d.core.a = d.core.b = 0.006;
    for (int i = 0; i < 40 && !s; i++) {
        d.parent = i - 1;
        s = cbm_plant_add_segment(p, &d, NULL);
    }
    if (!s)
        s = cbm_plant_set_ground(p, 0.0, 1e4, 0.0005);
    if (!s)
        s = cbm_plant_solve(p, NULL, NULL);
    if (!s && !(cbm_plant_contact_force(p, 39) > 0.0))
        s = CBM_E_INVALID; /* the case must reach the ground */
    for (int i = 0; i < 20 && !s; i++) {
        d.parent = 39 + i;
        s = cbm_plant_add_segment(p, &d, NULL); /* the workspace grows with the plant */
    }
    if (!s)
        s = cbm_plant_solve(p, NULL, NULL);
    cbm_plant_destroy(p);
    return s;
}

TEST(contact_out_of_memory)
{
    int runs = test_oom_loop(oom_case, NULL);
    printf("out-of-memory runs: %d\n", runs);
    CHECK(runs > 10);
}

/* ---- the shipped models ---- */

typedef struct model_result {
    size_t segments, touching;
    double depth;    /* deepest distal node below the ground over every step, m */
    double max_turn; /* largest angle between a segment and the one it continues, rad */
    double max_jump; /* largest change of that turn (vector) from one joint to the next, rad */
} model_result;

/* Runs models/<name> to its derivation length with the given -D overrides; ground at y0. */
static cbm_status run_model(cbm_context *ctx, const char *name, const char *define, double y0,
                            model_result *r)
{
    cbm_lsys *ls = NULL;
    memset(r, 0, sizeof *r);
    cbm_status st = lsys_load_shipped(ctx, name, define, &ls);
    if (st != CBM_OK)
        return st;
    st = cbm_lsys_reset(ls);
    for (int k = 0; st == CBM_OK && k < cbm_lsys_derivation_length(ls); k++) {
        st = cbm_lsys_step(ls);
        cbm_lsys_cursor c;
        cbm_lsys_cursor_begin(ls, false, &c);
        cbm_vec3 prev_h = v3(0, 0, 0), prev_end = v3(NAN, NAN, NAN), prev_t = v3(NAN, 0, 0);
        size_t n = 0, touching = 0;
        while (st == CBM_OK && cbm_lsys_cursor_next(ls, false, &c)) {
            if (c.symbol != 'I' || c.nparams < 26)
                continue;
            const double *g = c.params;
            cbm_vec3 pos = v3(g[13], g[14], g[15]), h = v3(g[16], g[17], g[18]);
            cbm_vec3 end = v3_add(pos, v3_scale(h, g[0]));
            if (v3_norm(v3_sub(pos, prev_end)) < 1e-9) {
                double t = acos(fmin(1.0, fmax(-1.0, v3_dot(h, prev_h))));
                r->max_turn = fmax(r->max_turn, t);
                cbm_vec3 tv = v3_cross(prev_h, h);
                if (!isnan(prev_t.x))
                    r->max_jump = fmax(r->max_jump, v3_norm(v3_sub(tv, prev_t)));
                prev_t = tv;
            } else
                prev_t = v3(NAN, 0, 0);
            r->depth = fmax(r->depth, y0 - end.y);
            touching += end.y < y0;
            prev_h = h;
            prev_end = end;
            n++;
        }
        r->segments = n;
        r->touching = touching;
    }
    cbm_lsys_destroy(ls);
    return st;
}

/* Fig. 7 (models/jirasek-ground.l): no kinks and no sinking, and nearby parameters converge
 * too: ground stiffness, smoothing, internode length, lean, leaf mass, tropism, ground depth,
 * section, length of the run. */
TEST(contact_model_ground_sweep)
{
    cbm_context *ctx = test_ctx();
    const char *sweep[] = {NULL,         "K=1e3",     "K=3e4",     "SMOOTH=0", "SMOOTH=0.005",
                           "SEG=0.04",   "SEG=0.06",  "DOWN=50",   "DOWN=70",  "LEAF=0.003",
                           "LEAF=0.005", "TROP=0.03", "TROP=0.08", "GY=0.15",  "GY=0.25",
                           "R0=0.0013",  "R0=0.0017", "STEPS=60"};
    for (size_t j = 0; j < sizeof sweep / sizeof *sweep; j++) {
        double gy = sweep[j] && !strncmp(sweep[j], "GY=", 3) ? atof(sweep[j] + 3) : 0.2;
        model_result r;
        cbm_status st = run_model(ctx, "jirasek-ground.l", sweep[j], -gy, &r);
        printf("%-13s %s: %zu internodes, %zu on the ground, depth %.2e m, largest turn %.3f "
               "rad, largest change of turn %.3f rad\n",
               sweep[j] ? sweep[j] : "(defaults)", cbm_status_name(st), r.segments, r.touching,
               r.depth, r.max_turn, r.max_jump);
        CHECK_OK(st);
        CHECK(r.touching >= 10); /* a good part of the axis lies on the ground */
        CHECK(r.depth < 1e-3);   /* no node sinks a millimetre */
        /* smooth: the sharpest turn is the clamp's (0.37 rad at the defaults) and the turn
         * changes little from joint to joint (0.09 rad at the defaults; the kinked shapes of
         * rings memorised from unbalanced states had 2 rad) */
        CHECK(r.max_turn < 0.5);
        CHECK(r.max_jump < 0.2);
    }
    test_ctx_end(ctx);
}

/* Fig. 8 (models/jirasek-cycad.l): the rosette converges at every step, the tips of the old
 * fronds rest on the ground, none deeper than the bound below; a stiffer ground keeps them
 * shallower; lighter and heavier leaflets and other insertion angles converge too. */
TEST(contact_model_cycad)
{
    cbm_context *ctx = test_ctx();
    model_result r, rs;
    CHECK_OK(run_model(ctx, "jirasek-cycad.l", NULL, 0.0, &r));
    CHECK_OK(run_model(ctx, "jirasek-cycad.l", "K=1e5", 0.0, &rs));
    printf("cycad: %zu internodes, %zu nodes on the ground, depth %.2e m (k 1e5: %zu, %.2e m), "
           "largest turn %.3f rad\n",
           r.segments, r.touching, r.depth, rs.touching, rs.depth, r.max_turn);
    CHECK(r.segments == 2 + 24 * 14);
    CHECK(r.touching >= 8);
    CHECK(r.depth > 0.0 && r.depth < 5e-4);
    CHECK(rs.touching >= 8);
    CHECK(rs.depth < 0.5 * r.depth);
    /* nearby leaflet loads and insertion angles converge too */
    const char *sweep[] = {"PINNA=0.25", "PINNA=0.5", "ANGLE=20", "ANGLE=45"};
    for (size_t j = 0; j < sizeof sweep / sizeof *sweep; j++) {
        cbm_status st = run_model(ctx, "jirasek-cycad.l", sweep[j], 0.0, &r);
        printf("cycad %-10s %s: %zu nodes on the ground, depth %.2e m\n", sweep[j],
               cbm_status_name(st), r.touching, r.depth);
        CHECK_OK(st);
        CHECK(r.touching >= 8);
        CHECK(r.depth > 0.0 && r.depth < 5e-4);
    }
    test_ctx_end(ctx);
}
