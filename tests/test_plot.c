/* The plotting module: nice ticks and their labels (values stated by hand), PNG files decoded
 * with libpng (size, white background, the series' colours present where drawn), SVG files
 * checked with xmllint when installed (well-formed, one <g class="series"> per series, text as
 * <text>), the same bytes for the same figure, and bad arguments refused with a message. */
#include "io_util.h"

#include "cambium/plot.h"

#include <stdlib.h>

static void check_ticks(double lo, double hi, int target, bool log, const double *want, size_t n)
{
    double t[64];
    size_t got = cbm_plot_ticks(lo, hi, target, log, t, 64);
    CHECK_MSG(got == n, "ticks of [%g, %g] target %d%s: %zu, expected %zu", lo, hi, target,
              log ? " log" : "", got, n);
    for (size_t i = 0; i < got && i < n; i++)
        CHECK_MSG(fabs(t[i] - want[i]) <= 1e-12 * fmax(1.0, fabs(want[i])),
                  "tick %zu of [%g, %g]: %.17g, expected %.17g", i, lo, hi, t[i], want[i]);
}

TEST(ticks_linear)
{
    check_ticks(0, 1, 5, false, (double[]){0, 0.2, 0.4, 0.6, 0.8, 1.0}, 6);
    check_ticks(0, 10, 4, false, (double[]){0, 2.5, 5, 7.5, 10}, 5);
    check_ticks(-3.2, 7.9, 5, false, (double[]){-2.5, 0, 2.5, 5, 7.5}, 5);
    check_ticks(-3.2, 7.9, 6, false, (double[]){-2, 0, 2, 4, 6}, 5);
    check_ticks(0.1, 0.35, 5, false, (double[]){0.1, 0.15, 0.2, 0.25, 0.3, 0.35}, 6);
    check_ticks(1e6, 5e6, 4, false, (double[]){1e6, 2e6, 3e6, 4e6, 5e6}, 5);
    check_ticks(-1e-5, 1e-5, 2, false, (double[]){-1e-5, 0, 1e-5}, 3);
    /* 0.1 * 3 is not 0.3 in binary: ticks are k * step, and 0 stays 0 */
    double t[16];
    size_t n = cbm_plot_ticks(-0.3, 0.3, 6, false, t, 16);
    CHECK_EQ_INT(n, 7);
    CHECK(t[3] == 0.0 && !signbit(t[3]));
    /* no range, no ticks */
    CHECK_EQ_INT(cbm_plot_ticks(1, 1, 5, false, t, 16), 0);
    CHECK_EQ_INT(cbm_plot_ticks(2, 1, 5, false, t, 16), 0);
    CHECK_EQ_INT(cbm_plot_ticks(0, NAN, 5, false, t, 16), 0);
    CHECK_EQ_INT(cbm_plot_ticks(0, 1, 5, false, t, 3), 3); /* capped by max */
}

TEST(ticks_log)
{
    check_ticks(1e-3, 1e3, 8, true, (double[]){1e-3, 1e-2, 1e-1, 1, 10, 100, 1000}, 7);
    check_ticks(1e-6, 1e6, 4, true, (double[]){1e-6, 1e-2, 1e2, 1e6}, 4); /* every 4th decade */
    check_ticks(1, 50, 5, true, (double[]){1, 2, 5, 10, 20, 50}, 6);
    double t[8];
    CHECK_EQ_INT(cbm_plot_ticks(0, 10, 5, true, t, 8), 0);
    CHECK_EQ_INT(cbm_plot_ticks(-1, 10, 5, true, t, 8), 0);
}

