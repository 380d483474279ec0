/* The linearised equations of motion of a plant about its equilibrium, and their O(n) operators.
 *
 * Coordinates. q_k is the small rotation (world components) of joint k about its node x_k,
 * applied to the whole subtree T_k that the joint carries, the joints composed from the tips to
 * the base (a point p of T_k moves to E_1(E_2(...E_k(p)))). The twist of segment s is then
 * Z_s = sum over the joints k on its path of S_k q_k, S_k q = (q, x_k x q): its rotation and the
 * displacement of the origin, so that a point p of s moves by d + Theta x p.
 *
 * Kinetic energy. 1/2 sum_s Z_s' . P_s Z_s' with P_s the 6x6 spatial inertia of segment s about
 * the origin (a uniform solid elliptical rod of the outer section: mass m at its centroid c,
 * rotary inertia J_c = R diag(m (a^2+b^2)/4, m (l^2/12 + a^2/4), m (l^2/12 + b^2/4)) R^T, plus
 * its point mass at the distal node): P = [[J_c + m [c][c]^T, m [c]], [m [c]^T, m I]].
 *
 * Potential energy, to second order.
 *  - Joints: the relative rotation of joint k changes by exactly R_k^T q_k (local), so the elastic
 *    energy is 1/2 q_k . K_k q_k with K_k = R_k diag(C_joint / d) R_k^T, the statics' joint
 *    rigidity and bending length, up to terms of relative order |d Omega| (the joint's own bend
 *    angle, small for short segments; docs/dynamics.md).
 *  - Dead loads (weights, tip forces F at points p): the second-order motion of p is
 *    1/2 sum_k [q_k]^2 r_k + sum_{j ancestor of k} [q_j][q_k] r_k with r_k = p - x_k, so
 *    -F . (that) = 1/2 q_k . sym(G_k) q_k + sum_{j ancestor of k} q_j . G_k q_k, with
 *    G_k = sum over the loads carried by k of (F . r_k) I - r_k F^T. For an upright stem
 *    (F down, r up) G is negative across the stem: gravity softens it; hanging, it stiffens.
 *
 * Hence the operator y = (sk K + sm M) v, one sweep each way:
 *     Z_k = Z_parent + S_k v_k,
 *     W_k = sm P_k Z_k + sum_children W_c,   (the wrench of the subtree, moment about the origin)
 *     y_k = A_k v_k + B_k Z_parent + S_k^T W_k,   then W_k += (sk G_k v_k, 0),
 * with A_k = sk (K_k + sym G_k), B_k = sk [G_k^T 0], S_k^T (n, f) = n - x_k x f.
 *
 * Solve. Each subtree responds to the twist of its parent linearly, W_k = Phi_k Z_parent + psi_k.
 * Eliminating from the tips (the articulated-body recursion of robot dynamics with joint springs
 * and the load terms added):
 *     Pi_k = sm P_k + sum_c Phi_c,  L_k = B_k + S_k^T Pi_k,  D_k = A_k + S_k^T Pi_k S_k,
 *     Phi_k = Pi_k - L_k^T D_k^-1 L_k,
 *     u_k = b_k - S_k^T sum_c psi_c,  psi_k = sum_c psi_c + L_k^T D_k^-1 u_k,
 * then from the base v_k = D_k^-1 (u_k - L_k Z_parent), Z_k = Z_parent + S_k v_k. The D_k are the
 * pivots of a block elimination of the symmetric matrix, so it is positive definite iff all are
 * (Sylvester), which the factorisation counts. Cost: a few hundred flops per segment for the
 * factorisation, about a hundred per solve or product.
 */
#include "mech/dyn_internal.h"
#include "core/vecmath.h"
#include "mech/mech_internal.h"

#include <math.h>
#include <string.h>

