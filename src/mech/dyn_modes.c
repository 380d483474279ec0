/* Natural frequencies and mode shapes: the lowest eigenpairs of K phi = lambda M phi by
 * shift-invert Lanczos in the M inner product.
 *
 * Why Lanczos with our own tree factorisation rather than ARPACK: the operator (K - sigma M)^-1 M
 * is applied in O(n) by the tree elimination of tree.c (one backward and one forward sweep per
 * solve, one each way per product with M), so a plain Lanczos run with full reorthogonalisation
 * needs nothing else; for the few tens of modes anyone asks for the Krylov basis stays small
 * (m = 3 count + 30, doubled if the Ritz values have not converged), and the library keeps no
 * Fortran dependency (ARPACK would add one to every build for a dozen lines of iteration here).
 *
 * The shift is 0: the factorisation of K then also decides the stability of the equilibrium
 * (positive pivots iff K is positive definite), and for a stable plant the largest Ritz values
 * theta of K^-1 M are the lowest lambda = 1 / theta. The small tridiagonal matrix is
 * diagonalised by cyclic Jacobi rotations (m is at most a few hundred).
 */
#include "mech/dyn_internal.h"

#include <math.h>
#include <string.h>

/* eigenvalues (w) and eigenvectors (columns of v, row-major m x m) of the symmetric a (destroyed)
 */
static void jacobi(double *a, size_t m, double *w, double *v)
{
    for (size_t i = 0; i < m; i++)
        for (size_t j = 0; j < m; j++)
            v[i * m + j] = i == j ? 1.0 : 0.0;
    for (int sweep = 0; sweep < 100; sweep++) {
        double off = 0.0, dia = 0.0;
        for (size_t i = 0; i < m; i++) {
            dia += a[i * m + i] * a[i * m + i];
            for (size_t j = i + 1; j < m; j++)
                off += a[i * m + j] * a[i * m + j];
        }
        if (off <= 1e-30 * dia || off == 0.0)
            break;
        for (size_t p = 0; p < m; p++)
            for (size_t q = p + 1; q < m; q++) {
                double apq = a[p * m + q];
                if (apq == 0.0)
                    continue;
                double theta = (a[q * m + q] - a[p * m + p]) / (2.0 * apq);
                double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (size_t k = 0; k < m; k++) {
                    double akp = a[k * m + p], akq = a[k * m + q];
                    a[k * m + p] = c * akp - s * akq;
                    a[k * m + q] = s * akp + c * akq;
                }
                for (size_t k = 0; k < m; k++) {
                    double apk = a[p * m + k], aqk = a[q * m + k];
                    a[p * m + k] = c * apk - s * aqk;
                    a[q * m + k] = s * apk + c * aqk;
                }
                for (size_t k = 0; k < m; k++) {
                    double vkp = v[k * m + p], vkq = v[k * m + q];
                    v[k * m + p] = c * vkp - s * vkq;
                    v[k * m + q] = s * vkp + c * vkq;
                }
            }
    }
    for (size_t i = 0; i < m; i++)
        w[i] = a[i * m + i];
}

static double dot(const double *a, const double *b, size_t n)
{
    double s = 0.0;
    for (size_t i = 0; i < n; i++)
        s += a[i] * b[i];
    return s;
}

/* w -= the M-projection of w on v[0..cols), twice (classical Gram-Schmidt); mw = M w after. When
 * diag is not NULL it receives the coefficient of column cols - 1 summed over both passes. */
static void m_orthogonalise(cbm__dyn *d, const double *v, size_t cols, double *w, double *mw,
                            double *diag)
{
    size_t N = 3 * d->n;
    for (int pass = 0; pass < 2; pass++) {
        cbm__dyn_apply(d, 0.0, 1.0, w, mw);
        for (size_t i = 0; i < cols; i++) {
            double c = dot(v + i * N, mw, N);
            if (diag && i + 1 == cols)
                *diag = pass == 0 ? c : *diag + c;
            for (size_t k = 0; k < N; k++)
                w[k] -= c * v[i * N + k];
        }
    }
    cbm__dyn_apply(d, 0.0, 1.0, w, mw);
}

