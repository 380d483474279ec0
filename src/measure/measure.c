/* A tree measured as a forester would (cambium/measure.h).
 *
 * Everything is one pass or two over the segment table (parents before children): the axes
 * (per parent the first child not marked lateral continues the axis, every other child starts
 * a lateral one, so a table with two "continuations" at a node still has one trunk), the trunk
 * (the first root and its continuations), the subtree lengths (summed from the last row up),
 * the forks and the laterals' angles. The buckling height is McMahon's (1973) elastic
 * similarity: a uniform column of diameter D buckles under its own weight at
 * H_cr = (7.837 E I / q)^(1/3) = 0.79 (E / (rho g))^(1/3) D^(2/3) (Greenhill, I = pi D^4 / 64,
 * q = rho g pi D^2 / 4), and McMahon found the record trees of the United States at about a
 * quarter of it. The pipe-model exponent of a fork solves sum (D_child / D_parent)^a = 1, which
 * has one root a > 0 when every child is thinner than the parent (the sum falls from the number
 * of children at a = 0 towards 0); Leonardo's rule is a = 2.
 */
#include "core/core.h"
#include "core/vecmath.h"

#include "cambium/measure.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

cbm_measure_def cbm_measure_def_default(void)
{
    return (cbm_measure_def){.breast_height = 1.3, .gravity = 9.81, .crown_branch_fraction = 0.05};
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Quantile q of a sorted sample, linear between order statistics (Hyndman-Fan type 7). */
static double quantile(const double *v, size_t n, double q)
{
    double h = q * (double)(n - 1);
    size_t lo = (size_t)floor(h);
    size_t hi = lo + 1 < n ? lo + 1 : lo;
    return v[lo] + (h - (double)lo) * (v[hi] - v[lo]);
}

/* Sorts v in place and fills the quantiles (NaN for an empty sample). */
static cbm_measure_quantiles quantiles(double *v, size_t n)
{
    cbm_measure_quantiles q = {n, NAN, NAN, NAN, NAN, NAN, NAN, NAN};
    if (n == 0)
        return q;
    qsort(v, n, sizeof *v, cmp_double);
    q.min = v[0];
    q.q10 = quantile(v, n, 0.10);
    q.q25 = quantile(v, n, 0.25);
    q.median = quantile(v, n, 0.50);
    q.q75 = quantile(v, n, 0.75);
    q.q90 = quantile(v, n, 0.90);
    q.max = v[n - 1];
    return q;
}

static double median_of(double *v, size_t n)
{
    return n ? quantiles(v, n).median : NAN;
}

/* The exponent a of sum x_i^a = 1 (0 < x_i < 1, k >= 2), by bisection: the sum falls strictly
 * with a. NaN when it lies beyond 64 (children all but as thick as the parent). */
static double pipe_exponent(const double *x, size_t k)
{
    double lo = 0.0, hi = 64.0;
    double f = -1.0;
    for (size_t i = 0; i < k; i++)
        f += pow(x[i], hi);
    if (f > 0.0)
        return NAN;
    for (int it = 0; it < 100 && hi - lo > 1e-12; it++) {
        double a = 0.5 * (lo + hi), s = -1.0;
        for (size_t i = 0; i < k; i++)
            s += pow(x[i], a);
        if (s > 0.0)
            lo = a;
        else
            hi = a;
    }
    return 0.5 * (lo + hi);
}

static cbm_status check_table(cbm_context *ctx, const cbm_measure_segment *s, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        if (s[i].parent < -1 || s[i].parent >= (int64_t)i)
            return cbm__fail(ctx, CBM_E_INVALID,
                             "segment %zu: parent %lld is not an earlier segment (or -1)", i,
                             (long long)s[i].parent);
        if (!v3_isfinite(s[i].p0) || !v3_isfinite(s[i].p1))
            return cbm__fail(ctx, CBM_E_INVALID, "segment %zu: a point is not finite", i);
        if (!(s[i].r0 >= 0.0 && s[i].r1 >= 0.0 && isfinite(s[i].r0) && isfinite(s[i].r1)))
            return cbm__fail(ctx, CBM_E_INVALID, "segment %zu: a radius is negative or not finite",
                             i);
    }
    return CBM_OK;
}

/* Scratch of one measurement, released at once. */
typedef struct work {
    size_t *first, *child; /* children of i: child[first[i] .. first[i+1]) in row order */
    size_t *cont;          /* the continuing child of i, or SIZE_MAX */
    double *sub;           /* axis length of the subtree of i, m */
    double *buf;           /* samples, 2 n */
} work;

