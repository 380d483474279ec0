/* lpfg geometry end to end: the six L+C models of ../shared/oracles/vlab/lpfg-* through
 * cbm_model (our derivation, our interpretation rules, our turtle with lpfg's module meanings),
 * compared with lpfg's own output:
 * - ref/interp.txt, lpfg's turtle trace after the interpretation rules (one turtle call a line:
 *   `F(1.000000)`, `SetColor(2)`, `IncColor`; branches are not traced, and Sphere0 is traced
 *   as `Sphere0` followed by the `Sphere(r)` it calls): the turtle modules of our interpreted
 *   string, in order, name by name, parameters within 1e-5 * (1 + |value|) (the trace prints 6
 *   decimals); every drawn F (length^2 > 1e-5, lpfg draws shorter ones, we drop them as cpfg)
 *   is one of our cylinders, in order, of that length within the same tolerance; every sphere
 *   has lpfg's radius (Sphere0: half the width); every cylinder's radius is half a width the
 *   trace sets (or of the initial width 1).
 * - ref/final.obj.gz where there is one: the exact bounding box of our primitives (cylinders
 *   with their radii, spheres) against the box of lpfg's mesh, within 1e-4 * size plus
 *   lpfg's tessellation (cylinders and spheres as polygons: up to 5% of the largest radius short
 *   of the exact surface).
 */
#define _POSIX_C_SOURCE 200809L
#include "test.h"

#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#define ORACLE CBM_TEST_SOURCE_DIR "/../shared/oracles/vlab/"

typedef struct tline {
    char name[32];
    int n;
    double p[6];
} tline;

typedef struct trace {
    tline *l;
    size_t n, cap;
} trace;

static void trace_push(trace *t, const tline *x)
{
    if (t->n == t->cap) {
        t->cap = t->cap ? 2 * t->cap : 1024;
        t->l = realloc(t->l, t->cap * sizeof *t->l);
    }
    t->l[t->n++] = *x;
}

/* One line of lpfg's trace: Name or Name(a,b,...). */
static bool parse_line(const char *s, tline *x)
{
    memset(x, 0, sizeof *x);
    size_t k = 0;
    while (s[k] && s[k] != '(' && s[k] != '\n' && k + 1 < sizeof x->name) {
        x->name[k] = s[k];
        k++;
    }
    if (k == 0)
        return false;
    if (s[k] != '(')
        return true;
    const char *p = s + k + 1;
    while (*p && *p != ')' && x->n < 6) {
        char *end;
        x->p[x->n++] = strtod(p, &end);
        if (end == p)
            return false;
        p = end;
        while (*p == ',' || *p == ' ')
            p++;
    }
    return true;
}

static bool read_trace(const char *path, trace *t)
{
    FILE *f = fopen(path, "r");
    if (!f)
        return false;
    char line[512];
    while (fgets(line, sizeof line, f)) {
        tline x;
        if (parse_line(line, &x))
            trace_push(t, &x);
    }
    fclose(f);
    return true;
}

/* The modules lpfg's text turtle traces (with the same parameters as the module). */
static bool traced(const char *nm)
{
    static const char *const T[] = {"F",        "f",        "G",        "g",        "Left",
                                    "Right",    "Down",     "Up",       "RollR",    "RollL",
                                    "IncColor", "DecColor", "SetColor", "SetWidth", "Sphere",
                                    "Sphere0",  "Circle",   "Circle0"};
    for (size_t i = 0; i < sizeof T / sizeof T[0]; i++)
        if (!strcmp(nm, T[i]))
            return true;
    return false;
}

static bool near(double a, double b)
{
    return fabs(a - b) <= 1e-5 * (1 + fabs(b));
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

/* lpfg's mesh vertices bucketed in a grid of cubes of side `cell`, sorted by cube. */
typedef struct gv {
    int64_t key;
    double v[3];
} gv;

static int64_t cube_key(const double *v, double cell, int dx, int dy, int dz)
{
    int64_t ix = (int64_t)floor(v[0] / cell) + dx + (1 << 20);
    int64_t iy = (int64_t)floor(v[1] / cell) + dy + (1 << 20);
    int64_t iz = (int64_t)floor(v[2] / cell) + dz + (1 << 20);
    return (ix << 42) | (iy << 21) | iz;
}

static int cmp_gv(const void *a, const void *b)
{
    int64_t x = ((const gv *)a)->key, y = ((const gv *)b)->key;
    return x < y ? -1 : x > y;
}

/* Whether lpfg's mesh has a vertex on the circle of radius r about P normal to the unit axis d:
 * a ring of one of its cylinders ends there. */
static bool ring_at(const gv *g, size_t n, double cell, const double *P, const double *d, double r,
                    double tol)
{
    for (int dx = -1; dx <= 1; dx++)
        for (int dy = -1; dy <= 1; dy++)
            for (int dz = -1; dz <= 1; dz++) {
                int64_t key = cube_key(P, cell, dx, dy, dz);
                size_t lo = 0, hi = n;
                while (lo < hi) {
                    size_t mid = (lo + hi) / 2;
                    if (g[mid].key < key)
                        lo = mid + 1;
                    else
                        hi = mid;
                }
                for (size_t k = lo; k < n && g[k].key == key; k++) {
                    double w[3] = {g[k].v[0] - P[0], g[k].v[1] - P[1], g[k].v[2] - P[2]};
                    double along = w[0] * d[0] + w[1] * d[1] + w[2] * d[2];
                    double dist = sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]);
                    if (fabs(along) <= tol && fabs(dist - r) <= tol)
                        return true;
                }
            }
    return false;
}

typedef struct lmodel {
    const char *dir;
    const char *sides[4];
    size_t nsides;
    double obj_extra; /* lpfg's tessellation allowance in the box, times the largest radius */
} lmodel;