/* R (local to world) as a row-major matrix: columns H, L, U. */
static void rotm(cbm_quat q, double *r)
{
    double xx = q.x * q.x, yy = q.y * q.y, zz = q.z * q.z;
    double xy = q.x * q.y, xz = q.x * q.z, yz = q.y * q.z;
    double wx = q.w * q.x, wy = q.w * q.y, wz = q.w * q.z;
    double m[9] = {1.0 - 2.0 * (yy + zz), 2.0 * (xy - wz),       2.0 * (xz + wy),
                   2.0 * (xy + wz),       1.0 - 2.0 * (xx + zz), 2.0 * (yz - wx),
                   2.0 * (xz - wy),       2.0 * (yz + wx),       1.0 - 2.0 * (xx + yy)};
    memcpy(r, m, sizeof m);
}

/* out = R diag(s) R^T */
static void rdrt(const double *r, cbm_vec3 s, double *out)
{
    double sv[3] = {s.x, s.y, s.z};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double a = 0.0;
            for (int k = 0; k < 3; k++)
                a += r[3 * i + k] * sv[k] * r[3 * j + k];
            out[3 * i + j] = a;
        }
}

/* adds the spatial inertia of mass m at c with rotary inertia jc (3x3 world, may be NULL) */
static void add_inertia(double *p, double m, cbm_vec3 c, const double *jc)
{
    double cx[9] = {0, -c.z, c.y, c.z, 0, -c.x, -c.y, c.x, 0};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            /* [c][c]^T = -[c][c] */
            double cc = 0.0;
            for (int k = 0; k < 3; k++)
                cc -= cx[3 * i + k] * cx[3 * k + j];
            p[6 * i + j] += m * cc + (jc ? jc[3 * i + j] : 0.0);
            p[6 * i + 3 + j] += m * cx[3 * i + j];
            p[6 * (3 + i) + j] += m * cx[3 * j + i];
        }
    for (int i = 0; i < 3; i++)
        p[6 * (3 + i) + 3 + i] += m;
}

void cbm__dyn_free(cbm__dyn *d)
{
    if (!d || !d->ctx)
        return;
    size_t n = d->n;
    cbm__free(d->ctx, d->parent, n * sizeof *d->parent);
    cbm__free(d->ctx, d->x, n * sizeof *d->x);
    cbm__free(d->ctx, d->e, n * sizeof *d->e);
    cbm__free(d->ctx, d->kel, 9 * n * sizeof(double));
    cbm__free(d->ctx, d->geo, 9 * n * sizeof(double));
    cbm__free(d->ctx, d->body, 36 * n * sizeof(double));
    cbm__free(d->ctx, d->pc, 10 * n * sizeof(double));
    cbm__free(d->ctx, d->ak, 9 * n * sizeof(double));
    cbm__free(d->ctx, d->dinv, 9 * n * sizeof(double));
    cbm__free(d->ctx, d->dl, 18 * n * sizeof(double));
    cbm__free(d->ctx, d->pi, 36 * n * sizeof(double));
    cbm__free(d->ctx, d->z, 6 * n * sizeof(double));
    cbm__free(d->ctx, d->acc, 6 * n * sizeof(double));
    cbm__free(d->ctx, d->u, 3 * n * sizeof(double));
    cbm__free(d->ctx, d->width, n * sizeof(double));
    cbm__free(d->ctx, d->pmass, n * sizeof(double));
    memset(d, 0, sizeof *d);
}

/* the joint's rigidity and bending length as the statics use them (solve_common.c, prepare) */
static void joint_rigidity(const cbm_plant *p, size_t i, cbm_vec3 *cj, double *dual)
{
    double l = p->len[i];
    int64_t pa = p->parent[i];
    if (p->disc != CBM_MECH_STAGGERED) {
        *dual = l;
        *cj = p->rig[i];
    } else if (pa < 0 || !(p->cont[i] & 1)) {
        *dual = 0.5 * l;
        *cj = p->rig[i];
    } else {
        double lp = p->len[pa], dd = 0.5 * (lp + l);
        cbm_vec3 cp = p->rig[pa], ci = p->rig[i];
        *dual = dd;
        *cj = v3(dd / (0.5 * lp / cp.x + 0.5 * l / ci.x), dd / (0.5 * lp / cp.y + 0.5 * l / ci.y),
                 dd / (0.5 * lp / cp.z + 0.5 * l / ci.z));
    }
}

