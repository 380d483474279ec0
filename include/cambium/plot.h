/* cambium: 2-D plots (equilibrium curves, sensitivity sweeps, quantities over time, spectra)
 * written as PNG or SVG.
 *
 * A plot is one figure of one or more panels stacked top to bottom, each with its own axes
 * (linear or logarithmic, ranges from the data rounded out to nice ticks unless set), labels and
 * any number of series: lines (solid, dashed, dotted), markers, or both, each with a colour and
 * a legend label. Text is drawn with DejaVu Sans through cairo (Debian fonts-dejavu-core); in SVG
 * it stays text. The same plot gives the same bytes on one machine. docs/formats.md describes
 * the files.
 *
 *     cbm_plot *p;
 *     cbm_plot_def d = cbm_plot_def_default();
 *     d.title = "Tip deflection";
 *     cbm_plot_create(ctx, &d, &p);
 *     cbm_plot_axes_def a = cbm_plot_axes_def_default();
 *     a.xlabel = "load (N)", a.ylabel = "deflection (m)";
 *     cbm_plot_set_axes(p, 0, &a);
 *     cbm_plot_series_def s = cbm_plot_series_def_default();
 *     s.x = load, s.y = tip, s.n = n, s.label = "stable";
 *     cbm_plot_add_series(p, 0, &s);
 *     cbm_plot_write(p, "tip.svg");
 *     cbm_plot_destroy(p);
 */
#ifndef CAMBIUM_PLOT_H
#define CAMBIUM_PLOT_H

#include "cambium/base.h"
#include "cambium/write.h"

#ifdef __cplusplus
extern "C" {
#endif

/// The most panels a figure holds (stacked top to bottom).
#define CBM_PLOT_MAX_PANELS 4

/// How a series' points are joined.
typedef enum cbm_plot_line {
    CBM_PLOT_SOLID,
    CBM_PLOT_DASHED,
    CBM_PLOT_DOTTED,
    CBM_PLOT_NO_LINE ///< markers only (a scatter plot)
} cbm_plot_line;

/// The mark drawn at each point.
typedef enum cbm_plot_marker {
    CBM_PLOT_MARKER_NONE,
    CBM_PLOT_MARKER_CIRCLE,
    CBM_PLOT_MARKER_SQUARE,
    CBM_PLOT_MARKER_TRIANGLE,
    CBM_PLOT_MARKER_DIAMOND,
    CBM_PLOT_MARKER_CROSS,
    CBM_PLOT_MARKER_PLUS
} cbm_plot_marker;

/// Where a panel's legend goes: AUTO takes the inside corner that covers the fewest points.
typedef enum cbm_plot_legend {
    CBM_PLOT_LEGEND_AUTO,
    CBM_PLOT_LEGEND_NONE,
    CBM_PLOT_LEGEND_TOP_RIGHT,
    CBM_PLOT_LEGEND_TOP_LEFT,
    CBM_PLOT_LEGEND_BOTTOM_RIGHT,
    CBM_PLOT_LEGEND_BOTTOM_LEFT
} cbm_plot_legend;

/// The figure.
typedef struct cbm_plot_def {
    int width, height; ///< pixels (SVG: user units), 16..16384; default 800 x 600
    const char *title; ///< above the panels; NULL or "" for none (copied)
    double font_size;  ///< pixels; 0: from the figure's size
    int panels;        ///< 1..CBM_PLOT_MAX_PANELS, stacked top to bottom; default 1
    bool transparent;  ///< PNG: transparent background instead of white (SVG: no backdrop)
} cbm_plot_def;

/// One panel's axes.
typedef struct cbm_plot_axes_def {
    const char *xlabel, *ylabel; ///< axis titles; NULL for none (copied)
    const char *title;           ///< the panel's own title; NULL for none (copied)
    bool xlog, ylog;             ///< logarithmic axis (points <= 0 are left out and break lines)
    double xmin, xmax;           ///< range; NaN: from the data, rounded out to ticks
    double ymin, ymax;           ///< range; NaN: from the data, rounded out to ticks
    bool grid;                   ///< light lines at the major ticks (default true)
    cbm_plot_legend legend;      ///< where the labelled series are named (default AUTO)
} cbm_plot_axes_def;

/// One series. Non-finite x or y leaves a point out and breaks the line there.
typedef struct cbm_plot_series_def {
    const double *x, *y; ///< n points each (copied); x NULL: 0, 1, 2, ...
    size_t n;
    const char *label;      ///< legend text; NULL or "": not in the legend (copied)
    cbm_plot_line line;     ///< default solid
    cbm_plot_marker marker; ///< default none
    float color[3];         ///< sRGB 0..1; a negative first component: the panel's next
                            ///< palette colour (Okabe-Ito, for colour-blind readers; default)
    double line_width;      ///< pixels; 0: from the font size
    double marker_size;     ///< marker radius, pixels; 0: from the font size
} cbm_plot_series_def;

CBM_API cbm_plot_def cbm_plot_def_default(void);
CBM_API cbm_plot_axes_def cbm_plot_axes_def_default(void);
CBM_API cbm_plot_series_def cbm_plot_series_def_default(void);

typedef struct cbm_plot cbm_plot;

/// A new empty figure (its panels with default axes). CBM_E_INVALID names a bad field.
CBM_API cbm_status cbm_plot_create(cbm_context *ctx, const cbm_plot_def *def, cbm_plot **out);
CBM_API void cbm_plot_destroy(cbm_plot *plot);
/// Sets the axes of panel 0..panels-1.
CBM_API cbm_status cbm_plot_set_axes(cbm_plot *plot, int panel, const cbm_plot_axes_def *def);
/// Adds a series to a panel (its points and label are copied).
CBM_API cbm_status cbm_plot_add_series(cbm_plot *plot, int panel, const cbm_plot_series_def *def);
/// Draws the figure into a new picture (8-bit sRGB RGBA), released with cbm_image_destroy.
CBM_API cbm_status cbm_plot_render(cbm_plot *plot, cbm_image **out);
/// Writes the figure as "png" or "svg" (case ignored), atomically (no partial file).
CBM_API cbm_status cbm_plot_write_as(cbm_plot *plot, const char *path, const char *format);
/// Writes the figure in the format of the path's extension (.png or .svg).
CBM_API cbm_status cbm_plot_write(cbm_plot *plot, const char *path);

/// Nice tick values for an axis from lo to hi (lo < hi): at most `max` of them in ticks[] (8
/// is enough for any target up to 7 on a linear axis), steps of 1, 2, 2.5 or 5 times a power
/// of ten on a linear axis, about `target` of them; on a log axis powers of ten (every k-th
/// decade when there are many; with 1, 2 and 5 of each decade when the range spans less than
/// two). Ticks lie within [lo, hi] (up to a relative 1e-9). Returns the count; 0 when lo and hi
/// do not make a range (or, on a log axis, lo <= 0).
CBM_API size_t cbm_plot_ticks(double lo, double hi, int target, bool log, double *ticks,
                              size_t max);
/// The range [lo, hi] rounded out to the nice ticks of `target` (loose labelling), so the axis
/// starts and ends on a tick. A point range (lo == hi) is widened first.
CBM_API void cbm_plot_nice_range(double *lo, double *hi, int target, bool log);
/// Tick labels: each value of ticks[0..n) as short text with the decimals the step needs (and
/// no "-0"), or in exponent form for very large or small magnitudes. label_size bytes each.
CBM_API void cbm_plot_tick_labels(const double *ticks, size_t n, bool log, char *labels,
                                  size_t label_size);

#ifdef __cplusplus
}
#endif

#endif
