/* cambium grow: grows a built-in tree model (cambium/tree.h) from a parameter file or a built-in
 * name for a number of years, and writes the final tree (pictures, meshes), the segments table
 * (.csv), the MTG (.mtg) and the year-by-year summary (.json); with --every K a .glb holds a
 * growth animation of one frame every K growth steps. With --seeds A-B it grows the model once
 * per seed and writes the distribution of the year-by-year figures over the seeds (.json). */
#include "cli_grow.h"
#include "cli_light.h"
#include "cli_output.h"
#include "commands.h"
#include "grow_sway.h"

#include "cambium/dynamics.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_OUTPUTS 16
#define MAX_DEFS    128

/* -o wind:FILE.csv: the static critical wind speed of the stem and of each first-order branch
 * (docs/dynamics.md, "Wind"), default wind (log profile, U_ref at 10 m, z0 0.1 m, along +x) */
static cbm_status write_wind(cbm_context *ctx, const cbm_plant *p, const cli_sway *organs,
                             const char *path)
{
    size_t n = 0;
    cbm_wind_def wd = cbm_wind_def_default();
    wd.leaf_area = organs->leaf_area; /* --organ-drag */
    wd.fruit_mass = organs->fruit_mass;
    wd.fruit_density = organs->fruit_density;
    cbm_status st = cbm_plant_critical_wind(p, &wd, NULL, 0, &n);
    if (st != CBM_OK)
        return st;
    cbm_wind_critical *rows = malloc((n ? n : 1) * sizeof *rows);
    if (!rows)
        return CBM_E_NOMEM;
    st = cbm_plant_critical_wind(p, &wd, rows, n, &n);
    cbm_out *o = NULL;
    if (st == CBM_OK)
        st = cbm_out_open(ctx, path, &o);
    if (st == CBM_OK) {
        FILE *f = cbm_out_stream(o);
        fprintf(f, "axis,order,first_segment,critical_wind_m_s,weakest_segment,height_m\n");
        for (size_t k = 0; k < n; k++)
            fprintf(f, "%s,%d,%zu,%.6g,%zu,%.6g\n", rows[k].order == 0 ? "stem" : "branch",
                    (int)rows[k].order, rows[k].first, rows[k].speed, rows[k].weakest,
                    rows[k].height);
        st = cbm_out_commit(o);
    }
    free(rows);
    return st;
}

static void help(const cli_opts *t)
{
    cli_grow_help(
        t,
        "usage: cambium grow [MODEL.tree | NAME] [-y YEARS] [-D NAME=VALUE]... [--seed N]\n"
        "                    [-o FILE]... [--every K] [--summer] [--timing] [--quiet]\n"
        "                    [--modes N] [--sway SECONDS [--wind M_S] [--gust I]]\n"
        "                    [--params] [--report] [--seeds A-B] [limits]\n"
        "                    [output options]\n\n"
        "Grows the general fruit tree of Taylor-Hell (2005) with full mechanics, or the\n"
        "wild or crooked aspen, from a parameter file or a built-in model (default\n"
        "fruit-tree; see docs/models.md). Outputs by extension: .png .svg .glb .obj .ply\n"
        "(the tree with leaves and fruit; .glb with --every K: a growth animation, one\n"
        "frame every K growth steps), .csv (segments table), .mtg, .json (year-by-year\n"
        "summary). FORMAT:PATH names a scene format explicitly. -o wind:FILE.csv writes the\n"
        "critical wind speed of the stem and of each first-order branch; -o light:FILE.csv\n"
        "the light of each leaf (--light). With --sway, .glb outputs are the grown tree\n"
        "swaying in a gusty wind (an animation) and .csv (or motion:FILE.csv) the\n"
        "displacements of the stem's and first-order branches' tips.\n\n",
        cbm_tree_builtin_names());
}

static bool parse_seed(const char *v, void *target, char *why, size_t n)
{
    (void)why, (void)n;
    long sd;
    if (!cli_parse_long(v, &sd) || sd < 0)
        return false;
    *(const char **)target = v;
    return true;
}

/* a non-negative number (--wind, --gust) or a positive one (--sway, --sway-dt) */
static bool parse_nonneg(const char *v, void *target, char *why, size_t n)
{
    double x;
    if (!cli_parse_double(v, &x))
        snprintf(why, n, "{opt}: '{value}' is not a number");
    else if (!(x >= 0.0))
        snprintf(why, n, "{opt} must be >= 0 (got {value})");
    else
        *(double *)target = x;
    return !*why;
}

static bool parse_pos(const char *v, void *target, char *why, size_t n)
{
    double x;
    if (!cli_parse_double(v, &x))
        snprintf(why, n, "{opt}: '{value}' is not a number");
    else if (!(x > 0.0) || x > 1e6)
        snprintf(why, n, "{opt} must be in (0, 1e6] (got {value})");
    else
        *(double *)target = x;
    return !*why;
}

