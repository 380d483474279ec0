/* Private layout of the plant shared by plant.c and the solver files (solve_*.c): the
 * struct-of-arrays segment data, the ring pool, and the solver workspace kept in the plant so
 * that no allocation happens inside a solve's iteration. */
#ifndef CBM_MECH_INTERNAL_H
#define CBM_MECH_INTERNAL_H

#include "cambium/mech.h"
#include "core/core.h"
#include "mech/mech.h" /* the package header: cbm__outer */

#include <math.h>

/* Solver workspace: joint arrays prepared once per solve, and the Newton-Krylov vectors, all
 * carved from one arena block (solve_common.c, "workspace"). */
typedef struct cbm__mech_work {
    cbm__arena arena; /* holds every array below in its one block */
    size_t cap;       /* segments the arrays below hold */
    int krylov_cap;   /* Krylov basis vectors allocated (m + 1), 0 = none */
    double *dual;     /* length over which joint i bends, m */
    cbm_vec3 *cj;     /* joint rigidity (C_H, C_L, C_U), N m^2 */
    cbm_vec3 *rj;     /* joint rest rotation rate, local, rad/m */
    cbm_vec3 *wown;   /* own weight of the segment (world, N), times the load scale */
    double *lever;    /* distance from the proximal node to where wown acts, m */
    cbm_vec3 *ftip;   /* point-mass weight + tip force, world, N (scaled) */
    cbm_vec3 *mtip;   /* tip moment, world, N m (scaled) */
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
    uint32_t *tpart;  /* the tree's split for the threads of solve_tree.c (subtree sizes, bins) */
    uint8_t *kin;     /* per segment: CBM__KIN_* (cbm__mech_prepare), its place among siblings */
    double *zz;       /* per joint: its term of the line search's merit (threaded backward sweep) */
    cbm_vec3 *best;   /* Omega of the best state found by the stability stage */
    cbm_vec3 *basis;  /* krylov_cap vectors of 3n doubles */
    cbm_vec3 *zbasis; /* the preconditioned vectors (flexible GMRES), krylov_cap of 3n */
    double *fdinv;    /* tree factorisation, 9 doubles per segment each: D^-1 */
    double *fq;       /* Q = R^T (W + [M]x) */
    double *fa;       /* a = R J_r(d Omega) d */
    double *fwad;     /* W a D^-1 (with fwad_ok; else scratch: Phi of a thread's subtree root) */
    double *fw;       /* W accumulators */
    size_t fneg;      /* negative eigenvalues of the pivots' symmetric parts, last factorisation */
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
    /* the split in tpart is for this topology while tsplit > 0: the threads it uses (1: serial),
     * asked for tsplit_req threads at tsplit_min segments (plant.c clears it when the topology
     * changes, a re-carved workspace when it is replaced) */
    int tsplit, tsplit_req;
    size_t tsplit_min;
    bool tsplit_sorted; /* the split is of the solve's depth-first order (sorder.active) */
    /* the joint arrays and work.kin were prepared in the solve's depth-first order, which has
     * been left: cbm__mech_work_current prepares them again before a reader outside a solve */
    bool stale;
    /* the last evaluation was fused with the factorisation (cbm__mech_backward_factor): the
     * tree arrays hold the factorisation (mu = 0) of the evaluated state (fready), with its
     * counts, and tmp the backward half of the solve J x = -res (fhalf); cleared by every sweep
     * or solve that could change them */
    bool fready, fhalf;
    bool fwad_ok; /* fwad holds W a D^-1 of the factorisation (the sweeps store it with ground
                   * contact only; cbm__mech_tree_apply computes it when it needs it) */
    size_t fsing, fnonpd;
    bool tip_moment; /* some segment has a tip moment (a component not +-0), cbm__mech_prepare */
    /* Omega was set to the rest rates (rj) for this solve, none NaN: Omega == rj everywhere
     * (cbm_plant_solve; the fast solver reads and clears it) */
    bool at_rest;
} cbm__mech_work;

/* The depth-first order of the solve (solve_order.c): a plant of many segments solved over
 * threads runs with its per-segment arrays in an order of the solver's own, the preorder that takes
 * the children of a segment in increasing index. There a segment's parent is the segment before it
 * or an ancestor still on the path, so the sweeps stream their arrays instead of reaching a
 * lateral's parent anywhere in memory, and a thread's subtrees lie in one stretch of memory.
 * cbm_plant_solve gathers the arrays below into that order, swaps them into the plant for the
 * solve and scatters its results back. The backward sweeps then meet a parent's children in
 * decreasing index as before (the first one is its child of highest index, work.kin), and every
 * sum over all segments runs in the plant's own order (cbm__mech_at), so the results are the
 * same to the bit. */
