/* A cpfg model run end to end: the L-system engine (src/lsys) joined with the view, the side
 * files and the turtle (src/turtle), as cpfg joins them.
 *
 * Algorithm. func(id, x) in expressions reads the view's function files
 * (cbm_view_func_callback). Environmental interpretation (cpfg's ProcessEnvironment): before a
 * derivation step whose string holds query modules, the engine computes the homomorphic image,
 * and the callback below runs the turtle over it module by module (cbm__turtle_feed joins cpfg's
 * one-character modules `@ M(...)`, `? P(...)`, `~ l(...)`) and writes the values the turtle put
 * in the query modules back into the image; the engine hands them to the string's query modules
 * in order. Steps whose string has no query module skip the pass (it could not change anything),
 * so plain models derive at the engine's speed; within the pass, a short branch that holds no
 * query and acts only on the turtle's state is passed over (pass_over_branch). cbm_model_interpret
 * runs the same protocol once with a turtle that draws into a scene and keeps the primitive record;
 * without a homomorphism it reads the string itself rather than a copy (half the memory on the
 * largest strings). L+C (lpfg) models: their modules are named, most without a cpfg symbol, so the
 * model maps each symbol once, by its name (cbm_lsys_module_name), to a turtle command with lpfg's
 * meaning (lpfg_map; docs/turtle.md "lpfg modules": lpfg's U is opposite to ours, so Up/Down and
 * RollL/RollR follow lpfg's "corrected rotation:"; Sphere takes a radius; SetColor ignores
 * colours outside 1..255), and the turtle runs in lpfg's mode (colour 1 at the start, each F its
 * own cylinder). func(name, x) calls the function set's function of that name, and functions are
 * tabulated with lpfg's tolerance. ABOP ch. 1 (turtle interpretation); Prusinkiewicz et al. 1994
 * "Synthetic topiary" (query modules); the lpfg manual (L+C turtle modules).
 */
#include "cambium/model.h"
#include "model_internal.h"

#include "core/core.h"
#include "lang/mechsegment.h"
#include "lsys/lsys.h"
#include "turtle/turtle.h"

#include <math.h>
#include <stdio.h>

struct cbm_model {
    cbm_context *ctx;
    cbm_lsys *ls;
    cbm_view *view;
    cbm_turtle *query_turtle; /* no scene, no record: the per-step pass */
    cbm_turtle *pass;         /* the turtle of the pass in progress */
    bool image;               /* the pass reads the homomorphic image (else the string) */
    bool may_query;           /* some successor or the axiom holds a '?' */
    bool lpfg;                /* L+C dialect: modules are mapped by name (lpfg_map) */
    bool no_pass_over;        /* the query pass interprets every branch (tests) */
    int16_t lmap[128];        /* L+C: the lpfg operation of each symbol (LP_*), 0: none */
};

/* lpfg's turtle modules (lpfg manual, "Turtle commands"; lpfg's turtle). Most are one turtle
 * command; the LP_* below need lpfg's own treatment of their parameter. */
enum {
    LP_CMD = 0,       /* lmap holds CBM_T_* + LP_CMD_BASE */
    LP_SET_COLOR = 1, /* SetColor(c): ignored outside 1..255 */
    LP_INC_COLOR,     /* IncColor: 255 wraps to 1 */
    LP_DEC_COLOR,     /* DecColor: 1 wraps to 255 */
    LP_SPHERE,        /* Sphere(r): radius r; Sphere0: diameter = width */
    LP_CIRCLE,        /* Circle(r), Circle0 */
    LP_CMD_BASE = 16
};

typedef struct lpfg_name {
    const char *name;
    int op; /* LP_* or CBM_T_* + LP_CMD_BASE */
} lpfg_name;

