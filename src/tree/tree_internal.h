/* Private layout of a built-in tree (fruit_tree.c, tree_spring.c, tree_scene.c): the plant, the
 * model's per-segment state kept parallel to the plant's segment arrays (same index, compacted
 * together when subtrees are removed), and the effective parameters after the form switch. */
#ifndef CBM_TREE_INTERNAL_H
#define CBM_TREE_INTERNAL_H

#include "cambium/tree.h"
#include "core/core.h"
#include "mech/mech.h"

enum {
    SEG_LATERAL = 1, /* a lateral bud internode (length bud_length) */
    SEG_BUD = 2,     /* carries an undecided bud (the listing's PotentialApex) */
    SEG_ABORTED = 4, /* an aborted bud: takes no resources */
    SEG_APEX = 8,    /* carries a growing apex */
    SEG_TRUNK1 = 16, /* part of the first year's trunk (lean measure) */
    SEG_REACT = 32,  /* laid reaction wood this year */
    SEG_GREW = 64,   /* laid a ring this year */
    SEG_TIP = 128    /* a branch tip at the end of this summer (spring-back measure) */
};

typedef struct tree_seg {
    uint8_t flags;
    uint8_t leader;    /* on the leader: the first shoot and its terminal buds' shoots */
    int32_t count;     /* node number in its annual shoot */
    int32_t nodes;     /* nodes of that shoot (numBuds) */
    int32_t low_since; /* year since which the segment has not grown, -1 */
    int32_t bud_year;  /* year (t->year) the bud was made or last decided dormant from */
    int32_t nleaf;     /* leaves at the node (0 or 1; a spur's rosette spur_leaves) */
    double h;          /* position of the node in its annual shoot, count / nodes (bud height) */
    double phyllo;     /* rad, divergence of the next lateral (listing phyllo) */
    double juv_e;      /* Pa, juvenile modulus of the shoot */
    double leaf, leaf_goal, fruit, fruit_goal; /* kg */
    double tip_y;                              /* m, height of a SEG_TIP at the end of summer */
    double vigour, sink, share;                /* last spring pass */
} tree_seg;

struct cbm_tree {
    cbm_context *ctx;
    cbm_tree_def def;
    cbm_plant *plant;
    cbm_rng rng;
    CBM_ARRAY(tree_seg) seg;
    cbm_growth_def growth;
    cbm_solve_def solve;
    /* effective values after the form switch */
    double e_juv, e_adult, trop, dev_factor;
    bool fade;
    int year; /* completed years */
    cbm_tree_season season;
    int winter_steps;
    bool unloaded_recorded;
    bool converged; /* the last equilibrium met the tolerance */
    CBM_ARRAY(cbm_tree_summary) years;
    cbm_tree_summary cur;
};

/* The plant's per-segment arrays the tree reads, from the mechanics' package header: a snapshot,
 * taken again after the plant gains or loses segments (tree_plant_of). */
typedef struct tree_plant {
    size_t n;
    const int64_t *parent;
    const int32_t *order;
    const uint32_t *nchild;
    const double *len, *area;
    const cbm__outer *outer;
    const cbm_vec3 *pos;
    const cbm_quat *q;
} tree_plant;

static inline tree_plant tree_plant_of(const cbm_plant *pl)
{
    return (tree_plant){
        cbm_plant_segment_count(pl), cbm_plant_parents(pl),   cbm__plant_orders(pl),
        cbm__plant_child_counts(pl), cbm__plant_lengths(pl),  cbm__plant_areas(pl),
        cbm__plant_outers(pl),       cbm_plant_positions(pl), cbm_plant_orientations(pl)};
}

/* tree_spring.c: the spring pass (bud fate by resource allocation, 4.8-4.19, 7.1). */
cbm_status cbm__tree_spring(cbm_tree *t);

/* A parameter file's text (tree_params.c; the fruit tree's and Oberländer's readers): *buf, len
 * bytes in cap allocated, freed by the caller (cbm__free(ctx, buf, cap)) also on failure. */
cbm_status cbm__tree_read_params(cbm_context *ctx, const char *path, char **buf, size_t *len,
                                 size_t *cap);

/* The lines of a parameter text (tree_params.c; both readers): cbm__param_next skips blank and
 * comment-only lines and gives the next line's start *l, its 1-based number (it->line), the first
 * non-blank column *i and the end *m of its content before a '#' and trailing blanks; false at the
 * end of the text. */
typedef struct cbm__param_lines {
    const char *text;
    size_t len, pos;
    int line;
} cbm__param_lines;
bool cbm__param_next(cbm__param_lines *it, const char **l, size_t *i, size_t *m);
/* A parameter value as a finite double (trailing blanks allowed, nothing else): false if it is
 * not one (both readers). */
bool cbm__param_real(const char *s, double *out);

#endif
