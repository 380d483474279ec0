/* Parameters of the built-in tree models: the defaults (the thesis' values, Taylor-Hell 2005
 * appendix A.1 #defines, digest §3.1), one table naming every field with its kind and range, the
 * setter shared by parameter files and -D overrides, the range check, and the parameter-file
 * reader.
 *
 * Parameter files: one `name = value` per line, `#` starts a comment, SI units, angles in
 * degrees, booleans 0/1/true/false, enumerations by name, and graphical functions as
 * `func NAME = x:y x:y ...` (control points with increasing x, evaluated piecewise linearly and
 * held constant beyond the ends; cpfg's B-spline curves are not used, so a curve means exactly
 * the polyline through its points). Unknown names and bad values are errors
 * `file:line:col: error: ...`; the reader reports every bad line before failing.
 */
#include "cambium/tree.h"
#include "core/core.h"
#include "core/vecmath.h"
#include "tree/tree_internal.h"

#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DEG (CBM_PI / 180.0)

double cbm_tree_func_eval(const cbm_tree_func *f, double x)
{
    if (!f || f->n <= 0)
        return 0.0;
    if (x <= f->x[0] || f->n == 1)
        return f->y[0];
    for (int k = 1; k < f->n; k++)
        if (x <= f->x[k]) {
            double t = (x - f->x[k - 1]) / (f->x[k] - f->x[k - 1]);
            return f->y[k - 1] + t * (f->y[k] - f->y[k - 1]);
        }
    return f->y[f->n - 1];
}

static cbm_tree_func func2(double x0, double y0, double x1, double y1)
{
    cbm_tree_func f;
    memset(&f, 0, sizeof f);
    f.n = 2;
    f.x[0] = x0, f.y[0] = y0, f.x[1] = x1, f.y[1] = y1;
    return f;
}

/* The thesis' constants (A.1 #defines, digest §3.1, and the calibrated resource values):
 * the built-in `fruit-tree-thesis` and the base of the chapter 7 thesis aspens. */
static cbm_tree_def thesis_def(void)
{
    cbm_tree_def d;
    memset(&d, 0, sizeof d);
    d.seed = 1484127;
    d.years = 10;
    d.form = CBM_TREE_GENERAL;
    d.internode_length = 0.055;
    d.bud_length = 0.008;
    d.radius = 0.002;
    d.max_buds = 21;
    d.first_buds = 10;
    d.phyllotaxis = 137.5 * DEG;
    d.elevation = 90.0 * DEG;
    /* the listing gives no control points: the weakest shooting bud (V just above the
     * threshold) makes one node, V = 0.5 about a third of max_buds, V >= 10 (a young leader)
     * max_buds */
    d.numbuds_vigour.n = 5;
    {
        static const double nx[] = {0.0, 0.1, 0.5, 2.0, 10.0}, ny[] = {0.05, 0.1, 0.3, 0.6, 1.0};
        for (int k = 0; k < 5; k++)
            d.numbuds_vigour.x[k] = nx[k], d.numbuds_vigour.y[k] = ny[k];
    }
    d.angle_min_height = func2(0, 0.35, 1, 0.25); /* 35 deg at the base of a shoot, 25 at the top */
    d.angle_max_height = func2(0, 0.6, 1, 0.45);
    d.vigour_height = func2(0, 0, 1, 1); /* f(h) = h, the general model */
    d.vigour_k = 800.0;
    d.vigour_d = 1.1;
    d.shoot_vigour = 0.2; /* listing 0.03, with its non-conserving spring split */
    d.sink = 0.05;
    d.fairness = 1.0;
    d.years_to_shed = 0;
    d.relay_bias = false;
    d.listing_vigour = false;
    d.youngs_juvenile = 600000.015157;
    d.youngs_juvenile_sd = 1.0 / 6.0;
    d.youngs_adult = 158700004.0;
    d.adult_age = 19.0 / 12.0;
    d.shear_ratio = 1.0 / 16.0;
    d.density = 77.9;
    d.modulus_of_rupture = 289999.986;
    d.tropism = 0.0008;
    d.pipe_exponent = 2.0;
    d.ring_rate = 0.6;
    d.min_ring = 1e-5; /* listing EPSILON 1e-8 */
    d.reaction_threshold = 0.3;
    d.reaction_beta = 0.3;
    d.reaction_increment = 0.001;
    d.growth_steps_per_year = 2.8 * 21;
    d.discretization = CBM_MECH_STAGGERED;
    d.memory = CBM_MEMORY_SEGMENT;
    d.ageing = CBM_AGEING_RINGS;
    d.solve_tolerance = 1e-6;
    d.solve_max_passes = 3000;
    d.solve_threads = 0;
    d.solver = CBM_MECH_NEWTON;
    d.approx_load = CBM_APPROX_LOAD_CALIBRATED;
    d.leaves = true;
    d.leaf_mass = 2e-6;
    d.leaf_density = 0.095;
    d.leaf_scale = 8.0;
    d.fruit_mass = 0.01;
    d.fruit_density = 300.0;
    d.fruit_prob = 0.27;
    d.first_fruit_year = 3;
    d.organ_rate = 0.9;
    d.leaf_drop = 0.5;
    d.fruit_drop = 0.5;
    d.stiffness_factor = 3.0;
    d.tropism_factor = 5.0;
    d.deviation_factor = 2.0;
    d.tropism_fade = 2.0 / 3.0;
    d.max_winter_steps = 12;
    return d;
}