static void summary_axes(const cbm_measure_segment *s, size_t n, const work *w,
                         cbm_tree_measures *m)
{
    int *order = (int *)(void *)w->buf; /* n ints fit in n doubles */
    m->axes = 0;
    m->max_order = 0;
    for (size_t i = 0; i < n; i++) {
        int64_t p = s[i].parent;
        if (p < 0) {
            order[i] = 0;
            m->axes++;
        } else if (w->cont[p] == i) {
            order[i] = order[p];
        } else {
            order[i] = order[p] + 1;
            m->axes++;
        }
        if (order[i] > m->max_order)
            m->max_order = order[i];
    }
}

/* The next trunk segment above i: the thickest child (the continuation on a tie), as a forester
 * follows the main stem through a fork; SIZE_MAX at the top. */
static size_t trunk_next(const cbm_measure_segment *s, const work *w, size_t i)
{
    size_t best = w->cont[i];
    for (size_t k = w->first[i]; k < w->first[i + 1]; k++) {
        size_t c = w->child[k];
        if (best == SIZE_MAX || s[c].r0 > s[best].r0)
            best = c;
    }
    return best;
}

/* Trunk diameter, wood and buckling height. */
static void summary_trunk(const cbm_measure_def *def, const cbm_measure_segment *s, size_t n,
                          const work *w, double base, cbm_tree_measures *m)
{
    size_t root = 0;
    while (root < n && s[root].parent >= 0)
        root++;
    m->base_diameter = 2.0 * s[root].r0;
    m->diameter = m->base_diameter;
    m->diameter_at_base = true;
    size_t upto = root; /* last trunk segment whose wood counts */
    for (size_t i = root; i != SIZE_MAX; i = trunk_next(s, w, i)) {
        double y0 = s[i].p0.y - base, y1 = s[i].p1.y - base;
        if (y0 <= def->breast_height && y1 >= def->breast_height) {
            double t = y1 > y0 ? (def->breast_height - y0) / (y1 - y0) : 0.0;
            m->diameter = 2.0 * (s[i].r0 + t * (s[i].r1 - s[i].r0));
            m->diameter_at_base = false;
            upto = i;
            break;
        }
    }
    size_t ne = 0, nr = 0;
    double *e = w->buf, *rho = w->buf + n;
    for (size_t i = root;; i = trunk_next(s, w, i)) {
        if (isfinite(s[i].youngs_modulus) && s[i].youngs_modulus > 0.0)
            e[ne++] = s[i].youngs_modulus;
        if (isfinite(s[i].density) && s[i].density > 0.0)
            rho[nr++] = s[i].density;
        if (i == upto || trunk_next(s, w, i) == SIZE_MAX)
            break;
    }
    m->trunk_modulus = median_of(e, ne);
    m->trunk_density = median_of(rho, nr);
    m->buckling_height = 0.79 * cbrt(m->trunk_modulus / (m->trunk_density * def->gravity)) *
                         pow(m->diameter, 2.0 / 3.0);
    m->buckling_ratio = m->height / m->buckling_height;
    /* crown base: the lowest trunk node where a branch of some size leaves */
    m->crown_base_height = NAN;
    for (size_t i = root; i != SIZE_MAX; i = trunk_next(s, w, i))
        for (size_t k = w->first[i]; k < w->first[i + 1]; k++) {
            size_t c = w->child[k];
            double y = s[i].p1.y - base;
            if (c != trunk_next(s, w, i) &&
                w->sub[c] >= def->crown_branch_fraction * m->total_length &&
                !(y >= m->crown_base_height))
                m->crown_base_height = y;
        }
}

static void summary_forks(const cbm_measure_segment *s, size_t n, const work *w,
                          cbm_tree_measures *m)
{
    double *a = w->buf, *x = w->buf + n;
    size_t na = 0;
    m->forks = m->forks_unsolved = 0;
    for (size_t i = 0; i < n; i++) {
        size_t k = w->first[i + 1] - w->first[i];
        if (k < 2)
            continue;
        m->forks++;
        double dp = 2.0 * s[i].r1;
        bool ok = dp > 0.0;
        for (size_t j = 0; j < k && ok; j++) {
            x[j] = 2.0 * s[w->child[w->first[i] + j]].r0 / dp;
            ok = x[j] > 0.0 && x[j] < 1.0;
        }
        double e = ok ? pipe_exponent(x, k) : NAN;
        if (isfinite(e))
            a[na++] = e;
        else
            m->forks_unsolved++;
    }
    m->pipe_exponent = quantiles(a, na);
}

