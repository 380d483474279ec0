/* What the benchmarks share: the clocks and the random branched tree of the mechanics benches
 * (random_tree.h, which the tests share). */
#ifndef CBM_BENCH_UTIL_H
#define CBM_BENCH_UTIL_H

#include "cambium/cambium.h"
#include "random_tree.h"

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

/* The random branched tree of random_tree.h (seed 7, vertical trunk) of n segments, Young's
 * modulus E (Pa), a point mass `leaf` (kg) on every tip, room for `capacity` segments. NULL when
 * out of memory. */
static inline cbm_plant *bench_random_tree(cbm_context *ctx, size_t n, size_t capacity, double E,
                                           double leaf)
{
    random_tree_def d = random_tree_def_default();
    d.n = n;
    d.capacity = capacity;
    d.E = E;
    d.leaf = leaf;
    return random_tree_create(ctx, &d);
}

#endif
