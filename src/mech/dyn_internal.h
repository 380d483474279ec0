/* Private layout of the linearised dynamics (src/mech/dyn_*.c): the plant's equilibrium copied into
 * the arrays of the O(n) tree operators (tree.c), used by the modes (modes.c) and the time stepping
 * (motion.c). */
#ifndef CBM_DYN_INTERNAL_H
#define CBM_DYN_INTERNAL_H

#include "cambium/dynamics.h"
#include "core/core.h"

#include <math.h>

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
    double *pc;    /* 10 per segment: body in compact form (cbm__dyn_pz) */
    double *ak;    /* 9 per joint: A = K_el + sym G */
    double *width; /* a + b of the outer section, m (the wind's drag, drag.c) */
    double *pmass; /* point mass at the distal node, kg */
    cbm_vec3 base; /* the plant's base position, m (world = base + relative) */
    /* factorisation of sK K + sM M (tree.c) */
    double fk, fm; /* its sK and sM */
    double *dinv;  /* 9 per joint */
    double *dl;    /* 18 per joint: D^-1 L for L = B + S^T Pi (3 x 6); as L^T D^-1 u =
                    * (D^-1 L)^T u for the symmetric D, the sweeps need no L */
    double *pi;    /* 36 per joint: articulated block (work of the factorisation) */
    /* work */
    double *z;   /* 6 per segment */
    double *acc; /* 6 per segment */
    double *u;   /* 3 per joint: D^-1 u of the last elimination (cbm__dyn_solve, the fused step) */
} cbm__dyn;

/* The per-segment kernels of the sweeps, shared by the operators of tree.c and the fused step of
 * motion.c (inline: they run once per segment per sweep). */

/* The sweeps read or update the parent's 6 doubles, and a lateral's parent can be anywhere before
 * it (a shoot added years after its mother's segments): a cache miss the loop waits for unless the
 * line is asked for some segments ahead (CBM__AHEAD). A hint only: no effect on the results. */
#if defined(__GNUC__) || defined(__clang__)
#define CBM__PREFETCH(p) __builtin_prefetch(p)
#else
#define CBM__PREFETCH(p) ((void)(p))
#endif
#define CBM__AHEAD 12

/// Asks for the parent's 6 doubles of arr of segment k (if it exists and has a parent). A macro:
/// GCC finds a function around the hint free of effects and drops its calls before inlining.
#define CBM__DYN_AHEAD(parent, n, k, arr)                                                          \
    do {                                                                                           \
        size_t k_ = (k);                                                                           \
        if (k_ < (n) && (parent)[k_] >= 0)                                                         \
            CBM__PREFETCH((arr) + 6 * (parent)[k_]);                                               \
    } while (0)

/// z += S q = (q, x x q): the twist of a rotation q about the joint's node x (tree.c), 6 doubles.
static inline void cbm__dyn_sq(const cbm_vec3 *x, const double *q, double *z)
{
    z[0] += q[0];
    z[1] += q[1];
    z[2] += q[2];
    z[3] += x->y * q[2] - x->z * q[1];
    z[4] += x->z * q[0] - x->x * q[2];
    z[5] += x->x * q[1] - x->y * q[0];
}

/// cbm__dyn_sq for a rotation given as three numbers (the sweeps' own values, kept out of memory:
/// stored one by one and read back in pairs they would stall the loads).
static inline void cbm__dyn_sq3(const cbm_vec3 *x, double q0, double q1, double q2, double *z)
{
    z[0] += q0;
    z[1] += q1;
    z[2] += q2;
    z[3] += x->y * q2 - x->z * q1;
    z[4] += x->z * q0 - x->x * q2;
    z[5] += x->x * q1 - x->y * q0;
}

/// out = S^T (n, f) = n - x x f, the joint's share of a wrench w = (n, f).
static inline void cbm__dyn_stw(const cbm_vec3 *x, const double *w, double *out)
{
    out[0] = w[0] - (x->y * w[5] - x->z * w[4]);
    out[1] = w[1] - (x->z * w[3] - x->x * w[5]);
    out[2] = w[2] - (x->x * w[4] - x->y * w[3]);
}