/* The spatial inertia P = [[J, [h]], [[h]^T, m I]] (add_inertia: J about the origin, h the first
 * moment of the mass) in 10 doubles (cbm__dyn_pz), and A = K_el + sym G: the blocks the sweeps
 * read, a third of the 36 + 9 + 9 doubles they are made of. */
static void compact_blocks(cbm__dyn *d)
{
    for (size_t k = 0; k < d->n; k++) {
        const double *p = d->body + 36 * k;
        double *c = d->pc + 10 * k;
        c[0] = p[0];
        c[1] = p[7];
        c[2] = p[14];
        c[3] = 0.5 * (p[1] + p[6]);
        c[4] = 0.5 * (p[2] + p[12]);
        c[5] = 0.5 * (p[8] + p[13]);
        c[6] = p[16]; /* h_x: [h] row 2, column 1 */
        c[7] = p[5];  /* h_y: row 0, column 2 */
        c[8] = p[9];  /* h_z: row 1, column 0 */
        c[9] = p[21];
        const double *g = d->geo + 9 * k, *ke = d->kel + 9 * k;
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                d->ak[9 * k + 3 * i + j] = ke[3 * i + j] + 0.5 * (g[3 * i + j] + g[3 * j + i]);
    }
}

cbm_status cbm__dyn_build(const cbm_plant *p, cbm__dyn *d)
{
    memset(d, 0, sizeof *d);
    if (!p)
        return CBM_E_INVALID;
    size_t n = p->n;
    if (n == 0)
        return cbm__fail(p->ctx, CBM_E_INVALID, "dynamics: the plant has no segments");
    d->ctx = p->ctx;
    d->n = n;
    d->parent = cbm__alloc(d->ctx, n * sizeof *d->parent);
    d->x = cbm__alloc(d->ctx, n * sizeof *d->x);
    d->e = cbm__alloc(d->ctx, n * sizeof *d->e);
    d->kel = cbm__alloc(d->ctx, 9 * n * sizeof(double));
    d->geo = cbm__calloc(d->ctx, 9 * n, sizeof(double));
    d->body = cbm__calloc(d->ctx, 36 * n, sizeof(double));
    d->pc = cbm__alloc(d->ctx, 10 * n * sizeof(double));
    d->ak = cbm__alloc(d->ctx, 9 * n * sizeof(double));
    d->dinv = cbm__alloc(d->ctx, 9 * n * sizeof(double));
    d->dl = cbm__alloc(d->ctx, 18 * n * sizeof(double));
    d->pi = cbm__alloc(d->ctx, 36 * n * sizeof(double));
    d->z = cbm__alloc(d->ctx, 6 * n * sizeof(double));
    d->acc = cbm__alloc(d->ctx, 6 * n * sizeof(double));
    d->u = cbm__alloc(d->ctx, 3 * n * sizeof(double));
    d->width = cbm__alloc(d->ctx, n * sizeof(double));
    d->pmass = cbm__alloc(d->ctx, n * sizeof(double));
    if (!d->width || !d->pmass || !d->parent || !d->x || !d->e || !d->kel || !d->geo || !d->body ||
        !d->pc || !d->ak || !d->dinv || !d->dl || !d->pi || !d->z || !d->acc || !d->u) {
        cbm__dyn_free(d);
        return CBM_E_NOMEM;
    }
    d->base = p->base_pos;
    bool chain = p->disc == CBM_MECH_CHAIN;
    /* load sums over each subtree for G: F_tot, sum F.p, sum p F^T */
    cbm_vec3 *ftot = (cbm_vec3 *)(void *)d->z; /* borrowed work: 6 doubles per segment */
    double *fp = d->u;                         /* 3 per segment, one used */
    double *pft = d->pi;                       /* 36 per segment, nine used */
    for (size_t i = 0; i < n; i++) {
        d->parent[i] = p->parent[i];
        double r[9];
        rotm(p->q[i], r);
        cbm_vec3 h = v3(r[0], r[3], r[6]);
        double l = p->len[i];
        d->x[i] = v3_sub(p->pos[i], d->base);
        d->e[i] = v3_madd(d->x[i], h, l);
        cbm_vec3 cj;
        double dl;
        joint_rigidity(p, i, &cj, &dl);
        rdrt(r, v3(cj.x / dl, cj.y / dl, cj.z / dl), d->kel + 9 * i);
        double m = p->mpl[i] * l, a = p->outer[i].a, b = p->outer[i].b;
        d->width[i] = a + b;
        d->pmass[i] = p->pmass[i];
        double jc[9];
        double lc = chain ? 0.0 : l * l / 12.0;
        rdrt(r, v3(m * (a * a + b * b) / 4.0, m * (lc + a * a / 4.0), m * (lc + b * b / 4.0)), jc);
        cbm_vec3 c = chain ? d->e[i] : v3_madd(d->x[i], h, 0.5 * l);
        double *pb = d->body + 36 * i;
        add_inertia(pb, m, c, jc);
        add_inertia(pb, p->pmass[i], d->e[i], NULL);
        if (!(pb[0] + pb[7] + pb[14] > 0.0) || !(pb[21] > 0.0))
            return cbm__dyn_free(d),
                   cbm__fail(p->ctx, CBM_E_INVALID,
                             "dynamics: segment %zu has no mass (density 0 and no point mass)", i);
        /* dead loads: own weight at c, point-mass weight and tip force at e */
        cbm_vec3 fw = v3_scale(p->gravity, m);
        cbm_vec3 ft = v3_add(v3_scale(p->gravity, p->pmass[i]), p->tipf[i]);
        ftot[2 * i] = v3_add(fw, ft);
        fp[3 * i] = v3_dot(fw, c) + v3_dot(ft, d->e[i]);
        double cv[3] = {c.x, c.y, c.z}, ev[3] = {d->e[i].x, d->e[i].y, d->e[i].z};
        double fwv[3] = {fw.x, fw.y, fw.z}, ftv[3] = {ft.x, ft.y, ft.z};
        for (int a2 = 0; a2 < 3; a2++)
            for (int b2 = 0; b2 < 3; b2++)
                pft[36 * i + 3 * a2 + b2] = cv[a2] * fwv[b2] + ev[a2] * ftv[b2];
    }
    for (size_t i = n; i-- > 0;) {
        cbm_vec3 f = ftot[2 * i];
        cbm_vec3 xi = d->x[i];
        double s = fp[3 * i] - v3_dot(f, xi);
        double xv[3] = {xi.x, xi.y, xi.z}, fv[3] = {f.x, f.y, f.z};
        double *g = d->geo + 9 * i;
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++)
                g[3 * a + b] = (a == b ? s : 0.0) - (pft[36 * i + 3 * a + b] - xv[a] * fv[b]);
        int64_t pa = d->parent[i];
        if (pa >= 0) {
            ftot[2 * pa] = v3_add(ftot[2 * pa], f);
            fp[3 * pa] += fp[3 * i];
            for (int k = 0; k < 9; k++)
                pft[36 * pa + k] += pft[36 * i + k];
        }
    }
    compact_blocks(d);
    d->fk = d->fm = NAN;
    return CBM_OK;
}

