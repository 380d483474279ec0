/* The general fruit tree of Taylor-Hell (2005, appendix A.1; digest §2.3-2.13), grown natively on
 * the statics engine, and the wild and crooked aspen of chapter 7 through one switch.
 *
 * The listing drives the seasons by alternating forward and backward relaxation passes of an
 * L-system (digest §2.3); here every growth step solves the static equilibrium at once with the
 * fast Newton solver, warm-started from the previous step, so the gating on equilibrium is
 * implicit. A growth step:
 *   summer: every apex adds one node (A.1 rule F1): a continuation internode of length LEN0 and
 *     a lateral bud internode of length BUDLENGTH, diverging by the phyllotactic angle (137.5 deg
 *     per node) and deviating by a random angle between two graphical functions of the node's
 *     position h = count / numBuds in the shoot; both get the tropism rest curvature (6.8-6.12)
 *     and the upright roll (U as close to vertical as possible, Fig. 8.4); the bud carries a leaf
 *     and, with a probability rising towards the shoot's base, a fruit (F2), whose masses grow
 *     towards stochastic goals at rate organ_rate (4.4-4.5). An apex below the ground stops.
 *     At the shoot's last node the continuation becomes the terminal bud.
 *   winter: leaves and fruit fall at random (F6): the branches spring back (Fig. 4.1).
 *   both: equilibrium (6.24 fixed point, solved); breakage of every segment whose bending stress
 *     exceeds the modulus of rupture (8.26-8.27); segments bent through the ground are cropped;
 *     pipe-model rings at rate kappa with shape memory and reaction wood (4.1-4.3, 6.25-6.34,
 *     8.17-8.25, cbm_plant_grow_rings). Once a year the wood ages by the year's growth steps /
 *     growth_steps_per_year years (8.2).
 * Summer ends when no apex is left; winter when the leaves and fruit are gone and the rings have
 * caught up (no increment above min_ring) or after max_winter_steps; then branches that laid no
 * ring for years_to_shed years are shed (§4.3.2), and the spring pass (tree_spring.c) decides
 * every bud's fate.
 *
 * The form switch (ch. 7, §7.3): wild = E x stiffness_factor and tropism x tropism_factor;
 * crooked = base E and tropism, beta = 0 (no reaction-wood righting), deviation x
 * deviation_factor, and the tropism of a shoot's new nodes fading linearly from the fraction
 * tropism_fade of its nodes to zero at its last node (the listing's factor (3n - c)/n is >= 2
 * and clamps to 1, digest erratum 7; this is the decreasing schedule the text describes, applied
 * per node without mutating a global). Juvenile E is drawn per shoot, N(E_juv, sd E_juv).
 */
#define _POSIX_C_SOURCE 200809L
#include "tree/tree_internal.h"
#include "core/vecmath.h"

#include <math.h>
#include <time.h>

static double monotonic_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double uniform(cbm_tree *t, double lo, double hi)
{
    return lo + (hi - lo) * cbm__rng_uniform(&t->rng);
}

/* normal draw clamped to at least `floor_frac` of the mean (masses and moduli stay positive) */
static double normal_pos(cbm_tree *t, double mean, double sd, double floor_frac)
{
    double v = mean + sd * cbm__rng_normal(&t->rng);
    return v < floor_frac * mean ? floor_frac * mean : v;
}

static cbm_vec3 distal(const tree_plant *p, size_t i)
{
    return v3_madd(p->pos[i], q_rotate(p->q[i], v3(1, 0, 0)), p->len[i]);
}

static cbm_ring core_ring(const cbm_tree *t, double e, double radius)
{
    cbm_ring r = cbm_ring_default();
    r.youngs_modulus = e;
    r.shear_modulus = t->def.shear_ratio * e;
    r.density = t->def.density;
    r.a = r.b = radius;
    r.modulus_of_rupture = t->def.modulus_of_rupture;
    return r;
}

static cbm_status set_mass(cbm_tree *t, size_t i)
{
    const tree_seg *s = &t->seg.data[i];
    return cbm_plant_set_load(t->plant, i, s->leaf + s->fruit, v3(0, 0, 0), v3(0, 0, 0));
}

