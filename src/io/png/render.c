/* The PNG renderer: ray casting with Embree 3 (the same machinery will serve light interception
 * in the tree models).
 *
 * Camera: orthographic, fitted to the plant (cbm__camera_fit: projected bounding box at 90 % of
 * the drawing area). Each pixel takes n x n stratified samples. A sample's primary ray finds
 * the nearest triangle; its normal is interpolated from the vertex normals (so tubes show their
 * true elliptical sections smoothly) and turned towards the viewer (leaves are two-sided).
 * Lighting, in linear RGB:
 *   colour = albedo * (k_sun * max(0, n.s) * V_sun + k_sky * A),
 * with s a sun direction fixed relative to the camera (above, left, in front), V_sun = 0 or 1
 * from a shadow ray, and A the ambient occlusion: the fraction of cosine-distributed hemisphere
 * rays that travel 0.2 plant sizes without hitting anything (Zhukov et al. 1998, "An ambient
 * light illumination model"); a pixel's occlusion rays are one stratified set (a rank-1 lattice
 * with a random shift from a hash of the pixel: shade_sample), so the picture is smooth and
 * does not depend on the number of threads. Rows are shared among threads through an
 * atomic counter. The legend (colour bar with its range, or one swatch per branch order) is
 * drawn in a strip on the right, its text in DejaVu Sans through cairo (src/plot/font.h).
 *
 * Lines (cpfg's pixel lines, kept untessellated in the scene) are rasterised, not ray cast: when
 * the scene has lines, every sample of an n x n grid per pixel keeps a depth and a colour; the
 * triangles' samples are stored there, then each line is drawn into the grid with a depth test
 * (draw_lines_band; the lines are first sorted into bands of sample rows, which the threads
 * take in turn), and the samples are averaged per pixel. Pictures of lines alone take at
 * least 3 x 3 samples per pixel (LINE_SAMPLES). The camera, background and legend are the same.
 *
 * Embree's own allocations are watched by its memory monitor, which refuses them when the
 * context's byte limit would be exceeded. */
#define _POSIX_C_SOURCE 200809L
#include "../writers.h"

#include "../../core/vecmath.h"
#include "../../plot/font.h"

#include "../../geom/embree_device.h"

#include <embree3/rtcore.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <unistd.h>

#define MAX_THREADS  64
#define LINE_SAMPLES 3 /* least samples per pixel side in a picture of lines alone */

typedef struct render_job {
    const cbm_scene *scene;
    const cbm_write_options *o;
    RTCScene rs;
    const uint32_t *prim_tri; /* kept triangle -> scene triangle */
    const float *colors;      /* per part, linear RGBA */
    cbm__camera cam;
    double back;    /* distance of ray origins behind the front of the plant, m */
    double eps;     /* ray offset, m */
    double ao_dist; /* m */
    cbm_vec3 sun;   /* unit, towards the sun */
    float ground_rgb[3];
    int width, height, ss, ao_rays;
    float *accum; /* width * height * 4, linear premultiplied */
    atomic_int next_row;
    /* with lines: one sample grid (ss x ss per pixel) of depths and linear colours that the
     * triangles' samples fill first and the lines are depth-tested into */
    float *sdepth;              /* sw * sh, m along dir from the camera centre; INFINITY: empty */
    float *scolor;              /* sw * sh * 3 */
    int sw, sh;                 /* sample grid size */
    int line_bands;             /* bands of sample rows the lines are drawn in */
    const size_t *band_first;   /* line_bands + 1 offsets into band_lines */
    const uint32_t *band_lines; /* the lines touching each band, in scene order */
    atomic_int next_band;
} render_job;

/* splitmix64 finaliser: decorrelated uniform numbers from a counter */
static double hash01(uint64_t x)
{
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    x ^= x >> 31;
    return (double)(x >> 11) * (1.0 / 9007199254740992.0);
}

static void set_ray(struct RTCRay *r, cbm_vec3 org, cbm_vec3 dir, double tfar)
{
    r->org_x = (float)org.x;
    r->org_y = (float)org.y;
    r->org_z = (float)org.z;
    r->dir_x = (float)dir.x;
    r->dir_y = (float)dir.y;
    r->dir_z = (float)dir.z;
    r->tnear = 0.0f;
    r->tfar = (float)tfar;
    r->time = 0.0f;
    r->mask = 0xFFFFFFFFu;
    r->id = 0;
    r->flags = 0;
}

static bool occluded(const render_job *j, cbm_vec3 org, cbm_vec3 dir, double dist)
{
    struct RTCIntersectContext ic;
    rtcInitIntersectContext(&ic);
    struct RTCRay r;
    set_ray(&r, org, dir, dist);
    cbm__rtc.rtcOccluded1(j->rs, &ic, &r);
    return r.tfar < 0.0f;
}

/* One sample: linear RGB and coverage (1 if something was hit), and its depth along the view
 * direction from the camera centre (INFINITY when nothing was hit). */
