// The wide BVH's walk (traverse_wide.h): watertightness with the vector
// test, the sorting network and key order, rays starting inside and on boxes,
// the fast node test against the scalar checks, padded slabs, the octant walk
// and scalars computed ahead giving the general walk's answers bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "accel/bvh/bvh_wide_node.h"
#include "accel/bvh/sort_network.h"
#include "accel/bvh/traverse_wide.h"
#include "accel/core/simd/simd.h"
#include "accel/registry.h"
#include "base/pcg.h"
#include "tests/accel_test_util.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

TEST(BvhWatertightness, ClosedSphereHasNoLeaksWithVectorisedTest) {
  for (const char* spec : {"bvh", "bvh:leaf=8", "bvh:leaf=32", "bvh:layout=bvh4", "bvh:layout=bvh2",
                           "bvh:builder=sbvh,sbudget=1", "bvh:layout=bvh16", "bvh:preset=sbvh"}) {
    EXPECT_EQ(test::closed_sphere_leaks(spec, Vec3f(0.3f, -0.2f, 0.1f), 8000), 0u) << spec;
    // Far from the origin the float spacing is 1/128 of the radius.
    EXPECT_EQ(test::closed_sphere_leaks(spec, Vec3f(1e5f, -2e4f, 3e4f), 8000), 0u) << spec << " far";
  }
}

TEST(BvhWatertightness, LeakCounterFindsAHole) {
  EXPECT_GT(test::closed_sphere_leaks("bvh", Vec3f::Zero(), 20000, 700), 0u);
}

TEST(BvhTraversal, SortingNetworkSortsDescending) {
  // 0-1 principle: a comparator network sorts every input iff it sorts all 0/1 inputs.
  // Every count: the networks differ by count (3, 4, and 5..8 padded to 8).
  for (int n = 1; n <= 8; ++n) {
    for (int bits = 0; bits < (1 << n); ++bits) {
      uint64_t keys[8] = {};
      for (int i = 0; i < n; ++i) keys[i] = ((bits >> i) & 1) ? 5 : 3;
      std::vector<uint64_t> want(keys, keys + n);
      std::sort(want.rbegin(), want.rend());
      ASSERT_EQ(sort8_keys_descending(keys, n), want[n - 1]) << "the least key is returned";
      for (int i = 0; i < n; ++i) ASSERT_EQ(keys[i], want[i]) << n << " keys, pattern " << bits;
    }
  }
  Pcg32 rng(1, 1);
  for (int k = 0; k < 2000; ++k) {
    const int n = 1 + static_cast<int>(rng.next() % 8);
    uint64_t keys[8] = {};
    for (int i = 0; i < n; ++i) keys[i] = child_key(rng.uniform() * 10.0f - 1.0f, rng.next());
    std::vector<uint64_t> want(keys, keys + n);
    std::sort(want.rbegin(), want.rend());
    ASSERT_EQ(sort8_keys_descending(keys, n), want[n - 1]);
    for (int i = 0; i < n; ++i) ASSERT_EQ(keys[i], want[i]);
  }
  // Keys order by distance, then leaves before inner nodes; refs survive.
  EXPECT_LT(child_key(1.0f, 5), child_key(2.0f, 3));
  EXPECT_LT(child_key(1.0f, wide_ref::leaf(7, 1)), child_key(1.0f, 3));
  EXPECT_EQ(key_ref(child_key(3.5f, wide_ref::leaf(9, 2))), wide_ref::leaf(9, 2));
  EXPECT_EQ(key_dist(child_key(3.5f, 12)), 3.5f);
  EXPECT_EQ(key_dist(child_key(-2.0f, 12)), 0.0f) << "negative distances order as 0";
}

#if defined(RAYLAB_SIMD_AVX512)
TEST(BvhTraversal, MinKeyIsTheLeastKeyInTheMask) {
  // The closest-hit walk takes its next node from min_key, beside the
  // sorting network: it must be the least key among the mask's lanes, for
  // every non-empty mask, whatever the other lanes hold (keys near 0 and
  // near the maximum included).
  Pcg32 rng(7, 3);
  for (int round = 0; round < 200; ++round) {
    alignas(64) uint64_t keys[8];
    for (int i = 0; i < 8; ++i) {
      const uint32_t kind = rng.next() % 4;
      keys[i] = kind == 0 ? rng.next() : kind == 1 ? ~uint64_t{0} - rng.next() % 4
                                                     : child_key(rng.uniform() * 10.0f, rng.next());
    }
    const __m512i v = _mm512_load_si512(keys);
    for (uint32_t mask = 1; mask < 256; ++mask) {
      uint64_t want = ~uint64_t{0};
      for (int i = 0; i < 8; ++i)
        if ((mask >> i) & 1) want = std::min(want, keys[i]);
      ASSERT_EQ(min_key(v, static_cast<__mmask8>(mask)), want) << mask;
    }
  }
}
#endif

