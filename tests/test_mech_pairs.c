/* Organ-organ contact by penalty (Jirasek et al. 2000 §2.8, Fig. 6; src/mech/contact.c): the grid
 * detection against brute force on random sets; the tangent with touching pairs against finite
 * differences; a symmetric pair of weightless cantilevers pushed apart against the closed form
 * P(k) = K delta / (1 + K / (2 k)) (K the discrete lateral stiffness from a separate solve with a
 * tip force, and 3 EI / (L^3 cos^2 theta)) and overlap = P / k; a hanging pair against a separate
 * single-stem solve with the contact force as a tip load; overlap bounded by force / k (+ s/2);
 * relaxation and Newton at the same equilibrium on a bunch; Newton's passes bounded; no
 * allocation in the solver loop; growth of the pair room when all spheres overlap; the OOM
 * loop; errors. */
#include "lsys_util.h"
#include "mech_testlib.h"
#include "mech/mech_internal.h"
#include "core/vecmath.h"
#include "cambium/lsys.h"

#include <stdio.h>

/* Two weightless (or heavy) stems of n segments clamped at the same base point, deviating by
 * +-theta about U from the base heading (identity base: H = +x, deviation turns H towards L =
 * +y), each with a fruit of radius r and mass m at its tip. */
static cbm_plant *pair_of_stems(cbm_context *ctx, int n, double L, double a, double E, double rho,
                                double theta, double r, double m, bool gravity, int stems)
{
    cbm_plant_def pd = cbm_plant_def_default();
    if (!gravity)
        pd.gravity = v3(0, 0, 0);
    else
        pd.base_orientation = cbm_mech_clamp_orientation(-0.5 * PI); /* hanging: H = -y */
    cbm_plant *p = NULL;
    CHECK_OK(cbm_plant_create(ctx, &pd, &p));
    if (!p)
        return NULL;
    for (int s = 0; s < stems; s++) {
        cbm_segment_def d = cbm_segment_def_default();
        d.length = L / n;
        d.core.youngs_modulus = E;
        d.core.shear_modulus = E / 2.6;
        d.core.density = rho;
        d.core.a = d.core.b = a;
        size_t base = cbm_plant_segment_count(p);
        for (int i = 0; i < n; i++) {
            d.parent = i == 0 ? -1 : (int64_t)(base + (size_t)i - 1);
            d.deviation = i == 0 ? (s == 0 ? theta : -theta) : 0.0;
            if (i == n - 1) {
                d.point_mass = m;
                d.contact_radius = r;
            }
            CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
        }
    }
    return p;
}

/* A bunch: a hanging peduncle of 3 segments, `k` pedicels of `m` segments spreading from its tip
 * by `spread` rad at even divergence angles, a fruit of radius r and mass `fm` on each. */
static cbm_plant *bunch(cbm_context *ctx, int k, int m, double spread, double r, double fm)
{
    cbm_plant *p = clamped_plant(ctx, -0.5 * PI + 0.3);
    if (!p)
        return NULL;
    cbm_segment_def d = cbm_segment_def_default();
    d.length = 0.01;
    d.core.youngs_modulus = 3e8;
    d.core.shear_modulus = 3e8 / 2.6;
    d.core.density = 1000;
    d.core.a = d.core.b = 0.0012;
    for (int i = 0; i < 3; i++) {
        d.parent = i - 1;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    d.core.a = d.core.b = 0.0006;
    d.length = 0.005;
    for (int j = 0; j < k; j++) {
        for (int i = 0; i < m; i++) {
            d.parent = i == 0 ? 2 : (int64_t)cbm_plant_segment_count(p) - 1;
            d.divergence = i == 0 ? 2.0 * PI * j / k : 0.0;
            d.deviation = i == 0 ? spread : 0.0;
            d.lateral = i == 0;
            d.point_mass = i == m - 1 ? fm : 0.0;
            d.contact_radius = i == m - 1 ? r : 0.0;
            CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
        }
    }
    return p;
}

/* brute-force pair forces of the current state (independent of the grid) */
static void brute_forces(const cbm_plant *p, double k, double s, cbm_vec3 *f, size_t *npairs)
{
    size_t n = cbm_plant_segment_count(p), np = 0;
    for (size_t i = 0; i < n; i++)
        f[i] = v3(0, 0, 0);
    for (size_t i = 0; i < n; i++) {
        cbm_segment_state a;
        CHECK_OK(cbm_plant_segment(p, i, &a));
        if (!(a.contact_radius > 0))
            continue;
        for (size_t j = i + 1; j < n; j++) {
            cbm_segment_state b;
            CHECK_OK(cbm_plant_segment(p, j, &b));
            if (!(b.contact_radius > 0))
                continue;
            cbm_vec3 d = v3_sub(b.distal, a.distal);
            double dist = v3_norm(d), ov = a.contact_radius + b.contact_radius - dist;
            if (!(ov > 0))
                continue;
            np++;
            double fm = ov < s ? 0.5 * k * ov * ov / s : k * (ov - 0.5 * s);
            cbm_vec3 fv = v3_scale(d, fm / dist);
            f[j] = v3_add(f[j], fv);
            f[i] = v3_sub(f[i], fv);
        }
    }
    *npairs = np;
}

static double max_overlap(const cbm_plant *p)
{
    cbm_contact_stats cs;
    CHECK_OK(cbm_plant_contact_stats(p, &cs));
    return cs.max_overlap;
}

/* a small seeded generator (xorshift) */
static double urand(uint64_t *s)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return (double)(*s >> 11) / 9007199254740992.0;
}

