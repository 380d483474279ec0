/* The mesh and table writers: OBJ + MTL, PLY, glTF binary (static and animated), SVG, parts
 * CSV, the dispatch by extension, disk errors (nothing left behind) and out-of-memory loops. */
#define _POSIX_C_SOURCE 200809L
#include "io_util.h"

#include <dirent.h>
#include <signal.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

typedef cbm_status (*cbm_write_fn)(cbm_context *, const cbm_scene *, const char *,
                                   const cbm_write_options *);

static cbm_scene *demo(cbm_context *ctx, size_t segments, bool ground)
{
    cbm_scene *s = NULL;
    CHECK_OK(cbm_scene_create(ctx, &s));
    CHECK_OK(cbm_scene_demo_tree(ctx, s, segments, 6, ground, 3));
    return s;
}

static size_t kept_triangles(const cbm_scene *s, bool ground)
{
    size_t n = 0;
    for (size_t t = 0; t < cbm_scene_triangle_count(s); t++)
        n += ground || cbm_scene_parts(s)[cbm_scene_triangle_parts(s)[t]].organ != CBM_ORGAN_GROUND;
    return n;
}

TEST(obj_counts_groups_and_materials)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = demo(ctx, 300, true);
    for (int ground = 0; ground < 2; ground++) {
        cbm_write_options o = cbm_write_options_default();
        o.ground = ground;
        CHECK_OK(cbm_scene_write(ctx, s, io_path("tree.obj"), &o));
        char *obj = io_read_all(io_path("tree.obj"), NULL);
        char *mtl = io_read_all(io_path("tree.mtl"), NULL);
        CHECK(obj && mtl);
        if (!obj || !mtl)
            break;
        CHECK_EQ_INT(io_count(obj, "\nf "), kept_triangles(s, ground));
        CHECK_EQ_INT(io_count(obj, "\nv "), io_count(obj, "\nvn "));
        CHECK(strstr(obj, "mtllib tree.mtl\n") != NULL);
        CHECK(strstr(obj, "\ng branch_order_0\n") != NULL);
        CHECK(strstr(obj, "\ng branch_order_2\n") != NULL);
        CHECK(strstr(obj, "\ng leaf\n") != NULL);
        CHECK(strstr(obj, "\ng fruit\n") != NULL);
        CHECK((strstr(obj, "\ng ground\n") != NULL) == (ground == 1));
        /* every material used is defined */
        CHECK(io_count(mtl, "newmtl ") >= 3);
        for (const char *u = strstr(obj, "usemtl "); u; u = strstr(u + 1, "usemtl ")) {
            char name[64], def[80];
            CHECK(sscanf(u, "usemtl %63s", name) == 1);
            snprintf(def, sizeof def, "newmtl %s\n", name);
            CHECK_MSG(strstr(mtl, def) != NULL, "material %s not defined", name);
        }
        /* face indices in range */
        size_t nv = io_count(obj, "\nv ");
        for (const char *f = strstr(obj, "\nf "); f; f = strstr(f + 1, "\nf ")) {
            unsigned a, b, c;
            CHECK(sscanf(f, "\nf %u//%*u %u//%*u %u//%*u", &a, &b, &c) == 3);
            CHECK(a >= 1 && b >= 1 && c >= 1 && a <= nv && b <= nv && c <= nv);
        }
        free(obj);
        free(mtl);
    }
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

static uint32_t rd32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float rdf(const unsigned char *p)
{
    uint32_t u = rd32(p);
    float f;
    memcpy(&f, &u, 4);
    return f;
}

TEST(ply_binary_layout_and_values)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(io_small_scene(ctx, &s));
    CHECK_OK(cbm_scene_write(ctx, s, io_path("small.ply"), NULL));
    size_t len = 0;
    char *b = io_read_all(io_path("small.ply"), &len);
    CHECK(b != NULL);
    if (b) {
        size_t nv = 0, nf = 0;
        CHECK(strncmp(b, "ply\nformat binary_little_endian 1.0\n", 36) == 0);
        const char *ev = strstr(b, "element vertex "), *ef = strstr(b, "element face ");
        CHECK(ev && ef && sscanf(ev, "element vertex %zu", &nv) == 1 &&
              sscanf(ef, "element face %zu", &nf) == 1);
        const char *end = strstr(b, "end_header\n");
        CHECK(end != NULL);
        size_t head = (size_t)(end - b) + 11;
        CHECK_EQ_INT(nv, cbm_scene_vertex_count(s));
        CHECK_EQ_INT(nf, cbm_scene_triangle_count(s));
        CHECK_EQ_INT(len, head + 52 * nv + 17 * nf);
        const unsigned char *v0 = (const unsigned char *)b + head;
        const cbm_scene_vertex *sv = cbm_scene_vertices(s);
        CHECK(rdf(v0) == sv[0].p[0] && rdf(v0 + 4) == sv[0].p[1] && rdf(v0 + 8) == sv[0].p[2]);
        CHECK_NEAR(rdf(v0 + 28), 0.5, 1e-7); /* stress ratio of the tube */
        CHECK_NEAR(rdf(v0 + 32), 3.0, 1e-7); /* age */
        CHECK_EQ_INT(rd32(v0 + 44), 7);      /* segment */
        const unsigned char *f0 = v0 + 52 * nv;
        CHECK_EQ_INT(f0[0], 3);
        CHECK_EQ_INT(rd32(f0 + 1), cbm_scene_triangles(s)[0]);
        /* the last face is the fruit's: part 2 */
        CHECK_EQ_INT(rd32(f0 + 17 * (nf - 1) + 13), 2);
        free(b);
    }
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

/* Minimal GLB checks: header, chunk layout, JSON content. Full validation is the Khronos
 * validator's job in the CLI tests. */
