/* cambium, the command-line tool: dispatches to the subcommands (CBM_COMMANDS, commands.h) and
 * holds the helpers they share. Uses only the public API. */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "commands.h"
#include "options.h"

static void print_diag(void *ud, const cbm_diagnostic *d)
{
    (void)ud;
    static const char *const sev[] = {"note", "warning", "error"};
    if (d->file && d->line > 0)
        fprintf(stderr, "%s:%d:%d: %s: %s\n", d->file, d->line, d->col, sev[d->severity],
                d->message);
    else if (d->file)
        fprintf(stderr, "%s: %s: %s\n", d->file, sev[d->severity], d->message);
    else if (d->severity != CBM_ERROR)
        fprintf(stderr, "cambium: %s: %s\n", sev[d->severity], d->message);
    /* errors without a location are printed once by cli_fail */
}

static FILE *model_output;

static void print_output(void *ud, const char *text, size_t n)
{
    (void)ud;
    if (model_output)
        fwrite(text, 1, n, model_output);
}

void cli_set_model_output(FILE *f)
{
    model_output = f;
}

/* The limits of the command line: the library's defaults, a memory limit that keeps a run well
 * below the machine's memory, and what the options asked. */
static cbm_limits limits;
static bool limits_ready;

static cbm_limits *cli_limits(void)
{
    if (!limits_ready) {
        limits = cbm_context_def_default().limits;
        /* 4 GiB, or half the physical memory on a smaller machine */
        size_t lim = (size_t)4 << 30;
        long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
        if (pages > 0 && page > 0 && (size_t)pages / 2 < lim / (size_t)page)
            lim = (size_t)pages / 2 * (size_t)page;
        limits.max_bytes = lim;
        limits_ready = true;
    }
    return &limits;
}

/* A limit's value: a non-negative integer (at least 1 unless zero_ok), at most max. */
static bool limit_value(const char *value, long max, bool zero_ok, long *out, char *why, size_t n)
{
    long v;
    if (!cli_parse_long(value, &v) || v < 0) {
        snprintf(why, n, "{opt} expects a non-negative integer");
        return false;
    }
    if (v > max) {
        snprintf(why, n, "{opt}: %ld is too large", v);
        return false;
    }
    if (v == 0 && !zero_ok) {
        snprintf(why, n, "{opt} must be at least 1");
        return false;
    }
    *out = v;
    return true;
}

/* megabytes into bytes (size_t); --max-memory 0 is no limit */
static bool limit_megabytes(const char *value, void *target, char *why, size_t n)
{
    long v;
    bool zero_ok = target == &limits.max_bytes;
    if (!limit_value(value, (long)(SIZE_MAX >> 21), zero_ok, &v, why, n))
        return false;
    *(size_t *)target = (size_t)v << 20;
    return true;
}

static bool limit_count(const char *value, void *target, char *why, size_t n)
{
    long v;
    if (!limit_value(value, LONG_MAX, false, &v, why, n))
        return false;
    *(size_t *)target = (size_t)v;
    return true;
}

static bool limit_long(const char *value, void *target, char *why, size_t n)
{
    return limit_value(value, LONG_MAX, false, target, why, n);
}

/* the depths are ints; nesting recurses on the stack, so its limit stays where the default 8 MB
 * stack holds (parsing and evaluation take up to ~3 kB a level) */
static bool limit_depth(const char *value, void *target, char *why, size_t n)
{
    long v;
    if (!limit_value(value, target == &limits.max_expr_depth ? 1000 : 1000000, false, &v, why, n))
        return false;
    *(int *)target = (int)v;
    return true;
}

