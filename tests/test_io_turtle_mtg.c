/* The turtle's segments as an MTG and a CSV table (cbm_write_turtle_mtg,
 * cbm_write_turtle_segments_csv): a bracketed string of known topology against a hand-written MTG,
 * degenerate segments skipped as the turtle skips them, a string without segments, random
 * bracketed strings read back by a small reader of the FORM-A subset we write (the TOPO column
 * rules of openalea/mtg doc/user/syntax.rst), out of memory, and no file left on failure. */
#include "io_util.h"

#include "cambium/turtle.h"
#include "cambium/write.h"

#include <math.h>
#include <unistd.h>

enum { MAXM = 4096 };

typedef struct mstr {
    cbm_tmodule m[MAXM];
    double p[MAXM];
    char names[MAXM][4];
    size_t n;
} mstr;

/* "F(1) [ | F(3) ]": modules separated by spaces, at most one parameter each. */
static void parse(mstr *s, const char *text)
{
    s->n = 0;
    const char *c = text;
    while (*c && s->n < MAXM) {
        while (*c == ' ')
            c++;
        if (!*c)
            break;
        size_t k = 0;
        while (*c && *c != ' ' && *c != '(' && k < 3)
            s->names[s->n][k++] = *c++;
        s->names[s->n][k] = '\0';
        cbm_tmodule *m = &s->m[s->n];
        m->name = s->names[s->n];
        m->nparams = 0;
        m->params = &s->p[s->n];
        if (*c == '(') {
            char *e;
            s->p[s->n] = strtod(c + 1, &e);
            m->nparams = 1;
            c = e + 1;
        }
        s->n++;
    }
}

static cbm_status interpret_into(cbm_context *ctx, mstr *s, cbm_scene *scene, cbm_view **v,
                                 cbm_turtle **t)
{
    *t = NULL;
    cbm_status st0 = cbm_view_create(ctx, v);
    if (st0 != CBM_OK)
        return st0;
    cbm_turtle_def def = {true};
    cbm_status st = cbm_turtle_interpret(ctx, *v, &def, s->m, s->n, scene, t);
    if (st != CBM_OK) {
        cbm_view_destroy(*v);
        *v = NULL;
    }
    return st;
}

static cbm_status interpret(cbm_context *ctx, mstr *s, cbm_view **v, cbm_turtle **t)
{
    return interpret_into(ctx, s, NULL, v, t);
}

/* Segment 0 bears two laterals before its continuation; the second lateral bears a lateral and a
 * continuation of its own (nested); colour and width set inside the branches. */
static const char *const KNOWN = "F(1) [ F(2) ] [ | F(3) [ ;(3) F(4) ] !(0.5) F(5) ] F(6)";

static const char *const KNOWN_MTG =
    "# cambium turtle: the model's units, y up; segments (S) as the turtle draws them, in axes "
    "(A) of plants (P)\n"
    "CODE:\tFORM-A\n"
    "CLASSES:\n"
    "SYMBOL\tSCALE\tDECOMPOSITION\tINDEXATION\tDEFINITION\n"
    "$\t0\tFREE\tFREE\tIMPLICIT\n"
    "P\t1\tCONNECTED\tFREE\tIMPLICIT\n"
    "A\t2\t<-LINEAR\tFREE\tIMPLICIT\n"
    "S\t3\tNONE\tFREE\tEXPLICIT\n"
    "DESCRIPTION:\n"
    "LEFT\tRIGHT\tRELTYPE\tMAX\n"
    "A\tA\t+\t?\n"
    "S\tS\t<\t1\n"
    "S\tS\t+\t?\n"
    "FEATURES:\n"
    "NAME\tTYPE\n"
    "id\tINT\n"
    "order\tINT\n"
    "module\tINT\n"
    "color\tINT\n"
    "x0\tREAL\n"
    "y0\tREAL\n"
    "z0\tREAL\n"
    "x1\tREAL\n"
    "y1\tREAL\n"
    "z1\tREAL\n"
    "width0\tREAL\n"
    "width1\tREAL\n"
    "length\tREAL\n"
    "MTG:\n"
    "TOPO\t\t\tid\torder\tmodule\tcolor\tx0\ty0\tz0\tx1\ty1\tz1\twidth0\twidth1\tlength\n"
    "/P1/A1/S1\t\t\t0\t0\t0\t128\t0\t0\t0\t0\t1\t0\t1\t1\t1\n"
    "\t+A2/S1\t\t1\t1\t2\t128\t0\t1\t0\t0\t3\t0\t1\t1\t2\n"
    "\t+A3/S1\t\t2\t1\t6\t128\t0\t1\t0\t0\t-2\t0\t1\t1\t3\n"
    "\t\t+A4/S1\t3\t2\t9\t3\t0\t-2\t0\t0\t-6\t0\t1\t1\t4\n"
    "\t^<S2\t\t4\t1\t12\t128\t0\t-2\t0\t0\t-7\t0\t0.5\t0.5\t5\n"
    "^<S2\t\t\t5\t0\t14\t128\t0\t1\t0\t0\t7\t0\t1\t1\t6\n";

