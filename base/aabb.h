#pragma once
// Axis-aligned bounding box.
#include <algorithm>
#include <limits>

#include "base/vec.h"

namespace raylab {

struct Aabb {
  Vec3f lo = Vec3f::Constant(std::numeric_limits<float>::infinity());
  Vec3f hi = Vec3f::Constant(-std::numeric_limits<float>::infinity());

  Aabb() = default;
  Aabb(const Vec3f& l, const Vec3f& h) : lo(l), hi(h) {}

  static Aabb empty() { return Aabb(); }

  bool is_empty() const { return lo.x() > hi.x() || lo.y() > hi.y() || lo.z() > hi.z(); }

  void extend(const Vec3f& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void extend(const Aabb& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }

  Vec3f diagonal() const { return is_empty() ? Vec3f::Zero() : Vec3f(hi - lo); }
  Vec3f center() const { return 0.5f * (lo + hi); }

  // Full surface area (0 for an empty box).
  float surface_area() const {
    if (is_empty()) return 0.0f;
    const Vec3f d = hi - lo;
    return 2.0f * (d.x() * d.y() + d.y() * d.z() + d.z() * d.x());
  }
  float half_area() const { return 0.5f * surface_area(); }

  int largest_axis() const {
    const Vec3f d = diagonal();
    if (d.x() >= d.y() && d.x() >= d.z()) return 0;
    return d.y() >= d.z() ? 1 : 2;
  }

  bool contains(const Vec3f& p) const {
    return (p.array() >= lo.array()).all() && (p.array() <= hi.array()).all();
  }
  bool contains(const Aabb& b) const { return b.is_empty() || (contains(b.lo) && contains(b.hi)); }
};

inline Aabb merge(const Aabb& a, const Aabb& b) {
  Aabb r = a;
  r.extend(b);
  return r;
}

}  // namespace raylab
