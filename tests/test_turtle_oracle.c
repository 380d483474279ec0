/* Geometry of the turtle against cpfg's own outputs (../shared/oracles/vlab/cpfg-*).
 *
 * For each model, the string cpfg interpreted is taken from the oracle, not derived here:
 * ref/final.homo.str (after the homomorphism, cpfg's %g notation, line-wrapped) when the model has
 * a homomorphism, else ref/final.exact.txt (one module per line, exact float32 parameters). The
 * string runs through our turtle with the model's view file and colour map or materials, and we
 * compare with ref/final.ray.gz (cylinders and cones with end points and radii, polygons,
 * spheres, discs, in order) and with the bounding box of ref/final.vv.
 * Tolerances: points and radii within 1e-5 * (1 + |value|) + 1e-5 * scale, where scale is the
 * largest extent of the box (the .ray file prints 6 significant digits, and final.homo.str's
 * parameters have 6 digits too, which accumulates along long branches); box within 1e-4 * scale.
 */
#define _POSIX_C_SOURCE 200809L
#include "oracle_geometry.h"

#include <stdlib.h>
#include <string.h>

/* ---- reading the string ---- */

typedef struct modlist {
    cbm_tmodule *m;
    char (*name)[4];
    double *par;
    size_t n, cap, npar, parcap;
} modlist;

static void parse_string(const char *text, modlist *L)
{
    size_t len = strlen(text);
    char *s = malloc(len + 1);
    size_t k = 0;
    for (size_t i = 0; i < len; i++)
        if (text[i] != '\n' && text[i] != '\r')
            s[k++] = text[i];
    s[k] = 0;
    /* raw modules */
    size_t cap = k + 1;
    char *sym = malloc(cap);
    int *np = malloc(cap * sizeof(int));
    size_t *pf = malloc(cap * sizeof(size_t));
    double *par = malloc((k + 1) * sizeof(double));
    size_t nraw = 0, npar = 0;
    const char *p = s;
    while (*p) {
        if (*p == ' ') {
            p++;
            continue;
        }
        sym[nraw] = *p++;
        np[nraw] = 0;
        pf[nraw] = npar;
        if (*p == '(') {
            p++;
            for (;;) {
                char *end;
                double v = strtod(p, &end);
                if (end == p)
                    break;
                par[npar++] = v;
                np[nraw]++;
                p = end;
                if (*p == ',')
                    p++;
                else
                    break;
            }
            if (*p == ')')
                p++;
        }
        nraw++;
    }
    L->m = malloc((nraw + 1) * sizeof *L->m);
    L->name = malloc((nraw + 1) * sizeof *L->name);
    L->par = par;
    L->n = 0;
    /* one module per symbol: the turtle combines @, ? and ~ with what follows, as cpfg */
    for (size_t i = 0; i < nraw; i++) {
        char nm[4] = {sym[i], 0, 0, 0};
        memcpy(L->name[L->n], nm, 4);
        L->m[L->n].nparams = np[i];
        L->m[L->n].params = par + pf[i];
        L->n++;
    }
    for (size_t i = 0; i < L->n; i++)
        L->m[i].name = L->name[i];
    free(s);
    free(sym);
    free(np);
    free(pf);
}

static void modlist_free(modlist *L)
{
    free(L->m);
    free(L->name);
    free(L->par);
}

static void run_model(const oracle_model *md, bool compare_prims)
{
    if (test_skip_without_oracles())
        return;
    char path[1024];
    cbm_context *ctx = test_ctx();
    cbm_view *view = NULL;
    snprintf(path, sizeof path, ORACLE "%s/model/%s", md->dir, md->view);
    CHECK_OK(cbm_view_load(ctx, path, &view));
    if (!view) {
        test_ctx_end(ctx);
        return;
    }
    if (md->colors) {
        snprintf(path, sizeof path, ORACLE "%s/model/%s", md->dir, md->colors);
        CHECK_OK(cbm_view_load_side_file(view, path));
    }
    snprintf(path, sizeof path, ORACLE "%s/ref/%s", md->dir,
             md->homo ? "final.homo.str" : "final.exact.txt");
    char *text = oracle_slurp(path, NULL);
    CHECK_MSG(text != NULL, "cannot read %s", path);
    if (!text) {
        cbm_view_destroy(view);
        test_ctx_end(ctx);
        return;
    }
    modlist L;
    parse_string(text, &L);
    free(text);

    cbm_scene *scene = NULL;
    CHECK_OK(cbm_scene_create(ctx, &scene));
    cbm_turtle *t = NULL;
    cbm_turtle_def def = {true};
    CHECK_OK(cbm_turtle_interpret(ctx, view, &def, L.m, L.n, scene, &t));
    if (t) {
        oracle_check_geometry(md, t, scene, L.n, compare_prims);
        cbm_turtle_destroy(t);
    }
    cbm_scene_destroy(scene);
    modlist_free(&L);
    cbm_view_destroy(view);
    test_ctx_end(ctx);
}