void cbm__dyn_apply(cbm__dyn *d, double sk, double sm, const double *v, double *y)
{
    size_t n = d->n;
    double *z = d->z, *acc = d->acc;
    for (size_t k = 0; k < n; k++) {
        int64_t pa = d->parent[k];
        double *zk = z + 6 * k;
        CBM__DYN_AHEAD(d->parent, n, k + CBM__AHEAD, z);
        if (pa >= 0)
            memcpy(zk, z + 6 * pa, 6 * sizeof(double));
        else
            memset(zk, 0, 6 * sizeof(double));
        cbm__dyn_sq(d->x + k, v + 3 * k, zk);
        memset(acc + 6 * k, 0, 6 * sizeof(double));
    }
    bool stiff = sk != 0.0;
    for (size_t k = n; k-- > 0;) {
        int64_t pa = d->parent[k];
        /* the subtree's wrench in registers (through acc only to the parent) */
        double w[6], pz[6], sw[3];
        if (k >= CBM__AHEAD)
            CBM__DYN_AHEAD(d->parent, n, k - CBM__AHEAD, acc);
        static const double none[6] = {0, 0, 0, 0, 0, 0};
        cbm__dyn_pz(d->pc + 10 * k, z + 6 * k, none, pz);
        for (int i = 0; i < 6; i++)
            w[i] = acc[6 * k + i] + sm * pz[i];
        cbm__dyn_stw(d->x + k, w, sw);
        if (stiff) {
            const double *vk = v + 3 * k, *g = d->geo + 9 * k, *ak = d->ak + 9 * k;
            const double *th = pa >= 0 ? z + 6 * pa : none;
            for (int i = 0; i < 3; i++) {
                double a = ak[3 * i] * vk[0] + ak[3 * i + 1] * vk[1] + ak[3 * i + 2] * vk[2] +
                           g[i] * th[0] + g[3 + i] * th[1] + g[6 + i] * th[2];
                y[3 * k + i] = sk * a + sw[i];
            }
            for (int i = 0; i < 3; i++)
                w[i] += sk * (g[3 * i] * vk[0] + g[3 * i + 1] * vk[1] + g[3 * i + 2] * vk[2]);
        } else
            memcpy(y + 3 * k, sw, sizeof sw);
        if (pa >= 0)
            for (int i = 0; i < 6; i++)
                acc[6 * pa + i] += w[i];
    }
}

