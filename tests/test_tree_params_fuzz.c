/* Replays the corpus of the libFuzzer target fuzz_tree_params (tests/fuzz/corpus/
 * fuzz_tree_params: the shipped models/NAME.tree and inputs the fuzzer found) as ordinary tests: no
 * crash, no leak, and every file that reads and checks writes a text that reads back to the
 * same text (the target aborts otherwise). Each input is also cut at several points, which
 * exercises the readers' errors. */
#define CBM_FUZZ_NO_MAIN
#include "../tests/fuzz/fuzz_tree_params.c"

#include "test.h"

#include <stdio.h>

static void replay(const char *path, const uint8_t *data, size_t size, void *ud)
{
    (void)path;
    (void)ud;
    cbm_fuzz_tree_params(data, size);
}

TEST(tree_params_corpus_replay)
{
    char dir[2048];
    snprintf(dir, sizeof dir, "%s/tests/fuzz/corpus/fuzz_tree_params", CBM_TEST_SOURCE_DIR);
    int n = test_replay_dir(dir, true, replay, NULL);
    printf("replayed %d corpus files\n", n);
    CHECK(n >= 11);
}

/* The shipped models read, check and survive their writer (not only "no crash"). */
TEST(tree_params_models_round_trip)
{
    static const char *const names[] = {"fruit-tree", "poplar-wild", "ober-carbon", "ober-rauh"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        char path[2048];
        snprintf(path, sizeof path, "%s/models/%s.tree", CBM_TEST_SOURCE_DIR, names[i]);
        FILE *f = fopen(path, "rb");
        CHECK_MSG(f != NULL, "cannot open %s", path);
        if (!f)
            continue;
        static char buf[1 << 16];
        size_t len = fread(buf, 1, sizeof buf - 1, f);
        fclose(f);
        buf[len] = 0;
        cbm_context *ctx = test_ctx();
        char *once = cbm_ober_text_is_family(buf, len) ? ober_round(ctx, buf, len)
                                                       : tree_round(ctx, buf, len);
        CHECK_MSG(once != NULL, "%s does not read and check", names[i]);
        free(once);
        test_ctx_end(ctx);
    }
}
