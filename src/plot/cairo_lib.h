/* cairo, loaded when a plot or a picture's text is first drawn (src/core/dynlib.h): a run that
 * draws no letter does not map cairo and the libraries it brings (fontconfig, FreeType, pixman,
 * the X client libraries). Its functions are called through cbm__cairo, whose fields have
 * cairo's own names and types: cbm__cairo.cairo_move_to(cr, x, y). Used by src/plot and, for the
 * PNG legend's text, src/io. */
#ifndef CBM_PLOT_CAIRO_LIB_H
#define CBM_PLOT_CAIRO_LIB_H

#include "../core/core.h"

#include <cairo.h>

/* The cairo functions cambium calls. */
#define CBM__CAIRO_FUNCTIONS(X)                                                                    \
    X(cairo_arc)                                                                                   \
    X(cairo_clip)                                                                                  \
    X(cairo_close_path)                                                                            \
    X(cairo_create)                                                                                \
    X(cairo_destroy)                                                                               \
    X(cairo_fill)                                                                                  \
    X(cairo_fill_preserve)                                                                         \
    X(cairo_font_options_create)                                                                   \
    X(cairo_font_options_destroy)                                                                  \
    X(cairo_font_options_set_antialias)                                                            \
    X(cairo_font_options_set_hint_metrics)                                                         \
    X(cairo_font_options_set_hint_style)                                                           \
    X(cairo_font_options_set_subpixel_order)                                                       \
    X(cairo_image_surface_create)                                                                  \
    X(cairo_image_surface_get_data)                                                                \
    X(cairo_image_surface_get_stride)                                                              \
    X(cairo_line_to)                                                                               \
    X(cairo_move_to)                                                                               \
    X(cairo_new_path)                                                                              \
    X(cairo_new_sub_path)                                                                          \
    X(cairo_paint)                                                                                 \
    X(cairo_rectangle)                                                                             \
    X(cairo_restore)                                                                               \
    X(cairo_rotate)                                                                                \
    X(cairo_save)                                                                                  \
    X(cairo_select_font_face)                                                                      \
    X(cairo_set_antialias)                                                                         \
    X(cairo_set_dash)                                                                              \
    X(cairo_set_font_options)                                                                      \
    X(cairo_set_font_size)                                                                         \
    X(cairo_set_line_cap)                                                                          \
    X(cairo_set_line_join)                                                                         \
    X(cairo_set_line_width)                                                                        \
    X(cairo_set_source_rgb)                                                                        \
    X(cairo_set_source_rgba)                                                                       \
    X(cairo_show_text)                                                                             \
    X(cairo_status)                                                                                \
    X(cairo_status_to_string)                                                                      \
    X(cairo_stroke)                                                                                \
    X(cairo_surface_destroy)                                                                       \
    X(cairo_surface_flush)                                                                         \
    X(cairo_text_extents)                                                                          \
    X(cairo_translate)

/// Pointers to cairo's functions, filled by the first successful cbm__cairo_load.
typedef struct cbm__cairo_api {
    /* f names the field: a declarator, not an expression to parenthesize */
    // NOLINTNEXTLINE(bugprone-macro-parentheses)
#define CBM__CAIRO_FIELD(f) __typeof__(f) *f;
    CBM__CAIRO_FUNCTIONS(CBM__CAIRO_FIELD)
#undef CBM__CAIRO_FIELD
} cbm__cairo_api;

/// cairo's functions: valid once cbm__cairo_load has returned CBM_OK.
extern cbm__cairo_api cbm__cairo;

/// Loads cairo on the first call; CBM_E_UNSUPPORTED, with a message naming the library and its
/// package after `who` on ctx (NULL: the status alone), when it cannot. Thread-safe.
cbm_status cbm__cairo_load(cbm_context *ctx, const char *who);

#endif
