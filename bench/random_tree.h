/* The random branched tree of the mechanics benchmarks and of the tests that split its solve
 * over threads (bench_mech, bench_dyn, bench_fem, tests/test_mech_threads.c): one header both
 * include, so the benches time the tree the tests check. */
#ifndef CBM_RANDOM_TREE_H
#define CBM_RANDOM_TREE_H

#include "cambium/cambium.h"

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>

/* What random_tree_create grows. */
typedef struct random_tree_def {
    size_t n;          /* segments */
    size_t capacity;   /* room for this many segments (at least n) */
    double E;          /* Young's modulus, Pa (shear modulus E/16) */
    double leaf;       /* point mass on every tip, kg */
    uint64_t seed;     /* of the context's generator */
    bool chain;        /* every segment continues the one before: no branches */
    double base_angle; /* the clamp's elevation, rad (pi/2: a vertical trunk) */
    bool depth_first;  /* the same tree numbered in depth-first preorder (siblings in the order
                        * of their numbers above): every parent is the segment before or one of
                        * its ancestors */
} random_tree_def;

/* The benches' tree: seed 7, branched, vertical trunk; n, capacity, E and leaf to set. */
static inline random_tree_def random_tree_def_default(void)
{
    return (random_tree_def){.E = 1e10, .seed = 7, .base_angle = 3.14159265358979323846 / 2};
}

/* A random tree of d->n segments grown from the clamp: segment i continues segment i - 1 with
 * probability 0.8 (always for a chain), otherwise it is a lateral of a uniformly chosen earlier
 * segment (deviation 30-60 degrees, golden-angle divergence); 2 cm segments, pipe-model radii
 * 2 mm x sqrt(segments carried), 700 kg/m^3, d->leaf on every tip. NULL when out of memory. */
static inline cbm_plant *random_tree_create(cbm_context *ctx, const random_tree_def *d)
{
    size_t n = d->n;
    cbm_context_seed(ctx, d->seed);
    int64_t *par = malloc(n * sizeof *par);
    double *count = malloc(n * sizeof *count);
    double *dev = malloc(n * sizeof *dev);        /* a lateral's deviation, rad; 0: continues */
    size_t *ord = malloc(n * sizeof *ord);        /* the numbering: segment k is ord[k] above */
    int64_t *newid = malloc(n * sizeof *newid);   /* and back */
    size_t *first = calloc(n + 1, sizeof *first); /* children of i: kids[first[i] .. first[i+1]) */
    size_t *kids = malloc(n * sizeof *kids);
    unsigned char *seen = calloc(n, 1); /* children seen so far: continuation or lateral */
    cbm_plant *p = NULL;
    cbm_plant_def pd = cbm_plant_def_default();
    pd.capacity = d->capacity;
    pd.base_orientation = cbm_mech_clamp_orientation(d->base_angle);
    if (!par || !count || !dev || !ord || !newid || !first || !kids || !seen ||
        cbm_plant_create(ctx, &pd, &p) != CBM_OK)
        goto done;
    par[0] = -1;
    for (size_t i = 1; i < n; i++)
        par[i] = d->chain || cbm_context_uniform(ctx) < 0.8
                     ? (int64_t)i - 1
                     : (int64_t)(cbm_context_uniform(ctx) * (double)i);
    for (size_t i = 0; i < n; i++)
        count[i] = 1;
    for (size_t i = n; i-- > 1;)
        count[par[i]] += count[i];
    for (size_t i = 0; i < n; i++) {
        dev[i] = 0.0;
        if (i > 0 && seen[par[i]])
            dev[i] = (30 + 30 * cbm_context_uniform(ctx)) * 3.14159265358979323846 / 180;
        if (i > 0)
            seen[par[i]] = 1;
        ord[i] = i;
    }
    if (d->depth_first && n > 0) {
        /* children lists in increasing number, then a preorder with an explicit stack (kept in
         * newid, free until filled) that takes the siblings in that order */
        for (size_t i = 1; i < n; i++)
            first[par[i] + 1]++;
        for (size_t i = 0; i < n; i++)
            first[i + 1] += first[i];
        for (size_t i = 1; i < n; i++)
            kids[first[par[i]]++] = i;
        for (size_t i = n; i-- > 0;) /* back to the starts */
            first[i + 1] = first[i];
        first[0] = 0;
        size_t top = 0, k = 0;
        int64_t *stack = newid;
        stack[top++] = 0;
        while (top > 0) {
            size_t i = (size_t)stack[--top];
            ord[k++] = i;
            for (size_t c = first[i + 1]; c-- > first[i];)
                stack[top++] = (int64_t)kids[c];
        }
    }
    for (size_t k = 0; k < n; k++)
        newid[ord[k]] = (int64_t)k;
    for (size_t k = 0; k < n && p; k++) {
        size_t i = ord[k];
        cbm_segment_def s = cbm_segment_def_default();
        s.parent = par[i] < 0 ? -1 : newid[par[i]];
        s.length = 0.02;
        s.core.a = s.core.b = 0.002 * sqrt(count[i]);
        s.core.youngs_modulus = d->E;
        s.core.shear_modulus = d->E / 16;
        s.core.density = 700;
        if (dev[i] != 0.0) {
            s.divergence = 2.39996 * (double)i;
            s.deviation = dev[i];
            s.roll = -s.divergence;
        }
        s.point_mass = count[i] == 1 ? d->leaf : 0.0;
        if (cbm_plant_add_segment(p, &s, NULL) != CBM_OK) {
            cbm_plant_destroy(p);
            p = NULL;
        }
    }
done:
    free(seen);
    free(kids);
    free(first);
    free(newid);
    free(ord);
    free(dev);
    free(par);
    free(count);
    return p;
}

#endif
