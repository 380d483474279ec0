/* Organ-organ contact by penalty forces: fruits in a bunch pushing each other aside (Jirasek,
 * Prusinkiewicz and Moulia 2000, §"Secondary growth, tropisms, and collisions" and Fig. 6;
 * digest §2.8: colliding organs are elastic and push on each other with forces proportional to
 * the penetration depth, the penalty method of Platt & Barr 1988).
 *
 * Geometry. A segment with a contact radius r > 0 carries a sphere of radius r centred at its
 * distal node X = P + l H (a fruit drawn centred at the end of its stalk; the stalk's last
 * segment is the pedicel). Two spheres a, b overlap when their distance d = |X_b - X_a| is below
 * r_a + r_b; the overlap is delta = r_a + r_b - d and n = (X_b - X_a) / d the line of centres.
 *
 * Force. The pair pushes b along n and a along -n with f(delta), the law of the ground contact
 * (solve_common.c): f = k delta^2 / (2 s) for delta < s (smoothing s > 0), k (delta - s/2)
 * beyond, continuous with its stiffness f' = k delta / s, then k. The forces act at the two
 * distal nodes (no moment about the node: the sphere is centred there). k is scaled with the
 * load during the solvers' load continuation, so lambda = 0 stays exact at the rest state even
 * where fruits overlap there. At equilibrium the overlap is f / k + s / 2 at most: a stiff k
 * keeps the interpenetration small.
 *
 * Detection in O(n) per evaluation: a uniform grid of cell size h = the largest diameter 2 r_max,
 * hashed into 2^m >= 2 n_spheres buckets (a 64-bit mix of the integer cell coordinates) and
 * sorted by a stable counting sort (centres, radii and cells copied in that order); each sphere
 * tests the later spheres of its own cell and all spheres of the 13 cells of the forward half of
 * its neighbourhood (offsets after (0, 0, 0) in x-major order), so each pair of cells is visited
 * once. Any overlapping pair is within one cell per axis (d < r_i + r_j <= h), so nothing is
 * missed; spheres that share a bucket only by a hash collision are skipped by their cell. The
 * order of the pairs (by bucket order, then neighbour cell) is deterministic. The cost is
 * O(n + pairs) for fruits of comparable size (measured: about 0.3 us per sphere up to 1e4).
 *
 * Tangent (Newton). With Delta = dX_b - dX_a (the nodes move with their paths: dX = dP +
 * l dth x H, from the tangent's forward sweep), d delta = -n.Delta and dn = (I - n n^T) Delta / d,
 * so the force on b changes by
 *     dF_b = -f' n (n.Delta) + (f / d) (Delta - n (n.Delta)),     dF_a = -dF_b,
 * which the tangent's backward sweep carries down the two paths like every other node force:
 * the Jacobian-vector product stays the exact derivative of the residual. A pair couples two
 * paths of the tree, which the O(n) tree factorisation (solve_tree.c) cannot hold; while any
 * pair touches, the fast solver uses that factorisation (without the pair terms) as the
 * preconditioner of its flexible GMRES, corrected for the normal stiffness of the pairs by the
 * Woodbury formula (below: one tree solve per pair per Newton step, up to CBM__CONTACT_RANK
 * pairs); the Krylov space picks up the rest (the tangential stiffness f / d, rank two per
 * pair, or all of the pair stiffness when more pairs touch).
 *
 * Memory: the sphere list, the grid and the pair list live in the plant and are reserved before
 * a solve (6 pairs per sphere at first). If an evaluation finds more pairs than that room, the
 * extra pairs are dropped for that evaluation and the solve entry point grows the room and
 * solves again, so no allocation happens inside the iteration.
 */
#include "mech/mech_internal.h"
#include "core/vecmath.h"

#include <math.h>
#include <stdint.h>

/* ---- the grid ---- */

