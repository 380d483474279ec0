/* cambium grow for Oberlaender's parametric tree (cambium/ober.h): `cambium grow` hands over to
 * this file when its model is a built-in ober-* name or a .tree file whose first setting is
 * `family = oberlaender`. It grows a stand (one tree, or --stand NxM trees --spacing D apart with
 * germination staggered over --stagger years) and writes the stand (pictures and meshes), the
 * per-tree per-year report (.json), and plot:FILE.svg|png, the carbon tax and the height of each
 * tree over the years (the thesis's Fig. 25). */
#include "cli_grow.h"
#include "cli_output.h"
#include "commands.h"

#include "cambium/ober.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define MAX_OUTPUTS 16
#define MAX_DEFS    128

bool cli_grow_is_ober(cli_opts *t, int argc, char **argv)
{
    for (int i = cli_options_next_word(t, argc, argv, 1); i < argc;
         i = cli_options_next_word(t, argc, argv, i + 1)) {
        const char *a = argv[i];
        for (const char *const *n = cbm_ober_builtin_names(); *n; n++)
            if (!strcmp(a, *n))
                return true;
        if (cli_grow_ends_with(a, ".tree")) {
            size_t len = 0;
            char *text = cli_read_regular_file(a, (size_t)1 << 24, &len);
            bool yes = text && cbm_ober_text_is_family(text, len);
            free(text);
            return yes;
        }
    }
    return false;
}

static void help(const cli_opts *t)
{
    cli_grow_help(
        t,
        "usage: cambium grow OBER-MODEL [-y YEARS] [-D NAME=VALUE]... [--seed N]\n"
        "                    [--stand NxM] [--spacing D] [--stagger N] [-o FILE]...\n"
        "                    [--params] [--quiet] [output options]\n\n"
        "Grows Oberlaender's parametric tree (a built-in ober-* model or a .tree file\n"
        "starting with 'family = oberlaender'; docs/models.md): one tree or a stand.\n"
        "Outputs by extension: .png .svg .glb .obj .ply (the stand), .json (the report of\n"
        "every tree and year), .mtg (the stand as one MTG, a plant per tree),\n"
        "plot:FILE.svg or plot:FILE.png (carbon tax and height over the years), and with\n"
        "--mechanics mech:FILE (the trees bent by the statics, any scene format).\n\n",
        cbm_ober_builtin_names());
}

/* --stand NxM */
static bool parse_stand(const char *v, void *target, char *why, size_t n)
{
    long *xy = target;
    char *end;
    xy[0] = strtol(v, &end, 10);
    if (end == v || (*end != 'x' && *end != 'X')) {
        snprintf(why, n, "--stand expects NxM, got '{value}'");
        return false;
    }
    const char *m = end + 1;
    xy[1] = strtol(m, &end, 10);
    if (end == m || *end || xy[0] < 1 || xy[1] < 1 || xy[0] > 20 || xy[1] > 20) {
        snprintf(why, n, "--stand expects NxM with 1 <= N, M <= 20, got '{value}'");
        return false;
    }
    return true;
}

static bool parse_spacing(const char *v, void *target, char *why, size_t n)
{
    (void)why, (void)n;
    double *d = target;
    return cli_parse_double(v, d) && *d >= 0.01 && *d <= 1000;
}

