/* The built-in fruit tree (Taylor-Hell 2005 A.1) and the aspen of ch. 7, measured against what
 * the thesis says they do: resource conservation at every node and the fairness identities
 * (4.9-4.19); spring-back when leaves and fruit fall (Fig. 4.1); reaction wood straightening a
 * leaning stem (Figs. 8.6-8.7); breakage under a low modulus of rupture only (Fig. 8.9); the
 * crooked aspen lower and wider than the wild type with relay shoots (ch. 7); F = 0.2 taller
 * and sparser than F = 1 (Fig. 4.7); determinism (hash of the segments table); the parameter
 * reader's errors. Runs are short: each property shows within a few years. */
#include "test.h"

#include "cambium/cambium.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static cbm_tree *grow(cbm_context *ctx, const char *model, int years, const char *const *set)
{
    cbm_tree_def d;
    CHECK_OK(cbm_tree_def_builtin(ctx, model, &d));
    for (int k = 0; set && set[k]; k += 2)
        CHECK_OK(cbm_tree_def_set(ctx, &d, set[k], set[k + 1]));
    d.years = years;
    cbm_tree *t = NULL;
    CHECK_OK(cbm_tree_create(ctx, &d, &t));
    if (t)
        CHECK_OK(cbm_tree_run(t));
    return t;
}

TEST(tree_func_and_fairness_identities)
{
    cbm_tree_func f = {3, {0, 0.5, 1}, {0, 0.4, 1}};
    CHECK_NEAR(cbm_tree_func_eval(&f, -1), 0, 0);
    CHECK_NEAR(cbm_tree_func_eval(&f, 0.25), 0.2, 1e-15);
    CHECK_NEAR(cbm_tree_func_eval(&f, 0.75), 0.7, 1e-15);
    CHECK_NEAR(cbm_tree_func_eval(&f, 7), 1, 0);
    for (int k = 0; k <= 20; k++) {
        double p = k / 20.0;
        /* F = 1 is the identity; a share of 1/2 is fair whatever F */
        CHECK_NEAR(cbm_tree_fairness(p, 1.0), p, 1e-15);
        for (double F = 0; F <= 1.0; F += 0.25) {
            double q = cbm_tree_fairness(p, F);
            CHECK(q >= 0 && q <= 1);
            if (p < 0.5)
                CHECK_NEAR(q, F * p, 1e-15); /* 4.18: the small share shrinks */
            else if (p > 0.5)
                CHECK_NEAR(1 - q, F * (1 - p), 1e-15); /* 4.19 */
            else
                CHECK_NEAR(q, 0.5, 0);
        }
    }
    /* F = 0: winner takes all */
    CHECK_NEAR(cbm_tree_fairness(0.3, 0.0), 0.0, 0);
    CHECK_NEAR(cbm_tree_fairness(0.7, 0.0), 1.0, 0);
}

/* After a spring pass every node with a child that takes resources passes on exactly what it
 * received: the children's vigour plus the sink taken at the node equal the node's vigour
 * (4.10-4.11, 4.14, 4.16). */
TEST(tree_resource_conservation_every_node)
{
    cbm_context *ctx = test_ctx();
    cbm_tree *t = grow(ctx, "fruit-tree-thesis", 4, NULL);
    const cbm_plant *p = cbm_tree_plant(t);
    size_t n = cbm_plant_segment_count(p), nodes = 0, sinks = 0;
    const int64_t *par = cbm_plant_parents(p);
    double *sum = calloc(n, sizeof *sum);
    int *kids = calloc(n, sizeof *kids);
    for (size_t i = 0; i < n; i++) {
        cbm_tree_segment s;
        CHECK_OK(cbm_tree_segment_info(t, i, &s));
        CHECK(s.vigour >= 0.0);
        if (par[i] >= 0) {
            sum[par[i]] += s.vigour;
            kids[par[i]] += !s.aborted; /* an aborted bud takes nothing */
        }
    }
    for (size_t i = 0; i < n; i++) {
        if (!kids[i])
            continue;
        cbm_tree_segment s;
        CHECK_OK(cbm_tree_segment_info(t, i, &s));
        CHECK_NEAR(sum[i] + s.sink, s.vigour, 1e-12 * (1 + s.vigour));
        nodes++;
        sinks += s.sink > 0.0;
    }
    printf("%zu nodes conserve their vigour, %zu with sinks\n", nodes, sinks);
    CHECK(nodes > 50);
    CHECK(sinks > 5);
    /* the base supply (K a)^d (4.12) */
    cbm_segment_state b;
    CHECK_OK(cbm_plant_segment(p, 0, &b));
    cbm_tree_segment s0;
    CHECK_OK(cbm_tree_segment_info(t, 0, &s0));
    CHECK_REL(s0.vigour, pow(800.0 * b.a, 1.1), 1e-12);
    free(sum);
    free(kids);
    cbm_tree_destroy(t);
    test_ctx_end(ctx);
}

