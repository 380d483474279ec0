/* cambium: status codes, the context, basic math types.
 *
 * Every fallible call of the library returns a cbm_status; results come back through
 * out-parameters, untouched or zeroed on failure. All memory is obtained through the context's
 * allocator hook, which keeps a byte count (tests check it returns to zero) and enforces the
 * memory limit. Diagnostics (model errors, warnings) go to the context's sink; the library never
 * prints, exits or aborts on input.
 */
#ifndef CAMBIUM_BASE_H
#define CAMBIUM_BASE_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>

#ifdef __cplusplus
extern "C" {
#endif

#if defined(__GNUC__)
#define CBM_API          __attribute__((visibility("default")))
#define CBM_PRINTF(f, a) __attribute__((format(printf, f, a)))
#else
#define CBM_API
#define CBM_PRINTF(f, a)
#endif

#define CBM_VERSION_MAJOR  0
#define CBM_VERSION_MINOR  1
#define CBM_VERSION_PATCH  0
#define CBM_VERSION_STRING "0.1.0"

/// The status codes, defined once with their names and messages (X-macro).
#define CBM_STATUS_LIST(X)                                                                         \
    X(CBM_OK, "ok")                                                                                \
    X(CBM_E_NOMEM, "out of memory")                                                                \
    X(CBM_E_INVALID, "invalid argument")                                                           \
    X(CBM_E_LIMIT, "a limit of the context was exceeded")                                          \
    X(CBM_E_SYNTAX, "syntax error")                                                                \
    X(CBM_E_SEMANTIC, "semantic error")                                                            \
    X(CBM_E_RUNTIME, "error while running the model")                                              \
    X(CBM_E_IO, "input/output error")                                                              \
    X(CBM_E_FORMAT, "malformed file")                                                              \
    X(CBM_E_NOT_CONVERGED, "the solver did not converge")                                          \
    X(CBM_E_NONFINITE, "a value became NaN or infinite")                                           \
    X(CBM_E_UNSUPPORTED, "not supported")                                                          \
    X(CBM_E_NOT_FOUND, "not found")                                                                \
    X(CBM_E_INTERNAL, "internal error")

typedef enum cbm_status {
#define CBM_X_ENUM(name, msg) name,
    CBM_STATUS_LIST(CBM_X_ENUM)
#undef CBM_X_ENUM
        CBM_STATUS_COUNT
} cbm_status;

/// The enumerator's name, e.g. "CBM_E_NOMEM". Never NULL.
CBM_API const char *cbm_status_name(cbm_status s);
/// A short human message for the status. Never NULL.
CBM_API const char *cbm_status_message(cbm_status s);

/* ---- math types (SI units; angles in radians inside the library) ---- */

typedef struct cbm_vec3 {
    double x, y, z;
} cbm_vec3;

/// Unit quaternion w + xi + yj + zk; rotates v as q v q*.
typedef struct cbm_quat {
    double w, x, y, z;
} cbm_quat;

/// Orthonormal turtle frame: heading H, left L, up U, right-handed (H x L = U).
typedef struct cbm_frame {
    cbm_vec3 h, l, u;
} cbm_frame;

/* ---- context ---- */

/// Allocator hook in the style of Lua: new_size == 0 frees (returns NULL), ptr == NULL allocates.
typedef void *(*cbm_alloc_fn)(void *ud, void *ptr, size_t old_size, size_t new_size);

typedef enum cbm_severity { CBM_NOTE, CBM_WARNING, CBM_ERROR } cbm_severity;

/// One diagnostic. file may be NULL (then line/col are 0); line and col are 1-based.
typedef struct cbm_diagnostic {
    cbm_severity severity;
    const char *file;
    int line, col;
    const char *message;
} cbm_diagnostic;

typedef void (*cbm_diag_fn)(void *ud, const cbm_diagnostic *d);

/// Receives text a model prints (`printf` in cpfg and L+C models): `n` bytes, not NUL-terminated.
typedef void (*cbm_output_fn)(void *ud, const char *text, size_t n);

/// Limits that keep any input from running away. 0 means "no limit" only where noted.
typedef struct cbm_limits {
    size_t max_bytes;         ///< live bytes through the allocator (0 = unlimited)
    size_t max_modules;       ///< modules in an L-system string
    size_t max_steps;         ///< derivation steps in one run
    size_t max_segments;      ///< mechanical segments in one plant
    size_t max_passes;        ///< solver passes in one equilibrium solve
    int max_expr_depth;       ///< nesting depth of expressions and statements
    int max_decomp_depth;     ///< decomposition / homomorphism recursion depth
    size_t max_diagnostics;   ///< errors reported before giving up
    int max_call_depth;       ///< nested function calls of an L+C model
    long max_loop_iterations; ///< loop iterations in one step (while, do, for; both dialects)
    long max_operations;      ///< function calls and loop iterations in one step (both dialects)
    size_t max_pp_bytes;      ///< size of a model's preprocessed text (#define, #include expansion)
    bool allow_nonfinite;     ///< a module parameter that is inf or NaN is a warning, not an error
} cbm_limits;

typedef struct cbm_context_def {
    cbm_alloc_fn alloc; ///< NULL: the C library's realloc/free
    void *alloc_ud;
    cbm_diag_fn diag; ///< NULL: diagnostics are only counted and the last error kept
    void *diag_ud;
    cbm_output_fn output; ///< NULL: text printed by models is discarded
    void *output_ud;
    cbm_limits limits;
    uint64_t seed; ///< seed of the context's generator
} cbm_context_def;

typedef struct cbm_context cbm_context;

/// Defaults: system allocator, no sink, generous limits, seed 1.
CBM_API cbm_context_def cbm_context_def_default(void);
CBM_API cbm_status cbm_context_create(const cbm_context_def *def, cbm_context **out);
/// Destroys the context. Everything allocated from it must have been released first.
CBM_API void cbm_context_destroy(cbm_context *ctx);
/// Bytes currently allocated through the context (returns to 0 when all objects are destroyed).
CBM_API size_t cbm_context_bytes(const cbm_context *ctx);
/// Highest value the byte count has reached.
CBM_API size_t cbm_context_peak_bytes(const cbm_context *ctx);
CBM_API const cbm_limits *cbm_context_limits(const cbm_context *ctx);
CBM_API void cbm_context_set_limits(cbm_context *ctx, const cbm_limits *limits);
/// The message of the last error diagnostic or failure, "" if none. Owned by the context.
CBM_API const char *cbm_context_last_error(const cbm_context *ctx);
CBM_API size_t cbm_context_error_count(const cbm_context *ctx);
CBM_API void cbm_context_clear_errors(cbm_context *ctx);
/// Reseeds the context's generator.
CBM_API void cbm_context_seed(cbm_context *ctx, uint64_t seed);
/// Next uniform double in [0, 1) from the context's generator.
CBM_API double cbm_context_uniform(cbm_context *ctx);

#ifdef __cplusplus
}
#endif
#endif
