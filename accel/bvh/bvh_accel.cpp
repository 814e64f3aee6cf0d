// `bvh`: the BVH family. A spec picks a builder for the canonical binary tree,
// an optional optimisation pass, and a traversal layout the tree is converted
// into:
//
//   builder=binned|sweep|sbvh|lbvh   opt=none|light|reinsert   layout=bvh2|bvh4|bvh8|bvh16
//   packet=0|16 (bvh8, bvh16: closest-hit batches traced as 16-ray frustum packets)
//   simd=1|0 (0: the wide layouts walked with scalar tests, same hits and counts)
//   node=f32|q8 (bvh8: float child boxes, or 8-bit planes on a per-node grid, quantized_node.h)
//
// Every combination reports the same statistics: build ms, bytes, nodes,
// leaves, depth and SAH cost of the traced structure (constants in
// bvh2_node.h), plus structure-specific figures in BuildStats::extra.
#include "accel/bvh/bvh_accel.h"

#include <cmath>
#include <memory>
#include <stdexcept>
#include <type_traits>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "accel/bvh/build_binned_sah.h"
#include "accel/bvh/build_lbvh.h"
#include "accel/bvh/build_sbvh.h"
#include "accel/bvh/build_sweep_sah.h"
#include "accel/bvh/optimize_reinsertion.h"
#include "accel/bvh/presplit.h"
#include "accel/bvh/quantized_node.h"
#include "accel/bvh/bvh2_layout.h"
#include "accel/bvh/occlusion_order.h"
#include "accel/bvh/bvh_outline.h"
#include "accel/bvh/collapse_wide.h"
#include "accel/bvh/traverse_sphere_bvh.h"
#include "accel/bvh/traverse_packet.h"
#include "accel/bvh/traverse_wide.h"
#include "accel/core/simd_param.h"
#include "accel/core/batch_accelerator.h"
#include "accel/core/triangle_test_param.h"
#include "base/timer.h"

namespace raylab {

namespace {

enum class BuilderKind { Binned, Sweep, Sbvh, Lbvh };
enum class LayoutKind { Bvh2, Bvh4, Bvh8, Bvh16 };

struct BvhConfig {
  BuilderKind builder = BuilderKind::Binned;
  LayoutKind layout = LayoutKind::Bvh8;
  bool reinsert = true;  // opt=light or reinsert (the rounds and batch say which)
  // Defaults as declared in bvh_accelerator_info (the spec parser fills
  // every field; these only matter to code that builds a config directly).
  int leaf = 16;              // max references per leaf (auto: bvh2 4, wide 2 blocks)
  int block = 8;              // triangles per SIMD block
  int bins = 64;
  int binary_leaf = 3;        // ranges this small become binary leaves without SAH test (auto: light 3, reinsert 1, none 4)
  float alpha = 1e-5f;        // SBVH overlap threshold
  float split_budget = 0.5f;  // SBVH extra references / triangles
  int spatial_min = 0;        // SBVH: minimum references for spatial split attempts
  int spatial_bins = 32;      // SBVH: slabs per axis
  bool split_planar = true;   // SBVH: spatial splits may cut axis-planar triangles (sflat=1)
  float presplit = 0.0f;      // binned: pre-split budget, extra references / triangles (presplit.h)
  float big_node = 0.1f;      // binned: large references in a child of their own (BuildOptions::big_node)
  float big_root = 0.03f;     // binned: the same against the root's area (BuildOptions::big_root)
  int big_min = 1024;         // binned: at nodes of at least this many references
  int opt_rounds = 4;         // reinsertion rounds (work, not time; auto: light 4, reinsert 32)
  double opt_batch = 0.005;   // reinsertion: nodes considered per round, a fraction of all nodes (auto: light 0.005, reinsert 0.15)
  float thick_limit = 0.0f;   // collapse: thick leaves (collapse_wide.h; auto: 0.4 on bvh16 without opt=reinsert, else off)
  float thick_area = 0.005f;  // collapse: ... above this fraction of the root box's surface area
  float node_cost = 2.0f;   // collapse: cost of a node visit
  float block_cost = 1.0f;  // collapse: cost of one block test
  TriangleTest tri = TriangleTest::Watertight;
  bool spheres = false;  // bound=sphere: the bvh2 tree with bounding spheres (traverse_sphere_bvh.h)
  int packet = 0;  // 16: closest-hit batches as 16-ray frustum packets (traverse_packet.h); bvh8 or bvh16
  bool simd = true;  // false: wide layouts walked with scalar tests (the algorithm-only comparison)
  bool quantized = false;  // node=q8: compressed 8-wide nodes (bvh8, single rays)
  bool occlusion_order = false;  // aorder=rtsah: child slots ordered for any-hit walks (occlusion_order.h)
  bool octant_walks = true;  // owalk=1: coherent batches take octant-specialised walks (traverse_wide.h)
  bool ahead = true;  // ahead=1: each ray's box-test scalars computed while the ray before walks (trace_rays_ahead)
};

int layout_width(LayoutKind l) {
  return l == LayoutKind::Bvh2 ? 2 : l == LayoutKind::Bvh4 ? 4 : l == LayoutKind::Bvh16 ? 16 : 8;
}

// The traversal structure behind the accelerator: one virtual call per batch.
class Kernel {
 public:
  virtual ~Kernel() = default;
  virtual void intersect(std::span<const Ray> rays, std::span<Hit> hits, TraversalStats* stats) const = 0;
  virtual void occluded(std::span<const Ray> rays, std::span<uint8_t> occ, TraversalStats* stats) const = 0;
  virtual void outline(int max_depth, StructureOutline& out) const = 0;
};

// The binary tree traced one ray at a time, with boxes (bvh2) or spheres
// (bound=sphere) as node bounds: the tree, its view, its walk
// (traverse_view) and its picture.
template <typename Tree, typename View, View (*kViewOf)(const Tree&),
          void (*kOutline)(const Tree&, int, StructureOutline&)>
class BinaryTreeKernel final : public BatchAccelerator<BinaryTreeKernel<Tree, View, kViewOf, kOutline>, Kernel> {
 public:
  BinaryTreeKernel(Tree tree, TriangleTest tri)
      : BatchAccelerator<BinaryTreeKernel, Kernel>(tri), tree_(std::move(tree)), view_(kViewOf(tree_)) {}

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

// The wide layouts test triangles with the vectorised watertight test, or
// with tri=mt the vectorised Moller-Trumbore test on blocks holding edges
// (a study option: what watertightness costs on the same tree and walk).
// kScalar: `simd=0`, the same tree and walk with scalar tests (traverse_wide.h).
// Node: WideNode<N>, or QuantNode8 (node=q8; single rays only, not simd=0).
template <int N, int W, bool kScalar = false, typename Node = WideNode<N>>
class WideKernel final : public BatchAccelerator<WideKernel<N, W, kScalar, Node>, Kernel> {
  using Batch = BatchAccelerator<WideKernel<N, W, kScalar, Node>, Kernel>;
  static constexpr bool kFloatNodes = std::is_same_v<Node, WideNode<N>>;
  // Octant-specialised walks for coherent batches (traverse_wide.h, batch_is_octant_coherent);
  // 8-triangle blocks only: sixteen walks more per kernel (they made this file's
  // compilation 50 % longer for all seven float-node kernels).
  static constexpr bool kOctantWalks = !kScalar && kFloatNodes && W == 8;
  // Node widths the packet walk takes (traverse_packet.h).
  static constexpr bool kPacketWidth = (N == 8 || N == 16) && !kScalar && kFloatNodes;
  static_assert(kFloatNodes || !kScalar, "simd=0 walks float nodes");