static void shade_sample(const render_job *j, double px, double py, uint64_t pixel, int sample,
                         float out[4], float *depth)
{
    const cbm__camera *c = &j->cam;
    double x = (px - c->cx) / c->scale, y = (c->cy - py) / c->scale;
    cbm_vec3 org = v3_add(c->center, v3_add(v3_scale(c->right, x), v3_scale(c->up, y)));
    org = v3_madd(org, c->dir, -j->back);
    struct RTCIntersectContext ic;
    rtcInitIntersectContext(&ic);
    struct RTCRayHit rh;
    set_ray(&rh.ray, org, c->dir, INFINITY);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    cbm__rtc.rtcIntersect1(j->rs, &ic, &rh);
    *depth = INFINITY;
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) {
        out[0] = out[1] = out[2] = out[3] = 0.0f;
        return;
    }
    *depth = (float)(rh.ray.tfar - j->back);
    cbm_vec3 p = v3_madd(org, c->dir, rh.ray.tfar);
    cbm_vec3 ng = v3_normalize(v3(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z));
    cbm_vec3 n;
    float albedo[3];
    if (rh.hit.geomID == 0) {
        size_t t = j->prim_tri[rh.hit.primID];
        const uint32_t *tri = cbm_scene_triangles(j->scene) + 3 * t;
        const cbm_scene_vertex *v = cbm_scene_vertices(j->scene);
        double u = rh.hit.u, w = rh.hit.v, z = 1.0 - u - w;
        const float *n0 = v[tri[0]].n, *n1 = v[tri[1]].n, *n2 = v[tri[2]].n;
        n = v3(z * n0[0] + u * n1[0] + w * n2[0], z * n0[1] + u * n1[1] + w * n2[1],
               z * n0[2] + u * n1[2] + w * n2[2]);
        if (v3_norm(n) < 1e-9)
            n = ng;
        n = v3_normalize(n);
        const float *col = j->colors + 4 * cbm_scene_triangle_parts(j->scene)[t];
        memcpy(albedo, col, sizeof albedo);
    } else {
        n = v3(0, 1, 0);
        memcpy(albedo, j->ground_rgb, sizeof albedo);
    }
    /* face the viewer */
    if (v3_dot(ng, c->dir) > 0)
        ng = v3_neg(ng);
    if (v3_dot(n, c->dir) > 0)
        n = v3_neg(n);
    cbm_vec3 base = v3_madd(p, ng, j->eps);
    double sun = fmax(0.0, v3_dot(n, j->sun));
    if (sun > 0 && j->o->shadows && occluded(j, base, j->sun, INFINITY))
        sun = 0;
    double ao = 1.0;
    if (j->ao_rays > 0) {
        /* cosine-weighted directions around n */
        cbm_vec3 t1 = fabs(n.x) < 0.9 ? v3(1, 0, 0) : v3(0, 1, 0);
        t1 = v3_normalize(v3_sub(t1, v3_scale(n, v3_dot(t1, n))));
        cbm_vec3 t2 = v3_cross(n, t1);
        int open = 0;
        /* the pixel's N = samples x rays directions are one stratified set: a rank-1 lattice
         * ((m + 1/2) / N, m phi mod 1), m = 0..N-1, shifted by a random offset per pixel
         * (Cranley-Patterson rotation); sample s takes the rays m = s rays .. s rays + rays - 1.
         * The pixel's mean of the occlusion then has far less variance than with independent
         * random rays (no grain), and stays a function of the pixel alone (any thread count). */
        int nall = j->ss * j->ss * j->ao_rays;
        double u1 = hash01(pixel * 2u), u2 = hash01(pixel * 2u + 1u);
        for (int k = 0; k < j->ao_rays; k++) {
            int m = sample * j->ao_rays + k;
            double r1 = ((double)m + 0.5) / nall + u1, r2 = (double)m * 0.6180339887498949 + u2;
            r1 -= floor(r1);
            r2 -= floor(r2);
            double rad = sqrt(r1), phi = 2.0 * CBM_PI * r2;
            cbm_vec3 d = v3_add(v3_add(v3_scale(t1, rad * cos(phi)), v3_scale(t2, rad * sin(phi))),
                                v3_scale(n, sqrt(fmax(0.0, 1.0 - r1))));
            if (v3_dot(d, ng) <= 0)
                d = v3_madd(d, ng, -2.0 * v3_dot(d, ng)); /* keep above the true surface */
            open += !occluded(j, base, v3_normalize(d), j->ao_dist);
        }
        ao = (double)open / j->ao_rays;
    }
    double light = 0.78 * sun + 0.42 * (0.35 + 0.65 * ao);
    for (int k = 0; k < 3; k++)
        out[k] = (float)(albedo[k] * light);
    out[3] = 1.0f;
}

