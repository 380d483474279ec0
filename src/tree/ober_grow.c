/* The growth step of Oberlaender's parametric tree (thesis §5.4; digest §2.7), one year for
 * every tree of a stand:
 *
 *   0. the light pass over every leaf of the stand (ober_light.c): each leaf's carbon;
 *   1. seeds: a timer above 0 counts down; at 0 the tree germinates: its age becomes 1 and its
 *      seedling trunk (specificLengthLambda[0] at age 1, or initialLength) is the first year's
 *      shoot, so that after n years the trunk is the sum of n yearly increments (E3);
 *   2. tree level: ages + 1, the aggregates (wood and trunk volume, leaves, active shoots, mean
 *      leaf carbon, height), then baseLengthLambda and carbonTaxLambda;
 *   3. shoot level, over the shoots that existed at the start of the year: the shoots made last
 *      year test sproutingPossibilityLambda; a sprouting shoot's growing buds (apical and
 *      lateral) make new shoots (bud level: apicalSplitLambda -> a fork, shortShootLambda -> a
 *      short shoot, else specificLengthLambda and numNodeLambda by order; a length <= 0 makes no
 *      shoot); the buds of a shoot that does not sprout die, its sleeping buds stay;
 *   4. pipe model (eqs. 5-6): a new shoot has R = R_p sqrt(its leaves); an older one
 *      R = sqrt(n R_p^2 + R^2) with n the leaves it supports (this year's new leaves of its
 *      subtree, or all living ones with pipeAllLeaves = 1), counted basipetally;
 *   5. bending: each older shoot's joint strength += bendingLambda; proventitious shoots: every
 *      sleeping bud of an older shoot tests proventitiosShootLambda;
 *   6. leaves older than leafDieAge die; shoots without leaves and without children are pruned
 *      (repeatedly: a pruned shoot may leave its mother bare).
 *
 * New shoots of the year take no part in the year's pipe update, bending or proventitious test
 * (the parallel rewriting of XL sees the old graph). Geometry is re-derived from the graph
 * every year (turtle semantics): a shoot starts at its mother's node (a lateral) or tip (the
 * continuation, a fork), turned by its head angle about the mother's axis and tilted by its
 * insertion angle, then the gravitropism joint rotates it (and everything distal) about H x G by
 * e |H x G| rad (the RV law of ABOP; e < 0 upward), never past the vertical. */
#include "tree/ober_internal.h"
#include "core/vecmath.h"

#include <math.h>

#define DEG (CBM_PI / 180.0)

static cbm_vec3 rotate_about(cbm_vec3 v, cbm_vec3 axis, double a)
{
    /* Rodrigues: axis is a unit vector */
    double c = cos(a), s = sin(a);
    return v3_add(v3_add(v3_scale(v, c), v3_scale(v3_cross(axis, v), s)),
                  v3_scale(axis, v3_dot(axis, v) * (1 - c)));
}

static void fill_tree(cbm_ober_stand *s, const ober_tree *t, size_t ti)
{
    double *v = s->prog.vars;
    v[V_AGE] = v[V_TREE_AGE] = t->age;
    v[V_CARBON_TAX] = t->carbon_tax;
    v[V_BASE_LENGTH] = t->base_length;
    v[V_CARBON_MEAN] = t->carbon_mean;
    v[V_ACTIVE_SHOOTS] = t->active_shoots;
    v[V_SUM_LEAVES] = t->sum_leaves;
    v[V_WOOD_VOLUME] = t->wood_volume;
    v[V_TRUNK_VOLUME] = t->trunk_volume;
    v[V_HEIGHT] = t->height;
    v[V_TREE_INDEX] = (double)ti;
}

static void fill_shoot(cbm_ober_stand *s, const ober_shoot *h)
{
    double *v = s->prog.vars;
    v[V_AGE] = h->age;
    v[V_LEN] = v[V_LENGTH] = h->len;
    v[V_DIAMETER] = 2 * h->radius;
    v[V_RADIUS] = h->radius;
    v[V_NODE_NUMBER] = h->nodes;
    v[V_ORDER] = h->order;
    v[V_TREND] = h->trend;
    v[V_VOLUME] = CBM_PI * h->radius * h->radius * h->len;
    v[V_CARBON] = h->carbon;
    v[V_LEAVES] = h->leaves;
}

