#include "accel/irgrid/irgrid_accel.h"

#include <cmath>

#include "accel/core/any_hit_order.h"
#include "accel/core/simd_param.h"
#include "accel/core/batch_accelerator.h"
#include "accel/core/leaf_block_dispatch.h"
#include "accel/core/structure_info.h"
#include "accel/core/triangle_test_param.h"
#include "accel/irgrid/build_irgrid.h"
#include "accel/irgrid/traverse_irgrid.h"
#include "accel/structure_outline.h"

namespace raylab {

namespace {

class IrgridAccel final : public BatchAccelerator<IrgridAccel> {
 public:
  IrgridAccel(IrgridOptions opt, TriangleTest test, bool simd, AnyHitOrder any_hit_order)
      : BatchAccelerator(test), opt_(opt), any_hit_order_(any_hit_order) {
    opt_.leaf_blocks = leaf_blocks_wanted(simd, test);
  }

  AnyHitOrder any_hit_order() const { return any_hit_order_; }
  template <TriangleTest kTest, bool kAnyHit, bool kCount>
  Hit trace(const Ray& ray, TraversalStats* stats, bool far_first = false) const {
    return walk_in_any_hit_order<kAnyHit>(far_first, [&]<bool kFarFirst>() {
      if constexpr (kTest == TriangleTest::Watertight) {
        if (grid_.leaf_blocks) return traverse_irgrid<kTest, kAnyHit, kCount, true, kFarFirst>(grid_, ray, stats);
      }
      return traverse_irgrid<kTest, kAnyHit, kCount, false, kFarFirst>(grid_, ray, stats);
    });
  }

  // Depth 0: the grid's box; depth 1: every cell's (expanded) box, filled
  // when it holds triangles. Expanded boxes overlap their neighbours.
  void outline(int max_depth, StructureOutline& out) const override {
    out.what = "cells (expanded boxes), occupied ones filled";
    if (grid_.empty) return;
    if (!out.add(OutlineBox{voxel_box(grid_.virt, 0, grid_.virt.res), 0, false}) || max_depth < 1) return;
    bool room = true;
    grid_.for_each_cell([&](const IrgridCell& c) {
      room = room && out.add(OutlineBox{voxel_box(grid_.virt, c.lo, c.hi), 1, c.count != 0});
    });
  }

 protected:
  BuildStats build_impl(const TriangleMesh& mesh) override {
    BuildStats s;
    grid_ = build_irgrid(mesh, opt_, s);
    return s;
  }

 private:
  static Aabb voxel_box(const DdaGrid& g, const int32_t* lo, const int32_t* hi) {
    Aabb b;
    for (int a = 0; a < 3; ++a) {
      b.lo[a] = static_cast<float>(g.boundary(a, lo ? lo[a] : 0));
      b.hi[a] = static_cast<float>(g.boundary(a, hi[a]));
    }
    return b;
  }

  IrgridOptions opt_;
  AnyHitOrder any_hit_order_ = AnyHitOrder::Back;
  Irgrid grid_;
};

}  // namespace

AcceleratorInfo irgrid_accelerator_info() {
  AcceleratorInfo info = structure_info(
      "irgrid",
      "irregular grid (Perard-Gayot, Kalojanov & Slusallek 2017): top grid, octree-subdivided cells merged by "
      "expected cost and expanded over neighbours they contain, walked cell to cell through a voxel map",
      {{"top", "0.25", "top grid density lambda_1 (top cells ~ top x triangles), in (0, 64]", real_in(0, 64, Ends::OpenLow)},
       {"sub", "0.1", "octree density lambda_2: a node with n triangles may split when sub x n > 8, in (0, 1024]",
        real_in(0, 1024, Ends::OpenLow)},
       {"step", "1",
        "cost of entering a cell in triangle tests, for the octree's split and the merge pass's cost model, in [0, 1000]",
        real_in(0, 1000)},
       {"depth", "12", "deepest octree level below a top cell, 0..16", integer_in(0, 16)},
       {"merge", "1", "merge pass: neighbours merged when the merged cell's expected cost is not larger (0/1)",
        boolean_flag()},
       {"expand", "1", "expand pass: each cell's box grown over neighbours it contains (0/1)", boolean_flag()},
       simd_param("cells' triangles as 8-wide SIMD blocks (tri=watertight)"), any_hit_order_param()},
      [](const Params& p) -> std::unique_ptr<Accelerator> {
        IrgridOptions opt;
        opt.top_density = p.real("top");
        opt.sub_density = p.real("sub");
        opt.step_cost = p.real("step");
        opt.max_depth = p.integer("depth");
        opt.merge = p.boolean("merge");
        opt.expand = p.boolean("expand");
        return std::make_unique<IrgridAccel>(opt, parse_triangle_test(p), parse_simd(p), parse_any_hit_order(p));
      });
  info.cover = {"irgrid:merge=0", "irgrid:expand=0", "irgrid:simd=0", "irgrid:anyhit=front", "irgrid:anyhit=back"};  // both off: tests/accel/irgrid/test_irgrid.cpp
  info.caps.scalar_variant = "simd=0";
  info.stats = {{"cells", "cells after merging"},
                {"nonempty_cells", "cells holding triangles"},
                {"refs", "triangle references in cells"},
                {"refs_per_triangle", "references per triangle"},
                {"initial_cells", "octree leaves before merging"},
                {"merged_pairs", "merges made by the merge pass"},
                {"expanded_cells", "cells whose box the expand pass grew"},
                {"depth", "deepest octree level used below the top grid"},
                {"max_tris_per_cell", "longest cell list"},
                {"mean_tris_per_nonempty_cell", "mean list length of the non-empty cells"},
                {"empty_fraction", "fraction of the cells that are empty"},
                {"top_x", "top grid resolution along x"},
                {"top_y", "top grid resolution along y"},
                {"top_z", "top grid resolution along z"}};
  info.build_peak_bytes_per_triangle = 400;
  return info;
}

}  // namespace raylab
