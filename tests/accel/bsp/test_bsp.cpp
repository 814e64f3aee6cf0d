// General BSP tree (accel/bsp): exact polytope areas (planes through
// vertices and edges, degenerate polytopes), agreement with brute force
// (bit-identical distances) including rays lying in triangle planes (the
// planes the builder splits on), rays through vertices and edges, and the
// candidate-set parameters; the packed 8-byte node encoding (every plane and
// child kept, rays lying in diagonal and triangle planes).
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <stdexcept>

#include "accel/bsp/bsp_packed_node.h"
#include "accel/bsp/build_bsp.h"
#include "accel/bsp/convex_polytope.h"
#include "accel/registry.h"
#include "base/mesh_shapes.h"
#include "base/pcg.h"
#include "scenes/procedural.h"
#include "scenes/scene_registry.h"
#include "tests/accel_test_util.h"
#include "tests/brute_agreement.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

TEST(ConvexPolytope, SplitAreasAreExact) {
  const ConvexPolytope cube = ConvexPolytope::box(Vec3d(0, 0, 0), Vec3d(1, 1, 1));
  EXPECT_DOUBLE_EQ(cube.surface_area(), 6.0);
  struct Case {
    Vec3d n;
    double d, below, above;
  };
  const double hex = 3.0 * std::sqrt(3.0) / 4.0;  // the cube's middle cross-section normal to (1,1,1)
  const Case cases[] = {
      {Vec3d(1, 0, 0), 0.25, 3.0, 5.0},  // x <= 0.25: two unit faces and four 0.25 x 1 strips
      {Vec3d(1, 1, 1).normalized(), 1.5 / std::sqrt(3.0), 3.0 + hex, 3.0 + hex},
      {Vec3d(1, 1, 1).normalized(), 0.0, 0.0, 6.0},                                      // through a vertex
      {Vec3d(1, 1, 0).normalized(), 0.0, 0.0, 6.0},                                      // through an edge
      {Vec3d(1, -1, 0).normalized(), 0.0, 3.0 + std::sqrt(2.0), 3.0 + std::sqrt(2.0)},  // through two edges
      {Vec3d(0, 0, 1), 1.0, 6.0, 0.0},                                                   // along a face
  };
  for (size_t i = 0; i < std::size(cases); ++i) {
    const Case& c = cases[i];
    const auto [al, ar] = cube.split_areas(c.n, c.d);
    const auto parts = cube.split(c.n, c.d);
    EXPECT_NEAR(al, c.below, 1e-12) << "case " << i;
    EXPECT_NEAR(ar, c.above, 1e-12) << "case " << i;
    EXPECT_NEAR(parts.first.surface_area(), c.below, 1e-12) << "case " << i;
    EXPECT_NEAR(parts.second.surface_area(), c.above, 1e-12) << "case " << i;
  }
}

// Areas without building the parts agree with the parts' areas after many
// slanted splits (the cap faces must keep the faces' common orientation).
TEST(ConvexPolytope, SplitAreasAgreeWithSplitsAtDepth) {
  Pcg32 rng(9, 9);
  ConvexPolytope p = ConvexPolytope::box(Vec3d(-1, -2, -3), Vec3d(4, 3, 2));
  for (int i = 0; i < 25; ++i) {
    const Vec3d n = test::random_direction(rng).cast<double>().normalized();
    const auto [lo, hi] = p.extent(n);
    const double d = lo + (0.2 + 0.6 * rng.uniform()) * (hi - lo);
    const auto [al, ar] = p.split_areas(n, d);
    auto parts = p.split(n, d);
    ASSERT_NEAR(al, parts.first.surface_area(), 1e-9 * (al + 1)) << i;
    ASSERT_NEAR(ar, parts.second.surface_area(), 1e-9 * (ar + 1)) << i;
    EXPECT_LT(al, p.surface_area());
    p = (i % 2) ? std::move(parts.first) : std::move(parts.second);
  }
}