TEST(BvhTraversal, SixteenWidePushEqualsTheScalarOrder) {
  // layout=bvh16's closest-hit step: the vector path (two key registers,
  // compress and expand, the 8-key network or an in-place sort above eight)
  // must push the same keys in the same order, return the same nearest
  // child and prefetch the same slots as the portable insertion sort, for
  // masks of every size, tied and zero distances, leaves and inner nodes.
  Pcg32 rng(11, 5);
  alignas(64) uint32_t refs[16];
  alignas(64) float dist[16];
  for (int round = 0; round < 3000; ++round) {
    for (int i = 0; i < 16; ++i) {
      refs[i] = rng.next() % 3 == 0 ? wide_ref::leaf(rng.next() % 1000, 1 + rng.next() % 3) : rng.next() % 100000;
      const uint32_t kind = rng.next() % 4;
      dist[i] = kind == 0 ? 0.0f : kind == 1 ? static_cast<float>(rng.next() % 4) : rng.uniform() * 100.0f;
    }
    for (int i = 1; i < 16; ++i)  // slots hold distinct references, as in a node
      for (int j = 0; j < i; ++j)
        if (refs[j] == refs[i]) refs[i] ^= 0x40000u;
    uint32_t mask = rng.next() & 0xFFFFu;
    if (round < 16) mask = (1u << (round + 1)) - 1u;  // 1..16 children, every count
    if ((mask & (mask - 1)) == 0) mask |= 0x8001u;    // the walk enters a single child directly
    const auto tnear = simd::vfloat<16>::load(dist);
    alignas(64) uint64_t got[64] = {}, want[64] = {};
    uint64_t* top_got = got + 3;  // on top of earlier entries
    uint64_t* top_want = want + 3;
    uint32_t pre_got = 0, pre_want = 0;
    const uint32_t next_got = push_by_distance<16>(refs, mask, tnear, top_got, [&](uint32_t i) { pre_got |= 1u << i; });
    const uint32_t next_want =
        push_by_distance<16, true>(refs, mask, tnear, top_want, [&](uint32_t i) { pre_want |= 1u << i; });
    ASSERT_EQ(next_got, next_want) << "mask " << mask;
    const int sp_got = static_cast<int>(top_got - got);
    ASSERT_EQ(sp_got, static_cast<int>(top_want - want)) << "mask " << mask;
    ASSERT_EQ(sp_got, 3 + simd::popcount(mask) - 1);
    for (int i = 3; i < sp_got; ++i) ASSERT_EQ(got[i], want[i]) << "mask " << mask << " entry " << i;
    EXPECT_EQ(pre_got & ~mask, 0u);
    EXPECT_EQ(pre_got, pre_want) << "mask " << mask;
    // The nearest is the least key.
    uint64_t least = ~uint64_t{0};
    for (uint32_t m = mask; m != 0; m &= m - 1) least = std::min(least, child_key(dist[simd::ctz(m)], refs[simd::ctz(m)]));
    ASSERT_EQ(next_got, key_ref(least));
  }
}

