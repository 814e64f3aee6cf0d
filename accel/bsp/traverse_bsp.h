#pragma once
// Front-to-back traversal of the general BSP tree: the k-d tree's recursive
// walk (accel/kdtree/traverse_kdtree.h, Havran 2000) with two plane tests.
//  - Axis-aligned nodes take the k-d tree's fast path: the per-ray
//    reciprocals, signs and margins of kd_enter_root, one subtraction and one
//    multiplication per node.
//  - General nodes compute the plane distance along the ray:
//      denom = n . dir, rel = d - n . org, t = rel / denom,
//    and the ray's side order from the sign of denom (below = n . x < d is
//    crossed first when denom > 0).
//  - Nodes on a fixed 26-DOP diagonal (kBspFixed) do the same with n . org
//    and 1 / denom computed once per ray for each diagonal the tree uses
//    (the same float operations on the same stored normal, so the same
//    values), which makes them as cheap as axis nodes.
// Robustness: every region is treated as inflated by a margin in space, as in
// the k-d tree, so the walk visits every leaf the ray passes within that
// margin. For axis planes it is the k-d tree's delta = 2^-20 M (M bounds
// |p - org| over the root cell). A general plane's rel carries the rounding of
// n . org and of d (a few ulps of |org| and of the scene's coordinates) and
// its crossing point the rounding of denom (a few ulps of the distance
// travelled, at most M), so general planes get
//    delta_g = 2^-18 (M + max|org| + max|bounds|),
// dozens of times those errors. A ray lying in (or parallel to and within
// delta_g of) a plane gets denom = +-0 or a tiny denom: IEEE division then
// gives +-inf (or NaN, treated as "visit") and the walk visits both sides,
// conservatively; a parallel ray farther away visits only its own side.
// Hit acceptance is the k-d tree's: a hit is final once no pending region
// starts before it.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "accel/bsp/bsp_node.h"
#include "accel/core/traversal_stack.h"
#include "accel/kdtree/traverse_kdtree.h"

namespace raylab {

struct BspView {
  const BspNode* nodes = nullptr;
  const LeafTriangle* tris = nullptr;
  const uint32_t* ids = nullptr;
  Aabb bounds;
  bool empty = true;
  // The fixed directions and how many of them kBspFixed nodes may use.
  const Vec3f* fixed_dirs = nullptr;
  int num_fixed_dirs = 3;
};

// Per-ray plane constants of a general plane with normal n.
struct BspPlaneRay {
  float n_org = 0, inv = 0;
  uint32_t neg = 0;
};

inline BspPlaneRay bsp_plane_ray(const float n[3], const Vec3f& org, const Vec3f& dir) {
  BspPlaneRay p;
  const float denom = n[0] * dir[0] + n[1] * dir[1] + n[2] * dir[2];
  p.n_org = n[0] * org[0] + n[1] * org[1] + n[2] * org[2];
  p.inv = 1.0f / denom;
  // A tiny denom whose reciprocal overflows: NaN makes both sides visited.
  if (denom != 0.0f && std::isinf(p.inv)) p.inv = std::numeric_limits<float>::quiet_NaN();
  p.neg = std::signbit(denom) ? 1u : 0u;
  return p;
}

inline constexpr float kBspGeneralMarginScale = 0x1p-18f;

template <TriangleTest kTest, bool kAnyHit, bool kCount>
inline Hit traverse_bsp(const BspView& tree, const Ray& ray, TraversalStats* stats) {
  HitRecorder<kAnyHit, kCount> rec(ray, stats);
  if (tree.empty || !ray_is_valid(ray)) return rec.hit();
  // The k-d tree's per-ray constants and root clip (same root box rule).
  KdTreeView root_cell;
  root_cell.bounds = tree.bounds;
  KdRay kr;
  if (!kd_enter_root(root_cell, ray, kr)) return rec.hit();
  const Vec3f& org = ray.org;
  const Vec3f& dir = ray.dir;
  float m = 0.0f, org_mag = 0.0f, box_mag = 0.0f;
  for (int k = 0; k < 3; ++k) {
    m = std::max(m, std::max(std::fabs(tree.bounds.lo[k] - org[k]), std::fabs(tree.bounds.hi[k] - org[k])));
    org_mag = std::max(org_mag, std::fabs(org[k]));
    box_mag = std::max(box_mag, std::max(std::fabs(tree.bounds.lo[k]), std::fabs(tree.bounds.hi[k])));
  }
  const float delta_g = std::max(kBspGeneralMarginScale * (m + org_mag + box_mag), std::numeric_limits<float>::min());
  const float delta_t = std::max(kr.delta_t, delta_g / dir.cwiseAbs().maxCoeff());
  float t0 = kr.t0 - delta_t + kr.delta_t, t1 = kr.t1 + delta_t - kr.delta_t;
  const TrianglePrecompute<kTest> pre(ray);
  BspPlaneRay fixed[13];
  for (int k = 3; k < tree.num_fixed_dirs; ++k) fixed[k] = bsp_plane_ray(tree.fixed_dirs[k].data(), org, dir);

  IntervalStack<kBspMaxDepthLimit> stack;
  uint32_t node = 0;
  while (true) {
    BspNode n = tree.nodes[node];
    while (!n.is_leaf()) {
      rec.count_nodes(1);
      const uint32_t kind = n.kind();
      float t_near_end, t_far_start;
      uint32_t near, far;
      if (kind < kBspGeneral) {  // k-d fast path
        const int k = static_cast<int>(kind);
        const float rel = n.d - org[k];
        t_near_end = (rel + kr.margin[k]) * kr.inv[k];
        t_far_start = (rel - kr.margin[k]) * kr.inv[k];
        near = n.index + kr.neg[k];
        far = n.index + 1u - kr.neg[k];
      } else {
        const BspPlaneRay p = kind == kBspFixed ? fixed[n.direction()] : bsp_plane_ray(n.n, org, dir);
        const float rel = n.d - p.n_org;
        const float margin = p.neg ? -delta_g : delta_g;
        t_near_end = (rel + margin) * p.inv;
        t_far_start = (rel - margin) * p.inv;
        near = n.index + p.neg;
        far = n.index + 1u - p.neg;
      }
      node = stack.descend(near, far, t_near_end, t_far_start, t0, t1);
      n = tree.nodes[node];
    }
    rec.count_nodes(1);
    if (intersect_leaf_indexed(pre, ray, tree.tris, tree.ids + n.index, n.count(), rec)) {
      if constexpr (kAnyHit) return rec.hit();
    }
    if (!stack.pop_within(rec.tmax() + delta_t, node, t0, t1)) return rec.hit();
  }
}

// The walk under the name the generic shell calls (accel/core/view_accelerator.h).
template <TriangleTest kTest, bool kAnyHit, bool kCount>
inline Hit traverse_view(const BspView& v, const Ray& ray, TraversalStats* stats) { return traverse_bsp<kTest, kAnyHit, kCount>(v, ray, stats); }

}  // namespace raylab
