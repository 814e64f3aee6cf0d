#pragma once
// The one triangle mesh shared by every accelerator: vertex positions and
// index triples. Materials and cameras live in scenes/, not here.
#include <array>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "base/aabb.h"
#include "base/vec.h"

namespace raylab {

// Thrown when a mesh is invalid; the message names the first offending element.
class MeshError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct TriangleMesh {
  std::vector<Vec3f> vertices;
  std::vector<std::array<uint32_t, 3>> triangles;

  size_t num_triangles() const { return triangles.size(); }
  size_t num_vertices() const { return vertices.size(); }

  const Vec3f& vertex(size_t tri, int corner) const { return vertices[triangles[tri][corner]]; }

  Aabb triangle_bounds(size_t tri) const {
    Aabb b;
    b.extend(vertex(tri, 0));
    b.extend(vertex(tri, 1));
    b.extend(vertex(tri, 2));
    return b;
  }

  // Bounds of the referenced vertices (empty box for an empty mesh).
  Aabb bounds() const;

  // Throws MeshError naming the first problem: a non-finite vertex coordinate,
  // an index out of range, or more triangles than ids can address.
  void validate() const;

  // Appends another mesh (indices are offset).
  void append(const TriangleMesh& other);
};

}  // namespace raylab
