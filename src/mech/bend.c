/* The `bend` job: the spec reader (key = value lines), the rod it describes, a simple growth
 * driver, and the node table of the result.
 *
 * Spec reader: a hand-written line scanner. Each line is blank, a comment (`#` to the end of the
 * line; also after a value), or `key = value` with a number or a word. Every problem is reported
 * as FILE:line:col (1-based, col pointing at the offending key or value) and the scan goes on so
 * that one run reports them all (up to limits.max_diagnostics). Numbers must be finite and
 * within each key's range; a key may appear once.
 *
 * The rod: `segments` equal segments along the final length, clamped at `angle` degrees above
 * the horizontal in the x-y plane (cbm_mech_clamp_orientation), a section of semi-axes a = r
 * (vertical, along U) and b = aspect * r, radius either uniform or linear from radius_base to
 * radius_tip evaluated at each segment's centroid, rest curvature as a rest rotation rate about
 * the clamp's L axis (L = -z, so a counter-clockwise curvature k is Omega_L = -k), tip load,
 * mass and moment on the last segment.
 *
 * Growth driver (steps > 0): a minimal primary/secondary growth loop. Primary growth starts
 * with round(length_initial / h) segments (h = length / segments) and adds segments at the tip
 * evenly over the steps; a new segment continues the tip's frame, and with `tropism` its rest
 * rotation rate is the tropism torque of Taylor-Hell eqs. 6.8-6.12, (l_parent H_parent x F) /
 * C componentwise in the local frame, F = tropism * (0, 1, 0). Secondary growth adds one ring
 * per step to every segment, its outer radius growing linearly from `radius` to `radius_final`;
 * the ring's rest rate is the segment's current material rate (Taylor-Hell 6.32, shape memory,
 * closed form of eqs. 6.29-6.34 in the plant's aggregates) and its weight is applied at once.
 * After each step the rod is re-solved from the previous equilibrium. With a modulus of rupture,
 * the most proximal segment whose stress exceeds it is removed with everything it carries.
 */
#include "cambium/bend.h"
#include "cambium/dynamics.h"
#include "core/core.h"
#include "core/vecmath.h"
#include "mech/growth_internal.h"
#include "mech/fem_internal.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>

cbm_bend_spec cbm_bend_spec_default(void)
{
    cbm_bend_spec s;
    memset(&s, 0, sizeof s);
    s.length = 1.0;
    s.segments = 100;
    s.radius = 0.01;
    s.aspect = 1.0;
    s.youngs_modulus = 1e10;
    s.density = 600.0;
    s.gravity = 9.81;
    s.solver = CBM_MECH_NEWTON;
    s.tolerance = 1e-8;
    s.alpha = 0.5;
    s.krylov_dim = 20;
    s.discretization = CBM_MECH_STAGGERED;
    s.push_unstable = 1;
    s.approx_mode = CBM_APPROX_CORRECTED;
    s.approx_p = 1.0;
    s.approx_force = 1.0;
    s.fem_increments = 20;
    s.fem_axial = CBM_FEM_AXIAL_FORMULA;
    s.fem_elements = 10;
    return s;
}

/* ---- the reader ---- */

typedef enum { K_NUM, K_INT, K_SOLVER, K_DISC, K_APPROX_MODE, K_AXIAL, K_WORD } key_kind;

typedef struct key_desc {
    const char *name;
    key_kind kind;
    size_t offset;
    double lo, hi; /* allowed range (inclusive) */
    bool lo_open;  /* lo excluded */
} key_desc;

static const char *const w_fem_path[] = {"clamped", "thesis", NULL};
static const char *const w_fem_support[] = {"free", "clamped", NULL};
static const char *const w_approx_load[] = {"thesis", "calibrated", NULL};
static const char *const w_fem_update[] = {"listing", "sagging", NULL};
static const char *const w_fem_stiffness[] = {"printed", "symmetric", NULL};
static const char *const w_motion[] = {"full", "modal", NULL};
/* K_WORD keys: the allowed words, NULL-terminated; the value stored is the word's index (an
 * int or an enum of the same values) */
static const struct {
    const char *key;
    const char *const *words;
} word_keys[] = {{"fem_path", w_fem_path},           {"fem_support", w_fem_support},
                 {"approx_load", w_approx_load},     {"fem_update", w_fem_update},
                 {"fem_stiffness", w_fem_stiffness}, {"motion", w_motion}};
_Static_assert(CBM_FEM_PATH_THESIS == 1 && CBM_FEM_SUPPORT_CLAMPED == 1 &&
                   CBM_APPROX_LOAD_CALIBRATED == 1 && sizeof(cbm_fem_path) == sizeof(int) &&
                   sizeof(cbm_fem_support) == sizeof(int) && sizeof(cbm_approx_load) == sizeof(int),
               "the word tables follow the enums");
_Static_assert(CBM_MOTION_MODAL == 1, "motion's words follow cbm_motion_method");

