/* The JSON writer (run.json summaries, glTF) and the progress line. */
#include "io_util.h"

TEST(json_nesting_escapes_and_numbers)
{
    cbm_context *ctx = test_ctx();
    cbm_json *j = NULL;
    CHECK_OK(cbm_json_create(ctx, &j));
    cbm_json_begin_object(j, NULL);
    cbm_json_string(j, "name", "a \"q\"\\\n\x01");
    cbm_json_number(j, "x", 0.1);
    cbm_json_number(j, "nan", NAN);
    cbm_json_int(j, "n", -42);
    cbm_json_bool(j, "ok", true);
    cbm_json_null(j, "none");
    cbm_json_begin_array(j, "steps");
    for (int k = 0; k < 3; k++) {
        cbm_json_begin_object(j, NULL);
        cbm_json_int(j, "step", k);
        cbm_json_number(j, "height_m", 1.0 / 3.0 * k);
        cbm_json_end_object(j);
    }
    cbm_json_end_array(j);
    cbm_json_end_object(j);
    const char *t = NULL;
    size_t n = 0;
    CHECK_OK(cbm_json_text(j, &t, &n));
    CHECK_MSG(
        t && strcmp(t, "{\"name\":\"a \\\"q\\\"\\\\\\n\\u0001\",\"x\":0.1,\"nan\":null,\"n\":-42,"
                       "\"ok\":true,\"none\":null,\"steps\":[{\"step\":0,\"height_m\":0},"
                       "{\"step\":1,\"height_m\":0.3333333333333333},"
                       "{\"step\":2,\"height_m\":0.6666666666666666}]}") == 0,
        "got %s", t ? t : "(null)");
    CHECK_EQ_INT(n, strlen(t));
    CHECK_OK(cbm_json_write_file(j, io_path("run.json")));
    char *b = io_read_all(io_path("run.json"), NULL);
    CHECK(b && strlen(b) == n + 1 && b[n] == '\n');
    free(b);
    cbm_json_destroy(j);
    test_ctx_end(ctx);
}

TEST(json_misuse_is_reported)
{
    cbm_context *ctx = test_ctx();
    const char *t;
    for (int c = 0; c < 4; c++) {
        cbm_json *j = NULL;
        CHECK_OK(cbm_json_create(ctx, &j));
        if (c == 0) { /* key inside an array */
            cbm_json_begin_array(j, NULL);
            cbm_json_int(j, "k", 1);
            cbm_json_end_array(j);
        } else if (c == 1) { /* missing key inside an object */
            cbm_json_begin_object(j, NULL);
            cbm_json_int(j, NULL, 1);
            cbm_json_end_object(j);
        } else if (c == 2) { /* not closed */
            cbm_json_begin_object(j, NULL);
        } else { /* mismatched close */
            cbm_json_begin_object(j, NULL);
            cbm_json_end_array(j);
        }
        CHECK_STATUS(cbm_json_text(j, &t, NULL), CBM_E_INVALID);
        CHECK_STATUS(cbm_json_write_file(j, io_path("bad.json")), CBM_E_INVALID);
        cbm_json_destroy(j);
    }
    FILE *f = fopen(io_path("bad.json"), "r");
    CHECK(f == NULL);
    if (f)
        fclose(f);
    test_ctx_end(ctx);
}

TEST(progress_line)
{
    char buf[256];
    cbm_progress p = {5, 10, 123456, 17, 10.0};
    size_t n = cbm_progress_format(&p, 100, buf, sizeof buf);
    CHECK_EQ_INT(n, strlen(buf));
    CHECK(n <= 100);
    CHECK(strstr(buf, " 50%") && strstr(buf, "step 5/10") && strstr(buf, "1.23e+05 modules") &&
          strstr(buf, "17 passes") && strstr(buf, "left 10s"));
    CHECK(buf[0] == '[' && strchr(buf, ']'));
    /* half the bar is filled */
    size_t bar = (size_t)(strchr(buf, ']') - buf - 1), hashes = 0;
    for (size_t k = 1; k <= bar; k++)
        hashes += buf[k] == '#';
    CHECK_EQ_INT(hashes, bar / 2);
    cbm_progress q = {0, 100, 10, 0, 0.0};
    cbm_progress_format(&q, 60, buf, sizeof buf);
    CHECK(strstr(buf, "left ?") != NULL && strlen(buf) <= 60);
    CHECK(strstr(buf, "passes") == NULL); /* no equilibrium passes: none shown */
    cbm_progress r = {30, 100, 10, 0, 600.0};
    cbm_progress_format(&r, 30, buf, sizeof buf);
    CHECK(strlen(buf) <= 30);
    cbm_progress_format(&r, 200, buf, sizeof buf);
    CHECK(strstr(buf, "left 23m20s") != NULL);
}
