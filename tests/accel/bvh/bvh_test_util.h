#pragma once
// Helpers of the BVH tests (tests/accel/bvh/): the triangles' boxes and
// centroids a builder takes, a binary tree built by a named builder, the
// well-formedness check of a binary tree, and the scenes with ray sets and
// brute-force answers the registry-level tests share (built once).
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "accel/bvh/build_binned_sah.h"
#include "accel/bvh/build_lbvh.h"
#include "accel/bvh/build_sbvh.h"
#include "accel/bvh/build_sweep_sah.h"
#include "accel/bvh/optimize_reinsertion.h"
#include "base/mesh_shapes.h"
#include "tests/accel_test_util.h"
#include "tests/brute_agreement.h"

namespace raylab::test {

struct Prims {
  std::vector<Aabb> boxes;
  std::vector<Vec3f> centroids;
};

inline Prims prims_of(const TriangleMesh& m) {
  Prims p;
  for (size_t i = 0; i < m.num_triangles(); ++i) {
    p.boxes.push_back(m.triangle_bounds(i));
    p.centroids.push_back(p.boxes.back().center());
  }
  return p;
}

inline BinaryBvh build_with(const std::string& builder, const TriangleMesh& mesh, int leaf_threshold = 1) {
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

inline bool is_leaf(const Bvh2Node& n) { return n.count != 0 || n.index == 0; }

// Every reference of a binary tree, and a check that children lie inside
// their parents' boxes.
inline void check_binary_tree(const BinaryBvh& t, const TriangleMesh& mesh, bool duplicates_allowed) {
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

struct RaySet {
  std::string name;
  std::vector<Ray> rays;
};

struct ReferenceScene {
  NamedMesh scene;
  std::vector<RaySet> sets;
  std::vector<BruteReference> brute;  // per set
};

inline const std::vector<ReferenceScene>& reference_scenes() {
  static const std::vector<ReferenceScene> refs = [] {
    std::vector<ReferenceScene> out;
    std::vector<NamedMesh> scenes;
    scenes.push_back(soup(2500, 17));
    scenes.push_back(soup(400, 5, 6.0f));  // long, heavily overlapping triangles
    scenes.push_back({"cornell", cornell_box_mesh()});
    scenes.push_back({"sphere", make_uv_sphere(40, 20, Vec3f(0.5f, 0.5f, 0.5f), 0.4f)});
    for (NamedMesh& s : scenes) {
      ReferenceScene r;
      std::vector<Ray> primary = camera_rays(s.mesh, 40, 40);
      const BruteReference first = brute_reference(s.mesh, primary);
      std::vector<Ray> diffuse = surface_rays(s.mesh, primary, first.hits, 3);
      r.sets = {{"primary", std::move(primary)}, {"random", segment_rays(s.mesh, 1500, 7)},
                {"diffuse", std::move(diffuse)}};
      for (const RaySet& set : r.sets) r.brute.push_back(brute_reference(s.mesh, set.rays));
      r.scene = std::move(s);
      out.push_back(std::move(r));
    }
    return out;
  }();
  return refs;
}

}  // namespace raylab::test
