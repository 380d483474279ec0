/* The leaves' carbon of Oberlaender's parametric tree. Without light every leaf counts as an
 * unshaded horizontal leaf (carbon 1), so formulas reading carbon see the statistical model's
 * neutral value. */
#include "tree/ober_internal.h"

cbm_status cbm__ober_light(cbm_ober_stand *s)
{
    if (s->def.light)
        return cbm__fail(s->ctx, CBM_E_UNSUPPORTED,
                         "light = 1: this build has no light module (cambium/light.h)");
    CBM_TRY(CBM_ARRAY_RESERVE(s->ctx, s->leaf_carbon, s->buds.len));
    s->leaf_carbon.len = s->buds.len;
    for (size_t b = 0; b < s->buds.len; b++)
        s->leaf_carbon.data[b] = 1.0;
    return CBM_OK;
}
