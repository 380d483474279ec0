/* cambium: output files written safely.
 *
 * Every file the library or the tool writes goes through cbm_out: the bytes go to a temporary
 * file beside the target, and only cbm_out_commit renames it into place. A failed write, a full
 * disk or an abort leaves no partial file behind, and the error names the path.
 */
#ifndef CAMBIUM_IO_H
#define CAMBIUM_IO_H

#include "cambium/base.h"

#include <stdio.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef struct cbm_out cbm_out;

/// Opens a temporary file in the target's directory. The target is not touched until commit
/// (a device or FIFO target is written in place, never replaced).
CBM_API cbm_status cbm_out_open(cbm_context *ctx, const char *path, cbm_out **out);
/// Appends bytes. Errors are sticky: later calls do nothing and commit reports the first one.
CBM_API cbm_status cbm_out_write(cbm_out *o, const void *data, size_t size);
CBM_API cbm_status cbm_out_printf(cbm_out *o, const char *fmt, ...) CBM_PRINTF(2, 3);
/// The underlying stream, for writers that use stdio directly (errors are caught at commit).
CBM_API FILE *cbm_out_stream(cbm_out *o);
/// Flushes, closes and renames into place; always releases o. CBM_E_IO on any error, with a
/// message naming the path, and then nothing is left behind.
CBM_API cbm_status cbm_out_commit(cbm_out *o);
/// Discards the temporary file; releases o. NULL is allowed.
CBM_API void cbm_out_abort(cbm_out *o);
/// Removes the temporary files of the outputs being written (async-signal-safe: for a
/// SIGINT/SIGTERM handler, so a killed run leaves no hidden temporary file behind).
CBM_API void cbm_out_remove_temporaries(void);
/// Whether `path` can be written as an output (its folder exists and is writable; an existing
/// file is writable and no dangling link): CBM_OK, else CBM_E_IO with a message. Lets a tool
/// refuse a bad output before a long computation.
CBM_API cbm_status cbm_out_check(cbm_context *ctx, const char *path);
/// The final path this output will have.
CBM_API const char *cbm_out_path(const cbm_out *o);

#ifdef __cplusplus
}
#endif
#endif
