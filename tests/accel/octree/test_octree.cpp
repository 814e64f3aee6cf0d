// octree (accel/octree): the parametric child order of Revelles et al. under
// every sign combination of the direction, exact agreement with brute force
// in all three layouts and both assignments (rays starting inside, +-0
// direction components, rays in and along the dividing planes), builder
// invariants and the layouts' memory figures.
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <map>

#include "accel/core/tri_box_overlap.h"
#include "accel/octree/build_octree.h"
#include "accel/octree/traverse_octree.h"
#include "accel/registry.h"
#include "base/mesh_shapes.h"
#include "base/pcg.h"
#include "scenes/procedural.h"
#include "tests/accel_test_util.h"
#include "tests/brute_agreement.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

const char* const kOctreeSpecs[] = {"octree", "octree:assign=straddle", "octree:storage=linear",
                                    "octree:storage=hash", "octree:leaf=1,max_depth=6", "octree:term=count",
                                    "octree:simd=0"};

// ------------------------------------------------------------ child order

// The child of [0,2]^3 (split at 1) holding point p, by position.
uint32_t child_at(const Vec3f& p) {
  return (p.x() > 1.0f ? 1u : 0u) | (p.y() > 1.0f ? 2u : 0u) | (p.z() > 1.0f ? 4u : 0u);
}

TEST(OctreeChildOrder, FrontToBackForEverySignCombination) {
  Pcg32 rng(7, 3);
  for (uint32_t signs = 0; signs < 8; ++signs) {
    for (int trial = 0; trial < 50; ++trial) {
      Vec3f dir(0.3f + rng.uniform(), 0.3f + rng.uniform(), 0.3f + rng.uniform());
      for (int k = 0; k < 3; ++k)
        if (signs >> k & 1u) dir[k] = -dir[k];
      // Through a random point near the centre, from outside the node.
      const Vec3f through(0.6f + 0.8f * rng.uniform(), 0.6f + 0.8f * rng.uniform(), 0.6f + 0.8f * rng.uniform());
      const Vec3f org = through - 4.0f * dir;
      float t0 = -std::numeric_limits<float>::infinity(), t1 = std::numeric_limits<float>::infinity();
      float near_end[3], far_start[3];
      for (int k = 0; k < 3; ++k) {
        const float a = (0.0f - org[k]) / dir[k], b = (2.0f - org[k]) / dir[k];
        t0 = std::max(t0, std::min(a, b));
        t1 = std::min(t1, std::max(a, b));
        near_end[k] = far_start[k] = (1.0f - org[k]) / dir[k];
      }
      const uint32_t neg_mask = signs;
      OctChild kids[8];
      const int n = octree_child_order(t0, t1, near_end, far_start, neg_mask, 0xffu, kids);
      // Expected: the children holding the midpoints between successive plane crossings.
      std::vector<float> events{t0, t1};
      for (int k = 0; k < 3; ++k)
        if (near_end[k] > t0 && near_end[k] < t1) events.push_back(near_end[k]);
      std::sort(events.begin(), events.end());
      ASSERT_EQ(n, static_cast<int>(events.size()) - 1) << "signs " << signs;
      // The first child is the one at the entry point (entry plane rule).
      EXPECT_EQ(kids[0].c, child_at(org + (t0 + 1e-3f) * dir)) << "signs " << signs;
      for (int i = 0; i < n; ++i) {
        const float tm = 0.5f * (events[i] + events[i + 1]);
        EXPECT_EQ(kids[i].c, child_at(org + tm * dir)) << "signs " << signs << " child " << i;
        EXPECT_FLOAT_EQ(kids[i].t0, events[i]);
        EXPECT_FLOAT_EQ(kids[i].t1, events[i + 1]);
      }
    }
  }
}

TEST(OctreeChildOrder, MissingChildrenAreSkippedAndNanPlanesVisitBothSides) {
  // A ray along +x at y = z = 0.5 through [0,2]^3: children 0 then 1.
  const float inf = std::numeric_limits<float>::infinity();
  float near_end[3] = {1.0f, inf, inf}, far_start[3] = {1.0f, inf, inf};
  OctChild kids[8];
  int n = octree_child_order(0.0f, 2.0f, near_end, far_start, 0u, 0xffu, kids);
  ASSERT_EQ(n, 2);
  EXPECT_EQ(kids[0].c, 0u);
  EXPECT_EQ(kids[1].c, 1u);
  n = octree_child_order(0.0f, 2.0f, near_end, far_start, 0u, 0xfeu, kids);
  ASSERT_EQ(n, 1);
  EXPECT_EQ(kids[0].c, 1u);
  // Lying in the y plane (NaN parameter): both y halves, in ray order.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  float ne2[3] = {1.0f, nan, inf}, fs2[3] = {1.0f, nan, inf};
  n = octree_child_order(0.0f, 2.0f, ne2, fs2, 0u, 0xffu, kids);
  ASSERT_EQ(n, 4);
  EXPECT_EQ(kids[0].c, 0u);
  EXPECT_EQ(kids[1].c, 2u);
  EXPECT_EQ(kids[2].c, 1u);
  EXPECT_EQ(kids[3].c, 3u);
  // The same ray going -x (mirrored: a = 1): children 1 then 0.
  float ne3[3] = {1.0f, inf, inf}, fs3[3] = {1.0f, inf, inf};
  n = octree_child_order(0.0f, 2.0f, ne3, fs3, 1u, 0xffu, kids);
  ASSERT_EQ(n, 2);
  EXPECT_EQ(kids[0].c, 1u);
  EXPECT_EQ(kids[1].c, 0u);
}

