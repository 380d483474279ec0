/* Internal structures of the L-system engine: the compiled model and the packed module string.
 *
 * The module string is three contiguous arrays, double-buffered between steps:
 *   sym[i]  the symbol of module i (7-bit ASCII); bit 7 set when the module has parameters;
 *   pc[j]   the parameter count of the j-th parametric module;
 *   par[k]  all parameters, in order (double; float in float32 mode, as cpfg stores them).
 * A non-parametric module costs one byte, and walking left or right (context matching) only
 * needs the three running indices (module, parametric module, parameter).
 *
 * Sub-L-systems (cpfg manual 7.2): the L-system a module belongs to is not stored per module;
 * it is given by the string itself, as in cpfg: `?(id, scale)` opens L-system `id` and `$`
 * returns to the one that opened it, so a left-to-right pass keeps a stack of L-system indices
 * (lstack) and knows each module's L-system from it. A model without sub-L-systems (no second
 * `Lsystem:` and no `?(id)` in an axiom or successor) never takes that path, so its string and
 * its derivation are exactly what they were without the feature.
 */
#ifndef CBM_LSYS_INTERNAL_H
#define CBM_LSYS_INTERNAL_H

#include "cambium/lsys.h"
#include "lang/lang.h"
#include "lsys/lsys.h"

#include <stddef.h>
#include <stdio.h>

#define LSYS_PARAM_BIT  0x80u
#define LSYS_MAX_PARAMS 255

typedef struct lstr {
    uint8_t *sym;
    size_t n, cap;
    uint8_t *pc;
    size_t npm, pccap;
    void *par; /* double, or float in float32 mode */
    size_t npar, parcap;
    bool f32;
} lstr;

/* A position in a string: module `mod`, with the indices that go with it in the other two
 * arrays. */
typedef struct lpos {
    size_t mod;   /* the module's index (in sym) */
    size_t pmod;  /* the parametric modules before it: its parameter count is pc[pmod] */
    size_t param; /* the parameters before it: its first parameter is par[param] */
} lpos;

/* ---- The parts of a step both dialects share (here and step.c) ----
 * Walking the packed string (a module, its parameter count, its parameters), making room in
 * it, copying and appending modules, the bracket table that makes skipping a branch a jump, and
 * the step loop itself. What the dialects do differently (matching a production, producing its
 * successor, cutting, decomposition, interpretation) stays in derive.c and lpfg.c, the step's as
 * the hooks of the loop (docs/design.md, "The step"). */

/* the bytes of one parameter of s */
static inline size_t cbm__param_size(const lstr *s)
{
    return s->f32 ? sizeof(float) : sizeof(double);
}

/* p to the next module of s */
static inline void cbm__pos_next(const lstr *s, lpos *p)
{
    if (s->sym[p->mod++] & LSYS_PARAM_BIT)
        p->param += s->pc[p->pmod++];
}

/* p to the previous module of s */
static inline void cbm__pos_prev(const lstr *s, lpos *p)
{
    if (s->sym[--p->mod] & LSYS_PARAM_BIT)
        p->param -= s->pc[--p->pmod];
}

/* the parameter count of the module at p */
static inline int cbm__module_params(const lstr *s, const lpos *p)
{
    return (s->sym[p->mod] & LSYS_PARAM_BIT) ? s->pc[p->pmod] : 0;
}

/* n parameters from parameter index k of s into dst, as doubles */
static inline void cbm__params_load(const lstr *s, size_t k, double *dst, int n)
{
    if (s->f32) {
        const float *p = (const float *)s->par + k;
        for (int i = 0; i < n; i++)
            dst[i] = p[i];
    } else {
        memcpy(dst, (const double *)s->par + k, (size_t)n * sizeof(double));
    }
}

static inline void cbm__lstr_clear(lstr *s)
{
    s->n = s->npm = s->npar = 0;
}

/* room for nsym more modules, npm more parameter counts and npar more parameters */
static inline cbm_status cbm__lstr_room(cbm_context *ctx, lstr *s, size_t nsym, size_t npm,
                                        size_t npar)
{
    if (s->n + nsym > s->cap)
        CBM_TRY(cbm__grow(ctx, (void **)&s->sym, &s->cap, 1, s->n + nsym));
    if (s->npm + npm > s->pccap)
        CBM_TRY(cbm__grow(ctx, (void **)&s->pc, &s->pccap, 1, s->npm + npm));
    if (s->npar + npar > s->parcap)
        CBM_TRY(cbm__grow(ctx, &s->par, &s->parcap, cbm__param_size(s), s->npar + npar));
    return CBM_OK;
}