static int pair_cmp(const void *x, const void *y)
{
    const cbm__mech_pair *a = x, *b = y;
    if (a->a != b->a)
        return a->a < b->a ? -1 : 1;
    return a->b < b->b ? -1 : (a->b > b->b);
}

TEST(pairs_grid_equals_brute_force)
{
    cbm_context *ctx = test_ctx();
    uint64_t seed = 0x9E3779B97F4A7C15ull;
    const size_t sizes[] = {2, 17, 200, 1500};
    for (int t = 0; t < 4; t++) {
        size_t n = sizes[t];
        cbm__sphere_grid g;
        memset(&g, 0, sizeof g);
        CHECK_OK(cbm__sphere_grid_reserve(ctx, &g, n));
        cbm_vec3 *c = malloc(n * sizeof *c);
        double *r = malloc(n * sizeof *r);
        /* a cloud whose density gives a few neighbours each; radii over a factor 4; some
         * spheres with radius 0; a far outlier; negative coordinates */
        double box = 0.02 * cbrt((double)n);
        for (size_t i = 0; i < n; i++) {
            c[i] = v3(box * (urand(&seed) - 0.5), box * (urand(&seed) - 0.7),
                      box * (urand(&seed) - 0.2));
            r[i] = (i % 11 == 5) ? 0.0 : 0.003 + 0.009 * urand(&seed);
        }
        c[0] = v3(1e6, -3e5, 2.5);
        size_t cap = n * n, brute = 0;
        cbm__mech_pair *out = malloc(cap * sizeof *out), *ref = malloc(cap * sizeof *ref);
        size_t found = cbm__sphere_grid_pairs(&g, c, r, n, out, cap);
        for (size_t i = 0; i < n; i++)
            for (size_t j = i + 1; j < n; j++) {
                if (!(r[i] > 0 && r[j] > 0))
                    continue;
                cbm_vec3 d = v3_sub(c[j], c[i]);
                if (v3_dot(d, d) < (r[i] + r[j]) * (r[i] + r[j])) {
                    ref[brute].a = i;
                    ref[brute].b = j;
                    brute++;
                }
            }
        printf("n = %zu: grid %zu pairs, brute force %zu\n", n, found, brute);
        CHECK_EQ_INT(found, brute);
        CHECK(n < 200 || brute > n / 2); /* the test has pairs to find */
        qsort(out, found, sizeof *out, pair_cmp);
        bool same = found == brute;
        for (size_t q = 0; q < found && same; q++) {
            same = out[q].a == ref[q].a && out[q].b == ref[q].b;
            same = same && fabs(out[q].over - (r[out[q].a] + r[out[q].b] -
                                               v3_norm(v3_sub(c[out[q].b], c[out[q].a])))) < 1e-15;
        }
        CHECK(same);
        /* a short room stores only what fits, and still counts all */
        if (found > 3)
            CHECK_EQ_INT(cbm__sphere_grid_pairs(&g, c, r, n, out, 3), found);
        free(out);
        free(ref);
        free(c);
        free(r);
        cbm__sphere_grid_free(ctx, &g);
    }
    test_ctx_end(ctx);
}

