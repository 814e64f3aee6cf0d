#include "accel/bvh/build_sweep_sah.h"

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <limits>
#include <numeric>

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

namespace raylab {

namespace {

constexpr size_t kParallelTaskSize = 4096;
constexpr size_t kParallelAxisSize = 16384;

class SweepBuilder {
 public:
  SweepBuilder(std::span<const Aabb> boxes, std::span<const Vec3f> centroids, const BuildOptions& o)
      : boxes_(boxes), centroids_(centroids), opt_(o) {
    opt_.max_leaf = std::max(1, opt_.max_leaf);
  }

  BinaryBvh run() {
    const size_t n = boxes_.size();
    if (!start_binary_bvh(out_, n)) return std::move(out_);
    area_.resize(n);
    left_.resize(n);
    temp_.resize(n);
    for (int a = 0; a < 3; ++a) {
      order_[a].resize(n);
      std::iota(order_[a].begin(), order_[a].end(), 0u);
    }
    tbb::parallel_invoke([&] { sort_axis(0); }, [&] { sort_axis(1); }, [&] { sort_axis(2); });
    Aabb bounds;
    for (const Aabb& b : boxes_) bounds.extend(b);
    build(0, 0, n, bounds, 0);
    out_.nodes.resize(next_node_.load());
    return std::move(out_);
  }

 private:
  void sort_axis(int a) {
    // Ties broken by id so the three orders are deterministic.
    tbb::parallel_sort(order_[a].begin(), order_[a].end(), [&](uint32_t x, uint32_t y) {
      const float cx = centroids_[x][a], cy = centroids_[y][a];
      return cx < cy || (cx == cy && x < y);
    });
  }

  struct AxisBest {
    float cost = std::numeric_limits<float>::infinity();
    size_t split = 0;  // number of references on the left
  };

  // Exact SAH sweep along one axis over order_[a][b, e). Axis 0 keeps its
  // right-side areas in area_[b, e) (disjoint between subtrees); the others
  // use thread-local scratch, so the three axes can sweep in parallel.
  AxisBest sweep(int a, size_t b, size_t e) {
    const uint32_t* o = order_[a].data();
    thread_local std::vector<float> local;
    float* area = area_.data() + b;
    if (a != 0) {
      local.resize(e - b);
      area = local.data();
    }
    AxisBest best;
    Aabb acc;
    for (size_t i = e - 1; i > b; --i) {
      acc.extend(boxes_[o[i]]);
      area[i - b] = acc.half_area();
    }
    Aabb left;
    for (size_t i = b + 1; i < e; ++i) {
      left.extend(boxes_[o[i - 1]]);
      const float cost = left.half_area() * static_cast<float>(i - b) + area[i - b] * static_cast<float>(e - i);
      // Equal costs (e.g. identical boxes) prefer the more balanced split.
      const auto imbalance = [&](size_t k) { return std::abs(2 * static_cast<long>(k) - static_cast<long>(e - b)); };
      if (cost < best.cost || (cost == best.cost && imbalance(i - b) < imbalance(best.split))) {
        best.cost = cost;
        best.split = i - b;
      }
    }
    return best;
  }

  void make_leaf(uint32_t node, size_t b, size_t e, const Aabb& bounds) {
    for (size_t i = b; i < e; ++i) out_.prim_ids[i] = order_[0][i];
    set_leaf(out_.nodes[node], bounds, static_cast<uint32_t>(b), static_cast<uint32_t>(e - b));
  }

  void build(uint32_t node, size_t b, size_t e, const Aabb& bounds, int depth) {
    const size_t n = e - b;
    if (n <= static_cast<size_t>(std::max(1, opt_.leaf_threshold))) return make_leaf(node, b, e, bounds);
    AxisBest best[3];
    if (n >= kParallelAxisSize) {
      tbb::parallel_invoke([&] { best[0] = sweep(0, b, e); }, [&] { best[1] = sweep(1, b, e); },
                           [&] { best[2] = sweep(2, b, e); });
    } else {
      for (int a = 0; a < 3; ++a) best[a] = sweep(a, b, e);
    }
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (best[a].cost < best[axis].cost) axis = a;
    size_t split = best[axis].split;
    const float area = bounds.half_area();
    const float split_cost =
        opt_.traversal_cost + opt_.intersection_cost * (area > 0.0f ? best[axis].cost / area : 0.0f);
    if (n <= static_cast<size_t>(opt_.max_leaf) && opt_.intersection_cost * static_cast<float>(n) <= split_cost)
      return make_leaf(node, b, e, bounds);
    if (depth >= kForceMedianDepth || split == 0) {
      // Bounded depth: object median along the widest centroid axis.
      Aabb cb;
      for (size_t i = b; i < e; ++i) cb.extend(centroids_[order_[0][i]]);
      axis = cb.largest_axis();
      split = n / 2;
    }
    const size_t mid = b + split;
    // Mark sides by id, then stable-partition the other two orders.
    for (size_t i = b; i < e; ++i) left_[order_[axis][i]] = i < mid;
    for (int a = 0; a < 3; ++a) {
      if (a == axis) continue;
      uint32_t* o = order_[a].data();
      size_t l = b, r = mid;
      for (size_t i = b; i < e; ++i) {
        const uint32_t id = o[i];
        temp_[left_[id] ? l++ : r++] = id;
      }
      std::copy(temp_.begin() + b, temp_.begin() + e, o + b);
    }
    Aabb lb, rb;
    for (size_t i = b; i < mid; ++i) lb.extend(boxes_[order_[axis][i]]);
    for (size_t i = mid; i < e; ++i) rb.extend(boxes_[order_[axis][i]]);

    const uint32_t left = next_node_.fetch_add(2);
    Bvh2Node& nd = out_.nodes[node];
    nd.set_bounds(bounds);
    nd.index = left;
    nd.count = 0;
    if (n >= kParallelTaskSize) {
      tbb::parallel_invoke([&] { build(left, b, mid, lb, depth + 1); },
                           [&] { build(left + 1, mid, e, rb, depth + 1); });
    } else {
      build(left, b, mid, lb, depth + 1);
      build(left + 1, mid, e, rb, depth + 1);
    }
  }

  std::span<const Aabb> boxes_;
  std::span<const Vec3f> centroids_;
  BuildOptions opt_;
  BinaryBvh out_;
  std::vector<uint32_t> order_[3];
  std::vector<float> area_;
  std::vector<uint8_t> left_;
  std::vector<uint32_t> temp_;
  std::atomic<uint32_t> next_node_{1};
};

}  // namespace

BinaryBvh build_sweep_sah(std::span<const Aabb> boxes, std::span<const Vec3f> centroids, const BuildOptions& options) {
  return SweepBuilder(boxes, centroids, options).run();
}

}  // namespace raylab
