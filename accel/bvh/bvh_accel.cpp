// `bvh`: the BVH family. A spec picks a builder for the canonical binary tree,
// an optional optimisation pass, and a traversal layout the tree is converted
// into (the parameters and presets: bvh_config.h):
//
//   builder=binned|sweep|sbvh|lbvh   opt=none|light|reinsert   layout=bvh2|bvh4|bvh8|bvh16
//   packet=0|16 (bvh8, bvh16: closest-hit batches traced as 16-ray frustum packets)
//   simd=1|0 (0: the wide layouts walked with scalar tests, same hits and counts)
//
// Every combination reports the same statistics: build ms, bytes, nodes,
// leaves, depth and SAH cost of the traced structure (constants in
// bvh2_node.h), plus structure-specific figures in BuildStats::extra.
#include "accel/bvh/bvh_accel.h"

#include <cmath>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "accel/bvh/build_binned_sah.h"
#include "accel/bvh/build_lbvh.h"
#include "accel/bvh/build_sbvh.h"
#include "accel/bvh/build_sweep_sah.h"
#include "accel/bvh/bvh2_layout.h"
#include "accel/bvh/bvh_config.h"
#include "accel/bvh/bvh_kernel.h"
#include "accel/bvh/bvh_outline.h"
#include "accel/bvh/collapse_wide.h"
#include "accel/bvh/optimize_reinsertion.h"
#include "accel/core/simd/simd.h"
#include "accel/bvh/traverse_sphere_bvh.h"
#include "accel/bvh/traverse_wide.h"
#include "accel/core/batch_accelerator.h"
#include "base/timer.h"

namespace raylab {

namespace {

// The binary tree traced one ray at a time, with boxes (bvh2) or spheres
// (bound=sphere) as node bounds: the tree, its view, its walk
// (traverse_view) and its picture.
template <typename Tree, typename View, View (*kViewOf)(const Tree&),
          void (*kOutline)(const Tree&, int, StructureOutline&)>
class BinaryTreeKernel final : public BatchAccelerator<BinaryTreeKernel<Tree, View, kViewOf, kOutline>, BvhKernel> {
 public:
  BinaryTreeKernel(Tree tree, TriangleTest tri)
      : BatchAccelerator<BinaryTreeKernel, BvhKernel>(tri), tree_(std::move(tree)), view_(kViewOf(tree_)) {}

  template <TriangleTest kTest, bool kAnyHit, bool kCount>
  Hit trace(const Ray& ray, TraversalStats* stats) const {
    return traverse_view<kTest, kAnyHit, kCount>(view_, ray, stats);
  }
  void outline(int max_depth, StructureOutline& out) const override { kOutline(tree_, max_depth, out); }

 private:
  Tree tree_;
  View view_;
};

Bvh2View bvh2_view(const Bvh2Layout& layout) { return layout.view(); }
SphereBvhView sphere_bvh_view(const SphereBvh& bvh) {
  return SphereBvhView{bvh.nodes.data(), bvh.tris.data(), bvh.tris.empty()};
}
using Bvh2Kernel = BinaryTreeKernel<Bvh2Layout, Bvh2View, bvh2_view, outline_bvh2>;
using SphereKernel = BinaryTreeKernel<SphereBvh, SphereBvhView, sphere_bvh_view, outline_sphere_bvh>;

class BvhAccel final : public Accelerator {
 public:
  explicit BvhAccel(const BvhConfig& c) : cfg_(c) {}

  void intersect(std::span<const Ray> rays, std::span<Hit> hits, TraversalStats* stats) const override {
    if (!kernel_) throw std::logic_error("bvh: intersect before build");
    kernel_->intersect(rays, hits, stats);
  }
  void occluded(std::span<const Ray> rays, std::span<uint8_t> occ, TraversalStats* stats) const override {
    if (!kernel_) throw std::logic_error("bvh: occluded before build");
    kernel_->occluded(rays, occ, stats);
  }
  void outline(int max_depth, StructureOutline& out) const override {
    if (kernel_) kernel_->outline(max_depth, out);
  }