static char *glb_json(const char *path, size_t *file_len)
{
    size_t len = 0;
    char *b = io_read_all(path, &len);
    if (!b)
        return NULL;
    const unsigned char *u = (const unsigned char *)b;
    CHECK(len >= 20 && memcmp(b, "glTF", 4) == 0);
    CHECK_EQ_INT(rd32(u + 4), 2);
    CHECK_EQ_INT(rd32(u + 8), len);
    uint32_t jl = rd32(u + 12);
    CHECK(memcmp(b + 16, "JSON", 4) == 0);
    CHECK(jl % 4 == 0 && 20 + jl <= len);
    if (20 + jl < len) {
        uint32_t bl = rd32(u + 20 + jl);
        CHECK(memcmp(b + 24 + jl, "BIN\0", 4) == 0);
        CHECK_EQ_INT(28 + jl + bl, len);
    }
    char *json = malloc(jl + 1);
    memcpy(json, b + 20, jl);
    json[jl] = '\0';
    free(b);
    *file_len = len;
    return json;
}

/* The value of the k-th element of the accessor an attribute names, found through the JSON
 * (accessors and bufferViews are written as flat arrays of objects in a fixed key order). */
static void glb_element(const char *path, const char *attr, int nth, size_t k, float *vf,
                        uint16_t *vh);

static float glb_attribute_of(const char *path, const char *attr, int nth, size_t k)
{
    float v = NAN;
    uint16_t h = 0;
    glb_element(path, attr, nth, k, &v, &h);
    return v;
}

/* The k-th 16-bit element of the accessor the nth attribute so named names (indices). */
static unsigned glb_u16_of(const char *path, const char *attr, int nth, size_t k)
{
    float v = NAN;
    uint16_t h = 0xffff;
    glb_element(path, attr, nth, k, &v, &h);
    return h;
}

static void glb_element(const char *path, const char *attr, int nth, size_t k, float *vf,
                        uint16_t *vh)
{
    size_t len = 0;
    char *b = io_read_all(path, &len), *json = b ? b + 20 : NULL;
    char key[64];
    snprintf(key, sizeof key, "\"%s\":", attr);
    const char *at = json ? strstr(json, key) : NULL;
    for (int i = 0; i < nth && at; i++)
        at = strstr(at + 1, key);
    const char *acc = json ? strstr(json, "\"accessors\":[") : NULL;
    const char *views = json ? strstr(json, "\"bufferViews\":[") : NULL;
    if (at && acc && views) {
        long ai = strtol(at + strlen(key), NULL, 10);
        const char *a = acc;
        for (long i = 0; i <= ai && a; i++)
            a = strstr(a + 1, "{\"bufferView\":");
        long vi = a ? strtol(a + 14, NULL, 10) : -1;
        const char *w = views;
        for (long i = 0; i <= vi && w; i++)
            w = strstr(w + 1, "{\"buffer\":0,\"byteOffset\":");
        if (w) {
            long off = strtol(w + 25, NULL, 10);
            uint32_t jl = rd32((const unsigned char *)b + 12);
            size_t pos = 28 + jl + (size_t)off;
            if (pos + 4 * k + 4 <= len)
                *vf = rdf((const unsigned char *)b + pos + 4 * k);
            if (pos + 2 * k + 2 <= len)
                memcpy(vh, b + pos + 2 * k, 2);
        }
    }
    free(b);
}

/* The same in the first attribute so named. */
static float glb_attribute(const char *path, const char *attr, size_t k)
{
    return glb_attribute_of(path, attr, 0, k);
}

TEST(glb_per_segment_attributes)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(io_small_scene(ctx, &s));
    CHECK_OK(cbm_scene_write(ctx, s, io_path("small.glb"), NULL));
    /* the first mesh is branch order 0: the tube with stress ratio 0.5, age 3, segment 7 */
    for (size_t k = 0; k < 10; k++) {
        CHECK(glb_attribute(io_path("small.glb"), "_STRESS_RATIO", k) == 0.5f);
        CHECK(glb_attribute(io_path("small.glb"), "_AGE", k) == 3.0f);
        CHECK(glb_attribute(io_path("small.glb"), "_REACTION_WOOD", k) == 0.25f);
        CHECK(glb_attribute(io_path("small.glb"), "_ORDER", k) == 0.0f);
        CHECK(glb_attribute(io_path("small.glb"), "_SEGMENT", k) == 7.0f);
    }
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

/* A scene in instancing mode keeps straight uncapped tubes of constant section as instances;
 * the .glb writes them as EXT_mesh_gpu_instancing nodes whose TRS applied to the unit
 * cylinder gives the tessellated tube's points; capped or tapered tubes stay triangles; the
 * other writers refuse the scene. */