static cli_opt limit_rows[] = {{.name = "--max-memory",
                                .kind = CLI_CUSTOM,
                                .target = &limits.max_bytes,
                                .arg = "MB",
                                .parse = limit_megabytes,
                                .help = "memory the library may hold (default 4096 or half the\n"
                                        "physical memory; 0: no limit)"},
                               {.name = "--max-modules",
                                .kind = CLI_CUSTOM,
                                .target = &limits.max_modules,
                                .arg = "N",
                                .parse = limit_count,
                                .help = "modules in the L-system string (default 2^31)"},
                               {.name = "--max-steps",
                                .kind = CLI_CUSTOM,
                                .target = &limits.max_steps,
                                .arg = "N",
                                .parse = limit_count,
                                .help = "derivation steps (default 10^6)"},
                               {.name = "--max-operations",
                                .kind = CLI_CUSTOM,
                                .target = &limits.max_operations,
                                .arg = "N",
                                .parse = limit_long,
                                .help = "function calls and loop iterations in one step (10^8)"},
                               {.name = "--max-loop-iterations",
                                .kind = CLI_CUSTOM,
                                .target = &limits.max_loop_iterations,
                                .arg = "N",
                                .parse = limit_long,
                                .help = "loop iterations in one step (10^8)"},
                               {.name = "--max-call-depth",
                                .kind = CLI_CUSTOM,
                                .target = &limits.max_call_depth,
                                .arg = "N",
                                .parse = limit_depth,
                                .help = "nested function calls (256)"},
                               {.name = "--max-expr-depth",
                                .kind = CLI_CUSTOM,
                                .target = &limits.max_expr_depth,
                                .arg = "N",
                                .parse = limit_depth,
                                .help = "nesting of expressions and statements, operator chains\n"
                                        "included (200, at most 1000)"},
                               {.name = "--max-decomp-depth",
                                .kind = CLI_CUSTOM,
                                .target = &limits.max_decomp_depth,
                                .arg = "N",
                                .parse = limit_depth,
                                .help = "maximum depth of decomposition and interpretation (1000)"},
                               {.name = "--max-expansion",
                                .kind = CLI_CUSTOM,
                                .target = &limits.max_pp_bytes,
                                .arg = "MB",
                                .parse = limit_megabytes,
                                .help = "size of the preprocessed model text, each macro\n"
                                        "expansion counting 64 bytes (64)"},
                               {.name = "--max-segments",
                                .kind = CLI_CUSTOM,
                                .target = &limits.max_segments,
                                .arg = "N",
                                .parse = limit_count,
                                .help = "mechanical segments of one plant (2^28)"},
                               {.name = "--allow-nonfinite",
                                .kind = CLI_SET,
                                .target = &limits.allow_nonfinite,
                                .help =
                                    "a module parameter that is inf or NaN is a warning (kept),\n"
                                    "not an error"},
                               {0}};

static cli_opts limit_table = {.title = "limits (per run; docs/cli.md):",
                               .opts = limit_rows,
                               .width = 23,
                               .missing = "{opt} expects a non-negative integer"};

cli_opts *cli_limit_options(void)
{
    cli_limits(); /* the defaults first: the options change them */
    return &limit_table;
}

cbm_context *cli_context(void)
{
    cbm_context_def def = cbm_context_def_default();
    def.limits = *cli_limits();
    def.diag = print_diag;
    def.output = print_output;
    cbm_context *ctx = NULL;
    if (cbm_context_create(&def, &ctx) != CBM_OK) {
        fprintf(stderr, "cambium: out of memory\n");
        exit(CLI_FAIL);
    }
    return ctx;
}

void cli_context_end(cbm_context *ctx)
{
    cbm_context_destroy(ctx);
}

int cli_fail(cbm_context *ctx, cbm_status s, const char *what)
{
    const char *msg = ctx ? cbm_context_last_error(ctx) : "";
    if (msg && *msg && strchr(msg, ':') && strstr(msg, ": error: "))
        fprintf(stderr, "cambium: %s failed (%s)\n", what, cbm_status_message(s));
    else if (msg && *msg)
        fprintf(stderr, "cambium: %s: %s\n", what, msg);
    else
        fprintf(stderr, "cambium: %s: %s\n", what, cbm_status_message(s));
    return CLI_FAIL;
}

