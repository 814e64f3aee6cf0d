#pragma once
// The loose box of an octree node (Ulrich, "Loose Octrees", Game
// Programming Gems, 2000; Ericson, Real-Time Collision Detection, 7.3.6):
// the node's cube grown about its centre by the looseness factor k, i.e. by
// (k - 1) / 2 of its side on every face (k = 2: each side doubled). One
// float formula, used by the builder (containment) and the walk (slab
// test), so both see the same box bit for bit.
#include <cstdint>

#include "accel/octree/octree_cube.h"

namespace raylab {

struct LooseBoxes {
  OctreeCube cube;
  float grow_per_unit = 0.5f;  // (k - 1) / 2

  [[gnu::always_inline]] void box(int level, const uint32_t c[3], float lo[3], float hi[3]) const {
    const uint32_t s = OctreeCube::span(level);
    const float grow = grow_per_unit * (static_cast<float>(s) * cube.unit);
    for (int k = 0; k < 3; ++k) {
      lo[k] = cube.plane(k, c[k]) - grow;
      hi[k] = cube.plane(k, c[k] + s) + grow;
    }
  }
};

}  // namespace raylab
