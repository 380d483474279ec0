/* The glTF 2.0 binary container (.glb) and the buffer bookkeeping shared by the io layer's two
 * glTF writers: gltf.c (scenes and growth animations) and gltf_frames.c (the motion of drawn
 * parts). Each writer keeps its own way of filling BIN (gltf.c measures, then streams; the motion
 * writer keeps it in memory); the accessors, the buffer views, their JSON and the GLB framing are
 * written here once (Khronos glTF 2.0 specification, sections 3.6-3.7 and 4.4). */
#ifndef CBM_IO_GLB_INTERNAL_H
#define CBM_IO_GLB_INTERNAL_H

#include "cambium/io.h"
#include "cambium/write.h"

#include "../core/core.h"

/// An accessor of the JSON: `count` elements of `ncomp` components of GL type `ctype` in a view;
/// with minmax, the per-component bounds (POSITION and animation inputs need them).
typedef struct cbm__gltf_accessor {
    size_t view, count;
    int ctype, ncomp;
    bool minmax;
    float min[4], max[4];
} cbm__gltf_accessor;

/// A buffer view: a byte range of BIN, and its target (0 for none).
typedef struct cbm__gltf_view {
    size_t offset, length;
    int target;
} cbm__gltf_view;

/// n rounded up to a multiple of 4 (every view and chunk starts 4-aligned).
static inline size_t cbm__glb_pad4(size_t n)
{
    return (n + 3) & ~(size_t)3;
}

/// Fills *a for `count` elements of `data` in `view`; with minmax, data holds floats and their
/// per-component bounds are taken.
void cbm__gltf_accessor_set(cbm__gltf_accessor *a, size_t view, const void *data, size_t count,
                            int ncomp, int ctype, bool minmax);

/// An array of n floats under `key` (NULL inside an array).
void cbm__gltf_json_floats(cbm_json *j, const char *key, const float *f, int n);

/// The "accessors", "bufferViews" and "buffers" (one, of bin_len bytes padded to 4) members.
void cbm__gltf_json_buffers(cbm_json *j, const cbm__gltf_accessor *acc, size_t nacc,
                            const cbm__gltf_view *views, size_t nview, size_t bin_len);

/// Opens `path` and writes the GLB header, the JSON chunk (text padded with spaces) and, if
/// bin_chunk, the header of a BIN chunk of bin_len bytes; the caller writes the BIN bytes, then
/// cbm__glb_bin_tail, then commits. `what` names the content in the size error ("scene").
cbm_status cbm__glb_open(cbm_context *ctx, const char *path, const char *what, const char *text,
                         size_t tlen, size_t bin_len, bool bin_chunk, cbm_out **out);

/// The zeros that pad a BIN of bin_len bytes to a multiple of 4.
void cbm__glb_bin_tail(cbm_out *out, size_t bin_len);

#endif
