/* Writers of the derived string: one module per line with parameters as %.9g (the notation of
 * cpfg's exact string dumps, round-trips float32 exactly), and cpfg's own `-str` layout
 * (modules run together, %g, lines wrapped at 70 characters); the buffered text writer with a
 * memo of number texts that the first uses (cbm__strw, for either dialect's writer). */
#include "lsys/lsys_internal.h"

#include <stdio.h>
#include <string.h>

/* ------------------------------------------------------------ buffered text with a number memo
 * A derived string of 10^7 modules is written one line per module; through stdio that is a
 * locked call per character and an fprintf("%.9g") per parameter, most of the run's time
 * (printf's exact decimal conversion). The lines are built in a buffer instead, and the text of
 * each number is kept in a direct-mapped memo keyed by its bit pattern: derived strings repeat
 * few distinct values (angles, scale factors), so most parameters are a copy of text printed
 * before. The text is what snprintf("%.9g") gives, so the output is byte for byte the same. */
cbm__strw *cbm__strw_open(cbm_context *ctx, FILE *f)
{
    cbm__strw *w = cbm__calloc(ctx, 1, sizeof *w);
    if (w) {
        w->ctx = ctx;
        w->f = f;
    }
    return w;
}

void cbm__strw_flush(cbm__strw *w)
{
    if (w->n && fwrite(w->buf, 1, w->n, w->f) != w->n)
        w->err = true;
    w->n = 0;
}

void cbm__strw_big(cbm__strw *w, const char *s, size_t n)
{
    cbm__strw_flush(w);
    if (n > STRW_BUF) {
        if (fwrite(s, 1, n, w->f) != n)
            w->err = true;
        return;
    }
    memcpy(w->buf, s, n);
    w->n = n;
}

void cbm__strw_g9(cbm__strw *w, double v)
{
    uint64_t bits;
    memcpy(&bits, &v, sizeof bits);
    unsigned h = (unsigned)((bits * 0x9E3779B97F4A7C15ull) >> 52) & (STRW_SLOTS - 1);
    if (!w->len[h] || w->key[h] != bits) {
        int n = snprintf(w->txt[h], STRW_TXT, "%.9g", v);
        w->key[h] = bits;
        w->len[h] = (uint8_t)(n > 0 && n < STRW_TXT ? n : 0);
        if (!w->len[h]) { /* cannot happen for %.9g; written directly all the same */
            char big[64];
            n = snprintf(big, sizeof big, "%.9g", v);
            cbm__strw_bytes(w, big, n > 0 ? (size_t)n : 0);
            return;
        }
    }
    cbm__strw_bytes(w, w->txt[h], w->len[h]);
}

void cbm__strw_lld(cbm__strw *w, long long v)
{
    /* the digits "%lld" gives, without printf */
    char t[24], *p = t + sizeof t;
    unsigned long long u = v < 0 ? 0 - (unsigned long long)v : (unsigned long long)v;
    do {
        *--p = (char)('0' + u % 10);
        u /= 10;
    } while (u);
    if (v < 0)
        *--p = '-';
    cbm__strw_bytes(w, p, (size_t)(t + sizeof t - p));
}

cbm_status cbm__strw_close(cbm__strw *w)
{
    if (!w)
        return CBM_E_NOMEM;
    cbm__strw_flush(w);
    bool err = w->err || ferror(w->f);
    cbm__free(w->ctx, w, sizeof *w);
    return err ? CBM_E_IO : CBM_OK;
}

cbm_status cbm_lsys_write_str(const cbm_lsys *ls, bool homomorphism, cbm_out *o)
{
    return ls->dialect->write_str(ls, homomorphism, o);
}

cbm_status cbm__cpfg_write_str(const cbm_lsys *ls, bool homomorphism, cbm_out *o)
{
    cbm_lsys_cursor c;
    cbm_lsys_cursor_begin(ls, homomorphism, &c);
    cbm__strw *w = cbm__strw_open(ls->ctx, cbm_out_stream(o));
    if (!w)
        return CBM_E_NOMEM;
    while (cbm_lsys_cursor_next(ls, homomorphism, &c)) {
        cbm__strw_char(w, (char)c.symbol);
        for (int i = 0; i < c.nparams; i++) {
            cbm__strw_char(w, i ? ',' : '(');
            cbm__strw_g9(w, c.params[i]);
        }
        if (c.nparams)
            cbm__strw_char(w, ')');
        cbm__strw_char(w, '\n');
    }
    return cbm__strw_close(w);
}

cbm_status cbm_lsys_write_cpfg(const cbm_lsys *ls, bool homomorphism, cbm_out *o)
{
    cbm_lsys_cursor c;
    cbm_lsys_cursor_begin(ls, homomorphism, &c);
    FILE *f = cbm_out_stream(o);
    int col = 0;
    char buf[64];
    while (cbm_lsys_cursor_next(ls, homomorphism, &c)) {
        for (int i = -1; i <= c.nparams; i++) {
            const char *s = buf;
            if (i < 0)
                buf[0] = (char)c.symbol, buf[1] = 0;
            else if (i == c.nparams)
                s = c.nparams ? ")" : "";
            else
                snprintf(buf, sizeof buf, "%c%g", i ? ',' : '(', c.params[i]);
            for (; *s; s++) {
                putc(*s, f);
                if (++col == 70) {
                    putc('\n', f);
                    col = 0;
                }
            }
        }
    }
    putc('\n', f);
    return ferror(f) ? CBM_E_IO : CBM_OK;
}

const char *cbm_lsys_module_name(const cbm_lsys *ls, int symbol)
{
    return cbm__lpfg_module_name(ls, symbol);
}

size_t cbm_lsys_func_names(const cbm_lsys *ls, const char *const **names)
{
    return ls->dialect->func_names(ls, names);
}

cbm_status cbm_lsys_set_func_ids(cbm_lsys *ls, const int *ids, size_t n)
{
    if (!ls)
        return n ? CBM_E_INVALID : CBM_OK;
    return ls->dialect->set_func_ids(ls, ids, n);
}

/* The cpfg dialect's func(id, x) names its function by the id: no names to bind. */
size_t cbm__cpfg_func_names(const cbm_lsys *ls, const char *const **names)
{
    (void)ls;
    *names = NULL;
    return 0;
}

cbm_status cbm__cpfg_set_func_ids(cbm_lsys *ls, const int *ids, size_t n)
{
    (void)ls;
    (void)ids;
    return n ? CBM_E_INVALID : CBM_OK;
}
