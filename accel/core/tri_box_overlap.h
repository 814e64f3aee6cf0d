#pragma once
// Exact triangle/box overlap by the separating axis theorem: Akenine-Moller,
// "Fast 3D Triangle-Box Overlap Testing", journal of graphics tools 6(1),
// 2001. A triangle and a box are disjoint if and only if one of 13 axes
// separates their projections: the 3 box normals, the triangle normal, and
// the 9 cross products of the box normals with the triangle's edges.
// Touching counts as overlap (closed sets), so a triangle lying in a cell's
// face belongs to both cells sharing it. Double precision; a degenerate
// triangle (segment or point) is handled by the same axes, zero axes
// separating nothing.
#include <algorithm>
#include <cmath>

#include "base/vec.h"

namespace raylab {

namespace detail {

// True when `axis` separates the triangle (vertices relative to the box
// centre) from the box of half-size `half`.
inline bool separates(const Vec3d& axis, const Vec3d& v0, const Vec3d& v1, const Vec3d& v2, const Vec3d& half) {
  const double p0 = axis.dot(v0), p1 = axis.dot(v1), p2 = axis.dot(v2);
  const double r = half.x() * std::fabs(axis.x()) + half.y() * std::fabs(axis.y()) + half.z() * std::fabs(axis.z());
  return std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r;
}

}  // namespace detail

inline bool triangle_box_overlap(const Vec3d& box_lo, const Vec3d& box_hi, const Vec3d& a, const Vec3d& b,
                                 const Vec3d& c) {
  const Vec3d center = 0.5 * (box_lo + box_hi);
  const Vec3d half = 0.5 * (box_hi - box_lo);
  const Vec3d v0 = a - center, v1 = b - center, v2 = c - center;

  // Box normals: the triangle's bounds against the box.
  for (int i = 0; i < 3; ++i) {
    if (std::min({v0[i], v1[i], v2[i]}) > half[i] || std::max({v0[i], v1[i], v2[i]}) < -half[i]) return false;
  }
  const Vec3d e0 = v1 - v0, e1 = v2 - v1, e2 = v0 - v2;
  // Triangle normal: the plane against the box.
  if (detail::separates(e0.cross(e1), v0, v1, v2, half)) return false;
  // Edge x box-normal axes.
  const Vec3d units[3] = {Vec3d::UnitX(), Vec3d::UnitY(), Vec3d::UnitZ()};
  for (const Vec3d& e : {e0, e1, e2})
    for (const Vec3d& u : units)
      if (detail::separates(u.cross(e), v0, v1, v2, half)) return false;
  return true;
}

}  // namespace raylab