TEST(turtle_mtg_known_topology)
{
    cbm_context *ctx = test_ctx();
    static mstr s;
    parse(&s, KNOWN);
    cbm_view *v;
    cbm_turtle *t;
    CHECK_OK(interpret(ctx, &s, &v, &t));
    CHECK_OK(cbm_write_turtle_mtg(ctx, t, io_path("known.mtg")));
    CHECK_OK(cbm_write_turtle_segments_csv(ctx, t, io_path("known.csv")));
    char *b = io_read_all(io_path("known.mtg"), NULL);
    CHECK(b != NULL);
    if (b) {
        CHECK_MSG(strcmp(b, KNOWN_MTG) == 0, "got:\n%s", b);
        free(b);
    }
    b = io_read_all(io_path("known.csv"), NULL);
    CHECK(b != NULL);
    if (b) {
        const char *want =
            "id,parent,lateral,order,module,color,x0,y0,z0,x1,y1,z1,width0,width1,length\n"
            "0,-1,0,0,0,128,0,0,0,0,1,0,1,1,1\n"
            "1,0,1,1,2,128,0,1,0,0,3,0,1,1,2\n"
            "2,0,1,1,6,128,0,1,0,0,-2,0,1,1,3\n"
            "3,2,1,2,9,3,0,-2,0,0,-6,0,1,1,4\n"
            "4,2,0,1,12,128,0,-2,0,0,-7,0,0.5,0.5,5\n"
            "5,0,0,0,14,128,0,1,0,0,7,0,1,1,6\n";
        CHECK_MSG(strcmp(b, want) == 0, "got:\n%s", b);
        free(b);
    }
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    test_ctx_end(ctx);
}

/* ---- a reader of the MTG subset we write ---- */

static double field(const char *line, int k)
{
    for (int i = 0; i < k && line; i++) {
        line = strchr(line, '\t');
        if (line)
            line++;
    }
    return line ? strtod(line, NULL) : NAN;
}

/* Parents (-1: a plant's root) and lateral flags by the id feature; returns the number of segment
 * lines, -1 on a malformed file. */
