/* libFuzzer target: loading, deriving (up to 8 steps) and the homomorphism of arbitrary models
 * under small limits (modules, memory, steps, decomposition depth, loop iterations), in double
 * and float32 modes, with printf formatting into a sink and the mechanical plant of models with
 * mechanics. Must never crash, leak or hang. */
#include "fuzz_util.h"

int cbm_fuzz_lsys_derive(const uint8_t *data, size_t size);

/* what models print is formatted and dropped */
static void sink(void *ud, const char *text, size_t n)
{
    (void)ud;
    (void)text;
    (void)n;
}

int cbm_fuzz_lsys_derive(const uint8_t *data, size_t size)
{
    if (size > 1 << 14)
        return 0;
    char *text = cbm_fuzz_text(data, size);
    if (!text)
        return 0;
    bool float32 = size & 1; /* both number modes, without spending input bytes */
    cbm_context_def cd = cbm_context_def_default();
    cd.output = sink;
    cd.limits.max_bytes = 64u << 20;
    cd.limits.max_modules = 200000;
    cd.limits.max_steps = 50;
    cd.limits.max_decomp_depth = 20;
    cd.limits.max_expr_depth = 64;
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
    def.float32 = float32;
    def.seed = 1;
    def.max_loop_iterations = 100000;
    cbm_lsys *ls = NULL;
    if (cbm_lsys_load(ctx, &def, &ls) == CBM_OK) {
        cbm_status s = cbm_lsys_reset(ls);
        for (int i = 0; i < 8 && s == CBM_OK; i++)
            s = cbm_lsys_step(ls);
        if (s == CBM_OK)
            (void)cbm_lsys_apply_homomorphism(ls);
        cbm_plant *pl = NULL;
        if (cbm_lsys_has_mechanics(ls) && cbm_lsys_mech_plant(ls, &pl) == CBM_OK)
            cbm_plant_destroy(pl);
        cbm_lsys_destroy(ls);
    }
    free(text);
    return cbm_fuzz_end(ctx);
}

CBM_FUZZ_ENTRY(cbm_fuzz_lsys_derive)
