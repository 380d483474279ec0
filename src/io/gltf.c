/* glTF 2.0 binary (.glb) writer (Khronos glTF 2.0 specification, sections 3 and 4; GLB layout:
 * 12-byte header, JSON chunk padded with spaces, BIN chunk padded with zeros, all 4-aligned).
 *
 * The triangles of a scene are grouped per organ kind, and per branch order for branches; each
 * group becomes one mesh (one primitive, indexed, UNSIGNED_INT indices) under its own node named
 * "branch order 2", "leaf", ... with extras {organ, order}. Vertex attributes: POSITION (m),
 * NORMAL, COLOR_0 (linear RGBA of the colour mode) and the per-part data as application
 * attributes _STRESS_RATIO, _AGE (years), _REACTION_WOOD, _ORDER and _SEGMENT (FLOAT scalars;
 * -1 where unknown, since glTF floats must be finite). One material per organ kind, white base
 * colour (COLOR_0 multiplies it), double-sided for the flat organs (leaf, flower, ground).
 *
 * Animation (frames given): one node per frame holding that frame's group nodes. Every frame
 * node has a scale channel with STEP interpolation over the shared frame times: 1 while it is
 * the current frame, 0 otherwise. This is the form viewers handle best: morph targets need the
 * same vertex count in every frame (a growing plant does not have it), and KHR_node_visibility
 * is not yet supported widely, while STEP scale animations play in three.js, Blender, Babylon.js
 * and the Khronos sample viewer. Without playback, the static pose shows the last frame. */
#include "glb_internal.h"
#include "writers.h"

#include "cambium/io.h"

#include "../core/vecmath.h"

#include <math.h>
#include <stdio.h>

#define GL_FLOAT                5126
#define GL_UNSIGNED_INT         5125
#define GL_UNSIGNED_SHORT       5123
#define GL_ARRAY_BUFFER         34962
#define GL_ELEMENT_ARRAY_BUFFER 34963
#define MAX_ORDER_GROUPS        32
#define NO_GROUP                0xff

typedef cbm__gltf_accessor accessor;
typedef cbm__gltf_view view;

typedef struct mesh {
    size_t pos, nrm, col, stress, age, react, order, seg, idx;
    int material;
    size_t cmat1;  /* instanced (POSITION, NORMAL and indices only): colour material + 1 */
    size_t unit1;  /* instanced: its unit cylinder + 1 */
    size_t smesh1; /* instanced: its shape mesh + 1 */
} mesh;

/* The per-instance accessors of an instanced node (EXT_mesh_gpu_instancing). */
typedef struct inst_attrs {
    size_t tr, rot, scale, stress, age, react, order, seg;
} inst_attrs;

/* A unit cylinder or frustum of `sides` (rings at y = 0 and 1, radii 1 and taper), shared by
 * instances. */
typedef struct unit_mesh {
    int sides;
    float taper;
    size_t pos, nrm, idx;
} unit_mesh;

/* A shape of the scene (a predefined surface) written once for its placements, its triangles
 * reversed for the mirroring ones (flip), whose winding a viewer reverses. Per scene. */
typedef struct shape_mesh {
    uint32_t shape;
    bool flip;
    size_t pos, nrm, idx;
} shape_mesh;

/* A material of instanced meshes: the organ's, coloured by baseColorFactor (no COLOR_0). */
typedef struct color_mat {
    int organ;
    uint32_t key; /* 8-bit sRGB RGB and alpha */
    float rgba[4];
} color_mat;

/* Instances of one group, side count and colour, or placements of one group, shape, mirroring
 * and colour: one instanced node. */
typedef struct bucket {
    uint64_t key;
    float taper;   /* tubes; 0 for placements */
    int64_t shape; /* placements: the shape; -1 for tubes */
    bool flip;     /* placements: mirroring */
    int grp, sides;
    uint32_t part0;
    size_t count, start;
} bucket;

typedef struct node {
    char name[48];
    long mesh;             /* -1 if none */
    size_t child0, nchild; /* range in the children array */
    int organ, order;      /* -1 if not a group node */
    bool hidden;           /* scale 0 in the static pose */
    bool frame;
    size_t inst1; /* instanced: its inst_attrs + 1 */
} node;

/* Where the BIN chunk goes: kept in memory (an animation built frame by frame, whose scenes may
 * be gone when it is written), only measured (the first of the two passes of a direct write: the
 * JSON needs every offset and bound before the first byte of BIN), or streamed to the file (the
 * second pass, the same calls again). Streaming spares a buffer as large as the file. */
typedef enum { BIN_MEMORY, BIN_MEASURE, BIN_STREAM } bin_mode;

typedef struct glb {
    cbm_context *ctx;
    const cbm_write_options *o;
    CBM_ARRAY(uint8_t) bin; /* BIN_MEMORY only */
    size_t bin_len;         /* bytes of BIN so far, in every mode */
    bin_mode mode;
    cbm_out *sink; /* BIN_STREAM only */
    CBM_ARRAY(accessor) acc;
    CBM_ARRAY(view) views;
    CBM_ARRAY(mesh) meshes;
    CBM_ARRAY(node) nodes;
    CBM_ARRAY(size_t) children;
    bool organ_used[CBM_ORGAN_COUNT];
    /* scratch of add_scene_groups, kept from frame to frame and from the measuring pass to the
     * streaming one: its pages are touched once, not once a pass */
    CBM_ARRAY(uint32_t) remap, verts, idx;
    CBM_ARRAY(uint8_t) tgroup; /* per triangle: its group, or NO_GROUP when not kept */
    CBM_ARRAY(float) pval;     /* per part: its PART_VALUES part values (part_value) */
    CBM_ARRAY(float) fbuf;
    CBM_ARRAY(inst_attrs) insts;
    CBM_ARRAY(unit_mesh) units;
    CBM_ARRAY(shape_mesh) smeshes; /* of the scene being added */
    size_t smesh_mesh0;            /* its first mesh: the older ones are other scenes' */
    CBM_ARRAY(color_mat) cmats;
    CBM_ARRAY(bucket) buckets;
    CBM_ARRAY(uint32_t) ibucket, iorder, htab; /* scratch of the instance grouping */
    /* a direct write of one scene: the measuring pass keeps the parts' colours, the sorted
     * instances, each triangle's group (tgroup) and the groups' triangle counts, each vertex's
     * part and segment (keep), which the streaming pass of the same, unchanged scene reuses
     * (reuse) */
    bool keep, reuse;
    /* the part values _STRESS_RATIO, _AGE, _REACTION_WOOD, _ORDER that every part of the scene
     * has alike (part_same[q]), the instances' attribute written without reading them */
    bool part_same[4];
    float part_val[4];
    float *kept_col;
    size_t kept_np;
    uint32_t *kept_vpart;
    float *kept_vseg;
    size_t kept_nv;
    size_t kept_ntg[CBM_ORGAN_COUNT + MAX_ORDER_GROUPS];
} glb;

/* A view of `bytes` at the next 4-aligned offset of BIN, its padding written; its bytes follow
 * with bin_put. */
static cbm_status open_view(glb *g, size_t bytes, int target, size_t *id)
{
    size_t off = cbm__glb_pad4(g->bin_len);
    if (g->mode == BIN_MEMORY) {
        CBM_TRY(CBM_ARRAY_RESERVE(g->ctx, g->bin, off + bytes));
        memset(g->bin.data + g->bin.len, 0, off - g->bin.len);
        g->bin.len = off;
    } else if (g->mode == BIN_STREAM) {
        const uint8_t zero[4] = {0, 0, 0, 0};
        cbm_out_write(g->sink, zero, off - g->bin_len); /* errors surface at commit */
    }
    g->bin_len = off + bytes;
    view v = {off, bytes, target};
    CBM_TRY(CBM_ARRAY_PUSH(g->ctx, g->views, v));
    *id = g->views.len - 1;
    return CBM_OK;
}

/* Bytes of the view opened last (reserved by open_view). */
static void bin_put(glb *g, const void *data, size_t bytes)
{
    if (!bytes)
        return;
    if (g->mode == BIN_MEMORY) {
        memcpy(g->bin.data + g->bin.len, data, bytes);
        g->bin.len += bytes;
    } else if (g->mode == BIN_STREAM) {
        cbm_out_write(g->sink, data, bytes);
    }
}

