// The any-hit child order (occlusion_order.h): it needs a wide layout, large
// occluders go to the highest slot, and closest hits and occlusion answers
// stay those of the slot order.
#include <gtest/gtest.h>

#include <vector>

#include "accel/bvh/collapse_wide.h"
#include "accel/bvh/occlusion_order.h"
#include "accel/registry.h"
#include "tests/accel_test_util.h"

namespace raylab {
namespace {

TEST(BvhOcclusionOrder, NeedsAWideLayout) {
  EXPECT_THROW(make_accelerator("bvh:aorder=rtsah,layout=bvh2"), SpecError);
  EXPECT_THROW(make_accelerator("bvh:aorder=rtsah,bound=sphere"), SpecError);
  EXPECT_THROW(make_accelerator("bvh:aorder=any"), SpecError);
  EXPECT_NO_THROW(make_accelerator("bvh:aorder=rtsah,layout=bvh4"));
}

// Ize & Hansen's order: per node, leaves above inner children, each group in
// ascending blocked-per-cost; the child most likely to block per unit cost
// sits in the highest slot, which the any-hit walk visits first.
TEST(BvhOcclusionOrder, LargeOccludersGoToTheHighestSlot) {
  TriangleMesh m;
  auto add = [&](Vec3f a, Vec3f b, Vec3f c) {
    const uint32_t i = static_cast<uint32_t>(m.vertices.size());
    m.vertices.insert(m.vertices.end(), {a, b, c});
    m.triangles.push_back({i, i + 1, i + 2});
  };
  add(Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0));              // 0: fills half of its box's face
  add(Vec3f(0, 0, 2), Vec3f(1, 1, 2), Vec3f(0.99f, 1, 2));          // 1: a diagonal sliver in a box as large
  add(Vec3f(3, 0, 0), Vec3f(4, 0, 0), Vec3f(3, 1, 0));              // 2, 3: an inner child's two leaves
  add(Vec3f(3, 0, 1), Vec3f(4, 0, 1), Vec3f(3, 1, 1));
  auto leaf_box = [&](uint32_t t) { return m.triangle_bounds(t); };
  WideTree w;
  w.leaf_begin = {0, 1, 2, 3, 4};
  w.leaf_prims = {1, 0, 2, 3};  // leaf i holds triangle leaf_prims[i]
  w.nodes.resize(2);
  Aabb inner_box = leaf_box(2);
  inner_box.extend(leaf_box(3));
  // Root: slot 0 the inner node, then the sliver's leaf, the large triangle's leaf (collapse order scrambled).
  w.nodes[0].count = 3;
  w.nodes[0].child[0] = {leaf_box(0), true, 1};
  w.nodes[0].child[1] = {inner_box, false, 1};
  w.nodes[0].child[2] = {leaf_box(1), true, 0};
  w.nodes[1].count = 2;
  w.nodes[1].child[0] = {leaf_box(2), true, 2};
  w.nodes[1].child[1] = {leaf_box(3), true, 3};
  w.root_box = inner_box;
  w.root_box.extend(leaf_box(0));
  w.root_box.extend(leaf_box(1));
  const double blocked = order_children_for_occlusion(w, m, {2.0f, 1.0f, 8});
  const WideTree::Node& r = w.nodes[0];
  ASSERT_EQ(r.count, 3);
  EXPECT_FALSE(r.child[0].leaf);
  EXPECT_EQ(r.child[0].index, 1u);
  EXPECT_TRUE(r.child[1].leaf);
  EXPECT_EQ(r.child[1].index, 0u) << "the sliver below";
  EXPECT_TRUE(r.child[2].leaf);
  EXPECT_EQ(r.child[2].index, 1u) << "the large triangle in the highest slot";
  EXPECT_TRUE(r.child[2].box.lo == leaf_box(0).lo && r.child[2].box.hi == leaf_box(0).hi) << "boxes move with their children";
  // A flat leaf box: its half area is the triangle's box face, the triangle half of it.
  const double p_large = 0.5;
  EXPECT_GT(blocked, 0.0);
  EXPECT_LT(blocked, 1.0);
  // The root's chance is at least the large leaf's share of the root.
  EXPECT_GE(blocked, p_large * leaf_box(0).half_area() / w.root_box.half_area() - 1e-9);
  // Equal priorities keep the collapse's order (stable): the inner node's two equal leaves.
  EXPECT_EQ(w.nodes[1].child[0].index, 2u);
  EXPECT_EQ(w.nodes[1].child[1].index, 3u);
}

TEST(BvhOcclusionOrder, SameClosestHitsAndOcclusionAsTheSlotOrder) {
  const test::NamedMesh s = test::soup(3000, 23);
  const std::vector<Ray> rays = test::segment_rays(s.mesh, 4000, 9);
  auto a = make_accelerator("bvh"), b = make_accelerator("bvh:aorder=rtsah");
  const BuildStats sa = a->build(s.mesh), sb = b->build(s.mesh);
  EXPECT_EQ(sa.nodes, sb.nodes);
  EXPECT_EQ(sa.sah_cost, sb.sah_cost);
  EXPECT_GT(sb.extra.at("occlusion_root"), 0.0);
  std::vector<Hit> ha(rays.size()), hb(rays.size());
  std::vector<uint8_t> oa(rays.size()), ob(rays.size());
  a->intersect(rays, ha);
  b->intersect(rays, hb);
  a->occluded(rays, oa);
  b->occluded(rays, ob);
  size_t occluded = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    ASSERT_EQ(ha[i].prim, hb[i].prim) << i;
    ASSERT_EQ(ha[i].t, hb[i].t) << i;
    ASSERT_EQ(oa[i], ob[i]) << i;
    occluded += oa[i];
  }
  EXPECT_GT(occluded, rays.size() / 10);
}

}  // namespace
}  // namespace raylab
