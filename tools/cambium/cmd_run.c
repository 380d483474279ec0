/* cambium run MODEL.l [SIDE FILES...] [-n STEPS] [-D NAME=VALUE]... [--seed N] [-o OUT]...
 *                     [--every K] [--homomorphism] [--float32] [--max-modules N]
 *
 * Loads a cpfg-dialect model, derives it for its derivation length (or -n STEPS) and writes the
 * requested outputs. Outputs are chosen by extension in one table (OUTPUTS) so writers of other
 * formats plug in there; side files are sorted by extension in SIDE_KINDS. With --every K the
 * outputs are also written after every K-th step as NAME-STEP.EXT. When a limit stops the
 * derivation, the outputs of the last complete step are written and the exit status is 1.
 */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "commands.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

typedef struct run_opts {
    bool homomorphism;
} run_opts;

typedef cbm_status (*output_fn)(cbm_context *ctx, cbm_lsys *ls, const run_opts *o, cbm_out *out);

static cbm_status out_str(cbm_context *ctx, cbm_lsys *ls, const run_opts *o, cbm_out *out)
{
    (void)ctx;
    if (o->homomorphism) {
        cbm_status s = cbm_lsys_apply_homomorphism(ls);
        if (s != CBM_OK)
            return s;
    }
    return cbm_lsys_write_str(ls, o->homomorphism, out);
}

/* The output formats by extension. */
static const struct {
    const char *ext;
    output_fn fn;
    const char *what;
} OUTPUTS[] = {
    {"str", out_str, "the derived string, one module per line, parameters as %.9g"},
};

/* Side files by extension (read by the turtle and the function evaluator). */
static const char *const SIDE_KINDS[] = {"v", "func", "fset", "s", "map", "mat", "a", "e", "txt"};

static output_fn find_output(const char *path)
{
    const char *ext = cli_extension(path);
    for (size_t i = 0; i < sizeof OUTPUTS / sizeof OUTPUTS[0]; i++)
        if (!strcmp(ext, OUTPUTS[i].ext))
            return OUTPUTS[i].fn;
    return NULL;
}

static void usage(void)
{
    printf("usage: cambium run MODEL.l [SIDE FILES...] [-n STEPS] [-D NAME=VALUE]... [--seed N]\n"
           "                  [-o OUT]... [--every K] [--homomorphism] [--float32]\n"
           "                  [--max-modules N]\n\n"
           "Derives a cpfg-dialect L-system. Without -o prints a one-line summary.\n"
           "  -n STEPS          derivation steps (default: the model's derivation length)\n"
           "  -D NAME=VALUE     overrides the model's #define NAME\n"
           "  --seed N          seed of stochastic production choice (srand48(N))\n"
           "  -o OUT            output, by extension:\n");
    for (size_t i = 0; i < sizeof OUTPUTS / sizeof OUTPUTS[0]; i++)
        printf("                      .%-5s %s\n", OUTPUTS[i].ext, OUTPUTS[i].what);
    printf("  --every K         also write the outputs after every K-th step as NAME-STEP.EXT\n"
           "  --homomorphism    write the string after the homomorphism\n"
           "  --float32         follow cpfg exactly: float32 parameters, seed: ignored as in\n"
           "                    cpfg's batch mode\n"
           "  --max-modules N   stop when the string would exceed N modules\n");
}

static char *step_path(const char *path, int step)
{
    const char *dot = strrchr(path, '.');
    const char *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash))
        dot = path + strlen(path);
    size_t n = strlen(path) + 16;
    char *p = malloc(n);
    if (p)
        snprintf(p, n, "%.*s-%04d%s", (int)(dot - path), path, step, dot);
    return p;
}

static int write_outputs(cbm_context *ctx, cbm_lsys *ls, const run_opts *o, char **outs, int nouts,
                         int step)
{
    for (int i = 0; i < nouts; i++) {
        char *path = step >= 0 ? step_path(outs[i], step) : outs[i];
        if (!path)
            return cli_fail(ctx, CBM_E_NOMEM, "output");
        cbm_out *out = NULL;
        cbm_status s = cbm_out_open(ctx, path, &out);
        if (s == CBM_OK) {
            s = find_output(outs[i])(ctx, ls, o, out);
            if (s == CBM_OK)
                s = cbm_out_commit(out);
            else
                cbm_out_abort(out);
        }
        int rc = s == CBM_OK ? CLI_OK : cli_fail(ctx, s, path);
        if (step >= 0)
            free(path);
        if (rc != CLI_OK)
            return rc;
    }
    return CLI_OK;
}