static cbm_status add_view(glb *g, const void *data, size_t bytes, int target, size_t *id)
{
    CBM_TRY(open_view(g, bytes, target, id));
    bin_put(g, data, bytes);
    return CBM_OK;
}

static cbm_status add_accessor(glb *g, const void *data, size_t count, int ncomp, int ctype,
                               int target, bool minmax, size_t *id)
{
    size_t csize = ctype == GL_UNSIGNED_SHORT ? 2 : 4, v = 0;
    CBM_TRY(add_view(g, data, count * (size_t)ncomp * csize, target, &v));
    accessor a;
    cbm__gltf_accessor_set(&a, v, data, count, ncomp, ctype, minmax);
    CBM_TRY(CBM_ARRAY_PUSH(g->ctx, g->acc, a));
    *id = g->acc.len - 1;
    return CBM_OK;
}

static int group_of(const cbm_part *p)
{
    if (p->organ == CBM_ORGAN_BRANCH && p->order >= 0)
        return CBM_ORGAN_COUNT + (p->order < MAX_ORDER_GROUPS ? p->order : MAX_ORDER_GROUPS - 1);
    return (int)p->organ < CBM_ORGAN_COUNT ? (int)p->organ : CBM_ORGAN_OTHER;
}

static float known(double x)
{
    return isfinite(x) ? (float)x : -1.0f;
}

/* The per-part attributes in file order: _STRESS_RATIO, _AGE, _REACTION_WOOD, _ORDER, _SEGMENT. */
enum { PART_VALUES = 5 };

static float part_value(const cbm_part *p, int q)
{
    double x = q == 0   ? p->stress_ratio
               : q == 1 ? p->age
               : q == 2 ? p->reaction_wood
               : q == 3 ? (p->order >= 0 ? (double)p->order : NAN)
                        : (p->segment >= 0 ? (double)p->segment : NAN);
    return known(x);
}

/* The unit cylinder or frustum of `sides`: the rings of cbm_scene_tube_ring at y = 0 and y = 1
 * in the frame x = U, y = H, z = L = U x H, radii 1 and taper, normals those of the rings'
 * sections (as the scene's), its triangles wound as the scene's; written once. */
static cbm_status unit_cylinder(glb *g, int sides, float taper, size_t *unit)
{
    for (size_t i = 0; i < g->units.len; i++)
        if (g->units.data[i].sides == sides && g->units.data[i].taper == taper) {
            *unit = i;
            return CBM_OK;
        }
    size_t n = (size_t)sides;
    float *f = cbm__alloc(g->ctx, 6 * n * sizeof *f);
    uint16_t *ix = cbm__alloc(g->ctx, 6 * n * sizeof *ix);
    cbm_status st = f && ix ? CBM_OK : CBM_E_NOMEM;
    unit_mesh u = {sides, taper, 0, 0, 0};
    for (size_t y = 0; y < 2 && st == CBM_OK; y++)
        for (int k = 0; k < sides; k++) {
            double t = 2.0 * CBM_PI * k / sides, r = y ? (double)taper : 1.0;
            float *v = f + 3 * (y * n + (size_t)k);
            v[0] = (float)(r * cos(t));
            v[1] = (float)y;
            v[2] = (float)(r * sin(t));
        }
    if (st == CBM_OK)
        st = add_accessor(g, f, 2 * n, 3, GL_FLOAT, GL_ARRAY_BUFFER, true, &u.pos);
    for (size_t y = 0; y < 2 && st == CBM_OK; y++)
        for (int k = 0; k < sides; k++) {
            double t = 2.0 * CBM_PI * k / sides;
            float *v = f + 3 * (y * n + (size_t)k);
            v[0] = (float)cos(t);
            v[1] = 0.0f;
            v[2] = (float)sin(t);
        }
    if (st == CBM_OK)
        st = add_accessor(g, f, 2 * n, 3, GL_FLOAT, GL_ARRAY_BUFFER, false, &u.nrm);
    for (size_t i = 0; i < n && st == CBM_OK; i++) {
        uint16_t i0 = (uint16_t)i, i1 = (uint16_t)((i + 1) % n), m = (uint16_t)n;
        uint16_t *t = ix + 6 * i;
        t[0] = i0, t[1] = (uint16_t)(m + i1), t[2] = i1;
        t[3] = i0, t[4] = (uint16_t)(m + i0), t[5] = (uint16_t)(m + i1);
    }
    if (st == CBM_OK)
        st = add_accessor(g, ix, 6 * n, 1, GL_UNSIGNED_SHORT, GL_ELEMENT_ARRAY_BUFFER, false,
                          &u.idx);
    if (st == CBM_OK)
        st = CBM_ARRAY_PUSH(g->ctx, g->units, u);
    *unit = g->units.len - 1;
    cbm__free(g->ctx, f, 6 * n * sizeof *f);
    cbm__free(g->ctx, ix, 6 * n * sizeof *ix);
    return st;
}

/* 8-bit display sRGB and alpha of a clamped linear colour: the key of a colour material. */
static uint32_t color_key(const float *c)
{
    return ((uint32_t)cbm__srgb8(c[0]) << 24) | ((uint32_t)cbm__srgb8(c[1]) << 16) |
           ((uint32_t)cbm__srgb8(c[2]) << 8) | (uint32_t)(c[3] * 255.0f + 0.5f);
}

/* Sorts the kept instances of the scene into buckets (group, sides, colour), each bucket's
 * instances contiguous in g->iorder, the buckets numbered in order of first appearance. */
static size_t bucket_hash(uint64_t key, float taper, int64_t shape, size_t cap)
{
    uint32_t tb;
    memcpy(&tb, &taper, sizeof tb);
    key ^= ((uint64_t)tb << 17) ^ ((uint64_t)shape << 7);
    return (size_t)((key * 0x9E3779B97F4A7C15ull) >> 32) & (cap - 1);
}

/* The bucket table at twice its capacity, every bucket placed again. */
static cbm_status grow_bucket_table(glb *g, size_t *cap)
{
    *cap = *cap ? 2 * *cap : 64;
    CBM_TRY(CBM_ARRAY_RESERVE(g->ctx, g->htab, *cap));
    uint32_t *ht = g->htab.data;
    memset(ht, 0xff, *cap * sizeof *ht);
    for (size_t b = 0; b < g->buckets.len; b++) {
        const bucket *bk = &g->buckets.data[b];
        size_t h = bucket_hash(bk->key, bk->taper, 2 * bk->shape + bk->flip, *cap);
        while (ht[h] != UINT32_MAX)
            h = (h + 1) & (*cap - 1);
        ht[h] = (uint32_t)b;
    }
    return CBM_OK;
}

/* Whether a placement mirrors (its columns' determinant is negative). */
static bool mirrors(const cbm_scene_placement *p)
{
    cbm_vec3 x = v3(p->x[0], p->x[1], p->x[2]), y = v3(p->y[0], p->y[1], p->y[2]),
             z = v3(p->z[0], p->z[1], p->z[2]);
    return v3_dot(x, v3_cross(y, z)) < 0.0;
}

