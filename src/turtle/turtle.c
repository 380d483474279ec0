/* The turtle: interprets the modules of a cpfg/ABOP string into geometry.
 *
 * State (ABOP ch. 1.5, cpfg manual "Turtle interpretation"): position P and frame H, L, U, line
 * width, colour index, elasticities, contour; `[` and `]` push and pop it. The frame follows
 * cpfg's convention: initially H = +y, L = -x, U = -z, so that L = H x U. Rotations are those of
 * ABOP section 1.5 (R_U, R_L, R_H) applied as cpfg does, e.g. turn (+):
 * H' = H cos a + L sin a, L' = L cos a - H sin a; the sine and cosine of the view's angle
 * increment are precomputed. Tropism (ABOP section 2.2, where the heading bends by
 * alpha = e |H x T|) comes in two forms, as in cpfg: the ABOP one
 * ("tropism direction", elasticity changed by `_`), applied after each move by two rotations
 * towards T (in the H-U and H-L planes, sin(alpha) = e T.U and e T.L), and cpfg's movements
 * ("tropism: T: A: E:"), applied before each move by rotating H about H x V by min(|H x V|, 1)
 * rad, where V sums e_i (cos(g_i) T_i + sin(g_i) T_i x (H x T_i) / |H x T_i|); U is then carried
 * along by the minimal rotation from the previous heading.
 *
 * Segments are emitted as cpfg does: a segment starts at F/G and ends at the next "node end"
 * (the next F f G g [ ] { } ~ @ or the end of the string), with the width at the start and at the
 * end (a cone when they differ) and the colour at the start; degenerate segments (length^2 <=
 * 1e-5, or zero width) are dropped. Polygons collect the positions of `.`, F and f between `{`
 * and `}` (nested polygons allowed). `%` cuts the rest of the branch. Generalized cylinders
 * (@Gs @Gc(n) @Ge(n)) join the turtle states at their control points with cubic Hermite
 * curves whose tangents are the headings scaled by the chord and by the tangent parameters
 * (1.2 by default, as cpfg), n bands each; the rings are contours resampled by arc length,
 * carried along by the minimal rotation of U (cpfg's generalized cylinders, cpfg manual
 * "Generalized cylinders"). cpfg's spline cylinders {(n[,r]) ... }(n) (cpfg's InitializeSpline,
 * SetControlPoint, FinishSpline) take their control points at F, f and `.`: n = 1, 2 join them
 * with the same Hermite pieces (2 closes back to the first point), n = 3, 4 with the pieces of a
 * uniform cubic B-spline between the knots (P0 + 4 P1 + P2) / 6 (4 closes by feeding the first
 * three points again).
 * lpfg's mode (L+C models, cbm__turtle_set_lpfg): colour 1 at the start, each F drawn at once as
 * a cylinder of the current width, and lpfg's commands SetHead, RollToVert, LineTo3d/LineRel3d
 * (a segment towards a point, the frame kept), MoveRel3d and ScaleContour (an elliptic section);
 * lpfg's frame has U opposite to ours (its L = U x H), which these commands account for.
 * The turtle's scale (cpfg's turtle scale factor: the view's "initial scale:", set by @D, @Di,
 * @Dd) multiplies the lengths of F f G g, the widths that ! and # set or step, the sizes of @O
 * @o @c given as parameters and of surfaces. A sub-L-system `?(id, s) ... $` (cpfg manual 7.2)
 * multiplies it by s on a stack of its own and returns to the caller's scale at `$`, the current
 * width following the ratio of the two scales (cpfg's UpdateCurrentLsystem).
 * The record links each segment (cylinder, generalized-cylinder piece) to its parent, the last
 * segment recorded on its branch path (kept in the state that `[` and `]` push and pop), and marks
 * it lateral when a `[` was opened since that parent (the mechanics' rule, docs/language.md).
 * Each segment, polygon, sphere, disc, surface and generalized cylinder is one part of the scene.
 * When the scene is in line mode, cpfg's pixel-style segments (not lpfg's) become lines of the
 * start width in pixels (cpfg's pixel lines) and consecutive lines with equal part data share one
 * part. Interpretation is linear in the number of modules, with no allocation per module beyond the
 * amortised growth of the output arrays and the branch stack.
 */
#include "tint.h"

#include "../core/vecmath.h"

#include <stdio.h>

/* A control point of a generalized cylinder: the turtle state that matters there. */
typedef struct gcpt {
    cbm_vec3 pos, h, l, u;
    double width;
    double tan[2];     /* tangent parameters (cpfg: leaving, arriving) */
    double rtan[2][2]; /* radius tangents (dt, dr) at the start and the end; 0: linear */
    bool rtan_scale;   /* scale the radius tangents by the segment length */
    int contour;       /* 0: circle; k: the view's contour k-1 */
    int sides;
} gcpt;

/* bands per connection of a generalized cylinder at most (cpfg has no bound) */
#define MAX_RINGS 10000

/* An open spline cylinder {(n) (cpfg's SPLINE and its control points). */
typedef struct spline {
    bool closed, bspline;
    int rings;     /* default bands per connection */
    int num;       /* control points so far */
    int nfirst;    /* closed: first control points kept (at most 1 Hermite, 3 B-spline) */
    gcpt tu;       /* the last ring's state: where the next band starts */
    gcpt win[3];   /* B-spline: the last three control points */
    gcpt first[3]; /* closed: the first control points, fed again at }(n) */
} spline;

typedef struct tstate {
    cbm_vec3 pos, h, l, u;
    cbm_vec3 prev_h, prev_u;
    double width;
    double width_up; /* lpfg's ScaleContour: the section's width along U (= width otherwise) */
    double scale;    /* cpfg's turtle scale */
    double elasticity;
    double mov_e[CBM__MAX_MOVEMENTS];
    int color;
    int contour;
    int sides;
    double tan[2];     /* @Gt tangent parameters */
    double rtan[2][2]; /* @Gr radius tangents */
    bool rtan_scale;
    bool gc_on; /* a generalized cylinder is open; gc is its last control point */
    gcpt gc;
    int spl;           /* the open spline cylinder {(n): index in splines, or -1 */
    int spl_mark;      /* in a saved state: splines.len when the branch started */
    int64_t seg_last;  /* the record's last segment on this branch path, -1: none */
    bool seg_branched; /* a `[` opened since seg_last */
} tstate;

typedef struct ccache {
    int contour, sides;
    size_t off; /* 3 * (sides + 1) floats in cpts */
} ccache;

struct cbm_turtle {
    cbm_context *ctx;
    const cbm_view *view;
    cbm_scene *scene;
    bool record;
    bool lpfg; /* lpfg's turtle: initial colour 1, each F its own cylinder */
    tstate cur;
    CBM_ARRAY(tstate) stack;
    CBM_ARRAY(double) subscale; /* scales of the open sub-L-systems ?(id, s) ... $ */
    /* the open segment */
    bool node_open;
    cbm_vec3 node_p, node_h, node_u;
    double node_w;
    double node_wup; /* lpfg: the width along U at the start */
    int node_color;
    /* polygons */
    CBM_ARRAY(cbm_vec3) polypts;
    CBM_ARRAY(int) polycolor; /* colour index at each vertex (cpfg colours by the first) */
    CBM_ARRAY(size_t) polystart;
    CBM_ARRAY(spline) splines; /* spline cylinders, a stack following the branches */
    /* % */
    int cut_depth; /* > 0 while skipping: bracket depth inside the cut part */
    /* generalized cylinders */
    CBM_ARRAY(ccache) ccache; /* contours resampled for a number of sides */
    CBM_ARRAY(double) cpts;
    CBM_ARRAY(cbm_vec3) ringv; /* ring vertices of one connection */
    CBM_ARRAY(cbm_vec3) ringn; /* their normals */
    CBM_ARRAY(uint32_t) ringt;
    char prefix[3]; /* cbm__turtle_feed: '@', '?', '~' or "@T"... waiting for their module */
    int nprefix;
    /* record */
    CBM_ARRAY(cbm_prim) prims;
    CBM_ARRAY(cbm_vec3) pts;
    bool box_set;
    cbm_vec3 lo, hi;
    CBM_ARRAY(cbm_vec3) scratch;
    int64_t module_index; /* modules fed so far (the one executing is module_index - 1) */
    int64_t node_module;  /* the module that opened the segment in progress */
    double turn_deg, turn_sin, turn_cos; /* the last explicit turn angle and its sine, cosine */
    int64_t part_module;                 /* >= 0: the module a part being emitted belongs to */
    size_t pixel_segments;               /* segments drawn in cpfg's pixel style */
};

/* ---- lookup ---- */

typedef struct tname {
    const char *name;
    int cmd;
} tname;

static const tname names[] = {
    {"F", CBM_T_F},
    {"f", CBM_T_f},
    {"G", CBM_T_G},
    {"g", CBM_T_g},
    {"+", CBM_T_LEFT},
    {"-", CBM_T_RIGHT},
    {"&", CBM_T_PITCH_DOWN},
    {"^", CBM_T_PITCH_UP},
    {"\\", CBM_T_ROLL_LEFT},
    {"/", CBM_T_ROLL_RIGHT},
    {"|", CBM_T_TURN_AROUND},
    {"[", CBM_T_PUSH},
    {"]", CBM_T_POP},
    {"!", CBM_T_WIDTH},
    {"'", CBM_T_COLOR_INC},
    {";", CBM_T_COLOR_INC},
    {",", CBM_T_COLOR_DEC},
    {"#", CBM_T_WIDTH_INC},
    {"~", CBM_T_SURFACE},
    {"%", CBM_T_CUT},
    {"{", CBM_T_POLY_BEGIN},
    {"}", CBM_T_POLY_END},
    {".", CBM_T_POLY_VERTEX},
    {"_", CBM_T_ELASTICITY},
    {"@v", CBM_T_ROLL_HORIZ},
    {"@O", CBM_T_SPHERE},
    {"@o", CBM_T_CIRCLE},
    {"@c", CBM_T_CONTOUR},
    {"@M", CBM_T_MOVE_TO},
    {"@Ts", CBM_T_TROPISM_SET},
    {"@Ti", CBM_T_TROPISM_INC},
    {"@Td", CBM_T_TROPISM_DEC},
    {"@Gs", CBM_T_GC_START},
    {"@Gc", CBM_T_GC_CONTROL},
    {"@Ge", CBM_T_GC_END},
    {"@Gt", CBM_T_GC_TANGENT},
    {"@Gr", CBM_T_GC_RADIUS},
    {"@Tp", CBM_T_TWIST_ADJUST},
    {"@Tf", CBM_T_TWIST_KEEP},
    {"@#", CBM_T_CONTOUR_SET},
    {"@!", CBM_T_SIDES_SET},
    {"@D", CBM_T_SCALE_SET},
    {"@Di", CBM_T_SCALE_MUL},
    {"@Dd", CBM_T_SCALE_DIV},
    {"?P", CBM_T_QUERY_P},
    {"?H", CBM_T_QUERY_H},
    {"?L", CBM_T_QUERY_L},
    {"?U", CBM_T_QUERY_U},
    {"?Q", CBM_T_QUERY_Q},
};