/* The fruit tree with real apple wood and organs (docs/models.md, "Real wood"): sources and the
 * ranges the growth is calibrated against are in the docs; what is not set here is the thesis'
 * model (its functions, the Borchert-Honda allocation, the reaction-wood law). */
cbm_tree_def cbm_tree_def_default(void)
{
    cbm_tree_def d = thesis_def();
    /* architecture of a young apple tree: 3 cm internodes, shoots up to 25 nodes (75 cm), a
     * 45 cm first-year seedling; new shoots 4 mm thick, buds 2 mm; 2/5 phyllotaxis */
    d.internode_length = 0.03;
    d.radius = 0.002;
    d.bud_radius = 0.001;
    d.max_buds = 25;
    d.first_buds = 15;
    d.phyllotaxis = 144.0 * DEG;
    /* wood: green apple wood, E 1 GPa young (MAppleT) to 6 GPa adult, MOR 50 MPa, fresh
     * density 950 kg/m^3 */
    d.youngs_juvenile = 1.0e9;
    d.youngs_adult = 6.0e9;
    d.adult_age = 3.0;
    d.density = 950.0;
    d.modulus_of_rupture = 50e6;
    d.tropism = 0.5;
    d.reaction_threshold = 0.05;
    d.reaction_increment = 1e-4;
    d.reaction_max_aspect = 1.5;
    /* the increment follows the lean (docs/growth.md): full at 10 deg from the set-point (at 20 deg
     * fruit-tree-low-mor died back in 5 of 50 seeds: limbs too little stiffened) */
    d.reaction_full_lean = 10.0 * DEG;
    d.growth_steps_per_year = 37.0;
    /* resources */
    d.vigour_k = 800.0;
    d.shoot_vigour = 0.2;
    d.sink = 0.05;
    d.dormancy = 5;
    d.bud_routing = true;
    d.stem_frame = true;
    /* organs: a leaf of 0.6 g fresh and 25 cm^2 (LMA 250 g/m^2 fresh), spurs of 4 leaves, an
     * apple of 150 g and 7 cm (835 kg/m^3), fruit on spurs from year 4 */
    d.leaf_mass = 6e-4;
    d.leaf_density = 0.25;
    d.leaf_scale = 1.0;
    d.spur_leaves = 4;
    d.fruit_mass = 0.15;
    d.fruit_density = 835.0;
    d.fruit_prob = 0.0;
    d.spur_fruit_prob = 0.1;
    d.first_fruit_year = 4;
    return d;
}

/* ---- the table ---- */

typedef enum kind {
    K_DOUBLE,
    K_ANGLE,
    K_INT,
    K_U64,
    K_BOOL,
    K_FUNC,
    K_FORM,
    K_DISC,
    K_MEM,
    K_AGE,
    K_ALOAD,
    K_SOLVER
} kind;

typedef struct param {
    const char *name;
    kind k;
    size_t off;
    double lo, hi; /* inclusive range (in file units); lo > hi: no check */
} param;

#define P(name, k, lo, hi)                                                                         \
    {                                                                                              \
#name, k, offsetof(cbm_tree_def, name), lo, hi                                             \
    }