/* The tubes' instances are items 0 .. ni-1, the placements ni .. ni+np-1. */
static cbm_status sort_instances(glb *g, const cbm_scene *s, const float *col)
{
    size_t ni = cbm_scene_instance_count(s), npl = cbm_scene_placement_count(s);
    const cbm_scene_placement *pl = cbm_scene_placements(s);
    cbm_scene_instance_cursor cur = {0};
    cbm_scene_instance in = {0};
    const cbm_part *parts = cbm_scene_parts(s);
    g->buckets.len = 0;
    if (!ni && !npl)
        return CBM_OK;
    size_t cap = 0; /* sized by the buckets, not the instances: a few in most drawings */
    CBM_TRY(grow_bucket_table(g, &cap));
    CBM_TRY(CBM_ARRAY_RESERVE(g->ctx, g->ibucket, ni + npl));
    CBM_TRY(CBM_ARRAY_RESERVE(g->ctx, g->iorder, ni + npl));
    uint32_t *ib = g->ibucket.data;
    for (size_t i = 0; i < ni + npl; i++) {
        if (i < ni)
            CBM_TRY(cbm_scene_instance_read(s, i, &cur, &in));
        uint32_t part = i < ni ? in.part : pl[i - ni].part;
        const cbm_part *p = &parts[part];
        ib[i] = UINT32_MAX;
        if (!cbm__part_kept(p, g->o))
            continue;
        int grp = group_of(p);
        int sides = i < ni ? in.sides : 0;
        uint64_t key = ((uint64_t)grp << 48) | ((uint64_t)sides << 32) | color_key(col + 4 * part);
        float tp = i < ni ? in.taper : 0.0f;
        int64_t shape = i < ni ? -1 : (int64_t)pl[i - ni].shape;
        bool flip = i >= ni && mirrors(&pl[i - ni]);
        uint32_t *ht = g->htab.data;
        size_t h = bucket_hash(key, tp, 2 * shape + flip, cap);
        while (ht[h] != UINT32_MAX &&
               (g->buckets.data[ht[h]].key != key || g->buckets.data[ht[h]].taper != tp ||
                g->buckets.data[ht[h]].shape != shape || g->buckets.data[ht[h]].flip != flip))
            h = (h + 1) & (cap - 1);
        uint32_t id = ht[h];
        if (id == UINT32_MAX) {
            bucket b = {key, tp, shape, flip, grp, sides, part, 0, 0};
            CBM_TRY(CBM_ARRAY_PUSH(g->ctx, g->buckets, b));
            id = ht[h] = (uint32_t)(g->buckets.len - 1);
            if (2 * g->buckets.len > cap)
                CBM_TRY(grow_bucket_table(g, &cap));
        }
        ib[i] = id;
        g->buckets.data[id].count++;
    }
    size_t at = 0;
    for (size_t b = 0; b < g->buckets.len; b++) {
        g->buckets.data[b].start = at;
        at += g->buckets.data[b].count;
    }
    for (size_t i = 0; i < ni + npl; i++)
        if (ib[i] != UINT32_MAX)
            g->iorder.data[g->buckets.data[ib[i]].start++] = (uint32_t)i;
    for (size_t b = 0; b < g->buckets.len; b++)
        g->buckets.data[b].start -= g->buckets.data[b].count;
    return CBM_OK;
}

/* A shape of the scene as it is kept (positions, unit normals), its triangles reversed when
 * flip; written once a scene. */
static cbm_status shape_of_scene(glb *g, const cbm_scene *s, uint32_t shape, bool flip, size_t *id)
{
    for (size_t i = 0; i < g->smeshes.len; i++)
        if (g->smeshes.data[i].shape == shape && g->smeshes.data[i].flip == flip) {
            *id = i;
            return CBM_OK;
        }
    const float *pos, *nrm;
    const uint32_t *tri;
    size_t nv, nt;
    CBM_TRY(cbm_scene_shape_mesh(s, shape, &pos, &nrm, &nv, &tri, &nt));
    shape_mesh m = {shape, flip, 0, 0, 0};
    CBM_TRY(add_accessor(g, pos, nv, 3, GL_FLOAT, GL_ARRAY_BUFFER, true, &m.pos));
    CBM_TRY(add_accessor(g, nrm, nv, 3, GL_FLOAT, GL_ARRAY_BUFFER, false, &m.nrm));
    bool small = nv <= 65536;
    size_t bytes = 3 * nt * (small ? sizeof(uint16_t) : sizeof(uint32_t));
    void *ix = cbm__alloc(g->ctx, bytes ? bytes : 1);
    if (!ix)
        return CBM_E_NOMEM;
    for (size_t t = 0; t < nt; t++)
        for (int k = 0; k < 3; k++) {
            /* reversed: a, c, b */
            uint32_t v = tri[3 * t + (size_t)(flip && k ? 3 - k : k)];
            if (small)
                ((uint16_t *)ix)[3 * t + (size_t)k] = (uint16_t)v;
            else
                ((uint32_t *)ix)[3 * t + (size_t)k] = v;
        }
    cbm_status st = add_accessor(g, ix, 3 * nt, 1, small ? GL_UNSIGNED_SHORT : GL_UNSIGNED_INT,
                                 GL_ELEMENT_ARRAY_BUFFER, false, &m.idx);
    cbm__free(g->ctx, ix, bytes ? bytes : 1);
    CBM_TRY(st);
    CBM_TRY(CBM_ARRAY_PUSH(g->ctx, g->smeshes, m));
    *id = g->smeshes.len - 1;
    return CBM_OK;
}

/* The instanced mesh of a unit cylinder (shape < 0) or of a shape of the scene in a colour
 * material (shared by every node using it). */
static cbm_status instanced_mesh(glb *g, const cbm_scene *s, int organ, const bucket *bk,
                                 const float *rgba, size_t *id)
{
    size_t unit = 0, sm = 0, cm = 0, m0 = 0;
    if (bk->shape < 0)
        CBM_TRY(unit_cylinder(g, bk->sides, bk->taper, &unit));
    else {
        CBM_TRY(shape_of_scene(g, s, (uint32_t)bk->shape, bk->flip, &sm));
        m0 = g->smesh_mesh0;
    }
    uint32_t key = color_key(rgba);
    while (cm < g->cmats.len && (g->cmats.data[cm].organ != organ || g->cmats.data[cm].key != key))
        cm++;
    if (cm == g->cmats.len) {
        color_mat c = {organ, key, {rgba[0], rgba[1], rgba[2], rgba[3]}};
        CBM_TRY(CBM_ARRAY_PUSH(g->ctx, g->cmats, c));
    }
    size_t unit1 = bk->shape < 0 ? unit + 1 : 0, smesh1 = bk->shape < 0 ? 0 : sm + 1;
    for (size_t i = m0; i < g->meshes.len; i++)
        if (g->meshes.data[i].unit1 == unit1 && g->meshes.data[i].smesh1 == smesh1 &&
            g->meshes.data[i].cmat1 == cm + 1) {
            *id = i;
            return CBM_OK;
        }
    mesh m;
    memset(&m, 0, sizeof m);
    if (unit1) {
        m.pos = g->units.data[unit].pos;
        m.nrm = g->units.data[unit].nrm;
        m.idx = g->units.data[unit].idx;
    } else {
        m.pos = g->smeshes.data[sm].pos;
        m.nrm = g->smeshes.data[sm].nrm;
        m.idx = g->smeshes.data[sm].idx;
    }
    m.material = organ;
    m.cmat1 = cm + 1;
    m.unit1 = unit1;
    m.smesh1 = smesh1;
    CBM_TRY(CBM_ARRAY_PUSH(g->ctx, g->meshes, m));
    *id = g->meshes.len - 1;
    return CBM_OK;
}

/* The rotation of a tube instance: the unit tube's H along the axis, U the sections' U. */
static cbm_quat tube_rotation(const cbm_scene_instance *q)
{
    cbm_vec3 p0 = v3(q->p0[0], q->p0[1], q->p0[2]), p1 = v3(q->p1[0], q->p1[1], q->p1[2]);
    cbm_vec3 h = v3_normalize(v3_sub(p1, p0)), u = v3(q->u[0], q->u[1], q->u[2]);
    u = v3_normalize(v3_madd(u, h, -v3_dot(u, h)));
    return cbm__quat_of_columns(u, h, v3_cross(u, h));
}

/* The rotation and signed scales of a placement's orthogonal columns x, y, z: R = (x', y', z')
 * with x' = x / |x|, y' = y made orthogonal to x' and unit, z' = x' x y' (proper), and
 * (x y z) = R diag(sx, sy, sz), sz < 0 for a mirroring placement. */
static void placement_rs(const cbm_scene_placement *p, cbm_quat *r, double sc[3])
{
    cbm_vec3 x = v3(p->x[0], p->x[1], p->x[2]), y = v3(p->y[0], p->y[1], p->y[2]),
             z = v3(p->z[0], p->z[1], p->z[2]);
    sc[0] = v3_norm(x);
    cbm_vec3 cx = v3_scale(x, 1.0 / sc[0]);
    cbm_vec3 yp = v3_madd(y, cx, -v3_dot(y, cx));
    sc[1] = v3_norm(yp);
    cbm_vec3 cy = v3_scale(yp, 1.0 / sc[1]), cz = v3_cross(cx, cy);
    sc[2] = v3_dot(z, cz);
    *r = cbm__quat_of_columns(cx, cy, cz);
}

/* Per-instance attributes in file order: TRANSLATION, ROTATION, SCALE, then the part values
 * _STRESS_RATIO, _AGE, _REACTION_WOOD, _ORDER, _SEGMENT. */
