/* Natural frequencies and mode shapes: the lowest eigenpairs of K phi = lambda M phi by
 * shift-invert Lanczos in the M inner product.
 *
 * Why Lanczos with our own tree factorisation rather than ARPACK: the operator (K - sigma M)^-1 M
 * is applied in O(n) by the tree elimination of tree.c (one backward and one forward sweep per
 * solve, one each way per product with M), so a plain Lanczos run needs nothing else (per step
 * one solve, the three-term recurrence and one product with M: four sweeps over the tree; a
 * Gram-Schmidt pass over the basis and another product with M only at the steps where the
 * estimated loss of orthogonality asks for it: partial reorthogonalisation, below; at 10^5
 * segments a pass at every step cost more than the sweeps, docs/performance.md); for the few tens
 * of modes anyone asks for
 * the Krylov basis stays small (m = 3 count + 30, doubled if the Ritz values have not converged),
 * and the library keeps no Fortran dependency (ARPACK would add one to every build for a dozen
 * lines of iteration here).
 *
 * The shift is 0: the factorisation of K then also decides the stability of the equilibrium
 * (positive pivots iff K is positive definite), and for a stable plant the largest Ritz values
 * theta of K^-1 M are the lowest lambda = 1 / theta. The small tridiagonal matrix is
 * diagonalised by cyclic Jacobi rotations (m is at most a few hundred).
 */
#define _DEFAULT_SOURCE /* madvise */
#include "mech/dyn_internal.h"

#include <math.h>
#include <stdint.h>
#include <string.h>
#if defined(__linux__)
#include <sys/mman.h>
#endif

/* Asks the kernel to back the 2 MiB-aligned part of [p, p + bytes) with huge pages. The basis is
 * written once and streamed through at every step: with 4 KiB pages its first touch costs a page
 * fault per 4 KiB (at 10^5 segments some 36,000, each a trap to the hypervisor on the virtual
 * machines these runs are measured on) and its passes a TLB miss per 4 KiB. A hint only: ignored
 * where the kernel has no transparent huge pages, and no effect on the results. */
static void advise_huge(void *p, size_t bytes)
{
#if defined(__linux__) && defined(MADV_HUGEPAGE)
    const size_t huge = (size_t)2 << 20;
    size_t off = (size_t)(-(uintptr_t)p & (huge - 1)); /* from p up to the next 2 MiB boundary */
    if (bytes > off && (bytes - off) >= huge)
        (void)madvise((char *)p + off, (bytes - off) & ~(huge - 1), MADV_HUGEPAGE);
#else
    (void)p;
    (void)bytes;
#endif
}

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

/* The dot product in four partial sums: one sum is bound by the latency of the additions. */
static double dot(const double *restrict a, const double *restrict b, size_t n)
{
    double s0 = 0.0, s1 = 0.0, s2 = 0.0, s3 = 0.0;
    size_t i = 0;
    for (; i + 4 <= n; i += 4) {
        s0 += a[i] * b[i];
        s1 += a[i + 1] * b[i + 1];
        s2 += a[i + 2] * b[i + 2];
        s3 += a[i + 3] * b[i + 3];
    }
    for (; i < n; i++)
        s0 += a[i] * b[i];
    return (s0 + s2) + (s1 + s3);
}

/* w -= c v */
static void axpy(double c, const double *restrict v, double *restrict w, size_t n)
{
    for (size_t i = 0; i < n; i++)
        w[i] -= c * v[i];
}

/* The Krylov basis (3n rows, up to cap columns) in row blocks: block b holds rows [b BLK, b BLK +
 * BLK) of every column, column after column. The Gram-Schmidt pass is then a product of the
 * basis with one vector and another of its transpose, each of which reads the basis once at the
 * speed of the memory bus while the few thousand bytes of the vectors' block stay in the L1 cache;
 * stored column by column the pass read each column twice and streamed the vectors once per
 * column (at 10^5 segments 2.4 MB each), about two and a half times the bytes. */
#define BLK 512
typedef struct basis {
    double *v;
    size_t rows, cap, nb;
} basis;

static double *basis_block(const basis *b, size_t k)
{
    return b->v + k * BLK * b->cap;
}

static size_t basis_block_len(const basis *b, size_t k)
{
    return k + 1 < b->nb ? BLK : b->rows - k * BLK;
}