TEST(glb_tube_instances)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *si = NULL, *sm = NULL;
    CHECK_OK(cbm_scene_create(ctx, &si));
    CHECK_OK(cbm_scene_create(ctx, &sm));
    cbm_scene_set_instancing(si, true);
    CHECK(cbm_scene_instancing(si) && !cbm_scene_instancing(sm));
    cbm_part p = cbm_part_default();
    p.order = 0;
    p.segment = 7;
    p.stress_ratio = 0.5;
    /* H along (1, 2, 2) / 3, U perpendicular to it, L = U x H */
    cbm_frame f;
    f.h = (cbm_vec3){1.0 / 3, 2.0 / 3, 2.0 / 3};
    f.u = (cbm_vec3){2.0 / 3, 1.0 / 3, -2.0 / 3};
    f.l = (cbm_vec3){f.u.y * f.h.z - f.u.z * f.h.y, f.u.z * f.h.x - f.u.x * f.h.z,
                     f.u.x * f.h.y - f.u.y * f.h.x};
    cbm_section s0 = {{1, 2, 3}, f, 0.04, 0.02}, s1 = {{1 + 0.5, 2 + 1, 3 + 1}, f, 0.04, 0.02};
    cbm_section t1 = s1;
    t1.a = 0.03; /* tapered: triangles */
    for (int k = 0; k < 2; k++) {
        cbm_scene *s = k ? sm : si;
        CHECK_OK(cbm_scene_begin_part(s, &p, NULL));
        CHECK_OK(cbm_scene_add_tube(s, &s0, &s1, 8, false));
        CHECK_OK(cbm_scene_add_tube(s, &s0, &s1, 8, true));
        CHECK_OK(cbm_scene_add_tube(s, &s0, &t1, 8, false));
    }
    CHECK_EQ_INT(cbm_scene_instance_count(si), 1);
    CHECK_EQ_INT(cbm_scene_instance_count(sm), 0);
    CHECK_EQ_INT(cbm_scene_triangle_count(sm), cbm_scene_triangle_count(si) + 16);
    cbm_scene_instance_cursor cur = {0};
    cbm_scene_instance in0;
    CHECK_OK(cbm_scene_instance_read(si, 0, &cur, &in0));
    CHECK(in0.sides == 8 && in0.part == 0 && in0.a == 0.04f && in0.b == 0.02f);
    CHECK(cbm_scene_instance_read(si, 1, &cur, &in0) == CBM_E_INVALID);
    cbm_vec3 lo, hi;
    CHECK(cbm_scene_bounds(si, &lo, &hi));
    CHECK(lo.x <= 1 - 0.04 + 1e-6 && hi.z >= 4 + 0.04 - 1e-6);

    CHECK_OK(cbm_scene_write(ctx, si, io_path("inst.glb"), NULL));
    size_t len = 0;
    char *j = glb_json(io_path("inst.glb"), &len);
    CHECK(j && strstr(j, "\"extensionsRequired\":[\"EXT_mesh_gpu_instancing\"]"));
    CHECK(j && strstr(j, "\"name\":\"branch order 0 tubes\""));
    free(j);
    const char *g = io_path("inst.glb");
    float t[3], q[4], sc[3];
    for (int k = 0; k < 3; k++) {
        t[k] = glb_attribute(g, "TRANSLATION", (size_t)k);
        sc[k] = glb_attribute(g, "SCALE", (size_t)k);
    }
    for (int k = 0; k < 4; k++)
        q[k] = glb_attribute(g, "ROTATION", (size_t)k);
    CHECK(t[0] == 1.0f && t[1] == 2.0f && t[2] == 3.0f);
    CHECK(sc[0] == 0.04f && fabsf(sc[1] - 1.5f) < 1e-6f && sc[2] == 0.02f);
    CHECK(glb_attribute(g, "_SEGMENT", 0) == 7.0f && glb_attribute(g, "_STRESS_RATIO", 0) == 0.5f);
    /* the tessellated tube's first ring from the instance: R (S (cos t, 0, sin t)) + T */
    const cbm_scene_vertex *v = cbm_scene_vertices(sm);
    double x = q[0], y = q[1], z = q[2], w = q[3];
    double m[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                      {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                      {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
    for (int k = 0; k < 8; k++) {
        double a = 2.0 * 3.14159265358979323846 * k / 8;
        double lp[3] = {sc[0] * cos(a), 0.0, sc[2] * sin(a)};
        for (int r = 0; r < 3; r++) {
            double pw = t[r] + m[r][0] * lp[0] + m[r][1] * lp[1] + m[r][2] * lp[2];
            CHECK(fabs(pw - v[k].p[r]) < 1e-6);
        }
    }
    /* meshes other than .glb refuse instances, as they refuse pixel lines */
    CHECK_STATUS(cbm_scene_write(ctx, si, io_path("inst.obj"), NULL), CBM_E_UNSUPPORTED);
    CHECK_STATUS(cbm_scene_write(ctx, si, io_path("inst.ply"), NULL), CBM_E_UNSUPPORTED);
    cbm_scene_clear(si);
    CHECK(cbm_scene_instance_count(si) == 0 && cbm_scene_instancing(si));
    cbm_scene_destroy(si);
    cbm_scene_destroy(sm);
    test_ctx_end(ctx);
}

/* Shared parts (cbm_scene_begin_part_shared): segments that differ only by their id share one
 * part, the last one or any begun before (orders interleaved, as a tree's are along its string),
 * and keep their ids in their instances; any other geometry stores its part; the .glb is the
 * same bytes as with a part per segment. 20,000 instances: several of the writer's chunks. */
TEST(glb_shared_parts)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *sh = NULL, *pl = NULL;
    CHECK_OK(cbm_scene_create(ctx, &sh));
    CHECK_OK(cbm_scene_create(ctx, &pl));
    cbm_scene_set_instancing(sh, true);
    cbm_scene_set_instancing(pl, true);
    const size_t n = 20000;
    for (int k = 0; k < 2; k++) {
        cbm_scene *s = k ? pl : sh;
        for (size_t i = 0; i < n; i++) {
            cbm_part p = cbm_part_default();
            p.order = (int32_t)(i / 5000 + i % 3);
            p.segment = (int64_t)(i + 100);
            size_t run = i / 777; /* runs of 777 of one colour */
            p.color[1] = (float)run * 0.01f;
            CHECK_OK(k ? cbm_scene_begin_part(s, &p, NULL) : cbm_scene_begin_part_shared(s, &p));
            cbm_frame f = {{0, 1, 0}, {1, 0, 0}, {0, 0, -1}};
            double x = 0.01 * (double)i;
            cbm_section s0 = {{x, 0, 0}, f, 0.002, 0.001}, s1 = {{x, 0.5, 0}, f, 0.002, 0.001};
            CHECK_OK(cbm_scene_add_tube(s, &s0, &s1, 8, false));
            if (i % 4999 == 3) { /* a polygon in the same part: stored with its segment */
                cbm_vec3 q[3] = {{x, 0, 0}, {x + 0.1, 0, 0}, {x, 0, 0.1}};
                CHECK_OK(cbm_scene_add_polygon(s, q, 3));
            }
        }
    }
    CHECK_EQ_INT(cbm_scene_instance_count(sh), n);
    CHECK_EQ_INT(cbm_scene_part_count(pl), n);
    size_t np = cbm_scene_part_count(sh);
    CHECK(np < 110); /* 26 colours by 3 orders (a part a segment: 20,000) */
    const cbm_part *parts = cbm_scene_parts(sh);
    cbm_scene_instance_cursor cur = {0};
    for (size_t i = 0; i < n; i++) {
        cbm_scene_instance in;
        CHECK_OK(cbm_scene_instance_read(sh, i, &cur, &in));
        CHECK(in.segment == (float)(i + 100));
        CHECK(parts[in.part].order == (int32_t)(i / 5000 + i % 3));
    }
    /* the polygons' triangles share the parts and keep their own segments */
    const uint32_t *tp = cbm_scene_triangle_parts(sh);
    const float *ts = cbm_scene_triangle_segments(sh);
    size_t nt = cbm_scene_triangle_count(sh);
    CHECK(nt > 0 && ts && !cbm_scene_triangle_segments(pl));
    for (size_t t = 0; ts && t < nt; t++) {
        CHECK(((int64_t)ts[t] - 103) % 4999 == 0);
        CHECK(parts[tp[t]].order ==
              (int32_t)(((int64_t)ts[t] - 100) / 5000 + ((int64_t)ts[t] - 100) % 3));
    }
    CHECK_OK(cbm_scene_write(ctx, sh, io_path("shared.glb"), NULL));
    CHECK_OK(cbm_scene_write(ctx, pl, io_path("plain.glb"), NULL));
    size_t la = 0, lb = 0;
    char *a = io_read_all(io_path("shared.glb"), &la), *b = io_read_all(io_path("plain.glb"), &lb);
    CHECK(a && b && la == lb && memcmp(a, b, la) == 0);
    free(a);
    free(b);
    /* a cleared scene shares from its own parts only */
    cbm_scene_clear(sh);
    cbm_part q = cbm_part_default();
    CHECK_OK(cbm_scene_begin_part_shared(sh, &q));
    q.order = 1;
    CHECK_OK(cbm_scene_begin_part_shared(sh, &q));
    q.order = -1;
    CHECK_OK(cbm_scene_begin_part_shared(sh, &q));
    CHECK_EQ_INT(cbm_scene_part_count(sh), 2);
    /* without instancing every part is stored */
    cbm_scene_clear(sh);
    cbm_scene_set_instancing(sh, false);
    cbm_part p = cbm_part_default();
    CHECK_OK(cbm_scene_begin_part_shared(sh, &p));
    CHECK_OK(cbm_scene_begin_part_shared(sh, &p));
    CHECK_EQ_INT(cbm_scene_part_count(sh), 2);
    cbm_scene_destroy(sh);
    cbm_scene_destroy(pl);
    test_ctx_end(ctx);
}

/* The scene's encoding of its instances gives back every field bit for bit, read in order, in
 * reverse and at random: chains of segments (a field the previous one's), jumps (every field
 * new), segment ids by small steps, large ones, -1; a chain costs 14 bytes an instance. */
static bool float_bits_equal(const float *a, const float *b, int n)
{
    for (int k = 0; k < n; k++) {
        uint32_t x, y;
        memcpy(&x, &a[k], sizeof x);
        memcpy(&y, &b[k], sizeof y);
        if (x != y)
            return false;
    }
    return true;
}

TEST(scene_instance_stream)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(cbm_scene_create(ctx, &s));
    cbm_scene_set_instancing(s, true);
    enum { N = 3000 };
    static cbm_scene_instance want[N];
    static int32_t want_order[N];
    uint64_t r = 12345;
    cbm_vec3 at = {0, 0, 0};
    int64_t seg = 0;
    const cbm_frame frames[3] = {{{0, 1, 0}, {1, 0, 0}, {0, 0, -1}},
                                 {{1, 0, 0}, {0, 0, 1}, {0, -1, 0}},
                                 {{0, 0, -1}, {0, 1, 0}, {1, 0, 0}}};
    int fr = 0;
    double a = 0.01, len = 0.3;
    for (size_t i = 0; i < N; i++) {
        r = r * 6364136223846793005ull + 1442695040888963407ull;
        unsigned bits = (unsigned)(r >> 40);
        if (i >= 1000 && i < 1300) /* a plain chain */
            bits = 0;
        if (bits & 1) /* a jump */
            at = (cbm_vec3){(double)(bits % 97) * 0.37, (double)(bits % 13) * -1.1, 0.5};
        if (bits & 2)
            fr = (fr + 1) % 3;
        if (bits & 4)
            a = 0.001 * (double)(bits % 50 + 1);
        seg += bits & 8 ? (int64_t)(bits % 100000) - 20000 : (int64_t)(bits % 9) - 3;
        int64_t id = bits & 16 && i % 7 == 0 ? -1 : seg;
        cbm_part p = cbm_part_default();
        p.order = (int32_t)(bits >> 5 & 3);
        p.segment = id;
        CHECK_OK(cbm_scene_begin_part_shared(s, &p));
        double taper = bits & 32 ? 0.5 : 1.0;
        if (bits & 64)
            len = 0.01 * (double)(bits % 77 + 1);
        const cbm_vec3 h = frames[fr].h;
        cbm_vec3 end = {at.x + h.x * len, at.y + h.y * len, at.z + h.z * len};
        cbm_section s0 = {at, frames[fr], a, 0.5 * a},
                    s1 = {end, frames[fr], a * taper, 0.5 * a * taper};
        int sides = bits & 128 ? 6 : 8;
        CHECK_OK(cbm_scene_add_tube(s, &s0, &s1, sides, false));
        cbm_scene_instance w = {
            {(float)at.x, (float)at.y, (float)at.z},
            {(float)end.x, (float)end.y, (float)end.z},
            {(float)frames[fr].u.x, (float)frames[fr].u.y, (float)frames[fr].u.z},
            (float)a,
            (float)(0.5 * a),
            (float)taper,
            0,
            sides,
            id >= 0 ? (float)(double)id : -1.0f};
        want[i] = w;
        want_order[i] = p.order;
        at = end;
    }
    CHECK_EQ_INT(cbm_scene_instance_count(s), N);
    const cbm_part *parts = cbm_scene_parts(s);
    cbm_scene_instance_cursor c = {0};
    bool same = true;
    for (size_t k = 0; k < 3 * N; k++) {
        /* in order, then in reverse, then at random */
        size_t i = k < N ? k : k < 2 * N ? 2 * N - 1 - k : (size_t)((k * 2654435761u) % N);
        cbm_scene_instance got;
        CHECK_OK(cbm_scene_instance_read(s, i, &c, &got));
        same = same && float_bits_equal(got.p0, want[i].p0, 3) &&
               float_bits_equal(got.p1, want[i].p1, 3) && float_bits_equal(got.u, want[i].u, 3) &&
               got.a == want[i].a && got.b == want[i].b && got.taper == want[i].taper &&
               got.sides == want[i].sides && float_bits_equal(&got.segment, &want[i].segment, 1) &&
               parts[got.part].order == want_order[i];
        if (!same) {
            fprintf(stderr, "instance %zu differs\n", i);
            break;
        }
    }
    CHECK(same);
    /* a chain: 14 bytes an instance and a key every 256 */
    cbm_scene_clear(s);
    cbm_part p = cbm_part_default();
    for (size_t i = 0; i < 4096; i++) {
        p.segment = (int64_t)(2 * i);
        CHECK_OK(cbm_scene_begin_part_shared(s, &p));
        cbm_section s0 = {{0, (double)i, 0}, frames[0], 0.01, 0.01},
                    s1 = {{0, (double)i + 1, 0}, frames[0], 0.01, 0.01};
        CHECK_OK(cbm_scene_add_tube(s, &s0, &s1, 8, false));
    }
    size_t bytes = cbm_scene_instance_bytes(s);
    CHECK(bytes < 4096 * 15);
    CHECK(cbm_scene_instance_read(s, 4096, &c, &want[0]) == CBM_E_INVALID);
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

/* Placed shapes (the turtle's predefined surfaces): a scene in instancing mode keeps the shape
 * once and each placement; the .glb's TRS of each placement applied to the shape gives the
 * triangles an ordinary scene gets (points and normals, a mirroring and a proper placement), and
 * the other writers refuse the scene. */
static void check_placed(const char *g, const cbm_scene *sm, size_t v0, const cbm_vec3 *pos,
                         const cbm_vec3 *nrm, size_t nv, size_t node)
{
    float t[3], q[4], sc[3];
    /* the accessors of the node-th instanced node */
    for (int k = 0; k < 3; k++)
        t[k] = glb_attribute_of(g, "TRANSLATION", node, (size_t)k);
    for (int k = 0; k < 4; k++)
        q[k] = glb_attribute_of(g, "ROTATION", node, (size_t)k);
    for (int k = 0; k < 3; k++)
        sc[k] = glb_attribute_of(g, "SCALE", node, (size_t)k);
    double x = q[0], y = q[1], z = q[2], w = q[3];
    double m[3][3] = {{1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)},
                      {2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)},
                      {2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)}};
    const cbm_scene_vertex *v = cbm_scene_vertices(sm);
    for (size_t i = 0; i < nv; i++) {
        double lp[3] = {sc[0] * pos[i].x, sc[1] * pos[i].y, sc[2] * pos[i].z};
        double ln[3] = {nrm[i].x / sc[0], nrm[i].y / sc[1], nrm[i].z / sc[2]}, wn[3], len = 0;
        for (int r = 0; r < 3; r++) {
            double pw = t[r] + m[r][0] * lp[0] + m[r][1] * lp[1] + m[r][2] * lp[2];
            CHECK_MSG(fabs(pw - v[v0 + i].p[r]) < 1e-6, "vertex %zu: %g vs %g", i, pw,
                      (double)v[v0 + i].p[r]);
            wn[r] = m[r][0] * ln[0] + m[r][1] * ln[1] + m[r][2] * ln[2];
            len += wn[r] * wn[r];
        }
        for (int r = 0; r < 3; r++)
            CHECK(fabs(wn[r] / sqrt(len) - v[v0 + i].n[r]) < 1e-6);
    }
}

