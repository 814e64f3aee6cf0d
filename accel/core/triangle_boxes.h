#pragma once
// Every triangle's bounding box and their union, computed in parallel: the
// first step of the k-d tree and octree builders.
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include "base/aabb.h"
#include "base/triangle_mesh.h"

namespace raylab {

// boxes[i] = the bounds of triangle i; returns their union.
inline Aabb triangle_boxes(const TriangleMesh& mesh, std::vector<Aabb>& boxes) {
  boxes.resize(mesh.num_triangles());
  return tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, boxes.size(), 8192), Aabb(),
      [&](const tbb::blocked_range<size_t>& r, Aabb acc) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
          boxes[i] = mesh.triangle_bounds(i);
          acc.extend(boxes[i]);
        }
        return acc;
      },
      [](const Aabb& a, const Aabb& b) { return merge(a, b); });
}

}  // namespace raylab
