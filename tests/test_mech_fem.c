/* The incremental finite-element method (src/mech/fem.c): closed-form cantilevers, agreement
 * with the statics where both are linear (also branched), the linearised load path under large
 * loads, the growth-memory identities and the maturation-strain curvature rate. Tolerances and
 * how each reference is obtained: docs/validation.md, "Incremental FEM". */
#include "mech_testlib.h"
#include "core/vecmath.h"

static cbm_solve_def fem_solve(size_t increments)
{
    cbm_solve_def sd = cbm_solve_def_default();
    sd.solver = CBM_MECH_FEM;
    sd.fem.increments = increments;
    return sd;
}

static cbm_plant *rod(cbm_context *ctx, int n, double L, double r, double E, double rho)
{
    cbm_plant *p = clamped_plant(ctx, 0.0);
    cbm_segment_def d = cbm_segment_def_default();
    d.length = L / n;
    d.core.youngs_modulus = E;
    d.core.shear_modulus = E / 2.6;
    d.core.density = rho;
    d.core.a = d.core.b = r;
    for (int i = 0; i < n; i++) {
        d.parent = i - 1;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    return p;
}

/* Hermite cubics with consistent loads are exact at the nodes of a prismatic cantilever: one
 * increment under a small load gives w L^4 / 8 EI and P L^3 / 3 EI up to the geometric
 * nonlinearity, O((deflection / L)^2) relative. */
TEST(fem_cantilever_closed_form)
{
    cbm_context *ctx = test_ctx();
    const double L = 1.0, r = 0.01, E = 1e11, rho = 600.0, g = 9.81;
    double ei = E * PI * pow(r, 4) / 4.0, w = rho * g * PI * r * r;
    for (int n = 1; n <= 40; n *= 4) {
        cbm_plant *p = rod(ctx, n, L, r, E, rho);
        cbm_solve_def sd = fem_solve(1);
        cbm_solve_stats st;
        CHECK_OK(cbm_plant_solve(p, &sd, &st));
        CHECK_EQ_INT(st.stage, CBM_SOLVE_STAGE_FEM);
        double dy = -rod_tip(p).y, want = w * pow(L, 4) / (8.0 * ei);
        printf("n=%d: uniform load tip %.9e m, closed form %.9e m\n", n, dy, want);
        CHECK_REL(dy, want, 1e-6);
        /* a tip mass alone */
        cbm_plant_destroy(p);
        p = rod(ctx, n, L, r, E, 0.0);
        CHECK_OK(cbm_plant_set_load(p, (size_t)n - 1, 0.05, v3(0, 0, 0), v3(0, 0, 0)));
        CHECK_OK(cbm_plant_solve(p, &sd, NULL));
        dy = -rod_tip(p).y;
        want = 0.05 * g * pow(L, 3) / (3.0 * ei);
        printf("n=%d: tip mass tip %.9e m, closed form %.9e m\n", n, dy, want);
        CHECK_REL(dy, want, 1e-6);
        cbm_plant_destroy(p);
    }
    test_ctx_end(ctx);
}

/* A branched plant under a small load: the FEM (one increment) and the statics (fast solver,
 * fine staggered discretisation, converging as h^2) must agree on every node. */
TEST(fem_branched_agrees_with_statics_small_load)
{
    cbm_context *ctx = test_ctx();
    double dmax[2] = {0, 0};
    cbm_vec3 tips[2][3];
    for (int which = 0; which < 2; which++) {
        int n = which ? 240 : 12; /* segments per axis: FEM coarse, statics fine */
        cbm_plant *p = clamped_plant(ctx, PI / 3);
        cbm_segment_def d = cbm_segment_def_default();
        d.core.youngs_modulus = 5e11;
        d.core.shear_modulus = 5e11 / 2.6;
        d.core.a = d.core.b = 0.01;
        d.length = 1.0 / n;
        size_t fork = 0, last = 0;
        for (int i = 0; i < n; i++) {
            d.parent = i - 1;
            CHECK_OK(cbm_plant_add_segment(p, &d, &fork));
        }
        /* two laterals from the stem's tip, 50 degrees either side, the second rolled */
        const int half = n / 2; /* segments a branch */
        for (int b = 0; b < 2; b++) {
            for (int i = 0; i < half; i++) {
                d.parent = i == 0 ? (int64_t)fork : (int64_t)last;
                d.lateral = i == 0;
                d.deviation = i == 0 ? (b ? -0.87 : 0.87) : 0.0;
                d.divergence = i == 0 && b ? 0.6 : 0.0;
                d.length = 0.6 / half;
                CHECK_OK(cbm_plant_add_segment(p, &d, &last));
            }
            d.deviation = d.divergence = 0.0;
            d.lateral = false;
            CHECK_OK(cbm_plant_set_load(p, last, 0.02, v3(0, 0, 0), v3(0, 0, 0)));
            cbm_segment_state s;
            CHECK_OK(cbm_plant_evaluate(p, NULL));
            CHECK_OK(cbm_plant_segment(p, last, &s));
            tips[which][b] = s.distal;
        }
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(p, fork, &s));
        tips[which][2] = s.distal;
        /* displacement from the unloaded shape */
        cbm_vec3 rest[3] = {tips[which][0], tips[which][1], tips[which][2]};
        cbm_solve_def sd = which ? cbm_solve_def_default() : fem_solve(1);
        sd.tolerance = 1e-12;
        CHECK_OK(cbm_plant_solve(p, &sd, NULL));
        /* the first lateral's tip (index n + n/2 - 1), the second's, the fork */
        size_t ids[3] = {(size_t)n + (size_t)(n / 2) - 1, last, fork};
        for (int k = 0; k < 3; k++) {
            CHECK_OK(cbm_plant_segment(p, ids[k], &s));
            tips[which][k] = v3_sub(s.distal, rest[k]);
            dmax[which] = fmax(dmax[which], v3_norm(tips[which][k]));
        }
        cbm_plant_destroy(p);
    }
    for (int k = 0; k < 3; k++) {
        double e = v3_norm(v3_sub(tips[0][k], tips[1][k]));
        printf("node %d: fem (%.4e %.4e %.4e) statics (%.4e %.4e %.4e) |diff| / max %.2e\n", k,
               tips[0][k].x, tips[0][k].y, tips[0][k].z, tips[1][k].x, tips[1][k].y, tips[1][k].z,
               e / dmax[1]);
        CHECK(e < 2e-3 * dmax[1]);
    }
    CHECK(dmax[1] > 1e-4); /* the load bends it measurably */
    test_ctx_end(ctx);
}

