/* The bend workbench's motion: the spec's time keys on the solved rod (docs/bend.md). */
#include "cambium/bend.h"
#include "mech/dyn_internal.h"
#include "core/vecmath.h"
#include "mech/mech_internal.h"

#include <math.h>

cbm_status cbm_bend_motion(const cbm_plant *plant, const cbm_bend_spec *spec, cbm_motion_row_fn row,
                           void *user, double *dt_used)
{
    if (!plant || !spec || !row || !(spec->duration > 0.0))
        return CBM_E_INVALID;
    size_t n = cbm_plant_segment_count(plant);
    if (n == 0)
        return CBM_E_INVALID;
    cbm_motion_def md = cbm_motion_def_default();
    md.damping_ratio = spec->damping_ratio;
    md.dt = spec->dt;
    if (spec->motion == 1) {
        md.method = CBM_MOTION_MODAL;
        md.modes = spec->motion_modes > 0 ? (size_t)spec->motion_modes : 0;
        md.mode_cut_hz = spec->motion_cut_hz;
        md.static_correction = spec->static_correction != 0;
    }
    if (!(md.dt > 0.0)) {
        /* from the highest frequency of interest: the 6th mode (three bending modes in each
         * plane of a round rod), 20 steps per its period */
        double f[6];
        CBM_TRY(cbm_plant_modes(plant, 6, f, NULL));
        double fmax = 0.0;
        for (int i = 0; i < 6; i++)
            if (isfinite(f[i]))
                fmax = fmax > f[i] ? fmax : f[i];
        if (!(fmax > 0.0))
            return cbm__fail(plant->ctx, CBM_E_RUNTIME, "motion: no positive frequency for dt");
        md.dt = 1.0 / (20.0 * fmax);
        if (spec->duration / md.dt > 1e8)
            return cbm__fail(plant->ctx, CBM_E_LIMIT,
                             "motion: duration / dt = %g steps (dt from the 6th mode) is more "
                             "than 1e8; give a dt",
                             spec->duration / md.dt);
    }
    if (dt_used)
        *dt_used = md.dt;
    cbm_motion *m = NULL;
    CBM_TRY(cbm_motion_create(plant, &md, &m));
    size_t tip = n - 1;
    cbm_vec3 down = {0.0, -1.0, 0.0};
    cbm_status st = CBM_OK;
    if (spec->initial_tip_load != 0.0)
        st = cbm_motion_start_deflected(m, tip, v3_scale(down, spec->initial_tip_load));
    cbm_segment_state ss;
    if (st == CBM_OK)
        st = cbm_plant_segment(plant, tip, &ss);
    size_t steps = (size_t)ceil(spec->duration / md.dt - 1e-9);
    size_t kimp = (size_t)llround(spec->impulse_time / md.dt);
    if (kimp == 0)
        kimp = 1;
    for (size_t k = 0; st == CBM_OK; k++) {
        cbm_motion_row r;
        cbm_vec3 u;
        cbm_motion_state(m, &r.t, &r.kinetic, &r.potential);
        st = cbm_motion_displacement(m, tip, &u);
        if (st != CBM_OK)
            break;
        r.tip_x = ss.distal.x + u.x;
        r.tip_y = ss.distal.y + u.y;
        r.tip_z = ss.distal.z + u.z;
        st = row(user, &r);
        if (st != CBM_OK || k == steps)
            break;
        if (spec->impulse_force != 0.0 && k + 1 == kimp)
            st = cbm_motion_add_force(m, tip, v3_scale(down, spec->impulse_force));
        if (st == CBM_OK)
            st = cbm_motion_step(m);
    }
    cbm_motion_destroy(m);
    return st;
}