static void fill_bud(cbm_ober_stand *s, const ober_bud *b, const ober_shoot *mother)
{
    fill_shoot(s, mother);
    double *v = s->prog.vars;
    v[V_ORDER] = b->order;
    v[V_TREND] = b->trend;
    v[V_POSITION] = b->position;
    v[V_SLEEP] = b->sleep;
    v[V_SHORT_SHOOT] = 0;
    v[V_APICAL] = b->apical;
    v[V_PARENT_ORDER] = mother->order;
    v[V_PARENT_TREND] = mother->trend;
}

static double draw_uniform(cbm_ober_stand *s)
{
    return cbm__rng_uniform(&s->rng);
}

static int sample_buds(cbm_ober_stand *s)
{
    const cbm_ober_def *d = &s->def;
    double u = draw_uniform(s), acc = 0;
    for (int k = 0; k < d->n_new_shoots; k++) {
        acc += d->number_new_shoots_0[k];
        if (u < acc)
            return k;
    }
    return d->n_new_shoots - 1;
}

typedef struct new_shoot {
    int32_t mother, tree;
    int order, trend, nodes;
    int32_t node;
    double head, insert, position, len, tropism;
    bool lateral, short_shoot, proventitious;
} new_shoot;

/* Appends a shoot with its buds and leaves (eq. 6 radius). */
static cbm_status add_shoot(cbm_ober_stand *s, const new_shoot *n)
{
    const cbm_ober_def *d = &s->def;
    ober_shoot h;
    memset(&h, 0, sizeof h);
    h.parent = n->mother;
    h.tree = n->tree;
    h.order = n->order;
    h.trend = n->trend;
    h.nodes = n->nodes;
    h.node = n->node;
    h.head = n->head;
    h.insert = n->insert;
    h.position = n->position;
    h.len = n->len;
    h.tropism = n->tropism;
    h.lateral = n->lateral;
    h.short_shoot = n->short_shoot;
    h.proventitious = n->proventitious;
    h.fresh = h.alive = 1;
    h.carbon = 0;
    if (n->mother >= 0) {
        const ober_shoot *m = &s->shoots.data[n->mother];
        /* the phyllotactic spiral goes on along an axis from one annual shoot to the next */
        if (!n->lateral && n->insert == 0)
            h.phase = m->phase + m->nodes * (m->order == 0 ? d->offset_0 : d->offset_x);
    }
    h.first_bud = (int32_t)s->buds.len;
    double offset = n->order == 0 ? d->offset_0 : d->offset_x;
    for (int i = 1; i <= n->nodes; i++) {
        bool fertile =
            draw_uniform(s) < (n->order == 0 ? d->possibility_node_0 : d->possibility_node_x);
        int k = n->order == 0 ? sample_buds(s) : d->n_shoot_poss;
        double ph = h.phase + i * offset;
        for (int j = 0; j < k; j++) {
            ober_bud b;
            memset(&b, 0, sizeof b);
            b.shoot = (int32_t)s->shoots.len;
            b.node = i;
            b.order = (int16_t)(n->order + 1);
            b.trend = 0;
            b.position = (double)i / n->nodes;
            b.head = n->order == 0 ? ph + j * 360.0 / k : ph + d->shoot_poss[j];
            bool grows =
                draw_uniform(s) < (n->order == 0 ? d->possibility_bud_0 : d->possibility_bud_y);
            if (n->short_shoot || n->order + 1 > d->max_order)
                b.none = 1;
            else {
                b.sleep = !(fertile && grows);
                h.active_buds += !b.sleep;
            }
            CBM_TRY(CBM_ARRAY_PUSH(s->ctx, s->buds, b));
            h.leaves_made++;
        }
    }
    h.nbuds = h.leaves_made;
    if (!n->short_shoot) {
        ober_bud a;
        memset(&a, 0, sizeof a);
        a.shoot = (int32_t)s->shoots.len;
        a.node = n->nodes;
        a.order = (int16_t)n->order;
        a.trend = (int16_t)(n->trend + 1);
        a.position = 1.0;
        a.apical = 1;
        CBM_TRY(CBM_ARRAY_PUSH(s->ctx, s->buds, a));
        h.nbuds++;
    }
    h.leaves = h.leaves_made;
    h.radius = d->pipe_size * sqrt(h.leaves_made > 0 ? (double)h.leaves_made : 1.0);
    if (n->mother >= 0)
        s->shoots.data[n->mother].children++;
    CBM_TRY(CBM_ARRAY_PUSH(s->ctx, s->shoots, h));
    ober_tree *t = &s->trees.data[n->tree];
    t->cur.new_shoots++;
    t->cur.proventitious += n->proventitious;
    return CBM_OK;
}

