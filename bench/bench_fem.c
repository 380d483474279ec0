/* Benchmark of the incremental finite-element method (src/mech/fem.c; docs/performance.md,
 * "Incremental FEM"):
 *   1. Guertler's experiment (thesis ch. 7): one branch grown from one element to n_FE elements,
 *      one element and one ring per step, one linear solve per step; the whole growth timed
 *      (best and mean of `reps` repetitions) with the peak bytes the context allocated. n_FE
 *      from his 10..40 to far beyond.
 *   2. One growth step on an unbranched branch of n elements (time per element: O(n)).
 *   3. One growth step on a random branched tree of n segments (ring on every segment, a new
 *      element at every tip, leaves' mass), the goal being < 1 s at 10^5.
 *   4. The thesis-compatible path (cambium/fem_thesis.h), n_FE 10..--thesis-max (<= 40).
 * Usage: bench_fem [--reps N] [--max N] [--thesis-max N] [--out file.csv] */
#define _POSIX_C_SOURCE 200809L
#include "cambium/cambium.h"
#include "bench_util.h"
#include "cambium/fem_thesis.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Guertler's branch: 4 m long (elements of Le = 4 / n_FE, so the physics stays the same across
 * the sweep), tip radius r_end, base radius r_start after n_FE steps (ring thickness
 * (r_start - r_end) / (n_FE - 1)), t0 = 60 degrees from the vertical. */
static int grow_branch(cbm_context *ctx, size_t nfe, cbm_plant **out)
{
    cbm_plant_def pd = cbm_plant_def_default();
    pd.base_orientation = cbm_mech_clamp_orientation(PI / 6);
    pd.capacity = nfe;
    cbm_plant *p = NULL;
    if (cbm_plant_create(ctx, &pd, &p) != CBM_OK)
        return 1;
    const double rs = 0.05, re = 0.01, E = 1e10;
    cbm_segment_def d = cbm_segment_def_default();
    d.length = 4.0 / (double)nfe;
    d.core.a = d.core.b = re;
    d.core.youngs_modulus = E;
    d.core.shear_modulus = E / 3;
    d.core.density = 700;
    cbm_fem_def fd = cbm_fem_def_default(); /* G = E/3 through the rings: O(1) sections */
    cbm_solve_def sd = cbm_solve_def_default();
    sd.solver = CBM_MECH_FEM;
    sd.fem = fd;
    sd.fem.increments = 1;
    if (cbm_plant_add_segment(p, &d, NULL) != CBM_OK || cbm_plant_solve(p, &sd, NULL) != CBM_OK) {
        cbm_plant_destroy(p);
        return 1;
    }
    cbm_fem_growth g = cbm_fem_growth_default();
    g.ring_thickness = nfe > 1 ? (rs - re) / (double)(nfe - 1) : 0.0;
    g.wood = d.core;
    g.tip_length = d.length;
    g.tip_radius = re;
    for (size_t k = 1; k < nfe; k++)
        if (cbm_plant_fem_grow(p, &fd, &g, NULL) != CBM_OK) {
            cbm_plant_destroy(p);
            return 1;
        }
    *out = p;
    return 0;
}

/* One growth step: a 0.1 mm ring everywhere, a 2 cm element at every tip. */
static double one_step(cbm_plant *p, size_t *tips, double *cpu_s)
{
    cbm_fem_growth g = cbm_fem_growth_default();
    g.ring_thickness = 1e-4;
    g.wood.youngs_modulus = 1e10;
    g.wood.shear_modulus = 1e10 / 16;
    g.wood.density = 700;
    g.tip_length = 0.02;
    g.tip_radius = 0.002;
    cbm_fem_stats fs;
    double t0 = now(), c0 = cpu();
    cbm_status s = cbm_plant_fem_grow(p, NULL, &g, &fs);
    double t = now() - t0;
    *cpu_s = cpu() - c0;
    *tips = fs.tips_added;
    return s == CBM_OK ? t : NAN;
}

