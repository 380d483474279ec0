/* cambium grow --sway: the grown tree swaying in the wind (docs/dynamics.md, "Sway of a grown
 * tree"). */
#ifndef CBM_CLI_GROW_SWAY_H
#define CBM_CLI_GROW_SWAY_H

#include "cambium/cambium.h"
#include "cambium/dynamics.h"

/// What --sway asks for.
typedef struct cli_sway {
    double seconds; ///< simulated time, s (> 0: sway on)
    double wind;    ///< mean speed at 10 m, m/s
    double gust;    ///< turbulence intensity sigma_u / U
    double dt;      ///< time step, s
    double fps;     ///< animation frames per second
    double damping; ///< structural damping ratio
    long seed;      ///< gust seed
} cli_sway;

/// Defaults: wind 10 m/s, gust 0.2, dt 2 ms, 25 fps, damping 0.03, seed 1.
cli_sway cli_sway_default(void);

/// Simulates the sway of the plant (at equilibrium) and writes the animations (glb) and the
/// tracked tips' displacements (csv). CBM status of the first failure.
cbm_status cli_grow_sway(cbm_context *ctx, const cbm_plant *plant, const cli_sway *o,
                         const char *const *glb, int nglb, const char *const *csv, int ncsv,
                         bool timing);

#endif
