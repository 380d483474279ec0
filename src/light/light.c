/* Per-leaf light interception by ray casting over every plant of a scene (docs/light.md).
 *
 * The leaves (one Embree quad each) and the occluder triangles form one Embree scene;
 * Embree's quads stop rays from either side, so both faces of a leaf shade. A leaf's light
 * is the integral over its area A of Σ_k E_k c_k(n, d_k) V(x, d_k), with the sky's sources
 * (d_k, E_k) of src/light/sky.c, c = |n·d| for a two-sided leaf or max(0, n·d) for the upper
 * face alone, and V(x, d) = 1 when the ray from x towards d reaches the sky. The integral is
 * taken over samples² points of the leaf's bilinear parametrisation x(u, v), one in each cell of
 * a samples x samples grid in (u, v) at a jittered place, each weighted by its Jacobian
 * |x_u × x_v| (exact for any planar quad and for a triangle, p3 = p2). An unshaded leaf
 * therefore gets A Σ_k E_k c_k to rounding, for any tilt and any sampling.
 *
 * Self-intersection: a ray starts on the face it leaves through, moved off the leaf's plane by
 * eps = 4e-6 x the largest coordinate of the scene + 1e-9 m along ±n (about 60 float ulps), so it
 * cannot hit its own planar leaf and still sees a leaf 0.1 mm above a leaf at 10 m.
 *
 * Where light enters (Oberländer 2020, §5.5):
 *   UOC, SOC, sun, unbounded dome: from infinity; a ray is one occlusion query to infinity.
 *   bounded dome (dome_radius > 0): each light is a beam of that radius around the line through
 *     the focus, so points away from the focus lose the lights whose beams miss them (the
 *     thesis's stated defect, reproduced on purpose).
 *   field, open edges: the lights fill the rectangle field_min..field_max at field_height; a
 *     point gets a light when its ray crosses that height inside the rectangle, and the ray
 *     is cast up to there.
 *   periodic edges (any sky): the rectangle is the tile of an endless stand. The scene holds
 *     each triangle translated by whole tiles wherever the copy overlaps the tile; a ray starts
 *     from its point folded into the tile and, where it leaves through a side, goes on from the
 *     opposite side, up to field_height, above which there is nothing. A ray that crosses more
 *     than MAX_WRAPS sides counts as stopped (it runs nearly level through an endless canopy).
 *
 * Work order: the leaves in Morton order of their centres, in batches of up to 64 sample points
 * (more when one leaf has more); a batch's rays go to Embree as one stream (rtcOccluded1M),
 * source by source, so the parallel rays of neighbouring points follow one another through the
 * same BVH nodes (1.2x fewer CPU seconds at 10^5 leaves than point by point; the same stream
 * flagged coherent, which makes Embree trace it in packets, was 2.3x slower: the rays of a
 * stand's sample points are too scattered for packets). Each point's light is then summed over
 * the sources in their order, so the result is that of the ray-by-ray loop, bit for bit.
 * The periodic stand, whose rays go segment by segment, casts ray by ray.
 *
 * The leaves are shared among threads in chunks through an atomic counter; a leaf's result
 * depends on its index, the seed and the scene alone, so it does not depend on the thread
 * count. Embree's allocations are watched by its memory monitor against the context's limit. */
#define _POSIX_C_SOURCE 200809L
#include "light_internal.h"

#include "../core/vecmath.h"

#include "../geom/embree_device.h"

#include <embree3/rtcore.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include <unistd.h>

#define MAX_THREADS 64
#define MAX_WRAPS   4096
#define CHUNK       32 /* leaves per work item */
#define BATCH       64 /* sample points per ray stream (at least one leaf's samples²) */
/* a thread's scratch for a batch of P points (P >= the points of one leaf): P x nsrc rays (Embree's
 * rays are 16-byte aligned; the context's allocator need not be: one block more and the start
 * rounded up), as many ray tags and visibility flags, the cosines of up to P leaves and the
 * points' places and weights */
#define SCRATCH(p, n)                                                                              \
    ((((p) * (n) * (sizeof(struct RTCRay) + sizeof(double) + sizeof(uint32_t) + 1) +               \
       (p) * (sizeof(batch_leaf) + sizeof(batch_point))) +                                         \
      15) &                                                                                        \
     ~(size_t)15)

typedef enum entry_mode { ENTRY_INFINITY, ENTRY_DOME, ENTRY_FIELD, ENTRY_PERIODIC } entry_mode;

typedef struct light_job {
    const cbm_light_def *def;
    const cbm_light_source *src;
    size_t nsrc;
    const cbm_light_leaf *leaves;
    size_t n;
    const uint32_t *order; /* leaves in Morton order of their centres */
    double *absorbed;
    double scale; /* 1 / max_light_square */
    RTCScene rs;
    double eps;
    entry_mode mode;
    double x0, x1, z0, z1, top; /* field rectangle and height */
    unsigned char *scratch_mem; /* as allocated */
    unsigned char *scratch;     /* 16-byte aligned; per thread SCRATCH(points, nsrc) bytes */
    size_t points;              /* sample points per batch */
    atomic_size_t next;
    atomic_size_t rays;
    atomic_int thread_id;
} light_job;

