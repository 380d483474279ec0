/* Reading a table of numbers for `cambium plot`. CSV: the first line that is not empty and does
 * not start with '#' names the columns; every later such line is a row with as many cells, split
 * at commas outside double quotes ("" inside quotes is a quote). JSON: the document is parsed
 * (objects, arrays, strings, numbers, true/false/null) until the first array whose first element
 * is an object; that array's objects are the rows, the first object's members the columns (a
 * missing member, null, or a non-number is NaN). Files are read whole; nothing here is in the
 * library because the library writes these files and never needs to read them. */
#define _POSIX_C_SOURCE 200809L
#include "table.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static bool fail(char *err, size_t n, const char *fmt, ...) __attribute__((format(printf, 3, 4)));

static bool fail(char *err, size_t n, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, n, fmt, ap);
    va_end(ap);
    return false;
}

static char *read_all(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    size_t cap = 1 << 16, n = 0;
    char *b = malloc(cap);
    bool bad = b == NULL;
    while (!bad) {
        if (n + 1 >= cap) {
            char *nb = realloc(b, cap *= 2);
            if (!nb) {
                bad = true;
                break;
            }
            b = nb;
        }
        size_t got = fread(b + n, 1, cap - n - 1, f);
        n += got;
        if (got == 0)
            break;
    }
    bad |= ferror(f) != 0;
    fclose(f);
    if (bad) {
        free(b);
        return NULL;
    }
    b[n] = '\0';
    *len = n;
    return b;
}

static double cell_value(const char *s)
{
    while (isspace((unsigned char)*s))
        s++;
    if (!*s)
        return NAN;
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    while (isspace((unsigned char)*end))
        end++;
    return *end || errno == ERANGE ? NAN : v;
}

static bool add_row(cli_table *t, size_t *cap)
{
    if (t->nrows < *cap)
        return true;
    size_t nc = *cap ? 2 * *cap : 256;
    for (size_t c = 0; c < t->ncols; c++) {
        double *p = realloc(t->cols[c], nc * sizeof *p);
        if (!p)
            return false;
        t->cols[c] = p;
    }
    *cap = nc;
    return true;
}

static bool add_column(cli_table *t, const char *name, size_t len)
{
    char **nn = realloc(t->names, (t->ncols + 1) * sizeof *nn);
    if (!nn)
        return false;
    t->names = nn;
    double **nc = realloc(t->cols, (t->ncols + 1) * sizeof *nc);
    if (!nc)
        return false;
    t->cols = nc;
    t->names[t->ncols] = strndup(name, len);
    t->cols[t->ncols] = NULL;
    if (!t->names[t->ncols])
        return false;
    t->ncols++;
    return true;
}

/* Splits one CSV line (NUL-terminated, modified in place) into cells; returns the count. */
static size_t split_csv(char *line, char **cells, size_t max)
{
    size_t n = 0;
    char *w = line, *r = line;
    while (n < max) {
        cells[n++] = w;
        bool quoted = false;
        for (;; r++) {
            if (*r == '"') {
                if (quoted && r[1] == '"')
                    *w++ = *r++;
                else
                    quoted = !quoted;
                continue;
            }
            if (*r == '\0' || (*r == ',' && !quoted))
                break;
            *w++ = *r;
        }
        bool end = *r == '\0';
        *w++ = '\0';
        if (end)
            return n;
        r++;
    }
    return n + 1; /* more cells than max */
}

#define MAX_COLS 4096

static bool read_csv(char *text, const char *path, cli_table *t, char *err, size_t en)
{
    char **cells = malloc(MAX_COLS * sizeof *cells);
    if (!cells)
        return fail(err, en, "%s: out of memory", path);
    size_t cap = 0, lineno = 0;
    bool header = true, ok = true;
    char *next = text;
    while (ok && next && *next) {
        char *line = next;
        next = strchr(line, '\n');
        if (next)
            *next++ = '\0';
        lineno++;
        size_t len = strlen(line);
        if (len && line[len - 1] == '\r')
            line[--len] = '\0';
        const char *s = line;
        while (isspace((unsigned char)*s))
            s++;
        if (!*s || *s == '#')
            continue;
        size_t n = split_csv(line, cells, MAX_COLS);
        if (n > MAX_COLS) {
            ok = fail(err, en, "%s:%zu: more than %d columns", path, lineno, MAX_COLS);
            break;
        }
        if (header) {
            for (size_t c = 0; c < n && ok; c++) {
                const char *a = cells[c];
                while (isspace((unsigned char)*a))
                    a++;
                size_t l = strlen(a);
                while (l && isspace((unsigned char)a[l - 1]))
                    l--;
                ok = add_column(t, a, l) || fail(err, en, "%s: out of memory", path);
            }
            header = false;
            continue;
        }
        if (n != t->ncols) {
            ok = fail(err, en, "%s:%zu: %zu cells where the header names %zu columns", path, lineno,
                      n, t->ncols);
            break;
        }
        if (!add_row(t, &cap)) {
            ok = fail(err, en, "%s: out of memory", path);
            break;
        }
        for (size_t c = 0; c < n; c++)
            t->cols[c][t->nrows] = cell_value(cells[c]);
        t->nrows++;
    }
    free(cells);
    if (ok && header)
        ok = fail(err, en, "%s: no header line (no columns)", path);
    return ok;
}