TEST(BvhTraversal, RaysStartingInsideAndOnBoxes) {
  // Axis-aligned slabs of triangles; rays start inside the scene, on box
  // faces and parallel to faces (zero direction components).
  TriangleMesh m;
  for (int z = 0; z < 6; ++z) {
    const uint32_t b = static_cast<uint32_t>(m.vertices.size());
    m.vertices.push_back(Vec3f(0, 0, static_cast<float>(z)));
    m.vertices.push_back(Vec3f(4, 0, static_cast<float>(z)));
    m.vertices.push_back(Vec3f(4, 4, static_cast<float>(z)));
    m.vertices.push_back(Vec3f(0, 4, static_cast<float>(z)));
    m.triangles.push_back({b, b + 1, b + 2});
    m.triangles.push_back({b, b + 2, b + 3});
  }
  for (const char* spec : {"bvh", "bvh:layout=bvh4", "bvh:layout=bvh2", "bvh:leaf=1", "bvh:layout=bvh16,leaf=1"}) {
    auto a = make_accelerator(spec);
    a->build(m);
    for (float z0 : {0.0f, 0.5f, 2.0f, 5.0f}) {
      const Hit up = a->intersect1(Ray(Vec3f(1, 3, z0), Vec3f(0, 0, 1), 0.25f));
      ASSERT_TRUE(up.valid() || z0 == 5.0f) << spec << " z0 " << z0;
      if (up.valid()) {
        EXPECT_EQ(up.t, std::ceil(z0 + 0.25f) - z0) << spec;
      }
      EXPECT_FALSE(a->intersect1(Ray(Vec3f(1, 3, z0 + 0.5f), Vec3f(1, 0, 0))).valid()) << "parallel to the slabs";
      EXPECT_EQ(a->occluded1(Ray(Vec3f(1, 3, 0.5f), Vec3f(0, 0, 1), 0, 0.4f)), false);
      EXPECT_EQ(a->occluded1(Ray(Vec3f(1, 3, 0.5f), Vec3f(0, 0, 1), 0, 0.5f)), true) << "tmax exactly at the hit";
    }
    // On the boundary face of the scene box, looking along it.
    EXPECT_TRUE(a->intersect1(Ray(Vec3f(4, 2, -1), Vec3f(0, 0, 1))).valid()) << spec << " on the box face";
    EXPECT_TRUE(a->intersect1(Ray(Vec3f(0, 0, -1), Vec3f(-0.0f, 0.0f, 1))).valid()) << spec << " corner, -0 dir";
  }
}

TEST(BvhTraversal, FastKernelTestIsTheScalarChecksTogether) {
  // ray_takes_fma_kernel (three vector comparisons) against its definition,
  // the scalar checks one by one, on every combination of awkward values in
  // one origin, one direction component, tmin and tmax (the others ordinary).
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  const float limit = 1000.0f;
  const std::vector<float> org_values = {0.0f, -0.0f, 1.0f, -999.0f, limit, -limit, std::nextafter(limit, inf),
                                         -2000.0f, FLT_MAX, inf, -inf, nan};
  const std::vector<float> dir_values = {0.0f, -0.0f, 1e-31f, std::nextafter(1e-30f, 0.0f), 1e-30f, -1e-30f, 0.5f,
                                         -3.0f, FLT_MAX, -FLT_MAX, inf, -inf, nan};
  const std::vector<float> t_values = {0.0f, -0.0f, -1e-30f, 0.25f, 1e30f, FLT_MAX, inf, -inf, nan};
  int fast = 0, slow = 0;
  for (int axis = 0; axis < 3; ++axis)
    for (float o : org_values)
      for (float d : dir_values)
        for (float t0 : t_values)
          for (float t1 : t_values) {
            Vec3f org(1.0f, -2.0f, 3.0f), dir(0.3f, -0.4f, 0.5f);
            org[axis] = o;
            dir[(axis + 1) % 3] = d;
            const Ray r(org, dir, t0, t1);
            // ray_is_valid (vector form with SSE4.1) against its rules (base/ray.h).
            const bool valid = org.allFinite() && dir.allFinite() && dir != Vec3f::Zero() && t0 <= t1 && t0 < inf;
            ASSERT_EQ(ray_is_valid(r), valid)
                << "org " << org.transpose() << " dir " << dir.transpose() << " t " << t0 << " " << t1;
            const bool expected =
                ray_is_valid(r) && !ray_is_axis_parallel(r) && r.tmin >= 0.0f && !origin_beyond(r, limit);
            ASSERT_EQ(ray_takes_fma_kernel(r, limit), expected)
                << "org " << org.transpose() << " dir " << dir.transpose() << " t " << t0 << " " << t1;
            (expected ? fast : slow)++;
          }
  EXPECT_GT(fast, 100);
  EXPECT_GT(slow, 100);
  for (const Vec3f& zero : {Vec3f(0, 0, 0), Vec3f(-0.0f, 0, -0.0f)}) {
    EXPECT_FALSE(ray_is_valid(Ray(Vec3f(1, 2, 3), zero)));
    EXPECT_FALSE(ray_takes_fma_kernel(Ray(Vec3f(1, 2, 3), zero), limit));
  }
  EXPECT_TRUE(ray_is_valid(Ray(Vec3f(1, 2, 3), Vec3f(0, 0, -1e-40f), -inf, -inf)));
  // The origin limit of a scene is at most FLT_MAX (so an infinite origin
  // never passes), 0 for a point.
  EXPECT_EQ(wide_fma_origin_limit(Aabb(Vec3f(-FLT_MAX, 0, 0), Vec3f(FLT_MAX, 1, 1))), FLT_MAX);
  EXPECT_EQ(wide_fma_origin_limit(Aabb(Vec3f(1, 1, 1), Vec3f(1, 1, 1))), 0.0f);
  EXPECT_EQ(wide_fma_origin_limit(Aabb(Vec3f(0, 0, 0), Vec3f(2, 1, 1))), 128.0f);
}

