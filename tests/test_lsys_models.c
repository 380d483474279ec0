/* The models of tests/lsys/: each file states what it must give, in comments:
 *   // expect string after N: MODULES       (cpfg notation, parameters as %g)
 *   // expect modules after N: COUNT
 *   // expect homomorphism after N: MODULES
 *   // options: float32
 * Every model is derived step by step and each expectation checked at its step. */
#include "lsys_util.h"

#include <dirent.h>

typedef struct expect {
    int kind; /* 0 string, 1 modules, 2 homomorphism */
    int step;
    char *text;
    long count;
} expect;

static int run_model(const char *path)
{
    char *src = read_text(path, false);
    CHECK_MSG(src != NULL, "cannot read %s", path);
    if (!src)
        return 0;
    expect ex[64];
    int nex = 0, max_step = 0;
    bool float32 = strstr(src, "// options: float32") != NULL;
    for (char *l = src; l && *l && nex < 64; l = strchr(l, '\n'), l = l ? l + 1 : NULL) {
        int kind = -1;
        const char *kinds[3] = {"// expect string after ", "// expect modules after ",
                                "// expect homomorphism after "};
        for (int k = 0; k < 3; k++)
            if (!strncmp(l, kinds[k], strlen(kinds[k])))
                kind = k;
        if (kind < 0)
            continue;
        char *p = l + strlen(kinds[kind]);
        expect e = {kind, (int)strtol(p, &p, 10), NULL, 0};
        p += 2; /* ": " */
        char *end = strchr(p, '\n');
        size_t n = end ? (size_t)(end - p) : strlen(p);
        e.text = malloc(n + 1);
        memcpy(e.text, p, n);
        e.text[n] = 0;
        e.count = strtol(p, NULL, 10);
        if (e.step > max_step)
            max_step = e.step;
        ex[nex++] = e;
    }
    CHECK_MSG(nex > 0, "%s states no expectation", path);
    cbm_context *ctx = test_ctx();
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = path;
    def.float32 = float32;
    cbm_lsys *ls = NULL;
    cbm_status s = cbm_lsys_load(ctx, &def, &ls);
    CHECK_MSG(s == CBM_OK, "%s: %s", path, cbm_context_last_error(ctx));
    if (s == CBM_OK) {
        CHECK_OK(cbm_lsys_reset(ls));
        for (int step = 0; step <= max_step; step++) {
            if (step > 0 && !cbm_lsys_stopped(ls)) /* stop() ends the derivation */
                CHECK_OK(cbm_lsys_step(ls));
            for (int i = 0; i < nex; i++) {
                if (ex[i].step != step)
                    continue;
                if (ex[i].kind == 1) {
                    CHECK_MSG((long)cbm_lsys_module_count(ls) == ex[i].count,
                              "%s: %zu modules after %d, expected %ld", path,
                              cbm_lsys_module_count(ls), step, ex[i].count);
                    continue;
                }
                bool homo = ex[i].kind == 2;
                if (homo)
                    CHECK_OK(cbm_lsys_apply_homomorphism(ls));
                tbuf got = {0};
                format_string(ls, homo, false, &got);
                CHECK_MSG(!strcmp(got.s, ex[i].text), "%s: after %d:\n  got      %s\n  expected %s",
                          path, step, got.s, ex[i].text);
                tb_free(&got);
            }
        }
        cbm_lsys_destroy(ls);
    }
    test_ctx_end(ctx);
    for (int i = 0; i < nex; i++)
        free(ex[i].text);
    free(src);
    return nex;
}

TEST(models_in_tests_lsys)
{
    char dir[2048];
    snprintf(dir, sizeof dir, "%s/tests/lsys", test_source_dir());
    DIR *d = opendir(dir);
    CHECK(d != NULL);
    if (!d)
        return;
    int models = 0, checks = 0;
    struct dirent *e;
    while ((e = readdir(d))) {
        size_t n = strlen(e->d_name);
        if (n < 3 || strcmp(e->d_name + n - 2, ".l"))
            continue;
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        checks += run_model(path);
        models++;
    }
    closedir(d);
    printf("%d models, %d expectations\n", models, checks);
    CHECK(models >= 20);
}
