/* The table-driven option parser of the tool (options.h). */
#include "options.h"

#include "cli.h"

#include <string.h>

/* A template with {opt}, {value} and {max} filled in. */
static void fill(char *out, size_t n, const char *tmpl, const char *opt, const char *value, int max)
{
    size_t k = 0;
    for (const char *p = tmpl; *p && k + 1 < n;) {
        const char *sub = NULL;
        char num[24];
        if (!strncmp(p, "{opt}", 5)) {
            sub = opt, p += 5;
        } else if (!strncmp(p, "{value}", 7)) {
            sub = value ? value : "", p += 7;
        } else if (!strncmp(p, "{max}", 5)) {
            snprintf(num, sizeof num, "%d", max);
            sub = num, p += 5;
        }
        if (sub) {
            size_t m = strlen(sub);
            if (m > n - 1 - k)
                m = n - 1 - k;
            memcpy(out + k, sub, m);
            k += m;
        } else {
            out[k++] = *p++;
        }
    }
    out[k] = '\0';
}

static int usage(const char *cmd, const char *tmpl, const char *opt, const char *value, int max)
{
    char msg[1024];
    fill(msg, sizeof msg, tmpl, opt, value, max);
    return cli_usage_error(cmd, "%s", msg);
}

/* Whether word is one of the '|'-separated names. */
static bool named(const char *names, const char *word)
{
    size_t n = strlen(word);
    for (const char *p = names; p && *p;) {
        const char *bar = strchr(p, '|');
        size_t len = bar ? (size_t)(bar - p) : strlen(p);
        if (len == n && !strncmp(p, word, n))
            return true;
        p = bar ? bar + 1 : NULL;
    }
    return false;
}

/* The row of t (or of its groups) that word names, with the table it belongs to; with
 * `attached`, a row "-D" also matches "-DNAME=VALUE" (*value then points after the name). */
static cli_opt *find(cli_opts *t, const char *word, cli_opts **owner, const char **value)
{
    for (cli_opt *o = t->opts; o->kind != CLI_END; o++) {
        if (o->kind == CLI_GROUP) {
            cli_opt *g = find(o->target, word, owner, value);
            if (g)
                return g;
            continue;
        }
        if (o->kind == CLI_DOC || o->kind == CLI_POSITIONAL)
            continue;
        size_t n = strlen(o->name);
        if (named(o->name, word) ||
            (o->attached && !strncmp(word, o->name, n) && word[n] && word[0] == '-')) {
            *owner = t;
            *value = named(o->name, word) ? NULL : word + n;
            return o;
        }
    }
    return NULL;
}

static cli_opt *positional(cli_opts *t)
{
    for (cli_opt *o = t->opts; o->kind != CLI_END; o++)
        if (o->kind == CLI_POSITIONAL)
            return o;
    return NULL;
}

/* Stores value through row o of table t: CLI_OK or the usage error (printed for cmd). */
static int store(const char *cmd, const cli_opts *t, cli_opt *o, const char *word,
                 const char *value)
{
    const char *bad = o->bad ? o->bad : t->missing ? t->missing : t->unknown;
    switch (o->kind) {
    case CLI_LONG:
    case CLI_INT: {
        long v;
        if (!cli_parse_long(value, &v) || v < o->min || v > o->max)
            return usage(cmd, bad, word, value, 0);
        if (o->kind == CLI_LONG)
            *(long *)o->target = v;
        else
            *(int *)o->target = (int)v;
        return CLI_OK;
    }
    case CLI_TEXT:
        *(const char **)o->target = value;
        return CLI_OK;
    case CLI_LIST: {
        cli_list *l = o->target;
        if (!cli_list_add(l, value))
            return usage(cmd, l->full, word, value, l->max);
        return CLI_OK;
    }
    default: { /* CLI_CUSTOM, CLI_POSITIONAL */
        char why[512] = "";
        if (!o->parse(value, o->target, why, sizeof why))
            return usage(cmd, *why ? why : bad, word, value, 0);
        return CLI_OK;
    }
    }
}

/* The first required row of t (or its groups) not given, or NULL. */
static const cli_opt *absent(const cli_opts *t, const cli_opts **owner)
{
    for (const cli_opt *o = t->opts; o->kind != CLI_END; o++) {
        if (o->kind == CLI_GROUP) {
            const cli_opt *g = absent(o->target, owner);
            if (g)
                return g;
        } else if (o->required && !o->seen) {
            *owner = t;
            return o;
        }
    }
    return NULL;
}

