/* cambium elastica SPEC [-o scurve.csv|.png|.svg]... [--json]: the continuous elastica of a rod
 * or a branched plant (docs/elastica.md). Traces the S-curve of the rod over the spec's tip
 * angles, its folds and jump targets, a base-angle sweep up and down (hysteresis), and with
 * `angle` every equilibrium at that clamp angle with its stability. Outputs are non-dimensional
 * (lengths in units of L, curvature times L, energy times L / D(0)). Files are written
 * atomically; nothing is written when the job fails. */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "cli_study.h"
#include "commands.h"
#include "options.h"

#include "cambium/elastica.h"
#include "cambium/elastica_growth.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_OUTPUTS 8
#define MAX_EQ      4096
#define MAX_JUMPS   64
#define DEG         (180.0 / 3.14159265358979323846)

static void help(const cli_opts *t)
{
    printf("usage: cambium elastica SPEC [-o FILE.csv|FILE.png|FILE.svg]... [--json] [limits]\n\n"
           "Every equilibrium of a heavy rod (or a branched plant) clamped at its base, by\n"
           "shooting from the tip (Tresierras 2009). SPEC is a bend spec (docs/bend.md) with\n"
           "alpha (rho g L^3 / D: non-dimensional mode), angle (any, degrees), theta_tip_min,\n"
           "theta_tip_max, sweep_min, sweep_max and branch lines (docs/elastica.md).\n"
           "-o writes the S-curve: .csv (theta_tip_deg,theta_base_deg,kappa_base,strain_base,\n"
           "energy,tip_x,tip_y,dbase_dtip,index,stable) or a plot (.png, .svg: base curvature\n"
           "and energy against the base angle). --json prints the folds, jumps, hysteresis\n"
           "and, with angle, the equilibria at that angle. With steps > 0 the rod grows\n"
           "(Tresierras ch. 3: tip growth, accretion, remodeling, the kappa^g law with\n"
           "kappa^c, the inverse problem): -o writes one row per cell per step (.csv) or the\n"
           "configurations and curvatures (.png, .svg); --json the frames.\n");
    cli_options_help(stdout, t);
}

/* An output: .csv, .png or .svg. */
static bool parse_output(const char *v, void *target, char *why, size_t n)
{
    cli_list *outs = target;
    const char *ext = cli_extension(v);
    if (outs->count == outs->max)
        snprintf(why, n, "at most %d outputs", outs->max);
    else if (strcmp(ext, "csv") && strcmp(ext, "png") && strcmp(ext, "svg"))
        snprintf(why, n, "{value}: unsupported output format '.%s' (use .csv, .png or .svg)", ext);
    else
        cli_list_add(outs, v);
    return !*why;
}

typedef struct units {
    double L, D;
} units;

static void state_json(FILE *f, const cbm_elastica_state *s, units u)
{
    fprintf(f,
            "{\"theta_tip_deg\": %.9g, \"theta_base_deg\": %.9g, \"kappa_base\": %.9g, "
            "\"tip_x\": %.9g, \"tip_y\": %.9g, \"energy\": %.9g, \"index\": %d, "
            "\"stable\": %s}",
            s->theta_tip * DEG, s->theta_base * DEG, s->curvature_base * u.L, s->tip_x / u.L,
            s->tip_y / u.L, s->energy * u.L / u.D, s->index, s->index == 0 ? "true" : "false");
}

static void jumps_json(FILE *f, const cbm_elastica_jump *j, size_t n, units u)
{
    fprintf(f, "[");
    for (size_t k = 0; k < n && k < MAX_JUMPS; k++) {
        fprintf(f, "%s{\"from\": ", k ? ", " : "");
        state_json(f, &j[k].from, u);
        fprintf(f, ", \"to\": ");
        state_json(f, &j[k].to, u);
        fprintf(f, "}");
    }
    fprintf(f, "]");
}

typedef struct result {
    const cbm_elastica_scurve *sc;
    const cbm_elastica_state *eq;
    size_t neq;
    const cbm_elastica_jump *up, *down;
    size_t nup, ndown;
    const cbm_elastica_plant_state *pe;
    size_t npe, nbr;
    double alpha, secs;
    units u;
    const cbm_elastica_spec *spec;
} result;

