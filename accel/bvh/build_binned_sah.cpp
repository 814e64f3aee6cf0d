#include "accel/bvh/build_binned_sah.h"

#include <emmintrin.h>
#if defined(__SSE4_1__)
#include <smmintrin.h>
#endif

#include <algorithm>
#include <atomic>
#include <limits>
#include <memory>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

namespace raylab {

namespace {

constexpr int kMaxBins = 256;
constexpr size_t kParallelTaskSize = 4096;     // subtrees at least this large become tasks
constexpr size_t kParallelBinSize = 32768;     // ranges at least this large bin in parallel
constexpr size_t kParallelPartitionSize = 32768;

struct BinSet {
  Box4 box[3][kMaxBins];
  uint32_t count[3][kMaxBins];

  explicit BinSet(int bins) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < bins; ++b) {
        box[a][b] = Box4();
        count[a][b] = 0;
      }
  }
  void merge_from(const BinSet& o, int bins) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < bins; ++b) {
        box[a][b].extend(o.box[a][b]);
        count[a][b] += o.count[a][b];
      }
  }
};

// Maps centroids to bins: bin = trunc((c - lo) * scale), clamped. Axes with
// flat centroid bounds get scale 0 (everything in bin 0) and are skipped.
struct Binning {
  __m128 lo;
  __m128 scale;
  alignas(16) float scale_s[4];
  __m128i max_bin;

  Binning(const Box4& cbounds, int bins) {
    lo = cbounds.lo;
    alignas(16) float ext[4];
    _mm_store_ps(ext, _mm_sub_ps(cbounds.hi, cbounds.lo));
    for (int a = 0; a < 3; ++a)
      scale_s[a] = ext[a] > 0.0f ? static_cast<float>(bins) * (1.0f - 1e-6f) / ext[a] : 0.0f;
    scale_s[3] = 0.0f;
    scale = _mm_load_ps(scale_s);
    max_bin = _mm_set1_epi32(bins - 1);
  }

  __m128i bins_of(const BuildRef& r) const {
    const __m128i i = _mm_cvttps_epi32(_mm_mul_ps(_mm_sub_ps(r.centroid(), lo), scale));
#if defined(__SSE4_1__)
    return _mm_max_epi32(_mm_min_epi32(i, max_bin), _mm_setzero_si128());
#else
    const __m128i over = _mm_cmpgt_epi32(i, max_bin);
    const __m128i clipped = _mm_or_si128(_mm_and_si128(over, max_bin), _mm_andnot_si128(over, i));
    return _mm_andnot_si128(_mm_cmplt_epi32(clipped, _mm_setzero_si128()), clipped);
#endif
  }
  int bin_of(const BuildRef& r, int axis) const {
    alignas(16) int32_t v[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(v), bins_of(r));
    return v[axis];
  }
};

struct Split {
  int axis = -1;
  int pos = 0;  // references in bins < pos go left
  float cost = std::numeric_limits<float>::infinity();  // lA*lN + rA*rN
  Box4 left, right;
  uint32_t left_count = 0;
};

class BinnedBuilder {
 public:
  BinnedBuilder(std::vector<BuildRef>&& refs, const BuildOptions& o) : refs_(std::move(refs)), opt_(o) {
    opt_.bins = std::clamp(opt_.bins, 2, kMaxBins);
    opt_.max_leaf = std::max(1, opt_.max_leaf);
  }

  BinaryBvh run() {
    const size_t n = refs_.size();
    out_.prim_ids.resize(n);
    if (n == 0) {
      out_.nodes.resize(1);
      set_leaf(out_.nodes[0], Aabb::empty(), 0, 0);
      return std::move(out_);
    }
    out_.nodes.resize(2 * n);
    scratch_.resize(n);
    Box4 bounds, cbounds;
    compute_bounds(refs_.data(), 0, n, bounds, cbounds);
    build(0, 0, n, bounds, cbounds, 0, refs_.data(), scratch_.data());
    out_.nodes.resize(next_node_.load());
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
    Pair res = (e - b >= kParallelBinSize)
                   ? tbb::parallel_reduce(tbb::blocked_range<size_t>(b, e, 8192), Pair{}, body,
                                          [](Pair x, const Pair& y) {
                                            return Pair{merge(x.first, y.first), merge(x.second, y.second)};
                                          })
                   : body(tbb::blocked_range<size_t>(b, e), Pair{});
    bounds = res.first;
    cbounds = res.second;
  }

