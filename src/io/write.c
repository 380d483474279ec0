/* Writers' common ground: default options, dispatch by extension, the orthographic camera fitted
 * to a scene (projection of every kept vertex and line end on the view plane, bounding box scaled
 * to a fraction of the picture), colour modes and their maps, and a 5x7 bitmap font for the legends
 * of pictures.
 *
 * Colour maps: stress ratio goes from blue (0) through yellow to red (1, the modulus of rupture
 * reached), a sequential map built on the perceptual "viridis"-like control points for age, a
 * white-to-reddish-brown ramp for reaction wood, and a qualitative palette (Okabe-Ito, safe
 * for colour-blind readers) for branch orders. */
#include "writers.h"

#include "../core/vecmath.h"

#include <math.h>
#include <string.h>

cbm_write_options cbm_write_options_default(void)
{
    cbm_write_options o;
    memset(&o, 0, sizeof o);
    o.width = 800;
    o.height = 800;
    o.view = CBM_VIEW_ISO;
    o.view_dir = v3(-1, -0.8, -1);
    o.background[0] = o.background[1] = o.background[2] = o.background[3] = 1.0f;
    o.color_by = CBM_COLOR_MATERIAL;
    o.range_min = NAN;
    o.range_max = NAN;
    o.ground = true;
    o.legend = true;
    o.shadows = true;
    o.ao_samples = 16;
    o.supersample = 2;
    o.threads = 0;
    o.frame_time = 0.5;
    return o;
}

static bool same_ci(const char *a, const char *b)
{
    for (; *a && *b; a++, b++) {
        char c = *a >= 'A' && *a <= 'Z' ? (char)(*a - 'A' + 'a') : *a;
        if (c != *b)
            return false;
    }
    return *a == *b;
}

cbm_status cbm_scene_write_as(cbm_context *ctx, const cbm_scene *scene, const char *path,
                              const char *format, const cbm_write_options *opts)
{
    if (!ctx || !path || !format)
        return CBM_E_INVALID;
    cbm_write_options def = cbm_write_options_default();
    if (!opts)
        opts = &def;
    bool picture = same_ci(format, "png") || same_ci(format, "svg");
    if (scene && !picture && cbm_scene_line_count(scene) > 0)
        return cbm__fail(ctx, CBM_E_UNSUPPORTED,
                         "%s: the scene holds %zu pixel lines, which only pictures (.png .svg) "
                         "draw; interpret the model with line mode off for a mesh",
                         path, cbm_scene_line_count(scene));
    if (same_ci(format, "glb"))
        return cbm_write_glb(ctx, scene, path, opts);
    if (!scene && opts->frame_count > 0 && opts->frames)
        scene = opts->frames[opts->frame_count - 1];
    if (!scene)
        return cbm__fail(ctx, CBM_E_INVALID, "%s: no scene to write", path);
    if (same_ci(format, "obj"))
        return cbm_write_obj(ctx, scene, path, opts);
    if (same_ci(format, "ply"))
        return cbm_write_ply(ctx, scene, path, opts);
    if (same_ci(format, "png"))
        return cbm_write_png(ctx, scene, path, opts);
    if (same_ci(format, "svg"))
        return cbm_write_svg(ctx, scene, path, opts);
    if (same_ci(format, "csv"))
        return cbm_write_parts_csv(ctx, scene, path, opts);
    return cbm__fail(ctx, CBM_E_UNSUPPORTED,
                     "%s: unknown output format '%s' (expected obj ply glb png svg csv)", path,
                     format);
}

cbm_status cbm_scene_write(cbm_context *ctx, const cbm_scene *scene, const char *path,
                           const cbm_write_options *opts)
{
    if (!ctx || !path)
        return CBM_E_INVALID;
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash))
        return cbm__fail(ctx, CBM_E_UNSUPPORTED,
                         "%s: no extension to name the format (.obj .ply .glb .png .svg .csv)",
                         path);
    return cbm_scene_write_as(ctx, scene, path, dot + 1, opts);
}

/* ---- parts ---- */

bool cbm__part_kept(const cbm_part *p, const cbm_write_options *o)
{
    return o->ground || p->organ != CBM_ORGAN_GROUND;
}

cbm_status cbm__vertex_parts(cbm_context *ctx, const cbm_scene *s, uint32_t **out)
{
    size_t nv = cbm_scene_vertex_count(s), nt = cbm_scene_triangle_count(s);
    uint32_t *vp = cbm__alloc(ctx, (nv ? nv : 1) * sizeof *vp);
    if (!vp)
        return CBM_E_NOMEM;
    memset(vp, 0xff, (nv ? nv : 1) * sizeof *vp);
    const uint32_t *tri = cbm_scene_triangles(s), *tp = cbm_scene_triangle_parts(s);
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++)
            vp[tri[3 * t + (size_t)k]] = tp[t];
    *out = vp;
    return CBM_OK;
}