/* Leaf and fruit of a new bud (A.1 F2). */
static cbm_status new_organs(cbm_tree *t, size_t i, int count)
{
    tree_seg *s = &t->seg.data[i];
    const cbm_tree_def *d = &t->def;
    if (d->leaves && d->leaf_mass > 0.0) {
        s->leaf_goal = normal_pos(t, d->leaf_mass, 0.5 * d->leaf_mass, 0.05);
        s->leaf = s->leaf_goal / 3.0;
        s->nleaf = 1;
    }
    double x = uniform(t, 0.0, 2.0 * (double)(d->max_buds - count) / (double)d->max_buds);
    if (d->fruit_mass > 0.0 && x < d->fruit_prob && count > 2 &&
        t->year + 1 >= d->first_fruit_year) {
        s->fruit_goal = normal_pos(t, d->fruit_mass, 0.5 * d->fruit_mass, 0.05);
        s->fruit = s->fruit_goal / 3.0;
    }
    return set_mass(t, i);
}

/* The rosette of leaves and maybe a fruit of a dormant bud (a spur) for the coming summer. */
static cbm_status spur_organs(cbm_tree *t, size_t i)
{
    tree_seg *s = &t->seg.data[i];
    const cbm_tree_def *d = &t->def;
    if (d->leaves && d->leaf_mass > 0.0 && d->spur_leaves > 0) {
        s->leaf_goal = 0.0;
        for (int k = 0; k < d->spur_leaves; k++)
            s->leaf_goal += normal_pos(t, d->leaf_mass, 0.5 * d->leaf_mass, 0.05);
        s->leaf = s->leaf_goal / 3.0;
        s->nleaf = d->spur_leaves;
    }
    if (d->fruit_mass > 0.0 && d->spur_fruit_prob > 0.0 && t->year + 1 >= d->first_fruit_year &&
        cbm__rng_uniform(&t->rng) < d->spur_fruit_prob) {
        s->fruit_goal = normal_pos(t, d->fruit_mass, 0.5 * d->fruit_mass, 0.05);
        s->fruit = s->fruit_goal / 3.0;
    }
    return set_mass(t, i);
}

static cbm_status push_seg(cbm_tree *t, const tree_seg *s)
{
    return CBM_ARRAY_PUSH(t->ctx, t->seg, *s);
}

/* Adds one segment to the plant and its model state. */
static cbm_status add_seg(cbm_tree *t, size_t parent, double length, double radius,
                          double divergence, double deviation, double e, double trop,
                          const tree_seg *s, bool continuation, size_t *out)
{
    cbm_segment_def sd = cbm_segment_def_default();
    sd.parent = (int64_t)parent;
    sd.length = length;
    sd.divergence = divergence;
    sd.deviation = deviation;
    sd.core = core_ring(t, e, radius);
    /* the upright roll (Fig. 8.4); with stem_frame a continuation keeps its stem's frame, so the
     * divergence of the next lateral is measured round the stem, not from a U that flips with
     * the slight lean of a nearly vertical shoot */
    if (!(continuation && t->def.stem_frame))
        CBM_TRY(cbm_plant_upright_roll(t->plant, &sd, &sd.roll));
    cbm_tropism tr = cbm_tropism_default();
    tr.strength = trop;
    CBM_TRY(CBM_ARRAY_RESERVE(t->ctx, t->seg, t->seg.len + 1));
    CBM_TRY(cbm_plant_grow_segment(t->plant, &sd, &tr, out));
    CBM_ASSERT(*out == t->seg.len);
    return push_seg(t, s);
}

