/* Growing one model for a study, shared by `cambium compare` (one model under several bending
 * methods) and `cambium sweep` (one model over a grid of parameter values): a built-in tree
 * model, a .tree file or an L-system model (.l), with the command's -D overrides, one swept
 * parameter, a seed, a year (step) count and a bending method, each run in a context of its own
 * so that its time and peak memory are its own; what both commands measure of the grown plant;
 * and their common -o handling (a .csv/.json table, .svg/.png plots). */
#ifndef CBM_CLI_STUDY_H
#define CBM_CLI_STUDY_H

#include "cli.h"
#include "options.h"

#include "cambium/tree.h"

#define CLI_STUDY_MAX_DEFS 32

/// The options both commands take for the model: -n YEARS and -D NAME=VALUE.
typedef struct cli_study_args {
    long years; ///< -1 unless -n
    const char *defs[CLI_STUDY_MAX_DEFS];
    cli_list def_list; ///< over defs
} cli_study_args;
/// The model of a study and the overrides every run shares.
typedef struct cli_study_model {
    const char *path;  ///< a .l file, a .tree file or a built-in tree model's name
    bool lsys;         ///< an L-system model (.l)
    cbm_tree_def tree; ///< tree models: the definition with the -D overrides
    /// .l: the -D NAME=VALUE (they override the model's #define), with room for the swept one
    const char *defines[CLI_STUDY_MAX_DEFS + 1];
    size_t ndefines;
    long years; ///< -1: the model's (tree years; derivation steps of a .l model)
} cli_study_model;

/// Reads the model and applies the -D overrides (tree models: every name is checked; .l: the
/// model is compiled once so that a syntax error stops the study before it starts). With
/// need_mechanics a .l model must declare `mechanics:`. What a .l model prints is discarded
/// from here on (it would mix with the tables). CLI_OK, or the error printed (usage
/// errors as `cambium CMD: ...`, exit 2).
int cli_study_model_load(cli_study_model *m, const char *cmd, const char *path,
                         const cli_study_args *a, bool need_mechanics);

/// Whether NAME=VALUE is a valid setting of a tree model (always true for a .l model, whose
/// #defines the preprocessor takes as they come); else prints the usage error (exit 2).
int cli_study_check_param(const cli_study_model *m, const char *cmd, const char *name,
                          const char *value);

/// One run of a study.
typedef struct cli_study_run {
    const char *name, *value; ///< a swept parameter (tree key or .l #define), or NULL
    const char *seed;         ///< NULL: the model's
    int solver;               ///< a cbm_mech_solver, or -1: the model's
    bool shape;               ///< keep the segments (nodes, lines) for distances and plots
} cli_study_run;

/// What a run grew and what it cost.
typedef struct cli_study_plant {
    size_t segments; ///< mechanical segments (a .l model without mechanics: turtle primitives)
    double ext[3];   ///< m, max - min over the segment nodes (turtle box without mechanics)
    /// m, the leader's tip (the distal node at the end of the first root's continuation chain);
    /// NaN without mechanics
    double tip[3];
    double height;     ///< m, the top node above the base (ext[1] without mechanics)
    double deflection; ///< m, horizontal distance of the leader's tip from the base node
    double seconds;    ///< wall time of the growth
    size_t peak_bytes; ///< peak of the run's context
    double *nodes;     ///< shape: 3 (segments + 1): the first root's proximal node, then each
                       ///< segment's distal node, in segment order (free with the plant)
    double *lines;     ///< shape: 6 segments: proximal and distal node of each segment
} cli_study_plant;

/// Grows one run; CLI_OK or the failure (printed).
int cli_study_grow(const cli_study_model *m, const cli_study_run *r, cli_study_plant *out);
void cli_study_plant_free(cli_study_plant *p);

/// The -o parser of both commands: .csv, .json, .svg or .png (target: a cli_list).
bool cli_study_parse_output(const char *v, void *target, char *why, size_t n);
/// Their option group (CLI_GROUP target), filling *a (set years = -1 and the list first:
/// cli_study_args_init).
void cli_study_args_init(cli_study_args *a);
cli_opts *cli_study_model_options(cli_study_args *a);
/// Whether an output is a plot (.svg, .png).
bool cli_study_is_plot(const char *path);

/// Writes every output in a context of its own: plots through plot(ctx, path, ud), tables
/// (.csv, .json) through table(stream, json, ud) via cbm_out. CLI_OK or the first failure
/// (printed; the outputs before it are written).
typedef cbm_status (*cli_study_plot_fn)(cbm_context *ctx, const char *path, void *ud);
typedef void (*cli_study_table_fn)(FILE *f, bool json, void *ud);
int cli_study_write(const char *const *outs, int n, cli_study_plot_fn plot,
                    cli_study_table_fn table, void *ud);

/// An S-curve to draw (`bend --continue` and `elastica` both draw one): n equilibria in the
/// order traced, against x, with y in the top panel and e (the energy) in the bottom one.
typedef struct cli_scurve_plot {
    const char *title, *xlabel, *ylabel, *elabel;
    const double *x, *y, *e;
    const bool *stable; ///< n: stable equilibria on the solid line, the others dashed
    const bool *gap;    ///< n or NULL: the line breaks before this point (a jump target)
    size_t n;
    const double *fx, *fy, *fe; ///< nf marked points (folds), circled; NaN x skips one
    size_t nf;
    const char *fold_label;
    const double *jx, *jy, *je; ///< nj jump targets, crossed
    size_t nj;
} cli_scurve_plot;

/// Draws the S-curve's two panels to path (.svg or .png): each arc joins its stable neighbours
/// so stable and unstable arcs meet.
cbm_status cli_scurve_plot_write(cbm_context *ctx, const cli_scurve_plot *s, const char *path);

#endif