enum { INST_ATTRS = 8, INST_CHUNK = 8192 };

static int inst_attr_ncomp(int q)
{
    return q == 1 ? 4 : q < 3 ? 3 : 1;
}

/* Attribute q of item `it` (a tube instance if it < ni, read with cursor c, else placement
 * it - ni) into d. */
static void inst_attr(const cbm_scene *s, cbm_scene_instance_cursor *c, uint32_t it, size_t ni,
                      int q, float *d)
{
    cbm_scene_instance tube;
    const cbm_scene_instance *in =
        it < ni && cbm_scene_instance_read(s, it, c, &tube) == CBM_OK ? &tube : NULL;
    const cbm_scene_placement *pl = it < ni ? NULL : &cbm_scene_placements(s)[it - ni];
    if (!in && !pl) /* not reached: it < ni */
        return;
    if (q >= 3) {
        /* a tube instance keeps its own segment id: its part may be shared */
        d[0] = in && q == 7 ? in->segment
                            : part_value(&cbm_scene_parts(s)[in ? in->part : pl->part], q - 3);
        return;
    }
    if (q == 0) {
        memcpy(d, in ? in->p0 : pl->o, 3 * sizeof(float));
        return;
    }
    cbm_quat r;
    double sc[3];
    if (in) {
        if (q == 1) {
            r = tube_rotation(in);
        } else {
            double dx = (double)in->p1[0] - in->p0[0], dy = (double)in->p1[1] - in->p0[1],
                   dz = (double)in->p1[2] - in->p0[2];
            d[0] = in->a;
            d[1] = (float)sqrt(dx * dx + dy * dy + dz * dz);
            d[2] = in->b;
            return;
        }
    } else {
        placement_rs(pl, &r, sc);
        if (q == 2) {
            for (int k = 0; k < 3; k++)
                d[k] = (float)sc[k];
            return;
        }
    }
    d[0] = (float)r.x, d[1] = (float)r.y, d[2] = (float)r.z, d[3] = (float)r.w;
}

/* The per-instance accessors of n items (ord): each written in chunks of INST_CHUNK items, so
 * that the scratch is a few pages rather than 16 bytes an instance. */
static cbm_status inst_accessors(glb *g, const cbm_scene *s, const uint32_t *ord, size_t n,
                                 inst_attrs *ia)
{
    size_t ni = cbm_scene_instance_count(s);
    size_t *dst[INST_ATTRS] = {&ia->tr,  &ia->rot,   &ia->scale, &ia->stress,
                               &ia->age, &ia->react, &ia->order, &ia->seg};
    bool fill = g->mode != BIN_MEASURE; /* no bounds needed: nothing to compute when measuring */
    for (int q = 0; q < INST_ATTRS; q++) {
        int nc = inst_attr_ncomp(q);
        accessor a;
        memset(&a, 0, sizeof a);
        CBM_TRY(open_view(g, n * (size_t)nc * sizeof(float), 0, &a.view));
        a.count = n;
        a.ncomp = nc;
        a.ctype = GL_FLOAT;
        /* the bucket's instances in increasing order: the cursor reads on */
        cbm_scene_instance_cursor cur = {0};
        bool same = q >= 3 && q < 7 && g->part_same[q - 3];
        for (size_t c0 = 0; fill && c0 < n; c0 += INST_CHUNK) {
            size_t m = n - c0 < INST_CHUNK ? n - c0 : INST_CHUNK;
            float *f = g->fbuf.data;
            for (size_t i = 0; i < m; i++)
                if (same)
                    f[i] = g->part_val[q - 3];
                else
                    inst_attr(s, &cur, ord[c0 + i], ni, q, f + (size_t)nc * i);
            bin_put(g, f, m * (size_t)nc * sizeof(float));
        }
        CBM_TRY(CBM_ARRAY_PUSH(g->ctx, g->acc, a));
        *dst[q] = g->acc.len - 1;
    }
    return CBM_OK;
}

/* One instanced node per bucket of group grp; their ids appended to g->children. */
static cbm_status add_instance_nodes(glb *g, const cbm_scene *s, const float *col, int grp,
                                     const char *group_name, size_t *count)
{
    *count = 0;
    for (size_t b = 0; b < g->buckets.len; b++) {
        const bucket *bk = &g->buckets.data[b];
        if (bk->grp != grp)
            continue;
        size_t n = bk->count, mid = 0;
        const uint32_t *ord = g->iorder.data + bk->start;
        int organ = grp >= CBM_ORGAN_COUNT ? CBM_ORGAN_BRANCH : grp;
        CBM_TRY(instanced_mesh(g, s, organ, bk, col + 4 * (size_t)bk->part0, &mid));
        CBM_TRY(CBM_ARRAY_RESERVE(g->ctx, g->fbuf, 4 * (n < INST_CHUNK ? n : INST_CHUNK)));
        inst_attrs ia;
        CBM_TRY(inst_accessors(g, s, ord, n, &ia));
        CBM_TRY(CBM_ARRAY_PUSH(g->ctx, g->insts, ia));
        node nd;
        memset(&nd, 0, sizeof nd);
        nd.mesh = (long)mid;
        nd.organ = nd.order = -1;
        nd.inst1 = g->insts.len;
        snprintf(nd.name, sizeof nd.name, "%.38s %s", group_name,
                 bk->shape >= 0 ? "surfaces" : "tubes");
        CBM_TRY(CBM_ARRAY_PUSH(g->ctx, g->nodes, nd));
        CBM_TRY(CBM_ARRAY_PUSH(g->ctx, g->children, g->nodes.len - 1));
        (*count)++;
    }
    return CBM_OK;
}

/* The per-vertex attributes of a group mesh in file order: POSITION, NORMAL, COLOR_0, then the
 * part values _STRESS_RATIO, _AGE, _REACTION_WOOD, _ORDER, _SEGMENT; written in chunks of
 * VERT_CHUNK vertices (and the indices in chunks of 3 VERT_CHUNK), so that the scratch is a few
 * pages rather than 16 bytes a vertex and 12 a triangle. */
enum { VERT_ATTRS = 8, VERT_CHUNK = 8192 };

/* Per vertex: its part (the part of the last triangle using it) and, for a scene whose
 * triangles keep their own segment ids, that triangle's (else NULL); per part, its values
 * (PART_VALUES a part, computed once a scene rather than once a vertex). */
typedef struct vertex_src {
    const uint32_t *part;
    const float *seg;
    const float *pval;
} vertex_src;

static cbm_status add_group_mesh(glb *g, const cbm_scene *s, const float *col, const vertex_src *vs,
                                 const uint8_t *tgroup, int grp, float *fbuf);

/* One node per non-empty group of the scene, with the mesh of its triangles and an instanced
 * child node per bucket of its instances; the group nodes' ids appended to children. */