/* Large load: the increments converge (first order in 1/N) to the linearised path, which bends
 * further than the exact elastica: each increment acts on the current geometry but the moment of
 * the load already applied is never re-evaluated with the shortened lever arms. */
TEST(fem_large_load_increments_converge)
{
    cbm_context *ctx = test_ctx();
    const double L = 1.0, r = 0.01, E = 2e8, rho = 600.0, g = 9.81;
    double ei = E * PI * pow(r, 4) / 4.0, w = rho * g * PI * r * r;
    elastica ex = elastica_solve(0.0, w, 0.0, 0.0, ei, L, 4000);
    double tip[5];
    for (int k = 0; k < 5; k++) {
        cbm_plant *p = rod(ctx, 40, L, r, E, rho);
        cbm_solve_def sd = fem_solve((size_t)10 << k);
        CHECK_OK(cbm_plant_solve(p, &sd, NULL));
        tip[k] = rod_tip(p).y;
        printf("increments %4d: tip y %.7f (elastica %.7f)\n", 10 << k, tip[k], ex.y);
        cbm_plant_destroy(p);
    }
    for (int k = 2; k < 5; k++) {
        double ratio = (tip[k - 2] - tip[k - 1]) / (tip[k - 1] - tip[k]);
        printf("  convergence ratio %.3f\n", ratio);
        CHECK(ratio > 1.8 && ratio < 2.2); /* first order */
    }
    /* the limit (Richardson) lies below the elastica by more than the last steps move */
    double lim = 2 * tip[4] - tip[3];
    printf("  limit %.7f, elastica %.7f, difference %.3e m (%.2f %% of the sag)\n", lim, ex.y,
           lim - ex.y, 100 * (ex.y - lim) / ex.y);
    CHECK(lim < ex.y - 10 * fabs(tip[4] - tip[3]));
    CHECK(fabs(lim - ex.y) < 0.02 * fabs(ex.y));
    test_ctx_end(ctx);
}

/* A ring under an unchanged load freezes the shape: no new weight, no new load, no motion. */
TEST(fem_ring_without_load_freezes_shape)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = rod(ctx, 20, 1.0, 0.01, 2e8, 600.0);
    cbm_solve_def sd = fem_solve(20);
    CHECK_OK(cbm_plant_solve(p, &sd, NULL));
    cbm_vec3 t0 = rod_tip(p);
    cbm_fem_growth gr = cbm_fem_growth_default();
    gr.ring_thickness = 0.003;
    gr.wood.youngs_modulus = 2e8;
    gr.wood.shear_modulus = 2e8 / 2.6;
    gr.wood.density = 0.0;
    cbm_fem_stats fs;
    CHECK_OK(cbm_plant_fem_grow(p, NULL, &gr, &fs));
    CHECK_EQ_INT(fs.rings_added, 20);
    CHECK_EQ_INT(cbm_plant_ring_count(p, 7), 2);
    double d = v3_norm(v3_sub(rod_tip(p), t0));
    printf("tip moved %.3e m (sag %.3f m)\n", d, -t0.y);
    CHECK(d < 1e-12);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Rings adding their own weight: each ring's weight bends the rod with the stiffness of all rings
 * so far, so after K steps the sag is sum_k w_k L^4 / (8 E I_k) (small loads); a one-shot solve
 * of the same final rod sags only w L^4 / (8 E I_K). The statics' ring memory (Jirasek eq. 24)
 * gives the same answer in the linear limit. */
