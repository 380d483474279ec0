/* Growth memory: primary growth with a tropism rest curvature, pipe-model radial growth, and the
 * rest rotation rate a new ring memorises.
 *
 * Primary growth (Taylor-Hell 2005 §6.1.5, eqs. 6.8-6.12; Jirasek et al. 2000 §SecGrowth). A
 * new segment attached at the distal end of its parent gets the tropism torque
 *     tau = l_parent x F_tropic,   l_parent = len_parent H_parent (world; 6.8),
 * with F_tropic = strength * direction, and its rest rotation rate is the compliance times that
 * torque, componentwise in the new segment's local frame before it bends (the parent's frame
 * times the branching rotation): rest = (tau_H / C_H, tau_L / C_L, tau_U / C_U) (6.9-6.12), C
 * the rigidity of the new segment's core. Its current Omega starts at the rest rate (as in the
 * listing). A root uses its own length and the clamp's heading. The torque turns H towards the
 * tropism direction (a rotation about l x F takes l towards F).
 *
 * Secondary growth (ch. 4.1 eqs. 4.1-4.3; area form 8.12-8.19). Tip to base, a segment with
 * children has the goal area
 *     A_goal = (sum_c A_c^(P/2))^(2/P)        (8.17; for circles r^P = sum r_c^P, 4.1-4.2)
 * from the children's areas after their own growth in this step, plus leaf_area^(P/2) for the
 * leaf or bud every segment carries (the lateral of 4.1 at every node); P = 2 conserves area
 * (the pipe model of Shinozaki; with leaf_area = the area of a new internode it is Jirasek's "a
 * new internode adds its area to every earlier segment"). The
 * goal semi-axis keeps the current aspect zeta = b/a (8.18-8.19): a_goal = sqrt(A_goal /
 * (pi zeta)), and a' = a + kappa (a_goal - a) (4.3), b' = zeta a'. Girth never decreases: a goal
 * below the current size adds nothing. A leaning segment also gets the reaction-wood increment a +=
 * delta (8.20, src/mech/wood.c), which ovalises the section (b is kept).
 *
 * Shape memory (6.29-6.34 = Jirasek eq. 24). A ring laid on a loaded segment is moulded on the
 * deformed segment: its own rest rate is the current rotation rate Omega (6.32/8.24). The
 * segment's rest rate becomes the rigidity-weighted mean per local component,
 *     rest'_c = (C_c rest_c + C'_c Omega_c) / (C_c + C'_c),
 * which the plant keeps as running sums over the rings (src/mech/plant.c: a new ring adds its
 * terms in O(1)), C' being the ring's own rigidity (outer minus inner second moments,
 * 8.21-8.22). The current rate used is the segment's material rate (cbm_segment_state.rate,
 * CBM_MEMORY_SEGMENT: rest + C^-1 times the mean of the moments at the segment's two ends) so
 * that, under unchanged load, the new equilibrium is the old shape (exactly for the chain
 * discretisation, where a segment is one joint; to O(h^2) for the staggered one, where a joint
 * spans two half segments). CBM_MEMORY_JOINT memorises the proximal joint's Omega as the
 * listing does (Ring_omega_e = Omega).
 */
#include "mech/growth_internal.h"
#include "core/vecmath.h"

#include <math.h>

cbm_tropism cbm_tropism_default(void)
{
    cbm_tropism t = {{0.0, 1.0, 0.0}, 0.0};
    return t;
}

cbm_growth_def cbm_growth_def_default(void)
{
    cbm_growth_def d;
    memset(&d, 0, sizeof d);
    d.pipe_exponent = 2.0;
    d.pipe_rate = 1.0;
    d.min_ring = 1e-9;
    d.youngs_juvenile = 10e9;
    d.youngs_adult = 10e9;
    d.adult_age = 0.0;
    d.shear_ratio = 1.0 / 16.0;
    d.density = 600.0;
    d.memory = CBM_MEMORY_SEGMENT;
    d.ageing = CBM_AGEING_RINGS;
    d.reaction_threshold = INFINITY;
    d.reaction_beta = 0.0;
    d.reaction_increment = 0.001;
    return d;
}

