/* Light interception (src/light) against cases computed by hand: an unshaded leaf at any tilt
 * (the discrete sky's closed form, and the analytic integral of the UOC and SOC skies as the
 * sectors refine), a leaf under a leaf in a directional beam (overlap of rectangles), a leaf
 * under an opaque disc and an annulus in a uniform sky (view factors), the bounded dome, the
 * open field and the periodic stand; determinism and independence of the thread count. The
 * references and tolerances are in docs/validation.md ("Light interception"). */
#include "test.h"

#include "cambium/light.h"

#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

static cbm_context *new_ctx(void)
{
    cbm_context_def cd = cbm_context_def_default();
    cbm_context *ctx = NULL;
    CHECK(cbm_context_create(&cd, &ctx) == CBM_OK);
    return ctx;
}

static void end_ctx(cbm_context *ctx)
{
    CHECK_EQ_INT(cbm_context_bytes(ctx), 0);
    cbm_context_destroy(ctx);
}

/* a w x d rectangle centred at c, tilted by beta about the x axis (upper face normal
 * (0, cos beta, -sin beta)... turned towards -z), CCW seen from above when beta < 90° */
static cbm_light_leaf rect_leaf(cbm_vec3 c, double w, double d, double beta)
{
    double cb = cos(beta), sb = sin(beta);
    cbm_light_leaf l;
    l.plant = 0;
    const double su[4] = {-0.5, 0.5, 0.5, -0.5}, sv[4] = {0.5, 0.5, -0.5, -0.5};
    for (int k = 0; k < 4; k++) {
        double x = su[k] * w, zl = sv[k] * d;
        /* rotate (0, 0, zl) about x by beta: y = zl sin(beta)... keep the leaf's centre */
        l.p[k] = (cbm_vec3){c.x + x, c.y + zl * sb, c.z + zl * cb};
    }
    return l;
}

/* the closed form of an unshaded leaf: area x sum_k E_k c_k(n . d_k) */
static double closed_form(cbm_context *ctx, const cbm_light_def *d, cbm_vec3 n, double area)
{
    cbm_light_source *s = NULL;
    size_t m = 0;
    CHECK(cbm_light_sources(ctx, d, &s, &m) == CBM_OK);
    double sum = 0.0;
    for (size_t k = 0; k < m; k++) {
        double c = n.x * s[k].dir.x + n.y * s[k].dir.y + n.z * s[k].dir.z;
        sum += s[k].irradiance * (d->two_sided ? fabs(c) : fmax(0.0, c));
    }
    cbm_light_sources_free(ctx, s, m);
    return area * sum;
}

static double one_leaf(cbm_context *ctx, const cbm_light_def *d, cbm_light_leaf l)
{
    double a = -1.0;
    CHECK(cbm_light_intercept(ctx, d, &l, 1, NULL, 0, &a, NULL) == CBM_OK);
    return a;
}

TEST(sources_normalised)
{
    cbm_context *ctx = new_ctx();
    for (int sky = CBM_SKY_DOME; sky <= CBM_SKY_SOC; sky++)
        for (int f = 0; f < 2; f++) {
            cbm_light_def d = cbm_light_def_default();
            d.sky = (cbm_sky_kind)sky;
            d.direct_fraction = 0.3 * f;
            cbm_light_source *s = NULL;
            size_t m = 0;
            CHECK(cbm_light_sources(ctx, &d, &s, &m) == CBM_OK);
            double h = 0.0;
            for (size_t k = 0; k < m; k++) {
                CHECK(s[k].dir.y > 0);
                CHECK_NEAR(sqrt(s[k].dir.x * s[k].dir.x + s[k].dir.y * s[k].dir.y +
                                s[k].dir.z * s[k].dir.z),
                           1.0, 1e-12);
                h += s[k].irradiance * s[k].dir.y;
            }
            CHECK_NEAR(h, 1.0, 1e-12);
            cbm_light_sources_free(ctx, s, m);
        }
    end_ctx(ctx);
}

/* an unshaded leaf at any tilt gets area x sum E_k c_k, to rounding, in every sky and
 * sampling; a horizontal one exactly its area */
