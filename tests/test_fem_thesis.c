/* Gürtler's FE branch as his listing computes it (cambium/fem_thesis.h, src/mech/fem_thesis.c):
 * the digest's independent re-computation of the listing (digest 001 §2.2.6, a Python transcript
 * with numpy's SVD) in the printed, clamped-lifting and clamped-sagging variants; the zero-load
 * identities the thesis reports (grav = 0 and t0 = 180 degrees leave the branch as it was); the
 * free-free pseudo-inverse against the clamped solve where they must agree (a self-equilibrated
 * load: the two differ by a rigid motion) and where they must not (the weight: the pseudo-inverse
 * drops its resultant); the planar split of the SVD against the whole one. docs/validation.md,
 * "The thesis-compatible FE path", has the tolerances and measurements. */
#include "test.h"

#include "cambium/bend.h"
#include "cambium/fem_thesis.h"
#include "mech/fem_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

static void check_row(const double *got, const double *want, int n, const char *what)
{
    /* the digest prints two decimals */
    for (int i = 0; i < n; i++)
        CHECK_MSG(fabs(got[i] - want[i]) <= 0.005 + 1e-9, "%s: element %d: %.4f, digest %.2f", what,
                  i, got[i], want[i]);
}

TEST(fem_thesis_digest_rows)
{
    cbm_context *ctx = test_ctx();
    double beta[10];
    cbm_fem_thesis_info in;
    /* as printed: free-free, K(4,8) = 0, beta += theta_y; n_FE 10, Le 0.1, r 0.05, rho 2, E 800,
     * grav 9.81, t0 60 */
    cbm_fem_thesis_def d = cbm_fem_thesis_def_default();
    static const double printed[10] = {59.95, 59.88, 59.99, 60.16, 60.31,
                                       60.43, 60.53, 60.61, 60.68, 60.74};
    CHECK_OK(cbm_fem_thesis_angles(ctx, &d, beta, 10, &in));
    check_row(beta, printed, 10, "as printed");
    printf("as printed: tip %.4f deg, %ld singular values cut, smallest kept %.3g, dropped load "
           "%.3f of |dF|\n",
           in.tip_angle, in.rank_deficiency, in.smallest_kept, in.residual);
    /* the printed matrix loses one null vector of the free-free element (its missing entry
     * makes the z translation of a node strain the rotation row): 5, not 6 */
    CHECK_EQ_INT(in.rank_deficiency, 5);
    d.grav = 20.0;
    CHECK_OK(cbm_fem_thesis_angles(ctx, &d, beta, 10, &in));
    CHECK_NEAR(in.tip_angle, 61.52, 0.005 + 1e-9);
    /* no load, or a hanging branch: nothing moves (the thesis's error 0 at grav 0 and t0 180) */
    d.grav = 0.0;
    CHECK_OK(cbm_fem_thesis_angles(ctx, &d, beta, 10, &in));
    for (int i = 0; i < 10; i++)
        CHECK_NEAR(beta[i], 60.0, 1e-12);
    d.grav = 9.81;
    d.t0 = 180.0;
    CHECK_OK(cbm_fem_thesis_angles(ctx, &d, beta, 10, &in));
    for (int i = 0; i < 10; i++)
        CHECK_NEAR(beta[i], 180.0, 1e-9);
    /* clamped, symmetric: the listing's += lifts the branch (D4), -= sags it past the vertical */
    d = cbm_fem_thesis_def_default();
    d.support = CBM_FEM_SUPPORT_CLAMPED;
    d.printed_stiffness = false;
    static const double lift[10] = {60.0,  25.89, 7.29,  -1.25, -3.98,
                                    -3.83, -2.74, -1.77, -1.28, -1.15};
    CHECK_OK(cbm_fem_thesis_angles(ctx, &d, beta, 10, &in));
    check_row(beta, lift, 10, "clamped +=");
    CHECK_NEAR(beta[0], 60.0, 1e-12); /* the base element's first node is the clamp (D8) */
    d.update_sign = -1;
    static const double sag[10] = {60.0,   115.63, 153.01, 174.59, 184.84,
                                   187.95, 187.28, 185.50, 184.26, 183.87};
    CHECK_OK(cbm_fem_thesis_angles(ctx, &d, beta, 10, &in));
    check_row(beta, sag, 10, "clamped -=");
    CHECK(in.residual < 1e-10);
    d.youngs_modulus = 8000.0;
    CHECK_OK(cbm_fem_thesis_angles(ctx, &d, beta, 10, &in));
    CHECK_NEAR(in.tip_angle, 94.97, 0.005 + 1e-9);
    d.youngs_modulus = 80000.0;
    CHECK_OK(cbm_fem_thesis_angles(ctx, &d, beta, 10, &in));
    CHECK_NEAR(in.tip_angle, 63.25, 0.005 + 1e-9);
    /* the symmetric free-free matrix has the six rigid-body modes as its null space */
    d = cbm_fem_thesis_def_default();
    d.printed_stiffness = false;
    CHECK_OK(cbm_fem_thesis_angles(ctx, &d, beta, 10, &in));
    CHECK_EQ_INT(in.rank_deficiency, 6);
    test_ctx_end(ctx);
}

