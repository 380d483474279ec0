/* Robustness of the side-file readers and the turtle: seeded mutations of real side files (the
 * oracle models' view, function, surface and contour files, read from ../shared at run time) and
 * random turtle programs, each run under a 64 MB byte limit. Every run must end with a status
 * (never a crash), and every byte must come back (test_ctx_end). Also replays the libFuzzer
 * corpus of fuzz_turtle_side, when present. Deterministic: fixed seeds. */
#define _POSIX_C_SOURCE 200809L
#include "test.h"

#include "core/vecmath.h"
#include "turtle/view_internal.h"

#include <stdlib.h>
#include <string.h>

#define ORACLE CBM_TEST_SOURCE_DIR "/../shared/oracles/vlab/"

static uint64_t rng_state = 0x9E3779B97F4A7C15u;

static uint64_t next_rand(void)
{
    uint64_t x = rng_state;
    x ^= x << 13;
    x ^= x >> 7;
    x ^= x << 17;
    return rng_state = x;
}

static char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *b = malloc((size_t)n + 1);
    size_t got = fread(b, 1, (size_t)n, f);
    fclose(f);
    b[got] = 0;
    *len = got;
    return b;
}

static cbm_context *limited_ctx(void)
{
    cbm_context *ctx = test_ctx();
    cbm_limits lim = *cbm_context_limits(ctx);
    lim.max_bytes = 64u << 20;
    cbm_context_set_limits(ctx, &lim);
    return ctx;
}

static bool acceptable(cbm_status s)
{
    return s == CBM_OK || s == CBM_E_FORMAT || s == CBM_E_NOMEM || s == CBM_E_LIMIT ||
           s == CBM_E_NONFINITE || s == CBM_E_IO || s == CBM_E_RUNTIME;
}

/* A program touching surfaces, contours, generalized cylinders, polygons and tropisms. */
static const char *const program[] = {"@#",  "@Gs", "F",  "~", "a", "~", "l", "@Gc", "+", "F",
                                      "_",   "@Ge", "{",  ".", "F", ".", "F", ".",   "}", "@O",
                                      "@Ts", "F",   "?P", "[", "&", "F", "%", "F",   "]", "!"};

static void run_program(cbm_context *ctx, const cbm_view *v)
{
    cbm_scene *scene = NULL;
    if (cbm_scene_create(ctx, &scene) != CBM_OK)
        return;
    enum { N = sizeof program / sizeof program[0] };
    cbm_tmodule m[N];
    double par[N][3];
    for (int i = 0; i < N; i++) {
        par[i][0] = 1.0 + (double)(i % 3);
        par[i][1] = 0.5;
        par[i][2] = 0.0;
        m[i].name = program[i];
        m[i].params = par[i];
        m[i].nparams = (i % 4 == 0) ? 0 : (i % 3 == 0 ? 3 : 1);
    }
    cbm_turtle *t = NULL;
    cbm_turtle_def def = {true};
    cbm_status s = cbm_turtle_interpret(ctx, v, &def, m, N, scene, &t);
    CHECK_MSG(acceptable(s), "turtle returned %s", cbm_status_name(s));
    cbm_turtle_destroy(t);
    cbm_scene_destroy(scene);
}

static void mutate(char *buf, size_t *len, size_t cap)
{
    int k = 1 + (int)(next_rand() % 4);
    static const char *const junk[] = {"-1", "1e300", "nan",       "0",    "999999", ":",
                                       "\n", " ",     "points: 3", "-0.0", "4 4 4 4"};
    for (int i = 0; i < k; i++) {
        size_t n = *len;
        size_t at = n ? (size_t)(next_rand() % n) : 0;
        switch (next_rand() % 4) {
        case 0: /* flip a byte */
            if (n)
                buf[at] = (char)(next_rand() & 0xff);
            break;
        case 1: { /* delete a range */
            size_t del = (size_t)(next_rand() % 16);
            if (at + del > n)
                del = n - at;
            memmove(buf + at, buf + at + del, n - at - del);
            *len = n - del;
            break;
        }
        default: { /* insert a token */
            const char *j = junk[next_rand() % (sizeof junk / sizeof junk[0])];
            size_t jl = strlen(j);
            if (n + jl < cap) {
                memmove(buf + at + jl, buf + at, n - at);
                memcpy(buf + at, j, jl);
                *len = n + jl;
            }
            break;
        }
        }
    }
    buf[*len] = 0;
}

