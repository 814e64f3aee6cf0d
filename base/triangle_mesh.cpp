#include "base/triangle_mesh.h"

#include <cmath>

#include <fmt/format.h>

#include "base/hit.h"
#include "base/ray.h"

namespace raylab {

Aabb TriangleMesh::bounds() const {
  Aabb b;
  for (size_t i = 0; i < triangles.size(); ++i) b.extend(triangle_bounds(i));
  return b;
}

void TriangleMesh::validate() const {
  if (triangles.size() >= static_cast<size_t>(kInvalidPrim))
    throw MeshError(fmt::format("mesh has {} triangles; at most {} are supported", triangles.size(),
                                kInvalidPrim - 1));
  for (size_t i = 0; i < vertices.size(); ++i) {
    const Vec3f& v = vertices[i];
    if (!std::isfinite(v.x()) || !std::isfinite(v.y()) || !std::isfinite(v.z()))
      throw MeshError(fmt::format("vertex {} has a non-finite coordinate ({}, {}, {})", i, v.x(),
                                  v.y(), v.z()));
  }
  for (size_t i = 0; i < triangles.size(); ++i) {
    for (int c = 0; c < 3; ++c) {
      if (triangles[i][c] >= vertices.size())
        throw MeshError(fmt::format("triangle {} refers to vertex {}, but the mesh has {} vertices",
                                    i, triangles[i][c], vertices.size()));
    }
  }
}

void TriangleMesh::append(const TriangleMesh& other) {
  const auto offset = static_cast<uint32_t>(vertices.size());
  vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
  // No reserve here: reserving the exact size on every call would defeat the
  // vector's geometric growth and make many small appends quadratic.
  for (const auto& t : other.triangles) triangles.push_back({t[0] + offset, t[1] + offset, t[2] + offset});
}


}  // namespace raylab
