/* The layout of a figure and its drawing through a canvas (PNG or SVG alike).
 *
 * Sizes derive from the font size fs. The figure has a title strip, then the panels stacked top
 * to bottom; every panel's plot area has the same left edge (the widest y tick labels of any
 * panel decide it) so stacked panels line up. Tick targets follow the plot area's size (about
 * one x label per 6 fs, one y label per 3.5 fs). Ranges come from the data (finite points; on a
 * log axis the positive ones) rounded out to the ticks, unless set. Series are clipped to the
 * plot area (Liang-Barsky, against the area grown by a margin so wide lines end cleanly, then a
 * clip to the area), which also keeps far-away points from overflowing the rasteriser's
 * fixed-point coordinates; a non-finite point breaks the line. Markers are drawn whole for the
 * points inside the area, so points on its edge (common with ranges rounded to ticks) show. The
 * legend goes in the corner of the plot area that covers the fewest points unless placed. */
#include "plot_internal.h"

#include <math.h>
#include <string.h>

#define MAX_TICKS 64
#define LABEL_LEN 40

static const cbm__rgb ink = {0.10, 0.10, 0.10}, axis_grey = {0.20, 0.20, 0.20},
                      grid_grey = {0.88, 0.88, 0.88}, white = {1.0, 1.0, 1.0},
                      frame_grey = {0.72, 0.72, 0.72};

typedef struct axis {
    double lo, hi; /* data range */
    bool log;
    double p0, p1; /* pixels of lo and hi */
    double ticks[MAX_TICKS];
    char labels[MAX_TICKS][LABEL_LEN];
    size_t nticks;
} axis;

typedef struct panel_box {
    double x0, y0, x1, y1; /* plot area, pixels (y down) */
    axis x, y;
} panel_box;

static double to_px(const axis *a, double v)
{
    double t = a->log ? (log10(v) - log10(a->lo)) / (log10(a->hi) - log10(a->lo))
                      : (v - a->lo) / (a->hi - a->lo);
    return a->p0 + t * (a->p1 - a->p0);
}

static bool usable(double v, bool log)
{
    return isfinite(v) && (!log || v > 0);
}

int cbm__plot_dashes(cbm_plot_line line, double width, double dash[2])
{
    double w = width > 1.0 ? width : 1.0;
    if (line == CBM_PLOT_DASHED) {
        dash[0] = 4.0 * w + 2.0, dash[1] = 2.5 * w + 1.5;
        return 2;
    }
    if (line == CBM_PLOT_DOTTED) {
        dash[0] = 0.0, dash[1] = 2.0 * w + 1.0; /* round caps make the dots */
        return 2;
    }
    return 0;
}

/* The data range of one axis of a panel, rounded out to nice values where not set. */
static void axis_range(const plot_panel *pl, bool is_x, int target, axis *a)
{
    bool log = is_x ? pl->axes.xlog : pl->axes.ylog;
    double set_lo = is_x ? pl->axes.xmin : pl->axes.ymin,
           set_hi = is_x ? pl->axes.xmax : pl->axes.ymax;
    double lo = INFINITY, hi = -INFINITY;
    for (size_t k = 0; k < pl->series.len; k++) {
        const plot_series *s = &pl->series.data[k];
        for (size_t i = 0; i < s->n; i++) {
            double u = is_x ? s->x[i] : s->y[i], w = is_x ? s->y[i] : s->x[i];
            bool wlog = is_x ? pl->axes.ylog : pl->axes.xlog;
            if (!usable(u, log) || !usable(w, wlog))
                continue;
            lo = fmin(lo, u);
            hi = fmax(hi, u);
        }
    }
    if (isfinite(set_lo))
        lo = isfinite(hi) ? fmin(lo, set_lo) : set_lo;
    if (isfinite(set_hi))
        hi = isfinite(lo) ? fmax(hi, set_hi) : set_hi;
    if (!(lo <= hi)) {
        lo = log ? 1.0 : 0.0;
        hi = log ? 10.0 : 1.0;
    }
    double nl = lo, nh = hi;
    cbm_plot_nice_range(&nl, &nh, target, log);
    a->lo = isfinite(set_lo) ? set_lo : nl;
    a->hi = isfinite(set_hi) ? set_hi : nh;
    if (!(a->lo < a->hi)) { /* one end set past the data: widen from it */
        double w = log ? 10.0 : fmax(1.0, fabs(a->lo));
        if (isfinite(set_lo))
            a->hi = log ? a->lo * w : a->lo + w;
        else
            a->lo = log ? a->hi / w : a->hi - w;
    }
    a->log = log;
    a->nticks = cbm_plot_ticks(a->lo, a->hi, target, log, a->ticks, MAX_TICKS);
    cbm_plot_tick_labels(a->ticks, a->nticks, log, &a->labels[0][0], LABEL_LEN);
}