/* ---- JSON ---- */

typedef struct json_reader {
    const char *s, *path;
    size_t line;
    char *err;
    size_t en;
    int depth;
} json_reader;

static void skip_ws(json_reader *j)
{
    for (; *j->s && isspace((unsigned char)*j->s); j->s++)
        if (*j->s == '\n')
            j->line++;
}

static bool jfail(json_reader *j, const char *what)
{
    return fail(j->err, j->en, "%s:%zu: %s", j->path, j->line, what);
}

/* A string at j->s (the opening quote); its text (escapes other than \" and \\ kept as
 * written, enough for member names) is copied into out when out is not NULL. */
static bool json_string(json_reader *j, char *out, size_t n)
{
    j->s++;
    size_t k = 0;
    while (*j->s && *j->s != '"') {
        char c = *j->s++;
        if (c == '\\' && *j->s)
            c = *j->s++;
        else if (c == '\n')
            return jfail(j, "line break inside a string");
        if (out && k + 1 < n)
            out[k++] = c;
    }
    if (*j->s != '"')
        return jfail(j, "unterminated string");
    j->s++;
    if (out)
        out[k] = '\0';
    return true;
}

static bool json_skip(json_reader *j);

/* The value at j->s as a number (NaN for null or any non-number, which is skipped). */
static bool json_number(json_reader *j, double *v)
{
    skip_ws(j);
    if (*j->s == '-' || isdigit((unsigned char)*j->s)) {
        char *end;
        *v = strtod(j->s, &end);
        if (end == j->s)
            return jfail(j, "bad number");
        j->s = end;
        return true;
    }
    *v = NAN;
    return json_skip(j);
}

static bool json_skip(json_reader *j)
{
    skip_ws(j);
    if (++j->depth > 256)
        return jfail(j, "nested too deeply");
    bool ok = true;
    char c = *j->s;
    if (c == '"') {
        ok = json_string(j, NULL, 0);
    } else if (c == '{' || c == '[') {
        char close = c == '{' ? '}' : ']';
        j->s++;
        skip_ws(j);
        if (*j->s == close) {
            j->s++;
        } else {
            for (;;) {
                if (c == '{') {
                    skip_ws(j);
                    if (*j->s != '"' || !json_string(j, NULL, 0))
                        return jfail(j, "expected a member name");
                    skip_ws(j);
                    if (*j->s++ != ':')
                        return jfail(j, "expected ':'");
                }
                if (!json_skip(j))
                    return false;
                skip_ws(j);
                if (*j->s == ',') {
                    j->s++;
                    continue;
                }
                if (*j->s++ != close)
                    return jfail(j, c == '{' ? "expected ',' or '}'" : "expected ',' or ']'");
                break;
            }
        }
    } else if (c == '-' || isdigit((unsigned char)c)) {
        double v;
        ok = json_number(j, &v);
    } else if (!strncmp(j->s, "true", 4) || !strncmp(j->s, "null", 4)) {
        j->s += 4;
    } else if (!strncmp(j->s, "false", 5)) {
        j->s += 5;
    } else {
        ok = jfail(j, "expected a value");
    }
    j->depth--;
    return ok;
}