static void run_model(const lmodel *md)
{
    if (test_skip_without_oracles())
        return;
    char lpath[1024], spath[4][1024], path[1024];
    const char *sides[4];
    cbm_context *ctx = test_ctx();
    snprintf(lpath, sizeof lpath, ORACLE "%s/model/lsystem.l", md->dir);
    for (size_t i = 0; i < md->nsides; i++) {
        snprintf(spath[i], sizeof spath[i], ORACLE "%s/model/%s", md->dir, md->sides[i]);
        sides[i] = spath[i];
    }
    cbm_model_def def = {cbm_lsys_def_default(), sides, md->nsides};
    def.lsys.path = lpath;
    cbm_model *mdl = NULL;
    CHECK_OK(cbm_model_load(ctx, &def, &mdl));
    if (!mdl) {
        fprintf(stderr, "%s\n", cbm_context_last_error(ctx));
        test_ctx_end(ctx);
        return;
    }
    CHECK_OK(cbm_model_reset(mdl));
    cbm_lsys *ls = cbm_model_lsys(mdl);
    for (int k = 0; k < cbm_lsys_derivation_length(ls) && !cbm_lsys_stopped(ls); k++)
        CHECK_OK(cbm_model_step(mdl));
    cbm_scene *scene = NULL;
    CHECK_OK(cbm_scene_create(ctx, &scene));
    cbm_turtle *t = NULL;
    CHECK_OK(cbm_model_interpret(mdl, scene, true, &t));

    /* our trace: the turtle modules of the interpreted string */
    trace ours = {0}, ref = {0};
    bool image = cbm_lsys_has_homomorphism(ls);
    cbm_lsys_cursor c;
    cbm_lsys_cursor_begin(ls, image, &c);
    while (cbm_lsys_cursor_next(ls, image, &c)) {
        const char *nm = cbm_lsys_module_name(ls, c.symbol);
        if (!nm || !traced(nm))
            continue;
        tline x;
        memset(&x, 0, sizeof x);
        snprintf(x.name, sizeof x.name, "%s", nm);
        x.n = c.nparams < 6 ? c.nparams : 6;
        for (int i = 0; i < x.n; i++)
            x.p[i] = c.params[i];
        trace_push(&ours, &x);
    }
    snprintf(path, sizeof path, ORACLE "%s/ref/interp.txt", md->dir);
    CHECK_MSG(read_trace(path, &ref), "cannot read %s", path);

    /* lpfg's trace against ours; Sphere0's Sphere(r) is checked against our spheres */
    size_t i = 0, j = 0, bad = 0, nsph = 0, ncyl = 0, nf = 0, nbadcolor = 0;
    double maxdev = 0.0;
    size_t nprim = t ? cbm_turtle_prim_count(t) : 0;
    const cbm_prim *pr = t ? cbm_turtle_prims(t) : NULL;
    size_t kcyl = 0, ksph = 0;
    double *widths = malloc((ref.n + 1) * sizeof *widths);
    size_t nw = 0;
    widths[nw++] = 1.0; /* lpfg's initial width */
    for (; i < ref.n; i++) {
        const tline *r = &ref.l[i];
        if (!strcmp(r->name, "SetWidth") && r->n == 1)
            widths[nw++] = r->p[0];
        if (!strcmp(r->name, "Sphere") && i > 0 && !strcmp(ref.l[i - 1].name, "Sphere0")) {
            /* the call Sphere0 makes: our sphere's radius */
            while (ksph < nprim && pr[ksph].kind != CBM_PRIM_SPHERE)
                ksph++;
            if (ksph < nprim) {
                maxdev = fmax(maxdev, fabs(pr[ksph].r0 - r->p[0]));
                if (!near(pr[ksph].r0, r->p[0]) && bad++ < 5)
                    fprintf(stderr, "%s: sphere %zu radius %g, lpfg %g\n", md->dir, nsph,
                            pr[ksph].r0, r->p[0]);
                ksph++;
            }
            nsph++;
            continue;
        }
        if (j >= ours.n) {
            bad++;
            break;
        }
        const tline *o = &ours.l[j++];
        bool same = !strcmp(o->name, r->name) && o->n == r->n;
        if (same && !strcmp(r->name, "SetColor") && r->n == 1 && !(r->p[0] >= 1 && r->p[0] < 256) &&
            !(o->p[0] >= 1 && o->p[0] < 256)) {
            /* (int) of -inf: lpfg's x86 gives INT_MIN, ours another out-of-range value; lpfg's
             * turtle and ours both ignore a colour outside 1..255 */
            nbadcolor++;
            continue;
        }
        for (int k = 0; same && k < r->n; k++) {
            maxdev = fmax(maxdev, fabs(o->p[k] - r->p[k]));
            same = near(o->p[k], r->p[k]);
        }
        if (!same && bad++ < 5)
            fprintf(stderr, "%s: trace line %zu: lpfg %s(%g) ours %s(%g)\n", md->dir, i + 1,
                    r->name, r->p[0], o->name, o->p[0]);
        if (!strcmp(r->name, "Sphere") && r->n == 1) {
            while (ksph < nprim && pr[ksph].kind != CBM_PRIM_SPHERE)
                ksph++;
            if (ksph < nprim && !near(pr[ksph].r0, r->p[0]) && bad++ < 5)
                fprintf(stderr, "%s: sphere radius %g, lpfg %g\n", md->dir, pr[ksph].r0, r->p[0]);
            ksph++;
            nsph++;
        }
        /* a drawn F: our next cylinder, of that length */
        if (!strcmp(r->name, "F") && r->n == 1 && r->p[0] * r->p[0] > 1e-5 * (1 + 1e-4)) {
            nf++;
            while (kcyl < nprim && pr[kcyl].kind != CBM_PRIM_CYLINDER)
                kcyl++;
            if (kcyl >= nprim) {
                bad++;
                continue;
            }
            double len =
                sqrt(pow(pr[kcyl].p1.x - pr[kcyl].p0.x, 2) + pow(pr[kcyl].p1.y - pr[kcyl].p0.y, 2) +
                     pow(pr[kcyl].p1.z - pr[kcyl].p0.z, 2));
            maxdev = fmax(maxdev, fabs(len - fabs(r->p[0])));
            if (!near(len, fabs(r->p[0])) && bad++ < 5)
                fprintf(stderr, "%s: cylinder %zu length %g, lpfg F(%g)\n", md->dir, ncyl, len,
                        r->p[0]);
            kcyl++;
            ncyl++;
        }
    }
    CHECK_MSG(j == ours.n, "%s: %zu turtle modules of ours, %zu traced by lpfg", md->dir, ours.n,
              j);
    size_t ourcyl = 0;
    for (size_t k = 0; k < nprim; k++)
        ourcyl += pr[k].kind == CBM_PRIM_CYLINDER;
    CHECK_MSG(ourcyl == nf, "%s: %zu cylinders, lpfg draws %zu", md->dir, ourcyl, nf);
    /* radii: half a width the trace sets */
    qsort(widths, nw, sizeof *widths, cmp_double);
    double rmax = 0.0;
    size_t badr = 0;
    for (size_t k = 0; k < nprim; k++) {
        if (pr[k].kind != CBM_PRIM_CYLINDER && pr[k].kind != CBM_PRIM_SPHERE)
            continue;
        rmax = fmax(rmax, pr[k].r0);
        if (pr[k].kind != CBM_PRIM_CYLINDER)
            continue;
        double w = 2.0 * pr[k].r0;
        size_t lo = 0, hi = nw;
        while (lo < hi) {
            size_t mid = (lo + hi) / 2;
            if (widths[mid] < w)
                lo = mid + 1;
            else
                hi = mid;
        }
        bool found = (lo < nw && near(w, widths[lo])) || (lo > 0 && near(w, widths[lo - 1])) ||
                     (w <= 2e-7 && widths[0] <= 1e-7); /* SetWidth(0): the turtle's least */
        badr += !found;
    }
    CHECK_MSG(badr == 0, "%s: %zu cylinders with a radius no SetWidth gives", md->dir, badr);
    fprintf(
        stderr,
        "%s: %zu trace lines, %zu cylinders (lpfg's drawn F), %zu spheres, %zu ignored colours, "
        "%zu differ, max deviation %.2g\n",
        md->dir, ref.n, ncyl, nsph, nbadcolor, bad, maxdev);
    CHECK_MSG(bad == 0, "%s: %zu differences with lpfg's trace", md->dir, bad);
    free(widths);

    /* the exact box of our primitives against lpfg's mesh */
    snprintf(path, sizeof path, "gzip -dc '" ORACLE "%s/ref/final.obj.gz' 2>/dev/null", md->dir);
    FILE *obj = md->obj_extra > 0 ? popen(path, "r") : NULL;
    if (obj) {
        char line[512];
        double olo[3] = {INFINITY, INFINITY, INFINITY}, ohi[3] = {-INFINITY, -INFINITY, -INFINITY};
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        size_t nv = 0, cap = 1 << 16;
        gv *g = malloc(cap * sizeof *g);
        while (fgets(line, sizeof line, obj)) {
            double q[3];
            if (line[0] == 'v' && line[1] == ' ' &&
                sscanf(line + 2, "%lf %lf %lf", &q[0], &q[1], &q[2]) == 3) {
                for (int k = 0; k < 3; k++) {
                    olo[k] = fmin(olo[k], q[k]);
                    ohi[k] = fmax(ohi[k], q[k]);
                }
                if (nv == cap)
                    g = realloc(g, (cap *= 2) * sizeof *g);
                memcpy(g[nv++].v, q, sizeof q);
            }
        }
        pclose(obj);
        /* segment end points: each of our cylinders' ends is the centre of a ring of lpfg's
         * mesh of our radius, normal to our axis (the OBJ prints 6 significant digits) */
        double cell = fmax(2.5 * rmax, 1e-3);
        for (size_t k = 0; k < nv; k++)
            g[k].key = cube_key(g[k].v, cell, 0, 0, 0);
        qsort(g, nv, sizeof *g, cmp_gv);
        double amax =
            fmax(fmax(fabs(olo[0]), fabs(ohi[0])),
                 fmax(fmax(fabs(olo[1]), fabs(ohi[1])), fmax(fabs(olo[2]), fabs(ohi[2]))));
        double etol = 2e-6 * fmax(1.0, amax) + 1e-5 * rmax;
        size_t nends = 0, missing = 0;
        for (size_t k = 0; k < nprim; k++) {
            const cbm_prim *p = &pr[k];
            if (p->kind != CBM_PRIM_CYLINDER)
                continue;
            double a[3] = {p->p0.x, p->p0.y, p->p0.z}, b[3] = {p->p1.x, p->p1.y, p->p1.z};
            double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
            double dl = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            for (int e = 0; e < 3; e++)
                d[e] /= dl;
            bool fa = ring_at(g, nv, cell, a, d, p->r0, etol);
            bool fb = ring_at(g, nv, cell, b, d, p->r1, etol);
            if ((!fa || !fb) && missing < 3)
                fprintf(stderr,
                        "%s: cylinder %zu (%g %g %g)-(%g %g %g) r %g: no ring in lpfg's mesh\n",
                        md->dir, k, a[0], a[1], a[2], b[0], b[1], b[2], p->r0);
            missing += !fa + !fb;
            nends += 2;
        }
        fprintf(stderr, "%s: %zu segment end points, %zu without lpfg's ring (tolerance %.2g)\n",
                md->dir, nends, missing, etol);
        CHECK_MSG(missing == 0, "%s: %zu segment end points are not in lpfg's mesh", md->dir,
                  missing);
        free(g);
        for (size_t k = 0; k < nprim; k++) {
            const cbm_prim *p = &pr[k];
            double a[3] = {p->p0.x, p->p0.y, p->p0.z}, b[3] = {p->p1.x, p->p1.y, p->p1.z};
            if (p->kind == CBM_PRIM_SPHERE) {
                for (int e = 0; e < 3; e++) {
                    lo[e] = fmin(lo[e], a[e] - p->r0);
                    hi[e] = fmax(hi[e], a[e] + p->r0);
                }
            } else if (p->kind == CBM_PRIM_CYLINDER) {
                double d[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
                double dl = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
                for (int e = 0; e < 3; e++) {
                    double s = sqrt(fmax(0.0, 1.0 - d[e] * d[e] / (dl * dl)));
                    lo[e] = fmin(lo[e], fmin(a[e] - p->r0 * s, b[e] - p->r1 * s));
                    hi[e] = fmax(hi[e], fmax(a[e] + p->r0 * s, b[e] + p->r1 * s));
                }
            }
        }
        double size = fmax(ohi[0] - olo[0], fmax(ohi[1] - olo[1], ohi[2] - olo[2]));
        double d = 0.0;
        for (int e = 0; e < 3; e++)
            d = fmax(d, fmax(fabs(lo[e] - olo[e]), fabs(hi[e] - ohi[e])));
        double tol = 1e-4 * size + md->obj_extra * rmax;
        fprintf(stderr,
                "%s: box vs lpfg's OBJ (%zu vertices): largest difference %.3g (tolerance %.3g); "
                "ours x %g..%g y %g..%g z %g..%g\n",
                md->dir, nv, d, tol, lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]);
        CHECK(nv > 0);
        CHECK_MSG(d <= tol, "%s: box differs from lpfg's OBJ by %g", md->dir, d);
    }
    CHECK(cbm_scene_triangle_count(scene) > 0);
    free(ours.l);
    free(ref.l);
    cbm_turtle_destroy(t);
    cbm_scene_destroy(scene);
    cbm_model_destroy(mdl);
    test_ctx_end(ctx);
}