/* A 1-pixel line's centre for a position: on the pixel grid, inside the frame [lo, hi]. */
static double snap(double v, double lo, double hi)
{
    return fmin(fmax(floor(v) + 0.5, lo + 0.5), hi - 0.5);
}

static int clampi(double v, int lo, int hi)
{
    int i = (int)lround(v);
    return i < lo ? lo : i > hi ? hi : i;
}

/* Liang-Barsky: clips segment a-b to the box; false when nothing is left. */
static bool clip_segment(double box[4], double *ax, double *ay, double *bx, double *by)
{
    double t0 = 0.0, t1 = 1.0, dx = *bx - *ax, dy = *by - *ay;
    const double p[4] = {-dx, dx, -dy, dy};
    const double q[4] = {*ax - box[0], box[2] - *ax, *ay - box[1], box[3] - *ay};
    for (int k = 0; k < 4; k++) {
        if (p[k] == 0.0) {
            if (q[k] < 0.0)
                return false;
            continue;
        }
        double r = q[k] / p[k];
        if (p[k] < 0.0) {
            if (r > t1)
                return false;
            if (r > t0)
                t0 = r;
        } else {
            if (r < t0)
                return false;
            if (r < t1)
                t1 = r;
        }
    }
    double x0 = *ax + t0 * dx, y0 = *ay + t0 * dy;
    *bx = *ax + t1 * dx, *by = *ay + t1 * dy;
    *ax = x0, *ay = y0;
    return true;
}

typedef struct path_buf {
    cbm_context *ctx;
    CBM_ARRAY(double) xy;
    CBM_ARRAY(size_t) runs;
    bool nomem;
} path_buf;

static void path_point(path_buf *b, double x, double y, bool new_run)
{
    if (b->nomem)
        return;
    if (new_run || b->runs.len == 0)
        b->nomem |= CBM_ARRAY_PUSH(b->ctx, b->runs, (size_t)0) != CBM_OK;
    if (b->nomem)
        return;
    b->nomem |= CBM_ARRAY_PUSH(b->ctx, b->xy, x) != CBM_OK;
    b->nomem |= CBM_ARRAY_PUSH(b->ctx, b->xy, y) != CBM_OK;
    if (!b->nomem)
        b->runs.data[b->runs.len - 1]++;
}

