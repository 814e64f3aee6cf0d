#pragma once
// Triangle meshes made from a few numbers, deterministic for a seed: the
// geometry of the procedural scenes (scenes/procedural.h adds materials and a
// camera) and the inputs of the structure tests, which see only this layer.
#include <cstddef>
#include <cstdint>

#include "base/triangle_mesh.h"

namespace raylab {

// Appends the triangle (a, b, c) with three vertices of its own.
void append_triangle(TriangleMesh& m, const Vec3f& a, const Vec3f& b, const Vec3f& c);

// n random triangles in the unit cube; their extent is about `size` times
// the mean spacing of n points, so density stays comparable across n.
TriangleMesh triangle_soup_mesh(size_t n, uint64_t seed, float size = 1.0f);

// n identical copies of one (not axis-aligned) triangle, each with its own
// three vertices: the degenerate input for spatial subdivisions.
TriangleMesh triangle_copies_mesh(size_t n);

// Everything in the axis-aligned plane coordinate[axis] = 0.5: a regular
// grid x grid of quads (two triangles each, shared edges) plus n random
// overlapping triangles, all inside the unit square of the plane.
TriangleMesh coplanar_mesh(size_t n, int grid, int axis, uint64_t seed);

// n needles: long triangles `width` wide between random points on opposite
// faces of the unit cube (the axis cycles x, y, z), each with its own three
// vertices: the slivers a structure's boxes and cells bound poorly.
TriangleMesh needles_mesh(size_t n, uint64_t seed, float width = 1e-4f);

// Closed UV sphere: `segments` around, `rings` from pole to pole; vertices
// are shared (one per pole), so the surface is exactly closed: every edge
// belongs to two triangles with identical endpoint coordinates.
TriangleMesh make_uv_sphere(int segments, int rings, const Vec3f& center = Vec3f::Zero(), float radius = 1.0f);

// The Cornell box's 16 quads (32 triangles, two per quad, in quad order)
// from Cornell's published measurements, in millimetres: floor, ceiling,
// back wall, green wall (x = 0), red wall, area light (0.1 mm below the
// ceiling), then the short and the tall block, five quads each.
TriangleMesh cornell_box_mesh();
inline constexpr int kCornellGreenQuad = 3, kCornellRedQuad = 4, kCornellLightQuad = 5;

}  // namespace raylab
