/* Parameters of Oberlaender's parametric tree: the defaults, the parameter-file reader (the
 * thesis's names; formulas, per-order slots `name[k]`, lists `{a, b, ...}`), the range checks,
 * the writer of a whole parameter set and the built-in presets (Table 4's Massart, Attims, Rauh
 * and Troll, the statistical Cryptomeria of eqs. 14-18). docs/models.md lists every name. */
#include "tree/ober_internal.h"
#include "tree/tree_internal.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>

static void set_formula(cbm_ober_formula *f, const char *text, const char *file, int line, int col)
{
    snprintf(f->text, sizeof f->text, "%s", text);
    snprintf(f->file, sizeof f->file, "%s", file);
    f->line = line;
    f->col = col;
}

/* The formulas of the defaults name this file in their messages (they cannot fail). */
#define DF(f, t) set_formula(&(f), (t), "<ober defaults>", 1, 1)

cbm_ober_def cbm_ober_def_default(void)
{
    cbm_ober_def d;
    memset(&d, 0, sizeof d);
    d.seed = 1;
    d.years = 12;
    d.max_order = 3;
    /* eq. 15: the Cryptomeria Richards increment h'(t), m/year -> cm/year */
    DF(d.base_length, "100 * richards_inc(age, 24.9506, 0.06438, 1.9736)");
    DF(d.carbon_tax, "0");
    /* eqs. 16-18 with epsilon = 0.5, omega = 0.3 (not given in the thesis) */
    d.n_specific_length = 3;
    DF(d.specific_length[0], "baseLength");
    DF(d.specific_length[1], "0.5 * len * position + 0.3 * baseLength");
    DF(d.specific_length[2], "len * position");
    d.n_num_nodes = 2;
    DF(d.num_nodes[0], "2");
    DF(d.num_nodes[1], "2");
    /* Listing 13: the trunk always sprouts, branches less with trend, more with the tree's age */
    DF(d.sprouting, "order == 0 ? 1 : ran(1) > 0.1 * trend - 0.05 * treeAge");
    DF(d.proventitious, "0");
    DF(d.apical_split, "0");
    DF(d.short_shoot, "0");
    d.possibility_node_0 = d.possibility_node_x = 1.0;
    d.possibility_bud_0 = 1.0;
    d.possibility_bud_y = 0.5; /* half the buds of a branch grow, the rest sleep */
    /* Table 4, Rauh: whorls of 5 (0.95) or 6 (0.05) buds, V-shaped branch nodes, orthotropic */
    d.n_new_shoots = 7;
    d.number_new_shoots_0[5] = 0.95;
    d.number_new_shoots_0[6] = 0.05;
    d.n_shoot_poss = 2;
    d.shoot_poss[0] = -30;
    d.shoot_poss[1] = -150;
    d.n_shoot_angle = 3;
    d.shoot_angle[0] = 60;
    d.shoot_angle[1] = 40;
    d.shoot_angle[2] = 50;
    d.leaf_length = 8;
    d.leaf_width = 4;
    d.leaf_die_age = 1;
    d.pipe_size = 0.06;
    DF(d.orientation, "-0.4");
    DF(d.bending, "order > 0 ? 0.01 : 0");
    d.offset_0 = d.offset_x = 75;
    d.initial_length = 0;
    d.fork_angle = 25;
    d.seed_stems = 1;
    d.seed_stem_head = 60; /* Listing 14's cumulative RH(60) */
    d.sky = 1;             /* the thesis's light field: even light over a stand */
    d.light_rings = 4;
    d.light_azimuths = 8;
    d.light_samples = 1;
    d.mech_e = 8e9; /* as cbm_ober_mech_def_default() */
    d.mech_density = 800;
    d.mech_leaf_mass = 0.2;
    d.solve_threads = 0; /* one per processor */
    d.stand_x = d.stand_y = 1;
    d.spacing = 3;
    return d;
}

/* ---- the parameter table ---- */

typedef enum kind { K_U64, K_INT, K_REAL, K_BOOL, K_FORMULA, K_ORDERS, K_LIST } kind;