/* Fig. 4.1: when the leaves and fruit fall in winter the branch tips rise. */
TEST(tree_spring_back_after_shedding)
{
    cbm_context *ctx = test_ctx();
    const char *set[] = {"first_fruit_year", "1", "modulus_of_rupture", "2.9e7", NULL};
    cbm_tree *t = grow(ctx, "fruit-tree-thesis", 3, set);
    for (int y = 2; y <= 3; y++) {
        const cbm_tree_summary *s = cbm_tree_summary_of(t, y);
        printf("year %d: %zu fruit, mean tip height loaded %.4f m, unloaded %.4f m\n", y, s->fruit,
               s->tip_height_loaded, s->tip_height_unloaded);
        CHECK(s->fruit > 0);
        CHECK(s->tip_height_unloaded > s->tip_height_loaded + 0.005);
    }
    cbm_tree_destroy(t);
    test_ctx_end(ctx);
}

/* Figs. 8.6-8.7: a stem started 30 degrees from the vertical; with reaction wood its lean falls
 * over the years, without it the stem sags further. */
TEST(tree_reaction_wood_corrects_lean)
{
    cbm_context *ctx = test_ctx();
    const char *rw[] = {"elevation", "60", "fruit_mass", "0", NULL};
    const char *none[] = {"elevation", "60", "fruit_mass", "0", "reaction_threshold", "0", NULL};
    cbm_tree *a = grow(ctx, "fruit-tree-thesis", 3, rw);
    cbm_tree *b = grow(ctx, "fruit-tree-thesis", 3, none);
    for (int y = 1; y <= 3; y++) {
        double la = cbm_tree_summary_of(a, y)->lean, lb = cbm_tree_summary_of(b, y)->lean;
        printf("year %d: lean %.2f deg with reaction wood, %.2f deg without (start 30)\n", y, la,
               lb);
        CHECK(la < 25.0);
        CHECK(lb > 30.0);
    }
    CHECK(cbm_tree_summary_of(a, 3)->reaction_segments > 0);
    CHECK_EQ_INT(cbm_tree_summary_of(b, 3)->reaction_segments, 0);
    cbm_tree_destroy(a);
    cbm_tree_destroy(b);
    test_ctx_end(ctx);
}

/* Fig. 8.9: a low modulus of rupture breaks fruit-laden branches that a high one keeps. */
TEST(tree_low_mor_breaks_high_keeps)
{
    cbm_context *ctx = test_ctx();
    cbm_tree *lo = grow(ctx, "fruit-tree-thesis-low-mor", 4, NULL);
    cbm_tree *hi = grow(ctx, "fruit-tree-thesis-high-mor", 4, NULL);
    size_t blo = 0, bhi = 0;
    for (int y = 1; y <= 4; y++) {
        blo += cbm_tree_summary_of(lo, y)->breaks;
        bhi += cbm_tree_summary_of(hi, y)->breaks;
    }
    printf("breaks in 4 years: %zu with low MOR, %zu with high MOR\n", blo, bhi);
    CHECK(blo >= 5);
    CHECK_EQ_INT(bhi, 0);
    cbm_tree_destroy(lo);
    cbm_tree_destroy(hi);
    test_ctx_end(ctx);
}

/* Ch. 7: the crooked aspen (supple wood, weak and fading tropism, no reaction wood) is lower and
 * wider than the wild type, and grows relay shoots from its bent branches. */
TEST(tree_crooked_poplar_lower_wider_relay)
{
    cbm_context *ctx = test_ctx();
    cbm_tree *w = grow(ctx, "poplar-wild-thesis", 5, NULL);
    cbm_tree *c = grow(ctx, "poplar-crooked-thesis", 5, NULL);
    const cbm_tree_summary *sw = cbm_tree_summary_of(w, 5), *sc = cbm_tree_summary_of(c, 5);
    size_t relay = 0;
    for (int y = 1; y <= 5; y++)
        relay += cbm_tree_summary_of(c, y)->relay_shoots;
    printf("wild: height %.3f m, crown %.3f m; crooked: height %.3f m, crown %.3f m, %zu relay "
           "shoots\n",
           sw->height, sw->crown_width, sc->height, sc->crown_width, relay);
    CHECK(sc->height < 0.8 * sw->height);
    CHECK(sc->crown_width > sw->crown_width);
    CHECK(sc->crown_width / sc->height > 2.0 * sw->crown_width / sw->height);
    CHECK(relay >= 1);
    cbm_tree_destroy(w);
    cbm_tree_destroy(c);
    test_ctx_end(ctx);
}

/* Fig. 4.7: F = 0.2 grows a taller, sparser tree than F = 1. */
TEST(tree_unfair_taller_sparser)
{
    cbm_context *ctx = test_ctx();
    cbm_tree *f1 = grow(ctx, "fruit-tree-thesis", 3, NULL);
    cbm_tree *f02 = grow(ctx, "fruit-tree-thesis-unfair", 3, NULL);
    const cbm_tree_summary *a = cbm_tree_summary_of(f1, 3), *b = cbm_tree_summary_of(f02, 3);
    printf("F = 1: %zu segments, height %.3f m; F = 0.2: %zu segments, height %.3f m\n",
           a->segments, a->height, b->segments, b->height);
    CHECK(b->height > 1.1 * a->height);
    CHECK(b->segments < a->segments * 3 / 4);
    cbm_tree_destroy(f1);
    cbm_tree_destroy(f02);
    test_ctx_end(ctx);
}

static uint64_t hash_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    uint64_t h = 1469598103934665603ull;
    int c;
    if (!f)
        return 0;
    while ((c = fgetc(f)) != EOF)
        h = (h ^ (uint64_t)(unsigned char)c) * 1099511628211ull;
    fclose(f);
    return h;
}