/* inverse of a symmetric 3x3 block and whether it is positive definite (leading minors) */
static bool inv3(const double *a, double *out, bool *pd)
{
    double c0 = a[4] * a[8] - a[5] * a[7], c1 = a[5] * a[6] - a[3] * a[8],
           c2 = a[3] * a[7] - a[4] * a[6];
    double det = a[0] * c0 + a[1] * c1 + a[2] * c2;
    double scale = fabs(a[0]) + fabs(a[4]) + fabs(a[8]);
    *pd = a[0] > 0.0 && a[0] * a[4] - a[1] * a[3] > 0.0 && det > 0.0;
    if (!(fabs(det) > 1e-300) || !(fabs(det) > 1e-15 * scale * scale * scale) || !isfinite(det))
        return false;
    double id = 1.0 / det;
    out[0] = c0 * id;
    out[1] = (a[2] * a[7] - a[1] * a[8]) * id;
    out[2] = (a[1] * a[5] - a[2] * a[4]) * id;
    out[3] = c1 * id;
    out[4] = (a[0] * a[8] - a[2] * a[6]) * id;
    out[5] = (a[2] * a[3] - a[0] * a[5]) * id;
    out[6] = c2 * id;
    out[7] = (a[1] * a[6] - a[0] * a[7]) * id;
    out[8] = (a[0] * a[4] - a[1] * a[3]) * id;
    return true;
}

