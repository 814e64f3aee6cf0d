#pragma once
// The hit recorder every traversal carries: it owns hit acceptance, the
// current bound (closest hit so far, or the ray's tmax) and the per-ray
// counters. Closest hit vs any hit (kAnyHit) and counting (kCount) are
// compile-time switches, so the uninstrumented kernels pay nothing for the
// counters. Each structure keeps its own walk and asks the recorder, as
// madmann91/bvh v2 separates its top-down walk from the leaf function.
//
// Counting, one definition for every structure (README "Statistics"):
//  - a ray: every ray handed to a traversal, valid or not;
//  - a node visited: an inner node or leaf whose bounds the ray is tested
//    against (a BVH counts each child box it tests, the root's included; a
//    k-d tree, whose cells are implicit, each node it enters), and for grids
//    each cell the walk enters (top cells and sub-grid cells alike);
//  - a triangle test: one ray-triangle test (SIMD blocks count their
//    distinct triangles).
#include <algorithm>
#include <cstdint>
#include <limits>

#include "accel/accelerator.h"
#include "base/hit.h"
#include "base/ray.h"

namespace raylab {

template <bool kAnyHit, bool kCount>
class HitRecorder {
 public:
  // Any hit ends the walk at the first hit kept.
  static constexpr bool kStopAtFirstHit = kAnyHit;

  // The bound starts at the ray's tmax, but at most FLT_MAX: a hit's
  // distance is a finite float. A triangle met beyond FLT_MAX (a tiny
  // direction, a far origin) rounds to t = +inf, the miss value of Hit::t;
  // it is a miss for every structure, as for Embree (found by fuzz_rays: the
  // grids' and trees' walks could not all agree on which of several hits at
  // +inf comes first).
  HitRecorder(const Ray& ray, TraversalStats* stats)
      : tmax_(std::min(ray.tmax, std::numeric_limits<float>::max())), stats_(stats) {
    if constexpr (kCount) stats_->rays++;
  }

  // Triangle tests are made on [ray.tmin, tmax()].
  float tmax() const { return tmax_; }
  bool found() const { return hit_.valid(); }
  const Hit& hit() const { return hit_; }

  // Hit acceptance, the one rule: a candidate the triangle test reported
  // within [tmin, tmax()] is kept when it is strictly nearer than the hit so
  // far, or when it is the first; among exact ties the lower primitive id
  // wins. The answer is then the least (t, prim) pair over every triangle
  // hit, whatever order a traversal visits them in (a packet and a single-ray
  // walk of the same tree agree bit for bit; so does the brute-force scan).
  // The first candidate is always kept: the triangle tests report t <= tmax
  // and the miss id kInvalidPrim exceeds every primitive id.
  // Returns true when the candidate was kept.
  [[gnu::always_inline]] bool record(float t, float u, float v, uint32_t prim) {
    if (t < tmax_ || (t == tmax_ && prim < hit_.prim)) {
      hit_ = Hit{t, u, v, prim};
      tmax_ = t;
      return true;
    }
    return false;
  }

  [[gnu::always_inline]] void count_nodes(uint64_t n) {
    if constexpr (kCount) stats_->nodes_visited += n;
  }
  [[gnu::always_inline]] void count_triangles(uint64_t n) {
    if constexpr (kCount) stats_->triangle_tests += n;
  }

 private:
  Hit hit_;
  float tmax_;
  TraversalStats* stats_;
};

}  // namespace raylab