/* The series as clipped pixel polylines (lines) or kept points (markers). */
static void series_path(const plot_series *s, const panel_box *pb, double margin, bool lines,
                        path_buf *b)
{
    double box[4] = {pb->x0 - margin, pb->y0 - margin, pb->x1 + margin, pb->y1 + margin};
    double px = 0, py = 0;
    bool have = false, open = false;
    for (size_t i = 0; i < s->n; i++) {
        if (!usable(s->x[i], pb->x.log) || !usable(s->y[i], pb->y.log)) {
            have = open = false;
            continue;
        }
        double x = to_px(&pb->x, s->x[i]), y = to_px(&pb->y, s->y[i]);
        if (!lines) {
            if (x >= box[0] && x <= box[2] && y >= box[1] && y <= box[3])
                path_point(b, x, y, false);
            continue;
        }
        if (have) {
            double ax = px, ay = py, bx = x, by = y;
            if (clip_segment(box, &ax, &ay, &bx, &by)) {
                bool starts_here = ax == px && ay == py;
                if (!open || !starts_here)
                    path_point(b, ax, ay, true);
                path_point(b, bx, by, false);
                open = bx == x && by == y;
            } else {
                open = false;
            }
        }
        px = x, py = y, have = true;
    }
    /* a lone point between gaps draws nothing as a line; markers show it */
}

static double series_width(const cbm_plot *p, const plot_series *s)
{
    return s->line_width > 0 ? s->line_width : fmax(1.5, p->font_size / 8.0);
}

static double marker_radius(const cbm_plot *p, const plot_series *s)
{
    return s->marker_size > 0 ? s->marker_size : fmax(2.5, 0.3 * p->font_size);
}

static cbm__rgb series_rgb(const plot_series *s)
{
    cbm__rgb c = {s->rgb[0], s->rgb[1], s->rgb[2]};
    return c;
}

static void draw_series(const cbm_plot *p, cbm__canvas *c, const plot_series *s,
                        const panel_box *pb, bool *nomem)
{
    char label[256];
    cbm__font_clean(s->label, label, sizeof label);
    c->ops->group_begin(c, "series", label);
    cbm__stroke st = {series_rgb(s), series_width(p, s), s->line};
    if (s->line != CBM_PLOT_NO_LINE) {
        path_buf b = {p->ctx, {0}, {0}, false};
        series_path(s, pb, 2.0 * st.width, true, &b);
        if (!b.nomem && b.runs.len) {
            c->ops->clip_begin(c, pb->x0, pb->y0, pb->x1 - pb->x0, pb->y1 - pb->y0);
            c->ops->polylines(c, b.xy.data, b.runs.data, b.runs.len, &st);
            c->ops->clip_end(c);
        }
        *nomem |= b.nomem;
        CBM_ARRAY_FREE(p->ctx, b.xy);
        CBM_ARRAY_FREE(p->ctx, b.runs);
    }
    if (s->marker != CBM_PLOT_MARKER_NONE) {
        path_buf b = {p->ctx, {0}, {0}, false};
        double r = marker_radius(p, s);
        series_path(s, pb, 0.5, false, &b); /* whole markers for the points in the area */
        cbm__rgb col = series_rgb(s);
        if (!b.nomem && b.xy.len)
            c->ops->markers(c, b.xy.data, b.xy.len / 2, s->marker, r, &col,
                            fmax(1.0, st.width * 0.8));
        *nomem |= b.nomem;
        CBM_ARRAY_FREE(p->ctx, b.xy);
        CBM_ARRAY_FREE(p->ctx, b.runs);
    }
    c->ops->group_end(c);
}

