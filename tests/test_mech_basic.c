/* Basic checks of the plant data structure and the statics solvers: construction, section
 * aggregates, small-deflection cantilever, both solvers at the same equilibrium. */
#include "test.h"
#include "cambium/mech.h"

#include <string.h>

#define PI 3.14159265358979323846

static cbm_plant *rod(cbm_context *ctx, int n, double L, double r, double E, double rho,
                      double elev_deg, cbm_mech_discretization disc)
{
    cbm_plant_def pd = cbm_plant_def_default();
    pd.base_orientation = cbm_mech_clamp_orientation(elev_deg * PI / 180.0);
    pd.discretization = disc;
    cbm_plant *p = NULL;
    CHECK_OK(cbm_plant_create(ctx, &pd, &p));
    cbm_segment_def d = cbm_segment_def_default();
    d.length = L / n;
    d.core.youngs_modulus = E;
    d.core.shear_modulus = E / 2.6;
    d.core.density = rho;
    d.core.a = d.core.b = r;
    for (int i = 0; i < n; i++) {
        d.parent = i - 1;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    return p;
}

static cbm_vec3 tip(const cbm_plant *p)
{
    cbm_segment_state s;
    cbm_plant_segment(p, cbm_plant_segment_count(p) - 1, &s);
    return s.distal;
}

TEST(mech_cantilever_small)
{
    cbm_context *ctx = test_ctx();
    double L = 1.0, r = 0.01, E = 1e12, rho = 1000.0;
    double I = PI * r * r * r * r / 4, w = rho * PI * r * r * 9.81;
    double exact = w * L * L * L * L / (8 * E * I);
    double err[2];
    int ns[2] = {50, 100};
    for (int k = 0; k < 2; k++) {
        cbm_plant *p = rod(ctx, ns[k], L, r, E, rho, 0.0, CBM_MECH_STAGGERED);
        cbm_solve_def sd = cbm_solve_def_default();
        cbm_solve_stats st;
        CHECK_OK(cbm_plant_solve(p, &sd, &st));
        cbm_vec3 t = tip(p);
        err[k] = fabs(-t.y - exact) / exact;
        printf("n=%d tip (%.10g %.10g) exact %.10g err %.3g passes %zu res %.3g\n", ns[k], t.x,
               t.y, exact, err[k], st.passes, st.residual);
        cbm_plant_destroy(p);
    }
    CHECK(err[1] < 1e-3);
    test_ctx_end(ctx);
}