int cli_options_parse(cli_opts *t, int argc, char **argv)
{
    for (int i = 1; i < argc; i++) {
        const char *word = argv[i];
        if (word[0] != '-' || !word[1]) {
            cli_opt *p = positional(t);
            if (!p)
                return usage(t->cmd,
                             i + 1 >= argc && t->unknown_last ? t->unknown_last : t->unknown, word,
                             NULL, 0);
            int rc = store(t->cmd, t, p, word, word);
            if (rc != CLI_OK)
                return rc;
            continue;
        }
        cli_opts *owner = NULL;
        const char *value = NULL;
        cli_opt *o = find(t, word, &owner, &value);
        if (!o)
            return usage(t->cmd, i + 1 >= argc && t->unknown_last ? t->unknown_last : t->unknown,
                         word, NULL, 0);
        o->seen = true;
        if (o->kind == CLI_HELP) {
            t->help(t);
            return CLI_HELP_SHOWN;
        }
        if (o->kind == CLI_SET || o->kind == CLI_CLEAR) {
            *(bool *)o->target = o->kind == CLI_SET;
            continue;
        }
        if (!value) {
            if (i + 1 >= argc) {
                const char *m = owner->missing ? owner->missing : o->bad ? o->bad : owner->unknown;
                return usage(t->cmd, m, word, NULL, 0);
            }
            value = argv[++i];
        }
        int rc = store(t->cmd, owner, o, word, value);
        if (rc != CLI_OK)
            return rc;
    }
    const cli_opts *owner = NULL;
    const cli_opt *o = absent(t, &owner);
    if (o)
        return usage(t->cmd, owner->required, o->name, NULL, 0);
    return CLI_OK;
}

int cli_options_next_word(cli_opts *t, int argc, char **argv, int from)
{
    for (int i = from; i < argc; i++) {
        const char *word = argv[i];
        if (word[0] != '-' || !word[1])
            return i;
        cli_opts *owner = NULL;
        const char *value = NULL;
        const cli_opt *o = find(t, word, &owner, &value);
        if (o && !value && o->kind != CLI_HELP && o->kind != CLI_SET && o->kind != CLI_CLEAR)
            i++; /* its value */
    }
    return argc;
}

bool cli_list_add(cli_list *l, const char *item)
{
    if (l->count >= l->max)
        return false;
    l->items[l->count++] = item;
    return true;
}

/* "  LABEL   text", the text's further lines under its first. */
static void help_row(FILE *f, int width, const char *label, const char *text)
{
    int n = (int)strlen(label);
    fprintf(f, "  %s%*s", label, n < width ? width - n : 2, "");
    for (const char *p = text; *p;) {
        const char *nl = strchr(p, '\n');
        int len = nl ? (int)(nl - p) : (int)strlen(p);
        fprintf(f, "%.*s\n", len, p);
        if (!nl || !nl[1])
            break;
        p = nl + 1;
        fprintf(f, "  %*s", width, "");
    }
}

void cli_options_rows(FILE *f, const cli_opts *t)
{
    for (const cli_opt *o = t->opts; o->kind != CLI_END; o++) {
        if (o->kind == CLI_GROUP || !o->help)
            continue;
        char label[128];
        size_t k = 0;
        for (const char *p = o->name; *p && k + 3 < sizeof label; p++) {
            if (*p == '|') {
                label[k++] = ',';
                label[k++] = ' ';
            } else {
                label[k++] = *p;
            }
        }
        label[k] = '\0';
        if (o->arg)
            snprintf(label + k, sizeof label - k, " %s", o->arg);
        help_row(f, t->width, label, o->help);
    }
}

void cli_options_groups(FILE *f, const cli_opts *t)
{
    for (const cli_opt *o = t->opts; o->kind != CLI_END; o++) {
        if (o->kind != CLI_GROUP)
            continue;
        const cli_opts *g = o->target;
        fprintf(f, "\n%s\n", g->title);
        cli_options_rows(f, g);
    }
}

void cli_options_help(FILE *f, const cli_opts *t)
{
    cli_options_rows(f, t);
    cli_options_groups(f, t);
}

bool cli_parse_one_spec(const char *word, void *target, char *why, size_t n)
{
    const char **spec = target;
    if (*spec)
        snprintf(why, n, "expected one SPEC, found '{value}' too");
    else
        *spec = word;
    return !*why;
}
