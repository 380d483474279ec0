/* Unit tests of the turtle commands against hand-computed frames, and of the view, function,
 * surface and contour readers. The turtle starts at the origin with cpfg's frame H = +y,
 * L = -x, U = -z. */
#include "test.h"

#include "core/vecmath.h"
#include "turtle/view_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define TOL 1e-12

/* Builds modules from a space-separated string like "F(2) + ?P(0,0,0)". */
typedef struct prog {
    cbm_tmodule m[64];
    char name[64][4];
    double par[64][4];
    size_t n;
} prog;

static void parse(prog *p, const char *s)
{
    memset(p, 0, sizeof *p);
    while (*s) {
        while (*s == ' ')
            s++;
        if (!*s)
            break;
        size_t i = p->n++;
        size_t k = 0;
        while (*s && *s != ' ' && *s != '(' && k < 3)
            p->name[i][k++] = *s++;
        p->name[i][k] = 0;
        p->m[i].name = p->name[i];
        p->m[i].params = p->par[i];
        p->m[i].nparams = 0;
        if (*s == '(') {
            s++;
            while (*s && *s != ')') {
                char *end;
                p->par[i][p->m[i].nparams++] = strtod(s, &end);
                s = end;
                if (*s == ',')
                    s++;
            }
            if (*s == ')')
                s++;
        }
    }
}

static void write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "wb");
    CHECK(f != NULL);
    if (f) {
        fputs(text, f);
        fclose(f);
    }
}

/* Runs `src` with a view read from `viewtext` (NULL: defaults). */
static cbm_turtle *run(cbm_context *ctx, cbm_view **view, const char *viewtext, prog *p,
                       const char *src)
{
    if (viewtext) {
        char path[1024];
        snprintf(path, sizeof path, "%s/t.v", test_tmp_dir());
        write_file(path, viewtext);
        CHECK_OK(cbm_view_load(ctx, path, view));
    } else {
        CHECK_OK(cbm_view_create(ctx, view));
    }
    parse(p, src);
    cbm_turtle *t = NULL;
    cbm_turtle_def def = {true};
    CHECK_OK(cbm_turtle_interpret(ctx, *view, &def, p->m, p->n, NULL, &t));
    return t;
}

static void check_v(cbm_vec3 a, double x, double y, double z, double tol)
{
    CHECK_NEAR(a.x, x, tol);
    CHECK_NEAR(a.y, y, tol);
    CHECK_NEAR(a.z, z, tol);
}

/* Ends a case: its turtle, its view and its context, in that order. */
static void end_run(cbm_context *ctx, cbm_view *v, cbm_turtle *t)
{
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    test_ctx_end(ctx);
}

TEST(lookup)
{
    CHECK_EQ_INT(cbm__turtle_lookup("F", 1), CBM_T_F);
    CHECK_EQ_INT(cbm__turtle_lookup("@Gs", 3), CBM_T_GC_START);
    CHECK_EQ_INT(cbm__turtle_lookup("?P", 2), CBM_T_QUERY_P);
    CHECK_EQ_INT(cbm__turtle_lookup(";", 1), CBM_T_COLOR_INC);
    CHECK_EQ_INT(cbm__turtle_lookup(",", 1), CBM_T_COLOR_DEC);
    CHECK_EQ_INT(cbm__turtle_lookup("_", 1), CBM_T_ELASTICITY);
    CHECK_EQ_INT(cbm__turtle_lookup("A", 1), CBM_T_NONE);
    static const char chars[] = "FfGg+-&^\\/|[]!';,#~%{}._";
    static const int cmds[] = {
        CBM_T_F,           CBM_T_f,          CBM_T_G,           CBM_T_g,         CBM_T_LEFT,
        CBM_T_RIGHT,       CBM_T_PITCH_DOWN, CBM_T_PITCH_UP,    CBM_T_ROLL_LEFT, CBM_T_ROLL_RIGHT,
        CBM_T_TURN_AROUND, CBM_T_PUSH,       CBM_T_POP,         CBM_T_WIDTH,     CBM_T_COLOR_INC,
        CBM_T_COLOR_INC,   CBM_T_COLOR_DEC,  CBM_T_WIDTH_INC,   CBM_T_SURFACE,   CBM_T_CUT,
        CBM_T_POLY_BEGIN,  CBM_T_POLY_END,   CBM_T_POLY_VERTEX, CBM_T_ELASTICITY};
    CHECK_EQ_INT(sizeof chars - 1, sizeof cmds / sizeof cmds[0]);
    for (size_t i = 0; i + 1 < sizeof chars; i++)
        CHECK_EQ_INT(cbm__turtle_lookup(&chars[i], 1), cmds[i]);
    char hi = (char)0xC3;
    CHECK_EQ_INT(cbm__turtle_lookup(&hi, 1), CBM_T_NONE);
    CHECK_EQ_INT(cbm__turtle_lookup("@Tp", 3), CBM_T_TWIST_ADJUST);
    CHECK_EQ_INT(cbm__turtle_lookup("@G", 2), CBM_T_NONE);
}

TEST(turn_pitch_roll)
{
    cbm_context *ctx = test_ctx();
    cbm_view *v;
    prog p;
    cbm_vec3 P, H, L, U;
    double s = sqrt(0.5);
    /* + by the default 45 degrees: H' = H c + L s, L' = L c - H s */
    cbm_turtle *t = run(ctx, &v, NULL, &p, "+");
    cbm_turtle_state(t, &P, &H, &L, &U, NULL, NULL);
    check_v(H, -s, s, 0, TOL);
    check_v(L, -s, -s, 0, TOL);
    check_v(U, 0, 0, -1, TOL);
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    /* & by 90: H' = U, U' = -H */
    t = run(ctx, &v, NULL, &p, "&(90)");
    cbm_turtle_state(t, &P, &H, &L, &U, NULL, NULL);
    check_v(H, 0, 0, -1, TOL);
    check_v(U, 0, -1, 0, TOL);
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    /* / by 90: L' = U, U' = -L */
    t = run(ctx, &v, NULL, &p, "/(90)");
    cbm_turtle_state(t, &P, &H, &L, &U, NULL, NULL);
    check_v(L, 0, 0, -1, TOL);
    check_v(U, 1, 0, 0, TOL);
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    /* | turns around; - and \ mirror + and / */
    t = run(ctx, &v, NULL, &p, "| - - \\(90)");
    cbm_turtle_state(t, &P, &H, &L, &U, NULL, NULL);
    check_v(H, -1, 0, 0, TOL); /* | gives H = -y, L = +x; two -45 give H = -L = -x */
    check_v(L, 0, 0, 1, TOL);  /* L = -y, rolled left by 90: L' = -U */
    check_v(U, 0, -1, 0, TOL);
    end_run(ctx, v, t);
}

