/* Continuation of bend's rod in a parameter (docs/bend.md "Continuation", docs/validation.md
 * "Folds of the discrete rod"): the heavy rod at alpha = 15 swept in base angle from 0 degrees
 * (one equilibrium, hanging to the right) towards 150 loses its branch at a fold, which must lie
 * on the elastica's fold (cbm_elastica_scurve_compute, 116.4134 degrees) within a tolerance that
 * shrinks at second order as the segments are refined; the rod must jump to the elastica's jump
 * target. Under a gravity sweep the vertical column loses its stability at Greenhill's load. */
#include "test.h"

#include <stdint.h>
#include <string.h>

#define PI 3.14159265358979323846

/* L of the spec's rod (r 0.01 m, E 1e10, density 600) for alpha = rho g L^3 / D at g = 9.81 */
static double rod_length(double alpha)
{
    double I = PI * 1e-8 / 4, w = 600 * PI * 1e-4 * 9.81;
    return cbrt(alpha * 1e10 * I / w);
}

static void run_m(cbm_context *ctx, long segs, double angle, cbm_bend_param param, double from,
                  double to, long steps, cbm_bend_continuation_method method, bool sw,
                  cbm_bend_branch *br)
{
    char t[256];
    snprintf(t, sizeof t,
             "length = %.17g\nsegments = %ld\nradius = 0.01\nangle = %g\n"
             "tolerance = 1e-10\n",
             rod_length(15), segs, angle);
    cbm_bend_spec sp;
    CHECK_OK(cbm_bend_spec_parse(ctx, t, strlen(t), "c.spec", &sp));
    cbm_bend_continuation_def d = cbm_bend_continuation_def_default();
    d.param = param;
    d.from = from;
    d.to = to;
    d.steps = steps;
    d.method = method;
    d.switch_branch = sw;
    CHECK_OK(cbm_bend_continue(ctx, &sp, &d, br));
}

/* the natural method (the tests below it were written for) */
static void run(cbm_context *ctx, long segs, double angle, cbm_bend_param param, double from,
                double to, long steps, cbm_bend_branch *br)
{
    run_m(ctx, segs, angle, param, from, to, steps, CBM_BEND_CONTINUE_NATURAL, false, br);
}

static const cbm_bend_fold *first(const cbm_bend_branch *b, bool fold)
{
    for (size_t i = 0; i < b->n_folds; i++)
        if (b->folds[i].fold == fold)
            return &b->folds[i];
    return NULL;
}

TEST(bend_continue_angle_fold_alpha15)
{
    cbm_context *ctx = test_ctx();
    /* the elastica's fold on the branch that starts hanging to the right (theta_base > 90) */
    cbm_elastica_piece pc = cbm_elastica_piece_default();
    pc.w0 = pc.w1 = 15;
    cbm_elastica_rod rod = cbm_elastica_rod_default();
    rod.pieces = &pc;
    rod.n_pieces = 1;
    cbm_elastica_scurve *sc = NULL;
    CHECK_OK(cbm_elastica_scurve_compute(ctx, &rod, NULL, &sc));
    const cbm_elastica_fold *ef = NULL;
    for (size_t k = 0; sc && k < sc->n_folds; k++)
        if (sc->folds[k].at.theta_base > PI / 2)
            ef = &sc->folds[k];
    CHECK(ef != NULL && ef->has_target);
    if (!ef || !ef->has_target) {
        cbm_elastica_scurve_destroy(ctx, sc);
        test_ctx_end(ctx);
        return;
    }
    double fold_deg = ef->at.theta_base * 180 / PI, L = rod_length(15);
    printf("elastica: fold %.6f deg, tip (%.5f, %.5f) L, jump target tip (%.5f, %.5f) L\n",
           fold_deg, ef->at.tip_x, ef->at.tip_y, ef->target.tip_x, ef->target.tip_y);
    double err[3];
    for (int k = 0; k < 3; k++) {
        long segs = 25L << k;
        cbm_bend_branch br;
        run(ctx, segs, 0, CBM_BEND_PARAM_ANGLE, 0, 150, 30, &br);
        const cbm_bend_fold *f = first(&br, true), *s = first(&br, false);
        CHECK(f != NULL && f->has_jump);
        err[k] = f ? fabs(f->at.param - fold_deg) : 1;
        if (f && f->has_jump) {
            double jx = f->jump.tip_x / L - ef->target.tip_x,
                   jy = f->jump.tip_y / L - ef->target.tip_y;
            printf("%ld segments: fold %.6f deg (elastica %.6f, error %.2e, bracket %.1e), "
                   "tip (%.5f, %.5f) L; jump to tip angle %.4f deg, tip error %.2e L\n",
                   segs, f->at.param, fold_deg, err[k], f->bracket, f->at.tip_x / L,
                   f->at.tip_y / L, f->jump.tip_angle_deg, hypot(jx, jy));
            CHECK(f->bracket < 1e-4);
            CHECK(hypot(f->at.tip_x / L - ef->at.tip_x, f->at.tip_y / L - ef->at.tip_y) < 2e-3);
            CHECK(hypot(jx, jy) < 2e-3); /* the elastica's jump target (hanging to the left) */
            CHECK_EQ_INT((long)f->jump.unstable_modes, 0);
            CHECK(f->jump.jumped);
        }
        /* before the fold, at exactly 90 degrees: the bent rod's plane can turn about the
         * vertical (an out-of-plane mode the planar elastica does not have) and past 90 the
         * rod is unstable to it; the count changes there, within O(h^2) */
        CHECK(s != NULL && s->at.param < (f ? f->at.param : 0));
        if (s)
            CHECK_MSG(fabs(s->at.param - 90) < 0.1, "stability change at %g", s->at.param);
        cbm_bend_branch_free(&br);
    }
    double o1 = log2(err[0] / err[1]), o2 = log2(err[1] / err[2]);
    printf("fold errors %.3e %.3e %.3e deg, orders %.2f %.2f\n", err[0], err[1], err[2], o1, o2);
    CHECK(err[2] < 0.005);
    CHECK_MSG(fabs(o1 - 2) < 0.3 && fabs(o2 - 2) < 0.3, "orders %g %g", o1, o2);
    cbm_elastica_scurve_destroy(ctx, sc);
    test_ctx_end(ctx);
}

