/* printf for models: the format checked when the model is compiled, the text formatted when the
 * call runs and handed to the context's output (cbm_context_def.output; the library itself never
 * writes to a stream).
 *
 * Both dialects call it: cpfg's `printf("...", e1, e2)` in pre- and post-condition blocks and the
 * L+C dialect's `printf`/`Printf` in productions, functions and control blocks. A format holds
 * text, `%%` and conversions `%[flags][width][.precision][length]conv` with conv one of
 * d i u o x X c (integers) f F e E g G a A (floating point) and s (a string literal argument).
 * Length modifiers (h, hh, l, ll, L, z, j, t) are accepted and ignored: a value is converted by
 * the conversion letter, an integer conversion truncating toward zero as C's cast does. `*`
 * widths, %n and %p are refused at compile time, so a running model can neither write memory nor
 * read arguments that do not exist.
 */
#include "lang/lang.h"

#include <stdio.h>
#include <string.h>

#define MAX_FIELD 200 /* width and precision above this are refused */

size_t cbm__unescape(const char *s, size_t n, char *out)
{
    size_t o = 0;
    for (size_t i = 0; i < n; i++) {
        char ch = s[i];
        if (ch != '\\' || i + 1 >= n) {
            out[o++] = ch;
            continue;
        }
        ch = s[++i];
        switch (ch) {
        case 'n':
            out[o++] = '\n';
            break;
        case 't':
            out[o++] = '\t';
            break;
        case 'r':
            out[o++] = '\r';
            break;
        case 'a':
            out[o++] = '\a';
            break;
        case 'b':
            out[o++] = '\b';
            break;
        case 'f':
            out[o++] = '\f';
            break;
        case 'v':
            out[o++] = '\v';
            break;
        case 'x': {
            unsigned v = 0;
            int k = 0;
            while (k < 2 && i + 1 < n && strchr("0123456789abcdefABCDEF", s[i + 1]) && s[i + 1]) {
                char h = s[++i];
                v = v * 16 + (unsigned)(h <= '9' ? h - '0' : (h | 32) - 'a' + 10);
                k++;
            }
            out[o++] = (char)v;
            break;
        }
        default:
            if (ch >= '0' && ch <= '7') {
                unsigned v = (unsigned)(ch - '0');
                for (int k = 0; k < 2 && i + 1 < n && s[i + 1] >= '0' && s[i + 1] <= '7'; k++)
                    v = v * 8 + (unsigned)(s[++i] - '0');
                out[o++] = (char)v;
            } else {
                out[o++] = ch; /* \\ \" \' \? and anything else: the character itself */
            }
        }
    }
    return o;
}

/* Parses one conversion starting after '%'; returns its length (up to and including the
 * conversion letter) and the letter, or 0 with a message. */
static size_t conversion(const char *f, char *conv, char *err, size_t errn)
{
    size_t i = 0;
    while (f[i] && strchr("-+ #0'", f[i]))
        i++;
    if (f[i] == '*') {
        snprintf(err, errn, "printf: '*' widths are not supported; write the width as a number");
        return 0;
    }
    long w = 0;
    for (; f[i] >= '0' && f[i] <= '9'; i++)
        if (w < 100000) /* past that it is too wide anyway; no overflow */
            w = w * 10 + (f[i] - '0');
    if (f[i] == '.') {
        i++;
        if (f[i] == '*') {
            snprintf(err, errn, "printf: '.*' precisions are not supported");
            return 0;
        }
        long p = 0;
        for (; f[i] >= '0' && f[i] <= '9'; i++)
            if (p < 100000)
                p = p * 10 + (f[i] - '0');
        if (p > MAX_FIELD)
            w = p;
    }
    if (w > MAX_FIELD) {
        snprintf(err, errn, "printf: a width or precision above %d", MAX_FIELD);
        return 0;
    }
    while (f[i] && strchr("hlLzjt", f[i]))
        i++;
    if (!f[i] || !strchr("diuoxXcfFeEgGaAs%", f[i])) {
        if (f[i] == 'n' || f[i] == 'p')
            snprintf(err, errn, "printf: %%%c is not supported", f[i]);
        else if (f[i])
            snprintf(err, errn, "printf: unknown conversion '%%%c'", f[i]);
        else
            snprintf(err, errn, "printf: the format ends inside a conversion");
        return 0;
    }
    *conv = f[i];
    return i + 1;
}