/* The bud level: the shoot(s) bud bi makes, if any. */
static cbm_status grow_bud(cbm_ober_stand *s, size_t ti, int32_t bi, bool proventitious)
{
    const cbm_ober_def *d = &s->def;
    cbm_status st = CBM_OK;
    ober_bud b = s->buds.data[bi];
    s->buds.data[bi].used = 1;
    if (b.order > d->max_order || b.none)
        return CBM_OK;
    ober_shoot m = s->shoots.data[b.shoot];
    fill_tree(s, &s->trees.data[ti], ti);
    fill_bud(s, &b, &m);
    int ko = b.order < d->n_specific_length ? b.order : d->n_specific_length - 1;
    int kn = b.order < d->n_num_nodes ? b.order : d->n_num_nodes - 1;
    bool fork = b.apical && cbm__ober_eval(&s->prog, F_APICAL_SPLIT, &st) != 0;
    bool short_shoot = !fork && cbm__ober_eval(&s->prog, F_SHORT_SHOOT, &st) != 0;
    s->prog.vars[V_SHORT_SHOOT] = short_shoot;
    double len = cbm__ober_eval(&s->prog, F_SPECIFIC_LENGTH + ko, &st);
    double nn = cbm__ober_eval(&s->prog, F_NUM_NODES + kn, &st);
    double e = cbm__ober_eval(&s->prog, F_ORIENTATION, &st);
    CBM_TRY(st);
    if (!(len > 0)) /* mortality rule 2: no shoot */
        return CBM_OK;
    int nodes = nn < 1 ? 1 : nn > 1000 ? 1000 : (int)lround(nn);
    new_shoot n = {.mother = b.shoot,
                   .tree = (int32_t)ti,
                   .order = b.order,
                   .trend = b.apical ? b.trend : 0,
                   .nodes = nodes,
                   .node = b.apical ? 0 : b.node,
                   .head = b.head,
                   .insert = 0,
                   .position = b.position,
                   .len = len,
                   .tropism = e,
                   .lateral = !b.apical,
                   .short_shoot = short_shoot,
                   .proventitious = proventitious};
    if (!b.apical) {
        int ka = b.order - 1 < d->n_shoot_angle ? b.order - 1 : d->n_shoot_angle - 1;
        n.insert = d->shoot_angle[ka < 0 ? 0 : ka];
    }
    if (short_shoot) {
        /* a short shoot: one node of leaves, a tenth of the length, no lateral buds */
        n.nodes = 1;
        n.len = len / 10;
        return add_shoot(s, &n);
    }
    if (fork) {
        /* apicalSplit: two shoots of the same order and trend, forkAngle either side */
        s->trees.data[ti].cur.forks++;
        for (int k = 0; k < 2; k++) {
            n.head = k * 180.0;
            n.insert = d->fork_angle;
            CBM_TRY(add_shoot(s, &n));
        }
        return CBM_OK;
    }
    return add_shoot(s, &n);
}

static double leaf_carbon_of(const cbm_ober_stand *s, const ober_shoot *h, double *sum)
{
    double acc = 0;
    int n = 0;
    for (int32_t k = 0; k < h->nbuds; k++) {
        size_t b = (size_t)h->first_bud + (size_t)k;
        if (s->buds.data[b].apical)
            continue;
        acc += b < s->leaf_carbon.len ? s->leaf_carbon.data[b] : 1.0;
        n++;
    }
    *sum = acc;
    return n ? acc / n : 0.0;
}

/* Tree-level aggregates over the tree's living shoots of the start of the year (own[0..n), in
 * increasing index). */
