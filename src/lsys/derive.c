/* Derivation of cpfg-dialect L-systems (ABOP ch. 1-2; cpfg's generate.c semantics).
 *
 * One step scans the current string left to right. At each module the productions whose
 * predecessor starts with its symbol are tried in declaration order: the strict predecessor
 * (symbols and parameter counts), the right context, the left context, then the
 * pre-condition statements and the condition. Context is bracket-aware as in ABOP: going right,
 * branches the context does not mention are skipped and the end of a branch ends the context;
 * going left, branches are skipped and '[' is climbed out of; `ignore:`/`consider:` symbols are
 * passed over. A deterministic L-system applies the first match; a stochastic one (any
 * production with a probability) collects every match, sums their probabilities in float32
 * and draws drand48() once per module, as cpfg does. The successor's parameters are evaluated
 * left to right into the other buffer (double-buffered; a successor without parameters is a
 * byte copy). With a decomposition section every produced module is rewritten recursively up
 * to `maximum depth`, context taken from the string being derived; the homomorphism is the
 * same recursion applied to the final string for output and interpretation. An unmatched cut
 * `%` removes the rest of its branch (up to the `]` that closes it, or the `$` that ends its
 * sub-L-system, cpfg's SkipCutPart).
 *
 * Sub-L-systems (cpfg manual 7.2, cpfg's generate.c): a pass keeps a stack of L-systems; the
 * module at hand is rewritten by the productions, decomposition, ignore table and stochastic
 * flag of the L-system on top, and once it is consumed, a `?(id, ...)` among the modules of the
 * predecessor pushes L-system id and a `$` pops (so `?(id)` itself belongs to the caller and
 * `$` to the sub-L-system). The homomorphism does the same over the modules it produces. Only
 * models with sub-L-systems take that path (ls->subcalls).
 *
 * Memory: the peak of a step is the current string plus the one being produced. When nothing
 * can look back into the current string (no left context in the productions, no
 * decomposition, in any of the model's L-systems) and the step cannot stop on a limit (the current
 * string times the longest successor, in modules and in bytes, is within max_modules and max_bytes;
 * failing that, the same bound by symbol, from a count of the current symbols), the pages of the
 * current string that the scan has passed are handed back to the system as it goes (madvise
 * MADV_DONTNEED, Linux), so the peak is close to the final string alone. The buffer keeps its
 * capacity and is refilled as the output of the next step.
 */
#define _DEFAULT_SOURCE
#include "lsys/lsys_internal.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#if defined(__linux__)
#include <sys/mman.h>
#include <unistd.h>
#endif

void cbm__lstr_free(cbm_context *ctx, lstr *s)
{
    cbm__free(ctx, s->sym, s->cap);
    cbm__free(ctx, s->pc, s->pccap);
    bool f32 = s->f32;
    cbm__free(ctx, s->par, s->parcap * cbm__param_size(s));
    memset(s, 0, sizeof *s);
    s->f32 = f32;
}

/* ---- matching ---- */
static bool match_predecessor(cbm_lsys *ls, const prod *pr, const lstr *s, lpos p, lpos *end,
                              int slot)
{
    const fmodule *m = ls->fmods.data + pr->pred;
    for (int32_t i = 0; i < pr->npred; i++) {
        if (p.mod >= s->n || (s->sym[p.mod] & 0x7f) != m[i].sym ||
            cbm__module_params(s, &p) != m[i].np)
            return false;
        if (m[i].np) {
            cbm__params_load(s, p.param, ls->frame + slot, m[i].np);
            slot += m[i].np;
        }
        cbm__pos_next(s, &p);
    }
    *end = p;
    return true;
}

/* The bracket table of s when s is the current string (started on the first branch a context
 * skips in it, kept while the string is unchanged, homomorphism included), else NULL: the walks
 * then scan. */
static cbm__brackets *brackets_of(cbm_lsys *ls, const lstr *s)
{
    if (s != &ls->cur)
        return NULL;
    cbm__brackets *t = &ls->brackets[0];
    if (t->s != &ls->cur || ls->brackets_gen != ls->cur_gen) {
        cbm__brackets_start(t, &ls->cur, 1, '[', ']');
        ls->brackets_gen = ls->cur_gen;
    }
    return t;
}

/* The parameter count of the module w is on. */
static inline int walk_params(const cbm__walk *w)
{
    return (w->s->sym[w->mod] & LSYS_PARAM_BIT) ? w->s->pc[w->pmod] : 0;
}

/* Right context from r (the module after the predecessor), through the walks of step.c: ignored
 * modules are passed over (even one the pattern names), a branch the pattern does not open is
 * skipped, `=` goes to the end of the branch and leaves its ']' (or to the end of the string
 * when there is none, or a '[' in the way is not closed). Parameters are bound as the pattern is
 * read. */
static bool match_right_context(cbm_lsys *ls, const prod *pr, const lstr *s, lpos r, int slot)
{
    const fmodule *m = ls->fmods.data + pr->right_ctx;
    cbm__brackets *t = NULL;
    cbm__walk w = cbm__walk_at(s, r.mod, r.pmod, r.param, 1);
    int32_t k = 0;
    while (k < pr->nright_ctx) {
        if (m[k].sym == '=') {
            t = t ? t : brackets_of(ls, s);
            if (!cbm__walk_to_branch_end(ls->ctx, t, &w, '[', ']'))
                w.mod = (ptrdiff_t)s->n; /* no ']': to the end */
            k++;
            continue;
        }
        if ((size_t)w.mod >= s->n) /* (never before the start: the walk only goes right) */
            return false;
        int c = cbm__walk_symbol(&w);
        if (ls->ign[c]) {
            cbm__walk_next_in_memory(&w);
        } else if (m[k].sym != '[' && c == '[') {
            t = t ? t : brackets_of(ls, s);
            if (!cbm__walk_skip_branch(ls->ctx, t, &w, '[', ']'))
                return false; /* unmatched: the branch runs to the end, the pattern does not */
            cbm__walk_next_in_memory(&w); /* past the ']' (the walk reads left to right) */
        } else {
            if (c != m[k].sym || walk_params(&w) != m[k].np)
                return false;
            if (m[k].np) {
                cbm__params_load(s, w.param, ls->frame + slot, m[k].np);
                slot += m[k].np;
            }
            cbm__walk_next_in_memory(&w);
            k++;
        }
    }
    return true;
}

