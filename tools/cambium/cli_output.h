/* Output targets and progress shared by the commands that write scenes (demo, run, grow); their
 * picture and colour options are the table cli_output_options (options.h). */
#ifndef CBM_CLI_OUTPUT_H
#define CBM_CLI_OUTPUT_H

#include "cli.h"
#include "options.h"

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
