/* Branch intersections (cambium/measure.h): which tubes pass through one another.
 *
 * Broad phase: a uniform grid of cubic cells of side h (the median over the segments of
 * max(length, 2 r), so a typical tube touches a few cells); each segment, cut into pieces no
 * longer than h, registers in every cell that the bounding box of a piece (grown by the radius)
 * touches. The (cell, segment) entries are sorted, and the segments sharing a cell are the
 * candidate pairs. When the entries would exceed 64 per segment (a few very fat tubes) the cell
 * doubles. The time is O(n log n) for the sort and O(n) for the pairs of a tree whose segments
 * are comparable; a pair met in several cells is tested again, and the intersecting pairs are
 * sorted and counted once.
 *
 * Narrow phase: the closest points of the two axes (segment-segment distance, Ericson,
 * "Real-Time Collision Detection" 5.1.9), and the tubes meet when that distance is below the sum
 * of the radii interpolated at those points (exact for cylinders; for cones a close
 * approximation, as the closest points of the axes are not quite those of the surfaces).
 *
 * Adjacent pairs are excluded: at a junction the tubes of a parent, its children and their
 * siblings share wood by construction, and a lateral leaving a thick axis at an angle theta
 * stays in that axis's wood for a while: its tube (radius r) leaves the axis's (radius R) a
 * distance (R + r) / sin theta along the lateral, level with (R + r) / tan theta along the
 * axis, so the two tubes overlap over a tree path of up to (R + r)(1 + cos theta) / sin theta
 * = (R + r) cot(theta / 2) from the junction. The path along the tree between the nearest ends
 * of the two segments (the lengths of the segments strictly between them, 0 when they share a
 * node) is compared with JUNCTION_REACH = 4 times the sum of their largest radii, cot(theta/2)
 * for theta = 28 degrees: no longer, and the pair is taken to meet inside a junction (laterals
 * leaving at 28 degrees or more have left it by then). A limb that passes through another
 * away from their common junction has a longer path and counts.
 *
 * Two more junctions. The knot of a node: the wood of all the segments meeting at a node fills
 * a ball about as large as the thickest of them, so siblings leaving a thick axis's end close
 * together (the fronds of a cycad's crown, 7.5 degrees apart in the golden spiral, on a trunk of
 * radius 6 cm) overlap inside it for longer than the path rule allows; a pair whose meeting point
 * lies within R of their common node, R the largest radius of the segments meeting there, each
 * of the two no farther than R from it along the tree, meets inside the knot. And roots whose
 * bases are one point (the stems of a spur, written as separate axes) join at that point. The
 * walks up the ancestors stop beyond the longer of the path bound and the largest radius.
 */
#include "core/core.h"
#include "core/vecmath.h"

#include "cambium/measure.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct entry {
    uint64_t cell;
    size_t seg;
} entry;

typedef struct pair {
    size_t a, b;
} pair;

typedef CBM_ARRAY(entry) entry_array;

static int cmp_entry(const void *x, const void *y)
{
    const entry *a = x, *b = y;
    if (a->cell != b->cell)
        return a->cell < b->cell ? -1 : 1;
    return (a->seg > b->seg) - (a->seg < b->seg);
}

