/* cambium: a growing planar elastica under control (Tresierras 2009, ch. 3): tip (primary)
 * growth with an optional preferred-angle law (3.34), lateral accretion (secondary growth) with a
 * taper law, remodeling (a time-varying modulus E(t)), and the evolution law of the intrinsic
 * curvature kappa^g, rigidity-weighted, with a control curvature kappa^c (asymmetric residual
 * growth stress, tension wood) and a curvature kappa_I^g independent of stiffness changes:
 *
 *     d(D kappa^g)/dt = Ddot (kappa + kappa^c) + D d(kappa_I^g)/dt          (3.1)
 *     kappa^g_n = [D_{n-1} kappa^g_{n-1} + (D_n - D_{n-1})(kappa_{n-1} + kappa^c_n)] / D_n
 *                 + (kappa_I,n^g - kappa_I,n-1^g)                            (3.18)/(3.26)
 *
 * held constant where D decreases (the decreasing-stiffness rule, §3.7). The inverse problem
 * (3.32)/(3.33) finds the kappa^c that keeps the present configuration static. Quasi-static: one
 * equilibrium per time step, followed by continuation (and a jump to the lowest-energy stable
 * equilibrium when the followed one disappears at a fold). docs/growth.md has the law, its
 * relation to the ring memory of the mechanical plant, and the cases of Table 3.1.
 *
 * The rod lives on a grid of equal cells (h = length0 / cells); a growth step adds
 * tip_growth / h cells at the tip. Each cell has a constant radius, D, weight per length and
 * kappa^g; the evolution law is applied per cell to its mean present curvature (the turn of the
 * tangent across the cell over h). Units: any consistent set (SI, or the thesis' gf, cm).
 *
 *     cbm_elastica_growth_def d = cbm_elastica_growth_def_default();   // Case A of Table 3.1
 *     cbm_elastica_growth *g;
 *     cbm_elastica_grow(ctx, &d, &g);
 *     ... g->frames[g->n_frames - 1].tip_y ...
 *     cbm_elastica_growth_destroy(ctx, g);
 */
#ifndef CAMBIUM_ELASTICA_GROWTH_H
#define CAMBIUM_ELASTICA_GROWTH_H

#include "cambium/elastica.h"

