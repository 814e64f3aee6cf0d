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
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "base/ray.h"
#include "accel/core/grid/dda_grid.h"

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

// The same line walked the other way: direction, reciprocal and step
// negated, the origin kept, so the parameter becomes s = -t and [t0, t1]
// becomes [-t1, -t0]. Negation is exact, so every point org + s * dir' equals
// org + t * dir bit for bit: the reversed walk visits the same cells in the
// opposite order (any-hit walks from the segment's far end,
// accel/core/any_hit_order.h).
[[gnu::always_inline]] inline DdaRay reversed(const DdaRay& r) {
  DdaRay out = r;
  for (int a = 0; a < 3; ++a) {
    out.dir[a] = -r.dir[a];
    out.step[a] = -r.step[a];
    if (r.step[a] != 0) out.inv_dir[a] = -r.inv_dir[a];
  }
  return out;
}

// The line and parameter range a walk takes: as given, or (kFarFirst, any
// hit from the far end) reversed over [-t1, -t0]. One definition for every
// grid walk; a plain value, not another lambda around the walk (grid2's
// nested walks stay inlined that way).
struct DdaSegment {
  DdaRay ray;
  double t0, t1;
};
template <bool kFarFirst>
[[gnu::always_inline]] inline DdaSegment walk_order(const DdaRay& r, double t0, double t1) {
  if constexpr (kFarFirst) return DdaSegment{reversed(r), -t1, -t0};
  else return DdaSegment{r, t0, t1};
}

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

// The line a grid walk follows, rebased for rays from far away. The walk
// finds cells from points org + t * dir and crossing distances
// (plane - org) / dir; for an origin at distance D from the grid both carry
// rounding errors of about D * 2^-53, which for D = 2^50 is a quarter of a
// unit: the walk then starts or ends cells away from where the ray enters
// and leaves a unit-sized scene, and misses triangles (found by fuzz_rays: a
// ray from z = -2^50 along +z into the unit box, whose closest-hit walk
// stopped one cell short of the back wall). So when the origin lies more
// than kDdaRebaseFactor box extents outside the box, the walk starts from
// the point of the line at the clipped entry parameter t_base, computed with
// one rounding (fused multiply-add: a point of the line, off it by an ulp of
// its own coordinates), and its parameter is s = t - t_base; [tmin, tmax]
// becomes [tmin - t_base, tmax - t_base], widened by 2^-48 of t_base (the
// entry parameter's own error). The triangle tests keep the ray, so the
// answers are the ray's; a walker compares hit distances with t_base + s.
// The entry parameter itself carries D * 2^-53 / |dir| of rounding error, so
// one rebase lands D * 2^-53 from the box along the line: 2^51 units for
// D = 2^104 (found by fuzz_rays: a ray from z = -2^104 whose two-level grid
// walk, at s ~ 2^58 with an ulp of 64, lost the back wall). The rebase is
// therefore repeated from the new point while it is still that far out;
// each round multiplies the distance by about 2^-53, so float origins
// (D < 2^128) need at most three.
// Nearer origins keep the plain line (t_base = 0): their errors are at most
// 2^16 extents * 2^-53 = 2^-37 of the grid's extent, far below the cell margin.
inline constexpr double kDdaRebaseFactor = 65536.0;

struct DdaLine {
  DdaRay ray;
  double t_base = 0.0;      // t = t_base + s
  double smin, smax;        // the ray's [tmin, tmax] in the walk's parameter s
};

