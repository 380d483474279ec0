/* The Embree device of cambium's two ray casters, the light pass (src/light/light.c) and the
 * renderer (src/io/png/render.c): made with a thread count, its allocations counted against the
 * context's byte limit, its errors turned into statuses whose messages name the caller. Embree
 * is loaded when the first device is made (src/core/dynlib.h: a run that casts no ray does not
 * map Embree, TBB and the C++ runtime); its functions are called through cbm__rtc, whose fields
 * have Embree's own names and types: cbm__rtc.rtcNewScene(dev). */
#ifndef CBM_GEOM_EMBREE_DEVICE_H
#define CBM_GEOM_EMBREE_DEVICE_H

#include "../core/core.h"
#include "../core/dynlib.h"

#include <embree3/rtcore.h>
#include <stdatomic.h>

/* The Embree functions cambium calls (rtcInitIntersectContext is inline in Embree's header). */
#define CBM__EMBREE_FUNCTIONS(X)                                                                   \
    X(rtcNewDevice)                                                                                \
    X(rtcReleaseDevice)                                                                            \
    X(rtcGetDeviceError)                                                                           \
    X(rtcSetDeviceMemoryMonitorFunction)                                                           \
    X(rtcNewScene)                                                                                 \
    X(rtcReleaseScene)                                                                             \
    X(rtcCommitScene)                                                                              \
    X(rtcNewGeometry)                                                                              \
    X(rtcReleaseGeometry)                                                                          \
    X(rtcCommitGeometry)                                                                           \
    X(rtcAttachGeometryByID)                                                                       \
    X(rtcSetNewGeometryBuffer)                                                                     \
    X(rtcSetSharedGeometryBuffer)                                                                  \
    X(rtcIntersect1)                                                                               \
    X(rtcOccluded1)                                                                                \
    X(rtcOccluded1M)

/// Pointers to Embree's functions, filled by the first cbm__rtc_device.
typedef struct cbm__embree_api {
    /* f names the field: a declarator, not an expression to parenthesize */
    // NOLINTNEXTLINE(bugprone-macro-parentheses)
#define CBM__EMBREE_FIELD(f) __typeof__(f) *f;
    CBM__EMBREE_FUNCTIONS(CBM__EMBREE_FIELD)
#undef CBM__EMBREE_FIELD
} cbm__embree_api;

/// Embree's functions: valid once a cbm__rtc_device call has returned CBM_OK.
extern cbm__embree_api cbm__rtc;

/// The bytes a device holds, for the context's limits.max_bytes; lives as long as the device.
typedef struct cbm__rtc_watch {
    cbm_context *ctx;
    atomic_llong bytes;
} cbm__rtc_watch;

/// A device of `threads` threads whose allocations *watch counts (and refuses beyond the
/// context's byte limit); `who` starts the error message ("light", "renderer"). Loads Embree
/// on the first call (CBM_E_UNSUPPORTED, naming the library and its package, when it cannot).
cbm_status cbm__rtc_device(cbm_context *ctx, int threads, const char *who, cbm__rtc_watch *watch,
                           RTCDevice *out);
/// CBM_OK, or the device's pending error as a status (CBM_E_NOMEM for out of memory) with the
/// message "<who>: ... while <what>".
cbm_status cbm__rtc_status(cbm_context *ctx, RTCDevice dev, const char *who, const char *what);

#endif
