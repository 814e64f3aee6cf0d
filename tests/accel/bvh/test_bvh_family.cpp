// The BVH family (accel/bvh): every builder x layout agrees with brute force;
// the SAH-optimal wide collapse keeps every triangle exactly once under
// enclosing boxes and beats a greedy collapse; SBVH references cover their
// triangles; LBVH copes with coincident centroids; reinsertion lowers the SAH
// cost; the vectorised watertight test equals the scalar one bit for bit and
// leaks nothing on closed spheres; the sorting network sorts.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <numeric>
#include <tuple>
#include <type_traits>

#include <fmt/format.h>
#include <tbb/global_control.h>

#include "accel/bvh/build_binned_sah.h"
#include "accel/bvh/build_lbvh.h"
#include "accel/bvh/build_sbvh.h"
#include "accel/bvh/build_sweep_sah.h"
#include "accel/bvh/bvh_accel.h"
#include "accel/bvh/bvh_wide_node.h"
#include "accel/bvh/collapse_wide.h"
#include "accel/bvh/optimize_reinsertion.h"
#include "accel/bvh/sah_binning.h"
#include "accel/bvh/small_sweep.h"
#include "accel/bvh/sort_network.h"
#include "accel/bvh/traverse_packet.h"
#include "accel/core/simd/triangle_block.h"
#include "accel/registry.h"
#include "tests/accel_test_util.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

// ---------------------------------------------------------------------------
// Helpers

struct Prims {
  std::vector<Aabb> boxes;
  std::vector<Vec3f> centroids;
};

Prims prims_of(const TriangleMesh& m) {
  Prims p;
  for (size_t i = 0; i < m.num_triangles(); ++i) {
    p.boxes.push_back(m.triangle_bounds(i));
    p.centroids.push_back(p.boxes.back().center());
  }
  return p;
}

BinaryBvh build_with(const std::string& builder, const TriangleMesh& mesh, int leaf_threshold = 1) {
  const Prims p = prims_of(mesh);
  BuildOptions bo;
  bo.leaf_threshold = leaf_threshold;
  if (builder == "binned") return build_binned_sah(p.boxes, p.centroids, bo);
  if (builder == "sweep") return build_sweep_sah(p.boxes, p.centroids, bo);
  if (builder == "lbvh") return build_lbvh(p.boxes, p.centroids);
  if (builder == "reinsert") return optimize_reinsertion(build_binned_sah(p.boxes, p.centroids, bo), {});
  SbvhOptions so;
  so.base = bo;
  so.alpha = 0.0f;
  so.split_budget = 1.0f;
  return build_sbvh(p.boxes, p.centroids, TriangleSplitter(mesh), so);
}

bool is_leaf(const Bvh2Node& n) { return n.count != 0 || n.index == 0; }

// Every reference of a binary tree, and a check that children lie inside
// their parents' boxes.
void check_binary_tree(const BinaryBvh& t, const TriangleMesh& mesh, bool duplicates_allowed) {
  std::vector<int> seen(mesh.num_triangles(), 0);
  std::vector<uint32_t> stack{0};
  size_t visited = 0;
  while (!stack.empty()) {
    const uint32_t i = stack.back();
    stack.pop_back();
    ++visited;
    const Bvh2Node& n = t.nodes[i];
    const Aabb box = n.bounds();
    if (is_leaf(n)) {
      for (uint32_t k = n.index; k < n.index + n.count; ++k) {
        const uint32_t prim = t.prim_ids[k];
        ASSERT_LT(prim, mesh.num_triangles());
        seen[prim]++;
        if (!duplicates_allowed) {
          EXPECT_TRUE(box.contains(mesh.triangle_bounds(prim))) << "leaf " << i;
        }
      }
      continue;
    }
    ASSERT_LT(n.index + 1, t.nodes.size());
    ASSERT_GT(n.index, i) << "children must follow their parent";
    for (uint32_t c : {n.index, n.index + 1}) {
      EXPECT_TRUE(box.contains(t.nodes[c].bounds())) << "node " << i << " child " << c;
      stack.push_back(c);
    }
  }
  EXPECT_EQ(visited, t.nodes.size()) << "every node is reachable exactly once";
  for (size_t p = 0; p < seen.size(); ++p) {
    if (duplicates_allowed) EXPECT_GE(seen[p], 1) << "triangle " << p;
    else EXPECT_EQ(seen[p], 1) << "triangle " << p;
  }
}

// ---------------------------------------------------------------------------
// Every builder x layout against brute force

std::vector<std::string> family_specs() {
  std::vector<std::string> specs;
  for (const char* b : {"binned", "sweep", "sbvh", "lbvh"})
    for (const char* l : {"bvh2", "bvh4", "bvh8"}) specs.push_back(fmt::format("bvh:builder={},layout={}", b, l));
  for (const char* extra :
       {"bvh:opt=reinsert,layout=bvh2", "bvh:opt=reinsert,layout=bvh8", "bvh:opt=reinsert,builder=sbvh,layout=bvh4",
        "bvh:leaf=8", "bvh:leaf=48", "bvh:leaf=4,opt=reinsert", "bvh:builder=sbvh,sbudget=2",
        "bvh:builder=sbvh,smin=64", "bvh:layout=bvh2,leaf=1", "bvh:ct=4,ci=0.5", "bvh:bins=4",
        "bvh:layout=bvh16", "bvh:layout=bvh16,opt=reinsert", "bvh:layout=bvh16,builder=sbvh,leaf=4",
        "bvh:layout=bvh16,builder=lbvh", "bvh:layout=bvh8,simd=0", "bvh:layout=bvh16,simd=0",
        "bvh:preset=fast", "bvh:preset=quality", "bvh:preset=sbvh", "bvh:preset=sbvh,layout=bvh16"})
    specs.push_back(extra);
  return specs;
}

struct RaySet {
  std::string name;
  std::vector<Ray> rays;
};

struct Reference {
  test::NamedMesh scene;
  std::vector<RaySet> sets;
  std::vector<test::BruteReference> brute;  // per set
};

const std::vector<Reference>& references() {
  static const std::vector<Reference> refs = [] {
    std::vector<Reference> out;
    std::vector<test::NamedMesh> scenes;
    scenes.push_back(test::soup(2500, 17));
    scenes.push_back(test::soup(400, 5, 6.0f));  // long, heavily overlapping triangles
    scenes.push_back({"cornell", cornell_box_mesh()});
    scenes.push_back({"sphere", make_uv_sphere(40, 20, Vec3f(0.5f, 0.5f, 0.5f), 0.4f)});
    for (test::NamedMesh& s : scenes) {
      Reference r;
      std::vector<Ray> primary = test::camera_rays(s.mesh, 40, 40);
      const test::BruteReference first = test::brute_reference(s.mesh, primary);
      std::vector<Ray> diffuse = test::surface_rays(s.mesh, primary, first.hits, 3);
      r.sets = {{"primary", std::move(primary)}, {"random", test::segment_rays(s.mesh, 1500, 7)},
                {"diffuse", std::move(diffuse)}};
      for (const RaySet& set : r.sets) r.brute.push_back(test::brute_reference(s.mesh, set.rays));
      r.scene = std::move(s);
      out.push_back(std::move(r));
    }
    return out;
  }();
  return refs;
}

class BvhFamily : public ::testing::TestWithParam<std::string> {};

TEST_P(BvhFamily, AgreesWithBruteForce) {
  for (const Reference& ref : references()) {
    auto accel = make_accelerator(GetParam());
    const BuildStats st = accel->build(ref.scene.mesh);
    EXPECT_TRUE(st.nodes > 0 || st.leaves == 1) << "a single leaf needs no node";
    EXPECT_GT(st.leaves, 0u);
    EXPECT_GT(st.bytes, 0u);
    EXPECT_TRUE(std::isfinite(st.sah_cost) && st.sah_cost > 0.0) << GetParam();
    size_t hits = 0;
    for (size_t s = 0; s < ref.sets.size(); ++s) {
      // Overlapping coplanar triangles (the size-6 soup, clamped to the unit
      // cube's faces) tie up to rounding of the coordinates: 1e-6.
      const std::string what = GetParam() + " " + ref.scene.name + " " + ref.sets[s].name;
      const test::Disagreement d = test::compare_with_brute(*accel, ref.brute[s], ref.sets[s].rays, what, 1e-6f);
      EXPECT_EQ(d.closest + d.barycentric + d.occlusion, 0u) << what;
      hits += d.reference_hits;
    }
    EXPECT_GT(hits, 300u) << "the ray sets must hit something on " << ref.scene.name;
  }
}

TEST_P(BvhFamily, InstrumentedKernelCountsAndAgrees) {
  const Reference& ref = references()[0];
  auto accel = make_accelerator(GetParam());
  accel->build(ref.scene.mesh);
  const auto& rays = ref.sets[1].rays;
  std::vector<Hit> plain(rays.size()), counted(rays.size());
  std::vector<uint8_t> occ_plain(rays.size()), occ_counted(rays.size());
  TraversalStats st, st_occ;
  accel->intersect(rays, plain);
  accel->intersect(rays, counted, &st);
  accel->occluded(rays, occ_plain);
  accel->occluded(rays, occ_counted, &st_occ);
  for (size_t i = 0; i < rays.size(); ++i) {
    ASSERT_EQ(plain[i].prim, counted[i].prim);
    ASSERT_EQ(occ_plain[i], occ_counted[i]);
  }
  EXPECT_EQ(st.rays, rays.size());
  EXPECT_GT(st.nodes_visited, rays.size());
  EXPECT_GT(st.triangle_tests, 0u);
  // Any hit stops early: never more work than closest hit on the same rays.
  EXPECT_LE(st_occ.triangle_tests, st.triangle_tests);
}

