/* cambium compare SPEC|MODEL [--solvers A,B,...] [-n YEARS] [-D NAME=VALUE]... [--seed N]
 *                 [-o FILE.csv|.json|.svg|.png]... [--json]: one problem solved by several
 * bending methods (solver = relax, fast, approx, fem), each in its own context so that its time
 * and peak memory are its own. The problem is a bend spec (docs/bend.md) or a grown plant: a
 * built-in tree model or .tree file (its `solver` set to each method) or an L+C model with
 * mechanics (.l: every SolverMethod() overridden by each method, cbm_lsys_def.solver), grown
 * once per method (cli_study.h). Written: their shapes, the phenotype distance of Gürtler eqs.
 * 5.3-5.7 between every ordered pair, the tip, heights, time and memory (docs/cli.md,
 * docs/methods.md). Any method failing fails the job and nothing is written. */
#define _POSIX_C_SOURCE 200809L
#include "cli_study.h"
#include "commands.h"
#include "options.h"

#include "cambium/approx.h"
#include "cambium/bend.h"
#include "cambium/plot.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_OUTPUTS 8

typedef struct solver_list {
    cbm_mech_solver s[CBM_MECH_SOLVER_COUNT];
    int n;
} solver_list;

/* One method's run: a bend spec's rod (nodes, res) or a grown plant (plant). */
typedef struct method_run {
    cbm_mech_solver solver;
    cbm_bend_node *nodes; /* n + 1 */
    double *xyz;          /* 3 (n + 1): the nodes the distance is measured on */
    size_t n;             /* segments */
    cbm_bend_result res;
    cli_study_plant plant; /* a grown model: its measures and shape (xyz is plant.nodes) */
    double seconds;
    size_t peak_bytes;
} method_run;

static void help(const cli_opts *t)
{
    char names[128];
    cbm_mech_solver_names(names, sizeof names);
    printf(
        "usage: cambium compare SPEC|MODEL [--solvers A,B,...] [-n YEARS] [-D NAME=VALUE]...\n"
        "                       [--seed N] [-o FILE.csv|.json|.svg|.png]... [--json] [limits]\n\n"
        "Solves one problem with several bending methods (default: all of %s) and\n"
        "compares them. The problem is the bend problem of SPEC (docs/bend.md; its own\n"
        "`solver` key is overridden) or a plant grown once per method: a built-in tree model\n"
        "or a .tree file (-D sets its parameters, `solver` is each method's) or an L+C model\n"
        "with mechanics (MODEL.l: -D overrides its #defines, -n its steps, --seed as run's;\n"
        "every SolverMethod() of the model gives way to each method).\n"
        "Each method's tip, time (s) and peak memory (bytes through the library's allocator)\n"
        "(a plant: segments, height of the top above the base, extents, the leader's tip and\n"
        "its horizontal deflection from the base), and the phenotype distance (Gurtler eqs.\n"
        "5.3-5.7) from each shape to each other one: the trapezoid sum over the nodes of the\n"
        "distance to the nearest node of the other shape (m x node index; `mean` divides it\n"
        "by the segment count, m).\n"
        "-o .csv writes the shapes (solver,node,s,x,y,z,angle_deg; a plant: solver,segment,\n"
        "x0,y0,z0,x1,y1,z1), .json the summary (as --json), .svg/.png a plot of the shapes\n"
        "(x, y; a plant: side x-y and front z-y).\n",
        names);
    cli_options_help(stdout, t);
}

static bool parse_solvers(const char *v, void *target, char *why, size_t n)
{
    solver_list *l = target;
    l->n = 0;
    const char *p = v;
    while (*p) {
        const char *e = strchr(p, ',');
        size_t len = e ? (size_t)(e - p) : strlen(p);
        char buf[64];
        if (len == 0 || len >= sizeof buf) {
            snprintf(why, n, "--solvers expects names separated by commas, found '{value}'");
            return false;
        }
        memcpy(buf, p, len);
        buf[len] = 0;
        cbm_mech_solver s;
        if (!cbm_mech_solver_parse(buf, &s)) {
            char names[128];
            cbm_mech_solver_names(names, sizeof names);
            snprintf(why, n, "--solvers: unknown solver '%s' (expected %s)", buf, names);
            return false;
        }
        for (int k = 0; k < l->n; k++)
            if (l->s[k] == s) {
                snprintf(why, n, "--solvers: '%s' is named twice", buf);
                return false;
            }
        l->s[l->n++] = s;
        p += len;
        if (*p == ',')
            p++;
    }
    if (l->n == 0)
        snprintf(why, n, "--solvers needs at least one name");
    return !*why;
}