static void summary_angles_stress(const cbm_measure_segment *s, size_t n, const work *w,
                                  cbm_tree_measures *m)
{
    double *v = w->buf;
    size_t nv = 0;
    for (size_t i = 0; i < n; i++) {
        int64_t p = s[i].parent;
        if (p < 0 || w->cont[p] == i)
            continue;
        cbm_vec3 dc = v3_sub(s[i].p1, s[i].p0), dp = v3_sub(s[p].p1, s[p].p0);
        double nc = v3_norm(dc), np = v3_norm(dp);
        if (nc > 0.0 && np > 0.0) {
            double c = v3_dot(dc, dp) / (nc * np);
            v[nv++] = acos(c > 1.0 ? 1.0 : c < -1.0 ? -1.0 : c);
        }
    }
    m->branch_angle = quantiles(v, nv);
    nv = 0;
    size_t above = 0;
    for (size_t i = 0; i < n; i++)
        if (isfinite(s[i].stress_ratio)) {
            v[nv++] = s[i].stress_ratio;
            above += s[i].stress_ratio > 0.5;
        }
    m->stress_ratio = quantiles(v, nv);
    m->stress_above_half = nv ? (double)above / (double)nv : NAN;
}

static void work_free(cbm_context *ctx, work *w, size_t n)
{
    cbm__free(ctx, w->first, (n + 1) * sizeof *w->first);
    cbm__free(ctx, w->child, n * sizeof *w->child);
    cbm__free(ctx, w->cont, n * sizeof *w->cont);
    cbm__free(ctx, w->sub, n * sizeof *w->sub);
    cbm__free(ctx, w->buf, 2 * n * sizeof *w->buf);
}

cbm_status cbm_measure_segments(cbm_context *ctx, const cbm_measure_def *def,
                                const cbm_measure_segment *s, size_t n, cbm_tree_measures *out)
{
    if (!ctx || !out || (n && !s))
        return CBM_E_INVALID;
    memset(out, 0, sizeof *out);
    cbm_measure_def d = def ? *def : cbm_measure_def_default();
    CBM_TRY(check_table(ctx, s, n));
    cbm_tree_measures m = {0};
    m.segments = n;
    if (n == 0) {
        cbm_measure_quantiles none = {0, NAN, NAN, NAN, NAN, NAN, NAN, NAN};
        m.height = m.lowest = m.diameter = m.base_diameter = m.crown_width = m.crown_base_height =
            NAN;
        m.trunk_modulus = m.trunk_density = m.buckling_height = m.buckling_ratio = NAN;
        m.pipe_exponent = m.branch_angle = m.stress_ratio = none;
        m.stress_above_half = m.intersecting_fraction = NAN;
        *out = m;
        return CBM_OK;
    }
    work w = {0};
    w.first = cbm__calloc(ctx, n + 1, sizeof *w.first);
    w.child = cbm__calloc(ctx, n, sizeof *w.child);
    w.cont = cbm__calloc(ctx, n, sizeof *w.cont);
    w.sub = cbm__calloc(ctx, n, sizeof *w.sub);
    w.buf = cbm__calloc(ctx, 2 * n, sizeof *w.buf);
    if (!w.first || !w.child || !w.cont || !w.sub || !w.buf) {
        work_free(ctx, &w, n);
        return CBM_E_NOMEM;
    }
    /* children in row order (counting sort by parent) and the continuing child */
    for (size_t i = 0; i < n; i++)
        if (s[i].parent >= 0)
            w.first[s[i].parent + 1]++;
    for (size_t i = 0; i < n; i++)
        w.first[i + 1] += w.first[i];
    size_t *fill = (size_t *)(void *)w.buf; /* n size_t fit in 2n doubles */
    memcpy(fill, w.first, n * sizeof *fill);
    for (size_t i = 0; i < n; i++) {
        w.cont[i] = SIZE_MAX;
        if (s[i].parent >= 0)
            w.child[fill[s[i].parent]++] = i;
    }
    for (size_t i = 0; i < n; i++)
        if (s[i].parent >= 0 && !s[i].lateral && w.cont[s[i].parent] == SIZE_MAX)
            w.cont[s[i].parent] = i;
    /* height, crown width, lengths */
    double base = INFINITY, top = -INFINITY, low = INFINITY;
    double xlo = INFINITY, xhi = -INFINITY, zlo = INFINITY, zhi = -INFINITY;
    for (size_t i = 0; i < n; i++) {
        if (s[i].parent < 0 && s[i].p0.y < base)
            base = s[i].p0.y;
        top = fmax(top, fmax(s[i].p0.y, s[i].p1.y));
        low = fmin(low, fmin(s[i].p0.y, s[i].p1.y));
        xlo = fmin(xlo, s[i].p1.x), xhi = fmax(xhi, s[i].p1.x);
        zlo = fmin(zlo, s[i].p1.z), zhi = fmax(zhi, s[i].p1.z);
        w.sub[i] = v3_norm(v3_sub(s[i].p1, s[i].p0));
        m.total_length += w.sub[i];
    }
    for (size_t i = n; i-- > 0;)
        if (s[i].parent >= 0)
            w.sub[s[i].parent] += w.sub[i];
    m.height = top - base;
    m.lowest = low;
    m.crown_width = fmax(xhi - xlo, zhi - zlo);
    summary_axes(s, n, &w, &m);
    summary_trunk(&d, s, n, &w, base, &m);
    summary_forks(s, n, &w, &m);
    summary_angles_stress(s, n, &w, &m);
    work_free(ctx, &w, n);
    cbm_status st =
        cbm_measure_intersections(ctx, s, n, &m.intersecting, &m.intersecting_pairs, NULL);
    if (st != CBM_OK)
        return st;
    m.intersecting_fraction = (double)m.intersecting / (double)n;
    *out = m;
    return CBM_OK;
}