#define C(cmd) ((cmd) + LP_CMD_BASE)
static const lpfg_name LPFG_NAMES[] = {
    {"F", C(CBM_T_F)},
    {"f", C(CBM_T_f)},
    {"G", C(CBM_T_G)},
    {"g", C(CBM_T_g)},
    {"Left", C(CBM_T_LEFT)},
    {"Right", C(CBM_T_RIGHT)},
    {"TurnAround", C(CBM_T_TURN_AROUND)},
    {"SB", C(CBM_T_PUSH)},
    {"EB", C(CBM_T_POP)},
    {"SetWidth", C(CBM_T_WIDTH)},
    {"IncWidth", C(CBM_T_WIDTH_INC)},
    {"Cut", C(CBM_T_CUT)},
    {"SP", C(CBM_T_POLY_BEGIN)},
    {"EP", C(CBM_T_POLY_END)},
    {"PP", C(CBM_T_POLY_VERTEX)},
    {"StartGC", C(CBM_T_GC_START)},
    {"PointGC", C(CBM_T_GC_CONTROL)},
    {"EndGC", C(CBM_T_GC_END)},
    {"CurrentContour", C(CBM_T_CONTOUR_SET)},
    {"ContourSides", C(CBM_T_SIDES_SET)},
    {"SetHead", C(CBM_T_SET_HEAD)},
    {"RollToVert", C(CBM_T_ROLL_TO_VERT)},
    {"LineTo3d", C(CBM_T_LINE_TO)},
    {"LineRel3d", C(CBM_T_LINE_REL)},
    {"MoveTo3d", C(CBM_T_MOVE_TO)},
    {"MoveRel3d", C(CBM_T_MOVE_REL)},
    {"Elasticity", C(CBM_T_ELASTICITY)},
    {"ScaleContour", C(CBM_T_SCALE_CONTOUR)},
    {"SetColor", LP_SET_COLOR},
    {"IncColor", LP_INC_COLOR},
    {"DecColor", LP_DEC_COLOR},
    {"Sphere", LP_SPHERE},
    {"Sphere0", LP_SPHERE},
    {"Circle", LP_CIRCLE},
    {"Circle0", LP_CIRCLE},
};
#undef C

/* The lpfg operation of each symbol of an L+C model. Up/Down and RollL/RollR depend on the view's
 * "corrected rotation:" (on by default): lpfg's frame has U opposite to this turtle's (lpfg: L =
 * U x H), so with corrected rotation lpfg's Down and Up are cpfg's & and ^ and lpfg's RollL and
 * RollR are cpfg's / and \; without it, the reverse. */
static void lpfg_map(cbm_model *m)
{
    bool corrected = cbm__view_lpfg_corrected(m->view);
    for (int sym = 1; sym < 128; sym++) {
        const char *nm = cbm_lsys_module_name(m->ls, sym);
        m->lmap[sym] = 0;
        if (!nm)
            continue;
        int op = -1;
        if (!strcmp(nm, "Down"))
            op = corrected ? CBM_T_PITCH_DOWN : CBM_T_PITCH_UP;
        else if (!strcmp(nm, "Up"))
            op = corrected ? CBM_T_PITCH_UP : CBM_T_PITCH_DOWN;
        else if (!strcmp(nm, "RollL"))
            op = corrected ? CBM_T_ROLL_RIGHT : CBM_T_ROLL_LEFT;
        else if (!strcmp(nm, "RollR"))
            op = corrected ? CBM_T_ROLL_LEFT : CBM_T_ROLL_RIGHT;
        if (op >= 0) {
            m->lmap[sym] = (int16_t)(op + LP_CMD_BASE);
            continue;
        }
        for (size_t i = 0; i < sizeof LPFG_NAMES / sizeof LPFG_NAMES[0]; i++)
            if (!strcmp(nm, LPFG_NAMES[i].name)) {
                m->lmap[sym] = (int16_t)LPFG_NAMES[i].op;
                break;
            }
    }
}

/* One module of an L+C model through the turtle, with lpfg's meaning. */
static cbm_status lpfg_exec(cbm_turtle *t, int op, double *p, int n)
{
    if (op >= LP_CMD_BASE)
        return cbm__turtle_exec(t, op - LP_CMD_BASE, p, n);
    int color = 1;
    double x;
    switch (op) {
    case LP_SET_COLOR:
        if (n < 1 || !(p[0] >= 1.0 && p[0] < 256.0))
            return cbm__turtle_exec(t, CBM_T_NONE, NULL, 0); /* lpfg ignores it */
        x = (double)(int)p[0];
        return cbm__turtle_exec(t, CBM_T_COLOR_INC, &x, 1);
    case LP_INC_COLOR:
    case LP_DEC_COLOR:
        cbm_turtle_state(t, NULL, NULL, NULL, NULL, NULL, &color);
        if (op == LP_INC_COLOR)
            color = color >= 255 ? 1 : color + 1;
        else
            color = color <= 1 ? 255 : color - 1;
        x = color;
        return cbm__turtle_exec(t, CBM_T_COLOR_INC, &x, 1);
    case LP_SPHERE:
    case LP_CIRCLE: {
        int cmd = op == LP_SPHERE ? CBM_T_SPHERE : CBM_T_CIRCLE;
        if (n < 1)
            return cbm__turtle_exec(t, cmd, NULL, 0); /* diameter: the width */
        x = 2.0 * p[0];
        return cbm__turtle_exec(t, cmd, &x, 1);
    }
    default:
        return cbm__turtle_exec(t, CBM_T_NONE, NULL, 0);
    }
}

