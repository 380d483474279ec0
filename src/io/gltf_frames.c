/* The motion of a model's drawn parts (cambium/turtle_motion.h): frames recorded from the
 * turtle's primitive record, written as a CSV table and as an animated glTF 2.0 binary.
 *
 * Each segment (cylinder, cone, generalized-cylinder piece) and sphere of the first frame is a
 * rigid part. A segment's frame is built from its axis: H along p1 - p0, U the turtle's up made
 * perpendicular to it, L = U x H; a sphere keeps the world axes. The part's mesh is built once,
 * in that frame (a segment along +x from the origin, a sphere about the origin), and its node
 * gets per-frame translation (p0) and rotation (the frame as a unit quaternion) keys with
 * LINEAR interpolation (slerp for rotations; consecutive quaternions are kept in the same
 * hemisphere so the slerp takes the short way). Node TRS animation rather than per-frame
 * meshes (the growth animation of gltf.c) or morph targets: a moving structure keeps its parts,
 * so 7 floats per part and frame describe it exactly, where a mesh per frame costs hundreds of
 * vertices per part and frame, and morph targets need one target per frame, which viewers
 * (three.js among them) handle only in small numbers. Translation and rotation channels play in
 * three.js, Blender, Babylon.js and the Khronos sample viewer.
 *
 * Parts with equal shape and colour share one mesh and one material. The writer uses the io
 * layer's JSON builder and atomic output (cbm_json, cbm_out), and the accessors, buffer views and
 * GLB framing it shares with gltf.c (the scene and growth-animation writer) in glb.c; it keeps
 * its BIN in memory. */
#include "cambium/turtle_motion.h"

#include "cambium/io.h"
#include "cambium/write.h"

#include "../core/core.h"
#include "../core/vecmath.h"
#include "glb_internal.h"
#include "writers.h"

#include <math.h>
#include <stdio.h>

#define GL_FLOAT        5126
#define GL_UNSIGNED_INT 5125
#define CYL_SIDES       12
#define SPHERE_SLICES   12
#define SPHERE_STACKS   8

typedef struct body {
    bool sphere;
    double len, r0, r1; /* model units */
    float rgba[4];
} body;

/* per frame and part: p0, p1, rotation (w x y z) */
enum { POSE = 10 };

struct cbm_turtle_motion {
    cbm_context *ctx;
    CBM_ARRAY(body) bodies;
    CBM_ARRAY(double) pose;
    CBM_ARRAY(double) times;
    CBM_ARRAY(long) steps;
};

cbm_status cbm_turtle_motion_create(cbm_context *ctx, cbm_turtle_motion **out)
{
    if (!ctx || !out)
        return CBM_E_INVALID;
    *out = cbm__calloc(ctx, 1, sizeof **out);
    if (!*out)
        return CBM_E_NOMEM;
    (*out)->ctx = ctx;
    return CBM_OK;
}

void cbm_turtle_motion_destroy(cbm_turtle_motion *m)
{
    if (!m)
        return;
    CBM_ARRAY_FREE(m->ctx, m->bodies);
    CBM_ARRAY_FREE(m->ctx, m->pose);
    CBM_ARRAY_FREE(m->ctx, m->times);
    CBM_ARRAY_FREE(m->ctx, m->steps);
    cbm__free(m->ctx, m, sizeof *m);
}

size_t cbm_turtle_motion_frame_count(const cbm_turtle_motion *m)
{
    return m ? m->times.len : 0;
}

size_t cbm_turtle_motion_part_count(const cbm_turtle_motion *m)
{
    return m ? m->bodies.len : 0;
}

static bool recorded(const cbm_prim *p)
{
    return p->kind == CBM_PRIM_CYLINDER || p->kind == CBM_PRIM_GCYL || p->kind == CBM_PRIM_SPHERE;
}

/* Rotation matrix with columns h, l, u -> unit quaternion (Shepperd's method); gltf.c's
 * instances use it too. */
