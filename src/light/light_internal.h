/* Private to src/light: the skies as source lists (sky.c) for the ray caster (light.c). */
#ifndef CBM_LIGHT_INTERNAL_H
#define CBM_LIGHT_INTERNAL_H

#include "cambium/light.h"

#include "../core/core.h"

/// Number of sources of a valid def's sky (sectors or lights, plus the sun when direct > 0).
size_t cbm__light_source_count(const cbm_light_def *d);
/// Fills out[cbm__light_source_count(d)]; horizontal irradiance sums to 1. d must be valid.
void cbm__light_fill_sources(const cbm_light_def *d, cbm_light_source *out);

#endif