// The vector child order is the scalar definition, lane by lane: the same
// children, order and intervals, bit for bit, also with NaN (rays in a
// plane), +-inf (parallel rays), ties, missing children and every mirror.
TEST(OctreeChildOrder, VectorFormEqualsScalarDefinition) {
  Pcg32 rng(23, 7);
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  const float specials[] = {nan, inf, -inf, 0.0f, -0.0f, 1.0f};
  auto value = [&](float lo, float hi) {
    const float u = rng.uniform();
    if (u < 0.15f) return specials[static_cast<int>(rng.uniform() * 6.0f) % 6];
    if (u < 0.3f) return 1.0f;  // ties with the other parameters
    return lo + (hi - lo) * rng.uniform();
  };
  int visited = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const float t0 = value(-1.0f, 1.0f), t1 = value(0.0f, 3.0f);
    float near_end[3], far_start[3];
    for (int k = 0; k < 3; ++k) {
      near_end[k] = value(-1.0f, 3.0f);
      far_start[k] = rng.uniform() < 0.5f ? near_end[k] : value(-1.0f, 3.0f);
    }
    const uint32_t neg_mask = static_cast<uint32_t>(trial) & 7u;
    const uint32_t mask = trial % 3 == 0 ? 0xffu : static_cast<uint32_t>(rng.uniform() * 256.0f) & 0xffu;
    OctChild a[8], b[8];
    const int na = octree_child_order(t0, t1, near_end, far_start, neg_mask, mask, a);
    const int nb = octree_child_order_scalar(t0, t1, near_end, far_start, neg_mask, mask, b);
    ASSERT_EQ(na, nb) << "trial " << trial;
    for (int i = 0; i < na; ++i) {
      ASSERT_EQ(a[i].c, b[i].c) << "trial " << trial << " child " << i;
      ASSERT_EQ(std::bit_cast<uint32_t>(a[i].t0), std::bit_cast<uint32_t>(b[i].t0)) << "trial " << trial;
      ASSERT_EQ(std::bit_cast<uint32_t>(a[i].t1), std::bit_cast<uint32_t>(b[i].t1)) << "trial " << trial;
    }
    visited += na;
  }
  EXPECT_GT(visited, 20000);
}

// ------------------------------------------------------------ brute force

TEST(Octree, MatchesBruteForceOnProceduralScenes) {
  const TriangleMesh scenes[] = {make_cornell_box().mesh, make_triangle_soup(300, 3).mesh,
                                 make_uv_sphere(24, 12, Vec3f(0.3f, -0.2f, 0.1f), 0.8f)};
  for (const TriangleMesh& mesh : scenes) {
    test::expect_specs_agree_with_brute(kOctreeSpecs, mesh, {test::rays_at_triangles(mesh, 1500, 11)});
  }
}

// Rays in, along and one ulp beside the dividing planes of the tree, with
// +0 and -0 components along the plane's axis, starting outside and inside.
TEST(Octree, RaysInAndAlongDividingPlanesAndSignedZeros) {
  const TriangleMesh mesh = make_triangle_soup(200, 9).mesh;
  OctreeBuildOptions opt;
  const OctreeTree tree = build_octree(mesh, opt);
  const OctreeCube& cube = tree.cube;
  Pcg32 rng(5, 1);
  std::vector<Ray> rays;
  for (int level = 1; level <= 4; ++level) {
    const uint32_t step = OctreeCube::span(level);
    for (uint32_t i = step; i < OctreeCube::span(0); i += step) {
      for (int k = 0; k < 3; ++k) {
        const float p = cube.plane(k, i);
        for (const float pos : {p, std::nextafter(p, -1e30f), std::nextafter(p, 1e30f)}) {
          for (const float zero : {0.0f, -0.0f}) {
            Vec3f org = cube.box().center() + 0.4f * cube.side * Vec3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f,
                                                                       rng.uniform() - 0.5f);
            org[k] = pos;
            Vec3f dir = test::random_direction(rng);
            dir[k] = zero;
            rays.emplace_back(org, dir);  // starts inside, lies in (or beside) the plane
            rays.emplace_back(org - 2.0f * cube.side * dir, dir);  // starts outside
            // Axis-aligned: along two planes at once.
            Vec3f axis = Vec3f::Zero();
            axis[(k + 1) % 3] = (rng.next() & 1) ? 1.0f : -1.0f;
            axis[k] = zero;
            Vec3f org2 = org;
            org2[(k + 2) % 3] = cube.plane((k + 2) % 3, i);
            rays.emplace_back(org2, axis);
          }
        }
      }
    }
  }
  test::expect_specs_agree_with_brute(kOctreeSpecs, mesh, {rays});
}

