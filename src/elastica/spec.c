/* The spec of the `elastica` command: the `bend` spec (read by bend's own reader, so its keys,
 * ranges and messages are the same) plus the elastica's keys, which are taken out of the text
 * first: their lines are blanked in a copy (line and column numbers stay right) before the
 * copy goes to cbm_bend_spec_parse. `alpha` means the non-dimensional load here (bend's
 * relaxation factor has no use for a continuous rod), and `angle` may be any angle.
 *
 *   alpha = 15                 # rho g L^3 / D: non-dimensional mode (L = D = 1)
 *   angle = 90                 # clamp angle, degrees (any)
 *   theta_tip_min = -90        # the scanned tip angles, degrees
 *   theta_tip_max = 270
 *   branch = parent 0 offset 20 length 0.5 stiffness 0.1 weight 0.3
 */
#include "cambium/elastica_growth.h"
#include "elastica_internal.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>

typedef struct spec_reader {
    cbm_context *ctx;
    const char *file;
    int errors;
} spec_reader;

CBM_PRINTF(4, 5)
static void spec_error(spec_reader *r, int line, int col, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    cbm__vdiag(r->ctx, CBM_ERROR, r->file, line, col, fmt, ap);
    va_end(ap);
    r->errors++;
}

static bool word(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '-' || c == '.' || c == '+';
}

/* A number token text[p..q); false (reported) if not a finite number in [lo, hi]. */
static bool number(spec_reader *r, const char *name, const char *t, size_t n, int line, int col,
                   double lo, double hi, double *out)
{
    char buf[64];
    if (n == 0 || n >= sizeof buf) {
        spec_error(r, line, col, "'%s' expects a number", name);
        return false;
    }
    memcpy(buf, t, n);
    buf[n] = 0;
    errno = 0;
    char *end = NULL;
    double x = strtod(buf, &end);
    if (end == buf || *end || errno == ERANGE || !isfinite(x)) {
        spec_error(r, line, col, "'%s' expects a finite number, found '%s'", name, buf);
        return false;
    }
    if (x < lo || x > hi) {
        spec_error(r, line, col, "'%s' = %s is out of range (%g .. %g)", name, buf, lo, hi);
        return false;
    }
    *out = x;
    return true;
}

enum {
    S_ALPHA,
    S_ANGLE,
    S_TMIN,
    S_TMAX,
    S_SMIN,
    S_SMAX,
    S_BRANCH,
    /* growth under control (steps > 0; docs/elastica.md "Growth") */
    S_TAPER,
    S_LAW,
    S_CONTROL,
    S_SRATIO,
    S_STAU,
    S_EFINAL,
    S_ETAU,
    S_SLOAD,
    S_SLOADPT,
    S_PREF,
    S_INDUCED,
    S_SUBSTEPS,
    S_STEPTIME,
    S_SIDE,
    S_N
};
static const char *const own[S_N] = {"alpha",
                                     "angle",
                                     "theta_tip_min",
                                     "theta_tip_max",
                                     "sweep_min",
                                     "sweep_max",
                                     "branch",
                                     "taper",
                                     "law",
                                     "control",
                                     "stiffness_ratio",
                                     "stiffness_tau",
                                     "youngs_final",
                                     "youngs_tau",
                                     "segment_load",
                                     "segment_load_point",
                                     "preferred_angle",
                                     "induced_rate",
                                     "substeps",
                                     "step_time",
                                     "side"};
static const double own_lo[S_N] = {0,     -720,   -3600, -3600, -720, -720, 0,    0, 0,     -1e6, 1,
                                   1e-12, 1e-300, 0,     0,     0,    -720, -1e6, 1, 1e-12, -1};
static const double own_hi[S_N] = {1e6,  720,   3600, 3600, 720, 720, 0,   0,     0,    1e6, 1e6,
                                   1e12, 1e300, 1e12, 1e12, 1,   720, 1e6, 10000, 1e12, 1};

/* keys of the base rod that have no meaning in the non-dimensional mode */
static const char *const dim_keys[] = {"length",  "radius",  "radius_base", "radius_tip", "E",
                                       "density", "gravity", "tip_mass",    "aspect"};
#define N_DIM (sizeof dim_keys / sizeof *dim_keys)

typedef struct branch_line {
    int line;
    int col_dim, col_nondim; /* columns of a mode-specific key (0: none) */
    const char *dim_name, *nondim_name;
} branch_line;

