/* Wind: the mean profile and the static critical wind speed of the stem and of each first-order
 * branch (issue 11). The drag of the mean wind on the equilibrium's geometry scales as U_ref^2,
 * so each segment's moment is M_weight + s M_wind with s = U_ref^2 and M_wind the moment of the
 * drag at U_ref = 1 (one backward sweep). Its peak bending stress (the statics' formula,
 * sqrt((M_L a / I_L)^2 + (M_U b / I_U)^2) in the segment's frame) reaches the modulus of rupture
 * at the smallest positive root of a quadratic in s. The geometry is held at the equilibrium
 * under weight alone: the extra bending under the wind (and the weight's extra lever arm it
 * gives) is neglected, which is conservative for a stem only in the sense of docs/dynamics.md.
 *
 * Leaves that reconfigure (cbm_wind_def.leaf_area with a Vogel exponent) make the drag grow
 * slower than U_ref^2. Then the speed of each row is found by freezing the leaves' factor at the
 * last speed and solving the quadratic again, from the factor 1 (no reconfiguration, the largest
 * drag): the speeds rise monotonically to the fixed point (a frozen factor at a speed below the
 * answer overstates the drag at every speed above it). A stem segment carries branches whose
 * leaves then see the stem's speed, a branch segment only its own branch's. */
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
    d.leaf_area = NULL;
    d.fruit_mass = NULL;
    d.drag_leaf = 1.17;
    d.leaf_vogel = -2.0 / 3.0;
    d.leaf_vogel_speed = 5.0;
    d.drag_fruit = 0.47;
    d.fruit_density = 800.0;
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
    if (d->leaf_area &&
        (!(d->drag_leaf >= 0.0) || !isfinite(d->drag_leaf) || !(d->leaf_vogel > -2.0) ||
         !(d->leaf_vogel <= 0.0) || !(d->leaf_vogel_speed > 0.0) || !isfinite(d->leaf_vogel_speed)))
        return cbm__fail(ctx, CBM_E_INVALID,
                         "wind: leaves need drag_leaf >= 0, -2 < leaf_vogel <= 0 and "
                         "leaf_vogel_speed > 0");
    if (d->fruit_mass && (!(d->drag_fruit >= 0.0) || !isfinite(d->drag_fruit) ||
                          !(d->fruit_density > 0.0) || !isfinite(d->fruit_density)))
        return cbm__fail(ctx, CBM_E_INVALID,
                         "wind: fruit need drag_fruit >= 0 and fruit_density > 0");
    return CBM_OK;
}

cbm_status cbm__wind_organs(cbm_context *ctx, const cbm_wind_def *d, size_t n, double **leaf,
                            double **fruit)
{
    *leaf = *fruit = NULL;
    double half_rho = 0.5 * d->air_density;
    for (int k = 0; k < 2; k++) {
        const double *src = k == 0 ? d->leaf_area : d->fruit_mass;
        if (!src)
            continue;
        double *dst = cbm__alloc(ctx, n * sizeof *dst);
        if (!dst) {
            cbm__free(ctx, *leaf, n * sizeof(double));
            *leaf = NULL;
            return CBM_E_NOMEM;
        }
        for (size_t i = 0; i < n; i++) {
            double x = src[i];
            if (!(x >= 0.0) || !isfinite(x)) {
                cbm__free(ctx, dst, n * sizeof *dst);
                cbm__free(ctx, *leaf, n * sizeof(double));
                *leaf = NULL;
                return cbm__fail(ctx, CBM_E_INVALID, "wind: %s of segment %zu is %g (must be >= 0)",
                                 k == 0 ? "leaf_area" : "fruit_mass", i, x);
            }
            if (k == 0)
                dst[i] = half_rho * d->drag_leaf * x;
            else { /* one sphere of the fruit's volume: its frontal area pi r^2 */
                double r = cbrt(0.75 * x / (CBM_PI * d->fruit_density));
                dst[i] = half_rho * d->drag_fruit * CBM_PI * r * r;
            }
        }
        *(k == 0 ? leaf : fruit) = dst;
    }
    return CBM_OK;
}

