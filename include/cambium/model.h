/* cambium: a cpfg model run end to end — the L-system (cambium/lsys.h), its side files and the
 * turtle (cambium/turtle.h) joined as cpfg joins them.
 *
 * cbm_model_load reads the model file and the side files (view file, function files, surfaces,
 * colour map, materials: by extension, as on cpfg's command line), connects func(id, x) to the
 * function files, and interprets the string with the turtle whenever the derivation needs it:
 * at the start of every step whose string holds query modules (?P ?H ?L ?U), so that
 * productions see the turtle's position and frame, as cpfg's environmental interpretation.
 * cbm_model_interpret draws the current string (after the homomorphism) into a scene and fills
 * its query modules; call it after the last step before writing outputs.
 */
#ifndef CAMBIUM_MODEL_H
#define CAMBIUM_MODEL_H

#include "cambium/geom.h"
#include "cambium/lsys.h"
#include "cambium/turtle.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cbm_model cbm_model;

/// How a model is loaded: the L-system and its side files.
typedef struct cbm_model_def {
    cbm_lsys_def lsys;             ///< the model file and its options (defines, float32, seed)
    const char *const *side_files; ///< .v .func .fset .s .con .map .mat, read in this order
    size_t side_count;
} cbm_model_def;

/// Defaults: the L-system defaults (cbm_lsys_def_default; no model yet: set lsys.path or
/// lsys.text), no side files.
CBM_API cbm_model_def cbm_model_def_default(void);

/// Loads the model and its side files (a view with cpfg's defaults when no .v is given).
/// Errors name the file (and line for syntax errors).
CBM_API cbm_status cbm_model_load(cbm_context *ctx, const cbm_model_def *def, cbm_model **out);
CBM_API void cbm_model_destroy(cbm_model *m);

/// The L-system (to read its string, counts, derivation length, or write it).
CBM_API cbm_lsys *cbm_model_lsys(cbm_model *m);
/// The view: settings of the view file and the side files.
CBM_API const cbm_view *cbm_model_view(const cbm_model *m);

/// Starts over at the axiom (step 0).
CBM_API cbm_status cbm_model_reset(cbm_model *m);
/// One derivation step; when the string holds query modules the turtle interprets it first and
/// the queries receive their values (cpfg's order). CBM_E_LIMIT as cbm_lsys_step.
CBM_API cbm_status cbm_model_step(cbm_model *m);

/// Interprets the current string (after the homomorphism) with the turtle: draws into scene
/// (may be NULL), fills the string's query modules, and gives the turtle with its primitive
/// record (when record) and view box in *turtle (may be NULL; release with cbm_turtle_destroy).
CBM_API cbm_status cbm_model_interpret(cbm_model *m, cbm_scene *scene, bool record,
                                       cbm_turtle **turtle);

/// Whether the current string holds query modules (`?` followed by P, H, L, U or Q).
CBM_API bool cbm_model_has_queries(const cbm_model *m);

/// What a model holds (for `cambium info`).
typedef struct cbm_model_summary {
    int derivation_length;   ///< steps
    size_t productions;      ///< productions of every L-system
    size_t decompositions;   ///< decomposition: productions (every L-system)
    size_t homomorphisms;    ///< homomorphism: (L+C: interpretation:) productions
    int decomposition_depth; ///< maximum depth:
    int homomorphism_depth;  ///< maximum depth:
    bool stochastic;         ///< productions with probabilities
    bool has_start_end;      ///< Start:, End:, StartEach: or EndEach: blocks
    int functions;           ///< functions read from the side files
    int lsystems;            ///< L-systems in the file (1 + sub-L-systems)
    bool lc_dialect;         ///< an L+C model (else cpfg dialect)
    bool mechanics;          ///< L+C: a module carries a mechanical segment (`mechanics:`)
    size_t modules_declared; ///< L+C: declared modules, the turtle's included
} cbm_model_summary;

/// Fills *out for a loaded model (before or after a derivation).
CBM_API void cbm_model_describe(const cbm_model *m, cbm_model_summary *out);

#ifdef __cplusplus
}
#endif
#endif