/* --seeds A-B */
static bool parse_seeds(const char *v, void *target, char *why, size_t n)
{
    long *range = target;
    const char *dash = strchr(v, '-');
    char lo[32];
    if (!dash || (size_t)(dash - v) >= sizeof lo) {
        snprintf(why, n, "--seeds expects A-B, got '{value}'");
        return false;
    }
    memcpy(lo, v, (size_t)(dash - v));
    lo[dash - v] = '\0';
    if (!cli_parse_long(lo, &range[0]) || !cli_parse_long(dash + 1, &range[1]) || range[0] < 0 ||
        range[1] < range[0] || range[1] - range[0] >= 100000) {
        snprintf(why, n, "--seeds expects A-B with 0 <= A <= B, got '{value}'");
        return false;
    }
    return true;
}

static void summary_object(cbm_json *j, const cbm_tree_summary *s, bool complete);

static cbm_status write_summary(cbm_context *ctx, const cbm_tree *t, const char *model,
                                const cbm_tree_def *d, double total, bool partial, const char *path)
{
    cbm_json *j = NULL;
    cbm_status cs = cbm_json_create(ctx, &j);
    if (cs != CBM_OK)
        return cs;
    cbm_json_begin_object(j, NULL);
    cbm_json_string(j, "model", model);
    cbm_json_int(j, "seed", (int64_t)d->seed);
    cbm_json_int(j, "years_grown", cbm_tree_years(t));
    cbm_json_number(j, "seconds", total);
    cbm_json_begin_array(j, "years");
    for (int y = 1; y <= cbm_tree_years(t); y++)
        summary_object(j, cbm_tree_summary_of(t, y), true);
    if (partial) /* --summer: the last year up to the end of its summer */
        summary_object(j, cbm_tree_summary_current(t), false);
    cbm_json_end_array(j);
    cbm_tree_measures tm; /* the final tree as a forester measures it (cambium info x.json) */
    if (cbm_measure_plant(ctx, NULL, cbm_tree_plant(t), &tm) == CBM_OK)
        cli_measures_json(j, "measures", &tm);
    cbm_json_end_object(j);
    cbm_status s = cbm_json_write_file(j, path);
    cbm_json_destroy(j);
    return s;
}

static void summary_object(cbm_json *j, const cbm_tree_summary *s, bool complete)
{
    cbm_json_begin_object(j, NULL);
    cbm_json_int(j, "year", s->year);
    cbm_json_bool(j, "complete", complete);
    cbm_json_int(j, "segments", (int64_t)s->segments);
    cbm_json_number(j, "height_m", s->height);
    cbm_json_number(j, "crown_width_m", s->crown_width);
    cbm_json_int(j, "leaves", (int64_t)s->leaves);
    cbm_json_int(j, "fruit", (int64_t)s->fruit);
    cbm_json_int(j, "breaks", (int64_t)s->breaks);
    cbm_json_int(j, "shed", (int64_t)s->shed);
    cbm_json_int(j, "removed_segments", (int64_t)s->removed);
    cbm_json_int(j, "reaction_wood_segments", (int64_t)s->reaction_segments);
    cbm_json_int(j, "shoots", (int64_t)s->shoots);
    cbm_json_int(j, "relay_shoots", (int64_t)s->relay_shoots);
    cbm_json_number(j, "tip_height_loaded_m", s->tip_height_loaded);
    cbm_json_number(j, "tip_height_unloaded_m", s->tip_height_unloaded);
    cbm_json_number(j, "trunk_lean_deg", s->lean);
    cbm_json_number(j, "base_diameter_m", s->base_diameter);
    cbm_json_int(j, "growth_steps", (int64_t)s->growth_steps);
    cbm_json_int(j, "equilibrium_passes", (int64_t)s->passes);
    cbm_json_int(j, "newton_steps", (int64_t)s->newton_steps);
    cbm_json_int(j, "unconverged", (int64_t)s->unconverged);
    cbm_json_number(j, "seconds", s->seconds);
    cbm_json_number(j, "seconds_equilibrium", s->seconds_solve);
    cbm_json_number(j, "seconds_rings", s->seconds_rings);
    cbm_json_end_object(j);
}

/* ---- --seeds: the distribution over seeds ---- */

/* The year-by-year figures a --seeds run reports (cbm_tree_summary fields). */
static const char *const seed_figures[] = {
    "segments", "height_m", "crown_width_m",          "base_diameter_m", "leaves",     "fruit",
    "breaks",   "shed",     "reaction_wood_segments", "shoots",          "unconverged"};
#define NFIG (sizeof seed_figures / sizeof seed_figures[0])

