/* The L-system engine's package header: what the model run end to end (src/lsys_model) reads of
 * a loaded L-system beyond the public API (cambium/lsys.h), without the engine's layout
 * (lsys_internal.h stays inside src/lsys). */
#ifndef CBM_LSYS_H
#define CBM_LSYS_H

#include "cambium/lsys.h"
#include "cambium/model.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/// Whether a successor or an axiom of any L-system of the model holds the symbol '?' (a query
/// module may then appear in the string; without one the string never holds any).
bool cbm__lsys_may_query(const cbm_lsys *ls);

/// The symbols of the current string, one byte per module (the 7-bit symbol, bit 7 set when the
/// module has parameters; lsys_internal.h), *n of them: valid until the string changes.
const uint8_t *cbm__lsys_symbols(const cbm_lsys *ls, size_t *n);

/// The L-system's part of a model's summary: every field of *out but `functions` (left as it
/// is), counted over all the L-systems of the file; for an L+C model the counts of its own rules
/// and its declared modules.
void cbm__lsys_describe(const cbm_lsys *ls, cbm_model_summary *out);

/// Models with mechanics: for each module of the string (or of its interpretation, through the
/// modules they came from) its MechSegment fields (offsets MS_* of lang/mechsegment.h), NULL for
/// other modules; *out is an array of *n pointers from the context (free with cbm__free), NULL
/// when the model has no mechanics.
cbm_status cbm__lpfg_mech_fields(const cbm_lsys *ls, bool homomorphism, const double ***out,
                                 size_t *n);

#endif