typedef struct param {
    const char *name;
    kind k;
    size_t off;
    size_t count_off; /* K_ORDERS, K_LIST: the int counting the slots set */
    double lo, hi;    /* range of numbers (K_INT, K_REAL) and of list entries */
} param;

#define O(f) offsetof(cbm_ober_def, f)
static const param PARAMS[] = {
    {"seed", K_U64, O(seed), 0, 0, 0},
    {"years", K_INT, O(years), 0, 0, 1000},
    {"maxOrder", K_INT, O(max_order), 0, 0, 7},
    {"baseLengthLambda", K_FORMULA, O(base_length), 0, 0, 0},
    {"carbonTaxLambda", K_FORMULA, O(carbon_tax), 0, 0, 0},
    {"specificLengthLambda", K_ORDERS, O(specific_length), O(n_specific_length), 0, 0},
    {"numNodeLambda", K_ORDERS, O(num_nodes), O(n_num_nodes), 0, 0},
    {"sproutingPossibilityLambda", K_FORMULA, O(sprouting), 0, 0, 0},
    {"proventitiosShootLambda", K_FORMULA, O(proventitious), 0, 0, 0},
    {"proventitiousShootLambda", K_FORMULA, O(proventitious), 0, 0, 0},
    {"apicalSplitLambda", K_FORMULA, O(apical_split), 0, 0, 0},
    {"treeForkLambda", K_FORMULA, O(apical_split), 0, 0, 0},
    {"shortShootLambda", K_FORMULA, O(short_shoot), 0, 0, 0},
    {"possibilityNode_0", K_REAL, O(possibility_node_0), 0, 0, 1},
    {"possibilityNode_x", K_REAL, O(possibility_node_x), 0, 0, 1},
    {"possibilityBud_0", K_REAL, O(possibility_bud_0), 0, 0, 1},
    {"possibilityBud_y", K_REAL, O(possibility_bud_y), 0, 0, 1},
    {"numberNewShoots_0", K_LIST, O(number_new_shoots_0), O(n_new_shoots), 0, 1},
    {"shootPoss", K_LIST, O(shoot_poss), O(n_shoot_poss), -360, 360},
    {"shootPos", K_LIST, O(shoot_poss), O(n_shoot_poss), -360, 360},
    {"shootangle", K_LIST, O(shoot_angle), O(n_shoot_angle), 0, 180},
    {"leafL", K_REAL, O(leaf_length), 0, 0, 1e4},
    {"leafW", K_REAL, O(leaf_width), 0, 0, 1e4},
    {"leafDieAge", K_INT, O(leaf_die_age), 0, 1, 1000},
    {"pipeSize", K_REAL, O(pipe_size), 0, 1e-6, 1e3},
    {"orientationLambda", K_FORMULA, O(orientation), 0, 0, 0},
    {"bendingLambda", K_FORMULA, O(bending), 0, 0, 0},
    {"offset_0", K_REAL, O(offset_0), 0, -360, 360},
    {"offset_x", K_REAL, O(offset_x), 0, -360, 360},
    {"initialLength", K_REAL, O(initial_length), 0, 0, 1e5},
    {"forkAngle", K_REAL, O(fork_angle), 0, 0, 90},
    {"seedStems", K_INT, O(seed_stems), 0, 1, 64},
    {"seedStemHead", K_REAL, O(seed_stem_head), 0, -360, 360},
    {"seedStemTilt", K_REAL, O(seed_stem_tilt), 0, 0, 180},
    {"pipeAllLeaves", K_BOOL, O(pipe_all_leaves), 0, 0, 0},
    {"carbonSum", K_BOOL, O(carbon_sum), 0, 0, 0},
    {"light", K_BOOL, O(light), 0, 0, 0},
    {"sky", K_INT, O(sky), 0, 0, 3},
    {"lightRings", K_INT, O(light_rings), 0, 1, 32},
    {"lightAzimuths", K_INT, O(light_azimuths), 0, 1, 64},
    {"lightSamples", K_INT, O(light_samples), 0, 1, 16},
    {"lightStems", K_BOOL, O(light_stems), 0, 0, 0},
    {"mechanicsFeedback", K_BOOL, O(mech_feedback), 0, 0, 0},
    {"mechE", K_REAL, O(mech_e), 0, 1e5, 1e15},
    {"mechDensity", K_REAL, O(mech_density), 0, 0, 1e5},
    {"mechLeafMass", K_REAL, O(mech_leaf_mass), 0, 0, 1e3},
    {"solve_threads", K_INT, O(solve_threads), 0, 0, 1024}, /* as the fruit tree's */
    {"standX", K_INT, O(stand_x), 0, 1, 20},
    {"standY", K_INT, O(stand_y), 0, 1, 20},
    {"spacing", K_REAL, O(spacing), 0, 0.01, 1e3},
    {"jitter", K_REAL, O(jitter), 0, 0, 1e3},
    {"stagger", K_INT, O(stagger), 0, 0, 100},
};
#undef O
#define NPARAMS (sizeof PARAMS / sizeof PARAMS[0])

