/* Benchmark of the built-in tree models (docs/performance.md, "built-in tree models"): the
 * default 10-year fruit tree end to end, split into equilibrium, rings and ageing, and growth
 * (apices, spring pass, bookkeeping), then a large tree: the fruit tree with the listing's shoot
 * threshold (0.03, which grows far more shoots) grown until it has at least --big N segments,
 * and the next --steps growth steps timed one by one (segments, rings, passes, seconds per phase:
 * equilibrium, rings and ageing, the rest), then the scene of the large tree (interpretation).
 * Writes a CSV (one row per measured step) and prints a summary.
 *
 * usage: bench_tree [--big N] [--steps K] [--out FILE.csv]
 */
#define _POSIX_C_SOURCE 200809L
#include "cambium/cambium.h"
#include "bench_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static size_t total_rings(const cbm_plant *p)
{
    size_t r = 0;
    for (size_t i = 0; i < cbm_plant_segment_count(p); i++)
        r += cbm_plant_ring_count(p, i);
    return r;
}

static int fail(cbm_context *ctx, const char *what)
{
    fprintf(stderr, "bench_tree: %s: %s\n", what, cbm_context_last_error(ctx));
    return 1;
}

int main(int argc, char **argv)
{
    long big = 100000, steps = 10;
    const char *out = "bench_tree.csv";
    for (int i = 1; i + 1 < argc; i += 2) {
        if (!strcmp(argv[i], "--big"))
            big = atol(argv[i + 1]);
        else if (!strcmp(argv[i], "--steps"))
            steps = atol(argv[i + 1]);
        else if (!strcmp(argv[i], "--out"))
            out = argv[i + 1];
    }
    cbm_context_def cd = cbm_context_def_default();
    cbm_context *ctx = NULL;
    if (cbm_context_create(&cd, &ctx) != CBM_OK)
        return 1;
    /* 1. the fruit tree with the thesis' constants, 10 years (the figures of
     * docs/performance.md; the real-wood default is `cambium grow --timing`) */
    cbm_tree_def d;
    if (cbm_tree_def_builtin(ctx, "fruit-tree-thesis", &d) != CBM_OK)
        return fail(ctx, "fruit-tree-thesis");
    cbm_tree *t = NULL;
    double t0 = now();
    if (cbm_tree_create(ctx, &d, &t) != CBM_OK || cbm_tree_run(t) != CBM_OK)
        return fail(ctx, "fruit tree");
    double total = now() - t0, solve = 0, rings = 0;
    size_t passes = 0, gsteps = 0;
    for (int y = 1; y <= cbm_tree_years(t); y++) {
        const cbm_tree_summary *s = cbm_tree_summary_of(t, y);
        solve += s->seconds_solve;
        rings += s->seconds_rings;
        passes += s->passes;
        gsteps += s->growth_steps;
    }
    cbm_scene *sc = NULL;
    double ts = now();
    if (cbm_scene_create(ctx, &sc) != CBM_OK || cbm_tree_to_scene(t, sc, 12, true) != CBM_OK)
        return fail(ctx, "scene");
    double tscene = now() - ts;
    printf("fruit tree, 10 years: %zu segments, %zu growth steps, %.3f s (equilibrium %.3f s in "
           "%zu passes = %.1f us/pass, rings and ageing %.3f s, growth and the rest %.3f s); "
           "scene %.3f s, %zu triangles\n",
           cbm_plant_segment_count(cbm_tree_plant(t)), gsteps, total, solve, passes,
           1e6 * solve / (double)(passes ? passes : 1), rings, total - solve - rings, tscene,
           cbm_scene_triangle_count(sc));
    cbm_scene_destroy(sc);
    cbm_tree_destroy(t);

    /* 2. a large tree */
    FILE *f = fopen(out, "w");
    if (!f) {
        perror(out);
        return 1;
    }
    fprintf(f, "step,season,segments,rings,passes,seconds,seconds_equilibrium,seconds_rings,"
               "seconds_rest\n");
    if (cbm_tree_def_builtin(ctx, "fruit-tree-thesis", &d) != CBM_OK)
        return fail(ctx, "fruit-tree-thesis");
    d.shoot_vigour = 0.03;
    d.years = 1000;
    if (cbm_tree_create(ctx, &d, &t) != CBM_OK)
        return fail(ctx, "big tree");
    double tg = now();
    while (cbm_plant_segment_count(cbm_tree_plant(t)) < (size_t)big)
        if (cbm_tree_step(t, NULL) != CBM_OK)
            return fail(ctx, "growing the big tree");
    printf("large tree: %zu segments, %zu rings after %d years in %.1f s; library memory %.0f MB "
           "(peak %.0f MB)\n",
           cbm_plant_segment_count(cbm_tree_plant(t)), total_rings(cbm_tree_plant(t)),
           cbm_tree_years(t), now() - tg, (double)cbm_context_bytes(ctx) / 1e6,
           (double)cbm_context_peak_bytes(ctx) / 1e6);
    double sum = 0, sum_solve = 0, sum_rings = 0;
    for (long k = 0; k < steps; k++) {
        cbm_tree_summary before = *cbm_tree_summary_current(t);
        int y0 = cbm_tree_years(t);
        cbm_tree_season season = cbm_tree_current_season(t);
        double a = now();
        if (cbm_tree_step(t, NULL) != CBM_OK)
            return fail(ctx, "step");
        double dt = now() - a;
        const cbm_tree_summary *c = cbm_tree_summary_current(t);
        size_t dp = cbm_tree_years(t) == y0 ? c->passes - before.passes : c->passes;
        double dsolve = cbm_tree_years(t) == y0 ? c->seconds_solve - before.seconds_solve : 0;
        double drings = cbm_tree_years(t) == y0 ? c->seconds_rings - before.seconds_rings : 0;
        sum += dt;
        sum_solve += dsolve;
        sum_rings += drings;
        size_t nseg = cbm_plant_segment_count(cbm_tree_plant(t));
        size_t nring = total_rings(cbm_tree_plant(t));
        fprintf(f, "%ld,%s,%zu,%zu,%zu,%.6f,%.6f,%.6f,%.6f\n", k,
                season == CBM_TREE_SUMMER ? "summer" : "winter", nseg, nring, dp, dt, dsolve,
                drings, dt - dsolve - drings);
        printf("  step %ld (%s): %zu segments, %zu rings, %zu passes, %.3f s (equilibrium %.3f s, "
               "rings %.3f s, the rest %.3f s)\n",
               k, season == CBM_TREE_SUMMER ? "summer" : "winter", nseg, nring, dp, dt, dsolve,
               drings, dt - dsolve - drings);
    }
    printf("large tree: %.2f growth steps per second (equilibrium %.0f %%, rings %.0f %% of the "
           "time)\n",
           (double)steps / sum, 100 * sum_solve / sum, 100 * sum_rings / sum);
    fclose(f);
    ts = now();
    if (cbm_scene_create(ctx, &sc) != CBM_OK || cbm_tree_to_scene(t, sc, 8, true) != CBM_OK)
        return fail(ctx, "scene of the large tree");
    printf("large tree: scene (8 sides) %.3f s, %zu triangles; library peak %.0f MB\n", now() - ts,
           cbm_scene_triangle_count(sc), (double)cbm_context_peak_bytes(ctx) / 1e6);
    cbm_scene_destroy(sc);
    cbm_tree_destroy(t);
    cbm_context_destroy(ctx);
    return 0;
}
