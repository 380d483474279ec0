/* libFuzzer target for the bend spec reader and the job it describes (see fuzz_spec.h). */
#include "fuzz_spec.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return cbm_fuzz_spec_one(data, size);
}
