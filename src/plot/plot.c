/* The figure as built by the caller: panels, their axes and series (copied, so the caller's
 * arrays need not outlive the calls), checked as they come in; writing by format. The drawing
 * itself is draw.c's, the files canvas_cairo.c's (PNG) and canvas_svg.c's (SVG). */
#define _POSIX_C_SOURCE 200809L /* strcasecmp */
#include "plot_internal.h"

#include "cambium/io.h"

#include <math.h>
#include <string.h>
#include <strings.h>

/* Okabe & Ito's qualitative palette (sRGB), ordered so the first colours differ most on white;
 * the yellow comes last since it is faint on a white background. */
static const float palette[8][3] = {{0.000f, 0.447f, 0.698f}, {0.835f, 0.369f, 0.000f},
                                    {0.000f, 0.620f, 0.451f}, {0.800f, 0.475f, 0.655f},
                                    {0.902f, 0.624f, 0.000f}, {0.337f, 0.706f, 0.914f},
                                    {0.000f, 0.000f, 0.000f}, {0.941f, 0.894f, 0.259f}};

cbm_plot_def cbm_plot_def_default(void)
{
    cbm_plot_def d;
    memset(&d, 0, sizeof d);
    d.width = 800;
    d.height = 600;
    d.panels = 1;
    return d;
}

cbm_plot_axes_def cbm_plot_axes_def_default(void)
{
    cbm_plot_axes_def a;
    memset(&a, 0, sizeof a);
    a.xmin = a.xmax = a.ymin = a.ymax = NAN;
    a.grid = true;
    a.legend = CBM_PLOT_LEGEND_AUTO;
    return a;
}

cbm_plot_series_def cbm_plot_series_def_default(void)
{
    cbm_plot_series_def s;
    memset(&s, 0, sizeof s);
    s.line = CBM_PLOT_SOLID;
    s.marker = CBM_PLOT_MARKER_NONE;
    s.color[0] = -1.0f;
    return s;
}

static char *copy_text(cbm_context *ctx, const char *s, bool *nomem)
{
    if (!s || !*s)
        return NULL;
    char *c = cbm__strdup(ctx, s);
    if (!c)
        *nomem = true;
    return c;
}

static void free_text(cbm_context *ctx, char *s)
{
    if (s)
        cbm__free(ctx, s, strlen(s) + 1);
}

cbm_status cbm_plot_create(cbm_context *ctx, const cbm_plot_def *def, cbm_plot **out)
{
    if (!ctx || !out)
        return CBM_E_INVALID;
    *out = NULL;
    cbm_plot_def d = def ? *def : cbm_plot_def_default();
    if (d.width < 16 || d.width > 16384 || d.height < 16 || d.height > 16384)
        return cbm__fail(ctx, CBM_E_INVALID, "plot: size %d x %d out of range 16..16384", d.width,
                         d.height);
    if (d.panels < 1 || d.panels > CBM_PLOT_MAX_PANELS)
        return cbm__fail(ctx, CBM_E_INVALID, "plot: %d panels, expected 1..%d", d.panels,
                         CBM_PLOT_MAX_PANELS);
    if (!(d.font_size == 0.0 || (d.font_size >= 4.0 && d.font_size <= 200.0)))
        return cbm__fail(ctx, CBM_E_INVALID, "plot: font size %g px, expected 4..200 or 0",
                         d.font_size);
    cbm_plot *p = cbm__calloc(ctx, 1, sizeof *p);
    if (!p)
        return CBM_E_NOMEM;
    p->ctx = ctx;
    p->width = d.width;
    p->height = d.height;
    p->npanels = d.panels;
    p->transparent = d.transparent;
    /* text about a 45th of the shorter side, 10 to 28 px */
    double fs = fmin(d.width, d.height / (0.6 + 0.4 * d.panels)) / 45.0;
    p->font_size = d.font_size > 0 ? d.font_size : fmax(10.0, fmin(28.0, round(fs)));
    bool nomem = false;
    p->title = copy_text(ctx, d.title, &nomem);
    for (int k = 0; k < p->npanels; k++)
        p->panel[k].axes = cbm_plot_axes_def_default();
    if (nomem) {
        cbm_plot_destroy(p);
        return CBM_E_NOMEM;
    }
    *out = p;
    return CBM_OK;
}

