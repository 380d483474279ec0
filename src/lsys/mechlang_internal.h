/* Mechanics inside the L+C dialect: the statics engine run over the module string (mechlang.c).
 */
#ifndef CBM_LSYS_MECHLANG_INTERNAL_H
#define CBM_LSYS_MECHLANG_INTERNAL_H

#include "cambium/light.h"
#include "cambium/mech.h"
#include "lang/mechsegment.h"
#include "lsys/lsys_internal.h"

#include <string.h>

typedef struct cbm__mechlang {
    int seg_code;        /* module code carrying the segment, -1: none declared */
    int seg_off;         /* double offset of its MechSegment parameter */
    int mass_off[128];   /* per module code: double offset of the mass parameter, -1: not a mass */
    int radius_off[128]; /* per code: double offset of the contact radius (m), -1: none */
    int light_area_off[128], light_out_off[128]; /* per code: a leaf's area and light, -1 */
    int turtle[128]; /* per code: the turtle rotation it stands for (see mechlang.c), 0: none */
    int sb, eb;      /* codes of SB and EB */
    cbm_vec3 gravity;
    double ground_y, ground_k, ground_s; /* ground (m), stiffness (N/m; 0: none), smoothing (m) */
    double contact_k, contact_s;         /* organ contact stiffness (N/m; 0: none), smoothing (m) */
    cbm_tropism tropism;
    cbm_growth_def growth;
    cbm_solve_def solve;
    bool go_on; /* an unconverged equilibrium keeps its best state (result -passes) */
    cbm_mech_discretization discretization;
    /* The plant of the last operation, kept while the string (compared byte for byte) and the
     * settings it was built with are unchanged (mechlang.c); keep: whether to keep it. */
    struct cbm__mechkept *kept;
    bool keep;
    /* Sway(duration, dt, wind, gust) of the next CBM__ML_SWAY; SwayDrag's coherence decay and
     * leaf area per kg after them, and 1 in the next for SwayDrag (0: Sway); then the setting
     * SwayModes(K, static correction 0/1) (K = 0: the full motion) */
    double dyn_args[9];
    cbm_lsys_sway_fn sway_fn; /* observer of Sway() (cbm_lsys_set_sway_observer), NULL: none */
    void *sway_ud;
} cbm__mechlang;

/* A walk over the modules of a string (parameters in double) that keeps a path state across
 * the brackets: the caller's state (size bytes at `state`, e.g. the last mechanical segment
 * before the module on its path from the root) is pushed at each SB and restored at its EB (an
 * unmatched EB keeps it), before the bracket is shown to the caller. mechlang.c builds the
 * plant and lightlang.c places the leaves with it.
 *     cbm__mwalk w = cbm__mwalk_start(m, s, &path, sizeof path, &stack);
 *     while (cbm__mwalk_next(ctx, &w)) { ... w.code, w.np, w.p ... }
 *     (w.st: CBM_E_NOMEM when a push failed and the walk stopped)
 * The stack's memory is the caller's, to keep between walks (CBM_ARRAY_FREE when done). */
typedef CBM_ARRAY(unsigned char) cbm__mwalk_stack;
typedef struct cbm__mwalk {
    const cbm__mechlang *m;
    lstr *s;
    void *state;
    size_t size;
    cbm__mwalk_stack *stack; /* the states pushed at the open SBs */
    size_t i, j, k;          /* the next module, parameter count and parameter */
    size_t at;               /* the module shown: its index, */
    int code, np;            /* code (7 bits) and parameter count */
    double *p;               /* and parameters */
    cbm_status st;
} cbm__mwalk;

static inline cbm__mwalk cbm__mwalk_start(const cbm__mechlang *m, lstr *s, void *state, size_t size,
                                          cbm__mwalk_stack *stack)
{
    stack->len = 0;
    return (cbm__mwalk){.m = m, .s = s, .state = state, .size = size, .stack = stack};
}