static void aggregates(cbm_ober_stand *s, size_t ti, const int32_t *own, size_t n)
{
    ober_tree *t = &s->trees.data[ti];
    double wood = 0, trunk = 0, leaves = 0, active = 0, csum = 0, top = 0;
    for (size_t q = 0; q < n; q++) {
        ober_shoot *h = &s->shoots.data[own[q]];
        if (!h->alive)
            continue;
        double v = CBM_PI * h->radius * h->radius * h->len;
        wood += v;
        if (h->order == 0)
            trunk += v;
        double sum = 0;
        if (h->leaves > 0) {
            double mean = leaf_carbon_of(s, h, &sum);
            h->carbon = s->def.carbon_sum ? sum : mean;
            leaves += h->leaves;
            active += 1;
            csum += sum;
        } else
            h->carbon = 0;
        top = fmax(top, fmax(h->tip.y, h->base.y) - t->pos.y);
    }
    t->wood_volume = wood;
    t->trunk_volume = trunk;
    t->sum_leaves = leaves;
    t->active_shoots = active;
    t->carbon_mean = leaves > 0 ? csum / leaves : 0;
    t->height = top;
}

/* Turtle interpretation: positions and frames of every shoot (parents come first). */
void cbm__ober_geometry(cbm_ober_stand *s)
{
    const cbm_vec3 up = v3(0, 1, 0), g = v3(0, -1, 0);
    for (size_t i = 0; i < s->shoots.len; i++) {
        ober_shoot *h = &s->shoots.data[i];
        cbm_vec3 H, L, U, base;
        if (h->parent < 0) {
            base = s->trees.data[h->tree].pos;
            H = up, L = v3(1, 0, 0), U = v3(0, 0, -1);
        } else {
            const ober_shoot *m = &s->shoots.data[h->parent];
            H = m->H, L = m->L, U = m->U;
            base = h->node == 0 ? m->tip : v3_madd(m->base, m->H, m->len * h->node / m->nodes);
        }
        if (h->insert != 0) { /* RH(head) then RL(insert) */
            L = rotate_about(L, H, h->head * DEG);
            U = rotate_about(U, H, h->head * DEG);
            H = rotate_about(H, L, h->insert * DEG);
            U = rotate_about(U, L, h->insert * DEG);
        }
        if (h->parent >= 0) { /* the gravitropism joint (RV) */
            cbm_vec3 a = v3_cross(H, g);
            double sn = v3_norm(a);
            if (sn > 1e-12) {
                a = v3_scale(a, 1.0 / sn);
                double ang = h->tropism * sn;
                double to_up = acos(fmax(-1.0, fmin(1.0, v3_dot(H, up))));
                double to_down = CBM_PI - to_up;
                ang = ang < -to_up ? -to_up : ang > to_down ? to_down : ang;
                H = rotate_about(H, a, ang);
                L = rotate_about(L, a, ang);
                U = rotate_about(U, a, ang);
            }
        }
        /* the bend of the statics (mechanicsFeedback), in the shoot's own frame */
        cbm_vec3 w = v3_add(h->bend_mem, h->bend_el);
        double wn = v3_norm(w);
        if (wn > 0) {
            cbm_vec3 a = v3_scale(
                v3_add(v3_add(v3_scale(H, w.x), v3_scale(L, w.y)), v3_scale(U, w.z)), 1.0 / wn);
            H = rotate_about(H, a, wn);
            L = rotate_about(L, a, wn);
            U = rotate_about(U, a, wn);
        }
        h->H = v3_normalize(H), h->L = v3_normalize(L), h->U = v3_normalize(U);
        h->base = base;
        h->tip = v3_madd(base, h->H, h->len);
    }
}

/* Drops the dead shoots and their buds, keeping the order (parents before children). */
static cbm_status compact(cbm_ober_stand *s)
{
    size_t n = s->shoots.len;
    int32_t *map = cbm__calloc(s->ctx, n ? n : 1, sizeof *map);
    if (!map)
        return CBM_E_NOMEM;
    size_t k = 0, kb = 0;
    for (size_t i = 0; i < n; i++) {
        ober_shoot h = s->shoots.data[i];
        if (!h.alive) {
            map[i] = -1;
            continue;
        }
        map[i] = (int32_t)k;
        h.parent = h.parent >= 0 ? map[h.parent] : -1;
        CBM_ASSERT(h.parent >= 0 || s->shoots.data[i].parent < 0);
        int32_t fb = (int32_t)kb;
        for (int32_t j = 0; j < h.nbuds; j++) {
            ober_bud b = s->buds.data[h.first_bud + j];
            b.shoot = (int32_t)k;
            s->buds.data[kb++] = b;
        }
        h.first_bud = fb;
        s->shoots.data[k++] = h;
    }
    s->shoots.len = k;
    s->buds.len = kb;
    cbm__free(s->ctx, map, (n ? n : 1) * sizeof *map);
    return CBM_OK;
}

