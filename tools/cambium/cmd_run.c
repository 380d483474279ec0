/* cambium run MODEL.l [SIDE FILES...] [-n STEPS] [-D NAME=VALUE]... [--seed N] [-o OUT]...
 *                     [--every K] [--homomorphism] [--float32] [--max-modules N]
 *                     [--max-memory MB] [--timing]
 *                     [output options]
 *
 * Loads a cpfg-dialect model with its side files (cbm_model: view file, function files,
 * surfaces, colour map, materials, by extension), derives it for its derivation length (or -n
 * STEPS) with the turtle filling query modules where the string has them, interprets the final
 * string into a scene and writes the requested outputs, chosen by extension (or FORMAT:PATH):
 * .str (the string), .json (a summary per step), and the scene writers of cambium/write.h (.obj
 * .ply .glb .png .svg .csv) with the shared output options of cli_output.h; .mtg and
 * segments:PATH write the plant's segments (the mechanical ones of an L+C model with mechanics,
 * otherwise those the turtle draws, from a pass with its record on). With --every K the
 * outputs are also written after step 0 and every K-th step as NAME.STEP.EXT (NAME.0003.png),
 * except .glb, which becomes one animation with a frame per K steps. Without -o it derives,
 * interprets and prints a one-line summary. When a limit stops the derivation, the outputs of
 * the last complete step are written and the exit status is 1; any other error writes nothing
 * more (every file goes through cbm_out: complete or absent). Pictures (.png .svg) draw cpfg's
 * pixel lines as lines, not tubes: when every scene output is a picture the scene is in line
 * mode; when meshes are asked too, the scene keeps tubes for them and a step with pixel lines
 * is interpreted a second time into a scene in line mode for the pictures.
 */
#define _POSIX_C_SOURCE 200809L
#include "cli_output.h"
#include "commands.h"
#include "grow_sway.h"

#include "cambium/turtle_motion.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define MAX_OUTPUTS 64

/* Outputs that are not scene formats. */
static const struct {
    const char *ext, *what;
} OTHER_OUTPUTS[] = {
    {"str", "the derived string, one module per line, parameters as %.9g"},
    {"json", "a summary per step: modules, primitives, bounding box, seconds"},
    {"mtg", "the plant as an OpenAlea MTG: the mechanical segments (L+C models with "
            "mechanics:), otherwise the segments the turtle draws, linked by its branches"},
    {"segments", "(segments:PATH) the same segments as a CSV table, one row each"},
    {"motion",
     "(motion:PATH.csv or .glb) the drawn segments and spheres at every recorded\n"
     "                            step: a table, or a glTF animating each as a rigid node"},
    {"sway",
     "(sway:PATH.csv or .glb) the motion of the model's last Sway() call (L+C\n"
     "                            mechanics): the tips' displacements, or a glTF animating\n"
     "                            each segment (the sway outputs of grow)"},
};

static const struct {
    const char *ext, *what;
} SCENE_OUTPUTS[] = {
    {"obj", "Wavefront OBJ with normals and colours (+ .mtl)"},
    {"ply", "binary PLY with normals, colours and part data"},
    {"glb", "glTF 2.0 binary; with --every one growth animation"},
    {"png", "shaded picture (Embree ray casting)"},
    {"svg", "vector projection"},
    {"csv", "one row per part (segment, organ, colour, centroid, ...)"},
};

/* Side files by extension (read by the turtle and the function evaluator). */
static const char *const SIDE_KINDS[] = {"v", "func", "fset", "s", "con", "map", "mat"};
/* Files of a cpfg model directory that cambium has no use for (animation, environment, text). */
static const char *const IGNORED_KINDS[] = {"a", "e", "txt"};

typedef struct target {
    char format[16];
    const char *path;
    const char *arg;
    cbm_animation *anim;       /* .glb with --every */
    cbm_turtle_motion *motion; /* motion:PATH */
} target;

static bool in_list(const char *ext, const char *const *list, size_t n)
{
    for (size_t k = 0; k < n; k++)
        if (!strcmp(ext, list[k]))
            return true;
    return false;
}

/* "x.str", "str:PATH", "x.json", or a scene target; false if the format is unknown. */
static bool parse_target(const char *arg, target *t)
{
    memset(t, 0, sizeof *t);
    t->arg = arg;
    for (size_t k = 0; k < sizeof OTHER_OUTPUTS / sizeof OTHER_OUTPUTS[0]; k++) {
        const char *e = OTHER_OUTPUTS[k].ext;
        size_t n = strlen(e);
        if (!strncmp(arg, e, n) && arg[n] == ':' && arg[n + 1]) {
            snprintf(t->format, sizeof t->format, "%s", e);
            t->path = strcmp(arg + n + 1, "-") ? arg + n + 1 : "/dev/stdout";
            return true;
        }
        if (!strcmp(cli_extension(arg), e)) {
            snprintf(t->format, sizeof t->format, "%s", e);
            t->path = arg;
            return true;
        }
    }
    cli_output_target tt;
    if (!cli_output_target_parse(arg, &tt))
        return false;
    snprintf(t->format, sizeof t->format, "%s", tt.format);
    t->path = tt.path;
    return true;
}

