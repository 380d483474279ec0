/* Atomic output files: write to "<dir>/.<name>.tmpXXXXXX", then fflush + rename onto the
 * target. rename(2) within one directory is atomic on POSIX file systems, so a reader sees
 * either the old file or the complete new one, and an error at any point removes the temporary
 * file. That is the promise against a crash or a kill of cambium. fsync before the rename adds
 * durability against a crash of the machine (power loss), which the peers and most tools do not
 * give by default and which made a small run's wall time the disk's under load: it is done only
 * on request, CBM_FSYNC set to a value other than "" and "0" (docs/design.md, Output). A target
 * that exists and is neither a regular file nor a directory (a device such as /dev/null or
 * /dev/full, a FIFO) is written in place instead, so it is never replaced; write errors on it
 * (ENOSPC from /dev/full) are still reported. */
#define _XOPEN_SOURCE 700
#include "cambium/io.h"

#include "../core/core.h"

#include <errno.h>
#include <limits.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

struct cbm_out {
    cbm_context *ctx;
    FILE *f;
    char *path;
    char *tmp;
    char *target; /* rename destination when path is a link to a regular file, else NULL */
    int err;      /* first errno seen, 0 if none */
    int slot;     /* in tmp_names, -1: none */
};

/* The temporary files being written, for cbm_out_remove_temporaries (a signal handler): fixed
 * slots, claimed and released with sig_atomic_t flags so the handler never reads a half-written
 * name. A name too long or a run with more files open than slots is simply not registered. */
#define TMP_SLOTS 32
static char tmp_names[TMP_SLOTS][512];
static volatile sig_atomic_t tmp_used[TMP_SLOTS];

static int tmp_register(const char *name)
{
    if (strlen(name) >= sizeof tmp_names[0])
        return -1;
    for (int i = 0; i < TMP_SLOTS; i++)
        if (!tmp_used[i]) {
            memcpy(tmp_names[i], name, strlen(name) + 1);
            tmp_used[i] = 1;
            return i;
        }
    return -1;
}

static void tmp_unregister(int slot)
{
    if (slot >= 0)
        tmp_used[slot] = 0;
}

void cbm_out_remove_temporaries(void)
{
    for (int i = 0; i < TMP_SLOTS; i++)
        if (tmp_used[i])
            unlink(tmp_names[i]);
}