#define OFF(f) offsetof(cbm_bend_spec, f)
static const key_desc keys[] = {
    {"length", K_NUM, OFF(length), 0, 1e6, true},
    {"segments", K_INT, OFF(segments), 1, 1e9, false},
    {"radius", K_NUM, OFF(radius), 0, 1e3, true},
    {"radius_base", K_NUM, OFF(radius_base), 0, 1e3, true},
    {"radius_tip", K_NUM, OFF(radius_tip), 0, 1e3, true},
    {"aspect", K_NUM, OFF(aspect), 0, 1, true},
    {"E", K_NUM, OFF(youngs_modulus), 0, 1e20, true},
    {"G", K_NUM, OFF(shear_modulus), 0, 1e20, true},
    {"density", K_NUM, OFF(density), 0, 1e6, false},
    {"gravity", K_NUM, OFF(gravity), -1e6, 1e6, false},
    {"angle", K_NUM, OFF(angle), -90, 90, false},
    {"tip_load", K_NUM, OFF(tip_load), -1e12, 1e12, false},
    {"tip_mass", K_NUM, OFF(tip_mass), 0, 1e12, false},
    {"tip_moment", K_NUM, OFF(tip_moment), -1e12, 1e12, false},
    {"rest_curvature", K_NUM, OFF(rest_curvature), -1e6, 1e6, false},
    {"tropism", K_NUM, OFF(tropism), -1e12, 1e12, false},
    {"modulus_of_rupture", K_NUM, OFF(modulus_of_rupture), 0, 1e15, false},
    {"solver", K_SOLVER, OFF(solver), 0, 0, false},
    {"tolerance", K_NUM, OFF(tolerance), 0, 1, true},
    {"alpha", K_NUM, OFF(alpha), 0, 1, true},
    {"max_passes", K_INT, OFF(max_passes), 0, 1e12, false},
    {"krylov_dim", K_INT, OFF(krylov_dim), 1, 500, false},
    {"discretization", K_DISC, OFF(discretization), 0, 0, false},
    {"approx_mode", K_APPROX_MODE, OFF(approx_mode), 0, 0, false},
    {"approx_p", K_NUM, OFF(approx_p), 0, 1, false},
    {"approx_force", K_NUM, OFF(approx_force), 0, 1e6, true},
    {"approx_load", K_WORD, OFF(approx_load), 0, 0, false},
    {"steps", K_INT, OFF(steps), 0, 1e7, false},
    {"length_initial", K_NUM, OFF(length_initial), 0, 1e6, true},
    {"radius_final", K_NUM, OFF(radius_final), 0, 1e3, true},
    {"control_curvature", K_NUM, OFF(control_curvature), -1e6, 1e6, false},
    {"push_unstable", K_INT, OFF(push_unstable), 0, 1, false},
    {"threads", K_INT, OFF(threads), 0, 1024, false},
    {"duration", K_NUM, OFF(duration), 0, 1e6, true},
    {"dt", K_NUM, OFF(dt), 0, 1e3, true},
    {"damping_ratio", K_NUM, OFF(damping_ratio), 0, 0.99, false},
    {"impulse_time", K_NUM, OFF(impulse_time), 0, 1e6, false},
    {"impulse_force", K_NUM, OFF(impulse_force), -1e12, 1e12, false},
    {"initial_tip_load", K_NUM, OFF(initial_tip_load), -1e12, 1e12, false},
    {"motion", K_WORD, OFF(motion), 0, 0, false},
    {"motion_modes", K_INT, OFF(motion_modes), 0, 1e9, false},
    {"motion_cut_hz", K_NUM, OFF(motion_cut_hz), 0, 1e12, true},
    {"static_correction", K_INT, OFF(static_correction), 0, 1, false},
    {"fem_increments", K_INT, OFF(fem_increments), 1, 1e7, false},
    {"fem_shear_ratio", K_NUM, OFF(fem_shear_ratio), 0, 1e3, false},
    {"fem_sigma", K_NUM, OFF(fem_sigma), 0, 1, false},
    {"fem_phi", K_NUM, OFF(fem_phi), -360, 360, false},
    {"fem_strain_min", K_NUM, OFF(fem_strain_min), -1, 1, false},
    {"fem_strain_max", K_NUM, OFF(fem_strain_max), -1, 1, false},
    {"fem_axial", K_AXIAL, OFF(fem_axial), 0, 0, false},
    {"fem_path", K_WORD, OFF(fem_path), 0, 0, false},
    {"fem_elements", K_INT, OFF(fem_elements), 5, 1000, false},
    {"fem_support", K_WORD, OFF(fem_support), 0, 0, false},
    {"fem_primary_tropism", K_INT, OFF(fem_primary_tropism), 0, 1, false},
    {"fem_update", K_WORD, OFF(fem_update), 0, 0, false},
    {"fem_stiffness", K_WORD, OFF(fem_stiffness), 0, 0, false},
};
#undef OFF
#define NKEYS (sizeof keys / sizeof *keys)

static bool is_word(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
           c == '-' || c == '.' || c == '+';
}

typedef struct reader {
    cbm_context *ctx;
    const char *file;
    int errors;
    cbm_status status;
} reader;

CBM_PRINTF(4, 5)
static void spec_error(reader *r, int line, int col, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    cbm__vdiag(r->ctx, CBM_ERROR, r->file, line, col, fmt, ap);
    va_end(ap);
    r->errors++;
}

