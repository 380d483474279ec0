/* The figure drawn with cairo into pixels: an ARGB32 image surface (premultiplied, native
 * endian), then converted to the library's 8-bit sRGB RGBA picture, which the PNG encoder of
 * src/io/png writes (so plots and renderings share one encoder and its atomic write). Colours
 * are sRGB values drawn as they are, as every plotting program does. */
#include "plot_internal.h"

#include "../core/vecmath.h"

#include <math.h>

static cairo_t *cr_of(cbm__canvas *c)
{
    return c->measure;
}

static void set_rgb(cairo_t *cr, const cbm__rgb *c, double alpha)
{
    cbm__cairo.cairo_set_source_rgba(cr, c->r, c->g, c->b, alpha);
}

static void set_stroke(cairo_t *cr, const cbm__stroke *s)
{
    set_rgb(cr, &s->color, 1.0);
    cbm__cairo.cairo_set_line_width(cr, s->width);
    double dash[2];
    int n = cbm__plot_dashes(s->line, s->width, dash);
    cbm__cairo.cairo_set_dash(cr, dash, n, 0.0);
    cbm__cairo.cairo_set_line_cap(cr, s->line == CBM_PLOT_DOTTED ? CAIRO_LINE_CAP_ROUND
                                                                 : CAIRO_LINE_CAP_BUTT);
    cbm__cairo.cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
}

static void group_begin(cbm__canvas *c, const char *cls, const char *label)
{
    (void)c, (void)cls, (void)label;
}

static void group_end(cbm__canvas *c)
{
    (void)c;
}

static void clip_begin(cbm__canvas *c, double x, double y, double w, double h)
{
    cairo_t *cr = cr_of(c);
    cbm__cairo.cairo_save(cr);
    cbm__cairo.cairo_rectangle(cr, x, y, w, h);
    cbm__cairo.cairo_clip(cr);
}

static void clip_end(cbm__canvas *c)
{
    cbm__cairo.cairo_restore(cr_of(c));
}

static void rect(cbm__canvas *c, double x, double y, double w, double h, const cbm__rgb *fill,
                 double fill_alpha, const cbm__stroke *stroke)
{
    cairo_t *cr = cr_of(c);
    cbm__cairo.cairo_new_path(cr);
    cbm__cairo.cairo_rectangle(cr, x, y, w, h);
    if (fill) {
        set_rgb(cr, fill, fill_alpha);
        cbm__cairo.cairo_fill_preserve(cr);
    }
    if (stroke) {
        set_stroke(cr, stroke);
        cbm__cairo.cairo_set_line_join(cr, CAIRO_LINE_JOIN_MITER);
        cbm__cairo.cairo_stroke(cr);
    }
    cbm__cairo.cairo_new_path(cr);
}

static void segments(cbm__canvas *c, const double *p, size_t n, const cbm__stroke *s)
{
    cairo_t *cr = cr_of(c);
    cbm__cairo.cairo_new_path(cr);
    for (size_t i = 0; i < n; i++) {
        cbm__cairo.cairo_move_to(cr, p[4 * i], p[4 * i + 1]);
        cbm__cairo.cairo_line_to(cr, p[4 * i + 2], p[4 * i + 3]);
    }
    set_stroke(cr, s);
    cbm__cairo.cairo_stroke(cr);
}

static void polylines(cbm__canvas *c, const double *xy, const size_t *runs, size_t nruns,
                      const cbm__stroke *s)
{
    cairo_t *cr = cr_of(c);
    cbm__cairo.cairo_new_path(cr);
    size_t at = 0;
    for (size_t r = 0; r < nruns; r++) {
        for (size_t i = 0; i < runs[r]; i++, at++) {
            if (i == 0)
                cbm__cairo.cairo_move_to(cr, xy[2 * at], xy[2 * at + 1]);
            else
                cbm__cairo.cairo_line_to(cr, xy[2 * at], xy[2 * at + 1]);
        }
    }
    set_stroke(cr, s);
    cbm__cairo.cairo_stroke(cr);
}

/* The outline of a marker of radius r at (x, y), as a new sub-path. */
static void marker_path(cairo_t *cr, cbm_plot_marker m, double x, double y, double r)
{
    switch (m) {
    case CBM_PLOT_MARKER_CIRCLE:
        cbm__cairo.cairo_new_sub_path(cr);
        cbm__cairo.cairo_arc(cr, x, y, r, 0.0, 2.0 * CBM_PI);
        cbm__cairo.cairo_close_path(cr);
        break;
    case CBM_PLOT_MARKER_SQUARE:
        cbm__cairo.cairo_rectangle(cr, x - 0.85 * r, y - 0.85 * r, 1.7 * r, 1.7 * r);
        break;
    case CBM_PLOT_MARKER_TRIANGLE:
        cbm__cairo.cairo_move_to(cr, x, y - 1.15 * r);
        cbm__cairo.cairo_line_to(cr, x + r, y + 0.6 * r);
        cbm__cairo.cairo_line_to(cr, x - r, y + 0.6 * r);
        cbm__cairo.cairo_close_path(cr);
        break;
    case CBM_PLOT_MARKER_DIAMOND:
        cbm__cairo.cairo_move_to(cr, x, y - 1.2 * r);
        cbm__cairo.cairo_line_to(cr, x + r, y);
        cbm__cairo.cairo_line_to(cr, x, y + 1.2 * r);
        cbm__cairo.cairo_line_to(cr, x - r, y);
        cbm__cairo.cairo_close_path(cr);
        break;
    case CBM_PLOT_MARKER_CROSS:
        cbm__cairo.cairo_move_to(cr, x - r, y - r);
        cbm__cairo.cairo_line_to(cr, x + r, y + r);
        cbm__cairo.cairo_move_to(cr, x - r, y + r);
        cbm__cairo.cairo_line_to(cr, x + r, y - r);
        break;
    case CBM_PLOT_MARKER_PLUS:
        cbm__cairo.cairo_move_to(cr, x - r, y);
        cbm__cairo.cairo_line_to(cr, x + r, y);
        cbm__cairo.cairo_move_to(cr, x, y - r);
        cbm__cairo.cairo_line_to(cr, x, y + r);
        break;
    default:
        break;
    }
}