 public:
  WideKernel(WideBvh<N, W, Node> bvh, bool packets, TriangleTest tri, bool octant_walks = false, bool ahead = true)
      : Batch(tri), bvh_(std::move(bvh)), packets_(packets), octant_walks_(octant_walks), ahead_(ahead) {
    view_ = WideView<N, W, Node>{bvh_.nodes.data(), bvh_.blocks.data(), bvh_.root_ref,
                                 wide_fma_origin_limit(bvh_.root_box)};
    // The packet walk pushes leaves as (parent node, slot) in a child reference.
    if constexpr (kPacketWidth) {
      if (packets_ && bvh_.nodes.size() > PacketTracer<N, W>::kMaxNodes)
        throw std::runtime_error("bvh: too many nodes for packet=16");
    }
  }

  // packet=16: uninstrumented closest-hit batches go through the packet
  // tracer (same answers); counted batches take the single-ray kernel, whose
  // counters mean what every structure's mean.
  void intersect(std::span<const Ray> rays, std::span<Hit> hits, TraversalStats* stats) const override {
    if constexpr (kPacketWidth) {
      if (packets_ && !stats) {
        // Rays that form no packet take this kernel's single-ray batch loop.
        PacketTracer<N, W>(view_).intersect(rays, hits, [&](std::span<const Ray> r, std::span<Hit> h) {
          trace_uncounted<false>(r, nullptr, [&](size_t i, const Hit& hit) { h[i] = hit; });
        });
        return;
      }
    }
    if (trace_uncounted<false>(rays, stats, [&](size_t i, const Hit& h) { hits[i] = h; })) return;
    Batch::intersect(rays, hits, stats);
  }
  void occluded(std::span<const Ray> rays, std::span<uint8_t> occ, TraversalStats* stats) const override {
    if (trace_uncounted<true>(rays, stats, [&](size_t i, const Hit& h) { occ[i] = h.valid(); })) return;
    Batch::occluded(rays, occ, stats);
  }

