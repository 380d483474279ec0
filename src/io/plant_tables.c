/* Tables of the mechanical plant: the per-segment CSV and the OpenAlea MTG coding file.
 *
 * MTG (openalea/mtg, doc/user/syntax.rst, FORM-A): three scales, plant P (1), axis A (2) and
 * segment S (3). The code is written depth-first with one TOPO column per axis level: a
 * segment's line, then the lateral axes it bears ("+A<n>/S1" one column to the right, relative
 * to the latest code of the column to the left), then its continuation ("^<S<k>" in the same
 * column, relative to the latest code above in that column). Each segment line carries the
 * features in the columns after the TOPO columns; unknown values are empty cells, and numbers have
 * no '+' (1e10: openalea.mtg's reader would take it for a branch). The traversal
 * uses an explicit stack (no recursion, any depth). One writer (cbm__write_mtg_table) takes a
 * generic table of parent / continuation / feature rows: the mechanical plant's here, the turtle's
 * segments in turtle_tables.c. */
#include "writers.h"

#include "cambium/io.h"

#include <math.h>
#include <stdio.h>

static void cell(FILE *f, double x)
{
    if (isfinite(x))
        fprintf(f, "%.9g", x);
}

static double outer_modulus(const cbm_plant *p, size_t i, size_t rings)
{
    cbm_ring r;
    if (rings == 0 || cbm_plant_get_ring(p, i, rings - 1, &r) != CBM_OK)
        return NAN;
    return r.youngs_modulus;
}

cbm_status cbm_write_segments_csv(cbm_context *ctx, const cbm_plant *p, const char *path)
{
    if (!ctx || !p || !path)
        return CBM_E_INVALID;
    cbm_out *out;
    CBM_TRY(cbm_out_open(ctx, path, &out));
    FILE *f = cbm_out_stream(out);
    fputs("id,parent,order,x0_m,y0_m,z0_m,x1_m,y1_m,z1_m,a_m,b_m,length_m,E_Pa,EI_L_Nm2,"
          "EI_U_Nm2,carried_mass_kg,M_H_Nm,M_L_Nm,M_U_Nm,bending_moment_Nm,stress_Pa,"
          "stress_ratio,omega_H_per_m,omega_L_per_m,omega_U_per_m,rest_omega_H_per_m,"
          "rest_omega_L_per_m,rest_omega_U_per_m,age_years,reaction_wood\n",
          f);
    size_t n = cbm_plant_segment_count(p);
    cbm_status st = CBM_OK;
    for (size_t i = 0; i < n && st == CBM_OK; i++) {
        cbm_segment_state s;
        if ((st = cbm_plant_segment(p, i, &s)) != CBM_OK)
            break;
        fprintf(f, "%zu,%lld,%d", i, (long long)s.parent, (int)s.order);
        const double v[] = {s.proximal.x,
                            s.proximal.y,
                            s.proximal.z,
                            s.distal.x,
                            s.distal.y,
                            s.distal.z,
                            s.a,
                            s.b,
                            s.length,
                            outer_modulus(p, i, s.ring_count),
                            s.rigidity.y,
                            s.rigidity.z,
                            s.carried_mass,
                            s.moment_local.x,
                            s.moment_local.y,
                            s.moment_local.z,
                            hypot(s.moment_local.y, s.moment_local.z),
                            s.stress,
                            s.stress_ratio,
                            s.omega.x,
                            s.omega.y,
                            s.omega.z,
                            s.rest_rate.x,
                            s.rest_rate.y,
                            s.rest_rate.z,
                            s.age,
                            s.reaction};
        for (size_t k = 0; k < sizeof v / sizeof v[0]; k++) {
            fputc(',', f);
            cell(f, v[k]);
        }
        fputc('\n', f);
    }
    if (st != CBM_OK) {
        cbm_out_abort(out);
        return st;
    }
    return cbm_out_commit(out);
}

/* ---- MTG ---- */

typedef struct mtg_item {
    size_t seg;
    int col;       /* TOPO column = axis level */
    int in_axis;   /* index of the segment in its axis, 1-based */
    bool new_axis; /* first segment of a lateral axis */
} mtg_item;

enum { MTG_MAX_FEATURES = 32 };

/* A REAL cell of the MTG: %.9g without the '+' of a positive exponent (1e10, not 1e+10), since
 * openalea.mtg's reader joins the features into the code and reads a '+' there as a branch. */
static void mtg_cell(FILE *f, double x)
{
    if (!isfinite(x))
        return;
    char b[40];
    int n = snprintf(b, sizeof b, "%.9g", x);
    for (int k = 0; k < n && k < (int)sizeof b; k++)
        if (b[k] != '+')
            fputc(b[k], f);
}

