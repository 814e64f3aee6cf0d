#pragma once
// The generic batch shell: the batch loops of the Accelerator interface
// around a structure's templated single-ray kernel
//   template <TriangleTest kTest, bool kAnyHit, bool kCount>
//   Hit trace(const Ray& ray, TraversalStats* stats) const;
// Dispatch is virtual per batch (and on the triangle test, once per batch);
// the loop inside calls the kernel directly. `Base` is the interface the
// shell implements: Accelerator, or a structure's own per-layout interface
// with the same two batch calls.
//
// A structure whose any-hit walk can run in either order (accel/core/
// any_hit_order.h) says so with `AnyHitOrder any_hit_order() const`, and its
// kernel takes the order per call: trace<kTest, kAnyHit, kCount>(ray, stats,
// far_first). The shell then picks the order of each occlusion batch, for
// anyhit=auto by measuring it on sample rays.
#include <atomic>
#include <concepts>

#include "accel/accelerator.h"
#include "accel/core/any_hit_order.h"
#include "accel/core/intersect_triangle.h"

namespace raylab {

template <typename S>
concept WalksAnyHitInEitherOrder = requires(const S& s) {
  { s.any_hit_order() } -> std::same_as<AnyHitOrder>;
};

template <typename Structure, typename Base = Accelerator>
class BatchAccelerator : public Base {
 protected:
  explicit BatchAccelerator(TriangleTest test) : test_(test) {}

 public:
  void intersect(std::span<const Ray> rays, std::span<Hit> hits, TraversalStats* stats) const override {
    const Structure& s = static_cast<const Structure&>(*this);
    dispatch_triangle_test(test_, [&]<TriangleTest kTest>() {
      if (stats) {
        for (size_t i = 0; i < rays.size(); ++i) hits[i] = s.template trace<kTest, false, true>(rays[i], stats);
      } else {
        for (size_t i = 0; i < rays.size(); ++i) hits[i] = s.template trace<kTest, false, false>(rays[i], nullptr);
      }
    });
  }

  void occluded(std::span<const Ray> rays, std::span<uint8_t> occ, TraversalStats* stats) const override {
    const Structure& s = static_cast<const Structure&>(*this);
    dispatch_triangle_test(test_, [&]<TriangleTest kTest>() {
      if constexpr (WalksAnyHitInEitherOrder<Structure>) {
        this->template occluded_in_order<kTest>(s, rays, occ, stats);
      } else if (stats) {
        for (size_t i = 0; i < rays.size(); ++i) occ[i] = s.template trace<kTest, true, true>(rays[i], stats).valid();
      } else {
        for (size_t i = 0; i < rays.size(); ++i) occ[i] = s.template trace<kTest, true, false>(rays[i], nullptr).valid();
      }
    });
  }

  TriangleTest triangle_test() const { return test_; }

 private:
  // Rays [begin, end) in one order.
  template <TriangleTest kTest>
  static void occluded_range(const Structure& s, std::span<const Ray> rays, std::span<uint8_t> occ, size_t begin,
                             size_t end, bool far_first, TraversalStats* stats) {
    if (stats) {
      for (size_t i = begin; i < end; ++i) occ[i] = s.template trace<kTest, true, true>(rays[i], stats, far_first).valid();
    } else {
      for (size_t i = begin; i < end; ++i)
        occ[i] = s.template trace<kTest, true, false>(rays[i], nullptr, far_first).valid();
    }
  }

  // The order the structure was made with, or for anyhit=auto the order the
  // samples favour. Every kAutoSamplePeriod-th batch (the first included),
  // kAutoSamples rays spread over it are traced both ways with their work
  // counted, and the score (half the old score plus the new cost difference
  // relative to the two costs) is updated; batches use the order it favours.
  // Sampling every batch cost 10 % on the atrium views, where back to front
  // is right: bench hands the kernel 256 rays at a time, and switching
  // between three large walk routines per batch costs more than the counted
  // work suggests. The samples' answers are kept (both orders give the same),
  // and `stats` gets all the work done: the samples' in both orders, each
  // sample counted as one ray. The shared score only steers speed: answers
  // never depend on it. Threads may race on it; each read sees some recent
  // score.
  template <TriangleTest kTest>
  void occluded_in_order(const Structure& s, std::span<const Ray> rays, std::span<uint8_t> occ,
                         TraversalStats* stats) const {
    const size_t n = rays.size();
    const AnyHitOrder order = s.any_hit_order();
    if (order != AnyHitOrder::Auto) {
      occluded_range<kTest>(s, rays, occ, 0, n, order == AnyHitOrder::Back, stats);
      return;
    }
    if (n < kAutoMinRays || auto_batches_.fetch_add(1, std::memory_order_relaxed) % kAutoSamplePeriod != 0) {
      occluded_range<kTest>(s, rays, occ, 0, n, auto_score_.load(std::memory_order_relaxed) >= 0.0f, stats);
      return;
    }
    size_t sample[kAutoSamples];
    TraversalStats work[2];  // [0] front to back, [1] back to front
    for (size_t j = 0; j < kAutoSamples; ++j) {
      sample[j] = (2 * j + 1) * n / (2 * kAutoSamples);
      const Ray& r = rays[sample[j]];
      occ[sample[j]] = s.template trace<kTest, true, true>(r, &work[0], false).valid();
      s.template trace<kTest, true, true>(r, &work[1], true);
    }
    const double front = any_hit_sample_cost(work[0]), back = any_hit_sample_cost(work[1]);
    const float diff = front + back > 0.0 ? static_cast<float>((front - back) / (front + back)) : 0.0f;
    const float score = kAutoScoreKeep * auto_score_.load(std::memory_order_relaxed) + diff;
    auto_score_.store(score, std::memory_order_relaxed);
    const bool far_first = score >= 0.0f;
    size_t begin = 0;
    for (size_t j = 0; j < kAutoSamples; ++j) {
      occluded_range<kTest>(s, rays, occ, begin, sample[j], far_first, stats);
      begin = sample[j] + 1;
    }
    occluded_range<kTest>(s, rays, occ, begin, n, far_first, stats);
    if (stats) {
      work[0].rays = kAutoSamples;
      work[1].rays = 0;
      *stats += work[0];
      *stats += work[1];
    }
  }

  mutable std::atomic<uint32_t> auto_batches_{0};
  mutable std::atomic<float> auto_score_{0.0f};
  TriangleTest test_;
};

}  // namespace raylab
