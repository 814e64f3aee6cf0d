#pragma once
// The sphere hierarchy (`bvh:bound=sphere`): the binary BVH's tree (same
// builder, same leaves, same child order) with a bounding sphere per node
// instead of a box (sphere_bounds.h), traced front to back like
// traverse_bvh2.h: both children's spheres are tested, the nearer entered
// first, the farther pushed with its entry distance.
//
// The ray-sphere test is conservative: the squared distance from the centre
// to the ray's line is computed from the component of (c - o) perpendicular
// to the direction (no cancellation-prone quadratic), and the radius is
// padded by 2^-16 of |c - o| + r, far above the few ulps that float rounding
// of these products can lose; the entry and exit distances are padded the
// same way. A sphere the ray really crosses is therefore never missed.
// The test runs on the direction scaled by a power of two to a largest
// component in [0.5, 1) (exact; distances scale back exactly, in two
// factors so that no factor over- or underflows): |dir|^2 of a valid ray
// can underflow to 0 (components near 2^-149) or overflow to inf (near
// 2^127), and 1 / |dir|^2 would then be inf or 0 and miss every sphere.
#include <cmath>
#include <cstdint>
#include <vector>

#include "accel/bvh/bvh2_layout.h"
#include "accel/bvh/sphere_bounds.h"
#include "accel/bvh/traverse_bvh2.h"
#include "accel/structure_outline.h"

namespace raylab {

struct SphereNode {
  float c[3];
  float r;
  uint32_t index;  // inner: left child (right = index + 1); leaf: first triangle
  uint32_t count;  // 0 for inner nodes
};
static_assert(sizeof(SphereNode) == 24);

// How much looser the spheres are than the boxes of the same nodes.
struct SphereLooseness {
  double volume_ratio = 0.0;        // sum of sphere volumes / sum of box volumes
  double area_ratio = 0.0;          // sum of sphere areas / sum of box areas
  double mean_node_area_ratio = 0.0;  // mean over nodes of sphere area / box area
};

struct SphereBvh {
  std::vector<SphereNode> nodes;
  HugePageVector<LeafTriangle> tris;
  SphereLooseness looseness;

  size_t bytes() const { return nodes.size() * sizeof(SphereNode) + tris.size() * sizeof(LeafTriangle); }
};

// Spheres for every node of `layout` (consumed: the triangles move over).
SphereBvh make_sphere_bvh(Bvh2Layout layout);

// Structure picture (Accelerator::outline): every node's sphere of depth <=
// max_depth as three great circles (segments), leaves included.
void outline_sphere_bvh(const SphereBvh& bvh, int max_depth, StructureOutline& out);

struct SphereBvhView {
  const SphereNode* nodes = nullptr;
  const LeafTriangle* tris = nullptr;
  bool empty = true;
};

inline constexpr float kSpherePad = 0x1p-16f;

// The ray with its direction scaled to a largest component in [0.5, 1):
// dir = unit_dir * 2^e, so t = t' * 2^-e, applied as two factors (2^-e
// alone may not be a float: e ranges over [-148, 128]).
struct SphereRay {
  Vec3f org, dir;   // dir scaled by 2^-e
  float inv_dd;     // 1 / |scaled dir|^2, in (0.33, 4]
  float back_a, back_b;  // 2^-e = back_a * back_b

  explicit SphereRay(const Ray& ray) : org(ray.org) {
    int e = 0;
    std::frexp(ray.dir.cwiseAbs().maxCoeff(), &e);
    dir = Vec3f(std::ldexp(ray.dir[0], -e), std::ldexp(ray.dir[1], -e), std::ldexp(ray.dir[2], -e));
    inv_dd = 1.0f / dir.squaredNorm();
    back_a = std::ldexp(1.0f, -e / 2);
    back_b = std::ldexp(1.0f, -e - (-e / 2));
  }
};

// The ray against one sphere: entry distance when [tmin, tmax] overlaps the
// (padded) chord.
[[gnu::always_inline]] inline bool ray_sphere_test(const SphereRay& ray, const SphereNode& s, float tmin, float tmax,
                                                   float& t_enter) {
  const Vec3f oc(s.c[0] - ray.org[0], s.c[1] - ray.org[1], s.c[2] - ray.org[2]);
  const float tca = oc.dot(ray.dir) * ray.inv_dd;  // closest approach, in scaled units
  const Vec3f perp = oc - tca * ray.dir;
  const float pad = kSpherePad * (oc.cwiseAbs().maxCoeff() + s.r);
  const float rr = s.r + pad;
  const float h2 = rr * rr - perp.squaredNorm();
  if (!(h2 >= 0.0f)) return false;
  const float half_chord = std::sqrt(h2 * ray.inv_dd);
  const float t_pad = kSpherePad * (std::fabs(tca) + half_chord);
  // Back to the ray's own distances (exact unless the result over- or
  // underflows: beyond FLT_MAX it is +-inf, which keeps the test conservative).
  t_enter = (tca - half_chord - t_pad) * ray.back_a * ray.back_b;
  const float t_exit = (tca + half_chord + t_pad) * ray.back_a * ray.back_b;
  return t_enter <= tmax && t_exit >= tmin;
}

template <TriangleTest kTest, bool kAnyHit, bool kCount>
inline Hit traverse_sphere_bvh(const SphereBvhView& bvh, const Ray& ray, TraversalStats* stats) {
  return trace_binary_bvh<kTest, kAnyHit, kCount, SphereRay>(
      bvh, ray, stats, [](const SphereRay& sray, const SphereNode& n, float tmin, float bound, float& t)
                           __attribute__((always_inline)) { return ray_sphere_test(sray, n, tmin, bound, t); });
}

// The walk under the name the generic shells call (accel/core/view_accelerator.h).
template <TriangleTest kTest, bool kAnyHit, bool kCount>
inline Hit traverse_view(const SphereBvhView& v, const Ray& ray, TraversalStats* stats) { return traverse_sphere_bvh<kTest, kAnyHit, kCount>(v, ray, stats); }

}  // namespace raylab
