/* The formulas of Oberlaender's parametric tree: every formula of a definition is compiled by
 * the model language's own parser (lang/expr_parse.c, cpfg dialect plus the growth functions,
 * CBM__TREE) into one node array and evaluated by its evaluator (lang/cpfg_code.c), so a formula
 * has the language's operators, ?:, math and seeded random functions. The variables of the
 * thesis's Table 2 are the parser's formal parameters; a formula may read the variables of its
 * level and of the levels above it (tree < shoot < bud, eq. 10), anything else is an error at
 * its file, line and column. The compiler sees one line per formula, placed at the formula's
 * column, and a line map back to where it was written. */
#include "tree/ober_internal.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>

typedef struct var_name {
    const char *name;
    int slot;
} var_name;

static const var_name VARS[] = {
    {"age", V_AGE},
    {"treeAge", V_TREE_AGE},
    {"carbonTax", V_CARBON_TAX},
    {"baseLength", V_BASE_LENGTH},
    {"carbonMean", V_CARBON_MEAN},
    {"activeShoots", V_ACTIVE_SHOOTS},
    {"sumLeaves", V_SUM_LEAVES},
    {"woodVolume", V_WOOD_VOLUME},
    {"trunkVolume", V_TRUNK_VOLUME},
    {"height", V_HEIGHT},
    {"tree", V_TREE_INDEX},
    {"len", V_LEN},
    {"length", V_LENGTH},
    {"diameter", V_DIAMETER},
    {"radius", V_RADIUS},
    {"nodeNumber", V_NODE_NUMBER},
    {"order", V_ORDER},
    {"trend", V_TREND},
    {"volume", V_VOLUME},
    {"carbon", V_CARBON},
    {"leaves", V_LEAVES},
    {"position", V_POSITION},
    {"sleep", V_SLEEP},
    {"shortShoot", V_SHORT_SHOOT},
    {"apical", V_APICAL},
    {"parentOrder", V_PARENT_ORDER},
    {"parentTrend", V_PARENT_TREND},
};
#define NVARS (sizeof VARS / sizeof VARS[0])

static const char *const NAMES[F_SPECIFIC_LENGTH] = {
    "baseLengthLambda",        "carbonTaxLambda",   "sproutingPossibilityLambda",
    "proventitiosShootLambda", "apicalSplitLambda", "shortShootLambda",
    "orientationLambda",       "bendingLambda"};

const char *cbm__ober_formula_name(int f)
{
    static char buf[F_COUNT][48];
    if (f < 0 || f >= F_COUNT)
        return "unknown formula";
    if (f < F_SPECIFIC_LENGTH)
        return NAMES[f];
    if (!buf[f][0])
        snprintf(buf[f], sizeof buf[f], "%s[%d]",
                 f < F_NUM_NODES ? "specificLengthLambda" : "numNodeLambda",
                 f < F_NUM_NODES ? f - F_SPECIFIC_LENGTH : f - F_NUM_NODES);
    return buf[f];
}

static ober_level level_of(int f)
{
    switch (f) {
    case F_BASE_LENGTH:
    case F_CARBON_TAX:
        return LVL_TREE;
    case F_SPROUTING:
    case F_BENDING:
        return LVL_SHOOT;
    default:
        return LVL_BUD;
    }
}

static const cbm_ober_formula *formula_of(const cbm_ober_def *d, int f)
{
    switch (f) {
    case F_BASE_LENGTH:
        return &d->base_length;
    case F_CARBON_TAX:
        return &d->carbon_tax;
    case F_SPROUTING:
        return &d->sprouting;
    case F_PROVENTITIOUS:
        return &d->proventitious;
    case F_APICAL_SPLIT:
        return &d->apical_split;
    case F_SHORT_SHOOT:
        return &d->short_shoot;
    case F_ORIENTATION:
        return &d->orientation;
    case F_BENDING:
        return &d->bending;
    default:
        if (f < F_NUM_NODES) {
            int k = f - F_SPECIFIC_LENGTH;
            return k < d->n_specific_length ? &d->specific_length[k] : NULL;
        }
        int k = f - F_NUM_NODES;
        return k < d->n_num_nodes ? &d->num_nodes[k] : NULL;
    }
}

