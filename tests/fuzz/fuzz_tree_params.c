/* libFuzzer target: the parameter files of the built-in tree models (cambium/tree.h, and
 * Oberlaender's parametric tree, cambium/ober.h, whose formulas go through the model language's
 * parser) on arbitrary text. Must never crash, leak or hang; every failure is a status with a
 * message. A file that reads and checks must also survive its own writer: the text
 * cbm_*_def_format writes reads back, checks, and writes the same text again.
 * Build with `make fuzz`; run build-fuzz/bin/fuzz_tree_params tests/fuzz/corpus/fuzz_tree_params.
 */
#include "fuzz_util.h"

int cbm_fuzz_tree_params(const uint8_t *data, size_t size);

/* The written text of a definition read from text: NULL when it does not read or check. */
static char *ober_round(cbm_context *ctx, const char *text, size_t len)
{
    cbm_ober_def d = cbm_ober_def_default();
    if (cbm_ober_def_parse(ctx, &d, text, len, "fuzz.tree") != CBM_OK ||
        cbm_ober_def_check(ctx, &d) != CBM_OK)
        return NULL;
    size_t n = cbm_ober_def_format(&d, NULL, 0) + 1;
    char *out = malloc(n);
    if (out)
        cbm_ober_def_format(&d, out, n);
    return out;
}

static char *tree_round(cbm_context *ctx, const char *text, size_t len)
{
    cbm_tree_def d = cbm_tree_def_default();
    if (cbm_tree_def_parse(ctx, &d, text, len, "fuzz.tree") != CBM_OK ||
        cbm_tree_def_check(ctx, &d) != CBM_OK)
        return NULL;
    size_t n = cbm_tree_def_format(&d, NULL, 0) + 1;
    char *out = malloc(n);
    if (out)
        cbm_tree_def_format(&d, out, n);
    return out;
}

int cbm_fuzz_tree_params(const uint8_t *data, size_t size)
{
    if (size > 1 << 16)
        return 0;
    char *text = cbm_fuzz_text(data, size);
    if (!text)
        return 0;
    cbm_context_def cd = cbm_context_def_default();
    cd.limits.max_bytes = 64u << 20;
    cd.limits.max_operations = 200000;
    cd.limits.max_loop_iterations = 100000;
    cbm_context *ctx = NULL;
    if (cbm_context_create(&cd, &ctx) != CBM_OK) {
        free(text);
        return 0;
    }
    bool ober = cbm_ober_text_is_family(text, size);
    char *(*round)(cbm_context *, const char *, size_t) = ober ? ober_round : tree_round;
    char *once = round(ctx, text, size);
    if (once) {
        char *twice = round(ctx, once, strlen(once));
        if (!twice || strcmp(once, twice) != 0)
            abort(); /* the writer's text does not read back as the same definition */
        free(twice);
        free(once);
    }
    free(text);
    return cbm_fuzz_end(ctx);
}

CBM_FUZZ_ENTRY(cbm_fuzz_tree_params)
