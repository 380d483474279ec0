/* The view: cpfg's view file (.v) settings that drive the turtle, and the side files attached to
 * a view (function files, surfaces, contours, colour maps, materials), chosen by extension as on
 * cpfg's command line.
 *
 * The view file is read line by line as "label: values" (cpfg manual, "View file"). Settings
 * that only concern cpfg's window (viewpoint, projection, lights, z buffer, ...) are accepted and
 * ignored. Tropisms follow cpfg's "tropism:" and "torque:" lines (T: direction, A: angle gamma
 * in degrees, E: elasticity, S: elasticity step, I: intensity) and the older ABOP ones
 * ("tropism direction:", "initial elasticity:", "elasticity increment:"; ABOP section 2.2).
 * A colour map holds 256 RGB byte triples; a material file holds records of an index byte and 14
 * bytes (transparency, ambient, diffuse, emissive, specular RGB, shininess); we keep the diffuse
 * colour. Colours are converted from sRGB bytes to linear RGB for the scene. Without either,
 * index i is a grey of value i/255, except indices 1-15: a palette of plant colours.
 */
#include "view_internal.h"

#include "../core/vecmath.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>

static float srgb_to_linear(unsigned char c)
{
    double v = c / 255.0;
    return (float)(v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4));
}

static void set_defaults(cbm_view *v)
{
    v->angle = 45.0;
    v->sin_a = sin(45.0 * CBM_PI / 180.0);
    v->cos_a = cos(45.0 * CBM_PI / 180.0);
    v->width = 1.0;
    v->width_inc = 0.0;
    v->color = 128;
    v->color_inc = 1;
    v->step = 1.0;
    v->scale = 1.0;
    v->init_scale = 1.0;
    v->scale_mul = 1.0;
    v->line_style = CBM__LS_PIXEL;
    v->sides = 8;
    v->past_cut = true;
    v->tropism_dir = v3(0, 1, 0);
    v->elasticity = 0.0;
    v->elasticity_inc = 0.0;
    for (int i = 0; i < 256; i++) {
        float g = srgb_to_linear((unsigned char)i);
        v->colors[i][0] = v->colors[i][1] = v->colors[i][2] = g;
        v->colors[i][3] = 1.0f;
    }
    /* the default palette of indices 1-15 (docs/turtle.md): plant colours instead of the near
     * black of the grey ramp; sRGB bytes */
    static const unsigned char pal[15][3] = {
        {110, 75, 45},   /* 1 bark brown */
        {60, 140, 50},   /* 2 leaf green */
        {30, 95, 35},    /* 3 dark green */
        {150, 200, 80},  /* 4 light (young) green */
        {190, 30, 40},   /* 5 red (fruit) */
        {240, 200, 40},  /* 6 yellow (flower) */
        {245, 245, 235}, /* 7 white (petal) */
        {235, 130, 35},  /* 8 orange */
        {130, 60, 150},  /* 9 purple */
        {235, 140, 170}, /* 10 pink */
        {60, 110, 190},  /* 11 blue */
        {185, 145, 95},  /* 12 light wood */
        {70, 45, 30},    /* 13 dark brown */
        {128, 128, 128}, /* 14 grey */
        {20, 20, 20},    /* 15 black */
    };
    for (int i = 0; i < 15; i++)
        for (int c = 0; c < 3; c++)
            v->colors[i + 1][c] = srgb_to_linear(pal[i][c]);
}

static void set_angle(cbm_view *v, double deg)
{
    v->angle = deg;
    v->sin_a = sin(deg * CBM_PI / 180.0);
    v->cos_a = cos(deg * CBM_PI / 180.0);
}

cbm_status cbm_view_create(cbm_context *ctx, cbm_view **out)
{
    if (!ctx || !out)
        return CBM_E_INVALID;
    *out = NULL;
    cbm_view *v = cbm__calloc(ctx, 1, sizeof *v);
    if (!v)
        return CBM_E_NOMEM;
    v->ctx = ctx;
    v->funcs.ctx = ctx;
    set_defaults(v);
    snprintf(v->dir, sizeof v->dir, ".");
    *out = v;
    return CBM_OK;
}