cbm_status cbm__growth_check(cbm_context *ctx, const cbm_growth_def *d)
{
    const char *bad = NULL;
    if (!(isfinite(d->pipe_exponent) && d->pipe_exponent > 0.0))
        bad = "pipe_exponent must be positive";
    else if (!(isfinite(d->pipe_rate) && d->pipe_rate > 0.0 && d->pipe_rate <= 1.0))
        bad = "pipe_rate must be in (0, 1]";
    else if (!(isfinite(d->min_ring) && d->min_ring >= 0.0))
        bad = "min_ring must be >= 0";
    else if (!(isfinite(d->leaf_area) && d->leaf_area >= 0.0))
        bad = "leaf_area must be >= 0";
    else if (!(isfinite(d->youngs_juvenile) && d->youngs_juvenile > 0.0))
        bad = "youngs_juvenile must be positive";
    else if (!(isfinite(d->youngs_adult) && d->youngs_adult >= d->youngs_juvenile))
        bad = "youngs_adult must be >= youngs_juvenile";
    else if (!(isfinite(d->adult_age) && d->adult_age >= 0.0))
        bad = "adult_age must be >= 0";
    else if (!(isfinite(d->shear_ratio) && d->shear_ratio > 0.0))
        bad = "shear_ratio must be positive";
    else if (!(isfinite(d->density) && d->density >= 0.0))
        bad = "density must be >= 0";
    else if (!(isfinite(d->modulus_of_rupture) && d->modulus_of_rupture >= 0.0))
        bad = "modulus_of_rupture must be >= 0";
    else if (d->memory != CBM_MEMORY_SEGMENT && d->memory != CBM_MEMORY_JOINT)
        bad = "memory is not a cbm_ring_memory";
    else if (d->ageing != CBM_AGEING_RINGS && d->ageing != CBM_AGEING_CORE)
        bad = "ageing is not a cbm_ageing";
    else if (isnan(d->reaction_threshold) || d->reaction_threshold < 0.0)
        bad = "reaction_threshold must be >= 0";
    else if (!(isfinite(d->reaction_beta) && d->reaction_beta >= 0.0 && d->reaction_beta <= 1.0))
        bad = "reaction_beta must be in [0, 1]";
    else if (!(isfinite(d->reaction_increment) && d->reaction_increment >= 0.0))
        bad = "reaction_increment must be >= 0";
    else if (!(isfinite(d->reaction_youngs) && d->reaction_youngs >= 0.0))
        bad = "reaction_youngs must be >= 0";
    else if (!v3_isfinite(d->control_rate) || !isfinite(d->control_up))
        bad = "control_rate and control_up must be finite";
    else if (!(isfinite(d->reaction_max_aspect) &&
               (d->reaction_max_aspect == 0.0 || d->reaction_max_aspect >= 1.0)))
        bad = "reaction_max_aspect must be 0 (no bound) or >= 1";
    else if (!(isfinite(d->reaction_full_lean) && d->reaction_full_lean >= 0.0 &&
               d->reaction_full_lean <= 0.5 * CBM_PI))
        bad = "reaction_full_lean must be in [0, pi/2] rad";
    if (bad)
        return cbm__fail(ctx, CBM_E_INVALID, "growth: %s", bad);
    return CBM_OK;
}

/* the branching rotation B = R_H(divergence) R_U(deviation) R_H(roll) (as the plant builds it) */
static cbm_quat branching(double div, double dev, double roll)
{
    cbm_quat a = q_axis_angle(v3(1, 0, 0), div);
    cbm_quat b = q_axis_angle(v3(0, 0, 1), dev);
    cbm_quat c = q_axis_angle(v3(1, 0, 0), roll);
    return q_normalize(q_mul(q_mul(a, b), c));
}