TEST(bend_continue_gravity_greenhill)
{
    /* the vertical column of alpha = 15 at g = 9.81: alpha_c = 7.8373 at g_c = 9.81 * 7.8373 / 15
     * (Greenhill; the elastica family's bifurcation, docs/elastica.md) */
    cbm_context *ctx = test_ctx();
    cbm_bend_branch br;
    run(ctx, 50, 90, CBM_BEND_PARAM_GRAVITY, 4, 6, 10, &br);
    const cbm_bend_fold *s = first(&br, false);
    double gc = 9.81 * 7.8373 / 15;
    CHECK(s != NULL);
    if (s) {
        printf("stability lost at g = %.6f (Greenhill %.6f, rel. error %.2e), modes %zu -> %zu\n",
               s->at.param, gc, fabs(s->at.param / gc - 1), s->at.unstable_modes,
               br.n_points ? br.points[br.n_points - 1].unstable_modes : 0);
        CHECK(fabs(s->at.param / gc - 1) < 1e-3);
        CHECK_EQ_INT((long)s->at.unstable_modes, 0);
    }
    /* every point before the change is stable, and the lowest eigenvalue falls towards 0 */
    CHECK(br.n_points > 2 && br.points[0].lowest_eigenvalue > 0);
    if (s)
        CHECK(s->at.lowest_eigenvalue < 0.01 * br.points[0].lowest_eigenvalue);
    cbm_bend_branch_free(&br);
    test_ctx_end(ctx);
}

TEST(bend_continue_refuses)
{
    cbm_context *ctx = test_ctx();
    cbm_bend_spec sp = cbm_bend_spec_default();
    cbm_bend_continuation_def d = cbm_bend_continuation_def_default();
    cbm_bend_branch br;
    d.from = d.to = 10; /* empty range */
    CHECK(cbm_bend_continue(ctx, &sp, &d, &br) == CBM_E_INVALID);
    CHECK(br.n_points == 0 && br.points == NULL);
    d.to = 20;
    sp.solver = CBM_MECH_RELAX;
    CHECK(cbm_bend_continue(ctx, &sp, &d, &br) == CBM_E_INVALID);
    sp = cbm_bend_spec_default();
    d.param = CBM_BEND_PARAM_GRAVITY;
    d.from = -1;
    CHECK(cbm_bend_continue(ctx, &sp, &d, &br) == CBM_E_INVALID);
    d.from = 1;
    d.switch_branch = true;
    d.switch_at = -1;
    CHECK(cbm_bend_continue(ctx, &sp, &d, &br) == CBM_E_INVALID);
    test_ctx_end(ctx);
}

/* The elastica's base angle (degrees) of the equilibrium with the discrete point's tip angle,
 * for the rod of non-dimensional load alpha and tip force f (F L^2 / D): on the elastica's
 * S-curve the tip angle is the parameter, so this places the discrete equilibrium against the
 * continuous one, also on unstable arcs and at folds. *index: its Morse index; *slope:
 * d theta_base / d theta_tip. */
static double elastica_base_deg(cbm_context *ctx, double alpha, double f, double tip_deg,
                                int *index, double *slope)
{
    cbm_elastica_piece pc = cbm_elastica_piece_default();
    pc.w0 = pc.w1 = alpha;
    cbm_elastica_rod rod = cbm_elastica_rod_default();
    rod.pieces = &pc;
    rod.n_pieces = 1;
    rod.tip_force = f;
    cbm_elastica_state e;
    if (cbm_elastica_shoot(ctx, &rod, tip_deg * PI / 180, &e) != CBM_OK)
        return NAN;
    if (index)
        *index = e.index;
    if (slope)
        *slope = e.dbase_dtip;
    return e.theta_base * 180 / PI;
}