/* One-character commands, by character (the common case, looked up per module by
 * cbm__turtle_feed). */
static const unsigned char single[128] = {
    ['F'] = CBM_T_F,          ['f'] = CBM_T_f,           ['G'] = CBM_T_G,
    ['g'] = CBM_T_g,          ['+'] = CBM_T_LEFT,        ['-'] = CBM_T_RIGHT,
    ['&'] = CBM_T_PITCH_DOWN, ['^'] = CBM_T_PITCH_UP,    ['\\'] = CBM_T_ROLL_LEFT,
    ['/'] = CBM_T_ROLL_RIGHT, ['|'] = CBM_T_TURN_AROUND, ['['] = CBM_T_PUSH,
    [']'] = CBM_T_POP,        ['!'] = CBM_T_WIDTH,       ['\''] = CBM_T_COLOR_INC,
    [';'] = CBM_T_COLOR_INC,  [','] = CBM_T_COLOR_DEC,   ['#'] = CBM_T_WIDTH_INC,
    ['~'] = CBM_T_SURFACE,    ['%'] = CBM_T_CUT,         ['{'] = CBM_T_POLY_BEGIN,
    ['}'] = CBM_T_POLY_END,   ['.'] = CBM_T_POLY_VERTEX,
};

int cbm__turtle_lookup(const char *name, size_t len)
{
    if (len == 1) {
        unsigned char c = (unsigned char)name[0];
        if (c == '_')
            return CBM_T_ELASTICITY;
        return c < 128 ? single[c] : CBM_T_NONE;
    }
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (strlen(names[i].name) == len && memcmp(names[i].name, name, len) == 0)
            return names[i].cmd;
    return CBM_T_NONE;
}

/* ---- creation ---- */

static void init_state(cbm_turtle *t)
{
    const cbm_view *v = t->view;
    tstate *s = &t->cur;
    memset(s, 0, sizeof *s);
    s->pos = v3(0, 0, 0);
    s->h = v3(0, 1, 0);
    s->l = v3(-1, 0, 0);
    s->u = v3(0, 0, -1);
    s->prev_h = s->h;
    s->prev_u = s->u;
    s->width = v->width;
    s->width_up = v->width;
    s->scale = v->init_scale;
    s->elasticity = v->elasticity;
    for (int i = 0; i < v->nmov; i++)
        s->mov_e[i] = v->mov[i].elasticity;
    s->color = v->color;
    s->contour = 0;
    s->sides = v->sides;
    s->tan[0] = s->tan[1] = 1.2; /* cpfg's default tangent parameter */
    s->spl = -1;
    s->seg_last = -1;
}

cbm_status cbm__turtle_create(cbm_context *ctx, const cbm_view *view, cbm_scene *scene,
                              cbm_turtle **out)
{
    if (!ctx || !view || !out)
        return CBM_E_INVALID;
    *out = NULL;
    cbm_turtle *t = cbm__calloc(ctx, 1, sizeof *t);
    if (!t)
        return CBM_E_NOMEM;
    t->ctx = ctx;
    t->view = view;
    t->scene = scene;
    cbm__turtle_reset(t);
    *out = t;
    return CBM_OK;
}

void cbm__turtle_set_record(cbm_turtle *t, bool record)
{
    t->record = record;
}

void cbm__turtle_destroy(cbm_turtle *t)
{
    if (!t)
        return;
    cbm_context *ctx = t->ctx;
    CBM_ARRAY_FREE(ctx, t->stack);
    CBM_ARRAY_FREE(ctx, t->subscale);
    CBM_ARRAY_FREE(ctx, t->polypts);
    CBM_ARRAY_FREE(ctx, t->polycolor);
    CBM_ARRAY_FREE(ctx, t->polystart);
    CBM_ARRAY_FREE(ctx, t->splines);
    CBM_ARRAY_FREE(ctx, t->ccache);
    CBM_ARRAY_FREE(ctx, t->cpts);
    CBM_ARRAY_FREE(ctx, t->ringv);
    CBM_ARRAY_FREE(ctx, t->ringn);
    CBM_ARRAY_FREE(ctx, t->ringt);
    CBM_ARRAY_FREE(ctx, t->prims);
    CBM_ARRAY_FREE(ctx, t->pts);
    CBM_ARRAY_FREE(ctx, t->scratch);
    cbm__free(ctx, t, sizeof *t);
}

void cbm__turtle_set_lpfg(cbm_turtle *t, bool lpfg)
{
    t->lpfg = lpfg;
}

void cbm__turtle_reset(cbm_turtle *t)
{
    init_state(t);
    if (t->lpfg)
        t->cur.color = 1;
    t->stack.len = 0;
    t->subscale.len = 0;
    t->node_open = false;
    t->polypts.len = 0;
    t->polycolor.len = 0;
    t->polystart.len = 0;
    t->splines.len = 0;
    t->cut_depth = 0;
    t->nprefix = 0;
    t->prims.len = 0;
    t->pts.len = 0;
    t->box_set = false;
    t->pixel_segments = 0;
    t->module_index = 0;
    t->node_module = -1;
    t->part_module = -1;
    t->turn_deg = 0.0;
    t->turn_sin = 0.0;
    t->turn_cos = 1.0;
}

/* ---- helpers ---- */

static void box_add(cbm_turtle *t, cbm_vec3 p)
{
    if (!t->box_set) {
        t->lo = t->hi = p;
        t->box_set = true;
        return;
    }
    if (p.x < t->lo.x)
        t->lo.x = p.x;
    if (p.y < t->lo.y)
        t->lo.y = p.y;
    if (p.z < t->lo.z)
        t->lo.z = p.z;
    if (p.x > t->hi.x)
        t->hi.x = p.x;
    if (p.y > t->hi.y)
        t->hi.y = p.y;
    if (p.z > t->hi.z)
        t->hi.z = p.z;
}

static cbm_part make_part(const cbm_turtle *t, cbm_organ organ, int color)
{
    cbm_part p = cbm_part_default();
    p.organ = organ;
    p.order = (int32_t)t->stack.len;
    p.segment = t->part_module >= 0 ? t->part_module : t->module_index - 1;
    p.material = color;
    int c = color & 255;
    for (int i = 0; i < 4; i++)
        p.color[i] = t->view->colors[c][i];
    return p;
}

/* Whether the part make_part(t, CBM_ORGAN_BRANCH, color) would build equals `last` but for its
 * segment and parent ids (then a line joins `last`). */
static bool line_part_reused(const cbm_turtle *t, const cbm_part *last, int color)
{
    return last->organ == CBM_ORGAN_BRANCH && last->order == (int32_t)t->stack.len &&
           last->material == color &&
           /* the same colour, bit for bit (identity, not value) */
           // NOLINTNEXTLINE(bugprone-suspicious-memory-comparison,cert-exp42-c,cert-flp37-c)
           memcmp(last->color, t->view->colors[color & 255], sizeof last->color) == 0 &&
           isnan(last->stress_ratio) && isnan(last->stress) && isnan(last->age) &&
           isnan(last->reaction_wood);
}

/* Records a primitive with its module; a segment (cylinder, generalized-cylinder piece) also
 * gets its parent, the last segment recorded on the branch path, and becomes that last segment. */
static cbm_status push_prim(cbm_turtle *t, cbm_prim *p)
{
    if (!t->record)
        return CBM_OK;
    p->module = t->part_module >= 0 ? t->part_module : t->module_index - 1;
    p->parent = -1;
    p->lateral = false;
    bool seg = p->kind == CBM_PRIM_CYLINDER || p->kind == CBM_PRIM_GCYL;
    if (seg) {
        p->parent = t->cur.seg_last;
        p->lateral = p->parent >= 0 && t->cur.seg_branched;
    }
    CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->prims, *p));
    if (seg) {
        t->cur.seg_last = (int64_t)t->prims.len - 1;
        t->cur.seg_branched = false;
    }
    return CBM_OK;
}

/* A right-handed section frame with H along d, U as close as possible to up. */
static cbm_frame section_frame(cbm_vec3 d, cbm_vec3 up)
{
    cbm_frame f;
    f.h = d;
    cbm_vec3 u = v3_madd(up, d, -v3_dot(up, d));
    if (v3_norm2(u) < 1e-24) {
        cbm_vec3 a = fabs(d.x) < 0.9 ? v3(1, 0, 0) : v3(0, 1, 0);
        u = v3_madd(a, d, -v3_dot(a, d));
    }
    f.u = v3_normalize(u);
    f.l = v3_cross(f.u, f.h); /* H x L = U */
    return f;
}

/* cpfg's "change_dir": v2' = c v2 + s v3, v3' = c v3 - s v2 */
/* Sine and cosine of a turn: the module's angle in degrees, or the view's angle increment
 * (precomputed) when the module has no parameter. The last explicit angle's pair is kept: most
 * strings turn by a few angles, and sin/cos were the largest cost of a pass over them. */
static void turn_angle(cbm_turtle *t, const double *params, int nparams, double *sn, double *cs)
{
    const cbm_view *v = t->view;
    if (nparams > 0) {
        if (params[0] != t->turn_deg) { /* NaN never matches: recomputed, as before */
            double a = params[0] * CBM_PI / 180.0;
            t->turn_deg = params[0];
            t->turn_sin = sin(a);
            t->turn_cos = cos(a);
        }
        *sn = t->turn_sin;
        *cs = t->turn_cos;
    } else {
        *sn = v->sin_a;
        *cs = v->cos_a;
    }
}

static inline void rotate_pair(cbm_vec3 *v2, cbm_vec3 *v3p, double s, double c)
{
    cbm_vec3 a = *v2, b = *v3p;
    *v2 = v3(c * a.x + s * b.x, c * a.y + s * b.y, c * a.z + s * b.z);
    *v3p = v3(c * b.x - s * a.x, c * b.y - s * a.y, c * b.z - s * a.z);
}

/* ---- segments ---- */

/* A segment in cpfg's terms: dropped when degenerate (length^2 <= 1e-5 or no end width). */
static cbm_status emit_segment_e(cbm_turtle *t, cbm_vec3 p0, cbm_vec3 p1, double w0, double w1,
                                 double wu, int color, cbm_vec3 h, cbm_vec3 u);

static cbm_status emit_segment(cbm_turtle *t, cbm_vec3 p0, cbm_vec3 p1, double w0, double w1,
                               int color, cbm_vec3 h, cbm_vec3 u)
{
    return emit_segment_e(t, p0, p1, w0, w1, -1.0, color, h, u);
}

