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
 *
 * This file: the turtle's creation and reset, the parts and segments it draws, the public API.
 * The commands are in commands.c, the tropisms in tropism.c, generalized cylinders in gencyl.c,
 * spline cylinders in spline.c, surfaces in surface.c; their shared state in turtle_internal.h.
 */
#include "turtle_internal.h"

#include <stdio.h>

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

void cbm__turtle_box_add(cbm_turtle *t, cbm_vec3 p)
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

cbm_part cbm__turtle_make_part(const cbm_turtle *t, cbm_organ organ, int color)
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

/* Whether the part cbm__turtle_make_part(t, CBM_ORGAN_BRANCH, color) would build equals `last` but
 * for its segment and parent ids (then a line joins `last`). */
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
cbm_status cbm__turtle_push_prim(cbm_turtle *t, cbm_prim *p)
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
void cbm__turtle_turn_angle(cbm_turtle *t, const double *params, int nparams, double *sn,
                            double *cs)
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

/* ---- segments ---- */

cbm_status cbm__turtle_emit_segment(cbm_turtle *t, cbm_vec3 p0, cbm_vec3 p1, double w0, double w1,
                                    int color, cbm_vec3 h, cbm_vec3 u)
{
    return cbm__turtle_emit_segment_e(t, p0, p1, w0, w1, -1.0, color, h, u);
}

/* The line style segments are drawn in. lpfg's default is pixel, as cpfg's: SetWidth(w) then
 * gives lines w pixels wide in pictures (tubes of diameter w in meshes, as lpfg's and cpfg's
 * OBJ export). An L+C model run without a view file (cambium's own models in models/, written
 * in metres) is drawn with cylinders, as if its view said "line style: cylinder". */
cbm__line_style cbm__turtle_line_style(const cbm_turtle *t)
{
    if (t->lpfg && !t->view->view_file)
        return CBM__LS_CYLINDER;
    return t->view->line_style;
}

/* A segment; wu >= 0: an elliptic section of width w0 along L and wu along U (lpfg's
 * ScaleContour; the record keeps w0 / 2). */
cbm_status cbm__turtle_emit_segment_e(cbm_turtle *t, cbm_vec3 p0, cbm_vec3 p1, double w0, double w1,
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
        CBM_TRY(cbm__turtle_push_prim(t, &pr));
    }
    if (!t->scene)
        return CBM_OK;
    cbm__line_style style = cbm__turtle_line_style(t);
    bool pixel = style == CBM__LS_PIXEL;
    t->pixel_segments += pixel;
    if (pixel && cbm_scene_line_mode(t->scene)) {
        /* a line w0 pixels wide, as cpfg draws pixel lines; a run of segments with the same
         * part data shares one part (the first segment's id), so a line costs 32 bytes */
        size_t np = cbm_scene_part_count(t->scene);
        const cbm_part *last = np ? &cbm_scene_parts(t->scene)[np - 1] : NULL;
        if (!last || !line_part_reused(t, last, color)) {
            cbm_part part = cbm__turtle_make_part(t, CBM_ORGAN_BRANCH, color);
            CBM_TRY(cbm_scene_begin_part(t->scene, &part, NULL));
        }
        return cbm_scene_add_line(t->scene, p0, p1, w0 > 0.0 ? w0 : w1);
    }
    cbm_part part = cbm__turtle_make_part(t, CBM_ORGAN_BRANCH, color);
    /* the cpfg dialect's parts are not changed after the pass (an L+C model's may take its
     * mechanics' stress by segment: cbm_model_interpret), so a run of segments of one order and
     * colour drawn as instances shares one part */
    if (t->lpfg)
        CBM_TRY(cbm_scene_begin_part(t->scene, &part, NULL));
    else
        CBM_TRY(cbm_scene_begin_part_shared(t->scene, &part));
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

cbm_status cbm__turtle_end_node(cbm_turtle *t)
{
    cbm__turtle_box_add(t, t->cur.pos);
    if (!t->node_open)
        return CBM_OK;
    t->node_open = false;
    t->part_module = t->node_module; /* the segment is the F or G that opened it */
    cbm_status st = cbm__turtle_emit_segment(t, t->node_p, t->cur.pos, t->node_w, t->cur.width,
                                             t->node_color, t->node_h, t->node_u);
    t->part_module = -1;
    return st;
}

void cbm__turtle_start_node(cbm_turtle *t)
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