/* largest distance (degrees) of the branch's points (base angle, tip angle) from the elastica's
 * curve theta_base(theta_tip): |base angle - elastica's| / sqrt(1 + slope^2), well conditioned
 * at folds (slope 0) and for a hanging rod (slope large: it is then the tip angle's error);
 * the map gives a point's elastica loads and clamp angle (NaN: the parameter). *mismatch counts
 * the points whose stability disagrees (below). */
typedef struct load_map {
    double alpha_at_one, alpha_power, force_per_param; /* alpha = a1 param^p; f = fp param */
    double base_deg;                                   /* NaN: the parameter is the base angle */
} load_map;

static double branch_error(cbm_context *ctx, const cbm_bend_branch *br, size_t first,
                           const load_map *m, size_t *mismatch)
{
    double worst = 0;
    *mismatch = 0;
    for (size_t i = first; i < br->n_points; i++) {
        const cbm_bend_branch_point *q = &br->points[i];
        if (q->jumped)
            continue;
        double alpha = m->alpha_at_one * pow(q->param, m->alpha_power);
        int idx = 0;
        double slope = 0;
        double b = elastica_base_deg(ctx, alpha, m->force_per_param * q->param, q->tip_angle_deg,
                                     &idx, &slope);
        double want = isnan(m->base_deg) ? q->param : m->base_deg;
        double e = fabs(remainder(b - want, 360.0)) / sqrt(1 + slope * slope);
        worst = fmax(worst, isfinite(e) ? e : 1e9);
        /* an in-plane unstable elastica state is unstable in the discrete rod too, and a stable
         * one is stable unless the clamp leans past the vertical away from the side the rod
         * hangs to (then the discrete rod is unstable out of its plane, docs/bend.md); 0.5
         * degrees off the folds and 90 */
        bool near = fabs(want - 90) < 0.5;
        for (size_t k = 0; k < br->n_folds; k++)
            near = near || fabs(br->folds[k].at.param - q->param) < 0.5;
        if (!near && ((idx > 0 && q->unstable_modes == 0) ||
                      (idx == 0 && (q->tip_x > 0) == (want < 90) && q->unstable_modes != 0)))
            (*mismatch)++;
    }
    return worst;
}

TEST(bend_continue_arclength_scurve_alpha15)
{
    /* round both folds of the S-curve: every traced equilibrium on the elastica's curve */
    cbm_context *ctx = test_ctx();
    cbm_elastica_piece pc = cbm_elastica_piece_default();
    pc.w0 = pc.w1 = 15;
    cbm_elastica_rod rod = cbm_elastica_rod_default();
    rod.pieces = &pc;
    rod.n_pieces = 1;
    cbm_elastica_scurve *sc = NULL;
    CHECK_OK(cbm_elastica_scurve_compute(ctx, &rod, NULL, &sc));
    double efold[2] = {0, 0}; /* 116.4134, 63.5866 */
    for (size_t k = 0; sc && k < sc->n_folds; k++) {
        double a = sc->folds[k].at.theta_base * 180 / PI;
        a -= 360 * floor(a / 360);
        efold[a > 90 ? 0 : 1] = a;
    }
    cbm_elastica_scurve_destroy(ctx, sc);
    const load_map m = {15, 0, 0, NAN};
    double ferr[3][2];
    for (int k = 0; k < 3; k++) {
        long segs = 25L << k;
        cbm_bend_branch br;
        run_m(ctx, segs, 0, CBM_BEND_PARAM_ANGLE, 0, 150, 30, CBM_BEND_CONTINUE_ARCLENGTH, false,
              &br);
        CHECK(br.end == CBM_BEND_END_TO);
        CHECK(br.n_points > 0 && br.points[br.n_points - 1].param == 150);
        const cbm_bend_fold *f[2] = {NULL, NULL};
        size_t nf = 0, back = 0;
        for (size_t i = 0; i < br.n_folds; i++)
            if (br.folds[i].fold && nf < 2)
                f[nf++] = &br.folds[i];
        for (size_t i = 1; i < br.n_points; i++)
            back += br.points[i].param < br.points[i - 1].param;
        CHECK_EQ_INT((long)nf, 2);
        CHECK(back > 5); /* the unstable arc goes back in the angle */
        for (int j = 0; j < 2; j++) {
            ferr[k][j] = f[j] ? fabs(f[j]->at.param - efold[j]) : 1;
            if (f[j]) {
                CHECK(f[j]->bracket < 1e-4);
                CHECK(f[j]->has_jump && f[j]->jump.unstable_modes == 0);
            }
        }
        size_t mism = 0;
        double worst = branch_error(ctx, &br, 0, &m, &mism);
        printf("%ld segments: %zu equilibria, folds %.6f %.6f deg (elastica %.6f %.6f), largest "
               "base-angle error over the branch %.2e deg, stability mismatches %zu\n",
               segs, br.n_points, f[0] ? f[0]->at.param : NAN, f[1] ? f[1]->at.param : NAN,
               efold[0], efold[1], worst, mism);
        /* measured 3.19e-2, 7.98e-3, 1.99e-3 deg: O(h^2) */
        CHECK(worst < 0.048 / (double)(1 << (2 * k)));
        CHECK_EQ_INT((long)mism, 0);
        cbm_bend_branch_free(&br);
    }
    for (int j = 0; j < 2; j++) {
        double o1 = log2(ferr[0][j] / ferr[1][j]), o2 = log2(ferr[1][j] / ferr[2][j]);
        printf("fold %d: errors %.3e %.3e %.3e deg, orders %.2f %.2f\n", j, ferr[0][j], ferr[1][j],
               ferr[2][j], o1, o2);
        CHECK(ferr[2][j] < 0.005);
        CHECK_MSG(fabs(o1 - 2) < 0.3 && fabs(o2 - 2) < 0.3, "orders %g %g", o1, o2);
    }
    test_ctx_end(ctx);
}