cbm_quat cbm__quat_of_columns(cbm_vec3 h, cbm_vec3 l, cbm_vec3 u)
{
    double m00 = h.x, m10 = h.y, m20 = h.z, m01 = l.x, m11 = l.y, m21 = l.z, m02 = u.x, m12 = u.y,
           m22 = u.z;
    double tr = m00 + m11 + m22;
    cbm_quat q;
    if (tr > 0) {
        double s = 2 * sqrt(tr + 1);
        q = (cbm_quat){s / 4, (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s};
    } else if (m00 > m11 && m00 > m22) {
        double s = 2 * sqrt(1 + m00 - m11 - m22);
        q = (cbm_quat){(m21 - m12) / s, s / 4, (m01 + m10) / s, (m02 + m20) / s};
    } else if (m11 > m22) {
        double s = 2 * sqrt(1 + m11 - m00 - m22);
        q = (cbm_quat){(m02 - m20) / s, (m01 + m10) / s, s / 4, (m12 + m21) / s};
    } else {
        double s = 2 * sqrt(1 + m22 - m00 - m11);
        q = (cbm_quat){(m10 - m01) / s, (m02 + m20) / s, (m12 + m21) / s, s / 4};
    }
    return q_normalize(q);
}

/* The frame of a segment: H along its axis, U the turtle's up made perpendicular to it. */
static cbm_quat segment_rotation(const cbm_prim *p)
{
    cbm_vec3 h = v3_normalize(v3_sub(p->p1, p->p0));
    cbm_vec3 up = p->frame.u;
    cbm_vec3 u = v3_madd(up, h, -v3_dot(up, h));
    if (v3_norm2(u) < 1e-20) {
        cbm_vec3 a = fabs(h.x) < 0.9 ? v3(1, 0, 0) : v3(0, 1, 0);
        u = v3_madd(a, h, -v3_dot(a, h));
    }
    u = v3_normalize(u);
    return cbm__quat_of_columns(h, v3_cross(u, h), u);
}

cbm_status cbm_turtle_motion_add_frame(cbm_turtle_motion *m, const cbm_turtle *t,
                                       const cbm_scene *scene, double time_s, long step)
{
    if (!m || !t)
        return CBM_E_INVALID;
    cbm_context *ctx = m->ctx;
    size_t np = cbm_turtle_prim_count(t), nf = m->times.len;
    const cbm_prim *pr = cbm_turtle_prims(t);
    size_t count = 0;
    for (size_t i = 0; i < np; i++)
        count += recorded(&pr[i]);
    if (!isfinite(time_s) || (nf && !(time_s > m->times.data[nf - 1])))
        return cbm__fail(ctx, CBM_E_INVALID, "motion: frame %zu: time %g s does not increase", nf,
                         time_s);
    if (nf && count != m->bodies.len)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "motion: frame %zu (step %ld) draws %zu segments and spheres where frame "
                         "0 drew %zu; a motion needs the same parts in every frame",
                         nf, step, count, m->bodies.len);
    if (!nf && count == 0)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "motion: step %ld draws no segment or sphere to follow", step);
    CBM_TRY(CBM_ARRAY_RESERVE(ctx, m->pose, m->pose.len + POSE * count));
    CBM_TRY(CBM_ARRAY_RESERVE(ctx, m->times, nf + 1));
    CBM_TRY(CBM_ARRAY_RESERVE(ctx, m->steps, nf + 1));
    if (!nf)
        CBM_TRY(CBM_ARRAY_RESERVE(ctx, m->bodies, count));
    size_t np_scene = scene ? cbm_scene_part_count(scene) : 0;
    const cbm_part *parts = scene ? cbm_scene_parts(scene) : NULL;
    size_t k = 0, base = m->pose.len, scan = 0;
    for (size_t i = 0; i < np; i++) {
        const cbm_prim *p = &pr[i];
        if (!recorded(p))
            continue;
        bool sphere = p->kind == CBM_PRIM_SPHERE;
        if (nf && m->bodies.data[k].sphere != sphere)
            return cbm__fail(ctx, CBM_E_INVALID,
                             "motion: frame %zu (step %ld): part %zu is a %s, in frame 0 a %s", nf,
                             step, k, sphere ? "sphere" : "segment", sphere ? "segment" : "sphere");
        if (!nf) {
            body b = {sphere,
                      sphere ? 0 : v3_norm(v3_sub(p->p1, p->p0)),
                      p->r0,
                      p->r1,
                      {0.5f, 0.5f, 0.5f, 1.0f}};
            /* the scene part the same module drew (parts come in drawing order) */
            for (size_t q = 0; q < np_scene; q++, scan = (scan + 1) % np_scene)
                if (parts[scan].segment == p->module) {
                    memcpy(b.rgba, parts[scan].color, sizeof b.rgba);
                    break;
                }
            m->bodies.data[m->bodies.len++] = b;
        }
        double *d = m->pose.data + base + POSE * k;
        cbm_vec3 e = sphere ? p->p0 : p->p1;
        cbm_quat q = sphere ? q_identity() : segment_rotation(p);
        if (nf) { /* the short way from the previous frame's rotation */
            const double *o = d - POSE * count + 6;
            if (o[0] * q.w + o[1] * q.x + o[2] * q.y + o[3] * q.z < 0)
                q = (cbm_quat){-q.w, -q.x, -q.y, -q.z};
        }
        const double v[POSE] = {p->p0.x, p->p0.y, p->p0.z, e.x, e.y, e.z, q.w, q.x, q.y, q.z};
        for (int c = 0; c < POSE; c++)
            if (!isfinite(v[c]))
                return cbm__fail(ctx, CBM_E_NONFINITE,
                                 "motion: frame %zu (step %ld): part %zu is not finite", nf, step,
                                 k);
        memcpy(d, v, sizeof v);
        k++;
    }
    m->pose.len += POSE * count;
    m->times.data[m->times.len++] = time_s;
    m->steps.data[m->steps.len++] = step;
    return CBM_OK;
}

