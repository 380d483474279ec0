/* cambium bend SPEC [-o FILE.csv|FILE.json]... [--json]: the mechanics workbench. Reads a spec
 * (docs/bend.md), builds the rod, grows it if asked, solves for static equilibrium and writes
 * the node table (CSV: s,x,y,z,angle_deg,curvature,moment,stress) and/or a JSON summary. Output
 * files are written atomically through cbm_out; nothing is written when the job fails. */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "cli_study.h"
#include "commands.h"
#include "options.h"

#include "cambium/bend.h"
#include "cambium/dynamics.h"
#include "cambium/plot.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_OUTPUTS 8

static void help(const cli_opts *t)
{
    printf("usage: cambium bend SPEC [-o FILE.csv|FILE.json]... [--json] [--modes N] [limits]\n"
           "       cambium bend SPEC --continue PARAM=FROM:TO[:STEPS] [-o FILE.csv|FILE.json]...\n"
           "            [--json]\n\n"
           "Solves one branch or rod described by SPEC (key = value lines; see docs/bend.md)\n"
           "for static equilibrium. -o writes the node table (.csv: s,x,y,z,angle_deg,\n"
           "curvature,moment,stress; SI units, degrees) or the summary (.json); --json prints\n"
           "the summary (tip_x, tip_y, tip_z, tip_angle_deg, base_moment, passes, residual,\n"
           "seconds, ...) on stdout.\n\n"
           "--modes N adds frequencies_hz, the N lowest natural frequencies (Hz) about the\n"
           "equilibrium, to the JSON (and prints them). With `duration` in the spec the rod\n"
           "moves about its equilibrium and -o FILE.csv writes the motion instead, one row per\n"
           "step: t,tip_x,tip_y,tip_z,kinetic_J,potential_J (docs/bend.md, \"Motion\").\n");
    cli_options_help(stdout, t);
}

/* An output: .csv or .json. */
static bool parse_output(const char *v, void *target, char *why, size_t n)
{
    cli_list *outs = target;
    const char *ext = cli_extension(v);
    if (outs->count == outs->max)
        snprintf(why, n, "at most %d outputs", outs->max);
    else if (strcmp(ext, "csv") && strcmp(ext, "json") && strcmp(ext, "svg") && strcmp(ext, "png"))
        snprintf(why, n,
                 "{value}: unsupported output format '.%s' (use .csv or .json; .svg or .png "
                 "with --continue)",
                 ext);
    else
        cli_list_add(outs, v);
    return !*why;
}

static void write_json_head(FILE *f, const cbm_bend_spec *spec, const cbm_bend_node *tip,
                            const cbm_bend_node *base, const cbm_bend_result *r, double secs,
                            size_t n);

/* --continue PARAM=FROM:TO[:STEPS] (docs/bend.md, "Continuation") */
typedef struct continue_arg {
    bool on;
    cbm_bend_continuation_def def;
} continue_arg;

static bool parse_continue(const char *v, void *target, char *why, size_t n)
{
    continue_arg *c = target;
    c->def = cbm_bend_continuation_def_default();
    const char *eq = strchr(v, '=');
    size_t k = eq ? (size_t)(eq - v) : 0;
    static const char *const names[] = {"angle", "gravity", "density", "tip_load", "length"};
    static const cbm_bend_param params[] = {CBM_BEND_PARAM_ANGLE, CBM_BEND_PARAM_GRAVITY,
                                            CBM_BEND_PARAM_DENSITY, CBM_BEND_PARAM_TIP_LOAD,
                                            CBM_BEND_PARAM_LENGTH};
    size_t which = 5;
    for (size_t i = 0; eq && i < 5; i++)
        if (k == strlen(names[i]) && !strncmp(v, names[i], k))
            which = i;
    if (which == 5) {
        snprintf(why, n,
                 "--continue expects PARAM=FROM:TO[:STEPS] with PARAM angle, gravity, density, "
                 "tip_load or length, found '{value}'");
        return false;
    }
    c->def.param = params[which];
    char *end = NULL;
    double a = strtod(eq + 1, &end), b = 0;
    bool ok = end != eq + 1 && *end == ':' && isfinite(a);
    if (ok) {
        const char *q = end + 1;
        b = strtod(q, &end);
        ok = end != q && isfinite(b) && b != a;
    }
    long steps = c->def.steps;
    if (ok && *end == ':') {
        const char *q = end + 1;
        steps = strtol(q, &end, 10);
        ok = end != q && steps >= 1 && steps <= 10000000;
    }
    if (!ok || *end) {
        snprintf(why, n,
                 "--continue: '{value}' is not PARAM=FROM:TO[:STEPS] (FROM != TO finite "
                 "numbers, STEPS 1..10^7)");
        return false;
    }
    c->def.from = a;
    c->def.to = b;
    c->def.steps = steps;
    c->on = true;
    return true;
}