/* Sets a value; returns false (after reporting) if bad. */
static void set_value(reader *r, const key_desc *k, const char *v, size_t vn, int line, int col,
                      cbm_bend_spec *s)
{
    char buf[64];
    if (vn >= sizeof buf) {
        spec_error(r, line, col, "value of '%s' is too long", k->name);
        r->status = CBM_E_SEMANTIC;
        return;
    }
    memcpy(buf, v, vn);
    buf[vn] = 0;
    char *base = (char *)s + k->offset;
    if (k->kind == K_SOLVER) {
        cbm_mech_solver sv;
        if (!cbm_mech_solver_parse(buf, &sv)) {
            char names[128];
            cbm_mech_solver_names(names, sizeof names);
            spec_error(r, line, col, "unknown solver '%s' (expected one of: %s; newton = fast)",
                       buf, names);
            r->status = CBM_E_SEMANTIC;
            return;
        }
        memcpy(base, &sv, sizeof sv);
        return;
    }
    if (k->kind == K_APPROX_MODE) {
        cbm_approx_mode m;
        if (!cbm_approx_mode_parse(buf, &m)) {
            spec_error(r, line, col, "unknown approx_mode '%s' (expected corrected or thesis)",
                       buf);
            r->status = CBM_E_SEMANTIC;
            return;
        }
        memcpy(base, &m, sizeof m);
        return;
    }
    if (k->kind == K_WORD) {
        const char *const *words = NULL;
        for (size_t w = 0; w < sizeof word_keys / sizeof *word_keys; w++)
            if (!strcmp(word_keys[w].key, k->name))
                words = word_keys[w].words;
        int iv = 0;
        while (words[iv] && strcmp(words[iv], buf))
            iv++;
        if (!words[iv]) {
            char names[96] = "";
            for (int w = 0; words[w]; w++) {
                strncat(names, w ? " or " : "", sizeof names - strlen(names) - 1);
                strncat(names, words[w], sizeof names - strlen(names) - 1);
            }
            spec_error(r, line, col, "unknown %s '%s' (expected %s)", k->name, buf, names);
            r->status = CBM_E_SEMANTIC;
            return;
        }
        memcpy(base, &iv, sizeof iv);
        return;
    }
    if (k->kind == K_AXIAL) {
        cbm_fem_axial a;
        if (!strcmp(buf, "formula"))
            a = CBM_FEM_AXIAL_FORMULA;
        else if (!strcmp(buf, "listing"))
            a = CBM_FEM_AXIAL_LISTING;
        else {
            spec_error(r, line, col, "unknown fem_axial '%s' (expected formula or listing)", buf);
            r->status = CBM_E_SEMANTIC;
            return;
        }
        memcpy(base, &a, sizeof a);
        return;
    }
    if (k->kind == K_DISC) {
        cbm_mech_discretization d;
        if (!strcmp(buf, "staggered"))
            d = CBM_MECH_STAGGERED;
        else if (!strcmp(buf, "chain"))
            d = CBM_MECH_CHAIN;
        else {
            spec_error(r, line, col, "unknown discretization '%s' (expected staggered or chain)",
                       buf);
            r->status = CBM_E_SEMANTIC;
            return;
        }
        memcpy(base, &d, sizeof d);
        return;
    }
    errno = 0;
    char *end = NULL;
    double x = strtod(buf, &end);
    if (end == buf || *end != 0 || errno == ERANGE || !isfinite(x)) {
        spec_error(r, line, col, "'%s' expects a finite number, found '%s'", k->name, buf);
        r->status = CBM_E_SEMANTIC;
        return;
    }
    if (x < k->lo || x > k->hi || (k->lo_open && x == k->lo)) {
        spec_error(r, line, col, "'%s' = %s is out of range (%s%g .. %g)", k->name, buf,
                   k->lo_open ? "above " : "", k->lo, k->hi);
        r->status = CBM_E_SEMANTIC;
        return;
    }
    if (k->kind == K_INT) {
        if (x != floor(x)) {
            spec_error(r, line, col, "'%s' expects a whole number, found '%s'", k->name, buf);
            r->status = CBM_E_SEMANTIC;
            return;
        }
        if (k->offset == offsetof(cbm_bend_spec, krylov_dim)) {
            int iv = (int)x;
            memcpy(base, &iv, sizeof iv);
        } else {
            long lv = (long)x;
            memcpy(base, &lv, sizeof lv);
        }
        return;
    }
    memcpy(base, &x, sizeof x);
}

static bool key_seen(const bool *seen, const char *name)
{
    for (size_t k = 0; k < NKEYS; k++)
        if (!strcmp(keys[k].name, name))
            return seen[k];
    return false;
}

/* fem_path = thesis: Gürtler's planar chain grown in n_FE steps (fem_thesis.h) takes the rod's
 * geometry, wood and gravity and nothing else; its listing's defaults where the spec is silent */