TEST(glb_surface_placements)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *si = NULL, *sm = NULL;
    CHECK_OK(cbm_scene_create(ctx, &si));
    CHECK_OK(cbm_scene_create(ctx, &sm));
    cbm_scene_set_instancing(si, true);
    /* a bent quad, no symmetry: two triangles, normals tilted */
    const cbm_vec3 pos[4] = {{0, 0, 0}, {1, 0, 0.2}, {1, 2, 0.1}, {-0.3, 1.5, 0}};
    cbm_vec3 nrm[4] = {{0.1, 0, 1}, {0, 0.2, 1}, {-0.1, 0.1, 1}, {0, 0, 1}};
    for (int i = 0; i < 4; i++) {
        double l = sqrt(nrm[i].x * nrm[i].x + nrm[i].y * nrm[i].y + nrm[i].z * nrm[i].z);
        nrm[i] = (cbm_vec3){nrm[i].x / l, nrm[i].y / l, nrm[i].z / l};
    }
    const uint32_t tri[6] = {0, 1, 2, 0, 2, 3};
    /* the turtle's frame: H, U, L = U x H; placements (L sx, H sy, U sz) mirror */
    cbm_vec3 h = {1.0 / 3, 2.0 / 3, 2.0 / 3}, u = {2.0 / 3, 1.0 / 3, -2.0 / 3};
    cbm_vec3 l = {u.y * h.z - u.z * h.y, u.z * h.x - u.x * h.z, u.x * h.y - u.y * h.x};
    const double sx[2] = {0.5, 0.25}, sy[2] = {2.0, 1.5}, sz[2] = {0.3, -0.4};
    cbm_part p = cbm_part_default();
    p.organ = CBM_ORGAN_LEAF;
    for (int k = 0; k < 2; k++) {
        cbm_scene *s = k ? sm : si;
        uint32_t id = 9;
        CHECK(!cbm_scene_find_shape(s, 42, &id));
        CHECK_OK(cbm_scene_add_shape(s, 42, pos, nrm, 4, tri, 2, &id));
        CHECK(id == 0 && cbm_scene_find_shape(s, 42, &id) && id == 0);
        for (int j = 0; j < 2; j++) {
            CHECK_OK(cbm_scene_begin_part(s, &p, NULL));
            cbm_vec3 o = {1 + j, 2, 3};
            CHECK_OK(cbm_scene_place_shape(s, 0, o,
                                           (cbm_vec3){l.x * sx[j], l.y * sx[j], l.z * sx[j]},
                                           (cbm_vec3){h.x * sy[j], h.y * sy[j], h.z * sy[j]},
                                           (cbm_vec3){u.x * sz[j], u.y * sz[j], u.z * sz[j]}));
        }
    }
    CHECK_STATUS(cbm_scene_place_shape(si, 1, (cbm_vec3){0, 0, 0}, l, h, u), CBM_E_INVALID);
    CHECK_EQ_INT(cbm_scene_placement_count(si), 2);
    CHECK_EQ_INT(cbm_scene_triangle_count(si), 0);
    CHECK_EQ_INT(cbm_scene_placement_count(sm), 0);
    CHECK_EQ_INT(cbm_scene_triangle_count(sm), 4);
    CHECK_EQ_INT(cbm_scene_vertex_count(sm), 8);
    /* the placements' bounds hold the triangles' points */
    cbm_vec3 lo, hi;
    CHECK(cbm_scene_bounds(si, &lo, &hi));
    const cbm_scene_vertex *v = cbm_scene_vertices(sm);
    for (size_t i = 0; i < 8; i++)
        CHECK(v[i].p[0] >= lo.x - 1e-6 && v[i].p[1] >= lo.y - 1e-6 && v[i].p[2] >= lo.z - 1e-6 &&
              v[i].p[0] <= hi.x + 1e-6 && v[i].p[1] <= hi.y + 1e-6 && v[i].p[2] <= hi.z + 1e-6);

    const char *g = io_path("placed.glb");
    CHECK_OK(cbm_scene_write(ctx, si, g, NULL));
    size_t len = 0;
    char *j = glb_json(g, &len);
    CHECK(j && strstr(j, "\"extensionsRequired\":[\"EXT_mesh_gpu_instancing\"]"));
    /* one node per placement here: the first mirrors, the second does not */
    const char *n1 = j ? strstr(j, "\"name\":\"leaf surfaces\"") : NULL;
    CHECK(n1 && strstr(n1 + 1, "\"name\":\"leaf surfaces\""));
    free(j);
    check_placed(g, sm, 0, pos, nrm, 4, 0);
    check_placed(g, sm, 4, pos, nrm, 4, 1);
    CHECK(glb_attribute_of(g, "SCALE", 0, 2) < 0.0f && glb_attribute_of(g, "SCALE", 1, 2) > 0.0f);
    /* the mirroring node's shape has its triangles reversed (a viewer reverses them again) */
    CHECK(glb_u16_of(g, "indices", 0, 0) == 0 && glb_u16_of(g, "indices", 0, 1) == 2 &&
          glb_u16_of(g, "indices", 0, 2) == 1 && glb_u16_of(g, "indices", 0, 5) == 2);
    CHECK(glb_u16_of(g, "indices", 1, 0) == 0 && glb_u16_of(g, "indices", 1, 1) == 1 &&
          glb_u16_of(g, "indices", 1, 2) == 2 && glb_u16_of(g, "indices", 1, 5) == 3);
    CHECK_STATUS(cbm_scene_write(ctx, si, io_path("placed.obj"), NULL), CBM_E_UNSUPPORTED);
    cbm_scene_clear(si);
    CHECK(cbm_scene_placement_count(si) == 0 && cbm_scene_shape_count(si) == 0);
    cbm_scene_destroy(si);
    cbm_scene_destroy(sm);
    test_ctx_end(ctx);
}

