#pragma once
// Front-to-back k-d tree traversal with an explicit stack: the recursive ray
// traversal algorithm (Jansen 1986; Arvo; Havran's thesis, 2000, "TA_rec"),
// written with distances along the ray instead of entry/exit points.
//
// The ray's [tmin, tmax] is first clipped to the root cell (conservative slab
// test of Ize 2013, accel/core/slab_test.h). At an inner node the distance
// t_split to the split plane decides: the child on the ray's origin side
// ("near") covers t < t_split, the other ("far") t > t_split; when both are
// crossed, far is pushed with its interval and near is visited first.
//
// Robustness, so float rounding never skips a cell the ray really crosses:
//  - t_split has a relative error of at most gamma(3) (subtraction, rounded
//    reciprocal, product); both children are given intervals padded by twice
//    that, so neighbouring cells overlap slightly at their common plane
//    instead of leaving a gap.
//  - Rays parallel to a split plane (direction component +0 or -0) get
//    t_split = +-inf from IEEE division and visit the side of their origin; a
//    ray lying in the plane itself gets NaN and visits both children with the
//    full interval (all comparisons below are written so NaN means "visit").
//    Denormal components, whose reciprocal overflows, are treated the same
//    conservative way.
//  - Triangles are tested on the ray's whole remaining segment
//    [tmin, closest hit so far], not just the leaf's. A hit is accepted as
//    the answer once no cell left on the stack begins before it: a hit inside
//    the current leaf's (padded) interval ends the traversal, while a hit
//    beyond the leaf (the triangle reaches into later cells) is kept as a
//    bound and the traversal goes on only through cells that start before
//    it. This is the leaf-interval rule of the classic algorithm without its
//    risk of rejecting a real hit a rounding error away from the leaf.
// Closest hit and any hit are one routine (kAnyHit returns at the first hit);
// counting is a compile-time switch (kCount).
#include <cmath>
#include <cstdint>
#include <limits>

#include "accel/accelerator.h"
#include "accel/core/intersect_triangle.h"
#include "accel/core/slab_test.h"
#include "accel/kdtree/kdtree_node.h"

namespace raylab {

// Triangle vertices copied in leaf order next to their original ids, so a
// leaf's triangles are contiguous (a triangle in several leaves is copied
// once per leaf).
struct KdLeafTriangle {
  Vec3f p0, p1, p2;
  uint32_t prim;
};

struct KdTreeView {
  const KdNode* nodes = nullptr;
  const KdLeafTriangle* tris = nullptr;
  const uint32_t* ids = nullptr;  // leaf ranges of indices into tris
  Aabb bounds;
  bool empty = true;
};

// Relative padding of split distances and of the root entry distance.
inline constexpr float kKdPad = 4.0f * kFloatGamma3;
inline constexpr float kKdPadUp = 1.0f + kKdPad;
inline constexpr float kKdPadDown = 1.0f - kKdPad;

template <TriangleTest kTest, bool kAnyHit, bool kCount>
inline Hit traverse_kdtree(const KdTreeView& tree, const Ray& ray, TraversalStats* stats) {
  Hit hit;
  if constexpr (kCount) stats->rays++;
  if (tree.empty || !ray_is_valid(ray) || !(ray.tmin <= ray.tmax)) return hit;

  // Clip to the root cell. Axes the ray is parallel to only need the origin
  // inside the slab (the slab test's tiny-reciprocal trick would cut a ray
  // lying in a face of the cell down to t = 0).
  const SlabRay sr(ray);
  float t0 = ray.tmin, t1 = ray.tmax;
  for (int k = 0; k < 3; ++k) {
    const float lo = tree.bounds.lo[k], hi = tree.bounds.hi[k];
    if (ray.dir[k] == 0.0f) {
      if (ray.org[k] < lo || ray.org[k] > hi) return hit;
      continue;
    }
    const float near_plane = sr.neg[k] ? hi : lo, far_plane = sr.neg[k] ? lo : hi;
    float tn = (near_plane - ray.org[k]) * sr.inv_dir[k];
    const float tf = (far_plane - ray.org[k]) * sr.inv_dir[k] * kSlabFarScale;
    tn = tn >= 0.0f ? tn * kKdPadDown : tn * kKdPadUp;
    t0 = tn > t0 ? tn : t0;
    t1 = tf < t1 ? tf : t1;
  }
  if (!(t0 <= t1)) return hit;

  // Exact IEEE reciprocals for the split planes: +-0 gives +-inf (parallel
  // rays); a denormal component whose reciprocal overflows gets NaN, which
  // makes every split along that axis visit both children.
  float inv[3];
  uint32_t neg[3];
  for (int k = 0; k < 3; ++k) {
    const float d = ray.dir[k];
    inv[k] = 1.0f / d;
    if (d != 0.0f && std::isinf(inv[k])) inv[k] = std::numeric_limits<float>::quiet_NaN();
    neg[k] = std::signbit(d) ? 1u : 0u;
  }

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
      const float ts = (n.split() - ray.org[k]) * inv[k];
      float ts_lo, ts_hi;  // NaN stays NaN
      if (ts >= 0.0f) {
        ts_lo = ts * kKdPadDown;
        ts_hi = ts * kKdPadUp;
      } else {
        ts_lo = ts * kKdPadUp;
        ts_hi = ts * kKdPadDown;
      }
      // Below child = child(), above = child() + 1; a ray going down (sign
      // bit set, -0 included) is above the plane before t_split.
      const uint32_t near = n.child() + neg[k];
      const uint32_t far = n.child() + 1u - neg[k];
      const bool visit_near = !(ts_hi < t0);
      const bool visit_far = !(ts_lo > t1);
      // Branch-free: the far entry is always written but only kept when
      // both children are visited. With one child only the interval stays
      // as it is (the padded plane lies outside it).
      stack[sp] = Entry{far, ts_lo > t0 ? ts_lo : t0, t1};
      sp += (visit_near && visit_far) ? 1 : 0;
      t1 = (visit_near && ts_hi < t1) ? ts_hi : t1;
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
    // closest hit so far are dropped.
    while (true) {
      if (sp == 0) return hit;
      const Entry& e = stack[--sp];
      if (e.t0 <= best_t) {
        node = e.node;
        t0 = e.t0;
        t1 = e.t1 < best_t ? e.t1 : best_t;
        break;
      }
    }
  }
}

}  // namespace raylab
