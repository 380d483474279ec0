/* Private functions shared by the growth files (growth.c, wood.c). */
#ifndef CBM_GROWTH_INTERNAL_H
#define CBM_GROWTH_INTERNAL_H

#include "mech/mech_internal.h"

/// Validates a growth definition, naming the bad field.
cbm_status cbm__growth_check(cbm_context *ctx, const cbm_growth_def *d);
/// The rate a new ring memorises, for every segment at once in O(n): cbm_segment_state.rate
/// (CBM_MEMORY_SEGMENT) or .omega (CBM_MEMORY_JOINT). out holds segment_count entries.
cbm_status cbm__growth_rates(cbm_plant *p, cbm_ring_memory memory, cbm_vec3 *out);
/// Whether a segment at rate `current` with rest rate `rest` leans (|Omega - rest| above the
/// reaction threshold, 8.7-8.8).
bool cbm__wood_leans(const cbm_growth_def *d, cbm_vec3 current, cbm_vec3 rest);
/// Material and rest rate of a new ring (E, G, rest rate, reaction fraction; 8.23-8.25).
/// `current` is the rate the ring memorises, `rest` the segment's rest rate (the EP).
void cbm__wood_new_ring(const cbm_growth_def *d, bool reaction, cbm_vec3 current, cbm_vec3 rest,
                        cbm_ring *r);

/// kappa^c of a new ring on segment `seg` in its local frame: `rate` plus `up` rad/m about the
/// axis that turns the segment's heading towards -gravity (zero when it is vertical).
cbm_vec3 cbm__growth_control(const cbm_plant *p, size_t seg, cbm_vec3 rate, double up);

#endif
