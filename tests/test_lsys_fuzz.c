/* Replays the fuzz corpus (tests/fuzz/corpus/lsys) and the test models (tests/lsys) through
 * both libFuzzer targets, as ordinary tests: no crash, no leak (the targets abort on a leak),
 * no hang. Every input is also truncated at several points to exercise error recovery. */
#define CBM_FUZZ_NO_MAIN
#include "../tests/fuzz/fuzz_lsys_derive.c"
#include "../tests/fuzz/fuzz_lsys_parse.c"

#include "lsys_util.h"

#include <dirent.h>

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
        char *t = read_text(path, false);
        if (!t)
            continue;
        size_t len = strlen(t);
        const uint8_t *b = (const uint8_t *)t;
        cbm_fuzz_lsys_parse(b, len);
        cbm_fuzz_lsys_derive(b, len);
        for (size_t cut = len / 7; cut < len; cut += len / 7 + 1) {
            cbm_fuzz_lsys_parse(b, cut);
            cbm_fuzz_lsys_derive(b, cut);
        }
        free(t);
        n++;
    }
    closedir(d);
    return n;
}

TEST(fuzz_corpus_replay)
{
    char dir[2048];
    snprintf(dir, sizeof dir, "%s/tests/fuzz/corpus/lsys", test_source_dir());
    int n = replay_dir(dir);
    snprintf(dir, sizeof dir, "%s/tests/lsys", test_source_dir());
    n += replay_dir(dir);
    CHECK(n >= 20);
}
