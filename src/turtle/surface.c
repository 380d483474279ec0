/* Predefined surfaces (.s, cpfg's patch format) and contours (.con).
 *
 * A surface file starts with the extents line, then CONTACT POINT, END POINT, HEADING, UP and
 * SIZE, then patches: a name line, a colour line, three neighbour lines and 16 control points
 * (4 rows of 4 "x y z") of a bicubic Bezier patch (tensor product of cubic Bernstein polynomials).
 * As cpfg, every point is moved so the contact point is at the origin, scaled by
 * (view size / SIZE), and expressed in the surface's frame (L = H x U, then U = L x H, with H and
 * U normalised); the turtle then places the point X, Y, Z at P + X L + Y H + Z U. Each patch is
 * tessellated once into a (n+1) x (n+1) grid of vertices with normals from the cross product of
 * the partial derivatives.
 *
 * A contour file ("cver 1 1" to "cver 1 3": name:, points: N M, type: (o|c)..., samples:, then N
 * lines "x y z multiplicity"; or the old "N dim open|closed" then N points) gives the control
 * points of a uniform cubic B-spline cross-section, open or closed; the turtle resamples it.
 */
#include "turtle_internal.h"

#include "../core/vecmath.h"

#include <stdio.h>
#include <stdlib.h>

void cbm__surface_free(cbm_context *ctx, cbm__surface *s)
{
    CBM_ARRAY_FREE(ctx, s->pos);
    CBM_ARRAY_FREE(ctx, s->nrm);
    CBM_ARRAY_FREE(ctx, s->tri);
    CBM_ARRAY_FREE(ctx, s->ctrl);
}

static bool getline_(const char **p, char *buf, size_t cap, int *line)
{
    if (!**p)
        return false;
    size_t n = 0;
    while (**p && **p != '\n') {
        if (n + 1 < cap && **p != '\r')
            buf[n++] = **p;
        (*p)++;
    }
    if (**p == '\n')
        (*p)++;
    buf[n] = '\0';
    (*line)++;
    return true;
}

static double bern(int i, double t)
{
    double s = 1 - t;
    switch (i) {
    case 0:
        return s * s * s;
    case 1:
        return 3 * t * s * s;
    case 2:
        return 3 * t * t * s;
    default:
        return t * t * t;
    }
}

static double dbern(int i, double t)
{
    double s = 1 - t;
    switch (i) {
    case 0:
        return -3 * s * s;
    case 1:
        return 3 * s * s - 6 * t * s;
    case 2:
        return 6 * t * s - 3 * t * t;
    default:
        return 3 * t * t;
    }
}

static cbm_status fmt_err(cbm_context *ctx, const char *path, int line, const char *what)
{
    cbm__diag(ctx, CBM_ERROR, path, line, 1, "%s", what);
    return CBM_E_FORMAT;
}

