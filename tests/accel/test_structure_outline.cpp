// Structure pictures (Accelerator::outline): every structure that declares
// Capabilities::outline draws non-empty geometry that stays within the
// scene's (padded) box, respects the depth limit and grows with depth;
// the others draw at most their root box. Covered through the registry, so
// a new structure is tested once it sets the capability.
#include <gtest/gtest.h>

#include "accel/registry.h"
#include "tests/accel_test_util.h"

namespace raylab {
namespace {

// The box every element must lie in: the mesh bounds plus a small margin
// (grids pad their box by 1e-5 of its size; a few ulps of float rounding).
Aabb allowed_box(const TriangleMesh& mesh) {
  Aabb b = mesh.bounds();
  const Vec3f pad = Vec3f::Constant(1e-3f * b.diagonal().maxCoeff() + 1e-6f);
  return Aabb(b.lo - pad, b.hi + pad);
}

StructureOutline outline_of(const Accelerator& accel, int depth) {
  StructureOutline out;
  accel.outline(depth, out);
  return out;
}

TEST(StructureOutline, SplitPlaneIsTheClippedPlane) {
  const Aabb box(Vec3f(0, 1, 2), Vec3f(4, 5, 6));
  const OutlineQuad q = StructureOutline::split_plane(box, 1, 3.0f, 2);
  EXPECT_EQ(q.depth, 2);
  Aabb seen;
  for (const auto& c : q.corners) {
    EXPECT_EQ(c.y(), 3.0f);
    seen.extend(c);
  }
  EXPECT_EQ(seen.lo, Vec3f(0, 3, 2));
  EXPECT_EQ(seen.hi, Vec3f(4, 3, 6));
}

TEST(StructureOutline, BudgetStopsAndMarksTruncated) {
  StructureOutline out;
  out.budget = 2;
  EXPECT_TRUE(out.add(OutlineBox{}));
  EXPECT_TRUE(out.add(OutlineSegment{Vec3f::Zero(), Vec3f::UnitX(), 0}));
  EXPECT_FALSE(out.add(OutlineQuad{}));
  EXPECT_EQ(out.size(), 2u);
  EXPECT_TRUE(out.truncated);
}

TEST(StructureOutline, EveryStructureDrawsWithinTheSceneAndByDepth) {
  const test::NamedMesh scene = test::soup(400, 7);
  const Aabb allowed = allowed_box(scene.mesh);
  for (const auto& info : accelerator_registry()) {
    SCOPED_TRACE(info.name);
    auto accel = make_accelerator(info.name);
    EXPECT_TRUE(outline_of(*accel, 8).empty()) << "outline before build must be empty";
    accel->build(scene.mesh);
    const StructureOutline shallow = outline_of(*accel, 0);
    const StructureOutline deep = outline_of(*accel, 12);
    EXPECT_FALSE(deep.truncated);
    if (!info.caps.outline) {
      EXPECT_LE(deep.size(), 1u);
      continue;
    }
    ASSERT_FALSE(deep.empty());
    EXPECT_FALSE(deep.what.empty());
    EXPECT_LE(shallow.max_depth(), 0);
    EXPECT_LE(deep.max_depth(), 12);
    EXPECT_LE(shallow.size(), deep.size());
    EXPECT_TRUE(allowed.contains(deep.bounds())) << deep.bounds().lo.transpose() << " / " << deep.bounds().hi.transpose();
    // A structure with more than one node shows more than its root at depth 12
    // (brute force is a single leaf).
    if (info.name != "brute") {
      EXPECT_GT(deep.size(), 1u);
      EXPECT_GE(deep.max_depth(), 1);
    }
  }
}

TEST(StructureOutline, BvhLeavesCoverEveryTriangle) {
  // At a depth beyond the tree's, the leaf boxes of a BVH together contain
  // every triangle: each triangle's centroid lies in some leaf box.
  const test::NamedMesh scene = test::soup(300, 11);
  for (const std::string spec : {"bvh:layout=bvh2", "bvh:layout=bvh8", "bvh:layout=bvh4"}) {
    SCOPED_TRACE(spec);
    auto accel = make_accelerator(spec);
    accel->build(scene.mesh);
    const StructureOutline out = outline_of(*accel, 64);
    std::vector<Aabb> leaves;
    for (const auto& b : out.boxes)
      if (b.leaf) leaves.push_back(b.box);
    ASSERT_FALSE(leaves.empty());
    for (size_t t = 0; t < scene.mesh.num_triangles(); ++t) {
      const Vec3f c = scene.mesh.triangle_bounds(t).center();
      bool inside = false;
      for (const auto& b : leaves) inside |= b.contains(c);
      ASSERT_TRUE(inside) << "triangle " << t;
    }
  }
}

TEST(StructureOutline, KdTreeDrawsSplitPlanesInsideTheirCells) {
  const test::NamedMesh scene = test::soup(300, 5);
  auto accel = make_accelerator("kdtree");
  accel->build(scene.mesh);
  const StructureOutline one = outline_of(*accel, 0);
  const StructureOutline out = outline_of(*accel, 6);
  ASSERT_EQ(one.quads.size(), 1u);  // the root's plane
  EXPECT_GT(out.quads.size(), 8u);
  const Aabb root = out.boxes.at(0).box;
  for (const auto& q : out.quads) {
    EXPECT_LE(q.depth, 6);
    for (const auto& c : q.corners) EXPECT_TRUE(root.contains(c));
  }
}

TEST(StructureOutline, GridCellsAreTheOccupiedCells) {
  // The picture draws exactly the non-empty cells the build counted
  // (grid2: the non-empty cells of its sub-grids, at depth 2).
  const test::NamedMesh scene = test::soup(200, 3, 0.2f);
  for (const std::string name : {"grid", "hashgrid", "grid2"}) {
    SCOPED_TRACE(name);
    auto accel = make_accelerator(name);
    const BuildStats stats = accel->build(scene.mesh);
    const int cell_depth = name == "grid2" ? 2 : 1;
    const StructureOutline out = outline_of(*accel, cell_depth);
    size_t cells = 0;
    for (const auto& b : out.boxes) cells += b.depth == cell_depth;
    EXPECT_GT(cells, 1u);
    EXPECT_EQ(cells, stats.leaves);
    EXPECT_EQ(out.boxes.at(0).depth, 0);
    if (name != "grid2") {
      EXPECT_LT(cells, stats.nodes);  // empty cells are not drawn
    }
  }
}

}  // namespace
}  // namespace raylab