cbm_status cbm_plant_grow_segment(cbm_plant *p, const cbm_segment_def *def,
                                  const cbm_tropism *tropism, size_t *index)
{
    if (!p || !def)
        return CBM_E_INVALID;
    cbm_segment_def d = *def;
    cbm_vec3 rest = v3(0, 0, 0);
    if (tropism && tropism->strength != 0.0) {
        if (!isfinite(tropism->strength) || !v3_isfinite(tropism->direction) ||
            v3_norm(tropism->direction) == 0.0)
            return cbm__fail(p->ctx, CBM_E_INVALID,
                             "tropism: strength must be finite and direction non-zero");
        /* bad parent, length or core are reported by cbm_plant_add_segment */
        bool parent_ok = d.parent == -1 || (d.parent >= 0 && (size_t)d.parent < p->n);
        if (parent_ok && isfinite(d.length) && d.length > 0.0 && d.core.a > 0.0 && d.core.b > 0.0 &&
            d.core.youngs_modulus > 0.0 && d.core.shear_modulus > 0.0) {
            cbm_quat qp = d.parent >= 0 ? p->q[d.parent] : p->base_q;
            double lp = d.parent >= 0 ? p->len[d.parent] : d.length;
            cbm_vec3 f = v3_scale(v3_normalize(tropism->direction), tropism->strength);
            cbm_vec3 tau = v3_cross(v3_scale(q_rotate(qp, v3(1, 0, 0)), lp), f);
            cbm_quat q0 = q_mul(qp, branching(d.divergence, d.deviation, d.roll));
            cbm_vec3 tl = q_rotate(q_conj(q0), tau);
            double il, iu, j;
            cbm_mech_ellipse_moments(d.core.a, d.core.b, &il, &iu, &j);
            rest = v3(tl.x / (d.core.shear_modulus * j), tl.y / (d.core.youngs_modulus * il),
                      tl.z / (d.core.youngs_modulus * iu));
        }
    }
    d.core.rest_rate = rest;
    d.omega = rest;
    return cbm_plant_add_segment(p, &d, index);
}

cbm_status cbm_plant_upright_roll(const cbm_plant *p, const cbm_segment_def *def, double *roll)
{
    if (!p || !def || !roll)
        return CBM_E_INVALID;
    *roll = 0.0;
    if (def->parent < -1 || (def->parent >= 0 && (size_t)def->parent >= p->n))
        return cbm__fail(p->ctx, CBM_E_INVALID, "upright roll: parent %lld is not a segment",
                         (long long)def->parent);
    if (!isfinite(def->divergence) || !isfinite(def->deviation))
        return cbm__fail(p->ctx, CBM_E_INVALID, "upright roll: branching angles must be finite");
    cbm_quat qp = def->parent >= 0 ? p->q[def->parent] : p->base_q;
    cbm_quat q0 = q_mul(qp, branching(def->divergence, def->deviation, 0.0));
    cbm_vec3 h = q_rotate(q0, v3(1, 0, 0)), l = q_rotate(q0, v3(0, 1, 0));
    cbm_vec3 u = q_rotate(q0, v3(0, 0, 1));
    double gn = v3_norm(p->gravity);
    cbm_vec3 up = gn > 0.0 ? v3_scale(p->gravity, -1.0 / gn) : v3(0, 1, 0);
    /* U* = H x (up x H) = up - (up . H) H */
    cbm_vec3 want = v3_sub(up, v3_scale(h, v3_dot(up, h)));
    double wn = v3_norm(want);
    if (wn < 1e-12)
        return CBM_OK;
    want = v3_scale(want, 1.0 / wn);
    /* a roll phi about H takes U to cos(phi) U - sin(phi) L */
    *roll = atan2(-v3_dot(want, l), v3_dot(want, u));
    return CBM_OK;
}

cbm_vec3 cbm__growth_control(const cbm_plant *p, size_t seg, cbm_vec3 rate, double up)
{
    if (up == 0.0)
        return rate;
    double gn = v3_norm(p->gravity);
    cbm_vec3 u = gn > 0.0 ? v3_scale(p->gravity, -1.0 / gn) : v3(0, 1, 0);
    cbm_vec3 h = q_rotate(p->q[seg], v3(1, 0, 0));
    /* a rotation about H x up turns H towards up */
    cbm_vec3 ax = v3_cross(h, u);
    double an = v3_norm(ax);
    if (an < 1e-12)
        return rate;
    cbm_vec3 loc = q_rotate(q_conj(p->q[seg]), v3_scale(ax, up / an));
    return v3_add(rate, loc);
}

/* The ring of new wood on segment `seg` (outer semi-axes a, b), memorising `cur` plus the
 * control rate kappa^c (wood.c fills the material and the rest rate, reaction wood or not). */
static cbm_status growth_ring(cbm_plant *p, size_t seg, double a, double b, const cbm_growth_def *d,
                              bool reaction, cbm_vec3 cur)
{
    cur = v3_add(cur, cbm__growth_control(p, seg, d->control_rate, d->control_up));
    cbm_ring r;
    memset(&r, 0, sizeof r);
    r.a = a;
    r.b = b;
    r.density = d->density;
    r.modulus_of_rupture = d->modulus_of_rupture;
    cbm__wood_new_ring(d, reaction, cur, p->rest[seg], &r);
    return cbm_plant_add_ring(p, seg, &r);
}