TEST(nice_range)
{
    double lo = 0.13, hi = 9.7;
    cbm_plot_nice_range(&lo, &hi, 5, false);
    CHECK(lo == 0.0 && hi == 10.0);
    lo = -0.013, hi = 0.0291;
    cbm_plot_nice_range(&lo, &hi, 4, false);
    CHECK_NEAR(lo, -0.02, 1e-15);
    CHECK_NEAR(hi, 0.04, 1e-15);
    lo = hi = 5.0; /* a point range is widened */
    cbm_plot_nice_range(&lo, &hi, 5, false);
    CHECK(lo < 5.0 && hi > 5.0);
    /* the range ends on ticks: [-0.81, 0.79] rounds to steps of 0.2 (-1, 0.8), whose ticks take
     * 0.25 and would stop at 0.75; it is rounded again to 0.25, so both ends are ticks */
    lo = -0.807935175864, hi = 0.790851308183;
    cbm_plot_nice_range(&lo, &hi, 8, false);
    {
        double t[32];
        size_t nt = cbm_plot_ticks(lo, hi, 8, false, t, 32);
        CHECK_MSG(nt >= 2 && fabs(t[0] - lo) < 1e-12 && fabs(t[nt - 1] - hi) < 1e-12,
                  "range [%g, %g], ticks %g .. %g", lo, hi, nt ? t[0] : NAN, nt ? t[nt - 1] : NAN);
    }
    for (double top = 0.05; top < 40.0; top *= 1.37) /* every range ends on ticks */
        for (int target = 3; target <= 10; target++) {
            double l2 = -0.3 * top, h2 = top, t[64];
            cbm_plot_nice_range(&l2, &h2, target, false);
            size_t nt = cbm_plot_ticks(l2, h2, target, false, t, 64);
            CHECK_MSG(nt >= 2 && fabs(t[0] - l2) <= 1e-9 * (h2 - l2) &&
                          fabs(t[nt - 1] - h2) <= 1e-9 * (h2 - l2) && l2 <= -0.3 * top && h2 >= top,
                      "[%g, %g] target %d: range [%g, %g], ticks %g .. %g", -0.3 * top, top, target,
                      l2, h2, nt ? t[0] : NAN, nt ? t[nt - 1] : NAN);
        }
    lo = 0.03, hi = 4000;
    cbm_plot_nice_range(&lo, &hi, 5, true);
    CHECK_NEAR(lo, 0.01, 1e-15);
    CHECK_NEAR(hi, 1e4, 1e-9);
    lo = 3, hi = 40;
    cbm_plot_nice_range(&lo, &hi, 5, true);
    CHECK(lo == 2.0 && hi == 50.0);
}

TEST(tick_labels)
{
    char lab[8][32];
    double a[] = {0, 0.2, 0.4, 0.6000000000000001};
    cbm_plot_tick_labels(a, 4, false, &lab[0][0], 32);
    CHECK(!strcmp(lab[0], "0.0") && !strcmp(lab[1], "0.2") && !strcmp(lab[3], "0.6"));
    double b[] = {-5, 0, 5, 10};
    cbm_plot_tick_labels(b, 4, false, &lab[0][0], 32);
    CHECK(!strcmp(lab[0], "-5") && !strcmp(lab[1], "0") && !strcmp(lab[3], "10"));
    double c[] = {0, 2.5, 5, 7.5};
    cbm_plot_tick_labels(c, 4, false, &lab[0][0], 32);
    CHECK(!strcmp(lab[1], "2.5") && !strcmp(lab[2], "5.0"));
    double d[] = {-1e-12, 0.25}; /* a rounding residue is not "-0.00" */
    cbm_plot_tick_labels(d, 2, false, &lab[0][0], 32);
    CHECK_MSG(!strcmp(lab[0], "0.00"), "got '%s'", lab[0]);
    double e[] = {1.2e6, 1.22e6, 1.24e6};
    cbm_plot_tick_labels(e, 3, false, &lab[0][0], 32);
    CHECK_MSG(!strcmp(lab[0], "1.20e+06") && !strcmp(lab[1], "1.22e+06"), "got '%s' '%s'", lab[0],
              lab[1]);
    double f[] = {1e-6, 1e-3, 1, 1e3, 1e6};
    cbm_plot_tick_labels(f, 5, true, &lab[0][0], 32);
    CHECK(!strcmp(lab[0], "1e-6") && !strcmp(lab[1], "0.001") && !strcmp(lab[2], "1") &&
          !strcmp(lab[3], "1000") && !strcmp(lab[4], "1e6"));
}