TEST(ConvexPolytope, DegeneratePolytopes) {
  // A flat box (zero volume): its two faces carry the area.
  const ConvexPolytope flat = ConvexPolytope::box(Vec3d(0, 0, 2), Vec3d(1, 1, 2));
  EXPECT_DOUBLE_EQ(flat.surface_area(), 2.0);
  const auto [al, ar] = flat.split_areas(Vec3d(1, 0, 0), 0.5);
  EXPECT_NEAR(al, 1.0, 1e-12);
  EXPECT_NEAR(ar, 1.0, 1e-12);
  // A sliver cut off a corner repeatedly stays finite and non-negative.
  ConvexPolytope p = ConvexPolytope::box(Vec3d(0, 0, 0), Vec3d(1, 1, 1));
  for (int i = 0; i < 30; ++i) {
    p = p.split(Vec3d(1, 1, 1).normalized(), std::ldexp(1.0, -i)).first;
    const double a = p.surface_area();
    ASSERT_TRUE(std::isfinite(a) && a >= 0.0) << i;
  }
  // Splitting an empty polytope gives two empty ones.
  const auto e = ConvexPolytope{}.split(Vec3d(1, 0, 0), 0.0);
  EXPECT_TRUE(e.first.empty() && e.second.empty());
}

// A tilted, finely tessellated surface (shared vertices and edges) plus a soup.
TriangleMesh tilted_scene() {
  TriangleMesh m = make_triangle_soup(300, 4).mesh;
  const int k = 12;
  const Vec3f ex = Vec3f(1, 0.3f, 0.2f), ey = Vec3f(-0.2f, 0.4f, 1.0f), o(-0.5f, -0.3f, -0.4f);
  const uint32_t base = static_cast<uint32_t>(m.vertices.size());
  for (int j = 0; j <= k; ++j)
    for (int i = 0; i <= k; ++i) m.vertices.push_back(o + (static_cast<float>(i) / k) * ex + (static_cast<float>(j) / k) * ey);
  for (int j = 0; j < k; ++j)
    for (int i = 0; i < k; ++i) {
      const uint32_t a = base + j * (k + 1) + i, b = a + 1, c = a + k + 1, d = c + 1;
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
    }
  return m;
}

const char* const kBspSpecs[] = {"bsp", "bsp:dirs=3,tplanes=0", "bsp:dirs=7,tplanes=32,bins=4,ct=1,ci=1"};

TEST(Bsp, AgreesWithBruteForceAtVerticesEdgesAndFromSurfaces) {
  const TriangleMesh mesh = tilted_scene();
  const auto rays = test::rays_at_triangles(mesh, 1500, 12);
  const auto secondary = test::secondary_rays(mesh, rays, 13);
  test::expect_specs_agree_with_brute(kBspSpecs, mesh, {rays, secondary});
}

// Rays lying in triangle planes (the split planes of triangle-plane nodes):
// from a vertex along an edge or towards the opposite edge's midpoint, both
// directions, and one ulp beside.
TEST(Bsp, RaysLyingInSplitPlanes) {
  const TriangleMesh mesh = tilted_scene();
  std::vector<Ray> rays;
  for (size_t t = 0; t < mesh.num_triangles(); t += 3) {
    const Vec3f a = mesh.vertex(t, 0), b = mesh.vertex(t, 1), c = mesh.vertex(t, 2);
    for (const Vec3f& d : {Vec3f(b - a), Vec3f(0.5f * (b + c) - a), Vec3f(a - b)}) {
      rays.emplace_back(a - d, d);
      rays.emplace_back(a, d, 0.0f);
      Vec3f o = a - 2.0f * d;
      o.x() = std::nextafter(o.x(), 1e30f);
      rays.emplace_back(o, d);
    }
  }
  BspBuildStats st;
  build_bsp(mesh, BspBuildOptions{}, &st);
  EXPECT_GT(st.triangle_plane_nodes, 0u);
  for (const char* spec : kBspSpecs) {
    auto acc = make_accelerator(spec);
    acc->build(mesh);
    std::string first;
    EXPECT_EQ(test::count_brute_mismatches(*acc, mesh, rays, &first), 0u) << spec << ": " << first;
  }
}

