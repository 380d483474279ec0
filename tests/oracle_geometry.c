/* The geometry checks against cpfg shared by the oracle tests (see oracle_geometry.h). */
#define _POSIX_C_SOURCE 200809L
#include "oracle_geometry.h"

#include <stdlib.h>
#include <string.h>

char *oracle_slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    size_t cap = 1 << 16, n = 0;
    char *b = malloc(cap);
    size_t got;
    while ((got = fread(b + n, 1, cap - n - 1, f)) > 0) {
        n += got;
        if (n + 1 >= cap)
            b = realloc(b, cap *= 2);
    }
    fclose(f);
    b[n] = 0;
    if (len)
        *len = n;
    return b;
}

/* Each test case's model: directory, L-system, view, colours, the string after the homomorphism,
 * the kinds compared (-1: all) and the tolerance of the scene bounds against final.obj.gz. */
static const struct {
    const char *test;
    oracle_model model;
} cpfg_models[] = {
    {"quadratic_koch",
     {"cpfg-quadratic-koch", "fractal.l", "fractal.v", "fractal.map", false, -1, 1e-3}},
    {"compound_homo", {"cpfg-compound-homo", "leaf.l", "leaf.v", "leaf.map", true, -1, 1e-3}},
    {"compound_param", {"cpfg-compound-param", "leaf.l", "leaf.v", "leaf.map", true, -1, 1e-3}},
    {"continuous_decomp",
     {"cpfg-continuous-decomp", "leaf.l", "leaf.v", "leaf.map", true, -1, 1e-3}},
    {"florigen_param",
     {"cpfg-florigen-param", "fractal.l", "fractal.v", "fractal.map", true, -1, 1e-3}},
    {"hormone_up", {"cpfg-hormone-up", "fractal.l", "fractal.v", "fractal.map", true, -1, 1e-3}},
    {"monopodial", {"cpfg-monopodial", "leaf.l", "leaf.v", "material.mat", true, -1, 1e-3}},
    {"sympodial", {"cpfg-sympodial", "plant.l", "plant.v", "material.mat", true, -1, 2e-3}},
    {"random_moss",
     {"cpfg-random-moss-abop1.27", "plant.l", "plant.v", "plant.map", false, -1, -1}},
    {"weeping_birch",
     {"cpfg-weeping-birch", "fractal.l", "fractal.v", "fractal.map", false, -1, 1e-3}},
    {"query_position", {"cpfg-query-position", "plant.l", "plant.v", "plant.map", false, -1, -1}},
    /* OBJ: cpfg's OBJ export mirrors predefined surfaces in x; its .ray output does not */
    {"leaf_rnd", {"cpfg-leaf-rnd", "leaf.l", "leaf.v", "material.mat", true, -1, 1e-2}},
    {"tropisms", {"cpfg-tropisms", "lsystem.l", "view.v", "materials.mat", true, -1, 1e-3}},
    {"lilac", {"cpfg-lilac", "plant.l", "plant.v", "materials.mat", true, -1, 1e-3}},
};

const oracle_model *oracle_cpfg_model(const char *test_name)
{
    for (size_t k = 0; k < sizeof cpfg_models / sizeof cpfg_models[0]; k++)
        if (!strcmp(cpfg_models[k].test, test_name))
            return &cpfg_models[k].model;
    fprintf(stderr, "oracle_cpfg_model: no model for the test '%s'\n", test_name);
    abort();
}

/* Parses cpfg's string notation (single-character symbols with optional parameters; newlines
 * ignored) into modules. */

/* ---- reading the .ray file ---- */

#define TRIANGLE 100 /* a .ray triangle (of a generalized cylinder) */

typedef struct rayprim {
    int kind;  /* CBM_PRIM_* */
    int color; /* colour index (surface sN is index N - 256), -1 if none */
    double v[16];
    size_t first, count; /* polygon points in pts */
} rayprim;

typedef struct ray {
    rayprim *p;
    size_t n;
    double *pts; /* 3 per polygon point */
    size_t npts;
} ray;

static bool is_number(const char *t)
{
    char *end;
    strtod(t, &end);
    return end != t && *end == 0;
}