/* appends the module at *p of src to dst (both of the same parameter width) and moves *p to
 * the next module */
static inline cbm_status cbm__lstr_copy_module(cbm_context *ctx, const lstr *src, lpos *p,
                                               lstr *dst)
{
    int np = cbm__module_params(src, p);
    CBM_TRY(cbm__lstr_room(ctx, dst, 1, 1, (size_t)np));
    dst->sym[dst->n++] = src->sym[p->mod];
    if (np) {
        size_t w = cbm__param_size(src);
        dst->pc[dst->npm++] = (uint8_t)np;
        memcpy((char *)dst->par + dst->npar * w, (const char *)src->par + p->param * w,
               (size_t)np * w);
        dst->npar += (size_t)np;
    }
    cbm__pos_next(src, p);
    return CBM_OK;
}

/* appends every module of src to dst, in reverse order when reversed */
cbm_status cbm__lstr_append(cbm_context *ctx, lstr *dst, const lstr *src, bool reversed);

/* The bracket matching of a string a right context walks: for every opening bracket (in the
 * order of the string) the position of the bracket that closes it, so that skipping a branch
 * is a jump, not a scan, and right contexts stay linear in the bracket depth. Extended lazily
 * up to the string's end at every look-up: a string being read is fixed, one being produced
 * only grows. dir +1 describes a string read left to right; dir -1 one built reversed (the L+C
 * dialect's new string going Backward(), where a closing bracket comes before its opening one
 * and waits for it). */
typedef struct cbm__brackets {
    const lstr *s;            /* the string it describes, NULL: none */
    int dir;                  /* +1 or -1, above */
    uint8_t open, close;      /* the bracket symbols: '[' ']', or the L+C dialect's SB EB codes */
    lpos at;                  /* modules before at.mod are in the table */
    CBM_ARRAY(size_t) opened; /* module index of every opening bracket, increasing */
    CBM_ARRAY(lpos) closed;   /* the closing bracket that matches it; mod == SIZE_MAX: none */
    CBM_ARRAY(lpos) waiting;  /* brackets waiting for their match (.mod: an index in opened) */
} cbm__brackets;

/* The table describes string s read in direction dir (forgetting what it held). */
void cbm__brackets_start(cbm__brackets *t, const lstr *s, int dir, uint8_t open, uint8_t close);
/* The opening bracket at module `at` of s: the position of the bracket that closes it in
 * *close (mod == SIZE_MAX when none does). False when the table does not describe s in direction
 * dir, or memory refuses (the table is then dropped and the caller scans). */
bool cbm__brackets_jump(cbm_context *ctx, cbm__brackets *t, const lstr *s, int dir, size_t at,
                        lpos *close);
void cbm__brackets_free(cbm_context *ctx, cbm__brackets *t);

/* A walk over a packed string, for context matching: a position and a reading direction, dir
 * +1 left to right, -1 right to left (the L+C dialect's new string, built reversed going
 * Backward()). The position is an lpos's (mod, pmod, param), but mod runs from -1 (before the
 * first module in memory) to n (after the last). */
typedef struct cbm__walk {
    const lstr *s;
    ptrdiff_t mod;
    size_t pmod, param;
    int dir;
} cbm__walk;

static inline cbm__walk cbm__walk_at(const lstr *s, size_t mod, size_t pmod, size_t param, int dir)
{
    cbm__walk w = {s, (ptrdiff_t)mod, pmod, param, dir};
    return w;
}

/* whether w is on a module of its string */
static inline bool cbm__walk_inside(const cbm__walk *w)
{
    return w->mod >= 0 && (size_t)w->mod < w->s->n;
}

/* the symbol of the module w is on */
static inline int cbm__walk_symbol(const cbm__walk *w)
{
    return w->s->sym[w->mod] & 0x7f;
}

/* a step in memory order, whatever the direction */
static inline void cbm__walk_next_in_memory(cbm__walk *w)
{
    if (w->s->sym[w->mod] & LSYS_PARAM_BIT)
        w->param += w->s->pc[w->pmod++];
    w->mod++;
}