/* The line style segments are drawn in. lpfg's default is pixel, as cpfg's: SetWidth(w) then
 * gives lines w pixels wide in pictures (tubes of diameter w in meshes, as lpfg's and cpfg's
 * OBJ export). An L+C model run without a view file (cambium's own models in models/, written
 * in metres) is drawn with cylinders, as if its view said "line style: cylinder". */
static cbm__line_style line_style(const cbm_turtle *t)
{
    if (t->lpfg && !t->view->view_file)
        return CBM__LS_CYLINDER;
    return t->view->line_style;
}

/* A segment; wu >= 0: an elliptic section of width w0 along L and wu along U (lpfg's
 * ScaleContour; the record keeps w0 / 2). */
static cbm_status emit_segment_e(cbm_turtle *t, cbm_vec3 p0, cbm_vec3 p1, double w0, double w1,
                                 double wu, int color, cbm_vec3 h, cbm_vec3 u)
{
    cbm_vec3 d = v3_sub(p1, p0);
    if (v3_norm2(d) <= 0.00001 || w1 <= 0.0 || (!t->record && !t->scene))
        return CBM_OK;
    cbm_prim pr;
    memset(&pr, 0, sizeof pr);
    pr.r0 = w0 / 2.0;
    pr.r1 = w1 / 2.0;
    if (t->record) {
        pr.kind = CBM_PRIM_CYLINDER;
        pr.color = color;
        pr.p0 = p0;
        pr.p1 = p1;
        pr.frame.h = h;
        pr.frame.u = u;
        pr.frame.l = v3_cross(h, u);
        CBM_TRY(push_prim(t, &pr));
    }
    if (!t->scene)
        return CBM_OK;
    cbm__line_style style = line_style(t);
    bool pixel = style == CBM__LS_PIXEL;
    t->pixel_segments += pixel;
    if (pixel && cbm_scene_line_mode(t->scene)) {
        /* a line w0 pixels wide, as cpfg draws pixel lines; a run of segments with the same
         * part data shares one part (the first segment's id), so a line costs 32 bytes */
        size_t np = cbm_scene_part_count(t->scene);
        const cbm_part *last = np ? &cbm_scene_parts(t->scene)[np - 1] : NULL;
        if (!last || !line_part_reused(t, last, color)) {
            cbm_part part = make_part(t, CBM_ORGAN_BRANCH, color);
            CBM_TRY(cbm_scene_begin_part(t->scene, &part, NULL));
        }
        return cbm_scene_add_line(t->scene, p0, p1, w0 > 0.0 ? w0 : w1);
    }
    cbm_part part = make_part(t, CBM_ORGAN_BRANCH, color);
    CBM_TRY(cbm_scene_begin_part(t->scene, &part, NULL));
    cbm_vec3 dir = v3_normalize(d);
    cbm_frame f = section_frame(dir, u);
    if (style == CBM__LS_POLYGON) {
        /* a flat ribbon in the H-L plane, as cpfg's polygon lines */
        cbm_vec3 q[4] = {v3_madd(p0, f.l, -pr.r0), v3_madd(p0, f.l, pr.r0), v3_madd(p1, f.l, pr.r1),
                         v3_madd(p1, f.l, -pr.r1)};
        return cbm_scene_add_polygon(t->scene, q, 4);
    }
    int sides = t->cur.sides; /* as cpfg's own OBJ output, pixel lines too */
    double a0 = wu >= 0.0 ? wu / 2.0 : pr.r0, a1 = wu >= 0.0 ? wu / 2.0 : pr.r1;
    cbm_section s0 = {p0, f, a0, pr.r0};
    cbm_section s1 = {p1, f, a1, pr.r1};
    return cbm_scene_add_tube(t->scene, &s0, &s1, sides, false);
}

static cbm_status end_node(cbm_turtle *t)
{
    box_add(t, t->cur.pos);
    if (!t->node_open)
        return CBM_OK;
    t->node_open = false;
    t->part_module = t->node_module; /* the segment is the F or G that opened it */
    cbm_status st = emit_segment(t, t->node_p, t->cur.pos, t->node_w, t->cur.width, t->node_color,
                                 t->node_h, t->node_u);
    t->part_module = -1;
    return st;
}

static void start_node(cbm_turtle *t)
{
    t->node_open = true;
    t->node_module = t->module_index - 1;
    t->node_p = t->cur.pos;
    t->node_h = t->cur.h;
    t->node_u = t->cur.u;
    t->node_w = t->cur.width;
    t->node_wup = t->cur.width_up;
    t->node_color = t->cur.color;
}

/* ---- tropisms ---- */

/* ABOP tropism after a move: two rotations towards T (cpfg's "bend"). */
static void bend(cbm_turtle *t)
{
    tstate *s = &t->cur;
    double e = s->elasticity;
    if (e == 0.0)
        return;
    cbm_vec3 T = t->view->tropism_dir;
    /* sin(alpha) is clamped to [-1, 1] (cpfg gives NaN when e |T.U| > 1) */
    double bc = fmax(-1.0, fmin(1.0, e * v3_dot(T, s->u)));
    double bs = sqrt(1.0 - bc * bc);
    rotate_pair(&s->h, &s->u, bc, bs);
    bc = fmax(-1.0, fmin(1.0, e * v3_dot(T, s->l)));
    bs = sqrt(1.0 - bc * bc);
    rotate_pair(&s->h, &s->l, bc, bs);
}

/* Rotate v about the unit axis n by angle (right hand). */
static cbm_vec3 rot_axis(cbm_vec3 v, cbm_vec3 n, double angle)
{
    return q_rotate(q_axis_angle(n, angle), v);
}

/* U follows H by the minimal rotation from the previous heading; L = H x U. */
static void adjust_up_and_left(tstate *s)
{
    cbm_vec3 r = v3_cross(s->prev_h, s->h);
    double len = v3_norm(r);
    if (len > 0.000001) {
        if (len > 1.0)
            len = 1.0;
        double angle = asin(len);
        if (v3_dot(s->h, s->prev_h) < 0)
            angle = CBM_PI - angle;
        s->u = rot_axis(s->prev_u, v3_scale(r, 1.0 / v3_norm(r)), angle);
    }
    s->l = v3_cross(s->h, s->u);
}

static void movements(cbm_turtle *t)
{
    const cbm_view *v = t->view;
    if (v->nmov == 0)
        return;
    tstate *s = &t->cur;
    cbm_vec3 V = v3(0, 0, 0), tw = v3(0, 0, 0);
    for (int i = 0; i < v->nmov; i++) {
        const cbm__movement *m = &v->mov[i];
        double e = s->mov_e[i];
        if (m->torque) {
            tw = v3_madd(tw, m->dir, e);
            continue;
        }
        V = v3_madd(V, m->dir, m->cos_g * e);
        if (m->sin_g != 0.0) {
            cbm_vec3 hx = v3_cross(s->h, m->dir);
            double len = v3_norm(hx);
            if (len < 0.0000001) {
                hx = s->l;
                len = 1.0;
            }
            V = v3_madd(V, v3_cross(m->dir, hx), m->sin_g * e / len);
        }
    }
    cbm_vec3 rv = v3_cross(s->h, V);
    double len = v3_norm(rv);
    if (len >= 0.000001) {
        double a = len > 1.0 ? 1.0 : len;
        s->h = v3_normalize(rot_axis(s->h, v3_scale(rv, 1.0 / len), a));
        adjust_up_and_left(s);
    }
    double twl = v3_norm(tw);
    if (twl > 0.0) {
        /* torque: roll U about H by the angle |U x D| (capped at 1 rad), D the torque direction
         * projected normal to H, in the sense of cpfg's code: away from D (its comment says
         * towards; the code's quaternion rotates by the opposite angle), so U settles at -D */
        cbm_vec3 dn = v3_scale(tw, 1.0 / twl);
        cbm_vec3 c = v3_cross(s->h, dn);
        if (v3_dot(c, c) > 0.00000001) {
            cbm_vec3 D = v3_scale(v3_cross(c, s->h), twl);
            cbm_vec3 ax = v3_cross(s->u, D);
            double al = v3_norm(ax);
            if (al >= 0.0000001) {
                s->u = rot_axis(s->u, v3_scale(ax, 1.0 / al), al > 1.0 ? -1.0 : -al);
                s->l = v3_cross(s->h, s->u);
            }
            s->prev_h = s->h;
            s->prev_u = s->u;
        }
    }
}

/* ---- generalized cylinders ---- */

/* cpfg's minimal rotation of a frame: U follows the rotation taking prev_h to h (by
 * asin |h x prev_h|), then turns by -beta about h; L = H x U. */
static void adjust_frame(cbm_vec3 h, cbm_vec3 prev_h, cbm_vec3 prev_u, double beta, cbm_vec3 *u,
                         cbm_vec3 *l)
{
    cbm_vec3 r = v3_cross(h, prev_h);
    double len = v3_norm(r);
    cbm_vec3 up = prev_u;
    if (len > 0.0) {
        double a = asin(len > 1.0 ? 1.0 : len);
        up = rot_axis(up, v3_scale(r, -1.0 / len), a);
    }
    if (beta != 0.0)
        up = rot_axis(up, h, -beta);
    *u = up;
    *l = v3_cross(h, up);
}

/* Angle by which g2's up must turn about its heading to follow g1 without twist (cpfg). */
static double twist_angle(const gcpt *g1, const gcpt *g2)
{
    cbm_vec3 up = g1->u;
    cbm_vec3 r = v3_cross(g2->h, g1->h);
    double len = v3_norm(r);
    if (len > 0.000001)
        up = rot_axis(up, v3_scale(r, -1.0 / len), asin(len > 1.0 ? 1.0 : len));
    double c = v3_norm(v3_cross(g2->u, up));
    double angle = asin(c > 1.0 ? 1.0 : c);
    if (v3_dot(g2->u, up) < 0.0)
        angle = CBM_PI - angle;
    if (v3_dot(g2->l, up) < 0.0)
        angle = -angle;
    return angle;
}

/* Uniform cubic B-spline of the contour's control points at parameter tt (indices wrap). */
static void contour_eval(const cbm__contour *c, float tt, float out[3])
{
    int num = (int)(c->pts.len / 3);
    int first = (int)floorf(tt);
    float u = tt - (float)first;
    float b[4] = {(1 - u) * (1 - u) * (1 - u) / 6.0f, (3 * u * u * u - 6 * u * u + 4) / 6.0f,
                  (-3 * u * u * u + 3 * u * u + 3 * u + 1) / 6.0f, u * u * u / 6.0f};
    out[0] = out[1] = out[2] = 0.0f;
    if (num == 0) /* no control points: the origin */
        return;
    for (int i = 0; i < 4; i++) {
        int k = ((first + i) % num + num) % num;
        for (int d = 0; d < 3; d++)
            out[d] += b[i] * (float)c->pts.data[3 * k + d];
    }
}

/* Points of contour `contour` (0: the unit circle) resampled at `sides` equal arc lengths (as
 * cpfg: arc length tabulated at 10 points per knot interval, closed contours rotated so their
 * first point lies on +x); sides + 1 points, the last equal to the first when closed. */
