/* Gürtler's incremental FE branch as his listing computes it (§3.2, getRotationAnglesFE; digest
 * 001 §2.2.3-2.2.6): the thesis-compatible path beside the corrected FEM of plants (fem.c).
 *
 * The chain: element i runs from node i to node i+1; its state is one angle beta_i from the
 * upward vertical, in the plane x (up) - z (the listing's internal frame: the element's axis is
 * (cos beta, 0, sin beta), R = [[c 0 s][0 1 0][-s 0 c]] takes world to local). Every element has
 * a core of r_end and one ring of dr = (r_start - r_end) / (n_FE - 1) per later step. A step adds
 * an element, rings the older ones, assembles K (every ring, G = E/3) and the load of the newest
 * rings (weight 2.76, maturation 2.78-2.82, the extra load's share), solves K dq = dF and adds
 * update_sign * theta_y of each element's first node to its angle.
 *
 * The solve is dense, as the listing's: the free-free system through the pseudo-inverse of a
 * one-sided Jacobi SVD (our own: Commons Math's SVD is not at hand in C, and the one-sided Jacobi
 * method is accurate for the small singular values whose cut decides the answer), or the clamped
 * system by Gaussian elimination with partial pivoting (the printed K is not symmetric, so no
 * Cholesky). O((6 n)^3) per step as in the thesis; the plants' FEM is the fast one. */
#include "cambium/fem_thesis.h"
#include "core/core.h"
#include "mech/fem_internal.h"
#include "core/vecmath.h"

#include <float.h>
#include <math.h>
#include <string.h>

#define PI  3.14159265358979323846
#define RAD (180.0 / PI)

const char *cbm_fem_support_name(cbm_fem_support s)
{
    switch (s) {
    case CBM_FEM_SUPPORT_FREE:
        return "free";
    case CBM_FEM_SUPPORT_CLAMPED:
        return "clamped";
    }
    return NULL;
}

bool cbm_fem_support_parse(const char *name, cbm_fem_support *out)
{
    if (!name || !out)
        return false;
    if (strcmp(name, "free") == 0)
        *out = CBM_FEM_SUPPORT_FREE;
    else if (strcmp(name, "clamped") == 0)
        *out = CBM_FEM_SUPPORT_CLAMPED;
    else
        return false;
    return true;
}

cbm_fem_thesis_def cbm_fem_thesis_def_default(void)
{
    cbm_fem_thesis_def d;
    memset(&d, 0, sizeof d);
    d.n_fe = 10;
    d.t0 = 60.0;
    d.rho = 2.0;
    d.youngs_modulus = 800.0;
    d.grav = 9.81;
    d.le = 0.1;
    d.r_start = d.r_end = 0.05;
    d.phi = 60.0;
    d.a = -200.0;
    d.b = 2000.0;
    d.support = CBM_FEM_SUPPORT_FREE;
    d.printed_stiffness = true;
    d.update_sign = 1;
    d.axial = CBM_FEM_AXIAL_LISTING;
    d.shear_ratio = 1.0 / 3.0;
    return d;
}

static cbm_status check(cbm_context *ctx, const cbm_fem_thesis_def *d)
{
#define BAD(msg) return cbm__fail(ctx, CBM_E_INVALID, "fem_thesis: " msg)
    if (d->n_fe < 2 || d->n_fe > 1000)
        BAD("n_fe must be in 2..1000");
    if (!(d->t0 >= 0.0 && d->t0 <= 180.0))
        BAD("t0 must be in [0, 180] degrees");
    if (!(isfinite(d->rho) && d->rho >= 0.0))
        BAD("rho must be >= 0");
    if (!(isfinite(d->youngs_modulus) && d->youngs_modulus > 0.0))
        BAD("youngs_modulus must be positive");
    if (!(isfinite(d->grav) && d->grav >= 0.0))
        BAD("grav must be >= 0");
    if (!(isfinite(d->le) && d->le > 0.0))
        BAD("le must be positive");
    if (!(isfinite(d->r_end) && d->r_end > 0.0))
        BAD("r_end must be positive");
    if (!(isfinite(d->r_start) && d->r_start >= d->r_end))
        BAD("r_start must be >= r_end");
    if (!(isfinite(d->sigma) && d->sigma >= 0.0))
        BAD("sigma must be >= 0");
    if (!isfinite(d->phi) || !isfinite(d->a) || !isfinite(d->b))
        BAD("phi, a and b must be finite");
    if (d->support != CBM_FEM_SUPPORT_FREE && d->support != CBM_FEM_SUPPORT_CLAMPED)
        BAD("unknown support");
    if (d->update_sign != 1 && d->update_sign != -1)
        BAD("update_sign must be +1 or -1");
    if (d->axial != CBM_FEM_AXIAL_FORMULA && d->axial != CBM_FEM_AXIAL_LISTING)
        BAD("unknown axial variant");
    if (!(isfinite(d->shear_ratio) && d->shear_ratio > 0.0))
        BAD("shear_ratio must be positive");
    if (d->extra_loads)
        for (long i = 0; i < d->n_fe; i++)
            if (!(isfinite(d->extra_loads[i]) && d->extra_loads[i] >= 0.0))
                return cbm__fail(ctx, CBM_E_INVALID,
                                 "fem_thesis: extra_loads[%ld] must be finite and >= 0", i);
#undef BAD
    return CBM_OK;
}

