/* Equilibria of a branched plant (Tresierras 2009, ch. 5), in three passes:
 *
 * 1. Upstream: every branch's response as seen from its parent, a set of "segments": pieces of
 *    its (composite) S-curve on which its base moment, the weight it carries and its energy are
 *    single-valued functions of its base angle. A free-end branch's segments are the monotone
 *    runs of its S-curve between folds (the split of Fig. 5.3). A parent's are made for every
 *    combination of its children's segments (each child possibly turned by a whole turn): its
 *    tip angle phi is scanned over the range the combination allows, the children are replaced
 *    by their base moments and weights at phi + offset (the discontinuity equivalence (2.27)),
 *    the parent is shot from its tip, and the resulting curve is split into monotone runs.
 * 2. Downstream: at the plant's base angle, every crossing of the base branch's segments
 *    (modulo whole turns) gives the base branch's tip angle, hence its children's base angles,
 *    and so on to the tips: one equilibrium per crossing (the four of Fig. 5.4).
 * 3. Polish and stability: the tip angles of all branches are refined together by Newton on the
 *    angle conditions (5.3) with exact shooting (the tables of step 1 are interpolated), and the
 *    Morse index of the whole plant is the number of negative pivots of the tree-ordered LDL^T
 *    factorisation of the discrete second variation (N elements per branch:
 *    sum D/h (eta_{i+1} - eta_i)^2 - h P sin(theta) eta^2, the clamp at the base and the
 *    branch joints as springs); eliminating from the tips inward makes no fill-in, and by
 *    Sylvester's law of inertia the count of negative pivots is the count of negative
 *    eigenvalues.
 */
#include "elastica_internal.h"

#include <math.h>
#include <stdlib.h>

cbm_elastica_plant_def cbm_elastica_plant_def_default(void)
{
    cbm_elastica_plant_def d;
    d.scan = cbm_elastica_scan_def_default();
    d.hessian_elements = 400;
    d.max_states = 0;
    return d;
}

typedef struct sample {
    double x, m, w, e, phi; /* base angle, base moment, carried weight, subtree energy, tip */
} sample;

typedef struct segment {
    sample *s;
    size_t n; /* x increasing */
    int *child_seg;
    double *child_shift; /* whole turns added to each child's segment */
} segment;

typedef struct bseg {
    segment *seg;
    size_t n, cap;
} bseg;

typedef struct plant {
    cbm_context *ctx;
    const cbm_elastica_branch *br;
    size_t nb;
    int **children;
    size_t *nchild;
    bseg *segs;
    double weight_total_guard;
} plant;

static cbm_elastica_rod rod_of(const cbm_elastica_branch *b, double force, double moment)
{
    cbm_elastica_rod r = cbm_elastica_rod_default();
    r.pieces = b->pieces, r.n_pieces = b->n_pieces;
    r.tip_force = force, r.tip_moment = moment;
    return r;
}

static double own_weight(const cbm_elastica_branch *b)
{
    double w = 0;
    for (size_t k = 0; k < b->n_pieces; k++) {
        const cbm_elastica_piece *p = &b->pieces[k];
        for (int i = 0; i < 16; i++) /* midpoint rule on a smooth taper: exact enough */
            w += cbm__el_weight(p, (i + 0.5) / 16) * p->length / 16;
    }
    return w;
}

/* Interpolates a segment at base angle x (inside its range). */
static sample seg_at(const segment *g, double x)
{
    size_t lo = 0, hi = g->n - 1;
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (g->s[mid].x <= x)
            lo = mid;
        else
            hi = mid;
    }
    const sample *a = &g->s[lo], *b = &g->s[hi];
    double t = b->x > a->x ? (x - a->x) / (b->x - a->x) : 0;
    sample r = {x, a->m + t * (b->m - a->m), a->w + t * (b->w - a->w), a->e + t * (b->e - a->e),
                a->phi + t * (b->phi - a->phi)};
    return r;
}

