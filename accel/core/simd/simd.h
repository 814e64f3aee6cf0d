#pragma once
// Thin SIMD layer for the vector kernels (the wide BVH's node tests, the
// triangle blocks of every structure with SIMD leaves): float vectors of
// width 4, 8 and 16 with the few operations the node and triangle tests
// need. Comparisons return plain bit masks (bit i = lane i), so kernels
// branch on integers.
//
// The ISA is chosen when the project is compiled (RAYLAB_NATIVE builds with
// -march=native): AVX-512 (F+VL+DQ+BW) uses mask registers for comparisons and
// 512-bit vectors for width 16; AVX2+FMA uses 256-bit vectors and movemask;
// anything else falls back to plain arrays the compiler may vectorise.
// isa_name() reports which one was compiled in; that the CPU can run it is
// checked once at start-up, for every kernel (instruction_sets.h).
//
// No operation here contracts a*b+c implicitly: fmadd() is explicit and only
// used where the caller has accounted for its rounding (the slab test); the
// watertight triangle test uses separate mul and sub, like the scalar test.
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

#if defined(__AVX512F__) && defined(__AVX512VL__) && defined(__AVX512DQ__) && defined(__AVX512BW__)
#define RAYLAB_SIMD_AVX512 1
#endif
#if defined(__AVX2__) && defined(__FMA__)
#define RAYLAB_SIMD_AVX2 1
#endif
#if defined(__FMA__)
#define RAYLAB_SIMD_FMA 1
#endif

namespace raylab::simd {

// Name of the instruction set the wide kernels were compiled for.
inline const char* isa_name() {
#if defined(RAYLAB_SIMD_AVX512)
  return "avx512";
#elif defined(RAYLAB_SIMD_AVX2)
  return "avx2";
#elif defined(__SSE2__)
  return "sse2";
#else
  return "scalar";
#endif
}

// Widest vector the kernels use natively, in bits (reported in build stats).
inline int isa_bits() {
#if defined(RAYLAB_SIMD_AVX512)
  return 512;
#elif defined(RAYLAB_SIMD_AVX2)
  return 256;
#elif defined(__SSE2__)
  return 128;
#else
  return 32;
#endif
}

inline uint32_t ctz(uint32_t m) { return static_cast<uint32_t>(__builtin_ctz(m)); }
inline int popcount(uint32_t m) { return __builtin_popcount(m); }
// ctz as a 64-bit index: with the 32-bit form GCC 12 sign-extended the
// result before addressing with it (one instruction on the walk's path from
// a node to the next).
inline uint64_t ctz_index(uint32_t m) { return static_cast<uint64_t>(__builtin_ctzll(static_cast<uint64_t>(m))); }

// A data-dependent condition, true about as often as false, that a branch
// predictor cannot learn: the compiler is told so, which makes it choose a
// conditional move over a branch (GCC 12 branched on a plain comparison).
inline bool unpredictable(bool c) {
#if defined(__clang__)
  return __builtin_unpredictable(c);
#elif defined(__GNUC__)
  return __builtin_expect_with_probability(c, 1, 0.5);
#else
  return c;
#endif
}

#if defined(__AVX2__)
// AVX2 has no compress instruction (AVX-512's vpcompress). Its stand-in: a
// permutation that moves the set lanes of an 8-bit mask to the front in
// order, from a 1 KiB table of packed 3-bit lane indices (lane i's source in
// bits 3i..3i+2) and one variable shift; vpermd reads only the low 3 bits of
// each index. Lanes past the mask's count get lane 0.
inline constexpr std::array<uint32_t, 256> kCompressIndex8 = [] {
  std::array<uint32_t, 256> table{};
  for (uint32_t mask = 0; mask < 256; ++mask) {
    uint32_t packed = 0;
    int lane = 0;
    for (uint32_t i = 0; i < 8; ++i)
      if ((mask >> i) & 1u) packed |= i << (3 * lane++);
    table[mask] = packed;
  }
  return table;
}();
inline __m256i compress_index8(uint32_t mask) {
  return _mm256_srlv_epi32(_mm256_set1_epi32(static_cast<int>(kCompressIndex8[mask & 0xFFu])),
                           _mm256_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21));
}
#endif

