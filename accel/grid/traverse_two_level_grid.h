#pragma once
// Nested 3D-DDA through a two-level grid: the outer walk visits top cells;
// in a non-empty top cell the ray first tests the cell's large triangles,
// then its part within the cell ([t_enter, t_exit], shortened to the
// closest hit so far) is clipped to the sub-grid's box and walked by the
// inner DDA. One mailbox and one closest hit serve both levels; the
// stopping rule of grid_ray_query.h applies to the inner cells (the large
// triangles of the top cell have been tested by then, and outside the
// sub-grid's box the cell holds no other triangle) and again to the top
// cell once its sub-grid is done.
#include <cstdint>

#include "accel/core/grid/grid_ray_query.h"
#include "accel/core/leaf_block_dispatch.h"
#include "accel/grid/two_level_grid.h"

namespace raylab {

struct TwoLevelGridView {
  DdaGrid top;
  const uint32_t* top_cells = nullptr;
  const TopCellContent* contents = nullptr;
  const uint32_t* offsets = nullptr;
  const uint32_t* refs = nullptr;
  const LeafTriangle* tris = nullptr;
  const CellTriangleBlock* blocks = nullptr;  // set when the cells are SIMD blocks
  bool empty = true;
};

inline TwoLevelGridView grid_view(const TwoLevelGrid& g) {
  return TwoLevelGridView{g.top,         g.top_cells.data(), g.contents.data(),
                          g.offsets.data(), g.refs.data(),  g.tris.data(),
                          g.blocks.empty() ? nullptr : g.blocks.data(), g.empty};
}

template <TriangleTest kTest, bool kAnyHit, bool kCount, bool kBlocks, bool kFarFirst>
inline Hit traverse_two_level_grid(const TwoLevelGridView& g, const Ray& ray, TraversalStats* stats) {
  using Recorder = HitRecorder<kAnyHit, kCount>;
  static_assert(!kFarFirst || kAnyHit, "only any-hit walks may change their order");
  if (g.empty || !ray_is_valid(ray)) return Recorder(ray, stats).hit();
  const DdaLine line = dda_line(ray, g.top.lo, g.top.hi);  // rebased when from far away (dda.h)
  double clip0 = line.smin, clip1 = line.smax;
  if (!dda_clip(line.ray, g.top.lo, g.top.hi, clip0, clip1)) return Recorder(ray, stats).hit();
  // Any hit from the far end (accel/core/any_hit_order.h): both levels walk
  // the reversed line; the triangle tests use the ray itself.
  const DdaSegment seg = walk_order<kFarFirst>(line.ray, clip0, clip1);
  const DdaRay& dr = seg.ray;
  const double t0 = seg.t0, t1 = seg.t1;
  // Not through walk_grid: one lambda less around the nested walks keeps
  // them inlined (measured 12 % faster on the bunny).
  GridRayQuery<kTest, Recorder, kBlocks, kCellBlockWidth> q(ray, stats);
  q.t_base = line.t_base;
  Recorder& rec = q.rec;
  {
    // always_inline: GCC otherwise keeps this lambda (the whole per-cell
    // body) out of line, which measured 10 % slower.
    dda_walk(g.top, dr, t0, t1, [&](int64_t top_cell, double t_enter, double t_exit) __attribute__((always_inline)) {
      const uint32_t k = g.top_cells[top_cell];
      if (k == kEmptyTopCell) {
        rec.count_cell(0);
        return false;
      }
      const TopCellContent& content = g.contents[k];
      if (!content.has_subgrid()) {
        rec.count_cell(content.large_count);
        return q.visit_run(g, content.large_begin, content.large_count, t_exit);
      }
      // A top cell with a sub-grid is a step, and a leaf for its large triangles.
      rec.count_inner();
      if (content.large_count != 0) rec.count_leaf(content.large_count);
      if (content.large_count != 0 && q.test_run(g, content.large_begin, content.large_count)) return true;
      const DdaGrid sub_dda = content.dda();
      // Closest hit: no farther than the hit so far (any hit: no hit yet).
      const double bound = static_cast<double>(rec.tmax()) - line.t_base;  // in the walk's parameter
      double s0 = t_enter, s1 = kAnyHit || t_exit < bound ? t_exit : bound;
      if (dda_clip(dr, sub_dda.lo, sub_dda.hi, s0, s1)) {
        const uint32_t* offsets = g.offsets + content.offsets_base;
        const bool stop = dda_walk(sub_dda, dr, s0, s1, [&](int64_t cell, double, double cell_exit) __attribute__((always_inline)) {
          const uint32_t begin = offsets[cell], end = offsets[cell + 1];
          rec.count_cell(end - begin);
          if (begin == end) return false;
          return q.visit_run(g, begin, end - begin, cell_exit);
        });
        if (stop) return true;
      }
      if constexpr (kAnyHit) return false;
      return q.done_at(t_exit);
    });
  }
  return rec.hit();
}

template <TriangleTest kTest, bool kAnyHit, bool kCount, bool kFarFirst>
inline Hit traverse_grid(const TwoLevelGridView& g, const Ray& ray, TraversalStats* stats) {
  return walk_with_leaf_blocks<kTest>(g, [&]<bool kBlocks>() {
    return traverse_two_level_grid<kTest, kAnyHit, kCount, kBlocks, kFarFirst>(g, ray, stats);
  });
}

}  // namespace raylab
