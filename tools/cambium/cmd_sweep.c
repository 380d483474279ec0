/* cambium sweep MODEL --param NAME=V1,V2,... [--param ...] [--seeds S1,S2,...] [-n YEARS]
 *              [-D NAME=VALUE]... [-o FILE.csv|.json|.svg|.png]...: the one-at-a-time
 * sensitivity sweeps of Gürtler's chapter 6 as a tool (docs/cli.md). For every --param in turn
 * and every value of it (the others at the model's values and the -D overrides), a built-in tree
 * model, a .tree file or an L-system model (.l: NAME is one of its #defines) is grown for each
 * seed (cli_study.h); the rows give the extent of the grown plant in x, y and z (max - min over
 * every segment node, m) and its segment count. The table has one row per (param, value, seed);
 * a plot per sweep shows the extents and the count against the value, averaged over the seeds. */
#define _POSIX_C_SOURCE 200809L
#include "cli_study.h"
#include "commands.h"
#include "options.h"

#include "cambium/plot.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_SWEEPS  8
#define MAX_VALUES  64
#define MAX_SEEDS   32
#define MAX_OUTPUTS 8

typedef struct sweep {
    char name[64];
    char values[MAX_VALUES][64];
    int n;
} sweep;

typedef struct sweep_list {
    sweep s[MAX_SWEEPS];
    int n;
} sweep_list;

typedef struct seed_list {
    char v[MAX_SEEDS][24];
    int n;
} seed_list;

typedef struct row {
    int sweep, value, seed;
    double ext[3];
    size_t segments;
    double seconds;
} row;

static void help(const cli_opts *t)
{
    printf("usage: cambium sweep MODEL --param NAME=V1,V2,... [--param ...] [--seeds S1,S2,...]\n"
           "                     [-n YEARS] [-D NAME=VALUE]... [-o FILE.csv|.json|.svg|.png]...\n\n"
           "One-at-a-time sensitivity sweeps of a built-in tree model or a .tree file (as\n"
           "`cambium grow` takes it) or of an L-system model (.l: NAME is a #define of the\n"
           "model, -n the derivation steps, --seeds seed its productions): for each --param\n"
           "and each of its values, the model is grown for every seed and measured: extent in\n"
           "x, y, z (max - min over the segment nodes, m; a .l model without mechanics: the\n"
           "turtle's box) and segment count (without mechanics: the turtle's primitives).\n"
           "-o .csv/.json writes the table (param,value,seed,extent_x,extent_y,extent_z,\n"
           "segments,seconds), .svg/.png a plot per sweep (several --param: FILE-NAME.svg\n"
           "each) of the seed means against the value. Without -o the table is printed.\n");
    cli_options_help(stdout, t);
}

static bool parse_param(const char *v, void *target, char *why, size_t n)
{
    sweep_list *l = target;
    const char *eq = strchr(v, '=');
    if (l->n == MAX_SWEEPS) {
        snprintf(why, n, "at most %d --param sweeps", MAX_SWEEPS);
        return false;
    }
    if (!eq || eq == v || (size_t)(eq - v) >= sizeof l->s[0].name || !eq[1]) {
        snprintf(why, n, "--param expects NAME=V1,V2,..., found '{value}'");
        return false;
    }
    sweep *s = &l->s[l->n];
    memset(s, 0, sizeof *s);
    memcpy(s->name, v, (size_t)(eq - v));
    for (const char *p = eq + 1; *p;) {
        const char *c = strchr(p, ',');
        size_t len = c ? (size_t)(c - p) : strlen(p);
        if (len == 0 || len >= sizeof s->values[0] || s->n == MAX_VALUES) {
            snprintf(why, n, "--param %s: empty or too long value, or more than %d values", s->name,
                     MAX_VALUES);
            return false;
        }
        memcpy(s->values[s->n++], p, len);
        p += len;
        if (*p == ',')
            p++;
    }
    l->n++;
    return true;
}

static bool parse_seeds(const char *v, void *target, char *why, size_t n)
{
    seed_list *l = target;
    l->n = 0;
    for (const char *p = v; *p;) {
        const char *c = strchr(p, ',');
        size_t len = c ? (size_t)(c - p) : strlen(p);
        long x;
        char buf[24];
        if (len == 0 || len >= sizeof buf || l->n == MAX_SEEDS) {
            snprintf(why, n, "--seeds expects up to %d numbers separated by commas", MAX_SEEDS);
            return false;
        }
        memcpy(buf, p, len);
        buf[len] = 0;
        if (!cli_parse_long(buf, &x) || x < 0) {
            snprintf(why, n, "--seeds: '%s' is not a seed (a whole number >= 0)", buf);
            return false;
        }
        memcpy(l->v[l->n++], buf, len + 1);
        p += len;
        if (*p == ',')
            p++;
    }
    return l->n > 0;
}

