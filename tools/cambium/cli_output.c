/* The output options of the tool (picture size, view, background, colouring, ground, legend,
 * lighting, threads) and the progress line, shared by every command that writes scenes. */
#define _POSIX_C_SOURCE 200809L
#include "cli_output.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/ioctl.h>
#include <time.h>
#include <unistd.h>

const char cli_output_help[] =
    "output options (pictures: .png .svg; colours apply to every format):\n"
    "  --size W[xH]        picture size in pixels (default 800x800)\n"
    "  --view V            front | side | top | iso | X,Y,Z (direction looked along; default iso)\n"
    "  --background C      white | black | grey | transparent | #rrggbb (default white)\n"
    "  --color-by M        material | stress (/ MOR) | stress-mpa | age | reaction |\n"
    "                      order (default material)\n"
    "  --range LO:HI       colour-bar range of the quantity (default: 0:1, or from the data)\n"
    "  --no-ground         drop the ground (and do not add one under the plant in PNGs)\n"
    "  --no-legend         no colour bar\n"
    "  --no-shadows        no sun shadows (PNG)\n"
    "  --ao N              ambient-occlusion rays per pixel, 0..256 (PNG; default 16)\n"
    "  --supersample N     N x N samples per pixel, 1..4 (PNG; default 2)\n"
    "  --threads N         render threads (PNG; default: one per processor)\n";

static int bad(const char *cmd, const char *opt, const char *val)
{
    cli_usage_error(cmd, "bad value '%s' for %s", val ? val : "", opt);
    return -1;
}

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

int cli_output_option(const char *cmd, int argc, char **argv, int *i, cbm_write_options *o)
{
    const char *a = argv[*i];
    static const char *const with_value[] = {"--size",  "--view", "--background",  "--color-by",
                                             "--range", "--ao",   "--supersample", "--threads"};
    bool takes = false;
    for (size_t k = 0; k < sizeof with_value / sizeof with_value[0]; k++)
        takes |= !strcmp(a, with_value[k]);
    if (!takes) {
        if (!strcmp(a, "--no-ground"))
            o->ground = false;
        else if (!strcmp(a, "--no-legend"))
            o->legend = false;
        else if (!strcmp(a, "--no-shadows"))
            o->shadows = false;
        else
            return 0;
        return 1;
    }
    if (*i + 1 >= argc) {
        cli_usage_error(cmd, "%s needs a value", a);
        return -1;
    }
    const char *v = argv[++*i];
    long n;
    if (!strcmp(a, "--size")) {
        char *end;
        long w = strtol(v, &end, 10), h = w;
        if (*end == 'x')
            h = strtol(end + 1, &end, 10);
        if (*end || w < 16 || h < 16 || w > 16384 || h > 16384)
            return bad(cmd, a, v);
        o->width = (int)w;
        o->height = (int)h;
    } else if (!strcmp(a, "--view")) {
        static const char *const names[] = {"front", "side", "top", "iso"};
        for (int k = 0; k < 4; k++)
            if (!strcmp(v, names[k])) {
                o->view = (cbm_camera_view)k;
                return 1;
            }
        double x, y, z;
        char tail;
        if (sscanf(v, "%lf,%lf,%lf%c", &x, &y, &z, &tail) != 3 || !isfinite(x) || !isfinite(y) ||
            !isfinite(z) || (x == 0 && y == 0 && z == 0))
            return bad(cmd, a, v);
        o->view = CBM_VIEW_VECTOR;
        o->view_dir = (cbm_vec3){x, y, z};
    } else if (!strcmp(a, "--background")) {
        if (!parse_color(v, o->background))
            return bad(cmd, a, v);
    } else if (!strcmp(a, "--color-by")) {
        static const char *const names[] = {"material", "stress", "age",
                                            "reaction", "order",  "stress-mpa"};
        for (int k = 0; k < (int)(sizeof names / sizeof names[0]); k++)
            if (!strcmp(v, names[k])) {
                o->color_by = (cbm_color_by)k;
                return 1;
            }
        return bad(cmd, a, v);
    } else if (!strcmp(a, "--range")) {
        double lo, hi;
        char tail;
        if (sscanf(v, "%lf:%lf%c", &lo, &hi, &tail) != 2 || !isfinite(lo) || !isfinite(hi) ||
            !(hi > lo))
            return bad(cmd, a, v);
        o->range_min = lo;
        o->range_max = hi;
    } else if (!strcmp(a, "--ao")) {
        if (!cli_parse_long(v, &n) || n < 0 || n > 256)
            return bad(cmd, a, v);
        o->ao_samples = (int)n;
    } else if (!strcmp(a, "--supersample")) {
        if (!cli_parse_long(v, &n) || n < 1 || n > 4)
            return bad(cmd, a, v);
        o->supersample = (int)n;
    } else {
        if (!cli_parse_long(v, &n) || n < 0 || n > 64)
            return bad(cmd, a, v);
        o->threads = (int)n;
    }
    return 1;
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
