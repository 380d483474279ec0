/* cambium buckle: Taylor-Hell's self-weight buckling protocol (§6.3) for a vertical column of
 * given wood, radius and segment length, with Greenhill's critical length for comparison. The
 * method is described in src/mech/buckle.c and docs/buckle.md. */
#include "cli.h"
#include "commands.h"

#include <math.h>
#include <string.h>

static void buckle_help(void)
{
    printf("usage: cambium buckle --E PA --density KG_M3 --radius M --segment M [options]\n"
           "\n"
           "Grows a vertical column clamped at its base segment by segment, pushes it, and\n"
           "reports the first length at which it no longer returns upright (Taylor-Hell 2005,\n"
           "section 6.3), with Greenhill's critical length (7.837 E I / q)^(1/3).\n"
           "\n"
           "  --E PA            Young's modulus (required)\n"
           "  --density KG_M3   wood density (required)\n"
           "  --radius M        radius of the column (required)\n"
           "  --segment M       segment length (required)\n"
           "  --G PA            shear modulus (default E/16)\n"
           "  --gravity M_S2    gravitational acceleration (default 9.81)\n"
           "  --max-segments N  give up beyond N segments (default 100000)\n"
           "  --chain           the seeds' first-order discretisation (default staggered)\n"
           "  --json            print one JSON object\n");
}

int cmd_buckle(int argc, char **argv)
{
    cbm_buckle_def d = cbm_buckle_def_default();
    bool json = false, have[4] = {false, false, false, false};
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            buckle_help();
            return CLI_OK;
        }
        if (!strcmp(a, "--json")) {
            json = true;
            continue;
        }
        if (!strcmp(a, "--chain")) {
            d.discretization = CBM_MECH_CHAIN;
            continue;
        }
        static const char *const opts[] = {"--E", "--density", "--radius",      "--segment",
                                           "--G", "--gravity", "--max-segments"};
        int k = -1;
        for (int j = 0; j < 7; j++)
            if (!strcmp(a, opts[j]))
                k = j;
        if (k < 0)
            return cli_usage_error("buckle", "unknown option '%s' (see --help)", a);
        if (i + 1 >= argc)
            return cli_usage_error("buckle", "%s needs a value", a);
        const char *v = argv[++i];
        if (k == 6) {
            long n;
            if (!cli_parse_long(v, &n) || n < 1)
                return cli_usage_error("buckle", "--max-segments: '%s' is not a positive integer",
                                       v);
            d.max_segments = (size_t)n;
            continue;
        }
        double x;
        if (!cli_parse_double(v, &x))
            return cli_usage_error("buckle", "%s: '%s' is not a number", a, v);
        bool pos = x > 0.0;
        switch (k) {
        case 0:
            d.youngs_modulus = x;
            break;
        case 1:
            d.density = x;
            break;
        case 2:
            d.radius = x;
            break;
        case 3:
            d.segment = x;
            break;
        case 4:
            d.shear_modulus = x;
            break;
        default:
            d.gravity = x;
            break;
        }
        if (!pos)
            return cli_usage_error("buckle", "%s must be positive (got %s)", a, v);
        if (k < 4)
            have[k] = true;
    }
    static const char *const req[] = {"--E", "--density", "--radius", "--segment"};
    for (int k = 0; k < 4; k++)
        if (!have[k])
            return cli_usage_error("buckle", "%s is required (see --help)", req[k]);
    cbm_context *ctx = cli_context();
    cbm_buckle_result r;
    cbm_status s = cbm_mech_buckle(ctx, &d, &r);
    if (s != CBM_OK) {
        int rc = cli_fail(ctx, s, "buckle");
        cli_context_end(ctx);
        return rc;
    }
    if (json)
        printf("{\"buckling_length_m\": %.6f, \"greenhill_length_m\": %.6f, \"segments\": %zu, "
               "\"segment_m\": %.9g, \"growth_factor\": %.9f, \"last_stable_factor\": %.9f, "
               "\"discretization\": \"%s\", \"passes\": %zu}\n",
               r.buckling_length, r.greenhill_length, r.segments, d.segment, r.growth_factor,
               r.last_stable_factor, cbm_mech_discretization_name(d.discretization), r.passes);
    else
        printf("buckling length  %.4f m  (%zu segment%s of %g m; perturbation factor %.6f, "
               "%.6f one segment shorter)\n"
               "Greenhill length %.4f m  (7.837 E I / q)^(1/3)\n",
               r.buckling_length, r.segments, r.segments == 1 ? "" : "s", d.segment,
               r.growth_factor, r.last_stable_factor, r.greenhill_length);
    cli_context_end(ctx);
    return CLI_OK;
}