TEST(bend_continue_switch_greenhill)
{
    /* the straight column past Greenhill's load: without the switch the branch stays straight
     * and unstable; with it the continuation leaves at the bifurcation onto the buckled branch,
     * whose every equilibrium is the elastica's at a vertical clamp (alpha = 15 g / 9.81) */
    cbm_context *ctx = test_ctx();
    double gc = 9.81 * 7.8373474 / 15;
    cbm_bend_branch br;
    run_m(ctx, 50, 90, CBM_BEND_PARAM_GRAVITY, 4, 15, 20, CBM_BEND_CONTINUE_ARCLENGTH, false, &br);
    const cbm_bend_fold *s = first(&br, false);
    CHECK(s != NULL && !s->switched);
    CHECK(br.n_points > 0 && br.points[br.n_points - 1].unstable_modes > 0 &&
          fabs(br.points[br.n_points - 1].tip_angle_deg - 90) < 1e-6);
    cbm_bend_branch_free(&br);
    run_m(ctx, 50, 90, CBM_BEND_PARAM_GRAVITY, 4, 15, 20, CBM_BEND_CONTINUE_ARCLENGTH, true, &br);
    s = first(&br, false);
    CHECK(s != NULL && s->switched);
    CHECK(first(&br, true) == NULL);
    CHECK(br.end == CBM_BEND_END_TO);
    if (s) {
        printf("switched at g = %.7f (Greenhill %.7f, rel. error %.2e, bracket %.1e)\n",
               s->at.param, gc, fabs(s->at.param / gc - 1), s->bracket);
        CHECK(fabs(s->at.param / gc - 1) < 1e-3);
        CHECK(s->bracket < 1e-5);
    }
    size_t k0 = 0;
    while (k0 < br.n_points && fabs(br.points[k0].tip_angle_deg - 90) < 1e-6)
        k0++;
    const load_map m = {15 / 9.81, 1, 0, 90};
    size_t mism = 0, unstable = 0;
    double worst = branch_error(ctx, &br, k0, &m, &mism);
    for (size_t i = k0; i < br.n_points; i++)
        unstable += br.points[i].unstable_modes > 0;
    const cbm_bend_branch_point *e = br.n_points ? &br.points[br.n_points - 1] : NULL;
    printf("buckled branch: %zu equilibria, largest distance from the elastica's curve %.2e deg, "
           "%zu unstable; at "
           "g = 15 tip angle %.4f deg\n",
           br.n_points - k0, worst, unstable, e ? e->tip_angle_deg : NAN);
    CHECK(br.n_points - k0 > 10);
    CHECK(worst < 0.015); /* measured 1.01e-2 deg at 50 segments */
    CHECK_EQ_INT((long)unstable, 0);
    CHECK(e && e->param == 15 && e->tip_angle_deg < 0);
    cbm_bend_branch_free(&br);
    test_ctx_end(ctx);
}

/* the elastica's k-th bifurcation of the straight heavy column in [lo, hi]: the load where
 * d theta_base / d theta_tip at the straight state (theta_tip = 90 deg) changes sign */
static double elastica_greenhill(cbm_context *ctx, double lo, double hi)
{
    double slo = 0, shi = 0;
    elastica_base_deg(ctx, lo, 0, 90, NULL, &slo);
    elastica_base_deg(ctx, hi, 0, 90, NULL, &shi);
    if (!(slo * shi < 0))
        return NAN;
    for (int it = 0; it < 60; it++) {
        double a = 0.5 * (lo + hi), sm = 0;
        elastica_base_deg(ctx, a, 0, 90, NULL, &sm);
        if ((sm < 0) == (slo < 0))
            lo = a;
        else
            hi = a;
    }
    return 0.5 * (lo + hi);
}