static cbm_status contour_points(cbm_turtle *t, int contour, int sides, const double **out)
{
    for (size_t i = 0; i < t->ccache.len; i++)
        if (t->ccache.data[i].contour == contour && t->ccache.data[i].sides == sides) {
            *out = t->cpts.data + t->ccache.data[i].off;
            return CBM_OK;
        }
    size_t off = t->cpts.len;
    CBM_TRY(CBM_ARRAY_RESERVE(t->ctx, t->cpts, off + 3 * (size_t)(sides + 1)));
    double *p = t->cpts.data + off;
    const cbm__contour *c = contour > 0 && (size_t)contour <= t->view->contours.len
                                ? &t->view->contours.data[contour - 1]
                                : NULL;
    if (!c) {
        float step = (float)(2.0 * CBM_PI) / (float)sides, angle = 0.0f;
        for (int i = 0; i < sides; i++) {
            p[3 * i] = (float)cos(angle);
            p[3 * i + 1] = (float)sin(angle);
            p[3 * i + 2] = 0.0;
            angle += step;
        }
        for (int d = 0; d < 3; d++)
            p[3 * sides + d] = p[d];
    } else {
        const int n = 10;
        int num = (int)(c->pts.len / 3);
        int segments = c->closed ? num : num - 3;
        if (segments < 1)
            segments = 1;
        float *len = cbm__alloc(t->ctx, (size_t)(segments * n) * sizeof(float));
        if (!len)
            return CBM_E_NOMEM;
        float last[3], act[3], total = 0.0f, invn = 1.0f / (float)n;
        contour_eval(c, 0.0f, last);
        for (int i = 0; i < segments; i++) {
            float tt = (float)i;
            for (int j = 0; j < n; j++, tt += invn) {
                contour_eval(c, tt, act);
                float dx = last[0] - act[0], dy = last[1] - act[1];
                total += sqrtf(dx * dx + dy * dy);
                len[i * n + j] = total;
                memcpy(last, act, sizeof last);
            }
        }
        float rot[2][2] = {{1, 0}, {0, 1}};
        if (c->closed) {
            contour_eval(c, 0.0f, act);
            float dx = last[0] - act[0], dy = last[1] - act[1];
            total += sqrtf(dx * dx + dy * dy);
            float q = act[0] * act[0] + act[1] * act[1];
            if (q >= 0.000000001f) {
                float inv = 1.0f / sqrtf(q);
                rot[0][0] = act[0] * inv;
                rot[0][1] = -act[1] * inv;
                rot[1][0] = -rot[0][1];
                rot[1][1] = rot[0][0];
            }
        }
        float step = total / (float)sides, target = 0.0f, eps = 1e-10f / step;
        int j = 0, last_j = segments * n - 1;
        int npts = c->closed ? sides : sides + 1;
        for (int i = 0; i < npts; i++) {
            float tt;
            if (i == 0) {
                while (j < last_j && len[j] < eps)
                    j++;
                tt = 0.0f;
            } else {
                while (j < last_j && len[j] < target)
                    j++;
                int j2 = j - 1;
                while (j2 > 0 && len[j] - len[j2] <= eps)
                    j2--;
                if (j2 < 0)
                    j2 = 0;
                float d = len[j] - len[j2];
                tt = (float)j2 / (float)n + (d > 0.0f ? (target - len[j2]) / d / (float)n : 0.0f);
            }
            contour_eval(c, tt, act);
            p[3 * i] = act[0] * rot[0][0] + act[1] * rot[1][0];
            p[3 * i + 1] = act[0] * rot[0][1] + act[1] * rot[1][1];
            p[3 * i + 2] = act[2];
            target += step;
        }
        if (c->closed)
            for (int d = 0; d < 3; d++)
                p[3 * sides + d] = p[d];
        cbm__free(t->ctx, len, (size_t)(segments * n) * sizeof(float));
    }
    t->cpts.len = off + 3 * (size_t)(sides + 1);
    ccache cc = {contour, sides, off};
    CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->ccache, cc));
    *out = t->cpts.data + off;
    return CBM_OK;
}

static gcpt gc_snapshot(const tstate *s)
{
    gcpt g;
    memset(&g, 0, sizeof g);
    g.pos = s->pos;
    g.h = s->h;
    g.l = s->l;
    g.u = s->u;
    g.width = s->width;
    g.tan[0] = s->tan[0];
    g.tan[1] = s->tan[1];
    memcpy(g.rtan, s->rtan, sizeof g.rtan);
    g.rtan_scale = s->rtan_scale;
    g.contour = s->contour;
    g.sides = s->sides;
    return g;
}

/* One ring: contour points mixed (1-mix, mix) between the two contours, scaled by radius and
 * placed at P + x U - y L + z H * zscale, as cpfg's make_contour. */
static cbm_status push_ring(cbm_turtle *t, cbm_vec3 P, cbm_vec3 h, cbm_vec3 u, cbm_vec3 l,
                            double radius, const double *c1, const double *c2, double mix,
                            double zscale, int sides)
{
    for (int k = 0; k <= sides; k++) {
        double x = radius * (c1[3 * k] * (1 - mix) + c2[3 * k] * mix);
        double y = radius * (c1[3 * k + 1] * (1 - mix) + c2[3 * k + 1] * mix);
        double z = radius * (c1[3 * k + 2] * (1 - mix) + c2[3 * k + 2] * mix);
        cbm_vec3 q =
            v3_add(v3_add(P, v3_scale(u, x)), v3_add(v3_scale(l, -y), v3_scale(h, z * zscale)));
        CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->ringv, q));
    }
    /* normals of the ring's curve (its tangent crossed with the heading, outwards), so that
     * the rings a control point shares between two connections, and the first and last point
     * of a closed contour, get the same normal: the cylinder is shaded without seams */
    const cbm_vec3 *q = t->ringv.data + t->ringv.len - (size_t)(sides + 1);
    bool closed = v3_norm(v3_sub(q[0], q[sides])) <= 1e-12 * (1.0 + radius);
    for (int k = 0; k <= sides; k++) {
        int a = k > 0 ? k - 1 : closed ? sides - 1 : 0;
        int b = k < sides ? k + 1 : closed ? 1 : sides;
        cbm_vec3 n = v3_cross(v3_sub(q[b], q[a]), h);
        cbm_vec3 out = v3_sub(q[k], P);
        if (v3_dot(n, out) < 0)
            n = v3_neg(n);
        double nn = v3_norm(n);
        if (nn > 1e-300)
            n = v3_scale(n, 1.0 / nn);
        else
            n = v3_norm(out) > 1e-300 ? v3_normalize(out) : u;
        CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->ringn, n));
    }
    return CBM_OK;
}

/* cpfg's band of a generalized cylinder from the ring state g1 to g2 (cpfg's
 * interpolate_connection): the spine is the cubic a0 + a1 t + a2 t^2 + a3 t^3 given by `bsp`
 * (a uniform cubic B-spline segment) or, when bsp is NULL, the Hermite cubic with tangents
 * H1 |P2-P1| tan1 and H2 |P2-P1| tan0; `rings` bands, radius and contour interpolated, each ring's
 * U carried from g1 by the minimal rotation (and `twist` when "twist of cylinders" is on). */
static cbm_status gc_segment(cbm_turtle *t, const gcpt *g1p, const gcpt *g2p, int rings,
                             const cbm_vec3 *bsp, double twist)
{
    tstate *s = &t->cur;
    gcpt g1 = *g1p, g2 = *g2p;
    double len = v3_norm(v3_sub(g2.pos, g1.pos));
    if (len < 0.00001)
        return CBM_OK;
    cbm_vec3 R1, c2, c3;
    if (bsp) {
        R1 = bsp[1];
        c2 = bsp[2];
        c3 = bsp[3];
    } else {
        R1 = v3_scale(g1.h, len * g1.tan[1]);
        cbm_vec3 R2 = v3_scale(g2.h, len * g2.tan[0]);
        cbm_vec3 d = v3_sub(g1.pos, g2.pos);
        c2 = v3_sub(v3_sub(v3_scale(d, -3.0), v3_scale(R1, 2.0)), R2);
        c3 = v3_add(v3_add(v3_scale(d, 2.0), R1), R2);
    }
    double dr = 0.5 * (g2.width - g1.width);
    /* the radius along the segment: a Hermite curve in (t, r) from (0, w1/2) to (1, w2/2) with
     * the radius tangents of the two control points (linear when they are zero) */
    double rt0[2] = {g1.rtan[1][0], g1.rtan[1][1]}, rt1[2] = {g2.rtan[0][0], g2.rtan[0][1]};
    if (g2.rtan_scale) {
        rt0[1] *= len;
        rt1[1] *= len;
    }
    if (rt0[0] == 0.0 && rt0[1] == 0.0) {
        rt0[0] = 1.0;
        rt0[1] = dr;
    }
    if (rt1[0] == 0.0 && rt1[1] == 0.0) {
        rt1[0] = 1.0;
        rt1[1] = dr;
    }
    double ta = 3 - 2 * rt0[0] - rt1[0], tb = -2 + rt0[0] + rt1[0];
    double ra = 3 * dr - 2 * rt0[1] - rt1[1], rb = -2 * dr + rt0[1] + rt1[1];
    int sides = g1.sides;
    bool cyl = line_style(t) == CBM__LS_CYLINDER;
    const double *k1 = NULL, *k2 = NULL;
    if (cyl) {
        CBM_TRY(contour_points(t, g1.contour, sides, &k1));
        CBM_TRY(contour_points(t, g2.contour, sides, &k2));
    }
    t->ringv.len = 0;
    t->ringn.len = 0;
    cbm_vec3 prev = g1.pos;
    for (int i = 0; i <= rings; i++) {
        double r = (double)i / rings;
        double tt = ((tb * r + ta) * r + rt0[0]) * r;
        cbm_vec3 P, H, U, L;
        double radius;
        if (i == 0) {
            P = g1.pos;
            H = g1.h;
            U = g1.u;
            L = g1.l;
            radius = 0.5 * g1.width;
        } else if (i == rings) {
            P = g2.pos;
            H = g2.h;
            U = g2.u;
            L = g2.l;
            radius = 0.5 * g2.width;
        } else {
            P = v3_add(v3_add(g1.pos, v3_scale(R1, tt)),
                       v3_add(v3_scale(c2, tt * tt), v3_scale(c3, tt * tt * tt)));
            H = v3_normalize(v3_add(R1, v3_add(v3_scale(c2, 2 * tt), v3_scale(c3, 3 * tt * tt))));
            adjust_frame(H, g1.h, g1.u, twist * tt, &U, &L);
            radius = 0.5 * g1.width + ((rb * r + ra) * r + rt0[1]) * r;
        }
        if (cyl) {
            double zs = i == 0 ? g1.tan[1] : i == rings ? g2.tan[0] : 1.0 / len;
            CBM_TRY(push_ring(t, P, H, U, L, radius, k1, k2, i == rings ? 1.0 : tt, zs, sides));
        } else if (i > 0) {
            /* pixel and polygon lines: cpfg draws the spine as segments */
            CBM_TRY(emit_segment(t, prev, P, g1.width, i == rings ? g2.width : g1.width, s->color,
                                 H, U));
            box_add(t, P);
        }
        prev = P;
    }
    if (!cyl)
        return CBM_OK;
    /* the bands, in cpfg's triangle order */
    uint32_t w = (uint32_t)sides + 1;
    t->ringt.len = 0;
    for (int i = 1; i <= rings; i++) {
        uint32_t a = (uint32_t)(i - 1) * w, b = (uint32_t)i * w;
        for (uint32_t k = 1; k <= (uint32_t)sides; k++) {
            uint32_t tri[6] = {b + k - 1, b + k, a + k - 1, a + k - 1, b + k, a + k};
            for (int m = 0; m < 6; m++)
                CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->ringt, tri[m]));
        }
    }
    for (size_t i = 0; i < t->ringv.len; i++)
        box_add(t, t->ringv.data[i]);
    if (t->record) {
        cbm_prim pr;
        memset(&pr, 0, sizeof pr);
        pr.kind = CBM_PRIM_GCYL;
        pr.color = s->color;
        pr.p0 = g1.pos;
        pr.p1 = g2.pos;
        pr.r0 = g1.width / 2;
        pr.r1 = g2.width / 2;
        pr.frame.h = g1.h;
        pr.frame.l = g1.l;
        pr.frame.u = g1.u;
        pr.first = t->pts.len;
        pr.count = t->ringt.len;
        for (size_t i = 0; i < t->ringt.len; i++)
            CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->pts, t->ringv.data[t->ringt.data[i]]));
        CBM_TRY(push_prim(t, &pr));
    }
    if (t->scene) {
        cbm_part part = make_part(t, CBM_ORGAN_BRANCH, s->color);
        CBM_TRY(cbm_scene_begin_part(t->scene, &part, NULL));
        CBM_TRY(cbm_scene_add_mesh(t->scene, t->ringv.data, t->ringn.data, t->ringv.len,
                                   t->ringt.data, t->ringt.len / 3));
        /* lpfg's turtle: each connection closed at its end, so that an axis which stops (a
         * branch broken off above a node, a leader taken over by a thinner lateral) shows bark,
         * not the inside of the tube; where the cylinder goes on, the disc lies inside it */
        if (t->lpfg && sides >= 3)
            CBM_TRY(cbm_scene_add_polygon(
                t->scene, t->ringv.data + t->ringv.len - (size_t)(sides + 1), (size_t)sides));
    }
    return CBM_OK;
}

