/* The output options of the tool (picture size, view, background, colouring, ground, legend,
 * lighting, threads) as a table of options.h, the output targets and the progress line, shared by
 * every command that writes scenes. */
#define _POSIX_C_SOURCE 200809L
#include "cli_output.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <time.h>
#include <unistd.h>

static bool parse_color(const char *s, float rgba[4])
{
    static const struct {
        const char *name;
        float c[4];
    } named[] = {{"white", {1, 1, 1, 1}},
                 {"black", {0, 0, 0, 1}},
                 {"grey", {0.2f, 0.2f, 0.2f, 1}},
                 {"gray", {0.2f, 0.2f, 0.2f, 1}},
                 {"transparent", {1, 1, 1, 0}}};
    for (size_t k = 0; k < sizeof named / sizeof named[0]; k++)
        if (!strcmp(s, named[k].name)) {
            memcpy(rgba, named[k].c, sizeof named[k].c);
            return true;
        }
    if (s[0] != '#' || strlen(s) != 7)
        return false;
    for (int k = 0; k < 3; k++) {
        char h[3] = {s[1 + 2 * k], s[2 + 2 * k], 0}, *end;
        long v = strtol(h, &end, 16);
        if (*end)
            return false;
        double c = v / 255.0; /* sRGB -> linear */
        rgba[k] = (float)(c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4));
    }
    rgba[3] = 1;
    return true;
}

/* The value parsers of the output options (target: the cbm_write_options). */

static bool parse_size(const char *v, void *target, char *why, size_t n)
{
    (void)why, (void)n;
    cbm_write_options *o = target;
    char *end;
    long w = strtol(v, &end, 10), h = w;
    if (*end == 'x')
        h = strtol(end + 1, &end, 10);
    if (*end || w < 16 || h < 16 || w > 16384 || h > 16384)
        return false;
    o->width = (int)w;
    o->height = (int)h;
    return true;
}

static bool parse_view(const char *v, void *target, char *why, size_t n)
{
    (void)why, (void)n;
    cbm_write_options *o = target;
    static const char *const names[] = {"front", "side", "top", "iso"};
    for (int k = 0; k < 4; k++)
        if (!strcmp(v, names[k])) {
            o->view = (cbm_camera_view)k;
            return true;
        }
    double x, y, z;
    char tail;
    if (sscanf(v, "%lf,%lf,%lf%c", &x, &y, &z, &tail) != 3 || !isfinite(x) || !isfinite(y) ||
        !isfinite(z) || (x == 0 && y == 0 && z == 0))
        return false;
    o->view = CBM_VIEW_VECTOR;
    o->view_dir = (cbm_vec3){x, y, z};
    return true;
}

static bool parse_background(const char *v, void *target, char *why, size_t n)
{
    (void)why, (void)n;
    cbm_write_options *o = target;
    return parse_color(v, o->background);
}

static bool parse_color_by(const char *v, void *target, char *why, size_t n)
{
    (void)why, (void)n;
    cbm_write_options *o = target;
    static const char *const names[] = {"material", "stress",     "age",  "reaction",
                                        "order",    "stress-mpa", "light"};
    for (int k = 0; k < (int)(sizeof names / sizeof names[0]); k++)
        if (!strcmp(v, names[k])) {
            o->color_by = (cbm_color_by)k;
            return true;
        }
    return false;
}

static bool parse_range(const char *v, void *target, char *why, size_t n)
{
    (void)why, (void)n;
    cbm_write_options *o = target;
    double lo, hi;
    char tail;
    if (sscanf(v, "%lf:%lf%c", &lo, &hi, &tail) != 2 || !isfinite(lo) || !isfinite(hi) ||
        !(hi > lo))
        return false;
    o->range_min = lo;
    o->range_max = hi;
    return true;
}

