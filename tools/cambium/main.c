/* cambium, the command-line tool: dispatches to the subcommands (run, bend, buckle, info) and
 * holds the helpers they share. Uses only the public API. */
#include "cli.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"

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

cbm_context *cli_context(void)
{
    cbm_context_def def = cbm_context_def_default();
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

int main(int argc, char **argv)
{
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
