#include "accel/bvh/build_lbvh.h"

#include <algorithm>
#include <atomic>
#include <bit>
#include <memory>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

namespace raylab {

uint64_t morton_spread21(uint32_t v) {
  uint64_t x = v & 0x1FFFFFu;
  x = (x | x << 32) & 0x1F00000000FFFFull;
  x = (x | x << 16) & 0x1F0000FF0000FFull;
  x = (x | x << 8) & 0x100F00F00F00F00Full;
  x = (x | x << 4) & 0x10C30C30C30C30C3ull;
  x = (x | x << 2) & 0x1249249249249249ull;
  return x;
}

namespace {

struct Keyed {
  uint64_t code;
  uint32_t id;
  bool operator<(const Keyed& o) const { return code < o.code || (code == o.code && id < o.id); }
};

constexpr uint32_t kLeafFlag = 0x80000000u;

class Lbvh {
 public:
  Lbvh(std::span<const Aabb> boxes, std::span<const Vec3f> centroids) : boxes_(boxes), centroids_(centroids) {}

  BinaryBvh run() {
    const size_t n = boxes_.size();
    BinaryBvh out;
    if (n <= 1) {
      out.nodes.resize(1);
      set_leaf(out.nodes[0], n ? boxes_[0] : Aabb::empty(), 0, static_cast<uint32_t>(n));
      out.prim_ids.assign(n, 0u);
      return out;
    }
    n_ = n;
    sort_codes();
    left_.resize(n - 1);
    right_.resize(n - 1);
    parent_.resize(2 * n - 1);  // internal i at i, leaf j at n - 1 + j
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n - 1, 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i) make_internal(static_cast<int64_t>(i));
    });
    fit_boxes();
    // Depth-first conversion into the canonical layout.
    out.nodes.resize(2 * n - 1);
    out.prim_ids.resize(n);
    uint32_t next_node = 1, next_prim = 0;
    std::vector<std::pair<uint32_t, uint32_t>> stack{{0u, 0u}};  // (karras node, out node)
    while (!stack.empty()) {
      const auto [k, o] = stack.back();
      stack.pop_back();
      Bvh2Node& dst = out.nodes[o];
      if (k & kLeafFlag) {
        const uint32_t j = k & ~kLeafFlag;
        out.prim_ids[next_prim] = keys_[j].id;
        set_leaf(dst, boxes_[keys_[j].id], next_prim++, 1);
        continue;
      }
      dst.set_bounds(box_[k].aabb());
      dst.index = next_node;
      dst.count = 0;
      stack.push_back({right_[k], next_node + 1});
      stack.push_back({left_[k], next_node});
      next_node += 2;
    }
    return out;
  }

 private:
  void sort_codes() {
    const Aabb cb = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, n_, 8192), Aabb(),
        [&](const tbb::blocked_range<size_t>& r, Aabb acc) {
          for (size_t i = r.begin(); i < r.end(); ++i) acc.extend(centroids_[i]);
          return acc;
        },
        [](const Aabb& a, const Aabb& b) { return merge(a, b); });
    // In double: centroids spread over more than FLT_MAX (a scene reaching both ends of float)
    // have an infinite float extent, and (c - lo) * (k / inf) would be inf * 0 = NaN, whose
    // conversion to an integer is undefined (UBSan's float-cast-overflow found it).
    double lo[3], scale[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = cb.lo[a];
      const double ext = double(cb.hi[a]) - lo[a];
      scale[a] = ext > 0.0 ? 2097151.0 / ext : 0.0;
    }
    keys_.resize(n_);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n_, 8192), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t i = r.begin(); i < r.end(); ++i) {
        uint64_t code = 0;
        for (int a = 0; a < 3; ++a) {
          const double x = (double(centroids_[i][a]) - lo[a]) * scale[a];
          const double q = x > 0.0 ? std::min(x, 2097151.0) : 0.0;  // NaN (an infinite centroid) -> 0
          code |= morton_spread21(static_cast<uint32_t>(q)) << (2 - a);
        }
        keys_[i] = Keyed{code, static_cast<uint32_t>(i)};
      }
    });
    tbb::parallel_sort(keys_.begin(), keys_.end());
  }

  // Length of the common prefix of keys i and j (-1 outside the range);
  // equal codes fall back to the indices' common prefix.
  int delta(int64_t i, int64_t j) const {
    if (j < 0 || j >= static_cast<int64_t>(n_)) return -1;
    const uint64_t a = keys_[i].code, b = keys_[j].code;
    if (a == b) return 64 + std::countl_zero(static_cast<uint64_t>(i ^ j));
    return std::countl_zero(a ^ b);
  }

  void make_internal(int64_t i) {
    const int d = delta(i, i + 1) - delta(i, i - 1) >= 0 ? 1 : -1;
    const int dmin = delta(i, i - d);
    int64_t lmax = 2;
    while (delta(i, i + lmax * d) > dmin) lmax *= 2;
    int64_t l = 0;
    for (int64_t t = lmax / 2; t >= 1; t /= 2)
      if (delta(i, i + (l + t) * d) > dmin) l += t;
    const int64_t j = i + l * d;
    const int dnode = delta(i, j);
    int64_t s = 0, t = l;
    do {
      t = (t + 1) >> 1;
      if (delta(i, i + (s + t) * d) > dnode) s += t;
    } while (t > 1);
    const int64_t gamma = i + s * d + std::min(d, 0);
    const uint32_t lc = std::min(i, j) == gamma ? kLeafFlag | static_cast<uint32_t>(gamma) : static_cast<uint32_t>(gamma);
    const uint32_t rc =
        std::max(i, j) == gamma + 1 ? kLeafFlag | static_cast<uint32_t>(gamma + 1) : static_cast<uint32_t>(gamma + 1);
    left_[i] = lc;
    right_[i] = rc;
    parent_[slot(lc)] = static_cast<uint32_t>(i);
    parent_[slot(rc)] = static_cast<uint32_t>(i);
  }

  size_t slot(uint32_t ref) const { return (ref & kLeafFlag) ? n_ - 1 + (ref & ~kLeafFlag) : ref; }

  Box4 box_of(uint32_t ref) const {
    return (ref & kLeafFlag) ? Box4::from(boxes_[keys_[ref & ~kLeafFlag].id]) : box_[ref];
  }

  // Bottom-up: the second child to arrive at a node computes its box.
  void fit_boxes() {
    box_.reset(new Box4[n_ - 1]);
    std::unique_ptr<std::atomic<uint32_t>[]> arrived(new std::atomic<uint32_t>[n_ - 1]);
    for (size_t i = 0; i + 1 < n_; ++i) arrived[i].store(0, std::memory_order_relaxed);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n_, 4096), [&](const tbb::blocked_range<size_t>& r) {
      for (size_t j = r.begin(); j < r.end(); ++j) {
        uint32_t node = parent_[n_ - 1 + j];
        while (true) {
          if (arrived[node].fetch_add(1, std::memory_order_acq_rel) == 0) break;
          box_[node] = merge(box_of(left_[node]), box_of(right_[node]));
          if (node == 0) break;
          node = parent_[node];
        }
      }
    });
  }

  std::span<const Aabb> boxes_;
  std::span<const Vec3f> centroids_;
  size_t n_ = 0;
  std::vector<Keyed> keys_;
  std::vector<uint32_t> left_, right_, parent_;
  std::unique_ptr<Box4[]> box_;
};

}  // namespace

BinaryBvh build_lbvh(std::span<const Aabb> boxes, std::span<const Vec3f> centroids) {
  return Lbvh(boxes, centroids).run();
}

}  // namespace raylab