static bool is_scene_format(const char *f)
{
    return strcmp(f, "str") && strcmp(f, "json") && strcmp(f, "mtg") && strcmp(f, "segments") &&
           strcmp(f, "motion") && strcmp(f, "sway");
}

static void usage(const cli_opts *t)
{
    printf("usage: cambium run MODEL.l [SIDE FILES...] [-n STEPS] [-D NAME=VALUE]... [--seed N]\n"
           "                  [-o OUT]... [--every K] [--homomorphism] [--float32]\n"
           "                  [--timing] [limits] [output options]\n\n"
           "Derives an L-system (cpfg or L+C dialect), interprets it with the turtle and\n"
           "writes the outputs. Without -o prints a one-line summary.\n");
    cli_options_help(stdout, t);
}

/* The help of -o: the formats, one a line. */
static const char *output_help(void)
{
    static char text[2048];
    if (*text)
        return text;
    size_t n =
        (size_t)snprintf(text, sizeof text, "output by extension, or FORMAT:PATH (- for stdout):");
    for (size_t i = 0; i < sizeof OTHER_OUTPUTS / sizeof OTHER_OUTPUTS[0] && n < sizeof text; i++)
        n += (size_t)snprintf(text + n, sizeof text - n, "\n  .%-5s %s", OTHER_OUTPUTS[i].ext,
                              OTHER_OUTPUTS[i].what);
    for (size_t i = 0; i < sizeof SCENE_OUTPUTS / sizeof SCENE_OUTPUTS[0] && n < sizeof text; i++)
        n += (size_t)snprintf(text + n, sizeof text - n, "\n  .%-5s %s", SCENE_OUTPUTS[i].ext,
                              SCENE_OUTPUTS[i].what);
    return text;
}

/* What the command line asks: the model, its side files and defines, the outputs. */
typedef struct run_args {
    const char *model;
    const char *sides[256];
    size_t nside;
    const char *defines[256];
    size_t ndefines;
    target targets[MAX_OUTPUTS];
    int ntargets;
} run_args;

/* A word that is not an option: the model (.l), a side file, or an ignored one. */
static bool parse_file(const char *a, void *args, char *why, size_t n)
{
    run_args *ra = args;
    if (!strcmp(a, "-"))
        snprintf(why, n, "unknown option '{value}'");
    else if (!ra->model && !strcmp(cli_extension(a), "l"))
        ra->model = a;
    else if (in_list(cli_extension(a), SIDE_KINDS, sizeof SIDE_KINDS / sizeof SIDE_KINDS[0])) {
        if (ra->nside >= 256)
            snprintf(why, n, "too many side files");
        else
            ra->sides[ra->nside++] = a;
    } else if (!in_list(cli_extension(a), IGNORED_KINDS,
                        sizeof IGNORED_KINDS / sizeof IGNORED_KINDS[0]))
        snprintf(why, n, "'{value}': not a model (.l) or a known side file");
    return !*why;
}

static bool parse_define(const char *d, void *args, char *why, size_t n)
{
    (void)why, (void)n;
    run_args *ra = args;
    if (!*d || *d == '=' || ra->ndefines >= 256)
        return false;
    ra->defines[ra->ndefines++] = d;
    return true;
}

static bool parse_output(const char *v, void *args, char *why, size_t n)
{
    run_args *ra = args;
    if (ra->ntargets >= MAX_OUTPUTS)
        snprintf(why, n, "too many outputs");
    else if (!parse_target(v, &ra->targets[ra->ntargets]))
        snprintf(why, n,
                 "no writer for '{value}' (.str .json .mtg .obj .ply .glb .png .svg .csv, "
                 "segments:PATH, or FORMAT:PATH)");
    else
        ra->ntargets++;
    return !*why;
}

/* --step-time: seconds of model time per derivation step, > 0. */
static bool parse_step_time(const char *v, void *seconds, char *why, size_t n)
{
    double *t = seconds;
    char *end = NULL;
    *t = strtod(v, &end);
    if (end == v || *end || !(*t > 0) || !(*t < 1e6))
        snprintf(why, n, "--step-time expects seconds > 0");
    return !*why;
}

/* NAME.EXT -> NAME.0003.EXT */
static char *step_path(const char *path, int step)
{
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash))
        dot = path + strlen(path);
    size_t n = strlen(path) + 16;
    char *p = malloc(n);
    if (p)
        snprintf(p, n, "%.*s.%04d%s", (int)(dot - path), path, step, dot);
    return p;
}

