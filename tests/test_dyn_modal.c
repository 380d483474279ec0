/* The modal motion (CBM_MOTION_MODAL, src/mech/dyn_modal.c) against the full one (dyn_motion.c):
 * with every mode the two integrate the same equations (to the round-off of the modes), with K
 * modes the truncation error of the tip's displacement after an impulse and in a gusty wind is
 * measured and bounded (docs/dynamics.md, "Modal reduction"; docs/validation.md). */
#include "dyn_testlib.h"
#include "cambium/dynamics.h"

#include "core/vecmath.h"

#include <stdlib.h>

static cbm_motion *motion(cbm_plant *p, const cbm_motion_def *md)
{
    cbm_motion *m = NULL;
    CHECK_OK(cbm_motion_create(p, md, &m));
    return m;
}

/* With all 3n modes the modal motion is the full one in other coordinates: 400 steps with
 * impulses, tugs and a base shake, undamped, with a damping ratio and with both Rayleigh terms
 * after a restart from a state, agree to 1e-7 of the largest rotation (the modes of a 120-DOF
 * plant are found to ~1e-9; tests/test_dyn_modes.c, all_modes), and so do the energies. */
TEST(modal_all_modes_matches_full)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = dyn_branched(ctx, 40);
    for (int variant = 0; variant < 3; variant++) {
        cbm_motion_def md = cbm_motion_def_default();
        md.dt = 2e-3;
        md.damping_ratio = variant == 1 ? 0.05 : 0.0;
        md.rayleigh_alpha = variant == 2 ? 0.7 : 0.0;
        md.rayleigh_beta = variant == 2 ? 1e-4 : 0.0;
        cbm_motion *fm = motion(p, &md);
        md.method = CBM_MOTION_MODAL;
        md.modes = 120;
        cbm_motion *mm = motion(p, &md);
        if (!fm || !mm)
            break;
        const double *fhz = NULL;
        CHECK(cbm_motion_modes(mm, &fhz) == 120 && fhz && fhz[0] > 0.0 && fhz[119] > fhz[0]);
        CHECK(cbm_motion_modes(fm, NULL) == 0);
        if (variant == 2) {
            double q[120], v[120];
            for (int i = 0; i < 120; i++) {
                q[i] = 1e-3 * sin(0.3 * i);
                v[i] = 1e-2 * cos(0.7 * i);
            }
            CHECK_OK(cbm_motion_start_state(fm, q, v));
            CHECK_OK(cbm_motion_start_state(mm, q, v));
        }
        double maxq = 0.0, maxd = 0.0, maxu = 0.0, maxdu = 0.0;
        for (int s = 0; s < 400; s++) {
            cbm_motion *both[2] = {fm, mm};
            for (int j = 0; j < 2; j++) {
                if (s == 0 || s == 150)
                    CHECK_OK(cbm_motion_add_force(both[j], 39, v3(0, -50, 10)));
                if (s >= 200 && s < 260)
                    CHECK_OK(cbm_motion_add_force(both[j], 20, v3(3, 0, -2)));
                if (s >= 300 && s < 320)
                    CHECK_OK(cbm_motion_base_acceleration(both[j], v3(0.5, 0, 2.0)));
                CHECK_OK(cbm_motion_step(both[j]));
            }
            const double *qf = cbm_motion_rotations(fm), *qm = cbm_motion_rotations(mm);
            for (int i = 0; i < 120; i++) {
                maxq = fmax(maxq, fabs(qf[i]));
                maxd = fmax(maxd, fabs(qf[i] - qm[i]));
            }
            cbm_vec3 uf, um;
            CHECK_OK(cbm_motion_displacement(fm, 39, &uf));
            CHECK_OK(cbm_motion_displacement(mm, 39, &um));
            maxu = fmax(maxu, v3_norm(uf));
            maxdu = fmax(maxdu, v3_norm(v3_sub(uf, um)));
        }
        double ef, em, kf, km;
        cbm_motion_state(fm, NULL, &kf, &ef);
        cbm_motion_state(mm, NULL, &km, &em);
        cbm_vec3 bf = cbm_motion_base_displacement(fm), bm = cbm_motion_base_displacement(mm);
        printf("variant %d: largest rotation %.4g rad, difference %.3g rad; tip %.4g m, "
               "difference %.3g m; energies %.9g / %.9g J\n",
               variant, maxq, maxd, maxu, maxdu, kf + ef, km + em);
        CHECK(maxq > 1e-5);
        CHECK(maxd <= 1e-7 * maxq);
        CHECK(maxdu <= 1e-7 * maxu);
        CHECK_REL(kf + ef, km + em, 1e-7);
        CHECK(v3_norm(v3_sub(bf, bm)) <= 1e-15 + 1e-12 * v3_norm(bf));
        cbm_motion_destroy(fm);
        cbm_motion_destroy(mm);
    }
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Without damping the modal energy 1/2 |eta'|^2 + 1/2 sum w^2 eta^2 is conserved by the
 * trapezoidal rule whatever dt: 20,000 steps of 5 ms (far longer than the 10th mode's period)
 * after a start from a deflection, to 1e-12 relative. */
TEST(modal_energy_conserved)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = dyn_branched(ctx, 60);
    cbm_motion_def md = cbm_motion_def_default();
    md.dt = 5e-3;
    md.method = CBM_MOTION_MODAL;
    md.modes = 10;
    cbm_motion *m = motion(p, &md);
    if (m) {
        CHECK_OK(cbm_motion_start_deflected(m, 59, v3(2, -10, 5)));
        double k0, e0, k, e, emin = INFINITY, emax = 0.0;
        cbm_motion_state(m, NULL, &k0, &e0);
        for (int s = 0; s < 20000; s++) {
            CHECK_OK(cbm_motion_step(m));
            cbm_motion_state(m, NULL, &k, &e);
            emin = fmin(emin, k + e);
            emax = fmax(emax, k + e);
        }
        printf("energy at start %.12g J, over 20,000 steps in [%.12g, %.12g] J, last kinetic "
               "%.3g J\n",
               k0 + e0, emin, emax, k);
        CHECK(k0 == 0.0 && e0 > 0.0);
        CHECK(emax - emin <= 1e-12 * e0);
        CHECK(k > 1e-3 * e0); /* it does move */
    }
    cbm_motion_destroy(m);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* The truncation error after loads at the tips: a 300-segment branched plant (900 DOF) with a
 * damping ratio of 2 %, (a) a kick (a force for one 1 ms step) at the main tip, then at a
 * lateral's tip, (b) a push (a half-sine force over 0.1 s) at the main tip. For K = 5 ... 80 the
 * largest and the RMS deviation of the main tip's displacement from the full motion's over 1 s,
 * relative to its largest and RMS displacement (printed for docs/dynamics.md). A kick excites
 * every mode (a point impulse has a flat spectrum): its error falls slowly with K; a push is
 * carried by the low modes. Both must fall as K grows; the push's to below 5 % at K = 40. */
static void load(cbm_motion *m, int kind, int s, int n)
{
    if (kind == 0) {
        if (s == 0)
            CHECK_OK(cbm_motion_add_force(m, (size_t)n - 1, v3(0, -200, 80)));
        if (s == 300)
            CHECK_OK(cbm_motion_add_force(m, 150, v3(50, 0, -100)));
    } else if (s < 100) {
        double f = sin(PI * (s + 1) / 100.0);
        CHECK_OK(cbm_motion_add_force(m, (size_t)n - 1, v3(0, -20 * f, 8 * f)));
    }
}

TEST(modal_truncation_loads)
{
    cbm_context *ctx = test_ctx();
    int n = 300, steps = 1000;
    cbm_plant *p = dyn_branched(ctx, n);
    size_t ks[] = {5, 10, 20, 40, 80};
    double errs[2][5], rms[2][5];
    cbm_vec3 *uf = calloc((size_t)steps, sizeof *uf);
    for (int kind = 0; kind < 2 && uf; kind++) {
        cbm_motion_def md = cbm_motion_def_default();
        md.dt = 1e-3;
        md.damping_ratio = 0.02;
        cbm_motion *fm = motion(p, &md);
        for (int s = 0; fm && s < steps; s++) {
            load(fm, kind, s, n);
            CHECK_OK(cbm_motion_step(fm));
            CHECK_OK(cbm_motion_displacement(fm, (size_t)n - 1, uf + s));
        }
        cbm_motion_destroy(fm);
        for (int j = 0; j < 5; j++) {
            md.method = CBM_MOTION_MODAL;
            md.modes = ks[j];
            cbm_motion *mm = motion(p, &md);
            double umax = 0.0, dmax = 0.0, u2 = 0.0, d2 = 0.0;
            for (int s = 0; mm && s < steps; s++) {
                load(mm, kind, s, n);
                CHECK_OK(cbm_motion_step(mm));
                cbm_vec3 u;
                CHECK_OK(cbm_motion_displacement(mm, (size_t)n - 1, &u));
                double e = v3_norm(v3_sub(u, uf[s]));
                umax = fmax(umax, v3_norm(uf[s]));
                dmax = fmax(dmax, e);
                u2 += v3_norm2(uf[s]);
                d2 += e * e;
            }
            errs[kind][j] = dmax / umax;
            rms[kind][j] = sqrt(d2 / u2);
            printf("%s: K = %zu, tip %.4g m at most, largest error %.3g m (%.3g %%), RMS error "
                   "%.3g %%\n",
                   kind ? "push" : "kick", ks[j], umax, dmax, 100.0 * errs[kind][j],
                   100.0 * rms[kind][j]);
            cbm_motion_destroy(mm);
        }
        CHECK(errs[kind][4] < errs[kind][2] && errs[kind][2] < errs[kind][0]);
        CHECK(rms[kind][4] < rms[kind][2] && rms[kind][2] < rms[kind][0]);
    }
    if (uf)
        CHECK(errs[1][3] < 0.05);
    free(uf);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Gusty wind: the same plant in a 15 m/s wind with 20 % turbulence, from the mean wind's static
 * deflection, over 2 s: the modal motion (projected, linearised drag) against the full one (the
 * drag with the relative velocity, iterated each step). The error holds the truncation and the
 * linearisation; it must fall from K = 5 to 40 and be below 10 % at K = 40. */
TEST(modal_truncation_wind)
{
    cbm_context *ctx = test_ctx();
    int n = 300;
    cbm_plant *p = dyn_branched(ctx, n);
    cbm_motion_def md = cbm_motion_def_default();
    md.dt = 2e-3;
    md.damping_ratio = 0.01;
    cbm_wind_def w = cbm_wind_def_default();
    w.direction = v3(0, 0, 1);
    w.profile = CBM_WIND_UNIFORM;
    w.organ_area_per_kg = 2.0;
    cbm_gust_def g = cbm_gust_def_default();
    g.intensity = 0.2;
    g.seed = 3;
    size_t ks[] = {5, 10, 20, 40};
    double errs[4];
    int steps = 1000;
    cbm_vec3 *uf = calloc((size_t)steps, sizeof *uf);
    cbm_motion *fm = motion(p, &md);
    if (fm) {
        CHECK_OK(cbm_motion_set_wind(fm, &w, 15.0, &g));
        CHECK_OK(cbm_motion_start_wind_static(fm));
    }
    for (int s = 0; fm && uf && s < steps; s++) {
        CHECK_OK(cbm_motion_step(fm));
        CHECK_OK(cbm_motion_displacement(fm, (size_t)n - 1, uf + s));
    }
    for (int j = 0; j < 4 && uf; j++) {
        md.method = CBM_MOTION_MODAL;
        md.modes = ks[j];
        cbm_motion *mm = motion(p, &md);
        if (!mm)
            break;
        CHECK_OK(cbm_motion_set_wind(mm, &w, 15.0, &g));
        CHECK_OK(cbm_motion_start_wind_static(mm));
        double umax = 0.0, dmax = 0.0, dyn = 0.0;
        for (int s = 0; s < steps; s++) {
            CHECK_OK(cbm_motion_step(mm));
            cbm_vec3 u;
            CHECK_OK(cbm_motion_displacement(mm, (size_t)n - 1, &u));
            umax = fmax(umax, v3_norm(uf[s]));
            dyn = fmax(dyn, v3_norm(v3_sub(uf[s], uf[0])));
            dmax = fmax(dmax, v3_norm(v3_sub(u, uf[s])));
        }
        CHECK(cbm_motion_drag_iterations(mm) == 0);
        errs[j] = dmax / umax;
        printf("wind: K = %zu, tip %.4g m at most (moves %.4g m about its start), largest error "
               "%.3g m (%.3g %%)\n",
               ks[j], umax, dyn, dmax, 100.0 * errs[j]);
        cbm_motion_destroy(mm);
    }
    CHECK(errs[3] < errs[0]);
    CHECK(errs[3] < 0.1);
    free(uf);
    cbm_motion_destroy(fm);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* The frequency cut takes every mode below it; bad requests fail with a reason. */
TEST(modal_cut_and_bad_input)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = dyn_branched(ctx, 40);
    double f[30];
    CHECK_OK(cbm_plant_modes(p, 30, f, NULL));
    cbm_motion_def md = cbm_motion_def_default();
    md.method = CBM_MOTION_MODAL;
    md.mode_cut_hz = 0.5 * (f[11] + f[12]);
    cbm_motion *m = motion(p, &md);
    const double *fhz = NULL;
    CHECK(m && cbm_motion_modes(m, &fhz) == 12);
    if (fhz)
        CHECK_REL(fhz[11], f[11], 1e-9);
    cbm_motion_destroy(m);
    m = NULL;
    md.mode_cut_hz = 0.0;
    CHECK(cbm_motion_create(p, &md, &m) == CBM_E_INVALID && !m);
    md.modes = 121;
    CHECK(cbm_motion_create(p, &md, &m) == CBM_E_INVALID && !m);
    md.modes = 5;
    md.method = (cbm_motion_method)7;
    CHECK(cbm_motion_create(p, &md, &m) == CBM_E_INVALID && !m);
    /* a gust field is not projected on the modes: refused, the series is taken */
    md.method = CBM_MOTION_MODAL;
    m = motion(p, &md);
    if (m) {
        cbm_wind_def wd = cbm_wind_def_default();
        cbm_gust_def gd = cbm_gust_def_default();
        gd.intensity = 0.2;
        gd.coherence_decay = 10.0;
        CHECK(cbm_motion_set_wind(m, &wd, 10.0, &gd) == CBM_E_INVALID);
        gd.coherence_decay = 0.0;
        CHECK_OK(cbm_motion_set_wind(m, &wd, 10.0, &gd));
    }
    cbm_motion_destroy(m);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}
