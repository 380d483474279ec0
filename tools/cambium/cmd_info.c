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

#include <dirent.h>
#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

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

int cmd_info(int argc, char **argv)
{
    if (argc != 2 || !strcmp(argv[1], "--help") || !strcmp(argv[1], "-h")) {
        if (argc == 2) {
            printf("usage: cambium info FILE\n\n"
                   "Says what a model (.l) or an output file (.str .obj .ply .glb .png .svg\n"
                   ".csv .json) holds.\n");
            return CLI_OK;
        }
        return cli_usage_error("info", "expected one FILE");
    }
    const char *path = argv[1];
    struct stat st;
    if (stat(path, &st) != 0 || !S_ISREG(st.st_mode)) {
        fprintf(stderr, "cambium: %s: cannot open\n", path);
        return CLI_FAIL;
    }
    const char *ext = cli_extension(path);
    if (!strcmp(ext, "l"))
        return info_model(path);
    size_t n = 0;
    char *t = slurp(path, &n);
    if (!t) {
        fprintf(stderr, "cambium: %s: cannot read\n", path);
        return CLI_FAIL;
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
    else if (!strcmp(ext, "csv"))
        info_csv(t);
    else if (!strcmp(ext, "json"))
        info_json(t);
    else
        printf("  a .%s file (cambium reads .l .str .obj .ply .glb .png .svg .csv .json)\n", ext);
    free(t);
    return rc;
}
