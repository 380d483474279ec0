/* Private layout of the plant shared by plant.c and the solver files (solve_*.c): the
 * struct-of-arrays segment data, the ring pool, and the solver workspace kept in the plant so
 * that no allocation happens inside a solve's iteration. */
#ifndef CBM_MECH_INTERNAL_H
#define CBM_MECH_INTERNAL_H

#include "cambium/mech.h"
#include "core/core.h"

/* The outer ring's semi-axes and modulus of rupture, kept per segment so that the passes over
 * the plant (ring growth, breakage) do not visit the ring pool. */
typedef struct cbm__outer {
    double a, b, mor;
} cbm__outer;

/* Solver workspace: joint arrays prepared once per solve, and the Newton-Krylov vectors. */
typedef struct cbm__mech_work {
    size_t cap;     /* segments the arrays below hold */
    int krylov_cap; /* Krylov basis vectors allocated (m + 1), 0 = none */
    double *dual;   /* length over which joint i bends, m */
    cbm_vec3 *cj;   /* joint rigidity (C_H, C_L, C_U), N m^2 */
    cbm_vec3 *rj;   /* joint rest rotation rate, local, rad/m */
    cbm_vec3 *wown; /* own weight of the segment (world, N), times the load scale */
    double *lever;  /* distance from the proximal node to where wown acts, m */
    cbm_vec3 *ftip; /* point-mass weight + tip force, world, N (scaled) */
    cbm_vec3 *mtip; /* tip moment, world, N m (scaled) */
    /* Newton-Krylov */
    cbm_vec3 *res;    /* residual C (Omega - rest) - M_local */
    cbm_vec3 *step;   /* Newton step */
    cbm_vec3 *save;   /* Omega at the last accepted continuation level */
    cbm_vec3 *start;  /* Omega at the start of a warm solve (fallback of the transient path) */
    cbm_vec3 *dth;    /* tangent: world rotation of each frame */
    cbm_vec3 *dm;     /* tangent: world moment */
    cbm_vec3 *dpos;   /* tangent: world displacement of the proximal node (ground contact) */
    cbm_vec3 *dfc;    /* tangent: world force accumulators (ground contact) */
    cbm_vec3 *tmp;    /* a vector of the Krylov space */
    cbm_vec3 *basis;  /* krylov_cap vectors of 3n doubles */
    cbm_vec3 *zbasis; /* the preconditioned vectors (flexible GMRES), krylov_cap of 3n */
    double *fdinv;    /* tree factorisation, 9 doubles per segment each: D^-1 */
    double *fq;       /* Q = R^T (W + [M]x) */
    double *fa;       /* a = R J_r(d Omega) d */
    double *fwad;     /* W a D^-1 */
    double *fw;       /* W accumulators */
    /* tree factorisation with ground contact (allocated once a plant has a ground): 9 doubles
     * per segment each; see solve_tree.c */
    size_t fcap;   /* segments the contact arrays hold */
    double *fgam;  /* Gamma accumulators: d moment / d proximal-node displacement, N */
    double *flam;  /* Lambda accumulators: d force / d rotation of the parent frame, N */
    double *fxi;   /* Xi accumulators: d force / d proximal-node displacement, N/m */
    double *fp;    /* P = R^T Y */
    double *fzad;  /* Z a D^-1 */
    uint8_t *fact; /* 1 if the segment or one it carries touches the ground */
    double *hess;  /* (m + 1) x m Hessenberg matrix and Givens data */
} cbm__mech_work;

struct cbm_plant {
    cbm_context *ctx;
    cbm_vec3 gravity;
    cbm_vec3 base_pos;
    cbm_quat base_q;
    cbm_mech_discretization disc;
    double load_scale; /* 1 except during load continuation */
    double mass_path;  /* 1 except during the continuation from the balanced point masses */
    bool ground;       /* a ground plane pushes the distal nodes below it up */
    double ground_y;   /* m, height of the ground plane */
    double ground_k;   /* N/m, penalty stiffness per metre of penetration */
    double ground_s;   /* m, smoothing depth (0: none) */

