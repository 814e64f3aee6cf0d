#pragma once
// Tracing with entry points (entry_grid.h), in two phases, both with the
// k-d tree's own traversal (accel/kdtree/traverse_kdtree.h):
//  1. a ray with tmin >= 0 whose origin lies in a grid cell and inside the
//     cell's entry node region R walks only R's subtree. Every point of the
//     ray between tmin and the exit from R lies in R (R is convex and holds
//     the origin), and every triangle touching R is in the subtree, so a hit
//     no farther than the exit (a lower bound of it, t_low) is the answer.
//  2. otherwise the walk restarts at the root over [max(tmin, t_low), best]
//     (no neighbour links: the restart re-descends the tree, which the node
//     counters show). A phase-2 hit replaces the phase-1 one only when
//     strictly nearer, as in the hit recorder.
// Rays starting outside the grid, or with tmin < 0, start at the root.
#include <algorithm>
#include <cmath>

#include "accel/hybrid/entry_grid.h"

namespace raylab {

struct EntryGridView {
  KdTreeView root;
  DdaGrid dda;
  const EntryNode* entry = nullptr;
  bool empty = true;
};

// A lower bound of the distance at which the ray leaves `r` (origin inside r).
inline float region_exit_lower_bound(const Aabb& r, const Ray& ray) {
  double t = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    const double d = ray.dir[a];
    if (d > 0.0) t = std::min(t, (static_cast<double>(r.hi[a]) - ray.org[a]) / d);
    else if (d < 0.0) t = std::min(t, (static_cast<double>(r.lo[a]) - ray.org[a]) / d);
  }
  // Rounded down to float, minus a relative margin for the float walk.
  const float f = static_cast<float>(t * (1.0 - 1e-6));
  return std::isfinite(f) ? std::nextafter(f, -std::numeric_limits<float>::infinity()) : f;
}

template <TriangleTest kTest, bool kAnyHit, bool kCount>
inline Hit traverse_entry_grid(const EntryGridView& g, const Ray& ray, TraversalStats* stats) {
  if (g.empty || !ray_is_valid(ray)) return HitRecorder<kAnyHit, kCount>(ray, stats).hit();
  const Vec3f& o = ray.org;
  bool inside = ray.tmin >= 0.0f;
  for (int a = 0; a < 3 && inside; ++a) inside = o[a] >= g.dda.lo[a] && o[a] <= g.dda.hi[a];
  if (inside) {
    const EntryNode& e = g.entry[g.dda.index(g.dda.coord(0, o[0]), g.dda.coord(1, o[1]), g.dda.coord(2, o[2]))];
    if (e.node != 0 && e.region.contains(o)) {
      KdTreeView sub = g.root;
      sub.root = e.node;
      sub.bounds = e.region;
      const Hit first = traverse_kdtree<kTest, kAnyHit, kCount>(sub, ray, stats);  // counts the ray
      if (first.valid() && kAnyHit) return first;
      const float t_low = region_exit_lower_bound(e.region, ray);
      if (first.valid() && first.t <= t_low) return first;
      Ray rest = ray;
      rest.tmin = std::max(ray.tmin, t_low);
      if (first.valid()) rest.tmax = first.t;
      if (!(rest.tmin <= rest.tmax)) return first;
      TraversalStats rest_stats;
      const Hit second = traverse_kdtree<kTest, kAnyHit, kCount>(g.root, rest, kCount ? &rest_stats : nullptr);
      if constexpr (kCount) stats->add_walk(rest_stats);
      if (second.valid() && (!first.valid() || second.t < first.t)) return second;
      return first;
    }
  }
  return traverse_kdtree<kTest, kAnyHit, kCount>(g.root, ray, stats);
}

}  // namespace raylab
