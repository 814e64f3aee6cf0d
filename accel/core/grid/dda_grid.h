#pragma once
// The geometry of one uniform grid as the 3D-DDA and the builders see it:
// box, cell size and resolution, in double precision.
//
// Why double: the DDA computes the distance to every cell boundary afresh as
// (boundary - org) / dir, never by accumulating increments, and in double
// the rounding of those distances (~1e-16 relative) is far below anything a
// float triangle test can resolve. The builders enlarge every cell by a
// margin (see assignment_margin) that covers both this and the fuzz of the
// float watertight test, so a triangle whose hit lies within rounding of a
// cell is always listed in that cell.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "base/aabb.h"
#include "accel/core/grid/grid_resolution.h"

namespace raylab {

struct DdaGrid {
  double lo[3] = {0, 0, 0};
  double hi[3] = {0, 0, 0};
  double cell[3] = {1, 1, 1};
  double inv_cell[3] = {1, 1, 1};
  int32_t res[3] = {1, 1, 1};
  int64_t stride[3] = {1, 1, 1};  // linear cell index = x*stride[0] + y*stride[1] + z*stride[2]
  // Distance scale of the triangle test's rounding the cell margin must
  // cover (see grid_error_scale); only the builders read it. A sub-grid
  // takes its root grid's, since rays reach it from anywhere in the root.
  double error_scale = 0.0;

  uint64_t cells() const { return static_cast<uint64_t>(res[0]) * res[1] * res[2]; }

  // Cell coordinate of x along `axis`, clamped into the grid.
  int32_t coord(int axis, double x) const {
    const double c = std::floor((x - lo[axis]) * inv_cell[axis]);
    if (!(c >= 0.0)) return 0;  // also NaN
    return c >= res[axis] ? res[axis] - 1 : static_cast<int32_t>(c);
  }
  double boundary(int axis, int64_t c) const { return lo[axis] + static_cast<double>(c) * cell[axis]; }
  int64_t index(int32_t x, int32_t y, int32_t z) const { return x * stride[0] + y * stride[1] + z * stride[2]; }

  // The box of cell (x, y, z), from the same boundaries the DDA uses
  // (structure outlines; no assignment margin).
  Aabb cell_box(int64_t x, int64_t y, int64_t z) const {
    const int64_t c[3] = {x, y, z};
    Aabb b;
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = static_cast<float>(boundary(a, c[a]));
      b.hi[a] = static_cast<float>(boundary(a, c[a] + 1));
    }
    return b;
  }
  // The box of the cell with linear index x + res[0] * (y + res[1] * z).
  Aabb cell_box_of_index(uint64_t index) const {
    const uint64_t rx = static_cast<uint64_t>(res[0]), ry = static_cast<uint64_t>(res[1]);
    return cell_box(static_cast<int64_t>(index % rx), static_cast<int64_t>((index / rx) % ry),
                    static_cast<int64_t>(index / (rx * ry)));
  }
};

// Why the margin is sized from the grid's extent, not its coordinates.
// The watertight test (Woop et al. 2013) decides on float p - org; the
// difference of two floats is rounded once, to within half an ulp of
// |p - org|, and the shear and edge functions add a few ulps of that same
// size. So the test's rounding moves a triangle by a few ulps of the
// distance between the ray's origin and the triangle (the k-d tree's margin
// uses the same bound, traverse_kdtree.h), whatever the absolute
// coordinates are. Sized from the coordinates instead, a mesh of size 2 at
// 3e5 would get a margin of 0.6, larger than the mesh: every cell would hold
// every triangle (test GridAccel.MeshFarFromTheOriginCostsWhatItCostsAtTheOrigin).
//
// The scale S is the smaller of the grid's largest coordinate (the old
// bound, still right near the origin) and kOriginReach times its largest
// side. 16 ulps of S cover every ray whose origin lies within about
// 2 S - diagonal ~ 6 grid sides of the grid box (cameras, bounces, shadow
// rays, stress's rays from inside). A ray from much farther away rounds by
// more than the margin, but only on triangles it passes within a few
// ulps(|p - org|) of: the oracle counts those as grazing (its tolerance is
// 1e-5 of that scale, the rounding 1e-7), so they are ties, not wrong hits
// - exactly as for brute force, whose float answer is no closer.
inline constexpr double kCellMarginRelative = 1e-3;
inline constexpr double kCellMarginUlps = 16.0 * 0x1p-23;
inline constexpr double kOriginReach = 4.0;

inline double grid_error_scale(const double lo[3], const double hi[3]) {
  double magnitude = 0.0, largest = 0.0;
  for (int a = 0; a < 3; ++a) {
    magnitude = std::max({magnitude, std::fabs(lo[a]), std::fabs(hi[a])});
    largest = std::max(largest, hi[a] - lo[a]);
  }
  return std::min(magnitude, kOriginReach * largest);
}

// A grid with origin `lo`, cell sides `cell` (> 0) and resolution `res`.
// Boundaries are lo + c * cell, so two grids made from the same lo and cell
// (the builder's and the traversal's) agree exactly.
inline DdaGrid make_dda_grid_from_cells(const double lo[3], const double cell[3], const int32_t res[3]) {
  DdaGrid g;
  for (int a = 0; a < 3; ++a) {
    g.lo[a] = lo[a];
    g.cell[a] = cell[a];
    g.inv_cell[a] = 1.0 / cell[a];
    g.res[a] = res[a];
    g.hi[a] = lo[a] + static_cast<double>(res[a]) * cell[a];
  }
  g.stride[0] = 1;
  g.stride[1] = res[0];
  g.stride[2] = static_cast<int64_t>(res[0]) * res[1];
  return g;
}

// A grid over [lo, hi] (hi > lo on every axis) with the given resolution.
inline DdaGrid make_dda_grid(const Vec3d& lo, const Vec3d& hi, const GridRes& res) {
  double cell[3];
  for (int a = 0; a < 3; ++a) cell[a] = (hi[a] - lo[a]) / res[a];
  DdaGrid g = make_dda_grid_from_cells(lo.data(), cell, res.data());
  g.error_scale = grid_error_scale(g.lo, g.hi);
  return g;
}

// Enlargement of every cell when triangles are assigned to cells: 1/1000 of
// a cell side, plus 16 float ulps of the grid's error scale.
inline Vec3d assignment_margin(const DdaGrid& g) {
  return Vec3d(kCellMarginRelative * g.cell[0], kCellMarginRelative * g.cell[1], kCellMarginRelative * g.cell[2])
      .array() + kCellMarginUlps * g.error_scale;
}

// The box a grid is laid over: `bounds` padded on every side by 1e-5 of its
// largest side, and at least by the cell margin's ulps term (a point where
// the triangle test may report a hit must lie in the box to be walked), so
// triangles on the boundary lie inside and a flat side gets a non-zero
// thickness.
inline void padded_grid_box(const Aabb& bounds, Vec3d& lo, Vec3d& hi) {
  lo = bounds.lo.cast<double>();
  hi = bounds.hi.cast<double>();
  const double largest = (hi - lo).maxCoeff();
  const double pad = std::max({1e-5 * largest, kCellMarginUlps * grid_error_scale(lo.data(), hi.data()), 1e-30});
  lo.array() -= pad;
  hi.array() += pad;
}

}  // namespace raylab
