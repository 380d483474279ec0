/* Mechanics inside the L+C dialect: the statics engine (include/cambium/mech.h) run over the
 * module string, in place (Jirasek, Prusinkiewicz and Moulia 2000; Taylor-Hell 2005 ch. 6, 8).
 *
 * The string is the plant: one declared module carries a mechanical segment in a MechSegment
 * parameter (inputs: length, semi-axes a >= b, E, G, density, modulus of rupture, rest rotation
 * rate; state and outputs: Omega, proximal position, H, U, stress, stress ratio, carried mass,
 * age), declared point-mass modules carry a mass in kg (and, if declared with a `radius` role,
 * the radius of the organ's contact sphere at the end of that segment: the largest of a node's
 * organs; Contact(k, s) turns organ-organ contact on, contact.c). One operation:
 *   1. one left-to-right scan (O(n)) builds an index view: each segment's parent is the last
 *      segment before it on its path from the root (a stack of it at `[`, restored at `]`); the
 *      turtle rotations between the parent and the segment (+ - & ^ \ / |, explicit angles in
 *      degrees) are composed in the parent's local frame into the branching rotation B and split
 *      into the plant's (divergence about H, deviation about U, roll about H) Euler angles
 *      (B = R_H(div) R_U(dev) R_H(roll)); a point mass is added at the distal end of the segment
 *      it follows. A first scan finds the axes: the segment that follows its parent with no `[`
 *      opened between them (`I [lateral] I`: the last I) continues the parent's axis and shares
 *      its joint (the staggered scheme); the others are declared laterals (order + 1), except
 *      that a segment with no axial child gives its joint to its first lateral. Segments keep
 *      their string order in the plant;
 *   2. a cbm_plant is made of it (one ring per segment with the parameters' section and wood,
 *      current Omega from the parameters), evaluated once; segments with a negative age are new:
 *      their rest rate is set by the tropism from the frames of that evaluation (Taylor-Hell
 *      6.8-6.12: tau = l_p H_p x F, rest = tau / C componentwise in the segment's frame before
 *      bending; a root uses its own length and heading), Omega = rest, age 0;
 *   3. the operation: equilibrium (cbm_plant_solve, warm-started from the stored Omega), rings
 *      (cbm_plant_grow_rings: pipe model and shape memory, Jirasek eq. 24), ageing
 *      (cbm_plant_age_wood, core ageing), breakage (cbm_plant_break, then the broken modules
 *      and the rest of their branches leave the string) or the stability query
 *      (cbm_plant_stability_factor: the factor by which one relaxation pass, Taylor-Hell 6.24
 *      with alpha = 1, grows a small push of the stored equilibrium; >= 1: the plant does not
 *      return to it, the buckling criterion of Taylor-Hell §6.3);
 *   4. results go back into the parameters. A segment's rings are kept in the parameters as one
 *      equivalent ring: E = C_L / I_L, G = C_H / J (the structural moduli, Taylor-Hell 8.5-8.6),
 *      density = mass per length / area, rest = the rigidity-weighted rest rate, age = the oldest
 *      ring's; this keeps C_H, C_L, the mass and the rest rate exactly (C_U too for a circular
 *      section), so state survives any rewriting that copies the parameter.
 * The plant is kept between operations while the string has not changed (compared byte for byte
 * with the string as the last operation left it, in the same buffer) and the settings it holds
 * (gravity, ground, contact, discretization) are the same: then the next operation skips the
 * build. After rings or ageing each segment's rings are replaced by the one equivalent ring
 * written back (step 4), so a kept plant is the plant a new build from the string would make,
 * bit for bit, and keeping changes no result. Its warm start also knows the point masses its
 * state balances (a new build balances none).
 * Frames: the turtle's (H, L, U) is left-handed (L = H x U, cpfg); the plant's is right-handed,
 * so the plant's L is minus the turtle's and a turtle rotation maps to the plant's local axes
 * with the signs in rot_of(). The clamp frame is the turtle's initial frame (H = +y, U = -z).
 */
#define _POSIX_C_SOURCE 200809L
#include "lsys/mechlang_internal.h"

#include "core/core.h"
#include "core/vecmath.h"

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

static double monotonic_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

enum { TR_NONE, TR_LEFT, TR_RIGHT, TR_DOWN, TR_UP, TR_ROLL_L, TR_ROLL_R, TR_TURN };