static uint64_t run_hash(cbm_context *ctx, const char *seed, const char *path)
{
    const char *set[] = {"seed", seed, NULL};
    cbm_tree *t = grow(ctx, "fruit-tree", 3, set);
    CHECK_OK(cbm_write_segments_csv(ctx, cbm_tree_plant(t), path));
    cbm_tree_destroy(t);
    return hash_file(path);
}

TEST(tree_deterministic_hash)
{
    cbm_context *ctx = test_ctx();
    char path[1024];
    snprintf(path, sizeof path, "%s/segments.csv", test_tmp_dir());
    uint64_t a = run_hash(ctx, "7", path), b = run_hash(ctx, "7", path);
    uint64_t c = run_hash(ctx, "8", path);
    printf("segments table hash: seed 7 %016llx twice %016llx, seed 8 %016llx\n",
           (unsigned long long)a, (unsigned long long)b, (unsigned long long)c);
    CHECK(a != 0);
    CHECK(a == b);
    CHECK(a != c);
    test_ctx_end(ctx);
}

TEST(tree_parameter_file)
{
    cbm_context *ctx = test_ctx();
    cbm_tree_def d = cbm_tree_def_default();
    const char *good = "# a comment\n"
                       "fairness = 0.2   # trailing comment\n"
                       "phyllotaxis = 90\n"
                       "form = crooked\n"
                       "func NUMBUDS_VIGOUR = 0:0 0.5:0.4 1:1\n";
    CHECK_OK(cbm_tree_def_parse(ctx, &d, good, strlen(good), "good.tree"));
    CHECK_NEAR(d.fairness, 0.2, 0);
    CHECK_NEAR(d.phyllotaxis, 90 * 3.14159265358979323846 / 180, 1e-15);
    CHECK(d.form == CBM_TREE_CROOKED);
    CHECK_EQ_INT(d.numbuds_vigour.n, 3);
    CHECK_NEAR(cbm_tree_func_eval(&d.numbuds_vigour, 0.25), 0.2, 1e-15);
    /* the formatted parameters read back to the same text */
    size_t need = cbm_tree_def_format(&d, NULL, 0);
    char *t1 = malloc(need + 1), *t2 = malloc(need + 1);
    cbm_tree_def_format(&d, t1, need + 1);
    cbm_tree_def e = cbm_tree_def_default();
    CHECK_OK(cbm_tree_def_parse(ctx, &e, t1, strlen(t1), "formatted"));
    cbm_tree_def_format(&e, t2, need + 1);
    CHECK(!strcmp(t1, t2));
    free(t1);
    free(t2);
    /* errors name file:line:col; every bad line is reported */
    const char *bad = "fairness = 0.5\n"
                      "  wobble = 3\n"
                      "fairness = 2\n"
                      "func NUMBUDS_VIGOUR = 0:0 0:1\n"
                      "years 4\n";
    cbm_context_clear_errors(ctx);
    CHECK_STATUS(cbm_tree_def_parse(ctx, &d, bad, strlen(bad), "bad.tree"), CBM_E_SYNTAX);
    CHECK_EQ_INT(cbm_context_error_count(ctx), 4);
    printf("last error: %s\n", cbm_context_last_error(ctx));
    CHECK_STATUS(cbm_tree_def_set(ctx, &d, "nonsense", "1"), CBM_E_NOT_FOUND);
    CHECK_STATUS(cbm_tree_def_set(ctx, &d, "fairness", "abc"), CBM_E_INVALID);
    CHECK(strstr(cbm_context_last_error(ctx), "fairness") != NULL);
    cbm_tree_def out;
    CHECK_STATUS(cbm_tree_def_builtin(ctx, "no-such-tree", &out), CBM_E_NOT_FOUND);
    /* every built-in reads and the shipped files say the same as the built-ins */
    for (const char *const *n = cbm_tree_builtin_names(); *n; n++) {
        cbm_tree_def bi;
        CHECK_OK(cbm_tree_def_builtin(ctx, *n, &bi));
        char path[1024];
        snprintf(path, sizeof path, "%s/models/%s.tree", test_source_dir(), *n);
        FILE *f = fopen(path, "rb");
        if (!f)
            continue; /* the figure variants are built-ins only */
        fclose(f);
        cbm_tree_def fd = cbm_tree_def_default();
        CHECK_OK(cbm_tree_def_read(ctx, &fd, path));
        size_t na = cbm_tree_def_format(&bi, NULL, 0), nb = cbm_tree_def_format(&fd, NULL, 0);
        char *ta = malloc(na + 1), *tb = malloc(nb + 1);
        cbm_tree_def_format(&bi, ta, na + 1);
        cbm_tree_def_format(&fd, tb, nb + 1);
        CHECK_MSG(!strcmp(ta, tb), "%s differs from the built-in %s", path, *n);
        free(ta);
        free(tb);
    }
    test_ctx_end(ctx);
}

static cbm_status oom_year(cbm_context *ctx, void *ud)
{
    (void)ud;
    cbm_tree_def d = cbm_tree_def_default();
    d.years = 1;
    d.first_fruit_year = 1;
    cbm_tree *t = NULL;
    cbm_status s = cbm_tree_create(ctx, &d, &t);
    if (s == CBM_OK)
        s = cbm_tree_run(t);
    cbm_scene *sc = NULL;
    if (s == CBM_OK)
        s = cbm_scene_create(ctx, &sc);
    if (s == CBM_OK)
        s = cbm_tree_to_scene(t, sc, 6, true);
    cbm_scene_destroy(sc);
    cbm_tree_destroy(t);
    return s;
}

