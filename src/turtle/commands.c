/* The turtle's commands (docs/turtle.md): the table of their names (cbm__turtle_lookup) and
 * their execution, module by module (cbm__turtle_exec, and cbm__turtle_feed for cpfg's string of
 * single-symbol modules). The state they act on is in turtle_internal.h. */
#include "turtle_internal.h"

#include <stdio.h>

/* ---- lookup ---- */

typedef struct tname {
    const char *name;
    size_t len; /* strlen(name): compared first, without a strlen per entry and module */
    int cmd;
} tname;

#define TNAME(s, cmd)                                                                              \
    {                                                                                              \
        (s), sizeof(s) - 1, (cmd)                                                                  \
    }

/* The commands of two characters, by their second one: cpfg's @ and ? prefixes with their
 * symbol (cbm__turtle_feed looks one up for every @ module of a string). */
static const int16_t at_names[128] = {
    ['v'] = CBM_T_ROLL_HORIZ, ['O'] = CBM_T_SPHERE,    ['o'] = CBM_T_CIRCLE,
    ['c'] = CBM_T_CONTOUR,    ['M'] = CBM_T_MOVE_TO,   ['#'] = CBM_T_CONTOUR_SET,
    ['!'] = CBM_T_SIDES_SET,  ['D'] = CBM_T_SCALE_SET,
};
static const int16_t query_names[128] = {
    ['P'] = CBM_T_QUERY_P, ['H'] = CBM_T_QUERY_H, ['L'] = CBM_T_QUERY_L,
    ['U'] = CBM_T_QUERY_U, ['Q'] = CBM_T_QUERY_Q,
};