static cbm_status push_seg(plant *P, size_t b, const sample *run, size_t n, int dir, const int *cs,
                           const double *csh, size_t nc)
{
    if (n < 2)
        return CBM_OK;
    bseg *B = &P->segs[b];
    if (B->n == B->cap) {
        size_t nc2 = B->cap ? 2 * B->cap : 8;
        segment *p = cbm__realloc(P->ctx, B->seg, B->cap * sizeof *p, nc2 * sizeof *p);
        if (!p)
            return CBM_E_NOMEM;
        B->seg = p, B->cap = nc2;
    }
    segment *g = &B->seg[B->n];
    memset(g, 0, sizeof *g);
    g->s = cbm__alloc(P->ctx, n * sizeof *g->s);
    g->child_seg = nc ? cbm__alloc(P->ctx, nc * sizeof *g->child_seg) : NULL;
    g->child_shift = nc ? cbm__alloc(P->ctx, nc * sizeof *g->child_shift) : NULL;
    if (!g->s || (nc && (!g->child_seg || !g->child_shift))) {
        cbm__free(P->ctx, g->s, n * sizeof *g->s);
        cbm__free(P->ctx, g->child_seg, nc * sizeof *g->child_seg);
        cbm__free(P->ctx, g->child_shift, nc * sizeof *g->child_shift);
        return CBM_E_NOMEM;
    }
    for (size_t i = 0; i < n; i++)
        g->s[i] = run[dir > 0 ? i : n - 1 - i];
    for (size_t i = 0; i < nc; i++)
        g->child_seg[i] = cs[i], g->child_shift[i] = csh[i];
    g->n = n;
    B->n++;
    return CBM_OK;
}

/* Splits a sampled curve (in order of its parameter) into monotone runs of x. */
static cbm_status split_runs(plant *P, size_t b, const sample *s, size_t n, const int *cs,
                             const double *csh, size_t nc)
{
    size_t start = 0;
    while (start + 1 < n) {
        int dir = s[start + 1].x > s[start].x ? 1 : -1;
        size_t end = start + 1;
        while (end + 1 < n && (s[end + 1].x > s[end].x ? 1 : -1) == dir)
            end++;
        cbm_status st = push_seg(P, b, s + start, end - start + 1, dir, cs, csh, nc);
        if (st != CBM_OK)
            return st;
        start = end;
    }
    return CBM_OK;
}

/* Shoots branch b at tip angle phi with the children of a combination interpolated. */
static cbm_status eval_branch(plant *P, size_t b, const int *cs, const double *csh, double phi,
                              sample *out, cbm_elastica_state *st)
{
    const cbm_elastica_branch *br = &P->br[b];
    double M = br->tip_moment, F = br->tip_force, E = 0;
    for (size_t c = 0; c < P->nchild[b]; c++) {
        int ch = P->children[b][c];
        const segment *g = &P->segs[ch].seg[cs[c]];
        sample a = seg_at(g, phi + P->br[ch].offset - csh[c]);
        M += a.m, F += a.w, E += a.e;
    }
    cbm_elastica_rod r = rod_of(br, F, M);
    double y[EL_N];
    int z = 0;
    cbm_status s = cbm__el_integrate(&r, phi, 0.0, y, &z, NULL, NULL, 0);
    if (s != CBM_OK)
        return cbm__fail(P->ctx, s, "elastica: branch %zu: integration failed", b);
    cbm__el_state(&r, phi, y, z, st);
    out->x = st->theta_base;
    out->m = st->moment_base;
    out->w = F + own_weight(br);
    out->e = E + st->energy + (M - br->tip_moment) * phi;
    out->phi = phi;
    return CBM_OK;
}

static cbm_status build_leaf(plant *P, size_t b, const cbm_elastica_scan_def *scan)
{
    const cbm_elastica_branch *br = &P->br[b];
    cbm_elastica_rod r = rod_of(br, br->tip_force, br->tip_moment);
    cbm_elastica_scurve *sc = NULL;
    cbm_status s = cbm_elastica_scurve_compute(P->ctx, &r, scan, &sc);
    if (s != CBM_OK)
        return s;
    sample *sm = cbm__alloc(P->ctx, sc->n_points * sizeof *sm);
    if (!sm) {
        cbm_elastica_scurve_destroy(P->ctx, sc);
        return CBM_E_NOMEM;
    }
    double w = br->tip_force + own_weight(br);
    for (size_t i = 0; i < sc->n_points; i++) {
        const cbm_elastica_state *a = &sc->points[i];
        sample q = {a->theta_base, a->moment_base, w, a->energy, a->theta_tip};
        sm[i] = q;
    }
    s = split_runs(P, b, sm, sc->n_points, NULL, NULL, 0);
    cbm__free(P->ctx, sm, sc->n_points * sizeof *sm);
    cbm_elastica_scurve_destroy(P->ctx, sc);
    return s;
}

