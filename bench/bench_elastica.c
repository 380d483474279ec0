/* Benchmark of the continuous elastica (docs/performance.md, docs/elastica.md): the time to
 * trace one S-curve (one full turn of the tip angle, arc-length steps of 0.02, folds refined,
 * jump targets found) for alpha = 1, 8, 15, 30, 100, the time to list every equilibrium at
 * 90 degrees on it, and the time of the branched plants of Figs. 5.4 and 5.7 (their
 * equilibria at the clamp angle). Prints a CSV on stdout; no timing is asserted anywhere.
 *
 * usage: bench_elastica [--repeat N]
 */
#define _POSIX_C_SOURCE 200809L
#include "cambium/cambium.h"
#include "bench_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static int plant(cbm_context *ctx, const char *name, const char *text, int repeat)
{
    cbm_elastica_spec sp;
    if (cbm_elastica_spec_parse(ctx, text, strlen(text), name, &sp) != CBM_OK)
        return 1;
    cbm_elastica_piece pc[CBM_ELASTICA_MAX_BRANCHES + 1];
    cbm_elastica_branch br[CBM_ELASTICA_MAX_BRANCHES + 1];
    cbm_elastica_spec_plant(&sp, pc, br, NULL, NULL);
    double best = 1e30;
    size_t n = 0;
    for (int r = 0; r < repeat; r++) {
        cbm_elastica_plant_state *ps = NULL;
        double t0 = now();
        cbm_elastica_plant_def d = cbm_elastica_plant_def_default();
        if (cbm_elastica_plant_equilibria(ctx, br, 1 + sp.n_branches, &d,
                                          sp.angle * 3.14159265358979 / 180, &ps, &n) != CBM_OK)
            return 1;
        double t = now() - t0;
        best = t < best ? t : best;
        cbm_elastica_plant_states_destroy(ctx, ps, n, 1 + sp.n_branches);
    }
    printf("%s,%zu,,,%zu,%.6f\n", name, 1 + sp.n_branches, n, best);
    return 0;
}

int main(int argc, char **argv)
{
    int repeat = 3;
    for (int i = 1; i < argc; i++)
        if (!strcmp(argv[i], "--repeat") && i + 1 < argc)
            repeat = atoi(argv[++i]);
    if (repeat < 1)
        repeat = 1;
    cbm_context_def cd = cbm_context_def_default();
    cbm_context *ctx = NULL;
    if (cbm_context_create(&cd, &ctx) != CBM_OK)
        return 1;
    printf("workload,branches,points,folds,equilibria,seconds\n");
    const double alphas[] = {1, 8, 15, 30, 100};
    for (size_t k = 0; k < sizeof alphas / sizeof *alphas; k++) {
        cbm_elastica_piece pc = cbm_elastica_piece_default();
        pc.w0 = pc.w1 = alphas[k];
        cbm_elastica_rod rod = cbm_elastica_rod_default();
        rod.pieces = &pc, rod.n_pieces = 1;
        double best = 1e30, beq = 1e30;
        size_t np = 0, nf = 0, ne = 0;
        for (int r = 0; r < repeat; r++) {
            cbm_elastica_scurve *sc = NULL;
            double t0 = now();
            if (cbm_elastica_scurve_compute(ctx, &rod, NULL, &sc) != CBM_OK)
                return 1;
            double t1 = now();
            cbm_elastica_state eq[64];
            if (cbm_elastica_equilibria(ctx, &rod, sc, 3.14159265358979 / 2, eq, 64, &ne) != CBM_OK)
                return 1;
            double t2 = now();
            best = t1 - t0 < best ? t1 - t0 : best;
            beq = t2 - t1 < beq ? t2 - t1 : beq;
            np = sc->n_points, nf = sc->n_folds;
            cbm_elastica_scurve_destroy(ctx, sc);
        }
        printf("scurve alpha=%g,1,%zu,%zu,,%.6f\n", alphas[k], np, nf, best);
        printf("equilibria at 90 alpha=%g,1,,,%zu,%.6f\n", alphas[k], ne, beq);
    }
    int rc = plant(ctx, "fig5_4",
                   "alpha = 0.2\nangle = 90\n"
                   "branch = parent 0 offset 0 stiffness 0.02 weight 1\n"
                   "branch = parent 0 offset 0 stiffness 0.02 weight 1\n",
                   repeat);
    rc |= plant(ctx, "fig5_7",
                "alpha = 1\nangle = 88\n"
                "branch = parent 0 offset 15 length 0.5 stiffness 0.2 weight 0.35\n"
                "branch = parent 0 offset -15 length 0.5 stiffness 0.2 weight 0.35\n"
                "branch = parent 1 offset 10 length 0.25 stiffness 0.0001 weight "
                "0.128 rest_curvature 0.5\n"
                "branch = parent 1 offset -10 length 0.25 stiffness 0.0001 weight "
                "0.128 rest_curvature 0.5\n"
                "branch = parent 2 offset 10 length 0.25 stiffness 0.0001 weight "
                "0.128 rest_curvature -0.5\n"
                "branch = parent 2 offset -10 length 0.25 stiffness 0.0001 weight "
                "0.128 rest_curvature -0.5\n",
                repeat);
    cbm_context_destroy(ctx);
    return rc;
}