typedef struct run {
    cbm_context *ctx;
    cbm_model *model;
    cbm_lsys *ls;
    cbm_write_options wopt;
    bool homomorphism;
    target *targets;
    int ntargets;
    bool need_scene, need_json;
    cbm_scene *scene; /* the scene of the current step, when a scene output asks */
    /* pictures beside mesh outputs: the same step in line mode when it has pixel lines */
    bool want_lines;
    cbm_scene *line_scene;
    bool line_scene_valid;
    cbm_json *json;
    int interpreted_step; /* step whose interpretation the scene holds, -1: none */
    size_t prims;         /* primitives of the last interpretation (with json) */
    cbm_vec3 lo, hi;      /* its box */
    bool has_box;
    double t_start, t_derive, t_interpret, t_write;
    double step_time; /* s of model time per derivation step (motion: outputs) */
} run;

/* Interprets the current string: fills its query modules, draws the scene if one is needed,
 * and keeps the box (and the primitive count when the json summary asks). */
static cbm_status interpret(run *r, int step)
{
    if (r->interpreted_step == step)
        return CBM_OK;
    double t0 = cli_seconds();
    if (r->scene)
        cbm_scene_clear(r->scene);
    cbm_turtle *t = NULL;
    cbm_status s = cbm_model_interpret(r->model, r->scene, r->need_json, &t);
    if (s != CBM_OK)
        return s;
    r->prims = cbm_turtle_prim_count(t);
    r->has_box = cbm_turtle_box(t, &r->lo, &r->hi);
    /* the scene and its writers hold single-precision coordinates: a drawing beyond float's
     * range (F(1e39)) would write inf vertices and a glTF with null bounds */
    double far = 0;
    if (r->has_box) {
        const double c[6] = {r->lo.x, r->lo.y, r->lo.z, r->hi.x, r->hi.y, r->hi.z};
        for (int q = 0; q < 6; q++)
            far = isfinite(c[q]) && fabs(c[q]) <= far ? far
                  : isfinite(c[q])                    ? fabs(c[q])
                                                      : INFINITY;
    }
    if (far > FLT_MAX) {
        cbm_turtle_destroy(t);
        fprintf(stderr,
                "cambium: step %d: the turtle drew beyond single precision (a coordinate of %g "
                "m; the outputs store floats)\n",
                step, far);
        return CBM_E_NONFINITE;
    }
    size_t pixel = cbm_turtle_pixel_segments(t);
    cbm_turtle_destroy(t);
    /* pictures beside meshes: a second pass in line mode when the step has pixel lines (the
     * meshes keep the tubes of the first) */
    r->line_scene_valid = false;
    if (r->want_lines && pixel > 0) {
        if (!r->line_scene) {
            if ((s = cbm_scene_create(r->ctx, &r->line_scene)) != CBM_OK)
                return s;
            cbm_scene_set_line_mode(r->line_scene, true);
        }
        cbm_scene_clear(r->line_scene);
        if ((s = cbm_model_interpret(r->model, r->line_scene, false, NULL)) != CBM_OK)
            return s;
        r->line_scene_valid = true;
    } else if (r->line_scene) {
        /* no lines in this step: release the previous step's */
        cbm_scene_destroy(r->line_scene);
        r->line_scene = NULL;
    }
    r->interpreted_step = step;
    r->t_interpret += cli_seconds() - t0;
    return CBM_OK;
}

static void json_step(run *r, int step)
{
    cbm_json *j = r->json;
    cbm_json_begin_object(j, NULL);
    cbm_json_int(j, "step", step);
    cbm_json_int(j, "modules", (int64_t)cbm_lsys_module_count(r->ls));
    cbm_json_int(j, "parameters", (int64_t)cbm_lsys_param_count(r->ls));
    cbm_json_int(j, "primitives", (int64_t)r->prims);
    if (r->has_box) {
        cbm_json_begin_object(j, "box");
        cbm_json_begin_array(j, "min");
        cbm_json_number(j, NULL, r->lo.x);
        cbm_json_number(j, NULL, r->lo.y);
        cbm_json_number(j, NULL, r->lo.z);
        cbm_json_end_array(j);
        cbm_json_begin_array(j, "max");
        cbm_json_number(j, NULL, r->hi.x);
        cbm_json_number(j, NULL, r->hi.y);
        cbm_json_number(j, NULL, r->hi.z);
        cbm_json_end_array(j);
        cbm_json_end_object(j);
    } else {
        cbm_json_null(j, "box");
    }
    cbm_json_number(j, "seconds", cli_seconds() - r->t_start);
    cbm_json_end_object(j);
}

static cbm_status write_str(run *r, const char *path)
{
    cbm_status s = r->homomorphism ? cbm_lsys_apply_homomorphism(r->ls) : CBM_OK;
    cbm_out *out = NULL;
    if (s == CBM_OK)
        s = cbm_out_open(r->ctx, path, &out);
    if (s != CBM_OK)
        return s;
    s = cbm_lsys_write_str(r->ls, r->homomorphism, out);
    if (s == CBM_OK)
        return cbm_out_commit(out);
    cbm_out_abort(out);
    return s;
}

static bool is_plant_format(const char *f)
{
    return !strcmp(f, "mtg") || !strcmp(f, "segments");
}

