/* cambium buckle: Taylor-Hell's self-weight buckling protocol (§6.3) for a vertical column of
 * given wood, radius and segment length, with Greenhill's critical length for comparison. The
 * method is described in src/mech/buckle.c and docs/buckle.md. */
#include "cli.h"
#include "commands.h"
#include "options.h"

#include <limits.h>
#include <math.h>
#include <string.h>

static void buckle_help(const cli_opts *t)
{
    printf("usage: cambium buckle --E PA --density KG_M3 --radius M --segment M [options]\n"
           "\n"
           "Grows a vertical column clamped at its base segment by segment, pushes it, and\n"
           "reports the first length at which it no longer returns upright (Taylor-Hell 2005,\n"
           "section 6.3), with Greenhill's critical length (7.837 E I / q)^(1/3).\n"
           "\n");
    cli_options_help(stdout, t);
}

/* A positive number. */
static bool parse_positive(const char *v, void *target, char *why, size_t n)
{
    double x;
    if (!cli_parse_double(v, &x))
        snprintf(why, n, "{opt}: '{value}' is not a number");
    else if (!(x > 0.0))
        snprintf(why, n, "{opt} must be positive (got {value})");
    else
        *(double *)target = x;
    return !*why;
}

int cmd_buckle(int argc, char **argv)
{
    cbm_buckle_def d = cbm_buckle_def_default();
    bool json = false, chain = false;
    long max_segments = (long)d.max_segments;
    cli_opt rows[] = {
        {.name = "--help|-h", .kind = CLI_HELP},
        {.name = "--E",
         .kind = CLI_CUSTOM,
         .target = &d.youngs_modulus,
         .parse = parse_positive,
         .required = true,
         .arg = "PA",
         .help = "Young's modulus (required)"},
        {.name = "--density",
         .kind = CLI_CUSTOM,
         .target = &d.density,
         .parse = parse_positive,
         .required = true,
         .arg = "KG_M3",
         .help = "wood density (required)"},
        {.name = "--radius",
         .kind = CLI_CUSTOM,
         .target = &d.radius,
         .parse = parse_positive,
         .required = true,
         .arg = "M",
         .help = "radius of the column (required)"},
        {.name = "--segment",
         .kind = CLI_CUSTOM,
         .target = &d.segment,
         .parse = parse_positive,
         .required = true,
         .arg = "M",
         .help = "segment length (required)"},
        {.name = "--G",
         .kind = CLI_CUSTOM,
         .target = &d.shear_modulus,
         .parse = parse_positive,
         .arg = "PA",
         .help = "shear modulus (default E/16)"},
        {.name = "--gravity",
         .kind = CLI_CUSTOM,
         .target = &d.gravity,
         .parse = parse_positive,
         .arg = "M_S2",
         .help = "gravitational acceleration (default 9.81)"},
        {.name = "--max-segments",
         .kind = CLI_LONG,
         .target = &max_segments,
         .min = 1,
         .max = LONG_MAX,
         .bad = "--max-segments: '{value}' is not a positive integer",
         .arg = "N",
         .help = "give up beyond N segments (default 100000)"},
        {.name = "--chain",
         .kind = CLI_SET,
         .target = &chain,
         .help = "the seeds' first-order discretisation (default staggered)"},
        {.name = "--json", .kind = CLI_SET, .target = &json, .help = "print one JSON object"},
        {0}};
    cli_opts table = {.cmd = "buckle",
                      .opts = rows,
                      .help = buckle_help,
                      .width = 18,
                      .unknown = "unknown option '{opt}' (see --help)",
                      .missing = "{opt} needs a value",
                      .required = "{opt} is required (see --help)"};
    int prc = cli_options_parse(&table, argc, argv);
    if (prc != CLI_OK)
        return prc == CLI_HELP_SHOWN ? CLI_OK : prc;
    d.max_segments = (size_t)max_segments;
    if (chain)
        d.discretization = CBM_MECH_CHAIN;
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