static inline void cbm__walk_prev_in_memory(cbm__walk *w)
{
    w->mod--;
    if (w->mod >= 0 && (w->s->sym[w->mod] & LSYS_PARAM_BIT))
        w->param -= w->s->pc[--w->pmod];
}

/* a step in the walk's direction; false when it leaves the string */
static inline bool cbm__walk_forward(cbm__walk *w)
{
    if (!cbm__walk_inside(w))
        return false;
    if (w->dir > 0)
        cbm__walk_next_in_memory(w);
    else
        cbm__walk_prev_in_memory(w);
    return cbm__walk_inside(w);
}

/* a step against the walk's direction; false when it leaves the string (or is out of it) */
static inline bool cbm__walk_backward(cbm__walk *w)
{
    if (w->dir > 0) {
        if (w->mod <= 0) {
            w->mod = -1;
            return false;
        }
        if (w->mod > (ptrdiff_t)w->s->n)
            return false;
        cbm__walk_prev_in_memory(w);
    } else {
        if (w->mod >= (ptrdiff_t)w->s->n - 1) {
            w->mod = (ptrdiff_t)w->s->n;
            return false;
        }
        if (w->mod < 0) /* before the logical start */
            return false;
        cbm__walk_next_in_memory(w);
    }
    return true;
}

/* w is on an opening bracket: moves it to the closing bracket of that branch, through table t
 * when it describes w's string in w's direction (t may be NULL), else by a scan. False when
 * the branch is not closed. */
bool cbm__walk_skip_branch(cbm_context *ctx, cbm__brackets *t, cbm__walk *w, int open, int close);
/* Moves w forward to the closing bracket of the branch it is in, over the branches inside;
 * false when there is none. */
bool cbm__walk_to_branch_end(cbm_context *ctx, cbm__brackets *t, cbm__walk *w, int open, int close);
/* The bracket-depth test of a scan for the bracket that closes the current nesting level:
 * symbol c met, depth the branches entered so far (opened by `opener`); true when c is the
 * `closer` of the level the scan started in. */
static inline bool cbm__closes_level(int c, int opener, int closer, int *depth)
{
    if (c == opener) {
        ++*depth;
        return false;
    }
    return c == closer && (*depth)-- == 0;
}

/* Walks to the bracket that closes the current nesting level: forward to its closing bracket
 * (opener: the opening one), or backward to its opening one (opener: the closing one).
 * Branches met on the way are passed whole. A scan in memory order, up or down whatever the
 * walk's direction (the left contexts of a bracketed string spend their time here). */
static inline bool cbm__walk_find_closing(cbm__walk *w, int opener, int closer, bool forward)
{
    const lstr *s = w->s;
    const ptrdiff_t n = (ptrdiff_t)s->n;
    ptrdiff_t mod = w->mod;
    size_t pmod = w->pmod, param = w->param;
    int depth = 0;
    if (forward == (w->dir > 0)) { /* up in memory */
        for (; mod >= 0 && mod < n; mod++) {
            uint8_t b = s->sym[mod];
            if (cbm__closes_level(b & 0x7f, opener, closer, &depth)) {
                w->mod = mod, w->pmod = pmod, w->param = param;
                return true;
            }
            if (b & LSYS_PARAM_BIT)
                param += s->pc[pmod++];
        }
    } else { /* down */
        if (mod >= n)
            mod = -1;
        for (; mod >= 0; mod--) {
            if (cbm__closes_level(s->sym[mod] & 0x7f, opener, closer, &depth)) {
                w->mod = mod, w->pmod = pmod, w->param = param;
                return true;
            }
            if (mod > 0 && (s->sym[mod - 1] & LSYS_PARAM_BIT))
                param -= s->pc[--pmod];
        }
    }
    w->mod = mod < 0 ? -1 : n;
    return false;
}

/* Moves w backward to the opening bracket of the branch it is in, over the branches inside;
 * false when there is none. */
static inline bool cbm__walk_to_branch_start(cbm__walk *w, int open, int close)
{
    return cbm__walk_find_closing(w, close, open, false);
}

/* The step loop, written once for both dialects (derive.c, lpfg.c): every module of the current
 * string, in the pass's direction, is rewritten by the production that applies at it, or else
 * handled as unmatched (copied, cut, decomposed), and then the dialect's bookkeeping runs. What
 * a dialect does at each of these points is its table of hooks; d is its pass state. */