void cbm__mechlang_init(cbm__mechlang *m)
{
    memset(m, 0, sizeof *m);
    m->seg_code = -1;
    for (int i = 0; i < 128; i++)
        m->mass_off[i] = m->radius_off[i] = -1;
    for (int i = 0; i < 128; i++)
        m->light_area_off[i] = m->light_out_off[i] = -1;
    m->turtle['+'] = TR_LEFT;
    m->turtle['-'] = TR_RIGHT;
    m->turtle['&'] = TR_DOWN;
    m->turtle['^'] = TR_UP;
    m->turtle['\\'] = TR_ROLL_L;
    m->turtle['/'] = TR_ROLL_R;
    m->turtle['|'] = TR_TURN;
    m->sb = '[';
    m->eb = ']';
    m->gravity = v3(0, -9.81, 0);
    m->ground_y = 0.0;
    m->ground_k = 0.0;
    m->ground_s = 0.0;
    m->tropism = cbm_tropism_default();
    m->growth = cbm_growth_def_default();
    m->growth.ageing = CBM_AGEING_CORE;
    m->solve = cbm_solve_def_default();
    m->solve.confirm_modes = false; /* no model reads the mode count: the same states, faster */
    /* SolverMethod(2) in growth: the rings memorise approx's shapes, and the thesis's tip load
     * buckles stems (docs/methods.md, "In growth") */
    m->solve.approx_load = CBM_APPROX_LOAD_CALIBRATED;
    m->discretization = CBM_MECH_STAGGERED;
    m->keep = true;
}

/* The turtle rotation of `tr` by `deg` degrees as a rotation about the plant's local axes
 * (x = H, y = L_plant = -L_turtle, z = U). */
static cbm_quat rot_of(int tr, double deg)
{
    double a = deg * CBM_PI / 180.0;
    switch (tr) {
    case TR_LEFT: /* H towards L_turtle = -L_plant: about U by -a */
        return q_axis_angle(v3(0, 0, 1), -a);
    case TR_RIGHT:
        return q_axis_angle(v3(0, 0, 1), a);
    case TR_DOWN: /* H towards U: about L by -a */
        return q_axis_angle(v3(0, 1, 0), -a);
    case TR_UP:
        return q_axis_angle(v3(0, 1, 0), a);
    case TR_ROLL_R: /* L_turtle towards U: U towards L_plant: about H by -a */
        return q_axis_angle(v3(1, 0, 0), -a);
    case TR_ROLL_L:
        return q_axis_angle(v3(1, 0, 0), a);
    default: /* TR_TURN */
        return q_axis_angle(v3(0, 0, 1), CBM_PI);
    }
}

/* B = R_x(div) R_z(dev) R_x(roll): the proper Euler angles x-z-x of the rotation q. */
static void euler_xzx(cbm_quat q, double *div, double *dev, double *roll)
{
    cbm_vec3 c0 = q_rotate(q, v3(1, 0, 0)), c1 = q_rotate(q, v3(0, 1, 0)),
             c2 = q_rotate(q, v3(0, 0, 1));
    /* M[r][c] = component r of column c */
    double m00 = c0.x, m10 = c0.y, m20 = c0.z, m01 = c1.x, m11 = c1.y, m21 = c1.z, m02 = c2.x;
    double sb = sqrt(m10 * m10 + m20 * m20);
    *dev = atan2(sb, m00);
    if (sb > 1e-12) {
        *div = atan2(m20, m10);
        *roll = atan2(m02, -m01);
    } else if (m00 > 0) {
        *div = 0;
        *roll = atan2(m21, m11);
    } else {
        *div = 0;
        *roll = atan2(m21, -m11);
    }
}

typedef struct view {
    CBM_ARRAY(double *) seg;  /* the MechSegment of each plant segment */
    CBM_ARRAY(size_t) mod;    /* module index of each segment in the string */
    cbm__mwalk_stack path;    /* the walks' bracket stack */
    CBM_ARRAY(uint8_t) axis;  /* per segment: bit 0 on its parent's axis, bit 1 has such a child */
    CBM_ARRAY(int32_t) order; /* per segment: branch order (bracket nesting along the path) */
} view;

