/* cambium demo: writes a synthetic tree (cbm_scene_demo_tree) in every format asked with -o, to
 * try the writers and viewers, and to measure them (--timing). With --frames F, a .glb holds a
 * growth animation of F frames (the tree grown to 1/F, 2/F, ... of its segments), built frame by
 * frame with cbm_animation from one scene refilled at each step, as a long run would; the other
 * formats get the last frame. */
#include "cli_output.h"
#include "commands.h"

#include <limits.h>
#include <string.h>

#define MAX_OUTPUTS 16

static void help(const cli_opts *t)
{
    printf("usage: cambium demo [--segments N] [--sides N] [--seed N] [--frames F] [--timing]\n"
           "                    -o FILE [-o FILE]... [output options]\n\n"
           "Writes a synthetic tree of N branch segments (default 2000) with leaves, fruit and\n"
           "ground, in the formats named by the extensions (.obj .ply .glb .png .svg .csv);\n"
           "FORMAT:PATH names the format explicitly (png:- writes a PNG to stdout).\n"
           "--frames F makes .glb files a growth animation of F frames. --timing prints the\n"
           "time each step takes to stderr.\n");
    cli_options_help(stdout, t);
}

int cmd_demo(int argc, char **argv)
{
    long segments = 2000, sides = 8, seed = 1, frames = 0;
    bool timing = false;
    const char *outs[MAX_OUTPUTS];
    cli_list out_list = {outs, 0, MAX_OUTPUTS, "at most {max} outputs"};
    cbm_write_options o = cbm_write_options_default();
    cli_opt rows[] = {{.name = "--help|-h", .kind = CLI_HELP},
                      {.name = "--timing", .kind = CLI_SET, .target = &timing},
                      {.name = "-o", .kind = CLI_LIST, .target = &out_list},
                      {.name = "--segments",
                       .kind = CLI_LONG,
                       .target = &segments,
                       .min = 1,
                       .max = 10000000,
                       .bad = "--segments must be 1..10000000"},
                      {.name = "--sides",
                       .kind = CLI_LONG,
                       .target = &sides,
                       .min = 3,
                       .max = 64,
                       .bad = "--sides must be 3..64"},
                      {.name = "--seed",
                       .kind = CLI_LONG,
                       .target = &seed,
                       .min = 0,
                       .max = LONG_MAX,
                       .bad = "--seed must be a non-negative integer"},
                      {.name = "--frames",
                       .kind = CLI_LONG,
                       .target = &frames,
                       .min = 1,
                       .max = 1000,
                       .bad = "--frames must be 1..1000"},
                      {.kind = CLI_GROUP, .target = cli_output_options(&o)},
                      {0}};
    cli_opts table = {.cmd = "demo",
                      .opts = rows,
                      .help = help,
                      .width = 18,
                      .unknown = "unknown option {opt}",
                      .unknown_last = "unknown option or missing value: {opt}",
                      .missing = "unknown option or missing value: {opt}"};
    int prc = cli_options_parse(&table, argc, argv);
    if (prc != CLI_OK)
        return prc == CLI_HELP_SHOWN ? CLI_OK : prc;
    int nout = out_list.count;
    if (nout == 0)
        return cli_usage_error("demo", "no output: give at least one -o FILE");
    cli_output_target targets[MAX_OUTPUTS];
    for (int k = 0; k < nout; k++)
        if (!cli_output_target_parse(outs[k], &targets[k]))
            return cli_usage_error("demo",
                                   "%s: unknown format (.obj .ply .glb .png .svg .csv, "
                                   "or FORMAT:PATH)",
                                   outs[k]);
    cbm_context *ctx = cli_context();
    size_t nf = frames > 0 ? (size_t)frames : 1;
    int rc = CLI_OK;
    cbm_scene *sc = NULL;
    cbm_animation *anim[MAX_OUTPUTS] = {NULL};
    cbm_status st = cbm_scene_create(ctx, &sc);
    /* a growth animation per .glb output, filled frame by frame from one scene */
    for (int k = 0; k < nout && st == CBM_OK && frames > 0; k++)
        if (!strcmp(targets[k].format, "glb"))
            st = cbm_animation_create(ctx, &o, &anim[k]);
    cli_progress pr;
    cli_progress_begin(&pr);
    double t0 = cli_seconds();
    for (size_t f = 0; f < nf && st == CBM_OK; f++) {
        size_t n = (size_t)segments * (f + 1) / nf;
        cbm_scene_clear(sc);
        st = cbm_scene_demo_tree(ctx, sc, n ? n : 1, (int)sides, o.ground, (uint64_t)seed);
        for (int k = 0; k < nout && st == CBM_OK; k++)
            if (anim[k])
                st = cbm_animation_add_frame(anim[k], sc);
        cbm_progress state = {f + 1, nf, n, 0, 0};
        cli_progress_update(&pr, &state);
    }
    cli_progress_end(&pr);
    if (st != CBM_OK) {
        rc = cli_fail(ctx, st, "building the demo tree");
        goto done;
    }
    if (timing)
        fprintf(stderr, "demo: %ld segments, %zu triangles built in %.3f s\n", segments,
                cbm_scene_triangle_count(sc), cli_seconds() - t0);
    for (int k = 0; k < nout && rc == CLI_OK; k++) {
        double t = cli_seconds();
        if (anim[k])
            st = cbm_animation_write(anim[k], targets[k].path);
        else
            st = cbm_scene_write_as(ctx, sc, targets[k].path, targets[k].format, &o);
        if (st != CBM_OK)
            rc = cli_fail(ctx, st, outs[k]);
        else if (timing)
            fprintf(stderr, "demo: wrote %s in %.3f s\n", outs[k], cli_seconds() - t);
    }
done:
    for (int k = 0; k < nout; k++)
        cbm_animation_destroy(anim[k]);
    cbm_scene_destroy(sc);
    cli_context_end(ctx);
    return rc;
}