/* cpfg's segment from a generalized cylinder's last control point to the turtle (@Gc, @Ge):
 * a Hermite band; then the turtle becomes the last control point. */
static cbm_status gc_connect(cbm_turtle *t, int rings)
{
    tstate *s = &t->cur;
    gcpt g1 = s->gc, g2 = gc_snapshot(s);
    double twist = 0.0;
    if (t->view->gc_twist)
        twist = twist_angle(&g1, &g2);
    else
        adjust_frame(g2.h, g1.h, g1.u, 0.0, &g2.u, &g2.l);
    s->gc = g2;
    return gc_segment(t, &g1, &g2, rings, NULL, twist);
}

/* ---- cpfg's spline cylinders {(n) ... }(n) ---- */

/* The index below which the spline records belong to enclosing branches. */
static size_t spline_level(const cbm_turtle *t)
{
    return t->stack.len ? (size_t)t->stack.data[t->stack.len - 1].spl_mark : 0;
}

/* {(n, r): a spline cylinder of kind n (1 open Hermite, 2 closed Hermite, 3 open B-spline,
 * 4 closed B-spline) with r rings per band (4 when r <= 0 or absent). Other n are ignored, as
 * cpfg. A spline already open in this branch is restarted. */
static cbm_status spline_open(cbm_turtle *t, const double *params, int nparams)
{
    tstate *s = &t->cur;
    int kind = cbm__to_int(params[0]);
    if (kind < 1 || kind > 4)
        return CBM_OK; /* cpfg: "Parameter following { is above 4", ignored */
    spline sp;
    memset(&sp, 0, sizeof sp);
    sp.closed = (kind - 1) % 2 == 1;
    sp.bspline = (kind - 1) / 2 == 1;
    int rings = nparams > 1 ? cbm__to_int(params[1]) : 0;
    sp.rings = rings <= 0 ? 4 : rings > MAX_RINGS ? MAX_RINGS : rings;
    if (s->spl >= 0 && (size_t)s->spl + 1 == t->splines.len && (size_t)s->spl >= spline_level(t)) {
        t->splines.data[s->spl] = sp;
        return CBM_OK;
    }
    CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->splines, sp));
    s->spl = (int)t->splines.len - 1;
    return CBM_OK;
}

/* Unit vector along d, or `dflt` (with its frame kept) when d is (nearly) null, then U and L
 * carried from (prev_h, prev_u) by the minimal rotation turned by beta: cpfg's frame of a
 * B-spline ring at a knot. */
static void knot_frame(gcpt *g, cbm_vec3 d, double beta)
{
    double n = v3_norm(d);
    if (n > 0.0000001) {
        cbm_vec3 ph = g->h, pu = g->u;
        g->h = v3_scale(d, 1.0 / n);
        adjust_frame(g->h, ph, pu, beta, &g->u, &g->l);
    }
}

/* A control point p (F, f, or . outside a polygon) of the open spline; `rings` bands (0: the
 * spline's default). Hermite: a band from the previous control point (cpfg's generalized
 * cylinder). B-spline: once four control points P0..P3 are known, the band of the uniform cubic
 * B-spline between the knots (P0 + 4 P1 + P2) / 6 and (P1 + 4 P2 + P3) / 6, with tangents
 * (P2 - P0) / 2 and (P3 - P1) / 2, the ring states (width, contour, tangent parameters, frame)
 * those of P1 and P2 (cpfg's SetControlPoint and interpolate_connection). */
static cbm_status spline_point(cbm_turtle *t, gcpt p, int rings)
{
    tstate *s = &t->cur;
    spline *sp = &t->splines.data[s->spl];
    if (rings == 0)
        rings = sp->rings;
    else if (rings < 1)
        rings = 1; /* cpfg: a single band */
    if (rings > MAX_RINGS)
        rings = MAX_RINGS;
    if (!sp->bspline) {
        if (sp->num++ == 0) {
            sp->tu = p;
            if (sp->closed)
                sp->first[sp->nfirst++] = p;
            return CBM_OK;
        }
        gcpt g1 = sp->tu, g2 = p;
        double twist = 0.0;
        if (t->view->gc_twist)
            twist = twist_angle(&g1, &g2);
        else
            adjust_frame(g2.h, g1.h, g1.u, 0.0, &g2.u, &g2.l);
        sp->tu = g2;
        return gc_segment(t, &g1, &g2, rings, NULL, twist);
    }
    if (sp->num < 3) {
        sp->win[sp->num] = p;
        if (sp->closed)
            sp->first[sp->nfirst++] = p;
        sp->num++;
        return CBM_OK;
    }
    cbm_vec3 P0 = sp->win[0].pos, P1 = sp->win[1].pos, P2 = sp->win[2].pos, P3 = p.pos;
    cbm_vec3 a[4];
    a[0] = v3_scale(v3_add(v3_add(P0, v3_scale(P1, 4.0)), P2), 1.0 / 6.0);
    a[1] = v3_scale(v3_sub(P2, P0), 0.5);
    a[2] = v3_scale(v3_add(v3_sub(P0, v3_scale(P1, 2.0)), P2), 0.5);
    a[3] = v3_scale(v3_add(v3_sub(v3_scale(v3_sub(P1, P2), 3.0), P0), P3), 1.0 / 6.0);
    gcpt g1 = sp->tu;
    if (sp->num == 3) {
        g1 = sp->win[1];
        g1.pos = a[0];
        knot_frame(&g1, a[1], 0.0);
    }
    gcpt raw = p;
    double twist = 0.0;
    if (t->view->gc_twist)
        twist = twist_angle(&g1, &raw);
    else
        adjust_frame(raw.h, g1.h, g1.u, 0.0, &raw.u, &raw.l);
    gcpt g2 = sp->win[2];
    g2.pos = v3_scale(v3_add(v3_add(P1, v3_scale(P2, 4.0)), P3), 1.0 / 6.0);
    knot_frame(&g2, v3_scale(v3_sub(P3, P1), 0.5), twist);
    sp->win[0] = sp->win[1];
    sp->win[1] = sp->win[2];
    sp->win[2] = p;
    sp->num++;
    /* cpfg: a band too short to draw leaves the control point itself as the next start */
    sp->tu = v3_norm(v3_sub(g2.pos, g1.pos)) < 0.00001 ? raw : g2;
    return gc_segment(t, &g1, &g2, rings, a, twist);
}

/* }(n), n != 0: the spline ends; a closed one is closed by feeding again its first control
 * points (1 for Hermite, 3 for B-spline, cyclically when it has fewer), as cpfg. */
static cbm_status spline_close(cbm_turtle *t)
{
    tstate *s = &t->cur;
    if (s->spl < 0)
        return CBM_OK; /* cpfg: "Spline is already finished or hasn't been started", ignored */
    spline *sp = &t->splines.data[s->spl];
    if (sp->closed && sp->nfirst > 0) {
        int nfeed = sp->bspline ? 3 : 1, nfirst = sp->nfirst;
        gcpt first[3];
        memcpy(first, sp->first, sizeof first);
        for (int i = 0; i < nfeed; i++)
            CBM_TRY(spline_point(t, first[i % nfirst], 0));
    }
    if ((size_t)s->spl + 1 == t->splines.len && (size_t)s->spl >= spline_level(t))
        t->splines.len--;
    s->spl = -1;
    return CBM_OK;
}

/* ---- surfaces ---- */

static const cbm__surface *find_surface(const cbm_view *v, char id)
{
    for (size_t i = 0; i < v->surfaces.len; i++)
        if (v->surfaces.data[i].id == id)
            return &v->surfaces.data[i];
    return NULL;
}

