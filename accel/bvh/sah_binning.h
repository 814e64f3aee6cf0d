#pragma once
// Binned SAH split search over build references (Wald 2007), shared by the
// binned builder and SBVH's object splits: references are binned by centroid
// along each axis, and every bin boundary is a split candidate. Large ranges
// bin in parallel (TBB reduction of per-chunk bin sets).
#include <immintrin.h>

#include <cstring>
#include <limits>
#include <memory>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "accel/bvh/build_common.h"

namespace raylab::sah {

inline constexpr int kMaxBins = 256;
inline constexpr size_t kParallelBinSize = 32768;  // ranges at least this large bin in parallel

// The boxes of bins on three axes (SSE lanes x, y, z, -). Bins are plain
// storage (default-initialised, i.e. not at all): a node initialises only
// the bins it uses, which matters because most nodes are small.
template <int kBins>
struct BinBoxes {
#if defined(__AVX__)
  // A bin's box as one 256-bit value, lo in the low half and -hi in the
  // high half, so that growing a bin is one min with one load and one store
  // (binning is a fifth of the build). With the bin as the first operand the
  // results are exactly min(lo, box.lo) and max(hi, box.hi): on equal values
  // (+0 and -0) both return the second operand, and negation is exact.
  __m256 bound[3][kBins];

  using Packed = __m256;  // a box in the bins' form: packed once, grown into three bins
  static Packed pack(const Box4& box) {
    const __m128 sign = _mm_set1_ps(-0.0f);
    return _mm256_insertf128_ps(_mm256_castps128_ps256(box.lo), _mm_xor_ps(box.hi, sign), 1);
  }
  void reset(int bins) {
    const __m256 empty = _mm256_set1_ps(std::numeric_limits<float>::infinity());  // lo = +inf, hi = -inf
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < bins; ++b) bound[a][b] = empty;
  }
  void grow_packed(int axis, int bin, Packed packed) { bound[axis][bin] = _mm256_min_ps(bound[axis][bin], packed); }
  void grow(int axis, int bin, const Box4& box) { grow_packed(axis, bin, pack(box)); }
  Box4 box(int axis, int bin) const {
    Box4 r;
    r.lo = _mm256_castps256_ps128(bound[axis][bin]);
    r.hi = _mm_xor_ps(_mm256_extractf128_ps(bound[axis][bin], 1), _mm_set1_ps(-0.0f));
    return r;
  }
  void merge_boxes(const BinBoxes& o, int bins) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < bins; ++b) bound[a][b] = _mm256_min_ps(bound[a][b], o.bound[a][b]);
  }
#else
  __m128 lo[3][kBins];
  __m128 hi[3][kBins];

  using Packed = Box4;
  static const Box4& pack(const Box4& box) { return box; }
  void grow_packed(int axis, int bin, const Box4& box) { grow(axis, bin, box); }

  void reset(int bins) {
    const __m128 inf = _mm_set1_ps(std::numeric_limits<float>::infinity());
    const __m128 ninf = _mm_set1_ps(-std::numeric_limits<float>::infinity());
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < bins; ++b) {
        lo[a][b] = inf;
        hi[a][b] = ninf;
      }
  }
  void grow(int axis, int bin, const Box4& box) {
    lo[axis][bin] = _mm_min_ps(lo[axis][bin], box.lo);
    hi[axis][bin] = _mm_max_ps(hi[axis][bin], box.hi);
  }
  Box4 box(int axis, int bin) const {
    Box4 r;
    r.lo = lo[axis][bin];
    r.hi = hi[axis][bin];
    return r;
  }
  void merge_boxes(const BinBoxes& o, int bins) {
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < bins; ++b) {
        lo[a][b] = _mm_min_ps(lo[a][b], o.lo[a][b]);
        hi[a][b] = _mm_max_ps(hi[a][b], o.hi[a][b]);
      }
  }
#endif
};

// Object bins: boxes and reference counts.
struct BinSet : BinBoxes<kMaxBins> {
  uint32_t count[3][kMaxBins];