static int read_mtg(const char *b, int64_t *parent, bool *lateral, int max, int *plants)
{
    const char *code = strstr(b, "\nMTG:\nTOPO");
    if (!code)
        return -1;
    int ncols = 0;
    const char *q = code + 10;
    while (*q == '\t')
        q++, ncols++;
    if (strncmp(q, "id\torder\tmodule\tcolor\t", 22) != 0 || ncols > 64)
        return -1;
    int64_t latest[64];
    int lines = 0;
    *plants = 0;
    for (const char *line = strchr(code + 6, '\n'); line && line[1];
         line = strchr(line + 1, '\n')) {
        const char *l = line + 1;
        int col = 0;
        while (l[col] == '\t')
            col++;
        char tok[32];
        double id = field(l + col, ncols - col);
        if (col >= ncols || sscanf(l + col, "%31[^\t]", tok) != 1 || !(id >= 0 && id < max))
            return -1;
        int64_t i = (int64_t)id, pa;
        if (tok[0] == '/') {
            if (col != 0 || !strstr(tok, "/A1/S1"))
                return -1;
            pa = -1;
            (*plants)++;
        } else if (tok[0] == '+') {
            if (col == 0 || !strstr(tok, "/S1"))
                return -1;
            pa = latest[col - 1];
        } else if (strncmp(tok, "^<S", 3) == 0) {
            pa = latest[col];
        } else {
            return -1;
        }
        parent[i] = pa;
        lateral[i] = tok[0] == '+';
        latest[col] = i;
        lines++;
    }
    return lines;
}

TEST(turtle_mtg_random_strings_read_back)
{
    cbm_context *ctx = test_ctx();
    static mstr s;
    static char text[MAXM * 8];
    static int64_t parent[MAXM];
    static bool lateral[MAXM];
    uint64_t g = 12345;
    for (int round = 0; round < 20; round++) {
        /* a random bracketed string: F of various lengths (some degenerate), turns, nested
         * branches, branches at the root (more plants) */
        size_t len = 0;
        int depth = 0;
        for (int k = 0; k < 600; k++) {
            g = g * 6364136223846793005ULL + 1442695040888963407ULL;
            int r = (int)(g >> 59); /* 0..31 */
            const char *m = r < 12                ? (r < 2 ? "F(0.001)" : "F(1)")
                            : r < 16              ? "+"
                            : r < 18              ? "&"
                            : r < 19              ? "f(1)"
                            : r < 24              ? "["
                            : r < 30 && depth > 0 ? "]"
                                                  : "/";
            depth += !strcmp(m, "[") - !strcmp(m, "]");
            len += (size_t)snprintf(text + len, sizeof text - len, "%s ", m);
        }
        parse(&s, text);
        cbm_view *v;
        cbm_turtle *t;
        CHECK_OK(interpret(ctx, &s, &v, &t));
        CHECK_OK(cbm_write_turtle_mtg(ctx, t, io_path("random.mtg")));
        /* the expected topology from the string alone: each F(1) draws a segment (F(0.001) is
         * degenerate), its parent the last one on the path, lateral after a `[` since it */
        static int64_t want_parent[MAXM];
        static bool want_lateral[MAXM];
        static int64_t st_last[MAXM];
        static bool st_br[MAXM];
        int64_t last = -1;
        bool br = false;
        size_t n = 0, sp = 0;
        int roots = 0;
        for (size_t k = 0; k < s.n; k++) {
            const char *m = s.m[k].name;
            if (!strcmp(m, "F") && s.p[k] > 0.5) {
                want_parent[n] = last;
                want_lateral[n] = last >= 0 && br;
                roots += last < 0;
                last = (int64_t)n++;
                br = false;
            } else if (!strcmp(m, "[")) {
                st_last[sp] = last;
                st_br[sp++] = br;
                br = true;
            } else if (!strcmp(m, "]")) {
                last = st_last[--sp];
                br = st_br[sp];
            }
        }
        /* the record agrees */
        const cbm_prim *p = cbm_turtle_prims(t);
        size_t np = cbm_turtle_prim_count(t);
        CHECK_EQ_INT(np, n);
        for (size_t i = 0; i < np && i < n; i++) {
            CHECK(p[i].kind == CBM_PRIM_CYLINDER);
            CHECK(p[i].parent == want_parent[i] && p[i].lateral == want_lateral[i]);
            CHECK(!strcmp(s.m[p[i].module].name, "F"));
        }
        CHECK(n > 50);
        char *b = io_read_all(io_path("random.mtg"), NULL);
        CHECK(b != NULL);
        int plants = 0;
        int lines = b ? read_mtg(b, parent, lateral, MAXM, &plants) : -1;
        CHECK_EQ_INT(lines, n);
        CHECK_EQ_INT(plants, roots);
        for (size_t i = 0; i < n && lines == (int)n; i++) {
            CHECK_MSG(parent[i] == want_parent[i] && lateral[i] == want_lateral[i],
                      "round %d segment %zu: parent %lld lateral %d, want %lld %d", round, i,
                      (long long)parent[i], lateral[i], (long long)want_parent[i], want_lateral[i]);
        }
        free(b);
        cbm_turtle_destroy(t);
        cbm_view_destroy(v);
    }
    test_ctx_end(ctx);
}