typedef struct seedfile {
    const char *path;
    cbm__side_kind kind;
} seedfile;

static const seedfile seeds[] = {
    {ORACLE "cpfg-leaf-rnd/model/leaf.v", CBM__SIDE_VIEW},
    {ORACLE "cpfg-tropisms/model/view.v", CBM__SIDE_VIEW},
    {ORACLE "cpfg-lilac/model/plant.v", CBM__SIDE_VIEW},
    {ORACLE "cpfg-monopodial/model/internode.func", CBM__SIDE_FUNC},
    {ORACLE "lpfg-sympodial/model/functions.fset", CBM__SIDE_FSET},
    {ORACLE "cpfg-leaf-rnd/model/leaf.s", CBM__SIDE_SURFACE},
    {ORACLE "cpfg-lilac/model/calyx.s", CBM__SIDE_SURFACE},
    {ORACLE "cpfg-tropisms/model/stripe.con", CBM__SIDE_CONTOUR},
};

TEST(mutated_side_files)
{
    if (test_skip_without_oracles())
        return;
    size_t runs = 0;
    for (size_t f = 0; f < sizeof seeds / sizeof seeds[0]; f++) {
        size_t len;
        char *orig = slurp(seeds[f].path, &len);
        CHECK_MSG(orig != NULL, "cannot read %s", seeds[f].path);
        if (!orig)
            continue;
        size_t cap = len + 4096;
        char *buf = malloc(cap);
        for (int it = 0; it < 150; it++) {
            memcpy(buf, orig, len + 1);
            size_t n = len;
            mutate(buf, &n, cap);
            cbm_context *ctx = limited_ctx();
            cbm_view *v = NULL;
            CHECK_OK(cbm_view_create(ctx, &v));
            /* surfaces are named by the first letter of their name: 'a' and 'l' are used */
            const char *name =
                seeds[f].kind == CBM__SIDE_SURFACE ? (it & 1 ? "a.s" : "l.s") : seeds[f].path;
            cbm_status s = cbm__view_add_text(v, seeds[f].kind, name, buf);
            CHECK_MSG(acceptable(s), "%s mutation %d: %s", seeds[f].path, it, cbm_status_name(s));
            run_program(ctx, v);
            cbm_view_destroy(v);
            cbm_context_clear_errors(ctx);
            test_ctx_end(ctx);
            runs++;
        }
        free(buf);
        free(orig);
    }
    CHECK(runs == 150 * (sizeof seeds / sizeof seeds[0]));
}

TEST(random_programs)
{
    /* every command with parameters from a mix of ordinary and extreme values */
    static const char *const names[] = {
        "F",   "f",  "G",  "g",  "+",  "-",   "&",   "^",   "\\",  "/",   "|",   "[",
        "]",   "!",  "'",  ";",  ",",  "#",   "~",   "%",   "{",   "}",   ".",   "_",
        "@v",  "@O", "@o", "@c", "@M", "@Ts", "@Ti", "@Td", "@Gs", "@Gc", "@Ge", "@Gt",
        "@Gr", "@#", "@!", "?P", "?H", "?L",  "?U",  "@",   "?",   "A"};
    static const double values[] = {0, 1, -1, 0.5, 2, 45, 90, 180, 360, -30, 1e-9, 1e6, 3, 7};
    enum { NN = sizeof names / sizeof names[0], NV = sizeof values / sizeof values[0] };
    for (int prog = 0; prog < 200; prog++) {
        cbm_context *ctx = limited_ctx();
        cbm_view *v = NULL;
        CHECK_OK(cbm_view_create(ctx, &v));
        cbm_scene *scene = NULL;
        CHECK_OK(cbm_scene_create(ctx, &scene));
        enum { LEN = 300 };
        cbm_tmodule m[LEN];
        double par[LEN][4];
        for (int i = 0; i < LEN; i++) {
            m[i].name = names[next_rand() % NN];
            m[i].nparams = (int)(next_rand() % 5);
            m[i].params = par[i];
            for (int k = 0; k < 4; k++)
                par[i][k] = values[next_rand() % NV];
            /* keep generalized cylinders and sides of a sane size; the limit covers the rest */
            if (m[i].name[0] == '@' && (m[i].name[1] == 'G' || m[i].name[1] == '!'))
                par[i][0] = fmod(fabs(par[i][0]), 64.0);
        }
        cbm_turtle *t = NULL;
        cbm_turtle_def def = {prog & 1};
        cbm_status s = cbm_turtle_interpret(ctx, v, &def, m, LEN, scene, &t);
        CHECK_MSG(acceptable(s), "program %d: %s", prog, cbm_status_name(s));
        cbm_turtle_destroy(t);
        cbm_scene_destroy(scene);
        cbm_view_destroy(v);
        cbm_context_clear_errors(ctx);
        test_ctx_end(ctx);
    }
}

