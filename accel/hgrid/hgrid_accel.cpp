#include "accel/hgrid/hgrid_accel.h"

#include <fmt/format.h>

#include "accel/core/batch_accelerator.h"
#include "accel/core/triangle_test_param.h"
#include "accel/hgrid/build_hgrid.h"
#include "accel/hgrid/traverse_hgrid.h"

namespace raylab {

namespace {

class HgridAccel final : public BatchAccelerator<HgridAccel> {
 public:
  HgridAccel(const HgridOptions& opt, TriangleTest test) : BatchAccelerator(test), opt_(opt) {}

  template <TriangleTest kTest, bool kAnyHit, bool kCount>
  Hit trace(const Ray& ray, TraversalStats* stats) const {
    return traverse_hgrid<kTest, kAnyHit, kCount>(grid_, ray, stats);
  }

 protected:
  BuildStats build_impl(const TriangleMesh& mesh) override {
    BuildStats s;
    grid_ = build_hgrid(mesh, opt_, s);
    return s;
  }

 private:
  HgridOptions opt_;
  Hgrid grid_;
};

}  // namespace

AcceleratorInfo hgrid_accelerator_info() {
  AcceleratorInfo info{
      "hgrid",
      "hierarchical grid (Ericson 7.2): levels of cell side ratio^l, each triangle at one level, shared hashed "
      "cells, per-level 3D-DDA merged by distance",
      {{"ratio", "2", "cell side ratio between successive levels, in [1.25, 16]"},
       {"neighbours", "store", "store (list a triangle in each cell of its level it overlaps, <= 8) or pad "
                               "(list it in its centre's cell; the walk looks up each cell's 3x3x3 neighbourhood)"},
       triangle_test_param()},
      [](const Params& p) -> std::unique_ptr<Accelerator> {
        HgridOptions opt;
        opt.ratio = p.real("ratio");
        if (!(opt.ratio >= 1.25 && opt.ratio <= 16.0)) throw SpecError("hgrid: ratio must be in [1.25, 16]");
        opt.neighbours = p.choice("neighbours", {"store", "pad"}) == "pad" ? HgridNeighbours::Pad
                                                                          : HgridNeighbours::Store;
        return std::make_unique<HgridAccel>(opt, parse_triangle_test(p));
      }};
  info.caps.mt_variant = "tri=mt";
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
  info.build_peak_bytes_per_triangle = 150;
  return info;
}

}  // namespace raylab
