#pragma once
// The order of an any-hit (occlusion) walk through a space partitioning (k-d
// tree, BSP, octree; the grids and the irregular grid, whose DDA walks the
// reversed line, grid/dda.h): the `anyhit` parameter, declared and parsed in
// one place.
//
// An occlusion query asks whether any triangle lies on the segment, so the
// walk may visit the cells in any order and still give the same answer (it
// stops at the first hit; with none it visits every cell on the segment
// either way). Front to back (the closest-hit order) starts at the origin,
// which for a shadow ray lies on a surface, in the densest cells of the
// tree, whose triangles (the surface it leaves and its neighbours) rarely
// occlude. Back to front starts at the far end, the light, which usually
// lies in open space, so an occluder between is found after fewer steps.
// Measured on the interior views (docs/structures/kdtree.md): node
// steps per shadow ray 25.5 -> 13.7 on sponza and 36.5 -> 13.2 on
// dragon_in_sponza, 2-3x faster; 10 % more steps on the conference room and
// the bunny, whose occluders lie nearer the origin, at the same speed.
// The grids: 1.7-4.4x on the atrium views, up to 23 % slower on the bunny and
// the conference room (docs/structures/irgrid.md).
// Neither order wins everywhere: on the bunny (a point light above one
// object that shadows itself) the irregular grid's shadow rays run 1.45x
// faster front to back, on the atrium views 1.6-3x slower. `anyhit=auto`
// measures instead of guessing: every eighth batch of occlusion rays traces
// a few sample rays both ways with the work counted, and the batches walk in
// the order the samples found cheaper (accel/core/batch_accelerator.h).
// The answers are the same in every order;
// only the work differs.
#include <cstddef>
#include <cstdint>

#include "accel/accelerator.h"
#include "base/spec.h"

namespace raylab {

enum class AnyHitOrder { Front, Back, Auto };

inline ParamInfo any_hit_order_param() {
  return ParamInfo{"anyhit", "auto",
                   "order of the any-hit (occlusion) walk: back (from the segment's far end), front (front to back, "
                   "the closest-hit order) or auto (per batch, the order that costs less on sample rays); same "
                   "answers",
                   one_of({"back", "front", "auto"})};
}

inline AnyHitOrder parse_any_hit_order(const Params& p) {
  const std::string& s = p.str("anyhit");
  return s == "back" ? AnyHitOrder::Back : s == "front" ? AnyHitOrder::Front : AnyHitOrder::Auto;
}

// anyhit=auto (the shell's occluded_in_order). Batches of kAutoMinRays rays
// or more are sampled, one in kAutoSamplePeriod: kAutoSamples rays, evenly
// spread over the batch, are traced in both orders. A sample's cost is its
// cell or node steps plus kAutoTriangleWeight per triangle test (a SIMD
// block tests 4-8 triangles for about the price of one or two steps). Ties
// go to the back order.
inline constexpr size_t kAutoMinRays = 64;
inline constexpr size_t kAutoSamples = 4;
inline constexpr uint32_t kAutoSamplePeriod = 8;  // batches per sampled batch
inline constexpr float kAutoScoreKeep = 0.5f;     // weight of the score so far at each update
inline constexpr double kAutoTriangleWeight = 0.25;

inline double any_hit_sample_cost(const TraversalStats& s) {
  return static_cast<double>(s.nodes_visited) + kAutoTriangleWeight * static_cast<double>(s.triangle_tests);
}

// Runs `walk.template operator()<kFarFirst>()` with kFarFirst = far_first for
// any-hit walks and false for closest-hit walks (whose order is fixed), so a
// structure's trace() picks the walk in one line and no closest-hit walk is
// ever instantiated with the reversed order.
template <bool kAnyHit, typename Walk>
[[gnu::always_inline]] inline auto walk_in_any_hit_order(bool far_first, Walk&& walk) {
  if constexpr (kAnyHit) {
    if (far_first) return walk.template operator()<true>();
  }
  return walk.template operator()<false>();
}

}  // namespace raylab
