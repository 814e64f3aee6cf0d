#pragma once
// Triangle vertices copied out of the mesh in id order, so a cell's
// reference leads to the vertices with one indirection instead of two.
#include <cstdint>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "accel/core/triangle_mesh.h"

namespace raylab {

struct GridTriangle {
  Vec3f p0, p1, p2;
};

inline std::vector<GridTriangle> copy_grid_triangles(const TriangleMesh& mesh) {
  std::vector<GridTriangle> tris(mesh.num_triangles());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, tris.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) tris[i] = {mesh.vertex(i, 0), mesh.vertex(i, 1), mesh.vertex(i, 2)};
  });
  return tris;
}

}  // namespace raylab
