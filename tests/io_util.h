/* Helpers of the output tests: small fixed scenes and whole-file reading. */
#ifndef CBM_TEST_IO_UTIL_H
#define CBM_TEST_IO_UTIL_H

#include "test.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The whole file (NUL-terminated, free() it), NULL if it cannot be read. */
static inline char *io_read_all(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *b = malloc((size_t)n + 1);
    if (b && fread(b, 1, (size_t)n, f) != (size_t)n) {
        free(b);
        b = NULL;
    }
    fclose(f);
    if (b) {
        b[n] = '\0';
        if (len)
            *len = (size_t)n;
    }
    return b;
}

static inline size_t io_count(const char *text, const char *needle)
{
    size_t n = 0, k = strlen(needle);
    for (const char *p = strstr(text, needle); p; p = strstr(p + k, needle))
        n++;
    return n;
}

static inline char *io_path(const char *name)
{
    static char buf[8][4096];
    static int next;
    char *b = buf[next++ % 8];
    snprintf(b, sizeof buf[0], "%s/%s", test_tmp_dir(), name);
    return b;
}

/* A tube (elliptical section a = 2b), a leaf and a fruit, with known part data. */
static inline cbm_status io_small_scene(cbm_context *ctx, cbm_scene **out)
{
    cbm_scene *s;
    cbm_status st0 = cbm_scene_create(ctx, &s);
    if (st0 != CBM_OK)
        return st0;
    cbm_part p = cbm_part_default();
    p.order = 0;
    p.segment = 7;
    p.stress_ratio = 0.5;
    p.age = 3;
    p.reaction_wood = 0.25;
    cbm_status st = cbm_scene_begin_part(s, &p, NULL);
    cbm_frame f = {{0, 1, 0}, {-1, 0, 0}, {0, 0, 1}};
    cbm_section s0 = {{0, 0, 0}, f, 0.04, 0.02}, s1 = {{0, 0.5, 0}, f, 0.03, 0.015};
    if (st == CBM_OK)
        st = cbm_scene_add_tube(s, &s0, &s1, 12, true);
    cbm_part l = cbm_part_default();
    l.organ = CBM_ORGAN_LEAF;
    l.color[0] = 0.1f, l.color[1] = 0.5f, l.color[2] = 0.1f;
    if (st == CBM_OK)
        st = cbm_scene_begin_part(s, &l, NULL);
    const cbm_vec3 leaf[4] = {{0, 0.5, 0}, {0.1, 0.55, 0.03}, {0.2, 0.5, 0}, {0.1, 0.47, -0.03}};
    if (st == CBM_OK)
        st = cbm_scene_add_polygon(s, leaf, 4);
    cbm_part fr = cbm_part_default();
    fr.organ = CBM_ORGAN_FRUIT;
    fr.color[0] = 0.8f, fr.color[1] = 0.1f, fr.color[2] = 0.05f;
    if (st == CBM_OK)
        st = cbm_scene_begin_part(s, &fr, NULL);
    if (st == CBM_OK)
        st = cbm_scene_add_sphere(s, (cbm_vec3){-0.08, 0.4, 0}, 0.04, 12);
    if (st != CBM_OK) {
        cbm_scene_destroy(s);
        return st;
    }
    *out = s;
    return CBM_OK;
}

#endif
