/* Wavefront OBJ and MTL writer. Vertices as "v x y z r g b" (colours in display sRGB 0..1, the
 * extension MeshLab, Blender and assimp read), normals "vn", faces "f a//a b//b c//c". One
 * material per distinct (organ, 8-bit colour) pair, found with an open-addressing hash table;
 * "g" starts a group per organ (per order for branches) so viewers list the organs. The .mtl is
 * committed before the .obj, both through cbm_out. */
#include "writers.h"

#include "cambium/io.h"

#include <math.h>
#include <stdio.h>

typedef struct mtl_table {
    uint32_t *keys; /* organ << 24 | rgb, UINT32_MAX empty */
    uint32_t *ids;
    size_t cap, count;
} mtl_table;

static uint32_t color_key(cbm_organ organ, const float *c)
{
    return ((uint32_t)organ << 24) | ((uint32_t)cbm__srgb8(c[0]) << 16) |
           ((uint32_t)cbm__srgb8(c[1]) << 8) | cbm__srgb8(c[2]);
}

static uint32_t mtl_find(mtl_table *t, uint32_t key)
{
    size_t h = (key * 2654435761u) & (t->cap - 1);
    while (t->keys[h] != UINT32_MAX && t->keys[h] != key)
        h = (h + 1) & (t->cap - 1);
    if (t->keys[h] == UINT32_MAX) {
        t->keys[h] = key;
        t->ids[h] = (uint32_t)t->count++;
    }
    return t->ids[h];
}

static void group_name(const cbm_part *p, char *buf, size_t n)
{
    if (p->organ == CBM_ORGAN_BRANCH && p->order >= 0)
        snprintf(buf, n, "branch_order_%d", (int)p->order);
    else
        snprintf(buf, n, "%s", cbm_organ_name(p->organ));
}

#define MAX_ORDER_GROUP 32

/* branch orders 0..31 first, then organs */
static int group_index(const cbm_part *p)
{
    if (p->organ == CBM_ORGAN_BRANCH && p->order >= 0)
        return p->order < MAX_ORDER_GROUP ? p->order : MAX_ORDER_GROUP - 1;
    return MAX_ORDER_GROUP + ((int)p->organ < CBM_ORGAN_COUNT ? (int)p->organ : CBM_ORGAN_OTHER);
}

