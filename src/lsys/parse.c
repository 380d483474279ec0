/* The parser of cpfg-dialect L-systems (after preprocessing), following cpfg's grammar
 * (lsys_input.y) and its two lexical modes: in "symbol mode" every character other than blanks
 * and `< > : * ( )` is one module symbol (so `@Gs` is the three modules @ G s, as in cpfg);
 * parentheses switch to expressions. A line ends a header item or a production, except that a
 * newline followed by a tab continues the line (cpfg's rule) and newlines inside parentheses
 * and braces are blanks.
 *
 *   Lsystem: N                       derivation length: EXPR      seed: EXPR
 *   ignore: SYMBOLS / consider: SYMBOLS                           define: { array a[n] = {...}; }
 *   Start: {..}  End: {..}  StartEach: {..}  EndEach: {..}        Axiom: MODULES
 *   lc < pred > rc : {pre} cond {post} --> successor : probability      (`*` = empty successor)
 *   decomposition / homomorphism, each with `maximum depth: EXPR`;  endlsystem
 *
 * A file may hold several L-systems, each `Lsystem: N ... endlsystem` (cpfg manual 7.2): the
 * first is the main one; the others are sub-L-systems, called from a string by `?(N, scale)`.
 * Each has its own productions, decomposition, homomorphism, ignore/consider symbols and
 * blocks; the derivation length and the seed are the main L-system's, the variables are shared.
 * Every `?(N)` whose N is a constant must name an L-system of the file.
 *
 * Errors are reported with file:line:col and what was expected; the parser recovers at the
 * next line, so one run reports several errors.
 */
#include "lsys/lsys_internal.h"

#include <ctype.h>
#include <math.h>
#include <stdlib.h>

/* A ?(id) with a constant id, checked once every L-system is known. */
typedef struct callref {
    double id;
    size_t pos;
} callref;

typedef struct parser {
    cbm_lsys *ls;
    cbm__compiler *c;
    const char *t; /* text */
    prodset *set;  /* current production set */
    /* the L-system being read: its sets, ignore table, stochastic flag, blocks and axiom */
    prodset *pmain, *pdecomp, *phomo;
    bool *ign, *stoch;
    int32_t *blk[4]; /* Start, StartEach, EndEach, End */
    int32_t *axiom, *naxiom;
    bool sub; /* a sub-L-system (not the first) */
    size_t lsys_pos;
    bool have_axiom, have_lsystem, ended;
    CBM_ARRAY(callref) calls;
} parser;

static bool at_eol(parser *p)
{
    char ch = p->t[p->c->pos];
    return ch == '\n' || ch == 0;
}

static void skip_line(parser *p)
{
    cbm__compiler *c = p->c;
    int level = 0;
    while (c->text[c->pos]) {
        char ch = c->text[c->pos];
        if (ch == '{' || ch == '(')
            level++;
        else if ((ch == '}' || ch == ')') && level > 0)
            level--;
        else if (ch == '\n' && (level == 0 || level > 64) && c->text[c->pos + 1] != '\t') {
            c->pos++;
            return;
        }
        c->pos++;
    }
}

static void expect_eol(parser *p, const char *after)
{
    cbm__skip(p->c, false);
    if (!at_eol(p)) {
        cbm__cerr(p->c, p->c->pos, "expected end of line after %s, found '%c'", after,
                  p->t[p->c->pos]);
        skip_line(p);
        return;
    }
    if (p->t[p->c->pos])
        p->c->pos++;
}

/* Keyword at the current position (case of the first letter free); returns its length. */
static size_t keyword(parser *p, const char *kw)
{
    const char *s = p->t + p->c->pos;
    size_t n = strlen(kw);
    if (tolower((unsigned char)s[0]) != tolower((unsigned char)kw[0]))
        return 0;
    size_t i = 1, k = 1;
    while (k < n) {
        if (kw[k] == ' ') { /* optional blank */
            if (s[i] == ' ')
                i++;
            k++;
            continue;
        }
        if (tolower((unsigned char)s[i]) != tolower((unsigned char)kw[k]))
            return 0;
        i++, k++;
    }
    return i;
}

static int symbol_ok(int ch)
{
    return ch > ' ' && ch < 127 && !strchr("<>:*()", ch);
}

static bool is_arrow(const char *s)
{
    return (s[0] == '-' && s[1] == '-' && s[2] == '>') ||
           (s[0] == '-' && s[1] == 'o' && s[2] == '>');
}

