#include "accel/octree/octree_accel.h"

#include "accel/core/any_hit_order.h"
#include "accel/core/simd_param.h"
#include "accel/core/batch_accelerator.h"
#include "accel/core/leaf_block_dispatch.h"
#include "accel/core/tree_stats.h"
#include "accel/core/structure_info.h"
#include "accel/core/triangle_test_param.h"
#include "accel/octree/build_octree.h"
#include "accel/octree/octree_leaf_blocks.h"
#include "accel/octree/octree_outline.h"
#include "accel/octree/octree_params.h"
#include "accel/octree/traverse_octree.h"

namespace raylab {

namespace {

struct OctreeOptions {
  OctreeBuildOptions build;
  OctreeStorage storage = OctreeStorage::Pointer;
  double budget_mib = 2048.0;
  bool simd = true;  // node lists as SIMD triangle blocks (watertight test only)
  AnyHitOrder any_hit_order = AnyHitOrder::Back;  // accel/core/any_hit_order.h
};

template <typename Layout>
class OctreeAccel final : public BatchAccelerator<OctreeAccel<Layout>> {
 public:
  OctreeAccel(const OctreeOptions& opt, TriangleTest test)
      : BatchAccelerator<OctreeAccel<Layout>>(test), opt_(opt), blocks_wanted_(leaf_blocks_wanted(opt.simd, test)) {}

  AnyHitOrder any_hit_order() const { return opt_.any_hit_order; }
  template <TriangleTest kTest, bool kAnyHit, bool kCount>
  Hit trace(const Ray& ray, TraversalStats* stats, bool far_first = false) const {
    return walk_with_leaf_blocks<kTest>(view_, [&]<bool kBlocks>() {
      return walk_in_any_hit_order<kAnyHit>(far_first, [&]<bool kFarFirst>() {
        return traverse_octree<kTest, kAnyHit, kCount, kBlocks, Layout, kFarFirst>(view_, ray, stats);
      });
    });
  }

  // raylab show: node cubes down to max_depth (leaves drawn as leaves).
  void outline(int max_depth, StructureOutline& out) const override {
    walk_octree_outline(out, "octree node cubes", view_.empty, Layout::kRoot, max_depth,
        [&](uint64_t node, int level, const uint32_t c[3]) {
          const uint32_t s = OctreeCube::span(level), mask = view_.layout.node(node, level).meta & 0xffu;
          // Cubes clipped to the scene's bounds (the root cube overhangs them).
          const Aabb box(Vec3f(view_.cube.plane(0, c[0]), view_.cube.plane(1, c[1]), view_.cube.plane(2, c[2])).cwiseMax(bounds_.lo),
                         Vec3f(view_.cube.plane(0, c[0] + s), view_.cube.plane(1, c[1] + s), view_.cube.plane(2, c[2] + s))
                             .cwiseMin(bounds_.hi));
          return out.add(OutlineBox{box, level, mask == 0}) ? static_cast<int>(mask) : -1;
        },
        [&](uint64_t node, int level, uint32_t i) { return view_.layout.child(node, view_.layout.node(node, level), i); });
  }

 protected:
  BuildStats build_impl(const TriangleMesh& mesh) override {
    bounds_ = mesh.bounds();
    OctreeTree tree = build_octree(mesh, opt_.build);
    const OctreeShape shape = measure_octree(tree);
    blocks_.clear();
    tris_.clear();
    ids_.clear();
    size_t shared_bytes = 0;
    if (blocks_wanted_) {
      // SIMD lists replace the indices and the triangle copies.
      blocks_ = make_octree_blocks(mesh, tree);
      shared_bytes = blocks_.size() * sizeof(OctTriangleBlock);
    } else {
      // Each referenced triangle copied once, in first-use order, nodes keep
      // indices into that copy (as the k-d tree does).
      IndexedLeafTriangles leaf_tris = copy_referenced_triangles(mesh, tree.refs);
      tris_ = std::move(leaf_tris.tris);
      ids_ = std::move(leaf_tris.ids);
      shared_bytes = tris_.size() * sizeof(LeafTriangle) + ids_.size() * sizeof(uint32_t);
    }
    const size_t hash_entries = std::max<size_t>(shape.nonempty_nodes, 1);
    const size_t pointer_bytes = tree.nodes.size() * sizeof(OctreeNode);
    const double linear_bytes = static_cast<double>(octree_linear_slots(shape.max_depth)) * sizeof(OctLinearSlot);
    const size_t hash_bytes = octree_hash_capacity(hash_entries) * sizeof(OctHashEntry);

    size_t layout_bytes = 0;
    if constexpr (std::is_same_v<Layout, OctPointerLayout>) {
      nodes_ = std::move(tree.nodes);
      view_.layout.nodes = nodes_.data();
      layout_bytes = pointer_bytes;
    } else if constexpr (std::is_same_v<Layout, OctLinearLayout>) {
      slots_ = make_octree_linear(tree, shape.max_depth, static_cast<uint64_t>(opt_.budget_mib * 1024.0 * 1024.0));
      view_.layout.slots = slots_.data();
      layout_bytes = slots_.size() * sizeof(OctLinearSlot);
    } else {
      table_ = make_octree_hash(tree, hash_entries, view_.layout);
      view_.layout.table = table_.data();
      layout_bytes = table_.size() * sizeof(OctHashEntry);
    }
    view_.cube = tree.cube;
    view_.tris = tris_.data();
    view_.ids = ids_.data();
    view_.blocks = blocks_wanted_ ? blocks_.data() : nullptr;
    view_.empty = mesh.num_triangles() == 0;

    BuildStats s = tree_build_stats(shape, mesh.num_triangles());
    s.bytes = layout_bytes + shared_bytes;
    s.extra["inner_references"] = static_cast<double>(shape.inner_references);
    s.extra["nonempty_nodes"] = static_cast<double>(shape.nonempty_nodes);
    s.extra["pointer_layout_bytes"] = static_cast<double>(pointer_bytes);
    s.extra["linear_layout_bytes"] = linear_bytes;
    s.extra["hash_layout_bytes"] = static_cast<double>(hash_bytes);
    s.extra["list_blocks"] = static_cast<double>(blocks_.size());
    return s;
  }