TEST(fem_rings_add_own_weight)
{
    cbm_context *ctx = test_ctx();
    const double L = 1.0, r0 = 0.01, t = 0.002, E = 1e11, rho = 600.0, g = 9.81;
    const int K = 5, n = 16;
    cbm_plant *p = rod(ctx, n, L, r0, E, rho);
    cbm_solve_def sd = fem_solve(1);
    CHECK_OK(cbm_plant_solve(p, &sd, NULL));
    double want = rho * g * PI * r0 * r0 * pow(L, 4) / (8.0 * E * PI * pow(r0, 4) / 4.0);
    cbm_fem_growth gr = cbm_fem_growth_default();
    gr.ring_thickness = t;
    gr.wood.youngs_modulus = E;
    gr.wood.shear_modulus = E / 2.6;
    gr.wood.density = rho;
    for (int k = 1; k <= K; k++) {
        CHECK_OK(cbm_plant_fem_grow(p, NULL, &gr, NULL));
        double ri = r0 + k * t, rp = ri - t;
        want += rho * g * PI * (ri * ri - rp * rp) * pow(L, 4) / (8.0 * E * PI * pow(ri, 4) / 4.0);
    }
    double rk = r0 + K * t;
    double oneshot = rho * g * PI * rk * rk * pow(L, 4) / (8.0 * E * PI * pow(rk, 4) / 4.0);
    double got = -rod_tip(p).y;
    printf("sag %.9e m, sum of ring increments %.9e m, one-shot %.9e m\n", got, want, oneshot);
    CHECK_REL(got, want, 1e-5);
    CHECK(got > 1.5 * oneshot);
    /* the statics with ring memory, the same rings: equal in the linear limit */
    cbm_plant *q = rod(ctx, 160, L, r0, E, rho);
    cbm_solve_def nd = cbm_solve_def_default();
    nd.tolerance = 1e-13;
    CHECK_OK(cbm_plant_solve(q, &nd, NULL));
    cbm_growth_def gd = cbm_growth_def_default();
    gd.youngs_juvenile = gd.youngs_adult = E;
    gd.shear_ratio = 1 / 2.6;
    gd.density = rho;
    for (int k = 1; k <= K; k++) {
        for (size_t i = 0; i < 160; i++)
            CHECK_OK(cbm_plant_add_growth_ring(q, i, r0 + k * t, r0 + k * t, &gd, NULL));
        CHECK_OK(cbm_plant_solve(q, &nd, NULL));
    }
    double st = -rod_tip(q).y;
    printf("statics with ring memory (160 segments): %.9e m\n", st);
    CHECK_REL(st, want, 2e-3);
    cbm_plant_destroy(q);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Maturation strain of a new ring (2.62, 2.78-2.82): without gravity the moment pair of every
 * element cancels at the inner nodes, leaving a uniform curvature change
 * (pi/6) E sigma (b - a) d(r^3) / (E I_total): the tip angle turns by that times L. */
TEST(fem_maturation_curvature_rate)
{
    cbm_context *ctx = test_ctx();
    const double L = 1.0, r0 = 0.01, t = 0.001, E = 1e10;
    double r1 = r0 + t;
    double rate = (PI / 6) * E * 1e-3 * (pow(r1, 3) - pow(r0, 3)) / (E * PI * pow(r1, 4) / 4);
    struct {
        double a, b, phi, sign;
    } cases[] = {
        {0.0, 1e-3, 0.0, 1.0},  /* compression wood below: up */
        {0.0, -1e-3, 0.0, 1.0}, /* tension wood above: up */
        {0.0, 1e-3, PI, -1.0},  /* reacting side turned over: down */
        {5e-4, 5e-4, 0.0, 0.0}, /* b = a: a uniform strain, no bending */
    };
    for (size_t c = 0; c < sizeof cases / sizeof *cases; c++) {
        cbm_plant *p = rod(ctx, 10, L, r0, E, 600.0);
        cbm_plant_set_gravity(p, v3(0, -1e-30, 0)); /* "up" is +y, no weight */
        CHECK_OK(cbm_plant_evaluate(p, NULL));
        cbm_fem_def fd = cbm_fem_def_default();
        fd.sigma = 1.0;
        fd.strain_min = cases[c].a;
        fd.strain_max = cases[c].b;
        fd.phi = cases[c].phi;
        cbm_fem_growth gr = cbm_fem_growth_default();
        gr.ring_thickness = t;
        gr.wood.youngs_modulus = E;
        gr.wood.shear_modulus = E / 2.6;
        CHECK_OK(cbm_plant_fem_grow(p, &fd, &gr, NULL));
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(p, 9, &s));
        double ang = atan2(s.frame.h.y, s.frame.h.x);
        /* the last chord turns by the curvature over the rod minus half a segment */
        double want = cases[c].sign * rate * (L - 0.05);
        printf("a=%g b=%g phi=%g: chord angle %.6e rad, curvature rate x (L - h/2) %.6e\n",
               cases[c].a, cases[c].b, cases[c].phi, ang, want);
        if (cases[c].sign == 0.0)
            CHECK(fabs(ang) < 1e-15);
        else
            CHECK_REL(ang, want, 1e-6);
        cbm_plant_destroy(p);
    }
    /* D5: the listing's axial resultant vanishes at sigma = 0, the formula's does not; neither
     * bends */
    test_ctx_end(ctx);
}

