/* Libraries loaded when first needed (dynlib.h): dlopen with RTLD_NOW | RTLD_LOCAL, every name
 * resolved with dlsym, once, before the table is published. The handle is kept for the rest of
 * the process (the functions stay in use; there is nothing to gain from closing it at exit). */
#include "dynlib.h"

#include <dlfcn.h>
#include <pthread.h>
#include <stdio.h>

static pthread_mutex_t load_lock = PTHREAD_MUTEX_INITIALIZER;

/* Opens lib and fills its table, or says why not in lib->why; under load_lock. Each name is
 * looked up once and its pointer stored as it is found; when one is missing, the pointers
 * stored before it are cleared again, so a refused library leaves its table as it was: empty
 * (a table is filled once per process, by the first load). */
static bool open_lib(cbm__dynlib *lib)
{
    void *h = dlopen(lib->soname, RTLD_NOW | RTLD_LOCAL);
    if (!h) {
        const char *e = dlerror();
        snprintf(lib->why, sizeof lib->why, "%s", e ? e : "dlopen failed");
        return false;
    }
    for (size_t i = 0; i < lib->nsyms; i++) {
        (void)dlerror();
        void *f = dlsym(h, lib->syms[i].name);
        if (!f) {
            snprintf(lib->why, sizeof lib->why, "it has no function %s", lib->syms[i].name);
            void *none = NULL;
            for (size_t k = 0; k < i; k++)
                memcpy((char *)lib->table + lib->syms[k].offset, &none, sizeof none);
            dlclose(h);
            return false;
        }
        /* POSIX: the object pointer dlsym returns converts to the function's pointer */
        memcpy((char *)lib->table + lib->syms[i].offset, &f, sizeof f);
    }
    return true;
}

cbm_status cbm__dynlib_load(cbm_context *ctx, cbm__dynlib *lib, const char *who)
{
    int state = atomic_load_explicit(&lib->state, memory_order_acquire);
    if (state == 0) {
        pthread_mutex_lock(&load_lock);
        state = atomic_load_explicit(&lib->state, memory_order_relaxed);
        if (state == 0) {
            state = open_lib(lib) ? 1 : -1;
            atomic_store_explicit(&lib->state, state, memory_order_release);
        }
        pthread_mutex_unlock(&load_lock);
    }
    if (state == 1)
        return CBM_OK;
    if (!ctx)
        return CBM_E_UNSUPPORTED;
    return cbm__fail(ctx, CBM_E_UNSUPPORTED, "%s: cannot load %s (Debian package %s): %s", who,
                     lib->soname, lib->package, lib->why);
}
