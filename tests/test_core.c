/* Core services: status names, allocation accounting and limits, arena, arrays, generator,
 * vector and quaternion math, atomic output files, libraries loaded at run time, the scene. */
#include "test.h"

#include "core/core.h"
#include "core/dynlib.h"
#include "core/vecmath.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

TEST(status_names)
{
    CHECK(!strcmp(cbm_status_name(CBM_OK), "CBM_OK"));
    CHECK(!strcmp(cbm_status_name(CBM_E_NOT_CONVERGED), "CBM_E_NOT_CONVERGED"));
    CHECK(!strcmp(cbm_status_message(CBM_E_NOMEM), "out of memory"));
    CHECK(!strcmp(cbm_status_name((cbm_status)999), "CBM_E_UNKNOWN"));
}

TEST(alloc_accounting)
{
    cbm_context *ctx = test_ctx();
    void *p = cbm__alloc(ctx, 100);
    CHECK(p != NULL);
    CHECK_EQ_INT(cbm_context_bytes(ctx), 100);
    p = cbm__realloc(ctx, p, 100, 300);
    CHECK_EQ_INT(cbm_context_bytes(ctx), 300);
    cbm__free(ctx, p, 300);
    CHECK_EQ_INT(cbm_context_bytes(ctx), 0);
    CHECK_EQ_INT(cbm_context_peak_bytes(ctx), 300);
    test_ctx_end(ctx);
}

TEST(memory_limit)
{
    cbm_context *ctx = test_ctx();
    cbm_limits lim = *cbm_context_limits(ctx);
    lim.max_bytes = 1000;
    cbm_context_set_limits(ctx, &lim);
    void *a = cbm__alloc(ctx, 600);
    CHECK(a != NULL);
    CHECK(cbm__alloc(ctx, 600) == NULL);
    cbm__free(ctx, a, 600);
    test_ctx_end(ctx);
}

TEST(arrays_and_arena)
{
    cbm_context *ctx = test_ctx();
    CBM_ARRAY(int) a = {0};
    for (int i = 0; i < 1000; i++)
        CHECK_OK(CBM_ARRAY_PUSH(ctx, a, i));
    CHECK_EQ_INT(a.len, 1000);
    CHECK_EQ_INT(a.data[999], 999);
    CBM_ARRAY_FREE(ctx, a);

    cbm__arena ar;
    cbm__arena_init(&ar, ctx, 256);
    for (int round = 0; round < 3; round++) {
        for (int i = 0; i < 50; i++) {
            char *p = cbm__arena_alloc(&ar, 40);
            CHECK(p != NULL && ((uintptr_t)p & 15u) == 0);
            memset(p, 1, 40);
        }
        cbm__arena_reset(&ar);
    }
    size_t after_reset = cbm_context_bytes(ctx);
    cbm__arena_alloc(&ar, 40);
    cbm__arena_reset(&ar);
    CHECK_EQ_INT(cbm_context_bytes(ctx), after_reset); /* steady reuse allocates nothing */
    cbm__arena_destroy(&ar);
    test_ctx_end(ctx);
}

TEST(generator)
{
    cbm_rng a, b;
    cbm__rng_seed(&a, 42);
    cbm__rng_seed(&b, 42);
    for (int i = 0; i < 100; i++)
        CHECK(cbm__rng_next(&a) == cbm__rng_next(&b));
    double sum = 0, sum2 = 0;
    int n = 100000;
    for (int i = 0; i < n; i++) {
        double u = cbm__rng_uniform(&a);
        CHECK(u >= 0.0 && u < 1.0);
        double z = cbm__rng_normal(&b);
        sum += z;
        sum2 += z * z;
    }
    CHECK_NEAR(sum / n, 0.0, 0.02);
    CHECK_NEAR(sum2 / n, 1.0, 0.02);
}

