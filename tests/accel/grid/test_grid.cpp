// The grids (grid, hashgrid, grid2) against the brute-force reference on
// Cornell, soups, a flat scene and a teapot in a stadium; statistics, memory
// budget and bad specs (agreement with Embree:
// tests/checks/test_structures_verify.cpp; the machinery they share with the
// other grid structures: tests/accel/core/grid/).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <tuple>
#include <vector>

#include "accel/grid/hash_grid.h"
#include "accel/grid/two_level_grid.h"
#include "accel/grid/uniform_grid.h"
#include "accel/registry.h"
#include "tests/accel_test_util.h"
#include "tests/brute_agreement.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

using test::kStadiumObject;

// ---------------------------------------------------------------------------
// Comparing an accelerator with the brute-force reference (same watertight
// test, so answers must agree up to ties within 1e-6 of the distance).

using test::flat_tiles_mesh;
using test::mesh_test_rays;
using test::teapot_in_stadium_mesh;

// The grid made from `spec` against brute force; overlapping coplanar
// triangles tie up to rounding of the coordinates (1e-6).
test::Disagreement grid_vs_brute(const TriangleMesh& mesh, const std::string& spec, const std::vector<Ray>& rays,
                                 const test::BruteReference& ref) {
  auto accel = make_accelerator(spec);
  accel->build(mesh);
  return test::compare_with_brute(*accel, ref, rays, {.tie_rel = 1e-6f});
}

const std::vector<std::string> kGridSpecs = {"grid", "hashgrid", "grid2", "grid:assign=bbox", "hashgrid:density=4",
                                             "grid2:top=1,density=2", "grid:res=7x3x5"};

void expect_all_agree(const TriangleMesh& mesh, const std::vector<Ray>& rays, const std::string& what) {
  const test::BruteReference reference = test::brute_reference(mesh, rays);
  for (const auto& spec : kGridSpecs) {
    const test::Disagreement m = grid_vs_brute(mesh, spec, rays, reference);
    EXPECT_EQ(m.closest, 0u) << spec << " on " << what << " (" << rays.size() << " rays):\n" << m.examples;
    EXPECT_EQ(m.occlusion, 0u) << spec << " on " << what << ":\n" << m.examples;
  }
}

// ---------------------------------------------------------------------------
// Accelerators against brute force

TEST(GridAccel, CornellBoxAgreesWithBrute) {
  const test::NamedMesh s{"cornell", cornell_box_mesh()};
  expect_all_agree(s.mesh, mesh_test_rays(s.mesh, 4000, 1), "cornell");
}

TEST(GridAccel, RandomSoupsAgreeWithBrute) {
  for (const auto& [n, size, seed] : {std::tuple{2000, 1.0f, 1}, std::tuple{5000, 4.0f, 2}, std::tuple{300, 20.0f, 3}}) {
    const test::NamedMesh s = test::soup(n, seed, size);
    expect_all_agree(s.mesh, mesh_test_rays(s.mesh, 3000, seed), s.name);
  }
}

TEST(GridAccel, AxisAlignedFlatSceneAgreesWithBrute) {
  const TriangleMesh m = flat_tiles_mesh(16, 400, 4);
  std::vector<Ray> rays = mesh_test_rays(m, 3000, 5);
  // Rays parallel to the plane, in it, and through it along +-z exactly.
  Pcg32 rng(6, 2);
  for (int i = 0; i < 500; ++i) {
    const float x = rng.uniform(), y = rng.uniform();
    rays.emplace_back(Vec3f(x, y, 2.0f), Vec3f(0.0f, -0.0f, -1.0f));
    rays.emplace_back(Vec3f(x, y, -1.0f), Vec3f(-0.0f, 0.0f, 1.0f));
    rays.emplace_back(Vec3f(-1, y, 0.5f), Vec3f(1, 0, 0));           // in the plane
    rays.emplace_back(Vec3f(x, y, 0.6f), Vec3f(1, rng.uniform(), 0));  // parallel above
  }
  expect_all_agree(m, rays, "flat scene");
  // And the plane is really hit from both sides.
  auto g = make_accelerator("grid");
  g->build(m);
  const Hit h = g->intersect1(Ray(Vec3f(0.3f, 0.3f, 2.0f), Vec3f(0, 0, -1)));
  ASSERT_TRUE(h.valid());
  EXPECT_FLOAT_EQ(h.t, 1.5f);
}