  void bin_range(const BuildRef* refs, size_t b, size_t e, const Binning& bn, BinSet& bins) const {
    for (size_t i = b; i < e; ++i) {
      const BuildRef& r = refs[i];
      alignas(16) int32_t idx[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(idx), bn.bins_of(r));
      for (int a = 0; a < 3; ++a) {
        bins.box[a][idx[a]].extend(r.box);
        bins.count[a][idx[a]]++;
      }
    }
  }

  std::unique_ptr<BinSet> bin(const BuildRef* refs, size_t b, size_t e, const Binning& bn) const {
    const int nb = opt_.bins;
    if (e - b < kParallelBinSize) {
      auto bins = std::make_unique<BinSet>(nb);
      bin_range(refs, b, e, bn, *bins);
      return bins;
    }
    struct Reducer {
      const BinnedBuilder* self;
      const BuildRef* refs;
      const Binning* bn;
      std::unique_ptr<BinSet> bins;
      Reducer(const BinnedBuilder* s, const BuildRef* r, const Binning* b)
          : self(s), refs(r), bn(b), bins(std::make_unique<BinSet>(s->opt_.bins)) {}
      Reducer(Reducer& o, tbb::split) : Reducer(o.self, o.refs, o.bn) {}
      void operator()(const tbb::blocked_range<size_t>& r) { self->bin_range(refs, r.begin(), r.end(), *bn, *bins); }
      void join(const Reducer& o) { bins->merge_from(*o.bins, self->opt_.bins); }
    } red(this, refs, &bn);
    tbb::parallel_reduce(tbb::blocked_range<size_t>(b, e, 16384), red);
    return std::move(red.bins);
  }

  Split find_split(const BinSet& bins, const Binning& bn, uint32_t n) const {
    const int nb = opt_.bins;
    Split best;
    float right_area[kMaxBins];
    uint32_t right_count[kMaxBins];
    Box4 right_box[kMaxBins];
    for (int a = 0; a < 3; ++a) {
      if (bn.scale_s[a] <= 0.0f) continue;
      Box4 acc;
      uint32_t cnt = 0;
      for (int b = nb - 1; b > 0; --b) {
        acc.extend(bins.box[a][b]);
        cnt += bins.count[a][b];
        right_box[b] = acc;
        right_area[b] = acc.half_area();
        right_count[b] = cnt;
      }
      Box4 left;
      uint32_t lc = 0;
      for (int b = 1; b < nb; ++b) {
        left.extend(bins.box[a][b - 1]);
        lc += bins.count[a][b - 1];
        if (lc == 0 || right_count[b] == 0) continue;
        const float cost = left.half_area() * static_cast<float>(lc) + right_area[b] * static_cast<float>(right_count[b]);
        if (cost < best.cost) {
          best.cost = cost;
          best.axis = a;
          best.pos = b;
          best.left = left;
          best.right = right_box[b];
          best.left_count = lc;
        }
      }
    }
    (void)n;
    return best;
  }

  // In-place partition of refs[b, e) by the split; accumulates the sides'
  // centroid bounds. Returns the first index of the right side.
  size_t partition_inplace(BuildRef* refs, size_t b, size_t e, const Binning& bn, const Split& s, Box4& lc,
                           Box4& rc) const {
    size_t i = b, j = e;
    while (true) {
      while (i < j && bn.bin_of(refs[i], s.axis) < s.pos) lc.extend(refs[i++].centroid());
      while (i < j && bn.bin_of(refs[j - 1], s.axis) >= s.pos) rc.extend(refs[--j].centroid());
      if (i >= j) return i;
      std::swap(refs[i], refs[j - 1]);
    }
  }