TEST(BvhTraversal, FarPaddingOnTheBitsIsNeverBelowTheScaling) {
  // The box test pads far distances by kSlabFarPadUlps on the bits, the
  // proof of conservativeness is for the scaling by kSlabFarScale: the padded
  // bits must reach at least the scaled value, for every float >= +0 (every
  // 97th bit pattern from +0 to +inf, every one near powers of two).
  auto bits = [](float x) {
    int32_t i;
    std::memcpy(&i, &x, 4);
    return i;
  };
  auto check = [&](int32_t b) {
    float t;
    std::memcpy(&t, &b, 4);
    ASSERT_LE(bits(t * kSlabFarScale), b + kSlabFarPadUlps) << t;
  };
  const int32_t inf_bits = 0x7F800000;
  for (int64_t b = 0; b <= inf_bits; b += 97) check(static_cast<int32_t>(b));
  for (int e = 1; e < 255; ++e)
    for (int32_t k = -16; k <= 16; ++k) check((e << 23) + k);
  check(inf_bits);
  // The vector form adds the same.
  using V = simd::vfloat<8>;
  alignas(64) float in[8] = {0.0f, 1.0f, 1.5f, 2.0f - 0x1p-23f, FLT_MAX, 1e-40f, 3.0f, 1e30f}, out[8];
  add_ulps(V::load(in), kSlabFarPadUlps).store(out);
  for (int i = 0; i < 8; ++i) EXPECT_EQ(bits(out[i]), bits(in[i]) + kSlabFarPadUlps) << in[i];
  EXPECT_EQ(cmp_lt_bits(V::load(in), V::load(out)), 0xFFu);
  EXPECT_EQ(cmp_lt_bits(V::load(out), V::load(in)), 0x00u);
}

TEST(BvhTraversal, PaddedSlabMaskIsTheLessOrEqualOfThePaddedFar) {
  // padded_slab_mask computes tnear <= tfar + kSlabFarPadUlps (on the bits) as tnear <
  // tfar + kSlabFarPadUlps + 1 (one comparison, no complement): the same
  // mask for every pair of entry distances (>= +0, as the kernels' are) and
  // far distances of every kind the FMA kernels produce (negative, -0, +0,
  // denormal, at and around the padding, FLT_MAX, +inf), at widths 4, 8, 16.
  auto from_bits = [](int32_t b) {
    float f;
    std::memcpy(&f, &b, 4);
    return f;
  };
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<float> fars = {-inf, -FLT_MAX, -1.0f, -1e-40f, -0.0f, 0.0f, 1e-45f, 1e-40f, 1.0f, FLT_MAX, inf};
  std::vector<float> nears = {0.0f, 1e-45f, 1e-40f, 1.0f, FLT_MAX, inf};
  for (float x : {0.0f, 1.0f, 3.5f, 1e30f, FLT_MAX})
    for (int32_t k = -8; k <= 8; ++k) {
      int32_t b;
      std::memcpy(&b, &x, 4);
      if (b + k < 0) continue;
      fars.push_back(from_bits(b + k));
      nears.push_back(from_bits(b + k));
    }
  auto check = [&](auto width) {
    constexpr int W = decltype(width)::value;
    using V = simd::vfloat<W>;
    alignas(64) float n[W], f[W];
    size_t lane = 0, tested = 0;
    for (float tn : nears)
      for (float tf : fars) {
        n[lane] = tn, f[lane] = tf;
        if (++lane < W) continue;
        lane = 0;
        // The definition, lane by lane: tnear's bits <= tfar's bits + kSlabFarPadUlps.
        uint32_t expect = 0;
        for (int i = 0; i < W; ++i) {
          int32_t nb, fb;
          std::memcpy(&nb, &n[i], 4);
          std::memcpy(&fb, &f[i], 4);
          expect |= static_cast<uint32_t>(int64_t{nb} <= int64_t{fb} + kSlabFarPadUlps) << i;
        }
        ASSERT_EQ(padded_slab_mask(V::load(n), V::load(f)), expect);
        tested += W;
      }
    EXPECT_GT(tested, 4000u);
  };
  check(std::integral_constant<int, 4>{});
  check(std::integral_constant<int, 8>{});
#if defined(RAYLAB_SIMD_AVX512)
  check(std::integral_constant<int, 16>{});
#endif
}

