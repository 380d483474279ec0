/* The PNG renderer: pictures of small fixed scenes compared with stored references
 * (PNG files in tests/render, tolerance below), a picture that is not blank with the plant centred
 * and filling the frame, true elliptical sections seen end-on, independence from the thread count,
 * shadows, the legend, pictures of lines (alone and with triangles), and the PNG round trip. Set
 * CBM_UPDATE_REFERENCES=1 to rewrite the references after an intended change (then look at them).
 */
#include "io_util.h"

#include "core/vecmath.h"
#include "io/writers.h"

/* Tolerance against a reference: mean absolute difference <= 3 levels of 255 per channel, and
 * at most 2 % of the pixels differ by more than 40 levels in some channel (ray-casting noise
 * and SIMD-width differences between machines move a few edge and shadow pixels). */
#define MEAN_TOL         3.0
#define OUTLIER_LEVELS   40
#define OUTLIER_FRACTION 0.02

static cbm_write_options small_opts(int w, int h)
{
    cbm_write_options o = cbm_write_options_default();
    o.width = w;
    o.height = h;
    o.threads = 1;
    return o;
}

static void compare_reference(cbm_context *ctx, const cbm_image *img, const char *name)
{
    char ref[4096];
    snprintf(ref, sizeof ref, "%s/tests/render/%s", test_source_dir(), name);
    const char *upd = getenv("CBM_UPDATE_REFERENCES");
    if (upd && !strcmp(upd, "1")) {
        CHECK_OK(cbm_image_write_png(ctx, img, ref));
        return;
    }
    cbm_image *r = NULL;
    CHECK_OK(cbm_image_read_png(ctx, ref, &r));
    if (!r)
        return;
    CHECK_EQ_INT(r->width, img->width);
    CHECK_EQ_INT(r->height, img->height);
    if (r->width == img->width && r->height == img->height) {
        size_t n = (size_t)r->width * (size_t)r->height, outliers = 0;
        double sum = 0;
        for (size_t i = 0; i < n; i++) {
            int worst = 0;
            for (int k = 0; k < 4; k++) {
                int d = abs((int)r->rgba[4 * i + (size_t)k] - (int)img->rgba[4 * i + (size_t)k]);
                sum += d;
                worst = d > worst ? d : worst;
            }
            outliers += worst > OUTLIER_LEVELS;
        }
        double mean = sum / (4.0 * (double)n);
        CHECK_MSG(mean <= MEAN_TOL, "%s: mean difference %.2f > %.2f", name, mean, MEAN_TOL);
        CHECK_MSG((double)outliers <= OUTLIER_FRACTION * (double)n, "%s: %zu of %zu pixels differ",
                  name, outliers, n);
        if (mean > MEAN_TOL) {
            char got[4200];
            snprintf(got, sizeof got, "%s/got_%s", test_tmp_dir(), name);
            cbm_image_write_png(ctx, img, got);
        }
    }
    cbm_image_destroy(r);
}

TEST(reference_small_scene_iso)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(io_small_scene(ctx, &s));
    cbm_write_options o = small_opts(96, 96);
    cbm_image *img = NULL;
    CHECK_OK(cbm_render(ctx, s, &o, &img));
    if (img)
        compare_reference(ctx, img, "small_iso.png");
    cbm_image_destroy(img);
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

TEST(reference_tree_front_stress_and_top_order)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(cbm_scene_create(ctx, &s));
    CHECK_OK(cbm_scene_demo_tree(ctx, s, 300, 6, true, 5));
    cbm_write_options o = small_opts(192, 144);
    o.view = CBM_VIEW_FRONT;
    o.color_by = CBM_COLOR_STRESS;
    cbm_image *img = NULL;
    CHECK_OK(cbm_render(ctx, s, &o, &img));
    if (img)
        compare_reference(ctx, img, "tree_front_stress.png");
    cbm_image_destroy(img);
    o = small_opts(96, 96);
    o.view = CBM_VIEW_TOP;
    o.color_by = CBM_COLOR_ORDER;
    o.legend = false;
    o.ground = false;
    o.background[3] = 0.0f;
    img = NULL;
    CHECK_OK(cbm_render(ctx, s, &o, &img));
    if (img) {
        compare_reference(ctx, img, "tree_top_order.png");
        CHECK_EQ_INT(img->rgba[3], 0); /* transparent background */
    }
    cbm_image_destroy(img);
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

/* Lines (cpfg's pixel lines): a branching figure of lines of several widths and colours in 3-D
 * around a leaf (a polygon) and a fruit (a sphere), iso view with the ground, shadows and
 * occlusion of the triangles; and the lines alone, seen from the front with colours by order. */
