/* Gürtler's FE branch as his listing computes it (cambium/fem_thesis.h, src/mech/fem_thesis.c):
 * the digest's independent re-computation of the listing (digest 001 §2.2.6, a Python transcript
 * with numpy's SVD) in the printed, clamped-lifting and clamped-sagging variants; the zero-load
 * identities the thesis reports (grav = 0 and t0 = 180 degrees leave the branch as it was); the
 * free-free pseudo-inverse against the clamped solve where they must agree (a self-equilibrated
 * load: the two differ by a rigid motion) and where they must not (the weight: the pseudo-inverse
 * drops its resultant); the planar split of the SVD against the whole one. docs/validation.md,
 * "The thesis-compatible FE path", has the tolerances and measurements. */
#include "test.h"

#include "cambium/fem_thesis.h"
#include "mech/fem_internal.h"

#include <math.h>
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
    double dd[48];
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
