/* The figure as SVG: the same layout as the picture (text measured by cairo with the same font),
 * written element by element rather than through cairo's SVG surface, so that text stays text
 * (<text>, searchable and editable, font-family DejaVu Sans), the file is small, and the bytes
 * depend only on the figure: no generated ids (the clip paths of the series' lines are numbered
 * in drawing order) and coordinates printed with two decimals. Each series is a <g class="series">
 * holding its <title> (the legend label), one <path> for its line and one for its markers. */
#include "plot_internal.h"

#include <math.h>
#include <string.h>

typedef struct svg_canvas {
    cbm__canvas base;
    FILE *f;
    int clips; /* clip paths written */
} svg_canvas;

static FILE *out(cbm__canvas *c)
{
    return ((svg_canvas *)(void *)c)->f;
}

static void rgb_hex(const cbm__rgb *c, char buf[8])
{
    int v[3] = {(int)lround(c->r * 255.0), (int)lround(c->g * 255.0), (int)lround(c->b * 255.0)};
    for (int k = 0; k < 3; k++)
        v[k] = v[k] < 0 ? 0 : v[k] > 255 ? 255 : v[k];
    snprintf(buf, 8, "#%02x%02x%02x", v[0], v[1], v[2]);
}

/* Text as XML character data or attribute value (the layout has removed control characters). */
static void escaped(FILE *f, const char *s)
{
    for (; *s; s++) {
        switch (*s) {
        case '&':
            fputs("&amp;", f);
            break;
        case '<':
            fputs("&lt;", f);
            break;
        case '>':
            fputs("&gt;", f);
            break;
        case '"':
            fputs("&quot;", f);
            break;
        default:
            fputc(*s, f);
        }
    }
}

static void stroke_attrs(FILE *f, const cbm__stroke *s, bool unfilled)
{
    char h[8];
    rgb_hex(&s->color, h);
    if (unfilled)
        fputs(" fill=\"none\"", f);
    fprintf(f, " stroke=\"%s\" stroke-width=\"%.2f\"", h, s->width);
    double dash[2];
    if (cbm__plot_dashes(s->line, s->width, dash) == 2)
        fprintf(f, " stroke-dasharray=\"%.2f %.2f\"", dash[0], dash[1]);
    if (s->line == CBM_PLOT_DOTTED)
        fputs(" stroke-linecap=\"round\"", f);
}

static void group_begin(cbm__canvas *c, const char *cls, const char *label)
{
    FILE *f = out(c);
    fprintf(f, "<g class=\"%s\">", cls);
    if (label && *label) {
        fputs("<title>", f);
        escaped(f, label);
        fputs("</title>", f);
    }
    fputc('\n', f);
}

static void group_end(cbm__canvas *c)
{
    fputs("</g>\n", out(c));
}

static void clip_begin(cbm__canvas *c, double x, double y, double w, double h)
{
    svg_canvas *s = (svg_canvas *)(void *)c;
    s->clips++;
    fprintf(s->f,
            "<clipPath id=\"clip%d\"><rect x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" "
            "height=\"%.2f\"/></clipPath>\n<g clip-path=\"url(#clip%d)\">\n",
            s->clips, x, y, w, h, s->clips);
}

static void clip_end(cbm__canvas *c)
{
    fputs("</g>\n", out(c));
}

static void rect(cbm__canvas *c, double x, double y, double w, double h, const cbm__rgb *fill,
                 double fill_alpha, const cbm__stroke *stroke)
{
    FILE *f = out(c);
    fprintf(f, "<rect x=\"%.2f\" y=\"%.2f\" width=\"%.2f\" height=\"%.2f\"", x, y, w, h);
    if (fill) {
        char hf[8];
        rgb_hex(fill, hf);
        fprintf(f, " fill=\"%s\"", hf);
        if (fill_alpha < 1.0)
            fprintf(f, " fill-opacity=\"%.2f\"", fill_alpha);
    }
    if (stroke)
        stroke_attrs(f, stroke, !fill);
    fputs("/>\n", f);
}

static void segments(cbm__canvas *c, const double *p, size_t n, const cbm__stroke *s)
{
    FILE *f = out(c);
    fputs("<path d=\"", f);
    for (size_t i = 0; i < n; i++)
        fprintf(f, "%sM%.2f %.2fL%.2f %.2f", i ? " " : "", p[4 * i], p[4 * i + 1], p[4 * i + 2],
                p[4 * i + 3]);
    fputc('"', f);
    stroke_attrs(f, s, true);
    fputs("/>\n", f);
}

static void polylines(cbm__canvas *c, const double *xy, const size_t *runs, size_t nruns,
                      const cbm__stroke *s)
{
    FILE *f = out(c);
    fputs("<path d=\"", f);
    size_t at = 0;
    for (size_t r = 0; r < nruns; r++)
        for (size_t i = 0; i < runs[r]; i++, at++)
            fprintf(f, "%s%c%.2f %.2f", at ? " " : "", i ? 'L' : 'M', xy[2 * at], xy[2 * at + 1]);
    fputc('"', f);
    stroke_attrs(f, s, true);
    fputs(" stroke-linejoin=\"round\"/>\n", f);
}