void cbm__sphere_grid_free(cbm_context *ctx, cbm__sphere_grid *g)
{
    cbm__free(ctx, g->bucket, g->cap * sizeof *g->bucket);
    cbm__free(ctx, g->sorted, g->cap * sizeof *g->sorted);
    cbm__free(ctx, g->sc, g->cap * sizeof *g->sc);
    cbm__free(ctx, g->sr, g->cap * sizeof *g->sr);
    cbm__free(ctx, g->scell, 3 * g->cap * sizeof *g->scell);
    if (g->nbuckets)
        cbm__free(ctx, g->start, (g->nbuckets + 1) * sizeof *g->start);
    memset(g, 0, sizeof *g);
}

cbm_status cbm__sphere_grid_reserve(cbm_context *ctx, cbm__sphere_grid *g, size_t n)
{
    if (n <= g->cap && g->nbuckets)
        return CBM_OK;
    size_t cap = n > 2 * g->cap ? n : 2 * g->cap;
    if (cap < 8)
        cap = 8;
    size_t nb = 16;
    while (nb < 2 * cap)
        nb <<= 1;
    size_t *bucket = cbm__alloc(ctx, cap * sizeof *bucket);
    size_t *sorted = cbm__alloc(ctx, cap * sizeof *sorted);
    size_t *start = cbm__alloc(ctx, (nb + 1) * sizeof *start);
    cbm_vec3 *sc = cbm__alloc(ctx, cap * sizeof *sc);
    double *sr = cbm__alloc(ctx, cap * sizeof *sr);
    int64_t *scell = cbm__alloc(ctx, 3 * cap * sizeof *scell);
    if (!bucket || !sorted || !start || !sc || !sr || !scell) {
        if (scell)
            cbm__free(ctx, scell, 3 * cap * sizeof *scell);
        if (sc)
            cbm__free(ctx, sc, cap * sizeof *sc);
        if (sr)
            cbm__free(ctx, sr, cap * sizeof *sr);
        if (bucket)
            cbm__free(ctx, bucket, cap * sizeof *bucket);
        if (sorted)
            cbm__free(ctx, sorted, cap * sizeof *sorted);
        if (start)
            cbm__free(ctx, start, (nb + 1) * sizeof *start);
        return CBM_E_NOMEM;
    }
    cbm__sphere_grid_free(ctx, g);
    g->cap = cap;
    g->nbuckets = nb;
    g->bucket = bucket;
    g->sorted = sorted;
    g->start = start;
    g->sc = sc;
    g->sr = sr;
    g->scell = scell;
    return CBM_OK;
}

/* integer cell coordinate, clamped so that far or non-finite points stay representable */
static inline int64_t cell_of(double x, double inv)
{
    double c = floor(x * inv);
    if (!(c > -4e15))
        c = -4e15;
    if (!(c < 4e15))
        c = 4e15;
    return (int64_t)c;
}

static inline size_t hash3(int64_t x, int64_t y, int64_t z, size_t mask)
{
    uint64_t h = (uint64_t)x * 0x9E3779B97F4A7C15ull;
    h ^= (uint64_t)y * 0xC2B2AE3D27D4EB4Full;
    h ^= (uint64_t)z * 0x165667B19E3779F9ull;
    h ^= h >> 29;
    h *= 0xBF58476D1CE4E5B9ull;
    h ^= h >> 32;
    return (size_t)(h & mask);
}

/* records the pair of spheres i, j (sorted positions ki, kj) if they overlap */
static inline size_t test_pair(const cbm__sphere_grid *g, size_t ki, size_t kj, cbm__mech_pair *out,
                               size_t cap, size_t found)
{
    cbm_vec3 d = v3_sub(g->sc[kj], g->sc[ki]);
    double d2 = v3_dot(d, d), rs = g->sr[ki] + g->sr[kj];
    if (!(d2 < rs * rs) || !(g->sr[kj] > 0.0))
        return found;
    if (found < cap) {
        size_t i = g->sorted[ki], j = g->sorted[kj];
        cbm__mech_pair *pr = &out[found];
        double dist = sqrt(d2);
        if (i > j) { /* a < b, the line of centres from a to b */
            size_t t = i;
            i = j;
            j = t;
            d = v3_scale(d, -1.0);
        }
        pr->a = i;
        pr->b = j;
        pr->dist = dist;
        pr->over = rs - dist;
        /* coincident centres: any direction will do; x keeps it deterministic */
        pr->n = dist > 1e-12 * rs ? v3_scale(d, 1.0 / dist) : v3(1, 0, 0);
        pr->force = pr->stiff = 0.0;
    }
    return found + 1;
}