TEST(move_and_segments)
{
    cbm_context *ctx = test_ctx();
    cbm_view *v;
    prog p;
    cbm_vec3 P;
    cbm_turtle *t =
        run(ctx, &v, "angle increment: 90\ninitial line width: 2\n", &p, "F(2.5) - F f G(0.5) g");
    cbm_turtle_state(t, &P, NULL, NULL, NULL, NULL, NULL);
    check_v(P, 3.5, 2.5, 0, 1e-12);
    CHECK_EQ_INT(cbm_turtle_prim_count(t), 3); /* F, F, G; f and g draw nothing */
    const cbm_prim *pr = cbm_turtle_prims(t);
    CHECK_EQ_INT(pr[0].kind, CBM_PRIM_CYLINDER);
    check_v(pr[0].p0, 0, 0, 0, TOL);
    check_v(pr[0].p1, 0, 2.5, 0, TOL);
    CHECK_NEAR(pr[0].r0, 1.0, TOL);
    check_v(pr[1].p1, 1, 2.5, 0, TOL);
    check_v(pr[2].p0, 2, 2.5, 0, TOL);
    cbm_vec3 lo, hi;
    CHECK(cbm_turtle_box(t, &lo, &hi));
    check_v(lo, 0, 0, 0, TOL);
    check_v(hi, 3.5, 2.5, 0, TOL);
    end_run(ctx, v, t);
}

TEST(width_semantics)
{
    cbm_context *ctx = test_ctx();
    cbm_view *v;
    prog p;
    /* ! decrements, # increments by the view's increment; a parameter sets; a width change
     * after F makes the segment a cone (cpfg ends the segment at the next node) */
    cbm_turtle *t = run(ctx, &v, "initial line width: 2\nline width increment: 0.5\n", &p,
                        "! F # # F !(3) F !(0.5) [ F ] F(0)");
    const cbm_prim *pr = cbm_turtle_prims(t);
    CHECK_EQ_INT(cbm_turtle_prim_count(t), 4);
    CHECK_NEAR(pr[0].r0, 0.75, TOL);
    CHECK_NEAR(pr[0].r1, 1.25, TOL); /* # # came before the next node: a cone */
    CHECK_NEAR(pr[1].r0, 1.25, TOL);
    CHECK_NEAR(pr[1].r1, 1.5, TOL);
    CHECK_NEAR(pr[2].r0, 1.5, TOL);
    CHECK_NEAR(pr[2].r1, 0.25, TOL); /* cone: !(0.5) came before the next node */
    CHECK_NEAR(pr[3].r0, 0.25, TOL);
    end_run(ctx, v, t);
}

TEST(colors)
{
    cbm_context *ctx = test_ctx();
    cbm_view *v;
    prog p;
    int c;
    cbm_turtle *t = run(ctx, &v, NULL, &p, "; ; ,");
    cbm_turtle_state(t, NULL, NULL, NULL, NULL, NULL, &c);
    CHECK_EQ_INT(c, 129);
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    t = run(ctx, &v, "initial color: 3\ncolor increment: 2\n", &p, ";(7) , , '");
    cbm_turtle_state(t, NULL, NULL, NULL, NULL, NULL, &c);
    CHECK_EQ_INT(c, 5);
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    t = run(ctx, &v, NULL, &p, ",(0) , F");
    cbm_turtle_state(t, NULL, NULL, NULL, NULL, NULL, &c);
    CHECK_EQ_INT(c, 255); /* wraps as cpfg's 256-entry map */
    CHECK_EQ_INT(cbm_turtle_prims(t)[0].color, 255);
    end_run(ctx, v, t);
}

TEST(branches_and_cut)
{
    cbm_context *ctx = test_ctx();
    cbm_view *v;
    prog p;
    cbm_vec3 P, H;
    const char *src = "[ + F [ F ] ] F [ F % F [ F ] F ] F ]";
    /* cpfg's default interprets past % (the engine cuts when deriving): every F draws */
    cbm_turtle *t = run(ctx, &v, NULL, &p, src);
    cbm_turtle_state(t, &P, &H, NULL, NULL, NULL, NULL);
    check_v(P, 0, 2, 0, TOL);
    check_v(H, 0, 1, 0, TOL);
    CHECK_EQ_INT(cbm_turtle_prim_count(t), 8);
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    /* with "interpretation past %: off" the rest of the branch is skipped: + F, F (inner), F,
     * F before %, F after the branch; the unmatched ] is ignored */
    t = run(ctx, &v, "interpretation past %: off\n", &p, src);
    cbm_turtle_state(t, &P, &H, NULL, NULL, NULL, NULL);
    check_v(P, 0, 2, 0, TOL);
    CHECK_EQ_INT(cbm_turtle_prim_count(t), 5);
    end_run(ctx, v, t);
}

TEST(polygons)
{
    cbm_context *ctx = test_ctx();
    cbm_view *v;
    prog p;
    cbm_turtle *t =
        run(ctx, &v, "angle increment: 90\n", &p, "{ . f + f + G + f } { . f(2) { . g . } + f }");
    const cbm_prim *pr = cbm_turtle_prims(t);
    size_t n = cbm_turtle_prim_count(t);
    const cbm_vec3 *pts = cbm_turtle_points(t);
    size_t npoly = 0;
    for (size_t i = 0; i < n; i++)
        if (pr[i].kind == CBM_PRIM_POLYGON) {
            npoly++;
            if (npoly == 1) {
                CHECK_EQ_INT(pr[i].count, 4); /* ., f, f, f: G adds no vertex */
                check_v(pts[pr[i].first + 2], -1, 1, 0, TOL);
            }
        }
    /* the nested polygon has 2 vertices and is dropped; the outer one has 3 (., f(2), f) */
    CHECK_EQ_INT(npoly, 2);
    end_run(ctx, v, t);
}

TEST(queries)
{
    cbm_context *ctx = test_ctx();
    cbm_view *v;
    prog p;
    cbm_turtle *t = run(ctx, &v, NULL, &p, "F(2) ?P(0,0,0) ?H(0,0,0) ?L(9,9) ?U(0,0,0)");
    CHECK_NEAR(p.par[1][1], 2.0, TOL);
    CHECK_NEAR(p.par[2][1], 1.0, TOL);
    CHECK_NEAR(p.par[3][0], -1.0, TOL);
    CHECK_NEAR(p.par[3][2], 0.0, TOL); /* only 2 parameters: the third is untouched */
    CHECK_NEAR(p.par[4][2], -1.0, TOL);
    end_run(ctx, v, t);
}

TEST(at_commands)
{
    cbm_context *ctx = test_ctx();
    cbm_view *v;
    prog p;
    cbm_vec3 P, H, L, U;
    cbm_turtle *t = run(ctx, &v, NULL, &p, "+(30) &(40) @v @M(1,2,3) @O(2) @c(4) @o");
    cbm_turtle_state(t, &P, &H, &L, &U, NULL, NULL);
    check_v(P, 1, 2, 3, TOL);
    CHECK_NEAR(L.y, 0.0, TOL); /* rolled to horizontal */
    CHECK_NEAR(v3_dot(H, U), 0.0, TOL);
    cbm_vec3 hu = v3_cross(H, U);
    check_v(hu, L.x, L.y, L.z, 1e-12); /* L = H x U */
    const cbm_prim *pr = cbm_turtle_prims(t);
    CHECK_EQ_INT(cbm_turtle_prim_count(t), 3);
    CHECK_EQ_INT(pr[0].kind, CBM_PRIM_SPHERE);
    CHECK_NEAR(pr[0].r0, 1.0, TOL);
    CHECK_EQ_INT(pr[1].kind, CBM_PRIM_DISC);
    CHECK_NEAR(pr[1].r0, 2.0, TOL);
    CHECK_NEAR(pr[2].r0, 0.5, TOL); /* @o without parameter: the line width */
    cbm_vec3 lo, hi;
    CHECK(cbm_turtle_box(t, &lo, &hi));
    check_v(lo, -1, 0, 0, TOL); /* disc corners x, y +- 2 around (1,2,3); sphere +- 1 */
    check_v(hi, 3, 4, 4, TOL);
    end_run(ctx, v, t);
}