    size_t n, cap;
    /* topology and rest geometry */
    int64_t *parent;
    int32_t *order;
    uint8_t *cont; /* bit 0: continues its parent's axis (or a root); bit 1: declared lateral */
    uint32_t *nchild;
    int64_t *fchild; /* the continuation child, -1 if none */
    double *len;
    double *angles;   /* 3 per segment: divergence, deviation, roll */
    cbm_quat *branch; /* B_i */
    /* section: ring pool indices and aggregates */
    size_t *ring_first, *ring_count;
    size_t *ring_cap;  /* slots of the segment's run in the pool (>= ring_count) */
    cbm__outer *outer; /* the outer ring's a, b and modulus of rupture */
    cbm_vec3 *rig;     /* (sum GJ, sum EI_L, sum EI_U) */
    cbm_vec3 *rigr;    /* sum over rings of the ring's rigidity times its rest rate */
    cbm_vec3 *rest;    /* rigidity-weighted rest rate = rigr / rig */
    double *mpl;       /* kg/m */
    double *area;      /* m^2 */
    /* state and loads */
    cbm_vec3 *omega;
    double *pmass;
    double *pmass0; /* point masses the last converged solve balanced (0 for new segments) */
    cbm_vec3 *tipf, *tipm;
    /* results */
    cbm_quat *q;
    cbm_vec3 *pos;    /* proximal node */
    cbm_vec3 *force;  /* world, through the proximal joint */
    cbm_vec3 *moment; /* world, about the proximal node */
    double *cmass;    /* carried mass */

    CBM_ARRAY(cbm_ring) rings;
    size_t ring_held; /* pool slots held by segments' runs (sum of ring_cap; the rest are holes) */
    /* free runs (holes) by capacity class (capacity 1, then 4, 8, 16, ...: class log2, 1 -> 0):
     * 1 + the first slot of a hole of that capacity, 0 = none; each hole's first slot holds
     * the next hole of its class the same way */
    size_t ring_free[64];

    cbm__mech_work work;
};

/* ---- plant.c ---- */

/// cbm_segment_state.rate of segment i in O(1) (cbm_plant_segment also visits every ring).
cbm_vec3 cbm__plant_segment_rate(const cbm_plant *p, size_t i);

/* ---- solve_common.c ---- */

/// Ensures the joint workspace for n segments (allocates only when it grows).
cbm_status cbm__mech_work_reserve(cbm_plant *p, int krylov_dim);
void cbm__mech_work_free(cbm_plant *p);
/// Joint arrays from the segment aggregates and loads (times p->load_scale).
void cbm__mech_prepare(cbm_plant *p);
/// Forward sweep: frames and proximal positions from Omega.
void cbm__mech_forward(cbm_plant *p);
/// Backward sweep: forces and moments; returns the max residual |C(Omega - rest) - M_local|
/// (N m) and *mmax = max |M|. If alpha > 0, also applies the relaxation update to Omega.
/// If res != NULL, stores the residual per joint. Returns NaN if anything is non-finite.
double cbm__mech_backward(cbm_plant *p, double alpha, cbm_vec3 *res, double *mmax, double *sumsq);
/// Upward contact force (N) on the distal node of segment i at the current state (0 without
/// ground or above it); *stiff (optional) receives d force / d height (N/m, <= 0).
double cbm__mech_contact(const cbm_plant *p, size_t i, cbm_vec3 h, double *stiff);
/// Names the first segment holding a non-finite value; returns CBM_E_NONFINITE.
cbm_status cbm__mech_report_nonfinite(cbm_plant *p);
/// Tangent passes: out = J v, where J = d(residual)/d(Omega) at the last evaluated state.
void cbm__mech_jvp(cbm_plant *p, const cbm_vec3 *v, cbm_vec3 *out);
/// Factorises the Newton matrix at the last evaluated state (tree preconditioner); returns the
/// number of joints whose pivot block was singular (replaced by the stiffness). *nonpd
/// (optional) receives the number whose pivot block's symmetric part is not positive definite
/// (an unstable configuration). With mu > 0 it factorises J + mu S (Levenberg-Marquardt).
size_t cbm__mech_tree_factor(cbm_plant *p, double mu, size_t *nonpd);
/// Factorises and solves (J + mu S) out = b in one backward and one forward sweep.
size_t cbm__mech_tree_solve(cbm_plant *p, const cbm_vec3 *b, cbm_vec3 *out, double mu,
                            size_t *nonpd);
/// After an unmodified factorisation, perturbs Omega at every joint whose pivot block is not
/// positive definite (by `angle` rad); returns their number.
size_t cbm__mech_tree_perturb_unstable(cbm_plant *p, double angle);
/// out = J^-1 b with the factorisation (out and b may not alias).
void cbm__mech_tree_apply(cbm_plant *p, const cbm_vec3 *b, cbm_vec3 *out);
/// Relative residual from the max residual and moments.
double cbm__mech_relres(double rmax, double mmax, double *char_moment);

/* ---- solve_relax.c / solve_newton.c ---- */
cbm_status cbm__mech_solve_relax(cbm_plant *p, const cbm_solve_def *def, size_t max_passes,
                                 cbm_solve_stats *st);
cbm_status cbm__mech_solve_newton(cbm_plant *p, const cbm_solve_def *def, size_t max_passes,
                                  cbm_solve_stats *st);

#endif