/* The dense system of an m-element chain at the given angles (the rings of the last step). */
typedef struct sys {
    size_t m, n;
    double rad[16], s2[16], s4[16];
    double beta[8], k[48 * 48], f[48];
} sys;

static void build(sys *s, const cbm_fem_thesis_def *d, size_t m)
{
    s->m = m;
    s->n = 6 * (m + 1);
    double dr = (d->r_start - d->r_end) / (double)(d->n_fe - 1);
    s->rad[0] = 0.0;
    s->rad[1] = d->r_end;
    for (size_t k = 2; k < 16; k++)
        s->rad[k] = s->rad[k - 1] + dr;
    s->s2[0] = s->s4[0] = 0.0;
    for (size_t k = 1; k < 16; k++) {
        double a = s->rad[k] * s->rad[k], b = s->rad[k - 1] * s->rad[k - 1];
        s->s2[k] = s->s2[k - 1] + a - b;
        s->s4[k] = s->s4[k - 1] + a * a - b * b;
    }
    for (size_t i = 0; i < m; i++)
        s->beta[i] = (60.0 + 17.0 * (double)i) * 3.14159265358979323846 / 180.0;
    cbm__fem_thesis_system(d, m, s->beta, s->rad, s->s2, s->s4, s->k, s->f);
}

/* Under a self-equilibrated load (the maturation strain alone) the pseudo-inverse solution is the
 * clamped one minus its rigid-motion part: the two differ by one translation t and one rotation
 * w, the same at every node (u_i = t + w x X_i, theta_i = w). */
TEST(fem_thesis_free_agrees_with_clamped_when_self_equilibrated)
{
    cbm_context *ctx = test_ctx();
    cbm_fem_thesis_def d = cbm_fem_thesis_def_default();
    d.printed_stiffness = false;
    d.grav = 0.0;
    d.sigma = 1e-4;
    d.r_start = 0.08;
    d.axial = CBM_FEM_AXIAL_FORMULA;
    static sys s;
    build(&s, &d, 6);
    double xf[48], xc[48];
    cbm__fem_pinv_info pi;
    CHECK_OK(cbm__fem_pinv_solve_planar(ctx, s.n, s.k, s.f, xf, &pi));
    CHECK_OK(cbm__fem_clamped_solve(ctx, s.n, s.k, s.f, xc));
    CHECK_EQ_INT(pi.dropped, 6);
    /* node positions: x up, z horizontal in the plane */
    double px[8] = {0}, pz[8] = {0}, scale = 0.0;
    for (size_t i = 0; i < s.m; i++) {
        px[i + 1] = px[i] + d.le * cos(s.beta[i]);
        pz[i + 1] = pz[i] + d.le * sin(s.beta[i]);
    }
    for (size_t i = 0; i < s.n; i++)
        scale = fmax(scale, fabs(xc[i]));
    CHECK(scale > 0.0);
    double dd[48] = {0};
    for (size_t i = 0; i < s.n; i++)
        dd[i] = xf[i] - xc[i];
    /* the rigid motion from node 0: t = dd[0..2], w = dd[3..5] */
    double worst = 0.0;
    for (size_t nd = 0; nd <= s.m; nd++) {
        const double *t = dd, *w = dd + 3, *g = dd + 6 * nd;
        double rx = px[nd] - px[0], ry = 0.0, rz = pz[nd] - pz[0];
        double want[6] = {t[0] + w[1] * rz - w[2] * ry,
                          t[1] + w[2] * rx - w[0] * rz,
                          t[2] + w[0] * ry - w[1] * rx,
                          w[0],
                          w[1],
                          w[2]};
        for (int k = 0; k < 6; k++)
            worst = fmax(worst, fabs(g[k] - want[k]));
    }
    printf("free - clamped: rigid to %.3g of the largest DOF (%.3g)\n", worst / scale, scale);
    CHECK(worst <= 1e-9 * scale);
    /* and the load is met exactly: nothing dropped */
    double r2 = 0.0, f2 = 0.0;
    for (size_t i = 0; i < s.n; i++) {
        double t = -s.f[i];
        for (size_t k = 0; k < s.n; k++)
            t += s.k[i * s.n + k] * xf[k];
        r2 += t * t;
        f2 += s.f[i] * s.f[i];
    }
    CHECK(sqrt(r2 / f2) < 1e-9);
    test_ctx_end(ctx);
}