/* The read-ahead of the query pass at a `[`, in modules at most: a branch longer than that is
 * interpreted, so that the read-ahead of a branch that must be interpreted after all (one that
 * holds a query) stays a bounded part of the pass. */
#define PASS_OVER_MODULES 32

/* The per-step query pass at a `[` (c has just read it): when the branch it opens holds no
 * query and only modules that act on nothing but the turtle's state, which its `]` restores
 * (cbm__turtle_branch_local, cbm__turtle_may_pass_over), no query of the pass depends on it:
 * the turtle is told (cbm__turtle_pass_over) and c moves past the `]`. ahead is the cursor of
 * the read-ahead (positioned here, its buffer not copied). False, c unmoved, when the branch
 * is to be interpreted. */
static bool pass_over_branch(cbm_model *m, cbm_lsys_cursor *c, cbm_lsys_cursor *ahead,
                             cbm_status *st)
{
    if (m->pass != m->query_turtle || m->lpfg || m->no_pass_over ||
        !cbm__turtle_may_pass_over(m->pass))
        return false;
    ahead->module = c->module;
    ahead->pmodule = c->pmodule;
    ahead->param = c->param;
    ahead->homomorphism = c->homomorphism;
    int depth = 1;
    int64_t modules = 1; /* the `[`; a `@` and its command are one module of the turtle */
    bool after_at = false;
    for (int k = 0; k < PASS_OVER_MODULES && cbm_lsys_cursor_next(m->ls, m->image, ahead); k++) {
        int sym = ahead->symbol;
        for (int i = 0; i < ahead->nparams; i++)
            if (!isfinite(ahead->params[i]))
                return false; /* the turtle reports it */
        if (after_at) {
            if (!cbm__turtle_branch_local(sym, true))
                return false;
            after_at = false;
            continue;
        }
        if (sym == '@' && ahead->nparams == 0) {
            after_at = true;
            modules++;
            continue;
        }
        if (!cbm__turtle_branch_local(sym, false))
            return false;
        modules++;
        if (sym == '[')
            depth++;
        else if (sym == ']' && --depth == 0) {
            c->module = ahead->module;
            c->pmodule = ahead->pmodule;
            c->param = ahead->param;
            c->symbol = ']';
            c->nparams = 0;
            c->params = NULL;
            *st = cbm__turtle_pass_over(m->pass, modules);
            return true;
        }
    }
    return false;
}

/* The turtle over the homomorphic image; query values written back into the image. */
static cbm_status interpret_cb(void *ud, cbm_lsys *ls)
{
    cbm_model *m = ud;
    cbm_turtle *t = m->pass;
    cbm__turtle_reset(t);
    cbm_lsys_cursor c, ahead;
    cbm_lsys_cursor_begin(ls, m->image, &c);
    cbm_lsys_cursor_begin(ls, m->image, &ahead);
    double buf[256];
    bool after_query = false;
    cbm_status s = CBM_OK;
    while (s == CBM_OK && cbm_lsys_cursor_next(ls, m->image, &c)) {
        int n = c.nparams;
        if (n > 0)
            memcpy(buf, c.params, (size_t)n * sizeof(double));
        if (m->lpfg) {
            int op = c.symbol > 0 && c.symbol < 128 ? m->lmap[c.symbol] : 0;
            s = lpfg_exec(t, op, buf, n);
            continue;
        }
        if (c.symbol == '[' && n == 0 && pass_over_branch(m, &c, &ahead, &s)) {
            after_query = false;
            continue;
        }
        s = cbm__turtle_feed(t, c.symbol, buf, n);
        if (s == CBM_OK && after_query && n > 0 &&
            (c.symbol == 'P' || c.symbol == 'H' || c.symbol == 'L' || c.symbol == 'U' ||
             c.symbol == 'Q'))
            for (int i = 0; i < n && s == CBM_OK; i++)
                s = cbm_lsys_cursor_set_param(ls, &c, i, buf[i]);
        after_query = c.symbol == '?' && n == 0;
    }
    if (s == CBM_OK)
        s = cbm__turtle_finish(t);
    return s;
}

