#include "accel/bvh/build_binned_sah.h"

#include <immintrin.h>

#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <limits>
#include <memory>
#include <stdexcept>

#include <tbb/blocked_range.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>
#include <tbb/task_arena.h>

#include "accel/core/huge_page_allocator.h"
#include "accel/bvh/sah_binning.h"
#include "accel/bvh/small_sweep.h"

namespace raylab {

namespace {

using sah::BinSet;
using sah::Binning;
using sah::Split;
using sah::bin_refs;
using sah::find_binned_split;

constexpr size_t kParallelTaskSize = 4096;     // subtrees at least this large become tasks
constexpr size_t kParallelPartitionSize = 32768;
// Nodes with at most this many references evaluate every object split exactly
// (sorted centroids) instead of binning: cheaper for small nodes, and exact.
constexpr size_t kSmallSweep = sah::kSmallSweepMax;
// Bins used for small ranges (measured: same SAH cost, ~10% less build time).
int bins_for(size_t n, int bins) { return std::min(bins, n < 128 ? 8 : n < 1024 ? 16 : bins); }

class BinnedBuilder {
 public:
  BinnedBuilder(std::vector<BuildRef>&& refs, const BuildOptions& o) : refs_(std::move(refs)), opt_(o) {
    opt_.bins = std::clamp(opt_.bins, 2, sah::kMaxBins);
    opt_.max_leaf = std::max(1, opt_.max_leaf);
  }

  BinaryBvh run() {
    const size_t n = refs_.size();
    if (n == 0) {
      start_binary_bvh(out_, n);
      return std::move(out_);
    }
    // Room for the worst case (2n - 1 nodes), not written (BinaryBvh::nodes
    // does not zero): only the pages of the nodes used are ever touched, and
    // the array is shrunk to them, with no second copy.
    out_.nodes.resize(2 * n);
    nodes_ = out_.nodes.data();
    out_.prim_ids.resize(n);
    if (n >= kParallelPartitionSize) scratch_ = HugePageBuffer<BuildRef>(n);
    serial_ = tbb::this_task_arena::max_concurrency() == 1 ||
              tbb::global_control::active_value(tbb::global_control::max_allowed_parallelism) == 1;
    Box4 bounds, cbounds;
    compute_bounds(refs_.data(), 0, n, bounds, cbounds);
    root_half_area_ = bounds.half_area();
    build(0, 0, n, bounds, cbounds, opt_.start_depth, refs_.data(), scratch_.data());
    out_.nodes.resize(next_node_.load());
    if (!serial_ && n >= kParallelTaskSize) renumber();
    return std::move(out_);
  }

 private:
  static void compute_bounds(const BuildRef* refs, size_t b, size_t e, Box4& bounds, Box4& cbounds) {
    using Pair = std::pair<Box4, Box4>;
    auto body = [&](const tbb::blocked_range<size_t>& r, Pair acc) {
      for (size_t i = r.begin(); i < r.end(); ++i) {
        acc.first.extend(refs[i].box);
        acc.second.extend(refs[i].centroid());
      }
      return acc;
    };
    Pair res = (e - b >= sah::kParallelBinSize)
                   ? tbb::parallel_reduce(tbb::blocked_range<size_t>(b, e, 8192), Pair{}, body,
                                          [](Pair x, const Pair& y) {
                                            return Pair{merge(x.first, y.first), merge(x.second, y.second)};
                                          })
                   : body(tbb::blocked_range<size_t>(b, e), Pair{});
    bounds = res.first;
    cbounds = res.second;
  }

  // In-place partition of refs[b, e) by the split; accumulates the sides'
  // centroid bounds. Returns the first index of the right side.
  size_t partition_inplace(BuildRef* refs, size_t b, size_t e, const Binning& bn, const Split& s, Box4& lc,
                           Box4& rc) const {
    size_t i = b, j = e;
    while (true) {
      while (i < j && bn.left_of(refs[i], s.axis, s.pos)) lc.extend(refs[i++].centroid());
      while (i < j && !bn.left_of(refs[j - 1], s.axis, s.pos)) rc.extend(refs[--j].centroid());
      if (i >= j) return i;
      std::swap(refs[i], refs[j - 1]);
    }
  }

