/* The mechanics' package header: what the library's other areas (the built-in trees of src/tree
 * above all) read of a plant beyond the public API (cambium/mech.h), without its layout
 * (mech_internal.h stays inside src/mech). The arrays are views of the plant's own, one entry per
 * segment, valid until the plant gains or loses segments (then ask again); the public
 * cbm_plant_parents, cbm_plant_positions and cbm_plant_orientations are the other views. */
#ifndef CBM_MECH_H
#define CBM_MECH_H

#include "cambium/mech.h"

#include <stdint.h>

/* The outer ring's semi-axes (m) and modulus of rupture (Pa), kept per segment so that the
 * passes over the plant (ring growth, breakage) do not visit the ring pool. */
typedef struct cbm__outer {
    double a, b, mor;
} cbm__outer;

/// Children of each segment.
const uint32_t *cbm__plant_child_counts(const cbm_plant *p);
/// Branch order of each segment (0: the trunk).
const int32_t *cbm__plant_orders(const cbm_plant *p);
/// Length of each segment, m.
const double *cbm__plant_lengths(const cbm_plant *p);
/// Wood cross-section of each segment (its rings), m^2.
const double *cbm__plant_areas(const cbm_plant *p);
/// The outer ring of each segment.
const cbm__outer *cbm__plant_outers(const cbm_plant *p);
/// The rings of segment i, pith first (*count of them), in the plant's ring pool: valid until a
/// ring is added anywhere.
const cbm_ring *cbm__plant_rings(const cbm_plant *p, size_t i, size_t *count);

#endif