 private:
  OctreeOptions opt_;
  std::vector<OctreeNode> nodes_;
  std::vector<OctLinearSlot> slots_;
  std::vector<OctHashEntry> table_;
  std::vector<LeafTriangle> tris_;
  std::vector<uint32_t> ids_;
  bool blocks_wanted_;
  std::vector<OctTriangleBlock> blocks_;  // C++17 aligned new honours the block alignment
  OctreeView<Layout> view_;
  Aabb bounds_;
};

}  // namespace

AcceleratorInfo octree_accelerator_info() {
  AcceleratorInfo info = structure_info(
      "octree",
      "regular octree over the bounding cube, exact SAT assignment, parametric traversal (Revelles et al. 2000)",
      {octree_leaf_param("a node with at most this many triangles becomes a leaf (1..1000)"),
       {"max_depth", "16", "depth limit, root = 0 (0..20); storage=linear defaults to 6 (its array grows as 8^depth)",
        integer_in(0, kOctMaxLevel)},
       {"growth", "2",
        "assign=exact: no split whose children hold more than growth x the node's references, in [1, 8] (coplanar or "
        "touching faces would otherwise split to max_depth)",
        real_in(1, 8)},
       {"term", "sah",
        "sah (split a node above leaf only when the surface-area cost of its eight children beats the leaf) or count "
        "(split every node above leaf, within growth)",
        one_of({"count", "sah"})},
       {"ct", "2", "term=sah: cost of a node visit, in 4-wide triangle-block tests (0..100)", real_in(0, 100)},
       {"assign", "exact",
        "exact (every leaf the triangle overlaps, SAT) or straddle (triangles crossing a dividing plane stay at the "
        "inner node, each stored once)",
        one_of({"exact", "straddle"})},
       {"storage", "pointer",
        "pointer (8-child blocks, one index per node), linear (complete tree by level, children by index arithmetic) "
        "or hash (Morton location codes, occupied nodes only)",
        one_of({"pointer", "linear", "hash"})},
       {"budget", "2048", "storage=linear: memory budget of the complete-tree array in MiB", real_in(0, 1e6, Ends::OpenLow)},
       simd_param("node lists as 4-wide SIMD triangle blocks (tri=watertight)"),
       any_hit_order_param()},
      [](const Params& p) -> std::unique_ptr<Accelerator> {
        OctreeOptions opt;
        opt.build.leaf = static_cast<uint32_t>(p.integer("leaf"));
        const std::string& storage = p.str("storage");
        opt.build.max_depth = p.given("max_depth") || storage != "linear" ? p.integer("max_depth") : 6;
        opt.build.max_growth = p.real("growth");
        opt.build.sah = p.str("term") == "sah";
        opt.build.ct = p.real("ct");
        if (p.given("ct") && !opt.build.sah) throw SpecError("octree: ct applies to term=sah only");
        opt.build.assign = p.str("assign") == "straddle" ? OctreeAssign::Straddle : OctreeAssign::Exact;
        opt.budget_mib = p.real("budget");
        if (p.given("budget") && storage != "linear") throw SpecError("octree: budget applies to storage=linear only");
        opt.simd = parse_simd(p);
        opt.any_hit_order = parse_any_hit_order(p);
        const TriangleTest test = parse_triangle_test(p);
        if (storage == "linear") return std::make_unique<OctreeAccel<OctLinearLayout>>(opt, test);
        if (storage == "hash") return std::make_unique<OctreeAccel<OctHashLayout>>(opt, test);
        return std::make_unique<OctreeAccel<OctPointerLayout>>(opt, test);
      });
  info.caps.scalar_variant = "simd=0";
  info.cover = {"octree:assign=straddle", "octree:storage=linear", "octree:storage=hash", "octree:simd=0",
                "octree:term=count", "octree:anyhit=front", "octree:anyhit=back"};
  info.stats = tree_stat_infos(
      "triangle references in all nodes", "references per triangle (exact assignment duplicates straddling triangles)",
      {{"inner_references", "references held by inner nodes (assign=straddle)"},
       {"nonempty_nodes", "nodes with triangles in their subtree (the hashed layout's entries)"},
       {"pointer_layout_bytes", "node memory of storage=pointer for this tree"},
       {"linear_layout_bytes", "node memory of storage=linear for this tree (complete tree to its depth)"},
       {"hash_layout_bytes", "node memory of storage=hash for this tree"},
       {"list_blocks", "SIMD triangle blocks of the node lists (0 with simd=0 or tri=mt)"}});
  // Bench's memory estimate: peak RSS growth measured 239 B/tri on soup:n=10^7 (term=count, before the
  // SIMD lists) and 266 on soup:n=10^6 with the SIMD lists and term=sah (term=count: 514).
  info.build_peak_bytes_per_triangle = 300;
  return info;
}

}  // namespace raylab
