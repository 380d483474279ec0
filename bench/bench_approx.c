/* Benchmark of Method A, the approximative bending (docs/performance.md, "Method A"):
 *
 *  1. the angle generator alone (cbm_approx_angles), as the thesis's chapter 7 measures it: 200
 *     repetitions per disc (10 .. 1000), both modes, time per call and the bytes of its result;
 *  2. on plants: solver = approx against one statics pass (cbm_plant_evaluate: one forward and
 *     one backward sweep, what one relaxation pass costs) and against the fast solver's
 *     equilibrium, per segment, on a horizontal chain and on a random branched tree;
 *  3. every method (a pass, approx in both modes, fast, relax, fem) side by side on the same
 *     tree (10^3 and 10^4 segments), each in a fresh context: time of one solve from rest and
 *     the peak memory it adds above the plant's own, per segment (kind "side").
 *
 * usage: bench_approx [--out FILE.csv] [--max N]
 * Writes rows kind,workload,mode,n,reps,seconds_per_call,ns_per_segment,bytes. */
#define _POSIX_C_SOURCE 200809L
#include "cambium/cambium.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define PI 3.14159265358979323846

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts); /* CPU time: the machine is shared */
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static cbm_plant *make_chain(cbm_context *ctx, size_t n)
{
    cbm_plant_def pd = cbm_plant_def_default();
    pd.capacity = n;
    cbm_plant *p = NULL;
    if (cbm_plant_create(ctx, &pd, &p) != CBM_OK)
        return NULL;
    cbm_segment_def d = cbm_segment_def_default();
    d.length = 1.0 / (double)n;
    d.core.a = d.core.b = 0.01;
    d.core.density = 1000;
    d.core.youngs_modulus = 1e9;
    for (size_t i = 0; i < n; i++) {
        d.parent = (int64_t)i - 1;
        if (cbm_plant_add_segment(p, &d, NULL) != CBM_OK) {
            cbm_plant_destroy(p);
            return NULL;
        }
    }
    return p;
}

/* A random tree: each new segment continues the previous one with probability 0.8, else starts
 * a lateral on a random earlier segment; radii by the number of segments carried (pipe model);
 * a fixed seed of our own generator so every run builds the same tree. */
static cbm_plant *make_tree(cbm_context *ctx, size_t n)
{
    cbm_plant_def pd = cbm_plant_def_default();
    pd.capacity = n;
    pd.base_orientation = cbm_mech_clamp_orientation(PI / 2);
    cbm_plant *p = NULL;
    if (cbm_plant_create(ctx, &pd, &p) != CBM_OK)
        return NULL;
    int64_t *par = malloc(n * sizeof *par);
    double *carried = calloc(n, sizeof *carried);
    bool *lat = calloc(n, sizeof *lat);
    uint64_t st = 7;
    for (size_t i = 0; i < n; i++) {
        st = st * 6364136223846793005ull + 1442695040888963407ull;
        double u = (double)(st >> 11) / 9007199254740992.0;
        st = st * 6364136223846793005ull + 1442695040888963407ull;
        double v = (double)(st >> 11) / 9007199254740992.0;
        par[i] = i == 0 ? -1 : (u < 0.8 ? (int64_t)i - 1 : (int64_t)(v * (double)i));
        lat[i] = i > 0 && u >= 0.8;
    }
    for (size_t i = n; i-- > 0;) {
        carried[i] += 1.0;
        if (par[i] >= 0)
            carried[par[i]] += carried[i];
    }
    cbm_segment_def d = cbm_segment_def_default();
    d.length = 0.02;
    d.core.density = 700;
    d.core.youngs_modulus = 1e10;
    cbm_status s = CBM_OK;
    for (size_t i = 0; i < n && s == CBM_OK; i++) {
        d.parent = par[i];
        d.lateral = lat[i];
        d.deviation = lat[i] ? PI / 4 : 0.0;
        d.divergence = lat[i] ? fmod(2.4 * (double)i, 2 * PI) : 0.0;
        d.core.a = d.core.b = 0.002 * sqrt(carried[i]);
        s = cbm_plant_add_segment(p, &d, NULL);
    }
    free(par);
    free(carried);
    free(lat);
    if (s != CBM_OK) {
        cbm_plant_destroy(p);
        return NULL;
    }
    return p;
}

