/* The compiler's cursor over the preprocessed text, shared by both dialects' parsers: the node
 * array, globals and arrays of the cpfg dialect, string literals, and the map from text offsets
 * back to file:line:col for the diagnostics of parsing and of runtime errors.
 */
#include "lang/lang.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

cbm_status cbm__compiler_init(cbm__compiler *c, cbm_context *ctx, cbm__pp *pp)
{
    memset(c, 0, sizeof *c);
    c->ctx = ctx;
    c->pp = pp;
    c->text = pp->text.data;
    c->status = CBM_OK;
    c->map.data = pp->lines.data;
    c->map.len = pp->lines.len;
    c->map.cap = pp->lines.cap;
    c->files.data = pp->files.data;
    c->files.len = pp->files.len;
    c->files.cap = pp->files.cap;
    memset(&pp->lines, 0, sizeof pp->lines);
    memset(&pp->files, 0, sizeof pp->files);
    size_t zero = 0;
    CBM_TRY(CBM_ARRAY_PUSH(ctx, c->line_start, zero));
    for (size_t i = 0; c->text[i]; i++)
        if (c->text[i] == '\n') {
            size_t s = i + 1;
            CBM_TRY(CBM_ARRAY_PUSH(ctx, c->line_start, s));
        }
    return CBM_OK;
}

void cbm__compiler_free(cbm__compiler *c)
{
    for (size_t i = 0; i < c->files.len; i++)
        cbm__strfree(c->ctx, c->files.data[i]);
    CBM_ARRAY_FREE(c->ctx, c->files);
    CBM_ARRAY_FREE(c->ctx, c->map);
    CBM_ARRAY_FREE(c->ctx, c->node_pos);
    for (size_t i = 0; i < c->globals.len; i++)
        cbm__strfree(c->ctx, c->globals.data[i]);
    CBM_ARRAY_FREE(c->ctx, c->globals);
    CBM_ARRAY_FREE(c->ctx, c->global_use);
    CBM_ARRAY_FREE(c->ctx, c->global_set);
    CBM_ARRAY_FREE(c->ctx, c->line_start);
    CBM_ARRAY_FREE(c->ctx, c->nodes);
    for (size_t i = 0; i < c->arrays.len; i++) {
        cbm__strfree(c->ctx, c->arrays.data[i].name);
        cbm__free(c->ctx, c->arrays.data[i].data, c->arrays.data[i].count * sizeof(double));
    }
    CBM_ARRAY_FREE(c->ctx, c->arrays);
    CBM_ARRAY_FREE(c->ctx, c->strings);
}

/* The index of the preprocessed line holding text position pos (binary search of line_start;
 * 0 when there are no lines). */
static size_t line_index(const cbm__compiler *c, size_t pos)
{
    size_t lo = 0, hi = c->line_start.len;
    while (hi - lo > 1) {
        size_t mid = (lo + hi) / 2;
        if (c->line_start.data[mid] <= pos)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* The error at text position pos, located (*file, *line, *col). */
static void report_error(const cbm__compiler *c, size_t pos, const char **file, int *line, int *col,
                         const char *fmt, va_list ap) __attribute__((format(printf, 6, 0)));
static void report_error(const cbm__compiler *c, size_t pos, const char **file, int *line, int *col,
                         const char *fmt, va_list ap)
{
    cbm__compiler_locate(c, pos, file, line, col);
    cbm__vdiag(c->ctx, CBM_ERROR, *file, *line, *col, fmt, ap);
}

void cbm__cerr(cbm__compiler *c, size_t pos, const char *fmt, ...)
{
    c->errors++;
    if (c->errors >= cbm_context_limits(c->ctx)->max_diagnostics) {
        c->fatal = true;
        if (c->status == CBM_OK)
            c->status = CBM_E_SYNTAX;
    }
    const char *file;
    int line, col;
    va_list ap;
    va_start(ap, fmt);
    report_error(c, pos, &file, &line, &col, fmt, ap);
    va_end(ap);
    /* the line expands a value given on the command line: say so, the error may be there */
    size_t lo = line_index(c, pos);
    if (lo < c->map.len && c->map.data[lo].define >= 0)
        cbm__diag(c->ctx, CBM_NOTE, file, line, col, "the line uses the command line's %s",
                  c->files.data[c->map.data[lo].define]);
}

void cbm__compiler_locate(const cbm__compiler *c, size_t pos, const char **file, int *line,
                          int *col)
{
    *file = NULL;
    *line = *col = 0;
    if (!c->line_start.len)
        return;
    size_t lo = line_index(c, pos);
    if (lo < c->map.len) {
        *file = c->files.data[c->map.data[lo].file];
        *line = c->map.data[lo].line;
    } else if (c->map.len) { /* the end of the text: after the last line */
        *file = c->files.data[c->map.data[c->map.len - 1].file];
        *line = c->map.data[c->map.len - 1].line;
    } else if (c->files.len) { /* an empty file */
        *file = c->files.data[0];
        *line = 1;
    }
    *col = (int)(pos - c->line_start.data[lo]) + 1;
}

size_t cbm__node_pos(const cbm__compiler *c, int32_t node)
{
    return node >= 0 && (size_t)node < c->node_pos.len ? (size_t)c->node_pos.data[node] : 0;
}

cbm_status cbm__compiler_fail(const cbm__compiler *c, cbm_status s, size_t pos, const char *fmt,
                              ...)
{
    const char *file;
    int line, col;
    va_list ap;
    va_start(ap, fmt);
    report_error(c, pos, &file, &line, &col, fmt, ap);
    va_end(ap);
    return s;
}

void cbm__skip(cbm__compiler *c, bool nl)
{
    for (;;) {
        char ch = c->text[c->pos];
        if (ch == ' ' || ch == '\t' || ch == '\r')
            c->pos++;
        else if (ch == '\n' && (nl || c->text[c->pos + 1] == '\t'))
            c->pos++;
        else
            return;
    }
}
