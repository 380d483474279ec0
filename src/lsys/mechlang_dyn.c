/* The dialect's dynamics of its mechanical plant (docs/language.md, "Mechanics"): Frequency(k),
 * Sway(duration, dt, wind, gust) and SwayDrag(duration, dt, wind, gust, coherence, leaf area per
 * kg), by the modal motion after SwayModes(K, static correction), over the library's
 * cbm_plant_modes and cbm_motion (docs/dynamics.md), about the plant's stored state.
 *
 * SwayDrag's organs: the dialect's point masses carry a mass and, where declared, the radius of
 * the organ's sphere (`mass: Grape(mass, radius)`), not whether they are leaves or fruit. A node
 * with a sphere is fruit, its drag that of the sphere (the library's sphere of the fruit's mass
 * and density has the same radius: the mass is passed as density x volume); a node without one
 * carries leaves, their area the point mass times the leaf area per kg (0: no leaf drag). */
#include "lsys/mechlang_internal.h"

#include "cambium/dynamics.h"
#include "core/core.h"
#include "core/vecmath.h"

#include <math.h>
#include <string.h>

cbm_status cbm__mechlang_frequency(cbm_context *ctx, const cbm_plant *p, size_t k, double *hz)
{
    *hz = 0;
    double *f = cbm__alloc(ctx, k * sizeof *f);
    if (!f)
        return CBM_E_NOMEM;
    cbm_status st = cbm_plant_modes(p, k, f, NULL);
    if (st == CBM_OK)
        *hz = isfinite(f[k - 1]) ? f[k - 1] : 0.0;
    cbm__free(ctx, f, k * sizeof *f);
    return st;
}

/* The largest displacement of any distal node: one sweep from the base (a node rides on its
 * parent's rigid motion: d_e(s) = d_e(parent) + Theta_parent x (x_s - e_parent) + Theta_s x
 * (e_s - x_s), Theta the summed joint rotations). */
static double peak_disp(size_t n, const int64_t *par, const cbm_vec3 *x, const cbm_vec3 *e,
                        const double *q, cbm_vec3 *th, cbm_vec3 *de)
{
    double mx = 0.0;
    for (size_t i = 0; i < n; i++) {
        cbm_vec3 qi = v3(q[3 * i], q[3 * i + 1], q[3 * i + 2]), dx = v3(0, 0, 0);
        if (par[i] >= 0) {
            size_t pa = (size_t)par[i];
            th[i] = v3_add(th[pa], qi);
            dx = v3_add(de[pa], v3_cross(th[pa], v3_sub(x[i], e[pa])));
        } else
            th[i] = qi;
        de[i] = v3_add(dx, v3_cross(th[i], v3_sub(e[i], x[i])));
        double d = v3_norm(de[i]);
        mx = d > mx ? d : mx;
    }
    return mx;
}

cbm_status cbm__mechlang_sway(cbm_context *ctx, const cbm_plant *p, const double *args,
                              cbm_lsys_sway_fn fn, void *ud, double *peak)
{
    *peak = 0;
    size_t n = cbm_plant_segment_count(p);
    const int64_t *par = cbm_plant_parents(p);
    const cbm_vec3 *pos = cbm_plant_positions(p);
    const cbm_quat *ori = cbm_plant_orientations(p);
    cbm_vec3 *buf = cbm__alloc(ctx, 3 * n * sizeof *buf);
    if (!buf)
        return CBM_E_NOMEM;
    cbm_vec3 *e = buf, *th = buf + n, *de = buf + 2 * n;
    for (size_t i = 0; i < n; i++) {
        cbm_segment_state s;
        cbm_plant_segment(p, i, &s);
        e[i] = v3_madd(pos[i], q_rotate(ori[i], v3(1, 0, 0)), s.length);
    }
    cbm_motion_def md = cbm_motion_def_default();
    md.dt = args[1];
    md.damping_ratio = 0.03;
    if (args[7] > 0) { /* SwayModes(K, correction) */
        md.method = CBM_MOTION_MODAL;
        md.modes = (size_t)args[7];
        md.static_correction = args[8] == 1.0;
    }
    cbm_motion *m = NULL;
    cbm_status st = cbm_motion_create(p, &md, &m);
    cbm_wind_def wd = cbm_wind_def_default();
    cbm_gust_def gd = cbm_gust_def_default();
    gd.intensity = args[3];
    double *organs = NULL;
    if (args[6] == 1.0) { /* SwayDrag */
        gd.coherence_decay = args[4];
        organs = cbm__alloc(ctx, 2 * n * sizeof *organs);
        if (!organs)
            st = CBM_E_NOMEM;
        for (size_t i = 0; organs && i < n; i++) {
            cbm_segment_state s;
            cbm_plant_segment(p, i, &s);
            double r = s.contact_radius;
            organs[i] = r > 0.0 ? 0.0 : s.point_mass * args[5];
            organs[n + i] = r > 0.0 ? wd.fruit_density * 4.0 / 3.0 * CBM_PI * r * r * r : 0.0;
        }
        wd.leaf_area = organs;
        wd.fruit_mass = organs ? organs + n : NULL;
    }
    if (st == CBM_OK)
        st = cbm_motion_set_wind(m, &wd, args[2], &gd);
    cbm__free(ctx, organs, 2 * n * sizeof *organs); /* the drag keeps its own constants */
    if (st == CBM_OK)
        st = cbm_motion_start_wind_static(m);
    long steps = (long)ceil(args[0] / args[1] - 1e-9);
    double mx = 0.0;
    if (st == CBM_OK)
        mx = peak_disp(n, par, pos, e, cbm_motion_rotations(m), th, de);
    if (st == CBM_OK && fn)
        st = fn(ud, p, m, CBM_LSYS_SWAY_BEGIN);
    for (long k = 0; k < steps && st == CBM_OK; k++) {
        st = cbm_motion_step(m);
        if (st == CBM_OK) {
            double d = peak_disp(n, par, pos, e, cbm_motion_rotations(m), th, de);
            mx = d > mx ? d : mx;
        }
        if (st == CBM_OK && fn)
            st = fn(ud, p, m, CBM_LSYS_SWAY_STEP);
    }
    if (st == CBM_OK && fn)
        st = fn(ud, p, m, CBM_LSYS_SWAY_END);
    cbm_motion_destroy(m);
    cbm__free(ctx, buf, 3 * n * sizeof *buf);
    *peak = mx;
    return st;
}