void cbm__ober_prog_free(ober_prog *p)
{
    cbm__eval_free(&p->ev);
    if (p->have_c)
        cbm__compiler_free(&p->c);
    p->have_c = false;
}

static cbm_status file_index(cbm_context *ctx, cbm__pp *pp, const char *name, int *out)
{
    for (size_t i = 0; i < pp->files.len; i++)
        if (!strcmp(pp->files.data[i], name)) {
            *out = (int)i;
            return CBM_OK;
        }
    char *d = cbm__strdup(ctx, name);
    if (!d)
        return CBM_E_NOMEM;
    if (CBM_ARRAY_PUSH(ctx, pp->files, d) != CBM_OK) {
        cbm__strfree(ctx, d);
        return CBM_E_NOMEM;
    }
    *out = (int)pp->files.len - 1;
    return CBM_OK;
}

/* The preprocessed text the compiler reads: formula f on its own line, indented to its column,
 * line_of[f] that line's index (-1: unset). */
static cbm_status build_text(cbm_context *ctx, const cbm_ober_def *d, cbm__pp *pp, int *line_of)
{
    int nl = 0;
    for (int f = 0; f < F_COUNT; f++) {
        line_of[f] = -1;
        const cbm_ober_formula *fm = formula_of(d, f);
        if (!fm || !fm->text[0])
            continue;
        int fi;
        CBM_TRY(file_index(ctx, pp, fm->file[0] ? fm->file : cbm__ober_formula_name(f), &fi));
        cbm__pp_line pl = {fi, fm->line > 0 ? fm->line : 1, -1};
        CBM_TRY(CBM_ARRAY_PUSH(ctx, pp->lines, pl));
        int col = fm->col > 1 && fm->col < 10000 ? fm->col : 1;
        for (int k = 1; k < col; k++)
            CBM_TRY(CBM_ARRAY_PUSH(ctx, pp->text, ' '));
        for (const char *s = fm->text; *s; s++) {
            char ch = *s == '\n' || *s == '\r' ? ' ' : *s;
            CBM_TRY(CBM_ARRAY_PUSH(ctx, pp->text, ch));
        }
        CBM_TRY(CBM_ARRAY_PUSH(ctx, pp->text, '\n'));
        line_of[f] = nl++;
    }
    return CBM_ARRAY_PUSH(ctx, pp->text, '\0');
}

/* Text offset of the first whole-word use of name on the line at start (node positions mark
 * where the parser was after a name, not where it began). */
static size_t word_at(const cbm__compiler *c, size_t start, const char *name)
{
    size_t n = strlen(name);
    for (size_t p = start; c->text[p] && c->text[p] != '\n'; p++)
        if (!strncmp(c->text + p, name, n) &&
            (p == start || !(isalnum((unsigned char)c->text[p - 1]) || c->text[p - 1] == '_')) &&
            !(isalnum((unsigned char)c->text[p + n]) || c->text[p + n] == '_'))
            return p;
    return start;
}

static const char *level_name(ober_level l)
{
    return l == LVL_TREE ? "tree" : l == LVL_SHOOT ? "shoot" : "bud";
}