/* ---- one element ---- */

/* g = R^T l per 3-block (local to world), R = [[c 0 s][0 1 0][-s 0 c]]. */
static void to_world(double c, double s, const double *l, double *g, int blocks)
{
    for (int b = 0; b < blocks; b++) {
        const double *x = l + 3 * b;
        double *y = g + 3 * b;
        y[0] = c * x[0] - s * x[2];
        y[1] = x[1];
        y[2] = s * x[0] + c * x[2];
    }
}

/* Scatters element e's world stiffness Q^T k Q and load Q^T f into the global K (n x n, row
 * major) and F at DOF 6e. */
static void scatter(double *kk, double *ff, size_t n, size_t e, double beta, const double k[144],
                    const double f[12])
{
    double c = cos(beta), s = sin(beta);
    double t[144], g[12];
    /* t = k R (each 3x3 block times R: columns mix) then rows by R^T */
    for (int i = 0; i < 12; i++)
        for (int bj = 0; bj < 4; bj++) {
            const double *r = k + 12 * i + 3 * bj;
            double *o = t + 12 * i + 3 * bj;
            /* (row of k) R: o_j = sum_a r_a R[a][j] */
            o[0] = c * r[0] - s * r[2];
            o[1] = r[1];
            o[2] = s * r[0] + c * r[2];
        }
    for (int j = 0; j < 12; j++)
        for (int bi = 0; bi < 4; bi++) {
            double x0 = t[12 * (3 * bi) + j], x1 = t[12 * (3 * bi + 1) + j],
                   x2 = t[12 * (3 * bi + 2) + j];
            kk[(6 * e + 3 * bi) * n + 6 * e + j] += c * x0 - s * x2;
            kk[(6 * e + 3 * bi + 1) * n + 6 * e + j] += x1;
            kk[(6 * e + 3 * bi + 2) * n + 6 * e + j] += s * x0 + c * x2;
        }
    to_world(c, s, f, g, 4);
    for (int i = 0; i < 12; i++)
        ff[6 * e + i] += g[i];
}

/* The local 12x12 of eq. 2.71 (digest §2.2.2's table) from the section's ES, EI, GJ. */
static void local_stiffness(double len, double es, double ei, double gj, bool printed, double *k)
{
    double a = es / len, b = 12 * ei / (len * len * len), c = 6 * ei / (len * len);
    double d = b, e = c, f = gj / len, g = 2 * ei / len, h = g, i4 = 4 * ei / len, j = i4;
    memset(k, 0, 144 * sizeof *k);
#define K(r, col, v) k[12 * (r) + (col)] = (v)
    K(0, 0, a), K(0, 6, -a);
    K(1, 1, b), K(1, 5, c), K(1, 7, -b), K(1, 11, c);
    K(2, 2, d), K(2, 4, -e), K(2, 8, -d), K(2, 10, -e);
    K(3, 3, f), K(3, 9, -f);
    K(4, 2, -e), K(4, 4, j), K(4, 8, printed ? 0.0 : e), K(4, 10, h);
    K(5, 1, c), K(5, 5, i4), K(5, 7, -c), K(5, 11, g);
    K(6, 0, -a), K(6, 6, a);
    K(7, 1, -b), K(7, 5, -c), K(7, 7, b), K(7, 11, -c);
    K(8, 2, -d), K(8, 4, e), K(8, 8, d), K(8, 10, e);
    K(9, 3, -f), K(9, 9, f);
    K(10, 2, -e), K(10, 4, h), K(10, 8, e), K(10, 10, j);
    K(11, 1, c), K(11, 5, g), K(11, 7, -c), K(11, 11, i4);
#undef K
}

