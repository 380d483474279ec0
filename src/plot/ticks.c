/* Axis ticks with nice numbers, and their labels.
 *
 * Linear axes follow Heckbert's "nice numbers for graph labels" (Graphics Gems, 1990) with the
 * step set {1, 2, 2.5, 5} x 10^k: the step is the smallest of these at least (hi - lo) / target,
 * so there are about `target` intervals. Tick values are computed as integer multiples of the
 * step (k * step, not by accumulation) so labels do not drift (0.30000000000000004). The range
 * is rounded out to the ticks ("loose" labelling) when it comes from the data. Log axes tick
 * the powers of ten, every k-th one when there are more decades than the target, and 1-2-5 in
 * each decade when the range spans less than two. */
#include "plot_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define REL_EPS 1e-9

/* The nice step for a span cut in about `target` intervals, and its mantissa (1, 2, 2.5, 5). */
static double nice_step(double span, int target, double *mantissa)
{
    if (target < 1)
        target = 1;
    double raw = span / target;
    double e = floor(log10(raw));
    double p = pow(10.0, e);
    static const double m[] = {1.0, 2.0, 2.5, 5.0, 10.0};
    for (int i = 0; i < 5; i++)
        if (m[i] * p >= raw * (1.0 - REL_EPS)) {
            *mantissa = m[i] == 10.0 ? 1.0 : m[i];
            return m[i] * p;
        }
    *mantissa = 1.0;
    return 10.0 * p;
}

static bool is_range(double lo, double hi, bool log)
{
    return isfinite(lo) && isfinite(hi) && lo < hi && (!log || lo > 0);
}

size_t cbm_plot_ticks(double lo, double hi, int target, bool log, double *ticks, size_t max)
{
    if (!ticks || max == 0 || !is_range(lo, hi, log))
        return 0;
    size_t n = 0;
    if (!log) {
        double mant, step = nice_step(hi - lo, target, &mant);
        double tol = REL_EPS * (hi - lo);
        double k0 = ceil((lo - tol) / step), k1 = floor((hi + tol) / step);
        for (double k = k0; k <= k1 && n < max; k++) {
            double v = k * step;
            ticks[n++] = fabs(v) < 1e-12 * step ? 0.0 : v;
        }
        return n;
    }
    double d0 = floor(log10(lo) + REL_EPS), d1 = floor(log10(hi) + REL_EPS);
    double decades = log10(hi) - log10(lo);
    if (decades < 2.0) {
        static const double sub[] = {1.0, 2.0, 5.0};
        for (double d = d0; d <= d1 && n < max; d++)
            for (int i = 0; i < 3 && n < max; i++) {
                double v = sub[i] * pow(10.0, d);
                if (v >= lo * (1 - REL_EPS) && v <= hi * (1 + REL_EPS))
                    ticks[n++] = v;
            }
        return n;
    }
    double every = ceil((d1 - d0 + 1.0) / (target < 1 ? 1 : target));
    if (every < 1)
        every = 1;
    /* from the first power of ten in the range, so a range rounded out to decades is labelled
     * at both ends when the count allows */
    if (pow(10.0, d0) < lo * (1 - REL_EPS))
        d0 += 1.0;
    for (double d = d0; d <= d1 && n < max; d += every)
        ticks[n++] = pow(10.0, d);
    return n;
}

