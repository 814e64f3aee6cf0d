#include "accel/hgrid/hgrid_accel.h"

#include <fmt/format.h>

#include "accel/core/view_accelerator.h"
#include "accel/core/structure_info.h"
#include "accel/core/triangle_test_param.h"
#include "accel/hgrid/build_hgrid.h"
#include "accel/hgrid/traverse_hgrid.h"
#include "accel/structure_outline.h"

namespace raylab {

namespace {

class HgridAccel final : public ViewAccelerator<HgridAccel, HgridOptions, Hgrid> {
 public:
  using ViewAccelerator::ViewAccelerator;

  // Depth 0: the scene box; depth k >= 1: the occupied cells of the k-th
  // coarsest occupied level (coarse cells hold the large triangles, as a
  // tree's upper nodes do), clipped to the scene box (a coarse level's cells
  // reach beyond the scene).
  void outline(int max_depth, StructureOutline& out) const override {
    if (!out.begin("occupied cells per level, coarsest first", view_.empty, scene_box_, max_depth)) return;
    const int occupied = static_cast<int>(view_.levels.size());
    for (const CellSlot& slot : view_.cells.slots()) {
      if (slot.key == CellHashTable::kEmptyKey || slot.count == 0) continue;
      const int level = static_cast<int>(slot.key >> kHgridKeyShift);
      const uint64_t local = slot.key & ((uint64_t{1} << kHgridKeyShift) - 1);
      for (int i = 0; i < occupied; ++i) {
        const HgridLevel& l = view_.levels[i];
        if (l.level != level) continue;
        const int depth = occupied - i;  // levels are finest first
        if (depth > max_depth) break;
        Aabb box = l.grid.cell_box_of_index(local);
        box.lo = box.lo.cwiseMax(scene_box_.lo);
        box.hi = box.hi.cwiseMin(scene_box_.hi);
        if (!box.is_empty() && !out.add(OutlineBox{box, depth, true})) return;
        break;
      }
    }
  }

 protected:
  BuildStats build_impl(const TriangleMesh& mesh) override {
    BuildStats s;
    view_ = build_hgrid(mesh, opt_, s);
    scene_box_ = mesh.bounds();
    return s;
  }

 private:
  Aabb scene_box_ = Aabb::empty();
};

}  // namespace

AcceleratorInfo hgrid_accelerator_info() {
  AcceleratorInfo info = structure_info(
      "hgrid",
      "hierarchical grid (Ericson 7.2): levels of cell side ratio^l, each triangle at one level, shared hashed "
      "cells, per-level 3D-DDA merged by distance",
      {{"ratio", "2", "cell side ratio between successive levels, in [1.25, 16]", real_in(1.25, 16)},
       {"neighbours", "store",
        "store (list a triangle in each cell of its level it overlaps, <= 8) or pad "
        "(list it in its centre's cell; the walk looks up each cell's 3x3x3 neighbourhood)",
        one_of({"store", "pad"})}},
      [](const Params& p) -> std::unique_ptr<Accelerator> {
        HgridOptions opt;
        opt.ratio = p.real("ratio");
        opt.neighbours = p.str("neighbours") == "pad" ? HgridNeighbours::Pad : HgridNeighbours::Store;
        return std::make_unique<HgridAccel>(opt, parse_triangle_test(p));
      });
  info.cover = {"hgrid:neighbours=pad"};
  info.stats = {{"occupied_levels", "levels holding triangles"},
                {"level_span", "levels from the finest to the coarsest occupied one"},
                {"finest_cell", "cell side of level 0 (the smallest triangle extent, >= 2^-18 of the scene)"},
                {"references", "triangle references in cells"},
                {"refs_per_triangle", "references per triangle (neighbours=pad: 1)"},
                {"walkable_cells", "cells in the occupied boxes of all levels (what a walk may enter)"},
                {"max_cell_size", "longest cell list"},
                {"max_probes", "longest probe sequence of the shared hash table"}};
  // Bench's memory estimate: about twice the final 57-61 bytes/tri on sponza and stadium (not measured at 10^7).
  info.build_peak_bytes_per_triangle = 150;  // measured 97 on soup:n=10^7
  return info;
}

}  // namespace raylab