static void *render_rows(void *arg)
{
    render_job *j = arg;
    int ss = j->ss;
    for (;;) {
        int y = atomic_fetch_add(&j->next_row, 1);
        if (y >= j->height)
            break;
        for (int x = 0; x < j->width; x++) {
            float acc[4] = {0, 0, 0, 0};
            for (int sy = 0; sy < ss; sy++)
                for (int sx = 0; sx < ss; sx++) {
                    uint64_t pixel = (uint64_t)y * (uint64_t)j->width + (uint64_t)x;
                    float s[4], depth;
                    shade_sample(j, x + (sx + 0.5) / ss, y + (sy + 0.5) / ss, pixel, sy * ss + sx,
                                 s, &depth);
                    if (j->sdepth) {
                        size_t q = (size_t)(y * ss + sy) * (size_t)j->sw + (size_t)(x * ss + sx);
                        j->sdepth[q] = depth;
                        memcpy(j->scolor + 3 * q, s, 3 * sizeof(float));
                        continue;
                    }
                    for (int k = 0; k < 4; k++)
                        acc[k] += s[k];
                }
            if (j->sdepth)
                continue;
            float *a = j->accum + 4 * ((size_t)y * (size_t)j->width + (size_t)x);
            for (int k = 0; k < 4; k++)
                a[k] = acc[k] / (float)(ss * ss);
        }
    }
    return NULL;
}

/* ---- lines ----
 * A line is the set of points within width / 2 pixels of its projected segment (round ends, so
 * the segments of a polyline join without gaps), at least one pixel wide, flat-coloured with its
 * part's colour as cpfg draws pixel lines. Its depth is interpolated along the segment. It is
 * scanned row by row of samples over the exact span of the row (row_span); a small one
 * (at most 64 samples in its box) by testing each sample of its box. Every
 * sample of the grid inside it takes its colour when the line is nearer than what the sample
 * holds (a triangle or another line; on equal depth the line wins over a triangle and the
 * earlier line over a later one). Coverage of a pixel is the fraction of its samples covered:
 * anti-aliased edges. The lines are sorted (stably) into bands of sample rows; threads take the
 * bands in turn and draw each band's lines in scene order clipped to it, so the picture is the
 * same with any thread count. */
/* The interval of x (relative to the line's start a) covered on a row at height py (relative to
 * a) by the capsule of radius sqrt(r2) around the segment from a to a + (dx, dy) of squared
 * length dd and length len: the hull of the two end discs' chords and the slab's interval (the
 * capsule is convex, so their union is one interval). False if the row misses it. */
static bool row_span(float py, float dx, float dy, float dd, float len, float r2, float *lo,
                     float *hi)
{
    float l = INFINITY, h = -INFINITY;
    if (py * py <= r2) {
        float c = sqrtf(r2 - py * py);
        l = -c;
        h = c;
    }
    float qy = py - dy;
    if (qy * qy <= r2) {
        float c = sqrtf(r2 - qy * qy);
        l = fminf(l, dx - c);
        h = fmaxf(h, dx + c);
    }
    if (dd > 0) {
        /* 0 <= (p - a).d <= dd and |d x (p - a)| <= r len, each linear in x */
        float sl = -INFINITY, sh = INFINITY, rl = sqrtf(r2) * len;
        const float coef[2] = {dx, -dy};
        const float bl[2] = {-py * dy, -dx * py - rl}, bh[2] = {dd - py * dy, -dx * py + rl};
        bool empty = false;
        for (int k = 0; k < 2 && !empty; k++) {
            if (coef[k] == 0.0f) {
                empty = !(bl[k] <= 0.0f && 0.0f <= bh[k]);
                continue;
            }
            float u = bl[k] / coef[k], v = bh[k] / coef[k];
            sl = fmaxf(sl, fminf(u, v));
            sh = fminf(sh, fmaxf(u, v));
        }
        if (!empty && sl <= sh) {
            l = fminf(l, sl);
            h = fmaxf(h, sh);
        }
    }
    *lo = l;
    *hi = h;
    return l <= h;
}

/* Sample-grid coordinates, affine in the point: x = p.R + kx, y = ky - p.U, z = p.D + kz;
 * sample (x, y) has its centre at (x + 0.5, y + 0.5). */
typedef struct line_xform {
    float R[3], U[3], D[3], kx, ky, kz;
} line_xform;

static line_xform line_transform(const render_job *j)
{
    const cbm__camera *c = &j->cam;
    int n = j->ss;
    double sc = c->scale * n;
    line_xform t = {{(float)(c->right.x * sc), (float)(c->right.y * sc), (float)(c->right.z * sc)},
                    {(float)(c->up.x * sc), (float)(c->up.y * sc), (float)(c->up.z * sc)},
                    {(float)c->dir.x, (float)c->dir.y, (float)c->dir.z},
                    (float)(c->cx * n - v3_dot(c->center, c->right) * sc),
                    (float)(c->cy * n + v3_dot(c->center, c->up) * sc),
                    (float)(-v3_dot(c->center, c->dir) - j->eps)}; /* lines win ties */
    return t;
}