static void write_json(FILE *f, const result *r)
{
    const cbm_elastica_scurve *sc = r->sc;
    units u = r->u;
    fprintf(f, "{\"alpha\": %.9g, \"theta_tip_min_deg\": %.9g, \"theta_tip_max_deg\": %.9g, ",
            r->alpha, r->spec->theta_tip_min, r->spec->theta_tip_max);
    fprintf(f, "\"points\": %zu, \"branches\": %zu, ", sc->n_points, r->nbr);
    if (r->spec->has_angle) {
        fprintf(f, "\"angle_deg\": %.9g, \"equilibria\": [", r->spec->angle);
        if (r->nbr > 1)
            for (size_t k = 0; k < r->npe; k++) {
                const cbm_elastica_plant_state *p = &r->pe[k];
                fprintf(f,
                        "%s{\"theta_tip_deg\": %.9g, \"kappa_base\": %.9g, \"tip_x\": %.9g, "
                        "\"tip_y\": %.9g, \"energy\": %.9g, \"index\": %d, \"stable\": %s, "
                        "\"branch\": [",
                        k ? ", " : "", p->theta_tip[0] * DEG,
                        p->moment_base[0] / u.D * u.L + r->spec->bend.rest_curvature * u.L,
                        p->tip_x[0] / u.L, p->tip_y[0] / u.L, p->energy * u.L / u.D, p->index,
                        p->index == 0 ? "true" : "false");
                for (size_t b = 0; b < r->nbr; b++)
                    fprintf(f,
                            "%s{\"theta_base_deg\": %.9g, \"theta_tip_deg\": %.9g, "
                            "\"moment_base\": %.9g, \"tip_x\": %.9g, \"tip_y\": %.9g}",
                            b ? ", " : "", p->theta_base[b] * DEG, p->theta_tip[b] * DEG,
                            p->moment_base[b] * u.L / u.D, p->tip_x[b] / u.L, p->tip_y[b] / u.L);
                fprintf(f, "]}");
            }
        else
            for (size_t k = 0; k < r->neq; k++) {
                fprintf(f, "%s", k ? ", " : "");
                state_json(f, &r->eq[k], u);
            }
        fprintf(f, "], ");
    }
    fprintf(f, "\"folds\": [");
    for (size_t k = 0; k < sc->n_folds; k++) {
        const cbm_elastica_fold *fd = &sc->folds[k];
        fprintf(f,
                "%s{\"theta_base_deg\": %.9g, \"theta_tip_deg\": %.9g, \"kappa_base\": %.9g, "
                "\"energy\": %.9g, \"jump\": ",
                k ? ", " : "", fd->at.theta_base * DEG, fd->at.theta_tip * DEG,
                fd->at.curvature_base * u.L, fd->at.energy * u.L / u.D);
        if (fd->has_target)
            state_json(f, &fd->target, u);
        else
            fprintf(f, "null");
        fprintf(f, "}");
    }
    fprintf(f, "], \"hysteresis\": {\"sweep_min_deg\": %.9g, \"sweep_max_deg\": %.9g, \"up\": ",
            r->spec->sweep_min, r->spec->sweep_max);
    jumps_json(f, r->up, r->nup, u);
    fprintf(f, ", \"down\": ");
    jumps_json(f, r->down, r->ndown, u);
    fprintf(f, "}, \"seconds\": %.6g}\n", r->secs);
}

static void write_csv(FILE *f, const result *r)
{
    fprintf(f, "theta_tip_deg,theta_base_deg,kappa_base,strain_base,energy,tip_x,tip_y,"
               "dbase_dtip,index,stable\n");
    for (size_t k = 0; k < r->sc->n_points; k++) {
        const cbm_elastica_state *s = &r->sc->points[k];
        fprintf(f, "%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%d,%d\n", s->theta_tip * DEG,
                s->theta_base * DEG, s->curvature_base * r->u.L, s->strain_base * r->u.L,
                s->energy * r->u.L / r->u.D, s->tip_x / r->u.L, s->tip_y / r->u.L, s->dbase_dtip,
                s->index, s->index == 0);
    }
}

/* Two panels against the base angle: base curvature and energy, stable arcs solid, unstable
 * dashed, folds marked. */
