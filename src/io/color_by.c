/* Colour modes (cbm_color_by): the quantity each mode shows for a part, its range over a scene,
 * the title of its legend, and the display colour of each part under the writer's options. Organs
 * other than wood keep their own colour, faded, since the quantities belong to the wood (light,
 * to the leaves: there the wood is faded). */
#include "writers.h"

#include <math.h>
#include <string.h>

double cbm__part_quantity(const cbm_part *p, cbm_color_by by)
{
    switch (by) {
    case CBM_COLOR_STRESS:
        return p->stress_ratio;
    case CBM_COLOR_AGE:
        return p->age;
    case CBM_COLOR_REACTION:
        return p->reaction_wood;
    case CBM_COLOR_ORDER:
        return p->order >= 0 ? (double)p->order : NAN;
    case CBM_COLOR_STRESS_MPA:
        return p->stress * 1e-6;
    case CBM_COLOR_LIGHT:
        return p->light;
    default:
        return NAN;
    }
}

const char *cbm__color_title(cbm_color_by by)
{
    switch (by) {
    case CBM_COLOR_STRESS:
        return "stress / MOR";
    case CBM_COLOR_AGE:
        return "age (years)";
    case CBM_COLOR_REACTION:
        return "reaction wood";
    case CBM_COLOR_ORDER:
        return "branch order";
    case CBM_COLOR_STRESS_MPA:
        return "stress (MPa)";
    case CBM_COLOR_LIGHT:
        return "light (rel.)";
    default:
        return "";
    }
}

int cbm__legend_max_order(const cbm_scene *s)
{
    int maxo = 0;
    const cbm_part *p = cbm_scene_parts(s);
    for (size_t i = 0; i < cbm_scene_part_count(s); i++)
        if (p[i].organ == CBM_ORGAN_BRANCH && p[i].order > maxo)
            maxo = p[i].order;
    return maxo > 15 ? 15 : maxo;
}

void cbm__color_range(const cbm_scene *s, const cbm_write_options *o, double *lo, double *hi)
{
    double a = INFINITY, b = -INFINITY;
    if (o->color_by == CBM_COLOR_STRESS || o->color_by == CBM_COLOR_REACTION) {
        a = 0.0;
        b = 1.0;
    } else {
        const cbm_part *p = cbm_scene_parts(s);
        for (size_t i = 0; i < cbm_scene_part_count(s); i++) {
            double q = cbm__part_quantity(&p[i], o->color_by);
            if (isfinite(q)) {
                a = fmin(a, q);
                b = fmax(b, q);
            }
        }
        if (!(a <= b))
            a = 0.0, b = 1.0;
        if (o->color_by == CBM_COLOR_AGE || o->color_by == CBM_COLOR_STRESS_MPA ||
            o->color_by == CBM_COLOR_LIGHT)
            a = fmin(a, 0.0);
    }
    if (isfinite(o->range_min))
        a = o->range_min;
    if (isfinite(o->range_max))
        b = o->range_max;
    if (!(b > a))
        b = a + 1.0;
    *lo = a;
    *hi = b;
}

void cbm__part_color_range(const cbm_part *p, const cbm_write_options *o, double lo, double hi,
                           float rgba[4])
{
    memcpy(rgba, p->color, 4 * sizeof(float));
    if (o->color_by == CBM_COLOR_MATERIAL || o->color_by >= CBM_COLOR_COUNT)
        return;
    if (o->color_by == CBM_COLOR_LIGHT ? p->organ != CBM_ORGAN_LEAF
                                       : p->organ != CBM_ORGAN_BRANCH) {
        /* quantities belong to the wood (light to the leaves): other organs keep their
         * colour, a little faded */
        for (int k = 0; k < 3; k++)
            rgba[k] = 0.5f * rgba[k] + 0.5f * 0.8f;
        return;
    }
    double q = cbm__part_quantity(p, o->color_by);
    if (!isfinite(q)) {
        rgba[0] = rgba[1] = rgba[2] = 0.35f; /* unknown: neutral grey */
        return;
    }
    double t = o->color_by == CBM_COLOR_ORDER ? q : (q - lo) / (hi - lo);
    cbm__colormap(o->color_by, t, rgba);
}

void cbm_part_color(const cbm_part *part, const cbm_write_options *opts, float rgba[4])
{
    cbm_write_options def = cbm_write_options_default();
    if (!opts)
        opts = &def;
    double lo = isfinite(opts->range_min) ? opts->range_min : 0.0;
    double hi = isfinite(opts->range_max) ? opts->range_max : 1.0;
    if (opts->color_by == CBM_COLOR_AGE && !isfinite(opts->range_max))
        hi = 100.0;
    if (!(hi > lo))
        hi = lo + 1.0;
    cbm__part_color_range(part, opts, lo, hi, rgba);
}

cbm_status cbm__part_colors(cbm_context *ctx, const cbm_scene *s, const cbm_write_options *o,
                            float **out, double *lo, double *hi)
{
    size_t np = cbm_scene_part_count(s);
    float *c = cbm__alloc(ctx, 4 * (np ? np : 1) * sizeof *c);
    if (!c)
        return CBM_E_NOMEM;
    double a, b;
    cbm__color_range(s, o, &a, &b);
    const cbm_part *p = cbm_scene_parts(s);
    for (size_t i = 0; i < np; i++)
        cbm__part_color_range(&p[i], o, a, b, c + 4 * i);
    *out = c;
    if (lo)
        *lo = a;
    if (hi)
        *hi = b;
    return CBM_OK;
}
