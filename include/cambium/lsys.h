/* cambium: L-systems in the cpfg dialect.
 *
 * A model file (`.l`) is preprocessed (#define with arguments, #include, C comments), parsed
 * into productions, and compiled once; cbm_lsys_reset then builds the axiom and each
 * cbm_lsys_step applies one parallel derivation step (with decomposition), as cpfg does. The
 * derived string is a sequence of modules: a one-character symbol (ASCII 1..127, as in cpfg)
 * with zero or more numeric parameters. See docs/language.md for the language.
 */
#ifndef CAMBIUM_LSYS_H
#define CAMBIUM_LSYS_H

#include "cambium/base.h"
#include "cambium/io.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cbm_lsys cbm_lsys;

/// How a model is loaded.
typedef struct cbm_lsys_def {
    const char *path;           ///< model file (used for #include and diagnostics)
    const char *text;           ///< model text; NULL: read `path`
    const char *const *defines; ///< "NAME=VALUE" or "NAME", override the file's #define
    size_t define_count;
    bool float32;             ///< keep parameters in float32 as cpfg does (compatibility)
    bool ignore_seed;         ///< ignore `seed:` as cpfg does in batch mode
    int64_t seed;             ///< >= 0: seed of stochastic choice (srand48); -1: the model's
    long max_loop_iterations; ///< loop iterations per step (0: limits.max_loop_iterations)
    /// >= 0: the bending method (a cbm_mech_solver of cambium/mech.h) of every mechanics
    /// operation of an L+C model, whatever its SolverMethod() calls say (`cambium compare`
    /// runs one model under several methods so); -1 (default): the model's own choice.
    int solver;
} cbm_lsys_def;

/// Function of the function files: value of function `id` (1-based) at x.
typedef double (*cbm_lsys_func_fn)(void *ud, int id, double x);
/// Connects func(id, x) to function files (before cbm_lsys_reset).
CBM_API void cbm_lsys_set_func(cbm_lsys *ls, cbm_lsys_func_fn fn, void *ud);

CBM_API cbm_lsys_def cbm_lsys_def_default(void);

/// Loads and compiles a model. Syntax errors are reported as file:line:col diagnostics
/// through the context (several per run), then CBM_E_SYNTAX; CBM_E_IO if the file cannot be
/// read.
CBM_API cbm_status cbm_lsys_load(cbm_context *ctx, const cbm_lsys_def *def, cbm_lsys **out);
CBM_API void cbm_lsys_destroy(cbm_lsys *ls);

/// Runs the L+C model's functions of scalar values (those the register code runs) as native
/// code: translated to C, compiled by the system C compiler (`cc` on PATH) into a shared object
/// cached in cache_dir (created when missing) under the hash of its source, and loaded. Results,
/// limits and error messages stay those of the register code, to the bit. Returns true when
/// native code runs; false leaves the model as it was and says why in *why (a static string,
/// may be NULL): a cpfg-dialect model, no function to compile, no compiler, an unwritable
/// directory. Call it after cbm_lsys_load, before the first step.
CBM_API bool cbm_lsys_compile_native(cbm_lsys *ls, const char *cache_dir, const char **why);

/// The model's `derivation length:` (steps).
CBM_API int cbm_lsys_derivation_length(const cbm_lsys *ls);
/// Starts over: runs the Start: block, builds the axiom (step 0).
CBM_API cbm_status cbm_lsys_reset(cbm_lsys *ls);
/// One derivation step (StartEach, productions with decomposition, EndEach; End after the
/// last step of the derivation length). CBM_E_LIMIT when the string would exceed the
/// context's max_modules or the memory limit; the previous string is then kept. After any
/// other failure (an expression's runtime error, out of memory) the string may be emptied
/// (large strings hand their pages back to the system while being derived): reset to go on.
CBM_API cbm_status cbm_lsys_step(cbm_lsys *ls);
/// Whether the model called stop() (in a production or block): the derivation should end after
/// the step in which it was called, as in cpfg.
CBM_API bool cbm_lsys_stopped(const cbm_lsys *ls);
/// Steps done since reset.
CBM_API int cbm_lsys_steps_done(const cbm_lsys *ls);

