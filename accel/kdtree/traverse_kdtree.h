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
// counting is a compile-time switch (kCount).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>

#include "accel/accelerator.h"
#include "accel/core/intersect_triangle.h"
#include "accel/kdtree/kdtree_node.h"

namespace raylab {

// Triangle vertices copied next to their original ids (once per triangle, in
// the order the leaves first refer to them).
struct KdLeafTriangle {
  Vec3f p0, p1, p2;
  uint32_t prim;
};

struct KdTreeView {
  const KdNode* nodes = nullptr;
  const KdLeafTriangle* tris = nullptr;
  const uint32_t* ids = nullptr;  // leaf ranges [offset, offset + count) of indices into tris
  Aabb bounds;
  bool empty = true;
};

// The margin delta as a fraction of M (8 ulps of M).
inline constexpr float kKdMarginScale = 0x1p-20f;

template <TriangleTest kTest, bool kAnyHit, bool kCount>
inline Hit traverse_kdtree(const KdTreeView& tree, const Ray& ray, TraversalStats* stats) {
  Hit hit;
  if constexpr (kCount) stats->rays++;
  if (tree.empty || !ray_is_valid(ray) || !(ray.tmin <= ray.tmax)) return hit;

  const Vec3f& org = ray.org;
  float m = 0.0f, dir_max = 0.0f;
  for (int k = 0; k < 3; ++k) {
    m = std::max(m, std::max(std::fabs(tree.bounds.lo[k] - org[k]), std::fabs(tree.bounds.hi[k] - org[k])));
    dir_max = std::max(dir_max, std::fabs(ray.dir[k]));
  }
  const float delta = std::max(kKdMarginScale * m, std::numeric_limits<float>::min());
  const float delta_t = delta / dir_max;

  // Exact IEEE reciprocals: +-0 gives +-inf (parallel rays); a denormal
  // component whose reciprocal overflows gets NaN, so every plane along that
  // axis visits both children. margin[k] moves a plane towards the far side.
  float inv[3], margin[3];
  uint32_t neg[3];
  for (int k = 0; k < 3; ++k) {
    const float d = ray.dir[k];
    inv[k] = 1.0f / d;
    if (d != 0.0f && std::isinf(inv[k])) inv[k] = std::numeric_limits<float>::quiet_NaN();
    neg[k] = std::signbit(d) ? 1u : 0u;
    margin[k] = neg[k] ? -delta : delta;
  }

  // Clip [tmin, tmax] (widened) to the inflated root cell.
  float t0 = ray.tmin - delta_t, t1 = ray.tmax + delta_t;
  for (int k = 0; k < 3; ++k) {
    const float near_plane = neg[k] ? tree.bounds.hi[k] : tree.bounds.lo[k];
    const float far_plane = neg[k] ? tree.bounds.lo[k] : tree.bounds.hi[k];
    const float tn = ((near_plane - org[k]) - margin[k]) * inv[k];
    const float tf = ((far_plane - org[k]) + margin[k]) * inv[k];
    t0 = tn > t0 ? tn : t0;
    t1 = tf < t1 ? tf : t1;
  }
  if (!(t0 <= t1)) return hit;

  const TrianglePrecompute<kTest> pre(ray);
  float best_t = ray.tmax;

  struct Entry {
    uint32_t node;
    float t0, t1;
  };
  // One entry per inner node on the current path at most.
  Entry stack[kKdMaxDepthLimit];
  int sp = 0;
  uint32_t node = 0;

  while (true) {
    KdNode n = tree.nodes[node];
    while (!n.is_leaf()) {
      if constexpr (kCount) stats->nodes_visited++;
      const int k = n.axis();
      const float rel = n.split() - org[k];
      // Where the ray leaves the (inflated) near child and enters the far one.
      const float t_near_end = (rel + margin[k]) * inv[k];
      const float t_far_start = (rel - margin[k]) * inv[k];
      // Below child = child(), above = child() + 1; a ray going down (sign
      // bit set, -0 included) is above the plane first.
      const uint32_t near = n.child() + neg[k];
      const uint32_t far = n.child() + 1u - neg[k];
      const bool visit_near = !(t_near_end < t0);
      const bool visit_far = !(t_far_start > t1);
      // Branch-free: the far entry is always written but only kept when
      // both children are visited. With one child only the interval stays
      // as it is (the padded plane lies outside it).
      stack[sp] = Entry{far, t_far_start > t0 ? t_far_start : t0, t1};
      sp += (visit_near && visit_far) ? 1 : 0;
      t1 = (visit_near && t_near_end < t1) ? t_near_end : t1;
      node = visit_near ? near : far;
      n = tree.nodes[node];
    }

    if constexpr (kCount) stats->nodes_visited++;
    const uint32_t* id = tree.ids + n.offset();
    for (uint32_t i = 0, count = n.count(); i < count; ++i) {
      const KdLeafTriangle* tri = tree.tris + id[i];
      if constexpr (kCount) stats->triangle_tests++;
      float t, u, v;
      if (pre.intersect(ray, tri->p0, tri->p1, tri->p2, ray.tmin, best_t, t, u, v)) {
        if (t < best_t || !hit.valid()) {
          hit = Hit{t, u, v, tri->prim};
          best_t = t;
          if constexpr (kAnyHit) return hit;
        }
      }
    }

    // Next cell that can still hold a closer hit; cells starting beyond the
    // closest hit so far (plus the test's distance error) are dropped.
    const float t_bound = best_t + delta_t;
    while (true) {
      if (sp == 0) return hit;
      const Entry& e = stack[--sp];
      if (e.t0 <= t_bound) {
        node = e.node;
        t0 = e.t0;
        t1 = e.t1 < t_bound ? e.t1 : t_bound;
        break;
      }
    }
  }
}

}  // namespace raylab