static cbm_status add_scene_groups(glb *g, const cbm_scene *s, size_t *first_child, size_t *count)
{
    cbm_context *ctx = g->ctx;
    const cbm_write_options *o = g->o;
    size_t nv = cbm_scene_vertex_count(s), nt = cbm_scene_triangle_count(s);
    size_t np = cbm_scene_part_count(s);
    const cbm_part *parts = cbm_scene_parts(s);
    const uint32_t *tp = cbm_scene_triangle_parts(s);
    enum { NG = CBM_ORGAN_COUNT + MAX_ORDER_GROUPS };
    _Static_assert(NG < NO_GROUP, "a group is a byte");
    size_t ntg[NG] = {0};
    bool reuse = g->reuse && g->kept_col && g->kept_np == np && g->kept_vpart && g->kept_nv == nv;
    /* each triangle's group, once: every group's mesh then scans bytes, not parts */
    CBM_TRY(CBM_ARRAY_RESERVE(ctx, g->tgroup, nt ? nt : 1));
    uint8_t *tg = g->tgroup.data;
    if (reuse)
        memcpy(ntg, g->kept_ntg, sizeof ntg);
    for (size_t t = 0; t < nt && !reuse; t++) {
        const cbm_part *p = &parts[tp[t]];
        tg[t] = cbm__part_kept(p, o) ? (uint8_t)group_of(p) : NO_GROUP;
        if (tg[t] != NO_GROUP)
            ntg[tg[t]]++;
    }
    float *col = NULL, *fbuf = NULL, *vseg = NULL;
    uint32_t *vpart = NULL;
    const float *tseg = cbm_scene_triangle_segments(s);
    vertex_src vs = {NULL, NULL, NULL};
    size_t maxt = 0;
    for (int k = 0; k < NG; k++)
        maxt = ntg[k] > maxt ? ntg[k] : maxt;
    size_t cap_v = maxt > 0 ? 3 * maxt : 1;
    /* a group's vertices are at most 3 a triangle and at most the scene's: the index of each
     * by the smaller; the attributes and the indices go in chunks */
    size_t cap_gv = nv < cap_v ? (nv ? nv : 1) : cap_v;
    cbm_status st;
    g->smeshes.len = 0; /* shapes are the scene's */
    g->smesh_mesh0 = g->meshes.len;
    if (reuse) {
        col = g->kept_col;
        vpart = g->kept_vpart;
        vseg = g->kept_vseg;
    }
    if (!reuse && ((st = cbm__part_colors(ctx, s, o, &col, NULL, NULL)) != CBM_OK ||
                   (st = cbm__vertex_parts(ctx, s, &vpart)) != CBM_OK))
        goto done;
    if (tseg && !reuse) {
        /* the segment of the triangle cbm__vertex_parts took the part of: the last one */
        const uint32_t *tri = cbm_scene_triangles(s);
        if (!(vseg = cbm__alloc(ctx, (nv ? nv : 1) * sizeof *vseg))) {
            st = CBM_E_NOMEM;
            goto done;
        }
        for (size_t t = 0; t < nt; t++)
            for (int k = 0; k < 3; k++)
                vseg[tri[3 * t + (size_t)k]] = tseg[t];
    }
    if ((st = CBM_ARRAY_RESERVE(ctx, g->pval, PART_VALUES * (np ? np : 1))) != CBM_OK)
        goto done;
    for (size_t i = 0; i < np; i++)
        for (int q = 0; q < PART_VALUES; q++)
            g->pval.data[PART_VALUES * i + (size_t)q] = part_value(&parts[i], q);
    vs.part = vpart;
    vs.seg = vseg;
    vs.pval = g->pval.data;
    if ((st = CBM_ARRAY_RESERVE(ctx, g->remap, nv ? nv : 1)) != CBM_OK ||
        (st = CBM_ARRAY_RESERVE(ctx, g->verts, cap_gv)) != CBM_OK ||
        (st = CBM_ARRAY_RESERVE(ctx, g->idx, 3 * VERT_CHUNK)) != CBM_OK ||
        (st = CBM_ARRAY_RESERVE(ctx, g->fbuf, 4 * (cap_gv < VERT_CHUNK ? cap_gv : VERT_CHUNK))) !=
            CBM_OK)
        goto done;
    /* COLOR_0 is clamped to [0, 1]: once per part, not once per vertex */
    for (size_t i = 0; i < 4 * np && !reuse; i++)
        col[i] = fminf(1.0f, fmaxf(0.0f, col[i]));
    if (!reuse && (st = sort_instances(g, s, col)) != CBM_OK)
        goto done;
    for (int q = 0; q < 4; q++) {
        uint32_t b0 = 0, b;
        g->part_val[q] = np ? vs.pval[q] : 0.0f;
        memcpy(&b0, &g->part_val[q], sizeof b0);
        g->part_same[q] = true;
        for (size_t i = 1; i < np && g->part_same[q]; i++) {
            float v = vs.pval[PART_VALUES * i + (size_t)q];
            memcpy(&b, &v, sizeof b);
            g->part_same[q] = b == b0;
        }
    }
    if (g->keep && !reuse) {
        g->kept_col = col; /* freed with the writer */
        g->kept_np = np;
        g->kept_vpart = vpart;
        g->kept_vseg = vseg;
        g->kept_nv = nv;
        memcpy(g->kept_ntg, ntg, sizeof ntg);
        g->keep = false;
    }
    bool has_inst[NG] = {false};
    for (size_t b = 0; b < g->buckets.len; b++)
        has_inst[g->buckets.data[b].grp] = true;
    /* the group nodes' ids go to children last, contiguous (their instanced nodes come first) */
    size_t gids[NG], ng = 0;
    /* groups in a fixed order: branch orders, then the organs */
    for (int gi = 0; gi < NG; gi++) {
        int grp = gi < MAX_ORDER_GROUPS ? CBM_ORGAN_COUNT + gi : gi - MAX_ORDER_GROUPS;
        if (!ntg[grp] && !has_inst[grp])
            continue;
        node nd;
        memset(&nd, 0, sizeof nd);
        nd.mesh = -1;
        nd.organ = grp >= CBM_ORGAN_COUNT ? CBM_ORGAN_BRANCH : grp;
        nd.order = grp >= CBM_ORGAN_COUNT ? grp - CBM_ORGAN_COUNT : -1;
        if (nd.order >= 0)
            snprintf(nd.name, sizeof nd.name, "branch order %d", nd.order);
        else
            snprintf(nd.name, sizeof nd.name, "%s", cbm_organ_name((cbm_organ)nd.organ));
        fbuf = g->fbuf.data; /* the instances may have moved it */
        if (ntg[grp] && (st = add_group_mesh(g, s, col, &vs, tg, grp, fbuf)) != CBM_OK)
            goto done;
        if (ntg[grp])
            nd.mesh = (long)g->meshes.len - 1;
        nd.child0 = g->children.len;
        if (has_inst[grp] &&
            (st = add_instance_nodes(g, s, col, grp, nd.name, &nd.nchild)) != CBM_OK)
            goto done;
        if ((st = CBM_ARRAY_PUSH(ctx, g->nodes, nd)) != CBM_OK)
            goto done;
        gids[ng++] = g->nodes.len - 1;
    }
    *first_child = g->children.len;
    *count = ng;
    for (size_t k = 0; k < ng && st == CBM_OK; k++)
        st = CBM_ARRAY_PUSH(ctx, g->children, gids[k]);
done:
    if (col != g->kept_col)
        cbm__free(ctx, col, 4 * (np ? np : 1) * sizeof *col);
    if (vpart != g->kept_vpart)
        cbm__free(ctx, vpart, (nv ? nv : 1) * sizeof *vpart);
    if (vseg != g->kept_vseg)
        cbm__free(ctx, vseg, (nv ? nv : 1) * sizeof *vseg);
    return st;
}

/* Attribute q (VERT_ATTRS) of the group's vertices verts[0 .. n-1] into f. */
static void vertex_attr(const cbm_scene *s, const float *col, const vertex_src *vs,
                        const uint32_t *verts, size_t n, int q, float *f)
{
    const uint32_t *vpart = vs->part;
    const cbm_scene_vertex *v = cbm_scene_vertices(s);
    /* one loop per attribute, not a test of q per vertex */
    if (q == 0) {
        for (size_t i = 0; i < n; i++)
            memcpy(f + 3 * i, v[verts[i]].p, 3 * sizeof(float));
    } else if (q == 1) {
        for (size_t i = 0; i < n; i++) {
            const float *nr = v[verts[i]].n;
            double len =
                sqrt((double)nr[0] * nr[0] + (double)nr[1] * nr[1] + (double)nr[2] * nr[2]);
            for (int k = 0; k < 3; k++)
                f[3 * i + (size_t)k] = len > 0 ? (float)(nr[k] / len) : (k == 1 ? 1.0f : 0.0f);
        }
    } else if (q == 2) {
        for (size_t i = 0; i < n; i++)
            memcpy(f + 4 * i, col + 4 * (size_t)vpart[verts[i]], 4 * sizeof(float));
    } else if (q == 7 && vs->seg) {
        for (size_t i = 0; i < n; i++)
            f[i] = vs->seg[verts[i]];
    } else {
        const float *pv = vs->pval + (q - 3);
        for (size_t i = 0; i < n; i++)
            f[i] = pv[PART_VALUES * (size_t)vpart[verts[i]]];
    }
}