TEST(bend_continue_switch_second_greenhill)
{
    /* The second buckling load of the heavy column: the straight column swept in g from 4 to
     * 60 m/s^2 (alpha 6.1 to 91.7) meets two bifurcations; leaving at the second follows the
     * second buckling mode. Reference: the elastica's second bifurcation of the straight state
     * (alpha_2 = 55.97703 = (9/4) j^2, j = 4.98785323 the second zero of J_-1/3), and every
     * equilibrium of the new branch on the elastica's solutions at a vertical clamp, each
     * unstable in both (the second mode is a saddle). The discretisation error at 50 and 100
     * segments shows the order. */
    cbm_context *ctx = test_ctx();
    double a1 = elastica_greenhill(ctx, 7, 9), a2 = elastica_greenhill(ctx, 50, 60);
    printf("elastica: alpha_1 = %.7f, alpha_2 = %.7f\n", a1, a2);
    CHECK_NEAR(a1, 2.25 * 1.86635086 * 1.86635086, 1e-6);
    CHECK_NEAR(a2, 2.25 * 4.98785323 * 4.98785323, 1e-5);
    double err[2] = {NAN, NAN};
    const long segs[2] = {50, 100};
    for (int r = 0; r < 2; r++) {
        char t[256];
        snprintf(t, sizeof t,
                 "length = %.17g\nsegments = %ld\nradius = 0.01\nangle = 90\ntolerance = 1e-10\n",
                 rod_length(15), segs[r]);
        cbm_bend_spec sp;
        CHECK_OK(cbm_bend_spec_parse(ctx, t, strlen(t), "c.spec", &sp));
        cbm_bend_continuation_def d = cbm_bend_continuation_def_default();
        d.param = CBM_BEND_PARAM_GRAVITY;
        d.from = 4;
        d.to = 60;
        d.steps = 40;
        d.switch_branch = true;
        d.switch_at = 2;
        cbm_bend_branch br;
        CHECK_OK(cbm_bend_continue(ctx, &sp, &d, &br));
        const cbm_bend_fold *b1 = NULL, *b2 = NULL;
        for (size_t i = 0; i < br.n_folds; i++) {
            if (br.folds[i].bifurcation == 1)
                b1 = &br.folds[i];
            if (br.folds[i].bifurcation == 2)
                b2 = &br.folds[i];
        }
        CHECK(b1 && !b1->switched && b2 && b2->switched);
        CHECK(br.end == CBM_BEND_END_TO);
        if (!b1 || !b2) {
            cbm_bend_branch_free(&br);
            continue;
        }
        double g2 = 9.81 * a2 / 15;
        err[r] = fabs(b2->at.param / g2 - 1);
        size_t k0 = 0;
        while (k0 < br.n_points && br.points[k0].param <= b2->at.param)
            k0++;
        const load_map m = {15 / 9.81, 1, 0, 90};
        size_t mism = 0, saddle = 0, n = 0;
        double worst = branch_error(ctx, &br, k0, &m, &mism);
        for (size_t i = k0; i < br.n_points; i++) {
            const cbm_bend_branch_point *q = &br.points[i];
            int idx = 0;
            elastica_base_deg(ctx, 15 * q->param / 9.81, 0, q->tip_angle_deg, &idx, NULL);
            n++;
            saddle += q->unstable_modes > 0 && idx > 0;
        }
        printf("%ld segments: bifurcations at g = %.7f and %.7f (elastica %.7f, %.7f; errors "
               "%.2e, %.2e); mode-2 branch: %zu equilibria within %.2e deg of the elastica, "
               "%zu unstable in both\n",
               segs[r], b1->at.param, b2->at.param, 9.81 * a1 / 15, g2,
               fabs(b1->at.param / (9.81 * a1 / 15) - 1), err[r], n, worst, saddle);
        CHECK(n > 10);
        CHECK(worst < (r ? 0.04 : 0.15)); /* measured 1.17e-1, 2.93e-2 deg */
        CHECK_EQ_INT((long)saddle, (long)n);
        cbm_bend_branch_free(&br);
    }
    if (isfinite(err[0]) && isfinite(err[1])) {
        double order = log2(err[0] / err[1]);
        printf("second load: order %.2f\n", order);
        CHECK(err[1] < 5e-4);
        CHECK(fabs(order - 2) < 0.3);
    }
    test_ctx_end(ctx);
}