static const param params[] = {
    P(seed, K_U64, 0, 0),
    P(years, K_INT, 0, 1000),
    P(form, K_FORM, 0, 0),
    P(internode_length, K_DOUBLE, 1e-6, 100),
    P(bud_length, K_DOUBLE, 1e-6, 100),
    P(radius, K_DOUBLE, 1e-6, 10),
    P(bud_radius, K_DOUBLE, 0, 10),
    P(max_buds, K_INT, 1, 1000),
    P(first_buds, K_INT, 1, 1000),
    P(phyllotaxis, K_ANGLE, -360, 360),
    P(elevation, K_ANGLE, -90, 90),
    P(numbuds_vigour, K_FUNC, 0, 0),
    P(angle_min_height, K_FUNC, 0, 0),
    P(angle_max_height, K_FUNC, 0, 0),
    P(vigour_height, K_FUNC, 0, 0),
    P(vigour_k, K_DOUBLE, 0, 1e12),
    P(vigour_d, K_DOUBLE, 0, 100),
    P(shoot_vigour, K_DOUBLE, 0, 1e12),
    P(sink, K_DOUBLE, 0, 1e6),
    P(fairness, K_DOUBLE, 0, 1),
    P(years_to_shed, K_INT, 0, 1000000),
    P(clear_trunk, K_DOUBLE, 0, 100),
    P(dormancy, K_INT, 0, 1000000),
    P(relay_bias, K_BOOL, 0, 0),
    P(listing_vigour, K_BOOL, 0, 0),
    P(bud_routing, K_BOOL, 0, 0),
    P(stem_frame, K_BOOL, 0, 0),
    P(youngs_juvenile, K_DOUBLE, 1e-3, 1e13),
    P(youngs_juvenile_sd, K_DOUBLE, 0, 0.5),
    P(youngs_adult, K_DOUBLE, 1e-3, 1e13),
    P(adult_age, K_DOUBLE, 0, 1e6),
    P(shear_ratio, K_DOUBLE, 1e-6, 10),
    P(density, K_DOUBLE, 0, 1e5),
    P(modulus_of_rupture, K_DOUBLE, 0, 1e13),
    P(tropism, K_DOUBLE, -1e6, 1e6),
    P(pipe_exponent, K_DOUBLE, 0.1, 10),
    P(ring_rate, K_DOUBLE, 0, 1),
    P(min_ring, K_DOUBLE, 0, 1),
    P(reaction_threshold, K_DOUBLE, 0, 1e12),
    P(reaction_beta, K_DOUBLE, 0, 1),
    P(reaction_increment, K_DOUBLE, 0, 1),
    P(reaction_max_aspect, K_DOUBLE, 0, 100),
    P(reaction_full_lean, K_ANGLE, 0, 90),
    P(growth_steps_per_year, K_DOUBLE, 1, 1e6),
    P(discretization, K_DISC, 0, 0),
    P(memory, K_MEM, 0, 0),
    P(ageing, K_AGE, 0, 0),
    P(solve_tolerance, K_DOUBLE, 1e-14, 0.1),
    P(solve_max_passes, K_INT, 3, 100000000),
    P(solve_threads, K_INT, 0, 1024),
    P(solver, K_SOLVER, 0, 0),
    P(approx_load, K_ALOAD, 0, 0),
    P(leaves, K_BOOL, 0, 0),
    P(leaf_mass, K_DOUBLE, 0, 1e3),
    P(leaf_density, K_DOUBLE, 1e-9, 1e6),
    P(leaf_scale, K_DOUBLE, 0, 1e6),
    P(fruit_mass, K_DOUBLE, 0, 1e3),
    P(fruit_density, K_DOUBLE, 1e-9, 1e6),
    P(fruit_prob, K_DOUBLE, 0, 10),
    P(spur_leaves, K_INT, 0, 100),
    P(spur_fruit_prob, K_DOUBLE, 0, 1),
    P(first_fruit_year, K_INT, 1, 1000000),
    P(organ_rate, K_DOUBLE, 0, 1),
    P(leaf_drop, K_DOUBLE, 0, 1),
    P(fruit_drop, K_DOUBLE, 0, 1),
    P(stiffness_factor, K_DOUBLE, 1e-6, 1e6),
    P(tropism_factor, K_DOUBLE, 0, 1e6),
    P(deviation_factor, K_DOUBLE, 0, 100),
    P(tropism_fade, K_DOUBLE, 0, 1),
    P(max_winter_steps, K_INT, 1, 100000),
};
#undef P
#define NPARAMS (sizeof params / sizeof params[0])