/* Runs one method in a context of its own; CLI_OK or the failure (printed). */
static int run_method(const char *text, size_t len, const char *path, method_run *m)
{
    cbm_context *ctx = cli_context();
    cbm_bend_spec spec;
    cbm_status s = cbm_bend_spec_parse(ctx, text, len, path, &spec);
    if (s != CBM_OK) {
        int rc = cli_fail(ctx, s, path);
        cli_context_end(ctx);
        return rc;
    }
    spec.solver = m->solver;
    cbm_plant *plant = NULL;
    double t0 = cli_now();
    s = cbm_bend_run(ctx, &spec, &plant, &m->res);
    m->seconds = cli_now() - t0;
    char what[64];
    snprintf(what, sizeof what, "compare (%s)", cbm_mech_solver_name(m->solver));
    if (s == CBM_OK) {
        m->n = cbm_plant_segment_count(plant);
        m->nodes = malloc((m->n + 1) * sizeof *m->nodes);
        m->xyz = malloc(3 * (m->n + 1) * sizeof *m->xyz);
        s = m->nodes && m->xyz ? cbm_bend_nodes(plant, m->nodes, m->n + 1) : CBM_E_NOMEM;
    }
    int rc = s == CBM_OK ? CLI_OK : cli_fail(ctx, s, what);
    if (rc == CLI_OK && m->nodes && m->xyz)
        for (size_t i = 0; i <= m->n; i++) {
            m->xyz[3 * i] = m->nodes[i].x;
            m->xyz[3 * i + 1] = m->nodes[i].y;
            m->xyz[3 * i + 2] = m->nodes[i].z;
        }
    cbm_plant_destroy(plant);
    m->peak_bytes = cbm_context_peak_bytes(ctx);
    cli_context_end(ctx);
    return rc;
}

/* Grows the plant of one method (cli_study.h). */
static int grow_method(const cli_study_model *model, const char *seed, method_run *m)
{
    cli_study_run r = {NULL, NULL, seed, (int)m->solver, true};
    int rc = cli_study_grow(model, &r, &m->plant);
    if (rc == CLI_OK) {
        m->n = m->plant.segments;
        m->xyz = m->plant.nodes;
        m->plant.nodes = NULL; /* freed with m */
        m->seconds = m->plant.seconds;
        m->peak_bytes = m->plant.peak_bytes;
    }
    return rc;
}

/* What the outputs show. */
typedef struct compare_out {
    const method_run *m;
    int nm;
    const double *dist;
    bool plant; /* grown plants, else a bend spec's rods */
} compare_out;