  // Traces an uncounted batch with vector tests, out(i, hit) per ray, and
  // returns true. A batch whose rays mostly share an octant (camera rays,
  // shadow rays towards one light) has each ray's box-test scalars computed
  // while the ray before it walks (trace_rays_ahead), and if watertight takes
  // the octant walks. Incoherent batches compute them when each ray starts:
  // their walks are long, the set-up's latency a small part of them, and the
  // hand-over's instructions measured 1-3 % slower there (Zen 3, AVX2). Else
  // false: counted batches keep the shell's loop, whose
  // counters every structure shares, and simd=0 its scalar kernel.
  template <bool kAnyHit, typename Out>
  bool trace_uncounted(std::span<const Ray> rays, TraversalStats* stats, Out&& out) const {
    if constexpr (kScalar) {
      return false;
    } else {
      if (stats) return false;
      // The scan only where its answer is used.
      const bool coherent = (ahead_ || (kOctantWalks && octant_walks_)) && batch_is_octant_coherent(rays);
      if constexpr (kOctantWalks) {
        if (octant_walks_ && this->triangle_test() == TriangleTest::Watertight && coherent) {
          trace_rays_ahead(
              rays, ahead_, [&](const Ray& r, const NodeRayScalars* a) { return traverse_wide_octant<N, W, kAnyHit>(view_, r, a); },
              out);
          return true;
        }
      }
      dispatch_triangle_test(this->triangle_test(), [&]<TriangleTest kTest>() {
        trace_rays_ahead(
            rays, ahead_ && coherent,
            [&](const Ray& r, const NodeRayScalars* a) {
              return traverse_wide<N, W, kAnyHit, false, false, kTest>(view_, r, nullptr, a);
            },
            out);
      });
      return true;
    }
  }

  template <TriangleTest kTest, bool kAnyHit, bool kCount>
  Hit trace(const Ray& ray, TraversalStats* stats) const {
    if constexpr (kScalar) return traverse_wide<N, W, kAnyHit, kCount, true>(view_, ray, stats);  // watertight only
    else return traverse_wide<N, W, kAnyHit, kCount, false, kTest>(view_, ray, stats);
  }
  void outline(int max_depth, StructureOutline& out) const override { outline_wide(bvh_, max_depth, out); }
  size_t bytes() const { return bvh_.bytes(); }

 private:
  WideBvh<N, W, Node> bvh_;
  bool packets_;
  bool octant_walks_;
  bool ahead_;
  WideView<N, W, Node> view_;
};

template <int N, int W, bool kScalar = false>
std::unique_ptr<Kernel> make_wide_kernel(const WideTree& tree, const TriangleMesh& mesh, bool packets,
                                         TriangleTest tri, size_t& bytes, bool octant_walks = false,
                                         bool ahead = true) {
  const bool edges = tri == TriangleTest::MollerTrumbore;
  auto k = std::make_unique<WideKernel<N, W, kScalar>>(make_wide_bvh<N, W>(tree, mesh, edges), packets, tri,
                                                     octant_walks, ahead);
  bytes = k->bytes();
  return k;
}

// node=q8: the same tree with compressed nodes.
template <int W>
std::unique_ptr<Kernel> make_quantized_kernel(const WideTree& tree, const TriangleMesh& mesh, TriangleTest tri,
                                              size_t& bytes, QuantLooseness& looseness, bool ahead) {
  const bool edges = tri == TriangleTest::MollerTrumbore;
  auto k = std::make_unique<WideKernel<8, W, false, QuantNode8>>(
      quantize_wide_bvh<W>(make_wide_bvh<8, W>(tree, mesh, edges), &looseness), false, tri, false, ahead);
  bytes = k->bytes();
  return k;
}

class BvhAccel final : public Accelerator {
 public:
  explicit BvhAccel(const BvhConfig& c) : cfg_(c) {
    if (!simd::isa_supported_by_cpu())
      throw std::runtime_error(fmt::format("bvh: this binary was built for {} but the CPU does not support it "
                                           "(rebuild with -DRAYLAB_NATIVE=ON on this machine)",
                                           simd::isa_name()));
  }

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
    CollapseOptions co;
    co.width = layout_width(cfg_.layout);
    co.block_width = block_width();
    co.max_leaf = cfg_.leaf;
    co.max_leaf_blocks = co.width == 2 ? 1 << 20 : static_cast<int>(wide_ref::kMaxBlocks);
    co.node_cost = cfg_.node_cost;
    co.block_cost = cfg_.block_cost;
    co.thick_leaf_area = cfg_.thick_area;
    co.thick_leaf_limit = cfg_.thick_limit;
    co.mesh = &mesh;
    WideTree wide = collapse_to_wide(tree, co);
    if (cfg_.occlusion_order)
      s.extra["occlusion_root"] = order_children_for_occlusion(wide, mesh, {co.node_cost, co.block_cost, co.block_width});
    const WideShape shape = measure_wide(wide);
    s.extra["ms_collapse"] = phase.ms();
    s.extra["avg_leaf_size"] = shape.avg_leaf_size;
    s.extra["child_fill"] = shape.child_fill;

    phase.reset();
    s.bytes = make_kernel(wide, shape, mesh, s);
    s.extra["ms_layout"] = phase.ms();
    s.nodes = cfg_.layout == LayoutKind::Bvh2 ? 2 * shape.nodes + 1 : shape.nodes;
    s.leaves = shape.leaves;
    s.max_depth = shape.max_depth;
    s.avg_depth = shape.avg_leaf_depth;
    s.sah_cost = shape.sah_cost;
    return s;
  }

