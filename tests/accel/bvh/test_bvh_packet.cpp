// Packet traversal (traverse_packet.h): the same answers as single rays bit
// for bit, the frustum culling only what every ray culls, bad parameters.
#include <gtest/gtest.h>

#include <algorithm>
#include <cfloat>
#include <cstring>
#include <vector>

#include "accel/bvh/bvh_wide_node.h"
#include "accel/bvh/traverse_packet.h"
#include "accel/core/simd/simd.h"
#include "accel/registry.h"
#include "base/pcg.h"
#include "tests/accel/bvh/bvh_test_util.h"
#include "tests/accel_test_util.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

using test::ReferenceScene;
using test::reference_scenes;

TEST(BvhPacket, SameAnswersAsSingleRaysBitForBit) {
  // Coherent camera rays (pixel order, a partial last packet) with invalid,
  // axis-parallel, tmin < 0 and short rays mixed in, through bvh:packet=16
  // and the single-ray kernel: every field equal, and occlusion agrees. Coincident copies of a triangle
  // make exact ties, which both must give to the lowest primitive id.
  for (const ReferenceScene& ref : reference_scenes()) {
    test::NamedMesh s = ref.scene;
    const size_t n = s.mesh.triangles.size();
    for (size_t i = 0; i < std::min<size_t>(n, 200); ++i) s.mesh.triangles.push_back(s.mesh.triangles[i]);
    std::vector<Ray> rays = test::camera_rays(s.mesh, 47, 40);
    for (size_t i = 5; i < rays.size(); i += 97) rays[i].dir = Vec3f(0, 0, 0);   // invalid
    for (size_t i = 9; i < rays.size(); i += 89) rays[i].dir.x() = 0.0f;          // axis-parallel component
    for (size_t i = 13; i < rays.size(); i += 83) rays[i].tmin = -1.0f;           // tmin < 0
    for (size_t i = 21; i < rays.size(); i += 79) rays[i].tmax = 0.5f;            // short
    // Packets whose rays differ in the watertight test's dominant axis: 16
    // rays from one point near the mesh centre, directions spread around a
    // diagonal within one octant.
    // (In front, so that they fill whole 16-ray chunks.)
    Pcg32 rng(9, 4);
    std::vector<Ray> fan;
    for (int p = 0; p < 40; ++p) {
      const Vec3f sign(p & 1 ? -1.0f : 1.0f, p & 2 ? -1.0f : 1.0f, p & 4 ? -1.0f : 1.0f);
      const Vec3f org = s.mesh.bounds().center() + 0.1f * test::random_direction(rng);
      for (int i = 0; i < 16; ++i) {
        const Vec3f d(0.6f + 0.8f * rng.uniform(), 0.6f + 0.8f * rng.uniform(), 0.6f + 0.8f * rng.uniform());
        fan.emplace_back(org, d.cwiseProduct(sign));
      }
    }
    rays.insert(rays.begin(), fan.begin(), fan.end());
    const std::pair<const char*, const char*> pairs[] = {
        {"bvh", "bvh:packet=16"},
        {"bvh:layout=bvh8", "bvh:packet=16,layout=bvh8"},
        {"bvh:layout=bvh16", "bvh:packet=16,layout=bvh16"},
        {"bvh:leaf=4,opt=reinsert", "bvh:packet=16,leaf=4,opt=reinsert"},
        {"bvh:leaf=48", "bvh:packet=16,leaf=48"}};
    for (const auto& [single_spec, spec] : pairs) {
      auto single = make_accelerator(single_spec);
      auto packet = make_accelerator(spec);
      auto brute = make_accelerator("brute");
      single->build(s.mesh);
      packet->build(s.mesh);
      brute->build(s.mesh);
      std::vector<Hit> a(rays.size()), b(rays.size()), c(rays.size());
      single->intersect(rays, a);
      packet->intersect(rays, b);
      brute->intersect(rays, c);
      size_t hits = 0, bad = 0;
      for (size_t i = 0; i < rays.size(); ++i) {
        hits += a[i].valid();
        const bool same = a[i].prim == b[i].prim && std::memcmp(&a[i], &b[i], sizeof(Hit)) == 0;
        if (!same && bad++ < 3)
          ADD_FAILURE() << spec << " " << s.name << " ray " << i << ": packet prim " << b[i].prim << " t " << b[i].t
                        << ", single prim " << a[i].prim << " t " << a[i].t;
        EXPECT_EQ(a[i].prim, c[i].prim) << spec << " " << s.name << " ray " << i << " vs brute force";
      }
      EXPECT_EQ(bad, 0u) << spec << " on " << s.name;
      EXPECT_GT(hits, rays.size() / 10) << s.name;
      // Occlusion through packets: occluded exactly when the closest hit exists.
      std::vector<uint8_t> occ(rays.size());
      packet->occluded(rays, occ);
      size_t occ_bad = 0;
      for (size_t i = 0; i < rays.size(); ++i) occ_bad += (occ[i] != 0) != a[i].valid();
      EXPECT_EQ(occ_bad, 0u) << spec << " occlusion on " << s.name;
    }
  }
}