static void panel_free(cbm_context *ctx, plot_panel *pl)
{
    free_text(ctx, pl->xlabel);
    free_text(ctx, pl->ylabel);
    free_text(ctx, pl->title);
    pl->xlabel = pl->ylabel = pl->title = NULL;
    for (size_t i = 0; i < pl->series.len; i++) {
        plot_series *s = &pl->series.data[i];
        cbm__free(ctx, s->x, (s->n ? s->n : 1) * sizeof *s->x);
        cbm__free(ctx, s->y, (s->n ? s->n : 1) * sizeof *s->y);
        free_text(ctx, s->label);
    }
    CBM_ARRAY_FREE(ctx, pl->series);
}

void cbm_plot_destroy(cbm_plot *p)
{
    if (!p)
        return;
    for (int k = 0; k < CBM_PLOT_MAX_PANELS; k++)
        panel_free(p->ctx, &p->panel[k]);
    free_text(p->ctx, p->title);
    cbm__free(p->ctx, p, sizeof *p);
}

static cbm_status check_range(cbm_context *ctx, int panel, char axis, double lo, double hi,
                              bool log)
{
    if ((!isnan(lo) && !isfinite(lo)) || (!isnan(hi) && !isfinite(hi)))
        return cbm__fail(ctx, CBM_E_INVALID, "plot: panel %d: %c range must be finite or NaN",
                         panel, axis);
    if (isfinite(lo) && isfinite(hi) && !(lo < hi))
        return cbm__fail(ctx, CBM_E_INVALID, "plot: panel %d: %c range %g..%g is empty", panel,
                         axis, lo, hi);
    if (log && ((isfinite(lo) && lo <= 0) || (isfinite(hi) && hi <= 0)))
        return cbm__fail(ctx, CBM_E_INVALID,
                         "plot: panel %d: log %c axis needs a positive range, got %g..%g", panel,
                         axis, lo, hi);
    return CBM_OK;
}

cbm_status cbm_plot_set_axes(cbm_plot *p, int panel, const cbm_plot_axes_def *def)
{
    if (!p || !def)
        return CBM_E_INVALID;
    if (panel < 0 || panel >= p->npanels)
        return cbm__fail(p->ctx, CBM_E_INVALID, "plot: no panel %d (the figure has %d)", panel,
                         p->npanels);
    CBM_TRY(check_range(p->ctx, panel, 'x', def->xmin, def->xmax, def->xlog));
    CBM_TRY(check_range(p->ctx, panel, 'y', def->ymin, def->ymax, def->ylog));
    if ((unsigned)def->legend > CBM_PLOT_LEGEND_BOTTOM_LEFT)
        return cbm__fail(p->ctx, CBM_E_INVALID, "plot: panel %d: unknown legend place %d", panel,
                         (int)def->legend);
    plot_panel *pl = &p->panel[panel];
    bool nomem = false;
    char *xl = copy_text(p->ctx, def->xlabel, &nomem), *yl = copy_text(p->ctx, def->ylabel, &nomem);
    char *ti = copy_text(p->ctx, def->title, &nomem);
    if (nomem) {
        free_text(p->ctx, xl);
        free_text(p->ctx, yl);
        free_text(p->ctx, ti);
        return CBM_E_NOMEM;
    }
    free_text(p->ctx, pl->xlabel);
    free_text(p->ctx, pl->ylabel);
    free_text(p->ctx, pl->title);
    pl->axes = *def;
    pl->xlabel = xl, pl->ylabel = yl, pl->title = ti;
    pl->axes.xlabel = xl, pl->axes.ylabel = yl, pl->axes.title = ti;
    return CBM_OK;
}