/* ---- camera ---- */

cbm_vec3 cbm__view_direction(const cbm_write_options *o)
{
    cbm_vec3 d;
    switch (o->view) {
    case CBM_VIEW_FRONT:
        d = v3(0, 0, -1);
        break;
    case CBM_VIEW_SIDE:
        d = v3(-1, 0, 0);
        break;
    case CBM_VIEW_TOP:
        d = v3(0, -1, 0);
        break;
    case CBM_VIEW_VECTOR:
        d = o->view_dir;
        break;
    case CBM_VIEW_ISO:
    default:
        d = v3(-1, -0.8, -1);
        break;
    }
    if (!v3_isfinite(d) || v3_norm(d) == 0.0)
        d = v3(-1, -0.8, -1);
    return v3_normalize(d);
}

static bool fit_point(const float *q, cbm_vec3 right, cbm_vec3 up, cbm_vec3 d, double lo[3],
                      double hi[3])
{
    cbm_vec3 pt = v3(q[0], q[1], q[2]);
    double c[3] = {v3_dot(pt, right), v3_dot(pt, up), v3_dot(pt, d)};
    for (int a = 0; a < 3; a++) {
        lo[a] = fmin(lo[a], c[a]);
        hi[a] = fmax(hi[a], c[a]);
    }
    return true;
}

bool cbm__camera_fit(cbm__camera *cam, const cbm_scene *s, const cbm_write_options *o, double w,
                     double h, double cx, double cy, double fill)
{
    cbm_vec3 d = cbm__view_direction(o);
    /* up: world y projected on the view plane; looking straight down, -z is up in the picture */
    cbm_vec3 up = v3_sub(v3(0, 1, 0), v3_scale(d, d.y));
    if (v3_norm(up) < 1e-6)
        up = v3_sub(v3(0, 0, -1), v3_scale(d, -d.z));
    up = v3_normalize(up);
    cbm_vec3 right = v3_cross(d, up);
    cam->dir = d;
    cam->up = up;
    cam->right = right;
    const cbm_scene_vertex *v = cbm_scene_vertices(s);
    const uint32_t *tri = cbm_scene_triangles(s), *tp = cbm_scene_triangle_parts(s);
    const cbm_part *parts = cbm_scene_parts(s);
    size_t nt = cbm_scene_triangle_count(s);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    bool any = false;
    const cbm_scene_line *ln = cbm_scene_lines(s);
    size_t nl = cbm_scene_line_count(s);
    for (int pass = 0; pass < 2 && !any; pass++) {
        /* fit on the plant; on the ground only when there is nothing else */
        for (size_t t = 0; t < nt; t++) {
            const cbm_part *p = &parts[tp[t]];
            if (!cbm__part_kept(p, o) || (pass == 0 && p->organ == CBM_ORGAN_GROUND))
                continue;
            for (int k = 0; k < 3; k++)
                any |= fit_point(v[tri[3 * t + (size_t)k]].p, right, up, d, lo, hi);
        }
        /* lines: their ends (their width in pixels is left to the margin) */
        for (size_t i = 0; i < nl; i++) {
            const cbm_part *p = &parts[ln[i].part];
            if (!cbm__part_kept(p, o) || (pass == 0 && p->organ == CBM_ORGAN_GROUND))
                continue;
            any |= fit_point(ln[i].p0, right, up, d, lo, hi);
            any |= fit_point(ln[i].p1, right, up, d, lo, hi);
        }
    }
    if (!any)
        return false;
    double ex = hi[0] - lo[0], ey = hi[1] - lo[1];
    double sx = ex > 0 ? fill * w / ex : INFINITY, sy = ey > 0 ? fill * h / ey : INFINITY;
    double sc = fmin(sx, sy);
    if (!isfinite(sc))
        sc = fill * fmin(w, h) / 1e-3;
    cam->scale = sc;
    cam->center = v3_add(v3_scale(right, 0.5 * (lo[0] + hi[0])),
                         v3_add(v3_scale(up, 0.5 * (lo[1] + hi[1])), v3_scale(d, lo[2])));
    cam->cx = cx;
    cam->cy = cy;
    cam->depth_min = 0.0;
    return true;
}

/* ---- colours ---- */

double cbm__part_quantity(const cbm_part *p, cbm_color_by by)
{
    switch (by) {
    case CBM_COLOR_STRESS:
        return p->stress_ratio;
    case CBM_COLOR_AGE:
        return p->age;
    case CBM_COLOR_REACTION:
        return p->reaction_wood;
    case CBM_COLOR_ORDER:
        return p->order >= 0 ? (double)p->order : NAN;
    case CBM_COLOR_STRESS_MPA:
        return p->stress * 1e-6;
    default:
        return NAN;
    }
}