static void write_json(FILE *f, const compare_out *o)
{
    const method_run *m = o->m;
    int nm = o->nm;
    fprintf(f, "{\"methods\": [");
    for (int a = 0; a < nm; a++) {
        const method_run *r = &m[a];
        if (o->plant) {
            const cli_study_plant *p = &r->plant;
            fprintf(f,
                    "%s{\"solver\": \"%s\", \"segments\": %zu, \"height\": %.12g, \"extent_x\": "
                    "%.12g, \"extent_y\": %.12g, \"extent_z\": %.12g, \"tip_x\": %.12g, "
                    "\"tip_y\": %.12g, \"tip_z\": %.12g, \"tip_deflection\": %.12g, "
                    "\"seconds\": %.6g, \"peak_bytes\": %zu}",
                    a ? ", " : "", cbm_mech_solver_name(r->solver), r->n, p->height, p->ext[0],
                    p->ext[1], p->ext[2], p->tip[0], p->tip[1], p->tip[2], p->deflection,
                    r->seconds, r->peak_bytes);
            continue;
        }
        if (!r->nodes) /* a method that did not run stops the command before any output */
            continue;
        const cbm_bend_node *tip = &r->nodes[r->n];
        fprintf(f,
                "%s{\"solver\": \"%s\", \"tip_x\": %.12g, \"tip_y\": %.12g, \"tip_z\": %.12g, "
                "\"tip_angle_deg\": %.12g, \"base_moment\": %.12g, \"seconds\": %.6g, "
                "\"peak_bytes\": %zu, \"passes\": %zu, \"residual\": %.6g, \"segments\": %zu}",
                a ? ", " : "", cbm_mech_solver_name(r->solver), tip->x, tip->y, tip->z,
                tip->angle_deg, r->nodes[0].moment, r->seconds, r->peak_bytes, r->res.stats.passes,
                r->res.stats.residual, r->n);
    }
    fprintf(f, "], \"distances\": [");
    int k = 0;
    for (int a = 0; a < nm; a++)
        for (int b = 0; b < nm; b++) {
            if (a == b)
                continue;
            double e = o->dist[a * nm + b];
            fprintf(f, "%s{\"from\": \"%s\", \"to\": \"%s\", \"error\": %.12g, \"mean\": %.12g}",
                    k++ ? ", " : "", cbm_mech_solver_name(m[a].solver),
                    cbm_mech_solver_name(m[b].solver), e, m[a].n ? e / (double)m[a].n : 0.0);
        }
    fprintf(f, "]}\n");
}

/* The shapes as a table: a rod's nodes, or a plant's segments. */
static void write_table(FILE *f, bool json, void *ud)
{
    const compare_out *o = ud;
    if (json) {
        write_json(f, o);
        return;
    }
    const method_run *m = o->m;
    fprintf(f, o->plant ? "solver,segment,x0,y0,z0,x1,y1,z1\n" : "solver,node,s,x,y,z,angle_deg\n");
    for (int a = 0; a < o->nm; a++) {
        const char *name = cbm_mech_solver_name(m[a].solver);
        for (size_t i = 0; o->plant && m[a].plant.lines && i < m[a].n; i++) {
            const double *l = m[a].plant.lines + 6 * i;
            fprintf(f, "%s,%zu,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g\n", name, i, l[0], l[1], l[2],
                    l[3], l[4], l[5]);
        }
        for (size_t i = 0; !o->plant && m[a].nodes && i <= m[a].n; i++) {
            const cbm_bend_node *d = &m[a].nodes[i];
            fprintf(f, "%s,%zu,%.12g,%.12g,%.12g,%.12g,%.12g\n", name, i, d->s, d->x, d->y, d->z,
                    d->angle_deg);
        }
    }
}

/* Method a's points for a plot against coordinate `h` (0 x, 2 z) and y: a rod's polyline, or
 * every segment of a plant with a break (NaN) after it. *n points; NULL without memory. */
static double *plot_points(const compare_out *o, int a, int h, size_t *n)
{
    const method_run *r = &o->m[a];
    *n = o->plant ? 3 * r->n : r->n + 1;
    double *xy = malloc(2 * (*n ? *n : 1) * sizeof *xy);
    if (!xy || (o->plant ? !r->plant.lines : !r->nodes)) {
        free(xy);
        return NULL;
    }
    for (size_t i = 0; i < *n; i++) {
        double *x = &xy[i], *y = &xy[*n + i];
        if (!o->plant) {
            *x = r->nodes[i].x;
            *y = r->nodes[i].y;
        } else if (i % 3 == 2) {
            *x = *y = NAN;
        } else {
            const double *p = r->plant.lines + 6 * (i / 3) + 3 * (i % 3);
            *x = p[h];
            *y = p[1];
        }
    }
    return xy;
}