/// Wall-clock time spent in the mechanics operations of the L+C dialect (docs/mechanics.md:
/// Equilibrium(), AddRings(), AgeWood(), Break(), Stability()) since the last cbm_lsys_reset,
/// including those called from Start/StartEach/EndEach/End. An operation builds the plant from
/// the string unless the string and the settings are unchanged since the previous one (then it
/// reuses that plant) and writes its results back; that is counted with the operation.
typedef struct cbm_lsys_mech_timing {
    double equilibrium; ///< s, Equilibrium() in all
    double solve;       ///< s, of which cbm_plant_solve itself
    double rings;       ///< s, AddRings() and AgeWood()
    double other;       ///< s, Break() and Stability()
    size_t operations;  ///< mechanics operations run
    size_t passes;      ///< solver passes of the Equilibrium() calls
    size_t kept;        ///< operations that reused the previous operation's plant (no build)
} cbm_lsys_mech_timing;

/// The mechanics time of the current run (all zero for a model without mechanics).
CBM_API cbm_lsys_mech_timing cbm_lsys_mech_time(const cbm_lsys *ls);
/// Modules in the current string.
CBM_API size_t cbm_lsys_module_count(const cbm_lsys *ls);
/// Parameters in the current string.
CBM_API size_t cbm_lsys_param_count(const cbm_lsys *ls);

/// Sequential reading of the current string (or of its homomorphic image).
typedef struct cbm_lsys_cursor {
    size_t module, pmodule, param; /* positions in the packed arrays (private) */
    bool homomorphism;             /* private */
    int symbol;                    ///< the module's symbol (ASCII)
    int nparams;
    const double *params; ///< nparams values (valid until the next call)
    double buf[255];      /* private: values converted from float32 storage */
} cbm_lsys_cursor;

/// Starts a cursor at the first module; homomorphism selects the string after the
/// homomorphism (computed by cbm_lsys_apply_homomorphism).
CBM_API void cbm_lsys_cursor_begin(const cbm_lsys *ls, bool homomorphism, cbm_lsys_cursor *c);
/// Loads the next module into c; false at the end.
CBM_API bool cbm_lsys_cursor_next(const cbm_lsys *ls, bool homomorphism, cbm_lsys_cursor *c);

/// Environmental interpretation (cpfg's ProcessEnvironment). The callback interprets the string
/// after the homomorphism (read it with a cursor with homomorphism = true) and writes the values
/// of the query modules (?P ?H ?L ?U: the modules that follow a '?') into that image with
/// cbm_lsys_cursor_set_param; the engine then gives the k-th query module of the image's values
/// to the k-th query module of the string. This runs at the start of every derivation step and
/// whenever cbm_lsys_interpret is called (after the last step, so the final string carries its
/// values as cpfg's does). A non-OK status from the callback stops the step.
typedef cbm_status (*cbm_lsys_interpret_fn)(void *ud, cbm_lsys *ls);
CBM_API void cbm_lsys_set_interpreter(cbm_lsys *ls, cbm_lsys_interpret_fn fn, void *ud);
/// Runs the interpretation protocol above now (nothing without an interpreter).
CBM_API cbm_status cbm_lsys_interpret(cbm_lsys *ls);
/// Sets parameter i of the module that cbm_lsys_cursor_next last returned (from the string, or
/// from the homomorphic image when the cursor reads it). CBM_E_INVALID if there is no such
/// parameter.
CBM_API cbm_status cbm_lsys_cursor_set_param(cbm_lsys *ls, cbm_lsys_cursor *c, int i, double v);