typedef struct cbm__step_hooks {
    /* Rewrites the module at *p (its symbol c) with the production that applies there (its
     * successor written), moving *p past the modules of its predecessor; *applied false: none
     * applies, *p is left where it was. */
    cbm_status (*rewrite)(void *d, lpos *p, size_t c, bool *applied);
    /* The module at *p (its symbol c), no production applying: copied, or cut with the rest
     * of its branch, or decomposed; moves *p past what it consumed. */
    cbm_status (*unmatched)(void *d, lpos *p, size_t c);
    /* After the modules from `from` up to *p were consumed: sub-L-system markers, limits,
     * handing pages back. */
    cbm_status (*after)(void *d, const lpos *from, const lpos *p);
} cbm__step_hooks;

/* The loop over string s from p. A pass that reads s right to left (the L+C dialect's
 * Backward()) moves before its first module to p.mod == SIZE_MAX, past the end of any string, so
 * one test ends both directions. Always inline, and each dialect passes a constant table: each
 * dialect's instance of the loop calls its hooks directly (or inlines them), with no call
 * through a pointer per module (the Koch curve spends a few nanoseconds per module). */
static inline __attribute__((always_inline)) cbm_status
cbm__step_loop(const cbm__step_hooks *h, void *d, const lstr *s, lpos p)
{
    while (p.mod < s->n) {
        const lpos from = p;
        const size_t c = s->sym[p.mod] & 0x7fu;
        bool applied;
        CBM_TRY(h->rewrite(d, &p, c, &applied));
        if (!applied)
            CBM_TRY(h->unmatched(d, &p, c));
        CBM_TRY(h->after(d, &from, &p));
    }
    return CBM_OK;
}

/* A module of a predecessor or context: symbol and parameter count. Formal parameter names are
 * slots of the production's frame in the order they appear (left context, predecessor, right
 * context). */
typedef struct fmodule {
    uint8_t sym, np;
} fmodule;

/* A module of a successor: symbol and its parameter expressions (a chain of nodes). */
typedef struct smod {
    uint8_t sym, np;
    int32_t args;
} smod;

typedef struct prod {
    int32_t left_ctx, nleft_ctx;   /* left context in fmods, in text order */
    int32_t pred, npred;           /* strict predecessor */
    int32_t right_ctx, nright_ctx; /* right context */
    int nformals;
    int32_t pre, cond, post, prob; /* -1: none */
    int32_t succ, nsucc;           /* in smods */
    bool const_succ;               /* successor without parameters: copied as bytes */
    int32_t succ_bytes;            /* offset in const_bytes */
    size_t pos;                    /* text offset, for messages */
} prod;

typedef struct prodset {
    CBM_ARRAY(prod) prods;
    int32_t *order; /* production indices grouped by first predecessor symbol */
    int32_t start[129];
    int depth;         /* maximum depth (decomposition, homomorphism) */
    int32_t seed_expr; /* homomorphism: its own random stream (seed:), -1 if none */
    bool present;
} prodset;

/* One L-system of the file. The first one's data are the fields of cbm_lsys (main, decomp,
 * homo, ignore, stochastic, the blocks); the others (sub-L-systems) are kept in `subs`. */
typedef struct sublsys {
    int id; /* its label, `Lsystem: id` */
    prodset main, decomp, homo;
    bool ignore[128];
    bool stochastic;
    int32_t start_block, end_block, start_each, end_each;
    int32_t axiom, naxiom; /* read and checked; a called sub-L-system does not use it (cpfg) */
} sublsys;

/* A view of one L-system for the derivation: index 0 is the first (main) L-system. */
typedef struct lsysv {
    int id;
    const prodset *main, *decomp, *homo;
    const bool *ignore;
    bool stochastic;
    int32_t blocks[4]; /* Start, StartEach, EndEach, End */
} lsysv;

