/* SVG projection writer (front, side, top or any view) for papers.
 *
 * Same orthographic camera as the PNG renderer (cbm__camera_fit). Painter's algorithm: ground
 * parts first, then every other kept triangle sorted from far to near by the depth of its
 * centroid along the view direction (qsort, ties broken by index so the output is
 * deterministic). Triangles of closed organs (branches, fruit, buds) whose mean vertex normal
 * faces away from the viewer are culled, which halves the file. Each triangle is flat-shaded
 * with the PNG's sun direction: colour = albedo * (0.38 + 0.7 max(0, n.s)), written as display
 * sRGB; a thin stroke of the same colour hides the hairline seams renderers leave between
 * abutting polygons. When colouring by a quantity, the legend is an SVG gradient with text
 * labels. Lines (cpfg's pixel lines kept untessellated) are sorted with the triangles by the
 * depth of their midpoint and written as <line> elements of their width in pixels (at least 1),
 * flat-coloured with round caps, as the PNG renderer draws them; consecutive lines with the same
 * stroke (colour, width, opacity) share a <g> that carries it. Output is well-formed XML
 * (checked with xmllint in the tests). */
#include "writers.h"

#include "cambium/io.h"

#include "../core/vecmath.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

typedef struct sort_key {
    double depth;
    uint32_t idx;  /* triangle or line */
    uint32_t line; /* 1 for a line */
} sort_key;

static int far_first(const void *a, const void *b)
{
    const sort_key *x = a, *y = b;
    if (x->depth != y->depth)
        return x->depth > y->depth ? -1 : 1;
    if (x->line != y->line)
        return x->line < y->line ? -1 : 1;
    return x->idx < y->idx ? -1 : x->idx > y->idx;
}

static void project(const cbm__camera *cam, cbm_vec3 p, double *x, double *y)
{
    cbm_vec3 d = v3_sub(p, cam->center);
    *x = cam->cx + v3_dot(d, cam->right) * cam->scale;
    *y = cam->cy - v3_dot(d, cam->up) * cam->scale;
}

static void shaded_hex(const float rgb[3], double light, char out[8])
{
    snprintf(out, 8, "#%02x%02x%02x", cbm__srgb8(rgb[0] * light), cbm__srgb8(rgb[1] * light),
             cbm__srgb8(rgb[2] * light));
}

static cbm_vec3 vpos(const cbm_scene_vertex *v)
{
    return v3(v->p[0], v->p[1], v->p[2]);
}

