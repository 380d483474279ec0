/* The context: allocator hook with a live byte count and a memory limit, limits, the diagnostics
 * sink with an error count and the last message, and the seeded generator. Also the status
 * names and messages, generated from the X-macro list in base.h. */
#include "core.h"

#include <stdio.h>
#include <stdlib.h>

struct cbm_context {
    cbm_alloc_fn alloc;
    void *alloc_ud;
    cbm_diag_fn diag;
    void *diag_ud;
    cbm_output_fn output;
    void *output_ud;
    cbm_limits limits;
    size_t bytes, peak;
    size_t errors;
    size_t counters[CBM__CONTEXT_COUNTERS]; /* library statistics (cbm__context_counters) */
    char last_error[1024];
    cbm_rng rng;
};

static const char *const status_names[] = {
#define CBM_X_NAME(name, msg) #name,
    CBM_STATUS_LIST(CBM_X_NAME)
#undef CBM_X_NAME
};
static const char *const status_messages[] = {
#define CBM_X_MSG(name, msg) msg,
    CBM_STATUS_LIST(CBM_X_MSG)
#undef CBM_X_MSG
};

const char *cbm_status_name(cbm_status s)
{
    if ((unsigned)s >= (unsigned)CBM_STATUS_COUNT)
        return "CBM_E_UNKNOWN";
    return status_names[s];
}

const char *cbm_status_message(cbm_status s)
{
    if ((unsigned)s >= (unsigned)CBM_STATUS_COUNT)
        return "unknown status";
    return status_messages[s];
}

_Noreturn void cbm__assert_fail(const char *expr, const char *file, int line)
{
    fprintf(stderr, "cambium: internal invariant failed: %s (%s:%d)\n", expr, file, line);
    abort();
}

static void *default_alloc(void *ud, void *ptr, size_t old_size, size_t new_size)
{
    (void)ud;
    (void)old_size;
    if (new_size == 0) {
        free(ptr);
        return NULL;
    }
    return realloc(ptr, new_size);
}

cbm_context_def cbm_context_def_default(void)
{
    cbm_context_def d;
    memset(&d, 0, sizeof d);
    d.limits.max_bytes = 0;
    d.limits.max_modules = (size_t)1 << 31;
    d.limits.max_steps = 1000000;
    d.limits.max_segments = (size_t)1 << 28;
    d.limits.max_passes = 1000000;
    d.limits.max_expr_depth = 200;
    d.limits.max_decomp_depth = 1000;
    d.limits.max_diagnostics = 50;
    d.limits.max_call_depth = 256;
    d.limits.max_loop_iterations = 100000000;
    d.limits.max_operations = 100000000;
    d.limits.max_pp_bytes = (size_t)64 << 20;
    d.limits.allow_nonfinite = false;
    d.seed = 1;
    return d;
}

cbm_status cbm_context_create(const cbm_context_def *def, cbm_context **out)
{
    if (!out)
        return CBM_E_INVALID;
    *out = NULL;
    cbm_context_def d = def ? *def : cbm_context_def_default();
    if (!d.alloc)
        d.alloc = default_alloc;
    cbm_context *ctx = d.alloc(d.alloc_ud, NULL, 0, sizeof *ctx);
    if (!ctx)
        return CBM_E_NOMEM;
    memset(ctx, 0, sizeof *ctx);
    ctx->alloc = d.alloc;
    ctx->alloc_ud = d.alloc_ud;
    ctx->diag = d.diag;
    ctx->diag_ud = d.diag_ud;
    ctx->output = d.output;
    ctx->output_ud = d.output_ud;
    ctx->limits = d.limits;
    cbm__rng_seed(&ctx->rng, d.seed);
    *out = ctx;
    return CBM_OK;
}

void cbm_context_destroy(cbm_context *ctx)
{
    if (!ctx)
        return;
    ctx->alloc(ctx->alloc_ud, ctx, sizeof *ctx, 0);
}

size_t cbm_context_bytes(const cbm_context *ctx)
{
    return ctx->bytes;
}

size_t cbm_context_peak_bytes(const cbm_context *ctx)
{
    return ctx->peak;
}

size_t *cbm__context_counters(cbm_context *ctx)
{
    return ctx->counters;
}

const size_t *cbm__context_counters_read(const cbm_context *ctx)
{
    return ctx->counters;
}

const cbm_limits *cbm_context_limits(const cbm_context *ctx)
{
    return &ctx->limits;
}

void cbm_context_set_limits(cbm_context *ctx, const cbm_limits *limits)
{
    ctx->limits = *limits;
}

const char *cbm_context_last_error(const cbm_context *ctx)
{
    return ctx->last_error;
}

size_t cbm_context_error_count(const cbm_context *ctx)
{
    return ctx->errors;
}

void cbm_context_clear_errors(cbm_context *ctx)
{
    ctx->errors = 0;
    ctx->last_error[0] = '\0';
}

void cbm_context_seed(cbm_context *ctx, uint64_t seed)
{
    cbm__rng_seed(&ctx->rng, seed);
}