/* One node on the apex at the tip of segment i (A.1 F1). */
static cbm_status grow_apex(cbm_tree *t, size_t i)
{
    const cbm_tree_def *d = &t->def;
    tree_seg ps = t->seg.data[i];
    ps.flags &= (uint8_t)~SEG_APEX;
    t->seg.data[i].flags = ps.flags;
    const tree_plant pv = tree_plant_of(t->plant);
    if (distal(&pv, i).y < d->bud_length)
        return CBM_OK; /* the shoot reached the ground */
    int count = ps.count + 1, nodes = ps.nodes;
    double h = (double)count / (double)nodes;
    double trop = t->trop;
    if (t->fade && nodes > 0) {
        double f = (1.0 - h) / (1.0 - d->tropism_fade > 1e-12 ? 1.0 - d->tropism_fade : 1e-12);
        trop *= f < 0.0 ? 0.0 : (f > 1.0 ? 1.0 : f);
    }
    /* continuation: the apex moves on, or becomes the terminal bud at the last node */
    tree_seg c;
    memset(&c, 0, sizeof c);
    c.flags = (uint8_t)((count < nodes ? SEG_APEX : SEG_BUD) | (ps.flags & SEG_TRUNK1));
    c.count = count;
    c.nodes = nodes;
    c.h = h;
    c.low_since = -1;
    c.bud_year = t->year;
    c.phyllo = fmod(ps.phyllo + d->phyllotaxis, 2.0 * CBM_PI);
    c.juv_e = ps.juv_e;
    c.leader = ps.leader;
    size_t ci, li;
    CBM_TRY(add_seg(t, i, d->internode_length, d->radius, 0.0, 0.0, c.juv_e, trop, &c, true, &ci));
    /* lateral bud: divergence = the parent's phyllotactic angle, deviation from h */
    double lo = cbm_tree_func_eval(&d->angle_min_height, h) * 100.0 * CBM_PI / 180.0;
    double hi = cbm_tree_func_eval(&d->angle_max_height, h) * 100.0 * CBM_PI / 180.0;
    double dev = uniform(t, lo, hi) * t->dev_factor;
    tree_seg l;
    memset(&l, 0, sizeof l);
    l.flags = SEG_LATERAL | SEG_BUD;
    l.count = count;
    l.nodes = nodes;
    l.h = h;
    l.low_since = -1;
    l.bud_year = t->year;
    l.juv_e = normal_pos(t, t->e_juv, d->youngs_juvenile_sd * t->e_juv, 0.1);
    double br = d->bud_radius > 0.0 ? d->bud_radius : d->radius;
    CBM_TRY(add_seg(t, i, d->bud_length, br, ps.phyllo, dev, l.juv_e, trop, &l, false, &li));
    CBM_TRY(new_organs(t, li, count));
    if (!(c.flags & SEG_APEX))
        CBM_TRY(new_organs(t, ci, count));
    return CBM_OK;
}

/* Removes the subtrees rooted at the marked segments from the plant and the model state. */
static cbm_status remove_marked(cbm_tree *t, uint8_t *gone, size_t *removed)
{
    const tree_plant v = tree_plant_of(t->plant), *p = &v;
    size_t n = p->n, nrm = 0;
    /* roots first (marked, parent not gone), then propagate */
    for (size_t i = 0; i < n; i++) {
        int64_t pa = p->parent[i];
        if (pa >= 0 && gone[pa])
            gone[i] = 2;
    }
    for (size_t i = n; i-- > 0;)
        if (gone[i] == 1) {
            size_t rm = 0;
            CBM_TRY(cbm_plant_remove_subtree(t->plant, i, &rm));
            nrm += rm;
        }
    size_t w = 0;
    for (size_t i = 0; i < n; i++)
        if (!gone[i])
            t->seg.data[w++] = t->seg.data[i];
    CBM_ASSERT(w == cbm_plant_segment_count(t->plant));
    t->seg.len = w;
    if (removed)
        *removed = nrm;
    return CBM_OK;
}

/* Removes the cnt marked segments (if any) with all they carry, frees the marks (n of them) and
 * counts the removed segments in the year's figures: shedding and pruning end alike. */
static cbm_status remove_gone(cbm_tree *t, uint8_t *gone, size_t cnt, size_t n)
{
    cbm_status s = CBM_OK;
    size_t nrm = 0;
    if (cnt)
        s = remove_marked(t, gone, &nrm);
    cbm__free(t->ctx, gone, n);
    t->cur.removed += nrm;
    return s;
}

static cbm_status solve(cbm_tree *t)
{
    cbm_solve_stats st;
    if (cbm_plant_segment_count(t->plant) == 0)
        return CBM_OK; /* the tree broke at its base: nothing left to grow */
    double t0 = monotonic_seconds();
    cbm_status s = cbm_plant_solve(t->plant, &t->solve, &st);
    t->cur.seconds_solve += monotonic_seconds() - t0;
    t->cur.passes += st.passes;
    t->cur.newton_steps += st.newton_steps;
    t->converged = s != CBM_E_NOT_CONVERGED;
    if (s == CBM_E_NOT_CONVERGED) {
        /* the state is the best iterate; the next step goes on from it */
        t->cur.unconverged++;
        cbm_context_clear_errors(t->ctx);
        return CBM_OK;
    }
    return s;
}

