/* The modal motion (CBM_MOTION_MODAL, src/mech/dyn_modal.c) against the full one (dyn_motion.c):
 * with every mode the two integrate the same equations (to the round-off of the modes), with K
 * modes the truncation error of the tip's displacement after an impulse and in a gusty wind is
 * measured and bounded (docs/dynamics.md, "Modal reduction"; docs/validation.md). */
#include "dyn_testlib.h"
#include "cambium/bend.h"
#include "cambium/dynamics.h"
#include "cambium/lsys.h"

#include "core/vecmath.h"

#include <stdlib.h>
#include <string.h>

static cbm_motion *motion(cbm_plant *p, const cbm_motion_def *md)
{
    cbm_motion *m = NULL;
    CHECK_OK(cbm_motion_create(p, md, &m));
    return m;
}

/* The wind of the modal wind tests: uniform along z, 2 m^2 of organs per kg, gusts of intensity
 * 0.2 drawn from seed 3. */
static void gusty_wind(cbm_wind_def *w, cbm_gust_def *g)
{
    *w = cbm_wind_def_default();
    w->direction = v3(0, 0, 1);
    w->profile = CBM_WIND_UNIFORM;
    w->organ_area_per_kg = 2.0;
    *g = cbm_gust_def_default();
    g->intensity = 0.2;
    g->seed = 3;
}