static void view_free(cbm_context *ctx, view *v)
{
    CBM_ARRAY_FREE(ctx, v->seg);
    CBM_ARRAY_FREE(ctx, v->mod);
    CBM_ARRAY_FREE(ctx, v->path);
    CBM_ARRAY_FREE(ctx, v->axis);
    CBM_ARRAY_FREE(ctx, v->order);
}

static cbm_status seg_error(char *err, size_t errn, size_t k, const char *what)
{
    snprintf(err, errn, "mechanical segment %zu: %s", k + 1, what);
    return CBM_E_INVALID;
}

/* First pass over the string: which segment continues its parent's axis. A segment after an SB
 * opened since its parent segment starts a lateral axis; the segment written after the branches
 * continues the axis (I [I ...] I: the last I). */
static cbm_status find_axes(cbm_context *ctx, const cbm__mechlang *m, lstr *s, view *v)
{
    struct {
        int64_t last;     /* the last segment on the path */
        uint8_t branched; /* a branch opened since it */
    } path = {-1, 0};
    v->axis.len = 0;
    cbm__mwalk w = cbm__mwalk_start(m, s, &path, sizeof path, &v->path);
    while (cbm__mwalk_next(ctx, &w)) {
        if (w.code == m->sb) {
            path.branched = 1;
        } else if (w.code == m->seg_code && w.np >= m->seg_off + MS_SIZE) {
            uint8_t a = (uint8_t)(path.last < 0 || !path.branched);
            if (a && path.last >= 0)
                v->axis.data[path.last] |= 2;
            CBM_TRY(CBM_ARRAY_PUSH(ctx, v->axis, a));
            path.last = (int64_t)v->axis.len - 1;
            path.branched = 0;
        }
    }
    return w.st;
}

/* The one ring of a segment of parameters g (index ix): the stored equivalent ring. */
static cbm_status core_of(const double *g, size_t ix, cbm_ring *r, char *err, size_t errn)
{
    if (!(g[MS_A] > 0) || !isfinite(g[MS_A]))
        return seg_error(err, errn, ix, "a must be > 0 (m)");
    if (!(g[MS_E] > 0) || !isfinite(g[MS_E]))
        return seg_error(err, errn, ix, "E must be > 0 (Pa)");
    if (!(g[MS_DENSITY] >= 0))
        return seg_error(err, errn, ix, "density must be >= 0 (kg/m^3)");
    *r = cbm_segment_def_default().core;
    r->youngs_modulus = g[MS_E];
    r->shear_modulus = g[MS_G] > 0 ? g[MS_G] : g[MS_E] / 16;
    r->density = g[MS_DENSITY];
    r->a = g[MS_A];
    r->b = g[MS_B] > 0 ? g[MS_B] : g[MS_A];
    if (r->b > r->a)
        return seg_error(err, errn, ix, "b must be <= a");
    r->modulus_of_rupture = g[MS_MOR] > 0 ? g[MS_MOR] : 0;
    r->age = g[MS_AGE] > 0 ? g[MS_AGE] : 0;
    r->rest_rate = v3(g[MS_REST], g[MS_REST + 1], g[MS_REST + 2]);
    return CBM_OK;
}