/* Breakage (8.26-8.27) and cropping of segments bent through the ground (A.1 F3). */
static cbm_status break_and_crop(cbm_tree *t)
{
    tree_plant v = tree_plant_of(t->plant), *p = &v;
    size_t n0 = p->n;
    if (n0 == 0)
        return CBM_OK;
    uint8_t *gone = cbm__calloc(t->ctx, n0, 1);
    size_t *broken = cbm__alloc(t->ctx, n0 * sizeof *broken);
    int64_t *par = cbm__alloc(t->ctx, n0 * sizeof *par);
    cbm_status s = gone && broken && par ? CBM_OK : CBM_E_NOMEM;
    size_t nb = 0, nrm = 0, ncrop = 0;
    /* breakage is decided on converged equilibria only: an iterate left above the tolerance
     * (the pass budget spent, e.g. near a fold) may carry stresses of no equilibrium at all,
     * and one wrong break removes a whole limb; the next step's equilibrium decides */
    if (s == CBM_OK && t->def.modulus_of_rupture > 0.0 && t->converged) {
        memcpy(par, p->parent, n0 * sizeof *par);
        s = cbm_plant_break(t->plant, broken, n0, &nb, &nrm);
        if (s == CBM_OK && nb) {
            for (size_t k = 0; k < nb; k++)
                gone[broken[k]] = 1;
            size_t w = 0;
            for (size_t i = 0; i < n0; i++) {
                if (par[i] >= 0 && gone[par[i]])
                    gone[i] = 2;
                if (!gone[i])
                    t->seg.data[w++] = t->seg.data[i];
            }
            CBM_ASSERT(w == cbm_plant_segment_count(t->plant));
            t->seg.len = w;
            t->cur.breaks += nb;
            t->cur.removed += nrm;
        }
    }
    if (s == CBM_OK) {
        v = tree_plant_of(t->plant); /* after the breaks */
        size_t n = p->n;
        memset(gone, 0, n0);
        if (nb && n > 0)
            s = cbm_plant_evaluate(t->plant, NULL);
        for (size_t i = 0; s == CBM_OK && i < n; i++)
            if (p->parent[i] >= 0 && distal(p, i).y < -t->def.bud_length) {
                gone[i] = 1;
                ncrop++;
            }
        if (s == CBM_OK && ncrop) {
            s = remove_marked(t, gone, &nrm);
            t->cur.removed += nrm;
        }
    }
    if (gone)
        cbm__free(t->ctx, gone, n0);
    if (broken)
        cbm__free(t->ctx, broken, n0 * sizeof *broken);
    if (par)
        cbm__free(t->ctx, par, n0 * sizeof *par);
    if (s == CBM_OK && (nb || ncrop))
        s = solve(t);
    return s;
}

/* Rings by the pipe model with reaction wood, and ageing; marks what grew. */
static cbm_status rings(cbm_tree *t, double *max_increment)
{
    const tree_plant v = tree_plant_of(t->plant), *p = &v;
    size_t n = p->n;
    double t0 = monotonic_seconds();
    double *a0 = cbm__alloc(t->ctx, (n ? n : 1) * sizeof *a0);
    if (!a0)
        return CBM_E_NOMEM;
    for (size_t i = 0; i < n; i++)
        a0[i] = p->outer[i].a; /* the outer ring, kept per segment */
    cbm_growth_stats gs;
    cbm_status s = cbm_plant_grow_rings(t->plant, &t->growth, &gs);
    for (size_t i = 0; s == CBM_OK && i < n; i++) {
        if (p->outer[i].a > a0[i]) { /* a new ring: the segment's last */
            size_t nr;
            const cbm_ring *o = cbm__plant_rings(t->plant, i, &nr) + nr - 1;
            t->seg.data[i].flags |= SEG_GREW;
            if (o->reaction > 0.0)
                t->seg.data[i].flags |= SEG_REACT;
        }
    }
    cbm__free(t->ctx, a0, (n ? n : 1) * sizeof *a0);
    *max_increment = gs.max_increment;
    t->cur.seconds_rings += monotonic_seconds() - t0;
    return s;
}

/* Shape statistics of the current state. */
static void measure(const cbm_tree *t, double *height, double *width, double *tip_height)
{
    const tree_plant v = tree_plant_of(t->plant), *p = &v;
    double top = 0.0, xlo = INFINITY, xhi = -INFINITY, zlo = INFINITY, zhi = -INFINITY;
    double tips = 0.0;
    size_t nt = 0;
    for (size_t i = 0; i < p->n; i++) {
        cbm_vec3 e = distal(p, i);
        top = e.y > top ? e.y : top;
        xlo = e.x < xlo ? e.x : xlo, xhi = e.x > xhi ? e.x : xhi;
        zlo = e.z < zlo ? e.z : zlo, zhi = e.z > zhi ? e.z : zhi;
        if (p->nchild[i] == 0) {
            tips += e.y;
            nt++;
        }
    }
    *height = top;
    double wx = xhi - xlo, wz = zhi - zlo;
    *width = p->n ? (wx > wz ? wx : wz) : 0.0;
    *tip_height = nt ? tips / (double)nt : NAN;
}