/* The mechanical segments of the string, at their stored state, as an MTG or a CSV table; for a
 * model without mechanics, the segments the turtle draws (a pass with the record on). */
static cbm_status write_plant(run *r, const char *path, const char *format)
{
    if (!cbm_lsys_has_mechanics(r->ls)) {
        cbm_turtle *t = NULL;
        cbm_status s = cbm_model_interpret(r->model, NULL, true, &t);
        if (s == CBM_OK)
            s = !strcmp(format, "mtg") ? cbm_write_turtle_mtg(r->ctx, t, path)
                                       : cbm_write_turtle_segments_csv(r->ctx, t, path);
        cbm_turtle_destroy(t);
        return s;
    }
    cbm_plant *pl = NULL;
    cbm_status s = cbm_lsys_mech_plant(r->ls, &pl);
    if (s == CBM_OK)
        s = !strcmp(format, "mtg") ? cbm_write_mtg(r->ctx, pl, path)
                                   : cbm_write_segments_csv(r->ctx, pl, path);
    cbm_plant_destroy(pl);
    return s;
}

/* cli_fail, with the memory limit named when memory ran out under it. */
static int run_fail(const run *r, cbm_status s, const char *what)
{
    int rc = cli_fail(r->ctx, s, what);
    size_t limit = cbm_context_limits(r->ctx)->max_bytes;
    if (s == CBM_E_NOMEM && limit)
        fprintf(stderr, "cambium: the memory limit is %zu MB (--max-memory MB changes it)\n",
                limit >> 20);
    return rc;
}

/* Whether the outputs need the turtle pass over the current string. Only the string (.str)
 * asked: no pass when it could not change the string or print anything: no query module for the
 * turtle to fill (cpfg's ?P ?H ?L ?U) and no homomorphism or interpretation rules, whose code may
 * print. The summary line without -o prints the box, a pass. (For the 8-step Koch curve the pass
 * was a third of a string-only run.) */
static bool needs_interpretation(const run *r)
{
    if (r->need_scene || r->json || r->ntargets == 0)
        return true;
    for (int k = 0; k < r->ntargets; k++)
        if (strcmp(r->targets[k].format, "str"))
            return true;
    return cbm_model_has_queries(r->model) || cbm_lsys_has_homomorphism(r->ls);
}

/* What write_outputs writes after a step. */
enum { ROW = 0, NUMBERED = 1, FINAL = 2 };

/* After step `done`: ROW adds the json row; NUMBERED also writes NAME.STEP.EXT files and adds
 * animation frames; FINAL writes the final files (the animations, the json document). */
static int write_outputs(run *r, int what, int done)
{
    cbm_status s = needs_interpretation(r) ? interpret(r, done) : CBM_OK;
    if (s != CBM_OK)
        return run_fail(r, s, "interpretation");
    double t0 = cli_seconds();
    if (what != FINAL && r->json)
        json_step(r, done);
    int rc = CLI_OK;
    for (int i = 0; i < r->ntargets && rc == CLI_OK && what != ROW; i++) {
        target *t = &r->targets[i];
        if (!strcmp(t->format, "json")) {
            if (what == FINAL && (s = cbm_json_write_file(r->json, t->path)) != CBM_OK)
                rc = run_fail(r, s, t->arg);
            continue;
        }
        if (!strcmp(t->format, "sway")) /* recorded by the Sway() observer, written after */
            continue;
        if (t->motion) { /* frames are recorded by record_motion; written at the end */
            if (what == FINAL) {
                s = !strcmp(cli_extension(t->path), "glb")
                        ? cbm_turtle_motion_write_glb(t->motion, t->path)
                        : cbm_turtle_motion_write_csv(t->motion, t->path);
                if (s != CBM_OK)
                    rc = run_fail(r, s, t->arg);
            }
            continue;
        }
        if (t->anim) {
            s = what == NUMBERED ? cbm_animation_add_frame(t->anim, r->scene)
                                 : cbm_animation_write(t->anim, t->path);
            if (s != CBM_OK)
                rc = run_fail(r, s, t->arg);
            continue;
        }
        char *numbered = what == NUMBERED ? step_path(t->path, done) : NULL;
        if (what == NUMBERED && !numbered)
            return run_fail(r, CBM_E_NOMEM, "output");
        const char *path = numbered ? numbered : t->path;
        if (!strcmp(t->format, "str"))
            s = write_str(r, path);
        else if (is_plant_format(t->format))
            s = write_plant(r, path, t->format);
        else {
            bool picture = !strcmp(t->format, "png") || !strcmp(t->format, "svg");
            const cbm_scene *sc = picture && r->line_scene_valid ? r->line_scene : r->scene;
            s = cbm_scene_write_as(r->ctx, sc, path, t->format, &r->wopt);
        }
        if (s != CBM_OK)
            rc = run_fail(r, s, path);
        free(numbered);
    }
    r->t_write += cli_seconds() - t0;
    return rc;
}