static cbm_status build(cbm_context *ctx, const cbm__mechlang *m, lstr *s, cbm_plant *pl, view *v,
                        char *err, size_t errn)
{
    struct {
        int64_t last; /* the last segment on the path */
        cbm_quat rel; /* the turtle's rotations since it, in its frame */
    } path = {-1, q_identity()};
    CBM_TRY(find_axes(ctx, m, s, v));
    cbm__mwalk w = cbm__mwalk_start(m, s, &path, sizeof path, &v->path);
    while (cbm__mwalk_next(ctx, &w)) {
        int code = w.code, np = w.np;
        double *p = w.p;
        if (code == m->sb || code == m->eb)
            continue; /* the path is the walk's */
        if (code == m->seg_code && np >= m->seg_off + MS_SIZE) {
            double *g = p + m->seg_off;
            size_t ix = v->seg.len;
            if (!(g[MS_LENGTH] > 0) || !isfinite(g[MS_LENGTH]))
                return seg_error(err, errn, ix, "length must be > 0 (m)");
            cbm_segment_def d = cbm_segment_def_default();
            CBM_TRY(core_of(g, ix, &d.core, err, errn));
            d.parent = path.last;
            /* a lateral leaves the joint with the parent's distal half to the axis; where the
             * parent has no axial child its first lateral takes that joint (the axis turns into
             * it, as when an apex dies), keeping its lateral order */
            bool axial = (v->axis.data[ix] & 1) != 0;
            d.lateral = !axial && path.last >= 0 && (v->axis.data[path.last] & 2);
            d.order = path.last < 0 ? 0 : v->order.data[path.last] + (axial ? 0 : 1);
            d.length = g[MS_LENGTH];
            euler_xzx(q_normalize(path.rel), &d.divergence, &d.deviation, &d.roll);
            d.omega = v3(g[MS_OMEGA], g[MS_OMEGA + 1], g[MS_OMEGA + 2]);
            d.point_mass = 0;
            cbm_status st = cbm_plant_add_segment(pl, &d, NULL);
            if (st != CBM_OK) {
                snprintf(err, errn, "mechanical segment %zu: %s", ix + 1,
                         cbm_context_last_error(ctx));
                return st;
            }
            CBM_TRY(CBM_ARRAY_PUSH(ctx, v->seg, g));
            CBM_TRY(CBM_ARRAY_PUSH(ctx, v->mod, w.at));
            CBM_TRY(CBM_ARRAY_PUSH(ctx, v->order, d.order));
            path.last = (int64_t)ix;
            path.rel = q_identity();
        } else if (m->turtle[code] && np >= (m->turtle[code] == TR_TURN ? 0 : 1)) {
            path.rel = q_mul(path.rel, rot_of(m->turtle[code], np ? p[0] : 0));
        } else if (m->mass_off[code] >= 0 && np > m->mass_off[code] && path.last >= 0) {
            double mass = p[m->mass_off[code]];
            if (!(mass >= 0) || !isfinite(mass)) {
                snprintf(err, errn, "point mass %g kg after mechanical segment %lld", mass,
                         (long long)path.last + 1);
                return CBM_E_INVALID;
            }
            cbm_segment_state st;
            CBM_TRY(cbm_plant_segment(pl, (size_t)path.last, &st));
            CBM_TRY(cbm_plant_set_load(pl, (size_t)path.last, st.point_mass + mass, st.tip_force,
                                       st.tip_moment));
            int ro = m->radius_off[code];
            if (ro >= 0 && np > ro) {
                /* one sphere per node: the largest organ there */
                double r = p[ro];
                if (!(r >= 0) || !isfinite(r)) {
                    snprintf(err, errn, "contact radius %g m after mechanical segment %lld", r,
                             (long long)path.last + 1);
                    return CBM_E_INVALID;
                }
                if (r > st.contact_radius)
                    CBM_TRY(cbm_plant_set_contact_radius(pl, (size_t)path.last, r));
            }
        }
    }
    return w.st;
}

/* New segments (negative age): rest rate from the tropism, Omega = rest. */
static cbm_status apply_tropism(const cbm__mechlang *m, cbm_plant *pl, const view *v)
{
    bool any = false;
    for (size_t i = 0; i < v->seg.len; i++)
        any |= v->seg.data[i][MS_AGE] < 0;
    if (!any)
        return CBM_OK;
    CBM_TRY(cbm_plant_evaluate(pl, NULL));
    cbm_vec3 f = v3(0, 0, 0);
    if (m->tropism.strength != 0 && v3_norm(m->tropism.direction) > 0)
        f = v3_scale(v3_normalize(m->tropism.direction), m->tropism.strength);
    const int64_t *par = cbm_plant_parents(pl);
    for (size_t i = 0; i < v->seg.len; i++) {
        double *g = v->seg.data[i];
        if (!(g[MS_AGE] < 0))
            continue;
        cbm_segment_state st, ps;
        CBM_TRY(cbm_plant_segment(pl, i, &st));
        cbm_vec3 lever = v3_scale(st.frame.h, st.length);
        if (par[i] >= 0) {
            CBM_TRY(cbm_plant_segment(pl, (size_t)par[i], &ps));
            lever = v3_scale(ps.frame.h, ps.length);
        }
        /* the frame before bending: the evaluated frame (a new segment has not bent yet) */
        cbm_vec3 tau = v3_cross(lever, f);
        cbm_vec3 loc = frame_to_local(st.frame, tau);
        cbm_vec3 rest = v3(loc.x / st.rigidity.x, loc.y / st.rigidity.y, loc.z / st.rigidity.z);
        cbm_ring r;
        CBM_TRY(cbm_plant_get_ring(pl, i, 0, &r));
        r.rest_rate = rest;
        r.age = 0;
        CBM_TRY(cbm_plant_set_ring(pl, i, 0, &r));
        CBM_TRY(cbm_plant_set_omega(pl, i, rest));
        g[MS_REST] = rest.x;
        g[MS_REST + 1] = rest.y;
        g[MS_REST + 2] = rest.z;
        g[MS_OMEGA] = rest.x;
        g[MS_OMEGA + 1] = rest.y;
        g[MS_OMEGA + 2] = rest.z;
        g[MS_AGE] = 0;
    }
    return CBM_OK;
}

