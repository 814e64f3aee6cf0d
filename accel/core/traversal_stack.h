#pragma once
// The explicit stack of the front-to-back interval walks, with the step each
// walk shares: which child to enter, what to push, and which pushed subtree may
// still hold a closer hit. The walks themselves (what a node's bounds are,
// how a leaf is tested) stay with each structure.
#include <cstdint>

namespace raylab {

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

  // descend() for the trees that store two children side by side, below the
  // plane at first_child and above it at first_child + 1: a ray going down
  // (neg = 1, its direction's sign bit, -0 included) meets the upper one first.
  [[gnu::always_inline]] uint32_t descend_pair(uint32_t first_child, uint32_t neg, float t_near_end,
                                               float t_far_start, float t0, float& t1) {
    return descend(first_child + neg, first_child + 1u - neg, t_near_end, t_far_start, t0, t1);
  }

  // The any-hit walk's back-to-front step (accel/core/any_hit_order.h):
  // the child the ray crosses last is visited first, with its interval
  // (t0 raised to where it begins), and the near one is pushed with its own
  // [t0, t_near_end]; with one child crossed the interval stays as it is.
  [[gnu::always_inline]] uint32_t descend_far_first(uint32_t near, uint32_t far, float t_near_end,
                                                    float t_far_start, float& t0, float t1) {
    const bool visit_near = !(t_near_end < t0);
    const bool visit_far = !(t_far_start > t1);
    stack_[sp_] = Entry{near, t0, t_near_end < t1 ? t_near_end : t1};
    sp_ += (visit_near && visit_far) ? 1 : 0;
    t0 = (visit_far && t_far_start > t0) ? t_far_start : t0;
    return visit_far ? far : near;
  }

  // One step of either order for child pairs (see descend_pair).
  template <bool kFarFirst>
  [[gnu::always_inline]] uint32_t descend_pair_in_order(uint32_t first_child, uint32_t neg, float t_near_end,
                                                        float t_far_start, float& t0, float& t1) {
    if constexpr (kFarFirst)
      return descend_far_first(first_child + neg, first_child + 1u - neg, t_near_end, t_far_start, t0, t1);
    else
      return descend_pair(first_child, neg, t_near_end, t_far_start, t0, t1);
  }

  // After a leaf: false when the walk is over, because an any-hit walk kept a
  // hit there (`kept`) or no pushed cell can still hold a closer one;
  // otherwise the next cell and its interval, as pop_within().
  template <bool kAnyHit>
  [[gnu::always_inline]] bool next_after_leaf(bool kept, float t_bound, uint32_t& node, float& t0, float& t1) {
    if constexpr (kAnyHit) {
      if (kept) return false;
    }
    return pop_within(t_bound, node, t0, t1);
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