/* A sphere's work is bounded: its slices follow `contour sides` (at least 16) up to
 * SPHERE_MAX_SLICES (128), with half as many stacks, so `contour sides: 1024` (the largest, as
 * cylinders allow) makes two spheres of 128 x 65 vertices, not of 1024 x 513 (a million
 * triangles each: the slow inputs of fuzz_turtle_side, tests/fuzz/corpus/fuzz_turtle_side/
 * view-sphere-sides). Counted in vertices and triangles, never timed. */
TEST(sphere_work_bounded)
{
    static const struct {
        const char *view;
        size_t slices;
    } cases[] = {{"contour sides: 1024\n", 128}, {"contour sides: 40\n", 40}, {NULL, 16}};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        cbm_context *ctx = test_ctx();
        cbm_view *v = NULL;
        if (cases[k].view) {
            char path[1024];
            snprintf(path, sizeof path, "%s/t.v", test_tmp_dir());
            write_file(path, cases[k].view);
            CHECK_OK(cbm_view_load(ctx, path, &v));
        } else
            CHECK_OK(cbm_view_create(ctx, &v));
        prog p;
        parse(&p, "@O(2) f @O(1)");
        cbm_scene *scene = NULL;
        CHECK_OK(cbm_scene_create(ctx, &scene));
        cbm_turtle *t = NULL;
        cbm_turtle_def def = {true};
        CHECK_OK(cbm_turtle_interpret(ctx, v, &def, p.m, p.n, scene, &t));
        size_t n = cases[k].slices, stacks = n / 2;
        CHECK_MSG(cbm_scene_vertex_count(scene) == 2 * n * (stacks + 1) &&
                      cbm_scene_triangle_count(scene) == 2 * n * (2 * stacks - 2),
                  "%s: %zu vertices, %zu triangles (expected spheres of %zu slices)",
                  cases[k].view ? cases[k].view : "default view", cbm_scene_vertex_count(scene),
                  cbm_scene_triangle_count(scene), n);
        cbm_turtle_destroy(t);
        cbm_scene_destroy(scene);
        cbm_view_destroy(v);
        test_ctx_end(ctx);
    }
}

TEST(single_symbol_modules)
{
    /* cpfg's strings hold one symbol per module: @, ? and ~ combine with the following ones */
    cbm_context *ctx = test_ctx();
    cbm_view *v;
    prog p;
    cbm_turtle *t = run(ctx, &v, "tropism: T: 1 0 0 E: 0.5\n", &p,
                        "@ M(1,2,3) ? P(0,0,0) ?(2) @ T s(1,0) F @ Z @ O(4) X F");
    CHECK_NEAR(p.par[3][0], 1.0, TOL);
    CHECK_NEAR(p.par[3][1], 2.0, TOL);
    CHECK_NEAR(p.par[3][2], 3.0, TOL);
    cbm_vec3 P, H;
    cbm_turtle_state(t, &P, &H, NULL, NULL, NULL, NULL);
    check_v(H, 0, 1, 0, TOL); /* @Ts(1,0) removed the tropism */
    check_v(P, 1, 4, 3, TOL);
    const cbm_prim *pr = cbm_turtle_prims(t);
    CHECK_EQ_INT(cbm_turtle_prim_count(t), 3); /* F, the sphere, F; @Z is no command */
    CHECK_EQ_INT(pr[1].kind, CBM_PRIM_SPHERE);
    CHECK_NEAR(pr[1].r0, 2.0, TOL);
    end_run(ctx, v, t);
}

TEST(twist_adjust)
{
    /* after F the reference is H = +y, U = -z; &(90) pitches (H = -z, U = -y); @Tp rebuilds U by
     * the minimal rotation from the reference: the same frame. After /(90) (a roll, which the
     * minimal rotation undoes) @Tp gives back U = -y; with @Tf first the roll is kept. */
    cbm_context *ctx = test_ctx();
    cbm_view *v;
    prog p;
    cbm_vec3 H, L, U;
    cbm_turtle *t = run(ctx, &v, NULL, &p, "F &(90) /(90) @Tp");
    cbm_turtle_state(t, NULL, &H, &L, &U, NULL, NULL);
    check_v(H, 0, 0, -1, 1e-12);
    check_v(U, 0, -1, 0, 1e-12);
    check_v(v3_cross(H, U), L.x, L.y, L.z, 1e-12);
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    t = run(ctx, &v, NULL, &p, "F &(90) /(90) @Tf @Tp");
    cbm_turtle_state(t, NULL, &H, &L, &U, NULL, NULL);
    check_v(U, 1, 0, 0, 1e-12); /* rolled: U' = -L, L = -x before the roll */
    end_run(ctx, v, t);
}

TEST(abop_tropism)
{
    cbm_context *ctx = test_ctx();
    cbm_view *v;
    prog p;
    cbm_vec3 H;
    /* after +(90), H = -x, L = -y; T = -y, e = 0.5: sin(alpha) = e T.L = 0.5 */
    cbm_turtle *t =
        run(ctx, &v, "tropism direction: 0,-1,0\ninitial elasticity: 0.5\n", &p, "+(90) F");
    cbm_turtle_state(t, NULL, &H, NULL, NULL, NULL, NULL);
    check_v(H, -sqrt(0.75), -0.5, 0, 1e-12);
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    /* _ sets the elasticity: none, no bending */
    t = run(ctx, &v, "tropism direction: 0,-1,0\ninitial elasticity: 0.5\n", &p, "+(90) _(0) F");
    cbm_turtle_state(t, NULL, &H, NULL, NULL, NULL, NULL);
    check_v(H, -1, 0, 0, 1e-12);
    end_run(ctx, v, t);
}

TEST(cpfg_tropism)
{
    cbm_context *ctx = test_ctx();
    cbm_view *v;
    prog p;
    cbm_vec3 H, L, U;
    /* H = -x, V = 0.1 (0,-1,0): H turns about H x V = +z by |H x V| = 0.1 rad before the move */
    cbm_turtle *t = run(ctx, &v, "tropism: T: 0 -1 0 E: 0.1\n", &p, "+(90) F");
    cbm_turtle_state(t, NULL, &H, &L, &U, NULL, NULL);
    check_v(H, -cos(0.1), -sin(0.1), 0, 1e-12);
    check_v(U, 0, 0, -1, 1e-12);
    check_v(v3_cross(H, U), L.x, L.y, L.z, 1e-12);
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    /* @Ts(1, 0) sets the elasticity of tropism 1 to 0 */
    t = run(ctx, &v, "tropism: T: 0 -1 0 E: 0.1\n", &p, "+(90) @Ts(1,0) F");
    cbm_turtle_state(t, NULL, &H, NULL, NULL, NULL, NULL);
    check_v(H, -1, 0, 0, 1e-12);
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    /* angle A: 90 (plagiotropism): V = e T x (H x T)/|H x T|; H = +y is already normal to T=+x
     * after +(90)? use H = (0,1,0), T = (1,0,0): V = 0.1 (0,1,0) = along H: no turn */
    t = run(ctx, &v, "tropism: T: 1 0 0 A: 90 E: 0.1\n", &p, "F");
    cbm_turtle_state(t, NULL, &H, NULL, NULL, NULL, NULL);
    check_v(H, 0, 1, 0, 1e-12);
    end_run(ctx, v, t);
}