int cmd_run(int argc, char **argv)
{
    const char *model = NULL;
    const char *defines[256];
    size_t ndefines = 0;
    char *outs[64];
    int nouts = 0;
    long steps = -1, every = 0, seed = -1, max_modules = 0;
    run_opts o = {0};
    bool float32 = false;
    int nside = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        bool has_next = i + 1 < argc;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage();
            return CLI_OK;
        } else if (!strcmp(a, "-n") || !strcmp(a, "--every") || !strcmp(a, "--seed") ||
                   !strcmp(a, "--max-modules")) {
            long v;
            if (!has_next || !cli_parse_long(argv[i + 1], &v) || v < 0)
                return cli_usage_error("run", "%s expects a non-negative integer", a);
            i++;
            if (!strcmp(a, "-n"))
                steps = v;
            else if (!strcmp(a, "--every"))
                every = v;
            else if (!strcmp(a, "--seed"))
                seed = v;
            else
                max_modules = v;
        } else if (!strncmp(a, "-D", 2)) {
            const char *d = a[2] ? a + 2 : (has_next ? argv[++i] : NULL);
            if (!d || !*d || *d == '=' || ndefines >= 256)
                return cli_usage_error("run", "-D expects NAME=VALUE");
            defines[ndefines++] = d;
        } else if (!strcmp(a, "-o")) {
            if (!has_next)
                return cli_usage_error("run", "-o expects a file name");
            if (!find_output(argv[i + 1]))
                return cli_usage_error("run", "no writer for '.%s' output (%s)",
                                       cli_extension(argv[i + 1]), argv[i + 1]);
            if (nouts >= 64)
                return cli_usage_error("run", "too many outputs");
            outs[nouts++] = argv[++i];
        } else if (!strcmp(a, "--homomorphism")) {
            o.homomorphism = true;
        } else if (!strcmp(a, "--float32")) {
            float32 = true;
        } else if (a[0] == '-') {
            return cli_usage_error("run", "unknown option '%s'", a);
        } else if (!model && !strcmp(cli_extension(a), "l")) {
            model = a;
        } else {
            bool known = false;
            for (size_t k = 0; k < sizeof SIDE_KINDS / sizeof SIDE_KINDS[0]; k++)
                if (!strcmp(cli_extension(a), SIDE_KINDS[k]))
                    known = true;
            if (!known)
                return cli_usage_error("run", "'%s': not a model (.l) or a known side file", a);
            FILE *f = fopen(a, "rb");
            if (!f) {
                fprintf(stderr, "cambium: %s: cannot open\n", a);
                return CLI_FAIL;
            }
            fclose(f);
            nside++;
        }
    }
    if (!model)
        return cli_usage_error("run", "expected a MODEL.l");
    cbm_context *ctx = cli_context();
    if (max_modules > 0) {
        cbm_limits lim = *cbm_context_limits(ctx);
        lim.max_modules = (size_t)max_modules;
        cbm_context_set_limits(ctx, &lim);
    }
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = model;
    def.defines = defines;
    def.define_count = ndefines;
    def.float32 = float32;
    def.ignore_seed = float32;
    def.seed = seed;
    cbm_lsys *ls = NULL;
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    cbm_status s = cbm_lsys_load(ctx, &def, &ls);
    if (s != CBM_OK) {
        int rc = cli_fail(ctx, s, model);
        cli_context_end(ctx);
        return rc;
    }
    int n = steps >= 0 ? (int)steps : cbm_lsys_derivation_length(ls);
    int rc = CLI_OK;
    s = cbm_lsys_reset(ls);
    if (s == CBM_OK && every > 0)
        rc = write_outputs(ctx, ls, &o, outs, nouts, 0);
    int done = 0;
    bool progress = isatty(2);
    while (s == CBM_OK && rc == CLI_OK && done < n && !cbm_lsys_stopped(ls)) {
        s = cbm_lsys_step(ls);
        if (s != CBM_OK)
            break;
        done++;
        if (progress)
            fprintf(stderr, "\rstep %d/%d, %zu modules ", done, n, cbm_lsys_module_count(ls));
        if (every > 0 && done % every == 0)
            rc = write_outputs(ctx, ls, &o, outs, nouts, done);
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    if (progress && done > 0)
        fputc('\n', stderr);
    if (s != CBM_OK) {
        rc = cli_fail(ctx, s, model);
        if (s == CBM_E_LIMIT && nouts) {
            fprintf(stderr, "cambium: writing the string of step %d, the last complete one\n",
                    done);
            write_outputs(ctx, ls, &o, outs, nouts, -1);
        }
    } else if (rc == CLI_OK) {
        rc = write_outputs(ctx, ls, &o, outs, nouts, -1);
        if (rc == CLI_OK && nouts == 0) {
            double secs =
                (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
            printf("%s: %d steps, %zu modules, %zu parameters, %d side file%s, %.3f s\n", model,
                   done, cbm_lsys_module_count(ls), cbm_lsys_param_count(ls), nside,
                   nside == 1 ? "" : "s", secs);
        }
    }
    cbm_lsys_destroy(ls);
    cli_context_end(ctx);
    return rc;
}
