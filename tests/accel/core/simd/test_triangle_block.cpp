// SIMD triangle blocks (accel/core/simd/triangle_block.h): the vector
// watertight test equals the scalar test bit for bit at every width, and
// padding lanes repeat the first triangle.
#include <gtest/gtest.h>

#include <cmath>
#include <numeric>
#include <vector>

#include "accel/core/simd/triangle_block.h"
#include "base/pcg.h"

namespace raylab {
namespace {

template <int W>
void expect_block_matches_scalar(uint64_t seed) {
  Pcg32 rng(seed, 17);
  // Triangles on an integer grid (shared edges, vertices hit exactly by
  // axis-aligned rays: edge functions of exactly 0) and random ones.
  std::vector<Vec3f> v;
  for (int i = 0; i < 3 * W; ++i) {
    if (i < 3 * W / 2) v.push_back(Vec3f(std::floor(4 * rng.uniform()), std::floor(4 * rng.uniform()), std::floor(2 * rng.uniform())));
    else v.push_back(Vec3f(4 * rng.uniform(), 4 * rng.uniform(), 4 * rng.uniform() - 1));
  }
  v[0] = v[1];  // one degenerate triangle
  TriangleBlock<W> blk;
  std::vector<uint32_t> ids(W);
  std::iota(ids.begin(), ids.end(), 0u);
  fill_block<W>(blk, ids.data(), W, [&](uint32_t prim, int c) -> const Vec3f& { return v[3 * prim + c]; });
  size_t hits = 0;
  for (int k = 0; k < 3000; ++k) {
    Ray r;
    if (k % 3 == 0) {  // axis-aligned through grid points
      const Vec3f target(std::floor(5 * rng.uniform()), std::floor(5 * rng.uniform()), 0.5f);
      const int axis = static_cast<int>(rng.next() % 3);
      Vec3f d = Vec3f::Zero();
      d[axis] = rng.uniform() < 0.5f ? -1.0f : 1.0f;
      r = Ray(target - 3.0f * d, d);
    } else {
      const Vec3f o(8 * rng.uniform() - 2, 8 * rng.uniform() - 2, 8 * rng.uniform() - 2);
      const Vec3f t(4 * rng.uniform(), 4 * rng.uniform(), 2 * rng.uniform());
      r = Ray(o, t - o, k % 5 == 0 ? 0.3f : 0.0f, k % 7 == 0 ? 0.8f : 100.0f);
    }
    const BlockRay<W> br(r);
    BlockHits<W> bh;
    const uint32_t mask = intersect_block<W>(blk, br, r.tmin, r.tmax, bh);
    const WatertightRay w(r);
    for (int lane = 0; lane < W; ++lane) {
      float t = 0, u = 0, vv = 0;
      const bool hit = intersect_watertight(w, v[3 * lane], v[3 * lane + 1], v[3 * lane + 2], r.tmin, r.tmax, t, u, vv);
      ASSERT_EQ(hit, ((mask >> lane) & 1) != 0) << "W " << W << " ray " << k << " lane " << lane;
      if (hit) {
        ++hits;
        EXPECT_EQ(t, bh.t[lane]);
        EXPECT_EQ(u, bh.u[lane]);
        EXPECT_EQ(vv, bh.v[lane]);
      }
    }
  }
  EXPECT_GT(hits, 300u);
}

TEST(TriangleBlock, VectorTestEqualsScalarTestBitForBit) {
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    expect_block_matches_scalar<4>(seed);
    expect_block_matches_scalar<8>(seed);
    expect_block_matches_scalar<16>(seed);
  }
}

TEST(TriangleBlock, PaddingLanesRepeatTheFirstTriangle) {
  std::vector<Vec3f> v = {Vec3f(0, 0, 1), Vec3f(1, 0, 1), Vec3f(0, 1, 1), Vec3f(0, 0, 2), Vec3f(1, 0, 2), Vec3f(0, 1, 2)};
  TriangleBlock<8> blk;
  const uint32_t ids[2] = {4, 9};
  fill_block<8>(blk, ids, 2, [&](uint32_t prim, int c) -> const Vec3f& { return v[(prim == 4 ? 0 : 3) + c]; });
  EXPECT_EQ(blk.count(), 2);
  for (int lane = 2; lane < 8; ++lane) EXPECT_EQ(blk.prim[lane], 4u);
}

}  // namespace
}  // namespace raylab