TEST(Octree, RaysStartingInsideWithTminTmaxWindows) {
  const TriangleMesh mesh = make_uv_sphere(32, 16);
  Pcg32 rng(3, 2);
  std::vector<Ray> rays;
  for (int i = 0; i < 600; ++i) {
    const Vec3f org(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f);
    Ray r(i % 7 == 0 ? Vec3f::Zero() : org, test::random_direction(rng));  // the centre: on every root plane
    r.tmin = (i % 3 == 0) ? 0.0f : 0.5f * rng.uniform();
    r.tmax = (i % 4 == 0) ? std::numeric_limits<float>::infinity() : r.tmin + 2.0f * rng.uniform();
    rays.push_back(r);
  }
  test::expect_specs_agree_with_brute(kOctreeSpecs, mesh, {rays});
}

// ------------------------------------------------------------ builder

TEST(OctreeBuilder, EveryTriangleIsInEveryLeafItOverlapsAndOnlyThere) {
  const TriangleMesh mesh = make_triangle_soup(150, 4).mesh;
  OctreeBuildOptions opt;
  opt.leaf = 2;
  opt.max_depth = 6;
  const OctreeTree tree = build_octree(mesh, opt);
  struct Item {
    uint32_t node;
    int level;
    uint32_t c[3];
  };
  std::vector<Item> stack{{0u, 0, {0, 0, 0}}};
  size_t leaves = 0;
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    const OctreeNode& n = tree.nodes[it.node];
    if (n.first_child) {
      EXPECT_EQ(n.count(), 0u);  // exact assignment: inner nodes hold nothing
      const uint32_t h = OctreeCube::span(it.level + 1);
      for (uint32_t ch = 0; ch < 8; ++ch) {
        const OctreeNode& kid = tree.nodes[n.first_child + ch];
        EXPECT_EQ((n.mask() >> ch) & 1u, (kid.count() || kid.mask()) ? 1u : 0u);
        stack.push_back({n.first_child + ch, it.level + 1,
                         {it.c[0] + (ch & 1u ? h : 0u), it.c[1] + (ch & 2u ? h : 0u), it.c[2] + (ch & 4u ? h : 0u)}});
      }
      continue;
    }
    ++leaves;
    const uint32_t s = OctreeCube::span(it.level);
    Vec3d lo, hi;
    for (int k = 0; k < 3; ++k) {
      lo[k] = tree.cube.plane(k, it.c[k]);
      hi[k] = tree.cube.plane(k, it.c[k] + s);
    }
    std::vector<uint32_t> listed(tree.refs.begin() + n.first_ref, tree.refs.begin() + n.first_ref + n.count());
    std::sort(listed.begin(), listed.end());
    std::vector<uint32_t> expected;
    for (uint32_t id = 0; id < mesh.num_triangles(); ++id)
      if (triangle_box_overlap(lo, hi, mesh.vertex(id, 0).cast<double>(), mesh.vertex(id, 1).cast<double>(),
                               mesh.vertex(id, 2).cast<double>()))
        expected.push_back(id);
    EXPECT_EQ(listed, expected) << "leaf at level " << it.level;
  }
  EXPECT_GT(leaves, 8u);
}

// term=sah (the default): a node whose triangles each cross most of its
// children stays a leaf (eight children would cost more than the list),
// where term=count with a generous growth limit splits it; well separated
// triangles are split down to small leaves.
TEST(OctreeBuilder, SahTerminationKeepsOverlappingListsAndSplitsSeparableOnes) {
  TriangleMesh planes;
  Pcg32 rng(9, 4);
  for (int i = 0; i < 16; ++i) {
    // Large triangles through the cube's centre, each crossing six octants.
    const Vec3f n = test::random_direction(rng);
    const Vec3f u = n.unitOrthogonal(), v = n.cross(u);
    append_triangle(planes, 3.0f * u, -1.5f * u + 2.6f * v, -1.5f * u - 2.6f * v);
  }
  OctreeBuildOptions sah;
  const OctreeTree kept = build_octree(planes, sah);
  EXPECT_EQ(kept.nodes.size(), 1u);
  EXPECT_EQ(kept.nodes[0].count(), 16u);
  OctreeBuildOptions count;
  count.sah = false;
  count.max_growth = 8.0;
  EXPECT_GT(build_octree(planes, count).nodes.size(), 1u);

  const TriangleMesh soup = make_triangle_soup(2000, 6, 0.02f).mesh;
  const OctreeShape shape = measure_octree(build_octree(soup, sah));
  EXPECT_GT(shape.inner, 8u);
  const size_t full_leaves = shape.leaves - shape.empty_leaves;
  ASSERT_GT(full_leaves, 0u);
  EXPECT_LT(static_cast<double>(shape.references) / static_cast<double>(full_leaves), 8.0) << shape.max_leaf_size;
}

