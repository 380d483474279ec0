/* Replays the corpus of the libFuzzer target fuzz_tree_params (tests/fuzz/corpus/
 * fuzz_tree_params: the shipped models/NAME.tree and inputs the fuzzer found) as ordinary tests: no
 * crash, no leak, and every file that reads and checks writes a text that reads back to the
 * same text (the target aborts otherwise). Each input is also cut at several points, which
 * exercises the readers' errors. */
#define CBM_FUZZ_NO_MAIN
#include "../tests/fuzz/fuzz_tree_params.c"

#include "test.h"

#include <dirent.h>
#include <stdio.h>

static int replay_dir(const char *dir)
{
    DIR *d = opendir(dir);
    CHECK_MSG(d != NULL, "cannot open %s", dir);
    if (!d)
        return 0;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (e->d_name[0] == '.')
            continue;
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        FILE *f = fopen(path, "rb");
        if (!f)
            continue;
        static uint8_t buf[1 << 16];
        size_t len = fread(buf, 1, sizeof buf, f);
        fclose(f);
        cbm_fuzz_tree_params(buf, len);
        for (size_t cut = len / 7; cut < len; cut += len / 7 + 1)
            cbm_fuzz_tree_params(buf, cut);
        n++;
    }
    closedir(d);
    return n;
}

TEST(tree_params_corpus_replay)
{
    char dir[2048];
    snprintf(dir, sizeof dir, "%s/tests/fuzz/corpus/fuzz_tree_params", CBM_TEST_SOURCE_DIR);
    CHECK(replay_dir(dir) >= 10);
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