TEST(unshaded_any_tilt)
{
    cbm_context *ctx = new_ctx();
    const double tilts[] = {0.0, 0.2, 0.7, PI / 2, 2.0, 3.0};
    for (int sky = CBM_SKY_DOME; sky <= CBM_SKY_SOC; sky++)
        for (int side = 0; side < 2; side++)
            for (size_t t = 0; t < sizeof tilts / sizeof tilts[0]; t++) {
                cbm_light_def d = cbm_light_def_default();
                d.sky = (cbm_sky_kind)sky;
                d.two_sided = side;
                d.direct_fraction = 0.25;
                d.samples = 3;
                double b = tilts[t];
                cbm_light_leaf l = rect_leaf((cbm_vec3){1.0, 2.0, -3.0}, 0.4, 0.25, b);
                cbm_vec3 n = {0.0, cos(b), -sin(b)};
                double want = closed_form(ctx, &d, n, 0.1);
                CHECK_NEAR(one_leaf(ctx, &d, l), want, 1e-12);
                if (b == 0.0)
                    CHECK_NEAR(want, 0.1, 1e-14);
            }
    end_ctx(ctx);
}

static double uoc_exact(double b, bool two)
{
    return two ? 1.0 : 0.5 * (1.0 + cos(b));
}

static double soc_exact(double b, bool two)
{
    double up = PI / 6 * (1 + cos(b)) + 4.0 / 9.0 * ((PI - b) * cos(b) + sin(b));
    double bm = PI - b;
    double down = PI / 6 * (1 + cos(bm)) + 4.0 / 9.0 * ((PI - bm) * cos(bm) + sin(bm));
    return (up + (two ? down : 0.0)) / (7.0 * PI / 9.0);
}

/* the discrete UOC and SOC skies converge to the analytic integrals as the sectors refine:
 * (1 + cos b)/2 for UOC, the lune integral for SOC; error at most 2e-3 at 24 x 48 sectors and
 * falling at least by half per doubling from 6 x 12 */
TEST(sky_sectors_converge)
{
    cbm_context *ctx = new_ctx();
    const double tilts[] = {0.3, 1.0, PI / 2, 2.2};
    for (int sky = CBM_SKY_UOC; sky <= CBM_SKY_SOC; sky++)
        for (int side = 0; side < 2; side++)
            for (size_t t = 0; t < sizeof tilts / sizeof tilts[0]; t++) {
                double b = tilts[t], prev = 1.0;
                double exact = sky == CBM_SKY_UOC ? uoc_exact(b, side) : soc_exact(b, side);
                for (int r = 6; r <= 48; r *= 2) {
                    cbm_light_def d = cbm_light_def_default();
                    d.sky = (cbm_sky_kind)sky;
                    d.two_sided = side;
                    d.rings = r;
                    d.azimuths = 2 * r;
                    d.samples = 1;
                    double got = one_leaf(ctx, &d, rect_leaf((cbm_vec3){0, 0, 0}, 1, 1, b));
                    double err = fabs(got - exact);
                    CHECK_MSG(err <= 0.5 * prev + 1e-9, "sky %d tilt %g: %d rings err %.3g", sky, b,
                              r, err);
                    if (r == 24)
                        CHECK_MSG(err <= 2e-3, "sky %d tilt %g: err %.3g", sky, b, err);
                    prev = err;
                }
            }
    end_ctx(ctx);
}

static double overlap1(double a0, double a1, double b0, double b1)
{
    return fmax(0.0, fmin(a1, b1) - fmax(a0, b0));
}

/* a leaf under a leaf in a directional beam (the sun alone): the lower leaf loses exactly the
 * overlap of the upper leaf's shadow (a rectangle shifted by h s_xz / s_y) with it */