/* The triangles of group grp as one mesh (appended to g->meshes). */
static cbm_status add_group_mesh(glb *g, const cbm_scene *s, const float *col, const vertex_src *vs,
                                 const uint8_t *tgroup, int grp, float *fbuf)
{
    cbm_context *ctx = g->ctx;
    size_t nv = cbm_scene_vertex_count(s), nt = cbm_scene_triangle_count(s);
    const uint32_t *tri = cbm_scene_triangles(s);
    uint32_t *remap = g->remap.data, *verts = g->verts.data, *idx = g->idx.data;
    memset(remap, 0xff, (nv ? nv : 1) * sizeof *remap);
    size_t nvg = 0, ni = 0;
    for (size_t t = 0; t < nt; t++) {
        if (tgroup[t] != grp)
            continue;
        for (int k = 0; k < 3; k++) {
            uint32_t vi = tri[3 * t + (size_t)k];
            if (remap[vi] == UINT32_MAX) {
                remap[vi] = (uint32_t)nvg;
                verts[nvg++] = vi;
            }
        }
        ni += 3;
    }
    mesh m;
    memset(&m, 0, sizeof m);
    m.material = grp >= CBM_ORGAN_COUNT ? CBM_ORGAN_BRANCH : grp; /* organ; renumbered */
    g->organ_used[m.material] = true;
    size_t *dst[VERT_ATTRS] = {&m.pos, &m.nrm,   &m.col,   &m.stress,
                               &m.age, &m.react, &m.order, &m.seg};
    for (int q = 0; q < VERT_ATTRS; q++) {
        int nc = q == 2 ? 4 : q < 2 ? 3 : 1;
        /* POSITION's bounds: measuring needs them and nothing else; streaming, whose JSON is
         * written, does not take them again */
        bool bounds = q == 0 && g->mode != BIN_STREAM;
        accessor a;
        cbm__gltf_accessor_set(&a, 0, NULL, nvg, nc, GL_FLOAT, false);
        a.minmax = q == 0;
        for (int k = 0; k < nc; k++) {
            a.min[k] = INFINITY;
            a.max[k] = -INFINITY;
        }
        CBM_TRY(open_view(g, nvg * (size_t)nc * sizeof(float), GL_ARRAY_BUFFER, &a.view));
        for (size_t c0 = 0; (bounds || g->mode != BIN_MEASURE) && c0 < nvg; c0 += VERT_CHUNK) {
            size_t n = nvg - c0 < VERT_CHUNK ? nvg - c0 : VERT_CHUNK;
            vertex_attr(s, col, vs, verts + c0, n, q, fbuf);
            /* fminf and fmaxf as glibc's, without a call per value: the bound kept on a tie
             * (+0 against -0) and against a NaN */
            for (size_t i = 0; bounds && i < n; i++)
                for (int k = 0; k < nc; k++) {
                    float x = fbuf[i * (size_t)nc + (size_t)k];
                    a.min[k] = x < a.min[k] ? x : a.min[k];
                    a.max[k] = x > a.max[k] ? x : a.max[k];
                }
            bin_put(g, fbuf, n * (size_t)nc * sizeof(float));
        }
        CBM_TRY(CBM_ARRAY_PUSH(ctx, g->acc, a));
        *dst[q] = g->acc.len - 1;
    }
    /* the indices: the group's triangles again, through the complete remap */
    accessor a;
    cbm__gltf_accessor_set(&a, 0, NULL, ni, 1, GL_UNSIGNED_INT, false);
    CBM_TRY(open_view(g, ni * sizeof(uint32_t), GL_ELEMENT_ARRAY_BUFFER, &a.view));
    size_t n = 0;
    for (size_t t = 0; g->mode != BIN_MEASURE && t < nt; t++) {
        if (tgroup[t] != grp)
            continue;
        for (int k = 0; k < 3; k++)
            idx[n++] = remap[tri[3 * t + (size_t)k]];
        if (n + 3 > 3 * VERT_CHUNK) {
            bin_put(g, idx, n * sizeof *idx);
            n = 0;
        }
    }
    bin_put(g, idx, n * sizeof *idx);
    CBM_TRY(CBM_ARRAY_PUSH(ctx, g->acc, a));
    m.idx = g->acc.len - 1;
    return CBM_ARRAY_PUSH(ctx, g->meshes, m);
}

static void write_json(glb *g, cbm_json *j, size_t root, long anim_input, size_t anim_first,
                       size_t nframes)
{
    cbm_json_begin_object(j, NULL);
    cbm_json_begin_object(j, "asset");
    cbm_json_string(j, "version", "2.0");
    cbm_json_string(j, "generator", "cambium " CBM_VERSION_STRING);
    cbm_json_end_object(j);
    if (g->insts.len) {
        /* required: a viewer without it would draw one tube per instanced node */
        for (int r = 0; r < 2; r++) {
            cbm_json_begin_array(j, r ? "extensionsRequired" : "extensionsUsed");
            cbm_json_string(j, NULL, "EXT_mesh_gpu_instancing");
            cbm_json_end_array(j);
        }
    }
    cbm_json_int(j, "scene", 0);
    cbm_json_begin_array(j, "scenes");
    cbm_json_begin_object(j, NULL);
    cbm_json_string(j, "name", "plant");
    cbm_json_begin_array(j, "nodes");
    cbm_json_int(j, NULL, (int64_t)root);
    cbm_json_end_array(j);
    cbm_json_end_object(j);
    cbm_json_end_array(j);

    cbm_json_begin_array(j, "nodes");
    for (size_t i = 0; i < g->nodes.len; i++) {
        const node *n = &g->nodes.data[i];
        cbm_json_begin_object(j, NULL);
        cbm_json_string(j, "name", n->name);
        if (n->mesh >= 0)
            cbm_json_int(j, "mesh", n->mesh);
        if (n->nchild) {
            cbm_json_begin_array(j, "children");
            for (size_t c = 0; c < n->nchild; c++)
                cbm_json_int(j, NULL, (int64_t)g->children.data[n->child0 + c]);
            cbm_json_end_array(j);
        }
        if (n->hidden) {
            const float z[3] = {0, 0, 0};
            cbm__gltf_json_floats(j, "scale", z, 3);
        }
        if (n->inst1) {
            const inst_attrs *ia = &g->insts.data[n->inst1 - 1];
            cbm_json_begin_object(j, "extensions");
            cbm_json_begin_object(j, "EXT_mesh_gpu_instancing");
            cbm_json_begin_object(j, "attributes");
            cbm_json_int(j, "TRANSLATION", (int64_t)ia->tr);
            cbm_json_int(j, "ROTATION", (int64_t)ia->rot);
            cbm_json_int(j, "SCALE", (int64_t)ia->scale);
            cbm_json_int(j, "_STRESS_RATIO", (int64_t)ia->stress);
            cbm_json_int(j, "_AGE", (int64_t)ia->age);
            cbm_json_int(j, "_REACTION_WOOD", (int64_t)ia->react);
            cbm_json_int(j, "_ORDER", (int64_t)ia->order);
            cbm_json_int(j, "_SEGMENT", (int64_t)ia->seg);
            cbm_json_end_object(j);
            cbm_json_end_object(j);
            cbm_json_end_object(j);
        }
        if (n->organ >= 0) {
            cbm_json_begin_object(j, "extras");
            cbm_json_string(j, "organ", cbm_organ_name((cbm_organ)n->organ));
            if (n->order >= 0)
                cbm_json_int(j, "order", n->order);
            cbm_json_end_object(j);
        } else if (i == root) {
            cbm_json_begin_object(j, "extras");
            cbm_json_string(j, "units", "m");
            cbm_json_string(j, "up", "+y");
            cbm_json_string(j, "unknown_attribute_value", "-1");
            cbm_json_end_object(j);
        }
        cbm_json_end_object(j);
    }
    cbm_json_end_array(j);

    if (g->meshes.len) {
        cbm_json_begin_array(j, "meshes");
        for (size_t i = 0; i < g->meshes.len; i++) {
            const mesh *m = &g->meshes.data[i];
            cbm_json_begin_object(j, NULL);
            cbm_json_begin_array(j, "primitives");
            cbm_json_begin_object(j, NULL);
            cbm_json_begin_object(j, "attributes");
            cbm_json_int(j, "POSITION", (int64_t)m->pos);
            cbm_json_int(j, "NORMAL", (int64_t)m->nrm);
            if (!m->cmat1) {
                cbm_json_int(j, "COLOR_0", (int64_t)m->col);
                cbm_json_int(j, "_STRESS_RATIO", (int64_t)m->stress);
                cbm_json_int(j, "_AGE", (int64_t)m->age);
                cbm_json_int(j, "_REACTION_WOOD", (int64_t)m->react);
                cbm_json_int(j, "_ORDER", (int64_t)m->order);
                cbm_json_int(j, "_SEGMENT", (int64_t)m->seg);
            }
            cbm_json_end_object(j);
            cbm_json_int(j, "indices", (int64_t)m->idx);
            /* the organs' materials, then the colour materials of the instanced meshes */
            int mat = 0;
            for (int k = 0; k < (m->cmat1 ? CBM_ORGAN_COUNT : m->material); k++)
                mat += g->organ_used[k];
            if (m->cmat1)
                mat += (int)m->cmat1 - 1;
            cbm_json_int(j, "material", mat);
            cbm_json_int(j, "mode", 4);
            cbm_json_end_object(j);
            cbm_json_end_array(j);
            cbm_json_end_object(j);
        }
        cbm_json_end_array(j);
        cbm_json_begin_array(j, "materials");
        for (int k = 0; k < CBM_ORGAN_COUNT; k++) {
            if (!g->organ_used[k])
                continue;
            cbm_json_begin_object(j, NULL);
            cbm_json_string(j, "name", cbm_organ_name((cbm_organ)k));
            cbm_json_begin_object(j, "pbrMetallicRoughness");
            const float white[4] = {1, 1, 1, 1};
            cbm__gltf_json_floats(j, "baseColorFactor", white, 4);
            cbm_json_number(j, "metallicFactor", 0.0);
            cbm_json_number(j, "roughnessFactor", k == CBM_ORGAN_FRUIT ? 0.45 : 0.85);
            cbm_json_end_object(j);
            if (k == CBM_ORGAN_LEAF || k == CBM_ORGAN_FLOWER || k == CBM_ORGAN_GROUND)
                cbm_json_bool(j, "doubleSided", true);
            cbm_json_end_object(j);
        }
        for (size_t c = 0; c < g->cmats.len; c++) {
            const color_mat *cm = &g->cmats.data[c];
            cbm_json_begin_object(j, NULL);
            cbm_json_string(j, "name", cbm_organ_name((cbm_organ)cm->organ));
            cbm_json_begin_object(j, "pbrMetallicRoughness");
            cbm__gltf_json_floats(j, "baseColorFactor", cm->rgba, 4);
            cbm_json_number(j, "metallicFactor", 0.0);
            cbm_json_number(j, "roughnessFactor", cm->organ == CBM_ORGAN_FRUIT ? 0.45 : 0.85);
            cbm_json_end_object(j);
            if (cm->organ == CBM_ORGAN_LEAF || cm->organ == CBM_ORGAN_FLOWER ||
                cm->organ == CBM_ORGAN_GROUND)
                cbm_json_bool(j, "doubleSided", true);
            cbm_json_end_object(j);
        }
        cbm_json_end_array(j);
    }
    if (g->acc.len)
        cbm__gltf_json_buffers(j, g->acc.data, g->acc.len, g->views.data, g->views.len, g->bin_len);
    if (anim_input >= 0) {
        cbm_json_begin_array(j, "animations");
        cbm_json_begin_object(j, NULL);
        cbm_json_string(j, "name", "growth");
        cbm_json_begin_array(j, "channels");
        for (size_t f = 0; f < nframes; f++) {
            cbm_json_begin_object(j, NULL);
            cbm_json_int(j, "sampler", (int64_t)f);
            cbm_json_begin_object(j, "target");
            cbm_json_int(j, "node", (int64_t)(anim_first + f));
            cbm_json_string(j, "path", "scale");
            cbm_json_end_object(j);
            cbm_json_end_object(j);
        }
        cbm_json_end_array(j);
        cbm_json_begin_array(j, "samplers");
        for (size_t f = 0; f < nframes; f++) {
            cbm_json_begin_object(j, NULL);
            cbm_json_int(j, "input", anim_input);
            cbm_json_int(j, "output", anim_input + 1 + (long)f);
            cbm_json_string(j, "interpolation", "STEP");
            cbm_json_end_object(j);
        }
        cbm_json_end_array(j);
        cbm_json_end_object(j);
        cbm_json_end_array(j);
    }
    cbm_json_end_object(j);
}