static cbm_status build_parent(plant *P, size_t b, const cbm_elastica_scan_def *scan)
{
    size_t nc = P->nchild[b];
    int cs[CBM_ELASTICA_MAX_BRANCHES + 1];
    double csh[CBM_ELASTICA_MAX_BRANCHES + 1];
    int kk[CBM_ELASTICA_MAX_BRANCHES + 1]; /* shift index 0..2 -> -1..1 turns */
    for (size_t c = 0; c < nc; c++)
        cs[c] = 0, kk[c] = 0;
    const double tp = 2 * CBM_PI;
    cbm_status s = CBM_OK;
    size_t cap = 0;
    sample *buf = NULL;
    for (size_t c = 0; c < nc; c++)
        if (P->segs[P->children[b][c]].n == 0)
            return CBM_OK;
    while (s == CBM_OK) {
        /* the phi interval of this combination */
        double lo = scan->theta_tip_min, hi = scan->theta_tip_max;
        for (size_t c = 0; c < nc; c++) {
            int ch = P->children[b][c];
            const segment *g = &P->segs[ch].seg[cs[c]];
            csh[c] = (kk[c] - 1) * tp;
            double a = g->s[0].x + csh[c] - P->br[ch].offset;
            double z = g->s[g->n - 1].x + csh[c] - P->br[ch].offset;
            lo = fmax(lo, a), hi = fmin(hi, z);
        }
        if (hi > lo) {
            size_t n = (size_t)ceil((hi - lo) / (0.5 * CBM_PI / 180)) + 1;
            if (n < 9)
                n = 9;
            if (n > cap) {
                sample *p = cbm__realloc(P->ctx, buf, cap * sizeof *p, n * sizeof *p);
                if (!p) {
                    s = CBM_E_NOMEM;
                    break;
                }
                buf = p, cap = n;
            }
            for (size_t i = 0; i < n && s == CBM_OK; i++) {
                double phi = lo + (hi - lo) * (double)i / (double)(n - 1);
                cbm_elastica_state st;
                s = eval_branch(P, b, cs, csh, phi, &buf[i], &st);
            }
            if (s == CBM_OK)
                s = split_runs(P, b, buf, n, cs, csh, nc);
        }
        /* next combination */
        size_t c = 0;
        for (; c < nc; c++) {
            if (++kk[c] < 3)
                break;
            kk[c] = 0;
            int ch = P->children[b][c];
            if ((size_t)++cs[c] < P->segs[ch].n)
                break;
            cs[c] = 0;
        }
        if (c == nc)
            break;
    }
    cbm__free(P->ctx, buf, cap * sizeof *buf);
    return s;
}

/* ---- downstream ---- */

/* Fills phi of b's subtree from segment g of b at base angle x; `shift` is the whole turns by
 * which the tables of b's frame are turned in the plant. */
static void descend(plant *P, size_t b, const segment *g, double x, double shift, double *phi)
{
    sample a = seg_at(g, x);
    phi[b] = a.phi + shift;
    for (size_t c = 0; c < P->nchild[b]; c++) {
        int ch = P->children[b][c];
        const segment *gc = &P->segs[ch].seg[g->child_seg[c]];
        descend(P, (size_t)ch, gc, a.phi + P->br[ch].offset - g->child_shift[c],
                shift + g->child_shift[c], phi);
    }
}

/* Exact shooting of the whole plant from the tip angles: base angle, moment, carried weight,
 * energy per branch (children first). */
static cbm_status shoot_plant(plant *P, const double *phi, double *xb, double *mb, double *wb,
                              double *eb, cbm_elastica_state *st)
{
    for (size_t b = P->nb; b-- > 0;) {
        const cbm_elastica_branch *br = &P->br[b];
        double M = br->tip_moment, F = br->tip_force, E = 0;
        for (size_t c = 0; c < P->nchild[b]; c++) {
            int ch = P->children[b][c];
            M += mb[ch], F += wb[ch], E += eb[ch];
        }
        cbm_elastica_rod r = rod_of(br, F, M);
        double y[EL_N];
        int z = 0;
        cbm_status s = cbm__el_integrate(&r, phi[b], 0.0, y, &z, NULL, NULL, 0);
        if (s != CBM_OK)
            return s;
        cbm__el_state(&r, phi[b], y, z, &st[b]);
        xb[b] = st[b].theta_base;
        mb[b] = st[b].moment_base;
        wb[b] = F + own_weight(br);
        eb[b] = E + st[b].energy + (M - br->tip_moment) * phi[b];
    }
    return CBM_OK;
}