static void marker_path(FILE *f, cbm_plot_marker m, double x, double y, double r)
{
    switch (m) {
    case CBM_PLOT_MARKER_CIRCLE:
        fprintf(f, "M%.2f %.2fa%.2f %.2f 0 1 0 %.2f 0a%.2f %.2f 0 1 0 %.2f 0Z", x - r, y, r, r,
                2 * r, r, r, -2 * r);
        break;
    case CBM_PLOT_MARKER_SQUARE:
        fprintf(f, "M%.2f %.2fh%.2fv%.2fh%.2fZ", x - 0.85 * r, y - 0.85 * r, 1.7 * r, 1.7 * r,
                -1.7 * r);
        break;
    case CBM_PLOT_MARKER_TRIANGLE:
        fprintf(f, "M%.2f %.2fL%.2f %.2fL%.2f %.2fZ", x, y - 1.15 * r, x + r, y + 0.6 * r, x - r,
                y + 0.6 * r);
        break;
    case CBM_PLOT_MARKER_DIAMOND:
        fprintf(f, "M%.2f %.2fL%.2f %.2fL%.2f %.2fL%.2f %.2fZ", x, y - 1.2 * r, x + r, y, x,
                y + 1.2 * r, x - r, y);
        break;
    case CBM_PLOT_MARKER_CROSS:
        fprintf(f, "M%.2f %.2fL%.2f %.2fM%.2f %.2fL%.2f %.2f", x - r, y - r, x + r, y + r, x - r,
                y + r, x + r, y - r);
        break;
    case CBM_PLOT_MARKER_PLUS:
        fprintf(f, "M%.2f %.2fL%.2f %.2fM%.2f %.2fL%.2f %.2f", x - r, y, x + r, y, x, y - r, x,
                y + r);
        break;
    default:
        break;
    }
}

static void markers(cbm__canvas *c, const double *xy, size_t n, cbm_plot_marker m, double r,
                    const cbm__rgb *color, double line_width)
{
    FILE *f = out(c);
    char h[8];
    rgb_hex(color, h);
    fputs("<path d=\"", f);
    for (size_t i = 0; i < n; i++)
        marker_path(f, m, xy[2 * i], xy[2 * i + 1], r);
    if (m == CBM_PLOT_MARKER_CROSS || m == CBM_PLOT_MARKER_PLUS)
        fprintf(f, "\" fill=\"none\" stroke=\"%s\" stroke-width=\"%.2f\"/>\n", h, line_width);
    else
        fprintf(f, "\" fill=\"%s\"/>\n", h);
}

static void text(cbm__canvas *c, double x, double y, const char *t, double size, cbm__anchor anchor,
                 bool vertical, const cbm__rgb *color)
{
    FILE *f = out(c);
    static const char *const anchors[] = {"start", "middle", "end"};
    fprintf(f, "<text x=\"%.2f\" y=\"%.2f\" font-size=\"%.2f\"", x, y, size);
    if (anchor != CBM__ANCHOR_START)
        fprintf(f, " text-anchor=\"%s\"", anchors[anchor]);
    if (vertical)
        fprintf(f, " transform=\"rotate(-90 %.2f %.2f)\"", x, y);
    char h[8];
    rgb_hex(color, h);
    if (strcmp(h, "#1a1a1a"))
        fprintf(f, " fill=\"%s\"", h);
    fputc('>', f);
    escaped(f, t);
    fputs("</text>\n", f);
}

static const cbm__canvas_ops svg_ops = {group_begin, group_end, clip_begin, clip_end, rect,
                                        segments,    polylines, markers,    text};

cbm_status cbm__plot_write_svg(const cbm_plot *p, FILE *f)
{
    CBM_TRY(cbm__cairo_load(p->ctx, "plot"));
    svg_canvas c = {{&svg_ops, cbm__font_measurer()}, f, 0};
    if (!c.base.measure)
        return CBM_E_NOMEM;
    fprintf(f,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
            "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"%d\" "
            "height=\"%d\" viewBox=\"0 0 %d %d\">\n",
            p->width, p->height, p->width, p->height);
    if (p->title) {
        char t[512];
        cbm__font_clean(p->title, t, sizeof t);
        fputs("<title>", f);
        escaped(f, t);
        fputs("</title>\n", f);
    }
    if (!p->transparent)
        fputs("<rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>\n", f);
    fputs("<g font-family=\"" CBM_FONT_FAMILY ", sans-serif\" fill=\"#1a1a1a\">\n", f);
    cbm_status st = cbm__plot_draw(p, &c.base);
    fputs("</g>\n</svg>\n", f);
    cbm__cairo.cairo_destroy(c.base.measure);
    return st;
}