const char *cbm__color_title(cbm_color_by by)
{
    switch (by) {
    case CBM_COLOR_STRESS:
        return "STRESS / MOR";
    case CBM_COLOR_AGE:
        return "AGE (YEARS)";
    case CBM_COLOR_REACTION:
        return "REACTION WOOD";
    case CBM_COLOR_ORDER:
        return "BRANCH ORDER";
    case CBM_COLOR_STRESS_MPA:
        return "STRESS (MPA)";
    default:
        return "";
    }
}

int cbm__legend_max_order(const cbm_scene *s)
{
    int maxo = 0;
    const cbm_part *p = cbm_scene_parts(s);
    for (size_t i = 0; i < cbm_scene_part_count(s); i++)
        if (p[i].organ == CBM_ORGAN_BRANCH && p[i].order > maxo)
            maxo = p[i].order;
    return maxo > 15 ? 15 : maxo;
}

void cbm__color_range(const cbm_scene *s, const cbm_write_options *o, double *lo, double *hi)
{
    double a = INFINITY, b = -INFINITY;
    if (o->color_by == CBM_COLOR_STRESS || o->color_by == CBM_COLOR_REACTION) {
        a = 0.0;
        b = 1.0;
    } else {
        const cbm_part *p = cbm_scene_parts(s);
        for (size_t i = 0; i < cbm_scene_part_count(s); i++) {
            double q = cbm__part_quantity(&p[i], o->color_by);
            if (isfinite(q)) {
                a = fmin(a, q);
                b = fmax(b, q);
            }
        }
        if (!(a <= b))
            a = 0.0, b = 1.0;
        if (o->color_by == CBM_COLOR_AGE || o->color_by == CBM_COLOR_STRESS_MPA)
            a = fmin(a, 0.0);
    }
    if (isfinite(o->range_min))
        a = o->range_min;
    if (isfinite(o->range_max))
        b = o->range_max;
    if (!(b > a))
        b = a + 1.0;
    *lo = a;
    *hi = b;
}

static void ramp(const float (*pts)[3], int n, double t, float rgb[3])
{
    if (!(t >= 0.0))
        t = 0.0;
    if (t > 1.0)
        t = 1.0;
    double x = t * (n - 1);
    int i = (int)x;
    if (i >= n - 1)
        i = n - 2;
    double f = x - i;
    for (int k = 0; k < 3; k++)
        rgb[k] = (float)((1.0 - f) * pts[i][k] + f * pts[i + 1][k]);
}

/* sRGB control points converted to linear once at use */
static float lin(float c)
{
    return c <= 0.04045f ? c / 12.92f : powf((c + 0.055f) / 1.055f, 2.4f);
}

void cbm__colormap(cbm_color_by by, double t, float rgb[3])
{
    static const float stress[5][3] = {{0.19f, 0.33f, 0.72f},
                                       {0.35f, 0.70f, 0.85f},
                                       {0.99f, 0.90f, 0.45f},
                                       {0.96f, 0.43f, 0.20f},
                                       {0.70f, 0.05f, 0.10f}};
    static const float viridis[5][3] = {{0.267f, 0.005f, 0.329f},
                                        {0.229f, 0.322f, 0.546f},
                                        {0.128f, 0.567f, 0.551f},
                                        {0.369f, 0.789f, 0.383f},
                                        {0.993f, 0.906f, 0.144f}};
    static const float react[3][3] = {
        {0.93f, 0.90f, 0.82f}, {0.80f, 0.45f, 0.25f}, {0.45f, 0.12f, 0.08f}};
    static const float okabe[8][3] = {
        {0.35f, 0.25f, 0.15f}, {0.90f, 0.62f, 0.00f}, {0.34f, 0.71f, 0.91f}, {0.00f, 0.62f, 0.45f},
        {0.94f, 0.89f, 0.26f}, {0.00f, 0.45f, 0.70f}, {0.84f, 0.37f, 0.00f}, {0.80f, 0.47f, 0.65f}};
    float c[3];
    switch (by) {
    case CBM_COLOR_STRESS:
    case CBM_COLOR_STRESS_MPA:
        ramp(stress, 5, t, c);
        break;
    case CBM_COLOR_REACTION:
        ramp(react, 3, t, c);
        break;
    case CBM_COLOR_ORDER: {
        int i = (int)lround(t);
        if (i < 0)
            i = 0;
        memcpy(c, okabe[i % 8], sizeof c);
        break;
    }
    case CBM_COLOR_AGE:
    default:
        ramp(viridis, 5, t, c);
        break;
    }
    for (int k = 0; k < 3; k++)
        rgb[k] = lin(c[k]);
}

