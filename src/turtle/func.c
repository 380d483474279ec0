/* Function files (.func) and function sets: the graphically defined functions of cpfg, used by
 * func(id, x) in model expressions.
 *
 * A function is a planar curve given by control points (x, y) of a clamped uniform cubic B-spline
 * (order 4, integer knots 0,0,0,0,1,2,...,n-2,n-2,n-2,n-2 over n+1 points; a point with a
 * multiplicity m is repeated m times). Its value at x is y(t) where x(t) = x: as in cpfg, t is
 * found by bisection on [0, 1] until |x(t) - x| <= 0.001. When the file asks for `samples` > 2,
 * the function is tabulated at x = i/(samples-1) and evaluated by linear interpolation in that
 * table, which is what cpfg returns (and what makes its results reproducible).
 * The basis is evaluated with the Cox-de Boor recursion (de Boor, A Practical Guide to Splines,
 * ch. IX), with 0/0 taken as 0 and the order-1 basis half-open [u_k, u_{k+1}); note that this
 * makes the curve's last point (t = 1) evaluate to the origin, which the bisection never reaches.
 *
 * Formats: "fver 1 1" (name:, samples:, optional background and markers lines, flip:, points: N,
 * then N lines "x y [multiplicity]"), the older "range: a b" (points: N, then N lines "x y";
 * samples from the view file), and function galleries (.fset: "funcgalleryver 1 1", "items: N",
 * then N functions in the "fver 1 1" form).
 */
#include "view_internal.h"

#include "../core/vecmath.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>

cbm_status cbm__read_file(cbm_context *ctx, const char *path, char **text, size_t *len)
{
    *text = NULL;
    *len = 0;
    FILE *f = fopen(path, "rb");
    if (!f)
        return cbm__fail(ctx, CBM_E_IO, "%s: cannot open: %s", path, strerror(errno));
    size_t cap = 4096, n = 0;
    char *buf = cbm__alloc(ctx, cap);
    if (!buf) {
        fclose(f);
        return CBM_E_NOMEM;
    }
    for (;;) {
        if (n + 1 >= cap) {
            char *nb = cbm__realloc(ctx, buf, cap, cap * 2);
            if (!nb) {
                cbm__free(ctx, buf, cap);
                fclose(f);
                return CBM_E_NOMEM;
            }
            buf = nb;
            cap *= 2;
        }
        size_t got = fread(buf + n, 1, cap - 1 - n, f);
        n += got;
        if (got == 0)
            break;
    }
    int err = ferror(f);
    fclose(f);
    if (err) {
        cbm__free(ctx, buf, cap);
        return cbm__fail(ctx, CBM_E_IO, "%s: read error", path);
    }
    buf[n] = '\0';
    *text = buf;
    *len = cap; /* the allocation size, for cbm__free_file */
    return CBM_OK;
}

void cbm__free_file(cbm_context *ctx, char *text, size_t len)
{
    cbm__free(ctx, text, len);
}

/* ---- the B-spline ---- */

static int knot(int j, int n)
{
    if (j < 4)
        return 0;
    if (j > n)
        return n - 2;
    return j - 3;
}

/* Point of the curve at parameter d in [0, 1]. Only the four basis functions N(j-3..j, 4) of
 * the knot span j of u (knot(j) <= u < knot(j+1): j = 3 + floor(u)) can be nonzero; the others
 * are exactly zero, and adding their products with finite control points to the sums (never
 * -0) leaves the sums' bits unchanged, so they are skipped: a point costs 4 terms, not one per
 * control point (a function of 6000 points tabulated at 10^6 samples was 10^12 terms). With a
 * control point that is not finite (a coordinate beyond float's range) every term is summed,
 * as 0 times infinity is NaN. */