/* The year's report of every tree, in one pass over the shoots (in index order, so that each
 * tree's sums are taken in the order of its shoots). */
static void reports(cbm_ober_stand *s)
{
    for (size_t ti = 0; ti < s->trees.len; ti++) {
        ober_tree *t = &s->trees.data[ti];
        cbm_ober_report *r = &t->cur;
        r->year = s->year;
        r->age = t->age;
        r->leaves = r->shoots = 0;
        memset(r->shoots_order, 0, sizeof r->shoots_order);
        r->wood_volume = r->trunk_volume = r->height = r->base_diameter = 0;
    }
    for (size_t i = 0; i < s->shoots.len; i++) {
        const ober_shoot *h = &s->shoots.data[i];
        ober_tree *t = &s->trees.data[h->tree];
        cbm_ober_report *r = &t->cur;
        r->leaves += (size_t)h->leaves;
        r->shoots++;
        r->shoots_order[h->order < 3 ? h->order : 3]++;
        double v = CBM_PI * h->radius * h->radius * h->len * 1e-6;
        r->wood_volume += v;
        if (h->order == 0)
            r->trunk_volume += v;
        r->height = fmax(r->height, (fmax(h->tip.y, h->base.y) - t->pos.y) * 0.01);
        if (h->parent < 0 && r->base_diameter == 0)
            r->base_diameter = 2 * h->radius * 0.01;
    }
    for (size_t ti = 0; ti < s->trees.len; ti++) {
        ober_tree *t = &s->trees.data[ti];
        cbm_ober_report *r = &t->cur;
        r->carbon_tax = t->carbon_tax;
        r->carbon_mean = t->carbon_mean;
        r->base_length = t->base_length;
        r->light_rays = s->light_rays;
        r->light_seconds = s->light_seconds;
    }
}

static cbm_status tree_level(cbm_ober_stand *s, size_t ti, const int32_t *own, size_t n)
{
    ober_tree *t = &s->trees.data[ti];
    cbm_status st = CBM_OK;
    aggregates(s, ti, own, n);
    fill_tree(s, t, ti);
    t->base_length = cbm__ober_eval(&s->prog, F_BASE_LENGTH, &st);
    s->prog.vars[V_BASE_LENGTH] = t->base_length;
    t->carbon_tax = cbm__ober_eval(&s->prog, F_CARBON_TAX, &st);
    return st;
}

static cbm_status germinate(cbm_ober_stand *s, size_t ti)
{
    ober_tree *t = &s->trees.data[ti];
    t->age = 1;
    CBM_TRY(tree_level(s, ti, NULL, 0));
    /* the seed acts as a virtual apical bud of order 0 on a shoot of length 0 */
    ober_shoot none;
    memset(&none, 0, sizeof none);
    ober_bud b;
    memset(&b, 0, sizeof b);
    b.position = 1;
    b.apical = 1;
    fill_tree(s, t, ti);
    fill_bud(s, &b, &none);
    /* a multi-stem seed (Listing 14's seeding): seedStems trunks, trunk k turned by k + 1 times
     * seedStemHead about the vertical (the cumulative RH) and tilted by seedStemTilt (RL), each
     * with its own draw of the length formula; one stem is upright (bit for bit the old seedling)
     * unless seedStemTilt says otherwise */
    int stems = s->def.seed_stems > 1 ? s->def.seed_stems : 1;
    for (int k = 0; k < stems; k++) {
        cbm_status st = CBM_OK;
        double len = s->def.initial_length > 0 ? s->def.initial_length
                                               : cbm__ober_eval(&s->prog, F_SPECIFIC_LENGTH, &st);
        double nn = cbm__ober_eval(&s->prog, F_NUM_NODES, &st);
        CBM_TRY(st);
        if (!(len > 0))
            len = 1e-3; /* a seedling of no length still carries its buds */
        new_shoot n = {.mother = -1,
                       .tree = (int32_t)ti,
                       .nodes = nn < 1      ? 1
                                : nn > 1000 ? 1000
                                            : (int)lround(nn),
                       .head = stems > 1 ? (k + 1) * s->def.seed_stem_head : 0,
                       .insert = s->def.seed_stem_tilt,
                       .position = 1,
                       .len = len};
        CBM_TRY(add_shoot(s, &n));
    }
    return CBM_OK;
}