/* Formal modules (predecessor or context) with their parameter names. */
static bool parse_formal(parser *p, int32_t *first, int32_t *count, const char **names,
                         size_t *lens, int *nnames)
{
    cbm__compiler *c = p->c;
    cbm_lsys *ls = p->ls;
    *first = (int32_t)ls->fmods.len;
    *count = 0;
    for (;;) {
        cbm__skip(c, false);
        const char *s = p->t + c->pos;
        if (!symbol_ok((unsigned char)*s) || is_arrow(s))
            return true;
        fmodule m = {(uint8_t)*s, 0};
        c->pos++;
        if (p->t[c->pos] == '(') {
            c->pos++;
            for (;;) {
                cbm__skip(c, true);
                size_t a = c->pos;
                while (isalnum((unsigned char)p->t[c->pos]) || p->t[c->pos] == '_')
                    c->pos++;
                if (c->pos == a || isdigit((unsigned char)p->t[a])) {
                    char buf[2] = {p->t[c->pos], 0};
                    cbm__cerr(c, c->pos, "expected a parameter name in the module '%c', found %s",
                              m.sym, buf[0] == '\n' || !buf[0] ? "end of line" : buf);
                    return false;
                }
                if (*nnames >= LSYS_MAX_PARAMS || m.np >= LSYS_MAX_PARAMS) {
                    cbm__cerr(c, a, "too many parameters (at most %d)", LSYS_MAX_PARAMS);
                    return false;
                }
                names[*nnames] = p->t + a;
                lens[(*nnames)++] = c->pos - a;
                m.np++;
                cbm__skip(c, true);
                if (p->t[c->pos] == ',') {
                    c->pos++;
                    continue;
                }
                if (p->t[c->pos] == ')') {
                    c->pos++;
                    break;
                }
                cbm__cerr(c, c->pos, "expected ',' or ')' in the parameters of '%c'", m.sym);
                return false;
            }
        }
        if (CBM_ARRAY_PUSH(ls->ctx, ls->fmods, m) != CBM_OK) {
            c->status = CBM_E_NOMEM;
            c->fatal = true;
            return false;
        }
        (*count)++;
    }
}

/* Successor (or axiom) modules with parameter expressions, up to the end of the line or ':'. */
static bool parse_succ(parser *p, int32_t *first, int32_t *count)
{
    cbm__compiler *c = p->c;
    cbm_lsys *ls = p->ls;
    *first = (int32_t)ls->smods.len;
    *count = 0;
    cbm__skip(c, false);
    if (p->t[c->pos] == '*') {
        c->pos++;
        return true;
    }
    for (;;) {
        cbm__skip(c, false);
        const char *s = p->t + c->pos;
        if (at_eol(p) || *s == ':')
            return true;
        if (!symbol_ok((unsigned char)*s)) {
            cbm__cerr(c, c->pos, "expected a module symbol, found '%c'", *s);
            return false;
        }
        smod m = {(uint8_t)*s, 0, -1};
        size_t mpos = c->pos;
        c->pos++;
        if (p->t[c->pos] == '(') {
            c->pos++;
            int32_t last = -1;
            if (m.sym == '?')
                ls->subcalls = true; /* a sub-L-system call ?(id, scale) */
            for (;;) {
                int32_t e = cbm__parse_expr(c, false);
                if (e < 0)
                    return false;
                if (m.np >= LSYS_MAX_PARAMS) {
                    cbm__cerr(c, mpos, "too many parameters (at most %d)", LSYS_MAX_PARAMS);
                    return false;
                }
                if (last >= 0) {
                    c->nodes.data[last].next = e;
                } else {
                    m.args = e;
                    double v;
                    if (m.sym == '?' && cbm__node_const(c, e, &v)) {
                        callref r = {v, mpos};
                        if (CBM_ARRAY_PUSH(ls->ctx, p->calls, r) != CBM_OK) {
                            c->status = CBM_E_NOMEM;
                            c->fatal = true;
                            return false;
                        }
                    }
                }
                last = e;
                m.np++;
                cbm__skip(c, false);
                if (p->t[c->pos] == ',') {
                    c->pos++;
                    continue;
                }
                if (p->t[c->pos] == ')') {
                    c->pos++;
                    break;
                }
                cbm__cerr(c, c->pos, "expected ',' or ')' after a parameter of '%c', found '%c'",
                          m.sym, p->t[c->pos] ? p->t[c->pos] : ' ');
                return false;
            }
        }
        if (CBM_ARRAY_PUSH(ls->ctx, ls->smods, m) != CBM_OK) {
            c->status = CBM_E_NOMEM;
            c->fatal = true;
            return false;
        }
        (*count)++;
    }
}

