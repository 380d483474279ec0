/* Loading and releasing an L-system model: preprocess, parse, then index the productions by
 * the first symbol of their predecessor (declaration order kept within a symbol, which is the
 * order cpfg tries them in), list the L-systems of the file (the main one and its
 * sub-L-systems, lsys_internal.h) and allocate the run state (globals, parameter frame). Also
 * what the package header lsys/lsys.h gives the model (src/lsys_model) of a loaded L-system. */
#include "lang/lc.h"
#include "cambium/mech.h"
#include "lsys/lsys_internal.h"

#include <stdlib.h>

cbm_lsys_def cbm_lsys_def_default(void)
{
    cbm_lsys_def d;
    memset(&d, 0, sizeof d);
    d.seed = -1;
    d.solver = -1;
    return d;
}

static cbm_status index_set(cbm_lsys *ls, prodset *set)
{
    size_t n = set->prods.len;
    set->order = cbm__calloc(ls->ctx, n ? n : 1, sizeof(int32_t));
    if (!set->order)
        return CBM_E_NOMEM;
    int32_t counts[129] = {0};
    for (size_t i = 0; i < n; i++)
        counts[ls->fmods.data[set->prods.data[i].pred].sym + 1]++;
    set->start[0] = 0;
    for (int s = 1; s <= 128; s++)
        set->start[s] = set->start[s - 1] + counts[s];
    int32_t fill[128];
    memcpy(fill, set->start, sizeof fill);
    for (size_t i = 0; i < n; i++)
        set->order[fill[ls->fmods.data[set->prods.data[i].pred].sym]++] = (int32_t)i;
    return CBM_OK;
}

static void free_sets(cbm_context *ctx, prodset *m, prodset *d, prodset *h)
{
    prodset *sets[3] = {m, d, h};
    for (int i = 0; i < 3; i++) {
        size_t n = sets[i]->prods.len;
        if (sets[i]->order)
            cbm__free(ctx, sets[i]->order, (n ? n : 1) * sizeof(int32_t));
        CBM_ARRAY_FREE(ctx, sets[i]->prods);
    }
}

int cbm__lsys_find(const cbm_lsys *ls, int id)
{
    for (int i = 0; i < ls->nsys; i++)
        if (ls->sys[i].id == id)
            return i;
    return -1;
}

/* The view of every L-system (ls->sys), the deepest recursion, the homomorphism streams. */
static cbm_status list_lsystems(cbm_lsys *ls)
{
    int n = 1 + (int)ls->subs.len;
    ls->sys = cbm__calloc(ls->ctx, (size_t)n, sizeof *ls->sys);
    if (!ls->sys)
        return CBM_E_NOMEM;
    ls->nsys = n;
    ls->hran = cbm__calloc(ls->ctx, (size_t)n, sizeof *ls->hran);
    if (!ls->hran)
        return CBM_E_NOMEM;
    ls->sys[0] = (lsysv){ls->id,
                         &ls->main,
                         &ls->decomp,
                         &ls->homo,
                         ls->ignore,
                         ls->stochastic,
                         {ls->start_block, ls->start_each, ls->end_each, ls->end_block}};
    for (int i = 1; i < n; i++) {
        const sublsys *b = &ls->subs.data[i - 1];
        ls->sys[i] = (lsysv){b->id,
                             &b->main,
                             &b->decomp,
                             &b->homo,
                             b->ignore,
                             b->stochastic,
                             {b->start_block, b->start_each, b->end_each, b->end_block}};
    }
    ls->max_depth = 0;
    for (int i = 0; i < n; i++) {
        if (ls->sys[i].decomp->depth > ls->max_depth)
            ls->max_depth = ls->sys[i].decomp->depth;
        if (ls->sys[i].homo->depth > ls->max_depth)
            ls->max_depth = ls->sys[i].homo->depth;
    }
    ls->ign = ls->ignore;
    return CBM_OK;
}