/* Left context ending just before l: ignored modules and '[' are passed over (a branch is
 * climbed out of), whole branches are skipped. */
static bool match_left_context(cbm_lsys *ls, const prod *pr, const lstr *s, lpos l)
{
    const fmodule *m = ls->fmods.data + pr->left_ctx;
    int slot = 0;
    for (int32_t k = 0; k < pr->nleft_ctx; k++)
        slot += m[k].np;
    cbm__walk w = cbm__walk_at(s, l.mod, l.pmod, l.param, 1);
    int32_t k = pr->nleft_ctx - 1;
    while (k >= 0) {
        if (w.mod <= 0)
            return false;
        cbm__walk_prev_in_memory(&w);
        int c = cbm__walk_symbol(&w);
        if (c == ']') { /* to its '[' */
            if (w.mod == 0)
                return false;
            cbm__walk_prev_in_memory(&w);
            if (!cbm__walk_to_branch_start(&w, '[', ']'))
                return false;
        } else if (c != '[' && !ls->ign[c]) {
            if (c != m[k].sym || walk_params(&w) != m[k].np)
                return false;
            slot -= m[k].np;
            if (m[k].np)
                cbm__params_load(s, w.param, ls->frame + slot, m[k].np);
            k--;
        }
    }
    return true;
}

static inline bool runtime_ok(cbm_lsys *ls)
{
    return ls->ev.error == CBM_OK;
}

/* The frame slots of a production's left context's parameters (bound first) and of its
 * predecessor's (then the right context's). */
static void param_slots(const cbm_lsys *ls, const prod *pr, int *lslots, int *pslots)
{
    *lslots = *pslots = 0;
    for (int32_t k = 0; k < pr->nleft_ctx; k++)
        *lslots += ls->fmods.data[pr->left_ctx + k].np;
    for (int32_t k = 0; k < pr->npred; k++)
        *pslots += ls->fmods.data[pr->pred + k].np;
}

/* Whole match: predecessor in src at p, context in ctxs at lc/rc (for the main derivation
 * these are the predecessor's own positions; for decomposition the produced module's). */
static bool match(cbm_lsys *ls, const prod *pr, const lstr *src, lpos p, lpos *end,
                  const lstr *ctxs, const lpos *lc, const lpos *rc)
{
    int lslots, pslots;
    param_slots(ls, pr, &lslots, &pslots);
    if (!match_predecessor(ls, pr, src, p, end, lslots))
        return false;
    if (pr->nright_ctx && !match_right_context(ls, pr, ctxs, rc ? *rc : *end, lslots + pslots))
        return false;
    if (pr->nleft_ctx && !match_left_context(ls, pr, ctxs, lc ? *lc : p))
        return false;
    ls->ev.params = ls->frame;
    if (pr->pre >= 0)
        cbm__eval_stmt(&ls->ev, pr->pre);
    if (pr->cond >= 0 && !cbm__eval_expr(&ls->ev, pr->cond))
        return false;
    return true;
}

/* A module parameter is infinite or NaN (division by zero, overflow, beyond float's range in
 * float32 mode): a runtime error at the expression, or with limits.allow_nonfinite a warning
 * (once per run) and the value is kept. Returns whether to go on. */
static bool nonfinite(cbm_lsys *ls, int32_t expr)
{
    if (!cbm_context_limits(ls->ctx)->allow_nonfinite) {
        if (ls->ev.error == CBM_OK) {
            ls->ev.error = CBM_E_RUNTIME;
            ls->ev.error_msg = "a module parameter is not a finite number (--allow-nonfinite "
                               "keeps it)";
            ls->ev.error_node = expr;
        }
        return false;
    }
    if (!ls->nonfinite_warned) {
        ls->nonfinite_warned = true;
        const char *file;
        int line, col;
        cbm__compiler_locate(&ls->comp, cbm__node_pos(&ls->comp, expr), &file, &line, &col);
        cbm__diag(ls->ctx, CBM_WARNING, file, line, col,
                  "a module parameter is not a finite number (kept: --allow-nonfinite; further "
                  "ones are not reported)");
    }
    return true;
}

/* Appends the successor of pr (parameters evaluated with the bound frame). */
static cbm_status append_succ(cbm_lsys *ls, const prod *pr, lstr *dst)
{
    if (pr->post >= 0)
        cbm__eval_stmt(&ls->ev, pr->post);
    if (pr->nsucc == 0)
        return CBM_OK;
    if (pr->const_succ) {
        CBM_TRY(cbm__lstr_room(ls->ctx, dst, (size_t)pr->nsucc, 0, 0));
        memcpy(dst->sym + dst->n, ls->const_bytes.data + pr->succ_bytes, (size_t)pr->nsucc);
        dst->n += (size_t)pr->nsucc;
        return CBM_OK;
    }
    const smod *m = ls->smods.data + pr->succ;
    for (int32_t i = 0; i < pr->nsucc; i++) {
        CBM_TRY(cbm__lstr_room(ls->ctx, dst, 1, 1, m[i].np));
        if (m[i].np == 0) {
            dst->sym[dst->n++] = m[i].sym;
            continue;
        }
        dst->sym[dst->n++] = (uint8_t)(m[i].sym | LSYS_PARAM_BIT);
        dst->pc[dst->npm++] = m[i].np;
        int k = 0;
        if (dst->f32) {
            float *out = (float *)dst->par + dst->npar;
            for (int32_t a = m[i].args; a >= 0; a = ls->comp.nodes.data[a].next) {
                out[k] = (float)cbm__eval_expr(&ls->ev, a);
                if (!isfinite(out[k++]) && !nonfinite(ls, a))
                    return ls->ev.error;
            }
        } else {
            double *out = (double *)dst->par + dst->npar;
            for (int32_t a = m[i].args; a >= 0; a = ls->comp.nodes.data[a].next) {
                out[k] = cbm__eval_expr(&ls->ev, a);
                if (!isfinite(out[k++]) && !nonfinite(ls, a))
                    return ls->ev.error;
            }
        }
        dst->npar += m[i].np;
    }
    return CBM_OK;
}