static bool read_ray(const char *path, ray *R)
{
    char cmd[1200];
    snprintf(cmd, sizeof cmd, "gzip -dc '%s'", path);
    FILE *f = popen(cmd, "r");
    if (!f)
        return false;
    memset(R, 0, sizeof *R);
    size_t cap = 1024, pcap = 1024;
    R->p = malloc(cap * sizeof *R->p);
    R->pts = malloc(pcap * sizeof(double));
    char tok[256];
    bool body = false;
    char pending[256] = "";
    for (;;) {
        if (pending[0]) {
            snprintf(tok, sizeof tok, "%s", pending);
            pending[0] = 0;
        } else if (fscanf(f, "%255s", tok) != 1) {
            break;
        }
        if (!body) {
            if (strcmp(tok, "#else") == 0)
                body = true;
            continue;
        }
        int kind = -1, nv = 0;
        if (strcmp(tok, "cylinder") == 0) {
            kind = CBM_PRIM_CYLINDER;
            nv = 7;
        } else if (strcmp(tok, "cone") == 0) {
            kind = CBM_PRIM_CYLINDER;
            nv = 8;
        } else if (strcmp(tok, "sphere") == 0) {
            kind = CBM_PRIM_SPHERE;
            nv = 4;
        } else if (strcmp(tok, "disc") == 0) {
            kind = CBM_PRIM_DISC;
            nv = 7;
        } else if (strcmp(tok, "poly") == 0) {
            kind = CBM_PRIM_POLYGON;
        } else if (strcmp(tok, "triangle") == 0) {
            /* a triangle of a generalized cylinder: 3 lines "x y z nx ny nz" */
            if (R->n == cap)
                R->p = realloc(R->p, (cap *= 2) * sizeof *R->p);
            rayprim *rp = &R->p[R->n++];
            memset(rp, 0, sizeof *rp);
            rp->kind = TRIANGLE;
            for (int k = 0; k < 3; k++) {
                double nrm[3];
                if (fscanf(f, "%lf %lf %lf %lf %lf %lf", &rp->v[3 * k], &rp->v[3 * k + 1],
                           &rp->v[3 * k + 2], &nrm[0], &nrm[1], &nrm[2]) != 6)
                    break;
            }
            continue;
        } else if (strcmp(tok, "object") == 0) {
            /* object ID scale sx sy sz transform (3 rows: L H U) translate x y z */
            char id[64], w1[64], w2[64], w3[64];
            if (R->n == cap)
                R->p = realloc(R->p, (cap *= 2) * sizeof *R->p);
            rayprim *rp = &R->p[R->n];
            memset(rp, 0, sizeof *rp);
            rp->kind = CBM_PRIM_SURFACE;
            if (fscanf(f, "%63s %63s %lf %lf %lf %63s", id, w1, &rp->v[0], &rp->v[1], &rp->v[2],
                       w2) == 6 &&
                strcmp(w1, "scale") == 0 && strcmp(w2, "transform") == 0) {
                for (int i = 0; i < 9; i++)
                    if (fscanf(f, "%lf", &rp->v[6 + i]) != 1)
                        break;
                if (fscanf(f, "%63s %lf %lf %lf", w3, &rp->v[3], &rp->v[4], &rp->v[5]) == 4 &&
                    strcmp(w3, "translate") == 0)
                    R->n++;
            }
            continue;
        }
        if (kind < 0)
            continue;
        char sname[64];
        if (fscanf(f, "%63s", sname) != 1)
            break;
        if (R->n == cap)
            R->p = realloc(R->p, (cap *= 2) * sizeof *R->p);
        rayprim *rp = &R->p[R->n++];
        memset(rp, 0, sizeof *rp);
        rp->kind = kind;
        rp->color = sname[0] == 's' ? atoi(sname + 1) - 256 : -1;
        if (kind == CBM_PRIM_POLYGON) {
            rp->first = R->npts;
            while (fscanf(f, "%255s", tok) == 1) {
                if (!is_number(tok)) {
                    snprintf(pending, sizeof pending, "%s", tok);
                    break;
                }
                if (R->npts * 3 + 3 > pcap)
                    R->pts = realloc(R->pts, (pcap *= 2) * sizeof(double));
                R->pts[R->npts * 3] = strtod(tok, NULL);
                if (fscanf(f, "%lf %lf", &R->pts[R->npts * 3 + 1], &R->pts[R->npts * 3 + 2]) != 2)
                    break;
                R->npts++;
                if (R->npts * 3 + 3 > pcap)
                    R->pts = realloc(R->pts, (pcap *= 2) * sizeof(double));
            }
            rp->count = R->npts - rp->first;
            continue;
        }
        for (int i = 0; i < nv; i++)
            if (fscanf(f, "%lf", &rp->v[i]) != 1)
                break;
        if (nv == 7 && kind == CBM_PRIM_CYLINDER) {
            /* r x y z x y z -> r0 x0 y0 z0 r1 x1 y1 z1 */
            double r = rp->v[0];
            double e[3] = {rp->v[4], rp->v[5], rp->v[6]};
            rp->v[4] = r;
            rp->v[5] = e[0];
            rp->v[6] = e[1];
            rp->v[7] = e[2];
        }
    }
    pclose(f);
    return body;
}

/* ---- the comparison ---- */

static double maxdev; /* largest |ours - cpfg| of the current model's primitives */

static bool near(double a, double b, double scale)
{
    if (fabs(a - b) > maxdev)
        maxdev = fabs(a - b);
    return fabs(a - b) <= 1e-5 * (1 + fabs(b)) + 1e-5 * scale;
}