static const char *const form_names[] = {"general", "wild", "crooked"};
static const char *const disc_names[] = {"staggered", "chain"};
static const char *const mem_names[] = {"segment", "joint"};
static const char *const age_names[] = {"rings", "core"};
/* in the order of cbm_approx_load */
static const char *const aload_names[] = {"thesis", "calibrated"};

static const param *find(const char *name, size_t len)
{
    for (size_t i = 0; i < NPARAMS; i++)
        if (strlen(params[i].name) == len && !strncmp(params[i].name, name, len))
            return &params[i];
    return NULL;
}

bool cbm__param_real(const char *s, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    while (*end == ' ' || *end == '\t')
        end++;
    if (end == s || *end || errno == ERANGE || !isfinite(v))
        return false;
    *out = v;
    return true;
}

static int parse_enum(const char *s, const char *const *names, int n)
{
    for (int i = 0; i < n; i++)
        if (!strcmp(s, names[i]))
            return i;
    return -1;
}

/* Parses "x:y x:y ..." into f; on error writes a message into err. */
static bool parse_func(const char *s, cbm_tree_func *f, char *err, size_t errsize)
{
    cbm_tree_func g;
    memset(&g, 0, sizeof g);
    const char *p = s;
    for (;;) {
        while (*p == ' ' || *p == '\t' || *p == ',')
            p++;
        if (!*p)
            break;
        if (g.n == CBM_TREE_FUNC_MAX) {
            snprintf(err, errsize, "at most %d control points", CBM_TREE_FUNC_MAX);
            return false;
        }
        char *end;
        double x = strtod(p, &end);
        if (end == p || *end != ':' || !isfinite(x)) {
            snprintf(err, errsize, "expected a control point x:y near '%.20s'", p);
            return false;
        }
        p = end + 1;
        double y = strtod(p, &end);
        if (end == p || !isfinite(y)) {
            snprintf(err, errsize, "expected a number after ':' near '%.20s'", p);
            return false;
        }
        p = end;
        if (g.n > 0 && !(x > g.x[g.n - 1])) {
            snprintf(err, errsize, "control points must have increasing x (%g after %g)", x,
                     g.x[g.n - 1]);
            return false;
        }
        g.x[g.n] = x;
        g.y[g.n] = y;
        g.n++;
    }
    if (g.n == 0) {
        snprintf(err, errsize, "a function needs at least one control point x:y");
        return false;
    }
    *f = g;
    return true;
}