cbm_status cbm_turtle_motion_add_parts(cbm_turtle_motion *m, const cbm_motion_part *parts,
                                       size_t count, double time_s, long step)
{
    if (!m || (count && !parts))
        return CBM_E_INVALID;
    cbm_context *ctx = m->ctx;
    size_t nf = m->times.len;
    if (!isfinite(time_s) || (nf && !(time_s > m->times.data[nf - 1])))
        return cbm__fail(ctx, CBM_E_INVALID, "motion: frame %zu: time %g s does not increase", nf,
                         time_s);
    if ((nf && count != m->bodies.len) || (!nf && count == 0))
        return cbm__fail(ctx, CBM_E_INVALID,
                         "motion: frame %zu gives %zu parts where frame 0 gave %zu", nf, count,
                         m->bodies.len);
    CBM_TRY(CBM_ARRAY_RESERVE(ctx, m->pose, m->pose.len + POSE * count));
    CBM_TRY(CBM_ARRAY_RESERVE(ctx, m->times, nf + 1));
    CBM_TRY(CBM_ARRAY_RESERVE(ctx, m->steps, nf + 1));
    if (!nf)
        CBM_TRY(CBM_ARRAY_RESERVE(ctx, m->bodies, count));
    size_t base = m->pose.len;
    for (size_t k = 0; k < count; k++) {
        const cbm_motion_part *p = &parts[k];
        cbm_quat q = q_normalize(p->frame);
        cbm_vec3 h = q_rotate(q, v3(1, 0, 0));
        cbm_vec3 e = v3_madd(p->p0, h, p->length);
        if (!nf) {
            body b = {
                false, p->length, p->r0, p->r1, {p->rgba[0], p->rgba[1], p->rgba[2], p->rgba[3]}};
            m->bodies.data[m->bodies.len++] = b;
        } else { /* the short way from the previous frame's rotation */
            const double *o = m->pose.data + base + POSE * k - POSE * count + 6;
            if (o[0] * q.w + o[1] * q.x + o[2] * q.y + o[3] * q.z < 0)
                q = (cbm_quat){-q.w, -q.x, -q.y, -q.z};
        }
        const double v[POSE] = {p->p0.x, p->p0.y, p->p0.z, e.x, e.y, e.z, q.w, q.x, q.y, q.z};
        for (int c = 0; c < POSE; c++)
            if (!isfinite(v[c]))
                return cbm__fail(ctx, CBM_E_NONFINITE, "motion: frame %zu: part %zu is not finite",
                                 nf, k);
        memcpy(m->pose.data + base + POSE * k, v, sizeof v);
    }
    m->pose.len += POSE * count;
    m->times.data[m->times.len++] = time_s;
    m->steps.data[m->steps.len++] = step;
    return CBM_OK;
}

