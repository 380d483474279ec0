/* libFuzzer target for the side-file readers and the turtle: the first byte selects the reader
 * (byte % 5: view file, function, function gallery, surface, contour), the rest is the file's
 * text; the resulting view then interprets a short string using surfaces, contours, generalized
 * cylinders, polygons and tropisms. Runs under a 64 MB byte limit; aborts if bytes leak.
 * Its corpus (tests/fuzz/corpus/fuzz_turtle_side) is replayed by tests/test_turtle_fuzz.c. */
#include "fuzz_util.h"
#include "turtle/view_internal.h"

static const char *const program[] = {"@#", "@Gs", "F", "~", "a", "~", "l", "@Gc", "+", "F",
                                      "_",  "@Ge", "{", ".", "F", ".", "F", ".",   "}", "@O"};

int cbm_fuzz_turtle_side(const uint8_t *data, size_t size);

int cbm_fuzz_turtle_side(const uint8_t *data, size_t size)
{
    if (size < 1 || size > 1 << 16)
        return 0;
    cbm_context_def def = cbm_context_def_default();
    def.limits.max_bytes = 64u << 20;
    cbm_context *ctx;
    if (cbm_context_create(&def, &ctx) != CBM_OK)
        return 0;
    char *text = cbm_fuzz_text(data + 1, size - 1);
    if (!text)
        return cbm_fuzz_end(ctx);
    cbm_view *v;
    if (cbm_view_create(ctx, &v) == CBM_OK) {
        (void)cbm__view_add_text(v, (cbm__side_kind)(data[0] % 5), "l.s", text);
        enum { N = sizeof program / sizeof program[0] };
        cbm_tmodule m[N];
        double par[N][3];
        for (int i = 0; i < N; i++) {
            par[i][0] = 1.0 + (double)(i % 3);
            par[i][1] = 0.5;
            par[i][2] = 0.0;
            m[i].name = program[i];
            m[i].params = par[i];
            m[i].nparams = i % 3;
        }
        cbm_scene *scene;
        if (cbm_scene_create(ctx, &scene) == CBM_OK) {
            cbm_turtle *t = NULL;
            cbm_turtle_def td = {true};
            (void)cbm_turtle_interpret(ctx, v, &td, m, N, scene, &t);
            cbm_turtle_destroy(t);
            cbm_scene_destroy(scene);
        }
        cbm_view_destroy(v);
    }
    free(text);
    return cbm_fuzz_end(ctx);
}

CBM_FUZZ_ENTRY(cbm_fuzz_turtle_side)
