#pragma once
// Short sorting networks for ordering a wide node's hit children by entry
// distance. Keys are 64-bit: entry distance bits (non-negative float, so
// integer order = float order) in the high half, child reference in the low
// half with its leaf bit flipped (unique per node, so keys never tie; among
// children at the same distance leaves come first -- rays starting on a
// surface enter every box around their origin at distance 0, and a leaf
// there often holds the hit). Sorted descending, the nearest child ends up
// last, i.e. on top of the traversal stack.
//
// The 8-key network is Batcher's odd-even merge sort (19 comparators in 6
// layers); its first 3 layers sort lanes 0..3 and 4..7 independently, which
// is all that is needed when at most 4 children were hit (the others are 0).
// Each layer is one permute, a min, a max and a blend.
#include <algorithm>
#include <cstdint>
#include <cstring>

#include "accel/core/simd/simd.h"
#include "accel/core/slab_test.h"

namespace raylab {

inline constexpr uint32_t kKeyRefFlip = 0x80000000u;  // the leaf bit of wide child references

// Key of a child from the bits of its entry distance, already clamped at 0
// (the walks clamp a node's distances in one vector operation).
inline uint64_t child_key_bits(uint32_t dist_bits, uint32_t ref) {
  return (static_cast<uint64_t>(dist_bits) << 32) | (ref ^ kKeyRefFlip);
}
// Key of a child: distance clamped at 0 (ordering only needs to be a heuristic
// for negative entry distances, which arise only when tmin < 0).
inline uint64_t child_key(float dist, uint32_t ref) {
  int32_t bits;
  std::memcpy(&bits, &dist, sizeof bits);
  bits = std::max(bits, 0);  // negative (or -0): order as 0
  return child_key_bits(static_cast<uint32_t>(bits), ref);
}
inline float key_dist(uint64_t key) {
  const uint32_t bits = static_cast<uint32_t>(key >> 32);
  float d;
  std::memcpy(&d, &bits, sizeof d);
  return d;
}
inline uint32_t key_ref(uint64_t key) { return static_cast<uint32_t>(key) ^ kKeyRefFlip; }

// The greatest key whose entry distance is within tmax padded as the box
// test pads far distances (kSlabFarPadUlps on the bits; nothing beyond +0
// for a negative tmax): a popped key above it cannot hold a hit closer than
// tmax, and one integer comparison of the whole key says so.
inline uint64_t key_cull_limit(float tmax) {
  uint32_t bits;
  std::memcpy(&bits, &tmax, sizeof bits);
  const uint32_t limit = tmax >= 0.0f ? bits + static_cast<uint32_t>(kSlabFarPadUlps) : 0u;
  return static_cast<uint64_t>(limit) << 32 | 0xFFFFFFFFu;
}

// Sorts keys[0, n) descending (insertion sort; the portable fallback).
inline void sort_keys_descending(uint64_t* keys, int n) {
  for (int i = 1; i < n; ++i) {
    const uint64_t k = keys[i];
    int j = i;
    for (; j > 0 && keys[j - 1] < k; --j) keys[j] = keys[j - 1];
    keys[j] = k;
  }
}

#if defined(RAYLAB_SIMD_AVX512)
namespace network_detail {
// The zero-masking forms (with a full mask) avoid GCC 12's spurious
// -Wuninitialized on the unmasked intrinsics' undefined pass-through operand.
[[gnu::always_inline]] inline __m512i layer(__m512i v, __m512i partner, __mmask8 take_max) {
  const __m512i p = _mm512_maskz_permutexvar_epi64(0xFF, partner, v);
  return _mm512_mask_blend_epi64(take_max, _mm512_maskz_min_epu64(0xFF, v, p), _mm512_maskz_max_epu64(0xFF, v, p));
}
}  // namespace network_detail

// Lanes 0..3 and 4..7 each sorted descending.
[[gnu::always_inline]] inline __m512i sort4x2_descending(__m512i v) {
  using network_detail::layer;
  v = layer(v, _mm512_setr_epi64(1, 0, 3, 2, 5, 4, 7, 6), 0x55);
  v = layer(v, _mm512_setr_epi64(2, 3, 0, 1, 6, 7, 4, 5), 0x33);
  v = layer(v, _mm512_setr_epi64(0, 2, 1, 3, 4, 6, 5, 7), 0x22);
  return v;
}

// The least of the keys in `mask` (at least one lane): three halving steps
// with immediate shuffles. GCC's _mm512_mask_reduce_min_epu64 would do, but
// its helpers start from undefined registers (GCC 12: -Wmaybe-uninitialized).
[[gnu::always_inline]] inline uint64_t min_key(__m512i keys, __mmask8 mask) {
  __m512i v = _mm512_mask_blend_epi64(mask, _mm512_set1_epi64(-1), keys);
  v = _mm512_maskz_min_epu64(0xFF, v, _mm512_maskz_shuffle_i64x2(0xFF, v, v, _MM_SHUFFLE(1, 0, 3, 2)));
  v = _mm512_maskz_min_epu64(0xFF, v, _mm512_maskz_permutex_epi64(0xFF, v, _MM_SHUFFLE(1, 0, 3, 2)));
  v = _mm512_maskz_min_epu64(0xFF, v, _mm512_maskz_shuffle_epi32(0xFFFF, v, _MM_PERM_BADC));
  return static_cast<uint64_t>(v[0]);  // a vector subscript (GCC, Clang): _mm512_castsi512_si128 warns as above
}

// All 8 lanes sorted descending.
[[gnu::always_inline]] inline __m512i sort8_descending(__m512i v) {
  using network_detail::layer;
  v = sort4x2_descending(v);
  v = layer(v, _mm512_setr_epi64(4, 5, 6, 7, 0, 1, 2, 3), 0x0F);
  v = layer(v, _mm512_setr_epi64(0, 1, 4, 5, 2, 3, 6, 7), 0x0C);
  v = layer(v, _mm512_setr_epi64(0, 2, 1, 4, 3, 6, 5, 7), 0x2A);
  return v;
}
#endif

// Sorts n <= 8 keys descending in place, with the vector network when
// available, and returns the least (keys[n - 1]). keys must have room for 8
// entries.
inline uint64_t sort8_keys_descending(uint64_t* keys, int n) {
#if defined(RAYLAB_SIMD_AVX512)
  const __mmask8 valid = static_cast<__mmask8>((1u << n) - 1u);
  __m512i v = _mm512_maskz_loadu_epi64(valid, keys);
  v = n <= 4 ? sort4x2_descending(v) : sort8_descending(v);
  _mm512_mask_storeu_epi64(keys, valid, v);
  return keys[n - 1];
#else
  // Without AVX-512: compare-exchange networks on registers, whose min/max
  // compile to conditional moves: three and four keys by their optimal
  // networks, five to eight by Batcher's odd-even merge network for eight
  // (19 exchanges, 6 layers; Knuth, TAOCP vol. 3, 5.3.4), padded with zeros,
  // which sort last. Incoherent rays' child orders are unpredictable, and the
  // insertion sort's branches were the largest source of mispredictions in
  // the closest-hit walk (callgrind --branch-sim, random rays on Sponza).
  // Any sorting method gives the same order of unique keys.
  const auto exchange = [](uint64_t& hi, uint64_t& lo) {
    const uint64_t a = hi, b = lo;
    hi = a > b ? a : b;
    lo = a > b ? b : a;
  };
  if (n == 3) {
    uint64_t a = keys[0], b = keys[1], c = keys[2];
    exchange(a, b);
    exchange(b, c);
    exchange(a, b);
    keys[0] = a, keys[1] = b, keys[2] = c;
    return c;  // from the register: the walk's next node, not a store's reload
  } else if (n == 4) {
    uint64_t a = keys[0], b = keys[1], c = keys[2], d = keys[3];
    exchange(a, b);
    exchange(c, d);
    exchange(a, c);
    exchange(b, d);
    exchange(b, c);
    keys[0] = a, keys[1] = b, keys[2] = c, keys[3] = d;
    return d;
  } else if (n > 4) {
    uint64_t k[8];
    for (int i = 0; i < 8; ++i) k[i] = i < n ? keys[i] : 0;
    exchange(k[0], k[1]), exchange(k[2], k[3]), exchange(k[4], k[5]), exchange(k[6], k[7]);
    exchange(k[0], k[2]), exchange(k[1], k[3]), exchange(k[4], k[6]), exchange(k[5], k[7]);
    exchange(k[1], k[2]), exchange(k[5], k[6]);
    exchange(k[0], k[4]), exchange(k[1], k[5]), exchange(k[2], k[6]), exchange(k[3], k[7]);
    exchange(k[2], k[4]), exchange(k[3], k[5]);
    exchange(k[1], k[2]), exchange(k[3], k[4]), exchange(k[5], k[6]);
    for (int i = 0; i < 8; ++i) keys[i] = k[i];  // room for 8 (above); lanes past n get zeros
  } else {
    sort_keys_descending(keys, n);
  }
  return keys[n - 1];
#endif
}

}  // namespace raylab