TEST(leaf_under_leaf_directional)
{
    cbm_context *ctx = new_ctx();
    cbm_light_def d = cbm_light_def_default();
    d.sky = CBM_SKY_UOC;
    d.direct_fraction = 1.0;
    d.sun = (cbm_vec3){0.3, 1.0, -0.2};
    d.samples = 16;
    /* lower leaf [0,1] x [0,1] at y = 0; upper leaf [0.3,1.3] x [0.2,0.7] at y = 0.5 */
    cbm_light_leaf l[2];
    l[0] = rect_leaf((cbm_vec3){0.5, 0.0, 0.5}, 1.0, 1.0, 0.0);
    l[1] = rect_leaf((cbm_vec3){0.8, 0.5, 0.45}, 1.0, 0.5, 0.0);
    double sx = -0.5 * 0.3, sz = -0.5 * -0.2; /* shadow shift h * (-s_x, -s_z) / s_y */
    double ov = overlap1(0, 1, 0.3 + sx, 1.3 + sx) * overlap1(0, 1, 0.2 + sz, 0.7 + sz);
    double mean = 0.0;
    const int seeds = 32;
    for (int s = 1; s <= seeds; s++) {
        d.seed = (uint64_t)s;
        double a[2];
        cbm_light_stats st;
        CHECK(cbm_light_intercept(ctx, &d, l, 2, NULL, 0, a, &st) == CBM_OK);
        CHECK_NEAR(a[1], 0.5, 1e-12);
        CHECK_NEAR(a[0], 1.0 - ov, 0.03);
        CHECK_EQ_INT(st.sources, 1);
        mean += a[0] / seeds;
    }
    CHECK_NEAR(mean, 1.0 - ov, 0.006);
    /* with 1 sample per leaf the lower leaf's centre decides: (0.5, 0.5) is in the shadow */
    d.samples = 1;
    d.seed = 1;
    double a[2];
    CHECK(cbm_light_intercept(ctx, &d, l, 2, NULL, 0, a, NULL) == CBM_OK);
    CHECK(a[0] >= 0.0 && a[0] <= 1.0);
    end_ctx(ctx);
}

/* a polygon of nseg sides (radius r0..r1 annulus; r0 = 0: a disc) at height h, as occluder
 * triangles; returns the triangle count */
static size_t annulus(cbm_vec3 *v, int nseg, double r0, double r1, double h)
{
    size_t n = 0;
    for (int k = 0; k < nseg; k++) {
        double a0 = 2 * PI * k / nseg, a1 = 2 * PI * (k + 1) / nseg;
        cbm_vec3 o0 = {r1 * cos(a0), h, r1 * sin(a0)}, o1 = {r1 * cos(a1), h, r1 * sin(a1)};
        cbm_vec3 i0 = {r0 * cos(a0), h, r0 * sin(a0)}, i1 = {r0 * cos(a1), h, r0 * sin(a1)};
        v[3 * n] = i0, v[3 * n + 1] = o0, v[3 * n + 2] = o1, n++;
        if (r0 > 0)
            v[3 * n] = i0, v[3 * n + 1] = o1, v[3 * n + 2] = i1, n++;
    }
    return n;
}

/* a small horizontal leaf in a uniform (and a standard overcast) sky under a coaxial opaque
 * disc or annulus: it sees 1 - F, with the view factor F = R²/(R² + h²) of a disc (differences
 * of two for an annulus). The edges sit on ring boundaries of the sky (45°; 30° and 60°), so
 * the sky's discretisation adds nothing; what remains is the 512-gon and the 1 cm leaf. */
TEST(leaf_in_uniform_sky_under_disc)
{
    cbm_context *ctx = new_ctx();
    enum { NSEG = 512 };
    cbm_vec3 *v = calloc(3 * 2 * NSEG, sizeof *v);
    cbm_light_leaf leaf = rect_leaf((cbm_vec3){0, 0, 0}, 0.01, 0.01, 0.0);
    const double h = 1.0;
    /* the third case's edge (38.7°) falls inside a 1° ring: up to that ring's share */
    struct {
        double r0, r1;
        int rings;
        double tol;
    } cases[] = {{0.0, 1.0, 18, 0.0},
                 {tan(PI / 6), tan(PI / 3), 12, 0.0},
                 {0.0, 0.8, 90, pow(sin(atan(0.8) + PI / 180), 2) - pow(sin(atan(0.8)), 2)}};
    for (int c = 0; c < 3; c++)
        for (int sky = CBM_SKY_UOC; sky <= CBM_SKY_SOC; sky++) {
            size_t nt = annulus(v, NSEG, cases[c].r0, cases[c].r1, h);
            cbm_light_def d = cbm_light_def_default();
            d.sky = (cbm_sky_kind)sky;
            d.rings = cases[c].rings;
            d.azimuths = 64;
            d.samples = 2;
            double a = 0;
            CHECK(cbm_light_intercept(ctx, &d, &leaf, 1, v, nt, &a, NULL) == CBM_OK);
            /* fraction of the horizontal irradiance from zenith angles below t */
            double c0 = cases[c].r0 / sqrt(cases[c].r0 * cases[c].r0 + h * h);
            double c1 = cases[c].r1 / sqrt(cases[c].r1 * cases[c].r1 + h * h);
            double t0 = asin(c0), t1 = asin(c1), blocked;
            if (sky == CBM_SKY_UOC) {
                blocked = sin(t1) * sin(t1) - sin(t0) * sin(t0);
            } else {
                /* 2π ∫ (1 + 2 cos t)/3 cos t sin t dt / (7π/9) */
                double g0 = 0.5 * sin(t0) * sin(t0) + 2.0 / 3.0 * (1 - pow(cos(t0), 3));
                double g1 = 0.5 * sin(t1) * sin(t1) + 2.0 / 3.0 * (1 - pow(cos(t1), 3));
                blocked = (2.0 * PI / 3.0) * (g1 - g0) / (7.0 * PI / 9.0);
            }
            double want = 1e-4 * (1.0 - blocked);
            if (cases[c].tol == 0.0)
                CHECK_REL(a, want, 1e-9);
            else
                CHECK_NEAR(a, want, 1e-4 * cases[c].tol);
        }
    free(v);
    end_ctx(ctx);
}