cbm_status cbm_measure_plant_table(cbm_context *ctx, const cbm_plant *plant,
                                   cbm_measure_segment **out, size_t *n)
{
    if (!ctx || !plant || !out || !n)
        return CBM_E_INVALID;
    *out = NULL;
    *n = 0;
    size_t count = cbm_plant_segment_count(plant);
    cbm_measure_segment *t = count ? cbm__calloc(ctx, count, sizeof *t) : NULL;
    if (count && !t)
        return CBM_E_NOMEM;
    int32_t *order = count ? cbm__calloc(ctx, count, sizeof *order) : NULL;
    if (count && !order) {
        cbm__free(ctx, t, count * sizeof *t);
        return CBM_E_NOMEM;
    }
    for (size_t i = 0; i < count; i++) {
        cbm_segment_state st;
        cbm_status s = cbm_plant_segment(plant, i, &st);
        if (s != CBM_OK) {
            cbm__free(ctx, t, count * sizeof *t);
            cbm__free(ctx, order, count * sizeof *order);
            return s;
        }
        order[i] = st.order;
        double r = 0.5 * (st.a + st.b);
        /* E from the rigidities, independent of which axis is which: I_L I_U = (pi a^2 b^2/4)^2 */
        double i_mean = CBM_PI * st.a * st.a * st.b * st.b / 4.0;
        t[i] = (cbm_measure_segment){
            .parent = st.parent,
            /* as in the segments table (which has the orders, not the links): a child of
             * another order than its parent's starts an axis */
            .lateral = st.parent >= 0 && st.order != order[st.parent],
            .p0 = st.proximal,
            .p1 = st.distal,
            .r0 = r,
            .r1 = r,
            .youngs_modulus = i_mean > 0.0 ? sqrt(st.rigidity.y * st.rigidity.z) / i_mean : NAN,
            .density = st.area > 0.0 ? st.mass_per_length / st.area : NAN,
            .stress_ratio = st.stress_ratio,
        };
    }
    cbm__free(ctx, order, count * sizeof *order);
    *out = t;
    *n = count;
    return CBM_OK;
}

void cbm_measure_table_free(cbm_context *ctx, cbm_measure_segment *table, size_t n)
{
    if (ctx && table)
        cbm__free(ctx, table, n * sizeof *table);
}

cbm_status cbm_measure_plant(cbm_context *ctx, const cbm_measure_def *def, const cbm_plant *plant,
                             cbm_tree_measures *out)
{
    if (!out)
        return CBM_E_INVALID;
    memset(out, 0, sizeof *out);
    cbm_measure_segment *t = NULL;
    size_t n = 0;
    CBM_TRY(cbm_measure_plant_table(ctx, plant, &t, &n));
    cbm_status s = cbm_measure_segments(ctx, def, t, n, out);
    cbm_measure_table_free(ctx, t, n);
    return s;
}