/* Degenerate segments (too short: length^2 <= 1e-5) are not drawn, so not rows: the next
 * segment's parent is the last segment drawn. The scene has one part per row. */
TEST(turtle_mtg_degenerate_segments_skipped)
{
    cbm_context *ctx = test_ctx();
    static mstr s;
    parse(&s, "F(1) F(0.001) [ F(1) ] F(0) F(1) [ F(0.003) ]");
    cbm_scene *scene;
    CHECK_OK(cbm_scene_create(ctx, &scene));
    cbm_view *v;
    cbm_turtle *t;
    CHECK_OK(interpret_into(ctx, &s, scene, &v, &t));
    CHECK_EQ_INT(cbm_scene_part_count(scene), 3);
    CHECK_OK(cbm_write_turtle_segments_csv(ctx, t, io_path("degenerate.csv")));
    char *b = io_read_all(io_path("degenerate.csv"), NULL);
    CHECK(b != NULL);
    if (b) {
        const char *want =
            "id,parent,lateral,order,module,color,x0,y0,z0,x1,y1,z1,width0,width1,length\n"
            "0,-1,0,0,0,128,0,0,0,0,1,0,1,1,1\n"
            "1,0,1,1,3,128,0,1.001,0,0,2.001,0,1,1,1\n"
            "2,0,0,0,6,128,0,1.001,0,0,2.001,0,1,1,1\n";
        CHECK_MSG(strcmp(b, want) == 0, "got:\n%s", b);
        free(b);
    }
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    cbm_scene_destroy(scene);
    test_ctx_end(ctx);
}

/* No segments: a valid MTG with its header, its TOPO line and no plant; a CSV with its header. */
TEST(turtle_mtg_no_segments)
{
    cbm_context *ctx = test_ctx();
    static mstr s;
    parse(&s, "f(1) [ + f(2) ] @O(1)");
    cbm_view *v;
    cbm_turtle *t;
    CHECK_OK(interpret(ctx, &s, &v, &t));
    CHECK_EQ_INT(cbm_turtle_prim_count(t), 1); /* the sphere */
    CHECK_OK(cbm_write_turtle_mtg(ctx, t, io_path("empty.mtg")));
    CHECK_OK(cbm_write_turtle_segments_csv(ctx, t, io_path("empty.csv")));
    char *b = io_read_all(io_path("empty.mtg"), NULL);
    CHECK(b != NULL);
    if (b) {
        const char *tail = "MTG:\nTOPO\tid\torder\tmodule\tcolor\tx0\ty0\tz0\tx1\ty1\tz1\twidth0\t"
                           "width1\tlength\n";
        size_t lb = strlen(b), lt = strlen(tail);
        CHECK(lb > lt && strcmp(b + lb - lt, tail) == 0);
        CHECK(strncmp(b, KNOWN_MTG, (size_t)(strstr(KNOWN_MTG, "MTG:\n") - KNOWN_MTG)) == 0);
        int64_t parent[1];
        bool lateral[1];
        int plants = -1;
        CHECK_EQ_INT(read_mtg(b, parent, lateral, 1, &plants), 0);
        CHECK_EQ_INT(plants, 0);
        free(b);
    }
    b = io_read_all(io_path("empty.csv"), NULL);
    CHECK(b && strcmp(b, "id,parent,lateral,order,module,color,x0,y0,z0,x1,y1,z1,width0,width1,"
                         "length\n") == 0);
    free(b);
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    test_ctx_end(ctx);
}