  static std::unique_ptr<BinSet> make(int bins) {
    std::unique_ptr<BinSet> s(new BinSet);
    s->clear(bins);
    return s;
  }
  // Empty boxes and zero counts in the first `bins` bins of each axis.
  void clear(int bins) {
    reset(bins);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < bins; ++b) count[a][b] = 0;
  }
  void add_packed(int axis, int bin, const Packed& packed) {
    grow_packed(axis, bin, packed);
    count[axis][bin]++;
  }
  void merge_from(const BinSet& o, int bins) {
    merge_boxes(o, bins);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < bins; ++b) count[a][b] += o.count[a][b];
  }
};

// Maps centroids to bins: bin = trunc((c - lo) * scale), clamped. Axes with
// flat centroid bounds get scale 0 (everything in bin 0) and are skipped.
struct Binning {
  __m128 lo;
  __m128 scale;
  alignas(16) float lo_s[4];
  alignas(16) float scale_s[4];
  __m128i max_bin;

  Binning(const Box4& cbounds, int bins) {
    lo = cbounds.lo;
    _mm_store_ps(lo_s, lo);
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
  // bins_of(r)[axis] < pos for a split boundary pos in [1, bins - 1], one
  // scalar lane instead of the conversion: with x = (c - lo) * scale as
  // bins_of computes it, trunc(x) < pos exactly when x < pos for
  // 0 <= x < 2^31, and x < 0, x >= 2^31 and NaN all land in bin 0 (the
  // conversion gives INT_MIN for the last two). The partitions rely on this
  // matching the bins exactly: the children's boxes come from the bins.
  bool left_of(const BuildRef& r, int axis, int pos) const {
    float c;
    std::memcpy(&c, reinterpret_cast<const char*>(&r.c) + sizeof(float) * static_cast<size_t>(axis), sizeof c);
    const float x = (c - lo_s[axis]) * scale_s[axis];
    return !(x >= static_cast<float>(pos)) || x >= 2147483648.0f;
  }
};

struct Split {
  int axis = -1;
  int pos = 0;  // references in bins < pos go left
  float cost = std::numeric_limits<float>::infinity();  // lA*lN + rA*rN
  Box4 left, right;
  uint32_t left_count = 0;
};


inline void bin_one(const BuildRef& r, const Binning& bn, BinSet& bins) {
  alignas(16) int32_t idx[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(idx), bn.bins_of(r));
  const BinSet::Packed packed = BinSet::pack(r.box);  // once for the three axes
  for (int a = 0; a < 3; ++a) bins.add_packed(a, idx[a], packed);
}

// Bins refs[b, e) into `bins` (which must be initialised for nbins). Long
// ranges spread consecutive references over two or four bin sets:
// neighbouring references often land in the same bins, and each update of a
// bin waits for the previous one's store (a min and a store-to-load forward,
// about ten cycles); independent sets let those chains overlap.
inline void bin_range(const BuildRef* refs, size_t b, size_t e, const Binning& bn, BinSet& bins, int nbins) {
  if (e - b < 256) {
    for (size_t i = b; i < e; ++i) bin_one(refs[i], bn, bins);
    return;
  }
  thread_local std::unique_ptr<BinSet> extra[3];
  const int sets = e - b >= 2048 ? 4 : 2;
  BinSet* set[4] = {&bins, nullptr, nullptr, nullptr};
  for (int k = 1; k < sets; ++k) {
    if (!extra[k - 1]) extra[k - 1].reset(new BinSet);
    set[k] = extra[k - 1].get();
    set[k]->clear(nbins);
  }
  size_t i = b;
  if (sets == 4) {
    for (; i + 3 < e; i += 4) {
      bin_one(refs[i], bn, *set[0]);
      bin_one(refs[i + 1], bn, *set[1]);
      bin_one(refs[i + 2], bn, *set[2]);
      bin_one(refs[i + 3], bn, *set[3]);
    }
  } else {
    for (; i + 1 < e; i += 2) {
      bin_one(refs[i], bn, *set[0]);
      bin_one(refs[i + 1], bn, *set[1]);
    }
  }
  for (; i < e; ++i) bin_one(refs[i], bn, bins);
  for (int k = 1; k < sets; ++k) bins.merge_from(*set[k], nbins);
}

// Bins refs[b, e) into `out` (cleared here; in parallel when the range is
// large). The caller owns the bin set: a node's bins are 28 KB, and a
// fresh allocation per node was a measurable part of the build (malloc and
// free of a chunk that size on every node of more than 16 references).
inline void bin_refs(const BuildRef* refs, size_t b, size_t e, const Binning& bn, int nbins, BinSet& out) {
  out.clear(nbins);
  if (e - b < kParallelBinSize) {
    bin_range(refs, b, e, bn, out, nbins);
    return;
  }
  struct Reducer {
    const BuildRef* refs;
    const Binning* bn;
    int nbins;
    std::unique_ptr<BinSet> own;  // the split-off reducers' bins
    BinSet* bins;
    Reducer(const BuildRef* r, const Binning* b, int nb, BinSet* into)
        : refs(r), bn(b), nbins(nb), own(into ? nullptr : BinSet::make(nb)), bins(into ? into : own.get()) {}
    Reducer(Reducer& o, tbb::split) : Reducer(o.refs, o.bn, o.nbins, nullptr) {}
    void operator()(const tbb::blocked_range<size_t>& r) { bin_range(refs, r.begin(), r.end(), *bn, *bins, nbins); }
    void join(const Reducer& o) { bins->merge_from(*o.bins, nbins); }
  } red(refs, &bn, nbins, &out);
  tbb::parallel_reduce(tbb::blocked_range<size_t>(b, e, 16384), red);
}

// The same into a new bin set.
inline std::unique_ptr<BinSet> bin_refs(const BuildRef* refs, size_t b, size_t e, const Binning& bn, int nbins) {
  std::unique_ptr<BinSet> bins(new BinSet);
  bin_refs(refs, b, e, bn, nbins, *bins);
  return bins;
}

// The SAH sweep over the nb bins of one axis, shared by the object splits
// here and SBVH's spatial splits: a right-to-left pass accumulates the boxes
// and counts right of each boundary, a left-to-right pass evaluates every
// boundary b (1..nb-1) with references on both sides and calls
// take(b, cost, left, right, left_count, right_count) where the cost is below
// `best_cost` (which take lowers). box(b): bin b's box; left_of(b) /
// right_of(b): references counted left / right of a boundary from bin b.
template <typename BoxOf, typename LeftOf, typename RightOf, typename Take>
inline void sweep_bins(int nb, float& best_cost, BoxOf&& box, LeftOf&& left_of, RightOf&& right_of, Take&& take) {
  float right_area[kMaxBins];
  uint32_t right_count[kMaxBins];
  __m128 right_lo[kMaxBins], right_hi[kMaxBins];
  Box4 acc;
  uint32_t cnt = 0;
  for (int b = nb - 1; b > 0; --b) {
    acc.extend(box(b));
    cnt += right_of(b);
    right_lo[b] = acc.lo;
    right_hi[b] = acc.hi;
    right_area[b] = acc.half_area();
    right_count[b] = cnt;
  }
  Box4 left;
  uint32_t lc = 0;
  for (int b = 1; b < nb; ++b) {
    left.extend(box(b - 1));
    lc += left_of(b - 1);
    if (lc == 0 || right_count[b] == 0) continue;
    const float cost = left.half_area() * static_cast<float>(lc) + right_area[b] * static_cast<float>(right_count[b]);
    if (cost < best_cost) {
      best_cost = cost;
      Box4 right;
      right.lo = right_lo[b];
      right.hi = right_hi[b];
      take(b, left, right, lc, right_count[b]);
    }
  }
}

// The cheapest bin boundary over the three axes (axis -1 when none splits).
inline Split find_binned_split(const BinSet& bins, const Binning& bn, int nb) {
  Split best;
  for (int a = 0; a < 3; ++a) {
    if (bn.scale_s[a] <= 0.0f) continue;
    const auto count = [&](int b) { return bins.count[a][b]; };
    sweep_bins(
        nb, best.cost, [&](int b) { return bins.box(a, b); }, count, count,
        [&](int b, const Box4& left, const Box4& right, uint32_t lc, uint32_t) {
          best.axis = a;
          best.pos = b;
          best.left = left;
          best.right = right;
          best.left_count = lc;
        });
  }
  return best;
}

}  // namespace raylab::sah