TEST(quadratic_koch)
{
    run_model(oracle_cpfg_model("quadratic_koch"), true);
}

TEST(compound_homo)
{
    run_model(oracle_cpfg_model("compound_homo"), true);
}

TEST(compound_param)
{
    run_model(oracle_cpfg_model("compound_param"), true);
}

TEST(continuous_decomp)
{
    run_model(oracle_cpfg_model("continuous_decomp"), true);
}

TEST(florigen_param)
{
    run_model(oracle_cpfg_model("florigen_param"), true);
}

TEST(hormone_up)
{
    run_model(oracle_cpfg_model("hormone_up"), true);
}

TEST(monopodial)
{
    run_model(oracle_cpfg_model("monopodial"), true);
}

TEST(sympodial)
{
    run_model(oracle_cpfg_model("sympodial"), true);
}

TEST(random_moss)
{
    run_model(oracle_cpfg_model("random_moss"), true);
}

TEST(weeping_birch)
{
    run_model(oracle_cpfg_model("weeping_birch"), true);
}

/* cpfg's oracle has no string after the homomorphism of this model, whose spheres and cylinders
 * come from it: the discs (@c of the derived string itself) are compared, and the box must
 * contain ours. */
TEST(query_position)
{
    oracle_model m = *oracle_cpfg_model("query_position");
    m.only_kind = CBM_PRIM_DISC;
    run_model(&m, true);
}

TEST(leaf_rnd)
{
    run_model(oracle_cpfg_model("leaf_rnd"), true);
}

TEST(tropisms)
{
    run_model(oracle_cpfg_model("tropisms"), true);
}

TEST(lilac)
{
    run_model(oracle_cpfg_model("lilac"), true);
}

/* The lilac's petals and calyxes (predefined surfaces) in a scene in instancing mode: each is a
 * placement of its surface's mesh, and the placement's map applied to the mesh gives the
 * triangles the turtle adds without instancing (same part, same order), points to 4e-7 of the
 * scene's size and normals (inverse transpose) to 1e-6 (found: 1.0e-7 and 8.5e-8). The .glb's TRS
 * of a placement is checked against its map in test_io_write (glb_surface_placements). */