  // Subtree tasks take their node numbers in the order they happen to run:
  // the nodes renumbered in the order of the serial build (a node's two
  // children take the next two numbers when it is reached, its left subtree
  // is numbered before its right one), so that the tree, and everything
  // derived from its numbering (the reinsertion's ties, the layouts), is the
  // same for every thread count and every run.
  void renumber() {
    const size_t m = out_.nodes.size();
    UninitHugePageVector<Bvh2Node> canon;
    canon.resize(m);
    canon[0] = out_.nodes[0];
    std::vector<std::pair<uint32_t, uint32_t>> stack{{0u, 0u}};  // (old number, new number)
    uint32_t next = 1;
    while (!stack.empty()) {
      const auto [from, to] = stack.back();
      stack.pop_back();
      const Bvh2Node& node = out_.nodes[from];
      if (node.count != 0) continue;
      const uint32_t left = next;
      next += 2;
      canon[to].index = left;
      canon[left] = out_.nodes[node.index];
      canon[left + 1] = out_.nodes[node.index + 1];
      stack.emplace_back(node.index + 1, left + 1);
      stack.emplace_back(node.index, left);
    }
    if (next != m) throw std::logic_error("bvh: binned build left unreachable nodes");
    out_.nodes.swap(canon);
  }

  // Copies src[cb, ce) into dst in order, the references left of the split
  // from l on and the others from r on, growing the sides' centroid bounds;
  // returns where the left run ends. The right run never passes e (its start
  // comes from counts; a disagreement with them throws rather than writes
  // out of range).
  static size_t scatter(const BuildRef* src, BuildRef* dst, size_t cb, size_t ce, size_t l, size_t r, size_t e,
                        const Binning& bn, const Split& s, Box4& lc, Box4& rc) {
    for (size_t i = cb; i < ce; ++i) {
      if (bn.left_of(src[i], s.axis, s.pos)) {
        lc.extend(src[i].centroid());
        dst[l++] = src[i];
      } else {
        if (r == e) throw std::logic_error("bvh: binned partition disagrees with the bins");
        rc.extend(src[i].centroid());
        dst[r++] = src[i];
      }
    }
    return l;
  }

  // Parallel stable partition of src[b, e) into dst[b, e): each chunk's left
  // references counted, then every chunk scattered to its offsets. With one
  // thread the same order in one pass: the split's left count (exact, as
  // left_of matches the bins) places the right side without a counting pass.
  size_t partition_parallel(const BuildRef* src, BuildRef* dst, size_t b, size_t e, const Binning& bn,
                            const Split& s, Box4& lc, Box4& rc) const {
    const size_t n = e - b;
    if (serial_) {
      const size_t mid = b + s.left_count;
      if (scatter(src, dst, b, e, b, mid, e, bn, s, lc, rc) != mid)
        throw std::logic_error("bvh: binned partition disagrees with the bins");
      return mid;
    }
    const size_t chunks = std::min<size_t>(256, (n + 8191) / 8192);
    const size_t chunk = (n + chunks - 1) / chunks;
    std::vector<size_t> left(chunks), loff(chunks), roff(chunks);
    std::vector<Box4> lcs(chunks), rcs(chunks);
    tbb::parallel_for(size_t{0}, chunks, [&](size_t c) {
      const size_t cb = b + c * chunk, ce = std::min(e, cb + chunk);
      size_t cnt = 0;
      for (size_t i = cb; i < ce; ++i) cnt += bn.left_of(src[i], s.axis, s.pos);
      left[c] = cnt;
    });
    size_t total_left = 0;
    for (size_t c = 0; c < chunks; ++c) {
      loff[c] = total_left;
      total_left += left[c];
    }
    size_t rsum = 0;
    for (size_t c = 0; c < chunks; ++c) {
      const size_t cb = b + c * chunk, ce = std::min(e, cb + chunk);
      roff[c] = total_left + rsum;
      rsum += (ce > cb ? ce - cb : 0) - left[c];
    }
    tbb::parallel_for(size_t{0}, chunks, [&](size_t c) {
      const size_t cb = b + c * chunk, ce = std::min(e, cb + chunk);
      scatter(src, dst, cb, ce, b + loff[c], b + roff[c], e, bn, s, lcs[c], rcs[c]);
    });
    for (size_t c = 0; c < chunks; ++c) {
      lc.extend(lcs[c]);
      rc.extend(rcs[c]);
    }
    return b + total_left;
  }