/* The weight has a resultant, which no free-free displacement can balance: the pseudo-inverse
 * answers the load minus its projection on the rigid modes, so its nodal forces sum to zero where
 * the weight's sum to -W. This is why the listing's branches barely bend (digest D3). */
TEST(fem_thesis_free_drops_the_weight_resultant)
{
    cbm_context *ctx = test_ctx();
    cbm_fem_thesis_def d = cbm_fem_thesis_def_default();
    d.printed_stiffness = false;
    static sys s;
    build(&s, &d, 5);
    double x[48];
    CHECK_OK(cbm__fem_pinv_solve_planar(ctx, s.n, s.k, s.f, x, NULL));
    double fx = 0.0, fz = 0.0, kx = 0.0, kz = 0.0;
    for (size_t nd = 0; nd <= s.m; nd++) {
        fx += s.f[6 * nd];
        fz += s.f[6 * nd + 2];
        for (size_t k = 0; k < s.n; k++) {
            kx += s.k[6 * nd * s.n + k] * x[k];
            kz += s.k[(6 * nd + 2) * s.n + k] * x[k];
        }
    }
    /* the weight of the rings present in the last step, downward (-x) */
    double w = 0.0;
    for (size_t i = 0; i < s.m; i++) {
        size_t nr = s.m - i;
        w += d.rho * d.grav * d.le * 3.14159265358979323846 *
             (s.rad[nr] * s.rad[nr] - s.rad[nr - 1] * s.rad[nr - 1]);
    }
    printf("weight %.6g, load sum (%.6g, %.3g), answered (%.3g, %.3g)\n", w, fx, fz, kx, kz);
    CHECK_REL(-fx, w, 1e-12);
    CHECK(fabs(fz) <= 1e-12 * w);
    CHECK(fabs(kx) <= 1e-9 * w && fabs(kz) <= 1e-9 * w);
    test_ctx_end(ctx);
}

/* The planar split is the same pseudo-inverse as one SVD of the whole matrix (also for the
 * printed, unsymmetric one). */
TEST(fem_thesis_planar_split_is_the_whole_svd)
{
    cbm_context *ctx = test_ctx();
    for (int printed = 0; printed < 2; printed++) {
        cbm_fem_thesis_def d = cbm_fem_thesis_def_default();
        d.printed_stiffness = printed != 0;
        d.sigma = 1e-5;
        d.r_start = 0.09;
        static sys s;
        build(&s, &d, 7);
        double xa[48], xb[48], scale = 0.0, diff = 0.0;
        cbm__fem_pinv_info ia, ib;
        CHECK_OK(cbm__fem_pinv_solve(ctx, s.n, s.k, s.f, xa, &ia));
        CHECK_OK(cbm__fem_pinv_solve_planar(ctx, s.n, s.k, s.f, xb, &ib));
        for (size_t i = 0; i < s.n; i++) {
            scale = fmax(scale, fabs(xa[i]));
            diff = fmax(diff, fabs(xa[i] - xb[i]));
        }
        printf(
            "printed %d: whole SVD %ld cut (%ld sweeps), split %ld cut; differ by %.3g of %.3g\n",
            printed, ia.dropped, ia.sweeps, ib.dropped, diff, scale);
        CHECK_EQ_INT(ia.dropped, ib.dropped);
        CHECK(diff <= 1e-9 * scale);
    }
    test_ctx_end(ctx);
}

