/* Taylor-Hell's general fruit tree in the L+C dialect with the thesis' constants
 * (models/taylor-hell-fruit-tree-thesis.l; the real-wood default is tests/cli/mechlang_fruit.sh's
 * seeds): the model runs years deterministically, its resources are conserved at every node, and
 * the behaviours of the thesis' figures hold: the branches spring back when the leaves and fruit
 * fall (Fig. 4.1), an unfair allocation (F = 0.2) grows a taller, sparser tree than a fair one
 * (F = 1, Fig. 4.7), a low modulus of rupture breaks branches that a high one keeps (Fig. 8.9),
 * and the crooked aspen is lower and wider than the wild one (ch. 7). Few years each, so the file
 * also runs quickly under the sanitizers. */
#include "lsys_util.h"

#include "cambium/lsys.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define MS 26 /* doubles of a MechSegment */
/* fields of the model's Node after the MechSegment */
enum { N_LATERAL = MS, N_BUD, N_ABORTED, N_NODE_COUNT };
#define N_VIGOUR  (MS + 22)
#define N_VL      (MS + 23)
#define N_VC      (MS + 24)
#define N_LATFATE (MS + 25)
#define N_SIZE    (MS + 31)

enum { GROW = 1, WINTER = 2, BASIPETAL = 3, ACROPETAL = 4 };

typedef struct tree {
    cbm_lsys *ls;
    int s_year, s_i, s_apex, s_leaf, s_fruit;
} tree;

typedef struct stats {
    int year, phase, broken, shed; /* the Year module: year (0 first) and phase of the step */
    size_t segments, apices, leaves, fruit, buds;
    double height, crown, bud_height; /* m; bud_height: mean distal height of the buds */
    uint64_t hash;                    /* FNV-1a of every parameter of the string */
} stats;

static cbm_status open_tree(cbm_context *ctx, const char *const *defines, size_t nd, tree *t)
{
    char p[2048];
    snprintf(p, sizeof p, "%s/models/taylor-hell-fruit-tree-thesis.l", test_source_dir());
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = p;
    def.defines = defines;
    def.define_count = nd;
    memset(t, 0, sizeof *t);
    cbm_status s = cbm_lsys_load(ctx, &def, &t->ls);
    if (s == CBM_OK)
        s = cbm_lsys_reset(t->ls);
    if (s == CBM_OK) {
        t->s_year = lsys_symbol(t->ls, "Year");
        t->s_i = lsys_symbol(t->ls, "I");
        t->s_apex = lsys_symbol(t->ls, "Apex");
        t->s_leaf = lsys_symbol(t->ls, "Leaf");
        t->s_fruit = lsys_symbol(t->ls, "Fruit");
    }
    return s;
}

static void measure(const tree *t, stats *st)
{
    memset(st, 0, sizeof *st);
    st->hash = 14695981039346656037ull;
    double xlo = INFINITY, xhi = -INFINITY, zlo = INFINITY, zhi = -INFINITY, bh = 0;
    cbm_lsys_cursor c;
    cbm_lsys_cursor_begin(t->ls, false, &c);
    while (cbm_lsys_cursor_next(t->ls, false, &c)) {
        for (int i = 0; i < c.nparams; i++) {
            unsigned char b[sizeof(double)];
            memcpy(b, &c.params[i], sizeof b);
            for (size_t k = 0; k < sizeof b; k++)
                st->hash = (st->hash ^ b[k]) * 1099511628211ull;
        }
        st->hash = (st->hash ^ (uint64_t)c.symbol) * 1099511628211ull;
        if (c.symbol == t->s_year && c.nparams == 4) {
            st->year = (int)c.params[0];
            st->phase = (int)c.params[1];
            st->broken = (int)c.params[2];
            st->shed = (int)c.params[3];
        } else if (c.symbol == t->s_i && c.nparams >= N_SIZE) {
            const double *g = c.params;
            double x = g[13] + g[0] * g[16], y = g[14] + g[0] * g[17], z = g[15] + g[0] * g[18];
            st->segments++;
            st->height = y > st->height ? y : st->height;
            xlo = fmin(xlo, x), xhi = fmax(xhi, x), zlo = fmin(zlo, z), zhi = fmax(zhi, z);
            if (g[N_BUD] != 0) {
                st->buds++;
                bh += y;
            }
        } else if (c.symbol == t->s_apex) {
            st->apices++;
        } else if (c.symbol == t->s_leaf) {
            st->leaves++;
        } else if (c.symbol == t->s_fruit) {
            st->fruit++;
        }
    }
    st->crown = st->segments ? fmax(xhi - xlo, zhi - zlo) : 0;
    st->bud_height = st->buds ? bh / (double)st->buds : NAN;
}

