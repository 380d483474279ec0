/* libFuzzer target: the bend spec reader on arbitrary bytes under tight limits and, when a spec
 * parses, the job it describes (built, grown and solved) and its node table. Must never crash,
 * leak or hang; any status is acceptable. Its corpus (tests/fuzz/corpus/spec) is replayed by
 * tests/test_mech_spec.c. */
#include "fuzz_util.h"

int cbm_fuzz_spec(const uint8_t *data, size_t size);

int cbm_fuzz_spec(const uint8_t *data, size_t size)
{
    cbm_context_def def = cbm_context_def_default();
    def.limits.max_segments = 400;
    def.limits.max_passes = 400;
    def.limits.max_bytes = (size_t)64 << 20;
    def.limits.max_diagnostics = 20;
    cbm_context *ctx = NULL;
    if (cbm_context_create(&def, &ctx) != CBM_OK)
        return 0;
    cbm_bend_spec spec;
    if (cbm_bend_spec_parse(ctx, (const char *)data, size, "fuzz.spec", &spec) == CBM_OK &&
        spec.steps <= 8) {
        cbm_plant *p = NULL;
        cbm_bend_result r;
        (void)cbm_bend_run(ctx, &spec, &p, &r);
        if (p) {
            size_t n = cbm_plant_segment_count(p);
            cbm_bend_node *nodes = malloc((n + 1) * sizeof *nodes);
            if (nodes && n > 0)
                (void)cbm_bend_nodes(p, nodes, n + 1);
            free(nodes);
            cbm_plant_destroy(p);
        }
    }
    return cbm_fuzz_end(ctx);
}

CBM_FUZZ_ENTRY(cbm_fuzz_spec)