static void legend(FILE *f, const cbm_scene *s, const cbm_write_options *o, int x0, double lo,
                   double hi)
{
    int W = o->width, H = o->height;
    int bx = x0 + (W - x0) / 6, bw = (W - x0) / 5, top = H / 5, bot = H - H / 5;
    int fs = H >= 600 ? 14 : 10;
    fprintf(f, "<g font-family=\"DejaVu Sans, sans-serif\" font-size=\"%d\" fill=\"#202020\">\n",
            fs);
    fprintf(f, "<text x=\"%d\" y=\"%d\" text-anchor=\"end\">%s</text>\n", W - 6, fs + 4,
            cbm__color_title(o->color_by));
    if (o->color_by == CBM_COLOR_ORDER) {
        int maxo = cbm__legend_max_order(s);
        int step = (bot - top) / (maxo + 1);
        if (step > 2 * fs)
            step = 2 * fs;
        for (int k = 0; k <= maxo; k++) {
            float c[3];
            char h[8];
            cbm__colormap(CBM_COLOR_ORDER, k, c);
            shaded_hex(c, 1.0, h);
            fprintf(f, "<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"%s\"/>\n", bx,
                    top + k * step, bw, step - 2, h);
            fprintf(f, "<text x=\"%d\" y=\"%d\">%d</text>\n", bx + bw + 4,
                    top + k * step + step / 2 + fs / 3, k);
        }
    } else {
        fprintf(f, "<defs><linearGradient id=\"bar\" x1=\"0\" y1=\"1\" x2=\"0\" y2=\"0\">\n");
        for (int k = 0; k <= 10; k++) {
            float c[3];
            char h[8];
            cbm__colormap(o->color_by, k / 10.0, c);
            shaded_hex(c, 1.0, h);
            fprintf(f, "<stop offset=\"%.1f\" stop-color=\"%s\"/>\n", k / 10.0, h);
        }
        fprintf(f, "</linearGradient></defs>\n");
        fprintf(f, "<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"url(#bar)\"/>\n", bx,
                top, bw, bot - top);
        for (int k = 0; k <= 4; k++) {
            double v = hi - (hi - lo) * k / 4.0;
            int y = top + (bot - top) * k / 4;
            fprintf(f, "<text x=\"%d\" y=\"%d\">%.3g</text>\n", bx + bw + 4, y + fs / 3, v);
        }
    }
    fprintf(f, "</g>\n");
}

cbm_status cbm_write_svg(cbm_context *ctx, const cbm_scene *s, const char *path,
                         const cbm_write_options *opts)
{
    if (!ctx || !s || !path)
        return CBM_E_INVALID;
    cbm_write_options def;
    const cbm_write_options *o = cbm__opts(opts, &def);
    if (o->width <= 0 || o->height <= 0 || o->width > 32768 || o->height > 32768)
        return cbm__fail(ctx, CBM_E_INVALID, "%s: picture size %d x %d out of range", path,
                         o->width, o->height);
    int W = o->width, H = o->height;
    bool leg = o->legend && o->color_by != CBM_COLOR_MATERIAL && o->color_by < CBM_COLOR_COUNT;
    int legend_w = leg ? (W / 6 > 70 ? W / 6 : 70) : 0;
    if (legend_w > W / 2)
        legend_w = 0, leg = false;
    size_t np = cbm_scene_part_count(s), nt = cbm_scene_triangle_count(s);
    size_t nl = cbm_scene_line_count(s), nkeys = nt + nl;
    const cbm_scene_line *ln = cbm_scene_lines(s);
    const cbm_part *parts = cbm_scene_parts(s);
    const cbm_scene_vertex *v = cbm_scene_vertices(s);
    const uint32_t *tri = cbm_scene_triangles(s), *tp = cbm_scene_triangle_parts(s);
    float *col = NULL;
    double lo = 0, hi = 1;
    cbm_status st = cbm__part_colors(ctx, s, o, &col, &lo, &hi);
    if (st != CBM_OK)
        return st;
    sort_key *keys = cbm__alloc(ctx, (nkeys ? nkeys : 1) * sizeof *keys);
    cbm_out *out = NULL;
    if (!keys) {
        st = CBM_E_NOMEM;
        goto done;
    }
    cbm__camera cam;
    bool fitted = cbm__camera_fit(&cam, s, o, W - legend_w, H, 0.5 * (W - legend_w), 0.5 * H, 0.9);
    cbm_vec3 sun = v3_normalize(v3_add(v3_add(v3_scale(cam.up, 0.85), v3_scale(cam.right, -0.45)),
                                       v3_scale(cam.dir, -0.55)));
    size_t nk = 0, nground = 0;
    if (fitted) {
        /* ground first (in scene order), then the sorted rest after it */
        for (int pass = 0; pass < 2; pass++)
            for (size_t t = 0; t < nt; t++) {
                const cbm_part *p = &parts[tp[t]];
                if (!cbm__part_kept(p, o) || (p->organ == CBM_ORGAN_GROUND) != (pass == 0))
                    continue;
                const cbm_scene_vertex *a = &v[tri[3 * t]], *b = &v[tri[3 * t + 1]],
                                       *c = &v[tri[3 * t + 2]];
                bool closed = p->organ == CBM_ORGAN_BRANCH || p->organ == CBM_ORGAN_FRUIT ||
                              p->organ == CBM_ORGAN_BUD;
                if (closed) {
                    cbm_vec3 n = v3(a->n[0] + b->n[0] + c->n[0], a->n[1] + b->n[1] + c->n[1],
                                    a->n[2] + b->n[2] + c->n[2]);
                    if (v3_dot(n, cam.dir) > 0)
                        continue;
                }
                cbm_vec3 m = v3_scale(v3_add(vpos(a), v3_add(vpos(b), vpos(c))), 1.0 / 3.0);
                keys[nk].depth = v3_dot(m, cam.dir);
                keys[nk].idx = (uint32_t)t;
                keys[nk].line = 0;
                nk++;
                if (pass == 0)
                    nground++;
            }
        /* lines, keyed by their midpoint's depth */
        for (size_t i = 0; i < nl; i++) {
            if (!cbm__part_kept(&parts[ln[i].part], o))
                continue;
            const float *a = ln[i].p0, *b = ln[i].p1;
            cbm_vec3 m = v3(0.5 * ((double)a[0] + b[0]), 0.5 * ((double)a[1] + b[1]),
                            0.5 * ((double)a[2] + b[2]));
            keys[nk].depth = v3_dot(m, cam.dir);
            keys[nk].idx = (uint32_t)i;
            keys[nk].line = 1;
            nk++;
        }
        qsort(keys + nground, nk - nground, sizeof *keys, far_first);
    }
    if ((st = cbm_out_open(ctx, path, &out)) != CBM_OK)
        goto done;
    FILE *f = cbm_out_stream(out);
    fprintf(f,
            "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
            "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"%d\" height=\"%d\" "
            "viewBox=\"0 0 %d %d\">\n"
            "<title>cambium scene</title>\n"
            "<desc>orthographic projection, %.6g pixels per metre, view direction (%.4f %.4f "
            "%.4f), y up</desc>\n",
            W, H, W, H, fitted ? cam.scale : 0.0, fitted ? cam.dir.x : 0.0,
            fitted ? cam.dir.y : 0.0, fitted ? cam.dir.z : 0.0);
    if (o->background[3] > 0) {
        char h[8];
        shaded_hex(o->background, 1.0, h);
        fprintf(f, "<rect width=\"100%%\" height=\"100%%\" fill=\"%s\" fill-opacity=\"%.3f\"/>\n",
                h, o->background[3]);
    }
    fprintf(f, "<g stroke-width=\"0.35\" stroke-linejoin=\"round\" stroke-linecap=\"round\">\n");
    bool group = false; /* a group of lines with the same stroke is open */
    char group_hex[8] = "";
    float group_w = 0.0f, group_a = 0.0f;
    for (size_t k = 0; k < nk; k++) {
        if (keys[k].line) {
            /* a line: flat-coloured, its width in pixels (at least 1), round ends; a run of
             * lines with the same stroke shares one group that holds it */
            const cbm_scene_line *l = &ln[keys[k].idx];
            const float *c = col + 4 * l->part;
            double x0, y0, x1, y1;
            project(&cam, v3(l->p0[0], l->p0[1], l->p0[2]), &x0, &y0);
            project(&cam, v3(l->p1[0], l->p1[1], l->p1[2]), &x1, &y1);
            char h[8];
            shaded_hex(c, 1.0, h);
            float w = l->width > 1.0f ? l->width : 1.0f;
            if (!group || strcmp(h, group_hex) || w != group_w || c[3] != group_a) {
                if (group)
                    fprintf(f, "</g>\n");
                fprintf(f, "<g stroke=\"%s\" stroke-width=\"%.3g\"", h, (double)w);
                if (c[3] < 1.0f)
                    fprintf(f, " stroke-opacity=\"%.3f\"", c[3]);
                fprintf(f, ">\n");
                group = true;
                memcpy(group_hex, h, sizeof h);
                group_w = w;
                group_a = c[3];
            }
            fprintf(f, "<line x1=\"%.2f\" y1=\"%.2f\" x2=\"%.2f\" y2=\"%.2f\"/>\n", x0, y0, x1, y1);
            continue;
        }
        if (group) {
            fprintf(f, "</g>\n");
            group = false;
        }
        size_t t = keys[k].idx;
        const float *c = col + 4 * tp[t];
        cbm_vec3 P[3];
        for (int q = 0; q < 3; q++)
            P[q] = vpos(&v[tri[3 * t + (size_t)q]]);
        cbm_vec3 n = v3_cross(v3_sub(P[1], P[0]), v3_sub(P[2], P[0]));
        if (v3_norm(n) == 0)
            continue;
        n = v3_normalize(n);
        if (v3_dot(n, cam.dir) > 0)
            n = v3_neg(n);
        double light = 0.38 + 0.7 * fmax(0.0, v3_dot(n, sun));
        char h[8];
        shaded_hex(c, light, h);
        fprintf(f, "<path d=\"");
        for (int q = 0; q < 3; q++) {
            double x, y;
            project(&cam, P[q], &x, &y);
            fprintf(f, "%c%.2f %.2f", q ? 'L' : 'M', x, y);
        }
        if (c[3] < 1.0f)
            fprintf(f, "Z\" fill=\"%s\" stroke=\"none\" fill-opacity=\"%.3f\"/>\n", h, c[3]);
        else
            fprintf(f, "Z\" fill=\"%s\" stroke=\"%s\"/>\n", h, h);
    }
    if (group)
        fprintf(f, "</g>\n");
    fprintf(f, "</g>\n");
    if (leg)
        legend(f, s, o, W - legend_w, lo, hi);
    fprintf(f, "</svg>\n");
    st = cbm_out_commit(out);
    out = NULL;
done:
    cbm_out_abort(out);
    cbm__free(ctx, col, 4 * (np ? np : 1) * sizeof *col);
    cbm__free(ctx, keys, (nkeys ? nkeys : 1) * sizeof *keys);
    return st;
}