/* The shoots of every tree at the start of the year: own[first[t] .. first[t + 1]) are tree t's
 * indices below n0, increasing (a counting sort), so that each tree's steps visit its own shoots
 * rather than all the stand's. */
typedef struct tree_lists {
    size_t *first; /* trees + 1 */
    int32_t *own;  /* n0 */
    size_t trees, n0;
} tree_lists;

static cbm_status lists_make(cbm_ober_stand *s, size_t n0, tree_lists *l)
{
    l->trees = s->trees.len;
    l->n0 = n0;
    l->first = cbm__calloc(s->ctx, l->trees + 1, sizeof *l->first);
    l->own = cbm__calloc(s->ctx, n0 ? n0 : 1, sizeof *l->own);
    if (!l->first || !l->own)
        return CBM_E_NOMEM;
    for (size_t i = 0; i < n0; i++)
        l->first[s->shoots.data[i].tree + 1]++;
    for (size_t t = 0; t < l->trees; t++)
        l->first[t + 1] += l->first[t];
    for (size_t i = n0; i-- > 0;) { /* from the end of each tree's run, backwards */
        int32_t t = s->shoots.data[i].tree;
        l->own[--l->first[t + 1]] = (int32_t)i;
    }
    /* first[t + 1] now holds tree t's start */
    for (size_t t = 0; t < l->trees; t++)
        l->first[t] = l->first[t + 1];
    l->first[l->trees] = n0;
    return CBM_OK;
}

static void lists_free(cbm_ober_stand *s, tree_lists *l)
{
    cbm__free(s->ctx, l->first, (l->trees + 1) * sizeof *l->first);
    cbm__free(s->ctx, l->own, (l->n0 ? l->n0 : 1) * sizeof *l->own);
}

/* Mortality rule 1: shoot i, bare and without children, dies (and leaves its mother one child
 * fewer). */
static void prune(cbm_ober_stand *s, ober_tree *t, size_t i)
{
    ober_shoot *h = &s->shoots.data[i];
    if (!h->alive || h->leaves > 0 || h->children > 0)
        return;
    h->alive = 0;
    t->cur.removed++;
    if (h->parent >= 0)
        s->shoots.data[h->parent].children--;
}

/* One tree's year (its age already counted): tree level, shoot level, pipe model, bending,
 * proventitious shoots, leaf death and pruning. own[0..n) are its shoots of the start of the year
 * (increasing); the shoots it makes are appended to the stand from index `from` on. */
