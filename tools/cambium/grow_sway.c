/* cambium grow --sway SECONDS [--wind M_S]: the grown tree's motion in a gusty wind (the library's
 * cbm_motion with cbm_motion_set_wind, docs/dynamics.md), written as an animated glTF (every
 * segment a rigid node keyed in translation and rotation at a fixed frame rate, the turtle-motion
 * writer of `run -o motion:F.glb`) and as a table of the tips' displacements.
 *
 * The motion starts at rest in the static deflection of the mean wind (no start-up transient of
 * a wind switched on at t = 0) and is linear about the equilibrium under weight: a segment's pose
 * at time t is its equilibrium pose turned by its rotation Theta_s (the sum of the joint rotations
 * from the base) and moved with its proximal node. Tracked in the table: the tip of the stem
 * (each order-0 segment without a continuation) and the tip of every first-order branch. */
#include "grow_sway.h"

#include "cli.h"
#include "cli_output.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

cli_sway cli_sway_default(void)
{
    cli_sway s = {0.0, 10.0, 0.2, 2e-3, 25.0, 0.03, 1, 0.0, 0.0, 0.0, 6, NULL, NULL, 800.0};
    return s;
}

static cbm_quat rotvec_quat(cbm_vec3 r)
{
    double a = sqrt(r.x * r.x + r.y * r.y + r.z * r.z);
    if (a < 1e-300)
        return (cbm_quat){1, 0, 0, 0};
    double s = sin(0.5 * a) / a;
    return (cbm_quat){cos(0.5 * a), r.x * s, r.y * s, r.z * s};
}

static cbm_quat quat_mul(cbm_quat a, cbm_quat b)
{
    return (cbm_quat){a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
                      a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
                      a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
                      a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w};
}