static int cmp_pair(const void *x, const void *y)
{
    const pair *a = x, *b = y;
    if (a->a != b->a)
        return a->a < b->a ? -1 : 1;
    return (a->b > b->b) - (a->b < b->b);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double clamp01(double x)
{
    return x < 0.0 ? 0.0 : x > 1.0 ? 1.0 : x;
}

/* Closest points P(s) = p + s d1, Q(t) = q + t d2 of two segments, s and t in [0, 1]; returns
 * the squared distance. */
static double closest(cbm_vec3 p, cbm_vec3 d1, cbm_vec3 q, cbm_vec3 d2, double *s, double *t)
{
    cbm_vec3 r = v3_sub(p, q);
    double a = v3_dot(d1, d1), e = v3_dot(d2, d2), f = v3_dot(d2, r);
    const double eps = 1e-300;
    if (a <= eps && e <= eps) {
        *s = *t = 0.0;
    } else if (a <= eps) {
        *s = 0.0;
        *t = clamp01(f / e);
    } else {
        double c = v3_dot(d1, r);
        if (e <= eps) {
            *t = 0.0;
            *s = clamp01(-c / a);
        } else {
            double b = v3_dot(d1, d2), den = a * e - b * b;
            *s = den > 0.0 ? clamp01((b * f - c * e) / den) : 0.0;
            *t = (b * *s + f) / e;
            if (*t < 0.0) {
                *t = 0.0;
                *s = clamp01(-c / a);
            } else if (*t > 1.0) {
                *t = 1.0;
                *s = clamp01((b - c) / a);
            }
        }
    }
    cbm_vec3 dd = v3_sub(v3_madd(p, d1, *s), v3_madd(q, d2, *t));
    return v3_dot(dd, dd);
}

/* Whether the tubes of x and y meet; *at is then the midpoint of the closest points of their
 * axes (where they meet). */
static bool tubes_meet(const cbm_measure_segment *x, const cbm_measure_segment *y, cbm_vec3 *at)
{
    double s, t;
    cbm_vec3 dx = v3_sub(x->p1, x->p0), dy = v3_sub(y->p1, y->p0);
    double d2 = closest(x->p0, dx, y->p0, dy, &s, &t);
    double r = x->r0 + s * (x->r1 - x->r0) + y->r0 + t * (y->r1 - y->r0);
    *at = v3_scale(v3_add(v3_madd(x->p0, dx, s), v3_madd(y->p0, dy, t)), 0.5);
    return r > 0.0 && d2 < r * r;
}

#define MAX_WALK       256
#define JUNCTION_REACH 4.0

/* Whether two segments that meet at `at` meet inside a junction (the header's comment): the tree
 * path between their nearest ends, through the node n where their lines of descent join, is no
 * longer than JUNCTION_REACH times the sum of their largest radii; or both lie within the knot of
 * n (the tree path from n to each no longer than R, the largest radius of the segments meeting
 * at n) and `at` lies inside it (no farther than R from n). Roots whose bases are the same point
 * (several axes clamped at one node, as the stems of a spur) join at that point. The walks up
 * the ancestors stop beyond the longer of the two reaches, `reach` being the largest radius of
 * the table. */
static bool adjacent(const cbm_measure_segment *s, const double *len, const double *rmax, size_t i,
                     size_t j, cbm_vec3 at, double reach)
{
    double bound = JUNCTION_REACH * (rmax[i] + rmax[j]);
    double walk = fmax(bound, reach);
    int64_t anc[MAX_WALK];
    double gap[MAX_WALK];
    size_t na = 0;
    double g = 0.0;
    int64_t below_i = (int64_t)i; /* the last segment of i's line below the ancestor */
    int64_t prev[MAX_WALK];
    int64_t a = s[i].parent;
    for (; a >= 0 && na < MAX_WALK && g <= walk; a = s[a].parent) {
        if ((size_t)a == j)
            break;
        anc[na] = a;
        prev[na] = below_i;
        gap[na++] = g;
        g += len[a];
        below_i = a;
    }
    /* the node and its knot's radius, the path between the two through it */
    cbm_vec3 node;
    double knot, path, gi, gj;
    if (a >= 0 && (size_t)a == j) { /* j is an ancestor of i: they join at j's distal node */
        node = s[j].p1;
        knot = fmax(rmax[j], rmax[below_i]);
        path = gi = g;
        gj = 0.0;
    } else {
        bool found = false;
        double h = 0.0;
        size_t steps = 0;
        int64_t below_j = (int64_t)j, b = s[j].parent;
        size_t k = 0;
        for (; b >= 0 && steps < MAX_WALK && h <= walk && !found; steps++) {
            if ((size_t)b == i)
                break;
            for (k = 0; k < na && anc[k] != b; k++)
                ;
            if (k < na) {
                found = true;
                break;
            }
            h += len[b];
            below_j = b;
            b = s[b].parent;
        }
        if (b >= 0 && (size_t)b == i) { /* i is an ancestor of j */
            node = s[i].p1;
            knot = fmax(rmax[i], rmax[below_j]);
            path = gj = h;
            gi = 0.0;
        } else if (found) {
            node = s[b].p1;
            knot = fmax(rmax[b], fmax(rmax[prev[k]], rmax[below_j]));
            gi = gap[k];
            gj = h;
            path = gi + gj;
        } else if (a < 0 && b < 0 && below_i != below_j) {
            /* both walks reached their roots: the same base point joins them */
            double rr = fmax(rmax[below_i], rmax[below_j]);
            cbm_vec3 d = v3_sub(s[below_i].p0, s[below_j].p0);
            if (!(v3_dot(d, d) <= 1e-12 * rr * rr))
                return false;
            node = s[below_i].p0;
            knot = rr;
            gi = g;
            gj = h;
            path = gi + gj;
        } else {
            return false;
        }
    }
    if (path <= bound)
        return true;
    cbm_vec3 d = v3_sub(at, node);
    return gi <= knot && gj <= knot && v3_dot(d, d) <= knot * knot;
}

typedef struct grid {
    cbm_vec3 origin;
    double h;
} grid;

static uint64_t cell_of(long ix, long iy, long iz)
{
    return (uint64_t)ix << 42 | (uint64_t)iy << 21 | (uint64_t)iz;
}

/* Appends the cells of segment i's pieces; *over when that would make more than `limit`
 * entries in all. */
static cbm_status add_cells(cbm_context *ctx, const grid *gr, const cbm_measure_segment *s,
                            size_t i, double rmax, entry_array *e, size_t limit, bool *over)
{
    cbm_vec3 d = v3_sub(s[i].p1, s[i].p0);
    double len = v3_norm(d);
    size_t k = len > gr->h ? (size_t)ceil(len / gr->h) : 1;
    for (size_t p = 0; p < k; p++) {
        cbm_vec3 a = v3_madd(s[i].p0, d, (double)p / (double)k);
        cbm_vec3 b = v3_madd(s[i].p0, d, (double)(p + 1) / (double)k);
        long lo[3], hi[3];
        double av[3] = {a.x, a.y, a.z}, bv[3] = {b.x, b.y, b.z};
        double ov[3] = {gr->origin.x, gr->origin.y, gr->origin.z};
        for (int c = 0; c < 3; c++) {
            lo[c] = (long)floor((fmin(av[c], bv[c]) - rmax - ov[c]) / gr->h);
            hi[c] = (long)floor((fmax(av[c], bv[c]) + rmax - ov[c]) / gr->h);
        }
        for (long x = lo[0]; x <= hi[0]; x++)
            for (long y = lo[1]; y <= hi[1]; y++)
                for (long z = lo[2]; z <= hi[2]; z++) {
                    if (e->len >= limit) {
                        *over = true;
                        return CBM_OK;
                    }
                    CBM_TRY(CBM_ARRAY_PUSH(ctx, *e, ((entry){cell_of(x, y, z), i})));
                }
    }
    return CBM_OK;
}

cbm_status cbm_measure_intersections(cbm_context *ctx, const cbm_measure_segment *s, size_t n,
                                     size_t *intersecting, size_t *pairs, unsigned char *flags)
{
    if (!ctx || (n && !s))
        return CBM_E_INVALID;
    if (intersecting)
        *intersecting = 0;
    if (pairs)
        *pairs = 0;
    if (flags)
        memset(flags, 0, n);
    for (size_t i = 0; i < n; i++)
        if (s[i].parent < -1 || s[i].parent >= (int64_t)i || !v3_isfinite(s[i].p0) ||
            !v3_isfinite(s[i].p1) || !(s[i].r0 >= 0.0 && s[i].r1 >= 0.0) ||
            !isfinite(s[i].r0 + s[i].r1))
            return cbm__fail(ctx, CBM_E_INVALID,
                             "segment %zu: bad parent, point or radius for the intersections", i);
    if (n < 2)
        return CBM_OK;
    double *len = cbm__calloc(ctx, 3 * n, sizeof *len);
    if (!len)
        return CBM_E_NOMEM;
    double *rmax = len + n, *size = len + 2 * n;
    double reach = 0.0; /* the largest radius: no knot is larger */
    grid gr = {v3(INFINITY, INFINITY, INFINITY), 0.0};
    cbm_vec3 top = v3(-INFINITY, -INFINITY, -INFINITY);
    for (size_t i = 0; i < n; i++) {
        len[i] = v3_norm(v3_sub(s[i].p1, s[i].p0));
        rmax[i] = fmax(s[i].r0, s[i].r1);
        reach = fmax(reach, rmax[i]);
        size[i] = fmax(len[i], 2.0 * rmax[i]);
        cbm_vec3 lo =
            v3(fmin(s[i].p0.x, s[i].p1.x), fmin(s[i].p0.y, s[i].p1.y), fmin(s[i].p0.z, s[i].p1.z));
        cbm_vec3 hi =
            v3(fmax(s[i].p0.x, s[i].p1.x), fmax(s[i].p0.y, s[i].p1.y), fmax(s[i].p0.z, s[i].p1.z));
        gr.origin = v3(fmin(gr.origin.x, lo.x - rmax[i]), fmin(gr.origin.y, lo.y - rmax[i]),
                       fmin(gr.origin.z, lo.z - rmax[i]));
        top = v3(fmax(top.x, hi.x + rmax[i]), fmax(top.y, hi.y + rmax[i]),
                 fmax(top.z, hi.z + rmax[i]));
    }
    qsort(size, n, sizeof *size, cmp_double);
    gr.h = size[n / 2];
    /* cell indices stay within 21 bits each */
    double extent = v3_maxabs(v3_sub(top, gr.origin));
    if (!(gr.h > extent / (double)(1 << 20)))
        gr.h = extent > 0.0 ? extent / (double)(1 << 20) : 1.0;
    entry_array e = {0};
    CBM_ARRAY(pair) found = {0};
    cbm_status st = CBM_OK;
    size_t limit = 64 * n + 1024;
    for (;;) {
        bool over = false;
        e.len = 0;
        for (size_t i = 0; i < n && st == CBM_OK && !over; i++)
            st = add_cells(ctx, &gr, s, i, rmax[i], &e, limit, &over);
        if (st != CBM_OK || !over)
            break;
        gr.h *= 2.0;
    }
    if (st == CBM_OK) {
        if (e.len)
            qsort(e.data, e.len, sizeof *e.data, cmp_entry);
        for (size_t a = 0; a < e.len && st == CBM_OK;) {
            size_t b = a;
            while (b < e.len && e.data[b].cell == e.data[a].cell)
                b++;
            for (size_t x = a; x < b && st == CBM_OK; x++)
                for (size_t y = x + 1; y < b && st == CBM_OK; y++) {
                    size_t i = e.data[x].seg, j = e.data[y].seg;
                    cbm_vec3 at;
                    if (i == j || !tubes_meet(&s[i], &s[j], &at))
                        continue;
                    if (adjacent(s, len, rmax, j > i ? j : i, j > i ? i : j, at, reach))
                        continue;
                    st = CBM_ARRAY_PUSH(ctx, found, ((pair){i < j ? i : j, i < j ? j : i}));
                }
            a = b;
        }
    }
    if (st == CBM_OK) {
        if (found.len) /* qsort's pointer must not be NULL, even for no element */
            qsort(found.data, found.len, sizeof *found.data, cmp_pair);
        size_t np = 0, ni = 0;
        unsigned char *mark = flags ? flags : cbm__calloc(ctx, n, 1);
        if (!mark) {
            st = CBM_E_NOMEM;
        } else {
            for (size_t k = 0; k < found.len; k++) {
                if (k && !cmp_pair(&found.data[k], &found.data[k - 1]))
                    continue;
                np++;
                ni += !mark[found.data[k].a] + !mark[found.data[k].b];
                mark[found.data[k].a] = mark[found.data[k].b] = 1;
            }
            if (!flags)
                cbm__free(ctx, mark, n);
            if (intersecting)
                *intersecting = ni;
            if (pairs)
                *pairs = np;
        }
    }
    CBM_ARRAY_FREE(ctx, e);
    CBM_ARRAY_FREE(ctx, found);
    cbm__free(ctx, len, 3 * n * sizeof *len);
    return st;
}