static void release(cbm_out *o)
{
    tmp_unregister(o->slot);
    cbm__strfree(o->ctx, o->path);
    cbm__strfree(o->ctx, o->tmp);
    cbm__strfree(o->ctx, o->target);
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
    o->slot = -1;
    o->path = cbm__strdup(ctx, path);
    /* Write in place, never replace: the standard streams (/dev/stdout, /dev/fd/N,
     * /proc/self/fd/N: the user means the stream), and targets that are neither regular files
     * nor directories (devices such as /dev/null or /dev/full, FIFOs): renaming a temporary file
     * onto them would replace the device node or the link itself. */
    struct stat sb;
    bool stream = !strncmp(path, "/dev/std", 8) || !strncmp(path, "/dev/fd/", 8) ||
                  !strncmp(path, "/proc/self/fd/", 14);
    if (o->path &&
        (stream || (stat(path, &sb) == 0 && !S_ISREG(sb.st_mode) && !S_ISDIR(sb.st_mode)))) {
        o->f = fopen(path, "wb");
        if (!o->f) {
            int e = errno;
            release(o);
            return cbm__fail(ctx, CBM_E_IO, "%s: cannot open for writing: %s", path, strerror(e));
        }
        *out = o;
        return CBM_OK;
    }
    /* A symbolic link to a regular file: replace the file it points to, keep the link. A
     * dangling link is refused (replacing it by a file would lose the link silently). */
    if (o->path && lstat(path, &sb) == 0 && S_ISLNK(sb.st_mode)) {
        char *real = realpath(path, NULL); /* malloc'd by the C library */
        if (!real) {
            release(o);
            return cbm__fail(ctx, CBM_E_IO,
                             "%s: a symbolic link to nothing (dangling); not replaced", path);
        }
        o->target = cbm__strdup(ctx, real);
        free(real);
        if (!o->target) {
            release(o);
            return CBM_E_NOMEM;
        }
        path = o->target;
    }
    /* An existing file keeps its permissions; a read-only one is not replaced (rename could,
     * as the folder is writable, but the user protected the file). */
    bool exists = o->path && stat(path, &sb) == 0 && S_ISREG(sb.st_mode);
    if (exists && ((sb.st_mode & 0222) == 0 || access(path, W_OK) != 0)) {
        release(o);
        return cbm__fail(ctx, CBM_E_IO, "%s: the file is read-only; not replaced", o->path);
    }
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
    /* hidden and named after the target: recognisable if a crash ever leaves one behind */
    snprintf(tmp, n, "%.*s.%s.tmpXXXXXX", (int)dirlen, path, base);
    int fd = mkstemp(tmp);
    if (fd < 0) {
        int e = errno;
        cbm__free(ctx, tmp, n);
        release(o);
        return cbm__fail(ctx, CBM_E_IO, "%s: cannot create output file: %s", path, strerror(e));
    }
    o->slot = tmp_register(tmp);
    /* mkstemp creates mode 0600: give the file the permissions of the file it replaces, or the
     * usual ones (0666 less the umask) */
    if (exists) {
        (void)fchmod(fd, sb.st_mode & 07777);
    } else {
        mode_t mask = umask(0);
        umask(mask);
        (void)fchmod(fd, 0666 & ~mask);
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

/* Whether outputs are synced to the disk before their rename (CBM_FSYNC). */
static bool durable(void)
{
    const char *e = getenv("CBM_FSYNC");
    return e && *e && strcmp(e, "0") != 0;
}

cbm_status cbm_out_commit(cbm_out *o)
{
    if (!o)
        return CBM_E_INVALID;
    cbm_context *ctx = o->ctx;
    int e = o->err;
    if (!e && (fflush(o->f) != 0 || ferror(o->f)))
        e = errno ? errno : EIO;
    if (!e && durable() && fsync(fileno(o->f)) != 0 && errno != EINVAL)
        e = errno;
    if (fclose(o->f) != 0 && !e)
        e = errno ? errno : EIO;
    if (!e && o->tmp && rename(o->tmp, o->target ? o->target : o->path) != 0)
        e = errno;
    if (e) {
        if (o->tmp)
            unlink(o->tmp);
        cbm_status s =
            cbm__fail(ctx, CBM_E_IO, "%s: cannot write output file: %s", o->path, strerror(e));
        release(o);
        return s;
    }
    release(o);
    return CBM_OK;
}

cbm_status cbm_out_check(cbm_context *ctx, const char *path)
{
    if (!ctx || !path || !*path)
        return CBM_E_INVALID;
    if (!strncmp(path, "/dev/", 5) || !strncmp(path, "/proc/self/fd/", 14))
        return CBM_OK; /* streams and devices are opened when written */
    struct stat sb;
    if (lstat(path, &sb) == 0 && S_ISLNK(sb.st_mode) && stat(path, &sb) != 0)
        return cbm__fail(ctx, CBM_E_IO, "%s: a symbolic link to nothing (dangling)", path);
    if (stat(path, &sb) == 0) {
        if (S_ISDIR(sb.st_mode))
            return cbm__fail(ctx, CBM_E_IO, "%s: is a folder", path);
        if (S_ISREG(sb.st_mode) && ((sb.st_mode & 0222) == 0 || access(path, W_OK) != 0))
            return cbm__fail(ctx, CBM_E_IO, "%s: the file is read-only", path);
    }
    const char *slash = strrchr(path, '/');
    char dir[PATH_MAX];
    if (!slash)
        snprintf(dir, sizeof dir, ".");
    else if (slash == path)
        snprintf(dir, sizeof dir, "/");
    else
        snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    if (stat(dir, &sb) != 0 || !S_ISDIR(sb.st_mode))
        return cbm__fail(ctx, CBM_E_IO, "%s: the folder %s does not exist", path, dir);
    if (access(dir, W_OK | X_OK) != 0)
        return cbm__fail(ctx, CBM_E_IO, "%s: the folder %s is not writable", path, dir);
    return CBM_OK;
}

void cbm_out_abort(cbm_out *o)
{
    if (!o)
        return;
    fclose(o->f);
    if (o->tmp)
        unlink(o->tmp);
    release(o);
}