TEST(glb_nodes_attributes_and_animation)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *fr[3];
    for (int k = 0; k < 3; k++)
        fr[k] = demo(ctx, 40 + 120 * (size_t)k, true);
    CHECK_OK(cbm_scene_write(ctx, fr[2], io_path("tree.glb"), NULL));
    size_t len;
    char *j = glb_json(io_path("tree.glb"), &len);
    CHECK(j != NULL);
    if (j) {
        CHECK(strstr(j, "\"name\":\"branch order 0\"") && strstr(j, "\"name\":\"branch order 2\""));
        CHECK(strstr(j, "\"name\":\"leaf\"") && strstr(j, "\"name\":\"fruit\""));
        CHECK(strstr(j, "\"extras\":{\"organ\":\"branch\",\"order\":1}"));
        CHECK(strstr(j, "\"_STRESS_RATIO\":") && strstr(j, "\"_AGE\":") &&
              strstr(j, "\"_ORDER\":") && strstr(j, "\"_SEGMENT\":"));
        CHECK(strstr(j, "\"NORMAL\":") && strstr(j, "\"COLOR_0\":"));
        CHECK(strstr(j, "\"animations\"") == NULL);
        free(j);
    }
    cbm_write_options o = cbm_write_options_default();
    o.frames = (const cbm_scene *const *)fr;
    o.frame_count = 3;
    o.frame_time = 0.25;
    CHECK_OK(cbm_scene_write(ctx, NULL, io_path("growth.glb"), &o));
    j = glb_json(io_path("growth.glb"), &len);
    CHECK(j != NULL);
    if (j) {
        CHECK(strstr(j, "\"name\":\"frame 0\"") && strstr(j, "\"name\":\"frame 2\""));
        CHECK_EQ_INT(io_count(j, "\"interpolation\":\"STEP\""), 3);
        CHECK_EQ_INT(io_count(j, "\"path\":\"scale\""), 3);
        CHECK_EQ_INT(io_count(j, "\"scale\":[0,0,0]"), 2); /* the last frame shows statically */
        CHECK(strstr(j, "\"max\":[0.5]") != NULL);         /* frame times 0, 0.25, 0.5 s */
        free(j);
    }
    o.frame_time = 0;
    CHECK_STATUS(cbm_scene_write(ctx, NULL, io_path("bad.glb"), &o), CBM_E_INVALID);
    for (int k = 0; k < 3; k++)
        cbm_scene_destroy(fr[k]);
    test_ctx_end(ctx);
}