TEST(random_spline_programs)
{
    /* cpfg's spline cylinders {(n, r) ... }(n) of every kind (and invalid ones), with control
     * points from F, f and .(k), branches, polygons and @G cylinders mixed in, as lines and as
     * cylinders, with and without twist */
    static const char *const names[] = {"{", "}", ".",   "F",   "f",   "+",   "&",   "/", "[",
                                        "]", "!", "@Gs", "@Gc", "@Ge", "@Gt", "@Gr", "g", "G"};
    static const double values[] = {0, 1, 2, 3, 4, 5, -1, 0.5, 1e-9, 90, 30, 1e6, 7, 1};
    enum { NN = sizeof names / sizeof names[0], NV = sizeof values / sizeof values[0] };
    size_t ngcyl = 0; /* cylinder pieces recorded (of splines and of @G cylinders) */
    for (int prog = 0; prog < 200; prog++) {
        cbm_context *ctx = limited_ctx();
        cbm_view *v = NULL;
        CHECK_OK(cbm_view_create(ctx, &v));
        if (prog & 2)
            CHECK_OK(cbm__view_add_text(v, CBM__SIDE_VIEW, "t.v",
                                        prog & 4 ? "line style: cylinder\ntwist of cylinders: on\n"
                                                 : "line style: cylinder\n"));
        cbm_scene *scene = NULL;
        CHECK_OK(cbm_scene_create(ctx, &scene));
        enum { LEN = 300 };
        cbm_tmodule m[LEN];
        double par[LEN][4];
        for (int i = 0; i < LEN; i++) {
            m[i].name = names[next_rand() % NN];
            m[i].nparams = (int)(next_rand() % 3);
            m[i].params = par[i];
            for (int k = 0; k < 4; k++)
                par[i][k] = values[next_rand() % NV];
            /* bands of a sane number; the limits cover the rest */
            for (int k = 0; k < 4 && m[i].name[0] != 'F' && m[i].name[0] != 'f'; k++)
                par[i][k] = fmod(fabs(par[i][k]), 64.0);
        }
        cbm_turtle *t = NULL;
        cbm_turtle_def def = {prog & 1};
        cbm_status s = cbm_turtle_interpret(ctx, v, &def, m, LEN, scene, &t);
        CHECK_MSG(acceptable(s), "program %d: %s", prog, cbm_status_name(s));
        if (s == CBM_OK)
            CHECK(cbm_turtle_prim_count(t) > 0 || !(prog & 1));
        for (size_t i = 0; s == CBM_OK && i < cbm_turtle_prim_count(t); i++)
            ngcyl += cbm_turtle_prims(t)[i].kind == CBM_PRIM_GCYL;
        cbm_turtle_destroy(t);
        cbm_scene_destroy(scene);
        cbm_view_destroy(v);
        cbm_context_clear_errors(ctx);
        test_ctx_end(ctx);
    }
    CHECK(ngcyl > 100);
}

static void replay_side(const char *path, const uint8_t *data, size_t size, void *ud)
{
    (void)ud;
    if (size == 0)
        return;
    cbm_context *ctx = limited_ctx();
    cbm_view *v = NULL;
    CHECK_OK(cbm_view_create(ctx, &v));
    cbm__side_kind kind = (cbm__side_kind)(data[0] % 5);
    cbm_status s = cbm__view_add_text(v, kind, "l.s", (const char *)data + 1);
    CHECK_MSG(acceptable(s), "%s: %s", path, cbm_status_name(s));
    run_program(ctx, v);
    cbm_view_destroy(v);
    cbm_context_clear_errors(ctx);
    test_ctx_end(ctx);
}

