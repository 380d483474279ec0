/* The scene: an indexed triangle mesh with one part per organ instance, and the tessellation of
 * the primitives plants are made of: generalized cylinders with elliptical sections (rings of
 * `sides` vertices joined by quads, normals of the ellipse), UV spheres, polygons (ear clipping
 * after projection on the plane of Newell's normal) and ready meshes. Lines (pixel-wide segments
 * for pictures) are kept untessellated, 32 bytes each, in their own array. */
#include "geom_internal.h"

#include "../core/core.h"
#include "../core/vecmath.h"

#include <float.h>
#include <math.h>

/* A shape: its key, its slices of the shape arrays, its box (for the placements' bounds). */
typedef struct shape_rec {
    uint64_t key;
    size_t v0, nv, t0, nt;
    float lo[3], hi[3];
} shape_rec;

struct cbm_scene {
    cbm_context *ctx;
    CBM_ARRAY(cbm_scene_vertex) verts;
    CBM_ARRAY(uint32_t) tris;  /* 3 per triangle */
    CBM_ARRAY(uint32_t) tpart; /* 1 per triangle */
    /* With shared parts: 1 per triangle, its segment id as the .glb writes it (a float, -1 if
     * none), from the first triangle whose segment is not its part's (tseg_on) */
    CBM_ARRAY(float) tseg;
    bool tseg_on;
    CBM_ARRAY(cbm_part) parts;
    CBM_ARRAY(cbm_scene_line) lines;
    /* The tube instances, encoded one after the other (encode_instance), a fully written one
     * every INST_KEY instances, whose byte offsets are inst_key; inst_last: the last added. */
    CBM_ARRAY(uint8_t) inst;
    CBM_ARRAY(size_t) inst_key;
    size_t ninst;
    cbm_scene_instance inst_last;
    CBM_ARRAY(shape_rec) shapes;
    CBM_ARRAY(float) shape_pos, shape_nrm; /* 3 a vertex, the shapes one after the other */
    CBM_ARRAY(uint32_t) shape_tri;         /* 3 a triangle, indices local to the shape */
    CBM_ARRAY(cbm_scene_placement) place;
    bool line_mode, instancing;
    /* The current part: the one later geometry belongs to (with shared parts, not always the
     * last one stored). A shared part (cbm_scene_begin_part_shared): the segment id of the part
     * begun last, which differs from the current part's when seg_pending; the next geometry
     * other than an instance stores the part with it first (ensure_part). */
    uint32_t cur_part;
    int64_t cur_seg;
    bool seg_pending;
    /* The parts a shared part may be: an open-addressing table of part indices (UINT32_MAX:
     * empty), hashed on every field but the segment id, at most half full. */
    CBM_ARRAY(uint32_t) share;
    size_t share_used;
    /* tube in progress */
    int tube_sides;
    bool tube_cap0, tube_cap1, tube_open; /* caps at the start, at the end */
    uint32_t tube_prev;                   /* first vertex of the previous ring */
    size_t tube_rings;
    cbm_section tube_last;
};

static const char *const organ_names[CBM_ORGAN_COUNT] = {"branch", "leaf",   "fruit", "flower",
                                                         "bud",    "ground", "other"};

const char *cbm_organ_name(cbm_organ o)
{
    if ((unsigned)o >= CBM_ORGAN_COUNT)
        return "other";
    return organ_names[o];
}

cbm_part cbm_part_default(void)
{
    cbm_part p;
    memset(&p, 0, sizeof p);
    p.organ = CBM_ORGAN_BRANCH;
    p.order = -1;
    p.segment = -1;
    p.parent = -1;
    p.material = -1;
    p.color[0] = p.color[1] = p.color[2] = 0.6f;
    p.color[3] = 1.0f;
    p.stress_ratio = NAN;
    p.stress = NAN;
    p.age = NAN;
    p.reaction_wood = NAN;
    p.light = NAN;
    return p;
}

cbm_status cbm_scene_create(cbm_context *ctx, cbm_scene **out)
{
    if (!ctx || !out)
        return CBM_E_INVALID;
    *out = NULL;
    cbm_scene *s = cbm__calloc(ctx, 1, sizeof *s);
    if (!s)
        return CBM_E_NOMEM;
    s->ctx = ctx;
    *out = s;
    return CBM_OK;
}

void cbm_scene_destroy(cbm_scene *s)
{
    if (!s)
        return;
    cbm_context *ctx = s->ctx;
    CBM_ARRAY_FREE(ctx, s->verts);
    CBM_ARRAY_FREE(ctx, s->tris);
    CBM_ARRAY_FREE(ctx, s->tpart);
    CBM_ARRAY_FREE(ctx, s->tseg);
    CBM_ARRAY_FREE(ctx, s->parts);
    CBM_ARRAY_FREE(ctx, s->lines);
    CBM_ARRAY_FREE(ctx, s->inst);
    CBM_ARRAY_FREE(ctx, s->inst_key);
    CBM_ARRAY_FREE(ctx, s->shapes);
    CBM_ARRAY_FREE(ctx, s->shape_pos);
    CBM_ARRAY_FREE(ctx, s->shape_nrm);
    CBM_ARRAY_FREE(ctx, s->shape_tri);
    CBM_ARRAY_FREE(ctx, s->place);
    CBM_ARRAY_FREE(ctx, s->share);
    cbm__free(ctx, s, sizeof *s);
}

void cbm_scene_clear(cbm_scene *s)
{
    s->verts.len = s->tris.len = s->tpart.len = s->parts.len = s->lines.len = s->inst.len = 0;
    s->inst_key.len = s->ninst = s->tseg.len = 0;
    s->tseg_on = false;
    s->shapes.len = s->shape_pos.len = s->shape_nrm.len = s->shape_tri.len = s->place.len = 0;
    s->tube_open = false;
    s->seg_pending = false;
    s->cur_part = 0;
    if (s->share.len)
        memset(s->share.data, 0xff, s->share.len * sizeof *s->share.data);
    s->share_used = 0;
}

/* Whether an array indexed by uint32_t (vertices, parts, lines) has no room for one more. */
static bool index_full(size_t len)
{
    return len >= UINT32_MAX - 1;
}