static char kind_of(char conv)
{
    if (strchr("di", conv))
        return CBM__FMT_INT;
    if (strchr("uoxX", conv))
        return CBM__FMT_UINT;
    if (conv == 'c')
        return CBM__FMT_CHAR;
    if (conv == 's')
        return CBM__FMT_STR;
    return CBM__FMT_REAL;
}

int cbm__fmt_scan(const char *fmt, uint8_t *kinds, int max, char *err, size_t errn)
{
    int n = 0;
    for (const char *p = fmt; *p; p++) {
        if (*p != '%')
            continue;
        char conv = 0;
        size_t len = conversion(p + 1, &conv, err, errn);
        if (!len)
            return -1;
        p += len;
        if (conv == '%')
            continue;
        if (n >= max) {
            snprintf(err, errn, "printf: more than %d conversions", max);
            return -1;
        }
        kinds[n++] = (uint8_t)kind_of(conv);
    }
    return n;
}

typedef struct outbuf {
    cbm_context *ctx;
    size_t len; /* bytes waiting in buf */
    char buf[1024];
} outbuf;

static void out_put(outbuf *o, const char *s, size_t n)
{
    if (o->len + n > sizeof o->buf) {
        cbm__output(o->ctx, o->buf, o->len);
        o->len = 0;
    }
    if (n > sizeof o->buf) {
        cbm__output(o->ctx, s, n);
        return;
    }
    memcpy(o->buf + o->len, s, n);
    o->len += n;
}

void cbm__fmt_print(cbm_context *ctx, const char *fmt, const cbm__fmt_arg *args, int nargs)
{
    if (!cbm__output_wanted(ctx))
        return;
    outbuf o = {.ctx = ctx};
    int k = 0;
    const char *p = fmt;
    while (*p) {
        const char *q = strchr(p, '%');
        if (!q) {
            out_put(&o, p, strlen(p));
            break;
        }
        out_put(&o, p, (size_t)(q - p));
        char conv = 0, err[8];
        size_t len = conversion(q + 1, &conv, err, sizeof err);
        if (!len) /* checked at compile time; never here */
            break;
        p = q + 1 + len;
        if (conv == '%') {
            out_put(&o, "%", 1);
            continue;
        }
        /* the spec: '%', flags, width and precision, the modifier this value needs, conv */
        char spec[32];
        size_t sl = 0;
        spec[sl++] = '%';
        for (size_t i = 0; i + 1 < len && sl < sizeof spec - 4; i++)
            if (!strchr("hlLzjt", q[1 + i]))
                spec[sl++] = q[1 + i];
        int kind = (unsigned char)kind_of(conv); /* a small kind code, never negative */
        if (kind == CBM__FMT_INT || kind == CBM__FMT_UINT) {
            spec[sl++] = 'l';
            spec[sl++] = 'l';
        }
        spec[sl++] = conv;
        spec[sl] = 0;
        char tmp[2 * MAX_FIELD + 64];
        int w = 0;
        double v = k < nargs ? args[k].v : 0;
        const char *str = k < nargs && args[k].s ? args[k].s : "";
        k++;
/* spec is one conversion assembled above from a format cbm__fmt_scan accepted, with the
 * argument type it names */
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wformat-nonliteral"
        switch (kind) {
        case CBM__FMT_INT:
            w = snprintf(tmp, sizeof tmp, spec, cbm__to_ll(v));
            break;
        case CBM__FMT_UINT: {
            long long i = cbm__to_ll(v);
            /* a negative C int prints as its 32-bit pattern, as lpfg's int would */
            unsigned long long u = i < 0 && i >= -2147483648LL ? (unsigned long long)(uint32_t)i
                                                               : (unsigned long long)i;
            w = snprintf(tmp, sizeof tmp, spec, u);
            break;
        }
        case CBM__FMT_CHAR:
            w = snprintf(tmp, sizeof tmp, spec, (int)(unsigned char)cbm__to_ll(v));
            break;
        case CBM__FMT_STR:
            w = snprintf(tmp, sizeof tmp, spec, str);
            if (w >= (int)sizeof tmp) { /* a long literal: print it whole */
                out_put(&o, str, strlen(str));
                w = 0;
            }
            break;
        default:
            w = snprintf(tmp, sizeof tmp, spec, v);
        }
#pragma GCC diagnostic pop
        if (w > 0)
            out_put(&o, tmp, (size_t)w < sizeof tmp ? (size_t)w : sizeof tmp - 1);
    }
    if (o.len)
        cbm__output(ctx, o.buf, o.len);
}