/* L+C: func(name, x) calls the function set's function of that name (its "name:" line). */
static cbm_status set_func_ids(cbm_model *m)
{
    const char *const *names = NULL;
    size_t n = cbm_lsys_func_names(m->ls, &names);
    if (n == 0)
        return CBM_OK;
    int *ids = cbm__alloc(m->ctx, n * sizeof *ids);
    if (!ids)
        return CBM_E_NOMEM;
    cbm_status s = CBM_OK;
    for (size_t i = 0; i < n && s == CBM_OK; i++) {
        ids[i] = cbm_funcset_find(cbm_view_functions(m->view), names[i]);
        if (ids[i] <= 0)
            s = cbm__fail(m->ctx, CBM_E_NOT_FOUND,
                          "func(%s, x): no function named \"%s\" in the function files", names[i],
                          names[i]);
    }
    if (s == CBM_OK)
        s = cbm_lsys_set_func_ids(m->ls, ids, n);
    cbm__free(m->ctx, ids, n * sizeof *ids);
    return s;
}

cbm_model_def cbm_model_def_default(void)
{
    cbm_model_def d;
    memset(&d, 0, sizeof d);
    d.lsys = cbm_lsys_def_default();
    return d;
}

cbm_status cbm_model_load(cbm_context *ctx, const cbm_model_def *def, cbm_model **out)
{
    if (!ctx || !def || !out || (def->side_count && !def->side_files))
        return CBM_E_INVALID;
    *out = NULL;
    cbm_model *m = cbm__calloc(ctx, 1, sizeof *m);
    if (!m)
        return CBM_E_NOMEM;
    m->ctx = ctx;
    cbm_status s = cbm_view_create(ctx, &m->view);
    for (size_t i = 0; i < def->side_count && s == CBM_OK; i++) {
        s = cbm_view_load_side_file(m->view, def->side_files[i]);
        if (s != CBM_OK && !strstr(cbm_context_last_error(ctx), def->side_files[i])) {
            char msg[512];
            snprintf(msg, sizeof msg, "%s", cbm_context_last_error(ctx));
            s = cbm__fail(ctx, s, "%s: %s", def->side_files[i], msg);
        }
    }
    if (s == CBM_OK)
        s = cbm_lsys_load(ctx, &def->lsys, &m->ls);
    if (s == CBM_OK)
        s = cbm__turtle_create(ctx, m->view, NULL, &m->query_turtle);
    if (s != CBM_OK) {
        cbm_model_destroy(m);
        return s;
    }
    m->may_query = cbm__lsys_may_query(m->ls);
    /* without function files func() stays an error naming what is missing */
    if (cbm_funcset_count(cbm_view_functions(m->view)) > 0) {
        cbm_lsys_set_func(m->ls, cbm_view_func_callback, m->view);
        s = set_func_ids(m);
        if (s != CBM_OK) {
            cbm_model_destroy(m);
            return s;
        }
    }
    m->lpfg = cbm_lsys_module_name(m->ls, '[') != NULL;
    if (m->lpfg) {
        m->may_query = false; /* cpfg's ?P ?H ?L ?U: a user module may have the code '?' */
        cbm__view_lpfg_functions(m->view);
        lpfg_map(m);
        cbm__turtle_set_lpfg(m->query_turtle, true);
    }
    *out = m;
    return CBM_OK;
}

void cbm__model_set_pass_over(cbm_model *m, bool on)
{
    m->no_pass_over = !on;
}

void cbm_model_destroy(cbm_model *m)
{
    if (!m)
        return;
    cbm__turtle_destroy(m->query_turtle);
    cbm_lsys_destroy(m->ls);
    cbm_view_destroy(m->view);
    cbm__free(m->ctx, m, sizeof *m);
}

cbm_lsys *cbm_model_lsys(cbm_model *m)
{
    return m ? m->ls : NULL;
}

const cbm_view *cbm_model_view(const cbm_model *m)
{
    return m ? m->view : NULL;
}