/* The rows of samples a line may cover (its box, before clipping): false if none or NaN. */
static bool line_rows(const line_xform *t, const cbm_scene_line *l, int n, float *ay, float *by,
                      float *r)
{
    const float *a = l->p0, *b = l->p1;
    *ay = t->ky - (a[0] * t->U[0] + a[1] * t->U[1] + a[2] * t->U[2]);
    *by = t->ky - (b[0] * t->U[0] + b[1] * t->U[1] + b[2] * t->U[2]);
    *r = 0.5f * (l->width > 1.0f ? l->width : 1.0f) * (float)n;
    return *ay == *ay && *by == *by;
}

/* v clamped to [lo, hi] as an int (NaN gives lo): no float-to-int overflow for far points. */
static int to_index(float v, int lo, int hi)
{
    if (!(v >= (float)lo))
        return lo;
    return v > (float)hi ? hi : (int)v;
}

static void draw_lines_band(const render_job *j, int band)
{
    const cbm_scene *s = j->scene;
    const cbm_scene_line *ln = cbm_scene_lines(s);
    const cbm_part *parts = cbm_scene_parts(s);
    int n = j->ss;
    int r0 = (int)((long long)j->sh * band / j->line_bands);
    int r1 = (int)((long long)j->sh * (band + 1) / j->line_bands);
    line_xform tf = line_transform(j);
    const float *R = tf.R, *D = tf.D, kx = tf.kx, kz = tf.kz;
    const float fr0 = (float)r0, fr1 = (float)r1, fsw = (float)j->sw;
    for (size_t k = j->band_first[band]; k < j->band_first[band + 1]; k++) {
        const cbm_scene_line *l = &ln[j->band_lines[k]];
        const float *a = l->p0, *b = l->p1;
        float ay, by, r;
        if (!line_rows(&tf, l, n, &ay, &by, &r))
            continue;
        float r2 = r * r;
        float y_lo = (ay < by ? ay : by) - r, y_hi = (ay < by ? by : ay) + r;
        if (!(y_hi >= fr0 && y_lo <= fr1)) /* outside the band */
            continue;
        float ax = kx + a[0] * R[0] + a[1] * R[1] + a[2] * R[2];
        float bx = kx + b[0] * R[0] + b[1] * R[1] + b[2] * R[2];
        float x_lo = (ax < bx ? ax : bx) - r, x_hi = (ax < bx ? bx : ax) + r;
        if (!(x_hi >= 0.0f && x_lo <= fsw) || !cbm__part_kept(&parts[l->part], j->o))
            continue;
        float az = kz + a[0] * D[0] + a[1] * D[1] + a[2] * D[2];
        float bz = kz + b[0] * D[0] + b[1] * D[1] + b[2] * D[2];
        /* first and last rows and columns, clamped so that an empty range stays empty */
        int yb = to_index(ceilf(y_lo - 0.5f), r0, r1),
            ye = to_index(floorf(y_hi - 0.5f), r0 - 1, r1 - 1);
        int xb = to_index(ceilf(x_lo - 0.5f), 0, j->sw);
        int xe = to_index(floorf(x_hi - 0.5f), -1, j->sw - 1);
        if (yb > ye || xb > xe)
            continue;
        float dx = bx - ax, dy = by - ay, dd = dx * dx + dy * dy;
        float inv = dd > 0 ? 1.0f / dd : 0.0f, len = sqrtf(dd), dz = bz - az;
        const float *col = j->colors + 4 * l->part;
        if ((long long)(ye - yb + 1) * (xe - xb + 1) <= 64) {
            /* small: every sample of the box tested against the distance */
            for (int y = yb; y <= ye; y++) {
                float py = (float)y + 0.5f - ay;
                for (int x = xb; x <= xe; x++) {
                    float px = (float)x + 0.5f - ax;
                    float t = (px * dx + py * dy) * inv;
                    t = t < 0.0f ? 0.0f : t > 1.0f ? 1.0f : t;
                    float ex = px - t * dx, ey = py - t * dy;
                    if (ex * ex + ey * ey > r2)
                        continue;
                    size_t q = (size_t)y * (size_t)j->sw + (size_t)x;
                    float z = az + t * dz;
                    if (z < j->sdepth[q]) {
                        j->sdepth[q] = z;
                        memcpy(j->scolor + 3 * q, col, 3 * sizeof(float));
                    }
                }
            }
            continue;
        }
        for (int y = yb; y <= ye; y++) {
            float py = (float)y + 0.5f - ay;
            float lo, hi;
            if (!row_span(py, dx, dy, dd, len, r2, &lo, &hi))
                continue;
            int x0 = to_index(ceilf(ax + lo - 0.5f), xb, xe + 1);
            int x1 = to_index(floorf(ax + hi - 0.5f), xb - 1, xe);
            float t = (((float)x0 + 0.5f - ax) * dx + py * dy) * inv, dt = dx * inv;
            float *zs = j->sdepth + (size_t)y * (size_t)j->sw;
            for (int x = x0; x <= x1; x++, t += dt) {
                float tc = t < 0.0f ? 0.0f : t > 1.0f ? 1.0f : t;
                float z = az + tc * dz;
                if (z < zs[x]) {
                    zs[x] = z;
                    memcpy(j->scolor + 3 * ((size_t)y * (size_t)j->sw + (size_t)x), col,
                           3 * sizeof(float));
                }
            }
        }
    }
}

