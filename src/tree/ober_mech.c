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
 * bending the joint does in the thesis (on a tree grown with mechanicsFeedback, plus the bends
 * its wood memorised: straight() says which). The shoot's living leaves hang as point masses,
 * spread evenly over the distal ends of its N segments. The base is clamped upright at the tree's
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

static cbm_vec3 rotate_about(cbm_vec3 v, cbm_vec3 axis, double a)
{
    double c = cos(a), s = sin(a);
    return v3_add(v3_add(v3_scale(v, c), v3_scale(v3_cross(axis, v), s)),
                  v3_scale(axis, v3_dot(axis, v) * (1 - c)));
}

typedef struct frame3 {
    cbm_vec3 H, L, U, base, tip; /* m */
} frame3;

/* The shoots' frames without the gravitropism joint (ober_grow.c geometry() less the RV and the
 * elastic part of the feedback's bend). */
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
            L = rotate_about(L, H, h->head * DEG);
            U = rotate_about(U, H, h->head * DEG);
            H = rotate_about(H, L, h->insert * DEG);
            U = rotate_about(U, L, h->insert * DEG);
        }
        /* the bend the wood had memorised under mechanicsFeedback when this year's statics
         * bent it (the rest shape the feedback solved from, less the joint), in the shoot's
         * frame as ober_grow.c applies it: the statics then finds this year's bend again, and
         * the difference left is the joint's. Not this year's share of the memory: the
         * feedback's equilibrium is the old memory plus the whole bend d (w d memorised,
         * (1 - w) d elastic), so starting from the new memory would count w d twice. Zero
         * without the feedback: the shape is as before. */
        double wn = v3_norm(h->bend_rest);
        if (wn > 0) {
            cbm_vec3 w = h->bend_rest;
            cbm_vec3 a = v3_scale(
                v3_add(v3_add(v3_scale(H, w.x), v3_scale(L, w.y)), v3_scale(U, w.z)), 1.0 / wn);
            H = rotate_about(H, a, wn);
            L = rotate_about(L, a, wn);
            U = rotate_about(U, a, wn);
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

/* Makes tree `tree` a mechanical plant whose rest shape is the frames f (m): each shoot N
 * segments, first[i] its first segment (-1: another tree's); *shoots counts them. */
static cbm_status build_plant(const cbm_ober_stand *s, size_t tree, const cbm_ober_mech_def *def,
                              const frame3 *f, int64_t *first, uint8_t *taken, cbm_plant **out,
                              size_t *shoots)
{
    cbm_context *ctx = s->ctx;
    size_t n = s->shoots.len;
    *out = NULL;
    *shoots = 0;
    memset(taken, 0, n ? n : 1);
    cbm_plant *p = NULL;
    cbm_plant_def pd = cbm_plant_def_default();
    pd.gravity = v3(0, -def->gravity, 0);
    pd.base_position = v3_scale(s->trees.data[tree].pos, 0.01);
    pd.base_orientation = cbm_mech_clamp_orientation(CBM_PI / 2);
    CBM_TRY(cbm_plant_create(ctx, &pd, &p));
    /* the clamp's frame: H = (0, 1, 0), U = (-1, 0, 0), L = (0, 0, -1) */
    const cbm_vec3 cH = v3(0, 1, 0), cL = v3(0, 0, -1), cU = v3(-1, 0, 0);
    double leaf = def->leaf_mass_per_area * s->def.leaf_length * s->def.leaf_width * 1e-4;
    cbm_status st = CBM_OK;
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
        ++*shoots;
    }
    if (st != CBM_OK) {
        cbm_plant_destroy(p);
        return st;
    }
    *out = p;
    return CBM_OK;
}

static cbm_status check_mech(cbm_context *ctx, const cbm_ober_mech_def *def)
{
    if (!(def->youngs_modulus > 0) || !(def->density >= 0) || !(def->leaf_mass_per_area >= 0) ||
        !(def->gravity >= 0) ||
        !isfinite(def->youngs_modulus + def->density + def->leaf_mass_per_area + def->gravity))
        return cbm__fail(ctx, CBM_E_INVALID,
                         "ober mechanics: E > 0, density, leaf mass per area and gravity >= 0");
    return CBM_OK;
}

