/* The ring pass (src/mech/plant.c): a new ring updates the section sums in O(1) and the ring pool
 * keeps per-segment runs with capacity doubling. Checked here: the incremental aggregates equal
 * a full recompute bit for bit and an independent sum to round-off, over many growth steps with
 * ageing, reaction wood and elliptical rings; rings survive run moves, removals and compaction;
 * allocations stay those of geometric growth; out of memory leaves everything consistent. */
#include "mech_testlib.h"
#include "core/vecmath.h"

/* Independent reference: the aggregates of a segment summed from its rings (Taylor-Hell
 * 6.25-6.34: ring moments are outer minus inner solid-ellipse moments). */
typedef struct ref_section {
    cbm_vec3 c, rest;
    double mpl, area;
} ref_section;

static ref_section reference(const cbm_plant *p, size_t seg)
{
    ref_section s;
    memset(&s, 0, sizeof s);
    double il0 = 0, iu0 = 0, j0 = 0, a0 = 0;
    cbm_vec3 cr = {0, 0, 0};
    size_t n = cbm_plant_ring_count(p, seg);
    for (size_t k = 0; k < n; k++) {
        cbm_ring r;
        CHECK_OK(cbm_plant_get_ring(p, seg, k, &r));
        double il = PI * r.a * r.a * r.a * r.b / 4, iu = PI * r.a * r.b * r.b * r.b / 4;
        double j = PI * pow(r.a * r.b, 3) / (r.a * r.a + r.b * r.b), ar = PI * r.a * r.b;
        double ch = r.shear_modulus * (j - j0), cl = r.youngs_modulus * (il - il0),
               cu = r.youngs_modulus * (iu - iu0);
        s.c.x += ch, s.c.y += cl, s.c.z += cu;
        cr.x += ch * r.rest_rate.x, cr.y += cl * r.rest_rate.y, cr.z += cu * r.rest_rate.z;
        s.mpl += r.density * (ar - a0);
        il0 = il, iu0 = iu, j0 = j, a0 = ar;
    }
    s.area = a0;
    s.rest = (cbm_vec3){cr.x / s.c.x, cr.y / s.c.y, cr.z / s.c.z};
    return s;
}

static double vmax(cbm_vec3 v)
{
    return fmax(fabs(v.x), fmax(fabs(v.y), fabs(v.z)));
}

/* Every segment: the stored (incremental) aggregates against the independent sum (relative
 * round-off 1e-12) and against the library's own full recompute, forced by rewriting the outer
 * ring with itself (bit for bit). Returns the number of segments checked. */
static size_t check_sections(cbm_plant *p)
{
    size_t n = cbm_plant_segment_count(p);
    for (size_t i = 0; i < n; i++) {
        cbm_segment_state a, b;
        CHECK_OK(cbm_plant_segment(p, i, &a));
        ref_section r = reference(p, i);
        CHECK_REL(a.rigidity.x, r.c.x, 1e-12);
        CHECK_REL(a.rigidity.y, r.c.y, 1e-12);
        CHECK_REL(a.rigidity.z, r.c.z, 1e-12);
        /* rest rates can be near 0: relative to the largest component */
        double scale = fmax(vmax(r.rest), 1e-300);
        CHECK_NEAR(a.rest_rate.x, r.rest.x, 1e-12 * scale);
        CHECK_NEAR(a.rest_rate.y, r.rest.y, 1e-12 * scale);
        CHECK_NEAR(a.rest_rate.z, r.rest.z, 1e-12 * scale);
        CHECK_REL(a.mass_per_length, r.mpl, 1e-12);
        CHECK_REL(a.area, r.area, 1e-15);
        cbm_ring outer;
        CHECK_OK(cbm_plant_get_ring(p, i, a.ring_count - 1, &outer));
        CHECK_OK(cbm_plant_set_ring(p, i, a.ring_count - 1, &outer)); /* full recompute */
        CHECK_OK(cbm_plant_segment(p, i, &b));
        CHECK(a.rigidity.x == b.rigidity.x && a.rigidity.y == b.rigidity.y &&
              a.rigidity.z == b.rigidity.z);
        CHECK(a.rest_rate.x == b.rest_rate.x && a.rest_rate.y == b.rest_rate.y &&
              a.rest_rate.z == b.rest_rate.z);
        CHECK(a.mass_per_length == b.mass_per_length && a.area == b.area);
    }
    return n;
}

/* A small branching plant with elliptical cores, clamped horizontally (so that it sags and
 * leans). */
