/* Private layout of Oberlaender's parametric tree (ober_params.c, ober_formula.c, ober_grow.c,
 * ober_scene.c): the compiled formulas, the shoots, buds and trees of a stand. */
#ifndef CBM_OBER_INTERNAL_H
#define CBM_OBER_INTERNAL_H

#include "cambium/ober.h"
#include "core/core.h"
#include "lang/lang.h"

/* The variables formulas read (Table 2), one slot each in the evaluation's parameter array. */
enum {
    V_AGE, /* the tree's age in a tree formula, the shoot's in a shoot formula, the mother
            * shoot's in a bud formula */
    V_TREE_AGE,
    V_CARBON_TAX,
    V_BASE_LENGTH,
    V_CARBON_MEAN,
    V_ACTIVE_SHOOTS,
    V_SUM_LEAVES,
    V_WOOD_VOLUME,
    V_TRUNK_VOLUME,
    V_HEIGHT,
    V_TREE_INDEX,
    V_TREE_LEVEL_END, /* shoot variables from here */
    V_LEN = V_TREE_LEVEL_END,
    V_LENGTH,
    V_DIAMETER,
    V_RADIUS,
    V_NODE_NUMBER,
    V_ORDER,
    V_TREND,
    V_VOLUME,
    V_CARBON,
    V_LEAVES,
    V_SHOOT_LEVEL_END, /* bud variables from here */
    V_POSITION = V_SHOOT_LEVEL_END,
    V_SLEEP,
    V_SHORT_SHOOT,
    V_APICAL,
    V_PARENT_ORDER,
    V_PARENT_TREND,
    V_COUNT
};

typedef enum ober_level { LVL_TREE, LVL_SHOOT, LVL_BUD } ober_level;

/* Every formula of a definition, compiled into one node array. */
enum {
    F_BASE_LENGTH,
    F_CARBON_TAX,
    F_SPROUTING,
    F_PROVENTITIOUS,
    F_APICAL_SPLIT,
    F_SHORT_SHOOT,
    F_ORIENTATION,
    F_BENDING,
    F_SPECIFIC_LENGTH,                                 /* + order */
    F_NUM_NODES = F_SPECIFIC_LENGTH + CBM_OBER_ORDERS, /* + order */
    F_COUNT = F_NUM_NODES + CBM_OBER_ORDERS
};

typedef struct ober_prog {
    cbm__compiler c;
    bool have_c;
    int32_t root[F_COUNT]; /* -1: not set (constant default) */
    cbm__eval ev;
    double vars[V_COUNT];
} ober_prog;

/// Compiles every formula of def (errors reported as file:line:col); CBM_E_SYNTAX on errors.
cbm_status cbm__ober_compile(cbm_context *ctx, const cbm_ober_def *def, ober_prog *p);
void cbm__ober_prog_free(ober_prog *p);
/// Value of formula f with p->vars filled; NaN or a runtime error is reported naming the
/// formula's file:line:col and gives CBM_E_RUNTIME in *st (left alone when fine).
double cbm__ober_eval(ober_prog *p, int f, cbm_status *st);
/// Name of the parameter of formula f (for messages).
const char *cbm__ober_formula_name(int f);

typedef struct ober_bud {
    int32_t shoot; /* carrier */
    int32_t node;  /* 1..N */
    int16_t order, trend;
    double position;
    double head; /* deg about the carrier's axis (phyllotaxis and the bud's own angle) */
    uint8_t sleep, used, none; /* none: a leaf position only (short shoot, beyond maxOrder) */
    uint8_t apical;            /* the apical bud (no leaf) */
} ober_bud;

typedef struct ober_shoot {
    int32_t parent, tree;
    int32_t order, trend, nodes, age;
    int32_t node;  /* lateral: node on the mother (1..N); 0: at the mother's tip */
    double head;   /* deg: lateral: head about the mother's axis; fork: the arm's side */
    double insert; /* deg: insertion angle from the mother's axis (0: continuation) */
    double phase;  /* deg: cumulative head rotation of the axis at the shoot's base */
    double position;
    double len, radius, tropism, carbon; /* cm, cm, -, - */
    int32_t leaves_made;
    int32_t leaves;    /* living */
    int32_t supported; /* leaves counted by the pipe model this year (basipetal) */
    int32_t first_bud, nbuds, active_buds;
    int32_t children;
    uint8_t lateral, short_shoot, proventitious, fresh, alive, sprouted;
    /* geometry, recomputed every year (cm, local frame) */
    cbm_vec3 base, tip, H, L, U;
    /* mechanics feedback (ober_mech.c): rotation vectors (rad) in the shoot's own (H, L, U) after
     * the joint, the bend its wood memorised and this year's elastic bend on top; the radius
     * (cm) when it last memorised; bend_rest: the memorised bend of the rest shape this year's
     * statics started from (bend_mem before this year's share), which --mechanics observes from */
    cbm_vec3 bend_mem, bend_el, bend_rest;
    double radius_mem;
} ober_shoot;

typedef struct ober_tree {
    cbm_vec3 pos; /* cm */
    int timer;    /* years before it germinates */
    int age;      /* 0: a seed */
    double carbon_tax, base_length, carbon_mean;
    double active_shoots, sum_leaves, wood_volume, trunk_volume, height;
    CBM_ARRAY(cbm_ober_report) years;
    cbm_ober_report cur;
} ober_tree;

struct cbm_ober_stand {
    cbm_context *ctx;
    cbm_ober_def def;
    ober_prog prog;
    cbm_rng rng;
    int year;
    CBM_ARRAY(ober_tree) trees;
    CBM_ARRAY(ober_shoot) shoots;
    CBM_ARRAY(ober_bud) buds;
    CBM_ARRAY(double) leaf_carbon; /* per lateral bud: carbon of its leaf from the light pass */
    size_t light_rays;             /* of the last light pass */
    double light_seconds;
};

/* ober_scene.c: the leaf quad of bud b (cm, world), false when it has no living leaf. */
bool cbm__ober_leaf_quad(const cbm_ober_stand *s, size_t b, cbm_vec3 q[4]);
/* ober_light.c: the leaves' carbon from the light pass (or 1 each without light). */
cbm_status cbm__ober_light(cbm_ober_stand *s);
/* ober_grow.c: positions and frames of every shoot from the graph (turtle interpretation). */
void cbm__ober_geometry(cbm_ober_stand *s);
/* ober_mech.c: the statics of every tree bends its shoots (mechanicsFeedback). */
cbm_status cbm__ober_feedback(cbm_ober_stand *s);

#endif
