#pragma once
// Conservative ray-box (slab) test.
//
// Ize, "Robust BVH Ray Traversal", JCGT 2(2), 2013: with correctly rounded
// reciprocals, scaling the far distance by 1 + 2*gamma(3) (gamma(n) = n*eps /
// (1 - n*eps), eps = 2^-24) guarantees that rounding never makes a box that the
// ray really crosses look missed. Far distances that are negative (boxes
// behind the origin, reached by rays with tmin < 0) are scaled by
// 1 - 2*gamma(3) instead, which moves them outward as well (pad_far).
//
// Zero direction components get exact reciprocals, 1 / +-0 = +-inf: a ray
// parallel to a slab and outside it gets entry/exit distances of +-inf (box
// missed), and a ray lying exactly in a box face plane gets 0 * inf = NaN,
// which the comparisons below ignore, leaving that slab unbounded (the ray
// is treated as inside, conservatively). An earlier version replaced zero
// components by +-1e-30; then (face - org) * (1 / -1e-30) = -0 ended the slab
// at t = 0 for a ray lying in a face plane with a -0 (or, on the other face,
// +0) component, and every box touching that plane was lost for tmin > 0.
//
// A nonzero component so small that its reciprocal overflows (|d| < 2^-128)
// gets NaN instead of +-inf: the slab is then unbounded. With +-inf a box
// beside the origin's coordinate on that axis would get an entry distance of
// +inf, although the ray reaches it at a finite (if large) t; the hybrid's
// cell trees, whose boxes lie in cells, lost hits that way.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "base/aabb.h"
#include "base/ray.h"

namespace raylab {

inline constexpr float kFloatGamma3 = (3.0f * 0x1p-24f) / (1.0f - 3.0f * 0x1p-24f);
inline constexpr float kSlabFarScale = 1.0f + 2.0f * kFloatGamma3;
inline constexpr float kSlabFarScaleNeg = 1.0f - 2.0f * kFloatGamma3;

// The same padding on the bits, for finite or infinite t >= +0: t's bits plus
// kSlabFarPadUlps, compared in the signed-integer order of the bits. With
// kSlabFarScale = 1 + 3 * 2^-23 (as rounded), t * kSlabFarScale is below
// t + 6 ulp(t) before rounding (t's significand is below 2), so rounded it is
// at most the float 6 steps above t (steps only grow across a power of two):
// this padding accepts every box the multiplication accepts. An integer add
// instead of a multiplication between a node's planes and its hit mask, and
// no float operation after the integer min/max (see traverse_wide.h).
inline constexpr int32_t kSlabFarPadUlps = 6;
static_assert(kSlabFarScale == 1.0f + 3.0f * 0x1p-23f, "kSlabFarPadUlps assumes this padding");

// A far distance padded outward: up when positive, towards zero when negative.
inline float pad_far(float t) { return t * (t >= 0.0f ? kSlabFarScale : kSlabFarScaleNeg); }

// 1 / d for the slab test: +-inf for +-0, NaN when a nonzero d's
// reciprocal overflows (see the comment at the top).
inline float safe_slab_reciprocal(float d) {
  const float inv = 1.0f / d;
  return d != 0.0f && std::isinf(inv) ? std::numeric_limits<float>::quiet_NaN() : inv;
}

struct SlabRay {
  Vec3f org;
  Vec3f inv_dir;
  int neg[3];  // 1 when the direction component is negative (sign bit set)

  SlabRay() = default;
  explicit SlabRay(const Ray& r) : org(r.org) {
    for (int i = 0; i < 3; ++i) {
      inv_dir[i] = safe_slab_reciprocal(r.dir[i]);
      neg[i] = std::signbit(r.dir[i]) ? 1 : 0;
    }
  }
};

// The ray's [tmin, tmax] clipped to a box given as lo/hi arrays (the far
// planes conservatively padded): entry and exit distances; true when the
// clipped interval is not empty.
[[gnu::always_inline]] inline bool clip_to_box(const SlabRay& r, const float lo[3], const float hi[3], float tmin,
                                               float tmax, float& t_enter, float& t_exit) {
  const float* bounds[2] = {lo, hi};
  float t0 = tmin, t1 = tmax;
  for (int a = 0; a < 3; ++a) {
    const float tn = (bounds[r.neg[a]][a] - r.org[a]) * r.inv_dir[a];
    const float tf = pad_far((bounds[1 - r.neg[a]][a] - r.org[a]) * r.inv_dir[a]);
    t0 = tn > t0 ? tn : t0;
    t1 = tf < t1 ? tf : t1;
  }
  t_enter = t0;
  t_exit = t1;
  return t0 <= t1;
}

inline bool clip_to_box(const SlabRay& r, const Aabb& b, float tmin, float tmax, float& t_enter, float& t_exit) {
  return clip_to_box(r, b.lo.data(), b.hi.data(), tmin, tmax, t_enter, t_exit);
}

// Whether [tmin, tmax] overlaps the box's padded interval; writes the entry distance.
[[gnu::always_inline]] inline bool slab_test(const SlabRay& r, const float lo[3], const float hi[3], float tmin,
                                             float tmax, float& t_entry) {
  float t_exit;
  return clip_to_box(r, lo, hi, tmin, tmax, t_entry, t_exit);
}

inline bool slab_test(const SlabRay& r, const Aabb& b, float tmin, float tmax, float& t_entry) {
  return slab_test(r, b.lo.data(), b.hi.data(), tmin, tmax, t_entry);
}

}  // namespace raylab
