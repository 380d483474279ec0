/* Linking against an installed cambium (README, "Installing and linking"):
 *
 *     cc bend_rod.c $(pkg-config --cflags --libs cambium) -lm -o bend_rod
 *
 * A stiff horizontal rod, clamped at one end, bends under its own weight. The program builds it
 * segment by segment, brings it to static equilibrium with the fast solver and prints the tip's
 * deflection beside the small-deflection theory, w L^4 / (8 EI) (1 + 1/N^2) for N segments of
 * the default (staggered) discretisation, the solver's passes and the stage that converged. */
#include <cambium/cambium.h>

#include <math.h>
#include <stdio.h>

int main(void)
{
    const double pi = 3.14159265358979323846;
    const int n = 50;                                      /* segments */
    const double len = 1.0, r = 0.01, E = 1e13, rho = 700; /* m, m, Pa, kg/m^3 */
    cbm_context *ctx = NULL;
    if (cbm_context_create(NULL, &ctx) != CBM_OK)
        return 1;
    cbm_plant_def pd = cbm_plant_def_default();
    pd.base_orientation = cbm_mech_clamp_orientation(0.0); /* horizontal */
    cbm_plant *plant = NULL;
    cbm_status s = cbm_plant_create(ctx, &pd, &plant);
    cbm_segment_def d = cbm_segment_def_default();
    d.length = len / n;
    d.core.a = d.core.b = r;
    d.core.youngs_modulus = E;
    d.core.shear_modulus = E / 2.6;
    d.core.density = rho;
    for (int i = 0; i < n && s == CBM_OK; i++) {
        d.parent = i - 1; /* -1: the root, clamped */
        s = cbm_plant_add_segment(plant, &d, NULL);
    }
    cbm_solve_stats st;
    if (s == CBM_OK)
        s = cbm_plant_solve(plant, NULL, &st);
    cbm_segment_state tip;
    if (s == CBM_OK)
        s = cbm_plant_segment(plant, (size_t)n - 1, &tip);
    if (s != CBM_OK) {
        fprintf(stderr, "bend_rod: %s\n", cbm_context_last_error(ctx));
        cbm_plant_destroy(plant);
        cbm_context_destroy(ctx);
        return 1;
    }
    double w = rho * pi * r * r * 9.81, I = pi * pow(r, 4) / 4;
    double theory = w * pow(len, 4) / (8 * E * I) * (1 + 1.0 / (n * n));
    printf("cambium %s: tip deflection %.9e m (theory %.9e m), %zu passes, stage %s\n",
           CBM_VERSION_STRING, -tip.distal.y, theory, st.passes, cbm_solve_stage_name(st.stage));
    cbm_plant_destroy(plant);
    cbm_context_destroy(ctx);
    return fabs(-tip.distal.y - theory) <= 1e-6 * theory ? 0 : 1;
}