static void parse_production(parser *p)
{
    cbm__compiler *c = p->c;
    cbm_lsys *ls = p->ls;
    const char *names[LSYS_MAX_PARAMS + 1];
    size_t lens[LSYS_MAX_PARAMS + 1];
    int nnames = 0;
    prod pr = {.pre = -1, .cond = -1, .post = -1, .prob = -1, .left_ctx = 0, .right_ctx = 0};
    pr.pos = c->pos;
    int32_t f, n;
    cbm__skip(c, false);
    size_t star = c->pos;
    if (p->t[star] == '*') {
        /* `* < pred`: an empty left context, as cpfg writes it */
        c->pos++;
        cbm__skip(c, false);
        if (p->t[c->pos] != '<') {
            cbm__cerr(c, star, "expected a predecessor module, found '*'");
            goto fail;
        }
        f = (int32_t)ls->fmods.len, n = 0;
    } else if (!parse_formal(p, &f, &n, names, lens, &nnames)) {
        goto fail;
    }
    cbm__skip(c, false);
    if (p->t[c->pos] == '<') {
        c->pos++;
        pr.left_ctx = f, pr.nleft_ctx = n;
        if (!parse_formal(p, &f, &n, names, lens, &nnames))
            goto fail;
    }
    pr.pred = f, pr.npred = n;
    if (n == 0) {
        char ch = p->t[c->pos];
        cbm__cerr(c, c->pos, "expected a predecessor module, found %s%c%s",
                  ch == '\n' || !ch ? "end of line" : "'", ch == '\n' || !ch ? ' ' : ch,
                  ch == '\n' || !ch ? "" : "'");
        goto fail;
    }
    cbm__skip(c, false);
    if (p->t[c->pos] == '>') {
        c->pos++;
        cbm__skip(c, false);
        if (p->t[c->pos] == '*') { /* `pred > *`: an empty right context (cpfg) */
            c->pos++;
            pr.right_ctx = (int32_t)ls->fmods.len, pr.nright_ctx = 0;
        } else if (!parse_formal(p, &pr.right_ctx, &pr.nright_ctx, names, lens, &nnames)) {
            goto fail;
        }
    }
    pr.nformals = nnames;
    if (nnames > ls->max_formals)
        ls->max_formals = nnames;
    c->formals = names;
    c->formal_len = lens;
    c->nformals = nnames;
    cbm__skip(c, false);
    if (p->t[c->pos] == ':') {
        c->pos++;
        cbm__skip(c, false);
        bool ok = true;
        if (p->t[c->pos] == '{') {
            pr.pre = cbm__parse_block(c, &ok);
            if (!ok)
                goto fail;
            cbm__skip(c, false);
        }
        if (p->t[c->pos] == '*') {
            c->pos++;
        } else if (p->t[c->pos] != '{' && !is_arrow(p->t + c->pos)) {
            pr.cond = cbm__parse_expr(c, false);
            if (pr.cond < 0)
                goto fail;
        }
        cbm__skip(c, false);
        if (p->t[c->pos] == '{') {
            pr.post = cbm__parse_block(c, &ok);
            if (!ok)
                goto fail;
        }
    }
    cbm__skip(c, false);
    if (!is_arrow(p->t + c->pos)) {
        char ch = p->t[c->pos];
        if (ch == '\n' || !ch)
            cbm__cerr(c, c->pos, "expected '-->' in the production, found end of line");
        else
            cbm__cerr(c, c->pos, "expected '-->', '<', '>' or ':' in the production, found '%c'",
                      ch);
        goto fail;
    }
    c->pos += 3;
    if (!parse_succ(p, &pr.succ, &pr.nsucc))
        goto fail;
    cbm__skip(c, false);
    if (p->t[c->pos] == ':') {
        c->pos++;
        pr.prob = cbm__parse_expr(c, false);
        if (pr.prob < 0)
            goto fail;
        if (p->set == p->pmain)
            *p->stoch = true;
    }
    c->nformals = 0;
    expect_eol(p, "the production");
    pr.const_succ = true;
    for (int32_t i = 0; i < pr.nsucc; i++)
        if (ls->smods.data[pr.succ + i].np)
            pr.const_succ = false;
    if (pr.const_succ) {
        pr.succ_bytes = (int32_t)ls->const_bytes.len;
        for (int32_t i = 0; i < pr.nsucc; i++)
            if (CBM_ARRAY_PUSH(ls->ctx, ls->const_bytes, ls->smods.data[pr.succ + i].sym) !=
                CBM_OK) {
                c->status = CBM_E_NOMEM;
                c->fatal = true;
                return;
            }
    }
    if (CBM_ARRAY_PUSH(ls->ctx, p->set->prods, pr) != CBM_OK) {
        c->status = CBM_E_NOMEM;
        c->fatal = true;
    }
    return;
fail:
    c->nformals = 0;
    skip_line(p);
}

