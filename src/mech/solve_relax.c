/* The seeds' relaxation solver (Jirasek et al. 2000 eqs. 17-21; Taylor-Hell 2005 eq. 6.24):
 * each pass propagates frames outward, accumulates forces and moments inward, and moves every
 * joint's rotation rate towards the elastic response to its current moment,
 *     Omega <- (1 - alpha) Omega + alpha (rest + C^-1 M_local),
 * componentwise in the local frame (the update is fused into the backward sweep). The fixed point
 * is the equilibrium C (Omega - rest) = M_local, independent of alpha. The solve stops when the
 * relative residual max|C(Omega - rest) - M_local| / max|M| of the state that produced the
 * moments is below the tolerance; a final evaluation pass (counted) makes the reported frames,
 * moments and residual those of the final Omega. See solve_common.c for the design. */
#include "mech/mech_internal.h"

#include <math.h>

cbm_status cbm__mech_solve_relax(cbm_plant *p, const cbm_solve_def *def, size_t max_passes,
                                 cbm_solve_stats *st)
{
    double alpha = def->alpha, tol = def->tolerance, mmax = 0.0, rel = INFINITY;
    st->continuation_steps = 1;
    for (;;) {
        if (st->passes + 1 >= max_passes)
            break;
        cbm__mech_forward_eval(p);
        double r = cbm__mech_backward(p, alpha, NULL, &mmax, NULL);
        st->passes++;
        if (!isfinite(r))
            return cbm__mech_report_nonfinite(p);
        rel = cbm__mech_relres(r, mmax, &st->char_moment);
        if (rel < tol)
            break;
        if (rel > 1e12) /* diverging: the state is meaningless, stop early */
            break;
    }
    /* evaluation pass: results consistent with the final Omega */
    cbm__mech_forward_eval(p);
    double r = cbm__mech_backward(p, 0.0, NULL, &mmax, NULL);
    st->passes++;
    if (!isfinite(r))
        return cbm__mech_report_nonfinite(p);
    rel = cbm__mech_relres(r, mmax, &st->char_moment);
    st->residual = rel;
    if (rel < tol) {
        st->stage = CBM_SOLVE_STAGE_RELAX;
        return CBM_OK;
    }
    return cbm__fail(p->ctx, CBM_E_NOT_CONVERGED,
                     "relax: relative residual %.3g after %zu passes (tolerance %.3g, alpha %g)",
                     rel, st->passes, tol, alpha);
}