cbm_status cbm_model_reset(cbm_model *m)
{
    if (!m)
        return CBM_E_INVALID;
    cbm_lsys_set_interpreter(m->ls, NULL, NULL);
    return cbm_lsys_reset(m->ls);
}

/* A query module: '?' without parameters followed by P, H, L or U. A scan of the packed symbol
 * bytes (memchr), skipped for models none of whose successors or axiom holds a '?'. */
bool cbm_model_has_queries(const cbm_model *m)
{
    if (!m || !m->may_query)
        return false;
    size_t n = 0;
    const uint8_t *p = cbm__lsys_symbols(m->ls, &n), *end = p + n;
    while (p < end && (p = memchr(p, '?', (size_t)(end - p))) != NULL) {
        p++;
        int next = p < end ? (*p & 0x7f) : 0;
        if (next == 'P' || next == 'H' || next == 'L' || next == 'U' || next == 'Q')
            return true;
    }
    return false;
}

cbm_status cbm_model_step(cbm_model *m)
{
    if (!m)
        return CBM_E_INVALID;
    m->pass = m->query_turtle;
    m->image = true;
    cbm__turtle_set_record(m->pass, false);
    cbm_lsys_set_interpreter(m->ls, cbm_model_has_queries(m) ? interpret_cb : NULL, m);
    cbm_status s = cbm_lsys_step(m->ls);
    cbm_lsys_set_interpreter(m->ls, NULL, NULL);
    return s;
}

/* L+C models with mechanics: the parts drawn from a mechanical segment's module (by its
 * interpretation rule) carry that segment's stress, stress ratio and age, so pictures and meshes
 * can be coloured by them. A part's `segment` is the index of the module that drew it. */
static cbm_status mech_parts(cbm_model *m, cbm_scene *scene, size_t first)
{
    const double **seg = NULL;
    size_t n = 0;
    CBM_TRY(cbm__lpfg_mech_fields(m->ls, m->image, &seg, &n));
    if (!seg)
        return CBM_OK;
    size_t np = cbm_scene_part_count(scene);
    for (size_t i = first; i < np; i++) {
        cbm_part *p = cbm_scene_part(scene, (uint32_t)i);
        if (!p || p->segment < 0 || (size_t)p->segment >= n || !seg[p->segment])
            continue;
        const double *g = seg[p->segment];
        p->stress = g[MS_STRESS];
        p->stress_ratio = g[MS_MOR] > 0 ? g[MS_RATIO] : NAN; /* no modulus of rupture: no ratio */
        p->age = g[MS_AGE] >= 0 ? g[MS_AGE] : 0;
    }
    cbm__free(m->ctx, (void *)seg, (n ? n : 1) * sizeof *seg);
    return CBM_OK;
}

cbm_status cbm_model_interpret(cbm_model *m, cbm_scene *scene, bool record, cbm_turtle **turtle)
{
    if (turtle)
        *turtle = NULL;
    if (!m)
        return CBM_E_INVALID;
    cbm_turtle *t = NULL;
    size_t first_part = scene ? cbm_scene_part_count(scene) : 0;
    CBM_TRY(cbm__turtle_create(m->ctx, m->view, scene, &t));
    cbm__turtle_set_record(t, record);
    cbm__turtle_set_lpfg(t, m->lpfg);
    m->pass = t;
    cbm_status s;
    if (cbm_lsys_has_homomorphism(m->ls)) {
        m->image = true;
        cbm_lsys_set_interpreter(m->ls, interpret_cb, m);
        s = cbm_lsys_interpret(m->ls);
        cbm_lsys_set_interpreter(m->ls, NULL, NULL);
    } else {
        /* the image would be a copy of the string: read and fill the string itself */
        m->image = false;
        s = interpret_cb(m, m->ls);
    }
    m->pass = m->query_turtle;
    if (s == CBM_OK && scene && m->lpfg)
        s = mech_parts(m, scene, first_part);
    if (s != CBM_OK || !turtle)
        cbm__turtle_destroy(t);
    else
        *turtle = t;
    return s;
}

void cbm_model_describe(const cbm_model *m, cbm_model_summary *out)
{
    memset(out, 0, sizeof *out);
    if (!m)
        return;
    cbm__lsys_describe(m->ls, out);
    out->functions = cbm_funcset_count(cbm_view_functions(m->view));
}