static const prod *find_first(cbm_lsys *ls, const prodset *set, const lstr *src, lpos p, lpos *end,
                              const lstr *ctxs, const lpos *lc, const lpos *rc)
{
    uint8_t s = src->sym[p.mod] & 0x7f;
    for (int32_t o = set->start[s]; o < set->start[s + 1]; o++) {
        const prod *pr = &set->prods.data[set->order[o]];
        if (match(ls, pr, src, p, end, ctxs, lc, rc))
            return pr;
        if (!runtime_ok(ls))
            return NULL;
    }
    return NULL;
}

/* cpfg's ApplyRecursiveProductions: rewrites the module at *p of src with `set`, recursively,
 * appending to dst. Returns through *applied whether anything was written (at depth 0 an
 * unmatched module is left to the caller). */
static cbm_status rewrite(cbm_lsys *ls, const prodset *set, const lstr *src, lpos *p, lstr *dst,
                          const lstr *ctxs, const lpos *lc, const lpos *rc, int depth,
                          bool *applied)
{
    lpos end;
    const prod *pr = find_first(ls, set, src, *p, &end, ctxs, lc, rc);
    if (!runtime_ok(ls))
        return ls->ev.error;
    if (depth >= set->depth) {
        if (set->depth > 0) {
            *applied = true;
            return cbm__lstr_copy_module(ls->ctx, src, p, dst);
        }
        *applied = false;
        return CBM_OK;
    }
    if (!pr) {
        *applied = depth > 0;
        return depth > 0 ? cbm__lstr_copy_module(ls->ctx, src, p, dst) : CBM_OK;
    }
    *applied = true;
    /* a production applied in a decomposition or homomorphism is an operation: one that
     * doubles to its maximum depth stops at the budget, not at the memory */
    if (--ls->ops < 0)
        return cbm__compiler_fail(&ls->comp, CBM_E_LIMIT, pr->pos,
                                  "more productions applied in one step than the limit "
                                  "(--max-operations)");
    lstr *buf = &ls->scratch.data[depth];
    cbm__lstr_clear(buf);
    CBM_TRY(append_succ(ls, pr, buf));
    if (!runtime_ok(ls))
        return ls->ev.error;
    *p = end;
    lpos q = {0, 0, 0};
    while (q.mod < buf->n) {
        bool a;
        CBM_TRY(rewrite(ls, set, buf, &q, dst, ctxs, lc, rc, depth + 1, &a));
    }
    return CBM_OK;
}

static cbm_status prepare_scratch(cbm_lsys *ls, int depth)
{
    size_t need = (size_t)depth + 2;
    if (ls->scratch.len >= need)
        return CBM_OK;
    CBM_TRY(CBM_ARRAY_RESERVE(ls->ctx, ls->scratch, need));
    while (ls->scratch.len < need) {
        lstr z = {0};
        z.f32 = ls->float32;
        ls->scratch.data[ls->scratch.len++] = z;
    }
    return CBM_OK;
}

/* The loop budget of a step or block: the model's max_loop_iterations or the context's limit,
 * and no more than the operations limit (the cpfg dialect has no functions: its operations are
 * its loop iterations). */
static long loop_budget(const cbm_lsys *ls)
{
    const cbm_limits *lim = cbm_context_limits(ls->ctx);
    long b = ls->loop_budget > 0 ? ls->loop_budget : lim->max_loop_iterations;
    return lim->max_operations < b ? lim->max_operations : b;
}

/* A runtime error of the expressions becomes a failure with its message, at the expression
 * where it happened when known; the evaluator is cleared for the next call. */
static cbm_status runtime_fail(cbm_lsys *ls, cbm_status s, const char *what)
{
    if (ls->ev.error != CBM_OK) {
        cbm_status e = ls->ev.error;
        int32_t node = ls->ev.error_node;
        ls->ev.error = CBM_OK;
        ls->ev.error_node = -1;
        if (node >= 0)
            return cbm__compiler_fail(&ls->comp, e, cbm__node_pos(&ls->comp, node), "%s: %s", what,
                                      ls->ev.error_msg);
        return cbm__fail(ls->ctx, e, "%s: %s", what, ls->ev.error_msg);
    }
    return s;
}

static cbm_status run_block(cbm_lsys *ls, int32_t block, const char *what)
{
    if (block < 0)
        return CBM_OK;
    ls->ev.while_budget = loop_budget(ls);
    cbm__eval_stmt(&ls->ev, block);
    return runtime_fail(ls, CBM_OK, what);
}

/* Block `which` (0 Start, 1 StartEach, 2 EndEach, 3 End) of every L-system, in file order
 * (cpfg's EvaluateStartEach and the like). */
static cbm_status run_blocks(cbm_lsys *ls, int which, const char *what)
{
    for (int i = 0; i < ls->nsys; i++)
        CBM_TRY(run_block(ls, ls->sys[i].blocks[which], what));
    return CBM_OK;
}

/* Follows the sub-L-system markers among the modules of s from a up to module b: `?(id, ...)`
 * pushes the current L-system and makes L-system id current, `$` returns to the one below (a
 * `$` with nothing below is passed over). step: the step for messages, 0 in the homomorphism. */
