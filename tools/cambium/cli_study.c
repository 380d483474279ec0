/* Growing one model for `cambium compare` and `cambium sweep` (cli_study.h). */
#define _POSIX_C_SOURCE 200809L
#include "cli_study.h"

#include "cambium/model.h"
#include "cambium/plot.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static bool ends_with(const char *s, const char *tail)
{
    size_t n = strlen(s), k = strlen(tail);
    return n > k && !strcmp(s + n - k, tail);
}

/* NAME=VALUE split into name (a buffer) and the value after '='. */
static const char *split(const char *nv, char *name, size_t n)
{
    const char *eq = strchr(nv, '=');
    size_t len = eq ? (size_t)(eq - nv) : strlen(nv);
    if (len >= n)
        len = n - 1;
    memcpy(name, nv, len);
    name[len] = 0;
    return eq ? eq + 1 : "";
}

/* The .l model's definition: its -D, then one more NAME=VALUE (or none) in defs (room for
 * CLI_STUDY_MAX_DEFS + 1). */
static cbm_model_def lsys_def(const cli_study_model *m, const char *extra, const char **defs)
{
    size_t nd = m->ndefines;
    memcpy(defs, m->defines, nd * sizeof *defs);
    if (extra)
        defs[nd++] = extra; /* after the -D: the preprocessor takes the last definition */
    cbm_model_def d = cbm_model_def_default();
    d.lsys.path = m->path;
    d.lsys.defines = defs;
    d.lsys.define_count = nd;
    return d;
}

/* Compiles the .l model with one more NAME=VALUE (or none): CBM_OK or the error (diagnostics
 * printed through ctx); *mechanics (may be NULL) says whether it declares any. */
static cbm_status compile_lsys(cbm_context *ctx, const cli_study_model *m, const char *extra,
                               bool *mechanics)
{
    const char *defs[CLI_STUDY_MAX_DEFS + 1];
    cbm_model_def d = lsys_def(m, extra, defs);
    cbm_model *model = NULL;
    cbm_status s = cbm_model_load(ctx, &d, &model);
    if (s == CBM_OK && mechanics)
        *mechanics = cbm_lsys_has_mechanics(cbm_model_lsys(model));
    cbm_model_destroy(model);
    return s;
}

int cli_study_model_load(cli_study_model *m, const char *cmd, const char *path,
                         const cli_study_args *a, bool need_mechanics)
{
    memset(m, 0, sizeof *m);
    m->path = path;
    m->years = a->years;
    const char *const *defs = a->defs;
    int ndefs = a->def_list.count;
    m->lsys = ends_with(path, ".l");
    cbm_context *ctx = cli_context();
    int rc = CLI_OK;
    if (m->lsys) {
        cli_set_model_output(NULL); /* what the model prints would mix with the tables */
        for (int k = 0; k < ndefs && k < CLI_STUDY_MAX_DEFS; k++)
            m->defines[m->ndefines++] = defs[k];
        /* compiled once here, so that a broken model stops the study before its first run */
        bool mechanics = false;
        cbm_status s = compile_lsys(ctx, m, NULL, &mechanics);
        if (s != CBM_OK)
            rc = cli_fail(ctx, s, path);
        else if (need_mechanics && !mechanics)
            rc = cli_usage_error(cmd, "%s declares no mechanics: there is no bending to compare",
                                 path);
    } else {
        m->tree = cbm_tree_def_default();
        cbm_status s = ends_with(path, ".tree") ? cbm_tree_def_read(ctx, &m->tree, path)
                                                : cbm_tree_def_builtin(ctx, path, &m->tree);
        if (s != CBM_OK)
            rc = s == CBM_E_NOT_FOUND ? cli_usage_error(cmd, "%s", cbm_context_last_error(ctx))
                                      : cli_fail(ctx, s, path);
        for (int k = 0; k < ndefs && rc == CLI_OK; k++) {
            char name[128];
            const char *value = split(defs[k], name, sizeof name);
            if (cbm_tree_def_set(ctx, &m->tree, name, value) != CBM_OK)
                rc = cli_usage_error(cmd, "-D %s", cbm_context_last_error(ctx));
        }
    }
    cli_context_end(ctx);
    return rc;
}

int cli_study_check_param(const cli_study_model *m, const char *cmd, const char *name,
                          const char *value)
{
    cbm_context *ctx = cli_context();
    int rc = CLI_OK;
    if (m->lsys) {
        /* the preprocessor refuses a name the model does not #define */
        char nv[256];
        snprintf(nv, sizeof nv, "%s=%s", name, value);
        if (compile_lsys(ctx, m, nv, NULL) != CBM_OK)
            rc = cli_usage_error(cmd, "--param %s: not a #define of %s, or a bad value", nv,
                                 m->path);
    } else {
        cbm_tree_def probe = m->tree;
        if (cbm_tree_def_set(ctx, &probe, name, value) != CBM_OK)
            rc = cli_usage_error(cmd, "--param %s", cbm_context_last_error(ctx));
    }
    cli_context_end(ctx);
    return rc;
}