cbm_light_def cbm_light_def_default(void)
{
    cbm_light_def d;
    memset(&d, 0, sizeof d);
    d.sky = CBM_SKY_SOC;
    d.rings = 6;
    d.azimuths = 12;
    d.direct_fraction = 0.0;
    d.sun = v3(0.3, 0.8, 0.2);
    d.focus = v3(0, 0, 0);
    d.dome_radius = 0.0;
    d.field_height = 0.0;
    d.edge = CBM_LIGHT_EDGE_OPEN;
    d.samples = 1;
    d.two_sided = true;
    d.max_light_square = 0.0;
    d.threads = 0;
    d.seed = 1;
    return d;
}

static cbm_status check_def(cbm_context *ctx, const cbm_light_def *d)
{
    if ((int)d->sky < CBM_SKY_DOME || (int)d->sky > CBM_SKY_SOC)
        return cbm__fail(ctx, CBM_E_INVALID, "light: sky must be dome, field, uoc or soc");
    if (d->rings < 1 || d->rings > 90 || d->azimuths < 1 || d->azimuths > 360)
        return cbm__fail(ctx, CBM_E_INVALID, "light: rings must be 1..90 and azimuths 1..360");
    if (d->samples < 1 || d->samples > 16)
        return cbm__fail(ctx, CBM_E_INVALID, "light: samples must be 1..16");
    if (!(d->direct_fraction >= 0.0 && d->direct_fraction <= 1.0))
        return cbm__fail(ctx, CBM_E_INVALID, "light: direct_fraction must be in [0, 1]");
    if (d->direct_fraction > 0.0 &&
        !(v3_isfinite(d->sun) && d->sun.y > 1e-6 * v3_norm(d->sun) && d->sun.y > 0))
        return cbm__fail(ctx, CBM_E_INVALID, "light: the sun must be above the horizon (y > 0)");
    if (!(d->dome_radius >= 0.0 && isfinite(d->dome_radius)) || !v3_isfinite(d->focus))
        return cbm__fail(ctx, CBM_E_INVALID, "light: dome_radius must be >= 0, focus finite");
    for (int a = 0; a < 2; a++)
        if (!(isfinite(d->field_min[a]) && isfinite(d->field_max[a]) &&
              d->field_min[a] <= d->field_max[a]))
            return cbm__fail(ctx, CBM_E_INVALID,
                             "light: the field rectangle needs finite field_min <= field_max");
    if (!isfinite(d->field_height))
        return cbm__fail(ctx, CBM_E_INVALID, "light: field_height must be finite");
    if (d->edge != CBM_LIGHT_EDGE_OPEN && d->edge != CBM_LIGHT_EDGE_PERIODIC)
        return cbm__fail(ctx, CBM_E_INVALID, "light: edge must be open or periodic");
    if (!(d->max_light_square >= 0.0 && isfinite(d->max_light_square)))
        return cbm__fail(ctx, CBM_E_INVALID, "light: max_light_square must be >= 0");
    if (d->threads < 0)
        return cbm__fail(ctx, CBM_E_INVALID, "light: threads must be >= 0");
    return CBM_OK;
}

cbm_status cbm_light_sources(cbm_context *ctx, const cbm_light_def *def, cbm_light_source **out,
                             size_t *n)
{
    if (!ctx || !def || !out || !n)
        return CBM_E_INVALID;
    *out = NULL;
    *n = 0;
    CBM_TRY(check_def(ctx, def));
    size_t m = cbm__light_source_count(def);
    cbm_light_source *s = cbm__calloc(ctx, m, sizeof *s);
    if (!s)
        return CBM_E_NOMEM;
    cbm__light_fill_sources(def, s);
    *out = s;
    *n = m;
    return CBM_OK;
}

void cbm_light_sources_free(cbm_context *ctx, cbm_light_source *s, size_t n)
{
    if (ctx && s)
        cbm__free(ctx, s, n * sizeof *s);
}

/* ---- ray casting ---- */

static bool occluded(RTCScene rs, cbm_vec3 o, cbm_vec3 d, double tfar)
{
    struct RTCIntersectContext ic;
    rtcInitIntersectContext(&ic);
    struct RTCRay r;
    r.org_x = (float)o.x;
    r.org_y = (float)o.y;
    r.org_z = (float)o.z;
    r.dir_x = (float)d.x;
    r.dir_y = (float)d.y;
    r.dir_z = (float)d.z;
    r.tnear = 0.0f;
    r.tfar = (float)tfar;
    r.time = 0.0f;
    r.mask = 0xFFFFFFFFu;
    r.id = 0;
    r.flags = 0;
    cbm__rtc.rtcOccluded1(rs, &ic, &r);
    return r.tfar < 0.0f;
}

static double fold(double v, double lo, double len)
{
    double f = v - len * floor((v - lo) / len);
    return f >= lo + len ? lo : f;
}

