/* Light inside the L+C dialect: Light(sky, samples) runs the light-interception module
 * (include/cambium/light.h, docs/light.md) over the leaves of the current string and writes
 * each leaf's intercepted light into its module (docs/language.md, "Light").
 *
 * The leaves are the modules declared `light: Leaf(area, light)`. Where a leaf is comes from
 * the mechanics (mechlang.c): the leaf sits on the distal node of the mechanical segment it
 * follows on its path from the root (the segment before it, `[` and `]` keeping the path, as a
 * point mass is placed), at the position and heading the last mechanics operation wrote into
 * that segment's MechSegment (pos + length H). So one Equilibrium() after the string changed and
 * before Light() places the leaves on the bent plant. A leaf is a horizontal square of its area
 * (the blade the sky's calibration assumes: an unshaded horizontal leaf of 1 m^2 receives 1),
 * one side along the horizontal part of the segment's heading. Leaves only are cast: the
 * stems do not shade (their area is small beside the leaves' in a leafy crown). A leaf with
 * area 0 casts nothing and receives 0. The result, in m^2 of unshaded horizontal leaf, goes
 * into the leaf's light parameter, which the next derivation's productions read. */
#define _POSIX_C_SOURCE 200809L
#include "lsys/mechlang_internal.h"

#include "core/core.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

cbm_status cbm__lightlang_run(cbm_context *ctx, const cbm__mechlang *m, lstr *s, int sky,
                              int samples, double *total, char *err, size_t errn)
{
    *total = 0;
    err[0] = 0;
    if (m->seg_code < 0) {
        snprintf(err, errn, "no `mechanics:` module declared (a leaf sits on a segment)");
        return CBM_E_INVALID;
    }
    bool any = false;
    for (int c = 0; c < 128; c++)
        any |= m->light_area_off[c] >= 0;
    if (!any) {
        snprintf(err, errn, "no leaf module declared (`light: Leaf(area, light);`)");
        return CBM_E_INVALID;
    }
    if (s->f32) {
        snprintf(err, errn, "light needs double parameters");
        return CBM_E_INVALID;
    }
    CBM_ARRAY(cbm_light_leaf) leaves = {0};
    CBM_ARRAY(double *) out = {0}; /* each leaf's light parameter */
    cbm__mwalk_stack stack = {0};
    double *absorbed = NULL;
    cbm_status st = CBM_OK;
    const double *last = NULL; /* the MechSegment of the last segment on the path */
    cbm__mwalk w = cbm__mwalk_start(m, s, (void *)&last, sizeof last, &stack);
    while (st == CBM_OK && cbm__mwalk_next(ctx, &w)) {
        int code = w.code, np = w.np;
        double *p = w.p;
        if (code == m->sb || code == m->eb) {
            continue; /* the path is the walk's */
        } else if (code == m->seg_code && np >= m->seg_off + MS_SIZE) {
            last = p + m->seg_off;
        } else if (m->light_area_off[code] >= 0 && np > m->light_area_off[code] &&
                   np > m->light_out_off[code]) {
            double area = p[m->light_area_off[code]];
            p[m->light_out_off[code]] = 0;
            if (!(area >= 0) || !isfinite(area)) {
                snprintf(err, errn, "leaf %zu: area %g m^2 (must be >= 0)", out.len + 1, area);
                st = CBM_E_INVALID;
                break;
            }
            if (!last) {
                snprintf(err, errn, "leaf %zu is before every mechanical segment", out.len + 1);
                st = CBM_E_INVALID;
                break;
            }
            if (area == 0)
                continue;
            const double *g = last;
            cbm_vec3 h = {g[MS_H], g[MS_H + 1], g[MS_H + 2]};
            cbm_vec3 c = {g[MS_POS] + g[MS_LENGTH] * h.x, g[MS_POS + 1] + g[MS_LENGTH] * h.y,
                          g[MS_POS + 2] + g[MS_LENGTH] * h.z};
            /* e1: the heading's horizontal part (x for an upright segment), e2 = up x e1: the
             * square is counter-clockwise seen from above */
            double hl = sqrt(h.x * h.x + h.z * h.z);
            cbm_vec3 e1 = hl > 1e-9 ? (cbm_vec3){h.x / hl, 0, h.z / hl} : (cbm_vec3){1, 0, 0};
            cbm_vec3 e2 = {e1.z, 0, -e1.x};
            double a = 0.5 * sqrt(area);
            cbm_light_leaf lf = {.plant = 0};
            const double s1[4] = {-1, 1, 1, -1}, s2[4] = {-1, -1, 1, 1};
            for (int q = 0; q < 4; q++)
                lf.p[q] = (cbm_vec3){c.x + a * (s1[q] * e1.x + s2[q] * e2.x), c.y,
                                     c.z + a * (s1[q] * e1.z + s2[q] * e2.z)};
            if (!(isfinite(c.x) && isfinite(c.y) && isfinite(c.z))) {
                snprintf(err, errn, "leaf %zu: its segment has no position (Equilibrium() first)",
                         out.len + 1);
                st = CBM_E_INVALID;
                break;
            }
            st = CBM_ARRAY_PUSH(ctx, leaves, lf);
            if (st == CBM_OK)
                st = CBM_ARRAY_PUSH(ctx, out, p + m->light_out_off[code]);
        }
    }
    if (st == CBM_OK)
        st = w.st;
    if (st == CBM_OK && leaves.len) {
        absorbed = cbm__calloc(ctx, leaves.len, sizeof *absorbed);
        if (!absorbed)
            st = CBM_E_NOMEM;
    }
    if (st == CBM_OK && leaves.len) {
        cbm_light_def def = cbm_light_def_default();
        def.sky = (cbm_sky_kind)sky;
        def.samples = samples;
        st = cbm_light_intercept(ctx, &def, leaves.data, leaves.len, NULL, 0, absorbed, NULL);
        if (st != CBM_OK)
            snprintf(err, errn, "%s", cbm_context_last_error(ctx));
        for (size_t i = 0; st == CBM_OK && i < leaves.len; i++) {
            *out.data[i] = absorbed[i];
            *total += absorbed[i];
        }
    } else if (st == CBM_E_NOMEM && !err[0]) {
        snprintf(err, errn, "out of memory");
    }
    if (absorbed)
        cbm__free(ctx, absorbed, leaves.len * sizeof *absorbed);
    CBM_ARRAY_FREE(ctx, leaves);
    CBM_ARRAY_FREE(ctx, out);
    CBM_ARRAY_FREE(ctx, stack);
    return st;
}