TEST(lilac_surface_placements)
{
    if (test_skip_without_oracles())
        return;
    cbm_context *ctx = test_ctx();
    cbm_view *view = NULL;
    CHECK_OK(cbm_view_load(ctx, ORACLE "cpfg-lilac/model/plant.v", &view));
    char *text = oracle_slurp(ORACLE "cpfg-lilac/ref/final.homo.str", NULL);
    CHECK(view && text);
    if (!view || !text) {
        free(text);
        cbm_view_destroy(view);
        test_ctx_end(ctx);
        return;
    }
    CHECK_OK(cbm_view_load_side_file(view, ORACLE "cpfg-lilac/model/materials.mat"));
    modlist L;
    parse_string(text, &L);
    free(text);
    cbm_scene *sc[2] = {NULL, NULL};
    for (int k = 0; k < 2; k++) {
        CHECK_OK(cbm_scene_create(ctx, &sc[k]));
        cbm_scene_set_instancing(sc[k], k == 1);
        cbm_turtle *t = NULL;
        cbm_turtle_def def = {true};
        CHECK_OK(cbm_turtle_interpret(ctx, view, &def, L.m, L.n, sc[k], &t));
        cbm_turtle_destroy(t);
    }
    cbm_scene *sm = sc[0], *si = sc[1];
    size_t np = cbm_scene_placement_count(si), nparts = cbm_scene_part_count(sm);
    CHECK(np > 100 && cbm_scene_shape_count(si) == 2);
    /* the instanced segments of one order and colour share parts (cbm_scene_begin_part_shared):
     * a placement's part is found in the triangle scene by its module (segment id), in order */
    CHECK(cbm_scene_part_count(si) <= nparts);
    const cbm_part *psi = cbm_scene_parts(si), *psm = cbm_scene_parts(sm);
    size_t jm = 0;
    /* the first triangle of each part of the triangle scene */
    size_t ntm = cbm_scene_triangle_count(sm);
    const uint32_t *tpm = cbm_scene_triangle_parts(sm), *trm = cbm_scene_triangles(sm);
    size_t *first = malloc((nparts + 1) * sizeof *first);
    for (size_t i = 0; first && i <= nparts; i++)
        first[i] = SIZE_MAX;
    for (size_t t = ntm; first && t-- > 0;)
        first[tpm[t]] = t;
    cbm_vec3 lo, hi;
    CHECK(cbm_scene_bounds(sm, &lo, &hi));
    double size = fmax(hi.x - lo.x, fmax(hi.y - lo.y, hi.z - lo.z)), worst_p = 0, worst_n = 0;
    const cbm_scene_placement *pl = cbm_scene_placements(si);
    const cbm_scene_vertex *vm = cbm_scene_vertices(sm);
    size_t checked = 0;
    for (size_t i = 0; first && i < np; i++) {
        const float *pos, *nrm;
        const uint32_t *tri;
        size_t nv, nt;
        CHECK_OK(cbm_scene_shape_mesh(si, pl[i].shape, &pos, &nrm, &nv, &tri, &nt));
        const cbm_part *pp = &psi[pl[i].part];
        while (jm < nparts && (psm[jm].segment != pp->segment || psm[jm].organ != pp->organ))
            jm++;
        CHECK(jm < nparts);
        if (jm >= nparts)
            break;
        size_t t0 = first[jm];
        CHECK(t0 != SIZE_MAX && t0 + nt <= ntm);
        if (t0 == SIZE_MAX || t0 + nt > ntm)
            break;
        /* the inverse transpose, up to a positive factor: cofactors signed by the determinant */
        const float *x = pl[i].x, *y = pl[i].y, *z = pl[i].z;
        double c[3][3];
        for (int r = 0; r < 3; r++) {
            int a = (r + 1) % 3, b = (r + 2) % 3;
            c[0][r] = (double)y[a] * z[b] - (double)y[b] * z[a];
            c[1][r] = (double)z[a] * x[b] - (double)z[b] * x[a];
            c[2][r] = (double)x[a] * y[b] - (double)x[b] * y[a];
        }
        double det = x[0] * c[0][0] + x[1] * c[0][1] + x[2] * c[0][2];
        for (size_t t = 0; t < nt; t++) {
            CHECK(tpm[t0 + t] == jm);
            for (int k = 0; k < 3; k++) {
                const float *q = pos + 3 * tri[3 * t + (size_t)k];
                const float *n = nrm + 3 * tri[3 * t + (size_t)k];
                const cbm_scene_vertex *w = &vm[trm[3 * (t0 + t) + (size_t)k]];
                double wn[3], len = 0;
                for (int r = 0; r < 3; r++) {
                    double p = pl[i].o[r] + (double)x[r] * q[0] + (double)y[r] * q[1] +
                               (double)z[r] * q[2];
                    worst_p = fmax(worst_p, fabs(p - w->p[r]));
                    wn[r] = (det < 0 ? -1 : 1) * (c[0][r] * n[0] + c[1][r] * n[1] + c[2][r] * n[2]);
                    len += wn[r] * wn[r];
                }
                for (int r = 0; r < 3; r++)
                    worst_n = fmax(worst_n, fabs(wn[r] / sqrt(len) - w->n[r]));
            }
            checked++;
        }
    }
    CHECK(checked > 1000);
    CHECK_MSG(worst_p <= 4e-7 * size, "points: %g (size %g)", worst_p, size);
    CHECK_MSG(worst_n <= 1e-6, "normals: %g", worst_n);
    free(first);
    cbm_scene_destroy(sm);
    cbm_scene_destroy(si);
    modlist_free(&L);
    cbm_view_destroy(view);
    test_ctx_end(ctx);
}

