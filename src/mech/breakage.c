/* Breakage (Taylor-Hell 2005 §8.6-8.8, eqs. 8.26-8.27).
 *
 * The peak normal stress of bending at a segment's proximal joint is sigma = M a / I for the
 * moment component turning about L, and M b / I_U for the one about U; for the ellipse the peak
 * over the boundary (u, l) = (a cos t, b sin t) of sigma = (M_L / I_L) u + (M_U / I_U) l is
 * sqrt((M_L a / I_L)^2 + (M_U b / I_U)^2) (cbm_segment_state.stress; for a circle 4 M / (pi r^3),
 * 8.26). Shear and torsion are ignored, as in the thesis. A segment breaks when sigma exceeds
 * the modulus of rupture of its outer ring (8.27), where the stress is largest. A broken segment
 * is removed with everything it carries (src/mech/plant.c keeps the arrays compact and in
 * topological order); the rest of the plant then springs back at the next solve (Fig. 8.8).
 * Only the most proximal break of each branch counts: a segment inside an already broken
 * subtree falls with it. Removal goes from the highest index down so that indices below stay
 * valid.
 */
#include "mech/growth_internal.h"
#include "core/vecmath.h"

#include <math.h>

/* Peak bending stress at the proximal joint of segment i and the outer ring's MOR (the same
 * formula as cbm_segment_state.stress, without the per-segment queries so that a pass over the
 * plant stays O(n)). */
static double joint_stress(const cbm_plant *p, size_t i, double *mor)
{
    const cbm__outer *r = &p->outer[i];
    cbm_quat q = p->q[i];
    cbm_vec3 m = p->moment[i];
    double ml = v3_dot(m, q_rotate(q, v3(0, 1, 0))), mu = v3_dot(m, q_rotate(q, v3(0, 0, 1)));
    double il, iu;
    cbm_mech_ellipse_moments(r->a, r->b, &il, &iu, NULL);
    double sl = ml * r->a / il, su = mu * r->b / iu;
    *mor = r->mor;
    return sqrt(sl * sl + su * su);
}

cbm_status cbm_plant_break(cbm_plant *p, size_t *broken, size_t max_broken, size_t *n_broken,
                           size_t *n_removed)
{
    if (n_broken)
        *n_broken = 0;
    if (n_removed)
        *n_removed = 0;
    if (!p)
        return CBM_E_INVALID;
    size_t n = p->n;
    if (n == 0)
        return CBM_OK;
    /* flag: 0 intact, 1 inside a broken subtree, 2 a most proximal break */
    uint8_t *flag = cbm__calloc(p->ctx, n, 1);
    if (!flag)
        return CBM_E_NOMEM;
    size_t nb = 0;
    cbm_status s = CBM_OK;
    for (size_t i = 0; i < n; i++) {
        int64_t pa = p->parent[i];
        if (pa >= 0 && flag[pa]) {
            flag[i] = 1;
            continue;
        }
        double mor, stress = joint_stress(p, i, &mor);
        if (!isfinite(stress)) {
            s = cbm__fail(p->ctx, CBM_E_NONFINITE, "segment %zu: bending stress is not finite", i);
            break;
        }
        if (mor > 0.0 && stress > mor) {
            flag[i] = 2;
            if (broken && nb < max_broken)
                broken[nb] = i;
            nb++;
        }
    }
    size_t total = 0;
    for (size_t i = n; s == CBM_OK && i-- > 0;) {
        if (flag[i] != 2)
            continue;
        size_t rm = 0;
        s = cbm_plant_remove_subtree(p, i, &rm);
        total += rm;
    }
    cbm__free(p->ctx, flag, n);
    if (n_broken)
        *n_broken = nb;
    if (n_removed)
        *n_removed = total;
    return s;
}