static void residual(plant *P, const double *phi, const double *xb, double theta_b, double *r)
{
    r[0] = xb[0] - theta_b;
    for (size_t b = 1; b < P->nb; b++)
        r[b] = xb[b] - (phi[P->br[b].parent] + P->br[b].offset);
}

/* Dense Gauss elimination with partial pivoting (n <= 64). */
static bool solve_dense(double *A, double *x, size_t n)
{
    for (size_t k = 0; k < n; k++) {
        size_t p = k;
        for (size_t i = k + 1; i < n; i++)
            if (fabs(A[i * n + k]) > fabs(A[p * n + k]))
                p = i;
        if (fabs(A[p * n + k]) < 1e-300)
            return false;
        if (p != k) {
            for (size_t j = 0; j < n; j++) {
                double t = A[k * n + j];
                A[k * n + j] = A[p * n + j], A[p * n + j] = t;
            }
            double t = x[k];
            x[k] = x[p], x[p] = t;
        }
        for (size_t i = k + 1; i < n; i++) {
            double f = A[i * n + k] / A[k * n + k];
            for (size_t j = k; j < n; j++)
                A[i * n + j] -= f * A[k * n + j];
            x[i] -= f * x[k];
        }
    }
    for (size_t k = n; k-- > 0;) {
        for (size_t j = k + 1; j < n; j++)
            x[k] -= A[k * n + j] * x[j];
        x[k] /= A[k * n + k];
    }
    return true;
}

typedef struct work {
    double *xb, *mb, *wb, *eb, *r, *r2, *J, *phi2;
    cbm_elastica_state *st;
} work;

static cbm_status polish(plant *P, double *phi, double theta_b, work *w, bool *ok)
{
    size_t n = P->nb;
    *ok = false;
    for (int it = 0; it < 40; it++) {
        cbm_status s = shoot_plant(P, phi, w->xb, w->mb, w->wb, w->eb, w->st);
        if (s != CBM_OK)
            return s;
        residual(P, phi, w->xb, theta_b, w->r);
        double nr = 0;
        for (size_t i = 0; i < n; i++)
            nr = fmax(nr, fabs(w->r[i]));
        if (nr < 1e-11) {
            *ok = true;
            return CBM_OK;
        }
        for (size_t j = 0; j < n; j++) {
            memcpy(w->phi2, phi, n * sizeof *phi);
            double h = 1e-7;
            w->phi2[j] += h;
            s = shoot_plant(P, w->phi2, w->xb, w->mb, w->wb, w->eb, w->st);
            if (s != CBM_OK)
                return s;
            residual(P, w->phi2, w->xb, theta_b, w->r2);
            for (size_t i = 0; i < n; i++)
                w->J[i * n + j] = (w->r2[i] - w->r[i]) / h;
        }
        for (size_t i = 0; i < n; i++)
            w->r[i] = -w->r[i];
        if (!solve_dense(w->J, w->r, n))
            return CBM_OK;
        double mx = 0;
        for (size_t i = 0; i < n; i++)
            mx = fmax(mx, fabs(w->r[i]));
        double sc = mx > 0.1 ? 0.1 / mx : 1.0; /* damped: the tables are close */
        for (size_t i = 0; i < n; i++)
            phi[i] += sc * w->r[i];
    }
    return CBM_OK;
}

/* ---- stability: the discrete second variation of the whole tree ---- */

static double weight_from(const cbm_elastica_branch *br, double s0)
{
    /* weight of the branch's own material between s0 and its tip */
    double w = 0, start = 0;
    for (size_t k = 0; k < br->n_pieces; k++) {
        const cbm_elastica_piece *p = &br->pieces[k];
        double a = fmax(s0, start), z = start + p->length;
        if (z > a)
            for (int i = 0; i < 16; i++) {
                double s = a + (z - a) * (i + 0.5) / 16;
                w += cbm__el_weight(p, (s - start) / p->length) * (z - a) / 16;
            }
        start += p->length;
    }
    return w;
}