struct cbm_lsys {
    cbm_context *ctx;
    cbm__compiler comp; /* nodes, globals, arrays */
    CBM_ARRAY(fmodule) fmods;
    CBM_ARRAY(smod) smods;
    CBM_ARRAY(uint8_t) const_bytes;
    prodset main, decomp, homo;
    bool ignore[128];
    bool stochastic;
    bool float32;
    bool ignore_seed;
    int64_t seed_override; /* -1: none */
    int solver_override;   /* -1: none; else the cbm_mech_solver of every mechanics operation */
    long loop_budget;      /* the model's max_loop_iterations, 0: the context's limit */
    bool nonfinite_warned; /* the warning of limits.allow_nonfinite was given */
    long ops;              /* productions applied in decomposition / homomorphism: budget left */
    /* the bracket tables of the strings a right context walks (step.c): the cpfg dialect's
     * current string in [0] (valid while brackets_gen == cur_gen); the L+C dialect's current
     * string in [0] and its new string, built reversed going Backward(), in [1] */
    cbm__brackets brackets[2];
    unsigned cur_gen, brackets_gen; /* cur_gen changes whenever the current string does */
    double (*func)(void *ud, int id, double x);
    void *func_ud;
    cbm_lsys_interpret_fn interp;
    void *interp_ud;
    double *array_init; /* initial values of all arrays, concatenated */
    size_t array_init_len;
    int32_t axiom, naxiom; /* in smods */
    int32_t start_block, end_block, start_each, end_each;
    int32_t dlength_expr, seed_expr;
    int derivation_length;
    int max_formals;
    int32_t q_slot; /* global Q: the current step */
    /* sub-L-systems */
    int id;                  /* label of the first L-system */
    CBM_ARRAY(sublsys) subs; /* the L-systems after the first */
    lsysv *sys;              /* all L-systems, the first at 0 (built after parsing) */
    int nsys;
    bool subcalls;   /* several L-systems or a ?(id) anywhere: passes follow the ?(id) and $ */
    int max_depth;   /* deepest decomposition or homomorphism of all L-systems */
    const bool *ign; /* the ignore table of the L-system being matched */
    /* run state */
    cbm__eval ev;
    double *globals;
    size_t nglobals;
    double *frame;
    cbm__rand48 drand; /* drand48 stream of stochastic choice */
    lstr cur, next, homo_str, succ;
    CBM_ARRAY(lstr) scratch; /* successor buffers per decomposition depth */
    CBM_ARRAY(int32_t) appl; /* applicable productions (stochastic) */
    CBM_ARRAY(float) applp;
    CBM_ARRAY(uint16_t) lstack; /* L-system stack of a pass over a string with sub-L-systems */
    cbm__rand48 *hran;          /* per L-system: the homomorphism's own stream (seed:) */
    int steps;
    bool homo_valid;
    cbm_lsys_mech_timing mech_time; /* mechanics operations since the last reset */
    struct lpfg *lp; /* the L+C dialect's model (lpfg.c), NULL for the cpfg dialect */
    const struct cbm__dialect *dialect; /* its step protocol (below) */
};

/* The step protocol where the two dialects differ: the public entry points (cbm_lsys_reset,
 * _step, _apply_homomorphism, _has_homomorphism, _write_str, _func_names, _set_func_ids) and
 * cbm__lsys_describe call the model's dialect through this table instead of testing which
 * dialect it is. The cpfg dialect's is in derive.c, write.c and lsys.c, the L+C dialect's in
 * lpfg.c. */
typedef struct cbm__dialect {
    cbm_status (*reset)(cbm_lsys *ls);              /* Start, the axiom */
    cbm_status (*step)(cbm_lsys *ls);               /* one derivation step */
    cbm_status (*interpret)(cbm_lsys *ls);          /* homomorphism / interpretation rules */
    bool (*has_interpretation)(const cbm_lsys *ls); /* the model has such rules */
    cbm_status (*write_str)(const cbm_lsys *ls, bool homomorphism, cbm_out *o); /* `.str` */
    /* its rules and modules in a model's summary (the fields cbm__lsys_describe leaves) */
    void (*describe)(const cbm_lsys *ls, cbm_model_summary *out);
    /* the names of func(name, x) and the function ids they call (the cpfg dialect's func(id,
     * x) takes the id itself: no names) */
    size_t (*func_names)(const cbm_lsys *ls, const char *const **names);
    cbm_status (*set_func_ids)(cbm_lsys *ls, const int *ids, size_t n);
} cbm__dialect;
extern const cbm__dialect cbm__cpfg_dialect, cbm__lpfg_dialect;
cbm_status cbm__cpfg_write_str(const cbm_lsys *ls, bool homomorphism, cbm_out *o);
void cbm__cpfg_describe(const cbm_lsys *ls, cbm_model_summary *out);
size_t cbm__cpfg_func_names(const cbm_lsys *ls, const char *const **names);
cbm_status cbm__cpfg_set_func_ids(cbm_lsys *ls, const int *ids, size_t n);

