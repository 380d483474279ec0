/* The Embree device of cambium's two ray casters, the light pass (src/light/light.c) and the
 * renderer (src/io/png/render.c): made with a thread count, its allocations counted against the
 * context's byte limit, its errors turned into statuses whose messages name the caller. */
#ifndef CBM_GEOM_EMBREE_DEVICE_H
#define CBM_GEOM_EMBREE_DEVICE_H

#include "../core/core.h"

#include <embree3/rtcore.h>
#include <stdatomic.h>

/// The bytes a device holds, for the context's limits.max_bytes; lives as long as the device.
typedef struct cbm__rtc_watch {
    cbm_context *ctx;
    atomic_llong bytes;
} cbm__rtc_watch;

/// A device of `threads` threads whose allocations *watch counts (and refuses beyond the
/// context's byte limit); `who` starts the error message ("light", "renderer").
cbm_status cbm__rtc_device(cbm_context *ctx, int threads, const char *who, cbm__rtc_watch *watch,
                           RTCDevice *out);
/// CBM_OK, or the device's pending error as a status (CBM_E_NOMEM for out of memory) with the
/// message "<who>: ... while <what>".
cbm_status cbm__rtc_status(cbm_context *ctx, RTCDevice dev, const char *who, const char *what);

#endif
