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

/* a position in a string */
typedef struct lpos {
    size_t i, j, k;
} lpos;

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
    int32_t lc, nlc;     /* left context in fmods, in text order */
    int32_t pred, npred; /* strict predecessor */
    int32_t rc, nrc;     /* right context */
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
    /* bracket matching of the current string, built on the first right-context match that
     * skips a branch in it (brk_gen == cur_gen): skipping a branch is then a jump, not a scan,
     * so right contexts stay linear in the bracket depth */
    CBM_ARRAY(size_t) brk_open; /* module index of every '[', in order */
    CBM_ARRAY(lpos) brk_close;  /* the position after its ']' (the end when unmatched) */
    CBM_ARRAY(size_t) brk_stack;
    unsigned cur_gen, brk_gen; /* cur_gen changes whenever the current string does */
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