// Portable fallback: an array of W floats. Loops are simple enough for the
// compiler to vectorise with whatever the target offers.
template <int W>
struct vfloat {
  float v[W];
  static vfloat load(const float* p) {
    vfloat r;
    std::memcpy(r.v, p, sizeof r.v);
    return r;
  }
  static vfloat broadcast(float x) {
    vfloat r;
    for (int i = 0; i < W; ++i) r.v[i] = x;
    return r;
  }
  void store(float* p) const { std::memcpy(p, v, sizeof v); }
#define RAYLAB_VF_BINOP(op)                                           \
  friend vfloat operator op(const vfloat& a, const vfloat& b) {       \
    vfloat r;                                                         \
    for (int i = 0; i < W; ++i) r.v[i] = a.v[i] op b.v[i];            \
    return r;                                                         \
  }
  RAYLAB_VF_BINOP(+)
  RAYLAB_VF_BINOP(-)
  RAYLAB_VF_BINOP(*)
  RAYLAB_VF_BINOP(/)
#undef RAYLAB_VF_BINOP
#define RAYLAB_VF_CMP(name, op)                                           \
  friend uint32_t name(const vfloat& a, const vfloat& b) {                \
    uint32_t m = 0;                                                       \
    for (int i = 0; i < W; ++i) m |= static_cast<uint32_t>(a.v[i] op b.v[i]) << i; \
    return m;                                                             \
  }
  RAYLAB_VF_CMP(cmp_lt, <)
  RAYLAB_VF_CMP(cmp_le, <=)
  RAYLAB_VF_CMP(cmp_gt, >)
  RAYLAB_VF_CMP(cmp_ge, >=)
  RAYLAB_VF_CMP(cmp_eq, ==)
  RAYLAB_VF_CMP(cmp_neq, !=)
#undef RAYLAB_VF_CMP
  // ~a & b (andnot(-0.0, x) = |x|), a & b and a ^ b on the bits.
  friend vfloat andnot(const vfloat& a, const vfloat& b) { return bitwise(a, b, [](uint32_t x, uint32_t y) { return ~x & y; }); }
  friend vfloat and_bits(const vfloat& a, const vfloat& b) { return bitwise(a, b, [](uint32_t x, uint32_t y) { return x & y; }); }
  friend vfloat xor_bits(const vfloat& a, const vfloat& b) { return bitwise(a, b, [](uint32_t x, uint32_t y) { return x ^ y; }); }
  template <typename Op>
  static vfloat bitwise(const vfloat& a, const vfloat& b, Op op) {
    vfloat r;
    for (int i = 0; i < W; ++i) {
      uint32_t x, y;
      std::memcpy(&x, &a.v[i], 4);
      std::memcpy(&y, &b.v[i], 4);
      x = op(x, y);
      std::memcpy(&r.v[i], &x, 4);
    }
    return r;
  }
  // Float min/max through the integer order of the bits (see vfloat<8>).
  static int32_t signed_bits(float f) {
    int32_t x;
    std::memcpy(&x, &f, 4);
    return x;
  }
  friend vfloat min_bits(const vfloat& a, const vfloat& b) {
    vfloat r;
    for (int i = 0; i < W; ++i) r.v[i] = signed_bits(a.v[i]) < signed_bits(b.v[i]) ? a.v[i] : b.v[i];
    return r;
  }
  friend vfloat max_bits(const vfloat& a, const vfloat& b) {
    vfloat r;
    for (int i = 0; i < W; ++i) r.v[i] = signed_bits(a.v[i]) > signed_bits(b.v[i]) ? a.v[i] : b.v[i];
    return r;
  }
  // The bits plus k as a signed integer (k units in the last place for a
  // finite float >= +0), and a < b in the signed-integer order of the bits.
  friend vfloat add_ulps(const vfloat& a, int32_t k) {
    vfloat r;
    for (int i = 0; i < W; ++i) {
      const int32_t x = static_cast<int32_t>(static_cast<uint32_t>(signed_bits(a.v[i])) + static_cast<uint32_t>(k));
      std::memcpy(&r.v[i], &x, 4);
    }
    return r;
  }
  friend uint32_t cmp_lt_bits(const vfloat& a, const vfloat& b) {
    uint32_t m = 0;
    for (int i = 0; i < W; ++i) m |= static_cast<uint32_t>(signed_bits(a.v[i]) < signed_bits(b.v[i])) << i;
    return m;
  }
  // Bit i set when lane i's sign bit is set (NaN and -0 included).
  friend uint32_t sign_bits(const vfloat& a) {
    uint32_t m = 0;
    for (int i = 0; i < W; ++i) m |= static_cast<uint32_t>(std::signbit(a.v[i])) << i;
    return m;
  }
  // min/max with the x86 convention: the second operand wins when either is NaN.
  friend vfloat min(const vfloat& a, const vfloat& b) {
    vfloat r;
    for (int i = 0; i < W; ++i) r.v[i] = a.v[i] < b.v[i] ? a.v[i] : b.v[i];
    return r;
  }
  friend vfloat max(const vfloat& a, const vfloat& b) {
    vfloat r;
    for (int i = 0; i < W; ++i) r.v[i] = a.v[i] > b.v[i] ? a.v[i] : b.v[i];
    return r;
  }
  // a*b+c with a single rounding (std::fma: exact, but slow without hardware FMA).
  friend vfloat fmadd(const vfloat& a, const vfloat& b, const vfloat& c) {
    vfloat r;
    for (int i = 0; i < W; ++i) r.v[i] = std::fma(a.v[i], b.v[i], c.v[i]);
    return r;
  }
};

