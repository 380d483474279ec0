/* The elastica of one rod, integrated backward from its tip (Tresierras 2009, (2.33)-(2.35) and
 * ch. 4): given the tip angle, the tip moment and the tip force, the equilibrium is one initial
 * value problem from s = L to the base, whose end values give the base angle and moment.
 *
 * State (s increasing; integrated from L down to 0):
 *   theta' = m / D + kappa^g          (m = D nu: integrating the moment, not nu, keeps D' out,
 *   m'     = P cos(theta)              which is singular where D jumps between pieces)
 *   P'     = -w                        (P: weight distal to s plus the tip force)
 *   X' = cos(theta), Y' = sin(theta)   (position, tip at the origin)
 *   V'     = m^2 / (2 D) + P sin(theta)   (energy (4.9): strain + weight potential)
 *   eta'   = zeta / D, zeta' = -P sin(theta) eta   (the Jacobi field d/d theta_tip)
 * The Jacobi field starts at eta(L) = 1 with zeta(L) = dM_tip/d theta_tip (0 for a dead moment,
 * which is the natural boundary condition of the second variation
 *   d2V = int D eta'^2 - P sin(theta) eta^2 ds,  eta(0) = 0 (clamp), free tip),
 * so eta(0) = d theta_base / d theta_tip (0 at a fold), and by Sturm's oscillation theorem the
 * number of zeros of eta in (0, L) is the number of negative eigenvalues of d2V: the Morse index.
 *
 * Integrator: Dormand-Prince 5(4) with local error control (relative 1e-10 of per-component
 * scales set by the rod: L, D(0)/L, the total weight), restarted at every piece boundary so that
 * the jumps of D, w and kappa^g fall on step ends. Our own: the library depends on no ODE
 * package, and the problem is small (8 unknowns, smooth within pieces).
 */
#include "elastica_internal.h"

#include <math.h>

cbm_elastica_piece cbm_elastica_piece_default(void)
{
    cbm_elastica_piece p = {1.0, 1.0, 1.0, 0.0, 0.0, 0.0};
    return p;
}

cbm_elastica_rod cbm_elastica_rod_default(void)
{
    cbm_elastica_rod r = {NULL, 0, 0.0, 0.0, NULL};
    return r;
}

double cbm__el_stiffness(const cbm_elastica_piece *pc, double t)
{
    if (pc->D0 == pc->D1)
        return pc->D0;
    double a = pow(pc->D0, 0.25) * (1.0 - t) + pow(pc->D1, 0.25) * t;
    return a * a * a * a;
}

double cbm__el_weight(const cbm_elastica_piece *pc, double t)
{
    if (pc->w0 == pc->w1)
        return pc->w0;
    double a = sqrt(pc->w0) * (1.0 - t) + sqrt(pc->w1) * t;
    return a * a;
}

double cbm__el_length(const cbm_elastica_rod *rod)
{
    double L = 0;
    for (size_t k = 0; k < rod->n_pieces; k++)
        L += rod->pieces[k].length;
    return L;
}

cbm_status cbm__el_check(cbm_context *ctx, const cbm_elastica_rod *rod)
{
    if (!rod || !rod->pieces || rod->n_pieces == 0)
        return cbm__fail(ctx, CBM_E_INVALID, "elastica: a rod needs at least one piece");
    if (!isfinite(rod->tip_force) || !isfinite(rod->tip_moment))
        return cbm__fail(ctx, CBM_E_INVALID, "elastica: tip force and moment must be finite");
    for (size_t k = 0; k < rod->n_pieces; k++) {
        const cbm_elastica_piece *p = &rod->pieces[k];
        if (!(p->length > 0 && isfinite(p->length) && p->D0 > 0 && p->D1 > 0 && isfinite(p->D0) &&
              isfinite(p->D1) && p->w0 >= 0 && p->w1 >= 0 && isfinite(p->w0) && isfinite(p->w1) &&
              isfinite(p->rest_curvature)))
            return cbm__fail(ctx, CBM_E_INVALID,
                             "elastica: piece %zu needs length > 0, D > 0, w >= 0 (finite)", k);
        if (rod->piece_loads && !isfinite(rod->piece_loads[k]))
            return cbm__fail(ctx, CBM_E_INVALID, "elastica: the load of piece %zu must be finite",
                             k);
    }
    return CBM_OK;
}

typedef struct piece_ctx {
    const cbm_elastica_piece *pc;
    double s0; /* arc length at the piece's start */
} piece_ctx;

static void deriv(const piece_ctx *c, double s, const double *y, double *f)
{
    double t = (s - c->s0) / c->pc->length;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    double D = cbm__el_stiffness(c->pc, t), w = cbm__el_weight(c->pc, t);
    double ct = cos(y[EL_THETA]), st = sin(y[EL_THETA]);
    f[EL_THETA] = y[EL_M] / D + c->pc->rest_curvature;
    f[EL_M] = y[EL_P] * ct;
    f[EL_P] = -w;
    f[EL_X] = ct;
    f[EL_Y] = st;
    f[EL_V] = 0.5 * y[EL_M] * y[EL_M] / D + y[EL_P] * st;
    f[EL_ETA] = y[EL_ZETA] / D;
    f[EL_ZETA] = -y[EL_P] * st * y[EL_ETA];
}

