/* Wind: the mean profile and the static critical wind speed of the stem and of each first-order
 * branch (issue 11). The drag of the mean wind on the equilibrium's geometry scales as U_ref^2,
 * so each segment's moment is M_weight + s M_wind with s = U_ref^2 and M_wind the moment of the
 * drag at U_ref = 1 (one backward sweep). Its peak bending stress (the statics' formula,
 * sqrt((M_L a / I_L)^2 + (M_U b / I_U)^2) in the segment's frame) reaches the modulus of rupture
 * at the smallest positive root of a quadratic in s. The geometry is held at the equilibrium
 * under weight alone: the extra bending under the wind (and the weight's extra lever arm it
 * gives) is neglected, which is conservative for a stem only in the sense of docs/dynamics.md. */
#include "mech/dyn_internal.h"
#include "core/vecmath.h"
#include "mech/mech_internal.h"

#include <math.h>
#include <string.h>

cbm_wind_def cbm_wind_def_default(void)
{
    cbm_wind_def d;
    memset(&d, 0, sizeof d);
    d.direction = v3(1, 0, 0);
    d.profile = CBM_WIND_LOG;
    d.reference_height = 10.0;
    d.roughness = 0.1;
    d.displacement = 0.0;
    d.exponent = 1.0 / 7.0;
    d.air_density = 1.226;
    d.drag_wood = 1.0;
    d.drag_organs = 0.5;
    d.organ_area_per_kg = 0.0;
    return d;
}

double cbm_wind_speed(const cbm_wind_def *def, double u_ref, double z)
{
    switch (def->profile) {
    case CBM_WIND_UNIFORM:
        return u_ref;
    case CBM_WIND_POWER:
        return z > 0.0 ? u_ref * pow(z / def->reference_height, def->exponent) : 0.0;
    case CBM_WIND_LOG:
    default: {
        double zz = z - def->displacement;
        if (!(zz > def->roughness))
            return 0.0;
        return u_ref * log(zz / def->roughness) /
               log((def->reference_height - def->displacement) / def->roughness);
    }
    }
}

cbm_status cbm__wind_check(cbm_context *ctx, const cbm_wind_def *d)
{
    cbm_vec3 dir = d->direction;
    if (!v3_isfinite(dir) || !(v3_norm(dir) > 0.0))
        return cbm__fail(ctx, CBM_E_INVALID, "wind: direction must be a non-zero vector");
    if (!(d->reference_height > 0.0) || !(d->air_density >= 0.0) || !(d->drag_wood >= 0.0) ||
        !(d->drag_organs >= 0.0) || !(d->organ_area_per_kg >= 0.0) ||
        !isfinite(d->reference_height) || !isfinite(d->air_density) || !isfinite(d->drag_wood) ||
        !isfinite(d->drag_organs) || !isfinite(d->organ_area_per_kg))
        return cbm__fail(ctx, CBM_E_INVALID,
                         "wind: reference_height must be > 0 and densities, drag coefficients "
                         "and areas >= 0");
    if (d->profile == CBM_WIND_LOG &&
        (!(d->roughness > 0.0) || !(d->reference_height - d->displacement > d->roughness)))
        return cbm__fail(ctx, CBM_E_INVALID,
                         "wind: the log profile needs roughness > 0 and reference_height - "
                         "displacement > roughness");
    if (d->profile == CBM_WIND_POWER && !(d->exponent >= 0.0 && d->exponent < 2.0))
        return cbm__fail(ctx, CBM_E_INVALID, "wind: exponent must be in [0, 2)");
    return CBM_OK;
}