cbm_status cbm__turtle_surface(cbm_turtle *t, const char *name, size_t len, const double *params,
                               int nparams)
{
    if (t->cut_depth > 0)
        return CBM_OK;
    if (len != 1)
        return cbm__fail(t->ctx, CBM_E_RUNTIME,
                         "~ must be followed by a one-letter surface name, found '%.*s'", (int)len,
                         name);
    const cbm__surface *sf = find_surface(t->view, name[0]);
    if (!sf)
        return CBM_OK; /* cpfg draws nothing for an unknown surface */
    double sx = 1, sy = 1, sz = 1;
    if (nparams >= 3) {
        sx = params[0];
        sy = params[1];
        sz = params[2];
    } else if (nparams >= 1) {
        sx = sy = sz = params[0];
    }
    const tstate *s = &t->cur;
    sx *= s->scale;
    sy *= s->scale;
    sz *= s->scale;
    const double k = 1.0;
    /* surface coordinates (already relative to the contact point): X along L, Y along H, Z
     * along U */
    size_t nv = sf->pos.len;
    t->scratch.len = 0;
    CBM_TRY(CBM_ARRAY_RESERVE(t->ctx, t->scratch, nv * 2));
    for (size_t i = 0; i < nv; i++) {
        cbm_vec3 q = sf->pos.data[i];
        cbm_vec3 w = v3_add(
            s->pos, v3_add(v3_add(v3_scale(s->l, q.x * k * sx), v3_scale(s->h, q.y * k * sy)),
                           v3_scale(s->u, q.z * k * sz)));
        cbm_vec3 nq = sf->nrm.data[i];
        cbm_vec3 nw =
            v3_normalize(v3_add(v3_add(v3_scale(s->l, nq.x / sx), v3_scale(s->h, nq.y / sy)),
                                v3_scale(s->u, nq.z / sz)));
        t->scratch.data[i] = w;
        t->scratch.data[nv + i] = nw;
    }
    /* cpfg's box holds the control points of the patches */
    for (size_t i = 0; i < sf->ctrl.len; i++) {
        cbm_vec3 q = sf->ctrl.data[i];
        box_add(t, v3_add(s->pos, v3_add(v3_add(v3_scale(s->l, q.x * sx), v3_scale(s->h, q.y * sy)),
                                         v3_scale(s->u, q.z * sz))));
    }
    t->scratch.len = 2 * nv;
    if (t->record) {
        cbm_prim pr;
        memset(&pr, 0, sizeof pr);
        pr.kind = CBM_PRIM_SURFACE;
        pr.id = sf->id;
        pr.frame.h = s->h;
        pr.frame.l = s->l;
        pr.frame.u = s->u;
        pr.color = s->color;
        pr.p0 = s->pos;
        pr.r0 = sx;
        pr.first = t->pts.len;
        pr.count = nv;
        for (size_t i = 0; i < nv; i++)
            CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->pts, t->scratch.data[i]));
        CBM_TRY(push_prim(t, &pr));
    }
    if (t->scene) {
        cbm_part part = make_part(t, CBM_ORGAN_LEAF, s->color);
        CBM_TRY(cbm_scene_begin_part(t->scene, &part, NULL));
        CBM_TRY(cbm_scene_add_mesh(t->scene, t->scratch.data, t->scratch.data + nv, nv,
                                   sf->tri.data, sf->tri.len / 3));
    }
    /* the turtle moves to the surface's end point (cpfg: x, z scaled as y when not index 0) */
    cbm_vec3 e = sf->end;
    t->cur.pos =
        v3_add(s->pos, v3_add(v3_add(v3_scale(s->l, e.x * k * sx), v3_scale(s->h, e.y * k * sx)),
                              v3_scale(s->u, e.z * k * sx)));
    return CBM_OK;
}

/* ---- the commands ---- */

static double param0(const double *p, int n, double dflt)
{
    return n > 0 ? p[0] : dflt;
}

static cbm_status sphere_or_disc(cbm_turtle *t, int cmd, const double *params, int nparams)
{
    tstate *s = &t->cur;
    double d = nparams > 0 ? params[0] * s->scale : s->width;
    double r = d / 2.0;
    cbm_prim pr;
    memset(&pr, 0, sizeof pr);
    pr.kind = cmd == CBM_T_SPHERE ? CBM_PRIM_SPHERE : CBM_PRIM_DISC;
    pr.color = s->color;
    pr.frame.h = s->h;
    pr.frame.l = s->l;
    pr.frame.u = s->u;
    pr.p0 = s->pos;
    pr.p1 = s->u;
    pr.r0 = pr.r1 = r;
    CBM_TRY(push_prim(t, &pr));
    if (cmd == CBM_T_SPHERE) {
        for (int i = 0; i < 8; i++)
            box_add(t, v3(s->pos.x + ((i & 1) ? r : -r), s->pos.y + ((i & 2) ? r : -r),
                          s->pos.z + ((i & 4) ? r : -r)));
    } else {
        for (int i = 0; i < 4; i++)
            box_add(t, v3(s->pos.x + ((i & 1) ? r : -r), s->pos.y + ((i & 2) ? r : -r), s->pos.z));
    }
    if (!t->scene || !(r > 0))
        return CBM_OK;
    cbm_part part = make_part(t, cmd == CBM_T_SPHERE ? CBM_ORGAN_FRUIT : CBM_ORGAN_OTHER, s->color);
    CBM_TRY(cbm_scene_begin_part(t->scene, &part, NULL));
    if (cmd == CBM_T_SPHERE) /* at least 16 slices: fewer show as polygons in a picture */
        return cbm_scene_add_sphere(t->scene, s->pos, r, s->sides < 16 ? 16 : s->sides);
    int n = s->sides;
    CBM_TRY(CBM_ARRAY_RESERVE(t->ctx, t->scratch, (size_t)n));
    for (int k = 0; k < n; k++) {
        double a = 2 * CBM_PI * k / n;
        t->scratch.data[k] = v3_madd(v3_madd(s->pos, s->h, r * cos(a)), s->l, r * sin(a));
    }
    return cbm_scene_add_polygon(t->scene, t->scratch.data, (size_t)n);
}

/* cpfg's ?Q: the frame whose rows are H, L, U as a quaternion (x, y, z, w), by the classic
 * conversion from a rotation matrix M (Shoemake 1985): w^2 =
 * (1 + trace M) / 4; when w^2 > 1e-10, (x, y, z) = (M12 - M21, M20 - M02, M01 - M10) / 4w;
 * otherwise w = 0 and, again by the first component whose square is large enough,
 * x^2 = -(M11 + M22) / 2, y = M01 / 2x, z = M02 / 2x; or x = 0, y^2 = (1 - M22) / 2,
 * z = M12 / 2y; or (0, 0, 1, 0). These are cpfg's branches, so a half-turn frame gives cpfg's
 * quaternion. */
static void frame_quaternion(const tstate *s, double q[4])
{
    const double m[3][3] = {
        {s->h.x, s->h.y, s->h.z}, {s->l.x, s->l.y, s->l.z}, {s->u.x, s->u.y, s->u.z}};
    const double eps = 1e-10;
    double w2 = 0.25 * (1.0 + m[0][0] + m[1][1] + m[2][2]);
    if (w2 > eps) {
        double w = sqrt(w2), k = 4.0 * w;
        q[0] = (m[1][2] - m[2][1]) / k;
        q[1] = (m[2][0] - m[0][2]) / k;
        q[2] = (m[0][1] - m[1][0]) / k;
        q[3] = w;
        return;
    }
    q[3] = 0.0;
    double x2 = -0.5 * (m[1][1] + m[2][2]);
    if (x2 > eps) {
        q[0] = sqrt(x2);
        q[1] = m[0][1] / (2.0 * q[0]);
        q[2] = m[0][2] / (2.0 * q[0]);
        return;
    }
    q[0] = 0.0;
    double y2 = 0.5 * (1.0 - m[2][2]);
    if (y2 > eps) {
        q[1] = sqrt(y2);
        q[2] = m[1][2] / (2.0 * q[1]);
    } else {
        q[1] = 0.0;
        q[2] = 1.0;
    }
}

static cbm_status query(cbm_turtle *t, int cmd, double *params, int nparams)
{
    const tstate *s = &t->cur;
    if (cmd == CBM_T_QUERY_Q) {
        double q[4];
        frame_quaternion(s, q);
        for (int i = 0; i < nparams && i < 4; i++)
            params[i] = q[i];
        return CBM_OK;
    }
    cbm_vec3 v = cmd == CBM_T_QUERY_P   ? s->pos
                 : cmd == CBM_T_QUERY_H ? s->h
                 : cmd == CBM_T_QUERY_L ? s->l
                                        : s->u;
    double c[3] = {v.x, v.y, v.z};
    for (int i = 0; i < nparams && i < 3; i++)
        params[i] = c[i];
    return CBM_OK;
}

static cbm_status poly_vertex(cbm_turtle *t)
{
    CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->polypts, t->cur.pos));
    return CBM_ARRAY_PUSH(t->ctx, t->polycolor, t->cur.color);
}

static cbm_status move(cbm_turtle *t, int cmd, const double *params, int nparams)
{
    tstate *s = &t->cur;
    movements(t);
    CBM_TRY(end_node(t));
    double len = param0(params, nparams, t->view->step) * s->scale;
    bool draw = cmd == CBM_T_F || cmd == CBM_T_G;
    if (draw)
        start_node(t);
    s->pos = v3_madd(s->pos, s->h, len);
    if (!v3_isfinite(s->pos))
        return cbm__fail(t->ctx, CBM_E_NONFINITE,
                         "turtle: the position is no longer finite at module %lld",
                         (long long)t->module_index);
    bend(t);
    if (t->polystart.len > 0 && (cmd == CBM_T_F || cmd == CBM_T_f))
        CBM_TRY(poly_vertex(t));
    if (s->spl >= 0 && (cmd == CBM_T_F || cmd == CBM_T_f))
        CBM_TRY(spline_point(t, gc_snapshot(s), 0));
    if (draw && t->lpfg) {
        /* lpfg draws each F at once as a cylinder of the current width */
        t->node_open = false;
        box_add(t, s->pos);
        CBM_TRY(emit_segment_e(t, t->node_p, s->pos, t->node_w, t->node_w, t->node_wup,
                               t->node_color, t->node_h, t->node_u));
    }
    if (draw) {
        s->prev_h = s->h;
        s->prev_u = s->u;
    }
    return CBM_OK;
}

static cbm_status poly_end(cbm_turtle *t)
{
    if (t->polystart.len == 0)
        return CBM_OK; /* cpfg: unmatched } ignored */
    CBM_TRY(end_node(t));
    size_t first = t->polystart.data[--t->polystart.len];
    size_t n = t->polypts.len - first;
    const cbm_vec3 *p = n ? t->polypts.data + first : NULL;
    if (n >= 3) {
        cbm_prim pr;
        memset(&pr, 0, sizeof pr);
        pr.kind = CBM_PRIM_POLYGON;
        pr.color = t->polycolor.data[first];
        pr.p0 = p[0];
        pr.first = t->pts.len;
        pr.count = n;
        if (t->record) {
            for (size_t i = 0; i < n; i++)
                CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->pts, p[i]));
            CBM_TRY(push_prim(t, &pr));
        }
        if (t->scene) {
            cbm_part part = make_part(t, CBM_ORGAN_LEAF, pr.color);
            CBM_TRY(cbm_scene_begin_part(t->scene, &part, NULL));
            CBM_TRY(cbm_scene_add_polygon(t->scene, p, n));
        }
    }
    t->polypts.len = first;
    t->polycolor.len = first;
    return CBM_OK;
}

