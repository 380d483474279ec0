/* cambium grow --sway: the grown tree swaying in the wind (docs/dynamics.md, "Sway of a grown
 * tree"). */
#ifndef CBM_CLI_GROW_SWAY_H
#define CBM_CLI_GROW_SWAY_H

#include "cambium/cambium.h"
#include "cambium/dynamics.h"
#include "cambium/lsys.h"

/// What --sway asks for.
typedef struct cli_sway {
    double seconds;    ///< simulated time, s (> 0: sway on)
    double wind;       ///< mean speed at 10 m, m/s
    double gust;       ///< turbulence intensity sigma_u / U
    double dt;         ///< time step, s
    double fps;        ///< animation frames per second
    double damping;    ///< structural damping ratio
    long seed;         ///< gust seed
    double organ_area; ///< drag area of the organs (point masses) per kg, m^2/kg; 0: none
    double modes;      ///< > 0: the modal motion of the lowest this many modes; 0: full order
    double coherence;  ///< Davenport decay constant of the gust field; 0: one series
    long grid;         ///< grid points of the gust field along the crown's longer side
    /// --organ-drag: per segment leaf area (m^2) and fruit mass (kg), NULL: none
    const double *leaf_area, *fruit_mass;
    double fruit_density; ///< kg/m^3 of the fruit (the model's)
} cli_sway;

/// Defaults: wind 10 m/s, gust 0.2, dt 2 ms, 25 fps, damping 0.03, seed 1, no organ drag.
cli_sway cli_sway_default(void);

/// Simulates the sway of the plant (at equilibrium) and writes the animations (glb) and the
/// tracked tips' displacements (csv). CBM status of the first failure.
cbm_status cli_grow_sway(cbm_context *ctx, const cbm_plant *plant, const cli_sway *o,
                         const char *const *glb, int nglb, const char *const *csv, int ncsv,
                         bool timing);

/// The recorder of a motion's outputs, shared by grow --sway and run's sway: outputs: every
/// segment a rigid node of the animations (glb) keyed at fps frames per second, and the tracked
/// tips' displacements (csv, written beside the target and renamed by cli_sway_rec_finish).
typedef struct cli_sway_rec cli_sway_rec;
/// A recorder for the motions of `plant` (at the equilibrium they are about); cmd names the
/// command in messages.
cbm_status cli_sway_rec_begin(cbm_context *ctx, const cbm_plant *plant, double fps,
                              const char *const *glb, int nglb, const char *const *csv, int ncsv,
                              const char *cmd, cli_sway_rec **out);
/// Records a frame of the motion's state after step `step` (0: the start) when it falls on a
/// frame, or when last.
cbm_status cli_sway_rec_step(cli_sway_rec *w, cbm_motion *m, long step, bool last);
/// Writes the outputs if st is CBM_OK (else removes what was begun) and frees w; the first
/// failure.
cbm_status cli_sway_rec_finish(cli_sway_rec *w, cbm_status st);
/// Frees w without writing its outputs.
void cli_sway_rec_discard(cli_sway_rec *w);

/// run's sway: outputs (the L+C dialect's Sway(), cbm_lsys_set_sway_observer): every Sway()
/// call starts a new recording (the last call's motion is written).
typedef struct cli_run_sway {
    cbm_context *ctx;
    const char *glb[8], *csv[8];
    int nglb, ncsv;
    cli_sway_rec *rec;
    long step;
} cli_run_sway;
/// The observer (ud: a cli_run_sway).
cbm_status cli_run_sway_observe(void *ud, const cbm_plant *plant, cbm_motion *motion,
                                cbm_lsys_sway_phase phase);

#endif
