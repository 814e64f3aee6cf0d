#pragma once
// Closest-hit / any-hit traversal of a dense uniform grid: clip the ray to
// the grid's box, walk the cells with the 3D-DDA (dda.h), test each cell's
// triangles (mailboxed), stop by the rule of grid_ray_query.h. The query
// kind (kAnyHit) and the counters (kCount) are compile-time switches of the
// one routine.
#include <cstdint>

#include "accel/grid/dda.h"
#include "accel/grid/grid_ray_query.h"

namespace raylab {

struct UniformGridView {
  DdaGrid dda;
  const uint32_t* offsets = nullptr;
  const uint32_t* refs = nullptr;
  const GridTriangle* tris = nullptr;
  bool empty = true;
};

template <TriangleTest kTest, bool kAnyHit, bool kCount>
inline Hit traverse_uniform_grid(const UniformGridView& g, const Ray& ray, TraversalStats* stats) {
  if constexpr (kCount) stats->rays++;
  if (g.empty || !ray_is_valid(ray) || !(ray.tmin <= ray.tmax)) return Hit{};
  const DdaRay dr(ray);
  double t0 = ray.tmin, t1 = ray.tmax;
  if (!dda_clip(dr, g.dda.lo, g.dda.hi, t0, t1)) return Hit{};
  GridRayQuery<kTest> q(ray);
  dda_walk(g.dda, dr, t0, t1, [&](int64_t cell, double, double t_exit) {
    if constexpr (kCount) stats->nodes_visited++;
    const uint32_t begin = g.offsets[cell], end = g.offsets[cell + 1];
    if (begin == end) return false;
    if (q.template test_cell<kAnyHit, kCount>(g.refs + begin, end - begin, g.tris, stats)) return true;
    if constexpr (kAnyHit) return false;
    return q.done_at(t_exit);
  });
  return q.hit;
}

}  // namespace raylab