 protected:
  // Build phases, each timed into BuildStats::extra: the binary tree, its
  // SAH-optimal collapse, the traversal layout.
  BuildStats build_impl(const TriangleMesh& mesh) override {
    BuildStats s;
    const BinaryBvh tree = build_binary_tree(mesh, s);
    Timer phase;
    const bool wide = cfg_.layout != BvhLayout::Bvh2;
    CollapseOptions co;
    co.width = cfg_.width();
    co.block_width = wide ? kBvhBlockWidth : 1;
    co.max_leaf = cfg_.leaf;
    co.max_leaf_blocks = wide ? static_cast<int>(wide_ref::kMaxBlocks) : 1 << 20;
    co.node_cost = cfg_.node_cost;
    co.block_cost = cfg_.block_cost;
    co.thick_leaf_area = kBvhThickLeafArea;
    co.thick_leaf_limit = cfg_.thick_limit;
    co.mesh = &mesh;
    const WideTree collapsed = collapse_to_wide(tree, co);
    const WideShape shape = measure_wide(collapsed);
    s.extra["ms_collapse"] = phase.ms();
    s.extra["avg_leaf_size"] = shape.avg_leaf_size;
    s.extra["child_fill"] = shape.child_fill;

    phase.reset();
    s.bytes = make_kernel(collapsed, shape, mesh, s);
    s.extra["ms_layout"] = phase.ms();
    s.nodes = wide ? shape.nodes : 2 * shape.nodes + 1;
    s.leaves = shape.leaves;
    s.max_depth = shape.max_depth;
    s.avg_depth = shape.avg_leaf_depth;
    s.sah_cost = shape.sah_cost;
    return s;
  }

 private:
  // The canonical binary tree by the configured builder, then the optional
  // reinsertion pass. Builders bound the depth (median splits beyond
  // kForceMedianDepth, LBVH by its key length, reinsertion by rejecting
  // deeper results); the wide layouts check their depth against the stack.
  BinaryBvh build_binary_tree(const TriangleMesh& mesh, BuildStats& s) const {
    Timer phase;
    const size_t n = mesh.num_triangles();
    // The binned builder takes its references directly, the other builders
    // triangle boxes and centroids (box centres).
    std::vector<Aabb> boxes;
    std::vector<Vec3f> centroids;
    std::vector<BuildRef> refs;
    if (cfg_.builder == BvhBuilder::Binned) {
      refs = triangle_build_refs(mesh);
    } else {
      boxes.resize(n);
      centroids.resize(n);
      tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
          boxes[i] = mesh.triangle_bounds(i);
          centroids[i] = boxes[i].center();
        }
      });
    }
    BuildOptions bo;
    bo.bins = cfg_.bins;
    bo.max_leaf = 1;  // leaves are formed by the SAH-optimal collapse
    bo.leaf_threshold = std::min(cfg_.binary_leaf, cfg_.leaf);
    bo.big_node = cfg_.big_node;
    bo.big_root = cfg_.big_root;
    bo.big_min = kBvhBigMin;
    s.extra["ms_prepare"] = phase.ms();
    phase.reset();
    BinaryBvh tree;
    switch (cfg_.builder) {
      case BvhBuilder::Binned: {
        BinnedBuildStats bs;
        tree = build_binned_sah(std::move(refs), bo, &bs);
        s.extra["big_splits"] = static_cast<double>(bs.big_splits);
        break;
      }
      case BvhBuilder::Sweep: tree = build_sweep_sah(boxes, centroids, bo); break;
      case BvhBuilder::Lbvh: tree = build_lbvh(boxes, centroids); break;
      case BvhBuilder::Sbvh: {
        SbvhOptions so;
        so.base = bo;
        so.alpha = kBvhSbvhAlpha;
        so.split_budget = cfg_.split_budget;
        so.min_spatial_refs = static_cast<size_t>(cfg_.spatial_min);
        so.spatial_bins = kBvhSpatialBins;
        SbvhStats ss;
        tree = build_sbvh(boxes, centroids, TriangleSplitter(mesh), so, &ss);
        s.extra["spatial_splits"] = static_cast<double>(ss.spatial_splits);
        break;
      }
    }
    s.extra["ms_tree"] = phase.ms();
    s.extra["refs_per_triangle"] = n ? static_cast<double>(tree.prim_ids.size()) / n : 0.0;
    if (cfg_.reinsert()) {
      ReinsertionOptions ro;
      ro.max_rounds = cfg_.opt_rounds;
      ro.batch_fraction = cfg_.opt_batch;
      ReinsertionStats rs;
      tree = optimize_reinsertion(tree, ro, &rs);
      s.extra["sah_before_opt"] = rs.sah_before;
      s.extra["sah_after_opt"] = rs.sah_after;
      s.extra["opt_ms"] = rs.ms;
      s.extra["opt_rounds"] = rs.rounds;
      s.extra["opt_moves"] = static_cast<double>(rs.moves);
    }
    phase.reset();
    s.extra["sah_tree"] = tree_sah_cost(tree.nodes);
    s.extra["ms_measure"] = phase.ms();
    return tree;
  }

  // The traversal structure for the configured layout; returns its bytes.
  size_t make_kernel(const WideTree& wide, const WideShape& shape, const TriangleMesh& mesh, BuildStats& s) {
    size_t bytes = 0;
    if (cfg_.bound == BvhBound::Sphere) {
      SphereBvh sb = make_sphere_bvh(make_bvh2_layout(wide, mesh));
      s.extra["sphere_volume_ratio"] = sb.looseness.volume_ratio;
      s.extra["sphere_area_ratio"] = sb.looseness.area_ratio;
      s.extra["sphere_node_area_ratio"] = sb.looseness.mean_node_area_ratio;
      bytes = sb.bytes();
      kernel_ = std::make_unique<SphereKernel>(std::move(sb), cfg_.tri);
      return bytes;
    }
    if (cfg_.layout == BvhLayout::Bvh2) {
      Bvh2Layout l = make_bvh2_layout(wide, mesh);
      bytes = l.bytes();
      kernel_ = std::make_unique<Bvh2Kernel>(std::move(l), cfg_.tri);
      return bytes;
    }
    const bool fits = cfg_.layout == BvhLayout::Bvh4    ? wide_stack_fits<4>(shape.max_depth)
                      : cfg_.layout == BvhLayout::Bvh16 ? wide_stack_fits<16>(shape.max_depth)
                                                        : wide_stack_fits<8>(shape.max_depth);
    if (!fits) throw std::runtime_error("bvh: tree too deep for the traversal stack");
    if (cfg_.layout == BvhLayout::Bvh4) kernel_ = make_wide_kernel<4>(wide, mesh, cfg_, bytes);
    else if (cfg_.layout == BvhLayout::Bvh16) kernel_ = make_wide_kernel<16>(wide, mesh, cfg_, bytes);
    else kernel_ = make_wide_kernel<8>(wide, mesh, cfg_, bytes);
    s.extra["simd_bits"] = simd::isa_bits();
    s.extra["block_width"] = kBvhBlockWidth;
    s.extra["node_width"] = cfg_.width();
    return bytes;
  }

  BvhConfig cfg_;
  std::unique_ptr<BvhKernel> kernel_;
};

}  // namespace