TEST(bend_continue_stability_count_honest)
{
    /* The count of unstable modes along a branch (docs/bend.md "Stability along a branch"): a
     * round column just past its buckling load has a lowest eigenvalue a hair below 0, and the
     * count must say so (2: the column may buckle in any plane), while the buckled states, whose
     * only non-positive eigenvalue is the zero mode of their turn about the vertical, count 0
     * and carry that mode as symmetry_mode. The bisection is pushed to 1e-12 of the range so
     * that the first state past the load has its eigenvalue in (-1e-9, 0). */
    cbm_context *ctx = test_ctx();
    char t[256];
    snprintf(t, sizeof t,
             "length = %.17g\nsegments = 50\nradius = 0.01\nangle = 90\ntolerance = 1e-10\n",
             rod_length(15));
    cbm_bend_spec sp;
    CHECK_OK(cbm_bend_spec_parse(ctx, t, strlen(t), "c.spec", &sp));
    cbm_bend_continuation_def d = cbm_bend_continuation_def_default();
    d.param = CBM_BEND_PARAM_GRAVITY;
    d.from = 4;
    d.to = 15;
    d.steps = 20;
    d.min_step = 1e-12;
    cbm_bend_branch br;
    CHECK_OK(cbm_bend_continue(ctx, &sp, &d, &br));
    const cbm_bend_fold *s = first(&br, false);
    CHECK(s != NULL);
    size_t k = 0;
    while (s && k < br.n_points &&
           !(br.points[k].param == s->at.param && br.points[k].unstable_modes == 0 &&
             k + 1 < br.n_points && br.points[k + 1].unstable_modes > 0))
        k++;
    CHECK(k + 1 < br.n_points);
    if (s && k + 1 < br.n_points) {
        const cbm_bend_branch_point *past = &br.points[k + 1];
        printf("past the load: g = %.12f, lowest eigenvalue %.3e, %zu unstable modes\n",
               past->param, past->lowest_eigenvalue, past->unstable_modes);
        CHECK(past->lowest_eigenvalue < 0 && past->lowest_eigenvalue > -1e-9);
        /* a double eigenvalue in exact arithmetic, split by rounding: 1 or 2 */
        CHECK(past->unstable_modes >= 1 && past->unstable_modes <= 2);
        CHECK(!past->symmetry_mode);
    }
    for (size_t i = 0; i < br.n_points; i++)
        CHECK(!br.points[i].symmetry_mode); /* a straight column: no circle of states */
    cbm_bend_branch_free(&br);
    d.min_step = 1e-7;
    d.switch_branch = true;
    CHECK_OK(cbm_bend_continue(ctx, &sp, &d, &br));
    size_t buckled = 0, sym = 0, unstable = 0;
    for (size_t i = 0; i < br.n_points; i++) {
        const cbm_bend_branch_point *q = &br.points[i];
        if (fabs(q->tip_angle_deg - 90) < 1e-3)
            continue;
        buckled++;
        sym += q->symmetry_mode;
        unstable += q->unstable_modes > 0;
        CHECK(q->lowest_eigenvalue > -1e-6); /* the zero mode is the lowest, to rounding */
    }
    printf("buckled: %zu states, %zu with the symmetry's zero mode, %zu counted unstable\n",
           buckled, sym, unstable);
    CHECK(buckled > 10);
    CHECK_EQ_INT((long)sym, (long)buckled);
    CHECK_EQ_INT((long)unstable, 0);
    cbm_bend_branch_free(&br);
    test_ctx_end(ctx);
}

TEST(bend_continue_arclength_params)
{
    /* density, tip load and length: each moves the elastica's load; every equilibrium of the
     * sweep at a horizontal clamp must be the elastica's */
    cbm_context *ctx = test_ctx();
    double L = rod_length(15), D = 1e10 * PI * 1e-8 / 4;
    struct {
        cbm_bend_param p;
        double from, to;
        load_map m;
    } cases[] = {
        {CBM_BEND_PARAM_DENSITY, 300, 900, {15.0 / 600, 1, 0, 0}},
        {CBM_BEND_PARAM_TIP_LOAD, 0, 50, {15, 0, L * L / D, 0}},
        {CBM_BEND_PARAM_LENGTH, 0.5 * L, 1.2 * L, {15 / (L * L * L), 3, 0, 0}},
    };
    for (int c = 0; c < 3; c++) {
        cbm_bend_branch br;
        run_m(ctx, 50, 0, cases[c].p, cases[c].from, cases[c].to, 10, CBM_BEND_CONTINUE_ARCLENGTH,
              false, &br);
        size_t mism = 0;
        double worst = branch_error(ctx, &br, 0, &cases[c].m, &mism);
        printf("param %d: %zu equilibria, largest distance from the elastica's curve %.2e deg\n", c,
               br.n_points, worst);
        CHECK(br.end == CBM_BEND_END_TO && br.n_points > 10);
        CHECK(worst < 0.01); /* measured 4.1e-3, 2.9e-3, 4.3e-3 deg at 50 segments */
        CHECK_EQ_INT((long)mism, 0);
        cbm_bend_branch_free(&br);
    }
    test_ctx_end(ctx);
}

/* ---- a branched plant (cbm_plant_continue) against the elastica's plant (Tresierras ch. 5) ----
 *
 * A planar Y: a stem of 0.5 L, its continuation of 0.5 L (the main axis, L = the alpha = 15
 * rod's length) and a lateral of 0.25 L at `Y_OFFSET` from the stem's tip tangent, all of the
 * rod's section (r 0.01 m, E 1e10, density 600). The lateral is turned in the plane: spun by 90
 * degrees about H (L, normal to the plane, goes to U), deviated, spun back. */
#define Y_OFFSET (40.0 * PI / 180)