static void parse_symbols(parser *p, bool consider)
{
    cbm__compiler *c = p->c;
    for (int i = 0; i < 128; i++)
        p->ign[i] = consider && i != 0;
    for (;;) {
        cbm__skip(c, false);
        unsigned char ch = (unsigned char)p->t[c->pos];
        if (ch == '\n' || ch == 0)
            break;
        if (ch >= 128) {
            cbm__cerr(c, c->pos, "symbols are ASCII characters");
        } else {
            p->ign[ch] = !consider;
        }
        c->pos++;
    }
    expect_eol(p, consider ? "consider:" : "ignore:");
}

static int32_t header_expr(parser *p, const char *what)
{
    int32_t e = cbm__parse_expr(p->c, false);
    if (e < 0) {
        skip_line(p);
        return -1;
    }
    expect_eol(p, what);
    return e;
}

static int eval_int(parser *p, int32_t e, size_t pos, const char *what, int lo, int hi)
{
    double v = 0;
    if (!cbm__node_const(p->c, e, &v)) {
        /* evaluate with zero globals: the value may use functions */
        cbm__eval ev = {.ctx = p->ls->ctx, .nodes = p->c->nodes.data, .arrays = p->c->arrays.data};
        double zeros[64] = {0};
        if (p->c->globals.len > 64) {
            cbm__cerr(p->c, pos, "%s must be a constant expression", what);
            return lo;
        }
        ev.globals = zeros;
        ev.while_budget = 1000000;
        v = cbm__eval_expr(&ev, e);
        cbm__eval_free(&ev);
    }
    if (!(v >= lo && v <= hi)) {
        cbm__cerr(p->c, pos, "%s must be between %d and %d, found %g", what, lo, hi, v);
        return lo;
    }
    return (int)v;
}

static void parse_block_item(parser *p, int32_t *slot, const char *what)
{
    bool ok = true;
    cbm__skip(p->c, false);
    *slot = cbm__parse_block(p->c, &ok);
    if (!ok) {
        skip_line(p);
        return;
    }
    expect_eol(p, what);
}

/* Points the parser at the L-system now being read (the first: the fields of ls). */
static void select_lsystem(parser *p, sublsys *sub)
{
    cbm_lsys *ls = p->ls;
    p->sub = sub != NULL;
    p->pmain = sub ? &sub->main : &ls->main;
    p->pdecomp = sub ? &sub->decomp : &ls->decomp;
    p->phomo = sub ? &sub->homo : &ls->homo;
    p->ign = sub ? sub->ignore : ls->ignore;
    p->stoch = sub ? &sub->stochastic : &ls->stochastic;
    p->blk[0] = sub ? &sub->start_block : &ls->start_block;
    p->blk[1] = sub ? &sub->start_each : &ls->start_each;
    p->blk[2] = sub ? &sub->end_each : &ls->end_each;
    p->blk[3] = sub ? &sub->end_block : &ls->end_block;
    p->axiom = sub ? &sub->axiom : &ls->axiom;
    p->naxiom = sub ? &sub->naxiom : &ls->naxiom;
    p->set = p->pmain;
    p->pmain->present = true;
    p->have_axiom = false;
    p->ended = false;
}

/* The checks at the end of an L-system, at the next Lsystem: (pos): its axiom, reported at its
 * own Lsystem: line, and its endlsystem. */
static void end_lsystem(parser *p, size_t pos)
{
    if (!p->have_axiom)
        cbm__cerr(p->c, p->lsys_pos, "the L-system has no axiom:");
    else if (!p->ended)
        cbm__cerr(p->c, pos, "expected 'endlsystem' at the end of the L-system");
}

/* `Lsystem: LABEL` (the keyword read): the first starts the main L-system, a further one a
 * sub-L-system, whose label must be a number no other L-system has. */