TEST(pairs_defaults_and_errors)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = pair_of_stems(ctx, 4, 0.1, 0.002, 1e9, 0, 0.05, 0.0055, 0.0, false, 2);
    CHECK(!cbm_plant_contact(p, NULL, NULL));
    CHECK_STATUS(cbm_plant_set_contact(p, -1.0, 0.0), CBM_E_INVALID);
    CHECK_STATUS(cbm_plant_set_contact(p, NAN, 0.0), CBM_E_INVALID);
    CHECK_STATUS(cbm_plant_set_contact(p, 1e3, -1.0), CBM_E_INVALID);
    CHECK_STATUS(cbm_plant_set_contact_radius(p, 99, 0.01), CBM_E_INVALID);
    CHECK_STATUS(cbm_plant_set_contact_radius(p, 0, -0.01), CBM_E_INVALID);
    CHECK_STATUS(cbm_plant_set_contact_radius(p, 0, INFINITY), CBM_E_INVALID);
    cbm_segment_def d = cbm_segment_def_default();
    d.contact_radius = -1;
    CHECK_STATUS(cbm_plant_add_segment(p, &d, NULL), CBM_E_INVALID);
    /* without contact the overlapping fruits do not interact */
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    CHECK(v3_norm(cbm_plant_organ_contact_force(p, 3)) == 0.0);
    cbm_contact_stats cs;
    CHECK_OK(cbm_plant_contact_stats(p, &cs));
    CHECK(cs.spheres == 2 && cs.pairs == 0);
    CHECK_OK(cbm_plant_set_contact(p, 2e3, 1e-4));
    double k = 0, s = 0;
    CHECK(cbm_plant_contact(p, &k, &s) && k == 2e3 && s == 1e-4);
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    CHECK_OK(cbm_plant_contact_stats(p, &cs));
    CHECK(cs.pairs == 1 && cs.max_overlap > 0);
    cbm_vec3 f3 = cbm_plant_organ_contact_force(p, 3), f7 = cbm_plant_organ_contact_force(p, 7);
    CHECK(f3.y > 0 && f7.y < 0 && fabs(f3.y + f7.y) < 1e-15); /* apart, equal and opposite */
    CHECK_OK(cbm_plant_set_contact(p, 0.0, 0.0));
    CHECK(!cbm_plant_contact(p, NULL, NULL));
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* The tangent with touching pairs (and the ground) is the exact derivative of the residual. */
TEST(pairs_tangent_matches_finite_differences)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = bunch(ctx, 7, 5, 0.25, 0.006, 0.004);
    size_t n = cbm_plant_segment_count(p);
    for (size_t i = 0; i < n; i++)
        CHECK_OK(cbm_plant_set_omega(
            p, i, v3(0.3 * sin(1.0 * i), 2.0 * cos(3.0 * i), 1.5 * sin(2.0 * i + 1))));
    CHECK_OK(cbm_plant_set_contact(p, 800.0, 0.0005));
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    /* a ground halfway up the fruits too */
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(p, i, &s));
        if (s.contact_radius > 0) {
            lo = fmin(lo, s.distal.y);
            hi = fmax(hi, s.distal.y);
        }
    }
    CHECK_OK(cbm_plant_set_ground(p, 0.5 * (lo + hi), 500.0, 0.0));
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    size_t below = 0;
    for (size_t i = 0; i < n; i++)
        below += cbm_plant_contact_force(p, i) > 0.0;
    cbm_contact_stats cs;
    CHECK_OK(cbm_plant_contact_stats(p, &cs));
    printf("touching pairs: %zu, max overlap %.3g m; %zu nodes below the ground\n", cs.pairs,
           cs.max_overlap, below);
    CHECK(below >= 2);
    CHECK(cs.pairs >= 3);
    /* some pairs on the smoothed branch, some beyond it */
    CHECK(cs.max_overlap > 0.0005);
    CHECK_OK(cbm__mech_work_reserve(p, 1));
    cbm__mech_prepare(p);
    /* NOLINTNEXTLINE(clang-analyzer-optin.portability.UnixAPI): n > 0, the plant built above */
    cbm_vec3 *v = calloc(n, sizeof *v), *jv = calloc(n, sizeof *jv), *rp = calloc(n, sizeof *rp),
             *rm = calloc(n, sizeof *rm), *om = calloc(n, sizeof *om);
    for (size_t i = 0; i < n; i++) {
        v[i] = v3(sin(3.0 * i), cos(5.0 * i), sin(7.0 * i + 1));
        om[i] = p->omega[i];
    }
    double mm;
    cbm__mech_forward(p);
    cbm__mech_backward(p, 0.0, NULL, &mm, NULL);
    CHECK(cbm__mech_pairs_active(p));
    cbm__mech_jvp(p, v, jv);
    double eps = 1e-7, maxd = 0, maxj = 0;
    for (int sgn = -1; sgn <= 1; sgn += 2) {
        for (size_t i = 0; i < n; i++)
            p->omega[i] = v3_add(om[i], v3_scale(v[i], sgn * eps));
        cbm__mech_forward(p);
        cbm__mech_backward(p, 0.0, sgn < 0 ? rm : rp, &mm, NULL);
    }
    for (size_t i = 0; i < n; i++) {
        cbm_vec3 fd = v3_scale(v3_sub(rp[i], rm[i]), 0.5 / eps);
        maxd = fmax(maxd, v3_norm(v3_sub(fd, jv[i])));
        maxj = fmax(maxj, v3_norm(jv[i]));
    }
    /* the same without the pair terms differs: the test sees them */
    for (size_t i = 0; i < n; i++)
        p->omega[i] = om[i];
    cbm__mech_forward(p);
    cbm__mech_backward(p, 0.0, NULL, &mm, NULL);
    size_t keep = p->contacts.npairs;
    p->contacts.npairs = 0;
    cbm__mech_jvp(p, v, rp);
    p->contacts.npairs = keep;
    double without = 0;
    for (size_t i = 0; i < n; i++)
        without = fmax(without, v3_norm(v3_sub(rp[i], jv[i])));
    printf("tangent with pairs vs central differences: max diff %.3g, max |Jv| %.3g; pair terms "
           "%.3g\n",
           maxd, maxj, without);
    CHECK(maxd < 1e-6 * maxj);
    CHECK(without > 1e-3 * maxj);
    free(v);
    free(jv);
    free(rp);
    free(rm);
    free(om);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Tip displacement along y of one weightless stem (deviation +theta) under the tip force (0, F,
 * 0): the discrete lateral stiffness K = F / dy, from a solve without contact. */
static double lateral_stiffness(cbm_context *ctx, int n, double L, double a, double E, double theta,
                                double F)
{
    cbm_plant *p = pair_of_stems(ctx, n, L, a, E, 0, theta, 0.0, 0.0, false, 1);
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    double y0 = rod_tip(p).y;
    CHECK_OK(cbm_plant_set_load(p, (size_t)n - 1, 0.0, v3(0, F, 0), v3(0, 0, 0)));
    cbm_solve_def sd = cbm_solve_def_default();
    sd.tolerance = 1e-12;
    CHECK_OK(cbm_plant_solve(p, &sd, NULL));
    double dy = rod_tip(p).y - y0;
    cbm_plant_destroy(p);
    return F / dy;
}

/* Two weightless cantilevers at +-theta whose fruits overlap at rest: the stiff limit and the
 * penalty closed form P(k) = K delta / (1 + K / (2 k)), overlap = P / k, from a separate solve
 * of K; K against the beam formula 3 EI / (L^3 cos^2 theta). */
