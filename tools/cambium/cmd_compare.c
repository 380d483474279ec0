/* cambium compare SPEC [--solvers A,B,...] [-o FILE.csv|.json|.svg|.png]... [--json]: one bend
 * problem (docs/bend.md) solved by several bending methods (solver = relax, fast, approx, ...),
 * each in its own context so that its time and peak memory are its own; their shapes, the
 * phenotype distance of Gürtler eqs. 5.3-5.7 between every ordered pair, time and memory
 * (docs/cli.md, docs/methods.md). Any method failing fails the job and nothing is written. */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "commands.h"
#include "options.h"

#include "cambium/approx.h"
#include "cambium/bend.h"
#include "cambium/plot.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_SPEC_BYTES (1u << 20)
#define MAX_OUTPUTS    8

typedef struct solver_list {
    cbm_mech_solver s[CBM_MECH_SOLVER_COUNT];
    int n;
} solver_list;

/* One method's run. */
typedef struct method_run {
    cbm_mech_solver solver;
    cbm_bend_node *nodes; /* n + 1 */
    double *xyz;          /* 3 (n + 1) */
    size_t n;             /* segments */
    cbm_bend_result res;
    double seconds;
    size_t peak_bytes;
} method_run;

static void help(const cli_opts *t)
{
    char names[128];
    cbm_mech_solver_names(names, sizeof names);
    printf("usage: cambium compare SPEC [--solvers A,B,...] [-o FILE.csv|.json|.svg|.png]...\n"
           "                       [--json] [limits]\n\n"
           "Solves the bend problem of SPEC (docs/bend.md; its own `solver` key is overridden)\n"
           "with several bending methods (default: all of %s) and compares them:\n"
           "each method's tip, time (s) and peak memory (bytes through the library's allocator),\n"
           "and the phenotype distance (Gurtler eqs. 5.3-5.7) from each shape to each other one:\n"
           "the trapezoid sum over the nodes of the distance to the nearest node of the other\n"
           "shape (m x node index; `mean` divides it by the segment count, m).\n"
           "-o .csv writes the shapes (solver,node,s,x,y,z,angle_deg), .json the summary (as\n"
           "--json), .svg/.png a plot of the shapes (x, y).\n",
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

static bool parse_output(const char *v, void *target, char *why, size_t n)
{
    cli_list *outs = target;
    const char *ext = cli_extension(v);
    if (outs->count == outs->max)
        snprintf(why, n, "at most %d outputs", outs->max);
    else if (strcmp(ext, "csv") && strcmp(ext, "json") && strcmp(ext, "svg") && strcmp(ext, "png"))
        snprintf(why, n, "{value}: unsupported output format '.%s' (use .csv, .json, .svg or .png)",
                 ext);
    else
        cli_list_add(outs, v);
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

static void write_json(FILE *f, const method_run *m, int nm, const double *dist)
{
    fprintf(f, "{\"methods\": [");
    for (int a = 0; a < nm; a++) {
        const method_run *r = &m[a];
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
            double e = dist[a * nm + b];
            fprintf(f, "%s{\"from\": \"%s\", \"to\": \"%s\", \"error\": %.12g, \"mean\": %.12g}",
                    k++ ? ", " : "", cbm_mech_solver_name(m[a].solver),
                    cbm_mech_solver_name(m[b].solver), e, m[a].n ? e / (double)m[a].n : 0.0);
        }
    fprintf(f, "]}\n");
}

static cbm_status write_plot(cbm_context *ctx, const char *path, const method_run *m, int nm)
{
    cbm_plot_def pd = cbm_plot_def_default();
    pd.title = "compare: shapes of the methods";
    cbm_plot *pl = NULL;
    cbm_status s = cbm_plot_create(ctx, &pd, &pl);
    if (s != CBM_OK)
        return s;
    cbm_plot_axes_def ax = cbm_plot_axes_def_default();
    ax.xlabel = "x (m)";
    ax.ylabel = "y (m)";
    s = cbm_plot_set_axes(pl, 0, &ax);
    for (int a = 0; a < nm && s == CBM_OK; a++) {
        size_t n = m[a].n + 1;
        double *x = malloc(n * sizeof *x), *y = malloc(n * sizeof *y);
        if (!x || !y || !m[a].nodes)
            s = CBM_E_NOMEM;
        for (size_t i = 0; s == CBM_OK && i < n; i++) {
            x[i] = m[a].nodes[i].x;
            y[i] = m[a].nodes[i].y;
        }
        cbm_plot_series_def sd = cbm_plot_series_def_default();
        sd.x = x;
        sd.y = y;
        sd.n = n;
        sd.label = cbm_mech_solver_name(m[a].solver);
        sd.line = (cbm_plot_line)(a % 3);
        if (s == CBM_OK)
            s = cbm_plot_add_series(pl, 0, &sd);
        free(x);
        free(y);
    }
    if (s == CBM_OK)
        s = cbm_plot_write(pl, path);
    cbm_plot_destroy(pl);
    return s;
}

static int write_outputs(const char *const *outs, int nout, bool json, const method_run *m, int nm,
                         const double *dist)
{
    cbm_context *ctx = cli_context();
    int rc = CLI_OK;
    for (int k = 0; k < nout && rc == CLI_OK; k++) {
        const char *ext = cli_extension(outs[k]);
        cbm_status s;
        if (!strcmp(ext, "svg") || !strcmp(ext, "png"))
            s = write_plot(ctx, outs[k], m, nm);
        else {
            cbm_out *o = NULL;
            s = cbm_out_open(ctx, outs[k], &o);
            if (s == CBM_OK) {
                FILE *f = cbm_out_stream(o);
                if (!strcmp(ext, "json"))
                    write_json(f, m, nm, dist);
                else {
                    fprintf(f, "solver,node,s,x,y,z,angle_deg\n");
                    for (int a = 0; a < nm; a++)
                        for (size_t i = 0; m[a].nodes && i <= m[a].n; i++) {
                            const cbm_bend_node *d = &m[a].nodes[i];
                            fprintf(f, "%s,%zu,%.12g,%.12g,%.12g,%.12g,%.12g\n",
                                    cbm_mech_solver_name(m[a].solver), i, d->s, d->x, d->y, d->z,
                                    d->angle_deg);
                        }
                }
                s = cbm_out_commit(o);
            }
        }
        if (s != CBM_OK)
            rc = cli_fail(ctx, s, outs[k]);
    }
    cli_context_end(ctx);
    if (rc == CLI_OK && json)
        write_json(stdout, m, nm, dist);
    if (rc == CLI_OK && !json && nout == 0) {
        for (int a = 0; a < nm; a++) {
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
                printf(" %12.6g", dist[a * nm + b]);
            printf("\n");
        }
    }
    return rc;
}

int cmd_compare(int argc, char **argv)
{
    const char *spec_path = NULL;
    solver_list solvers = {{0}, 0};
    const char *outs[MAX_OUTPUTS];
    cli_list out_list = {outs, 0, MAX_OUTPUTS, NULL};
    bool json = false;
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
        {.name = "--json", .kind = CLI_SET, .target = &json, .help = "print the summary"},
        {.name = "-o",
         .kind = CLI_CUSTOM,
         .target = &out_list,
         .arg = "FILE",
         .help = ".csv shapes, .json summary, .svg/.png plot (repeatable)",
         .parse = parse_output,
         .bad = "-o needs a file name"},
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
        return cli_usage_error("compare", "expected a SPEC file (see cambium compare --help)");
    if (solvers.n == 0)
        for (int k = 0; k < CBM_MECH_SOLVER_COUNT; k++)
            solvers.s[solvers.n++] = (cbm_mech_solver)k;
    if (cli_check_outputs(outs, out_list.count) != CLI_OK)
        return CLI_FAIL;
    size_t len = 0;
    char *text = cli_read_regular_file(spec_path, MAX_SPEC_BYTES, &len);
    if (!text) {
        fprintf(stderr, "cambium: %s: cannot read the spec\n", spec_path);
        return CLI_FAIL;
    }
    if (len > MAX_SPEC_BYTES) {
        free(text);
        fprintf(stderr, "cambium: %s: spec larger than %u bytes\n", spec_path, MAX_SPEC_BYTES);
        return CLI_FAIL;
    }
    int nm = solvers.n;
    method_run m[CBM_MECH_SOLVER_COUNT];
    memset(m, 0, sizeof m);
    int rc = CLI_OK;
    for (int a = 0; a < nm && rc == CLI_OK; a++) {
        m[a].solver = solvers.s[a];
        rc = run_method(text, len, spec_path, &m[a]);
    }
    free(text);
    double dist[CBM_MECH_SOLVER_COUNT * CBM_MECH_SOLVER_COUNT] = {0};
    for (int a = 0; a < nm && rc == CLI_OK; a++)
        for (int b = 0; b < nm; b++)
            if (a != b && cbm_approx_phenotype_distance(m[a].xyz, m[a].n + 1, m[b].xyz, m[b].n + 1,
                                                        3, NULL, &dist[a * nm + b]) != CBM_OK)
                rc = CLI_FAIL;
    if (rc == CLI_OK)
        rc = write_outputs(outs, out_list.count, json, m, nm, dist);
    for (int a = 0; a < nm; a++) {
        free(m[a].nodes);
        free(m[a].xyz);
    }
    return rc;
}
