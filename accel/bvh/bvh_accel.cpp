#include "accel/bvh/bvh_accel.h"

#include <tbb/parallel_for.h>

#include "accel/bvh/build_binned_sah.h"
#include "accel/bvh/traverse_bvh2.h"
#include "accel/util/timer.h"

namespace raylab {

namespace {

class BvhAccel final : public Accelerator {
 public:
  BvhAccel(const BinnedSahOptions& opt, TriangleTest test) : opt_(opt), test_(test) {}

  BuildStats build(const TriangleMesh& mesh) override {
    mesh.validate();
    Timer timer;
    const size_t n = mesh.num_triangles();
    std::vector<Aabb> boxes(n);
    std::vector<Vec3f> centroids(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i) {
        boxes[i] = mesh.triangle_bounds(i);
        centroids[i] = boxes[i].center();
      }
    });
    BinaryBvh tree = build_binned_sah(boxes, centroids, opt_);
    nodes_ = std::move(tree.nodes);
    tris_.resize(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i) {
        const uint32_t id = tree.prim_ids[i];
        tris_[i] = LeafTriangle{mesh.vertex(id, 0), mesh.vertex(id, 1), mesh.vertex(id, 2), id};
      }
    });
    view_ = Bvh2View{nodes_.data(), tris_.data(), n == 0};

    BuildStats s;
    s.build_ms = timer.ms();
    const TreeShape shape = measure_tree(nodes_);
    s.nodes = shape.nodes;
    s.leaves = shape.leaves;
    s.max_depth = shape.max_depth;
    s.avg_depth = shape.avg_leaf_depth;
    s.sah_cost = shape.sah_cost;
    s.bytes = nodes_.size() * sizeof(Bvh2Node) + tris_.size() * sizeof(LeafTriangle);
    return s;
  }

  void intersect(std::span<const Ray> rays, std::span<Hit> hits, TraversalStats* stats) const override {
    dispatch_triangle_test(test_, [&]<TriangleTest kTest>() {
      if (stats) {
        for (size_t i = 0; i < rays.size(); ++i) hits[i] = traverse_bvh2<kTest, false, true>(view_, rays[i], stats);
      } else {
        for (size_t i = 0; i < rays.size(); ++i) hits[i] = traverse_bvh2<kTest, false, false>(view_, rays[i], nullptr);
      }
    });
  }

  void occluded(std::span<const Ray> rays, std::span<uint8_t> occ, TraversalStats* stats) const override {
    dispatch_triangle_test(test_, [&]<TriangleTest kTest>() {
      if (stats) {
        for (size_t i = 0; i < rays.size(); ++i)
          occ[i] = traverse_bvh2<kTest, true, true>(view_, rays[i], stats).valid();
      } else {
        for (size_t i = 0; i < rays.size(); ++i)
          occ[i] = traverse_bvh2<kTest, true, false>(view_, rays[i], nullptr).valid();
      }
    });
  }

 private:
  BinnedSahOptions opt_;
  TriangleTest test_;
  std::vector<Bvh2Node> nodes_;
  std::vector<LeafTriangle> tris_;
  Bvh2View view_;
};

}  // namespace

AcceleratorInfo bvh_accelerator_info() {
  return AcceleratorInfo{
      "bvh",
      "binary BVH, binned SAH build (TBB), ordered traversal, conservative slab test",
      {{"leaf", "4", "maximum primitives per leaf"},
       {"bins", "16", "SAH bins per axis (2..256)"},
       {"tri", "watertight", "triangle test: watertight (Woop et al. 2013) or mt (Moller-Trumbore)"}},
      [](const Params& p) -> std::unique_ptr<Accelerator> {
        BinnedSahOptions opt;
        opt.max_leaf = p.integer("leaf");
        opt.bins = p.integer("bins");
        if (opt.max_leaf < 1 || opt.max_leaf > 255) throw SpecError("bvh: leaf must be in 1..255");
        if (opt.bins < 2 || opt.bins > 256) throw SpecError("bvh: bins must be in 2..256");
        const auto& t = p.choice("tri", {"watertight", "mt"});
        return std::make_unique<BvhAccel>(opt, t == "mt" ? TriangleTest::MollerTrumbore : TriangleTest::Watertight);
      }};
}

}  // namespace raylab
