/*
 * adaptive-pm's C shim over Embree: one interface for Embree 3 and 4.
 *
 * Embree's C API differs between majors in exactly the places the ray
 * queries touch (Embree 3 passes an RTCIntersectContext that must be
 * initialised by an inline function, Embree 4 passes optional
 * RTCIntersectArguments / RTCOccludedArguments, also initialised inline).
 * Inline functions have no symbol for Rust to link against, so the shim
 * compiles them here, once, against the header the build script found.
 * APM_EMBREE_MAJOR (3 or 4) is set by embree-sys/build.rs.
 */
#ifndef APM_EMBREE_SHIM_H
#define APM_EMBREE_SHIM_H

#include <stddef.h>

#if APM_EMBREE_MAJOR == 4
#include <embree4/rtcore.h>
#elif APM_EMBREE_MAJOR == 3
#include <embree3/rtcore.h>
#else
#error "APM_EMBREE_MAJOR must be 3 or 4"
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* RTC_VERSION_MAJOR of the header the shim was compiled against. */
unsigned int apm_header_version_major(void);

/* sizeof(struct RTCRayHit) as the C compiler sees it (80 in Embree 3, 96 in 4). */
size_t apm_sizeof_rayhit(void);

/* sizeof(struct RTCRayHit8) as the C compiler sees it. */
size_t apm_sizeof_rayhit8(void);

/* sizeof(struct RTCRayHit16) as the C compiler sees it. */
size_t apm_sizeof_rayhit16(void);

/* Closest hit of one ray, default (incoherent) query flags. */
void apm_intersect1(RTCScene scene, struct RTCRayHit* rayhit);

/* Any hit of one ray: sets ray->tfar to -inf when occluded. */
void apm_occluded1(RTCScene scene, struct RTCRay* ray);

/* Closest hits of an 8-wide packet; valid[i] == -1 marks active lanes.
 * valid and rayhit must be 32-byte aligned. */
void apm_intersect8(const int* valid, RTCScene scene, struct RTCRayHit8* rayhit);

/* Occlusion of an 8-wide packet; same conventions as apm_intersect8. */
void apm_occluded8(const int* valid, RTCScene scene, struct RTCRay8* ray);

/* Closest hits of a 16-wide packet; valid[i] == -1 marks active lanes.
 * valid and rayhit must be 64-byte aligned. */
void apm_intersect16(const int* valid, RTCScene scene, struct RTCRayHit16* rayhit);

/* Occlusion of a 16-wide packet; same conventions as apm_intersect16. */
void apm_occluded16(const int* valid, RTCScene scene, struct RTCRay16* ray);

#ifdef __cplusplus
}
#endif

#endif