static cbm_status write_plot(cbm_context *ctx, const char *path, void *ud)
{
    const compare_out *o = ud;
    cbm_plot_def pd = cbm_plot_def_default();
    pd.title = "compare: shapes of the methods";
    pd.panels = o->plant ? 2 : 1;
    cbm_plot *pl = NULL;
    cbm_status s = cbm_plot_create(ctx, &pd, &pl);
    if (s != CBM_OK)
        return s;
    for (int panel = 0; panel < pd.panels && s == CBM_OK; panel++) {
        cbm_plot_axes_def ax = cbm_plot_axes_def_default();
        ax.xlabel = panel ? "z (m)" : "x (m)";
        ax.ylabel = "y (m)";
        if (o->plant)
            ax.title = panel ? "front" : "side";
        s = cbm_plot_set_axes(pl, panel, &ax);
        for (int a = 0; a < o->nm && s == CBM_OK; a++) {
            size_t n = 0;
            double *xy = plot_points(o, a, panel ? 2 : 0, &n);
            cbm_plot_series_def sd = cbm_plot_series_def_default();
            sd.x = xy;
            sd.y = xy ? xy + n : NULL;
            sd.n = n;
            sd.label = cbm_mech_solver_name(o->m[a].solver);
            sd.line = (cbm_plot_line)(a % 3);
            s = xy ? cbm_plot_add_series(pl, panel, &sd) : CBM_E_NOMEM;
            free(xy);
        }
    }
    if (s == CBM_OK)
        s = cbm_plot_write(pl, path);
    cbm_plot_destroy(pl);
    return s;
}

static void print_summary(const compare_out *o)
{
    const method_run *m = o->m;
    int nm = o->nm;
    if (o->plant)
        printf("%-8s %9s %10s %10s %10s %10s %11s %9s %12s\n", "method", "segments", "height_m",
               "extent_x", "extent_z", "tip_y", "deflection", "seconds", "peak_bytes");
    for (int a = 0; a < nm; a++) {
        if (o->plant) {
            const cli_study_plant *p = &m[a].plant;
            printf("%-8s %9zu %10.4g %10.4g %10.4g %10.4g %11.4g %9.3g %12zu\n",
                   cbm_mech_solver_name(m[a].solver), m[a].n, p->height, p->ext[0], p->ext[2],
                   p->tip[1], p->deflection, m[a].seconds, m[a].peak_bytes);
            continue;
        }
        if (!m[a].nodes)
            continue;
        const cbm_bend_node *tip = &m[a].nodes[m[a].n];
        printf("%-8s tip (%.6g, %.6g) m, tip angle %.6g deg, %.3g s, %zu bytes peak, %zu "
               "passes, residual %.3g\n",
               cbm_mech_solver_name(m[a].solver), tip->x, tip->y, tip->angle_deg, m[a].seconds,
               m[a].peak_bytes, m[a].res.stats.passes, m[a].res.stats.residual);
    }
    printf("phenotype distance (eq. 5.7, m x node; row: from, column: to):\n%-8s", "");
    for (int b = 0; b < nm; b++)
        printf(" %12s", cbm_mech_solver_name(m[b].solver));
    printf("\n");
    for (int a = 0; a < nm; a++) {
        printf("%-8s", cbm_mech_solver_name(m[a].solver));
        for (int b = 0; b < nm; b++)
            printf(" %12.6g", o->dist[a * nm + b]);
        printf("\n");
    }
}

/* A plant to grow, not a bend spec: a .l or .tree file or a built-in tree model's name. */
static bool names_model(const char *path)
{
    const char *ext = cli_extension(path);
    if (!strcmp(ext, "l") || !strcmp(ext, "tree"))
        return true;
    for (const char *const *b = cbm_tree_builtin_names(); *b; b++)
        if (!strcmp(path, *b))
            return true;
    return false;
}

/* The bend problem of the spec, once per method. */
static int run_spec(const char *spec_path, method_run *m, int nm)
{
    size_t len = 0;
    char *text = cli_read_spec(spec_path, &len);
    if (!text)
        return CLI_FAIL;
    int rc = CLI_OK;
    for (int a = 0; a < nm && rc == CLI_OK; a++)
        rc = run_method(text, len, spec_path, &m[a]);
    free(text);
    return rc;
}