/* of the topology: gathered when the order is computed, kept between solves (the solve does not
 * write them) */
#define CBM__ORDER_TOPO(X) X(parent) X(cont)
/* what the solve's sweeps read and do not write: gathered at every solve. The rigidities, rest
 * rates, masses and tip loads (rig, rest, mpl, pmass, pmass0, tipf, tipm) are read in a solve by
 * cbm__mech_prepare alone, which turns them into the workspace's joint arrays and reads them from
 * the plant's own arrays through ord; the organ radii (crad) by the organ contact alone, which
 * never runs in the order. Neither is gathered. */
#define CBM__ORDER_IN(X) X(len) X(branch)
/* the state, read and written: gathered for a warm start (a solve from rest sets it before
 * reading it), scattered back */
#define CBM__ORDER_STATE(X) X(omega)
/* what the solve writes before it reads them (an evaluation first): scattered back */
#define CBM__ORDER_OUT(X) X(q) X(pos) X(force) X(moment) X(cmass)
#define CBM__ORDER_ARRAYS(X)                                                                       \
    CBM__ORDER_TOPO(X) CBM__ORDER_IN(X) CBM__ORDER_STATE(X) CBM__ORDER_OUT(X)
typedef struct cbm__mech_order {
    size_t cap;      /* segments the arrays hold */
    bool valid;      /* ord and at are of the plant's topology (plant.c clears it) */
    bool identity;   /* the plant is numbered in that order already: nothing to do */
    bool active;     /* a solve runs on the arrays below: the plant's own are held here */
    uint32_t *ord;   /* the solve's k-th segment is the plant's ord[k] */
    uint32_t *at;    /* the plant's segment i is the solve's at[i] */
    int64_t *parent; /* the plant's arrays in that order (swapped with the plant's) */
    uint8_t *cont;
    double *len;
    cbm_quat *branch;
    cbm_vec3 *omega;
    cbm_quat *q;
    cbm_vec3 *pos, *force, *moment;
    double *cmass;
} cbm__mech_order;

/* work.kin, set by cbm__mech_prepare from the topology: the backward sweeps add what a segment
 * hands to its parent into the parent's accumulators (force and moment of the evaluation, W and
 * psi of the tree factorisation), in decreasing index. Instead of clearing every accumulator before
 * a sweep (a write of the whole array), the first child to arrive (the parent's child of highest
 * index) stores 0.0 + its term, which is the same bits as the cleared accumulator plus the term,
 * and a segment without children reads zero instead of its accumulator. */
#define CBM__KIN_CHILDREN 1u /* some segment has this one as its parent */
#define CBM__KIN_FIRST    2u /* the child of highest index of its parent */
/* acc = acc + x, or 0.0 + x for the first term (the same bits as acc cleared, then added to) */
static inline void cbm__kin_add3(cbm_vec3 *acc, cbm_vec3 x, bool first)
{
    acc->x = (first ? 0.0 : acc->x) + x.x;
    acc->y = (first ? 0.0 : acc->y) + x.y;
    acc->z = (first ? 0.0 : acc->z) + x.z;
}
static inline void cbm__kin_add9(double *acc, const double *x, bool first)
{
#pragma GCC unroll 9
    for (int k = 0; k < 9; k++)
        acc[k] = (first ? 0.0 : acc[k]) + x[k];
}

/* Threads of the tree sweeps (solve_tree.c, "Threads"): the count comes from cbm_solve_def.threads
 * (cbm_plant.threads); they are used only for plants of at least `min_segments` segments
 * (default 50,000; tests lower it to compare small trees). The results are the same to the bit
 * for any count. */
void cbm__mech_tree_min_segments(size_t min_segments);
/* The split's entry per segment in work.tpart: bits 0-27 the subtree size, then the thread
 * (0: the top, swept serially) and the root bit (a subtree's root: its parent is in the top). */