INSTANTIATE_TEST_SUITE_P(Combinations, BvhFamily, ::testing::ValuesIn(family_specs()), [](const auto& info) {
  std::string n = info.param.substr(4);
  for (char& c : n)
    if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
  return n;
});

TEST(BvhFamily, ReportsSimdIsaAndStatistics) {
  const test::NamedMesh s = test::soup(1000, 3);
  for (const char* spec : {"bvh", "bvh:layout=bvh4", "bvh:layout=bvh2"}) {
    auto a = make_accelerator(spec);
    const BuildStats st = a->build(s.mesh);
    EXPECT_GT(st.build_ms, 0.0);
    EXPECT_GT(st.max_depth, 0);
    EXPECT_GT(st.avg_depth, 0.0);
    EXPECT_TRUE(st.extra.count("sah_tree")) << spec;
    EXPECT_TRUE(st.extra.count("ms_tree")) << spec;
    if (std::string(spec) != "bvh:layout=bvh2") {
      ASSERT_TRUE(st.extra.count("simd_bits")) << spec;
      EXPECT_GE(st.extra.at("simd_bits"), 32.0);
    }
  }
  EXPECT_FALSE(bvh_kernel_isa().empty());
  EXPECT_NE(bvh_kernel_isa(), "unknown");
}

TEST(BvhFamily, RejectsBadParameters) {
  for (const char* spec : {"bvh:leaf=0", "bvh:leaf=-1", "bvh:leaf=many", "bvh:builder=octree", "bvh:layout=bvh3",
                           "bvh:tri=mt,simd=0", "bvh:tri=mt,packet=16", "bvh:bins=1", "bvh:sbudget=9", "bvh:ct=0",
                           "bvh:opt=anneal", "bvh:leaf=500", "bvh:leaf=121", "bvh:smin=-2", "bvh:nodes=3",
                           "bvh:layout=bvh32", "bvh:preset=best", "bvh:preset=", "bvh:bound=sphere,layout=bvh8"})
    EXPECT_THROW(make_accelerator(spec), SpecError) << spec;
  EXPECT_NO_THROW(make_accelerator("bvh:layout=bvh2,tri=mt"));
  EXPECT_NO_THROW(make_accelerator("bvh:tri=mt"));
  EXPECT_NO_THROW(make_accelerator("bvh:tri=mt,layout=bvh4"));
  EXPECT_NO_THROW(make_accelerator("bvh:leaf=auto"));
  EXPECT_NO_THROW(make_accelerator("bvh:leaf=120"));
  EXPECT_NO_THROW(make_accelerator("bvh:layout=bvh2,leaf=255"));
}

// tri=mt (the non-watertight option, measuring what watertightness costs) tests the
// wide layouts' blocks with the vectorised Moller-Trumbore test, which
// computes what the scalar intersect_moller_trumbore computes lane by lane
// (its pre-division range test is conservative): the same closest hits as
// brute force with that test, bit for bit, and the same occlusion answers.
TEST(BvhFamily, MollerTrumboreBlocksMatchBruteForceWithTheSameTest) {
  std::vector<test::NamedMesh> scenes;
  scenes.push_back(test::soup(2000, 53));
  scenes.push_back(test::soup(400, 5, 6.0f));  // long, heavily overlapping triangles
  for (const test::NamedMesh& s : scenes) {
    std::vector<Ray> rays = test::mesh_test_rays(s.mesh, 3000, 61);
    // Rays through vertices and edge midpoints, where the test's rounding decides.
    for (size_t t = 0; t < std::min<size_t>(s.mesh.num_triangles(), 300); ++t) {
      const Vec3f target = t % 2 ? s.mesh.vertex(t, 0) : 0.5f * (s.mesh.vertex(t, 1) + s.mesh.vertex(t, 2));
      const Vec3f org = target + Vec3f(0.3f, 2.0f, -0.7f);
      rays.push_back(Ray(org, (target - org).normalized()));
    }
    auto brute = make_accelerator("brute:tri=mt");
    brute->build(s.mesh);
    for (const char* spec : {"bvh:tri=mt", "bvh:tri=mt,layout=bvh4", "bvh:tri=mt,layout=bvh16",
                             "bvh:tri=mt,opt=reinsert"}) {
      auto accel = make_accelerator(spec);
      accel->build(s.mesh);
      size_t bad = 0, bad_occ = 0, hits = 0;
      for (const Ray& r : rays) {
        const Hit a = accel->intersect1(r), b = brute->intersect1(r);
        const bool differs = a.valid() != b.valid() ||
                             (a.valid() && (a.t != b.t || a.u != b.u || a.v != b.v || a.prim != b.prim));
        if (differs && bad == 0)
          ADD_FAILURE() << fmt::format("{}: first difference: t {} / {}, u {} / {}, v {} / {}, prim {} / {}", spec,
                                       a.t, b.t, a.u, b.u, a.v, b.v, a.prim, b.prim);
        bad += differs;
        bad_occ += accel->occluded1(r) != b.valid();
        hits += b.valid();
      }
      EXPECT_GT(hits, rays.size() / 4) << spec;
      EXPECT_EQ(bad, 0u) << spec << " " << s.name;
      EXPECT_EQ(bad_occ, 0u) << spec << " " << s.name;
    }
  }
}

TEST(BvhFamily, ScalarTestsGiveIdenticalHitsAndCounts) {
  // simd=0 walks the same wide tree with scalar box and triangle tests: the
  // same hits bit for bit, the same occlusion and the same counted work, for
  // both wide layouts and for the rays that take the exact box test
  // (axis-parallel, tmin < 0) as well as the FMA one. The registry-wide test
  // (Registry.ScalarVariantGivesIdenticalHits) covers the default layout.
  const test::NamedMesh s = test::soup(2500, 29);
  std::vector<Ray> rays = test::camera_rays(s.mesh, 40, 30);
  Pcg32 rng(3, 11);
  const Aabb box = s.mesh.bounds();
  for (int i = 0; i < 1500; ++i) {
    const Vec3f u(rng.uniform(), rng.uniform(), rng.uniform());
    rays.emplace_back(Vec3f(box.lo + u.cwiseProduct(box.hi - box.lo)), test::random_direction(rng));
  }
  for (size_t i = 3; i < rays.size(); i += 37) rays[i].dir.y() = 0.0f;  // axis-parallel component
  for (size_t i = 7; i < rays.size(); i += 41) rays[i].tmin = -1.0f;     // tmin < 0
  for (const char* layout : {"bvh8", "bvh4", "bvh16"}) {
    auto simd = make_accelerator(fmt::format("bvh:layout={}", layout));
    auto scalar = make_accelerator(fmt::format("bvh:layout={},simd=0", layout));
    simd->build(s.mesh);
    scalar->build(s.mesh);
    std::vector<Hit> a(rays.size()), b(rays.size());
    std::vector<uint8_t> oa(rays.size()), ob(rays.size());
    TraversalStats sa, sb, soa, sob;
    simd->intersect(rays, a, &sa);
    scalar->intersect(rays, b, &sb);
    simd->occluded(rays, oa, &soa);
    scalar->occluded(rays, ob, &sob);
    size_t hits = 0, bad = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      hits += a[i].valid();
      bad += std::memcmp(&a[i], &b[i], sizeof(Hit)) != 0 || oa[i] != ob[i];
    }
    EXPECT_EQ(bad, 0u) << layout;
    EXPECT_GT(hits, rays.size() / 4) << layout;
    EXPECT_EQ(sa.nodes_visited, sb.nodes_visited) << layout;
    EXPECT_EQ(sa.triangle_tests, sb.triangle_tests) << layout;
    EXPECT_EQ(soa.nodes_visited, sob.nodes_visited) << layout;
    EXPECT_EQ(soa.triangle_tests, sob.triangle_tests) << layout;
  }
  EXPECT_THROW(make_accelerator("bvh:simd=0,packet=16"), SpecError);
}

TEST(BvhFamily, CoincidentTrianglesEveryBuilder) {
  // 600 copies of one triangle plus 600 of another: identical centroids
  // force the median fallbacks; every copy must stay reachable.
  TriangleMesh m;
  m.vertices = {Vec3f(0, 0, 1), Vec3f(1, 0, 1), Vec3f(0, 1, 1), Vec3f(0, 0, 2), Vec3f(1, 0, 2), Vec3f(0, 1, 2)};
  for (int i = 0; i < 600; ++i) m.triangles.push_back({0, 1, 2}), m.triangles.push_back({3, 4, 5});
  for (const char* b : {"binned", "sweep", "sbvh", "lbvh"}) {
    for (const char* l : {"bvh2", "bvh8"}) {
      const std::string spec = fmt::format("bvh:builder={},layout={}", b, l);
      auto a = make_accelerator(spec);
      const BuildStats st = a->build(m);
      EXPECT_LT(st.max_depth, 64) << spec;
      const Hit h = a->intersect1(Ray(Vec3f(0.2f, 0.2f, 0), Vec3f(0, 0, 1)));
      ASSERT_TRUE(h.valid()) << spec;
      EXPECT_EQ(h.t, 1.0f) << spec;
      EXPECT_EQ(m.triangles[h.prim][0], 0u) << spec;
      EXPECT_EQ(h.prim, 0u) << spec << ": exact ties go to the lowest primitive id (HitRecorder)";
      EXPECT_TRUE(a->occluded1(Ray(Vec3f(0.2f, 0.2f, 3), Vec3f(0, 0, -1)))) << spec;
    }
    const BinaryBvh t = build_with(b, m);
    check_binary_tree(t, m, std::string(b) == "sbvh");
  }
}

