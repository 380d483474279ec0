/* Continuation of bend's rod in a parameter (docs/bend.md "Continuation", docs/validation.md
 * "Folds of the discrete rod"): the heavy rod at alpha = 15 swept in base angle from 0 degrees
 * (one equilibrium, hanging to the right) towards 150 loses its branch at a fold, which must lie
 * on the elastica's fold (cbm_elastica_scurve_compute, 116.4134 degrees) within a tolerance that
 * shrinks at second order as the segments are refined; the rod must jump to the elastica's jump
 * target. Under a gravity sweep the vertical column loses its stability at Greenhill's load. */
#include "test.h"

#include <string.h>

#define PI 3.14159265358979323846

/* L of the spec's rod (r 0.01 m, E 1e10, density 600) for alpha = rho g L^3 / D at g = 9.81 */
static double rod_length(double alpha)
{
    double I = PI * 1e-8 / 4, w = 600 * PI * 1e-4 * 9.81;
    return cbrt(alpha * 1e10 * I / w);
}

static void run(cbm_context *ctx, long segs, double angle, cbm_bend_param param, double from,
                double to, long steps, cbm_bend_branch *br)
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
    CHECK_OK(cbm_bend_continue(ctx, &sp, &d, br));
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
    test_ctx_end(ctx);
}