/* A frame of every motion: output after step `done`: the turtle's record of the current string
 * (the first frame also draws a scene, for the parts' colours). */
static int record_motion(run *r, int done, bool *any)
{
    bool first = true, want = false;
    for (int i = 0; i < r->ntargets; i++)
        if (r->targets[i].motion) {
            want = true;
            first = cbm_turtle_motion_frame_count(r->targets[i].motion) == 0;
        }
    if (!want)
        return CLI_OK;
    *any = true;
    double t0 = cli_seconds();
    cbm_scene *sc = NULL;
    cbm_turtle *t = NULL;
    cbm_status s = first ? cbm_scene_create(r->ctx, &sc) : CBM_OK;
    if (s == CBM_OK)
        s = cbm_model_interpret(r->model, sc, true, &t);
    for (int i = 0; i < r->ntargets && s == CBM_OK; i++)
        if (r->targets[i].motion)
            s = cbm_turtle_motion_add_frame(r->targets[i].motion, t, sc, done * r->step_time, done);
    cbm_turtle_destroy(t);
    cbm_scene_destroy(sc);
    r->t_interpret += cli_seconds() - t0;
    return s == CBM_OK ? CLI_OK : run_fail(r, s, "motion");
}

/* --timing: the phases on stderr. For a model with mechanics (L+C Equilibrium(), AddRings(), ...)
 * the derivation is split into the mechanics operations and the rest. */
static void print_timing(const run *r)
{
    cbm_lsys_mech_timing mt = cbm_lsys_mech_time(r->ls);
    double mech = mt.equilibrium + mt.rings + mt.other;
    if (mt.operations == 0) {
        fprintf(stderr, "run: derive %.4f s, ", r->t_derive);
    } else {
        fprintf(stderr,
                "run: derive %.4f s (rewriting %.4f s, equilibrium %.4f s of which solver %.4f s "
                "in %zu passes, rings and ageing %.4f s, other mechanics %.4f s; %zu mechanics "
                "operations, %zu on a kept plant), ",
                r->t_derive, r->t_derive - mech, mt.equilibrium, mt.solve, mt.passes, mt.rings,
                mt.other, mt.operations, mt.kept);
    }
    fprintf(stderr, "interpret %.4f s, write %.4f s, total %.4f s; peak %.1f MB in the library\n",
            r->t_interpret, r->t_write, cli_seconds() - r->t_start,
            (double)cbm_context_peak_bytes(r->ctx) / 1e6);
    cli_print_solve_stages("run", r->ctx);
}

/* Closes the json document (its rows are complete). */
static void json_end(run *r)
{
    if (!r->json)
        return;
    cbm_json_end_array(r->json);
    cbm_json_number(r->json, "seconds", cli_seconds() - r->t_start);
    cbm_json_end_object(r->json);
}

/* `cambium run fruit-tree` and `cambium run X.tree` run a built-in tree model: the same job as
 * `cambium grow`, under the command DESIGN.md names for every model. The model is the first word
 * of the line that is not an option of run's table nor its value. */
static bool names_tree_model(cli_opts *t, int argc, char **argv)
{
    int i = cli_options_next_word(t, argc, argv, 1);
    if (i >= argc)
        return false;
    const char *a = argv[i];
    size_t n = strlen(a);
    if (n > 5 && !strcmp(a + n - 5, ".tree"))
        return true;
    if (strchr(a, '.') || strchr(a, '/'))
        return false;
    cbm_context *ctx = cli_context();
    cbm_tree_def def;
    bool builtin = cbm_tree_def_builtin(ctx, a, &def) == CBM_OK;
    cli_context_end(ctx);
    return builtin;
}

/* The L+C model's functions as native code, cached in $XDG_CACHE_HOME/cambium (or
 * ~/.cache/cambium): a model whose functions compute then runs as fast as compiled C. Without
 * a compiler or a cache directory the register code runs them, with the same results. */
static void native_code(cbm_lsys *ls, bool timing)
{
    const char *xdg = getenv("XDG_CACHE_HOME"), *home = getenv("HOME");
    char dir[4096];
    int n = -1;
    if (xdg && xdg[0] == '/')
        n = snprintf(dir, sizeof dir, "%s/cambium", xdg);
    else if (home && home[0] == '/')
        n = snprintf(dir, sizeof dir, "%s/.cache/cambium", home);
    const char *why = "no cache directory ($XDG_CACHE_HOME and $HOME unset)";
    bool ok = n > 0 && (size_t)n < sizeof dir && cbm_lsys_compile_native(ls, dir, &why);
    if (timing)
        fprintf(stderr, "native code: %s\n", ok ? "yes" : why ? why : "no");
}