static void thesis_check(reader *r, cbm_bend_spec *s, const bool *seen)
{
    static const char *const refused[] = {
        "tip_load",           "tip_mass", "tip_moment",     "rest_curvature",    "tropism",
        "modulus_of_rupture", "steps",    "fem_increments", "control_curvature", "aspect"};
    for (size_t k = 0; k < sizeof refused / sizeof *refused; k++)
        if (key_seen(seen, refused[k])) {
            spec_error(r, 0, 0,
                       "fem_path = thesis grows its own chain of fem_elements steps under its own "
                       "weight: '%s' has no meaning there",
                       refused[k]);
            r->status = CBM_E_SEMANTIC;
        }
    if (s->gravity < 0) {
        spec_error(r, 0, 0, "fem_path = thesis needs gravity >= 0 (got %g)", s->gravity);
        r->status = CBM_E_SEMANTIC;
    }
    if (s->segments < s->fem_elements) {
        spec_error(
            r, 0, 0,
            "fem_path = thesis resamples fem_elements = %ld angles to segments = %ld: segments "
            "must be at least fem_elements",
            s->fem_elements, s->segments);
        r->status = CBM_E_SEMANTIC;
    }
    double rb = s->radius_base > 0 ? s->radius_base : s->radius;
    double rt = s->radius_tip > 0 ? s->radius_tip : s->radius;
    if (rt > rb) {
        spec_error(r, 0, 0, "fem_path = thesis needs radius_tip (%g) <= radius_base (%g)", rt, rb);
        r->status = CBM_E_SEMANTIC;
    }
    if (!key_seen(seen, "fem_axial"))
        s->fem_axial = CBM_FEM_AXIAL_LISTING;
    if (!key_seen(seen, "fem_shear_ratio"))
        s->fem_shear_ratio =
            s->shear_modulus > 0 ? s->shear_modulus / s->youngs_modulus : 1.0 / 3.0;
}