/* Spring-back (Fig. 4.1) over the same tips: the branch tips marked at the end of summer that
 * are still there (breakage or cropping in winter removes some) give the mean loaded height
 * (then) and the mean unloaded height (now). */
static void spring_back(cbm_tree *t)
{
    const tree_plant v = tree_plant_of(t->plant), *p = &v;
    double lo = 0.0, un = 0.0;
    size_t nt = 0;
    for (size_t i = 0; i < p->n; i++)
        if ((t->seg.data[i].flags & SEG_TIP) && p->nchild[i] == 0) {
            lo += t->seg.data[i].tip_y;
            un += distal(p, i).y;
            nt++;
        }
    t->cur.tip_height_loaded = nt ? lo / (double)nt : NAN;
    t->cur.tip_height_unloaded = nt ? un / (double)nt : NAN;
}

static double trunk_lean(const cbm_tree *t)
{
    const tree_plant v = tree_plant_of(t->plant), *p = &v;
    size_t last = SIZE_MAX;
    for (size_t i = 0; i < p->n; i++)
        if (t->seg.data[i].flags & SEG_TRUNK1)
            last = i;
    if (last == SIZE_MAX || p->n == 0)
        return NAN;
    cbm_vec3 c = v3_sub(distal(p, last), p->pos[0]);
    double cn = v3_norm(c);
    if (cn == 0.0)
        return NAN;
    double cy = c.y / cn;
    cy = cy > 1.0 ? 1.0 : (cy < -1.0 ? -1.0 : cy);
    return acos(cy) * 180.0 / CBM_PI;
}

static void begin_year(cbm_tree *t)
{
    memset(&t->cur, 0, sizeof t->cur);
    t->cur.year = t->year + 1;
    t->cur.tip_height_unloaded = NAN;
    t->cur.lean = NAN;
    t->season = CBM_TREE_SUMMER;
    t->winter_steps = 0;
    t->unloaded_recorded = false;
    for (size_t i = 0; i < t->seg.len; i++)
        t->seg.data[i].flags &= (uint8_t) ~(SEG_REACT | SEG_GREW | SEG_TIP);
}

cbm_status cbm_tree_create(cbm_context *ctx, const cbm_tree_def *def, cbm_tree **out)
{
    if (!ctx || !def || !out)
        return CBM_E_INVALID;
    *out = NULL;
    CBM_TRY(cbm_tree_def_check(ctx, def));
    cbm_tree *t = cbm__calloc(ctx, 1, sizeof *t);
    if (!t)
        return CBM_E_NOMEM;
    t->ctx = ctx;
    t->def = *def;
    cbm__rng_seed(&t->rng, def->seed);
    bool wild = def->form == CBM_TREE_WILD, crooked = def->form == CBM_TREE_CROOKED;
    t->e_juv = def->youngs_juvenile * (wild ? def->stiffness_factor : 1.0);
    t->e_adult = def->youngs_adult * (wild ? def->stiffness_factor : 1.0);
    t->trop = def->tropism * (wild ? def->tropism_factor : 1.0);
    t->dev_factor = crooked ? def->deviation_factor : 1.0;
    t->fade = crooked;
    cbm_growth_def g = cbm_growth_def_default();
    g.pipe_exponent = def->pipe_exponent;
    g.pipe_rate = def->ring_rate > 0.0 ? def->ring_rate : 1e-12;
    g.min_ring = def->min_ring;
    g.youngs_juvenile = t->e_juv;
    g.youngs_adult = t->e_adult;
    g.adult_age = def->adult_age;
    g.shear_ratio = def->shear_ratio;
    g.density = def->density;
    g.modulus_of_rupture = def->modulus_of_rupture;
    g.memory = def->memory;
    g.ageing = def->ageing;
    /* the listing applies reaction wood only if beta > 0: the crooked form has none */
    g.reaction_threshold =
        def->reaction_threshold > 0.0 && !crooked ? def->reaction_threshold : INFINITY;
    g.reaction_beta = crooked ? 0.0 : def->reaction_beta;
    g.reaction_increment = def->reaction_increment;
    g.reaction_max_aspect = def->reaction_max_aspect;
    g.reaction_full_lean = def->reaction_full_lean;
    t->growth = g;
    t->solve = cbm_solve_def_default();
    t->solve.tolerance = def->solve_tolerance;
    t->solve.warm_start = true;
    t->solve.confirm_modes = false; /* the growth reads no mode count: the same tree, faster */
    t->solve.max_passes = (size_t)def->solve_max_passes;
    t->solve.solver = def->solver;
    t->solve.threads = def->solve_threads;
    /* approx in growth: the rings memorise its shapes, and the thesis's tip load buckles
     * stems (docs/methods.md, "In growth"); calibrated unless the parameters say thesis */
    t->solve.approx_load = def->approx_load;
    cbm_plant_def pd = cbm_plant_def_default();
    pd.gravity = v3(0, -9.81, 0);
    pd.base_orientation = cbm_mech_clamp_orientation(def->elevation);
    pd.discretization = def->discretization;
    cbm_status s = cbm_plant_create(ctx, &pd, &t->plant);
    if (s == CBM_OK) {
        tree_seg r;
        memset(&r, 0, sizeof r);
        r.flags = SEG_APEX | SEG_TRUNK1;
        r.leader = 1;
        r.nodes = def->first_buds;
        r.low_since = -1;
        r.juv_e = t->e_juv;
        r.bud_year = 0;
        cbm_segment_def sd = cbm_segment_def_default();
        sd.parent = -1;
        sd.length = def->internode_length;
        sd.core = core_ring(t, t->e_juv, def->radius);
        cbm_tropism tr = cbm_tropism_default();
        tr.strength = t->trop;
        s = cbm_plant_grow_segment(t->plant, &sd, &tr, NULL);
        if (s == CBM_OK)
            s = push_seg(t, &r);
    }
    if (s == CBM_OK) {
        begin_year(t);
        s = solve(t);
    }
    if (s != CBM_OK) {
        cbm_tree_destroy(t);
        return s;
    }
    *out = t;
    return CBM_OK;
}

