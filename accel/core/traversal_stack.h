#pragma once
// The explicit stacks of the front-to-back walks, with the step each walk
// shares: which child to enter, what to push, and which pushed subtree may
// still hold a closer hit. The walks themselves (what a node's bounds are,
// how a leaf is tested) stay with each structure.
#include <cstdint>

namespace raylab {

// Bounding-volume trees (binary BVH, sphere BVH): subtrees pushed with the
// distance at which the ray enters their bounds.
template <int kSize>
class EntryDistanceStack {
 public:
  // Both children of `first` (at first, first + 1) are hit, at t_first and
  // t_second: returns the nearer one to visit now and pushes the farther.
  [[gnu::always_inline]] uint32_t visit_nearer(uint32_t first, float t_first, float t_second) {
    if (t_second < t_first) {
      stack_[sp_++] = Entry{first, t_first};
      return first + 1;
    }
    stack_[sp_++] = Entry{first + 1, t_second};
    return first;
  }

  // Pops until a subtree entered no later than `bound` (the padded closest
  // hit so far) comes up; false when the stack runs empty.
  [[gnu::always_inline]] bool pop_within(float bound, uint32_t& node) {
    while (sp_ > 0) {
      const Entry e = stack_[--sp_];
      if (e.t <= bound) {
        node = e.node;
        return true;
      }
    }
    return false;
  }

 private:
  struct Entry {
    uint32_t node;
    float t;
  };
  Entry stack_[kSize];
  int sp_ = 0;
};

// Space-partitioning trees (k-d tree, BSP): cells pushed with the ray's
// interval [t0, t1] inside them (the recursive ray traversal, Jansen 1986;
// Havran's thesis, 2000, "TA_rec").
template <int kSize>
class IntervalStack {
 public:
  // An inner node: the ray is in [t0, t1]; it leaves the near child at
  // t_near_end and enters the far one at t_far_start (both already padded
  // by the walk's margin; NaN means "visit"). Returns the child to visit
  // now and narrows t1 to it; when both are crossed, far is pushed with its
  // interval. Branch-free: the far entry is always written but only kept
  // when both children are visited; with one child only the interval stays
  // as it is (the padded plane lies outside it).
  [[gnu::always_inline]] uint32_t descend(uint32_t near, uint32_t far, float t_near_end, float t_far_start, float t0,
                                          float& t1) {
    const bool visit_near = !(t_near_end < t0);
    const bool visit_far = !(t_far_start > t1);
    stack_[sp_] = Entry{far, t_far_start > t0 ? t_far_start : t0, t1};
    sp_ += (visit_near && visit_far) ? 1 : 0;
    t1 = (visit_near && t_near_end < t1) ? t_near_end : t1;
    return visit_near ? near : far;
  }

  // The next cell that can still hold a closer hit: cells starting beyond
  // t_bound (the closest hit so far plus the test's distance error) are
  // dropped. False when the stack runs empty.
  [[gnu::always_inline]] bool pop_within(float t_bound, uint32_t& node, float& t0, float& t1) {
    while (sp_ > 0) {
      const Entry& e = stack_[--sp_];
      if (e.t0 <= t_bound) {
        node = e.node;
        t0 = e.t0;
        t1 = e.t1 < t_bound ? e.t1 : t_bound;
        return true;
      }
    }
    return false;
  }

 private:
  struct Entry {
    uint32_t node;
    float t0, t1;
  };
  // One entry per inner node on the current path at most.
  Entry stack_[kSize];
  int sp_ = 0;
};

}  // namespace raylab