/* column j = s w */
static void col_set(basis *b, size_t j, double s, const double *w)
{
    for (size_t k = 0; k < b->nb; k++) {
        double *c = basis_block(b, k) + j * BLK;
        const double *wk = w + k * BLK;
        size_t len = basis_block_len(b, k);
        for (size_t r = 0; r < len; r++)
            c[r] = s * wk[r];
    }
}

/* w -= c (column j) */
static void col_axpy(const basis *b, size_t j, double c, double *w)
{
    for (size_t k = 0; k < b->nb; k++)
        axpy(c, basis_block(b, k) + j * BLK, w + k * BLK, basis_block_len(b, k));
}

/* c[0..cols) = V^T mw */
static void basis_tmul(const basis *b, size_t cols, const double *mw, double *c)
{
    for (size_t i = 0; i < cols; i++)
        c[i] = 0.0;
    for (size_t k = 0; k < b->nb; k++) {
        const double *vk = basis_block(b, k), *mk = mw + k * BLK;
        size_t len = basis_block_len(b, k);
        for (size_t i = 0; i < cols; i++)
            c[i] += dot(vk + i * BLK, mk, len);
    }
}

/* w -= V c over cols columns */
static void basis_sub(const basis *b, size_t cols, const double *c, double *w)
{
    for (size_t k = 0; k < b->nb; k++) {
        const double *vk = basis_block(b, k);
        double *wk = w + k * BLK;
        size_t len = basis_block_len(b, k);
        for (size_t i = 0; i < cols; i++)
            axpy(c[i], vk + i * BLK, wk, len);
    }
}

/* out = sum_k s[k m] (column k) over the first m columns (a Ritz vector: s strided by m) */
static void basis_combine(const basis *b, size_t m, const double *s, size_t stride, double *out)
{
    for (size_t k = 0; k < b->nb; k++) {
        const double *vk = basis_block(b, k);
        double *ok = out + k * BLK;
        size_t len = basis_block_len(b, k);
        for (size_t r = 0; r < len; r++)
            ok[r] = 0.0;
        for (size_t i = 0; i < m; i++)
            axpy(-s[i * stride], vk + i * BLK, ok, len);
    }
}

/* w -= the M-projection of w on the first cols columns of the basis by classical Gram-Schmidt,
 * repeated once when the pass removed more than 1 - 1/sqrt(2) of w's M-norm (the criterion of
 * Daniel, Gragg, Kaufman and Stewart: a second pass then restores orthogonality to round-off, a
 * third is never needed); mw holds M w on entry and on return, and the result is w' M w. M w is
 * recomputed after each pass: carried as M w_before, off by the M V c the pass removed, its error
 * re-enters the next step multiplied by about alpha / beta and grows (tried: the tenth frequency
 * of the 10^5-segment tree came out 5e-4 high while the residual test passed). When diag is not
 * NULL it receives the coefficient of column cols - 1 summed over the passes; c is scratch (cols
 * doubles). */