int cmd_run(int argc, char **argv)
{
    run_args ra = {0};
    long steps = -1, every = 0, seed = -1, motion_every = 1;
    double step_time = 0.04;
    bool float32 = false, timing = false, homomorphism = false, no_print = false;
    bool no_native = false;
    bool glb_mesh = false;
    cbm_write_options wopt = cbm_write_options_default();
    const char *count = "{opt} expects a non-negative integer up to 10^8";
    cli_opt rows[] = {
        {.name = "--help|-h", .kind = CLI_HELP},
        {.name = "MODEL.l", .kind = CLI_POSITIONAL, .target = &ra, .parse = parse_file},
        {.name = "SIDE FILES",
         .kind = CLI_DOC,
         .help = "by extension: .v view file, .func/.fset functions, .s surface,\n"
                 ".con contour, .map colour map, .mat materials (.a .e .txt are\n"
                 "accepted and ignored)"},
        {.name = "-n",
         .kind = CLI_LONG,
         .target = &steps,
         .min = 0,
         .max = 100000000,
         .bad = count,
         .arg = "STEPS",
         .help = "derivation steps (default: the model's derivation length)"},
        {.name = "-D",
         .kind = CLI_CUSTOM,
         .target = &ra,
         .parse = parse_define,
         .attached = true,
         .bad = "-D expects NAME=VALUE",
         .arg = "NAME=VALUE",
         .help = "overrides the model's #define NAME"},
        {.name = "--seed",
         .kind = CLI_LONG,
         .target = &seed,
         .min = 0,
         .max = LONG_MAX,
         .bad = "{opt} expects a non-negative integer",
         .arg = "N",
         .help = "seed of stochastic production choice (srand48(N))"},
        {.name = "-o",
         .kind = CLI_CUSTOM,
         .target = &ra,
         .parse = parse_output,
         .bad = "-o expects a file name",
         .arg = "OUT",
         .help = output_help()},
        {.name = "--every",
         .kind = CLI_LONG,
         .target = &every,
         .min = 0,
         .max = 100000000,
         .bad = count,
         .arg = "K",
         .help = "also write the outputs after step 0 and every K-th step as\n"
                 "NAME.STEP.EXT (NAME.0003.png); a .glb becomes one animation\n"
                 "with a frame per K steps"},
        {.name = "--motion-every",
         .kind = CLI_LONG,
         .target = &motion_every,
         .min = 1,
         .max = 100000000,
         .bad = "--motion-every expects an integer 1..10^8",
         .arg = "K",
         .help = "motion: outputs record a frame after step 0, every K-th step\n"
                 "(default 1) and the last step"},
        {.name = "--step-time",
         .kind = CLI_CUSTOM,
         .target = &step_time,
         .parse = parse_step_time,
         .bad = "--step-time expects seconds > 0",
         .arg = "S",
         .help = "model time of one derivation step in motion: outputs, s\n"
                 "(default 0.04)"},
        {.name = "--homomorphism",
         .kind = CLI_SET,
         .target = &homomorphism,
         .help = "write the string after the homomorphism"},
        {.name = "--float32",
         .kind = CLI_SET,
         .target = &float32,
         .help = "follow cpfg exactly: float32 parameters, seed: ignored as in\n"
                 "cpfg's batch mode"},
        {.name = "--timing",
         .kind = CLI_SET,
         .target = &timing,
         .help = "print the time and memory of each phase to stderr"},
        {.name = "--no-print",
         .kind = CLI_SET,
         .target = &no_print,
         .help = "discard what the model prints (printf); it goes to stdout,\n"
                 "or to stderr when an output is written to stdout"},
        {.name = "--no-native",
         .kind = CLI_SET,
         .target = &no_native,
         .help = "run the L+C functions in the register code, not as native code\n"
                 "compiled with cc (cached in $XDG_CACHE_HOME/cambium)"},
        {.name = "--glb-mesh",
         .kind = CLI_SET,
         .target = &glb_mesh,
         .help = ".glb: every segment's tube as triangles with per-vertex colours,\n"
                 "not as an instance of one cylinder (EXT_mesh_gpu_instancing)"},
        {.kind = CLI_GROUP, .target = cli_limit_options()},
        {.kind = CLI_GROUP, .target = cli_output_options(&wopt)},
        {0}};
    cli_opts table = {.cmd = "run",
                      .opts = rows,
                      .help = usage,
                      .width = 18,
                      .unknown = "unknown option '{opt}'"};
    if (names_tree_model(&table, argc, argv))
        return cmd_grow(argc, argv);
    int prc = cli_options_parse(&table, argc, argv);
    if (prc != CLI_OK)
        return prc == CLI_HELP_SHOWN ? CLI_OK : prc;
    const char *model = ra.model;
    const char **defines = ra.defines, **sides = ra.sides;
    size_t ndefines = ra.ndefines, nside = ra.nside;
    target *targets = ra.targets;
    int ntargets = ra.ntargets;
    if (!model)
        return cli_usage_error("run", "expected a MODEL.l");
    {
        const char *paths[MAX_OUTPUTS];
        for (int k = 0; k < ntargets; k++)
            paths[k] = targets[k].path;
        if (cli_check_outputs(paths, ntargets) != CLI_OK)
            return CLI_FAIL;
    }
    for (int k = 0; k < ntargets; k++)
        if (!strcmp(targets[k].format, "motion") && strcmp(cli_extension(targets[k].path), "csv") &&
            strcmp(cli_extension(targets[k].path), "glb"))
            return cli_usage_error("run", "%s: a motion is written as .csv or .glb",
                                   targets[k].arg);
    cli_run_sway sway = {0};
    for (int k = 0; k < ntargets; k++) {
        if (strcmp(targets[k].format, "sway"))
            continue;
        bool glb = !strcmp(cli_extension(targets[k].path), "glb");
        if (!glb && strcmp(cli_extension(targets[k].path), "csv"))
            return cli_usage_error("run", "%s: a sway is written as .csv or .glb", targets[k].arg);
        if ((glb ? sway.nglb : sway.ncsv) == 8)
            return cli_usage_error("run", "at most 8 sway: outputs of each kind");
        if (glb)
            sway.glb[sway.nglb++] = targets[k].path;
        else
            sway.csv[sway.ncsv++] = targets[k].path;
    }
    for (int k = 0; k < ntargets; k++)
        if (every > 0 && !strcmp(targets[k].path, "/dev/stdout") &&
            strcmp(targets[k].format, "glb") && strcmp(targets[k].format, "json"))
            return cli_usage_error("run", "--every writes numbered files: %s cannot be stdout",
                                   targets[k].arg);

    cli_set_model_output(stdout);
    for (int k = 0; k < ntargets; k++)
        if (!strcmp(targets[k].path, "/dev/stdout"))
            cli_set_model_output(stderr);
    if (no_print)
        cli_set_model_output(NULL);
    /* the limits of the command line (a run that would exhaust the machine stops with a
     * message: the strings, the scene and the writers' buffers count) */
    cbm_context *ctx = cli_context();
    run r = {0};
    r.ctx = ctx;
    r.wopt = wopt;
    r.homomorphism = homomorphism;
    r.targets = targets;
    r.ntargets = ntargets;
    r.interpreted_step = -1;
    r.t_start = cli_seconds();
    r.step_time = step_time;
    cbm_model_def def = {cbm_lsys_def_default(), sides, nside};
    def.lsys.path = model;
    def.lsys.defines = defines;
    def.lsys.define_count = ndefines;
    def.lsys.float32 = float32;
    def.lsys.ignore_seed = float32;
    def.lsys.seed = seed;
    int rc = CLI_OK;
    cbm_status s = cbm_model_load(ctx, &def, &r.model);
    if (s != CBM_OK) {
        rc = cli_fail(ctx, s, model);
        goto done;
    }
    r.ls = cbm_model_lsys(r.model);
    if (!no_native)
        native_code(r.ls, timing);
    sway.ctx = ctx;
    if (sway.nglb + sway.ncsv > 0) {
        if (!cbm_lsys_has_mechanics(r.ls)) {
            fprintf(stderr,
                    "cambium run: %s: sway: outputs need an L+C model with mechanics "
                    "that calls Sway()\n",
                    model);
            rc = CLI_FAIL;
            goto done;
        }
        cbm_lsys_set_sway_observer(r.ls, cli_run_sway_observe, &sway);
    }
    for (int k = 0; k < ntargets; k++) {
        r.need_scene |= is_scene_format(targets[k].format);
        r.need_json |= !strcmp(targets[k].format, "json");
    }
    /* pixel lines stay lines (32 bytes each, rasterised) when every scene output is a picture;
     * with a mesh output too, the scene has tubes for the meshes and the pictures get a second
     * scene in line mode (interpret) */
    bool pictures = false, meshes = false;
    for (int k = 0; k < ntargets; k++) {
        if (!is_scene_format(targets[k].format))
            continue;
        if (!strcmp(targets[k].format, "png") || !strcmp(targets[k].format, "svg"))
            pictures = true;
        else
            meshes = true;
    }
    r.want_lines = pictures && meshes;
    if (r.need_scene)
        s = cbm_scene_create(ctx, &r.scene);
    if (s == CBM_OK && pictures && !meshes)
        cbm_scene_set_line_mode(r.scene, true);
    /* straight tubes as instances of one cylinder when every scene output is a .glb */
    bool glb_only = meshes && !pictures && !glb_mesh;
    for (int k = 0; k < ntargets; k++)
        glb_only &= !is_scene_format(targets[k].format) || !strcmp(targets[k].format, "glb");
    if (s == CBM_OK && glb_only)
        cbm_scene_set_instancing(r.scene, true);
    if (s == CBM_OK && r.need_json)
        s = cbm_json_create(ctx, &r.json);
    for (int k = 0; k < ntargets && s == CBM_OK && every > 0; k++)
        if (!strcmp(targets[k].format, "glb"))
            s = cbm_animation_create(ctx, &wopt, &targets[k].anim);
    for (int k = 0; k < ntargets && s == CBM_OK; k++)
        if (!strcmp(targets[k].format, "motion"))
            s = cbm_turtle_motion_create(ctx, &targets[k].motion);
    if (s != CBM_OK) {
        rc = cli_fail(ctx, s, "output");
        goto done;
    }
    if (r.json) {
        cbm_json_begin_object(r.json, NULL);
        cbm_json_string(r.json, "model", model);
        cbm_json_bool(r.json, "float32", float32);
        if (seed >= 0)
            cbm_json_int(r.json, "seed", seed);
        cbm_json_begin_array(r.json, "steps");
    }

    int n = steps >= 0 ? (int)steps : cbm_lsys_derivation_length(r.ls);
    /* rows of the json summary and numbered outputs: step 0 and every K-th step (K = 1 for the
     * json rows without --every), and the last step */
    long row_every = every > 0 ? every : 1;
    double t_reset = cli_seconds();
    s = cbm_model_reset(r.model); /* the Start block (and its mechanics) count as derivation */
    r.t_derive += cli_seconds() - t_reset;
    if (s == CBM_OK && (every > 0 || r.json))
        rc = write_outputs(&r, every > 0 ? NUMBERED : ROW, 0);
    bool motion = false;
    if (s == CBM_OK && rc == CLI_OK)
        rc = record_motion(&r, 0, &motion);
    int done = 0, last_row = 0, last_motion = 0;
    cli_progress pr;
    cli_progress_begin(&pr);
    while (s == CBM_OK && rc == CLI_OK && done < n && !cbm_lsys_stopped(r.ls)) {
        double t0 = cli_seconds();
        s = cbm_model_step(r.model);
        r.t_derive += cli_seconds() - t0;
        if (s != CBM_OK)
            break;
        done++;
        cbm_progress state = {(size_t)done, (size_t)n, cbm_lsys_module_count(r.ls), 0, 0};
        cli_progress_update(&pr, &state);
        if ((every > 0 || r.json) && done % row_every == 0) {
            last_row = done;
            rc = write_outputs(&r, every > 0 ? NUMBERED : ROW, done);
        }
        if (motion && rc == CLI_OK && done % motion_every == 0) {
            last_motion = done;
            rc = record_motion(&r, done, &motion);
        }
    }
    cli_progress_end(&pr);
    if (s != CBM_OK) {
        rc = cli_fail(ctx, s, model);
        if (s != CBM_E_LIMIT || ntargets == 0)
            goto done;
        fprintf(stderr, "cambium: writing the outputs of step %d, the last complete one\n", done);
    } else if (rc != CLI_OK) {
        goto done;
    }
    /* the last step ends the json rows and the animations even off the K grid */
    int final_rc = CLI_OK;
    if (last_row != done && (r.json || every > 0)) {
        final_rc = write_outputs(&r, ROW, done);
        for (int k = 0; k < ntargets && final_rc == CLI_OK; k++)
            if (targets[k].anim) {
                cbm_status fs = cbm_animation_add_frame(targets[k].anim, r.scene);
                if (fs != CBM_OK)
                    final_rc = cli_fail(ctx, fs, targets[k].arg);
            }
    }
    if (final_rc == CLI_OK && motion && last_motion != done)
        final_rc = record_motion(&r, done, &motion);
    json_end(&r);
    if (final_rc == CLI_OK)
        final_rc = write_outputs(&r, FINAL, done);
    if (final_rc == CLI_OK && sway.nglb + sway.ncsv > 0) {
        if (!sway.rec) {
            fprintf(stderr, "cambium run: %s: sway: outputs asked but the model called no Sway()\n",
                    model);
            final_rc = CLI_FAIL;
        } else {
            cbm_status ss = cli_sway_rec_finish(sway.rec, CBM_OK);
            sway.rec = NULL;
            if (ss != CBM_OK)
                final_rc = cli_fail(ctx, ss, "sway");
        }
    }
    if (rc == CLI_OK)
        rc = final_rc;
    if (rc == CLI_OK && ntargets == 0) {
        printf("%s: %d steps, %zu modules, %zu parameters", model, done,
               cbm_lsys_module_count(r.ls), cbm_lsys_param_count(r.ls));
        if (r.has_box)
            printf(", box %.4g..%.4g x %.4g..%.4g x %.4g..%.4g", r.lo.x, r.hi.x, r.lo.y, r.hi.y,
                   r.lo.z, r.hi.z);
        printf(", %zu side file%s, %.3f s\n", nside, nside == 1 ? "" : "s",
               cli_seconds() - r.t_start);
    }
    if (timing)
        print_timing(&r);
done:
    cli_sway_rec_discard(sway.rec);
    for (int k = 0; k < ntargets; k++) {
        cbm_animation_destroy(targets[k].anim);
        cbm_turtle_motion_destroy(targets[k].motion);
    }
    cbm_json_destroy(r.json);
    cbm_scene_destroy(r.scene);
    cbm_scene_destroy(r.line_scene);
    cbm_model_destroy(r.model);
    cli_context_end(ctx);
    return rc;
}