static cbm_status write_back(const cbm_plant *pl, const view *v, bool section)
{
    for (size_t i = 0; i < v->seg.len; i++) {
        double *g = v->seg.data[i];
        cbm_segment_state st;
        CBM_TRY(cbm_plant_segment(pl, i, &st));
        double o[] = {st.omega.x,    st.omega.y,    st.omega.z,   st.proximal.x,
                      st.proximal.y, st.proximal.z, st.frame.h.x, st.frame.h.y,
                      st.frame.h.z,  st.frame.u.x,  st.frame.u.y, st.frame.u.z};
        memcpy(g + MS_OMEGA, o, sizeof o);
        g[MS_STRESS] = st.stress;
        g[MS_RATIO] = isfinite(st.stress_ratio) ? st.stress_ratio : 0;
        g[MS_CARRIED] = st.carried_mass;
        if (section) {
            double e, gm;
            CBM_TRY(cbm_plant_structural_modulus(pl, i, &e, &gm));
            g[MS_A] = st.a;
            g[MS_B] = st.b;
            g[MS_E] = e;
            g[MS_G] = gm;
            g[MS_DENSITY] = st.area > 0 ? st.mass_per_length / st.area : 0;
            g[MS_REST] = st.rest_rate.x;
            g[MS_REST + 1] = st.rest_rate.y;
            g[MS_REST + 2] = st.rest_rate.z;
            g[MS_AGE] = st.age;
        }
    }
    return CBM_OK;
}

/* Removes the modules marked in `cut` (1 at a broken segment) and the rest of their branches. */
static void cut_string(const cbm__mechlang *m, lstr *s, const uint8_t *cut)
{
    double *par = s->par;
    size_t j = 0, k = 0, oi = 0, oj = 0, ok = 0;
    int skipping = -1, depth = 0;
    for (size_t i = 0; i < s->n; i++) {
        int code = s->sym[i] & 0x7f;
        size_t np = (s->sym[i] & LSYS_PARAM_BIT) ? s->pc[j] : 0;
        if (skipping < 0 && cut[i]) {
            skipping = 1;
            depth = 0;
        }
        if (skipping >= 0) {
            if (code == m->sb)
                depth++;
            else if (code == m->eb && depth-- == 0)
                skipping = -1; /* the closing bracket of the branch stays */
        }
        if (skipping < 0) {
            s->sym[oi++] = s->sym[i];
            if (s->sym[i] & LSYS_PARAM_BIT) {
                s->pc[oj++] = (uint8_t)np;
                memmove(par + ok, par + k, np * sizeof(double));
                ok += np;
            }
        }
        if (s->sym[i] & LSYS_PARAM_BIT) {
            j++;
            k += np;
        }
    }
    s->n = oi;
    s->npm = oj;
    s->npar = ok;
}

static cbm_status run_op(cbm_context *ctx, cbm__mechlang *m, lstr *s, int op, double arg,
                         double *result, char *err, size_t errn, cbm_lsys_mech_timing *timing);

/* The plant kept between operations (see cbm__mechlang.kept): its view, the string's parameter
 * buffer its view points into, a copy of the string it was built from and written back to, and
 * the settings the plant holds. */
struct cbm__mechkept {
    cbm_plant *pl; /* NULL: none */
    view v;
    const void *par;
    uint8_t *sym, *pc;
    double *spar;
    size_t n, npm, npar, capsym, cappc, cappar;
    cbm_vec3 gravity;
    double ground[3], contact[2];
    cbm_mech_discretization discretization;
};