static void add_line_figure(cbm_scene *s, bool triangles)
{
    cbm_part p = cbm_part_default();
    p.order = 0;
    p.color[0] = 0.25f, p.color[1] = 0.15f, p.color[2] = 0.05f;
    CHECK_OK(cbm_scene_begin_part(s, &p, NULL));
    CHECK_OK(cbm_scene_add_line(s, v3(0, 0, 0), v3(0, 0.5, 0), 5));
    for (int k = 0; k < 5; k++) {
        double a = 2.0 * CBM_PI * k / 5.0;
        cbm_vec3 tip = v3(0.4 * cos(a), 0.8 + 0.1 * k, 0.4 * sin(a));
        p.order = 1 + k % 3;
        p.color[0] = 0.1f * (float)k, p.color[1] = 0.5f, p.color[2] = 0.2f;
        CHECK_OK(cbm_scene_begin_part(s, &p, NULL));
        CHECK_OK(cbm_scene_add_line(s, v3(0, 0.5, 0), tip, 3 - 0.5 * k));
        CHECK_OK(cbm_scene_add_line(s, tip, v3_add(tip, v3(0, 0.15, 0)), 1));
    }
    if (!triangles)
        return;
    cbm_part leaf = cbm_part_default();
    leaf.organ = CBM_ORGAN_LEAF;
    leaf.color[0] = 0.2f, leaf.color[1] = 0.6f, leaf.color[2] = 0.15f;
    CHECK_OK(cbm_scene_begin_part(s, &leaf, NULL));
    cbm_vec3 q[4] = {{0, 0.6, 0}, {0.3, 0.7, 0.1}, {0.35, 0.9, 0.1}, {0.05, 0.8, 0}};
    CHECK_OK(cbm_scene_add_polygon(s, q, 4));
    cbm_part fruit = cbm_part_default();
    fruit.organ = CBM_ORGAN_FRUIT;
    fruit.color[0] = 0.8f, fruit.color[1] = 0.1f, fruit.color[2] = 0.1f;
    CHECK_OK(cbm_scene_begin_part(s, &fruit, NULL));
    CHECK_OK(cbm_scene_add_sphere(s, v3(-0.2, 0.45, 0.1), 0.08, 12));
}

TEST(reference_lines)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(cbm_scene_create(ctx, &s));
    add_line_figure(s, true);
    cbm_write_options o = small_opts(96, 96);
    cbm_image *img = NULL;
    CHECK_OK(cbm_render(ctx, s, &o, &img));
    if (img)
        compare_reference(ctx, img, "lines_iso.png");
    cbm_image_destroy(img);
    cbm_scene_clear(s);
    add_line_figure(s, false);
    o = small_opts(120, 96);
    o.view = CBM_VIEW_FRONT;
    o.color_by = CBM_COLOR_ORDER;
    img = NULL;
    CHECK_OK(cbm_render(ctx, s, &o, &img));
    if (img)
        compare_reference(ctx, img, "lines_front_order.png");
    cbm_image_destroy(img);
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

/* Bounding box of the pixels that differ from the white background. */
static size_t drawn_box(const cbm_image *img, int *x0, int *y0, int *x1, int *y1)
{
    size_t n = 0;
    *x0 = *y0 = 1 << 30;
    *x1 = *y1 = -1;
    for (int y = 0; y < img->height; y++)
        for (int x = 0; x < img->width; x++) {
            const uint8_t *p = img->rgba + 4 * ((size_t)y * (size_t)img->width + (size_t)x);
            if (p[0] > 250 && p[1] > 250 && p[2] > 250)
                continue;
            n++;
            *x0 = x < *x0 ? x : *x0;
            *y0 = y < *y0 ? y : *y0;
            *x1 = x > *x1 ? x : *x1;
            *y1 = y > *y1 ? y : *y1;
        }
    return n;
}

TEST(plant_not_blank_centred_and_filling)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(cbm_scene_create(ctx, &s));
    CHECK_OK(cbm_scene_demo_tree(ctx, s, 500, 6, false, 2));
    const cbm_camera_view views[4] = {CBM_VIEW_FRONT, CBM_VIEW_SIDE, CBM_VIEW_TOP, CBM_VIEW_ISO};
    for (int v = 0; v < 4; v++) {
        cbm_write_options o = small_opts(200, 160);
        o.view = views[v];
        o.ground = false;
        o.ao_samples = 0;
        cbm_image *img = NULL;
        CHECK_OK(cbm_render(ctx, s, &o, &img));
        if (!img)
            continue;
        int x0, y0, x1, y1;
        size_t n = drawn_box(img, &x0, &y0, &x1, &y1);
        CHECK_MSG(n > (size_t)(0.05 * 200 * 160), "view %d: only %zu pixels drawn", v, n);
        double cx = 0.5 * (x0 + x1 + 1), cy = 0.5 * (y0 + y1 + 1);
        CHECK_MSG(fabs(cx - 100) <= 3 && fabs(cy - 80) <= 3, "view %d: centre (%g, %g)", v, cx, cy);
        double fw = (x1 - x0 + 1) / 200.0, fh = (y1 - y0 + 1) / 160.0;
        double fill = fw > fh ? fw : fh;
        CHECK_MSG(fill >= 0.86 && fill <= 0.93, "view %d: fills %.3f of the frame", v, fill);
        cbm_image_destroy(img);
    }
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

