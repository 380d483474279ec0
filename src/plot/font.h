/* The font of every picture's text (plots and the legends of the PNG renderer): DejaVu Sans
 * through cairo, with fixed rendering options so the pixels do not depend on desktop settings.
 * Used by src/plot and src/io. */
#ifndef CBM_PLOT_FONT_H
#define CBM_PLOT_FONT_H

#include "cambium/write.h"

#include "cairo_lib.h"

/// The family asked of fontconfig (Debian package fonts-dejavu-core).
#define CBM_FONT_FAMILY "DejaVu Sans"

/// Sets the font at `size` pixels and the rendering options on a cairo context.
void cbm__font_use(cairo_t *cr, double size);
/// Advance width of text at `size` pixels (text as cbm__font_clean leaves it).
double cbm__font_width(cairo_t *cr, const char *text, double size);
/// Height of the capitals at `size` pixels (of 'H').
double cbm__font_cap_height(cairo_t *cr, double size);
/// Copies text into out (at most size bytes with the NUL) as valid UTF-8 without control
/// characters: bytes of broken sequences and controls become '?'. Never splits a character.
void cbm__font_clean(const char *text, char *out, size_t size);
/// A context on a 1 x 1 surface for measuring; NULL when out of memory or when cairo cannot be
/// loaded (cbm__cairo_load first, for the message). cbm__cairo.cairo_destroy it.
cairo_t *cbm__font_measurer(void);

/// Horizontal anchor of text drawn on a picture.
typedef enum cbm__text_align { CBM__TEXT_LEFT, CBM__TEXT_CENTER, CBM__TEXT_RIGHT } cbm__text_align;

/// Draws text on a picture (8-bit sRGB RGBA) with its baseline at y and anchored at x, blending
/// the ink by coverage (anti-aliased); parts outside the picture are clipped. CBM_E_UNSUPPORTED
/// when cairo cannot be loaded (cbm__cairo_load first, for the message).
cbm_status cbm__font_draw(cbm_image *img, double x, double y, double size, cbm__text_align align,
                          const char *text, const uint8_t rgb[3]);

#endif