static cbm_vec3 cross(cbm_vec3 a, cbm_vec3 b)
{
    return (cbm_vec3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

static cbm_vec3 add(cbm_vec3 a, cbm_vec3 b)
{
    return (cbm_vec3){a.x + b.x, a.y + b.y, a.z + b.z};
}

static cbm_vec3 sub(cbm_vec3 a, cbm_vec3 b)
{
    return (cbm_vec3){a.x - b.x, a.y - b.y, a.z - b.z};
}

typedef struct sway_run {
    size_t n;
    cbm_segment_state *seg;
    cbm_vec3 *theta, *dx,
        *de; /* per segment: rotation, displacement of the proximal and distal node */
    cbm_motion_part *parts;
    size_t *track;
    size_t ntrack;
} sway_run;

/* theta and the nodes' displacements from the joint rotations q (first order, one sweep) */
static void kinematics(sway_run *r, const double *q)
{
    for (size_t i = 0; i < r->n; i++) {
        const cbm_segment_state *s = &r->seg[i];
        cbm_vec3 qi = {q[3 * i], q[3 * i + 1], q[3 * i + 2]};
        if (s->parent < 0) {
            r->theta[i] = qi;
            r->dx[i] = (cbm_vec3){0, 0, 0};
        } else {
            size_t p = (size_t)s->parent;
            r->theta[i] = add(r->theta[p], qi);
            /* the proximal node rides on the parent's rigid motion */
            r->dx[i] = add(r->de[p], cross(r->theta[p], sub(s->proximal, r->seg[p].distal)));
        }
        r->de[i] = add(r->dx[i], cross(r->theta[i], sub(s->distal, s->proximal)));
    }
}

static cbm_status add_frame(sway_run *r, cbm_turtle_motion *const *anims, int nglb, double t,
                            long step)
{
    for (size_t i = 0; i < r->n; i++) {
        const cbm_segment_state *s = &r->seg[i];
        cbm_motion_part *p = &r->parts[i];
        p->p0 = add(s->proximal, r->dx[i]);
        p->frame = quat_mul(rotvec_quat(r->theta[i]), s->orientation);
    }
    cbm_status st = CBM_OK;
    for (int k = 0; k < nglb && st == CBM_OK; k++)
        st = cbm_turtle_motion_add_parts(anims[k], r->parts, r->n, t, step);
    return st;
}

static void free_run(sway_run *r)
{
    free(r->seg);
    free(r->theta);
    free(r->dx);
    free(r->de);
    free(r->parts);
    free(r->track);
}

/* The recorder of one motion's outputs (grow --sway, run's sway: outputs). */
struct cli_sway_rec {
    sway_run r;
    size_t *axis;
    cbm_turtle_motion *anims[8];
    const char *glb[8];
    int nglb, ncsv;
    FILE *tables[8];
    char *tmpnames[8];
    const char *csv[8];
    double fps;
    long per_frame, last_frame; /* steps per frame, the step of the last frame (-1: none) */
};

void cli_sway_rec_discard(cli_sway_rec *w)
{
    if (!w)
        return;
    for (int k = 0; k < 8; k++) {
        if (w->tables[k])
            fclose(w->tables[k]);
        if (w->tmpnames[k]) {
            remove(w->tmpnames[k]);
            free(w->tmpnames[k]);
        }
        cbm_turtle_motion_destroy(w->anims[k]);
    }
    free(w->axis);
    free_run(&w->r);
    free(w);
}

cbm_status cli_sway_rec_begin(cbm_context *ctx, const cbm_plant *plant, double fps,
                              const char *const *glb, int nglb, const char *const *csv, int ncsv,
                              const char *cmd, cli_sway_rec **out)
{
    *out = NULL;
    size_t n = cbm_plant_segment_count(plant);
    if (n == 0 || nglb > 8 || ncsv > 8 || nglb < 0 || ncsv < 0)
        return CBM_E_INVALID;
    cli_sway_rec *w = calloc(1, sizeof *w);
    if (!w)
        return CBM_E_NOMEM;
    sway_run *r = &w->r;
    r->n = n;
    w->fps = fps;
    w->last_frame = -1;
    w->nglb = nglb;
    w->ncsv = ncsv;
    r->seg = malloc(n * sizeof *r->seg);
    r->theta = malloc(n * sizeof *r->theta);
    r->dx = malloc(n * sizeof *r->dx);
    r->de = malloc(n * sizeof *r->de);
    r->parts = calloc(n, sizeof *r->parts);
    r->track = malloc(n * sizeof *r->track);
    bool *cont = calloc(n, sizeof *cont);
    w->axis = malloc(n * sizeof *w->axis);
    cbm_status st = CBM_OK;
    if (!r->seg || !r->theta || !r->dx || !r->de || !r->parts || !r->track || !cont || !w->axis)
        st = CBM_E_NOMEM;
    for (size_t i = 0; i < n && st == CBM_OK; i++)
        st = cbm_plant_segment(plant, i, &r->seg[i]);
    for (size_t i = 0; i < n && st == CBM_OK; i++) {
        const cbm_segment_state *sg = &r->seg[i];
        int64_t p = sg->parent;
        bool same_axis = p >= 0 && sg->continuation && r->seg[p].order == sg->order;
        if (same_axis)
            cont[p] = true;
        w->axis[i] = same_axis ? w->axis[p] : i;
        double rad = sqrt(sg->a * sg->b);
        cbm_motion_part *pt = &r->parts[i];
        pt->length = sg->length;
        pt->r0 = pt->r1 = rad;
        float bark[4] = {0.42f, 0.31f, 0.2f, 1.0f};
        memcpy(pt->rgba, bark, sizeof bark);
    }
    for (size_t i = 0; i < n && st == CBM_OK; i++)
        if (!cont[i] && r->seg[i].order <= 1)
            r->track[r->ntrack++] = i;
    free(cont);
    for (int k = 0; k < nglb && st == CBM_OK; k++) {
        w->glb[k] = glb[k];
        st = cbm_turtle_motion_create(ctx, &w->anims[k]);
    }
    for (int k = 0; k < ncsv && st == CBM_OK; k++) {
        /* written beside the target and renamed at the end: no half-written table */
        w->csv[k] = csv[k];
        size_t len = strlen(csv[k]) + 16;
        w->tmpnames[k] = malloc(len);
        if (!w->tmpnames[k]) {
            st = CBM_E_NOMEM;
            break;
        }
        snprintf(w->tmpnames[k], len, "%s.part", csv[k]);
        w->tables[k] = fopen(w->tmpnames[k], "w");
        if (!w->tables[k]) {
            fprintf(stderr, "cambium %s: cannot write %s\n", cmd, csv[k]);
            st = CBM_E_IO;
            break;
        }
        fprintf(w->tables[k], "t_s,wind_m_s,axis,order,segment,dx_m,dy_m,dz_m\n");
    }
    if (st != CBM_OK) {
        cli_sway_rec_discard(w);
        return st;
    }
    *out = w;
    return CBM_OK;
}

cbm_status cli_sway_rec_step(cli_sway_rec *w, cbm_motion *m, long step, bool last)
{
    if (w->per_frame == 0) {
        w->per_frame = lround(1.0 / (w->fps * cbm_motion_dt(m)));
        if (w->per_frame < 1)
            w->per_frame = 1;
    }
    bool frame = step % w->per_frame == 0 || last;
    if (!frame || step == w->last_frame)
        return CBM_OK;
    w->last_frame = step;
    sway_run *r = &w->r;
    double t;
    cbm_motion_state(m, &t, NULL, NULL);
    kinematics(r, cbm_motion_rotations(m));
    cbm_status st = add_frame(r, w->anims, w->nglb, t, step);
    double u = cbm_motion_wind_at(m, t);
    for (int k = 0; k < w->ncsv; k++)
        for (size_t j = 0; j < r->ntrack; j++) {
            size_t i = r->track[j];
            cbm_vec3 d = r->de[i];
            fprintf(w->tables[k], "%.6f,%.6g,%zu,%d,%zu,%.9g,%.9g,%.9g\n", t, u, w->axis[i],
                    r->seg[i].order, i, d.x, d.y, d.z);
        }
    return st;
}

cbm_status cli_sway_rec_finish(cli_sway_rec *w, cbm_status st)
{
    for (int k = 0; k < w->nglb && st == CBM_OK; k++)
        st = cbm_turtle_motion_write_glb(w->anims[k], w->glb[k]);
    for (int k = 0; k < w->ncsv; k++) {
        if (w->tables[k] && fclose(w->tables[k]) != 0 && st == CBM_OK)
            st = CBM_E_IO;
        w->tables[k] = NULL;
        if (st == CBM_OK && rename(w->tmpnames[k], w->csv[k]) != 0)
            st = CBM_E_IO;
        if (st == CBM_OK) {
            free(w->tmpnames[k]);
            w->tmpnames[k] = NULL;
        }
    }
    cli_sway_rec_discard(w); /* removes the parts left when st is not OK */
    return st;
}

cbm_status cli_grow_sway(cbm_context *ctx, const cbm_plant *plant, const cli_sway *o,
                         const char *const *glb, int nglb, const char *const *csv, int ncsv,
                         bool timing)
{
    size_t n = cbm_plant_segment_count(plant);
    if (n == 0)
        return CBM_E_INVALID;
    cli_sway_rec *w = NULL;
    cbm_motion *m = NULL;
    /* the motion */
    cbm_motion_def md = cbm_motion_def_default();
    md.dt = o->dt;
    md.damping_ratio = o->damping;
    if (o->modes > 0) {
        md.method = CBM_MOTION_MODAL;
        md.modes = (size_t)o->modes;
    }
    double t0 = cli_seconds();
    cbm_status st = cbm_motion_create(plant, &md, &m);
    if (st != CBM_OK)
        return st;
    cbm_wind_def wd = cbm_wind_def_default();
    wd.organ_area_per_kg = o->organ_area;
    wd.leaf_area = o->leaf_area;
    wd.fruit_mass = o->fruit_mass;
    wd.fruit_density = o->fruit_density;
    cbm_gust_def gd = cbm_gust_def_default();
    gd.intensity = o->gust;
    gd.seed = (uint64_t)o->seed;
    gd.coherence_decay = o->coherence;
    gd.grid = (int32_t)o->grid;
    st = cbm_motion_set_wind(m, &wd, o->wind, &gd);
    if (st == CBM_OK)
        st = cbm_motion_start_wind_static(m);
    if (st == CBM_OK)
        st = cli_sway_rec_begin(ctx, plant, o->fps, glb, nglb, csv, ncsv, "grow", &w);
    if (st != CBM_OK) {
        cbm_motion_destroy(m);
        return st;
    }
    long steps = (long)ceil(o->seconds / o->dt - 1e-9);
    int max_it = 0;
    for (long s = 0; s <= steps && st == CBM_OK; s++) {
        if (s > 0) {
            st = cbm_motion_step(m);
            int it = cbm_motion_drag_iterations(m);
            max_it = it > max_it ? it : max_it;
        }
        if (st == CBM_OK)
            st = cli_sway_rec_step(w, m, s, s == steps);
    }
    if (timing && st == CBM_OK)
        fprintf(stderr,
                "grow: sway of %zu segments, %ld steps of %g s in %.3f s (%.1f us/step, drag "
                "iterations <= %d)\n",
                n, steps, o->dt, cli_seconds() - t0, 1e6 * (cli_seconds() - t0) / (double)steps,
                max_it);
    st = cli_sway_rec_finish(w, st);
    cbm_motion_destroy(m);
    return st;
}

cbm_status cli_run_sway_observe(void *ud, const cbm_plant *plant, cbm_motion *motion,
                                cbm_lsys_sway_phase phase)
{
    cli_run_sway *o = ud;
    if (phase == CBM_LSYS_SWAY_BEGIN) {
        cli_sway_rec_discard(o->rec); /* an earlier call's recording: the last call wins */
        o->rec = NULL;
        o->step = 0;
        cbm_status st = cli_sway_rec_begin(o->ctx, plant, cli_sway_default().fps, o->glb, o->nglb,
                                           o->csv, o->ncsv, "run", &o->rec);
        if (st != CBM_OK)
            return st;
        return cli_sway_rec_step(o->rec, motion, 0, false);
    }
    if (!o->rec)
        return CBM_E_INTERNAL;
    if (phase == CBM_LSYS_SWAY_STEP)
        return cli_sway_rec_step(o->rec, motion, ++o->step, false);
    return cli_sway_rec_step(o->rec, motion, o->step, true);
}