static void write_branch_point(FILE *f, const cbm_bend_branch_point *p)
{
    char eig[32] = "null";
    if (isfinite(p->lowest_eigenvalue))
        snprintf(eig, sizeof eig, "%.9g", p->lowest_eigenvalue);
    fprintf(f,
            "{\"param\": %.12g, \"tip_angle_deg\": %.12g, \"tip_x\": %.12g, \"tip_y\": %.12g, "
            "\"tip_z\": %.12g, \"unstable_modes\": %zu, \"lowest_eigenvalue\": %s, "
            "\"symmetry_mode\": %s, \"energy\": %.12g, \"jumped\": %s}",
            p->param, p->tip_angle_deg, p->tip_x, p->tip_y, p->tip_z, p->unstable_modes, eig,
            p->symmetry_mode ? "true" : "false", p->energy, p->jumped ? "true" : "false");
}

static const char *param_name(cbm_bend_param p)
{
    switch (p) {
    case CBM_BEND_PARAM_ANGLE:
        return "angle";
    case CBM_BEND_PARAM_GRAVITY:
        return "gravity";
    case CBM_BEND_PARAM_DENSITY:
        return "density";
    case CBM_BEND_PARAM_TIP_LOAD:
        return "tip_load";
    case CBM_BEND_PARAM_LENGTH:
        return "length";
    }
    return "?";
}

static void write_branch_json(FILE *f, const cbm_bend_continuation_def *d, const cbm_bend_branch *b,
                              double secs)
{
    bool arc = d->method == CBM_BEND_CONTINUE_ARCLENGTH;
    fprintf(f, "{\"param\": \"%s\", \"from\": %.12g, \"to\": %.12g, \"steps\": %ld, ",
            param_name(d->param), d->from, d->to, d->steps);
    if (arc) /* the natural method's JSON keeps its members */
        fprintf(f, "\"method\": \"arclength\", \"switch_branch\": %s, \"end\": \"%s\", ",
                d->switch_branch ? "true" : "false",
                b->end == CBM_BEND_END_TO     ? "to"
                : b->end == CBM_BEND_END_FROM ? "from"
                                              : "limit");
    if (arc && d->switch_branch)
        fprintf(f, "\"switch_at\": %ld, ", d->switch_at);
    fprintf(f, "\"branch\": [");
    for (size_t i = 0; i < b->n_points; i++) {
        fprintf(f, "%s", i ? ", " : "");
        write_branch_point(f, &b->points[i]);
    }
    fprintf(f, "], \"folds\": [");
    for (size_t i = 0; i < b->n_folds; i++) {
        const cbm_bend_fold *k = &b->folds[i];
        fprintf(f, "%s{\"kind\": \"%s\", \"bracket\": %.6g, ", i ? ", " : "",
                k->fold ? "fold" : "stability", k->bracket);
        if (arc)
            fprintf(f, "\"switched\": %s, ", k->switched ? "true" : "false");
        fprintf(f, "\"at\": ");
        write_branch_point(f, &k->at);
        fprintf(f, ", \"jump\": ");
        if (k->has_jump)
            write_branch_point(f, &k->jump);
        else
            fprintf(f, "null");
        if (arc)
            fprintf(f, ", \"bifurcation\": %ld", k->bifurcation);
        fprintf(f, "}");
    }
    fprintf(f, "], \"seconds\": %.6g}\n", secs);
}