TEST(lpfg_geometry_quadratic_koch)
{
    static const lmodel m = {"lpfg-quadratic-koch", {"view.v", "color.map"}, 2, 0.05};
    run_model(&m);
}

TEST(lpfg_geometry_compound_param)
{
    static const lmodel m = {"lpfg-compound-param", {"view.v", "color.map"}, 2, 0.05};
    run_model(&m);
}

TEST(lpfg_geometry_hormone_up)
{
    static const lmodel m = {"lpfg-hormone-up", {"view.v", "color.map"}, 2, 0.05};
    run_model(&m);
}

TEST(lpfg_geometry_sympodial)
{
    static const lmodel m = {
        "lpfg-sympodial", {"view.v", "material.mat", "functions.fset"}, 3, 0.05};
    run_model(&m);
}

TEST(lpfg_geometry_newcontext)
{
    static const lmodel m = {"lpfg-newcontext", {"view.v", "color.map"}, 2, 0.0};
    run_model(&m);
}

TEST(lpfg_geometry_innewcontext)
{
    static const lmodel m = {"lpfg-innewcontext", {"view.v", "color.map"}, 2, 0.0};
    run_model(&m);
}

/* func(name, x) calls the function of that name, whatever the order of first use; an unknown
 * name is an error naming it. */
