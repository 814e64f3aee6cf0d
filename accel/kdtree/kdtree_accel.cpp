#include "accel/kdtree/kdtree_accel.h"

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "accel/core/simd_param.h"
#include "accel/core/any_hit_order.h"
#include "accel/core/batch_accelerator.h"
#include "accel/core/leaf_block_dispatch.h"
#include "accel/core/tree_stats.h"
#include "accel/core/triangle_test_param.h"
#include "accel/kdtree/build_sah_events.h"
#include "accel/kdtree/build_spatial_median.h"
#include "accel/kdtree/kd_cache_layout.h"
#include "accel/kdtree/kd_leaf_blocks.h"
#include "accel/kdtree/kdtree_outline.h"
#include "accel/kdtree/traverse_kdtree.h"

namespace raylab {

namespace {

enum class KdBuilder { Sah, Median };

class KdTreeAccel final : public BatchAccelerator<KdTreeAccel> {
 public:
  KdTreeAccel(KdBuilder builder, const KdBuildOptions& opt, TriangleTest test, bool simd, bool cluster,
              AnyHitOrder any_hit_order)
      : BatchAccelerator(test),
        builder_(builder),
        opt_(opt),
        cluster_(cluster),
        any_hit_order_(any_hit_order),
        blocks_wanted_(leaf_blocks_wanted(simd, test)) {}

  AnyHitOrder any_hit_order() const { return any_hit_order_; }
  template <TriangleTest kTest, bool kAnyHit, bool kCount>
  Hit trace(const Ray& ray, TraversalStats* stats, bool far_first = false) const {
    return walk_with_leaf_blocks<kTest>(view_, [&]<bool kBlocks>() {
      return walk_in_any_hit_order<kAnyHit>(far_first, [&]<bool kFarFirst>() {
        return traverse_kdtree<kTest, kAnyHit, kCount, kBlocks, kFarFirst>(view_, ray, stats);
      });
    });
  }
  void outline(int max_depth, StructureOutline& out) const override {
    outline_kdtree(view_.bounds, nodes_, max_depth, out);
  }

 protected:
  BuildStats build_impl(const TriangleMesh& mesh) override {
    KdTree tree = builder_ == KdBuilder::Sah ? build_kdtree_sah(mesh, opt_) : build_kdtree_median(mesh, opt_);
    if (cluster_) tree = cluster_kd_nodes(tree);
    nodes_.assign(tree.nodes.begin(), tree.nodes.end());
    blocks_.clear();
    if (blocks_wanted_) {
      // SIMD leaves replace the indices and the triangle copies.
      blocks_ = make_kd_leaf_blocks(mesh, nodes_, tree.prim_ids);
      ids_.clear();
    } else {
      IndexedLeafTriangles leaf_tris = copy_referenced_triangles(mesh, tree.prim_ids);
      tris_ = std::move(leaf_tris.tris);
      ids_ = std::move(leaf_tris.ids);
    }
    view_ = KdTreeView{nodes_.data(), tris_.data(), ids_.data(), tree.bounds, mesh.num_triangles() == 0,
                       /*root=*/0, blocks_wanted_ ? blocks_.data() : nullptr};

    const KdTreeShape shape = measure_kdtree(tree.bounds, nodes_);
    BuildStats s = tree_build_stats(shape, mesh.num_triangles());
    s.bytes = nodes_.size() * sizeof(KdNode) + tris_.size() * sizeof(LeafTriangle) + ids_.size() * sizeof(uint32_t) +
              blocks_.size() * sizeof(KdTriangleBlock);
    s.extra["leaf_blocks"] = static_cast<double>(blocks_.size());
    const size_t full_leaves = shape.leaves - shape.empty_leaves;
    s.extra["avg_leaf_size"] = full_leaves ? static_cast<double>(shape.references) / static_cast<double>(full_leaves) : 0.0;
    s.extra["max_depth_limit"] =
        opt_.max_depth < 0 ? kd_default_max_depth(mesh.num_triangles()) : std::min(opt_.max_depth, kKdMaxDepthLimit);
    return s;
  }