TEST(OctreeBuilder, DegenerateInputsStopAtTheDepthLimit) {
  TriangleMesh mesh;
  for (int i = 0; i < 200; ++i) append_triangle(mesh, Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0));
  auto a = make_accelerator("octree:max_depth=5");
  const BuildStats s = a->build(mesh);
  EXPECT_LE(s.max_depth, 5);
  const Hit h = a->intersect1(Ray(Vec3f(0.2f, 0.2f, 1.0f), Vec3f(0, 0, -1)));
  ASSERT_TRUE(h.valid());
  EXPECT_EQ(h.t, 1.0f);
}

// ------------------------------------------------------------ layouts, stats

TEST(OctreeLayouts, MemoryFiguresAndIdenticalTrees) {
  const TriangleMesh mesh = make_triangle_soup(500, 2).mesh;
  std::map<std::string, BuildStats> st;
  for (const char* spec : {"octree:max_depth=6", "octree:storage=linear", "octree:storage=hash,max_depth=6"})
    st[spec] = make_accelerator(spec)->build(mesh);
  const BuildStats& p = st["octree:max_depth=6"];
  const BuildStats& l = st["octree:storage=linear"];
  const BuildStats& h = st["octree:storage=hash,max_depth=6"];
  // One tree, three layouts.
  for (const BuildStats* s : {&l, &h}) {
    EXPECT_EQ(s->nodes, p.nodes);
    EXPECT_EQ(s->extra.at("references"), p.extra.at("references"));
    EXPECT_EQ(s->extra.at("linear_layout_bytes"), p.extra.at("linear_layout_bytes"));
  }
  EXPECT_EQ(p.extra.at("pointer_layout_bytes"), 12.0 * static_cast<double>(p.nodes));
  const double slots = (std::pow(8.0, p.max_depth + 1) - 1.0) / 7.0;
  EXPECT_EQ(p.extra.at("linear_layout_bytes"), 8.0 * slots);
  EXPECT_LE(p.extra.at("nonempty_nodes"), static_cast<double>(p.nodes));
  EXPECT_GE(p.extra.at("hash_layout_bytes"), 32.0 * p.extra.at("nonempty_nodes") - 1e-9);
  const double shared = static_cast<double>(p.bytes) - p.extra.at("pointer_layout_bytes");
  EXPECT_EQ(static_cast<double>(l.bytes), shared + p.extra.at("linear_layout_bytes"));
  EXPECT_EQ(static_cast<double>(h.bytes), shared + p.extra.at("hash_layout_bytes"));
}

TEST(OctreeLayouts, LinearOverBudgetFailsClearly) {
  const TriangleMesh mesh = make_triangle_soup(2000, 2).mesh;
  auto a = make_accelerator("octree:storage=linear,max_depth=8,leaf=1,budget=1,term=count");
  EXPECT_THROW(a->build(mesh), std::length_error);
}

TEST(OctreeStats, StraddleStoresEachTriangleOnce) {
  const TriangleMesh mesh = make_triangle_soup(400, 8).mesh;
  const BuildStats s = make_accelerator("octree:assign=straddle")->build(mesh);
  EXPECT_EQ(s.extra.at("refs_per_triangle"), 1.0);
  EXPECT_GT(s.extra.at("inner_references"), 0.0);
  const BuildStats e = make_accelerator("octree")->build(mesh);
  EXPECT_GT(e.extra.at("refs_per_triangle"), 1.0);
  EXPECT_EQ(e.extra.at("inner_references"), 0.0);
}

TEST(OctreeParams, BadParametersAreRejected) {
  for (const char* spec : {"octree:leaf=0", "octree:max_depth=21", "octree:max_depth=-1", "octree:assign=loose",
                           "octree:storage=array", "octree:budget=10", "octree:storage=linear,budget=0",
                           "octree:tri=x"})
    EXPECT_THROW(make_accelerator(spec), SpecError) << spec;
}

}  // namespace
}  // namespace raylab
