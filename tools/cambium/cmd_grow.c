/* cambium grow: grows a built-in tree model (cambium/tree.h) from a parameter file or a built-in
 * name for a number of years, and writes the final tree (pictures, meshes), the segments table
 * (.csv), the MTG (.mtg) and the year-by-year summary (.json); with --every K a .glb holds a
 * growth animation of one frame every K growth steps. */
#include "cli_output.h"
#include "commands.h"

#include <stdlib.h>
#include <string.h>

#define MAX_OUTPUTS 16
#define MAX_DEFS    128

static void help(void)
{
    printf("usage: cambium grow [MODEL.tree | NAME] [-y YEARS] [-D NAME=VALUE]... [--seed N]\n"
           "                    [-o FILE]... [--every K] [--summer] [--timing] [--quiet]\n"
           "                    [--params] [limits] [output options]\n\n"
           "Grows the general fruit tree of Taylor-Hell (2005) with full mechanics, or the\n"
           "wild or crooked aspen, from a parameter file or a built-in model (default\n"
           "fruit-tree; see docs/models.md). Outputs by extension: .png .svg .glb .obj .ply\n"
           "(the tree with leaves and fruit; .glb with --every K: a growth animation, one\n"
           "frame every K growth steps), .csv (segments table), .mtg, .json (year-by-year\n"
           "summary). FORMAT:PATH names a scene format explicitly.\n\n"
           "  -y, -n, --years N years to grow (default: the model's 'years')\n"
           "  -D NAME=VALUE     set a parameter (as in a parameter file; angles in degrees)\n"
           "  --seed N          generator seed (same as -D seed=N)\n"
           "  --every K         animation frame every K growth steps (.glb outputs)\n"
           "  --summer          stop at the end of the last summer (leaves and fruit on; the\n"
           "                    .json then ends with that year, \"complete\": false)\n"
           "  --timing          time spent per phase on stderr\n"
           "  --quiet           no per-year lines on stdout\n"
           "  --params          print every parameter (parameter-file syntax) and exit\n\n"
           "built-in models:");
    for (const char *const *n = cbm_tree_builtin_names(); *n; n++)
        printf(" %s", *n);
    printf("\n\n%s\n%s", cli_limits_help, cli_output_help);
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
    cbm_json_int(j, "growth_steps", (int64_t)s->growth_steps);
    cbm_json_int(j, "equilibrium_passes", (int64_t)s->passes);
    cbm_json_int(j, "newton_steps", (int64_t)s->newton_steps);
    cbm_json_int(j, "unconverged", (int64_t)s->unconverged);
    cbm_json_number(j, "seconds", s->seconds);
    cbm_json_number(j, "seconds_equilibrium", s->seconds_solve);
    cbm_json_number(j, "seconds_rings", s->seconds_rings);
    cbm_json_end_object(j);
}

static bool ends_with(const char *s, const char *suf)
{
    size_t a = strlen(s), b = strlen(suf);
    return a >= b && !strcmp(s + a - b, suf);
}

/* --timing: where the time went. `derive` is the growth itself (the tree's steps: equilibrium,
 * rings and ageing, growth and bookkeeping), `interpret` the scene building, `write` the
 * writers. */
static void print_timing(cbm_context *ctx, const cbm_tree *t, double derive, double interpret,
                         double write, double total)
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
    fprintf(stderr,
            "grow: %d years, %zu segments: derive %.3f s (equilibrium %.3f s in %zu passes, "
            "rings and ageing %.3f s, growth and the rest %.3f s), interpret %.3f s, write "
            "%.3f s, total %.3f s; peak %.1f MB in the library\n",
            cbm_tree_years(t), cbm_plant_segment_count(cbm_tree_plant(t)), derive, solve, passes,
            rings, derive - solve - rings, interpret, write, total,
            (double)cbm_context_peak_bytes(ctx) / 1e6);
}