static double m_orthogonalise(cbm__dyn *d, const basis *b, size_t cols, double *w, double *mw,
                              double *diag, double *c)
{
    size_t N = 3 * d->n;
    double before = dot(w, mw, N), after = before;
    for (int pass = 0; pass < 2; pass++) {
        basis_tmul(b, cols, mw, c);
        if (diag)
            *diag = pass == 0 ? c[cols - 1] : *diag + c[cols - 1];
        basis_sub(b, cols, c, w);
        cbm__dyn_apply(d, 0.0, 1.0, w, mw);
        after = dot(w, mw, N);
        if (after >= 0.5 * before)
            break;
        before = after;
    }
    return after;
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

/* The Ritz values th (of the m x m tridiagonal al, be; t is overwritten) with their vectors ev,
 * and ord the order of decreasing theta (increasing lambda). */
static void ritz(const double *al, const double *be, size_t m, double *t, double *ev, double *th,
                 size_t *ord)
{
    memset(t, 0, m * m * sizeof(double));
    for (size_t i = 0; i < m; i++) {
        t[i * m + i] = al[i];
        if (i + 1 < m)
            t[i * m + i + 1] = t[(i + 1) * m + i] = be[i];
    }
    jacobi(t, m, th, ev);
    for (size_t i = 0; i < m; i++)
        ord[i] = i;
    for (size_t i = 1; i < m; i++)
        for (size_t k = i; k > 0 && th[ord[k]] > th[ord[k - 1]]; k--) {
            size_t tmp = ord[k];
            ord[k] = ord[k - 1];
            ord[k - 1] = tmp;
        }
}

/* whether the lowest `want` Ritz pairs of a run of m steps ending with beta = bm have residuals
 * |bm s_m| <= tol theta */
static bool ritz_converged(size_t m, size_t want, double bm, const double *ev, const double *th,
                           const size_t *ord, double tol)
{
    for (size_t i = 0; i < want && i < m; i++) {
        size_t c = ord[i];
        if (fabs(bm * ev[(m - 1) * m + c]) > tol * fabs(th[c]))
            return false;
    }
    return want <= m;
}

/* The Lanczos run stops early, before mmax, once the wanted pairs' residuals are below this (the
 * acceptance test below is 1e-8): the eigenvalues then agree with a longer run's to about its
 * square, the shapes to it over the relative gap. Checked every CHECK_EVERY steps (the small
 * eigenproblem costs O(m^3) against the O(m n) of a step). */
#define EARLY_TOL   1e-12
#define CHECK_EVERY 4

/* Partial reorthogonalisation (Simon, "The Lanczos algorithm with partial reorthogonalization",
 * Math. Comp. 42, 1984). The full Gram-Schmidt pass at every step read the whole basis twice (at
 * 10^5 segments and 60 steps some 8.6 GB through the memory bus in a run, more than the sweeps
 * over the tree) though it mostly removed round-off. Instead the M inner products omega_k =
 * v_k' M v_{j+1} of the new vector with the basis are estimated from the recurrence they obey,
 *   beta_j omega_{j+1,k} = beta_k omega_{j,k+1} + (alpha_k - alpha_j) omega_{j,k}
 *                          + beta_{k-1} omega_{j,k-1} - beta_{j-1} omega_{j-1,k},
 * each with a round-off term of its sign added (PRO_EPS times the estimate of |A| over beta_j), and
 * the basis is swept only when one of them exceeds PRO_TOL: then at that step and the next (the
 * new vector's successor inherits the loss through the three-term recurrence), after which the
 * estimates restart at round-off. Lanczos with a basis orthogonal to PRO_TOL gives the Ritz values
 * of a fully orthogonal one to round-off (Simon's theorem: T is the projection of A on the span to
 * O(eps |A|)); PRO_TOL is set below sqrt(eps) ~ 1.5e-8 so that the Ritz vectors, combined from the
 * basis, stay M-orthonormal to the 1e-9 the tests ask of them. */
#define PRO_TOL 1e-10
#define PRO_EPS 1e-15

/* the estimates on[0..j+1] of v_k' M v_{j+1} from oc (v_k' M v_j, 0..j) and op (v_k' M v_{j-1},
 * 0..j-1), with alpha al[0..j], beta be[0..j] (be[j] the new vector's), anorm the estimate of
 * |A|; returns max |on[k]| over k <= j */
static double pro_update(size_t j, const double *al, const double *be, double anorm,
                         const double *op, const double *oc, double *on)
{
    double bj = be[j], psi = PRO_EPS * anorm / bj, mx = 0.0;
    for (size_t k = 0; k < j; k++) {
        double t = be[k] * oc[k + 1] + (al[k] - al[j]) * oc[k];
        if (k > 0)
            t += be[k - 1] * oc[k - 1];
        if (j > 0)
            t -= be[j - 1] * op[k];
        t = t / bj;
        t += t >= 0 ? psi : -psi;
        on[k] = t;
        mx = fmax(mx, fabs(t));
    }
    on[j] = psi;
    on[j + 1] = 1.0;
    return fmax(mx, psi);
}

/* One Lanczos run of at most mmax steps; returns the steps done (the basis in v, the tridiagonal
 * in al, be). When the Krylov space closes (an invariant subspace: it happens with exactly
 * repeated frequencies, or when the run reaches all N degrees of freedom) the run restarts from a
 * new start vector M-orthogonal to the basis, with be = 0 at the seam, so T stays tridiagonal and
 * its eigenvalues those of the whole space spanned; it stops when no new direction is left, or
 * when the lowest `want` Ritz pairs have converged (t, ev, th, ord: scratch for ritz). M v_j is
 * carried from the step before (M w / b, M w fresh), om scratch of 3 (mmax + 1) doubles for the
 * orthogonality estimates; full: sweep at every step (the reference of the tests); *sweeps
 * receives the number of steps that swept the basis. */
static size_t lanczos(cbm__dyn *d, size_t mmax, size_t want, basis *v, double *al, double *be,
                      double *w, double *mw, double *mv, double *c, double *t, double *ev,
                      double *th, size_t *ord, double *om, bool full, size_t *sweeps)
{
    size_t N = 3 * d->n;
    uint64_t s = 0x9E3779B97F4A7C15ull;
    double *op = om, *oc = om + (mmax + 1), *on = om + 2 * (mmax + 1), anorm = 0.0;
    bool again = false; /* the step after a reorthogonalisation sweeps too */
    *sweeps = 0;
    start_vector(&s, w, N);
    cbm__dyn_apply(d, 0.0, 1.0, w, mw);
    double nrm = sqrt(dot(w, mw, N));
    col_set(v, 0, 1.0 / nrm, w);
    for (size_t i = 0; i < N; i++)
        mv[i] = mw[i] / nrm;
    oc[0] = 1.0;
    size_t j = 0;
    for (; j < mmax; j++) {
        cbm__dyn_solve(d, mv, w);
        /* the three-term recurrence (v_{j-1}' M w = beta_{j-1}, v_j' M w = (M v_j)' w), then M w
         * afresh: carried through the recurrence from the M v's its error re-enters the next
         * step multiplied by about alpha / beta and grows (tried: the tenth frequency of the
         * 10^5-segment tree came out 5e-4 high while the residual test passed) */
        double a;
        if (j > 0)
            col_axpy(v, j - 1, be[j - 1], w);
        a = dot(mv, w, N);
        col_axpy(v, j, a, w);
        cbm__dyn_apply(d, 0.0, 1.0, w, mw);
        double bb = dot(w, mw, N), bprev = j > 0 ? be[j - 1] : 0.0;
        al[j] = a;
        be[j] = sqrt(fmax(bb, 0.0));
        anorm = fmax(anorm, fabs(a) + be[j] + bprev);
        /* the recurrence cancelled more than 99.99 % of x's M-norm (x' M x = a^2 + beta_{j-1}^2 +
         * b^2 in exact arithmetic): the Krylov space is about to close, as with repeated
         * frequencies, and what is left of w is mostly round-off of the basis: sweep */
        bool sweep = full || again || !(bb > 1e-4 * (a * a + bprev * bprev + bb)) || !(be[j] > 0.0);
        if (!sweep)
            sweep = pro_update(j, al, be, anorm, op, oc, on) > PRO_TOL;
        bool second = again; /* this is the sweep after one: the next need not */
        again = false;
        if (sweep) {
            double corr = 0.0;
            double b = sqrt(fmax(m_orthogonalise(d, v, j + 1, w, mw, &corr, c), 0.0));
            al[j] = a + corr;
            be[j] = b;
            (*sweeps)++;
            again = !second;
            for (size_t k = 0; k <= j; k++)
                on[k] = PRO_EPS;
            on[j + 1] = 1.0;
        }
        double b = be[j];
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
            b = sqrt(fmax(m_orthogonalise(d, v, j + 1, w, mw, NULL, c), 0.0));
            (*sweeps)++;
            if (!(b > 1e-8 * n0)) {
                j++;
                break;
            }
            again = true;
            for (size_t k = 0; k <= j; k++)
                on[k] = PRO_EPS;
            on[j + 1] = 1.0;
        } else if (j + 1 >= want && (j + 1) % CHECK_EVERY == 0) {
            ritz(al, be, j + 1, t, ev, th, ord);
            if (ritz_converged(j + 1, want, b, ev, th, ord, EARLY_TOL)) {
                j++;
                break;
            }
        }
        double rb = 1.0 / b, *tmp;
        col_set(v, j + 1, rb, w);
        for (size_t k = 0; k < N; k++)
            mv[k] = mw[k] * rb;
        tmp = op;
        op = oc;
        oc = on;
        on = tmp;
    }
    return j;
}