TEST(Bsp, CandidateSetsAndStatistics) {
  const TriangleMesh mesh = tilted_scene();
  BspBuildStats axes, full;
  BspBuildOptions o;
  o.directions = 3;
  o.triangle_planes = 0;
  const BspTree t = build_bsp(mesh, o, &axes);
  EXPECT_EQ(axes.kdop_nodes + axes.triangle_plane_nodes, 0u);
  EXPECT_GT(axes.axis_nodes, 0u);
  for (const auto& n : t.nodes) EXPECT_NE(n.kind(), kBspGeneral);
  build_bsp(mesh, BspBuildOptions{}, &full);
  EXPECT_GT(full.kdop_nodes + full.triangle_plane_nodes, 0u);
  EXPECT_GE(full.references, mesh.num_triangles());
  EXPECT_LE(full.max_depth, full.depth_limit);
  auto a = make_accelerator("bsp");
  const BuildStats s = a->build(mesh);
  EXPECT_GT(s.nodes, 1u);
  EXPECT_GT(s.sah_cost, 0.0);
  EXPECT_GE(s.extra.at("refs_per_triangle"), 1.0);
  EXPECT_THROW(make_accelerator("bsp:dirs=5"), SpecError);
  EXPECT_THROW(make_accelerator("bsp:bins=1"), SpecError);
  EXPECT_THROW(make_accelerator("bsp:tplanes=-1"), SpecError);
  // Depth 0: one leaf holding everything, still correct.
  auto leaf = make_accelerator("bsp:max_depth=0");
  EXPECT_EQ(leaf->build(mesh).nodes, 1u);
  const auto rays = test::rays_at_triangles(mesh, 300, 1);
  EXPECT_EQ(test::count_brute_mismatches(*leaf, mesh, rays), 0u);
}

// With the axes alone the BSP builder is the k-d tree's, including its two
// rules for triangles lying in a split plane (Wald & Havran 2006): they may
// go to either side (a floor's with the room above it), and a plane on the
// region's boundary may cut off a flat cell holding them. The city's boxes
// are all axis-aligned faces; when lying triangles always went below, the
// tree's SAH cost was 12 % above the k-d tree's (35.1 against 31.4).
TEST(Bsp, AxisOnlyTreeMatchesTheKdTreeOnAxisAlignedFaces) {
  const Scene city = load_scene("city:n=4");
  const BuildStats kd = make_accelerator("kdtree")->build(city.mesh);
  const BuildStats bsp = make_accelerator("bsp:dirs=3,tplanes=0")->build(city.mesh);
  EXPECT_NEAR(bsp.sah_cost, kd.sah_cost, 0.01 * kd.sah_cost);
  EXPECT_NEAR(bsp.extra.at("refs_per_triangle"), kd.extra.at("refs_per_triangle"), 0.02 * kd.extra.at("refs_per_triangle"));
  BspBuildOptions o;
  o.directions = 3;
  o.triangle_planes = 0;
  const BspTree t = build_bsp(city.mesh, o);  // K_T = 15: more and smaller cells
  // Flat cells: nodes whose region has zero width along an axis.
  size_t flat = 0;
  struct Item {
    uint32_t node;
    Vec3f lo, hi;
  };
  std::vector<Item> todo{{0, t.bounds.lo, t.bounds.hi}};
  while (!todo.empty()) {
    const Item it = todo.back();
    todo.pop_back();
    const BspNode& n = t.nodes[it.node];
    flat += it.lo.x() == it.hi.x() || it.lo.y() == it.hi.y() || it.lo.z() == it.hi.z();
    if (n.is_leaf()) continue;
    const int k = static_cast<int>(n.kind());
    Item below{n.index, it.lo, it.hi}, above{n.index + 1, it.lo, it.hi};
    below.hi[k] = n.d;
    above.lo[k] = n.d;
    todo.push_back(below);
    todo.push_back(above);
  }
  EXPECT_GT(flat, 0u);
  const auto rays = test::rays_at_triangles(city.mesh, 300, 3);
  EXPECT_EQ(test::mismatches_vs_brute("bsp:dirs=3,tplanes=0", city.mesh, rays), 0u);
}