/* lpfg's SetHead(h, u): H = h/|h|, U = the part of u/|u| normal to H (lpfg's U, which is minus
 * this turtle's U: lpfg's frame has L = U x H, cpfg's L = H x U). Null or parallel vectors leave
 * the frame as it is, as lpfg. */
static cbm_status set_head(cbm_turtle *t, const double *params, int nparams)
{
    if (nparams < 6)
        return CBM_OK;
    tstate *s = &t->cur;
    cbm_vec3 h = v3(params[0], params[1], params[2]), u = v3(params[3], params[4], params[5]);
    if (v3_norm(h) < 1e-5 || v3_norm(u) < 1e-5)
        return CBM_OK;
    h = v3_normalize(h);
    u = v3_normalize(u);
    cbm_vec3 l = v3_cross(u, h);
    if (v3_norm(l) < 1e-5)
        return CBM_OK;
    s->h = h;
    s->l = v3_normalize(l);
    s->u = v3_cross(s->l, s->h); /* this turtle's U = L x H = -(lpfg's H x L) */
    return CBM_OK;
}

/* lpfg's LineTo3d(p) and LineRel3d(d): a segment from the position to p (or by d), drawn with
 * the heading along it and L normal to the old U, then the frame as before. */
static cbm_status line_to(cbm_turtle *t, int cmd, const double *params, int nparams)
{
    if (nparams < 3)
        return CBM_OK;
    tstate *s = &t->cur;
    cbm_vec3 p = v3(params[0], params[1], params[2]);
    cbm_vec3 d = cmd == CBM_T_LINE_TO ? v3_sub(p, s->pos) : p;
    double len = v3_norm(d);
    if (len < 1e-5)
        return CBM_OK;
    cbm_vec3 h0 = s->h, l0 = s->l, u0 = s->u;
    s->h = v3_scale(d, 1.0 / len);
    cbm_vec3 l = v3_cross(s->h, s->u); /* lpfg: U x H with its U = -ours */
    if (v3_norm(l) < 1e-5)
        l = v3(-s->h.y, s->h.x, 0.0);
    s->l = v3_norm(l) < 1e-5 ? v3(1, 0, 0) : v3_normalize(l);
    s->u = v3_cross(s->l, s->h);
    double len_param = len;
    cbm_status st = move(t, CBM_T_F, &len_param, 1);
    s->h = h0;
    s->l = l0;
    s->u = u0;
    return st;
}

/* ?(id, s) and $: the scale of a sub-L-system, on its own stack (cpfg's UpdateCurrentLsystem:
 * brackets do not restore it); the width follows the ratio of the new scale to the old. An
 * unmatched $ is passed over. */
static cbm_status sublsys_scale(cbm_turtle *t, int cmd, const double *params, int nparams)
{
    tstate *s = &t->cur;
    size_t n = t->subscale.len;
    double old = n ? t->subscale.data[n - 1] : t->view->init_scale, nw;
    if (cmd == CBM_T_SUBLSYS_BEGIN) {
        nw = nparams >= 2 ? old * params[1] : old;
        if (n >= cbm_context_limits(t->ctx)->max_modules)
            return cbm__fail(t->ctx, CBM_E_LIMIT, "turtle: sub-L-systems nested deeper than %zu",
                             n);
        CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->subscale, nw));
    } else {
        if (n == 0)
            return CBM_OK;
        t->subscale.len--;
        nw = n > 1 ? t->subscale.data[n - 2] : t->view->init_scale;
    }
    s->scale = nw;
    if (old != 0.0 && isfinite(s->width * nw / old)) {
        s->width = (float)(s->width * nw / old);
        s->width_up = s->width;
    }
    return CBM_OK;
}

/* The @ commands (and the queries): they end the current segment first, as in cpfg. */
static cbm_status exec_at(cbm_turtle *t, int cmd, double *params, int nparams)
{
    tstate *s = &t->cur;
    const cbm_view *v = t->view;
    if (cmd >= CBM_T_ROLL_HORIZ && cmd <= CBM_T_GC_END) {
        CBM_TRY(end_node(t));
    } else if (cmd >= CBM_T_USER_FIRST && cmd != CBM_T_ELASTICITY) {
        CBM_TRY(end_node(t));
    }
    switch (cmd) {
    case CBM_T_ROLL_HORIZ:
        if (s->h.y < 1.0 && s->h.y > -1.0) {
            s->l = v3_normalize(v3_cross(v3(0, 1, 0), s->h));
            s->u = v3_cross(s->l, s->h);
        }
        return CBM_OK;
    case CBM_T_SPHERE:
    case CBM_T_CIRCLE:
    case CBM_T_CONTOUR:
        return sphere_or_disc(t, cmd == CBM_T_SPHERE ? CBM_T_SPHERE : CBM_T_CIRCLE, params,
                              nparams);
    case CBM_T_SCALE_CONTOUR:
        /* lpfg's ScaleContour(p, q): the section's width along L and along U */
        if (nparams >= 2) {
            s->width = params[0];
            s->width_up = params[1];
        }
        return CBM_OK;
    case CBM_T_ROLL_TO_VERT: {
        /* lpfg's RollToVert: L = y x H, or -x when H is vertical; U (this turtle's) = L x H */
        cbm_vec3 l = v3_cross(v3(0, 1, 0), s->h);
        s->l = v3_norm(l) < 1e-5 ? v3(-1, 0, 0) : v3_normalize(l);
        s->u = v3_cross(s->l, s->h);
        return CBM_OK;
    }
    case CBM_T_SET_HEAD:
        return set_head(t, params, nparams);
    case CBM_T_LINE_TO:
    case CBM_T_LINE_REL:
        return line_to(t, cmd, params, nparams);
    case CBM_T_MOVE_REL:
        CBM_TRY(end_node(t));
        if (nparams >= 3) {
            s->pos = v3_add(s->pos, v3(params[0], params[1], params[2]));
            box_add(t, s->pos);
        }
        return CBM_OK;
    case CBM_T_MOVE_TO:
        if (nparams >= 2) {
            s->pos = v3(params[0], params[1], nparams >= 3 ? params[2] : 0.0);
            box_add(t, s->pos);
        }
        return CBM_OK;
    case CBM_T_TROPISM_SET:
    case CBM_T_TROPISM_INC:
    case CBM_T_TROPISM_DEC: {
        if (nparams == 0)
            return CBM_OK; /* cpfg applies @T only with an index */
        int i = cbm__to_int(params[0]) - 1;
        if (i < 0 || i >= v->nmov)
            return CBM_OK; /* cpfg: "Movement index out of range", ignored */
        double aux = nparams >= 2 ? params[1] : v->mov[i].elasticity_inc;
        if (cmd == CBM_T_TROPISM_DEC)
            aux = -aux;
        else if (cmd == CBM_T_TROPISM_SET)
            aux = nparams >= 2 ? params[1] - s->mov_e[i] : -s->mov_e[i];
        s->mov_e[i] += aux;
        return CBM_OK;
    }
    case CBM_T_GC_START:
        /* the turtle becomes the first control point (an open one is restarted, as cpfg) */
        s->gc_on = true;
        s->gc = gc_snapshot(s);
        return CBM_OK;
    case CBM_T_GC_CONTROL:
    case CBM_T_GC_END: {
        int rings = 4; /* cpfg's default */
        if (nparams > 0) {
            double r = params[0];
            rings = r < 1.0 ? 1 : r > MAX_RINGS ? MAX_RINGS : (int)r;
        }
        if (!s->gc_on) {
            /* cpfg starts a cylinder at a control point without @Gs */
            s->gc_on = cmd == CBM_T_GC_CONTROL;
            s->gc = gc_snapshot(s);
            return CBM_OK;
        }
        CBM_TRY(gc_connect(t, rings));
        if (cmd == CBM_T_GC_END)
            s->gc_on = false;
        return CBM_OK;
    }
    case CBM_T_TWIST_ADJUST:
        adjust_up_and_left(s);
        return CBM_OK;
    case CBM_T_TWIST_KEEP:
        s->prev_h = s->h;
        s->prev_u = s->u;
        return CBM_OK;
    case CBM_T_GC_RADIUS:
        if (nparams == 1) {
            s->rtan_scale = params[0] != 0.0;
        } else if (nparams >= 2) {
            double a = params[0] * CBM_PI / 180.0;
            s->rtan[0][0] = s->rtan[1][0] = cos(a) * params[1];
            s->rtan[0][1] = s->rtan[1][1] = sin(a) * params[1];
            if (nparams >= 4) {
                double b = params[2] * CBM_PI / 180.0;
                s->rtan[1][0] = cos(b) * params[3];
                s->rtan[1][1] = sin(b) * params[3];
            }
        }
        return CBM_OK;
    case CBM_T_GC_TANGENT:
        if (nparams > 0) {
            s->tan[0] = params[0];
            s->tan[1] = nparams > 1 ? params[1] : params[0];
        }
        return CBM_OK;
    case CBM_T_CONTOUR_SET:
        /* the view's contour with this id; the circle when none (as cpfg) */
        s->contour = 0;
        if (nparams > 0)
            for (size_t i = 0; i < v->contours.len; i++)
                if (v->contours.data[i].id == cbm__to_int(params[0])) {
                    s->contour = (int)i + 1;
                    break;
                }
        return CBM_OK;
    case CBM_T_SIDES_SET:
        s->sides = nparams > 0 ? cbm__to_int(params[0]) : 8;
        if (s->sides < 3)
            s->sides = 3;
        if (s->sides > 1024)
            s->sides = 1024;
        return CBM_OK;
    case CBM_T_QUERY_P:
    case CBM_T_QUERY_H:
    case CBM_T_QUERY_L:
    case CBM_T_QUERY_U:
    case CBM_T_QUERY_Q:
        return query(t, cmd, params, nparams);
    case CBM_T_SCALE_SET:
        if (nparams > 0)
            s->scale = params[0];
        return CBM_OK;
    case CBM_T_SCALE_MUL:
    case CBM_T_SCALE_DIV: {
        /* cpfg: a zero parameter leaves the scale */
        double k = nparams > 0 ? params[0] : v->scale_mul;
        if (k != 0.0)
            s->scale = cmd == CBM_T_SCALE_MUL ? s->scale * k : s->scale / k;
        return CBM_OK;
    }
    default:
        return CBM_OK;
    }
}