/* The band of sample row y. */
static int band_of(const render_job *j, int y)
{
    int b = (int)((long long)y * j->line_bands / j->sh);
    while (b + 1 < j->line_bands && (long long)j->sh * (b + 1) / j->line_bands <= y)
        b++;
    while (b > 0 && (long long)j->sh * b / j->line_bands > y)
        b--;
    return b;
}

/* Sorts the kept lines into the bands of rows they touch (a counting sort, stable: each band
 * keeps the scene order), so that each band reads only its own lines. */
static cbm_status bin_lines(cbm_context *ctx, render_job *j, size_t **first, uint32_t **lines,
                            size_t *nentries)
{
    const cbm_scene *s = j->scene;
    const cbm_scene_line *ln = cbm_scene_lines(s);
    const cbm_part *parts = cbm_scene_parts(s);
    size_t nl = cbm_scene_line_count(s), nb = (size_t)j->line_bands;
    line_xform tf = line_transform(j);
    size_t *f = cbm__calloc(ctx, nb + 1, sizeof *f);
    if (!f)
        return CBM_E_NOMEM;
    for (int pass = 0; pass < 2; pass++) {
        size_t *pos = f;
        if (pass == 1) {
            size_t total = 0;
            for (size_t b = 0; b < nb; b++) {
                size_t c = f[b];
                f[b] = total;
                total += c;
            }
            f[nb] = total;
            *nentries = total;
            *lines = cbm__alloc(ctx, (total ? total : 1) * sizeof **lines);
            if (!*lines) {
                cbm__free(ctx, f, (nb + 1) * sizeof *f);
                return CBM_E_NOMEM;
            }
            pos = cbm__alloc(ctx, (nb + 1) * sizeof *pos);
            if (!pos) {
                cbm__free(ctx, *lines, (total ? total : 1) * sizeof **lines);
                cbm__free(ctx, f, (nb + 1) * sizeof *f);
                return CBM_E_NOMEM;
            }
            memcpy(pos, f, (nb + 1) * sizeof *pos);
        }
        for (size_t i = 0; i < nl; i++) {
            float ay, by, r;
            if (!line_rows(&tf, &ln[i], j->ss, &ay, &by, &r) ||
                !cbm__part_kept(&parts[ln[i].part], j->o))
                continue;
            float y_lo = (ay < by ? ay : by) - r, y_hi = (ay < by ? by : ay) + r;
            if (!(y_hi >= 0.0f && y_lo <= (float)j->sh))
                continue;
            int y0 = to_index(y_lo, 0, j->sh - 1), y1 = to_index(y_hi, 0, j->sh - 1);
            for (int b = band_of(j, y0), e = band_of(j, y1); b <= e; b++) {
                if (pass == 0)
                    f[b]++;
                else
                    (*lines)[pos[b]++] = (uint32_t)i;
            }
        }
        if (pass == 1)
            cbm__free(ctx, pos, (nb + 1) * sizeof *pos);
    }
    *first = f;
    return CBM_OK;
}

static void *draw_lines(void *arg)
{
    render_job *j = arg;
    for (;;) {
        int b = atomic_fetch_add(&j->next_band, 1);
        if (b >= j->line_bands)
            break;
        draw_lines_band(j, b);
    }
    return NULL;
}

/* Average of each pixel's samples into accum (linear, premultiplied by coverage). */
static void resolve_samples(render_job *j)
{
    int n = j->ss;
    float inv = 1.0f / (float)(n * n);
    for (int y = 0; y < j->height; y++)
        for (int x = 0; x < j->width; x++) {
            float acc[4] = {0, 0, 0, 0};
            for (int sy = 0; sy < n; sy++)
                for (int sx = 0; sx < n; sx++) {
                    size_t q = (size_t)(y * n + sy) * (size_t)j->sw + (size_t)(x * n + sx);
                    if (!(j->sdepth[q] < INFINITY))
                        continue;
                    for (int k = 0; k < 3; k++)
                        acc[k] += j->scolor[3 * q + (size_t)k];
                    acc[3] += 1.0f;
                }
            float *a = j->accum + 4 * ((size_t)y * (size_t)j->width + (size_t)x);
            for (int k = 0; k < 4; k++)
                a[k] = acc[k] * inv;
        }
}

/* Runs fn on nthreads threads (the caller's included). */
static void run_threads(void *(*fn)(void *), render_job *j, int nthreads)
{
    pthread_t th[MAX_THREADS];
    int started = 0;
    for (int k = 1; k < nthreads; k++) {
        if (pthread_create(&th[started], NULL, fn, j) != 0)
            break;
        started++;
    }
    fn(j);
    for (int k = 0; k < started; k++)
        pthread_join(th[k], NULL);
}

