/* cambium info FILE: what a model or an output file holds, in a few lines.
 *
 * A model (.l) is loaded (with the view file beside it, named as the model or the only one, as
 * a cpfg model directory holds it; the view file names the function files) and described:
 * productions, decomposition and homomorphism, derivation length, the axiom, and the side files it
 * uses or that lie beside it. Output files are read just enough to count what they hold: .str
 * modules and parameters; .obj vertices, faces and bounds; .ply its header; .glb nodes, meshes,
 * animation and bounds (from the POSITION accessors' min/max); .png size and pixel format; .svg
 * size and elements; .csv rows and columns; .json the steps of a run summary.
 */
#define _POSIX_C_SOURCE 200809L
#include "cli.h"
#include "commands.h"
#include "options.h"

#include <dirent.h>
#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define INFO_PI 3.14159265358979323846

static const char *const SIDE_KINDS[] = {"v", "func", "fset", "s", "con", "map", "mat"};

/* The whole file (NUL-terminated), NULL if unreadable. */
static char *slurp(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    size_t cap = 1 << 16, n = 0;
    char *b = malloc(cap);
    while (b) {
        size_t got = fread(b + n, 1, cap - n - 1, f);
        n += got;
        if (got == 0)
            break;
        if (n + 1 >= cap) {
            char *nb = realloc(b, cap *= 2);
            if (!nb)
                free(b);
            b = nb;
        }
    }
    fclose(f);
    if (b)
        b[n] = 0;
    *len = n;
    return b;
}

static int info_model(const char *path)
{
    /* the side files beside the model, in cpfg's order: view file first */
    char dir[4096];
    const char *slash = strrchr(path, '/');
    snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - path) : 1, slash ? path : ".");
    char *found[64];
    size_t nfound = 0;
    DIR *d = opendir(dir);
    for (struct dirent *e; d && (e = readdir(d)) && nfound < 64;) {
        const char *ext = cli_extension(e->d_name);
        for (size_t k = 0; k < sizeof SIDE_KINDS / sizeof SIDE_KINDS[0]; k++)
            if (!strcmp(ext, SIDE_KINDS[k]) && e->d_name[0] != '.') {
                size_t n = strlen(dir) + strlen(e->d_name) + 2;
                found[nfound] = malloc(n);
                if (found[nfound])
                    snprintf(found[nfound++], n, "%s/%s", dir, e->d_name);
            }
    }
    if (d)
        closedir(d);
    /* the view file: the one named as the model (plant.l, plant.v), else the only one there;
     * it names the function files, surfaces and contours the model uses */
    char base[4096];
    const char *name = slash ? slash + 1 : path;
    snprintf(base, sizeof base, "%.*s.v", (int)(strlen(name) - 2), name);
    const char *view = NULL;
    size_t nview = 0;
    for (size_t k = 0; k < nfound; k++)
        if (!strcmp(cli_extension(found[k]), "v")) {
            nview++;
            if (!strcmp(found[k] + strlen(dir) + 1, base) || !view)
                view = found[k];
        }
    if (nview > 1 && strcmp(view + strlen(dir) + 1, base))
        view = NULL;
    const char *sides[1] = {view};
    size_t nside = view ? 1 : 0;
    cbm_context *ctx = cli_context();
    cbm_model_def def = {cbm_lsys_def_default(), sides, nside};
    def.lsys.path = path;
    cbm_model *m = NULL;
    cbm_status s = cbm_model_load(ctx, &def, &m);
    int rc = CLI_OK;
    if (s == CBM_OK)
        s = cbm_model_reset(m);
    if (s != CBM_OK) {
        rc = cli_fail(ctx, s, path);
    } else {
        cbm_model_summary sm;
        cbm_model_describe(m, &sm);
        cbm_lsys *ls = cbm_model_lsys(m);
        printf("%s: %s L-system model\n", path, sm.lc_dialect ? "L+C" : "cpfg");
        if (sm.lsystems > 1)
            printf("  L-systems: %d (the main one and %d sub-L-system%s)\n", sm.lsystems,
                   sm.lsystems - 1, sm.lsystems == 2 ? "" : "s");
        if (sm.lc_dialect)
            printf("  modules declared: %zu (with the turtle's)\n", sm.modules_declared);
        printf("  productions: %zu%s\n", sm.productions, sm.stochastic ? " (stochastic)" : "");
        if (sm.decompositions)
            printf("  decomposition: %zu productions, maximum depth %d\n", sm.decompositions,
                   sm.decomposition_depth);
        if (sm.homomorphisms)
            printf("  %s: %zu productions, maximum depth %d\n",
                   sm.lc_dialect ? "interpretation" : "homomorphism", sm.homomorphisms,
                   sm.homomorphism_depth);
        if (sm.mechanics)
            printf("  mechanics: a module carries a mechanical segment (mechanics:)\n");
        printf("  derivation length: %d steps\n", sm.derivation_length);
        printf("  axiom: %zu modules%s\n", cbm_lsys_module_count(ls),
               cbm_model_has_queries(m) ? ", with query modules (?P ?H ?L ?U)" : "");
        if (sm.has_start_end)
            printf("  blocks: Start/End/StartEach/EndEach\n");
        size_t len = 0;
        char *text = slurp(path, &len);
        bool uses_func = text && strstr(text, "func(");
        free(text);
        if (uses_func)
            printf("  calls func(id, x): needs function files (%d read from beside it)\n",
                   sm.functions);
        if (view)
            printf("  view file: %s\n", view + strlen(dir) + 1);
        printf("  side files beside it:%s", nfound ? "" : " none");
        for (size_t k = 0; k < nfound && k < 12; k++)
            printf(" %s", found[k] + strlen(dir) + 1);
        printf("%s\n", nfound > 12 ? " ..." : "");
    }
    cbm_model_destroy(m);
    cli_context_end(ctx);
    for (size_t k = 0; k < nfound; k++)
        free(found[k]);
    return rc;
}

