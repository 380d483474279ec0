/* The one-dimensional mass-spring chain of Taylor-Hell (2005) §9.2 (eqs. 9.6-9.20), inertial and
 * non-inertial, the thesis' first check of its non-inertial method: "tests of inertial and
 * non-inertial mass-spring systems indicate that they produce identical resulting motion".
 *
 * Inertial form (§9.2.1): each particle's force is the pull of its own spring, the push of the
 * next one and the damping of its world velocity, a_i = F_i / m_i (9.12), and each spring's
 * length changes with the difference of the world velocities of its two ends (9.14).
 *
 * Non-inertial form (§9.2.2): particle i is seen from particle i-1. One pass from the wall
 * accumulates the world velocity and acceleration of each particle from the relative ones
 * (9.16/9.17), the relative acceleration is the spring and damping force plus the fictitious
 * force -m_i a_{i-1} of the accelerating frame, over m_i (9.18), and a spring's length changes
 * with its particle's relative velocity alone (9.20).
 *
 * In exact arithmetic the relative velocity u_i is v_i - v_{i-1} at every step and the relative
 * acceleration a_i - a_{i-1}, so the two forms trace the same motion; in floating point they
 * differ by round-off only. Both use the same Euler scheme: the text's explicit Euler (lengths
 * with the old velocities) or the semi-implicit one of the A.4 listing. */
#include "cambium/chain.h"

#include "../core/core.h"

#include <math.h>

struct cbm_chain {
    cbm_context *ctx;
    cbm_chain_def def; /* array pointers cleared: the chain owns copies below */
    size_t steps;
    double *k, *rest, *mass;
    double *len; /* l_i, m */
    double *vel; /* inertial: v_i seen from the wall; non-inertial: u_i seen from particle i-1 */
    double *acc; /* scratch: a_i (inertial) or the relative acceleration (non-inertial) */
};

cbm_chain_def cbm_chain_def_default(void)
{
    cbm_chain_def d;
    memset(&d, 0, sizeof d);
    d.dt = 1e-3;
    d.form = CBM_CHAIN_INERTIAL;
    d.scheme = CBM_CHAIN_EXPLICIT_EULER;
    return d;
}

static size_t bytes(const cbm_chain *c)
{
    return 6 * c->def.n * sizeof(double);
}

void cbm_chain_destroy(cbm_chain *c)
{
    if (!c)
        return;
    cbm__free(c->ctx, c->k, bytes(c));
    cbm__free(c->ctx, c, sizeof *c);
}

cbm_status cbm_chain_create(cbm_context *ctx, const cbm_chain_def *def, cbm_chain **out)
{
    if (!ctx || !def || !out)
        return CBM_E_INVALID;
    *out = NULL;
    size_t n = def->n;
    if (n < 1 || n > ((size_t)1 << 28))
        return cbm__fail(ctx, CBM_E_INVALID, "chain: n must be 1..2^28 links (got %zu)", n);
    if (!def->k || !def->rest || !def->mass)
        return cbm__fail(ctx, CBM_E_INVALID, "chain: k, rest and mass must be given");
    if (!(def->dt > 0) || !isfinite(def->dt))
        return cbm__fail(ctx, CBM_E_INVALID, "chain: dt must be > 0 s");
    if (!(def->damping >= 0) || !isfinite(def->damping))
        return cbm__fail(ctx, CBM_E_INVALID, "chain: damping must be >= 0 N s/m");
    if (def->form != CBM_CHAIN_INERTIAL && def->form != CBM_CHAIN_NONINERTIAL)
        return cbm__fail(ctx, CBM_E_INVALID, "chain: unknown form %d", (int)def->form);
    if (def->scheme != CBM_CHAIN_EXPLICIT_EULER && def->scheme != CBM_CHAIN_SEMI_IMPLICIT_EULER)
        return cbm__fail(ctx, CBM_E_INVALID, "chain: unknown scheme %d", (int)def->scheme);
    for (size_t i = 0; i < n; i++) {
        if (!(def->k[i] > 0) || !isfinite(def->k[i]))
            return cbm__fail(ctx, CBM_E_INVALID, "chain: k[%zu] must be > 0 N/m", i);
        if (!(def->mass[i] > 0) || !isfinite(def->mass[i]))
            return cbm__fail(ctx, CBM_E_INVALID, "chain: mass[%zu] must be > 0 kg", i);
        if (!isfinite(def->rest[i]) || (def->length && !isfinite(def->length[i])) ||
            (def->velocity && !isfinite(def->velocity[i])))
            return cbm__fail(ctx, CBM_E_INVALID,
                             "chain: rest, length and velocity of link %zu must be finite", i);
    }
    cbm_chain *c = cbm__calloc(ctx, 1, sizeof *c);
    if (!c)
        return CBM_E_NOMEM;
    c->ctx = ctx;
    c->def = *def;
    c->def.k = c->def.rest = c->def.mass = c->def.length = c->def.velocity = NULL;
    c->k = cbm__alloc(ctx, bytes(c));
    if (!c->k) {
        cbm__free(ctx, c, sizeof *c);
        return CBM_E_NOMEM;
    }
    c->rest = c->k + n;
    c->mass = c->rest + n;
    c->len = c->mass + n;
    c->vel = c->len + n;
    c->acc = c->vel + n;
    double prev = 0;
    for (size_t i = 0; i < n; i++) {
        c->k[i] = def->k[i];
        c->rest[i] = def->rest[i];
        c->mass[i] = def->mass[i];
        c->len[i] = def->length ? def->length[i] : def->rest[i];
        double v = def->velocity ? def->velocity[i] : 0;
        /* the non-inertial form keeps each particle's velocity relative to its parent (9.19) */
        c->vel[i] = def->form == CBM_CHAIN_NONINERTIAL ? v - prev : v;
        c->acc[i] = 0;
        prev = v;
    }
    *out = c;
    return CBM_OK;
}