/* A file that cannot be written is an error naming it, and leaves nothing behind. */
TEST(turtle_mtg_unwritable_path)
{
    cbm_context *ctx = test_ctx();
    static mstr s;
    parse(&s, KNOWN);
    cbm_view *v;
    cbm_turtle *t;
    CHECK_OK(interpret(ctx, &s, &v, &t));
    const char *path = io_path("no-such-dir/x.mtg");
    CHECK(cbm_write_turtle_mtg(ctx, t, path) != CBM_OK);
    CHECK(strstr(cbm_context_last_error(ctx), "no-such-dir") != NULL);
    CHECK(access(path, F_OK) != 0);
    CHECK(cbm_write_turtle_segments_csv(ctx, t, path) != CBM_OK);
    CHECK(access(path, F_OK) != 0);
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    test_ctx_end(ctx);
}

static cbm_status write_both(cbm_context *ctx, void *ud)
{
    mstr *s = ud;
    cbm_view *v;
    cbm_turtle *t;
    const char *mtg = io_path("oom.mtg"), *csv = io_path("oom.csv");
    remove(mtg);
    remove(csv);
    cbm_status st = interpret(ctx, s, &v, &t);
    if (st != CBM_OK)
        return st;
    st = cbm_write_turtle_mtg(ctx, t, mtg);
    if (st != CBM_OK && access(mtg, F_OK) == 0)
        st = CBM_E_INTERNAL; /* a half-written file */
    if (st == CBM_OK) {
        st = cbm_write_turtle_segments_csv(ctx, t, csv);
        if (st != CBM_OK && access(csv, F_OK) == 0)
            st = CBM_E_INTERNAL;
    }
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    return st;
}

TEST(turtle_mtg_out_of_memory)
{
    static mstr s;
    parse(&s, KNOWN);
    CHECK(test_oom_loop(write_both, &s) > 5);
}

/* Generalized cylinders (cylinder line style): each piece is a segment, in the axis of its
 * branch. */
TEST(turtle_mtg_generalized_cylinder_pieces)
{
    cbm_context *ctx = test_ctx();
    const char *vpath = io_path("gc.v");
    FILE *f = fopen(vpath, "w");
    CHECK(f != NULL);
    if (!f) {
        test_ctx_end(ctx);
        return;
    }
    fputs("line style: cylinder\n", f);
    fclose(f);
    cbm_view *v;
    CHECK_OK(cbm_view_load(ctx, vpath, &v));
    static mstr s;
    parse(&s, "F(1) [ + @Gs f(1) @Gc(2) f(1) @Ge(2) ] F(1)");
    cbm_turtle_def def = {true};
    cbm_turtle *t = NULL;
    CHECK_OK(cbm_turtle_interpret(ctx, v, &def, s.m, s.n, NULL, &t));
    const cbm_prim *p = cbm_turtle_prims(t);
    CHECK_EQ_INT(cbm_turtle_prim_count(t), 4);
    if (cbm_turtle_prim_count(t) == 4) {
        CHECK(p[1].kind == CBM_PRIM_GCYL && p[2].kind == CBM_PRIM_GCYL);
        CHECK(p[1].module == 5 && p[2].module == 7);
    }
    CHECK_OK(cbm_write_turtle_segments_csv(ctx, t, io_path("gc.csv")));
    char *b = io_read_all(io_path("gc.csv"), NULL);
    CHECK(b != NULL);
    if (b) {
        /* id,parent,lateral,order,module: the pieces are a lateral axis of two segments */
        const char *rows[] = {"0,-1,0,0,0,", "1,0,1,1,5,", "2,1,0,1,7,", "3,0,0,0,9,"};
        const char *line = strchr(b, '\n');
        for (int i = 0; i < 4; i++) {
            CHECK(line && strncmp(line + 1, rows[i], strlen(rows[i])) == 0);
            line = line ? strchr(line + 1, '\n') : NULL;
        }
        CHECK(line && line[1] == '\0');
        free(b);
    }
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    test_ctx_end(ctx);
}

