/* cbm_turtle_motion (src/io/gltf_frames.c): the frames must draw the same parts at increasing
 * times; a frame records segment ends and sphere centres; one frame writes a static glTF. */
#include "test.h"

#include "cambium/turtle_motion.h"

#include <stdio.h>
#include <string.h>

/* F(len) then optionally a sphere, through the turtle with cpfg's defaults */
static cbm_turtle *draw(cbm_context *ctx, cbm_view *v, int nseg, double len)
{
    double p[4][1] = {{len}, {len}, {len}, {0.2}};
    cbm_tmodule m[4];
    int n = 0;
    for (int i = 0; i < nseg; i++)
        m[n++] = (cbm_tmodule){"F", 1, p[i]};
    m[n++] = (cbm_tmodule){"@O", 1, p[3]};
    cbm_turtle *t = NULL;
    CHECK_OK(cbm_turtle_interpret(ctx, v, NULL, m, (size_t)n, NULL, &t));
    return t;
}

TEST(motion_frames_and_errors)
{
    cbm_context *ctx = test_ctx();
    cbm_view *v = NULL;
    CHECK_OK(cbm_view_create(ctx, &v));
    cbm_turtle_motion *mo = NULL;
    CHECK_OK(cbm_turtle_motion_create(ctx, &mo));
    cbm_turtle *a = draw(ctx, v, 2, 1.0), *b = draw(ctx, v, 2, 1.5), *c = draw(ctx, v, 3, 1.0);
    CHECK_OK(cbm_turtle_motion_add_frame(mo, a, NULL, 0.0, 0));
    CHECK_EQ_INT((int)cbm_turtle_motion_part_count(mo), 3);
    cbm_vec3 p0, p1;
    CHECK(cbm_turtle_motion_part(mo, 0, 1, &p0, &p1));
    CHECK_NEAR(p1.y, 2.0, 1e-12); /* the second F ends 2 up (cpfg's turtle heads along +y) */
    CHECK(cbm_turtle_motion_part(mo, 0, 2, &p0, &p1));
    CHECK_NEAR(p0.y, 2.0, 1e-12); /* the sphere's centre, twice */
    CHECK_NEAR(p1.y, 2.0, 1e-12);
    char path[4096];
    snprintf(path, sizeof path, "%s/motion-static.glb", test_tmp_dir());
    CHECK_OK(cbm_turtle_motion_write_glb(mo, path)); /* one frame: no animation, still valid */
    CHECK_STATUS(cbm_turtle_motion_add_frame(mo, b, NULL, 0.0, 1), CBM_E_INVALID);
    CHECK(strstr(cbm_context_last_error(ctx), "does not increase") != NULL);
    CHECK_STATUS(cbm_turtle_motion_add_frame(mo, c, NULL, 1.0, 1), CBM_E_INVALID);
    CHECK(strstr(cbm_context_last_error(ctx),
                 "draws 4 segments and spheres where frame 0 drew 3") != NULL);
    CHECK_EQ_INT((int)cbm_turtle_motion_frame_count(mo), 1);
    CHECK_OK(cbm_turtle_motion_add_frame(mo, b, NULL, 1.0, 1));
    CHECK(cbm_turtle_motion_part(mo, 1, 1, &p0, &p1));
    CHECK_NEAR(p1.y, 3.0, 1e-12);
    CHECK(!cbm_turtle_motion_part(mo, 2, 0, &p0, &p1));
    snprintf(path, sizeof path, "%s/motion-two.csv", test_tmp_dir());
    CHECK_OK(cbm_turtle_motion_write_csv(mo, path));
    FILE *f = fopen(path, "r");
    CHECK(f != NULL);
    int lines = 0;
    char line[256];
    while (f && fgets(line, sizeof line, f))
        lines++;
    if (f)
        fclose(f);
    CHECK_EQ_INT(lines, 1 + 2 * 3);
    cbm_turtle_destroy(a);
    cbm_turtle_destroy(b);
    cbm_turtle_destroy(c);
    cbm_turtle_motion_destroy(mo);
    cbm_view_destroy(v);
    test_ctx_end(ctx);
}