static cbm_turtle *run_scene(cbm_context *ctx, const cbm_view *v, prog *p, const char *src,
                             cbm_scene *scene)
{
    parse(p, src);
    cbm_turtle *t = NULL;
    cbm_turtle_def def = {true};
    CHECK_OK(cbm_turtle_interpret(ctx, v, &def, p->m, p->n, scene, &t));
    return t;
}

TEST(torque)
{
    /* T = +x, e = 0.5, H = +y, U = -z: D = 0.5 x; cpfg's code turns U about U x D = -0.5 y by
     * -0.5 rad, i.e. about +y by 0.5 rad: U = (-sin 0.5, 0, -cos 0.5), away from D */
    cbm_context *ctx = test_ctx();
    cbm_view *v;
    prog p;
    cbm_vec3 H, L, U;
    cbm_turtle *t = run(ctx, &v, "torque: T: 1 0 0 E: 0.5\n", &p, "F");
    cbm_turtle_state(t, NULL, &H, &L, &U, NULL, NULL);
    check_v(H, 0, 1, 0, 1e-12);
    check_v(U, -sin(0.5), 0, -cos(0.5), 1e-12);
    check_v(L, -cos(0.5), 0, sin(0.5), 1e-12);
    end_run(ctx, v, t);
}

TEST(generalized_cylinder)
{
    cbm_context *ctx = test_ctx();
    char path[1024];
    snprintf(path, sizeof path, "%s/gc.v", test_tmp_dir());
    write_file(path, "line style: cylinder\n");
    cbm_view *v;
    CHECK_OK(cbm_view_load(ctx, path, &v));
    prog p;
    cbm_scene *scene;
    CHECK_OK(cbm_scene_create(ctx, &scene));
    cbm_turtle *t = run_scene(ctx, v, &p, "@Gs f + f [ F ] @Gc(4) f @Ge(3)", scene);
    const cbm_prim *pr = cbm_turtle_prims(t);
    const cbm_vec3 *pts = cbm_turtle_points(t);
    size_t ngc = 0;
    for (size_t i = 0; i < cbm_turtle_prim_count(t); i++)
        if (pr[i].kind == CBM_PRIM_GCYL) {
            ngc++;
            CHECK_EQ_INT(pr[i].count, 3 * 2 * 8 * (ngc == 1 ? 4 : 3));
            if (ngc == 1) {
                /* first triangle (new ring 0, new ring 1, old ring 0): the old ring's first
                 * point is P + r U with r = 0.5, U = -z */
                check_v(pts[pr[i].first + 2], 0, 0, -0.5, 1e-12);
                check_v(pr[i].p0, 0, 0, 0, 1e-12);
            }
        }
    CHECK_EQ_INT(ngc, 2);
    /* 4 + 3 bands of 8 sides, and the branch F as an 8-sided tube */
    CHECK_EQ_INT(cbm_scene_triangle_count(scene), 7 * 8 * 2 + 8 * 2);
    cbm_turtle_destroy(t);
    /* a branch continues the cylinder from the last control point before it (as cpfg) */
    cbm_scene_clear(scene);
    t = run_scene(ctx, v, &p, "@Gs f [ f @Gc(2) ] f @Ge(2) @Gc(2)", scene);
    pr = cbm_turtle_prims(t);
    CHECK_EQ_INT(cbm_turtle_prim_count(t), 2);
    for (size_t i = 0; i < cbm_turtle_prim_count(t); i++) {
        check_v(pr[i].p0, 0, 0, 0, 1e-12);
        check_v(pr[i].p1, 0, 2, 0, 1e-12);
    }
    cbm_turtle_destroy(t);
    /* radius tangents (0, 1) (@Gr(90, 1)): ring r at Hermite t = 3r^2 - 2r^3 and radius
     * w/2 + 2r^3 - 3r^2 + r; on a straight spine with tangents 1.2 H, y(t) = 1.2t - 0.6t^2 +
     * 0.4t^3. Ring 1 of 4: t = 0.15625, radius 0.59375; its first point is P + r U. */
    t = run_scene(ctx, v, &p, "@Gr(90,1) @Gs f @Gc(4)", NULL);
    pr = cbm_turtle_prims(t);
    CHECK_EQ_INT(cbm_turtle_prim_count(t), 1);
    double tt = 0.15625;
    check_v(cbm_turtle_points(t)[pr[0].first], 0, 1.2 * tt - 0.6 * tt * tt + 0.4 * tt * tt * tt,
            -0.59375, 1e-12);
    cbm_turtle_destroy(t);
    cbm_scene_destroy(scene);
    cbm_view_destroy(v);
    test_ctx_end(ctx);
}

TEST(contour)
{
    cbm_context *ctx = test_ctx();
    char path[1024], cpath[1024];
    snprintf(cpath, sizeof cpath, "%s/line.con", test_tmp_dir());
    /* an open contour along x: a flat ribbon */
    write_file(cpath, "cver 1 3\nname: line\npoints: 2 6\ntype: or\nsamples: 5\n"
                      "-1 0 0 3\n1 0 0 3\n");
    snprintf(path, sizeof path, "%s/con.v", test_tmp_dir());
    write_file(path, "line style: cylinder\ncontour sides: 6\ncontour: 7 line.con\n");
    cbm_view *v;
    CHECK_OK(cbm_view_load(ctx, path, &v));
    prog p;
    cbm_turtle *t = run_scene(ctx, v, &p, "@#(7) !(2) @Gs F @Ge(1)", NULL);
    const cbm_prim *pr = cbm_turtle_prims(t);
    const cbm_vec3 *pts = cbm_turtle_points(t);
    size_t n = cbm_turtle_prim_count(t);
    CHECK_EQ_INT(n, 2); /* the F segment and the cylinder */
    if (n == 2) {
        CHECK_EQ_INT(pr[1].kind, CBM_PRIM_GCYL);
        CHECK_EQ_INT(pr[1].count, 3 * 2 * 6);
        /* radius 1; x along U = -z, no component along L = -x */
        double zmin = 1, zmax = -1;
        for (size_t k = 0; k < pr[1].count; k++) {
            cbm_vec3 q = pts[pr[1].first + k];
            CHECK_NEAR(q.x, 0.0, 1e-6);
            zmin = fmin(zmin, q.z);
            zmax = fmax(zmax, q.z);
        }
        CHECK_NEAR(zmax, 1.0, 1e-6); /* the first contour point, x = -1 */
        CHECK(zmin < -0.9 && zmin > -1.0 - 1e-6);
    }
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    /* malformed contours */
    write_file(cpath, "cver 1 3\nname: x\npoints: 2 2\ntype: or\nsamples: 5\n0 0 0 1\n1 0 0 1\n");
    CHECK_OK(cbm_view_create(ctx, &v));
    CHECK_STATUS(cbm_view_add_contour(v, 1, cpath), CBM_E_FORMAT);
    write_file(cpath, "cver 1 3\nname: x\npoints: 3 3\ntype: or\nsamples: 5\n0 0 0 1\n");
    CHECK_STATUS(cbm_view_add_contour(v, 1, cpath), CBM_E_FORMAT);
    cbm_view_destroy(v);
    cbm_context_clear_errors(ctx);
    test_ctx_end(ctx);
}

