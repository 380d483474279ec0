/* The mechanical plant of an L+C model's string (cbm_lsys_mech_plant), for the MTG and segment
 * table writers: it holds the string's segments in string order, at the stored state (the
 * positions, frames, carried masses and stresses the last Equilibrium() wrote into the
 * parameters), with laterals where the string has brackets; models without mechanics are refused.
 */
#include "lsys_util.h"

#include "cambium/lsys.h"
#include "cambium/mech.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define MS 26 /* doubles of a MechSegment */

TEST(mechlang_export_plant_is_the_stored_state)
{
    cbm_context *ctx = test_ctx();
    cbm_lsys *ls = NULL;
    CHECK_OK(lsys_load_shipped(ctx, "jirasek-hanging.l", NULL, &ls));
    if (!ls) {
        test_ctx_end(ctx);
        return;
    }
    CHECK(cbm_lsys_has_mechanics(ls));
    CHECK_OK(cbm_lsys_reset(ls));
    for (int i = 0; i < cbm_lsys_derivation_length(ls); i++)
        CHECK_OK(cbm_lsys_step(ls));
    cbm_plant *pl = NULL;
    CHECK_OK(cbm_lsys_mech_plant(ls, &pl));
    CHECK(pl != NULL);
    int sym = lsys_symbol(ls, "I"), sb = lsys_symbol(ls, "SB"), eb = lsys_symbol(ls, "EB");
    cbm_lsys_cursor c;
    cbm_lsys_cursor_begin(ls, false, &c);
    size_t k = 0;
    int depth = 0, laterals = 0, max_order = 0;
    double worst = 0;
    while (pl && cbm_lsys_cursor_next(ls, false, &c)) {
        if (c.symbol == sb)
            depth++;
        else if (c.symbol == eb)
            depth--;
        if (c.symbol != sym || c.nparams < MS)
            continue;
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(pl, k, &s));
        const double *g = c.params;
        double d[] = {s.proximal.x - g[13],   s.proximal.y - g[14],     s.proximal.z - g[15],
                      s.frame.h.x - g[16],    s.frame.h.y - g[17],      s.frame.h.z - g[18],
                      s.carried_mass - g[24], (s.stress - g[22]) / 1e6, s.omega.x - g[10],
                      s.length - g[0]};
        for (size_t i = 0; i < sizeof d / sizeof d[0]; i++)
            worst = fabs(d[i]) > worst ? fabs(d[i]) : worst;
        if (!s.continuation && s.parent >= 0)
            laterals++;
        max_order = s.order > max_order ? s.order : max_order;
        /* a segment inside brackets is on a lateral axis: order >= 1 */
        CHECK(depth == 0 ? s.order == 0 : s.order >= 1);
        k++;
    }
    CHECK_EQ_INT(k, pl ? cbm_plant_segment_count(pl) : 0);
    CHECK_MSG(worst < 1e-9, "largest difference from the stored state %g", worst);
    CHECK_EQ_INT(laterals, 3);
    CHECK_EQ_INT(max_order, 1);
    cbm_plant_destroy(pl);
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

TEST(mechlang_export_refused_without_mechanics)
{
    cbm_context *ctx = test_ctx();
    cbm_lsys_def def = cbm_lsys_def_default();
    def.path = "m.l";
    def.text = "#include <lpfgall.h>\nmodule A(int);\nAxiom: A(1);\n";
    cbm_lsys *ls = NULL;
    CHECK_OK(cbm_lsys_load(ctx, &def, &ls));
    if (ls) {
        CHECK(!cbm_lsys_has_mechanics(ls));
        CHECK_OK(cbm_lsys_reset(ls));
        cbm_plant *pl = (cbm_plant *)&def; /* must be reset to NULL */
        CHECK_STATUS(cbm_lsys_mech_plant(ls, &pl), CBM_E_INVALID);
        CHECK(pl == NULL);
        CHECK(strstr(cbm_context_last_error(ctx), "mechanics:") != NULL);
        cbm_lsys_destroy(ls);
    }
    test_ctx_end(ctx);
}

static cbm_status oom_export(cbm_context *ctx, void *ud)
{
    (void)ud;
    cbm_lsys *ls = NULL;
    cbm_status s = lsys_load_shipped(ctx, "jirasek-cherries.l", NULL, &ls);
    if (s != CBM_OK)
        return s;
    s = cbm_lsys_reset(ls);
    for (int i = 0; i < 2 && s == CBM_OK; i++)
        s = cbm_lsys_step(ls);
    cbm_plant *pl = NULL;
    if (s == CBM_OK)
        s = cbm_lsys_mech_plant(ls, &pl);
    cbm_plant_destroy(pl);
    cbm_lsys_destroy(ls);
    return s;
}

TEST(mechlang_export_out_of_memory)
{
    CHECK(test_oom_loop(oom_export, NULL) > 10);
}

/* Orders and continuations of `axiom` (segments I(S())), checked against the expected strings
 * of orders ("01110") and continuation flags ("10001"). */
static void check_axes(const char *axiom, const char *orders, const char *conts)
{
    cbm_context *ctx = test_ctx();
    char text[1024];
    snprintf(text, sizeof text,
             "#include <lpfgall.h>\nmodule I(MechSegment);\nmechanics: I;\n"
             "MechSegment S() { MechSegment s; s.length = 0.1; s.a = 0.003; s.b = 0.003; "
             "s.E = 1e9; s.density = 700; return s; }\nAxiom: %s;\n",
             axiom);
    cbm_lsys *ls = lsys_from_text(ctx, "axes.l", text);
    cbm_plant *pl = NULL;
    if (ls)
        CHECK_OK(cbm_lsys_mech_plant(ls, &pl));
    size_t n = pl ? cbm_plant_segment_count(pl) : 0;
    CHECK_EQ_INT(n, strlen(orders));
    char o[64] = {0}, c[64] = {0};
    for (size_t i = 0; i < n && i < 63; i++) {
        cbm_segment_state s;
        CHECK_OK(cbm_plant_segment(pl, i, &s));
        o[i] = (char)('0' + s.order);
        c[i] = s.continuation ? '1' : '0';
    }
    CHECK_MSG(!strcmp(o, orders) && !strcmp(c, conts),
              "%s: orders %s (want %s), continuations %s (want %s)", axiom, o, orders, c, conts);
    cbm_plant_destroy(pl);
    cbm_lsys_destroy(ls);
    test_ctx_end(ctx);
}

TEST(mechlang_export_axes_from_brackets)
{
    /* the I after the branches continues the axis */
    check_axes("I(S()) SB Down(30) I(S()) EB SB Up(30) I(S()) I(S()) EB I(S())", "01110", "10011");
    /* branches in branches */
    check_axes("I(S()) SB Down(30) I(S()) SB Up(20) I(S()) EB I(S()) EB I(S())", "01210", "10011");
    /* no axial child: the first lateral takes the joint (continuation), keeping order 1 */
    check_axes("I(S()) SB Down(30) I(S()) EB SB Up(30) I(S()) EB", "011", "110");
}