size_t cbm__dyn_factor(cbm__dyn *d, double sk, double sm)
{
    size_t n = d->n, nonpd = 0;
    bool singular = false;
    for (size_t k = 0; k < 36 * n; k++)
        d->pi[k] = sm * d->body[k];
    for (size_t k = n; k-- > 0;) {
        double *pk = d->pi + 36 * k;
        cbm_vec3 x = d->x[k];
        double xm[9] = {0, -x.z, x.y, x.z, 0, -x.x, -x.y, x.x, 0};
        /* PS = Pi S (6x3) = Pi[:, 0:3] + Pi[:, 3:6] [x] */
        double ps[18];
        for (int i = 0; i < 6; i++)
            for (int j = 0; j < 3; j++) {
                double a = pk[6 * i + j];
                for (int t = 0; t < 3; t++)
                    a += pk[6 * i + 3 + t] * xm[3 * t + j];
                ps[3 * i + j] = a;
            }
        const double *g = d->geo + 9 * k, *ke = d->kel + 9 * k;
        double lm[18];
        /* L = B + PS^T; B = sk [G^T 0] */
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 6; j++)
                lm[6 * i + j] = ps[3 * j + i] + (j < 3 ? sk * g[3 * j + i] : 0.0);
        /* D = A + S^T PS = A + PS[0:3] - [x] PS[3:6] */
        double dm[9];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) {
                double a =
                    sk * (ke[3 * i + j] + 0.5 * (g[3 * i + j] + g[3 * j + i])) + ps[3 * i + j];
                for (int t = 0; t < 3; t++)
                    a -= xm[3 * i + t] * ps[3 * (3 + t) + j];
                dm[3 * i + j] = a;
            }
        /* symmetric up to round-off: make it exactly so */
        for (int i = 0; i < 3; i++)
            for (int j = i + 1; j < 3; j++)
                dm[3 * i + j] = dm[3 * j + i] = 0.5 * (dm[3 * i + j] + dm[3 * j + i]);
        double *di = d->dinv + 9 * k;
        bool pd;
        if (!inv3(dm, di, &pd)) {
            singular = true;
            memset(di, 0, 9 * sizeof(double));
        }
        if (!pd)
            nonpd++;
        double *dl = d->dl + 18 * k; /* D^-1 L */
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 6; j++)
                dl[6 * i + j] =
                    di[3 * i] * lm[j] + di[3 * i + 1] * lm[6 + j] + di[3 * i + 2] * lm[12 + j];
        int64_t pa = d->parent[k];
        if (pa < 0)
            continue;
        /* Phi = Pi - L^T D^-1 L into the parent's Pi */
        double *pp = d->pi + 36 * pa;
        for (int i = 0; i < 6; i++)
            for (int j = 0; j < 6; j++)
                pp[6 * i + j] += pk[6 * i + j] -
                                 (lm[i] * dl[j] + lm[6 + i] * dl[6 + j] + lm[12 + i] * dl[12 + j]);
    }
    d->fk = sk;
    d->fm = sm;
    return singular ? (size_t)-1 : nonpd;
}