/* The function tabulation as func.c computed it before its work was bounded (every basis
 * function of every control point, 200 halvings), the reference of function_work_bounded. */
static int ref_knot(int j, int n)
{
    return j < 4 ? 0 : j > n ? n - 2 : j - 3;
}

static double ref_value(const cbm__func *f, double x)
{
    double lo = 0.0, hi = 1.0, cy = 0.0;
    int n = f->npts - 1;
    for (int it = 0; it < 200; it++) {
        double mid = 0.5 * (lo + hi), u = mid * (double)(n - 2), sx = 0.0, sy = 0.0;
        for (int k = 0; k <= n; k++) {
            double t1[4];
            for (int i = 0; i < 4; i++)
                t1[i] = (ref_knot(k + i, n) <= u && u < ref_knot(k + i + 1, n)) ? 1.0 : 0.0;
            for (int t = 2; t <= 4; t++)
                for (int i = 0; i + t <= 4; i++) {
                    int a = k + i;
                    double v = 0.0;
                    int div = ref_knot(a + t - 1, n) - ref_knot(a, n);
                    if (div != 0)
                        v = (u - ref_knot(a, n)) / div * t1[i];
                    div = ref_knot(a + t, n) - ref_knot(a + 1, n);
                    if (div != 0)
                        v += (ref_knot(a + t, n) - u) / div * t1[i + 1];
                    t1[i] = v;
                }
            sx += f->px[k] * t1[0];
            sy += f->py[k] * t1[0];
        }
        cy = sy;
        if (sx > x)
            hi = mid;
        else
            lo = mid;
        if (fabs(sx - x) <= 0.001)
            break;
    }
    return cy;
}

/* Tabulating a function costs a bounded number of basis functions a sample: the four of the
 * point's knot span, not one per control point, and the bisection stops once its interval
 * cannot shrink (a curve that never reaches x spent all 200 halvings). fuzz_turtle_side's
 * slow function files (samples: 881 on a curve that turns back) were 0.1 s each. The values
 * are those of the former computation (ref_value), bit for bit: a zigzag
 * whose x goes back and forth (1000 control points), a smooth increasing one that ends at
 * x = 0.5 (the bisection never reaches the samples beyond), and one with a control point beyond
 * float's range (every term is then summed, as 0 times infinity is NaN). */
TEST(function_work_bounded)
{
    enum { SAMPLES = 301 };
    for (int kind = 0; kind < 3; kind++) {
        int npts = kind == 0 ? 1000 : 40;
        size_t cap = (size_t)npts * 48 + 256, len = 0;
        char *text = malloc(cap);
        CHECK(text != NULL);
        if (!text)
            return;
        len += (size_t)snprintf(
            text, cap, "fver 1 1\nname: f\nsamples: %d\nflip: off\npoints: %d\n", SAMPLES, npts);
        for (int i = 0; i < npts; i++) {
            double x = kind == 0 ? (i % 7) / 6.0 : 0.5 * i / (npts - 1);
            double y = kind == 2 && i == 20 ? 1e39 : sin(0.1 * i);
            len += (size_t)snprintf(text + len, cap - len, "%.17g %.17g 1\n", x, y);
        }
        cbm_context *ctx = test_ctx();
        cbm__func f;
        memset(&f, 0, sizeof f);
        CHECK_OK(cbm__func_read(ctx, "f.func", text, 0, &f));
        CHECK(f.finite == (kind != 2));
        int same = 0;
        for (int i = 0; i < SAMPLES && f.vals; i++) {
            double r = ref_value(&f, (double)i / (double)(SAMPLES - 1));
            uint64_t a, b; /* the bits: -0 and NaN told apart */
            memcpy(&a, &r, sizeof a);
            memcpy(&b, &f.vals[i], sizeof b);
            same += a == b;
        }
        CHECK_MSG(same == SAMPLES, "kind %d: %d of %d values equal the former computation's", kind,
                  same, SAMPLES);
        /* 4 terms a point at most (finite), 64 halvings at most (the interval of [0, 1]
         * stops shrinking after about 53) */
        size_t bound = kind == 2 ? (size_t)SAMPLES * 200 * (size_t)npts : (size_t)SAMPLES * 64 * 4;
        CHECK_MSG(f.basis_evals <= bound, "kind %d: %zu basis functions evaluated (bound %zu)",
                  kind, f.basis_evals, bound);
        cbm__func_free(ctx, &f);
        test_ctx_end(ctx);
        free(text);
    }
}

TEST(nonfinite_parameter)
{
    cbm_context *ctx = test_ctx();
    cbm_view *v;
    CHECK_OK(cbm_view_create(ctx, &v));
    prog p;
    parse(&p, "F F(1) +(2)");
    p.par[1][0] = NAN;
    cbm_turtle *t = NULL;
    CHECK_STATUS(cbm_turtle_interpret(ctx, v, NULL, p.m, p.n, NULL, &t), CBM_E_NONFINITE);
    CHECK(t == NULL);
    CHECK(strstr(cbm_context_last_error(ctx), "module 2") != NULL);
    cbm_context_clear_errors(ctx);
    cbm_view_destroy(v);
    test_ctx_end(ctx);
}

TEST(functions)
{
    cbm_context *ctx = test_ctx();
    char path[1024];
    snprintf(path, sizeof path, "%s/lin.func", test_tmp_dir());
    /* collinear control points: the curve is the line y = x */
    write_file(path, "fver 1 1\nname: lin\nsamples: 11\nflip: off\npoints: 4\n"
                     "0 0 1\n0.333333 0.333333 1\n0.666667 0.666667 1\n1 1 1\n");
    char path2[1024];
    snprintf(path2, sizeof path2, "%s/sq.func", test_tmp_dir());
    write_file(path2, "range: 0 1\npoints: 5\n0 1\n0.25 1\n0.5 1\n0.75 1\n1 1\n");
    cbm_view *v;
    CHECK_OK(cbm_view_create(ctx, &v));
    CHECK_OK(cbm_view_add_function(v, path, -1));
    CHECK_OK(cbm_view_add_function(v, path2, 100));
    const cbm_funcset *fs = cbm_view_functions(v);
    CHECK_EQ_INT(cbm_funcset_count(fs), 2);
    for (int i = 0; i <= 10; i++) {
        double x = i / 10.0;
        CHECK_NEAR(cbm__funcset_eval(fs, 1, x), x, 1.5e-3);
    }
    CHECK_NEAR(cbm__funcset_eval(fs, 1, -3), 0.0, 1.5e-3); /* clamped */
    CHECK_NEAR(cbm__funcset_eval(fs, 1, 7), 1.0, 1.5e-3);
    CHECK_NEAR(cbm__funcset_eval(fs, 2, 0.37), 1.0, 1e-12);
    CHECK_NEAR(cbm__funcset_eval(fs, 3, 0.5), 0.0, 0.0); /* unknown id */
    cbm_view_destroy(v);
    /* a gallery named by the view file, functions found by name */
    char gpath[1024], vpath[1024];
    snprintf(gpath, sizeof gpath, "%s/g.fset", test_tmp_dir());
    write_file(gpath, "funcgalleryver 1 1\nitems: 2\n"
                      "fver 1 1\nname: one\nsamples: 5\nflip: off\npoints: 4\n"
                      "0 1\n0.3 1\n0.6 1\n1 1\n"
                      "fver 1 1\nname: two\nsamples: 5\nflip: off\npoints: 4\n"
                      "0 2\n0.3 2\n0.6 2\n1 2\n");
    snprintf(vpath, sizeof vpath, "%s/g.v", test_tmp_dir());
    write_file(vpath, "function set: g.fset\n");
    CHECK_OK(cbm_view_load(ctx, vpath, &v));
    fs = cbm_view_functions(v);
    CHECK_EQ_INT(cbm_funcset_find(fs, "two"), 2);
    CHECK_NEAR(cbm_funcset_value(fs, 2, 0.4), 2.0, 1e-12);
    CHECK_NEAR(cbm_view_func_callback(v, 1, 0.4), 1.0, 1e-12);
    cbm_view_destroy(v);
    write_file(gpath, "funcgalleryver 1 1\nitems: 2\n"
                      "fver 1 1\nname: one\nsamples: 5\nflip: off\npoints: 4\n"
                      "0 1\n0.3 1\n0.6 1\n1 1\n");
    CHECK_STATUS(cbm_view_load(ctx, vpath, &v), CBM_E_FORMAT);
    /* malformed: too few points */
    write_file(path, "fver 1 1\nname: bad\nsamples: 5\nflip: off\npoints: 2\n0 0\n1 1\n");
    CHECK_OK(cbm_view_create(ctx, &v));
    CHECK_STATUS(cbm_view_add_function(v, path, -1), CBM_E_FORMAT);
    cbm_view_destroy(v);
    cbm_context_clear_errors(ctx);
    test_ctx_end(ctx);
}