static void begin_lsystem(parser *p, size_t at)
{
    cbm__compiler *c = p->c;
    cbm_lsys *ls = p->ls;
    cbm__skip(c, false);
    size_t lab = c->pos;
    while (!at_eol(p))
        c->pos++;
    size_t end = c->pos;
    while (end > lab && (p->t[end - 1] == ' ' || p->t[end - 1] == '\t' || p->t[end - 1] == '\r'))
        end--;
    char buf[32] = {0};
    size_t n = end - lab < sizeof buf - 1 ? end - lab : sizeof buf - 1;
    memcpy(buf, p->t + lab, n);
    char *e = NULL;
    double v = strtod(buf, &e);
    bool numeric = n > 0 && n == end - lab && e == buf + n && v >= -2e9 && v <= 2e9;
    int id = numeric ? (int)v : 0;
    if (!p->have_lsystem) {
        p->have_lsystem = true;
        p->lsys_pos = at;
        ls->id = id;
        return;
    }
    end_lsystem(p, at);
    if (!numeric)
        cbm__cerr(c, lab, "the label of a sub-L-system must be a number, found %s",
                  n ? "text" : "nothing");
    else if (ls->id == id)
        cbm__cerr(c, lab, "a second L-system labelled %d", id);
    for (size_t i = 0; numeric && i < ls->subs.len; i++)
        if (ls->subs.data[i].id == id) {
            cbm__cerr(c, lab, "a second L-system labelled %d", id);
            break;
        }
    if (ls->subs.len >= 255) {
        cbm__cerr(c, at, "more than 256 L-systems in one file");
        c->fatal = true;
        return;
    }
    sublsys z;
    memset(&z, 0, sizeof z);
    z.id = id;
    z.start_block = z.end_block = z.start_each = z.end_each = -1;
    z.main.seed_expr = z.decomp.seed_expr = z.homo.seed_expr = -1;
    if (CBM_ARRAY_PUSH(ls->ctx, ls->subs, z) != CBM_OK) {
        c->status = CBM_E_NOMEM;
        c->fatal = true;
        return;
    }
    select_lsystem(p, &ls->subs.data[ls->subs.len - 1]);
    p->lsys_pos = at;
    ls->subcalls = true;
}