std::string bvh_kernel_isa() { return simd::isa_name(); }

AcceleratorInfo bvh_accelerator_info() {
  AcceleratorInfo info{
      "bvh",
      fmt::format("BVH family: SAH builders, optional reinsertion, SAH-optimal wide collapse, SIMD kernels ({})",
                  simd::isa_name()),
      bvh_parameters(),
      [](const Params& p) -> std::unique_ptr<Accelerator> { return std::make_unique<BvhAccel>(bvh_config(p)); }};
  info.caps.mt_variant = "tri=mt,layout=bvh2";
  info.caps.scalar_variant = "simd=0";
  info.caps.outline = true;
  info.cover = {"bvh:layout=bvh2", "bvh:layout=bvh4", "bvh:layout=bvh2,tri=mt", "bvh:tri=mt", "bvh:builder=sweep",
                "bvh:builder=sbvh", "bvh:builder=lbvh,opt=reinsert", "bvh:packet=16", "bvh:bound=sphere",
                "bvh:bound=sphere,tri=mt", "bvh:simd=0", "bvh:simd=0,layout=bvh4", "bvh:layout=bvh16",
                "bvh:layout=bvh8", "bvh:preset=fast", "bvh:preset=quality", "bvh:preset=sbvh"};
  info.describe = [] { return Description{{"isa", simd::isa_name()}}; };
  info.stats = {{"ms_prepare", "ms: triangle boxes and centroids"},
                {"ms_tree", "ms: the binary tree"},
                {"ms_measure", "ms: measuring the binary tree"},
                {"ms_collapse", "ms: SAH-optimal collapse to the layout's width"},
                {"ms_layout", "ms: the traversal layout (nodes, triangle blocks)"},
                {"refs_per_triangle", "references per triangle (sbvh duplicates split triangles)"},
                {"spatial_splits", "sbvh: spatial splits taken"},
                {"big_splits", "binned: nodes whose large references became a child of their own"},
                {"sah_tree", "SAH cost of the binary tree before the collapse (reporting constants)"},
                {"sah_before_opt", "reinsert: SAH cost before"},
                {"sah_after_opt", "reinsert: SAH cost after"},
                {"opt_ms", "reinsert: ms spent"},
                {"opt_rounds", "reinsert: rounds run"},
                {"opt_moves", "reinsert: subtrees moved"},
                {"avg_leaf_size", "mean triangles per leaf"},
                {"child_fill", "mean children per inner node over the width"},
                {"simd_bits", "wide layouts: SIMD width of the kernels in bits"},
                {"block_width", "wide layouts: triangles per SIMD block"},
                {"node_width", "wide layouts: children per node (4, 8 or 16; layout=auto resolved)"},
                {"sphere_volume_ratio", "bound=sphere: sum of sphere volumes / sum of box volumes over all nodes"},
                {"sphere_area_ratio", "bound=sphere: sum of sphere surface areas / sum of box surface areas"},
                {"sphere_node_area_ratio", "bound=sphere: mean over nodes of sphere area / box area"}};
  info.build_peak_bytes_per_triangle = 170;  // measured 164 on soup:n=10^7

  return info;
}

}  // namespace raylab