/* The consistent load pattern of a uniform line load (2.76) with fac = -(weight)/12 per element
 * and the up vector Z in local axes. */
static void weight_pattern(double fac, double len, const double z[3], double *v)
{
    for (int k = 0; k < 3; k++) {
        v[k] += 6 * fac * z[k];
        v[6 + k] += 6 * fac * z[k];
    }
    v[4] += -fac * len * z[2];
    v[5] += fac * len * z[1];
    v[10] += fac * len * z[2];
    v[11] += -fac * len * z[1];
}

void cbm__fem_thesis_system(const cbm_fem_thesis_def *d, size_t m, const double *beta,
                            const double *rad, const double *s2, const double *s4, double *kk,
                            double *ff)
{
    size_t n = 6 * (m + 1);
    memset(kk, 0, n * n * sizeof *kk);
    memset(ff, 0, n * sizeof *ff);
    double e = d->youngs_modulus, len = d->le;
    for (size_t i = 0; i < m; i++) {
        size_t nr = m - i; /* rings of element i: its core and one per later step */
        double es = PI * e * s2[nr], ei = 0.25 * PI * e * s4[nr];
        double gj = 0.5 * PI * d->shear_ratio * e * s4[nr];
        double k[144], f[12] = {0};
        local_stiffness(len, es, ei, gj, d->printed_stiffness, k);
        double re = rad[nr], ri = rad[nr - 1];
        double z[3] = {cos(beta[i]), 0.0, -sin(beta[i])};
        /* self-weight of the newest ring */
        weight_pattern(-d->rho * d->grav * len * PI * (re * re - ri * ri) / 12.0, len, z, f);
        /* the extra mass's share of this step (D1: 1/n_FE of it per step the element exists) */
        if (d->extra_loads)
            weight_pattern(-d->grav * d->extra_loads[i] / (12.0 * (double)d->n_fe), len, z, f);
        /* maturation strain of the newest ring (2.78-2.82; the listing's psi) */
        if (d->sigma != 0.0 || d->axial == CBM_FEM_AXIAL_FORMULA) {
            double da = PI * e * (re * re - ri * ri), dr3 = re * re * re - ri * ri * ri;
            double dd = d->phi / RAD - beta[i], psi = d->b < 0.0 ? dd : dd + PI;
            double sg = d->sigma, a = d->a, b = d->b;
            double ne = d->axial == CBM_FEM_AXIAL_LISTING ? da * sg * (a + 0.5 * (b - a))
                                                          : da * (a + 0.5 * sg * (b - a));
            double my = -PI * e * sg * (b - a) * dr3 * cos(psi) / 6.0;
            double mz = PI * e * sg * (b - a) * dr3 * sin(psi) / 6.0;
            f[0] += -ne, f[4] += -my, f[5] += -mz;
            f[6] += ne, f[10] += my, f[11] += mz;
        }
        scatter(kk, ff, n, i, beta[i], k, f);
    }
}

/* ---- dense solves ---- */

/* One-sided Jacobi on the columns of the n x n A (row-major): on return u holds the columns of
 * A V = U Sigma (column-major; their norms are the singular values) and v the columns of V. */