/* A vertical tube with sections a = 2b, seen from the top: its outline is the ellipse of the
 * section, twice as wide as deep, and turning the section frame by 90 degrees turns it. */
TEST(elliptical_sections_seen_end_on)
{
    cbm_context *ctx = test_ctx();
    for (int turn = 0; turn < 2; turn++) {
        cbm_scene *s = NULL;
        CHECK_OK(cbm_scene_create(ctx, &s));
        cbm_part p = cbm_part_default();
        CHECK_OK(cbm_scene_begin_part(s, &p, NULL));
        cbm_frame f = {{0, 1, 0}, {-1, 0, 0}, {0, 0, 1}}; /* U along z, L along -x */
        if (turn)
            f = (cbm_frame){{0, 1, 0}, {0, 0, 1}, {1, 0, 0}};
        cbm_section s0 = {{0, 0, 0}, f, 0.1, 0.05}, s1 = {{0, 1, 0}, f, 0.1, 0.05};
        CHECK_OK(cbm_scene_add_tube(s, &s0, &s1, 64, true));
        cbm_write_options o = small_opts(200, 200);
        o.view = CBM_VIEW_TOP;
        o.ground = false;
        cbm_image *img = NULL;
        CHECK_OK(cbm_render(ctx, s, &o, &img));
        if (img) {
            int x0, y0, x1, y1;
            drawn_box(img, &x0, &y0, &x1, &y1);
            double w = x1 - x0 + 1, h = y1 - y0 + 1;
            /* top view: picture x = world x, picture up = world -z */
            double want = turn ? 2.0 : 0.5;
            CHECK_MSG(fabs(w / h - want) <= 0.05 * want, "turn %d: aspect %g, want %g", turn, w / h,
                      want);
            cbm_image_destroy(img);
        }
        cbm_scene_destroy(s);
    }
    test_ctx_end(ctx);
}

TEST(same_picture_with_any_thread_count)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(cbm_scene_create(ctx, &s));
    CHECK_OK(cbm_scene_demo_tree(ctx, s, 200, 6, true, 1));
    cbm_image *a = NULL, *b = NULL;
    cbm_write_options o = small_opts(80, 80);
    CHECK_OK(cbm_render(ctx, s, &o, &a));
    o.threads = 3;
    CHECK_OK(cbm_render(ctx, s, &o, &b));
    CHECK(a && b && memcmp(a->rgba, b->rgba, 80 * 80 * 4) == 0);
    cbm_image_destroy(a);
    cbm_image_destroy(b);
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

static double mean_luma(const cbm_image *img)
{
    double s = 0;
    size_t n = (size_t)img->width * (size_t)img->height;
    for (size_t i = 0; i < n; i++)
        s += 0.2126 * img->rgba[4 * i] + 0.7152 * img->rgba[4 * i + 1] +
             0.0722 * img->rgba[4 * i + 2];
    return s / (double)n;
}

TEST(shadows_and_occlusion_darken)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(cbm_scene_create(ctx, &s));
    CHECK_OK(cbm_scene_demo_tree(ctx, s, 400, 6, true, 1));
    cbm_write_options o = small_opts(96, 96);
    o.shadows = false;
    o.ao_samples = 0;
    double l[3];
    for (int k = 0; k < 3; k++) {
        if (k == 1)
            o.shadows = true;
        if (k == 2)
            o.ao_samples = 8;
        cbm_image *img = NULL;
        CHECK_OK(cbm_render(ctx, s, &o, &img));
        l[k] = img ? mean_luma(img) : 0;
        cbm_image_destroy(img);
    }
    CHECK_MSG(l[1] < l[0] - 0.5, "shadows: %g vs %g", l[1], l[0]);
    CHECK_MSG(l[2] < l[1] - 0.5, "occlusion: %g vs %g", l[2], l[1]);
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

/* Root-mean-square difference of two pictures' luma, levels of 255, over the pixels where the
 * reference b is not the white background. */
