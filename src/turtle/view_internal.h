/* Private declarations of the turtle module: the view settings, the side files they name
 * (function files, surfaces, contours, colour maps, materials) and the readers shared by the
 * files of src/turtle. */
#ifndef CBM_TURTLE_VIEW_INTERNAL_H
#define CBM_TURTLE_VIEW_INTERNAL_H

#include "cambium/turtle.h"
#include "turtle.h"

#include "../core/core.h"

#define CBM__MAX_MOVEMENTS 8 /* tropisms + torques of one view file */
#define CBM__MAX_CONTOURS  64

/* ---- function files (.func): a clamped uniform cubic B-spline y(x) ---- */
typedef struct cbm__func {
    char name[64];
    int npts;        /* control points, multiplicities expanded */
    double *px, *py; /* control points */
    int samples;     /* > 2: values tabulated at `samples` points and interpolated linearly */
    double *vals;
    bool finite;        /* every control point finite (as float): curve points sum 4 terms */
    size_t basis_evals; /* basis functions evaluated while tabulating (the tests bound it) */
} cbm__func;

struct cbm_funcset {
    cbm_context *ctx;
    CBM_ARRAY(cbm__func) funcs;
};
/* Re-tabulates the functions with lpfg's bisection tolerance (0.01 / samples instead of cpfg's
 * 0.001), as lpfg's function files evaluate. */
void cbm__funcset_lpfg(cbm_funcset *fs);

cbm_status cbm__func_read(cbm_context *ctx, const char *path, const char *text, int samples,
                          cbm__func *f);
void cbm__func_free(cbm_context *ctx, cbm__func *f);
/* Appends the functions of a gallery (.fset); on failure the ones read so far stay in fs. */
cbm_status cbm__funcset_read_gallery(cbm_context *ctx, const char *path, const char *text,
                                     cbm_funcset *fs);

/* ---- surfaces (.s): bicubic Bezier patches, tessellated once when read ---- */
typedef struct cbm__surface {
    char id;                  /* the symbol after ~ */
    double size;              /* the view file's size */
    cbm_vec3 contact;         /* contact point (file coordinates) */
    cbm_vec3 end;             /* end point (X, Y, Z below): where the turtle moves after ~ */
    cbm_vec3 heading, up;     /* the surface's own frame */
    CBM_ARRAY(cbm_vec3) pos;  /* tessellated vertices X, Y, Z: placed at P + X L + Y H + Z U */
    CBM_ARRAY(cbm_vec3) nrm;  /* their normals */
    CBM_ARRAY(cbm_vec3) ctrl; /* Bezier control points, same coordinates (cpfg's box) */
    CBM_ARRAY(uint32_t) tri;  /* 3 per triangle */
} cbm__surface;

/* size: the view file's size of the surface; sprec, tprec: cpfg's precisions (grid cells per
 * patch side; 0: the file's or the default). On failure s may hold memory: release it with
 * cbm__surface_free. */
cbm_status cbm__surface_read(cbm_context *ctx, const char *path, const char *text, double size,
                             int sprec, int tprec, cbm__surface *s);
void cbm__surface_free(cbm_context *ctx, cbm__surface *s);

/* ---- contours (.con): cross-section curves, uniform cubic B-splines of control points ---- */
typedef struct cbm__contour {
    int id;
    bool closed;
    CBM_ARRAY(double) pts; /* 3 per control point (x, y, z), multiplicities expanded */
} cbm__contour;

cbm_status cbm__contour_read(cbm_context *ctx, const char *path, const char *text, cbm__contour *c);

/* ---- movements (tropisms and torques of the view file, cpfg's "tropism:" lines) ---- */
typedef struct cbm__movement {
    int torque;            /* 0 tropism, 1 torque ("twist") */
    cbm_vec3 dir;          /* unit vector times intensity */
    double cos_g, sin_g;   /* angle gamma to the direction (A:, degrees in the file) */
    double elasticity;     /* initial elasticity (E:) */
    double elasticity_inc; /* step of @Ti/@Td (S:) */
} cbm__movement;

typedef enum cbm__line_style { CBM__LS_PIXEL, CBM__LS_POLYGON, CBM__LS_CYLINDER } cbm__line_style;

struct cbm_view {
    cbm_context *ctx;
    double angle;        /* angle increment, degrees */
    double sin_a, cos_a; /* of the angle increment */
    double width;        /* initial line width (diameter) */
    double width_inc;    /* line width increment of ! and # without parameter */
    int color;           /* initial colour index */
    int color_inc;       /* colour increment */
    double step;         /* step of F, f without parameter */
    double scale;        /* scale factor of the view (display only; kept) */
    double init_scale;   /* "initial scale:" the turtle's scale at the start (cpfg) */
    double scale_mul;    /* "scale multiplier:" of @Di and @Dd without parameter */
    cbm__line_style line_style;
    bool view_file;        /* a view file (.v) was read: an L+C model then takes its line style */
    int sides;             /* contour sides of cylinders */
    bool gc_twist;         /* twist of cylinders */
    bool past_cut;         /* interpret past % (cpfg's default: the engine cuts when deriving) */
    bool lpfg_uncorrected; /* lpfg's "corrected rotation: off" (Up/Down, RollL/RollR swapped) */
    /* ABOP tropism (T and e of ABOP section 2.2: "tropism direction", "initial elasticity") */
    cbm_vec3 tropism_dir;
    double elasticity, elasticity_inc;
    cbm__movement mov[CBM__MAX_MOVEMENTS];
    int nmov;
    /* side files */
    cbm_funcset funcs;
    CBM_ARRAY(cbm__surface) surfaces;
    CBM_ARRAY(cbm__contour) contours;
    float colors[256][4]; /* linear RGBA of each colour index */
    bool have_colors;
    char dir[512]; /* directory side files are looked up in */
};

/* Side files from text (the file readers and the fuzz targets use these). name is the file's
 * name in messages; a surface's id is name[0]; a contour's id is the count of contours + 1. */
typedef enum cbm__side_kind {
    CBM__SIDE_VIEW,
    CBM__SIDE_FUNC,
    CBM__SIDE_FSET,
    CBM__SIDE_SURFACE,
    CBM__SIDE_CONTOUR
} cbm__side_kind;
cbm_status cbm__view_add_text(cbm_view *v, cbm__side_kind kind, const char *name, const char *text);

/* A double from input as an int: truncated, clamped to +-2e9, NaN as 0 (no undefined casts). */
static inline int cbm__to_int(double x)
{
    if (!(x == x))
        return 0;
    if (x > 2e9)
        return 2000000000;
    if (x < -2e9)
        return -2000000000;
    return (int)x;
}

/* Reads a whole file into memory (NUL-terminated), bytes counted by the context. */
cbm_status cbm__read_file(cbm_context *ctx, const char *path, char **text, size_t *len);
void cbm__free_file(cbm_context *ctx, char *text, size_t len);

#endif