/* Stores a part and makes it the current one. */
static cbm_status push_part(cbm_scene *s, const cbm_part *p)
{
    if (index_full(s->parts.len))
        return CBM_E_LIMIT;
    CBM_TRY(CBM_ARRAY_PUSH(s->ctx, s->parts, *p));
    s->cur_part = (uint32_t)(s->parts.len - 1);
    s->cur_seg = p->segment;
    s->seg_pending = false;
    return CBM_OK;
}

/* A part for geometry other than an instance: the default one in an empty scene, the shared
 * part of another segment stored as its own. */
static cbm_status ensure_part(cbm_scene *s)
{
    if (s->parts.len > 0 && !s->seg_pending)
        return CBM_OK;
    cbm_part p = s->parts.len > 0 ? s->parts.data[s->cur_part] : cbm_part_default();
    if (s->seg_pending)
        p.segment = s->cur_seg;
    return push_part(s, &p);
}

/* A segment id as the .glb writes it. */
static float segment_float(int64_t seg)
{
    return seg >= 0 ? (float)(double)seg : -1.0f;
}

/* From now on every triangle keeps its segment id; those before take their parts'. */
static cbm_status start_tri_segments(cbm_scene *s)
{
    CBM_TRY(CBM_ARRAY_RESERVE(s->ctx, s->tseg, s->tpart.len + 1));
    for (size_t t = 0; t < s->tpart.len; t++)
        s->tseg.data[t] = segment_float(s->parts.data[s->tpart.data[t]].segment);
    s->tseg.len = s->tpart.len;
    s->tseg_on = true;
    return CBM_OK;
}

/* The part for triangles: in instancing mode, the shared part itself, the triangles keeping
 * their segment id (4 bytes a triangle instead of an 88-byte part a segment); else as
 * ensure_part. */
static cbm_status ensure_tri_part(cbm_scene *s)
{
    if (!s->instancing || !s->seg_pending || s->parts.len == 0)
        return ensure_part(s);
    return s->tseg_on ? CBM_OK : start_tri_segments(s);
}

cbm_status cbm_scene_begin_part(cbm_scene *s, const cbm_part *part, uint32_t *id)
{
    if (!s || !part)
        return CBM_E_INVALID;
    CBM_TRY(push_part(s, part));
    if (id)
        *id = s->cur_part;
    return CBM_OK;
}

/* Equal bit for bit (NaN equals the same NaN; 0 and -0 differ, as the writers' bytes do). */
static bool same_bits(double a, double b)
{
    uint64_t x, y;
    memcpy(&x, &a, sizeof x);
    memcpy(&y, &b, sizeof y);
    return x == y;
}

/* Equal but for the segment id, field by field (NaNs of the unknown quantities equal bit for
 * bit: they are cbm_part_default's). */
static bool same_but_segment(const cbm_part *a, const cbm_part *b)
{
    return a->organ == b->organ && a->order == b->order && a->parent == b->parent &&
           a->material == b->material &&
           // NOLINTNEXTLINE(bugprone-suspicious-memory-comparison,cert-exp42-c,cert-flp37-c)
           memcmp(a->color, b->color, sizeof a->color) == 0 &&
           same_bits(a->stress_ratio, b->stress_ratio) && same_bits(a->stress, b->stress) &&
           same_bits(a->age, b->age) && same_bits(a->reaction_wood, b->reaction_wood) &&
           same_bits(a->light, b->light);
}

static uint64_t hash_mix(uint64_t h, uint64_t x)
{
    return (h ^ x) * 0x100000001B3ull + (x >> 29);
}

static uint64_t double_bits(double x)
{
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}

/* A hash of every field of a part but the segment id (equal bits, equal hash: same_but_segment). */
static size_t share_hash(const cbm_part *p, size_t cap)
{
    uint32_t c[4];
    memcpy(c, p->color, sizeof c);
    uint64_t h = 0xCBF29CE484222325ull;
    h = hash_mix(h, (uint64_t)p->organ | (uint64_t)(uint32_t)p->order << 32);
    h = hash_mix(h, (uint64_t)p->parent);
    h = hash_mix(h, (uint64_t)(uint32_t)p->material);
    h = hash_mix(h, (uint64_t)c[0] | (uint64_t)c[1] << 32);
    h = hash_mix(h, (uint64_t)c[2] | (uint64_t)c[3] << 32);
    h = hash_mix(h, double_bits(p->stress_ratio));
    h = hash_mix(h, double_bits(p->stress));
    h = hash_mix(h, double_bits(p->age));
    h = hash_mix(h, double_bits(p->reaction_wood));
    h = hash_mix(h, double_bits(p->light));
    return (size_t)((h * 0x9E3779B97F4A7C15ull) >> 32) & (cap - 1);
}

/* The slot of a part equal to `part` but for its segment id in the share table, or of the
 * empty slot where it goes. */
static uint32_t *share_slot(cbm_scene *s, const cbm_part *part)
{
    size_t cap = s->share.len, h = share_hash(part, cap);
    while (s->share.data[h] != UINT32_MAX &&
           !same_but_segment(&s->parts.data[s->share.data[h]], part))
        h = (h + 1) & (cap - 1);
    return &s->share.data[h];
}

/* The share table at twice its size (at least 64 slots), every entry placed again. */
static cbm_status share_grow(cbm_scene *s)
{
    size_t old = s->share.len, cap = old ? 2 * old : 64;
    uint32_t *keep = NULL;
    if (old) {
        keep = cbm__alloc(s->ctx, old * sizeof *keep);
        if (!keep)
            return CBM_E_NOMEM;
        memcpy(keep, s->share.data, old * sizeof *keep);
    }
    cbm_status st = CBM_ARRAY_RESERVE(s->ctx, s->share, cap);
    if (st == CBM_OK) {
        s->share.len = cap;
        memset(s->share.data, 0xff, cap * sizeof *s->share.data);
        for (size_t i = 0; i < old; i++)
            if (keep[i] != UINT32_MAX)
                *share_slot(s, &s->parts.data[keep[i]]) = keep[i];
    }
    cbm__free(s->ctx, keep, old * sizeof *keep);
    return st;
}

