/* Private functions shared by the growth files (growth.c, wood.c). */
#ifndef CBM_GROWTH_INTERNAL_H
#define CBM_GROWTH_INTERNAL_H

#include "mech/mech_internal.h"

/// Validates a growth definition, naming the bad field.
cbm_status cbm__growth_check(cbm_context *ctx, const cbm_growth_def *d);
/// Lays a ring of new wood (outer semi-axes a, b) on a segment; `reaction` selects reaction wood.
cbm_status cbm__growth_ring(cbm_plant *p, size_t seg, double a, double b, const cbm_growth_def *d,
                            bool reaction);
/// Whether segment `seg` leans (|Omega - rest| above the reaction threshold, 8.7-8.8).
cbm_status cbm__wood_leans(const cbm_plant *p, size_t seg, const cbm_growth_def *d, bool *leans);
/// Material and rest rate of a new ring (E, G, rest rate, reaction fraction; 8.23-8.25).
/// `current` is the rate the ring memorises, `rest` the segment's rest rate (the EP).
void cbm__wood_new_ring(const cbm_growth_def *d, bool reaction, cbm_vec3 current, cbm_vec3 rest,
                        cbm_ring *r);

#endif