#define CBM__PART_SIZE  0x0fffffffu
#define CBM__PART_SHIFT 28
#define CBM__PART_ROOT  0x80000000u
static inline uint32_t cbm__part_thread(uint32_t e)
{
    return e >> CBM__PART_SHIFT & 7u;
}
/* One backward sweep of the tree factorisation (solve_tree.c): with b and out, the backward half
 * of the solve J out = b too (fused), with only_solve that half alone over an existing
 * factorisation; neg_b: the right-hand side is -b (b the residual). */
typedef struct cbm__mech_fsweep {
    cbm_plant *p;
    const cbm_vec3 *b;
    cbm_vec3 *out;
    double mu;
    bool ground, only_solve, neg_b;
    size_t singular, nonpd; /* counted by the sweep */
    size_t negative;        /* negative eigenvalues of the pivots' symmetric parts (stability) */
} cbm__mech_fsweep;
/// The factorisation at segment i (and the backward half of the solve there); with defer (a
/// subtree's root swept by a thread) what it hands to its parent stays in fw[i] and dm[i].
/// frame: segment i's rotation matrix R = [H L U] (row-major) if the caller has it (the fused
/// sweep, from the same expressions of q[i]), else NULL.
void cbm__mech_factor_one(cbm__mech_fsweep *sw, size_t i, bool defer, const double *frame);
/// Clears what a backward sweep of the factorisation needs cleared: only the ground's force
/// accumulators (work.dfc) when solving with ground contact (W and psi: see work.kin).
void cbm__mech_factor_clear(cbm_plant *p, bool solving);

/* Prefetches of the sweeps: a lateral's parent lies anywhere in memory, and a sweep would wait
 * for its accumulators (a quarter of the factorisation's time at 10^6 segments, measured with
 * perf); the parent of the segment CBM__PF ahead is fetched meanwhile. No effect on the results.
 * (Macros: GCC drops __builtin_prefetch inside a static inline function.) */
#define CBM__PF 16
#define CBM__PREFETCH_PARENT_BWD(par, i, base, elems)                                              \
    do {                                                                                           \
        if ((i) >= CBM__PF) {                                                                      \
            int64_t pf_ = (par)[(i)-CBM__PF];                                                      \
            if (pf_ >= 0) {                                                                        \
                __builtin_prefetch((base) + (size_t)pf_ * (elems), 1, 3);                          \
                __builtin_prefetch((base) + (size_t)pf_ * (elems) + (elems)-1, 1, 3);              \
            }                                                                                      \
        }                                                                                          \
    } while (0)
#define CBM__PREFETCH_PARENT_FWD(par, i, n, base, elems)                                           \
    do {                                                                                           \
        if ((i) + CBM__PF < (n)) {                                                                 \
            int64_t pf_ = (par)[(i) + CBM__PF];                                                    \
            if (pf_ >= 0) {                                                                        \
                __builtin_prefetch((base) + (size_t)pf_ * (elems), 0, 3);                          \
                __builtin_prefetch((base) + (size_t)pf_ * (elems) + (elems)-1, 0, 3);              \
            }                                                                                      \
        }                                                                                          \
    } while (0)
/// The threads the plant's tree sweeps ask for (1: serial; the split may still use fewer).
int cbm__mech_tree_threads(const cbm_plant *p);
/// The threads the plant's tree sweeps use (1: serial), with the split in work.tpart; cached
/// until the topology, the thread count or the workspace changes.
int cbm__mech_tree_split(cbm_plant *p);
/// Runs fn(args + k size) for k = 0 .. t-1: k = 0 on the calling thread, the others each on a
/// thread of its own (on the caller when one cannot start); returns when all are done.
void cbm__mech_run_threads(int t, void (*fn)(void *), void *args, size_t size);

/* One overlapping pair of organ spheres (contact.c), a < b (segment indices). */
typedef struct cbm__mech_pair {
    size_t a, b;
    cbm_vec3 n;   /* unit vector from a's centre to b's, world */
    double dist;  /* m, distance of the centres */
    double over;  /* m, overlap r_a + r_b - dist (> 0) */
    double force; /* N, push on b along n (on a along -n), >= 0 */
    double stiff; /* N/m, d force / d overlap, >= 0 */
} cbm__mech_pair;

/* A uniform grid over spheres, hashed into buckets (counting sort, no allocation per query). */
typedef struct cbm__sphere_grid {
    size_t cap;      /* spheres the arrays hold */
    size_t nbuckets; /* power of two >= 2 cap */
    size_t *bucket;  /* per sphere: its bucket */
    size_t *start;   /* nbuckets + 1 prefix sums */
    size_t *sorted;  /* sphere indices ordered by bucket (stable) */
    cbm_vec3 *sc;    /* centres in that order (contiguous scans) */
    double *sr;      /* radii in that order */
    int64_t *scell;  /* integer cells in that order, 3 per sphere */
} cbm__sphere_grid;