/* The corpus of the libFuzzer target fuzz_turtle_side: first byte selects the reader. */
TEST(fuzz_corpus_replay)
{
    int n = test_replay_dir(CBM_TEST_SOURCE_DIR "/tests/fuzz/corpus/fuzz_turtle_side", false,
                            replay_side, NULL);
    printf("replayed %d corpus files\n", n);
    CHECK(n >= 7);
}

/* Out-of-memory loop over reading every kind of side file and interpreting with them. */
static cbm_status oom_side_files(cbm_context *ctx, void *ud)
{
    (void)ud;
    static const char view[] = "angle factor: 12\nline style: cylinder\ncontour sides: 5\n"
                               "tropism: T: 0 -1 0 A: 30 E: 0.2\ntwist of cylinders: on\n";
    static const char func[] = "fver 1 1\nname: f\nsamples: 5\nflip: off\npoints: 4\n"
                               "0 0 1\n0.3 0.5 2\n0.6 0.6 1\n1 1 1\n";
    static const char fset[] = "funcgalleryver 1 1\nitems: 1\nfver 1 1\nname: g\nsamples: 4\n"
                               "flip: off\npoints: 4\n0 1\n0.3 1\n0.6 1\n1 1\n";
    static const char surf[] = "0 1 0 1 0 0\nCONTACT POINT  X: 0 Y: 0 Z: 0\n"
                               "END POINT  X: 0 Y: 1 Z: 0\nHEADING  X: 0 Y: 1 Z: 0\n"
                               "UP  X: 0 Y: 0 Z: -1\nSIZE: 1\np\nc\na\nb\nd\n"
                               "0 0 0 1 0 0 2 0 0 3 0 0\n0 1 0 1 1 0 2 1 0 3 1 0\n"
                               "0 2 0 1 2 0 2 2 0 3 2 0\n0 3 0 1 3 0 2 3 0 3 3 0\n";
    static const char con[] = "cver 1 3\nname: c\npoints: 4 4\ntype: cr\nsamples: 4\n"
                              "1 0 0 1\n0 1 0 1\n-1 0 0 1\n0 -1 0 1\n";
    cbm_view *v;
    CBM_TRY(cbm_view_create(ctx, &v));
    cbm_status s = cbm__view_add_text(v, CBM__SIDE_VIEW, "t.v", view);
    if (s == CBM_OK)
        s = cbm__view_add_text(v, CBM__SIDE_FUNC, "f.func", func);
    if (s == CBM_OK)
        s = cbm__view_add_text(v, CBM__SIDE_FSET, "g.fset", fset);
    if (s == CBM_OK)
        s = cbm__view_add_text(v, CBM__SIDE_SURFACE, "l.s", surf);
    if (s == CBM_OK)
        s = cbm__view_add_text(v, CBM__SIDE_CONTOUR, "c.con", con);
    if (s == CBM_OK) {
        cbm_scene *scene;
        s = cbm_scene_create(ctx, &scene);
        if (s == CBM_OK) {
            static const char *const prog[] = {"@#", "@Gs", "F", "~", "l", "+", "F", "@Gc",
                                               "{",  ".",   "f", "+", "f", ".", "}", "@Ge",
                                               "{",  ".",   "f", "+", "f", "+", "f", "}"};
            enum { NP = sizeof prog / sizeof prog[0] };
            cbm_tmodule m[NP];
            double par[NP] = {1, 0, 1, 0, 1, 30, 1, 3,  0, 0,  1, 60,
                              1, 0, 0, 2, 4, 0,  1, 90, 1, 90, 1, 4};
            for (int i = 0; i < NP; i++) {
                m[i].name = prog[i];
                m[i].params = &par[i];
                m[i].nparams = (i == 0 || i == 7 || i == 15 || i == 16 || i == 23) ? 1 : 0;
            }
            cbm_turtle *t = NULL;
            cbm_turtle_def def = {true};
            s = cbm_turtle_interpret(ctx, v, &def, m, NP, scene, &t);
            cbm_turtle_destroy(t);
            cbm_scene_destroy(scene);
        }
    }
    cbm_view_destroy(v);
    return s;
}

TEST(out_of_memory_side_files)
{
    CHECK(test_oom_loop(oom_side_files, NULL) > 20);
}