static cbm_plant *y_plant(cbm_context *ctx, long per_l, double angle_deg)
{
    cbm_plant_def pd = cbm_plant_def_default();
    pd.base_orientation = cbm_mech_clamp_orientation(angle_deg * PI / 180);
    cbm_plant *p = NULL;
    CHECK_OK(cbm_plant_create(ctx, &pd, &p));
    if (!p)
        return NULL;
    double L = rod_length(15), h = L / (double)per_l;
    long ns = per_l / 2, nl = per_l / 4;
    int64_t prev = -1;
    for (long k = 0; k < 2 * ns; k++) { /* the main axis: stem then continuation */
        cbm_segment_def d = cbm_segment_def_default();
        d.parent = prev;
        d.length = h;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
        prev++;
    }
    prev = ns - 1; /* the stem's tip */
    for (long k = 0; k < nl; k++) {
        cbm_segment_def d = cbm_segment_def_default();
        d.parent = prev;
        d.length = h;
        if (k == 0) {
            d.divergence = PI / 2;
            d.deviation = Y_OFFSET;
            d.roll = -PI / 2;
            d.lateral = true;
        }
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
        prev = (int64_t)cbm_plant_segment_count(p) - 1;
    }
    return p;
}

static cbm_status y_elastica(cbm_context *ctx, double theta_base, cbm_elastica_plant_state **ps,
                             size_t *n)
{
    double L = rod_length(15), D = 1e10 * PI * 1e-8 / 4, w = 600 * 9.81 * PI * 1e-4;
    cbm_elastica_piece half = cbm_elastica_piece_default(), lat;
    half.length = 0.5 * L, half.D0 = half.D1 = D, half.w0 = half.w1 = w;
    lat = half;
    lat.length = 0.25 * L;
    cbm_elastica_branch b[3];
    memset(b, 0, sizeof b);
    b[0].parent = -1, b[0].pieces = &half, b[0].n_pieces = 1;
    b[1].parent = 0, b[1].pieces = &half, b[1].n_pieces = 1;
    b[2].parent = 0, b[2].offset = Y_OFFSET, b[2].pieces = &lat, b[2].n_pieces = 1;
    cbm_elastica_plant_def d = cbm_elastica_plant_def_default();
    return cbm_elastica_plant_equilibria(ctx, b, 3, &d, theta_base, ps, n);
}

/* the number of the elastica Y's equilibria at a base angle (degrees) */
static size_t y_count(cbm_context *ctx, double deg)
{
    cbm_elastica_plant_state *ps = NULL;
    size_t n = 0;
    CHECK_OK(y_elastica(ctx, deg * PI / 180, &ps, &n));
    cbm_elastica_plant_states_destroy(ctx, ps, n, 3);
    return n;
}

static double wrap180(double a)
{
    return a - 360.0 * round(a / 360.0);
}

/* The Y swept in base angle from 90 degrees (hanging left, stable) down to 10: the branch folds
 * and comes back to 90 on its unstable arc. Both equilibria met at 90 lie on the elastica's
 * (main axis tip angle, to O(h): three resolutions), stable iff the elastica's is; the fold lies
 * where the elastica's composite S-curve has one (two of its equilibria merge: the count drops by
 * 2). */
