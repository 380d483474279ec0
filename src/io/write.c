/* Dispatch of a scene to its writer by format name or by the file's extension. Pixel lines (cpfg's
 * untessellated lines) are drawn only by the picture writers, so the mesh formats refuse a scene
 * that holds any. */
#include "writers.h"

#include <string.h>

static bool same_ci(const char *a, const char *b)
{
    for (; *a && *b; a++, b++) {
        char c = *a >= 'A' && *a <= 'Z' ? (char)(*a - 'A' + 'a') : *a;
        if (c != *b)
            return false;
    }
    return *a == *b;
}

cbm_status cbm_scene_write_as(cbm_context *ctx, const cbm_scene *scene, const char *path,
                              const char *format, const cbm_write_options *opts)
{
    if (!ctx || !path || !format)
        return CBM_E_INVALID;
    cbm_write_options def = cbm_write_options_default();
    if (!opts)
        opts = &def;
    bool picture = same_ci(format, "png") || same_ci(format, "svg");
    if (scene && !picture && cbm_scene_line_count(scene) > 0)
        return cbm__fail(ctx, CBM_E_UNSUPPORTED,
                         "%s: the scene holds %zu pixel lines, which only pictures (.png .svg) "
                         "draw; interpret the model with line mode off for a mesh",
                         path, cbm_scene_line_count(scene));
    if (scene && !same_ci(format, "glb") && cbm_scene_instance_count(scene) > 0)
        return cbm__fail(ctx, CBM_E_UNSUPPORTED,
                         "%s: the scene holds %zu tube instances, which only .glb writes; "
                         "interpret the model with instancing off",
                         path, cbm_scene_instance_count(scene));
    if (scene && !same_ci(format, "glb") && cbm_scene_placement_count(scene) > 0)
        return cbm__fail(ctx, CBM_E_UNSUPPORTED,
                         "%s: the scene holds %zu placed surfaces, which only .glb writes; "
                         "interpret the model with instancing off",
                         path, cbm_scene_placement_count(scene));
    if (same_ci(format, "glb"))
        return cbm_write_glb(ctx, scene, path, opts);
    if (!scene && opts->frame_count > 0 && opts->frames)
        scene = opts->frames[opts->frame_count - 1];
    if (!scene)
        return cbm__fail(ctx, CBM_E_INVALID, "%s: no scene to write", path);
    if (same_ci(format, "obj"))
        return cbm_write_obj(ctx, scene, path, opts);
    if (same_ci(format, "ply"))
        return cbm_write_ply(ctx, scene, path, opts);
    if (same_ci(format, "png"))
        return cbm_write_png(ctx, scene, path, opts);
    if (same_ci(format, "svg"))
        return cbm_write_svg(ctx, scene, path, opts);
    if (same_ci(format, "csv"))
        return cbm_write_parts_csv(ctx, scene, path, opts);
    return cbm__fail(ctx, CBM_E_UNSUPPORTED,
                     "%s: unknown output format '%s' (expected obj ply glb png svg csv)", path,
                     format);
}

cbm_status cbm_scene_write(cbm_context *ctx, const cbm_scene *scene, const char *path,
                           const cbm_write_options *opts)
{
    if (!ctx || !path)
        return CBM_E_INVALID;
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash))
        return cbm__fail(ctx, CBM_E_UNSUPPORTED,
                         "%s: no extension to name the format (.obj .ply .glb .png .svg .csv)",
                         path);
    return cbm_scene_write_as(ctx, scene, path, dot + 1, opts);
}