TEST(view_errors)
{
    cbm_context *ctx = test_ctx();
    char path[1024];
    snprintf(path, sizeof path, "%s/bad.v", test_tmp_dir());
    cbm_view *v = NULL;
    write_file(path, "angle factor: 0\n");
    CHECK_STATUS(cbm_view_load(ctx, path, &v), CBM_E_FORMAT);
    CHECK(v == NULL);
    CHECK(strstr(cbm_context_last_error(ctx), "angle factor") != NULL);
    write_file(path, "line style: wobbly\n");
    CHECK_STATUS(cbm_view_load(ctx, path, &v), CBM_E_FORMAT);
    write_file(path, "tropism: T: 0 0 0\n");
    CHECK_STATUS(cbm_view_load(ctx, path, &v), CBM_E_FORMAT);
    write_file(path, "function: missing.func 10\n");
    CHECK_STATUS(cbm_view_load(ctx, path, &v), CBM_E_IO);
    CHECK_STATUS(cbm_view_load(ctx, "/nonexistent/x.v", &v), CBM_E_IO);
    write_file(path, "angle factor: 8\nviewpoint: 0,0,1\npolygonization level: 2\n"
                     "line style: cylinder\ninitial line width: 3 pixels\n");
    CHECK_OK(cbm_view_load(ctx, path, &v));
    CHECK_NEAR(v->angle, 45.0, 1e-12);
    CHECK_EQ_INT(v->sides, 8);
    CHECK_EQ_INT(v->line_style, CBM__LS_PIXEL); /* the later line wins, as in cpfg */
    cbm_view_destroy(v);
    cbm_context_clear_errors(ctx);
    test_ctx_end(ctx);
}

TEST(surface_file)
{
    cbm_context *ctx = test_ctx();
    char path[1024];
    snprintf(path, sizeof path, "%s/sq.s", test_tmp_dir());
    /* a flat unit square patch in x-y, contact at the origin, end point at (0, 1, 0) */
    write_file(path, "0 1 0 1 0 0\nCONTACT POINT  X: 0 Y: 0 Z: 0\nEND POINT  X: 0 Y: 1 Z: 0\n"
                     "HEADING  X: 0 Y: 1 Z: 0\nUP  X: 0 Y: 0 Z: -1\nSIZE: 1\npatch\n"
                     "TOP COLOR: 0 DIFFUSE: 0 BOTTOM COLOR: 0 DIFFUSE: 0\n"
                     "AL: ~ A: ~ AR: ~\nL: ~ R: ~\nBL: ~ B: ~ BR: ~\n"
                     "0 0 0 0.333 0 0 0.667 0 0 1 0 0\n"
                     "0 0.333 0 0.333 0.333 0 0.667 0.333 0 1 0.333 0\n"
                     "0 0.667 0 0.333 0.667 0 0.667 0.667 0 1 0.667 0\n"
                     "0 1 0 0.333 1 0 0.667 1 0 1 1 0\n");
    cbm_view *v;
    CHECK_OK(cbm_view_create(ctx, &v));
    CHECK_OK(cbm_view_add_surface(v, 's', path, 2.0));
    prog p;
    parse(&p, "~ s(1.5) F(0)");
    cbm_scene *scene;
    CHECK_OK(cbm_scene_create(ctx, &scene));
    cbm_turtle *t = NULL;
    cbm_turtle_def def = {true};
    CHECK_OK(cbm_turtle_interpret(ctx, v, &def, p.m, p.n, scene, &t));
    cbm_vec3 P;
    cbm_turtle_state(t, &P, NULL, NULL, NULL, NULL, NULL);
    /* end point y = 1, scaled by 2/1 (view size / SIZE) and by 1.5 along H */
    check_v(P, 0, 3, 0, 1e-12);
    CHECK(cbm_scene_triangle_count(scene) > 0);
    CHECK_EQ_INT(cbm_scene_parts(scene)[0].organ, CBM_ORGAN_LEAF);
    cbm_vec3 lo, hi;
    CHECK(cbm_turtle_box(t, &lo, &hi));
    CHECK_NEAR(hi.y, 3.0, 1e-12);
    /* cpfg expresses the patch in the file's frame (X = -x here) and places X along L = -x */
    CHECK_NEAR(lo.x, 0.0, 1e-12);
    CHECK_NEAR(hi.x, 3.0, 1e-12);
    cbm_turtle_destroy(t);
    cbm_scene_destroy(scene);
    cbm_view_destroy(v);
    test_ctx_end(ctx);
}

TEST(engine_interface)
{
    /* the engine's way: lookup once, exec per module, ~ followed by cbm__turtle_surface; and a
     * second pass after reset gives the same result */
    cbm_context *ctx = test_ctx();
    char path[1024];
    snprintf(path, sizeof path, "%s/e.s", test_tmp_dir());
    write_file(path, "0 1 0 1 0 0\nCONTACT POINT  X: 0 Y: 0 Z: 0\nEND POINT  X: 0 Y: 2 Z: 0\n"
                     "HEADING  X: 0 Y: 1 Z: 0\nUP  X: 0 Y: 0 Z: -1\nSIZE: 1\np\nc\na\nb\nd\n"
                     "0 0 0 1 0 0 2 0 0 3 0 0\n0 1 0 1 1 0 2 1 0 3 1 0\n"
                     "0 2 0 1 2 0 2 2 0 3 2 0\n0 3 0 1 3 0 2 3 0 3 3 0\n");
    cbm_view *v;
    CHECK_OK(cbm_view_create(ctx, &v));
    CHECK_OK(cbm_view_add_surface(v, 'k', path, 1.0));
    cbm_turtle *t;
    CHECK_OK(cbm__turtle_create(ctx, v, NULL, &t));
    cbm__turtle_set_record(t, true);
    int F = cbm__turtle_lookup("F", 1), S = cbm__turtle_lookup("~", 1),
        Q = cbm__turtle_lookup("?P", 2);
    for (int pass = 0; pass < 2; pass++) {
        cbm__turtle_reset(t);
        double one[1] = {1.5}, q[3] = {0, 0, 0};
        CHECK_OK(cbm__turtle_exec(t, F, NULL, 0));
        CHECK_OK(cbm__turtle_exec(t, S, NULL, 0));
        CHECK_OK(cbm__turtle_surface(t, "k", 1, one, 1));
        CHECK_OK(cbm__turtle_exec(t, Q, q, 3));
        CHECK_OK(cbm__turtle_finish(t));
        /* F to y = 1, then the surface's end point y = 2, scaled by 1.5 */
        CHECK_NEAR(q[1], 4.0, 1e-12);
        CHECK_EQ_INT(cbm_turtle_prim_count(t), 2);
    }
    CHECK_STATUS(cbm__turtle_surface(t, "kk", 2, NULL, 0), CBM_E_RUNTIME);
    cbm__turtle_destroy(t);
    cbm_view_destroy(v);
    cbm_context_clear_errors(ctx);
    test_ctx_end(ctx);
}