struct cbm_animation {
    glb g;
    cbm_write_options o;      /* a copy: g.o points here */
    CBM_ARRAY(size_t) frames; /* per frame: first group node in children, group count */
    bool animated, finished;
    const cbm_scene *const *frame_src; /* a direct write's scenes (cbm_write_glb), NULL otherwise */
    size_t frame_src_count;
};

cbm_status cbm_animation_create(cbm_context *ctx, const cbm_write_options *opts,
                                cbm_animation **out)
{
    if (!ctx || !out)
        return CBM_E_INVALID;
    *out = NULL;
    cbm_animation *a = cbm__calloc(ctx, 1, sizeof *a);
    if (!a)
        return CBM_E_NOMEM;
    a->o = opts ? *opts : cbm_write_options_default();
    a->o.frames = NULL;
    a->o.frame_count = 0;
    if (!(a->o.frame_time > 0)) {
        cbm__free(ctx, a, sizeof *a);
        return cbm__fail(ctx, CBM_E_INVALID, "glTF animation: frame_time must be > 0 s");
    }
    a->g.ctx = ctx;
    a->g.o = &a->o;
    a->animated = true;
    *out = a;
    return CBM_OK;
}

void cbm_animation_destroy(cbm_animation *a)
{
    if (!a)
        return;
    cbm_context *ctx = a->g.ctx;
    CBM_ARRAY_FREE(ctx, a->g.bin);
    CBM_ARRAY_FREE(ctx, a->g.acc);
    CBM_ARRAY_FREE(ctx, a->g.views);
    CBM_ARRAY_FREE(ctx, a->g.meshes);
    CBM_ARRAY_FREE(ctx, a->g.nodes);
    CBM_ARRAY_FREE(ctx, a->g.children);
    CBM_ARRAY_FREE(ctx, a->frames);
    CBM_ARRAY_FREE(ctx, a->g.remap);
    CBM_ARRAY_FREE(ctx, a->g.tgroup);
    CBM_ARRAY_FREE(ctx, a->g.pval);
    CBM_ARRAY_FREE(ctx, a->g.verts);
    CBM_ARRAY_FREE(ctx, a->g.idx);
    CBM_ARRAY_FREE(ctx, a->g.fbuf);
    CBM_ARRAY_FREE(ctx, a->g.insts);
    CBM_ARRAY_FREE(ctx, a->g.smeshes);
    CBM_ARRAY_FREE(ctx, a->g.units);
    CBM_ARRAY_FREE(ctx, a->g.cmats);
    CBM_ARRAY_FREE(ctx, a->g.buckets);
    CBM_ARRAY_FREE(ctx, a->g.ibucket);
    CBM_ARRAY_FREE(ctx, a->g.iorder);
    CBM_ARRAY_FREE(ctx, a->g.htab);
    cbm__free(ctx, a->g.kept_col, 4 * (a->g.kept_np ? a->g.kept_np : 1) * sizeof(float));
    size_t knv = a->g.kept_nv ? a->g.kept_nv : 1;
    cbm__free(ctx, a->g.kept_vpart, knv * sizeof *a->g.kept_vpart);
    cbm__free(ctx, a->g.kept_vseg, knv * sizeof *a->g.kept_vseg);
    cbm__free(ctx, a, sizeof *a);
}

cbm_status cbm_animation_add_frame(cbm_animation *a, const cbm_scene *scene)
{
    if (!a || !scene || a->finished)
        return CBM_E_INVALID;
    if (cbm_scene_line_count(scene) > 0) /* a mesh has no pixel lines: refuse, not drop */
        return cbm__fail(a->g.ctx, CBM_E_UNSUPPORTED,
                         "animation frame: the scene holds %zu pixel lines, which only pictures "
                         "draw; interpret the model with line mode off for a mesh",
                         cbm_scene_line_count(scene));
    size_t first = 0, cnt = 0;
    CBM_TRY(CBM_ARRAY_RESERVE(a->g.ctx, a->frames, a->frames.len + 2));
    CBM_TRY(add_scene_groups(&a->g, scene, &first, &cnt));
    a->frames.data[a->frames.len++] = first;
    a->frames.data[a->frames.len++] = cnt;
    return CBM_OK;
}

size_t cbm_animation_frame_count(const cbm_animation *a)
{
    return a ? a->frames.len / 2 : 0;
}