TEST(BvhOctantWalk, CoherentBatchesGiveTheGeneralWalksAnswersBitForBit) {
  // A batch whose rays mostly share a direction octant takes the walk
  // specialised to each ray's octant (traverse_wide.h); the same rays
  // interleaved so the octant changes every ray, or traced with counters,
  // take the general walk. Every hit field must be equal, occlusion too.
  // Each octant's group holds rays that leave the fast kernel (axis-parallel,
  // tmin < 0, invalid, an origin far beyond the scene) and short ones.
  const test::NamedMesh s = test::soup(3000, 29);
  const Aabb box = s.mesh.bounds();
  const Vec3f centre = box.center(), half = 0.5f * (box.hi - box.lo);
  Pcg32 rng(21, 3);
  constexpr int kPerOctant = 96;
  std::vector<Ray> grouped;
  for (int oct = 0; oct < 8; ++oct) {
    const Vec3f sign(oct & 1 ? -1.0f : 1.0f, oct & 2 ? -1.0f : 1.0f, oct & 4 ? -1.0f : 1.0f);
    for (int i = 0; i < kPerOctant; ++i) {
      const Vec3f u(2.0f * rng.uniform() - 1.0f, 2.0f * rng.uniform() - 1.0f, 2.0f * rng.uniform() - 1.0f);
      Ray r(centre + 1.2f * half.cwiseProduct(u), test::random_direction(rng).cwiseAbs().cwiseProduct(sign));
      if (i == 7) r.dir.x() = sign.x() * 0.0f;  // axis-parallel, in its octant (+0 or -0)
      if (i == 11) r.tmin = -1.0f;
      if (i == 13) r.dir = Vec3f(0, 0, 0);  // invalid
      if (i == 17) r.org = centre + 1e6f * sign;
      if (i % 5 == 3) r.tmax = 0.3f * half.norm();
      ASSERT_EQ(ray_octant(r), i == 13 ? 0 : oct);
      grouped.push_back(r);
    }
  }
  std::vector<Ray> interleaved;
  for (int i = 0; i < kPerOctant; ++i)
    for (int oct = 0; oct < 8; ++oct) interleaved.push_back(grouped[oct * kPerOctant + i]);
  ASSERT_TRUE(batch_is_octant_coherent(grouped));
  ASSERT_FALSE(batch_is_octant_coherent(interleaved));
  const size_t n = grouped.size();
  for (const char* spec : {"bvh", "bvh:layout=bvh4", "bvh:layout=bvh8", "bvh:layout=bvh16", "bvh:packet=16",
                           "bvh:builder=sbvh,opt=reinsert"}) {
    auto accel = make_accelerator(spec);
    accel->build(s.mesh);
    std::vector<Hit> octant(n), general(n), counted(n);
    std::vector<uint8_t> occ_octant(n), occ_general(n), occ_counted(n);
    TraversalStats stats, occ_stats;
    accel->intersect(grouped, octant);
    accel->intersect(grouped, counted, &stats);
    accel->occluded(grouped, occ_octant);
    accel->occluded(grouped, occ_counted, &occ_stats);
    {
      std::vector<Hit> h(n);
      std::vector<uint8_t> o(n);
      accel->intersect(interleaved, h);
      accel->occluded(interleaved, o);
      for (int i = 0; i < kPerOctant; ++i)
        for (int oct = 0; oct < 8; ++oct) {
          general[oct * kPerOctant + i] = h[i * 8 + oct];
          occ_general[oct * kPerOctant + i] = o[i * 8 + oct];
        }
    }
    size_t hits = 0, occluded = 0;
    for (size_t i = 0; i < n; ++i) {
      hits += octant[i].valid();
      occluded += occ_octant[i];
      ASSERT_EQ(std::memcmp(&octant[i], &general[i], sizeof(Hit)), 0)
          << spec << " ray " << i << ": octant walk prim " << octant[i].prim << " t " << octant[i].t
          << ", general prim " << general[i].prim << " t " << general[i].t;
      ASSERT_EQ(std::memcmp(&octant[i], &counted[i], sizeof(Hit)), 0) << spec << " ray " << i << " (counted)";
      ASSERT_EQ(occ_octant[i], occ_counted[i]) << spec << " ray " << i << " (counted)";
      ASSERT_EQ(occ_octant[i], occ_general[i]) << spec << " ray " << i;
      ASSERT_EQ(occ_octant[i] != 0, octant[i].valid()) << spec << " ray " << i;
    }
    EXPECT_GT(hits, n / 4) << spec;
    EXPECT_EQ(occluded, hits) << spec;
  }
}