static cbm_status oom_body(cbm_context *ctx, void *ud)
{
    (void)ud;
    cbm_view *v;
    CBM_TRY(cbm_view_create(ctx, &v));
    prog p;
    parse(&p, "F [ + F { . f + f + f } ] @Gs f @Gc(3) f @Ge(2) [ @O(1) ] F {(4,3) . f [ + f ] "
              "+ f + f }(4) {(2) . f + f }(2)");
    cbm_scene *scene;
    cbm_status s = cbm_scene_create(ctx, &scene);
    if (s != CBM_OK) {
        cbm_view_destroy(v);
        return s;
    }
    cbm_turtle *t = NULL;
    cbm_turtle_def def = {true};
    s = cbm_turtle_interpret(ctx, v, &def, p.m, p.n, scene, &t);
    cbm_turtle_destroy(t);
    cbm_scene_destroy(scene);
    cbm_view_destroy(v);
    return s;
}

TEST(out_of_memory)
{
    CHECK(test_oom_loop(oom_body, NULL) > 5);
}

/* ---- cpfg's spline cylinders {(n) ... }(n) ---- */

/* The spine of the spline cylinders of `src` drawn with pixel lines (the default view): the
 * segment prims (other prims skipped), whose end points are the ring centres. Returns the number
 * of segments. */
static size_t spine(cbm_context *ctx, const cbm_view *v, const char *src, cbm_vec3 *a, cbm_vec3 *b,
                    size_t max)
{
    prog p;
    cbm_turtle *t = run_scene(ctx, v, &p, src, NULL);
    size_t n = 0;
    const cbm_prim *pr = cbm_turtle_prims(t);
    for (size_t i = 0; i < cbm_turtle_prim_count(t); i++) {
        if (pr[i].kind != CBM_PRIM_CYLINDER)
            continue;
        if (n < max) {
            a[n] = pr[i].p0;
            b[n] = pr[i].p1;
        }
        n++;
    }
    cbm_turtle_destroy(t);
    return n;
}

/* Control points of the unit square, (0,0) (0,1) (-1,1) (-1,0) in the x-y plane: `.` at the
 * origin, then each f a control point. 2 bands per connection: each connection is two
 * segments, start knot -> curve at t = 1/2 -> end knot. */
#define SQUARE ". f(1) +(90) f(1) +(90) f(1)"

TEST(spline_cylinder_bspline_square)
{
    cbm_context *ctx = test_ctx();
    cbm_view *v;
    CHECK_OK(cbm_view_create(ctx, &v));
    cbm_vec3 a[16], b[16];
    const cbm_vec3 P[4] = {v3(0, 0, 0), v3(0, 1, 0), v3(-1, 1, 0), v3(-1, 0, 0)};
    /* closed uniform cubic B-spline (kind 4): 4 connections, knot k at (P[k-1] + 4 P[k] +
     * P[k+1]) / 6 starting with k = 1, the point at t = 1/2 (P0 + 23 P1 + 23 P2 + P3) / 48 of
     * the window P[k-1..k+2] */
    size_t n = spine(ctx, v, "{(4,2) " SQUARE " }(4)", a, b, 16);
    CHECK_EQ_INT(n, 8);
    check_v(a[0], -1.0 / 6, 5.0 / 6, 0, 1e-12); /* knot at t = 0 */
    check_v(b[0], -0.5, 23.0 / 24, 0, 1e-12);   /* t = 1/2 */
    check_v(b[1], -5.0 / 6, 5.0 / 6, 0, 1e-12); /* knot at t = 1 */
    for (int k = 0; k < 4 && n == 8; k++) {
        cbm_vec3 q0 = P[k], q1 = P[(k + 1) % 4], q2 = P[(k + 2) % 4], q3 = P[(k + 3) % 4];
        cbm_vec3 k0 = v3_scale(v3_add(v3_add(q0, v3_scale(q1, 4)), q2), 1.0 / 6);
        cbm_vec3 k1 = v3_scale(v3_add(v3_add(q1, v3_scale(q2, 4)), q3), 1.0 / 6);
        cbm_vec3 m =
            v3_scale(v3_add(v3_add(q0, v3_scale(q1, 23)), v3_add(v3_scale(q2, 23), q3)), 1.0 / 48);
        check_v(a[2 * k], k0.x, k0.y, k0.z, 1e-12);
        check_v(b[2 * k], m.x, m.y, m.z, 1e-12);
        check_v(a[2 * k + 1], m.x, m.y, m.z, 1e-12);
        check_v(b[2 * k + 1], k1.x, k1.y, k1.z, 1e-12);
    }
    /* the closed curve ends where it started */
    if (n == 8)
        check_v(b[7], a[0].x, a[0].y, a[0].z, 1e-12);
    /* open (kind 3): the one window of four control points */
    n = spine(ctx, v, "{(3,2) " SQUARE " }(3)", a, b, 16);
    CHECK_EQ_INT(n, 2);
    check_v(a[0], -1.0 / 6, 5.0 / 6, 0, 1e-12);
    check_v(b[1], -5.0 / 6, 5.0 / 6, 0, 1e-12);
    /* 4 bands by default; .(k) sets the bands of the connection it ends */
    CHECK_EQ_INT(spine(ctx, v, "{(3) " SQUARE " }(3)", a, b, 16), 4);
    CHECK_EQ_INT(spine(ctx, v, "{(3) . f(1) +(90) f(1) +(90) f(1) +(90) .(3) }(3)", a, b, 16),
                 4 + 3);
    cbm_view_destroy(v);
    /* as a cylinder: the first ring sits at the knot (-1/6, 5/6, 0) with P1's U = -z carried to
     * the heading (-1, 1, 0)/sqrt 2 (a rotation about z keeps it); its first point is P + r U,
     * r = 0.5; the last ring of the closed curve is back at that knot */
    char path[1024];
    snprintf(path, sizeof path, "%s/splb.v", test_tmp_dir());
    write_file(path, "line style: cylinder\n");
    CHECK_OK(cbm_view_load(ctx, path, &v));
    prog p;
    cbm_turtle *t = run_scene(ctx, v, &p, "{(4,2) " SQUARE " }(4)", NULL);
    const cbm_prim *pr = cbm_turtle_prims(t);
    const cbm_vec3 *pts = cbm_turtle_points(t);
    CHECK_EQ_INT(cbm_turtle_prim_count(t), 4);
    if (cbm_turtle_prim_count(t) == 4) {
        check_v(pts[pr[0].first + 2], -1.0 / 6, 5.0 / 6, -0.5, 1e-12);
        check_v(pr[0].p0, -1.0 / 6, 5.0 / 6, 0, 1e-12);
        check_v(pr[3].p1, -1.0 / 6, 5.0 / 6, 0, 1e-12);
        for (int i = 0; i < 4; i++)
            CHECK_EQ_INT(pr[i].count, 3 * 2 * 8 * 2);
    }
    end_run(ctx, v, t);
}