void cbm__part_color_range(const cbm_part *p, const cbm_write_options *o, double lo, double hi,
                           float rgba[4])
{
    memcpy(rgba, p->color, 4 * sizeof(float));
    if (o->color_by == CBM_COLOR_MATERIAL || o->color_by >= CBM_COLOR_COUNT)
        return;
    if (p->organ != CBM_ORGAN_BRANCH) {
        /* quantities belong to the wood: other organs keep their colour, a little faded */
        for (int k = 0; k < 3; k++)
            rgba[k] = 0.5f * rgba[k] + 0.5f * 0.8f;
        return;
    }
    double q = cbm__part_quantity(p, o->color_by);
    if (!isfinite(q)) {
        rgba[0] = rgba[1] = rgba[2] = 0.35f; /* unknown: neutral grey */
        return;
    }
    double t = o->color_by == CBM_COLOR_ORDER ? q : (q - lo) / (hi - lo);
    cbm__colormap(o->color_by, t, rgba);
}

void cbm_part_color(const cbm_part *part, const cbm_write_options *opts, float rgba[4])
{
    cbm_write_options def = cbm_write_options_default();
    if (!opts)
        opts = &def;
    double lo = isfinite(opts->range_min) ? opts->range_min : 0.0;
    double hi = isfinite(opts->range_max) ? opts->range_max : 1.0;
    if (opts->color_by == CBM_COLOR_AGE && !isfinite(opts->range_max))
        hi = 100.0;
    if (!(hi > lo))
        hi = lo + 1.0;
    cbm__part_color_range(part, opts, lo, hi, rgba);
}

uint8_t cbm__srgb8(double c)
{
    if (!(c > 0.0))
        return 0;
    if (c >= 1.0)
        return 255;
    double s = c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
    return (uint8_t)lround(s * 255.0);
}

/* ---- 5x7 font ---- */

static const char glyph_chars[] = "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZ.-+/()%,:";
static const uint8_t glyph_rows[][7] = {
    {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}, {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E},
    {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}, {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E},
    {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}, {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E},
    {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}, {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08},
    {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}, {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C},
    {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}, {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E},
    {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}, {0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C},
    {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}, {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10},
    {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}, {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11},
    {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}, {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C},
    {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}, {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F},
    {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}, {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11},
    {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}, {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10},
    {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}, {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11},
    {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}, {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04},
    {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}, {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04},
    {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}, {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11},
    {0x11, 0x11, 0x11, 0x0A, 0x04, 0x04, 0x04}, {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F},
    {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}, {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00},
    {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}, {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00},
    {0x04, 0x08, 0x08, 0x08, 0x08, 0x08, 0x04}, {0x04, 0x02, 0x02, 0x02, 0x02, 0x02, 0x04},
    {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}, {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08},
    {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00},
};

const uint8_t *cbm__glyph(char c)
{
    static const uint8_t blank[7] = {0};
    if (c >= 'a' && c <= 'z')
        c = (char)(c - 'a' + 'A');
    const char *at = c ? strchr(glyph_chars, c) : NULL;
    return at ? glyph_rows[at - glyph_chars] : blank;
}

/* ---- helpers for the mesh writers ---- */

const cbm_write_options *cbm__opts(const cbm_write_options *o, cbm_write_options *def)
{
    if (o)
        return o;
    *def = cbm_write_options_default();
    return def;
}

cbm_status cbm__part_colors(cbm_context *ctx, const cbm_scene *s, const cbm_write_options *o,
                            float **out, double *lo, double *hi)
{
    size_t np = cbm_scene_part_count(s);
    float *c = cbm__alloc(ctx, 4 * (np ? np : 1) * sizeof *c);
    if (!c)
        return CBM_E_NOMEM;
    double a, b;
    cbm__color_range(s, o, &a, &b);
    const cbm_part *p = cbm_scene_parts(s);
    for (size_t i = 0; i < np; i++)
        cbm__part_color_range(&p[i], o, a, b, c + 4 * i);
    *out = c;
    if (lo)
        *lo = a;
    if (hi)
        *hi = b;
    return CBM_OK;
}

cbm_status cbm__vertex_remap(cbm_context *ctx, const cbm_scene *s, const cbm_write_options *o,
                             const uint32_t *vpart, uint32_t **out, size_t *kept)
{
    size_t nv = cbm_scene_vertex_count(s);
    uint32_t *m = cbm__alloc(ctx, (nv ? nv : 1) * sizeof *m);
    if (!m)
        return CBM_E_NOMEM;
    const cbm_part *p = cbm_scene_parts(s);
    size_t k = 0;
    for (size_t i = 0; i < nv; i++)
        m[i] = (vpart[i] != UINT32_MAX && cbm__part_kept(&p[vpart[i]], o)) ? (uint32_t)k++
                                                                           : UINT32_MAX;
    *out = m;
    *kept = k;
    return CBM_OK;
}
