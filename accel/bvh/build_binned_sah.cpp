#include "accel/bvh/build_binned_sah.h"

#include <algorithm>
#include <atomic>
#include <numeric>

#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>
#include <tbb/blocked_range.h>

namespace raylab {

namespace {

constexpr int kMaxBins = 256;
// Beyond this depth splits fall back to the object median, so the depth (and
// the traversal stack) stays bounded even for pathological inputs.
constexpr int kForceMedianDepth = 96;
constexpr size_t kParallelTaskSize = 4096;
constexpr size_t kParallelBinSize = 65536;

struct Bin {
  Aabb box;
  uint32_t count = 0;
};

struct BinSet {
  Bin bins[3][kMaxBins];
};

class Builder {
 public:
  Builder(std::span<const Aabb> boxes, std::span<const Vec3f> centroids, const BinnedSahOptions& o)
      : boxes_(boxes), centroids_(centroids), opt_(o) {
    opt_.bins = std::clamp(opt_.bins, 2, kMaxBins);
    opt_.max_leaf = std::max(1, opt_.max_leaf);
  }

  BinaryBvh run() {
    const size_t n = boxes_.size();
    bvh_.prim_ids.resize(n);
    std::iota(bvh_.prim_ids.begin(), bvh_.prim_ids.end(), 0u);
    bvh_.nodes.resize(std::max<size_t>(1, 2 * n));
    next_node_ = 1;
    if (n == 0) {
      // Empty scene: a single empty leaf whose box no ray can hit.
      Bvh2Node& root = bvh_.nodes[0];
      root.set_bounds(Aabb::empty());
      root.index = 0;
      root.count = 0;
      bvh_.nodes.resize(1);
      return std::move(bvh_);
    }
    Aabb bounds, cbounds;
    compute_bounds(0, n, bounds, cbounds);
    build(0, 0, n, bounds, cbounds, 0);
    bvh_.nodes.resize(next_node_.load());
    return std::move(bvh_);
  }

 private:
  void compute_bounds(size_t begin, size_t end, Aabb& bounds, Aabb& cbounds) const {
    using Pair = std::pair<Aabb, Aabb>;
    auto body = [&](const tbb::blocked_range<size_t>& r, Pair acc) {
      for (size_t i = r.begin(); i < r.end(); ++i) {
        const uint32_t id = bvh_.prim_ids[i];
        acc.first.extend(boxes_[id]);
        acc.second.extend(centroids_[id]);
      }
      return acc;
    };
    Pair result;
    if (end - begin >= kParallelBinSize) {
      result = tbb::parallel_reduce(
          tbb::blocked_range<size_t>(begin, end, 8192), Pair{}, body,
          [](Pair a, const Pair& b) { return Pair{merge(a.first, b.first), merge(a.second, b.second)}; });
    } else {
      result = body(tbb::blocked_range<size_t>(begin, end), Pair{});
    }
    bounds = result.first;
    cbounds = result.second;
  }

  int bin_of(float c, float lo, float scale) const {
    const int b = static_cast<int>((c - lo) * scale);
    return std::clamp(b, 0, opt_.bins - 1);
  }

  void fill_bins(size_t begin, size_t end, const Aabb& cb, const Vec3f& scale, BinSet& out) const {
    auto body = [&](const tbb::blocked_range<size_t>& r, BinSet* acc) {
      for (size_t i = r.begin(); i < r.end(); ++i) {
        const uint32_t id = bvh_.prim_ids[i];
        for (int a = 0; a < 3; ++a) {
          if (scale[a] <= 0.0f) continue;
          Bin& bin = acc->bins[a][bin_of(centroids_[id][a], cb.lo[a], scale[a])];
          bin.box.extend(boxes_[id]);
          bin.count++;
        }
      }
    };
    if (end - begin < kParallelBinSize) {
      body(tbb::blocked_range<size_t>(begin, end), &out);
      return;
    }
    struct Reducer {
      const decltype(body)& f;
      std::unique_ptr<BinSet> set = std::make_unique<BinSet>();
      Reducer(const decltype(body)& fn) : f(fn) {}
      Reducer(Reducer& o, tbb::split) : f(o.f) {}
      void operator()(const tbb::blocked_range<size_t>& r) { f(r, set.get()); }
      void join(const Reducer& o) {
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < kMaxBins; ++b) {
            set->bins[a][b].box.extend(o.set->bins[a][b].box);
            set->bins[a][b].count += o.set->bins[a][b].count;
          }
      }
    } reducer(body);
    tbb::parallel_reduce(tbb::blocked_range<size_t>(begin, end, 16384), reducer);
    out = *reducer.set;
  }

  void make_leaf(uint32_t node, size_t begin, size_t end, const Aabb& bounds) {
    Bvh2Node& nd = bvh_.nodes[node];
    nd.set_bounds(bounds);
    nd.index = static_cast<uint32_t>(begin);
    nd.count = static_cast<uint32_t>(end - begin);
  }