static cbm_status write_plot(cbm_context *ctx, const result *r, const char *path)
{
    const cbm_elastica_scurve *sc = r->sc;
    size_t n = sc->n_points;
    double *x = malloc((3 * n + 1) * sizeof *x);
    bool *stable = malloc((n + 1) * sizeof *stable);
    double fx[64], fy[64], fe[64];
    cbm_status s = CBM_E_NOMEM;
    if (x && stable) {
        double *y = x + n, *e = y + n;
        for (size_t k = 0; k < n; k++) {
            const cbm_elastica_state *a = &sc->points[k];
            x[k] = a->theta_base * DEG;
            y[k] = a->curvature_base * r->u.L;
            e[k] = a->energy * r->u.L / r->u.D;
            stable[k] = a->index == 0;
        }
        size_t nf = sc->n_folds < 64 ? sc->n_folds : 64;
        for (size_t k = 0; k < nf; k++) {
            fx[k] = sc->folds[k].at.theta_base * DEG;
            fy[k] = sc->folds[k].at.curvature_base * r->u.L;
            fe[k] = sc->folds[k].at.energy * r->u.L / r->u.D;
        }
        char title[96];
        snprintf(title, sizeof title, "S-curve, alpha = %.4g", r->alpha);
        cli_scurve_plot sp = {.title = title,
                              .xlabel = "base angle (deg)",
                              .ylabel = "base curvature kappa L",
                              .elabel = "energy V L / D",
                              .x = x,
                              .y = y,
                              .e = e,
                              .stable = stable,
                              .n = n,
                              .fx = fx,
                              .fy = fy,
                              .fe = fe,
                              .nf = nf,
                              .fold_label = "fold (jumping point)"};
        s = cli_scurve_plot_write(ctx, &sp, path);
    }
    free(x);
    free(stable);
    return s;
}

static cbm_status run(cbm_context *ctx, const cbm_elastica_spec *spec, result *r,
                      cbm_elastica_scurve **sc, cbm_elastica_state **eq, cbm_elastica_jump *up,
                      cbm_elastica_jump *down, cbm_elastica_plant_state **pe)
{
    static cbm_elastica_piece pieces[CBM_ELASTICA_MAX_BRANCHES + 1];
    static cbm_elastica_branch br[CBM_ELASTICA_MAX_BRANCHES + 1];
    cbm_status s = cbm_elastica_spec_plant(spec, pieces, br, &r->u.L, &r->u.D);
    if (s != CBM_OK)
        return s;
    r->nbr = 1 + spec->n_branches;
    r->alpha = pieces[0].w0 * r->u.L * r->u.L * r->u.L / r->u.D;
    cbm_elastica_rod rod = cbm_elastica_rod_default();
    rod.pieces = br[0].pieces, rod.n_pieces = 1;
    rod.tip_force = br[0].tip_force, rod.tip_moment = br[0].tip_moment;
    cbm_elastica_scan_def d = cbm_elastica_scan_def_default();
    d.theta_tip_min = spec->theta_tip_min / DEG, d.theta_tip_max = spec->theta_tip_max / DEG;
    s = cbm_elastica_scurve_compute(ctx, &rod, &d, sc);
    if (s != CBM_OK)
        return s;
    r->sc = *sc;
    if (spec->has_angle && r->nbr == 1) {
        *eq = malloc(MAX_EQ * sizeof **eq);
        if (!*eq)
            return CBM_E_NOMEM;
        s = cbm_elastica_equilibria(ctx, &rod, *sc, spec->angle / DEG, *eq, MAX_EQ, &r->neq);
        if (s == CBM_OK && r->neq > MAX_EQ)
            r->neq = MAX_EQ;
        r->eq = *eq;
    }
    if (spec->has_angle && r->nbr > 1) {
        cbm_elastica_plant_def pd = cbm_elastica_plant_def_default();
        pd.scan = d;
        s = cbm_elastica_plant_equilibria(ctx, br, r->nbr, &pd, spec->angle / DEG, pe, &r->npe);
        r->pe = *pe;
    }
    size_t np = 0;
    if (s == CBM_OK && r->nbr == 1) {
        s = cbm_elastica_sweep(ctx, &rod, *sc, spec->sweep_min / DEG, spec->sweep_max / DEG, NULL,
                               0, &np, up, MAX_JUMPS, &r->nup);
        if (s == CBM_OK)
            s = cbm_elastica_sweep(ctx, &rod, *sc, spec->sweep_max / DEG, spec->sweep_min / DEG,
                                   NULL, 0, &np, down, MAX_JUMPS, &r->ndown);
    }
    return s;
}