/* Primary and secondary growth on a branched plant: one new element per tip per step, a ring on
 * every older element, the element count and ring counts as the thesis's scheme gives. */
TEST(fem_growth_counts_and_tropism)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = clamped_plant(ctx, PI / 2);
    cbm_segment_def d = cbm_segment_def_default();
    d.length = 0.1;
    d.core.youngs_modulus = 1e8;
    d.core.shear_modulus = 1e8 / 16;
    CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    d.parent = 0;
    d.deviation = 0.8;
    d.lateral = true;
    CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    d.deviation = 0.0;
    d.lateral = false;
    CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    cbm_fem_growth gr = cbm_fem_growth_default();
    gr.ring_thickness = 0.001;
    gr.tip_length = 0.1;
    gr.tip_radius = 0.005;
    gr.wood = d.core;
    cbm_fem_stats fs;
    for (int k = 0; k < 5; k++) {
        CHECK_OK(cbm_plant_fem_grow(p, NULL, &gr, &fs));
        CHECK_EQ_INT(fs.tips_added, 2);
    }
    CHECK_EQ_INT(cbm_plant_segment_count(p), 13);
    CHECK_EQ_INT(cbm_plant_ring_count(p, 0), 6);
    CHECK_EQ_INT(cbm_plant_ring_count(p, 12), 1);
    /* the lateral sags under its growing weight: its tip lies lower than a straight lateral */
    cbm_segment_state s;
    CHECK_OK(cbm_plant_segment(p, 11, &s));
    printf("lateral tip heading y %.4f (straight: %.4f)\n", s.frame.h.y, cos(0.8));
    CHECK(s.frame.h.y < cos(0.8) - 1e-2);
    /* primary tropism: every new element starts along the direction */
    gr.primary_tropism = true;
    gr.direction = v3(1, 0, 0);
    gr.wood.density = 0.0;
    gr.ring_thickness = 0.0;
    CHECK_OK(cbm_plant_fem_grow(p, NULL, &gr, &fs));
    size_t n = cbm_plant_segment_count(p);
    for (size_t i = n - 2; i < n; i++) {
        CHECK_OK(cbm_plant_segment(p, i, &s));
        CHECK(v3_norm(v3_sub(s.frame.h, v3(1, 0, 0))) < 1e-9);
    }
    /* bad input is refused with a message, nothing changes */
    gr.tip_radius = -1;
    CHECK_STATUS(cbm_plant_fem_grow(p, NULL, &gr, NULL), CBM_E_INVALID);
    CHECK_EQ_INT(cbm_plant_segment_count(p), n);
    cbm_fem_def fd = cbm_fem_def_default();
    fd.sigma = 2;
    gr.tip_radius = 0.005;
    CHECK_STATUS(cbm_plant_fem_grow(p, &fd, &gr, NULL), CBM_E_INVALID);
    cbm_solve_def sd = fem_solve(0);
    CHECK_STATUS(cbm_plant_solve(p, &sd, NULL), CBM_E_INVALID);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

TEST(fem_solver_name)
{
    cbm_mech_solver s;
    CHECK(cbm_mech_solver_parse("fem", &s));
    CHECK_EQ_INT(s, CBM_MECH_FEM);
    CHECK(!strcmp(cbm_mech_solver_name(CBM_MECH_FEM), "fem"));
    CHECK(!strcmp(cbm_solve_stage_name(CBM_SOLVE_STAGE_FEM), "fem"));
}