// ---------------------------------------------------------------------------
// Builders and the wide collapse

TEST(BvhBuilders, BinaryTreesHoldEveryTriangleOnceInsideEnclosingBoxes) {
  const test::NamedMesh s = test::soup(3000, 23);
  for (const char* b : {"binned", "sweep", "lbvh", "reinsert"}) {
    SCOPED_TRACE(b);
    check_binary_tree(build_with(b, s.mesh), s.mesh, false);
    check_binary_tree(build_with(b, s.mesh, 4), s.mesh, false);
  }
  check_binary_tree(build_with("sbvh", s.mesh), s.mesh, true);
}

// Small ranges are split by an exact sweep whose per-axis order is a rank
// sort: with centroids on a coarse lattice (many equal coordinates, and
// -0 beside +0) every rank must still be a distinct slot. A lost or doubled
// reference would show as a triangle seen zero or two times.
TEST(BvhBuilders, SmallRangesWithTiedCentroidsKeepEveryTriangle) {
  TriangleMesh m;
  Pcg32 rng(9, 3);
  const float lattice[] = {-1.0f, -0.0f, 0.0f, 1.0f};
  for (int i = 0; i < 1500; ++i) {
    const Vec3f c(lattice[rng.next() % 4], lattice[rng.next() % 4], lattice[rng.next() % 4]);
    const float h = (rng.next() % 2) ? 0.25f : 0.125f;  // two sizes: ties in centroids, not in boxes
    const auto v = static_cast<uint32_t>(m.vertices.size());
    m.vertices.push_back(Vec3f(c.x() - h, c.y() - h, c.z()));  // z kept exactly: a -0 plane stays -0
    m.vertices.push_back(Vec3f(c.x() + h, c.y() - h, c.z()));
    m.vertices.push_back(Vec3f(c.x(), c.y() + h, c.z()));
    m.triangles.push_back({v, v + 1, v + 2});
  }
  for (int threshold : {1, 2, 3, 4}) {
    SCOPED_TRACE(threshold);
    check_binary_tree(build_with("binned", m, threshold), m, false);
  }
}

// The small-node sweep's fast path (AVX-512 registers where built for it)
// must choose exactly what the portable sweep chooses: the same orders, axis,
// position and cost bits, so that the tree does not depend on the ISA. And
// the portable sweep must choose the cheapest split by a plain recount. Sets
// of 2..16 references: random boxes, centroids tied on a lattice (-0 beside
// +0), flat and point boxes, identical references, and coordinates near the
// float limit whose extents overflow (infinite and NaN costs).
TEST(BvhBuilders, SmallSweepChoosesTheCheapestSplitOnEveryPath) {
  Pcg32 rng(41, 7);
  const float lattice[] = {-1.0f, -0.0f, 0.0f, 1.0f};
  for (int trial = 0; trial < 4000; ++trial) {
    const int n = 2 + trial % 15;
    const int kind = (trial / 15) % 5;
    std::vector<BuildRef> refs;
    for (int i = 0; i < n; ++i) {
      Vec3f lo, hi;
      for (int a = 0; a < 3; ++a) {
        float l = 0.0f, h = 0.0f;
        switch (kind) {
          case 0: l = rng.uniform() * 10.0f - 5.0f; h = l + rng.uniform() * 3.0f; break;
          case 1: l = lattice[rng.next() % 4]; h = l + ((rng.next() % 2) ? 0.5f : 0.0f); break;
          case 2: l = h = lattice[rng.next() % 4]; break;                        // points and flat boxes
          case 3: l = -1.0f; h = 2.0f; break;                                    // identical references
          default: l = (rng.next() % 2 ? 1.0f : -1.0f) * 3.0e38f * rng.uniform();  // overflowing extents
                   h = (rng.next() % 3) ? l : std::max(l, 3.0e38f * rng.uniform());
        }
        lo[a] = l;
        hi[a] = h;
      }
      const Aabb box(lo, hi);
      refs.push_back(BuildRef::make(box, box.center(), static_cast<uint32_t>(i)));
    }
    SCOPED_TRACE(fmt::format("trial {} n {} kind {}", trial, n, kind));
    uint8_t fast_order[3][sah::kSmallSweepMax], order[3][sah::kSmallSweepMax];
    const sah::SmallSplit fast = sah::choose_small_split(refs.data(), n, fast_order);
    const sah::SmallSplit ref = sah::choose_small_split_scalar(refs.data(), n, order);
    ASSERT_EQ(fast.axis, ref.axis);
    ASSERT_EQ(fast.pos, ref.pos);
    ASSERT_EQ(std::bit_cast<uint32_t>(fast.cost), std::bit_cast<uint32_t>(ref.cost));
    for (int a = 0; a < 3; ++a) ASSERT_TRUE(std::equal(order[a], order[a] + n, fast_order[a])) << "axis " << a;
    ASSERT_GE(ref.axis, 0);
    ASSERT_LE(ref.axis, 2);
    ASSERT_GE(ref.pos, 1);
    ASSERT_LT(ref.pos, n);
    // The orders: permutations, sorted by centroid (ties by index).
    for (int a = 0; a < 3; ++a) {
      std::vector<int> seen(n, 0);
      for (int i = 0; i < n; ++i) seen[order[a][i]]++;
      ASSERT_EQ(std::count(seen.begin(), seen.end(), 1), n);
      for (int i = 1; i < n; ++i) {
        const float p = refs[order[a][i - 1]].box.aabb().center()[a], q = refs[order[a][i]].box.aabb().center()[a];
        ASSERT_TRUE(p < q || (p == q && order[a][i - 1] < order[a][i]) || std::signbit(p) != std::signbit(q))
            << "axis " << a << " position " << i;
      }
    }
    // The cost recounted, and no split of any axis cheaper.
    const auto split_cost = [&](int a, int pos) {
      Box4 l, r;
      for (int i = 0; i < n; ++i) (i < pos ? l : r).extend(refs[order[a][i]].box);
      const float c = l.half_area() * static_cast<float>(pos) + r.half_area() * static_cast<float>(n - pos);
      return c == c ? c : std::numeric_limits<float>::infinity();
    };
    ASSERT_EQ(std::bit_cast<uint32_t>(split_cost(ref.axis, ref.pos)), std::bit_cast<uint32_t>(ref.cost));
    for (int a = 0; a < 3; ++a)
      for (int pos = 1; pos < n; ++pos) ASSERT_GE(split_cost(a, pos), ref.cost) << "axis " << a << " pos " << pos;
  }
}

// The partitions test a reference against a bin boundary with one scalar
// lane (Binning::left_of) and must agree with the bins the SAH counted
// (Binning::bins_of), or a child's box (taken from its bins) would miss a
// reference: centroids inside, on and outside the binned bounds, NaN, and
// the largest floats.
TEST(BvhBuilders, BoundaryTestAgreesWithTheBins) {
  Pcg32 rng(5, 11);
  Box4 cb;
  cb.extend(_mm_setr_ps(-2.0f, 0.0f, 1.0e-3f, 0.0f));
  cb.extend(_mm_setr_ps(6.0f, 1.0e-30f, 3.0e38f, 0.0f));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int bins : {2, 8, 16, 64, 256}) {
    const sah::Binning bn(cb, bins);
    for (int t = 0; t < 20000; ++t) {
      float c[3];
      for (int a = 0; a < 3; ++a) {
        const float lo = cb.lo_at(a), hi = cb.hi_at(a);
        switch (rng.next() % 6) {
          case 0: c[a] = lo; break;
          case 1: c[a] = hi; break;
          case 2: c[a] = lo - (hi - lo) * rng.uniform(); break;
          case 3: c[a] = (rng.next() % 2 ? 1.0f : -1.0f) * std::numeric_limits<float>::max(); break;
          case 4: c[a] = (t % 97 == 0) ? nan : lo + (hi - lo) * rng.uniform(); break;
          default: c[a] = lo + (hi - lo) * (std::floor(rng.uniform() * bins) / bins);  // on a bin boundary
        }
      }
      const BuildRef r = BuildRef::make(Aabb(Vec3f(0, 0, 0), Vec3f(1, 1, 1)), Vec3f(c[0], c[1], c[2]), 0);
      alignas(16) int32_t bin[4];
      _mm_store_si128(reinterpret_cast<__m128i*>(bin), bn.bins_of(r));
      for (int a = 0; a < 3; ++a)
        for (int pos = 1; pos < bins; ++pos)
          ASSERT_EQ(bn.left_of(r, a, pos), bin[a] < pos)
              << "bins " << bins << " axis " << a << " centroid " << c[a] << " pos " << pos;
    }
  }
}