void cbm_tree_destroy(cbm_tree *t)
{
    if (!t)
        return;
    cbm_plant_destroy(t->plant);
    CBM_ARRAY_FREE(t->ctx, t->seg);
    CBM_ARRAY_FREE(t->ctx, t->years);
    cbm__free(t->ctx, t, sizeof *t);
}

/* Diameter of the base segment's outer ring, m (0 without segments). */
static double base_diameter(const cbm_tree *t)
{
    const tree_plant p = tree_plant_of(t->plant);
    return p.n ? 2.0 * sqrt(p.outer[0].a * p.outer[0].b) : 0.0;
}

static cbm_status summer_step(cbm_tree *t)
{
    size_t n = t->seg.len;
    for (size_t i = 0; i < n; i++)
        if (t->seg.data[i].flags & SEG_APEX)
            CBM_TRY(grow_apex(t, i));
    /* leaves and fruit grow towards their goals (4.4-4.5) */
    double k = t->def.organ_rate;
    for (size_t i = 0; i < t->seg.len; i++) {
        tree_seg *s = &t->seg.data[i];
        if (s->leaf_goal > s->leaf || s->fruit_goal > s->fruit) {
            s->leaf += k * (s->leaf_goal - s->leaf);
            s->fruit += k * (s->fruit_goal - s->fruit);
            CBM_TRY(set_mass(t, i));
        }
    }
    CBM_TRY(solve(t));
    CBM_TRY(break_and_crop(t));
    double inc;
    CBM_TRY(rings(t, &inc));
    bool apex = false;
    for (size_t i = 0; i < t->seg.len && !apex; i++)
        apex = (t->seg.data[i].flags & SEG_APEX) != 0;
    if (!apex) {
        /* end of summer: the loaded tree */
        double h, w, th;
        measure(t, &h, &w, &th);
        t->cur.height = h;
        t->cur.crown_width = w;
        t->cur.tip_height_loaded = th;
        const tree_plant pv = tree_plant_of(t->plant);
        for (size_t i = 0; i < t->seg.len; i++)
            if (pv.nchild[i] == 0) {
                t->seg.data[i].flags |= SEG_TIP;
                t->seg.data[i].tip_y = distal(&pv, i).y;
            }
        size_t nl = 0, nf = 0;
        for (size_t i = 0; i < t->seg.len; i++) {
            nl += t->seg.data[i].leaf > 0.0 ? (size_t)t->seg.data[i].nleaf : 0;
            nf += t->seg.data[i].fruit > 0.0;
        }
        t->cur.leaves = nl;
        t->cur.fruit = nf;
        t->cur.segments = t->seg.len; /* the year's final count replaces it */
        t->cur.lean = trunk_lean(t);
        t->cur.base_diameter = base_diameter(t);
        t->season = CBM_TREE_WINTER;
    }
    return CBM_OK;
}