 private:
  int block_width() const { return cfg_.layout == LayoutKind::Bvh2 ? 1 : cfg_.block; }

  // The canonical binary tree by the configured builder, then the optional
  // reinsertion pass. Builders bound the depth (median splits beyond
  // kForceMedianDepth, LBVH by its key length, reinsertion by rejecting
  // deeper results); the wide layouts check their depth against the stack.
  BinaryBvh build_binary_tree(const TriangleMesh& mesh, BuildStats& s) const {
    Timer phase;
    const size_t n = mesh.num_triangles();
    // Triangle boxes and centroids (box centres); the binned builder takes
    // its references directly, the other builders the two arrays.
    std::vector<Aabb> boxes;
    std::vector<Vec3f> centroids;
    std::vector<BuildRef> refs;
    if (cfg_.builder == BuilderKind::Binned) {
      // presplit=0 (the default): one reference per triangle, its box.
      PresplitOptions po;
      po.budget = cfg_.presplit;
      PresplitStats ps;
      refs = presplit_references(mesh, po, &ps);
      if (cfg_.presplit > 0.0f) s.extra["presplit_triangles"] = static_cast<double>(ps.triangles_split);
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
    bo.big_min = static_cast<size_t>(cfg_.big_min);
    s.extra["ms_prepare"] = phase.ms();
    phase.reset();
    BinaryBvh tree;
    switch (cfg_.builder) {
      case BuilderKind::Binned: {
        BinnedBuildStats bs;
        tree = build_binned_sah(std::move(refs), bo, &bs);
        s.extra["big_splits"] = static_cast<double>(bs.big_splits);
        break;
      }
      case BuilderKind::Sweep: tree = build_sweep_sah(boxes, centroids, bo); break;
      case BuilderKind::Lbvh: tree = build_lbvh(boxes, centroids); break;
      case BuilderKind::Sbvh: {
        SbvhOptions so;
        so.base = bo;
        so.alpha = cfg_.alpha;
        so.split_budget = cfg_.split_budget;
        so.min_spatial_refs = static_cast<size_t>(cfg_.spatial_min);
        so.spatial_bins = cfg_.spatial_bins;
        so.split_planar = cfg_.split_planar;
        SbvhStats ss;
        tree = build_sbvh(boxes, centroids, TriangleSplitter(mesh), so, &ss);
        s.extra["spatial_splits"] = static_cast<double>(ss.spatial_splits);
        break;
      }
    }
    s.extra["ms_tree"] = phase.ms();
    s.extra["refs_per_triangle"] = n ? static_cast<double>(tree.prim_ids.size()) / n : 0.0;
    if (cfg_.reinsert) {
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
    if (cfg_.spheres) {
      SphereBvh sb = make_sphere_bvh(make_bvh2_layout(wide, mesh));
      s.extra["sphere_volume_ratio"] = sb.looseness.volume_ratio;
      s.extra["sphere_area_ratio"] = sb.looseness.area_ratio;
      s.extra["sphere_node_area_ratio"] = sb.looseness.mean_node_area_ratio;
      bytes = sb.bytes();
      kernel_ = std::make_unique<SphereKernel>(std::move(sb), cfg_.tri);
      return bytes;
    }
    if (cfg_.layout == LayoutKind::Bvh2) {
      Bvh2Layout l = make_bvh2_layout(wide, mesh);
      bytes = l.bytes();
      kernel_ = std::make_unique<Bvh2Kernel>(std::move(l), cfg_.tri);
      return bytes;
    }
    const bool fits = cfg_.layout == LayoutKind::Bvh4    ? wide_stack_fits<4>(shape.max_depth)
                      : cfg_.layout == LayoutKind::Bvh16 ? wide_stack_fits<16>(shape.max_depth)
                                                         : wide_stack_fits<8>(shape.max_depth);
    if (!fits) throw std::runtime_error("bvh: tree too deep for the traversal stack");
    const int block = block_width();
    const bool packets = cfg_.packet == kPacketSize;
    if (cfg_.quantized) {  // bvh8, simd=1, packet=0 (checked by the spec parser)
      QuantLooseness loose;
      if (block == 4) kernel_ = make_quantized_kernel<4>(wide, mesh, cfg_.tri, bytes, loose, cfg_.ahead);
      else if (block == 8) kernel_ = make_quantized_kernel<8>(wide, mesh, cfg_.tri, bytes, loose, cfg_.ahead);
      else kernel_ = make_quantized_kernel<16>(wide, mesh, cfg_.tri, bytes, loose, cfg_.ahead);
      s.extra["q8_area_ratio"] = loose.area_ratio();
    } else if (!cfg_.simd) {  // block=8 (checked by the spec parser)
      if (cfg_.layout == LayoutKind::Bvh4) kernel_ = make_wide_kernel<4, 8, true>(wide, mesh, false, cfg_.tri, bytes);
      else if (cfg_.layout == LayoutKind::Bvh16) kernel_ = make_wide_kernel<16, 8, true>(wide, mesh, false, cfg_.tri, bytes);
      else kernel_ = make_wide_kernel<8, 8, true>(wide, mesh, false, cfg_.tri, bytes);
    } else if (cfg_.layout == LayoutKind::Bvh16) {  // block=8 (checked by the spec parser)
      kernel_ = make_wide_kernel<16, 8>(wide, mesh, packets, cfg_.tri, bytes, cfg_.octant_walks, cfg_.ahead);
    } else if (cfg_.layout == LayoutKind::Bvh4) {
      if (block == 4) kernel_ = make_wide_kernel<4, 4>(wide, mesh, false, cfg_.tri, bytes, cfg_.octant_walks, cfg_.ahead);
      else if (block == 8) kernel_ = make_wide_kernel<4, 8>(wide, mesh, false, cfg_.tri, bytes, cfg_.octant_walks, cfg_.ahead);
      else kernel_ = make_wide_kernel<4, 16>(wide, mesh, false, cfg_.tri, bytes, cfg_.octant_walks, cfg_.ahead);
    } else {
      if (block == 4) kernel_ = make_wide_kernel<8, 4>(wide, mesh, packets, cfg_.tri, bytes, cfg_.octant_walks, cfg_.ahead);
      else if (block == 8) kernel_ = make_wide_kernel<8, 8>(wide, mesh, packets, cfg_.tri, bytes, cfg_.octant_walks, cfg_.ahead);
      else kernel_ = make_wide_kernel<8, 16>(wide, mesh, packets, cfg_.tri, bytes, cfg_.octant_walks, cfg_.ahead);
    }
    s.extra["simd_bits"] = simd::isa_bits();
    s.extra["block_width"] = block;
    s.extra["node_width"] = layout_width(cfg_.layout);
    return bytes;
  }

  BvhConfig cfg_;
  std::unique_ptr<Kernel> kernel_;
};

}  // namespace

std::string bvh_kernel_isa() { return simd::isa_name(); }

AcceleratorInfo bvh_accelerator_info() {
  AcceleratorInfo info{
      "bvh",
      fmt::format("BVH family: SAH builders, optional reinsertion, SAH-optimal wide collapse, SIMD kernels ({})",
                  simd::isa_name()),
      {{"builder", "binned", "binary tree builder: binned (SAH), sweep (full-sweep SAH), sbvh (spatial splits), lbvh (Morton)",
        one_of({"binned", "sweep", "sbvh", "lbvh"})},
       {"layout", "auto", "traversal layout: bvh2, bvh4, bvh8, bvh16 (16-wide nodes, 448 bytes: one AVX-512 "
        "instruction per plane; block=8, node=f32) or auto (bvh16 where the kernel is AVX-512 "
        "and the spec allows it, else bvh8)",
        one_of({"auto", "bvh2", "bvh4", "bvh8", "bvh16"})},
       {"opt", "light", "post-build optimisation: none, light (four reinsertion rounds over the worst 0.5 % of the nodes, "
        "3-triangle binary leaves; the default) or reinsert (up to 32 rounds over 15 %, single-triangle leaves; the "
        "high-quality preset)",
        one_of({"none", "light", "reinsert"})},
       {"leaf", "auto", "max triangles per leaf (auto = layout default: bvh2 4, wide 2 blocks)",
        integer_in(1, 255).or_word("auto")},
       {"block", "8", "wide layouts: triangles per SIMD test block (4, 8 or 16)", integer_of({4, 8, 16})},
       {"bins", "64", "SAH bins per axis for nodes of 1024 references or more (fewer below: 8 under 128, 16 under 1024), 2..256", integer_in(2, 256)},
       {"bleaf", "auto", "binary tree: ranges of at most this many triangles become leaves before the collapse "
        "(auto: 1 with opt=reinsert, which moves leaves whole, 3 with opt=light, 4 with opt=none)",
        integer_in(1, 16).or_word("auto")},
       {"alpha", "1e-5", "sbvh: try spatial splits when children overlap more than alpha * root area",
        real_in(0, kUnbounded).as_float()},
       {"sbudget", "0.5", "sbvh: split budget, extra references as a fraction of the triangle count", real_in(0, 4).as_float()},
       {"smin", "0", "sbvh: try spatial splits only at nodes with at least this many references",
        integer_in(0, kUnbounded)},
       {"presplit", "0", "binned: pre-split budget, extra references as a fraction of the triangle count; the "
        "triangles whose boxes exceed them most, near the coarsest planes of the scene's dyadic grid, are cut there "
        "before the build (Karras & Aila 2013)",
        real_in(0, 4).as_float()},
       {"big", "0.1", "binned: at nodes of at least bigmin references, the references whose boxes have more than "
        "this fraction of the node box's surface area (or bigroot of the root box's) become a child of their own, "
        "when they are at most a quarter of the node's: floors and walls no longer stretch every box on their way "
        "down; 0 = off", real_in(0, 1).as_float()},
       {"bigroot", "0.03", "binned: as big, against the root box's surface area (the scene's largest triangles "
        "together under the root); 0 = off", real_in(0, 1).as_float()},
       {"bigmin", "1024", "binned: big and bigroot apply at nodes of at least this many references",
        integer_in(1, kUnbounded)},
       {"sbins", "32", "sbvh: spatial split slabs per axis (2..256)", integer_in(2, 256)},
       {"sflat", "1", "sbvh: 1 (spatial splits may cut axis-planar triangles: floors, walls) or 0 (they stay whole: "
        "on the Sponza views fewer box tests for shadow rays, more for camera rays; a study option)",
        integer_of({0, 1})},
       {"opt_rounds", "auto", "reinsertion: at most this many rounds (auto: light 4, reinsert 32; work-bounded: the tree "
        "does not depend on machine load)",
        integer_in(0, 1000).or_word("auto")},
       {"opt_batch", "auto", "reinsertion: nodes considered per round, a fraction of all nodes, the worst by Bittner's "
        "measure (auto: light 0.005, reinsert 0.15)",
        real_in(0, 1, Ends::OpenLow).or_word("auto")},
       {"thick", "auto", "collapse: a leaf merging several binary leaves is not formed when its box is larger than "
        "thickarea of the root box's surface area and thicker than this (its volume over that of the cube with the same "
        "surface area: 1 a cube, 0 flat); such boxes (a floor and a wall together) are entered by every ray starting "
        "inside them. 0 = off (auto: 0.4 on bvh16 with opt=light or none, else 0)",
        real_in(0, 1).as_float().or_word("auto")},
       {"thickarea", "0.005", "collapse: thick leaves (see thick) count from this fraction of the root box's surface area",
        real_in(0, 1).as_float()},
       {"ct", "2", "collapse SAH cost of a node visit (relative to ci)", real_in(0, kUnbounded, Ends::Open).as_float()},
       {"ci", "1", "collapse SAH cost of a triangle block test (bvh2: of a triangle)", real_in(0, kUnbounded, Ends::Open).as_float()},
       triangle_test_param("; mt: not with simd=0 or packet=16"),
       {"packet", "0", "bvh8, bvh16: 0 (single rays) or 16 (closest-hit batches: 16 rays from one origin as one frustum, other rays singly)",
        integer_of({0, kPacketSize})},
       {"bound", "box", "node bounds: box, or sphere (Ritter spheres on the bvh2 tree; layout=bvh2 implied)",
        one_of({"box", "sphere"})},
       {"node", "f32", "bvh8 child boxes: f32 (float planes, 256-byte nodes) or q8 (8-bit planes on a per-node "
        "power-of-two grid, conservative and exactly decoded, 128-byte nodes; single rays, not with packet=16 or simd=0)",
        one_of({"f32", "q8"})},
       {"aorder", "slot", "wide layouts, any-hit child order: slot (the collapse's, descending) or rtsah (slots ordered "
        "by estimated occlusion per cost, Ize & Hansen 2011; the same tree and closest hits)",
        one_of({"slot", "rtsah"})},
       {"owalk", "1", "wide layouts with float nodes and block=8: 1 (batches whose rays mostly share a direction octant, such as "
        "camera rays, walk with the node test specialised to each ray's octant) or 0 (the general walk for every batch; "
        "a study option, the same answers)",
        integer_of({0, 1})},
       {"ahead", "1", "wide layouts with simd=1: 1 (in batches whose rays mostly share a direction octant, such as camera "
        "rays, each ray's box-test reciprocals and offsets are computed while the ray before it walks, so their latency "
        "hides behind that walk) or 0 (computed when each ray starts; a study option, the same answers)",
        integer_of({0, 1})},
       simd_param("SIMD node and leaf tests",
                  " and counts; wide layouts need block=8; bvh2 is scalar either way")},
      [](const Params& p) -> std::unique_ptr<Accelerator> {
        BvhConfig c;
        const auto& b = p.str("builder");
        c.builder = b == "sweep" ? BuilderKind::Sweep : b == "sbvh" ? BuilderKind::Sbvh : b == "lbvh" ? BuilderKind::Lbvh : BuilderKind::Binned;
        c.spheres = p.str("bound") == "sphere";
        if (c.spheres && p.given("layout") && p.str("layout") != "bvh2")
          throw SpecError("bvh: bound=sphere needs layout=bvh2");
        const auto& l = c.spheres ? std::string("bvh2") : p.str("layout");
        // auto is settled below, once packet, simd, node and block are known.
        c.layout = l == "bvh2"    ? LayoutKind::Bvh2
                   : l == "bvh4"  ? LayoutKind::Bvh4
                   : l == "bvh16" ? LayoutKind::Bvh16
                                  : LayoutKind::Bvh8;
        // opt=light, the default: four rounds over the worst 0.5 % of the
        // nodes of a tree with leaves of up to 3 triangles. A few rounds of
        // small batches move the few badly placed subtrees that cost
        // incoherent rays most (large triangles deep in the tree; each round
        // re-ranks after the last one's moves), and leaves of 3 instead of 4
        // let them move alone: +20 % on shadow rays, +6 % random, +3 %
        // diffuse over one round of 2 % on 4-triangle leaves, for a build
        // still under Embree's (docs/structures/bvh.md). The full
        // reinsertion is the preset (32 rounds over 15 %, at 5-35x Embree's build).
        const std::string& opt = p.str("opt");
        const bool light = opt == "light", full = opt == "reinsert";
        c.reinsert = light || full;
        c.block = p.integer("block");
        // The leaf limit depends on the layout (a wide leaf holds at most kMaxBlocks blocks).
        c.leaf = p.str("leaf") == "auto" ? (c.layout == LayoutKind::Bvh2 ? 4 : 2 * c.block) : p.integer("leaf");
        const int max_leaf = c.layout == LayoutKind::Bvh2 ? 255 : static_cast<int>(wide_ref::kMaxBlocks) * c.block;
        if (c.leaf > max_leaf) throw SpecError(fmt::format("bvh: leaf must be in 1..{}", max_leaf));
        c.bins = p.integer("bins");
        // Reinsertion moves leaves whole: single-triangle leaves let it move
        // every triangle (+4 % over bleaf=4 on the interior views, all four
        // ray sets). The collapse merges them
        // into wide leaves afterwards either way.
        c.binary_leaf = p.str("bleaf") == "auto" ? (full ? 1 : light ? 3 : 4) : p.integer("bleaf");
        c.alpha = static_cast<float>(p.real("alpha"));
        c.split_budget = static_cast<float>(p.real("sbudget"));
        c.opt_rounds = p.str("opt_rounds") == "auto" ? (light ? 4 : 32) : p.integer("opt_rounds");
        c.opt_batch = p.str("opt_batch") == "auto" ? (light ? 0.005 : 0.15) : p.real("opt_batch");
        c.spatial_min = p.integer("smin");
        c.spatial_bins = p.integer("sbins");
        c.thick_area = static_cast<float>(p.real("thickarea"));
        c.split_planar = p.integer("sflat") == 1;
        c.presplit = static_cast<float>(p.real("presplit"));
        if (c.presplit > 0.0f && c.builder != BuilderKind::Binned)
          throw SpecError("bvh: presplit needs builder=binned");
        // big / bigroot (on by default with the binned builder): a node's
        // large references as a child of their own. Centroid splits never
        // separate references by size, so a floor stretches the box of every
        // node down to its leaf; with the split, camera rays walk 7 % fewer
        // nodes and shadow rays 21 % fewer over 34 views of the interior
        // scenes; primary and diffuse rays 3-5 % faster, shadow 1-8 %, random
        // 0-2 % (conference's shadow rays 6 % slower).
        c.big_node = static_cast<float>(p.real("big"));
        c.big_root = static_cast<float>(p.real("bigroot"));
        c.big_min = p.integer("bigmin");
        if (c.builder != BuilderKind::Binned) {
          if ((p.given("big") && c.big_node > 0.0f) || (p.given("bigroot") && c.big_root > 0.0f) || p.given("bigmin"))
            throw SpecError("bvh: big, bigroot and bigmin need builder=binned");
          c.big_node = c.big_root = 0.0f;
        }
        c.node_cost = static_cast<float>(p.real("ct"));
        c.block_cost = static_cast<float>(p.real("ci"));
        c.tri = parse_triangle_test(p);
        c.packet = p.integer("packet");
        c.simd = parse_simd(p);
        c.quantized = p.str("node") == "q8";
        c.occlusion_order = p.str("aorder") == "rtsah";
        c.octant_walks = p.integer("owalk") == 1;
        c.ahead = p.integer("ahead") == 1;
        // layout=auto: 16-wide nodes where one AVX-512 instruction tests a
        // plane of all sixteen children and nothing in the spec needs 8-wide
        // ones (simd=0 follows, so that it stays the same tree with scalar
        // tests); they beat bvh8 on every ray set of the interior views on
        // machines with AVX-512. Elsewhere a 16-wide plane takes
        // two or four instructions, and bvh8 stays the layout.
        if (l == "auto")
          c.layout = simd::isa_bits() >= 512 && !c.quantized && c.block == 8
                         ? LayoutKind::Bvh16
                         : LayoutKind::Bvh8;
        // Thick leaves (collapse_wide.h), measured on 16-wide trees after the
        // light pass: camera rays +4 %, shadow +3 % (Sponza's shadow rays a
        // third fewer triangle tests, conference's camera rays +15 %). Off
        // with 8-wide nodes, where an opened leaf costs a level of its own
        // (Sponza's shadow rays 2.3x the box tests, 0.6x the speed), and with
        // the full reinsertion, which moves such triangles apart itself (the
        // limit only adds node tests there: +5 % over the 34 views);
        // docs/structures/bvh.md.
        c.thick_limit = p.str("thick") != "auto" ? static_cast<float>(p.real("thick"))
                        : c.layout == LayoutKind::Bvh16 && !full ? 0.4f
                                                                 : 0.0f;
        if (!c.simd && c.packet != 0) throw SpecError("bvh: packet=16 needs simd=1");
        if (!c.simd && c.layout != LayoutKind::Bvh2 && c.block != 8)
          throw SpecError("bvh: simd=0 with a wide layout needs block=8");
        if (c.packet != 0 && c.layout != LayoutKind::Bvh8 && c.layout != LayoutKind::Bvh16)
          throw SpecError("bvh: packet=16 needs layout=bvh8 or bvh16");
        // The binary walk orders both children by entry distance, any hit too: no slot order to set.
        if (c.occlusion_order && c.layout == LayoutKind::Bvh2)
          throw SpecError("bvh: aorder=rtsah needs a wide layout (bvh4, bvh8, bvh16)");
        if (c.layout == LayoutKind::Bvh16 && c.block != 8) throw SpecError("bvh: layout=bvh16 needs block=8");
        if (p.given("owalk") && (c.layout == LayoutKind::Bvh2 || c.quantized || !c.simd || c.block != 8))
          throw SpecError("bvh: owalk needs a wide layout with float nodes, block=8 and simd=1");
        if (p.given("ahead") && (c.layout == LayoutKind::Bvh2 || !c.simd))
          throw SpecError("bvh: ahead needs a wide layout and simd=1");
        if (c.quantized && (c.layout != LayoutKind::Bvh8 || c.packet != 0 || !c.simd))
          throw SpecError("bvh: node=q8 needs layout=bvh8, packet=0 and simd=1");
        if (c.tri != TriangleTest::Watertight && c.layout != LayoutKind::Bvh2 && (!c.simd || c.packet != 0))
          throw SpecError("bvh: tri=mt with a wide layout needs simd=1 and packet=0 (the scalar and packet tests are watertight only)");
        return std::make_unique<BvhAccel>(c);
      }};
  info.caps.mt_variant = "tri=mt,layout=bvh2";
  info.caps.scalar_variant = "simd=0";
  info.caps.outline = true;
  info.cover = {"bvh:layout=bvh2", "bvh:layout=bvh4", "bvh:layout=bvh2,tri=mt", "bvh:tri=mt", "bvh:builder=sweep",
                "bvh:builder=sbvh", "bvh:builder=lbvh,opt=reinsert", "bvh:block=4", "bvh:block=16", "bvh:packet=16",
                "bvh:bound=sphere", "bvh:bound=sphere,tri=mt", "bvh:simd=0", "bvh:simd=0,layout=bvh4", "bvh:node=q8", "bvh:node=q8,tri=mt",
                "bvh:layout=bvh16", "bvh:layout=bvh8", "bvh:presplit=0.3", "bvh:layout=bvh8,thick=0.2,thickarea=0.001"};
  info.describe = [] { return Description{{"isa", simd::isa_name()}}; };
  info.stats = {{"ms_prepare", "ms: triangle boxes and centroids"},
                {"ms_tree", "ms: the binary tree"},
                {"ms_measure", "ms: measuring the binary tree"},
                {"ms_collapse", "ms: SAH-optimal collapse to the layout's width"},
                {"ms_layout", "ms: the traversal layout (nodes, triangle blocks)"},
                {"refs_per_triangle", "references per triangle (sbvh and presplit duplicate split triangles)"},
                {"spatial_splits", "sbvh: spatial splits taken"},
                {"big_splits", "binned: nodes whose large references became a child of their own (big, bigroot)"},
                {"presplit_triangles", "presplit: triangles cut before the build"},
                {"sah_tree", "SAH cost of the binary tree before the collapse (reporting constants)"},
                {"sah_before_opt", "reinsert: SAH cost before"},
                {"sah_after_opt", "reinsert: SAH cost after"},
                {"opt_ms", "reinsert: ms spent"},
                {"opt_rounds", "reinsert: rounds run"},
                {"opt_moves", "reinsert: subtrees moved"},
                {"occlusion_root", "aorder=rtsah: estimated chance that a random line through the root box is blocked"},
                {"avg_leaf_size", "mean triangles per leaf"},
                {"child_fill", "mean children per inner node over the width"},
                {"simd_bits", "wide layouts: SIMD width of the kernels in bits"},
                {"block_width", "wide layouts: triangles per SIMD block"},
                {"node_width", "wide layouts: children per node (4, 8 or 16; layout=auto resolved)"},
                {"q8_area_ratio", "node=q8: sum of decoded child box areas / sum of float child box areas"},
                {"sphere_volume_ratio", "bound=sphere: sum of sphere volumes / sum of box volumes over all nodes"},
                {"sphere_area_ratio", "bound=sphere: sum of sphere surface areas / sum of box surface areas"},
                {"sphere_node_area_ratio", "bound=sphere: mean over nodes of sphere area / box area"}};
  info.build_peak_bytes_per_triangle = 170;  // measured 164 on soup:n=10^7

  return info;
}

}  // namespace raylab