cbm_status cbm_plant_add_growth_ring(cbm_plant *p, size_t seg, double a, double b,
                                     const cbm_growth_def *def, bool *reaction)
{
    if (!p || !def)
        return CBM_E_INVALID;
    CBM_TRY(cbm__growth_check(p->ctx, def));
    if (seg >= p->n)
        return cbm__fail(p->ctx, CBM_E_INVALID, "segment %zu does not exist (plant has %zu)", seg,
                         p->n);
    /* O(1): no visit of the segment's rings (cbm_plant_segment would) */
    cbm_vec3 cur =
        def->memory == CBM_MEMORY_JOINT ? p->omega[seg] : cbm__plant_segment_rate(p, seg);
    bool rw = cbm__wood_leans(def, cur, p->rest[seg]);
    CBM_TRY(growth_ring(p, seg, a, b, def, rw, cur));
    if (reaction)
        *reaction = rw;
    return CBM_OK;
}

cbm_status cbm__growth_rates(cbm_plant *p, cbm_ring_memory memory, cbm_vec3 *out)
{
    size_t n = p->n;
    if (memory == CBM_MEMORY_JOINT || p->disc == CBM_MECH_CHAIN) {
        memcpy(out, p->omega, n * sizeof *out);
        return CBM_OK;
    }
    /* the moment at each distal node: the continuation child's joint moment, or the tip moment
     * at a free end (as cbm_segment_state.rate) */
    int64_t *cc = cbm__alloc(p->ctx, n * sizeof *cc);
    if (!cc)
        return CBM_E_NOMEM;
    for (size_t i = 0; i < n; i++)
        cc[i] = -1;
    for (size_t i = 0; i < n; i++) {
        int64_t pa = p->parent[i];
        if (pa >= 0 && (p->cont[i] & 1) && cc[pa] < 0)
            cc[pa] = (int64_t)i;
    }
    for (size_t i = 0; i < n; i++) {
        cbm_vec3 md = cc[i] >= 0
                          ? p->moment[cc[i]]
                          : (p->nchild[i] == 0 ? v3_scale(p->tipm[i], p->load_scale) : v3(0, 0, 0));
        cbm_vec3 m = v3_scale(v3_add(p->moment[i], md), 0.5);
        cbm_quat qc = q_conj(p->q[i]);
        cbm_vec3 ml = q_rotate(qc, m), c = p->rig[i], r = p->rest[i];
        out[i] = v3(r.x + ml.x / c.x, r.y + ml.y / c.y, r.z + ml.z / c.z);
    }
    cbm__free(p->ctx, cc, n * sizeof *cc);
    return CBM_OK;
}

/* The stimulus of reaction wood: the angle theta by which each segment's heading has left its
 * set-point, the heading its rest shape would give it. The loaded shape turns a segment away
 * from its rest shape by (Omega - rest) len over its length (a rotation vector, taken to world
 * axes); summed from the base (small rotations add), the sum at a segment's middle is the turn
 * of its heading from the set-point, and its part about the heading itself (twist) is no lean.
 * dose = min(1, sin(theta) / sin(full lean)): the response grows with the sine of the lean as
 * the graviceptive term of the AC model (Bastien et al. 2013) and the eccentric growth of
 * inclined stems with their inclination (Sinnott 1952; Alméras & Fournier 2009). Parents come
 * before their children in the plant's order. */