static long jacobi_svd(size_t n, const double *a, double *u, double *v)
{
    for (size_t j = 0; j < n; j++)
        for (size_t i = 0; i < n; i++) {
            u[j * n + i] = a[i * n + j];
            v[j * n + i] = i == j ? 1.0 : 0.0;
        }
    long sweeps = 0;
    const double tol = (double)n * DBL_EPSILON;
    for (bool rotated = true; rotated && sweeps < 100; sweeps++) {
        rotated = false;
        for (size_t p = 0; p + 1 < n; p++)
            for (size_t q = p + 1; q < n; q++) {
                double *up = u + p * n, *uq = u + q * n;
                double al = 0, be = 0, ga = 0;
                for (size_t i = 0; i < n; i++) {
                    al += up[i] * up[i];
                    be += uq[i] * uq[i];
                    ga += up[i] * uq[i];
                }
                if (ga == 0.0 || !(fabs(ga) > tol * sqrt(al * be)))
                    continue;
                rotated = true;
                double zeta = (be - al) / (2.0 * ga);
                double t = (zeta >= 0 ? 1.0 : -1.0) / (fabs(zeta) + sqrt(1.0 + zeta * zeta));
                double c = 1.0 / sqrt(1.0 + t * t), s = c * t;
                double *vp = v + p * n, *vq = v + q * n;
                for (size_t i = 0; i < n; i++) {
                    double x1 = up[i], x2 = uq[i];
                    up[i] = c * x1 - s * x2;
                    uq[i] = s * x1 + c * x2;
                    x1 = vp[i], x2 = vq[i];
                    vp[i] = c * x1 - s * x2;
                    vq[i] = s * x1 + c * x2;
                }
            }
    }
    return sweeps;
}

static double col_norm(size_t n, const double *c)
{
    double s = 0;
    for (size_t i = 0; i < n; i++)
        s += c[i] * c[i];
    return sqrt(s);
}

/* x += V Sigma^+ U^T b over the singular values above the cut (u, v from jacobi_svd). */
static void pinv_apply(size_t n, const double *u, const double *v, const double *b, double cut,
                       double *x, long *dropped, double *kept_min)
{
    for (size_t j = 0; j < n; j++) {
        const double *uj = u + j * n, *vj = v + j * n;
        double s2 = 0, ub = 0;
        for (size_t i = 0; i < n; i++) {
            s2 += uj[i] * uj[i];
            ub += uj[i] * b[i];
        }
        double sv = sqrt(s2);
        if (!(sv > cut)) {
            (*dropped)++;
            continue;
        }
        *kept_min = fmin(*kept_min, sv);
        double w = ub / s2; /* (u_j . b) / sigma_j with u_j = U_j / sigma_j, times v_j */
        for (size_t i = 0; i < n; i++)
            x[i] += w * vj[i];
    }
}

/* Commons Math's cut (SingularValueDecomposition: tol = max(m sigma_max EPS, sqrt(SAFE_MIN)),
 * EPS = 2^-52, m the row count). */
static double commons_cut(size_t m, double smax)
{
    return fmax((double)m * smax * 0x1.0p-52, sqrt(DBL_MIN));
}

cbm_status cbm__fem_pinv_solve(cbm_context *ctx, size_t n, const double *a, const double *b,
                               double *x, cbm__fem_pinv_info *info)
{
    size_t bytes = 2 * n * n * sizeof(double);
    double *u = cbm__alloc(ctx, bytes);
    if (!u)
        return CBM_E_NOMEM;
    double *v = u + n * n;
    long sweeps = jacobi_svd(n, a, u, v);
    double smax = 0.0;
    for (size_t j = 0; j < n; j++)
        smax = fmax(smax, col_norm(n, u + j * n));
    long dropped = 0;
    double kept_min = INFINITY;
    memset(x, 0, n * sizeof *x);
    pinv_apply(n, u, v, b, commons_cut(n, smax), x, &dropped, &kept_min);
    cbm__free(ctx, u, bytes);
    if (info) {
        info->dropped = dropped;
        info->sweeps = sweeps;
        info->smallest_kept = smax > 0.0 ? kept_min / smax : 0.0;
    }
    return CBM_OK;
}

