/* The views of a plant's arrays that the package header src/mech/mech.h gives the library's other
 * areas. */
#include "mech/mech_internal.h"

const uint32_t *cbm__plant_child_counts(const cbm_plant *p)
{
    return p->nchild;
}

const int32_t *cbm__plant_orders(const cbm_plant *p)
{
    return p->order;
}

const double *cbm__plant_lengths(const cbm_plant *p)
{
    return p->len;
}

const double *cbm__plant_areas(const cbm_plant *p)
{
    return p->area;
}

const cbm__outer *cbm__plant_outers(const cbm_plant *p)
{
    return p->outer;
}

const cbm_ring *cbm__plant_rings(const cbm_plant *p, size_t i, size_t *count)
{
    *count = p->ring_count[i];
    return p->rings.data + p->ring_first[i];
}