static cbm_plant *small_tree(cbm_context *ctx)
{
    cbm_plant *p = clamped_plant(ctx, 0.3);
    cbm_segment_def d = cbm_segment_def_default();
    d.core.youngs_modulus = 2e8;
    d.core.shear_modulus = 2e8 / 16;
    const int64_t parent[12] = {-1, 0, 1, 2, 1, 4, 2, 6, 3, 8, 0, 10};
    for (int i = 0; i < 12; i++) {
        d.parent = parent[i];
        d.length = 0.2 - 0.01 * i;
        d.divergence = 2.4 * i;
        d.deviation = parent[i] >= 0 && parent[i] != i - 1 ? 0.6 : 0.0;
        d.core.a = 0.012 - 0.0006 * i;
        d.core.b = 0.7 * d.core.a; /* elliptical */
        d.point_mass = 0.01;
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    return p;
}

/* 80 growth steps: equilibrium, pipe-model rings with shape memory and reaction wood (some
 * segments lean), ageing every 4 steps; at every step the aggregates are checked. */
static void grow_and_check(cbm_ageing ageing)
{
    cbm_context *ctx = test_ctx();
    cbm_plant *p = small_tree(ctx);
    cbm_growth_def g = cbm_growth_def_default();
    g.leaf_area = 2e-5;
    g.pipe_rate = 0.3;
    g.youngs_juvenile = 2e8;
    g.youngs_adult = 1e9;
    g.adult_age = 3.0;
    g.ageing = ageing;
    g.reaction_threshold = 0.05;
    g.reaction_beta = 0.4;
    g.reaction_increment = 2e-4;
    size_t reaction = 0, rings = 0;
    for (int step = 0; step < 80; step++) {
        cbm_solve_def sd = cbm_solve_def_default();
        sd.max_passes = 2000;
        cbm_status s = cbm_plant_solve(p, &sd, NULL);
        CHECK(s == CBM_OK || s == CBM_E_NOT_CONVERGED);
        cbm_growth_stats gs;
        CHECK_OK(cbm_plant_grow_rings(p, &g, &gs));
        reaction += gs.reaction_rings;
        rings += gs.rings_added;
        if (step % 4 == 3)
            CHECK_OK(cbm_plant_age_wood(p, &g, 0.25));
        CHECK(check_sections(p) == 12);
    }
    CHECK(rings > 200);
    CHECK(reaction > 20);
    if (ageing == CBM_AGEING_RINGS) {
        /* old rings did age: the core of the base is adult, its last ring still juvenile */
        cbm_ring core, outer;
        CHECK_OK(cbm_plant_get_ring(p, 0, 0, &core));
        CHECK_OK(cbm_plant_get_ring(p, 0, cbm_plant_ring_count(p, 0) - 1, &outer));
        CHECK_REL(core.youngs_modulus, 1e9, 1e-12);
        CHECK(outer.youngs_modulus < 1e9);
        CHECK(cbm_plant_ring_count(p, 0) > 50);
    }
    cbm_plant_destroy(p);
    test_ctx_end(ctx);
}

TEST(growth_rings_incremental_equals_full_recompute)
{
    grow_and_check(CBM_AGEING_RINGS);
}

TEST(growth_rings_incremental_equals_full_recompute_core_ageing)
{
    grow_and_check(CBM_AGEING_CORE);
}

/* A ring whose fields encode (segment id, ring number): survives run moves and compaction. */
static cbm_ring tagged(double id, size_t k)
{
    cbm_ring r = cbm_ring_default();
    r.a = 0.01 + 1e-4 * (double)k;
    r.b = 0.008 + 1e-4 * (double)k;
    r.age = (double)k;
    r.modulus_of_rupture = id;
    r.rest_rate = v3(1e-3 * (double)k, -id, 0.5);
    return r;
}

/* 300 segments get 120 rings each, added round-robin (the worst case for a pool of contiguous
 * runs: every run is full in turn while others follow it). The allocations are those of the
 * pool's geometric growth (a few dozen for 36,000 rings, none per ring; a pool that moves a run
 * to its end at every new ring compacts every round and made 343), the memory stays within
 * a small factor of the rings held, and every ring reads back as written after the runs moved,
 * after a subtree removal and after compaction. */
TEST(growth_rings_pool_amortised)
{
    size_t allocs = 0;
    cbm_context *ctx = test_counting_ctx(&allocs);
    CHECK(ctx != NULL);
    cbm_plant_def pd = cbm_plant_def_default();
    pd.capacity = 300;
    cbm_plant *p = NULL;
    CHECK_OK(cbm_plant_create(ctx, &pd, &p));
    cbm_segment_def d = cbm_segment_def_default();
    enum { NSEG = 300, NRING = 120 };
    for (size_t i = 0; i < NSEG; i++) {
        d.parent = (int64_t)i - 1;
        d.core = tagged((double)i, 0);
        CHECK_OK(cbm_plant_add_segment(p, &d, NULL));
    }
    size_t base = cbm_context_bytes(ctx), c0 = allocs;
    for (size_t k = 1; k < NRING; k++)
        for (size_t i = 0; i < NSEG; i++) {
            cbm_ring r = tagged((double)i, k);
            CHECK_OK(cbm_plant_add_ring(p, i, &r));
        }
    size_t calls = allocs - c0;
    CHECK_MSG(calls <= 40, "%zu allocations for %d rings", calls, NSEG * (NRING - 1));
    double ring_bytes = (double)(NSEG * NRING) * (double)sizeof(cbm_ring);
    CHECK((double)(cbm_context_bytes(ctx) - base) <= 4.0 * ring_bytes);
    CHECK((double)cbm_context_peak_bytes(ctx) <= (double)base + 6.0 * ring_bytes);
    for (size_t i = 0; i < NSEG; i += 7)
        for (size_t k = 0; k < NRING; k += 5) {
            cbm_ring r;
            CHECK_OK(cbm_plant_get_ring(p, i, k, &r));
            CHECK(r.age == (double)k && r.modulus_of_rupture == (double)i);
            CHECK(r.rest_rate.y == -(double)i);
        }
    CHECK(check_sections(p) == NSEG);
    /* remove the outer two thirds (holes), then add more rings to the rest (compaction) */
    size_t removed = 0;
    CHECK_OK(cbm_plant_remove_subtree(p, 100, &removed));
    CHECK_EQ_INT(removed, 200);
    for (size_t k = NRING; k < NRING + 40; k++)
        for (size_t i = 0; i < 100; i++) {
            cbm_ring r = tagged((double)i, k);
            CHECK_OK(cbm_plant_add_ring(p, i, &r));
        }
    for (size_t i = 0; i < 100; i++) {
        CHECK_EQ_INT(cbm_plant_ring_count(p, i), NRING + 40);
        for (size_t k = 0; k < NRING + 40; k += 3) {
            cbm_ring r;
            CHECK_OK(cbm_plant_get_ring(p, i, k, &r));
            CHECK(r.age == (double)k && r.modulus_of_rupture == (double)i);
        }
    }
    CHECK(check_sections(p) == 100);
    cbm_plant_destroy(p);
    CHECK_EQ_INT(cbm_context_bytes(ctx), 0);
    cbm_context_destroy(ctx);
}

/* Out of memory anywhere in building, ring runs moving, removal and compaction, growth and
 * ageing: NOMEM or OK, nothing leaked, and a ring that could not be added left the segment as
 * it was (ring count and aggregates unchanged). */
static cbm_status oom_rings(cbm_context *ctx, void *ud)
{
    (void)ud;
    cbm_plant *p = NULL;
    cbm_status s = cbm_plant_create(ctx, NULL, &p);
    if (s != CBM_OK)
        return s;
    cbm_segment_def d = cbm_segment_def_default();
    for (int i = 0; i < 30 && s == CBM_OK; i++) {
        d.parent = i - 1;
        d.core = tagged((double)i, 0);
        s = cbm_plant_add_segment(p, &d, NULL);
    }
    for (size_t k = 1; k < 12 && s == CBM_OK; k++)
        for (size_t i = 0; i < 30 && s == CBM_OK; i++) {
            cbm_ring r = tagged((double)i, k);
            cbm_segment_state before, after;
            CHECK_OK(cbm_plant_segment(p, i, &before));
            s = cbm_plant_add_ring(p, i, &r);
            if (s == CBM_E_NOMEM) {
                CHECK_OK(cbm_plant_segment(p, i, &after));
                CHECK_EQ_INT(after.ring_count, before.ring_count);
                CHECK(after.rigidity.y == before.rigidity.y && after.area == before.area);
            }
        }
    if (s == CBM_OK)
        s = cbm_plant_remove_subtree(p, 20, NULL);
    for (size_t k = 12; k < 30 && s == CBM_OK; k++)
        for (size_t i = 0; i < 20 && s == CBM_OK; i++) {
            cbm_ring r = tagged((double)i, k);
            s = cbm_plant_add_ring(p, i, &r);
        }
    cbm_growth_def g = cbm_growth_def_default();
    g.leaf_area = 1e-4;
    g.adult_age = 2;
    g.youngs_adult = 2e10;
    if (s == CBM_OK)
        s = cbm_plant_evaluate(p, NULL);
    if (s == CBM_OK)
        s = cbm_plant_grow_rings(p, &g, NULL);
    if (s == CBM_OK)
        s = cbm_plant_age_wood(p, &g, 1.0);
    if (s == CBM_OK)
        CHECK(check_sections(p) == 20);
    cbm_plant_destroy(p);
    return s;
}

TEST(growth_rings_out_of_memory)
{
    CHECK(test_oom_loop(oom_rings, NULL) > 0);
}