TEST(lpfg_func_by_name)
{
    if (test_skip_without_oracles())
        return;
    cbm_context *ctx = test_ctx();
    const char *fset = ORACLE "lpfg-sympodial/model/functions.fset";
    const char *sides[1] = {fset};
    const char *text = "#include <lpfgall.h>\n"
                       "derivation length: 1;\n"
                       "module A(float, float);\n"
                       "Axiom: A(0, 0);\n"
                       "A(a, b): { produce A(func(flower, 0.5), func(internode, 0.5)); }\n";
    cbm_model_def def = {cbm_lsys_def_default(), sides, 1};
    def.lsys.path = "byname.l";
    def.lsys.text = text;
    cbm_model *m = NULL;
    CHECK_OK(cbm_model_load(ctx, &def, &m));
    if (m) {
        const cbm_funcset *fs = cbm_view_functions(cbm_model_view(m));
        int fl = cbm_funcset_find(fs, "flower"), in = cbm_funcset_find(fs, "internode");
        CHECK(fl > 0 && in > 0 && fl != in);
        CHECK_OK(cbm_model_reset(m));
        CHECK_OK(cbm_model_step(m));
        cbm_lsys *ls = cbm_model_lsys(m);
        cbm_lsys_cursor c;
        cbm_lsys_cursor_begin(ls, false, &c);
        CHECK(cbm_lsys_cursor_next(ls, false, &c));
        CHECK_EQ_INT(c.nparams, 2);
        if (c.nparams == 2) {
            CHECK_NEAR(c.params[0], cbm_funcset_value(fs, fl, 0.5), 1e-6);
            CHECK_NEAR(c.params[1], cbm_funcset_value(fs, in, 0.5), 1e-6);
            CHECK(fabs(c.params[0] - c.params[1]) > 1e-3); /* the two functions differ there */
        }
        cbm_model_destroy(m);
    }
    def.lsys.text = "#include <lpfgall.h>\n"
                    "derivation length: 1;\n"
                    "module A(float);\n"
                    "Axiom: A(0);\n"
                    "A(a): { produce A(func(nosuchfunction, 0.5)); }\n";
    m = NULL;
    CHECK_STATUS(cbm_model_load(ctx, &def, &m), CBM_E_NOT_FOUND);
    CHECK(m == NULL);
    CHECK(strstr(cbm_context_last_error(ctx), "nosuchfunction") != NULL);
    test_ctx_end(ctx);
}

/* ---- lpfg's turtle modules one by one (lpfg's turtle: H = +y, L = -x, lpfg's U = +z) ---- */

/* Interprets the axiom `axiom` of a one-line L+C model; the turtle keeps its record. */
static cbm_turtle *axiom_turtle_scene(cbm_context *ctx, const char *axiom, const char *view,
                                      cbm_scene *scene)
{
    char text[1024];
    snprintf(text, sizeof text,
             "#include <lpfgall.h>\nderivation length: 0;\nmodule A();\nAxiom: %s;\n", axiom);
    char vpath[64];
    snprintf(vpath, sizeof vpath, "/tmp/cbm_lpfg_view_%ld.v", (long)getpid());
    const char *sides[1] = {vpath};
    size_t nsides = 0;
    if (view) {
        FILE *f = fopen(vpath, "w");
        CHECK(f != NULL);
        if (f) {
            fputs(view, f);
            fclose(f);
        }
        nsides = 1;
    }
    cbm_model_def def = {cbm_lsys_def_default(), sides, nsides};
    def.lsys.path = "axiom.l";
    def.lsys.text = text;
    cbm_model *m = NULL;
    cbm_turtle *t = NULL;
    CHECK_OK(cbm_model_load(ctx, &def, &m));
    if (view)
        remove(vpath);
    if (!m) {
        fprintf(stderr, "%s\n", cbm_context_last_error(ctx));
        return NULL;
    }
    CHECK_OK(cbm_model_reset(m));
    CHECK_OK(cbm_model_interpret(m, scene, true, &t));
    cbm_model_destroy(m);
    return t;
}

static cbm_turtle *axiom_turtle(cbm_context *ctx, const char *axiom, const char *view)
{
    return axiom_turtle_scene(ctx, axiom, view, NULL);
}