cbm_status cbm__turtle_exec(cbm_turtle *t, int cmd, double *params, int nparams)
{
    tstate *s = &t->cur;
    const cbm_view *v = t->view;
    t->module_index++;
    if (cmd < CBM_T_QUERY_P || cmd > CBM_T_QUERY_Q) {
        for (int i = 0; i < nparams; i++)
            if (!isfinite(params[i]))
                return cbm__fail(t->ctx, CBM_E_NONFINITE,
                                 "turtle: parameter %d of module %lld is %g", i + 1,
                                 (long long)t->module_index, params[i]);
    }
    if (t->cut_depth > 0) {
        if (cmd == CBM_T_PUSH)
            t->cut_depth++;
        if (cmd != CBM_T_POP || --t->cut_depth > 0)
            return CBM_OK;
        /* the ] closing the cut branch is interpreted */
    }
    switch (cmd) {
    case CBM_T_NONE:
        return CBM_OK;
    case CBM_T_F:
    case CBM_T_f:
    case CBM_T_G:
    case CBM_T_g:
        return move(t, cmd, params, nparams);
    case CBM_T_LEFT:
    case CBM_T_RIGHT: {
        double sn, cs;
        turn_angle(t, params, nparams, &sn, &cs);
        rotate_pair(&s->h, &s->l, cmd == CBM_T_LEFT ? sn : -sn, cs);
        return CBM_OK;
    }
    case CBM_T_PITCH_DOWN:
    case CBM_T_PITCH_UP: {
        double sn, cs;
        turn_angle(t, params, nparams, &sn, &cs);
        rotate_pair(&s->h, &s->u, cmd == CBM_T_PITCH_DOWN ? sn : -sn, cs);
        return CBM_OK;
    }
    case CBM_T_ROLL_RIGHT:
    case CBM_T_ROLL_LEFT: {
        double sn, cs;
        turn_angle(t, params, nparams, &sn, &cs);
        rotate_pair(&s->l, &s->u, cmd == CBM_T_ROLL_RIGHT ? sn : -sn, cs);
        return CBM_OK;
    }
    case CBM_T_TURN_AROUND:
        rotate_pair(&s->h, &s->l, 0.0, -1.0);
        return CBM_OK;
    case CBM_T_PUSH: {
        CBM_TRY(end_node(t));
        if (t->stack.len >= cbm_context_limits(t->ctx)->max_modules)
            return cbm__fail(t->ctx, CBM_E_LIMIT, "turtle: branches nested deeper than %zu",
                             t->stack.len);
        s->spl_mark = (int)t->splines.len;
        CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->stack, *s));
        s->seg_branched = true; /* the branch's first segment starts a lateral axis */
        if (s->spl >= 0) {
            /* the branch continues a copy of the open spline cylinder */
            spline copy = t->splines.data[s->spl];
            CBM_TRY(CBM_ARRAY_PUSH(t->ctx, t->splines, copy));
            s->spl = (int)t->splines.len - 1;
        }
        return CBM_OK;
    }
    case CBM_T_POP: {
        CBM_TRY(end_node(t));
        if (t->stack.len == 0)
            return CBM_OK; /* cpfg: unmatched ] ignored */
        *s = t->stack.data[--t->stack.len];
        t->splines.len = (size_t)s->spl_mark;
        return CBM_OK;
    }
    case CBM_T_WIDTH:
    case CBM_T_WIDTH_INC: {
        if (nparams > 0)
            s->width = (float)(params[0] * s->scale);
        else if (cmd == CBM_T_WIDTH)
            s->width -= v->width_inc * s->scale;
        else
            s->width += v->width_inc * s->scale;
        if (s->width < 0.0000001f)
            s->width = 0.0000001f;
        s->width_up = s->width;
        return CBM_OK;
    }
    case CBM_T_COLOR_INC:
    case CBM_T_COLOR_DEC:
        if (nparams > 0)
            s->color = cbm__to_int(params[0]);
        else
            s->color += cmd == CBM_T_COLOR_INC ? v->color_inc : -v->color_inc;
        if (s->color < 0)
            s->color += 256;
        if (s->color > 255)
            s->color -= 256;
        return CBM_OK;
    case CBM_T_ELASTICITY:
        if (nparams > 0)
            s->elasticity = (float)params[0];
        else
            s->elasticity += v->elasticity_inc;
        return CBM_OK;
    case CBM_T_SURFACE:
        return end_node(t); /* the surface comes with the next module (cbm__turtle_surface) */
    case CBM_T_CUT:
        /* cpfg cuts when deriving; the turtle skips the rest of the branch only with
         * "interpretation past %: off". The parametric % belongs to environment programs. */
        if (nparams == 0 && !v->past_cut)
            t->cut_depth = 1;
        return CBM_OK;
    case CBM_T_POLY_BEGIN:
        CBM_TRY(end_node(t));
        if (nparams > 0 && params[0] != 0.0)
            return spline_open(t, params, nparams); /* cpfg's spline cylinder {(n) */
        return CBM_ARRAY_PUSH(t->ctx, t->polystart, t->polypts.len);
    case CBM_T_POLY_END:
        if (nparams > 0 && params[0] != 0.0)
            return spline_close(t); /* as cpfg, without ending the segment in progress */
        return poly_end(t);
    case CBM_T_POLY_VERTEX:
        if (t->polystart.len > 0)
            return poly_vertex(t);
        if (s->spl >= 0)
            return spline_point(t, gc_snapshot(s), nparams > 0 ? cbm__to_int(params[0]) : 0);
        return CBM_OK;
    case CBM_T_SUBLSYS_BEGIN:
    case CBM_T_SUBLSYS_END:
        return sublsys_scale(t, cmd, params, nparams);
    default:
        break;
    }
    return exec_at(t, cmd, params, nparams);
}

cbm_status cbm__turtle_finish(cbm_turtle *t)
{
    t->cut_depth = 0;
    t->nprefix = 0;
    CBM_TRY(end_node(t));
    while (t->polystart.len > 0)
        CBM_TRY(poly_end(t));
    return CBM_OK;
}

/* ---- single-symbol modules (cpfg's string) ---- */

cbm_status cbm__turtle_feed(cbm_turtle *t, int symbol, double *params, int nparams)
{
    if (t->nprefix == 0) {
        switch (symbol) {
        case '@':
            t->prefix[0] = '@';
            t->nprefix = 1;
            /* cpfg ends the current segment at every @ */
            if (t->cut_depth == 0)
                return end_node(t);
            return CBM_OK;
        case '?':
            if (nparams > 0) /* cpfg's sub-L-system ?(id, s): not a query */
                return cbm__turtle_exec(t, CBM_T_SUBLSYS_BEGIN, params, nparams);
            t->prefix[0] = '?';
            t->nprefix = 1;
            return CBM_OK;
        case '~':
            t->prefix[0] = '~';
            t->nprefix = 1;
            return cbm__turtle_exec(t, CBM_T_SURFACE, params, nparams);
        case '$':
            return cbm__turtle_exec(t, CBM_T_SUBLSYS_END, params, nparams);
        default: {
            char c = (char)symbol;
            int cmd = cbm__turtle_lookup(&c, 1);
            if (cmd == CBM_T_NONE) {
                t->module_index++;
                return CBM_OK;
            }
            return cbm__turtle_exec(t, cmd, params, nparams);
        }
        }
    }
    char name[4];
    memcpy(name, t->prefix, (size_t)t->nprefix);
    name[t->nprefix] = (char)symbol;
    size_t len = (size_t)t->nprefix + 1;
    if (t->prefix[0] == '~') {
        t->nprefix = 0;
        return cbm__turtle_surface(t, name + 1, 1, params, nparams);
    }
    /* @T, @G, @m, @P, @D, @b take a sub-symbol when they have no parameter (cpfg) */
    if (t->prefix[0] == '@' && t->nprefix == 1 && nparams == 0 && symbol != 0 &&
        strchr("TGmPDb", symbol)) {
        t->prefix[1] = (char)symbol;
        t->nprefix = 2;
        return CBM_OK;
    }
    t->nprefix = 0;
    int cmd = cbm__turtle_lookup(name, len);
    if (cmd == CBM_T_NONE) {
        t->module_index++;
        return CBM_OK; /* an @ or ? function we do not draw */
    }
    return cbm__turtle_exec(t, cmd, params, nparams);
}

/* ---- public API ---- */

cbm_turtle_def cbm_turtle_def_default(void)
{
    cbm_turtle_def d;
    memset(&d, 0, sizeof d);
    d.record = true;
    return d;
}

cbm_status cbm_turtle_interpret(cbm_context *ctx, const cbm_view *view, const cbm_turtle_def *def,
                                cbm_tmodule *mods, size_t n, cbm_scene *scene, cbm_turtle **out)
{
    if (!ctx || !view || (!mods && n) || !out)
        return CBM_E_INVALID;
    *out = NULL;
    cbm_turtle *t;
    CBM_TRY(cbm__turtle_create(ctx, view, scene, &t));
    t->record = def ? def->record : true;
    cbm_status s = CBM_OK;
    for (size_t i = 0; i < n && s == CBM_OK; i++) {
        const char *nm = mods[i].name ? mods[i].name : "";
        if (strlen(nm) == 1 || t->nprefix > 0) {
            /* cpfg's single symbols: @, ? and ~ combine with the next modules */
            s = cbm__turtle_feed(t, (unsigned char)nm[0], mods[i].params, mods[i].nparams);
            continue;
        }
        int cmd = cbm__turtle_lookup(nm, strlen(nm));
        if (cmd != CBM_T_NONE)
            s = cbm__turtle_exec(t, cmd, mods[i].params, mods[i].nparams);
    }
    if (s == CBM_OK)
        s = cbm__turtle_finish(t);
    if (s != CBM_OK) {
        cbm__turtle_destroy(t);
        return s;
    }
    *out = t;
    return CBM_OK;
}

void cbm_turtle_destroy(cbm_turtle *t)
{
    cbm__turtle_destroy(t);
}

size_t cbm_turtle_pixel_segments(const cbm_turtle *t)
{
    return t ? t->pixel_segments : 0;
}

size_t cbm_turtle_prim_count(const cbm_turtle *t)
{
    return t ? t->prims.len : 0;
}

const cbm_prim *cbm_turtle_prims(const cbm_turtle *t)
{
    return t ? t->prims.data : NULL;
}

const cbm_vec3 *cbm_turtle_points(const cbm_turtle *t)
{
    return t ? t->pts.data : NULL;
}

bool cbm_turtle_box(const cbm_turtle *t, cbm_vec3 *lo, cbm_vec3 *hi)
{
    if (!t || !t->box_set)
        return false;
    if (lo)
        *lo = t->lo;
    if (hi)
        *hi = t->hi;
    return true;
}

void cbm_turtle_state(const cbm_turtle *t, cbm_vec3 *pos, cbm_vec3 *h, cbm_vec3 *l, cbm_vec3 *u,
                      double *width, int *color)
{
    if (pos)
        *pos = t->cur.pos;
    if (h)
        *h = t->cur.h;
    if (l)
        *l = t->cur.l;
    if (u)
        *u = t->cur.u;
    if (width)
        *width = t->cur.width;
    if (color)
        *color = t->cur.color;
}