TEST(pairs_symmetric_cantilevers_closed_form)
{
    cbm_context *ctx = test_ctx();
    const int n = 40;
    /* each tip must move 50 um out (delta / L = 5e-4: the small-deflection closed form holds to
     * about 1e-5, with the tension of the force's axial component P sin theta) */
    const double L = 0.1, a = 0.002, E = 1e9, theta = 0.05, r = L * sin(theta) + 5e-5;
    double EI = E * PI * pow(a, 4) / 4;
    double Kbeam = 3 * EI / (L * L * L * cos(theta) * cos(theta));
    double delta = r - L * sin(theta);
    double K = lateral_stiffness(ctx, n, L, a, E, theta, 1e-3);
    printf("lateral stiffness: discrete %.6g N/m, beam formula %.6g N/m\n", K, Kbeam);
    CHECK_REL(K, Kbeam, 2e-3);
    double prev_err = INFINITY;
    /* up to k = 300 K: beyond, the round-off of the node positions times k (k |X| eps against
     * the contact force) is above the residual tolerance */
    const double ks[] = {0.3, 3.0, 30.0, 300.0};
    for (int t = 0; t < 4; t++) {
        double k = ks[t] * K;
        cbm_plant *p = pair_of_stems(ctx, n, L, a, E, 0, theta, r, 0.0, false, 2);
        CHECK_OK(cbm_plant_set_contact(p, k, 0.0));
        /* the relaxation needs alpha below 2 K / (K + 2 k): slow for a stiff contact */
        for (int solver = 0; solver < (ks[t] < 10 ? 2 : 1); solver++) {
            for (size_t i = 0; i < 2 * (size_t)n; i++)
                CHECK_OK(cbm_plant_set_omega(p, i, v3(0, 0, 0)));
            cbm_solve_def sd = cbm_solve_def_default();
            sd.tolerance = 1e-10;
            sd.solver = solver ? CBM_MECH_RELAX : CBM_MECH_NEWTON;
            sd.alpha = 1.0 / (1.0 + k / K);
            sd.max_passes = 100000;
            cbm_solve_stats st;
            CHECK_OK(cbm_plant_solve(p, &sd, &st));
            cbm_vec3 f = cbm_plant_organ_contact_force(p, (size_t)2 * n - 1);
            double P = v3_norm(f), expect = K * delta / (1.0 + K / (2.0 * k));
            double ov = max_overlap(p);
            printf("k = %g K (%s): P = %.8g N, closed form %.8g N, overlap %.3g m = P/k * "
                   "%.9f; %zu passes, %zu Newton steps, %zu Krylov\n",
                   ks[t], solver ? "relax" : "fast", P, expect, ov, ov * k / P, st.passes,
                   st.newton_steps, st.krylov_iterations);
            /* small-deflection closed form: delta / L = 0.5 % leaves a relative 1e-4 */
            CHECK_REL(P, expect, 3e-5);
            CHECK_REL(ov, P / k, 1e-8);
            CHECK(fabs(f.x) < 1e-9 * P && fabs(f.z) < 1e-9 * P); /* along the line of centres */
            if (solver == 0) {
                CHECK(st.newton_steps <= 12);
                CHECK(st.passes <= 200);
                double err = fabs(P - K * delta);
                CHECK(err < prev_err);
                prev_err = err;
            }
        }
        cbm_plant_destroy(p);
    }
    test_ctx_end(ctx);
}

/* Two heavy hanging stems pushed apart by their heavy fruits: the contact force on one fruit,
 * put on a single stem as a dead tip force, gives the same stem (a separate computation). The
 * overlap is at most force / k. */
TEST(pairs_hanging_pair_matches_single_stem)
{
    cbm_context *ctx = test_ctx();
    const int n = 16;
    const double L = 0.04, a = 0.0006, E = 3e8, theta = 0.08, r = 0.006, m = 0.006;
    const double ks[] = {50.0, 500.0, 5000.0};
    for (int t = 0; t < 3; t++) {
        cbm_plant *p = pair_of_stems(ctx, n, L, a, E, 1000, theta, r, m, true, 2);
        CHECK_OK(cbm_plant_set_contact(p, ks[t], 0.0));
        cbm_solve_stats st;
        CHECK_OK(cbm_plant_solve(p, NULL, &st));
        cbm_vec3 f = cbm_plant_organ_contact_force(p, (size_t)n - 1);
        double ov = max_overlap(p);
        cbm_plant *q = pair_of_stems(ctx, n, L, a, E, 1000, theta, 0.0, m, true, 1);
        CHECK_OK(cbm_plant_set_load(q, (size_t)n - 1, m, f, v3(0, 0, 0)));
        cbm_solve_def sd = cbm_solve_def_default();
        sd.tolerance = 1e-12;
        CHECK_OK(cbm_plant_solve(q, &sd, NULL));
        cbm_segment_state s1;
        CHECK_OK(cbm_plant_segment(p, (size_t)n - 1, &s1));
        double d = v3_norm(v3_sub(s1.distal, rod_tip(q)));
        printf("k = %g N/m: contact force %.6g N, overlap %.3g m (force/k %.3g); tip of the "
               "single stem under it within %.2g m; %zu passes, %zu Newton steps\n",
               ks[t], v3_norm(f), ov, v3_norm(f) / ks[t], d, st.passes, st.newton_steps);
        CHECK(v3_norm(f) > 1e-4);
        CHECK(d < 1e-7 * L);
        CHECK(ov <= v3_norm(f) / ks[t] * (1 + 1e-8));
        CHECK(st.newton_steps <= 25);
        cbm_plant_destroy(q);
        cbm_plant_destroy(p);
    }
    test_ctx_end(ctx);
}

/* A bunch of six fruits that overlap at rest: both solvers reach the same equilibrium, the
 * forces equal a brute-force evaluation, the overlap stays below force / k + s / 2. (Crowd
 * them more and several equilibria exist: the relaxation and the fast solver, which follows the
 * loading path, may then settle in different ones.) Newton's passes stay bounded as k grows. */