int cmd_compare(int argc, char **argv)
{
    const char *spec_path = NULL, *seed = NULL;
    solver_list solvers = {{0}, 0};
    const char *outs[MAX_OUTPUTS];
    cli_list out_list = {outs, 0, MAX_OUTPUTS, NULL};
    cli_study_args margs;
    cli_study_args_init(&margs);
    bool json = false;
    long seed_value = -1;
    cli_opt rows[] = {
        {.name = "--help|-h", .kind = CLI_HELP},
        {.name = "SPEC", .kind = CLI_POSITIONAL, .target = &spec_path, .parse = cli_parse_one_spec},
        {.name = "--solvers",
         .kind = CLI_CUSTOM,
         .target = &solvers,
         .arg = "A,B,...",
         .help = "the methods to run, in this order (default: all)",
         .parse = parse_solvers,
         .bad = "--solvers needs a list of solver names"},
        {.name = "--seed",
         .kind = CLI_LONG,
         .target = &seed_value,
         .arg = "N",
         .help = "a MODEL's seed (default: the model's)",
         .min = 0,
         .max = 2147483647,
         .bad = "{opt} expects a whole number >= 0, found '{value}'"},
        {.name = "--json", .kind = CLI_SET, .target = &json, .help = "print the summary"},
        {.name = "-o",
         .kind = CLI_CUSTOM,
         .target = &out_list,
         .arg = "FILE",
         .help = ".csv shapes, .json summary, .svg/.png plot (repeatable)",
         .parse = cli_study_parse_output,
         .bad = "-o needs a file name"},
        {.kind = CLI_GROUP, .target = cli_study_model_options(&margs)},
        {.kind = CLI_GROUP, .target = cli_limit_options()},
        {0}};
    cli_opts table = {.cmd = "compare",
                      .opts = rows,
                      .help = help,
                      .width = 22,
                      .unknown = "unknown option '{opt}'"};
    int prc = cli_options_parse(&table, argc, argv);
    if (prc != CLI_OK)
        return prc == CLI_HELP_SHOWN ? CLI_OK : prc;
    if (!spec_path)
        return cli_usage_error("compare",
                               "expected a SPEC file or a MODEL (see cambium compare --help)");
    bool plant = names_model(spec_path);
    if (!plant && (margs.years >= 0 || margs.def_list.count || seed_value >= 0))
        return cli_usage_error("compare", "-n, -D and --seed go with a MODEL, not a bend SPEC");
    if (solvers.n == 0)
        for (int k = 0; k < CBM_MECH_SOLVER_COUNT; k++)
            solvers.s[solvers.n++] = (cbm_mech_solver)k;
    if (cli_check_outputs(outs, out_list.count) != CLI_OK)
        return CLI_FAIL;
    int nm = solvers.n;
    method_run m[CBM_MECH_SOLVER_COUNT];
    memset(m, 0, sizeof m);
    for (int a = 0; a < nm; a++)
        m[a].solver = solvers.s[a];
    int rc = CLI_OK;
    char seed_text[24];
    if (seed_value >= 0) {
        snprintf(seed_text, sizeof seed_text, "%ld", seed_value);
        seed = seed_text;
    }
    if (plant) {
        cli_study_model *model = malloc(sizeof *model);
        rc = model ? cli_study_model_load(model, "compare", spec_path, &margs, true) : CLI_FAIL;
        for (int a = 0; a < nm && rc == CLI_OK; a++)
            rc = grow_method(model, seed, &m[a]);
        free(model);
    } else {
        rc = run_spec(spec_path, m, nm);
    }
    double dist[CBM_MECH_SOLVER_COUNT * CBM_MECH_SOLVER_COUNT] = {0};
    for (int a = 0; a < nm && rc == CLI_OK; a++)
        for (int b = 0; b < nm; b++)
            if (a != b && cbm_approx_phenotype_distance(m[a].xyz, m[a].n + 1, m[b].xyz, m[b].n + 1,
                                                        3, NULL, &dist[a * nm + b]) != CBM_OK)
                rc = CLI_FAIL;
    compare_out o = {m, nm, dist, plant};
    if (rc == CLI_OK)
        rc = cli_study_write(outs, out_list.count, write_plot, write_table, &o);
    if (rc == CLI_OK && json)
        write_json(stdout, &o);
    if (rc == CLI_OK && !json && out_list.count == 0)
        print_summary(&o);
    for (int a = 0; a < nm; a++) {
        free(m[a].nodes);
        free(m[a].xyz);
        cli_study_plant_free(&m[a].plant);
    }
    return rc;
}
