/* Oberlaender's tree under cambium's statics (issue 13, item 4, beyond the thesis): a tree of the
 * stand becomes a mechanical plant (cambium/mech.h) and is brought to equilibrium under its own
 * weight, so that the shape the statics give can be set against the shape of the kinematic
 * gravitropism joint.
 *
 * The plant: every annual shoot of N nodes is N straight segments of length len/N (a lateral bud
 * at node k sits at the distal end of the k-th, so the laterals attach where the turtle puts
 * them; the continuation and the fork arms at the N-th), with the shoot's pipe-model radius as a
 * round section of one ring of wood (def: E, G = E/16, green density). Its rest shape is the
 * turtle's shape WITHOUT the joint: the head and insertion angles only (each shoot straight along
 * its mother's frame turned by its head and insertion angles), so that the statics alone do the
 * bending the joint does in the thesis. The shoot's living leaves hang as point masses, spread
 * evenly over the distal ends of its N segments. The base is clamped upright at the tree's
 * position. Only the final tree is solved (one equilibrium, not a history: no rings laid down on
 * the bent shape, no yearly growth of the plant); docs/models.md says so. */
#include "core/vecmath.h"
#include "tree/ober_internal.h"

#include "cambium/mech.h"

#include <math.h>

#define DEG (CBM_PI / 180.0)

cbm_ober_mech_def cbm_ober_mech_def_default(void)
{
    return (cbm_ober_mech_def){
        .youngs_modulus = 8e9, .density = 800, .leaf_mass_per_area = 0.2, .gravity = 9.81};
}

static cbm_vec3 rot(cbm_vec3 v, cbm_vec3 axis, double a)
{
    double c = cos(a), s = sin(a);
    return v3_add(v3_add(v3_scale(v, c), v3_scale(v3_cross(axis, v), s)),
                  v3_scale(axis, v3_dot(axis, v) * (1 - c)));
}

typedef struct frame3 {
    cbm_vec3 H, L, U, base, tip; /* m */
} frame3;

/* The shoots' frames without the gravitropism joint (ober_grow.c geometry() less the RV). */
static void straight(const cbm_ober_stand *s, frame3 *f)
{
    for (size_t i = 0; i < s->shoots.len; i++) {
        const ober_shoot *h = &s->shoots.data[i];
        cbm_vec3 H, L, U, base;
        if (h->parent < 0) {
            base = v3_scale(s->trees.data[h->tree].pos, 0.01);
            H = v3(0, 1, 0), L = v3(1, 0, 0), U = v3(0, 0, -1);
        } else {
            const frame3 *m = &f[h->parent];
            const ober_shoot *mh = &s->shoots.data[h->parent];
            H = m->H, L = m->L, U = m->U;
            base = h->node == 0 ? m->tip
                                : v3_madd(m->base, m->H, mh->len * 0.01 * h->node / mh->nodes);
        }
        if (h->insert != 0) {
            L = rot(L, H, h->head * DEG);
            U = rot(U, H, h->head * DEG);
            H = rot(H, L, h->insert * DEG);
            U = rot(U, L, h->insert * DEG);
        }
        f[i].H = v3_normalize(H), f[i].L = v3_normalize(L), f[i].U = v3_normalize(U);
        f[i].base = base;
        f[i].tip = v3_madd(base, f[i].H, h->len * 0.01);
    }
}

/* Divergence (about the parent's H), deviation (about the spun U, H towards L) and roll (about
 * the new H) that turn the parent frame (Hp, Lp, Up) into (H, L). */
static void angles(cbm_vec3 Hp, cbm_vec3 Lp, cbm_vec3 Up, cbm_vec3 H, cbm_vec3 L, double *div,
                   double *dev, double *roll)
{
    cbm_vec3 h = v3(v3_dot(H, Hp), v3_dot(H, Lp), v3_dot(H, Up));
    cbm_vec3 l = v3(v3_dot(L, Hp), v3_dot(L, Lp), v3_dot(L, Up));
    *dev = acos(fmax(-1.0, fmin(1.0, h.x)));
    *div = hypot(h.y, h.z) > 1e-12 ? atan2(h.z, h.y) : 0;
    double sd = sin(*dev), cd = cos(*dev), sv = sin(*div), cv = cos(*div);
    cbm_vec3 l1 = v3(-sd, cd * cv, cd * sv), u1 = v3(0, -sv, cv);
    *roll = atan2(v3_dot(l, u1), v3_dot(l, l1));
}