/* ---- growth under control (steps > 0): one frame per step ---- */

static void growth_json(FILE *f, const cbm_elastica_growth *g, const cbm_elastica_growth_def *d,
                        double secs)
{
    fprintf(f,
            "{\"growth\": {\"steps\": %zu, \"substeps\": %zu, \"cell_length\": %.9g, "
            "\"tip_growth\": %.9g, \"layer\": %.9g, \"control\": \"%s\", \"frames\": [",
            d->steps, d->substeps, g->cell_length, d->tip_growth, d->layer,
            d->control == CBM_ELASTICA_CONTROL_STATIC ? "static" : "given");
    for (size_t k = 0; k < g->n_frames; k++) {
        const cbm_elastica_growth_frame *fr = &g->frames[k];
        fprintf(f,
                "%s{\"step\": %zu, \"time\": %.9g, \"length\": %.9g, \"theta_tip_deg\": %.9g, "
                "\"tip_x\": %.9g, \"tip_y\": %.9g, \"strain_base\": %.9g, \"moment_base\": %.9g, "
                "\"stiffness_base\": %.9g, \"radius_base\": %.9g, \"energy\": %.9g, "
                "\"index\": %d, \"stable\": %s, \"jumped\": %s, \"hold_error\": %.3g}",
                k ? ", " : "", k, fr->time, fr->length, fr->theta_tip * DEG, fr->tip_x, fr->tip_y,
                fr->strain_base, fr->moment_base, fr->stiffness_base, fr->cells[0].radius,
                fr->energy, fr->index, fr->index == 0 ? "true" : "false",
                fr->jumped ? "true" : "false", fr->hold_error);
    }
    fprintf(f, "]}, \"seconds\": %.6g}\n", secs);
}

static void growth_csv(FILE *f, const cbm_elastica_growth *g)
{
    fprintf(f, "step,time,s,x,y,theta_deg,x_g,y_g,kappa,kappa_g,kappa_c,kappa_o_g,k_ss,k_as,k_i,"
               "stiffness,weight,radius,born\n");
    for (size_t k = 0; k < g->n_frames; k++) {
        const cbm_elastica_growth_frame *fr = &g->frames[k];
        for (size_t i = 0; i < fr->n_cells; i++) {
            const cbm_elastica_growth_cell *c = &fr->cells[i];
            fprintf(f,
                    "%zu,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,%.12g,"
                    "%.12g,%.12g,%.12g,%.12g,%.12g,%.12g\n",
                    k, fr->time, c->s, c->x, c->y, c->theta * DEG, c->xg, c->yg, c->kappa,
                    c->kappa_g, c->kappa_c, c->kappa_o_g, c->k_ss, c->k_as, c->k_i, c->stiffness,
                    c->weight, c->radius, c->born);
        }
    }
}

/* Two panels: the present configurations of (up to 8) frames and the last growth configuration
 * (dashed); the last frame's kappa, kappa^g and kappa^c against s. */
