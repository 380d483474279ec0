/* The glTF 2.0 binary container and buffer bookkeeping shared by the glTF writers (glb_internal.h).
 */
#include "glb_internal.h"

#include <math.h>

void cbm__gltf_accessor_set(cbm__gltf_accessor *a, size_t view, const void *data, size_t count,
                            int ncomp, int ctype, bool minmax)
{
    memset(a, 0, sizeof *a);
    a->view = view;
    a->count = count;
    a->ncomp = ncomp;
    a->ctype = ctype;
    a->minmax = minmax;
    if (!minmax)
        return;
    const float *f = data;
    for (int k = 0; k < ncomp; k++) {
        a->min[k] = INFINITY;
        a->max[k] = -INFINITY;
    }
    for (size_t i = 0; i < count; i++)
        for (int k = 0; k < ncomp; k++) {
            a->min[k] = fminf(a->min[k], f[i * (size_t)ncomp + (size_t)k]);
            a->max[k] = fmaxf(a->max[k], f[i * (size_t)ncomp + (size_t)k]);
        }
}

void cbm__gltf_json_floats(cbm_json *j, const char *key, const float *f, int n)
{
    cbm_json_begin_array(j, key);
    for (int k = 0; k < n; k++)
        cbm_json_number(j, NULL, f[k]);
    cbm_json_end_array(j);
}

void cbm__gltf_json_buffers(cbm_json *j, const cbm__gltf_accessor *acc, size_t nacc,
                            const cbm__gltf_view *views, size_t nview, size_t bin_len)
{
    static const char *const types[5] = {"", "SCALAR", "VEC2", "VEC3", "VEC4"};
    cbm_json_begin_array(j, "accessors");
    for (size_t i = 0; i < nacc; i++) {
        const cbm__gltf_accessor *a = &acc[i];
        cbm_json_begin_object(j, NULL);
        cbm_json_int(j, "bufferView", (int64_t)a->view);
        cbm_json_int(j, "componentType", a->ctype);
        cbm_json_int(j, "count", (int64_t)a->count);
        cbm_json_string(j, "type", types[a->ncomp]);
        if (a->minmax) {
            cbm__gltf_json_floats(j, "min", a->min, a->ncomp);
            cbm__gltf_json_floats(j, "max", a->max, a->ncomp);
        }
        cbm_json_end_object(j);
    }
    cbm_json_end_array(j);
    cbm_json_begin_array(j, "bufferViews");
    for (size_t i = 0; i < nview; i++) {
        const cbm__gltf_view *v = &views[i];
        cbm_json_begin_object(j, NULL);
        cbm_json_int(j, "buffer", 0);
        cbm_json_int(j, "byteOffset", (int64_t)v->offset);
        cbm_json_int(j, "byteLength", (int64_t)v->length);
        if (v->target)
            cbm_json_int(j, "target", v->target);
        cbm_json_end_object(j);
    }
    cbm_json_end_array(j);
    cbm_json_begin_array(j, "buffers");
    cbm_json_begin_object(j, NULL);
    cbm_json_int(j, "byteLength", (int64_t)cbm__glb_pad4(bin_len));
    cbm_json_end_object(j);
    cbm_json_end_array(j);
}

static void le32(uint8_t *b, uint32_t v)
{
    b[0] = (uint8_t)v;
    b[1] = (uint8_t)(v >> 8);
    b[2] = (uint8_t)(v >> 16);
    b[3] = (uint8_t)(v >> 24);
}

cbm_status cbm__glb_open(cbm_context *ctx, const char *path, const char *what, const char *text,
                         size_t tlen, size_t bin_len, bool bin_chunk, cbm_out **out)
{
    size_t jpad = cbm__glb_pad4(tlen), bpad = cbm__glb_pad4(bin_len);
    size_t total = 12 + 8 + jpad + (bin_chunk ? 8 + bpad : 0);
    *out = NULL;
    if (total > UINT32_MAX)
        return cbm__fail(ctx, CBM_E_LIMIT, "%s: %s too large for a .glb (%zu bytes > 4 GiB)", path,
                         what, total);
    CBM_TRY(cbm_out_open(ctx, path, out));
    uint8_t h[12];
    /* the 4-byte magic, not a string */
    // NOLINTNEXTLINE(bugprone-not-null-terminated-result)
    memcpy(h, "glTF", 4);
    le32(h + 4, 2);
    le32(h + 8, (uint32_t)total);
    cbm_out_write(*out, h, 12);
    le32(h, (uint32_t)jpad);
    /* a 4-byte chunk type, not a string */
    // NOLINTNEXTLINE(bugprone-not-null-terminated-result)
    memcpy(h + 4, "JSON", 4);
    cbm_out_write(*out, h, 8);
    cbm_out_write(*out, text, tlen);
    cbm_out_write(*out, "   ", jpad - tlen);
    if (bin_chunk) {
        le32(h, (uint32_t)bpad);
        /* a 4-byte chunk type, not a string */
        // NOLINTNEXTLINE(bugprone-not-null-terminated-result)
        memcpy(h + 4, "BIN\0", 4);
        cbm_out_write(*out, h, 8);
    }
    return CBM_OK;
}

void cbm__glb_bin_tail(cbm_out *out, size_t bin_len)
{
    const uint8_t zero[4] = {0, 0, 0, 0};
    cbm_out_write(out, zero, cbm__glb_pad4(bin_len) - bin_len);
}
