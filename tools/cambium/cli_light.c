/* `--light SKY[,KEY=VALUE...]`: the light pass of cambium grow on the grown plant's scene and its
 * per-leaf table (docs/cli.md, docs/light.md). */
#include "cli_light.h"

#include "cambium/io.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *const sky_names[] = {"dome", "field", "uoc", "soc"};

bool cli_light_parse(const char *v, void *target, char *why, size_t n)
{
    cli_light *l = target;
    l->def = cbm_light_def_default();
    l->on = true;
    char buf[256];
    if (strlen(v) >= sizeof buf) {
        snprintf(why, n, "--light: value too long");
        return false;
    }
    memcpy(buf, v, strlen(v) + 1);
    char *next = strchr(buf, ',');
    if (next)
        *next++ = '\0';
    char *tok = buf;
    bool sky = false;
    for (int k = 0; k < 4; k++)
        if (!strcmp(tok, sky_names[k])) {
            l->def.sky = (cbm_sky_kind)k;
            sky = true;
        }
    if (!sky) {
        snprintf(why, n, "--light: the sky must be dome, field, uoc or soc, not '%s'", tok);
        return false;
    }
    while ((tok = next)) {
        next = strchr(tok, ',');
        if (next)
            *next++ = '\0';
        char *eq = strchr(tok, '=');
        char *end = NULL;
        double x = eq ? strtod(eq + 1, &end) : NAN;
        bool num = eq && end && end != eq + 1 && *end == '\0' && isfinite(x);
        if (eq)
            *eq = '\0';
        if (!strcmp(tok, "one-sided") && !eq)
            l->def.two_sided = false;
        else if (!strcmp(tok, "periodic") && !eq)
            l->def.edge = CBM_LIGHT_EDGE_PERIODIC;
        else if (num && !strcmp(tok, "rings") && x == floor(x) && x >= 1 && x <= 90)
            l->def.rings = (int)x;
        else if (num && !strcmp(tok, "azimuths") && x == floor(x) && x >= 1 && x <= 360)
            l->def.azimuths = (int)x;
        else if (num && !strcmp(tok, "samples") && x == floor(x) && x >= 1 && x <= 16)
            l->def.samples = (int)x;
        else if (num && !strcmp(tok, "direct") && x >= 0 && x <= 1)
            l->def.direct_fraction = x;
        else if (num && !strcmp(tok, "sun-elevation") && x > 0 && x <= 90) {
            double e = x * 3.14159265358979323846 / 180.0;
            l->def.sun = (cbm_vec3){cos(e), sin(e), 0.0};
        } else {
            snprintf(why, n,
                     "--light: bad item '%s%s%s' (rings=1..90, azimuths=1..360, samples=1..16, "
                     "direct=0..1, sun-elevation=DEG, one-sided, periodic)",
                     tok, eq ? "=" : "", eq ? eq + 1 : "");
            return false;
        }
    }
    return true;
}

cbm_status cli_light_run(cbm_context *ctx, const cli_light *l, cbm_scene *sc, const char *csv_path,
                         bool quiet)
{
    size_t np = cbm_scene_part_count(sc), nl = 0;
    double *pl = malloc((np ? np : 1) * sizeof *pl), *pa = malloc((np ? np : 1) * sizeof *pa);
    if (!pl || !pa) {
        free(pl);
        free(pa);
        return CBM_E_NOMEM;
    }
    cbm_light_stats st;
    cbm_status s = cbm_light_scene(ctx, &l->def, sc, pl, pa, &nl, &st);
    const cbm_part *parts = cbm_scene_parts(sc);
    size_t leaves = 0;
    for (size_t k = 0; k < np; k++)
        leaves += parts[k].organ == CBM_ORGAN_LEAF;
    if (s == CBM_OK && !quiet)
        printf("light (%s, %zu sources, %dx%d samples): %zu leaf parts (%zu triangles), leaf area "
               "%.4g m2, intercepted %.4g m2 (%.3f of unshaded horizontal), %zu rays in %.3f s "
               "(%.3g rays/s)\n",
               sky_names[l->def.sky], st.sources, l->def.samples, l->def.samples, leaves, nl,
               st.leaf_area, st.total, st.leaf_area > 0 ? st.total / st.leaf_area : 0.0, st.rays,
               st.seconds, st.seconds > 0 ? (double)st.rays / st.seconds : 0.0);
    if (s == CBM_OK && csv_path) {
        /* each leaf part's centre: the mean of its triangles' vertices */
        double *c = calloc(4 * (np ? np : 1), sizeof *c);
        cbm_out *o = NULL;
        s = c ? cbm_out_open(ctx, csv_path, &o) : CBM_E_NOMEM;
        if (s == CBM_OK) {
            const uint32_t *tri = cbm_scene_triangles(sc), *tp = cbm_scene_triangle_parts(sc);
            const cbm_scene_vertex *vx = cbm_scene_vertices(sc);
            for (size_t t = 0; t < cbm_scene_triangle_count(sc); t++)
                for (int q = 0; q < 3; q++) {
                    const float *p = vx[tri[3 * t + (size_t)q]].p;
                    double *cc = c + 4 * tp[t];
                    cc[0] += p[0], cc[1] += p[1], cc[2] += p[2], cc[3] += 1.0;
                }
            FILE *f = cbm_out_stream(o);
            fprintf(f, "part,segment,order,cx_m,cy_m,cz_m,area_m2,light_m2,relative_light\n");
            for (size_t k = 0; k < np; k++) {
                if (parts[k].organ != CBM_ORGAN_LEAF)
                    continue;
                const double *cc = c + 4 * k, w = cc[3] > 0 ? 1.0 / cc[3] : 0.0;
                fprintf(f, "%zu,%lld,%d,%.6g,%.6g,%.6g,%.6g,%.6g,%.6g\n", k,
                        (long long)parts[k].segment, (int)parts[k].order, cc[0] * w, cc[1] * w,
                        cc[2] * w, pa[k], pl[k], pa[k] > 0 ? pl[k] / pa[k] : 0.0);
            }
            s = cbm_out_commit(o);
        }
        free(c);
    }
    free(pl);
    free(pa);
    return s;
}