template <int N>
void check_packet_frustum() {
  // Random 16-ray packets (one origin, directions spread over a cone, some
  // rays short) against random N-box nodes (N = 8, 16): the frustum test keeps every box
  // some ray's own single-ray test enters, with an entry distance no larger
  // than that ray's; and the per-lane leaf test is each ray's own test, bit
  // for bit. The frustum must also cull: a test that keeps every box would
  // pass the first check vacuously.
  Pcg32 rng(2024, 5);
  auto uniform = [&](float lo, float hi) { return lo + (hi - lo) * rng.uniform(); };
  size_t packets = 0, frustum_culled = 0, kept_by_rays = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const float spread = trial % 3 == 0 ? 0.3f : 0.02f;
    const Vec3f org = Vec3f(uniform(-2, 2), uniform(-2, 2), uniform(-2, 2)) + (trial % 7 == 0 ? Vec3f(300, 0, 0) : Vec3f::Zero());
    const Vec3f base = test::random_direction(rng);
    std::vector<Ray> rays(kPacketSize);
    for (Ray& r : rays) {
      r = Ray(org, (base + spread * test::random_direction(rng)).normalized());
      if (rng.uniform() < 0.2f) r.tmax = uniform(0.1f, 4.0f);
      if (rng.uniform() < 0.1f) r.tmin = uniform(0.0f, 0.5f);
    }
    const PacketInput in(rays);
    if (!in.coherent(FLT_MAX)) continue;
    ++packets;
    PacketRays pr;
    PacketFrustum<N> fr;
    PacketHits ph;
    make_packet(in, pr, fr, ph);
    WideNode<N> node{};
    for (int c = 0; c < N; ++c) {
      // Boxes near the packet's path (so that rays hit some), corner a.
      const Vec3f a = org + uniform(-0.5f, 5.0f) * base + Vec3f(uniform(-1, 0.5f), uniform(-1, 0.5f), uniform(-1, 0.5f));
      Vec3f e(uniform(0, 1.5f), uniform(0, 1.5f), uniform(0, 1.5f));
      if (c == 5) e.y() = 0.0f;  // a flat box
      for (int ax = 0; ax < 3; ++ax) node.bounds[2 * ax][c] = a[ax], node.bounds[2 * ax + 1][c] = a[ax] + e[ax];
      node.child[c] = c;
    }
    using VN = simd::vfloat<N>;
    VN ftnear;
    const uint32_t fmask = frustum_children(node, fr, VN::broadcast(ph.greatest_t()), ftnear);
    alignas(64) float fnear[N];
    ftnear.store(fnear);
    frustum_culled += N - simd::popcount(fmask);
    uint32_t lanes_of_slot[N] = {};
    for (int c = 0; c < N; ++c) lanes_of_slot[c] = rays_entering(node, c, pr, simd::vfloat<kPacketSize>::load(ph.t));
    for (int i = 0; i < kPacketSize; ++i) {
      WideNodeRay<N> nr;
      init_node_ray(nr, rays[i], false);
      VN tnear;
      const uint32_t m = intersect_children<N, false>(node, nr, VN::broadcast(rays[i].tmin), VN::broadcast(rays[i].tmax), tnear);
      alignas(64) float near[N];
      tnear.store(near);
      kept_by_rays += simd::popcount(m);
      EXPECT_EQ(m & ~fmask, 0u) << "trial " << trial << " ray " << i;
      for (int c = 0; c < N; ++c) {
        if ((m >> c) & 1u) {
          EXPECT_LE(fnear[c], near[c]) << "trial " << trial << " ray " << i << " slot " << c;
        }
        EXPECT_EQ((lanes_of_slot[c] >> i) & 1u, (m >> c) & 1u) << "trial " << trial << " ray " << i << " slot " << c;
      }
    }
  }
  EXPECT_GT(packets, 1000u);
  EXPECT_GT(kept_by_rays, packets);        // boxes are hit
  EXPECT_GT(frustum_culled, 2 * packets);  // and culled
}

TEST(BvhPacket, FrustumCullsOnlyWhatEveryRayCulls) {
  check_packet_frustum<8>();   // layout=bvh8
  check_packet_frustum<16>();  // layout=bvh16
}

TEST(BvhPacket, RejectsBadParameters) {
  EXPECT_THROW(make_accelerator("bvh:packet=8"), SpecError);
  EXPECT_THROW(make_accelerator("bvh:packet=16,layout=bvh4"), SpecError);
  EXPECT_NO_THROW(make_accelerator("bvh:packet=16,layout=bvh16"));
}

}  // namespace
}  // namespace raylab