TEST(fem_thesis_bad_input)
{
    cbm_context *ctx = test_ctx();
    double beta[10];
    cbm_fem_thesis_def d = cbm_fem_thesis_def_default();
    d.n_fe = 1;
    CHECK_STATUS(cbm_fem_thesis_angles(ctx, &d, beta, 10, NULL), CBM_E_INVALID);
    d = cbm_fem_thesis_def_default();
    d.r_start = 0.01; /* below r_end */
    CHECK_STATUS(cbm_fem_thesis_angles(ctx, &d, beta, 10, NULL), CBM_E_INVALID);
    d = cbm_fem_thesis_def_default();
    d.update_sign = 0;
    CHECK_STATUS(cbm_fem_thesis_angles(ctx, &d, beta, 10, NULL), CBM_E_INVALID);
    d = cbm_fem_thesis_def_default();
    d.t0 = NAN;
    CHECK_STATUS(cbm_fem_thesis_angles(ctx, &d, beta, 10, NULL), CBM_E_INVALID);
    d = cbm_fem_thesis_def_default();
    CHECK_STATUS(cbm_fem_thesis_angles(ctx, &d, beta, 9, NULL), CBM_E_INVALID);
    double extra[10] = {0, 0, -1};
    d.extra_loads = extra;
    CHECK_STATUS(cbm_fem_thesis_angles(ctx, &d, beta, 10, NULL), CBM_E_INVALID);
    cbm_fem_support sp;
    CHECK(cbm_fem_support_parse("clamped", &sp) && sp == CBM_FEM_SUPPORT_CLAMPED);
    CHECK(!cbm_fem_support_parse("pinned", &sp));
    CHECK(strcmp(cbm_fem_support_name(CBM_FEM_SUPPORT_FREE), "free") == 0);
    test_ctx_end(ctx);
}

/* The out-of-memory loop over both supports: every allocation failure is reported and releases
 * every byte. */
static cbm_status oom_run(cbm_context *ctx, void *ud)
{
    (void)ud;
    double beta[6];
    cbm_fem_thesis_def d = cbm_fem_thesis_def_default();
    d.n_fe = 6;
    CBM_TRY(cbm_fem_thesis_angles(ctx, &d, beta, 6, NULL));
    d.support = CBM_FEM_SUPPORT_CLAMPED;
    return cbm_fem_thesis_angles(ctx, &d, beta, 6, NULL);
}

/* Extra loads (D1: element i feels (steps it exists) / n_FE of its mass): a mass on every element
 * bends the sagging clamped branch further down. */
TEST(fem_thesis_extra_loads_and_oom)
{
    cbm_context *ctx = test_ctx();
    cbm_fem_thesis_def d = cbm_fem_thesis_def_default();
    d.support = CBM_FEM_SUPPORT_CLAMPED;
    d.printed_stiffness = false;
    d.update_sign = -1;
    d.youngs_modulus = 8000.0;
    double b0[10], b1[10], extra[10];
    CHECK_OK(cbm_fem_thesis_angles(ctx, &d, b0, 10, NULL));
    for (int i = 0; i < 10; i++)
        extra[i] = 0.01;
    d.extra_loads = extra;
    CHECK_OK(cbm_fem_thesis_angles(ctx, &d, b1, 10, NULL));
    printf("tip without extra load %.3f, with 0.01 per element %.3f\n", b0[9], b1[9]);
    CHECK(b1[9] > b0[9] + 1.0);
    test_ctx_end(ctx);
    CHECK(test_oom_loop(oom_run, NULL) > 2);
}

/* ---- the output step: Akima's interpolation, the resampling, the `bend` path ---- */

