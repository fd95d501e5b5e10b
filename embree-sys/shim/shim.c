/* See shim.h: the only file where Embree 3 and Embree 4 differ. */
#include "shim.h"

unsigned int apm_header_version_major(void) { return RTC_VERSION_MAJOR; }

size_t apm_sizeof_rayhit(void) { return sizeof(struct RTCRayHit); }

size_t apm_sizeof_rayhit8(void) { return sizeof(struct RTCRayHit8); }

size_t apm_sizeof_rayhit16(void) { return sizeof(struct RTCRayHit16); }

#if RTC_VERSION_MAJOR >= 4

void apm_intersect1(RTCScene scene, struct RTCRayHit* rayhit)
{
  struct RTCIntersectArguments args;
  rtcInitIntersectArguments(&args);
  rtcIntersect1(scene, rayhit, &args);
}

void apm_occluded1(RTCScene scene, struct RTCRay* ray)
{
  struct RTCOccludedArguments args;
  rtcInitOccludedArguments(&args);
  rtcOccluded1(scene, ray, &args);
}

void apm_intersect8(const int* valid, RTCScene scene, struct RTCRayHit8* rayhit)
{
  struct RTCIntersectArguments args;
  rtcInitIntersectArguments(&args);
  rtcIntersect8(valid, scene, rayhit, &args);
}

void apm_occluded8(const int* valid, RTCScene scene, struct RTCRay8* ray)
{
  struct RTCOccludedArguments args;
  rtcInitOccludedArguments(&args);
  rtcOccluded8(valid, scene, ray, &args);
}

void apm_intersect16(const int* valid, RTCScene scene, struct RTCRayHit16* rayhit)
{
  struct RTCIntersectArguments args;
  rtcInitIntersectArguments(&args);
  rtcIntersect16(valid, scene, rayhit, &args);
}

void apm_occluded16(const int* valid, RTCScene scene, struct RTCRay16* ray)
{
  struct RTCOccludedArguments args;
  rtcInitOccludedArguments(&args);
  rtcOccluded16(valid, scene, ray, &args);
}

#else /* Embree 3 */

void apm_intersect1(RTCScene scene, struct RTCRayHit* rayhit)
{
  struct RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcIntersect1(scene, &context, rayhit);
}

void apm_occluded1(RTCScene scene, struct RTCRay* ray)
{
  struct RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcOccluded1(scene, &context, ray);
}

void apm_intersect8(const int* valid, RTCScene scene, struct RTCRayHit8* rayhit)
{
  struct RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcIntersect8(valid, scene, &context, rayhit);
}

void apm_occluded8(const int* valid, RTCScene scene, struct RTCRay8* ray)
{
  struct RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcOccluded8(valid, scene, &context, ray);
}

void apm_intersect16(const int* valid, RTCScene scene, struct RTCRayHit16* rayhit)
{
  struct RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcIntersect16(valid, scene, &context, rayhit);
}

void apm_occluded16(const int* valid, RTCScene scene, struct RTCRay16* ray)
{
  struct RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcOccluded16(valid, scene, &context, ray);
}

#endif
