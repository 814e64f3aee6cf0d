#include "accel/bvh/small_sweep.h"

#include <immintrin.h>

#include <algorithm>
#include <bit>
#include <cstdlib>
#include <limits>
#include <type_traits>

namespace raylab::sah {

namespace {

// Centroid keys: integers that order like the floats (and give any bits,
// NaN included, a place), so that ranks always form a permutation.
int32_t order_key(int32_t bits) { return bits ^ ((bits >> 31) & 0x7FFFFFFF); }

// A split's SAH cost as the sweep compares it: NaN (an overflowed extent
// times a flat one) counts as infinite, so some split is always chosen.
float comparable_cost(float cost) { return cost == cost ? cost : std::numeric_limits<float>::infinity(); }

#if defined(__AVX512F__)
// The least lane, in four halving steps (GCC 12's _mm512_reduce_min_*
// helpers, like the plain forms of most intrinsics below, read an undefined
// vector and trip -Wmaybe-uninitialized; the zero-masking forms with every
// lane set do not).
float lane_min(__m512 v) {
  const __mmask16 all = 0xFFFF;
  v = _mm512_maskz_min_ps(all, v, _mm512_maskz_shuffle_f32x4(all, v, v, _MM_SHUFFLE(1, 0, 3, 2)));
  v = _mm512_maskz_min_ps(all, v, _mm512_maskz_shuffle_f32x4(all, v, v, _MM_SHUFFLE(2, 3, 0, 1)));
  v = _mm512_maskz_min_ps(all, v, _mm512_maskz_permute_ps(all, v, _MM_SHUFFLE(1, 0, 3, 2)));
  v = _mm512_maskz_min_ps(all, v, _mm512_maskz_permute_ps(all, v, _MM_SHUFFLE(2, 3, 0, 1)));
  return v[0];
}
int32_t lane_min(__m512i v) {
  const __mmask16 all = 0xFFFF;
  v = _mm512_maskz_min_epi32(all, v, _mm512_maskz_shuffle_i32x4(all, v, v, _MM_SHUFFLE(1, 0, 3, 2)));
  v = _mm512_maskz_min_epi32(all, v, _mm512_maskz_shuffle_i32x4(all, v, v, _MM_SHUFFLE(2, 3, 0, 1)));
  v = _mm512_maskz_min_epi32(all, v, _mm512_maskz_shuffle_epi32(all, v, _MM_PERM_BADC));
  v = _mm512_maskz_min_epi32(all, v, _mm512_maskz_shuffle_epi32(all, v, _MM_PERM_CDAB));
  return static_cast<int32_t>(v[0]);  // lane 0: the low half of the first 64-bit element
}

// choose_small_split_scalar with the (at most sixteen) references in
// registers, one lane each: boxes and centroids transposed to one register
// per coordinate, each axis's order applied by a permutation, the left and
// right boxes of every split position by log-step min/max scans, and the
// costs of all positions at once. Same arithmetic in the same order as the
// scalar sweep (no contraction: -ffp-contract=off), so the same choice.
SmallSplit choose_small_split_avx512(const BuildRef* refs, int n, uint8_t (&order)[3][kSmallSweepMax]) {
  const float inf = std::numeric_limits<float>::infinity();
  const __mmask16 all = 0xFFFF;
  const __mmask16 valid = static_cast<__mmask16>((1u << n) - 1u);
  // Three groups of four floats per reference (box lo, box hi, centroid +
  // id). Reference j + 4l goes to 128-bit lane l of register j; a 4x4
  // transpose inside each lane then gives one register per coordinate
  // with reference i in lane i. Missing references are empty boxes.
  const auto transpose = [&](int group, float fill, __m512& x, __m512& y, __m512& z) {
    __m512 r[4];
    for (int j = 0; j < 4; ++j) {
      r[j] = _mm512_set1_ps(fill);
      for (int l = 0; l < 4 && j + 4 * l < n; ++l) {
        const float* p = reinterpret_cast<const float*>(&refs[j + 4 * l]) + 4 * group;
        r[j] = _mm512_mask_broadcast_f32x4(r[j], static_cast<__mmask16>(0xFu << (4 * l)), _mm_load_ps(p));
      }
    }
    const __m512 t0 = _mm512_maskz_unpacklo_ps(all, r[0], r[1]), t1 = _mm512_maskz_unpacklo_ps(all, r[2], r[3]);
    const __m512 t2 = _mm512_maskz_unpackhi_ps(all, r[0], r[1]), t3 = _mm512_maskz_unpackhi_ps(all, r[2], r[3]);
    x = _mm512_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
    y = _mm512_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
    z = _mm512_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
  };
  __m512 lo[3], hi[3], c[3];
  transpose(0, inf, lo[0], lo[1], lo[2]);
  transpose(1, -inf, hi[0], hi[1], hi[2]);
  transpose(2, 0.0f, c[0], c[1], c[2]);

  const __m512 pos_inf = _mm512_set1_ps(inf), neg_inf = _mm512_set1_ps(-inf);
  // Lane i takes lane i - s (i >= s) / i + s (i + s < 16), else `fill`.
  const auto from_left = [all](__m512 v, __m512 fill, auto s) {
    const __m512i vi = _mm512_castps_si512(v), fi = _mm512_castps_si512(fill);
    return _mm512_castsi512_ps(_mm512_maskz_alignr_epi32(all, vi, fi, 16 - decltype(s)::value));
  };
  const auto from_right = [all](__m512 v, __m512 fill, auto s) {
    const __m512i vi = _mm512_castps_si512(v), fi = _mm512_castps_si512(fill);
    return _mm512_castsi512_ps(_mm512_maskz_alignr_epi32(all, fi, vi, decltype(s)::value));
  };
  // Half areas of boxes lane by lane, 0 for empty ones (as Box4::half_area).
  const auto half_area = [](const __m512* l, const __m512* h) {
    const __m512 dx = _mm512_sub_ps(h[0], l[0]), dy = _mm512_sub_ps(h[1], l[1]), dz = _mm512_sub_ps(h[2], l[2]);
    const __m512 area =
        _mm512_add_ps(_mm512_add_ps(_mm512_mul_ps(dx, dy), _mm512_mul_ps(dy, dz)), _mm512_mul_ps(dz, dx));
    const __mmask16 empty = _mm512_cmp_ps_mask(l[0], h[0], _CMP_GT_OQ) | _mm512_cmp_ps_mask(l[1], h[1], _CMP_GT_OQ) |
                            _mm512_cmp_ps_mask(l[2], h[2], _CMP_GT_OQ);
    return _mm512_maskz_mov_ps(static_cast<__mmask16>(~empty), area);
  };

  const __m512 lane = _mm512_setr_ps(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  const __m512 left_count = lane, right_count = _mm512_sub_ps(_mm512_set1_ps(static_cast<float>(n)), lane);
  const __mmask16 positions = static_cast<__mmask16>(valid & ~1u);  // split i: lanes 1..n-1
  __m512 cost[3];
  __m512 lowest = pos_inf;  // lane by lane over the axes
  alignas(64) int32_t key[kSmallSweepMax];
  // All three orders first: each sweep then loads its order as one vector
  // long after the byte stores that wrote it (right after them the load
  // waits for the stores to retire, a fifth of this function's time).
  for (int a = 0; a < 3; ++a) {
    // Stable sort by rank (the number of keys before a key, ties by
    // index): a key's rank is the population count of two comparison
    // masks, the sort branch-free.
    const __m512i bits = _mm512_castps_si512(c[a]);
    const __m512i kv = _mm512_xor_si512(
        bits, _mm512_and_si512(_mm512_maskz_srai_epi32(all, bits, 31), _mm512_set1_epi32(0x7FFFFFFF)));
    _mm512_store_si512(key, kv);
    uint8_t* o = order[a];
    for (int i = n; i < 16; ++i) o[i] = static_cast<uint8_t>(i);  // missing references stay last
    for (int i = 0; i < n; ++i) {
      const __m512i ki = _mm512_set1_epi32(key[i]);
      const __mmask16 before = static_cast<__mmask16>((1u << i) - 1u);  // lanes j < i (all valid)
      const __mmask16 less = _mm512_mask_cmplt_epi32_mask(valid, kv, ki);
      const __mmask16 tied = _mm512_mask_cmpeq_epi32_mask(before, kv, ki);
      o[std::popcount(static_cast<unsigned>(less | tied))] = static_cast<uint8_t>(i);
    }
  }
  for (int a = 0; a < 3; ++a) {
    const uint8_t* o = order[a];
    const __m512i perm = _mm512_maskz_cvtepu8_epi32(all, _mm_loadu_si128(reinterpret_cast<const __m128i*>(o)));
    __m512 pl[3], ph[3], sl[3], sh[3];
    for (int d = 0; d < 3; ++d) {
      pl[d] = sl[d] = _mm512_maskz_permutexvar_ps(all, perm, lo[d]);
      ph[d] = sh[d] = _mm512_maskz_permutexvar_ps(all, perm, hi[d]);
    }
    // p: box of sorted lanes 0..i (left of split i + 1); s: box of sorted
    // lanes i..15 (right of split i; missing references are empty).
    const auto scan = [&](auto step) {
      for (int d = 0; d < 3; ++d) {
        pl[d] = _mm512_maskz_min_ps(all, pl[d], from_left(pl[d], pos_inf, step));
        ph[d] = _mm512_maskz_max_ps(all, ph[d], from_left(ph[d], neg_inf, step));
        sl[d] = _mm512_maskz_min_ps(all, sl[d], from_right(sl[d], pos_inf, step));
        sh[d] = _mm512_maskz_max_ps(all, sh[d], from_right(sh[d], neg_inf, step));
      }
    };
    scan(std::integral_constant<int, 1>{});
    scan(std::integral_constant<int, 2>{});
    scan(std::integral_constant<int, 4>{});
    scan(std::integral_constant<int, 8>{});
    const __m512 left_area = from_left(half_area(pl, ph), _mm512_setzero_ps(), std::integral_constant<int, 1>{});
    const __m512 right_area = half_area(sl, sh);
    __m512 ca = _mm512_add_ps(_mm512_mul_ps(left_area, left_count), _mm512_mul_ps(right_area, right_count));
    ca = _mm512_mask_mov_ps(ca, _mm512_cmp_ps_mask(ca, ca, _CMP_UNORD_Q), pos_inf);  // comparable_cost
    cost[a] = ca;
    lowest = _mm512_mask_min_ps(lowest, positions, lowest, ca);
  }
  const float min_cost = lane_min(lowest);
  // Among the positions at the lowest cost: the most central, then the
  // first axis, then the first position (key |2i - n| * 64 + axis * 16 + i).
  const __m512i ilane = _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15);
  const __m512i twice_minus_n = _mm512_sub_epi32(_mm512_maskz_slli_epi32(all, ilane, 1), _mm512_set1_epi32(n));
  const __m512i central = _mm512_maskz_abs_epi32(all, twice_minus_n);
  __m512i keys = _mm512_set1_epi32(std::numeric_limits<int32_t>::max());
  const __m512 m = _mm512_set1_ps(min_cost);
  for (int a = 0; a < 3; ++a) {
    const __mmask16 at_min = _mm512_mask_cmp_ps_mask(positions, cost[a], m, _CMP_EQ_OQ);
    const __m512i k =
        _mm512_add_epi32(_mm512_maskz_slli_epi32(all, central, 6), _mm512_add_epi32(_mm512_set1_epi32(16 * a), ilane));
    keys = _mm512_mask_min_epi32(keys, at_min, keys, k);
  }
  const int best_key = lane_min(keys);
  SmallSplit best;
  best.axis = (best_key >> 4) & 3;
  best.pos = best_key & 15;
  best.cost = min_cost;
  return best;
}
#endif

}  // namespace

SmallSplit choose_small_split_scalar(const BuildRef* refs, int n, uint8_t (&order)[3][kSmallSweepMax]) {
  SmallSplit best;
  best.cost = std::numeric_limits<float>::infinity();
  alignas(64) int32_t key[3][kSmallSweepMax];
  for (int i = 0; i < n; ++i) {
    alignas(16) int32_t v[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(v), _mm_castps_si128(refs[i].centroid()));
    for (int a = 0; a < 3; ++a) key[a][i] = order_key(v[a]);
  }
  float right_area[kSmallSweepMax];
  for (int a = 0; a < 3; ++a) {
    // Stable sort by rank (the number of keys before a key, ties by
    // index): branch-free, where an insertion sort mispredicted on every
    // move (perf: the sort was a fifth of the builder's own time).
    uint8_t* o = order[a];
    const int32_t* k = key[a];
    for (int i = 0; i < n; ++i) {
      int rank = 0;
      for (int j = 0; j < n; ++j) rank += (k[j] < k[i]) | ((k[j] == k[i]) & (j < i));
      o[rank] = static_cast<uint8_t>(i);
    }
    Box4 acc;
    for (int i = n - 1; i > 0; --i) {
      acc.extend(refs[o[i]].box);
      right_area[i] = acc.half_area();
    }
    Box4 left;
    for (int i = 1; i < n; ++i) {
      left.extend(refs[o[i - 1]].box);
      const float cost = comparable_cost(left.half_area() * static_cast<float>(i) +
                                         right_area[i] * static_cast<float>(n - i));
      if (cost < best.cost || (cost == best.cost && std::abs(2 * i - n) < std::abs(2 * best.pos - n))) {
        best.cost = cost;
        best.axis = a;
        best.pos = i;
      }
    }
  }
  return best;
}

SmallSplit choose_small_split(const BuildRef* refs, int n, uint8_t (&order)[3][kSmallSweepMax]) {
#if defined(__AVX512F__)
  return choose_small_split_avx512(refs, n, order);
#else
  return choose_small_split_scalar(refs, n, order);
#endif
}

}  // namespace raylab::sah
