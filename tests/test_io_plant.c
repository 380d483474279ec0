/* Tables of the mechanical plant: the per-segment CSV against the plant's own state, and the MTG
 * coding file read back by a small reader of the subset we write (the TOPO column rules of
 * openalea/mtg doc/user/syntax.rst) to recover the topology. */
#include "io_util.h"

/* Trunk of 6 segments; laterals on segments 1, 3 (two) and a sub-lateral; then a second root. */
static cbm_plant *small_plant(cbm_context *ctx)
{
    cbm_plant *p = NULL;
    CHECK_OK(cbm_plant_create(ctx, NULL, &p));
    cbm_plant_set_base(p, (cbm_vec3){0, 0, 0}, cbm_mech_clamp_orientation(1.2));
    const int64_t parents[] = {-1, 0, 1, 2, 3, 4, 1, 6, 3, 8, 9, 3, 8, -1, 13};
    for (size_t i = 0; i < sizeof parents / sizeof parents[0]; i++) {
        cbm_segment_def d = cbm_segment_def_default();
        d.parent = parents[i];
        d.length = 0.1 + 0.01 * (double)i;
        d.core.a = d.core.b = 0.02 - 0.001 * (double)i;
        d.core.modulus_of_rupture = 60e6;
        d.core.age = (double)(15 - i);
        d.deviation = parents[i] >= 0 && i != (size_t)parents[i] + 1 ? 0.7 : 0.0;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    CHECK_OK(cbm_plant_evaluate(p, NULL));
    return p;
}

static double field(const char *line, int k, char sep)
{
    for (int i = 0; i < k && line; i++) {
        line = strchr(line, sep);
        if (line)
            line++;
    }
    return line ? strtod(line, NULL) : NAN;
}

TEST(segments_csv_matches_the_plant)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = small_plant(ctx);
    CHECK_OK(cbm_write_plant(ctx, p, io_path("segments.csv"), NULL, 8));
    char *b = io_read_all(io_path("segments.csv"), NULL);
    CHECK(b != NULL);
    if (b) {
        CHECK(strncmp(b, "id,parent,order,x0_m,", 21) == 0);
        size_t n = cbm_plant_segment_count(p);
        CHECK_EQ_INT(io_count(b, "\n"), n + 1);
        const char *line = strchr(b, '\n') + 1;
        for (size_t i = 0; i < n && line; i++) {
            cbm_segment_state s;
            CHECK_OK(cbm_plant_segment(p, i, &s));
            CHECK_EQ_INT(field(line, 0, ','), i);
            CHECK_EQ_INT(field(line, 1, ','), s.parent);
            CHECK_EQ_INT(field(line, 2, ','), s.order);
            CHECK_REL(field(line, 6, ','), s.distal.x, 1e-8);
            CHECK_REL(field(line, 7, ','), s.distal.y, 1e-8);
            CHECK_REL(field(line, 11, ','), s.length, 1e-8);
            CHECK_REL(field(line, 12, ','), 10e9, 1e-12); /* E of the default ring */
            CHECK_REL(field(line, 15, ','), s.carried_mass, 1e-8);
            CHECK_REL(field(line, 19, ','), hypot(s.moment_local.y, s.moment_local.z), 1e-8);
            CHECK_REL(field(line, 20, ','), s.stress, 1e-8);
            CHECK_REL(field(line, 21, ','), s.stress / 60e6, 1e-8);
            CHECK_REL(field(line, 28, ','), s.age, 1e-12);
            line = strchr(line, '\n');
            line = line ? line + 1 : NULL;
        }
        free(b);
    }
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

TEST(mtg_topology_read_back)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = small_plant(ctx);
    CHECK_OK(cbm_write_plant(ctx, p, io_path("plant.mtg"), NULL, 8));
    char *b = io_read_all(io_path("plant.mtg"), NULL);
    CHECK(b != NULL);
    size_t n = cbm_plant_segment_count(p);
    if (b) {
        CHECK(strstr(b, "CODE:\tFORM-A\n") && strstr(b, "CLASSES:\n") &&
              strstr(b, "DESCRIPTION:\n") && strstr(b, "FEATURES:\n"));
        CHECK(strstr(b, "\nS\t3\tNONE\tFREE\tEXPLICIT\n") != NULL);
        char *code = strstr(b, "\nMTG:\nTOPO");
        CHECK(code != NULL);
        /* TOPO columns: tabs after TOPO up to the first feature name */
        int ncols = 0;
        const char *q = code ? code + 10 : "";
        while (*q == '\t')
            q++, ncols++;
        CHECK(strncmp(q, "id\torder\t", 9) == 0);
        int64_t latest[16] = {0};
        int64_t parent[64] = {0};
        bool seen[64] = {false}, lateral[64] = {false};
        int lines = 0, plants = 0;
        for (char *line = code ? strchr(code + 6, '\n') : NULL; line && line[1];
             line = strchr(line + 1, '\n')) {
            char *l = line + 1;
            int col = 0;
            while (l[col] == '\t')
                col++;
            CHECK(col < ncols && col < 16);
            char tok[32];
            CHECK(sscanf(l + col, "%31[^\t]", tok) == 1);
            double id = field(l + col, ncols - col, '\t');
            CHECK(id >= 0 && id < (double)n && id < 64);
            if (!(id >= 0 && id < (double)n && id < 64 && col < 16))
                break;
            int64_t i = (int64_t)id, pa;
            if (tok[0] == '/') {
                pa = -1;
                plants++;
                CHECK(col == 0 && strstr(tok, "/A1/S1"));
            } else if (tok[0] == '+') {
                CHECK(col > 0 && strstr(tok, "/S1"));
                pa = col > 0 ? latest[col - 1] : -2;
                lateral[i] = true;
            } else {
                CHECK(strncmp(tok, "^<S", 3) == 0);
                pa = latest[col];
            }
            parent[i] = pa;
            seen[i] = true;
            latest[col] = i;
            lines++;
        }
        CHECK_EQ_INT(lines, n);
        CHECK_EQ_INT(plants, 2);
        const int64_t *want = cbm_plant_parents(p);
        for (size_t i = 0; i < n; i++) {
            cbm_segment_state s;
            CHECK_OK(cbm_plant_segment(p, i, &s));
            CHECK_MSG(seen[i] && parent[i] == want[i], "segment %zu: parent %lld, want %lld", i,
                      (long long)parent[i], (long long)want[i]);
            CHECK(lateral[i] == (!s.continuation));
        }
        free(b);
    }
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

TEST(plant_to_picture_and_mesh)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = small_plant(ctx);
    cbm_write_options o = cbm_write_options_default();
    o.width = o.height = 64;
    o.threads = 1;
    o.color_by = CBM_COLOR_STRESS;
    CHECK_OK(cbm_write_plant(ctx, p, io_path("plant.png"), &o, 8));
    CHECK_OK(cbm_write_plant(ctx, p, io_path("plant.glb"), &o, 8));
    size_t len = 0;
    char *b = io_read_all(io_path("plant.glb"), &len);
    CHECK(b && len > 1000 && strstr(b + 20, "branch order 1") != NULL);
    free(b);
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

static cbm_status write_tables(cbm_context *ctx, void *ud)
{
    (void)ud;
    cbm_plant *p = NULL;
    cbm_status st = cbm_plant_create(ctx, NULL, &p);
    if (st != CBM_OK)
        return st;
    for (int i = 0; i < 6 && st == CBM_OK; i++) {
        cbm_segment_def d = cbm_segment_def_default();
        d.parent = i == 0 ? -1 : (i == 4 ? 1 : i - 1);
        st = cbm_plant_add_segment(p, &d, NULL);
    }
    if (st == CBM_OK)
        st = cbm_plant_evaluate(p, NULL);
    if (st == CBM_OK)
        st = cbm_write_plant(ctx, p, io_path("oom.csv"), NULL, 6);
    if (st == CBM_OK)
        st = cbm_write_plant(ctx, p, io_path("oom.mtg"), NULL, 6);
    if (st == CBM_OK)
        st = cbm_write_plant(ctx, p, io_path("oom.ply"), NULL, 6);
    cbm_plant_destroy(p);
    return st;
}

TEST(plant_tables_out_of_memory)
{
    CHECK(test_oom_loop(write_tables, NULL) > 5);
}
