// Triangle/box overlap by the separating axis test (accel/core/tri_box_overlap.h):
// its cases, and agreement with clipping the triangle to the box.
#include <gtest/gtest.h>

#include <utility>
#include <vector>

#include "accel/core/tri_box_overlap.h"
#include "base/pcg.h"

namespace raylab {
namespace {

TEST(TriangleBoxOverlap, SeparatingAxisCases) {
  const Vec3d lo(0, 0, 0), hi(1, 1, 1);
  // All vertices outside, the triangle slices through the box.
  EXPECT_TRUE(triangle_box_overlap(lo, hi, {-5, -5, 0.5}, {5, -5, 0.5}, {0, 5, 0.5}));
  // Touching a face counts as overlap.
  EXPECT_TRUE(triangle_box_overlap(lo, hi, {1, 0.2, 0.2}, {2, 0.2, 0.8}, {1, 0.8, 0.5}));
  // Separated along a box normal (the bounds do not overlap in x).
  EXPECT_FALSE(triangle_box_overlap(lo, hi, {1.4, 1.4, -1}, {1.4, 1.4, 3}, {3, -1, 1}));
  // Bounds overlap, but the plane x+y+z = 3.1 passes beyond the corner (1,1,1).
  EXPECT_FALSE(triangle_box_overlap(lo, hi, {3.1, 0, 0}, {0, 3.1, 0}, {0, 0, 3.1}));
  // The plane x+y+z = 2.5 cuts off the corner and the triangle contains (5/6, 5/6, 5/6).
  EXPECT_TRUE(triangle_box_overlap(lo, hi, {2.5, 0, 0}, {0, 2.5, 0}, {0, 0, 2.5}));
  // Edge-axis separation: bounds overlap and the plane z = 0.5 cuts the box,
  // but the triangle lies beyond x + y = 3.3; only the axis edge x z-normal
  // (proportional to (1, 1, 0)) separates it.
  EXPECT_FALSE(triangle_box_overlap(lo, hi, {0.8, 2.5, 0.5}, {2.5, 0.8, 0.5}, {2.5, 2.5, 0.5}));
  // The same triangle moved until its hypotenuse passes through the box.
  EXPECT_TRUE(triangle_box_overlap(lo, hi, {0.2, 1.6, 0.5}, {1.6, 0.2, 0.5}, {2.5, 2.5, 0.5}));
  // A degenerate triangle (segment) through the box, and a point outside.
  EXPECT_TRUE(triangle_box_overlap(lo, hi, {-1, 0.5, 0.5}, {2, 0.5, 0.5}, {0.5, 0.5, 0.5}));
  EXPECT_FALSE(triangle_box_overlap(lo, hi, {2, 2, 2}, {2, 2, 2}, {2, 2, 2}));
}

// Reference: clip the triangle polygon against the box's six planes
// (Sutherland-Hodgman); the triangle overlaps when something is left.
bool clip_overlap(const Vec3d& lo, const Vec3d& hi, const Vec3d& a, const Vec3d& b, const Vec3d& c) {
  std::vector<Vec3d> poly = {a, b, c};
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      std::vector<Vec3d> out;
      auto inside = [&](const Vec3d& p) { return side == 0 ? p[axis] >= lo[axis] : p[axis] <= hi[axis]; };
      const double plane = side == 0 ? lo[axis] : hi[axis];
      for (size_t i = 0; i < poly.size(); ++i) {
        const Vec3d& p = poly[i];
        const Vec3d& q = poly[(i + 1) % poly.size()];
        if (inside(p)) out.push_back(p);
        if (inside(p) != inside(q)) {
          const double t = (plane - p[axis]) / (q[axis] - p[axis]);
          Vec3d x = p + t * (q - p);
          x[axis] = plane;
          out.push_back(x);
        }
      }
      poly = std::move(out);
      if (poly.empty()) return false;
    }
  return true;
}

TEST(TriangleBoxOverlap, AgreesWithPolygonClippingOnRandomTriangles) {
  Pcg32 rng(3, 7);
  const Vec3d lo(0, 0, 0), hi(1, 1, 1);
  size_t overlaps = 0, checked = 0;
  for (int i = 0; i < 20000; ++i) {
    Vec3d v[3];
    const Vec3d c(3 * rng.uniform() - 1, 3 * rng.uniform() - 1, 3 * rng.uniform() - 1);
    for (auto& p : v) p = c + Vec3d(rng.uniform() - 0.5, rng.uniform() - 0.5, rng.uniform() - 0.5) * 2.0;
    const bool sat = triangle_box_overlap(lo, hi, v[0], v[1], v[2]);
    // Decided cases only: the answer must not change under a tiny shrink/grow.
    const double e = 1e-9;
    const bool grown = clip_overlap(lo.array() - e, hi.array() + e, v[0], v[1], v[2]);
    const bool shrunk = clip_overlap(lo.array() + e, hi.array() - e, v[0], v[1], v[2]);
    if (grown != shrunk) continue;
    ++checked;
    overlaps += sat;
    EXPECT_EQ(sat, grown) << "triangle " << i;
  }
  EXPECT_GT(checked, 19000u);
  EXPECT_GT(overlaps, 2000u);  // both outcomes are exercised
  EXPECT_LT(overlaps, checked - 2000u);
}

}  // namespace
}  // namespace raylab