// bin_refs spreads long ranges over two or four bin sets (and the longest
// over threads) and merges them: the same boxes and counts as binning the
// references one by one into one set, for every range length's path and
// remainder.
TEST(BvhBuilders, BinningMatchesOneByOne) {
  const test::NamedMesh s = test::soup(40000, 17, 0.05f);
  const Prims p = prims_of(s.mesh);
  const std::vector<BuildRef> refs = make_build_refs(p.boxes, p.centroids);
  for (size_t n : {size_t{7}, size_t{255}, size_t{256}, size_t{1001}, size_t{2047}, size_t{2048}, size_t{5003},
                   size_t{40000}}) {
    for (int nb : {8, 64}) {
      SCOPED_TRACE(fmt::format("{} references, {} bins", n, nb));
      const size_t b = refs.size() - n;
      Box4 cb;
      for (size_t i = b; i < refs.size(); ++i) cb.extend(refs[i].centroid());
      const sah::Binning bn(cb, nb);
      const auto bins = sah::bin_refs(refs.data(), b, refs.size(), bn, nb);
      std::vector<Box4> box(3 * nb);
      std::vector<uint32_t> count(3 * nb, 0);
      for (size_t i = b; i < refs.size(); ++i) {
        alignas(16) int32_t bin[4];
        _mm_store_si128(reinterpret_cast<__m128i*>(bin), bn.bins_of(refs[i]));
        for (int a = 0; a < 3; ++a) {
          box[a * nb + bin[a]].extend(refs[i].box);
          ++count[a * nb + bin[a]];
        }
      }
      for (int a = 0; a < 3; ++a)
        for (int k = 0; k < nb; ++k) {
          ASSERT_EQ(bins->count[a][k], count[a * nb + k]) << a << " " << k;
          if (!count[a * nb + k]) continue;
          const Box4 got = bins->box(a, k), want = box[a * nb + k];
          ASSERT_EQ(got.aabb().lo, want.aabb().lo) << a << " " << k;
          ASSERT_EQ(got.aabb().hi, want.aabb().hi) << a << " " << k;
          ASSERT_EQ(got.max_ref_half_area(), want.max_ref_half_area()) << a << " " << k;
        }
    }
  }
}

TEST(BvhBuilders, SweepIsNoWorseThanBinnedAndLbvhNoBetter) {
  // The full sweep evaluates a superset of the binned candidates at each
  // node; LBVH ignores the SAH. Compared on a clustered scene.
  const test::NamedMesh s = test::soup(4000, 31);
  const double binned = tree_sah_cost(build_with("binned", s.mesh).nodes);
  const double sweep = tree_sah_cost(build_with("sweep", s.mesh).nodes);
  const double lbvh = tree_sah_cost(build_with("lbvh", s.mesh).nodes);
  EXPECT_LE(sweep, binned * 1.01);
  EXPECT_GT(lbvh, sweep);
}

// The DP's objective evaluated on its own output.
double collapse_cost(const WideTree& t, const CollapseOptions& o) {
  auto blocks = [&](uint32_t n) { return static_cast<double>((n + o.block_width - 1) / o.block_width); };
  if (t.root_leaf >= 0) return o.block_cost * blocks(t.leaf_size(0));
  double cost = 0.0;
  for (const WideTree::Node& n : t.nodes) {
    Aabb box;
    for (int c = 0; c < n.count; ++c) box.extend(n.child[c].box);
    cost += o.node_cost * box.half_area();
    for (int c = 0; c < n.count; ++c)
      if (n.child[c].leaf) cost += o.block_cost * n.child[c].box.half_area() * blocks(t.leaf_size(n.child[c].index));
  }
  return cost / t.root_box.half_area();
}

// Greedy top-down collapse (open the largest inner child until the node is
// full), with binary leaves as leaves: what level skipping would give.
double greedy_cost(const BinaryBvh& t, const CollapseOptions& o, const std::vector<uint32_t>& counts) {
  double cost = 0.0;
  std::vector<uint32_t> stack{0};
  while (!stack.empty()) {
    const uint32_t x = stack.back();
    stack.pop_back();
    cost += o.node_cost * t.nodes[x].bounds().half_area();
    std::vector<uint32_t> slots{t.nodes[x].index, t.nodes[x].index + 1};
    while (static_cast<int>(slots.size()) < o.width) {
      int best = -1;
      float area = -1.0f;
      for (size_t i = 0; i < slots.size(); ++i)
        if (!is_leaf(t.nodes[slots[i]]) && t.nodes[slots[i]].bounds().half_area() > area)
          area = t.nodes[slots[i]].bounds().half_area(), best = static_cast<int>(i);
      if (best < 0) break;
      const uint32_t open = slots[best];
      slots.erase(slots.begin() + best);
      slots.push_back(t.nodes[open].index);
      slots.push_back(t.nodes[open].index + 1);
    }
    for (uint32_t s : slots) {
      if (is_leaf(t.nodes[s]))
        cost += o.block_cost * t.nodes[s].bounds().half_area() *
                static_cast<double>((counts[s] + o.block_width - 1) / o.block_width);
      else
        stack.push_back(s);
    }
  }
  return cost / t.nodes[0].bounds().half_area();
}

// The collapse's optimum against the recurrence of collapse_wide.h evaluated
// plainly (doubles, every k, no slot bounds): the DP's bounded ranges
// (a subtree never uses more slots than it has binary leaves) must reach the
// same value.
TEST(BvhCollapse, OptimumMatchesThePlainRecurrence) {
  const test::NamedMesh s = test::soup(2500, 43);
  for (const char* b : {"binned", "reinsert"}) {
    const BinaryBvh tree = build_with(b, s.mesh);
    const std::vector<uint32_t> counts = subtree_ref_counts(tree.nodes);
    for (int width : {2, 4, 8, 16}) {
      SCOPED_TRACE(fmt::format("{} width {}", b, width));
      CollapseOptions o;
      o.width = width;
      o.block_width = width == 2 ? 1 : 4;
      o.max_leaf = width == 2 ? 4 : 8;
      o.node_cost = 2.0f;
      const double inf = std::numeric_limits<double>::infinity();
      // C[n][i - 1] for i = 1..width, children before parents (indices grow downwards).
      std::vector<std::vector<double>> c(tree.nodes.size());
      auto leaf = [&](uint32_t n, bool forced) {
        const uint32_t blocks = (counts[n] + o.block_width - 1) / o.block_width;
        if (!forced && (counts[n] > static_cast<uint32_t>(o.max_leaf) ||
                        blocks > static_cast<uint32_t>(o.max_leaf_blocks)))
          return inf;
        return static_cast<double>(tree.nodes[n].bounds().half_area()) * o.block_cost * blocks;
      };
      std::vector<uint32_t> order{0};
      for (size_t k = 0; k < order.size(); ++k)
        if (!is_leaf(tree.nodes[order[k]])) {
          order.push_back(tree.nodes[order[k]].index);
          order.push_back(tree.nodes[order[k]].index + 1);
        }
      for (auto it = order.rbegin(); it != order.rend(); ++it) {
        const uint32_t n = *it;
        c[n].assign(width, 0.0);
        if (is_leaf(tree.nodes[n])) {
          std::fill(c[n].begin(), c[n].end(), leaf(n, true));
          continue;
        }
        const auto& cl = c[tree.nodes[n].index];
        const auto& cr = c[tree.nodes[n].index + 1];
        auto d = [&](int i) {
          double best = inf;
          for (int k = 1; k < i; ++k) best = std::min(best, cl[k - 1] + cr[i - k - 1]);
          return best;
        };
        c[n][0] = std::min(leaf(n, false),
                           static_cast<double>(tree.nodes[n].bounds().half_area()) * o.node_cost + d(width));
        for (int i = 2; i <= width; ++i) c[n][i - 1] = std::min(c[n][i - 2], d(i));
      }
      const WideTree w = collapse_to_wide(tree, o);
      const double want = c[0][0] / tree.nodes[0].bounds().half_area();
      EXPECT_NEAR(w.dp_cost, want, 1e-4 * want);
      EXPECT_NEAR(collapse_cost(w, o), want, 1e-3 * want);
    }
  }
}

