/* Method A on a plant (CBM_MECH_APPROX; Gürtler 2018 §2.1, §4; docs/methods.md): every axis
 * (a root or a lateral and its chain of continuations) is bent by the approximative angle
 * generator of cambium/approx.h, in index order so that an axis starts from its parent's bent
 * frame (the thesis passes the parent's angle to its children; here the whole frame is
 * inherited, so the lateral's own branching angles count too).
 *
 * Per axis, from the plant (the thesis's conversion 5.1-5.2, generalised):
 *   t0   the angle of the axis's first segment, in the unloaded state of its own joint, from the
 *        upward vertical (against gravity);
 *   disc the axis's segment count; h its length / disc (the method assumes equal segments);
 *   coni 1 - r_end / r_start of the linear taper through the first and last segments' semi-axes
 *        a at their centroids, extrapolated to the axis's ends (clamped to [0, 0.99]);
 *   F    approx_force_factor times the weight the axis carries (its own wood, its laterals and
 *        every point mass on them: the thesis's "extra loads" of sub-branches, at the tip);
 *   EI   the first segment's rigidity about the bending axis, scaled to r_start;
 *   K0 = h sqrt(F / EI).
 * With approx_load = calibrated (what growth uses), K0 is chosen instead so that the generator's
 * small-load tip rotation (K0 disc)^2 / 2 is the axis's own linear one as a horizontal
 * cantilever, the integral of M/EI with every segment's EI and the load where it hangs, and
 * coni = 0: the tip load on a strongly tapered stem buckles the thesis's cone.
 * The axis bends in the vertical plane through its first segment: joint k turns about the
 * horizontal axis H x g by res[k+1] on top of its rest rotation. Tip forces and moments, ground
 * and organ contact, torsion and out-of-plane loads are ignored; a rest curvature is kept as the
 * unloaded shape and the bending superimposed (exactly where it lies in the bending plane).
 * The frames are set while bending, exactly as the forward sweep would set them; afterwards one
 * backward sweep computes forces and moments; stats.residual says how far the
 * shape is from the equilibrium of the segment model (it is not one). */
#include "mech/approx_internal.h"
#include "mech/mech_internal.h"
#include "core/vecmath.h"

#include <math.h>
#include <string.h>

/* The scratch lives in the plant's solver workspace (cbm__mech_work), whose Newton-Krylov
 * arrays (3 doubles per segment each, held whatever the solver, and used by no one else during
 * an approx pass) it borrows: no allocation per solve, and no fresh pages to fault in (on a
 * 10^4-segment tree a fifth of the pass went to the kernel's page faults when these were
 * allocated at every solve). */
typedef struct approx_scratch {
    double *inc;   /* per segment: the bending rotation of its joint, rad */
    cbm_vec3 *ax;  /* per segment: the world axis of that rotation */
    size_t *chain; /* one axis's segments */
    double *res;   /* the generator's output, chain length + 1 */
    size_t n;
} approx_scratch;

static bool starts_axis(const cbm_plant *p, size_t i)
{
    return p->parent[i] < 0 || !(p->cont[i] & 1);
}

static bool rest_free(cbm_vec3 r)
{
    return r.x == 0.0 && r.y == 0.0 && r.z == 0.0;
}

/* The parent's frame turned by segment i's branching rotation, and i's proximal node. */
static cbm_quat joint_base(const cbm_plant *p, size_t i, cbm_vec3 *pos)
{
    int64_t pa = p->parent[i];
    cbm_quat qa;
    if (pa < 0) {
        qa = p->base_q;
        *pos = p->base_pos;
    } else {
        qa = p->q[pa];
        *pos = v3_madd(p->pos[pa], q_h(qa), p->len[pa]);
    }
    cbm_quat b = p->branch[i];
    if (b.w != 1.0)
        qa = q_mul(qa, b);
    return qa;
}

/* The generator's increments (degrees, in sc->res[1..m]) onto the axis's chain. */
static cbm_status set_increments(approx_scratch *sc, size_t m, cbm_vec3 axis)
{
    for (size_t k = 0; k < m; k++) {
        sc->inc[sc->chain[k]] = sc->res[k + 1] * (CBM_PI / 180.0);
        sc->ax[sc->chain[k]] = axis;
    }
    return CBM_OK;
}

/* Generator parameters of the axis starting at segment i (frame before its joint: qa) and the
 * increments of its chain into the scratch arrays. */