/* the dome: unbounded it is translation invariant; with a beam radius a leaf beyond it from
 * the focus loses the lights whose beams miss it, and the calibration says so */
TEST(dome_focus_and_calibration)
{
    cbm_context *ctx = new_ctx();
    cbm_light_def d = cbm_light_def_default();
    d.sky = CBM_SKY_DOME;
    double m = 0;
    CHECK(cbm_light_calibrate(ctx, &d, (cbm_vec3){40, 3, -7}, &m) == CBM_OK);
    CHECK_NEAR(m, 1.0, 1e-12);
    d.dome_radius = 5.0;
    d.samples = 4; /* the 1 m leaf straddles the beams' edges: sample it */
    CHECK(cbm_light_calibrate(ctx, &d, (cbm_vec3){0, 0, 0}, &m) == CBM_OK);
    CHECK_NEAR(m, 1.0, 1e-12); /* a 1 m leaf at the focus is inside every beam */
    CHECK(cbm_light_calibrate(ctx, &d, (cbm_vec3){4.9, 0, 0}, &m) == CBM_OK);
    CHECK(m < 0.95 && m > 0.2);
    CHECK(cbm_light_calibrate(ctx, &d, (cbm_vec3){50, 0, 0}, &m) == CBM_OK);
    CHECK_NEAR(m, 0.0, 1e-12);
    /* max_light_square divides: calibrating at a point makes a leaf there 1 */
    CHECK(cbm_light_calibrate(ctx, &d, (cbm_vec3){4.9, 0, 0}, &m) == CBM_OK);
    d.max_light_square = m;
    CHECK_NEAR(one_leaf(ctx, &d, rect_leaf((cbm_vec3){4.9, 0, 0}, 1, 1, 0)), 1.0, 1e-12);
    end_ctx(ctx);
}

/* the open field: an isolated leaf is lit the same anywhere inside; below a wide roof a leaf
 * at the field's edge gets the oblique light the centre's roof blocks... and none from outside */