cbm_status cbm_scene_begin_part_shared(cbm_scene *s, const cbm_part *part)
{
    if (!s || !part)
        return CBM_E_INVALID;
    if (!s->instancing)
        return cbm_scene_begin_part(s, part, NULL);
    /* the current part first (a run of segments), then any part begun before */
    uint32_t k = s->cur_part;
    if (s->parts.len == 0 || !same_but_segment(&s->parts.data[k], part)) {
        if (2 * (s->share_used + 1) > s->share.len)
            CBM_TRY(share_grow(s));
        uint32_t *slot = share_slot(s, part);
        if (*slot == UINT32_MAX) {
            CBM_TRY(push_part(s, part));
            *slot = s->cur_part;
            s->share_used++;
            return CBM_OK;
        }
        k = *slot;
    }
    s->cur_part = k;
    s->cur_seg = part->segment;
    s->seg_pending = part->segment != s->parts.data[k].segment;
    return CBM_OK;
}

static cbm_status push_vertex(cbm_scene *s, cbm_vec3 p, cbm_vec3 n)
{
    if (index_full(s->verts.len))
        return CBM_E_LIMIT;
    cbm_scene_vertex v = {{(float)p.x, (float)p.y, (float)p.z},
                          {(float)n.x, (float)n.y, (float)n.z}};
    return CBM_ARRAY_PUSH(s->ctx, s->verts, v);
}

static cbm_status push_tri(cbm_scene *s, uint32_t a, uint32_t b, uint32_t c)
{
    CBM_TRY(CBM_ARRAY_RESERVE(s->ctx, s->tris, s->tris.len + 3));
    CBM_TRY(CBM_ARRAY_RESERVE(s->ctx, s->tpart, s->tpart.len + 1));
    if (s->seg_pending && !s->tseg_on)
        CBM_TRY(start_tri_segments(s));
    if (s->tseg_on) {
        CBM_TRY(CBM_ARRAY_RESERVE(s->ctx, s->tseg, s->tseg.len + 1));
        s->tseg.data[s->tseg.len++] = segment_float(s->cur_seg);
    }
    s->tris.data[s->tris.len++] = a;
    s->tris.data[s->tris.len++] = b;
    s->tris.data[s->tris.len++] = c;
    s->tpart.data[s->tpart.len++] = s->cur_part;
    return CBM_OK;
}

/* ---- generalized cylinders ---- */

cbm_status cbm_scene_tube_begin(cbm_scene *s, int sides, bool caps)
{
    return cbm__scene_tube_begin_caps(s, sides, caps, caps);
}

cbm_status cbm__scene_tube_begin_caps(cbm_scene *s, int sides, bool cap_start, bool cap_end)
{
    if (!s || sides < 3 || sides > 1024)
        return CBM_E_INVALID;
    CBM_TRY(ensure_tri_part(s));
    s->tube_sides = sides;
    s->tube_cap0 = cap_start;
    s->tube_cap1 = cap_end;
    s->tube_open = true;
    s->tube_rings = 0;
    return CBM_OK;
}

static cbm_status add_cap(cbm_scene *s, const cbm_section *sec, uint32_t ring, bool at_start)
{
    /* A flat disc: a fan around the centre with its own vertices (sharp edge). */
    cbm_vec3 n = at_start ? v3_neg(sec->frame.h) : sec->frame.h;
    uint32_t c = (uint32_t)s->verts.len;
    CBM_TRY(push_vertex(s, sec->center, n));
    for (int i = 0; i < s->tube_sides; i++) {
        const cbm_scene_vertex *v = &s->verts.data[ring + (uint32_t)i];
        CBM_TRY(push_vertex(s, v3(v->p[0], v->p[1], v->p[2]), n));
    }
    for (int i = 0; i < s->tube_sides; i++) {
        uint32_t a = c + 1 + (uint32_t)i, b = c + 1 + (uint32_t)((i + 1) % s->tube_sides);
        CBM_TRY(at_start ? push_tri(s, c, a, b) : push_tri(s, c, b, a));
    }
    return CBM_OK;
}

cbm_context *cbm__scene_context(const cbm_scene *s)
{
    return s->ctx;
}

/* Joins the ring just pushed (its first vertex `first`) to the previous one, or caps it. */
static cbm_status close_ring(cbm_scene *s, const cbm_section *sec, uint32_t first)
{
    int n = s->tube_sides;
    if (s->tube_rings == 0) {
        if (s->tube_cap0)
            CBM_TRY(add_cap(s, sec, first, true));
    } else {
        uint32_t p = s->tube_prev;
        for (int i = 0; i < n; i++) {
            uint32_t i0 = (uint32_t)i, i1 = (uint32_t)((i + 1) % n);
            /* the ring runs from U towards L, clockwise seen from +H: wind outwards */
            CBM_TRY(push_tri(s, p + i0, first + i1, p + i1));
            CBM_TRY(push_tri(s, p + i0, first + i0, first + i1));
        }
    }
    s->tube_prev = first;
    s->tube_last = *sec;
    s->tube_rings++;
    return CBM_OK;
}

cbm_status cbm_scene_tube_ring_points(cbm_scene *s, cbm_vec3 center, cbm_vec3 axis,
                                      const cbm_vec3 *pts, const cbm_vec3 *nrm)
{
    if (!s || !pts || !nrm || !s->tube_open)
        return CBM_E_INVALID;
    if (!v3_isfinite(center) || !v3_isfinite(axis))
        return CBM_E_NONFINITE;
    int n = s->tube_sides;
    for (int i = 0; i < n; i++)
        if (!v3_isfinite(pts[i]) || !v3_isfinite(nrm[i]))
            return CBM_E_NONFINITE;
    uint32_t first = (uint32_t)s->verts.len;
    for (int i = 0; i < n; i++)
        CBM_TRY(push_vertex(s, pts[i], nrm[i]));
    /* the cap needs the centre and the axis only */
    cbm_section sec = {center, {axis, v3(0, 0, 0), v3(0, 0, 0)}, 0.0, 0.0};
    return close_ring(s, &sec, first);
}