size_t cbm__sphere_grid_pairs(cbm__sphere_grid *g, const cbm_vec3 *c, const double *r, size_t n,
                              cbm__mech_pair *out, size_t cap)
{
    if (n < 2 || n > g->cap)
        return 0;
    double rmax = 0.0;
    for (size_t i = 0; i < n; i++)
        if (r[i] > rmax)
            rmax = r[i];
    if (!(rmax > 0.0) || !isfinite(rmax))
        return 0;
    const double inv = 1.0 / (2.0 * rmax);
    const size_t nb = g->nbuckets, mask = nb - 1;
    size_t *start = g->start, *bucket = g->bucket, *sorted = g->sorted;
    /* stable counting sort of the spheres by bucket */
    memset(start, 0, (nb + 1) * sizeof *start);
    for (size_t i = 0; i < n; i++) {
        size_t b = hash3(cell_of(c[i].x, inv), cell_of(c[i].y, inv), cell_of(c[i].z, inv), mask);
        bucket[i] = b;
        start[b + 1]++;
    }
    for (size_t b = 0; b < nb; b++)
        start[b + 1] += start[b];
    for (size_t i = 0; i < n; i++)
        sorted[start[bucket[i]]++] = i;
    for (size_t b = nb; b > 0; b--)
        start[b] = start[b - 1];
    start[0] = 0;
    /* centres, radii and cells in bucket order: a bucket's scan reads contiguous memory */
    int64_t *cell = g->scell;
    for (size_t k = 0; k < n; k++) {
        cbm_vec3 ck = c[sorted[k]];
        g->sc[k] = ck;
        g->sr[k] = r[sorted[k]];
        cell[3 * k] = cell_of(ck.x, inv);
        cell[3 * k + 1] = cell_of(ck.y, inv);
        cell[3 * k + 2] = cell_of(ck.z, inv);
    }
    /* each sphere meets the later spheres of its own cell and every sphere of the 13 cells of
     * the forward half of its neighbourhood; a bucket's spheres of other cells (hash
     * collisions) are skipped by their cell, so each pair of cells is visited once */
    size_t found = 0;
    for (size_t k0 = 0; k0 < n; k0++) {
        if (!(g->sr[k0] > 0.0))
            continue;
        const int64_t cx = cell[3 * k0], cy = cell[3 * k0 + 1], cz = cell[3 * k0 + 2];
        size_t b0 = bucket[sorted[k0]];
        for (size_t k = k0 + 1; k < start[b0 + 1]; k++)
            if (cell[3 * k] == cx && cell[3 * k + 1] == cy && cell[3 * k + 2] == cz)
                found = test_pair(g, k0, k, out, cap, found);
        for (int o = 14; o < 27; o++) { /* offsets after (0, 0, 0) in x-major order */
            int64_t nx = cx + o / 9 - 1, ny = cy + (o / 3) % 3 - 1, nz = cz + o % 3 - 1;
            size_t b = hash3(nx, ny, nz, mask);
            for (size_t k = start[b]; k < start[b + 1]; k++)
                if (cell[3 * k] == nx && cell[3 * k + 1] == ny && cell[3 * k + 2] == nz)
                    found = test_pair(g, k0, k, out, cap, found);
        }
    }
    return found;
}

/* ---- the plant's contacts ---- */

static void lowrank_free(cbm_plant *p);