TEST(field_open_and_periodic)
{
    cbm_context *ctx = new_ctx();
    cbm_light_def d = cbm_light_def_default();
    d.sky = CBM_SKY_FIELD;
    d.field_min[0] = -10, d.field_max[0] = 10;
    d.field_min[1] = -10, d.field_max[1] = 10;
    d.field_height = 5;
    /* an isolated leaf near the lights' height gets every light, wherever it is */
    CHECK_NEAR(one_leaf(ctx, &d, rect_leaf((cbm_vec3){0, 4.9, 0}, 1, 1, 0)), 1.0, 1e-12);
    CHECK_NEAR(one_leaf(ctx, &d, rect_leaf((cbm_vec3){5, 4.9, -5}, 1, 1, 0)), 1.0, 1e-12);
    /* deep below the field near its edge some lights enter outside the rectangle: less */
    double edge = one_leaf(ctx, &d, rect_leaf((cbm_vec3){9, -20, 0}, 1, 1, 0));
    CHECK(edge < 0.9 && edge > 0.1);

    /* periodic: the sun alone at 3 tiles across per unit of height; a canopy strip
     * [0, 0.5] x [0, 1] at y = 1 of the 1 x 1 tile; a ray from (x, 0) reaches the canopy at
     * x + 3, so it is stopped when frac(x) < 0.5 (after wrapping 3 times), and never when
     * the edges are open */
    cbm_light_def p = cbm_light_def_default();
    p.sky = CBM_SKY_UOC;
    p.direct_fraction = 1.0;
    p.sun = (cbm_vec3){3.0, 1.0, 0.0};
    p.samples = 2;
    p.field_min[0] = 0, p.field_max[0] = 1;
    p.field_min[1] = 0, p.field_max[1] = 1;
    cbm_light_leaf l[3];
    l[0] = rect_leaf((cbm_vec3){0.25, 1.0, 0.5}, 0.5, 1.0, 0.0); /* canopy */
    l[1] = rect_leaf((cbm_vec3){0.65, 0.0, 0.5}, 0.1, 0.1, 0.0); /* lit */
    l[2] = rect_leaf((cbm_vec3){0.25, 0.0, 0.5}, 0.1, 0.1, 0.0); /* shaded */
    double a[3];
    cbm_light_stats st;
    p.edge = CBM_LIGHT_EDGE_PERIODIC;
    CHECK(cbm_light_intercept(ctx, &p, l, 3, NULL, 0, a, &st) == CBM_OK);
    CHECK_NEAR(a[0], 0.5, 1e-12);
    CHECK_NEAR(a[1], 0.01, 1e-12);
    CHECK_NEAR(a[2], 0.0, 1e-12);
    CHECK(st.rays > 3 * 4);
    /* the same stand shifted by whole tiles gives the same light */
    cbm_light_leaf s[3];
    memcpy(s, l, sizeof s);
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 4; k++)
            s[i].p[k].x += 7.0, s[i].p[k].z -= 2.0;
    double b[3];
    CHECK(cbm_light_intercept(ctx, &p, s, 3, NULL, 0, b, NULL) == CBM_OK);
    for (int i = 0; i < 3; i++)
        CHECK_NEAR(b[i], a[i], 1e-12);
    p.edge = CBM_LIGHT_EDGE_OPEN;
    CHECK(cbm_light_intercept(ctx, &p, l, 3, NULL, 0, a, NULL) == CBM_OK);
    CHECK_NEAR(a[2], 0.01, 1e-12);
    end_ctx(ctx);
}

static cbm_light_leaf *random_leaves(size_t n, uint64_t seed)
{
    cbm_light_leaf *l = calloc(n, sizeof *l);
    uint64_t x = seed;
    for (size_t i = 0; i < n; i++) {
        double r[5];
        for (int k = 0; k < 5; k++) {
            x = x * 6364136223846793005ull + 1442695040888963407ull;
            r[k] = (double)(x >> 11) / 9007199254740992.0;
        }
        l[i] =
            rect_leaf((cbm_vec3){4 * r[0], 3 * r[1], 4 * r[2]}, 0.1 + 0.1 * r[3], 0.1, 1.2 * r[4]);
        l[i].plant = (uint32_t)(i % 3);
    }
    return l;
}

/* a canopy of random leaves: the same numbers with 1, 2 and 3 threads; another seed moves
 * the sample points (results change a little, the mean stays); shaded leaves get less */
TEST(deterministic_any_threads)
{
    cbm_context *ctx = new_ctx();
    const size_t n = 700;
    cbm_light_leaf *l = random_leaves(n, 7);
    double *a = calloc(n, sizeof *a), *b = calloc(n, sizeof *b);
    cbm_light_def d = cbm_light_def_default();
    d.threads = 1;
    cbm_light_stats s1, s2;
    CHECK(cbm_light_intercept(ctx, &d, l, n, NULL, 0, a, &s1) == CBM_OK);
    for (int t = 2; t <= 3; t++) {
        d.threads = t;
        CHECK(cbm_light_intercept(ctx, &d, l, n, NULL, 0, b, &s2) == CBM_OK);
        CHECK(memcmp(a, b, n * sizeof *a) == 0);
        CHECK_EQ_INT(s1.rays, s2.rays);
    }
    CHECK(s1.total < s1.leaf_area);
    CHECK(s1.total > 0.2 * s1.leaf_area);
    d.seed = 99;
    CHECK(cbm_light_intercept(ctx, &d, l, n, NULL, 0, b, &s2) == CBM_OK);
    CHECK(memcmp(a, b, n * sizeof *a) != 0);
    CHECK_REL(s2.total, s1.total, 0.02);
    free(a);
    free(b);
    free(l);
    end_ctx(ctx);
}