cbm_status cbm_scene_tube_ring(cbm_scene *s, const cbm_section *sec)
{
    if (!s || !sec || !s->tube_open)
        return CBM_E_INVALID;
    if (!v3_isfinite(sec->center) || !isfinite(sec->a) || !isfinite(sec->b))
        return CBM_E_NONFINITE;
    uint32_t first = (uint32_t)s->verts.len;
    int n = s->tube_sides;
    double a = fabs(sec->a), b = fabs(sec->b);
    for (int i = 0; i < n; i++) {
        double t = 2.0 * CBM_PI * i / n, c = cos(t), sn = sin(t);
        /* point a cos t U + b sin t L; normal ~ (cos t / a) U + (sin t / b) L */
        cbm_vec3 p = v3_add(sec->center,
                            v3_add(v3_scale(sec->frame.u, a * c), v3_scale(sec->frame.l, b * sn)));
        cbm_vec3 nn = v3_add(v3_scale(sec->frame.u, b * c), v3_scale(sec->frame.l, a * sn));
        nn = v3_normalize(nn);
        if (a == 0.0 && b == 0.0)
            nn = v3_normalize(v3_add(v3_scale(sec->frame.u, c), v3_scale(sec->frame.l, sn)));
        CBM_TRY(push_vertex(s, p, nn));
    }
    return close_ring(s, sec, first);
}

cbm_status cbm_scene_tube_end(cbm_scene *s)
{
    if (!s || !s->tube_open)
        return CBM_E_INVALID;
    s->tube_open = false;
    if (s->tube_cap1 && s->tube_rings > 0)
        CBM_TRY(add_cap(s, &s->tube_last, s->tube_prev, false));
    return CBM_OK;
}

static bool same_vec(cbm_vec3 a, cbm_vec3 b)
{
    return a.x == b.x && a.y == b.y && a.z == b.z;
}

/* A tube an instance can stand for: no caps, sections in the same frame, the end one the start
 * one scaled by *taper, H along the axis (then the instance's rotation and scale give the rings'
 * points and normals: the scene's ring normals are the sections' own, without the taper's
 * slope, so both rings' normals are the unit frustum's scaled as the start section). */
static bool instanceable(const cbm_scene *s, const cbm_section *s0, const cbm_section *s1,
                         int sides, bool caps, double *taper)
{
    double a0 = fabs(s0->a), b0 = fabs(s0->b), a1 = fabs(s1->a), b1 = fabs(s1->b);
    *taper = a0 == a1 && b0 == b1 ? 1.0 : a0 > 0.0 ? a1 / a0 : -1.0;
    if (!s->instancing || caps || sides < 3 || sides > 1024 || !(*taper > 0.0) ||
        !(fabs(b0 * *taper - b1) <= 1e-12 * (b1 + a1)) || !isfinite(*taper) ||
        !same_vec(s0->frame.h, s1->frame.h) || !same_vec(s0->frame.u, s1->frame.u) ||
        !same_vec(s0->frame.l, s1->frame.l) || !v3_isfinite(s0->center) ||
        !v3_isfinite(s1->center) || !isfinite(s0->a) || !isfinite(s0->b))
        return false;
    cbm_vec3 d = v3_sub(s1->center, s0->center), h = s0->frame.h, u = s0->frame.u;
    double len = v3_norm(d);
    /* a right frame: unit H along the axis, unit U across it, L = +-(U x H) (an ellipse is
     * symmetric, so a mirrored L draws the same tube) */
    return len > 0.0 && fabs(v3_norm(h) - 1.0) < 1e-9 && fabs(v3_norm(u) - 1.0) < 1e-9 &&
           v3_norm(v3_cross(d, h)) <= 1e-9 * len && v3_dot(d, h) > 0.0 &&
           fabs(v3_dot(u, h)) < 1e-9 &&
           fabs(fabs(v3_dot(s0->frame.l, v3_cross(u, h))) - 1.0) < 1e-9;
}

void cbm_scene_set_instancing(cbm_scene *s, bool on)
{
    if (s)
        s->instancing = on;
}

bool cbm_scene_instancing(const cbm_scene *s)
{
    return s && s->instancing;
}

size_t cbm_scene_instance_count(const cbm_scene *s)
{
    return s ? s->ninst : 0;
}

/* An instance in the byte stream: a flags byte saying which fields are the previous instance's
 * (left out), then those written, p1 last. A branch's segments follow one another along the
 * string, so most instances start where the previous one ended, in its frame, width and part:
 * 14 bytes (p1, the segment id as a 1-byte step) instead of 60. Bit for bit: the stream gives
 * back the floats it was given. */
enum {
    INST_KEY = 256,     /* a fully written instance every INST_KEY: where a reader can start */
    INST_P0_LAST = 1,   /* p0 is the previous p1 */
    INST_U_LAST = 2,    /* u is the previous u */
    INST_AB_LAST = 4,   /* a, b are the previous */
    INST_KIND_LAST = 8, /* taper, part, sides are the previous */
    INST_SEG_STEP = 16, /* segment is the previous plus a signed byte (else a float) */
    INST_MAX_BYTES = 1 + 12 + 12 + 8 + 12 + 4 + 12
};

static bool same_floats(const float *a, const float *b, size_t n)
{
    return memcmp(a, b, n * sizeof *a) == 0;
}

static uint8_t *pack_bytes(uint8_t *d, const void *v, size_t n)
{
    memcpy(d, v, n);
    return d + n;
}