void cbm_lsys_destroy(cbm_lsys *ls)
{
    if (!ls)
        return;
    cbm_context *ctx = ls->ctx;
    free_sets(ctx, &ls->main, &ls->decomp, &ls->homo);
    for (size_t i = 0; i < ls->subs.len; i++)
        free_sets(ctx, &ls->subs.data[i].main, &ls->subs.data[i].decomp, &ls->subs.data[i].homo);
    CBM_ARRAY_FREE(ctx, ls->subs);
    cbm__free(ctx, ls->sys, (size_t)ls->nsys * sizeof *ls->sys);
    if (ls->hran)
        cbm__free(ctx, ls->hran, (size_t)ls->nsys * sizeof *ls->hran);
    CBM_ARRAY_FREE(ctx, ls->lstack);
    CBM_ARRAY_FREE(ctx, ls->fmods);
    CBM_ARRAY_FREE(ctx, ls->smods);
    CBM_ARRAY_FREE(ctx, ls->const_bytes);
    cbm__free(ctx, ls->globals, ls->nglobals * sizeof(double));
    cbm__free(ctx, ls->frame, (size_t)(ls->max_formals + 1) * sizeof(double));
    cbm__free(ctx, ls->array_init, ls->array_init_len * sizeof(double));
    cbm__lstr_free(ctx, &ls->cur);
    cbm__lstr_free(ctx, &ls->next);
    cbm__lstr_free(ctx, &ls->homo_str);
    cbm__lstr_free(ctx, &ls->succ);
    for (size_t i = 0; i < ls->scratch.len; i++)
        cbm__lstr_free(ctx, &ls->scratch.data[i]);
    CBM_ARRAY_FREE(ctx, ls->scratch);
    cbm__lpfg_free(ls);
    cbm__brackets_free(ctx, &ls->brackets[0]);
    cbm__brackets_free(ctx, &ls->brackets[1]);
    CBM_ARRAY_FREE(ctx, ls->appl);
    CBM_ARRAY_FREE(ctx, ls->applp);
    cbm__eval_free(&ls->ev);
    cbm__compiler_free(&ls->comp);
    cbm__free(ctx, ls, sizeof *ls);
}

cbm_status cbm_lsys_load(cbm_context *ctx, const cbm_lsys_def *def, cbm_lsys **out)
{
    if (!ctx || !def || !out || (!def->path && !def->text))
        return CBM_E_INVALID;
    *out = NULL;
    if (def->solver < -1 || def->solver >= CBM_MECH_SOLVER_COUNT)
        return cbm__fail(ctx, CBM_E_INVALID, "solver %d: -1 (the model's) or 0 .. %d", def->solver,
                         CBM_MECH_SOLVER_COUNT - 1);
    cbm__pp pp;
    CBM_TRY(cbm__pp_run(ctx, def->path, def->text, def->defines, def->define_count, &pp));
    if (pp.errors) {
        size_t n = pp.errors;
        cbm__pp_free(&pp);
        return cbm__fail(ctx, CBM_E_SYNTAX, "%zu preprocessor error%s", n, n == 1 ? "" : "s");
    }
    cbm_lsys *ls = cbm__calloc(ctx, 1, sizeof *ls);
    if (!ls) {
        cbm__pp_free(&pp);
        return CBM_E_NOMEM;
    }
    ls->ctx = ctx;
    ls->float32 = def->float32;
    ls->ignore_seed = def->ignore_seed;
    ls->cur.f32 = ls->next.f32 = ls->homo_str.f32 = ls->succ.f32 = def->float32;
    ls->seed_override = def->seed;
    ls->solver_override = def->solver;
    ls->loop_budget = def->max_loop_iterations; /* 0: the context's limit */
    ls->start_block = ls->end_block = ls->start_each = ls->end_each = -1;
    ls->dlength_expr = ls->seed_expr = -1;
    ls->main.seed_expr = ls->decomp.seed_expr = ls->homo.seed_expr = -1;
    cbm_status s = cbm__compiler_init(&ls->comp, ctx, &pp);
    bool lc = s == CBM_OK && cbm__lc_detect(&pp);
    ls->dialect = lc ? &cbm__lpfg_dialect : &cbm__cpfg_dialect;
    if (s == CBM_OK)
        s = lc ? cbm__lpfg_parse(ls, &pp) : cbm__lsys_parse(ls, &pp);
    cbm__pp_free(&pp);
    ls->comp.pp = NULL;
    ls->comp.text = NULL;
    if (s == CBM_OK)
        s = index_set(ls, &ls->main);
    if (s == CBM_OK)
        s = index_set(ls, &ls->decomp);
    if (s == CBM_OK)
        s = index_set(ls, &ls->homo);
    for (size_t i = 0; s == CBM_OK && i < ls->subs.len; i++) {
        s = index_set(ls, &ls->subs.data[i].main);
        if (s == CBM_OK)
            s = index_set(ls, &ls->subs.data[i].decomp);
        if (s == CBM_OK)
            s = index_set(ls, &ls->subs.data[i].homo);
    }
    if (s == CBM_OK)
        s = list_lsystems(ls);
    if (s == CBM_OK) {
        ls->q_slot = (int32_t)ls->comp.globals.len;
        for (size_t i = 0; i < ls->comp.globals.len; i++)
            if (!strcmp(ls->comp.globals.data[i], "Q"))
                ls->q_slot = (int32_t)i;
        ls->nglobals = ls->comp.globals.len + 1;
        ls->globals = cbm__calloc(ctx, ls->nglobals, sizeof(double));
        ls->frame = cbm__calloc(ctx, (size_t)ls->max_formals + 1, sizeof(double));
        for (size_t i = 0; i < ls->comp.arrays.len; i++)
            ls->array_init_len += ls->comp.arrays.data[i].count;
        ls->array_init =
            cbm__calloc(ctx, ls->array_init_len ? ls->array_init_len : 1, sizeof(double));
        if (!ls->array_init_len && ls->array_init) {
            cbm__free(ctx, ls->array_init, sizeof(double));
            ls->array_init = NULL;
        }
        if (!ls->globals || !ls->frame || (ls->array_init_len && !ls->array_init))
            s = CBM_E_NOMEM;
    }
    if (s != CBM_OK) {
        cbm_lsys_destroy(ls);
        return s;
    }
    size_t off = 0;
    for (size_t i = 0; i < ls->comp.arrays.len; i++) {
        cbm__array *a = &ls->comp.arrays.data[i];
        if (a->count == 0) /* array_init may be NULL (nothing to hold) */
            continue;
        /* count > 0 here, so array_init (checked above) is set */
        // NOLINTNEXTLINE(clang-analyzer-core.NonNullParamChecker)
        memcpy(ls->array_init + off, a->data, a->count * sizeof(double));
        off += a->count;
    }
    ls->ev.ctx = ctx;
    ls->ev.nodes = ls->comp.nodes.data;
    ls->ev.strings = ls->comp.strings.data;
    ls->ev.globals = ls->globals;
    ls->ev.arrays = ls->comp.arrays.data;
    ls->ev.params = ls->frame;
    ls->ev.error_node = -1;
    ls->cur_gen = 1;
    *out = ls;
    return CBM_OK;
}