TEST(bad_input)
{
    cbm_context *ctx = new_ctx();
    cbm_light_leaf l = rect_leaf((cbm_vec3){0, 0, 0}, 1, 1, 0);
    double a = 5;
    cbm_light_def d = cbm_light_def_default();
    d.rings = 0;
    CHECK(cbm_light_intercept(ctx, &d, &l, 1, NULL, 0, &a, NULL) == CBM_E_INVALID);
    d = cbm_light_def_default();
    d.direct_fraction = 0.5;
    d.sun = (cbm_vec3){1, -1, 0};
    CHECK(cbm_light_intercept(ctx, &d, &l, 1, NULL, 0, &a, NULL) == CBM_E_INVALID);
    d = cbm_light_def_default();
    l.p[2].y = NAN;
    CHECK(cbm_light_intercept(ctx, &d, &l, 1, NULL, 0, &a, NULL) == CBM_E_INVALID);
    CHECK(strstr(cbm_context_last_error(ctx), "leaf 0") != NULL);
    CHECK(cbm_light_intercept(ctx, &d, NULL, 0, NULL, 0, NULL, NULL) == CBM_OK);
    /* a degenerate leaf gets nothing */
    l = rect_leaf((cbm_vec3){0, 0, 0}, 0, 1, 0);
    CHECK(cbm_light_intercept(ctx, &d, &l, 1, NULL, 0, &a, NULL) == CBM_OK);
    CHECK_NEAR(a, 0.0, 0.0);
    /* the memory limit is honoured (Embree's allocations included) */
    cbm_limits lim = *cbm_context_limits(ctx);
    lim.max_bytes = 4096;
    cbm_context_set_limits(ctx, &lim);
    cbm_light_leaf *many = random_leaves(2000, 3);
    double *out = calloc(2000, sizeof *out);
    cbm_status st = cbm_light_intercept(ctx, &d, many, 2000, NULL, 0, out, NULL);
    CHECK(st == CBM_E_NOMEM);
    free(many);
    free(out);
    end_ctx(ctx);
}

static void square_part(cbm_scene *s, cbm_organ organ, double x0, double x1, double y, bool flip)
{
    cbm_part p = cbm_part_default();
    p.organ = organ;
    CHECK(cbm_scene_begin_part(s, &p, NULL) == CBM_OK);
    cbm_vec3 q[4] = {{x0, y, 0}, {x1, y, 0}, {x1, y, 1}, {x0, y, 1}};
    if (flip) {
        cbm_vec3 t = q[1];
        q[1] = q[3];
        q[3] = t;
    }
    CHECK(cbm_scene_add_polygon(s, q, 4) == CBM_OK);
}

/* a writer's scene: the leaf parts are the leaves (turned up whatever their winding), other
 * parts occlude, the ground does not; the sun overhead, a roof over half the leaf: the leaf
 * part gets half its area, its relative light 0.5 (16 x 16 jittered points per triangle: the
 * worst of 200 seeds was 0.016 off) */
TEST(scene_parts)
{
    cbm_context *ctx = new_ctx();
    cbm_scene *s = NULL;
    CHECK(cbm_scene_create(ctx, &s) == CBM_OK);
    square_part(s, CBM_ORGAN_LEAF, 0, 1, 0, true);
    square_part(s, CBM_ORGAN_BRANCH, 0, 0.5, 1, false);
    square_part(s, CBM_ORGAN_GROUND, -5, 5, 2, false);
    cbm_light_def d = cbm_light_def_default();
    d.direct_fraction = 1.0;
    d.sun = (cbm_vec3){0, 1, 0};
    d.samples = 16;
    d.two_sided = false;
    double pl[3], pa[3];
    size_t nl = 0;
    CHECK(cbm_light_scene(ctx, &d, s, pl, pa, &nl, NULL) == CBM_OK);
    CHECK_EQ_INT(nl, 2);
    CHECK_NEAR(pa[0], 1.0, 1e-6);
    CHECK_NEAR(pl[0], 0.5, 0.03);
    CHECK_NEAR(cbm_scene_parts(s)[0].light, pl[0] / pa[0], 1e-12);
    CHECK(isnan(cbm_scene_parts(s)[1].light));
    CHECK_NEAR(pa[1], 0.0, 0.0);
    cbm_scene_destroy(s);
    end_ctx(ctx);
}