TEST(BvhCollapse, EveryTriangleReachableOnceAndBoxesEnclose) {
  const test::NamedMesh s = test::soup(3000, 41);
  for (const char* b : {"binned", "lbvh", "reinsert"}) {
    const BinaryBvh tree = build_with(b, s.mesh);
    for (int width : {2, 4, 8, 16}) {
      for (int block : {1, 4, 8, 16}) {
        if ((width == 2) != (block == 1)) continue;
        SCOPED_TRACE(fmt::format("{} width {} block {}", b, width, block));
        CollapseOptions o;
        o.width = width;
        o.block_width = block;
        o.max_leaf = width == 2 ? 4 : 2 * block;
        o.node_cost = 2.0f;
        const WideTree w = collapse_to_wide(tree, o);
        ASSERT_LT(w.root_leaf, 0);
        std::vector<int> seen(s.mesh.num_triangles(), 0);
        for (size_t leaf = 0; leaf < w.leaf_count(); ++leaf) {
          EXPECT_LE(static_cast<int>(w.leaf_size(leaf)), o.max_leaf);
          for (uint32_t k = w.leaf_begin[leaf]; k < w.leaf_begin[leaf + 1]; ++k) seen[w.leaf_prims[k]]++;
        }
        for (int c : seen) ASSERT_EQ(c, 1);
        // Each node's child boxes enclose what lies below them.
        std::vector<int> parents(w.nodes.size(), 0);
        for (const WideTree::Node& n : w.nodes) {
          EXPECT_GE(n.count, 2);
          EXPECT_LE(n.count, width);
          for (int c = 0; c < n.count; ++c) {
            const WideTree::Child& ch = n.child[c];
            if (ch.leaf) {
              for (uint32_t k = w.leaf_begin[ch.index]; k < w.leaf_begin[ch.index + 1]; ++k)
                EXPECT_TRUE(ch.box.contains(s.mesh.triangle_bounds(w.leaf_prims[k])));
            } else {
              parents[ch.index]++;
              for (int g = 0; g < w.nodes[ch.index].count; ++g)
                EXPECT_TRUE(ch.box.contains(w.nodes[ch.index].child[g].box));
            }
          }
        }
        for (size_t i = 1; i < parents.size(); ++i) EXPECT_EQ(parents[i], 1) << "wide node " << i;
        // The DP is optimal for its cost model: its value matches its tree,
        // and it beats opening the largest child greedily.
        EXPECT_NEAR(collapse_cost(w, o), w.dp_cost, 1e-3 * w.dp_cost);
        EXPECT_LE(w.dp_cost, greedy_cost(tree, o, subtree_ref_counts(tree.nodes)) * (1 + 1e-5));
      }
    }
  }
}

TEST(BvhCollapse, BoxThicknessIsTheVolumeOfTheCubeOfTheSameArea) {
  EXPECT_NEAR(box_thickness(Aabb{Vec3f(0, 0, 0), Vec3f(2, 2, 2)}), 1.0f, 1e-6f);
  EXPECT_EQ(box_thickness(Aabb{Vec3f(0, 0, 0), Vec3f(3, 0, 5)}), 0.0f);
  // 2 x 1 x 1: volume 2, half area 5, sqrt(27) * 2 / 5^1.5
  EXPECT_NEAR(box_thickness(Aabb{Vec3f(1, 1, 1), Vec3f(3, 2, 2)}), std::sqrt(27.0f) * 2.0f / std::pow(5.0f, 1.5f), 1e-6f);
  EXPECT_EQ(box_thickness(Aabb::empty()), 0.0f);
}

// A room's corner in [0, 4]^3 (the floor and two walls, each one quad of
// two triangles) beside a cloud of 400 small triangles in [6, 7]^3.
TriangleMesh room_corner_beside_a_cloud() {
  TriangleMesh m = test::soup(400, 47).mesh;
  for (Vec3f& v : m.vertices) v = v + Vec3f(6, 6, 6);
  const auto quad = [&](Vec3f o, Vec3f u, Vec3f w) {
    const auto base = static_cast<uint32_t>(m.vertices.size());
    m.vertices.insert(m.vertices.end(), {o, o + u, o + u + w, o + w});
    m.triangles.push_back({base, base + 1, base + 2});
    m.triangles.push_back({base, base + 2, base + 3});
  };
  quad(Vec3f(0, 0, 0), Vec3f(4, 0, 0), Vec3f(0, 0, 4));  // floor
  quad(Vec3f(0, 0, 0), Vec3f(0, 4, 0), Vec3f(0, 0, 4));  // wall x = 0
  quad(Vec3f(0, 0, 0), Vec3f(4, 0, 0), Vec3f(0, 4, 0));  // wall z = 0
  return m;
}

// The room corner beside its cloud: without the thick-leaf limit the
// collapse merges the corner's triangles of different planes into one leaf
// whose box is a cube (by the SAH it should: one block test over the cube's
// area against six over the flat boxes' larger total); with it no leaf of
// more than one binary leaf (one triangle here) is large and thick, and the
// tree still holds every triangle once.
TEST(BvhCollapse, ThickLeavesAreNotFormed) {
  const TriangleMesh m = room_corner_beside_a_cloud();
  const BinaryBvh tree = build_with("binned", m, 1);
  const float root_area = tree.nodes[0].bounds().half_area();
  for (int width : {8, 16}) {
    SCOPED_TRACE(fmt::format("width {}", width));
    CollapseOptions o;
    o.width = width;
    o.block_width = 8;
    o.max_leaf = 16;
    o.node_cost = 2.0f;
    o.thick_leaf_area = 0.005f;
    o.mesh = &m;
    // The largest thick leaf's triangle count, and every triangle seen once.
    const auto largest_thick_leaf = [&](const WideTree& w) {
      uint32_t most = 0;
      std::vector<int> seen(m.num_triangles(), 0);
      for (const WideTree::Node& n : w.nodes)
        for (int c = 0; c < n.count; ++c) {
          const WideTree::Child& ch = n.child[c];
          if (!ch.leaf) continue;
          for (uint32_t k = w.leaf_begin[ch.index]; k < w.leaf_begin[ch.index + 1]; ++k) seen[w.leaf_prims[k]]++;
          if (ch.box.half_area() > o.thick_leaf_area * root_area && box_thickness(ch.box) > 0.4f)
            most = std::max(most, w.leaf_size(ch.index));
        }
      for (int c : seen) EXPECT_EQ(c, 1);
      return most;
    };
    o.thick_leaf_limit = 0.0f;
    EXPECT_GE(largest_thick_leaf(collapse_to_wide(tree, o)), 2u) << "the scene no longer tests the limit";
    o.thick_leaf_limit = 0.4f;
    EXPECT_LE(largest_thick_leaf(collapse_to_wide(tree, o)), 1u);
  }
  // Large triangles of every orientation fill their leaves' boxes: on a soup
  // of them the limit opens at most the odd leaf of nearly flat ones (one
  // node more of 34 here; without the flat-triangle condition 3.7x the
  // nodes).
  const test::NamedMesh soup = test::soup(3000, 5);
  const BinaryBvh soup_tree = build_with("binned", soup.mesh, 3);
  CollapseOptions o;
  o.width = 16;
  o.block_width = 8;
  o.max_leaf = 16;
  o.node_cost = 2.0f;
  o.thick_leaf_area = 0.005f;
  o.mesh = &soup.mesh;
  const WideTree off = collapse_to_wide(soup_tree, o);
  o.thick_leaf_limit = 0.4f;
  const WideTree on = collapse_to_wide(soup_tree, o);
  EXPECT_LE(on.nodes.size(), off.nodes.size() + 2);
  EXPECT_LE(on.dp_cost, off.dp_cost * 1.05);
}

// The accelerator sets the limit on 16-wide trees after the light pass only
// (BvhConfig::thick_limit): counted on the leaf boxes of its outline, the
// corner's large triangles being axis-planar, so that a large thick leaf box
// holds more than one of them. The trees without the limit have such leaves,
// the one with it none.
TEST(BvhCollapse, ThickLeafLimitByDefaultOnSixteenWideLightPassTrees) {
  const TriangleMesh m = room_corner_beside_a_cloud();
  const auto thick_leaves = [&](const std::string& spec) {
    auto accel = make_accelerator(spec);
    accel->build(m);
    StructureOutline out;
    accel->outline(64, out);
    EXPECT_FALSE(out.truncated);
    const float root_area = m.bounds().half_area();
    int thick = 0;
    for (const OutlineBox& b : out.boxes)
      thick += b.leaf && b.box.half_area() > 0.005f * root_area && box_thickness(b.box) > 0.4f;
    return thick;
  };
  EXPECT_EQ(thick_leaves("bvh:layout=bvh16"), 0);
  EXPECT_GE(thick_leaves("bvh:layout=bvh8"), 1);
  EXPECT_GE(thick_leaves("bvh:layout=bvh16,opt=reinsert"), 1);
}

TEST(BvhCollapse, WideLayoutNodesAndBlocks) {
  const test::NamedMesh s = test::soup(2000, 43);
  const BinaryBvh tree = build_with("binned", s.mesh);
  CollapseOptions o;
  o.width = 8;
  o.block_width = 8;
  o.max_leaf = 16;
  const WideTree w = collapse_to_wide(tree, o);
  const WideBvh<8, 8> bvh = make_wide_bvh<8, 8>(w, s.mesh);
  std::vector<int> seen(s.mesh.num_triangles(), 0);
  for (const WideNode<8>& n : bvh.nodes) {
    for (int c = 0; c < 8; ++c) {
      const uint32_t ref = n.child[c];
      if (!wide_ref::is_leaf(ref)) {
        const WideNode<8>& ch = bvh.nodes[ref];
        for (int g = 0; g < 8; ++g)
          if (!(wide_ref::is_leaf(ch.child[g]) && wide_ref::leaf_blocks(ch.child[g]) == 0)) {
            EXPECT_TRUE(n.child_box(c).contains(ch.child_box(g)));
          }
        continue;
      }
      if (wide_ref::leaf_blocks(ref) == 0) {
        EXPECT_TRUE(n.child_box(c).is_empty()) << "unused slots have empty boxes";
        continue;
      }
      for (uint32_t b = 0; b < wide_ref::leaf_blocks(ref); ++b) {
        const TriangleBlock<8>& blk = bvh.blocks[wide_ref::leaf_first(ref) + b];
        for (int lane = 0; lane < blk.count(); ++lane) {
          seen[blk.prim[lane]]++;
          EXPECT_TRUE(n.child_box(c).contains(s.mesh.triangle_bounds(blk.prim[lane])));
        }
      }
    }
  }
  for (int c : seen) EXPECT_EQ(c, 1);
}