/* Shedding of branches that laid no ring for years_to_shed years (§4.3.2); buds, apices and
 * the base are productive by definition, and so is every segment that carries something
 * productive: a branch is shed only when nothing on it has grown (a segment that laid no ring
 * because its children's pipes already fit it is not dead while they live; shedding it took the
 * whole tree with it). */
static cbm_status shed_unproductive(cbm_tree *t)
{
    int yts = t->def.years_to_shed;
    size_t n = t->seg.len;
    if (yts <= 0 || n < 2)
        return CBM_OK;
    uint8_t *gone = cbm__calloc(t->ctx, n, 1);
    if (!gone)
        return CBM_E_NOMEM;
    const tree_plant pv = tree_plant_of(t->plant);
    size_t cnt = 0;
    /* gone[] first holds the productive flag, propagated from the tips to the base */
    for (size_t i = 0; i < n; i++) {
        const tree_seg *s = &t->seg.data[i];
        gone[i] = (s->flags & (SEG_GREW | SEG_BUD | SEG_APEX)) ||
                  (pv.nchild[i] == 0 && !(s->flags & SEG_ABORTED));
    }
    for (size_t i = n; i-- > 1;)
        if (gone[i] && pv.parent[i] >= 0)
            gone[pv.parent[i]] = 1;
    gone[0] = 0; /* the base is never shed */
    for (size_t i = 1; i < n; i++) {
        tree_seg *s = &t->seg.data[i];
        bool productive = gone[i] != 0;
        gone[i] = 0;
        if (productive) {
            s->low_since = -1;
            continue;
        }
        if (s->low_since < 0)
            s->low_since = t->year;
        else if (t->year - s->low_since + 1 >= yts) {
            gone[i] = 1;
            cnt++;
        }
    }
    /* count only the most proximal shed branches */
    size_t branches = 0;
    for (size_t i = 0; i < n; i++)
        if (gone[i] && !(pv.parent[i] >= 0 && gone[pv.parent[i]]))
            branches++;
    t->cur.shed += branches;
    return remove_gone(t, gone, cnt, n);
}

/* Winter pruning of a trained tree: every branch that leaves the leader below clear_trunk is
 * removed with all it carries, as orchardists remove the feathers below the lowest scaffold
 * (docs/models.md); the wood it laid on the trunk stays. */
static cbm_status prune_trunk(cbm_tree *t)
{
    size_t n = t->seg.len;
    if (t->def.clear_trunk <= 0.0 || n < 2)
        return CBM_OK;
    uint8_t *gone = cbm__calloc(t->ctx, n, 1);
    if (!gone)
        return CBM_E_NOMEM;
    const tree_plant pv = tree_plant_of(t->plant);
    size_t cnt = 0;
    for (size_t i = 1; i < n; i++) {
        int64_t pa = pv.parent[i];
        if (pa >= 0 && t->seg.data[pa].leader && !t->seg.data[i].leader &&
            pv.pos[i].y < t->def.clear_trunk) {
            gone[i] = 1;
            cnt++;
        }
    }
    return remove_gone(t, gone, cnt, n);
}

static cbm_status end_year(cbm_tree *t)
{
    /* ageing (8.2) once a year by the year's growth steps: the rings of the year age together */
    double t0 = monotonic_seconds();
    CBM_TRY(cbm_plant_age_wood(t->plant, &t->growth,
                               (double)t->cur.growth_steps / t->def.growth_steps_per_year));
    t->cur.seconds_rings += monotonic_seconds() - t0;
    CBM_TRY(shed_unproductive(t));
    CBM_TRY(prune_trunk(t));
    if (!t->unloaded_recorded)
        spring_back(t);
    t->cur.segments = t->seg.len;
    t->cur.lean = trunk_lean(t);
    t->cur.base_diameter = base_diameter(t);
    for (size_t i = 0; i < t->seg.len; i++)
        t->cur.reaction_segments += (t->seg.data[i].flags & SEG_REACT) != 0;
    CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->years, t->cur));
    t->year++;
    begin_year(t);
    t0 = monotonic_seconds();
    CBM_TRY(cbm__tree_spring(t));
    if (t->def.spur_leaves > 0 || t->def.spur_fruit_prob > 0.0)
        for (size_t i = 0; i < t->seg.len; i++)
            if ((t->seg.data[i].flags & (SEG_BUD | SEG_APEX)) == SEG_BUD)
                CBM_TRY(spur_organs(t, i));
    CBM_TRY(solve(t));
    t->cur.seconds += monotonic_seconds() - t0;
    return CBM_OK;
}