void cbm_plot_nice_range(double *lo, double *hi, int target, bool log)
{
    double a = *lo, b = *hi;
    if (log) {
        if (!(a > 0) || !isfinite(a) || !isfinite(b) || !(b > 0)) {
            *lo = 1.0, *hi = 10.0;
            return;
        }
        if (a == b)
            a /= 2.0, b *= 2.0;
        /* whole decades, or (for less than two) the enclosing 1-2-5 values */
        double d0 = floor(log10(a) + REL_EPS), d1 = ceil(log10(b) - REL_EPS);
        if (log10(b) - log10(a) >= 2.0) {
            *lo = pow(10.0, d0), *hi = pow(10.0, d1);
            return;
        }
        static const double sub[] = {1.0, 2.0, 5.0, 10.0};
        double l = pow(10.0, d0), h = pow(10.0, d1);
        for (int i = 0; i < 4; i++) {
            double v = sub[i] * pow(10.0, d0);
            if (v <= a * (1 + REL_EPS))
                l = v;
        }
        double top = pow(10.0, d1 - 1.0);
        for (int i = 3; i >= 0; i--) {
            double v = sub[i] * top;
            if (v >= b * (1 - REL_EPS))
                h = v;
        }
        *lo = l, *hi = h;
        return;
    }
    if (!isfinite(a) || !isfinite(b)) {
        *lo = 0.0, *hi = 1.0;
        return;
    }
    if (a > b) {
        double t = a;
        a = b, b = t;
    }
    if (a == b) {
        double w = a == 0.0 ? 1.0 : 0.1 * fabs(a);
        a -= w, b += w;
    }
    double mant, step = nice_step(b - a, target, &mant);
    double tol = REL_EPS * (b - a);
    double l = floor((a + tol) / step) * step, h = ceil((b - tol) / step) * step;
    /* The rounded range is wider than the data, so its ticks (cbm_plot_ticks on [l, h]) may
     * take a coarser step and end short of h: data between the last tick and the frame looked
     * cut (0.79 on an axis ticked to 0.75 and framed at 0.8). Round out again to the step of
     * the ticks with the next nice step until the range's own ticks take that step (a few
     * mantissas at most: a step of at least the span / target rounds to a span that keeps it). */
    for (int it = 0; it < 8; it++) {
        double s2 = nice_step(h - l, target, &mant);
        if (fabs(s2 - step) <= REL_EPS * step)
            break;
        step = nice_step(step * target * (1.0 + 1e-6), target, &mant);
        l = floor((a + tol) / step) * step;
        h = ceil((b - tol) / step) * step;
    }
    *lo = l;
    *hi = h;
}

/* Decimals that tell apart ticks `step` apart: -floor(log10 step), one more for a mantissa of
 * 2.5 (and 0 for steps of 1 or more). */
static int decimals_for(double step)
{
    double e = floor(log10(step) + REL_EPS);
    double m = step / pow(10.0, e);
    int d = (int)-e + (fabs(m - 2.5) < 1e-6 ? 1 : 0);
    return d < 0 ? 0 : d;
}

void cbm_plot_tick_labels(const double *ticks, size_t n, bool log, char *labels, size_t label_size)
{
    if (!ticks || !labels || label_size == 0)
        return;
    double big = 0.0, step = INFINITY;
    for (size_t i = 0; i < n; i++) {
        big = fmax(big, fabs(ticks[i]));
        if (i > 0)
            step = fmin(step, fabs(ticks[i] - ticks[i - 1]));
    }
    if (!isfinite(step) || step == 0.0)
        step = big > 0 ? big : 1.0;
    bool expo = big >= 1e6 || (big > 0 && big < 1e-3);
    /* exponent form: the significant digits that tell apart ticks a step apart */
    int sig = 1;
    if (expo) {
        double sd = floor(log10(step) + REL_EPS);
        sig = (int)(floor(log10(big) + REL_EPS) - sd) + 1 + (decimals_for(step / pow(10.0, sd)));
        sig = sig < 1 ? 1 : sig > 15 ? 15 : sig;
    }
    for (size_t i = 0; i < n; i++) {
        char *out = labels + i * label_size;
        double v = ticks[i];
        if (log) {
            double e = round(log10(v));
            if (fabs(v - pow(10.0, e)) <= 1e-9 * v && (e < -3 || e > 5))
                snprintf(out, label_size, "1e%d", (int)e);
            else if (v >= 1e-3 && v < 1e6)
                snprintf(out, label_size, "%g", v);
            else
                snprintf(out, label_size, "%.0e", v);
            continue;
        }
        if (expo) {
            if (v == 0.0)
                snprintf(out, label_size, "0");
            else
                snprintf(out, label_size, "%.*e", sig - 1, v);
            continue;
        }
        int d = decimals_for(step);
        snprintf(out, label_size, "%.*f", d, v);
        /* no "-0", "-0.00" */
        bool zero = true;
        for (const char *c = out; *c; c++)
            if (*c >= '1' && *c <= '9')
                zero = false;
        if (zero)
            snprintf(out, label_size, "%.*f", d, 0.0);
    }
}