/// t = g + P z for the spatial inertia P = [[J, [h]], [[h]^T, m I]] in the 10 doubles pc: the
/// symmetric J about the origin (xx, yy, zz, xy, xz, yz), the first moment h, the mass m.
static inline void cbm__dyn_pz(const double *pc, const double *z, const double *g, double *t)
{
    t[0] = g[0] + pc[0] * z[0] + pc[3] * z[1] + pc[4] * z[2] + pc[7] * z[5] - pc[8] * z[4];
    t[1] = g[1] + pc[3] * z[0] + pc[1] * z[1] + pc[5] * z[2] + pc[8] * z[3] - pc[6] * z[5];
    t[2] = g[2] + pc[4] * z[0] + pc[5] * z[1] + pc[2] * z[2] + pc[6] * z[4] - pc[7] * z[3];
    t[3] = g[3] + pc[9] * z[3] + z[1] * pc[8] - z[2] * pc[7];
    t[4] = g[4] + pc[9] * z[4] + z[2] * pc[6] - z[0] * pc[8];
    t[5] = g[5] + pc[9] * z[5] + z[0] * pc[7] - z[1] * pc[6];
}

/// s = D^-1 u for the joint's inverse pivot di (3x3), the elimination's step from the tips.
static inline void cbm__dyn_dinv_u(const double *di, const double *u, double *s)
{
    for (int i = 0; i < 3; i++)
        s[i] = di[3 * i] * u[0] + di[3 * i + 1] * u[1] + di[3 * i + 2] * u[2];
}

/// out = L^T s (6) for a joint's L (3x6); with D^-1 L and u, L^T D^-1 u: the wrench the
/// elimination passes on to the parent.
static inline void cbm__dyn_lt_s(const double *lm, const double *s, double *out)
{
    for (int j = 0; j < 6; j++)
        out[j] = lm[j] * s[0] + lm[6 + j] * s[1] + lm[12 + j] * s[2];
}

/// q = s - D^-1 L zp: the back-substitution of a joint from s = D^-1 u and the parent's twist.
static inline void cbm__dyn_back_sub(const double *dl, const double *s, const double *zp, double *q)
{
    for (int i = 0; i < 3; i++)
        q[i] = s[i] - (dl[6 * i] * zp[0] + dl[6 * i + 1] * zp[1] + dl[6 * i + 2] * zp[2] +
                       dl[6 * i + 3] * zp[3] + dl[6 * i + 4] * zp[4] + dl[6 * i + 5] * zp[5]);
}

/// Copies the plant's equilibrium (its state must be current: after a solve or an evaluation)
/// into d. CBM_E_INVALID for an empty plant or a segment without mass.
cbm_status cbm__dyn_build(const cbm_plant *p, cbm__dyn *d);
void cbm__dyn_free(cbm__dyn *d);
/// y = (sk K + sm M) v, 3n doubles each (v and y must not alias).
void cbm__dyn_apply(cbm__dyn *d, double sk, double sm, const double *v, double *y);
/// Factorises sk K + sm M; returns the number of pivot blocks that are not positive definite
/// (0: the matrix is positive definite), or (size_t)-1 if one is singular.
size_t cbm__dyn_factor(cbm__dyn *d, double sk, double sm);
/// x = (sk K + sm M)^-1 b with the last factorisation (x and b may alias; u is used as work).
void cbm__dyn_solve(cbm__dyn *d, const double *b, double *x);
/// y = M x for the x of the last cbm__dyn_solve: its twists are still in d->z, so only the sweep
/// from the tips is needed (the product after a solve, in the Lanczos steps of modes.c).
void cbm__dyn_mass_solved(cbm__dyn *d, double *y);
/// cbm_plant_modes with the Lanczos run's basis swept (Gram-Schmidt) at every step when full
/// (else only where the orthogonality estimates ask, dyn_modes.c); steps and sweeps (either may be
/// NULL) receive the steps of the last run and how many of them swept.
cbm_status cbm__plant_modes(const cbm_plant *plant, size_t count, double *freqs_hz, double *shapes,
                            bool full, size_t *steps, size_t *sweeps);
/// f += the generalised force of a force F (world) at the distal node of seg.
void cbm__dyn_point_force(const cbm__dyn *d, size_t seg, cbm_vec3 F, double *f);
/// Displacement of the distal node of seg for the rotations q.
cbm_vec3 cbm__dyn_node_disp(const cbm__dyn *d, const double *q, size_t seg);

/// The twists z (6 per segment: rotation, velocity of the origin) of the joint rates v: a point p
/// of segment s moves at z[3..6) + z[0..3) x p (relative to the base).
void cbm__dyn_twists(const cbm__dyn *d, const double *v, double *z);
/// f += the generalised forces of per-segment wrenches w (6 per segment: moment about the
/// origin, force), each acting on its segment; w is overwritten (summed over the subtrees).
void cbm__dyn_wrench_force(const cbm__dyn *d, double *w, double *f);