void cbm_view_destroy(cbm_view *v)
{
    if (!v)
        return;
    cbm_context *ctx = v->ctx;
    for (size_t i = 0; i < v->funcs.funcs.len; i++)
        cbm__func_free(ctx, &v->funcs.funcs.data[i]);
    CBM_ARRAY_FREE(ctx, v->funcs.funcs);
    for (size_t i = 0; i < v->surfaces.len; i++)
        cbm__surface_free(ctx, &v->surfaces.data[i]);
    CBM_ARRAY_FREE(ctx, v->surfaces);
    for (size_t i = 0; i < v->contours.len; i++)
        CBM_ARRAY_FREE(ctx, v->contours.data[i].pts);
    CBM_ARRAY_FREE(ctx, v->contours);
    cbm__free(ctx, v, sizeof *v);
}

const cbm_funcset *cbm_view_functions(const cbm_view *v)
{
    return v ? &v->funcs : NULL;
}

/* path relative to the view's directory unless absolute */
static void side_path(const cbm_view *v, const char *name, char *buf, size_t cap)
{
    if (name[0] == '/' || !v->dir[0] || strcmp(v->dir, ".") == 0)
        snprintf(buf, cap, "%s", name);
    else
        snprintf(buf, cap, "%s/%s", v->dir, name);
}

/* ---- side files from their text ---- */

static cbm_status add_function_text(cbm_view *v, const char *path, const char *text, int samples)
{
    cbm__func f;
    CBM_TRY(cbm__func_read(v->ctx, path, text, samples, &f));
    if (CBM_ARRAY_PUSH(v->ctx, v->funcs.funcs, f) != CBM_OK) {
        cbm__func_free(v->ctx, &f);
        return CBM_E_NOMEM;
    }
    return CBM_OK;
}

static cbm_status add_surface_text(cbm_view *v, char id, const char *path, const char *text,
                                   double size, int sprec, int tprec)
{
    cbm__surface sf;
    cbm_status s =
        cbm__surface_read(v->ctx, path, text, size > 0.0 ? size : 1.0, sprec, tprec, &sf);
    if (s != CBM_OK) {
        cbm__surface_free(v->ctx, &sf);
        return s;
    }
    sf.id = id;
    /* a later surface with the same id replaces the earlier one, as in cpfg */
    for (size_t i = 0; i < v->surfaces.len; i++) {
        if (v->surfaces.data[i].id == id) {
            cbm__surface_free(v->ctx, &v->surfaces.data[i]);
            v->surfaces.data[i] = sf;
            return CBM_OK;
        }
    }
    if (CBM_ARRAY_PUSH(v->ctx, v->surfaces, sf) != CBM_OK) {
        cbm__surface_free(v->ctx, &sf);
        return CBM_E_NOMEM;
    }
    return CBM_OK;
}

static cbm_status add_contour_text(cbm_view *v, int id, const char *path, const char *text)
{
    if (v->contours.len >= CBM__MAX_CONTOURS)
        return cbm__fail(v->ctx, CBM_E_LIMIT, "%s: more than %d contours", path, CBM__MAX_CONTOURS);
    cbm__contour c;
    cbm_status s = cbm__contour_read(v->ctx, path, text, &c);
    if (s != CBM_OK) {
        CBM_ARRAY_FREE(v->ctx, c.pts);
        return s;
    }
    c.id = id;
    if (CBM_ARRAY_PUSH(v->ctx, v->contours, c) != CBM_OK) {
        CBM_ARRAY_FREE(v->ctx, c.pts);
        return CBM_E_NOMEM;
    }
    return CBM_OK;
}

static cbm_status parse_view(cbm_view *v, const char *path, const char *text);

