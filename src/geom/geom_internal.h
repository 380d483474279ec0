/* Internal contract of the scene for the geometry builders of src/geom/. */
#ifndef CBM_GEOM_INTERNAL_H
#define CBM_GEOM_INTERNAL_H

#include "cambium/geom.h"

#include "../core/core.h"

/* The context the scene allocates from (for the builders' scratch memory). */
cbm_context *cbm__scene_context(const cbm_scene *s);

/* cbm_scene_tube_begin with a cap at the start and at the end chosen apart. */
cbm_status cbm__scene_tube_begin_caps(cbm_scene *s, int sides, bool cap_start, bool cap_end);

#endif