double cbm_context_uniform(cbm_context *ctx)
{
    return cbm__rng_uniform(&ctx->rng);
}

cbm_rng *cbm__context_rng(cbm_context *ctx)
{
    return &ctx->rng;
}

/* ---- allocation ---- */

void *cbm__realloc(cbm_context *ctx, void *ptr, size_t old_size, size_t new_size)
{
    if (new_size == 0) {
        cbm__free(ctx, ptr, old_size);
        return NULL;
    }
    if (new_size > old_size && ctx->limits.max_bytes &&
        ctx->bytes - old_size + new_size > ctx->limits.max_bytes) {
        /* the caller sees CBM_E_NOMEM; the message says how much was asked (not counted as a
         * diagnostic: the caller reports the failure) */
        snprintf(ctx->last_error, sizeof ctx->last_error,
                 "out of memory: the limit of %zu MB (--max-memory) would be exceeded: %zu "
                 "bytes asked "
                 "while %zu are held",
                 ctx->limits.max_bytes >> 20, new_size, ctx->bytes);
        return NULL;
    }
    void *p = ctx->alloc(ctx->alloc_ud, ptr, ptr ? old_size : 0, new_size);
    if (!p) {
        snprintf(ctx->last_error, sizeof ctx->last_error,
                 "out of memory: %zu bytes asked while %zu are held", new_size, ctx->bytes);
        return NULL;
    }
    ctx->bytes = ctx->bytes - (ptr ? old_size : 0) + new_size;
    if (ctx->bytes > ctx->peak)
        ctx->peak = ctx->bytes;
    return p;
}

void *cbm__alloc(cbm_context *ctx, size_t size)
{
    if (size == 0)
        size = 1;
    return cbm__realloc(ctx, NULL, 0, size);
}

void *cbm__calloc(cbm_context *ctx, size_t n, size_t size)
{
    if (size && n > SIZE_MAX / size)
        return NULL;
    void *p = cbm__alloc(ctx, n * size);
    if (p)
        memset(p, 0, (n * size) != 0 ? n * size : 1);
    return p;
}

void cbm__free(cbm_context *ctx, void *ptr, size_t size)
{
    if (!ptr)
        return;
    if (size == 0)
        size = 1; /* matches cbm__alloc's minimum */
    CBM_ASSERT(ctx->bytes >= size);
    ctx->alloc(ctx->alloc_ud, ptr, size, 0);
    ctx->bytes -= size;
}

char *cbm__strdup(cbm_context *ctx, const char *s)
{
    size_t n = strlen(s) + 1;
    char *p = cbm__alloc(ctx, n);
    if (p)
        memcpy(p, s, n);
    return p;
}

void cbm__strfree(cbm_context *ctx, char *s)
{
    if (s)
        cbm__free(ctx, s, strlen(s) + 1);
}

cbm_status cbm__grow(cbm_context *ctx, void **data, size_t *cap, size_t elem_size, size_t need)
{
    if (need <= *cap)
        return CBM_OK;
    size_t ncap = *cap ? *cap : 8;
    while (ncap < need) {
        if (ncap > SIZE_MAX / 2 / elem_size)
            return CBM_E_NOMEM;
        ncap *= 2;
    }
    if (ncap > SIZE_MAX / elem_size)
        return CBM_E_NOMEM;
    void *p = cbm__realloc(ctx, *data, *cap * elem_size, ncap * elem_size);
    if (!p)
        return CBM_E_NOMEM;
    *data = p;
    *cap = ncap;
    return CBM_OK;
}

/* ---- text printed by models ---- */

bool cbm__output_wanted(const cbm_context *ctx)
{
    return ctx->output != NULL;
}

void cbm__output(cbm_context *ctx, const char *text, size_t n)
{
    if (ctx->output && n)
        ctx->output(ctx->output_ud, text, n);
}

/* ---- diagnostics ---- */

void cbm__vdiag(cbm_context *ctx, cbm_severity sev, const char *file, int line, int col,
                const char *fmt, va_list ap)
{
    char msg[512];
    vsnprintf(msg, sizeof msg, fmt, ap);
    if (sev == CBM_ERROR) {
        ctx->errors++;
        if (file && line > 0)
            snprintf(ctx->last_error, sizeof ctx->last_error, "%.300s:%d:%d: error: %.600s", file,
                     line, col, msg);
        else if (file)
            snprintf(ctx->last_error, sizeof ctx->last_error, "%.300s: error: %.600s", file, msg);
        else
            snprintf(ctx->last_error, sizeof ctx->last_error, "%s", msg);
    }
    if (ctx->diag) {
        cbm_diagnostic d = {sev, file, line, col, msg};
        ctx->diag(ctx->diag_ud, &d);
    }
}

void cbm__diag(cbm_context *ctx, cbm_severity sev, const char *file, int line, int col,
               const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    cbm__vdiag(ctx, sev, file, line, col, fmt, ap);
    va_end(ap);
}

cbm_status cbm__fail(cbm_context *ctx, cbm_status s, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    cbm__vdiag(ctx, CBM_ERROR, NULL, 0, 0, fmt, ap);
    va_end(ap);
    return s;
}