/* Organ-organ contact state and workspace (contact.c). */
typedef struct cbm__mech_contacts {
    bool on;
    double k, s;      /* N/m per metre of overlap; smoothing, m */
    size_t nsph;      /* spheres (segments with a radius) at the last prepare */
    size_t cap;       /* segments the per-segment arrays hold */
    size_t *sph;      /* sphere -> segment */
    cbm_vec3 *centre; /* per sphere, world */
    double *rad;      /* per sphere, m */
    cbm_vec3 *fnode;  /* per segment: sum of pair forces on its distal node, world, N */
    cbm_vec3 *dx;     /* per segment: tangent displacement of the distal node */
    cbm__sphere_grid grid;
    cbm__mech_pair *pairs;
    size_t npairs, pcap; /* found (stored: min(npairs, pcap)) and capacity */
    /* low-rank correction of the tree preconditioner (contact.c): the normal stiffness of up to
     * CBM__CONTACT_RANK touching pairs, Woodbury form */
    bool lr_valid;  /* set up for the current state and factorisation */
    bool lr_off;    /* no correction (tests compare): FGMRES alone */
    int lr_rank;    /* pairs in the correction */
    double *lr_z;   /* rank x 3 cap: T^-1 u_p */
    double *lr_g;   /* rank x 3 cap: g_p (n . (dX_b - dX_a) = g_p . v) */
    double *lr_tmp; /* 3 cap */
    double *lr_m;   /* rank x rank: LU of I + D G^T Z */
    double *lr_d;   /* rank: -f'_p */
    double *lr_c;   /* rank: right-hand side */
    int *lr_piv;    /* rank */
} cbm__mech_contacts;

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
    cbm__mech_contacts contacts; /* organ-organ contact (contact.c) */
    int threads; /* of the tree sweeps: cbm_solve_def.threads of the last solve (0: one per CPU) */

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
    double *ea;        /* N: axial rigidity, sum over rings of E times ring area (fem.c) */
    /* state and loads */
    cbm_vec3 *omega;
    double *pmass;
    double *pmass0; /* point masses the last converged solve balanced (0 for new segments) */
    double *crad;   /* contact radius of the organ at the distal node, m (0: none) */
    cbm_vec3 *tipf, *tipm;
    /* some segment may carry a tip force or moment (some byte of tipf or tipm not +0.0's): set
     * by every writer of them (plant.c), never cleared; the prepare reads them only then */
    bool tip_loads;
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
    cbm__mech_order sorder; /* the solve's depth-first order (solve_order.c) */
    /* the incremental FEM's workspace and growth snapshot (fem.c), kept between calls so that a
     * growth step does not fault fresh pages in again; grow-only */
    void *fem_ws, *fem_snap;
    size_t fem_ws_bytes, fem_snap_bytes;
};

/* ---- plant.c ---- */

/// cbm_segment_state.rate of segment i in O(1) (cbm_plant_segment also visits every ring).
cbm_vec3 cbm__plant_segment_rate(const cbm_plant *p, size_t i);

/* ---- solve_order.c ---- */

/// The least segments for the depth-first order (default 50,000; tests lower it to compare).
void cbm__mech_order_min_segments(size_t min_segments);
/// Whether a solve on one thread uses the order too (default false: its gathering and
/// scattering cost more than its sweeps save, docs/performance.md; tests switch it on).
void cbm__mech_order_serial(bool on);
/// Gathers the plant's arrays into the depth-first order and swaps them in (nothing for a small
/// plant, one solved on one thread, one with organ contact, or one numbered in that order
/// already). With omega false the rotation rates are not gathered: the caller sets every one
/// before anything reads them (a solve from the rest state). CBM_E_NOMEM leaves the plant as it
/// was.
cbm_status cbm__mech_order_enter(cbm_plant *p, bool omega);
/// Swaps the plant's own arrays back and scatters the solve's results into them (nothing when
/// not entered); the workspace is left stale (work.stale) until prepared again.
void cbm__mech_order_leave(cbm_plant *p);
/// The workspace's joint arrays and accumulator marks for the plant's numbering: prepares them
/// again after a solve in the depth-first order (for readers of the workspace after a solve
/// without a prepare of their own, the bend continuation).
void cbm__mech_work_current(cbm_plant *p);
void cbm__mech_order_free(cbm_plant *p);
/// The index in the solve's arrays of the plant's segment k: sums over all segments run over k
/// in the plant's order, so that they add the same terms in the same order whichever order the
/// arrays are in.
static inline size_t cbm__mech_at(const cbm_plant *p, size_t k)
{
    return p->sorder.active ? p->sorder.at[k] : k;
}
/* how many places ahead a pass through the order (the gather, the prepare, the scatter) fetches
 * the plant's lines that it will read or write through ord */
