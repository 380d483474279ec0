/* The test runner's main: registry, selection by name, failure counting, helpers. */
#define _POSIX_C_SOURCE 200809L
#include "test.h"

#include <dirent.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define MAX_TESTS 1024

static struct {
    const char *name;
    cbm_test_fn fn;
} tests[MAX_TESTS];
static int ntests;
static int current_failures;
static const char *current_name = "";
static char skip_reason[512]; /* non-empty: the current case is skipped */

void cbm_test_register(const char *name, cbm_test_fn fn)
{
    if (ntests >= MAX_TESTS) {
        fprintf(stderr, "too many tests\n");
        exit(2);
    }
    tests[ntests].name = name;
    tests[ntests].fn = fn;
    ntests++;
}

void cbm_test_fail(const char *file, int line, const char *fmt, ...)
{
    va_list ap;
    fprintf(stderr, "%s:%d: %s: FAIL: ", file, line, current_name);
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
    current_failures++;
}

cbm_context *test_ctx(void)
{
    cbm_context *ctx = NULL;
    cbm_context_def def = cbm_context_def_default();
    if (cbm_context_create(&def, &ctx) != CBM_OK) {
        fprintf(stderr, "cannot create context\n");
        exit(2);
    }
    return ctx;
}

static void test_diag_sink(void *ud, const cbm_diagnostic *d)
{
    test_diags *g = ud;
    size_t n = strlen(g->text);
    snprintf(g->text + n, sizeof g->text - n, "%s:%d:%d: %s\n", d->file ? d->file : "?", d->line,
             d->col, d->message);
    g->count++;
}

cbm_context *test_diag_ctx(test_diags *g)
{
    memset(g, 0, sizeof *g);
    cbm_context_def def = cbm_context_def_default();
    def.diag = test_diag_sink;
    def.diag_ud = g;
    cbm_context *ctx = NULL;
    if (cbm_context_create(&def, &ctx) != CBM_OK)
        return NULL;
    return ctx;
}

static void *counting_alloc(void *ud, void *ptr, size_t old_size, size_t new_size)
{
    (void)old_size;
    if (new_size == 0) {
        free(ptr);
        return NULL;
    }
    ++*(size_t *)ud;
    return realloc(ptr, new_size);
}

cbm_context *test_counting_ctx(size_t *calls)
{
    *calls = 0;
    cbm_context_def def = cbm_context_def_default();
    def.alloc = counting_alloc;
    def.alloc_ud = calls;
    cbm_context *ctx = NULL;
    if (cbm_context_create(&def, &ctx) != CBM_OK)
        return NULL;
    return ctx;
}

void test_ctx_end_at(cbm_context *ctx, const char *file, int line)
{
    if (!ctx)
        return;
    size_t b = cbm_context_bytes(ctx);
    if (b != 0)
        cbm_test_fail(file, line, "%zu bytes still allocated at the end of the test", b);
    cbm_context_destroy(ctx);
}

typedef struct {
    long countdown; /* fail when it reaches 0; negative: never */
    int injected;
} oom_state;

static void *oom_alloc(void *ud, void *ptr, size_t old_size, size_t new_size)
{
    oom_state *st = ud;
    (void)old_size;
    if (new_size == 0) {
        free(ptr);
        return NULL;
    }
    if (new_size > old_size || !ptr) {
        if (st->countdown == 0) {
            st->injected = 1;
            st->countdown = -1;
            return NULL;
        }
        if (st->countdown > 0)
            st->countdown--;
    }
    return realloc(ptr, new_size);
}

int test_oom_loop_at(test_oom_fn fn, void *ud, const char *file, int line)
{
    for (long n = 0; n < 1000000; n++) {
        oom_state st = {n, 0};
        cbm_context_def def = cbm_context_def_default();
        def.alloc = oom_alloc;
        def.alloc_ud = &st;
        cbm_context *ctx = NULL;
        if (cbm_context_create(&def, &ctx) != CBM_OK)
            continue; /* the context itself was the failed allocation */
        cbm_status s = fn(ctx, ud);
        if (s != CBM_OK && s != CBM_E_NOMEM)
            cbm_test_fail(file, line, "OOM loop run %ld: status %s", n, cbm_status_name(s));
        if (cbm_context_bytes(ctx) != 0)
            cbm_test_fail(file, line, "OOM loop run %ld: %zu bytes leaked", n,
                          cbm_context_bytes(ctx));
        cbm_context_destroy(ctx);
        if (!st.injected) {
            if (s != CBM_OK)
                cbm_test_fail(file, line, "OOM loop: failed without injected failure");
            return (int)n + 1;
        }
        if (current_failures > 20)
            return (int)n + 1;
    }
    cbm_test_fail(file, line, "OOM loop did not finish");
    return 0;
}