cbm_status cbm__view_add_text(cbm_view *v, cbm__side_kind kind, const char *name, const char *text)
{
    if (!v || !name || !text)
        return CBM_E_INVALID;
    switch (kind) {
    case CBM__SIDE_VIEW:
        return parse_view(v, name, text);
    case CBM__SIDE_FUNC:
        return add_function_text(v, name, text, -1);
    case CBM__SIDE_FSET:
        return cbm__funcset_read_gallery(v->ctx, name, text, &v->funcs);
    case CBM__SIDE_SURFACE:
        return add_surface_text(v, name[0], name, text, 1.0, 0, 0);
    case CBM__SIDE_CONTOUR:
        return add_contour_text(v, (int)v->contours.len + 1, name, text);
    }
    return CBM_E_INVALID;
}

/* Reads the file and hands its text to one of the readers above. */
typedef struct side_args {
    cbm__side_kind kind;
    int samples, id;
    double size;
    int sprec, tprec;
} side_args;

static cbm_status add_file(cbm_view *v, const char *path, const side_args *a)
{
    if (!v || !path)
        return CBM_E_INVALID;
    char *text;
    size_t len;
    CBM_TRY(cbm__read_file(v->ctx, path, &text, &len));
    cbm_status s;
    switch (a->kind) {
    case CBM__SIDE_FUNC:
        s = add_function_text(v, path, text, a->samples);
        break;
    case CBM__SIDE_SURFACE:
        s = add_surface_text(v, (char)a->id, path, text, a->size, a->sprec, a->tprec);
        break;
    case CBM__SIDE_CONTOUR:
        s = add_contour_text(v, a->id, path, text);
        break;
    default:
        s = cbm__view_add_text(v, a->kind, path, text);
        break;
    }
    cbm__free_file(v->ctx, text, len);
    return s;
}

cbm_status cbm_view_add_function(cbm_view *v, const char *path, int samples)
{
    side_args a = {CBM__SIDE_FUNC, samples, 0, 0.0, 0, 0};
    return add_file(v, path, &a);
}

cbm_status cbm_view_add_function_set(cbm_view *v, const char *path)
{
    side_args a = {CBM__SIDE_FSET, 0, 0, 0.0, 0, 0};
    return add_file(v, path, &a);
}

cbm_status cbm_view_add_surface(cbm_view *v, char id, const char *path, double size)
{
    side_args a = {CBM__SIDE_SURFACE, 0, id, size, 0, 0};
    return add_file(v, path, &a);
}

/* A surface with cpfg's s and t precisions (0: the file's or the default). */
static cbm_status add_surface_prec(cbm_view *v, char id, const char *path, double size, int sp,
                                   int tp)
{
    side_args a = {CBM__SIDE_SURFACE, 0, id, size, sp, tp};
    return add_file(v, path, &a);
}

cbm_status cbm_view_add_contour(cbm_view *v, int id, const char *path)
{
    side_args a = {CBM__SIDE_CONTOUR, 0, id, 0.0, 0, 0};
    return add_file(v, path, &a);
}

cbm_status cbm_view_load_colormap(cbm_view *v, const char *path)
{
    if (!v || !path)
        return CBM_E_INVALID;
    FILE *f = fopen(path, "rb");
    if (!f)
        return cbm__fail(v->ctx, CBM_E_IO, "%s: cannot open", path);
    unsigned char b[768];
    size_t n = fread(b, 1, sizeof b, f);
    fclose(f);
    if (n < 768)
        return cbm__fail(v->ctx, CBM_E_FORMAT,
                         "%s: a colour map holds 256 RGB byte triples (768 bytes), found %zu", path,
                         n);
    for (int i = 0; i < 256; i++) {
        for (int c = 0; c < 3; c++)
            v->colors[i][c] = srgb_to_linear(b[3 * i + c]);
        v->colors[i][3] = 1.0f;
    }
    v->have_colors = true;
    return CBM_OK;
}