cbm_status cbm__surface_read(cbm_context *ctx, const char *path, const char *text, double size,
                             int sprec, int tprec, cbm__surface *s)
{
    memset(s, 0, sizeof *s);
    const char *p = text;
    int line = 0;
    char buf[512];
    float x, y, z;
    cbm_vec3 cp, ep, hd, up;
    float maxdim;
    if (!getline_(&p, buf, sizeof buf, &line))
        return fmt_err(ctx, path, 1, "empty surface file");
    if (!getline_(&p, buf, sizeof buf, &line))
        return fmt_err(ctx, path, line, "expected CONTACT POINT");
    /* precision: the view's, else the file's PRECISION line, else 5; as cpfg, a missing t
     * precision takes the file's (or default) s precision */
    int fs = 5;
    if (strstr(buf, "PRECISION")) {
        int a = 0, b = 0;
        if (sscanf(buf, " PRECISION S: %d T: %d", &a, &b) == 2)
            fs = a;
        if (!getline_(&p, buf, sizeof buf, &line))
            return fmt_err(ctx, path, line, "expected CONTACT POINT");
    }
    if (sprec <= 0)
        sprec = fs;
    if (tprec <= 0)
        tprec = fs;
    sprec = sprec < 1 ? 1 : sprec > 10 ? 10 : sprec;
    tprec = tprec < 1 ? 1 : tprec > 10 ? 10 : tprec;
    if (sscanf(buf, " CONTACT POINT X: %f Y: %f Z: %f", &x, &y, &z) != 3)
        return fmt_err(ctx, path, line, "expected 'CONTACT POINT  X: x Y: y Z: z'");
    cp = v3(x, y, z);
    if (!getline_(&p, buf, sizeof buf, &line) ||
        sscanf(buf, " END POINT X: %f Y: %f Z: %f", &x, &y, &z) != 3)
        return fmt_err(ctx, path, line, "expected 'END POINT  X: x Y: y Z: z'");
    ep = v3(x, y, z);
    if (!getline_(&p, buf, sizeof buf, &line) ||
        sscanf(buf, " HEADING X: %f Y: %f Z: %f", &x, &y, &z) != 3)
        return fmt_err(ctx, path, line, "expected 'HEADING  X: x Y: y Z: z'");
    hd = v3_normalize(v3(x, y, z));
    if (!getline_(&p, buf, sizeof buf, &line) ||
        sscanf(buf, " UP X: %f Y: %f Z: %f", &x, &y, &z) != 3)
        return fmt_err(ctx, path, line, "expected 'UP  X: x Y: y Z: z'");
    up = v3_normalize(v3(x, y, z));
    if (!getline_(&p, buf, sizeof buf, &line) || sscanf(buf, " SIZE: %f", &maxdim) != 1 ||
        !(maxdim > 0))
        return fmt_err(ctx, path, line, "expected 'SIZE: s' with s > 0");
    if (!v3_isfinite(cp) || !v3_isfinite(ep) || !v3_isfinite(hd) || !v3_isfinite(up) ||
        !isfinite(maxdim) || v3_norm2(hd) == 0.0 || v3_norm2(up) == 0.0)
        return fmt_err(ctx, path, line, "the surface's points and frame must be finite, non-zero");
    cbm_vec3 left = v3_cross(hd, up);
    if (v3_norm2(left) < 1e-24)
        return fmt_err(ctx, path, line, "the surface's HEADING and UP are parallel");
    up = v3_cross(left, hd);
    double k = size / maxdim;
    s->contact = cp;
    s->heading = hd;
    s->up = up;
    s->size = size;
#define XFORM(q)                                                                                   \
    v3_add(v3_add(v3_scale(left, ((q).x - cp.x) * k), v3_scale(hd, ((q).y - cp.y) * k)),           \
           v3_scale(up, ((q).z - cp.z) * k))
    s->end = XFORM(ep);
    const int ns = sprec, nt = tprec;
    for (;;) {
        /* patch header: name, colour line, three neighbour lines */
        if (!getline_(&p, buf, sizeof buf, &line))
            break;
        char *w = buf;
        while (*w == ' ' || *w == '\t')
            w++;
        if (!*w)
            continue;
        for (int i = 0; i < 4; i++)
            if (!getline_(&p, buf, sizeof buf, &line))
                return fmt_err(ctx, path, line, "incomplete patch header");
        cbm_vec3 c[4][4];
        for (int i = 0; i < 4; i++) {
            if (!getline_(&p, buf, sizeof buf, &line))
                return fmt_err(ctx, path, line, "expected 4 rows of control points");
            double v[12];
            const char *q = buf;
            int got = 0;
            while (got < 12) {
                char *end;
                v[got] = strtod(q, &end);
                if (end == q)
                    break;
                q = end;
                got++;
            }
            if (got != 12)
                return fmt_err(ctx, path, line, "expected 4 control points 'x y z' in a row");
            for (int e = 0; e < 12; e++)
                if (!isfinite(v[e]) || fabs(v[e]) > 1e30)
                    return fmt_err(ctx, path, line, "control point is not a finite number");
            for (int j = 0; j < 4; j++) {
                cbm_vec3 raw = v3((float)v[3 * j], (float)v[3 * j + 1], (float)v[3 * j + 2]);
                c[i][j] = XFORM(raw);
                CBM_TRY(CBM_ARRAY_PUSH(ctx, s->ctrl, c[i][j]));
            }
        }
        uint32_t base = (uint32_t)s->pos.len;
        for (int a = 0; a <= ns; a++) {
            double u = (double)a / ns;
            for (int b = 0; b <= nt; b++) {
                double t = (double)b / nt;
                cbm_vec3 P = v3(0, 0, 0), Pu = v3(0, 0, 0), Pt = v3(0, 0, 0);
                for (int i = 0; i < 4; i++)
                    for (int j = 0; j < 4; j++) {
                        P = v3_madd(P, c[i][j], bern(i, u) * bern(j, t));
                        Pu = v3_madd(Pu, c[i][j], dbern(i, u) * bern(j, t));
                        Pt = v3_madd(Pt, c[i][j], bern(i, u) * dbern(j, t));
                    }
                cbm_vec3 N = v3_cross(Pt, Pu);
                if (v3_norm2(N) < 1e-30)
                    N = up;
                CBM_TRY(CBM_ARRAY_PUSH(ctx, s->pos, P));
                CBM_TRY(CBM_ARRAY_PUSH(ctx, s->nrm, v3_normalize(N)));
            }
        }
        for (int a = 0; a < ns; a++)
            for (int b = 0; b < nt; b++) {
                uint32_t i0 = base + (uint32_t)(a * (nt + 1) + b);
                uint32_t i1 = i0 + 1, i2 = i0 + (uint32_t)(nt + 1), i3 = i2 + 1;
                uint32_t tri[6] = {i0, i2, i1, i1, i2, i3};
                for (int m = 0; m < 6; m++)
                    CBM_TRY(CBM_ARRAY_PUSH(ctx, s->tri, tri[m]));
            }
    }
#undef XFORM
    if (s->pos.len == 0) {
        cbm__surface_free(ctx, s);
        return fmt_err(ctx, path, line, "surface file without patches");
    }
    return CBM_OK;
}

