/* Internal core services shared by every module: allocation through the context, diagnostics,
 * the seeded generator, check-and-propagate macros and the invariant assert. */
#ifndef CBM_CORE_H
#define CBM_CORE_H

#include "cambium/base.h"

#include <stdarg.h>
#include <string.h>

/* Invariant check: stays on in debug and release-with-debug-info builds (it is compiled out
 * only when CBM_NO_ASSERT is defined). Use it for "cannot happen", never for bad input. */
#ifndef CBM_NO_ASSERT
#define CBM_ASSERT(c) ((c) ? (void)0 : cbm__assert_fail(#c, __FILE__, __LINE__))
#else
#define CBM_ASSERT(c) ((void)0)
#endif
_Noreturn void cbm__assert_fail(const char *expr, const char *file, int line);

/// Propagate a non-OK status.
#define CBM_TRY(expr)                                                                              \
    do {                                                                                           \
        cbm_status cbm__s = (expr);                                                                \
        if (cbm__s != CBM_OK)                                                                      \
            return cbm__s;                                                                         \
    } while (0)

/* ---- allocation: every byte goes through the context ---- */

/// Returns NULL on failure (allocator failed or the byte limit would be exceeded).
void *cbm__alloc(cbm_context *ctx, size_t size);
/// Zeroed allocation of n * size bytes, with overflow check.
void *cbm__calloc(cbm_context *ctx, size_t n, size_t size);
/// On failure returns NULL and leaves ptr valid.
void *cbm__realloc(cbm_context *ctx, void *ptr, size_t old_size, size_t new_size);
void cbm__free(cbm_context *ctx, void *ptr, size_t size);
/// Copy of a NUL-terminated string (size strlen+1), NULL on failure.
char *cbm__strdup(cbm_context *ctx, const char *s);
void cbm__strfree(cbm_context *ctx, char *s);

/* ---- growable arrays ----
 * A growable array is three fields: T *data; size_t len, cap. cbm__grow makes room for `need`
 * elements in total (geometric growth). */
cbm_status cbm__grow(cbm_context *ctx, void **data, size_t *cap, size_t elem_size, size_t need);

#define CBM_ARRAY(T)                                                                               \
    struct {                                                                                       \
        T *data;                                                                                   \
        size_t len, cap;                                                                           \
    }
#define CBM_ARRAY_RESERVE(ctx, arr, n)                                                             \
    ((n) <= (arr).cap                                                                              \
         ? CBM_OK                                                                                  \
         : cbm__grow((ctx), (void **)&(arr).data, &(arr).cap, sizeof(*(arr).data), (n)))
/* Evaluates to a cbm_status. */
#define CBM_ARRAY_PUSH(ctx, arr, value)                                                            \
    (CBM_ARRAY_RESERVE(ctx, arr, (arr).len + 1) == CBM_OK                                          \
         ? ((arr).data[(arr).len++] = (value), CBM_OK)                                             \
         : CBM_E_NOMEM)
#define CBM_ARRAY_FREE(ctx, arr)                                                                   \
    (cbm__free((ctx), (arr).data, (arr).cap * sizeof(*(arr).data)), (arr).data = NULL,             \
     (arr).len = (arr).cap = 0)

/* ---- statistics over a context's life ---- */
/* Counters the library's areas keep in the context (zero at creation); each area owns a range
 * (mech: [0, CBM_SOLVE_STAGE_COUNT), solves by converged stage). */
#define CBM__CONTEXT_COUNTERS 16
size_t *cbm__context_counters(cbm_context *ctx);
const size_t *cbm__context_counters_read(const cbm_context *ctx);

/* ---- arena: scratch memory released all at once ---- */
typedef struct cbm__arena_block cbm__arena_block;
typedef struct cbm__arena {
    cbm_context *ctx;
    cbm__arena_block *head;
    size_t block_size;
} cbm__arena;

void cbm__arena_init(cbm__arena *a, cbm_context *ctx, size_t block_size);
/// 16-byte aligned; NULL on failure.
void *cbm__arena_alloc(cbm__arena *a, size_t size);
/// Releases every block but keeps the first one for reuse (no allocation on steady reuse).
void cbm__arena_reset(cbm__arena *a);
void cbm__arena_destroy(cbm__arena *a);

/* ---- diagnostics ---- */
/// Sends a diagnostic to the sink; errors are counted and the last message kept.
CBM_PRINTF(6, 7)
void cbm__diag(cbm_context *ctx, cbm_severity sev, const char *file, int line, int col,
               const char *fmt, ...);
CBM_PRINTF(6, 0)
void cbm__vdiag(cbm_context *ctx, cbm_severity sev, const char *file, int line, int col,
                const char *fmt, va_list ap);
/// Records an error message (no location) and returns the status, for `return cbm__fail(...)`.
CBM_PRINTF(3, 4)
cbm_status cbm__fail(cbm_context *ctx, cbm_status s, const char *fmt, ...);

/* ---- text printed by models ---- */
/// True when the context has an output sink (cbm_context_def.output).
bool cbm__output_wanted(const cbm_context *ctx);
/// Sends n bytes of model output to the sink (nothing without one).
void cbm__output(cbm_context *ctx, const char *text, size_t n);

/* ---- generator: xoshiro256** seeded through splitmix64 ---- */
typedef struct cbm_rng {
    uint64_t s[4];
} cbm_rng;
void cbm__rng_seed(cbm_rng *r, uint64_t seed);
uint64_t cbm__rng_next(cbm_rng *r);
/// Uniform in [0, 1), 53 bits.
double cbm__rng_uniform(cbm_rng *r);
/// Standard normal (Marsaglia polar method; no cached second value, so draws are independent of
/// call history beyond the generator state).
double cbm__rng_normal(cbm_rng *r);
cbm_rng *cbm__context_rng(cbm_context *ctx);

#endif
