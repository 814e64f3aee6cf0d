// Havran's per-ray counts (accel/core/hit_recorder.h): steps, leaves, empty
// leaves and triangle tests on hand-made scenes whose path is known, and for
// every registered structure the rule that a ray that hits visited a leaf.
#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "accel/registry.h"
#include "tests/accel_test_util.h"

namespace raylab {
namespace {

// Small walls facing +x at the given x positions, in y [0, 0.2]; each is two
// triangles (a quad) reaching up to z = `top`. The scene is 0.2 x 0.2 across
// and ~8 long, so every spatial median split is along x.
TriangleMesh walls(const std::vector<std::pair<float, float>>& x_top) {
  TriangleMesh m;
  for (const auto& [x, top] : x_top) {
    const uint32_t b = static_cast<uint32_t>(m.vertices.size());
    m.vertices.push_back(Vec3f(x, 0.0f, 0.0f));
    m.vertices.push_back(Vec3f(x, 0.2f, 0.0f));
    m.vertices.push_back(Vec3f(x, 0.2f, top));
    m.vertices.push_back(Vec3f(x, 0.0f, top));
    m.triangles.push_back({b, b + 1, b + 2});
    m.triangles.push_back({b, b + 2, b + 3});
  }
  return m;
}

// Low walls (up to z = 0.1) at x = 0.1 and 2.0, a full wall (z = 0.2) at 7.9.
// The ray along +x at z = 0.15 passes over the low walls and hits the last.
const TriangleMesh kThreeWalls = walls({{0.1f, 0.1f}, {2.0f, 0.1f}, {7.9f, 0.2f}});
const TriangleMesh kTwoWalls = walls({{0.1f, 0.1f}, {7.9f, 0.2f}});

Ray along_x(float z = 0.15f) {
  Ray r;
  r.org = Vec3f(-1.0f, 0.1f, z);
  r.dir = Vec3f(1.0f, 0.0f, 0.0f);
  return r;
}

TraversalStats trace_one(const std::string& spec, const TriangleMesh& mesh, const Ray& ray, Hit* hit = nullptr) {
  auto accel = make_accelerator(spec);
  accel->build(mesh);
  std::vector<Ray> rays{ray};
  std::vector<Hit> hits(1);
  TraversalStats st;
  accel->intersect(rays, hits, &st);
  if (hit) *hit = hits[0];
  return st;
}

// Havran's four counts of one traced ray.
void expect_counts(const TraversalStats& st, uint64_t steps, uint64_t leaves, uint64_t empty_leaves,
                   uint64_t triangle_tests) {
  EXPECT_EQ(st.rays, 1u);
  EXPECT_EQ(st.steps, steps);
  EXPECT_EQ(st.leaves, leaves);
  EXPECT_EQ(st.empty_leaves, empty_leaves);
  EXPECT_EQ(st.triangle_tests, triangle_tests);
}

TEST(TraversalCounts, KdTreeMedianSplitsCountStepsLeavesAndTheEmptyLeaf) {
  // The spatial median builder, one triangle pair per leaf: root [0.1, 7.9]
  // split at 4.0; its left [0.1, 4.0] at 2.05; that one's left [0.1, 2.05] at
  // 1.075 (the walls at 0.1 and 2.0 apart); [2.05, 4.0] is an empty leaf.
  // The ray enters root, left, left-left (3 steps), the leaves of the two low
  // walls (2 triangles each, missed), the empty leaf, and the far wall's leaf.
  Hit hit;
  const TraversalStats st = trace_one("kdtree:builder=median,leaf=2", kThreeWalls, along_x(), &hit);
  ASSERT_TRUE(hit.valid());
  EXPECT_GE(hit.prim, 4u);  // the far wall
  expect_counts(st, 3, 3, 1, 6);
  // A ray above the scene misses the root cell: counted, nothing visited.
  expect_counts(trace_one("kdtree:builder=median,leaf=2", kThreeWalls, along_x(5.0f)), 0, 0, 0, 0);
}

TEST(TraversalCounts, GridCountsEveryCellAsAStepAndEmptyCellsAsEmptyLeaves) {
  // Four cells along x over [0.1, 7.9]: the low wall in cell 0, the far wall
  // in cell 3, cells 1 and 2 empty. The ray crosses all four.
  for (const char* spec : {"grid:res=4x1x1,skip=0", "hashgrid:res=4x1x1"}) {
    SCOPED_TRACE(spec);
    Hit hit;
    const TraversalStats st = trace_one(spec, kTwoWalls, along_x(), &hit);
    ASSERT_TRUE(hit.valid());
    expect_counts(st, 4, 2, 2, 4);
    EXPECT_EQ(st.nodes_visited, 4u);
  }
}

TEST(TraversalCounts, BinaryBvhCountsItsInnerNodeAndTheLeafItEnters) {
  // Two leaves under one root: the ray passes over the low wall's box, so it
  // enters the root (1 step, 3 boxes tested: the root's and two children's)
  // and the far wall's leaf only.
  Hit hit;
  const TraversalStats st = trace_one("bvh:layout=bvh2,leaf=2", kTwoWalls, along_x(), &hit);
  ASSERT_TRUE(hit.valid());
  expect_counts(st, 1, 1, 0, 2);
  EXPECT_EQ(st.nodes_visited, 3u);
}

TEST(TraversalCounts, BruteForceIsOneLeafWithoutSteps) {
  expect_counts(trace_one("brute", kThreeWalls, along_x()), 0, 1, 0, 6);
}

// Every structure with counters: each ray that hits tested a triangle in a
// leaf it visited, so leaves >= hits; every structure but brute force takes
// steps; the counters are deterministic.
TEST(TraversalCounts, EveryStructureCountsALeafForEachHit) {
  const test::NamedMesh soup = test::soup(400, 3);
  const std::vector<Ray> rays = test::mesh_test_rays(soup.mesh, 256, 5);
  size_t checked = 0;
  for (const auto& spec : coverage_specs()) {
    const AcceleratorInfo& info = accelerator_info(Spec::parse(spec).name);
    if (!info.caps.per_ray_counters) continue;
    SCOPED_TRACE(spec);
    const test::CountedHits a = test::counted_hits(spec, soup.mesh, rays);
    const test::CountedHits b = test::counted_hits(spec, soup.mesh, rays);
    size_t hits = 0;
    for (const Hit& h : a.hits) hits += h.valid();
    ASSERT_GT(hits, 0u);
    EXPECT_GE(a.stats.leaves, hits);
    EXPECT_GE(a.stats.triangle_tests, a.stats.leaves);
    if (info.name != "brute") {
      EXPECT_GT(a.stats.steps, 0u);
    }
    EXPECT_EQ(a.stats.steps, b.stats.steps);
    EXPECT_EQ(a.stats.leaves, b.stats.leaves);
    EXPECT_EQ(a.stats.empty_leaves, b.stats.empty_leaves);
    ++checked;
  }
  EXPECT_GT(checked, 10u);
}

}  // namespace
}  // namespace raylab