/* A figure of two panels: a curve solid and dashed with a gap, a scatter of markers, a log axis. */
static cbm_plot *sample_plot(cbm_context *ctx)
{
    cbm_plot_def d = cbm_plot_def_default();
    d.width = 480;
    d.height = 400;
    d.panels = 2;
    d.title = "Equilibria & <branches>";
    cbm_plot *p = NULL;
    CHECK_OK(cbm_plot_create(ctx, &d, &p));
    if (!p)
        return NULL;
    double x[50], y[50], z[50];
    for (int i = 0; i < 50; i++) {
        x[i] = i * 0.1;
        y[i] = sin(x[i]) * x[i];
        z[i] = exp(0.1 * i);
    }
    y[20] = NAN;
    cbm_plot_axes_def a = cbm_plot_axes_def_default();
    a.xlabel = "load (N)";
    a.ylabel = "deflection (m)";
    CHECK_OK(cbm_plot_set_axes(p, 0, &a));
    cbm_plot_series_def s = cbm_plot_series_def_default();
    s.x = x, s.y = y, s.n = 25, s.label = "stable";
    CHECK_OK(cbm_plot_add_series(p, 0, &s));
    s.x = x + 24, s.y = y + 24, s.n = 26, s.label = "unstable", s.line = CBM_PLOT_DASHED;
    CHECK_OK(cbm_plot_add_series(p, 0, &s));
    s = cbm_plot_series_def_default();
    s.x = x, s.y = z, s.n = 50, s.label = "growth", s.line = CBM_PLOT_NO_LINE;
    s.marker = CBM_PLOT_MARKER_CIRCLE;
    s.color[0] = 1.0f, s.color[1] = 0.0f, s.color[2] = 0.0f;
    a = cbm_plot_axes_def_default();
    a.ylog = true;
    a.xlabel = "time (years)";
    CHECK_OK(cbm_plot_set_axes(p, 1, &a));
    CHECK_OK(cbm_plot_add_series(p, 1, &s));
    return p;
}

/* A pixel within 40 levels of a colour in every channel (lines are anti-aliased). */
static bool near(const uint8_t *q, int r, int g, int b)
{
    return abs(q[0] - r) <= 40 && abs(q[1] - g) <= 40 && abs(q[2] - b) <= 40;
}

TEST(png_decodes_with_the_series_drawn)
{
    cbm_context *ctx = test_ctx();
    cbm_plot *p = sample_plot(ctx);
    char path[4096];
    snprintf(path, sizeof path, "%s/plot_sample.png", test_tmp_dir());
    CHECK_OK(cbm_plot_write(p, path));
    cbm_image *img = NULL;
    CHECK_OK(cbm_image_read_png(ctx, path, &img));
    if (img) {
        CHECK_EQ_INT(img->width, 480);
        CHECK_EQ_INT(img->height, 400);
        const uint8_t *c = img->rgba;
        CHECK(c[0] == 255 && c[1] == 255 && c[2] == 255 && c[3] == 255); /* white corner */
        size_t red = 0, blue = 0, vermillion = 0, dark = 0;
        for (size_t i = 0; i < (size_t)img->width * (size_t)img->height; i++) {
            const uint8_t *q = img->rgba + 4 * i;
            red += near(q, 255, 0, 0);
            blue += near(q, 0, 114, 178);      /* palette 1: #0072b2 */
            vermillion += near(q, 213, 94, 0); /* palette 2: #d55e00 */
            dark += q[0] < 60 && q[1] < 60 && q[2] < 60;
        }
        CHECK_MSG(red > 500 && blue > 150 && vermillion > 100 && dark > 500,
                  "red %zu blue %zu vermillion %zu dark %zu pixels", red, blue, vermillion, dark);
        /* the same figure rendered again gives the same pixels */
        cbm_image *again = NULL;
        CHECK_OK(cbm_plot_render(p, &again));
        if (again)
            CHECK(!memcmp(again->rgba, img->rgba, (size_t)img->width * (size_t)img->height * 4));
        cbm_image_destroy(again);
    }
    cbm_image_destroy(img);
    if (system("command -v pngfix >/dev/null 2>&1") == 0) {
        char cmd[4200];
        snprintf(cmd, sizeof cmd, "pngfix '%s' >/dev/null 2>&1", path);
        CHECK_MSG(system(cmd) == 0, "pngfix rejects %s", path);
    }
    cbm_plot_destroy(p);
    test_ctx_end(ctx);
}