TEST(tree_out_of_memory)
{
    int runs = test_oom_loop(oom_year, NULL);
    printf("%d out-of-memory runs\n", runs);
    CHECK(runs > 10);
}

/* A tree whose base breaks (a tiny modulus of rupture) is gone: the following years run on an
 * empty plant without errors, and the scene is empty but valid. */
TEST(tree_broken_at_base)
{
    cbm_context *ctx = test_ctx();
    const char *set[] = {"modulus_of_rupture", "1000", NULL};
    cbm_tree *t = grow(ctx, "fruit-tree-thesis", 3, set);
    CHECK_EQ_INT(cbm_plant_segment_count(cbm_tree_plant(t)), 0);
    CHECK(cbm_tree_summary_of(t, 1)->breaks >= 1);
    CHECK_EQ_INT(cbm_tree_summary_of(t, 3)->segments, 0);
    cbm_scene *sc = NULL;
    CHECK_OK(cbm_scene_create(ctx, &sc));
    CHECK_OK(cbm_tree_to_scene(t, sc, 6, false));
    CHECK_EQ_INT(cbm_scene_part_count(sc), 0);
    cbm_scene_destroy(sc);
    cbm_tree_destroy(t);
    test_ctx_end(ctx);
}

/* §4.3.2: branches that lay no ring for years_to_shed years are shed; with 0 none are. */
TEST(tree_shedding_unproductive)
{
    cbm_context *ctx = test_ctx();
    const char *on[] = {"years_to_shed", "2", NULL};
    cbm_tree *a = grow(ctx, "fruit-tree-thesis", 5, on);
    cbm_tree *b = grow(ctx, "fruit-tree-thesis", 5, NULL);
    size_t sa = 0, sb = 0;
    for (int y = 1; y <= 5; y++) {
        sa += cbm_tree_summary_of(a, y)->shed;
        sb += cbm_tree_summary_of(b, y)->shed;
        if (y < 3) /* a branch needs two full unproductive years */
            CHECK_EQ_INT(cbm_tree_summary_of(a, y)->shed, 0);
    }
    printf("branches shed in 5 years: %zu (years_to_shed = 2), %zu (never)\n", sa, sb);
    CHECK(sa > 0);
    CHECK_EQ_INT(sb, 0);
    cbm_tree_destroy(a);
    cbm_tree_destroy(b);
    test_ctx_end(ctx);
}

/* ---- the real-wood models over seeds: distributions, not one seed's numbers ---- */

typedef struct seed_run {
    cbm_tree_summary last; /* the last year */
    size_t peak;           /* most segments in any year */
    size_t breaks;         /* in all years */
    double max_aspect;     /* largest a/b of any segment at the end */
} seed_run;

static seed_run run_seed(cbm_context *ctx, const char *model, int years, unsigned seed)
{
    char sd[32];
    snprintf(sd, sizeof sd, "%u", seed);
    const char *set[] = {"seed", sd, NULL};
    cbm_tree *t = grow(ctx, model, years, set);
    seed_run r;
    memset(&r, 0, sizeof r);
    for (int y = 1; y <= years; y++) {
        const cbm_tree_summary *s = cbm_tree_summary_of(t, y);
        r.peak = s->segments > r.peak ? s->segments : r.peak;
        r.breaks += s->breaks;
        r.last = *s;
    }
    const cbm_plant *p = cbm_tree_plant(t);
    for (size_t i = 0; i < cbm_plant_segment_count(p); i++) {
        cbm_segment_state st;
        CHECK_OK(cbm_plant_segment(p, i, &st));
        double k = st.a > st.b ? st.a / st.b : st.b / st.a;
        r.max_aspect = k > r.max_aspect ? k : r.max_aspect;
    }
    cbm_tree_destroy(t);
    return r;
}

/* Every real-wood preset and documented variation grows over seeds 1-6 (6 years): no seed dies
 * back (less than half its largest size at the end) or ends its last summer leafless, and every
 * section stays within the reaction-wood bound a/b <= 1.5. */
TEST(tree_real_presets_never_collapse)
{
    cbm_context *ctx = test_ctx();
    const char *models[] = {"fruit-tree",          "fruit-tree-unfair", "fruit-tree-low-mor",
                            "fruit-tree-high-mor", "poplar-wild",       "poplar-crooked"};
    for (size_t m = 0; m < sizeof models / sizeof models[0]; m++) {
        size_t least = SIZE_MAX;
        double aspect = 0.0;
        for (unsigned seed = 1; seed <= 6; seed++) {
            seed_run r = run_seed(ctx, models[m], 6, seed);
            CHECK_MSG(2 * r.last.segments >= r.peak && r.last.leaves > 0,
                      "%s seed %u collapsed: %zu segments (peak %zu), %zu leaves", models[m], seed,
                      r.last.segments, r.peak, r.last.leaves);
            least = r.last.segments < least ? r.last.segments : least;
            aspect = r.max_aspect > aspect ? r.max_aspect : aspect;
        }
        printf("%s: at least %zu segments after 6 years over seeds 1-6, largest a/b %.3f\n",
               models[m], least, aspect);
        CHECK(least >= 100);
        CHECK(aspect <= 1.5 + 1e-9);
    }
    test_ctx_end(ctx);
}

