/* Private layout of the linearised dynamics (src/mech/dyn_*.c): the plant's equilibrium copied into
 * the arrays of the O(n) tree operators (tree.c), used by the modes (modes.c) and the time stepping
 * (motion.c). */
#ifndef CBM_DYN_INTERNAL_H
#define CBM_DYN_INTERNAL_H

#include "cambium/dynamics.h"
#include "core/core.h"

/* The linear system about one equilibrium. Coordinates: q_k, the small rotation (world) of joint
 * k about its node x_k; a twist Z = (rotation, displacement of the origin) is a 6-vector, a
 * wrench W = (moment about the origin, force) too; positions are relative to the plant's base so
 * that the spatial blocks stay well scaled. See tree.c for the operators. */
typedef struct cbm__dyn {
    cbm_context *ctx;
    size_t n;
    int64_t *parent;
    cbm_vec3 *x;   /* proximal node (the joint), relative to the base, m */
    cbm_vec3 *e;   /* distal node, relative to the base, m */
    double *kel;   /* 9 per joint: elastic stiffness R diag(C / d) R^T, N m / rad */
    double *geo;   /* 9 per joint: G_k of the dead loads carried, N m / rad (tree.c) */
    double *body;  /* 36 per segment: spatial inertia about the base (segment + point mass) */
    cbm_vec3 base; /* the plant's base position, m (world = base + relative) */
    /* factorisation of sK K + sM M (tree.c) */
    double fk, fm; /* its sK and sM */
    double *dinv;  /* 9 per joint */
    double *lmat;  /* 18 per joint: L = B + S^T Pi (3 x 6) */
    double *pi;    /* 36 per joint: articulated block (work of the factorisation) */
    /* work */
    double *z;   /* 6 per segment */
    double *acc; /* 6 per segment */
    double *u;   /* 3 per joint */
} cbm__dyn;

/// Copies the plant's equilibrium (its state must be current: after a solve or an evaluation)
/// into d. CBM_E_INVALID for an empty plant or a segment without mass.
cbm_status cbm__dyn_build(const cbm_plant *p, cbm__dyn *d);
void cbm__dyn_free(cbm__dyn *d);
/// y = (sk K + sm M) v, 3n doubles each (v and y must not alias).
void cbm__dyn_apply(cbm__dyn *d, double sk, double sm, const double *v, double *y);
/// Factorises sk K + sm M; returns the number of pivot blocks that are not positive definite
/// (0: the matrix is positive definite), or (size_t)-1 if one is singular.
size_t cbm__dyn_factor(cbm__dyn *d, double sk, double sm);
/// x = (sk K + sm M)^-1 b with the last factorisation (x and b may alias).
void cbm__dyn_solve(cbm__dyn *d, const double *b, double *x);
/// f += the generalised force of a force F (world) at the distal node of seg.
void cbm__dyn_point_force(const cbm__dyn *d, size_t seg, cbm_vec3 F, double *f);
/// Displacement of the distal node of seg for the rotations q.
cbm_vec3 cbm__dyn_node_disp(const cbm__dyn *d, const double *q, size_t seg);

#endif
