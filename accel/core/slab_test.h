#pragma once
// Conservative ray-box (slab) test.
//
// Ize, "Robust BVH Ray Traversal", JCGT 2(2), 2013: with correctly rounded
// reciprocals, scaling the far distance by 1 + 2*gamma(3) (gamma(n) = n*eps /
// (1 - n*eps), eps = 2^-24) guarantees that rounding never makes a box that the
// ray really crosses look missed. Zero direction components are replaced by a
// tiny value of the same sign, so (lo - org) * inv never becomes 0 * inf = NaN;
// a ray lying exactly in a box face is then treated as entering the box
// (conservative).
#include <algorithm>
#include <cmath>
#include <limits>

#include "accel/core/aabb.h"
#include "accel/core/ray.h"

namespace raylab {

inline constexpr float kFloatGamma3 = (3.0f * 0x1p-24f) / (1.0f - 3.0f * 0x1p-24f);
inline constexpr float kSlabFarScale = 1.0f + 2.0f * kFloatGamma3;

inline float safe_reciprocal(float d) {
  constexpr float kTiny = 1e-30f;
  if (std::fabs(d) < kTiny) d = std::copysign(kTiny, d);
  return 1.0f / d;
}

struct SlabRay {
  Vec3f org;
  Vec3f inv_dir;
  int neg[3];  // 1 when the direction component is negative (sign bit set)

  SlabRay() = default;
  explicit SlabRay(const Ray& r) : org(r.org) {
    for (int i = 0; i < 3; ++i) {
      inv_dir[i] = safe_reciprocal(r.dir[i]);
      neg[i] = std::signbit(r.dir[i]) ? 1 : 0;
    }
  }
};

// Box given as lo/hi arrays. Returns true when [tmin, tmax] overlaps the box's
// (conservatively padded) interval; writes the entry distance.
inline bool slab_test(const SlabRay& r, const float lo[3], const float hi[3], float tmin, float tmax,
                      float& t_entry) {
  const float* bounds[2] = {lo, hi};
  float t0 = tmin, t1 = tmax;
  for (int a = 0; a < 3; ++a) {
    const float tn = (bounds[r.neg[a]][a] - r.org[a]) * r.inv_dir[a];
    const float tf = (bounds[1 - r.neg[a]][a] - r.org[a]) * r.inv_dir[a] * kSlabFarScale;
    t0 = tn > t0 ? tn : t0;
    t1 = tf < t1 ? tf : t1;
  }
  t_entry = t0;
  return t0 <= t1;
}

inline bool slab_test(const SlabRay& r, const Aabb& b, float tmin, float tmax, float& t_entry) {
  return slab_test(r, b.lo.data(), b.hi.data(), tmin, tmax, t_entry);
}

// Entry and exit distances of the ray's [tmin, tmax] clipped to a box.
inline bool clip_to_box(const SlabRay& r, const Aabb& b, float tmin, float tmax, float& t_enter,
                        float& t_exit) {
  const float* bounds[2] = {b.lo.data(), b.hi.data()};
  float t0 = tmin, t1 = tmax;
  for (int a = 0; a < 3; ++a) {
    const float tn = (bounds[r.neg[a]][a] - r.org[a]) * r.inv_dir[a];
    const float tf = (bounds[1 - r.neg[a]][a] - r.org[a]) * r.inv_dir[a] * kSlabFarScale;
    t0 = tn > t0 ? tn : t0;
    t1 = tf < t1 ? tf : t1;
  }
  t_enter = t0;
  t_exit = t1;
  return t0 <= t1;
}

}  // namespace raylab
