#include "accel/loose_octree/loose_octree_accel.h"

#include "accel/core/simd_param.h"
#include "accel/core/batch_accelerator.h"
#include "accel/core/leaf_block_dispatch.h"
#include "accel/core/tree_stats.h"
#include "accel/core/structure_info.h"
#include "accel/core/triangle_test_param.h"
#include "accel/loose_octree/build_loose_octree.h"
#include "accel/loose_octree/traverse_loose_octree.h"
#include "accel/octree/octree_outline.h"
#include "accel/octree/octree_params.h"

namespace raylab {

namespace {

class LooseOctreeAccel final : public BatchAccelerator<LooseOctreeAccel> {
 public:
  LooseOctreeAccel(const LooseOctreeOptions& opt, TriangleTest test, bool simd)
      : BatchAccelerator(test), opt_(opt), blocks_wanted_(leaf_blocks_wanted(simd, test)) {}

  template <TriangleTest kTest, bool kAnyHit, bool kCount>
  Hit trace(const Ray& ray, TraversalStats* stats) const {
    return walk_with_leaf_blocks<kTest>(view_, [&]<bool kBlocks>() {
      return traverse_loose_octree<kTest, kAnyHit, kCount, kBlocks>(view_, ray, stats);
    });
  }

  // raylab show: the loose boxes of the nodes down to max_depth.
  void outline(int max_depth, StructureOutline& out) const override {
    walk_octree_outline(out, "loose octree node boxes", view_.empty, 0u, max_depth,
        [&](uint32_t node, int level, const uint32_t c[3]) {
          const uint32_t mask = nodes_[node].mask();
          float lo[3], hi[3];
          view_.boxes.box(level, c, lo, hi);
          // Loose boxes clipped to the scene's bounds (they overhang it).
          const Aabb box(Vec3f(lo[0], lo[1], lo[2]).cwiseMax(bounds_.lo), Vec3f(hi[0], hi[1], hi[2]).cwiseMin(bounds_.hi));
          return out.add(OutlineBox{box, level, mask == 0}) ? static_cast<int>(mask) : -1;
        },
        [&](uint32_t node, int, uint32_t i) { return nodes_[node].first_child + i; });
  }

 protected:
  BuildStats build_impl(const TriangleMesh& mesh) override {
    bounds_ = mesh.bounds();
    LooseBoxes boxes;
    OctreeTree tree = build_loose_octree(mesh, opt_, boxes);
    const OctreeShape shape = measure_octree(tree);
    blocks_.clear();
    tris_.clear();
    if (blocks_wanted_) {
      blocks_ = make_octree_blocks(mesh, tree);  // rewrites first_ref to block indices
    } else {
      // One reference per triangle: the triangles themselves in node order.
      tris_ = copy_leaf_triangles(mesh, tree.refs);
    }
    nodes_ = std::move(tree.nodes);
    view_ = LooseOctreeView{nodes_.data(), boxes, tris_.data(), mesh.num_triangles() == 0,
                            blocks_wanted_ ? blocks_.data() : nullptr};

    BuildStats s = tree_build_stats(shape, mesh.num_triangles());
    // The octree's SAH is measured on the cubes; loose boxes overlap, so it is not reported.
    s.sah_cost = std::numeric_limits<double>::quiet_NaN();
    s.bytes = nodes_.size() * sizeof(OctreeNode) + tris_.size() * sizeof(LeafTriangle) +
              blocks_.size() * sizeof(OctTriangleBlock);
    s.extra["list_blocks"] = static_cast<double>(blocks_.size());
    s.extra["inner_references"] = static_cast<double>(shape.inner_references);
    s.extra["looseness"] = opt_.looseness;
    return s;
  }

 private:
  LooseOctreeOptions opt_;
  std::vector<OctreeNode> nodes_;
  std::vector<LeafTriangle> tris_;
  bool blocks_wanted_;
  std::vector<OctTriangleBlock> blocks_;
  LooseOctreeView view_;
  Aabb bounds_;
};

}  // namespace

AcceleratorInfo loose_octree_accelerator_info() {
  AcceleratorInfo info = structure_info(
      "loose_octree",
      "loose octree (Ulrich 2000): node boxes grown by k, each triangle once at the deepest node containing it, "
      "children walked by entry distance",
      {{"k", "2", "looseness: loose box side / cell side, in [1, 4] (2 = each side doubled, Ericson 7.3.6)", real_in(1, 4)},
       octree_leaf_param("a node with at most this many triangles keeps them (1..1000)"),
       {"max_depth", "20", "depth limit, root = 0 (0..20)", integer_in(0, kOctMaxLevel)},
       simd_param("node lists as 4-wide SIMD triangle blocks (tri=watertight)")},
      [](const Params& p) -> std::unique_ptr<Accelerator> {
        LooseOctreeOptions opt;
        opt.looseness = p.real("k");
        opt.leaf = static_cast<uint32_t>(p.integer("leaf"));
        opt.max_depth = p.integer("max_depth");
        return std::make_unique<LooseOctreeAccel>(opt, parse_triangle_test(p), parse_simd(p));
      });
  info.caps.scalar_variant = "simd=0";
  info.cover = {"loose_octree:k=1.25", "loose_octree:simd=0"};
  info.stats = tree_stat_infos("triangle references (= triangles: each stored once)",
                               "references per triangle (1 by construction)",
                               {{"inner_references", "triangles held by inner nodes"},
                                {"looseness", "k in force"},
                                {"list_blocks", "SIMD triangle blocks of the node lists (0 with simd=0 or tri=mt)"}});
  // Bench's memory estimate: about twice the final 49-50 bytes/tri on sponza and stadium (not measured at 10^7).
  // 179 on soup:n=10^6, 253 on 2x10^6; 196 on terrain:n=707, 214 on terrain:n=2236
  // (raylab info under /usr/bin/time -v, the scene's own subtracted).
  info.build_peak_bytes_per_triangle = 260;
  return info;
}

}  // namespace raylab
