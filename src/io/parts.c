/* Which parts a writer keeps (the ground can be left out) and the maps between vertices and parts
 * that the mesh writers need to drop the vertices of parts left out. */
#include "writers.h"

#include <string.h>

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
