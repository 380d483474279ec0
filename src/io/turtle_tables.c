/* Tables of a turtle's segments (plain L-system models: cpfg, L+C without mechanics): the
 * topology as the turtle draws it, as an OpenAlea MTG coding file and as a CSV table.
 *
 * Each segment of the turtle's record (a cylinder drawn by F or G, a generalized-cylinder piece)
 * is one row; degenerate segments the turtle drops are not in the record, so not here either.
 * A segment's parent is the last segment recorded before it on its branch path (the turtle's
 * bracket stack); it starts a lateral axis when a `[` was opened since that parent, otherwise it
 * continues the parent's axis (the mechanics' rule, docs/language.md). The MTG is written by the
 * mechanical plant's writer (cbm__write_mtg_table, plant_tables.c, FORM-A with scales P, A, S);
 * the order of a segment is its axis level there: the parent's, plus one for a lateral. */
#include "writers.h"

#include "cambium/io.h"

#include "../core/vecmath.h"

#include <math.h>
#include <stdio.h>

/* The segments of the record: prim index of each row, parent row, continuation, order. */
typedef struct seg_rows {
    const cbm_prim *prims;
    size_t n;
    size_t *prim;
    int64_t *parent;
    uint8_t *cont;
    int *order;
} seg_rows;

static void rows_free(cbm_context *ctx, seg_rows *r)
{
    size_t k = r->n ? r->n : 1;
    cbm__free(ctx, r->prim, k * sizeof *r->prim);
    cbm__free(ctx, r->parent, k * sizeof *r->parent);
    cbm__free(ctx, r->cont, k);
    cbm__free(ctx, r->order, k * sizeof *r->order);
}

static bool is_segment(const cbm_prim *p)
{
    return p->kind == CBM_PRIM_CYLINDER || p->kind == CBM_PRIM_GCYL;
}

static cbm_status rows_build(cbm_context *ctx, const cbm_turtle *t, seg_rows *r)
{
    memset(r, 0, sizeof *r);
    size_t np = cbm_turtle_prim_count(t);
    const cbm_prim *pr = cbm_turtle_prims(t);
    r->prims = pr;
    for (size_t i = 0; i < np; i++)
        r->n += is_segment(&pr[i]);
    size_t k = r->n ? r->n : 1;
    int64_t *row_of = cbm__alloc(ctx, (np ? np : 1) * sizeof *row_of);
    r->prim = cbm__alloc(ctx, k * sizeof *r->prim);
    r->parent = cbm__alloc(ctx, k * sizeof *r->parent);
    r->cont = cbm__calloc(ctx, k, 1);
    r->order = cbm__calloc(ctx, k, sizeof *r->order);
    cbm_status st = CBM_OK;
    if (!row_of || !r->prim || !r->parent || !r->cont || !r->order)
        st = CBM_E_NOMEM;
    size_t n = 0;
    for (size_t i = 0; i < np && st == CBM_OK; i++) {
        row_of[i] = -1;
        if (!is_segment(&pr[i]))
            continue;
        int64_t pa = pr[i].parent;
        int64_t prow = pa >= 0 && (size_t)pa < i ? row_of[pa] : -1;
        r->prim[n] = i;
        r->parent[n] = prow;
        r->cont[n] = prow >= 0 && !pr[i].lateral;
        r->order[n] = prow < 0 ? 0 : r->order[prow] + (r->cont[n] ? 0 : 1);
        row_of[i] = (int64_t)n++;
    }
    cbm__free(ctx, row_of, (np ? np : 1) * sizeof *row_of);
    if (st != CBM_OK)
        rows_free(ctx, r);
    return st;
}

static const char *const features[] = {"id", "order", "module", "color",  "x0",     "y0",    "z0",
                                       "x1", "y1",    "z1",     "width0", "width1", "length"};

enum { NFEAT = sizeof features / sizeof features[0] };

static void row_values(const seg_rows *r, size_t i, double *v)
{
    const cbm_prim *p = &r->prims[r->prim[i]];
    const double x[NFEAT] = {(double)i,
                             (double)r->order[i],
                             (double)p->module,
                             (double)p->color,
                             p->p0.x,
                             p->p0.y,
                             p->p0.z,
                             p->p1.x,
                             p->p1.y,
                             p->p1.z,
                             2.0 * p->r0,
                             2.0 * p->r1,
                             v3_norm(v3_sub(p->p1, p->p0))};
    memcpy(v, x, sizeof x);
}

static cbm_status mtg_row(const void *user, size_t i, double *v)
{
    row_values(user, i, v);
    return CBM_OK;
}

cbm_status cbm_write_turtle_mtg(cbm_context *ctx, const cbm_turtle *t, const char *path)
{
    if (!ctx || !t || !path)
        return CBM_E_INVALID;
    seg_rows r;
    CBM_TRY(rows_build(ctx, t, &r));
    cbm__mtg_table tab = {.comment = "cambium turtle: the model's units, y up; segments (S) as "
                                     "the turtle draws them, in axes (A) of plants (P)",
                          .rows = r.n,
                          .parent = r.parent,
                          .continuation = r.cont,
                          .features = features,
                          .nfeatures = NFEAT,
                          .nint = 4,
                          .row = mtg_row,
                          .user = &r};
    cbm_status st = cbm__write_mtg_table(ctx, &tab, path);
    rows_free(ctx, &r);
    return st;
}

cbm_status cbm_write_turtle_segments_csv(cbm_context *ctx, const cbm_turtle *t, const char *path)
{
    if (!ctx || !t || !path)
        return CBM_E_INVALID;
    seg_rows r;
    CBM_TRY(rows_build(ctx, t, &r));
    cbm_out *out = NULL;
    cbm_status st = cbm_out_open(ctx, path, &out);
    if (st == CBM_OK) {
        FILE *f = cbm_out_stream(out);
        fputs("id,parent,lateral,order,module,color,x0,y0,z0,x1,y1,z1,width0,width1,length\n", f);
        for (size_t i = 0; i < r.n; i++) {
            double v[NFEAT];
            row_values(&r, i, v);
            fprintf(f, "%zu,%lld,%d,%d,%lld,%d", i, (long long)r.parent[i],
                    r.parent[i] >= 0 && !r.cont[i], r.order[i], (long long)v[2], (int)v[3]);
            for (size_t k = 4; k < NFEAT; k++) {
                fputc(',', f);
                if (isfinite(v[k]))
                    fprintf(f, "%.9g", v[k]);
            }
            fputc('\n', f);
        }
        st = cbm_out_commit(out);
    }
    rows_free(ctx, &r);
    return st;
}
