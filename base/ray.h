#pragma once
// The one ray type used by every accelerator, the tracer and the benchmarks.
#include <cstddef>
#include <limits>

#if defined(__SSE4_1__)
#include <immintrin.h>
#endif

#include "base/vec.h"

namespace raylab {

// A ray segment: points org + t * dir for t in [tmin, tmax]. A hit's
// distance is a finite float: a triangle met beyond FLT_MAX (tmax = +inf
// with a tiny direction or a far origin) is a miss, as for Embree
// (accel/core/hit_recorder.h).
// dir need not be normalised; t is measured in units of |dir|.
struct Ray {
  Vec3f org = Vec3f::Zero();
  float tmin = 0.0f;
  Vec3f dir = Vec3f::UnitZ();
  float tmax = std::numeric_limits<float>::infinity();

  Ray() = default;
  Ray(const Vec3f& o, const Vec3f& d, float t0 = 0.0f,
      float t1 = std::numeric_limits<float>::infinity())
      : org(o), tmin(t0), dir(d), tmax(t1) {}

  Vec3f at(float t) const { return org + t * dir; }
};

#if defined(__SSE4_1__)
// The operands of the ray checks (ray_is_valid here, the wide BVH's
// ray_takes_fma_kernel): the ray's two 16-byte halves, (org, tmin) and (dir,
// tmax), with magnitudes in the first three lanes and tmin in the last.
struct RayLanes {
  __m128 abs_org_tmin;  // |ox| |oy| |oz| tmin
  __m128 abs_dir_tmin;  // |dx| |dy| |dz| tmin
  __m128 dir_tmax;      // dx dy dz tmax
  explicit RayLanes(const Ray& r) {
    static_assert(offsetof(Ray, tmin) == offsetof(Ray, org) + 12 && offsetof(Ray, dir) == offsetof(Ray, org) + 16 &&
                  offsetof(Ray, tmax) == offsetof(Ray, dir) + 12, "Ray: org, tmin, dir, tmax packed in this order");
    const __m128 org_tmin = _mm_loadu_ps(r.org.data());
    dir_tmax = _mm_loadu_ps(r.dir.data());
    const __m128 abs_xyz = _mm_castsi128_ps(_mm_setr_epi32(0x7FFFFFFF, 0x7FFFFFFF, 0x7FFFFFFF, -1));
    abs_org_tmin = _mm_and_ps(org_tmin, abs_xyz);
    abs_dir_tmin = _mm_blend_ps(_mm_and_ps(dir_tmax, abs_xyz), org_tmin, 8);
  }
  // All four lanes set.
  static bool all(__m128 m) { return _mm_movemask_ps(m) == 0xF; }
};
#endif

// True when a ray can be traced: finite origin, finite non-zero direction,
// tmin and tmax not NaN, tmin <= tmax, and tmin < +inf (a segment that starts
// at infinity is empty; without this rule [+inf, +inf] would accept exactly
// the hits whose distance overflows to +inf, which structures that widen
// their intervals by margins cannot all reproduce). Every accelerator (and the oracle)
// treats a ray failing this as a miss, never as undefined behaviour:
// intersect() reports no hit, occluded() reports not occluded (tested for
// every accelerator in test_accelerators.cpp, and by the `rays` scenario of
// `raylab stress`). Inline and branch-free: it is the prologue of every
// traversal. The command line makes no rays from user input except through
// cameras, whose views are checked (view_problem) before any ray is made.
inline bool ray_is_valid(const Ray& r) {
#if defined(__SSE4_1__)
  // The same rules as the scalar form below, as three comparisons: every
  // traversal's prologue.
  const RayLanes l(r);
  const __m128 flt_max = _mm_set1_ps(std::numeric_limits<float>::max());
  // |ox| |oy| |oz| <= FLT_MAX (finite), tmin <= tmax
  const __m128 ok_org = _mm_cmple_ps(l.abs_org_tmin, _mm_blend_ps(flt_max, l.dir_tmax, 8));
  // |dx| |dy| |dz| <= FLT_MAX (finite), tmin <= FLT_MAX (below +inf)
  const __m128 ok_dir = _mm_cmple_ps(l.abs_dir_tmin, flt_max);
  const int nonzero = _mm_movemask_ps(_mm_cmpgt_ps(l.abs_dir_tmin, _mm_setzero_ps())) & 7;
  return RayLanes::all(_mm_and_ps(ok_org, ok_dir)) & (nonzero != 0);
#else
  bool finite = true, nonzero = false;
  for (int a = 0; a < 3; ++a) {
    finite &= r.org[a] - r.org[a] == 0.0f;  // false for inf and NaN
    finite &= r.dir[a] - r.dir[a] == 0.0f;
    nonzero |= r.dir[a] != 0.0f;
  }
  return finite & nonzero & (r.tmin <= r.tmax) & (r.tmin < std::numeric_limits<float>::infinity());  // false for NaN
#endif
}

}  // namespace raylab