static double rms_luma_diff(const cbm_image *a, const cbm_image *b)
{
    double s = 0;
    size_t n = (size_t)a->width * (size_t)a->height, m = 0;
    static const double w[3] = {0.2126, 0.7152, 0.0722};
    for (size_t i = 0; i < n; i++) {
        double d = 0, lb = 0;
        for (int k = 0; k < 3; k++) {
            d += w[k] * ((double)a->rgba[4 * i + (size_t)k] - (double)b->rgba[4 * i + (size_t)k]);
            lb += w[k] * b->rgba[4 * i + (size_t)k];
        }
        if (lb < 250) {
            s += d * d;
            m++;
        }
    }
    return m ? sqrt(s / (double)m) : 0.0;
}

/* No visible grain: the default occlusion rays (16, a stratified set per pixel) give a picture
 * within 1.8 levels RMS of a 256-ray reference over the plant and ground (measured 1.27; 16
 * independent random rays gave 1.44, the former default of 4 random rays about 2.9, visible as
 * grain on the ground under the crown), and closer than 4 rays give. */
TEST(occlusion_is_smooth)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(cbm_scene_create(ctx, &s));
    CHECK_OK(cbm_scene_demo_tree(ctx, s, 400, 6, true, 1));
    cbm_write_options o = small_opts(160, 160);
    static const int rays[3] = {256, 16, 4};
    cbm_image *img[3] = {NULL, NULL, NULL};
    CHECK_EQ_INT(cbm_write_options_default().ao_samples, 16);
    for (int k = 0; k < 3; k++) {
        o.ao_samples = rays[k];
        CHECK_OK(cbm_render(ctx, s, &o, &img[k]));
    }
    if (img[0] && img[1] && img[2]) {
        double d16 = rms_luma_diff(img[1], img[0]), d4 = rms_luma_diff(img[2], img[0]);
        CHECK_MSG(d16 < 1.8, "16 rays: %.2f levels RMS from 256 rays", d16);
        CHECK_MSG(d16 < d4, "16 rays %.2f, 4 rays %.2f levels RMS from 256 rays", d16, d4);
    }
    for (int k = 0; k < 3; k++)
        cbm_image_destroy(img[k]);
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

TEST(legend_shows_the_colour_map)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(io_small_scene(ctx, &s));
    cbm_write_options o = small_opts(240, 200);
    o.color_by = CBM_COLOR_STRESS;
    cbm_image *img = NULL;
    CHECK_OK(cbm_render(ctx, s, &o, &img));
    if (img) {
        /* bar: x from W - legend + legend/6, rows H/5 .. 4H/5, top = ratio 1 */
        int lw = 240 / 6 > 70 ? 240 / 6 : 70, x = 240 - lw + lw / 6 + 2;
        float top[3], bot[3];
        cbm__colormap(CBM_COLOR_STRESS, 1.0, top);
        cbm__colormap(CBM_COLOR_STRESS, 0.0, bot);
        const uint8_t *pt = img->rgba + 4 * ((size_t)(200 / 5 + 1) * 240 + (size_t)x);
        const uint8_t *pb = img->rgba + 4 * ((size_t)(200 - 200 / 5 - 2) * 240 + (size_t)x);
        for (int k = 0; k < 3; k++) {
            CHECK(abs((int)pt[k] - (int)cbm__srgb8(top[k])) <= 4);
            CHECK(abs((int)pb[k] - (int)cbm__srgb8(bot[k])) <= 4);
        }
        cbm_image_destroy(img);
    }
    /* the tube's own colour (stress ratio 0.5) appears in the picture */
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

TEST(png_round_trip)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(io_small_scene(ctx, &s));
    cbm_write_options o = small_opts(50, 40);
    cbm_image *img = NULL, *back = NULL;
    CHECK_OK(cbm_render(ctx, s, &o, &img));
    CHECK_OK(cbm_scene_write(ctx, s, io_path("small.png"), &o));
    CHECK_OK(cbm_image_read_png(ctx, io_path("small.png"), &back));
    CHECK(img && back && back->width == 50 && back->height == 40 &&
          memcmp(img->rgba, back->rgba, 50 * 40 * 4) == 0);
    cbm_image_destroy(img);
    cbm_image_destroy(back);
    CHECK_STATUS(cbm_image_read_png(ctx, io_path("missing.png"), &back), CBM_E_IO);
    o.width = 0;
    CHECK_STATUS(cbm_render(ctx, s, &o, &img), CBM_E_INVALID);
    /* an empty scene is the background alone */
    cbm_scene *e = NULL;
    CHECK_OK(cbm_scene_create(ctx, &e));
    o = small_opts(20, 10);
    o.background[0] = 0.0f;
    CHECK_OK(cbm_render(ctx, e, &o, &img));
    for (int i = 0; img && i < 20 * 10; i++)
        CHECK(img->rgba[4 * i] == 0 && img->rgba[4 * i + 1] == 255 && img->rgba[4 * i + 3] == 255);
    cbm_image_destroy(img);
    cbm_scene_destroy(e);
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}