bool cbm__lsys_may_query(const cbm_lsys *ls)
{
    for (size_t i = 0; i < ls->smods.len; i++)
        if ((ls->smods.data[i].sym & 0x7f) == '?')
            return true;
    return false;
}

const uint8_t *cbm__lsys_symbols(const cbm_lsys *ls, size_t *n)
{
    *n = ls->cur.n;
    return ls->cur.sym;
}

/* The cpfg dialect's rules: those of every L-system of the file. */
void cbm__cpfg_describe(const cbm_lsys *ls, cbm_model_summary *out)
{
    out->productions = ls->main.prods.len;
    out->decompositions = ls->decomp.prods.len;
    out->homomorphisms = ls->homo.prods.len;
    out->decomposition_depth = ls->decomp.present ? ls->decomp.depth : 0;
    out->homomorphism_depth = ls->homo.present ? ls->homo.depth : 0;
    for (size_t i = 0; i < ls->subs.len; i++) {
        const sublsys *sub = &ls->subs.data[i];
        out->productions += sub->main.prods.len;
        out->decompositions += sub->decomp.prods.len;
        out->homomorphisms += sub->homo.prods.len;
        out->stochastic |= sub->stochastic;
        if (sub->decomp.present && sub->decomp.depth > out->decomposition_depth)
            out->decomposition_depth = sub->decomp.depth;
        if (sub->homo.present && sub->homo.depth > out->homomorphism_depth)
            out->homomorphism_depth = sub->homo.depth;
    }
}

void cbm__lsys_describe(const cbm_lsys *ls, cbm_model_summary *out)
{
    out->derivation_length = ls->derivation_length;
    out->stochastic = ls->stochastic;
    out->has_start_end =
        ls->start_block >= 0 || ls->end_block >= 0 || ls->start_each >= 0 || ls->end_each >= 0;
    out->lsystems = 1 + (int)ls->subs.len;
    ls->dialect->describe(ls, out);
}
