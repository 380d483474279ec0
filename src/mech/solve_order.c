/* The depth-first order of the solve (mech_internal.h, "The depth-first order of the solve").
 *
 * A plant's numbering is whatever built it: a user's calls, an L-system's string order, a
 * generator that appends a lateral on any earlier segment. The sweeps run in index order, so the
 * parent of a lateral may lie anywhere in memory, and each sweep waits for its lines (the parent's
 * frame, position and length forward; its accumulators backward). The solve runs instead on
 * copies of the plant's per-segment arrays (CBM__ORDER_ARRAYS) in depth-first preorder with the
 * children of a segment in increasing index: a segment's parent is then the segment before it
 * or an ancestor still on the path (a working set of the tree's depth), and a subtree is one
 * stretch of every array, so a thread of the tree sweeps reads its own lines.
 *
 * The same bits: the forward sweeps compute each segment from its parent alone; the backward
 * sweeps add a segment's terms into its parent, and in decreasing preorder a parent's children
 * arrive in decreasing index, as in the plant's order (the last child in preorder is the one of
 * highest index, which work.kin marks first); maxima do not depend on the order; sums over all
 * segments run in the plant's order through cbm__mech_at. The tests solve with and without the
 * order and compare every result bit for bit (test_mech_threads).
 *
 * The order is computed once per topology (plant.c clears it when segments are added or
 * removed), with the parents and axis flags in it. What the sweeps read is gathered at every
 * solve (the lengths, branching rotations and rotation rates may have changed between solves;
 * the rotation rates only for a warm start, a solve from rest setting every one before it reads
 * it), and what the solve writes (an evaluation sets every frame, position, force, moment and
 * carried mass before anything reads them) is scattered back after it with the rotation rates.
 * The rigidities, rest rates, masses and tip loads are not gathered: in a solve only the
 * prepare reads them (cbm__mech_prepare, which turns them into the workspace's joint arrays, in
 * the order), and it reads them from the plant's own arrays through ord, fetching each place's
 * lines ahead, once a solve instead of twice (a gather's read and the prepare's). The solver
 * asks of them only whether any point mass changed or any tip moment is set, which does not
 * depend on the order; the organ radii are read by the organ contact alone, which never runs in
 * the order. So a gather moves 64 bytes a segment (40 from rest) instead of 192.
 *
 * Only a solve over threads uses it (plants of 50,000 segments or more, more than one thread):
 * on one thread the gathering and scattering cost more than the sweeps save, on two the threads
 * no longer write into each other's lines (docs/performance.md, "The solve's depth-first
 * order"). */
#include "mech/mech_internal.h"

#include <string.h>

static size_t order_min_segments = 50000;

static bool order_serial = false;

void cbm__mech_order_min_segments(size_t min_segments)
{
    order_min_segments = min_segments;
}

void cbm__mech_order_serial(bool on)
{
    order_serial = on;
}

void cbm__mech_order_free(cbm_plant *p)
{
    cbm__mech_order *o = &p->sorder; /* never active here: cbm_plant_solve leaves it */
    cbm_context *ctx = p->ctx;
    cbm__free(ctx, o->ord, o->cap * sizeof *o->ord);
    cbm__free(ctx, o->at, o->cap * sizeof *o->at);
#define FREE(f) cbm__free(ctx, o->f, o->cap * sizeof *o->f);
    CBM__ORDER_ARRAYS(FREE)
#undef FREE
    memset(o, 0, sizeof *o);
}

/* Room for the plant's segments (grown by half again, as the workspace). */
static cbm_status order_reserve(cbm_plant *p)
{
    cbm__mech_order *o = &p->sorder;
    if (p->n <= o->cap)
        return CBM_OK;
    size_t cap = p->n > o->cap + o->cap / 2 ? p->n : o->cap + o->cap / 2;
    cbm__mech_order_free(p);
    cbm_context *ctx = p->ctx;
    bool ok = true;
    o->ord = cbm__alloc(ctx, cap * sizeof *o->ord);
    o->at = cbm__alloc(ctx, cap * sizeof *o->at);
    ok = o->ord && o->at;
#define ALLOC(f)                                                                                   \
    o->f = cbm__alloc(ctx, cap * sizeof *o->f);                                                    \
    ok = ok && o->f;
    CBM__ORDER_ARRAYS(ALLOC)
#undef ALLOC
    o->cap = cap; /* so that the free below releases what was taken */
    if (!ok) {
        cbm__mech_order_free(p);
        return CBM_E_NOMEM;
    }
    return CBM_OK;
}

/* ord and at from the parents (parent[i] < i): the subtree sizes from the tips, then each
 * segment in increasing index takes the next free place of its parent's stretch (a root, the
 * next place after the trees before it). ord holds the sizes, then each placed segment's next
 * free place, then the order itself. */
static void order_compute(cbm_plant *p)
{
    cbm__mech_order *o = &p->sorder;
    const size_t n = p->n;
    const int64_t *par = p->parent;
    uint32_t *ord = o->ord, *at = o->at;
    for (size_t i = 0; i < n; i++)
        ord[i] = 1;
    for (size_t i = n; i-- > 0;)
        if (par[i] >= 0)
            ord[par[i]] += ord[i];
    uint32_t next_root = 0;
    for (size_t i = 0; i < n; i++) {
        uint32_t size = ord[i];
        int64_t pa = par[i];
        if (pa < 0) {
            at[i] = next_root;
            next_root += size;
        } else {
            at[i] = ord[pa];
            ord[pa] += size;
        }
        ord[i] = at[i] + 1; /* the place of its first child */
    }
    bool identity = true;
    for (size_t i = 0; i < n; i++) {
        ord[at[i]] = (uint32_t)i;
        identity = identity && at[i] == i;
    }
    o->identity = identity;
    o->valid = true;
}