/* Frame by frame, refilling one scene, gives the same file as the list of frames. */
TEST(glb_animation_frame_by_frame)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *fr[3];
    for (int k = 0; k < 3; k++)
        fr[k] = demo(ctx, 30 + 50 * (size_t)k, true);
    cbm_write_options o = cbm_write_options_default();
    o.frames = (const cbm_scene *const *)fr;
    o.frame_count = 3;
    o.color_by = CBM_COLOR_AGE;
    CHECK_OK(cbm_scene_write(ctx, NULL, io_path("list.glb"), &o));
    cbm_animation *a = NULL;
    CHECK_OK(cbm_animation_create(ctx, &o, &a));
    cbm_scene *one = NULL;
    CHECK_OK(cbm_scene_create(ctx, &one));
    for (int k = 0; k < 3; k++) {
        cbm_scene_clear(one);
        CHECK_OK(cbm_scene_demo_tree(ctx, one, 30 + 50 * (size_t)k, 6, true, 3));
        CHECK_OK(cbm_animation_add_frame(a, one));
    }
    CHECK_EQ_INT(cbm_animation_frame_count(a), 3);
    CHECK_OK(cbm_animation_write(a, io_path("steps.glb")));
    CHECK_STATUS(cbm_animation_add_frame(a, one), CBM_E_INVALID);
    cbm_animation_destroy(a);
    size_t la = 0, lb = 0;
    char *x = io_read_all(io_path("list.glb"), &la), *y = io_read_all(io_path("steps.glb"), &lb);
    CHECK(x && y && la == lb && memcmp(x, y, la) == 0);
    free(x);
    free(y);
    o.frame_time = -1;
    CHECK_STATUS(cbm_animation_create(ctx, &o, &a), CBM_E_INVALID);
    o.frames = NULL;
    o.frame_count = 0;
    CHECK_OK(cbm_scene_write(ctx, one, io_path("static.glb"), &o)); /* frame_time unused */
    cbm_scene_destroy(one);
    for (int k = 0; k < 3; k++)
        cbm_scene_destroy(fr[k]);
    test_ctx_end(ctx);
}