void oracle_check_geometry(const oracle_model *md, cbm_turtle *t, cbm_scene *scene, size_t nmod,
                           bool compare_prims)
{
    char path[1024];
    /* box */
    snprintf(path, sizeof path, ORACLE "%s/ref/final.vv", md->dir);
    char *vv = oracle_slurp(path, NULL);
    double b[6] = {0};
    CHECK(vv && sscanf(vv, "box: x: %lf,%lf y: %lf,%lf z: %lf,%lf", &b[0], &b[1], &b[2], &b[3],
                       &b[4], &b[5]) == 6);
    free(vv);
    cbm_vec3 lo, hi;
    CHECK(cbm_turtle_box(t, &lo, &hi));
    double scale = fmax(b[1] - b[0], fmax(b[3] - b[2], b[5] - b[4]));
    double tol = 1e-4 * scale;
    double bdev = fmax(fmax(fabs(lo.x - b[0]), fabs(hi.x - b[1])),
                       fmax(fmax(fabs(lo.y - b[2]), fabs(hi.y - b[3])),
                            fmax(fabs(lo.z - b[4]), fabs(hi.z - b[5]))));
    maxdev = 0.0;
    if (md->only_kind < 0) {
        CHECK_NEAR(lo.x, b[0], tol);
        CHECK_NEAR(hi.x, b[1], tol);
        CHECK_NEAR(lo.y, b[2], tol);
        CHECK_NEAR(hi.y, b[3], tol);
        CHECK_NEAR(lo.z, b[4], tol);
        CHECK_NEAR(hi.z, b[5], tol);
    } else {
        CHECK(lo.x >= b[0] - tol && hi.x <= b[1] + tol);
        CHECK(lo.y >= b[2] - tol && hi.y <= b[3] + tol);
        CHECK(lo.z >= b[4] - tol && hi.z <= b[5] + tol);
    }

    if (compare_prims) {
        ray R = {0};
        snprintf(path, sizeof path, ORACLE "%s/ref/final.ray.gz", md->dir);
        CHECK(read_ray(path, &R));
        const cbm_prim *P = cbm_turtle_prims(t);
        const cbm_vec3 *pts = cbm_turtle_points(t);
        size_t np = cbm_turtle_prim_count(t);
        /* our record in the ray's terms: GC and surfaces are not compared */
        size_t j = 0, bad = 0, compared = 0;
        for (size_t i = 0; i < np; i++) {
            if (P[i].kind == CBM_PRIM_GCYL) {
                /* our triangles, in cpfg's order */
                for (size_t k = 0; k + 3 <= P[i].count; k += 3) {
                    if (j >= R.n || R.p[j].kind != TRIANGLE) {
                        bad++;
                        continue;
                    }
                    const rayprim *r = &R.p[j++];
                    compared++;
                    bool ok = true;
                    for (int q = 0; q < 3; q++) {
                        cbm_vec3 a = pts[P[i].first + k + (size_t)q];
                        ok = ok && near(a.x, r->v[3 * q], scale) &&
                             near(a.y, r->v[3 * q + 1], scale) && near(a.z, r->v[3 * q + 2], scale);
                    }
                    if (!ok) {
                        if (bad < 3)
                            fprintf(stderr,
                                    "%s: triangle %zu differs: ours (%g %g %g) cpfg (%g %g "
                                    "%g)\n",
                                    md->dir, j - 1, pts[P[i].first + k].x, pts[P[i].first + k].y,
                                    pts[P[i].first + k].z, r->v[0], r->v[1], r->v[2]);
                        bad++;
                    }
                }
                continue;
            }
            if (md->only_kind >= 0 && (int)P[i].kind != md->only_kind)
                continue;
            while (md->only_kind >= 0 && j < R.n && R.p[j].kind != md->only_kind)
                j++;
            if (j >= R.n) {
                bad++;
                continue;
            }
            const rayprim *r = &R.p[j++];
            compared++;
            bool ok = (int)P[i].kind == r->kind;
            if (ok && r->kind != CBM_PRIM_SURFACE && r->color != P[i].color) {
                if (bad < 3)
                    fprintf(stderr, "%s: primitive %zu has colour %d, cpfg %d\n", md->dir, j - 1,
                            P[i].color, r->color);
                ok = false;
            }
            if (ok && r->kind == CBM_PRIM_CYLINDER) {
                double mine[8] = {P[i].r0, P[i].p0.x, P[i].p0.y, P[i].p0.z,
                                  P[i].r1, P[i].p1.x, P[i].p1.y, P[i].p1.z};
                for (int k = 0; k < 8; k++)
                    ok = ok && near(mine[k], r->v[k], scale);
            } else if (ok && (r->kind == CBM_PRIM_SPHERE || r->kind == CBM_PRIM_DISC)) {
                double mine[7] = {P[i].r0,   P[i].p0.x, P[i].p0.y, P[i].p0.z,
                                  P[i].p1.x, P[i].p1.y, P[i].p1.z};
                int nk = r->kind == CBM_PRIM_SPHERE ? 4 : 7;
                for (int k = 0; k < nk; k++)
                    ok = ok && near(mine[k], r->v[k], scale);
            } else if (ok && r->kind == CBM_PRIM_SURFACE) {
                /* scale (uniform here), position, and the frame rows L, H, U */
                const cbm_frame *F = &P[i].frame;
                double mine[15] = {P[i].r0,   P[i].r0, P[i].r0, P[i].p0.x, P[i].p0.y,
                                   P[i].p0.z, F->l.x,  F->l.y,  F->l.z,    F->h.x,
                                   F->h.y,    F->h.z,  F->u.x,  F->u.y,    F->u.z};
                for (int k = 0; k < 15; k++)
                    ok = ok && near(mine[k], r->v[k], k >= 6 ? 1.0 : scale);
            } else if (ok) {
                ok = P[i].count == r->count;
                for (size_t k = 0; ok && k < r->count; k++) {
                    const cbm_vec3 q = pts[P[i].first + k];
                    const double *w = &R.pts[3 * (r->first + k)];
                    ok = near(q.x, w[0], scale) && near(q.y, w[1], scale) && near(q.z, w[2], scale);
                }
            }
            if (!ok) {
                if (bad < 3)
                    fprintf(stderr,
                            "%s: primitive %zu (kind %d) differs: ours r0 %g (%g %g %g) r1 %g "
                            "(%g %g %g); cpfg %g (%g %g %g) %g (%g %g %g)\n",
                            md->dir, j - 1, r->kind, P[i].r0, P[i].p0.x, P[i].p0.y, P[i].p0.z,
                            P[i].r1, P[i].p1.x, P[i].p1.y, P[i].p1.z, r->v[0], r->v[1], r->v[2],
                            r->v[3], r->v[4], r->v[5], r->v[6], r->v[7]);
                bad++;
            }
        }
        while (md->only_kind >= 0 && j < R.n && R.p[j].kind != md->only_kind)
            j++;
        CHECK_MSG(j == R.n, "%s: cpfg has %zu primitives, we compared %zu", md->dir, R.n, j);
        CHECK(compared > 0);
        fprintf(stderr,
                "%s: %zu modules, %zu of cpfg's %zu .ray primitives compared, %zu differ, "
                "max deviation %.2g (box %.2g) of size %.3g\n",
                md->dir, nmod, compared, R.n, bad, maxdev, bdev, scale);
        CHECK_MSG(bad == 0, "%s: %zu of %zu primitives differ", md->dir, bad, compared);
        free(R.p);
        free(R.pts);
    }
    CHECK(cbm_scene_triangle_count(scene) > 0);
    /* the scene's bounds against cpfg's OBJ export, where there is one */
    snprintf(path, sizeof path, "gzip -dc '" ORACLE "%s/ref/final.obj.gz' 2>/dev/null", md->dir);
    FILE *obj = popen(path, "r");
    if (obj) {
        char line[512];
        double olo[3] = {INFINITY, INFINITY, INFINITY}, ohi[3] = {-INFINITY, -INFINITY, -INFINITY};
        size_t nv = 0;
        while (fgets(line, sizeof line, obj)) {
            double q[3];
            if (line[0] == 'v' && line[1] == ' ' &&
                sscanf(line + 2, "%lf %lf %lf", &q[0], &q[1], &q[2]) == 3) {
                for (int k = 0; k < 3; k++) {
                    olo[k] = fmin(olo[k], q[k]);
                    ohi[k] = fmax(ohi[k], q[k]);
                }
                nv++;
            }
        }
        pclose(obj);
        cbm_vec3 slo, shi;
        if (nv > 0 && cbm_scene_bounds(scene, &slo, &shi)) {
            double d = fmax(fmax(fabs(slo.x - olo[0]), fabs(shi.x - ohi[0])),
                            fmax(fmax(fabs(slo.y - olo[1]), fabs(shi.y - ohi[1])),
                                 fmax(fabs(slo.z - olo[2]), fabs(shi.z - ohi[2]))));
            fprintf(stderr,
                    "%s: scene bounds vs cpfg's OBJ: largest difference %.3g (ours %g %g %g %g "
                    "%g %g)\n",
                    md->dir, d, slo.x, shi.x, slo.y, shi.y, slo.z, shi.z);
            if (md->obj_tol >= 0.0)
                CHECK_MSG(d <= md->obj_tol, "%s: scene bounds differ from cpfg's OBJ by %g",
                          md->dir, d);
        }
    }
}