cbm_status cbm__plant_modes(const cbm_plant *plant, size_t count, double *freqs_hz, double *shapes,
                            bool full, size_t *steps, size_t *sweeps)
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
        /* the basis is written column by column before it is read: not cleared, so that the
         * pages of the columns an early stop leaves unused are never touched */
        basis v = {NULL, N, mmax + 1, (N + BLK - 1) / BLK};
        size_t vbytes = v.nb * BLK * v.cap * sizeof(double);
        v.v = cbm__alloc(ctx, vbytes);
        if (v.v)
            advise_huge(v.v, vbytes);
        double *gc = cbm__alloc(ctx, (mmax + 1) * sizeof(double));
        double *w = cbm__alloc(ctx, N * sizeof(double));
        double *mw = cbm__alloc(ctx, N * sizeof(double));
        double *mv = cbm__alloc(ctx, N * sizeof(double));
        double *al = cbm__calloc(ctx, mmax, sizeof(double));
        double *be = cbm__calloc(ctx, mmax, sizeof(double));
        double *t = cbm__calloc(ctx, mmax * mmax, sizeof(double));
        double *ev = cbm__alloc(ctx, mmax * mmax * sizeof(double));
        double *th = cbm__alloc(ctx, mmax * sizeof(double));
        size_t *ord = cbm__alloc(ctx, mmax * sizeof(size_t));
        double *om = cbm__alloc(ctx, 3 * (mmax + 1) * sizeof(double));
        if (!v.v || !gc || !w || !mw || !mv || !al || !be || !t || !ev || !th || !ord || !om)
            st = CBM_E_NOMEM;
        else {
            size_t sw = 0;
            /* a basis of every direction: the shapes are then the whole eigenbasis, which the
             * modal motion (its static correction) relies on being M-orthonormal to round-off,
             * and the run is short anyway: sweep at every step */
            size_t m = lanczos(&d, mmax, want, &v, al, be, w, mw, mv, gc, t, ev, th, ord, om,
                               full || mmax == N, &sw);
            if (steps)
                *steps = m;
            if (sweeps)
                *sweeps = sw;
            ritz(al, be, m, t, ev, th, ord);
            size_t got = want < m ? want : m;
            bool ok = m == N || got == want;
            if (ok && m < N)
                ok = ritz_converged(m, got, be[m - 1], ev, th, ord, 1e-8);
            if (ok) {
                for (size_t i = 0; i < got; i++) {
                    size_t c = ord[i];
                    double lam = 1.0 / th[c];
                    freqs_hz[i] = sqrt(fmax(lam, 0.0)) / (2.0 * 3.14159265358979323846);
                    if (shapes)
                        basis_combine(&v, m, ev + c, m, shapes + i * N);
                }
                st = CBM_OK;
            } else if (mmax == N)
                st = CBM_E_INTERNAL;
            else
                mmax = 2 * mmax > N ? N : 2 * mmax;
        }
        cbm__free(ctx, v.v, vbytes);
        cbm__free(ctx, gc, (ma + 1) * sizeof(double));
        cbm__free(ctx, w, N * sizeof(double));
        cbm__free(ctx, mw, N * sizeof(double));
        cbm__free(ctx, mv, N * sizeof(double));
        cbm__free(ctx, al, ma * sizeof(double));
        cbm__free(ctx, be, ma * sizeof(double));
        cbm__free(ctx, t, ma * ma * sizeof(double));
        cbm__free(ctx, ev, ma * ma * sizeof(double));
        cbm__free(ctx, th, ma * sizeof(double));
        cbm__free(ctx, ord, ma * sizeof(size_t));
        cbm__free(ctx, om, 3 * (ma + 1) * sizeof(double));
    }
    cbm__dyn_free(&d);
    if (st == CBM_E_INTERNAL || st == CBM_E_NOT_CONVERGED)
        return cbm__fail(ctx, CBM_E_NOT_CONVERGED, "modes: the Lanczos iteration did not converge");
    return st;
}

cbm_status cbm_plant_modes(const cbm_plant *plant, size_t count, double *freqs_hz, double *shapes)
{
    return cbm__plant_modes(plant, count, freqs_hz, shapes, false, NULL, NULL);
}
