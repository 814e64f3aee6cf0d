#pragma once
// The region of a BSP node: a convex polytope, kept as its boundary faces
// (convex polygons, double precision). The builder needs its exact surface
// area for the SAH (Ize, Wald & Parker 2008 use the polytope areas of the
// children, not of their bounding boxes) and its extent along a direction to
// place candidate planes.
//
// Splitting by a plane clips every face (Sutherland-Hodgman against one
// plane); the new cap face is the polygon of the crossing points, ordered by
// angle in the plane. The children's areas alone (split_areas) need no cap
// polygon: the area vectors of a closed surface sum to zero, so the cap's
// area is |sum of the clipped faces' area vectors|. Degenerate results (a
// plane through a face or an edge, a sliver thinner than rounding) give a
// child with zero area or no faces; the builder treats it as empty space.
#include <utility>
#include <vector>

#include "base/aabb.h"
#include "base/vec.h"

namespace raylab {

struct ConvexPolytope {
  // Boundary polygons, all oriented the same way (area vectors inward).
  std::vector<std::vector<Vec3d>> faces;

  static ConvexPolytope box(const Vec3d& lo, const Vec3d& hi);

  bool empty() const { return faces.size() < 4; }
  double surface_area() const;
  // [min, max] of u . x over the vertices.
  std::pair<double, double> extent(const Vec3d& u) const;
  // The parts with n . x <= d (first) and n . x >= d (second).
  std::pair<ConvexPolytope, ConvexPolytope> split(const Vec3d& n, double d) const;
  // Surface areas of the two parts, without building them.
  std::pair<double, double> split_areas(const Vec3d& n, double d) const;
};

// Area vector of a planar polygon (half the sum of cross products): its
// length is the area, its direction the normal.
Vec3d polygon_area_vector(const std::vector<Vec3d>& poly);

}  // namespace raylab