static void markers(cbm__canvas *c, const double *xy, size_t n, cbm_plot_marker m, double r,
                    const cbm__rgb *color, double line_width)
{
    cairo_t *cr = cr_of(c);
    cbm__cairo.cairo_new_path(cr);
    for (size_t i = 0; i < n; i++)
        marker_path(cr, m, xy[2 * i], xy[2 * i + 1], r);
    set_rgb(cr, color, 1.0);
    cbm__cairo.cairo_set_dash(cr, NULL, 0, 0.0);
    if (m == CBM_PLOT_MARKER_CROSS || m == CBM_PLOT_MARKER_PLUS) {
        cbm__cairo.cairo_set_line_width(cr, line_width);
        cbm__cairo.cairo_set_line_cap(cr, CAIRO_LINE_CAP_BUTT);
        cbm__cairo.cairo_stroke(cr);
    } else {
        cbm__cairo.cairo_fill(cr);
    }
}

static void text(cbm__canvas *c, double x, double y, const char *t, double size, cbm__anchor anchor,
                 bool vertical, const cbm__rgb *color)
{
    cairo_t *cr = cr_of(c);
    double w = cbm__font_width(cr, t, size);
    double dx = anchor == CBM__ANCHOR_MIDDLE ? -0.5 * w : anchor == CBM__ANCHOR_END ? -w : 0.0;
    cbm__cairo.cairo_save(cr);
    cbm__cairo.cairo_translate(cr, x, y);
    if (vertical)
        cbm__cairo.cairo_rotate(cr, -0.5 * CBM_PI);
    cbm__cairo.cairo_move_to(cr, dx, 0.0);
    set_rgb(cr, color, 1.0);
    cbm__cairo.cairo_show_text(cr, t);
    cbm__cairo.cairo_restore(cr);
    cbm__cairo.cairo_new_path(cr);
}

static const cbm__canvas_ops cairo_ops = {group_begin, group_end, clip_begin, clip_end, rect,
                                          segments,    polylines, markers,    text};

cbm_status cbm__plot_render_cairo(const cbm_plot *p, cbm_image **out)
{
    *out = NULL;
    CBM_TRY(cbm__cairo_load(p->ctx, "plot"));
    cairo_surface_t *surf =
        cbm__cairo.cairo_image_surface_create(CAIRO_FORMAT_ARGB32, p->width, p->height);
    cairo_t *cr = cbm__cairo.cairo_create(surf);
    cbm__cairo.cairo_surface_destroy(surf); /* the context keeps it */
    if (cbm__cairo.cairo_status(cr) != CAIRO_STATUS_SUCCESS) {
        cbm__cairo.cairo_destroy(cr);
        return cbm__fail(p->ctx, CBM_E_NOMEM, "plot: cannot create a %d x %d picture", p->width,
                         p->height);
    }
    cbm__cairo.cairo_set_antialias(cr, CAIRO_ANTIALIAS_GRAY);
    if (!p->transparent) {
        cbm__cairo.cairo_set_source_rgb(cr, 1.0, 1.0, 1.0);
        cbm__cairo.cairo_paint(cr);
    }
    cbm__canvas c = {&cairo_ops, cr};
    cbm_status st = cbm__plot_draw(p, &c);
    cbm__cairo.cairo_surface_flush(surf);
    if (st == CBM_OK && cbm__cairo.cairo_status(cr) != CAIRO_STATUS_SUCCESS)
        st = cbm__fail(p->ctx, CBM_E_INTERNAL, "plot: cairo: %s",
                       cbm__cairo.cairo_status_to_string(cbm__cairo.cairo_status(cr)));
    cbm_image *img = NULL;
    if (st == CBM_OK)
        st = cbm_image_create(p->ctx, p->width, p->height, &img);
    if (st == CBM_OK) {
        const unsigned char *data = cbm__cairo.cairo_image_surface_get_data(surf);
        int stride = cbm__cairo.cairo_image_surface_get_stride(surf);
        for (int y = 0; y < p->height; y++) {
            const uint32_t *row =
                (const uint32_t *)(const void *)(data + (size_t)y * (size_t)stride);
            for (int x = 0; x < p->width; x++) {
                uint32_t v = row[x];
                unsigned a = v >> 24, rgb[3] = {(v >> 16) & 255u, (v >> 8) & 255u, v & 255u};
                uint8_t *q = img->rgba + 4 * ((size_t)y * (size_t)p->width + (size_t)x);
                for (int k = 0; k < 3; k++)
                    q[k] = (uint8_t)(a ? (rgb[k] * 255u + a / 2) / a : 0);
                q[3] = (uint8_t)a;
            }
        }
    }
    cbm__cairo.cairo_destroy(cr);
    *out = img;
    return st;
}