/* Whether light from d reaches o in the periodic stand; *rays counts the segments cast. */
static bool lit_periodic(const light_job *j, cbm_vec3 o, cbm_vec3 d, size_t *rays)
{
    if (o.y >= j->top) {
        ++*rays;
        return !occluded(j->rs, o, d, INFINITY);
    }
    double lx = j->x1 - j->x0, lz = j->z1 - j->z0;
    o.x = fold(o.x, j->x0, lx);
    o.z = fold(o.z, j->z0, lz);
    for (int w = 0; w <= MAX_WRAPS; w++) {
        double tt = (j->top - o.y) / d.y;
        double tx = d.x > 0 ? (j->x1 - o.x) / d.x : d.x < 0 ? (j->x0 - o.x) / d.x : INFINITY;
        double tz = d.z > 0 ? (j->z1 - o.z) / d.z : d.z < 0 ? (j->z0 - o.z) / d.z : INFINITY;
        double t = fmax(0.0, fmin(tt, fmin(tx, tz)));
        ++*rays;
        if (occluded(j->rs, o, d, t))
            return false;
        if (t >= tt)
            return true;
        o = v3_madd(o, d, t);
        if (tx <= tz)
            o.x = d.x > 0 ? j->x0 : j->x1;
        else
            o.z = d.z > 0 ? j->z0 : j->z1;
        o.y = fmin(o.y, j->top);
    }
    return false;
}

/* splitmix64 finaliser: decorrelated uniform numbers from a counter */
static double hash01(uint64_t x)
{
    x += 0x9e3779b97f4a7c15ull;
    x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
    x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
    x ^= x >> 31;
    return (double)(x >> 11) * (1.0 / 9007199254740992.0);
}

static cbm_vec3 bilinear(const cbm_vec3 *p, double u, double v, cbm_vec3 *xu, cbm_vec3 *xv)
{
    *xu = v3_add(v3_scale(v3_sub(p[1], p[0]), 1.0 - v), v3_scale(v3_sub(p[2], p[3]), v));
    *xv = v3_add(v3_scale(v3_sub(p[3], p[0]), 1.0 - u), v3_scale(v3_sub(p[2], p[1]), u));
    cbm_vec3 a = v3_add(v3_scale(p[0], (1 - u) * (1 - v)), v3_scale(p[1], u * (1 - v)));
    cbm_vec3 b = v3_add(v3_scale(p[2], u * v), v3_scale(p[3], (1 - u) * v));
    return v3_add(a, b);
}

static void set_ray(struct RTCRay *r, cbm_vec3 o, cbm_vec3 d, double tfar)
{
    r->org_x = (float)o.x;
    r->org_y = (float)o.y;
    r->org_z = (float)o.z;
    r->dir_x = (float)d.x;
    r->dir_y = (float)d.y;
    r->dir_z = (float)d.z;
    r->tnear = 0.0f;
    r->tfar = (float)tfar;
    r->time = 0.0f;
    r->mask = 0xFFFFFFFFu;
    r->id = 0;
    r->flags = 0;
}

/* The light a point x of a leaf of normal n receives in the periodic stand, ray by ray (a ray
 * there is a chain of segments, tile by tile). */
static double point_light(const light_job *j, cbm_vec3 x, cbm_vec3 n, const double *cosk,
                          size_t *rays)
{
    double acc = 0.0;
    for (size_t k = 0; k < j->nsrc; k++) {
        double cs = cosk[k];
        if (cs == 0.0)
            continue;
        cbm_vec3 o = v3_madd(x, n, cs > 0 ? j->eps : -j->eps);
        if (lit_periodic(j, o, j->src[k].dir, rays))
            acc += j->src[k].irradiance * fabs(cs);
    }
    return acc;
}

/* A leaf's normal, one-sided area and the cosines c_k of its face with every source (cosk);
 * false when it gets no light at all (no area, or no source on a face that takes light). */
static bool leaf_setup(const light_job *j, size_t i, double *cosk, cbm_vec3 *n, double *area)
{
    const cbm_light_leaf *lf = &j->leaves[i];
    cbm_vec3 c = v3_cross(v3_sub(lf->p[2], lf->p[0]), v3_sub(lf->p[3], lf->p[1]));
    double len = v3_norm(c);
    if (!(len > 0))
        return false;
    *n = v3_scale(c, 1.0 / len);
    *area = 0.5 * len;
    bool any = false;
    for (size_t k = 0; k < j->nsrc; k++) {
        double cs = v3_dot(*n, j->src[k].dir);
        cosk[k] = j->def->two_sided ? cs : fmax(0.0, cs);
        any |= cosk[k] != 0.0;
    }
    return any;
}