static void print_bounds(const double lo[3], const double hi[3])
{
    if (lo[0] <= hi[0])
        printf("  bounds: x %.6g..%.6g, y %.6g..%.6g, z %.6g..%.6g (m)\n", lo[0], hi[0], lo[1],
               hi[1], lo[2], hi[2]);
}

static void info_str(const char *t)
{
    size_t modules = 0, params = 0, parametric = 0;
    for (const char *p = t; *p;) {
        const char *nl = strchr(p, '\n');
        const char *end = nl ? nl : p + strlen(p);
        if (end > p) {
            modules++;
            const char *par = memchr(p, '(', (size_t)(end - p));
            if (par) {
                parametric++;
                params++;
                for (const char *q = par; q < end; q++)
                    params += *q == ',';
            }
        }
        p = nl ? nl + 1 : end;
    }
    printf("  derived string: %zu modules, %zu with parameters, %zu parameters\n", modules,
           parametric, params);
}

static void info_obj(const char *t)
{
    size_t v = 0, f = 0, mtl = 0;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (const char *p = t; *p;) {
        if (p[0] == 'v' && p[1] == ' ') {
            double q[3];
            if (sscanf(p + 2, "%lf %lf %lf", &q[0], &q[1], &q[2]) == 3)
                for (int k = 0; k < 3; k++) {
                    lo[k] = fmin(lo[k], q[k]);
                    hi[k] = fmax(hi[k], q[k]);
                }
            v++;
        } else if (p[0] == 'f' && p[1] == ' ') {
            f++;
        } else if (!strncmp(p, "usemtl ", 7)) {
            mtl++;
        }
        const char *nl = strchr(p, '\n');
        if (!nl)
            break;
        p = nl + 1;
    }
    printf("  Wavefront OBJ: %zu vertices, %zu faces, %zu material switches\n", v, f, mtl);
    print_bounds(lo, hi);
}

static void info_ply(const char *t)
{
    const char *end = strstr(t, "end_header");
    printf("  PLY header:\n");
    for (const char *p = t; end && p < end;) {
        const char *nl = strchr(p, '\n');
        if (!nl)
            break;
        if (!strncmp(p, "format", 6) || !strncmp(p, "element", 7) || !strncmp(p, "comment", 7))
            printf("    %.*s\n", (int)(nl - p), p);
        p = nl + 1;
    }
}

static uint32_t le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* The value of the top-level key of a JSON object (just after its ':'), NULL if absent. */
static const char *json_top_value(const char *js, size_t n, const char *key)
{
    int depth = 0;
    size_t klen = strlen(key);
    for (const char *p = js; p < js + n; p++) {
        char c = *p;
        if (c == '"') {
            const char *q = p + 1;
            while (q < js + n && *q != '"')
                q += *q == '\\' ? 2 : 1;
            if (depth == 1 && (size_t)(q - p - 1) == klen && !strncmp(p + 1, key, klen) &&
                q + 1 < js + n && q[1] == ':')
                return q + 2;
            p = q;
        } else if (c == '[' || c == '{') {
            depth++;
        } else if (c == ']' || c == '}') {
            depth--;
        }
    }
    return NULL;
}

/* Number of elements of the top-level array "key":[...]. */
static size_t json_array_count(const char *js, size_t n, const char *key)
{
    const char *p = json_top_value(js, n, key);
    if (!p || *p != '[')
        return 0;
    p++;
    size_t count = 0;
    int depth = 0;
    bool any = false;
    for (; p < js + n; p++) {
        char c = *p;
        if (c == '"') {
            p++;
            while (p < js + n && *p != '"')
                p += *p == '\\' ? 2 : 1;
            any = true;
            continue;
        }
        if (depth == 0 && c == ']')
            break;
        if (c == '[' || c == '{')
            depth++;
        if (c == ']' || c == '}')
            depth--;
        if (depth == 0 && c == ',')
            count++;
        if (c != ' ' && c != '\n')
            any = true;
    }
    return any ? count + 1 : 0;
}

/* Whether js[0..n) is one JSON object: brackets and braces nest and match, strings close,
 * and nothing but blanks follows (a structural check, enough to refuse a broken file). */
static bool json_object_ok(const char *js, size_t n)
{
    char stack[256];
    int depth = 0;
    size_t i = 0;
    while (i < n && isspace((unsigned char)js[i]))
        i++;
    if (i >= n || js[i] != '{')
        return false;
    for (; i < n; i++) {
        char c = js[i];
        if (c == '"') {
            for (i++; i < n && js[i] != '"'; i++)
                if (js[i] == '\\')
                    i++;
            if (i >= n)
                return false;
        } else if (c == '{' || c == '[') {
            if (depth == (int)sizeof stack)
                return false;
            stack[depth++] = c == '{' ? '}' : ']';
        } else if (c == '}' || c == ']') {
            if (depth == 0 || stack[--depth] != c)
                return false;
            if (depth == 0)
                break;
        } else if (c == 0) {
            return false;
        }
    }
    if (depth != 0 || i >= n)
        return false;
    for (i++; i < n; i++)
        if (!isspace((unsigned char)js[i]) && js[i] != 0)
            return false;
    return true;
}

