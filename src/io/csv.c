/* The parts table: one CSV row per part of the scene (RFC 4180, header line, '.' decimal
 * point, empty field for an unknown quantity). Columns: id, segment, parent, organ, order,
 * material, stress_Pa, stress_ratio, age_years, reaction_wood, r, g, b, a (linear colour),
 * triangles, cx_m, cy_m, cz_m (centroid of the part's vertices). The plant table with geometry
 * and loads per mechanical segment is written from the plant itself. */
#include "writers.h"

#include "cambium/io.h"

#include <math.h>
#include <stdio.h>

static void write_number(FILE *f, double x)
{
    if (isfinite(x))
        fprintf(f, ",%.9g", x);
    else
        fputs(",", f);
}

cbm_status cbm_write_parts_csv(cbm_context *ctx, const cbm_scene *s, const char *path,
                               const cbm_write_options *opts)
{
    if (!ctx || !s || !path)
        return CBM_E_INVALID;
    cbm_write_options def;
    const cbm_write_options *o = cbm__opts(opts, &def);
    size_t np = cbm_scene_part_count(s), nt = cbm_scene_triangle_count(s);
    size_t nv = cbm_scene_vertex_count(s);
    const cbm_part *parts = cbm_scene_parts(s);
    const cbm_scene_vertex *v = cbm_scene_vertices(s);
    const uint32_t *tp = cbm_scene_triangle_parts(s);
    size_t m = np ? np : 1;
    double *cen = cbm__calloc(ctx, 3 * m, sizeof *cen);
    size_t *ntri = cbm__calloc(ctx, 2 * m, sizeof *ntri), *nvert = ntri ? ntri + m : NULL;
    uint32_t *vpart = NULL;
    cbm_status st = cen && ntri ? cbm__vertex_parts(ctx, s, &vpart) : CBM_E_NOMEM;
    if (st != CBM_OK) {
        cbm__free(ctx, cen, 3 * m * sizeof *cen);
        cbm__free(ctx, ntri, 2 * m * sizeof *ntri);
        return st;
    }
    for (size_t t = 0; t < nt; t++)
        ntri[tp[t]]++;
    for (size_t i = 0; i < nv; i++) {
        if (vpart[i] == UINT32_MAX)
            continue;
        for (int k = 0; k < 3; k++)
            cen[3 * vpart[i] + (size_t)k] += v[i].p[k];
        nvert[vpart[i]]++;
    }
    cbm_out *out;
    if ((st = cbm_out_open(ctx, path, &out)) == CBM_OK) {
        FILE *f = cbm_out_stream(out);
        fputs("id,segment,parent,organ,order,material,stress_Pa,stress_ratio,age_years,"
              "reaction_wood,r,g,b,a,triangles,cx_m,cy_m,cz_m\n",
              f);
        for (size_t i = 0; i < np; i++) {
            const cbm_part *p = &parts[i];
            if (!cbm__part_kept(p, o))
                continue;
            fprintf(f, "%zu,%lld,%lld,%s,%d,%d", i, (long long)p->segment, (long long)p->parent,
                    cbm_organ_name(p->organ), (int)p->order, (int)p->material);
            write_number(f, p->stress);
            write_number(f, p->stress_ratio);
            write_number(f, p->age);
            write_number(f, p->reaction_wood);
            for (int k = 0; k < 4; k++)
                fprintf(f, ",%.4f", p->color[k]);
            fprintf(f, ",%zu", ntri[i]);
            for (int k = 0; k < 3; k++)
                write_number(f, nvert[i] ? cen[3 * i + (size_t)k] / (double)nvert[i] : NAN);
            fputc('\n', f);
        }
        st = cbm_out_commit(out);
    }
    cbm__free(ctx, cen, 3 * m * sizeof *cen);
    cbm__free(ctx, ntri, 2 * m * sizeof *ntri);
    cbm__free(ctx, vpart, (nv ? nv : 1) * sizeof *vpart);
    return st;
}