TEST(svg_well_formed_and_sorted)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = demo(ctx, 200, true);
    cbm_write_options o = cbm_write_options_default();
    o.view = CBM_VIEW_FRONT;
    o.color_by = CBM_COLOR_AGE;
    CHECK_OK(cbm_scene_write(ctx, s, io_path("front.svg"), &o));
    char *b = io_read_all(io_path("front.svg"), NULL);
    CHECK(b != NULL);
    if (b) {
        CHECK(strncmp(b, "<?xml version=\"1.0\"", 19) == 0);
        CHECK(strstr(b, "</svg>\n") != NULL);
        size_t paths = io_count(b, "<path ");
        /* back faces of closed organs culled: fewer paths than triangles, but many */
        CHECK(paths > cbm_scene_triangle_count(s) / 4 && paths < cbm_scene_triangle_count(s));
        CHECK(strstr(b, ">age (years)</text>") != NULL && strstr(b, "linearGradient") != NULL);
        CHECK_EQ_INT(io_count(b, "<g"), io_count(b, "</g>"));
        free(b);
    }
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

TEST(csv_one_row_per_part)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(io_small_scene(ctx, &s));
    CHECK_OK(cbm_scene_write(ctx, s, io_path("parts.csv"), NULL));
    char *b = io_read_all(io_path("parts.csv"), NULL);
    CHECK(b != NULL);
    if (b) {
        const char *head = "id,segment,parent,organ,order,material,stress_Pa,stress_ratio,";
        CHECK(strncmp(b, head, strlen(head)) == 0);
        CHECK_EQ_INT(io_count(b, "\n"), 1 + cbm_scene_part_count(s));
        CHECK(strstr(b, "\n0,7,-1,branch,0,-1,,0.5,3,0.25,") != NULL);
        CHECK(strstr(b, "\n1,-1,-1,leaf,-1,-1,,,,,") != NULL);
        free(b);
    }
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

TEST(unknown_extension_and_missing_directory)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(io_small_scene(ctx, &s));
    CHECK_STATUS(cbm_scene_write(ctx, s, io_path("x.stl"), NULL), CBM_E_UNSUPPORTED);
    CHECK(strstr(cbm_context_last_error(ctx), "x.stl") != NULL);
    const char *exts[] = {"obj", "ply", "glb", "png", "svg", "csv"};
    for (int k = 0; k < 6; k++) {
        char p[4200];
        snprintf(p, sizeof p, "%s/no/such/dir/out.%s", test_tmp_dir(), exts[k]);
        cbm_context_clear_errors(ctx);
        CHECK_STATUS(cbm_scene_write(ctx, s, p, NULL), CBM_E_IO);
        CHECK_MSG(strstr(cbm_context_last_error(ctx), p) != NULL, "%s: message '%s'", exts[k],
                  cbm_context_last_error(ctx));
    }
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