cbm_status cbm__fem_pinv_solve_planar(cbm_context *ctx, size_t n, const double *a, const double *b,
                                      double *x, cbm__fem_pinv_info *info)
{
    /* the chain lies in the x-z plane: DOF (ux, uz, theta_y) of every node never couple with
     * (uy, theta_x, theta_z) (the element's in-plane set {u, w, theta_y} is closed, also in the
     * printed matrix, and the rotation about y keeps each set). Permuted, K is block-diagonal;
     * the SVD of each half costs an eighth, and the singular values are the union. */
    size_t h = n / 2, bytes = (5 * h * h + 2 * h) * sizeof(double);
    double *w = cbm__alloc(ctx, bytes);
    if (!w)
        return CBM_E_NOMEM;
    /* blk the half being decomposed; (u0, v0) and (u1, v1) the two halves' factors; bb, xx */
    double *blk = w, *u0 = blk + h * h, *v0 = u0 + h * h, *u1 = v0 + h * h, *v1 = u1 + h * h;
    double *bb = v1 + h * h, *xx = bb + h;
    double smax = 0.0;
    long dropped = 0, sweeps = 0;
    double kept_min = INFINITY;
    static const int set[2][3] = {{0, 2, 4}, {1, 3, 5}};
    memset(x, 0, n * sizeof *x);
    for (int half = 0; half < 2; half++) {
        for (size_t i = 0; i < h; i++)
            for (size_t j = 0; j < h; j++)
                blk[i * h + j] = a[(6 * (i / 3) + (size_t)set[half][i % 3]) * n + 6 * (j / 3) +
                                   (size_t)set[half][j % 3]];
        double *uh = half == 0 ? u0 : u1, *vh = half == 0 ? v0 : v1;
        sweeps += jacobi_svd(h, blk, uh, vh);
        for (size_t j = 0; j < h; j++)
            smax = fmax(smax, col_norm(h, uh + j * h));
    }
    double cut = commons_cut(n, smax); /* of the whole matrix, as one SVD would have it */
    for (int half = 0; half < 2; half++) {
        const double *uh = half == 0 ? u0 : u1, *vh = half == 0 ? v0 : v1;
        for (size_t i = 0; i < h; i++) {
            bb[i] = b[6 * (i / 3) + (size_t)set[half][i % 3]];
            xx[i] = 0.0;
        }
        pinv_apply(h, uh, vh, bb, cut, xx, &dropped, &kept_min);
        for (size_t i = 0; i < h; i++)
            x[6 * (i / 3) + (size_t)set[half][i % 3]] = xx[i];
    }
    cbm__free(ctx, w, bytes);
    if (info) {
        info->dropped = dropped;
        info->sweeps = sweeps;
        info->smallest_kept = smax > 0.0 ? kept_min / smax : 0.0;
    }
    return CBM_OK;
}

cbm_status cbm__fem_clamped_solve(cbm_context *ctx, size_t n, const double *a, const double *b,
                                  double *x)
{
    /* the DOF of node 0 are fixed: eliminate on the rest, rows and columns 6.. */
    size_t r = n - 6, bytes = (r * r + r) * sizeof(double);
    double *m = cbm__alloc(ctx, bytes);
    if (!m)
        return CBM_E_NOMEM;
    double *y = m + r * r;
    for (size_t i = 0; i < r; i++) {
        memcpy(m + i * r, a + (i + 6) * n + 6, r * sizeof *m);
        y[i] = b[i + 6];
    }
    cbm_status st = CBM_OK;
    for (size_t c = 0; c < r && st == CBM_OK; c++) {
        size_t piv = c;
        for (size_t i = c + 1; i < r; i++)
            if (fabs(m[i * r + c]) > fabs(m[piv * r + c]))
                piv = i;
        if (!(fabs(m[piv * r + c]) > 0.0)) {
            st = cbm__fail(ctx, CBM_E_NONFINITE, "fem_thesis: the clamped stiffness is singular");
            break;
        }
        if (piv != c) {
            for (size_t k = 0; k < r; k++) {
                double t = m[c * r + k];
                m[c * r + k] = m[piv * r + k];
                m[piv * r + k] = t;
            }
            double t = y[c];
            y[c] = y[piv];
            y[piv] = t;
        }
        for (size_t i = c + 1; i < r; i++) {
            double l = m[i * r + c] / m[c * r + c];
            if (l == 0.0)
                continue;
            for (size_t k = c; k < r; k++)
                m[i * r + k] -= l * m[c * r + k];
            y[i] -= l * y[c];
        }
    }
    if (st == CBM_OK) {
        for (size_t i = r; i-- > 0;) {
            double t = y[i];
            for (size_t k = i + 1; k < r; k++)
                t -= m[i * r + k] * x[k + 6];
            x[i + 6] = t / m[i * r + i];
        }
        for (size_t i = 0; i < 6; i++)
            x[i] = 0.0;
    }
    cbm__free(ctx, m, bytes);
    return st;
}

