/* The font of pictures: DejaVu Sans (fonts-dejavu-core) found by fontconfig through cairo's
 * font selection, drawn with grey anti-aliasing, no hinting and unhinted metrics. Fixing these
 * options (rather than taking the desktop's) keeps the same input giving the same pixels, and
 * unhinted metrics make text widths proportional to the size, so the PNG and SVG layouts agree.
 * Text drawn on a finished picture is rendered as a coverage mask (cairo A8 surface the size of
 * the text's box) and blended into the 8-bit sRGB pixels. */
#include "font.h"

#include "../core/core.h"

#include <math.h>
#include <string.h>

void cbm__font_use(cairo_t *cr, double size)
{
    cbm__cairo.cairo_select_font_face(cr, CBM_FONT_FAMILY, CAIRO_FONT_SLANT_NORMAL,
                                      CAIRO_FONT_WEIGHT_NORMAL);
    cbm__cairo.cairo_set_font_size(cr, size);
    cairo_font_options_t *fo = cbm__cairo.cairo_font_options_create();
    cbm__cairo.cairo_font_options_set_antialias(fo, CAIRO_ANTIALIAS_GRAY);
    cbm__cairo.cairo_font_options_set_hint_style(fo, CAIRO_HINT_STYLE_NONE);
    cbm__cairo.cairo_font_options_set_hint_metrics(fo, CAIRO_HINT_METRICS_OFF);
    cbm__cairo.cairo_font_options_set_subpixel_order(fo, CAIRO_SUBPIXEL_ORDER_DEFAULT);
    cbm__cairo.cairo_set_font_options(cr, fo);
    cbm__cairo.cairo_font_options_destroy(fo);
}

double cbm__font_width(cairo_t *cr, const char *text, double size)
{
    if (!text || !*text)
        return 0.0;
    cbm__font_use(cr, size);
    cairo_text_extents_t e;
    cbm__cairo.cairo_text_extents(cr, text, &e);
    return e.x_advance;
}

double cbm__font_cap_height(cairo_t *cr, double size)
{
    cbm__font_use(cr, size);
    cairo_text_extents_t e;
    cbm__cairo.cairo_text_extents(cr, "H", &e);
    return -e.y_bearing;
}

cairo_t *cbm__font_measurer(void)
{
    if (cbm__cairo_load(NULL, "font") != CBM_OK)
        return NULL;
    cairo_surface_t *s = cbm__cairo.cairo_image_surface_create(CAIRO_FORMAT_A8, 1, 1);
    cairo_t *cr = cbm__cairo.cairo_create(s);
    cbm__cairo.cairo_surface_destroy(s);
    if (cbm__cairo.cairo_status(cr) != CAIRO_STATUS_SUCCESS) {
        cbm__cairo.cairo_destroy(cr);
        return NULL;
    }
    return cr;
}

/* Length of the valid UTF-8 character at s (1..4), 0 if the bytes there do not form one
 * (overlong forms, surrogates and values past U+10FFFF are refused). */
static size_t utf8_char(const unsigned char *s)
{
    unsigned c = s[0];
    if (c < 0x80)
        return 1;
    size_t n = c >= 0xF0 ? 4 : c >= 0xE0 ? 3 : c >= 0xC2 ? 2 : 0;
    if (n == 0 || c > 0xF4)
        return 0;
    unsigned v = c & (0x3F >> (n - 1));
    for (size_t k = 1; k < n; k++) {
        if ((s[k] & 0xC0) != 0x80)
            return 0;
        v = (v << 6) | (s[k] & 0x3F);
    }
    static const unsigned least[5] = {0, 0, 0x80, 0x800, 0x10000};
    if (v < least[n] || v > 0x10FFFF || (v >= 0xD800 && v <= 0xDFFF))
        return 0;
    return n;
}

void cbm__font_clean(const char *text, char *out, size_t size)
{
    if (!out || size == 0)
        return;
    size_t k = 0;
    const unsigned char *s = (const unsigned char *)(text ? text : "");
    while (*s) {
        size_t n = utf8_char(s);
        if (n == 0 || (n == 1 && (*s < 0x20 || *s == 0x7F))) {
            if (k + 1 >= size)
                break;
            out[k++] = '?';
            s++;
            continue;
        }
        if (k + n >= size)
            break;
        memcpy(out + k, s, n);
        k += n;
        s += n;
    }
    out[k] = '\0';
}

cbm_status cbm__font_draw(cbm_image *img, double x, double y, double size, cbm__text_align align,
                          const char *text, const uint8_t rgb[3])
{
    if (!img || !text || !*text || !(size > 0))
        return CBM_OK;
    CBM_TRY(cbm__cairo_load(NULL, "font"));
    char clean[512];
    cbm__font_clean(text, clean, sizeof clean);
    cairo_t *m = cbm__font_measurer();
    if (!m)
        return CBM_E_NOMEM;
    cbm__font_use(m, size);
    cairo_text_extents_t e;
    cbm__cairo.cairo_text_extents(m, clean, &e);
    cbm__cairo.cairo_destroy(m);
    double x0 = align == CBM__TEXT_CENTER  ? x - 0.5 * e.x_advance
                : align == CBM__TEXT_RIGHT ? x - e.x_advance
                                           : x;
    /* the mask covers the ink box with a pixel to spare, on the pixel grid */
    int bx = (int)floor(x0 + e.x_bearing) - 1, by = (int)floor(y + e.y_bearing) - 1;
    int bw = (int)ceil(e.width) + 3, bh = (int)ceil(e.height) + 3;
    if (bw <= 0 || bh <= 0 || bx >= img->width || by >= img->height || bx + bw <= 0 || by + bh <= 0)
        return CBM_OK;
    cairo_surface_t *s = cbm__cairo.cairo_image_surface_create(CAIRO_FORMAT_A8, bw, bh);
    cairo_t *cr = cbm__cairo.cairo_create(s);
    cbm__font_use(cr, size);
    cbm__cairo.cairo_move_to(cr, x0 - bx, y - by);
    cbm__cairo.cairo_show_text(cr, clean);
    cbm__cairo.cairo_surface_flush(s);
    cbm_status st = cbm__cairo.cairo_status(cr) == CAIRO_STATUS_SUCCESS ? CBM_OK : CBM_E_NOMEM;
    const unsigned char *mask = cbm__cairo.cairo_image_surface_get_data(s);
    int stride = cbm__cairo.cairo_image_surface_get_stride(s);
    for (int j = 0; st == CBM_OK && mask && j < bh; j++) {
        int Y = by + j;
        if (Y < 0 || Y >= img->height)
            continue;
        for (int i = 0; i < bw; i++) {
            int X = bx + i;
            unsigned a = mask[(size_t)j * (size_t)stride + (size_t)i];
            if (X < 0 || X >= img->width || a == 0)
                continue;
            uint8_t *q = img->rgba + 4 * ((size_t)Y * (size_t)img->width + (size_t)X);
            /* ink over the pixel: coverage c, the pixel's own alpha behind it */
            double c = a / 255.0, under = q[3] / 255.0 * (1.0 - c), out = c + under;
            for (int k = 0; k < 3; k++)
                q[k] = (uint8_t)lround((rgb[k] * c + q[k] * under) / out);
            q[3] = (uint8_t)lround(out * 255.0);
        }
    }
    cbm__cairo.cairo_destroy(cr);
    cbm__cairo.cairo_surface_destroy(s);
    return st;
}