static void write_branch_csv(FILE *f, const cbm_bend_branch *b)
{
    fprintf(f, "param,tip_angle_deg,tip_x,tip_y,tip_z,unstable_modes,lowest_eigenvalue,energy,"
               "jumped\n");
    for (size_t i = 0; i < b->n_points; i++) {
        const cbm_bend_branch_point *p = &b->points[i];
        fprintf(f, "%.12g,%.12g,%.12g,%.12g,%.12g,%zu,%.9g,%.12g,%d\n", p->param, p->tip_angle_deg,
                p->tip_x, p->tip_y, p->tip_z, p->unstable_modes, p->lowest_eigenvalue, p->energy,
                p->jumped ? 1 : 0);
    }
}

/* Two panels against the parameter: the tip's angle and the energy, stable arcs solid, unstable
 * dashed, folds circled, jump targets crossed (the branch's S-curve). */
static cbm_status write_branch_plot(cbm_context *ctx, const cbm_bend_continuation_def *d,
                                    const cbm_bend_branch *b, const char *path)
{
    size_t n = b->n_points, nf = b->n_folds, nj = 0;
    double *x = malloc((3 * n + 6 * nf + 1) * sizeof *x);
    bool *flags = malloc((2 * n + 1) * sizeof *flags);
    if (!x || !flags) {
        free(x);
        free(flags);
        return CBM_E_NOMEM;
    }
    double *y = x + n, *e = y + n, *fx = e + n, *fy = fx + nf, *fe = fy + nf, *jx = fe + nf,
           *jy = jx + nf, *je = jy + nf;
    bool *stable = flags, *gap = flags + n;
    for (size_t k = 0; k < n; k++) {
        const cbm_bend_branch_point *a = &b->points[k];
        x[k] = a->param, y[k] = a->tip_angle_deg, e[k] = a->energy;
        stable[k] = a->unstable_modes == 0;
        gap[k] = a->jumped;
    }
    for (size_t k = 0; k < nf; k++) {
        const cbm_bend_fold *f = &b->folds[k];
        fx[k] = f->fold ? f->at.param : NAN;
        fy[k] = f->at.tip_angle_deg;
        fe[k] = f->at.energy;
        if (f->fold && f->has_jump) {
            jx[nj] = f->jump.param;
            jy[nj] = f->jump.tip_angle_deg;
            je[nj++] = f->jump.energy;
        }
    }
    static const char *const units[] = {"deg", "m/s^2", "kg/m^3", "N", "m"};
    char xl[64], title[96];
    snprintf(xl, sizeof xl, "%s (%s)", param_name(d->param), units[d->param]);
    snprintf(title, sizeof title, "equilibria of the rod in %s", param_name(d->param));
    cli_scurve_plot sp = {.title = title,
                          .xlabel = xl,
                          .ylabel = "tip angle (deg)",
                          .elabel = "energy (J)",
                          .x = x,
                          .y = y,
                          .e = e,
                          .stable = stable,
                          .gap = gap,
                          .n = n,
                          .fx = fx,
                          .fy = fy,
                          .fe = fe,
                          .nf = nf,
                          .fold_label = "fold",
                          .jx = jx,
                          .jy = jy,
                          .je = je,
                          .nj = nj};
    cbm_status s = cli_scurve_plot_write(ctx, &sp, path);
    free(x);
    free(flags);
    return s;
}