static double stiff_at(const cbm_elastica_branch *br, double s)
{
    double start = 0;
    for (size_t k = 0; k < br->n_pieces; k++) {
        const cbm_elastica_piece *p = &br->pieces[k];
        if (s <= start + p->length || k + 1 == br->n_pieces)
            return cbm__el_stiffness(p, fmin(fmax((s - start) / p->length, 0), 1));
        start += p->length;
    }
    return br->pieces[0].D0;
}

static cbm_status morse_index(plant *P, const double *phi, const double *wb, const double *mb,
                              size_t N, int *index)
{
    size_t nb = P->nb;
    double *diag = cbm__alloc(P->ctx, nb * N * sizeof *diag);
    double *off = cbm__alloc(P->ctx, nb * N * sizeof *off); /* coupling to the proximal one */
    double *th = cbm__alloc(P->ctx, (2 * N + 1) * sizeof *th);
    if (!diag || !off || !th) {
        cbm__free(P->ctx, diag, nb * N * sizeof *diag);
        cbm__free(P->ctx, off, nb * N * sizeof *off);
        cbm__free(P->ctx, th, (2 * N + 1) * sizeof *th);
        return CBM_E_NOMEM;
    }
    memset(diag, 0, nb * N * sizeof *diag);
    cbm_status s = CBM_OK;
    for (size_t b = 0; b < nb && s == CBM_OK; b++) {
        const cbm_elastica_branch *br = &P->br[b];
        double F = br->tip_force, M = br->tip_moment;
        for (size_t c = 0; c < P->nchild[b]; c++)
            F += wb[P->children[b][c]], M += mb[P->children[b][c]];
        cbm_elastica_rod r = rod_of(br, F, M);
        s = cbm_elastica_shape(P->ctx, &r, phi[b], 2 * N + 1, NULL, NULL, th);
        double L = cbm__el_length(&r), h = L / (double)N;
        for (size_t i = 0; s == CBM_OK && i < N; i++) {
            double sm = (i + 0.5) * h;
            double Pm = F + weight_from(br, sm);
            size_t e = b * N + i;
            diag[e] -= h * Pm * sin(th[2 * i + 1]);
            double k;
            if (i > 0) {
                k = stiff_at(br, i * h) / h;
            } else if (b == 0) {
                k = stiff_at(br, 0) / (0.5 * h); /* the clamp */
                diag[e] += k;
                off[e] = 0;
                continue;
            } else {
                const cbm_elastica_branch *pb = &P->br[br->parent];
                double Lp = 0;
                for (size_t q = 0; q < pb->n_pieces; q++)
                    Lp += pb->pieces[q].length;
                double hp = Lp / (double)N;
                k = 1.0 / (0.5 * hp / stiff_at(pb, Lp) + 0.5 * h / stiff_at(br, 0));
                size_t pe = (size_t)br->parent * N + N - 1;
                diag[e] += k, diag[pe] += k;
                off[e] = -k;
                continue;
            }
            diag[e] += k, diag[e - 1] += k;
            off[e] = -k;
        }
    }
    /* eliminate from the tips: branches in reverse order, each from its tip to its base */
    int neg = 0;
    for (size_t b = nb; s == CBM_OK && b-- > 0;)
        for (size_t i = N; i-- > 0;) {
            size_t e = b * N + i;
            double d = diag[e];
            if (d < 0)
                neg++;
            if (b == 0 && i == 0)
                break;
            size_t pe = i > 0 ? e - 1 : (size_t)P->br[b].parent * N + N - 1;
            if (d != 0)
                diag[pe] -= off[e] * off[e] / d;
        }
    *index = neg;
    cbm__free(P->ctx, diag, nb * N * sizeof *diag);
    cbm__free(P->ctx, off, nb * N * sizeof *off);
    cbm__free(P->ctx, th, (2 * N + 1) * sizeof *th);
    return s;
}

void cbm_elastica_plant_states_destroy(cbm_context *ctx, cbm_elastica_plant_state *s, size_t n,
                                       size_t nb)
{
    if (!s)
        return;
    for (size_t i = 0; i < n; i++) {
        double **f[] = {&s[i].theta_tip, &s[i].theta_base, &s[i].moment_base, &s[i].tip_x,
                        &s[i].tip_y};
        for (int k = 0; k < 5; k++)
            cbm__free(ctx, *f[k], nb * sizeof(double));
    }
    cbm__free(ctx, s, n * sizeof *s);
}

