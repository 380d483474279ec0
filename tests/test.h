/* The in-repo test runner: TEST(name) registers a case; each test program runs all its cases or
 * the ones named on its command line and ends with "N passed, N failed". CTest registers every
 * case separately (see tests/CMakeLists.txt). Checks report file:line and let the case go on. */
#ifndef CBM_TEST_H
#define CBM_TEST_H

#include "cambium/cambium.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>

typedef void (*cbm_test_fn)(void);
void cbm_test_register(const char *name, cbm_test_fn fn);
void cbm_test_fail(const char *file, int line, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

#define TEST(name)                                                                                 \
    static void test_##name(void);                                                                 \
    __attribute__((constructor)) static void register_##name(void)                                 \
    {                                                                                              \
        cbm_test_register(#name, test_##name);                                                     \
    }                                                                                              \
    static void test_##name(void)

#define CHECK(c)                                                                                   \
    do {                                                                                           \
        if (!(c))                                                                                  \
            cbm_test_fail(__FILE__, __LINE__, "CHECK(%s)", #c);                                    \
    } while (0)

#define CHECK_MSG(c, ...)                                                                          \
    do {                                                                                           \
        if (!(c))                                                                                  \
            cbm_test_fail(__FILE__, __LINE__, __VA_ARGS__);                                        \
    } while (0)

/// |a - b| <= tol
#define CHECK_NEAR(a, b, tol)                                                                      \
    do {                                                                                           \
        double cbm_a_ = (a), cbm_b_ = (b), cbm_t_ = (tol);                                         \
        if (!(fabs(cbm_a_ - cbm_b_) <= cbm_t_))                                                    \
            cbm_test_fail(__FILE__, __LINE__, "%s = %.12g, %s = %.12g, |diff| = %.3g > %.3g", #a,  \
                          cbm_a_, #b, cbm_b_, fabs(cbm_a_ - cbm_b_), cbm_t_);                      \
    } while (0)

/// |a - b| <= rel * |b|
#define CHECK_REL(a, b, rel)                                                                       \
    do {                                                                                           \
        double cbm_a_ = (a), cbm_b_ = (b), cbm_r_ = (rel);                                         \
        if (!(fabs(cbm_a_ - cbm_b_) <= cbm_r_ * fabs(cbm_b_)))                                     \
            cbm_test_fail(__FILE__, __LINE__, "%s = %.12g, %s = %.12g, rel diff %.3g > %.3g", #a,  \
                          cbm_a_, #b, cbm_b_, fabs(cbm_a_ - cbm_b_) / fabs(cbm_b_), cbm_r_);       \
    } while (0)

#define CHECK_EQ_INT(a, b)                                                                         \
    do {                                                                                           \
        long long cbm_a_ = (long long)(a), cbm_b_ = (long long)(b);                                \
        if (cbm_a_ != cbm_b_)                                                                      \
            cbm_test_fail(__FILE__, __LINE__, "%s = %lld, expected %s = %lld", #a, cbm_a_, #b,     \
                          cbm_b_);                                                                 \
    } while (0)

#define CHECK_STATUS(expr, want)                                                                   \
    do {                                                                                           \
        cbm_status cbm_s_ = (expr);                                                                \
        if (cbm_s_ != (want))                                                                      \
            cbm_test_fail(__FILE__, __LINE__, "%s returned %s, expected %s", #expr,                \
                          cbm_status_name(cbm_s_), cbm_status_name(want));                         \
    } while (0)

#define CHECK_OK(expr) CHECK_STATUS(expr, CBM_OK)

/// A context for one test; test_ctx_end checks that every byte was returned, then destroys it.
cbm_context *test_ctx(void);
/// Diagnostics collected as "file:line:col: message" lines ("?:0:0:" without a file).
typedef struct test_diags {
    char text[8192];
    int count;
} test_diags;
/// A context whose diagnostics go to *g (cleared first); NULL if it cannot be made. Release with
/// test_ctx_end.
cbm_context *test_diag_ctx(test_diags *g);
/// A context whose allocator counts in *calls every allocation and reallocation (not frees);
/// NULL if it cannot be made. Release with test_ctx_end.
cbm_context *test_counting_ctx(size_t *calls);
void test_ctx_end_at(cbm_context *ctx, const char *file, int line);
#define test_ctx_end(ctx) test_ctx_end_at((ctx), __FILE__, __LINE__)

/// Out-of-memory loop (SQLite style): runs fn with a context whose allocator fails the n-th
/// allocation, for n = 1, 2, ... until fn returns CBM_OK without any failure injected. Every run
/// must return CBM_OK or CBM_E_NOMEM and release every byte. Returns the number of runs.
typedef cbm_status (*test_oom_fn)(cbm_context *ctx, void *ud);
int test_oom_loop_at(test_oom_fn fn, void *ud, const char *file, int line);
#define test_oom_loop(fn, ud) test_oom_loop_at((fn), (ud), __FILE__, __LINE__)

/// Every file of a directory, for replaying a fuzz corpus: calls fn(path, data, size, ud) with
/// the bytes of each file (names starting with '.' left out; data is followed by a NUL not counted
/// in size) and, when cuts is true, again with prefixes of it cut at every seventh of its
/// length, which exercises the readers' errors. A directory or a file that cannot be read is a
/// failure. Returns the number of files replayed.
typedef void (*test_bytes_fn)(const char *path, const uint8_t *data, size_t size, void *ud);
int test_replay_dir_at(const char *dir, bool cuts, test_bytes_fn fn, void *ud, const char *file,
                       int line);
#define test_replay_dir(dir, cuts, fn, ud)                                                         \
    test_replay_dir_at((dir), (cuts), (fn), (ud), __FILE__, __LINE__)

/// Directory of the repository's test data (tests/data) and of ../shared, set by CMake.
const char *test_source_dir(void);

/// Exit status of a test program whose selected cases were all skipped (CTest's
/// SKIP_RETURN_CODE, set in tests/CMakeLists.txt).
#define TEST_SKIP_STATUS 77
/// The oracle models of ../shared/oracles/vlab (with a trailing '/'), beside the repository.
#define TEST_ORACLE_DIR CBM_TEST_SOURCE_DIR "/../shared/oracles/vlab/"
/// Whether the current case must be skipped for want of the oracle data: true when
/// TEST_ORACLE_DIR is absent (the case is then reported as skipped and should return at once:
/// `if (test_skip_without_oracles()) return;`), false when it is there. When the environment
/// has CBM_REQUIRE_ORACLES=1 (CI, where ../shared exists) an absent directory is a failure.
bool test_skip_without_oracles(void);
/// Marks the current case skipped, with the reason printed by the runner.
void test_skip(const char *reason);
/// A fresh scratch directory for the current test (under the build tree).
const char *test_tmp_dir(void);

#endif
