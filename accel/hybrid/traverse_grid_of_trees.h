#pragma once
// Walk of the grid of trees: the 3D-DDA (accel/grid/dda.h) over the coarse
// top grid; in every non-empty cell the cell's own tree is traced with the
// ray's segment cut to the cell's interval [t_enter, t_exit], widened by a
// small pad (the cell boxes the trees were built for carry the grid's
// assignment margin, so a hit within rounding of the cell is in the cell's
// tree; the pad lets the interval reach it).
//
// Termination, as in the plain grid (accel/grid/grid_ray_query.h): a hit is
// accepted only once it lies within the part of the ray already walked
// (hit.t <= t_exit of the current cell). A hit found beyond the cell's exit
// (possible within the pad) is kept as the bound for later cells but the walk
// goes on, because a nearer triangle may wait in the next cell.
//
// The inner traversals count their own ray; the walk adds only their node
// and triangle counters, so a ray counts once and nodes_visited = cells
// entered + inner nodes tested.
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "accel/core/hit_recorder.h"
#include "accel/core/grid/dda.h"
#include "accel/hybrid/cell_trees.h"

namespace raylab {

template <typename View>
struct GridOfTreesView {
  DdaGrid dda;
  const uint32_t* cell_tree = nullptr;  // per cell: index into views, or kNoCellTree
  const View* views = nullptr;
  bool empty = true;
};

// Relative pad of a cell's interval, as a fraction of the smallest cell side
// crossed at the ray's largest direction component (far above float rounding
// of t, far below a cell).
inline constexpr double kCellIntervalPad = 1e-4;

// `inner(view, ray, stats)` traces one cell's tree; it is called with a
// sub-ray of the same origin and direction and a narrower [tmin, tmax].
template <bool kAnyHit, bool kCount, typename View, typename Inner>
inline Hit traverse_grid_of_trees(const GridOfTreesView<View>& g, const Ray& ray, TraversalStats* stats,
                                  Inner&& inner) {
  HitRecorder<kAnyHit, kCount> rec(ray, stats);  // counts the ray; holds the answer
  if (g.empty || !ray_is_valid(ray)) return rec.hit();
  const DdaLine line = dda_line(ray, g.dda.lo, g.dda.hi);  // rebased when from far away (dda.h)
  const DdaRay& dr = line.ray;
  const double t_base = line.t_base;
  double t0 = line.smin, t1 = line.smax;
  if (!dda_clip(dr, g.dda.lo, g.dda.hi, t0, t1)) return rec.hit();
  const float dir_max = ray.dir.cwiseAbs().maxCoeff();
  const double min_cell = std::min({g.dda.cell[0], g.dda.cell[1], g.dda.cell[2]});
  const double pad_base = kCellIntervalPad * min_cell / dir_max;
  TraversalStats inner_stats;
  dda_walk(g.dda, dr, t0, t1, [&](int64_t cell, double s_enter, double s_exit) {
    const double t_enter = t_base + s_enter, t_exit = t_base + s_exit;
    const uint32_t tree = g.cell_tree[cell];
    if (tree == kNoCellTree) {
      rec.count_cell(0);
      return false;
    }
    // A cell with a tree is a step; its tree's walk counts its own.
    rec.count_inner();
    // Pad also by a relative amount of t: float rounding of large t.
    const double pad = pad_base + 1e-6 * std::max(std::fabs(t_enter), std::fabs(t_exit));
    Ray sub = ray;
    sub.tmin = std::max(ray.tmin, static_cast<float>(t_enter - pad));
    // The last cell keeps the whole remaining segment (hits rounded just
    // past the grid's far side).
    const float bound = rec.tmax();
    sub.tmax = s_exit >= t1 ? bound : std::min(bound, static_cast<float>(t_exit + pad));
    if (!(sub.tmin <= sub.tmax)) return false;
    const Hit h = inner(g.views[tree], sub, kCount ? &inner_stats : nullptr);
    if (h.valid()) {
      rec.record(h.t, h.u, h.v, h.prim);
      if constexpr (kAnyHit) return true;
    }
    return rec.found() && static_cast<double>(rec.hit().t) <= t_exit;
  });
  rec.count_walk(inner_stats);
  return rec.hit();
}

}  // namespace raylab