/* The layout of a binary glTF: header (magic, version 2, total length = file size), a JSON
 * chunk holding one object with "asset", then chunks that fit exactly. NULL when it is sound,
 * else what is wrong. */
static const char *glb_problem(const unsigned char *b, size_t n)
{
    if (n < 20 || memcmp(b, "glTF", 4))
        return "not a glTF binary file";
    if (le32(b + 4) != 2)
        return "not glTF version 2";
    if (le32(b + 8) != n)
        return "the length in its header is not the file's length";
    if (le32(b + 16) != 0x4E4F534A)
        return "the first chunk is not JSON";
    size_t off = 12;
    while (off < n) {
        if (n - off < 8)
            return "truncated chunk header";
        size_t len = le32(b + off);
        if (len % 4 || len > n - off - 8)
            return "a chunk runs past the end of the file";
        off += 8 + len;
    }
    size_t jl = le32(b + 12);
    if (!json_object_ok((const char *)b + 20, jl))
        return "its JSON chunk is not a well-formed JSON object";
    bool asset = false, null_bound = false;
    const char *js = (const char *)b + 20;
    for (size_t i = 0; i + 7 <= jl; i++) {
        if (!memcmp(js + i, "\"asset\"", 7))
            asset = true;
        if (i + 12 <= jl &&
            (!memcmp(js + i, "\"max\":[null", 12) || !memcmp(js + i, "\"min\":[null", 12)))
            null_bound = true;
    }
    if (!asset)
        return "its JSON has no \"asset\"";
    if (null_bound)
        return "an accessor has a null (non-finite) min or max";
    return NULL;
}

static int info_glb(const char *path, const unsigned char *b, size_t n)
{
    const char *problem = glb_problem(b, n);
    if (problem) {
        fprintf(stderr, "cambium: %s: malformed glTF: %s\n", path, problem);
        return CLI_FAIL;
    }
    size_t jl = le32(b + 12);
    char *js = malloc(jl + 1);
    if (!js)
        return CLI_FAIL;
    memcpy(js, b + 20, jl);
    js[jl] = 0;
    printf("  glTF %u binary: %zu nodes, %zu meshes, %zu materials, %zu animations\n", le32(b + 4),
           json_array_count(js, jl, "nodes"), json_array_count(js, jl, "meshes"),
           json_array_count(js, jl, "materials"), json_array_count(js, jl, "animations"));
    /* bounds: the min/max of the 3-component accessors (POSITION has them, by the spec) */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (const char *p = js; (p = strstr(p, "\"max\":[")) != NULL; p++) {
        double q[3], r[3];
        const char *mn = strstr(p, "\"min\":[");
        if (sscanf(p + 7, "%lf,%lf,%lf]", &q[0], &q[1], &q[2]) == 3 && mn &&
            sscanf(mn + 7, "%lf,%lf,%lf]", &r[0], &r[1], &r[2]) == 3 && mn - p < 200)
            for (int k = 0; k < 3; k++) {
                hi[k] = fmax(hi[k], q[k]);
                lo[k] = fmin(lo[k], r[k]);
            }
    }
    /* accessors with max before min are found the other way round */
    for (const char *p = js; (p = strstr(p, "\"min\":[")) != NULL; p++) {
        double q[3], r[3];
        const char *mx = strstr(p, "\"max\":[");
        if (sscanf(p + 7, "%lf,%lf,%lf]", &r[0], &r[1], &r[2]) == 3 && mx &&
            sscanf(mx + 7, "%lf,%lf,%lf]", &q[0], &q[1], &q[2]) == 3 && mx - p < 200)
            for (int k = 0; k < 3; k++) {
                hi[k] = fmax(hi[k], q[k]);
                lo[k] = fmin(lo[k], r[k]);
            }
    }
    print_bounds(lo, hi);
    if (strstr(js, "\"EXT_mesh_gpu_instancing\""))
        printf("  instanced tubes (EXT_mesh_gpu_instancing): the bounds are the unit tubes' and "
               "the triangles', not the placed instances'\n");
    free(js);
    return CLI_OK;
}

static int info_png(const unsigned char *b, size_t n)
{
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (n < 33 || memcmp(b, sig, 8) || memcmp(b + 12, "IHDR", 4)) {
        printf("  not a PNG file\n");
        return CLI_FAIL;
    }
    uint32_t w = (uint32_t)b[16] << 24 | (uint32_t)b[17] << 16 | (uint32_t)b[18] << 8 | b[19];
    uint32_t h = (uint32_t)b[20] << 24 | (uint32_t)b[21] << 16 | (uint32_t)b[22] << 8 | b[23];
    static const char *const types[] = {"grey", "?", "RGB", "palette", "grey+alpha", "?", "RGBA"};
    printf("  PNG picture: %u x %u pixels, %d-bit %s\n", w, h, b[24],
           b[25] < 7 ? types[b[25]] : "?");
    return CLI_OK;
}