// A sphere in its box leaves the box's corners empty: slanted planes may cut
// them off, but no plane may cut a region it already bounds (the same float
// plane again, through double rounding of the region's vertices, used to
// shave slivers level after level). Diagonal nodes store the index of their
// direction, whose per-ray constants the traversal uses.
TEST(Bsp, NoPlaneRepeatsOnAPathAndDiagonalNodesNameTheirDirection) {
  const TriangleMesh mesh = make_uv_sphere(24, 12, Vec3f(0.1f, 0.2f, 0.3f), 0.7f);
  BspBuildStats st;
  const BspTree t = build_bsp(mesh, BspBuildOptions{}, &st);
  ASSERT_GT(st.kdop_nodes, 0u);
  size_t fixed = 0;
  for (const BspNode& node : t.nodes) {
    if (node.kind() != kBspFixed) continue;
    ++fixed;
    ASSERT_GE(node.direction(), 3u);
    ASSERT_LT(node.direction(), 13u);
    const Vec3f& u = bsp_fixed_directions()[node.direction()];
    EXPECT_EQ(Vec3f(node.n[0], node.n[1], node.n[2]), u);
  }
  EXPECT_EQ(fixed, st.kdop_nodes);
  struct Item {
    uint32_t node;
    std::vector<uint32_t> path;
  };
  std::vector<Item> todo{{0, {}}};
  while (!todo.empty()) {
    Item it = std::move(todo.back());
    todo.pop_back();
    const BspNode& node = t.nodes[it.node];
    if (node.is_leaf()) continue;
    for (const uint32_t a : it.path) {
      const BspNode& up = t.nodes[a];
      const bool same = up.n[0] == node.n[0] && up.n[1] == node.n[1] && up.n[2] == node.n[2] && up.d == node.d;
      ASSERT_FALSE(same) << "node " << it.node << " repeats the plane of its ancestor " << a;
    }
    it.path.push_back(it.node);
    todo.push_back({node.index, it.path});
    todo.push_back({node.index + 1, it.path});
  }
  EXPECT_EQ(test::mismatches_vs_brute("bsp", mesh, test::rays_at_triangles(mesh, 300, 2)), 0u);
}

// The 26-DOP diagonals are candidates only in regions already cut by a
// slanted plane (diag=polytope, the default): no diagonal node has only
// axis-aligned ancestors. diag=any allows them in box regions too (a sphere's
// empty box corners invite them), and both trees find the same hits.
TEST(Bsp, DiagonalsOnlyBelowASlantedPlaneUnlessAsked) {
  const TriangleMesh mesh = make_uv_sphere(24, 12, Vec3f(0.1f, 0.2f, 0.3f), 0.7f);
  auto diagonals_in_boxes = [](const BspTree& t) {
    size_t count = 0;
    std::vector<std::pair<uint32_t, bool>> todo{{0, false}};  // node, below a slanted plane
    while (!todo.empty()) {
      const auto [index, slanted] = todo.back();
      todo.pop_back();
      const BspNode& n = t.nodes[index];
      if (n.is_leaf()) continue;
      count += n.kind() == kBspFixed && !slanted;
      const bool below_slanted = slanted || n.kind() == kBspFixed || n.kind() == kBspGeneral;
      todo.emplace_back(n.index, below_slanted);
      todo.emplace_back(n.index + 1, below_slanted);
    }
    return count;
  };
  BspBuildStats polytope_only, anywhere;
  BspBuildOptions o;
  EXPECT_EQ(diagonals_in_boxes(build_bsp(mesh, o, &polytope_only)), 0u);
  EXPECT_GT(polytope_only.kdop_nodes, 0u);
  o.diagonals_in_boxes = true;
  EXPECT_GT(diagonals_in_boxes(build_bsp(mesh, o, &anywhere)), 0u);
  const auto rays = test::rays_at_triangles(mesh, 300, 4);
  EXPECT_EQ(test::mismatches_vs_brute("bsp:diag=any", mesh, rays), 0u);
  EXPECT_THROW(make_accelerator("bsp:diag=box"), SpecError);
}

