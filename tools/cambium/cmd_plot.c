/* cambium plot: a generic plotter of table files (CSV, or the array of objects of a JSON file)
 * through the library's plots (cambium/plot.h): one or more y columns against an x column, in
 * one or more panels, written as PNG or SVG. Made for the files cambium writes (grow's
 * year-by-year JSON and segment tables, bend's node tables, any CSV). */
#include "cli.h"
#include "commands.h"
#include "options.h"
#include "table.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_OUTPUTS 8
#define MAX_Y       16

static void plot_help(const cli_opts *t)
{
    printf("usage: cambium plot DATA.csv|DATA.json -y COL[,COL...] -o PLOT.png|PLOT.svg [options]\n"
           "\n"
           "Plots columns of a table: a CSV file whose first line names the columns (lines\n"
           "starting with '#' are skipped) or the first array of objects in a JSON file (e.g.\n"
           "the \"years\" of `cambium grow -o summary.json`). A column is named by its header or\n"
           "by its number from 1. Empty cells and non-numbers leave gaps.\n"
           "\n");
    cli_options_help(stdout, t);
}

/* "a,b,c" into at most max names (pointers into s, which is modified). */
static int split_names(char *s, char **out, int max)
{
    int n = 0;
    for (char *tok = s; tok && n < max;) {
        char *c = strchr(tok, ',');
        if (c)
            *c++ = '\0';
        if (*tok)
            out[n++] = tok;
        tok = c;
    }
    return n;
}

/* "MIN:MAX" with either side empty (NaN). */
static bool parse_range(const char *s, double *lo, double *hi)
{
    const char *colon = strchr(s, ':');
    if (!colon)
        return false;
    char a[64], b[64];
    size_t la = (size_t)(colon - s);
    if (la >= sizeof a || strlen(colon + 1) >= sizeof b)
        return false;
    memcpy(a, s, la);
    a[la] = '\0';
    memcpy(b, colon + 1, strlen(colon + 1) + 1);
    *lo = *hi = NAN;
    if (*a && !cli_parse_double(a, lo))
        return false;
    if (*b && !cli_parse_double(b, hi))
        return false;
    return !(isfinite(*lo) && isfinite(*hi) && !(*lo < *hi));
}

typedef struct plot_args {
    const char *data, *x, *title, *xlabel, *ylabel;
    const char *panel_cols[CBM_PLOT_MAX_PANELS];
    int npanels;
    const char *outputs[MAX_OUTPUTS];
    int noutputs;
    int style; /* 0 line, 1 points, 2 both */
    bool logx, logy;
    double xr[2], yr[2];
    int width, height;
} plot_args;

/* The value parsers of the options (target: the plot_args, or the field named). */

static bool parse_data(const char *v, void *target, char *why, size_t n)
{
    plot_args *a = target;
    if (a->data)
        snprintf(why, n, "one data file, got '%s' and '{value}'", a->data);
    else
        a->data = v;
    return !*why;
}

/* -y COLS, then --panel COLS for each further panel */
static bool add_panel(plot_args *a, const char *v, bool first, char *why, size_t n)
{
    if (first && a->panel_cols[0])
        snprintf(why, n, "-y given twice (use --panel for more panels)");
    else if (!first && !a->panel_cols[0])
        snprintf(why, n, "--panel comes after -y");
    else if (a->npanels >= CBM_PLOT_MAX_PANELS)
        snprintf(why, n, "at most %d panels", CBM_PLOT_MAX_PANELS);
    else
        a->panel_cols[a->npanels++] = v;
    return !*why;
}

static bool parse_y(const char *v, void *target, char *why, size_t n)
{
    return add_panel(target, v, true, why, n);
}

static bool parse_panel(const char *v, void *target, char *why, size_t n)
{
    return add_panel(target, v, false, why, n);
}

static bool parse_style(const char *v, void *target, char *why, size_t n)
{
    int *style = target;
    if (!strcmp(v, "line") || !strcmp(v, "lines"))
        *style = 0;
    else if (!strcmp(v, "points"))
        *style = 1;
    else if (!strcmp(v, "both"))
        *style = 2;
    else
        snprintf(why, n, "--style: '{value}' is not line, points or both");
    return !*why;
}

static bool parse_axis_range(const char *v, void *target, char *why, size_t n)
{
    double *r = target;
    if (!parse_range(v, &r[0], &r[1]))
        snprintf(why, n, "{opt}: '{value}' is not MIN:MAX with MIN < MAX");
    return !*why;
}