static void kept_drop(cbm_context *ctx, cbm__mechlang *m)
{
    struct cbm__mechkept *k = m->kept;
    if (!k || !k->pl)
        return;
    view_free(ctx, &k->v);
    cbm_plant_destroy(k->pl);
    k->pl = NULL;
}

void cbm__mechlang_free(cbm_context *ctx, cbm__mechlang *m)
{
    struct cbm__mechkept *k = m->kept;
    if (k) {
        kept_drop(ctx, m);
        cbm__free(ctx, k->sym, k->capsym);
        cbm__free(ctx, k->pc, k->cappc);
        cbm__free(ctx, k->spar, k->cappar * sizeof *k->spar);
        cbm__free(ctx, k, sizeof *k);
        m->kept = NULL;
    }
}

static bool same_settings(const cbm__mechlang *m, const struct cbm__mechkept *k)
{
    return k->gravity.x == m->gravity.x && k->gravity.y == m->gravity.y &&
           k->gravity.z == m->gravity.z && k->ground[0] == m->ground_y &&
           k->ground[1] == m->ground_k && k->ground[2] == m->ground_s &&
           k->contact[0] == m->contact_k && k->contact[1] == m->contact_s &&
           k->discretization == m->discretization;
}

/* The kept plant and its view, moved out to the caller, when the string and the settings are
 * those it was kept with; false otherwise (the caller builds a new plant). */
static bool kept_take(cbm__mechlang *m, const lstr *s, cbm_plant **pl, view *v)
{
    struct cbm__mechkept *k = m->kept;
    if (!m->keep || !k || !k->pl || k->par != s->par || k->n != s->n || k->npm != s->npm ||
        k->npar != s->npar || !same_settings(m, k) || memcmp(k->sym, s->sym, s->n) != 0 ||
        memcmp(k->pc, s->pc, s->npm) != 0 ||
        memcmp(k->spar, s->par, s->npar * sizeof *k->spar) != 0)
        return false;
    *pl = k->pl;
    *v = k->v;
    k->pl = NULL;
    memset(&k->v, 0, sizeof k->v);
    return true;
}

static bool grow_buf(cbm_context *ctx, void **buf, size_t *cap, size_t need, size_t size)
{
    if (need <= *cap)
        return true;
    size_t nc = need + need / 2;
    void *b = cbm__alloc(ctx, nc * size);
    if (!b)
        return false;
    if (*buf)
        cbm__free(ctx, *buf, *cap * size);
    *buf = b;
    *cap = nc;
    return true;
}

/* Keeps pl and v with a copy of the string s as written back; false (nothing kept, the caller
 * still owns pl and v) when out of memory: keeping is only a saving. */
static bool kept_store(cbm_context *ctx, cbm__mechlang *m, const lstr *s, cbm_plant *pl, view *v)
{
    kept_drop(ctx, m);
    if (!m->kept) {
        m->kept = cbm__calloc(ctx, 1, sizeof *m->kept);
        if (!m->kept)
            return false;
    }
    struct cbm__mechkept *k = m->kept;
    if (!grow_buf(ctx, (void **)&k->sym, &k->capsym, s->n, 1) ||
        !grow_buf(ctx, (void **)&k->pc, &k->cappc, s->npm, 1) ||
        !grow_buf(ctx, (void **)&k->spar, &k->cappar, s->npar, sizeof *k->spar))
        return false;
    if (s->n)
        memcpy(k->sym, s->sym, s->n);
    if (s->npm)
        memcpy(k->pc, s->pc, s->npm);
    if (s->npar)
        memcpy(k->spar, s->par, s->npar * sizeof *k->spar);
    k->par = s->par;
    k->n = s->n;
    k->npm = s->npm;
    k->npar = s->npar;
    k->gravity = m->gravity;
    k->ground[0] = m->ground_y;
    k->ground[1] = m->ground_k;
    k->ground[2] = m->ground_s;
    k->contact[0] = m->contact_k;
    k->contact[1] = m->contact_s;
    k->discretization = m->discretization;
    k->pl = pl;
    k->v = *v;
    return true;
}

/* After rings or ageing: each segment's rings replaced by the one equivalent ring written back,
 * the plant a new build from the string would make (cbm_plant_replace_rings). */