/* Steps until the model stops (after its YEARS) or a step limit. */
static cbm_status run_all(tree *t)
{
    cbm_status s = CBM_OK;
    for (int k = 0; s == CBM_OK && !cbm_lsys_stopped(t->ls) && k < 5000; k++)
        s = cbm_lsys_step(t->ls);
    return s;
}

static cbm_status grow(cbm_context *ctx, const char *const *defines, size_t nd, stats *st)
{
    tree t;
    cbm_status s = open_tree(ctx, defines, nd, &t);
    if (s == CBM_OK)
        s = run_all(&t);
    if (s == CBM_OK)
        measure(&t, st);
    cbm_lsys_destroy(t.ls);
    return s;
}

/* The same parameters give the same tree bit for bit; another seed another tree. Every node
 * passes on what it receives: vl + vc = V, less the sink of a shooting lateral (4.14, 4.16). */
TEST(model_fruit_deterministic_and_conserving)
{
    cbm_context *ctx = test_ctx();
    const char *d[] = {"YEARS=3"}, *d7[] = {"YEARS=3", "SEED=7"};
    stats a = {0}, b = {0}, c = {0};
    CHECK_OK(grow(ctx, d, 1, &a));
    CHECK_OK(grow(ctx, d, 1, &b));
    CHECK_OK(grow(ctx, d7, 2, &c));
    printf("3 years: %zu segments, %.3f m, %d broken; seed 7: %zu segments; hash %016llx\n",
           a.segments, a.height, a.broken, c.segments, (unsigned long long)a.hash);
    CHECK_EQ_INT(a.year, 2); /* the last step: the third year's spring */
    CHECK_EQ_INT(a.phase, ACROPETAL);
    CHECK(a.hash == b.hash);
    CHECK(a.hash != c.hash);
    CHECK(a.segments > 100); /* it grew: 21 after the first year */
    CHECK(a.height > 0.9);
    /* conservation, read from the nodes after the last spring */
    tree t;
    CHECK_OK(open_tree(ctx, d, 1, &t));
    CHECK_OK(run_all(&t));
    int s_i = t.s_i, nodes = 0, sinks = 0;
    cbm_lsys_cursor cu;
    cbm_lsys_cursor_begin(t.ls, false, &cu);
    while (cbm_lsys_cursor_next(t.ls, false, &cu)) {
        if (cu.symbol != s_i || cu.nparams < N_SIZE)
            continue;
        const double *g = cu.params;
        double v = g[N_VIGOUR], out = g[N_VL] + g[N_VC];
        if (g[N_LATFATE] > 0) {
            sinks++;
            CHECK(out <= v * (1 + 1e-12));
        } else if (out > 0) {
            nodes++;
            CHECK_NEAR(out, v, 1e-12 * v);
        }
    }
    CHECK(nodes > 20);
    CHECK(sinks > 5);
    cbm_lsys_destroy(t.ls);
    test_ctx_end(ctx);
}

/* Fig. 4.1: when the leaves and fruit have fallen the same buds stand higher than at the end of
 * summer (fruit from the second year, a modulus of rupture that breaks nothing; fruit on the
 * first-year whip pulls it to the ground, where it is cropped). */
