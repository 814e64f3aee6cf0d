// The vector layer (accel/core/simd/simd.h): sixteen lanes compute what each
// lane defines, and compress moves the masked lanes to the front.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "accel/core/simd/simd.h"

namespace raylab {
namespace {

TEST(Simd, SixteenLanesComputeWhatEachLaneDefines) {
  // vfloat<16> is one AVX-512 register, two AVX2 halves or an array,
  // depending on the build: every form must give, lane by lane, the scalar
  // definitions (x86 min/max: the second operand when either is NaN; the
  // integer order of the bits; one rounding for fmadd), with lane i of a
  // mask in bit i, across both halves.
  using V = simd::vfloat<16>;
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  alignas(64) const float a[16] = {1.0f, -2.0f, 0.0f, -0.0f, nan, 3.5f, inf, 1e-40f,
                                   7.0f, 1.0f, -inf, 2.0f, 5.0f, -1e30f, 0.25f, nan};
  alignas(64) const float b[16] = {2.0f, -2.0f, -0.0f, 0.0f, 1.0f, nan, 1.0f, 2e-40f,
                                   -7.0f, 1.0f + 0x1p-23f, 1.0f, 3.0f, 5.0f, 1e30f, 4.0f, 0.0f};
  alignas(64) const float c[16] = {0.5f, 1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f, 7.0f,
                                   -0.5f, -1.0f, 1e-8f, 0.1f, 0.2f, 0.3f, 1.0f / 3.0f, 9.0f};
  const V va = V::load(a), vb = V::load(b), vc = V::load(c);
  const auto bits = [](float f) {
    int32_t i;
    std::memcpy(&i, &f, 4);
    return i;
  };
  const auto from_bits = [](int32_t i) {
    float f;
    std::memcpy(&f, &i, 4);
    return f;
  };
  const auto same = [&](V got, auto want, const char* what) {
    alignas(64) float g[16];
    got.store(g);
    for (int i = 0; i < 16; ++i) {
      const float w = want(i);
      if (std::isnan(w)) EXPECT_TRUE(std::isnan(g[i])) << what << " lane " << i;
      else EXPECT_EQ(bits(g[i]), bits(w)) << what << " lane " << i;
    }
  };
  same(va + vb, [&](int i) { return a[i] + b[i]; }, "+");
  same(va - vb, [&](int i) { return a[i] - b[i]; }, "-");
  same(va * vb, [&](int i) { return a[i] * b[i]; }, "*");
  same(va / vc, [&](int i) { return a[i] / c[i]; }, "/");
  same(min(va, vb), [&](int i) { return a[i] < b[i] ? a[i] : b[i]; }, "min");
  same(max(va, vb), [&](int i) { return a[i] > b[i] ? a[i] : b[i]; }, "max");
  same(min_bits(va, vb), [&](int i) { return bits(a[i]) < bits(b[i]) ? a[i] : b[i]; }, "min_bits");
  same(max_bits(va, vb), [&](int i) { return bits(a[i]) > bits(b[i]) ? a[i] : b[i]; }, "max_bits");
  same(fmadd(va, vc, vb), [&](int i) { return std::fma(a[i], c[i], b[i]); }, "fmadd");
  same(V::broadcast(2.5f), [&](int) { return 2.5f; }, "broadcast");
  const auto bitwise = [&](int i, auto op) { return from_bits(op(bits(a[i]), bits(b[i]))); };
  same(and_bits(va, vb), [&](int i) { return bitwise(i, [](int32_t x, int32_t y) { return x & y; }); }, "and");
  same(xor_bits(va, vb), [&](int i) { return bitwise(i, [](int32_t x, int32_t y) { return x ^ y; }); }, "xor");
  same(andnot(va, vb), [&](int i) { return bitwise(i, [](int32_t x, int32_t y) { return ~x & y; }); }, "andnot");
  same(add_ulps(vc, 3), [&](int i) { return from_bits(bits(c[i]) + 3); }, "add_ulps");
  const auto mask = [&](auto pred) {
    uint32_t m = 0;
    for (int i = 0; i < 16; ++i) m |= static_cast<uint32_t>(pred(i)) << i;
    return m;
  };
  EXPECT_EQ(cmp_lt(va, vb), mask([&](int i) { return a[i] < b[i]; }));
  EXPECT_EQ(cmp_le(va, vb), mask([&](int i) { return a[i] <= b[i]; }));
  EXPECT_EQ(cmp_gt(va, vb), mask([&](int i) { return a[i] > b[i]; }));
  EXPECT_EQ(cmp_ge(va, vb), mask([&](int i) { return a[i] >= b[i]; }));
  EXPECT_EQ(cmp_eq(va, vb), mask([&](int i) { return a[i] == b[i]; }));
  EXPECT_EQ(cmp_neq(va, vb), mask([&](int i) { return !(a[i] == b[i]); }));
  EXPECT_EQ(cmp_lt_bits(va, vb), mask([&](int i) { return bits(a[i]) < bits(b[i]); }));
  EXPECT_EQ(sign_bits(va), mask([&](int i) { return std::signbit(a[i]); }));
}

#if defined(__AVX2__)
TEST(Simd, CompressIndexMovesTheMaskedLanesToTheFront) {
  // The AVX2 stand-in for a compress instruction (the closest-hit child
  // keys): for every 8-bit mask, lane j of the permutation is the j-th set
  // bit's lane, in order, and lanes past the count are 0.
  for (uint32_t mask = 0; mask < 256; ++mask) {
    alignas(32) int32_t lane[8];
    _mm256_store_si256(reinterpret_cast<__m256i*>(lane), simd::compress_index8(mask));
    int j = 0;
    for (int i = 0; i < 8; ++i)
      if ((mask >> i) & 1u) {
        EXPECT_EQ(lane[j] & 7, i) << "mask " << mask << " lane " << j;
        ++j;
      }
    for (; j < 8; ++j) EXPECT_EQ(lane[j] & 7, 0) << "mask " << mask << " lane " << j;
  }
  // Bits above 7 are ignored.
  alignas(32) int32_t a[8], b[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(a), simd::compress_index8(0x1A5u));
  _mm256_store_si256(reinterpret_cast<__m256i*>(b), simd::compress_index8(0xA5u));
  for (int i = 0; i < 8; ++i) EXPECT_EQ(a[i] & 7, b[i] & 7) << i;
}
#endif

}  // namespace
}  // namespace raylab
