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

/* ---- the thesis-compatible path (fem_thesis.c), exposed for its tests ---- */

struct cbm_fem_thesis_def;

/// Gürtler's dense system of a chain of m elements at angles beta (radians): K (n x n, row-major,
/// n = 6 (m + 1)) of all rings and F of the newest rings' loads. rad, s2, s4: the rings' radii and
/// running sums of r^2 and r^4 differences (cbm_fem_thesis_angles builds them).
void cbm__fem_thesis_system(const struct cbm_fem_thesis_def *d, size_t m, const double *beta,
                            const double *rad, const double *s2, const double *s4, double *kk,
                            double *ff);

/// What the pseudo-inverse solve did.
typedef struct cbm__fem_pinv_info {
    long dropped;         /* singular values at or below the cut */
    long sweeps;          /* Jacobi sweeps */
    double smallest_kept; /* smallest singular value kept / the largest */
} cbm__fem_pinv_info;

/// x = pinv(A) b for a dense n x n A (row-major): one-sided Jacobi SVD, singular values at or
/// below max(n sigma_max 2^-52, sqrt(DBL_MIN)) dropped (Commons Math's cut). info may be NULL.
cbm_status cbm__fem_pinv_solve(cbm_context *ctx, size_t n, const double *a, const double *b,
                               double *x, cbm__fem_pinv_info *info);

/// The same for Gürtler's planar chain (n = 6 (m + 1)): the SVDs of its two uncoupled halves,
/// (ux, uz, theta_y) and (uy, theta_x, theta_z) of every node, with the cut of the whole matrix.
cbm_status cbm__fem_pinv_solve_planar(cbm_context *ctx, size_t n, const double *a, const double *b,
                                      double *x, cbm__fem_pinv_info *info);

/// A x = b with the first six DOF fixed (x[0..5] = 0), by Gaussian elimination with partial
/// pivoting on the rest. CBM_E_NONFINITE if singular.
cbm_status cbm__fem_clamped_solve(cbm_context *ctx, size_t n, const double *a, const double *b,
                                  double *x);

/// Rotation vector of a unit quaternion (|angle| <= pi).
cbm_vec3 cbm__fem_q_log(cbm_quat q);

/// Poses the single-chain plant p (n segments) at the absolute angles beta (degrees from the
/// upward vertical, in the clamp's plane: cbm_fem_thesis_resample's output) and sets each core's
/// rest rate so that the pose is an equilibrium of the plant's loads; the plant evaluated, its
/// relative equilibrium residual (round-off) into *residual (may be NULL).
cbm_status cbm__fem_thesis_pose(cbm_plant *p, const double *beta, size_t n, double *residual);

#endif