static cbm_status collapse(cbm_plant *pl, const view *v, char *err, size_t errn)
{
    for (size_t i = 0; i < v->seg.len; i++) {
        cbm_ring r;
        CBM_TRY(core_of(v->seg.data[i], i, &r, err, errn));
        CBM_TRY(cbm_plant_replace_rings(pl, i, &r));
    }
    return CBM_OK;
}

/* After rings were added or the wood aged: the plant evaluated, the sections written back to the
 * string, each segment's rings collapsed to the equivalent ring. */
static cbm_status settle_wood(cbm_plant *pl, const view *v, char *err, size_t errn)
{
    CBM_TRY(cbm_plant_evaluate(pl, NULL));
    CBM_TRY(write_back(pl, v, true));
    return collapse(pl, v, err, errn);
}

/* A model and string the mechanics can run on; else a message in err. */
static cbm_status usable(const cbm__mechlang *m, const lstr *s, char *err, size_t errn)
{
    err[0] = 0;
    if (m->seg_code < 0) {
        snprintf(err, errn, "no `mechanics:` module declared");
        return CBM_E_INVALID;
    }
    if (s->f32) {
        snprintf(err, errn, "mechanics needs double parameters");
        return CBM_E_INVALID;
    }
    return CBM_OK;
}

/* The plant of the string's segments (create, ground, build, tropism for new segments). */
static cbm_status make_plant(cbm_context *ctx, const cbm__mechlang *m, lstr *s, cbm_plant **out,
                             view *v, char *err, size_t errn)
{
    cbm_plant_def pd = cbm_plant_def_default();
    pd.gravity = m->gravity;
    pd.discretization = m->discretization;
    /* clamp: the turtle's initial frame, H = +y, L_plant = +x, U = -z */
    pd.base_orientation =
        q_mul(q_axis_angle(v3(0, 0, 1), CBM_PI / 2), q_axis_angle(v3(1, 0, 0), CBM_PI));
    cbm_status st = cbm_plant_create(ctx, &pd, out);
    if (st == CBM_OK)
        st = cbm_plant_set_ground(*out, m->ground_y, m->ground_k, m->ground_s);
    if (st == CBM_OK)
        st = cbm_plant_set_contact(*out, m->contact_k, m->contact_s);
    if (st == CBM_OK)
        st = build(ctx, m, s, *out, v, err, errn);
    if (st == CBM_OK && v->seg.len)
        st = apply_tropism(m, *out, v);
    return st;
}

cbm_status cbm__mechlang_plant(cbm_context *ctx, const cbm__mechlang *m, lstr *s, cbm_plant **out,
                               char *err, size_t errn)
{
    *out = NULL;
    CBM_TRY(usable(m, s, err, errn));
    cbm_plant *pl = NULL;
    view v;
    memset(&v, 0, sizeof v);
    cbm_status st = make_plant(ctx, m, s, &pl, &v, err, errn);
    if (st == CBM_OK)
        st = cbm_plant_evaluate(pl, NULL);
    view_free(ctx, &v);
    if (st != CBM_OK) {
        if (!err[0])
            snprintf(err, errn, "%s", cbm_context_last_error(ctx));
        cbm_plant_destroy(pl);
        return st;
    }
    *out = pl;
    return CBM_OK;
}

cbm_status cbm__mechlang_run(cbm_context *ctx, cbm__mechlang *m, lstr *s, int op, double arg,
                             double *result, char *err, size_t errn, cbm_lsys_mech_timing *timing)
{
    cbm_lsys_mech_timing scratch;
    if (!timing) {
        memset(&scratch, 0, sizeof scratch);
        timing = &scratch;
    }
    double t0 = monotonic_seconds();
    cbm_status st = run_op(ctx, m, s, op, arg, result, err, errn, timing);
    double dt = monotonic_seconds() - t0;
    timing->operations++;
    if (op == CBM__ML_EQUILIBRIUM)
        timing->equilibrium += dt;
    else if (op == CBM__ML_RINGS || op == CBM__ML_AGE)
        timing->rings += dt;
    else
        timing->other += dt;
    return st;
}

cbm_lsys_mech_timing cbm_lsys_mech_time(const cbm_lsys *ls)
{
    cbm_lsys_mech_timing t;
    memset(&t, 0, sizeof t);
    return ls ? ls->mech_time : t;
}