int main(int argc, char **argv)
{
    int reps = 200;
    size_t maxn = 1000000;
    const char *out = NULL;
    size_t thesis_max = 40;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--reps") && i + 1 < argc)
            reps = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--max") && i + 1 < argc)
            maxn = (size_t)atof(argv[++i]);
        else if (!strcmp(argv[i], "--out") && i + 1 < argc)
            out = argv[++i];
        else if (!strcmp(argv[i], "--thesis-max") && i + 1 < argc)
            thesis_max = (size_t)atof(argv[++i]);
        else {
            fprintf(stderr, "usage: bench_fem [--reps N] [--max N] [--thesis-max N] [--out "
                            "file.csv]\n");
            return 2;
        }
    }
    FILE *csv = out ? fopen(out, "w") : NULL;
    if (out && !csv) {
        fprintf(stderr, "bench_fem: cannot write %s\n", out);
        return 1;
    }
    if (csv)
        fprintf(csv, "experiment,n,reps,best_s,mean_or_cpu_s,per_element_us,peak_bytes\n");
    cbm_context *ctx = NULL;
    if (cbm_context_create(NULL, &ctx) != CBM_OK)
        return 1;
    printf("1. Guertler's branch grown to n_FE elements (n_FE steps, one solve each)\n");
    printf("%8s %6s %12s %12s %14s %12s %10s\n", "n_FE", "reps", "best s", "mean s", "us/(step*el)",
           "peak bytes", "tip deg");
    static const size_t nfes[] = {10, 20, 30, 40, 100, 400, 1000, 2000};
    for (size_t k = 0; k < sizeof nfes / sizeof *nfes && nfes[k] <= maxn; k++) {
        size_t nfe = nfes[k];
        int r = nfe <= 40 ? reps : nfe <= 400 ? 20 : nfe <= 1000 ? 3 : 1;
        double best = INFINITY, sum = 0, tip = 0;
        size_t peak = 0;
        for (int j = 0; j < r; j++) {
            cbm_context *c2 = NULL;
            if (cbm_context_create(NULL, &c2) != CBM_OK)
                return 1;
            cbm_plant *p = NULL;
            double t0 = now();
            int bad = grow_branch(c2, nfe, &p);
            double t = now() - t0;
            if (bad) {
                fprintf(stderr, "bench_fem: growth failed at n_FE = %zu: %s\n", nfe,
                        cbm_context_last_error(c2));
                return 1;
            }
            peak = cbm_context_peak_bytes(c2);
            cbm_segment_state s;
            if (cbm_plant_segment(p, nfe - 1, &s) == CBM_OK)
                tip = acos(s.frame.h.y) * 180 / PI;
            cbm_plant_destroy(p);
            cbm_context_destroy(c2);
            best = fmin(best, t);
            sum += t;
        }
        double per = best / (0.5 * (double)nfe * (double)(nfe + 1)) * 1e6;
        printf("%8zu %6d %12.3e %12.3e %14.3f %12zu %10.2f\n", nfe, r, best, sum / r, per, peak,
               tip);
        if (csv)
            fprintf(csv, "guertler-branch,%zu,%d,%.6e,%.6e,%.4f,%zu\n", nfe, r, best, sum / r, per,
                    peak);
    }
    printf("\n2. One growth step, unbranched branch of n elements of 2 cm\n");
    printf("(a first step, then the best of 3: the buffers a growing plant keeps are in place)\n");
    printf("%9s %12s %12s %12s\n", "n", "step s", "cpu s", "us/element");
    for (size_t n = 100; n <= maxn; n *= 10) {
        cbm_plant_def pd = cbm_plant_def_default();
        pd.capacity = n + 1;
        cbm_plant *p = NULL;
        if (cbm_plant_create(ctx, &pd, &p) != CBM_OK)
            return 1;
        cbm_segment_def d = cbm_segment_def_default();
        d.length = 0.02; /* as the tree's: 1e-5 m elements of 1 cm radius lose definiteness */
        for (size_t i = 0; i < n; i++) {
            d.parent = (int64_t)i - 1;
            if (cbm_plant_add_segment(p, &d, NULL) != CBM_OK)
                return 1;
        }
        if (cbm_plant_evaluate(p, NULL) != CBM_OK)
            return 1;
        size_t tips = 0;
        double best = INFINITY, bc = INFINITY, c = 0;
        (void)one_step(p, &tips, &c);
        for (int j = 0; j < 3; j++) {
            best = fmin(best, one_step(p, &tips, &c));
            bc = fmin(bc, c);
        }
        printf("%9zu %12.3e %12.3e %12.3f\n", n, best, bc, bc / (double)n * 1e6);
        if (csv)
            fprintf(csv, "chain-step,%zu,3,%.6e,%.6e,%.4f,\n", n, best, bc, bc / (double)n * 1e6);
        cbm_plant_destroy(p);
    }
    printf("\n3. One growth step, random branched tree of n segments\n");
    printf("(first step, then the best of 3)\n");
    printf("%9s %8s %12s %12s %12s %12s %14s\n", "n", "tips", "first s", "step s", "cpu s",
           "us/element", "peak bytes");
    for (size_t n = 1000; n <= maxn; n *= 10) {
        cbm_context *c2 = NULL;
        if (cbm_context_create(NULL, &c2) != CBM_OK)
            return 1;
        cbm_plant *p = bench_random_tree(c2, n, 2 * n, 1e10, 0.005);
        if (!p || cbm_plant_evaluate(p, NULL) != CBM_OK)
            return 1;
        size_t tips = 0, base = cbm_context_bytes(c2);
        double c = 0, first = one_step(p, &tips, &c), t = INFINITY, bc = INFINITY;
        size_t peak = cbm_context_peak_bytes(c2) - base;
        for (int j = 0; j < 3; j++) {
            t = fmin(t, one_step(p, &tips, &c));
            bc = fmin(bc, c);
        }
        printf("%9zu %8zu %12.3e %12.3e %12.3e %12.3f %14zu\n", n, tips, first, t, bc,
               bc / (double)n * 1e6, peak);
        if (csv)
            fprintf(csv, "tree-step,%zu,3,%.6e,%.6e,%.4f,%zu\n", n, t, bc, bc / (double)n * 1e6,
                    peak);
        cbm_plant_destroy(p);
        cbm_context_destroy(c2);
    }
    printf(
        "\n4. The thesis-compatible path (cbm_fem_thesis_angles): the listing as printed (dense,\n"
        "free-free SVD) and clamped (dense elimination), the digest's branch (L = 1 m)\n");
    printf("%8s %6s %12s %12s %10s\n", "n_FE", "reps", "free cpu s", "clamp cpu s", "tip deg");
    static const long tfes[] = {10, 20, 30, 40};
    for (size_t k = 0; k < sizeof tfes / sizeof *tfes && (size_t)tfes[k] <= thesis_max; k++) {
        cbm_fem_thesis_def d = cbm_fem_thesis_def_default();
        d.n_fe = tfes[k];
        d.le = 1.0 / (double)tfes[k];
        double beta[40], tf = INFINITY, tc = INFINITY;
        int r = tfes[k] <= 20 ? 5 : 1;
        cbm_fem_thesis_info in;
        for (int j = 0; j < r; j++) {
            d.support = CBM_FEM_SUPPORT_FREE;
            double c0 = cpu();
            if (cbm_fem_thesis_angles(ctx, &d, beta, 40, &in) != CBM_OK)
                return 1;
            tf = fmin(tf, cpu() - c0);
            d.support = CBM_FEM_SUPPORT_CLAMPED;
            c0 = cpu();
            if (cbm_fem_thesis_angles(ctx, &d, beta, 40, NULL) != CBM_OK)
                return 1;
            tc = fmin(tc, cpu() - c0);
        }
        printf("%8ld %6d %12.3e %12.3e %10.3f\n", tfes[k], r, tf, tc, in.tip_angle);
        if (csv)
            fprintf(csv, "thesis-path,%ld,%d,%.6e,%.6e,,\n", tfes[k], r, tf, tc);
    }
    cbm_context_destroy(ctx);
    if (csv)
        fclose(csv);
    return 0;
}
