/* The forward sweep's work at one segment, shared by the evaluation's forward sweep
 * (solve_common.c) and the Newton step's fused sweep (solve_tree.c, cbm__mech_tree_step_fused),
 * which runs it right after the solve and the step at that segment: one code, so the frames are
 * the same to the bit whichever sweep sets them. */
#ifndef CBM_SWEEP_INTERNAL_H
#define CBM_SWEEP_INTERNAL_H

#include "mech/mech_internal.h"
#include "core/vecmath.h"

/// Forward sweep at segment i: its frame and proximal node from its parent's (set before it);
/// with clear, its force and moment zeroed (an evaluation's backward sweep sets them without:
/// work.kin).
static inline void cbm__mech_forward_seg(cbm_plant *p, size_t i, bool clear)
{
    const int64_t *restrict par = p->parent;
    const double *restrict len = p->len;
    cbm_quat *restrict q = p->q;
    cbm_vec3 *restrict pos = p->pos;
    int64_t pa = par[i];
    cbm_quat qa;
    cbm_vec3 pp;
    if (pa < 0) {
        qa = p->base_q;
        pp = p->base_pos;
    } else {
        qa = q[pa];
        pp = v3_madd(pos[pa], q_h(qa), len[pa]);
    }
    cbm_quat b = p->branch[i];
    if (b.w != 1.0)
        qa = q_mul(qa, b);
    q[i] = cbm__mech_qnorm(q_mul(qa, cbm__mech_qexp(v3_scale(p->omega[i], p->work.dual[i]))));
    pos[i] = pp;
    if (clear) {
        p->force[i] = v3(0, 0, 0);
        p->moment[i] = v3(0, 0, 0);
    }
}

#endif