static cbm_status growth_plot(cbm_context *ctx, const cbm_elastica_growth *g, const char *path)
{
    const cbm_elastica_growth_frame *lf = &g->frames[g->n_frames - 1];
    size_t n = lf->n_cells + 1;
    double *x = malloc(n * sizeof *x), *y = malloc(n * sizeof *y), *s = malloc(n * sizeof *s),
           *k1 = malloc(n * sizeof *s), *k2 = malloc(n * sizeof *s), *k3 = malloc(n * sizeof *s);
    cbm_status st = CBM_E_NOMEM;
    cbm_plot *p = NULL;
    if (!x || !y || !s || !k1 || !k2 || !k3)
        goto done;
    cbm_plot_def d = cbm_plot_def_default();
    d.title = "growing elastica";
    d.panels = 2;
    d.height = 800;
    st = cbm_plot_create(ctx, &d, &p);
    cbm_plot_axes_def a = cbm_plot_axes_def_default();
    a.xlabel = "x";
    a.ylabel = "y";
    if (st == CBM_OK)
        st = cbm_plot_set_axes(p, 0, &a);
    size_t every = g->n_frames > 8 ? (g->n_frames + 7) / 8 : 1;
    char labels[10][32];
    int nl = 0;
    for (size_t k = 0; k < g->n_frames && st == CBM_OK; k++) {
        if (k % every && k + 1 != g->n_frames)
            continue;
        const cbm_elastica_growth_frame *fr = &g->frames[k];
        x[0] = y[0] = 0;
        for (size_t i = 0; i < fr->n_cells; i++)
            x[i + 1] = fr->cells[i].x, y[i + 1] = fr->cells[i].y;
        cbm_plot_series_def ser = cbm_plot_series_def_default();
        snprintf(labels[nl % 10], sizeof labels[0], "t = %g", fr->time);
        ser.x = x, ser.y = y, ser.n = fr->n_cells + 1, ser.label = labels[nl % 10];
        nl++;
        st = cbm_plot_add_series(p, 0, &ser);
    }
    if (st == CBM_OK) {
        x[0] = y[0] = 0;
        for (size_t i = 0; i < lf->n_cells; i++)
            x[i + 1] = lf->cells[i].xg, y[i + 1] = lf->cells[i].yg;
        cbm_plot_series_def ser = cbm_plot_series_def_default();
        ser.x = x, ser.y = y, ser.n = n, ser.label = "growth configuration (last)";
        ser.line = CBM_PLOT_DASHED;
        st = cbm_plot_add_series(p, 0, &ser);
    }
    a.xlabel = "s";
    a.ylabel = "curvature (last frame)";
    if (st == CBM_OK)
        st = cbm_plot_set_axes(p, 1, &a);
    for (size_t i = 0; i < lf->n_cells; i++) {
        s[i] = lf->cells[i].s;
        k1[i] = lf->cells[i].kappa, k2[i] = lf->cells[i].kappa_g, k3[i] = lf->cells[i].kappa_c;
    }
    const double *ys[3] = {k1, k2, k3};
    const char *ln[3] = {"kappa", "kappa^g", "kappa^c"};
    for (int q = 0; q < 3 && st == CBM_OK; q++) {
        cbm_plot_series_def ser = cbm_plot_series_def_default();
        ser.x = s, ser.y = ys[q], ser.n = lf->n_cells, ser.label = ln[q];
        if (q)
            ser.line = CBM_PLOT_DASHED;
        st = cbm_plot_add_series(p, 1, &ser);
    }
    if (st == CBM_OK)
        st = cbm_plot_write(p, path);
done:
    cbm_plot_destroy(p);
    free(x), free(y), free(s), free(k1), free(k2), free(k3);
    return st;
}

static int run_growth(cbm_context *ctx, const cbm_elastica_spec *spec, const char *const *outs,
                      int nout, bool json)
{
    cbm_elastica_growth_def d;
    cbm_elastica_growth *g = NULL;
    double t0 = cli_now();
    cbm_status s = cbm_elastica_spec_growth(ctx, spec, &d);
    if (s == CBM_OK)
        s = cbm_elastica_grow(ctx, &d, &g);
    double secs = cli_now() - t0;
    if (s == CBM_OK && (!g || g->n_frames == 0))
        s = CBM_E_INTERNAL; /* a growth that succeeded has its first frame at least */
    int rc = s == CBM_OK ? CLI_OK : cli_fail(ctx, s, "elastica");
    for (int k = 0; k < nout && rc == CLI_OK && g; k++) {
        const char *ext = cli_extension(outs[k]);
        if (!strcmp(ext, "csv")) {
            cbm_out *o = NULL;
            s = cbm_out_open(ctx, outs[k], &o);
            if (s == CBM_OK) {
                growth_csv(cbm_out_stream(o), g);
                s = cbm_out_commit(o);
            }
        } else
            s = growth_plot(ctx, g, outs[k]);
        if (s != CBM_OK)
            rc = cli_fail(ctx, s, outs[k]);
    }
    if (rc == CLI_OK && g && json)
        growth_json(stdout, g, &d, secs);
    if (rc == CLI_OK && g && !json && nout == 0) {
        const cbm_elastica_growth_frame *f = &g->frames[g->n_frames - 1];
        size_t jumps = 0;
        for (size_t k = 0; k < g->n_frames; k++)
            jumps += g->frames[k].jumped;
        printf("grew %zu steps to length %.6g: tip (%.6g, %.6g), tip angle %.4g deg, %zu "
               "jump%s, %.3g s\n",
               d.steps, f->length, f->tip_x, f->tip_y, f->theta_tip * DEG, jumps,
               jumps == 1 ? "" : "s", secs);
    }
    cbm_elastica_growth_destroy(ctx, g);
    return rc;
}