int cmd_grow(int argc, char **argv)
{
    const char *model = NULL, *outs[MAX_OUTPUTS], *defs[MAX_DEFS];
    int nout = 0, ndef = 0;
    long years = -1, every = 0;
    const char *seed = NULL;
    bool timing = false, quiet = false, params = false, summer = false;
    cbm_write_options o = cbm_write_options_default();
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            help();
            return CLI_OK;
        }
        int r = cli_output_option("grow", argc, argv, &i, &o);
        if (r == 0)
            r = cli_limit_option("grow", argc, argv, &i);
        if (r < 0)
            return CLI_USAGE;
        if (r > 0)
            continue;
        if (!strcmp(a, "--timing")) {
            timing = true;
            continue;
        }
        if (!strcmp(a, "--quiet")) {
            quiet = true;
            continue;
        }
        if (!strcmp(a, "--summer")) {
            summer = true;
            continue;
        }
        if (!strcmp(a, "--params")) {
            params = true;
            continue;
        }
        if (a[0] != '-') {
            if (model)
                return cli_usage_error("grow", "more than one model: '%s' and '%s'", model, a);
            model = a;
            continue;
        }
        if (!strncmp(a, "-D", 2) && a[2]) { /* -DNAME=VALUE */
            if (ndef == MAX_DEFS)
                return cli_usage_error("grow", "at most %d -D options", MAX_DEFS);
            defs[ndef++] = a + 2;
            continue;
        }
        if (i + 1 >= argc)
            return cli_usage_error("grow", "unknown option or missing value: %s", a);
        const char *v = argv[++i];
        if (!strcmp(a, "-o")) {
            if (nout == MAX_OUTPUTS)
                return cli_usage_error("grow", "at most %d outputs", MAX_OUTPUTS);
            outs[nout++] = v;
        } else if (!strcmp(a, "-D")) {
            if (ndef == MAX_DEFS)
                return cli_usage_error("grow", "at most %d -D options", MAX_DEFS);
            defs[ndef++] = v;
        } else if (!strcmp(a, "-y") || !strcmp(a, "--years") || !strcmp(a, "-n")) {
            if (!cli_parse_long(v, &years) || years < 0 || years > 1000)
                return cli_usage_error("grow", "%s must be 0..1000", a);
        } else if (!strcmp(a, "--seed")) {
            long sd;
            if (!cli_parse_long(v, &sd) || sd < 0)
                return cli_usage_error("grow", "--seed must be a non-negative integer");
            seed = v;
        } else if (!strcmp(a, "--every")) {
            if (!cli_parse_long(v, &every) || every < 1 || every > 1000000)
                return cli_usage_error("grow", "--every must be 1..1000000");
        } else {
            return cli_usage_error("grow", "unknown option %s", a);
        }
    }
    cli_output_target targets[MAX_OUTPUTS];
    int kind[MAX_OUTPUTS]; /* 0 scene, 1 csv, 2 mtg, 3 json */
    for (int k = 0; k < nout; k++) {
        const char *ext = cli_extension(outs[k]);
        kind[k] = !strcmp(ext, "csv") ? 1 : !strcmp(ext, "mtg") ? 2 : !strcmp(ext, "json") ? 3 : 0;
        if (kind[k] == 0 && !cli_output_target_parse(outs[k], &targets[k]))
            return cli_usage_error("grow",
                                   "%s: unknown format (.png .svg .glb .obj .ply .csv .mtg "
                                   ".json, or FORMAT:PATH)",
                                   outs[k]);
    }
    {
        const char *paths[MAX_OUTPUTS];
        for (int k = 0; k < nout; k++)
            paths[k] = kind[k] == 0 ? targets[k].path : outs[k];
        if (cli_check_outputs(paths, nout) != CLI_OK)
            return CLI_FAIL;
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
    if (ends_with(model, ".tree"))
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
            const char *eq = strchr(dv, '=');
            if (!eq || eq == dv || (size_t)(eq - dv) >= sizeof name) {
                rc = cli_usage_error("grow", "-D expects NAME=VALUE, got '%s'", dv);
                goto done;
            }
            memcpy(name, dv, (size_t)(eq - dv));
            name[eq - dv] = '\0';
            val = eq + 1;
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
    if (nout == 0 && quiet) {
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
    double grow_time = cli_seconds() - t0;
    double derive = grow_time - t_interpret - t_write; /* minus the animation frames */
    if (st != CBM_OK) {
        rc = cli_fail(ctx, st, "growing the tree");
        goto done;
    }
    bool scene_built = false;
    for (int k = 0; k < nout && rc == CLI_OK; k++) {
        double tw = cli_seconds(), ti = 0.0;
        if (kind[k] == 1)
            st = cbm_write_segments_csv(ctx, cbm_tree_plant(t), outs[k]);
        else if (kind[k] == 2)
            st = cbm_write_mtg(ctx, cbm_tree_plant(t), outs[k]);
        else if (kind[k] == 3)
            st = write_summary(ctx, t, model, &d, grow_time, summer, outs[k]);
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
        print_timing(ctx, t, derive, t_interpret, t_write, cli_seconds() - t0);
done:
    for (int k = 0; k < nout; k++)
        cbm_animation_destroy(anim[k]);
    cbm_scene_destroy(sc);
    cbm_tree_destroy(t);
    cli_context_end(ctx);
    return rc;
}