/* Sets a parameter; on error writes the message into err (without the name). */
static cbm_status set_param(const param *pm, cbm_tree_def *d, const char *value, char *err,
                            size_t errsize)
{
    char *base = (char *)d + pm->off;
    double v = 0.0;
    int e;
    switch (pm->k) {
    case K_SOLVER: {
        cbm_mech_solver sv;
        if (!cbm_mech_solver_parse(value, &sv)) {
            char names[128];
            cbm_mech_solver_names(names, sizeof names);
            snprintf(err, errsize, "'%s' is not one of %s", value, names);
            return CBM_E_INVALID;
        }
        *(cbm_mech_solver *)(void *)base = sv;
        return CBM_OK;
    }
    case K_FUNC:
        return parse_func(value, (cbm_tree_func *)(void *)base, err, errsize) ? CBM_OK
                                                                              : CBM_E_INVALID;
    case K_FORM:
    case K_DISC:
    case K_MEM:
    case K_AGE:
    case K_ALOAD: {
        const char *const *names = pm->k == K_FORM    ? form_names
                                   : pm->k == K_DISC  ? disc_names
                                   : pm->k == K_MEM   ? mem_names
                                   : pm->k == K_ALOAD ? aload_names
                                                      : age_names;
        int n = pm->k == K_FORM ? 3 : 2;
        e = parse_enum(value, names, n);
        if (e < 0) {
            int w = snprintf(err, errsize, "'%s' is not one of", value);
            for (int i = 0; i < n && w > 0 && (size_t)w < errsize; i++)
                w += snprintf(err + w, errsize - (size_t)w, " %s", names[i]);
            return CBM_E_INVALID;
        }
        if (pm->k == K_FORM)
            *(cbm_tree_form *)(void *)base = (cbm_tree_form)e;
        else if (pm->k == K_DISC)
            *(cbm_mech_discretization *)(void *)base = (cbm_mech_discretization)e;
        else if (pm->k == K_MEM)
            *(cbm_ring_memory *)(void *)base = (cbm_ring_memory)e;
        else if (pm->k == K_ALOAD)
            *(cbm_approx_load *)(void *)base = (cbm_approx_load)e;
        else
            *(cbm_ageing *)(void *)base = (cbm_ageing)e;
        return CBM_OK;
    }
    case K_BOOL:
        if (!strcmp(value, "1") || !strcmp(value, "true") || !strcmp(value, "on"))
            *(bool *)(void *)base = true;
        else if (!strcmp(value, "0") || !strcmp(value, "false") || !strcmp(value, "off"))
            *(bool *)(void *)base = false;
        else {
            snprintf(err, errsize, "'%s' is not a boolean (0, 1, true, false)", value);
            return CBM_E_INVALID;
        }
        return CBM_OK;
    default:
        break;
    }
    if (!cbm__param_real(value, &v)) {
        snprintf(err, errsize, "'%s' is not a number", value);
        return CBM_E_INVALID;
    }
    if (pm->k == K_U64) {
        if (v < 0 || v != floor(v) || v > 9007199254740992.0) {
            snprintf(err, errsize, "'%s' is not a non-negative integer", value);
            return CBM_E_INVALID;
        }
        *(uint64_t *)(void *)base = (uint64_t)v;
        return CBM_OK;
    }
    if (pm->lo <= pm->hi && (v < pm->lo || v > pm->hi)) {
        snprintf(err, errsize, "%s is out of range [%g, %g]%s", value, pm->lo, pm->hi,
                 pm->k == K_ANGLE ? " degrees" : "");
        return CBM_E_INVALID;
    }
    if (pm->k == K_INT) {
        if (v != floor(v)) {
            snprintf(err, errsize, "'%s' is not an integer", value);
            return CBM_E_INVALID;
        }
        *(int *)(void *)base = (int)v;
    } else if (pm->k == K_ANGLE) {
        *(double *)(void *)base = v * DEG;
    } else {
        *(double *)(void *)base = v;
    }
    return CBM_OK;
}

cbm_status cbm_tree_def_set(cbm_context *ctx, cbm_tree_def *def, const char *name,
                            const char *value)
{
    if (!def || !name || !value)
        return CBM_E_INVALID;
    const param *pm = find(name, strlen(name));
    if (!pm)
        return cbm__fail(ctx, CBM_E_NOT_FOUND, "unknown tree parameter '%s'", name);
    char err[160];
    cbm_status s = set_param(pm, def, value, err, sizeof err);
    if (s != CBM_OK)
        return cbm__fail(ctx, s, "parameter %s: %s", name, err);
    return CBM_OK;
}

cbm_status cbm_tree_def_check(cbm_context *ctx, const cbm_tree_def *d)
{
    const char *bad = NULL;
    if (!d)
        return CBM_E_INVALID;
    for (size_t i = 0; i < NPARAMS && !bad; i++) {
        const param *pm = &params[i];
        const char *base = (const char *)d + pm->off;
        if (pm->k == K_DOUBLE || pm->k == K_ANGLE || pm->k == K_INT) {
            double v = pm->k == K_INT     ? *(const int *)(const void *)base
                       : pm->k == K_ANGLE ? *(const double *)(const void *)base / DEG
                                          : *(const double *)(const void *)base;
            if (!isfinite(v) || (pm->lo <= pm->hi && (v < pm->lo || v > pm->hi)))
                bad = pm->name;
        } else if (pm->k == K_FUNC) {
            const cbm_tree_func *f = (const cbm_tree_func *)(const void *)base;
            if (f->n < 1 || f->n > CBM_TREE_FUNC_MAX)
                bad = pm->name;
            for (int k = 1; k < f->n && !bad; k++)
                if (!(f->x[k] > f->x[k - 1]))
                    bad = pm->name;
        }
    }
    if (bad)
        return cbm__fail(ctx, CBM_E_INVALID, "tree parameter %s is out of range", bad);
    if (d->reaction_max_aspect > 0.0 && d->reaction_max_aspect < 1.0)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "tree parameter reaction_max_aspect must be 0 (no bound) or >= 1");
    if (d->youngs_adult < d->youngs_juvenile)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "tree parameter youngs_adult must be >= youngs_juvenile");
    if ((unsigned)d->form > CBM_TREE_CROOKED || (unsigned)d->discretization > CBM_MECH_CHAIN ||
        (unsigned)d->memory > CBM_MEMORY_JOINT || (unsigned)d->ageing > CBM_AGEING_CORE)
        return cbm__fail(ctx, CBM_E_INVALID, "tree parameter: bad enumeration value");
    return CBM_OK;
}