/* The legend's box size, and where it goes. */
static void draw_legend(const cbm_plot *p, cbm__canvas *c, const plot_panel *pl,
                        const panel_box *pb)
{
    if (pl->axes.legend == CBM_PLOT_LEGEND_NONE)
        return;
    double fs = 0.9 * p->font_size, row = 1.45 * fs, sample = 2.4 * fs, pad = 0.5 * fs;
    double textw = 0;
    size_t rows = 0;
    char label[256];
    for (size_t k = 0; k < pl->series.len; k++) {
        if (!pl->series.data[k].label)
            continue;
        cbm__font_clean(pl->series.data[k].label, label, sizeof label);
        textw = fmax(textw, cbm__font_width(c->measure, label, fs));
        rows++;
    }
    if (rows == 0)
        return;
    double w = pad + sample + 0.5 * fs + textw + pad, h = 2 * pad + rows * row - 0.3 * fs;
    double inset = 0.6 * p->font_size;
    double cx[4] = {pb->x1 - inset - w, pb->x0 + inset, pb->x1 - inset - w, pb->x0 + inset};
    double cy[4] = {pb->y0 + inset, pb->y0 + inset, pb->y1 - inset - h, pb->y1 - inset - h};
    int at = 0;
    switch (pl->axes.legend) {
    case CBM_PLOT_LEGEND_TOP_LEFT:
        at = 1;
        break;
    case CBM_PLOT_LEGEND_BOTTOM_RIGHT:
        at = 2;
        break;
    case CBM_PLOT_LEGEND_BOTTOM_LEFT:
        at = 3;
        break;
    case CBM_PLOT_LEGEND_AUTO: {
        size_t best = SIZE_MAX;
        for (int k = 0; k < 4; k++) {
            /* points, and the midpoints of lines between them (sparse lines cross corners) */
            size_t covered = 0;
            for (size_t q = 0; q < pl->series.len; q++) {
                const plot_series *s = &pl->series.data[q];
                double px = NAN, py = NAN;
                for (size_t i = 0; i < s->n; i++) {
                    if (!usable(s->x[i], pb->x.log) || !usable(s->y[i], pb->y.log)) {
                        px = py = NAN;
                        continue;
                    }
                    double x = to_px(&pb->x, s->x[i]), y = to_px(&pb->y, s->y[i]);
                    covered += x >= cx[k] && x <= cx[k] + w && y >= cy[k] && y <= cy[k] + h;
                    if (s->line != CBM_PLOT_NO_LINE && isfinite(px)) {
                        double mx = 0.5 * (x + px), my = 0.5 * (y + py);
                        covered += mx >= cx[k] && mx <= cx[k] + w && my >= cy[k] && my <= cy[k] + h;
                    }
                    px = x, py = y;
                }
            }
            if (covered < best)
                best = covered, at = k;
        }
        break;
    }
    default:
        break;
    }
    double x = cx[at], y = cy[at];
    c->ops->group_begin(c, "legend", "");
    cbm__stroke frame = {frame_grey, 1.0, CBM_PLOT_SOLID};
    c->ops->rect(c, round(x) + 0.5, round(y) + 0.5, round(w), round(h), &white, 0.85, &frame);
    double cap = cbm__font_cap_height(c->measure, fs);
    size_t r = 0;
    for (size_t k = 0; k < pl->series.len; k++) {
        const plot_series *s = &pl->series.data[k];
        if (!s->label)
            continue;
        double mid = y + pad + (r + 0.5) * row - 0.15 * fs;
        double sx0 = x + pad, sx1 = x + pad + sample;
        cbm__rgb col = series_rgb(s);
        if (s->line != CBM_PLOT_NO_LINE) {
            double xy[4] = {sx0, mid, sx1, mid};
            size_t runs[1] = {2};
            cbm__stroke st = {col, series_width(p, s), s->line};
            c->ops->polylines(c, xy, runs, 1, &st);
        }
        if (s->marker != CBM_PLOT_MARKER_NONE) {
            double m[2] = {0.5 * (sx0 + sx1), mid};
            c->ops->markers(c, m, 1, s->marker, marker_radius(p, s), &col,
                            fmax(1.0, 0.8 * series_width(p, s)));
        }
        cbm__font_clean(s->label, label, sizeof label);
        c->ops->text(c, sx1 + 0.5 * fs, mid + 0.5 * cap, label, fs, CBM__ANCHOR_START, false, &ink);
        r++;
    }
    c->ops->group_end(c);
}