static void curve_point(const cbm__func *f, double d, double *x, double *y, size_t *evals)
{
    int n = f->npts - 1;
    double u = d * (double)(n - 2);
    double sx = 0.0, sy = 0.0;
    int k0 = 0, k1 = n;
    if (f->finite && u >= 0.0 && u < (double)(n - 2)) {
        k1 = 3 + (int)u;
        k0 = k1 - 3;
    } else if (f->finite && u == (double)(n - 2)) { /* the end: no span holds u, all zero */
        k0 = 0;
        k1 = -1;
    }
    if (evals)
        *evals += (size_t)(k1 >= k0 ? k1 - k0 + 1 : 0);
    for (int k = k0; k <= k1; k++) {
        /* N(k, 4) from the order-1 functions N(k..k+3, 1), raised in place */
        double t1[4];
        for (int i = 0; i < 4; i++)
            t1[i] = (knot(k + i, n) <= u && u < knot(k + i + 1, n)) ? 1.0 : 0.0;
        for (int t = 2; t <= 4; t++) {
            for (int i = 0; i + t <= 4; i++) {
                int a = k + i;
                double s = 0.0;
                int div = knot(a + t - 1, n) - knot(a, n);
                if (div != 0)
                    s = (u - knot(a, n)) / div * t1[i];
                div = knot(a + t, n) - knot(a + 1, n);
                if (div != 0)
                    s += (knot(a + t, n) - u) / div * t1[i + 1];
                t1[i] = s;
            }
        }
        sx += f->px[k] * t1[0];
        sy += f->py[k] * t1[0];
    }
    *x = sx;
    *y = sy;
}

/* y at x by bisection on the curve parameter until |x(t) - x| <= tol (cpfg: 0.001; lpfg:
 * 0.01 / samples), at most 200 halvings. Where x(t) never comes within tol (a curve that does
 * not reach x) the interval stops shrinking long before: once the midpoint rounds to an end,
 * every later halving evaluates that same point again and keeps it, so the loop stops there
 * with the value the 200 halvings would return. */
static double bisect_value(const cbm__func *f, double x, double tol, size_t *evals)
{
    double lo = 0.0, hi = 1.0, cx = 0.0, cy = 0.0;
    for (int it = 0; it < 200; it++) {
        double mid = 0.5 * (lo + hi);
        curve_point(f, mid, &cx, &cy, evals);
        bool stuck = mid == lo || mid == hi;
        if (cx > x)
            hi = mid;
        else
            lo = mid;
        if (fabs(cx - x) <= tol || stuck)
            break;
    }
    return cy;
}

static double exact_value(const cbm__func *f, double x, size_t *evals)
{
    return bisect_value(f, x, 0.001, evals);
}

void cbm__funcset_lpfg(cbm_funcset *fs)
{
    for (size_t k = 0; k < fs->funcs.len; k++) {
        cbm__func *f = &fs->funcs.data[k];
        if (f->samples <= 2)
            continue;
        double tol = 0.01 / f->samples;
        for (int i = 0; i < f->samples; i++)
            f->vals[i] =
                bisect_value(f, (double)i / (double)(f->samples - 1), tol, &f->basis_evals);
    }
}

static double func_value(const cbm__func *f, double x)
{
    if (!(x >= 0.0))
        x = 0.0; /* also NaN */
    if (x > 1.0)
        x = 1.0;
    if (f->samples > 2) {
        double idx = x * (double)(f->samples - 1);
        int i = (int)floor(idx);
        if (i >= f->samples - 1)
            return f->vals[f->samples - 1];
        double w2 = idx - i;
        return (1.0 - w2) * f->vals[i] + w2 * f->vals[i + 1];
    }
    return exact_value(f, x, NULL);
}

/* ---- reading ---- */

typedef struct lines {
    const char *p;
    int line;
} lines;

/* Next line into buf (without the newline); false at the end. */
static bool next_line(lines *L, char *buf, size_t cap)
{
    if (!*L->p)
        return false;
    size_t n = 0;
    while (*L->p && *L->p != '\n') {
        if (n + 1 < cap && *L->p != '\r')
            buf[n++] = *L->p;
        L->p++;
    }
    if (*L->p == '\n')
        L->p++;
    buf[n] = '\0';
    L->line++;
    return true;
}

static cbm_status format_error(cbm_context *ctx, const char *path, int line, const char *what)
{
    cbm__diag(ctx, CBM_ERROR, path, line, 1, "%s", what);
    return CBM_E_FORMAT;
}

