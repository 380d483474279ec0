/* The model's internals for its tests: switches that the library keeps on. */
#ifndef CBM_LSYS_MODEL_INTERNAL_H
#define CBM_LSYS_MODEL_INTERNAL_H

#include "cambium/model.h"

/// Whether the per-step query pass may pass over branches that no query depends on (model.c,
/// pass_over_branch; on by default). Off, every module of the image goes through the turtle:
/// the reference the tests compare with.
void cbm__model_set_pass_over(cbm_model *m, bool on);

#endif
