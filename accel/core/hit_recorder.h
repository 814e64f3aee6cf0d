#pragma once
// The hit recorder every traversal carries: it owns hit acceptance, the
// current bound (closest hit so far, or the ray's tmax) and the per-ray
// counters. Closest hit vs any hit (kAnyHit) and counting (kCount) are
// compile-time switches, so the uninstrumented kernels pay nothing for the
// counters. Each structure keeps its own walk and asks the recorder, as
// madmann91/bvh v2 separates its top-down walk from the leaf function.
//
// Counting, one definition for every structure, defined once in
// docs/json-reports.md ("Per-ray counters"): rays; Havran's traversal steps
// (count_step: an inner node visited or a grid cell entered), leaves and
// empty leaves visited (count_leaf: a triangle list tested, or none to
// test); triangle tests (count_triangles); and nodes visited, i.e. bounds
// tests (count_nodes). A grid cell is all three of a node, a step and a
// leaf or empty leaf (count_cell).
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
  [[gnu::always_inline]] void count_step() {
    if constexpr (kCount) stats_->steps++;
  }
  // An inner node visited whose walk tested `bounds` bounds: nodes and a step.
  [[gnu::always_inline]] void count_inner(uint64_t bounds = 1) {
    count_nodes(bounds);
    count_step();
  }
  // A leaf (or cell) visited that holds `triangles` triangles (or blocks):
  // a leaf when it holds some, an empty leaf otherwise.
  [[gnu::always_inline]] void count_leaf(uint64_t triangles) {
    if constexpr (kCount) (triangles ? stats_->leaves : stats_->empty_leaves)++;
  }
  // A grid cell entered: a node visited, a step, and a leaf or empty leaf.
  [[gnu::always_inline]] void count_cell(uint64_t triangles) {
    count_inner();
    count_leaf(triangles);
  }
  // The work of an inner walk made for this ray (its ray not counted again).
  [[gnu::always_inline]] void count_walk(const TraversalStats& inner) {
    if constexpr (kCount) stats_->add_walk(inner);
  }

 private:
  Hit hit_;
  float tmax_;
  TraversalStats* stats_;
};

}  // namespace raylab