static cbm_status push_point(cbm_context *ctx, cbm__contour *c, double x, double y, double z)
{
    CBM_TRY(CBM_ARRAY_PUSH(ctx, c->pts, x));
    CBM_TRY(CBM_ARRAY_PUSH(ctx, c->pts, y));
    return CBM_ARRAY_PUSH(ctx, c->pts, z);
}

cbm_status cbm__contour_read(cbm_context *ctx, const char *path, const char *text, cbm__contour *c)
{
    memset(c, 0, sizeof *c);
    const char *p = text;
    int line = 0;
    char buf[512];
    int vmaj, vmin, npts = -1, dim = 3;
    c->closed = true;
    if (!getline_(&p, buf, sizeof buf, &line))
        return fmt_err(ctx, path, 1, "empty contour file");
    bool versioned = sscanf(buf, "cver %d %d", &vmaj, &vmin) == 2;
    if (!versioned) {
        /* old format: "num dim open|closed", then the points */
        char type[16] = "";
        if (sscanf(buf, "%d %d %15s", &npts, &dim, type) != 3 || (dim != 2 && dim != 3))
            return fmt_err(ctx, path, line, "expected 'cver 1 N' or 'points dimension type'");
        c->closed = strcmp(type, "closed") == 0;
    } else {
        if (vmaj != 1 || vmin < 1 || vmin > 3)
            return fmt_err(ctx, path, line, "unsupported contour version (cver 1 1 to 1 3)");
        /* header lines up to the first point */
        const char *save = p;
        int save_line = line;
        while (getline_(&p, buf, sizeof buf, &line)) {
            double x, y, z, m;
            if (sscanf(buf, "%lf %lf %lf %lf", &x, &y, &z, &m) == 4) {
                p = save;
                line = save_line;
                break;
            }
            int a, b;
            char type[16];
            if (sscanf(buf, "points: %d %d", &a, &b) >= 1)
                npts = a;
            else if (sscanf(buf, "type: %15s", type) == 1)
                c->closed = type[0] == 'c';
            save = p;
            save_line = line;
        }
    }
    if (npts < 1 || npts > 100000)
        return fmt_err(ctx, path, line, "expected the number of points ('points: N')");
    for (int i = 0; i < npts; i++) {
        if (!getline_(&p, buf, sizeof buf, &line))
            return fmt_err(ctx, path, line, "fewer contour points than announced");
        double x = 0, y = 0, z = 0, m = 1;
        int got = sscanf(buf, "%lf %lf %lf %lf", &x, &y, &z, &m);
        int want = versioned ? 4 : dim;
        if (got < want)
            return fmt_err(ctx, path, line,
                           versioned ? "expected a contour point 'x y z multiplicity'"
                                     : "expected a contour point");
        if (!versioned) {
            m = 1;
            if (dim == 2)
                z = 0;
        }
        if (!(m >= 1 && m <= 4))
            return fmt_err(ctx, path, line, "multiplicity must be 1 to 4");
        if (!isfinite(x) || !isfinite(y) || !isfinite(z))
            return fmt_err(ctx, path, line, "contour point is not a finite number");
        for (int k = 0; k < (int)m; k++)
            CBM_TRY(push_point(ctx, c, (float)x, (float)y, (float)z));
    }
    if (c->pts.len / 3 < 4)
        return fmt_err(ctx, path, line, "a contour needs at least 4 control points");
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
    /* a scene in instancing mode keeps the surface once and this placement of it (the .glb
     * writer's instances), not a copy of its vertices */
    bool placed = t->scene && cbm_scene_instancing(t->scene) && nv > 0;
    t->scratch.len = 0;
    CBM_TRY(CBM_ARRAY_RESERVE(t->ctx, t->scratch, nv * 2));
    for (size_t i = 0; i < nv && (t->record || !placed); i++) {
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
        cbm__turtle_box_add(
            t, v3_add(s->pos, v3_add(v3_add(v3_scale(s->l, q.x * sx), v3_scale(s->h, q.y * sy)),
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
        CBM_TRY(cbm__turtle_push_prim(t, &pr));
    }
    if (t->scene) {
        cbm_part part = cbm__turtle_make_part(t, CBM_ORGAN_LEAF, s->color);
        CBM_TRY(cbm_scene_begin_part(t->scene, &part, NULL));
        uint32_t shape = 0;
        if (placed && !cbm_scene_find_shape(t->scene, (uint64_t)(uintptr_t)sf, &shape))
            CBM_TRY(cbm_scene_add_shape(t->scene, (uint64_t)(uintptr_t)sf, sf->pos.data,
                                        sf->nrm.data, nv, sf->tri.data, sf->tri.len / 3, &shape));
        if (placed)
            CBM_TRY(cbm_scene_place_shape(t->scene, shape, s->pos, v3_scale(s->l, k * sx),
                                          v3_scale(s->h, k * sy), v3_scale(s->u, k * sz)));
        else
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