cbm_status cbm_bend_spec_parse(cbm_context *ctx, const char *text, size_t len, const char *file,
                               cbm_bend_spec *out)
{
    if (!ctx || (!text && len) || !out)
        return CBM_E_INVALID;
    cbm_bend_spec s = cbm_bend_spec_default();
    reader r = {ctx, file ? file : "<spec>", 0, CBM_OK};
    bool seen[NKEYS];
    memset(seen, 0, sizeof seen);
    size_t maxd = cbm_context_limits(ctx)->max_diagnostics;
    size_t i = 0;
    int line = 0;
    while (i < len) {
        line++;
        size_t ls = i, le = i;
        while (le < len && text[le] != '\n')
            le++;
        i = le + 1;
        if (maxd && (size_t)r.errors >= maxd)
            break;
        /* strip comment */
        size_t e = ls;
        while (e < le && text[e] != '#')
            e++;
        size_t p = ls;
#define SKIPWS                                                                                     \
    while (p < e && (text[p] == ' ' || text[p] == '\t' || text[p] == '\r'))                        \
        p++;
        SKIPWS
        if (p == e)
            continue;
        int kcol = (int)(p - ls) + 1;
        size_t ks = p;
        while (p < e && is_word(text[p]))
            p++;
        size_t kn = p - ks;
        if (kn == 0) {
            unsigned char c = (unsigned char)text[p];
            spec_error(&r, line, kcol, "expected a key, found '%s%c'",
                       c < 32 || c > 126 ? "\\x" : "", c < 32 || c > 126 ? '?' : (char)c);
            r.status = r.status ? r.status : CBM_E_SYNTAX;
            continue;
        }
        SKIPWS
        if (p >= e || text[p] != '=') {
            spec_error(&r, line, (int)(p - ls) + 1, "expected '=' after '%.*s'",
                       (int)(kn > 40 ? 40 : kn), text + ks);
            r.status = r.status ? r.status : CBM_E_SYNTAX;
            continue;
        }
        p++;
        SKIPWS
        int vcol = (int)(p - ls) + 1;
        size_t vs = p;
        while (p < e && is_word(text[p]))
            p++;
        size_t vn = p - vs;
        SKIPWS
        if (vn == 0) {
            spec_error(&r, line, vcol, "missing value for '%.*s'", (int)(kn > 40 ? 40 : kn),
                       text + ks);
            r.status = r.status ? r.status : CBM_E_SYNTAX;
            continue;
        }
        if (p < e) {
            spec_error(&r, line, (int)(p - ls) + 1, "unexpected text after the value of '%.*s'",
                       (int)(kn > 40 ? 40 : kn), text + ks);
            r.status = r.status ? r.status : CBM_E_SYNTAX;
            continue;
        }
#undef SKIPWS
        size_t k = 0;
        while (k < NKEYS && !(strlen(keys[k].name) == kn && !memcmp(keys[k].name, text + ks, kn)))
            k++;
        if (k == NKEYS) {
            spec_error(&r, line, kcol, "unknown key '%.*s'", (int)(kn > 40 ? 40 : kn), text + ks);
            r.status = r.status ? r.status : CBM_E_SEMANTIC;
            continue;
        }
        if (seen[k]) {
            spec_error(&r, line, kcol, "key '%s' given twice", keys[k].name);
            r.status = r.status ? r.status : CBM_E_SEMANTIC;
            continue;
        }
        seen[k] = true;
        set_value(&r, &keys[k], text + vs, vn, line, vcol, &s);
    }
    if (r.status == CBM_OK) {
        /* consistency of the keys together (reported at line 0: the whole file) */
        if (s.length_initial > s.length) {
            spec_error(&r, 0, 0, "length_initial (%g) must not exceed length (%g)",
                       s.length_initial, s.length);
            r.status = CBM_E_SEMANTIC;
        }
        if (s.steps == 0 && (s.length_initial > 0 || s.radius_final > 0)) {
            spec_error(&r, 0, 0, "length_initial and radius_final need steps > 0");
            r.status = CBM_E_SEMANTIC;
        }
        double r0 = s.radius_base > 0 ? s.radius_base : s.radius;
        if (s.radius_final > 0 && s.radius_final < r0) {
            spec_error(&r, 0, 0, "radius_final (%g) must be at least the initial radius (%g)",
                       s.radius_final, r0);
            r.status = CBM_E_SEMANTIC;
        }
        if (s.duration == 0 && (s.dt > 0 || s.damping_ratio > 0 || s.impulse_time > 0 ||
                                s.impulse_force != 0 || s.initial_tip_load != 0)) {
            spec_error(&r, 0, 0,
                       "dt, damping_ratio, impulse_time, impulse_force and initial_tip_load need "
                       "duration > 0");
            r.status = CBM_E_SEMANTIC;
        }
        if (s.motion == 0 && (s.motion_modes > 0 || s.motion_cut_hz > 0 || s.static_correction)) {
            spec_error(&r, 0, 0,
                       "motion_modes, motion_cut_hz and static_correction need motion = modal");
            r.status = CBM_E_SEMANTIC;
        }
        if (s.motion == 1 && s.duration == 0) {
            spec_error(&r, 0, 0, "motion = modal needs duration > 0");
            r.status = CBM_E_SEMANTIC;
        }
        if (s.motion == 1 && s.motion_modes == 0 && !(s.motion_cut_hz > 0)) {
            spec_error(&r, 0, 0, "motion = modal needs motion_modes > 0 or motion_cut_hz > 0");
            r.status = CBM_E_SEMANTIC;
        }
        if (s.dt > 0 && s.duration / s.dt > 1e8) {
            spec_error(&r, 0, 0, "duration / dt = %g steps is more than 1e8", s.duration / s.dt);
            r.status = CBM_E_SEMANTIC;
        }
        if (s.duration > 0 && s.solver == CBM_MECH_APPROX) {
            spec_error(&r, 0, 0,
                       "duration (motion about an equilibrium) needs solver relax or fast: "
                       "approx gives no equilibrium");
            r.status = CBM_E_SEMANTIC;
        }
        if (s.duration > 0 && s.steps > 0) {
            spec_error(&r, 0, 0, "duration (motion) and steps (growth) cannot be combined");
            r.status = CBM_E_SEMANTIC;
        }
        bool fem_keys = false;
        for (size_t k = 0; k < NKEYS; k++)
            if (seen[k] && !strncmp(keys[k].name, "fem_", 4))
                fem_keys = true;
        if (fem_keys && s.solver != CBM_MECH_FEM) {
            spec_error(&r, 0, 0, "the fem_* keys need solver = fem");
            r.status = CBM_E_SEMANTIC;
        }
        bool thesis_keys = false;
        for (size_t k = 0; k < NKEYS; k++)
            if (seen[k] && keys[k].offset >= offsetof(cbm_bend_spec, fem_elements) &&
                !strncmp(keys[k].name, "fem_", 4))
                thesis_keys = true;
        if (thesis_keys && s.fem_path != CBM_FEM_PATH_THESIS) {
            spec_error(
                &r, 0, 0,
                "fem_elements, fem_support, fem_primary_tropism, fem_update and fem_stiffness "
                "need fem_path = thesis");
            r.status = CBM_E_SEMANTIC;
        }
        if (s.fem_path == CBM_FEM_PATH_THESIS)
            thesis_check(&r, &s, seen);
        if (s.solver == CBM_MECH_FEM && s.duration > 0) {
            spec_error(&r, 0, 0,
                       "solver = fem cannot be combined with duration (motion starts from a "
                       "static equilibrium)");
            r.status = CBM_E_SEMANTIC;
        }
        if (s.solver == CBM_MECH_FEM && s.steps > 0 && s.modulus_of_rupture > 0) {
            spec_error(&r, 0, 0,
                       "solver = fem grows without breakage: drop modulus_of_rupture or steps");
            r.status = CBM_E_SEMANTIC;
        }
        size_t lim = cbm_context_limits(ctx)->max_segments;
        if (lim && (size_t)s.segments > lim) {
            spec_error(&r, 0, 0, "segments = %ld exceeds limits.max_segments (%zu)", s.segments,
                       lim);
            r.status = CBM_E_LIMIT;
        }
    }
    if (r.status != CBM_OK)
        return r.status;
    *out = s;
    return CBM_OK;
}

/* ---- the rod ---- */

static double radius_at(const cbm_bend_spec *s, double t) /* t = s / L in [0, 1] */
{
    double rb = s->radius_base > 0 ? s->radius_base : s->radius;
    double rt = s->radius_tip > 0 ? s->radius_tip : s->radius;
    return rb + (rt - rb) * t;
}