static void draw_axes(const cbm_plot *p, cbm__canvas *c, const plot_panel *pl, const panel_box *pb)
{
    double fs = p->font_size, tick = 0.35 * fs;
    double cap = cbm__font_cap_height(c->measure, fs);
    c->ops->group_begin(c, "axes", "");
    cbm__stroke ax = {axis_grey, 1.0, CBM_PLOT_SOLID};
    double segs[4 * 2 * MAX_TICKS];
    size_t n = 0;
    for (size_t i = 0; i < pb->x.nticks; i++) {
        double x = snap(to_px(&pb->x, pb->x.ticks[i]), pb->x0, pb->x1);
        double s[4] = {x, pb->y1, x, pb->y1 + tick};
        memcpy(segs + 4 * n++, s, sizeof s);
    }
    for (size_t i = 0; i < pb->y.nticks; i++) {
        double y = snap(to_px(&pb->y, pb->y.ticks[i]), pb->y0, pb->y1);
        double s[4] = {pb->x0 - tick, y, pb->x0, y};
        memcpy(segs + 4 * n++, s, sizeof s);
    }
    if (n)
        c->ops->segments(c, segs, n, &ax);
    c->ops->rect(c, pb->x0 + 0.5, pb->y0 + 0.5, pb->x1 - pb->x0 - 1.0, pb->y1 - pb->y0 - 1.0, NULL,
                 0.0, &ax);
    for (size_t i = 0; i < pb->x.nticks; i++)
        c->ops->text(c, to_px(&pb->x, pb->x.ticks[i]), pb->y1 + tick + 0.35 * fs + cap,
                     pb->x.labels[i], fs, CBM__ANCHOR_MIDDLE, false, &ink);
    for (size_t i = 0; i < pb->y.nticks; i++)
        c->ops->text(c, pb->x0 - tick - 0.35 * fs, to_px(&pb->y, pb->y.ticks[i]) + 0.5 * cap,
                     pb->y.labels[i], fs, CBM__ANCHOR_END, false, &ink);
    char label[256];
    if (pl->xlabel) {
        cbm__font_clean(pl->xlabel, label, sizeof label);
        c->ops->text(c, 0.5 * (pb->x0 + pb->x1), pb->y1 + tick + 0.35 * fs + 2.0 * cap + 0.9 * fs,
                     label, fs, CBM__ANCHOR_MIDDLE, false, &ink);
    }
    if (pl->ylabel) {
        cbm__font_clean(pl->ylabel, label, sizeof label);
        c->ops->text(c, 0.5 * fs + cap, 0.5 * (pb->y0 + pb->y1), label, fs, CBM__ANCHOR_MIDDLE,
                     true, &ink);
    }
    if (pl->title) {
        cbm__font_clean(pl->title, label, sizeof label);
        c->ops->text(c, 0.5 * (pb->x0 + pb->x1), pb->y0 - 0.45 * fs, label, fs, CBM__ANCHOR_MIDDLE,
                     false, &ink);
    }
    c->ops->group_end(c);
}

static void draw_grid(cbm__canvas *c, const panel_box *pb)
{
    double segs[4 * 2 * MAX_TICKS];
    size_t n = 0;
    for (size_t i = 0; i < pb->x.nticks; i++) {
        double x = snap(to_px(&pb->x, pb->x.ticks[i]), pb->x0, pb->x1);
        double s[4] = {x, pb->y0, x, pb->y1};
        memcpy(segs + 4 * n++, s, sizeof s);
    }
    for (size_t i = 0; i < pb->y.nticks; i++) {
        double y = snap(to_px(&pb->y, pb->y.ticks[i]), pb->y0, pb->y1);
        double s[4] = {pb->x0, y, pb->x1, y};
        memcpy(segs + 4 * n++, s, sizeof s);
    }
    cbm__stroke g = {grid_grey, 1.0, CBM_PLOT_SOLID};
    if (n) {
        c->ops->group_begin(c, "grid", "");
        c->ops->segments(c, segs, n, &g);
        c->ops->group_end(c);
    }
}