static cbm_status encode_instance(cbm_scene *s, const cbm_scene_instance *in)
{
    CBM_TRY(CBM_ARRAY_RESERVE(s->ctx, s->inst, s->inst.len + INST_MAX_BYTES));
    const cbm_scene_instance *l = &s->inst_last;
    unsigned flags = 0;
    float step = in->segment - l->segment;
    if (s->ninst % INST_KEY == 0) {
        CBM_TRY(CBM_ARRAY_PUSH(s->ctx, s->inst_key, s->inst.len));
    } else {
        flags |= same_floats(in->p0, l->p1, 3) ? INST_P0_LAST : 0u;
        flags |= same_floats(in->u, l->u, 3) ? INST_U_LAST : 0u;
        flags |= in->a == l->a && in->b == l->b ? INST_AB_LAST : 0u;
        flags |= in->taper == l->taper && in->part == l->part && in->sides == l->sides
                     ? INST_KIND_LAST
                     : 0u;
        /* a whole step of a byte that gives back the same float, bit for bit */
        float back = l->segment + step;
        flags |=
            fabsf(step) <= 127.0f && step == truncf(step) && same_floats(&back, &in->segment, 1)
                ? INST_SEG_STEP
                : 0u;
    }
    uint8_t *d = s->inst.data + s->inst.len, *d0 = d;
    *d++ = (uint8_t)flags;
    if (!(flags & INST_P0_LAST))
        d = pack_bytes(d, in->p0, sizeof in->p0);
    if (!(flags & INST_U_LAST))
        d = pack_bytes(d, in->u, sizeof in->u);
    if (!(flags & INST_AB_LAST)) {
        d = pack_bytes(d, &in->a, sizeof in->a);
        d = pack_bytes(d, &in->b, sizeof in->b);
    }
    if (!(flags & INST_KIND_LAST)) {
        d = pack_bytes(d, &in->taper, sizeof in->taper);
        d = pack_bytes(d, &in->part, sizeof in->part);
        d = pack_bytes(d, &in->sides, sizeof in->sides);
    }
    if (flags & INST_SEG_STEP)
        *d++ = (uint8_t)(int8_t)step;
    else
        d = pack_bytes(d, &in->segment, sizeof in->segment);
    d = pack_bytes(d, in->p1, sizeof in->p1);
    s->inst.len += (size_t)(d - d0);
    s->inst_last = *in;
    s->ninst++;
    return CBM_OK;
}

static const uint8_t *unpack_bytes(const uint8_t *d, void *v, size_t n)
{
    memcpy(v, d, n);
    return d + n;
}

/* The instance at byte `off` into *l, which holds the previous one; the offset of the next. */
static size_t decode_instance(const cbm_scene *s, size_t off, cbm_scene_instance *l)
{
    const uint8_t *d = s->inst.data + off, *d0 = d;
    unsigned flags = *d++;
    if (flags & INST_P0_LAST)
        memcpy(l->p0, l->p1, sizeof l->p0);
    else
        d = unpack_bytes(d, l->p0, sizeof l->p0);
    if (!(flags & INST_U_LAST))
        d = unpack_bytes(d, l->u, sizeof l->u);
    if (!(flags & INST_AB_LAST)) {
        d = unpack_bytes(d, &l->a, sizeof l->a);
        d = unpack_bytes(d, &l->b, sizeof l->b);
    }
    if (!(flags & INST_KIND_LAST)) {
        d = unpack_bytes(d, &l->taper, sizeof l->taper);
        d = unpack_bytes(d, &l->part, sizeof l->part);
        d = unpack_bytes(d, &l->sides, sizeof l->sides);
    }
    if (flags & INST_SEG_STEP)
        l->segment += (float)(int8_t)*d++;
    else
        d = unpack_bytes(d, &l->segment, sizeof l->segment);
    d = unpack_bytes(d, l->p1, sizeof l->p1);
    return off + (size_t)(d - d0);
}

cbm_status cbm_scene_instance_read(const cbm_scene *s, size_t i, cbm_scene_instance_cursor *c,
                                   cbm_scene_instance *out)
{
    if (!s || !c || !out || i >= s->ninst)
        return CBM_E_INVALID;
    size_t key = i / INST_KEY * INST_KEY;
    if (i < c->next || key > c->next || c->offset > s->inst.len) {
        c->next = key;
        c->offset = s->inst_key.data[key / INST_KEY];
    }
    while (c->next <= i) {
        c->offset = decode_instance(s, c->offset, &c->last);
        c->next++;
    }
    *out = c->last;
    return CBM_OK;
}

size_t cbm_scene_instance_bytes(const cbm_scene *s)
{
    return s ? s->inst.len + s->inst_key.len * sizeof *s->inst_key.data : 0;
}

cbm_status cbm_scene_add_tube(cbm_scene *s, const cbm_section *s0, const cbm_section *s1, int sides,
                              bool caps)
{
    double taper = 1.0;
    if (s && s0 && s1 && !s->tube_open && instanceable(s, s0, s1, sides, caps, &taper)) {
        if (s->parts.len == 0)
            CBM_TRY(ensure_part(s));
        cbm_scene_instance in = {{(float)s0->center.x, (float)s0->center.y, (float)s0->center.z},
                                 {(float)s1->center.x, (float)s1->center.y, (float)s1->center.z},
                                 {(float)s0->frame.u.x, (float)s0->frame.u.y, (float)s0->frame.u.z},
                                 (float)fabs(s0->a),
                                 (float)fabs(s0->b),
                                 (float)taper,
                                 s->cur_part,
                                 sides,
                                 /* as the writer writes the part's id: through a double */
                                 s->cur_seg >= 0 ? (float)(double)s->cur_seg : -1.0f};
        return encode_instance(s, &in);
    }
    CBM_TRY(cbm_scene_tube_begin(s, sides, caps));
    CBM_TRY(cbm_scene_tube_ring(s, s0));
    CBM_TRY(cbm_scene_tube_ring(s, s1));
    return cbm_scene_tube_end(s);
}

/* ---- spheres ---- */

cbm_status cbm_scene_add_sphere(cbm_scene *s, cbm_vec3 c, double r, int slices)
{
    if (!s || slices < 3 || slices > 1024 || !(r >= 0.0) || !v3_isfinite(c))
        return CBM_E_INVALID;
    CBM_TRY(ensure_tri_part(s));
    int stacks = slices / 2 < 2 ? 2 : slices / 2;
    uint32_t base = (uint32_t)s->verts.len;
    /* the meridians' cosines and sines once a sphere, not once a ring (the same values) */
    double cph[64], sph[64];
    int ncs = slices < 64 ? slices : 64;
    for (int j = 0; j < ncs; j++) {
        double ph = 2.0 * CBM_PI * j / slices;
        cph[j] = cos(ph);
        sph[j] = sin(ph);
    }
    for (int i = 0; i <= stacks; i++) {
        double th = CBM_PI * i / stacks, st = sin(th), ct = cos(th);
        for (int j = 0; j < slices; j++) {
            double ph = 2.0 * CBM_PI * j / slices;
            cbm_vec3 n =
                j < ncs ? v3(st * cph[j], ct, st * sph[j]) : v3(st * cos(ph), ct, st * sin(ph));
            CBM_TRY(push_vertex(s, v3_madd(c, n, r), n));
        }
    }
    for (int i = 0; i < stacks; i++) {
        for (int j = 0; j < slices; j++) {
            uint32_t a = base + (uint32_t)(i * slices + j);
            uint32_t b = base + (uint32_t)(i * slices + (j + 1) % slices);
            uint32_t cc = a + (uint32_t)slices, d = b + (uint32_t)slices;
            if (i > 0)
                CBM_TRY(push_tri(s, a, b, d));
            if (i < stacks - 1)
                CBM_TRY(push_tri(s, a, d, cc));
        }
    }
    return CBM_OK;
}