/* Sample point (a, b) of leaf i: its place and Jacobian (the point is skipped when jac <= 0). */
static cbm_vec3 leaf_point(const light_job *j, size_t i, int a, int b, double *jac)
{
    int m = j->def->samples;
    uint64_t base = (j->def->seed * 0x9e3779b97f4a7c15ull) ^ ((uint64_t)i * 0x2545f4914f6cdd1dull);
    uint64_t h = base + 2u * (uint64_t)(a * m + b);
    double u = (a + hash01(h)) / m, v = (b + hash01(h + 1u)) / m;
    cbm_vec3 xu, xv;
    cbm_vec3 x = bilinear(j->leaves[i].p, u, v, &xu, &xv);
    *jac = v3_norm(v3_cross(xu, xv));
    return x;
}

typedef struct batch_point {
    cbm_vec3 x;
    double jac;
    uint32_t leaf; /* its slot in the batch */
} batch_point;

/* The sample points of leaf i with a positive Jacobian, in grid order, into out[0..) (room for
 * samples²), each tagged with the batch slot `slot`; returns their number. Both passes (ray by
 * ray and batched) take their points here, so they see the same points in the same order. */
static size_t leaf_points(const light_job *j, size_t i, uint32_t slot, batch_point *out)
{
    int m = j->def->samples;
    size_t np = 0;
    for (int a = 0; a < m; a++)
        for (int b = 0; b < m; b++) {
            double jac;
            cbm_vec3 x = leaf_point(j, i, a, b, &jac);
            if (!(jac > 0))
                continue;
            out[np].x = x;
            out[np].jac = jac;
            out[np++].leaf = slot;
        }
    return np;
}

/* light of one leaf in the sky's units, ray by ray (the periodic stand) */
static double leaf_light(const light_job *j, size_t i, double *cosk, size_t *rays)
{
    cbm_vec3 n;
    double area;
    if (!leaf_setup(j, i, cosk, &n, &area))
        return 0.0;
    batch_point pt[16 * 16]; /* samples <= 16 (check_def) */
    size_t np = leaf_points(j, i, 0, pt);
    double total = 0.0, wsum = 0.0;
    for (size_t p = 0; p < np; p++) {
        total += pt[p].jac * point_light(j, pt[p].x, n, cosk, rays);
        wsum += pt[p].jac;
    }
    return wsum > 0 ? area * total / wsum : 0.0;
}

/* ---- batches: the rays of many points, source by source, as one coherent stream ---- */

typedef struct batch_leaf {
    cbm_vec3 n;
    double area;
    uint32_t index, first, count; /* the leaf, its first point in the batch and their number */
} batch_leaf;

/* a thread's scratch, carved from SCRATCH(points, nsrc) bytes (16-byte aligned) */
typedef struct scratch {
    struct RTCRay *rays; /* points x nsrc */
    double *cosk;        /* leaves x nsrc (a batch holds at most `points` leaves) */
    batch_leaf *leaf;
    batch_point *pt;
    uint32_t *tag; /* ray q is point tag / nsrc towards source tag % nsrc */
    uint8_t *vis;  /* points x nsrc: the ray reached the sky */
} scratch;

static scratch scratch_of(const light_job *j, unsigned char *mem)
{
    size_t p = j->points, n = j->nsrc;
    scratch w;
    w.rays = (struct RTCRay *)(void *)mem;
    mem += p * n * sizeof *w.rays;
    w.cosk = (double *)(void *)mem;
    mem += p * n * sizeof *w.cosk;
    w.leaf = (batch_leaf *)(void *)mem;
    mem += p * sizeof *w.leaf;
    w.pt = (batch_point *)(void *)mem;
    mem += p * sizeof *w.pt;
    w.tag = (uint32_t *)(void *)mem;
    mem += p * n * sizeof *w.tag;
    w.vis = mem;
    return w;
}

/* Casts the rays of the batch's points (the sources outside, the points inside: neighbouring
 * points' parallel rays one after the other, through the same BVH nodes), then sums each point's
 * light over the sources in their order, as point_light does, so the results are those of the
 * ray-by-ray loop. */