cbm_status cbm__plot_draw(const cbm_plot *p, cbm__canvas *c)
{
    double W = p->width, H = p->height, fs = p->font_size;
    double cap = cbm__font_cap_height(c->measure, fs);
    double top = p->title ? 2.2 * fs : 1.0 * fs;
    /* per panel: space above (its title) and below (tick labels, x label) the plot area */
    double above[CBM_PLOT_MAX_PANELS] = {0}, below[CBM_PLOT_MAX_PANELS] = {0}, used = top;
    for (int k = 0; k < p->npanels; k++) {
        const plot_panel *pl = &p->panel[k];
        above[k] = pl->title ? 1.6 * fs : (k ? 0.9 * fs : 0.2 * fs);
        below[k] = 0.35 * fs + 0.35 * fs + cap + (pl->xlabel ? 0.9 * fs + cap : 0.0) + 0.7 * fs;
        used += above[k] + below[k];
    }
    double ph = (H - used) / p->npanels;
    if (ph < 4.0 * fs)
        ph = fmax(1.0, ph);
    /* ranges and ticks first: the widest y label sets the common left edge */
    panel_box pb[CBM_PLOT_MAX_PANELS];
    memset(pb, 0, sizeof pb);
    int xt = clampi((W - 8.0 * fs) / (6.0 * fs), 2, 8), yt = clampi(ph / (3.5 * fs), 2, 8);
    double ylab = 0, right = fs;
    bool any_ylabel = false;
    for (int k = 0; k < p->npanels; k++) {
        axis_range(&p->panel[k], true, xt, &pb[k].x);
        axis_range(&p->panel[k], false, yt, &pb[k].y);
        for (size_t i = 0; i < pb[k].y.nticks; i++)
            ylab = fmax(ylab, cbm__font_width(c->measure, pb[k].y.labels[i], fs));
        if (pb[k].x.nticks > 0 &&
            pb[k].x.ticks[pb[k].x.nticks - 1] >= pb[k].x.hi - 1e-9 * (pb[k].x.hi - pb[k].x.lo))
            right = fmax(right,
                         0.5 * cbm__font_width(c->measure, pb[k].x.labels[pb[k].x.nticks - 1], fs) +
                             0.3 * fs);
        any_ylabel |= p->panel[k].ylabel != NULL;
    }
    double left = 0.6 * fs + (any_ylabel ? cap + 1.0 * fs : 0.0) + ylab + 0.35 * fs + 0.35 * fs;
    double x0 = round(left), x1 = round(W - right);
    if (x1 <= x0 + 1)
        x1 = x0 + 1;
    double y = top;
    for (int k = 0; k < p->npanels; k++) {
        y += above[k];
        pb[k].x0 = x0, pb[k].x1 = x1;
        pb[k].y0 = round(y), pb[k].y1 = round(y + ph);
        if (pb[k].y1 <= pb[k].y0 + 1)
            pb[k].y1 = pb[k].y0 + 1;
        y += ph + below[k];
        pb[k].x.p0 = x0, pb[k].x.p1 = x1;
        pb[k].y.p0 = pb[k].y1, pb[k].y.p1 = pb[k].y0;
    }
    bool nomem = false;
    for (int k = 0; k < p->npanels; k++) {
        const plot_panel *pl = &p->panel[k];
        if (pl->axes.grid)
            draw_grid(c, &pb[k]);
        for (size_t i = 0; i < pl->series.len; i++)
            draw_series(p, c, &pl->series.data[i], &pb[k], &nomem);
        draw_axes(p, c, pl, &pb[k]);
        draw_legend(p, c, pl, &pb[k]);
    }
    if (p->title) {
        char t[512];
        cbm__font_clean(p->title, t, sizeof t);
        double tfs = 1.25 * fs;
        c->ops->text(c, 0.5 * (x0 + x1), 0.5 * top + 0.5 * cbm__font_cap_height(c->measure, tfs), t,
                     tfs, CBM__ANCHOR_MIDDLE, false, &ink);
    }
    return nomem ? CBM_E_NOMEM : CBM_OK;
}