bool cbm_turtle_motion_part(const cbm_turtle_motion *m, size_t frame, size_t part, cbm_vec3 *p0,
                            cbm_vec3 *p1)
{
    if (!m || frame >= m->times.len || part >= m->bodies.len)
        return false;
    const double *d = m->pose.data + POSE * (frame * m->bodies.len + part);
    if (p0)
        *p0 = v3(d[0], d[1], d[2]);
    if (p1)
        *p1 = v3(d[3], d[4], d[5]);
    return true;
}

cbm_status cbm_turtle_motion_write_csv(const cbm_turtle_motion *m, const char *path)
{
    if (!m || !path)
        return CBM_E_INVALID;
    cbm_out *out = NULL;
    CBM_TRY(cbm_out_open(m->ctx, path, &out));
    cbm_out_printf(out, "frame,step,time_s,part,kind,x0,y0,z0,x1,y1,z1\n");
    for (size_t f = 0; f < m->times.len; f++)
        for (size_t i = 0; i < m->bodies.len; i++) {
            const double *d = m->pose.data + POSE * (f * m->bodies.len + i);
            cbm_out_printf(out, "%zu,%ld,%.9g,%zu,%s,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g\n", f,
                           m->steps.data[f], m->times.data[f], i,
                           m->bodies.data[i].sphere ? "sphere" : "segment", d[0], d[1], d[2], d[3],
                           d[4], d[5]);
        }
    return cbm_out_commit(out);
}

/* ---- glTF ---- */

typedef cbm__gltf_accessor acc;
typedef cbm__gltf_view gview;

typedef struct gmesh {
    size_t body; /* the first body with this shape and colour */
    size_t pos, nrm, idx, material;
} gmesh;

typedef struct frames_writer {
    cbm_context *ctx;
    CBM_ARRAY(uint8_t) bin;
    CBM_ARRAY(acc) accs;
    CBM_ARRAY(gview) views;
} frames_writer;

static cbm_status add_accessor(frames_writer *g, const void *data, size_t count, int ncomp,
                               int ctype, int target, bool minmax, size_t *id)
{
    size_t bytes = count * (size_t)ncomp * 4, off = cbm__glb_pad4(g->bin.len);
    CBM_TRY(CBM_ARRAY_RESERVE(g->ctx, g->bin, off + bytes));
    memset(g->bin.data + g->bin.len, 0, off - g->bin.len);
    memcpy(g->bin.data + off, data, bytes);
    g->bin.len = off + bytes;
    gview v = {off, bytes, target};
    CBM_TRY(CBM_ARRAY_PUSH(g->ctx, g->views, v));
    acc a;
    cbm__gltf_accessor_set(&a, g->views.len - 1, data, count, ncomp, ctype, minmax);
    CBM_TRY(CBM_ARRAY_PUSH(g->ctx, g->accs, a));
    *id = g->accs.len - 1;
    return CBM_OK;
}

