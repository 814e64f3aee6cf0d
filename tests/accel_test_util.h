#pragma once
// Helpers of the structure tests (raylab_tests_accel), which link the base
// and structures layers only: meshes come from base/mesh_shapes.h, rays from
// here, and the reference answers from the brute-force structure.
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

// Closest hits and occlusion answers of the brute-force structure.
struct BruteReference {
  std::vector<Hit> hits;
  std::vector<uint8_t> occluded;
};
BruteReference brute_reference(const TriangleMesh& mesh, std::span<const Ray> rays);

// How far an accelerator's answers are from brute force's. The same
// watertight test on the same vertices gives the same triangle bit-identical
// (t, u, v), so a different triangle is accepted only at a tie: the same
// distance bit for bit or, with tie_rel > 0, within tie_rel of the
// coordinates involved (|origin| + t): two overlapping coplanar triangles
// give distances that differ by rounding at that scale, and a structure may
// cull the second one's box by an ulp once the first is found.
struct Disagreement {
  size_t closest = 0;    // different hit/miss, or a different triangle not at a tie
  size_t barycentric = 0;  // same triangle, different distance or (u, v)
  size_t occlusion = 0;  // any-hit answer differs from closest hit
  size_t reference_hits = 0;
};
// Reports the first few differences (ADD_FAILURE, prefixed with `what`).
Disagreement compare_with_brute(const Accelerator& accel, const BruteReference& ref, std::span<const Ray> rays,
                                const std::string& what, float tie_rel = 0.0f);

}  // namespace raylab::test