TEST(GridAccel, TeapotInAStadiumAgreesWithBrute) {
  const TriangleMesh m = teapot_in_stadium_mesh();
  std::vector<Ray> rays = mesh_test_rays(m, 2000, 7);
  // Rays from around the room aimed at the small dense object.
  Pcg32 rng(8, 4);
  for (int i = 0; i < 2000; ++i) {
    const Vec3f org(800 * rng.uniform() - 400, 800 * rng.uniform() - 400, 800 * rng.uniform() - 400);
    const Vec3f target = kStadiumObject + 0.6f * test::random_direction(rng);
    rays.emplace_back(org, (target - org).normalized());
  }
  const test::BruteReference reference = test::brute_reference(m, rays);
  for (const auto& spec : {"grid", "hashgrid", "grid2", "grid2:top=0.01"}) {
    const test::Disagreement mm = grid_vs_brute(m, spec, rays, reference);
    EXPECT_EQ(mm.closest, 0u) << spec << ":\n" << mm.examples;
    EXPECT_EQ(mm.occlusion, 0u) << spec << ":\n" << mm.examples;
  }
}

TEST(GridAccel, TwoLevelGridStaysUsableInTheStadium) {
  // Counted work, not time: rays aimed at the dense object test far fewer
  // triangles in grid2, whose sub-grid adapts to the object.
  const TriangleMesh m = teapot_in_stadium_mesh();
  std::vector<Ray> rays;
  Pcg32 rng(9, 4);
  for (int i = 0; i < 2000; ++i) {
    const Vec3f org = kStadiumObject + Vec3f(0, 0, 0) + 20.0f * test::random_direction(rng);
    const Vec3f target = kStadiumObject + 0.5f * test::random_direction(rng);
    rays.emplace_back(org, (target - org).normalized());
  }
  auto tests_per_ray = [&](const std::string& spec) {
    const test::CountedHits traced = test::counted_hits(spec, m, rays);
    size_t hit_count = 0;
    for (const Hit& h : traced.hits) hit_count += h.valid();
    EXPECT_EQ(hit_count, rays.size()) << spec;  // every ray hits the object or the room
    return static_cast<double>(traced.stats.triangle_tests) / static_cast<double>(traced.stats.rays);
  };
  const double grid = tests_per_ray("grid");
  const double grid2 = tests_per_ray("grid2");
  auto two = make_accelerator("grid2");
  const BuildStats st = two->build(m);
  EXPECT_GT(st.extra.at("large_refs"), 0.0);  // the walls and the table top stay at the top level
  EXPECT_GT(st.extra.at("subgrids"), 0.0);
  EXPECT_GT(grid, 500.0);           // the single grid collapses: the object sits in a few cells
  EXPECT_LT(grid2 * 10.0, grid);    // the two-level grid does not
  EXPECT_LT(grid2, 50.0);
}

