#pragma once
// 6-connected 3D-DDA: Amanatides & Woo, "A Fast Voxel Traversal Algorithm
// for Ray Tracing", Eurographics 1987.
//
// The walk starts in the cell holding the ray's entry point and repeatedly
// steps into the face-adjacent cell whose boundary the ray crosses first, so
// every cell the ray passes through is visited, in order, with its parametric
// interval [t_enter, t_exit]. When the ray crosses an edge or corner exactly
// the axes are stepped one at a time (a zero-length visit of the cell in
// between), which keeps the walk 6-connected.
//
// Differences from the paper, for robustness:
//  - boundary distances are kept in double precision, so the error that
//    builds up along long walks stays negligible (see dda_walk);
//  - a direction component that is zero (+0 or -0) gets step 0 and a next
//    boundary at +infinity; the ray then stays in its slab of cells (a ray
//    lying exactly in a cell boundary plane stays in the cell above it,
//    which the builders' cell margin makes sufficient);
//  - the entry cell is clamped into the grid, so an entry point rounded just
//    outside the grid still starts in the boundary cell.
#include <cmath>
#include <cstdint>
#include <limits>

#include "base/ray.h"
#include "accel/grid/dda_grid.h"

namespace raylab {

// Per-ray constants of the walk (double precision).
struct DdaRay {
  double org[3];
  double dir[3];
  double inv_dir[3];  // 1/dir, unused (infinity) where dir is zero
  int32_t step[3];    // +1, -1, or 0 for a zero component (either sign)

  [[gnu::always_inline]] explicit DdaRay(const Ray& r) {
    for (int a = 0; a < 3; ++a) {
      org[a] = r.org[a];
      dir[a] = r.dir[a];
      if (dir[a] > 0.0) {
        step[a] = 1;
        inv_dir[a] = 1.0 / dir[a];
      } else if (dir[a] < 0.0) {
        step[a] = -1;
        inv_dir[a] = 1.0 / dir[a];
      } else {
        step[a] = 0;
        inv_dir[a] = std::numeric_limits<double>::infinity();
      }
    }
  }
};

// Clips [t0, t1] to the box [lo, hi]; false when nothing is left. A zero
// direction component keeps the interval when the origin lies in the slab
// (boundaries included) and empties it otherwise.
[[gnu::always_inline]] inline bool dda_clip(const DdaRay& r, const double lo[3], const double hi[3], double& t0, double& t1) {
  for (int a = 0; a < 3; ++a) {
    if (r.step[a] == 0) {
      if (r.org[a] < lo[a] || r.org[a] > hi[a]) return false;
      continue;
    }
    double tn = (lo[a] - r.org[a]) * r.inv_dir[a];
    double tf = (hi[a] - r.org[a]) * r.inv_dir[a];
    if (r.step[a] < 0) std::swap(tn, tf);
    t0 = tn > t0 ? tn : t0;
    t1 = tf < t1 ? tf : t1;
  }
  return t0 <= t1;
}

// Walks the cells of `g` that the ray crosses over [t0, t1], which must
// already be clipped to the grid's box. Calls visit(linear_index, t_enter,
// t_exit) for each cell in order; the walk stops when visit returns true
// (and then returns true), or when the ray leaves the grid or passes t1.
//
// The first boundary distance on each axis is computed from the entry cell;
// later ones by adding the per-cell step tDelta, as in the paper. In double
// precision k steps accumulate at most about k * 2^-53 of relative error,
// which stays far below the builders' cell margin (1e-3 of a cell) for any
// walk through a grid of at most 2^20 cells per axis.
template <typename Visit>
inline bool dda_walk(const DdaGrid& g, const DdaRay& r, double t0, double t1, Visit&& visit) {
  int32_t c[3];
  double next[3], delta_t[3];
  int64_t index = 0;
  for (int a = 0; a < 3; ++a) {
    const double p = r.org[a] + t0 * r.dir[a];
    c[a] = g.coord(a, p);
    index += c[a] * g.stride[a];
    if (r.step[a] > 0) next[a] = (g.boundary(a, c[a] + 1) - r.org[a]) * r.inv_dir[a];
    else if (r.step[a] < 0) next[a] = (g.boundary(a, c[a]) - r.org[a]) * r.inv_dir[a];
    else next[a] = std::numeric_limits<double>::infinity();
    delta_t[a] = r.step[a] != 0 ? g.cell[a] * std::fabs(r.inv_dir[a]) : 0.0;
  }
  // Scalars, so the loop keeps its state in registers.
  double nx = next[0], ny = next[1], nz = next[2];
  int32_t cx = c[0], cy = c[1], cz = c[2];
  const int32_t sx = r.step[0], sy = r.step[1], sz = r.step[2];
  const int64_t ix = sx * g.stride[0], iy = sy * g.stride[1], iz = sz * g.stride[2];
  const uint32_t rx = static_cast<uint32_t>(g.res[0]), ry = static_cast<uint32_t>(g.res[1]),
                 rz = static_cast<uint32_t>(g.res[2]);
  double t_enter = t0;
  while (true) {
    // The axis whose boundary comes first; one axis per step (6-connected).
    const int axis = nx < ny ? (nx < nz ? 0 : 2) : (ny < nz ? 1 : 2);
    const double t_next = axis == 0 ? nx : (axis == 1 ? ny : nz);
    if (visit(index, t_enter, t_next < t1 ? t_next : t1)) return true;
    if (!(t_next < t1)) return false;
    t_enter = t_next;
    if (axis == 0) {
      cx += sx;
      if (static_cast<uint32_t>(cx) >= rx) return false;
      index += ix;
      nx += delta_t[0];
    } else if (axis == 1) {
      cy += sy;
      if (static_cast<uint32_t>(cy) >= ry) return false;
      index += iy;
      ny += delta_t[1];
    } else {
      cz += sz;
      if (static_cast<uint32_t>(cz) >= rz) return false;
      index += iz;
      nz += delta_t[2];
    }
  }
}

}  // namespace raylab