/* ---- the run ---- */

cbm_status cbm_fem_thesis_angles(cbm_context *ctx, const cbm_fem_thesis_def *def, double *beta,
                                 size_t n_beta, cbm_fem_thesis_info *info)
{
    if (info)
        memset(info, 0, sizeof *info);
    if (!def || !beta)
        return CBM_E_INVALID;
    CBM_TRY(check(ctx, def));
    size_t nfe = (size_t)def->n_fe;
    if (n_beta < nfe)
        return cbm__fail(ctx, CBM_E_INVALID, "fem_thesis: beta has %zu entries, n_fe is %zu",
                         n_beta, nfe);
    size_t nmax = 6 * (nfe + 1);
    /* rad[k]: outer radius of ring k-1 (the listing's radii[], built by repeated addition);
     * s2, s4: running sums of r^2 and r^4 differences over rings 0..k-1 (its tmp1, tmp2) */
    size_t bytes = (3 * (nfe + 2) + nmax * nmax + 3 * nmax + nfe) * sizeof(double);
    double *buf = cbm__alloc(ctx, bytes);
    if (!buf)
        return CBM_E_NOMEM;
    double *rad = buf, *s2 = rad + nfe + 2, *s4 = s2 + nfe + 2, *kk = s4 + nfe + 2;
    double *ff = kk + nmax * nmax, *x = ff + nmax, *res = x + nmax, *ang = res + nmax;
    double dr = (def->r_start - def->r_end) / (double)(nfe - 1);
    rad[0] = 0.0;
    rad[1] = def->r_end;
    for (size_t k = 2; k <= nfe + 1; k++)
        rad[k] = rad[k - 1] + dr;
    s2[0] = s4[0] = 0.0;
    for (size_t k = 1; k <= nfe + 1; k++) {
        double a2 = rad[k] * rad[k], b2 = rad[k - 1] * rad[k - 1];
        s2[k] = s2[k - 1] + (a2 - b2);
        s4[k] = s4[k - 1] + (a2 * a2 - b2 * b2);
    }
    cbm_status st = CBM_OK;
    double t0 = def->t0 / RAD;
    cbm__fem_pinv_info pi = {0};
    double resid = 0.0;
    for (size_t m = 1; m <= nfe && st == CBM_OK; m++) {
        /* primary growth: element m-1 at t0 or the tip's angle; the older ones got a ring */
        ang[m - 1] = (m == 1 || def->primary_tropism) ? t0 : ang[m - 2];
        size_t n = 6 * (m + 1);
        cbm__fem_thesis_system(def, m, ang, rad, s2, s4, kk, ff);
        if (def->support == CBM_FEM_SUPPORT_FREE)
            st = cbm__fem_pinv_solve_planar(ctx, n, kk, ff, x, &pi);
        else
            st = cbm__fem_clamped_solve(ctx, n, kk, ff, x);
        if (st != CBM_OK)
            break;
        double r2 = 0, f2 = 0;
        for (size_t i = 0; i < n; i++) {
            double t = -ff[i];
            for (size_t k = 0; k < n; k++)
                t += kk[i * n + k] * x[k];
            /* the clamp's reactions are not a residual */
            if (def->support == CBM_FEM_SUPPORT_FREE || i >= 6) {
                r2 += t * t;
                f2 += ff[i] * ff[i];
            }
        }
        resid = f2 > 0.0 ? sqrt(r2 / f2) : sqrt(r2);
        for (size_t i = 0; i < m; i++) {
            ang[i] += (double)def->update_sign * x[6 * i + 4];
            if (!isfinite(ang[i])) {
                st = cbm__fail(ctx, CBM_E_NONFINITE,
                               "fem_thesis: step %zu: element %zu's angle is not finite", m, i);
                break;
            }
        }
    }
    if (st == CBM_OK) {
        for (size_t i = 0; i < nfe; i++)
            beta[i] = ang[i] * RAD;
        if (info) {
            info->tip_angle = beta[nfe - 1];
            info->residual = resid;
            if (def->support == CBM_FEM_SUPPORT_FREE) {
                info->rank_deficiency = pi.dropped;
                info->smallest_kept = pi.smallest_kept;
                info->sweeps = pi.sweeps;
            }
        }
    }
    cbm__free(ctx, buf, bytes);
    return st;
}