TEST(quaternions)
{
    cbm_quat q = q_axis_angle(v3(0, 0, 1), CBM_PI / 2);
    cbm_vec3 r = q_rotate(q, v3(1, 0, 0));
    CHECK_NEAR(r.x, 0.0, 1e-15);
    CHECK_NEAR(r.y, 1.0, 1e-15);
    /* composition: a*b applies b first */
    cbm_quat qa = q_axis_angle(v3(1, 0, 0), 0.3), qb = q_axis_angle(v3(0, 1, 0), -0.7);
    cbm_vec3 v = v3(0.2, -1.1, 0.5);
    cbm_vec3 r1 = q_rotate(q_mul(qa, qb), v), r2 = q_rotate(qa, q_rotate(qb, v));
    CHECK_NEAR(v3_norm(v3_sub(r1, r2)), 0.0, 1e-14);
    /* rotation vector, small and large */
    cbm_vec3 rv = v3(1e-6, 2e-6, -1e-6);
    cbm_quat qs = q_from_rotvec(rv);
    CHECK_NEAR(qs.w * qs.w + qs.x * qs.x + qs.y * qs.y + qs.z * qs.z, 1.0, 1e-15);
    cbm_quat ql = q_from_rotvec(v3(0, 0, CBM_PI / 2));
    CHECK_NEAR(q_rotate(ql, v3(1, 0, 0)).y, 1.0, 1e-15);
    /* frames stay orthonormal and right-handed */
    cbm_frame f = frame_rotate(q_mul(qa, qb), frame_identity());
    CHECK_NEAR(v3_norm(v3_sub(v3_cross(f.h, f.l), f.u)), 0.0, 1e-14);
    cbm_vec3 loc = frame_to_local(f, v);
    CHECK_NEAR(v3_norm(v3_sub(frame_to_world(f, loc), v)), 0.0, 1e-14);
}

TEST(atomic_output)
{
    cbm_context *ctx = test_ctx();
    char path[4200];
    snprintf(path, sizeof path, "%s/a.txt", test_tmp_dir());
    unlink(path);
    cbm_out *o;
    CHECK_OK(cbm_out_open(ctx, path, &o));
    CHECK_OK(cbm_out_printf(o, "hello %d\n", 1));
    CHECK(access(path, F_OK) != 0); /* nothing at the target before commit */
    CHECK_OK(cbm_out_commit(o));
    FILE *f = fopen(path, "r");
    char buf[32] = {0};
    CHECK(f && fgets(buf, sizeof buf, f));
    CHECK(!strcmp(buf, "hello 1\n"));
    if (f)
        fclose(f);
    /* abort leaves the old file */
    CHECK_OK(cbm_out_open(ctx, path, &o));
    CHECK_OK(cbm_out_printf(o, "partial"));
    cbm_out_abort(o);
    f = fopen(path, "r");
    CHECK(f && fgets(buf, sizeof buf, f) && !strcmp(buf, "hello 1\n"));
    if (f)
        fclose(f);
    /* an unwritable directory is an error naming the path */
    CHECK_STATUS(cbm_out_open(ctx, "/nonexistent-dir/x.csv", &o), CBM_E_IO);
    CHECK(strstr(cbm_context_last_error(ctx), "/nonexistent-dir/x.csv") != NULL);
    /* a full disk is reported at commit */
    if (access("/dev/full", W_OK) == 0) {
        /* cannot create a temp beside /dev/full; write through the stream instead */
    }
    test_ctx_end(ctx);
}

/* The C library's math, loaded as the renderer loads Embree: a table typed by the functions. */
typedef struct math_api {
    __typeof__(cos) *cos;
    __typeof__(hypot) *hypot;
} math_api;

TEST(libraries_loaded_at_run_time)
{
    cbm_context *ctx = test_ctx();
    math_api m = {NULL, NULL};
    static const cbm__dynsym syms[] = {{"cos", offsetof(math_api, cos)},
                                       {"hypot", offsetof(math_api, hypot)}};
    cbm__dynlib lib = CBM__DYNLIB_INIT("libm.so.6", "libc6", syms, &m);
    CHECK_OK(cbm__dynlib_load(ctx, &lib, "test"));
    CHECK(m.cos && m.hypot);
    if (m.cos && m.hypot) {
        volatile double three = 3.0; /* a call through the table, not a folded constant */
        CHECK(m.cos(0.0) == 1.0);
        CHECK(m.hypot(three, 4.0) == 5.0);
    }
    CHECK_OK(cbm__dynlib_load(ctx, &lib, "test")); /* loaded: the table as it is */

    /* a library that is not installed: the status and a message naming it and its package,
     * the same at every later call; the table untouched */
    math_api none = {NULL, NULL};
    cbm__dynlib missing =
        CBM__DYNLIB_INIT("libcambium-no-such-library.so.9", "no-such-package", syms, &none);
    for (int k = 0; k < 2; k++) {
        CHECK_STATUS(cbm__dynlib_load(ctx, &missing, "renderer"), CBM_E_UNSUPPORTED);
        const char *e = cbm_context_last_error(ctx);
        CHECK(e && strstr(e, "renderer: cannot load libcambium-no-such-library.so.9 (Debian "
                             "package no-such-package)"));
    }
    CHECK(!none.cos && !none.hypot);
    CHECK_STATUS(cbm__dynlib_load(NULL, &missing, "renderer"), CBM_E_UNSUPPORTED);

    /* a library without one of the functions: refused whole, the function named */
    static const cbm__dynsym partial_syms[] = {{"cos", offsetof(math_api, cos)},
                                               {"cbm_no_such_function", offsetof(math_api, hypot)}};
    math_api half = {NULL, NULL};
    cbm__dynlib partial = CBM__DYNLIB_INIT("libm.so.6", "libc6", partial_syms, &half);
    CHECK_STATUS(cbm__dynlib_load(ctx, &partial, "plot"), CBM_E_UNSUPPORTED);
    CHECK(strstr(cbm_context_last_error(ctx), "has no function cbm_no_such_function"));
    CHECK(!half.cos && !half.hypot);
    test_ctx_end(ctx);
}