static size_t count_of(const char *t, const char *s)
{
    size_t n = 0;
    for (const char *p = t; (p = strstr(p, s)) != NULL; p += strlen(s))
        n++;
    return n;
}

static void info_svg(const char *t)
{
    const char *w = strstr(t, " width=\""), *h = strstr(t, " height=\"");
    printf("  SVG picture: %.*s x %.*s, %zu polygons, %zu paths\n",
           w ? (int)strcspn(w + 8, "\"") : 1, w ? w + 8 : "?", h ? (int)strcspn(h + 9, "\"") : 1,
           h ? h + 9 : "?", count_of(t, "<polygon"), count_of(t, "<path"));
    const char *d = strstr(t, "<desc>");
    if (d)
        printf("  %.*s\n", (int)strcspn(d + 6, "<"), d + 6);
}

static void info_csv(const char *t)
{
    size_t rows = 0;
    const char *nl = strchr(t, '\n');
    size_t cols = 0;
    if (nl) {
        size_t c = 1;
        for (const char *p = t; p < nl; p++)
            c += *p == ',';
        cols = c;
        for (const char *p = nl + 1; *p; p++)
            rows += *p == '\n';
    }
    printf("  table: %zu rows, %zu columns: %.*s\n", rows, cols, nl ? (int)(nl - t) : 0, t);
}

static void info_json(const char *t)
{
    size_t steps = count_of(t, "\"step\":");
    if (steps == 0) {
        printf("  JSON document\n");
        return;
    }
    const char *last = t;
    for (const char *p = t; (p = strstr(p, "\"step\":")) != NULL; p++)
        last = p;
    long step = 0, modules = 0, prims = 0;
    const char *m = strstr(last, "\"modules\":"), *pr = strstr(last, "\"primitives\":");
    sscanf(last + 7, "%ld", &step);
    if (m)
        sscanf(m + 10, "%ld", &modules);
    if (pr)
        sscanf(pr + 13, "%ld", &prims);
    printf("  run summary: %zu steps recorded; last, step %ld: %ld modules, %ld primitives\n",
           steps, step, modules, prims);
}

/* ---- the forester's summary (cambium/measure.h) ---- */

static void print_quantiles(const cbm_measure_quantiles *q, double scale, const char *unit)
{
    printf("median %.3g%s, quartiles %.3g..%.3g, 10-90 %% %.3g..%.3g, range %.3g..%.3g",
           q->median * scale, unit, q->q25 * scale, q->q75 * scale, q->q10 * scale, q->q90 * scale,
           q->min * scale, q->max * scale);
}

void cli_measures_print(const cbm_tree_measures *m)
{
    if (m->diameter_at_base)
        printf(
            "  height %.3f m; trunk diameter at the base %.2f cm (the trunk stays below 1.3 m)\n",
            m->height, m->base_diameter * 100.0);
    else
        printf("  height %.3f m; trunk diameter at breast height (1.3 m) %.2f cm, at the base "
               "%.2f cm\n",
               m->height, m->diameter * 100.0, m->base_diameter * 100.0);
    printf("  crown width %.3f m, crown base ", m->crown_width);
    if (isfinite(m->crown_base_height))
        printf("%.3f m", m->crown_base_height);
    else
        printf("none (no branch of 5 %% of the axis length)");
    printf(", lowest point %.3f m", m->lowest);
    printf("; %zu segments, %zu axes, branch orders 0..%d, axis length %.3g m\n", m->segments,
           m->axes, m->max_order, m->total_length);
    if (isfinite(m->buckling_height))
        printf("  self-buckling: trunk E %.3g GPa, density %.0f kg/m^3: H_cr %.3g m, "
               "H/H_cr %.3f (real trees about 0.25)\n",
               m->trunk_modulus / 1e9, m->trunk_density, m->buckling_height, m->buckling_ratio);
    else
        printf("  self-buckling: unknown (the table has no wood modulus and density)\n");
    printf("  pipe model at %zu forks", m->forks);
    if (m->forks_unsolved)
        printf(" (%zu without an exponent: a child as thick as its parent)", m->forks_unsolved);
    if (m->pipe_exponent.count) {
        printf(": exponent ");
        print_quantiles(&m->pipe_exponent, 1.0, "");
        printf(" (Leonardo: 2)");
    }
    printf("\n  branch angles of %zu laterals", m->branch_angle.count);
    if (m->branch_angle.count) {
        printf(": ");
        print_quantiles(&m->branch_angle, 180.0 / INFO_PI, " deg");
    }
    printf("\n");
    if (m->stress_ratio.count) {
        printf("  stress ratio (stress / MOR) of %zu segments: ", m->stress_ratio.count);
        print_quantiles(&m->stress_ratio, 1.0, "");
        printf("; %.2f %% above 0.5\n", 100.0 * m->stress_above_half);
    } else {
        printf("  stress ratio: unknown (no stress or modulus of rupture in the table)\n");
    }
    printf("  intersections: %zu segments (%.2f %%) pass through a non-adjacent segment, %zu "
           "pairs\n",
           m->intersecting, 100.0 * m->intersecting_fraction, m->intersecting_pairs);
}

