/* Checks of our turtle's geometry against cpfg's outputs in ../shared/oracles/vlab: the box of
 * ref/final.vv, every primitive of ref/final.ray.gz in order (cylinders, cones, polygons,
 * spheres, discs, surfaces, generalized-cylinder triangles) and the scene's bounds against
 * ref/final.obj.gz. Shared by the turtle's oracle test (fed cpfg's strings) and the whole-pipeline
 * oracle test (fed our own derivation). Points and radii agree within
 * 1e-5 * (1 + |value|) + 1e-5 * scale, scale the largest extent of the box (the .ray file prints 6
 * significant digits); the box within 1e-4 * scale. */
#ifndef CBM_TEST_ORACLE_GEOMETRY_H
#define CBM_TEST_ORACLE_GEOMETRY_H

#include "test.h"

#include "turtle/view_internal.h"

#define ORACLE CBM_TEST_SOURCE_DIR "/../shared/oracles/vlab/"

/// Whole file as a NUL-terminated string (malloc'ed), NULL if it cannot be read.
char *oracle_slurp(const char *path, size_t *len);

typedef struct oracle_model {
    const char *dir, *lfile, *view, *colors;
    bool homo;      /* compare with the string after the homomorphism (turtle test only) */
    int only_kind;  /* -1: all; else compare only this kind, and require box containment */
    double obj_tol; /* scene bounds against cpfg's final.obj.gz; < 0: not comparable */
} oracle_model;

/// The cpfg models both oracle tests run (test_turtle_oracle.c on cpfg's strings,
/// test_run_oracle.c on our own derivation), by the name of their test case: one row each in
/// oracle_geometry.c, so that the two tests cannot drift apart. An unknown name aborts.
const oracle_model *oracle_cpfg_model(const char *test_name);

/// Compares the turtle's box (and, with compare_prims, its primitive record) and the scene's
/// bounds with cpfg's; nmod is the number of modules interpreted (for the report line).
void oracle_check_geometry(const oracle_model *md, cbm_turtle *t, cbm_scene *scene, size_t nmod,
                           bool compare_prims);

#endif
