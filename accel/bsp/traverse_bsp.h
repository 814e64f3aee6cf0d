#pragma once
// Front-to-back traversal of the general BSP tree: the k-d tree's recursive
// walk (accel/kdtree/traverse_kdtree.h, Havran 2000) over the packed 8-byte
// nodes (bsp_packed_node.h) with two plane tests.
//  - Nodes on a fixed direction (the axes and the 26-DOP diagonals) use
//    per-ray constants of their direction, computed once per ray: for the
//    axes the k-d tree's own (kd_enter_root: org[k], the reciprocal, sign and
//    margin), for each diagonal u the same from n.org = u . org and
//    1 / (u . dir), all 13 directions in a few vector instructions
//    (bsp_direction_rays). Per node that is one table look-up, one
//    subtraction and two multiply-adds, as in the k-d tree.
//  - Free-plane nodes (a triangle's plane) load their plane from the side
//    array and compute the plane distance along the ray:
//      denom = n . dir, rel = d - n . org, t = rel / denom,
//    and the ray's side order from the sign of denom (below = n . x < d is
//    crossed first when denom > 0).
// Robustness: every region is treated as inflated by a margin in space, as in
// the k-d tree, so the walk visits every leaf the ray passes within that
// margin. For axis planes it is the k-d tree's delta = 2^-20 M (M bounds
// |p - org| over the root cell). A general plane's rel carries the rounding of
// n . org and of d (a few ulps of |org| and of the scene's coordinates) and
// its crossing point the rounding of denom (a few ulps of the distance
// travelled, at most M), so diagonal and free planes get
//    delta_g = 2^-18 (M + max|org| + max|bounds|),
// dozens of times those errors. A ray lying in (or parallel to and within
// delta_g of) a plane gets denom = +-0 or a tiny denom: IEEE division then
// gives +-inf (or NaN, treated as "visit") and the walk visits both sides,
// conservatively; a parallel ray farther away visits only its own side.
// Hit acceptance is the k-d tree's: a hit is final once no pending region
// starts before it; any-hit walks go back to front unless anyhit=front
// (accel/core/any_hit_order.h). Leaves are the k-d tree's 4-wide SIMD triangle blocks
// (kd_leaf_blocks.h) with the watertight test, indices into triangle copies
// with tri=mt; the block test gives the scalar test's hits bit for bit.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "accel/core/any_hit_order.h"
#include "accel/bsp/bsp_packed_node.h"
#include "accel/core/leaf_block_dispatch.h"
#include "accel/core/traversal_stack.h"
#include "accel/kdtree/traverse_kdtree.h"