/// Whether the model has a homomorphism: section.
CBM_API bool cbm_lsys_has_homomorphism(const cbm_lsys *ls);
/// Computes the image of the current string under the homomorphism (with its maximum depth).
/// Without a homomorphism the image is a copy of the string.
CBM_API cbm_status cbm_lsys_apply_homomorphism(cbm_lsys *ls);
/// Module count of the homomorphic image (0 before cbm_lsys_apply_homomorphism).
CBM_API size_t cbm_lsys_homomorphism_module_count(const cbm_lsys *ls);

/// Writes the string one module per line, parameters as %.9g: `F(1,2.5)` (the notation of
/// cpfg's exact string dumps).
CBM_API cbm_status cbm_lsys_write_str(const cbm_lsys *ls, bool homomorphism, cbm_out *o);
/// Writes the string as cpfg's `-str` does: modules run together, parameters as %g, lines
/// wrapped at 70 characters.
CBM_API cbm_status cbm_lsys_write_cpfg(const cbm_lsys *ls, bool homomorphism, cbm_out *o);

/// L+C dialect: the declared name of a module symbol (e.g. "Internode", "SB" for '['), NULL
/// for cpfg-dialect models and unknown symbols.
CBM_API const char *cbm_lsys_module_name(const cbm_lsys *ls, int symbol);
/// L+C dialect: the names used in func(name, x), in order of first use. func(name, x) calls
/// the function set with cbm_lsys_set_func with the id given to the name by
/// cbm_lsys_set_func_ids (by default 1 + the name's index here).
CBM_API size_t cbm_lsys_func_names(const cbm_lsys *ls, const char *const **names);
/// L+C dialect: ids[i] is the function id passed to the cbm_lsys_set_func callback for the
/// i-th name of cbm_lsys_func_names (e.g. from the function set's own names). n must be the
/// number of names: CBM_E_INVALID otherwise.
CBM_API cbm_status cbm_lsys_set_func_ids(cbm_lsys *ls, const int *ids, size_t n);

typedef struct cbm_plant cbm_plant; /* cambium/mech.h */
/// L+C dialect: true when the model declares a module carrying a mechanical segment
/// (`mechanics:`).
CBM_API bool cbm_lsys_has_mechanics(const cbm_lsys *ls);
/// L+C dialect: a new plant made of the mechanical segments of the current string, at the state
/// stored in them (no solve: positions, forces, moments and stresses evaluated at the stored
/// rotation rates), with the model's gravity, ground and discretisation. For the plant writers
/// (cbm_write_mtg, cbm_write_segments_csv); release with cbm_plant_destroy. CBM_E_INVALID with
/// a message when the model declares no mechanics or the string holds an invalid segment.
CBM_API cbm_status cbm_lsys_mech_plant(cbm_lsys *ls, cbm_plant **out);

typedef struct cbm_motion cbm_motion; /* cambium/dynamics.h */
/// Phases of a Sway() call reported to the sway observer.
typedef enum cbm_lsys_sway_phase {
    CBM_LSYS_SWAY_BEGIN, ///< the motion is set up and at its start (t = 0)
    CBM_LSYS_SWAY_STEP,  ///< after each time step
    CBM_LSYS_SWAY_END    ///< after the last step (the motion is still valid)
} cbm_lsys_sway_phase;
/// Observer of the L+C dialect's Sway(): called with the plant at its stored state (the
/// equilibrium the motion is about) and the motion (read its time, rotations and wind with
/// cbm_motion_state, cbm_motion_rotations, cbm_motion_wind_at; do not step it). A non-OK status
/// stops the Sway() call and the run with that status.
typedef cbm_status (*cbm_lsys_sway_fn)(void *ud, const cbm_plant *plant, cbm_motion *motion,
                                       cbm_lsys_sway_phase phase);
/// L+C dialect: sets (fn NULL: clears) the observer of every later Sway() call.
CBM_API void cbm_lsys_set_sway_observer(cbm_lsys *ls, cbm_lsys_sway_fn fn, void *ud);

#ifdef __cplusplus
}
#endif
#endif