static void flush_batch(const light_job *j, scratch *w, size_t nl, size_t np, size_t *rays)
{
    size_t ns = j->nsrc;
    unsigned m = 0;
    for (size_t k = 0; k < ns; k++) {
        cbm_vec3 d = j->src[k].dir;
        for (size_t p = 0; p < np; p++) {
            const batch_point *q = &w->pt[p];
            double cs = w->cosk[q->leaf * ns + k];
            if (cs == 0.0)
                continue;
            cbm_vec3 o = v3_madd(q->x, w->leaf[q->leaf].n, cs > 0 ? j->eps : -j->eps);
            double tfar = INFINITY;
            if (j->mode == ENTRY_DOME) {
                cbm_vec3 r = v3_sub(o, j->def->focus);
                if (v3_norm(v3_madd(r, d, -v3_dot(r, d))) > j->def->dome_radius)
                    continue;
            } else if (j->mode == ENTRY_FIELD) {
                if (o.y >= j->top)
                    continue;
                tfar = (j->top - o.y) / d.y;
                double qx = o.x + tfar * d.x, qz = o.z + tfar * d.z;
                if (qx < j->x0 || qx > j->x1 || qz < j->z0 || qz > j->z1)
                    continue;
            }
            set_ray(&w->rays[m], o, d, tfar);
            w->tag[m++] = (uint32_t)(p * ns + k);
        }
    }
    memset(w->vis, 0, np * ns);
    if (m > 0) {
        struct RTCIntersectContext ic;
        rtcInitIntersectContext(&ic);
        cbm__rtc.rtcOccluded1M(j->rs, &ic, w->rays, m, sizeof *w->rays);
        *rays += m;
        for (unsigned q = 0; q < m; q++)
            w->vis[w->tag[q]] = !(w->rays[q].tfar < 0.0f);
    }
    for (size_t t = 0; t < nl; t++) {
        const batch_leaf *lf = &w->leaf[t];
        const double *ck = w->cosk + t * ns;
        double total = 0.0, wsum = 0.0;
        for (uint32_t p = lf->first; p < lf->first + lf->count; p++) {
            const uint8_t *v = w->vis + (size_t)p * ns;
            double acc = 0.0;
            for (size_t k = 0; k < ns; k++)
                if (v[k])
                    acc += j->src[k].irradiance * fabs(ck[k]);
            total += w->pt[p].jac * acc;
            wsum += w->pt[p].jac;
        }
        j->absorbed[lf->index] = (wsum > 0 ? lf->area * total / wsum : 0.0) * j->scale;
    }
}

/* The leaves order[first..last) in batches of at most j->points sample points. */
static void run_batches(const light_job *j, scratch *w, size_t first, size_t last, size_t *rays)
{
    int m = j->def->samples;
    size_t per = (size_t)m * (size_t)m, nl = 0, np = 0;
    for (size_t q = first; q < last; q++) {
        if (np + per > j->points) {
            flush_batch(j, w, nl, np, rays);
            nl = np = 0;
        }
        size_t i = j->order[q];
        batch_leaf *lf = &w->leaf[nl];
        if (!leaf_setup(j, i, w->cosk + nl * j->nsrc, &lf->n, &lf->area)) {
            j->absorbed[i] = 0.0 * j->scale;
            continue;
        }
        lf->index = (uint32_t)i;
        lf->first = (uint32_t)np;
        np += leaf_points(j, i, (uint32_t)nl, w->pt + np);
        lf->count = (uint32_t)np - lf->first;
        nl++;
    }
    if (nl > 0)
        flush_batch(j, w, nl, np, rays);
}

static void *work(void *arg)
{
    light_job *j = arg;
    unsigned char *mem =
        j->scratch + (size_t)atomic_fetch_add(&j->thread_id, 1) * SCRATCH(j->points, j->nsrc);
    scratch w = scratch_of(j, mem);
    size_t rays = 0;
    for (;;) {
        size_t first = atomic_fetch_add(&j->next, CHUNK);
        if (first >= j->n)
            break;
        size_t last = first + CHUNK < j->n ? first + CHUNK : j->n;
        if (j->mode != ENTRY_PERIODIC) {
            run_batches(j, &w, first, last, &rays);
            continue;
        }
        for (size_t q = first; q < last; q++) {
            size_t i = j->order[q];
            j->absorbed[i] = leaf_light(j, i, w.cosk, &rays) * j->scale;
        }
    }
    atomic_fetch_add(&j->rays, rays);
    return NULL;
}

static int default_threads(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : n > MAX_THREADS ? MAX_THREADS : (int)n;
}

static double now_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- the order of the work ---- */

/* 3 x 21 bits of a point in the box, interleaved (a Morton code) */
static uint64_t spread(uint64_t v)
{
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffull;
    v = (v | v << 16) & 0x1f0000ff0000ffull;
    v = (v | v << 8) & 0x100f00f00f00f00full;
    v = (v | v << 4) & 0x10c30c30c30c30c3ull;
    v = (v | v << 2) & 0x1249249249249249ull;
    return v;
}

typedef struct keyed {
    uint64_t key;
    uint32_t index;
} keyed;

static int by_key(const void *a, const void *b)
{
    const keyed *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return x->index < y->index ? -1 : x->index > y->index;
}

/* The leaves in Morton order of their centres: neighbouring leaves cast their rays one after
 * the other, through the same parts of the BVH, which stay in the cache. Only the order of the
 * work changes (each result goes to its leaf's index); it keeps the cost per ray nearly flat
 * as the scene grows (docs/performance.md, "Light interception"). */
