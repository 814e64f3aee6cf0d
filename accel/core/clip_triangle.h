#pragma once
// Bounds of the part of a triangle inside a box, for "perfect splits"
// (Havran's thesis, 2000; Wald & Havran 2006): a triangle
// that straddles a split plane is clipped to each child cell, and the child's
// split candidates come from the clipped polygon's bounds rather than from the
// triangle's bounding box. Triangles whose box overlaps a cell but whose
// surface does not are dropped from that cell altogether.
//
// Robustness: the clip runs in double precision on the float vertices (which
// double represents exactly), and the result is rounded outward to float with
// one extra ulp of margin, then clamped to the cell and to the triangle's own
// box (both exact bounds of the true clipped part). The bounds are therefore
// never smaller than the true intersection, so no cell loses a triangle that
// really reaches into it. A vertex exactly on a cell face counts as inside.
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>

#include "base/aabb.h"
#include "base/vec.h"

namespace raylab {

namespace kd_detail {

// The next float towards -inf / +inf of a finite float (std::nextafter
// without the library call).
inline float next_down(float f) {
  if (f == 0.0f) return -std::numeric_limits<float>::denorm_min();
  const uint32_t b = std::bit_cast<uint32_t>(f);
  return std::bit_cast<float>(f > 0.0f ? b - 1 : b + 1);
}
inline float next_up(float f) { return -next_down(-f); }

// Double to float, rounded outward, plus one more ulp of margin.
inline float round_down(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = next_down(f);
  return next_down(f);
}

inline float round_up(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) < x) f = next_up(f);
  return next_up(f);
}

}  // namespace kd_detail

// Bounding box of a triangle's box intersected with a cell (the "clip=0"
// variant). Returns false when they do not overlap (touching counts).
inline bool clip_box_to_cell(const Aabb& tri_box, const Aabb& cell, Aabb& out) {
  out.lo = tri_box.lo.cwiseMax(cell.lo);
  out.hi = tri_box.hi.cwiseMin(cell.hi);
  return !out.is_empty();
}

// Bounds of triangle (a, b, c) intersected with `cell` (Sutherland-Hodgman
// clipping against the six faces). Returns false when the intersection is
// empty.
inline bool clip_triangle_to_cell(const Vec3f& a, const Vec3f& b, const Vec3f& c, const Aabb& cell,
                                  Aabb& out) {
  Aabb tri_box;
  tri_box.extend(a);
  tri_box.extend(b);
  tri_box.extend(c);
  if (!clip_box_to_cell(tri_box, cell, out)) return false;
  if (cell.contains(tri_box)) return true;  // nothing to clip

  // A convex polygon gains at most one vertex per clip plane: 3 + 6 = 9.
  constexpr int kMaxVerts = 16;
  Vec3d buf[2][kMaxVerts];
  buf[0][0] = a.cast<double>();
  buf[0][1] = b.cast<double>();
  buf[0][2] = c.cast<double>();
  int n = 3, cur = 0;
  for (int axis = 0; axis < 3; ++axis) {
    for (int side = 0; side < 2; ++side) {
      // Faces the whole triangle is inside of clip nothing.
      if (side == 0 ? tri_box.lo[axis] >= cell.lo[axis] : tri_box.hi[axis] <= cell.hi[axis]) continue;
      const double plane = side == 0 ? cell.lo[axis] : cell.hi[axis];
      const Vec3d* in = buf[cur];
      Vec3d* dst = buf[1 - cur];
      int m = 0;
      for (int i = 0; i < n; ++i) {
        const Vec3d& p = in[i];
        const Vec3d& q = in[(i + 1) % n];
        const bool p_in = side == 0 ? p[axis] >= plane : p[axis] <= plane;
        const bool q_in = side == 0 ? q[axis] >= plane : q[axis] <= plane;
        if (m + 2 > kMaxVerts) return true;  // cannot happen for a convex polygon; keep the plain box
        if (p_in) dst[m++] = p;
        if (p_in != q_in) {
          const double t = (plane - p[axis]) / (q[axis] - p[axis]);
          Vec3d x = p + t * (q - p);
          x[axis] = plane;  // exactly on the face
          dst[m++] = x;
        }
      }
      n = m;
      cur = 1 - cur;
      if (n == 0) return false;
    }
  }
  Vec3d lo = buf[cur][0], hi = buf[cur][0];
  for (int i = 1; i < n; ++i) {
    lo = lo.cwiseMin(buf[cur][i]);
    hi = hi.cwiseMax(buf[cur][i]);
  }
  for (int k = 0; k < 3; ++k) {
    // `out` already holds tri_box ∩ cell; only tighten it.
    out.lo[k] = std::max(out.lo[k], kd_detail::round_down(lo[k]));
    out.hi[k] = std::min(out.hi[k], kd_detail::round_up(hi[k]));
    if (out.lo[k] > out.hi[k]) {
      // The outward rounding cannot cross; only reachable through a polygon
      // of zero extent right at a face. Keep the box conservative.
      out.lo[k] = out.hi[k] = std::clamp(static_cast<float>(lo[k]), std::max(tri_box.lo[k], cell.lo[k]),
                                         std::min(tri_box.hi[k], cell.hi[k]));
    }
  }
  return true;
}

}  // namespace raylab