static cbm_status follow_markers(cbm_lsys *ls, const lstr *s, lpos a, size_t b, int *cursys,
                                 int step)
{
    while (a.mod < b) {
        uint8_t c = s->sym[a.mod];
        if (c == ('?' | LSYS_PARAM_BIT)) {
            double v;
            cbm__params_load(s, a.param, &v, 1);
            int k = v >= -2e9 && v <= 2e9 ? cbm__lsys_find(ls, (int)v) : -1;
            if (k < 0) {
                char where[32] = "homomorphism";
                if (step > 0)
                    snprintf(where, sizeof where, "step %d", step);
                double id = v >= -2e9 && v <= 2e9 ? (double)(int)v : v;
                return cbm__fail(ls->ctx, CBM_E_RUNTIME,
                                 "%s: ?(%g, ...) calls a sub-L-system, but no L-system of the "
                                 "file is labelled %g",
                                 where, v, id);
            }
            CBM_TRY(CBM_ARRAY_PUSH(ls->ctx, ls->lstack, (uint16_t)*cursys));
            *cursys = k;
        } else if (c == '$' && ls->lstack.len > 0) {
            *cursys = ls->lstack.data[--ls->lstack.len];
        }
        cbm__pos_next(s, &a);
    }
    return CBM_OK;
}

/* Applies decomposition to the successor held in ls->succ (context: predecessor lc..rc). */
static cbm_status decompose_succ(cbm_lsys *ls, const prodset *dset, const lpos *lc, const lpos *rc)
{
    lpos q = {0, 0, 0};
    const lstr *buf = &ls->succ;
    while (q.mod < buf->n) {
        bool a;
        CBM_TRY(rewrite(ls, dset, buf, &q, &ls->next, &ls->cur, lc, rc, 0, &a));
        if (!a)
            CBM_TRY(cbm__lstr_copy_module(ls->ctx, buf, &q, &ls->next));
    }
    return CBM_OK;
}

/* ---- handing consumed pages of the current string back to the system ---- */

#define RELEASE_EVERY ((size_t)1 << 18) /* bytes of progress between two releases */

typedef struct release {
    bool on;
    size_t page;
    size_t done[3]; /* bytes of sym, pc, par already released (from the array's start) */
    size_t at;      /* next module index at which to release */
} release;

/* Whether a next string of at most nsym modules and npar parameters stays within the limits:
 * max_modules, and max_bytes with the symbols and counts, the parameters, capacity doubling
 * and a margin for the small arrays a step may grow. */
static bool release_fits(const cbm_lsys *ls, double nsym, double npar)
{
    const cbm_limits *lim = cbm_context_limits(ls->ctx);
    if (nsym > (double)lim->max_modules)
        return false;
    double nprods = 0;
    for (int k = 0; k < ls->nsys; k++)
        nprods += (double)ls->sys[k].main->prods.len;
    /* with sub-L-systems, the L-system stack: at most one entry per module, doubling */
    double lstack = ls->subcalls ? 4.0 * (double)ls->cur.n : 0.0;
    double need = (double)cbm_context_bytes(ls->ctx) +
                  2.0 * (2.0 * nsym + npar * (double)cbm__param_size(&ls->cur)) +
                  (double)(1u << 20) + 16.0 * nprods + lstack;
    return !lim->max_bytes || need <= (double)lim->max_bytes;
}

/* Whether the step over ls->cur may release its consumed pages (see the file comment). */
static void release_begin(const cbm_lsys *ls, release *r)
{
    memset(r, 0, sizeof *r);
#if defined(__linux__) && defined(MADV_DONTNEED)
    if (ls->cur.n < RELEASE_EVERY)
        return;
    for (int k = 0; k < ls->nsys; k++)
        if (ls->sys[k].decomp->present)
            return;
    /* bounds of the next string: a module becomes at most the longest successor of the
     * productions (of any L-system) that start with its symbol (with at most their most
     * parameters), or itself */
    size_t len[128], par[128], longest = 1, most = 0;
    for (int c = 0; c < 128; c++)
        len[c] = 1, par[c] = 0;
    for (int k = 0; k < ls->nsys; k++) {
        const prodset *set = ls->sys[k].main;
        for (size_t i = 0; i < set->prods.len; i++) {
            const prod *pr = &set->prods.data[i];
            if (pr->nleft_ctx)
                return;
            size_t np = 0;
            for (int32_t m = 0; !pr->const_succ && m < pr->nsucc; m++)
                np += ls->smods.data[pr->succ + m].np;
            int c = ls->fmods.data[pr->pred].sym & 0x7f;
            if ((size_t)pr->nsucc > len[c])
                len[c] = (size_t)pr->nsucc;
            if (np > par[c])
                par[c] = np;
            longest = len[c] > longest ? len[c] : longest;
            most = par[c] > most ? par[c] : most;
        }
    }
    const lstr *cur = &ls->cur;
    double nsym = (double)cur->n * (double)longest;
    double npar = (double)cur->npar + (double)cur->n * (double)most;
    if (!release_fits(ls, nsym, npar)) {
        /* tighter, at the cost of one pass over the symbols: by symbol */
        size_t hist[128] = {0};
        for (size_t i = 0; i < cur->n; i++)
            hist[cur->sym[i] & 0x7f]++;
        nsym = npar = 0;
        for (int c = 0; c < 128; c++) {
            nsym += (double)hist[c] * (double)len[c];
            npar += (double)hist[c] * (double)par[c];
        }
        npar += (double)cur->npar;
        if (!release_fits(ls, nsym, npar))
            return;
    }
    long page = sysconf(_SC_PAGESIZE);
    if (page <= 0)
        return;
    r->page = (size_t)page;
    r->on = true;
    r->at = RELEASE_EVERY;
#else
    (void)ls;
    (void)release_fits;
#endif
}

/* Releases the whole pages of [base, base + used) not released yet; the page holding base is
 * kept (it may hold the allocator's header). */
