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
// Measured on the interior views (docs/fair-fight.md, section 2c): node
// steps per shadow ray 25.5 -> 13.7 on sponza and 36.5 -> 13.2 on
// dragon_in_sponza, 2-3x faster; 10 % more steps on the conference room and
// the bunny, whose occluders lie nearer the origin, at the same speed.
// The grids: 1.7-4.4x on the atrium views, up to 23 % slower on the bunny and
// the conference room (docs/fair-fight.md, section 4b).
#include "base/spec.h"

namespace raylab {

inline ParamInfo any_hit_order_param() {
  return ParamInfo{"anyhit", "back",
                   "order of the any-hit (occlusion) walk: back (from the segment's far end) or front (front to back, "
                   "the closest-hit order); same answers, docs/fair-fight.md",
                   one_of({"back", "front"})};
}

// True when any-hit walks visit cells from the far end.
inline bool parse_any_hit_far_first(const Params& p) { return p.str("anyhit") == "back"; }

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