cbm_status cbm_plot_add_series(cbm_plot *p, int panel, const cbm_plot_series_def *def)
{
    if (!p || !def)
        return CBM_E_INVALID;
    cbm_context *ctx = p->ctx;
    if (panel < 0 || panel >= p->npanels)
        return cbm__fail(ctx, CBM_E_INVALID, "plot: no panel %d (the figure has %d)", panel,
                         p->npanels);
    if (def->n > 0 && !def->y)
        return cbm__fail(ctx, CBM_E_INVALID, "plot: series of %zu points without y values", def->n);
    if ((unsigned)def->line > CBM_PLOT_NO_LINE || (unsigned)def->marker > CBM_PLOT_MARKER_PLUS)
        return cbm__fail(ctx, CBM_E_INVALID, "plot: unknown line style or marker");
    if (!(def->line_width >= 0 && def->line_width <= 100) ||
        !(def->marker_size >= 0 && def->marker_size <= 100))
        return cbm__fail(ctx, CBM_E_INVALID,
                         "plot: line width and marker size must be 0..100 px (0: automatic)");
    plot_panel *pl = &p->panel[panel];
    plot_series s;
    memset(&s, 0, sizeof s);
    s.n = def->n;
    s.line = def->line;
    s.marker = def->marker;
    s.line_width = def->line_width;
    s.marker_size = def->marker_size;
    if (def->color[0] < 0) {
        memcpy(s.rgb, palette[pl->palette_next % 8], sizeof s.rgb);
        pl->palette_next++;
    } else {
        for (int k = 0; k < 3; k++)
            s.rgb[k] = def->color[k] > 1.0f ? 1.0f : def->color[k] >= 0 ? def->color[k] : 0.0f;
    }
    bool nomem = false;
    s.label = copy_text(ctx, def->label, &nomem);
    size_t bytes = (s.n ? s.n : 1) * sizeof(double);
    s.x = cbm__alloc(ctx, bytes);
    s.y = cbm__alloc(ctx, bytes);
    cbm_status st = CBM_OK;
    if (nomem || !s.x || !s.y)
        st = CBM_E_NOMEM;
    else
        st = CBM_ARRAY_PUSH(ctx, pl->series, s);
    if (st != CBM_OK) {
        cbm__free(ctx, s.x, bytes);
        cbm__free(ctx, s.y, bytes);
        free_text(ctx, s.label);
        return st;
    }
    for (size_t i = 0; i < s.n; i++) {
        s.x[i] = def->x ? def->x[i] : (double)i;
        s.y[i] = def->y[i];
    }
    return CBM_OK;
}

cbm_status cbm_plot_write_as(cbm_plot *p, const char *path, const char *format)
{
    if (!p || !path || !format)
        return CBM_E_INVALID;
    if (!strcasecmp(format, "png")) {
        cbm_image *img = NULL;
        CBM_TRY(cbm__plot_render_cairo(p, &img));
        cbm_status st = cbm_image_write_png(p->ctx, img, path);
        cbm_image_destroy(img);
        return st;
    }
    if (!strcasecmp(format, "svg")) {
        cbm_out *o = NULL;
        CBM_TRY(cbm_out_open(p->ctx, path, &o));
        cbm_status st = cbm__plot_write_svg(p, cbm_out_stream(o));
        if (st != CBM_OK) {
            cbm_out_abort(o);
            return st;
        }
        return cbm_out_commit(o);
    }
    return cbm__fail(p->ctx, CBM_E_UNSUPPORTED, "%s: unknown plot format '%s' (expected png svg)",
                     path, format);
}

cbm_status cbm_plot_write(cbm_plot *p, const char *path)
{
    if (!p || !path)
        return CBM_E_INVALID;
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash))
        return cbm__fail(p->ctx, CBM_E_UNSUPPORTED,
                         "%s: no extension to name the plot format (.png .svg)", path);
    return cbm_plot_write_as(p, path, dot + 1);
}

cbm_status cbm_plot_render(cbm_plot *p, cbm_image **out)
{
    if (!p || !out)
        return CBM_E_INVALID;
    return cbm__plot_render_cairo(p, out);
}