static cbm_status run_op(cbm_context *ctx, cbm__mechlang *m, lstr *s, int op, double arg,
                         double *result, char *err, size_t errn, cbm_lsys_mech_timing *timing)
{
    *result = 0;
    CBM_TRY(usable(m, s, err, errn));
    cbm_plant *pl = NULL;
    view v;
    memset(&v, 0, sizeof v);
    cbm_status st = CBM_OK;
    if (kept_take(m, s, &pl, &v))
        timing->kept++;
    else {
        kept_drop(ctx, m);
        st = make_plant(ctx, m, s, &pl, &v, err, errn);
    }
    bool cut = false;
    if (st == CBM_OK && v.seg.len == 0)
        goto done;
    if (st == CBM_OK && op == CBM__ML_EQUILIBRIUM) {
        cbm_solve_stats ss;
        memset(&ss, 0, sizeof ss);
        cbm_solve_def sd = m->solve;
        sd.warm_start = true;
        double t0 = monotonic_seconds();
        st = cbm_plant_solve(pl, &sd, &ss);
        timing->solve += monotonic_seconds() - t0;
        timing->passes += ss.passes;
        *result = (double)ss.passes;
        if (st == CBM_E_NOT_CONVERGED && m->go_on) { /* the best iterate; the model goes on */
            cbm_context_clear_errors(ctx);
            *result = -(double)ss.passes;
            st = CBM_OK;
        }
        if (st == CBM_OK)
            st = write_back(pl, &v, false);
    } else if (st == CBM_OK && op == CBM__ML_RINGS) {
        cbm_growth_stats gs = {0, 0, 0};
        st = cbm_plant_evaluate(pl, NULL);
        if (st == CBM_OK)
            st = cbm_plant_grow_rings(pl, &m->growth, &gs);
        *result = (double)gs.rings_added;
        if (st == CBM_OK)
            st = settle_wood(pl, &v, err, errn);
    } else if (st == CBM_OK && op == CBM__ML_AGE) {
        st = cbm_plant_age_wood(pl, &m->growth, arg);
        if (st == CBM_OK)
            st = settle_wood(pl, &v, err, errn);
        *result = (double)v.seg.len;
    } else if (st == CBM_OK && (op == CBM__ML_FREQUENCY || op == CBM__ML_SWAY)) {
        /* the dynamics about the stored state; the string is not changed */
        st = cbm_plant_evaluate(pl, NULL);
        if (st == CBM_OK && op == CBM__ML_FREQUENCY)
            st = cbm__mechlang_frequency(ctx, pl, (size_t)arg, result);
        else if (st == CBM_OK)
            st = cbm__mechlang_sway(ctx, pl, m->dyn_args, m->sway_fn, m->sway_ud, result);
    } else if (st == CBM_OK && op == CBM__ML_STABILITY) {
        st = cbm_plant_stability_factor(pl, result, NULL);
        if (st != CBM_OK)
            *result = 0;
    } else if (st == CBM_OK && op == CBM__ML_BREAK) {
        size_t nb = 0, n = v.seg.len, ns = s->n ? s->n : 1;
        size_t *broken = cbm__alloc(ctx, n * sizeof *broken);
        uint8_t *cutm = cbm__calloc(ctx, ns, 1);
        st = broken && cutm ? cbm_plant_evaluate(pl, NULL) : CBM_E_NOMEM;
        if (st == CBM_OK)
            st = write_back(pl, &v, false);
        if (st == CBM_OK)
            st = cbm_plant_break(pl, broken, n, &nb, NULL);
        if (st == CBM_OK) {
            for (size_t i = 0; i < nb; i++)
                cutm[v.mod.data[broken[i]]] = 1;
            cut_string(m, s, cutm);
            *result = (double)nb;
            cut = nb > 0;
        }
        if (broken)
            cbm__free(ctx, broken, n * sizeof *broken);
        if (cutm)
            cbm__free(ctx, cutm, ns);
    }
    if (st != CBM_OK && !err[0])
        snprintf(err, errn, "%s", cbm_context_last_error(ctx));
done:
    /* kept for the next operation unless the string lost segments (a new build is cheap for an
     * empty plant) */
    if (st == CBM_OK && !cut && v.seg.len && m->keep && kept_store(ctx, m, s, pl, &v))
        return st;
    view_free(ctx, &v);
    cbm_plant_destroy(pl);
    return st;
}