static void parse_branch(spec_reader *r, const char *t, size_t p, size_t e, size_t ls, int line,
                         size_t idx, cbm_elastica_branch_spec *b, branch_line *bl)
{
    static const char *const names[] = {"parent",     "offset",         "length",    "radius",
                                        "radius_tip", "stiffness",      "weight",    "tip_load",
                                        "tip_mass",   "rest_curvature", "tip_moment"};
    memset(b, 0, sizeof *b);
    b->stiffness = 1, b->weight = 1, b->parent = -1;
    memset(bl, 0, sizeof *bl);
    bl->line = line;
    bool seen[11] = {false};
    while (p < e) {
        while (p < e && (t[p] == ' ' || t[p] == '\t' || t[p] == '\r'))
            p++;
        if (p >= e)
            break;
        size_t ks = p;
        while (p < e && word(t[p]))
            p++;
        int kcol = (int)(ks - ls) + 1;
        size_t kn = p - ks;
        if (kn == 0) {
            spec_error(r, line, kcol, "unexpected '%c' in a branch line", t[ks]);
            return;
        }
        size_t k = 0;
        while (k < 11 && !(strlen(names[k]) == kn && !memcmp(names[k], t + ks, kn)))
            k++;
        if (k == 11) {
            spec_error(r, line, kcol,
                       "unknown branch key '%.*s' (parent, offset, length, radius, ...)",
                       (int)(kn > 40 ? 40 : kn), t + ks);
            return;
        }
        if (seen[k]) {
            spec_error(r, line, kcol, "branch key '%s' given twice", names[k]);
            return;
        }
        seen[k] = true;
        while (p < e && (t[p] == ' ' || t[p] == '\t'))
            p++;
        size_t vs = p;
        while (p < e && word(t[p]))
            p++;
        int vcol = (int)(vs - ls) + 1;
        double lo = -1e12, hi = 1e12, x = 0;
        if (k == 0)
            lo = 0, hi = (double)idx;
        else if (k == 1)
            lo = -720, hi = 720;
        else if (k >= 2 && k <= 5)
            lo = 1e-300, hi = 1e6;
        else if (k == 6 || k == 8)
            lo = 0;
        if (!number(r, names[k], t + vs, p - vs, line, vcol, lo, hi, &x))
            return;
        if (k == 0 && x != floor(x)) {
            spec_error(r, line, vcol, "'parent' expects a whole number");
            return;
        }
        double *f[] = {NULL,           &b->offset,         &b->length,    &b->radius,
                       &b->radius_tip, &b->stiffness,      &b->weight,    &b->tip_load,
                       &b->tip_mass,   &b->rest_curvature, &b->tip_moment};
        if (k == 0)
            b->parent = (int)x;
        else
            *f[k] = x;
        if ((k == 3 || k == 4 || k == 8) && !bl->col_dim)
            bl->col_dim = kcol, bl->dim_name = names[k];
        if ((k == 5 || k == 6) && !bl->col_nondim)
            bl->col_nondim = kcol, bl->nondim_name = names[k];
    }
    if (!seen[0])
        spec_error(r, line, 1,
                   "a branch needs 'parent' (0: the base rod, k: the k-th branch line)");
}