void cbm__dyn_solve(cbm__dyn *d, const double *b, double *xout)
{
    size_t n = d->n;
    double *acc = d->acc, *u = d->u, *z = d->z;
    memset(acc, 0, 6 * n * sizeof(double));
    /* from the tips: u_k = b_k - S^T sum psi_c, kept as D^-1 u_k (in u), psi into the parent */
    for (size_t k = n; k-- > 0;) {
        double sw[3], uk[3], lts[6];
        if (k >= CBM__AHEAD)
            CBM__DYN_AHEAD(d->parent, n, k - CBM__AHEAD, acc);
        const double *ak = acc + 6 * k;
        cbm__dyn_stw(d->x + k, ak, sw);
        for (int i = 0; i < 3; i++)
            uk[i] = b[3 * k + i] - sw[i];
        double *s = u + 3 * k;
        cbm__dyn_dinv_u(d->dinv + 9 * k, uk, s);
        int64_t pa = d->parent[k];
        if (pa < 0)
            continue;
        cbm__dyn_lt_s(d->dl + 18 * k, uk, lts);
        double *ap = acc + 6 * pa;
        for (int j = 0; j < 6; j++)
            ap[j] += ak[j] + lts[j];
    }
    /* from the base: v_k = D^-1 u_k - D^-1 L_k Z_parent, Z_k = Z_parent + S_k v_k */
    for (size_t k = 0; k < n; k++) {
        int64_t pa = d->parent[k];
        double *zk = z + 6 * k, q[3];
        CBM__DYN_AHEAD(d->parent, n, k + CBM__AHEAD, z);
        if (pa >= 0) {
            const double *zp = z + 6 * pa;
            cbm__dyn_back_sub(d->dl + 18 * k, u + 3 * k, zp, q);
            memcpy(zk, zp, 6 * sizeof(double));
        } else {
            memcpy(q, u + 3 * k, sizeof q);
            memset(zk, 0, 6 * sizeof(double));
        }
        cbm__dyn_sq(d->x + k, q, zk);
        memcpy(xout + 3 * k, q, sizeof q);
    }
}

void cbm__dyn_mass_solved(cbm__dyn *d, double *y)
{
    size_t n = d->n;
    double *z = d->z, *acc = d->acc;
    memset(acc, 0, 6 * n * sizeof(double));
    for (size_t k = n; k-- > 0;) {
        double w[6];
        if (k >= CBM__AHEAD)
            CBM__DYN_AHEAD(d->parent, n, k - CBM__AHEAD, acc);
        cbm__dyn_pz(d->pc + 10 * k, z + 6 * k, acc + 6 * k, w);
        cbm__dyn_stw(d->x + k, w, y + 3 * k);
        int64_t pa = d->parent[k];
        if (pa >= 0)
            for (int i = 0; i < 6; i++)
                acc[6 * pa + i] += w[i];
    }
}

void cbm__dyn_point_force(const cbm__dyn *d, size_t seg, cbm_vec3 F, double *f)
{
    cbm_vec3 e = d->e[seg];
    for (int64_t k = (int64_t)seg; k >= 0; k = d->parent[k]) {
        cbm_vec3 m = v3_cross(v3_sub(e, d->x[k]), F);
        f[3 * k] += m.x;
        f[3 * k + 1] += m.y;
        f[3 * k + 2] += m.z;
    }
}

cbm_vec3 cbm__dyn_node_disp(const cbm__dyn *d, const double *q, size_t seg)
{
    cbm_vec3 e = d->e[seg], u = v3(0, 0, 0);
    for (int64_t k = (int64_t)seg; k >= 0; k = d->parent[k]) {
        cbm_vec3 qk = v3(q[3 * k], q[3 * k + 1], q[3 * k + 2]);
        u = v3_add(u, v3_cross(qk, v3_sub(e, d->x[k])));
    }
    return u;
}

void cbm__dyn_twists(const cbm__dyn *d, const double *v, double *z)
{
    for (size_t k = 0; k < d->n; k++) {
        int64_t pa = d->parent[k];
        double *zk = z + 6 * k;
        if (pa >= 0)
            memcpy(zk, z + 6 * pa, 6 * sizeof(double));
        else
            memset(zk, 0, 6 * sizeof(double));
        cbm__dyn_sq(d->x + k, v + 3 * k, zk);
    }
}

void cbm__dyn_wrench_force(const cbm__dyn *d, double *w, double *f)
{
    for (size_t k = d->n; k-- > 0;) {
        double *wk = w + 6 * k, sw[3];
        cbm__dyn_stw(d->x + k, wk, sw);
        f[3 * k] += sw[0];
        f[3 * k + 1] += sw[1];
        f[3 * k + 2] += sw[2];
        int64_t pa = d->parent[k];
        if (pa >= 0)
            for (int i = 0; i < 6; i++)
                w[6 * pa + i] += wk[i];
    }
}
