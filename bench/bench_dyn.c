/* Benchmark of the dynamics (docs/performance.md, "Dynamics"): the lowest 10 natural
 * frequencies and the time steps per second of Newmark's rule on random branched trees of
 * 2,500 to 10^5 segments (the tree of bench_mech: trunk continued with probability 0.8,
 * otherwise a lateral on a uniformly chosen earlier segment, 2 cm segments, pipe-model radii,
 * E = 10 GPa, 700 kg/m^3, 5 g leaves on the tips, seed 7), solved for equilibrium first.
 *
 * usage: bench_dyn [--sizes N,N,...] [--modes K] [--steps S] [--stream] [--modal K]
 *
 * --modal K adds the modal motion of the lowest K modes (CBM_MOTION_MODAL): its set-up (the K
 * modes), a step (timed over at least 10^5 steps, the same tip load) and one output frame (the
 * full rotations rebuilt, cbm_motion_rotations), CPU times; then its set-up for a gusty wind
 * (10 m/s at 10 m, log profile, intensity 0.2: the drag's projections) and a windy step (timed
 * over 10^4 steps).
 *
 * --stream adds the CPU time of reading, once, as many bytes as a still-air step reads from
 * memory when its arrays do not fit in the cache (STEP_BYTES per segment), summed with four
 * partial sums: the floor the memory bus sets under the step (docs/performance.md).
 */
#define _POSIX_C_SOURCE 200809L
#include "cambium/cambium.h"
#include "bench_util.h"
#include "cambium/dynamics.h"

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Bytes a still-air undamped step (dyn_motion.c, fused_step) reads per segment: the backward
 * sweep the parent index 8, the inertia 80, the right-hand side's twist 48, the carried sum 48,
 * the node 24, D^-1 72, D^-1 L 144; the forward sweep the parent index 8, D^-1 L 144 again (at
 * 10^5 segments long gone from the cache), D^-1 u 24, the
 * twists 48 + 48 (written: read for ownership), the node 24, q, v, a 72; plus D^-1 u written in
 * the backward sweep 24. The parent's values are in the cache (just written or read). */
#define STEP_BYTES 816

/* CPU seconds to read `bytes` once (the best of five passes over a buffer that large) */
static double stream_read(size_t bytes, double *sink)
{
    size_t n = bytes / sizeof(double);
    double *a = malloc(n * sizeof *a), best = INFINITY;
    if (!a)
        return NAN;
    for (size_t i = 0; i < n; i++)
        a[i] = (double)(i & 255);
    for (int r = 0; r < 5; r++) {
        double c0 = cpu(), s0 = 0, s1 = 0, s2 = 0, s3 = 0;
        size_t i = 0;
        for (; i + 4 <= n; i += 4) {
            s0 += a[i];
            s1 += a[i + 1];
            s2 += a[i + 2];
            s3 += a[i + 3];
        }
        *sink += s0 + s1 + s2 + s3;
        double t = cpu() - c0;
        best = t < best ? t : best;
    }
    free(a);
    return best;
}

