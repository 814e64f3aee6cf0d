#pragma once
// The per-ray state every grid kernel carries through its walk: the triangle
// test's precomputation, the mailbox, and the hit recorder (which owns hit
// acceptance and the counters, accel/core/hit_recorder.h); and the walk of a
// single-level grid, shared by `grid` and `hashgrid`, which differ only in
// how a cell's triangle list is found.
//
// Termination rule (closest hit): after a cell's triangles are tested, the
// walk stops only if the closest hit so far lies within the part of the ray
// already walked (hit.t <= the cell's t_exit). A hit farther away, found on a
// triangle that extends into later cells, is kept (it shortens tmax for
// every later test) but not accepted yet: a nearer triangle may still wait in
// the next cell. This is also what makes mailboxing safe: a triangle skipped
// by the mailbox has already had its hit recorded.
#include <cstdint>

#include "accel/core/hit_recorder.h"
#include "accel/core/leaf_triangle.h"
#include "accel/grid/dda.h"
#include "accel/grid/mailbox.h"

namespace raylab {

template <TriangleTest kTest, typename Recorder>
struct GridRayQuery {
  const Ray& ray;
  TrianglePrecompute<kTest> pre;
  RayMailbox mailbox;
  // Held by value, as a member next to the mailbox: the walk keeps the bound
  // in this one object (measured: a reference to an outer recorder costs
  // the grids 5-20 %).
  Recorder rec;

  GridRayQuery(const Ray& r, TraversalStats* stats) : ray(r), pre(r), rec(r, stats) {}

  // Tests the triangles ids[0..count) not yet tested by this ray. Returns
  // true when the recorder stops at the first hit and one was found.
  bool test_cell(const uint32_t* ids, uint32_t count, const LeafTriangle* tris) {
    for (uint32_t i = 0; i < count; ++i) {
      const uint32_t id = ids[i];
      if (mailbox.seen(id)) continue;
      if (intersect_leaf_triangle(pre, ray, tris[id], rec)) {
        if constexpr (Recorder::kStopAtFirstHit) return true;
      }
    }
    return false;
  }

  // Closest hit: true once the best hit lies within [.., t_exit].
  bool done_at(double t_exit) const { return rec.found() && static_cast<double>(rec.hit().t) <= t_exit; }

  // One cell entered by the walk: test its list, then apply the stopping rule.
  bool visit_cell(const uint32_t* ids, uint32_t count, const LeafTriangle* tris, double t_exit) {
    if (test_cell(ids, count, tris)) return true;
    if constexpr (Recorder::kStopAtFirstHit) return false;
    return done_at(t_exit);
  }
};

// A single-level grid as its walk sees it; `Cells` finds a cell's list of
// references (dense compressed rows, or a hash table of occupied cells).
template <typename Cells>
struct SingleLevelGridView {
  DdaGrid dda;
  Cells cells;
  const uint32_t* refs = nullptr;
  const LeafTriangle* tris = nullptr;
  bool empty = true;
};

// The frame of every grid walk: the recorder, the validity check, the ray
// clipped to the grid's box; `walk(dr, t0, t1, query)` then walks the cells
// of [t0, t1] and the recorder's hit is the answer.
template <TriangleTest kTest, bool kAnyHit, bool kCount, typename Walk>
[[gnu::always_inline]] inline Hit walk_grid(const DdaGrid& grid, bool empty, const Ray& ray, TraversalStats* stats,
                                            Walk&& walk) {
  using Recorder = HitRecorder<kAnyHit, kCount>;
  // A ray that never reaches the cells still counts (the recorder counts it).
  if (empty || !ray_is_valid(ray)) return Recorder(ray, stats).hit();
  const DdaRay dr(ray);
  double t0 = ray.tmin, t1 = ray.tmax;
  if (!dda_clip(dr, grid.lo, grid.hi, t0, t1)) return Recorder(ray, stats).hit();
  GridRayQuery<kTest, Recorder> q(ray, stats);
  walk(dr, t0, t1, q);
  return q.rec.hit();
}

// Closest-hit / any-hit walk of a single-level grid: the cells of the
// 3D-DDA (dda.h), each non-empty cell's triangles tested (mailboxed), the
// stopping rule above.
template <TriangleTest kTest, bool kAnyHit, bool kCount, typename Cells>
inline Hit traverse_grid(const SingleLevelGridView<Cells>& g, const Ray& ray, TraversalStats* stats) {
  return walk_grid<kTest, kAnyHit, kCount>(g.dda, g.empty, ray, stats, [&](const DdaRay& dr, double t0, double t1, auto& q) {
    dda_walk(g.dda, dr, t0, t1, [&](int64_t cell, double, double t_exit) {
      q.rec.count_nodes(1);
      uint32_t begin, count;
      if (!g.cells.find(cell, begin, count)) return false;
      return q.visit_cell(g.refs + begin, count, g.tris, t_exit);
    });
  });
}

}  // namespace raylab