// The traced tree is the builder's repacked into 8-byte nodes: every node
// keeps its plane (axis and diagonal: direction index and offset bits;
// triangle plane: its side-array entry), its child pair or leaf range.
TEST(Bsp, PackedNodesKeepEveryPlaneAndChild) {
  const TriangleMesh mesh = make_uv_sphere(24, 12, Vec3f(0.1f, 0.2f, 0.3f), 0.7f);
  BspBuildStats st;
  const BspTree t = build_bsp(mesh, BspBuildOptions{}, &st);
  ASSERT_GT(st.kdop_nodes, 0u);
  ASSERT_GT(st.triangle_plane_nodes, 0u);
  ASSERT_GT(st.axis_nodes, 0u);
  const BspPackedTree p = pack_bsp_nodes(t.nodes);
  ASSERT_EQ(p.nodes.size(), t.nodes.size());
  EXPECT_EQ(p.planes.size(), st.triangle_plane_nodes);
  size_t fixed = 0;
  for (size_t i = 0; i < t.nodes.size(); ++i) {
    const BspNode& b = t.nodes[i];
    const BspPackedNode& n = p.nodes[i];
    ASSERT_EQ(n.is_leaf(), b.is_leaf()) << i;
    if (b.is_leaf()) {
      EXPECT_EQ(n.first(), b.index);
      EXPECT_EQ(n.count(), b.count());
      continue;
    }
    EXPECT_EQ(n.child(), b.index);
    if (b.kind() == kBspGeneral) {
      ASSERT_TRUE(n.is_free_plane());
      ASSERT_LT(n.plane(), p.planes.size());
      const BspPlane& q = p.planes[n.plane()];
      EXPECT_EQ(Vec3f(q.n[0], q.n[1], q.n[2]), Vec3f(b.n[0], b.n[1], b.n[2]));
      EXPECT_EQ(std::bit_cast<uint32_t>(q.d), std::bit_cast<uint32_t>(b.d));
    } else {
      ++fixed;
      ASSERT_LT(n.code(), 13u);
      EXPECT_EQ(n.code(), b.kind() == kBspFixed ? b.direction() : b.kind());
      EXPECT_EQ(bsp_fixed_directions()[n.code()], Vec3f(b.n[0], b.n[1], b.n[2]));
      EXPECT_EQ(std::bit_cast<uint32_t>(n.offset()), std::bit_cast<uint32_t>(b.d));
    }
  }
  EXPECT_EQ(fixed, st.axis_nodes + st.kdop_nodes);
  // 28 bits of child index / leaf count: a clear error beyond.
  EXPECT_EQ(BspPackedNode::leaf(7, kBspPackedMaxIndex).count(), kBspPackedMaxIndex);
  EXPECT_THROW(BspPackedNode::leaf(0, kBspPackedMaxIndex + 1), std::length_error);
}

// Rays lying in the planes of diagonal and triangle-plane nodes (as far as
// float allows: exactly parallel where the normal has a zero component), one
// ulp beside them, and starting on them: the packed walk's per-ray
// direction constants and side-array planes visit both sides when the ray is
// within the margin, so every hit is found (bit-identical to brute force).
TEST(Bsp, RaysLyingInDiagonalAndTrianglePlanes) {
  const TriangleMesh mesh = make_uv_sphere(24, 12, Vec3f(0.1f, 0.2f, 0.3f), 0.7f);
  const BspTree t = build_bsp(mesh, BspBuildOptions{}, nullptr);
  const Vec3d center(0.1, 0.2, 0.3);
  std::vector<Ray> rays;
  size_t diagonal = 0, triangle = 0;
  for (const BspNode& b : t.nodes) {
    if (b.is_leaf() || b.kind() < 3) continue;
    size_t& taken = b.kind() == kBspFixed ? diagonal : triangle;
    if (taken >= 40) continue;
    ++taken;
    const Vec3d n = Vec3d(b.n[0], b.n[1], b.n[2]).normalized();
    const Vec3d c = center - (n.dot(center) - static_cast<double>(b.d)) * n;  // the centre projected on the plane
    const Vec3d u = n.unitOrthogonal(), v = n.cross(u);
    for (int k = 0; k < 6; ++k) {
      const double a = k * 3.14159265358979 / 6.0;
      const Vec3f d = (std::cos(a) * u + std::sin(a) * v).cast<float>();
      const Vec3f o = (c - 2.0 * d.cast<double>()).cast<float>();
      rays.emplace_back(o, d);
      rays.emplace_back(c.cast<float>(), d, 0.0f);
      Vec3f beside = o;
      beside[k % 3] = std::nextafter(beside[k % 3], 1e30f);
      rays.emplace_back(beside, d);
    }
    // Exactly parallel: along a zero component of a face diagonal.
    for (int a = 0; a < 3; ++a) {
      if (b.n[a] != 0.0f) continue;
      Vec3f d = Vec3f::Zero();
      d[a] = 1.0f;
      rays.emplace_back((c - 2.0 * d.cast<double>()).cast<float>(), d);
    }
  }
  ASSERT_GT(diagonal, 0u);
  ASSERT_GT(triangle, 0u);
  for (const char* spec : {"bsp", "bsp:dirs=7"}) {
    auto acc = make_accelerator(spec);
    acc->build(mesh);
    std::string first;
    EXPECT_EQ(test::count_brute_mismatches(*acc, mesh, rays, &first), 0u) << spec << ": " << first;
  }
}

}  // namespace
}  // namespace raylab