/* ---- the output step: Akima's interpolation and the thesis's resampling ---- */

/* Slope at x1 (the middle point, at = 1) or x0 (at = 0) / x2 (at = 2) of the parabola through
 * three points (Lagrange form differentiated). */
static double parabola_slope(const double *x, const double *y, int at)
{
    double t = x[at];
    return y[0] * (2 * t - x[1] - x[2]) / ((x[0] - x[1]) * (x[0] - x[2])) +
           y[1] * (2 * t - x[0] - x[2]) / ((x[1] - x[0]) * (x[1] - x[2])) +
           y[2] * (2 * t - x[0] - x[1]) / ((x[2] - x[0]) * (x[2] - x[1]));
}

cbm_status cbm_akima(cbm_context *ctx, const double *x, const double *y, size_t n, const double *xq,
                     double *yq, size_t m)
{
    if (!x || !y || (m && (!xq || !yq)))
        return CBM_E_INVALID;
    if (n < 5)
        return cbm__fail(ctx, CBM_E_INVALID, "akima: %zu points, at least 5 needed", n);
    for (size_t i = 0; i < n; i++)
        if (!isfinite(x[i]) || !isfinite(y[i]) || (i > 0 && !(x[i] > x[i - 1])))
            return cbm__fail(ctx, CBM_E_INVALID,
                             "akima: point %zu: abscissae must be finite and strictly increasing, "
                             "ordinates finite",
                             i);
    for (size_t j = 0; j < m; j++)
        if (!isfinite(xq[j]))
            return cbm__fail(ctx, CBM_E_INVALID, "akima: query %zu is not finite", j);
    /* d[i]: chord slopes (n - 1); s[i]: the slopes at the points (n) */
    size_t bytes = (2 * n - 1) * sizeof(double);
    double *d = cbm__alloc(ctx, bytes);
    if (!d)
        return CBM_E_NOMEM;
    double *s = d + (n - 1);
    for (size_t i = 0; i + 1 < n; i++)
        d[i] = (y[i + 1] - y[i]) / (x[i + 1] - x[i]);
    for (size_t i = 2; i + 2 < n; i++) {
        double wp = fabs(d[i + 1] - d[i]), wm = fabs(d[i - 1] - d[i - 2]);
        if (wp == 0.0 && wm == 0.0)
            s[i] =
                ((x[i + 1] - x[i]) * d[i - 1] + (x[i] - x[i - 1]) * d[i]) / (x[i + 1] - x[i - 1]);
        else
            s[i] = (wp * d[i - 1] + wm * d[i]) / (wp + wm);
    }
    s[0] = parabola_slope(x, y, 0);
    s[1] = parabola_slope(x, y, 1);
    s[n - 2] = parabola_slope(x + n - 3, y + n - 3, 1);
    s[n - 1] = parabola_slope(x + n - 3, y + n - 3, 2);
    for (size_t j = 0; j < m; j++) {
        /* the interval [x[k], x[k+1]] holding xq (the end ones continued outside) */
        size_t lo = 0, hi = n - 2;
        while (lo < hi) {
            size_t mid = (lo + hi + 1) / 2;
            if (x[mid] <= xq[j])
                lo = mid;
            else
                hi = mid - 1;
        }
        double h = x[lo + 1] - x[lo], t = xq[j] - x[lo];
        double c2 = (3.0 * d[lo] - 2.0 * s[lo] - s[lo + 1]) / h;
        double c3 = (s[lo] + s[lo + 1] - 2.0 * d[lo]) / (h * h);
        yq[j] = y[lo] + t * (s[lo] + t * (c2 + t * c3));
    }
    cbm__free(ctx, d, bytes);
    return CBM_OK;
}

