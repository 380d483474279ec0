/* Benchmark of the L-system engine: derivation time and memory of the two reference runs of
 * the issue (quadratic Koch curve 8 steps, 31.2 M modules; ABOP fig. 2.8, 13 steps, 14.3 M
 * parametric modules), in double and float32 modes, and the Koch curve again inside a
 * sub-L-system call ?(1)...$ (kochsub: the same rewriting on the path that follows the L-system
 * of every module, so the difference to koch is that path's cost). Writes one CSV row per run to
 * the file given as argument (default bench_lsys.csv) and prints the rows. Not run by the tests.
 *
 *   build/bin/bench_lsys [out.csv [koch|fig28|fig28f|kochsub]]
 *
 * With a run named, only that run is made, so that the process's peak RSS is that run's.
 */
#define _POSIX_C_SOURCE 200809L
#include "cambium/cambium.h"
#include "bench_util.h"

#include <stdio.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>

static const char KOCH[] = "Lsystem: 1\nderivation length: 8\nAxiom: -F\n"
                           "F --> F+F-F-FF+F+F-F\nendlsystem\n";
static const char KOCHSUB[] = "Lsystem: 1\nderivation length: 8\nAxiom: ?(1)-F$\n"
                              "F --> F+F-F-FF+F+F-F\nendlsystem\n";
static const char FIG28[] =
    "#define d1 94.74\n#define d2 132.63\n#define a 18.95\n#define lr 1.109\n#define vr 1.732\n"
    "Lsystem: 1\nderivation length: 13\nAxiom: !(1)F(200)/(45)A\n"
    "A --> !(vr)F(50)[&(a)F(50)A]/(d1)[&(a)F(50)A]/(d2)[&(a)F(50)A]\n"
    "F(l) --> F(l*lr)\n!(w) --> !(w*vr)\nendlsystem\n";

static int run(FILE *csv, const char *name, const char *text, bool float32)
{
    cbm_context *ctx = NULL;
    cbm_context_def cd = cbm_context_def_default();
    if (cbm_context_create(&cd, &ctx) != CBM_OK)
        return 1;
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = name;
    def.text = text;
    def.float32 = float32;
    cbm_lsys *ls = NULL;
    double t0 = now();
    cbm_status s = cbm_lsys_load(ctx, &def, &ls);
    if (s == CBM_OK)
        s = cbm_lsys_reset(ls);
    for (int i = 0; s == CBM_OK && i < cbm_lsys_derivation_length(ls); i++)
        s = cbm_lsys_step(ls);
    double t1 = now();
    if (s != CBM_OK) {
        fprintf(stderr, "%s: %s\n", name, cbm_context_last_error(ctx));
        cbm_lsys_destroy(ls);
        cbm_context_destroy(ctx);
        return 1;
    }
    double mb = (double)cbm_context_peak_bytes(ctx) / 1e6;
    double bpm = (double)cbm_context_peak_bytes(ctx) / (double)cbm_lsys_module_count(ls);
    fprintf(csv, "%s,%s,%d,%zu,%zu,%.3f,%.1f,%.2f\n", name, float32 ? "float32" : "double",
            cbm_lsys_derivation_length(ls), cbm_lsys_module_count(ls), cbm_lsys_param_count(ls),
            t1 - t0, mb, bpm);
    printf("%-6s %-7s %2d steps %10zu modules %9zu params  %.3f s  peak %.1f MB (%.2f B/module)\n",
           name, float32 ? "float32" : "double", cbm_lsys_derivation_length(ls),
           cbm_lsys_module_count(ls), cbm_lsys_param_count(ls), t1 - t0, mb, bpm);
    cbm_lsys_destroy(ls);
    cbm_context_destroy(ctx);
    return 0;
}

int main(int argc, char **argv)
{
    const char *path = argc > 1 ? argv[1] : "bench_lsys.csv";
    FILE *csv = fopen(path, "w");
    if (!csv) {
        fprintf(stderr, "cannot write %s\n", path);
        return 1;
    }
    fprintf(csv, "model,mode,steps,modules,parameters,seconds,peak_mb,bytes_per_module\n");
    const char *only = argc > 2 ? argv[2] : NULL;
    int rc = 0;
    if (!only || !strcmp(only, "koch"))
        rc |= run(csv, "koch", KOCH, false);
    if (!only || !strcmp(only, "fig28"))
        rc |= run(csv, "fig28", FIG28, false);
    if (!only || !strcmp(only, "fig28f"))
        rc |= run(csv, "fig28", FIG28, true);
    if (!only || !strcmp(only, "kochsub"))
        rc |= run(csv, "kochsub", KOCHSUB, false);
    fclose(csv);
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    printf("process peak RSS %.1f MB (all runs)\n", (double)ru.ru_maxrss / 1024.0);
    return rc;
}