/* a reproducible start vector with every component in [0.5, 1.5) (xorshift state s) */
static void start_vector(uint64_t *s, double *w, size_t N)
{
    for (size_t i = 0; i < N; i++) {
        *s ^= *s << 13;
        *s ^= *s >> 7;
        *s ^= *s << 17;
        w[i] = 0.5 + (double)(*s >> 11) * 0x1.0p-53;
    }
}

/* One Lanczos run of at most mmax steps; returns the steps done (the basis in v, the tridiagonal
 * in al, be). When the Krylov space closes (an invariant subspace: it happens with exactly
 * repeated frequencies, or when the run reaches all N degrees of freedom) the run restarts from a
 * new start vector M-orthogonal to the basis, with be = 0 at the seam, so T stays tridiagonal and
 * its eigenvalues those of the whole space spanned; it stops when no new direction is left. */
static size_t lanczos(cbm__dyn *d, size_t mmax, double *v, double *al, double *be, double *w,
                      double *mw)
{
    size_t N = 3 * d->n;
    uint64_t s = 0x9E3779B97F4A7C15ull;
    start_vector(&s, w, N);
    cbm__dyn_apply(d, 0.0, 1.0, w, mw);
    double nrm = sqrt(dot(w, mw, N));
    for (size_t i = 0; i < N; i++)
        v[i] = w[i] / nrm;
    size_t j = 0;
    for (; j < mmax; j++) {
        double *vj = v + j * N;
        cbm__dyn_apply(d, 0.0, 1.0, vj, mw);
        cbm__dyn_solve(d, mw, w);
        /* full reorthogonalisation in the M inner product */
        m_orthogonalise(d, v, j + 1, w, mw, &al[j]);
        double b = sqrt(fmax(dot(w, mw, N), 0.0));
        be[j] = b;
        if (j + 1 == mmax || !isfinite(b)) {
            j++;
            break;
        }
        if (!(b > 1e-10 * fabs(al[j]))) {
            /* closed: restart M-orthogonal to the basis, or stop if it spans everything */
            be[j] = 0.0;
            start_vector(&s, w, N);
            cbm__dyn_apply(d, 0.0, 1.0, w, mw);
            double n0 = sqrt(dot(w, mw, N));
            m_orthogonalise(d, v, j + 1, w, mw, NULL);
            b = sqrt(fmax(dot(w, mw, N), 0.0));
            if (!(b > 1e-8 * n0)) {
                j++;
                break;
            }
        }
        for (size_t k = 0; k < N; k++)
            v[(j + 1) * N + k] = w[k] / b;
    }
    return j;
}

