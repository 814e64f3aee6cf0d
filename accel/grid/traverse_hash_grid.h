#pragma once
// Traversal of the hashed grid: the same 3D-DDA walk as the dense grid
// (dda.h); each visited cell is looked up in the hash table by its linear
// index, and a cell that is not stored is empty.
#include <cstdint>

#include "accel/grid/cell_hash_table.h"
#include "accel/grid/dda.h"
#include "accel/grid/grid_ray_query.h"

namespace raylab {

struct HashGridView {
  DdaGrid dda;
  const CellHashTable* table = nullptr;
  const uint32_t* refs = nullptr;
  const GridTriangle* tris = nullptr;
  bool empty = true;
};

template <TriangleTest kTest, bool kAnyHit, bool kCount>
inline Hit traverse_hash_grid(const HashGridView& g, const Ray& ray, TraversalStats* stats) {
  if constexpr (kCount) stats->rays++;
  if (g.empty || !ray_is_valid(ray) || !(ray.tmin <= ray.tmax)) return Hit{};
  const DdaRay dr(ray);
  double t0 = ray.tmin, t1 = ray.tmax;
  if (!dda_clip(dr, g.dda.lo, g.dda.hi, t0, t1)) return Hit{};
  GridRayQuery<kTest> q(ray);
  dda_walk(g.dda, dr, t0, t1, [&](int64_t cell, double, double t_exit) {
    if constexpr (kCount) stats->nodes_visited++;
    const CellSlot* slot = g.table->find(static_cast<uint64_t>(cell));
    if (!slot) return false;
    if (q.template test_cell<kAnyHit, kCount>(g.refs + slot->begin, slot->count, g.tris, stats)) return true;
    if constexpr (kAnyHit) return false;
    return q.done_at(t_exit);
  });
  return q.hit;
}

}  // namespace raylab
