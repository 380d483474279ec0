/* The command table: one line per subcommand, X(name, function, summary). Each function lives
 * in its own file cmd_<name>.c. */
#ifndef CBM_COMMANDS_H
#define CBM_COMMANDS_H

int cmd_run(int argc, char **argv);
int cmd_grow(int argc, char **argv);
int cmd_bend(int argc, char **argv);
int cmd_buckle(int argc, char **argv);
int cmd_info(int argc, char **argv);
int cmd_demo(int argc, char **argv);
int cmd_plot(int argc, char **argv);
int cmd_elastica(int argc, char **argv);
int cmd_compare(int argc, char **argv);
int cmd_sweep(int argc, char **argv);
/* grow for Oberlaender's parametric tree (cmd_grow_ober.c): cmd_grow hands over when the model
 * is one (cli_grow_is_ober: a word of the line, read through grow's option table t, that names
 * a built-in ober-* model or a .tree file of that family) */
#include "options.h"

#include <stdbool.h>
bool cli_grow_is_ober(cli_opts *t, int argc, char **argv);
int cmd_grow_ober(int argc, char **argv);

/* The forester's summary of a tree (cmd_info.c), also printed by `grow --report` and written in
 * the year-by-year summary of `grow`. */
struct cbm_tree_measures;
struct cbm_json;
void cli_measures_print(const struct cbm_tree_measures *m);
void cli_measures_json(struct cbm_json *j, const char *key, const struct cbm_tree_measures *m);

#define CBM_COMMANDS(X)                                                                            \
    X("run", cmd_run, "derive an L-system model and write its outputs")                            \
    X("grow", cmd_grow, "grow a built-in tree model (fruit tree, aspen) with mechanics")           \
    X("bend", cmd_bend, "static equilibrium of one branch or rod from a spec file")                \
    X("compare", cmd_compare, "one bend problem by several bending methods, side by side")         \
    X("sweep", cmd_sweep, "one-at-a-time sensitivity sweeps of a built-in tree model")             \
    X("buckle", cmd_buckle, "self-weight buckling length of a vertical column")                    \
    X("info", cmd_info, "what a model or output file holds")                                       \
    X("demo", cmd_demo, "write a synthetic tree in any output format")                             \
    X("plot", cmd_plot, "plot columns of a CSV or JSON table as PNG or SVG")                       \
    X("elastica", cmd_elastica, "every equilibrium of a heavy elastica or plant, S-curves")

#endif
