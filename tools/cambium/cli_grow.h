/* What `cambium grow` shares between its two model families (cmd_grow.c: the built-in tree
 * models of cambium/tree.h; cmd_grow_ober.c: Oberlaender's parametric tree): the model word, the
 * option rows both take with the same meaning, the -D NAME=VALUE split and the help's tail. */
#ifndef CBM_CLI_GROW_H
#define CBM_CLI_GROW_H

#include "options.h"

#include <stdbool.h>
#include <stddef.h>

/// Whether s ends with suf (".tree").
bool cli_grow_ends_with(const char *s, const char *suf);

/// The MODEL row: one parameter file or built-in name into *model ("-" is an unknown option).
cli_opt cli_grow_model_row(const char **model);
/// -y|-n|--years N, 0..1000, into *years.
cli_opt cli_grow_years_row(long *years);
/// -D NAME=VALUE (also -DNAME=VALUE) appended to *defs; `help` says what NAME sets.
cli_opt cli_grow_defines_row(cli_list *defs, const char *help);
/// --params: print every parameter and exit.
cli_opt cli_grow_params_row(bool *params);

/// Splits a -D word into its NAME (copied to name, a buffer of n bytes) and returns VALUE, or
/// NULL after printing the usage error "-D expects NAME=VALUE, got '...'".
const char *cli_grow_define(const char *word, char *name, size_t n);

/// The help: `text` (usage and description), the option rows, the built-in model names, then
/// the option groups.
void cli_grow_help(const cli_opts *t, const char *text, const char *const *builtin);

#endif
