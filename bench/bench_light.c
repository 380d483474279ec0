/* Benchmark of the light pass (cbm_light_intercept): a stand of n random leaves (0.1 m squares
 * tilted up to 60°, random azimuth) filling a 10 m high canopy whose ground area grows with n so
 * that the leaf area index stays 4 (more leaves = more trees, the case of a stand), under the
 * default SOC sky (6 x 12 sectors) and samples x samples points per leaf. Prints one CSV line
 * per run: leaves, samples, sources, threads, rays, wall-clock and CPU seconds, rays per second
 * (wall-clock and CPU), CPU ns per leaf, mean light per unit leaf area.
 * Usage: bench_light [max_leaves (default 1000000)] [samples (default 2)] [threads (0: all)]
 *                    [periodic: the stand's square is the tile of an endless stand, so every
 *                     leaf has the same surroundings whatever n; open: not]
 *                    [min_leaves (default 1000)]
 * n runs over 1e3, 3e3, 1e4, ... up to max_leaves (from min_leaves on). */
#define _POSIX_C_SOURCE 200809L
#include "cambium/cambium.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* CPU time of the process (all threads): on a shared machine wall-clock rates say more about
 * the other users than about the code */
static double cpu_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double urand(uint64_t *x)
{
    *x = *x * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(*x >> 11) / 9007199254740992.0;
}

static void stand(cbm_light_leaf *l, size_t n)
{
    double side = sqrt((double)n * 0.01 / 4.0);
    uint64_t x = 12345;
    for (size_t i = 0; i < n; i++) {
        cbm_vec3 c = {side * urand(&x), 10.0 * urand(&x), side * urand(&x)};
        double tilt = acos(1.0 - urand(&x) * 0.5), az = 6.283185307179586 * urand(&x);
        /* unit vectors in the leaf plane: e1 horizontal, e2 up the slope */
        cbm_vec3 e1 = {cos(az), 0, sin(az)};
        cbm_vec3 e2 = {-sin(az) * cos(tilt), sin(tilt), cos(az) * cos(tilt)};
        const double su[4] = {-0.05, 0.05, 0.05, -0.05}, sv[4] = {-0.05, -0.05, 0.05, 0.05};
        for (int k = 0; k < 4; k++)
            l[i].p[k] =
                (cbm_vec3){c.x + su[k] * e1.x + sv[k] * e2.x, c.y + su[k] * e1.y + sv[k] * e2.y,
                           c.z + su[k] * e1.z + sv[k] * e2.z};
        l[i].plant = (uint32_t)(i / 1000);
    }
}

int main(int argc, char **argv)
{
    size_t max = argc > 1 ? (size_t)atof(argv[1]) : 1000000;
    int samples = argc > 2 ? atoi(argv[2]) : 2;
    int threads = argc > 3 ? atoi(argv[3]) : 0;
    bool periodic = argc > 4 && !strcmp(argv[4], "periodic");
    double min = argc > 5 ? atof(argv[5]) : 1000;
    cbm_context_def cd = cbm_context_def_default();
    cbm_context *ctx = NULL;
    if (cbm_context_create(&cd, &ctx) != CBM_OK)
        return 1;
    printf("edge,leaves,samples,sources,threads,rays,seconds,cpu_seconds,rays_per_s,rays_per_cpu_s,"
           "cpu_ns_per_leaf,mean_light\n");
    for (double nd = 1000; nd <= (double)max * 1.0001; nd *= sqrt(10.0)) {
        size_t n =
            (size_t)llround(nd / pow(10, floor(log10(nd)))) * (size_t)pow(10, floor(log10(nd)));
        if ((double)n < min * 0.9999)
            continue;
        cbm_light_leaf *l = malloc(n * sizeof *l);
        double *a = malloc(n * sizeof *a);
        if (!l || !a) {
            free(l);
            free(a);
            cbm_context_destroy(ctx);
            return 1;
        }
        stand(l, n);
        cbm_light_def d = cbm_light_def_default();
        d.samples = samples;
        d.threads = threads;
        if (periodic) {
            double side = sqrt((double)n * 0.01 / 4.0);
            d.edge = CBM_LIGHT_EDGE_PERIODIC;
            d.field_max[0] = d.field_max[1] = side;
        }
        cbm_light_stats st;
        double c0 = cpu_now();
        cbm_status s = cbm_light_intercept(ctx, &d, l, n, NULL, 0, a, &st);
        double cpu = cpu_now() - c0;
        if (s != CBM_OK) {
            fprintf(stderr, "bench_light: %s\n", cbm_context_last_error(ctx));
            return 1;
        }
        printf("%s,%zu,%d,%zu,%d,%zu,%.4f,%.4f,%.4g,%.4g,%.1f,%.4f\n",
               periodic ? "periodic" : "open", n, samples, st.sources, threads, st.rays, st.seconds,
               cpu, (double)st.rays / st.seconds, (double)st.rays / cpu, 1e9 * cpu / (double)n,
               st.total / st.leaf_area);
        fflush(stdout);
        free(l);
        free(a);
    }
    cbm_context_destroy(ctx);
    return 0;
}