static double seed_figure(const cbm_tree_summary *s, size_t k)
{
    switch (k) {
    case 0:
        return (double)s->segments;
    case 1:
        return s->height;
    case 2:
        return s->crown_width;
    case 3:
        return s->base_diameter;
    case 4:
        return (double)s->leaves;
    case 5:
        return (double)s->fruit;
    case 6:
        return (double)s->breaks;
    case 7:
        return (double)s->shed;
    case 8:
        return (double)s->reaction_segments;
    case 9:
        return (double)s->shoots;
    default:
        return (double)s->unconverged;
    }
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* Quantile q of sorted v[0..n) by linear interpolation between order statistics. */
static double quantile(const double *v, size_t n, double q)
{
    double h = q * (double)(n - 1);
    size_t lo = (size_t)floor(h);
    if (lo + 1 >= n)
        return v[n - 1];
    return v[lo] + (h - (double)lo) * (v[lo + 1] - v[lo]);
}

/* A seed's tree collapsed: at the end it has less than half of its largest segment count, or
 * (with leaves) no leaf in its last summer. */
static bool collapsed(const cbm_tree_summary *s, int years, const cbm_tree_def *d)
{
    if (years <= 0)
        return false;
    size_t peak = 0;
    for (int y = 0; y < years; y++)
        peak = s[y].segments > peak ? s[y].segments : peak;
    const cbm_tree_summary *last = &s[years - 1];
    return 2 * last->segments < peak ||
           (d->leaves && d->leaf_mass > 0.0 && last->leaves == 0 && years > 1);
}

static int grow_seeds(cbm_context *ctx, const cbm_tree_def *def, const char *model, long first,
                      long last, const char *const *outs, int nout, bool quiet)
{
    size_t ns = (size_t)(last - first + 1), ny = def->years > 0 ? (size_t)def->years : 0;
    cbm_tree_summary *all = calloc(ns * (ny ? ny : 1), sizeof *all);
    double *v = malloc(ns * sizeof *v);
    if (!all || !v) {
        free(all);
        free(v);
        return CLI_FAIL;
    }
    double t0 = cli_seconds();
    int rc = CLI_OK;
    for (size_t k = 0; k < ns && rc == CLI_OK; k++) {
        cbm_tree_def d = *def;
        d.seed = (uint64_t)(first + (long)k);
        cbm_tree *t = NULL;
        cbm_status st = cbm_tree_create(ctx, &d, &t);
        if (st == CBM_OK)
            st = cbm_tree_run(t);
        if (st != CBM_OK) {
            char what[64];
            snprintf(what, sizeof what, "growing seed %llu", (unsigned long long)d.seed);
            rc = cli_fail(ctx, st, what);
        } else {
            for (size_t y = 0; y < ny; y++)
                all[k * ny + y] = *cbm_tree_summary_of(t, (int)y + 1);
        }
        cbm_tree_destroy(t);
    }
    double total = cli_seconds() - t0;
    size_t ncol = 0;
    for (size_t k = 0; k < ns && rc == CLI_OK; k++)
        ncol += collapsed(all + k * ny, (int)ny, def);
    if (rc == CLI_OK && !quiet) {
        for (size_t y = 0; y < ny; y++) {
            double med[NFIG];
            for (size_t f = 0; f < NFIG; f++) {
                for (size_t k = 0; k < ns; k++)
                    v[k] = seed_figure(&all[k * ny + y], f);
                qsort(v, ns, sizeof *v, cmp_double);
                med[f] = quantile(v, ns, 0.5);
            }
            printf("year %2zu, median of %zu seeds: %7.0f segments, height %.2f m, crown %.2f m, "
                   "base diameter %.1f cm, %.0f leaves, %.0f fruit, %.0f breaks\n",
                   y + 1, ns, med[0], med[1], med[2], 100.0 * med[3], med[4], med[5], med[6]);
        }
        printf("%zu seeds in %.1f s, %zu collapsed\n", ns, total, ncol);
    }
    for (int o = 0; o < nout && rc == CLI_OK; o++) {
        cbm_json *j = NULL;
        cbm_status st = cbm_json_create(ctx, &j);
        if (st != CBM_OK) {
            rc = cli_fail(ctx, st, outs[o]);
            break;
        }
        cbm_json_begin_object(j, NULL);
        cbm_json_string(j, "model", model);
        cbm_json_begin_object(j, "seeds");
        cbm_json_int(j, "first", first);
        cbm_json_int(j, "last", last);
        cbm_json_int(j, "count", (int64_t)ns);
        cbm_json_end_object(j);
        cbm_json_int(j, "years_grown", (int64_t)ny);
        cbm_json_number(j, "seconds", total);
        cbm_json_begin_array(j, "collapsed_seeds");
        for (size_t k = 0; k < ns; k++)
            if (collapsed(all + k * ny, (int)ny, def))
                cbm_json_int(j, NULL, first + (long)k);
        cbm_json_end_array(j);
        cbm_json_begin_array(j, "years");
        for (size_t y = 0; y < ny; y++) {
            cbm_json_begin_object(j, NULL);
            cbm_json_int(j, "year", (int64_t)y + 1);
            for (size_t f = 0; f < NFIG; f++) {
                for (size_t k = 0; k < ns; k++)
                    v[k] = seed_figure(&all[k * ny + y], f);
                qsort(v, ns, sizeof *v, cmp_double);
                cbm_json_begin_object(j, seed_figures[f]);
                cbm_json_number(j, "min", v[0]);
                cbm_json_number(j, "q1", quantile(v, ns, 0.25));
                cbm_json_number(j, "median", quantile(v, ns, 0.5));
                cbm_json_number(j, "q3", quantile(v, ns, 0.75));
                cbm_json_number(j, "max", v[ns - 1]);
                cbm_json_end_object(j);
            }
            cbm_json_end_object(j);
        }
        cbm_json_end_array(j);
        cbm_json_begin_array(j, "final");
        for (size_t k = 0; k < ns && ny; k++) {
            const cbm_tree_summary *s = &all[k * ny + ny - 1];
            size_t breaks = 0;
            for (size_t y = 0; y < ny; y++)
                breaks += all[k * ny + y].breaks;
            cbm_json_begin_object(j, NULL);
            cbm_json_int(j, "seed", first + (long)k);
            for (size_t f = 0; f < NFIG; f++)
                cbm_json_number(j, seed_figures[f], seed_figure(s, f));
            cbm_json_int(j, "breaks_total", (int64_t)breaks);
            cbm_json_bool(j, "collapsed", collapsed(all + k * ny, (int)ny, def));
            cbm_json_end_object(j);
        }
        cbm_json_end_array(j);
        cbm_json_end_object(j);
        st = cbm_json_write_file(j, outs[o]);
        cbm_json_destroy(j);
        if (st != CBM_OK)
            rc = cli_fail(ctx, st, outs[o]);
    }
    free(all);
    free(v);
    return rc;
}

/* --timing: where the time went. `derive` is the growth itself (the tree's steps: equilibrium,
 * rings and ageing, growth and bookkeeping), `interpret` the scene building, `write` the
 * writers. */
static void print_timing(cbm_context *ctx, const cbm_tree *t, bool summer, double derive,
                         double interpret, double write, double total)
{
    double solve = 0, rings = 0;
    size_t passes = 0;
    for (int y = 1; y <= cbm_tree_years(t); y++) {
        const cbm_tree_summary *s = cbm_tree_summary_of(t, y);
        solve += s->seconds_solve;
        rings += s->seconds_rings;
        passes += s->passes;
    }
    /* the year under way: the spring solve after the last year, or an unfinished summer */
    const cbm_tree_summary *c = cbm_tree_summary_current(t);
    if (c) {
        solve += c->seconds_solve;
        rings += c->seconds_rings;
        passes += c->passes;
    }
    fprintf(
        stderr,
        "grow: %d years%s, %zu segments: derive %.3f s (equilibrium %.3f s in %zu passes, "
        "rings and ageing %.3f s, growth and the rest %.3f s), interpret %.3f s, write "
        "%.3f s, total %.3f s; peak %.1f MB in the library\n",
        cbm_tree_years(t) + (summer ? 1 : 0), summer ? " (the last to the end of its summer)" : "",
        cbm_plant_segment_count(cbm_tree_plant(t)), derive, solve, passes, rings,
        derive - solve - rings, interpret, write, total, (double)cbm_context_peak_bytes(ctx) / 1e6);
    cli_print_solve_stages("grow", ctx);
}

int cmd_grow(int argc, char **argv)
{
    const char *model = NULL, *outs[MAX_OUTPUTS], *defs[MAX_DEFS];
    cli_list out_list = {outs, 0, MAX_OUTPUTS, "at most {max} outputs"};
    cli_list def_list = {defs, 0, MAX_DEFS, "at most {max} -D options"};
    long years = -1, every = 0, seeds[2] = {-1, -1};
    const char *seed = NULL;
    bool timing = false, quiet = false, params = false, summer = false, report = false;
    bool organ_drag = false;
    double *organ_buf = NULL; /* --organ-drag: leaf areas and fruit masses per segment */
    long modes = 0;
    cli_sway sway = cli_sway_default();
    cbm_write_options o = cbm_write_options_default();
    cli_light light = {false, cbm_light_def_default()};
    const char *light_csv = NULL;
    cli_opt rows[] = {
        {.name = "--help|-h", .kind = CLI_HELP},
        cli_grow_model_row(&model),
        cli_grow_years_row(&years),
        cli_grow_defines_row(&def_list,
                             "set a parameter (as in a parameter file; angles in degrees)"),
        {.name = "--seed",
         .kind = CLI_CUSTOM,
         .target = &seed,
         .parse = parse_seed,
         .bad = "--seed must be a non-negative integer",
         .arg = "N",
         .help = "generator seed (same as -D seed=N)"},
        {.name = "-o", .kind = CLI_LIST, .target = &out_list},
        {.name = "--every",
         .kind = CLI_LONG,
         .target = &every,
         .min = 1,
         .max = 1000000,
         .bad = "--every must be 1..1000000",
         .arg = "K",
         .help = "animation frame every K growth steps (.glb outputs)"},
        {.name = "--summer",
         .kind = CLI_SET,
         .target = &summer,
         .help = "stop at the end of the last summer (leaves and fruit on; the\n"
                 ".json then ends with that year, \"complete\": false)"},
        {.name = "--timing",
         .kind = CLI_SET,
         .target = &timing,
         .help = "time spent per phase on stderr"},
        {.name = "--modes",
         .kind = CLI_LONG,
         .target = &modes,
         .min = 1,
         .max = 10000,
         .bad = "--modes must be 1..10000",
         .arg = "N",
         .help = "print the N lowest natural frequencies (Hz) of the grown tree"},
        {.name = "--sway",
         .kind = CLI_CUSTOM,
         .target = &sway.seconds,
         .parse = parse_pos,
         .arg = "SECONDS",
         .help = "simulate the grown tree swaying in a gusty wind for SECONDS:\n"
                 ".glb outputs become the animation, .csv the tips' displacements"},
        {.name = "--wind",
         .kind = CLI_CUSTOM,
         .target = &sway.wind,
         .parse = parse_nonneg,
         .arg = "M_S",
         .help = "mean wind speed at 10 m for --sway (log profile; default 10)"},
        {.name = "--gust",
         .kind = CLI_CUSTOM,
         .target = &sway.gust,
         .parse = parse_nonneg,
         .arg = "I",
         .help = "turbulence intensity of the gusts for --sway (default 0.2; 0 steady)"},
        {.name = "--organ-area",
         .kind = CLI_CUSTOM,
         .target = &sway.organ_area,
         .parse = parse_nonneg,
         .arg = "M2_PER_KG",
         .help = "drag area of the leaves and fruit per kg for --sway (C_d 0.5;\n"
                 "default 0: no drag on them)"},
        {.name = "--gust-coherence",
         .kind = CLI_CUSTOM,
         .target = &sway.coherence,
         .parse = parse_nonneg,
         .arg = "A",
         .help = "gusts as a field correlated over the crown, coherence\n"
                 "exp(-A f r / U) (Davenport; ~10; default 0: one series)"},
        {.name = "--gust-grid",
         .kind = CLI_LONG,
         .target = &sway.grid,
         .min = 2,
         .max = 16,
         .bad = "--gust-grid must be 2..16",
         .arg = "N",
         .help = "points of the gust field along the crown (default 6)"},
        {.name = "--organ-drag",
         .kind = CLI_SET,
         .target = &organ_drag,
         .help = "drag on the model's leaves (plates that reconfigure) and fruit\n"
                 "(spheres) apart, for --sway and -o wind:FILE.csv"},
        {.name = "--sway-dt",
         .kind = CLI_CUSTOM,
         .target = &sway.dt,
         .parse = parse_pos,
         .arg = "S",
         .help = "time step of --sway (default 0.002 s)"},
        {.name = "--sway-modes",
         .kind = CLI_CUSTOM,
         .target = &sway.modes,
         .parse = parse_nonneg,
         .arg = "K",
         .help = "--sway by the lowest K modes only (modal reduction; default 0:\n"
                 "all degrees of freedom)"},
        {.name = "--quiet",
         .kind = CLI_SET,
         .target = &quiet,
         .help = "no per-year lines on stdout"},
        cli_grow_params_row(&params),
        {.name = "--seeds",
         .kind = CLI_CUSTOM,
         .target = seeds,
         .parse = parse_seeds,
         .arg = "A-B",
         .help = "grow once per seed A..B and write the median, quartiles,\n"
                 "minimum and maximum of the year-by-year figures over the\n"
                 "seeds (-o FILE.json; stdout: medians per year)"},
        {.name = "--report",
         .kind = CLI_SET,
         .target = &report,
         .help = "the final tree as a forester measures it (height, diameter at\n"
                 "breast height, crown, buckling safety, pipe model, branch\n"
                 "angles, stress ratios, intersections; cambium info --help)"},
        {.name = "--light",
         .kind = CLI_CUSTOM,
         .target = &light,
         .parse = cli_light_parse,
         .arg = "SKY[,K=V]",
         .help = "light of every leaf of the final tree by ray casting: SKY is\n"
                 "soc, uoc, dome or field; K=V: rings=N azimuths=N samples=N\n"
                 "direct=F sun-elevation=DEG one-sided periodic (docs/light.md);\n"
                 "-o light:FILE.csv writes it per leaf, --color-by light paints it"},
        {.kind = CLI_GROUP, .target = cli_limit_options()},
        {.kind = CLI_GROUP, .target = cli_output_options(&o)},
        {0}};
    cli_opts table = {.cmd = "grow",
                      .opts = rows,
                      .help = help,
                      .width = 18,
                      .unknown = "unknown option {opt}",
                      .unknown_last = "unknown option or missing value: {opt}",
                      .missing = "unknown option or missing value: {opt}"};
    if (cli_grow_is_ober(&table, argc, argv)) /* Oberlaender's parametric tree: its own command */
        return cmd_grow_ober(argc, argv);
    int prc = cli_options_parse(&table, argc, argv);
    if (prc != CLI_OK)
        return prc == CLI_HELP_SHOWN ? CLI_OK : prc;
    int nout = out_list.count, ndef = def_list.count;
    long seed_first = seeds[0], seed_last = seeds[1];
    if (seed_first >= 0) {
        for (int k = 0; k < nout; k++)
            if (strcmp(cli_extension(outs[k]), "json"))
                return cli_usage_error("grow", "--seeds writes statistics: %s is not .json",
                                       outs[k]);
        if (summer || every || params || seed)
            return cli_usage_error("grow",
                                   "--seeds does not go with --summer, --every, --params, --seed");
        if (modes > 0)
            return cli_usage_error("grow", "--seeds does not go with --modes");
        if (sway.seconds > 0)
            return cli_usage_error("grow", "--seeds does not go with --sway");
        if (light.on)
            return cli_usage_error("grow", "--seeds does not go with --light");
    }
    bool swaying = sway.seconds > 0;
    {
        /* the options of --sway without it: say so rather than ignore them */
        const char *only[] = {"--wind",       "--gust",      "--sway-dt",       "--organ-area",
                              "--sway-modes", "--gust-grid", "--gust-coherence"};
        for (int k = 0; k < 7 && !swaying; k++)
            for (cli_opt *r = rows; r->name; r++)
                if (!strcmp(r->name, only[k]) && r->seen)
                    return cli_usage_error("grow", "%s needs --sway SECONDS", only[k]);
        if (swaying && every > 0)
            return cli_usage_error("grow", "--sway does not go with --every");
        if (sway.modes != floor(sway.modes) || sway.modes > 1e9)
            return cli_usage_error("grow", "--sway-modes must be a whole number");
        if (swaying && sway.dt > sway.seconds)
            return cli_usage_error("grow", "--sway-dt must not exceed --sway");
        if (organ_drag && sway.organ_area > 0)
            return cli_usage_error("grow", "--organ-drag does not go with --organ-area");
    }
    cli_output_target targets[MAX_OUTPUTS];
    /* 0 scene, 1 csv, 2 mtg, 3 json, 4 wind:FILE.csv, 5 sway .glb, 6 sway table .csv,
     * 7 light:FILE.csv */
    int kind[MAX_OUTPUTS];
    const char *sway_glb[MAX_OUTPUTS], *sway_csv[MAX_OUTPUTS];
    int nsway_glb = 0, nsway_csv = 0;
    for (int k = 0; k < nout; k++) {
        const char *ext = cli_extension(outs[k]);
        kind[k] = !strcmp(ext, "csv") ? 1 : !strcmp(ext, "mtg") ? 2 : !strcmp(ext, "json") ? 3 : 0;
        if (!strncmp(outs[k], "wind:", 5)) {
            if (strcmp(ext, "csv"))
                return cli_usage_error("grow", "%s: the wind table is .csv", outs[k]);
            kind[k] = 4;
        }
        if (!strncmp(outs[k], "light:", 6)) {
            if (strcmp(ext, "csv"))
                return cli_usage_error("grow", "%s: the light table is .csv", outs[k]);
            kind[k] = 7;
            light_csv = outs[k] + 6;
            continue;
        }
        bool mprefix = !strncmp(outs[k], "motion:", 7);
        if (mprefix && !swaying)
            return cli_usage_error("grow", "%s: motion outputs need --sway SECONDS", outs[k]);
        if (swaying && (mprefix || (kind[k] == 1 && strncmp(outs[k], "wind:", 5)) ||
                        (kind[k] == 0 && !strcmp(ext, "glb") && !strchr(outs[k], ':')))) {
            const char *path = mprefix ? outs[k] + 7 : outs[k];
            if (!strcmp(ext, "glb")) {
                kind[k] = 5;
                sway_glb[nsway_glb++] = path;
            } else if (!strcmp(ext, "csv")) {
                kind[k] = 6;
                sway_csv[nsway_csv++] = path;
            } else
                return cli_usage_error("grow", "%s: a motion output is .glb or .csv", outs[k]);
            continue;
        }
        if (kind[k] == 0 && !cli_output_target_parse(outs[k], &targets[k]))
            return cli_usage_error("grow",
                                   "%s: unknown format (.png .svg .glb .obj .ply .csv .mtg "
                                   ".json, or FORMAT:PATH)",
                                   outs[k]);
    }
    /* the light table or the light colours ask for the light pass (soc sky by default) */
    if (light_csv || o.color_by == CBM_COLOR_LIGHT)
        light.on = true;
    {
        const char *paths[MAX_OUTPUTS];
        for (int k = 0; k < nout; k++)
            paths[k] = kind[k] == 0                                      ? targets[k].path
                       : kind[k] == 4                                    ? outs[k] + 5
                       : kind[k] == 7                                    ? outs[k] + 6
                       : kind[k] >= 5 && !strncmp(outs[k], "motion:", 7) ? outs[k] + 7
                                                                         : outs[k];
        if (cli_check_outputs(paths, nout) != CLI_OK)
            return CLI_FAIL;
    }
    if (organ_drag && !swaying) {
        bool wind_out = false;
        for (int k = 0; k < nout; k++)
            wind_out = wind_out || kind[k] == 4;
        if (!wind_out)
            return cli_usage_error("grow", "--organ-drag needs --sway SECONDS or -o wind:FILE.csv");
    }
    if (!model)
        model = "fruit-tree";
    cbm_context *ctx = cli_context();
    int rc = CLI_OK;
    cbm_tree *t = NULL;
    cbm_scene *sc = NULL;
    cbm_animation *anim[MAX_OUTPUTS] = {NULL};
    cbm_tree_def d = cbm_tree_def_default();
    cbm_status st;
    if (cli_grow_ends_with(model, ".tree"))
        st = cbm_tree_def_read(ctx, &d, model);
    else
        st = cbm_tree_def_builtin(ctx, model, &d);
    if (st != CBM_OK) {
        if (st == CBM_E_NOT_FOUND) {
            fprintf(stderr, "cambium grow: %s (built-in:", cbm_context_last_error(ctx));
            for (const char *const *n = cbm_tree_builtin_names(); *n; n++)
                fprintf(stderr, " %s", *n);
            fprintf(stderr, "; or a file NAME.tree)\n");
            cli_context_end(ctx);
            return CLI_USAGE;
        }
        rc = st == CBM_E_SYNTAX ? CLI_FAIL : cli_fail(ctx, st, model);
        goto done;
    }
    for (int k = 0; k < ndef + (seed ? 1 : 0); k++) {
        char name[128];
        const char *dv = k < ndef ? defs[k] : NULL, *val;
        if (dv) {
            if (!(val = cli_grow_define(dv, name, sizeof name))) {
                rc = CLI_USAGE;
                goto done;
            }
        } else {
            strcpy(name, "seed");
            val = seed;
        }
        if (!strncmp(name, "func", 4) && (name[4] == ' ' || name[4] == ':'))
            memmove(name, name + 5, strlen(name + 5) + 1);
        st = cbm_tree_def_set(ctx, &d, name, val);
        if (st != CBM_OK) {
            rc = cli_usage_error("grow", "-D %s", cbm_context_last_error(ctx));
            goto done;
        }
    }
    if (years >= 0)
        d.years = (int)years;
    if (params) {
        size_t need = cbm_tree_def_format(&d, NULL, 0);
        char *buf = malloc(need + 1);
        if (!buf) {
            rc = CLI_FAIL;
            goto done;
        }
        cbm_tree_def_format(&d, buf, need + 1);
        fputs(buf, stdout);
        free(buf);
        goto done;
    }
    if (seed_first >= 0) {
        rc = grow_seeds(ctx, &d, model, seed_first, seed_last, outs, nout, quiet);
        goto done;
    }
    if (swaying && nsway_glb + nsway_csv == 0) {
        rc = cli_usage_error("grow", "--sway writes .glb or .csv outputs: give -o FILE");
        goto done;
    }
    if (nout == 0 && quiet && !report && modes == 0) {
        rc = cli_usage_error("grow", "nothing to do: give -o FILE or drop --quiet");
        goto done;
    }
    st = cbm_tree_create(ctx, &d, &t);
    if (st == CBM_OK)
        st = cbm_scene_create(ctx, &sc);
    for (int k = 0; k < nout && st == CBM_OK && every > 0; k++)
        if (kind[k] == 0 && !strcmp(targets[k].format, "glb"))
            st = cbm_animation_create(ctx, &o, &anim[k]);
    if (st != CBM_OK) {
        rc = cli_fail(ctx, st, model);
        goto done;
    }
    cli_progress pr;
    cli_progress_begin(&pr);
    /* --timing: growth (derivation), scene building (interpretation, also for the animation
     * frames) and writing (animation frames added and files written) */
    double t0 = cli_seconds(), t_interpret = 0.0, t_write = 0.0;
    size_t step = 0;
    /* with --summer the last year stops at the end of its summer (leaves and fruit on) */
    int full = summer && d.years > 0 ? d.years - 1 : d.years;
    while (st == CBM_OK &&
           (cbm_tree_years(t) < full || (summer && d.years > 0 && cbm_tree_years(t) == full &&
                                         cbm_tree_current_season(t) == CBM_TREE_SUMMER))) {
        bool done_year = false;
        st = cbm_tree_step(t, &done_year);
        step++;
        if (st == CBM_OK && every > 0 && step % (size_t)every == 0) {
            double tf = cli_seconds();
            cbm_scene_clear(sc);
            st = cbm_tree_to_scene(t, sc, 8, o.ground);
            double tw = cli_seconds();
            t_interpret += tw - tf;
            for (int k = 0; k < nout && st == CBM_OK; k++)
                if (anim[k])
                    st = cbm_animation_add_frame(anim[k], sc);
            t_write += cli_seconds() - tw;
        }
        if (st == CBM_OK && done_year) {
            int y = cbm_tree_years(t);
            const cbm_tree_summary *s = cbm_tree_summary_of(t, y);
            cli_progress_end(&pr);
            if (!quiet)
                printf("year %2d: %6zu segments, height %.3f m, crown %.3f m, %zu leaves, %zu "
                       "fruit, %zu breaks, %zu reaction-wood segments, %zu passes, %.3f s\n",
                       y, s->segments, s->height, s->crown_width, s->leaves, s->fruit, s->breaks,
                       s->reaction_segments, s->passes, s->seconds);
        }
        const cbm_tree_summary *cs = cbm_tree_summary_current(t);
        cbm_progress state = {(size_t)cbm_tree_years(t), (size_t)d.years,
                              cbm_plant_segment_count(cbm_tree_plant(t)), cs->passes,
                              cli_seconds() - t0};
        cli_progress_update(&pr, &state);
    }
    cli_progress_end(&pr);
    if (st == CBM_OK && summer && d.years > 0 && !quiet) {
        const cbm_tree_summary *s = cbm_tree_summary_current(t);
        printf("year %2d: %6zu segments, height %.3f m, crown %.3f m, %zu leaves, %zu fruit, %zu "
               "breaks (to the end of summer), %zu passes, %.3f s\n",
               s->year, s->segments, s->height, s->crown_width, s->leaves, s->fruit, s->breaks,
               s->passes, s->seconds);
    }
    double grow_time = cli_seconds() - t0;
    double derive = grow_time - t_interpret - t_write; /* minus the animation frames */
    if (st != CBM_OK) {
        rc = cli_fail(ctx, st, "growing the tree");
        goto done;
    }
    bool scene_built = false;
    if (organ_drag) {
        /* the leaves' area from their mass and the model's leaf_density (kg/m^2), the fruit's
         * mass: per segment, at its distal node (docs/dynamics.md, "Drag of leaves and fruit") */
        size_t ns = cbm_plant_segment_count(cbm_tree_plant(t));
        organ_buf = calloc(2 * (ns ? ns : 1), sizeof *organ_buf);
        if (!organ_buf) {
            rc = cli_fail(ctx, CBM_E_NOMEM, "--organ-drag");
            goto done;
        }
        for (size_t i = 0; i < ns; i++) {
            cbm_tree_segment ts;
            if (cbm_tree_segment_info(t, i, &ts) == CBM_OK) {
                organ_buf[i] = ts.leaf_mass / d.leaf_density;
                organ_buf[ns + i] = ts.fruit_mass;
            }
        }
        sway.leaf_area = organ_buf;
        sway.fruit_mass = organ_buf + ns;
        sway.fruit_density = d.fruit_density;
    }
    if (light.on) {
        /* the light of the scene the writers get, so that --color-by light paints it */
        double tw = cli_seconds();
        cbm_scene_clear(sc);
        st = cbm_tree_to_scene(t, sc, 12, o.ground);
        scene_built = true;
        t_interpret += cli_seconds() - tw;
        if (st == CBM_OK)
            st = cli_light_run(ctx, &light, sc, light_csv, quiet);
        if (st != CBM_OK)
            rc = cli_fail(ctx, st, "light");
    }
    for (int k = 0; k < nout && rc == CLI_OK; k++) {
        double tw = cli_seconds(), ti = 0.0;
        if (kind[k] == 1)
            st = cbm_write_segments_csv(ctx, cbm_tree_plant(t), outs[k]);
        else if (kind[k] == 2)
            st = cbm_write_mtg(ctx, cbm_tree_plant(t), outs[k]);
        else if (kind[k] == 3)
            st = write_summary(ctx, t, model, &d, grow_time, summer, outs[k]);
        else if (kind[k] == 4)
            st = write_wind(ctx, cbm_tree_plant(t), &sway, outs[k] + 5);
        else if (kind[k] == 7)
            st = CBM_OK; /* written by the light pass above */
        else if (kind[k] >= 5)
            continue; /* the sway's, below */
        else if (anim[k])
            st = cbm_animation_write(anim[k], targets[k].path);
        else {
            if (!scene_built) {
                cbm_scene_clear(sc);
                st = cbm_tree_to_scene(t, sc, 12, o.ground);
                scene_built = true;
                ti = cli_seconds() - tw;
                t_interpret += ti;
            }
            if (st == CBM_OK)
                st = cbm_scene_write_as(ctx, sc, targets[k].path, targets[k].format, &o);
        }
        double dw = cli_seconds() - tw - ti;
        t_write += dw;
        if (st != CBM_OK)
            rc = cli_fail(ctx, st, outs[k]);
        else if (timing)
            fprintf(stderr, "grow: wrote %s in %.3f s\n", outs[k], dw);
    }
    if (timing && rc == CLI_OK)
        print_timing(ctx, t, summer, derive, t_interpret, t_write, cli_seconds() - t0);
    if (swaying && rc == CLI_OK) {
        st = cli_grow_sway(ctx, cbm_tree_plant(t), &sway, sway_glb, nsway_glb, sway_csv, nsway_csv,
                           timing);
        if (st != CBM_OK)
            rc = cli_fail(ctx, st, "sway");
    }
    if (modes > 0 && rc == CLI_OK) {
        /* natural frequencies about the final equilibrium (docs/dynamics.md) */
        double *f = malloc((size_t)modes * sizeof *f);
        double tm = cli_seconds();
        st = f ? cbm_plant_modes(cbm_tree_plant(t), (size_t)modes, f, NULL) : CBM_E_NOMEM;
        if (st == CBM_OK) {
            printf("%s after %d years: lowest %ld natural frequencies (Hz):", model,
                   cbm_tree_years(t), modes);
            for (long k = 0; k < modes; k++)
                printf(" %.6g", f[k]);
            printf("\n");
            if (timing)
                fprintf(stderr, "grow: modes in %.3f s\n", cli_seconds() - tm);
        } else
            rc = cli_fail(ctx, st, "natural frequencies");
        free(f);
    }
    if (report && rc == CLI_OK) {
        cbm_tree_measures tm;
        st = cbm_measure_plant(ctx, NULL, cbm_tree_plant(t), &tm);
        if (st == CBM_OK) {
            printf("%s after %d years:\n", model, cbm_tree_years(t));
            cli_measures_print(&tm);
        } else {
            rc = cli_fail(ctx, st, "measuring the tree");
        }
    }
done:
    free(organ_buf);
    for (int k = 0; k < nout; k++)
        cbm_animation_destroy(anim[k]);
    cbm_scene_destroy(sc);
    cbm_tree_destroy(t);
    cli_context_end(ctx);
    return rc;
}