cbm_status cbm_elastica_spec_parse(cbm_context *ctx, const char *text, size_t len, const char *file,
                                   cbm_elastica_spec *out)
{
    if (!ctx || (!text && len) || !out)
        return CBM_E_INVALID;
    cbm_elastica_spec sp;
    memset(&sp, 0, sizeof sp);
    sp.theta_tip_min = -90, sp.theta_tip_max = 270;
    sp.sweep_min = -90, sp.sweep_max = 270;
    sp.stiffness_ratio = 1, sp.stiffness_tau = 1, sp.substeps = 1, sp.step_time = 1, sp.side = 1;
    spec_reader r = {ctx, file ? file : "<spec>", 0};
    char *copy = cbm__alloc(ctx, len + 1);
    if (!copy)
        return CBM_E_NOMEM;
    if (len)
        memcpy(copy, text, len);
    copy[len] = 0;
    bool seen[S_N] = {false};
    int dim_line = 0, dim_col = 0;
    const char *dim_name = NULL;
    branch_line bl[CBM_ELASTICA_MAX_BRANCHES];
    memset(bl, 0, sizeof bl);
    size_t i = 0;
    int line = 0;
    bool syntax = false;
    while (i < len) {
        line++;
        size_t ls = i, le = i;
        while (le < len && text[le] != '\n')
            le++;
        i = le + 1;
        size_t e = ls;
        while (e < le && text[e] != '#')
            e++;
        size_t p = ls;
        while (p < e && (text[p] == ' ' || text[p] == '\t' || text[p] == '\r'))
            p++;
        size_t ks = p;
        while (p < e && word(text[p]))
            p++;
        size_t kn = p - ks;
        if (kn == 0)
            continue; /* blank, comment, or an error bend's reader reports */
        for (size_t k = 0; k < N_DIM; k++)
            if (strlen(dim_keys[k]) == kn && !memcmp(dim_keys[k], text + ks, kn) && !dim_line)
                dim_line = line, dim_col = (int)(ks - ls) + 1, dim_name = dim_keys[k];
        int k = 0;
        while (k < S_N && !(strlen(own[k]) == kn && !memcmp(own[k], text + ks, kn)))
            k++;
        if (k == S_N)
            continue;
        int kcol = (int)(ks - ls) + 1;
        memset(copy + ls, ' ', le - ls); /* bend's reader sees a blank line */
        while (p < e && (text[p] == ' ' || text[p] == '\t'))
            p++;
        if (p >= e || text[p] != '=') {
            spec_error(&r, line, (int)(p - ls) + 1, "expected '=' after '%s'", own[k]);
            syntax = true;
            continue;
        }
        p++;
        if (k == S_BRANCH) {
            if (sp.n_branches == CBM_ELASTICA_MAX_BRANCHES) {
                spec_error(&r, line, kcol, "more than %d branches", CBM_ELASTICA_MAX_BRANCHES);
                continue;
            }
            parse_branch(&r, text, p, e, ls, line, sp.n_branches, &sp.branches[sp.n_branches],
                         &bl[sp.n_branches]);
            sp.n_branches++;
            continue;
        }
        if (seen[k]) {
            spec_error(&r, line, kcol, "key '%s' given twice", own[k]);
            continue;
        }
        seen[k] = true;
        while (p < e && (text[p] == ' ' || text[p] == '\t'))
            p++;
        size_t vs = p;
        while (p < e && word(text[p]))
            p++;
        size_t vn = p - vs;
        int vcol = (int)(vs - ls) + 1;
        while (p < e && (text[p] == ' ' || text[p] == '\t' || text[p] == '\r'))
            p++;
        if (p < e) {
            spec_error(&r, line, (int)(p - ls) + 1, "unexpected text after the value of '%s'",
                       own[k]);
            syntax = true;
            continue;
        }
        if (k == S_TAPER || k == S_LAW ||
            (k == S_CONTROL && vn == 6 && !memcmp(text + vs, "static", 6))) {
            static const char *const words[3][3] = {
                {"linear", "uniform", "step"}, {"growth", "remodel", "none"}, {"static", 0, 0}};
            const char *const *w = words[k == S_TAPER ? 0 : k == S_LAW ? 1 : 2];
            int m = 0;
            while (m < 3 && !(w[m] && strlen(w[m]) == vn && !memcmp(w[m], text + vs, vn)))
                m++;
            if (m == 3) {
                spec_error(&r, line, vcol, "'%s' expects %s, found '%.*s'", own[k],
                           k == S_TAPER ? "linear, uniform or step" : "growth, remodel or none",
                           (int)(vn > 40 ? 40 : vn), text + vs);
                continue;
            }
            if (k == S_TAPER)
                sp.taper = m;
            else if (k == S_LAW)
                sp.law = m;
            else
                sp.control_static = true;
            continue;
        }
        double x;
        if (!number(&r, own[k], text + vs, vn, line, vcol, own_lo[k], own_hi[k], &x))
            continue;
        double *dst[S_N] = {&sp.alpha,
                            &sp.angle,
                            &sp.theta_tip_min,
                            &sp.theta_tip_max,
                            &sp.sweep_min,
                            &sp.sweep_max,
                            NULL,
                            NULL,
                            NULL,
                            &sp.control_curvature,
                            &sp.stiffness_ratio,
                            &sp.stiffness_tau,
                            &sp.youngs_final,
                            &sp.youngs_tau,
                            &sp.segment_load,
                            &sp.segment_load_point,
                            &sp.preferred_angle,
                            &sp.induced_rate,
                            &sp.substeps,
                            &sp.step_time,
                            &sp.side};
        *dst[k] = x;
    }
    sp.dimensionless = seen[S_ALPHA];
    sp.has_angle = seen[S_ANGLE];
    cbm_status st = cbm_bend_spec_parse(ctx, copy, len, r.file, &sp.bend);
    cbm__free(ctx, copy, len + 1);
    if (sp.dimensionless && dim_line)
        spec_error(&r, dim_line, dim_col,
                   "'%s' has no meaning with 'alpha' (non-dimensional: L = D = 1, w = alpha)",
                   dim_name);
    for (size_t b = 0; b < sp.n_branches; b++) {
        if (sp.dimensionless && bl[b].col_dim)
            spec_error(&r, bl[b].line, bl[b].col_dim, "branch key '%s' needs the dimensional mode",
                       bl[b].dim_name);
        if (!sp.dimensionless && bl[b].col_nondim)
            spec_error(&r, bl[b].line, bl[b].col_nondim, "branch key '%s' needs 'alpha'",
                       bl[b].nondim_name);
    }
    sp.grows = st == CBM_OK && sp.bend.steps > 0;
    sp.has_preferred = seen[S_PREF];
    sp.has_youngs_final = seen[S_EFINAL];
    for (int k = S_TAPER; k < S_N; k++)
        if (seen[k] && !sp.grows)
            spec_error(&r, 0, 0, "'%s' is a growth key: it needs steps > 0", own[k]);
    if (seen[S_SUBSTEPS] && sp.substeps != floor(sp.substeps))
        spec_error(&r, 0, 0, "'substeps' expects a whole number");
    if (sp.grows) {
        const cbm_bend_spec *b = &sp.bend;
        if (sp.dimensionless)
            spec_error(&r, 0, 0, "growth is dimensional: drop 'alpha'");
        if (sp.n_branches)
            spec_error(&r, 0, 0, "growth is for a single rod: drop the branch lines");
        if (b->aspect != 1 || b->radius_base > 0 || b->radius_tip > 0)
            spec_error(&r, 0, 0,
                       "growth starts from a round, uniform rod: drop aspect, radius_base and "
                       "radius_tip (radius_final sets the taper)");
        if (b->tip_moment != 0 || b->tropism != 0)
            spec_error(&r, 0, 0, "growth takes no tip_moment or tropism (use preferred_angle)");
    }
    if (!(sp.theta_tip_max > sp.theta_tip_min))
        spec_error(&r, 0, 0, "theta_tip_max (%g) must exceed theta_tip_min (%g)", sp.theta_tip_max,
                   sp.theta_tip_min);
    if (sp.n_branches && sp.theta_tip_max - sp.theta_tip_min < 360)
        spec_error(&r, 0, 0, "a branched plant needs a full turn of theta_tip (max - min >= 360)");
    if (st != CBM_OK)
        return st;
    if (r.errors)
        return syntax ? CBM_E_SYNTAX : CBM_E_SEMANTIC;
    *out = sp;
    return CBM_OK;
}

