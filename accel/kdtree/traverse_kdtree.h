#pragma once
// Front-to-back k-d tree traversal with an explicit stack: the recursive ray
// traversal algorithm (Jansen 1986; Arvo; Havran's thesis, 2000, "TA_rec"),
// written with distances along the ray instead of entry/exit points.
//
// The ray's [tmin, tmax] is first clipped to the root cell (a slab test). At
// an inner node the distance to the split plane decides: the child on the
// ray's origin side ("near") is crossed before the plane, the other ("far")
// after it; when both are crossed, far is pushed with its interval and near
// is visited first.
//
// Robustness. Every cell, the root included, is treated as inflated by a
// margin delta = 2^-20 M in space, where M bounds |p - org| over the root
// cell (M is per ray). This is Ize's conservative slab test (JCGT 2013) with
// the padding put on positions instead of on distances, which covers two
// kinds of error with one rule:
//  - the traversal's own rounding: (s - org) and the product with the
//    reciprocal are off by at most 2 ulp(M) in position, well inside delta;
//  - the triangle test's resolution: the watertight test (Woop et al. 2013)
//    decides on sheared float coordinates of p - org, i.e. on a triangle
//    moved by a few ulp(M), so it can report a hit on a ray passing a few
//    ulp(M) beside a triangle, or a distance off by a few ulp(M)/|dir|. The
//    cell holding such a triangle is still within delta of the ray and is
//    visited, and [tmin, tmax] is widened by delta / max|dir| for the same
//    reason. So the traversal finds every hit the triangle test would report
//    when testing all triangles (the tests check this bit for bit against
//    brute force, also for rays in, along and one ulp beside split planes).
// Rays parallel to a split plane (direction component +0 or -0) get +-inf
// from IEEE division and visit the side(s) within delta of their origin; a
// NaN (a ray exactly on an inflated plane, or a denormal component whose
// reciprocal overflows) visits both children with the full interval: every
// comparison below is written so that NaN means "visit".
//
// Hit acceptance: triangles are tested on the ray's remaining segment
// [tmin, closest hit so far], not just on the leaf's interval. A hit is the
// answer once no cell left on the stack begins before it: a hit inside the
// current leaf's interval ends the traversal, as in the classic algorithm,
// while a hit beyond the leaf (the triangle reaches into later cells) is
// kept as a bound and the traversal goes on only through cells that start
// before it, instead of being rejected and found again later.
// Closest hit and any hit are one routine (kAnyHit returns at the first hit);
// counting is a compile-time switch (kCount). An any-hit walk may visit the
// cells back to front instead (kFarFirst, accel/core/any_hit_order.h): same
// answers, fewer steps for shadow rays leaving dense surfaces.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "accel/core/hit_recorder.h"
#include "accel/core/leaf_triangle.h"
#include "accel/core/traversal_stack.h"
#include "accel/kdtree/kd_leaf_blocks.h"
#include "accel/kdtree/kdtree_node.h"