/// Checks a wind definition (wind.c): CBM_E_INVALID with the reason.
cbm_status cbm__wind_check(cbm_context *ctx, const cbm_wind_def *d);
/// The drag constants 1/2 rho C_d A (kg/m) of the leaves and of the fruit of n segments from
/// d->leaf_area and d->fruit_mass (wind.c); *leaf or *fruit NULL when its array is; free with
/// cbm__free (n doubles). CBM_E_INVALID for a negative or non-finite entry.
cbm_status cbm__wind_organs(cbm_context *ctx, const cbm_wind_def *d, size_t n, double **leaf,
                            double **fruit);
/// The factor (|w| / U_0)^B above U_0 (1 below) by which a leaf's drag coefficient falls as it
/// reconfigures (wind.c's formula, docs/dynamics.md).
static inline double cbm__leaf_reconfiguration(double vogel, double u0, double w)
{
    return vogel != 0.0 && w > u0 ? pow(w / u0, vogel) : 1.0;
}

/* Gust series (gust.c): u'(t) = sum_k amp_k cos(omega_k t + phase_k); with a coherence decay,
 * a field over a grid of np = nx ny points in the plane normal to the wind (origin o, lateral
 * axis ex, vertical axis ey, spacings hx, hy): u'_j(t) = sum_k (are_kj cos omega_k t - aim_kj
 * sin omega_k t), the values of the last time asked kept in gv. */
typedef struct cbm__gust {
    int32_t n;
    double *amp, *omega, *phase;
    int32_t np, nx, ny;
    cbm_vec3 o, ex, ey;
    double hx, hy;
    double *are, *aim; /* n * np, harmonic after harmonic */
    double *gv;        /* np */
    double t_last;
    bool have;
} cbm__gust;
/// Synthesises the series for reference speed u_ref (no harmonics when the intensity or u_ref is
/// 0).
cbm_status cbm__gust_build(cbm_context *ctx, const cbm_gust_def *g, const cbm_wind_def *w,
                           double u_ref, cbm__gust *out);
double cbm__gust_at(const cbm__gust *g, double t);
void cbm__gust_free(cbm_context *ctx, cbm__gust *g);
/// The one-sided spectrum (m^2/s^2/Hz) of the gusts at frequency f (Hz), and the length scale.
double cbm__gust_spectrum(const cbm_gust_def *g, double sigma, double length, double u_ref,
                          double f);
double cbm__gust_length(const cbm_gust_def *g, const cbm_wind_def *w);
/// Turns a built series (out of cbm__gust_build, with harmonics) into the spatially correlated
/// field of g->coherence_decay > 0 over the bounding box of the points pts[0..npts) (relative to
/// the base) seen along the wind's direction dir (unit); nothing when the decay is 0.
cbm_status cbm__gust_field_build(cbm_context *ctx, const cbm_gust_def *g, double u_ref,
                                 cbm_vec3 dir, const cbm_vec3 *pts, size_t npts, cbm__gust *out);
/// The field's values at its grid points at time t (cached: the drag's iterations ask the same t).
const double *cbm__gust_field_at(cbm__gust *g, double t);
/// The 4 grid points and bilinear weights of the point p (its projection, clamped to the grid).
void cbm__gust_field_weights(const cbm__gust *g, cbm_vec3 p, int32_t idx[4], double wt[4]);

/* Drag of the wind on the moving plant (drag.c): per segment, the drag point (the segment's
 * midpoint) and axis, the drag constants, and the mean speed factors of the profile there. */
typedef struct cbm__drag {
    size_t n;
    cbm_vec3 dir; /* unit, where the wind blows to */
    double u_ref; /* m/s */
    cbm_vec3 *c;  /* midpoint, relative to the base */
    cbm_vec3 *h;  /* axis */
    double *kw;   /* 1/2 rho C_d (a + b) l, kg/m */
    double *ko;   /* 1/2 rho C_d,organ A, kg/m (0: none) */
    double *uc;   /* U(z)/U_ref at the midpoint */
    double *ue;   /* U(z)/U_ref at the distal node */
    cbm__gust gust;
    int32_t *gi;   /* with a gust field: 4 grid points of the midpoint, 4 of the distal node */
    double *gw;    /* their bilinear weights */
    double *leaf;  /* 1/2 rho C_d,leaf A_leaf at the distal node, kg/m (NULL: none) */
    double *fruit; /* 1/2 rho C_d,fruit A_fruit at the distal node, kg/m (NULL: none) */
    double vogel, vogel_speed; /* the leaves' reconfiguration: exponent B and onset U_0 */
    double *z, *w;             /* work: 6 per segment each */
} cbm__drag;
/// Reads the wind's data off the dynamics' geometry (d) and the plant's sections.
cbm_status cbm__drag_build(const cbm__dyn *d, const cbm_wind_def *wind, double u_ref,
                           const cbm_gust_def *gust, cbm__drag *out);
