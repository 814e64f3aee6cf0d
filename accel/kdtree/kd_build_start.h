#pragma once
// The start both k-d tree builders share: the size limit, the depth limit in
// force, and every triangle's box with their union (accel/core/triangle_boxes.h).
#include <algorithm>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>
#include <tbb/parallel_invoke.h>

#include "accel/core/triangle_boxes.h"
#include "accel/kdtree/kd_build_options.h"
#include "accel/kdtree/kd_tree_writer.h"
#include "accel/kdtree/kdtree_node.h"
#include "base/triangle_mesh.h"

namespace raylab {

// Throws std::length_error when the mesh has more than max_triangles triangles.
inline int kd_build_depth_limit(const TriangleMesh& mesh, const KdBuildOptions& opt, size_t max_triangles) {
  const size_t n = mesh.num_triangles();
  if (n > max_triangles) throw std::length_error(fmt::format("kdtree: {} triangles, at most {} supported", n, max_triangles));
  return opt.max_depth < 0 ? kd_default_max_depth(n) : std::min(opt.max_depth, kKdMaxDepthLimit);
}

// The tree of an empty mesh: one empty leaf.
inline KdTree empty_kdtree(KdTreeWriter& writer) {
  writer.set_leaf(0, {});
  return writer.finish(Aabb::empty());
}

// Subtrees of at least this many triangles are built as parallel tasks.
inline constexpr size_t kKdParallelTaskSize = 1024;

// Builds both children of a node of n triangles: as two parallel tasks when
// the node is large, else one after the other.
template <typename BuildBelow, typename BuildAbove>
void build_children(size_t n, BuildBelow&& below, BuildAbove&& above) {
  if (n >= kKdParallelTaskSize) {
    tbb::parallel_invoke(below, above);
  } else {
    below();
    above();
  }
}

// What both builders hold: the mesh, the options, the depth limit in force
// and the tree being written.
class KdBuilderBase {
 public:
  KdBuilderBase(const TriangleMesh& mesh, const KdBuildOptions& o) : mesh_(mesh), opt_(o) {}

 protected:
  // The run every builder shares: the depth limit (for trees indexing at
  // most max_triangles), the triangles' boxes (tri_boxes_), the builder's
  // recursion from the root (build_root(bounds)) and the finished tree; an
  // empty mesh gives the empty tree.
  template <typename BuildRoot>
  KdTree run_from_root(size_t max_triangles, BuildRoot&& build_root) {
    max_depth_ = kd_build_depth_limit(mesh_, opt_, max_triangles);
    if (mesh_.num_triangles() == 0) return empty_kdtree(writer_);
    const Aabb bounds = triangle_boxes(mesh_, tri_boxes_);
    build_root(bounds);
    return writer_.finish(bounds);
  }

  const TriangleMesh& mesh_;
  KdBuildOptions opt_;
  int max_depth_ = 0;
  KdTreeWriter writer_;
  std::vector<Aabb> tri_boxes_;  // bounds of each triangle
};

}  // namespace raylab
