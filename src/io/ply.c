/* PLY writer, binary little-endian (PLY format 1.0). Each vertex: float position (m) and unit
 * normal, uchar RGBA (display sRGB), and the data of its part (float stress_ratio, age in years,
 * reaction_wood; int order; int segment; uint part). Each face: a uchar-counted list of three
 * uint indices and its uint part. Missing quantities are NaN in the file. Values are stored
 * little-endian whatever the host. */
#include "writers.h"

#include "cambium/io.h"

#include <stdio.h>

static void put_u32(uint8_t *b, uint32_t v)
{
    b[0] = (uint8_t)v;
    b[1] = (uint8_t)(v >> 8);
    b[2] = (uint8_t)(v >> 16);
    b[3] = (uint8_t)(v >> 24);
}

static void put_f32(uint8_t *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    put_u32(b, u);
}

cbm_status cbm_write_ply(cbm_context *ctx, const cbm_scene *s, const char *path,
                         const cbm_write_options *opts)
{
    if (!ctx || !s || !path)
        return CBM_E_INVALID;
    cbm_write_options def;
    const cbm_write_options *o = cbm__opts(opts, &def);
    size_t np = cbm_scene_part_count(s), nv = cbm_scene_vertex_count(s);
    size_t nt = cbm_scene_triangle_count(s);
    const cbm_part *parts = cbm_scene_parts(s);
    const cbm_scene_vertex *v = cbm_scene_vertices(s);
    const uint32_t *tri = cbm_scene_triangles(s), *tp = cbm_scene_triangle_parts(s);
    float *col = NULL;
    uint32_t *vpart = NULL, *remap = NULL;
    size_t kept = 0, faces = 0;
    cbm_out *out = NULL;
    cbm_status st;
    if ((st = cbm__part_colors(ctx, s, o, &col, NULL, NULL)) != CBM_OK ||
        (st = cbm__vertex_parts(ctx, s, &vpart)) != CBM_OK ||
        (st = cbm__vertex_remap(ctx, s, o, vpart, &remap, &kept)) != CBM_OK)
        goto done;
    for (size_t k = 0; k < nt; k++)
        faces += cbm__part_kept(&parts[tp[k]], o);
    if ((st = cbm_out_open(ctx, path, &out)) != CBM_OK)
        goto done;
    cbm_out_printf(out,
                   "ply\nformat binary_little_endian 1.0\n"
                   "comment cambium scene: metres, y up; colours display sRGB\n"
                   "element vertex %zu\n"
                   "property float x\nproperty float y\nproperty float z\n"
                   "property float nx\nproperty float ny\nproperty float nz\n"
                   "property uchar red\nproperty uchar green\nproperty uchar blue\n"
                   "property uchar alpha\n"
                   "property float stress_ratio\nproperty float age\n"
                   "property float reaction_wood\nproperty int order\nproperty int segment\n"
                   "property uint part\n"
                   "element face %zu\nproperty list uchar uint vertex_indices\n"
                   "property uint part\nend_header\n",
                   kept, faces);
    uint8_t rec[56];
    for (size_t i = 0; i < nv; i++) {
        if (remap[i] == UINT32_MAX)
            continue;
        const cbm_part *p = &parts[vpart[i]];
        const float *c = col + 4 * vpart[i];
        for (int k = 0; k < 3; k++) {
            put_f32(rec + 4 * k, v[i].p[k]);
            put_f32(rec + 12 + 4 * k, v[i].n[k]);
        }
        for (int k = 0; k < 3; k++)
            rec[24 + k] = cbm__srgb8(c[k]);
        rec[27] = (uint8_t)(c[3] <= 0 ? 0 : c[3] >= 1 ? 255 : (int)(c[3] * 255.0f + 0.5f));
        put_f32(rec + 28, (float)p->stress_ratio);
        put_f32(rec + 32, (float)p->age);
        put_f32(rec + 36, (float)p->reaction_wood);
        put_u32(rec + 40, (uint32_t)p->order);
        put_u32(rec + 44, (uint32_t)(int32_t)(p->segment < INT32_MIN   ? INT32_MIN
                                              : p->segment > INT32_MAX ? INT32_MAX
                                                                       : p->segment));
        put_u32(rec + 48, vpart[i]);
        cbm_out_write(out, rec, 52);
    }
    for (size_t k = 0; k < nt; k++) {
        if (!cbm__part_kept(&parts[tp[k]], o))
            continue;
        rec[0] = 3;
        for (int q = 0; q < 3; q++)
            put_u32(rec + 1 + 4 * q, remap[tri[3 * k + (size_t)q]]);
        put_u32(rec + 13, tp[k]);
        cbm_out_write(out, rec, 17);
    }
    st = cbm_out_commit(out);
    out = NULL;
done:
    cbm_out_abort(out);
    cbm__free(ctx, col, 4 * (np ? np : 1) * sizeof *col);
    cbm__free(ctx, vpart, (nv ? nv : 1) * sizeof *vpart);
    cbm__free(ctx, remap, (nv ? nv : 1) * sizeof *remap);
    return st;
}
