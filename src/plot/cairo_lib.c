/* cairo, loaded when first needed (cairo_lib.h). */
#include "cairo_lib.h"

#include "../core/dynlib.h"

#include <stddef.h>

cbm__cairo_api cbm__cairo;

static const cbm__dynsym cairo_syms[] = {
#define CBM__CAIRO_SYM(f) {#f, offsetof(cbm__cairo_api, f)},
    CBM__CAIRO_FUNCTIONS(CBM__CAIRO_SYM)
#undef CBM__CAIRO_SYM
};

static cbm__dynlib cairo_lib =
    CBM__DYNLIB_INIT("libcairo.so.2", "libcairo2", cairo_syms, &cbm__cairo);

cbm_status cbm__cairo_load(cbm_context *ctx, const char *who)
{
    return cbm__dynlib_load(ctx, &cairo_lib, who);
}