cbm_status cbm_write_obj(cbm_context *ctx, const cbm_scene *s, const char *path,
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

    /* .mtl path: the .obj path with its extension replaced */
    size_t plen = strlen(path);
    const char *dot = strrchr(path, '.');
    size_t stem =
        dot && (!strrchr(path, '/') || dot > strrchr(path, '/')) ? (size_t)(dot - path) : plen;
    size_t mlen = stem + 5;
    char *mpath = cbm__alloc(ctx, mlen);
    float *col = NULL;
    uint32_t *vpart = NULL, *remap = NULL, *pmtl = NULL;
    mtl_table t = {0};
    size_t kept = 0;
    cbm_status st = CBM_OK;
    cbm_out *mo = NULL, *oo = NULL;
    if (!mpath) {
        st = CBM_E_NOMEM;
        goto done;
    }
    snprintf(mpath, mlen, "%.*s.mtl", (int)stem, path);
    if ((st = cbm__part_colors(ctx, s, o, &col, NULL, NULL)) != CBM_OK ||
        (st = cbm__vertex_parts(ctx, s, &vpart)) != CBM_OK ||
        (st = cbm__vertex_remap(ctx, s, o, vpart, &remap, &kept)) != CBM_OK)
        goto done;
    t.cap = 16;
    while (t.cap < 2 * np)
        t.cap *= 2;
    t.keys = cbm__alloc(ctx, t.cap * sizeof *t.keys);
    t.ids = cbm__alloc(ctx, t.cap * sizeof *t.ids);
    pmtl = cbm__alloc(ctx, (np ? np : 1) * sizeof *pmtl);
    if (!t.keys || !t.ids || !pmtl) {
        st = CBM_E_NOMEM;
        goto done;
    }
    memset(t.keys, 0xff, t.cap * sizeof *t.keys);
    for (size_t i = 0; i < np; i++)
        pmtl[i] = mtl_find(&t, color_key(parts[i].organ, col + 4 * i));

    /* the .obj is opened first so that an unwritable target is reported under its own name */
    if ((st = cbm_out_open(ctx, path, &oo)) != CBM_OK ||
        (st = cbm_out_open(ctx, mpath, &mo)) != CBM_OK)
        goto done;
    /* the material library: materials in id order */
    FILE *f = cbm_out_stream(mo);
    fprintf(f, "# cambium materials: one per organ and colour (display sRGB)\n");
    for (uint32_t id = 0; id < t.count; id++) {
        for (size_t h = 0; h < t.cap; h++) {
            if (t.keys[h] == UINT32_MAX || t.ids[h] != id)
                continue;
            uint32_t k = t.keys[h];
            cbm_organ organ = (cbm_organ)(k >> 24);
            fprintf(f,
                    "\nnewmtl m%u_%s\nKa 0 0 0\nKd %.4f %.4f %.4f\nKs 0.02 0.02 0.02\nNs 10\nd "
                    "1\nillum 2\n",
                    id, cbm_organ_name(organ), ((k >> 16) & 255) / 255.0, ((k >> 8) & 255) / 255.0,
                    (k & 255) / 255.0);
            break;
        }
    }
    f = cbm_out_stream(oo);
    const char *mbase = strrchr(mpath, '/');
    mbase = mbase ? mbase + 1 : mpath;
    fprintf(f, "# cambium scene: metres, y up; %zu vertices, %zu triangles, %zu parts\n", kept, nt,
            np);
    fprintf(f, "mtllib %s\n", mbase);
    for (size_t i = 0; i < nv; i++) {
        if (remap[i] == UINT32_MAX)
            continue;
        const float *c = col + 4 * vpart[i];
        fprintf(f, "v %.7g %.7g %.7g %.4f %.4f %.4f\n", v[i].p[0], v[i].p[1], v[i].p[2],
                cbm__srgb8(c[0]) / 255.0, cbm__srgb8(c[1]) / 255.0, cbm__srgb8(c[2]) / 255.0);
    }
    for (size_t i = 0; i < nv; i++)
        if (remap[i] != UINT32_MAX)
            fprintf(f, "vn %.6f %.6f %.6f\n", v[i].n[0], v[i].n[1], v[i].n[2]);
    /* triangles grouped: branch orders first, then the other organs */
    char g[64];
    for (int gi = 0; gi < CBM_ORGAN_COUNT + MAX_ORDER_GROUP; gi++) {
        uint32_t cur = UINT32_MAX;
        bool opened = false;
        for (size_t k = 0; k < nt; k++) {
            const cbm_part *p = &parts[tp[k]];
            if (!cbm__part_kept(p, o) || group_index(p) != gi)
                continue;
            if (!opened) {
                group_name(p, g, sizeof g);
                fprintf(f, "g %s\n", g);
                opened = true;
            }
            if (pmtl[tp[k]] != cur) {
                cur = pmtl[tp[k]];
                fprintf(f, "usemtl m%u_%s\n", cur, cbm_organ_name(p->organ));
            }
            uint32_t a = remap[tri[3 * k]] + 1, b = remap[tri[3 * k + 1]] + 1,
                     c = remap[tri[3 * k + 2]] + 1;
            fprintf(f, "f %u//%u %u//%u %u//%u\n", a, a, b, b, c, c);
        }
    }
    /* the .mtl first (the .obj names it); if the .obj then fails, the new .mtl goes too */
    st = cbm_out_commit(mo);
    mo = NULL;
    if (st == CBM_OK) {
        st = cbm_out_commit(oo);
        if (st != CBM_OK)
            remove(mpath);
    } else {
        cbm_out_abort(oo);
    }
    oo = NULL;
done:
    cbm_out_abort(mo);
    cbm_out_abort(oo);
    cbm__free(ctx, mpath, mlen);
    cbm__free(ctx, col, 4 * (np ? np : 1) * sizeof *col);
    cbm__free(ctx, vpart, (nv ? nv : 1) * sizeof *vpart);
    cbm__free(ctx, remap, (nv ? nv : 1) * sizeof *remap);
    cbm__free(ctx, pmtl, (np ? np : 1) * sizeof *pmtl);
    cbm__free(ctx, t.keys, t.cap * sizeof *t.keys);
    cbm__free(ctx, t.ids, t.cap * sizeof *t.ids);
    return st;
}