static const param *find(const char *name, size_t len)
{
    for (size_t i = 0; i < NPARAMS; i++)
        if (strlen(PARAMS[i].name) == len && !memcmp(PARAMS[i].name, name, len))
            return &PARAMS[i];
    return NULL;
}

/* `{a, b, c}` or `a b c` */
static bool parse_list(const char *s, double *v, int *n, double lo, double hi, char *err, size_t en)
{
    while (*s == ' ' || *s == '\t')
        s++;
    bool brace = *s == '{';
    if (brace)
        s++;
    int k = 0;
    for (;;) {
        while (*s == ' ' || *s == '\t' || *s == ',')
            s++;
        if (!*s || *s == '}')
            break;
        char *end;
        errno = 0;
        double x = strtod(s, &end);
        if (end == s || errno == ERANGE || !isfinite(x)) {
            snprintf(err, en, "expected a number in the list, found '%.20s'", s);
            return false;
        }
        if (x < lo || x > hi) {
            snprintf(err, en, "list entry %g outside [%g, %g]", x, lo, hi);
            return false;
        }
        if (k >= CBM_OBER_LIST_MAX) {
            snprintf(err, en, "more than %d entries", CBM_OBER_LIST_MAX);
            return false;
        }
        v[k++] = x;
        s = end;
    }
    if (brace && *s != '}') {
        snprintf(err, en, "missing '}' at the end of the list");
        return false;
    }
    if (*s == '}') {
        s++;
        while (*s == ' ' || *s == '\t')
            s++;
        if (*s) {
            snprintf(err, en, "unexpected '%c' after the list", *s);
            return false;
        }
    }
    if (k == 0) {
        snprintf(err, en, "empty list");
        return false;
    }
    *n = k;
    return true;
}

