/* The full cone (tip radius 0) clamped at its base: its bending frequencies against the exact
 * solution (docs/validation.md, "Dynamics: natural frequencies and motion"). */
#include "dyn_testlib.h"
#include "cambium/dynamics.h"

/* With x the distance from the apex over L, a solid circular cone of base radius R has
 * EI = E pi R^4 x^4 / 4 and rho A = rho pi R^2 x^2, so (EI w'')'' = rho A omega^2 w reads
 * (x^4 w'')'' = kappa x^2 w, kappa = 4 rho omega^2 L^4 / (E R^2). A power series
 * w = sum c_m x^m gives c_m m (m - 1) (m + 1) (m + 2) = kappa c_(m-2): two entire solutions, even
 * (c_0 = 1) and odd (c_1 = 1), both regular at the apex, where the moment x^4 w'' and the shear
 * (x^4 w'')' vanish of themselves (the free tip). Clamped at x = 1: w = w' = 0, so kappa is a root
 * of W(kappa) = w_e(1) w_o'(1) - w_o(1) w_e'(1) (the cone Kirchhoff solved in Bessel functions,
 * 1879, "Ueber die Transversalschwingungen eines Stabes von veraenderlichem Querschnitt"; the
 * series here is derived independently and needs no tables). */
static double cone_wronskian(double kappa)
{
    double w[2], dw[2];
    for (int s = 0; s < 2; s++) {
        double c = 1.0, sum = 1.0, dsum = (double)s;
        for (int m = s + 2; m < 400; m += 2) {
            c *= kappa / ((double)m * (m - 1) * (m + 1) * (m + 2));
            sum += c;
            dsum += m * c;
            if (fabs(c) * m < 1e-18 * fabs(sum))
                break;
        }
        w[s] = sum;
        dw[s] = dsum;
    }
    return w[0] * dw[1] - w[1] * dw[0];
}

TEST(full_cone)
{
    cbm_context *ctx = test_ctx();
    const double L = 1.0, R = 0.002, E = 1e10, rho = 600;
    /* the first two roots in kappa */
    double kap[2] = {NAN, NAN};
    int found = 0;
    double k = 1.0, prev = cone_wronskian(k);
    while (found < 2 && k < 1e6) {
        double k1 = k * 1.01, d1 = cone_wronskian(k1);
        if ((d1 > 0) != (prev > 0)) {
            double lo = k, hi = k1, dlo = prev;
            for (int it = 0; it < 80; it++) {
                double mid = 0.5 * (lo + hi), dm = cone_wronskian(mid);
                if ((dm > 0) == (dlo > 0))
                    lo = mid, dlo = dm;
                else
                    hi = mid;
            }
            kap[found++] = 0.5 * (lo + hi);
        }
        k = k1;
        prev = d1;
    }
    CHECK_EQ_INT(found, 2);
    double ref[2];
    for (int j = 0; j < 2; j++)
        ref[j] = R / (2.0 * L * L) * sqrt(kap[j] * E / rho) / (2.0 * PI);
    /* consistent with the commonly quoted omega_1 ~ 4.36 R / L^2 sqrt(E / rho) of the cone */
    printf("cone: kappa %.9g, %.9g; omega L^2 / (R sqrt(E / rho)) = %.6f, %.6f\n", kap[0], kap[1],
           0.5 * sqrt(kap[0]), 0.5 * sqrt(kap[1]));
    CHECK(fabs(0.5 * sqrt(kap[0]) - 4.36) < 0.01);
    double err[3][2];
    const int ns[3] = {50, 100, 200};
    for (int q = 0; q < 3; q++) {
        cbm_plant_def pd = cbm_plant_def_default();
        pd.gravity = v3(0, 0, 0);
        cbm_plant *p = NULL;
        CHECK_OK(cbm_plant_create(ctx, &pd, &p));
        int n = ns[q];
        cbm_segment_def d = cbm_segment_def_default();
        d.length = L / n;
        d.core.youngs_modulus = E;
        d.core.shear_modulus = E / 2.6;
        d.core.density = rho;
        for (int i = 0; i < n; i++) {
            d.parent = i - 1;
            d.core.a = d.core.b = R * (1.0 - (i + 0.5) / n); /* at the centroid */
            CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
        }
        cbm_solve_def sd = cbm_solve_def_default();
        CHECK_OK(cbm_plant_solve(p, &sd, NULL));
        double f[4];
        CHECK_OK(cbm_plant_modes(p, 4, f, NULL));
        err[q][0] = fabs(f[0] - ref[0]) / ref[0];
        err[q][1] = fabs(f[2] - ref[1]) / ref[1];
        printf("cone, %3d segments: %.9g / %.9g Hz, exact %.9g / %.9g Hz, errors %.2e / %.2e\n", n,
               f[0], f[2], ref[0], ref[1], err[q][0], err[q][1]);
        cbm_plant_destroy(p);
    }
    for (int j = 0; j < 2; j++)
        printf("observed order, mode %d: %.2f, %.2f\n", j + 1, log2(err[0][j] / err[1][j]),
               log2(err[1][j] / err[2][j]));
    CHECK(err[2][0] < 5e-4 && err[2][1] < 1e-3);
    CHECK(err[2][0] < err[1][0] && err[1][0] < err[0][0]);
    CHECK(log2(err[1][0] / err[2][0]) > 1.5);
    test_ctx_end(ctx);
}
