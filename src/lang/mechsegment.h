/* The layout of the L+C dialect's built-in struct MechSegment: the language declares it
 * (lc_parse.c) and the mechanics bridge (lsys/mechlang.c) reads and writes it. */
#ifndef CBM_LANG_MECHSEGMENT_H
#define CBM_LANG_MECHSEGMENT_H

/* Offsets (doubles) of the fields of the built-in struct MechSegment. */
enum {
    MS_LENGTH = 0,
    MS_A = 1,
    MS_B = 2,
    MS_E = 3,
    MS_G = 4,
    MS_DENSITY = 5,
    MS_MOR = 6,
    MS_REST = 7,   /* V3d, local (H, L, U), rad/m */
    MS_OMEGA = 10, /* V3d, local */
    MS_POS = 13,   /* V3d, world, proximal node */
    MS_H = 16,     /* V3d, world */
    MS_U = 19,     /* V3d, world */
    MS_STRESS = 22,
    MS_RATIO = 23,
    MS_CARRIED = 24,
    MS_AGE = 25,
    MS_SIZE = 26
};

#endif