cbm_status cbm__ober_compile(cbm_context *ctx, const cbm_ober_def *d, ober_prog *p)
{
    memset(p, 0, sizeof *p);
    cbm__pp pp;
    memset(&pp, 0, sizeof pp);
    pp.ctx = ctx;
    int line_of[F_COUNT];
    cbm_status st = build_text(ctx, d, &pp, line_of);
    if (st == CBM_OK)
        st = cbm__compiler_init(&p->c, ctx, &pp);
    if (st != CBM_OK) {
        cbm__pp_free(&pp);
        return st;
    }
    p->have_c = true;
    /* the compiler keeps the text's line map; the text itself is read during parsing only */
    cbm__compiler *c = &p->c;
    const char *formals[NVARS];
    size_t flen[NVARS];
    for (size_t i = 0; i < NVARS; i++)
        formals[i] = VARS[i].name, flen[i] = strlen(VARS[i].name);
    c->formals = formals;
    c->formal_len = flen;
    c->nformals = (int)NVARS;
    c->dialect = CBM__CPFG | CBM__TREE;
    for (int f = 0; f < F_COUNT; f++) {
        p->root[f] = -1;
        if (line_of[f] < 0 || c->fatal)
            continue;
        size_t start = c->line_start.data[line_of[f]];
        c->pos = start;
        size_t nodes0 = c->nodes.len, globals0 = c->globals.len, errors0 = c->errors;
        int32_t r = cbm__parse_expr(c, false);
        if (r >= 0) {
            cbm__skip(c, false);
            if (c->text[c->pos] != '\n' && c->text[c->pos] != '\0')
                cbm__cerr(c, c->pos, "%s: unexpected '%c' after the formula",
                          cbm__ober_formula_name(f), c->text[c->pos]);
        }
        for (size_t g = globals0; g < c->globals.len; g++)
            cbm__cerr(c, (size_t)c->global_use.data[g],
                      "%s: unknown variable '%s' (a %s formula reads: %s)",
                      cbm__ober_formula_name(f), c->globals.data[g], level_name(level_of(f)),
                      level_of(f) == LVL_TREE
                          ? "age treeAge carbonTax baseLength carbonMean activeShoots sumLeaves "
                            "woodVolume trunkVolume height tree"
                      : level_of(f) == LVL_SHOOT
                          ? "the tree's and len length diameter radius nodeNumber order trend "
                            "volume carbon leaves"
                          : "the tree's, the mother shoot's and position sleep shortShoot "
                            "apical parentOrder parentTrend");
        /* the formals' indices become the variables' slots; a variable of a lower level is
         * an error */
        int lim = level_of(f) == LVL_TREE    ? V_TREE_LEVEL_END
                  : level_of(f) == LVL_SHOOT ? V_SHOOT_LEVEL_END
                                             : V_COUNT;
        for (size_t n = nodes0; n < c->nodes.len; n++) {
            cbm__node *nd = &c->nodes.data[n];
            if (nd->op != OP_PARAM)
                continue;
            const var_name *v = &VARS[nd->slot];
            nd->slot = v->slot;
            nd->op = OP_GLOBAL; /* read from vars (the evaluator's globals) */
            if (v->slot >= lim)
                cbm__cerr(c, word_at(c, start, v->name),
                          "%s: '%s' is a %s variable, not readable in a %s formula",
                          cbm__ober_formula_name(f), v->name,
                          v->slot >= V_SHOOT_LEVEL_END ? "bud" : "shoot", level_name(level_of(f)));
        }
        if (c->errors == errors0)
            p->root[f] = r;
    }
    c->formals = NULL;
    c->formal_len = NULL;
    c->nformals = 0;
    c->text = NULL;
    cbm_status out = c->status != CBM_OK ? c->status : c->errors ? CBM_E_SYNTAX : CBM_OK;
    cbm__pp_free(&pp);
    if (out != CBM_OK) {
        cbm__ober_prog_free(p);
        return out;
    }
    p->ev.ctx = ctx;
    p->ev.nodes = c->nodes.data;
    p->ev.strings = c->strings.data;
    p->ev.globals = p->vars;
    p->ev.error_node = -1;
    cbm__random_seed(&p->ev.rnd, (long long)(d->seed & 0x7fffffffffffLL));
    return CBM_OK;
}

double cbm__ober_eval(ober_prog *p, int f, cbm_status *st)
{
    int32_t r = p->root[f];
    if (r < 0)
        return 0.0;
    p->ev.error = CBM_OK;
    p->ev.error_node = -1;
    p->ev.while_budget = 1000000;
    double v = cbm__eval_expr(&p->ev, r);
    if (p->ev.error != CBM_OK || !isfinite(v)) {
        int32_t at = p->ev.error_node >= 0 ? p->ev.error_node : r;
        if (*st == CBM_OK)
            *st = cbm__compiler_fail(&p->c, CBM_E_RUNTIME, cbm__node_pos(&p->c, at), "%s: %s",
                                     cbm__ober_formula_name(f),
                                     p->ev.error != CBM_OK && p->ev.error_msg
                                         ? p->ev.error_msg
                                         : "the formula's value is not a finite number");
        return 0.0;
    }
    return v;
}