static void quantiles_json(cbm_json *j, const char *key, const cbm_measure_quantiles *q,
                           double scale)
{
    cbm_json_begin_object(j, key);
    cbm_json_int(j, "count", (int64_t)q->count);
    cbm_json_number(j, "min", q->min * scale);
    cbm_json_number(j, "q10", q->q10 * scale);
    cbm_json_number(j, "q25", q->q25 * scale);
    cbm_json_number(j, "median", q->median * scale);
    cbm_json_number(j, "q75", q->q75 * scale);
    cbm_json_number(j, "q90", q->q90 * scale);
    cbm_json_number(j, "max", q->max * scale);
    cbm_json_end_object(j);
}

void cli_measures_json(cbm_json *j, const char *key, const cbm_tree_measures *m)
{
    cbm_json_begin_object(j, key);
    cbm_json_int(j, "segments", (int64_t)m->segments);
    cbm_json_int(j, "axes", (int64_t)m->axes);
    cbm_json_int(j, "max_order", m->max_order);
    cbm_json_number(j, "height_m", m->height);
    cbm_json_number(j, "lowest_m", m->lowest);
    cbm_json_number(j, "axis_length_m", m->total_length);
    cbm_json_number(j, "diameter_m", m->diameter);
    cbm_json_string(j, "diameter_at", m->diameter_at_base ? "base" : "breast height");
    cbm_json_number(j, "base_diameter_m", m->base_diameter);
    cbm_json_number(j, "crown_width_m", m->crown_width);
    cbm_json_number(j, "crown_base_height_m", m->crown_base_height);
    cbm_json_number(j, "trunk_modulus_Pa", m->trunk_modulus);
    cbm_json_number(j, "trunk_density_kg_m3", m->trunk_density);
    cbm_json_number(j, "buckling_height_m", m->buckling_height);
    cbm_json_number(j, "buckling_ratio", m->buckling_ratio);
    cbm_json_int(j, "forks", (int64_t)m->forks);
    cbm_json_int(j, "forks_unsolved", (int64_t)m->forks_unsolved);
    quantiles_json(j, "pipe_exponent", &m->pipe_exponent, 1.0);
    quantiles_json(j, "branch_angle_deg", &m->branch_angle, 180.0 / INFO_PI);
    quantiles_json(j, "stress_ratio", &m->stress_ratio, 1.0);
    cbm_json_number(j, "stress_above_half", m->stress_above_half);
    cbm_json_int(j, "intersecting_segments", (int64_t)m->intersecting);
    cbm_json_number(j, "intersecting_fraction", m->intersecting_fraction);
    cbm_json_int(j, "intersecting_pairs", (int64_t)m->intersecting_pairs);
    cbm_json_end_object(j);
}

/* The number of a top-level-of-obj key "key": inside the object text obj..end; NaN if absent
 * or null. */
static double json_number_in(const char *obj, const char *end, const char *key)
{
    char pat[64];
    snprintf(pat, sizeof pat, "\"%s\":", key);
    size_t n = strlen(pat);
    for (const char *p = obj; p && p + n <= end; p++) {
        p = strstr(p, pat);
        if (!p || p + n > end)
            break;
        char *e = NULL;
        double v = strtod(p + n, &e);
        return e == p + n ? NAN : v;
    }
    return NAN;
}

/* The end of the JSON object or array that starts at p (just after its closing bracket). */
static const char *json_skip(const char *p)
{
    int depth = 0;
    for (; *p; p++) {
        if (*p == '"') {
            for (p++; *p && *p != '"'; p++)
                if (*p == '\\' && p[1])
                    p++;
            if (!*p)
                break;
        } else if (*p == '{' || *p == '[') {
            depth++;
        } else if (*p == '}' || *p == ']') {
            if (--depth == 0)
                return p + 1;
        }
    }
    return p;
}

static cbm_measure_quantiles quantiles_from_json(const char *obj, const char *end, const char *key)
{
    cbm_measure_quantiles q = {0, NAN, NAN, NAN, NAN, NAN, NAN, NAN};
    char pat[64];
    snprintf(pat, sizeof pat, "\"%s\":{", key);
    const char *p = strstr(obj, pat);
    if (!p || p >= end)
        return q;
    p += strlen(pat) - 1;
    const char *e = json_skip(p);
    double c = json_number_in(p, e, "count");
    q.count = c > 0 ? (size_t)c : 0;
    q.min = json_number_in(p, e, "min");
    q.q10 = json_number_in(p, e, "q10");
    q.q25 = json_number_in(p, e, "q25");
    q.median = json_number_in(p, e, "median");
    q.q75 = json_number_in(p, e, "q75");
    q.q90 = json_number_in(p, e, "q90");
    q.max = json_number_in(p, e, "max");
    return q;
}

