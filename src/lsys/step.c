/* The parts of a derivation step both dialects share (lsys_internal.h): appending one string to
 * another, the bracket table that turns skipping a branch into a jump, and the walks of context
 * matching over branches. The walking and copying of single modules and the scan to a branch's
 * bracket are inline in lsys_internal.h, since a step calls them per module. */
#include "lsys/lsys_internal.h"

#include <stdint.h>

cbm_status cbm__lstr_append(cbm_context *ctx, lstr *dst, const lstr *src, bool reversed)
{
    if (!src->n)
        return CBM_OK;
    CBM_TRY(cbm__lstr_room(ctx, dst, src->n, src->npm, src->npar));
    size_t w = cbm__param_size(src);
    if (!reversed) {
        memcpy(dst->sym + dst->n, src->sym, src->n);
        if (src->npm)
            memcpy(dst->pc + dst->npm, src->pc, src->npm);
        if (src->npar)
            memcpy((char *)dst->par + dst->npar * w, src->par, src->npar * w);
        dst->n += src->n;
        dst->npm += src->npm;
        dst->npar += src->npar;
        return CBM_OK;
    }
    size_t j = src->npm, k = src->npar;
    for (size_t i = src->n; i-- > 0;) {
        uint8_t s = src->sym[i];
        dst->sym[dst->n++] = s;
        if (s & LSYS_PARAM_BIT) {
            uint8_t np = src->pc[--j];
            k -= np;
            dst->pc[dst->npm++] = np;
            memcpy((char *)dst->par + dst->npar * w, (const char *)src->par + k * w, np * w);
            dst->npar += np;
        }
    }
    return CBM_OK;
}

void cbm__brackets_start(cbm__brackets *t, const lstr *s, int dir, uint8_t open, uint8_t close)
{
    t->s = s;
    t->dir = dir;
    t->open = open;
    t->close = close;
    t->at = (lpos){0, 0, 0};
    t->opened.len = t->closed.len = t->waiting.len = 0;
}

/* Scans the string from t->at to its end; false when memory refuses (the table is dropped).
 * Read left to right an opening bracket waits for its closing one; in a string built reversed
 * the closing bracket comes first and waits for the opening one appended later. */
static bool extend(cbm_context *ctx, cbm__brackets *t)
{
    const lstr *s = t->s;
    lpos *p = &t->at;
    const lpos none = {SIZE_MAX, 0, 0};
    while (p->mod < s->n) {
        uint8_t c = s->sym[p->mod] & 0x7f;
        bool ok = true;
        if (c == t->open) {
            lpos match = none;
            if (t->dir < 0 && t->waiting.len)
                match = t->waiting.data[--t->waiting.len];
            ok = CBM_ARRAY_PUSH(ctx, t->opened, p->mod) == CBM_OK &&
                 CBM_ARRAY_PUSH(ctx, t->closed, match) == CBM_OK;
            if (ok && t->dir > 0) {
                lpos order = {t->opened.len - 1, 0, 0};
                ok = CBM_ARRAY_PUSH(ctx, t->waiting, order) == CBM_OK;
            }
        } else if (c == t->close) {
            if (t->dir < 0)
                ok = CBM_ARRAY_PUSH(ctx, t->waiting, *p) == CBM_OK;
            else if (t->waiting.len)
                t->closed.data[t->waiting.data[--t->waiting.len].mod] = *p;
        }
        if (!ok) {
            t->s = NULL;
            return false;
        }
        cbm__pos_next(s, p);
    }
    return true;
}

bool cbm__brackets_jump(cbm_context *ctx, cbm__brackets *t, const lstr *s, int dir, size_t at,
                        lpos *close)
{
    if (t->s != s || t->dir != dir || !extend(ctx, t))
        return false;
    size_t lo = 0, hi = t->opened.len;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (t->opened.data[mid] < at)
            lo = mid + 1;
        else
            hi = mid;
    }
    if (lo == t->opened.len || t->opened.data[lo] != at)
        return false;
    *close = t->closed.data[lo];
    return true;
}

void cbm__brackets_free(cbm_context *ctx, cbm__brackets *t)
{
    CBM_ARRAY_FREE(ctx, t->opened);
    CBM_ARRAY_FREE(ctx, t->closed);
    CBM_ARRAY_FREE(ctx, t->waiting);
    t->s = NULL;
}

bool cbm__walk_skip_branch(cbm_context *ctx, cbm__brackets *t, cbm__walk *w, int open, int close)
{
    lpos at;
    if (t && cbm__brackets_jump(ctx, t, w->s, w->dir, (size_t)w->mod, &at)) {
        if (at.mod == SIZE_MAX) { /* unmatched: the walk leaves the string */
            w->mod = -1;
            return false;
        }
        *w = cbm__walk_at(w->s, at.mod, at.pmod, at.param, w->dir);
        return true;
    }
    cbm__walk_forward(w);
    return cbm__walk_find_closing(w, open, close, true);
}

bool cbm__walk_to_branch_end(cbm_context *ctx, cbm__brackets *t, cbm__walk *w, int open, int close)
{
    while (cbm__walk_inside(w)) {
        int c = cbm__walk_symbol(w);
        if (c == close)
            return true;
        if (c == open && !cbm__walk_skip_branch(ctx, t, w, open, close))
            return false;
        if (!cbm__walk_forward(w))
            return false;
    }
    return false;
}
