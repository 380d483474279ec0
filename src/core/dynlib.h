/* Libraries loaded when first needed (dlopen), not at the start of every process: Embree (with
 * TBB and the C++ runtime) for the two ray casters, cairo (with fontconfig, FreeType, pixman and
 * the X client libraries) for plots and the text of pictures. Linked at build time, these are
 * twenty-odd shared objects the loader maps and relocates before main, in every run, also in the
 * runs (most of them: a derivation, a mesh, a table) that never cast a ray or draw a letter; on
 * the machine of docs/performance.md that start cost about as much as a small model's whole
 * derivation and mesh. Their headers are still used at build time, so the types and the functions'
 * signatures are the libraries' own (each table's fields are declared with the types of the
 * functions they point to).
 *
 * A library is a cbm__dynlib: its soname, the Debian package that installs it (for the message
 * when it is missing) and a table of named function pointers to fill. cbm__dynlib_load opens it
 * and resolves every name once per process, under a lock, whichever thread asks first; after
 * that a load is one atomic read. A library that cannot be opened, or lacks a function, leaves
 * the table as it was, empty (its pointers NULL), and every load fails with the same message. */
#ifndef CBM_CORE_DYNLIB_H
#define CBM_CORE_DYNLIB_H

#include "core.h"

#include <stdatomic.h>

/// One function of a table: its name in the library and the offset of its pointer field.
typedef struct cbm__dynsym {
    const char *name;
    size_t offset;
} cbm__dynsym;

/// A library to load at run time and the table its functions go to. Define one statically with
/// CBM__DYNLIB_INIT; the fields below the table are the loader's.
typedef struct cbm__dynlib {
    const char *soname;  /* "libembree3.so.3" */
    const char *package; /* "libembree3-3": named in the message when it cannot be loaded */
    const cbm__dynsym *syms;
    size_t nsyms;
    void *table;      /* a struct of function pointers, syms[i].offset into it */
    atomic_int state; /* 0 not tried, 1 loaded, -1 failed */
    char why[256];    /* the reason of a failure */
} cbm__dynlib;

#define CBM__DYNLIB_INIT(soname, package, syms, table)                                             \
    {                                                                                              \
        (soname), (package), (syms), sizeof(syms) / sizeof((syms)[0]), (table), 0,                 \
        {                                                                                          \
            0                                                                                      \
        }                                                                                          \
    }

/// CBM_OK once every function of lib is in its table; else CBM_E_UNSUPPORTED with the message
/// "<who>: cannot load <soname> (Debian package <package>): <reason>" on ctx (which may be NULL:
/// the status alone). Thread-safe.
cbm_status cbm__dynlib_load(cbm_context *ctx, cbm__dynlib *lib, const char *who);

#endif