/* ---- the reader ---- */

bool cbm__param_next(cbm__param_lines *it, const char **l, size_t *i, size_t *m)
{
    while (it->pos < it->len) {
        it->line++;
        size_t end = it->pos;
        while (end < it->len && it->text[end] != '\n')
            end++;
        size_t n = end - it->pos;
        const char *t = it->text + it->pos;
        it->pos = end + 1;
        /* strip the comment (no value holds a '#') and trailing space */
        size_t e = 0;
        while (e < n && t[e] != '#')
            e++;
        while (e > 0 && (t[e - 1] == ' ' || t[e - 1] == '\t' || t[e - 1] == '\r'))
            e--;
        size_t b = 0;
        while (b < e && (t[b] == ' ' || t[b] == '\t'))
            b++;
        if (b == e)
            continue;
        *l = t, *i = b, *m = e;
        return true;
    }
    return false;
}

static bool is_name_char(char c)
{
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
}

cbm_status cbm_tree_def_parse(cbm_context *ctx, cbm_tree_def *def, const char *text, size_t len,
                              const char *name)
{
    if (!def || (!text && len))
        return CBM_E_INVALID;
    const char *file = name ? name : "<parameters>";
    size_t errors = 0;
    size_t max_diag = cbm_context_limits(ctx)->max_diagnostics;
    cbm__param_lines it = {text, len, 0, 0};
    char buf[1024];
    const char *l;
    size_t i, m;
    while (cbm__param_next(&it, &l, &i, &m)) {
        int line = it.line;
#define ERR(col, ...)                                                                              \
    do {                                                                                           \
        cbm__diag(ctx, CBM_ERROR, file, line, (int)(col) + 1, __VA_ARGS__);                        \
        errors++;                                                                                  \
        goto next;                                                                                 \
    } while (0)
        if (memchr(l, '\0', m))
            ERR(i, "NUL byte in a parameter file");
        bool is_func = false;
        if (m - i > 5 && !strncmp(l + i, "func", 4) && (l[i + 4] == ' ' || l[i + 4] == '\t')) {
            is_func = true;
            i += 4;
            while (i < m && (l[i] == ' ' || l[i] == '\t'))
                i++;
        }
        size_t k0 = i;
        while (i < m && is_name_char(l[i]))
            i++;
        if (i == k0)
            ERR(k0, "expected a parameter name, found '%c'", l[k0]);
        {
            char key[64];
            size_t klen = i - k0;
            if (klen >= sizeof key)
                ERR(k0, "parameter name too long");
            for (size_t c = 0; c < klen; c++) {
                char ch = l[k0 + c];
                /* function names are case-insensitive (NUMBUDS_VIGOUR = numbuds_vigour) */
                key[c] = is_func && ch >= 'A' && ch <= 'Z' ? (char)(ch - 'A' + 'a') : ch;
            }
            key[klen] = '\0';
            while (i < m && (l[i] == ' ' || l[i] == '\t'))
                i++;
            if (i >= m || l[i] != '=')
                ERR(i, "expected '=' after '%s'", key);
            i++;
            while (i < m && (l[i] == ' ' || l[i] == '\t'))
                i++;
            if (i == m)
                ERR(i, "missing value for '%s'", key);
            const param *pm = find(key, klen);
            if (!pm)
                ERR(k0, "unknown parameter '%s'", key);
            if (is_func != (pm->k == K_FUNC))
                ERR(k0,
                    is_func ? "'%s' is not a function"
                            : "'%s' is a function: write 'func %s = x:y ...'",
                    key, key);
            if (m - i >= sizeof buf)
                ERR(i, "value too long");
            memcpy(buf, l + i, m - i);
            buf[m - i] = '\0';
            char err[160];
            if (set_param(pm, def, buf, err, sizeof err) != CBM_OK)
                ERR(i, "%s: %s", key, err);
        }
#undef ERR
    next:
        if (max_diag && errors >= max_diag)
            break;
    }
    if (errors)
        return CBM_E_SYNTAX;
    return cbm_tree_def_check(ctx, def);
}