static cbm_status tree_year(cbm_ober_stand *s, size_t ti, const int32_t *own, size_t n)
{
    const cbm_ober_def *d = &s->def;
    ober_tree *t = &s->trees.data[ti];
    size_t from = s->shoots.len;
    for (size_t q = 0; q < n; q++)
        s->shoots.data[own[q]].age++;
    CBM_TRY(tree_level(s, ti, own, n));
    /* shoot level: last year's shoots sprout */
    for (size_t q = 0; q < n; q++) {
        ober_shoot *h = &s->shoots.data[own[q]];
        if (!h->alive || !h->fresh)
            continue;
        h->fresh = 0;
        cbm_status st = CBM_OK;
        fill_tree(s, t, ti);
        fill_shoot(s, h);
        bool sprout = cbm__ober_eval(&s->prog, F_SPROUTING, &st) != 0;
        CBM_TRY(st);
        int32_t fb = h->first_bud, nb = h->nbuds;
        h->sprouted = sprout;
        for (int32_t k = 0; k < nb; k++) {
            ober_bud *b = &s->buds.data[fb + k];
            if (b->used || b->sleep || b->none)
                continue;
            if (sprout)
                CBM_TRY(grow_bud(s, ti, fb + k, false));
            else
                b->used = 1; /* a bud that misses its year dies */
        }
    }
    /* pipe model: leaves supported, basipetally (the new shoots, all above `from`, first) */
    for (size_t q = 0; q < n; q++) {
        ober_shoot *h = &s->shoots.data[own[q]];
        h->supported = d->pipe_all_leaves ? h->leaves : 0;
    }
    for (size_t i = from; i < s->shoots.len; i++) {
        ober_shoot *h = &s->shoots.data[i];
        h->supported = d->pipe_all_leaves ? h->leaves : h->leaves_made;
    }
    for (size_t i = s->shoots.len; i-- > from;) {
        ober_shoot *h = &s->shoots.data[i];
        if (h->alive && h->parent >= 0)
            s->shoots.data[h->parent].supported += h->supported;
    }
    for (size_t q = n; q-- > 0;) {
        ober_shoot *h = &s->shoots.data[own[q]];
        if (h->alive && h->parent >= 0)
            s->shoots.data[h->parent].supported += h->supported;
    }
    for (size_t q = 0; q < n; q++) {
        int32_t i = own[q];
        ober_shoot *h = &s->shoots.data[i];
        if (!h->alive)
            continue;
        h->radius = sqrt(h->supported * d->pipe_size * d->pipe_size + h->radius * h->radius);
        /* bending: the joint's strength grows by bendingLambda each year */
        cbm_status st = CBM_OK;
        fill_tree(s, t, ti);
        fill_shoot(s, h);
        h->tropism += cbm__ober_eval(&s->prog, F_BENDING, &st);
        CBM_TRY(st);
        /* proventitious shoots from sleeping buds */
        int32_t fb = h->first_bud, nb = h->nbuds;
        for (int32_t k = 0; k < nb; k++) {
            ober_bud *b = &s->buds.data[fb + k];
            if (!b->sleep || b->used || b->none)
                continue;
            fill_tree(s, t, ti);
            fill_bud(s, b, &s->shoots.data[i]);
            bool wake = cbm__ober_eval(&s->prog, F_PROVENTITIOUS, &st) != 0;
            CBM_TRY(st);
            if (wake)
                CBM_TRY(grow_bud(s, ti, fb + k, true));
        }
    }
    /* leaf death, then pruning of bare shoots without children (children first) */
    for (size_t q = 0; q < n; q++) {
        ober_shoot *h = &s->shoots.data[own[q]];
        if (h->age >= d->leaf_die_age)
            h->leaves = 0;
    }
    for (size_t i = from; i < s->shoots.len; i++) {
        ober_shoot *h = &s->shoots.data[i];
        if (h->age >= d->leaf_die_age)
            h->leaves = 0;
    }
    for (size_t i = s->shoots.len; i-- > from;)
        prune(s, t, i);
    for (size_t q = n; q-- > 0;)
        prune(s, t, (size_t)own[q]);
    return CBM_OK;
}

cbm_status cbm_ober_year(cbm_ober_stand *s)
{
    if (!s)
        return CBM_E_INVALID;
    s->year++;
    CBM_TRY(cbm__ober_light(s));
    size_t n0 = s->shoots.len;
    tree_lists l;
    memset(&l, 0, sizeof l);
    cbm_status st = lists_make(s, n0, &l);
    for (size_t ti = 0; ti < s->trees.len && st == CBM_OK; ti++) {
        ober_tree *t = &s->trees.data[ti];
        memset(&t->cur, 0, sizeof t->cur);
        if (t->age == 0) {
            if (t->timer > 0)
                t->timer--;
            else
                st = germinate(s, ti);
            continue;
        }
        t->age++;
        st = tree_year(s, ti, l.own + l.first[ti], l.first[ti + 1] - l.first[ti]);
    }
    lists_free(s, &l);
    CBM_TRY(st);
    CBM_TRY(compact(s));
    cbm__ober_geometry(s);
    if (s->def.mech_feedback)
        CBM_TRY(cbm__ober_feedback(s));
    reports(s);
    for (size_t ti = 0; ti < s->trees.len; ti++) {
        ober_tree *t = &s->trees.data[ti];
        CBM_TRY(CBM_ARRAY_PUSH(s->ctx, t->years, t->cur));
    }
    return CBM_OK;
}

