/* Wood: the material of new rings, wood ageing and reaction wood (Taylor-Hell 2005 ch. 8).
 *
 * Ageing (8.1-8.6). Juvenile wood is as dense as adult wood but less stiff (the thesis' option
 * 2). The modulus rises linearly with age, E' = E + dt (E_adult - E_juv) / adult_age, capped at
 * E_adult (8.2); G keeps its ratio to E (the listing adds the E increment to G as well, which
 * makes G > E/2 and is unphysical: digest erratum 12). Default CBM_AGEING_RINGS applies 8.2 to
 * every ring by its own age, the rigidity being C = sum_k E_k I_k (8.3-8.4); the structural
 * modulus E = C_L / I_L, G = C_H / J (8.1, 8.5-8.6) is an output. CBM_AGEING_CORE reproduces
 * the listing: the rings are merged into one core with the structural moduli (and the
 * rigidity-weighted rest rate) and that core ages.
 *
 * Reaction wood (8.3-8.5). The equilibrium position is the rest rate (8.7); a segment leans when
 * |Omega - rest| > xi (8.8), Omega being the rate the new ring would memorise (see growth.c).
 * A ring laid down while leaning is reaction wood: the semi-axis a (U, the bending plane of a
 * vertical lean) gets an extra increment after the pipe computation (8.20; b is kept, so the
 * section ovalises and I_L = pi a^3 b / 4 (8.9) grows fastest: the physically consistent
 * assignment, digest erratum 3), its modulus is E_ring = E_rw/2 + E_juv/2 (8.23: about half of
 * the ring is reaction wood; E_rw defaults to E_adult as in the listing), its reaction fraction
 * is 1/2, and its rest rate is (1 - beta) Omega + beta rest (8.25) instead of Omega (8.24): the
 * growth strain that pulls the segment back towards its equilibrium position through the
 * rigidity-weighted mean (6.29-6.31). Ring second moments are the outer minus the inner ellipse
 * (8.21-8.22, with pi on both terms: digest erratum 4) in src/mech/plant.c.
 */
#include "mech/growth_internal.h"
#include "core/vecmath.h"

#include <math.h>

bool cbm__wood_leans(const cbm_growth_def *d, cbm_vec3 current, cbm_vec3 rest)
{
    return v3_norm(v3_sub(current, rest)) > d->reaction_threshold;
}

void cbm__wood_new_ring(const cbm_growth_def *d, bool reaction, cbm_vec3 current, cbm_vec3 rest,
                        cbm_ring *r)
{
    double e = d->youngs_juvenile;
    if (reaction) {
        double erw = d->reaction_youngs > 0.0 ? d->reaction_youngs : d->youngs_adult;
        e = 0.5 * erw + 0.5 * d->youngs_juvenile;
        double beta = d->reaction_beta;
        r->rest_rate = v3_add(v3_scale(current, 1.0 - beta), v3_scale(rest, beta));
        r->reaction = 0.5;
    } else {
        r->rest_rate = current;
        r->reaction = 0.0;
    }
    r->youngs_modulus = e;
    r->shear_modulus = d->shear_ratio * e;
    r->age = 0.0;
}

static double aged(double e, double dt, const cbm_growth_def *d)
{
    if (d->adult_age <= 0.0 || e >= d->youngs_adult)
        return e;
    double ne = e + dt * (d->youngs_adult - d->youngs_juvenile) / d->adult_age;
    return ne < d->youngs_adult ? ne : d->youngs_adult;
}

/* Merges the rings of a segment into one core of the structural moduli (listing). */
static cbm_status merge_core(cbm_plant *p, size_t seg, double dt, const cbm_growth_def *d)
{
    cbm_segment_state st;
    CBM_TRY(cbm_plant_segment(p, seg, &st));
    cbm_ring outer;
    CBM_TRY(cbm_plant_get_ring(p, seg, st.ring_count - 1, &outer));
    double il, iu, j;
    cbm_mech_ellipse_moments(st.a, st.b, &il, &iu, &j);
    cbm_ring c = outer;
    double e = st.rigidity.y / il, g = st.rigidity.x / j;
    double ne = aged(e, dt, d);
    c.youngs_modulus = ne;
    c.shear_modulus = g * ne / e;
    c.density = st.area > 0.0 ? st.mass_per_length / st.area : outer.density;
    c.rest_rate = st.rest_rate;
    c.age = st.age + dt;
    c.reaction = st.reaction;
    /* drop the outer rings (the run keeps its slots), then write the core (which updates the
     * section) */
    p->ring_count[seg] = 1;
    return cbm_plant_set_ring(p, seg, 0, &c);
}

cbm_status cbm_plant_age_wood(cbm_plant *p, const cbm_growth_def *d, double dt)
{
    if (!p || !d)
        return CBM_E_INVALID;
    CBM_TRY(cbm__growth_check(p->ctx, d));
    if (!(isfinite(dt) && dt >= 0.0))
        return cbm__fail(p->ctx, CBM_E_INVALID, "age_wood: dt must be >= 0 years");
    for (size_t i = 0; i < p->n; i++) {
        if (d->ageing == CBM_AGEING_CORE) {
            CBM_TRY(merge_core(p, i, dt, d));
            continue;
        }
        size_t nr = p->ring_count[i];
        cbm_ring *r = p->rings.data + p->ring_first[i];
        for (size_t k = 0; k < nr; k++) {
            double e = r[k].youngs_modulus, ne = aged(e, dt, d);
            r[k].shear_modulus *= ne / e;
            r[k].youngs_modulus = ne;
            r[k].age += dt;
        }
        /* rewriting the outer ring recomputes the section aggregates */
        cbm_ring last = r[nr - 1];
        CBM_TRY(cbm_plant_set_ring(p, i, nr - 1, &last));
    }
    return CBM_OK;
}

cbm_status cbm_plant_structural_modulus(const cbm_plant *p, size_t seg, double *e, double *g)
{
    if (!p)
        return CBM_E_INVALID;
    cbm_segment_state st;
    CBM_TRY(cbm_plant_segment(p, seg, &st));
    double il, iu, j;
    cbm_mech_ellipse_moments(st.a, st.b, &il, &iu, &j);
    if (e)
        *e = st.rigidity.y / il;
    if (g)
        *g = st.rigidity.x / j;
    return CBM_OK;
}