static cbm_status write_report(cbm_context *ctx, const cbm_ober_stand *s, const char *model,
                               const cbm_ober_def *d, double seconds,
                               const cbm_ober_mech_result *mech, const double *yearly,
                               const char *path)
{
    cbm_json *j = NULL;
    cbm_status cs = cbm_json_create(ctx, &j);
    if (cs != CBM_OK)
        return cs;
    cbm_json_begin_object(j, NULL);
    cbm_json_string(j, "model", model);
    cbm_json_string(j, "family", "oberlaender");
    cbm_json_int(j, "seed", (int64_t)d->seed);
    cbm_json_int(j, "years_grown", cbm_ober_years(s));
    cbm_json_number(j, "seconds", seconds);
    cbm_json_begin_array(j, "trees");
    for (size_t t = 0; t < cbm_ober_tree_count(s); t++) {
        cbm_vec3 p = cbm_ober_tree_position(s, t);
        cbm_json_begin_object(j, NULL);
        cbm_json_int(j, "tree", (int64_t)t);
        cbm_json_begin_array(j, "position_m");
        cbm_json_number(j, NULL, p.x);
        cbm_json_number(j, NULL, p.y);
        cbm_json_number(j, NULL, p.z);
        cbm_json_end_array(j);
        cbm_json_begin_array(j, "years");
        for (int y = 1; y <= cbm_ober_years(s); y++) {
            const cbm_ober_report *r = cbm_ober_report_of(s, t, y);
            cbm_json_begin_object(j, NULL);
            cbm_json_int(j, "year", r->year);
            cbm_json_int(j, "age", r->age);
            cbm_json_number(j, "height_m", r->height);
            cbm_json_int(j, "leaves", (int64_t)r->leaves);
            cbm_json_int(j, "shoots", (int64_t)r->shoots);
            cbm_json_begin_array(j, "shoots_per_order");
            for (int k = 0; k < 4; k++)
                cbm_json_int(j, NULL, (int64_t)r->shoots_order[k]);
            cbm_json_end_array(j);
            cbm_json_int(j, "new_shoots", (int64_t)r->new_shoots);
            cbm_json_int(j, "proventitious_shoots", (int64_t)r->proventitious);
            cbm_json_int(j, "forks", (int64_t)r->forks);
            cbm_json_int(j, "pruned_shoots", (int64_t)r->removed);
            cbm_json_number(j, "wood_volume_m3", r->wood_volume);
            cbm_json_number(j, "trunk_volume_m3", r->trunk_volume);
            cbm_json_number(j, "base_diameter_m", r->base_diameter);
            cbm_json_number(j, "base_length_cm", r->base_length);
            cbm_json_number(j, "carbon_tax", r->carbon_tax);
            cbm_json_number(j, "carbon_mean", r->carbon_mean);
            cbm_json_int(j, "light_rays", (int64_t)r->light_rays);
            cbm_json_number(j, "light_seconds", r->light_seconds);
            if (yearly && r->age > 0) { /* --mechanics: this year's tree under the statics */
                const double *m = &yearly[((size_t)(y - 1) * cbm_ober_tree_count(s) + t) * 2];
                cbm_json_number(j, "mech_max_tip_difference_m", m[0]);
                cbm_json_number(j, "mech_mean_tip_difference_m", m[1]);
            }
            cbm_json_end_object(j);
        }
        cbm_json_end_array(j);
        if (mech && mech[t].shoots > 0) { /* --mechanics: the final tree under the statics */
            const cbm_ober_mech_result *m = &mech[t];
            cbm_json_begin_object(j, "mechanics");
            cbm_json_int(j, "year", cbm_ober_years(s));
            cbm_json_int(j, "shoots", (int64_t)m->shoots);
            cbm_json_int(j, "segments", (int64_t)m->segments);
            cbm_json_number(j, "mass_kg", m->mass);
            cbm_json_bool(j, "converged", m->converged);
            cbm_json_number(j, "residual", m->residual);
            cbm_json_number(j, "max_tip_difference_m", m->max_tip_difference);
            cbm_json_number(j, "mean_tip_difference_m", m->mean_tip_difference);
            cbm_json_int(j, "max_tip_difference_shoot", (int64_t)m->max_shoot);
            cbm_json_number(j, "max_sag_m", m->max_sag);
            cbm_json_number(j, "max_joint_displacement_m", m->max_joint);
            cbm_json_number(j, "kinematic_height_m", m->kinematic_height);
            cbm_json_number(j, "mechanical_height_m", m->mechanical_height);
            cbm_json_end_object(j);
        }
        cbm_json_end_object(j);
    }
    cbm_json_end_array(j);
    cbm_json_end_object(j);
    cbm_status st = cbm_json_write_file(j, path);
    cbm_json_destroy(j);
    return st;
}