cbm_status cbm_view_load_materials(cbm_view *v, const char *path)
{
    if (!v || !path)
        return CBM_E_INVALID;
    FILE *f = fopen(path, "rb");
    if (!f)
        return cbm__fail(v->ctx, CBM_E_IO, "%s: cannot open", path);
    unsigned char rec[15];
    size_t count = 0;
    while (fread(rec, 1, 15, f) == 15) {
        int idx = rec[0];
        /* rec[1] transparency, [2..4] ambient, [5..7] diffuse */
        for (int c = 0; c < 3; c++)
            v->colors[idx][c] = srgb_to_linear(rec[5 + c]);
        v->colors[idx][3] = 1.0f - rec[1] / 255.0f;
        count++;
    }
    fclose(f);
    if (count == 0)
        return cbm__fail(v->ctx, CBM_E_FORMAT, "%s: no material records (15 bytes each)", path);
    v->have_colors = true;
    return CBM_OK;
}

static const char *ext_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(path, '.');
    if (!dot || (slash && dot < slash))
        return "";
    return dot + 1;
}

cbm_status cbm_view_load_side_file(cbm_view *v, const char *path)
{
    if (!v || !path)
        return CBM_E_INVALID;
    const char *e = ext_of(path);
    if (strcmp(e, "v") == 0) {
        char *text;
        size_t len;
        CBM_TRY(cbm__read_file(v->ctx, path, &text, &len));
        const char *slash = strrchr(path, '/');
        if (slash)
            snprintf(v->dir, sizeof v->dir, "%.*s", (int)(slash - path), path);
        cbm_status s = parse_view(v, path, text);
        cbm__free_file(v->ctx, text, len);
        return s;
    }
    if (strcmp(e, "func") == 0)
        return cbm_view_add_function(v, path, -1);
    if (strcmp(e, "fset") == 0)
        return cbm_view_add_function_set(v, path);
    if (strcmp(e, "map") == 0)
        return cbm_view_load_colormap(v, path);
    if (strcmp(e, "mat") == 0)
        return cbm_view_load_materials(v, path);
    if (strcmp(e, "s") == 0) {
        /* as cpfg: a surface given alone is named by the first letter of its file name */
        const char *slash = strrchr(path, '/');
        const char *base = slash ? slash + 1 : path;
        return cbm_view_add_surface(v, base[0], path, 1.0);
    }
    if (strcmp(e, "con") == 0)
        return cbm_view_add_contour(v, (int)v->contours.len + 1, path);
    return cbm__fail(v->ctx, CBM_E_UNSUPPORTED, "%s: unknown side file type '.%s'", path, e);
}

cbm_status cbm_view_load(cbm_context *ctx, const char *path, cbm_view **out)
{
    if (!ctx || !path || !out)
        return CBM_E_INVALID;
    *out = NULL;
    cbm_view *v;
    CBM_TRY(cbm_view_create(ctx, &v));
    char *text;
    size_t len;
    cbm_status s = cbm__read_file(ctx, path, &text, &len);
    if (s != CBM_OK) {
        cbm_view_destroy(v);
        return s;
    }
    const char *slash = strrchr(path, '/');
    if (slash)
        snprintf(v->dir, sizeof v->dir, "%.*s", (int)(slash - path), path);
    s = parse_view(v, path, text);
    cbm__free_file(ctx, text, len);
    if (s != CBM_OK) {
        cbm_view_destroy(v);
        return s;
    }
    *out = v;
    return CBM_OK;
}

/* ---- the view file ---- */

/* Reads up to n numbers separated by spaces or commas; returns how many. */
static int numbers(const char *s, double *out, int n)
{
    int k = 0;
    while (k < n) {
        while (*s == ' ' || *s == '\t' || *s == ',')
            s++;
        char *end;
        double x = strtod(s, &end);
        if (end == s || !isfinite(x))
            break;
        out[k++] = x;
        s = end;
    }
    return k;
}