/* The measures written by cli_measures_json, read back from the object at obj (its '{'). */
static cbm_tree_measures measures_from_json(const char *obj)
{
    const char *e = json_skip(obj);
    cbm_tree_measures m = {0};
    /* the quantile objects hold no key of the outer object's names */
    m.segments = (size_t)fmax(0.0, json_number_in(obj, e, "segments"));
    m.axes = (size_t)fmax(0.0, json_number_in(obj, e, "axes"));
    m.max_order = (int)fmax(0.0, json_number_in(obj, e, "max_order"));
    m.height = json_number_in(obj, e, "height_m");
    m.lowest = json_number_in(obj, e, "lowest_m");
    m.total_length = json_number_in(obj, e, "axis_length_m");
    m.diameter = json_number_in(obj, e, "diameter_m");
    const char *at = strstr(obj, "\"diameter_at\":\"base\"");
    m.diameter_at_base = at && at < e;
    m.base_diameter = json_number_in(obj, e, "base_diameter_m");
    m.crown_width = json_number_in(obj, e, "crown_width_m");
    m.crown_base_height = json_number_in(obj, e, "crown_base_height_m");
    m.trunk_modulus = json_number_in(obj, e, "trunk_modulus_Pa");
    m.trunk_density = json_number_in(obj, e, "trunk_density_kg_m3");
    m.buckling_height = json_number_in(obj, e, "buckling_height_m");
    m.buckling_ratio = json_number_in(obj, e, "buckling_ratio");
    m.forks = (size_t)fmax(0.0, json_number_in(obj, e, "forks"));
    m.forks_unsolved = (size_t)fmax(0.0, json_number_in(obj, e, "forks_unsolved"));
    m.pipe_exponent = quantiles_from_json(obj, e, "pipe_exponent");
    m.branch_angle = quantiles_from_json(obj, e, "branch_angle_deg");
    m.branch_angle.min *= INFO_PI / 180.0;
    m.branch_angle.q10 *= INFO_PI / 180.0;
    m.branch_angle.q25 *= INFO_PI / 180.0;
    m.branch_angle.median *= INFO_PI / 180.0;
    m.branch_angle.q75 *= INFO_PI / 180.0;
    m.branch_angle.q90 *= INFO_PI / 180.0;
    m.branch_angle.max *= INFO_PI / 180.0;
    m.stress_ratio = quantiles_from_json(obj, e, "stress_ratio");
    m.stress_above_half = json_number_in(obj, e, "stress_above_half");
    m.intersecting = (size_t)fmax(0.0, json_number_in(obj, e, "intersecting_segments"));
    m.intersecting_fraction = json_number_in(obj, e, "intersecting_fraction");
    m.intersecting_pairs = (size_t)fmax(0.0, json_number_in(obj, e, "intersecting_pairs"));
    return m;
}

/* The measures as a JSON document on stdout: {"file": ..., "table": ..., "measures": {...}}. */
static int print_measures_json(const char *path, const char *table, const cbm_tree_measures *m)
{
    cbm_context *ctx = cli_context();
    cbm_json *j = NULL;
    cbm_status s = cbm_json_create(ctx, &j);
    if (s == CBM_OK) {
        cbm_json_begin_object(j, NULL);
        cbm_json_string(j, "file", path);
        cbm_json_string(j, "table", table);
        cli_measures_json(j, "measures", m);
        cbm_json_end_object(j);
        const char *text = NULL;
        size_t len = 0;
        s = cbm_json_text(j, &text, &len);
        if (s == CBM_OK) {
            fwrite(text, 1, len, stdout);
            fputc('\n', stdout);
        }
    }
    cbm_json_destroy(j);
    int rc = s == CBM_OK ? CLI_OK : cli_fail(ctx, s, path);
    cli_context_end(ctx);
    return rc;
}

/* ---- segment tables (docs/formats.md): the mechanical plant's and the turtle's ---- */

enum { SEG_MECH, SEG_TURTLE };

/* The columns a table needs, by kind; -1 = not needed. */
static const char *const MECH_COLS[] = {
    "id",          "parent",   "order",    "x0_m",     "y0_m",
    "z0_m",        "x1_m",     "y1_m",     "z1_m",     "a_m",
    "b_m",         "length_m", "EI_L_Nm2", "EI_U_Nm2", "carried_mass_kg",
    "stress_ratio"};
static const char *const TURTLE_COLS[] = {"id", "parent", "lateral", "order", "x0",     "y0",
                                          "z0", "x1",     "y1",      "z1",    "width0", "width1"};
#define NMECH   (sizeof MECH_COLS / sizeof MECH_COLS[0])
#define NTURTLE (sizeof TURTLE_COLS / sizeof TURTLE_COLS[0])

/* Index of each wanted column in the header line (which ends at nl); false if one is missing. */
static bool header_columns(const char *t, const char *nl, const char *const *want, size_t nwant,
                           int *col)
{
    for (size_t k = 0; k < nwant; k++) {
        col[k] = -1;
        int c = 0;
        for (const char *p = t; p < nl; c++) {
            size_t n = strcspn(p, ",\r\n");
            if (n == strlen(want[k]) && !strncmp(p, want[k], n))
                col[k] = c;
            p += n;
            if (*p != ',')
                break;
            p++;
        }
        if (col[k] < 0)
            return false;
    }
    return true;
}

/* Reads a segments table into *out (n rows); returns CLI_OK, or prints "path:line: error: ..."
 * and returns CLI_FAIL. */