static void dim_piece(const cbm_bend_spec *b, double length, double r0, double r1,
                      cbm_elastica_piece *pc)
{
    double a0 = r0, b0 = r0 * b->aspect, a1 = r1, b1 = r1 * b->aspect;
    pc->length = length;
    pc->D0 = b->youngs_modulus * CBM_PI * a0 * a0 * a0 * b0 / 4;
    pc->D1 = b->youngs_modulus * CBM_PI * a1 * a1 * a1 * b1 / 4;
    pc->w0 = b->density * CBM_PI * a0 * b0 * b->gravity;
    pc->w1 = b->density * CBM_PI * a1 * b1 * b->gravity;
    if (pc->w0 < 0 || pc->w1 < 0) /* gravity pointing up: not modelled */
        pc->w0 = pc->w1 = 0;
}

cbm_status cbm_elastica_spec_plant(const cbm_elastica_spec *sp, cbm_elastica_piece *pieces,
                                   cbm_elastica_branch *branches, double *length_ref,
                                   double *stiffness_ref)
{
    if (!sp || !pieces || !branches)
        return CBM_E_INVALID;
    const cbm_bend_spec *b = &sp->bend;
    cbm_elastica_piece base = cbm_elastica_piece_default();
    if (sp->dimensionless) {
        base.w0 = base.w1 = sp->alpha;
    } else {
        double rb = b->radius_base > 0 ? b->radius_base : b->radius;
        double rt = b->radius_tip > 0 ? b->radius_tip : b->radius;
        dim_piece(b, b->length, rb, rt, &base);
    }
    base.rest_curvature = b->rest_curvature;
    pieces[0] = base;
    branches[0].parent = -1;
    branches[0].offset = 0;
    branches[0].pieces = &pieces[0];
    branches[0].n_pieces = 1;
    double g = sp->dimensionless ? 0 : b->gravity;
    branches[0].tip_force = b->tip_load + b->tip_mass * g;
    branches[0].tip_moment = b->tip_moment;
    for (size_t k = 0; k < sp->n_branches; k++) {
        const cbm_elastica_branch_spec *s = &sp->branches[k];
        cbm_elastica_piece pc = base;
        if (sp->dimensionless) {
            pc.length = s->length > 0 ? s->length : 1.0;
            pc.D0 = pc.D1 = s->stiffness;
            pc.w0 = pc.w1 = sp->alpha * s->weight;
        } else {
            double r0 = s->radius > 0 ? s->radius : b->radius;
            double r1 = s->radius_tip > 0 ? s->radius_tip : r0;
            dim_piece(b, s->length > 0 ? s->length : b->length, r0, r1, &pc);
        }
        pc.rest_curvature = s->rest_curvature;
        pieces[k + 1] = pc;
        cbm_elastica_branch *br = &branches[k + 1];
        br->parent = s->parent;
        br->offset = s->offset * CBM_PI / 180;
        br->pieces = &pieces[k + 1];
        br->n_pieces = 1;
        br->tip_force = s->tip_load + s->tip_mass * g;
        br->tip_moment = s->tip_moment;
    }
    if (length_ref)
        *length_ref = base.length;
    if (stiffness_ref)
        *stiffness_ref = base.D0;
    return CBM_OK;
}

