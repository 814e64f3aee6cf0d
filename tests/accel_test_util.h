#pragma once
// Meshes and rays for the structure tests (raylab_tests_accel); the answers
// they are compared with come from brute force (brute_agreement.h), scenes
// from the scenes layer (scenes/procedural.h).
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "accel/accelerator.h"
#include "base/mesh_shapes.h"
#include "base/ray.h"
#include "base/triangle_mesh.h"

namespace raylab::test {

// A mesh and the name the failure messages give it.
struct NamedMesh {
  std::string name;
  TriangleMesh mesh;
};

// triangle_soup_mesh(n, seed, size) named like the scene spec "soup:n=..,seed=..".
NamedMesh soup(size_t n, uint64_t seed, float size = 1.0f);

// All triangles in the plane z = 0.5: a tiles x tiles tessellated unit square
// plus `extra` random small triangles lying in the same plane (overlapping).
TriangleMesh flat_tiles_mesh(int tiles, size_t extra, uint64_t seed);

// "Teapot in a stadium": a closed room 1000 units wide (floor tessellated,
// walls and ceiling as big triangles) around a dense sphere of diameter 1
// (about 8,000 triangles) at kStadiumObject, 1000x smaller than the room,
// resting on a huge table top that crosses its cell.
TriangleMesh teapot_in_stadium_mesh();
inline const Vec3f kStadiumObject(3.0f, -2.0f, 1.5f);

// Coherent rays, like a camera's: a w x h grid of directions from a point in
// front of the mesh's bounds (on the -z side, slightly off-axis) through its
// middle plane, enlarged by 10 % so some rays miss.
std::vector<Ray> camera_rays(const TriangleMesh& mesh, int width, int height);

// Incoherent rays: half from random points in the (enlarged) bounds in
// random directions, half aimed at random triangles' interiors, edges and
// vertices.
std::vector<Ray> mesh_test_rays(const TriangleMesh& mesh, size_t count, uint64_t seed);

// Segments between two random points of the bounds enlarged by 5 % of the
// diagonal (tmax = the segment's length).
std::vector<Ray> segment_rays(const TriangleMesh& mesh, size_t count, uint64_t seed);

// Rays leaving the surface, like diffuse bounces: from the hit point of each
// ray that hit, in a random direction on the side the ray came from, the
// origin pushed off the plane by 1e-5 of the scene diagonal.
std::vector<Ray> surface_rays(const TriangleMesh& mesh, std::span<const Ray> rays, std::span<const Hit> hits,
                              uint64_t seed);

// Closest hits of a structure made from `spec` and built on `mesh`, traced
// with the counting kernels (stats.rays is expected to equal rays.size()).
struct CountedHits {
  std::vector<Hit> hits;
  TraversalStats stats;
};
CountedHits counted_hits(const std::string& spec, const TriangleMesh& mesh, std::span<const Ray> rays);

// Every spec the registry asks to cover, except the reference (Embree),
// brute force itself (the ground truth) and Moller-Trumbore variants (a
// different test may pick the other triangle at a shared edge).
std::vector<std::string> specs_checked_against_brute();
// A spec as a gtest parameter name ("bvh:layout=bvh2" -> "bvh_layout_bvh2").
std::string gtest_name(const std::string& spec);

// Rays from outside a closed UV sphere (48 x 24) aimed at its shared edges
// and vertices, and rays from its centre: how many of them miss (closest
// hit) or are not occluded, with triangle `remove` taken out (a hole) when
// it is a valid index.
size_t closed_sphere_leaks(const std::string& spec, const Vec3f& center, size_t rays, size_t remove = SIZE_MAX);

// Rays aimed at points of the mesh's triangles (interior, edges, vertices)
// from random directions, plus random rays through the box.
std::vector<Ray> rays_at_triangles(const TriangleMesh& mesh, size_t count, uint64_t seed);

// Secondary rays: from the hit points of `primary` (closest hits by brute
// force) in random directions, tmin = 0 (rays starting on a surface).
std::vector<Ray> secondary_rays(const TriangleMesh& mesh, std::span<const Ray> primary, uint64_t seed);

// A ray in hexadecimal floats, for failure messages.
std::string describe_ray(const Ray& r);

}  // namespace raylab::test