static void release_range(const release *r, void *base, size_t used, size_t *done)
{
#if defined(__linux__) && defined(MADV_DONTNEED)
    uintptr_t b = (uintptr_t)base;
    uintptr_t start = (b + *done + r->page - 1) / r->page * r->page;
    uintptr_t end = (b + used) / r->page * r->page;
    if (base == NULL || end <= start)
        return;
    /* page-aligned address computed as an integer */
    // NOLINTNEXTLINE(performance-no-int-to-ptr)
    if (madvise((void *)start, end - start, MADV_DONTNEED) == 0)
        *done = end - b;
#else
    (void)r, (void)base, (void)used, (void)done;
#endif
}

/* Called with p the first module the step may still read. */
static void release_consumed(release *r, const lstr *cur, const lpos *p)
{
    release_range(r, cur->sym, p->mod, &r->done[0]);
    release_range(r, cur->pc, p->pmod, &r->done[1]);
    release_range(r, cur->par, p->param * cbm__param_size(cur), &r->done[2]);
    r->at = p->mod + RELEASE_EVERY;
}

/* ---- the step: the step loop of lsys_internal.h with the cpfg dialect's hooks ---- */

/* The state of a step's pass over the current string. */
typedef struct cpfg_pass {
    cbm_lsys *ls;
    const lstr *cur; /* the current string */
    lstr *next;      /* the string being produced */
    release *rel;
    const prodset *set, *dset; /* of the L-system of the module at hand */
    bool decomp, stoch;
    bool sub;   /* the model has sub-L-systems: follow their markers */
    int cursys; /* the L-system of the module at hand (index in ls->sys) */
    bool cut;   /* the module just consumed was a cut */
    size_t max_modules;
} cpfg_pass;

/* The stochastic choice at p (cpfg): every production that matches, their probabilities summed
 * in float32, one drand48 draw; the chosen one's parameters bound again. */
static cbm_status choose_stochastic(cbm_lsys *ls, const prodset *set, lpos p, lpos *end,
                                    const prod **chosen)
{
    const lstr *cur = &ls->cur;
    uint8_t s = cur->sym[p.mod] & 0x7f;
    float total = 0;
    ls->appl.len = 0;
    ls->applp.len = 0;
    for (int32_t o = set->start[s]; o < set->start[s + 1]; o++) {
        int32_t pi = set->order[o];
        const prod *c = &set->prods.data[pi];
        lpos e;
        if (match(ls, c, cur, p, &e, cur, NULL, NULL)) {
            float pb = c->prob >= 0 ? (float)cbm__eval_expr(&ls->ev, c->prob) : 1.0f;
            total += pb;
            CBM_TRY(CBM_ARRAY_PUSH(ls->ctx, ls->appl, pi));
            CBM_TRY(CBM_ARRAY_PUSH(ls->ctx, ls->applp, pb));
        }
        if (!runtime_ok(ls))
            return CBM_E_RUNTIME;
    }
    float r = (float)((double)total * cbm__rand48_next(&ls->drand));
    for (size_t a = 0; a < ls->appl.len; a++) {
        if ((r -= ls->applp.data[a]) <= 0) {
            const prod *pr = &set->prods.data[ls->appl.data[a]];
            int lslots, pslots;
            param_slots(ls, pr, &lslots, &pslots);
            match_predecessor(ls, pr, cur, p, end, lslots);
            if (pr->nright_ctx)
                match_right_context(ls, pr, cur, *end, lslots + pslots);
            if (pr->nleft_ctx)
                match_left_context(ls, pr, cur, p);
            *chosen = pr;
            break;
        }
    }
    return CBM_OK;
}

/* The production of the module at *p (the first that matches, or the stochastic choice), its
 * successor written to the next string, decomposed as it is produced when the L-system has a
 * decomposition. */
static cbm_status cpfg_rewrite(void *d, lpos *p, size_t c, bool *applied)
{
    cpfg_pass *ps = d;
    cbm_lsys *ls = ps->ls;
    const prodset *set = ps->set;
    lpos end = *p;
    const prod *pr = NULL;
    if (ps->stoch)
        CBM_TRY(choose_stochastic(ls, set, *p, &end, &pr));
    else if (set->start[c] < set->start[c + 1])
        pr = find_first(ls, set, ps->cur, *p, &end, ps->cur, NULL, NULL);
    if (!runtime_ok(ls))
        return CBM_E_RUNTIME;
    *applied = pr != NULL;
    if (!pr)
        return CBM_OK;
    if (ps->decomp) {
        cbm__lstr_clear(&ls->succ);
        CBM_TRY(append_succ(ls, pr, &ls->succ));
        lpos lc = *p;
        CBM_TRY(decompose_succ(ls, ps->dset, &lc, &end));
    } else {
        CBM_TRY(append_succ(ls, pr, ps->next));
    }
    if (!runtime_ok(ls))
        return CBM_E_RUNTIME;
    *p = end;
    return CBM_OK;
}

/* A cut `%` at *p: p goes past it to the end of its branch (the ']' is kept), or to the '$'
 * that ends the sub-L-system the cut is in (kept too), or to the end of the string. */
static void cut_branch(const lstr *s, lpos *p)
{
    cbm__pos_next(s, p);
    int level = 0, slevel = 0;
    while (p->mod < s->n) {
        uint8_t b = s->sym[p->mod];
        uint8_t c = b & 0x7f;
        if (c == '[')
            level++;
        else if (c == ']' && level-- == 0)
            break;
        else if (b == ('?' | LSYS_PARAM_BIT))
            slevel++;
        else if (b == '$' && slevel-- == 0)
            break;
        cbm__pos_next(s, p);
    }
}

/* A module no production rewrites: decomposed (depth 0 of the decomposition), else cut if it
 * is a `%` without parameters, else copied. */
static cbm_status cpfg_unmatched(void *d, lpos *p, size_t c)
{
    cpfg_pass *ps = d;
    cbm_lsys *ls = ps->ls;
    const lstr *cur = ps->cur;
    bool done = false;
    if (ps->decomp) {
        lpos lc = *p, rc = *p;
        cbm__pos_next(cur, &rc);
        CBM_TRY(rewrite(ls, ps->dset, cur, p, ps->next, cur, &lc, &rc, 0, &done));
    }
    if (done)
        return CBM_OK;
    if (c == '%' && cbm__module_params(cur, p) == 0) {
        cut_branch(cur, p);
        ps->cut = true;
        return CBM_OK;
    }
    return cbm__lstr_copy_module(ls->ctx, cur, p, ps->next);
}