static const cbm_prim *nth_prim(const cbm_turtle *t, cbm_prim_kind kind, size_t n)
{
    for (size_t k = 0; t && k < cbm_turtle_prim_count(t); k++)
        if (cbm_turtle_prims(t)[k].kind == kind && n-- == 0)
            return &cbm_turtle_prims(t)[k];
    return NULL;
}

static void check_seg(cbm_context *ctx, const char *axiom, const char *view, size_t n, double x0,
                      double y0, double z0, double x1, double y1, double z1)
{
    cbm_turtle *t = axiom_turtle(ctx, axiom, view);
    const cbm_prim *p = nth_prim(t, CBM_PRIM_CYLINDER, n);
    CHECK_MSG(p != NULL, "%s: no cylinder %zu", axiom, n);
    if (p) {
        double got[6] = {p->p0.x, p->p0.y, p->p0.z, p->p1.x, p->p1.y, p->p1.z};
        double want[6] = {x0, y0, z0, x1, y1, z1};
        for (int k = 0; k < 6; k++)
            CHECK_MSG(fabs(got[k] - want[k]) < 1e-9, "%s: cylinder %zu coordinate %d is %g, not %g",
                      axiom, n, k, got[k], want[k]);
    }
    cbm_turtle_destroy(t);
}

TEST(lpfg_modules_frame)
{
    cbm_context *ctx = test_ctx();
    check_seg(ctx, "F(1)", NULL, 0, 0, 0, 0, 0, 1, 0);
    check_seg(ctx, "Left(90) F(1)", NULL, 0, 0, 0, 0, -1, 0, 0);
    /* corrected rotation (lpfg's default): Down turns H towards -U, Up towards +U (+z) */
    check_seg(ctx, "Down(90) F(1)", NULL, 0, 0, 0, 0, 0, 0, -1);
    check_seg(ctx, "Up(90) F(1)", NULL, 0, 0, 0, 0, 0, 0, 1);
    check_seg(ctx, "RollL(90) Left(90) F(1)", NULL, 0, 0, 0, 0, 0, 0, -1);
    check_seg(ctx, "RollR(90) Left(90) F(1)", NULL, 0, 0, 0, 0, 0, 0, 1);
    /* corrected rotation: off reverses them, as lpfg */
    check_seg(ctx, "Down(90) F(1)", "corrected rotation: off\n", 0, 0, 0, 0, 0, 0, 1);
    check_seg(ctx, "RollL(90) Left(90) F(1)", "corrected rotation: off\n", 0, 0, 0, 0, 0, 0, 1);
    /* SetHead(H, U): then Left turns towards lpfg's L = U x H */
    check_seg(ctx, "SetHead(2, 0, 0, 0, 0, 3) F(1)", NULL, 0, 0, 0, 0, 1, 0, 0);
    check_seg(ctx, "SetHead(1, 0, 0, 0, 0, 1) Left(90) F(1)", NULL, 0, 0, 0, 0, 0, 1, 0);
    check_seg(ctx, "SetHead(0, 0, 0, 0, 0, 1) F(1)", NULL, 0, 0, 0, 0, 0, 1, 0); /* ignored */
    /* RollToVert: L horizontal (y x H), -x when H is vertical */
    check_seg(ctx, "Left(90) RollL(30) RollToVert Left(90) F(1)", NULL, 0, 0, 0, 0, 0, 0, 1);
    check_seg(ctx, "RollL(90) RollToVert Left(90) F(1)", NULL, 0, 0, 0, 0, -1, 0, 0);
    test_ctx_end(ctx);
}

TEST(lpfg_modules_lines_and_moves)
{
    cbm_context *ctx = test_ctx();
    /* LineTo3d draws to the point and keeps the heading */
    check_seg(ctx, "LineTo3d(V3f(3, 4, 0)) F(1)", NULL, 0, 0, 0, 0, 3, 4, 0);
    check_seg(ctx, "LineTo3d(V3f(3, 4, 0)) F(1)", NULL, 1, 3, 4, 0, 3, 5, 0);
    check_seg(ctx, "f(1) LineRel3d(V3f(0, 0, 2))", NULL, 0, 0, 1, 0, 0, 1, 2);
    check_seg(ctx, "MoveRel3d(V3f(1, 0, 0)) F(1)", NULL, 0, 1, 0, 0, 1, 1, 0);
    check_seg(ctx, "F(1) MoveTo3d(V3f(0, 5, 0)) F(1)", NULL, 1, 0, 5, 0, 0, 6, 0);
    test_ctx_end(ctx);
}

TEST(lpfg_modules_spheres_colours_widths)
{
    cbm_context *ctx = test_ctx();
    cbm_turtle *t = axiom_turtle(ctx, "Sphere(2) SetWidth(3) Sphere0() Circle(1) Circle0()", NULL);
    const cbm_prim *p;
    CHECK((p = nth_prim(t, CBM_PRIM_SPHERE, 0)) && fabs(p->r0 - 2.0) < 1e-12);
    CHECK((p = nth_prim(t, CBM_PRIM_SPHERE, 1)) && fabs(p->r0 - 1.5) < 1e-12);
    CHECK((p = nth_prim(t, CBM_PRIM_DISC, 0)) && fabs(p->r0 - 1.0) < 1e-12);
    CHECK((p = nth_prim(t, CBM_PRIM_DISC, 1)) && fabs(p->r0 - 1.5) < 1e-12);
    cbm_turtle_destroy(t);
    /* colours: 1 at the start; SetColor outside 1..255 ignored; IncColor 255 -> 1, DecColor
     * 1 -> 255 */
    t = axiom_turtle(ctx,
                     "F(1) SetColor(7) F(1) SetColor(0) F(1) SetColor(300) F(1) IncColor() F(1) "
                     "DecColor() DecColor() F(1) SetColor(255) IncColor() F(1) DecColor() F(1)",
                     NULL);
    static const int want[] = {1, 7, 7, 7, 8, 6, 1, 255};
    for (size_t k = 0; k < sizeof want / sizeof want[0]; k++) {
        p = nth_prim(t, CBM_PRIM_CYLINDER, k);
        CHECK_MSG(p && p->color == want[k], "cylinder %zu colour %d, not %d", k, p ? p->color : -1,
                  want[k]);
    }
    cbm_turtle_destroy(t);
    /* each F is its own cylinder of the width at the F (lpfg), not a cone to the next width */
    t = axiom_turtle(ctx, "SetWidth(2) F(1) SetWidth(4) F(1)", NULL);
    CHECK((p = nth_prim(t, CBM_PRIM_CYLINDER, 0)) && p->r0 == 1.0 && p->r1 == 1.0);
    CHECK((p = nth_prim(t, CBM_PRIM_CYLINDER, 1)) && p->r0 == 2.0 && p->r1 == 2.0);
    cbm_turtle_destroy(t);
    /* ScaleContour(p, q): an elliptic section, width p along L (x here), q along U (z) */
    static const char *const sc[] = {"ScaleContour(2, 4) F(1)",
                                     "ScaleContour(2, 4) SetWidth(2) F(1)"};
    for (int k = 0; k < 2; k++) {
        cbm_scene *scene = NULL;
        CHECK_OK(cbm_scene_create(ctx, &scene));
        t = axiom_turtle_scene(ctx, sc[k], NULL, scene);
        cbm_vec3 lo, hi;
        CHECK(cbm_scene_bounds(scene, &lo, &hi));
        CHECK_NEAR(hi.x, 1.0, 1e-9);
        CHECK_NEAR(hi.z, k == 0 ? 2.0 : 1.0, 1e-9);
        CHECK_NEAR(lo.z, k == 0 ? -2.0 : -1.0, 1e-9);
        cbm_turtle_destroy(t);
        cbm_scene_destroy(scene);
    }
    test_ctx_end(ctx);
}