static cbm_ring spec_ring(const cbm_bend_spec *s, double r)
{
    cbm_ring g = cbm_ring_default();
    g.youngs_modulus = s->youngs_modulus;
    g.shear_modulus = s->shear_modulus > 0 ? s->shear_modulus : s->youngs_modulus / 16.0;
    g.density = s->density;
    g.a = r;
    g.b = r * s->aspect;
    g.rest_rate = v3(0, -s->rest_curvature, 0);
    g.modulus_of_rupture = s->modulus_of_rupture;
    return g;
}

static cbm_status add_rod_segment(cbm_plant *p, const cbm_bend_spec *s, size_t k, double h)
{
    cbm_segment_def d = cbm_segment_def_default();
    d.parent = (int64_t)k - 1;
    d.length = h;
    d.core = spec_ring(s, radius_at(s, ((double)k + 0.5) / (double)s->segments));
    d.omega = d.core.rest_rate;
    return cbm_plant_add_segment(p, &d, NULL);
}

static cbm_status place_tip_load(cbm_plant *p, const cbm_bend_spec *s)
{
    size_t n = cbm_plant_segment_count(p);
    for (size_t i = 0; i + 1 < n; i++)
        CBM_TRY(cbm_plant_set_load(p, i, 0.0, v3(0, 0, 0), v3(0, 0, 0)));
    return cbm_plant_set_load(p, n - 1, s->tip_mass, v3(0, -s->tip_load, 0),
                              v3(0, 0, s->tip_moment));
}

cbm_status cbm_bend_build(cbm_context *ctx, const cbm_bend_spec *s, cbm_plant **out)
{
    if (!ctx || !s || !out)
        return CBM_E_INVALID;
    *out = NULL;
    cbm_plant_def pd = cbm_plant_def_default();
    pd.gravity = v3(0, -s->gravity, 0);
    pd.base_orientation = cbm_mech_clamp_orientation(s->angle * CBM_PI / 180.0);
    pd.discretization = s->discretization;
    double h = s->length / (double)s->segments;
    long n0 = s->segments;
    if (s->steps > 0 && s->length_initial > 0) {
        n0 = lround(s->length_initial / h);
        if (n0 < 1)
            n0 = 1;
    }
    cbm_plant *p = NULL;
    pd.capacity = (size_t)s->segments;
    CBM_TRY(cbm_plant_create(ctx, &pd, &p));
    cbm_status st = CBM_OK;
    for (long k = 0; k < n0 && st == CBM_OK; k++)
        st = add_rod_segment(p, s, (size_t)k, h);
    if (st == CBM_OK)
        st = place_tip_load(p, s);
    if (st != CBM_OK) {
        cbm_plant_destroy(p);
        return st;
    }
    *out = p;
    return CBM_OK;
}

static cbm_solve_def spec_solve_def(const cbm_bend_spec *s)
{
    cbm_solve_def d = cbm_solve_def_default();
    d.solver = s->solver;
    d.tolerance = s->tolerance;
    d.alpha = s->alpha;
    d.max_passes = (size_t)s->max_passes;
    d.krylov_dim = s->krylov_dim;
    d.push_unstable = s->push_unstable != 0;
    d.threads = (int)s->threads;
    d.approx_mode = s->approx_mode;
    d.approx_p = s->approx_p;
    d.approx_force_factor = s->approx_force;
    d.approx_load = s->approx_load;
    d.eigenvalue = true; /* bend reports the lowest eigenvalue of every answer */
    d.fem.increments = (size_t)s->fem_increments;
    d.fem.shear_ratio = s->fem_shear_ratio;
    d.fem.sigma = s->fem_sigma;
    d.fem.phi = s->fem_phi * CBM_PI / 180.0;
    d.fem.strain_min = s->fem_strain_min;
    d.fem.strain_max = s->fem_strain_max;
    d.fem.axial = s->fem_axial;
    return d;
}

/* The thesis path's inputs from the spec (docs/bend.md, "fem_path = thesis"). */
static cbm_fem_thesis_def thesis_def(const cbm_bend_spec *s)
{
    cbm_fem_thesis_def d = cbm_fem_thesis_def_default();
    d.n_fe = s->fem_elements;
    d.t0 = 90.0 - s->angle;
    d.rho = s->density;
    d.youngs_modulus = s->youngs_modulus;
    d.grav = s->gravity;
    d.le = s->length / (double)s->fem_elements;
    d.r_start = s->radius_base > 0 ? s->radius_base : s->radius;
    d.r_end = s->radius_tip > 0 ? s->radius_tip : s->radius;
    d.sigma = s->fem_sigma;
    d.phi = s->fem_phi;
    d.a = s->fem_strain_min;
    d.b = s->fem_strain_max;
    d.primary_tropism = s->fem_primary_tropism != 0;
    d.extra_loads = NULL;
    d.support = s->fem_support;
    d.printed_stiffness = s->fem_stiffness == 0;
    d.update_sign = s->fem_update == 0 ? 1 : -1;
    d.axial = s->fem_axial;
    d.shear_ratio = s->fem_shear_ratio > 0 ? s->fem_shear_ratio
                    : s->shear_modulus > 0 ? s->shear_modulus / s->youngs_modulus
                                           : 1.0 / 3.0;
    return d;
}