cbm_status cbm_elastica_spec_growth(cbm_context *ctx, const cbm_elastica_spec *sp,
                                    cbm_elastica_growth_def *out)
{
    if (!ctx || !sp || !out || !sp->grows)
        return CBM_E_INVALID;
    const cbm_bend_spec *b = &sp->bend;
    cbm_elastica_growth_def d = cbm_elastica_growth_def_default();
    double L0 = b->length_initial > 0 ? b->length_initial : b->length;
    double h = b->length / (double)b->segments, q = L0 / h;
    if (fabs(q - nearbyint(q)) > 1e-9 * q || nearbyint(q) < 1)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "elastica growth: length_initial (%g) must be a whole number of segments "
                         "(length / segments = %g)",
                         L0, h);
    d.length0 = L0;
    d.cells = (size_t)nearbyint(q);
    d.steps = (size_t)b->steps;
    d.tip_growth = (b->length - L0) / (double)b->steps;
    d.dt = sp->step_time;
    d.substeps = (size_t)sp->substeps;
    d.theta_base = (sp->has_angle ? sp->angle : b->angle) * CBM_PI / 180;
    d.radius0 = b->radius;
    d.layer = b->radius_final > 0 ? (b->radius_final - b->radius) / (double)b->steps : 0.0;
    d.taper = (cbm_elastica_taper)sp->taper;
    d.stiffness_ratio = sp->stiffness_ratio;
    d.stiffness_tau = sp->stiffness_tau;
    d.youngs = b->youngs_modulus;
    d.youngs_final = sp->has_youngs_final ? sp->youngs_final : b->youngs_modulus;
    d.youngs_tau = sp->youngs_tau;
    d.density = b->density;
    d.gravity = b->gravity;
    d.segment_load = sp->segment_load;
    d.segment_load_point = sp->segment_load_point != 0;
    d.tip_load = b->tip_load + b->tip_mass * b->gravity;
    d.rest_curvature0 = b->rest_curvature;
    d.preferred = sp->has_preferred;
    d.preferred_angle = sp->preferred_angle * CBM_PI / 180;
    d.law = (cbm_elastica_law)sp->law;
    d.control = sp->control_static ? CBM_ELASTICA_CONTROL_STATIC : CBM_ELASTICA_CONTROL_GIVEN;
    d.control_curvature = sp->control_curvature;
    d.induced_rate = sp->induced_rate;
    d.side = sp->side < 0 ? -1 : 1;
    *out = d;
    return CBM_OK;
}
