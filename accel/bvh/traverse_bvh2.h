#pragma once
// Front-to-back traversal of a binary BVH with an explicit stack. Both
// children's boxes are tested (conservative slab test, Ize 2013); the nearer
// one is visited first and the farther one pushed with its entry distance, so
// it can be skipped when a closer hit has been found by the time it is popped.
// Closest hit and any hit are the same routine (kAnyHit); counting is a
// compile-time switch (kCount), so the uninstrumented kernel pays nothing.
//
// Boxes are tested against tmax padded like the far planes (box_tmax): the
// computed entry distance of a box may exceed the true one by a few ulps, so
// comparing it with the exact distance of the current closest hit could cull
// a box holding a hit that is closer by less than that.
#include <cstdint>

#include "accel/accelerator.h"
#include "accel/bvh/bvh2_node.h"
#include "accel/core/hit_recorder.h"
#include "accel/core/leaf_triangle.h"
#include "accel/core/slab_test.h"

namespace raylab {

struct Bvh2View {
  const Bvh2Node* nodes = nullptr;
  const LeafTriangle* tris = nullptr;  // in leaf order: indexed like BinaryBvh::prim_ids
  bool empty = true;
};

// Stack depth needed: the builder bounds tree depth (median fallback beyond
// depth 96), and only far children are pushed.
inline constexpr int kBvh2StackSize = 192;

// The walk shared by the binary trees (Bvh2Node boxes, SphereNode spheres:
// nodes with `index` = left child or first triangle, `count` = 0 for inner
// nodes): `enters(node, tmin, bound, t)` tests a node's bounds against
// [tmin, bound] and gives the entry distance t. The caller's recorder has counted
// the ray and checked it.
template <TriangleTest kTest, typename Node, typename Recorder, typename Enters>
[[gnu::always_inline]] inline Hit walk_binary_bvh(const Node* nodes, const LeafTriangle* tris, const Ray& ray,
                                                  Recorder& rec, Enters&& enters) {
  const TrianglePrecompute<kTest> pre(ray);
  const float tmin = ray.tmin;
  float bound = pad_far(rec.tmax());

  struct Entry {
    uint32_t node;
    float t;
  };
  Entry stack[kBvh2StackSize];
  int sp = 0;

  float t_root;
  rec.count_nodes(1);
  if (!enters(nodes[0], tmin, bound, t_root)) return rec.hit();
  uint32_t node = 0;

  while (true) {
    const Node& n = nodes[node];
    if (n.count != 0) {
      rec.count_leaf(n.count);
      if (intersect_leaf(pre, ray, tris + n.index, n.count, rec)) {
        if constexpr (Recorder::kStopAtFirstHit) return rec.hit();
        bound = pad_far(rec.tmax());
      }
    } else {
      rec.count_inner(2);
      float tl, tr;
      const bool hl = enters(nodes[n.index], tmin, bound, tl);
      const bool hr = enters(nodes[n.index + 1], tmin, bound, tr);
      if (hl && hr) {
        // Both: the nearer now, the farther pushed with its entry distance.
        uint32_t near = n.index, far = n.index + 1;
        if (tr < tl) {
          std::swap(near, far);
          std::swap(tl, tr);
        }
        stack[sp++] = Entry{far, tr};
        node = near;
        continue;
      }
      if (hl) {
        node = n.index;
        continue;
      }
      if (hr) {
        node = n.index + 1;
        continue;
      }
    }
    // Pop the next subtree that can still hold a closer hit.
    while (true) {
      if (sp == 0) return rec.hit();
      const Entry e = stack[--sp];
      if (e.t <= bound) {
        node = e.node;
        break;
      }
    }
  }
}

// The entry of every binary BVH walk (box or sphere bounds): the recorder,
// the validity check, the node test's per-ray form (NodeRay, made once the
// ray is known to be valid), then the walk; enters(node_ray, node, tmin,
// bound, t) is the node test.
template <TriangleTest kTest, bool kAnyHit, bool kCount, typename NodeRay, typename View, typename Enters>
[[gnu::always_inline]] inline Hit trace_binary_bvh(const View& bvh, const Ray& ray, TraversalStats* stats,
                                                   Enters&& enters) {
  HitRecorder<kAnyHit, kCount> rec(ray, stats);
  if (bvh.empty || !ray_is_valid(ray)) return rec.hit();
  const NodeRay node_ray(ray);
  return walk_binary_bvh<kTest>(bvh.nodes, bvh.tris, ray, rec,
                                [&](const auto& n, float tmin, float bound, float& t) __attribute__((always_inline)) {
                                  return enters(node_ray, n, tmin, bound, t);
                                });
}

template <TriangleTest kTest, bool kAnyHit, bool kCount>
inline Hit traverse_bvh2(const Bvh2View& bvh, const Ray& ray, TraversalStats* stats) {
  // SlabRay has exact reciprocals (+-inf for zero components, see slab_test.h).
  return trace_binary_bvh<kTest, kAnyHit, kCount, SlabRay>(
      bvh, ray, stats, [](const SlabRay& sr, const Bvh2Node& n, float tmin, float bound, float& t)
                           __attribute__((always_inline)) { return slab_test(sr, n.lo, n.hi, tmin, bound, t); });
}

// The walk under the name the generic shells call (accel/core/view_accelerator.h).
template <TriangleTest kTest, bool kAnyHit, bool kCount>
inline Hit traverse_view(const Bvh2View& v, const Ray& ray, TraversalStats* stats) { return traverse_bvh2<kTest, kAnyHit, kCount>(v, ray, stats); }

}  // namespace raylab