TEST(BvhAhead, ScalarsComputedAheadGiveTheSameAnswersBitForBit) {
  // Uncounted coherent batches compute each ray's box-test scalars while the
  // ray before it walks (trace_rays_ahead); counted batches, and incoherent
  // ones, compute them when the ray starts. Every hit field and every
  // occlusion answer must be equal, in coherent and incoherent batches, with
  // rays that leave the fast kernel (axis-parallel, tmin < 0, invalid, an
  // origin far beyond the scene) between ordinary ones, and as the last ray.
  const test::NamedMesh s = test::soup(2000, 31);
  const Aabb box = s.mesh.bounds();
  const Vec3f centre = box.center(), half = 0.5f * (box.hi - box.lo);
  Pcg32 rng(5, 9);
  std::vector<Ray> coherent, incoherent;
  const Vec3f eye = centre - 2.5f * half;
  for (int i = 0; i < 600; ++i) {
    const Vec3f target = centre + 0.9f * half.cwiseProduct(Vec3f(2.0f * rng.uniform() - 1.0f, 2.0f * rng.uniform() - 1.0f,
                                                                 2.0f * rng.uniform() - 1.0f));
    coherent.emplace_back(eye, (target - eye).normalized());
    const Vec3f u(2.0f * rng.uniform() - 1.0f, 2.0f * rng.uniform() - 1.0f, 2.0f * rng.uniform() - 1.0f);
    incoherent.emplace_back(centre + 1.2f * half.cwiseProduct(u), test::random_direction(rng));
  }
  for (std::vector<Ray>* rays : {&coherent, &incoherent}) {
    std::vector<Ray>& r = *rays;
    r[10].dir.y() = 0.0f;        // axis-parallel
    r[20].tmin = -1.0f;          // tmin < 0
    r[30].dir = Vec3f(0, 0, 0);  // invalid
    r[40].org = centre + Vec3f(1e7f, 0, 0);
    r[41].tmax = 0.2f * half.norm();
    r.back().dir = Vec3f(0, 0, 0);
  }
  ASSERT_TRUE(batch_is_octant_coherent(coherent));
  ASSERT_FALSE(batch_is_octant_coherent(incoherent));
  for (const char* spec : {"bvh", "bvh:layout=bvh4", "bvh:layout=bvh16", "bvh:tri=mt", "bvh:preset=sbvh"}) {
    auto ahead = make_accelerator(spec);
    ahead->build(s.mesh);
    for (const std::vector<Ray>* rays : {&coherent, &incoherent}) {
      const size_t n = rays->size();
      std::vector<Hit> a(n), b(n);
      std::vector<uint8_t> oa(n), ob(n);
      TraversalStats sb, sob;
      ahead->intersect(*rays, a);
      ahead->intersect(*rays, b, &sb);
      ahead->occluded(*rays, oa);
      ahead->occluded(*rays, ob, &sob);
      size_t hits = 0;
      for (size_t i = 0; i < n; ++i) {
        hits += a[i].valid();
        ASSERT_EQ(std::memcmp(&a[i], &b[i], sizeof(Hit)), 0)
            << spec << " ray " << i << ": ahead prim " << a[i].prim << " t " << a[i].t << ", plain prim " << b[i].prim;
        ASSERT_EQ(oa[i], ob[i]) << spec << " ray " << i;
      }
      EXPECT_GT(hits, n / 4) << spec;
      EXPECT_FALSE(a[30].valid());
      EXPECT_FALSE(a.back().valid());
    }
  }
  EXPECT_THROW(make_accelerator("bvh:ahead=0"), SpecError);
}

}  // namespace
}  // namespace raylab