TEST(pairs_bunch_solvers_agree)
{
    cbm_context *ctx = test_ctx();
    const double sm = 2e-4;
    cbm_vec3 tips[2][64];
    size_t n = 0;
    const double ks[] = {30.0, 30.0, 300.0, 3000.0, 30000.0};
    for (int t = 0; t < 5; t++) {
        int solver = t == 0;
        double k = ks[t];
        cbm_plant *p = bunch(ctx, 6, 5, 0.4, 0.006, 0.004);
        CHECK_OK(cbm_plant_set_contact(p, k, sm));
        n = cbm_plant_segment_count(p);
        cbm_solve_def sd = cbm_solve_def_default();
        sd.solver = solver ? CBM_MECH_RELAX : CBM_MECH_NEWTON;
        sd.tolerance = 1e-10;
        sd.alpha = 0.05;
        sd.max_passes = 200000;
        cbm_solve_stats st;
        CHECK_OK(cbm_plant_solve(p, &sd, &st));
        cbm_contact_stats cs;
        CHECK_OK(cbm_plant_contact_stats(p, &cs));
        printf(
            "k = %g N/m, %s: %zu passes, %zu Newton steps, %zu Krylov iterations, %zu continuation "
            "steps; %zu pairs, max overlap %.3g m, max force %.3g N\n",
            k, solver ? "relax" : "fast", st.passes, st.newton_steps, st.krylov_iterations,
            st.continuation_steps, cs.pairs, cs.max_overlap, cs.max_force);
        CHECK(cs.pairs >= 5);
        CHECK(cs.max_overlap <= cs.max_force / k + 0.5 * sm + 1e-12);
        if (solver == 0)
            CHECK(st.passes <= 400 && st.newton_steps <= 20);
        cbm_vec3 bf[64];
        size_t np = 0;
        brute_forces(p, k, sm, bf, &np);
        CHECK_EQ_INT(np, cs.pairs);
        double fe = 0, fm = 0;
        for (size_t i = 0; i < n; i++) {
            fe = fmax(fe, v3_norm(v3_sub(bf[i], cbm_plant_organ_contact_force(p, i))));
            fm = fmax(fm, v3_norm(bf[i]));
        }
        CHECK(fe <= 1e-12 * fm);
        for (size_t i = 0; i < n && t < 2; i++) {
            cbm_segment_state s;
            CHECK_OK(cbm_plant_segment(p, i, &s));
            tips[solver][i] = s.distal;
        }
        cbm_plant_destroy(p);
    }
    double dmax = 0;
    for (size_t i = 0; i < n; i++)
        dmax = fmax(dmax, v3_norm(v3_sub(tips[0][i], tips[1][i])));
    printf("largest node distance between the solvers: %.3g m\n", dmax);
    CHECK(dmax < 1e-7);
    test_ctx_end(ctx);
}

/* No allocation inside the solver loop with contact (a counting allocator). */
TEST(pairs_no_allocation_in_solver_loop)
{
    size_t calls = 0;
    cbm_context *ctx = test_counting_ctx(&calls);
    CHECK(ctx != NULL);
    cbm_plant *p = bunch(ctx, 6, 5, 0.4, 0.006, 0.004);
    CHECK_OK(cbm_plant_set_contact(p, 30.0, 2e-4));
    for (int solver = 0; solver < 2; solver++) {
        cbm_solve_def sd = cbm_solve_def_default();
        sd.solver = (cbm_mech_solver)solver;
        sd.alpha = 0.05;
        sd.warm_start = false;
        sd.max_passes = 6;
        (void)cbm_plant_solve(p, &sd, NULL); /* may allocate the workspace once */
        size_t c0 = calls;
        sd.max_passes = 200000;
        CHECK_OK(cbm_plant_solve(p, &sd, NULL));
        CHECK_EQ_INT(calls - c0, 0);
    }
    cbm_plant_destroy(p);
    CHECK_EQ_INT(cbm_context_bytes(ctx), 0);
    cbm_context_destroy(ctx);
}

/* Thirty fruits on thirty stems from one point, all overlapping: 435 pairs, more than the room
 * reserved at first (6 per sphere); the solve grows it and the forces are complete. */
TEST(pairs_room_grows)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = bunch(ctx, 30, 2, 0.05, 0.01, 0.002);
    CHECK_OK(cbm_plant_set_contact(p, 20.0, 0.0));
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    cbm_contact_stats cs;
    CHECK_OK(cbm_plant_contact_stats(p, &cs));
    CHECK_EQ_INT(cs.pairs, 435);
    cbm_solve_def sd = cbm_solve_def_default();
    cbm_solve_stats st;
    CHECK_OK(cbm_plant_solve(p, &sd, &st));
    CHECK_OK(cbm_plant_contact_stats(p, &cs));
    size_t n = cbm_plant_segment_count(p), np = 0;
    cbm_vec3 *bf = calloc(n, sizeof *bf);
    brute_forces(p, 20.0, 0.0, bf, &np);
    double fe = 0, fm = 0;
    for (size_t i = 0; i < n; i++) {
        fe = fmax(fe, v3_norm(v3_sub(bf[i], cbm_plant_organ_contact_force(p, i))));
        fm = fmax(fm, v3_norm(bf[i]));
    }
    printf("30 fruits: %zu pairs at equilibrium (brute force %zu), %zu passes\n", cs.pairs, np,
           st.passes);
    CHECK_EQ_INT(np, cs.pairs);
    CHECK(fm > 0 && fe <= 1e-12 * fm);
    free(bf);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