TEST(spline_cylinder_hermite_square)
{
    cbm_context *ctx = test_ctx();
    cbm_view *v;
    CHECK_OK(cbm_view_create(ctx, &v));
    cbm_vec3 a[16], b[16];
    /* open Hermite (kind 1): connections P0-P1, P1-P2, P2-P3 with tangents 1.2 |P2 - P1| H
     * (cpfg's tangent parameter); at t = 1/2 the curve is (P1 + P2) / 2 + (R1 - R2) / 8 */
    size_t n = spine(ctx, v, "{(1,2) " SQUARE " }(1)", a, b, 16);
    CHECK_EQ_INT(n, 6);
    check_v(a[0], 0, 0, 0, 1e-12);
    check_v(b[0], 0, 0.5, 0, 1e-12);      /* straight: H = +y at both ends */
    check_v(b[2], -0.35, 1.15, 0, 1e-12); /* H1 = +y, H2 = -x */
    check_v(b[3], -1, 1, 0, 1e-12);
    check_v(b[4], -1.15, 0.65, 0, 1e-12); /* H1 = -x, H2 = -y */
    check_v(b[5], -1, 0, 0, 1e-12);
    /* closed (kind 2): a fourth connection back to the first control point (H = +y there) */
    n = spine(ctx, v, "{(2,2) " SQUARE " }(2)", a, b, 16);
    CHECK_EQ_INT(n, 8);
    check_v(b[6], -0.5, -0.3, 0, 1e-12); /* H1 = -y, H2 = +y */
    check_v(b[7], 0, 0, 0, 1e-12);
    /* as a cylinder: one generalized-cylinder primitive per connection, 2 bands of 8 sides */
    char path[1024];
    snprintf(path, sizeof path, "%s/spl.v", test_tmp_dir());
    write_file(path, "line style: cylinder\n");
    cbm_view *vc;
    CHECK_OK(cbm_view_load(ctx, path, &vc));
    prog p;
    cbm_scene *scene;
    CHECK_OK(cbm_scene_create(ctx, &scene));
    cbm_turtle *t = run_scene(ctx, vc, &p, "{(2,2) " SQUARE " }(2)", scene);
    const cbm_prim *pr = cbm_turtle_prims(t);
    CHECK_EQ_INT(cbm_turtle_prim_count(t), 4);
    for (size_t i = 0; i < cbm_turtle_prim_count(t); i++) {
        CHECK_EQ_INT(pr[i].kind, CBM_PRIM_GCYL);
        CHECK_EQ_INT(pr[i].count, 3 * 2 * 8 * 2);
    }
    CHECK_EQ_INT(cbm_scene_triangle_count(scene), 4 * 2 * 8 * 2);
    cbm_turtle_destroy(t);
    cbm_scene_destroy(scene);
    cbm_view_destroy(vc);
    cbm_view_destroy(v);
    test_ctx_end(ctx);
}

TEST(spline_cylinder_degenerate)
{
    cbm_context *ctx = test_ctx();
    cbm_view *v;
    CHECK_OK(cbm_view_create(ctx, &v));
    cbm_vec3 a[16], b[16];
    /* too few control points draw nothing, as cpfg: Hermite needs 2, open B-spline 4 */
    CHECK_EQ_INT(spine(ctx, v, "{(1) . }(1)", a, b, 16), 0);
    CHECK_EQ_INT(spine(ctx, v, "{(2) . }(2)", a, b, 16), 0);
    CHECK_EQ_INT(spine(ctx, v, "{(3) . f +(90) f }(3)", a, b, 16), 0);
    CHECK_EQ_INT(spine(ctx, v, "{(4) }(4)", a, b, 16), 0);
    CHECK_EQ_INT(spine(ctx, v, "{(4) . }(4)", a, b, 16), 0); /* all points coincide */
    /* a closed B-spline of two points is fed P0 P1 P0 P1 P0, as cpfg: two connections between
     * the knots (2 P0 + 4 P1) / 6 and (4 P0 + 2 P1) / 6 */
    size_t n = spine(ctx, v, "{(4,1) . f(3) }(4)", a, b, 16);
    CHECK_EQ_INT(n, 2);
    check_v(a[0], 0, 2, 0, 1e-12);
    check_v(b[0], 0, 1, 0, 1e-12);
    check_v(b[1], 0, 2, 0, 1e-12);
    /* kinds outside 1..4 are ignored (cpfg warns); } with a parameter and no spline too */
    CHECK_EQ_INT(spine(ctx, v, "{(5) " SQUARE " }(5) }(1) {(-1) " SQUARE " }(1)", a, b, 16), 0);
    /* an unfinished spline draws what it has */
    CHECK_EQ_INT(spine(ctx, v, "{(1,1) " SQUARE, a, b, 16), 3);
    /* coincident control points: no band */
    CHECK_EQ_INT(spine(ctx, v, "{(1,1) . . f(1) }(1)", a, b, 16), 1);
    /* {(0) is a polygon; . inside a polygon is a polygon vertex, not a control point */
    CHECK_EQ_INT(spine(ctx, v, "{(1,1) {(0) . f(1) +(90) f(1) }(0) }(1)", a, b, 16), 1);
    cbm_view_destroy(v);
    test_ctx_end(ctx);
}

TEST(spline_cylinder_branches)
{
    cbm_context *ctx = test_ctx();
    cbm_view *v;
    CHECK_OK(cbm_view_create(ctx, &v));
    cbm_vec3 a[16], b[16];
    /* a branch continues a copy of the spline; after ] the parent continues from its own last
     * control point (0, 1, 0) */
    size_t n = spine(ctx, v, "{(1,1) . f(1) [ +(90) f(1) ] f(1) }(1)", a, b, 16);
    CHECK_EQ_INT(n, 3);
    if (n == 3) {
        check_v(b[1], -1, 1, 0, 1e-12);
        check_v(a[2], 0, 1, 0, 1e-12);
        check_v(b[2], 0, 2, 0, 1e-12);
    }
    /* a spline opened in a branch ends with it */
    CHECK_EQ_INT(spine(ctx, v, "[ {(1,1) . f(1) ] f(1) f(1)", a, b, 16), 1);
    /* a B-spline window survives a branch: 4 control points across [ ] */
    n = spine(ctx, v, "{(3,1) . f(1) [ {(1,1) . f(5) }(1) ] +(90) f(1) +(90) f(1) }(3)", a, b, 16);
    CHECK_EQ_INT(n, 2);
    if (n == 2)
        check_v(a[1], -1.0 / 6, 5.0 / 6, 0, 1e-12);
    cbm_view_destroy(v);
    test_ctx_end(ctx);
}
