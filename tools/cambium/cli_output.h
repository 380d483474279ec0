/* Output options and progress shared by the commands that write scenes (demo, run): parsing of
 * the picture and colour options into cbm_write_options, and the progress line on stderr. */
#ifndef CBM_CLI_OUTPUT_H
#define CBM_CLI_OUTPUT_H

#include "cli.h"

/// The help text of the output options (for a command's --help).
extern const char cli_output_help[];

/// If argv[*i] is an output option, parses it (and its value, advancing *i) into o and returns 1;
/// returns 0 if it is not one; on a bad value prints a usage error for `cmd` and returns -1.
int cli_output_option(const char *cmd, int argc, char **argv, int *i, cbm_write_options *o);

/// An output: "FILE.ext" (format from the extension), or "FORMAT:PATH" with "-" for stdout.
typedef struct cli_output_target {
    char format[8];
    const char *path;
} cli_output_target;

/// Parses an -o argument; false if the format is unknown.
bool cli_output_target_parse(const char *arg, cli_output_target *out);

/// Progress line on stderr, redrawn at most 10 times a second; silent unless stderr is a
/// terminal (or CBM_PROGRESS=1 forces it, for tests).
typedef struct cli_progress {
    bool on;
    double start, last; /* s, monotonic */
} cli_progress;

void cli_progress_begin(cli_progress *p);
void cli_progress_update(cli_progress *p, cbm_progress *state);
/// Clears the line.
void cli_progress_end(cli_progress *p);
/// Seconds on a monotonic clock.
double cli_seconds(void);
/// --timing: the statics solves through ctx by the stage that converged, one line on stderr
/// ("CMD: solves by converged stage: newton 120, transient 3"); nothing without solves.
void cli_print_solve_stages(const char *cmd, const cbm_context *ctx);

#endif