static cbm_status oom_case(cbm_context *ctx, void *ud)
{
    (void)ud;
    cbm_plant_def pd = cbm_plant_def_default();
    cbm_plant *p = NULL;
    CBM_TRY(cbm_plant_create(ctx, &pd, &p));
    cbm_segment_def d = cbm_segment_def_default();
    d.core.a = d.core.b = 0.002;
    d.core.youngs_modulus = 1e9;
    cbm_status s = CBM_OK;
    for (int j = 0; j < 3 && s == CBM_OK; j++)
        for (int i = 0; i < 4 && s == CBM_OK; i++) {
            d.parent = i == 0 ? -1 : (int64_t)cbm_plant_segment_count(p) - 1;
            d.deviation = i == 0 ? 0.05 * (j - 1) : 0.0;
            d.contact_radius = i == 3 ? 0.015 : 0.0; /* neighbours overlap at rest */
            d.point_mass = i == 3 ? 0.01 : 0.0;
            s = cbm_plant_add_segment(p, &d, NULL);
        }
    if (s == CBM_OK)
        s = cbm_plant_set_contact(p, 100.0, 1e-4);
    cbm_solve_stats st;
    memset(&st, 0, sizeof st);
    if (s == CBM_OK)
        s = cbm_plant_solve(p, NULL, &st);
    cbm_contact_stats cs;
    memset(&cs, 0, sizeof cs);
    if (s == CBM_OK)
        s = cbm_plant_contact_stats(p, &cs);
    if (s == CBM_OK && (cs.pairs < 2 || st.krylov_iterations == 0))
        s = CBM_E_INVALID; /* the case must exercise the pairs and the FGMRES path */
    cbm_plant_destroy(p);
    return s;
}

TEST(pairs_out_of_memory)
{
    int runs = test_oom_loop(oom_case, NULL);
    CHECK(runs > 5);
}

/* ---- the L+C dialect and the shipped model ---- */

typedef struct grapes_result {
    size_t spheres, pairs, max_pairs, segments;
    double overlap, force; /* largest over the steps, m and N */
    double geometric;      /* largest overlap of any two berries at the end (brute force), m */
    double passes;         /* largest Equilibrium() pass count of a step */
} grapes_result;

/* Runs models/<name> (optional -D override), evaluating the plant of every step. */
static cbm_status run_grapes(cbm_context *ctx, const char *name, const char *define,
                             grapes_result *r)
{
    cbm_lsys *ls = NULL;
    memset(r, 0, sizeof *r);
    cbm_status st = lsys_load_shipped(ctx, name, define, &ls);
    if (st != CBM_OK)
        return st;
    st = cbm_lsys_reset(ls);
    for (int k = 0; st == CBM_OK && k < cbm_lsys_derivation_length(ls); k++) {
        st = cbm_lsys_step(ls);
        cbm_plant *p = NULL;
        if (st == CBM_OK)
            st = cbm_lsys_mech_plant(ls, &p);
        double res = 1;
        if (st == CBM_OK)
            st = cbm_plant_evaluate(p, &res);
        cbm_contact_stats cs;
        memset(&cs, 0, sizeof cs);
        if (st == CBM_OK)
            st = cbm_plant_contact_stats(p, &cs);
        if (st == CBM_OK && res > 1e-7)
            st = CBM_E_NOT_CONVERGED; /* the stored state is the equilibrium */
        r->spheres = cs.spheres;
        r->pairs = cs.pairs;
        r->max_pairs = cs.pairs > r->max_pairs ? cs.pairs : r->max_pairs;
        r->overlap = fmax(r->overlap, cs.max_overlap);
        r->force = fmax(r->force, cs.max_force);
        r->segments = p ? cbm_plant_segment_count(p) : 0;
        r->geometric = 0;
        for (size_t i = 0; p && i < r->segments; i++) {
            cbm_segment_state a, b;
            CHECK_OK(cbm_plant_segment(p, i, &a));
            for (size_t j = i + 1; a.contact_radius > 0 && j < r->segments; j++) {
                CHECK_OK(cbm_plant_segment(p, j, &b));
                if (b.contact_radius > 0)
                    r->geometric = fmax(r->geometric, a.contact_radius + b.contact_radius -
                                                          v3_norm(v3_sub(a.distal, b.distal)));
            }
        }
        cbm_plant_destroy(p);
    }
    cbm_lsys_destroy(ls);
    return st;
}