/* m under that wind at 15 m/s, started from the static deflection under its mean. */
static void start_gusty_wind(cbm_motion *m)
{
    cbm_wind_def w;
    cbm_gust_def g;
    gusty_wind(&w, &g);
    CHECK_OK(cbm_motion_set_wind(m, &w, 15.0, &g));
    CHECK_OK(cbm_motion_start_wind_static(m));
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
    double errs[2][5] = {{0}}, rms[2][5] = {{0}}; /* a run that did not happen fails the checks */
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

/* The wind of start_gusty_wind pinned from outside it, so that a weaker wind cannot pass the
 * comparisons below (both sides run in it): the drag of the mean wind on the organs is computed
 * here from the wind's figures (15 m/s, 2 m^2/kg, C_d 0.5, rho 1.226: 1/2 rho C_d A U^2 = 6.90 N
 * on each 50 g mass, along z) and the static deflection under it superposed from the plant's
 * response to one force at a time (K q = f); the deflection the wind starts from (organs and
 * wood) must be 1.1 to 1.3 times that (the wood's drag adds 17 % on this plant), so a mean
 * wind 5 % weaker fails. The gust series, over two periods of its slowest harmonic, must have
 * the mean 15 m/s and 15 to 25 % of it as standard deviation (measured: 15.1 and 19 %). */
static void check_gusty_wind_strength(cbm_plant *p, int n, const cbm_motion_def *md, cbm_vec3 u0,
                                      cbm_motion *gusty, int steps)
{
    const double force = 0.5 * 1.226 * 0.5 * (0.05 * 2.0) * 15.0 * 15.0; /* N */
    cbm_motion *m = motion(p, md);
    cbm_vec3 organs = v3(0, 0, 0);
    for (int i = 0; m && i < n; i += 4) { /* dyn_branched: 50 g on every fourth segment */
        cbm_vec3 u;
        CHECK_OK(cbm_motion_start_deflected(m, (size_t)i, v3(0, 0, force)));
        CHECK_OK(cbm_motion_displacement(m, (size_t)n - 1, &u));
        organs = v3_add(organs, u);
    }
    cbm_motion_destroy(m);
    double sum = 0.0, sum2 = 0.0;
    int samples = 20000; /* 1000 s, two periods of the slowest harmonic (0.002 Hz) */
    for (int s = 0; s < samples; s++) {
        double w = cbm_motion_wind_at(gusty, 0.05 * s);
        sum += w;
        sum2 += w * w;
    }
    double mean = sum / samples, sd = sqrt(fmax(0.0, sum2 / samples - mean * mean));
    printf("wind: static tip deflection %.4g m, %.4g m from the organs' drag alone (%.3f); gusts "
           "%.3g m/s mean, %.3g m/s standard deviation\n",
           v3_norm(u0), v3_norm(organs), v3_norm(u0) / v3_norm(organs), mean, sd);
    CHECK(v3_norm(organs) > 0.0);
    CHECK(v3_norm(u0) > 1.1 * v3_norm(organs) && v3_norm(u0) < 1.3 * v3_norm(organs));
    CHECK(fabs(mean - 15.0) < 0.5);
    CHECK(sd > 0.15 * 15.0 && sd < 0.25 * 15.0);
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
    size_t ks[] = {5, 10, 20, 40};
    double errs[4] = {NAN, NAN, NAN, NAN}; /* a run that did not happen fails the checks */
    int steps = 1000;
    cbm_vec3 *uf = calloc((size_t)steps, sizeof *uf);
    cbm_motion *fm = motion(p, &md);
    if (fm) {
        start_gusty_wind(fm);
    }
    cbm_vec3 u0 = v3(0, 0, 0);
    if (fm)
        CHECK_OK(cbm_motion_displacement(fm, (size_t)n - 1, &u0));
    for (int s = 0; fm && uf && s < steps; s++) {
        CHECK_OK(cbm_motion_step(fm));
        CHECK_OK(cbm_motion_displacement(fm, (size_t)n - 1, uf + s));
    }
    if (fm)
        check_gusty_wind_strength(p, n, &md, u0, fm, steps);
    for (int j = 0; j < 4 && uf; j++) {
        md.method = CBM_MOTION_MODAL;
        md.modes = ks[j];
        cbm_motion *mm = motion(p, &md);
        if (!mm)
            break;
        start_gusty_wind(mm);
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
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* A gust field (Davenport coherence over a grid, dyn_gust.c) on the modal motion: its drag is
 * projected per grid point (dyn_modal.c, "Gust field").
 * (a) The uniform limit: with a coherence decay of 1e-15 the field is the series at every grid
 * point, and the field's projections (per-segment wrenches on the modes' twists, split by the
 * grid's weights) must give the series' motion (the projections of the summed generalised
 * force): the tip to 1e-9 of its largest displacement over 500 steps.
 * (b) The same 300-segment plant, wind and turbulence as modal_truncation_wind, with a field of
 * decay 8 on a 6-point grid, over 2 s: the modal motion against the full one with the same field
 * (the drag with the relative velocity at every segment's interpolated gust). The error holds
 * the truncation and the linearisation; it must fall from K = 5 to 40 and be below 10 % at
 * K = 40, as for the series (printed for docs/dynamics.md), and K = 20 with the static correction
 * (the field's drag in full at each output) no worse than without. A field that fell back to the
 * series would differ from the full motion by the field's effect, which is checked to be larger
 * than that (the full motion with the series against the full one with the field). */
TEST(modal_gust_field)
{
    cbm_context *ctx = test_ctx();
    int n = 300, steps = 1000;
    cbm_plant *p = dyn_branched(ctx, n);
    cbm_motion_def md = cbm_motion_def_default();
    md.dt = 2e-3;
    md.damping_ratio = 0.01;
    cbm_wind_def w;
    cbm_gust_def g;
    gusty_wind(&w, &g);
    /* (a) */
    md.method = CBM_MOTION_MODAL;
    md.modes = 20;
    cbm_motion *ms = motion(p, &md), *mf = motion(p, &md);
    if (ms && mf) {
        CHECK_OK(cbm_motion_set_wind(ms, &w, 15.0, &g));
        g.coherence_decay = 1e-15; /* the field's Cholesky drops the other points' series */
        CHECK_OK(cbm_motion_set_wind(mf, &w, 15.0, &g));
        CHECK_OK(cbm_motion_start_wind_static(ms));
        CHECK_OK(cbm_motion_start_wind_static(mf));
        double umax = 0.0, dmax = 0.0;
        for (int s = 0; s < 500; s++) {
            CHECK_OK(cbm_motion_step(ms));
            CHECK_OK(cbm_motion_step(mf));
            cbm_vec3 us, uf;
            CHECK_OK(cbm_motion_displacement(ms, (size_t)n - 1, &us));
            CHECK_OK(cbm_motion_displacement(mf, (size_t)n - 1, &uf));
            umax = fmax(umax, v3_norm(us));
            dmax = fmax(dmax, v3_norm(v3_sub(us, uf)));
        }
        printf("uniform limit: tip %.4g m at most, field against series %.3g m\n", umax, dmax);
        CHECK(umax > 1e-3 && dmax <= 1e-9 * umax);
    }
    cbm_motion_destroy(ms);
    cbm_motion_destroy(mf);
    /* (b) */
    g.coherence_decay = 8.0;
    g.grid = 6;
    md.method = CBM_MOTION_FULL;
    md.modes = 0;
    cbm_vec3 *uf = calloc((size_t)steps, sizeof *uf);
    double field_effect = 0.0;
    for (int pass = 0; pass < 2 && uf; pass++) {
        cbm_gust_def gp = g;
        gp.coherence_decay = pass == 0 ? 0.0 : g.coherence_decay;
        cbm_motion *fm = motion(p, &md);
        if (!fm)
            break;
        CHECK_OK(cbm_motion_set_wind(fm, &w, 15.0, &gp));
        CHECK_OK(cbm_motion_start_wind_static(fm));
        for (int s = 0; s < steps; s++) {
            CHECK_OK(cbm_motion_step(fm));
            cbm_vec3 u;
            CHECK_OK(cbm_motion_displacement(fm, (size_t)n - 1, &u));
            if (pass == 0)
                uf[s] = u;
            else {
                field_effect = fmax(field_effect, v3_norm(v3_sub(u, uf[s])));
                uf[s] = u;
            }
        }
        cbm_motion_destroy(fm);
    }
    size_t ks[] = {5, 10, 20, 40, 20};
    double errs[5] = {0, 0, 0, 0, 0}, umax = 0.0;
    for (int j = 0; j < 5 && uf; j++) {
        md.method = CBM_MOTION_MODAL;
        md.modes = ks[j];
        md.static_correction = j == 4; /* the last: K = 20 with the static correction */
        cbm_motion *mm = motion(p, &md);
        if (!mm)
            break;
        CHECK_OK(cbm_motion_set_wind(mm, &w, 15.0, &g));
        CHECK_OK(cbm_motion_start_wind_static(mm));
        double dmax = 0.0;
        umax = 0.0;
        for (int s = 0; s < steps; s++) {
            CHECK_OK(cbm_motion_step(mm));
            cbm_vec3 u;
            CHECK_OK(cbm_motion_displacement(mm, (size_t)n - 1, &u));
            umax = fmax(umax, v3_norm(uf[s]));
            dmax = fmax(dmax, v3_norm(v3_sub(u, uf[s])));
        }
        errs[j] = dmax / umax;
        printf("field: K = %zu%s, tip %.4g m at most, largest error %.3g m (%.3g %%)\n", ks[j],
               j == 4 ? " with the static correction" : "", umax, dmax, 100.0 * errs[j]);
        cbm_motion_destroy(mm);
    }
    printf("the field's effect on the full motion's tip: %.3g m (%.3g %%)\n", field_effect,
           100.0 * field_effect / umax);
    CHECK(errs[3] < errs[0]);
    CHECK(errs[3] < 0.1);
    CHECK(errs[4] < errs[2] * 1.01);
    CHECK(field_effect > 2.0 * errs[3] * umax);
    free(uf);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* The static correction (mode acceleration, dyn_modal.c "Static correction"):
 * (a) with all 3n modes it vanishes: a 40-segment plant under a push, a base shake and a gusty
 * wind, with and without it, the same rotations to 1e-12 of the largest, and the full motion's
 * to 1e-3 (the modal motion linearises the drag; measured 1.2e-4);
 * (b) on the 300-segment plant of modal_truncation_loads and _wind, at K = 10, 20, 40, the tip's
 * largest error against the full motion under the half-sine push and in the gusty wind, without
 * and with it (printed for docs/dynamics.md): with it the push's error must fall at least
 * threefold at every K (measured 3.8x, 6x, 9x) and the wind's must fall (measured 2.06 -> 1.61 %
 * at K = 10; from K = 20 on the error is the drag's linearisation, 0.7 %, which no correction of
 * the truncation reaches);
 * (c) the option on the full motion is refused. */
static double corrected_error(cbm_plant *p, int n, int kind, size_t k, bool sc, const cbm_vec3 *uf,
                              int steps)
{
    cbm_motion_def md = cbm_motion_def_default();
    md.dt = kind ? 2e-3 : 1e-3;
    md.damping_ratio = kind ? 0.01 : 0.02;
    md.method = k ? CBM_MOTION_MODAL : CBM_MOTION_FULL;
    md.modes = k;
    md.static_correction = sc;
    cbm_motion *m = motion(p, &md);
    if (!m)
        return INFINITY;
    if (kind) {
        start_gusty_wind(m);
    }
    double umax = 0.0, dmax = 0.0;
    for (int s = 0; s < steps; s++) {
        if (!kind)
            load(m, 1, s, n);
        CHECK_OK(cbm_motion_step(m));
        cbm_vec3 u;
        CHECK_OK(cbm_motion_displacement(m, (size_t)n - 1, &u));
        umax = fmax(umax, v3_norm(uf[s]));
        dmax = fmax(dmax, v3_norm(v3_sub(u, uf[s])));
    }
    cbm_motion_destroy(m);
    return dmax / umax;
}

TEST(modal_static_correction)
{
    cbm_context *ctx = test_ctx();
    /* (a) */
    cbm_plant *p = dyn_branched(ctx, 40);
    cbm_motion_def md = cbm_motion_def_default();
    md.dt = 2e-3;
    md.damping_ratio = 0.02;
    cbm_motion *ms[3];
    for (int j = 0; j < 3; j++) {
        md.method = j ? CBM_MOTION_MODAL : CBM_MOTION_FULL;
        md.modes = j ? 120 : 0;
        md.static_correction = j == 2;
        ms[j] = motion(p, &md);
    }
    if (ms[0] && ms[1] && ms[2]) {
        cbm_wind_def w = cbm_wind_def_default();
        cbm_gust_def g = cbm_gust_def_default();
        g.intensity = 0.2;
        double maxq = 0.0, d01 = 0.0, d12 = 0.0;
        for (int j = 0; j < 3; j++)
            CHECK_OK(cbm_motion_set_wind(ms[j], &w, 10.0, &g));
        for (int s = 0; s < 300; s++) {
            for (int j = 0; j < 3; j++) {
                if (s < 100)
                    CHECK_OK(cbm_motion_add_force(ms[j], 39, v3(0, -5 * sin(PI * s / 100.0), 2)));
                if (s >= 150 && s < 170)
                    CHECK_OK(cbm_motion_base_acceleration(ms[j], v3(0.5, 0, 2.0)));
                CHECK_OK(cbm_motion_step(ms[j]));
            }
            const double *q0 = cbm_motion_rotations(ms[0]), *q1 = cbm_motion_rotations(ms[1]),
                         *q2 = cbm_motion_rotations(ms[2]);
            for (int i = 0; i < 120; i++) {
                maxq = fmax(maxq, fabs(q0[i]));
                d01 = fmax(d01, fabs(q0[i] - q2[i]));
                d12 = fmax(d12, fabs(q1[i] - q2[i]));
            }
        }
        printf("all modes: largest rotation %.4g rad; corrected against plain modal %.3g, "
               "against full %.3g rad\n",
               maxq, d12, d01);
        CHECK(maxq > 1e-5 && d12 <= 1e-12 * maxq && d01 <= 1e-3 * maxq);
    }
    for (int j = 0; j < 3; j++)
        cbm_motion_destroy(ms[j]);
    /* (c) */
    cbm_motion *m = NULL;
    md.method = CBM_MOTION_FULL;
    md.static_correction = true;
    CHECK(cbm_motion_create(p, &md, &m) == CBM_E_INVALID && !m);
    cbm_plant_destroy(p);
    /* (b) */
    int n = 300, steps = 1000;
    p = dyn_branched(ctx, n);
    cbm_vec3 *uf = calloc((size_t)steps, sizeof *uf);
    for (int kind = 0; kind < 2 && uf; kind++) {
        /* the full motion's tip, as corrected_error runs it */
        md = cbm_motion_def_default();
        md.dt = kind ? 2e-3 : 1e-3;
        md.damping_ratio = kind ? 0.01 : 0.02;
        cbm_motion *fm = motion(p, &md);
        if (!fm)
            break;
        if (kind) {
            start_gusty_wind(fm);
        }
        for (int s = 0; s < steps; s++) {
            if (!kind)
                load(fm, 1, s, n);
            CHECK_OK(cbm_motion_step(fm));
            CHECK_OK(cbm_motion_displacement(fm, (size_t)n - 1, uf + s));
        }
        cbm_motion_destroy(fm);
        size_t ks[] = {10, 20, 40};
        for (int j = 0; j < 3; j++) {
            double e0 = corrected_error(p, n, kind, ks[j], false, uf, steps);
            double e1 = corrected_error(p, n, kind, ks[j], true, uf, steps);
            printf("%s: K = %zu, tip's largest error %.3g %% without, %.3g %% with the static "
                   "correction\n",
                   kind ? "wind" : "push", ks[j], 100.0 * e0, 100.0 * e1);
            CHECK(e1 < (kind ? 1.0 : 1.0 / 3.0) * e0);
        }
    }
    free(uf);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* `bend`'s modal keys (motion = modal, motion_modes, motion_cut_hz, static_correction) give the
 * motion of the API with the same definition: every row of a released tip load and an impulse
 * equal to the bit, for K = 8 with the static correction and for a frequency cut; the keys'
 * errors (without motion = modal, without modes or a cut, without duration) are refused. */
typedef struct rows {
    cbm_motion_row r[400];
    size_t n;
} rows;

static cbm_status keep_row(void *user, const cbm_motion_row *row)
{
    rows *rs = user;
    if (rs->n < 400)
        rs->r[rs->n] = *row;
    rs->n++;
    return CBM_OK;
}

TEST(modal_bend_keys_equal_api)
{
    cbm_context *ctx = test_ctx();
    static const char *const variants[] = {"motion_modes = 8\nstatic_correction = 1\n",
                                           "motion_cut_hz = 300\n"};
    rows *a = calloc(1, sizeof *a);
    for (int v = 0; v < 2 && a; v++) {
        char text[512];
        snprintf(text, sizeof text,
                 "length = 1\nsegments = 30\nradius = 0.01\nangle = 20\nduration = 0.2\n"
                 "dt = 0.001\ndamping_ratio = 0.02\ninitial_tip_load = 2\nimpulse_time = 0.05\n"
                 "impulse_force = 5\nmotion = modal\n%s",
                 variants[v]);
        cbm_bend_spec sp;
        CHECK_OK(cbm_bend_spec_parse(ctx, text, strlen(text), "m.spec", &sp));
        cbm_plant *p = NULL;
        cbm_bend_result br;
        CHECK_OK(cbm_bend_run(ctx, &sp, &p, &br));
        if (!p)
            break;
        a->n = 0;
        CHECK_OK(cbm_bend_motion(p, &sp, keep_row, a, NULL));
        CHECK_EQ_INT(a->n, 201);
        /* the API by hand */
        cbm_motion_def md = cbm_motion_def_default();
        md.dt = 0.001;
        md.damping_ratio = 0.02;
        md.method = CBM_MOTION_MODAL;
        md.modes = v == 0 ? 8 : 0;
        md.mode_cut_hz = v == 0 ? 0.0 : 300.0;
        md.static_correction = v == 0;
        cbm_motion *m = motion(p, &md);
        size_t tip = cbm_plant_segment_count(p) - 1;
        cbm_segment_state ss;
        CHECK_OK(cbm_plant_segment(p, tip, &ss));
        const double *fhz = NULL;
        size_t k = m ? cbm_motion_modes(m, &fhz) : 0;
        CHECK(v == 0 ? k == 8 : (k > 0 && k < 90 && fhz[k - 1] < 300.0));
        if (m)
            CHECK_OK(cbm_motion_start_deflected(m, tip, v3(0, -2, 0)));
        bool same = m != NULL;
        for (size_t s = 0; m && s < 201 && s < a->n; s++) {
            cbm_vec3 u;
            double t, ek, ep;
            cbm_motion_state(m, &t, &ek, &ep);
            CHECK_OK(cbm_motion_displacement(m, tip, &u));
            const cbm_motion_row *r = a->r + s;
            same = same && r->t == t && r->tip_x == ss.distal.x + u.x &&
                   r->tip_y == ss.distal.y + u.y && r->tip_z == ss.distal.z + u.z &&
                   r->kinetic == ek && r->potential == ep;
            if (s + 1 == 50)
                CHECK_OK(cbm_motion_add_force(m, tip, v3(0, -5, 0)));
            CHECK_OK(cbm_motion_step(m));
        }
        CHECK_MSG(same, "variant %d: the spec's rows differ from the API's", v);
        cbm_motion_destroy(m);
        cbm_plant_destroy(p);
    }
    free(a);
    /* the keys' errors */
    static const char *const bad[] = {"duration = 0.1\nmotion_modes = 5\n",
                                      "duration = 0.1\nstatic_correction = 1\n",
                                      "duration = 0.1\nmotion = modal\n",
                                      "motion = modal\nmotion_modes = 5\n",
                                      "duration = 0.1\nmotion = partial\n",
                                      "duration = 0.1\nmotion = modal\nmotion_modes = -1\n"};
    for (size_t i = 0; i < sizeof bad / sizeof *bad; i++) {
        test_diags g;
        cbm_context *c2 = test_diag_ctx(&g);
        if (!c2)
            break;
        cbm_bend_spec sp;
        CHECK_MSG(cbm_bend_spec_parse(c2, bad[i], strlen(bad[i]), "m.spec", &sp) != CBM_OK, "%s",
                  bad[i]);
        CHECK_MSG(g.count > 0 && strstr(g.text, "m.spec"), "%s: %s", bad[i], g.text);
        test_ctx_end(c2);
    }
    test_ctx_end(ctx);
}

/* The L+C dialect's SwayModes(K, correction) (docs/language.md): the model's Sway() after it is
 * the API's modal motion on the model's plant (the same definition: dt, the damping ratio 0.03
 * of Sway(), the default wind with the gusts, K modes, the correction), rotation for rotation to
 * the bit at every step (through the sway observer); SwayModes(0, 0) goes back to the full
 * motion; bad arguments stop the run with a file:line:col error. */
typedef struct lc_check {
    cbm_motion *api;
    size_t want_k;
    int steps, begins;
    bool same;
} lc_check;

static cbm_status lc_observe(void *ud, const cbm_plant *plant, cbm_motion *m,
                             cbm_lsys_sway_phase ph)
{
    lc_check *c = ud;
    if (ph == CBM_LSYS_SWAY_BEGIN) {
        c->begins++;
        c->same = c->same && cbm_motion_modes(m, NULL) == c->want_k;
        if (c->want_k == 0)
            return CBM_OK;
        cbm_motion_def md = cbm_motion_def_default();
        md.dt = 0.002;
        md.damping_ratio = 0.03;
        md.method = CBM_MOTION_MODAL;
        md.modes = c->want_k;
        md.static_correction = true;
        cbm_status st = cbm_motion_create(plant, &md, &c->api);
        cbm_wind_def wd = cbm_wind_def_default();
        cbm_gust_def gd = cbm_gust_def_default();
        gd.intensity = 0.2;
        if (st == CBM_OK)
            st = cbm_motion_set_wind(c->api, &wd, 20.0, &gd);
        if (st == CBM_OK)
            st = cbm_motion_start_wind_static(c->api);
        if (st != CBM_OK)
            return st;
    } else if (ph == CBM_LSYS_SWAY_STEP && c->api) {
        c->steps++;
        cbm_status st = cbm_motion_step(c->api);
        if (st != CBM_OK)
            return st;
    }
    if (c->api) {
        const double *qa = cbm_motion_rotations(c->api), *qm = cbm_motion_rotations(m);
        for (size_t i = 0; i < 3 * cbm_plant_segment_count(plant); i++)
            c->same = c->same && qa[i] == qm[i];
    }
    if (ph == CBM_LSYS_SWAY_END) {
        cbm_motion_destroy(c->api);
        c->api = NULL;
    }
    return CBM_OK;
}

static const char LC_ROD[] =
    "#include <lpfgall.h>\n"
    "derivation length: 20;\n"
    "module I(MechSegment);\n"
    "module A(int);\n"
    "mechanics: I;\n"
    "MechSegment S()\n"
    "{\n"
    "    MechSegment s;\n"
    "    s.length = 0.05; s.a = 0.01; s.b = 0.01; s.E = 1e10; s.density = 600;\n"
    "    return s;\n"
    "}\n"
    "Axiom: A(20);\n"
    "A(n): { if (n > 0) produce I(S()) A(n - 1); produce; }\n"
    "End: {\n"
    "    Equilibrium();\n"
    "    SwayModes(%s);\n" /* line 16 */
    "    Sway(0.1, 0.002, 20, 0.2);\n"
    "}\n";

TEST(modal_lc_sway_modes_equal_api)
{
    const char *args[] = {"6, 1", "0, 0"};
    for (int v = 0; v < 2; v++) {
        cbm_context *ctx = test_ctx();
        char text[1024];
        snprintf(text, sizeof text, LC_ROD, args[v]);
        cbm_lsys_def def = cbm_lsys_def_default();
        def.path = "rod.l";
        def.text = text;
        cbm_lsys *ls = NULL;
        CHECK_OK(cbm_lsys_load(ctx, &def, &ls));
        lc_check c = {NULL, v == 0 ? 6 : 0, 0, 0, true};
        if (ls) {
            cbm_lsys_set_sway_observer(ls, lc_observe, &c);
            CHECK_OK(cbm_lsys_reset(ls));
            for (int s = 0; s < 20; s++)
                CHECK_OK(cbm_lsys_step(ls));
            cbm_lsys_destroy(ls);
        }
        cbm_motion_destroy(c.api);
        CHECK(c.begins == 1 && c.same);
        CHECK(v == 1 || c.steps == 50);
        test_ctx_end(ctx);
    }
    const char *bad[] = {"2.5, 0", "-1, 0", "6, 2", "0, 1"};
    for (int v = 0; v < 4; v++) {
        test_diags g;
        cbm_context *ctx = test_diag_ctx(&g);
        if (!ctx)
            break;
        char text[1024];
        snprintf(text, sizeof text, LC_ROD, bad[v]);
        cbm_lsys_def def = cbm_lsys_def_default();
        def.path = "rod.l";
        def.text = text;
        cbm_lsys *ls = NULL;
        CHECK_OK(cbm_lsys_load(ctx, &def, &ls));
        if (ls) {
            cbm_status st = cbm_lsys_reset(ls);
            for (int s = 0; s < 20 && st == CBM_OK; s++)
                st = cbm_lsys_step(ls);
            CHECK(st != CBM_OK);
            CHECK_MSG(strstr(g.text, "rod.l:16:") && strstr(g.text, "SwayModes"), "%s", g.text);
            cbm_lsys_destroy(ls);
        }
        test_ctx_end(ctx);
    }
}
