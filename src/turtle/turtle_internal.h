/* The turtle's state, shared by the files of its interpreter: turtle.c (creation, parts and
 * segments, the public API), commands.c (the command table and the commands), tropism.c,
 * gencyl.c (generalized cylinders), spline.c (cpfg's spline cylinders) and surface.c (surfaces
 * placed by ~). Internal to src/turtle: the other areas use turtle.h. */
#ifndef CBM_TURTLE_INTERNAL_H
#define CBM_TURTLE_INTERNAL_H

#include "view_internal.h"

#include "../core/vecmath.h"

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

/* slices of a sphere at most (`contour sides` above it): a sphere is slices x slices / 2
 * vertices; at 128 its outline departs from the circle by 3e-4 of the radius */
#define SPHERE_MAX_SLICES 128

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

/* cpfg's "change_dir": v2' = c v2 + s v3, v3' = c v3 - s v2 */
static inline void cbm__turtle_rotate_pair(cbm_vec3 *v2, cbm_vec3 *v3p, double s, double c)
{
    cbm_vec3 a = *v2, b = *v3p;
    *v2 = v3(c * a.x + s * b.x, c * a.y + s * b.y, c * a.z + s * b.z);
    *v3p = v3(c * b.x - s * a.x, c * b.y - s * a.y, c * b.z - s * a.z);
}

/* Grows the box of what was drawn by p. */
void cbm__turtle_box_add(cbm_turtle *t, cbm_vec3 p);
/* A scene part of the organ in colour index color, for the module being executed. */
cbm_part cbm__turtle_make_part(const cbm_turtle *t, cbm_organ organ, int color);
/* Records a primitive with its module (a segment also with its parent on the branch path). */
cbm_status cbm__turtle_push_prim(cbm_turtle *t, cbm_prim *p);
/* Sine and cosine of a turn: the module's angle in degrees, else the view's increment. */
void cbm__turtle_turn_angle(cbm_turtle *t, const double *params, int nparams, double *sn,
                            double *cs);
/* A segment in cpfg's terms: dropped when degenerate (length^2 <= 1e-5 or no end width). */
cbm_status cbm__turtle_emit_segment(cbm_turtle *t, cbm_vec3 p0, cbm_vec3 p1, double w0, double w1,
                                    int color, cbm_vec3 h, cbm_vec3 u);
/* The same; wu >= 0: an elliptic section of width w0 along L and wu along U. */
cbm_status cbm__turtle_emit_segment_e(cbm_turtle *t, cbm_vec3 p0, cbm_vec3 p1, double w0, double w1,
                                      double wu, int color, cbm_vec3 h, cbm_vec3 u);
/* The line style segments are drawn in (turtle.c says why for L+C models). */
cbm__line_style cbm__turtle_line_style(const cbm_turtle *t);
/* Opens a segment at the turtle (F, G). */
void cbm__turtle_start_node(cbm_turtle *t);
/* Ends the open segment at the turtle and draws it (a node end). */
cbm_status cbm__turtle_end_node(cbm_turtle *t);
/* ABOP tropism after a move: two rotations towards T (tropism.c). */
void cbm__turtle_bend(cbm_turtle *t);
/* Rotates v about the unit axis n by angle (right hand). */
cbm_vec3 cbm__turtle_rot_axis(cbm_vec3 v, cbm_vec3 n, double angle);
/* U follows H by the minimal rotation from the previous heading; L = H x U. */
void cbm__turtle_adjust_up_and_left(tstate *s);
/* cpfg's movements (the view's tropisms and torques) before a move. */
void cbm__turtle_movements(cbm_turtle *t);
/* cpfg's minimal rotation of a frame from prev_h to h, then -beta about h (gencyl.c). */
void cbm__turtle_adjust_frame(cbm_vec3 h, cbm_vec3 prev_h, cbm_vec3 prev_u, double beta,
                              cbm_vec3 *u, cbm_vec3 *l);
/* Angle by which g2's up must turn about its heading to follow g1 without twist. */
double cbm__turtle_twist_angle(const gcpt *g1, const gcpt *g2);
/* A generalized cylinder's control point from the turtle state. */
gcpt cbm__turtle_gc_snapshot(const tstate *s);
/* The bands between two control points (Hermite, or the B-spline piece bsp). */
cbm_status cbm__turtle_gc_segment(cbm_turtle *t, const gcpt *g1p, const gcpt *g2p, int rings,
                                  const cbm_vec3 *bsp, double twist);
/* A band from the open generalized cylinder's last control point to the turtle. */
cbm_status cbm__turtle_gc_connect(cbm_turtle *t, int rings);
/* {(n, r): opens a spline cylinder of kind n (spline.c). */
cbm_status cbm__turtle_spline_open(cbm_turtle *t, const double *params, int nparams);
/* A control point of the open spline cylinder (F, f, `.`). */
cbm_status cbm__turtle_spline_point(cbm_turtle *t, gcpt p, int rings);
/* }(n): ends the open spline cylinder, closing a closed one. */
cbm_status cbm__turtle_spline_close(cbm_turtle *t);

#endif