/* colours compared by value (not by bytes: a float has no unique representation) */
static bool same_rgba(const float *a, const float *b)
{
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2] && a[3] == b[3];
}

static bool same_shape(const body *a, const body *b)
{
    return a->sphere == b->sphere && a->len == b->len && a->r0 == b->r0 && a->r1 == b->r1 &&
           same_rgba(a->rgba, b->rgba);
}

/* A segment along +x from the origin (radii r0 -> r1, closed by discs) or a sphere. */
static cbm_status body_mesh(frames_writer *g, const body *b, gmesh *gm)
{
    enum { NV = 4 * CYL_SIDES + 2 + (SPHERE_STACKS + 1) * (SPHERE_SLICES + 1) };
    enum { NI = 12 * CYL_SIDES + 6 * SPHERE_STACKS * SPHERE_SLICES };
    float pos[3 * NV], nrm[3 * NV];
    uint32_t idx[NI];
    size_t nv = 0, ni = 0;
#define VTX(px, py, pz, nx, ny, nz)                                                                \
    (pos[3 * nv] = (float)(px), pos[3 * nv + 1] = (float)(py), pos[3 * nv + 2] = (float)(pz),      \
     nrm[3 * nv] = (float)(nx), nrm[3 * nv + 1] = (float)(ny), nrm[3 * nv + 2] = (float)(nz),      \
     nv++)
    if (b->sphere) {
        for (int i = 0; i <= SPHERE_STACKS; i++) {
            double th = CBM_PI * i / SPHERE_STACKS;
            for (int j = 0; j <= SPHERE_SLICES; j++) {
                double ph = 2 * CBM_PI * j / SPHERE_SLICES;
                double x = sin(th) * cos(ph), y = cos(th), z = sin(th) * sin(ph);
                VTX(b->r0 * x, b->r0 * y, b->r0 * z, x, y, z);
            }
        }
        for (int i = 0; i < SPHERE_STACKS; i++)
            for (int j = 0; j < SPHERE_SLICES; j++) {
                uint32_t a = (uint32_t)(i * (SPHERE_SLICES + 1) + j), c = a + SPHERE_SLICES + 1;
                /* counter-clockwise seen from outside */
                const uint32_t t[6] = {a, a + 1, c, a + 1, c + 1, c};
                memcpy(idx + ni, t, sizeof t);
                ni += 6;
            }
    } else {
        double slope = (b->r0 - b->r1) / (b->len > 0 ? b->len : 1);
        double nn = sqrt(1 + slope * slope);
        for (int j = 0; j < CYL_SIDES; j++) { /* side: two rings */
            double ph = 2 * CBM_PI * j / CYL_SIDES, cy = cos(ph), cz = sin(ph);
            VTX(0, b->r0 * cy, b->r0 * cz, slope / nn, cy / nn, cz / nn);
            VTX(b->len, b->r1 * cy, b->r1 * cz, slope / nn, cy / nn, cz / nn);
        }
        for (int j = 0; j < CYL_SIDES; j++) {
            uint32_t a = (uint32_t)(2 * j), c = (uint32_t)(2 * ((j + 1) % CYL_SIDES));
            const uint32_t t[6] = {a, a + 1, c + 1, a, c + 1, c};
            memcpy(idx + ni, t, sizeof t);
            ni += 6;
        }
        for (int e = 0; e < 2; e++) { /* caps */
            double x = e ? b->len : 0, r = e ? b->r1 : b->r0, s = e ? 1 : -1;
            uint32_t centre = (uint32_t)nv;
            VTX(x, 0, 0, s, 0, 0);
            for (int j = 0; j < CYL_SIDES; j++) {
                double ph = 2 * CBM_PI * j / CYL_SIDES;
                VTX(x, r * cos(ph), r * sin(ph), s, 0, 0);
            }
            for (int j = 0; j < CYL_SIDES; j++) {
                uint32_t a = centre + 1 + (uint32_t)j,
                         c = centre + 1 + (uint32_t)((j + 1) % CYL_SIDES);
                const uint32_t t[3] = {centre, e ? a : c, e ? c : a};
                memcpy(idx + ni, t, sizeof t);
                ni += 3;
            }
        }
    }
#undef VTX
    CBM_TRY(add_accessor(g, pos, nv, 3, GL_FLOAT, 34962, true, &gm->pos));
    CBM_TRY(add_accessor(g, nrm, nv, 3, GL_FLOAT, 34962, false, &gm->nrm));
    return add_accessor(g, idx, ni, 1, GL_UNSIGNED_INT, 34963, false, &gm->idx);
}