cbm_status cbm_ober_mechanics(const cbm_ober_stand *s, size_t tree, const cbm_ober_mech_def *def,
                              cbm_ober_mech_result *out, cbm_plant **plant_out)
{
    if (plant_out)
        *plant_out = NULL;
    if (!s || !def || !out || tree >= s->trees.len)
        return CBM_E_INVALID;
    cbm_context *ctx = s->ctx;
    CBM_TRY(check_mech(ctx, def));
    memset(out, 0, sizeof *out);
    out->tree = tree;
    const cbm_vec3 base_position = v3_scale(s->trees.data[tree].pos, 0.01);
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
    if ((st = build_plant(s, tree, def, f, first, taken, &p, &out->shoots)) != CBM_OK)
        goto done;
    if (st != CBM_OK || out->shoots == 0)
        goto done;
    out->segments = cbm_plant_segment_count(p);
    out->mass = cbm_plant_total_mass(p);
    cbm_solve_def sv = cbm_solve_def_default();
    sv.threads = s->def.solve_threads;
    sv.confirm_modes = false; /* no mode count read */
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
        out->kinematic_height = fmax(out->kinematic_height, kin.y - base_position.y);
        out->mechanical_height = fmax(out->mechanical_height, ss2.distal.y - base_position.y);
        out->mechanical_height = fmax(out->mechanical_height, ss2.proximal.y - base_position.y);
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

/* ---- mechanics in the growth (mechanicsFeedback) ----
 *
 * Every year, after the growth step, each tree becomes a plant as above, but its rest shape is
 * the tree as it stands with the joint and the bends its wood memorised in earlier years (not
 * the straight shape), and the statics bends it under this year's weight. Each annual shoot stays
 * straight in the model: its new direction is its chord in the solved plant (first segment's
 * proximal node to last segment's distal node). The bend is stored per shoot as a rotation in
 * its own frame relative to its mother's: with W_m the (minimal) rotation that took the mother
 * from its rest direction to its chord, the shoot's bend d is the minimal rotation from W_m H
 * to its own chord, in the components of W_m (H, L, U). Of d, the share w = 1 - (r_0 / r)^4
 * is memorised (r_0 the radius when the shoot last memorised, 0 for a new shoot): the new wood
 * laid down this year, w of the section's bending stiffness, grows stress-free in the bent shape
 * (the rings of cambium's growth, docs/methods.md), so the rest shape moves by w d; the rest,
 * (1 - w) d, stays elastic. A shoot that thickens little keeps sagging elastically from the same
 * rest shape; one that thickens keeps its droop. Approximations: the rotations add as vectors
 * (exact when they share an axis), a lateral starts on its mother's chord at its node (the solved
 * plant has it on the curved mother), twist about a shoot's axis is dropped. */

static cbm_vec3 min_rotation(cbm_vec3 from, cbm_vec3 to) /* axis x angle, unit vectors */
{
    cbm_vec3 c = v3_cross(from, to);
    double sn = v3_norm(c), cs = v3_dot(from, to);
    if (!(sn > 1e-15))
        return v3(0, 0, 0);
    return v3_scale(c, atan2(sn, cs) / sn);
}

static cbm_vec3 apply_rotation(cbm_vec3 w, cbm_vec3 v)
{
    double a = v3_norm(w);
    return a > 0 ? rotate_about(v, v3_scale(w, 1.0 / a), a) : v;
}

cbm_status cbm__ober_feedback(cbm_ober_stand *s)
{
    cbm_context *ctx = s->ctx;
    cbm_ober_mech_def md = cbm_ober_mech_def_default();
    md.youngs_modulus = s->def.mech_e;
    md.density = s->def.mech_density;
    md.leaf_mass_per_area = s->def.mech_leaf_mass;
    CBM_TRY(check_mech(ctx, &md));
    size_t n = s->shoots.len, m = n ? n : 1;
    for (size_t i = 0; i < n; i++)
        s->shoots.data[i].bend_el = v3(0, 0, 0);
    cbm__ober_geometry(s); /* the rest shape: joints and memorised bends */
    frame3 *f = cbm__alloc(ctx, m * sizeof *f);
    cbm_vec3 *world = cbm__calloc(ctx, m, sizeof *world); /* W of each shoot */
    int64_t *first = cbm__alloc(ctx, m * sizeof *first);
    uint8_t *taken = cbm__calloc(ctx, m, 1);
    uint8_t *has = cbm__calloc(ctx, s->trees.len ? s->trees.len : 1, 1);
    cbm_status st = f && world && first && taken && has ? CBM_OK : CBM_E_NOMEM;
    for (size_t i = 0; i < n && st == CBM_OK; i++) {
        const ober_shoot *h = &s->shoots.data[i];
        f[i].H = h->H, f[i].L = h->L, f[i].U = h->U;
        f[i].base = v3_scale(h->base, 0.01);
        f[i].tip = v3_scale(h->tip, 0.01);
        has[h->tree] = 1;
    }
    for (size_t t = 0; t < s->trees.len && st == CBM_OK; t++) {
        if (!has[t])
            continue;
        cbm_plant *p = NULL;
        size_t shoots = 0;
        if ((st = build_plant(s, t, &md, f, first, taken, &p, &shoots)) != CBM_OK)
            break;
        cbm_solve_def sv = cbm_solve_def_default();
        sv.threads = s->def.solve_threads;
        sv.confirm_modes = false; /* no mode count read */
        cbm_solve_stats stats;
        memset(&stats, 0, sizeof stats);
        cbm_status ss = cbm_plant_solve(p, &sv, &stats);
        if (ss != CBM_OK && ss != CBM_E_NOT_CONVERGED)
            st = ss;
        for (size_t i = 0; i < n && st == CBM_OK; i++) {
            ober_shoot *h = &s->shoots.data[i];
            if (first[i] < 0)
                continue;
            int nodes = h->nodes > 0 ? h->nodes : 1;
            cbm_segment_state a, b;
            if ((st = cbm_plant_segment(p, (size_t)first[i], &a)) != CBM_OK ||
                (st = cbm_plant_segment(p, (size_t)first[i] + (size_t)nodes - 1, &b)) != CBM_OK)
                break;
            cbm_vec3 chord = v3_sub(b.distal, a.proximal);
            double len = v3_norm(chord);
            if (!(len > 0) || !v3_isfinite(chord))
                continue; /* no bend from a failed solve */
            chord = v3_scale(chord, 1.0 / len);
            cbm_vec3 wm = h->parent >= 0 ? world[h->parent] : v3(0, 0, 0);
            cbm_vec3 H = apply_rotation(wm, h->H), L = apply_rotation(wm, h->L),
                     U = apply_rotation(wm, h->U);
            cbm_vec3 d = min_rotation(H, chord);
            cbm_vec3 dl = v3(v3_dot(d, H), v3_dot(d, L), v3_dot(d, U));
            world[i] = min_rotation(h->H, chord);
            double r0 = h->radius_mem, r = h->radius;
            double w = r > 0 ? 1.0 - (r0 / r) * (r0 / r) * (r0 / r) * (r0 / r) : 1.0;
            w = w < 0 ? 0 : w;
            h->bend_rest = h->bend_mem;
            h->bend_mem = v3_madd(h->bend_mem, dl, w);
            h->bend_el = v3_scale(dl, 1.0 - w);
            h->radius_mem = r;
        }
        cbm_plant_destroy(p);
    }
    cbm__free(ctx, f, m * sizeof *f);
    cbm__free(ctx, world, m * sizeof *world);
    cbm__free(ctx, first, m * sizeof *first);
    cbm__free(ctx, taken, m);
    cbm__free(ctx, has, s->trees.len ? s->trees.len : 1);
    CBM_TRY(st);
    cbm__ober_geometry(s); /* the bent tree */
    return CBM_OK;
}
