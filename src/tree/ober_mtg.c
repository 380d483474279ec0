/* The stand of Oberlaender's parametric tree as one OpenAlea MTG coding file (issue 13, item 5):
 * one plant P<n> (scale 1) per tree, n = the tree's index + 1, its annual shoots as the segments S
 * (scale 3) grouped in axes A (scale 2). The shared FORM-A writer (cbm__write_mtg_table,
 * src/io/plant_tables.c) does the coding; this file orders the rows tree by tree (a stand's shoots
 * are interleaved between trees, parents always before children, which stays true within a tree)
 * and says which shoot continues its mother's axis: the apical continuation, and of the two arms of
 * a fork (apicalSplitLambda) the first, since an MTG segment has at most one successor ('<'); the
 * second arm starts a new axis ('+'). Trees not germinated, or dead, have no shoots and no plant,
 * so plant numbers can skip. */
#include "io/writers.h"
#include "tree/ober_internal.h"

#include <math.h>

static const char *const features[] = {
    "id",          "tree",        "order",         "trend",    "age",     "nodes", "leaves", "buds",
    "active_buds", "short_shoot", "proventitious", "x0",       "y0",      "z0",    "x1",     "y1",
    "z1",          "length",      "radius",        "position", "tropism", "carbon"};
enum { NINT = 11 };

typedef struct mtg_rows {
    const cbm_ober_stand *s;
    const size_t *shoot; /* row -> shoot index in the stand */
} mtg_rows;

static cbm_status shoot_row(const void *user, size_t i, double *v)
{
    const mtg_rows *m = user;
    cbm_ober_shoot o;
    CBM_TRY(cbm_ober_shoot_info(m->s, m->shoot[i], &o));
    const double r[] = {(double)m->shoot[i],
                        (double)o.tree,
                        o.order,
                        o.trend,
                        o.age,
                        o.nodes,
                        o.leaves,
                        o.buds,
                        o.active_buds,
                        o.short_shoot,
                        o.proventitious,
                        o.base.x,
                        o.base.y,
                        o.base.z,
                        o.tip.x,
                        o.tip.y,
                        o.tip.z,
                        o.length,
                        o.radius,
                        o.position,
                        o.tropism,
                        o.carbon};
    memcpy(v, r, sizeof r);
    return CBM_OK;
}

cbm_status cbm_ober_write_mtg(cbm_context *ctx, const cbm_ober_stand *s, const char *path)
{
    if (!ctx || !s || !path)
        return CBM_E_INVALID;
    size_t n = s->shoots.len, nt = s->trees.len, m = n ? n : 1;
    size_t *shoot = cbm__alloc(ctx, m * sizeof *shoot);
    int64_t *rowof = cbm__alloc(ctx, m * sizeof *rowof);
    int64_t *parent = cbm__alloc(ctx, m * sizeof *parent);
    int64_t *plant = cbm__alloc(ctx, m * sizeof *plant);
    uint8_t *cont = cbm__calloc(ctx, m, 1);
    uint8_t *taken = cbm__calloc(ctx, m, 1); /* per shoot: its axis is continued already */
    cbm_status st = CBM_OK;
    if (!shoot || !rowof || !parent || !plant || !cont || !taken) {
        st = CBM_E_NOMEM;
        goto done;
    }
    /* rows tree by tree, each tree's shoots in stand order (parents first) */
    size_t k = 0;
    for (size_t t = 0; t < nt; t++)
        for (size_t i = 0; i < n; i++)
            if (s->shoots.data[i].tree == (int32_t)t) {
                const ober_shoot *h = &s->shoots.data[i];
                shoot[k] = i;
                rowof[i] = (int64_t)k;
                parent[k] = h->parent >= 0 ? rowof[h->parent] : -1;
                plant[k] = (int64_t)t + 1;
                if (h->parent >= 0 && !h->lateral && !taken[h->parent]) {
                    cont[k] = 1;
                    taken[h->parent] = 1;
                }
                k++;
            }
    CBM_ASSERT(k == n);
    mtg_rows user = {s, shoot};
    cbm__mtg_table tab = {.comment = "cambium Oberlaender stand: one plant (P) per tree, annual "
                                     "shoots (S) in axes (A); metres, y up",
                          .rows = n,
                          .parent = parent,
                          .continuation = cont,
                          .features = features,
                          .nfeatures = sizeof features / sizeof features[0],
                          .nint = NINT,
                          .row = shoot_row,
                          .user = &user,
                          .plant = plant};
    st = cbm__write_mtg_table(ctx, &tab, path);
done:
    cbm__free(ctx, shoot, m * sizeof *shoot);
    cbm__free(ctx, rowof, m * sizeof *rowof);
    cbm__free(ctx, parent, m * sizeof *parent);
    cbm__free(ctx, plant, m * sizeof *plant);
    cbm__free(ctx, cont, m);
    cbm__free(ctx, taken, m);
    return st;
}
