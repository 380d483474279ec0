/* A small JSON writer: the document grows in a context-allocated buffer; a stack of nesting
 * levels (object or array, first element or not) places commas and checks that keys appear in
 * objects only. Strings are escaped per RFC 8259; numbers use the shortest "%.17g" that reads
 * back to the same double; non-finite numbers become null (JSON has no NaN). */
#include "writers.h"

#include "cambium/io.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define JSON_MAX_DEPTH 64

struct cbm_json {
    cbm_context *ctx;
    CBM_ARRAY(char) buf;
    int depth;
    char kind[JSON_MAX_DEPTH]; /* 'o' or 'a' */
    bool first[JSON_MAX_DEPTH];
    bool done; /* a complete top-level value was written */
    cbm_status err;
};

cbm_status cbm_json_create(cbm_context *ctx, cbm_json **out)
{
    if (!ctx || !out)
        return CBM_E_INVALID;
    cbm_json *j = cbm__calloc(ctx, 1, sizeof *j);
    if (!j)
        return CBM_E_NOMEM;
    j->ctx = ctx;
    *out = j;
    return CBM_OK;
}

void cbm_json_destroy(cbm_json *j)
{
    if (!j)
        return;
    CBM_ARRAY_FREE(j->ctx, j->buf);
    cbm__free(j->ctx, j, sizeof *j);
}

static void append_raw(cbm_json *j, const char *s, size_t n)
{
    if (j->err)
        return;
    if (CBM_ARRAY_RESERVE(j->ctx, j->buf, j->buf.len + n + 1) != CBM_OK) {
        j->err = CBM_E_NOMEM;
        return;
    }
    memcpy(j->buf.data + j->buf.len, s, n);
    j->buf.len += n;
    j->buf.data[j->buf.len] = '\0';
}

static void puts_(cbm_json *j, const char *s)
{
    append_raw(j, s, strlen(s));
}

static void put_string(cbm_json *j, const char *s)
{
    append_raw(j, "\"", 1);
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        char esc[8];
        if (*p == '"' || *p == '\\') {
            esc[0] = '\\';
            esc[1] = (char)*p;
            append_raw(j, esc, 2);
        } else if (*p == '\n') {
            append_raw(j, "\\n", 2);
        } else if (*p == '\t') {
            append_raw(j, "\\t", 2);
        } else if (*p < 0x20) {
            snprintf(esc, sizeof esc, "\\u%04x", *p);
            append_raw(j, esc, 6);
        } else {
            append_raw(j, (const char *)p, 1);
        }
    }
    append_raw(j, "\"", 1);
}

/* Comma, key, and checks before any value. */
static bool value_start(cbm_json *j, const char *key)
{
    if (j->err)
        return false;
    if (j->depth == 0) {
        if (key || j->done) {
            j->err = CBM_E_INVALID;
            return false;
        }
        return true;
    }
    int d = j->depth - 1;
    if ((j->kind[d] == 'o') != (key != NULL)) {
        j->err = CBM_E_INVALID;
        return false;
    }
    if (!j->first[d])
        append_raw(j, ",", 1);
    j->first[d] = false;
    if (key) {
        put_string(j, key);
        append_raw(j, ":", 1);
    }
    return true;
}

static void value_end(cbm_json *j)
{
    if (j->depth == 0)
        j->done = true;
}

static void open_(cbm_json *j, const char *key, char kind)
{
    if (!value_start(j, key))
        return;
    if (j->depth >= JSON_MAX_DEPTH) {
        j->err = CBM_E_LIMIT;
        return;
    }
    append_raw(j, kind == 'o' ? "{" : "[", 1);
    j->kind[j->depth] = kind;
    j->first[j->depth] = true;
    j->depth++;
}

static void close_(cbm_json *j, char kind)
{
    if (j->err)
        return;
    if (j->depth == 0 || j->kind[j->depth - 1] != kind) {
        j->err = CBM_E_INVALID;
        return;
    }
    j->depth--;
    append_raw(j, kind == 'o' ? "}" : "]", 1);
    value_end(j);
}

void cbm_json_begin_object(cbm_json *j, const char *key)
{
    open_(j, key, 'o');
}
void cbm_json_end_object(cbm_json *j)
{
    close_(j, 'o');
}
void cbm_json_begin_array(cbm_json *j, const char *key)
{
    open_(j, key, 'a');
}
void cbm_json_end_array(cbm_json *j)
{
    close_(j, 'a');
}

void cbm_json_number(cbm_json *j, const char *key, double v)
{
    if (!value_start(j, key))
        return;
    if (!isfinite(v)) {
        puts_(j, "null");
    } else {
        char b[32];
        for (int prec = 15; prec <= 17; prec++) {
            snprintf(b, sizeof b, "%.*g", prec, v);
            if (strtod(b, NULL) == v)
                break;
        }
        puts_(j, b);
    }
    value_end(j);
}

void cbm_json_int(cbm_json *j, const char *key, int64_t v)
{
    if (!value_start(j, key))
        return;
    char b[32];
    snprintf(b, sizeof b, "%lld", (long long)v);
    puts_(j, b);
    value_end(j);
}

void cbm_json_string(cbm_json *j, const char *key, const char *s)
{
    if (!value_start(j, key))
        return;
    put_string(j, s ? s : "");
    value_end(j);
}

void cbm_json_bool(cbm_json *j, const char *key, bool v)
{
    if (!value_start(j, key))
        return;
    puts_(j, v ? "true" : "false");
    value_end(j);
}

void cbm_json_null(cbm_json *j, const char *key)
{
    if (!value_start(j, key))
        return;
    puts_(j, "null");
    value_end(j);
}

cbm_status cbm_json_text(cbm_json *j, const char **text, size_t *len)
{
    if (!j || !text)
        return CBM_E_INVALID;
    if (j->err)
        return j->err;
    if (j->depth != 0 || !j->done)
        return CBM_E_INVALID;
    *text = j->buf.data;
    if (len)
        *len = j->buf.len;
    return CBM_OK;
}

cbm_status cbm_json_write_file(cbm_json *j, const char *path)
{
    const char *text;
    size_t len;
    cbm_status st = cbm_json_text(j, &text, &len);
    if (st != CBM_OK)
        return cbm__fail(j->ctx, st, "%s: incomplete JSON document", path);
    cbm_out *o;
    CBM_TRY(cbm_out_open(j->ctx, path, &o));
    cbm_out_write(o, text, len);
    cbm_out_write(o, "\n", 1);
    return cbm_out_commit(o);
}