  // Exact SAH over the n-1 object splits of each axis for small nodes
  // (small_sweep.h); reorders refs[b, e) along the best axis and returns the split.
  Split small_sweep(BuildRef* refs, size_t b, size_t e, size_t& mid, Box4& lcb, Box4& rcb) const {
    const int n = static_cast<int>(e - b);
    uint8_t order[3][sah::kSmallSweepMax];
    const sah::SmallSplit choice = sah::choose_small_split(refs + b, n, order);
    Split best;
    best.axis = choice.axis;
    best.pos = choice.pos;
    best.cost = choice.cost;
    BuildRef tmp[kSmallSweep];
    for (int i = 0; i < n; ++i) tmp[i] = refs[b + i];
    const uint8_t* o = order[best.axis];
    best.left = Box4();
    best.right = Box4();
    for (int i = 0; i < n; ++i) {
      refs[b + i] = tmp[o[i]];
      if (i < best.pos) {
        lcb.extend(refs[b + i].centroid());
        best.left.extend(refs[b + i].box);
      } else {
        rcb.extend(refs[b + i].centroid());
        best.right.extend(refs[b + i].box);
      }
    }
    best.left_count = static_cast<uint32_t>(best.pos);
    mid = b + static_cast<size_t>(best.pos);
    return best;
  }

  // The node's large references (BuildOptions::big_node, big_root) moved to
  // the front of refs[b, e) as the left child, the rest as the right one.
  // Returns false (refs perhaps reordered, nothing else changed) when there
  // are none or more than a quarter of the node's references.
  // Nothing moves where no reference is large, which the node's box tells
  // without a pass over them (lane 3: the largest reference half area).
  bool split_off_large(BuildRef* refs, size_t b, size_t e, const Box4& bounds, size_t& mid, Box4& lb, Box4& lcb,
                       Box4& rb, Box4& rcb) {
    constexpr float kInf = std::numeric_limits<float>::infinity();
    const float limit = std::min(opt_.big_node > 0.0f ? opt_.big_node * bounds.half_area() : kInf,
                                 opt_.big_root > 0.0f ? opt_.big_root * root_half_area_ : kInf);
    if (!(bounds.max_ref_half_area() > limit)) return false;
    BuildRef* first_small =
        std::partition(refs + b, refs + e, [limit](const BuildRef& r) { return r.box.half_area() > limit; });
    const size_t large = static_cast<size_t>(first_small - (refs + b));
    if (large == 0 || large > (e - b) / 4) return false;
    big_splits_.fetch_add(1, std::memory_order_relaxed);
    mid = b + large;
    compute_bounds(refs, b, mid, lb, lcb);
    compute_bounds(refs, mid, e, rb, rcb);
    return true;
  }

  void make_leaf(uint32_t node, const BuildRef* refs, size_t b, size_t e, const Box4& bounds) {
    for (size_t i = b; i < e; ++i) out_.prim_ids[i] = refs[i].prim();
    set_leaf(nodes_[node], bounds.aabb(), static_cast<uint32_t>(b), static_cast<uint32_t>(e - b));
  }

