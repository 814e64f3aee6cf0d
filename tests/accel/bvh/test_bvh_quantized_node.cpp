// Quantised wide nodes (node=q8, quantized_node.h): exact decoding to the
// tightest containing grid box, and the same answers as float nodes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "accel/bvh/bvh_wide_node.h"
#include "accel/bvh/quantized_node.h"
#include "accel/registry.h"
#include "base/pcg.h"
#include "tests/accel_test_util.h"

namespace raylab {
namespace {

// node=q8: for child boxes at every scale and distance from the origin, the
// compressed node decodes (with the traversal's own arithmetic, one fused
// multiply-add in float) to exactly the planes the builder computed in
// double, those planes contain the float box, and they are the tightest
// grid planes that do (less than one cell away). Unused slots keep the empty
// reference and decode to inverted intervals.
TEST(BvhQuantizedNode, DecodesExactlyToTheTightestContainingGridBox) {
  Pcg32 rng(20261127, 3);
  const float offsets[] = {0.0f, 1e-30f, 1e-3f, 1.0f, -7.5f, 1e3f, 3e5f, -1e7f, 1e20f, -1e30f};
  const float sizes[] = {0.0f, 1e-7f, 1e-3f, 1.0f, 1e4f, 1e9f};
  size_t checked = 0;
  for (int trial = 0; trial < 3001; ++trial) {
    WideNode<8> node;
    const uint32_t used = trial == 3000 ? 3u : trial % 97 == 0 ? 0u : 1u + rng.next() % 255u;
    const float off = offsets[trial % 10];
    for (int c = 0; c < 8; ++c) {
      for (int a = 0; a < 3; ++a) {
        node.bounds[2 * a][c] = std::numeric_limits<float>::infinity();
        node.bounds[2 * a + 1][c] = -std::numeric_limits<float>::infinity();
      }
      node.child[c] = wide_ref::kEmpty;
      if (!(used >> c & 1)) continue;
      node.child[c] = static_cast<uint32_t>(c + 1);
      for (int a = 0; a < 3; ++a) {
        // A child's size and place: mixed scales inside one node, so small children sit next to big ones.
        const float size = sizes[rng.next() % 6] * rng.uniform();
        const float lo = off + (std::fabs(off) + 1.0f) * (rng.uniform() - 0.5f) * (c == 0 ? 1e-6f : 1.0f);
        node.bounds[2 * a][c] = lo;
        node.bounds[2 * a + 1][c] = lo + size;
      }
    }
    if (trial == 3000) {
      // Planes just off a grid point far below the origin's magnitude:
      // lo - origin and hi - origin round in double to the grid point, so
      // the first quotients are one cell off and the builder must step.
      for (int a = 0; a < 3; ++a) {
        node.bounds[2 * a][0] = -1.0f, node.bounds[2 * a + 1][0] = -0.5f;
        node.bounds[2 * a][1] = -1e-30f, node.bounds[2 * a + 1][1] = 1e-30f;
      }
    }
    const QuantNode8 q = quantize_node(node);
    for (int a = 0; a < 3; ++a) {
      ASSERT_GE(q.cell_exp[a], 1);
      ASSERT_LE(q.cell_exp[a], 254);
    }
    for (int c = 0; c < 8; ++c) {
      ASSERT_EQ(q.child[c], node.child[c]);
      for (int a = 0; a < 3; ++a) {
        const float cell = q.cell(a);
        const double exact_lo = static_cast<double>(q.origin[a]) + q.q[2 * a][c] * static_cast<double>(cell);
        const double exact_hi = static_cast<double>(q.origin[a]) + q.q[2 * a + 1][c] * static_cast<double>(cell);
        if (!(used >> c & 1)) {
          EXPECT_EQ(q.q[2 * a][c], 255);
          EXPECT_EQ(q.q[2 * a + 1][c], 0);
          continue;
        }
        const float dec_lo = std::fma(static_cast<float>(q.q[2 * a][c]), cell, q.origin[a]);
        const float dec_hi = std::fma(static_cast<float>(q.q[2 * a + 1][c]), cell, q.origin[a]);
        ASSERT_EQ(static_cast<double>(dec_lo), exact_lo) << "decoding rounds: trial " << trial;
        ASSERT_EQ(static_cast<double>(dec_hi), exact_hi) << "decoding rounds: trial " << trial;
        ASSERT_EQ(dec_lo, q.plane(2 * a, c));
        ASSERT_EQ(dec_hi, q.plane(2 * a + 1, c));
        const float lo = node.bounds[2 * a][c], hi = node.bounds[2 * a + 1][c];
        ASSERT_LE(dec_lo, lo) << "trial " << trial << " child " << c << " axis " << a;
        ASSERT_GE(dec_hi, hi) << "trial " << trial << " child " << c << " axis " << a;
        // The next grid planes inward (exact in double) no longer contain the box.
        EXPECT_GT(exact_lo + cell, static_cast<double>(lo)) << "not the tightest lower plane";
        EXPECT_LT(exact_hi - cell, static_cast<double>(hi)) << "not the tightest upper plane";
        ++checked;
      }
      EXPECT_EQ(q.child_box(c).is_empty(), !(used >> c & 1));
    }
  }
  EXPECT_GT(checked, 30000u);
  WideNode<8> bad;
  for (int c = 0; c < 8; ++c) {
    for (int a = 0; a < 6; ++a) bad.bounds[a][c] = 0.0f;
    bad.child[c] = static_cast<uint32_t>(c);
  }
  bad.bounds[1][3] = std::numeric_limits<float>::infinity();
  EXPECT_THROW(quantize_node(bad), std::domain_error);
}

// node=q8 changes the boxes, not the answers: the same closest hits (prim,
// t, u, v bit for bit) and occlusion as the float nodes, on scenes with
// children of very different sizes in one node and far from the origin,
// and at least as many child boxes entered (the decoded boxes contain the
// float ones).
TEST(BvhQuantizedNode, SameAnswersAsFloatNodes) {
  std::vector<std::pair<std::string, TriangleMesh>> meshes;
  meshes.emplace_back("soup", test::soup(3000, 5).mesh);
  meshes.emplace_back("stadium", test::teapot_in_stadium_mesh());
  TriangleMesh far = test::soup(2000, 9, 2.0f).mesh;
  for (Vec3f& v : far.vertices) v += Vec3f(3e5f, -2e5f, 1e5f);
  meshes.emplace_back("far", std::move(far));
  for (const auto& [name, mesh] : meshes) {
    std::vector<Ray> rays = test::segment_rays(mesh, 3000, 17);
    const std::vector<Ray> cam = test::camera_rays(mesh, 48, 48);
    rays.insert(rays.end(), cam.begin(), cam.end());
    auto f = make_accelerator("bvh:layout=bvh8");  // the tree node=q8 compresses
    auto q = make_accelerator("bvh:node=q8");
    const BuildStats fs = f->build(mesh);
    const BuildStats qs = q->build(mesh);
    ASSERT_TRUE(qs.extra.count("q8_area_ratio"));
    EXPECT_GE(qs.extra.at("q8_area_ratio"), 1.0);
    std::vector<Hit> hf(rays.size()), hq(rays.size());
    std::vector<uint8_t> of(rays.size()), oq(rays.size());
    TraversalStats sf, sq;
    f->intersect(rays, hf, &sf);
    q->intersect(rays, hq, &sq);
    f->occluded(rays, of);
    q->occluded(rays, oq);
    size_t hits = 0;
    for (size_t i = 0; i < rays.size(); ++i) {
      ASSERT_EQ(hf[i].prim, hq[i].prim) << name << " ray " << i;
      ASSERT_EQ(std::memcmp(&hf[i].t, &hq[i].t, sizeof(float)), 0) << name << " ray " << i;
      ASSERT_EQ(hf[i].u, hq[i].u);
      ASSERT_EQ(hf[i].v, hq[i].v);
      ASSERT_EQ(of[i], oq[i]) << name << " ray " << i;
      hits += hf[i].valid();
    }
    EXPECT_GT(hits, rays.size() / 10) << name;
    EXPECT_GE(sq.nodes_visited, sf.nodes_visited) << name;
    EXPECT_LT(qs.bytes, fs.bytes) << name << ": compressed nodes take less memory";
  }
}

}  // namespace
}  // namespace raylab
