/* cpfg's quaternion query ?Q(x,y,z,w): cpfg's matrix-to-quaternion conversion applied to the
 * matrix whose rows are the turtle's H, L, U, vector part first. Checked against frames worked
 * by hand that take each branch of the conversion, against the first branch's formula for a
 * general frame, and through a model whose production reads the value (the environmental
 * interpretation before each step). */
#include "test.h"

#include <math.h>
#include <string.h>

/* The values ?Q(0,0,0,0) receives after the modules of `pre` (names and one parameter each). */
static void query_after(const char *const *pre, const double *par, size_t n, double q[4],
                        cbm_vec3 fr[3])
{
    cbm_context *ctx = test_ctx();
    cbm_view *view = NULL;
    CHECK_OK(cbm_view_create(ctx, &view));
    cbm_tmodule m[16];
    double p[16][4];
    memset(p, 0, sizeof p);
    size_t k = 0;
    for (size_t i = 0; i < n; i++) {
        p[k][0] = par[i];
        m[k] = (cbm_tmodule){pre[i], 1, p[k]};
        k++;
    }
    m[k] = (cbm_tmodule){"?", 0, p[k]};
    k++;
    size_t qi = k++;
    m[qi] = (cbm_tmodule){"Q", 4, p[qi]};
    cbm_turtle *t = NULL;
    CHECK_OK(cbm_turtle_interpret(ctx, view, NULL, m, k, NULL, &t));
    memcpy(q, p[qi], 4 * sizeof(double));
    if (t)
        cbm_turtle_state(t, NULL, &fr[0], &fr[1], &fr[2], NULL, NULL);
    cbm_turtle_destroy(t);
    cbm_view_destroy(view);
    test_ctx_end(ctx);
}

TEST(hand_worked_frames)
{
    cbm_vec3 fr[3];
    double q[4];
    /* H = +y, L = -x, U = -z: trace -1, so w = 0; x^2 = -(L.y + U.z)/2 = 1/2, y = H.y / 2x */
    query_after(NULL, NULL, 0, q, fr);
    const double h = sqrt(0.5);
    CHECK_NEAR(q[0], h, 1e-15);
    CHECK_NEAR(q[1], h, 1e-15);
    CHECK_NEAR(q[2], 0, 1e-15);
    CHECK_NEAR(q[3], 0, 1e-15);
    /* +(90): H = -x, L = -y, U = -z: w = 0, x^2 = 1, y = H.y / 2 = 0, z = H.z / 2 = 0 */
    const char *turn[1] = {"+"};
    const double ninety[1] = {90};
    query_after(turn, ninety, 1, q, fr);
    CHECK_NEAR(q[0], 1, 1e-15);
    CHECK_NEAR(q[1], 0, 1e-15);
    CHECK_NEAR(q[2], 0, 1e-15);
    CHECK_NEAR(q[3], 0, 1e-15);
    /* &(90): H = -z, L = -x, U = -y: trace 0, w = 1/2, x = (L.z - U.y)/2 = 1/2,
     * y = (U.x - H.z)/2 = 1/2, z = (H.y - L.x)/2 = 1/2 */
    const char *pitch[1] = {"&"};
    query_after(pitch, ninety, 1, q, fr);
    for (int i = 0; i < 4; i++)
        CHECK_NEAR(q[i], 0.5, 1e-15);
    /* +(90)/(90): H = -x, L = -z, U = +y: trace -1 and L.y + U.z = 0, so w = x = 0,
     * y^2 = (1 - U.z)/2 = 1/2, z = L.z / 2y = -sqrt(1/2) */
    const char *roll[2] = {"+", "/"};
    const double nn[2] = {90, 90};
    query_after(roll, nn, 2, q, fr);
    CHECK_NEAR(q[0], 0, 1e-15);
    CHECK_NEAR(q[1], h, 1e-15);
    CHECK_NEAR(q[2], -h, 1e-15);
    CHECK_NEAR(q[3], 0, 1e-15);
}

TEST(general_frame)
{
    /* a frame with no zero entry and 1 + trace = 0.22: the first branch, from the rows H, L, U */
    const char *mods[3] = {"&", "/", "+"};
    const double ang[3] = {80, 20, 15};
    cbm_vec3 f[3];
    double q[4];
    query_after(mods, ang, 3, q, f);
    double w = sqrt(0.25 * (1.0 + f[0].x + f[1].y + f[2].z));
    CHECK(w > 0.1);
    CHECK_NEAR(q[3], w, 1e-15);
    CHECK_NEAR(q[0], (f[1].z - f[2].y) / (4 * w), 1e-15);
    CHECK_NEAR(q[1], (f[2].x - f[0].z) / (4 * w), 1e-15);
    CHECK_NEAR(q[2], (f[0].y - f[1].x) / (4 * w), 1e-15);
    /* cpfg's frame is left-handed (L = H x U), so the four numbers are not a unit quaternion in
     * general (as cpfg gives them) */
    double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    CHECK(fabs(n - 1.0) > 1e-3);
}

TEST(a_production_reads_the_quaternion)
{
    /* before step 1 the turtle fills ?Q after +(90) with (1,0,0,0): A becomes B */
    cbm_context *ctx = test_ctx();
    cbm_model_def def = {cbm_lsys_def_default(), NULL, 0};
    def.lsys.path = "q.l";
    def.lsys.text = "Lsystem: 1\nderivation length: 1\nconsider: ?Q\nAxiom: +(90)A?Q(0,0,0,0)\n"
                    "A > ?Q(x,y,z,w) : x > 0.99 && w < 0.01 --> B\nendlsystem\n";
    cbm_model *m = NULL;
    CHECK_OK(cbm_model_load(ctx, &def, &m));
    if (m) {
        CHECK_OK(cbm_model_reset(m));
        CHECK(cbm_model_has_queries(m));
        CHECK_OK(cbm_model_step(m));
        cbm_lsys *ls = cbm_model_lsys(m);
        cbm_lsys_cursor c;
        cbm_lsys_cursor_begin(ls, false, &c);
        char syms[8] = {0};
        int n = 0;
        while (cbm_lsys_cursor_next(ls, false, &c) && n < 7)
            syms[n++] = (char)c.symbol;
        CHECK_MSG(!strcmp(syms, "+B?Q"), "%s", syms);
        cbm_model_destroy(m);
    }
    test_ctx_end(ctx);
}
