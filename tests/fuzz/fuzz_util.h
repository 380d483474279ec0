/* What the libFuzzer targets share: the input as text, the end of one input (the leak check and
 * the context's release) and the entry point. A replay test includes a target's .c file with
 * CBM_FUZZ_NO_MAIN defined and calls its function directly. */
#ifndef CBM_FUZZ_UTIL_H
#define CBM_FUZZ_UTIL_H

#include "cambium/cambium.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* A NUL-terminated copy of the input's bytes (to be freed); NULL when memory is short. */
static inline char *cbm_fuzz_text(const uint8_t *data, size_t size)
{
    char *text = malloc(size + 1);
    if (text) {
        memcpy(text, data, size);
        text[size] = 0;
    }
    return text;
}

/* The end of one input: every byte the context lent must have come back, or the process
 * aborts, which libFuzzer reports as a crash with the input; then the context is destroyed.
 * Returns 0, the value libFuzzer expects. */
static inline int cbm_fuzz_end(cbm_context *ctx)
{
    if (cbm_context_bytes(ctx) != 0)
        abort(); /* a leak */
    cbm_context_destroy(ctx);
    return 0;
}

/* libFuzzer's entry point, calling fn(data, size); nothing under CBM_FUZZ_NO_MAIN. */
#ifdef CBM_FUZZ_NO_MAIN
#define CBM_FUZZ_ENTRY(fn)
#else
#define CBM_FUZZ_ENTRY(fn)                                                                         \
    int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);                                  \
    int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)                                   \
    {                                                                                              \
        return fn(data, size);                                                                     \
    }
#endif

#endif
