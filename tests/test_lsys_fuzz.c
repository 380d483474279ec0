/* Replays the fuzz corpus (tests/fuzz/corpus/lsys) and the test models (tests/lsys) through
 * both libFuzzer targets, as ordinary tests: no crash, no leak (the targets abort on a leak),
 * no hang. Every input is also cut at several points to exercise error recovery. */
#define CBM_FUZZ_NO_MAIN
#include "../tests/fuzz/fuzz_lsys_derive.c"
#include "../tests/fuzz/fuzz_lsys_parse.c"

#include "test.h"

static void parse_and_derive(const char *path, const uint8_t *data, size_t size, void *ud)
{
    (void)path;
    (void)ud;
    cbm_fuzz_lsys_parse(data, size);
    cbm_fuzz_lsys_derive(data, size);
}

TEST(fuzz_corpus_replay)
{
    char dir[2048];
    snprintf(dir, sizeof dir, "%s/tests/fuzz/corpus/lsys", test_source_dir());
    int corpus = test_replay_dir(dir, true, parse_and_derive, NULL);
    snprintf(dir, sizeof dir, "%s/tests/lsys", test_source_dir());
    int models = test_replay_dir(dir, true, parse_and_derive, NULL);
    printf("replayed %d corpus files and %d test models\n", corpus, models);
    CHECK(corpus >= 38);
    CHECK(models >= 30);
}
