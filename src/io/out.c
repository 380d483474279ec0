/* Atomic output files: write to "<dir>/.<name>.tmpXXXXXX", then fflush + fsync + rename onto
 * the target. rename(2) within one directory is atomic on POSIX file systems, so a reader sees
 * either the old file or the complete new one, and an error at any point removes the temporary
 * file. */
#define _POSIX_C_SOURCE 200809L
#include "cambium/io.h"

#include "../core/core.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

struct cbm_out {
    cbm_context *ctx;
    FILE *f;
    char *path;
    char *tmp;
    int err; /* first errno seen, 0 if none */
};

static void release(cbm_out *o)
{
    cbm__strfree(o->ctx, o->path);
    cbm__strfree(o->ctx, o->tmp);
    cbm__free(o->ctx, o, sizeof *o);
}

cbm_status cbm_out_open(cbm_context *ctx, const char *path, cbm_out **out)
{
    if (!ctx || !path || !out || !*path)
        return CBM_E_INVALID;
    *out = NULL;
    cbm_out *o = cbm__calloc(ctx, 1, sizeof *o);
    if (!o)
        return CBM_E_NOMEM;
    o->ctx = ctx;
    o->path = cbm__strdup(ctx, path);
    const char *slash = strrchr(path, '/');
    size_t dirlen = slash ? (size_t)(slash - path) + 1 : 0;
    const char *base = path + dirlen;
    size_t n = dirlen + strlen(base) + 16;
    char *tmp = cbm__alloc(ctx, n);
    if (!o->path || !tmp) {
        cbm__free(ctx, tmp, n);
        release(o);
        return CBM_E_NOMEM;
    }
    snprintf(tmp, n, "%.*s.%s.tmpXXXXXX", (int)dirlen, path, base);
    int fd = mkstemp(tmp);
    if (fd < 0) {
        int e = errno;
        cbm__free(ctx, tmp, n);
        release(o);
        return cbm__fail(ctx, CBM_E_IO, "%s: cannot create output file: %s", path, strerror(e));
    }
    o->tmp = cbm__strdup(ctx, tmp);
    cbm__free(ctx, tmp, n);
    o->f = o->tmp ? fdopen(fd, "wb") : NULL;
    if (!o->f) {
        if (o->tmp)
            unlink(o->tmp);
        else
            close(fd);
        release(o);
        return CBM_E_NOMEM;
    }
    *out = o;
    return CBM_OK;
}

cbm_status cbm_out_write(cbm_out *o, const void *data, size_t size)
{
    if (o->err)
        return CBM_E_IO;
    if (size && fwrite(data, 1, size, o->f) != size) {
        o->err = errno ? errno : EIO;
        return CBM_E_IO;
    }
    return CBM_OK;
}

cbm_status cbm_out_printf(cbm_out *o, const char *fmt, ...)
{
    if (o->err)
        return CBM_E_IO;
    va_list ap;
    va_start(ap, fmt);
    int r = vfprintf(o->f, fmt, ap);
    va_end(ap);
    if (r < 0) {
        o->err = errno ? errno : EIO;
        return CBM_E_IO;
    }
    return CBM_OK;
}

FILE *cbm_out_stream(cbm_out *o)
{
    return o->f;
}

const char *cbm_out_path(const cbm_out *o)
{
    return o->path;
}

cbm_status cbm_out_commit(cbm_out *o)
{
    if (!o)
        return CBM_E_INVALID;
    cbm_context *ctx = o->ctx;
    int e = o->err;
    if (!e && (fflush(o->f) != 0 || ferror(o->f)))
        e = errno ? errno : EIO;
    if (!e && fsync(fileno(o->f)) != 0 && errno != EINVAL)
        e = errno;
    if (fclose(o->f) != 0 && !e)
        e = errno ? errno : EIO;
    if (!e && rename(o->tmp, o->path) != 0)
        e = errno;
    if (e) {
        unlink(o->tmp);
        cbm_status s =
            cbm__fail(ctx, CBM_E_IO, "%s: cannot write output file: %s", o->path, strerror(e));
        release(o);
        return s;
    }
    release(o);
    return CBM_OK;
}

void cbm_out_abort(cbm_out *o)
{
    if (!o)
        return;
    fclose(o->f);
    unlink(o->tmp);
    release(o);
}
