/* Private to src/plot: the figure as stored, and the canvas the layout draws through. The layout
 * (draw.c) computes every position in pixels once and issues drawing operations to a canvas;
 * canvas_cairo.c turns them into pixels (PNG), canvas_svg.c into SVG elements. Text is measured
 * by cairo with the same font for both, so the two files have the same layout. */
#ifndef CBM_PLOT_INTERNAL_H
#define CBM_PLOT_INTERNAL_H

#include "cambium/plot.h"

#include "../core/core.h"
#include "font.h"

#include <cairo.h>
#include <stdio.h>

typedef struct plot_series {
    double *x, *y; /* n each */
    size_t n;
    char *label; /* NULL: not in the legend */
    cbm_plot_line line;
    cbm_plot_marker marker;
    float rgb[3]; /* sRGB, resolved from the palette when asked */
    double line_width, marker_size;
} plot_series;

typedef struct plot_panel {
    cbm_plot_axes_def axes; /* labels point into the copies below */
    char *xlabel, *ylabel, *title;
    CBM_ARRAY(plot_series) series;
    int palette_next;
} plot_panel;

struct cbm_plot {
    cbm_context *ctx;
    int width, height, npanels;
    double font_size;
    bool transparent;
    char *title;
    plot_panel panel[CBM_PLOT_MAX_PANELS];
};

typedef struct cbm__rgb {
    double r, g, b; /* sRGB 0..1 */
} cbm__rgb;

/// A stroke: colour, width (px), dash pattern.
typedef struct cbm__stroke {
    cbm__rgb color;
    double width;
    cbm_plot_line line;
} cbm__stroke;

/// Horizontal anchor of text at its point, and the baseline is at the point's y.
typedef enum cbm__anchor { CBM__ANCHOR_START, CBM__ANCHOR_MIDDLE, CBM__ANCHOR_END } cbm__anchor;

typedef struct cbm__canvas cbm__canvas;
/// Drawing operations, in pixels with y down. Strings are valid UTF-8 without control characters
/// (the layout cleans them). A group names a series or a part of the figure (SVG <g class>).
typedef struct cbm__canvas_ops {
    void (*group_begin)(cbm__canvas *c, const char *cls, const char *label);
    void (*group_end)(cbm__canvas *c);
    void (*clip_begin)(cbm__canvas *c, double x, double y, double w, double h);
    void (*clip_end)(cbm__canvas *c);
    /// Filled and/or stroked rectangle (fill or stroke NULL: none).
    void (*rect)(cbm__canvas *c, double x, double y, double w, double h, const cbm__rgb *fill,
                 double fill_alpha, const cbm__stroke *stroke);
    /// Separate straight segments x0 y0 x1 y1 (axes, ticks, grid), square ends.
    void (*segments)(cbm__canvas *c, const double *xyxy, size_t n, const cbm__stroke *s);
    /// Open polylines: runs[k] points each, xy packed one run after another.
    void (*polylines)(cbm__canvas *c, const double *xy, const size_t *runs, size_t nruns,
                      const cbm__stroke *s);
    /// One marker at each point, radius r px.
    void (*markers)(cbm__canvas *c, const double *xy, size_t n, cbm_plot_marker m, double r,
                    const cbm__rgb *color, double line_width);
    /// Text with its baseline at y, anchored at x; rotated by -90 degrees (reading upwards)
    /// about (x, y) when `vertical`.
    void (*text)(cbm__canvas *c, double x, double y, const char *text, double size,
                 cbm__anchor anchor, bool vertical, const cbm__rgb *color);
} cbm__canvas_ops;

struct cbm__canvas {
    const cbm__canvas_ops *ops;
    cairo_t *measure; /* measures text (the drawing context itself for cairo) */
};

/// The dash pattern of a line style at a width (px): count of entries, 0 for solid.
int cbm__plot_dashes(cbm_plot_line line, double width, double dash[2]);

/// Lays the figure out and draws it on the canvas (CBM_E_NOMEM: out of memory for a series).
cbm_status cbm__plot_draw(const cbm_plot *p, cbm__canvas *c);

/// Draws the figure with cairo on a new picture.
cbm_status cbm__plot_render_cairo(const cbm_plot *p, cbm_image **out);
/// Writes the figure as SVG to a stream.
cbm_status cbm__plot_write_svg(const cbm_plot *p, FILE *f);

#endif
