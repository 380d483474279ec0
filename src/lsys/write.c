/* Writers of the derived string: one module per line with parameters as %.9g (the notation of
 * cpfg's exact string dumps, round-trips float32 exactly), and cpfg's own `-str` layout
 * (modules run together, %g, lines wrapped at 70 characters). */
#include "lsys/lsys_internal.h"

#include <stdio.h>

cbm_status cbm_lsys_write_str(const cbm_lsys *ls, bool homomorphism, cbm_out *o)
{
    if (ls->lp)
        return cbm__lpfg_write_str(ls, homomorphism, o);
    cbm_lsys_cursor c;
    cbm_lsys_cursor_begin(ls, homomorphism, &c);
    FILE *f = cbm_out_stream(o);
    while (cbm_lsys_cursor_next(ls, homomorphism, &c)) {
        putc(c.symbol, f);
        for (int i = 0; i < c.nparams; i++)
            fprintf(f, "%c%.9g", i ? ',' : '(', c.params[i]);
        if (c.nparams)
            putc(')', f);
        putc('\n', f);
    }
    return ferror(f) ? CBM_E_IO : CBM_OK;
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
    if (!ls->lp) {
        *names = NULL;
        return 0;
    }
    return cbm__lpfg_func_names(ls, names);
}

cbm_status cbm_lsys_set_func_ids(cbm_lsys *ls, const int *ids, size_t n)
{
    if (!ls || !ls->lp)
        return n ? CBM_E_INVALID : CBM_OK;
    return cbm__lpfg_set_func_ids(ls, ids, n);
}