/* plot:FILE: carbon tax (top) and height (bottom) of every tree over the years */
static cbm_status write_plot(cbm_context *ctx, const cbm_ober_stand *s, const char *model,
                             const char *path)
{
    size_t nt = cbm_ober_tree_count(s), ny = (size_t)cbm_ober_years(s);
    double *x = calloc(ny ? ny : 1, sizeof *x), *tax = calloc(ny ? ny : 1, sizeof *tax),
           *h = calloc(ny ? ny : 1, sizeof *h);
    if (!x || !tax || !h) {
        free(x), free(tax), free(h);
        return CBM_E_NOMEM;
    }
    cbm_plot_def pd = cbm_plot_def_default();
    char title[160];
    snprintf(title, sizeof title, "%s: carbon tax and height", model);
    pd.title = title;
    pd.panels = 2;
    cbm_plot *p = NULL;
    cbm_status st = cbm_plot_create(ctx, &pd, &p);
    cbm_plot_axes_def a = cbm_plot_axes_def_default();
    a.xlabel = "year";
    a.ylabel = "carbon tax";
    if (st == CBM_OK)
        st = cbm_plot_set_axes(p, 0, &a);
    a.ylabel = "height (m)";
    if (st == CBM_OK)
        st = cbm_plot_set_axes(p, 1, &a);
    for (size_t t = 0; t < nt && t < 12 && st == CBM_OK; t++) {
        for (size_t y = 0; y < ny; y++) {
            const cbm_ober_report *r = cbm_ober_report_of(s, t, (int)y + 1);
            x[y] = (double)y + 1;
            tax[y] = r->age > 0 ? r->carbon_tax : NAN;
            h[y] = r->age > 0 ? r->height : NAN;
        }
        char label[32];
        snprintf(label, sizeof label, "tree %zu", t);
        cbm_plot_series_def sd = cbm_plot_series_def_default();
        sd.x = x, sd.n = ny, sd.label = nt > 1 ? label : NULL;
        sd.marker = CBM_PLOT_MARKER_CIRCLE;
        sd.y = tax;
        st = cbm_plot_add_series(p, 0, &sd);
        sd.y = h;
        if (st == CBM_OK)
            st = cbm_plot_add_series(p, 1, &sd);
    }
    if (st == CBM_OK)
        st = cbm_plot_write(p, path);
    cbm_plot_destroy(p);
    free(x), free(tax), free(h);
    return st;
}