/* fem_path = thesis: the listing's n_FE angles, Akima-resampled to the rod's segments (n_GU),
 * posed as the rod's shape (fem_thesis.c). */
static cbm_status thesis_run(cbm_context *ctx, const cbm_bend_spec *s, cbm_plant *p,
                             cbm_bend_result *r)
{
    cbm_fem_thesis_def d = thesis_def(s);
    size_t nfe = (size_t)s->fem_elements, ngu = cbm_plant_segment_count(p);
    size_t bytes = (nfe + ngu) * sizeof(double);
    double *beta = cbm__alloc(ctx, bytes);
    if (!beta)
        return CBM_E_NOMEM;
    double *a = beta + nfe;
    cbm_status st = cbm_fem_thesis_angles(ctx, &d, beta, nfe, NULL);
    if (st == CBM_OK)
        st = cbm_fem_thesis_resample(ctx, beta, nfe, a, ngu);
    double resid = 0.0;
    if (st == CBM_OK)
        st = cbm__fem_thesis_pose(p, a, ngu, &resid);
    cbm__free(ctx, beta, bytes);
    if (st == CBM_OK) {
        /* one dense solve per growth step; the residual of the posed plant (its cores remember
         * the pose), not info.residual, the share of the step's load the pseudo-inverse drops */
        r->stats.passes = nfe;
        r->stats.residual = resid;
        r->stats.lowest_eigenvalue = NAN;
        r->steps_done = (long)nfe;
    }
    return st;
}

/* Tropism rest rate of a new segment continuing `parent` (Taylor-Hell 6.8-6.12). */
static cbm_vec3 tropism_rate(const cbm_plant *p, size_t parent, double strength, cbm_vec3 rig)
{
    cbm_segment_state ps;
    if (cbm_plant_segment(p, parent, &ps) != CBM_OK)
        return v3(0, 0, 0);
    cbm_vec3 tau = v3_cross(v3_scale(ps.frame.h, ps.length), v3(0, strength, 0));
    cbm_vec3 tl = frame_to_local(ps.frame, tau);
    return v3(tl.x / rig.x, tl.y / rig.y, tl.z / rig.z);
}

static cbm_status grow_step(cbm_plant *p, const cbm_bend_spec *s, long step)
{
    double h = s->length / (double)s->segments;
    size_t n = cbm_plant_segment_count(p);
    /* primary growth: segments to have after this step */
    size_t n0 = s->length_initial > 0 ? (size_t)lround(s->length_initial / h) : (size_t)s->segments;
    if (n0 < 1)
        n0 = 1;
    size_t target =
        n0 + (size_t)((double)((size_t)s->segments - n0) * (double)step / (double)s->steps + 0.5);
    if (target > (size_t)s->segments)
        target = (size_t)s->segments;
    while (n < target) {
        cbm_segment_def d = cbm_segment_def_default();
        d.parent = (int64_t)n - 1;
        d.length = h;
        d.core = spec_ring(s, radius_at(s, ((double)n + 0.5) / (double)s->segments));
        if (s->tropism != 0.0) {
            /* rigidity of the new segment's core */
            double il, iu, j;
            cbm_mech_ellipse_moments(d.core.a, d.core.b, &il, &iu, &j);
            cbm_vec3 rig = v3(d.core.shear_modulus * j, d.core.youngs_modulus * il,
                              d.core.youngs_modulus * iu);
            d.core.rest_rate = v3_add(d.core.rest_rate, tropism_rate(p, n - 1, s->tropism, rig));
        }
        d.omega = d.core.rest_rate;
        CBM_TRY(cbm_plant_add_segment(p, &d, NULL));
        n++;
    }
    CBM_TRY(place_tip_load(p, s));
    /* secondary growth: one ring per step on every segment */
    if (s->radius_final > 0) {
        for (size_t i = 0; i < n; i++) {
            cbm_segment_state st;
            CBM_TRY(cbm_plant_segment(p, i, &st));
            double r0 = radius_at(s, ((double)i + 0.5) / (double)s->segments);
            double r1 =
                r0 + (s->radius_final - radius_at(s, 0.0)) * (double)step / (double)s->steps;
            if (r1 <= st.a)
                continue;
            cbm_ring g = spec_ring(s, r1);
            /* shape memory: the current material rate, plus kappa^c (Tresierras (3.14)) */
            g.rest_rate =
                v3_add(st.rate, cbm__growth_control(p, i, v3(0, 0, 0), s->control_curvature));
            CBM_TRY(cbm_plant_add_ring(p, i, &g));
        }
    }
    return CBM_OK;
}

