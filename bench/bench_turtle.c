/* Benchmark of the turtle: interprets the quadratic Koch curve (ABOP fig. 1.9b, axiom F,
 * F -> F+F-F-FF+F+F-F, as cpfg's cpfg-quadratic-koch example with axiom -F) after n steps,
 * module by module as the L-system engine does (cbm__turtle_feed on the symbols, or
 * cbm__turtle_exec on commands looked up once), without a scene, with the primitive record, and
 * (for smaller n) into a scene. Prints one CSV line per run:
 * what,steps,modules,seconds,ns_per_module,peak_bytes.
 * Usage: bench_turtle [max_steps (default 7)] [exec: only the plain exec runs, for profiling] */
#define _POSIX_C_SOURCE 200809L
#include "bench_util.h"
#include "turtle/view_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <time.h>

/* The Koch string after n steps, as turtle commands. */
static unsigned char *koch(int n, size_t *len)
{
    static const char rule[] = "F+F-F-FF+F+F-F";
    size_t fcount = 1, other = 1; /* axiom -F */
    for (int i = 0; i < n; i++) {
        other += fcount * 6;
        fcount *= 8;
    }
    size_t total = fcount + other;
    unsigned char *s = malloc(total);
    unsigned char *tmp = malloc(total);
    if (!s || !tmp)
        exit(1);
    size_t m = 0;
    s[m++] = '-';
    s[m++] = 'F';
    for (int i = 0; i < n; i++) {
        size_t k = 0;
        for (size_t j = 0; j < m; j++) {
            if (s[j] == 'F') {
                memcpy(tmp + k, rule, sizeof rule - 1);
                k += sizeof rule - 1;
            } else {
                tmp[k++] = s[j];
            }
        }
        unsigned char *x = s;
        s = tmp;
        tmp = x;
        m = k;
    }
    free(tmp);
    *len = m;
    return s;
}

static void run(const char *what, int steps, const unsigned char *cmds, size_t n, bool record,
                bool with_scene, bool feed)
{
    cbm_context_def def = cbm_context_def_default();
    def.limits.max_bytes = 0;
    cbm_context *ctx;
    if (cbm_context_create(&def, &ctx) != CBM_OK)
        exit(1);
    cbm_view *view;
    cbm_view_create(ctx, &view);
    view->angle = 90;
    view->sin_a = 1.0;
    view->cos_a = 0.0;
    view->line_style = CBM__LS_CYLINDER;
    cbm_scene *scene = NULL;
    if (with_scene)
        cbm_scene_create(ctx, &scene);
    cbm_turtle *t;
    cbm__turtle_create(ctx, view, scene, &t);
    cbm__turtle_set_record(t, record);
    double t0 = now();
    cbm_status s = CBM_OK;
    if (feed) {
        /* the symbols as the engine holds them: the turtle looks each one up */
        for (size_t i = 0; i < n && s == CBM_OK; i++)
            s = cbm__turtle_feed(t, cmds[i], NULL, 0);
    } else {
        for (size_t i = 0; i < n && s == CBM_OK; i++)
            s = cbm__turtle_exec(t, cmds[i], NULL, 0);
    }
    if (s == CBM_OK)
        s = cbm__turtle_finish(t);
    double dt = now() - t0;
    printf("%s,%d,%zu,%.4f,%.2f,%zu%s\n", what, steps, n, dt, 1e9 * dt / (double)n,
           cbm_context_peak_bytes(ctx), s == CBM_OK ? "" : ",FAILED");
    cbm__turtle_destroy(t);
    cbm_scene_destroy(scene);
    cbm_view_destroy(view);
    cbm_context_destroy(ctx);
}

int main(int argc, char **argv)
{
    int max = argc > 1 ? atoi(argv[1]) : 7;
    bool only_exec = argc > 2 && strcmp(argv[2], "exec") == 0; /* for profiling */
    if (max < 1 || max > 9)
        max = 7;
    printf("what,steps,modules,seconds,ns_per_module,peak_bytes\n");
    for (int n = max - 2; n <= max; n++) {
        size_t len;
        unsigned char *syms = koch(n, &len);
        if (!only_exec)
            run("feed", n, syms, len, false, false, true);
        unsigned char *cmds = malloc(len);
        for (size_t j = 0; j < len; j++)
            cmds[j] = (unsigned char)cbm__turtle_lookup((const char *)&syms[j], 1);
        run("exec", n, cmds, len, false, false, false);
        if (!only_exec)
            run("exec+record", n, cmds, len, true, false, false);
        if (n <= 6 && !only_exec)
            run("exec+scene", n, cmds, len, false, true, false);
        free(cmds);
        free(syms);
    }
    return 0;
}
