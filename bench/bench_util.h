/* What the benchmarks share: the clocks and the random branched tree of the mechanics benches. */
#ifndef CBM_BENCH_UTIL_H
#define CBM_BENCH_UTIL_H

#include "cambium/cambium.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <time.h>

#ifndef PI
#define PI 3.14159265358979323846
#endif

/* Wall-clock seconds (monotonic). */
static inline double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* CPU time of the process: on a shared machine the wall clock also counts the other processes */
static inline double cpu(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* A random branched tree of n segments grown from a vertical trunk (seed 7 of the context's
 * generator): segment i continues segment i - 1 with probability 0.8, otherwise it is a lateral
 * of a uniformly chosen earlier segment (deviation 30-60 degrees, golden-angle divergence);
 * 2 cm segments, pipe-model radii 2 mm x sqrt(segments carried), Young's modulus E (shear E/16),
 * 700 kg/m^3, a point mass `leaf` (kg) on every tip. The plant has room for `capacity` segments.
 * NULL when out of memory. */
static inline cbm_plant *bench_random_tree(cbm_context *ctx, size_t n, size_t capacity, double E,
                                           double leaf)
{
    cbm_context_seed(ctx, 7);
    int64_t *par = malloc(n * sizeof *par);
    double *count = malloc(n * sizeof *count);
    unsigned char *seen = calloc(n, 1); /* children seen so far: continuation or lateral */
    cbm_plant *p = NULL;
    cbm_plant_def pd = cbm_plant_def_default();
    pd.capacity = capacity;
    pd.base_orientation = cbm_mech_clamp_orientation(PI / 2);
    if (!par || !count || !seen || cbm_plant_create(ctx, &pd, &p) != CBM_OK)
        goto done;
    par[0] = -1;
    for (size_t i = 1; i < n; i++)
        par[i] = cbm_context_uniform(ctx) < 0.8 ? (int64_t)i - 1
                                                : (int64_t)(cbm_context_uniform(ctx) * (double)i);
    for (size_t i = 0; i < n; i++)
        count[i] = 1;
    for (size_t i = n; i-- > 1;)
        count[par[i]] += count[i];
    for (size_t i = 0; i < n && p; i++) {
        cbm_segment_def d = cbm_segment_def_default();
        d.parent = par[i];
        d.length = 0.02;
        d.core.a = d.core.b = 0.002 * sqrt(count[i]);
        d.core.youngs_modulus = E;
        d.core.shear_modulus = E / 16;
        d.core.density = 700;
        if (i > 0 && seen[par[i]]) {
            d.divergence = 2.39996 * (double)i;
            d.deviation = (30 + 30 * cbm_context_uniform(ctx)) * PI / 180;
            d.roll = -d.divergence;
        }
        if (i > 0)
            seen[par[i]] = 1;
        d.point_mass = count[i] == 1 ? leaf : 0.0;
        if (cbm_plant_add_segment(p, &d, NULL) != CBM_OK) {
            cbm_plant_destroy(p);
            p = NULL;
        }
    }
done:
    free(seen);
    free(par);
    free(count);
    return p;
}

#endif