void cbm__func_free(cbm_context *ctx, cbm__func *f)
{
    cbm__free(ctx, f->px, (size_t)f->npts * sizeof(double));
    cbm__free(ctx, f->py, (size_t)f->npts * sizeof(double));
    cbm__free(ctx, f->vals, f->samples > 2 ? (size_t)f->samples * sizeof(double) : 0);
    memset(f, 0, sizeof *f);
}

/* One function from the cursor L (which is left after it). */
static cbm_status read_func(cbm_context *ctx, const char *path, lines *Lp, int samples,
                            cbm__func *f)
{
    memset(f, 0, sizeof *f);
    lines L = *Lp;
    char buf[256];
    if (!next_line(&L, buf, sizeof buf))
        return format_error(ctx, path, L.line + 1,
                            "expected a function ('fver 1 1'), found the end");
    int vmaj = 0, vmin = 0;
    float lo, up;
    bool v101 = false;
    if (sscanf(buf, "range: %f %f", &lo, &up) == 2) {
        v101 = false;
    } else if (sscanf(buf, "fver %d %d", &vmaj, &vmin) == 2) {
        if (vmaj != 1 || vmin != 1)
            return format_error(ctx, path, L.line,
                                "unsupported function file version (expected fver 1 1)");
        v101 = true;
    } else {
        return format_error(ctx, path, L.line, "expected 'fver 1 1' or 'range: a b'");
    }
    if (v101) {
        if (!next_line(&L, buf, sizeof buf) || sscanf(buf, "name: %63s", f->name) != 1)
            return format_error(ctx, path, L.line, "expected 'name: NAME'");
        if (!next_line(&L, buf, sizeof buf) || sscanf(buf, "samples: %d", &samples) != 1)
            return format_error(ctx, path, L.line, "expected 'samples: N'");
        /* optional background (two lines) and markers; then flip: */
        for (;;) {
            if (!next_line(&L, buf, sizeof buf))
                return format_error(ctx, path, L.line, "unexpected end of file before 'points:'");
            if (strncmp(buf, "background", 10) == 0) {
                next_line(&L, buf, sizeof buf);
                continue;
            }
            if (strncmp(buf, "markers:", 8) == 0) {
                int m = 0;
                sscanf(buf, "markers: %d", &m);
                for (int i = 0; i < m; i++)
                    next_line(&L, buf, sizeof buf);
                continue;
            }
            if (strncmp(buf, "flip:", 5) == 0)
                continue;
            break;
        }
    } else {
        if (!next_line(&L, buf, sizeof buf))
            return format_error(ctx, path, L.line, "expected 'points: N'");
    }
    int npts = 0;
    if (sscanf(buf, "points: %d", &npts) != 1)
        return format_error(ctx, path, L.line, "expected 'points: N'");
    if (npts < 4 || npts > 100000)
        return format_error(ctx, path, L.line, "a function needs at least 4 control points");
    /* first pass: count with multiplicities */
    lines save = L;
    int total = 0;
    for (int i = 0; i < npts; i++) {
        double x, y, m = 1.0;
        if (!next_line(&L, buf, sizeof buf))
            return format_error(ctx, path, L.line, "fewer control points than 'points:' says");
        int k = sscanf(buf, "%lf %lf %lf", &x, &y, &m);
        if (k < 2)
            return format_error(ctx, path, L.line, "expected 'x y [multiplicity]'");
        if (k < 3 || !v101)
            m = 1.0;
        if (!(m >= 1.0 && m <= 4.0))
            return format_error(ctx, path, L.line, "multiplicity must be 1 to 4");
        if (!isfinite(x) || !isfinite(y))
            return format_error(ctx, path, L.line, "control point is not a finite number");
        total += (int)m;
    }
    L = save;
    f->px = cbm__alloc(ctx, (size_t)total * sizeof(double));
    f->py = cbm__alloc(ctx, (size_t)total * sizeof(double));
    f->npts = total;
    if (!f->px || !f->py) {
        cbm__func_free(ctx, f);
        return CBM_E_NOMEM;
    }
    int j = 0;
    for (int i = 0; i < npts; i++) {
        double x, y, m = 1.0;
        next_line(&L, buf, sizeof buf);
        int k = sscanf(buf, "%lf %lf %lf", &x, &y, &m);
        if (k < 3 || !v101)
            m = 1.0;
        /* cpfg reads the coordinates as float */
        for (int r = 0; r < (int)m; r++) {
            f->px[j] = (float)x;
            f->py[j] = (float)y;
            j++;
        }
    }
    f->finite = true;
    for (int i = 0; i < f->npts; i++)
        f->finite = f->finite && isfinite(f->px[i]) && isfinite(f->py[i]);
    if (samples > 2) {
        if (samples > 1000000) {
            cbm__func_free(ctx, f);
            return format_error(ctx, path, 0, "too many samples");
        }
        f->vals = cbm__alloc(ctx, (size_t)samples * sizeof(double));
        if (!f->vals) {
            cbm__func_free(ctx, f);
            return CBM_E_NOMEM;
        }
        f->samples = 0; /* exact values while tabulating */
        for (int i = 0; i < samples; i++)
            f->vals[i] = exact_value(f, (double)i / (double)(samples - 1), &f->basis_evals);
        f->samples = samples;
    }
    *Lp = L;
    return CBM_OK;
}