static cbm_status read_movement(cbm_view *v, const char *path, int line, const char *s, int torque)
{
    if (v->nmov >= CBM__MAX_MOVEMENTS) {
        cbm__diag(v->ctx, CBM_WARNING, path, line, 1, "more than %d tropisms; ignored",
                  CBM__MAX_MOVEMENTS);
        return CBM_OK;
    }
    cbm__movement m;
    memset(&m, 0, sizeof m);
    m.torque = torque;
    double len = 0.0, gamma = 0.0;
    bool have_t = false;
    while (*s) {
        while (*s == ' ' || *s == '\t')
            s++;
        if (!*s)
            break;
        char key = *s++;
        if (*s == ':')
            s++;
        double val[3];
        int want = key == 'T' ? 3 : 1;
        int got = numbers(s, val, want);
        if (got != want) {
            cbm__diag(v->ctx, CBM_ERROR, path, line, 1, "tropism: expected %d number%s after '%c:'",
                      want, want > 1 ? "s" : "", key);
            return CBM_E_FORMAT;
        }
        /* skip what numbers() consumed */
        for (int i = 0; i < got; i++) {
            while (*s == ' ' || *s == '\t' || *s == ',')
                s++;
            char *end;
            strtod(s, &end);
            s = end;
        }
        switch (key) {
        case 'T':
            m.dir = v3(val[0], val[1], val[2]);
            if (v3_norm2(m.dir) == 0.0) {
                cbm__diag(v->ctx, CBM_ERROR, path, line, 1, "tropism with a zero vector");
                return CBM_E_FORMAT;
            }
            len = 1.0 / v3_norm(m.dir);
            have_t = true;
            break;
        case 'I':
            len *= val[0];
            if (len > 1.0)
                len = 1.0;
            if (len < -1.0)
                len = -1.0;
            break;
        case 'A':
            gamma = val[0];
            break;
        case 'E':
            m.elasticity = val[0];
            break;
        case 'S':
            m.elasticity_inc = val[0];
            break;
        default:
            cbm__diag(v->ctx, CBM_ERROR, path, line, 1,
                      "tropism: unknown field '%c' (expected T, A, E, S or I)", key);
            return CBM_E_FORMAT;
        }
    }
    if (!have_t) {
        cbm__diag(v->ctx, CBM_ERROR, path, line, 1, "tropism: missing direction 'T: x y z'");
        return CBM_E_FORMAT;
    }
    m.dir = v3_scale(m.dir, len);
    m.cos_g = cos(gamma * CBM_PI / 180.0);
    m.sin_g = sin(gamma * CBM_PI / 180.0);
    v->mov[v->nmov++] = m;
    return CBM_OK;
}

static bool word_on(const char *s)
{
    while (*s == ' ' || *s == '\t')
        s++;
    return strncmp(s, "on", 2) == 0;
}