#define EL_TOL 1e-10 /* relative local error per step */

/* Dormand-Prince 5(4) tableau */
static const double A21 = 1.0 / 5, A31 = 3.0 / 40, A32 = 9.0 / 40, A41 = 44.0 / 45,
                    A42 = -56.0 / 15, A43 = 32.0 / 9, A51 = 19372.0 / 6561, A52 = -25360.0 / 2187,
                    A53 = 64448.0 / 6561, A54 = -212.0 / 729, A61 = 9017.0 / 3168,
                    A62 = -355.0 / 33, A63 = 46732.0 / 5247, A64 = 49.0 / 176,
                    A65 = -5103.0 / 18656, B1 = 35.0 / 384, B3 = 500.0 / 1113, B4 = 125.0 / 192,
                    B5 = -2187.0 / 6784, B6 = 11.0 / 84, E1 = 71.0 / 57600, E3 = -71.0 / 16695,
                    E4 = 71.0 / 1920, E5 = -17253.0 / 339200, E6 = 22.0 / 525, E7 = -1.0 / 40;

/* One step of size h from (s, y); ynew and the scaled error norm. */
static double dp_step(const piece_ctx *c, double s, const double *y, double h, const double *sc,
                      double *ynew)
{
    double k1[EL_N], k2[EL_N], k3[EL_N], k4[EL_N], k5[EL_N], k6[EL_N], k7[EL_N], t[EL_N];
    deriv(c, s, y, k1);
    for (int i = 0; i < EL_N; i++)
        t[i] = y[i] + h * A21 * k1[i];
    deriv(c, s + h / 5, t, k2);
    for (int i = 0; i < EL_N; i++)
        t[i] = y[i] + h * (A31 * k1[i] + A32 * k2[i]);
    deriv(c, s + 0.3 * h, t, k3);
    for (int i = 0; i < EL_N; i++)
        t[i] = y[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i]);
    deriv(c, s + 0.8 * h, t, k4);
    for (int i = 0; i < EL_N; i++)
        t[i] = y[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]);
    deriv(c, s + h * 8.0 / 9, t, k5);
    for (int i = 0; i < EL_N; i++)
        t[i] = y[i] + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i]);
    deriv(c, s + h, t, k6);
    for (int i = 0; i < EL_N; i++)
        ynew[i] = y[i] + h * (B1 * k1[i] + B3 * k3[i] + B4 * k4[i] + B5 * k5[i] + B6 * k6[i]);
    deriv(c, s + h, ynew, k7);
    double err = 0;
    for (int i = 0; i < EL_N; i++) {
        double e =
            h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
        double m = fabs(y[i]) > fabs(ynew[i]) ? fabs(y[i]) : fabs(ynew[i]);
        double r = fabs(e) / (sc[i] + EL_TOL * m);
        if (r > err)
            err = r;
    }
    return err;
}