  void build(uint32_t node, size_t b, size_t e, const Box4& bounds, const Box4& cbounds, int depth, BuildRef* cur,
             BuildRef* other) {
    const size_t n = e - b;
    if (n <= static_cast<size_t>(std::max(1, opt_.leaf_threshold))) return make_leaf(node, cur, b, e, bounds);

    alignas(16) float cext[4];
    _mm_store_ps(cext, _mm_sub_ps(cbounds.hi, cbounds.lo));
    const bool flat = !(cext[0] > 0.0f || cext[1] > 0.0f || cext[2] > 0.0f);

    size_t mid = b;
    Box4 lb, rb, lcb, rcb;
    BuildRef* child_buf = cur;
    BuildRef* child_other = other;
    bool done = false;
    if ((opt_.big_node > 0.0f || opt_.big_root > 0.0f) && n >= opt_.big_min && depth < kForceMedianDepth)
      done = split_off_large(cur, b, e, bounds, mid, lb, lcb, rb, rcb);
    if (done) {
      // the large references on the left, the rest on the right
    } else if (n <= kSmallSweep && depth < kForceMedianDepth) {
      const Split s = small_sweep(cur, b, e, mid, lcb, rcb);
      const float area = bounds.half_area();
      const float split_cost = opt_.traversal_cost + opt_.intersection_cost * (area > 0.0f ? s.cost / area : 0.0f);
      if (n <= static_cast<size_t>(opt_.max_leaf) && opt_.intersection_cost * static_cast<float>(n) <= split_cost)
        return make_leaf(node, cur, b, e, bounds);
      lb = s.left;
      rb = s.right;
      done = true;
    } else if (!flat && depth < kForceMedianDepth) {
      // Fewer bins for small ranges: with few references most of 32 bins are
      // empty, and sweeping them costs more than binning.
      const int nb = bins_for(n, opt_.bins);
      const Binning bn(cbounds, nb);
      // One bin set per thread, reused, for the nodes binned serially:
      // nothing between their binning and their split search can run another
      // node's build on this thread. A node binned in parallel waits inside
      // TBB, where this thread may run another subtree's build: it gets a
      // bin set of its own (there are few such nodes).
      thread_local std::unique_ptr<BinSet> node_bins;
      std::unique_ptr<BinSet> own_bins;
      BinSet* bins = nullptr;
      if (n >= sah::kParallelBinSize) {
        own_bins.reset(new BinSet);
        bins = own_bins.get();
      } else {
        if (!node_bins) node_bins.reset(new BinSet);
        bins = node_bins.get();
      }
      bin_refs(cur, b, e, bn, nb, *bins);
      const Split s = find_binned_split(*bins, bn, nb);
      const float area = bounds.half_area();
      const float split_cost =
          opt_.traversal_cost + opt_.intersection_cost * (area > 0.0f ? s.cost / area : 0.0f);
      const float leaf_cost = opt_.intersection_cost * static_cast<float>(n);
      if (n <= static_cast<size_t>(opt_.max_leaf) && (s.axis < 0 || leaf_cost <= split_cost))
        return make_leaf(node, cur, b, e, bounds);
      if (s.axis >= 0) {
        if (n >= kParallelPartitionSize) {
          mid = partition_parallel(cur, other, b, e, bn, s, lcb, rcb);
          std::swap(child_buf, child_other);
        } else {
          mid = partition_inplace(cur, b, e, bn, s, lcb, rcb);
        }
        lb = s.left;
        rb = s.right;
        done = mid > b && mid < e;
      }
    } else if (n <= static_cast<size_t>(opt_.max_leaf)) {
      return make_leaf(node, cur, b, e, bounds);
    }
    if (!done) {
      // Identical centroids (or too deep): split the range at the object
      // median of the widest axis so leaves stay small and depth logarithmic.
      mid = b + n / 2;
      int axis = 0;
      if (cext[1] > cext[axis]) axis = 1;
      if (cext[2] > cext[axis]) axis = 2;
      BuildRef* data = child_buf;  // where the references are now
      std::nth_element(data + b, data + mid, data + e, [axis](const BuildRef& x, const BuildRef& y) {
        alignas(16) float cx[4], cy[4];
        _mm_store_ps(cx, x.centroid());
        _mm_store_ps(cy, y.centroid());
        return cx[axis] < cy[axis];
      });
      compute_bounds(data, b, mid, lb, lcb);
      compute_bounds(data, mid, e, rb, rcb);
    }

    const uint32_t left = next_node_.fetch_add(2);
    Bvh2Node& nd = nodes_[node];
    nd.set_bounds(bounds.aabb());
    nd.index = left;
    nd.count = 0;
    if (n >= kParallelTaskSize && !serial_) {
      tbb::parallel_invoke([&] { build(left, b, mid, lb, lcb, depth + 1, child_buf, child_other); },
                           [&] { build(left + 1, mid, e, rb, rcb, depth + 1, child_buf, child_other); });
    } else {
      build(left, b, mid, lb, lcb, depth + 1, child_buf, child_other);
      build(left + 1, mid, e, rb, rcb, depth + 1, child_buf, child_other);
    }
  }

  std::vector<BuildRef> refs_;
  // The parallel partition's target (ranges of kParallelPartitionSize
  // references or more), uninitialised: every element is written before it is read.
  HugePageBuffer<BuildRef> scratch_;
  Bvh2Node* nodes_ = nullptr;  // out_.nodes.data()
  float root_half_area_ = 0.0f;
  // One thread: the subtrees built in turn (left first), the nodes numbered
  // as they are reached, and the large nodes partitioned in one pass.
  bool serial_ = false;
  BuildOptions opt_;
  BinaryBvh out_;
  std::atomic<uint32_t> next_node_{1};
  std::atomic<size_t> big_splits_{0};

 public:
  size_t big_splits() const { return big_splits_.load(); }
};

}  // namespace

BinaryBvh build_binned_sah(std::vector<BuildRef> refs, const BuildOptions& options, BinnedBuildStats* stats) {
  BinnedBuilder builder(std::move(refs), options);
  BinaryBvh tree = builder.run();
  if (stats) stats->big_splits = builder.big_splits();
  return tree;
}

BinaryBvh build_binned_sah(std::span<const Aabb> boxes, std::span<const Vec3f> centroids,
                           const BuildOptions& options, BinnedBuildStats* stats) {
  return build_binned_sah(make_build_refs(boxes, centroids), options, stats);
}

}  // namespace raylab
