/* Lines (cpfg's pixel lines kept untessellated): the PNG rasteriser on known figures (a square of
 * four lines at a fitted camera: the dark pixels where the lines run, the inside left to the
 * background, the width in pixels as asked, anti-aliased edges), the depth order of crossing
 * lines in 3-D, lines and triangles in one picture, the SVG <line> elements and their order,
 * the refusal of the mesh formats, the turtle's line mode (lines instead of tubes, runs of
 * segments sharing a part; cylinders stay tubes), the same picture with any thread count, no file
 * left by a failed write, and allocation failures. */
#include "io_util.h"

#include "core/vecmath.h"
#include "io/writers.h"

#include <math.h>
#include <sys/stat.h>

#define LSYS CBM_TEST_SOURCE_DIR "/tests/lsys/"

/* sRGB byte -> linear */
static double lin(uint8_t v)
{
    double c = v / 255.0;
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

static const uint8_t *px(const cbm_image *img, int x, int y)
{
    return img->rgba + 4 * ((size_t)y * (size_t)img->width + (size_t)x);
}

/* Front view, white opaque background, no legend, one thread. */
static cbm_write_options line_opts(int w, int h)
{
    cbm_write_options o = cbm_write_options_default();
    o.width = w;
    o.height = h;
    o.view = CBM_VIEW_FRONT;
    o.threads = 1;
    o.shadows = false;
    o.ao_samples = 0;
    o.ground = false;
    return o;
}

static cbm_part colored(float r, float g, float b)
{
    cbm_part p = cbm_part_default();
    p.color[0] = r;
    p.color[1] = g;
    p.color[2] = b;
    return p;
}

/* The unit square in the z = 0 plane as four black lines `width` pixels wide. */
static void add_square(cbm_scene *s, double width)
{
    cbm_part p = colored(0, 0, 0);
    CHECK_OK(cbm_scene_begin_part(s, &p, NULL));
    cbm_vec3 c[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    for (int k = 0; k < 4; k++)
        CHECK_OK(cbm_scene_add_line(s, c[k], c[(k + 1) % 4], width));
}

TEST(square_of_four_lines)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(cbm_scene_create(ctx, &s));
    add_square(s, 3.0);
    CHECK_EQ_INT((int)cbm_scene_line_count(s), 4);
    CHECK_EQ_INT((int)cbm_scene_triangle_count(s), 0);
    cbm_vec3 lo, hi;
    CHECK(cbm_scene_bounds(s, &lo, &hi));
    CHECK_NEAR(hi.x - lo.x, 1.0, 1e-7);
    /* 100 x 100, the square fitted to 90 %: its sides run along x, y = 5 and 95 (pixel edges);
     * 4 x 4 samples per pixel put each side's 3-pixel band exactly on 2 full rows and 2 halves */
    cbm_write_options o = line_opts(100, 100);
    o.supersample = 4;
    cbm_image *img = NULL;
    CHECK_OK(cbm_render(ctx, s, &o, &img));
    if (img) {
        /* the top side, at x = 50: rows 4 and 5 black, rows 3 and 6 half, rows 2 and 7 white */
        CHECK_EQ_INT(px(img, 50, 4)[0], 0);
        CHECK_EQ_INT(px(img, 50, 5)[0], 0);
        CHECK_NEAR(1.0 - lin(px(img, 50, 3)[0]), 0.5, 0.01);
        CHECK_NEAR(1.0 - lin(px(img, 50, 6)[0]), 0.5, 0.01);
        CHECK_EQ_INT(px(img, 50, 2)[0], 255);
        CHECK_EQ_INT(px(img, 50, 7)[0], 255);
        /* the other three sides */
        CHECK_EQ_INT(px(img, 50, 95)[1], 0);
        CHECK_EQ_INT(px(img, 4, 50)[2], 0);
        CHECK_EQ_INT(px(img, 95, 50)[0], 0);
        /* the inside and the outside are the background; the picture is opaque */
        CHECK_EQ_INT(px(img, 50, 50)[0], 255);
        CHECK_EQ_INT(px(img, 20, 80)[1], 255);
        CHECK_EQ_INT(px(img, 1, 1)[2], 255);
        CHECK_EQ_INT(px(img, 50, 50)[3], 255);
        /* the width: coverage summed across each side is 3 pixels, wherever along it */
        for (int x = 20; x <= 80; x += 15) {
            double cov = 0, cov2 = 0;
            for (int y = 0; y < 20; y++)
                cov += 1.0 - lin(px(img, x, y)[0]);
            for (int xx = 80; xx < 100; xx++)
                cov2 += 1.0 - lin(px(img, xx, x)[0]);
            CHECK_NEAR(cov, 3.0, 0.02);
            CHECK_NEAR(cov2, 3.0, 0.02);
        }
        /* the corner at (5, 5) is rounded (the lines' round ends): pixel (3, 4), beyond the
         * end of the top side, has 6 of its 16 samples within 1.5 pixels of the corner (a
         * square end would cover 8) */
        CHECK_NEAR(1.0 - lin(px(img, 3, 4)[0]), 6.0 / 16.0, 0.01);
        CHECK_EQ_INT(px(img, 3, 3)[0], 255);
    }
    cbm_image_destroy(img);
    /* a line one pixel wide (widths below 1 are drawn 1 wide) */
    cbm_scene_clear(s);
    add_square(s, 0.25);
    o.supersample = 4;
    CHECK_OK(cbm_render(ctx, s, &o, &img));
    if (img) {
        double cov = 0;
        for (int y = 0; y < 20; y++)
            cov += 1.0 - lin(px(img, 50, y)[0]);
        CHECK_NEAR(cov, 1.0, 0.02);
        /* the band [4.5, 5.5]: half of row 4 and half of row 5, anti-aliased */
        CHECK_NEAR(1.0 - lin(px(img, 50, 4)[0]), 0.5, 0.01);
        CHECK_NEAR(1.0 - lin(px(img, 50, 5)[0]), 0.5, 0.01);
    }
    cbm_image_destroy(img);
    /* a line 1e30 pixels wide covers the whole picture (no overflow on the way) */
    cbm_part red = colored(1, 0, 0);
    CHECK_OK(cbm_scene_begin_part(s, &red, NULL));
    CHECK_OK(cbm_scene_add_line(s, v3(0.5, 0.5, 1), v3(0.6, 0.5, 1), 1e30));
    CHECK_OK(cbm_render(ctx, s, &o, &img));
    if (img) {
        CHECK_EQ_INT(px(img, 0, 0)[0], 255);
        CHECK_EQ_INT(px(img, 0, 0)[1], 0);
        CHECK_EQ_INT(px(img, 99, 99)[1], 0);
    }
    cbm_image_destroy(img);
    cbm_scene_clear(s);
    add_square(s, 0.25);
    /* transparent background: coverage goes to alpha */
    o.background[3] = 0.0f;
    CHECK_OK(cbm_render(ctx, s, &o, &img));
    if (img) {
        CHECK_EQ_INT(px(img, 50, 50)[3], 0);
        CHECK_NEAR(px(img, 50, 4)[3], 128, 1);
    }
    cbm_image_destroy(img);
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

/* Pixel (x, y) is mostly the colour (linear) c. */
static bool is_color(const cbm_image *img, int x, int y, const float c[3])
{
    for (int k = 0; k < 3; k++)
        if (fabs(lin(px(img, x, y)[k]) - c[k]) > 0.02)
            return false;
    return true;
}

TEST(crossing_lines_in_depth)
{
    cbm_context *ctx = test_ctx();
    const float red[3] = {1, 0, 0}, blue[3] = {0, 0, 1};
    /* the front view looks along -z: larger z is nearer */
    for (int order = 0; order < 2; order++) {
        cbm_scene *s = NULL;
        CHECK_OK(cbm_scene_create(ctx, &s));
        for (int k = 0; k < 2; k++) {
            bool horizontal = (k == 0) == (order == 0);
            if (horizontal) {
                /* red, along x, from z = -1 (left) to z = +1 (right) */
                cbm_part p = colored(1, 0, 0);
                CHECK_OK(cbm_scene_begin_part(s, &p, NULL));
                CHECK_OK(cbm_scene_add_line(s, v3(0, 0.5, -1), v3(1, 0.5, 1), 5));
            } else {
                /* blue, two vertical lines at z = 0: at x = 0.25 in front of the red line
                 * (z = -0.5 there), at x = 0.75 behind it (z = +0.5) */
                cbm_part p = colored(0, 0, 1);
                CHECK_OK(cbm_scene_begin_part(s, &p, NULL));
                CHECK_OK(cbm_scene_add_line(s, v3(0.25, 0, 0), v3(0.25, 1, 0), 5));
                CHECK_OK(cbm_scene_add_line(s, v3(0.75, 0, 0), v3(0.75, 1, 0), 5));
            }
        }
        cbm_write_options o = line_opts(100, 100);
        cbm_image *img = NULL;
        CHECK_OK(cbm_render(ctx, s, &o, &img));
        if (img) {
            /* x = 0.25 -> pixel 27.5, 0.75 -> 72.5, y = 0.5 -> 50 */
            CHECK_MSG(is_color(img, 27, 50, blue), "order %d: blue in front at x = 0.25", order);
            CHECK_MSG(is_color(img, 72, 50, red), "order %d: red in front at x = 0.75", order);
            CHECK(is_color(img, 50, 50, red));
            CHECK(is_color(img, 27, 20, blue));
            CHECK(is_color(img, 72, 80, blue));
        }
        cbm_image_destroy(img);
        cbm_scene_destroy(s);
    }
    test_ctx_end(ctx);
}

/* A grey square polygon at z = 0 over the middle, a red line in front of it (z = 0.5) and a
 * blue line behind it (z = -0.5), both running across the picture. */
static cbm_status mixed_scene(cbm_context *ctx, cbm_scene **out)
{
    cbm_scene *s = NULL;
    CBM_TRY(cbm_scene_create(ctx, &s));
    cbm_part g = colored(0.5f, 0.5f, 0.5f);
    cbm_part r = colored(1, 0, 0), b = colored(0, 0, 1);
    cbm_vec3 q[4] = {{0.25, 0.25, 0}, {0.75, 0.25, 0}, {0.75, 0.75, 0}, {0.25, 0.75, 0}};
    cbm_status st = cbm_scene_begin_part(s, &g, NULL);
    if (st == CBM_OK)
        st = cbm_scene_add_polygon(s, q, 4);
    if (st == CBM_OK)
        st = cbm_scene_begin_part(s, &r, NULL);
    if (st == CBM_OK)
        st = cbm_scene_add_line(s, v3(0, 0.4, 0.5), v3(1, 0.4, 0.5), 4);
    if (st == CBM_OK)
        st = cbm_scene_begin_part(s, &b, NULL);
    if (st == CBM_OK)
        st = cbm_scene_add_line(s, v3(0, 0.6, -0.5), v3(1, 0.6, -0.5), 4);
    if (st != CBM_OK) {
        cbm_scene_destroy(s);
        return st;
    }
    *out = s;
    return CBM_OK;
}

TEST(lines_and_triangles_in_one_picture)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(mixed_scene(ctx, &s));
    if (s) {
        cbm_write_options o = line_opts(100, 100);
        cbm_image *img = NULL;
        CHECK_OK(cbm_render(ctx, s, &o, &img));
        if (img) {
            const float red[3] = {1, 0, 0}, blue[3] = {0, 0, 1};
            /* the square spans pixels 5..95 (the lines fit the frame: x in [0, 1]); y = 0.4 is
             * row 5 + 90 * 0.6 = 59, y = 0.6 is row 41 */
            CHECK(is_color(img, 50, 59, red));   /* in front of the square */
            CHECK(is_color(img, 10, 59, red));   /* beside it */
            CHECK(is_color(img, 10, 41, blue));  /* beside it */
            CHECK(!is_color(img, 50, 41, blue)); /* hidden by the square */
            /* there the square's shaded grey: equal channels, neither white nor black */
            const uint8_t *g = px(img, 50, 41);
            CHECK(g[0] == g[1] && g[1] == g[2] && g[0] > 60 && g[0] < 250);
            CHECK_EQ_INT(px(img, 50, 5)[0], 255); /* background above the square */
        }
        cbm_image_destroy(img);
        /* SVG: the far line, the square, the near line, in this order */
        const char *path = io_path("mixed.svg");
        CHECK_OK(cbm_scene_write(ctx, s, path, &o));
        char *t = io_read_all(path, NULL);
        CHECK(t != NULL);
        if (t) {
            CHECK_EQ_INT((int)io_count(t, "<line "), 2);
            const char *blue_l = strstr(t, "stroke=\"#0000ff\""),
                       *red_l = strstr(t, "stroke=\"#ff0000\""), *tri = strstr(t, "<path ");
            CHECK(blue_l && red_l && tri && blue_l < tri && tri < red_l);
            CHECK(strstr(t, "stroke-width=\"4\"") != NULL);
            free(t);
        }
    }
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

TEST(svg_lines_well_formed)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(cbm_scene_create(ctx, &s));
    add_square(s, 2.5);
    cbm_write_options o = line_opts(100, 100);
    const char *path = io_path("square.svg");
    CHECK_OK(cbm_scene_write(ctx, s, path, &o));
    char *t = io_read_all(path, NULL);
    CHECK(t != NULL);
    if (t) {
        /* one group with the stroke, holding the four lines (the bottom side first: at equal
         * depth the scene order) */
        CHECK_EQ_INT((int)io_count(t, "<line "), 4);
        CHECK_EQ_INT((int)io_count(t, "<g stroke=\"#000000\" stroke-width=\"2.5\">\n"), 1);
        CHECK(strstr(t, "stroke-width=\"2.5\">\n<line x1=\"5.00\" y1=\"95.00\" x2=\"95.00\" "
                        "y2=\"95.00\"/>\n") != NULL);
        CHECK(strstr(t, "stroke-linecap=\"round\"") != NULL);
        free(t);
    }
    if (system("command -v xmllint > /dev/null 2>&1") == 0) {
        char cmd[4400];
        snprintf(cmd, sizeof cmd, "xmllint --noout '%s'", path);
        CHECK_MSG(system(cmd) == 0, "xmllint rejects %s", path);
    }
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

TEST(mesh_formats_refuse_lines_and_leave_no_file)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(cbm_scene_create(ctx, &s));
    add_square(s, 1);
    const char *names[] = {"l.obj", "l.ply", "l.glb", "l.csv"};
    for (int k = 0; k < 4; k++) {
        const char *path = io_path(names[k]);
        remove(path);
        CHECK_STATUS(cbm_scene_write(ctx, s, path, NULL), CBM_E_UNSUPPORTED);
        CHECK(strstr(cbm_context_last_error(ctx), "pixel lines") != NULL);
        struct stat sb;
        CHECK(stat(path, &sb) != 0);
    }
    /* nor does an animation take a frame of lines */
    cbm_animation *anim = NULL;
    CHECK_OK(cbm_animation_create(ctx, NULL, &anim));
    if (anim) {
        CHECK_STATUS(cbm_animation_add_frame(anim, s), CBM_E_UNSUPPORTED);
        CHECK(cbm_animation_frame_count(anim) == 0);
        cbm_animation_destroy(anim);
    }
    /* a picture that runs out of memory leaves no file either */
    cbm_limits lim = *cbm_context_limits(ctx);
    cbm_limits tight = lim;
    tight.max_bytes = cbm_context_bytes(ctx) + 100000; /* less than the sample grid */
    cbm_context_set_limits(ctx, &tight);
    const char *png = io_path("l.png");
    remove(png);
    CHECK_STATUS(cbm_scene_write(ctx, s, png, NULL), CBM_E_NOMEM);
    struct stat sb;
    CHECK(stat(png, &sb) != 0);
    cbm_context_set_limits(ctx, &lim);
    CHECK_OK(cbm_scene_write(ctx, s, png, NULL));
    CHECK(stat(png, &sb) == 0 && sb.st_size > 100);
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

/* The quadratic Koch island at 2 steps through the turtle, in line mode or not, with pixel
 * lines 2 pixels wide or (cylinder) tubes of diameter 2. */
static cbm_status koch_style(cbm_context *ctx, bool lines, bool cylinder, cbm_scene **out)
{
    const char *view = io_path("koch.v");
    FILE *f = fopen(view, "wb");
    if (!f)
        return CBM_E_IO;
    fputs("angle increment: 90\ninitial line width: 2 pixels\ninitial color: 1\n", f);
    if (cylinder)
        fputs("line style: cylinder\n", f);
    fclose(f);
    const char *sides[] = {view};
    cbm_model_def def = {cbm_lsys_def_default(), sides, 1};
    def.lsys.path = "koch.l";
    def.lsys.text = "Lsystem: 1\nderivation length: 2\nAxiom: F-F-F-F\n"
                    "F --> F+F-F-FF+F+F-F\nendlsystem\n";
    cbm_model *m = NULL;
    CBM_TRY(cbm_model_load(ctx, &def, &m));
    cbm_scene *s = NULL;
    cbm_status st = cbm_model_reset(m);
    for (int k = 0; k < 2 && st == CBM_OK; k++)
        st = cbm_model_step(m);
    if (st == CBM_OK)
        st = cbm_scene_create(ctx, &s);
    if (st == CBM_OK) {
        cbm_scene_set_line_mode(s, lines);
        st = cbm_model_interpret(m, s, false, NULL);
    }
    cbm_model_destroy(m);
    if (st != CBM_OK) {
        cbm_scene_destroy(s);
        return st;
    }
    *out = s;
    return CBM_OK;
}

static cbm_status koch(cbm_context *ctx, bool lines, cbm_scene **out)
{
    return koch_style(ctx, lines, false, out);
}

TEST(turtle_line_mode)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *tubes = NULL, *lines = NULL;
    CHECK_OK(koch(ctx, false, &tubes));
    CHECK_OK(koch(ctx, true, &lines));
    if (tubes && lines) {
        /* 4 x 8^2 segments: tubes of 8 sides (16 triangles) one part each, or lines sharing
         * one part (same colour, order and width all along) */
        size_t n = 4 * 8 * 8;
        CHECK_EQ_INT((int)cbm_scene_line_count(tubes), 0);
        CHECK_EQ_INT((int)cbm_scene_part_count(tubes), (int)n);
        CHECK_EQ_INT((int)cbm_scene_triangle_count(tubes), (int)(16 * n));
        CHECK(cbm_scene_line_mode(lines) && !cbm_scene_line_mode(tubes));
        CHECK_EQ_INT((int)cbm_scene_line_count(lines), (int)n);
        CHECK_EQ_INT((int)cbm_scene_triangle_count(lines), 0);
        CHECK_EQ_INT((int)cbm_scene_part_count(lines), 1);
        const cbm_scene_line *l = cbm_scene_lines(lines);
        CHECK_NEAR(l[0].width, 2.0, 0);
        /* the same polyline: each line ends where the next starts; same bounds as the tubes'
         * axes (the tubes are 1 unit wider on each side: radius 1) */
        for (size_t i = 0; i + 1 < n; i++)
            if (memcmp(l[i].p1, l[i + 1].p0, sizeof l[i].p1) != 0) {
                CHECK_MSG(false, "line %zu does not join the next", i);
                break;
            }
        cbm_vec3 lo, hi, tlo, thi;
        CHECK(cbm_scene_bounds(lines, &lo, &hi));
        CHECK(cbm_scene_bounds(tubes, &tlo, &thi));
        CHECK_NEAR(hi.x - lo.x + 2.0, thi.x - tlo.x, 1e-4);
        CHECK_NEAR(hi.y - lo.y + 2.0, thi.y - tlo.y, 1e-4);
        /* `line style: cylinder` keeps its tubes in line mode */
        cbm_scene *cyl = NULL;
        CHECK_OK(koch_style(ctx, true, true, &cyl));
        if (cyl) {
            CHECK_EQ_INT((int)cbm_scene_line_count(cyl), 0);
            CHECK_EQ_INT((int)cbm_scene_triangle_count(cyl), (int)(16 * n));
        }
        cbm_scene_destroy(cyl);
        /* cleared scenes keep their mode */
        cbm_scene_clear(lines);
        CHECK(cbm_scene_line_mode(lines));
        CHECK_EQ_INT((int)cbm_scene_line_count(lines), 0);
    }
    cbm_scene_destroy(tubes);
    cbm_scene_destroy(lines);
    test_ctx_end(ctx);
}

TEST(same_picture_with_any_thread_count)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *k = NULL, *m = NULL;
    CHECK_OK(koch(ctx, true, &k));
    CHECK_OK(mixed_scene(ctx, &m));
    cbm_scene *scenes[2] = {k, m};
    for (int i = 0; i < 2; i++) {
        if (!scenes[i])
            continue;
        cbm_image *one = NULL, *three = NULL;
        cbm_write_options o = cbm_write_options_default();
        o.width = 160;
        o.height = 120;
        o.threads = 1;
        CHECK_OK(cbm_render(ctx, scenes[i], &o, &one));
        o.threads = 3;
        CHECK_OK(cbm_render(ctx, scenes[i], &o, &three));
        if (one && three)
            CHECK_MSG(!memcmp(one->rgba, three->rgba, 160 * 120 * 4), "scene %d differs", i);
        cbm_image_destroy(one);
        cbm_image_destroy(three);
    }
    cbm_scene_destroy(k);
    cbm_scene_destroy(m);
    test_ctx_end(ctx);
}

static cbm_status oom_pictures(cbm_context *ctx, void *ud)
{
    (void)ud;
    cbm_scene *s = NULL;
    CBM_TRY(mixed_scene(ctx, &s));
    cbm_write_options o = line_opts(24, 24);
    o.legend = true;
    o.color_by = CBM_COLOR_ORDER;
    cbm_status st = cbm_scene_write(ctx, s, io_path("oom.png"), &o);
    if (st == CBM_OK)
        st = cbm_scene_write(ctx, s, io_path("oom.svg"), &o);
    cbm_scene_destroy(s);
    return st;
}

static cbm_status oom_turtle(cbm_context *ctx, void *ud)
{
    (void)ud;
    cbm_scene *s = NULL;
    CBM_TRY(koch(ctx, true, &s));
    cbm_scene_destroy(s);
    return CBM_OK;
}

TEST(allocation_failures)
{
    CHECK(test_oom_loop(oom_pictures, NULL) > 5);
    CHECK(test_oom_loop(oom_turtle, NULL) > 5);
}