TEST(model_fruit_spring_back_after_shedding)
{
    cbm_context *ctx = test_ctx();
    const char *d[] = {"YEARS=3", "FIRST_FRUIT_YEAR=2", "MOR=2.9e7"};
    tree t;
    CHECK_OK(open_tree(ctx, d, 3, &t));
    int checked = 0;
    stats loaded = {0}, st = {0};
    memset(&loaded, 0, sizeof loaded);
    bool summer_over = false;
    for (int k = 0; k < 5000 && !cbm_lsys_stopped(t.ls); k++) {
        CHECK_OK(cbm_lsys_step(t.ls));
        measure(&t, &st);
        if (st.phase == GROW && st.apices == 0) { /* the end of summer: loaded */
            loaded = st;
            summer_over = true;
        } else if (summer_over && st.phase == WINTER && st.leaves + st.fruit == 0) {
            summer_over = false;
            printf("year %d: %zu buds, %zu fruit: mean bud height %.7f m loaded, %.7f m bare\n",
                   st.year + 1, st.buds, loaded.fruit, loaded.bud_height, st.bud_height);
            CHECK_EQ_INT((int)st.buds, (int)loaded.buds);
            CHECK_EQ_INT(st.broken, 0);
            if (st.year >= 1) { /* fruit on the tree */
                CHECK(loaded.fruit > 0);
                CHECK(st.bud_height > loaded.bud_height + 1e-3);
                checked++;
            } else { /* leaves of 2 mg: no spring-back above the solve tolerance (~10 um here) */
                CHECK(fabs(st.bud_height - loaded.bud_height) < 1e-4);
            }
        }
    }
    CHECK_EQ_INT(checked, 2);
    cbm_lsys_destroy(t.ls);
    test_ctx_end(ctx);
}

/* Fig. 4.7: F = 0.2 (winner takes most) grows a taller tree with fewer branches than F = 1. */
TEST(model_fruit_unfair_taller_sparser)
{
    cbm_context *ctx = test_ctx();
    const char *fair[] = {"YEARS=2", "FAIRNESS=1"}, *unfair[] = {"YEARS=2", "FAIRNESS=0.2"};
    stats f = {0}, u = {0};
    CHECK_OK(grow(ctx, fair, 2, &f));
    CHECK_OK(grow(ctx, unfair, 2, &u));
    printf("2 years: F = 1: %zu segments, %.3f m; F = 0.2: %zu segments, %.3f m\n", f.segments,
           f.height, u.segments, u.height);
    CHECK(u.height > f.height + 0.1);
    CHECK(4 * u.segments < 3 * f.segments);
    test_ctx_end(ctx);
}

/* Fig. 8.9: a low modulus of rupture breaks branches under the fruit, a high one none. */
TEST(model_fruit_low_mor_breaks_high_keeps)
{
    cbm_context *ctx = test_ctx();
    const char *low[] = {"YEARS=4", "MOR=1.2e5"}, *high[] = {"YEARS=4", "MOR=2.9e7"};
    stats l = {0}, h = {0};
    CHECK_OK(grow(ctx, low, 2, &l));
    CHECK_OK(grow(ctx, high, 2, &h));
    printf("4 years: MOR 1.2e5 Pa: %d broken, %zu segments; MOR 2.9e7 Pa: %d broken, %zu "
           "segments\n",
           l.broken, l.segments, h.broken, h.segments);
    CHECK(l.broken >= 5);
    CHECK_EQ_INT(h.broken, 0);
    CHECK(h.segments > l.segments);
    test_ctx_end(ctx);
}

/* Ch. 7: the crooked aspen (base E, tropism fading late in a shoot, no reaction wood, double
 * deviation) stays far lower and spreads wider than the wild one (E x 3, tropism x 5). */
TEST(model_fruit_crooked_aspen_lower)
{
    cbm_context *ctx = test_ctx();
    const char *wild[] = {"YEARS=3", "FORM=1", "YEARS_TO_SHED=3", "RELAY_BIAS=1", "FRUIT_PROB=0"};
    const char *crooked[] = {"YEARS=3", "FORM=2", "YEARS_TO_SHED=3", "RELAY_BIAS=1",
                             "FRUIT_PROB=0"};
    stats w = {0}, c = {0};
    CHECK_OK(grow(ctx, wild, 5, &w));
    CHECK_OK(grow(ctx, crooked, 5, &c));
    printf("3 years: wild %.3f m high, crown %.3f m; crooked %.3f m high, crown %.3f m\n", w.height,
           w.crown, c.height, c.crown);
    CHECK(c.height < 0.6 * w.height);
    CHECK(c.crown > w.crown); /* and wider: pendulous branches */
    test_ctx_end(ctx);
}