// a*b+c lane by lane with std::fma (exact, but slow without hardware FMA).
template <typename V, int W>
V fmadd_by_lanes(V a, V b, V c) {
  alignas(4 * W) float x[W], y[W], z[W];
  a.store(x), b.store(y), c.store(z);
  for (int i = 0; i < W; ++i) x[i] = std::fma(x[i], y[i], z[i]);
  return V::load(x);
}

// The members of the register specialisations whose intrinsics differ only
// in their width prefix (MM: _mm, _mm256 or _mm512), written once.
#define RAYLAB_VF_INTRINSICS(MM)                                                   \
  static vfloat load(const float* p) { return {MM##_load_ps(p)}; }                 \
  static vfloat broadcast(float x) { return {MM##_set1_ps(x)}; }                   \
  void store(float* p) const { MM##_store_ps(p, v); }                              \
  friend vfloat operator+(vfloat a, vfloat b) { return {MM##_add_ps(a.v, b.v)}; }  \
  friend vfloat operator-(vfloat a, vfloat b) { return {MM##_sub_ps(a.v, b.v)}; }  \
  friend vfloat operator*(vfloat a, vfloat b) { return {MM##_mul_ps(a.v, b.v)}; }  \
  friend vfloat operator/(vfloat a, vfloat b) { return {MM##_div_ps(a.v, b.v)}; }  \
  friend vfloat andnot(vfloat a, vfloat b) { return {MM##_andnot_ps(a.v, b.v)}; }  \
  friend vfloat and_bits(vfloat a, vfloat b) { return {MM##_and_ps(a.v, b.v)}; }   \
  friend vfloat xor_bits(vfloat a, vfloat b) { return {MM##_xor_ps(a.v, b.v)}; }

// Float min/max (x86: the second operand wins when either is NaN).
#define RAYLAB_VF_MIN_MAX(MM)                                                      \
  friend vfloat min(vfloat a, vfloat b) { return {MM##_min_ps(a.v, b.v)}; }        \
  friend vfloat max(vfloat a, vfloat b) { return {MM##_max_ps(a.v, b.v)}; }

// min/max by the signed-integer order of the bits: equal to float min/max
// when both are >= +0, and a negative input always wins min / loses max.
// One cycle instead of four (Embree's slab test uses the same trick).
// BITS: the register width in the cast intrinsics' names (128, 256).
#define RAYLAB_VF_INTEGER_MIN_MAX(MM, BITS)                                                         \
  friend vfloat min_bits(vfloat a, vfloat b) {                                                      \
    return {MM##_castsi##BITS##_ps(MM##_min_epi32(MM##_castps_si##BITS(a.v), MM##_castps_si##BITS(b.v)))}; \
  }                                                                                                 \
  friend vfloat max_bits(vfloat a, vfloat b) {                                                      \
    return {MM##_castsi##BITS##_ps(MM##_max_epi32(MM##_castps_si##BITS(a.v), MM##_castps_si##BITS(b.v)))}; \
  }

// a*b+c with a single rounding: one instruction, or lane by lane.
#if defined(RAYLAB_SIMD_FMA)
#define RAYLAB_VF_FMADD(MM, W) \
  friend vfloat fmadd(vfloat a, vfloat b, vfloat c) { return {MM##_fmadd_ps(a.v, b.v, c.v)}; }
#else
#define RAYLAB_VF_FMADD(MM, W) \
  friend vfloat fmadd(vfloat a, vfloat b, vfloat c) { return fmadd_by_lanes<vfloat, W>(a, b, c); }
#endif

// Comparisons into AVX-512 mask registers (any width with AVX-512VL).
#define RAYLAB_VF_MASK_COMPARE(MM)                                                             \
  friend uint32_t cmp_lt(vfloat a, vfloat b) { return MM##_cmp_ps_mask(a.v, b.v, _CMP_LT_OQ); }  \
  friend uint32_t cmp_le(vfloat a, vfloat b) { return MM##_cmp_ps_mask(a.v, b.v, _CMP_LE_OQ); }  \
  friend uint32_t cmp_gt(vfloat a, vfloat b) { return MM##_cmp_ps_mask(a.v, b.v, _CMP_GT_OQ); }  \
  friend uint32_t cmp_ge(vfloat a, vfloat b) { return MM##_cmp_ps_mask(a.v, b.v, _CMP_GE_OQ); }  \
  friend uint32_t cmp_eq(vfloat a, vfloat b) { return MM##_cmp_ps_mask(a.v, b.v, _CMP_EQ_OQ); }  \
  friend uint32_t cmp_neq(vfloat a, vfloat b) { return MM##_cmp_ps_mask(a.v, b.v, _CMP_NEQ_UQ); }

#if defined(__SSE2__)
template <>
struct vfloat<4> {
  __m128 v;
  RAYLAB_VF_INTRINSICS(_mm)
  friend uint32_t sign_bits(vfloat a) { return static_cast<uint32_t>(_mm_movemask_ps(a.v)); }
  RAYLAB_VF_MIN_MAX(_mm)
#if defined(__SSE4_1__)
  RAYLAB_VF_INTEGER_MIN_MAX(_mm, 128)
#else
  friend vfloat min_bits(vfloat a, vfloat b) {
    const __m128i x = _mm_castps_si128(a.v), y = _mm_castps_si128(b.v);
    const __m128i lt = _mm_cmplt_epi32(x, y);
    return {_mm_castsi128_ps(_mm_or_si128(_mm_and_si128(lt, x), _mm_andnot_si128(lt, y)))};
  }
  friend vfloat max_bits(vfloat a, vfloat b) {
    const __m128i x = _mm_castps_si128(a.v), y = _mm_castps_si128(b.v);
    const __m128i gt = _mm_cmpgt_epi32(x, y);
    return {_mm_castsi128_ps(_mm_or_si128(_mm_and_si128(gt, x), _mm_andnot_si128(gt, y)))};
  }
#endif
  friend vfloat add_ulps(vfloat a, int32_t k) {
    return {_mm_castsi128_ps(_mm_add_epi32(_mm_castps_si128(a.v), _mm_set1_epi32(k)))};
  }
  // A vector comparison and a movemask, also with AVX-512: GCC 12 under
  // -fsanitize spilled a comparison's 8-bit mask register with kmovb and
  // read it back as 32 bits (popcnt from memory), so the upper bits were
  // stack garbage (BvhPacket.FrustumCullsOnlyWhatEveryRayCulls failed in the
  // sanitizer build only, in about half of the runs).
  // a < b: one comparison and the movemask, no complement (the box test's critical path).
  friend uint32_t cmp_lt_bits(vfloat a, vfloat b) {
    return static_cast<uint32_t>(_mm_movemask_ps(_mm_castsi128_ps(_mm_cmpgt_epi32(_mm_castps_si128(b.v), _mm_castps_si128(a.v)))));
  }
#if defined(RAYLAB_SIMD_AVX512)
  RAYLAB_VF_MASK_COMPARE(_mm)
#else
  friend uint32_t cmp_lt(vfloat a, vfloat b) { return static_cast<uint32_t>(_mm_movemask_ps(_mm_cmplt_ps(a.v, b.v))); }
  friend uint32_t cmp_le(vfloat a, vfloat b) { return static_cast<uint32_t>(_mm_movemask_ps(_mm_cmple_ps(a.v, b.v))); }
  friend uint32_t cmp_gt(vfloat a, vfloat b) { return static_cast<uint32_t>(_mm_movemask_ps(_mm_cmpgt_ps(a.v, b.v))); }
  friend uint32_t cmp_ge(vfloat a, vfloat b) { return static_cast<uint32_t>(_mm_movemask_ps(_mm_cmpge_ps(a.v, b.v))); }
  friend uint32_t cmp_eq(vfloat a, vfloat b) { return static_cast<uint32_t>(_mm_movemask_ps(_mm_cmpeq_ps(a.v, b.v))); }
  friend uint32_t cmp_neq(vfloat a, vfloat b) { return static_cast<uint32_t>(_mm_movemask_ps(_mm_cmpneq_ps(a.v, b.v))); }
#endif
  RAYLAB_VF_FMADD(_mm, 4)
};
#endif

#if defined(__AVX__)
template <>
struct vfloat<8> {
  __m256 v;
  RAYLAB_VF_INTRINSICS(_mm256)
  friend uint32_t sign_bits(vfloat a) { return static_cast<uint32_t>(_mm256_movemask_ps(a.v)); }
  RAYLAB_VF_MIN_MAX(_mm256)
#if defined(__AVX2__)
  RAYLAB_VF_INTEGER_MIN_MAX(_mm256, 256)
  friend vfloat add_ulps(vfloat a, int32_t k) {
    return {_mm256_castsi256_ps(_mm256_add_epi32(_mm256_castps_si256(a.v), _mm256_set1_epi32(k)))};
  }
  // A vector comparison and a movemask, also with AVX-512 (see vfloat<4>).
  friend uint32_t cmp_lt_bits(vfloat a, vfloat b) {
    return static_cast<uint32_t>(_mm256_movemask_ps(_mm256_castsi256_ps(_mm256_cmpgt_epi32(_mm256_castps_si256(b.v), _mm256_castps_si256(a.v)))));
  }
#else
  friend vfloat min_bits(vfloat a, vfloat b) { return min(a, b); }
  friend vfloat max_bits(vfloat a, vfloat b) { return max(a, b); }
  // AVX without AVX2: the integer forms on the two 128-bit halves.
  friend vfloat add_ulps(vfloat a, int32_t k) {
    const __m128i lo = _mm_add_epi32(_mm_castps_si128(_mm256_castps256_ps128(a.v)), _mm_set1_epi32(k));
    const __m128i hi = _mm_add_epi32(_mm_castps_si128(_mm256_extractf128_ps(a.v, 1)), _mm_set1_epi32(k));
    return {_mm256_insertf128_ps(_mm256_castps128_ps256(_mm_castsi128_ps(lo)), _mm_castsi128_ps(hi), 1)};
  }
  friend uint32_t cmp_lt_bits(vfloat a, vfloat b) {
    const __m128i gl = _mm_cmpgt_epi32(_mm_castps_si128(_mm256_castps256_ps128(b.v)), _mm_castps_si128(_mm256_castps256_ps128(a.v)));
    const __m128i gh = _mm_cmpgt_epi32(_mm_castps_si128(_mm256_extractf128_ps(b.v, 1)), _mm_castps_si128(_mm256_extractf128_ps(a.v, 1)));
    return static_cast<uint32_t>(_mm_movemask_ps(_mm_castsi128_ps(gl))) |
           static_cast<uint32_t>(_mm_movemask_ps(_mm_castsi128_ps(gh))) << 4;
  }
#endif
#if defined(RAYLAB_SIMD_AVX512)
  RAYLAB_VF_MASK_COMPARE(_mm256)
#else
  template <int kPredicate>
  static uint32_t compare(vfloat a, vfloat b) {
    return static_cast<uint32_t>(_mm256_movemask_ps(_mm256_cmp_ps(a.v, b.v, kPredicate)));
  }
  friend uint32_t cmp_lt(vfloat a, vfloat b) { return compare<_CMP_LT_OQ>(a, b); }
  friend uint32_t cmp_le(vfloat a, vfloat b) { return compare<_CMP_LE_OQ>(a, b); }
  friend uint32_t cmp_gt(vfloat a, vfloat b) { return compare<_CMP_GT_OQ>(a, b); }
  friend uint32_t cmp_ge(vfloat a, vfloat b) { return compare<_CMP_GE_OQ>(a, b); }
  friend uint32_t cmp_eq(vfloat a, vfloat b) { return compare<_CMP_EQ_OQ>(a, b); }
  friend uint32_t cmp_neq(vfloat a, vfloat b) { return compare<_CMP_NEQ_UQ>(a, b); }
#endif
  RAYLAB_VF_FMADD(_mm256, 8)
};
#endif

#if defined(RAYLAB_SIMD_AVX2) && !defined(RAYLAB_SIMD_AVX512)
// Sixteen lanes as two AVX2 halves (lanes 0..7 and 8..15), for the 16-ray
// packets (traverse_packet.h) and the 16-wide layouts on AVX2 machines. The
// portable array form had them compiled as scalar loops: `bvh:packet=16` ran
// at half the single-ray speed on a Zen 3.
// Every operation is the 8-lane one on each half; masks are lo | hi << 8.
template <>
struct vfloat<16> {
  vfloat<8> lo, hi;
  static vfloat load(const float* p) { return {vfloat<8>::load(p), vfloat<8>::load(p + 8)}; }
  static vfloat broadcast(float x) {
    const vfloat<8> h = vfloat<8>::broadcast(x);
    return {h, h};
  }
  void store(float* p) const { lo.store(p), hi.store(p + 8); }
  // One 8-lane operation applied to each half.
  template <class Op>
  static vfloat halves(vfloat x, vfloat y, Op op) { return {op(x.lo, y.lo), op(x.hi, y.hi)}; }
  friend vfloat operator+(vfloat x, vfloat y) { return halves(x, y, [](vfloat<8> a, vfloat<8> b) { return a + b; }); }
  friend vfloat operator-(vfloat x, vfloat y) { return halves(x, y, [](vfloat<8> a, vfloat<8> b) { return a - b; }); }
  friend vfloat operator*(vfloat x, vfloat y) { return halves(x, y, [](vfloat<8> a, vfloat<8> b) { return a * b; }); }
  friend vfloat operator/(vfloat x, vfloat y) { return halves(x, y, [](vfloat<8> a, vfloat<8> b) { return a / b; }); }
  friend vfloat andnot(vfloat x, vfloat y) { return halves(x, y, [](vfloat<8> a, vfloat<8> b) { return andnot(a, b); }); }
  friend vfloat and_bits(vfloat x, vfloat y) { return halves(x, y, [](vfloat<8> a, vfloat<8> b) { return and_bits(a, b); }); }
  friend vfloat xor_bits(vfloat x, vfloat y) { return halves(x, y, [](vfloat<8> a, vfloat<8> b) { return xor_bits(a, b); }); }
  friend vfloat min(vfloat x, vfloat y) { return halves(x, y, [](vfloat<8> a, vfloat<8> b) { return min(a, b); }); }
  friend vfloat max(vfloat x, vfloat y) { return halves(x, y, [](vfloat<8> a, vfloat<8> b) { return max(a, b); }); }
  friend vfloat min_bits(vfloat x, vfloat y) { return halves(x, y, [](vfloat<8> a, vfloat<8> b) { return min_bits(a, b); }); }
  friend vfloat max_bits(vfloat x, vfloat y) { return halves(x, y, [](vfloat<8> a, vfloat<8> b) { return max_bits(a, b); }); }
  friend vfloat fmadd(vfloat a, vfloat b, vfloat c) { return {fmadd(a.lo, b.lo, c.lo), fmadd(a.hi, b.hi, c.hi)}; }
  friend vfloat add_ulps(vfloat a, int32_t k) { return {add_ulps(a.lo, k), add_ulps(a.hi, k)}; }
#define RAYLAB_VF_HALVES_MASK(name) \
  friend uint32_t name(vfloat a, vfloat b) { return name(a.lo, b.lo) | name(a.hi, b.hi) << 8; }
  RAYLAB_VF_HALVES_MASK(cmp_lt)
  RAYLAB_VF_HALVES_MASK(cmp_le)
  RAYLAB_VF_HALVES_MASK(cmp_gt)
  RAYLAB_VF_HALVES_MASK(cmp_ge)
  RAYLAB_VF_HALVES_MASK(cmp_eq)
  RAYLAB_VF_HALVES_MASK(cmp_neq)
  RAYLAB_VF_HALVES_MASK(cmp_lt_bits)
#undef RAYLAB_VF_HALVES_MASK
  friend uint32_t sign_bits(vfloat a) { return sign_bits(a.lo) | sign_bits(a.hi) << 8; }
};
#endif

#if defined(RAYLAB_SIMD_AVX512)
template <>
struct vfloat<16> {
  __m512 v;
  RAYLAB_VF_INTRINSICS(_mm512)
  friend uint32_t sign_bits(vfloat a) {
    return _mm512_cmplt_epi32_mask(_mm512_castps_si512(a.v), _mm512_setzero_si512());
  }
  // Zero-masking forms with a full mask: GCC 12's unmasked forms read an
  // undefined vector and trip -Wmaybe-uninitialized (as in sort_network.h).
  friend vfloat min(vfloat a, vfloat b) { return {_mm512_maskz_min_ps(0xFFFF, a.v, b.v)}; }
  friend vfloat max(vfloat a, vfloat b) { return {_mm512_maskz_max_ps(0xFFFF, a.v, b.v)}; }
  friend vfloat min_bits(vfloat a, vfloat b) {
    return {_mm512_castsi512_ps(_mm512_maskz_min_epi32(0xFFFF, _mm512_castps_si512(a.v), _mm512_castps_si512(b.v)))};
  }
  friend vfloat max_bits(vfloat a, vfloat b) {
    return {_mm512_castsi512_ps(_mm512_maskz_max_epi32(0xFFFF, _mm512_castps_si512(a.v), _mm512_castps_si512(b.v)))};
  }
  friend vfloat add_ulps(vfloat a, int32_t k) {
    return {_mm512_castsi512_ps(_mm512_maskz_add_epi32(0xFFFF, _mm512_castps_si512(a.v), _mm512_set1_epi32(k)))};
  }
  // The mask register moved out as 32 bits (see vfloat<4> on GCC 12).
  friend uint32_t cmp_lt_bits(vfloat a, vfloat b) {
    return _cvtmask16_u32(_mm512_cmplt_epi32_mask(_mm512_castps_si512(a.v), _mm512_castps_si512(b.v)));
  }
  RAYLAB_VF_MASK_COMPARE(_mm512)
  friend vfloat fmadd(vfloat a, vfloat b, vfloat c) { return {_mm512_fmadd_ps(a.v, b.v, c.v)}; }
};
#endif

// Eight bytes as eight floats (0..255, exact): the compressed node's planes.
inline vfloat<8> u8_to_float8(const uint8_t* p) {
#if defined(__AVX2__)
  return {_mm256_cvtepi32_ps(_mm256_cvtepu8_epi32(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p))))};
#elif defined(__AVX__)
  const __m128i b = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(p));
  const __m128 lo = _mm_cvtepi32_ps(_mm_cvtepu8_epi32(b));
  const __m128 hi = _mm_cvtepi32_ps(_mm_cvtepu8_epi32(_mm_srli_si128(b, 4)));
  return {_mm256_insertf128_ps(_mm256_castps128_ps256(lo), hi, 1)};
#else
  alignas(32) float f[8];
  for (int i = 0; i < 8; ++i) f[i] = static_cast<float>(p[i]);
  return vfloat<8>::load(f);
#endif
}

#undef RAYLAB_VF_INTRINSICS
#undef RAYLAB_VF_MIN_MAX
#undef RAYLAB_VF_MASK_COMPARE
#undef RAYLAB_VF_INTEGER_MIN_MAX
#undef RAYLAB_VF_FMADD

}  // namespace raylab::simd