/* Contact(k, smoothing) and `mass: Grape(mass, radius)`; the declaration's errors. */
TEST(pairs_language)
{
    cbm_context *ctx = test_ctx();
    static const char *src =
        "#include <lpfgall.h>\n"
        "derivation length: 1;\n"
        "module I(MechSegment);\n"
        "module Fruit(int, double, double);\n"
        "mechanics: I;\n"
        "mass: Fruit(_, radius, mass);\n"
        "MechSegment S() { MechSegment s; s.length = 0.05; s.a = 0.002; s.b = 0.002; s.E = 1e9; "
        "s.density = 0; return s; }\n"
        "Start: { Gravity(0, 0, 0); Contact(3000, 0); }\n"
        "EndEach: { Equilibrium(); }\n"
        "Axiom: SB Left(3) I(S()) I(S()) Fruit(7, 0.006, 0.01) EB SB Right(3) I(S()) I(S()) "
        "Fruit(7, 0.006, 0.01) EB;\n";
    cbm_lsys_def def = cbm_lsys_def_default();
    def.text = src;
    def.path = "fruit.l";
    cbm_lsys *ls = lsys_from_def(ctx, &def);
    CHECK_OK(cbm_lsys_step(ls));
    cbm_plant *p = NULL;
    CHECK_OK(cbm_lsys_mech_plant(ls, &p));
    double k = 0;
    CHECK(cbm_plant_contact(p, &k, NULL) && k == 3000);
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    cbm_contact_stats cs;
    CHECK_OK(cbm_plant_contact_stats(p, &cs));
    cbm_segment_state s;
    CHECK_OK(cbm_plant_segment(p, 1, &s));
    printf("two fruits from the language: %zu spheres, %zu pairs, overlap %.3g m, force %.3g N, "
           "mass %g kg\n",
           cs.spheres, cs.pairs, cs.max_overlap, cs.max_force, s.point_mass);
    CHECK(cs.spheres == 2 && s.contact_radius == 0.006 && s.point_mass == 0.01);
    /* 2 sin(3 deg) 0.1 m = 10.5 mm apart at rest: pushed apart to 12 mm less force / k */
    CHECK(cs.pairs == 1 && cs.max_overlap > 0 && cs.max_overlap <= cs.max_force / 3000 * 1.0001);
    cbm_plant_destroy(p);
    cbm_lsys_destroy(ls);
    const char *bad[] = {"mass: Fruit(_, radius);", "mass: Fruit(weight);",
                         "mass: Fruit(mass, mass);", "mass: Fruit(mass, _, radius, _);",
                         "mass: Fruit(mass, radius, _;"};
    for (int j = 0; j < 5; j++) {
        char buf[512];
        snprintf(buf, sizeof buf,
                 "module Fruit(double, double, double);\nmodule I(MechSegment);\n"
                 "mechanics: I;\n%s\nmodule A();\nAxiom: A;\n",
                 bad[j]);
        test_diags g;
        cbm_context *dc = test_diag_ctx(&g);
        CHECK(dc != NULL);
        def.text = buf;
        ls = NULL;
        cbm_status st = cbm_lsys_load(dc, &def, &ls);
        printf("%-40s -> %s: %s", bad[j], cbm_status_name(st), g.text);
        CHECK(st == CBM_E_SYNTAX);
        CHECK(!strncmp(g.text, "fruit.l:4:", 10) && strstr(g.text, "\n?:0:0: 1 error in"));
        cbm_lsys_destroy(ls);
        CHECK_EQ_INT(cbm_context_bytes(dc), 0);
        cbm_context_destroy(dc);
    }
    def.text = "module A();\nderivation length: 1;\nStart: { Contact(-1, 0); }\nAxiom: A;\n";
    ls = NULL;
    CHECK_OK(cbm_lsys_load(ctx, &def, &ls));
    if (ls)
        CHECK_STATUS(cbm_lsys_reset(ls), CBM_E_INVALID);
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

/* Fig. 6 (models/jirasek-grapes.l): the berries touch (several pairs), no two overlap by more
 * than 0.5 mm at any step, every step converges; without contact they pass through each other;
 * softer and stiffer contact converge too, the overlap falling as k grows. */
TEST(pairs_model_grapes)
{
    cbm_context *ctx = test_ctx();
    grapes_result r, r0;
    CHECK_OK(run_grapes(ctx, "jirasek-grapes.l", NULL, &r));
    printf("grapes: %zu segments, %zu berries, %zu touching pairs at the end (at most %zu), "
           "largest overlap %.3g m, largest pair force %.3g N\n",
           r.segments, r.spheres, r.pairs, r.max_pairs, r.overlap, r.force);
    CHECK(r.spheres == 15);
    CHECK(r.max_pairs >= 6);
    CHECK(r.overlap > 0 && r.overlap < 5e-4);
    CHECK_REL(r.geometric, r.overlap, 0.5); /* the last step's overlap is near the largest */
    CHECK(r.geometric <= r.overlap);
    CHECK_OK(run_grapes(ctx, "jirasek-grapes.l", "K=0", &r0));
    printf("grapes without contact: berries overlap by up to %.3g m\n", r0.geometric);
    CHECK(r0.spheres == 15 && r0.pairs == 0);
    CHECK(r0.geometric > 0.003); /* they pass through each other */
    const char *sweep[] = {"K=1000", "K=20000", "SMOOTH=0", "SPREAD=45", "RMAX=0.011"};
    double prev = INFINITY;
    for (int j = 0; j < 5; j++) {
        grapes_result rs;
        cbm_status st = run_grapes(ctx, "jirasek-grapes.l", sweep[j], &rs);
        printf("grapes %-10s %s: %zu pairs at most, overlap %.3g m\n", sweep[j],
               cbm_status_name(st), rs.max_pairs, rs.overlap);
        CHECK_OK(st);
        CHECK(rs.max_pairs >= 3);
        if (j < 2) {
            CHECK(rs.overlap < prev);
            prev = rs.overlap;
        }
    }
    test_ctx_end(ctx);
}

/* The low-rank (Woodbury) correction of the tree preconditioner: the same equilibrium as FGMRES
 * with the bare factorisation, in fewer Krylov iterations per Newton step; applied to a vector
 * it inverts the Newton matrix up to the pairs' tangential stiffness. */
TEST(pairs_lowrank_correction)
{
    cbm_context *ctx = test_ctx();
    cbm_vec3 tips[2][64];
    size_t n = 0, kry[2] = {0, 0}, steps[2] = {0, 0};
    for (int off = 0; off < 2; off++) {
        cbm_plant *p = bunch(ctx, 6, 5, 0.4, 0.006, 0.004);
        CHECK_OK(cbm_plant_set_contact(p, 3000.0, 0.0));
        p->contacts.lr_off = off == 1;
        n = cbm_plant_segment_count(p);
        cbm_solve_stats st;
        cbm_solve_def sd = cbm_solve_def_default();
        sd.tolerance = 1e-10;
        CHECK_OK(cbm_plant_solve(p, &sd, &st));
        printf("%s: %zu passes, %zu Newton steps, %zu Krylov iterations\n",
               off ? "FGMRES, bare factorisation" : "FGMRES, low-rank correction", st.passes,
               st.newton_steps, st.krylov_iterations);
        kry[off] = st.krylov_iterations;
        steps[off] = st.newton_steps;
        for (size_t i = 0; i < n; i++) {
            cbm_segment_state s;
            CHECK_OK(cbm_plant_segment(p, i, &s));
            tips[off][i] = s.distal;
        }
        if (off == 0) {
            /* at the equilibrium: P^-1 J v against v, the pairs' tangential part aside */
            CHECK_OK(cbm__mech_work_reserve(p, 10));
            cbm__mech_prepare(p);
            cbm__mech_forward(p);
            double mm;
            cbm__mech_backward(p, 0.0, NULL, &mm, NULL);
            CHECK(cbm__mech_pairs_active(p));
            size_t nonpd = 0;
            cbm__mech_tree_factor(p, 0.0, &nonpd);
            /* NOLINTNEXTLINE(clang-analyzer-optin.portability.UnixAPI): n > 0, built above */
            cbm_vec3 *v = calloc(n, sizeof *v), *jv = calloc(n, sizeof *jv),
                     *z = calloc(n, sizeof *z);
            for (size_t i = 0; i < n; i++)
                v[i] = v3(sin(3.0 * i), cos(5.0 * i), sin(7.0 * i + 1));
            /* the tangent without the pairs' tangential stiffness f/d (I - n n^T): the part the
             * correction leaves out (the pair records' forces enter only that term) */
            for (size_t q = 0; q < p->contacts.npairs; q++)
                p->contacts.pairs[q].force = 0.0;
            cbm__mech_jvp(p, v, jv);
            double e[2];
            for (int corr = 0; corr < 2; corr++) {
                cbm__mech_tree_apply(p, jv, z);
                if (corr)
                    (void)cbm__mech_pairs_precond(p, (double *)z);
                double d = 0, vm = 0;
                for (size_t i = 0; i < n; i++) {
                    d = fmax(d, v3_norm(v3_sub(z[i], v[i])));
                    vm = fmax(vm, v3_norm(v[i]));
                }
                e[corr] = d / vm;
            }
            printf("|P^-1 J v - v| / |v|: bare factorisation %.3g, corrected %.3g\n", e[0], e[1]);
            CHECK(e[1] < 1e-9 * e[0]);
            free(v);
            free(jv);
            free(z);
        }
        cbm_plant_destroy(p);
    }
    double dmax = 0;
    for (size_t i = 0; i < n; i++)
        dmax = fmax(dmax, v3_norm(v3_sub(tips[0][i], tips[1][i])));
    printf("largest node distance: %.3g m\n", dmax);
    CHECK(dmax < 1e-8);
    CHECK(kry[0] * steps[1] < kry[1] * steps[0]); /* fewer Krylov iterations per Newton step */
    test_ctx_end(ctx);
}

/* Fruits that touch each other and rest on the ground: both solvers at the same equilibrium. */
TEST(pairs_with_ground_solvers_agree)
{
    cbm_context *ctx = test_ctx();
    cbm_vec3 tips[2][64];
    size_t n = 0;
    for (int solver = 0; solver < 2; solver++) {
        cbm_plant *p = bunch(ctx, 6, 5, 0.4, 0.006, 0.004);
        CHECK_OK(cbm_plant_set_contact(p, 30.0, 2e-4));
        CHECK_OK(cbm_plant_set_ground(p, -0.05, 30.0, 2e-4));
        n = cbm_plant_segment_count(p);
        cbm_solve_def sd = cbm_solve_def_default();
        sd.solver = solver ? CBM_MECH_RELAX : CBM_MECH_NEWTON;
        sd.tolerance = 1e-10;
        sd.alpha = 0.05;
        sd.max_passes = 200000;
        cbm_solve_stats st;
        CHECK_OK(cbm_plant_solve(p, &sd, &st));
        cbm_contact_stats cs;
        CHECK_OK(cbm_plant_contact_stats(p, &cs));
        size_t below = 0;
        for (size_t i = 0; i < n; i++) {
            below += cbm_plant_contact_force(p, i) > 0.0;
            cbm_segment_state s;
            CHECK_OK(cbm_plant_segment(p, i, &s));
            tips[solver][i] = s.distal;
        }
        printf("%s: %zu passes, %zu Newton steps, %zu Krylov; %zu pairs, %zu nodes on the "
               "ground\n",
               solver ? "relax" : "fast", st.passes, st.newton_steps, st.krylov_iterations,
               cs.pairs, below);
        CHECK(cs.pairs >= 3 && below >= 2);
        cbm_plant_destroy(p);
    }
    double dmax = 0;
    for (size_t i = 0; i < n; i++)
        dmax = fmax(dmax, v3_norm(v3_sub(tips[0][i], tips[1][i])));
    printf("largest node distance between the solvers: %.3g m\n", dmax);
    CHECK(dmax < 1e-7);
    test_ctx_end(ctx);
}
