/* The discrete 3-D rod of `bend` converges to the continuous elastica as its segments are
 * refined (docs/validation.md "The discrete rod against the elastica"): at alpha = 15 and clamp
 * angles 0 and 45 degrees (one equilibrium each: points of the S-curve), the tip of bend's rod
 * (staggered and chain discretisations, 25, 50, 100 segments) against the elastica's, with the
 * observed order of convergence. */
#include "test.h"

#include <stdlib.h>
#include <string.h>

#define DEG (180.0 / 3.14159265358979323846)

/* the elastica's tip (x, y) / L at alpha, clamp angle deg (the unique equilibrium) */
static void elastica_tip(cbm_context *ctx, double alpha, double angle, double *x, double *y)
{
    cbm_elastica_piece pc = cbm_elastica_piece_default();
    pc.w0 = pc.w1 = alpha;
    cbm_elastica_rod rod = cbm_elastica_rod_default();
    rod.pieces = &pc;
    rod.n_pieces = 1;
    cbm_elastica_scurve *sc = NULL;
    CHECK_OK(cbm_elastica_scurve_compute(ctx, &rod, NULL, &sc));
    cbm_elastica_state eq[8];
    size_t n = 0;
    if (sc)
        CHECK_OK(cbm_elastica_equilibria(ctx, &rod, sc, angle / DEG, eq, 8, &n));
    CHECK_EQ_INT((long)n, 1);
    *x = n ? eq[0].tip_x : 0, *y = n ? eq[0].tip_y : 0;
    cbm_elastica_scurve_destroy(ctx, sc);
}

/* bend's tip / L for the same rod: r = 0.01 m, E 1e10, density 600, g 9.81, L from alpha */
static double bend_error(cbm_context *ctx, double alpha, double angle, long segs, const char *disc,
                         double ex, double ey)
{
    double E = 1e10, r = 0.01, I = 3.14159265358979323846 * r * r * r * r / 4;
    double w = 600 * 3.14159265358979323846 * r * r * 9.81, L = cbrt(alpha * E * I / w);
    char t[512];
    snprintf(t, sizeof t,
             "length = %.17g\nsegments = %ld\nradius = 0.01\nangle = %g\ntolerance = 1e-12\n"
             "discretization = %s\n",
             L, segs, angle, disc);
    cbm_bend_spec sp;
    CHECK_OK(cbm_bend_spec_parse(ctx, t, strlen(t), "d.spec", &sp));
    cbm_plant *p = NULL;
    CHECK_OK(cbm_bend_run(ctx, &sp, &p, NULL));
    cbm_bend_node *nd = calloc((size_t)segs + 1, sizeof *nd);
    double e = 1;
    if (p && nd && cbm_bend_nodes(p, nd, (size_t)segs + 1) == CBM_OK)
        e = hypot(nd[segs].x / L - ex, nd[segs].y / L - ey);
    free(nd);
    cbm_plant_destroy(p);
    return e;
}

TEST(elastica_discrete_convergence)
{
    cbm_context *ctx = test_ctx();
    const double angles[2] = {0, 45};
    const char *disc[2] = {"staggered", "chain"};
    for (int a = 0; a < 2; a++) {
        double ex, ey;
        elastica_tip(ctx, 15, angles[a], &ex, &ey);
        for (int d = 0; d < 2; d++) {
            double e[3];
            for (int k = 0; k < 3; k++)
                e[k] = bend_error(ctx, 15, angles[a], 25L << k, disc[d], ex, ey);
            double o1 = log2(e[0] / e[1]), o2 = log2(e[1] / e[2]);
            printf("alpha 15, %g deg, %s: tip errors %.3e %.3e %.3e (L), orders %.2f %.2f\n",
                   angles[a], disc[d], e[0], e[1], e[2], o1, o2);
            /* staggered: second order; chain (Jirasek's index convention): first order */
            double want = d == 0 ? 2.0 : 1.0;
            CHECK(e[2] < 0.03);
            CHECK_MSG(fabs(o1 - want) < 0.15 && fabs(o2 - want) < 0.15, "orders %g %g", o1, o2);
        }
    }
    test_ctx_end(ctx);
}