#define CBM__ORDER_AHEAD 24

/* ---- solve_common.c ---- */

/// Ensures the joint workspace for n segments (allocates only when it grows).
cbm_status cbm__mech_work_reserve(cbm_plant *p, int krylov_dim);
void cbm__mech_work_free(cbm_plant *p);
/// Joint arrays from the segment aggregates and loads (times p->load_scale).
void cbm__mech_prepare(cbm_plant *p);
/// Forward sweep: frames and proximal positions from Omega; forces and moments zeroed.
void cbm__mech_forward(cbm_plant *p);
/// The forward sweep of an evaluation: as cbm__mech_forward, but forces and moments are left as
/// they are (the backward sweep, which must follow before anything reads them, sets them all;
/// see work.kin): 48 bytes a segment less to write.
void cbm__mech_forward_eval(cbm_plant *p);
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
/// Backward sweep fused with the factorisation: cbm__mech_backward(p, 0, res, mmax, sumsq) that
/// also factorises the Newton matrix (mu = 0) at the state it evaluates and runs the backward
/// half of the solve J x = -res into work.tmp, segment by segment in the one sweep; the same
/// results to the bit as the three apart. Sets work.fready and work.fhalf (needs the tree
/// arrays: a Krylov workspace; no ground, no organ contact).
double cbm__mech_backward_factor(cbm_plant *p, cbm_vec3 *res, double *mmax, double *sumsq);
/// After a fused evaluation (work.fhalf): the forward half of J x = -res into work.tmp, i.e.
/// what cbm__mech_tree_solve(p, -res, work.tmp, 0, nonpd) would give; returns the singular
/// pivots and *nonpd as that. False (nothing done) when the workspace holds no such half.
bool cbm__mech_tree_solve_fused(cbm_plant *p, size_t *singular, size_t *nonpd);
/// After a fused evaluation (work.fhalf) whose factorisation is exact and stable (no singular
/// pivot, none not positive definite; no ground): the Newton step's solve, its step and the
/// line search's first trial in one forward sweep. At each segment, parents first: the forward
/// half of J x = -res (the bits of cbm__mech_tree_solve_fused) into work.step, the old Omega
/// into work.tmp, Omega += 1.0 step, the frame and node (the bits of cbm__mech_forward_eval).
/// *turn: the largest frame rotation of the full step, rad (the maximum of work.dth, as the
/// trust region reads it). The caller restores Omega from work.tmp where the step is not taken
/// at full length; the frames are then those of the trial until the next evaluation. Clears
/// work.fready and work.fhalf. False (nothing done) where the conditions do not hold.
bool cbm__mech_tree_step_fused(cbm_plant *p, double *turn);
/* The context's counters (cbm__context_counters) after the solve stages' counts: the Newton
 * steps taken by cbm__mech_tree_step_fused, and those of them restored (the step not taken at
 * full length). */
#define CBM__MECH_COUNT_STEP_FUSED    CBM_SOLVE_STAGE_COUNT
#define CBM__MECH_COUNT_STEP_RESTORED (CBM_SOLVE_STAGE_COUNT + 1)
/// Clears work.fready and work.fhalf (the state or the workspace changed).
static inline void cbm__mech_fused_clear(cbm_plant *p)
{
    p->work.fready = p->work.fhalf = false;
}
/// After an unmodified factorisation, perturbs Omega at every joint whose pivot block is not
/// positive definite (by `angle` rad); returns their number.
size_t cbm__mech_tree_perturb_unstable(cbm_plant *p, double angle);
/// out = J^-1 b with the factorisation (out and b may not alias).
void cbm__mech_tree_apply(cbm_plant *p, const cbm_vec3 *b, cbm_vec3 *out);
/* The forward sweep's rotation exponential and renormalisation (solve_common.c), shared with
 * the approx pass, which sets the frames bit for bit as the sweep would and then skips it. */