/* Sets parameter pm (slot `index` of a per-order formula, -1: all) from value. */
static cbm_status set_param(const param *pm, int index, cbm_ober_def *d, const char *value,
                            const char *file, int line, int col, char *err, size_t en)
{
    char *base = (char *)d + pm->off;
    double v;
    switch (pm->k) {
    case K_U64: {
        char *end;
        errno = 0;
        unsigned long long u = strtoull(value, &end, 10);
        if (end == value || *end || errno || value[0] == '-') {
            snprintf(err, en, "expected a non-negative integer");
            return CBM_E_INVALID;
        }
        *(uint64_t *)(void *)base = u;
        return CBM_OK;
    }
    case K_INT:
    case K_REAL:
        if (!cbm__param_real(value, &v) || (pm->k == K_INT && v != floor(v))) {
            snprintf(err, en, "expected %s", pm->k == K_INT ? "an integer" : "a number");
            return CBM_E_INVALID;
        }
        if (v < pm->lo || v > pm->hi) {
            snprintf(err, en, "%g outside [%g, %g]", v, pm->lo, pm->hi);
            return CBM_E_INVALID;
        }
        if (pm->k == K_INT)
            *(int *)(void *)base = (int)v;
        else
            *(double *)(void *)base = v;
        return CBM_OK;
    case K_BOOL:
        if (!strcmp(value, "1") || !strcmp(value, "true"))
            *(bool *)(void *)base = true;
        else if (!strcmp(value, "0") || !strcmp(value, "false"))
            *(bool *)(void *)base = false;
        else {
            snprintf(err, en, "expected 0 or 1");
            return CBM_E_INVALID;
        }
        return CBM_OK;
    case K_FORMULA:
    case K_ORDERS: {
        if (strlen(value) >= CBM_OBER_FORMULA_MAX) {
            snprintf(err, en, "formula longer than %d characters", CBM_OBER_FORMULA_MAX - 1);
            return CBM_E_INVALID;
        }
        cbm_ober_formula *f = (cbm_ober_formula *)(void *)base;
        if (pm->k == K_FORMULA) {
            set_formula(f, value, file, line, col);
            return CBM_OK;
        }
        int *n = (int *)(void *)((char *)d + pm->count_off);
        if (index < 0) { /* every order */
            for (int k = 0; k < CBM_OBER_ORDERS; k++)
                set_formula(&f[k], value, file, line, col);
            *n = 1;
            return CBM_OK;
        }
        /* slots between the last set and this one repeat the last set */
        for (int k = *n; k < index; k++)
            f[k] = f[*n > 0 ? *n - 1 : 0];
        set_formula(&f[index], value, file, line, col);
        if (index + 1 > *n)
            *n = index + 1;
        return CBM_OK;
    }
    case K_LIST: {
        double tmp[CBM_OBER_LIST_MAX];
        int n;
        if (!parse_list(value, tmp, &n, pm->lo, pm->hi, err, en))
            return CBM_E_INVALID;
        memcpy(base, tmp, sizeof tmp);
        *(int *)(void *)((char *)d + pm->count_off) = n;
        return CBM_OK;
    }
    }
    return CBM_E_INVALID;
}

/* Splits `name` or `name[k]`: the parameter and the slot (-1: none). */
static const param *lookup(const char *key, size_t klen, int *index, char *err, size_t en)
{
    *index = -1;
    const char *br = memchr(key, '[', klen);
    size_t nlen = br ? (size_t)(br - key) : klen;
    const param *pm = find(key, nlen);
    if (!pm) {
        snprintf(err, en, "unknown parameter '%.*s'", (int)nlen, key);
        return NULL;
    }
    if (br) {
        if (pm->k != K_ORDERS) {
            snprintf(err, en, "'%s' has no per-order slots", pm->name);
            return NULL;
        }
        char *end;
        long k = strtol(br + 1, &end, 10);
        if (end == br + 1 || *end != ']' || (size_t)(end + 1 - key) != klen || k < 0 ||
            k >= CBM_OBER_ORDERS) {
            snprintf(err, en, "'%s[k]' takes an order k in 0..%d", pm->name, CBM_OBER_ORDERS - 1);
            return NULL;
        }
        *index = (int)k;
    }
    return pm;
}

cbm_status cbm_ober_def_set(cbm_context *ctx, cbm_ober_def *def, const char *name,
                            const char *value, const char *origin)
{
    if (!def || !name || !value)
        return CBM_E_INVALID;
    char err[200], where[96];
    int index;
    const param *pm = lookup(name, strlen(name), &index, err, sizeof err);
    if (!pm)
        return cbm__fail(ctx, CBM_E_NOT_FOUND, "%s", err);
    snprintf(where, sizeof where, "%s", origin ? origin : "-D");
    if (!origin)
        snprintf(where, sizeof where, "-D %.80s", name);
    if (set_param(pm, index, def, value, where, 1, 1, err, sizeof err) != CBM_OK)
        return cbm__fail(ctx, CBM_E_INVALID, "%s: %s", name, err);
    return CBM_OK;
}

static bool name_char(char c)
{
    return isalnum((unsigned char)c) || c == '_' || c == '[' || c == ']';
}