static void free_plant(plant *P)
{
    for (size_t b = 0; b < P->nb; b++) {
        if (P->segs)
            for (size_t k = 0; k < P->segs[b].n; k++) {
                segment *g = &P->segs[b].seg[k];
                size_t nc = P->nchild[b];
                cbm__free(P->ctx, g->s, g->n * sizeof *g->s);
                cbm__free(P->ctx, g->child_seg, nc * sizeof *g->child_seg);
                cbm__free(P->ctx, g->child_shift, nc * sizeof *g->child_shift);
            }
        if (P->segs)
            cbm__free(P->ctx, P->segs[b].seg, P->segs[b].cap * sizeof *P->segs[b].seg);
        if (P->children)
            cbm__free(P->ctx, P->children[b], P->nb * sizeof **P->children);
    }
    cbm__free(P->ctx, P->segs, P->nb * sizeof *P->segs);
    cbm__free(P->ctx, P->children, P->nb * sizeof *P->children);
    cbm__free(P->ctx, P->nchild, P->nb * sizeof *P->nchild);
}

cbm_status cbm_elastica_plant_equilibria(cbm_context *ctx, const cbm_elastica_branch *br, size_t nb,
                                         const cbm_elastica_plant_def *def, double theta_b,
                                         cbm_elastica_plant_state **out, size_t *n_out)
{
    if (!ctx || !br || !out || !n_out || nb == 0 || nb > CBM_ELASTICA_MAX_BRANCHES + 1 ||
        !isfinite(theta_b))
        return CBM_E_INVALID;
    *out = NULL, *n_out = 0;
    cbm_elastica_plant_def d = def ? *def : cbm_elastica_plant_def_default();
    size_t maxs = d.max_states ? d.max_states : 4096, N = d.hessian_elements;
    if (N < 8)
        N = 8;
    for (size_t b = 0; b < nb; b++) {
        cbm_elastica_rod r = rod_of(&br[b], br[b].tip_force, br[b].tip_moment);
        cbm_status s = cbm__el_check(ctx, &r);
        if (s != CBM_OK)
            return s;
        if ((b == 0 && br[b].parent != -1) ||
            (b > 0 && (br[b].parent < 0 || (size_t)br[b].parent >= b)) || !isfinite(br[b].offset))
            return cbm__fail(ctx, CBM_E_INVALID,
                             "elastica: branch %zu: its parent must come before it", b);
    }
    plant P;
    memset(&P, 0, sizeof P);
    P.ctx = ctx, P.br = br, P.nb = nb;
    P.children = cbm__calloc(ctx, nb, sizeof *P.children);
    P.nchild = cbm__calloc(ctx, nb, sizeof *P.nchild);
    P.segs = cbm__calloc(ctx, nb, sizeof *P.segs);
    cbm_status s = (!P.children || !P.nchild || !P.segs) ? CBM_E_NOMEM : CBM_OK;
    for (size_t b = 0; s == CBM_OK && b < nb; b++) {
        P.children[b] = cbm__alloc(ctx, nb * sizeof **P.children);
        if (!P.children[b])
            s = CBM_E_NOMEM;
    }
    for (size_t b = 1; s == CBM_OK && b < nb; b++) {
        size_t p = (size_t)br[b].parent;
        P.children[p][P.nchild[p]++] = (int)b;
    }
    /* 1. upstream */
    for (size_t b = nb; s == CBM_OK && b-- > 0;)
        s = P.nchild[b] ? build_parent(&P, b, &d.scan) : build_leaf(&P, b, &d.scan);
    /* 2. downstream and 3. polish */
    work w;
    memset(&w, 0, sizeof w);
    double *buf = s == CBM_OK ? cbm__alloc(ctx, (8 * nb + nb * nb) * sizeof *buf) : NULL;
    w.st = s == CBM_OK ? cbm__alloc(ctx, nb * sizeof *w.st) : NULL;
    if (s == CBM_OK && (!buf || !w.st))
        s = CBM_E_NOMEM;
    double *phi = NULL;
    size_t cap = 0;
    cbm_elastica_plant_state *res = NULL;
    size_t nres = 0;
    if (s == CBM_OK) {
        w.xb = buf, w.mb = buf + nb, w.wb = buf + 2 * nb, w.eb = buf + 3 * nb;
        w.r = buf + 4 * nb, w.r2 = buf + 5 * nb, w.phi2 = buf + 6 * nb;
        phi = buf + 7 * nb;
        w.J = buf + 8 * nb;
    }
    const double tp = 2 * CBM_PI;
    for (size_t k = 0; s == CBM_OK && k < P.segs[0].n; k++) {
        const segment *g = &P.segs[0].seg[k];
        double lo = g->s[0].x, hi = g->s[g->n - 1].x;
        const double t0 = ceil((lo - theta_b) / tp), t1 = floor((hi - theta_b) / tp);
        for (long m = 0; m <= (long)(t1 - t0); m++) { /* whole turns t0..t1 */
            const double t = t0 + (double)m;
            descend(&P, 0, g, theta_b + t * tp, 0.0, phi);
            bool ok;
            s = polish(&P, phi, theta_b + t * tp, &w, &ok);
            if (s != CBM_OK || !ok)
                continue;
            /* turn the whole plant back by t turns */
            for (size_t b = 0; b < nb; b++)
                phi[b] -= t * tp;
            s = shoot_plant(&P, phi, w.xb, w.mb, w.wb, w.eb, w.st);
            if (s != CBM_OK)
                break;
            bool dup = false;
            for (size_t q = 0; q < nres && !dup; q++) {
                double dmax = 0;
                for (size_t b = 0; b < nb; b++)
                    dmax = fmax(dmax, fabs(remainder(res[q].theta_tip[b] - phi[b], tp)));
                dup = dmax < 1e-6;
            }
            if (dup)
                continue;
            if (nres == maxs) {
                s = cbm__fail(ctx, CBM_E_LIMIT, "elastica: more than %zu equilibria", maxs);
                break;
            }
            if (nres == cap) {
                size_t nc = cap ? 2 * cap : 8;
                cbm_elastica_plant_state *p =
                    cbm__realloc(ctx, res, cap * sizeof *p, nc * sizeof *p);
                if (!p) {
                    s = CBM_E_NOMEM;
                    break;
                }
                res = p, cap = nc;
            }
            cbm_elastica_plant_state *o = &res[nres];
            memset(o, 0, sizeof *o);
            double **f[] = {&o->theta_tip, &o->theta_base, &o->moment_base, &o->tip_x, &o->tip_y};
            for (int q = 0; q < 5; q++)
                if (!(*f[q] = cbm__alloc(ctx, nb * sizeof(double))))
                    s = CBM_E_NOMEM;
            nres++;
            if (s != CBM_OK)
                break;
            /* tips relative to the plant's base: each branch's tip offset added to its base */
            for (size_t b = 0; b < nb; b++) {
                o->theta_tip[b] = phi[b];
                o->theta_base[b] = w.xb[b];
                o->moment_base[b] = w.mb[b];
                double bx = 0, by = 0;
                if (b > 0)
                    bx = o->tip_x[br[b].parent], by = o->tip_y[br[b].parent];
                o->tip_x[b] = bx + w.st[b].tip_x;
                o->tip_y[b] = by + w.st[b].tip_y;
            }
            o->energy = w.eb[0];
            o->branch_index0 = w.st[0].index;
            s = morse_index(&P, phi, w.wb, w.mb, N, &o->index);
        }
    }
    cbm__free(ctx, buf, (8 * nb + nb * nb) * sizeof *buf);
    cbm__free(ctx, w.st, nb * sizeof *w.st);
    free_plant(&P);
    if (s == CBM_OK && nres < cap) { /* exact size, as the destroyer frees it */
        cbm_elastica_plant_state *p = nres ? cbm__alloc(ctx, nres * sizeof *p) : NULL;
        if (nres && !p)
            s = CBM_E_NOMEM;
        else {
            if (nres)
                memcpy(p, res, nres * sizeof *p);
            cbm__free(ctx, res, cap * sizeof *res);
            res = p, cap = nres;
        }
    }
    if (s != CBM_OK) {
        for (size_t i = 0; i < nres; i++) {
            double **f[] = {&res[i].theta_tip, &res[i].theta_base, &res[i].moment_base,
                            &res[i].tip_x, &res[i].tip_y};
            for (int k = 0; k < 5; k++)
                cbm__free(ctx, *f[k], nb * sizeof(double));
        }
        cbm__free(ctx, res, cap * sizeof *res);
        return s;
    }
    *out = res, *n_out = nres;
    return CBM_OK;
}