int cmd_grow_ober(int argc, char **argv)
{
    const char *model = NULL, *outs[MAX_OUTPUTS], *defs[MAX_DEFS];
    cli_list out_list = {outs, 0, MAX_OUTPUTS, "at most {max} outputs"};
    cli_list def_list = {defs, 0, MAX_DEFS, "at most {max} -D options"};
    long years = -1, stand[2] = {0, 0}, stagger = -1, seed = -1;
    double spacing = -1;
    bool quiet = false, params = false, mechanics = false;
    cbm_write_options o = cbm_write_options_default();
    cli_opt rows[] = {
        {.name = "--help|-h", .kind = CLI_HELP},
        cli_grow_model_row(&model),
        cli_grow_years_row(&years),
        cli_grow_defines_row(&def_list, "set a parameter or formula (as in a parameter file)"),
        {.name = "--seed",
         .kind = CLI_LONG,
         .target = &seed,
         .min = 0,
         .max = 0x7fffffffL,
         .bad = "--seed must be a non-negative integer",
         .arg = "N",
         .help = "generator seed (same as -D seed=N)"},
        {.name = "--stand",
         .kind = CLI_CUSTOM,
         .target = stand,
         .parse = parse_stand,
         .arg = "NxM",
         .help = "a stand of N x M trees on a grid (standX, standY)"},
        {.name = "--spacing",
         .kind = CLI_CUSTOM,
         .target = &spacing,
         .parse = parse_spacing,
         .bad = "--spacing must be a distance in m, 0.01..1000",
         .arg = "D",
         .help = "m between neighbouring trees of the stand (spacing)"},
        {.name = "--stagger",
         .kind = CLI_LONG,
         .target = &stagger,
         .min = 0,
         .max = 100,
         .bad = "--stagger must be 0..100",
         .arg = "N",
         .help = "germination spread over 0..N years (stagger)"},
        {.name = "-o", .kind = CLI_LIST, .target = &out_list},
        {.name = "--quiet", .kind = CLI_SET, .target = &quiet, .help = "no per-year lines"},
        {.name = "--mechanics",
         .kind = CLI_SET,
         .target = &mechanics,
         .help = "solve the final trees' statics (.json 'mechanics', mech:FILE)"},
        cli_grow_params_row(&params),
        {.kind = CLI_GROUP, .target = cli_output_options(&o)},
        {0}};
    cli_opts table = {.cmd = "grow",
                      .opts = rows,
                      .help = help,
                      .width = 18,
                      .unknown = "unknown option {opt} (for an Oberlaender tree)",
                      .unknown_last = "unknown option or missing value: {opt}",
                      .missing = "unknown option or missing value: {opt}"};
    int prc = cli_options_parse(&table, argc, argv);
    if (prc != CLI_OK)
        return prc == CLI_HELP_SHOWN ? CLI_OK : prc;
    int nout = out_list.count;
    cli_output_target targets[MAX_OUTPUTS];
    int kind[MAX_OUTPUTS]; /* 0 scene, 1 json, 2 plot, 3 mtg, 4 mech: scene of the statics */
    const char *paths[MAX_OUTPUTS];
    for (int k = 0; k < nout; k++) {
        kind[k] = !strncmp(outs[k], "mech:", 5)             ? 4
                  : !strncmp(outs[k], "plot:", 5)           ? 2
                  : !strcmp(cli_extension(outs[k]), "json") ? 1
                  : !strcmp(cli_extension(outs[k]), "mtg")  ? 3
                                                            : 0;
        paths[k] = kind[k] == 2 ? outs[k] + 5 : outs[k];
        if (kind[k] == 2 && strcmp(cli_extension(paths[k]), "svg") &&
            strcmp(cli_extension(paths[k]), "png"))
            return cli_usage_error("grow", "%s: the plot is .svg or .png", outs[k]);
        if (kind[k] == 4 && !mechanics)
            return cli_usage_error("grow", "%s: a mech: output needs --mechanics", outs[k]);
        if (kind[k] == 0 || kind[k] == 4) {
            if (!cli_output_target_parse(outs[k] + (kind[k] == 4 ? 5 : 0), &targets[k]))
                return cli_usage_error("grow",
                                       "%s: unknown format (.png .svg .glb .obj .ply .json .mtg, "
                                       "plot:FILE.svg, or FORMAT:PATH)",
                                       outs[k]);
            paths[k] = targets[k].path;
        }
    }
    if (cli_check_outputs(paths, nout) != CLI_OK)
        return CLI_FAIL;
    cbm_context *ctx = cli_context();
    int rc = CLI_OK;
    cbm_ober_stand *s = NULL;
    cbm_scene *sc = NULL;
    cbm_ober_mech_result *mech = NULL;
    cbm_plant **plants = NULL;
    double *yearly = NULL; /* --mechanics: per year and tree, max and mean tip difference */
    cbm_ober_def d = cbm_ober_def_default();
    cbm_status st = cli_grow_ends_with(model, ".tree") ? cbm_ober_def_read(ctx, &d, model)
                                                       : cbm_ober_def_builtin(ctx, model, &d);
    if (st != CBM_OK) {
        rc = st == CBM_E_SYNTAX ? CLI_FAIL : cli_fail(ctx, st, model);
        goto done;
    }
    for (int k = 0; k < def_list.count; k++) {
        char name[128];
        const char *value = cli_grow_define(defs[k], name, sizeof name);
        if (!value) {
            rc = CLI_USAGE;
            goto done;
        }
        st = cbm_ober_def_set(ctx, &d, name, value, NULL);
        if (st != CBM_OK) {
            rc = cli_usage_error("grow", "-D %s", cbm_context_last_error(ctx));
            goto done;
        }
    }
    if (seed >= 0)
        d.seed = (uint64_t)seed;
    if (years >= 0)
        d.years = (int)years;
    if (stand[0] > 0)
        d.stand_x = (int)stand[0], d.stand_y = (int)stand[1];
    if (spacing > 0)
        d.spacing = spacing;
    if (stagger >= 0)
        d.stagger = (int)stagger;
    if (params) {
        st = cbm_ober_def_check(ctx, &d);
        if (st != CBM_OK) {
            rc = CLI_FAIL;
            goto done;
        }
        size_t need = cbm_ober_def_format(&d, NULL, 0);
        char *buf = malloc(need + 1);
        if (!buf) {
            rc = CLI_FAIL;
            goto done;
        }
        cbm_ober_def_format(&d, buf, need + 1);
        fputs(buf, stdout);
        free(buf);
        goto done;
    }
    if (nout == 0 && quiet) {
        rc = cli_usage_error("grow", "nothing to do: give -o FILE or drop --quiet");
        goto done;
    }
    st = cbm_ober_create(ctx, &d, &s);
    if (st != CBM_OK) {
        rc = st == CBM_E_SYNTAX ? CLI_FAIL : cli_fail(ctx, st, model);
        goto done;
    }
    double t0 = cli_seconds();
    if (mechanics && d.years > 0 &&
        !(yearly = calloc((size_t)d.years * cbm_ober_tree_count(s) * 2, sizeof *yearly))) {
        rc = cli_fail(ctx, CBM_E_NOMEM, "mechanics");
        goto done;
    }
    while (cbm_ober_years(s) < d.years) {
        st = cbm_ober_year(s);
        if (st != CBM_OK) {
            rc = cli_fail(ctx, st, "growing the stand");
            goto done;
        }
        if (yearly) { /* the statics of every tree after the year (the growth stays kinematic) */
            size_t nt = cbm_ober_tree_count(s), y = (size_t)cbm_ober_years(s) - 1;
            cbm_ober_mech_def md = cbm_ober_mech_def_default();
            for (size_t t = 0; t < nt; t++) {
                cbm_ober_mech_result mr;
                st = cbm_ober_mechanics(s, t, &md, &mr, NULL);
                if (st != CBM_OK) {
                    rc = cli_fail(ctx, st, "mechanics");
                    goto done;
                }
                yearly[(y * nt + t) * 2] = mr.max_tip_difference;
                yearly[(y * nt + t) * 2 + 1] = mr.mean_tip_difference;
            }
        }
        if (!quiet) {
            int y = cbm_ober_years(s);
            size_t nt = cbm_ober_tree_count(s), leaves = 0, shoots = 0;
            double hmax = 0, tax = 0;
            for (size_t t = 0; t < nt; t++) {
                const cbm_ober_report *r = cbm_ober_report_of(s, t, y);
                leaves += r->leaves, shoots += r->shoots;
                hmax = r->height > hmax ? r->height : hmax;
                tax += r->carbon_tax / (double)nt;
            }
            printf("year %2d: %zu tree%s, %zu shoots, %zu leaves, height %.3f m%s, carbon tax "
                   "%.4g\n",
                   y, nt, nt == 1 ? "" : "s", shoots, leaves, hmax, nt > 1 ? " (tallest)" : "",
                   tax);
        }
    }
    double seconds = cli_seconds() - t0;
    if (!quiet && cbm_ober_tree_count(s) > 0) { /* the light passes' rays (the same in each tree) */
        size_t rays = 0;
        double light_s = 0;
        for (int y = 1; y <= cbm_ober_years(s); y++) {
            rays += cbm_ober_report_of(s, 0, y)->light_rays;
            light_s += cbm_ober_report_of(s, 0, y)->light_seconds;
        }
        if (rays > 0)
            printf("light: %zu rays in %.3f s (%.3g M rays/s); all else %.3f s\n", rays, light_s,
                   light_s > 0 ? 1e-6 * (double)rays / light_s : 0.0, seconds - light_s);
    }
    if (mechanics) {
        size_t nt = cbm_ober_tree_count(s);
        mech = calloc(nt ? nt : 1, sizeof *mech);
        // NOLINTNEXTLINE(bugprone-sizeof-expression): an array of pointers, one plant per tree
        plants = calloc(nt ? nt : 1, sizeof *plants);
        if (!mech || !plants) {
            rc = cli_fail(ctx, CBM_E_NOMEM, "mechanics");
            goto done;
        }
        cbm_ober_mech_def md = cbm_ober_mech_def_default();
        for (size_t t = 0; t < nt; t++) {
            st = cbm_ober_mechanics(s, t, &md, &mech[t], &plants[t]);
            if (st != CBM_OK) {
                rc = cli_fail(ctx, st, "mechanics");
                goto done;
            }
            if (!quiet && mech[t].shoots > 0)
                printf("mechanics, tree %zu: %zu segments, %.4g kg, tip difference to the joint's "
                       "shape max %.4g m, mean %.4g m (sag %.4g m)%s\n",
                       t, mech[t].segments, mech[t].mass, mech[t].max_tip_difference,
                       mech[t].mean_tip_difference, mech[t].max_sag,
                       mech[t].converged ? "" : ", NOT converged");
        }
    }
    for (int k = 0; k < nout && rc == CLI_OK; k++) {
        if (kind[k] == 1)
            st = write_report(ctx, s, model, &d, seconds, mech, yearly, outs[k]);
        else if (kind[k] == 2)
            st = write_plot(ctx, s, model, paths[k]);
        else if (kind[k] == 3)
            st = cbm_ober_write_mtg(ctx, s, outs[k]);
        else if (kind[k] == 4) {
            cbm_scene *ms = NULL;
            st = cbm_scene_create(ctx, &ms);
            for (size_t t = 0; t < cbm_ober_tree_count(s) && st == CBM_OK; t++)
                if (plants[t])
                    st = cbm_plant_to_scene(plants[t], ms, 10);
            if (st == CBM_OK)
                st = cbm_scene_write_as(ctx, ms, targets[k].path, targets[k].format, &o);
            cbm_scene_destroy(ms);
        } else {
            if (!sc) {
                st = cbm_scene_create(ctx, &sc);
                if (st == CBM_OK)
                    st = cbm_ober_to_scene(s, sc, 10, o.ground);
            }
            if (st == CBM_OK)
                st = cbm_scene_write_as(ctx, sc, targets[k].path, targets[k].format, &o);
        }
        if (st != CBM_OK)
            rc = cli_fail(ctx, st, outs[k]);
    }
done:
    for (size_t t = 0; plants && t < cbm_ober_tree_count(s); t++)
        cbm_plant_destroy(plants[t]);
    free(plants);
    free(mech);
    free(yearly);
    cbm_scene_destroy(sc);
    cbm_ober_destroy(s);
    cli_context_end(ctx);
    return rc;
}