  void build(uint32_t node, size_t begin, size_t end, const Aabb& bounds, const Aabb& cbounds, int depth) {
    const size_t n = end - begin;
    if (n == 1) return make_leaf(node, begin, end, bounds);

    size_t mid = begin;
    bool split_found = false;
    const Vec3f ext = cbounds.diagonal();
    const bool degenerate_centroids = ext.maxCoeff() <= 0.0f;

    if (!degenerate_centroids && depth < kForceMedianDepth) {
      Vec3f scale;
      for (int a = 0; a < 3; ++a)
        scale[a] = ext[a] > 0.0f ? static_cast<float>(opt_.bins) * (1.0f - 1e-6f) / ext[a] : 0.0f;
      auto bins = std::make_unique<BinSet>();
      fill_bins(begin, end, cbounds, scale, *bins);

      float best_cost = std::numeric_limits<float>::infinity();
      int best_axis = -1, best_split = -1;
      float right_area[kMaxBins];
      for (int a = 0; a < 3; ++a) {
        if (scale[a] <= 0.0f) continue;
        const Bin* row = bins->bins[a];
        Aabb acc;
        for (int b = opt_.bins - 1; b > 0; --b) {
          acc.extend(row[b].box);
          right_area[b] = acc.half_area();
        }
        Aabb left;
        uint32_t left_count = 0;
        for (int b = 1; b < opt_.bins; ++b) {
          left.extend(row[b - 1].box);
          left_count += row[b - 1].count;
          const uint32_t right_count = static_cast<uint32_t>(n) - left_count;
          if (left_count == 0 || right_count == 0) continue;
          const float cost = left.half_area() * left_count + right_area[b] * right_count;
          if (cost < best_cost) {
            best_cost = cost;
            best_axis = a;
            best_split = b;
          }
        }
      }
      const float parent_area = bounds.half_area();
      const float split_cost = opt_.traversal_cost +
                               opt_.intersection_cost * (parent_area > 0.0f ? best_cost / parent_area : 0.0f);
      const float leaf_cost = opt_.intersection_cost * static_cast<float>(n);
      if (n <= static_cast<size_t>(opt_.max_leaf) && (best_axis < 0 || leaf_cost <= split_cost))
        return make_leaf(node, begin, end, bounds);
      if (best_axis >= 0) {
        const float lo = cbounds.lo[best_axis], sc = scale[best_axis];
        auto* first = bvh_.prim_ids.data() + begin;
        auto* last = bvh_.prim_ids.data() + end;
        auto* pivot = std::partition(first, last, [&](uint32_t id) {
          return bin_of(centroids_[id][best_axis], lo, sc) < best_split;
        });
        mid = begin + static_cast<size_t>(pivot - first);
        split_found = mid > begin && mid < end;
      }
    } else if (n <= static_cast<size_t>(opt_.max_leaf)) {
      return make_leaf(node, begin, end, bounds);
    }

    if (!split_found) {
      // Identical centroids (or forced): split the range in the middle by
      // the largest axis so leaves stay small and the depth logarithmic.
      mid = begin + n / 2;
      const int axis = cbounds.largest_axis();
      auto* first = bvh_.prim_ids.data() + begin;
      std::nth_element(first, first + n / 2, bvh_.prim_ids.data() + end,
                       [&](uint32_t x, uint32_t y) { return centroids_[x][axis] < centroids_[y][axis]; });
    }

    const uint32_t left = next_node_.fetch_add(2);
    Bvh2Node& nd = bvh_.nodes[node];
    nd.set_bounds(bounds);
    nd.index = left;
    nd.count = 0;

    Aabb lb, lcb, rb, rcb;
    compute_bounds(begin, mid, lb, lcb);
    compute_bounds(mid, end, rb, rcb);
    if (n >= kParallelTaskSize) {
      tbb::parallel_invoke([&] { build(left, begin, mid, lb, lcb, depth + 1); },
                           [&] { build(left + 1, mid, end, rb, rcb, depth + 1); });
    } else {
      build(left, begin, mid, lb, lcb, depth + 1);
      build(left + 1, mid, end, rb, rcb, depth + 1);
    }
  }

  std::span<const Aabb> boxes_;
  std::span<const Vec3f> centroids_;
  BinnedSahOptions opt_;
  BinaryBvh bvh_;
  std::atomic<uint32_t> next_node_{1};
};

}  // namespace

BinaryBvh build_binned_sah(std::span<const Aabb> boxes, std::span<const Vec3f> centroids,
                           const BinnedSahOptions& options) {
  return Builder(boxes, centroids, options).run();
}

TreeShape measure_tree(std::span<const Bvh2Node> nodes) {
  TreeShape s;
  if (nodes.empty()) return s;
  const double root_area = nodes[0].bounds().half_area();
  struct Item {
    uint32_t node;
    int depth;
  };
  std::vector<Item> stack{{0, 0}};
  double depth_sum = 0.0, cost = 0.0;
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    const Bvh2Node& n = nodes[it.node];
    s.nodes++;
    s.max_depth = std::max(s.max_depth, it.depth);
    const double area = n.bounds().half_area();
    if (n.is_leaf() || n.index == 0) {
      s.leaves++;
      depth_sum += it.depth;
      cost += kSahIntersectionCost * area * n.count;
    } else {
      cost += kSahTraversalCost * area;
      stack.push_back({n.index, it.depth + 1});
      stack.push_back({n.index + 1, it.depth + 1});
    }
  }
  s.avg_leaf_depth = s.leaves ? depth_sum / static_cast<double>(s.leaves) : 0.0;
  s.sah_cost = root_area > 0.0 ? cost / root_area : 0.0;
  return s;
}

}  // namespace raylab