int main(int argc, char **argv)
{
    size_t sizes[16] = {2500, 10000, 100000};
    int nsizes = 3, modes = 10, steps = 1000, modal = 0;
    bool stream = false;
    double sink = 0.0;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--sizes") && i + 1 < argc) {
            nsizes = 0;
            for (char *t = strtok(argv[++i], ","); t && nsizes < 16; t = strtok(NULL, ","))
                sizes[nsizes++] = (size_t)strtoull(t, NULL, 10);
        } else if (!strcmp(argv[i], "--modes") && i + 1 < argc)
            modes = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--steps") && i + 1 < argc)
            steps = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--stream"))
            stream = true;
        else if (!strcmp(argv[i], "--modal") && i + 1 < argc)
            modal = atoi(argv[++i]);
        else {
            fprintf(stderr, "usage: bench_dyn [--sizes N,N,...] [--modes K] [--steps S] [--stream] "
                            "[--modal K]\n");
            return 2;
        }
    }
    if (modes < 1 || steps < 1 || modal < 0)
        return 2;
    printf("segments,modes,modes_s,modes_cpu_s,f1_hz,f%d_hz,steps,steps_per_s,ms_per_step,"
           "cpu_ms_per_step%s%s\n",
           modes, stream ? ",stream_read_ms" : "",
           modal ? ",modal_k,modal_setup_cpu_s,modal_cpu_ms_per_step,modal_frame_cpu_ms,"
                   "modal_wind_setup_cpu_s,modal_wind_cpu_ms_per_step"
                 : "");
    for (int k = 0; k < nsizes; k++) {
        cbm_context *ctx = NULL;
        cbm_context_def cd = cbm_context_def_default();
        if (cbm_context_create(&cd, &ctx) != CBM_OK)
            return 1;
        cbm_plant *p = bench_random_tree(ctx, sizes[k], sizes[k], 1e10, 0.005);
        cbm_solve_def sd = cbm_solve_def_default();
        if (!p || cbm_plant_solve(p, &sd, NULL) != CBM_OK) {
            fprintf(stderr, "bench_dyn: no equilibrium for %zu segments\n", sizes[k]);
            return 1;
        }
        double *f = malloc((size_t)modes * sizeof *f);
        double t0 = now(), c0 = cpu();
        cbm_status st = cbm_plant_modes(p, (size_t)modes, f, NULL);
        double tm = now() - t0, cm = cpu() - c0;
        if (st != CBM_OK) {
            fprintf(stderr, "bench_dyn: modes: %s\n", cbm_context_last_error(ctx));
            return 1;
        }
        cbm_motion_def md = cbm_motion_def_default();
        md.dt = 1e-3;
        cbm_motion *m = NULL;
        if (cbm_motion_create(p, &md, &m) != CBM_OK)
            return 1;
        cbm_motion_add_force(m, sizes[k] - 1, (cbm_vec3){0, -1, 0});
        t0 = now();
        c0 = cpu();
        for (int s = 0; s < steps; s++)
            if (cbm_motion_step(m) != CBM_OK)
                return 1;
        double ts = now() - t0, cs = cpu() - c0;
        printf("%zu,%d,%.4f,%.4f,%.6g,%.6g,%d,%.1f,%.4f,%.4f", sizes[k], modes, tm, cm, f[0],
               f[modes - 1], steps, steps / ts, 1e3 * ts / steps, 1e3 * cs / steps);
        if (stream)
            printf(",%.4f", 1e3 * stream_read(STEP_BYTES * sizes[k], &sink));
        if (modal) {
            cbm_motion *mm = NULL;
            md.method = CBM_MOTION_MODAL;
            md.modes = (size_t)modal;
            c0 = cpu();
            if (cbm_motion_create(p, &md, &mm) != CBM_OK) {
                fprintf(stderr, "bench_dyn: modal: %s\n", cbm_context_last_error(ctx));
                return 1;
            }
            double csu = cpu() - c0;
            cbm_motion_add_force(mm, sizes[k] - 1, (cbm_vec3){0, -1, 0});
            int ms = steps < 100000 ? 100000 : steps;
            c0 = cpu();
            for (int s = 0; s < ms; s++)
                if (cbm_motion_step(mm) != CBM_OK)
                    return 1;
            double cms = cpu() - c0;
            c0 = cpu();
            const double *q = cbm_motion_rotations(mm);
            double cf = cpu() - c0;
            sink += q[0];
            printf(",%d,%.4f,%.6f,%.4f", modal, csu, 1e3 * cms / ms, 1e3 * cf);
            cbm_wind_def wd = cbm_wind_def_default();
            cbm_gust_def gd = cbm_gust_def_default();
            gd.intensity = 0.2;
            c0 = cpu();
            if (cbm_motion_set_wind(mm, &wd, 10.0, &gd) != CBM_OK)
                return 1;
            double cws = cpu() - c0;
            c0 = cpu();
            for (int s = 0; s < 10000; s++)
                if (cbm_motion_step(mm) != CBM_OK)
                    return 1;
            printf(",%.4f,%.6f", cws, 1e3 * (cpu() - c0) / 10000);
            cbm_motion_destroy(mm);
        }
        printf("\n");
        fflush(stdout);
        free(f);
        cbm_motion_destroy(m);
        cbm_plant_destroy(p);
        cbm_context_destroy(ctx);
    }
    if (sink == 1.0) /* keeps the sums */
        printf("#\n");
    return 0;
}