/* The measures of a mechanical plant, and its shape when asked. */
static cbm_status measure_plant(const cbm_plant *p, bool shape, cli_study_plant *out)
{
    size_t n = cbm_plant_segment_count(p);
    out->segments = n;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    double base[3] = {0, 0, 0};
    for (int a = 0; a < 3; a++)
        out->tip[a] = NAN;
    if (shape) {
        out->nodes = malloc(3 * (n + 1) * sizeof *out->nodes);
        out->lines = malloc(6 * (n ? n : 1) * sizeof *out->lines);
        if (!out->nodes || !out->lines)
            return CBM_E_NOMEM;
    }
    /* the leader: from the first root along the continuation children (a child comes after its
     * parent in segment order, so one pass finds the chain's end) */
    int64_t leader = -1;
    for (size_t i = 0; i < n; i++) {
        cbm_segment_state s;
        cbm_status st = cbm_plant_segment(p, i, &s);
        if (st != CBM_OK)
            return st;
        const double pr[3] = {s.proximal.x, s.proximal.y, s.proximal.z};
        const double di[3] = {s.distal.x, s.distal.y, s.distal.z};
        if (i == 0) {
            memcpy(base, pr, sizeof base);
            leader = 0;
        } else if (s.parent == leader && s.continuation) {
            leader = (int64_t)i;
        }
        if ((int64_t)i == leader)
            memcpy(out->tip, di, sizeof base);
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], fmin(pr[a], di[a]));
            hi[a] = fmax(hi[a], fmax(pr[a], di[a]));
        }
        if (shape) {
            if (i == 0)
                memcpy(out->nodes, pr, sizeof base);
            memcpy(out->nodes + 3 * (i + 1), di, sizeof base);
            memcpy(out->lines + 6 * i, pr, sizeof base);
            memcpy(out->lines + 6 * i + 3, di, sizeof base);
        }
    }
    for (int a = 0; a < 3; a++)
        out->ext[a] = n ? hi[a] - lo[a] : 0.0;
    out->height = n ? hi[1] - base[1] : 0.0;
    out->deflection = n ? hypot(out->tip[0] - base[0], out->tip[2] - base[2]) : 0.0;
    if (shape && n == 0)
        memcpy(out->nodes, base, sizeof base);
    return CBM_OK;
}

static int grow_tree(cbm_context *ctx, const cli_study_model *m, const cli_study_run *r,
                     cli_study_plant *out, const char *what)
{
    cbm_tree_def d = m->tree;
    cbm_status s = r->name ? cbm_tree_def_set(ctx, &d, r->name, r->value) : CBM_OK;
    if (s == CBM_OK && r->seed)
        s = cbm_tree_def_set(ctx, &d, "seed", r->seed);
    if (s == CBM_OK && r->solver >= 0)
        s = cbm_tree_def_set(ctx, &d, "solver", cbm_mech_solver_name((cbm_mech_solver)r->solver));
    if (s != CBM_OK)
        return cli_fail(ctx, s, what);
    if (m->years >= 0)
        d.years = (int)m->years;
    cbm_tree *t = NULL;
    double t0 = cli_now();
    s = cbm_tree_create(ctx, &d, &t);
    if (s == CBM_OK)
        s = cbm_tree_run(t);
    out->seconds = cli_now() - t0;
    if (s == CBM_OK)
        s = measure_plant(cbm_tree_plant(t), r->shape, out);
    cbm_tree_destroy(t);
    return s == CBM_OK ? CLI_OK : cli_fail(ctx, s, what);
}