/* lpfg's line styles: with a view file, the view's style, pixel by default (lpfg's default, as
 * cpfg's): in a picture's line-mode scene SetWidth(w) gives lines w pixels wide, as lpfg draws
 * them on screen (hormone-up: SetWidth(5) and F(1) is a 5-pixel line, not a tube 5 units across);
 * in a mesh scene, tubes of diameter w, as lpfg's OBJ export. Without a view file (cambium's own
 * models in metres), tubes. */
TEST(lpfg_line_widths)
{
    cbm_context *ctx = test_ctx();
    static const struct {
        const char *view;
        bool line_mode;
        size_t lines;
        bool tubes;
    } cases[] = {
        {"corrected rotation: on\n", true, 2, false}, /* pixel by default */
        {"line style: pixel\n", true, 2, false},
        {"line style: cylinder\n", true, 0, true},
        {"corrected rotation: on\n", false, 0, true}, /* a mesh: tubes of diameter w */
        {NULL, true, 0, true},                        /* no view file */
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        cbm_scene *scene = NULL;
        CHECK_OK(cbm_scene_create(ctx, &scene));
        if (!scene)
            break;
        cbm_scene_set_line_mode(scene, cases[k].line_mode);
        cbm_turtle *t =
            axiom_turtle_scene(ctx, "SetWidth(5) F(1) SetWidth(3) F(1)", cases[k].view, scene);
        CHECK_MSG(cbm_scene_line_count(scene) == cases[k].lines, "case %zu: %zu lines", k,
                  cbm_scene_line_count(scene));
        CHECK_MSG((cbm_scene_triangle_count(scene) > 0) == cases[k].tubes, "case %zu: %zu tris", k,
                  cbm_scene_triangle_count(scene));
        if (cbm_scene_line_count(scene) == 2) {
            CHECK_NEAR(cbm_scene_lines(scene)[0].width, 5.0, 1e-6);
            CHECK_NEAR(cbm_scene_lines(scene)[1].width, 3.0, 1e-6);
        }
        if (cases[k].tubes) {
            cbm_vec3 lo, hi;
            CHECK(cbm_scene_bounds(scene, &lo, &hi));
            CHECK_NEAR(hi.x, 2.5, 1e-6); /* the first tube's radius: half the width */
        }
        /* the record is the same whatever the style: cylinders of radius w / 2 */
        const cbm_prim *p = nth_prim(t, CBM_PRIM_CYLINDER, 0);
        CHECK(p && p->r0 == 2.5);
        cbm_turtle_destroy(t);
        cbm_scene_destroy(scene);
    }
    test_ctx_end(ctx);
}

/* How many vertices of scene part `cur` lie on its first ring (at distance r0 from p0, the
 * connection's first control point) and how many of those are vertices of part `prev` too, at
 * the same point with the same normal (no gap, no seam); *rmin: the nearest of `cur`'s vertices
 * to p0 (a pinched cylinder would come close to its spine). */
static void first_ring_shared(const cbm_scene *scene, size_t prev, size_t cur, cbm_vec3 p0,
                              double r0, size_t *ring, size_t *matched, double *rmin)
{
    size_t nt = cbm_scene_triangle_count(scene);
    const uint32_t *tri = cbm_scene_triangles(scene), *tp = cbm_scene_triangle_parts(scene);
    const cbm_scene_vertex *v = cbm_scene_vertices(scene);
    *ring = *matched = 0;
    *rmin = INFINITY;
    for (size_t i = 0; i < nt; i++) {
        if (tp[i] != cur)
            continue;
        for (int k = 0; k < 3; k++) {
            const cbm_scene_vertex *a = &v[tri[3 * i + (size_t)k]];
            cbm_vec3 d = {a->p[0] - p0.x, a->p[1] - p0.y, a->p[2] - p0.z};
            double r = sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
            *rmin = fmin(*rmin, r);
            if (fabs(r - r0) > 1e-5 * fmax(1, r0))
                continue; /* not on the first ring */
            (*ring)++;
            bool found = false;
            for (size_t j = 0; j < nt && !found; j++) {
                if (tp[j] != prev)
                    continue;
                for (int m = 0; m < 3 && !found; m++) {
                    const cbm_scene_vertex *b = &v[tri[3 * j + (size_t)m]];
                    found = !memcmp(a->p, b->p, sizeof a->p) && fabs(a->n[0] - b->n[0]) +
                                                                        fabs(a->n[1] - b->n[1]) +
                                                                        fabs(a->n[2] - b->n[2]) <
                                                                    1e-6;
                }
            }
            *matched += found;
        }
    }
}