/* The commands of three characters. */
static const tname names[] = {
    TNAME("@Ts", CBM_T_TROPISM_SET),  TNAME("@Ti", CBM_T_TROPISM_INC),
    TNAME("@Td", CBM_T_TROPISM_DEC),  TNAME("@Gs", CBM_T_GC_START),
    TNAME("@Gc", CBM_T_GC_CONTROL),   TNAME("@Ge", CBM_T_GC_END),
    TNAME("@Gt", CBM_T_GC_TANGENT),   TNAME("@Gr", CBM_T_GC_RADIUS),
    TNAME("@Tp", CBM_T_TWIST_ADJUST), TNAME("@Tf", CBM_T_TWIST_KEEP),
    TNAME("@Di", CBM_T_SCALE_MUL),    TNAME("@Dd", CBM_T_SCALE_DIV),
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
    if (len == 2) {
        unsigned char c = (unsigned char)name[1];
        if (c >= 128)
            return CBM_T_NONE;
        return name[0] == '@' ? at_names[c] : name[0] == '?' ? query_names[c] : CBM_T_NONE;
    }
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++)
        if (names[i].len == len && names[i].name[1] == name[1] &&
            memcmp(names[i].name, name, len) == 0) /* the second byte tells most */
            return names[i].cmd;
    return CBM_T_NONE;
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
    CBM_TRY(cbm__turtle_push_prim(t, &pr));
    if (cmd == CBM_T_SPHERE) {
        for (int i = 0; i < 8; i++)
            cbm__turtle_box_add(t, v3(s->pos.x + ((i & 1) ? r : -r), s->pos.y + ((i & 2) ? r : -r),
                                      s->pos.z + ((i & 4) ? r : -r)));
    } else {
        for (int i = 0; i < 4; i++)
            cbm__turtle_box_add(
                t, v3(s->pos.x + ((i & 1) ? r : -r), s->pos.y + ((i & 2) ? r : -r), s->pos.z));
    }
    if (!t->scene || !(r > 0))
        return CBM_OK;
    cbm_part part =
        cbm__turtle_make_part(t, cmd == CBM_T_SPHERE ? CBM_ORGAN_FRUIT : CBM_ORGAN_OTHER, s->color);
    CBM_TRY(cbm_scene_begin_part(t->scene, &part, NULL));
    /* at least 16 slices (fewer show as polygons in a picture) and at most SPHERE_MAX_SLICES:
     * a sphere is slices x slices / 2 vertices, and `contour sides` (up to 1024 for
     * cylinders, whose work is linear in it) would make one sphere a million triangles */
    if (cmd == CBM_T_SPHERE)
        return cbm_scene_add_sphere(t->scene, s->pos, r,
                                    s->sides < 16                  ? 16
                                    : s->sides > SPHERE_MAX_SLICES ? SPHERE_MAX_SLICES
                                                                   : s->sides);
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
    cbm__turtle_movements(t);
    CBM_TRY(cbm__turtle_end_node(t));
    double len = param0(params, nparams, t->view->step) * s->scale;
    bool draw = cmd == CBM_T_F || cmd == CBM_T_G;
    if (draw)
        cbm__turtle_start_node(t);
    s->pos = v3_madd(s->pos, s->h, len);
    if (!v3_isfinite(s->pos))
        return cbm__fail(t->ctx, CBM_E_NONFINITE,
                         "turtle: the position is no longer finite at module %lld",
                         (long long)t->module_index);
    cbm__turtle_bend(t);
    if (t->polystart.len > 0 && (cmd == CBM_T_F || cmd == CBM_T_f))
        CBM_TRY(poly_vertex(t));
    if (s->spl >= 0 && (cmd == CBM_T_F || cmd == CBM_T_f))
        CBM_TRY(cbm__turtle_spline_point(t, cbm__turtle_gc_snapshot(s), 0));
    if (draw && t->lpfg) {
        /* lpfg draws each F at once as a cylinder of the current width */
        t->node_open = false;
        cbm__turtle_box_add(t, s->pos);
        CBM_TRY(cbm__turtle_emit_segment_e(t, t->node_p, s->pos, t->node_w, t->node_w, t->node_wup,
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
    CBM_TRY(cbm__turtle_end_node(t));
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
            CBM_TRY(cbm__turtle_push_prim(t, &pr));
        }
        if (t->scene) {
            cbm_part part = cbm__turtle_make_part(t, CBM_ORGAN_LEAF, pr.color);
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
        CBM_TRY(cbm__turtle_end_node(t));
    } else if (cmd >= CBM_T_USER_FIRST && cmd != CBM_T_ELASTICITY) {
        CBM_TRY(cbm__turtle_end_node(t));
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
        CBM_TRY(cbm__turtle_end_node(t));
        if (nparams >= 3) {
            s->pos = v3_add(s->pos, v3(params[0], params[1], params[2]));
            cbm__turtle_box_add(t, s->pos);
        }
        return CBM_OK;
    case CBM_T_MOVE_TO:
        if (nparams >= 2) {
            s->pos = v3(params[0], params[1], nparams >= 3 ? params[2] : 0.0);
            cbm__turtle_box_add(t, s->pos);
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
        s->gc = cbm__turtle_gc_snapshot(s);
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
            s->gc = cbm__turtle_gc_snapshot(s);
            return CBM_OK;
        }
        CBM_TRY(cbm__turtle_gc_connect(t, rings));
        if (cmd == CBM_T_GC_END)
            s->gc_on = false;
        return CBM_OK;
    }
    case CBM_T_TWIST_ADJUST:
        cbm__turtle_adjust_up_and_left(s);
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
        cbm__turtle_turn_angle(t, params, nparams, &sn, &cs);
        cbm__turtle_rotate_pair(&s->h, &s->l, cmd == CBM_T_LEFT ? sn : -sn, cs);
        return CBM_OK;
    }
    case CBM_T_PITCH_DOWN:
    case CBM_T_PITCH_UP: {
        double sn, cs;
        cbm__turtle_turn_angle(t, params, nparams, &sn, &cs);
        cbm__turtle_rotate_pair(&s->h, &s->u, cmd == CBM_T_PITCH_DOWN ? sn : -sn, cs);
        return CBM_OK;
    }
    case CBM_T_ROLL_RIGHT:
    case CBM_T_ROLL_LEFT: {
        double sn, cs;
        cbm__turtle_turn_angle(t, params, nparams, &sn, &cs);
        cbm__turtle_rotate_pair(&s->l, &s->u, cmd == CBM_T_ROLL_RIGHT ? sn : -sn, cs);
        return CBM_OK;
    }
    case CBM_T_TURN_AROUND:
        cbm__turtle_rotate_pair(&s->h, &s->l, 0.0, -1.0);
        return CBM_OK;
    case CBM_T_PUSH: {
        CBM_TRY(cbm__turtle_end_node(t));
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
        CBM_TRY(cbm__turtle_end_node(t));
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
        return cbm__turtle_end_node(
            t); /* the surface comes with the next module (cbm__turtle_surface) */
    case CBM_T_CUT:
        /* cpfg cuts when deriving; the turtle skips the rest of the branch only with
         * "interpretation past %: off". The parametric % belongs to environment programs. */
        if (nparams == 0 && !v->past_cut)
            t->cut_depth = 1;
        return CBM_OK;
    case CBM_T_POLY_BEGIN:
        CBM_TRY(cbm__turtle_end_node(t));
        if (nparams > 0 && params[0] != 0.0)
            return cbm__turtle_spline_open(t, params, nparams); /* cpfg's spline cylinder {(n) */
        return CBM_ARRAY_PUSH(t->ctx, t->polystart, t->polypts.len);
    case CBM_T_POLY_END:
        if (nparams > 0 && params[0] != 0.0)
            return cbm__turtle_spline_close(
                t); /* as cpfg, without ending the segment in progress */
        return poly_end(t);
    case CBM_T_POLY_VERTEX:
        if (t->polystart.len > 0)
            return poly_vertex(t);
        if (s->spl >= 0)
            return cbm__turtle_spline_point(t, cbm__turtle_gc_snapshot(s),
                                            nparams > 0 ? cbm__to_int(params[0]) : 0);
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
    CBM_TRY(cbm__turtle_end_node(t));
    while (t->polystart.len > 0)
        CBM_TRY(poly_end(t));
    return CBM_OK;
}

/* ---- branches a query pass may pass over ---- */

/* The modules of cpfg's string that act only on the turtle's state (tstate, which the `]` of
 * their branch restores), on what a pass without scene or record does not keep (the segment in
 * progress, the box), on the turn angle's cache, or on nothing: the turns, `[` `]`, width and
 * colour, and the symbols that are no command. Not the moves (F f G g: a position that stops
 * being finite is an error), nor `%`, `{` `}` `.`, `~`, `_`, `$`, `?`, whose effects outlive the
 * branch or are the point of the pass. After a parameterless `@`, the commands @M @O @o @c @v. */
static const bool branch_local_single[128] = {
    ['+'] = true, ['-'] = true, ['&'] = true, ['^'] = true,  ['\\'] = true,
    ['/'] = true, ['|'] = true, ['['] = true, [']'] = true,  ['!'] = true,
    ['#'] = true, [';'] = true, [','] = true, ['\''] = true,
};
static const bool branch_local_at[128] = {
    ['M'] = true, ['O'] = true, ['o'] = true, ['c'] = true, ['v'] = true,
};

bool cbm__turtle_branch_local(int symbol, bool after_at)
{
    if (symbol <= 0 || symbol >= 128)
        return false;
    if (after_at)
        return branch_local_at[symbol];
    if (branch_local_single[symbol])
        return true;
    char c = (char)symbol;
    return symbol != '@' && symbol != '?' && symbol != '~' && symbol != '$' &&
           cbm__turtle_lookup(&c, 1) == CBM_T_NONE;
}

bool cbm__turtle_may_pass_over(const cbm_turtle *t)
{
    return !t->scene && !t->record && !t->lpfg && t->nprefix == 0 && t->cut_depth == 0 &&
           t->polystart.len == 0 && t->cur.spl < 0;
}

cbm_status cbm__turtle_pass_over(cbm_turtle *t, int64_t modules)
{
    /* what the branch's `[` and `]` do outside the state: the segment in progress ended (`[`
     * ends it; the one the branch opens, `]` ends), every module counted */
    t->module_index += modules;
    return cbm__turtle_end_node(t);
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
                return cbm__turtle_end_node(t);
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