static void fill_rect(cbm_image *img, int x0, int y0, int x1, int y1, const uint8_t rgb[3])
{
    for (int y = y0 < 0 ? 0 : y0; y < y1 && y < img->height; y++)
        for (int x = x0 < 0 ? 0 : x0; x < x1 && x < img->width; x++) {
            uint8_t *q = img->rgba + 4 * ((size_t)y * (size_t)img->width + (size_t)x);
            q[0] = rgb[0];
            q[1] = rgb[1];
            q[2] = rgb[2];
            q[3] = 255;
        }
}

static void format_value(double v, char *buf, size_t n)
{
    double a = fabs(v);
    if (a != 0 && (a < 1e-2 || a >= 1e5))
        snprintf(buf, n, "%.2e", v);
    else
        snprintf(buf, n, "%.3g", v);
}

static cbm_status draw_legend(cbm_image *img, const cbm_scene *s, const cbm_write_options *o,
                              int x0, double lo, double hi)
{
    const float *bg = o->background;
    double lum = 0.2126 * bg[0] + 0.7152 * bg[1] + 0.0722 * bg[2];
    uint8_t ink[3] = {20, 20, 20};
    if (o->background[3] > 0.5f && lum < 0.3)
        ink[0] = ink[1] = ink[2] = 235;
    int W = img->width, H = img->height;
    int px = H >= 600 ? 2 : 1;
    double fs = 10.0 * px; /* capitals 7.3 px high per px, as the 5x7 font's were 7 */
    cbm_status st = cbm__font_draw(img, W - 6 * px, 13 * px, fs, CBM__TEXT_RIGHT,
                                   cbm__color_title(o->color_by), ink);
    int bx = x0 + (W - x0) / 6, bw = (W - x0) / 5;
    int top = H / 5, bot = H - H / 5;
    char lab[32];
    if (o->color_by == CBM_COLOR_ORDER) {
        int maxo = cbm__legend_max_order(s);
        int step = (bot - top) / (maxo + 1);
        if (step > 12 * px * 2)
            step = 12 * px * 2;
        for (int k = 0; k <= maxo; k++) {
            float c[3];
            cbm__colormap(CBM_COLOR_ORDER, k, c);
            uint8_t rgb[3] = {cbm__srgb8(c[0]), cbm__srgb8(c[1]), cbm__srgb8(c[2])};
            int y = top + k * step;
            fill_rect(img, bx, y, bx + bw, y + step - 2 * px, rgb);
            snprintf(lab, sizeof lab, "%d", k);
            int ty = y + (step - 2 * px + 7 * px) / 2; /* the label's baseline, whole pixels */
            if (st == CBM_OK)
                st = cbm__font_draw(img, bx + bw + 4 * px, ty, fs, CBM__TEXT_LEFT, lab, ink);
        }
        return st;
    }
    for (int y = top; y < bot; y++) {
        double t = 1.0 - (double)(y - top) / (double)(bot - top - 1);
        float c[3];
        cbm__colormap(o->color_by, t, c);
        uint8_t rgb[3] = {cbm__srgb8(c[0]), cbm__srgb8(c[1]), cbm__srgb8(c[2])};
        fill_rect(img, bx, y, bx + bw, y + 1, rgb);
    }
    for (int k = 0; k <= 4; k++) {
        double v = hi - (hi - lo) * k / 4.0;
        int y = top + (int)lround((bot - top - 1) * k / 4.0);
        fill_rect(img, bx + bw, y, bx + bw + 3 * px, y + px, ink);
        format_value(v, lab, sizeof lab);
        if (st == CBM_OK)
            st = cbm__font_draw(img, bx + bw + 5 * px, y + 4 * px, fs, CBM__TEXT_LEFT, lab, ink);
    }
    return st;
}

static int default_threads(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n > MAX_THREADS ? MAX_THREADS : (int)n;
}

