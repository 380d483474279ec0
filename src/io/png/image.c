/* Pictures in memory and PNG files: encoding and decoding through libpng's simplified API
 * (png_image, libpng 1.6), 8-bit sRGB RGBA. The encoded bytes are produced in memory, then
 * written through cbm_out, so a failed write leaves no partial file. */
#include "../writers.h"

#include "cambium/io.h"

#include <png.h>

static cbm_status image_new(cbm_context *ctx, int w, int h, cbm_image **out)
{
    if (w <= 0 || h <= 0 || w > 32768 || h > 32768)
        return cbm__fail(ctx, CBM_E_INVALID, "picture size %d x %d out of range 1..32768", w, h);
    cbm_image *img = cbm__calloc(ctx, 1, sizeof *img);
    if (!img)
        return CBM_E_NOMEM;
    img->ctx = ctx;
    img->width = w;
    img->height = h;
    img->rgba = cbm__calloc(ctx, (size_t)w * (size_t)h, 4);
    if (!img->rgba) {
        cbm__free(ctx, img, sizeof *img);
        return CBM_E_NOMEM;
    }
    *out = img;
    return CBM_OK;
}

cbm_status cbm__image_create(cbm_context *ctx, int w, int h, cbm_image **out)
{
    return image_new(ctx, w, h, out);
}

cbm_status cbm_image_create(cbm_context *ctx, int w, int h, cbm_image **out)
{
    if (!ctx || !out)
        return CBM_E_INVALID;
    *out = NULL;
    return image_new(ctx, w, h, out);
}

void cbm_image_destroy(cbm_image *img)
{
    if (!img)
        return;
    cbm__free(img->ctx, img->rgba, (size_t)img->width * (size_t)img->height * 4);
    cbm__free(img->ctx, img, sizeof *img);
}

cbm_status cbm_image_write_png(cbm_context *ctx, const cbm_image *img, const char *path)
{
    if (!ctx || !img || !path)
        return CBM_E_INVALID;
    png_image pi;
    memset(&pi, 0, sizeof pi);
    pi.version = PNG_IMAGE_VERSION;
    pi.width = (png_uint_32)img->width;
    pi.height = (png_uint_32)img->height;
    pi.format = PNG_FORMAT_RGBA;
    png_alloc_size_t size = 0;
    if (!png_image_write_to_memory(&pi, NULL, &size, 0, img->rgba, 0, NULL))
        return cbm__fail(ctx, CBM_E_INTERNAL, "%s: PNG encoder: %s", path, pi.message);
    void *mem = cbm__alloc(ctx, size);
    if (!mem)
        return CBM_E_NOMEM;
    png_alloc_size_t cap = size;
    cbm_status st = CBM_OK;
    if (!png_image_write_to_memory(&pi, mem, &size, 0, img->rgba, 0, NULL)) {
        st = cbm__fail(ctx, CBM_E_INTERNAL, "%s: PNG encoder: %s", path, pi.message);
    } else {
        cbm_out *o;
        st = cbm_out_open(ctx, path, &o);
        if (st == CBM_OK) {
            cbm_out_write(o, mem, size);
            st = cbm_out_commit(o);
        }
    }
    cbm__free(ctx, mem, cap);
    return st;
}

cbm_status cbm_image_read_png(cbm_context *ctx, const char *path, cbm_image **out)
{
    if (!ctx || !path || !out)
        return CBM_E_INVALID;
    *out = NULL;
    png_image pi;
    memset(&pi, 0, sizeof pi);
    pi.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&pi, path))
        return cbm__fail(ctx, CBM_E_IO, "%s: cannot read PNG: %s", path, pi.message);
    pi.format = PNG_FORMAT_RGBA;
    cbm_image *img;
    cbm_status st = image_new(ctx, (int)pi.width, (int)pi.height, &img);
    if (st != CBM_OK) {
        png_image_free(&pi);
        return st;
    }
    /* image_new returned CBM_OK, so img is set */
    // NOLINTNEXTLINE(clang-analyzer-core.NullDereference)
    if (!png_image_finish_read(&pi, NULL, img->rgba, 0, NULL)) {
        cbm_image_destroy(img);
        return cbm__fail(ctx, CBM_E_FORMAT, "%s: bad PNG: %s", path, pi.message);
    }
    *out = img;
    return CBM_OK;
}