/* func(id, x) against cpfg: in cpfg-monopodial the homomorphism maps I(t) to
 * F(0.5 func(1, t/20)) and L(t) to ;F(1.5 func(2, t/20)), so the F parameters of cpfg's string
 * after the homomorphism (6 significant digits) give cpfg's function values at the t of
 * final.exact.txt. */
TEST(function_values_monopodial)
{
    if (test_skip_without_oracles())
        return;
    cbm_context *ctx = test_ctx();
    cbm_view *view = NULL;
    CHECK_OK(cbm_view_load(ctx, ORACLE "cpfg-monopodial/model/leaf.v", &view));
    char *exact = oracle_slurp(ORACLE "cpfg-monopodial/ref/final.exact.txt", NULL);
    char *homo = oracle_slurp(ORACLE "cpfg-monopodial/ref/final.homo.str", NULL);
    CHECK(view && exact && homo);
    if (view && exact && homo) {
        modlist E, H;
        parse_string(exact, &E);
        parse_string(homo, &H);
        const cbm_funcset *fs = cbm_view_functions(view);
        CHECK_EQ_INT(cbm_funcset_count(fs), 2);
        size_t j = 0, checked = 0;
        double worst = 0.0;
        for (size_t i = 0; i < E.n; i++) {
            char c = E.m[i].name[0];
            if ((c != 'I' && c != 'L') || E.m[i].nparams != 1)
                continue;
            while (j < H.n && H.m[j].name[0] != 'F')
                j++;
            if (j >= H.n)
                break;
            double cpfg = H.m[j++].params[0];
            double x = (float)(E.m[i].params[0] / 20.0);
            double ours =
                c == 'I' ? 0.5 * cbm_funcset_value(fs, 1, x) : 1.5 * cbm_funcset_value(fs, 2, x);
            double dev = fabs(ours - cpfg) / fmax(fabs(cpfg), 1e-3);
            if (dev > worst)
                worst = dev;
            checked++;
        }
        CHECK(checked > 100);
        CHECK_MSG(worst < 1e-5, "largest relative deviation from cpfg's func values: %g", worst);
        fprintf(stderr, "func: %zu values checked against cpfg, largest relative deviation %.2g\n",
                checked, worst);
        modlist_free(&E);
        modlist_free(&H);
    }
    free(exact);
    free(homo);
    cbm_view_destroy(view);
    test_ctx_end(ctx);
}

/* A function gallery (.fset, lpfg-sympodial) holds the same curves as cpfg-sympodial's .func
 * files, tabulated at 100 samples instead of 10: found by name, and equal where both tables
 * sample the same x (x = k/9 is not a multiple of 1/99 except at 0 and 1; compare there and
 * require closeness elsewhere). */
TEST(function_gallery)
{
    if (test_skip_without_oracles())
        return;
    cbm_context *ctx = test_ctx();
    cbm_view *view = NULL;
    CHECK_OK(cbm_view_create(ctx, &view));
    CHECK_OK(cbm_view_load_side_file(view, ORACLE "lpfg-sympodial/model/functions.fset"));
    CHECK_OK(cbm_view_add_function(view, ORACLE "cpfg-sympodial/model/internode.func", -1));
    CHECK_OK(cbm_view_add_function(view, ORACLE "cpfg-sympodial/model/flower.func", -1));
    const cbm_funcset *fs = cbm_view_functions(view);
    CHECK_EQ_INT(cbm_funcset_count(fs), 4);
    CHECK_EQ_INT(cbm_funcset_find(fs, "flower"), 1);
    CHECK_EQ_INT(cbm_funcset_find(fs, "internode"), 2);
    CHECK_EQ_INT(cbm_funcset_find(fs, "leaf"), 0);
    for (int i = 0; i <= 20; i++) {
        double x = i / 20.0;
        CHECK_NEAR(cbm_funcset_value(fs, 2, x), cbm_funcset_value(fs, 3, x), 2e-2);
        CHECK_NEAR(cbm_funcset_value(fs, 1, x), cbm_funcset_value(fs, 4, x), 2e-2);
    }
    CHECK_NEAR(cbm_funcset_value(fs, 2, 0.0), cbm_funcset_value(fs, 3, 0.0), 1e-12);
    CHECK_NEAR(cbm_view_func_callback(view, 1, 1.0), cbm_funcset_value(fs, 4, 1.0), 1e-12);
    cbm_view_destroy(view);
    test_ctx_end(ctx);
}