static size_t dir_entries(const char *dir)
{
    DIR *d = opendir(dir);
    size_t n = 0;
    if (!d)
        return 0;
    for (struct dirent *e; (e = readdir(d));)
        n += strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
    closedir(d);
    return n;
}

/* A full disk, simulated with a file-size limit (EFBIG on write): every writer reports CBM_E_IO
 * naming the path and leaves nothing in the directory. */
TEST(disk_full_leaves_nothing)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = demo(ctx, 400, true);
    char dir[4200];
    snprintf(dir, sizeof dir, "%s/full", test_tmp_dir());
    mkdir(dir, 0777);
    struct rlimit old, lim;
    getrlimit(RLIMIT_FSIZE, &old);
    lim = old;
    lim.rlim_cur = 4096;
    signal(SIGXFSZ, SIG_IGN);
    CHECK(setrlimit(RLIMIT_FSIZE, &lim) == 0);
    const char *exts[] = {"obj", "ply", "glb", "png", "svg", "csv"};
    cbm_write_options o = cbm_write_options_default();
    o.width = o.height = 256;
    o.threads = 1;
    for (int k = 0; k < 6; k++) {
        char p[4300];
        snprintf(p, sizeof p, "%s/tree.%s", dir, exts[k]);
        cbm_context_clear_errors(ctx);
        CHECK_STATUS(cbm_scene_write(ctx, s, p, &o), CBM_E_IO);
        CHECK_MSG(strstr(cbm_context_last_error(ctx), p) != NULL, "%s: message '%s'", exts[k],
                  cbm_context_last_error(ctx));
        CHECK_EQ_INT(dir_entries(dir), 0);
    }
    setrlimit(RLIMIT_FSIZE, &old);
    signal(SIGXFSZ, SIG_DFL);
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

/* /dev/full: written in place (never replaced), ENOSPC reported; /dev/null accepts anything. The
 * OBJ writer is left out: its .mtl would go beside the target, into /dev. */
TEST(device_targets_are_written_in_place)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = demo(ctx, 100, true);
    cbm_write_options o = cbm_write_options_default();
    o.width = o.height = 64;
    o.threads = 1;
    const char *exts[] = {"ply", "glb", "png", "svg", "csv"};
    cbm_write_fn fns[] = {cbm_write_ply, cbm_write_glb, cbm_write_png, cbm_write_svg,
                          cbm_write_parts_csv};
    for (int k = 0; k < 5; k++) {
        cbm_context_clear_errors(ctx);
        CHECK_STATUS(fns[k](ctx, s, "/dev/full", &o), CBM_E_IO);
        CHECK_MSG(strstr(cbm_context_last_error(ctx), "/dev/full: ") &&
                      strstr(cbm_context_last_error(ctx), "No space left"),
                  "%s: message '%s'", exts[k], cbm_context_last_error(ctx));
        CHECK_OK(fns[k](ctx, s, "/dev/null", &o));
        struct stat sb;
        CHECK(stat("/dev/full", &sb) == 0 && S_ISCHR(sb.st_mode));
        CHECK(stat("/dev/null", &sb) == 0 && S_ISCHR(sb.st_mode));
    }
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

/* A symbolic link to a regular file: the file is replaced, the link stays a link. */
TEST(links_are_kept)
{
    cbm_context *ctx = test_ctx();
    cbm_scene *s = NULL;
    CHECK_OK(io_small_scene(ctx, &s));
    char real[4200], link[4200];
    snprintf(real, sizeof real, "%s/real.csv", test_tmp_dir());
    snprintf(link, sizeof link, "%s/link.csv", test_tmp_dir());
    FILE *f = fopen(real, "w");
    CHECK(f != NULL);
    if (f) {
        fputs("old\n", f);
        fclose(f);
    }
    remove(link);
    CHECK(symlink("real.csv", link) == 0);
    CHECK_OK(cbm_scene_write(ctx, s, link, NULL));
    struct stat sb;
    CHECK(lstat(link, &sb) == 0 && S_ISLNK(sb.st_mode));
    char *b = io_read_all(real, NULL);
    CHECK(b && strncmp(b, "id,segment,", 11) == 0);
    free(b);
    cbm_scene_destroy(s);
    test_ctx_end(ctx);
}

typedef struct oom_case {
    const char *name;
} oom_case;

static cbm_status write_small(cbm_context *ctx, void *ud)
{
    const oom_case *c = ud;
    cbm_scene *s = NULL;
    cbm_status st0 = io_small_scene(ctx, &s);
    if (st0 != CBM_OK)
        return st0;
    cbm_write_options o = cbm_write_options_default();
    o.width = o.height = 32;
    o.threads = 1;
    o.color_by = CBM_COLOR_STRESS;
    cbm_scene *fr[2] = {s, s};
    if (strstr(c->name, "anim")) {
        o.frames = (const cbm_scene *const *)fr;
        o.frame_count = 2;
    }
    cbm_status st = cbm_scene_write(ctx, s, c->name, &o);
    cbm_scene_destroy(s);
    return st;
}

TEST(out_of_memory_every_writer)
{
    const char *names[] = {"oom.obj", "oom.ply", "oom.glb", "oom_anim.glb",
                           "oom.svg", "oom.csv", "oom.png"};
    for (int k = 0; k < 7; k++) {
        oom_case c = {io_path(names[k])};
        int runs = test_oom_loop(write_small, &c);
        CHECK_MSG(runs > 3, "%s: %d runs", names[k], runs);
    }
}