/* ---- polygons ---- */

static double cross2(double ax, double ay, double bx, double by)
{
    return ax * by - ay * bx;
}

cbm_status cbm_scene_add_polygon(cbm_scene *s, const cbm_vec3 *pts, size_t n)
{
    if (!s || (!pts && n))
        return CBM_E_INVALID;
    if (n < 3)
        return CBM_OK; /* nothing to draw */
    CBM_TRY(ensure_tri_part(s));
    cbm_vec3 nrm = v3(0, 0, 0);
    for (size_t i = 0; i < n; i++) {
        cbm_vec3 a = pts[i], b = pts[(i + 1) % n];
        if (!v3_isfinite(a))
            return CBM_E_NONFINITE;
        nrm.x += (a.y - b.y) * (a.z + b.z);
        nrm.y += (a.z - b.z) * (a.x + b.x);
        nrm.z += (a.x - b.x) * (a.y + b.y);
    }
    if (v3_norm(nrm) == 0.0)
        return CBM_OK; /* degenerate: no area */
    nrm = v3_normalize(nrm);
    /* 2-D basis of the plane */
    cbm_vec3 ex = fabs(nrm.x) < 0.9 ? v3(1, 0, 0) : v3(0, 1, 0);
    ex = v3_normalize(v3_sub(ex, v3_scale(nrm, v3_dot(ex, nrm))));
    cbm_vec3 ey = v3_cross(nrm, ex);
    uint32_t base = (uint32_t)s->verts.len;
    for (size_t i = 0; i < n; i++)
        CBM_TRY(push_vertex(s, pts[i], nrm));
    /* ear clipping over an index list, O(n^2) (polygons of plants are small) */
    uint32_t *idx = cbm__alloc(s->ctx, n * sizeof *idx);
    double *xy = cbm__alloc(s->ctx, 2 * n * sizeof *xy);
    cbm_status st = CBM_OK;
    if (!idx || !xy) {
        st = CBM_E_NOMEM;
        goto done;
    }
    for (size_t i = 0; i < n; i++) {
        idx[i] = (uint32_t)i;
        xy[2 * i] = v3_dot(pts[i], ex);
        xy[2 * i + 1] = v3_dot(pts[i], ey);
    }
    size_t m = n, guard = 0;
    while (m > 3 && st == CBM_OK) {
        bool clipped = false;
        for (size_t k = 0; k < m; k++) {
            uint32_t i0 = idx[(k + m - 1) % m], i1 = idx[k], i2 = idx[(k + 1) % m];
            double ax = xy[2 * i0], ay = xy[2 * i0 + 1], bx = xy[2 * i1], by = xy[2 * i1 + 1];
            double cx = xy[2 * i2], cy = xy[2 * i2 + 1];
            double area = cross2(bx - ax, by - ay, cx - ax, cy - ay);
            if (area <= 0.0)
                continue; /* reflex or degenerate */
            bool inside = false;
            for (size_t q = 0; q < m && !inside; q++) {
                uint32_t j = idx[q];
                if (j == i0 || j == i1 || j == i2)
                    continue;
                double px = xy[2 * j], py = xy[2 * j + 1];
                if (cross2(bx - ax, by - ay, px - ax, py - ay) >= 0 &&
                    cross2(cx - bx, cy - by, px - bx, py - by) >= 0 &&
                    cross2(ax - cx, ay - cy, px - cx, py - cy) >= 0)
                    inside = true;
            }
            if (inside)
                continue;
            st = push_tri(s, base + i0, base + i1, base + i2);
            memmove(idx + k, idx + k + 1, (m - k - 1) * sizeof *idx);
            m--;
            clipped = true;
            break;
        }
        if (!clipped) {
            /* self-intersecting or numerically degenerate: fall back to a fan */
            for (size_t k = 1; k + 1 < m && st == CBM_OK; k++)
                st = push_tri(s, base + idx[0], base + idx[k], base + idx[k + 1]);
            m = 0;
        }
        if (++guard > 4 * n)
            break;
    }
    if (m == 3 && st == CBM_OK)
        st = push_tri(s, base + idx[0], base + idx[1], base + idx[2]);
done:
    cbm__free(s->ctx, idx, n * sizeof *idx);
    cbm__free(s->ctx, xy, 2 * n * sizeof *xy);
    return st;
}

cbm_status cbm_scene_add_mesh(cbm_scene *s, const cbm_vec3 *pos, const cbm_vec3 *nrm, size_t nverts,
                              const uint32_t *tri, size_t ntri)
{
    if (!s || (!pos && nverts) || (!tri && ntri))
        return CBM_E_INVALID;
    CBM_TRY(ensure_tri_part(s));
    for (size_t i = 0; i < 3 * ntri; i++)
        if (tri[i] >= nverts)
            return CBM_E_INVALID;
    uint32_t base = (uint32_t)s->verts.len;
    for (size_t i = 0; i < nverts; i++) {
        if (!v3_isfinite(pos[i]))
            return CBM_E_NONFINITE;
        CBM_TRY(push_vertex(s, pos[i], nrm ? v3_normalize(nrm[i]) : v3(0, 0, 0)));
    }
    for (size_t t = 0; t < ntri; t++)
        CBM_TRY(push_tri(s, base + tri[3 * t], base + tri[3 * t + 1], base + tri[3 * t + 2]));
    if (!nrm) {
        /* area-weighted vertex normals */
        for (size_t t = 0; t < ntri; t++) {
            /* ntri > 0 implies nverts > 0 and pos set (checked above) */
            // NOLINTNEXTLINE(clang-analyzer-core.NullDereference)
            cbm_vec3 a = pos[tri[3 * t]], b = pos[tri[3 * t + 1]], c = pos[tri[3 * t + 2]];
            cbm_vec3 fn = v3_cross(v3_sub(b, a), v3_sub(c, a));
            for (int k = 0; k < 3; k++) {
                float *vn = s->verts.data[base + tri[3 * t + (size_t)k]].n;
                vn[0] += (float)fn.x;
                vn[1] += (float)fn.y;
                vn[2] += (float)fn.z;
            }
        }
        for (size_t i = 0; i < nverts; i++) {
            float *vn = s->verts.data[base + i].n;
            cbm_vec3 v = v3_normalize(v3(vn[0], vn[1], vn[2]));
            if (v3_norm(v) == 0.0)
                v = v3(0, 1, 0);
            vn[0] = (float)v.x;
            vn[1] = (float)v.y;
            vn[2] = (float)v.z;
        }
    }
    return CBM_OK;
}