cbm_status cbm__lsys_parse(cbm_lsys *ls, const cbm__pp *pp)
{
    cbm__compiler *c = &ls->comp;
    parser p;
    memset(&p, 0, sizeof p);
    p.ls = ls;
    p.c = c;
    p.t = pp->text.data;
    select_lsystem(&p, NULL);
    const size_t max_steps = cbm_context_limits(ls->ctx)->max_steps;
    int max_depth = cbm_context_limits(ls->ctx)->max_decomp_depth;
    ls->derivation_length = 0;
    while (c->text[c->pos] && !c->fatal) {
        cbm__skip(c, false);
        if (c->text[c->pos] == '\n') {
            c->pos++;
            continue;
        }
        if (!c->text[c->pos])
            break;
        size_t at = c->pos, k;
        if ((k = keyword(&p, "Lsystem:"))) {
            c->pos += k;
            begin_lsystem(&p, at);
            continue;
        }
        if (p.ended) {
            skip_line(&p); /* text after endlsystem that starts no L-system is ignored */
            continue;
        }
        if (!p.have_lsystem) {
            cbm__cerr(c, at, "expected 'Lsystem:' before the L-system");
            skip_line(&p);
            p.have_lsystem = true;
            p.lsys_pos = at;
            continue;
        }
        if ((k = keyword(&p, "derivation length:"))) {
            c->pos += k;
            int32_t e = header_expr(&p, "derivation length:");
            /* only the main L-system's counts (cpfg) */
            if (!p.sub) {
                ls->dlength_expr = e;
                if (e >= 0)
                    ls->derivation_length =
                        eval_int(&p, e, at, "derivation length", 0,
                                 (int)(max_steps < 1000000000 ? max_steps : 1000000000));
            }
        } else if ((k = keyword(&p, "maximum depth:"))) {
            c->pos += k;
            int32_t e = header_expr(&p, "maximum depth:");
            if (p.set == p.pmain)
                cbm__cerr(c, at, "maximum depth: belongs to decomposition or homomorphism");
            else if (e >= 0)
                p.set->depth = eval_int(&p, e, at, "maximum depth", 0, max_depth);
        } else if ((k = keyword(&p, "seed:"))) {
            c->pos += k;
            int32_t e = header_expr(&p, "seed:");
            if (p.set == p.phomo)
                p.phomo->seed_expr = e;
            else if (p.set == p.pdecomp)
                cbm__cerr(c, at, "seed: belongs to the header or to the homomorphism");
            else if (!p.sub)
                ls->seed_expr = e; /* a sub-L-system's seed: is not used (cpfg) */
        } else if ((k = keyword(&p, "consider:"))) {
            c->pos += k;
            parse_symbols(&p, true);
        } else if ((k = keyword(&p, "ignore:"))) {
            c->pos += k;
            parse_symbols(&p, false);
        } else if ((k = keyword(&p, "define:"))) {
            c->pos += k;
            if (!cbm__parse_define_block(c))
                skip_line(&p);
            else
                expect_eol(&p, "define:");
        } else if ((k = keyword(&p, "start each:"))) {
            c->pos += k;
            parse_block_item(&p, p.blk[1], "StartEach:");
        } else if ((k = keyword(&p, "end each:"))) {
            c->pos += k;
            parse_block_item(&p, p.blk[2], "EndEach:");
        } else if ((k = keyword(&p, "start:"))) {
            c->pos += k;
            parse_block_item(&p, p.blk[0], "Start:");
        } else if ((k = keyword(&p, "end:"))) {
            c->pos += k;
            parse_block_item(&p, p.blk[3], "End:");
        } else if ((k = keyword(&p, "axiom:"))) {
            c->pos += k;
            if (p.have_axiom)
                cbm__cerr(c, at, "a second axiom");
            p.have_axiom = true;
            if (!parse_succ(&p, p.axiom, p.naxiom))
                skip_line(&p);
            else
                expect_eol(&p, "the axiom");
        } else if ((k = keyword(&p, "decomposition")) || (k = keyword(&p, "homomorphism"))) {
            bool homo = tolower((unsigned char)c->text[at]) == 'h';
            c->pos += k;
            if (c->text[c->pos] == ':')
                c->pos++;
            cbm__skip(c, false);
            size_t w;
            if ((w = keyword(&p, "no warnings")) || (w = keyword(&p, "warnings")))
                c->pos += w;
            prodset *s = homo ? p.phomo : p.pdecomp;
            if (s->present || (!homo && p.phomo->present))
                cbm__cerr(c, at,
                          homo ? "a second homomorphism section"
                               : "decomposition must come once, before homomorphism");
            s->present = true;
            s->depth = 1;
            p.set = s;
            expect_eol(&p, homo ? "homomorphism" : "decomposition");
        } else if ((k = keyword(&p, "endlsystem"))) {
            c->pos += k;
            p.ended = true;
        } else if (!p.have_axiom) {
            cbm__cerr(c, at,
                      "expected a header item (derivation length:, axiom:, ...) before "
                      "the productions");
            skip_line(&p);
        } else {
            parse_production(&p);
        }
    }
    if (!c->fatal) {
        size_t blank = 0;
        while (pp->text.data[blank] && isspace((unsigned char)pp->text.data[blank]))
            blank++;
        if (!p.have_lsystem && !pp->text.data[blank])
            cbm__cerr(c, c->pos, "the model is empty (expected 'Lsystem:')");
        else if (!p.have_lsystem)
            cbm__cerr(c, c->pos, "expected 'Lsystem:'");
        else if (!p.have_axiom)
            cbm__cerr(c, p.lsys_pos, "the L-system has no axiom:");
        else if (!p.ended)
            cbm__cerr(c, p.lsys_pos,
                      "expected 'endlsystem' at the end of the L-system (the file ends first)");
        for (size_t i = 0; i < p.calls.len; i++) {
            double v = p.calls.data[i].id;
            bool in = v >= -2e9 && v <= 2e9; /* a label is an int, as cpfg's (int) of it */
            int id = in ? (int)v : 0;
            bool found = in && id == ls->id;
            for (size_t j = 0; in && !found && j < ls->subs.len; j++)
                found = ls->subs.data[j].id == id;
            if (!found)
                cbm__cerr(c, p.calls.data[i].pos,
                          "?(%g, ...) calls a sub-L-system, but no L-system of the file is "
                          "labelled %g",
                          in ? (double)id : v, in ? (double)id : v);
        }
        cbm__check_globals(c);
    }
    CBM_ARRAY_FREE(ls->ctx, p.calls);
    if (c->status != CBM_OK && c->status != CBM_E_SYNTAX)
        return c->status;
    if (c->errors)
        return cbm__fail(ls->ctx, CBM_E_SYNTAX, "%zu error%s in the model", c->errors,
                         c->errors == 1 ? "" : "s");
    return CBM_OK;
}