namespace raylab {

struct KdTreeView {
  const KdNode* nodes = nullptr;
  const LeafTriangle* tris = nullptr;  // once per triangle, in the order the leaves first refer to them
  const uint32_t* ids = nullptr;  // leaf ranges [offset, offset + count) of indices into tris
  Aabb bounds;
  bool empty = true;
  // The node the walk starts at and whose cell `bounds` is: the root, or an
  // entry node of a subtree (accel/hybrid's entry-point grid).
  uint32_t root = 0;
  // SIMD leaves (kd_leaf_blocks.h): a leaf's offset is then its first block.
  const KdTriangleBlock* blocks = nullptr;
};

// The margin delta as a fraction of M (8 ulps of M).
inline constexpr float kKdMarginScale = 0x1p-20f;

// Per-ray constants of the walk: reciprocals, the plane margins and the
// distance margin, and [t0, t1] = the ray's (widened) interval clipped to the
// inflated root cell.
struct KdRay {
  float inv[3], margin[3];
  uint32_t neg[3];
  float delta_t;
  float t0, t1;
};

// Fills `kr`; false when the ray misses the inflated root cell.
[[gnu::always_inline]] inline bool kd_enter_root(const KdTreeView& tree, const Ray& ray, KdRay& kr) {
  const Vec3f& org = ray.org;
  float m = 0.0f, dir_max = 0.0f;
  for (int k = 0; k < 3; ++k) {
    m = std::max(m, std::max(std::fabs(tree.bounds.lo[k] - org[k]), std::fabs(tree.bounds.hi[k] - org[k])));
    dir_max = std::max(dir_max, std::fabs(ray.dir[k]));
  }
  const float delta = std::max(kKdMarginScale * m, std::numeric_limits<float>::min());
  // Capped at FLT_MAX: for a tiny direction delta / dir_max overflows, and
  // the BSP tree widens this clip by the difference of its own margin and
  // this one (traverse_bsp.h), which must not be inf - inf = NaN.
  kr.delta_t = std::min(delta / dir_max, std::numeric_limits<float>::max());

  // Exact IEEE reciprocals: +-0 gives +-inf (parallel rays); a denormal
  // component whose reciprocal overflows gets NaN, so every plane along that
  // axis visits both children. margin[k] moves a plane towards the far side.
  for (int k = 0; k < 3; ++k) {
    const float d = ray.dir[k];
    kr.inv[k] = 1.0f / d;
    if (d != 0.0f && std::isinf(kr.inv[k])) kr.inv[k] = std::numeric_limits<float>::quiet_NaN();
    kr.neg[k] = std::signbit(d) ? 1u : 0u;
    kr.margin[k] = kr.neg[k] ? -delta : delta;
  }

  // Clip [tmin, tmax] (widened) to the inflated root cell.
  float t0 = ray.tmin - kr.delta_t, t1 = ray.tmax + kr.delta_t;
  for (int k = 0; k < 3; ++k) {
    const float near_plane = kr.neg[k] ? tree.bounds.hi[k] : tree.bounds.lo[k];
    const float far_plane = kr.neg[k] ? tree.bounds.lo[k] : tree.bounds.hi[k];
    const float tn = ((near_plane - org[k]) - kr.margin[k]) * kr.inv[k];
    const float tf = ((far_plane - org[k]) + kr.margin[k]) * kr.inv[k];
    t0 = tn > t0 ? tn : t0;
    t1 = tf < t1 ? tf : t1;
  }
  kr.t0 = t0;
  kr.t1 = t1;
  return t0 <= t1;
}

// kBlocks: leaves are SIMD triangle blocks (watertight test only); else
// indices into the scalar triangle copies.
// One leaf of a k-d style tree (this one, and the BSP tree, which stores the
// same leaves): a node visited under the shared definition, then its
// triangles as 4-wide SIMD blocks when the tree keeps them (the watertight
// test), else one by one through the id list. True when a hit was kept, so
// an any-hit walk can stop.
template <bool kBlocks, class Tree, class LeafRay, class Recorder>
[[gnu::always_inline]] inline bool intersect_kd_leaf(const Tree& tree, uint32_t first, uint32_t count,
                                                     const LeafRay& pre, const Ray& ray, Recorder& rec) {
  rec.count_nodes(1);
  rec.count_leaf(count);
  if constexpr (kBlocks)
    return intersect_block_leaf<kKdBlockWidth>(tree.blocks + first, kd_leaf_blocks(count), pre, ray.tmin, rec);
  else
    return intersect_leaf_indexed(pre, ray, tree.tris, tree.ids + first, count, rec);
}

template <TriangleTest kTest, bool kAnyHit, bool kCount, bool kBlocks = false, bool kFarFirst = false>
inline Hit traverse_kdtree(const KdTreeView& tree, const Ray& ray, TraversalStats* stats) {
  static_assert(!kFarFirst || kAnyHit, "only an any-hit walk may change the order");
  HitRecorder<kAnyHit, kCount> rec(ray, stats);
  if (tree.empty || !ray_is_valid(ray)) return rec.hit();
  KdRay kr;
  if (!kd_enter_root(tree, ray, kr)) return rec.hit();
  const Vec3f& org = ray.org;
  const float* inv = kr.inv;
  const float* margin = kr.margin;
  const uint32_t* neg = kr.neg;
  const float delta_t = kr.delta_t;
  float t0 = kr.t0, t1 = kr.t1;

  static_assert(!kBlocks || kTest == TriangleTest::Watertight, "the SIMD leaves run the watertight test");
  using LeafRay = std::conditional_t<kBlocks, BlockRay<kKdBlockWidth>, TrianglePrecompute<kTest>>;
  const LeafRay pre(ray);

  IntervalStack<kKdMaxDepthLimit> stack;
  uint32_t node = tree.root;

  while (true) {
    KdNode n = tree.nodes[node];
    while (!n.is_leaf()) {
      rec.count_inner();
      const int k = n.axis();
      const float rel = n.split() - org[k];
      // Where the ray leaves the (inflated) near child and enters the far one.
      const float t_near_end = (rel + margin[k]) * inv[k];
      const float t_far_start = (rel - margin[k]) * inv[k];
      // Below child = child(), above = child() + 1.
      node = stack.template descend_pair_in_order<kFarFirst>(n.child(), neg[k], t_near_end, t_far_start, t0, t1);
      n = tree.nodes[node];
    }

    const bool kept = intersect_kd_leaf<kBlocks>(tree, n.offset(), n.count(), pre, ray, rec);
    // Next cell that can still hold a closer hit (plus the test's distance error).
    if (!stack.template next_after_leaf<kAnyHit>(kept, rec.tmax() + delta_t, node, t0, t1)) return rec.hit();
  }
}

}  // namespace raylab