static bool parse_size(const char *v, void *target, char *why, size_t n)
{
    plot_args *a = target;
    const char *xpos = strchr(v, 'x');
    char w_text[32];
    long w, h;
    if (!xpos) {
        snprintf(why, n, "--size: '{value}' is not WxH");
        return false;
    }
    bool ok = (size_t)(xpos - v) < sizeof w_text;
    if (ok) {
        memcpy(w_text, v, (size_t)(xpos - v));
        w_text[xpos - v] = '\0';
    }
    ok = ok && cli_parse_long(w_text, &w) && cli_parse_long(xpos + 1, &h);
    if (!ok || w < 16 || h < 16 || w > 16384 || h > 16384) {
        snprintf(why, n, "--size: '{value}' is not WxH with 16..16384 pixels");
        return false;
    }
    a->width = (int)w, a->height = (int)h;
    return true;
}

static int parse_args(int argc, char **argv, plot_args *a)
{
    memset(a, 0, sizeof *a);
    a->xr[0] = a->xr[1] = a->yr[0] = a->yr[1] = NAN;
    a->width = 800, a->height = 600;
    cli_list outs = {a->outputs, 0, MAX_OUTPUTS, "at most {max} outputs"};
    cli_opt rows[] = {{.name = "--help|-h", .kind = CLI_HELP},
                      {.name = "DATA", .kind = CLI_POSITIONAL, .target = a, .parse = parse_data},
                      {.name = "-x",
                       .kind = CLI_TEXT,
                       .target = &a->x,
                       .arg = "COL",
                       .help = "the x column (default: the row number from 0)"},
                      {.name = "-y",
                       .kind = CLI_CUSTOM,
                       .target = a,
                       .parse = parse_y,
                       .arg = "COL[,COL...]",
                       .help = "the y columns of the first panel (required)"},
                      {.name = "--panel",
                       .kind = CLI_CUSTOM,
                       .target = a,
                       .parse = parse_panel,
                       .arg = "COL[,...]",
                       .help = "a further panel below, with these y columns (up to 3 more)"},
                      {.name = "-o",
                       .kind = CLI_LIST,
                       .target = &outs,
                       .arg = "FILE",
                       .help = "output, .png or .svg (repeatable; FORMAT:PATH names the format)"},
                      {.name = "--style",
                       .kind = CLI_CUSTOM,
                       .target = &a->style,
                       .parse = parse_style,
                       .arg = "S",
                       .help = "line (default), points, or both"},
                      {.name = "--title",
                       .kind = CLI_TEXT,
                       .target = &a->title,
                       .arg = "TEXT",
                       .help = "figure title"},
                      {.name = "--xlabel",
                       .kind = CLI_TEXT,
                       .target = &a->xlabel,
                       .arg = "TEXT",
                       .help = "x axis title (default: the x column's name)"},
                      {.name = "--ylabel",
                       .kind = CLI_TEXT,
                       .target = &a->ylabel,
                       .arg = "TEXT",
                       .help = "y axis title of every panel (default: the column's name when\n"
                               "a panel has one; a legend names several)"},
                      {.name = "--logx, --logy",
                       .kind = CLI_DOC,
                       .help = "logarithmic axes (points <= 0 are left out)"},
                      {.name = "--logx", .kind = CLI_SET, .target = &a->logx},
                      {.name = "--logy", .kind = CLI_SET, .target = &a->logy},
                      {.name = "--xrange",
                       .kind = CLI_CUSTOM,
                       .target = a->xr,
                       .parse = parse_axis_range,
                       .arg = "MIN:MAX",
                       .help = "x range (either side may be empty: from the data)"},
                      {.name = "--yrange",
                       .kind = CLI_CUSTOM,
                       .target = a->yr,
                       .parse = parse_axis_range,
                       .arg = "MIN:MAX",
                       .help = "y range of every panel"},
                      {.name = "--size",
                       .kind = CLI_CUSTOM,
                       .target = a,
                       .parse = parse_size,
                       .arg = "WxH",
                       .help = "picture size in pixels (default 800x600)"},
                      {0}};
    cli_opts table = {.cmd = "plot",
                      .opts = rows,
                      .help = plot_help,
                      .width = 19,
                      .unknown = "unknown option '{opt}'",
                      .missing = "{opt} needs a value"};
    int rc = cli_options_parse(&table, argc, argv);
    a->noutputs = outs.count;
    if (rc != CLI_OK)
        return rc;
    if (!a->data)
        return cli_usage_error("plot", "no data file");
    if (!a->npanels)
        return cli_usage_error("plot", "no y column (-y COL)");
    if (!a->noutputs)
        return cli_usage_error("plot", "no output (-o PLOT.png or PLOT.svg)");
    for (int k = 0; k < a->noutputs; k++) {
        const char *colon = strchr(a->outputs[k], ':');
        const char *ext =
            colon && colon - a->outputs[k] <= 4 ? a->outputs[k] : cli_extension(a->outputs[k]);
        if (strncmp(ext, "png", 3) && strncmp(ext, "svg", 3) && strncmp(ext, "PNG", 3) &&
            strncmp(ext, "SVG", 3))
            return cli_usage_error("plot", "-o %s: plots are .png or .svg", a->outputs[k]);
    }
    return CLI_OK;
}