static void write_table(FILE *f, bool json, const sweep_list *sl, const seed_list *seeds,
                        const row *rows, int nr)
{
    if (json)
        fprintf(f, "{\"rows\": [");
    else
        fprintf(f, "param,value,seed,extent_x,extent_y,extent_z,segments,seconds\n");
    for (int i = 0; i < nr; i++) {
        const row *r = &rows[i];
        const sweep *s = &sl->s[r->sweep];
        const char *seed = seeds->n ? seeds->v[r->seed] : "model";
        if (json)
            fprintf(f,
                    "%s{\"param\": \"%s\", \"value\": \"%s\", \"seed\": \"%s\", \"extent_x\": "
                    "%.9g, \"extent_y\": %.9g, \"extent_z\": %.9g, \"segments\": %zu, "
                    "\"seconds\": %.6g}",
                    i ? ", " : "", s->name, s->values[r->value], seed, r->ext[0], r->ext[1],
                    r->ext[2], r->segments, r->seconds);
        else
            fprintf(f, "%s,%s,%s,%.9g,%.9g,%.9g,%zu,%.6g\n", s->name, s->values[r->value], seed,
                    r->ext[0], r->ext[1], r->ext[2], r->segments, r->seconds);
    }
    if (json)
        fprintf(f, "]}\n");
}

/* The plot of sweep k: extents (top) and segment count (bottom) against the value (or its
 * index when a value is not a number), seed means. */
static cbm_status write_plot(cbm_context *ctx, const char *path, const sweep *sw, int k,
                             const row *rows, int nr)
{
    double x[MAX_VALUES], m[4][MAX_VALUES];
    bool numeric = true;
    for (int v = 0; v < sw->n; v++) {
        numeric = numeric && cli_parse_double(sw->values[v], &x[v]);
        int c = 0;
        for (int q = 0; q < 4; q++)
            m[q][v] = 0.0;
        for (int i = 0; i < nr; i++)
            if (rows[i].sweep == k && rows[i].value == v) {
                for (int q = 0; q < 3; q++)
                    m[q][v] += rows[i].ext[q];
                m[3][v] += (double)rows[i].segments;
                c++;
            }
        for (int q = 0; q < 4; q++)
            m[q][v] = c ? m[q][v] / c : NAN;
    }
    if (!numeric)
        for (int v = 0; v < sw->n; v++)
            x[v] = v;
    cbm_plot_def pd = cbm_plot_def_default();
    char title[128];
    snprintf(title, sizeof title, "sweep of %s", sw->name);
    pd.title = title;
    pd.panels = 2;
    cbm_plot *pl = NULL;
    cbm_status s = cbm_plot_create(ctx, &pd, &pl);
    if (s != CBM_OK)
        return s;
    cbm_plot_axes_def ax = cbm_plot_axes_def_default();
    ax.xlabel = numeric ? sw->name : "value index";
    ax.ylabel = "extent (m)";
    s = cbm_plot_set_axes(pl, 0, &ax);
    ax.ylabel = "segments";
    if (s == CBM_OK)
        s = cbm_plot_set_axes(pl, 1, &ax);
    static const char *const labels[4] = {"x", "y", "z", "segments"};
    for (int q = 0; q < 4 && s == CBM_OK; q++) {
        cbm_plot_series_def sd = cbm_plot_series_def_default();
        sd.x = x;
        sd.y = m[q];
        sd.n = (size_t)sw->n;
        sd.label = q < 3 ? labels[q] : NULL;
        sd.marker = CBM_PLOT_MARKER_CIRCLE;
        s = cbm_plot_add_series(pl, q < 3 ? 0 : 1, &sd);
    }
    if (s == CBM_OK)
        s = cbm_plot_write(pl, path);
    cbm_plot_destroy(pl);
    return s;
}

/* What the outputs show. */
typedef struct sweep_out {
    const sweep_list *sl;
    const seed_list *seeds;
    const row *rows;
    int nr;
} sweep_out;

static void write_rows(FILE *f, bool json, void *ud)
{
    const sweep_out *o = ud;
    write_table(f, json, o->sl, o->seeds, o->rows, o->nr);
}

/* FILE.svg for one sweep, FILE-NAME.svg for each of several. */
static void plot_path(char *buf, size_t n, const char *path, const char *name, bool several)
{
    if (!several) {
        snprintf(buf, n, "%s", path);
        return;
    }
    const char *dot = strrchr(path, '.');
    snprintf(buf, n, "%.*s-%s%s", (int)(dot - path), path, name, dot);
}

static cbm_status write_plots(cbm_context *ctx, const char *path, void *ud)
{
    const sweep_out *o = ud;
    cbm_status s = CBM_OK;
    for (int w = 0; w < o->sl->n && s == CBM_OK; w++) {
        char p[512];
        plot_path(p, sizeof p, path, o->sl->s[w].name, o->sl->n > 1);
        s = write_plot(ctx, p, &o->sl->s[w], w, o->rows, o->nr);
    }
    return s;
}