static int grow_lsys(cbm_context *ctx, const cli_study_model *m, const cli_study_run *r,
                     cli_study_plant *out, const char *what)
{
    const char *defs[CLI_STUDY_MAX_DEFS + 1];
    char nv[256];
    if (r->name)
        snprintf(nv, sizeof nv, "%s=%s", r->name, r->value);
    cbm_model_def d = lsys_def(m, r->name ? nv : NULL, defs);
    d.lsys.solver = r->solver;
    long seed = -1;
    if (r->seed && !cli_parse_long(r->seed, &seed))
        seed = -1;
    d.lsys.seed = seed;
    cbm_model *model = NULL;
    double t0 = cli_now();
    cbm_status s = cbm_model_load(ctx, &d, &model);
    cbm_lsys *ls = s == CBM_OK ? cbm_model_lsys(model) : NULL;
    if (s == CBM_OK)
        s = cbm_model_reset(model);
    int steps = ls ? (m->years >= 0 ? (int)m->years : cbm_lsys_derivation_length(ls)) : 0;
    for (int k = 0; s == CBM_OK && k < steps && !cbm_lsys_stopped(ls); k++)
        s = cbm_model_step(model);
    out->seconds = cli_now() - t0;
    if (s == CBM_OK && cbm_lsys_has_mechanics(ls)) {
        cbm_plant *p = NULL;
        s = cbm_lsys_mech_plant(ls, &p);
        if (s == CBM_OK)
            s = measure_plant(p, r->shape, out);
        cbm_plant_destroy(p);
    } else if (s == CBM_OK) {
        /* no mechanics: what the turtle draws */
        cbm_turtle *t = NULL;
        s = cbm_model_interpret(model, NULL, true, &t);
        cbm_vec3 lo, hi;
        if (s == CBM_OK) {
            out->segments = cbm_turtle_prim_count(t);
            bool box = cbm_turtle_box(t, &lo, &hi);
            out->ext[0] = box ? hi.x - lo.x : 0.0;
            out->ext[1] = box ? hi.y - lo.y : 0.0;
            out->ext[2] = box ? hi.z - lo.z : 0.0;
            out->height = out->ext[1];
            out->tip[0] = out->tip[1] = out->tip[2] = out->deflection = NAN;
        }
        cbm_turtle_destroy(t);
    }
    cbm_model_destroy(model);
    return s == CBM_OK ? CLI_OK : cli_fail(ctx, s, what);
}

int cli_study_grow(const cli_study_model *m, const cli_study_run *r, cli_study_plant *out)
{
    memset(out, 0, sizeof *out);
    char what[192];
    int k = snprintf(what, sizeof what, "%s", m->path);
    if (r->name && k > 0 && (size_t)k < sizeof what)
        k += snprintf(what + k, sizeof what - (size_t)k, " %s=%s", r->name, r->value);
    if (r->solver >= 0 && k > 0 && (size_t)k < sizeof what)
        snprintf(what + k, sizeof what - (size_t)k, " (%s)",
                 cbm_mech_solver_name((cbm_mech_solver)r->solver));
    cbm_context *ctx = cli_context();
    int rc = m->lsys ? grow_lsys(ctx, m, r, out, what) : grow_tree(ctx, m, r, out, what);
    out->peak_bytes = cbm_context_peak_bytes(ctx);
    cli_context_end(ctx);
    if (rc != CLI_OK)
        cli_study_plant_free(out);
    return rc;
}

void cli_study_plant_free(cli_study_plant *p)
{
    free(p->nodes);
    free(p->lines);
    p->nodes = p->lines = NULL;
}

bool cli_study_is_plot(const char *path)
{
    const char *ext = cli_extension(path);
    return !strcmp(ext, "svg") || !strcmp(ext, "png");
}

bool cli_study_parse_output(const char *v, void *target, char *why, size_t n)
{
    cli_list *outs = target;
    const char *ext = cli_extension(v);
    if (outs->count == outs->max)
        snprintf(why, n, "at most %d outputs", outs->max);
    else if (strcmp(ext, "csv") && strcmp(ext, "json") && !cli_study_is_plot(v))
        snprintf(why, n, "{value}: unsupported output format '.%s' (use .csv, .json, .svg or .png)",
                 ext);
    else
        cli_list_add(outs, v);
    return !*why;
}

static bool parse_define(const char *v, void *target, char *why, size_t n)
{
    cli_list *l = target;
    if (!strchr(v, '=') || v[0] == '=')
        snprintf(why, n, "-D expects NAME=VALUE, found '{value}'");
    else if (!cli_list_add(l, v))
        snprintf(why, n, "at most %d -D", l->max);
    return !*why;
}

void cli_study_args_init(cli_study_args *a)
{
    memset(a, 0, sizeof *a);
    a->years = -1;
    a->def_list = (cli_list){a->defs, 0, CLI_STUDY_MAX_DEFS, NULL};
}

cli_opts *cli_study_model_options(cli_study_args *a)
{
    static cli_opt rows[] = {
        {.name = "-n|--years",
         .kind = CLI_LONG,
         .arg = "YEARS",
         .help = "years to grow (a .l model: derivation steps; default: the\nmodel's)",
         .min = 0,
         .max = 1000,
         .bad = "{opt} expects 0..1000, found '{value}'"},
        {.name = "-D",
         .kind = CLI_CUSTOM,
         .arg = "NAME=VALUE",
         .help = "a model parameter (a .l model: a #define) for every run\n(repeatable)",
         .parse = parse_define,
         .attached = true,
         .bad = "-D needs NAME=VALUE"},
        {0}};
    static cli_opts table = {.title = "the model:", .opts = rows, .width = 24};
    rows[0].target = &a->years;
    rows[1].target = &a->def_list;
    return &table;
}