static cbm_status winter_step(cbm_tree *t, bool *done)
{
    bool any = false;
    for (size_t i = 0; i < t->seg.len; i++) {
        tree_seg *s = &t->seg.data[i];
        bool ch = false;
        if (s->leaf > 0.0 && cbm__rng_uniform(&t->rng) < t->def.leaf_drop)
            s->leaf = s->leaf_goal = 0.0, s->nleaf = 0, ch = true;
        if (s->fruit > 0.0 && cbm__rng_uniform(&t->rng) < t->def.fruit_drop)
            s->fruit = s->fruit_goal = 0.0, ch = true;
        if (ch)
            CBM_TRY(set_mass(t, i));
        any = any || s->leaf > 0.0 || s->fruit > 0.0;
    }
    CBM_TRY(solve(t));
    if (!any && !t->unloaded_recorded) {
        spring_back(t);
        t->unloaded_recorded = true;
    }
    CBM_TRY(break_and_crop(t));
    double inc;
    CBM_TRY(rings(t, &inc));
    t->winter_steps++;
    *done = (!any && inc <= t->def.min_ring) || t->winter_steps >= t->def.max_winter_steps;
    return CBM_OK;
}

cbm_status cbm_tree_step(cbm_tree *t, bool *year_done)
{
    if (year_done)
        *year_done = false;
    if (!t)
        return CBM_E_INVALID;
    double t0 = monotonic_seconds();
    bool done = false;
    cbm_status s;
    if (t->season == CBM_TREE_SUMMER)
        s = summer_step(t);
    else
        s = winter_step(t, &done);
    t->cur.growth_steps++;
    t->cur.seconds += monotonic_seconds() - t0;
    if (s == CBM_OK && done) {
        s = end_year(t);
        if (year_done)
            *year_done = true;
    }
    return s;
}

cbm_status cbm_tree_year(cbm_tree *t)
{
    if (!t)
        return CBM_E_INVALID;
    const cbm_limits *lim = cbm_context_limits(t->ctx);
    for (size_t k = 0;; k++) {
        if (lim->max_steps && k >= lim->max_steps)
            return cbm__fail(t->ctx, CBM_E_LIMIT, "tree: a year took more than %zu steps",
                             lim->max_steps);
        bool done;
        CBM_TRY(cbm_tree_step(t, &done));
        if (done)
            return CBM_OK;
    }
}

cbm_status cbm_tree_run(cbm_tree *t)
{
    if (!t)
        return CBM_E_INVALID;
    while (t->year < t->def.years)
        CBM_TRY(cbm_tree_year(t));
    return CBM_OK;
}

int cbm_tree_years(const cbm_tree *t)
{
    return t ? t->year : 0;
}

cbm_tree_season cbm_tree_current_season(const cbm_tree *t)
{
    return t ? t->season : CBM_TREE_SUMMER;
}

const cbm_tree_summary *cbm_tree_summary_of(const cbm_tree *t, int year)
{
    if (!t || year < 1 || (size_t)year > t->years.len)
        return NULL;
    return &t->years.data[year - 1];
}

const cbm_tree_summary *cbm_tree_summary_current(const cbm_tree *t)
{
    return t ? &t->cur : NULL;
}

const cbm_plant *cbm_tree_plant(const cbm_tree *t)
{
    return t ? t->plant : NULL;
}

cbm_status cbm_tree_segment_info(const cbm_tree *t, size_t seg, cbm_tree_segment *out)
{
    if (!t || !out)
        return CBM_E_INVALID;
    if (seg >= t->seg.len)
        return cbm__fail(t->ctx, CBM_E_INVALID, "tree: no segment %zu", seg);
    const tree_seg *s = &t->seg.data[seg];
    memset(out, 0, sizeof *out);
    out->lateral_bud = (s->flags & SEG_LATERAL) != 0;
    out->bud = (s->flags & SEG_BUD) != 0;
    out->aborted = (s->flags & SEG_ABORTED) != 0;
    out->apex = (s->flags & SEG_APEX) != 0;
    out->count = s->count;
    out->h = s->h;
    out->vigour = s->vigour;
    out->sink = s->sink;
    out->lateral_share = s->share;
    out->leaf_mass = s->leaf;
    out->fruit_mass = s->fruit;
    out->leaves = s->leaf > 0.0 ? s->nleaf : 0;
    out->dormant = (s->flags & (SEG_BUD | SEG_APEX)) == SEG_BUD && s->bud_year < t->year;
    return CBM_OK;
}