int main(int argc, char **argv)
{
    const char *out = "bench_approx.csv";
    size_t maxn = 100000;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--out") && i + 1 < argc)
            out = argv[++i];
        else if (!strcmp(argv[i], "--max") && i + 1 < argc)
            maxn = (size_t)atof(argv[++i]);
        else {
            fprintf(stderr, "usage: bench_approx [--out FILE.csv] [--max N]\n");
            return 2;
        }
    }
    FILE *f = fopen(out, "w");
    if (!f) {
        fprintf(stderr, "bench_approx: cannot write %s\n", out);
        return 1;
    }
    fprintf(f, "kind,workload,mode,n,reps,seconds_per_call,ns_per_segment,bytes\n");
    cbm_context *ctx = NULL;
    cbm_context_def cd = cbm_context_def_default();
    if (cbm_context_create(&cd, &ctx) != CBM_OK)
        return 1;
    /* 1. the generator alone (thesis ch. 7: 200 repetitions per setting) */
    long discs[] = {10, 20, 40, 100, 140, 200, 1000};
    double res[1001];
    for (int m = 0; m < 2; m++)
        for (size_t k = 0; k < sizeof discs / sizeof *discs; k++) {
            cbm_approx_def d = cbm_approx_def_default();
            d.disc = discs[k];
            d.t0 = 100;
            d.k0 = 1.0 / (double)discs[k]; /* K0 h = 1: omega about 26 degrees */
            d.mode = m ? CBM_APPROX_THESIS : CBM_APPROX_CORRECTED;
            int reps = 200;
            double best = INFINITY;
            for (int round = 0; round < 5; round++) {
                double t0 = now();
                for (int r = 0; r < reps; r++)
                    (void)cbm_approx_angles(ctx, &d, res, 1001, NULL);
                double t = (now() - t0) / reps;
                best = fmin(best, t);
            }
            size_t bytes = (size_t)(discs[k] + 1) * sizeof(double);
            const char *mode = cbm_approx_mode_name(d.mode);
            fprintf(f, "generator,branch,%s,%ld,%d,%.6g,%.6g,%zu\n", mode, discs[k], reps, best,
                    1e9 * best / (double)discs[k], bytes);
            printf("generator %-9s disc %5ld: %8.3f us per call, %6.1f ns per segment, %zu bytes\n",
                   mode, discs[k], 1e6 * best, 1e9 * best / (double)discs[k], bytes);
        }
    /* 2. plants: approx vs one statics pass vs the fast equilibrium */
    const char *work[] = {"chain", "tree"};
    for (int w = 0; w < 2; w++)
        for (size_t n = 1000; n <= maxn; n *= 10) {
            cbm_plant *p = w ? make_tree(ctx, n) : make_chain(ctx, n);
            if (!p)
                return 1;
            int reps = n <= 10000 ? 50 : 5;
            cbm_solve_def sd = cbm_solve_def_default();
            double t_eval = INFINITY, t_apx = INFINITY, t_thesis = INFINITY;
            for (int round = 0; round < 3; round++) {
                double t0 = now();
                for (int r = 0; r < reps; r++)
                    (void)cbm_plant_evaluate(p, NULL);
                t_eval = fmin(t_eval, (now() - t0) / reps);
                sd.solver = CBM_MECH_APPROX;
                sd.approx_mode = CBM_APPROX_CORRECTED;
                t0 = now();
                for (int r = 0; r < reps; r++)
                    (void)cbm_plant_solve(p, &sd, NULL);
                t_apx = fmin(t_apx, (now() - t0) / reps);
                sd.approx_mode = CBM_APPROX_THESIS;
                t0 = now();
                for (int r = 0; r < reps; r++)
                    (void)cbm_plant_solve(p, &sd, NULL);
                t_thesis = fmin(t_thesis, (now() - t0) / reps);
            }
            sd.solver = CBM_MECH_NEWTON;
            sd.warm_start = false;
            double t0 = now();
            cbm_solve_stats st;
            cbm_status s = cbm_plant_solve(p, &sd, &st);
            double t_fast = now() - t0;
            size_t bytes = cbm_context_peak_bytes(ctx);
            double dn = (double)n;
            fprintf(f, "plant,%s,pass,%zu,%d,%.6g,%.6g,%zu\n", work[w], n, reps, t_eval,
                    1e9 * t_eval / dn, bytes);
            fprintf(f, "plant,%s,approx-corrected,%zu,%d,%.6g,%.6g,%zu\n", work[w], n, reps, t_apx,
                    1e9 * t_apx / dn, bytes);
            fprintf(f, "plant,%s,approx-thesis,%zu,%d,%.6g,%.6g,%zu\n", work[w], n, reps, t_thesis,
                    1e9 * t_thesis / dn, bytes);
            fprintf(f, "plant,%s,fast,%zu,1,%.6g,%.6g,%zu\n", work[w], n, t_fast, 1e9 * t_fast / dn,
                    bytes);
            printf("%-5s n %7zu: pass %6.1f ns/seg, approx %6.1f ns/seg (%.2fx a pass), thesis "
                   "%6.1f ns/seg, fast equilibrium %8.1f ns/seg (%s, %zu passes)\n",
                   work[w], n, 1e9 * t_eval / dn, 1e9 * t_apx / dn, t_apx / t_eval,
                   1e9 * t_thesis / dn, 1e9 * t_fast / dn, s == CBM_OK ? "converged" : "failed",
                   st.passes);
            cbm_plant_destroy(p);
            cbm_context_clear_errors(ctx);
        }
    /* 3. every method side by side on the same tree, each in a fresh context: time of one solve
     * from rest (the best of 3 for the one-shot ones) and the peak memory it adds above the
     * plant's own (bytes through the library's allocator), per segment */
    const struct {
        const char *name;
        int solver; /* -1: one statics pass */
        cbm_approx_mode mode;
    } meth[] = {{"pass", -1, CBM_APPROX_CORRECTED},
                {"approx-corrected", CBM_MECH_APPROX, CBM_APPROX_CORRECTED},
                {"approx-thesis", CBM_MECH_APPROX, CBM_APPROX_THESIS},
                {"fast", CBM_MECH_NEWTON, CBM_APPROX_CORRECTED},
                {"relax", CBM_MECH_RELAX, CBM_APPROX_CORRECTED},
                {"fem", CBM_MECH_FEM, CBM_APPROX_CORRECTED}};
    for (size_t n = 1000; n <= maxn && n <= 10000; n *= 10)
        for (size_t k = 0; k < sizeof meth / sizeof *meth; k++) {
            cbm_context *c2 = NULL;
            if (cbm_context_create(&cd, &c2) != CBM_OK)
                return 1;
            cbm_plant *p = make_tree(c2, n);
            if (!p)
                return 1;
            size_t base = cbm_context_peak_bytes(c2);
            cbm_solve_def sd = cbm_solve_def_default();
            sd.warm_start = false;
            sd.approx_mode = meth[k].mode;
            if (meth[k].solver >= 0)
                sd.solver = (cbm_mech_solver)meth[k].solver;
            bool once = meth[k].solver >= 0 && meth[k].solver != CBM_MECH_APPROX;
            double best = INFINITY;
            cbm_solve_stats st = {0};
            cbm_status s = CBM_OK;
            for (int r = 0; r < (once ? 1 : 3); r++) {
                double t0 = now();
                s = meth[k].solver < 0 ? cbm_plant_evaluate(p, NULL) : cbm_plant_solve(p, &sd, &st);
                best = fmin(best, now() - t0);
            }
            size_t extra = cbm_context_peak_bytes(c2) - base;
            double dn = (double)n;
            fprintf(f, "side,tree,%s,%zu,%d,%.6g,%.6g,%zu\n", meth[k].name, n, once ? 1 : 3, best,
                    1e9 * best / dn, extra);
            printf("side by side, tree n %5zu: %-16s %10.1f ns/seg %8.1f extra bytes/seg (plant "
                   "%.0f bytes/seg)%s\n",
                   n, meth[k].name, 1e9 * best / dn, (double)extra / dn, (double)base / dn,
                   s == CBM_OK ? "" : " (failed)");
            cbm_plant_destroy(p);
            cbm_context_destroy(c2);
        }
    fclose(f);
    cbm_context_destroy(ctx);
    return 0;
}
