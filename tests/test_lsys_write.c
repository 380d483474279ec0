/* The string writer (cbm_lsys_write_str) builds its lines in a buffer and keeps the text of the
 * numbers it printed in a memo keyed by their bits: its file must be byte for byte what the
 * plain per-module fprintf("%.9g") gives, with more distinct values than memo slots (so slots
 * are overwritten), negative, tiny and huge values, repeats, and in float32 mode. */
#include "lsys_util.h"

#include "cambium/io.h"

static const char *MODEL =
    "Lsystem: 1\n"
    "derivation length: 12\n"
    "Axiom: A(1,0)\n"
    "A(x,y) --> A(x*1.109,y-0.37)B(ran(1e6)-5e5,x/3)[C(1e-30*x,1e30/x,90)]A(-x,y*1e-7)\n"
    "B(a,b) --> B(a,b)\n"
    "endlsystem\n";

static void check_writer(bool float32)
{
    cbm_context *ctx = NULL;
    CHECK_OK(cbm_context_create(NULL, &ctx));
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = "write.l";
    def.text = MODEL;
    def.float32 = float32;
    cbm_lsys *ls = lsys_from_def(ctx, &def);
    for (int i = 0; i < 12 && ls; i++)
        CHECK_OK(cbm_lsys_step(ls));
    /* 4096 A, 4095 B, 4095 C: more distinct numbers than the memo's 4096 slots */
    CHECK_MSG(ls && cbm_lsys_module_count(ls) > 12000, "%zu modules",
              ls ? cbm_lsys_module_count(ls) : 0);
    char path[1024];
    snprintf(path, sizeof path, "%s/write%d.str", test_tmp_dir(), float32);
    cbm_out *o = NULL;
    CHECK_OK(cbm_out_open(ctx, path, &o));
    CHECK_OK(cbm_lsys_write_str(ls, false, o));
    CHECK_OK(cbm_out_commit(o));
    tbuf want = {0};
    format_string(ls, false, true, &want);
    char *got = read_text(path, false);
    CHECK(got != NULL);
    if (got && want.s) {
        size_t k = 0;
        /* both strings are NUL-terminated (tb_put): the analyzer does not follow fread */
        /* NOLINTNEXTLINE(clang-analyzer-core.UndefinedBinaryOperatorResult) */
        while (got[k] && got[k] == want.s[k])
            k++;
        CHECK_MSG(!got[k] && !want.s[k], "float32=%d: differs at byte %zu: '%.20s' vs '%.20s'",
                  float32, k, got + k, want.s + k);
    }
    free(got);
    tb_free(&want);
    remove(path);
    cbm_lsys_destroy(ls);
    cbm_context_destroy(ctx);
}

TEST(write_str_matches_fprintf_double)
{
    check_writer(false);
}

TEST(write_str_matches_fprintf_float32)
{
    check_writer(true);
}