static cbm_status bend_axis(cbm_plant *p, const cbm_solve_def *d, approx_scratch *sc, size_t i,
                            cbm_quat qa)
{
    const cbm__mech_work *w = &p->work;
    size_t m = 0;
    double len = 0.0;
    for (int64_t j = (int64_t)i; j >= 0; j = p->fchild[j]) {
        sc->chain[m++] = (size_t)j;
        len += p->len[j];
    }
    double g = v3_norm(p->gravity);
    cbm_vec3 gdir = g > 0.0 ? v3_scale(p->gravity, 1.0 / g) : v3(0, -1, 0);
    /* a joint without rest rotation (most of a tree's): the frame is qa itself, bit for bit */
    cbm_quat q0 =
        rest_free(w->rj[i]) ? qa : q_mul(qa, q_from_rotvec(v3_scale(w->rj[i], w->dual[i])));
    cbm_vec3 h0 = q_h(q0);
    double cosv = -v3_dot(h0, gdir);
    cbm_vec3 axis = v3_cross(h0, gdir);
    double an = v3_norm(axis); /* sin t0 (h0 and gdir are unit vectors) */
    /* vertical: any horizontal axis; the segment's L keeps it deterministic */
    axis = an > 1e-12 ? v3_scale(axis, 1.0 / an) : q_rotate(q0, v3(0, 1, 0));
    /* taper through the centroids' semi-axes, extrapolated half a segment to each end */
    double a0 = p->outer[i].a, a1 = p->outer[sc->chain[m - 1]].a;
    double rb = a0, rt = a0;
    if (m >= 2) {
        double slope = (a1 - a0) / (double)(m - 1);
        rb = a0 - 0.5 * slope;
        rt = a1 + 0.5 * slope;
    }
    double coni = rb > 0.0 ? 1.0 - rt / rb : 0.0;
    coni = fmax(0.0, fmin(0.99, coni));
    if (!(rb > 0.0))
        rb = a0;
    cbm_vec3 al = q_rotate(q_conj(q0), axis);
    cbm_vec3 c = p->rig[i];
    double ei = al.y * al.y * c.y + al.z * al.z * c.z + al.x * al.x * c.x;
    double scale = rb / a0;
    ei *= scale * scale * scale * scale;
    double f = d->approx_force_factor * g * p->cmass[i];
    double hseg = len / (double)m;
    cbm_approx_def ad = cbm_approx_def_default();
    ad.disc = (long)m;
    ad.k0 = f > 0.0 && ei > 0.0 ? hseg * sqrt(f / ei) : 0.0;
    ad.coni = coni;
    if (d->approx_load == CBM_APPROX_LOAD_CALIBRATED) {
        /* the axis straightened horizontally: from the tip down, the moment at a distance u
         * before segment j's distal node is M_d + g (beyond u + mpl u^2 / 2), "beyond" all that
         * hangs from the distal node (continuation, laterals, point mass); Simpson's rule is
         * exact for it */
        double md = 0.0, wl = 0.0;
        for (size_t k = m; k-- > 0;) {
            size_t j = sc->chain[k];
            double lj = p->len[j], own = p->mpl[j] * lj, beyond = p->cmass[j] - own;
            double mp = md + g * (beyond * lj + 0.5 * own * lj);
            double mm = md + g * (0.5 * beyond * lj + 0.125 * own * lj);
            double eij = 0.5 * (p->rig[j].y + p->rig[j].z);
            wl += lj / 6.0 * (md + 4.0 * mm + mp) / eij;
            md = mp;
        }
        wl *= d->approx_force_factor;
        ad.k0 = wl > 0.0 ? sqrt(2.0 * wl) / (double)m : (wl == 0.0 ? 0.0 : NAN);
        ad.coni = 0.0;
    }
    ad.p = d->approx_p;
    ad.mode = d->approx_mode;
    /* the corrected mode's small loads (most axes of a tree of short axes): the series from
     * sin t0 and cos t0 as they are here, no acos, no root (approx.c) */
    if (ad.mode == CBM_APPROX_CORRECTED && isfinite(ad.k0) && an > 1e-12 &&
        cbm__approx_series(&ad, an, fmax(-1.0, fmin(1.0, cosv)), sc->res))
        return set_increments(sc, m, axis);
    double t0 = acos(fmax(-1.0, fmin(1.0, cosv)));
    ad.t0 = t0 * (180.0 / CBM_PI);
    if (!isfinite(ad.k0) || !isfinite(ad.t0))
        return cbm__fail(p->ctx, CBM_E_NONFINITE,
                         "approx: axis from segment %zu: K0 or t0 is not "
                         "finite",
                         i);
    cbm_status s = cbm_approx_angles(p->ctx, &ad, sc->res, m + 1, NULL);
    if (s != CBM_OK)
        return cbm__fail(p->ctx, s, "approx: axis from segment %zu failed", i);
    return set_increments(sc, m, axis);
}

/* Whether segment c continues its parent's axis with the parent's local bending axis: the
 * parent's joint turns only about that axis (no rest rotation) and c's branching rotation is the
 * identity, so the axis, fixed in the world along the chain, has the same local coordinates in
 * both frames. */
static bool carries_axis(const cbm_plant *p, size_t c)
{
    int64_t pa = p->parent[c];
    return pa >= 0 && (p->cont[c] & 1) && p->fchild[pa] == (int64_t)c &&
           rest_free(p->work.rj[pa]) && p->branch[c].w == 1.0;
}