/* the continuation job: the branch to the outputs; nothing written on failure */
static int run_continue(cbm_context *ctx, const cbm_bend_spec *spec,
                        const cbm_bend_continuation_def *d, const char **outs, int nout, bool json)
{
    double t0 = cli_now();
    cbm_bend_branch br;
    cbm_status s = cbm_bend_continue(ctx, spec, d, &br);
    double secs = cli_now() - t0;
    if (s != CBM_OK)
        return cli_fail(ctx, s, "bend --continue");
    int rc = CLI_OK;
    for (int k = 0; k < nout && rc == CLI_OK; k++) {
        cbm_out *o = NULL;
        const char *ext = cli_extension(outs[k]);
        if (!strcmp(ext, "svg") || !strcmp(ext, "png")) {
            s = write_branch_plot(ctx, d, &br, outs[k]);
            if (s != CBM_OK)
                rc = cli_fail(ctx, s, outs[k]);
            continue;
        }
        s = cbm_out_open(ctx, outs[k], &o);
        if (s == CBM_OK) {
            FILE *f = cbm_out_stream(o);
            if (!strcmp(ext, "json"))
                write_branch_json(f, d, &br, secs);
            else
                write_branch_csv(f, &br);
            s = cbm_out_commit(o);
        }
        if (s != CBM_OK)
            rc = cli_fail(ctx, s, outs[k]);
    }
    if (rc == CLI_OK && json)
        write_branch_json(stdout, d, &br, secs);
    if (rc == CLI_OK && !json && nout == 0) {
        printf("%zu equilibria, %zu events, %.3g s\n", br.n_points, br.n_folds, secs);
        for (size_t i = 0; i < br.n_folds; i++) {
            const cbm_bend_fold *k = &br.folds[i];
            printf("%s at %.9g (tip angle %.6g deg, tip (%.6g, %.6g, %.6g) m, lowest eigenvalue "
                   "%.3g)",
                   k->fold       ? "fold"
                   : k->switched ? "bifurcation (branch switched)"
                                 : "stability change",
                   k->at.param, k->at.tip_angle_deg, k->at.tip_x, k->at.tip_y, k->at.tip_z,
                   k->at.lowest_eigenvalue);
            if (k->has_jump)
                printf(", jumps to tip angle %.6g deg, tip (%.6g, %.6g, %.6g) m",
                       k->jump.tip_angle_deg, k->jump.tip_x, k->jump.tip_y, k->jump.tip_z);
            printf("\n");
        }
    }
    cbm_bend_branch_free(&br);
    return rc;
}

/* the motion and modes members of the JSON (empty without --modes and duration) */
typedef struct bend_extra {
    const double *freqs;
    size_t nfreq;
    double dt;
    size_t rows;
} bend_extra;

static void write_json(FILE *f, const cbm_bend_spec *spec, const cbm_bend_node *tip,
                       const cbm_bend_node *base, const cbm_bend_result *r, double secs, size_t n,
                       const bend_extra *x)
{
    write_json_head(f, spec, tip, base, r, secs, n);
    if (x->nfreq && x->freqs) {
        fprintf(f, ", \"frequencies_hz\": [");
        for (size_t i = 0; i < x->nfreq; i++) {
            if (isfinite(x->freqs[i]))
                fprintf(f, "%s%.12g", i ? ", " : "", x->freqs[i]);
            else
                fprintf(f, "%snull", i ? ", " : "");
        }
        fprintf(f, "]");
    }
    if (x->rows)
        fprintf(f, ", \"dt\": %.12g, \"motion_rows\": %zu", x->dt, x->rows);
    fprintf(f, "}\n");
}

