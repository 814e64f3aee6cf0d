#pragma once
// Structures whose leaves may be stored as SIMD triangle blocks (k-d tree,
// octree, loose octree: simd=1 with the watertight test) have two variants
// of their walk (kBlocks). The blocks are wanted only with the watertight
// test, and the view's `blocks` pointer says whether they were built; this
// picks the walk once per ray, in one place.
#include "accel/core/intersect_triangle.h"
#include "base/hit.h"

namespace raylab {

inline bool leaf_blocks_wanted(bool simd, TriangleTest test) { return simd && test == TriangleTest::Watertight; }

// walk.template operator()<kBlocks>(): the structure's walk of that variant.
template <TriangleTest kTest, typename View, typename Walk>
[[gnu::always_inline]] inline Hit walk_with_leaf_blocks(const View& view, Walk&& walk) {
  if constexpr (kTest == TriangleTest::Watertight) {
    if (view.blocks) return walk.template operator()<true>();
  }
  return walk.template operator()<false>();
}

}  // namespace raylab
