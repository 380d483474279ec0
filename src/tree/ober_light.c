/* The leaves' carbon of Oberlaender's parametric tree (§5.5, eqs. 19-22): with `light = 1`
 * every living leaf of every tree of the stand goes to the ray caster (cambium/light.h) as its
 * quad; a leaf's carbon is the light it intercepts divided by its area, in units of an unshaded
 * horizontal leaf (the thesis's normalisation by maxLightSquare and the leaf's size): 1 for an
 * unshaded horizontal leaf, less in the shade. Stems do not shade (the thesis's light model
 * sees leaves only). Without light every leaf counts as unshaded (carbon 1), the statistical
 * model's neutral value. */
#include "tree/ober_internal.h"
#include "cambium/light.h"
#include "core/vecmath.h"

#define PRISM 6 /* sides of a shoot's prism: 2 triangles each */

/* The prisms of every shoot (m, 3 vertices per triangle) into occ[PRISM * 2 * 3 * shoots]. */
static size_t stem_triangles(const cbm_ober_stand *s, cbm_vec3 *occ)
{
    size_t m = 0;
    for (size_t i = 0; i < s->shoots.len; i++) {
        const ober_shoot *h = &s->shoots.data[i];
        double R = CBM_PI * h->radius / 3.0;
        if (!(h->len > 0 && R > 0))
            continue;
        cbm_vec3 ring[2][PRISM];
        for (int k = 0; k < PRISM; k++) {
            double a = 2.0 * CBM_PI * k / PRISM;
            cbm_vec3 off = v3_add(v3_scale(h->L, R * cos(a)), v3_scale(h->U, R * sin(a)));
            ring[0][k] = v3_scale(v3_add(h->base, off), 0.01);
            ring[1][k] = v3_scale(v3_add(h->tip, off), 0.01);
        }
        for (int k = 0; k < PRISM; k++) {
            int k1 = (k + 1) % PRISM;
            occ[m++] = ring[0][k], occ[m++] = ring[0][k1], occ[m++] = ring[1][k1];
            occ[m++] = ring[0][k], occ[m++] = ring[1][k1], occ[m++] = ring[1][k];
        }
    }
    return m / 3;
}

cbm_status cbm__ober_light(cbm_ober_stand *s)
{
    CBM_TRY(CBM_ARRAY_RESERVE(s->ctx, s->leaf_carbon, s->buds.len));
    s->leaf_carbon.len = s->buds.len;
    for (size_t b = 0; b < s->buds.len; b++)
        s->leaf_carbon.data[b] = 1.0;
    s->light_rays = 0;
    s->light_seconds = 0;
    if (!s->def.light || s->buds.len == 0)
        return CBM_OK;
    size_t n = 0;
    for (size_t b = 0; b < s->buds.len; b++) {
        cbm_vec3 q[4];
        n += cbm__ober_leaf_quad(s, b, q);
    }
    if (n == 0)
        return CBM_OK;
    cbm_light_leaf *leaves = cbm__calloc(s->ctx, n, sizeof *leaves);
    double *absorbed = cbm__calloc(s->ctx, n, sizeof *absorbed);
    size_t *which = cbm__calloc(s->ctx, n, sizeof *which);
    size_t nocc = s->def.light_stems ? (size_t)PRISM * 2 * 3 * s->shoots.len : 0, ntri = 0;
    cbm_vec3 *occ = nocc ? cbm__calloc(s->ctx, nocc, sizeof *occ) : NULL;
    cbm_status st = leaves && absorbed && which && (occ || !nocc) ? CBM_OK : CBM_E_NOMEM;
    if (st == CBM_OK && occ)
        ntri = stem_triangles(s, occ);
    size_t k = 0;
    for (size_t b = 0; b < s->buds.len && st == CBM_OK; b++) {
        if (!cbm__ober_leaf_quad(s, b, leaves[k].p))
            continue;
        leaves[k].plant = (uint32_t)s->shoots.data[s->buds.data[b].shoot].tree;
        which[k++] = b;
    }
    if (st == CBM_OK) {
        cbm_light_def ld = cbm_light_def_default();
        ld.sky = (cbm_sky_kind)s->def.sky;
        ld.rings = s->def.light_rings;
        ld.azimuths = s->def.light_azimuths;
        ld.samples = s->def.light_samples;
        ld.seed = s->def.seed + (uint64_t)s->year;
        cbm_light_stats stats;
        st = cbm_light_intercept(s->ctx, &ld, leaves, n, occ, ntri, absorbed, &stats);
        if (st == CBM_OK) {
            s->light_rays = stats.rays;
            s->light_seconds = stats.seconds;
            double area = s->def.leaf_length * s->def.leaf_width * 1e-4; /* m^2 */
            for (size_t i = 0; i < n; i++)
                s->leaf_carbon.data[which[i]] = absorbed[i] / area;
        }
    }
    cbm__free(s->ctx, leaves, n * sizeof *leaves);
    cbm__free(s->ctx, absorbed, n * sizeof *absorbed);
    cbm__free(s->ctx, which, n * sizeof *which);
    cbm__free(s->ctx, occ, nocc * sizeof *occ);
    return st;
}
