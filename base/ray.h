#pragma once
// The one ray type used by every accelerator, the tracer and the benchmarks.
#include <limits>

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
  bool finite = true, nonzero = false;
  for (int a = 0; a < 3; ++a) {
    finite &= (r.org[a] - r.org[a] == 0.0f) & (r.dir[a] - r.dir[a] == 0.0f);  // false for inf and NaN
    nonzero |= r.dir[a] != 0.0f;
  }
  return finite & nonzero & (r.tmin <= r.tmax) & (r.tmin < std::numeric_limits<float>::infinity());  // false for NaN
}

}  // namespace raylab