/* ---- shapes and their placements ---- */

bool cbm_scene_find_shape(const cbm_scene *s, uint64_t key, uint32_t *id)
{
    for (size_t i = 0; s && i < s->shapes.len; i++)
        if (s->shapes.data[i].key == key) {
            if (id)
                *id = (uint32_t)i;
            return true;
        }
    return false;
}

cbm_status cbm_scene_add_shape(cbm_scene *s, uint64_t key, const cbm_vec3 *pos, const cbm_vec3 *nrm,
                               size_t nverts, const uint32_t *tri, size_t ntri, uint32_t *id)
{
    if (!s || !pos || !nrm || !nverts || (!tri && ntri) || nverts > UINT32_MAX)
        return CBM_E_INVALID;
    for (size_t i = 0; i < 3 * ntri; i++)
        if (tri[i] >= nverts)
            return CBM_E_INVALID;
    shape_rec r = {key,
                   s->shape_pos.len / 3,
                   nverts,
                   s->shape_tri.len / 3,
                   ntri,
                   {FLT_MAX, FLT_MAX, FLT_MAX},
                   {-FLT_MAX, -FLT_MAX, -FLT_MAX}};
    CBM_TRY(CBM_ARRAY_RESERVE(s->ctx, s->shape_pos, s->shape_pos.len + 3 * nverts));
    CBM_TRY(CBM_ARRAY_RESERVE(s->ctx, s->shape_nrm, s->shape_nrm.len + 3 * nverts));
    CBM_TRY(CBM_ARRAY_RESERVE(s->ctx, s->shape_tri, s->shape_tri.len + 3 * ntri));
    for (size_t i = 0; i < nverts; i++) {
        if (!v3_isfinite(pos[i]))
            return CBM_E_NONFINITE;
        const double p[3] = {pos[i].x, pos[i].y, pos[i].z};
        cbm_vec3 n = v3_normalize(nrm[i]);
        const double q[3] = {n.x, n.y, n.z};
        for (int k = 0; k < 3; k++) {
            float f = (float)p[k];
            s->shape_pos.data[s->shape_pos.len++] = f;
            s->shape_nrm.data[s->shape_nrm.len++] = (float)q[k];
            r.lo[k] = f < r.lo[k] ? f : r.lo[k];
            r.hi[k] = f > r.hi[k] ? f : r.hi[k];
        }
    }
    for (size_t i = 0; i < 3 * ntri; i++)
        s->shape_tri.data[s->shape_tri.len++] = tri[i];
    CBM_TRY(CBM_ARRAY_PUSH(s->ctx, s->shapes, r));
    if (id)
        *id = (uint32_t)(s->shapes.len - 1);
    return CBM_OK;
}

/* Columns a placement can keep: finite, non-zero and orthogonal (then the map is a rotation, a
 * scale and perhaps a mirror, as an instance's TRS needs). */
static bool placeable(cbm_vec3 o, cbm_vec3 x, cbm_vec3 y, cbm_vec3 z)
{
    double nx = v3_norm(x), ny = v3_norm(y), nz = v3_norm(z);
    return v3_isfinite(o) && isfinite(nx) && isfinite(ny) && isfinite(nz) && nx > 0.0 && ny > 0.0 &&
           nz > 0.0 && fabs(v3_dot(x, y)) <= 1e-6 * nx * ny &&
           fabs(v3_dot(y, z)) <= 1e-6 * ny * nz && fabs(v3_dot(z, x)) <= 1e-6 * nz * nx;
}

cbm_status cbm_scene_place_shape(cbm_scene *s, uint32_t shape, cbm_vec3 o, cbm_vec3 x, cbm_vec3 y,
                                 cbm_vec3 z)
{
    if (!s || shape >= s->shapes.len)
        return CBM_E_INVALID;
    CBM_TRY(ensure_part(s));
    if (s->instancing && placeable(o, x, y, z)) {
        cbm_scene_placement pl = {{(float)o.x, (float)o.y, (float)o.z},
                                  {(float)x.x, (float)x.y, (float)x.z},
                                  {(float)y.x, (float)y.y, (float)y.z},
                                  {(float)z.x, (float)z.y, (float)z.z},
                                  s->cur_part,
                                  shape};
        return CBM_ARRAY_PUSH(s->ctx, s->place, pl);
    }
    /* the triangles: normals by the cofactors of (x y z), the inverse transpose up to a factor */
    const shape_rec *r = &s->shapes.data[shape];
    cbm_vec3 cx = v3_cross(y, z), cy = v3_cross(z, x), cz = v3_cross(x, y);
    double det = v3_dot(x, cx);
    if (det < 0.0)
        cx = v3_scale(cx, -1.0), cy = v3_scale(cy, -1.0), cz = v3_scale(cz, -1.0);
    uint32_t base = (uint32_t)s->verts.len;
    for (size_t i = 0; i < r->nv; i++) {
        const float *q = s->shape_pos.data + 3 * (r->v0 + i),
                    *n = s->shape_nrm.data + 3 * (r->v0 + i);
        cbm_vec3 p =
            v3_add(o, v3_add(v3_add(v3_scale(x, q[0]), v3_scale(y, q[1])), v3_scale(z, q[2])));
        if (!v3_isfinite(p))
            return CBM_E_NONFINITE;
        cbm_vec3 m = v3_normalize(
            v3_add(v3_add(v3_scale(cx, n[0]), v3_scale(cy, n[1])), v3_scale(cz, n[2])));
        CBM_TRY(push_vertex(s, p, m));
    }
    for (size_t t = 0; t < r->nt; t++) {
        const uint32_t *tr = s->shape_tri.data + 3 * (r->t0 + t);
        CBM_TRY(push_tri(s, base + tr[0], base + tr[1], base + tr[2]));
    }
    return CBM_OK;
}