TEST(plant_continue_y_elastica)
{
    cbm_context *ctx = test_ctx();
    cbm_elastica_plant_state *ps = NULL;
    size_t ne = 0;
    CHECK_OK(y_elastica(ctx, PI / 2, &ps, &ne));
    CHECK_EQ_INT((long)ne, 3);
    /* the elastica's fold: bisection on the count of equilibria */
    double lo = 40, hi = 50;
    size_t nlo = y_count(ctx, lo), nhi = y_count(ctx, hi);
    CHECK(nhi == nlo + 2);
    for (int k = 0; k < 24 && nhi == nlo + 2; k++) {
        double m = 0.5 * (lo + hi);
        if (y_count(ctx, m) == nhi)
            hi = m;
        else
            lo = m;
    }
    double efold = 0.5 * (lo + hi);
    printf("elastica Y: %zu equilibria at 90 deg; fold at %.6f deg (bracket %.1e)\n", ne, efold,
           hi - lo);
    double tip_err[3] = {1, 1, 1}, fold_err[3] = {1, 1, 1};
    for (int r = 0; r < 3; r++) {
        long per_l = 40L << r;
        cbm_plant *p = y_plant(ctx, per_l, 90);
        if (!p)
            break;
        cbm_plant_continuation_def d = cbm_plant_continuation_def_default();
        d.cont.from = 90;
        d.cont.to = 10;
        d.cont.steps = 40;
        d.solve.tolerance = 1e-10;
        d.solve.push_unstable = true; /* start on a stable state */
        cbm_bend_branch br;
        CHECK_OK(cbm_plant_continue(ctx, p, &d, &br));
        CHECK_EQ_INT((long)br.end, (long)CBM_BEND_END_FROM);
        CHECK(br.n_points > 2 && br.points[0].unstable_modes == 0);
        double worst = 0.0;
        int at90 = 0;
        for (size_t i = 0; i < br.n_points; i++) {
            const cbm_bend_branch_point *q = &br.points[i];
            if (q->param != 90.0)
                continue;
            at90++;
            size_t best = 0;
            double e = INFINITY;
            for (size_t k = 0; k < ne; k++) {
                double ek = fabs(wrap180(q->tip_angle_deg - ps[k].theta_tip[1] * 180 / PI));
                if (ek < e)
                    e = ek, best = k;
            }
            worst = fmax(worst, e);
            printf("%ld per L: at 90 deg main tip %.5f deg (elastica %.5f, error %.2e), unstable "
                   "modes %zu (elastica planar index %d)\n",
                   per_l, q->tip_angle_deg, ps[best].theta_tip[1] * 180 / PI, e, q->unstable_modes,
                   ps[best].index);
            CHECK((q->unstable_modes == 0) == (ps[best].index == 0));
        }
        CHECK_EQ_INT(at90, 2);
        const cbm_bend_fold *f = first(&br, true), *s = first(&br, false);
        CHECK(f != NULL && f->has_jump);
        /* the bent plant's plane can turn about the vertical: the 3-D count gains the
         * out-of-plane mode, without a fold, before the fold (the rod's does at 90 degrees) */
        CHECK(s != NULL && f != NULL && s->at.param > f->at.param);
        if (f)
            printf("%ld per L: fold at %.6f deg (elastica %.6f, error %.2e), jump to main tip "
                   "%.4f deg (stable: %d)\n",
                   per_l, f->at.param, efold, fabs(f->at.param - efold), f->jump.tip_angle_deg,
                   f->jump.unstable_modes == 0);
        if (f && f->has_jump)
            CHECK_EQ_INT((long)f->jump.unstable_modes, 0);
        tip_err[r] = worst;
        fold_err[r] = f ? fabs(f->at.param - efold) : 1;
        cbm_bend_branch_free(&br);
        cbm_plant_destroy(p);
    }
    double ot1 = log2(tip_err[0] / tip_err[1]), ot2 = log2(tip_err[1] / tip_err[2]);
    double of1 = log2(fold_err[0] / fold_err[1]), of2 = log2(fold_err[1] / fold_err[2]);
    printf("Y: tip errors %.3e %.3e %.3e deg (orders %.2f %.2f), fold errors %.3e %.3e %.3e deg "
           "(orders %.2f %.2f)\n",
           tip_err[0], tip_err[1], tip_err[2], ot1, ot2, fold_err[0], fold_err[1], fold_err[2], of1,
           of2);
    CHECK(tip_err[2] < 0.03 && fold_err[2] < 0.02);
    /* FIRST order, not the single rod's second: the error is O(h) at the branch point
     * (docs/validation.md "Folds of a branched discrete plant"). The test fails if the order
     * changes either way. */
    CHECK_MSG(fabs(ot1 - 1) < 0.25 && fabs(ot2 - 1) < 0.25, "tip orders %g %g", ot1, ot2);
    CHECK_MSG(fabs(of1 - 1) < 0.25 && fabs(of2 - 1) < 0.25, "fold orders %g %g", of1, of2);
    cbm_elastica_plant_states_destroy(ctx, ps, ne, 3);
    test_ctx_end(ctx);
}

TEST(plant_continue_errors)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = y_plant(ctx, 8, 90);
    if (!p) {
        test_ctx_end(ctx);
        return;
    }
    /* the default tip is the main axis's: the stem's continuation, not the lateral added last */
    CHECK_EQ_INT((long)cbm_plant_main_tip(p), 7);
    cbm_plant_continuation_def d = cbm_plant_continuation_def_default();
    CHECK(d.tip_segment == SIZE_MAX && d.length == 0 && d.solve.solver == CBM_MECH_NEWTON);
    CHECK(d.cont.method == CBM_BEND_CONTINUE_ARCLENGTH && d.cont.param == CBM_BEND_PARAM_ANGLE);
    d.cont.from = 90;
    d.cont.to = 80;
    cbm_bend_branch br;
    cbm_plant_continuation_def bad = d;
    bad.cont.param = CBM_BEND_PARAM_DENSITY; /* a bend spec's parameter */
    CHECK(cbm_plant_continue(ctx, p, &bad, &br) == CBM_E_INVALID);
    bad = d;
    bad.tip_segment = 10; /* 8 + 2 segments: 0 .. 9 */
    CHECK(cbm_plant_continue(ctx, p, &bad, &br) == CBM_E_INVALID);
    bad = d;
    bad.solve.solver = CBM_MECH_RELAX;
    CHECK(cbm_plant_continue(ctx, p, &bad, &br) == CBM_E_INVALID);
    bad = d;
    bad.cont.to = bad.cont.from;
    CHECK(cbm_plant_continue(ctx, p, &bad, &br) == CBM_E_INVALID);
    CHECK(br.n_points == 0 && br.points == NULL);
    /* a second root: two clamps */
    cbm_segment_def sd = cbm_segment_def_default();
    CHECK_OK(cbm_plant_add_segment(p, &sd, NULL));
    CHECK(cbm_plant_continue(ctx, p, &d, &br) == CBM_E_INVALID);
    cbm_context_clear_errors(ctx);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}