cbm_status cbm_plant_critical_wind(const cbm_plant *p, const cbm_wind_def *def,
                                   cbm_wind_critical *out, size_t max, size_t *count)
{
    if (!p || !count || (max > 0 && !out))
        return CBM_E_INVALID;
    cbm_wind_def wd = def ? *def : cbm_wind_def_default();
    CBM_TRY(cbm__wind_check(p->ctx, &wd));
    size_t n = p->n;
    *count = 0;
    if (n == 0)
        return cbm__fail(p->ctx, CBM_E_INVALID, "wind: the plant has no segments");
    cbm_vec3 dir = v3_normalize(wd.direction);
    double base_y = p->base_pos.y, half_rho = 0.5 * wd.air_density;
    /* per segment: drag force F (world, at U_ref = 1), its sum over the subtree and the sum of
     * p x F, then the moment about the proximal node: sum (p x F) - x_i x sum F */
    cbm_vec3 *fs = cbm__alloc(p->ctx, 2 * n * sizeof *fs);
    size_t *group = cbm__alloc(p->ctx, n * sizeof *group);
    if (!fs || !group) {
        cbm__free(p->ctx, fs, 2 * n * sizeof *fs);
        cbm__free(p->ctx, group, n * sizeof *group);
        return CBM_E_NOMEM;
    }
    cbm_vec3 *mx = fs + n;
    for (size_t i = 0; i < n; i++) {
        cbm_quat q = p->q[i];
        cbm_vec3 h = v3(1.0 - 2.0 * (q.y * q.y + q.z * q.z), 2.0 * (q.x * q.y + q.w * q.z),
                        2.0 * (q.x * q.z - q.w * q.y));
        double l = p->len[i];
        cbm_vec3 c = v3_madd(p->pos[i], h, 0.5 * l), e = v3_madd(p->pos[i], h, l);
        double u = cbm_wind_speed(&wd, 1.0, c.y - base_y);
        cbm_vec3 uv = v3_scale(dir, u);
        cbm_vec3 vn = v3_sub(uv, v3_scale(h, v3_dot(uv, h)));
        double width = p->outer[i].a + p->outer[i].b;
        cbm_vec3 f = v3_scale(vn, half_rho * wd.drag_wood * width * l * v3_norm(vn));
        double ue = cbm_wind_speed(&wd, 1.0, e.y - base_y);
        cbm_vec3 fo =
            v3_scale(dir, half_rho * wd.drag_organs * wd.organ_area_per_kg * p->pmass[i] * ue * ue);
        fs[i] = v3_add(f, fo);
        mx[i] = v3_add(v3_cross(c, f), v3_cross(e, fo));
    }
    for (size_t i = n; i-- > 0;) {
        int64_t pa = p->parent[i];
        if (pa >= 0) {
            fs[pa] = v3_add(fs[pa], fs[i]);
            mx[pa] = v3_add(mx[pa], mx[i]);
        }
    }
    /* groups: the stem (roots' order-0 axis) and each first-order branch with all it carries */
    size_t rows = 0;
    for (size_t i = 0; i < n; i++) {
        int64_t pa = p->parent[i];
        if (p->order[i] <= 0)
            group[i] = (size_t)-1; /* the stem */
        else if (pa >= 0 && p->order[pa] <= 0)
            group[i] = i; /* a first-order branch starts */
        else
            group[i] = pa >= 0 ? group[pa] : (size_t)-1;
    }
    bool has_stem = false;
    for (size_t i = 0; i < n && !has_stem; i++)
        has_stem = group[i] == (size_t)-1;
    /* rows: the stem first, then the branches in the order of their first segment */
    size_t nrows = (has_stem ? 1 : 0);
    for (size_t i = 0; i < n; i++)
        if (group[i] == i)
            nrows++;
    (void)rows;
    cbm_wind_critical *tmp = cbm__alloc(p->ctx, nrows * sizeof *tmp);
    size_t *rowof = cbm__alloc(p->ctx, n * sizeof *rowof);
    if (!tmp || !rowof) {
        cbm__free(p->ctx, tmp, nrows * sizeof *tmp);
        cbm__free(p->ctx, rowof, n * sizeof *rowof);
        cbm__free(p->ctx, fs, 2 * n * sizeof *fs);
        cbm__free(p->ctx, group, n * sizeof *group);
        return CBM_E_NOMEM;
    }
    size_t r = 0;
    if (has_stem) {
        size_t first = 0;
        while (group[first] != (size_t)-1)
            first++;
        tmp[r++] = (cbm_wind_critical){first, 0, NAN, first, NAN};
    }
    for (size_t i = 0; i < n; i++) {
        if (group[i] == i) {
            rowof[i] = r;
            tmp[r++] = (cbm_wind_critical){i, 1, NAN, i, NAN};
        }
    }
    for (size_t i = 0; i < n; i++) {
        size_t row = group[i] == (size_t)-1 ? 0 : rowof[group[i]];
        double mor = p->outer[i].mor;
        if (!(mor > 0.0))
            continue;
        cbm_quat q = p->q[i];
        /* local L and U axes of the segment */
        cbm_vec3 lax = v3(2.0 * (q.x * q.y - q.w * q.z), 1.0 - 2.0 * (q.x * q.x + q.z * q.z),
                          2.0 * (q.y * q.z + q.w * q.x));
        cbm_vec3 uax = v3(2.0 * (q.x * q.z + q.w * q.y), 2.0 * (q.y * q.z - q.w * q.x),
                          1.0 - 2.0 * (q.x * q.x + q.y * q.y));
        cbm_vec3 mw = v3_sub(mx[i], v3_cross(p->pos[i], fs[i]));
        cbm_vec3 mg = p->moment[i];
        double a = p->outer[i].a, b = p->outer[i].b, il, iu;
        cbm_mech_ellipse_moments(a, b, &il, &iu, NULL);
        double wl = a / il, wu = b / iu;
        double g0 = wl * v3_dot(mg, lax), g1 = wl * v3_dot(mw, lax);
        double h0 = wu * v3_dot(mg, uax), h1 = wu * v3_dot(mw, uax);
        double A = g1 * g1 + h1 * h1, B = 2.0 * (g0 * g1 + h0 * h1),
               C = g0 * g0 + h0 * h0 - mor * mor;
        double s;
        if (C >= 0.0)
            s = 0.0;
        else if (!(A > 0.0))
            s = INFINITY;
        else
            s = (-B + sqrt(B * B - 4.0 * A * C)) / (2.0 * A);
        double speed = sqrt(s);
        if (isnan(tmp[row].speed) || speed < tmp[row].speed) {
            tmp[row].speed = speed;
            tmp[row].weakest = i;
            tmp[row].height = p->pos[i].y - base_y;
        }
    }
    for (size_t k = 0; k < nrows && k < max; k++)
        out[k] = tmp[k];
    *count = nrows;
    cbm__free(p->ctx, tmp, nrows * sizeof *tmp);
    cbm__free(p->ctx, rowof, n * sizeof *rowof);
    cbm__free(p->ctx, fs, 2 * n * sizeof *fs);
    cbm__free(p->ctx, group, n * sizeof *group);
    return CBM_OK;
}