/* The drag forces fs (world, at U_ref = 1) and their moments about the origin mx of every segment
 * summed over its subtree; the leaves' drag factor frozen at the reference speed uo[row[i]]
 * (uo NULL or no leaves: factor 1; urow >= 0: all at that speed). */
static void wind_loads(const cbm_plant *p, const cbm_wind_def *wd, const double *leaf,
                       const double *fruit, const double *uo, const size_t *rowseg, double urow,
                       cbm_vec3 *fs, cbm_vec3 *mx)
{
    size_t n = p->n;
    cbm_vec3 dir = v3_normalize(wd->direction);
    double base_y = p->base_pos.y, half_rho = 0.5 * wd->air_density;
    for (size_t i = 0; i < n; i++) {
        cbm_quat q = p->q[i];
        cbm_vec3 h = v3(1.0 - 2.0 * (q.y * q.y + q.z * q.z), 2.0 * (q.x * q.y + q.w * q.z),
                        2.0 * (q.x * q.z - q.w * q.y));
        double l = p->len[i];
        cbm_vec3 c = v3_madd(p->pos[i], h, 0.5 * l), e = v3_madd(p->pos[i], h, l);
        double u = cbm_wind_speed(wd, 1.0, c.y - base_y);
        cbm_vec3 uv = v3_scale(dir, u);
        cbm_vec3 vn = v3_sub(uv, v3_scale(h, v3_dot(uv, h)));
        double width = p->outer[i].a + p->outer[i].b;
        cbm_vec3 f = v3_scale(vn, half_rho * wd->drag_wood * width * l * v3_norm(vn));
        double ue = cbm_wind_speed(wd, 1.0, e.y - base_y);
        double ko = half_rho * wd->drag_organs * wd->organ_area_per_kg * p->pmass[i];
        if (fruit)
            ko += fruit[i];
        if (leaf && leaf[i] > 0.0) {
            double us = urow >= 0.0 ? urow : uo ? uo[rowseg[i]] : 0.0;
            us = isfinite(us) || us == INFINITY ? us : 0.0;
            ko +=
                leaf[i] * cbm__leaf_reconfiguration(wd->leaf_vogel, wd->leaf_vogel_speed, us * ue);
        }
        cbm_vec3 fo = v3_scale(dir, ko * ue * ue);
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
}

/* The smallest U_ref at which segment i's peak stress reaches its modulus of rupture under the
 * wind moment mw (at U_ref = 1) and the equilibrium's moment; NAN without a modulus. */
static double segment_speed(const cbm_plant *p, size_t i, cbm_vec3 mw)
{
    double mor = p->outer[i].mor;
    if (!(mor > 0.0))
        return NAN;
    cbm_quat q = p->q[i];
    /* local L and U axes of the segment */
    cbm_vec3 lax = v3(2.0 * (q.x * q.y - q.w * q.z), 1.0 - 2.0 * (q.x * q.x + q.z * q.z),
                      2.0 * (q.y * q.z + q.w * q.x));
    cbm_vec3 uax = v3(2.0 * (q.x * q.z + q.w * q.y), 2.0 * (q.y * q.z - q.w * q.x),
                      1.0 - 2.0 * (q.x * q.x + q.y * q.y));
    cbm_vec3 mg = p->moment[i];
    double a = p->outer[i].a, b = p->outer[i].b, il, iu;
    cbm_mech_ellipse_moments(a, b, &il, &iu, NULL);
    double wl = a / il, wu = b / iu;
    double g0 = wl * v3_dot(mg, lax), g1 = wl * v3_dot(mw, lax);
    double h0 = wu * v3_dot(mg, uax), h1 = wu * v3_dot(mw, uax);
    double A = g1 * g1 + h1 * h1, B = 2.0 * (g0 * g1 + h0 * h1), C = g0 * g0 + h0 * h0 - mor * mor;
    double s;
    if (C >= 0.0)
        s = 0.0;
    else if (!(A > 0.0))
        s = INFINITY;
    else
        s = (-B + sqrt(B * B - 4.0 * A * C)) / (2.0 * A);
    return sqrt(s);
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
    double *leaf = NULL, *fruit = NULL;
    CBM_TRY(cbm__wind_organs(p->ctx, &wd, n, &leaf, &fruit));
    bool reconf = false;
    for (size_t i = 0; leaf && i < n && !reconf; i++)
        reconf = leaf[i] > 0.0 && wd.leaf_vogel != 0.0;
    /* per segment: drag force F (world, at U_ref = 1), its sum over the subtree and the sum of
     * p x F, then the moment about the proximal node: sum (p x F) - x_i x sum F; with
     * reconfiguring leaves a second set with every leaf at the stem's speed */
    size_t nv = reconf ? 4 * n : 2 * n;
    cbm_vec3 *fs = cbm__alloc(p->ctx, nv * sizeof *fs);
    size_t *group = cbm__alloc(p->ctx, 2 * n * sizeof *group);
    cbm_wind_critical *tmp = NULL;
    double *speed = NULL;
    size_t nrows = 0;
    cbm_status st = fs && group ? CBM_OK : CBM_E_NOMEM;
    if (st != CBM_OK)
        goto done;
    size_t *rowof = group + n;
    cbm_vec3 *mx = fs + n, *fs2 = reconf ? fs + 2 * n : NULL, *mx2 = reconf ? fs + 3 * n : NULL;
    /* groups: the stem (roots' order-0 axis) and each first-order branch with all it carries */
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
    nrows = (has_stem ? 1 : 0);
    for (size_t i = 0; i < n; i++)
        if (group[i] == i)
            nrows++;
    tmp = cbm__alloc(p->ctx, nrows * sizeof *tmp);
    speed = cbm__alloc(p->ctx, nrows * sizeof *speed);
    if (!tmp || !speed) {
        st = CBM_E_NOMEM;
        goto done;
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
    for (size_t i = 0; i < n; i++)
        rowof[i] = group[i] == (size_t)-1 ? 0 : rowof[group[i]];
    for (size_t k = 0; k < nrows; k++)
        speed[k] = 0.0;
    /* the first pass is the answer without reconfiguration; then the fixed point */
    for (int it = 0; it < (reconf ? 200 : 1); it++) {
        wind_loads(p, &wd, leaf, fruit, reconf ? speed : NULL, rowof, -1.0, fs, mx);
        if (reconf)
            wind_loads(p, &wd, leaf, fruit, NULL, rowof, has_stem ? speed[0] : 0.0, fs2, mx2);
        for (size_t k = 0; k < nrows; k++)
            tmp[k].speed = NAN;
        for (size_t i = 0; i < n; i++) {
            size_t row = rowof[i];
            bool stem = group[i] == (size_t)-1;
            cbm_vec3 mw = reconf && stem ? v3_sub(mx2[i], v3_cross(p->pos[i], fs2[i]))
                                         : v3_sub(mx[i], v3_cross(p->pos[i], fs[i]));
            double sp = segment_speed(p, i, mw);
            if (isnan(sp))
                continue;
            if (isnan(tmp[row].speed) || sp < tmp[row].speed) {
                tmp[row].speed = sp;
                tmp[row].weakest = i;
                tmp[row].height = p->pos[i].y - p->base_pos.y;
            }
        }
        double change = 0.0;
        for (size_t k = 0; k < nrows; k++) {
            double a = speed[k], b = tmp[k].speed;
            if (isfinite(a) && isfinite(b) && b > 0.0)
                change = fmax(change, fabs(b - a) / b);
            else if (!(isnan(a) && isnan(b)) && !(a == b))
                change = INFINITY;
            speed[k] = b;
        }
        if (change <= 1e-13)
            break;
    }
    for (size_t k = 0; k < nrows && k < max; k++)
        out[k] = tmp[k];
    *count = nrows;
done:
    cbm__free(p->ctx, tmp, nrows * sizeof *tmp);
    cbm__free(p->ctx, speed, nrows * sizeof *speed);
    cbm__free(p->ctx, fs, nv * sizeof *fs);
    cbm__free(p->ctx, group, 2 * n * sizeof *group);
    cbm__free(p->ctx, leaf, n * sizeof(double));
    cbm__free(p->ctx, fruit, n * sizeof(double));
    return st;
}