static int read_segment_table(const char *path, const char *t, int kind, cbm_measure_segment **out,
                              size_t *nout)
{
    const char *nl = strchr(t, '\n');
    int col[NMECH] = {0};
    const char *const *want = kind == SEG_MECH ? MECH_COLS : TURTLE_COLS;
    size_t nwant = kind == SEG_MECH ? NMECH : NTURTLE;
    header_columns(t, nl, want, nwant, col);
    size_t rows = 0;
    for (const char *p = nl + 1; *p; p++)
        rows += *p == '\n' || !p[1];
    double *own = NULL, *volume = NULL, *order = NULL; /* in v after the 64 fields */
    cbm_measure_segment *s = calloc(rows ? rows : 1, sizeof *s);
    double *v = calloc(64 + 3 * (rows ? rows : 1), sizeof *v);
    if (!s || !v) {
        free(s), free(v);
        fprintf(stderr, "cambium: %s: out of memory\n", path);
        return CLI_FAIL;
    }
    own = v + 64, volume = own + rows, order = volume + rows;
    size_t n = 0;
    int line = 1;
    for (const char *p = nl + 1; *p && n < rows; line++) {
        const char *end = strchr(p, '\n');
        if (!end)
            end = p + strlen(p);
        if (end == p || (end == p + 1 && *p == '\r')) {
            p = *end ? end + 1 : end;
            continue;
        }
        /* every field of the row as a number (empty = NaN) */
        int nf = 0;
        const char *q = p;
        for (;;) {
            char *e = NULL;
            double x = NAN;
            if (*q != ',' && *q != '\n' && *q != '\r' && *q) {
                x = strtod(q, &e);
                if (e == q || (*e != ',' && *e != '\n' && *e != '\r' && *e)) {
                    fprintf(stderr, "%s:%d:%d: error: field %d is not a number\n", path, line + 1,
                            (int)(q - p) + 1, nf + 1);
                    free(s), free(v);
                    return CLI_FAIL;
                }
                q = e;
            }
            if (nf < 64)
                v[nf] = x;
            nf++;
            if (*q != ',')
                break;
            q++;
        }
        double f[NMECH] = {0};
        for (size_t k = 0; k < nwant; k++) {
            if (col[k] >= nf || col[k] >= 64) {
                fprintf(stderr, "%s:%d: error: %d fields, the column %s is missing\n", path,
                        line + 1, nf, want[k]);
                free(s), free(v);
                return CLI_FAIL;
            }
            f[k] = v[col[k]];
        }
        cbm_measure_segment *g = &s[n];
        double parent = f[1];
        if (f[0] != (double)n || !(parent >= -1.0 && parent < (double)n) ||
            parent != floor(parent)) {
            fprintf(stderr,
                    "%s:%d: error: segment %zu: id %g or parent %g (the rows must be numbered "
                    "from 0, each parent an earlier row or -1)\n",
                    path, line + 1, n, f[0], parent);
            free(s), free(v);
            return CLI_FAIL;
        }
        g->parent = (int64_t)parent;
        if (kind == SEG_MECH) {
            g->p0 = (cbm_vec3){f[3], f[4], f[5]};
            g->p1 = (cbm_vec3){f[6], f[7], f[8]};
            double a = f[9], b = f[10], len = f[11];
            g->r0 = g->r1 = 0.5 * (a + b);
            double im = INFO_PI * a * a * b * b / 4.0;
            g->youngs_modulus = im > 0.0 ? sqrt(f[12] * f[13]) / im : NAN;
            own[n] = f[14]; /* carried; the children's carried masses are taken off below */
            volume[n] = len * INFO_PI * a * b;
            g->stress_ratio = f[15];
            /* the continuation keeps its parent's order (the first such child) */
            order[n] = f[2];
            g->lateral = g->parent >= 0 && order[n] != order[g->parent];
        } else {
            g->lateral = f[2] != 0.0;
            g->p0 = (cbm_vec3){f[4], f[5], f[6]};
            g->p1 = (cbm_vec3){f[7], f[8], f[9]};
            g->r0 = 0.5 * f[10];
            g->r1 = 0.5 * f[11];
            g->youngs_modulus = g->density = g->stress_ratio = NAN;
        }
        n++;
        p = *end ? end + 1 : end;
    }
    if (kind == SEG_MECH) {
        /* own mass = carried - the children's carried (wood and the point mass at the tip); in
         * increasing order own[i] is still i's carried mass when i is taken off its parent */
        for (size_t i = 0; i < n; i++)
            if (s[i].parent >= 0)
                own[s[i].parent] -= own[i];
        for (size_t i = 0; i < n; i++)
            s[i].density = volume[i] > 0.0 && own[i] > 0.0 ? own[i] / volume[i] : NAN;
    }
    free(v);
    *out = s;
    *nout = n;
    return CLI_OK;
}

/* The kind of segments table a CSV header names, -1 for any other table. */
static int segment_table_kind(const char *t)
{
    const char *nl = strchr(t, '\n');
    int col[NMECH] = {0};
    if (!nl)
        return -1;
    if (header_columns(t, nl, MECH_COLS, NMECH, col))
        return SEG_MECH;
    if (header_columns(t, nl, TURTLE_COLS, NTURTLE, col))
        return SEG_TURTLE;
    return -1;
}

static int info_segments(const char *path, const char *t, int kind, bool json)
{
    cbm_measure_segment *s = NULL;
    size_t n = 0;
    int rc = read_segment_table(path, t, kind, &s, &n);
    if (rc != CLI_OK)
        return rc;
    cbm_context *ctx = cli_context();
    cbm_tree_measures m;
    cbm_status st = cbm_measure_segments(ctx, NULL, s, n, &m);
    free(s);
    if (st != CBM_OK) {
        rc = cli_fail(ctx, st, path);
        cli_context_end(ctx);
        return rc;
    }
    cli_context_end(ctx);
    const char *table = kind == SEG_MECH ? "mechanical segments" : "turtle segments";
    if (json)
        return print_measures_json(path, table, &m);
    printf("  %s table: %zu segments%s\n", table, n,
           kind == SEG_TURTLE ? " (the model's units, read as metres)" : "");
    cli_measures_print(&m);
    return CLI_OK;
}