TEST(svg_is_wellformed_with_series_and_text)
{
    cbm_context *ctx = test_ctx();
    cbm_plot *p = sample_plot(ctx);
    char path[4096], path2[4096];
    snprintf(path, sizeof path, "%s/plot_sample.svg", test_tmp_dir());
    snprintf(path2, sizeof path2, "%s/plot_sample2.svg", test_tmp_dir());
    CHECK_OK(cbm_plot_write(p, path));
    CHECK_OK(cbm_plot_write_as(p, path2, "SVG"));
    size_t n1 = 0, n2 = 0;
    char *a = io_read_all(path, &n1), *b = io_read_all(path2, &n2);
    CHECK(a && b);
    if (a && b) {
        CHECK(n1 == n2 && !memcmp(a, b, n1)); /* the same bytes */
        CHECK_EQ_INT(io_count(a, "<g class=\"series\">"), 3);
        CHECK_EQ_INT(io_count(a, "<g class=\"legend\">"), 2);
        CHECK(strstr(a, ">Equilibria &amp; &lt;branches&gt;</text>") != NULL);
        CHECK(strstr(a, ">deflection (m)</text>") != NULL);
        CHECK(strstr(a, "<title>unstable</title>") != NULL);
        CHECK(strstr(a, ">unstable</text>") != NULL);
        CHECK(strstr(a, "stroke-dasharray") != NULL);
        CHECK(strstr(a, ">time (years)</text>") != NULL);
        CHECK(strstr(a, ">100</text>") != NULL); /* a decade of the log axis */
        CHECK(strstr(a, "font-family=\"DejaVu Sans, sans-serif\"") != NULL);
    }
    free(a);
    free(b);
    if (system("command -v xmllint >/dev/null 2>&1") == 0) {
        char cmd[4200];
        snprintf(cmd, sizeof cmd, "xmllint --noout '%s'", path);
        CHECK_MSG(system(cmd) == 0, "xmllint rejects %s", path);
    }
    cbm_plot_destroy(p);
    test_ctx_end(ctx);
}

TEST(odd_data_and_text)
{
    cbm_context *ctx = test_ctx();
    cbm_plot *p = NULL;
    CHECK_OK(cbm_plot_create(ctx, NULL, &p));
    /* no series, a constant series, a series of NaN, points far outside a set range, and text
     * with broken UTF-8 and control characters: all drawn, none fails */
    cbm_plot_axes_def a = cbm_plot_axes_def_default();
    a.ymin = -1, a.ymax = 1;
    a.xlabel = "bad \xff\xfe utf-8 \x01 ok \xc3\xa9";
    CHECK_OK(cbm_plot_set_axes(p, 0, &a));
    double y[4] = {5, 5, 5, 5}, z[3] = {NAN, NAN, NAN}, far[3] = {-1e300, 1e300, 0};
    cbm_plot_series_def s = cbm_plot_series_def_default();
    s.y = y, s.n = 4, s.label = "\x1b[31mcolour";
    CHECK_OK(cbm_plot_add_series(p, 0, &s));
    s.y = z, s.n = 3, s.label = NULL;
    CHECK_OK(cbm_plot_add_series(p, 0, &s));
    s.y = far, s.n = 3, s.marker = CBM_PLOT_MARKER_PLUS;
    CHECK_OK(cbm_plot_add_series(p, 0, &s));
    char path[4096];
    snprintf(path, sizeof path, "%s/plot_odd.svg", test_tmp_dir());
    CHECK_OK(cbm_plot_write(p, path));
    char *t = io_read_all(path, NULL);
    CHECK(t && strstr(t, "bad ?? utf-8 ? ok \xc3\xa9") && strstr(t, "?[31mcolour"));
    free(t);
    if (system("command -v xmllint >/dev/null 2>&1") == 0) {
        char cmd[4200];
        snprintf(cmd, sizeof cmd, "xmllint --noout '%s'", path);
        CHECK_MSG(system(cmd) == 0, "xmllint rejects %s", path);
    }
    cbm_image *img = NULL;
    CHECK_OK(cbm_plot_render(p, &img));
    cbm_image_destroy(img);
    cbm_plot_destroy(p);
    test_ctx_end(ctx);
}

