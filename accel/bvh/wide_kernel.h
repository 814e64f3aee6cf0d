#pragma once
// The wide layouts' kernel: the N-wide tree with 8-triangle blocks and its
// walks (traverse_wide.h, traverse_packet.h) behind the batch interface.
// Included only by wide_kernel_<N>.cpp, one node width per translation unit.
//
// Uncounted batches of vector tests go through trace_uncounted: a batch whose
// rays mostly share a direction octant (camera rays, shadow rays towards one
// light) has each ray's box-test scalars computed while the ray before it
// walks (trace_rays_ahead) and, watertight, takes the walks specialised to
// each ray's octant (traverse_wide_octant); incoherent batches compute the
// scalars when each ray starts (their walks are long, the set-up's latency a
// small part of them, and the hand-over measured 1-3 % slower there). Counted
// batches keep the shell's loop, whose counters every structure shares.
// kScalar: `simd=0`, the same tree and walk with scalar tests.
#include <memory>
#include <span>
#include <stdexcept>

#include "accel/bvh/bvh_kernel.h"
#include "accel/bvh/bvh_outline.h"
#include "accel/bvh/bvh_wide_node.h"
#include "accel/bvh/traverse_packet.h"
#include "accel/bvh/traverse_wide.h"
#include "accel/core/batch_accelerator.h"

namespace raylab {

template <int N, bool kScalar>
class WideKernel final : public BatchAccelerator<WideKernel<N, kScalar>, BvhKernel> {
  static constexpr int W = kBvhBlockWidth;
  using Batch = BatchAccelerator<WideKernel<N, kScalar>, BvhKernel>;
  // Node widths the packet walk takes (traverse_packet.h).
  static constexpr bool kPacketWidth = (N == 8 || N == 16) && !kScalar;

 public:
  WideKernel(WideBvh<N, W> bvh, bool packets, TriangleTest tri)
      : Batch(tri), bvh_(std::move(bvh)), packets_(packets) {
    view_ = WideView<N, W>{bvh_.nodes.data(), bvh_.blocks.data(), bvh_.root_ref, wide_fma_origin_limit(bvh_.root_box)};
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
  // returns true (see the top of this file); else false.
  template <bool kAnyHit, typename Out>
  bool trace_uncounted(std::span<const Ray> rays, TraversalStats* stats, Out&& out) const {
    if constexpr (kScalar) {
      return false;
    } else {
      if (stats) return false;
      const bool coherent = batch_is_octant_coherent(rays);
      if (coherent && this->triangle_test() == TriangleTest::Watertight) {
        trace_rays_ahead(
            rays, true, [&](const Ray& r, const NodeRayScalars* a) { return traverse_wide_octant<N, W, kAnyHit>(view_, r, a); },
            out);
        return true;
      }
      dispatch_triangle_test(this->triangle_test(), [&]<TriangleTest kTest>() {
        trace_rays_ahead(
            rays, coherent,
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
  WideBvh<N, W> bvh_;
  bool packets_;
  WideView<N, W> view_;
};

template <int N>
std::unique_ptr<BvhKernel> make_wide_kernel(const WideTree& tree, const TriangleMesh& mesh, const BvhConfig& cfg,
                                            size_t& bytes) {
  const bool edges = cfg.tri == TriangleTest::MollerTrumbore;
  auto layout = make_wide_bvh<N, kBvhBlockWidth>(tree, mesh, edges);
  bytes = layout.bytes();
  if (!cfg.simd) return std::make_unique<WideKernel<N, true>>(std::move(layout), false, cfg.tri);
  return std::make_unique<WideKernel<N, false>>(std::move(layout), cfg.packet != 0, cfg.tri);
}

}  // namespace raylab