cbm_status cbm_ober_mechanics(const cbm_ober_stand *s, size_t tree, const cbm_ober_mech_def *def,
                              cbm_ober_mech_result *out, cbm_plant **plant_out)
{
    if (plant_out)
        *plant_out = NULL;
    if (!s || !def || !out || tree >= s->trees.len)
        return CBM_E_INVALID;
    cbm_context *ctx = s->ctx;
    if (!(def->youngs_modulus > 0) || !(def->density >= 0) || !(def->leaf_mass_per_area >= 0) ||
        !(def->gravity >= 0) ||
        !isfinite(def->youngs_modulus + def->density + def->leaf_mass_per_area + def->gravity))
        return cbm__fail(ctx, CBM_E_INVALID,
                         "ober mechanics: E > 0, density, leaf mass per area and gravity >= 0");
    memset(out, 0, sizeof *out);
    out->tree = tree;
    size_t n = s->shoots.len, m = n ? n : 1;
    frame3 *f = cbm__alloc(ctx, m * sizeof *f);
    int64_t *first = cbm__alloc(ctx, m * sizeof *first); /* shoot -> its first segment */
    uint8_t *taken = cbm__calloc(ctx, m, 1);
    cbm_plant *p = NULL;
    cbm_status st = CBM_OK;
    if (!f || !first || !taken) {
        st = CBM_E_NOMEM;
        goto done;
    }
    straight(s, f);
    cbm_plant_def pd = cbm_plant_def_default();
    pd.gravity = v3(0, -def->gravity, 0);
    pd.base_position = v3_scale(s->trees.data[tree].pos, 0.01);
    pd.base_orientation = cbm_mech_clamp_orientation(CBM_PI / 2);
    if ((st = cbm_plant_create(ctx, &pd, &p)) != CBM_OK)
        goto done;
    /* the clamp's frame: H = (0, 1, 0), U = (-1, 0, 0), L = (0, 0, -1) */
    const cbm_vec3 cH = v3(0, 1, 0), cL = v3(0, 0, -1), cU = v3(-1, 0, 0);
    double leaf = def->leaf_mass_per_area * s->def.leaf_length * s->def.leaf_width * 1e-4;
    for (size_t i = 0; i < n && st == CBM_OK; i++) {
        const ober_shoot *h = &s->shoots.data[i];
        first[i] = -1;
        if (h->tree != (int32_t)tree)
            continue;
        int nodes = h->nodes > 0 ? h->nodes : 1;
        double r = fmax(h->radius * 0.01, 1e-5), len = fmax(h->len * 0.01, 1e-6);
        cbm_segment_def sd = cbm_segment_def_default();
        sd.length = len / nodes;
        sd.core.youngs_modulus = def->youngs_modulus;
        sd.core.shear_modulus = def->youngs_modulus / 16;
        sd.core.density = def->density;
        sd.core.a = sd.core.b = r;
        sd.core.modulus_of_rupture = 0;
        sd.point_mass = leaf * h->leaves / nodes;
        if (h->parent < 0) {
            sd.parent = -1;
            angles(cH, cL, cU, f[i].H, f[i].L, &sd.divergence, &sd.deviation, &sd.roll);
        } else {
            const ober_shoot *mh = &s->shoots.data[h->parent];
            int mnodes = mh->nodes > 0 ? mh->nodes : 1;
            int at = h->node == 0 ? mnodes : h->node;
            sd.parent = first[h->parent] + at - 1;
            const frame3 *mf = &f[h->parent];
            angles(mf->H, mf->L, mf->U, f[i].H, f[i].L, &sd.divergence, &sd.deviation, &sd.roll);
            /* the continuation and a fork's first arm continue the axis, the rest branch */
            sd.lateral = h->lateral || taken[h->parent];
            if (!h->lateral)
                taken[h->parent] = 1;
        }
        size_t idx = 0;
        if ((st = cbm_plant_add_segment(p, &sd, &idx)) != CBM_OK)
            break;
        first[i] = (int64_t)idx;
        cbm_segment_def next = sd;
        next.divergence = next.deviation = next.roll = 0;
        next.lateral = false;
        for (int k = 1; k < nodes && st == CBM_OK; k++) {
            next.parent = (int64_t)(idx + (size_t)k - 1);
            st = cbm_plant_add_segment(p, &next, NULL);
        }
        out->shoots++;
    }
    if (st != CBM_OK || out->shoots == 0)
        goto done;
    out->segments = cbm_plant_segment_count(p);
    out->mass = cbm_plant_total_mass(p);
    cbm_solve_def sv = cbm_solve_def_default();
    cbm_solve_stats stats;
    memset(&stats, 0, sizeof stats);
    cbm_status ss = cbm_plant_solve(p, &sv, &stats);
    if (ss != CBM_OK && ss != CBM_E_NOT_CONVERGED) {
        st = ss;
        goto done;
    }
    out->converged = ss == CBM_OK;
    out->residual = stats.residual;
    /* tips: the kinematic (joint) shape, the straight rest shape, the statics */
    double sum = 0;
    for (size_t i = 0; i < n && st == CBM_OK; i++) {
        const ober_shoot *h = &s->shoots.data[i];
        if (first[i] < 0)
            continue;
        int nodes = h->nodes > 0 ? h->nodes : 1;
        cbm_segment_state ss2;
        if ((st = cbm_plant_segment(p, (size_t)first[i] + (size_t)nodes - 1, &ss2)) != CBM_OK)
            break;
        cbm_vec3 kin = v3_scale(h->tip, 0.01);
        double d = v3_norm(v3_sub(ss2.distal, kin));
        double sag = v3_norm(v3_sub(ss2.distal, f[i].tip));
        sum += d;
        if (d > out->max_tip_difference) {
            out->max_tip_difference = d;
            out->max_shoot = i;
        }
        out->max_sag = fmax(out->max_sag, sag);
        out->max_joint = fmax(out->max_joint, v3_norm(v3_sub(kin, f[i].tip)));
        out->kinematic_height = fmax(out->kinematic_height, kin.y - pd.base_position.y);
        out->mechanical_height = fmax(out->mechanical_height, ss2.distal.y - pd.base_position.y);
        out->mechanical_height = fmax(out->mechanical_height, ss2.proximal.y - pd.base_position.y);
    }
    out->mean_tip_difference = out->shoots ? sum / (double)out->shoots : 0;
done:
    if (st == CBM_OK && plant_out)
        *plant_out = p;
    else
        cbm_plant_destroy(p);
    cbm__free(ctx, f, m * sizeof *f);
    cbm__free(ctx, first, m * sizeof *first);
    cbm__free(ctx, taken, m);
    return st;
}
