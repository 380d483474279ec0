/* `--light SKY[,KEY=VALUE...]` and `-o light:FILE.csv` of cambium grow: the light of every leaf
 * of the grown plant (cbm_light_scene; docs/light.md, docs/cli.md). */
#ifndef CBM_CLI_LIGHT_H
#define CBM_CLI_LIGHT_H

#include "cli.h"

#include "cambium/light.h"

typedef struct cli_light {
    bool on;
    cbm_light_def def;
} cli_light;

/// CLI_CUSTOM parser of --light's value into a cli_light (target).
bool cli_light_parse(const char *v, void *target, char *why, size_t n);
/// Runs the light pass on the scene (parts get their light), prints one line on stdout unless
/// quiet, writes the per-leaf table to csv_path when not NULL.
cbm_status cli_light_run(cbm_context *ctx, const cli_light *l, cbm_scene *sc, const char *csv_path,
                         bool quiet);

#endif