#ifdef __cplusplus
extern "C" {
#endif

/// How lateral accretion adds wood at each step.
typedef enum cbm_elastica_taper {
    CBM_ELASTICA_TAPER_LINEAR,  ///< a layer `layer` thick at the base tapering linearly to 0 at
                                ///< the new tip (base radius R0 + N layer after N steps)
    CBM_ELASTICA_TAPER_UNIFORM, ///< a layer `layer` thick on every cell that existed before
    CBM_ELASTICA_TAPER_STEP,    ///< D of a cell rises as a first-order step with its age a:
                                ///< D/D_birth = 1 + (stiffness_ratio - 1)(1 - exp(-a / tau))
} cbm_elastica_taper;

/// The evolution law of kappa^g.
typedef enum cbm_elastica_law {
    CBM_ELASTICA_LAW_GROWTH,  ///< (3.1)/(3.18)/(3.26) with kappa^c and kappa_I^g
    CBM_ELASTICA_LAW_REMODEL, ///< the remodeling-only law (3.19)/(3.22)/(3.25): kappa^c = 0
    CBM_ELASTICA_LAW_NONE,    ///< kappa^g frozen (no evolution; Fig. 3.4b, 3.5)
} cbm_elastica_law;

/// Where kappa^c comes from.
typedef enum cbm_elastica_control {
    CBM_ELASTICA_CONTROL_GIVEN,  ///< the input (control_fn, else control_curvature)
    CBM_ELASTICA_CONTROL_STATIC, ///< the inverse problem (3.33): the kappa^c that keeps every
                                 ///< cell that existed before a step at its present curvature
} cbm_elastica_control;

/// A field f(s, t) given by the caller (s from the base, t the time).
typedef double (*cbm_elastica_field_fn)(void *ud, double s, double t);

typedef struct cbm_elastica_growth_def {
    double length0;    ///< L0 at t = 0 (> 0)
    size_t cells;      ///< cells in L0 (h = length0 / cells); tip_growth must be a multiple of h
    double tip_growth; ///< Delta L added at the tip per step (>= 0)
    size_t steps;      ///< N growth steps
    double dt;         ///< time per step (> 0)
    size_t substeps;   ///< equilibria per step: 1 = the discrete law (3.18); more integrates the
                       ///< continuous form (3.30) by explicit Euler in time (the tip segment is
                       ///< added at the first substep, the layer and E(t) spread over them)
    double theta_base; ///< clamp angle, rad from the horizontal (counter-clockwise)
    double radius0;    ///< R0, the radius of new (primary) material (> 0)
    double layer;      ///< Delta R, the layer of secondary growth per step (>= 0)
    cbm_elastica_taper taper;
    double stiffness_ratio, stiffness_tau; ///< CBM_ELASTICA_TAPER_STEP (ratio >= 1, tau > 0)
    double youngs;                         ///< E at t = 0 (> 0)
    double youngs_final, youngs_tau;       ///< remodeling: E(t) = E_f + (E - E_f) exp(-t / tau);
                                           ///< tau 0: E constant
    double density;                        ///< rho*, mass per volume (>= 0)
    double gravity;                        ///< g (>= 0); weight per length rho* pi R^2 g
    double segment_load;                   ///< F_N, an extra load per tip_growth of length (>= 0)
    bool segment_load_point;               ///< F_N as a point force at the tip of each Delta L of
                             ///< length instead of spread over it (Yamamoto & Yoshida)
    double tip_load;        ///< a downward force at the tip
    double rest_curvature0; ///< kappa_o^g of the initial rod
    bool preferred;         ///< new tip material from the preferred-angle law (3.34)
    double preferred_angle; ///< theta^d, rad: kappa_o^g = (theta^d - theta_tip) / Delta L
    cbm_elastica_law law;
    cbm_elastica_control control;
    double control_curvature; ///< kappa^c where control_fn is NULL (1/length)
    cbm_elastica_field_fn control_fn;
    void *control_ud;
    double induced_rate;              ///< d kappa_I^g / dt where induced_fn is NULL
    cbm_elastica_field_fn induced_fn; ///< kappa_I^g(s, t) itself (not its rate)
    void *induced_ud;
    int side; ///< at t = 0, of several stable equilibria of equal energy the one whose tip
              ///< leans to +x (side >= 0, default) or to -x (side < 0)
} cbm_elastica_growth_def;

/// Case A of Table 3.1: E 1, rho* 4.231, R0 1.05, Delta R 0.01 (linear taper), L0 1, Delta L
/// 0.1, 2 steps, g 1, clamped vertically, 100 cells; the growth law with kappa^c = 0.
CBM_API cbm_elastica_growth_def cbm_elastica_growth_def_default(void);

/// One cell of a frame. Positions are of the cell's distal end, relative to the base.
typedef struct cbm_elastica_growth_cell {
    double s;          ///< the cell's mid arc length
    double x, y;       ///< distal end, present configuration
    double theta;      ///< tangent angle at the distal end, rad
    double xg, yg;     ///< distal end of the growth (unloaded) configuration, same clamp
    double kappa;      ///< mean present curvature of the cell
    double kappa_g;    ///< intrinsic curvature kappa^g
    double kappa_c;    ///< the control curvature of the last step (0 where D did not rise)
    double stiffness;  ///< D
    double weight;     ///< weight per length (self-weight + spread segment load)
    double radius;     ///< R
    double k_ss, k_as; ///< K_SS^g, K_AS^g of (3.36): symmetric and asymmetric parts
    double k_i;        ///< K_I^g / D
    double kappa_o_g;  ///< kappa_o^g, the cell's intrinsic curvature when it was made
    double born;       ///< time the cell was made
} cbm_elastica_growth_cell;

/// The state at the end of a step (frame 0: the initial equilibrium).
typedef struct cbm_elastica_growth_frame {
    double time, length;
    double theta_tip;      ///< rad
    double tip_x, tip_y;   ///< relative to the base
    double strain_base;    ///< nu(0)
    double moment_base;    ///< m(0) = D(0) nu(0)
    double stiffness_base; ///< D(0)
    double energy;         ///< V of the equilibrium
    int index;             ///< Morse index of the equilibrium (0 stable)
    bool jumped;           ///< the followed equilibrium was lost (a fold): the rod jumped to the
                           ///< lowest-energy stable equilibrium at the clamp angle
    double hold_error;     ///< CONTROL_STATIC: max |theta - target| at the held cells' ends, rad
    size_t n_cells;
    cbm_elastica_growth_cell *cells; ///< base to tip
} cbm_elastica_growth_frame;

typedef struct cbm_elastica_growth {
    cbm_elastica_growth_frame *frames; ///< steps + 1
    size_t n_frames;
    double cell_length; ///< h
} cbm_elastica_growth;

/// Runs the growth. CBM_E_INVALID for a bad def, CBM_E_NOT_CONVERGED when no equilibrium is
/// found, CBM_E_RUNTIME when the inverse problem has no kappa^c (D does not rise at a held cell
/// that must change). *out is released with cbm_elastica_growth_destroy.
CBM_API cbm_status cbm_elastica_grow(cbm_context *ctx, const cbm_elastica_growth_def *def,
                                     cbm_elastica_growth **out);
CBM_API void cbm_elastica_growth_destroy(cbm_context *ctx, cbm_elastica_growth *g);

/// The growth def of a parsed elastica spec with steps > 0 (docs/elastica.md "Growth"): L0 =
/// length_initial (or length), Delta L = (length - L0) / steps, h = length / segments, R0 =
/// radius, Delta R = (radius_final - radius) / steps, angle in degrees, tip_load + tip_mass g,
/// rest_curvature as kappa_o^g, and the growth keys. CBM_E_INVALID (reported) when L0 or Delta L
/// is not a whole number of cells.
CBM_API cbm_status cbm_elastica_spec_growth(cbm_context *ctx, const cbm_elastica_spec *spec,
                                            cbm_elastica_growth_def *out);

#ifdef __cplusplus
}
#endif
#endif
