/* Light of the leaves of a writer's scene (cbm_scene, include/cambium/geom.h): every triangle
 * of a part whose organ is a leaf becomes one light leaf (a triangle, p3 = p2, turned to face
 * up, so that `two_sided = false` means the upper face), the triangles of every other part but
 * the ground occlude, and the sums per part go back into the parts (cbm_part.light, relative to
 * the part's one-sided area) and into the caller's arrays. A leaf part holds its petiole too
 * (src/tree/tree_scene.c), which is then counted as leaf. */
#include "light_internal.h"

#include "../core/vecmath.h"
#include "cambium/geom.h"

#include <math.h>

static cbm_vec3 vertex(const cbm_scene_vertex *v)
{
    return v3(v->p[0], v->p[1], v->p[2]);
}

cbm_status cbm_light_scene(cbm_context *ctx, const cbm_light_def *def, cbm_scene *scene,
                           double *part_light, double *part_area, size_t *n_leaf_triangles,
                           cbm_light_stats *stats)
{
    if (!ctx || !scene)
        return CBM_E_INVALID;
    size_t np = cbm_scene_part_count(scene), nt = cbm_scene_triangle_count(scene);
    const cbm_part *parts = cbm_scene_parts(scene);
    const uint32_t *tri = cbm_scene_triangles(scene), *tp = cbm_scene_triangle_parts(scene);
    const cbm_scene_vertex *vx = cbm_scene_vertices(scene);
    size_t nl = 0, no = 0;
    for (size_t t = 0; t < nt; t++) {
        cbm_organ o = parts[tp[t]].organ;
        nl += o == CBM_ORGAN_LEAF;
        no += o != CBM_ORGAN_LEAF && o != CBM_ORGAN_GROUND;
    }
    cbm_light_leaf *leaves = cbm__calloc(ctx, nl ? nl : 1, sizeof *leaves);
    cbm_vec3 *occ = cbm__calloc(ctx, 3 * (no ? no : 1), sizeof *occ);
    double *a = cbm__calloc(ctx, nl ? nl : 1, sizeof *a);
    double *sum = cbm__calloc(ctx, np ? np : 1, sizeof *sum);
    double *area = cbm__calloc(ctx, np ? np : 1, sizeof *area);
    cbm_status st = CBM_OK;
    if (!leaves || !occ || !a || !sum || !area) {
        st = CBM_E_NOMEM;
        goto done;
    }
    size_t il = 0, io = 0;
    for (size_t t = 0; t < nt; t++) {
        cbm_organ o = parts[tp[t]].organ;
        cbm_vec3 p0 = vertex(&vx[tri[3 * t]]), p1 = vertex(&vx[tri[3 * t + 1]]),
                 p2 = vertex(&vx[tri[3 * t + 2]]);
        if (o == CBM_ORGAN_LEAF) {
            if (v3_cross(v3_sub(p1, p0), v3_sub(p2, p0)).y < 0) {
                cbm_vec3 s = p1;
                p1 = p2;
                p2 = s;
            }
            cbm_light_leaf *l = &leaves[il++];
            l->p[0] = p0, l->p[1] = p1, l->p[2] = p2, l->p[3] = p2;
            l->plant = tp[t];
        } else if (o != CBM_ORGAN_GROUND) {
            occ[io++] = p0, occ[io++] = p1, occ[io++] = p2;
        }
    }
    st = cbm_light_intercept(ctx, def, leaves, nl, occ, no, a, stats);
    if (st != CBM_OK)
        goto done;
    for (size_t i = 0; i < nl; i++) {
        const cbm_vec3 *p = leaves[i].p;
        sum[leaves[i].plant] += a[i];
        area[leaves[i].plant] += 0.5 * v3_norm(v3_cross(v3_sub(p[1], p[0]), v3_sub(p[2], p[0])));
    }
    for (size_t k = 0; k < np; k++) {
        if (parts[k].organ == CBM_ORGAN_LEAF)
            cbm_scene_part(scene, (uint32_t)k)->light = area[k] > 0 ? sum[k] / area[k] : NAN;
        if (part_light)
            part_light[k] = sum[k];
        if (part_area)
            part_area[k] = area[k];
    }
    if (n_leaf_triangles)
        *n_leaf_triangles = nl;
done:
    cbm__free(ctx, leaves, (nl ? nl : 1) * sizeof *leaves);
    cbm__free(ctx, occ, 3 * (no ? no : 1) * sizeof *occ);
    cbm__free(ctx, a, (nl ? nl : 1) * sizeof *a);
    cbm__free(ctx, sum, (np ? np : 1) * sizeof *sum);
    cbm__free(ctx, area, (np ? np : 1) * sizeof *area);
    return st;
}