int cmd_elastica(int argc, char **argv)
{
    const char *spec_path = NULL, *outs[MAX_OUTPUTS];
    cli_list out_list = {outs, 0, MAX_OUTPUTS, NULL};
    bool json = false;
    cli_opt rows[] = {
        {.name = "--help|-h", .kind = CLI_HELP},
        {.name = "SPEC", .kind = CLI_POSITIONAL, .target = &spec_path, .parse = cli_parse_one_spec},
        {.name = "--json", .kind = CLI_SET, .target = &json},
        {.name = "-o",
         .kind = CLI_CUSTOM,
         .target = &out_list,
         .parse = parse_output,
         .bad = "-o needs a file name"},
        {.kind = CLI_GROUP, .target = cli_limit_options()},
        {0}};
    cli_opts table = {.cmd = "elastica",
                      .opts = rows,
                      .help = help,
                      .width = 18,
                      .unknown = "unknown option '{opt}'"};
    int prc = cli_options_parse(&table, argc, argv);
    if (prc != CLI_OK)
        return prc == CLI_HELP_SHOWN ? CLI_OK : prc;
    int nout = out_list.count;
    if (!spec_path)
        return cli_usage_error("elastica", "expected a SPEC file (see cambium elastica --help)");
    if (cli_check_outputs(outs, nout) != CLI_OK)
        return CLI_FAIL;
    size_t len = 0;
    char *text = cli_read_spec(spec_path, &len);
    if (!text)
        return CLI_FAIL;
    cbm_context *ctx = cli_context();
    static cbm_elastica_spec spec;
    cbm_status s = cbm_elastica_spec_parse(ctx, text, len, spec_path, &spec);
    free(text);
    if (s != CBM_OK) {
        int rc = cli_fail(ctx, s, spec_path);
        cli_context_end(ctx);
        return rc;
    }
    if (spec.grows) {
        int grc = run_growth(ctx, &spec, outs, nout, json);
        cli_context_end(ctx);
        return grc;
    }
    double t0 = cli_now();
    result r;
    memset(&r, 0, sizeof r);
    r.spec = &spec;
    cbm_elastica_scurve *sc = NULL;
    cbm_elastica_state *eq = NULL;
    cbm_elastica_plant_state *pe = NULL;
    static cbm_elastica_jump up[MAX_JUMPS], down[MAX_JUMPS];
    r.up = up, r.down = down;
    s = run(ctx, &spec, &r, &sc, &eq, up, down, &pe);
    r.secs = cli_now() - t0;
    int rc = s == CBM_OK ? CLI_OK : cli_fail(ctx, s, "elastica");
    for (int k = 0; k < nout && rc == CLI_OK; k++) {
        const char *ext = cli_extension(outs[k]);
        if (!strcmp(ext, "csv")) {
            cbm_out *o = NULL;
            s = cbm_out_open(ctx, outs[k], &o);
            if (s == CBM_OK) {
                write_csv(cbm_out_stream(o), &r);
                s = cbm_out_commit(o);
            }
        } else
            s = write_plot(ctx, &r, outs[k]);
        if (s != CBM_OK)
            rc = cli_fail(ctx, s, outs[k]);
    }
    if (rc == CLI_OK && json)
        write_json(stdout, &r);
    if (rc == CLI_OK && !json && nout == 0 && sc) {
        printf("alpha %.6g: %zu points, %zu fold%s", r.alpha, sc->n_points, sc->n_folds,
               sc->n_folds == 1 ? "" : "s");
        if (spec.has_angle)
            printf(", %zu equilibri%s at %g deg", r.nbr > 1 ? r.npe : r.neq,
                   (r.nbr > 1 ? r.npe : r.neq) == 1 ? "um" : "a", spec.angle);
        printf(", %.3g s\n", r.secs);
    }
    cbm_elastica_plant_states_destroy(ctx, pe, r.npe, r.nbr);
    free(eq);
    cbm_elastica_scurve_destroy(ctx, sc);
    cli_context_end(ctx);
    return rc;
}