cbm_status cbm_fem_thesis_resample(cbm_context *ctx, const double *beta, size_t n_fe, double *out,
                                   size_t n_gu)
{
    if (!beta || !out)
        return CBM_E_INVALID;
    if (n_fe < 5 || n_gu < n_fe)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "fem_thesis: resampling needs n_fe >= 5 (Akima) and n_gu >= n_fe; got "
                         "n_fe %zu, n_gu %zu",
                         n_fe, n_gu);
    size_t bytes = (n_fe + n_gu) * sizeof(double);
    double *xs = cbm__alloc(ctx, bytes);
    if (!xs)
        return CBM_E_NOMEM;
    double *xq = xs + n_fe;
    for (size_t i = 0; i < n_fe; i++)
        xs[i] = (double)i / (double)(n_fe - 1);
    for (size_t j = 0; j < n_gu; j++)
        xq[j] = (double)j / (double)(n_gu - 1);
    cbm_status st = cbm_akima(ctx, xs, beta, n_fe, xq, out, n_gu);
    cbm__free(ctx, xs, bytes);
    return st;
}

/* ---- the rod of `bend` posed at the resampled angles ---- */

cbm_status cbm__fem_thesis_pose(cbm_plant *p, const double *beta, size_t n, double *residual)
{
    if (!p || !beta || n != p->n)
        return CBM_E_INVALID;
    CBM_TRY(cbm__mech_work_reserve(p, 0));
    p->load_scale = 1.0;
    cbm__mech_prepare(p);
    const double *dual = p->work.dual;
    /* beta: degrees from the upward vertical in the clamp's plane; the clamp is at elevation
     * e0 = 90 - beta_0 of the thesis's t0, and turning up by d is a turn by -d about L */
    cbm_quat prev = p->base_q;
    cbm_vec3 hb = q_rotate(p->base_q, v3(1, 0, 0));
    double e0 = atan2(hb.y, sqrt(hb.x * hb.x + hb.z * hb.z));
    for (size_t i = 0; i < n; i++) {
        if (p->parent[i] != (int64_t)i - 1 || p->branch[i].w != 1.0)
            return cbm__fail(p->ctx, CBM_E_INVALID,
                             "fem_thesis: the rod must be one straight chain");
        double d = (90.0 - beta[i]) / RAD - e0;
        cbm_quat q = q_normalize(q_mul(p->base_q, q_from_rotvec(v3(0, -d, 0))));
        p->omega[i] = v3_scale(cbm__fem_q_log(q_mul(q_conj(prev), q)), 1.0 / dual[i]);
        prev = q;
    }
    CBM_TRY(cbm_plant_evaluate(p, NULL));
    /* the posed shape memorised: the rest rates that make it an equilibrium of its loads, as a
     * grown branch's rings remember their history. Joint i must rest at rj = Omega - M/C (its
     * moment in its frame, its rigidity); a staggered joint's rest is the length-weighted mean
     * of its two segments' (cbm__mech_prepare), solved for segment by segment from the base. */
    bool stag = cbm_plant_discretization(p) == CBM_MECH_STAGGERED;
    cbm_vec3 rprev = v3(0, 0, 0);
    for (size_t i = 0; i < n; i++) {
        cbm_vec3 m = p->moment[i], c = p->work.cj[i], o = p->omega[i];
        cbm_vec3 h = q_rotate(p->q[i], v3(1, 0, 0)), l = q_rotate(p->q[i], v3(0, 1, 0)),
                 u = q_rotate(p->q[i], v3(0, 0, 1));
        cbm_vec3 rj =
            v3(o.x - v3_dot(m, h) / c.x, o.y - v3_dot(m, l) / c.y, o.z - v3_dot(m, u) / c.z);
        cbm_vec3 ri = rj;
        if (stag && i > 0 && (p->cont[i] & 1)) {
            double lp = p->len[i - 1], li = p->len[i];
            ri = v3_scale(v3_sub(v3_scale(rj, dual[i]), v3_scale(rprev, 0.5 * lp)), 2.0 / li);
        }
        if (cbm_plant_ring_count(p, i) != 1)
            return cbm__fail(p->ctx, CBM_E_INVALID, "fem_thesis: segment %zu has several rings", i);
        cbm_ring g;
        CBM_TRY(cbm_plant_get_ring(p, i, 0, &g));
        g.rest_rate = ri;
        CBM_TRY(cbm_plant_set_ring(p, i, 0, &g));
        rprev = ri;
    }
    return cbm_plant_evaluate(p, residual);
}