/* Share of successive lateral buds on the first-year trunk whose azimuths differ by the
 * phyllotactic angle (144 deg either way round, within 5 deg). */
static double spiral_share(cbm_context *ctx, unsigned seed, const char *stem_frame)
{
    char sd[32];
    snprintf(sd, sizeof sd, "%u", seed);
    const char *set[] = {"seed", sd, "stem_frame", stem_frame, NULL};
    cbm_tree *t = grow(ctx, "fruit-tree", 1, set);
    cbm_measure_segment *tab = NULL;
    size_t n = 0, pairs = 0, good = 0;
    CHECK_OK(cbm_measure_plant_table(ctx, cbm_tree_plant(t), &tab, &n));
    double prev = NAN;
    for (size_t i = 1; tab && i < n; i++) {
        if (!tab[i].lateral || tab[i].parent < 0 || tab[tab[i].parent].lateral)
            continue;
        double az = atan2(tab[i].p1.z - tab[i].p0.z, tab[i].p1.x - tab[i].p0.x) * 180 /
                    3.14159265358979323846;
        if (!isnan(prev)) {
            double d = fmod(az - prev + 720.0, 360.0);
            pairs++;
            good += fabs(d - 144.0) < 5.0 || fabs(d - 216.0) < 5.0;
        }
        prev = az;
    }
    cbm_measure_table_free(ctx, tab, n);
    cbm_tree_destroy(t);
    return pairs ? (double)good / (double)pairs : 0.0;
}