/* Spring forces on particle i (9.8-9.10): its own spring pulls it back, the next one pushes. */
static double spring_force(const cbm_chain *c, size_t i)
{
    double f = -c->k[i] * (c->len[i] - c->rest[i]);
    if (i + 1 < c->def.n)
        f += c->k[i + 1] * (c->len[i + 1] - c->rest[i + 1]);
    return f;
}

static void step_inertial(cbm_chain *c)
{
    size_t n = c->def.n;
    double dt = c->def.dt;
    for (size_t i = 0; i < n; i++) /* 9.11, 9.12 */
        c->acc[i] = (spring_force(c, i) - c->def.damping * c->vel[i]) / c->mass[i];
    if (c->def.scheme == CBM_CHAIN_EXPLICIT_EULER) {
        /* 9.14 with the old velocities, from the tip down so that v_{i-1} is still the old one */
        for (size_t i = n; i-- > 0;)
            c->len[i] += dt * (c->vel[i] - (i ? c->vel[i - 1] : 0));
        for (size_t i = 0; i < n; i++) /* 9.13 */
            c->vel[i] += dt * c->acc[i];
    } else {
        for (size_t i = 0; i < n; i++)
            c->vel[i] += dt * c->acc[i];
        for (size_t i = 0; i < n; i++)
            c->len[i] += dt * (c->vel[i] - (i ? c->vel[i - 1] : 0));
    }
}

static void step_noninertial(cbm_chain *c)
{
    size_t n = c->def.n;
    double dt = c->def.dt, wv = 0, wa = 0; /* the wall's frame neither moves nor accelerates */
    for (size_t i = 0; i < n; i++) {
        wv += c->vel[i]; /* W v_i = W v_{i-1} + (i-1) v_i */
        /* 9.18: springs, damping of the world velocity, fictitious force of frame i-1 */
        double f = spring_force(c, i) - c->def.damping * wv - c->mass[i] * wa;
        c->acc[i] = f / c->mass[i];
        wa += c->acc[i]; /* W a_i = W a_{i-1} + (i-1) a_i (9.16) */
    }
    for (size_t i = 0; i < n; i++) {
        if (c->def.scheme == CBM_CHAIN_EXPLICIT_EULER) {
            c->len[i] += dt * c->vel[i]; /* 9.20 with the old relative velocity */
            c->vel[i] += dt * c->acc[i];
        } else {
            c->vel[i] += dt * c->acc[i];
            c->len[i] += dt * c->vel[i];
        }
    }
}

cbm_status cbm_chain_step(cbm_chain *c, size_t steps)
{
    if (!c)
        return CBM_E_INVALID;
    for (size_t s = 0; s < steps; s++) {
        if (c->def.form == CBM_CHAIN_INERTIAL)
            step_inertial(c);
        else
            step_noninertial(c);
        c->steps++;
    }
    for (size_t i = 0; i < c->def.n; i++)
        if (!isfinite(c->len[i]) || !isfinite(c->vel[i]))
            return cbm__fail(c->ctx, CBM_E_NONFINITE,
                             "chain: link %zu left the finite numbers after %zu steps (dt %g s "
                             "too large for the stiffest spring?)",
                             i, c->steps, c->def.dt);
    return CBM_OK;
}

double cbm_chain_time(const cbm_chain *c)
{
    return c ? (double)c->steps * c->def.dt : 0;
}

void cbm_chain_positions(const cbm_chain *c, double *x)
{
    double s = 0;
    for (size_t i = 0; c && i < c->def.n; i++)
        x[i] = s += c->len[i];
}

void cbm_chain_velocities(const cbm_chain *c, double *v)
{
    double s = 0;
    for (size_t i = 0; c && i < c->def.n; i++)
        v[i] = c->def.form == CBM_CHAIN_NONINERTIAL ? (s += c->vel[i]) : c->vel[i];
}

double cbm_chain_energy(const cbm_chain *c)
{
    if (!c)
        return 0;
    double e = 0, wv = 0;
    for (size_t i = 0; i < c->def.n; i++) {
        wv = c->def.form == CBM_CHAIN_NONINERTIAL ? wv + c->vel[i] : c->vel[i];
        double d = c->len[i] - c->rest[i];
        e += 0.5 * c->mass[i] * wv * wv + 0.5 * c->k[i] * d * d;
    }
    return e;
}