// Triangles that coincide (the same three vertices, as in real meshes with
// doubled faces) have one centroid, so no object split separates them; a
// spatial split cannot either (every plane puts all of them on both sides).
// With single-triangle binary leaves such a node must still end in a
// median split, not in spatial splits that copy every reference into both
// children until the duplication budget is spent (it was: 1.5 references per
// triangle, twice the memory, on sponza and dragon_in_sponza).
TEST(BvhSbvh, CoincidentTrianglesDoNotSpendTheSplitBudget) {
  test::NamedMesh s = test::soup(300, 47, 3.0f);
  TriangleMesh dup;
  dup.vertices = {Vec3f(0.1f, 0.2f, 0.3f), Vec3f(0.9f, 0.25f, 0.35f), Vec3f(0.4f, 0.8f, 0.3f)};
  for (int i = 0; i < 12; ++i) dup.triangles.push_back({0, 1, 2});
  s.mesh.append(dup);
  const Prims p = prims_of(s.mesh);
  SbvhOptions so;
  so.base.leaf_threshold = 1;
  so.alpha = 1.0f;  // spatial splits only where no object split exists
  so.split_budget = 0.5f;
  SbvhStats st;
  const BinaryBvh t = build_sbvh(p.boxes, p.centroids, TriangleSplitter(s.mesh), so, &st);
  check_binary_tree(t, s.mesh, true);
  EXPECT_EQ(st.spatial_splits, 0u);
  EXPECT_EQ(t.prim_ids.size(), s.mesh.num_triangles());
}

// Points of every triangle (its vertices and 197 random ones) that lie in
// none of the boxes given for it: 0 when the boxes cover their triangles.
size_t uncovered_points(const TriangleMesh& mesh, std::map<uint32_t, std::vector<Aabb>>& boxes_of) {
  Pcg32 rng(5, 7);
  size_t uncovered = 0;
  for (uint32_t prim = 0; prim < mesh.num_triangles(); ++prim) {
    const Vec3f a = mesh.vertex(prim, 0), b = mesh.vertex(prim, 1), c = mesh.vertex(prim, 2);
    for (int i = 0; i < 200; ++i) {
      float u = rng.uniform(), v = rng.uniform();
      if (u + v > 1.0f) u = 1.0f - u, v = 1.0f - v;
      if (i < 3) u = i == 1, v = i == 2;  // the vertices themselves
      // Points are rounded in float; allow that rounding.
      const Vec3f q = (1.0f - u - v) * a + u * b + v * c;
      const float tol = 4e-7f * q.cwiseAbs().maxCoeff() + 1e-30f;
      bool covered = false;
      for (const Aabb& box : boxes_of[prim])
        covered |= (q.array() >= box.lo.array() - tol).all() && (q.array() <= box.hi.array() + tol).all();
      uncovered += !covered;
    }
  }
  return uncovered;
}

TEST(BvhSbvh, ReferencesCoverTheirTriangles) {
  // Long thin triangles across a box: the case spatial splits exist for.
  const test::NamedMesh s = test::soup(300, 47, 3.0f);
  const Prims p = prims_of(s.mesh);
  SbvhOptions so;
  so.alpha = 0.0f;
  so.split_budget = 1.0f;
  so.spatial_bins = 16;
  SbvhStats st;
  const BinaryBvh t = build_sbvh(p.boxes, p.centroids, TriangleSplitter(s.mesh), so, &st);
  EXPECT_GT(st.spatial_splits, 10u) << "the scene must exercise spatial splits";
  EXPECT_GT(t.prim_ids.size(), s.mesh.num_triangles());
  EXPECT_LE(t.prim_ids.size(), 2 * s.mesh.num_triangles()) << "split budget";
  check_binary_tree(t, s.mesh, true);
  // Every point of every triangle lies in the box of one of its references.
  std::map<uint32_t, std::vector<Aabb>> boxes_of;
  for (const Bvh2Node& n : t.nodes)
    if (is_leaf(n))
      for (uint32_t k = n.index; k < n.index + n.count; ++k) boxes_of[t.prim_ids[k]].push_back(n.bounds());
  EXPECT_EQ(uncovered_points(s.mesh, boxes_of), 0u);
}

// A build reference carries its box's half area in lane 3 of hi, computed as
// Box4::half_area computes it, and a union of references' boxes carries the
// largest: the size split skips its pass over a node's references on it.
TEST(BvhBinned, ReferenceBoxesCarryTheirLargestHalfArea) {
  const Aabb a(Vec3f(0, 0, 0), Vec3f(1, 2, 3)), b(Vec3f(5, 5, 5), Vec3f(5.5f, 5, 7)), flat(Vec3f(1, 1, 1), Vec3f(1, 1, 4));
  const BuildRef ra = BuildRef::make(a, a.center(), 0), rb = BuildRef::make(b, b.center(), 1),
                 rf = BuildRef::make(flat, flat.center(), 2);
  EXPECT_EQ(ra.box.max_ref_half_area(), ra.box.half_area());
  EXPECT_EQ(ra.box.max_ref_half_area(), 11.0f);
  EXPECT_EQ(rb.box.max_ref_half_area(), 1.0f);
  EXPECT_EQ(rf.box.max_ref_half_area(), 0.0f);
  EXPECT_EQ(merge(rb.box, ra.box).max_ref_half_area(), 11.0f);
  EXPECT_EQ(merge(rf.box, rb.box).max_ref_half_area(), 1.0f);
  EXPECT_EQ(merge(ra.box, rb.box).half_area(), Box4::from(Aabb(Vec3f(0, 0, 0), Vec3f(5.5f, 5, 7))).half_area());
  EXPECT_EQ(Box4::from(a).max_ref_half_area(), 0.0f) << "boxes not made from references carry 0";
  // A denormal area is stored as the smallest normal float: still a bound.
  const Aabb tiny(Vec3f(0, 0, 0), Vec3f(1e-20f, 1e-20f, 0));
  const BuildRef rt = BuildRef::make(tiny, tiny.center(), 3);
  EXPECT_GT(rt.box.half_area(), 0.0f);
  EXPECT_LT(rt.box.half_area(), std::numeric_limits<float>::min());
  EXPECT_EQ(rt.box.max_ref_half_area(), std::numeric_limits<float>::min());
  // The bins keep the largest too (the children's boxes come from them).
  Box4 cbounds;
  for (const BuildRef* r : {&ra, &rb, &rf}) cbounds.extend(r->centroid());
  const sah::Binning bn(cbounds, 4);
  const BuildRef refs[] = {ra, rb, rf};
  const auto bins = sah::bin_refs(refs, 0, 3, bn, 4);
  float largest = 0.0f;
  for (int bin = 0; bin < 4; ++bin)
    if (bins->count[0][bin]) largest = std::max(largest, bins->box(0, bin).max_ref_half_area());
  EXPECT_EQ(largest, 11.0f);
}

// One thread and the default pool give the same binned tree, node for node
// (the pool's subtree tasks number their nodes as they run; the build
// renumbers them as the serial build does), and so do two runs of the pool:
// the one-thread path partitions large nodes in one pass (the split's left
// count placing the right side), the parallel one counts per chunk first;
// both are stable. The same for the accelerator's whole build, reinsertion
// (whose ties follow the numbering) and layout included.
TEST(BvhBinned, OneThreadAndThePoolBuildTheSameTree) {
  test::NamedMesh s = test::soup(40000, 31, 0.02f);
  const Prims p = prims_of(s.mesh);
  BuildOptions bo;
  bo.big_node = 0.1f;
  bo.big_root = 0.03f;
  bo.leaf_threshold = 1;
  const BinaryBvh pool = build_binned_sah(p.boxes, p.centroids, bo);
  const BinaryBvh pool2 = build_binned_sah(p.boxes, p.centroids, bo);
  BinaryBvh serial;
  BuildStats serial_stats;
  {
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    serial = build_binned_sah(p.boxes, p.centroids, bo);
    serial_stats = make_accelerator("bvh:preset=quality")->build(s.mesh);
  }
  check_binary_tree(serial, s.mesh, false);
  for (const BinaryBvh* t : {&pool, &pool2}) {
    ASSERT_EQ(serial.nodes.size(), t->nodes.size());
    EXPECT_EQ(serial.prim_ids, t->prim_ids);
    for (size_t i = 0; i < t->nodes.size(); ++i) {
      ASSERT_EQ(serial.nodes[i].index, t->nodes[i].index) << i;
      ASSERT_EQ(serial.nodes[i].count, t->nodes[i].count) << i;
      ASSERT_EQ(serial.nodes[i].bounds().lo, t->nodes[i].bounds().lo) << i;
      ASSERT_EQ(serial.nodes[i].bounds().hi, t->nodes[i].bounds().hi) << i;
    }
  }
  const BuildStats pool_stats = make_accelerator("bvh:preset=quality")->build(s.mesh);
  EXPECT_EQ(pool_stats.extra.at("opt_moves"), serial_stats.extra.at("opt_moves"));
  // (a parallel sum: equal up to the order of its additions)
  EXPECT_NEAR(pool_stats.extra.at("sah_tree"), serial_stats.extra.at("sah_tree"),
              1e-9 * serial_stats.extra.at("sah_tree"));
  EXPECT_EQ(pool_stats.nodes, serial_stats.nodes);
  EXPECT_EQ(pool_stats.bytes, serial_stats.bytes);
}