/* An axis drawn as one generalized cylinder (StartGC, SetWidth PointGC at every node): the
 * first ring of each connection is the last ring of the one before, point for point and normal
 * for normal (no gap, no seam), across a branch opened on the way; the radius never reaches 0;
 * every connection's end is closed by a disc (lpfg's turtle). */
TEST(lpfg_gc_axis_is_continuous)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *scene = NULL;
    CHECK_OK(cbm_scene_create(ctx, &scene));
    if (!scene) {
        test_ctx_end(ctx);
        return;
    }
    cbm_turtle *t =
        axiom_turtle_scene(ctx,
                           "SetWidth(0.4) StartGC() f(1) SetWidth(0.3) PointGC() "
                           "SB() Left(60) SetWidth(0.1) StartGC() f(0.5) PointGC() EB() "
                           "RollL(70) Left(30) f(1) SetWidth(0.2) PointGC() Right(40) "
                           "f(1) SetWidth(0.1) PointGC()",
                           NULL, scene);
    /* parts: the axis's three connections and the lateral's one, in the order drawn */
    CHECK_EQ_INT(cbm_scene_part_count(scene), 4);
    /* the axis's connections are parts 0, 2, 3: each one's start ring (its vertices on the
     * plane through its first control point) must be vertices of the previous connection */
    static const uint32_t axis[3] = {0, 2, 3};
    for (int c = 1; c < 3; c++) {
        size_t matched = 0, ring = 0;
        double rmin = INFINITY;
        const cbm_prim *pr = nth_prim(t, CBM_PRIM_GCYL, (size_t)(c == 1 ? 2 : 3));
        if (!pr)
            break;
        first_ring_shared(scene, axis[c - 1], axis[c], pr->p0, pr->r0, &ring, &matched, &rmin);
        CHECK_MSG(ring > 0 && matched == ring,
                  "connection %d: %zu of %zu first-ring vertices shared", c, matched, ring);
        CHECK_MSG(rmin > 0.04, "connection %d: a vertex %g from its first control point", c, rmin);
    }
    /* the lateral starts on the axis inside it: its first ring's radius 0.05 < the axis's 0.15 */
    const cbm_prim *lat = nth_prim(t, CBM_PRIM_GCYL, 1);
    CHECK_MSG(lat && fabs(lat->r0 - 0.05) < 1e-7 && fabs(lat->p0.y - 1.0) < 1e-12,
              "lateral r0 %g y %g", lat ? lat->r0 : -1, lat ? lat->p0.y : -1);
    cbm_turtle_destroy(t);
    cbm_scene_destroy(scene);
    test_ctx_end(ctx);
}

/* The shipped L+C models draw each axis as one generalized cylinder (issue 9): the S-shaped
 * branch (one axis) and the cherries (three stems) as drawn, at the end of their runs. No
 * internode is a cylinder of its own: every mechanical segment is one connection of its axis's
 * cylinder, from its proximal to its distal node (the segment table's positions) with the
 * diameters 2a at its ends, and every connection after an axis's first starts on the last ring
 * of the one before, point for point and normal for normal, never pinched (no vertex nearer
 * its spine than half its radius). */
static void check_model_axes(cbm_context *ctx, const char *model, size_t axes, size_t segs)
{
    char path[2048];
    snprintf(path, sizeof path, "%s/models/%s", test_source_dir(), model);
    cbm_model_def def = {cbm_lsys_def_default(), NULL, 0};
    def.lsys.path = path;
    cbm_model *m = NULL;
    cbm_scene *scene = NULL;
    cbm_turtle *t = NULL;
    cbm_plant *pl = NULL;
    CHECK_OK(cbm_model_load(ctx, &def, &m));
    CHECK_OK(cbm_scene_create(ctx, &scene));
    if (!m || !scene) {
        cbm_model_destroy(m);
        cbm_scene_destroy(scene);
        return;
    }
    CHECK_OK(cbm_model_reset(m));
    for (int k = 0; k < cbm_lsys_derivation_length(cbm_model_lsys(m)); k++)
        CHECK_OK(cbm_model_step(m));
    CHECK_OK(cbm_model_interpret(m, scene, true, &t));
    CHECK_OK(cbm_lsys_mech_plant(cbm_model_lsys(m), &pl));
    size_t n = pl ? cbm_plant_segment_count(pl) : 0;
    CHECK_EQ_INT(n, segs);
    CHECK_MSG(!nth_prim(t, CBM_PRIM_CYLINDER, 0), "%s: an internode drawn as a cylinder", model);
    /* the connections in string order, one per segment, their parts (the branch parts: the
     * cherries are parts too) in the same order */
    const cbm_part *parts = cbm_scene_parts(scene);
    size_t starts = 0, np = cbm_scene_part_count(scene), nb = 0;
    enum { MAXP = 64 };
    size_t branch[MAXP];
    for (size_t k = 0; k < np && nb < MAXP; k++)
        if (parts[k].organ == CBM_ORGAN_BRANCH)
            branch[nb++] = k;
    CHECK_EQ_INT(nb, n);
    for (size_t i = 0; i < n; i++) {
        const cbm_prim *pr = nth_prim(t, CBM_PRIM_GCYL, i);
        cbm_segment_state x;
        CHECK_OK(cbm_plant_segment(pl, i, &x));
        if (!pr)
            break;
        double e = fabs(pr->p0.x - x.proximal.x) + fabs(pr->p0.y - x.proximal.y) +
                   fabs(pr->p0.z - x.proximal.z) + fabs(pr->p1.x - x.distal.x) +
                   fabs(pr->p1.y - x.distal.y) + fabs(pr->p1.z - x.distal.z);
        CHECK_MSG(e < 1e-5 * x.length && fabs(pr->r1 - x.a) < 1e-6 * x.a,
                  "%s: connection %zu off its segment by %g (r1 %.17g, a %.17g, length %g)", model,
                  i, e, pr->r1, x.a, x.length);
        bool first = i == 0 || x.parent < 0 || (size_t)x.parent != i - 1;
        starts += first;
        if (first || i >= nb)
            continue;
        size_t ring = 0, matched = 0;
        double rmin = INFINITY;
        first_ring_shared(scene, branch[i - 1], branch[i], pr->p0, pr->r0, &ring, &matched, &rmin);
        CHECK_MSG(ring > 0 && matched == ring,
                  "%s: connection %zu: %zu of %zu first-ring vertices shared", model, i, matched,
                  ring);
        CHECK_MSG(rmin > 0.5 * pr->r0, "%s: connection %zu pinched: a vertex %g from its start",
                  model, i, rmin);
    }
    CHECK_EQ_INT(starts, axes);
    CHECK(!nth_prim(t, CBM_PRIM_GCYL, n)); /* no connection beyond the segments */
    cbm_plant_destroy(pl);
    cbm_turtle_destroy(t);
    cbm_scene_destroy(scene);
    cbm_model_destroy(m);
}