bool cbm_ober_text_is_family(const char *text, size_t len)
{
    size_t pos = 0;
    while (pos < len) {
        size_t end = pos;
        while (end < len && text[end] != '\n')
            end++;
        const char *l = text + pos;
        size_t n = end - pos, i = 0;
        pos = end + 1;
        while (i < n && (l[i] == ' ' || l[i] == '\t' || l[i] == '\r'))
            i++;
        if (i == n || l[i] == '#')
            continue;
        /* the first setting decides */
        char buf[64];
        size_t k = 0;
        for (; i < n && k + 1 < sizeof buf; i++)
            if (l[i] != ' ' && l[i] != '\t' && l[i] != '\r')
                buf[k++] = l[i];
        buf[k] = '\0';
        char *hash = strchr(buf, '#');
        if (hash)
            *hash = '\0';
        return !strcmp(buf, "family=oberlaender");
    }
    return false;
}

cbm_status cbm_ober_def_parse(cbm_context *ctx, cbm_ober_def *def, const char *text, size_t len,
                              const char *name)
{
    if (!def || (!text && len))
        return CBM_E_INVALID;
    const char *file = name ? name : "<parameters>";
    size_t errors = 0, max_diag = cbm_context_limits(ctx)->max_diagnostics;
    cbm__param_lines it = {text, len, 0, 0}; /* a '#' starts a comment: formulas have none */
    char buf[CBM_OBER_FORMULA_MAX + 8], err[240];
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
        size_t k0 = i;
        while (i < m && name_char(l[i]))
            i++;
        if (i == k0)
            ERR(k0, "expected a parameter name, found '%c'", l[k0]);
        size_t klen = i - k0;
        while (i < m && (l[i] == ' ' || l[i] == '\t'))
            i++;
        if (i >= m || l[i] != '=')
            ERR(i, "expected '=' after '%.*s'", (int)klen, l + k0);
        i++;
        while (i < m && (l[i] == ' ' || l[i] == '\t'))
            i++;
        if (i == m)
            ERR(i, "missing value for '%.*s'", (int)klen, l + k0);
        if (m - i >= sizeof buf)
            ERR(i, "value too long");
        memcpy(buf, l + i, m - i);
        buf[m - i] = '\0';
        if (klen == 6 && !memcmp(l + k0, "family", 6)) {
            if (strcmp(buf, "oberlaender"))
                ERR(i, "family '%s': this reader knows 'oberlaender'", buf);
            goto next;
        }
        int index;
        const param *pm = lookup(l + k0, klen, &index, err, sizeof err);
        if (!pm)
            ERR(k0, "%s", err);
        if (set_param(pm, index, def, buf, file, line, (int)i + 1, err, sizeof err) != CBM_OK)
            ERR(i, "%.*s: %s", (int)klen, l + k0, err);
#undef ERR
    next:
        if (max_diag && errors >= max_diag)
            break;
    }
    if (errors)
        return CBM_E_SYNTAX;
    return cbm_ober_def_check(ctx, def);
}

cbm_status cbm_ober_def_read(cbm_context *ctx, cbm_ober_def *def, const char *path)
{
    if (!path || !def)
        return CBM_E_INVALID;
    char *buf = NULL;
    size_t len = 0, cap = 0;
    cbm_status s = cbm__tree_read_params(ctx, path, &buf, &len, &cap);
    if (s == CBM_OK)
        s = cbm_ober_def_parse(ctx, def, buf, len, path);
    if (buf)
        cbm__free(ctx, buf, cap);
    return s;
}