static cbm_status write_output(cbm_plot *p, const char *spec)
{
    const char *colon = strchr(spec, ':');
    if (colon && colon - spec <= 4) {
        char fmt[8];
        memcpy(fmt, spec, (size_t)(colon - spec));
        fmt[colon - spec] = '\0';
        return cbm_plot_write_as(p, colon + 1, fmt);
    }
    return cbm_plot_write(p, spec);
}

int cmd_plot(int argc, char **argv)
{
    plot_args a;
    int rc = parse_args(argc, argv, &a);
    if (rc != CLI_OK)
        return rc < 0 ? CLI_OK : rc;
    cli_table t;
    char err[512];
    if (!cli_table_read(a.data, &t, err, sizeof err)) {
        fprintf(stderr, "cambium plot: %s\n", err);
        return CLI_FAIL;
    }
    /* the columns, checked before anything is drawn */
    long xcol = -1, ycols[CBM_PLOT_MAX_PANELS][MAX_Y];
    int ny[CBM_PLOT_MAX_PANELS];
    rc = CLI_OK;
    if (a.x && (xcol = cli_table_column(&t, a.x)) < 0)
        rc = cli_usage_error("plot", "%s has no column '%s'", a.data, a.x);
    for (int k = 0; k < a.npanels && rc == CLI_OK; k++) {
        char *names[MAX_Y + 1];
        size_t len = strlen(a.panel_cols[k]) + 1;
        char *cols = malloc(len); /* split_names cuts it */
        if (!cols) {
            rc = CLI_FAIL;
            break;
        }
        memcpy(cols, a.panel_cols[k], len);
        ny[k] = split_names(cols, names, MAX_Y + 1);
        if (ny[k] == 0 || ny[k] > MAX_Y)
            rc = cli_usage_error("plot", "a panel takes 1 to %d y columns", MAX_Y);
        for (int c = 0; c < ny[k] && rc == CLI_OK; c++)
            if ((ycols[k][c] = cli_table_column(&t, names[c])) < 0)
                rc = cli_usage_error("plot", "%s has no column '%s' (it has %zu: %s%s)", a.data,
                                     names[c], t.ncols, t.ncols ? t.names[0] : "",
                                     t.ncols > 1 ? ", ..." : "");
        free(cols);
    }
    if (rc != CLI_OK) {
        cli_table_free(&t);
        return rc;
    }
    cbm_context *ctx = cli_context();
    cbm_plot_def d = cbm_plot_def_default();
    d.width = a.width, d.height = a.height, d.panels = a.npanels, d.title = a.title;
    cbm_plot *p = NULL;
    cbm_status st = cbm_plot_create(ctx, &d, &p);
    for (int k = 0; k < a.npanels && st == CBM_OK; k++) {
        cbm_plot_axes_def ax = cbm_plot_axes_def_default();
        ax.xlog = a.logx, ax.ylog = a.logy;
        ax.xmin = a.xr[0], ax.xmax = a.xr[1], ax.ymin = a.yr[0], ax.ymax = a.yr[1];
        if (k == a.npanels - 1)
            ax.xlabel = a.xlabel ? a.xlabel : xcol >= 0 ? t.names[xcol] : "row";
        ax.ylabel = a.ylabel ? a.ylabel : ny[k] == 1 ? t.names[ycols[k][0]] : NULL;
        st = cbm_plot_set_axes(p, k, &ax);
        for (int c = 0; c < ny[k] && st == CBM_OK; c++) {
            cbm_plot_series_def s = cbm_plot_series_def_default();
            s.x = xcol >= 0 ? t.cols[xcol] : NULL;
            s.y = t.cols[ycols[k][c]];
            s.n = t.nrows;
            s.label = ny[k] > 1 ? t.names[ycols[k][c]] : NULL;
            s.line = a.style == 1 ? CBM_PLOT_NO_LINE : CBM_PLOT_SOLID;
            s.marker =
                a.style ? (cbm_plot_marker)(CBM_PLOT_MARKER_CIRCLE + c % 6) : CBM_PLOT_MARKER_NONE;
            st = cbm_plot_add_series(p, k, &s);
        }
    }
    for (int k = 0; k < a.noutputs && st == CBM_OK; k++)
        if ((st = write_output(p, a.outputs[k])) != CBM_OK)
            rc = cli_fail(ctx, st, a.outputs[k]);
    if (st != CBM_OK && rc == CLI_OK)
        rc = cli_fail(ctx, st, "plot");
    cbm_plot_destroy(p);
    cli_context_end(ctx);
    cli_table_free(&t);
    return rc;
}
