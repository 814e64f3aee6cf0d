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
#include <type_traits>

#include "accel/core/simd/triangle_block.h"
#include "accel/core/hit_recorder.h"
#include "accel/core/leaf_block_dispatch.h"
#include "accel/core/leaf_triangle.h"
#include "accel/core/grid/dda.h"
#include "accel/core/grid/mailbox.h"
#include "accel/kdtree/kd_leaf_blocks.h"

namespace raylab {

// kBlocks: the grid's cells hold SIMD triangle blocks of kBlockWidth lanes
// (cell_blocks.h: the k-d tree's 4; the irregular grid's slabs: 8; simd=1
// with the watertight test) instead of ids into triangle copies.
template <TriangleTest kTest, typename Recorder, bool kBlocks = false, int kBlockWidth = kKdBlockWidth>
struct GridRayQuery {
  static_assert(!kBlocks || kTest == TriangleTest::Watertight, "the SIMD blocks run the watertight test");
  struct NoBlockRay {};
  const Ray& ray;
  TrianglePrecompute<kTest> pre;
  RayMailbox mailbox;
  // Held by value, as a member next to the mailbox: the walk keeps the bound
  // in this one object (measured: a reference to an outer recorder costs
  // the grids 5-20 %).
  Recorder rec;
  [[no_unique_address]] std::conditional_t<kBlocks, BlockRay<kBlockWidth>, NoBlockRay> block_ray;
  // The walk's parameter origin (dda.h, dda_line): t = t_base + s, 0 unless
  // the ray comes from far away.
  double t_base = 0.0;

  GridRayQuery(const Ray& r, TraversalStats* stats) : ray(r), pre(r), rec(r, stats) {
    if constexpr (kBlocks) block_ray.init(pre.w);
  }

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

  // The same for a cell stored as `count` blocks: a block whose triangles
  // were all tested is skipped; one with a new triangle is tested whole (a
  // triangle tested again gives the same (t, id), which the recorder does
  // not take twice) and counts its new triangles, as the scalar walk does.
  bool test_cell(const KdTriangleBlock* blocks, uint32_t count) {
    for (uint32_t b = 0; b < count; ++b) {
      const uint32_t fresh = mailbox.fresh(blocks[b].prim);
      if (fresh == 0) continue;
      rec.count_triangles(fresh);
      if (intersect_block_record<kKdBlockWidth>(blocks[b], block_ray, ray.tmin, rec)) {
        if constexpr (Recorder::kStopAtFirstHit) return true;
      }
    }
    return false;
  }

  // A cell's run [begin, begin + count) of a grid view with `refs` and
  // `tris` (ids) or `blocks` (kBlocks: begin and count in blocks).
  template <typename View>
  [[gnu::always_inline]] bool test_run(const View& g, uint32_t begin, uint32_t count) {
    if constexpr (kBlocks) return test_cell(g.blocks + begin, count);
    else return test_cell(g.refs + begin, count, g.tris);
  }

  // Closest hit: true once the best hit lies within [.., t_exit] (t_exit in
  // the walk's parameter).
  bool done_at(double t_exit) const { return rec.found() && static_cast<double>(rec.hit().t) <= t_base + t_exit; }

  // One cell entered by the walk: test its run, then apply the stopping rule.
  template <typename View>
  [[gnu::always_inline]] bool visit_run(const View& g, uint32_t begin, uint32_t count, double t_exit) {
    if (test_run(g, begin, count)) return true;
    if constexpr (Recorder::kStopAtFirstHit) return false;
    return done_at(t_exit);
  }
};

// A single-level grid as its walk sees it; `Cells` finds a cell's run of
// references (dense compressed rows, or a hash table of occupied cells):
// ids into `tris`, or with `blocks` (cell_blocks.h) blocks.
template <typename Cells>
struct SingleLevelGridView {
  DdaGrid dda;
  Cells cells;
  const uint32_t* refs = nullptr;
  const LeafTriangle* tris = nullptr;
  const KdTriangleBlock* blocks = nullptr;  // set when the cells are SIMD blocks
  // Per cell, the distance to the nearest occupied cell (cell_clearance.h),
  // when the walk skips empty space.
  const uint8_t* clearance = nullptr;
  bool empty = true;
};

// The frame of every grid walk: the recorder, the validity check, the ray's
// line (rebased when it comes from far away, dda_line) clipped to the grid's
// box; `walk(dr, t0, t1, query)` then walks the cells of [t0, t1] and the
// recorder's hit is the answer.
template <TriangleTest kTest, bool kAnyHit, bool kCount, bool kBlocks = false, bool kFarFirst = false,
          int kBlockWidth = kKdBlockWidth, typename Walk>
[[gnu::always_inline]] inline Hit walk_grid(const DdaGrid& grid, bool empty, const Ray& ray, TraversalStats* stats,
                                            Walk&& walk) {
  using Recorder = HitRecorder<kAnyHit, kCount>;
  // A ray that never reaches the cells still counts (the recorder counts it).
  if (empty || !ray_is_valid(ray)) return Recorder(ray, stats).hit();
  const DdaLine line = dda_line(ray, grid.lo, grid.hi);
  double t0 = line.smin, t1 = line.smax;
  if (!dda_clip(line.ray, grid.lo, grid.hi, t0, t1)) return Recorder(ray, stats).hit();
  GridRayQuery<kTest, Recorder, kBlocks, kBlockWidth> q(ray, stats);
  q.t_base = line.t_base;
  // Any hit from the far end (accel/core/any_hit_order.h): the walk gets the
  // reversed line and its parameter range; the triangle tests still use the
  // ray itself, so the answers are the same.
  static_assert(!kFarFirst || kAnyHit, "only any-hit walks may change their order");
  const DdaSegment s = walk_order<kFarFirst>(line.ray, t0, t1);
  walk(s.ray, s.t0, s.t1, q);
  return q.rec.hit();
}

// Closest-hit / any-hit walk of a single-level grid: the cells of the
// 3D-DDA (dda.h), each non-empty cell's triangles tested (mailboxed), the
// stopping rule above; with a clearance per cell, empty cubes are crossed
// in one jump (dda_walk_skipping), and a cell's clearance says whether it
// is empty before its list is looked up.
template <TriangleTest kTest, bool kAnyHit, bool kCount, bool kFarFirst, typename Cells>
inline Hit traverse_grid(const SingleLevelGridView<Cells>& g, const Ray& ray, TraversalStats* stats) {
  return walk_with_leaf_blocks<kTest>(g, [&]<bool kBlocks>() {
    return walk_grid<kTest, kAnyHit, kCount, kBlocks, kFarFirst>(g.dda, g.empty, ray, stats, [&](const DdaRay& dr, double t0,
                                                                                    double t1, auto& q) {
      const auto visit = [&](int64_t cell, double, double t_exit) __attribute__((always_inline)) {
        uint32_t begin, count;
        const bool found = g.cells.find(cell, begin, count);
        q.rec.count_cell(found ? count : 0);
        if (!found) return false;
        return q.visit_run(g, begin, count, t_exit);
      };
      if (g.clearance) {
        dda_walk_skipping(g.dda, dr, t0, t1, [&](int64_t cell) { return g.clearance[cell]; },
                          [&](int64_t cell, double t_enter, double t_exit) __attribute__((always_inline)) {
                            if (g.clearance[cell] != 0) {
                              q.rec.count_cell(0);
                              return false;
                            }
                            return visit(cell, t_enter, t_exit);
                          });
      } else {
        dda_walk(g.dda, dr, t0, t1, visit);
      }
    });
  });
}

}  // namespace raylab