int cmd_sweep(int argc, char **argv)
{
    const char *model = NULL;
    sweep_list *sl = calloc(1, sizeof *sl);
    seed_list seeds;
    memset(&seeds, 0, sizeof seeds);
    const char *outs[MAX_OUTPUTS];
    cli_list out_list = {outs, 0, MAX_OUTPUTS, NULL};
    cli_study_args margs;
    cli_study_args_init(&margs);
    if (!sl)
        return CLI_FAIL;
    cli_opt opts[] = {
        {.name = "--help|-h", .kind = CLI_HELP},
        {.name = "MODEL", .kind = CLI_POSITIONAL, .target = &model, .parse = cli_parse_one_spec},
        {.name = "--param",
         .kind = CLI_CUSTOM,
         .target = sl,
         .arg = "NAME=V1,V2,...",
         .help = "a parameter and its values: one sweep (repeatable)",
         .parse = parse_param,
         .bad = "--param needs NAME=V1,V2,..."},
        {.name = "--seeds",
         .kind = CLI_CUSTOM,
         .target = &seeds,
         .arg = "S1,S2,...",
         .help = "grow each value with these seeds (default: the model's seed)",
         .parse = parse_seeds,
         .bad = "--seeds needs a list of seeds"},
        {.name = "-o",
         .kind = CLI_CUSTOM,
         .target = &out_list,
         .arg = "FILE",
         .help = ".csv/.json table, .svg/.png plot per sweep (repeatable)",
         .parse = cli_study_parse_output,
         .bad = "-o needs a file name"},
        {.kind = CLI_GROUP, .target = cli_study_model_options(&margs)},
        {.kind = CLI_GROUP, .target = cli_limit_options()},
        {0}};
    cli_opts table = {.cmd = "sweep",
                      .opts = opts,
                      .help = help,
                      .width = 24,
                      .unknown = "unknown option '{opt}'"};
    int rc = cli_options_parse(&table, argc, argv);
    if (rc != CLI_OK) {
        free(sl);
        return rc == CLI_HELP_SHOWN ? CLI_OK : rc;
    }
    if (!model || sl->n == 0) {
        free(sl);
        return cli_usage_error("sweep", "expected a MODEL and at least one --param NAME=V1,...");
    }
    static char ppaths[MAX_OUTPUTS * MAX_SWEEPS][512];
    const char *check[MAX_OUTPUTS * MAX_SWEEPS];
    int nc = 0;
    for (int k = 0; k < out_list.count; k++) {
        if (!cli_study_is_plot(outs[k]))
            check[nc++] = outs[k];
        else
            for (int w = 0; w < sl->n; w++) {
                plot_path(ppaths[nc], sizeof ppaths[nc], outs[k], sl->s[w].name, sl->n > 1);
                check[nc] = ppaths[nc];
                nc++;
            }
    }
    rc = cli_check_outputs(check, nc);
    if (rc != CLI_OK) {
        free(sl);
        return CLI_FAIL;
    }
    /* the model and the -D overrides; every swept value must be valid: all are checked
     * before anything grows */
    cli_study_model *base = malloc(sizeof *base);
    rc = base ? cli_study_model_load(base, "sweep", model, &margs, false) : CLI_FAIL;
    for (int w = 0; w < sl->n && rc == CLI_OK; w++)
        for (int v = 0; v < sl->s[w].n && rc == CLI_OK; v++)
            rc = cli_study_check_param(base, "sweep", sl->s[w].name, sl->s[w].values[v]);
    int nseeds = seeds.n ? seeds.n : 1, nr = 0, cap = 0;
    for (int w = 0; w < sl->n; w++)
        cap += sl->s[w].n * nseeds;
    row *rows = calloc(cap > 0 ? (size_t)cap : 1, sizeof *rows);
    if (!rows)
        rc = CLI_FAIL;
    for (int w = 0; w < sl->n && rc == CLI_OK; w++)
        for (int v = 0; v < sl->s[w].n && rc == CLI_OK; v++)
            for (int q = 0; q < nseeds && rc == CLI_OK; q++) {
                row *r = &rows[nr];
                r->sweep = w;
                r->value = v;
                r->seed = q;
                cli_study_run run = {sl->s[w].name, sl->s[w].values[v], seeds.n ? seeds.v[q] : NULL,
                                     -1, false};
                cli_study_plant p;
                rc = cli_study_grow(base, &run, &p);
                if (rc == CLI_OK) {
                    memcpy(r->ext, p.ext, sizeof r->ext);
                    r->segments = p.segments;
                    r->seconds = p.seconds;
                    nr++;
                }
            }
    sweep_out so = {sl, &seeds, rows, nr};
    if (rc == CLI_OK)
        rc = cli_study_write(outs, out_list.count, write_plots, write_rows, &so);
    if (rc == CLI_OK && out_list.count == 0)
        write_table(stdout, false, sl, &seeds, rows, nr);
    free(rows);
    free(base);
    free(sl);
    return rc;
}