namespace raylab {

// The 13 fixed directions as structure of arrays, padded to 16 lanes with
// zero vectors (no node names those), so the per-ray constants of all of
// them are a few vector instructions.
struct alignas(64) BspDirectionTable {
  float x[16] = {}, y[16] = {}, z[16] = {};
};

struct BspView {
  const BspPackedNode* nodes = nullptr;
  const BspPlane* planes = nullptr;    // free planes (bsp_packed_node.h)
  const LeafTriangle* tris = nullptr;  // scalar leaves: ids index these
  const uint32_t* ids = nullptr;
  Aabb bounds;
  bool empty = true;
  // The fixed directions (bsp_fixed_directions(), structure of arrays).
  const BspDirectionTable* directions = nullptr;
  // SIMD leaves (watertight test): a leaf's first() is then its first block.
  const KdTriangleBlock* blocks = nullptr;
};

// Per-ray constants of every fixed direction a node may name.
struct alignas(64) BspDirectionRays {
  float n_org[16], inv[16], margin[16];
  uint32_t neg[16];
};

// n . org, 1 / (n . dir) (NaN when the reciprocal of a tiny denom
// overflows: both sides visited), the side order and the margin delta_g
// moved towards the far side, for all 16 lanes at once (branch-free, so the
// compiler vectorises it).
inline void bsp_direction_rays(const BspDirectionTable& t, const Vec3f& org, const Vec3f& dir, float delta_g,
                               BspDirectionRays& dr) {
  const float ox = org[0], oy = org[1], oz = org[2], dx = dir[0], dy = dir[1], dz = dir[2];
  const uint32_t delta_bits = std::bit_cast<uint32_t>(delta_g);
  for (int k = 0; k < 16; ++k) {
    const float denom = t.x[k] * dx + t.y[k] * dy + t.z[k] * dz;
    const float inv = 1.0f / denom;
    const bool overflow = denom != 0.0f && std::fabs(inv) == std::numeric_limits<float>::infinity();
    dr.inv[k] = overflow ? std::numeric_limits<float>::quiet_NaN() : inv;
    dr.n_org[k] = t.x[k] * ox + t.y[k] * oy + t.z[k] * oz;
    const uint32_t neg = std::bit_cast<uint32_t>(denom) >> 31;
    dr.neg[k] = neg;
    dr.margin[k] = std::bit_cast<float>(delta_bits | (neg << 31));
  }
}

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

template <TriangleTest kTest, bool kAnyHit, bool kCount, bool kBlocks, bool kFarFirst = false>
inline Hit traverse_bsp(const BspView& tree, const Ray& ray, TraversalStats* stats) {
  static_assert(!kFarFirst || kAnyHit, "only an any-hit walk may change the order");
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
  // Capped at FLT_MAX as the k-d tree's (kd_enter_root), so that widening
  // the k-d tree's clip by the difference never computes inf - inf = NaN,
  // which made every interval test false and skipped the tree (fuzz_rays:
  // a direction of 2^-148).
  const float delta_t =
      std::min(std::max(kr.delta_t, delta_g / dir.cwiseAbs().maxCoeff()), std::numeric_limits<float>::max());
  const float widen = delta_t - kr.delta_t;
  float t0 = kr.t0 - widen, t1 = kr.t1 + widen;
  static_assert(!kBlocks || kTest == TriangleTest::Watertight, "the SIMD leaves run the watertight test");
  using LeafRay = std::conditional_t<kBlocks, BlockRay<kKdBlockWidth>, TrianglePrecompute<kTest>>;
  const LeafRay pre(ray);
  BspDirectionRays dr;
  bsp_direction_rays(*tree.directions, org, dir, delta_g, dr);
  for (int k = 0; k < 3; ++k) {  // the axes: exactly the k-d tree's constants
    dr.n_org[k] = org[k];
    dr.inv[k] = kr.inv[k];
    dr.margin[k] = kr.margin[k];
    dr.neg[k] = kr.neg[k];
  }

  IntervalStack<kBspMaxDepthLimit> stack;
  uint32_t node = 0;
  while (true) {
    BspPackedNode n = tree.nodes[node];
    while (!n.is_leaf()) {
      rec.count_inner();
      const uint32_t code = n.code();
      float rel, margin, inv;
      uint32_t neg;
      if (code < kBspPackedFreePlane) [[likely]] {
        rel = n.offset() - dr.n_org[code];
        margin = dr.margin[code];
        inv = dr.inv[code];
        neg = dr.neg[code];
      } else {
        const BspPlane& plane = tree.planes[n.plane()];
        const BspPlaneRay p = bsp_plane_ray(plane.n, org, dir);
        rel = plane.d - p.n_org;
        margin = p.neg ? -delta_g : delta_g;
        inv = p.inv;
        neg = p.neg;
      }
      const float t_near_end = (rel + margin) * inv;
      const float t_far_start = (rel - margin) * inv;
      node = stack.template descend_pair_in_order<kFarFirst>(n.child(), neg, t_near_end, t_far_start, t0, t1);
      n = tree.nodes[node];
    }
    const bool kept = intersect_kd_leaf<kBlocks>(tree, n.first(), n.count(), pre, ray, rec);
    if (!stack.template next_after_leaf<kAnyHit>(kept, rec.tmax() + delta_t, node, t0, t1)) return rec.hit();
  }
}

// The walk under the name the generic shell calls (accel/core/view_accelerator.h);
// far_first: an any-hit walk visits the cells back to front (accel/core/any_hit_order.h).
template <TriangleTest kTest, bool kAnyHit, bool kCount>
inline Hit traverse_view(const BspView& v, const Ray& ray, TraversalStats* stats, bool far_first = false) {
  return walk_with_leaf_blocks<kTest>(v, [&]<bool kBlocks>() {
    return walk_in_any_hit_order<kAnyHit>(far_first, [&]<bool kFarFirst>() {
      return traverse_bsp<kTest, kAnyHit, kCount, kBlocks, kFarFirst>(v, ray, stats);
    });
  });
}

}  // namespace raylab