cbm_status cbm__func_read(cbm_context *ctx, const char *path, const char *text, int samples,
                          cbm__func *f)
{
    lines L = {text, 0};
    CBM_TRY(read_func(ctx, path, &L, samples, f));
    if (!f->name[0]) {
        /* the older format has no name: the file's, without directory and extension */
        const char *b = strrchr(path, '/');
        b = b ? b + 1 : path;
        size_t n = strcspn(b, ".");
        if (n >= sizeof f->name)
            n = sizeof f->name - 1;
        memcpy(f->name, b, n);
        f->name[n] = '\0';
    }
    return CBM_OK;
}

cbm_status cbm__funcset_read_gallery(cbm_context *ctx, const char *path, const char *text,
                                     cbm_funcset *fs)
{
    lines L = {text, 0};
    char buf[256];
    int vmaj, vmin, items;
    if (!next_line(&L, buf, sizeof buf) || sscanf(buf, "funcgalleryver %d %d", &vmaj, &vmin) != 2)
        return format_error(ctx, path, L.line, "expected 'funcgalleryver 1 1'");
    if (vmaj != 1 || vmin != 1)
        return format_error(ctx, path, L.line,
                            "unsupported function gallery version (expected 1 1)");
    if (!next_line(&L, buf, sizeof buf) || sscanf(buf, "items: %d", &items) != 1 || items < 0 ||
        items > 100000)
        return format_error(ctx, path, L.line, "expected 'items: N'");
    for (int i = 0; i < items; i++) {
        cbm__func f;
        cbm_status s = read_func(ctx, path, &L, -1, &f);
        if (s != CBM_OK)
            return s;
        if (CBM_ARRAY_PUSH(ctx, fs->funcs, f) != CBM_OK) {
            cbm__func_free(ctx, &f);
            return CBM_E_NOMEM;
        }
    }
    return CBM_OK;
}

/* ---- the set ---- */

double cbm__funcset_eval(const cbm_funcset *fs, int id, double x)
{
    if (!fs || id < 1 || (size_t)id > fs->funcs.len)
        return 0.0;
    return func_value(&fs->funcs.data[id - 1], x);
}

int cbm_funcset_find(const cbm_funcset *fs, const char *name)
{
    if (!fs || !name)
        return 0;
    for (size_t i = 0; i < fs->funcs.len; i++)
        if (strcmp(fs->funcs.data[i].name, name) == 0)
            return (int)i + 1;
    return 0;
}

double cbm_view_func_callback(void *view, int id, double x)
{
    const cbm_view *v = view;
    return v ? cbm__funcset_eval(&v->funcs, id, x) : 0.0;
}

int cbm_funcset_count(const cbm_funcset *fs)
{
    return fs ? (int)fs->funcs.len : 0;
}

double cbm_funcset_value(const cbm_funcset *fs, int id, double x)
{
    return cbm__funcset_eval(fs, id, x);
}