TEST(scene_tessellation)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s;
    CHECK_OK(cbm_scene_create(ctx, &s));
    cbm_part p = cbm_part_default();
    uint32_t id;
    CHECK_OK(cbm_scene_begin_part(s, &p, &id));
    CHECK_EQ_INT(id, 0);
    cbm_section a = {v3(0, 0, 0), frame_identity(), 0.1, 0.05};
    cbm_section b = a;
    b.center = v3(0, 1, 0);
    CHECK_OK(cbm_scene_add_tube(s, &a, &b, 8, true));
    CHECK_EQ_INT(cbm_scene_triangle_count(s), 16 + 16);
    /* outward normals: every side vertex normal points away from the axis */
    const cbm_scene_vertex *v = cbm_scene_vertices(s);
    for (int i = 0; i < 8; i++) {
        double dx = v[i].p[0], dz = v[i].p[2];
        CHECK(dx * v[i].n[0] + dz * v[i].n[2] > 0);
    }
    /* triangle winding agrees with the vertex normals */
    const uint32_t *t = cbm_scene_triangles(s);
    for (size_t k = 0; k < cbm_scene_triangle_count(s); k++) {
        const float *p0 = v[t[3 * k]].p, *p1 = v[t[3 * k + 1]].p, *p2 = v[t[3 * k + 2]].p;
        cbm_vec3 e1 = v3(p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]);
        cbm_vec3 e2 = v3(p2[0] - p0[0], p2[1] - p0[1], p2[2] - p0[2]);
        cbm_vec3 fn = v3_cross(e1, e2);
        const float *n0 = v[t[3 * k]].n;
        CHECK(v3_dot(fn, v3(n0[0], n0[1], n0[2])) > 0);
    }
    cbm_vec3 lo, hi;
    CHECK(cbm_scene_bounds(s, &lo, &hi));
    CHECK_NEAR(hi.y, 1.0, 1e-6);
    CHECK_NEAR(hi.z, 0.1, 1e-6); /* U = +z carries the semi-axis a */
    CHECK_NEAR(hi.x, 0.05, 1e-6);
    /* a concave polygon (an L shape) triangulates into n - 2 triangles */
    size_t before = cbm_scene_triangle_count(s);
    cbm_vec3 L[6] = {v3(0, 0, 0), v3(2, 0, 0), v3(2, 1, 0), v3(1, 1, 0), v3(1, 2, 0), v3(0, 2, 0)};
    CHECK_OK(cbm_scene_add_polygon(s, L, 6));
    CHECK_EQ_INT(cbm_scene_triangle_count(s) - before, 4);
    before = cbm_scene_triangle_count(s);
    CHECK_OK(cbm_scene_add_sphere(s, v3(0, 0, 0), 1.0, 8));
    CHECK(cbm_scene_triangle_count(s) > before);
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

static cbm_status oom_scene(cbm_context *ctx, void *ud)
{
    (void)ud;
    cbm_scene *s;
    CBM_TRY(cbm_scene_create(ctx, &s));
    cbm_part p = cbm_part_default();
    cbm_status st = cbm_scene_begin_part(s, &p, NULL);
    cbm_vec3 pts[5] = {v3(0, 0, 0), v3(1, 0, 0), v3(1, 1, 0), v3(0.5, 0.4, 0), v3(0, 1, 0)};
    if (st == CBM_OK)
        st = cbm_scene_add_polygon(s, pts, 5);
    if (st == CBM_OK)
        st = cbm_scene_add_sphere(s, v3(0, 0, 0), 1, 12);
    cbm_scene_destroy(s);
    return st;
}

TEST(scene_out_of_memory)
{
    int runs = test_oom_loop(oom_scene, NULL);
    CHECK(runs > 3);
}