void cbm__mech_pairs_free(cbm_plant *p)
{
    cbm__mech_contacts *c = &p->contacts;
    cbm_context *ctx = p->ctx;
    cbm__free(ctx, c->sph, c->cap * sizeof *c->sph);
    cbm__free(ctx, c->centre, c->cap * sizeof *c->centre);
    cbm__free(ctx, c->rad, c->cap * sizeof *c->rad);
    cbm__free(ctx, c->fnode, c->cap * sizeof *c->fnode);
    cbm__free(ctx, c->dx, c->cap * sizeof *c->dx);
    cbm__free(ctx, c->pairs, c->pcap * sizeof *c->pairs);
    lowrank_free(p);
    cbm__sphere_grid_free(ctx, &c->grid);
    c->sph = NULL;
    c->centre = NULL;
    c->rad = NULL;
    c->fnode = NULL;
    c->dx = NULL;
    c->pairs = NULL;
    c->cap = c->pcap = c->npairs = c->nsph = 0;
}

/* ---- the low-rank correction's workspace ---- */

enum { RK = CBM__CONTACT_RANK };

static void lowrank_free(cbm_plant *p)
{
    cbm__mech_contacts *c = &p->contacts;
    cbm_context *ctx = p->ctx;
    size_t n3 = 3 * c->cap;
    if (c->lr_z) {
        cbm__free(ctx, c->lr_z, RK * n3 * sizeof(double));
        cbm__free(ctx, c->lr_g, RK * n3 * sizeof(double));
        cbm__free(ctx, c->lr_tmp, n3 * sizeof(double));
        cbm__free(ctx, c->lr_m, RK * RK * sizeof(double));
        cbm__free(ctx, c->lr_d, RK * sizeof(double));
        cbm__free(ctx, c->lr_c, RK * sizeof(double));
        cbm__free(ctx, c->lr_piv, RK * sizeof(int));
    }
    c->lr_z = c->lr_g = c->lr_tmp = c->lr_m = c->lr_d = c->lr_c = NULL;
    c->lr_piv = NULL;
    c->lr_valid = false;
    c->lr_rank = 0;
}

/* for c->cap segments, all or none (after segment_arrays set the new cap) */
static cbm_status lowrank_alloc(cbm_plant *p)
{
    cbm__mech_contacts *c = &p->contacts;
    cbm_context *ctx = p->ctx;
    size_t n3 = 3 * c->cap;
    double *z = cbm__alloc(ctx, RK * n3 * sizeof(double));
    double *g = cbm__alloc(ctx, RK * n3 * sizeof(double));
    double *t = cbm__alloc(ctx, n3 * sizeof(double));
    double *m = cbm__alloc(ctx, RK * RK * sizeof(double));
    double *d = cbm__alloc(ctx, RK * sizeof(double));
    double *cc = cbm__alloc(ctx, RK * sizeof(double));
    int *piv = cbm__alloc(ctx, RK * sizeof(int));
    if (!z || !g || !t || !m || !d || !cc || !piv) {
        if (z)
            cbm__free(ctx, z, RK * n3 * sizeof(double));
        if (g)
            cbm__free(ctx, g, RK * n3 * sizeof(double));
        if (t)
            cbm__free(ctx, t, n3 * sizeof(double));
        if (m)
            cbm__free(ctx, m, RK * RK * sizeof(double));
        if (d)
            cbm__free(ctx, d, RK * sizeof(double));
        if (cc)
            cbm__free(ctx, cc, RK * sizeof(double));
        if (piv)
            cbm__free(ctx, piv, RK * sizeof(int));
        return CBM_E_NOMEM;
    }
    c->lr_z = z;
    c->lr_g = g;
    c->lr_tmp = t;
    c->lr_m = m;
    c->lr_d = d;
    c->lr_c = cc;
    c->lr_piv = piv;
    c->lr_valid = false;
    return CBM_OK;
}