cbm_status cbm_render(cbm_context *ctx, const cbm_scene *s, const cbm_write_options *opts,
                      cbm_image **out)
{
    if (!ctx || !s || !out)
        return CBM_E_INVALID;
    *out = NULL;
    cbm_write_options def;
    const cbm_write_options *o = cbm__opts(opts, &def);
    if (o->supersample < 1 || o->supersample > 4 || o->ao_samples < 0 || o->ao_samples > 256 ||
        o->threads < 0)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "render options: supersample must be 1..4, ao_samples 0..256");
    cbm_image *img;
    CBM_TRY(cbm__image_create(ctx, o->width, o->height, &img));
    int W = img->width, H = img->height;
    bool legend = o->legend && o->color_by != CBM_COLOR_MATERIAL && o->color_by < CBM_COLOR_COUNT;
    int legend_w = legend ? (W / 6 > 70 ? W / 6 : 70) : 0;
    if (legend_w > W / 2)
        legend_w = 0, legend = false;

    render_job j;
    memset(&j, 0, sizeof j);
    j.scene = s;
    j.o = o;
    j.width = W;
    j.height = H;
    size_t np = cbm_scene_part_count(s), nt = cbm_scene_triangle_count(s);
    size_t nl = cbm_scene_line_count(s);
    size_t pix = (size_t)W * (size_t)H, nsamp = 0;
    float *colors = NULL;
    uint32_t *prim = NULL;
    double lo = 0, hi = 1;
    cbm_status st = cbm__part_colors(ctx, s, o, &colors, &lo, &hi);
    if (st != CBM_OK) {
        cbm_image_destroy(img);
        return st;
    }
    j.colors = colors;
    prim = cbm__alloc(ctx, (nt ? nt : 1) * sizeof *prim);
    j.accum = cbm__calloc(ctx, pix, 4 * sizeof(float));
    RTCDevice dev = NULL;
    RTCScene rs = NULL;
    cbm__rtc_watch watch;
    if (!prim || !j.accum) {
        st = CBM_E_NOMEM;
        goto done;
    }
    j.prim_tri = prim;
    const cbm_part *parts = cbm_scene_parts(s);
    const uint32_t *tp = cbm_scene_triangle_parts(s), *tri = cbm_scene_triangles(s);
    size_t kept = 0, lines_kept = 0;
    bool has_ground = false;
    for (size_t t = 0; t < nt; t++) {
        const cbm_part *p = &parts[tp[t]];
        if (!cbm__part_kept(p, o))
            continue;
        has_ground |= p->organ == CBM_ORGAN_GROUND;
        prim[kept++] = (uint32_t)t;
    }
    for (size_t i = 0; i < nl; i++)
        lines_kept += cbm__part_kept(&parts[cbm_scene_lines(s)[i].part], o);
    /* samples per pixel side: the options', at least 3 for a picture of lines alone (no rays
     * to pay for, and 10 levels of coverage on their edges) */
    j.ss = o->supersample;
    if (lines_kept > 0 && kept == 0 && j.ss < LINE_SAMPLES)
        j.ss = LINE_SAMPLES;
    int spp = j.ss * j.ss;
    j.ao_rays = o->ao_samples == 0 ? 0 : (o->ao_samples + spp - 1) / spp;
    bool fitted =
        cbm__camera_fit(&j.cam, s, o, W - legend_w, H, 0.5 * (W - legend_w), 0.5 * H, 0.9);
    int nthreads = o->threads ? o->threads : default_threads();
    if (nthreads > MAX_THREADS)
        nthreads = MAX_THREADS;
    cbm_vec3 blo = v3(0, 0, 0), bhi = v3(0, 0, 0);
    bool bounded = kept > 0 && cbm_scene_bounds(s, &blo, &bhi);
    /* the plant's size, for the ground, the offsets and the occlusion distance */
    double size = bounded ? v3_norm(v3_sub(bhi, blo)) : fitted ? (W + H) / j.cam.scale : 1.0;
    if (!(size > 0))
        size = 1.0;
    j.eps = 1e-5 * size + 1e-7;
    if (fitted && lines_kept > 0) {
        j.sw = W * j.ss;
        j.sh = H * j.ss;
        nsamp = (size_t)j.sw * (size_t)j.sh;
        j.sdepth = cbm__alloc(ctx, nsamp * sizeof *j.sdepth);
        j.scolor = cbm__alloc(ctx, nsamp * 3 * sizeof *j.scolor);
        if (!j.sdepth || !j.scolor) {
            st = CBM_E_NOMEM;
            goto done;
        }
        for (size_t q = 0; q < nsamp; q++)
            j.sdepth[q] = INFINITY;
    }
    if (fitted && kept > 0 && bounded) {
        if ((st = cbm__rtc_device(ctx, nthreads, "renderer", &watch, &dev)) != CBM_OK)
            goto done;
        rs = cbm__rtc.rtcNewScene(dev);
        RTCGeometry g = cbm__rtc.rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
        /* positions straight from the scene's vertices (stride 24 bytes; the 16-byte reads of
         * the last position stay inside its vertex) */
        cbm__rtc.rtcSetSharedGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                            cbm_scene_vertices(s), 0, sizeof(cbm_scene_vertex),
                                            cbm_scene_vertex_count(s));
        unsigned *ib = cbm__rtc.rtcSetNewGeometryBuffer(
            g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), kept);
        if (ib)
            for (size_t k = 0; k < kept; k++)
                for (int q = 0; q < 3; q++)
                    ib[3 * k + (size_t)q] = tri[3 * (size_t)prim[k] + (size_t)q];
        cbm__rtc.rtcCommitGeometry(g);
        cbm__rtc.rtcAttachGeometryByID(rs, g, 0);
        cbm__rtc.rtcReleaseGeometry(g);
        if (o->ground && !has_ground) {
            cbm_vec3 c = v3_scale(v3_add(blo, bhi), 0.5);
            double half = fmax(bhi.x - blo.x, bhi.z - blo.z);
            half = 1.5 * fmax(half, 0.6 * (bhi.y - blo.y));
            if (!(half > 0))
                half = 1.0;
            RTCGeometry gg = cbm__rtc.rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_TRIANGLE);
            float *vb = cbm__rtc.rtcSetNewGeometryBuffer(gg, RTC_BUFFER_TYPE_VERTEX, 0,
                                                         RTC_FORMAT_FLOAT3, 3 * sizeof(float), 4);
            unsigned *gi = cbm__rtc.rtcSetNewGeometryBuffer(
                gg, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), 2);
            if (vb && gi) {
                const double sx[4] = {-1, 1, 1, -1}, sz[4] = {-1, -1, 1, 1};
                for (int k = 0; k < 4; k++) {
                    vb[3 * k] = (float)(c.x + sx[k] * half);
                    vb[3 * k + 1] = (float)blo.y;
                    vb[3 * k + 2] = (float)(c.z + sz[k] * half);
                }
                const unsigned q[6] = {0, 2, 1, 0, 3, 2};
                memcpy(gi, q, sizeof q);
            }
            cbm__rtc.rtcCommitGeometry(gg);
            cbm__rtc.rtcAttachGeometryByID(rs, gg, 1);
            cbm__rtc.rtcReleaseGeometry(gg);
            size += 2.0 * half;
        }
        cbm__rtc.rtcCommitScene(rs);
        if ((st = cbm__rtc_status(ctx, dev, "renderer", "building the ray-casting scene")) !=
            CBM_OK)
            goto done;
        j.rs = rs;
        j.back = 2.0 * size + 1.0;
        j.eps = 1e-5 * size + 1e-7;
        j.ao_dist = 0.2 * v3_norm(v3_sub(bhi, blo));
        j.sun = v3_normalize(v3_add(v3_add(v3_scale(j.cam.up, 0.85), v3_scale(j.cam.right, -0.45)),
                                    v3_scale(j.cam.dir, -0.55)));
        j.ground_rgb[0] = 0.50f;
        j.ground_rgb[1] = 0.48f;
        j.ground_rgb[2] = 0.40f;
        atomic_init(&j.next_row, 0);
        run_threads(render_rows, &j, nthreads);
    }
    if (j.sdepth) {
        /* bands of at least 32 sample rows, 8 per thread, taken in turn by the threads */
        j.line_bands = j.sh / 32 < 8 * nthreads ? j.sh / 32 : 8 * nthreads;
        if (j.line_bands < 1)
            j.line_bands = 1;
        size_t *first = NULL, nentries = 0;
        uint32_t *lines = NULL;
        if ((st = bin_lines(ctx, &j, &first, &lines, &nentries)) != CBM_OK)
            goto done;
        j.band_first = first;
        j.band_lines = lines;
        atomic_init(&j.next_band, 0);
        run_threads(draw_lines, &j, nthreads < j.line_bands ? nthreads : j.line_bands);
        cbm__free(ctx, first, ((size_t)j.line_bands + 1) * sizeof *first);
        cbm__free(ctx, lines, (nentries ? nentries : 1) * sizeof *lines);
        resolve_samples(&j);
    }
    /* compose over the background, linear -> sRGB */
    for (size_t i = 0; i < pix; i++) {
        const float *a = j.accum + 4 * i;
        float cov = a[3];
        uint8_t *q = img->rgba + 4 * i;
        float ba = o->background[3];
        float outa = cov + ba * (1.0f - cov);
        for (int k = 0; k < 3; k++) {
            float c = a[k] + o->background[k] * ba * (1.0f - cov);
            q[k] = cbm__srgb8(outa > 0 ? c / outa : 0.0);
        }
        q[3] = (uint8_t)lroundf(fminf(fmaxf(outa, 0.0f), 1.0f) * 255.0f);
    }
    if (legend && (st = cbm__cairo_load(ctx, "renderer")) == CBM_OK)
        st = draw_legend(img, s, o, W - legend_w, lo, hi);
done:
    if (rs)
        cbm__rtc.rtcReleaseScene(rs);
    if (dev)
        cbm__rtc.rtcReleaseDevice(dev);
    cbm__free(ctx, colors, 4 * (np ? np : 1) * sizeof *colors);
    cbm__free(ctx, prim, (nt ? nt : 1) * sizeof *prim);
    cbm__free(ctx, j.accum, pix * 4 * sizeof(float));
    cbm__free(ctx, j.sdepth, nsamp * sizeof *j.sdepth);
    cbm__free(ctx, j.scolor, nsamp * 3 * sizeof *j.scolor);
    if (st != CBM_OK) {
        cbm_image_destroy(img);
        return st;
    }
    *out = img;
    return CBM_OK;
}

cbm_status cbm_write_png(cbm_context *ctx, const cbm_scene *s, const char *path,
                         const cbm_write_options *opts)
{
    if (!ctx || !s || !path)
        return CBM_E_INVALID;
    cbm_image *img;
    CBM_TRY(cbm_render(ctx, s, opts, &img));
    cbm_status st = cbm_image_write_png(ctx, img, path);
    cbm_image_destroy(img);
    return st;
}