cbm_status cbm_ober_def_check(cbm_context *ctx, const cbm_ober_def *d)
{
    if (!d)
        return CBM_E_INVALID;
    for (size_t i = 0; i < NPARAMS; i++) {
        const param *pm = &PARAMS[i];
        const char *base = (const char *)d + pm->off;
        double v = pm->k == K_INT    ? *(const int *)(const void *)base
                   : pm->k == K_REAL ? *(const double *)(const void *)base
                                     : 0;
        if ((pm->k == K_INT || pm->k == K_REAL) && !(v >= pm->lo && v <= pm->hi))
            return cbm__fail(ctx, CBM_E_INVALID, "%s = %g outside [%g, %g]", pm->name, v, pm->lo,
                             pm->hi);
    }
    if (d->n_specific_length < 1 || d->n_num_nodes < 1 || d->n_specific_length > CBM_OBER_ORDERS ||
        d->n_num_nodes > CBM_OBER_ORDERS)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "specificLengthLambda and numNodeLambda need a formula for order 0");
    if (d->n_new_shoots < 1 || d->n_shoot_poss < 1 || d->n_shoot_angle < 1 ||
        d->n_new_shoots > CBM_OBER_LIST_MAX || d->n_shoot_poss > CBM_OBER_LIST_MAX ||
        d->n_shoot_angle > CBM_OBER_LIST_MAX)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "numberNewShoots_0, shootPoss and shootangle need at least one entry");
    double sum = 0;
    for (int k = 0; k < d->n_new_shoots; k++)
        sum += d->number_new_shoots_0[k];
    if (fabs(sum - 1.0) > 1e-6)
        return cbm__fail(ctx, CBM_E_INVALID,
                         "numberNewShoots_0: the probabilities sum to %g, not 1", sum);
    if ((long)d->stand_x * d->stand_y > CBM_OBER_TREES_MAX)
        return cbm__fail(ctx, CBM_E_INVALID, "standX x standY: at most %d trees",
                         CBM_OBER_TREES_MAX);
    ober_prog p;
    cbm_status st = cbm__ober_compile(ctx, d, &p);
    if (st == CBM_OK)
        cbm__ober_prog_free(&p);
    return st;
}

static void append_printf(char *buf, size_t size, size_t *n, const char *fmt, ...) CBM_PRINTF(4, 5);
static void append_printf(char *buf, size_t size, size_t *n, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int w = vsnprintf(*n < size ? buf + *n : NULL, *n < size ? size - *n : 0, fmt, ap);
    va_end(ap);
    if (w > 0)
        *n += (size_t)w;
}

size_t cbm_ober_def_format(const cbm_ober_def *d, char *buf, size_t size)
{
    size_t n = 0;
    if (buf && size)
        buf[0] = '\0';
    append_printf(buf, size, &n, "family = oberlaender\n");
    for (size_t i = 0; i < NPARAMS; i++) {
        const param *pm = &PARAMS[i];
        if (i > 0 && PARAMS[i - 1].off == pm->off)
            continue; /* an alias */
        const char *base = (const char *)d + pm->off;
        switch (pm->k) {
        case K_U64:
            append_printf(buf, size, &n, "%s = %llu\n", pm->name,
                          (unsigned long long)*(const uint64_t *)(const void *)base);
            break;
        case K_INT:
            append_printf(buf, size, &n, "%s = %d\n", pm->name, *(const int *)(const void *)base);
            break;
        case K_REAL:
            append_printf(buf, size, &n, "%s = %.15g\n", pm->name,
                          *(const double *)(const void *)base);
            break;
        case K_BOOL:
            append_printf(buf, size, &n, "%s = %d\n", pm->name,
                          *(const bool *)(const void *)base ? 1 : 0);
            break;
        case K_FORMULA:
            append_printf(buf, size, &n, "%s = %s\n", pm->name,
                          ((const cbm_ober_formula *)(const void *)base)->text);
            break;
        case K_ORDERS: {
            /* slot 0 unindexed, which sets every slot and the count to 1, so the slots read
             * back are exactly these whatever the defaults hold beyond them */
            int cnt = *(const int *)(const void *)((const char *)d + pm->count_off);
            const cbm_ober_formula *f = (const cbm_ober_formula *)(const void *)base;
            for (int k = 0; k < cnt; k++) {
                if (k == 0)
                    append_printf(buf, size, &n, "%s = %s\n", pm->name, f[0].text);
                else
                    append_printf(buf, size, &n, "%s[%d] = %s\n", pm->name, k, f[k].text);
            }
            break;
        }
        case K_LIST: {
            int cnt = *(const int *)(const void *)((const char *)d + pm->count_off);
            append_printf(buf, size, &n, "%s = {", pm->name);
            for (int k = 0; k < cnt; k++)
                append_printf(buf, size, &n, "%s%.15g", k ? ", " : "",
                              ((const double *)(const void *)base)[k]);
            append_printf(buf, size, &n, "}\n");
            break;
        }
        }
    }
    return n;
}

