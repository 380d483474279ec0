/* The orthographic camera of the pictures (PNG and SVG), fitted to a scene: every kept vertex and
 * line end is projected on the view plane and the bounding box scaled to a fraction of the
 * drawing area. The ground counts only when there is nothing else to fit. */
#include "writers.h"

#include "../core/vecmath.h"

#include <math.h>

cbm_vec3 cbm__view_direction(const cbm_write_options *o)
{
    cbm_vec3 d;
    switch (o->view) {
    case CBM_VIEW_FRONT:
        d = v3(0, 0, -1);
        break;
    case CBM_VIEW_SIDE:
        d = v3(-1, 0, 0);
        break;
    case CBM_VIEW_TOP:
        d = v3(0, -1, 0);
        break;
    case CBM_VIEW_VECTOR:
        d = o->view_dir;
        break;
    case CBM_VIEW_ISO:
    default:
        d = v3(-1, -0.8, -1);
        break;
    }
    if (!v3_isfinite(d) || v3_norm(d) == 0.0)
        d = v3(-1, -0.8, -1);
    return v3_normalize(d);
}

static bool fit_point(const float *q, cbm_vec3 right, cbm_vec3 up, cbm_vec3 d, double lo[3],
                      double hi[3])
{
    cbm_vec3 pt = v3(q[0], q[1], q[2]);
    double c[3] = {v3_dot(pt, right), v3_dot(pt, up), v3_dot(pt, d)};
    for (int a = 0; a < 3; a++) {
        lo[a] = fmin(lo[a], c[a]);
        hi[a] = fmax(hi[a], c[a]);
    }
    return true;
}

bool cbm__camera_fit(cbm__camera *cam, const cbm_scene *s, const cbm_write_options *o, double w,
                     double h, double cx, double cy, double fill)
{
    cbm_vec3 d = cbm__view_direction(o);
    /* up: world y projected on the view plane; looking straight down, -z is up in the picture */
    cbm_vec3 up = v3_sub(v3(0, 1, 0), v3_scale(d, d.y));
    if (v3_norm(up) < 1e-6)
        up = v3_sub(v3(0, 0, -1), v3_scale(d, -d.z));
    up = v3_normalize(up);
    cbm_vec3 right = v3_cross(d, up);
    cam->dir = d;
    cam->up = up;
    cam->right = right;
    const cbm_scene_vertex *v = cbm_scene_vertices(s);
    const uint32_t *tri = cbm_scene_triangles(s), *tp = cbm_scene_triangle_parts(s);
    const cbm_part *parts = cbm_scene_parts(s);
    size_t nt = cbm_scene_triangle_count(s);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    bool any = false;
    const cbm_scene_line *ln = cbm_scene_lines(s);
    size_t nl = cbm_scene_line_count(s);
    for (int pass = 0; pass < 2 && !any; pass++) {
        /* fit on the plant; on the ground only when there is nothing else */
        for (size_t t = 0; t < nt; t++) {
            const cbm_part *p = &parts[tp[t]];
            if (!cbm__part_kept(p, o) || (pass == 0 && p->organ == CBM_ORGAN_GROUND))
                continue;
            for (int k = 0; k < 3; k++)
                any |= fit_point(v[tri[3 * t + (size_t)k]].p, right, up, d, lo, hi);
        }
        /* lines: their ends (their width in pixels is left to the margin) */
        for (size_t i = 0; i < nl; i++) {
            const cbm_part *p = &parts[ln[i].part];
            if (!cbm__part_kept(p, o) || (pass == 0 && p->organ == CBM_ORGAN_GROUND))
                continue;
            any |= fit_point(ln[i].p0, right, up, d, lo, hi);
            any |= fit_point(ln[i].p1, right, up, d, lo, hi);
        }
    }
    if (!any)
        return false;
    double ex = hi[0] - lo[0], ey = hi[1] - lo[1];
    double sx = ex > 0 ? fill * w / ex : INFINITY, sy = ey > 0 ? fill * h / ey : INFINITY;
    double sc = fmin(sx, sy);
    if (!isfinite(sc))
        sc = fill * fmin(w, h) / 1e-3;
    cam->scale = sc;
    cam->center = v3_add(v3_scale(right, 0.5 * (lo[0] + hi[0])),
                         v3_add(v3_scale(up, 0.5 * (lo[1] + hi[1])), v3_scale(d, lo[2])));
    cam->cx = cx;
    cam->cy = cy;
    cam->depth_min = 0.0;
    return true;
}