 private:
  KdBuilder builder_;
  KdBuildOptions opt_;
  bool cluster_;  // layout=cluster (kd_cache_layout.h)
  AnyHitOrder any_hit_order_;  // accel/core/any_hit_order.h
  // Nodes and leaf blocks on transparent huge pages (huge_page_allocator.h):
  // a ray's ~50 node loads land all over a 5-25 MB tree, and with 4 KiB
  // pages most of them would also miss the TLB.
  HugePageVector<KdNode> nodes_;
  std::vector<LeafTriangle> tris_;
  std::vector<uint32_t> ids_;
  bool blocks_wanted_;
  HugePageVector<KdTriangleBlock> blocks_;
  KdTreeView view_;
};

}  // namespace

AcceleratorInfo kdtree_accelerator_info() {
  AcceleratorInfo info{
      "kdtree",
      "k-d tree: O(N log N) SAH build (Wald & Havran 2006, TBB), perfect splits, front-to-back traversal "
      "(any-hit: back to front)",
      {{"builder", "sah", "sah (event sweep, Wald & Havran 2006) or median (spatial median baseline)",
        one_of({"sah", "median"})},
       // K_T = 200 against K_I = 20 (Wald & Havran: 15 and 20): with 4-wide
       // SIMD leaf blocks a triangle costs a fraction of a scalar test, while
       // a node step (a dependent load and an unpredictable branch) does not
       // get cheaper; measured best of 15..300 on the interior views
       // (docs/structures/kdtree.md). One tree for simd=0 and 1 (same hits and
       // counts); ct=15 is the tree tuned for the scalar test.
       sah_traversal_cost_param("builder=sah: ", kKdDefaultTraversalCost),
       sah_intersection_cost_param("builder=sah: "),
       {"empty_bonus", "0.2", "builder=sah: cost reduction of splits with an empty child, in [0, 1)",
        real_in(0, 1, Ends::OpenHigh)},
       {"clip", "1", "perfect splits: clip straddling triangles to the cells (0 = bounding boxes)", boolean_flag()},
       depth_limit_param(kKdMaxDepthLimit),
       {"leaf", "2", "builder=median: cells with at most this many triangles become leaves", integer_in(1, kUnbounded)},
       triangle_test_param(),
       simd_param("leaves as 4-wide SIMD triangle blocks (tri=watertight)"),
       {"layout", "depth_first",
        "node order: depth_first (the builder's) or cluster (subtrees clustered into 64-byte cache lines, "
        "kd_cache_layout.h; measured no faster with the default costs)",
        one_of({"depth_first", "cluster"})},
       any_hit_order_param()},
      [](const Params& p) -> std::unique_ptr<Accelerator> {
        const KdBuilder builder = p.str("builder") == "median" ? KdBuilder::Median : KdBuilder::Sah;
        KdBuildOptions opt;
        if (builder == KdBuilder::Median) {
          for (const char* key : {"ct", "ci", "empty_bonus"})
            if (p.given(key)) throw SpecError(fmt::format("kdtree: {} applies to builder=sah only", key));
        } else if (p.given("leaf")) {
          throw SpecError("kdtree: leaf applies to builder=median only (the SAH decides leaf sizes)");
        }
        const SahCosts costs = parse_sah_costs(p);
        opt.traversal_cost = costs.traversal;
        opt.intersection_cost = costs.intersection;
        opt.empty_bonus = static_cast<float>(p.real("empty_bonus"));
        opt.perfect_splits = p.boolean("clip");
        opt.max_depth = parse_depth_limit(p);
        opt.median_leaf_size = p.integer("leaf");
        return std::make_unique<KdTreeAccel>(builder, opt, parse_triangle_test(p), parse_simd(p),
                                             p.str("layout") == "cluster", parse_any_hit_order(p));
      }};
  info.caps.mt_variant = "tri=mt";
  info.caps.scalar_variant = "simd=0";
  info.caps.outline = true;
  info.cover = {"kdtree:builder=median", "kdtree:clip=0", "kdtree:tri=mt", "kdtree:simd=0", "kdtree:layout=cluster",
                "kdtree:anyhit=front", "kdtree:anyhit=back"};
  info.stats = tree_stat_infos("triangle references in leaves",
                               "references per triangle (perfect splits duplicate straddling triangles)",
                               {{"avg_leaf_size", "mean references per non-empty leaf"},
                                {"max_depth_limit", "the depth limit in force (auto: 8 + 1.3 log2 N)"},
                                {"leaf_blocks", "SIMD triangle blocks of the leaves (0 with simd=0 or tri=mt)"}});
  // Peak bytes per triangle (raylab info under /usr/bin/time -v, the scene's
  // own subtracted): 215 on soup:n=10^6, 227 on 2x10^6, 131 on 10^7 (shallower
  // trees); 162 on terrain:n=707, 116 on terrain:n=2236.
  info.build_peak_bytes_per_triangle = 240;
  return info;
}

}  // namespace raylab