TEST(GridAccel, MeshFarFromTheOriginCostsWhatItCostsAtTheOrigin) {  // and the wide BVH
  // A cell margin sized from the absolute coordinates would give a sphere
  // of radius 8 at 3e5 a margin (0.6) as large as a cell, and every cell
  // would list its neighbours' triangles. Counted work, not time:
  // the same rays (moved with the mesh) visit about as many cells and test
  // about as many triangles far away as at the origin, and all hit.
  const Vec3f offset(3e5f, 1e5f, -2e5f);
  const float radius = 8.0f;
  const TriangleMesh near_mesh = make_uv_sphere(96, 48, Vec3f::Zero(), radius);
  const TriangleMesh far_mesh = make_uv_sphere(96, 48, offset, radius);
  std::vector<Ray> near_rays, far_rays;
  Pcg32 rng(17, 3);
  for (int i = 0; i < 600; ++i) {
    // From inside towards the shell, and from outside at the sphere.
    const Vec3f org = (i % 2 ? 0.5f : 2.5f) * radius * test::random_direction(rng);
    const Vec3f target = 0.5f * radius * test::random_direction(rng);
    const Vec3f dir = i % 2 ? test::random_direction(rng) : Vec3f((target - org).normalized());
    near_rays.emplace_back(org, dir);
    far_rays.emplace_back(Vec3f(org + offset), dir);
  }
  auto work = [](const std::string& spec, const TriangleMesh& m, const std::vector<Ray>& rays) {
    auto a = make_accelerator(spec);
    a->build(m);
    std::vector<Hit> hits(rays.size());
    TraversalStats st;
    a->intersect(rays, hits, &st);
    size_t hit_count = 0;
    for (const Hit& h : hits) hit_count += h.valid();
    EXPECT_EQ(hit_count, rays.size()) << spec;  // every ray meets the closed sphere
    return std::pair<double, double>(static_cast<double>(st.nodes_visited) / static_cast<double>(rays.size()),
                                     static_cast<double>(st.triangle_tests) / static_cast<double>(rays.size()));
  };
  for (const std::string spec : {"grid", "hashgrid", "grid2"}) {
    const auto [near_cells, near_tests] = work(spec, near_mesh, near_rays);
    const auto [far_cells, far_tests] = work(spec, far_mesh, far_rays);
    EXPECT_LT(far_cells, 1.25 * near_cells) << spec;
    EXPECT_GT(far_cells, 0.8 * near_cells) << spec;
    EXPECT_LT(far_tests, 1.5 * near_tests) << spec;  // the old margin: 5-11x
  }
  // The wide BVH's FMA box test is exact only to 2^-22 |origin| (0.07 at 3e5):
  // on a radius-1 sphere there every ray entered the boxes of its neighbours
  // too (40x the triangle tests) until such rays took the exact kernel.
  const TriangleMesh near_small = make_uv_sphere(128, 64, Vec3f::Zero(), 1.0f);
  const TriangleMesh far_small = make_uv_sphere(128, 64, offset, 1.0f);
  std::vector<Ray> near_small_rays, far_small_rays;
  for (const Ray& r : near_rays) {
    near_small_rays.emplace_back(Vec3f(r.org / radius), r.dir);
    far_small_rays.emplace_back(Vec3f(r.org / radius + offset), r.dir);
  }
  for (const std::string spec : {"bvh", "bvh:layout=bvh4", "bvh:packet=16"}) {
    const auto [near_nodes, near_tests] = work(spec, near_small, near_small_rays);
    const auto [far_nodes, far_tests] = work(spec, far_small, far_small_rays);
    EXPECT_LT(far_nodes, 1.5 * near_nodes) << spec;
    EXPECT_LT(far_tests, 1.5 * near_tests) << spec;
  }
}

TEST(GridAccel, HitFarAlongASpanningTriangleWaitsForNearerCells) {
  // T is nearly parallel to the ray and listed in every cell the ray walks;
  // its hit at x = 9 is found in the first cell and must not be accepted
  // there: the small triangle S at x = 5 is nearer.
  TriangleMesh m;
  append_triangle(m, {0, 0, 0.59f}, {0, 1, 0.59f}, {10, 0.5f, 0.49f});  // T, id 0
  append_triangle(m, {5, 0.3f, 0.3f}, {5, 0.7f, 0.3f}, {5, 0.5f, 0.7f});  // S, id 1
  append_triangle(m, {0, 0, 0}, {10, 0, 0}, {10, 1, 1});                 // grows the box, id 2
  const Ray r(Vec3f(-0.5f, 0.5f, 0.5f), Vec3f(1, 0, 0));
  for (const auto& spec : {"grid:res=10x1x1", "hashgrid:res=10x1x1", "grid2:top=1,density=1", "grid", "grid:res=40x3x3"}) {
    auto a = make_accelerator(spec);
    a->build(m);
    const Hit h = a->intersect1(r);
    ASSERT_TRUE(h.valid()) << spec;
    EXPECT_EQ(h.prim, 1u) << spec;
    EXPECT_FLOAT_EQ(h.t, 5.5f) << spec;
    // Without S the far hit on T is found (the mailbox must not lose it).
    TriangleMesh m2 = m;
    m2.triangles.erase(m2.triangles.begin() + 1);
    auto b = make_accelerator(spec);
    b->build(m2);
    const Hit h2 = b->intersect1(r);
    ASSERT_TRUE(h2.valid()) << spec;
    EXPECT_EQ(h2.prim, 0u) << spec;
    EXPECT_NEAR(h2.t, 9.5f, 1e-4f) << spec;
  }
}