[[gnu::always_inline]] inline DdaLine dda_line(const Ray& r, const double lo[3], const double hi[3]) {
  DdaLine line{DdaRay(r), 0.0, r.tmin, r.tmax};
  double extent = 0.0;
  for (int a = 0; a < 3; ++a) extent = std::max(extent, hi[a] - lo[a]);
  const auto far_out = [&] {
    double outside = 0.0;
    for (int a = 0; a < 3; ++a)
      outside = std::max(outside, std::max(lo[a] - line.ray.org[a], line.ray.org[a] - hi[a]));
    return outside > kDdaRebaseFactor * extent;
  };
  if (!far_out()) [[likely]]
    return line;
  double t0 = r.tmin, t1 = r.tmax;
  if (!dda_clip(line.ray, lo, hi, t0, t1)) return line;  // a miss either way
  for (int round = 0;; ++round) {
    line.t_base += t0;
    for (int a = 0; a < 3; ++a) line.ray.org[a] = std::fma(t0, line.ray.dir[a], line.ray.org[a]);
    // The next round re-enters the box from the new point along the whole
    // line (the ray's interval is applied below, through t_base).
    t0 = -std::numeric_limits<double>::infinity(), t1 = std::numeric_limits<double>::infinity();
    if (round == 3 || !far_out() || !dda_clip(line.ray, lo, hi, t0, t1)) break;
  }
  const double pad = std::fabs(line.t_base) * 0x1p-48;
  line.smin = (static_cast<double>(r.tmin) - line.t_base) - pad;
  line.smax = (static_cast<double>(r.tmax) - line.t_base) + pad;
  return line;
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
//
// With empty-space skipping (dda_walk_skipping), clearance(linear_index)
// returns the Chebyshev distance d, in cells, from a visited cell to the
// nearest occupied one (cell_clearance.h; 0 = occupied). When d >= 3 every
// cell of the cube of cells within d - 1 of it is empty, and the ray, which
// is inside that cube, leaves it at once: the walk restarts in the first
// cell past the cube's exit face (dda_jump) instead of stepping through it.
namespace dda_detail {

// The walk's state: cell coordinates, linear index, next boundary distance per axis.
struct Cursor {
  int32_t c[3];
  int64_t index;
  double next[3];
};

// Boundary distances of the cell c (afresh, from the cell's planes).
[[gnu::always_inline]] inline void set_next(const DdaGrid& g, const DdaRay& r, Cursor& k) {
  k.index = 0;
  for (int a = 0; a < 3; ++a) {
    k.index += k.c[a] * g.stride[a];
    if (r.step[a] > 0) k.next[a] = (g.boundary(a, k.c[a] + 1) - r.org[a]) * r.inv_dir[a];
    else if (r.step[a] < 0) k.next[a] = (g.boundary(a, k.c[a]) - r.org[a]) * r.inv_dir[a];
    else k.next[a] = std::numeric_limits<double>::infinity();
  }
}

// Leaves the empty cube of cells within `reach` of k.c: moves k to the first
// cell past the cube's exit face and returns the exit distance (>= t1, or
// false, when the ray ends or leaves the grid first). On the exit axis the
// coordinate jumps past the face; on the others it takes the exit point's
// cell, clamped into the cube and never backwards, so the walk always ends
// (irgrid's rule, traverse_irgrid.h).
[[gnu::always_inline]] inline bool jump(const DdaGrid& g, const DdaRay& r, int32_t reach, double t1, Cursor& k,
                                        double& t_exit) {
  t_exit = std::numeric_limits<double>::infinity();
  int exit_axis = 0;
  for (int a = 0; a < 3; ++a) {
    if (r.step[a] == 0) continue;
    const int64_t face = r.step[a] > 0 ? int64_t{k.c[a]} + reach + 1 : int64_t{k.c[a]} - reach;
    const double t = (g.boundary(a, face) - r.org[a]) * r.inv_dir[a];
    if (t < t_exit) {
      t_exit = t;
      exit_axis = a;
    }
  }
  if (!(t_exit < t1)) return false;
  for (int a = 0; a < 3; ++a) {
    if (a == exit_axis || r.step[a] == 0) continue;
    const int32_t at = g.coord(a, r.org[a] + t_exit * r.dir[a]);
    if (r.step[a] > 0) k.c[a] = std::clamp(at, k.c[a], k.c[a] + reach);
    else k.c[a] = std::clamp(at, k.c[a] - reach, k.c[a]);
  }
  k.c[exit_axis] += r.step[exit_axis] * (reach + 1);
  if (static_cast<uint32_t>(k.c[exit_axis]) >= static_cast<uint32_t>(g.res[exit_axis])) return false;
  set_next(g, r, k);
  return true;
}

// Jumps only from cells of clearance d >= kMinClearance (a cube 5 cells
// across or more): a jump costs about as much as two or three steps (3, 2
// and 4 measured alike on bunny, sponza and conference).
inline constexpr int kMinClearance = 3;

template <bool kSkip, typename Clearance, typename Visit>
[[gnu::always_inline]] inline bool walk(const DdaGrid& g, const DdaRay& r, double t0, double t1, Clearance&& clearance,
                                        Visit&& visit) {
  Cursor k;
  for (int a = 0; a < 3; ++a) k.c[a] = g.coord(a, r.org[a] + t0 * r.dir[a]);
  set_next(g, r, k);
  double delta_t[3];
  for (int a = 0; a < 3; ++a) delta_t[a] = r.step[a] != 0 ? g.cell[a] * std::fabs(r.inv_dir[a]) : 0.0;
  const int64_t ix = r.step[0] * g.stride[0], iy = r.step[1] * g.stride[1], iz = r.step[2] * g.stride[2];
  const uint32_t rx = static_cast<uint32_t>(g.res[0]), ry = static_cast<uint32_t>(g.res[1]),
                 rz = static_cast<uint32_t>(g.res[2]);
  double t_enter = t0;
  while (true) {
    // Scalars, so the loop keeps its state in registers.
    double nx = k.next[0], ny = k.next[1], nz = k.next[2];
    int32_t cx = k.c[0], cy = k.c[1], cz = k.c[2];
    int64_t index = k.index;
    while (true) {
      const double t_next = std::min(nx, std::min(ny, nz));
      if (visit(index, t_enter, t_next < t1 ? t_next : t1)) return true;
      if (!(t_next < t1)) return false;
      if constexpr (kSkip) {
        const int d = clearance(index);
        if (d >= kMinClearance) {
          k.c[0] = cx, k.c[1] = cy, k.c[2] = cz;
          if (!jump(g, r, d - 1, t1, k, t_enter)) return false;
          break;
        }
      }
      t_enter = t_next;
      // The axis whose boundary comes first, without branches: one axis per
      // step (6-connected; ties go to x, then y).
      const bool ax = nx == t_next;
      const bool ay = !ax && ny == t_next;
      const bool az = !ax && !ay;
      nx += ax ? delta_t[0] : 0.0;
      ny += ay ? delta_t[1] : 0.0;
      nz += az ? delta_t[2] : 0.0;
      cx += ax ? r.step[0] : 0;
      cy += ay ? r.step[1] : 0;
      cz += az ? r.step[2] : 0;
      index += ax ? ix : (ay ? iy : iz);
      if ((static_cast<uint32_t>(cx) >= rx) | (static_cast<uint32_t>(cy) >= ry) | (static_cast<uint32_t>(cz) >= rz))
        return false;
    }
  }
}

}  // namespace dda_detail

template <typename Visit>
inline bool dda_walk(const DdaGrid& g, const DdaRay& r, double t0, double t1, Visit&& visit) {
  return dda_detail::walk<false>(g, r, t0, t1, [](int64_t) { return 0; }, visit);
}

// The walk with empty-space skipping (see above).
template <typename Clearance, typename Visit>
inline bool dda_walk_skipping(const DdaGrid& g, const DdaRay& r, double t0, double t1, Clearance&& clearance,
                              Visit&& visit) {
  return dda_detail::walk<true>(g, r, t0, t1, clearance, visit);
}

}  // namespace raylab
