/* Progress line of long runs: "[#####.....]  42%  step 21/50  1.2e+05 modules  37 passes
 * ETA 1m05s". The time left is extrapolated linearly from the mean time per finished step.
 * The library only formats the line; the tool decides whether to print it (only to a terminal). */
#include "core.h"

#include "cambium/write.h"

#include <math.h>
#include <stdio.h>

static void duration(double s, char *buf, size_t n)
{
    if (!(s >= 0) || s > 3.6e6) {
        snprintf(buf, n, "?");
        return;
    }
    long t = lround(s);
    if (t >= 3600)
        snprintf(buf, n, "%ldh%02ldm", t / 3600, (t / 60) % 60);
    else if (t >= 60)
        snprintf(buf, n, "%ldm%02lds", t / 60, t % 60);
    else
        snprintf(buf, n, "%lds", t);
}

size_t cbm_progress_format(const cbm_progress *p, int width, char *buf, size_t size)
{
    if (!buf || size == 0)
        return 0;
    buf[0] = '\0';
    if (!p)
        return 0;
    if (width < 20)
        width = 20;
    if ((size_t)width >= size)
        width = (int)size - 1;
    double frac = p->steps ? (double)p->step / (double)p->steps : 0.0;
    if (frac > 1)
        frac = 1;
    char tail[160], left[32] = "?", mods[32];
    if (p->step > 0 && p->steps >= p->step && p->elapsed >= 0)
        duration(p->elapsed / (double)p->step * (double)(p->steps - p->step), left, sizeof left);
    if (p->modules >= 100000)
        snprintf(mods, sizeof mods, "%.3g", (double)p->modules);
    else
        snprintf(mods, sizeof mods, "%zu", p->modules);
    /* runs without mechanics (plain L-systems) have no equilibrium passes to show */
    char passes[40] = "";
    if (p->passes > 0)
        snprintf(passes, sizeof passes, "  %zu passes", p->passes);
    int n = snprintf(tail, sizeof tail, " %3d%%  step %zu/%zu  %s modules%s  left %s",
                     (int)floor(100.0 * frac), p->step, p->steps, mods, passes, left);
    if (n < 0)
        return 0;
    int bar = width - n - 2;
    if (bar < 5) {
        /* too narrow for a bar: the numbers alone, cut to width */
        snprintf(buf, (size_t)width + 1, "%s", tail + 1);
        return strlen(buf);
    }
    size_t k = 0;
    buf[k++] = '[';
    int fill = (int)floor(frac * bar);
    for (int i = 0; i < bar; i++)
        buf[k++] = i < fill ? '#' : '.';
    buf[k++] = ']';
    snprintf(buf + k, size - k, "%s", tail);
    return strlen(buf);
}