static cbm_status parse_view(cbm_view *v, const char *path, const char *text)
{
    v->view_file = true;
    const char *p = text;
    int line = 0;
    char buf[1024];
    cbm_status result = CBM_OK;
    while (*p) {
        size_t n = 0;
        while (*p && *p != '\n') {
            if (n + 1 < sizeof buf && *p != '\r')
                buf[n++] = *p;
            p++;
        }
        if (*p == '\n')
            p++;
        buf[n] = '\0';
        line++;
        const char *s = buf;
        while (*s == ' ' || *s == '\t')
            s++;
        if (!*s || *s == '#' || (s[0] == '/' && s[1] == '*'))
            continue;
        const char *colon = strchr(s, ':');
        if (!colon)
            continue; /* cpfg skips what it does not recognise */
        size_t klen = (size_t)(colon - s);
        const char *a = colon + 1;
        double x[4];
        int k;
#define KEY(str) (klen == sizeof(str) - 1 && strncmp(s, str, klen) == 0)
/* too few numbers: report and go on with the next line (no do-while wrapper: its `continue`
 * would leave only the wrapper, and the key's code would then read the numbers not given) */
#define NEED(cnt)                                                                                  \
    if (k < (cnt)) {                                                                               \
        cbm__diag(v->ctx, CBM_ERROR, path, line, (int)(a - buf) + 1,                               \
                  "'%.*s:' expects %d number%s", (int)klen, s, (cnt), (cnt) > 1 ? "s" : "");       \
        result = CBM_E_FORMAT;                                                                     \
        continue;                                                                                  \
    } else                                                                                         \
        (void)0
        k = numbers(a, x, 4);
        if (KEY("angle factor")) {
            NEED(1);
            if (x[0] == 0.0) {
                cbm__diag(v->ctx, CBM_ERROR, path, line, 1, "angle factor must not be 0");
                result = CBM_E_FORMAT;
                continue;
            }
            set_angle(v, 360.0 / (float)x[0]);
        } else if (KEY("angle increment")) {
            NEED(1);
            set_angle(v, (float)x[0]);
        } else if (KEY("initial color")) {
            NEED(1);
            v->color = cbm__to_int(x[0]);
        } else if (KEY("color increment")) {
            NEED(1);
            v->color_inc = cbm__to_int(x[0]);
        } else if (KEY("initial line width")) {
            NEED(1);
            v->width = (float)x[0];
            v->line_style = CBM__LS_POLYGON;
            const char *w = a;
            while (*w == ' ' || *w == '\t')
                w++;
            char *rest;
            strtod(w, &rest);
            w = rest;
            while (*w == ' ' || *w == '\t')
                w++;
            if (*w == 'p')
                v->line_style = CBM__LS_PIXEL;
            else if (*w == 's')
                v->line_style = CBM__LS_CYLINDER;
        } else if (KEY("line width increment")) {
            NEED(1);
            v->width_inc = (float)x[0];
        } else if (KEY("scale factor")) {
            NEED(1);
            v->scale = x[0] == 0.0 ? 1.0 : x[0];
        } else if (KEY("initial scale")) {
            NEED(1);
            v->init_scale = x[0] == 0.0 ? 1.0 : (float)x[0]; /* cpfg: 0 is taken as 1 */
        } else if (KEY("scale multiplier")) {
            NEED(1);
            v->scale_mul = x[0] == 0.0 ? 1.0 : (float)x[0];
        } else if (KEY("tropism direction")) {
            NEED(3);
            cbm_vec3 t = v3(x[0], x[1], x[2]);
            if (v3_norm2(t) == 0.0) {
                cbm__diag(v->ctx, CBM_ERROR, path, line, 1, "tropism direction is zero");
                result = CBM_E_FORMAT;
                continue;
            }
            v->tropism_dir = v3_normalize(t);
        } else if (KEY("initial elasticity")) {
            NEED(1);
            v->elasticity = (float)x[0];
        } else if (KEY("elasticity increment")) {
            NEED(1);
            v->elasticity_inc = (float)x[0];
        } else if (KEY("tropism") || KEY("torque")) {
            cbm_status s2 = read_movement(v, path, line, a, KEY("torque"));
            if (s2 != CBM_OK)
                result = s2;
        } else if (KEY("line style")) {
            const char *w = a;
            while (*w == ' ' || *w == '\t')
                w++;
            if (strncmp(w, "pixel", 5) == 0 || *w == '1')
                v->line_style = CBM__LS_PIXEL;
            else if (strncmp(w, "polygon", 7) == 0 || *w == '2')
                v->line_style = CBM__LS_POLYGON;
            else if (strncmp(w, "cylinder", 8) == 0 || *w == '3')
                v->line_style = CBM__LS_CYLINDER;
            else {
                cbm__diag(v->ctx, CBM_ERROR, path, line, (int)(w - buf) + 1,
                          "unknown line style '%s' (expected pixel, polygon or cylinder)", w);
                result = CBM_E_FORMAT;
            }
        } else if (KEY("contour sides")) {
            NEED(1);
            v->sides = x[0] < 3 ? 3 : cbm__to_int(x[0]);
            if (v->sides > 1024)
                v->sides = 1024;
        } else if (KEY("polygonization level")) {
            NEED(1);
            int level = cbm__to_int(x[0]);
            if (level > 9)
                level = 9;
            v->sides = (int)rint(pow(2.0, level + 1));
            if (v->sides <= 2)
                v->sides = 3;
        } else if (KEY("corrected rotation")) {
            const char *w = a;
            while (*w == ' ' || *w == '\t')
                w++;
            v->lpfg_uncorrected = strncmp(w, "off", 3) == 0;
        } else if (KEY("twist of cylinders")) {
            v->gc_twist = word_on(a);
        } else if (KEY("interpretation past %")) {
            const char *w = a;
            while (*w == ' ' || *w == '\t')
                w++;
            v->past_cut = strncmp(w, "off", 3) != 0;
        } else if (KEY("function")) {
            char name[512];
            int samples = -1;
            int got = sscanf(a, " %511s %d", name, &samples);
            if (got < 1) {
                cbm__diag(v->ctx, CBM_ERROR, path, line, 1, "function: expects a file name");
                result = CBM_E_FORMAT;
                continue;
            }
            char full[1100];
            side_path(v, name, full, sizeof full);
            cbm_status s2 = cbm_view_add_function(v, full, got == 2 ? samples : -1);
            if (s2 != CBM_OK) {
                cbm__diag(v->ctx, CBM_ERROR, path, line, 1, "cannot read function file %s", full);
                result = s2;
            }
        } else if (KEY("function set")) {
            char name[512];
            if (sscanf(a, " %511s", name) != 1) {
                cbm__diag(v->ctx, CBM_ERROR, path, line, 1, "function set: expects a file name");
                result = CBM_E_FORMAT;
                continue;
            }
            char full[1100];
            side_path(v, name, full, sizeof full);
            cbm_status s2 = cbm_view_add_function_set(v, full);
            if (s2 != CBM_OK) {
                cbm__diag(v->ctx, CBM_ERROR, path, line, 1, "cannot read function set %s", full);
                result = s2;
            }
        } else if (KEY("surface")) {
            char id;
            char name[512];
            float size = 1.0f;
            int sp = 0, tp = 0;
            if (sscanf(a, " %c %511s %f %d %d", &id, name, &size, &sp, &tp) < 5)
                sp = tp = 0; /* cpfg takes the precisions only as a pair */
            if (sscanf(a, " %c %511s %f", &id, name, &size) < 2) {
                cbm__diag(v->ctx, CBM_ERROR, path, line, 1,
                          "surface: expects an id, a file name and a size");
                result = CBM_E_FORMAT;
                continue;
            }
            char full[1100];
            side_path(v, name, full, sizeof full);
            cbm_status s2 = add_surface_prec(v, id, full, size, sp, tp);
            if (s2 != CBM_OK) {
                cbm__diag(v->ctx, CBM_ERROR, path, line, 1, "cannot read surface file %s", full);
                result = s2;
            }
        } else if (KEY("contour")) {
            int id;
            char name[512];
            if (sscanf(a, " %d %511s", &id, name) != 2) {
                cbm__diag(v->ctx, CBM_ERROR, path, line, 1, "contour: expects an id and a file");
                result = CBM_E_FORMAT;
                continue;
            }
            char full[1100];
            side_path(v, name, full, sizeof full);
            cbm_status s2 = cbm_view_add_contour(v, id, full);
            if (s2 != CBM_OK) {
                cbm__diag(v->ctx, CBM_ERROR, path, line, 1, "cannot read contour file %s", full);
                result = s2;
            }
        }
        /* everything else concerns cpfg's window and renderer */
#undef KEY
#undef NEED
    }
    return result;
}

bool cbm__view_lpfg_corrected(const cbm_view *view)
{
    return !view->lpfg_uncorrected;
}

void cbm__view_lpfg_functions(cbm_view *view)
{
    cbm__funcset_lpfg(&view->funcs);
}