  // Parallel stable partition of src[b, e) into dst[b, e).
  size_t partition_parallel(const BuildRef* src, BuildRef* dst, size_t b, size_t e, const Binning& bn,
                            const Split& s, Box4& lc, Box4& rc) const {
    const size_t n = e - b;
    const size_t chunks = std::min<size_t>(256, (n + 8191) / 8192);
    const size_t chunk = (n + chunks - 1) / chunks;
    std::vector<size_t> left(chunks), loff(chunks), roff(chunks);
    std::vector<Box4> lcs(chunks), rcs(chunks);
    tbb::parallel_for(size_t{0}, chunks, [&](size_t c) {
      const size_t cb = b + c * chunk, ce = std::min(e, cb + chunk);
      size_t cnt = 0;
      for (size_t i = cb; i < ce; ++i) cnt += bn.bin_of(src[i], s.axis) < s.pos;
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
      size_t l = b + loff[c], r = b + roff[c];
      Box4 lcb, rcb;
      for (size_t i = cb; i < ce; ++i) {
        if (bn.bin_of(src[i], s.axis) < s.pos) {
          lcb.extend(src[i].centroid());
          dst[l++] = src[i];
        } else {
          rcb.extend(src[i].centroid());
          dst[r++] = src[i];
        }
      }
      lcs[c] = lcb;
      rcs[c] = rcb;
    });
    for (size_t c = 0; c < chunks; ++c) {
      lc.extend(lcs[c]);
      rc.extend(rcs[c]);
    }
    return b + total_left;
  }

  void make_leaf(uint32_t node, const BuildRef* refs, size_t b, size_t e, const Box4& bounds) {
    for (size_t i = b; i < e; ++i) out_.prim_ids[i] = refs[i].prim();
    set_leaf(out_.nodes[node], bounds.aabb(), static_cast<uint32_t>(b), static_cast<uint32_t>(e - b));
  }

  void build(uint32_t node, size_t b, size_t e, const Box4& bounds, const Box4& cbounds, int depth, BuildRef* cur,
             BuildRef* other) {
    const size_t n = e - b;
    if (n <= 1) return make_leaf(node, cur, b, e, bounds);

    alignas(16) float cext[4];
    _mm_store_ps(cext, _mm_sub_ps(cbounds.hi, cbounds.lo));
    const bool flat = !(cext[0] > 0.0f || cext[1] > 0.0f || cext[2] > 0.0f);

    size_t mid = b;
    Box4 lb, rb, lcb, rcb;
    BuildRef* child_buf = cur;
    BuildRef* child_other = other;
    bool done = false;
    if (!flat && depth < kForceMedianDepth) {
      const Binning bn(cbounds, opt_.bins);
      const auto bins = bin(cur, b, e, bn);
      const Split s = find_split(*bins, bn, static_cast<uint32_t>(n));
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
    Bvh2Node& nd = out_.nodes[node];
    nd.set_bounds(bounds.aabb());
    nd.index = left;
    nd.count = 0;
    if (n >= kParallelTaskSize) {
      tbb::parallel_invoke([&] { build(left, b, mid, lb, lcb, depth + 1, child_buf, child_other); },
                           [&] { build(left + 1, mid, e, rb, rcb, depth + 1, child_buf, child_other); });
    } else {
      build(left, b, mid, lb, lcb, depth + 1, child_buf, child_other);
      build(left + 1, mid, e, rb, rcb, depth + 1, child_buf, child_other);
    }
  }

  std::vector<BuildRef> refs_, scratch_;
  BuildOptions opt_;
  BinaryBvh out_;
  std::atomic<uint32_t> next_node_{1};
};

}  // namespace

BinaryBvh build_binned_sah(std::vector<BuildRef> refs, const BuildOptions& options) {
  return BinnedBuilder(std::move(refs), options).run();
}

BinaryBvh build_binned_sah(std::span<const Aabb> boxes, std::span<const Vec3f> centroids,
                           const BuildOptions& options) {
  return build_binned_sah(make_build_refs(boxes, centroids), options);
}

}  // namespace raylab