cbm_status cbm_bend_run(cbm_context *ctx, const cbm_bend_spec *s, cbm_plant **out,
                        cbm_bend_result *res)
{
    if (!ctx || !s || !out)
        return CBM_E_INVALID;
    *out = NULL;
    cbm_bend_result r;
    memset(&r, 0, sizeof r);
    cbm_plant *p = NULL;
    CBM_TRY(cbm_bend_build(ctx, s, &p));
    if (s->solver == CBM_MECH_FEM && s->fem_path == CBM_FEM_PATH_THESIS) {
        cbm_status ts = thesis_run(ctx, s, p, &r);
        if (ts != CBM_OK) {
            cbm_plant_destroy(p);
            return ts;
        }
        if (res)
            *res = r;
        *out = p;
        return CBM_OK;
    }
    cbm_solve_def sd = spec_solve_def(s);
    size_t passes = 0;
    cbm_status st = cbm_plant_solve(p, &sd, &r.stats);
    passes += r.stats.passes;
    for (long k = 1; st == CBM_OK && k <= s->steps; k++) {
        if (s->solver == CBM_MECH_FEM) {
            /* the step's new loads as one increment on the current geometry (fem.c) */
            cbm__fem_snap sn;
            st = cbm__fem_snap_take(p, &sn);
            if (st == CBM_OK)
                st = grow_step(p, s, k);
            if (st == CBM_OK)
                st = cbm__fem_increment(p, &sd.fem, &sn, NULL);
            cbm__fem_snap_free(p, &sn);
            passes++;
            if (st == CBM_OK)
                r.steps_done = k;
            continue;
        }
        st = grow_step(p, s, k);
        if (st == CBM_OK) {
            st = cbm_plant_solve(p, &sd, &r.stats);
            passes += r.stats.passes;
        }
        if (st == CBM_OK && s->modulus_of_rupture > 0) {
            size_t n = cbm_plant_segment_count(p);
            for (size_t i = 0; i < n; i++) {
                cbm_segment_state ss;
                st = cbm_plant_segment(p, i, &ss);
                if (st == CBM_OK && ss.stress > s->modulus_of_rupture) {
                    size_t rm = 0;
                    if (i == 0) {
                        st = cbm__fail(ctx, CBM_E_RUNTIME,
                                       "bend: the rod broke at its base at step %ld", k);
                        break;
                    }
                    st = cbm_plant_remove_subtree(p, i, &rm);
                    r.broken_segments += rm;
                    if (st == CBM_OK) {
                        st = cbm_plant_solve(p, &sd, &r.stats);
                        passes += r.stats.passes;
                    }
                    break;
                }
            }
        }
        if (st == CBM_OK)
            r.steps_done = k;
    }
    r.stats.passes = passes;
    if (res)
        *res = r;
    if (st != CBM_OK && st != CBM_E_NOT_CONVERGED) {
        cbm_plant_destroy(p);
        return st;
    }
    *out = p;
    return st;
}

/* ---- node table ---- */

static double elevation_deg(cbm_quat q)
{
    cbm_vec3 h = q_rotate(q, v3(1, 0, 0));
    double hor = sqrt(h.x * h.x + h.z * h.z);
    return atan2(h.y, hor) * 180.0 / CBM_PI;
}

cbm_status cbm_bend_nodes(const cbm_plant *p, cbm_bend_node *nodes, size_t nn)
{
    size_t n = cbm_plant_segment_count(p);
    if (!p || !nodes || nn != n + 1 || n == 0)
        return CBM_E_INVALID;
    const int64_t *par = cbm_plant_parents(p);
    for (size_t i = 0; i < n; i++)
        if (par[i] != (int64_t)i - 1)
            return CBM_E_INVALID; /* not a single unbranched rod */
    double s = 0;
    for (size_t j = 0; j <= n; j++) {
        cbm_segment_state st;
        size_t i = j < n ? j : n - 1;
        CBM_TRY(cbm_plant_segment(p, i, &st));
        cbm_bend_node *o = &nodes[j];
        cbm_vec3 m; /* moment about the node, world */
        cbm_quat q; /* tangent frame at the node */
        if (j < n) {
            o->x = st.proximal.x;
            o->y = st.proximal.y;
            o->z = st.proximal.z;
            m = st.moment;
            if (j == 0) {
                /* the clamp: the segment's frame turned back by the base half-joint */
                cbm_vec3 w = st.omega;
                double d =
                    cbm_plant_discretization(p) == CBM_MECH_STAGGERED ? 0.5 * st.length : st.length;
                q = q_normalize(q_mul(st.orientation, q_from_rotvec(v3_scale(w, -d))));
            } else
                CBM_TRY(cbm_plant_distal_frame(p, j - 1, &q));
        } else {
            o->x = st.distal.x;
            o->y = st.distal.y;
            o->z = st.distal.z;
            m = st.tip_moment;
            CBM_TRY(cbm_plant_distal_frame(p, n - 1, &q));
        }
        o->s = s;
        if (j < n)
            s += st.length;
        o->angle_deg = elevation_deg(q);
        /* curvature: rest + M/C of the segment at the node, in-plane (world z) component */
        cbm_vec3 ml = frame_to_local(st.frame, m);
        cbm_vec3 k =
            v3(st.rest_rate.x + ml.x / st.rigidity.x, st.rest_rate.y + ml.y / st.rigidity.y,
               st.rest_rate.z + ml.z / st.rigidity.z);
        o->curvature = frame_to_world(st.frame, k).z;
        o->moment = m.z;
        double il, iu;
        cbm_mech_ellipse_moments(st.a, st.b, &il, &iu, NULL);
        double sl = ml.y * st.a / il, su = ml.z * st.b / iu;
        o->stress = sqrt(sl * sl + su * su);
    }
    return CBM_OK;
}