/* A parameter file's whole text (both model families' readers): *buf holds len bytes in an
 * allocation of cap bytes, which the caller frees, also on failure; at most 16 MiB. */
cbm_status cbm__tree_read_params(cbm_context *ctx, const char *path, char **out, size_t *out_len,
                                 size_t *out_cap)
{
    *out = NULL;
    *out_len = *out_cap = 0;
    FILE *f = fopen(path, "rb");
    if (!f)
        return cbm__fail(ctx, CBM_E_IO, "%s: cannot open: %s", path, strerror(errno));
    size_t cap = 4096, len = 0;
    char *buf = cbm__alloc(ctx, cap);
    cbm_status s = buf ? CBM_OK : CBM_E_NOMEM;
    while (s == CBM_OK) {
        if (len == cap) {
            if (cap > ((size_t)1 << 24)) {
                s = cbm__fail(ctx, CBM_E_LIMIT, "%s: parameter file larger than 16 MiB", path);
                break;
            }
            char *nb = cbm__realloc(ctx, buf, cap, cap * 2);
            if (!nb) {
                s = CBM_E_NOMEM;
                break;
            }
            buf = nb;
            cap *= 2;
        }
        size_t r = fread(buf + len, 1, cap - len, f);
        len += r;
        if (r == 0) {
            if (ferror(f))
                s = cbm__fail(ctx, CBM_E_IO, "%s: read error", path);
            break;
        }
    }
    fclose(f);
    *out = buf;
    *out_len = len;
    *out_cap = buf ? cap : 0;
    return s;
}

cbm_status cbm_tree_def_read(cbm_context *ctx, cbm_tree_def *def, const char *path)
{
    if (!path || !def)
        return CBM_E_INVALID;
    char *buf = NULL;
    size_t len = 0, cap = 0;
    cbm_status s = cbm__tree_read_params(ctx, path, &buf, &len, &cap);
    if (s == CBM_OK)
        s = cbm_tree_def_parse(ctx, def, buf, len, path);
    if (buf)
        cbm__free(ctx, buf, cap);
    return s;
}

size_t cbm_tree_def_format(const cbm_tree_def *d, char *buf, size_t size)
{
    size_t w = 0;
#define OUT(...)                                                                                   \
    do {                                                                                           \
        int r_ = snprintf(size > w ? buf + w : NULL, size > w ? size - w : 0, __VA_ARGS__);        \
        if (r_ > 0)                                                                                \
            w += (size_t)r_;                                                                       \
    } while (0)
    if (buf && size)
        buf[0] = '\0';
    for (size_t i = 0; i < NPARAMS; i++) {
        const param *pm = &params[i];
        const char *base = (const char *)d + pm->off;
        switch (pm->k) {
        case K_DOUBLE:
            OUT("%s = %.15g\n", pm->name, *(const double *)(const void *)base);
            break;
        case K_ANGLE:
            OUT("%s = %.15g\n", pm->name, *(const double *)(const void *)base / DEG);
            break;
        case K_INT:
            OUT("%s = %d\n", pm->name, *(const int *)(const void *)base);
            break;
        case K_U64:
            OUT("%s = %llu\n", pm->name, (unsigned long long)*(const uint64_t *)(const void *)base);
            break;
        case K_BOOL:
            OUT("%s = %d\n", pm->name, *(const bool *)(const void *)base ? 1 : 0);
            break;
        case K_FORM:
            OUT("%s = %s\n", pm->name, form_names[d->form]);
            break;
        case K_DISC:
            OUT("%s = %s\n", pm->name, disc_names[d->discretization]);
            break;
        case K_MEM:
            OUT("%s = %s\n", pm->name, mem_names[d->memory]);
            break;
        case K_AGE:
            OUT("%s = %s\n", pm->name, age_names[d->ageing]);
            break;
        case K_ALOAD:
            OUT("%s = %s\n", pm->name, aload_names[d->approx_load]);
            break;
        case K_SOLVER:
            OUT("%s = %s\n", pm->name, cbm_mech_solver_name(d->solver));
            break;
        case K_FUNC: {
            const cbm_tree_func *f = (const cbm_tree_func *)(const void *)base;
            OUT("func %s =", pm->name);
            for (int k = 0; k < f->n; k++)
                OUT(" %.15g:%.15g", f->x[k], f->y[k]);
            OUT("\n");
            break;
        }
        }
    }
#undef OUT
    return w;
}