static cbm_status mtg_row(FILE *f, const cbm__mtg_table *t, size_t i, double *v)
{
    CBM_TRY(t->row(t->user, i, v));
    for (size_t k = 0; k < t->nfeatures; k++) {
        if (k)
            fputc('\t', f);
        if (k < t->nint && isfinite(v[k]))
            fprintf(f, "%lld", (long long)v[k]);
        else if (k >= t->nint)
            mtg_cell(f, v[k]);
    }
    fputc('\n', f);
    return CBM_OK;
}

cbm_status cbm__write_mtg_table(cbm_context *ctx, const cbm__mtg_table *t, const char *path)
{
    if (!ctx || !t || !path || (t->rows && (!t->parent || !t->continuation)) || !t->row ||
        t->nfeatures > MTG_MAX_FEATURES || t->nint > t->nfeatures)
        return CBM_E_INVALID;
    size_t n = t->rows;
    const int64_t *par = t->parent;
    const uint8_t *cont = t->continuation;
    for (size_t i = 0; i < n; i++)
        if (par[i] >= (int64_t)i)
            return cbm__fail(ctx, CBM_E_INVALID, "mtg: row %zu has parent %lld (parents first)", i,
                             (long long)par[i]);
    /* children in CSR form, in index order */
    size_t *first = cbm__calloc(ctx, n + 2, sizeof *first);
    size_t *kids = cbm__alloc(ctx, (n ? n : 1) * sizeof *kids);
    int *level = cbm__calloc(ctx, n ? n : 1, sizeof *level);
    CBM_ARRAY(mtg_item) stack = {0};
    cbm_out *out = NULL;
    cbm_status st = CBM_OK;
    double v[MTG_MAX_FEATURES];
    if (!first || !kids || !level) {
        st = CBM_E_NOMEM;
        goto done;
    }
    for (size_t i = 0; i < n; i++)
        if (par[i] >= 0)
            first[par[i] + 2]++;
    for (size_t i = 0; i < n; i++)
        first[i + 2] += first[i + 1];
    for (size_t i = 0; i < n; i++) {
        if (par[i] >= 0)
            kids[first[par[i] + 1]++] = i;
        /* axis level: the parent's, plus one for a lateral (parents come first) */
        level[i] = par[i] < 0 ? 0 : level[par[i]] + (cont[i] ? 0 : 1);
    }
    int ncols = 1;
    for (size_t i = 0; i < n; i++)
        ncols = level[i] + 1 > ncols ? level[i] + 1 : ncols;
    if ((st = cbm_out_open(ctx, path, &out)) != CBM_OK)
        goto done;
    FILE *f = cbm_out_stream(out);
    fprintf(f, "# %s\n", t->comment);
    fputs("CODE:\tFORM-A\n"
          "CLASSES:\n"
          "SYMBOL\tSCALE\tDECOMPOSITION\tINDEXATION\tDEFINITION\n"
          "$\t0\tFREE\tFREE\tIMPLICIT\n"
          "P\t1\tCONNECTED\tFREE\tIMPLICIT\n"
          "A\t2\t<-LINEAR\tFREE\tIMPLICIT\n"
          "S\t3\tNONE\tFREE\tEXPLICIT\n"
          "DESCRIPTION:\n"
          "LEFT\tRIGHT\tRELTYPE\tMAX\n"
          "A\tA\t+\t?\n"
          "S\tS\t<\t1\n"
          "S\tS\t+\t?\n"
          "FEATURES:\n"
          "NAME\tTYPE\n",
          f);
    for (size_t k = 0; k < t->nfeatures; k++)
        fprintf(f, "%s\t%s\n", t->features[k], k < t->nint ? "INT" : "REAL");
    fputs("MTG:\nTOPO", f);
    for (int c = 0; c < ncols; c++)
        fputc('\t', f);
    for (size_t k = 0; k < t->nfeatures; k++)
        fprintf(f, "%s%s", t->features[k], k + 1 < t->nfeatures ? "\t" : "");
    fputc('\n', f);
    int plant_no = 0, axis_no = 0;
    for (size_t r = 0; r < n && st == CBM_OK; r++) {
        if (par[r] >= 0)
            continue;
        mtg_item root = {r, 0, 1, false};
        if ((st = CBM_ARRAY_PUSH(ctx, stack, root)) != CBM_OK)
            break;
        plant_no++;
        axis_no = 1;
        bool first_line = true;
        while (stack.len && st == CBM_OK) {
            mtg_item it = stack.data[--stack.len];
            for (int c = 0; c < it.col; c++)
                fputc('\t', f);
            if (first_line)
                fprintf(f, "/P%lld/A1/S1", t->plant ? (long long)t->plant[r] : (long long)plant_no);
            else if (it.new_axis)
                fprintf(f, "+A%d/S1", ++axis_no);
            else
                fprintf(f, "^<S%d", it.in_axis);
            first_line = false;
            for (int c = it.col; c < ncols; c++)
                fputc('\t', f);
            if ((st = mtg_row(f, t, it.seg, v)) != CBM_OK)
                break;
            /* continuation last (pushed first), laterals before it in index order */
            for (size_t k = first[it.seg]; k < first[it.seg + 1] && st == CBM_OK; k++) {
                size_t c = kids[k];
                if (cont[c]) {
                    mtg_item ci = {c, it.col, it.in_axis + 1, false};
                    st = CBM_ARRAY_PUSH(ctx, stack, ci);
                }
            }
            for (size_t k = first[it.seg + 1]; k > first[it.seg] && st == CBM_OK; k--) {
                size_t c = kids[k - 1];
                if (!cont[c]) {
                    mtg_item li = {c, it.col + 1, 1, true};
                    st = CBM_ARRAY_PUSH(ctx, stack, li);
                }
            }
        }
    }
    if (st == CBM_OK) {
        st = cbm_out_commit(out);
        out = NULL;
    }
done:
    cbm_out_abort(out);
    CBM_ARRAY_FREE(ctx, stack);
    cbm__free(ctx, first, (n + 2) * sizeof *first);
    cbm__free(ctx, kids, (n ? n : 1) * sizeof *kids);
    cbm__free(ctx, level, (n ? n : 1) * sizeof *level);
    return st;
}

