/* The writers' options: their defaults, and the stand-in when a writer is given none. */
#include "writers.h"

#include "../core/vecmath.h"

#include <math.h>
#include <string.h>

cbm_write_options cbm_write_options_default(void)
{
    cbm_write_options o;
    memset(&o, 0, sizeof o);
    o.width = 800;
    o.height = 800;
    o.view = CBM_VIEW_ISO;
    o.view_dir = v3(-1, -0.8, -1);
    o.background[0] = o.background[1] = o.background[2] = o.background[3] = 1.0f;
    o.color_by = CBM_COLOR_MATERIAL;
    o.range_min = NAN;
    o.range_max = NAN;
    o.ground = true;
    o.legend = true;
    o.shadows = true;
    o.ao_samples = 16;
    o.supersample = 2;
    o.threads = 0;
    o.frame_time = 0.5;
    return o;
}

const cbm_write_options *cbm__opts(const cbm_write_options *o, cbm_write_options *def)
{
    if (o)
        return o;
    *def = cbm_write_options_default();
    return def;
}