TEST(GridAccel, TminTmaxWindowsAndStartingInside) {
  TriangleMesh m;
  for (int i = 0; i < 5; ++i) {
    const float x = 1.0f + i;
    append_triangle(m, {x, -1, -1}, {x, 3, -1}, {x, -1, 3});  // planes x = 1..5 covering y,z in [0,1]
  }
  for (const auto& spec : {"grid", "hashgrid", "grid2", "grid:res=3x2x2"}) {
    auto a = make_accelerator(spec);
    a->build(m);
    const Vec3f dir(1, 0, 0);
    const Vec3f org(0, 0.25f, 0.25f);
    EXPECT_EQ(a->intersect1(Ray(org, dir)).prim, 0u) << spec;
    EXPECT_EQ(a->intersect1(Ray(org, dir, 1.5f)).prim, 1u) << spec;          // tmin skips x = 1
    EXPECT_EQ(a->intersect1(Ray(org, dir, 2.0f)).prim, 1u) << spec;          // tmin exactly at x = 2
    EXPECT_FALSE(a->intersect1(Ray(org, dir, 0.0f, 0.99f)).valid()) << spec;  // tmax before x = 1
    EXPECT_EQ(a->intersect1(Ray(org, dir, 0.0f, 1.0f)).prim, 0u) << spec;    // tmax exactly at x = 1
    EXPECT_FALSE(a->intersect1(Ray(org, dir, 5.5f)).valid()) << spec;
    EXPECT_EQ(a->intersect1(Ray(Vec3f(3.5f, 0.5f, 0.5f), -dir)).prim, 2u) << spec;  // from inside, backwards
    EXPECT_EQ(a->intersect1(Ray(Vec3f(3.0f, 0.5f, 0.5f), dir)).prim, 2u) << spec;  // on a triangle: t = 0 hit
    EXPECT_TRUE(a->occluded1(Ray(org, dir, 3.5f, 4.5f))) << spec;
    EXPECT_FALSE(a->occluded1(Ray(org, dir, 3.2f, 3.8f))) << spec;
    // Missing the grid, pointing away, invalid rays.
    EXPECT_FALSE(a->intersect1(Ray(Vec3f(0, 10, 0), dir)).valid()) << spec;
    EXPECT_FALSE(a->intersect1(Ray(org, -dir)).valid()) << spec;
    EXPECT_FALSE(a->intersect1(Ray(org, Vec3f::Zero())).valid()) << spec;
    EXPECT_FALSE(a->intersect1(Ray(org, dir, 2.0f, 1.0f)).valid()) << spec;
    EXPECT_FALSE(a->intersect1(Ray(Vec3f(NAN, 0, 0), dir)).valid()) << spec;
    EXPECT_FALSE(a->occluded1(Ray(org, Vec3f::Zero()))) << spec;
  }
}

TEST(GridAccel, OriginsOnCellBoundariesAndRaysAlongThem) {
  // Origins placed exactly on the grid's cell boundaries (as floats), rays
  // along and across them, compared with brute force.
  const test::NamedMesh s = test::soup(3000, 11, 2.0f);
  GridOptions opt;
  opt.res = GridRes{8, 8, 8};
  BuildStats st;
  const UniformGrid g = build_uniform_grid(s.mesh, opt, st);
  std::vector<Ray> rays;
  Pcg32 rng(12, 9);
  for (int i = 0; i < 3000; ++i) {
    Vec3f org;
    for (int a = 0; a < 3; ++a) org[a] = static_cast<float>(g.dda.boundary(a, static_cast<int64_t>(rng.next() % 9)));
    Vec3f dir = test::random_direction(rng);
    const int zeroed = static_cast<int>(rng.next() % 4);
    if (zeroed < 3) dir[zeroed] = (i % 2) ? 0.0f : -0.0f;
    if (i % 7 == 0) dir = Vec3f::Unit(i % 3) * ((i % 2) ? 1.0f : -1.0f);
    rays.emplace_back(org, dir);
  }
  const test::BruteReference reference = test::brute_reference(s.mesh, rays);
  for (const auto& spec : {"grid:res=8x8x8", "hashgrid:res=8x8x8", "grid", "grid2"}) {
    const test::Disagreement m = grid_vs_brute(s.mesh, spec, rays, reference);
    EXPECT_EQ(m.closest, 0u) << spec << ":\n" << m.examples;
    EXPECT_EQ(m.occlusion, 0u) << spec << ":\n" << m.examples;
  }
}