/* The plant's segment CBM__ORDER_AHEAD places after place k when the order jumps there (a
 * lateral's subtree done, the next begins elsewhere in the plant's arrays), so that its lines are
 * fetched ahead; SIZE_MAX where the order runs on in the plant's numbering or the range ends
 * first. */
static inline size_t jump_ahead(const uint32_t *restrict ord, size_t k, size_t hi)
{
    if (k + CBM__ORDER_AHEAD < hi && ord[k + CBM__ORDER_AHEAD] != ord[k + CBM__ORDER_AHEAD - 1] + 1)
        return ord[k + CBM__ORDER_AHEAD];
    return SIZE_MAX;
}

typedef struct move_job {
    cbm_plant *p;
    size_t lo, hi; /* places in the order */
    bool omega;    /* gather the state too (CBM__ORDER_STATE) */
} move_job;

/* What a solve's sweeps read, into the order: one pass over [lo, hi), the plant's lines of each
 * place fetched CBM__ORDER_AHEAD places ahead (at every place: where the order runs on in the
 * plant's numbering for a few segments only, as a `tree`'s axes do, fetching only where it jumps
 * leaves the run's next lines to wait). */
static void gather_job(void *arg)
{
    const move_job *j = arg;
    cbm_plant *p = j->p;
    cbm__mech_order *o = &p->sorder;
    const uint32_t *restrict ord = o->ord;
    const size_t hi = j->hi, last = hi > CBM__ORDER_AHEAD ? hi - CBM__ORDER_AHEAD : 0;
    for (size_t k = j->lo; k < hi; k++) {
        size_t i = ord[k];
        if (k < last) {
            size_t m = ord[k + CBM__ORDER_AHEAD];
#define PREFETCH(f) __builtin_prefetch(&p->f[m], 0, 3);
            CBM__ORDER_IN(PREFETCH)
            if (j->omega) {
                CBM__ORDER_STATE(PREFETCH)
            }
#undef PREFETCH
        }
#define GATHER(f) o->f[k] = p->f[i];
        CBM__ORDER_IN(GATHER)
        if (j->omega) {
            CBM__ORDER_STATE(GATHER)
        }
#undef GATHER
    }
}

/* What a solve wrote, back into the plant's arrays (swapped back), over [lo, hi). */
static void scatter_job(void *arg)
{
    const move_job *j = arg;
    cbm_plant *p = j->p;
    cbm__mech_order *o = &p->sorder;
    const uint32_t *restrict ord = o->ord;
    for (size_t k = j->lo; k < j->hi; k++) {
        size_t i = ord[k];
        size_t m = jump_ahead(ord, k, j->hi);
        if (m != SIZE_MAX) {
#define PREFETCH(f) __builtin_prefetch(&p->f[m], 1, 3);
            CBM__ORDER_STATE(PREFETCH) CBM__ORDER_OUT(PREFETCH)
#undef PREFETCH
        }
#define SCATTER(f) p->f[i] = o->f[k];
        CBM__ORDER_STATE(SCATTER) CBM__ORDER_OUT(SCATTER)
#undef SCATTER
    }
}

cbm_status cbm__mech_order_enter(cbm_plant *p, bool omega)
{
    cbm__mech_order *o = &p->sorder;
    const size_t n = p->n;
    if (o->active || n < order_min_segments || n < 2 || n > UINT32_MAX || p->contacts.on ||
        (!order_serial && cbm__mech_tree_threads(p) < 2))
        return CBM_OK;
    if (n > o->cap) {
        o->valid = false;
        CBM_TRY(order_reserve(p));
    }
    bool topo = !o->valid;
    if (topo)
        order_compute(p);
    if (o->identity)
        return CBM_OK;
    const uint32_t *restrict ord = o->ord;
    const uint32_t *restrict at = o->at;
    if (topo)
        for (size_t k = 0; k < n; k++) {
            size_t i = ord[k];
            int64_t pa = p->parent[i];
            o->parent[k] = pa < 0 ? pa : (int64_t)at[pa];
            o->cont[k] = p->cont[i];
        }
    /* over the threads of the solve, each a range of the order */
    int t = cbm__mech_tree_threads(p);
    move_job jobs[8];
    for (int k = 0; k < t; k++)
        jobs[k] = (move_job){p, n * (size_t)k / (size_t)t, n * (size_t)(k + 1) / (size_t)t, omega};
    cbm__mech_run_threads(t, gather_job, jobs, sizeof *jobs);
#define SWAP(f)                                                                                    \
    {                                                                                              \
        void *t_ = p->f;                                                                           \
        p->f = o->f;                                                                               \
        o->f = t_;                                                                                 \
    }
    CBM__ORDER_ARRAYS(SWAP)
    o->active = true;
    cbm__mech_fused_clear(p);
    return CBM_OK;
}

void cbm__mech_order_leave(cbm_plant *p)
{
    cbm__mech_order *o = &p->sorder;
    if (!o->active)
        return;
    CBM__ORDER_ARRAYS(SWAP)
#undef SWAP
    o->active = false;
    const size_t n = p->n;
    int t = cbm__mech_tree_threads(p);
    move_job jobs[8];
    for (int k = 0; k < t; k++)
        jobs[k] = (move_job){p, n * (size_t)k / (size_t)t, n * (size_t)(k + 1) / (size_t)t, true};
    cbm__mech_run_threads(t, scatter_job, jobs, sizeof *jobs);
    /* the workspace's joint arrays and accumulator marks are of the depth-first order: the next
     * prepare (every solve and evaluation starts with one) or cbm__mech_work_current renews them */
    p->work.stale = true;
}

void cbm__mech_work_current(cbm_plant *p)
{
    if (p->work.stale)
        cbm__mech_prepare(p);
}