/* Frame nodes, the root and the animation accessors, after the last frame. */
static cbm_status finish(cbm_animation *a, size_t *root, long *anim_input, size_t *anim_first,
                         size_t *nframes)
{
    glb *g = &a->g;
    cbm_context *ctx = g->ctx;
    size_t nf = a->frames.len / 2;
    cbm_status st = CBM_OK;
    *nframes = 0;
    *anim_input = -1;
    node r;
    memset(&r, 0, sizeof r);
    snprintf(r.name, sizeof r.name, "plant");
    r.mesh = -1;
    r.organ = r.order = -1;
    if (!a->animated) {
        r.child0 = nf ? a->frames.data[0] : 0;
        r.nchild = nf ? a->frames.data[1] : 0;
        CBM_TRY(CBM_ARRAY_PUSH(ctx, g->nodes, r));
        *root = g->nodes.len - 1;
        return CBM_OK;
    }
    *anim_first = g->nodes.len;
    for (size_t f = 0; f < nf && st == CBM_OK; f++) {
        node fn;
        memset(&fn, 0, sizeof fn);
        snprintf(fn.name, sizeof fn.name, "frame %zu", f);
        fn.mesh = -1;
        fn.organ = fn.order = -1;
        fn.child0 = a->frames.data[2 * f];
        fn.nchild = a->frames.data[2 * f + 1];
        fn.hidden = f + 1 < nf;
        fn.frame = true;
        st = CBM_ARRAY_PUSH(ctx, g->nodes, fn);
    }
    size_t c0 = g->children.len;
    for (size_t f = 0; f < nf && st == CBM_OK; f++)
        st = CBM_ARRAY_PUSH(ctx, g->children, *anim_first + f);
    r.child0 = c0;
    r.nchild = nf;
    if (st == CBM_OK)
        st = CBM_ARRAY_PUSH(ctx, g->nodes, r);
    *root = g->nodes.len - 1;
    if (st != CBM_OK || nf == 0)
        return st;
    /* times, then one scale track per frame node (1 in its slot, 0 elsewhere) */
    float *buf = cbm__alloc(ctx, 3 * nf * sizeof *buf);
    if (!buf)
        return CBM_E_NOMEM;
    size_t id = 0;
    for (size_t f = 0; f < nf; f++)
        buf[f] = (float)(a->o.frame_time * (double)f);
    st = add_accessor(g, buf, nf, 1, GL_FLOAT, 0, true, &id);
    *anim_input = (long)id;
    for (size_t f = 0; f < nf && st == CBM_OK; f++) {
        for (size_t k = 0; k < nf; k++)
            buf[3 * k] = buf[3 * k + 1] = buf[3 * k + 2] = k == f ? 1.0f : 0.0f;
        st = add_accessor(g, buf, nf, 3, GL_FLOAT, 0, false, &id);
    }
    cbm__free(ctx, buf, 3 * nf * sizeof *buf);
    *nframes = nf;
    return st;
}

/* Opens the file and writes the GLB header, the JSON chunk and the BIN chunk's header for a BIN
 * of g->bin_len bytes (none when BIN is empty); the caller writes BIN, then cbm__glb_bin_tail. */
static cbm_status open_glb(glb *g, const char *path, const char *text, size_t tlen, cbm_out **out)
{
    return cbm__glb_open(g->ctx, path, "scene", text, tlen, g->bin_len, g->bin_len > 0, out);
}

/* The frame nodes and the JSON text of a finished animation (j holds the text). */
static cbm_status finish_json(cbm_animation *a, cbm_json **j, const char **text, size_t *tlen)
{
    size_t root = 0, anim_first = 0, nframes = 0;
    long anim_input = -1;
    *j = NULL;
    CBM_TRY(finish(a, &root, &anim_input, &anim_first, &nframes));
    CBM_TRY(cbm_json_create(a->g.ctx, j));
    write_json(&a->g, *j, root, anim_input, anim_first, nframes);
    return cbm_json_text(*j, text, tlen);
}

cbm_status cbm_animation_write(cbm_animation *a, const char *path)
{
    if (!a || !path || a->finished)
        return CBM_E_INVALID;
    a->finished = true;
    glb *g = &a->g;
    cbm_json *j = NULL;
    const char *text = NULL;
    size_t tlen = 0;
    cbm_out *out = NULL;
    cbm_status st = finish_json(a, &j, &text, &tlen);
    if (st == CBM_OK)
        st = open_glb(g, path, text, tlen, &out);
    if (st == CBM_OK) {
        cbm_out_write(out, g->bin.data, g->bin.len);
        cbm__glb_bin_tail(out, g->bin_len);
        st = cbm_out_commit(out);
    }
    cbm_json_destroy(j);
    return st;
}

/* Adds the frames of a direct write (one scene, or the options' frames). */
static cbm_status add_frames(cbm_animation *a, const cbm_scene *scene, const char *path)
{
    size_t nf = a->animated ? a->frame_src_count : 1;
    for (size_t f = 0; f < nf; f++) {
        const cbm_scene *s = a->animated ? a->frame_src[f] : scene;
        if (!s)
            return cbm__fail(a->g.ctx, CBM_E_INVALID, "%s: animation frame %zu has no scene", path,
                             f);
        CBM_TRY(cbm_animation_add_frame(a, s));
    }
    return CBM_OK;
}

/* Forgets what the measuring pass recorded, so that the streaming pass records it again. */
static void rewind_glb(cbm_animation *a)
{
    glb *g = &a->g;
    g->acc.len = g->views.len = g->meshes.len = g->nodes.len = g->children.len = 0;
    g->insts.len = g->units.len = g->cmats.len = g->smeshes.len = 0;
    a->frames.len = 0;
    g->bin_len = 0;
    memset(g->organ_used, 0, sizeof g->organ_used);
}

cbm_status cbm_write_glb(cbm_context *ctx, const cbm_scene *scene, const char *path,
                         const cbm_write_options *opts)
{
    if (!ctx || !path)
        return CBM_E_INVALID;
    cbm_write_options def;
    const cbm_write_options *o = cbm__opts(opts, &def);
    bool anim = o->frames && o->frame_count > 0;
    if (!scene && !anim)
        return cbm__fail(ctx, CBM_E_INVALID, "%s: no scene to write", path);
    cbm_write_options copy = *o;
    if (!anim && !(copy.frame_time > 0))
        copy.frame_time = 1.0; /* unused without animation */
    cbm_animation *a;
    CBM_TRY(cbm_animation_create(ctx, &copy, &a));
    /* cbm_animation_create set a (CBM_TRY returned otherwise) */
    // NOLINTNEXTLINE(clang-analyzer-core.NullDereference)
    a->animated = anim;
    a->frame_src = anim ? o->frames : NULL;
    a->frame_src_count = anim ? o->frame_count : 0;
    /* Every scene is at hand: measure BIN in a first pass (for the JSON), then stream it. */
    glb *g = &a->g;
    g->mode = BIN_MEASURE;
    g->keep = !anim; /* one scene, unchanged between the passes */
    cbm_json *j = NULL;
    const char *text = NULL;
    size_t tlen = 0;
    cbm_out *out = NULL;
    cbm_status st = add_frames(a, scene, path);
    if (st == CBM_OK)
        st = finish_json(a, &j, &text, &tlen);
    if (st == CBM_OK)
        st = open_glb(g, path, text, tlen, &out);
    size_t measured = g->bin_len;
    if (st == CBM_OK) {
        rewind_glb(a);
        g->mode = BIN_STREAM;
        g->sink = out;
        g->reuse = g->kept_col != NULL;
        st = add_frames(a, scene, path);
        size_t root = 0, anim_first = 0, nframes = 0;
        long anim_input = -1;
        if (st == CBM_OK)
            st = finish(a, &root, &anim_input, &anim_first, &nframes);
        if (st == CBM_OK && g->bin_len != measured)
            st = cbm__fail(ctx, CBM_E_INTERNAL, "%s: BIN chunk of %zu bytes measured as %zu", path,
                           g->bin_len, measured);
        if (st == CBM_OK) {
            cbm__glb_bin_tail(out, g->bin_len);
            st = cbm_out_commit(out);
        } else {
            cbm_out_abort(out);
        }
    }
    cbm_json_destroy(j);
    cbm_animation_destroy(a);
    return st;
}