/* After the modules from..p: the sub-L-system markers among them (not after a cut), the
 * max_modules limit, the pages the pass has left behind. */
static cbm_status cpfg_after(void *d, const lpos *from, const lpos *p)
{
    cpfg_pass *ps = d;
    cbm_lsys *ls = ps->ls;
    if (ps->sub && !ps->cut) {
        int cursys = ps->cursys; /* (a copy: ps is not taken by address, it stays in registers) */
        CBM_TRY(follow_markers(ls, ps->cur, *from, p->mod, &cursys, ls->steps + 1));
        if (cursys != ps->cursys) {
            ps->cursys = cursys;
            const lsysv *L = &ls->sys[cursys];
            ps->set = L->main;
            ps->dset = L->decomp;
            ps->decomp = ps->dset->present;
            ps->stoch = L->stochastic;
            ls->ign = L->ignore;
        }
    }
    ps->cut = false;
    if (ps->next->n > ps->max_modules)
        return cbm__fail(ls->ctx, CBM_E_LIMIT,
                         "step %d: the string would exceed %zu modules (the max_modules "
                         "limit); stopped after step %d",
                         ls->steps + 1, ps->max_modules, ls->steps);
    if (ps->rel->on && p->mod >= ps->rel->at)
        release_consumed(ps->rel, ps->cur, p);
    return CBM_OK;
}

static const cbm__step_hooks CPFG_STEP = {cpfg_rewrite, cpfg_unmatched, cpfg_after};

/* A step that failed after releasing part of the current string cannot keep it: the string is
 * then emptied (cbm_lsys_step documents this). */
static cbm_status derive(cbm_lsys *ls)
{
    release rel;
    release_begin(ls, &rel);
    cbm__lstr_clear(&ls->next);
    ls->lstack.len = 0;
    ls->ign = ls->ignore;
    cpfg_pass ps = {.ls = ls,
                    .cur = &ls->cur,
                    .next = &ls->next,
                    .rel = &rel,
                    .set = &ls->main,
                    .dset = &ls->decomp,
                    .decomp = ls->decomp.present,
                    .stoch = ls->stochastic,
                    .sub = ls->subcalls,
                    .max_modules = cbm_context_limits(ls->ctx)->max_modules};
    lpos start = {0, 0, 0};
    cbm_status s = cbm__step_loop(&CPFG_STEP, &ps, &ls->cur, start);
    if (s != CBM_OK && (rel.done[0] || rel.done[1] || rel.done[2])) {
        cbm__lstr_clear(&ls->cur);
        ls->cur_gen++;
        ls->homo_valid = false;
    }
    return s;
}

static cbm_status cpfg_step(cbm_lsys *ls)
{
    if (ls->steps >= (int)cbm_context_limits(ls->ctx)->max_steps)
        return cbm__fail(ls->ctx, CBM_E_LIMIT, "more than %zu derivation steps (max_steps)",
                         cbm_context_limits(ls->ctx)->max_steps);
    CBM_TRY(prepare_scratch(ls, ls->max_depth));
    if (ls->interp)
        CBM_TRY(cbm_lsys_interpret(ls));
    ls->globals[ls->q_slot] = ls->steps + 1;
    CBM_TRY(run_blocks(ls, 1, "StartEach"));
    ls->ev.while_budget = loop_budget(ls);
    ls->ops = cbm_context_limits(ls->ctx)->max_operations;
    cbm_status s = derive(ls);
    if (s != CBM_OK) {
        char what[64];
        snprintf(what, sizeof what, "step %d", ls->steps + 1);
        s = runtime_fail(ls, s, what);
    }
    if (s == CBM_E_NOMEM && cbm_context_limits(ls->ctx)->max_bytes)
        s = cbm__fail(ls->ctx, CBM_E_LIMIT,
                      "step %d: the string would exceed the memory limit of %zu bytes; "
                      "stopped after step %d",
                      ls->steps + 1, cbm_context_limits(ls->ctx)->max_bytes, ls->steps);
    if (s != CBM_OK)
        return s;
    lstr t = ls->cur;
    ls->cur = ls->next;
    ls->next = t;
    ls->cur_gen++;
    ls->steps++;
    ls->homo_valid = false;
    CBM_TRY(run_blocks(ls, 2, "EndEach"));
    if (ls->steps == ls->derivation_length)
        CBM_TRY(run_blocks(ls, 3, "End"));
    return CBM_OK;
}

static cbm_status cpfg_reset(cbm_lsys *ls)
{
    memset(ls->globals, 0, ls->nglobals * sizeof(double));
    size_t off = 0;
    for (size_t i = 0; i < ls->comp.arrays.len; i++) {
        cbm__array *a = &ls->comp.arrays.data[i];
        memcpy(a->data, ls->array_init + off, a->count * sizeof(double));
        off += a->count;
    }
    ls->steps = 0;
    ls->homo_valid = false;
    cbm__rand48_seed16(&ls->ev.rnd.r48, 0x330E, 0, 0);
    /* cpfg starts nran with its pair cache marked full of a zero: the first nran(m, s) before
     * any srand returns m */
    ls->ev.rnd.normal_have = 1;
    ls->ev.rnd.normal_cached = 0;
    ls->ev.error = CBM_OK;
    ls->ev.error_node = -1;
    ls->nonfinite_warned = false;
    ls->ev.stopped = false;
    ls->ev.func = ls->func;
    ls->ev.func_ud = ls->func_ud;
    /* drand48: glibc's default state is 0; srand48(s) gives (s << 16) | 0x330E */
    bool seeded = false;
    uint64_t seed = 0;
    if (ls->seed_override >= 0) {
        seeded = true;
        seed = (uint64_t)ls->seed_override;
    } else if (ls->seed_expr >= 0 && !ls->ignore_seed) {
        seeded = true;
        seed = (uint64_t)cbm__to_ll(cbm__eval_expr(&ls->ev, ls->seed_expr));
    }
    ls->drand.x = seeded ? (((seed & 0xFFFFFFFFu) << 16) | 0x330E) : 0;
    CBM_TRY(run_blocks(ls, 0, "Start"));
    cbm__lstr_clear(&ls->cur);
    ls->cur_gen++;
    prod ax = {
        .pre = -1, .cond = -1, .post = -1, .prob = -1, .succ = ls->axiom, .nsucc = ls->naxiom};
    ax.const_succ = false;
    ls->ev.params = ls->frame;
    ls->ev.while_budget = loop_budget(ls);
    ls->ops = cbm_context_limits(ls->ctx)->max_operations;
    cbm_status s = append_succ(ls, &ax, &ls->cur);
    return runtime_fail(ls, s, "axiom");
}