/* the per-segment arrays for `cap` segments, all or none */
static cbm_status segment_arrays(cbm_plant *p, size_t cap)
{
    cbm__mech_contacts *c = &p->contacts;
    cbm_context *ctx = p->ctx;
    size_t *sph = cbm__alloc(ctx, cap * sizeof *sph);
    cbm_vec3 *centre = cbm__alloc(ctx, cap * sizeof *centre);
    double *rad = cbm__alloc(ctx, cap * sizeof *rad);
    cbm_vec3 *fnode = cbm__calloc(ctx, cap, sizeof *fnode);
    cbm_vec3 *dx = cbm__alloc(ctx, cap * sizeof *dx);
    /* the correction's workspace at the new size (released first: it holds 2 RK vectors) */
    lowrank_free(p);
    size_t oldcap = c->cap;
    c->cap = cap;
    bool lr = sph && centre && rad && fnode && dx && lowrank_alloc(p) == CBM_OK;
    c->cap = oldcap;
    if (!lr) {
        if (sph)
            cbm__free(ctx, sph, cap * sizeof *sph);
        if (centre)
            cbm__free(ctx, centre, cap * sizeof *centre);
        if (rad)
            cbm__free(ctx, rad, cap * sizeof *rad);
        if (fnode)
            cbm__free(ctx, fnode, cap * sizeof *fnode);
        if (dx)
            cbm__free(ctx, dx, cap * sizeof *dx);
        return CBM_E_NOMEM;
    }
    cbm__free(ctx, c->sph, c->cap * sizeof *c->sph);
    cbm__free(ctx, c->centre, c->cap * sizeof *c->centre);
    cbm__free(ctx, c->rad, c->cap * sizeof *c->rad);
    cbm__free(ctx, c->fnode, c->cap * sizeof *c->fnode);
    cbm__free(ctx, c->dx, c->cap * sizeof *c->dx);
    c->sph = sph;
    c->centre = centre;
    c->rad = rad;
    c->fnode = fnode;
    c->dx = dx;
    c->cap = cap;
    c->npairs = 0;
    return CBM_OK;
}

cbm_status cbm__mech_pairs_reserve(cbm_plant *p)
{
    cbm__mech_contacts *c = &p->contacts;
    if (!c->on)
        return CBM_OK;
    if (p->n > c->cap || !c->sph)
        CBM_TRY(segment_arrays(p, p->n > 16 ? p->n : 16));
    size_t ns = 0;
    for (size_t i = 0; i < p->n; i++)
        ns += p->crad[i] > 0.0;
    CBM_TRY(cbm__sphere_grid_reserve(p->ctx, &c->grid, ns));
    size_t want = 6 * ns + 16;
    if (c->npairs > c->pcap && 2 * c->npairs > want)
        want = 2 * c->npairs; /* the last evaluation found more than there was room for */
    if (want > c->pcap) {
        cbm__mech_pair *np = cbm__alloc(p->ctx, want * sizeof *np);
        if (!np)
            return CBM_E_NOMEM;
        cbm__free(p->ctx, c->pairs, c->pcap * sizeof *c->pairs);
        c->pairs = np;
        c->pcap = want;
        c->npairs = 0;
    }
    return CBM_OK;
}

void cbm__mech_pairs_prepare(cbm_plant *p)
{
    cbm__mech_contacts *c = &p->contacts;
    c->nsph = 0;
    if (!c->on || c->cap < p->n || !c->sph)
        return;
    size_t ns = 0;
    for (size_t i = 0; i < p->n && ns < c->grid.cap; i++)
        if (p->crad[i] > 0.0) {
            c->sph[ns] = i;
            c->rad[ns] = p->crad[i];
            ns++;
        }
    c->nsph = ns;
}

void cbm__mech_pairs_eval(cbm_plant *p)
{
    cbm__mech_contacts *c = &p->contacts;
    c->npairs = 0;
    c->lr_valid = false; /* a new state: the correction is set up again when used */
    if (!c->on || c->cap < p->n || !c->sph)
        return;
    memset(c->fnode, 0, p->n * sizeof *c->fnode);
    const size_t ns = c->nsph;
    for (size_t s = 0; s < ns; s++) {
        size_t i = c->sph[s];
        c->centre[s] = v3_madd(p->pos[i], q_h(p->q[i]), p->len[i]);
    }
    size_t found = cbm__sphere_grid_pairs(&c->grid, c->centre, c->rad, ns, c->pairs, c->pcap);
    c->npairs = found;
    size_t stored = found < c->pcap ? found : c->pcap;
    const double k = c->k * p->load_scale, sm = c->s;
    for (size_t q = 0; q < stored; q++) {
        cbm__mech_pair *pr = &c->pairs[q];
        pr->a = c->sph[pr->a];
        pr->b = c->sph[pr->b];
        double d = pr->over;
        if (d < sm) {
            pr->force = 0.5 * k * d * d / sm;
            pr->stiff = k * d / sm;
        } else {
            pr->force = k * (d - 0.5 * sm);
            pr->stiff = k;
        }
        cbm_vec3 f = v3_scale(pr->n, pr->force);
        c->fnode[pr->b] = v3_add(c->fnode[pr->b], f);
        c->fnode[pr->a] = v3_sub(c->fnode[pr->a], f);
    }
}