static void write_json_head(FILE *f, const cbm_bend_spec *spec, const cbm_bend_node *tip,
                            const cbm_bend_node *base, const cbm_bend_result *r, double secs,
                            size_t n)
{
    char eig[32] = "null"; /* NaN (not computed) is no JSON number */
    if (isfinite(r->stats.lowest_eigenvalue))
        snprintf(eig, sizeof eig, "%.9g", r->stats.lowest_eigenvalue);
    fprintf(f,
            "{\"tip_x\": %.12g, \"tip_y\": %.12g, \"tip_z\": %.12g, \"tip_angle_deg\": %.12g, "
            "\"base_moment\": %.12g, \"passes\": %zu, \"residual\": %.6g, \"seconds\": %.6g, "
            "\"solver\": \"%s\", \"discretization\": \"%s\", \"segments\": %zu, "
            "\"newton_steps\": %zu, \"krylov_iterations\": %zu, \"base_stress\": %.12g, "
            "\"steps\": %ld, \"broken_segments\": %zu, \"stage\": \"%s\", "
            "\"unstable_modes\": %zu, \"stable\": %s, \"lowest_eigenvalue\": %s",
            tip->x, tip->y, tip->z, tip->angle_deg, base->moment, r->stats.passes,
            r->stats.residual, secs, cbm_mech_solver_name(spec->solver),
            cbm_mech_discretization_name(spec->discretization), n, r->stats.newton_steps,
            r->stats.krylov_iterations, base->stress, r->steps_done, r->broken_segments,
            cbm_solve_stage_name(r->stats.stage), r->stats.unstable_modes,
            r->stats.unstable_modes ? "false" : "true", eig);
}

/* streams motion rows into the open CSV outputs */
typedef struct motion_sink {
    FILE *f[MAX_OUTPUTS];
    int n;
    size_t rows;
} motion_sink;

static cbm_status motion_row(void *user, const cbm_motion_row *r)
{
    motion_sink *m = user;
    for (int k = 0; k < m->n; k++)
        fprintf(m->f[k], "%.12g,%.12g,%.12g,%.12g,%.12g,%.12g\n", r->t, r->tip_x, r->tip_y,
                r->tip_z, r->kinetic, r->potential);
    m->rows++;
    return CBM_OK;
}