void cbm__lstr_free(cbm_context *ctx, lstr *s);

/* Buffered text for the string writers (write.c): bytes and characters, numbers as "%.9g" (byte
 * for byte snprintf's text, memoised by value) and "%lld". open gives NULL when memory runs out
 * (close(NULL) then says CBM_E_NOMEM); close flushes, frees and reports a write error. */
#define STRW_BUF   (1u << 16)
#define STRW_SLOTS 4096u
#define STRW_TXT   32 /* "%.9g" of a double: at most 16 characters ("-1.23456789e-308") */

typedef struct cbm__strw {
    cbm_context *ctx;
    FILE *f;
    size_t n;
    bool err;
    uint64_t key[STRW_SLOTS];
    uint8_t len[STRW_SLOTS]; /* 0: empty slot */
    char txt[STRW_SLOTS][STRW_TXT];
    char buf[STRW_BUF];
} cbm__strw;

cbm__strw *cbm__strw_open(cbm_context *ctx, FILE *f);
void cbm__strw_flush(cbm__strw *w);
void cbm__strw_big(cbm__strw *w, const char *s, size_t n);
/* inline: the writers call these per character and per module */
static inline void cbm__strw_bytes(cbm__strw *w, const char *s, size_t n)
{
    if (n > STRW_BUF - w->n) {
        cbm__strw_big(w, s, n);
        return;
    }
    char *d = w->buf + w->n;
    for (size_t i = 0; i < n; i++) /* short texts: a loop, not a call */
        d[i] = s[i];
    w->n += n;
}
static inline void cbm__strw_char(cbm__strw *w, char c)
{
    if (w->n == STRW_BUF)
        cbm__strw_flush(w);
    w->buf[w->n++] = c;
}
void cbm__strw_g9(cbm__strw *w, double v);
void cbm__strw_lld(cbm__strw *w, long long v);
cbm_status cbm__strw_close(cbm__strw *w);
/* Index in ls->sys of the L-system labelled id, -1 if none. */
int cbm__lsys_find(const cbm_lsys *ls, int id);
cbm_status cbm__lsys_parse(cbm_lsys *ls, const cbm__pp *pp);

/* The L+C (lpfg) dialect, lpfg.c: compiled by lang/lc_parse.c (detected there by the file's
 * form, cbm__lc_detect), derived over the same packed string. */
cbm_status cbm__lpfg_parse(cbm_lsys *ls, const cbm__pp *pp);
void cbm__lpfg_free(cbm_lsys *ls);
/* Whether the mechanics keep their plant between operations (default true; false: every
 * operation builds a new one, as a reference for tests). */
void cbm__lpfg_mech_keep(cbm_lsys *ls, bool keep);
cbm_status cbm__lpfg_reset(cbm_lsys *ls);
/* The production bodies compiled to the register code (lang/lc_code.h), of all (a production
 * without a body has none); whether body `index` of rule set `set` (LC_MAIN, LC_DECOMP,
 * LC_INTERP) is compiled. */
void cbm__lpfg_bodies(const cbm_lsys *ls, size_t *compiled, size_t *total);
bool cbm__lpfg_body_compiled(const cbm_lsys *ls, int set, size_t index);
cbm_status cbm__lpfg_step(cbm_lsys *ls);
cbm_status cbm__lpfg_interpretation(cbm_lsys *ls);
bool cbm__lpfg_has_interpretation(const cbm_lsys *ls);
cbm_status cbm__lpfg_write_str(const cbm_lsys *ls, bool homomorphism, cbm_out *o);
const char *cbm__lpfg_module_name(const cbm_lsys *ls, int symbol);
size_t cbm__lpfg_func_names(const cbm_lsys *ls, const char *const **names);
cbm_status cbm__lpfg_set_func_ids(cbm_lsys *ls, const int *ids, size_t n);
/* An L+C model in a model's summary: the dialect, whether it has mechanics, its productions,
 * decomposition and interpretation rules with their depths, declared modules (turtle modules
 * included). */
void cbm__lpfg_describe(const cbm_lsys *ls, cbm_model_summary *out);
/* cbm__lpfg_mech_fields: the package header lsys/lsys.h */

#endif
