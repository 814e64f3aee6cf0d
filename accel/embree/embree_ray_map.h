#pragma once
// How the Embree adapter hands our rays to Embree: the valid-range mapping
// (done once per ray in prepare(), recorded in a side list only for the rays
// that need it) and the conversion of Embree's answers back to our Hit.
#include <embree3/rtcore.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstddef>

#include "base/hit.h"
#include "base/ray.h"

namespace raylab::embree_adapter {

// Embree's valid ray (asserted in its debug builds, undefined otherwise):
// 0 <= tnear, and every origin and direction component within FLT_LARGE =
// 1.844e18 in magnitude. Our rays are wider, so map_ray converts them: a
// segment that starts behind the origin (tmin < 0) is traced from the point
// at tmin (rounded to float, so distances can differ in the last bits from a
// structure that keeps the original origin), a direction beyond FLT_LARGE
// is scaled down by a power of two (exact), distances by the inverse, and a
// direction shorter than kEmbreeSmallDirection is scaled up the same way to
// a largest component in [0.5, 1): Embree's stream kernel, given such a ray
// (reciprocals near 1e25) in one packet with a ray from 7e14 away, fails
// its own assertion `cur != BVH::emptyNode` and aborts the process (found by
// fuzz_rays, embree:api=stream). Denormal components left after scaling
// become zeros. Hit distances map back as t = t_embree * scale + shift,
// computed in double (a NaN distance from Embree, or one beyond FLT_MAX
// after the mapping, is a miss). Rays
// whose origin (after the shift) is beyond FLT_LARGE cannot be given to
// Embree at all: the adapter reports them as misses (a documented limit of
// the reference; no scene of ours reaches 1e18). tmin = -inf cannot be
// shifted: Embree then sees only the part t >= 0.
inline constexpr float kEmbreeLarge = 1.8e18f;  // just below Embree's FLT_LARGE
// Below this largest direction component a ray is mapped (see embree_takes_as_is).
inline constexpr float kEmbreeSmallDirection = 0x1p-40f;

// Side-list entry for a ray that needed mapping (see map_ray).
struct RayFix {
  size_t index = 0;  // position in the prepared set
  float shift = 0.0f;
  double scale = 1.0;  // up to 2^149 for a denormal direction: not a float
  float tmin = 0.0f, tmax = 0.0f;  // the ray's own range: mapped hits are clamped to it
  bool traced = true;  // false: a miss without asking Embree (masked in packets; a dummy ray otherwise)
};

inline void set_embree_ray(RTCRay& ray, const float org[3], const float dir[3], float tnear, float tfar) {
  ray.org_x = org[0];
  ray.org_y = org[1];
  ray.org_z = org[2];
  ray.tnear = tnear;
  ray.dir_x = dir[0];
  ray.dir_y = dir[1];
  ray.dir_z = dir[2];
  ray.time = 0.0f;
  ray.tfar = tfar;  // tmax = +inf stays +inf
  ray.mask = 0xFFFFFFFFu;
  ray.id = 0;
  ray.flags = 0;
}

// An empty segment at the origin: what untraced rays give Embree.
inline void set_dummy_ray(RTCRay& ray) {
  const float zero[3] = {0.0f, 0.0f, 0.0f}, up[3] = {0.0f, 0.0f, 1.0f};
  set_embree_ray(ray, zero, up, 0.0f, 0.0f);
}

// The common case, tested cheaply: a valid ray Embree takes unchanged.
inline bool embree_takes_as_is(const Ray& r) {
  if (!(r.tmin >= 0.0f && r.tmin <= r.tmax)) return false;  // also rejects NaN
  for (int a = 0; a < 3; ++a) {
    const float o = std::fabs(r.org[a]), d = std::fabs(r.dir[a]);
    if (!(o <= kEmbreeLarge) || !(d <= kEmbreeLarge) || (d != 0.0f && d < FLT_MIN)) return false;
  }
  // A direction this short (e.g. (0, 0, FLT_MIN), found by fuzz_rays) makes
  // Embree's flushed-to-zero products underflow, and it can answer a NaN or
  // out-of-range distance: such rays take the mapped path, whose fix_hit turns
  // NaN into a miss and clamps to [tmin, tmax], as the adapter always did.
  const float dmax = std::max({std::fabs(r.dir[0]), std::fabs(r.dir[1]), std::fabs(r.dir[2])});
  return dmax >= kEmbreeSmallDirection;
}

// Converts one ray; returns true when it needed mapping (`fix` then filled in).
inline bool map_ray(const Ray& r, RTCRay& ray, RayFix& fix) {
  if (embree_takes_as_is(r)) {
    const float org[3] = {r.org.x(), r.org.y(), r.org.z()};
    const float dir[3] = {r.dir.x(), r.dir.y(), r.dir.z()};
    set_embree_ray(ray, org, dir, r.tmin, r.tmax);
    return false;
  }
  fix = RayFix{};
  fix.tmin = r.tmin;
  fix.tmax = r.tmax;
  if (!ray_is_valid(r)) {  // includes tmin <= tmax
    set_dummy_ray(ray);
    fix.traced = false;
    return true;
  }
  float org[3] = {r.org.x(), r.org.y(), r.org.z()};
  float dir[3] = {r.dir.x(), r.dir.y(), r.dir.z()};
  float tmin = r.tmin, tmax = r.tmax;
  if (tmin < 0.0f && std::isfinite(tmin)) {
    fix.shift = tmin;
    for (int a = 0; a < 3; ++a)
      org[a] = static_cast<float>(static_cast<double>(r.org[a]) + static_cast<double>(tmin) * r.dir[a]);
    tmax -= tmin;
    tmin = 0.0f;
  }
  const float dmax = std::max({std::fabs(dir[0]), std::fabs(dir[1]), std::fabs(dir[2])});
  int e = 0;  // the direction is scaled by 2^-e, distances by 2^e
  if (dmax > kEmbreeLarge) std::frexp(dmax / kEmbreeLarge, &e);  // 2^e > dmax / large
  else if (dmax < kEmbreeSmallDirection) std::frexp(dmax, &e);    // dmax = m 2^e, m in [0.5, 1)
  if (e != 0) {
    for (float& d : dir) d = std::ldexp(d, -e);
    tmin = std::ldexp(tmin, e);
    tmax = std::ldexp(tmax, e);
    fix.scale = std::ldexp(1.0, -e);
  }
  // Denormal components become signed zeros: Embree's kernels run with
  // denormals flushed and return NaN distances for them (found by fuzz_rays).
  for (float& d : dir)
    if (std::fabs(d) < FLT_MIN) d = std::copysign(0.0f, d);
  for (float o : org) fix.traced &= std::fabs(o) <= kEmbreeLarge;
  if (!fix.traced) set_dummy_ray(ray);
  else set_embree_ray(ray, org, dir, std::max(0.0f, tmin), tmax);
  return true;
}

inline void reset_hit(RTCHit& hit) {
  hit.geomID = RTC_INVALID_GEOMETRY_ID;
  hit.primID = RTC_INVALID_GEOMETRY_ID;
  hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

// Our hit from Embree's answer (distance still in Embree's parametrisation).
inline void write_hit(const RTCRayHit& rh, Hit& h) {
  if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
    h.t = rh.ray.tfar;
    h.u = rh.hit.u;
    h.v = rh.hit.v;
    h.prim = rh.hit.primID;
  } else {
    h = Hit{};
  }
}

// The mapping back for a listed ray, after its answer was written as usual.
inline void fix_hit(const RayFix& f, Hit& h) {
  if (!f.traced || (h.valid() && std::isnan(h.t))) {
    h = Hit{};
    return;
  }
  if (!h.valid()) return;
  // Clamped to the ray's range: the mapping back may round just outside it.
  const float t = static_cast<float>(static_cast<double>(h.t) * f.scale + f.shift);
  if (!std::isfinite(t)) h = Hit{};  // beyond FLT_MAX: a miss, as for every structure
  else h.t = std::clamp(t, f.tmin, f.tmax);
}

}  // namespace raylab::embree_adapter
