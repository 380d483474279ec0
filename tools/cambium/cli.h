/* Shared pieces of the command-line tool: the command table and the helpers every command
 * uses (context with a stderr diagnostics sink, error reporting, number parsing). */
#ifndef CBM_CLI_H
#define CBM_CLI_H

#include "cambium/cambium.h"

#include <stdio.h>

/// Exit codes: 0 success, 1 failure of the job (bad model, solver failure, I/O), 2 bad usage.
enum { CLI_OK = 0, CLI_FAIL = 1, CLI_USAGE = 2 };

typedef int (*cli_command_fn)(int argc, char **argv);

/// A context whose diagnostics print to stderr as "file:line:col: error: message", with the
/// limits of the command line (cli_limit_options, options.h) or their defaults.
cbm_context *cli_context(void);
/// Checks that the output paths can be written (folder exists and is writable, no read-only
/// file or dangling link) before a long computation: CLI_OK, else prints why and CLI_FAIL.
int cli_check_outputs(const char *const *paths, int n);
/// Where the text a model prints (printf) goes: stdout by default, NULL discards it.
void cli_set_model_output(FILE *f);
/// Destroys the context made by cli_context.
void cli_context_end(cbm_context *ctx);
/// Prints "cambium: <what>: <last error or status message>" to stderr and returns CLI_FAIL.
int cli_fail(cbm_context *ctx, cbm_status s, const char *what);
/// Prints "cambium <cmd>: <message>" and returns CLI_USAGE.
int cli_usage_error(const char *cmd, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
/// Strict number parsing: the whole string must be a finite number.
bool cli_parse_double(const char *s, double *out);
bool cli_parse_long(const char *s, long *out);
/// The extension of a path after the last dot ("csv"), "" if none.
const char *cli_extension(const char *path);
/// The contents of a regular file (a FIFO or a device would block or never end), up to max + 1
/// bytes so that the caller sees an oversized file (*len > max); NULL when it cannot be read.
/// Free with free().
char *cli_read_regular_file(const char *path, size_t max, size_t *len);
/// A spec file (bend, compare, elastica) whole, up to 1 MiB; NULL after saying why on stderr.
char *cli_read_spec(const char *path, size_t *len);
/// Seconds of the monotonic clock.
double cli_now(void);

#endif