int cli_study_write(const char *const *outs, int n, cli_study_plot_fn plot,
                    cli_study_table_fn table, void *ud)
{
    cbm_context *ctx = cli_context();
    int rc = CLI_OK;
    for (int k = 0; k < n && rc == CLI_OK; k++) {
        cbm_status s;
        if (cli_study_is_plot(outs[k])) {
            s = plot(ctx, outs[k], ud);
        } else {
            cbm_out *o = NULL;
            s = cbm_out_open(ctx, outs[k], &o);
            if (s == CBM_OK) {
                table(cbm_out_stream(o), !strcmp(cli_extension(outs[k]), "json"), ud);
                s = cbm_out_commit(o);
            }
        }
        if (s != CBM_OK)
            rc = cli_fail(ctx, s, outs[k]);
    }
    cli_context_end(ctx);
    return rc;
}

cbm_status cli_scurve_plot_write(cbm_context *ctx, const cli_scurve_plot *s, const char *path)
{
    const size_t n = s->n;
    /* 2 n slots: a NaN before each gap breaks the lines there */
    double *x = malloc((10 * n + 1) * sizeof *x);
    if (!x)
        return CBM_E_NOMEM;
    double *ys = x + 2 * n, *yu = ys + 2 * n, *es = yu + 2 * n, *eu = es + 2 * n;
    size_t m = 0;
    for (size_t k = 0; k < n; k++) {
        bool gap = s->gap && s->gap[k];
        if (gap) {
            x[m] = ys[m] = yu[m] = es[m] = eu[m] = NAN;
            m++;
        }
        /* a point joins the stable line if it or a neighbour it is joined to is stable (so the
         * arcs meet), the unstable line likewise */
        bool st = s->stable[k], ps = false, pu = false;
        if (k > 0 && !gap) {
            ps = s->stable[k - 1];
            pu = !ps;
        }
        if (k + 1 < n && !(s->gap && s->gap[k + 1])) {
            bool ns = s->stable[k + 1];
            ps = ps || ns;
            pu = pu || !ns;
        }
        x[m] = s->x[k];
        ys[m] = st || ps ? s->y[k] : NAN;
        es[m] = st || ps ? s->e[k] : NAN;
        yu[m] = !st || pu ? s->y[k] : NAN;
        eu[m] = !st || pu ? s->e[k] : NAN;
        m++;
    }
    cbm_plot *p = NULL;
    cbm_plot_def pd = cbm_plot_def_default();
    pd.title = s->title;
    pd.panels = 2;
    pd.height = 800;
    cbm_status st = cbm_plot_create(ctx, &pd, &p);
    for (int panel = 0; panel < 2 && st == CBM_OK; panel++) {
        cbm_plot_axes_def a = cbm_plot_axes_def_default();
        a.xlabel = s->xlabel;
        a.ylabel = panel ? s->elabel : s->ylabel;
        st = cbm_plot_set_axes(p, panel, &a);
        cbm_plot_series_def ser = cbm_plot_series_def_default();
        ser.x = x, ser.n = m;
        ser.y = panel ? es : ys, ser.label = "stable";
        if (st == CBM_OK)
            st = cbm_plot_add_series(p, panel, &ser);
        ser.y = panel ? eu : yu, ser.label = "unstable", ser.line = CBM_PLOT_DASHED;
        if (st == CBM_OK)
            st = cbm_plot_add_series(p, panel, &ser);
        cbm_plot_series_def fs = cbm_plot_series_def_default();
        fs.line = CBM_PLOT_NO_LINE;
        if (s->nf && st == CBM_OK) {
            fs.x = s->fx, fs.y = panel ? s->fe : s->fy, fs.n = s->nf, fs.label = s->fold_label;
            fs.marker = CBM_PLOT_MARKER_CIRCLE;
            st = cbm_plot_add_series(p, panel, &fs);
        }
        if (s->nj && st == CBM_OK) {
            fs.x = s->jx, fs.y = panel ? s->je : s->jy, fs.n = s->nj, fs.label = "jump target";
            fs.marker = CBM_PLOT_MARKER_CROSS;
            st = cbm_plot_add_series(p, panel, &fs);
        }
    }
    if (st == CBM_OK)
        st = cbm_plot_write(p, path);
    cbm_plot_destroy(p);
    free(x);
    return st;
}
