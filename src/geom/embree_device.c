/* The Embree device of the light pass and the renderer (embree_device.h). */
#include "embree_device.h"

#include <stddef.h>
#include <stdio.h>

cbm__embree_api cbm__rtc;

static const cbm__dynsym embree_syms[] = {
#define CBM__EMBREE_SYM(f) {#f, offsetof(cbm__embree_api, f)},
    CBM__EMBREE_FUNCTIONS(CBM__EMBREE_SYM)
#undef CBM__EMBREE_SYM
};

static cbm__dynlib embree_lib =
    CBM__DYNLIB_INIT("libembree3.so.3", "libembree3-3", embree_syms, &cbm__rtc);

static bool memory_monitor(void *ud, ssize_t bytes, bool post)
{
    cbm__rtc_watch *m = ud;
    long long now = atomic_fetch_add(&m->bytes, (long long)bytes) + (long long)bytes;
    if (bytes > 0 && !post) {
        size_t max = cbm_context_limits(m->ctx)->max_bytes;
        if (max && (size_t)now + cbm_context_bytes(m->ctx) > max) {
            atomic_fetch_sub(&m->bytes, (long long)bytes);
            return false;
        }
    }
    return true;
}

cbm_status cbm__rtc_device(cbm_context *ctx, int threads, const char *who, cbm__rtc_watch *watch,
                           RTCDevice *out)
{
    *out = NULL;
    CBM_TRY(cbm__dynlib_load(ctx, &embree_lib, who));
    char cfg[64];
    snprintf(cfg, sizeof cfg, "threads=%d,verbose=0", threads);
    watch->ctx = ctx;
    atomic_init(&watch->bytes, 0);
    *out = cbm__rtc.rtcNewDevice(cfg);
    if (!*out)
        return cbm__fail(ctx, CBM_E_INTERNAL, "%s: cannot create the Embree device", who);
    cbm__rtc.rtcSetDeviceMemoryMonitorFunction(*out, memory_monitor, watch);
    return CBM_OK;
}

cbm_status cbm__rtc_status(cbm_context *ctx, RTCDevice dev, const char *who, const char *what)
{
    enum RTCError e = cbm__rtc.rtcGetDeviceError(dev);
    if (e == RTC_ERROR_NONE)
        return CBM_OK;
    if (e == RTC_ERROR_OUT_OF_MEMORY)
        return cbm__fail(ctx, CBM_E_NOMEM, "%s: out of memory while %s", who, what);
    return cbm__fail(ctx, CBM_E_INTERNAL, "%s: Embree error %d while %s", who, (int)e, what);
}