int cmd_bend(int argc, char **argv)
{
    const char *spec_path = NULL;
    long modes = 0;
    const char *outs[MAX_OUTPUTS];
    cli_list out_list = {outs, 0, MAX_OUTPUTS, NULL};
    bool json = false, natural = false, switch_branch = false;
    long switch_at = -1;
    continue_arg cont = {false, cbm_bend_continuation_def_default()};
    cli_opt rows[] = {
        {.name = "--help|-h", .kind = CLI_HELP},
        {.name = "SPEC", .kind = CLI_POSITIONAL, .target = &spec_path, .parse = cli_parse_one_spec},
        {.name = "--json", .kind = CLI_SET, .target = &json},
        {.name = "--modes",
         .kind = CLI_LONG,
         .target = &modes,
         .min = 1,
         .max = 10000,
         .bad = "--modes expects a count 1..10000, found '{value}'"},
        {.name = "-o",
         .kind = CLI_CUSTOM,
         .target = &out_list,
         .parse = parse_output,
         .bad = "-o needs a file name"},
        {.name = "--continue",
         .kind = CLI_CUSTOM,
         .target = &cont,
         .arg = "PARAM=FROM:TO[:STEPS]",
         .help = "follow the equilibria in PARAM (angle, gravity) from FROM to TO; folds,\n"
                 "jumps; -o FILE.csv/.json and --json write the branch",
         .parse = parse_continue,
         .bad = "--continue needs PARAM=FROM:TO[:STEPS]"},
        {.name = "--natural",
         .kind = CLI_SET,
         .target = &natural,
         .help = "with --continue: natural-parameter steps (the parameter only moves\n"
                 "forward, the rod jumps at a fold) instead of pseudo-arclength"},
        {.name = "--switch-branch",
         .kind = CLI_SET,
         .target = &switch_branch,
         .help = "with --continue: at the first loss of stability without a fold\n"
                 "(a bifurcation) follow the bifurcating branch"},
        {.name = "--switch-at",
         .kind = CLI_LONG,
         .target = &switch_at,
         .arg = "N",
         .min = 0,
         .max = 1000000,
         .help = "with --switch-branch: leave at the N-th bifurcation met (default 1;\n"
                 "0: at every one)",
         .bad = "--switch-at expects a count 0..1000000, found '{value}'"},
        {.kind = CLI_GROUP, .target = cli_limit_options()},
        {0}};
    cli_opts table = {.cmd = "bend",
                      .opts = rows,
                      .help = help,
                      .width = 18,
                      .unknown = "unknown option '{opt}'"};
    int prc = cli_options_parse(&table, argc, argv);
    if (prc != CLI_OK)
        return prc == CLI_HELP_SHOWN ? CLI_OK : prc;
    int nout = out_list.count;
    if (!spec_path)
        return cli_usage_error("bend", "expected a SPEC file (see cambium bend --help)");
    if (cli_check_outputs(outs, nout) != CLI_OK)
        return CLI_FAIL;
    if ((natural || switch_branch) && !cont.on)
        return cli_usage_error("bend", "--natural and --switch-branch need --continue");
    if (natural && switch_branch)
        return cli_usage_error("bend",
                               "--switch-branch needs the arclength method (not --natural)");
    for (int k = 0; k < nout && !cont.on; k++) {
        const char *ext = cli_extension(outs[k]);
        if (!strcmp(ext, "svg") || !strcmp(ext, "png"))
            return cli_usage_error("bend", "%s: plots (.svg, .png) need --continue", outs[k]);
    }
    cont.def.method = natural ? CBM_BEND_CONTINUE_NATURAL : CBM_BEND_CONTINUE_ARCLENGTH;
    cont.def.switch_branch = switch_branch;
    if (switch_at >= 0 && !switch_branch)
        return cli_usage_error("bend", "--switch-at needs --switch-branch");
    if (switch_at >= 0)
        cont.def.switch_at = switch_at;

    size_t len = 0;
    char *text = cli_read_spec(spec_path, &len);
    if (!text)
        return CLI_FAIL;
    cbm_context *ctx = cli_context();
    cbm_bend_spec spec;
    cbm_status s = cbm_bend_spec_parse(ctx, text, len, spec_path, &spec);
    free(text);
    if (s != CBM_OK) {
        int rc = cli_fail(ctx, s, spec_path);
        cli_context_end(ctx);
        return rc;
    }
    if (cont.on) {
        int crc = run_continue(ctx, &spec, &cont.def, outs, nout, json);
        cli_context_end(ctx);
        return crc;
    }
    double t0 = cli_now();
    cbm_plant *plant = NULL;
    cbm_bend_result res;
    s = cbm_bend_run(ctx, &spec, &plant, &res);
    double secs = cli_now() - t0;
    if (s != CBM_OK) {
        int rc = cli_fail(ctx, s, "bend");
        cbm_plant_destroy(plant);
        cli_context_end(ctx);
        return rc;
    }
    size_t n = cbm_plant_segment_count(plant);
    cbm_bend_node *nodes = malloc((n + 1) * sizeof *nodes);
    if (!nodes) {
        cbm_plant_destroy(plant);
        cli_context_end(ctx);
        fprintf(stderr, "cambium: out of memory\n");
        return CLI_FAIL;
    }
    s = cbm_bend_nodes(plant, nodes, n + 1);
    int rc = CLI_OK;
    if (res.stats.unstable_modes > 0) /* never an unstable answer without saying so */
        fprintf(stderr,
                "cambium: bend: warning: the equilibrium is unstable (%zu unstable modes, lowest "
                "eigenvalue %.3g)%s\n",
                res.stats.unstable_modes, res.stats.lowest_eigenvalue,
                spec.push_unstable ? "; no push along the unstable mode reached a stable one"
                                   : " (push_unstable = 0)");
    if (s != CBM_OK)
        rc = cli_fail(ctx, s, "bend");
    bend_extra extra = {NULL, 0, 0.0, 0};
    double *freqs = NULL;
    if (rc == CLI_OK && modes > 0) {
        freqs = malloc((size_t)modes * sizeof *freqs);
        s = freqs ? cbm_plant_modes(plant, (size_t)modes, freqs, NULL) : CBM_E_NOMEM;
        if (s != CBM_OK)
            rc = cli_fail(ctx, s, "bend --modes");
        extra.freqs = freqs;
        extra.nfreq = (size_t)modes;
    }
    bool motion = spec.duration > 0;
    if (rc == CLI_OK && motion) {
        /* the CSV outputs receive the motion, streamed row by row */
        cbm_out *mo[MAX_OUTPUTS];
        motion_sink sink = {{NULL}, 0, 0};
        int nmo = 0;
        for (int k = 0; k < nout && rc == CLI_OK; k++) {
            if (strcmp(cli_extension(outs[k]), "csv"))
                continue;
            s = cbm_out_open(ctx, outs[k], &mo[nmo]);
            if (s != CBM_OK) {
                rc = cli_fail(ctx, s, outs[k]);
                break;
            }
            sink.f[nmo] = cbm_out_stream(mo[nmo]);
            fprintf(sink.f[nmo], "t,tip_x,tip_y,tip_z,kinetic_J,potential_J\n");
            nmo++;
        }
        sink.n = nmo;
        if (rc == CLI_OK) {
            s = cbm_bend_motion(plant, &spec, motion_row, &sink, &extra.dt);
            if (s != CBM_OK)
                rc = cli_fail(ctx, s, "bend (motion)");
            extra.rows = sink.rows;
        }
        for (int k = 0; k < nmo; k++) {
            if (rc == CLI_OK) {
                s = cbm_out_commit(mo[k]);
                if (s != CBM_OK)
                    rc = cli_fail(ctx, s, "bend (motion output)");
            } else
                cbm_out_abort(mo[k]);
        }
    }
    for (int k = 0; k < nout && rc == CLI_OK; k++) {
        if (motion && !strcmp(cli_extension(outs[k]), "csv"))
            continue;
        cbm_out *o = NULL;
        s = cbm_out_open(ctx, outs[k], &o);
        if (s == CBM_OK) {
            FILE *f = cbm_out_stream(o);
            if (!strcmp(cli_extension(outs[k]), "json"))
                write_json(f, &spec, &nodes[n], &nodes[0], &res, secs, n, &extra);
            else {
                fprintf(f, "s,x,y,z,angle_deg,curvature,moment,stress\n");
                for (size_t j = 0; j <= n; j++) {
                    const cbm_bend_node *d = &nodes[j];
                    fprintf(f, "%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g\n", d->s, d->x,
                            d->y, d->z, d->angle_deg, d->curvature, d->moment, d->stress);
                }
            }
            s = cbm_out_commit(o);
        }
        if (s != CBM_OK)
            rc = cli_fail(ctx, s, outs[k]);
    }
    if (rc == CLI_OK && json)
        write_json(stdout, &spec, &nodes[n], &nodes[0], &res, secs, n, &extra);
    if (rc == CLI_OK && !json && nout == 0)
        printf("tip (%.6g, %.6g, %.6g) m, tip angle %.6g deg, base moment %.6g N m, %zu passes, "
               "residual %.3g (stage %s), %.3g s\n",
               nodes[n].x, nodes[n].y, nodes[n].z, nodes[n].angle_deg, nodes[0].moment,
               res.stats.passes, res.stats.residual, cbm_solve_stage_name(res.stats.stage), secs);
    if (rc == CLI_OK && !json && nout == 0 && extra.nfreq && extra.freqs) {
        printf("frequencies (Hz):");
        for (size_t k = 0; k < extra.nfreq; k++)
            printf(" %.6g", extra.freqs[k]);
        printf("\n");
    }
    free(freqs);
    free(nodes);
    cbm_plant_destroy(plant);
    cli_context_end(ctx);
    return rc;
}
