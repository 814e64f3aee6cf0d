// The irregular grid: bit-exact agreement with brute force
// with and without the merge and expand passes, on rays along cell faces,
// rays starting inside and rays with +-0 direction components; the passes'
// effect on the teapot in a stadium; bad parameters; the outline.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "accel/irgrid/build_irgrid.h"
#include "accel/registry.h"
#include "base/pcg.h"
#include "tests/accel_test_util.h"
#include "tests/brute_agreement.h"

namespace raylab {
namespace {

// simd=0: the scalar mailboxed walk; the others test the SIMD leaf blocks.
const std::vector<std::string> kIrgridSpecs = {"irgrid", "irgrid:merge=0", "irgrid:expand=0",
                                               "irgrid:merge=0,expand=0", "irgrid:top=1,depth=1",
                                               "irgrid:top=0.01,step=4,depth=5", "irgrid:simd=0"};

Vec3f unit_random(Pcg32& rng) {
  while (true) {
    const Vec3f d(2 * rng.uniform() - 1, 2 * rng.uniform() - 1, 2 * rng.uniform() - 1);
    const float n = d.norm();
    if (n > 0.1f && n <= 1.0f) return d / n;
  }
}

// Rays that differ from brute force in hit/miss, distance (bit for bit),
// triangle (ties included), occlusion, or between the plain and the counting
// kernel.
size_t mismatches(const std::string& spec, const TriangleMesh& mesh, const std::vector<Ray>& rays,
                  const test::BruteReference& ref, std::string& first) {
  auto accel = make_accelerator(spec);
  accel->build(mesh);
  const test::Disagreement d =
      test::compare_with_brute(*accel, ref, rays, {.same_triangle = true, .counting_kernel = true});
  first = d.examples;
  return d.total();
}

void expect_exact(const TriangleMesh& mesh, const std::vector<Ray>& rays, const std::string& what) {
  const test::BruteReference ref = test::brute_reference(mesh, rays);
  for (const auto& spec : kIrgridSpecs) {
    std::string first;
    EXPECT_EQ(mismatches(spec, mesh, rays, ref, first), 0u) << what << ": " << first;
  }
}

// Rays lying in the planes of the cells' faces (the face coordinate as the
// origin's, that direction component +0 or -0), and rays aimed at cell
// corners, for the cells of the default irgrid of `mesh`.
std::vector<Ray> cell_face_rays(const TriangleMesh& mesh, size_t count, uint64_t seed) {
  auto accel = make_accelerator("irgrid");
  accel->build(mesh);
  StructureOutline out;
  accel->outline(1, out);
  std::vector<Ray> rays;
  Pcg32 rng(seed, 11);
  const Aabb box = mesh.bounds();
  for (size_t i = 0; i < count && out.boxes.size() > 1; ++i) {
    const Aabb& cell = out.boxes[1 + rng.next() % (out.boxes.size() - 1)].box;
    Vec3f corner;
    for (int a = 0; a < 3; ++a) corner[a] = (rng.next() & 1) ? cell.hi[a] : cell.lo[a];
    Vec3f dir = unit_random(rng);
    Vec3f org = box.lo + Vec3f(rng.uniform(), rng.uniform(), rng.uniform()).cwiseProduct(box.diagonal());
    if (i % 2 == 0) {
      // In one or two face planes through the corner.
      const int a = static_cast<int>(rng.next() % 3);
      org[a] = corner[a];
      dir[a] = (rng.next() & 1) ? 0.0f : -0.0f;
      if (i % 4 == 0) {
        const int b = (a + 1) % 3;
        org[b] = corner[b];
        dir[b] = (rng.next() & 1) ? 0.0f : -0.0f;
      }
    } else {
      dir = corner - org;  // through the corner (an edge of up to 8 cells)
      if (dir.norm() == 0.0f) dir = Vec3f(1, 0, 0);
    }
    rays.emplace_back(org, dir.normalized());
  }
  return rays;
}

TEST(Irgrid, SoupMatchesBruteForceExactly) {
  const TriangleMesh mesh = test::soup(400, 3).mesh;
  expect_exact(mesh, test::mesh_test_rays(mesh, 1500, 7), "soup");
  expect_exact(mesh, test::segment_rays(mesh, 500, 8), "soup segments");
  expect_exact(mesh, cell_face_rays(mesh, 800, 9), "soup cell faces");
}

TEST(Irgrid, FlatAndAxisAlignedScenesMatchBruteForce) {
  const TriangleMesh flat = test::flat_tiles_mesh(8, 40, 5);
  std::vector<Ray> rays = test::mesh_test_rays(flat, 800, 2);
  // In the scene's plane, along tile edges, with +-0 components.
  Pcg32 rng(4, 1);
  for (int i = 0; i < 300; ++i) {
    const float x = static_cast<float>(rng.next() % 9) / 8.0f;
    const float sz = (i & 1) ? 0.0f : -0.0f, sx = (i & 2) ? 0.0f : -0.0f;
    rays.emplace_back(Vec3f(x, -0.5f, 0.5f), Vec3f(sx, 1.0f, sz));
    rays.emplace_back(Vec3f(rng.uniform(), rng.uniform(), 0.5f), Vec3f(2 * rng.uniform() - 1, 2 * rng.uniform() - 1, sz));
    rays.emplace_back(Vec3f(x, rng.uniform(), 1.5f), Vec3f(sx, 0.0f, -1.0f));
  }
  expect_exact(flat, rays, "flat tiles");
  expect_exact(flat, cell_face_rays(flat, 600, 3), "flat tiles cell faces");
}

TEST(Irgrid, StadiumMatchesBruteForceFromInsideAndOutside) {
  const TriangleMesh mesh = test::teapot_in_stadium_mesh();
  std::vector<Ray> rays = test::camera_rays(mesh, 24, 24);
  Pcg32 rng(6, 2);
  for (int i = 0; i < 400; ++i) {
    // From around the small object, in every direction (starting inside cells).
    const Vec3f o = test::kStadiumObject + 2.0f * Vec3f(rng.uniform() - 0.5f, rng.uniform() - 0.5f, rng.uniform() - 0.5f);
    rays.emplace_back(o, unit_random(rng));
  }
  expect_exact(mesh, rays, "stadium");
}

// The merge pass turns the empty stadium into few cells; expansion lets rays
// cross it in fewer steps; neither changes a hit (checked above).
// A dense sphere (2,256 triangles, diameter 1) in an empty box 1000 wide
// made of 12 triangles: the octree goes deep around the sphere, and the
// merge pass must turn the empty space into few cells.
TriangleMesh sphere_in_big_box() {
  TriangleMesh m = make_uv_sphere(48, 24, test::kStadiumObject, 0.5f);
  const float h = 500.0f;
  const Vec3f c[8] = {{-h, -h, -h}, {h, -h, -h}, {h, h, -h}, {-h, h, -h}, {-h, -h, h}, {h, -h, h}, {h, h, h}, {-h, h, h}};
  const int quads[6][4] = {{0, 1, 2, 3}, {4, 5, 6, 7}, {0, 1, 5, 4}, {3, 2, 6, 7}, {0, 3, 7, 4}, {1, 2, 6, 5}};
  for (const auto& q : quads) {
    append_triangle(m, c[q[0]], c[q[1]], c[q[2]]);
    append_triangle(m, c[q[0]], c[q[2]], c[q[3]]);
  }
  return m;
}

TEST(Irgrid, MergeLeavesFewCellsAroundADenseObject) {
  const TriangleMesh mesh = sphere_in_big_box();
  auto build = [&](const std::string& spec) {
    auto accel = make_accelerator(spec);
    return accel->build(mesh);
  };
  const BuildStats plain = build("irgrid:merge=0");
  const BuildStats merged = build("irgrid");
  std::printf("sphere in a box: %.0f cells unmerged (%.0f empty), %.0f merged (%.0f empty), depth %d\n",
              plain.extra.at("cells"), plain.extra.at("cells") - plain.extra.at("nonempty_cells"),
              merged.extra.at("cells"), merged.extra.at("cells") - merged.extra.at("nonempty_cells"), merged.max_depth);
  EXPECT_GE(merged.max_depth, 6);  // the octree resolved the small sphere
  const double plain_empty = plain.extra.at("cells") - plain.extra.at("nonempty_cells");
  const double merged_empty = merged.extra.at("cells") - merged.extra.at("nonempty_cells");
  EXPECT_EQ(plain.extra.at("cells"), merged.extra.at("initial_cells"));
  EXPECT_LT(merged.extra.at("cells") * 1.5, plain.extra.at("cells"));
  EXPECT_LT(merged_empty * 3, plain_empty);
  EXPECT_LT(merged.bytes, plain.bytes);
}

TEST(Irgrid, MergeAndExpandShrinkTheStadium) {
  const TriangleMesh mesh = test::teapot_in_stadium_mesh();
  auto cells_of = [&](const std::string& spec) {
    auto accel = make_accelerator(spec);
    const BuildStats s = accel->build(mesh);
    EXPECT_EQ(s.extra.at("cells"), static_cast<double>(s.nodes)) << spec;
    return s;
  };
  const BuildStats plain = cells_of("irgrid:merge=0,expand=0");
  const BuildStats merged = cells_of("irgrid:expand=0");
  EXPECT_EQ(plain.extra.at("cells"), plain.extra.at("initial_cells"));
  EXPECT_GT(merged.extra.at("merged_pairs"), 0.0);
  EXPECT_EQ(merged.extra.at("cells") + merged.extra.at("merged_pairs"), merged.extra.at("initial_cells"));
  EXPECT_LT(merged.extra.at("cells") * 2, plain.extra.at("cells"));
  EXPECT_LT(merged.bytes, plain.bytes);

  // From inside the room, across the empty stadium to the walls.
  std::vector<Ray> rays;
  Pcg32 rng(8, 3);
  for (int i = 0; i < 500; ++i) rays.emplace_back(Vec3f(-200.0f, 100.0f, 50.0f), unit_random(rng));
  auto nodes_of = [&](const std::string& spec) { return test::counted_hits(spec, mesh, rays).stats.nodes_visited; };
  const uint64_t plain_nodes = nodes_of("irgrid:merge=0,expand=0");
  const uint64_t merged_nodes = nodes_of("irgrid:expand=0");
  const uint64_t full_nodes = nodes_of("irgrid");
  EXPECT_LT(merged_nodes, plain_nodes);
  EXPECT_LT(full_nodes, merged_nodes);
  EXPECT_GT(cells_of("irgrid").extra.at("expanded_cells"), 0.0);
}

// tri=mt runs the scalar walk with the Moller-Trumbore test (no blocks):
// the same hits as brute force with that test.
TEST(Irgrid, MollerTrumboreVariantMatchesBruteForceWithTheSameTest) {
  const TriangleMesh mesh = test::soup(400, 5).mesh;
  const std::vector<Ray> rays = test::mesh_test_rays(mesh, 1500, 4);
  auto grid = make_accelerator("irgrid:tri=mt");
  auto brute = make_accelerator("brute:tri=mt");
  grid->build(mesh);
  brute->build(mesh);
  size_t bad = 0, hits = 0;
  for (const Ray& r : rays) {
    const Hit a = grid->intersect1(r), b = brute->intersect1(r);
    bad += a.valid() != b.valid() || (a.valid() && (a.t != b.t || a.prim != b.prim));
    hits += b.valid();
  }
  EXPECT_GT(hits, rays.size() / 10);
  EXPECT_EQ(bad, 0u);
}

// The merge and expand passes and the octrees run in parallel; the grid must
// not depend on the thread count: every cell's box and occupancy (outline)
// and every statistic equal with 1 thread and with all.
TEST(Irgrid, SameGridForAnyThreadCount) {
  const TriangleMesh mesh = test::teapot_in_stadium_mesh();
  auto built = [&](int threads, StructureOutline& out) {
    std::unique_ptr<tbb::global_control> limit;
    if (threads > 0) limit = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, threads);
    auto accel = make_accelerator("irgrid");
    const BuildStats s = accel->build(mesh);
    accel->outline(1, out);
    return s;
  };
  StructureOutline one, all;
  const BuildStats s1 = built(1, one), sa = built(0, all);
  EXPECT_GT(s1.extra.at("merged_pairs"), 0.0);
  EXPECT_EQ(s1.extra, sa.extra);
  EXPECT_EQ(s1.bytes, sa.bytes);
  ASSERT_EQ(one.boxes.size(), all.boxes.size());
  size_t differ = 0;
  for (size_t i = 0; i < one.boxes.size(); ++i) {
    const OutlineBox &a = one.boxes[i], &b = all.boxes[i];
    differ += a.box.lo != b.box.lo || a.box.hi != b.box.hi || a.leaf != b.leaf || a.depth != b.depth;
  }
  EXPECT_EQ(differ, 0u);
}

TEST(Irgrid, EmptyMeshAndInvalidRaysMiss) {
  TriangleMesh empty;
  auto accel = make_accelerator("irgrid");
  accel->build(empty);
  EXPECT_FALSE(accel->intersect1(Ray(Vec3f(0, 0, 0), Vec3f(1, 0, 0))).valid());
  const TriangleMesh mesh = test::soup(50, 1).mesh;
  auto a = make_accelerator("irgrid");
  a->build(mesh);
  EXPECT_FALSE(a->intersect1(Ray(Vec3f(0, 0, 0), Vec3f(0, 0, 0))).valid());
  EXPECT_FALSE(a->occluded1(Ray(Vec3f(0, 0, 0), Vec3f(NAN, 0, 1))));
}

TEST(Irgrid, BadParametersAreRejected) {
  for (const char* spec : {"irgrid:top=0", "irgrid:top=-1", "irgrid:step=-1", "irgrid:sub=0", "irgrid:depth=17", "irgrid:depth=-1",
                           "irgrid:merge=2", "irgrid:expand=x", "irgrid:tri=foo", "irgrid:nope=1"})
    EXPECT_THROW(make_accelerator(spec), SpecError) << spec;
}

TEST(Irgrid, OutlineHasTheGridBoxAndEveryCell) {
  const TriangleMesh mesh = test::soup(200, 2).mesh;
  auto accel = make_accelerator("irgrid");
  const BuildStats s = accel->build(mesh);
  StructureOutline out;
  accel->outline(1, out);
  ASSERT_EQ(out.boxes.size(), s.nodes + 1);
  EXPECT_EQ(out.boxes[0].depth, 0);
  size_t filled = 0;
  for (size_t i = 1; i < out.boxes.size(); ++i) {
    EXPECT_EQ(out.boxes[i].depth, 1);
    EXPECT_FALSE(out.boxes[i].box.is_empty());
    filled += out.boxes[i].leaf;
  }
  EXPECT_EQ(filled, s.leaves);
  StructureOutline root;
  accel->outline(0, root);
  EXPECT_EQ(root.boxes.size(), 1u);
}

}  // namespace
}  // namespace raylab