/* The whole file at path, followed by a NUL; NULL if it cannot be read. */
static uint8_t *read_bytes(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    uint8_t *b = NULL;
    size_t n = 0, cap = 0;
    for (;;) {
        if (cap - n < 4096) {
            cap = cap ? 2 * cap : 65536;
            uint8_t *nb = realloc(b, cap + 1);
            if (!nb) {
                free(b);
                fclose(f);
                return NULL;
            }
            b = nb;
        }
        size_t k = fread(b + n, 1, cap - n, f);
        n += k;
        if (k == 0)
            break;
    }
    bool bad = ferror(f) != 0;
    fclose(f);
    if (bad) {
        free(b);
        return NULL;
    }
    b[n] = 0;
    *size = n;
    return b;
}

int test_replay_dir_at(const char *dir, bool cuts, test_bytes_fn fn, void *ud, const char *file,
                       int line)
{
    DIR *d = opendir(dir);
    if (!d) {
        cbm_test_fail(file, line, "cannot open the directory %s", dir);
        return 0;
    }
    int n = 0;
    for (struct dirent *e; (e = readdir(d)) != NULL;) {
        if (e->d_name[0] == '.')
            continue;
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        size_t len = 0;
        uint8_t *data = read_bytes(path, &len);
        if (!data) {
            cbm_test_fail(file, line, "cannot read %s", path);
            continue;
        }
        fn(path, data, len, ud);
        if (cuts)
            for (size_t cut = len / 7; cut < len; cut += len / 7 + 1) {
                uint8_t keep = data[cut];
                data[cut] = 0; /* the prefix is NUL-terminated too */
                fn(path, data, cut, ud);
                data[cut] = keep;
            }
        free(data);
        n++;
    }
    closedir(d);
    return n;
}

const char *test_source_dir(void)
{
    return CBM_TEST_SOURCE_DIR;
}

void test_skip(const char *reason)
{
    snprintf(skip_reason, sizeof skip_reason, "%s", reason);
}

bool test_skip_without_oracles(void)
{
    struct stat st;
    if (stat(TEST_ORACLE_DIR, &st) == 0 && S_ISDIR(st.st_mode))
        return false;
    const char *req = getenv("CBM_REQUIRE_ORACLES");
    if (req && strcmp(req, "0") && *req) {
        cbm_test_fail(__FILE__, __LINE__,
                      "%s is absent and CBM_REQUIRE_ORACLES is set: the oracle tests must run",
                      TEST_ORACLE_DIR);
        return true;
    }
    test_skip(TEST_ORACLE_DIR " is absent (the oracle data of ../shared)");
    return true;
}

const char *test_tmp_dir(void)
{
    static char dir[4096];
    snprintf(dir, sizeof dir, "%s/%s", CBM_TEST_BINARY_DIR "/tmp", current_name);
    mkdir(CBM_TEST_BINARY_DIR "/tmp", 0777);
    mkdir(dir, 0777);
    return dir;
}

int main(int argc, char **argv)
{
    int passed = 0, failed = 0, skipped = 0;
    for (int i = 0; i < ntests; i++) {
        if (argc > 1) {
            int want = 0;
            for (int a = 1; a < argc; a++)
                if (strcmp(argv[a], tests[i].name) == 0)
                    want = 1;
            if (!want)
                continue;
        }
        current_name = tests[i].name;
        current_failures = 0;
        skip_reason[0] = 0;
        tests[i].fn();
        if (current_failures) {
            failed++;
            printf("FAIL %s\n", tests[i].name);
        } else if (skip_reason[0]) {
            skipped++;
            printf("skip %s: %s\n", tests[i].name, skip_reason);
        } else {
            passed++;
            printf("ok   %s\n", tests[i].name);
        }
        fflush(stdout);
    }
    if (argc > 1 && passed + failed + skipped == 0) {
        fprintf(stderr, "no test matched\n");
        return 2;
    }
    if (skipped)
        printf("%d skipped\n", skipped);
    printf("%d passed, %d failed\n", passed, failed);
    /* every selected case skipped: CTest counts the test as skipped, not passed */
    return failed ? 1 : skipped && !passed ? TEST_SKIP_STATUS : 0;
}
