/* The contract between the L-system engine (src/lsys) and the turtle (src/turtle).
 *
 * The engine resolves each module symbol to a turtle command once, when it compiles a model
 * (cbm__turtle_lookup), and during interpretation calls cbm__turtle_exec for every module of the
 * string in order, with the module's parameters as doubles. Query modules (?P ?H ?L ?U ?Q) get
 * their parameters written back through `params`. Modules that are not turtle commands are skipped
 * by the engine (lookup returns CBM_T_NONE). `~` hands the module after it to cbm__turtle_surface.
 * An engine whose modules are cpfg's single symbols (`@` `M`(1,2) rather than `@M`(1,2)) calls
 * cbm__turtle_feed for every module instead: it combines `@`, `?` and `~` with what follows.
 *
 * Side files (view file, surfaces, colour maps, materials, function files) are read by the
 * turtle module (src/turtle/...), because the view file configures the turtle; function files
 * are also used by expressions (func(id, x)), through cbm__funcset_eval.
 */
#ifndef CBM_TURTLE_H
#define CBM_TURTLE_H

#include "cambium/geom.h"
#include "cambium/turtle.h"

/* The turtle commands, ABOP and cpfg. The names in comments are the module symbols. */
typedef enum cbm_tcmd {
    CBM_T_NONE = 0,
    CBM_T_F,                 /* F  move forward drawing */
    CBM_T_f,                 /* f  move forward without drawing */
    CBM_T_G,                 /* G  move forward drawing, not a polygon vertex */
    CBM_T_g,                 /* g  move forward, not drawing, not a polygon vertex */
    CBM_T_LEFT,              /* +  turn left */
    CBM_T_RIGHT,             /* -  turn right */
    CBM_T_PITCH_DOWN,        /* &  */
    CBM_T_PITCH_UP,          /* ^  */
    CBM_T_ROLL_LEFT,         /* \  */
    CBM_T_ROLL_RIGHT,        /* /  */
    CBM_T_TURN_AROUND,       /* |  */
    CBM_T_PUSH,              /* [  */
    CBM_T_POP,               /* ]  */
    CBM_T_WIDTH,             /* !  set or decrement width */
    CBM_T_COLOR_INC,         /* ' (ABOP) and ; (cpfg) increment colour index, or set it */
    CBM_T_COLOR_DEC,         /* ,  decrement colour index, or set it (cpfg) */
    CBM_T_WIDTH_INC,         /* #  increment width (cpfg) */
    CBM_T_SURFACE,           /* ~  predefined surface */
    CBM_T_CUT,               /* %  cut the rest of the branch */
    CBM_T_POLY_BEGIN,        /* {  */
    CBM_T_POLY_END,          /* }  */
    CBM_T_POLY_VERTEX,       /* .  */
    CBM_T_ROLL_HORIZ,        /* @v roll to horizontal */
    CBM_T_SPHERE,            /* @O */
    CBM_T_CIRCLE,            /* @o */
    CBM_T_CONTOUR,           /* @c */
    CBM_T_MOVE_TO,           /* @M */
    CBM_T_TROPISM_SET,       /* @Ts */
    CBM_T_GC_START,          /* @Gs */
    CBM_T_GC_CONTROL,        /* @Gc */
    CBM_T_GC_END,            /* @Ge */
    CBM_T_QUERY_P,           /* ?P */
    CBM_T_QUERY_H,           /* ?H */
    CBM_T_QUERY_L,           /* ?L */
    CBM_T_QUERY_U,           /* ?U */
    CBM_T_QUERY_Q,           /* ?Q: the frame as a quaternion */
    CBM_T_USER_FIRST = 1000, /* further commands are the turtle module's own business */
    CBM_T_ELASTICITY = CBM_T_USER_FIRST, /* _  set or increment the ABOP tropism elasticity */
    CBM_T_TROPISM_INC,                   /* @Ti(i, de) */
    CBM_T_TROPISM_DEC,                   /* @Td(i, de) */
    CBM_T_CONTOUR_SET,                   /* @#(id) contour of generalized cylinders */
    CBM_T_SIDES_SET,                     /* @!(n) sides of cylinders */
    CBM_T_GC_TANGENT,   /* @Gt(a[,b]) tangent parameters of generalized cylinders */
    CBM_T_GC_RADIUS,    /* @Gr(...) radius tangents of generalized cylinders */
    CBM_T_TWIST_ADJUST, /* @Tp: U follows H from the last drawn segment without twist */
    CBM_T_TWIST_KEEP,   /* @Tf: the current frame becomes the reference of @Tp */
    /* lpfg's commands that cpfg lacks (L+C dialect; no module symbol: the model maps names) */
    CBM_T_SET_HEAD,      /* SetHead(hx,hy,hz, ux,uy,uz): heading and up in lpfg's frame */
    CBM_T_LINE_TO,       /* LineTo3d(x,y,z): a segment to the point, the frame kept */
    CBM_T_LINE_REL,      /* LineRel3d(dx,dy,dz): a segment by the vector, the frame kept */
    CBM_T_MOVE_REL,      /* MoveRel3d(dx,dy,dz): move by the vector without drawing */
    CBM_T_ROLL_TO_VERT,  /* RollToVert: roll so that L is horizontal (-x if H is vertical) */
    CBM_T_SCALE_CONTOUR, /* ScaleContour(p, q): widths of the section along L and U */
    /* the turtle's scale (cpfg manual 6 and 7.2): lengths, widths and sizes are multiplied by it */
    CBM_T_SUBLSYS_BEGIN, /* ?(id, s): a sub-L-system starts; the scale is multiplied by s */
    CBM_T_SUBLSYS_END,   /* $: it ends; the scale returns to the caller's */
    CBM_T_SCALE_SET,     /* @D(s): set the scale */
    CBM_T_SCALE_MUL,     /* @Di(s): multiply the scale by s (by the view's scale multiplier) */
    CBM_T_SCALE_DIV      /* @Dd(s): divide the scale by s (by the view's scale multiplier) */
} cbm_tcmd;