TEST(fem_thesis_akima_closed_forms)
{
    cbm_context *ctx = test_ctx();
    /* a straight line on uneven abscissae: exact (every chord slope the same, the weights 0) */
    double x[24], y[24], xq[200], yq[200];
    for (int i = 0; i < 12; i++) {
        x[i] = 0.3 * i + 0.07 * (i % 3);
        y[i] = 2.5 - 1.75 * x[i];
    }
    for (int j = 0; j < 200; j++)
        xq[j] = -0.2 + 3.6 * j / 199.0; /* past both ends too: the end cubics continued */
    CHECK_OK(cbm_akima(ctx, x, y, 12, xq, yq, 200));
    for (int j = 0; j < 200; j++)
        CHECK_NEAR(yq[j], 2.5 - 1.75 * xq[j], 1e-13);
    /* at the data points the curve passes through the data */
    for (int i = 0; i < 12; i++)
        y[i] = sin(3.0 * x[i]);
    CHECK_OK(cbm_akima(ctx, x, y, 12, x, yq, 12));
    for (int i = 0; i < 12; i++)
        CHECK_NEAR(yq[i], y[i], 1e-15);
    /* a cubic, y = x^3 on [0, 1]: Akima's interior slopes are O(h^2) wrong in general (Akima
     * 1970), so the bound asked is h^2 / 4 and a ratio of at least 3.5 per halving of h; measured
     * 0.0031, 0.00038, 0.000048 at n 6, 11, 21 (a ratio of 8 on this smooth cubic) */
    double err[3];
    int ns[3] = {6, 11, 21};
    for (int c = 0; c < 3; c++) {
        int n = ns[c];
        for (int i = 0; i < n; i++) {
            x[i] = (double)i / (n - 1);
            y[i] = x[i] * x[i] * x[i];
        }
        for (int j = 0; j < 200; j++)
            xq[j] = j / 199.0;
        CHECK_OK(cbm_akima(ctx, x, y, (size_t)n, xq, yq, 200));
        double h = 1.0 / (n - 1), e = 0;
        for (int j = 0; j < 200; j++)
            e = fmax(e, fabs(yq[j] - xq[j] * xq[j] * xq[j]));
        err[c] = e;
        printf("akima on x^3, n %d: max error %.3g (h^2/4 = %.3g)\n", n, e, h * h / 4);
        CHECK(e <= h * h / 4);
    }
    CHECK(err[0] / err[1] >= 3.5 && err[1] / err[2] >= 3.5);
    /* a step: no overshoot, flat beside it, monotone across */
    for (int i = 0; i < 10; i++) {
        x[i] = i;
        y[i] = i < 5 ? 0.0 : 1.0;
    }
    for (int j = 0; j < 200; j++)
        xq[j] = 9.0 * j / 199.0;
    CHECK_OK(cbm_akima(ctx, x, y, 10, xq, yq, 200));
    for (int j = 0; j < 200; j++) {
        if (xq[j] <= 4.0)
            CHECK_NEAR(yq[j], 0.0, 0);
        else if (xq[j] >= 5.0)
            CHECK_NEAR(yq[j], 1.0, 0);
        else
            CHECK(yq[j] >= yq[j - 1] && yq[j] <= 1.0);
    }
    /* bad input */
    CHECK_STATUS(cbm_akima(ctx, x, y, 4, xq, yq, 1), CBM_E_INVALID);
    x[3] = x[2];
    CHECK_STATUS(cbm_akima(ctx, x, y, 10, xq, yq, 1), CBM_E_INVALID);
    test_ctx_end(ctx);
}