// big / bigroot (BuildOptions::big_node, big_root): a node's references whose
// boxes are large against its own (or the root's) become one child, the rest
// the other; nothing else about the tree changes.
TEST(BvhBinned, LargeReferencesGetAChildOfTheirOwn) {
  // Small triangles filling the unit cube, a floor and a wall across it.
  test::NamedMesh s = test::soup(3000, 29, 0.05f);
  const uint32_t first_large = static_cast<uint32_t>(s.mesh.num_triangles());
  TriangleMesh large;
  large.vertices = {Vec3f(-0.1f, 0.5f, -0.1f), Vec3f(1.1f, 0.5f, -0.1f), Vec3f(1.1f, 0.5f, 1.1f),
                    Vec3f(-0.1f, 0.5f, 1.1f),  Vec3f(0.3f, -0.1f, -0.1f), Vec3f(0.3f, 1.1f, -0.1f),
                    Vec3f(0.3f, 1.1f, 1.1f),   Vec3f(0.3f, -0.1f, 1.1f)};
  large.triangles = {{0, 1, 2}, {0, 2, 3}, {4, 5, 6}, {4, 6, 7}};
  s.mesh.append(large);
  const Prims p = prims_of(s.mesh);
  // The triangles under a node.
  auto triangles_under = [](const BinaryBvh& t, uint32_t node) {
    std::vector<uint32_t> out, stack{node};
    while (!stack.empty()) {
      const Bvh2Node& n = t.nodes[stack.back()];
      stack.pop_back();
      if (is_leaf(n)) {
        for (uint32_t k = n.index; k < n.index + n.count; ++k) out.push_back(t.prim_ids[k]);
      } else {
        stack.push_back(n.index);
        stack.push_back(n.index + 1);
      }
    }
    std::sort(out.begin(), out.end());
    return out;
  };
  const std::vector<uint32_t> large_ids{first_large, first_large + 1, first_large + 2, first_large + 3};
  for (int rule = 0; rule < 3; ++rule) {
    SCOPED_TRACE(rule == 0 ? "off" : rule == 1 ? "big_node" : "big_root");
    BuildOptions bo;
    bo.big_node = rule == 1 ? 0.1f : 0.0f;
    bo.big_root = rule == 2 ? 0.1f : 0.0f;
    bo.big_min = 1024;
    const BinaryBvh t = build_binned_sah(p.boxes, p.centroids, bo);
    check_binary_tree(t, s.mesh, false);
    ASSERT_FALSE(is_leaf(t.nodes[0]));
    const std::vector<uint32_t> left = triangles_under(t, t.nodes[0].index);
    if (rule == 0) EXPECT_NE(left, large_ids) << "centroid splits do not separate by size";
    else EXPECT_EQ(left, large_ids) << "the floor and the wall, and only they, under the root's first child";
  }
  // Only at nodes of at least big_min references.
  BuildOptions few;
  few.big_node = 0.1f;
  few.big_min = 4000;
  BinnedBuildStats few_stats;
  EXPECT_NE(triangles_under(build_binned_sah(p.boxes, p.centroids, few, &few_stats), 1), large_ids);
  EXPECT_EQ(few_stats.big_splits, 0u);
  // More than a quarter of a node's references large: ordinary splits only.
  test::NamedMesh longs = test::soup(1200, 7, 3.0f);
  const Prims lp = prims_of(longs.mesh);
  BuildOptions all;
  all.big_node = 1e-6f;
  all.big_min = 16;
  BinnedBuildStats all_stats;
  check_binary_tree(build_binned_sah(lp.boxes, lp.centroids, all, &all_stats), longs.mesh, false);
  EXPECT_EQ(all_stats.big_splits, 0u);
  // Through the spec: on with the binned builder (the family's brute-force
  // test checks the hits), off with the others.
  const BuildStats split = make_accelerator("bvh:opt=none")->build(s.mesh);
  EXPECT_GE(split.extra.at("big_splits"), 1.0);
  EXPECT_EQ(make_accelerator("bvh:opt=none,builder=sweep")->build(s.mesh).extra.count("big_splits"), 0u);
}

TEST(BvhSbvh, SplitterBoxesEncloseTheExactCrossing) {
  const test::NamedMesh s = test::soup(200, 53, 2.0f);
  const TriangleSplitter split(s.mesh);
  Pcg32 rng(11, 3);
  size_t crossings = 0;
  for (uint32_t prim = 0; prim < s.mesh.num_triangles(); ++prim) {
    const Aabb box = s.mesh.triangle_bounds(prim);
    for (int axis = 0; axis < 3; ++axis) {
      const float pos = box.lo[axis] + rng.uniform() * (box.hi[axis] - box.lo[axis]);
      Aabb l, r;
      split.split(prim, box, axis, pos, true, l, r);
      EXPECT_TRUE(box.contains(l) && box.contains(r));
      // Each edge crossing the plane, in double precision, lies in both boxes.
      for (int e = 0; e < 3; ++e) {
        const Vec3f p = s.mesh.vertex(prim, e), q = s.mesh.vertex(prim, (e + 1) % 3);
        if (!((p[axis] < pos && q[axis] > pos) || (p[axis] > pos && q[axis] < pos))) continue;
        ++crossings;
        const double t = (static_cast<double>(pos) - p[axis]) / (static_cast<double>(q[axis]) - p[axis]);
        for (int a = 0; a < 3; ++a) {
          const double x = a == axis ? pos : p[a] + t * (static_cast<double>(q[a]) - p[a]);
          EXPECT_LE(l.lo[a], x);
          EXPECT_GE(l.hi[a], x);
          EXPECT_LE(r.lo[a], x);
          EXPECT_GE(r.hi[a], x);
        }
      }
      for (int c = 0; c < 3; ++c) {
        const Vec3f v = s.mesh.vertex(prim, c);
        if (v[axis] <= pos) {
          EXPECT_TRUE(l.contains(v));
        }
        if (v[axis] >= pos) {
          EXPECT_TRUE(r.contains(v));
        }
      }
    }
  }
  EXPECT_GT(crossings, 100u);
}

TEST(BvhLbvh, CoincidentCentroidsGiveABalancedTree) {
  // 4096 triangles with the very same box centre (rotated copies), and
  // Morton codes that all collide: the index breaks the ties.
  TriangleMesh m;
  const int n = 4096;
  for (int i = 0; i < n; ++i) {
    const float a = 6.2831853f * static_cast<float>(i) / n;
    const uint32_t base = static_cast<uint32_t>(m.vertices.size());
    m.vertices.push_back(Vec3f(std::cos(a), std::sin(a), 0.0f));
    m.vertices.push_back(Vec3f(-std::cos(a), -std::sin(a), 0.0f));
    m.vertices.push_back(Vec3f(0.0f, 0.0f, 1.0f + 0.0001f * static_cast<float>(i % 7)));
    m.vertices.push_back(Vec3f(0.0f, 0.0f, -1.0f - 0.0001f * static_cast<float>(i % 7)));
    m.triangles.push_back({base, base + 1, base + 2});
    m.triangles.push_back({base + 1, base, base + 3});
  }
  const Prims p = prims_of(m);
  const BinaryBvh t = build_lbvh(p.boxes, p.centroids);
  check_binary_tree(t, m, false);
  const Bvh2Shape shape = measure_tree(t.nodes);
  EXPECT_LE(shape.max_depth, 2 + static_cast<int>(std::ceil(std::log2(2.0 * n)))) << "ties split by index";
  // And the accelerator built on it answers like brute force.
  auto a = make_accelerator("bvh:builder=lbvh");
  auto brute = make_accelerator("brute");
  a->build(m);
  brute->build(m);
  Pcg32 rng(3, 9);
  for (int i = 0; i < 300; ++i) {
    const Ray r(Vec3f(2.0f * rng.uniform() - 1.0f, 2.0f * rng.uniform() - 1.0f, 3.0f), Vec3f(0.01f, 0.02f, -1.0f));
    const Hit x = a->intersect1(r), y = brute->intersect1(r);
    ASSERT_EQ(x.valid(), y.valid());
    if (x.valid()) {
      EXPECT_EQ(x.t, y.t);
    }
  }
}

TEST(BvhLbvh, MortonSpreadPlacesBitsEveryThird) {
  EXPECT_EQ(morton_spread21(0), 0u);
  EXPECT_EQ(morton_spread21(1), 1u);
  EXPECT_EQ(morton_spread21(2), 8u);
  EXPECT_EQ(morton_spread21(0x1FFFFF), 0x1249249249249249ull);
  for (int bit = 0; bit < 21; ++bit) EXPECT_EQ(morton_spread21(1u << bit), 1ull << (3 * bit));
  EXPECT_EQ(morton_spread21(1u << 21), 0u) << "only 21 bits are used";
}

