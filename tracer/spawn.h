#pragma once
// Where a secondary ray starts: the one spawn-offset rule, owned by the
// tracer and used by the ray sets (diffuse and shadow rays) as well.
//
// The hit point p is interpolated from the triangle's vertices in float, so
// it lies off the triangle's plane by a few ulps of the coordinates involved
// - of p itself and, through the distance t the hit was found at, of the
// incoming ray's origin. The origin is pushed along the geometric normal (on
// the side the new ray leaves from) by a relative bound on that error,
// 2e-5 (|p|max + |o|max), plus 1e-6 of the scene's diagonal for points near
// the coordinate origin. As pbrt-v4 (Pharr, Jakob & Humphreys, 4th ed.,
// "Robust spawned ray origins") the goal is that a ray spawned from a hit
// never hits the same triangle again (tests/tracer/test_tracer.cpp checks it).
#include "base/aabb.h"
#include "base/ray.h"
#include "base/vec.h"

namespace raylab {

// Shadow rays aimed at a point stop this short of it (as a fraction of the
// segment), so the light's own surface does not occlude it.
inline constexpr float kShadowRayEnd = 1.0f - 1e-4f;

class SpawnOffset {
 public:
  explicit SpawnOffset(const Aabb& scene_bounds)
      : scene_eps_(scene_bounds.is_empty() ? 1e-6f : 1e-6f * scene_bounds.diagonal().norm()) {}

  // Offset distance for a hit point p of a ray from `from`.
  float distance(const Vec3f& p, const Vec3f& from) const {
    return 2e-5f * (p.cwiseAbs().maxCoeff() + from.cwiseAbs().maxCoeff()) + scene_eps_;
  }

  // The origin of rays leaving the surface at p on the side of the unit
  // normal n (the side the incoming ray from `from` arrived on).
  Vec3f origin(const Vec3f& p, const Vec3f& n, const Vec3f& from) const { return p + distance(p, from) * n; }

 private:
  float scene_eps_;
};

// A shadow ray from a spawned origin towards a point (t in [0, kShadowRayEnd]
// of the segment).
inline Ray shadow_ray_to(const Vec3f& origin, const Vec3f& target) {
  return Ray(origin, target - origin, 0.0f, kShadowRayEnd);
}

}  // namespace raylab