TEST(fem_thesis_resample)
{
    cbm_context *ctx = test_ctx();
    cbm_fem_thesis_def d = cbm_fem_thesis_def_default();
    double beta[10], a[10], b[37];
    CHECK_OK(cbm_fem_thesis_angles(ctx, &d, beta, 10, NULL));
    /* n_GU = n_FE: the angles themselves (the thesis's interpolation "off") */
    CHECK_OK(cbm_fem_thesis_resample(ctx, beta, 10, a, 10));
    for (int i = 0; i < 10; i++)
        CHECK_NEAR(a[i], beta[i], 1e-12);
    /* n_GU = 37 = 4 (n_FE - 1) + 1: every 4th output is an element's angle */
    CHECK_OK(cbm_fem_thesis_resample(ctx, beta, 10, b, 37));
    for (int i = 0; i < 10; i++)
        CHECK_NEAR(b[4 * i], beta[i], 1e-12);
    CHECK_STATUS(cbm_fem_thesis_resample(ctx, beta, 10, b, 9), CBM_E_INVALID);
    CHECK_STATUS(cbm_fem_thesis_resample(ctx, beta, 4, b, 9), CBM_E_INVALID);
    test_ctx_end(ctx);
}

/* Elevation of segment i's axis above the horizontal, degrees, in the x-y plane (past the
 * vertical: above 90). */
static double seg_elevation(const cbm_plant *p, size_t i)
{
    cbm_segment_state ss;
    if (cbm_plant_segment(p, i, &ss) != CBM_OK)
        return NAN;
    return atan2(ss.frame.h.y, ss.frame.h.x) * 180.0 / 3.14159265358979323846;
}

TEST(fem_thesis_bend_path_equals_api)
{
    cbm_context *ctx = test_ctx();
    /* the digest's branch (n_FE 10, Le 0.1, r 0.05, rho 2, E 800, t0 60) as a `bend` spec, in
     * both supports and update signs, resampled to 40 growth units */
    static const char *const variants[] = {"", "fem_support = clamped\nfem_stiffness = symmetric\n",
                                           ("fem_support = clamped\nfem_stiffness = symmetric\n"
                                            "fem_update = sagging\nfem_primary_tropism = 1\n")};
    for (int v = 0; v < 3; v++) {
        char text[512];
        snprintf(text, sizeof text,
                 "length = 1\nsegments = 40\nradius_base = 0.05\nradius_tip = 0.03\nE = 800\n"
                 "density = 2\ngravity = 9.81\nangle = 30\nsolver = fem\nfem_path = thesis\n"
                 "fem_elements = 10\n%s",
                 variants[v]);
        cbm_bend_spec sp;
        CHECK_OK(cbm_bend_spec_parse(ctx, text, strlen(text), "t.spec", &sp));
        cbm_plant *p = NULL;
        cbm_bend_result r;
        CHECK_OK(cbm_bend_run(ctx, &sp, &p, &r));
        /* the API by hand */
        cbm_fem_thesis_def d = cbm_fem_thesis_def_default();
        d.n_fe = 10;
        d.t0 = 60.0;
        d.le = 0.1;
        d.r_start = 0.05;
        d.r_end = 0.03;
        d.rho = 2.0;
        d.youngs_modulus = 800.0;
        if (v > 0) {
            d.support = CBM_FEM_SUPPORT_CLAMPED;
            d.printed_stiffness = false;
        }
        if (v == 2) {
            d.update_sign = -1;
            d.primary_tropism = true;
        }
        double beta[10], a[40];
        CHECK_OK(cbm_fem_thesis_angles(ctx, &d, beta, 10, NULL));
        CHECK_OK(cbm_fem_thesis_resample(ctx, beta, 10, a, 40));
        CHECK_EQ_INT(cbm_plant_segment_count(p), 40);
        double dmax = 0;
        for (size_t i = 0; i < 40; i++)
            dmax = fmax(dmax, fabs(remainder(seg_elevation(p, i) - (90.0 - a[i]), 360.0)));
        printf("bend fem_path = thesis, variant %d: tip %.4f deg from the vertical, largest "
               "difference from the API %.2g deg, residual %.2g\n",
               v, a[39], dmax, r.stats.residual);
        CHECK(dmax <= 1e-9);
        /* the pose is an equilibrium of the plant (its cores remember it) */
        CHECK(r.stats.residual <= 1e-9);
        CHECK_EQ_INT(r.steps_done, 10);
        cbm_plant_destroy(p);
    }
    test_ctx_end(ctx);
}

