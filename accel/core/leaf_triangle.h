#pragma once
// The one leaf-triangle type of the scalar traversals (binary BVH, k-d tree,
// grids, brute force): a triangle's vertices copied out of the mesh next to
// its id, so a leaf leads to its vertices with no indirection through the
// index buffer. The SIMD layouts of the wide BVH keep their own blocks
// (accel/bvh/triangle_block.h). Also the leaf functions: one triangle, a
// contiguous run, or a run of indices into the copied triangles.
#include <cstdint>
#include <span>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "accel/core/intersect_triangle.h"
#include "base/triangle_mesh.h"

namespace raylab {

struct LeafTriangle {
  Vec3f p0, p1, p2;
  uint32_t prim;
};

// The one way a leaf triangle is copied out of the mesh.
inline LeafTriangle make_leaf_triangle(const TriangleMesh& mesh, uint32_t id) {
  return LeafTriangle{mesh.vertex(id, 0), mesh.vertex(id, 1), mesh.vertex(id, 2), id};
}

// The triangles `ids` of the mesh, in that order (in parallel: large meshes).
inline std::vector<LeafTriangle> copy_leaf_triangles(const TriangleMesh& mesh, std::span<const uint32_t> ids) {
  std::vector<LeafTriangle> tris(ids.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, ids.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      tris[i] = make_leaf_triangle(mesh, ids[i]);
    }
  });
  return tris;
}

// Every triangle of the mesh, in id order (tris[i].prim == i).
inline std::vector<LeafTriangle> copy_leaf_triangles(const TriangleMesh& mesh) {
  std::vector<uint32_t> ids(mesh.num_triangles());
  for (size_t i = 0; i < ids.size(); ++i) ids[i] = static_cast<uint32_t>(i);
  return copy_leaf_triangles(mesh, ids);
}

// Leaves that refer to triangles by index (a triangle may lie in several
// leaves or nodes): each referenced triangle is copied once, in the order the
// leaves first use it (neighbouring leaves share cache lines), and every
// reference becomes an index into that copy. On the bunny (5.3 references per
// triangle) this was faster than one copy per reference, with half the memory.
struct IndexedLeafTriangles {
  std::vector<LeafTriangle> tris;  // once per referenced triangle, in first-use order
  std::vector<uint32_t> ids;       // ids[i]: the copy of the triangle refs[i] names
};

// The triangles `refs` names, each once, in first-use order; ids[i] becomes
// the position of refs[i] in that order.
inline std::vector<uint32_t> first_use_order(size_t num_triangles, std::span<const uint32_t> refs,
                                             std::vector<uint32_t>& ids) {
  std::vector<uint32_t> slot(num_triangles, UINT32_MAX), order;
  ids.resize(refs.size());
  for (size_t i = 0; i < refs.size(); ++i) {
    const uint32_t id = refs[i];
    if (slot[id] == UINT32_MAX) {
      slot[id] = static_cast<uint32_t>(order.size());
      order.push_back(id);
    }
    ids[i] = slot[id];
  }
  return order;
}

inline IndexedLeafTriangles copy_referenced_triangles(const TriangleMesh& mesh, std::span<const uint32_t> refs) {
  IndexedLeafTriangles out;
  out.tris = copy_leaf_triangles(mesh, first_use_order(mesh.num_triangles(), refs, out.ids));
  return out;
}

// Tests one triangle on [ray.tmin, rec.tmax()]; true when the recorder kept the hit.
template <TriangleTest kTest, typename Recorder>
[[gnu::always_inline]] inline bool intersect_leaf_triangle(const TrianglePrecompute<kTest>& pre, const Ray& ray,
                                                           const LeafTriangle& tri, Recorder& rec) {
  rec.count_triangles(1);
  float t, u, v;
  return pre.intersect(ray, tri.p0, tri.p1, tri.p2, ray.tmin, rec.tmax(), t, u, v) && rec.record(t, u, v, tri.prim);
}

// A leaf stored as a contiguous run of triangles. True when a hit was kept
// (an any-hit recorder stops at the first one).
template <TriangleTest kTest, typename Recorder>
[[gnu::always_inline]] inline bool intersect_leaf(const TrianglePrecompute<kTest>& pre, const Ray& ray,
                                                  const LeafTriangle* tris, uint32_t count, Recorder& rec) {
  bool kept = false;
  for (uint32_t i = 0; i < count; ++i) {
    if (intersect_leaf_triangle(pre, ray, tris[i], rec)) {
      kept = true;
      if constexpr (Recorder::kStopAtFirstHit) return true;
    }
  }
  return kept;
}

// A leaf stored as indices into the copied triangles (structures that refer
// to a triangle from several leaves or cells).
template <TriangleTest kTest, typename Recorder>
[[gnu::always_inline]] inline bool intersect_leaf_indexed(const TrianglePrecompute<kTest>& pre, const Ray& ray,
                                                          const LeafTriangle* tris, const uint32_t* ids,
                                                          uint32_t count, Recorder& rec) {
  bool kept = false;
  for (uint32_t i = 0; i < count; ++i) {
    if (intersect_leaf_triangle(pre, ray, tris[ids[i]], rec)) {
      kept = true;
      if constexpr (Recorder::kStopAtFirstHit) return true;
    }
  }
  return kept;
}

}  // namespace raylab