TEST(GridAccel, DegenerateInputs) {
  // Empty mesh: builds, every ray misses.
  TriangleMesh empty;
  // 1000 copies of one triangle, and degenerate (zero-area) triangles.
  TriangleMesh copies;
  for (int i = 0; i < 1000; ++i) append_triangle(copies, {0, 0, 0}, {1, 0, 0}, {0, 1, 0});
  append_triangle(copies, {0, 0, 1}, {1, 1, 1}, {2, 2, 1});  // collinear
  append_triangle(copies, {3, 3, 3}, {3, 3, 3}, {3, 3, 3});  // a point
  for (const auto& spec : {"grid", "hashgrid", "grid2", "grid:assign=bbox"}) {
    auto a = make_accelerator(spec);
    a->build(empty);
    EXPECT_FALSE(a->intersect1(Ray(Vec3f::Zero(), Vec3f::UnitX())).valid());
    EXPECT_FALSE(a->occluded1(Ray(Vec3f::Zero(), Vec3f::UnitX())));
    auto b = make_accelerator(spec);
    const BuildStats st = b->build(copies);
    EXPECT_GE(st.nodes, 1u);
    const Hit h = b->intersect1(Ray(Vec3f(0.2f, 0.2f, 5), Vec3f(0, 0, -1)));
    ASSERT_TRUE(h.valid()) << spec;
    EXPECT_FLOAT_EQ(h.t, 5.0f);
    EXPECT_LT(h.prim, 1000u);
  }
  expect_all_agree(copies, mesh_test_rays(copies, 500, 13), "copies");
}

// ---------------------------------------------------------------------------
// Statistics, memory, budget, parameters

TEST(GridStats, BuildAndTraversalFiguresAreConsistent) {
  const test::NamedMesh s = test::soup(4000, 3, 1.0f);
  for (const auto& spec : {"grid", "hashgrid", "grid2"}) {
    auto a = make_accelerator(spec);
    const BuildStats st = a->build(s.mesh);
    EXPECT_GT(st.bytes, s.mesh.num_triangles() * sizeof(LeafTriangle)) << spec;
    EXPECT_GT(st.nodes, 0u);
    EXPECT_GT(st.leaves, 0u);
    EXPECT_LE(st.leaves, st.nodes);
    for (const char* key : {"empty_fraction", "refs_per_triangle", "mean_tris_per_nonempty_cell", "max_tris_per_cell"})
      ASSERT_TRUE(st.extra.count(key)) << spec << " " << key;
    EXPECT_GE(st.extra.at("refs_per_triangle"), 1.0) << spec;
    EXPECT_GE(st.extra.at("empty_fraction"), 0.0);
    EXPECT_LT(st.extra.at("empty_fraction"), 1.0);
    EXPECT_GE(st.extra.at("max_tris_per_cell"), st.extra.at("mean_tris_per_nonempty_cell"));
    const std::vector<Ray> rays = mesh_test_rays(s.mesh, 1000, 2);
    std::vector<Hit> hits(rays.size());
    TraversalStats ts;
    a->intersect(rays, hits, &ts);
    EXPECT_EQ(ts.rays, rays.size());
    EXPECT_GT(ts.nodes_visited, rays.size() / 2) << spec;
    EXPECT_GT(ts.triangle_tests, 0u);
    EXPECT_LT(ts.triangle_tests, rays.size() * s.mesh.num_triangles() / 20) << spec;  // far below brute force
    // The uninstrumented kernel gives the same answers.
    std::vector<Hit> plain(rays.size());
    a->intersect(rays, plain);
    for (size_t i = 0; i < rays.size(); ++i) EXPECT_EQ(plain[i].prim, hits[i].prim);
  }
  // Dense grid: cells = resolution product, bbox assignment adds references.
  auto exact = make_accelerator("grid:res=10x12x14");
  auto bbox = make_accelerator("grid:res=10x12x14,assign=bbox");
  const BuildStats se = exact->build(s.mesh), sb = bbox->build(s.mesh);
  EXPECT_EQ(se.nodes, 10u * 12u * 14u);
  EXPECT_EQ(se.extra.at("res_y"), 12.0);
  EXPECT_GT(sb.extra.at("refs_per_triangle"), se.extra.at("refs_per_triangle"));
  EXPECT_EQ(se.max_depth, 1);
  auto two = make_accelerator("grid2");
  EXPECT_EQ(two->build(s.mesh).max_depth, 2);
}