/* The mechanical plant's MTG through the shared writer: its header, feature list and TOPO codes
 * as they were before the writer was shared (the feature values are the plant's, checked in
 * test_io_plant.c). */
TEST(mechanical_mtg_header_and_codes_pinned)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = NULL;
    CHECK_OK(cbm_plant_create(ctx, NULL, &p));
    const int64_t parents[] = {-1, 0, 1, 0, 3, -1};
    for (size_t i = 0; i < 6; i++) {
        cbm_segment_def d = cbm_segment_def_default();
        d.parent = parents[i];
        d.deviation = i == 3 ? 0.7 : 0.0;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    CHECK_OK(cbm_write_mtg(ctx, p, io_path("mech.mtg")));
    char *b = io_read_all(io_path("mech.mtg"), NULL);
    CHECK(b != NULL);
    if (b) {
        const char *head =
            "# cambium plant: metres, y up; segments (S) grouped in axes (A) of plants (P)\n"
            "CODE:\tFORM-A\n";
        CHECK(strncmp(b, head, strlen(head)) == 0);
        const char *feat = "FEATURES:\nNAME\tTYPE\nid\tINT\norder\tINT\nx0\tREAL\n";
        CHECK(strstr(b, feat) != NULL);
        CHECK(strstr(b, "\nreaction_wood\tREAL\nMTG:\nTOPO\t\tid\torder\tx0\t") != NULL);
        /* segment 3 is the lateral of 0 (deviated), 1 its continuation */
        const char *codes[] = {"\n/P1/A1/S1\t\t0\t0\t", "\n\t+A2/S1\t3\t1\t",
                               "\n\t^<S2\t4\t1\t",      "\n^<S2\t\t1\t0\t",
                               "\n^<S3\t\t2\t0\t",      "\n/P2/A1/S1\t\t5\t0\t"};
        /* E = 1e10 Pa, written without the exponent's '+' (a branch to openalea.mtg's reader):
         * no '+' but in the codes */
        CHECK(strstr(b, "\t1e10\t") != NULL);
        CHECK_EQ_INT(io_count(b, "+"), 2 + 1); /* DESCRIPTION's two ("A A +", "S S +"), +A2/S1 */
        const char *at = b;
        for (size_t i = 0; i < 6; i++) {
            const char *q = strstr(at, codes[i]);
            CHECK_MSG(q != NULL, "code %zu", i);
            at = q ? q + 1 : at;
        }
        free(b);
    }
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

/* Large values: exponents without '+' (openalea.mtg's reader would take it for a branch). */
TEST(turtle_mtg_exponents_without_plus)
{
    cbm_context *ctx = test_ctx();
    static mstr s;
    parse(&s, "F(2e10) F(3e-9) !(1e-6) F(4)");
    cbm_view *v;
    cbm_turtle *t;
    CHECK_OK(interpret(ctx, &s, &v, &t));
    CHECK_OK(cbm_write_turtle_mtg(ctx, t, io_path("big.mtg")));
    char *b = io_read_all(io_path("big.mtg"), NULL);
    CHECK(b != NULL);
    if (b) {
        const char *code = strstr(b, "\nMTG:\n");
        CHECK(code && strstr(code, "\t0\t0\t0\t0\t2e10\t0\t1\t1\t2e10\n") != NULL);
        CHECK(code && strchr(code, '+') == NULL); /* a single axis: no '+' at all */
        /* negative exponents as they are; the width is cpfg's float */
        CHECK(code && strstr(code, "\t9.99999997e-07\t9.99999997e-07\t4\n") != NULL);
        free(b);
    }
    cbm_turtle_destroy(t);
    cbm_view_destroy(v);
    test_ctx_end(ctx);
}