/* exp of a local rotation vector as a quaternion: short series for small angles (error below
 * 3e-17 for |r| < 0.2), sin/cos otherwise */
static inline cbm_quat cbm__mech_qexp(cbm_vec3 r)
{
    double a2 = r.x * r.x + r.y * r.y + r.z * r.z;
    double c, k;
    if (a2 < 0.04) {
        double h2 = 0.25 * a2;
        c = 1.0 + h2 * (-0.5 + h2 * (1.0 / 24.0 + h2 * (-1.0 / 720.0 + h2 * (1.0 / 40320.0))));
        k = 0.5 * (1.0 + h2 * (-1.0 / 6.0 +
                               h2 * (1.0 / 120.0 + h2 * (-1.0 / 5040.0 + h2 * (1.0 / 362880.0)))));
    } else {
        double a = sqrt(a2);
        c = cos(0.5 * a);
        k = sin(0.5 * a) / a;
    }
    cbm_quat q = {c, r.x * k, r.y * k, r.z * k};
    return q;
}

static inline cbm_quat cbm__mech_qnorm(cbm_quat q)
{
    double n2 = q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z;
    /* one Newton step of 1/sqrt around 1 is enough to keep |q| = 1 to round-off, since the
     * product of unit quaternions drifts by O(1e-16) per step */
    double s = 1.5 - 0.5 * n2;
    cbm_quat r = {q.w * s, q.x * s, q.y * s, q.z * s};
    return r;
}

/* ---- stability.c ---- */

/// Total potential energy of the current state (after a forward sweep, loads as prepared):
/// strain energy sum_i d_i (Omega - rest) . C (Omega - rest) / 2, minus the work of the dead
/// forces (weights at their points, point masses, tip forces), plus the ground's penalty.
double cbm__mech_energy(const cbm_plant *p);
/// Lowest eigenvalue of C^-1 J at the last evaluated state by shifted inverse iteration with the
/// tree factorisation (J + mu S, mu raised until every pivot is positive definite); the
/// eigenvector (Omega components) goes to `mode` (n entries). Uses work.step and work.tmp.
/// Returns the factor-and-solve passes taken; *lambda is NaN if it failed.
size_t cbm__mech_lowest_mode(cbm_plant *p, cbm_vec3 *mode, double *lambda);
/// S-weighted dot product a . S b (S = diag of the joints' rigidities, work.cj).
double cbm__mech_sdot(const cbm_plant *p, const cbm_vec3 *a, const cbm_vec3 *b);
/// v -= (g.S v / g.S g) g: v made S-orthogonal to g (gg = g.S g).
void cbm__mech_deflate(const cbm_plant *p, const cbm_vec3 *g, double gg, cbm_vec3 *v);
/// Factors J + mu S with mu = 0, then 0.05, doubling, until every pivot is positive definite;
/// false once mu passes 1e6 (no usable factorisation). *passes counts the factorisations.
bool cbm__mech_shift_until_definite(cbm_plant *p, double *mu, size_t *passes);
typedef struct cbm__mech_inverse_def {
    double mu;         ///< the shift the factorisation was made with
    const cbm_vec3 *g; ///< when not NULL, every iterate is made S-orthogonal to g
    double gg;         ///< g.S g
    int max_it;        ///< iterations at most
} cbm__mech_inverse_def;
/// Shifted inverse iteration v <- (J + mu S)^-1 S v with the factorisation the caller made.
/// v: the start on entry (any scale), the S-normalised iterate on return; b, x: n scratch
/// vectors each. *theta: the last Rayleigh quotient of S^-1 (J + mu S), NaN if none; *ok is
/// false when an iterate broke down (zero or not finite). Returns the solves taken.
size_t cbm__mech_inverse_iteration(cbm_plant *p, const cbm__mech_inverse_def *d, cbm_vec3 *v,
                                   cbm_vec3 *b, cbm_vec3 *x, double *theta, bool *ok);
/// Largest frame rotation (rad) a change `v` of Omega causes (tangent forward sweep).
double cbm__mech_mode_turn(cbm_plant *p, const cbm_vec3 *v);

/// Relative residual from the max residual and moments.
double cbm__mech_relres(double rmax, double mmax, double *char_moment);

/* ---- contact.c: organ-organ contact ---- */