static const char *const mtg_features[] = {
    "id",      "order",   "x0",      "y0",  "z0",           "x1",     "y1",     "z1",
    "a",       "b",       "length",  "E",   "mass",         "moment", "stress", "stress_ratio",
    "omega_H", "omega_L", "omega_U", "age", "reaction_wood"};

static cbm_status plant_mtg_row(const void *user, size_t i, double *v)
{
    const cbm_plant *p = user;
    cbm_segment_state s;
    CBM_TRY(cbm_plant_segment(p, i, &s));
    const double r[] = {(double)i,
                        (double)s.order,
                        s.proximal.x,
                        s.proximal.y,
                        s.proximal.z,
                        s.distal.x,
                        s.distal.y,
                        s.distal.z,
                        s.a,
                        s.b,
                        s.length,
                        outer_modulus(p, i, s.ring_count),
                        s.carried_mass,
                        hypot(s.moment_local.y, s.moment_local.z),
                        s.stress,
                        s.stress_ratio,
                        s.omega.x,
                        s.omega.y,
                        s.omega.z,
                        s.age,
                        s.reaction};
    memcpy(v, r, sizeof r);
    return CBM_OK;
}

cbm_status cbm_write_mtg(cbm_context *ctx, const cbm_plant *p, const char *path)
{
    if (!ctx || !p || !path)
        return CBM_E_INVALID;
    size_t n = cbm_plant_segment_count(p);
    uint8_t *cont = cbm__calloc(ctx, n ? n : 1, 1);
    if (!cont)
        return CBM_E_NOMEM;
    cbm_status st = CBM_OK;
    for (size_t i = 0; i < n && st == CBM_OK; i++) {
        cbm_segment_state s;
        if ((st = cbm_plant_segment(p, i, &s)) == CBM_OK)
            cont[i] = s.continuation;
    }
    cbm__mtg_table t = {.comment = "cambium plant: metres, y up; segments (S) grouped in axes (A) "
                                   "of plants (P)",
                        .rows = n,
                        .parent = cbm_plant_parents(p),
                        .continuation = cont,
                        .features = mtg_features,
                        .nfeatures = sizeof mtg_features / sizeof mtg_features[0],
                        .nint = 2,
                        .row = plant_mtg_row,
                        .user = p};
    if (st == CBM_OK)
        st = cbm__write_mtg_table(ctx, &t, path);
    cbm__free(ctx, cont, n ? n : 1);
    return st;
}

cbm_status cbm_write_plant(cbm_context *ctx, const cbm_plant *p, const char *path,
                           const cbm_write_options *opts, int sides)
{
    if (!ctx || !p || !path)
        return CBM_E_INVALID;
    const char *dot = strrchr(path, '.');
    if (dot && !strcmp(dot, ".csv"))
        return cbm_write_segments_csv(ctx, p, path);
    if (dot && !strcmp(dot, ".mtg"))
        return cbm_write_mtg(ctx, p, path);
    cbm_scene *s;
    CBM_TRY(cbm_scene_create(ctx, &s));
    cbm_status st = cbm_plant_to_scene(p, s, sides);
    if (st == CBM_OK)
        st = cbm_scene_write(ctx, s, path, opts);
    cbm_scene_destroy(s);
    return st;
}