TEST(bad_arguments)
{
    cbm_context *ctx = test_ctx();
    cbm_plot_def d = cbm_plot_def_default();
    cbm_plot *p = NULL;
    d.width = 5;
    CHECK(cbm_plot_create(ctx, &d, &p) == CBM_E_INVALID && !p);
    CHECK(strstr(cbm_context_last_error(ctx), "size") != NULL);
    d = cbm_plot_def_default();
    d.panels = 5;
    CHECK(cbm_plot_create(ctx, &d, &p) == CBM_E_INVALID);
    CHECK_OK(cbm_plot_create(ctx, NULL, &p));
    cbm_plot_axes_def a = cbm_plot_axes_def_default();
    a.xlog = true, a.xmin = 0, a.xmax = 10;
    CHECK(cbm_plot_set_axes(p, 0, &a) == CBM_E_INVALID);
    CHECK(strstr(cbm_context_last_error(ctx), "log x axis") != NULL);
    a = cbm_plot_axes_def_default();
    a.ymin = 3, a.ymax = 3;
    CHECK(cbm_plot_set_axes(p, 0, &a) == CBM_E_INVALID);
    CHECK(cbm_plot_set_axes(p, 1, &a) == CBM_E_INVALID); /* one panel only */
    cbm_plot_series_def s = cbm_plot_series_def_default();
    s.n = 3;
    CHECK(cbm_plot_add_series(p, 0, &s) == CBM_E_INVALID); /* no y */
    char path[4096];
    snprintf(path, sizeof path, "%s/plot_bad.pdf", test_tmp_dir());
    CHECK(cbm_plot_write(p, path) == CBM_E_UNSUPPORTED);
    FILE *f = fopen(path, "rb");
    CHECK(f == NULL); /* nothing written */
    if (f)
        fclose(f);
    snprintf(path, sizeof path, "%s/no-such-dir/plot.svg", test_tmp_dir());
    CHECK(cbm_plot_write(p, path) == CBM_E_IO);
    cbm_plot_destroy(p);
    test_ctx_end(ctx);
}

/* Every allocation failing in turn: the figure is built and drawn, or refused with
 * CBM_E_NOMEM, with every byte returned (test_oom_loop checks both). */
static cbm_status build_and_render(cbm_context *ctx, void *ud)
{
    (void)ud;
    cbm_plot *p = NULL;
    cbm_status cs = cbm_plot_create(ctx, NULL, &p);
    if (cs != CBM_OK)
        return cs;
    double y[300];
    for (int i = 0; i < 300; i++)
        y[i] = i % 7;
    y[100] = NAN;
    cbm_plot_series_def s = cbm_plot_series_def_default();
    s.y = y, s.n = 300, s.label = "a", s.marker = CBM_PLOT_MARKER_SQUARE;
    cbm_status st = cbm_plot_add_series(p, 0, &s);
    cbm_image *img = NULL;
    if (st == CBM_OK)
        st = cbm_plot_render(p, &img);
    cbm_image_destroy(img);
    cbm_plot_destroy(p);
    return st;
}

TEST(out_of_memory)
{
    CHECK(test_oom_loop(build_and_render, NULL) > 3);
}