static cbm_status homomorphism(cbm_lsys *ls, const lstr *cur, lstr *out);
static cbm_status homomorphism_sub(cbm_lsys *ls, const lstr *cur, lstr *out);

static cbm_status cpfg_interpretation(cbm_lsys *ls)
{
    lstr *out = &ls->homo_str;
    cbm__lstr_clear(out);
    CBM_TRY(prepare_scratch(ls, ls->max_depth));
    ls->ops = cbm_context_limits(ls->ctx)->max_operations;
    const lstr *cur = &ls->cur;
    if (ls->subcalls) {
        /* each L-system's homomorphism with a seed: has its own stream, restarted here */
        for (int i = 0; i < ls->nsys; i++) {
            int32_t e = ls->sys[i].homo->seed_expr;
            if (e < 0)
                continue;
            long long seed = cbm__to_ll(cbm__eval_expr(&ls->ev, e));
            cbm__rand48_seed16(&ls->hran[i], 0x330E, (uint16_t)(seed & 0xFFFF),
                               (uint16_t)((seed >> 16) & 0xFFFF));
        }
        cbm_status s = homomorphism_sub(ls, cur, out);
        if (s == CBM_OK)
            ls->homo_valid = true;
        return s;
    }
    /* with its own seed:, the homomorphism draws from its own erand48 stream, restarted at every
     * pass (cpfg), so the image is the same at every interpretation */
    cbm__rand48 saved = ls->ev.rnd.r48;
    if (ls->homo.seed_expr >= 0) {
        long long seed = cbm__to_ll(cbm__eval_expr(&ls->ev, ls->homo.seed_expr));
        cbm__rand48_seed16(&ls->ev.rnd.r48, 0x330E, (uint16_t)(seed & 0xFFFF),
                           (uint16_t)((seed >> 16) & 0xFFFF));
    }
    cbm_status s = homomorphism(ls, cur, out);
    if (ls->homo.seed_expr >= 0)
        ls->ev.rnd.r48 = saved;
    if (s == CBM_OK)
        ls->homo_valid = true;
    return s;
}

/* The homomorphism of a string with sub-L-systems: each module by the homomorphism of its
 * L-system, followed through the ?(id) and $ that come out (cpfg's interpretation switches on
 * the modules it interprets). */
static cbm_status homomorphism_sub(cbm_lsys *ls, const lstr *cur, lstr *out)
{
    lpos p = {0, 0, 0};
    int cursys = 0;
    ls->lstack.len = 0;
    while (p.mod < cur->n) {
        const lsysv *L = &ls->sys[cursys];
        ls->ign = L->ignore;
        lpos o = {out->n, out->npm, out->npar};
        bool done = false;
        if (L->homo->present) {
            lpos lc = p, rc = p;
            cbm__pos_next(cur, &rc);
            bool own = L->homo->seed_expr >= 0;
            cbm__rand48 t = ls->ev.rnd.r48;
            if (own)
                ls->ev.rnd.r48 = ls->hran[cursys];
            cbm_status s = rewrite(ls, L->homo, cur, &p, out, cur, &lc, &rc, 0, &done);
            if (own) {
                ls->hran[cursys] = ls->ev.rnd.r48;
                ls->ev.rnd.r48 = t;
            }
            if (s != CBM_OK)
                return runtime_fail(ls, s, "homomorphism");
        }
        if (!done)
            CBM_TRY(cbm__lstr_copy_module(ls->ctx, cur, &p, out));
        if (out->n > cbm_context_limits(ls->ctx)->max_modules)
            return cbm__fail(ls->ctx, CBM_E_LIMIT,
                             "the homomorphism would exceed %zu modules (max_modules)",
                             cbm_context_limits(ls->ctx)->max_modules);
        CBM_TRY(follow_markers(ls, out, o, out->n, &cursys, 0));
    }
    ls->ign = ls->ignore;
    return CBM_OK;
}

static cbm_status homomorphism(cbm_lsys *ls, const lstr *cur, lstr *out)
{
    lpos p = {0, 0, 0};
    ls->ign = ls->ignore;
    while (p.mod < cur->n) {
        bool done = false;
        if (ls->homo.present) {
            lpos lc = p, rc = p;
            cbm__pos_next(cur, &rc);
            cbm_status s = rewrite(ls, &ls->homo, cur, &p, out, cur, &lc, &rc, 0, &done);
            if (s != CBM_OK)
                return runtime_fail(ls, s, "homomorphism");
        }
        if (!done)
            CBM_TRY(cbm__lstr_copy_module(ls->ctx, cur, &p, out));
        if (out->n > cbm_context_limits(ls->ctx)->max_modules)
            return cbm__fail(ls->ctx, CBM_E_LIMIT,
                             "the homomorphism would exceed %zu modules (max_modules)",
                             cbm_context_limits(ls->ctx)->max_modules);
    }
    return CBM_OK;
}