TEST(GridMemory, HashGridBytesFollowOccupiedCellsDenseGridBytesFollowResolution) {
  // Teapot in a stadium: at high density almost every dense cell is empty.
  const TriangleMesh m = teapot_in_stadium_mesh();
  struct Figures {
    double bytes, cells, occupied, refs;
  };
  auto figures = [&](const std::string& spec) {
    auto a = make_accelerator(spec);
    const BuildStats st = a->build(m);
    return Figures{static_cast<double>(st.bytes - m.num_triangles() * sizeof(LeafTriangle)), st.extra.at("cells"),
                   st.extra.at("nonempty_cells"), st.extra.at("refs")};
  };
  std::vector<Figures> dense, hashed;
  for (const char* density : {"1", "8", "64", "512"}) {
    // The scalar layout (simd=0): ids into one copy of each triangle.
    dense.push_back(figures(std::string("grid:simd=0,skip=0,density=") + density));
    hashed.push_back(figures(std::string("hashgrid:simd=0,density=") + density));
    const Figures& d = dense.back();
    const Figures& h = hashed.back();
    EXPECT_EQ(d.cells, h.cells) << density;
    EXPECT_EQ(d.occupied, h.occupied) << density;
    EXPECT_EQ(d.refs, h.refs) << density;
    // Dense: 4 bytes per cell and per reference. Hashed: 32 bytes per
    // occupied cell (16-byte slots, load factor 1/2) and 4 per reference.
    EXPECT_EQ(d.bytes, 4.0 * (d.cells + 1) + 4.0 * d.refs + sizeof(UniformGrid)) << density;
    EXPECT_EQ(h.bytes, 32.0 * h.occupied + 4.0 * h.refs + sizeof(HashGrid)) << density;
    // Empty-space skipping (the default): one more byte per cell.
    EXPECT_EQ(figures(std::string("grid:simd=0,density=") + density).bytes, d.bytes + d.cells) << density;
  }
  // From density 1 to 512 the dense grid grows with its cells (512x), the
  // hashed grid with its occupied cells (~70x here: the room's walls).
  EXPECT_GT(dense[3].bytes / dense[0].bytes, 150.0);
  EXPECT_LT(hashed[3].bytes / hashed[0].bytes, 100.0);
  EXPECT_LT(hashed[3].occupied, 0.05 * hashed[3].cells);
  EXPECT_LT(hashed[3].bytes, 0.5 * dense[3].bytes);
  // SIMD blocks (the default): each cell's list as ceil(n / 4) 160-byte
  // blocks in place of its ids, and no triangle copies.
  for (const char* spec : {"grid", "hashgrid", "grid2"}) {
    auto ids = make_accelerator(std::string(spec) + ":simd=0");
    auto blocks = make_accelerator(spec);
    const BuildStats si = ids->build(m), sb = blocks->build(m);
    const double cell_blocks = sb.extra.at("cell_blocks");
    EXPECT_EQ(si.extra.at("cell_blocks"), 0.0) << spec;
    EXPECT_GE(cell_blocks, sb.extra.at("refs") / 4.0) << spec;
    // At most 3 padding lanes per run: the non-empty cells, and grid2's top cells' large lists.
    const double runs = sb.extra.at("nonempty_cells") + (sb.extra.count("top_cells") ? sb.extra.at("top_cells") : 0.0);
    EXPECT_LE(cell_blocks, (sb.extra.at("refs") + 3.0 * runs) / 4.0) << spec;
    EXPECT_EQ(static_cast<double>(sb.bytes),
              static_cast<double>(si.bytes) - 4.0 * sb.extra.at("refs") - m.num_triangles() * sizeof(LeafTriangle) +
                  cell_blocks * sizeof(CellTriangleBlock))
        << spec;
  }
}