void cbm__mech_pairs_jvp(cbm_plant *p, const cbm_vec3 *dpos, const cbm_vec3 *dth, cbm_vec3 *dfc)
{
    cbm__mech_contacts *c = &p->contacts;
    if (!cbm__mech_pairs_active(p))
        return;
    for (size_t s = 0; s < c->nsph; s++) {
        size_t i = c->sph[s];
        c->dx[i] = v3_add(dpos[i], v3_scale(v3_cross(dth[i], q_h(p->q[i])), p->len[i]));
    }
    size_t stored = c->npairs < c->pcap ? c->npairs : c->pcap;
    for (size_t q = 0; q < stored; q++) {
        const cbm__mech_pair *pr = &c->pairs[q];
        cbm_vec3 del = v3_sub(c->dx[pr->b], c->dx[pr->a]);
        double nd = v3_dot(pr->n, del);
        cbm_vec3 df = v3_scale(pr->n, -pr->stiff * nd);
        if (pr->dist > 1e-12 * (pr->dist + pr->over))
            df = v3_add(df, v3_scale(v3_sub(del, v3_scale(pr->n, nd)), pr->force / pr->dist));
        dfc[pr->b] = v3_add(dfc[pr->b], df);
        dfc[pr->a] = v3_sub(dfc[pr->a], df);
    }
}

/* ---- the low-rank correction of the tree preconditioner ----
 *
 * With T the Newton matrix the tree factorisation holds (every term but the pair stiffness) and
 * the normal stiffness of pair p written as u_p d_p g_p^T (u_p: the residual's response to a
 * unit push along n at b and -n at a, u_p[i] = -R_i^T sum (X - P_i) x (+-n) over the pair's
 * nodes X carried by joint i; g_p: n . (dX_b - dX_a) = g_p . v, g_p[j] = a_j^T ((X - P_j) x
 * (+-n)) over the joints j on the nodes' paths, a_j = R_j J_r d_j the joint's rotation map;
 * d_p = -f'), Woodbury gives
 *     (T + U D G^T)^-1 = T^-1 - Z (I + D G^T Z)^-1 D G^T T^-1,   Z = T^-1 U.
 * Set-up: one tree solve per pair (Z), the small matrix and its LU; then each application costs
 * rank dot products and axpys on top of the tree solve. The tangential part of the pair
 * stiffness (f/d (I - n n^T): small, but it acts in the soft directions of the stems) is left
 * to FGMRES, and so is everything when more than CBM__CONTACT_RANK pairs touch. */

/* adds s * (the pair's u or g contributions) along the path of node `x` (segment) into v */
static void path_terms(const cbm_plant *p, size_t x, cbm_vec3 n, double sg, double *u, double *g)
{
    const double *fa = p->work.fa;
    cbm_vec3 X = v3_madd(p->pos[x], q_h(p->q[x]), p->len[x]);
    for (int64_t j = (int64_t)x; j >= 0; j = p->parent[j]) {
        cbm_vec3 r = v3_scale(v3_cross(v3_sub(X, p->pos[j]), n), sg);
        size_t o = 3 * (size_t)j;
        if (u) {
            cbm_quat q = p->q[j];
            cbm_vec3 h = q_h(q);
            cbm_vec3 l = v3(2.0 * (q.x * q.y - q.w * q.z), 1.0 - 2.0 * (q.x * q.x + q.z * q.z),
                            2.0 * (q.y * q.z + q.w * q.x));
            cbm_vec3 uu = v3_cross(h, l);
            u[o] -= v3_dot(r, h);
            u[o + 1] -= v3_dot(r, l);
            u[o + 2] -= v3_dot(r, uu);
        }
        if (g) {
            const double *a = fa + 9 * (size_t)j; /* row-major; g += a^T r */
            g[o] += a[0] * r.x + a[3] * r.y + a[6] * r.z;
            g[o + 1] += a[1] * r.x + a[4] * r.y + a[7] * r.z;
            g[o + 2] += a[2] * r.x + a[5] * r.y + a[8] * r.z;
        }
    }
}