/* Shows the next module; false at the end of the string or after a failed push. */
static inline bool cbm__mwalk_next(cbm_context *ctx, cbm__mwalk *w)
{
    const lstr *s = w->s;
    if (w->i >= s->n || w->st != CBM_OK)
        return false;
    uint8_t sym = s->sym[w->i];
    w->at = w->i++;
    w->code = sym & 0x7f;
    w->np = (sym & LSYS_PARAM_BIT) ? s->pc[w->j] : 0;
    w->p = (double *)s->par + w->k;
    if (sym & LSYS_PARAM_BIT) {
        w->j++;
        w->k += (size_t)w->np;
    }
    if (w->code == w->m->sb) {
        cbm__mwalk_stack *k = w->stack;
        w->st = CBM_ARRAY_RESERVE(ctx, *k, k->len + w->size);
        if (w->st != CBM_OK)
            return false;
        memcpy(k->data + k->len, w->state, w->size);
        k->len += w->size;
    } else if (w->code == w->m->eb && w->stack->len) {
        w->stack->len -= w->size;
        memcpy(w->state, w->stack->data + w->stack->len, w->size);
    }
    return true;
}

/* The plant's dynamics for the dialect (mechlang_dyn.c): the k-th lowest natural frequency (Hz)
 * and the peak displacement (m) of any node over a sway in the wind of args (duration s, dt s,
 * U_ref m/s at 10 m, gust intensity, then for SwayDrag (args[6] = 1) the gust field's coherence
 * decay and the leaves' area per kg). The plant must be evaluated. */
cbm_status cbm__mechlang_frequency(cbm_context *ctx, const cbm_plant *p, size_t k, double *hz);
cbm_status cbm__mechlang_sway(cbm_context *ctx, const cbm_plant *p, const double *args,
                              cbm_lsys_sway_fn fn, void *ud, double *peak);

enum {
    CBM__ML_EQUILIBRIUM,
    CBM__ML_RINGS,
    CBM__ML_AGE,
    CBM__ML_BREAK,
    CBM__ML_STABILITY,
    CBM__ML_FREQUENCY, /* arg: k; the k-th lowest natural frequency, Hz */
    CBM__ML_SWAY       /* dyn_args: duration, dt, wind, gust; the peak displacement, m */
};

/* Defaults: no segment module, gravity (0, -9.81, 0), no ground, no tropism, growth and solve
 * defaults. */
void cbm__mechlang_init(cbm__mechlang *m);

/* Frees the kept plant (m stays usable: the next operation builds a new one). */
void cbm__mechlang_free(cbm_context *ctx, cbm__mechlang *m);

/* Runs one operation over the string s (parameters in double): builds the plant from the
 * segments of the string, does `op` (arg: years for CBM__ML_AGE), writes the results back into
 * the segments' parameters, and for CBM__ML_BREAK removes the broken segments and the rest of
 * their branches from the string. *result: passes (equilibrium), rings added, segments aged,
 * segments broken (equilibrium: minus the passes when the solve did not converge and go_on is
 * set; the best state is kept), the stability factor (CBM__ML_STABILITY: cbm_plant_stability_factor
 * at the stored omega; the string is not changed). Errors go to err (a message) with the status.
 * The wall-clock time of the operation is added to *timing (may be NULL). The plant is kept in m
 * for the next operation while the string and the settings stay as this one left them (with the
 * same results as a new build); a Break() that cuts drops it. */
cbm_status cbm__mechlang_run(cbm_context *ctx, cbm__mechlang *m, lstr *s, int op, double arg,
                             double *result, char *err, size_t errn, cbm_lsys_mech_timing *timing);

/* A new plant of the string's segments at their stored state (cbm_lsys_mech_plant); *out NULL
 * and a message in err on failure. */
cbm_status cbm__mechlang_plant(cbm_context *ctx, const cbm__mechlang *m, lstr *s, cbm_plant **out,
                               char *err, size_t errn);

/* Light(sky, samples) (lightlang.c): the light every leaf module of s (declared `light:`)
 * intercepts under the sky (cbm_sky_kind), written into its light parameter, in m^2 of
 * unshaded horizontal leaf; *total their sum. A leaf is a horizontal square of its area,
 * centred on the distal node of the mechanical segment it follows, at the positions the last
 * mechanics operation wrote. Errors go to err with the status. */
cbm_status cbm__lightlang_run(cbm_context *ctx, const cbm__mechlang *m, lstr *s, int sky,
                              int samples, double *total, char *err, size_t errn);

#endif
