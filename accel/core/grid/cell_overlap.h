#pragma once
// Which cells of a grid a triangle is assigned to.
//
// AssignMode::Exact: every cell whose box, enlarged by the grid's margin,
// the triangle overlaps (separating axis test, tri_box_overlap.h). Candidate
// cells are not the whole bounding box of the triangle, which for a large
// slanted triangle holds k^3 cells while the triangle crosses only ~k^2:
// along the axis where the triangle's normal is largest, each column of
// cells only needs the cells between the plane's lowest and highest points
// over that column (a conservative range; the separating axis test decides).
//
// AssignMode::Bbox: every cell overlapped by the triangle's (enlarged)
// bounding box; cheaper to build, more references (for the study).
#include <algorithm>
#include <cstdint>
#include <type_traits>

#include "base/aabb.h"
#include "accel/core/grid/dda_grid.h"
#include "accel/core/tri_box_overlap.h"

namespace raylab {

enum class AssignMode : uint8_t { Exact, Bbox };

namespace detail {

// Calls f; a callback returning bool can stop the enumeration with false.
template <typename F>
inline bool keep_going(F& f, int32_t x, int32_t y, int32_t z) {
  if constexpr (std::is_same_v<decltype(f(x, y, z)), bool>) {
    return f(x, y, z);
  } else {
    f(x, y, z);
    return true;
  }
}

}  // namespace detail

// Calls f(x, y, z) for every cell of `g` the triangle (p0, p1, p2) is
// assigned to. Parts of the triangle outside the grid are ignored (the
// two-level grid assigns a cell's triangles to a sub-grid covering only
// that cell). If f returns bool, returning false stops the enumeration (the
// builders' count passes stop once a memory budget is exceeded).
template <typename F>
inline void for_each_assigned_cell(const DdaGrid& g, AssignMode mode, const Vec3f& p0, const Vec3f& p1,
                                   const Vec3f& p2, F&& f) {
  const Vec3d v0 = p0.cast<double>(), v1 = p1.cast<double>(), v2 = p2.cast<double>();
  const Vec3d margin = assignment_margin(g);
  int32_t lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    const double mn = std::min({v0[a], v1[a], v2[a]}) - margin[a];
    const double mx = std::max({v0[a], v1[a], v2[a]}) + margin[a];
    if (mx < g.lo[a] || mn > g.hi[a]) return;  // outside this grid
    lo[a] = g.coord(a, mn);
    hi[a] = g.coord(a, mx);
  }
  auto cell_lo = [&](int a, int32_t c) { return g.boundary(a, c) - margin[a]; };
  auto cell_hi = [&](int a, int32_t c) { return g.boundary(a, c + 1) + margin[a]; };

  if (mode == AssignMode::Bbox) {
    for (int32_t z = lo[2]; z <= hi[2]; ++z)
      for (int32_t y = lo[1]; y <= hi[1]; ++y)
        for (int32_t x = lo[0]; x <= hi[0]; ++x)
          if (!detail::keep_going(f, x, y, z)) return;
    return;
  }

  const Vec3d n = (v1 - v0).cross(v2 - v0);
  const int d = std::fabs(n.x()) >= std::fabs(n.y()) ? (std::fabs(n.x()) >= std::fabs(n.z()) ? 0 : 2)
                                                     : (std::fabs(n.y()) >= std::fabs(n.z()) ? 1 : 2);
  const int a = (d + 1) % 3, b = (d + 2) % 3;
  const bool has_plane = n[d] != 0.0 && std::isfinite(n[d]);
  const double plane = n.dot(v0);
  int32_t c[3];
  for (c[a] = lo[a]; c[a] <= hi[a]; ++c[a]) {
    for (c[b] = lo[b]; c[b] <= hi[b]; ++c[b]) {
      int32_t d0 = lo[d], d1 = hi[d];
      if (has_plane) {
        // The plane's extent along d over the column's (enlarged) rectangle:
        // x_d = (plane - n_a x_a - n_b x_b) / n_d is linear, so its extremes
        // are at the rectangle's corners.
        const double a0 = cell_lo(a, c[a]), a1 = cell_hi(a, c[a]);
        const double b0 = cell_lo(b, c[b]), b1 = cell_hi(b, c[b]);
        double mn = std::numeric_limits<double>::infinity(), mx = -mn;
        for (const double xa : {a0, a1})
          for (const double xb : {b0, b1}) {
            const double xd = (plane - n[a] * xa - n[b] * xb) / n[d];
            mn = std::min(mn, xd);
            mx = std::max(mx, xd);
          }
        // Slack for the rounding of this estimate; the SAT decides exactly.
        const double slack = 1e-9 * (std::fabs(mn) + std::fabs(mx)) + margin[d];
        d0 = std::max(d0, g.coord(d, mn - slack));
        d1 = std::min(d1, g.coord(d, mx + slack));
      }
      for (c[d] = d0; c[d] <= d1; ++c[d]) {
        const Vec3d box_lo(cell_lo(0, c[0]), cell_lo(1, c[1]), cell_lo(2, c[2]));
        const Vec3d box_hi(cell_hi(0, c[0]), cell_hi(1, c[1]), cell_hi(2, c[2]));
        if (triangle_box_overlap(box_lo, box_hi, v0, v1, v2) && !detail::keep_going(f, c[0], c[1], c[2])) return;
      }
    }
  }
}

}  // namespace raylab