TEST(lpfg_model_axes_are_continuous)
{
    cbm_context *ctx = test_ctx();
    check_model_axes(ctx, "jirasek-s-branch.l", 1, 30);
    check_model_axes(ctx, "jirasek-cherries.l", 3, 24);
    test_ctx_end(ctx);
}

/* models/jirasek-grapes.l as drawn: 15 berries, spheres where the contact puts them, no two
 * overlapping by more than 0.3 mm (the contact's penalty lets 0.17 mm; without the contact,
 * -D K=0, they pass 8 mm into each other). Each berry's centre and radius are recovered from its
 * sphere's vertices. */
static double drawn_grapes_overlap(cbm_context *ctx, const char *define, size_t *berries)
{
    char path[2048];
    snprintf(path, sizeof path, "%s/models/jirasek-grapes.l", test_source_dir());
    cbm_model_def def = {cbm_lsys_def_default(), NULL, 0};
    def.lsys.path = path;
    def.lsys.defines = define ? &define : NULL;
    def.lsys.define_count = define ? 1 : 0;
    cbm_model *m = NULL;
    cbm_scene *scene = NULL;
    cbm_turtle *t = NULL;
    double worst = -INFINITY;
    *berries = 0;
    CHECK_OK(cbm_model_load(ctx, &def, &m));
    CHECK_OK(cbm_scene_create(ctx, &scene));
    if (!m || !scene) {
        cbm_model_destroy(m);
        cbm_scene_destroy(scene);
        return worst;
    }
    CHECK_OK(cbm_model_reset(m));
    for (int k = 0; k < cbm_lsys_derivation_length(cbm_model_lsys(m)); k++)
        CHECK_OK(cbm_model_step(m));
    CHECK_OK(cbm_model_interpret(m, scene, false, &t));
    size_t np = cbm_scene_part_count(scene), nt = cbm_scene_triangle_count(scene);
    const cbm_part *parts = cbm_scene_parts(scene);
    const uint32_t *tri = cbm_scene_triangles(scene), *tp = cbm_scene_triangle_parts(scene);
    const cbm_scene_vertex *v = cbm_scene_vertices(scene);
    enum { MAXB = 64 };
    double c[MAXB][3], r[MAXB];
    size_t nb = 0;
    for (size_t k = 0; k < np && nb < MAXB; k++) {
        if (parts[k].organ != CBM_ORGAN_FRUIT)
            continue;
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (size_t i = 0; i < nt; i++)
            for (int j = 0; tp[i] == k && j < 3; j++)
                for (int d = 0; d < 3; d++) {
                    lo[d] = fmin(lo[d], v[tri[3 * i + (size_t)j]].p[d]);
                    hi[d] = fmax(hi[d], v[tri[3 * i + (size_t)j]].p[d]);
                }
        for (int d = 0; d < 3; d++)
            c[nb][d] = 0.5 * (lo[d] + hi[d]);
        r[nb] = 0.5 * (hi[1] - lo[1]); /* poles along y: the full radius */
        nb++;
    }
    for (size_t i = 0; i < nb; i++)
        for (size_t j = i + 1; j < nb; j++) {
            double dx = c[i][0] - c[j][0], dy = c[i][1] - c[j][1], dz = c[i][2] - c[j][2];
            worst = fmax(worst, r[i] + r[j] - sqrt(dx * dx + dy * dy + dz * dz));
        }
    *berries = nb;
    cbm_turtle_destroy(t);
    cbm_scene_destroy(scene);
    cbm_model_destroy(m);
    return worst;
}

TEST(lpfg_grapes_drawn_apart)
{
    cbm_context *ctx = test_ctx();
    size_t n = 0;
    double ov = drawn_grapes_overlap(ctx, NULL, &n);
    printf("grapes as drawn: %zu berries, largest overlap %.3g mm\n", n, ov * 1e3);
    CHECK_EQ_INT(n, 15);
    CHECK_MSG(ov < 3e-4, "drawn berries overlap by %g m", ov);
    ov = drawn_grapes_overlap(ctx, "K=0", &n);
    printf("grapes without contact, as drawn: largest overlap %.3g mm\n", ov * 1e3);
    CHECK(n == 15 && ov > 3e-3);
    test_ctx_end(ctx);
}

/* Every allocation of an lpfg run (func names, the function set, spheres) may fail: a clean
 * status and no leak each time. */
static cbm_status oom_run(cbm_context *ctx, void *ud)
{
    (void)ud;
    const char *sides[] = {ORACLE "lpfg-sympodial/model/view.v",
                           ORACLE "lpfg-sympodial/model/functions.fset"};
    cbm_model_def def = {cbm_lsys_def_default(), sides, 2};
    def.lsys.path = ORACLE "lpfg-sympodial/model/lsystem.l";
    cbm_model *m = NULL;
    cbm_status s = cbm_model_load(ctx, &def, &m);
    if (s != CBM_OK)
        return s;
    cbm_scene *scene = NULL;
    cbm_turtle *t = NULL;
    s = cbm_model_reset(m);
    for (int k = 0; k < 20 && s == CBM_OK; k++)
        s = cbm_model_step(m);
    if (s == CBM_OK)
        s = cbm_scene_create(ctx, &scene);
    if (s == CBM_OK)
        s = cbm_model_interpret(m, scene, true, &t);
    if (s == CBM_OK && !nth_prim(t, CBM_PRIM_SPHERE, 0))
        s = CBM_E_INTERNAL;
    cbm_turtle_destroy(t);
    cbm_scene_destroy(scene);
    cbm_model_destroy(m);
    return s;
}

TEST(lpfg_allocation_failures)
{
    if (test_skip_without_oracles())
        return;
    CHECK(test_oom_loop(oom_run, NULL) > 10);
}