/* The corrected mode's sweep (the thesis mode keeps the general one below, bit for bit): the
 * local bending axis is found by one rotation per axis and handed down the chain in sc->ax where
 * carries_axis holds (in place of the world axis, which that segment no longer needs).
 * Differs from the general loop by round-off (test approx_corrected_sweep). */
static cbm_status bend_corrected(cbm_plant *p, const cbm_solve_def *d, approx_scratch *sc)
{
    const cbm__mech_work *w = &p->work;
    for (size_t i = 0; i < p->n; i++) {
        cbm_vec3 pos;
        cbm_quat qa = joint_base(p, i, &pos);
        cbm_vec3 la;
        if (starts_axis(p, i)) {
            cbm_status s = bend_axis(p, d, sc, i, qa);
            if (s != CBM_OK)
                return s;
            la = q_rotate(q_conj(qa), sc->ax[i]);
        } else if (carries_axis(p, i)) {
            la = sc->ax[i];
        } else {
            la = q_rotate(q_conj(qa), sc->ax[i]);
        }
        /* omega dual through omega, as the general loop: the ApproxLoad routes compare bits */
        p->omega[i] = v3_add(w->rj[i], v3_scale(la, sc->inc[i] / w->dual[i]));
        cbm_vec3 rot = v3_scale(p->omega[i], w->dual[i]);
        p->q[i] = cbm__mech_qnorm(q_mul(qa, cbm__mech_qexp(rot)));
        p->pos[i] = pos;
        p->force[i] = v3(0, 0, 0);
        p->moment[i] = v3(0, 0, 0);
        int64_t c = p->fchild[i];
        if (c >= 0 && carries_axis(p, (size_t)c))
            sc->ax[c] = la;
    }
    return CBM_OK;
}

cbm_status cbm__mech_solve_approx(cbm_plant *p, const cbm_solve_def *d, cbm_solve_stats *st)
{
    if (!(d->approx_p >= 0.0 && d->approx_p <= 1.0))
        return cbm__fail(p->ctx, CBM_E_INVALID, "solve: approx_p must be in [0, 1]");
    if (!(d->approx_force_factor > 0.0) || !isfinite(d->approx_force_factor))
        return cbm__fail(p->ctx, CBM_E_INVALID, "solve: approx_force_factor must be > 0");
    if (d->approx_load != CBM_APPROX_LOAD_TIP && d->approx_load != CBM_APPROX_LOAD_CALIBRATED)
        return cbm__fail(p->ctx, CBM_E_INVALID, "solve: unknown approx load %d",
                         (int)d->approx_load);
    if (d->approx_mode != CBM_APPROX_CORRECTED && d->approx_mode != CBM_APPROX_THESIS)
        return cbm__fail(p->ctx, CBM_E_INVALID, "solve: unknown approx mode %d",
                         (int)d->approx_mode);
    size_t n = p->n;
    approx_scratch sc = {0};
    cbm__mech_work *wk = &p->work;
    sc.n = n;
    sc.ax = wk->res;                     /* n vectors */
    sc.inc = (double *)wk->step;         /* n of its 3n doubles */
    sc.res = (double *)wk->step + n;     /* n + 1 more (3n >= 2n + 1) */
    sc.chain = (size_t *)(void *)wk->dm; /* n of its 3n words */
    cbm_status s = wk->cap >= n && sc.ax && sc.inc && sc.chain ? CBM_OK : CBM_E_NOMEM;
    const cbm__mech_work *w = &p->work;
    if (d->approx_mode == CBM_APPROX_CORRECTED)
        s = bend_corrected(p, d, &sc);
    for (size_t i = 0; i < n && s == CBM_OK && d->approx_mode == CBM_APPROX_THESIS; i++) {
        cbm_vec3 pos;
        cbm_quat qa = joint_base(p, i, &pos);
        if (starts_axis(p, i))
            s = bend_axis(p, d, &sc, i, qa);
        if (s != CBM_OK)
            break;
        cbm_vec3 bend = v3_scale(q_rotate(q_conj(qa), sc.ax[i]), sc.inc[i] / w->dual[i]);
        p->omega[i] = v3_add(w->rj[i], bend);
        p->q[i] = cbm__mech_qnorm(q_mul(qa, cbm__mech_qexp(v3_scale(p->omega[i], w->dual[i]))));
        p->pos[i] = pos;
        p->force[i] = v3(0, 0, 0);
        p->moment[i] = v3(0, 0, 0);
    }
    if (s != CBM_OK)
        return s == CBM_E_NOMEM ? cbm__fail(p->ctx, s, "approx: out of memory") : s;
    double mmax = 0.0;
    double r = cbm__mech_backward(p, 0.0, NULL, &mmax, NULL);
    if (!isfinite(r))
        return cbm__mech_report_nonfinite(p);
    st->passes = 1;
    st->residual = cbm__mech_relres(r, mmax, &st->char_moment);
    st->stage = CBM_SOLVE_STAGE_NONE;
    st->lowest_eigenvalue = NAN;
    return CBM_OK;
}