TEST(BvhReinsertion, LowersSahCostAndRespectsTheTimeBudget) {
  const test::NamedMesh s{"sphere", make_uv_sphere(96, 48)};  // a surface: LBVH leaves room to improve
  const Prims p = prims_of(s.mesh);
  const BinaryBvh base = build_lbvh(p.boxes, p.centroids);
  ReinsertionStats st;
  const BinaryBvh opt = optimize_reinsertion(base, ReinsertionOptions{}, &st);
  check_binary_tree(opt, s.mesh, false);
  EXPECT_NEAR(st.sah_before, tree_sah_cost(base.nodes), 1e-3 * st.sah_before);
  EXPECT_NEAR(st.sah_after, tree_sah_cost(opt.nodes), 1e-3 * st.sah_after);
  EXPECT_LT(st.sah_after, 0.98 * st.sah_before);
  EXPECT_GT(st.moves, 0u);
  // No rounds, no change.
  ReinsertionOptions none;
  none.max_rounds = 0;
  ReinsertionStats st0;
  const BinaryBvh same = optimize_reinsertion(base, none, &st0);
  EXPECT_EQ(st0.rounds, 0);
  EXPECT_EQ(st0.moves, 0u);
  EXPECT_NEAR(tree_sah_cost(same.nodes), st.sah_before, 1e-6 * st.sah_before);
  // Reported by the accelerator.
  auto a = make_accelerator("bvh:builder=lbvh,opt=reinsert");
  const BuildStats bs = a->build(s.mesh);
  ASSERT_TRUE(bs.extra.count("sah_before_opt") && bs.extra.count("sah_after_opt"));
  EXPECT_LT(bs.extra.at("sah_after_opt"), bs.extra.at("sah_before_opt"));
}

// The light pass (the default) and the full reinsertion differ in rounds,
// batch and binary leaves (BvhConfig, test_bvh_config.cpp): the light pass
// starts from the tree without it and lowers its SAH cost, the full one
// lowers it further.
TEST(BvhReinsertion, LightPassBetweenNoneAndTheFullPass) {
  const test::NamedMesh s = test::soup(3000, 5);
  auto stats_of = [&](const char* spec) {
    auto a = make_accelerator(spec);
    return a->build(s.mesh);
  };
  const BuildStats light = stats_of("bvh"), none = stats_of("bvh:opt=none"), full = stats_of("bvh:opt=reinsert");
  EXPECT_GE(light.extra.at("opt_rounds"), 1.0);
  EXPECT_LE(light.extra.at("opt_rounds"), 4.0);
  EXPECT_GT(light.extra.at("opt_moves"), 0.0);
  EXPECT_GT(full.extra.at("opt_moves"), light.extra.at("opt_moves"));
  EXPECT_EQ(none.extra.count("opt_rounds"), 0u);
  EXPECT_LT(light.extra.at("sah_tree"), light.extra.at("sah_before_opt"));
  EXPECT_LT(full.extra.at("sah_tree"), light.extra.at("sah_tree"));
  for (const char* bad : {"bvh:opt=heavy", "bvh:opt_batch=0.1", "bvh:opt_rounds=4"})
    EXPECT_THROW(make_accelerator(bad), SpecError) << bad;
}

// Each round re-measures only the nodes the last round's moves changed
// (relinked, refit, or all when the root moved): the same trees as
// measuring every node every round, on meshes, builders and batch sizes
// where many rounds apply many moves.
TEST(BvhReinsertion, IncrementalMeasureGivesTheSameTree) {
  const test::NamedMesh soup = test::soup(4000, 11), big = test::soup(1500, 4, 6.0f);
  for (const TriangleMesh* m : {&soup.mesh, &big.mesh})
    for (const char* b : {"binned", "lbvh"})
      for (double batch : {0.005, 0.05, 0.3}) {
        const Prims p = prims_of(*m);
        BuildOptions bo;
        bo.leaf_threshold = 2;
        const BinaryBvh base = std::string(b) == "lbvh" ? build_lbvh(p.boxes, p.centroids)
                                                         : build_binned_sah(p.boxes, p.centroids, bo);
        ReinsertionOptions fast, full;
        fast.max_rounds = full.max_rounds = 12;
        fast.batch_fraction = full.batch_fraction = batch;
        fast.min_gain = full.min_gain = 0.0;
        full.remeasure_all = true;
        ReinsertionStats sf, sa;
        const BinaryBvh a = optimize_reinsertion(base, fast, &sf), c = optimize_reinsertion(base, full, &sa);
        SCOPED_TRACE(fmt::format("{} batch {}", b, batch));
        if (batch >= 0.05) {
          EXPECT_GT(sf.moves, 0u);
        }
        EXPECT_EQ(sf.moves, sa.moves);
        EXPECT_EQ(sf.rounds, sa.rounds);
        ASSERT_EQ(a.nodes.size(), c.nodes.size());
        EXPECT_EQ(a.prim_ids, c.prim_ids);
        for (size_t i = 0; i < a.nodes.size(); ++i)
          EXPECT_EQ(std::memcmp(&a.nodes[i], &c.nodes[i], sizeof(Bvh2Node)), 0) << "node " << i;
      }
}

// A round's candidates: the k largest non-zero keys, ties by the lower
// index, as a full sort would pick them, with keys spread over many
// histogram buckets, crowded into one, tiny (below the histogram's first
// bucket) and zero, and k below, at and above the number of non-zero keys.
TEST(BvhReinsertion, SelectsTheLargestKeysAsASortWould) {
  auto reference = [](const std::vector<uint32_t>& keys, size_t k) {
    std::vector<uint32_t> idx;
    for (uint32_t i = 0; i < keys.size(); ++i)
      if (keys[i]) idx.push_back(i);
    std::sort(idx.begin(), idx.end(), [&](uint32_t a, uint32_t b) { return keys[a] != keys[b] ? keys[a] > keys[b] : a < b; });
    idx.resize(std::min(k, idx.size()));
    std::sort(idx.begin(), idx.end());
    return idx;
  };
  auto bits = [](float v) {
    uint32_t b;
    std::memcpy(&b, &v, sizeof b);
    return b;
  };
  Pcg32 rng(42, 7);
  std::vector<std::vector<uint32_t>> cases;
  std::vector<uint32_t> spread, crowded, tiny, mixed;
  for (int i = 0; i < 5000; ++i) {
    spread.push_back(bits(std::ldexp(rng.uniform() + 0.5f, static_cast<int>(rng.uniform() * 60.0f) - 30)));
    crowded.push_back(i % 7 == 0 ? 0u : bits(1.0f + 0.01f * rng.uniform()));  // one bucket, many equal keys
    tiny.push_back(i % 3 == 0 ? 0u : 1u + static_cast<uint32_t>(rng.uniform() * 1000.0f));
    mixed.push_back(i % 2 ? bits(static_cast<float>(i % 13)) : 0u);
  }
  cases = {spread, crowded, tiny, mixed, std::vector<uint32_t>(100, 0u), {}};
  for (size_t c = 0; c < cases.size(); ++c)
    for (size_t k : {size_t{0}, size_t{1}, size_t{17}, size_t{500}, size_t{2500}, size_t{4300}, size_t{6000}}) {
      std::vector<uint32_t> got;
      select_largest_keys(cases[c], k, got);
      std::sort(got.begin(), got.end());
      EXPECT_EQ(got, reference(cases[c], k)) << "case " << c << " k " << k;
    }
}

// ---------------------------------------------------------------------------
// Vectorised watertight test and traversal details

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

TEST(BvhTriangleBlock, VectorTestEqualsScalarTestBitForBit) {
  for (uint64_t seed = 1; seed <= 4; ++seed) {
    expect_block_matches_scalar<4>(seed);
    expect_block_matches_scalar<8>(seed);
    expect_block_matches_scalar<16>(seed);
  }
}

TEST(BvhTriangleBlock, PaddingLanesRepeatTheFirstTriangle) {
  std::vector<Vec3f> v = {Vec3f(0, 0, 1), Vec3f(1, 0, 1), Vec3f(0, 1, 1), Vec3f(0, 0, 2), Vec3f(1, 0, 2), Vec3f(0, 1, 2)};
  TriangleBlock<8> blk;
  const uint32_t ids[2] = {4, 9};
  fill_block<8>(blk, ids, 2, [&](uint32_t prim, int c) -> const Vec3f& { return v[(prim == 4 ? 0 : 3) + c]; });
  EXPECT_EQ(blk.count(), 2);
  for (int lane = 2; lane < 8; ++lane) EXPECT_EQ(blk.prim[lane], 4u);
}

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

TEST(BvhPacket, SameAnswersAsSingleRaysBitForBit) {
  // Coherent camera rays (pixel order, a partial last packet) with invalid,
  // axis-parallel, tmin < 0 and short rays mixed in, through bvh:packet=16
  // and the single-ray kernel: every field equal, and occlusion agrees. Coincident copies of a triangle
  // make exact ties, which both must give to the lowest primitive id.
  for (const Reference& ref : references()) {
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

TEST(BvhSimd, SixteenLanesComputeWhatEachLaneDefines) {
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
TEST(BvhSimd, CompressIndexMovesTheMaskedLanesToTheFront) {
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