static size_t lowrank_setup(cbm_plant *p)
{
    cbm__mech_contacts *c = &p->contacts;
    const size_t n3 = 3 * p->n;
    size_t stored = c->npairs < c->pcap ? c->npairs : c->pcap;
    c->lr_valid = true;
    c->lr_rank = 0;
    /* more touching pairs than the rank: FGMRES alone (the tree solves of a partial correction
     * cost more than the Krylov iterations they save) */
    if (c->lr_off || !c->lr_z || c->cap < p->n || stored > RK)
        return 0;
    /* the stiffest pairs: selection by repeated maximum (rank is small) */
    int sel[RK];
    int rank = 0;
    double last = INFINITY;
    size_t lastq = SIZE_MAX;
    while (rank < RK) {
        size_t best = SIZE_MAX;
        for (size_t q = 0; q < stored; q++) {
            double s = c->pairs[q].stiff;
            if (!(s > 0.0) || s > last || (s == last && q <= lastq))
                continue; /* taken already (ties by index) */
            if (best == SIZE_MAX || s > c->pairs[best].stiff)
                best = q;
        }
        if (best == SIZE_MAX)
            break;
        sel[rank++] = (int)best;
        last = c->pairs[best].stiff;
        lastq = best;
    }
    size_t passes = 0;
    for (int k = 0; k < rank; k++) {
        const cbm__mech_pair *pr = &c->pairs[sel[k]];
        double *u = c->lr_tmp, *g = c->lr_g + (size_t)k * n3, *z = c->lr_z + (size_t)k * n3;
        memset(u, 0, n3 * sizeof *u);
        memset(g, 0, n3 * sizeof *g);
        path_terms(p, pr->b, pr->n, 1.0, u, g);
        path_terms(p, pr->a, pr->n, -1.0, u, g);
        cbm__mech_tree_apply(p, (const cbm_vec3 *)u, (cbm_vec3 *)z);
        passes++;
        c->lr_d[k] = -pr->stiff;
    }
    /* M = I + D G^T Z, LU with partial pivoting */
    double *m = c->lr_m;
    for (int i = 0; i < rank; i++)
        for (int j = 0; j < rank; j++) {
            const double *g = c->lr_g + (size_t)i * n3, *z = c->lr_z + (size_t)j * n3;
            double s = 0.0;
            for (size_t q = 0; q < n3; q++)
                s += g[q] * z[q];
            m[i * rank + j] = (i == j ? 1.0 : 0.0) + c->lr_d[i] * s;
        }
    for (int k = 0; k < rank; k++) {
        int pv = k;
        for (int i = k + 1; i < rank; i++)
            if (fabs(m[i * rank + k]) > fabs(m[pv * rank + k]))
                pv = i;
        c->lr_piv[k] = pv;
        if (pv != k)
            for (int j = 0; j < rank; j++) {
                double t = m[k * rank + j];
                m[k * rank + j] = m[pv * rank + j];
                m[pv * rank + j] = t;
            }
        double d = m[k * rank + k];
        if (!(fabs(d) > 1e-300) || !isfinite(d))
            return passes; /* singular: leave it to FGMRES (rank 0) */
        for (int i = k + 1; i < rank; i++) {
            double f = m[i * rank + k] / d;
            m[i * rank + k] = f;
            for (int j = k + 1; j < rank; j++)
                m[i * rank + j] -= f * m[k * rank + j];
        }
    }
    c->lr_rank = rank;
    return passes;
}