/* touching pairs held exactly by the preconditioner's low-rank correction */
#ifndef CBM__CONTACT_RANK
#define CBM__CONTACT_RANK 32
#endif
/* least Krylov dimension of the fast solver with organ contact on */
#ifndef CBM__CONTACT_KRYLOV
#define CBM__CONTACT_KRYLOV 60
#endif

/// Ensures the contact workspace for the plant's spheres (no-op without contact).
cbm_status cbm__mech_pairs_reserve(cbm_plant *p);
void cbm__mech_pairs_free(cbm_plant *p);
/// Lists the spheres (segments with a radius); part of cbm__mech_prepare.
void cbm__mech_pairs_prepare(cbm_plant *p);
/// Finds the overlapping pairs at the current positions (after a forward sweep) and their forces
/// into contacts.fnode; part of the backward sweep.
void cbm__mech_pairs_eval(cbm_plant *p);
/// Tangent: adds the pair force changes to dfc (per segment) from the displacements of the
/// proximal nodes (dpos) and the frame rotations (dth) of the tangent's forward sweep.
void cbm__mech_pairs_jvp(cbm_plant *p, const cbm_vec3 *dpos, const cbm_vec3 *dth, cbm_vec3 *dfc);
/// The tree preconditioner's output z = T^-1 v (after cbm__mech_tree_apply) corrected in place
/// for the normal stiffness of the touching pairs (Woodbury); sets the correction up on first use
/// after an evaluation (one tree solve per pair). Returns the passes that took.
size_t cbm__mech_pairs_precond(cbm_plant *p, double *z);
/// Is any pair in contact at the last evaluation?
/* Coefficients of the right Jacobian of the rotation vector r (|r|^2 = t2):
 * J_r = I - c1 [r]x + c2 [r]x^2, c1 = (1 - cos t)/t^2, c2 = (t - sin t)/t^3, by their series
 * below t^2 = 1e-4 (the tangent pass and the tree factorisation). */
static inline void cbm__mech_jr_coeffs(double t2, double *c1, double *c2)
{
    if (t2 < 1e-4) {
        *c1 = 0.5 - t2 / 24.0 + t2 * t2 / 720.0;
        *c2 = 1.0 / 6.0 - t2 / 120.0 + t2 * t2 / 5040.0;
    } else {
        double t = sqrt(t2);
        *c1 = (1.0 - cos(t)) / t2;
        *c2 = (t - sin(t)) / (t2 * t);
    }
}

static inline bool cbm__mech_pairs_active(const cbm_plant *p)
{
    return p->contacts.on && p->contacts.npairs > 0;
}
/// Grid: ensures room for n spheres.
cbm_status cbm__sphere_grid_reserve(cbm_context *ctx, cbm__sphere_grid *g, size_t n);
void cbm__sphere_grid_free(cbm_context *ctx, cbm__sphere_grid *g);
/// All pairs (i < j) of the n spheres (n <= the reserved count) whose centres are closer than
/// r_i + r_j, in a deterministic order; at most cap are stored in out (a = i, b = j, n, dist,
/// over; force and stiff zero); returns the number found. O(n + pairs) for spheres of comparable
/// size (cell = the largest diameter).
size_t cbm__sphere_grid_pairs(cbm__sphere_grid *g, const cbm_vec3 *c, const double *r, size_t n,
                              cbm__mech_pair *out, size_t cap);

/* ---- solve_relax.c / solve_newton.c ---- */
cbm_status cbm__mech_solve_relax(cbm_plant *p, const cbm_solve_def *def, size_t max_passes,
                                 cbm_solve_stats *st);
cbm_status cbm__mech_solve_newton(cbm_plant *p, const cbm_solve_def *def, size_t max_passes,
                                  cbm_solve_stats *st);

/// Whether the fast solver's evaluations fuse the tree factorisation (default on; the results
/// are the same to the bit either way: tests switch it off to compare).
void cbm__mech_newton_fuse(bool on);
/// Whether a direct Newton step fuses its solve with the line search's first trial
/// (cbm__mech_tree_step_fused; default on, the same bits either way: tests switch it off).
void cbm__mech_newton_fuse_step(bool on);

/* ---- solve_approx.c ---- */

/// Method A on the plant (CBM_MECH_APPROX): sets every joint's Omega from the approximative
/// angle generator of its axis, then evaluates; after cbm__mech_prepare.
cbm_status cbm__mech_solve_approx(cbm_plant *p, const cbm_solve_def *def, cbm_solve_stats *st);

#endif