cbm_status cbm_plant_modes(const cbm_plant *plant, size_t count, double *freqs_hz, double *shapes)
{
    if (!plant || !freqs_hz || count == 0)
        return CBM_E_INVALID;
    cbm__dyn d;
    cbm_status st = cbm__dyn_build(plant, &d);
    if (st != CBM_OK)
        return st;
    cbm_context *ctx = d.ctx;
    size_t N = 3 * d.n;
    size_t nonpd = cbm__dyn_factor(&d, 1.0, 0.0);
    if (nonpd != 0) {
        cbm__dyn_free(&d);
        if (nonpd == (size_t)-1)
            return cbm__fail(ctx, CBM_E_RUNTIME,
                             "modes: the stiffness is singular at this equilibrium (a buckling "
                             "load)");
        return cbm__fail(ctx, CBM_E_RUNTIME,
                         "modes: the equilibrium is unstable (%zu joints with a stiffness block "
                         "that is not positive definite)",
                         nonpd);
    }
    size_t want = count < N ? count : N;
    size_t mmax = 3 * want + 30;
    if (mmax > N)
        mmax = N;
    for (size_t i = 0; i < count; i++)
        freqs_hz[i] = NAN;
    st = CBM_E_NOT_CONVERGED;
    for (int attempt = 0; attempt < 6 && st == CBM_E_NOT_CONVERGED; attempt++) {
        size_t ma = mmax; /* the sizes allocated (mmax may grow below) */
        double *v = cbm__calloc(ctx, (mmax + 1) * N, sizeof(double));
        double *w = cbm__alloc(ctx, N * sizeof(double));
        double *mw = cbm__alloc(ctx, N * sizeof(double));
        double *al = cbm__calloc(ctx, mmax, sizeof(double));
        double *be = cbm__calloc(ctx, mmax, sizeof(double));
        double *t = cbm__calloc(ctx, mmax * mmax, sizeof(double));
        double *ev = cbm__alloc(ctx, mmax * mmax * sizeof(double));
        double *th = cbm__alloc(ctx, mmax * sizeof(double));
        size_t *ord = cbm__alloc(ctx, mmax * sizeof(size_t));
        if (!v || !w || !mw || !al || !be || !t || !ev || !th || !ord)
            st = CBM_E_NOMEM;
        else {
            size_t m = lanczos(&d, mmax, v, al, be, w, mw);
            for (size_t i = 0; i < m; i++) {
                t[i * m + i] = al[i];
                if (i + 1 < m)
                    t[i * m + i + 1] = t[(i + 1) * m + i] = be[i];
            }
            jacobi(t, m, th, ev);
            /* order by decreasing theta (increasing lambda) */
            for (size_t i = 0; i < m; i++)
                ord[i] = i;
            for (size_t i = 1; i < m; i++)
                for (size_t k = i; k > 0 && th[ord[k]] > th[ord[k - 1]]; k--) {
                    size_t tmp = ord[k];
                    ord[k] = ord[k - 1];
                    ord[k - 1] = tmp;
                }
            size_t got = want < m ? want : m;
            bool ok = m == N || got == want;
            double bm = be[m - 1];
            for (size_t i = 0; i < got && ok; i++) {
                size_t c = ord[i];
                /* residual of the Ritz pair: |beta_m s_m| against theta */
                if (m < N && fabs(bm * ev[(m - 1) * m + c]) > 1e-8 * fabs(th[c]))
                    ok = false;
            }
            if (ok) {
                for (size_t i = 0; i < got; i++) {
                    size_t c = ord[i];
                    double lam = 1.0 / th[c];
                    freqs_hz[i] = sqrt(fmax(lam, 0.0)) / (2.0 * 3.14159265358979323846);
                    if (shapes) {
                        double *ph = shapes + i * N;
                        memset(ph, 0, N * sizeof(double));
                        for (size_t k = 0; k < m; k++) {
                            double s = ev[k * m + c];
                            for (size_t r = 0; r < N; r++)
                                ph[r] += s * v[k * N + r];
                        }
                    }
                }
                st = CBM_OK;
            } else if (mmax == N)
                st = CBM_E_INTERNAL;
            else
                mmax = 2 * mmax > N ? N : 2 * mmax;
        }
        cbm__free(ctx, v, (ma + 1) * N * sizeof(double));
        cbm__free(ctx, w, N * sizeof(double));
        cbm__free(ctx, mw, N * sizeof(double));
        cbm__free(ctx, al, ma * sizeof(double));
        cbm__free(ctx, be, ma * sizeof(double));
        cbm__free(ctx, t, ma * ma * sizeof(double));
        cbm__free(ctx, ev, ma * ma * sizeof(double));
        cbm__free(ctx, th, ma * sizeof(double));
        cbm__free(ctx, ord, ma * sizeof(size_t));
    }
    cbm__dyn_free(&d);
    if (st == CBM_E_INTERNAL || st == CBM_E_NOT_CONVERGED)
        return cbm__fail(ctx, CBM_E_NOT_CONVERGED, "modes: the Lanczos iteration did not converge");
    return st;
}
