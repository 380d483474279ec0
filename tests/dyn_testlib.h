/* The straight rod the dynamics tests start from (test_dyn_modes.c, test_dyn_loads.c): n equal
 * segments of wood (600 kg/m^3) clamped at elev rad, a tip mass, solved for equilibrium (or only
 * evaluated). Header-only, static functions. */
#ifndef CBM_DYN_TESTLIB_H
#define CBM_DYN_TESTLIB_H

#include "mech_testlib.h"
#include "core/vecmath.h"

/* radius r, gravity g (m/s^2, along -y), Young's modulus E, shear modulus G (0: E / 2.6) */
static inline cbm_plant *dyn_rod(cbm_context *ctx, int n, double L, double r, double elev, double g,
                                 double tip_mass, double E, double G, bool solve)
{
    cbm_plant_def pd = cbm_plant_def_default();
    pd.base_orientation = cbm_mech_clamp_orientation(elev);
    pd.gravity = v3(0, -g, 0);
    cbm_plant *p = NULL;
    CHECK_OK(cbm_plant_create(ctx, &pd, &p));
    if (!p)
        return NULL;
    cbm_segment_def d = cbm_segment_def_default();
    d.length = L / n;
    d.core.youngs_modulus = E;
    d.core.shear_modulus = G > 0 ? G : E / 2.6;
    d.core.density = 600;
    d.core.a = d.core.b = r;
    for (int i = 0; i < n; i++) {
        d.parent = i - 1;
        d.point_mass = i == n - 1 ? tip_mass : 0.0;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    if (solve) {
        cbm_solve_def sd = cbm_solve_def_default();
        CHECK_OK(cbm_plant_solve(p, &sd, NULL));
    } else
        CHECK_OK(cbm_plant_evaluate(p, NULL));
    return p;
}

/* A branched plant of n segments under gravity, clamped at 1.2 rad, solved: a main axis with a
 * lateral every third segment, elliptical sections 2 x 1.5 cm, 50 g on every fourth segment
 * (test_dyn_loads.c, test_dyn_modal.c, test_dyn_modes.c). */
static inline cbm_plant *dyn_branched(cbm_context *ctx, int n)
{
    cbm_plant *p = clamped_plant(ctx, 1.2);
    cbm_segment_def d = cbm_segment_def_default();
    d.core.a = 0.02;
    d.core.b = 0.015;
    for (int i = 0; i < n; i++) {
        d.parent = i == 0 ? -1 : (i % 3 == 0 ? i / 2 : i - 1);
        d.lateral = i % 3 == 0 && i > 0;
        d.deviation = d.lateral ? 0.6 : 0.05;
        d.divergence = 2.4 * i;
        d.point_mass = i % 4 == 0 ? 0.05 : 0.0;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    cbm_solve_def sd = cbm_solve_def_default();
    CHECK_OK(cbm_plant_solve(p, &sd, NULL));
    return p;
}

#endif