/* The BIN chunk is written even when empty (a motion of no part and one frame), as it always was.
 */
static cbm_status write_container(cbm_context *ctx, const char *path, const char *text, size_t tlen,
                                  const frames_writer *g)
{
    cbm_out *out;
    CBM_TRY(cbm__glb_open(ctx, path, "motion", text, tlen, g->bin.len, true, &out));
    cbm_out_write(out, g->bin.data, g->bin.len);
    cbm__glb_bin_tail(out, g->bin.len);
    return cbm_out_commit(out);
}

static void write_json(cbm_json *j, const cbm_turtle_motion *m, const frames_writer *g,
                       const gmesh *meshes, size_t nmesh, const size_t *mesh_of, size_t nmat,
                       const size_t *mat_body, long anim_in, const size_t *anim_out)
{
    size_t nb = m->bodies.len, nf = m->times.len;
    cbm_json_begin_object(j, NULL);
    cbm_json_begin_object(j, "asset");
    cbm_json_string(j, "version", "2.0");
    cbm_json_string(j, "generator", "cambium " CBM_VERSION_STRING " (motion)");
    cbm_json_end_object(j);
    cbm_json_int(j, "scene", 0);
    cbm_json_begin_array(j, "scenes");
    cbm_json_begin_object(j, NULL);
    cbm_json_string(j, "name", "motion");
    cbm_json_begin_array(j, "nodes");
    cbm_json_int(j, NULL, (int64_t)nb);
    cbm_json_end_array(j);
    cbm_json_end_object(j);
    cbm_json_end_array(j);
    cbm_json_begin_array(j, "nodes");
    for (size_t i = 0; i < nb; i++) {
        const double *d = m->pose.data + POSE * i; /* frame 0 */
        char name[48];
        snprintf(name, sizeof name, "%s %zu", m->bodies.data[i].sphere ? "sphere" : "segment", i);
        cbm_json_begin_object(j, NULL);
        cbm_json_string(j, "name", name);
        cbm_json_int(j, "mesh", (int64_t)mesh_of[i]);
        const float t[3] = {(float)d[0], (float)d[1], (float)d[2]};
        cbm__gltf_json_floats(j, "translation", t, 3);
        if (!m->bodies.data[i].sphere) {
            const float r[4] = {(float)d[7], (float)d[8], (float)d[9], (float)d[6]}; /* x y z w */
            cbm__gltf_json_floats(j, "rotation", r, 4);
        }
        cbm_json_end_object(j);
    }
    cbm_json_begin_object(j, NULL);
    cbm_json_string(j, "name", "plant");
    cbm_json_begin_array(j, "children");
    for (size_t i = 0; i < nb; i++)
        cbm_json_int(j, NULL, (int64_t)i);
    cbm_json_end_array(j);
    cbm_json_begin_object(j, "extras");
    cbm_json_string(j, "units", "model units (m)");
    cbm_json_string(j, "up", "+y");
    cbm_json_int(j, "frames", (int64_t)nf);
    cbm_json_end_object(j);
    cbm_json_end_object(j);
    cbm_json_end_array(j);

    cbm_json_begin_array(j, "meshes");
    for (size_t i = 0; i < nmesh; i++) {
        cbm_json_begin_object(j, NULL);
        cbm_json_begin_array(j, "primitives");
        cbm_json_begin_object(j, NULL);
        cbm_json_begin_object(j, "attributes");
        cbm_json_int(j, "POSITION", (int64_t)meshes[i].pos);
        cbm_json_int(j, "NORMAL", (int64_t)meshes[i].nrm);
        cbm_json_end_object(j);
        cbm_json_int(j, "indices", (int64_t)meshes[i].idx);
        cbm_json_int(j, "material", (int64_t)meshes[i].material);
        cbm_json_int(j, "mode", 4);
        cbm_json_end_object(j);
        cbm_json_end_array(j);
        cbm_json_end_object(j);
    }
    cbm_json_end_array(j);
    cbm_json_begin_array(j, "materials");
    for (size_t i = 0; i < nmat; i++) {
        cbm_json_begin_object(j, NULL);
        cbm_json_begin_object(j, "pbrMetallicRoughness");
        cbm__gltf_json_floats(j, "baseColorFactor", m->bodies.data[mat_body[i]].rgba, 4);
        cbm_json_number(j, "metallicFactor", 0.0);
        cbm_json_number(j, "roughnessFactor", 0.8);
        cbm_json_end_object(j);
        cbm_json_end_object(j);
    }
    cbm_json_end_array(j);
    if (anim_in >= 0) {
        cbm_json_begin_array(j, "animations");
        cbm_json_begin_object(j, NULL);
        cbm_json_string(j, "name", "motion");
        cbm_json_begin_array(j, "channels");
        size_t s = 0;
        for (size_t i = 0; i < nb; i++)
            for (int r = 0; r < (m->bodies.data[i].sphere ? 1 : 2); r++) {
                cbm_json_begin_object(j, NULL);
                cbm_json_int(j, "sampler", (int64_t)s++);
                cbm_json_begin_object(j, "target");
                cbm_json_int(j, "node", (int64_t)i);
                cbm_json_string(j, "path", r ? "rotation" : "translation");
                cbm_json_end_object(j);
                cbm_json_end_object(j);
            }
        cbm_json_end_array(j);
        cbm_json_begin_array(j, "samplers");
        for (size_t k = 0; k < s; k++) {
            cbm_json_begin_object(j, NULL);
            cbm_json_int(j, "input", anim_in);
            cbm_json_int(j, "output", (int64_t)anim_out[k]);
            cbm_json_string(j, "interpolation", "LINEAR");
            cbm_json_end_object(j);
        }
        cbm_json_end_array(j);
        cbm_json_end_object(j);
        cbm_json_end_array(j);
    }
    cbm__gltf_json_buffers(j, g->accs.data, g->accs.len, g->views.data, g->views.len, g->bin.len);
    cbm_json_end_object(j);
}