void cbm__drag_free(cbm_context *ctx, cbm__drag *g);
/// f = the generalised drag forces at time t for joint rates v and base velocity vb.
void cbm__drag_force(cbm__drag *g, const cbm__dyn *d, double t, const double *v, cbm_vec3 vb,
                     double *f);
/// The mean wind's drag wrenches per segment (6 each, as cbm__dyn_wrench_force takes them), of
/// the wood at the midpoints into ww and of the organs at the distal nodes into wo, for joint
/// rates v and base velocity vb (the gust field's share per grid point: modal.c).
void cbm__drag_wrenches(cbm__drag *g, const cbm__dyn *d, const double *v, cbm_vec3 vb, double *ww,
                        double *wo);

/* The modal reduction of a motion (modal.c, CBM_MOTION_MODAL): K mass-normalised modes phi_r
 * (M-orthonormal, phi_r^T K phi_r = w_r^2), the modal coordinates eta (q = sum eta_r phi_r) and
 * their rates, and the projections of the loads that do not change during a run. */
typedef struct cbm__modal {
    size_t k;
    double *phi;            /* k x 3n, mode after mode */
    double *w, *fhz;        /* k: rad/s, Hz */
    double *eta, *ed, *edd; /* k: coordinates, rates, accelerations */
    double *p;              /* k: forces added for the next step, projected */
    double *cr;             /* k: Rayleigh damping of each mode, alpha + beta w^2 */
    double *gb;             /* 3k: phi_r^T of the base's fictitious force per unit acceleration */
    bool gb_valid;
    /* wind, linearised about the still plant: g(t, v) ~ s|s| g_mean + |s| (G v + G_b v_base),
     * s = U_ref(t) / U_ref (the gusts are uniform, the drag is homogeneous of degree 2) */
    bool wind;
    double s_last; /* |s| the matrix a was factorised for (NAN: none) */
    double *pw;    /* k: phi^T g_mean */
    double *ca;    /* k x k: -phi^T G phi (symmetric, positive semi-definite) */
    double *cb;    /* k x 3: phi^T G_b */
    double *a, *r; /* k x k: the step's matrix (Cholesky factor); k: work */
    double *qbuf;  /* 3n: the rebuilt rotations */
    bool q_stale;
    struct cbm__modal_ext *x; /* the gust field's projections, the static correction (modal.c) */
} cbm__modal;

/* A motion (motion.c; its modal reduction in modal.c). */
struct cbm_motion {
    cbm__dyn d;
    size_t nq;
    double dt, t, alpha, beta;
    double *q, *v, *a, *f, *w1, *w2, *y;
    /* loads in time: the wind's drag (drag.c) and the base's motion */
    bool wind;
    cbm__drag drag;
    double *g, *g2, *rhs; /* 3n: drag forces of two iterates, the step's right-hand side */
    double *wb;           /* 6n: the base's fictitious wrenches */
    int iters;
    bool base_moves;
    cbm_vec3 ba_next, ba, bv, bd; /* the base's acceleration (next step, now), velocity, disp */
    /* the fused step (fused_step below): per segment the carried sums of the backward sweep
     * (6), the twists of the solution (6) and of the next step's right-hand side vector (6, and
     * 3 for the damping's) */
    double *gam, *zs, *zw, *thw;
    bool zw_valid;     /* zw and thw hold the twists of the current state's vectors */
    bool forced;       /* f holds forces added since the last step */
    cbm__modal *modal; /* CBM_MOTION_MODAL: the reduced state (modal.c); NULL for the full one */
};

/* The modal motion (modal.c): the public cbm_motion_* calls hand over when m->modal is set. */
cbm_status cbm__modal_create(const cbm_plant *plant, cbm_motion *m, size_t count, double cut_hz,
                             double damping_ratio, bool static_correction);
void cbm__modal_free(cbm_context *ctx, cbm__modal *md, size_t nq);
cbm_status cbm__modal_step(cbm_motion *m);
cbm_status cbm__modal_add_force(cbm_motion *m, size_t seg, cbm_vec3 force);
cbm_status cbm__modal_start_deflected(cbm_motion *m, size_t seg, cbm_vec3 force);
cbm_status cbm__modal_start_state(cbm_motion *m, const double *q, const double *v);
cbm_status cbm__modal_set_wind(cbm_motion *m, cbm__drag *nd);
cbm_status cbm__modal_start_wind_static(cbm_motion *m);
void cbm__modal_energies(const cbm_motion *m, double *kinetic, double *potential);
cbm_vec3 cbm__modal_displacement(const cbm_motion *m, size_t seg);
const double *cbm__modal_rotations(const cbm_motion *m);

#endif