size_t cbm_scene_shape_count(const cbm_scene *s)
{
    return s ? s->shapes.len : 0;
}

cbm_status cbm_scene_shape_mesh(const cbm_scene *s, uint32_t shape, const float **pos,
                                const float **nrm, size_t *nverts, const uint32_t **tri,
                                size_t *ntri)
{
    if (!s || shape >= s->shapes.len)
        return CBM_E_INVALID;
    const shape_rec *r = &s->shapes.data[shape];
    if (pos)
        *pos = s->shape_pos.data + 3 * r->v0;
    if (nrm)
        *nrm = s->shape_nrm.data + 3 * r->v0;
    if (nverts)
        *nverts = r->nv;
    if (tri)
        *tri = s->shape_tri.data + 3 * r->t0;
    if (ntri)
        *ntri = r->nt;
    return CBM_OK;
}

size_t cbm_scene_placement_count(const cbm_scene *s)
{
    return s ? s->place.len : 0;
}

const cbm_scene_placement *cbm_scene_placements(const cbm_scene *s)
{
    return s ? s->place.data : NULL;
}

size_t cbm_scene_vertex_count(const cbm_scene *s)
{
    return s->verts.len;
}
const cbm_scene_vertex *cbm_scene_vertices(const cbm_scene *s)
{
    return s->verts.data;
}
size_t cbm_scene_triangle_count(const cbm_scene *s)
{
    return s->tpart.len;
}
const uint32_t *cbm_scene_triangles(const cbm_scene *s)
{
    return s->tris.data;
}
const uint32_t *cbm_scene_triangle_parts(const cbm_scene *s)
{
    return s->tpart.data;
}
const float *cbm_scene_triangle_segments(const cbm_scene *s)
{
    return s && s->tseg_on ? s->tseg.data : NULL;
}
size_t cbm_scene_part_count(const cbm_scene *s)
{
    return s->parts.len;
}
const cbm_part *cbm_scene_parts(const cbm_scene *s)
{
    return s->parts.data;
}
cbm_part *cbm_scene_part(cbm_scene *s, uint32_t id)
{
    return id < s->parts.len ? &s->parts.data[id] : NULL;
}

/* ---- lines ---- */

void cbm_scene_set_line_mode(cbm_scene *s, bool lines)
{
    if (s)
        s->line_mode = lines;
}

bool cbm_scene_line_mode(const cbm_scene *s)
{
    return s && s->line_mode;
}

cbm_status cbm_scene_add_line(cbm_scene *s, cbm_vec3 p0, cbm_vec3 p1, double width)
{
    if (!s || !(width >= 0.0) || !isfinite(width))
        return CBM_E_INVALID;
    if (index_full(s->lines.len))
        return CBM_E_LIMIT;
    CBM_TRY(ensure_part(s));
    cbm_scene_line l = {{(float)p0.x, (float)p0.y, (float)p0.z},
                        {(float)p1.x, (float)p1.y, (float)p1.z},
                        (float)width,
                        s->cur_part};
    return CBM_ARRAY_PUSH(s->ctx, s->lines, l);
}

size_t cbm_scene_line_count(const cbm_scene *s)
{
    return s->lines.len;
}

const cbm_scene_line *cbm_scene_lines(const cbm_scene *s)
{
    return s->lines.data;
}

static void grow_bounds(const float *p, double l[3], double h[3])
{
    for (int k = 0; k < 3; k++) {
        double v = p[k];
        if (v < l[k])
            l[k] = v;
        if (v > h[k])
            h[k] = v;
    }
}

bool cbm_scene_bounds(const cbm_scene *s, cbm_vec3 *lo, cbm_vec3 *hi)
{
    if (s->verts.len == 0 && s->lines.len == 0 && s->ninst == 0 && s->place.len == 0)
        return false;
    double l[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, h[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    for (size_t i = 0; i < s->verts.len; i++)
        grow_bounds(s->verts.data[i].p, l, h);
    for (size_t i = 0; i < s->lines.len; i++) {
        grow_bounds(s->lines.data[i].p0, l, h);
        grow_bounds(s->lines.data[i].p1, l, h);
    }
    cbm_scene_instance_cursor cur = {0};
    for (size_t i = 0; i < s->ninst; i++) {
        cbm_scene_instance inst;
        (void)cbm_scene_instance_read(s, i, &cur, &inst);
        const cbm_scene_instance *in = &inst;
        float r = in->a > in->b ? in->a : in->b;
        for (int e = 0; e < 2; e++)
            for (int k = 0; k < 3; k++) {
                const float *p = e ? in->p1 : in->p0;
                float q[3] = {p[0], p[1], p[2]};
                q[k] -= r;
                grow_bounds(q, l, h);
                q[k] += 2 * r;
                grow_bounds(q, l, h);
            }
    }
    for (size_t i = 0; i < s->place.len; i++) {
        const cbm_scene_placement *pl = &s->place.data[i];
        const shape_rec *r = &s->shapes.data[pl->shape];
        for (int c = 0; c < 8; c++) {
            float q[3] = {c & 1 ? r->hi[0] : r->lo[0], c & 2 ? r->hi[1] : r->lo[1],
                          c & 4 ? r->hi[2] : r->lo[2]};
            float w[3];
            for (int k = 0; k < 3; k++)
                w[k] = pl->o[k] + pl->x[k] * q[0] + pl->y[k] * q[1] + pl->z[k] * q[2];
            grow_bounds(w, l, h);
        }
    }
    if (lo)
        *lo = v3(l[0], l[1], l[2]);
    if (hi)
        *hi = v3(h[0], h[1], h[2]);
    return true;
}