cbm_status cbm__el_integrate(const cbm_elastica_rod *rod, double theta_tip, double dmoment,
                             double y_base[EL_N], int *zeros, cbm__el_sample_fn sample, void *ud,
                             size_t n_sample)
{
    double L = cbm__el_length(rod);
    double Wtot = fabs(rod->tip_force), Dref = rod->pieces[0].D0;
    for (size_t k = 0; k < rod->n_pieces; k++) {
        const cbm_elastica_piece *p = &rod->pieces[k];
        Wtot += 0.5 * (p->w0 + p->w1) * p->length;
        if (rod->piece_loads)
            Wtot += fabs(rod->piece_loads[k]);
    }
    double Mref = Dref / L + Wtot * L + fabs(rod->tip_moment) + fabs(dmoment);
    double sc[EL_N];
    sc[EL_THETA] = sc[EL_ETA] = 1.0;
    sc[EL_M] = sc[EL_ZETA] = Mref;
    sc[EL_P] = Wtot + Mref / L;
    sc[EL_X] = sc[EL_Y] = L;
    sc[EL_V] = Mref * L;
    for (int i = 0; i < EL_N; i++)
        sc[i] *= EL_TOL;

    double y[EL_N] = {theta_tip, rod->tip_moment, rod->tip_force, 0, 0, 0, 1.0, dmoment};
    int nz = 0;
    double send = L;
    size_t next_sample = n_sample; /* samples are taken from the tip down: index n-1 .. 0 */
    double h = -L / 64;
    for (size_t kk = rod->n_pieces; kk-- > 0;) {
        piece_ctx c = {&rod->pieces[kk], send - rod->pieces[kk].length};
        if (kk == 0)
            c.s0 = 0;
        /* a point force at the piece's distal end joins the weight carried from there on */
        if (rod->piece_loads)
            y[EL_P] += rod->piece_loads[kk];
        double s = send, stop_piece = c.s0;
        while (true) {
            /* the next stop: a sample point or the piece's start */
            double stop = stop_piece;
            if (sample && next_sample > 0) {
                double ss = L * (double)(next_sample - 1) / (double)(n_sample - 1);
                if (ss >= s - 1e-15 * L) {
                    sample(ud, next_sample - 1, s, y);
                    next_sample--;
                    continue;
                }
                if (ss > stop)
                    stop = ss;
            }
            if (s - stop <= 1e-15 * L) {
                if (stop == stop_piece)
                    break;
                continue;
            }
            double hh = h;
            bool last = false;
            if (s + hh <= stop) {
                hh = stop - s;
                last = true;
            }
            double ynew[EL_N];
            double err = dp_step(&c, s, y, hh, sc, ynew);
            if (!isfinite(err))
                return CBM_E_NONFINITE;
            if (err <= 1.0) {
                /* a zero of eta inside (0, L); eta(0) == 0 itself is the fold */
                if ((ynew[EL_ETA] > 0) != (y[EL_ETA] > 0) && ynew[EL_ETA] != 0.0)
                    nz++;
                memcpy(y, ynew, sizeof y);
                s = last ? stop : s + hh;
            }
            double fac = err > 0 ? 0.9 * pow(err, -0.2) : 5.0;
            fac = fac < 0.2 ? 0.2 : fac > 5.0 ? 5.0 : fac;
            h = hh * fac;
            if (fabs(h) < 1e-14 * L)
                return CBM_E_NOT_CONVERGED;
            if (h > -1e-12 * L)
                h = -1e-12 * L;
            if (-h > rod->pieces[kk].length / 4)
                h = -rod->pieces[kk].length / 4;
        }
        send = c.s0;
    }
    if (sample)
        while (next_sample > 0) {
            sample(ud, next_sample - 1, 0.0, y);
            next_sample--;
        }
    memcpy(y_base, y, sizeof y);
    if (zeros)
        *zeros = nz;
    return CBM_OK;
}

void cbm__el_state(const cbm_elastica_rod *rod, double theta_tip, const double *y, int zeros,
                   cbm_elastica_state *out)
{
    const cbm_elastica_piece *p0 = &rod->pieces[0];
    out->theta_tip = theta_tip;
    out->theta_base = y[EL_THETA];
    out->moment_base = y[EL_M];
    out->strain_base = y[EL_M] / p0->D0;
    out->curvature_base = out->strain_base + p0->rest_curvature;
    out->tip_x = -y[EL_X];
    out->tip_y = -y[EL_Y];
    out->energy = -y[EL_V] - rod->tip_moment * theta_tip;
    out->dbase_dtip = y[EL_ETA];
    out->dmoment_dtip = y[EL_ZETA];
    out->index = zeros;
}

cbm_status cbm_elastica_shoot(cbm_context *ctx, const cbm_elastica_rod *rod, double theta_tip,
                              cbm_elastica_state *out)
{
    if (!ctx || !out || !isfinite(theta_tip))
        return CBM_E_INVALID;
    cbm_status s = cbm__el_check(ctx, rod);
    if (s != CBM_OK)
        return s;
    double y[EL_N];
    int z = 0;
    s = cbm__el_integrate(rod, theta_tip, 0.0, y, &z, NULL, NULL, 0);
    if (s != CBM_OK)
        return cbm__fail(ctx, s, "elastica: integration failed at theta_tip = %g rad", theta_tip);
    cbm__el_state(rod, theta_tip, y, z, out);
    return CBM_OK;
}

typedef struct shape_out {
    double *x, *y, *theta;
} shape_out;

static void shape_sample(void *ud, size_t i, double s, const double *y)
{
    (void)s;
    shape_out *o = ud;
    /* positions relative to the tip for now; shifted to the base afterwards */
    if (o->x)
        o->x[i] = y[EL_X];
    if (o->y)
        o->y[i] = y[EL_Y];
    if (o->theta)
        o->theta[i] = y[EL_THETA];
}

cbm_status cbm_elastica_shape(cbm_context *ctx, const cbm_elastica_rod *rod, double theta_tip,
                              size_t n, double *x, double *y, double *theta)
{
    if (!ctx || n < 2 || !isfinite(theta_tip))
        return CBM_E_INVALID;
    cbm_status s = cbm__el_check(ctx, rod);
    if (s != CBM_OK)
        return s;
    shape_out o = {x, y, theta};
    double yb[EL_N];
    s = cbm__el_integrate(rod, theta_tip, 0.0, yb, NULL, shape_sample, &o, n);
    if (s != CBM_OK)
        return cbm__fail(ctx, s, "elastica: integration failed at theta_tip = %g rad", theta_tip);
    for (size_t i = 0; i < n; i++) {
        if (x)
            x[i] -= yb[EL_X];
        if (y)
            y[i] -= yb[EL_Y];
    }
    return CBM_OK;
}