TEST(fem_thesis_bend_spec_errors)
{
    test_diags g;
    cbm_context *ctx = test_diag_ctx(&g);
    CHECK(ctx != NULL);
    cbm_bend_spec sp;
    const char *t1 = "solver = fem\nfem_elements = 12\n";
    CHECK_STATUS(cbm_bend_spec_parse(ctx, t1, strlen(t1), "a.spec", &sp), CBM_E_SEMANTIC);
    CHECK(strstr(g.text, "need fem_path = thesis"));
    const char *t2 = "solver = fem\nfem_path = thesis\ntip_load = 1\nsegments = 8\n";
    CHECK_STATUS(cbm_bend_spec_parse(ctx, t2, strlen(t2), "b.spec", &sp), CBM_E_SEMANTIC);
    CHECK(strstr(g.text, "'tip_load' has no meaning there"));
    CHECK(strstr(g.text, "segments must be at least fem_elements"));
    const char *t3 = "solver = fem\nfem_path = thesys\n";
    CHECK_STATUS(cbm_bend_spec_parse(ctx, t3, strlen(t3), "c.spec", &sp), CBM_E_SEMANTIC);
    CHECK(strstr(g.text, "c.spec:2:12: unknown fem_path 'thesys' (expected clamped or thesis)"));
    const char *t4 = "fem_path = thesis\n";
    CHECK_STATUS(cbm_bend_spec_parse(ctx, t4, strlen(t4), "d.spec", &sp), CBM_E_SEMANTIC);
    CHECK(strstr(g.text, "the fem_* keys need solver = fem"));
    /* the listing's defaults where the spec is silent */
    const char *t5 = "solver = fem\nfem_path = thesis\n";
    CHECK_OK(cbm_bend_spec_parse(ctx, t5, strlen(t5), "e.spec", &sp));
    CHECK(sp.fem_axial == CBM_FEM_AXIAL_LISTING);
    CHECK_NEAR(sp.fem_shear_ratio, 1.0 / 3.0, 0);
    CHECK_EQ_INT(sp.fem_elements, 10);
    test_ctx_end(ctx);
}

TEST(bend_approx_load_key_equals_api)
{
    cbm_context *ctx = test_ctx();
    /* a tapered heavy branch: the two loads give different shapes (docs/validation.md) */
    const char *base = "length = 2\nsegments = 40\nradius_base = 0.03\nradius_tip = 0.005\n"
                       "E = 5e9\ndensity = 900\nangle = 20\nsolver = approx\n";
    double tip[2];
    for (int c = 0; c < 2; c++) {
        char text[512];
        snprintf(text, sizeof text, "%sapprox_load = %s\n", base, c ? "calibrated" : "thesis");
        cbm_bend_spec sp;
        CHECK_OK(cbm_bend_spec_parse(ctx, text, strlen(text), "l.spec", &sp));
        CHECK(sp.approx_load == (c ? CBM_APPROX_LOAD_CALIBRATED : CBM_APPROX_LOAD_TIP));
        cbm_plant *p = NULL, *q = NULL;
        CHECK_OK(cbm_bend_run(ctx, &sp, &p, NULL));
        /* the API: the same rod, cbm_solve_def with the enum */
        CHECK_OK(cbm_bend_build(ctx, &sp, &q));
        cbm_solve_def sd = cbm_solve_def_default();
        sd.solver = CBM_MECH_APPROX;
        sd.tolerance = sp.tolerance;
        sd.approx_load = c ? CBM_APPROX_LOAD_CALIBRATED : CBM_APPROX_LOAD_TIP;
        cbm_solve_stats st;
        CHECK_OK(cbm_plant_solve(q, &sd, &st));
        cbm_segment_state a, b;
        CHECK_OK(cbm_plant_segment(p, 39, &a));
        CHECK_OK(cbm_plant_segment(q, 39, &b));
        CHECK_NEAR(a.distal.x, b.distal.x, 0);
        CHECK_NEAR(a.distal.y, b.distal.y, 0);
        tip[c] = a.distal.y;
        cbm_plant_destroy(p);
        cbm_plant_destroy(q);
    }
    printf("approx_load thesis: tip y %.4f m, calibrated: %.4f m\n", tip[0], tip[1]);
    CHECK(fabs(tip[0] - tip[1]) > 1e-3);
    test_ctx_end(ctx);
}