static uint32_t *morton_order(cbm_context *ctx, const cbm_light_leaf *l, size_t n, cbm_vec3 lo,
                              cbm_vec3 hi)
{
    keyed *k = cbm__calloc(ctx, n ? n : 1, sizeof *k);
    uint32_t *order = cbm__calloc(ctx, n ? n : 1, sizeof *order);
    if (!k || !order) {
        cbm__free(ctx, k, (n ? n : 1) * sizeof *k);
        cbm__free(ctx, order, (n ? n : 1) * sizeof *order);
        return NULL;
    }
    cbm_vec3 ext = v3_sub(hi, lo);
    double s = 2097151.0 / fmax(fmax(ext.x, ext.y), fmax(ext.z, 1e-300));
    for (size_t i = 0; i < n; i++) {
        cbm_vec3 c = v3_scale(v3_add(l[i].p[0], l[i].p[2]), 0.5);
        uint64_t x = (uint64_t)fmin(fmax((c.x - lo.x) * s, 0.0), 2097151.0);
        uint64_t y = (uint64_t)fmin(fmax((c.y - lo.y) * s, 0.0), 2097151.0);
        uint64_t z = (uint64_t)fmin(fmax((c.z - lo.z) * s, 0.0), 2097151.0);
        k[i].key = spread(x) | spread(y) << 1 | spread(z) << 2;
        k[i].index = (uint32_t)i;
    }
    qsort(k, n, sizeof *k, by_key);
    for (size_t i = 0; i < n; i++)
        order[i] = k[i].index;
    cbm__free(ctx, k, (n ? n : 1) * sizeof *k);
    return order;
}

/* ---- the scene ---- */

/* The scene's primitives: every leaf one quad, every occluder triangle a quad whose last two
 * vertices are the same (Embree's quads take that as a triangle). One primitive per leaf rather
 * than two triangles halves the BVH. */
typedef struct prim_src {
    const cbm_light_leaf *leaves;
    size_t n_leaves;
    const cbm_vec3 *occ;
    size_t n_occ;
} prim_src;

static size_t prim_count(const prim_src *t)
{
    return t->n_leaves + t->n_occ;
}

static void prim_get(const prim_src *t, size_t k, cbm_vec3 v[4])
{
    if (k < t->n_leaves) {
        for (int q = 0; q < 4; q++)
            v[q] = t->leaves[k].p[q];
    } else {
        const cbm_vec3 *p = t->occ + 3 * (k - t->n_leaves);
        v[0] = p[0];
        v[1] = p[1];
        v[2] = p[2];
        v[3] = p[2];
    }
}

static void prim_box(const cbm_vec3 v[4], double *x0, double *x1, double *z0, double *z1)
{
    *x0 = *x1 = v[0].x;
    *z0 = *z1 = v[0].z;
    for (int q = 1; q < 4; q++) {
        *x0 = fmin(*x0, v[q].x), *x1 = fmax(*x1, v[q].x);
        *z0 = fmin(*z0, v[q].z), *z1 = fmax(*z1, v[q].z);
    }
}

/* copies of a primitive by whole tiles that overlap [lo, lo + len) in one axis: range of i */
static void copy_range(double tmin, double tmax, double lo, double len, long *i0, long *i1)
{
    *i0 = (long)ceil((lo - tmax) / len);
    *i1 = (long)floor((lo + len - tmin) / len);
    if (*i1 < *i0)
        *i1 = *i0; /* cannot happen for a finite triangle; keep one copy */
}

static cbm_status build_scene(cbm_context *ctx, RTCDevice dev, const light_job *j,
                              const prim_src *t, RTCScene *out)
{
    size_t np = prim_count(t), total = 0;
    double lx = j->x1 - j->x0, lz = j->z1 - j->z0;
    bool periodic = j->mode == ENTRY_PERIODIC;
    for (size_t k = 0; k < np; k++) {
        if (!periodic) {
            total++;
            continue;
        }
        cbm_vec3 v[4];
        double x0, x1, z0, z1;
        prim_get(t, k, v);
        prim_box(v, &x0, &x1, &z0, &z1);
        long a0, a1, b0, b1;
        copy_range(x0, x1, j->x0, lx, &a0, &a1);
        copy_range(z0, z1, j->z0, lz, &b0, &b1);
        total += (size_t)(a1 - a0 + 1) * (size_t)(b1 - b0 + 1);
        if (total > (size_t)1 << 30)
            return cbm__fail(ctx, CBM_E_LIMIT,
                             "light: the periodic tile is too small for the scene's leaves");
    }
    RTCScene rs = cbm__rtc.rtcNewScene(dev);
    if (total > 0) {
        RTCGeometry g = cbm__rtc.rtcNewGeometry(dev, RTC_GEOMETRY_TYPE_QUAD);
        float *vb = cbm__rtc.rtcSetNewGeometryBuffer(
            g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), 4 * total);
        unsigned *ib = cbm__rtc.rtcSetNewGeometryBuffer(
            g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT4, 4 * sizeof(unsigned), total);
        if (vb && ib) {
            size_t m = 0;
            for (size_t k = 0; k < np; k++) {
                cbm_vec3 v[4];
                prim_get(t, k, v);
                long a0 = 0, a1 = 0, b0 = 0, b1 = 0;
                if (periodic) {
                    double x0, x1, z0, z1;
                    prim_box(v, &x0, &x1, &z0, &z1);
                    copy_range(x0, x1, j->x0, lx, &a0, &a1);
                    copy_range(z0, z1, j->z0, lz, &b0, &b1);
                }
                for (long a = a0; a <= a1; a++)
                    for (long b = b0; b <= b1; b++) {
                        for (int q = 0; q < 4; q++) {
                            vb[12 * m + 3 * (size_t)q] = (float)(v[q].x + (double)a * lx);
                            vb[12 * m + 3 * (size_t)q + 1] = (float)v[q].y;
                            vb[12 * m + 3 * (size_t)q + 2] = (float)(v[q].z + (double)b * lz);
                            ib[4 * m + (size_t)q] = (unsigned)(4 * m + (size_t)q);
                        }
                        m++;
                    }
            }
            CBM_ASSERT(m == total);
        }
        cbm__rtc.rtcCommitGeometry(g);
        cbm__rtc.rtcAttachGeometryByID(rs, g, 0);
        cbm__rtc.rtcReleaseGeometry(g);
    }
    cbm__rtc.rtcCommitScene(rs);
    *out = rs;
    return cbm__rtc_status(ctx, dev, "light", "building the light scene");
}