/* ---- built-in models: the shipped parameter files' settings over the defaults ---- */

typedef struct builtin {
    const char *name;
    bool thesis;      /* over thesis_def() instead of cbm_tree_def_default() */
    const char *text; /* parameter-file text applied over the base */
} builtin;

#define ASPEN "years_to_shed = 3\nrelay_bias = 1\nfruit_prob = 0\n"
/* real trembling aspen (docs/models.md): green Populus tremuloides wood, the wild form's E; the
 * chapter 7 switch multiplies the base E by stiffness_factor (3) for the wild form, so the base
 * here is a third of it (the crooked clone's supple wood, the thesis' hypothesis). Phyllotaxis
 * 137.5 deg, not the apple's 144: poplar shoots pass from 2/5 to 3/8 and 5/13 (Larson 1977),
 * towards the golden angle, and an exact 2/5 spiral stacks every fifth bud on one side, where the
 * wild form's fivefold tropism merges them into crossing branches */
#define REAL_ASPEN                                                                                 \
    ASPEN "youngs_juvenile = 3.3e8\nyoungs_adult = 1.97e9\ndensity = 800\n"                        \
          "modulus_of_rupture = 35e6\nleaf_mass = 4e-4\nleaf_density = 0.2\nspur_fruit_prob = 0\n" \
          "tropism = 0.1\nphyllotaxis = 137.5\n"
static const builtin builtins[] = {
    {"fruit-tree", false, ""},
    {"fruit-tree-fair", false, "fairness = 1\n"},
    {"fruit-tree-unfair", false, "fairness = 0.2\n"},
    {"fruit-tree-high-mor", false, "modulus_of_rupture = 100e6\n"},
    {"fruit-tree-low-mor", false, "modulus_of_rupture = 15e6\n"},
    {"poplar-wild", false, "form = wild\n" REAL_ASPEN},
    {"poplar-crooked", false, "form = crooked\n" REAL_ASPEN},
    {"fruit-tree-thesis", true, ""},
    {"fruit-tree-thesis-unfair", true, "fairness = 0.2\n"},
    {"fruit-tree-thesis-high-mor", true, "modulus_of_rupture = 2.9e7\n"},
    {"fruit-tree-thesis-low-mor", true, "modulus_of_rupture = 1.2e5\n"},
    {"poplar-wild-thesis", true, "form = wild\n" ASPEN},
    {"poplar-crooked-thesis", true, "form = crooked\n" ASPEN},
};
#define NBUILTINS (sizeof builtins / sizeof builtins[0])

const char *const *cbm_tree_builtin_names(void)
{
    static const char *const names[] = {"fruit-tree",
                                        "fruit-tree-fair",
                                        "fruit-tree-unfair",
                                        "fruit-tree-high-mor",
                                        "fruit-tree-low-mor",
                                        "poplar-wild",
                                        "poplar-crooked",
                                        "fruit-tree-thesis",
                                        "fruit-tree-thesis-unfair",
                                        "fruit-tree-thesis-high-mor",
                                        "fruit-tree-thesis-low-mor",
                                        "poplar-wild-thesis",
                                        "poplar-crooked-thesis",
                                        NULL};
    _Static_assert(sizeof names / sizeof names[0] == NBUILTINS + 1, "builtin names");
    return names;
}

cbm_status cbm_tree_def_builtin(cbm_context *ctx, const char *name, cbm_tree_def *out)
{
    if (!name || !out)
        return CBM_E_INVALID;
    for (size_t i = 0; i < NBUILTINS; i++)
        if (!strcmp(name, builtins[i].name)) {
            cbm_tree_def d = builtins[i].thesis ? thesis_def() : cbm_tree_def_default();
            CBM_TRY(cbm_tree_def_parse(ctx, &d, builtins[i].text, strlen(builtins[i].text),
                                       builtins[i].name));
            *out = d;
            return CBM_OK;
        }
    return cbm__fail(ctx, CBM_E_NOT_FOUND, "no built-in tree model '%s'", name);
}