/* ---- built-in presets: the shipped models/NAME.tree settings over the defaults ---- */

typedef struct builtin {
    const char *name, *text;
} builtin;

/* Table 4 */
#define WHORLED "numNodeLambda[0] = 2\nnumberNewShoots_0 = {0,0,0,0,0,0.95,0.05}\n"
#define SPIRAL  "numNodeLambda[0] = 4\nnumberNewShoots_0 = {0,0.95,0.05}\n"
#define PLAGIO  "shootangle = {80,70,50}\nshootPoss = {0,180}\norientationLambda = -0.01\n"
#define ORTHO   "shootangle = {60,40,50}\nshootPoss = {-30,-150}\norientationLambda = -0.4\n"
static const builtin BUILTINS[] = {
    {"ober-massart", WHORLED PLAGIO "offset_0 = 75\noffset_x = 75\n"},
    {"ober-attims", SPIRAL ORTHO "offset_0 = 75\noffset_x = 75\n"},
    {"ober-rauh", WHORLED ORTHO "offset_0 = 75\noffset_x = 75\n"},
    {"ober-troll", SPIRAL PLAGIO "offset_0 = 75\noffset_x = 75\n"},
    {"ober-cryptomeria", ""},
    /* the carbon balance (eqs. 19-22) on Rauh's architecture, c = carbon - carbonTax: the
     * tax with alpha = 0.5 and beta = 5e-4 per cm^3, l_max 60/40/25 cm, phi = 0.7, xi = 0.3,
     * x = 2 cm (none given in the thesis), the sprouting thresholds of eq. 22 */
    {"ober-carbon",
     "light = 1\nyears = 15\ninitialLength = 30\n"
     "carbonTaxLambda = (woodVolume - 0.5 * trunkVolume) / (1 + activeShoots) * 5e-4\n"
     "specificLengthLambda[0] = 60 * max(carbon - carbonTax, 0)\n"
     "specificLengthLambda[1] = 0.7 * 40 * max(carbon - carbonTax, 0) + 0.3 * (len * position - "
     "2 * trend)\n"
     "specificLengthLambda[2] = 0.7 * 25 * max(carbon - carbonTax, 0) + 0.3 * (len * position - "
     "2 * trend)\n"
     "sproutingPossibilityLambda = order == 0 ? carbon - carbonTax > 0.05 : carbon - carbonTax > "
     "0.2\n"},
};
#define NBUILTINS (sizeof BUILTINS / sizeof BUILTINS[0])

const char *const *cbm_ober_builtin_names(void)
{
    static const char *const names[] = {
        "ober-massart",     "ober-attims", "ober-rauh", "ober-troll",
        "ober-cryptomeria", "ober-carbon", NULL};
    _Static_assert(sizeof names / sizeof names[0] == NBUILTINS + 1, "builtin names");
    return names;
}

cbm_status cbm_ober_def_builtin(cbm_context *ctx, const char *name, cbm_ober_def *out)
{
    if (!name || !out)
        return CBM_E_INVALID;
    for (size_t i = 0; i < NBUILTINS; i++)
        if (!strcmp(name, BUILTINS[i].name)) {
            cbm_ober_def d = cbm_ober_def_default();
            CBM_TRY(cbm_ober_def_parse(ctx, &d, BUILTINS[i].text, strlen(BUILTINS[i].text),
                                       BUILTINS[i].name));
            *out = d;
            return CBM_OK;
        }
    return cbm__fail(ctx, CBM_E_NOT_FOUND, "no built-in Oberlaender tree '%s'", name);
}