/* `cambium grow -o x.json`: the last year's figures and the measures of the final tree. */
static int info_grow_summary(const char *path, const char *t, bool json)
{
    const char *mo = strstr(t, "\"measures\":{");
    cbm_tree_measures m;
    if (mo)
        m = measures_from_json(mo + strlen("\"measures\":"));
    if (json) {
        if (!mo) {
            fprintf(stderr,
                    "cambium: %s: no measures in this summary (written before they were "
                    "added)\n",
                    path);
            return CLI_FAIL;
        }
        return print_measures_json(path, "grow summary", &m);
    }
    const char *last = NULL;
    for (const char *p = t; (p = strstr(p, "{\"year\":")) != NULL; p++)
        last = p;
    const char *model = strstr(t, "\"model\":\"");
    printf("  growth summary of %.*s: %zu years recorded\n",
           model ? (int)strcspn(model + 9, "\"") : 1, model ? model + 9 : "?",
           count_of(t, "{\"year\":"));
    if (last) {
        const char *e = json_skip(last);
        printf("  last year %g: %g segments, height %.3f m, crown %.3f m, %g leaves, %g fruit\n",
               json_number_in(last, e, "year"), json_number_in(last, e, "segments"),
               json_number_in(last, e, "height_m"), json_number_in(last, e, "crown_width_m"),
               json_number_in(last, e, "leaves"), json_number_in(last, e, "fruit"));
    }
    if (mo) {
        printf("  the final tree:\n");
        cli_measures_print(&m);
    }
    return CLI_OK;
}

static void info_help(const cli_opts *t)
{
    printf("usage: cambium info [--json] FILE\n\n"
           "Says what a model (.l) or an output file (.str .obj .ply .glb .png .svg\n"
           ".csv .json) holds. A segments table (cambium grow -o x.csv, cambium run\n"
           "-o segments:x.csv) and the summary of cambium grow (-o x.json) get the\n"
           "forester's measures of the tree: height, trunk diameter at breast height,\n"
           "crown width and base, safety against self-buckling, pipe-model exponent,\n"
           "branch angles, stress ratios, branch intersections (docs/models.md).\n\n");
    cli_options_help(stdout, t);
}

/* The file: one. */
static bool parse_file(const char *a, void *target, char *why, size_t n)
{
    const char **path = target;
    if (*path)
        snprintf(why, n, "expected one FILE, got '%s' and '{value}'", *path);
    else
        *path = a;
    return !*why;
}

int cmd_info(int argc, char **argv)
{
    const char *path = NULL;
    bool json = false;
    cli_opt rows[] = {
        {.name = "--help|-h", .kind = CLI_HELP},
        {.name = "FILE", .kind = CLI_POSITIONAL, .target = &path, .parse = parse_file},
        {.name = "--json",
         .kind = CLI_SET,
         .target = &json,
         .help = "the measures as JSON on stdout (segments tables, grow summaries)"},
        {0}};
    cli_opts table = {.cmd = "info",
                      .opts = rows,
                      .help = info_help,
                      .width = 9,
                      .unknown = "unknown option {opt}"};
    int prc = cli_options_parse(&table, argc, argv);
    if (prc != CLI_OK)
        return prc == CLI_HELP_SHOWN ? CLI_OK : prc;
    if (!path)
        return cli_usage_error("info", "expected one FILE");
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISREG(st.st_mode)) {
        fprintf(stderr, "cambium: %s: cannot open\n", path);
        return CLI_FAIL;
    }
    const char *ext = cli_extension(path);
    if (!strcmp(ext, "l") && !json)
        return info_model(path);
    size_t n = 0;
    char *t = slurp(path, &n);
    if (!t) {
        fprintf(stderr, "cambium: %s: cannot read\n", path);
        return CLI_FAIL;
    }
    int kind = !strcmp(ext, "csv") ? segment_table_kind(t) : -1;
    bool grow_json = !strcmp(ext, "json") && strstr(t, "\"years\":[") != NULL;
    if (json) {
        int r = CLI_FAIL;
        if (kind >= 0)
            r = info_segments(path, t, kind, true);
        else if (grow_json)
            r = info_grow_summary(path, t, true);
        else
            fprintf(stderr, "cambium info: --json takes a segments table (.csv) or a grow "
                            "summary (.json)\n");
        free(t);
        return r;
    }
    printf("%s: %.1f kB\n", path, (double)n / 1e3);
    int rc = CLI_OK;
    if (!strcmp(ext, "str"))
        info_str(t);
    else if (!strcmp(ext, "obj"))
        info_obj(t);
    else if (!strcmp(ext, "ply"))
        info_ply(t);
    else if (!strcmp(ext, "glb"))
        rc = info_glb(path, (const unsigned char *)t, n);
    else if (!strcmp(ext, "png"))
        rc = info_png((const unsigned char *)t, n);
    else if (!strcmp(ext, "svg"))
        info_svg(t);
    else if (kind >= 0)
        rc = info_segments(path, t, kind, false);
    else if (!strcmp(ext, "csv"))
        info_csv(t);
    else if (grow_json)
        rc = info_grow_summary(path, t, false);
    else if (!strcmp(ext, "json"))
        info_json(t);
    else
        printf("  a .%s file (cambium reads .l .str .obj .ply .glb .png .svg .csv .json)\n", ext);
    free(t);
    return rc;
}