cbm_status cbm_turtle_motion_write_glb(const cbm_turtle_motion *m, const char *path)
{
    if (!m || !path)
        return CBM_E_INVALID;
    cbm_context *ctx = m->ctx;
    size_t nb = m->bodies.len, nf = m->times.len;
    if (!nf)
        return cbm__fail(ctx, CBM_E_INVALID, "%s: the motion has no frame", path);
    frames_writer g = {ctx, {0}, {0}, {0}};
    size_t nchan = 0;
    for (size_t i = 0; i < nb; i++)
        nchan += m->bodies.data[i].sphere ? 1 : 2;
    gmesh *meshes = cbm__calloc(ctx, nb, sizeof *meshes);
    size_t *mesh_of = cbm__calloc(ctx, nb, sizeof *mesh_of);
    size_t *mat_body = cbm__calloc(ctx, nb, sizeof *mat_body);
    size_t *anim_out = cbm__calloc(ctx, nchan, sizeof *anim_out);
    float *buf = cbm__calloc(ctx, 4 * nf, sizeof *buf);
    cbm_json *j = NULL;
    cbm_status st = meshes && mesh_of && mat_body && anim_out && buf ? CBM_OK : CBM_E_NOMEM;
    size_t nmesh = 0, nmat = 0;
    for (size_t i = 0; i < nb && st == CBM_OK; i++) {
        const body *b = &m->bodies.data[i];
        size_t k = 0;
        while (k < nmesh && !same_shape(&m->bodies.data[meshes[k].body], b))
            k++;
        mesh_of[i] = k;
        if (k < nmesh)
            continue;
        meshes[k].body = i;
        size_t mat = 0;
        while (mat < nmat && !same_rgba(m->bodies.data[mat_body[mat]].rgba, b->rgba))
            mat++;
        if (mat == nmat)
            mat_body[nmat++] = i;
        meshes[k].material = mat;
        st = body_mesh(&g, b, &meshes[k]);
        nmesh++;
    }
    long anim_in = -1;
    if (st == CBM_OK && nf > 1) {
        size_t id = 0;
        for (size_t f = 0; f < nf; f++)
            buf[f] = (float)(m->times.data[f] - m->times.data[0]);
        for (size_t f = 1; f < nf && st == CBM_OK; f++)
            if (!(buf[f] > buf[f - 1]))
                st = cbm__fail(ctx, CBM_E_INVALID,
                               "%s: frames %zu and %zu fall on the same time in single precision "
                               "(%.9g s); record fewer frames or lengthen the frame time",
                               path, f - 1, f, m->times.data[f]);
        if (st == CBM_OK)
            st = add_accessor(&g, buf, nf, 1, GL_FLOAT, 0, true, &id);
        anim_in = (long)id;
        size_t s = 0;
        for (size_t i = 0; i < nb && st == CBM_OK; i++)
            for (int r = 0; r < (m->bodies.data[i].sphere ? 1 : 2) && st == CBM_OK; r++) {
                int nc = r ? 4 : 3;
                for (size_t f = 0; f < nf; f++) {
                    const double *d = m->pose.data + POSE * (f * nb + i);
                    if (r) { /* glTF's order: x y z w */
                        buf[4 * f] = (float)d[7];
                        buf[4 * f + 1] = (float)d[8];
                        buf[4 * f + 2] = (float)d[9];
                        buf[4 * f + 3] = (float)d[6];
                    } else {
                        for (int c = 0; c < 3; c++)
                            buf[3 * f + (size_t)c] = (float)d[c];
                    }
                }
                st = add_accessor(&g, buf, nf, nc, GL_FLOAT, 0, false, &anim_out[s++]);
            }
    }
    if (st == CBM_OK)
        st = cbm_json_create(ctx, &j);
    const char *text = NULL;
    size_t tlen = 0;
    if (st == CBM_OK) {
        write_json(j, m, &g, meshes, nmesh, mesh_of, nmat, mat_body, anim_in, anim_out);
        st = cbm_json_text(j, &text, &tlen);
    }
    if (st == CBM_OK)
        st = write_container(ctx, path, text, tlen, &g);
    cbm_json_destroy(j);
    cbm__free(ctx, meshes, nb * sizeof *meshes);
    cbm__free(ctx, mesh_of, nb * sizeof *mesh_of);
    cbm__free(ctx, mat_body, nb * sizeof *mat_body);
    cbm__free(ctx, anim_out, nchan * sizeof *anim_out);
    cbm__free(ctx, buf, 4 * nf * sizeof *buf);
    CBM_ARRAY_FREE(ctx, g.bin);
    CBM_ARRAY_FREE(ctx, g.accs);
    CBM_ARRAY_FREE(ctx, g.views);
    return st;
}