/* Intersecting fraction of the tree of a model of `years` years of a seed. */
static double crossing(cbm_context *ctx, const char *model, unsigned seed, int years,
                       const char *stem_frame)
{
    char sd[32];
    snprintf(sd, sizeof sd, "%u", seed);
    const char *set[] = {"seed", sd, "stem_frame", stem_frame, NULL};
    cbm_tree *t = grow(ctx, model, years, set);
    cbm_measure_def md = cbm_measure_def_default();
    cbm_tree_measures m;
    memset(&m, 0, sizeof m);
    CHECK_OK(cbm_measure_plant(ctx, &md, cbm_tree_plant(t), &m));
    cbm_tree_destroy(t);
    return m.intersecting_fraction;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The phyllotactic spiral goes round the stem (stem_frame, the real presets): over seeds 1-5 the
 * first-year trunk's successive buds leave 144 deg apart, where the thesis' upright roll at
 * every node (stem_frame = 0) breaks the spiral for most of them; and the 10-year trees of seeds
 * 1-3 have few segments passing through another one (median below 1 %). */
TEST(tree_real_phyllotaxis_round_the_stem)
{
    cbm_context *ctx = test_ctx();
    for (unsigned seed = 1; seed <= 5; seed++) {
        double with = spiral_share(ctx, seed, "1"), without = spiral_share(ctx, seed, "0");
        CHECK_MSG(with >= 0.9 && without < 0.5,
                  "seed %u: %.2f of the buds on the spiral (%.2f "
                  "with the upright roll)",
                  seed, with, without);
    }
    double f[3];
    for (unsigned seed = 1; seed <= 3; seed++)
        f[seed - 1] = crossing(ctx, "fruit-tree", seed, 10, "1");
    qsort(f, 3, sizeof f[0], cmp_double);
    printf("intersecting after 10 years, seeds 1-3: median %.4f\n", f[1]);
    CHECK(f[1] < 0.01);
    test_ctx_end(ctx);
}

/* The wild aspen's spiral is the golden angle (phyllotaxis 137.5): with the apple's exact 2/5
 * (144 deg) every fifth bud left on the same side and the wild form's fivefold tropism turned
 * those laterals into one another (1.6-2.6 % of the segments intersecting in seeds 1-3); the
 * 10-year trees of seeds 1-3 now have a median below 1 % (0.06-0.20 % measured). */
TEST(tree_real_wild_aspen_few_crossings)
{
    cbm_context *ctx = test_ctx();
    double f[3];
    for (unsigned seed = 1; seed <= 3; seed++)
        f[seed - 1] = crossing(ctx, "poplar-wild", seed, 10, "1");
    qsort(f, 3, sizeof f[0], cmp_double);
    printf("wild aspen intersecting after 10 years, seeds 1-3: %.4f %.4f %.4f\n", f[0], f[1], f[2]);
    CHECK(f[1] < 0.01);
    test_ctx_end(ctx);
}

/* Ch. 7 with real aspen wood: the crooked form is lower and wider than the wild one in at least
 * 9 of seeds 1-10 (6 years). */
TEST(tree_real_crooked_aspen_lower_wider)
{
    cbm_context *ctx = test_ctx();
    int both = 0;
    for (unsigned seed = 1; seed <= 10; seed++) {
        seed_run w = run_seed(ctx, "poplar-wild", 6, seed);
        seed_run c = run_seed(ctx, "poplar-crooked", 6, seed);
        both += c.last.height < w.last.height && c.last.crown_width > w.last.crown_width;
    }
    printf("crooked lower and wider than wild in %d of 10 seeds\n", both);
    CHECK(both >= 9);
    test_ctx_end(ctx);
}

/* Fig. 4.7 with real wood: F = 0.2 grows sparser than F = 1 in at least 9 of seeds 1-10 (5
 * years) and taller in the median (in some seeds its long leader bends over under its first
 * apples, as unthinned leaders do), and it keeps growing (more segments in year 5 than in 3). */
static int cmp_dbl(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

TEST(tree_real_unfair_taller_sparser)
{
    cbm_context *ctx = test_ctx();
    int sparser = 0, grows = 0;
    double hf[10], hu[10];
    for (unsigned seed = 1; seed <= 10; seed++) {
        seed_run f = run_seed(ctx, "fruit-tree", 5, seed);
        seed_run u = run_seed(ctx, "fruit-tree-unfair", 5, seed);
        sparser += u.last.segments < f.last.segments;
        hf[seed - 1] = f.last.height;
        hu[seed - 1] = u.last.height;
        seed_run u3 = run_seed(ctx, "fruit-tree-unfair", 3, seed);
        grows += u.last.segments > u3.last.segments;
    }
    qsort(hf, 10, sizeof *hf, cmp_dbl);
    qsort(hu, 10, sizeof *hu, cmp_dbl);
    double mf = 0.5 * (hf[4] + hf[5]), mu = 0.5 * (hu[4] + hu[5]);
    printf("F = 0.2 sparser in %d of 10 seeds, median height %.2f m against %.2f m; growing in "
           "%d\n",
           sparser, mu, mf, grows);
    CHECK(sparser >= 9);
    CHECK(mu > 1.2 * mf);
    CHECK_EQ_INT(grows, 10);
    test_ctx_end(ctx);
}

/* Fig. 8.9 with real wood: MOR 15 MPa breaks fruit-laden branches in at least 9 of seeds 1-10,
 * green apple wood's 50 MPa in at most 2 (6 years; a limb does break now and then). */
TEST(tree_real_low_mor_breaks)
{
    cbm_context *ctx = test_ctx();
    int lo = 0, real = 0;
    for (unsigned seed = 1; seed <= 10; seed++) {
        lo += run_seed(ctx, "fruit-tree-low-mor", 6, seed).breaks > 0;
        real += run_seed(ctx, "fruit-tree", 6, seed).breaks > 0;
    }
    printf("seeds with breaks in 6 years: %d of 10 at 15 MPa, %d at 50 MPa\n", lo, real);
    CHECK(lo >= 9);
    CHECK(real <= 2);
    test_ctx_end(ctx);
}

static double med3(const double *v)
{
    return v[0] + v[1] + v[2] - fmax(fmax(v[0], v[1]), v[2]) - fmin(fmin(v[0], v[1]), v[2]);
}

/* The 10-year real fruit tree against pomological ranges (docs/models.md, "Real wood"): median
 * over seeds 1-3 of height 2.5-4 m, trunk diameter at the base 6-15 cm, crown 2-4.5 m, and a
 * crop (fruit in every seed). Long: about 1 s a seed. */
TEST(tree_real_ten_years_in_range)
{
    cbm_context *ctx = test_ctx();
    double h[3], dia[3], w[3];
    size_t fruit = SIZE_MAX;
    for (unsigned seed = 1; seed <= 3; seed++) {
        seed_run r = run_seed(ctx, "fruit-tree", 10, seed);
        h[seed - 1] = r.last.height;
        dia[seed - 1] = r.last.base_diameter;
        w[seed - 1] = r.last.crown_width;
        fruit = r.last.fruit < fruit ? r.last.fruit : fruit;
    }
    double mh = med3(h), md = med3(dia), mw = med3(w);
    printf("10 years, median of seeds 1-3: height %.2f m, base diameter %.1f cm, crown %.2f m; "
           "fewest fruit %zu\n",
           mh, 100 * md, mw, fruit);
    CHECK(mh >= 2.5 && mh <= 4.0);
    CHECK(md >= 0.06 && md <= 0.15);
    CHECK(mw >= 2.0 && mw <= 4.5);
    CHECK(fruit >= 20);
    test_ctx_end(ctx);
}

/* Winter pruning (clear_trunk, docs/models.md): with clear_trunk = 0.6 m no branch leaves the
 * leader below 0.6 m after 4 years in seeds 1-3, where the unpruned tree has several. */
static size_t low_laterals(cbm_context *ctx, unsigned seed, const char *clear)
{
    char sd[32];
    snprintf(sd, sizeof sd, "%u", seed);
    const char *set[] = {"seed", sd, "clear_trunk", clear, NULL};
    cbm_tree *t = grow(ctx, "fruit-tree", 4, set);
    cbm_measure_segment *tab = NULL;
    size_t n = 0, low = 0;
    CHECK_OK(cbm_measure_plant_table(ctx, cbm_tree_plant(t), &tab, &n));
    char *leader = calloc(n ? n : 1, 1);
    for (size_t i = 0; tab && leader && i < n; i++) {
        int64_t pa = tab[i].parent;
        leader[i] = pa < 0 || (!tab[i].lateral && leader[pa]);
        low += pa >= 0 && leader[pa] && !leader[i] && tab[i].p0.y < 0.6 - 1e-9;
    }
    free(leader);
    cbm_measure_table_free(ctx, tab, n);
    cbm_tree_destroy(t);
    return low;
}

TEST(tree_real_clear_trunk_pruned)
{
    cbm_context *ctx = test_ctx();
    for (unsigned seed = 1; seed <= 3; seed++) {
        size_t kept = low_laterals(ctx, seed, "0"), pruned = low_laterals(ctx, seed, "0.6");
        printf("seed %u: branches off the leader below 0.6 m after 4 years: %zu unpruned, %zu "
               "with clear_trunk 0.6\n",
               seed, kept, pruned);
        CHECK(kept > 0);
        CHECK(pruned == 0);
    }
    test_ctx_end(ctx);
}

/* Share of segments whose section sits at the reaction-wood bound a/b = 1.5, of all segments and
 * of the limbs (segments thicker than 1 cm: the trunk and the main branches). */
static void bound_share(cbm_context *ctx, unsigned seed, const char *full, double *all,
                        double *limbs)
{
    char sd[32];
    snprintf(sd, sizeof sd, "%u", seed);
    const char *set[] = {"seed", sd, "reaction_full_lean", full, NULL};
    cbm_tree *t = grow(ctx, "fruit-tree", 8, set);
    const cbm_plant *p = cbm_tree_plant(t);
    size_t n = cbm_plant_segment_count(p), at = 0, nl = 0, atl = 0;
    for (size_t i = 0; i < n; i++) {
        cbm_segment_state st;
        CHECK_OK(cbm_plant_segment(p, i, &st));
        bool bound = st.a >= 1.5 * st.b * (1.0 - 1e-6);
        at += bound;
        if (st.b > 0.005) {
            nl++;
            atl += bound;
        }
    }
    *all = n ? (double)at / (double)n : 0.0;
    *limbs = nl ? (double)atl / (double)nl : 0.0;
    cbm_tree_destroy(t);
}

/* The reaction-wood increment follows the lean (docs/growth.md): with the fixed increment of
 * the thesis about 23 % of the 8-year real tree's segments (over half of its limbs) sat at the
 * 1.5 bound; with the increment scaled by sin(lean) / sin(10 deg) (the presets' theta_f) the
 * bound is the exception: the median over seeds 1-5 is below 15 % of the segments and 30 % of the
 * limbs (measured: 23 % -> 11 % of the segments, 65 % -> 20 % of the limbs; theta_f = 20 deg gave
 * 6 % and 6 % but let fruit-tree-low-mor die back in 5 of 50 seeds, docs/models.md). */
TEST(tree_real_reaction_bound_the_exception)
{
    cbm_context *ctx = test_ctx();
    double all[5], limbs[5], all0[5], limbs0[5];
    for (unsigned seed = 1; seed <= 5; seed++) {
        bound_share(ctx, seed, "10", &all[seed - 1], &limbs[seed - 1]);
        bound_share(ctx, seed, "0", &all0[seed - 1], &limbs0[seed - 1]);
        printf("seed %u at the bound: fixed increment %.1f %% of segments, %.1f %% of limbs; "
               "following the lean %.1f %%, %.1f %%\n",
               seed, 100 * all0[seed - 1], 100 * limbs0[seed - 1], 100 * all[seed - 1],
               100 * limbs[seed - 1]);
    }
    qsort(all, 5, sizeof all[0], cmp_dbl);
    qsort(limbs, 5, sizeof limbs[0], cmp_dbl);
    qsort(all0, 5, sizeof all0[0], cmp_dbl);
    printf("median at the bound: %.1f %% -> %.1f %% of segments, %.1f %% -> %.1f %% of limbs\n",
           100 * all0[2], 100 * all[2], 100 * limbs0[2], 100 * limbs[2]);
    CHECK(all[2] < 0.15);
    CHECK(limbs[2] < 0.30);
    test_ctx_end(ctx);
}

/* The real-wood tree does not hang on the solver's path: solved to a relative residual of 1e-4,
 * 1e-6 (the default) or 1e-9, seeds 1-3 grow to within 5 % of the same segments and 2 % of the
 * same height in 6 years (the thesis constants' tree, whose thin rubber shoots pass folds,
 * moved between 1,682 and 3,246 segments with small solver changes). */
TEST(tree_real_insensitive_to_solver_path)
{
    cbm_context *ctx = test_ctx();
    const char *tol[] = {"1e-4", "1e-9"};
    double worst_n = 0.0, worst_h = 0.0;
    for (unsigned seed = 1; seed <= 3; seed++) {
        seed_run ref = run_seed(ctx, "fruit-tree", 6, seed);
        for (int k = 0; k < 2; k++) {
            char sd[32];
            snprintf(sd, sizeof sd, "%u", seed);
            const char *set[] = {"seed", sd, "solve_tolerance", tol[k], NULL};
            cbm_tree *t = grow(ctx, "fruit-tree", 6, set);
            const cbm_tree_summary *s = cbm_tree_summary_of(t, 6);
            double dn =
                fabs((double)s->segments - (double)ref.last.segments) / (double)ref.last.segments;
            double dh = fabs(s->height - ref.last.height) / ref.last.height;
            worst_n = dn > worst_n ? dn : worst_n;
            worst_h = dh > worst_h ? dh : worst_h;
            cbm_tree_destroy(t);
        }
    }
    printf("tolerance 1e-4 and 1e-9 against 1e-6: segments within %.2f %%, height within %.2f "
           "%%\n",
           100 * worst_n, 100 * worst_h);
    CHECK(worst_n <= 0.05);
    CHECK(worst_h <= 0.02);
    test_ctx_end(ctx);
}

/* The picture's organs sit where the model puts them: every leaf's petiole starts at its node
 * (the end of its bud internode: the nearest vertex is the petiole's ring there, radius 0.0125
 * of the blade's length), and the blade reaches 1.3 blade lengths from it (petiole 0.3 + blade 1),
 * the blade's length 1.5 leaf_scale sqrt(m / leaf_density); every fruit is a sphere of the fruit's
 * volume hanging below its node on a stalk. */
TEST(tree_leaves_on_their_nodes)
{
    cbm_context *ctx = test_ctx();
    cbm_tree_def d;
    CHECK_OK(cbm_tree_def_builtin(ctx, "fruit-tree", &d));
    d.years = 4;
    cbm_tree *t = NULL;
    CHECK_OK(cbm_tree_create(ctx, &d, &t));
    /* three years, then the fourth summer (leaves and fruit on) */
    for (int y = 0; y < 3 && t; y++)
        CHECK_OK(cbm_tree_year(t));
    for (int k = 0; k < 200 && t && cbm_tree_current_season(t) == CBM_TREE_SUMMER; k++)
        CHECK_OK(cbm_tree_step(t, NULL));
    cbm_scene *sc = NULL;
    CHECK_OK(cbm_scene_create(ctx, &sc));
    if (!t || !sc) {
        cbm_scene_destroy(sc);
        cbm_tree_destroy(t);
        test_ctx_end(ctx);
        return;
    }
    CHECK_OK(cbm_tree_to_scene(t, sc, 6, false));
    const cbm_plant *p = cbm_tree_plant(t);
    size_t np = cbm_scene_part_count(sc), nt = cbm_scene_triangle_count(sc);
    const cbm_part *parts = cbm_scene_parts(sc);
    const uint32_t *tri = cbm_scene_triangles(sc), *tp = cbm_scene_triangle_parts(sc);
    const cbm_scene_vertex *v = cbm_scene_vertices(sc);
    double *dmin = calloc(np, sizeof *dmin), *dmax = calloc(np, sizeof *dmax), *ymin = NULL;
    ymin = calloc(np, sizeof *ymin);
    cbm_vec3 *node = calloc(np, sizeof *node);
    CHECK(dmin && dmax && ymin && node);
    size_t leaves = 0, fruit = 0;
    for (size_t k = 0; dmin && dmax && ymin && node && k < np; k++) {
        dmin[k] = INFINITY;
        dmax[k] = 0;
        ymin[k] = INFINITY;
        if (parts[k].organ == CBM_ORGAN_LEAF || parts[k].organ == CBM_ORGAN_FRUIT) {
            cbm_segment_state st;
            CHECK_OK(cbm_plant_segment(p, (size_t)parts[k].segment, &st));
            node[k] = st.distal;
        }
    }
    for (size_t i = 0; dmin && dmax && ymin && node && i < nt; i++) {
        uint32_t k = tp[i];
        for (int m = 0; m < 3; m++) {
            const float *q = v[tri[3 * i + (size_t)m]].p;
            double dx = q[0] - node[k].x, dy = q[1] - node[k].y, dz = q[2] - node[k].z;
            double r = sqrt(dx * dx + dy * dy + dz * dz);
            dmin[k] = fmin(dmin[k], r);
            dmax[k] = fmax(dmax[k], r);
            ymin[k] = fmin(ymin[k], q[1]);
        }
    }
    for (size_t k = 0; dmin && dmax && ymin && node && k < np; k++) {
        cbm_tree_segment info;
        if (parts[k].organ == CBM_ORGAN_LEAF) {
            CHECK_OK(cbm_tree_segment_info(t, (size_t)parts[k].segment, &info));
            /* a spur's rosette: info.leaves blades of an equal share of the mass */
            int nl = info.leaves > 1 ? info.leaves : 1;
            double len = 1.5 * d.leaf_scale * sqrt(info.leaf_mass / nl / d.leaf_density);
            CHECK_MSG(fabs(dmin[k] - 0.0125 * len) < 1e-3 * len + 1e-6,
                      "leaf %zu: nearest point %g from its node, petiole radius %g", k, dmin[k],
                      0.0125 * len);
            CHECK_MSG(fabs(dmax[k] - 1.3 * len) < 1e-3 * len + 1e-6,
                      "leaf %zu: reaches %g from its node, not %g", k, dmax[k], 1.3 * len);
            leaves++;
        } else if (parts[k].organ == CBM_ORGAN_FRUIT) {
            CHECK_OK(cbm_tree_segment_info(t, (size_t)parts[k].segment, &info));
            double r = cbrt(0.75 / 3.141592653589793 * info.fruit_mass / d.fruit_density);
            CHECK_MSG(dmin[k] < 0.05 * r + 1e-6, "fruit %zu: stalk %g from its node", k, dmin[k]);
            CHECK_MSG(fabs(node[k].y - ymin[k] - 2.7 * r) < 1e-3 * r + 1e-6,
                      "fruit %zu: lowest point %g below its node, not %g", k, node[k].y - ymin[k],
                      2.7 * r);
            fruit++;
        }
    }
    printf("fourth summer: %zu leaves and %zu fruit checked\n", leaves, fruit);
    CHECK(leaves > 10);
    free(dmin);
    free(dmax);
    free(ymin);
    free(node);
    cbm_scene_destroy(sc);
    cbm_tree_destroy(t);
    test_ctx_end(ctx);
}