cli_opts *cli_output_options(cbm_write_options *o)
{
    static cli_opt rows[14];
    static cli_opts table = {
        .title = "output options (pictures: .png .svg; colours apply to every format):",
        .opts = rows,
        .width = 20,
        .missing = "{opt} needs a value"};
    const char *bad = "bad value '{value}' for {opt}";
    cli_opt r[] = {
        {.name = "--size",
         .kind = CLI_CUSTOM,
         .target = o,
         .parse = parse_size,
         .bad = bad,
         .arg = "W[xH]",
         .help = "picture size in pixels (default 800x800)"},
        {.name = "--view",
         .kind = CLI_CUSTOM,
         .target = o,
         .parse = parse_view,
         .bad = bad,
         .arg = "V",
         .help = "front | side | top | iso | X,Y,Z (direction looked along; default iso)"},
        {.name = "--background",
         .kind = CLI_CUSTOM,
         .target = o,
         .parse = parse_background,
         .bad = bad,
         .arg = "C",
         .help = "white | black | grey | transparent | #rrggbb (default white)"},
        {.name = "--color-by",
         .kind = CLI_CUSTOM,
         .target = o,
         .parse = parse_color_by,
         .bad = bad,
         .arg = "M",
         .help = "material | stress (/ MOR) | stress-mpa | age | reaction |\n"
                 "order | light (leaves; grow) (default material)"},
        {.name = "--range",
         .kind = CLI_CUSTOM,
         .target = o,
         .parse = parse_range,
         .bad = bad,
         .arg = "LO:HI",
         .help = "colour-bar range of the quantity (default: 0:1, or from the data)"},
        {.name = "--no-ground",
         .kind = CLI_CLEAR,
         .target = &o->ground,
         .help = "drop the ground (and do not add one under the plant in PNGs)"},
        {.name = "--no-legend", .kind = CLI_CLEAR, .target = &o->legend, .help = "no colour bar"},
        {.name = "--no-shadows",
         .kind = CLI_CLEAR,
         .target = &o->shadows,
         .help = "no sun shadows (PNG)"},
        {.name = "--ao",
         .kind = CLI_INT,
         .target = &o->ao_samples,
         .min = 0,
         .max = 256,
         .bad = bad,
         .arg = "N",
         .help = "ambient-occlusion rays per pixel, 0..256 (PNG; default 16)"},
        {.name = "--supersample",
         .kind = CLI_INT,
         .target = &o->supersample,
         .min = 1,
         .max = 4,
         .bad = bad,
         .arg = "N",
         .help = "N x N samples per pixel, 1..4 (PNG; default 2)"},
        {.name = "--threads",
         .kind = CLI_INT,
         .target = &o->threads,
         .min = 0,
         .max = 64,
         .bad = bad,
         .arg = "N",
         .help = "render threads (PNG; default: one per processor)"},
        {0}};
    _Static_assert(sizeof r <= sizeof rows, "rows holds the output options");
    memcpy(rows, r, sizeof r);
    return &table;
}

bool cli_output_target_parse(const char *arg, cli_output_target *out)
{
    static const char *const formats[] = {"obj", "ply", "glb", "png", "svg", "csv"};
    const char *colon = strchr(arg, ':');
    const char *fmt = NULL;
    size_t flen = 0;
    out->path = arg;
    if (colon && colon - arg >= 3 && colon - arg <= 4) {
        for (size_t k = 0; k < sizeof formats / sizeof formats[0]; k++)
            if ((size_t)(colon - arg) == strlen(formats[k]) &&
                !strncmp(arg, formats[k], strlen(formats[k]))) {
                fmt = arg;
                flen = (size_t)(colon - arg);
                out->path = colon + 1;
            }
    }
    if (!fmt) {
        fmt = cli_extension(arg);
        flen = strlen(fmt);
    }
    if (!strcmp(out->path, "-"))
        out->path = "/dev/stdout";
    if (!*out->path || flen == 0 || flen >= sizeof out->format)
        return false;
    memcpy(out->format, fmt, flen);
    out->format[flen] = '\0';
    for (size_t k = 0; k < sizeof formats / sizeof formats[0]; k++)
        if (!strcmp(out->format, formats[k]))
            return true;
    return false;
}

double cli_seconds(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

void cli_print_solve_stages(const char *cmd, const cbm_context *ctx)
{
    size_t counts[CBM_SOLVE_STAGE_COUNT];
    cbm_solve_stage_counts(ctx, counts);
    const char *sep = ": solves by converged stage: ";
    bool any = false;
    /* the stages in pipeline order, then the relaxation solver, then the failures */
    for (int s = CBM_SOLVE_STAGE_NONE + 1; s <= CBM_SOLVE_STAGE_COUNT; s++) {
        int stage = s == CBM_SOLVE_STAGE_COUNT ? CBM_SOLVE_STAGE_NONE : s;
        if (counts[stage] == 0)
            continue;
        if (!any)
            fputs(cmd, stderr);
        fprintf(stderr, "%s%s %zu", sep,
                stage == CBM_SOLVE_STAGE_NONE ? "not converged"
                                              : cbm_solve_stage_name((cbm_solve_stage)stage),
                counts[stage]);
        sep = ", ";
        any = true;
    }
    if (any)
        fputc('\n', stderr);
}

void cli_progress_begin(cli_progress *p)
{
    const char *force = getenv("CBM_PROGRESS");
    p->on = force ? !strcmp(force, "1") : isatty(STDERR_FILENO) == 1;
    p->start = cli_seconds();
    p->last = -1;
}

void cli_progress_update(cli_progress *p, cbm_progress *state)
{
    if (!p->on)
        return;
    double now = cli_seconds();
    if (p->last >= 0 && now - p->last < 0.1 && state->step < state->steps)
        return;
    p->last = now;
    state->elapsed = now - p->start;
    int width = 80;
    struct winsize ws;
    if (ioctl(STDERR_FILENO, TIOCGWINSZ, &ws) == 0 && ws.ws_col > 20)
        width = ws.ws_col - 1;
    char line[512];
    cbm_progress_format(state, width, line, sizeof line);
    fprintf(stderr, "\r%s\033[K", line);
    fflush(stderr);
}

void cli_progress_end(cli_progress *p)
{
    if (p->on && p->last >= 0) {
        fprintf(stderr, "\r\033[K");
        fflush(stderr);
    }
}