static cbm_status reaction_dose(const cbm_plant *p, const cbm_growth_def *def, const cbm_vec3 *cur,
                                double *dose)
{
    size_t n = p->n;
    cbm_vec3 *prox = cbm__alloc(p->ctx, n * sizeof *prox);
    if (!prox)
        return CBM_E_NOMEM;
    const double full =
        sin(def->reaction_full_lean < 0.5 * CBM_PI ? def->reaction_full_lean : 0.5 * CBM_PI);
    for (size_t i = 0; i < n; i++) {
        int64_t pa = p->parent[i];
        cbm_vec3 turn = v3_scale(q_rotate(p->q[i], v3_sub(cur[i], p->rest[i])), p->len[i]);
        cbm_vec3 base = v3(0, 0, 0);
        if (pa >= 0) {
            cbm_vec3 tp = v3_scale(q_rotate(p->q[pa], v3_sub(cur[pa], p->rest[pa])), p->len[pa]);
            base = v3_add(prox[pa], tp);
        }
        prox[i] = base;
        cbm_vec3 mid = v3_madd(base, turn, 0.5);
        cbm_vec3 h = q_rotate(p->q[i], v3(1, 0, 0));
        double theta = v3_norm(v3_sub(mid, v3_scale(h, v3_dot(mid, h))));
        double d = sin(theta < 0.5 * CBM_PI ? theta : 0.5 * CBM_PI) / full;
        dose[i] = d < 1.0 ? d : 1.0;
    }
    cbm__free(p->ctx, prox, n * sizeof *prox);
    return CBM_OK;
}

cbm_status cbm_plant_grow_rings(cbm_plant *p, const cbm_growth_def *def, cbm_growth_stats *stats)
{
    cbm_growth_stats gs;
    memset(&gs, 0, sizeof gs);
    if (stats)
        *stats = gs;
    if (!p || !def)
        return CBM_E_INVALID;
    CBM_TRY(cbm__growth_check(p->ctx, def));
    size_t n = p->n;
    if (n == 0)
        return CBM_OK;
    /* acc[i] = sum over the children of i of area^(P/2) after their growth; cur[i] = the rate a
     * ring on i memorises, from the state before this step */
    double *acc = cbm__calloc(p->ctx, n, sizeof *acc);
    cbm_vec3 *cur = cbm__alloc(p->ctx, n * sizeof *cur);
    cbm_status s = acc && cur ? cbm__growth_rates(p, def->memory, cur) : CBM_E_NOMEM;
    /* the lean stimulus: the share of the full increment each segment lays (NULL = all of it) */
    double *dose = NULL;
    if (s == CBM_OK && def->reaction_full_lean > 0.0) {
        dose = cbm__alloc(p->ctx, n * sizeof *dose);
        s = dose ? reaction_dose(p, def, cur, dose) : CBM_E_NOMEM;
    }
    const double h = 0.5 * def->pipe_exponent;
    /* pow(x, 1) is x exactly: the area-preserving P = 2 needs no pow */
    const double leaf = h == 1.0 ? def->leaf_area : pow(def->leaf_area, h);
    for (size_t i = n; s == CBM_OK && i-- > 0;) {
        double a = p->outer[i].a, b = p->outer[i].b, zeta = b / a;
        double na = a;
        {
            double goal = h == 1.0 ? acc[i] + leaf : pow(acc[i] + leaf, 1.0 / h);
            double ag = sqrt(goal / (CBM_PI * zeta));
            if (ag > a)
                na = a + def->pipe_rate * (ag - a);
        }
        double nb = zeta * na;
        bool rw = cbm__wood_leans(def, cur[i], p->rest[i]);
        if (rw) {
            na += dose ? dose[i] * def->reaction_increment : def->reaction_increment;
            double k = def->reaction_max_aspect;
            if (k >= 1.0 && na > k * nb) {
                /* eccentric growth is bounded in real wood: the reaction ring's area goes round
                 * the section at the bound's aspect (its rigidity and memory stay) */
                nb = sqrt(na * nb / k);
                na = k * nb;
            }
        }
        if (nb < b)
            nb = b;
        if (na < nb)
            na = nb;
        if (na - a > def->min_ring || (rw && def->reaction_increment > 0.0)) {
            s = growth_ring(p, i, na, nb, def, rw, cur[i]);
            if (s != CBM_OK)
                break;
            gs.rings_added++;
            gs.reaction_rings += rw ? 1 : 0;
            if (na - a > gs.max_increment)
                gs.max_increment = na - a;
        } else {
            na = a;
            nb = b;
        }
        if (p->parent[i] >= 0)
            acc[p->parent[i]] += h == 1.0 ? CBM_PI * na * nb : pow(CBM_PI * na * nb, h);
    }
    if (acc)
        cbm__free(p->ctx, acc, n * sizeof *acc);
    if (cur)
        cbm__free(p->ctx, cur, n * sizeof *cur);
    if (dose)
        cbm__free(p->ctx, dose, n * sizeof *dose);
    if (stats)
        *stats = gs;
    return s;
}
