/* What `cambium grow` shares between its two model families (cli_grow.h). */
#include "cli_grow.h"

#include "cli.h"

#include <stdio.h>
#include <string.h>

bool cli_grow_ends_with(const char *s, const char *suf)
{
    size_t a = strlen(s), b = strlen(suf);
    return a >= b && !strcmp(s + a - b, suf);
}

static bool parse_model(const char *a, void *target, char *why, size_t n)
{
    const char **model = target;
    if (!strcmp(a, "-"))
        snprintf(why, n, "unknown option {value}");
    else if (*model)
        snprintf(why, n, "more than one model: '%s' and '{value}'", *model);
    else
        *model = a;
    return !*why;
}

cli_opt cli_grow_model_row(const char **model)
{
    return (cli_opt){
        .name = "MODEL", .kind = CLI_POSITIONAL, .target = model, .parse = parse_model};
}

cli_opt cli_grow_years_row(long *years)
{
    return (cli_opt){.name = "-y|-n|--years",
                     .kind = CLI_LONG,
                     .target = years,
                     .min = 0,
                     .max = 1000,
                     .bad = "{opt} must be 0..1000",
                     .arg = "N",
                     .help = "years to grow (default: the model's 'years')"};
}

cli_opt cli_grow_defines_row(cli_list *defs, const char *help)
{
    return (cli_opt){.name = "-D",
                     .kind = CLI_LIST,
                     .target = defs,
                     .attached = true,
                     .arg = "NAME=VALUE",
                     .help = help};
}

cli_opt cli_grow_params_row(bool *params)
{
    return (cli_opt){.name = "--params",
                     .kind = CLI_SET,
                     .target = params,
                     .help = "print every parameter (parameter-file syntax) and exit"};
}

const char *cli_grow_define(const char *word, char *name, size_t n)
{
    const char *eq = strchr(word, '=');
    if (!eq || eq == word || (size_t)(eq - word) >= n) {
        cli_usage_error("grow", "-D expects NAME=VALUE, got '%s'", word);
        return NULL;
    }
    memcpy(name, word, (size_t)(eq - word));
    name[eq - word] = '\0';
    return eq + 1;
}

void cli_grow_help(const cli_opts *t, const char *text, const char *const *builtin)
{
    fputs(text, stdout);
    cli_options_rows(stdout, t);
    printf("\nbuilt-in models:");
    for (const char *const *n = builtin; *n; n++)
        printf(" %s", *n);
    printf("\n");
    cli_options_groups(stdout, t);
}