int cbm_lsys_derivation_length(const cbm_lsys *ls)
{
    return ls->derivation_length;
}
int cbm_lsys_steps_done(const cbm_lsys *ls)
{
    return ls->steps;
}
bool cbm_lsys_stopped(const cbm_lsys *ls)
{
    return ls->ev.stopped;
}
size_t cbm_lsys_module_count(const cbm_lsys *ls)
{
    return ls->cur.n;
}
size_t cbm_lsys_param_count(const cbm_lsys *ls)
{
    return ls->cur.npar;
}
static bool cpfg_has_interpretation(const cbm_lsys *ls)
{
    return ls->homo.present;
}

/* The step protocol of the cpfg dialect (the L+C one is in lpfg.c). */
const cbm__dialect cbm__cpfg_dialect = {.reset = cpfg_reset,
                                        .step = cpfg_step,
                                        .interpret = cpfg_interpretation,
                                        .has_interpretation = cpfg_has_interpretation,
                                        .write_str = cbm__cpfg_write_str,
                                        .describe = cbm__cpfg_describe,
                                        .func_names = cbm__cpfg_func_names,
                                        .set_func_ids = cbm__cpfg_set_func_ids};

/* The entry points: the dialect's step protocol (lsys_internal.h). */
cbm_status cbm_lsys_reset(cbm_lsys *ls)
{
    memset(&ls->mech_time, 0, sizeof ls->mech_time);
    return ls->dialect->reset(ls);
}

cbm_status cbm_lsys_step(cbm_lsys *ls)
{
    return ls->dialect->step(ls);
}

cbm_status cbm_lsys_apply_homomorphism(cbm_lsys *ls)
{
    return ls->dialect->interpret(ls);
}

bool cbm_lsys_has_homomorphism(const cbm_lsys *ls)
{
    return ls->dialect->has_interpretation(ls);
}

size_t cbm_lsys_homomorphism_module_count(const cbm_lsys *ls)
{
    return ls->homo_valid ? ls->homo_str.n : 0;
}

void cbm_lsys_set_func(cbm_lsys *ls, cbm_lsys_func_fn fn, void *ud)
{
    ls->func = fn;
    ls->func_ud = ud;
    ls->ev.func = fn;
    ls->ev.func_ud = ud;
}

void cbm_lsys_cursor_begin(const cbm_lsys *ls, bool homomorphism, cbm_lsys_cursor *c)
{
    (void)ls;
    c->module = c->pmodule = c->param = 0;
    c->symbol = c->nparams = 0;
    c->params = NULL;
    c->homomorphism = homomorphism;
}

bool cbm_lsys_cursor_next(const cbm_lsys *ls, bool homomorphism, cbm_lsys_cursor *c)
{
    const lstr *s = homomorphism && ls->homo_valid ? &ls->homo_str : &ls->cur;
    if (c->module >= s->n)
        return false;
    uint8_t b = s->sym[c->module];
    c->symbol = b & 0x7f;
    c->nparams = 0;
    c->params = NULL;
    if (b & LSYS_PARAM_BIT) {
        c->nparams = s->pc[c->pmodule];
        if (s->f32) {
            cbm__params_load(s, c->param, c->buf, c->nparams);
            c->params = c->buf;
        } else {
            c->params = (const double *)s->par + c->param;
        }
        c->param += (size_t)c->nparams;
        c->pmodule++;
    }
    c->module++;
    return true;
}

void cbm_lsys_set_interpreter(cbm_lsys *ls, cbm_lsys_interpret_fn fn, void *ud)
{
    ls->interp = fn;
    ls->interp_ud = ud;
}

cbm_status cbm_lsys_cursor_set_param(cbm_lsys *ls, cbm_lsys_cursor *c, int i, double v)
{
    lstr *s = c->homomorphism ? &ls->homo_str : &ls->cur;
    if (i < 0 || i >= c->nparams || c->param < (size_t)c->nparams || c->param > s->npar ||
        (c->homomorphism && !ls->homo_valid))
        return CBM_E_INVALID;
    size_t k = c->param - (size_t)c->nparams + (size_t)i;
    if (s->f32) {
        ((float *)s->par)[k] = (float)v;
        c->buf[i] = (float)v;
    } else {
        ((double *)s->par)[k] = v;
    }
    if (!c->homomorphism)
        ls->homo_valid = false;
    return CBM_OK;
}

/* The values of the query modules of the image (the modules that follow a '?') go to the query
 * modules of the string, the k-th to the k-th, as many parameters as both have. */
static void return_queries(cbm_lsys *ls)
{
    const lstr *img = &ls->homo_str;
    lstr *str = &ls->cur;
    lpos a = {0, 0, 0}, b = {0, 0, 0};
    for (;;) {
        /* a '?' with parameters is a sub-L-system call, not a query */
        while (a.mod < img->n && !(a.mod > 0 && img->sym[a.mod - 1] == '?'))
            cbm__pos_next(img, &a);
        while (b.mod < str->n && !(b.mod > 0 && str->sym[b.mod - 1] == '?'))
            cbm__pos_next(str, &b);
        if (a.mod >= img->n || b.mod >= str->n)
            return;
        int na = cbm__module_params(img, &a), nb = cbm__module_params(str, &b);
        double v[LSYS_MAX_PARAMS];
        cbm__params_load(img, a.param, v, na < nb ? na : nb);
        for (int j = 0; j < na && j < nb; j++) {
            if (str->f32)
                ((float *)str->par)[b.param + (size_t)j] = (float)v[j];
            else
                ((double *)str->par)[b.param + (size_t)j] = v[j];
        }
        cbm__pos_next(img, &a);
        cbm__pos_next(str, &b);
    }
}

cbm_status cbm_lsys_interpret(cbm_lsys *ls)
{
    if (!ls->interp)
        return CBM_OK;
    CBM_TRY(cbm_lsys_apply_homomorphism(ls));
    CBM_TRY(ls->interp(ls->interp_ud, ls));
    return_queries(ls);
    return CBM_OK;
}