cbm_status cbm_ober_create(cbm_context *ctx, const cbm_ober_def *def, cbm_ober_stand **out)
{
    if (!def || !out)
        return CBM_E_INVALID;
    *out = NULL;
    CBM_TRY(cbm_ober_def_check(ctx, def));
    cbm_ober_stand *s = cbm__calloc(ctx, 1, sizeof *s);
    if (!s)
        return CBM_E_NOMEM;
    s->ctx = ctx;
    s->def = *def;
    cbm__rng_seed(&s->rng, def->seed);
    cbm_status st = cbm__ober_compile(ctx, def, &s->prog);
    if (st != CBM_OK) {
        cbm__free(ctx, s, sizeof *s);
        return st;
    }
    int nx = def->stand_x, ny = def->stand_y;
    for (int iy = 0; iy < ny && st == CBM_OK; iy++)
        for (int ix = 0; ix < nx && st == CBM_OK; ix++) {
            ober_tree t;
            memset(&t, 0, sizeof t);
            double x = (ix - 0.5 * (nx - 1)) * def->spacing,
                   z = (iy - 0.5 * (ny - 1)) * def->spacing;
            if (def->jitter > 0) {
                x += (2 * draw_uniform(s) - 1) * def->jitter;
                z += (2 * draw_uniform(s) - 1) * def->jitter;
            }
            t.pos = v3(100 * x, 0, 100 * z); /* cm */
            t.timer = def->stagger > 0 ? (int)(draw_uniform(s) * (def->stagger + 1)) : 0;
            st = CBM_ARRAY_PUSH(ctx, s->trees, t);
        }
    if (st != CBM_OK) {
        cbm_ober_destroy(s);
        return st;
    }
    *out = s;
    return CBM_OK;
}

void cbm_ober_destroy(cbm_ober_stand *s)
{
    if (!s)
        return;
    cbm_context *ctx = s->ctx;
    for (size_t i = 0; i < s->trees.len; i++)
        CBM_ARRAY_FREE(ctx, s->trees.data[i].years);
    CBM_ARRAY_FREE(ctx, s->trees);
    CBM_ARRAY_FREE(ctx, s->shoots);
    CBM_ARRAY_FREE(ctx, s->buds);
    CBM_ARRAY_FREE(ctx, s->leaf_carbon);
    cbm__ober_prog_free(&s->prog);
    cbm__free(ctx, s, sizeof *s);
}

cbm_status cbm_ober_run(cbm_ober_stand *s)
{
    if (!s)
        return CBM_E_INVALID;
    while (s->year < s->def.years)
        CBM_TRY(cbm_ober_year(s));
    return CBM_OK;
}

int cbm_ober_years(const cbm_ober_stand *s)
{
    return s ? s->year : 0;
}

size_t cbm_ober_tree_count(const cbm_ober_stand *s)
{
    return s ? s->trees.len : 0;
}

const cbm_ober_report *cbm_ober_report_of(const cbm_ober_stand *s, size_t tree, int year)
{
    if (!s || tree >= s->trees.len || year < 1 || (size_t)year > s->trees.data[tree].years.len)
        return NULL;
    return &s->trees.data[tree].years.data[year - 1];
}

cbm_vec3 cbm_ober_tree_position(const cbm_ober_stand *s, size_t tree)
{
    if (!s || tree >= s->trees.len)
        return v3(0, 0, 0);
    return v3_scale(s->trees.data[tree].pos, 0.01);
}

size_t cbm_ober_shoot_count(const cbm_ober_stand *s)
{
    return s ? s->shoots.len : 0;
}

cbm_status cbm_ober_shoot_info(const cbm_ober_stand *s, size_t i, cbm_ober_shoot *o)
{
    if (!s || !o || i >= s->shoots.len)
        return CBM_E_INVALID;
    const ober_shoot *h = &s->shoots.data[i];
    memset(o, 0, sizeof *o);
    o->tree = (size_t)h->tree;
    o->parent = h->parent;
    o->order = h->order;
    o->trend = h->trend;
    o->age = h->age;
    o->nodes = h->nodes;
    o->lateral = h->lateral;
    o->short_shoot = h->short_shoot;
    o->proventitious = h->proventitious;
    o->position = h->position;
    o->length = h->len * 0.01;
    o->radius = h->radius * 0.01;
    o->tropism = h->tropism;
    o->carbon = h->carbon;
    o->leaves = h->leaves;
    o->buds = h->leaves_made;
    o->active_buds = h->active_buds;
    o->base = v3_scale(h->base, 0.01);
    o->tip = v3_scale(h->tip, 0.01);
    return CBM_OK;
}