int cli_usage_error(const char *cmd, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "cambium %s: ", cmd);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fprintf(stderr, "\n(see 'cambium %s --help')\n", cmd);
    return CLI_USAGE;
}

bool cli_parse_double(const char *s, double *out)
{
    if (!s || !*s)
        return false;
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (*end || errno == ERANGE || !isfinite(v))
        return false;
    *out = v;
    return true;
}

bool cli_parse_long(const char *s, long *out)
{
    if (!s || !*s)
        return false;
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (*end || errno == ERANGE)
        return false;
    *out = v;
    return true;
}

const char *cli_extension(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(path, '.');
    if (!dot || (slash && dot < slash))
        return "";
    return dot + 1;
}

char *cli_read_regular_file(const char *path, size_t max, size_t *len)
{
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISREG(st.st_mode))
        return NULL;
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    char *buf = malloc(max + 1);
    size_t n = buf ? fread(buf, 1, max + 1, f) : 0;
    bool bad = !buf || ferror(f);
    fclose(f);
    if (bad) {
        free(buf);
        return NULL;
    }
    *len = n;
    return buf;
}

#define MAX_SPEC_BYTES (1u << 20)

char *cli_read_spec(const char *path, size_t *len)
{
    char *text = cli_read_regular_file(path, MAX_SPEC_BYTES, len);
    if (!text) {
        fprintf(stderr, "cambium: %s: cannot read the spec\n", path);
        return NULL;
    }
    if (*len > MAX_SPEC_BYTES) {
        free(text);
        fprintf(stderr, "cambium: %s: spec larger than %u bytes\n", path, MAX_SPEC_BYTES);
        return NULL;
    }
    return text;
}

double cli_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static const struct {
    const char *name;
    cli_command_fn fn;
    const char *summary;
} commands[] = {
#define CBM_COMMAND(name, fn, summary) {name, fn, summary},
    CBM_COMMANDS(CBM_COMMAND)
#undef CBM_COMMAND
};

static void usage(FILE *f)
{
    fprintf(f, "usage: cambium COMMAND [ARGS...]\n\ncommands:\n");
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        fprintf(f, "  %-8s %s\n", commands[i].name, commands[i].summary);
    fprintf(f, "\n'cambium COMMAND --help' describes a command. Units are SI.\n");
}

/* SIGINT, SIGTERM, SIGHUP: remove the temporary files of the outputs being written, then die
 * of the signal as before. */
static void on_signal(int sig)
{
    /* async-signal-safe by construction (src/io/out.c): it reads sig_atomic_t slot flags and
     * calls unlink(2), nothing else */
    cbm_out_remove_temporaries(); // NOLINT(bugprone-signal-handler,cert-sig30-c)
    signal(sig, SIG_DFL);
    raise(sig);
}

int cli_check_outputs(const char *const *paths, int n)
{
    cbm_context *ctx = NULL;
    int rc = CLI_OK;
    for (int k = 0; k < n && rc == CLI_OK; k++) {
        if (!ctx)
            ctx = cli_context();
        cbm_status s = cbm_out_check(ctx, paths[k]);
        if (s != CBM_OK)
            rc = cli_fail(ctx, s, "output");
    }
    if (ctx)
        cli_context_end(ctx);
    return rc;
}

int main(int argc, char **argv)
{
    signal(SIGINT, on_signal);
    signal(SIGTERM, on_signal);
    signal(SIGHUP, on_signal);
    if (argc < 2) {
        usage(stderr);
        return CLI_USAGE;
    }
    if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
        usage(stdout);
        return CLI_OK;
    }
    if (!strcmp(argv[1], "--version") || !strcmp(argv[1], "version")) {
        printf("cambium %s\n", CBM_VERSION_STRING);
        return CLI_OK;
    }
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        if (!strcmp(argv[1], commands[i].name))
            return commands[i].fn(argc - 1, argv + 1);
    fprintf(stderr, "cambium: unknown command '%s'\n", argv[1]);
    usage(stderr);
    return CLI_USAGE;
}