TEST(GridBudget, ExceedingTheBudgetLowersDensityWithAWarning) {
  const test::NamedMesh s = test::soup(20000, 5, 1.0f);
  // simd=0: ids (4 bytes per reference); the default SIMD blocks take at
  // least 40 bytes per reference, so their budgets are larger.
  for (const auto& spec : {"grid:simd=0,density=64,budget=0.5", "hashgrid:simd=0,density=64,budget=0.5",
                           "grid2:simd=0,density=64,budget=0.5", "grid:simd=0,res=1000x1000x1000,budget=1",
                           "grid:density=64,budget=4", "hashgrid:density=64,budget=4", "grid2:density=64,budget=4",
                           "grid:res=1000x1000x1000,budget=8"}) {
    auto a = make_accelerator(spec);
    testing::internal::CaptureStderr();
    const BuildStats st = a->build(s.mesh);
    const std::string err = testing::internal::GetCapturedStderr();
    EXPECT_NE(err.find("warning"), std::string::npos) << spec;
    EXPECT_NE(err.find("budget"), std::string::npos) << spec;
    EXPECT_EQ(st.extra.at("budget_capped"), 1.0) << spec;
    const double budget = std::stod(std::string(spec).substr(std::string(spec).find("budget=") + 7));
    EXPECT_LE(static_cast<double>(st.bytes - s.mesh.num_triangles() * sizeof(LeafTriangle)),
              budget * 1024 * 1024 * 1.05)
        << spec;
    if (std::string(spec).find("res=") == std::string::npos) {
      EXPECT_LT(st.extra.at("lambda"), 64.0) << spec;
    }
    // Still correct.
    const std::vector<Ray> rays = mesh_test_rays(s.mesh, 300, 3);
    const test::Disagreement m = grid_vs_brute(s.mesh, spec, rays, test::brute_reference(s.mesh, rays));
    EXPECT_EQ(m.closest, 0u) << spec << ":\n" << m.examples;
  }
  // Within the budget: no warning.
  auto ok = make_accelerator("grid");
  testing::internal::CaptureStderr();
  const BuildStats st = ok->build(s.mesh);
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
  EXPECT_EQ(st.extra.at("budget_capped"), 0.0);
  // A budget that cannot even hold one reference per triangle: a clear error.
  for (const auto& spec : {"grid:budget=0.01", "hashgrid:budget=0.01", "grid2:budget=0.01"}) {
    auto tiny = make_accelerator(spec);
    testing::internal::CaptureStderr();
    EXPECT_THROW(tiny->build(s.mesh), std::runtime_error) << spec;
    testing::internal::GetCapturedStderr();
  }
}

TEST(GridParams, BadParametersAreRejected) {
  for (const char* spec : {"grid:density=0", "grid:density=-1", "grid:density=nan", "grid:density=abc",
                           "grid:density=1e9", "grid:res=0x1x1", "grid:res=64x64", "grid:res=axbxc", "grid:budget=0",
                           "grid:budget=-5", "grid:assign=foo", "grid:tri=fast", "grid:top=1", "hashgrid:res=1x1",
                           "hashgrid:density=0", "grid2:top=0", "grid2:density=-2", "grid2:res=4x4x4",
                           "grid2:assign=none"}) {
    EXPECT_THROW(make_accelerator(spec), SpecError) << spec;
  }
  EXPECT_NO_THROW(make_accelerator("grid:density=0.125,res=4x4x4,budget=16,assign=bbox,tri=mt"));
  EXPECT_NO_THROW(make_accelerator("grid2:top=0.5,density=2"));
}

}  // namespace
}  // namespace raylab