/* Rows from the array at j->s whose first element is an object. */
static bool json_rows(json_reader *j, cli_table *t)
{
    size_t cap = 0;
    char name[256];
    j->s++; /* '[' */
    for (;;) {
        skip_ws(j);
        if (*j->s == ']') {
            j->s++;
            return true;
        }
        if (*j->s != '{')
            return jfail(j, "an element of the table's array is not an object");
        j->s++;
        bool first = t->nrows == 0;
        if (!add_row(t, &cap))
            return jfail(j, "out of memory");
        for (size_t c = 0; c < t->ncols; c++)
            t->cols[c][t->nrows] = NAN;
        skip_ws(j);
        while (*j->s != '}') {
            skip_ws(j);
            if (*j->s != '"' || !json_string(j, name, sizeof name))
                return jfail(j, "expected a member name");
            skip_ws(j);
            if (*j->s++ != ':')
                return jfail(j, "expected ':'");
            long col = -1;
            for (size_t c = 0; c < t->ncols && col < 0; c++)
                if (!strcmp(t->names[c], name))
                    col = (long)c;
            if (col < 0 && first) {
                if (!add_column(t, name, strlen(name)))
                    return jfail(j, "out of memory");
                col = (long)t->ncols - 1;
                double *p = realloc(t->cols[col], cap * sizeof *p);
                if (!p)
                    return jfail(j, "out of memory");
                t->cols[col] = p;
            }
            double v;
            if (!json_number(j, &v))
                return false;
            if (col >= 0)
                t->cols[col][t->nrows] = v;
            skip_ws(j);
            if (*j->s == ',')
                j->s++;
            else if (*j->s != '}')
                return jfail(j, "expected ',' or '}'");
        }
        j->s++;
        t->nrows++;
        skip_ws(j);
        if (*j->s == ',')
            j->s++;
        else if (*j->s != ']')
            return jfail(j, "expected ',' or ']'");
    }
}

/* Walks the document until the first array of objects; *found tells whether one was read. */
static bool json_find(json_reader *j, cli_table *t, bool *found)
{
    skip_ws(j);
    if (++j->depth > 256)
        return jfail(j, "nested too deeply");
    bool ok = true;
    if (*j->s == '[') {
        const char *at = j->s + 1;
        while (isspace((unsigned char)*at))
            at++;
        if (*at == '{') {
            *found = true;
            ok = json_rows(j, t);
        } else {
            ok = json_skip(j);
        }
    } else if (*j->s == '{') {
        j->s++;
        skip_ws(j);
        while (ok && !*found && *j->s != '}') {
            skip_ws(j);
            if (*j->s != '"' || !json_string(j, NULL, 0))
                return jfail(j, "expected a member name");
            skip_ws(j);
            if (*j->s++ != ':')
                return jfail(j, "expected ':'");
            ok = json_find(j, t, found);
            skip_ws(j);
            if (ok && !*found) {
                if (*j->s == ',')
                    j->s++;
                else if (*j->s != '}')
                    ok = jfail(j, "expected ',' or '}'");
            }
        }
        if (ok && !*found)
            j->s++; /* '}' */
    } else {
        ok = json_skip(j);
    }
    j->depth--;
    return ok;
}

static bool read_json(const char *text, const char *path, cli_table *t, char *err, size_t en)
{
    json_reader j = {text, path, 1, err, en, 0};
    bool found = false;
    if (!json_find(&j, t, &found))
        return false;
    if (!found)
        return fail(err, en, "%s: no array of objects (rows) in the JSON document", path);
    if (t->ncols == 0)
        return fail(err, en, "%s: the rows have no members", path);
    return true;
}

bool cli_table_read(const char *path, cli_table *t, char *err, size_t en)
{
    memset(t, 0, sizeof *t);
    size_t len = 0;
    char *text = read_all(path, &len);
    if (!text)
        return fail(err, en, "%s: cannot read: %s", path, strerror(errno ? errno : EIO));
    if (strlen(text) != len) {
        free(text);
        return fail(err, en, "%s: holds NUL bytes (not a text table)", path);
    }
    const char *dot = strrchr(path, '.');
    bool json = dot && (!strcmp(dot, ".json") || !strcmp(dot, ".JSON"));
    bool ok = json ? read_json(text, path, t, err, en) : read_csv(text, path, t, err, en);
    free(text);
    if (!ok)
        cli_table_free(t);
    return ok;
}

long cli_table_column(const cli_table *t, const char *name)
{
    for (size_t c = 0; c < t->ncols; c++)
        if (!strcmp(t->names[c], name))
            return (long)c;
    char *end;
    long k = strtol(name, &end, 10);
    if (*name && !*end && k >= 1 && (size_t)k <= t->ncols)
        return k - 1;
    return -1;
}

void cli_table_free(cli_table *t)
{
    for (size_t c = 0; c < t->ncols; c++) {
        free(t->names[c]);
        free(t->cols[c]);
    }
    free(t->names);
    free(t->cols);
    memset(t, 0, sizeof *t);
}
