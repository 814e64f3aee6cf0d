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
//  - boundary distances are recomputed from the cell index at every step
//    ((boundary - org) * inv_dir, in double) instead of accumulated with
//    tDelta, so no error builds up along long walks;
//  - a direction component that is zero (+0 or -0) gets step 0 and a next
//    boundary at +infinity; the ray then stays in its slab of cells (a ray
//    lying exactly in a cell boundary plane stays in the cell above it,
//    which the builders' cell margin makes sufficient);
//  - the entry cell is clamped into the grid, so an entry point rounded just
//    outside the grid still starts in the boundary cell.
#include <cmath>
#include <cstdint>
#include <limits>

#include "accel/core/ray.h"
#include "accel/grid/dda_grid.h"

namespace raylab {

// Per-ray constants of the walk (double precision).
struct DdaRay {
  double org[3];
  double dir[3];
  double inv_dir[3];  // 1/dir, unused (infinity) where dir is zero
  int32_t step[3];    // +1, -1, or 0 for a zero component (either sign)

  explicit DdaRay(const Ray& r) {
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
inline bool dda_clip(const DdaRay& r, const double lo[3], const double hi[3], double& t0, double& t1) {
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
template <typename Visit>
inline bool dda_walk(const DdaGrid& g, const DdaRay& r, double t0, double t1, Visit&& visit) {
  int32_t c[3];
  double next[3];
  int64_t delta[3];
  int64_t index = 0;
  for (int a = 0; a < 3; ++a) {
    const double p = r.org[a] + t0 * r.dir[a];
    c[a] = g.coord(a, p);
    index += c[a] * g.stride[a];
    delta[a] = r.step[a] * g.stride[a];
    if (r.step[a] > 0) next[a] = (g.boundary(a, c[a] + 1) - r.org[a]) * r.inv_dir[a];
    else if (r.step[a] < 0) next[a] = (g.boundary(a, c[a]) - r.org[a]) * r.inv_dir[a];
    else next[a] = std::numeric_limits<double>::infinity();
  }
  double t_enter = t0;
  while (true) {
    const int axis = next[0] < next[1] ? (next[0] < next[2] ? 0 : 2) : (next[1] < next[2] ? 1 : 2);
    const double t_next = next[axis];
    const double t_exit = t_next < t1 ? t_next : t1;
    if (visit(index, t_enter, t_exit)) return true;
    if (!(t_next < t1)) return false;
    c[axis] += r.step[axis];
    if (static_cast<uint32_t>(c[axis]) >= static_cast<uint32_t>(g.res[axis])) return false;
    index += delta[axis];
    t_enter = t_next;
    next[axis] = (g.boundary(axis, c[axis] + (r.step[axis] > 0 ? 1 : 0)) - r.org[axis]) * r.inv_dir[axis];
  }
}

}  // namespace raylab
