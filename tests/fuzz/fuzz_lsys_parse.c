/* libFuzzer target: the model-language front end (preprocessor and parser) on arbitrary text,
 * under small limits. Must never crash, leak or hang; every failure is a status with a message.
 * Build with `make fuzz`; run build-fuzz/bin/fuzz_lsys_parse tests/fuzz/corpus/lsys. */
#include "fuzz_util.h"

int cbm_fuzz_lsys_parse(const uint8_t *data, size_t size);

int cbm_fuzz_lsys_parse(const uint8_t *data, size_t size)
{
    if (size > 1 << 16)
        return 0;
    char *text = cbm_fuzz_text(data, size);
    if (!text)
        return 0;
    cbm_context_def cd = cbm_context_def_default();
    cd.limits.max_bytes = 64u << 20;
    cd.limits.max_modules = 100000;
    cd.limits.max_steps = 50;
    cd.limits.max_decomp_depth = 50;
    /* every input ends quickly: a step's calls, loops and productions, and the expansion */
    cd.limits.max_operations = 200000;
    cd.limits.max_loop_iterations = 100000;
    cd.limits.max_pp_bytes = 4u << 20;
    cbm_context *ctx = NULL;
    if (cbm_context_create(&cd, &ctx) != CBM_OK) {
        free(text);
        return 0;
    }
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = "fuzz.l";
    def.text = text;
    cbm_lsys *ls = NULL;
    if (cbm_lsys_load(ctx, &def, &ls) == CBM_OK)
        cbm_lsys_destroy(ls);
    free(text);
    return cbm_fuzz_end(ctx);
}

CBM_FUZZ_ENTRY(cbm_fuzz_lsys_parse)
