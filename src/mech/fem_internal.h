/* Private interface of the incremental finite-element method (fem.c) for the drivers in the
 * same area (bend.c): a snapshot of the plant's loads and rings before a growth step, and the
 * one linear increment that applies what the step added. */
#ifndef CBM_FEM_INTERNAL_H
#define CBM_FEM_INTERNAL_H

#include "mech/mech_internal.h"

/* What the plant carried before a growth step (per segment). */
typedef struct cbm__fem_snap {
    size_t n;       /* segments then */
    double *mpl;    /* kg/m */
    double *pmass;  /* kg */
    size_t *rings;  /* ring count */
    cbm_vec3 *tipf; /* N, world */
    cbm_vec3 *tipm; /* N m, world */
} cbm__fem_snap;

/// Releases the FEM buffers kept in the plant (cbm_plant_destroy).
void cbm__fem_free(cbm_plant *p);

/// Records the plant's loads and ring counts (into a buffer the plant keeps; cbm__fem_snap_free
/// forgets it).
cbm_status cbm__fem_snap_take(cbm_plant *p, cbm__fem_snap *s);
void cbm__fem_snap_free(cbm_plant *p, cbm__fem_snap *s);

/// One linear FEM increment on the current geometry: the load of everything added since the
/// snapshot (new wood's weight and maturation strain, changed point masses and tip loads, new
/// segments whole), the stiffness of all rings; rotations accumulated into frames and Omega,
/// the plant evaluated at the end.
cbm_status cbm__fem_increment(cbm_plant *p, const cbm_fem_def *d, const cbm__fem_snap *s,
                              cbm_fem_stats *stats);

/// cbm_plant_solve with CBM_MECH_FEM: from the rest shape, the full load in d->increments steps.
cbm_status cbm__mech_solve_fem(cbm_plant *p, const cbm_fem_def *d, cbm_solve_stats *st);

#endif