size_t cbm__mech_pairs_precond(cbm_plant *p, double *z)
{
    cbm__mech_contacts *c = &p->contacts;
    size_t passes = 0;
    if (!c->lr_valid)
        passes = lowrank_setup(p);
    const int rank = c->lr_rank;
    if (rank == 0)
        return passes;
    const size_t n3 = 3 * p->n;
    double *e = c->lr_c;
    /* e = M^-1 D G^T y */
    for (int i = 0; i < rank; i++) {
        const double *g = c->lr_g + (size_t)i * n3;
        double s = 0.0;
        for (size_t q = 0; q < n3; q++)
            s += g[q] * z[q];
        e[i] = c->lr_d[i] * s;
    }
    const double *m = c->lr_m;
    for (int k = 0; k < rank; k++) {
        int pv = c->lr_piv[k];
        double t = e[k];
        e[k] = e[pv];
        e[pv] = t;
        for (int i = k + 1; i < rank; i++)
            e[i] -= m[i * rank + k] * e[k];
    }
    for (int i = rank - 1; i >= 0; i--) {
        double s = e[i];
        for (int j = i + 1; j < rank; j++)
            s -= m[i * rank + j] * e[j];
        e[i] = s / m[i * rank + i];
    }
    for (int i = 0; i < rank; i++) {
        const double *zi = c->lr_z + (size_t)i * n3;
        for (size_t q = 0; q < n3; q++)
            z[q] -= e[i] * zi[q];
    }
    return passes;
}

/* ---- public ---- */

cbm_status cbm_plant_set_contact(cbm_plant *p, double k, double smoothing)
{
    if (!p)
        return CBM_E_INVALID;
    if (!(isfinite(k) && k >= 0.0))
        return cbm__fail(p->ctx, CBM_E_INVALID, "contact: stiffness k must be finite and >= 0");
    if (!(isfinite(smoothing) && smoothing >= 0.0))
        return cbm__fail(p->ctx, CBM_E_INVALID, "contact: smoothing must be finite and >= 0 (m)");
    cbm__mech_contacts *c = &p->contacts;
    c->on = k > 0.0;
    c->k = k;
    c->s = smoothing;
    c->npairs = 0;
    c->nsph = 0;
    return CBM_OK;
}

bool cbm_plant_contact(const cbm_plant *p, double *k, double *smoothing)
{
    if (!p || !p->contacts.on)
        return false;
    if (k)
        *k = p->contacts.k;
    if (smoothing)
        *smoothing = p->contacts.s;
    return true;
}

cbm_status cbm_plant_set_contact_radius(cbm_plant *p, size_t seg, double radius)
{
    if (!p)
        return CBM_E_INVALID;
    if (seg >= p->n)
        return cbm__fail(p->ctx, CBM_E_INVALID, "segment %zu does not exist (plant has %zu)", seg,
                         p->n);
    if (!(isfinite(radius) && radius >= 0.0))
        return cbm__fail(p->ctx, CBM_E_INVALID,
                         "segment %zu: contact radius must be finite and >= 0 (m)", seg);
    p->crad[seg] = radius;
    return CBM_OK;
}

cbm_vec3 cbm_plant_organ_contact_force(const cbm_plant *p, size_t seg)
{
    if (!p || seg >= p->n || !p->contacts.on || p->contacts.cap < p->n || !p->contacts.fnode)
        return v3(0, 0, 0);
    return p->contacts.fnode[seg];
}

cbm_status cbm_plant_contact_stats(const cbm_plant *p, cbm_contact_stats *out)
{
    if (!p || !out)
        return CBM_E_INVALID;
    memset(out, 0, sizeof *out);
    for (size_t i = 0; i < p->n; i++)
        out->spheres += p->crad[i] > 0.0;
    const cbm__mech_contacts *c = &p->contacts;
    if (!c->on)
        return CBM_OK;
    size_t stored = c->npairs < c->pcap ? c->npairs : c->pcap;
    out->pairs = c->npairs;
    for (size_t q = 0; q < stored; q++) {
        if (c->pairs[q].over > out->max_overlap)
            out->max_overlap = c->pairs[q].over;
        if (c->pairs[q].force > out->max_force)
            out->max_force = c->pairs[q].force;
    }
    return CBM_OK;
}