cbm_status cbm_light_intercept(cbm_context *ctx, const cbm_light_def *def,
                               const cbm_light_leaf *leaves, size_t n_leaves,
                               const cbm_vec3 *occluders, size_t n_occluder_triangles,
                               double *absorbed, cbm_light_stats *stats)
{
    if (!ctx || (n_leaves && (!leaves || !absorbed)) || (n_occluder_triangles && !occluders))
        return CBM_E_INVALID;
    double t0 = now_seconds();
    if (stats)
        memset(stats, 0, sizeof *stats);
    cbm_light_def dd = def ? *def : cbm_light_def_default();
    CBM_TRY(check_def(ctx, &dd));
    if (n_leaves > ((size_t)1 << 31) || n_occluder_triangles > ((size_t)1 << 31))
        return cbm__fail(ctx, CBM_E_LIMIT, "light: more than 2^31 leaves or occluders");
    /* the scene's bounds; every corner must be finite */
    cbm_vec3 lo = v3(INFINITY, INFINITY, INFINITY), hi = v3(-INFINITY, -INFINITY, -INFINITY);
    for (size_t i = 0; i < n_leaves; i++)
        for (int q = 0; q < 4; q++) {
            cbm_vec3 p = leaves[i].p[q];
            if (!v3_isfinite(p))
                return cbm__fail(ctx, CBM_E_INVALID, "light: leaf %zu has a non-finite corner", i);
            lo = v3(fmin(lo.x, p.x), fmin(lo.y, p.y), fmin(lo.z, p.z));
            hi = v3(fmax(hi.x, p.x), fmax(hi.y, p.y), fmax(hi.z, p.z));
        }
    for (size_t i = 0; i < 3 * n_occluder_triangles; i++) {
        cbm_vec3 p = occluders[i];
        if (!v3_isfinite(p))
            return cbm__fail(ctx, CBM_E_INVALID,
                             "light: occluder triangle %zu has a non-finite vertex", i / 3);
        lo = v3(fmin(lo.x, p.x), fmin(lo.y, p.y), fmin(lo.z, p.z));
        hi = v3(fmax(hi.x, p.x), fmax(hi.y, p.y), fmax(hi.z, p.z));
    }
    size_t nsrc = cbm__light_source_count(&dd);
    cbm_light_source *src = cbm__calloc(ctx, nsrc, sizeof *src);
    if (!src)
        return CBM_E_NOMEM;
    cbm__light_fill_sources(&dd, src);

    light_job j;
    memset(&j, 0, sizeof j);
    j.def = &dd;
    j.src = src;
    j.nsrc = nsrc;
    j.leaves = leaves;
    j.n = n_leaves;
    j.absorbed = absorbed;
    j.scale = dd.max_light_square > 0 ? 1.0 / dd.max_light_square : 1.0;
    bool empty = n_leaves == 0 && n_occluder_triangles == 0;
    double big = empty ? 0.0 : fmax(v3_maxabs(lo), v3_maxabs(hi));
    j.eps = 4e-6 * big + 1e-9;
    double top = empty ? 0 : hi.y + 2.0 * j.eps;
    j.top = dd.field_height > top ? dd.field_height : top;
    /* without a rectangle: the scene's, widened for an open field so that every point of the
     * scene gets every light (no edge), kept tight as the tile of a periodic stand */
    bool rect = dd.field_min[0] < dd.field_max[0] && dd.field_min[1] < dd.field_max[1];
    double margin = 0.0;
    if (!rect && !empty && dd.edge == CBM_LIGHT_EDGE_OPEN)
        for (size_t k = 0; k < nsrc; k++)
            margin = fmax(margin,
                          (j.top - lo.y) * hypot(src[k].dir.x, src[k].dir.z) / src[k].dir.y * 1.01);
    j.x0 = rect ? dd.field_min[0] : empty ? 0 : lo.x - margin;
    j.x1 = rect ? dd.field_max[0] : empty ? 0 : hi.x + margin;
    j.z0 = rect ? dd.field_min[1] : empty ? 0 : lo.z - margin;
    j.z1 = rect ? dd.field_max[1] : empty ? 0 : hi.z + margin;
    if (dd.edge == CBM_LIGHT_EDGE_PERIODIC)
        j.mode = ENTRY_PERIODIC;
    else if (dd.sky == CBM_SKY_FIELD)
        j.mode = ENTRY_FIELD;
    else if (dd.sky == CBM_SKY_DOME && dd.dome_radius > 0)
        j.mode = ENTRY_DOME;
    else
        j.mode = ENTRY_INFINITY;
    cbm_status st = CBM_OK;
    if (j.mode == ENTRY_PERIODIC && n_leaves > 0 && !(j.x1 > j.x0 && j.z1 > j.z0)) {
        cbm__free(ctx, src, nsrc * sizeof *src);
        return cbm__fail(ctx, CBM_E_INVALID,
                         "light: periodic edges need a field rectangle of positive size");
    }
    int nthreads = dd.threads ? dd.threads : default_threads();
    if (nthreads > MAX_THREADS)
        nthreads = MAX_THREADS;
    size_t chunks = (n_leaves + CHUNK - 1) / CHUNK;
    if ((size_t)nthreads > chunks)
        nthreads = chunks ? (int)chunks : 1;
    RTCDevice dev = NULL;
    RTCScene rs = NULL;
    uint32_t *order = NULL;
    cbm__rtc_watch watch;
    if (n_leaves > 0) {
        if ((st = cbm__rtc_device(ctx, nthreads, "light", &watch, &dev)) != CBM_OK)
            goto done;
        prim_src ts = {leaves, n_leaves, occluders, n_occluder_triangles};
        if ((st = build_scene(ctx, dev, &j, &ts, &rs)) != CBM_OK)
            goto done;
        j.rs = rs;
        order = morton_order(ctx, leaves, n_leaves, lo, hi);
        j.order = order;
        if (!order) {
            st = CBM_E_NOMEM;
            goto done;
        }
        j.points = (size_t)dd.samples * (size_t)dd.samples;
        if (j.points < BATCH)
            j.points = BATCH;
        j.scratch_mem = cbm__calloc(ctx, (size_t)nthreads * SCRATCH(j.points, nsrc) + 16, 1);
        j.scratch = j.scratch_mem + ((16 - (uintptr_t)j.scratch_mem % 16) % 16);
        if (!j.scratch_mem) {
            st = CBM_E_NOMEM;
            goto done;
        }
        atomic_init(&j.thread_id, 0);
        atomic_init(&j.next, 0);
        atomic_init(&j.rays, 0);
        pthread_t th[MAX_THREADS];
        int started = 0;
        for (int k = 1; k < nthreads; k++) {
            if (pthread_create(&th[started], NULL, work, &j) != 0)
                break;
            started++;
        }
        work(&j);
        for (int k = 0; k < started; k++)
            pthread_join(th[k], NULL);
    }
    if (stats) {
        stats->rays = atomic_load(&j.rays);
        stats->sources = nsrc;
        for (size_t i = 0; i < n_leaves; i++) {
            stats->total += absorbed[i];
            const cbm_vec3 *p = leaves[i].p;
            stats->leaf_area += 0.5 * v3_norm(v3_cross(v3_sub(p[2], p[0]), v3_sub(p[3], p[1])));
        }
    }
done:
    if (rs)
        cbm__rtc.rtcReleaseScene(rs);
    if (dev)
        cbm__rtc.rtcReleaseDevice(dev);
    cbm__free(ctx, src, nsrc * sizeof *src);
    cbm__free(ctx, j.scratch_mem, (size_t)nthreads * SCRATCH(j.points, nsrc) + 16);
    cbm__free(ctx, order, (n_leaves ? n_leaves : 1) * sizeof *order);
    if (st != CBM_OK) {
        for (size_t i = 0; i < n_leaves; i++)
            absorbed[i] = 0.0;
        if (stats)
            memset(stats, 0, sizeof *stats);
        return st;
    }
    if (stats)
        stats->seconds = now_seconds() - t0;
    return CBM_OK;
}

cbm_status cbm_light_calibrate(cbm_context *ctx, const cbm_light_def *def, cbm_vec3 at,
                               double *max_light_square)
{
    if (!ctx || !max_light_square)
        return CBM_E_INVALID;
    *max_light_square = 0.0;
    cbm_light_def d = def ? *def : cbm_light_def_default();
    d.max_light_square = 0.0;
    if (!v3_isfinite(at))
        return cbm__fail(ctx, CBM_E_INVALID, "light: the calibration point must be finite");
    cbm_light_leaf leaf;
    leaf.plant = 0;
    leaf.p[0] = v3(at.x - 0.5, at.y, at.z + 0.5);
    leaf.p[1] = v3(at.x + 0.5, at.y, at.z + 0.5);
    leaf.p[2] = v3(at.x + 0.5, at.y, at.z - 0.5);
    leaf.p[3] = v3(at.x - 0.5, at.y, at.z - 0.5);
    double a = 0.0;
    CBM_TRY(cbm_light_intercept(ctx, &d, &leaf, 1, NULL, 0, &a, NULL));
    *max_light_square = a;
    return CBM_OK;
}