/// The command of a module symbol (name of `len` bytes, e.g. "F", "@Gs", "?P"), or CBM_T_NONE.
int cbm__turtle_lookup(const char *name, size_t len);

/* cbm_view (view file settings), cbm_funcset (function files) and cbm_turtle are declared in
 * include/cambium/turtle.h. */

/// A turtle drawing into `scene` (may be NULL: only queries, the record and the box are kept).
cbm_status cbm__turtle_create(cbm_context *ctx, const cbm_view *view, cbm_scene *scene,
                              cbm_turtle **out);
void cbm__turtle_destroy(cbm_turtle *t);
/// Resets the turtle to its initial state for a new pass over a string.
void cbm__turtle_reset(cbm_turtle *t);
/// Executes one module. params may be written (query modules).
cbm_status cbm__turtle_exec(cbm_turtle *t, int cmd, double *params, int nparams);
/// Finishes the pass (ends the last segment, closes open polygons).
cbm_status cbm__turtle_finish(cbm_turtle *t);
/// `~` (CBM_T_SURFACE) names its surface with the module that follows it (`~l(2)`: the module
/// `l` with parameter 2 is the surface `l` scaled by 2; 3 parameters scale x, y, z). The engine
/// calls cbm__turtle_exec for `~`, then this function with the next module instead of executing
/// that module.
cbm_status cbm__turtle_surface(cbm_turtle *t, const char *name, size_t len, const double *params,
                               int nparams);
/// Executes one module of cpfg's string, where modules are single symbols: `@`, `?` and `~` take
/// the following module(s) as their function, as cpfg reads its string (`@` `O`(2) is @O(2);
/// `@` `T` `s`(1,0) is @Ts(1,0) since @T, @G, @m, @P, @D, @b without parameter take a second
/// symbol; `?` `P`(x,y,z) is ?P; `~` `l`(2) is surface l scaled by 2). Other symbols are looked
/// up and executed; symbols that are not turtle commands are skipped. An engine with one-character
/// symbols can call this for every module instead of lookup + exec.
cbm_status cbm__turtle_feed(cbm_turtle *t, int symbol, double *params, int nparams);
/// The query pass's short cut (cbm_model_step): a branch of cpfg's string that holds no query
/// and only modules for which cbm__turtle_branch_local is true (after_at: the module follows a
/// parameterless `@`), all parameters finite, leaves every query of the pass as it would be: a
/// turtle for which cbm__turtle_may_pass_over is true (no scene, no record, cpfg's turtle, no
/// `@`/`?` waiting, no cut, polygon or spline cylinder open) may be given, for that branch,
/// cbm__turtle_pass_over with the number of turtle modules it holds (a `@` and its command are
/// one), instead of the branch. Its state after is the state cbm__turtle_feed would leave.
bool cbm__turtle_branch_local(int symbol, bool after_at);
bool cbm__turtle_may_pass_over(const cbm_turtle *t);
cbm_status cbm__turtle_pass_over(cbm_turtle *t, int64_t modules);
/// Keep a record of the primitives/// Keep a record of the primitives (cylinders, polygons, ...;
/// see cbm_turtle_prims). Off by default.
void cbm__turtle_set_record(cbm_turtle *t, bool record);

/// lpfg's initial state (L+C models): colour index 1 instead of the view's, as lpfg's turtle.
/// Takes effect at the next cbm__turtle_reset.
void cbm__turtle_set_lpfg(cbm_turtle *t, bool lpfg);
/// lpfg's view-file setting "corrected rotation:" (on unless the view file says off).
bool cbm__view_lpfg_corrected(const cbm_view *view);

/// lpfg's function evaluation for the view's functions (L+C models): tabulated with lpfg's
/// bisection tolerance, 0.01 / samples in x, rather than cpfg's 0.001.
void cbm__view_lpfg_functions(cbm_view *view);

/// Value of function `id` (1-based, in the order the function files were given, as cpfg) at x.
double cbm__funcset_eval(const cbm_funcset *fs, int id, double x);

#endif
