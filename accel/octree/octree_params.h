#pragma once
// The spec parameters the octree family (octree, loose_octree) declares alike:
// the leaf size and the SIMD node lists.
#include <string>

#include "base/spec.h"

namespace raylab {

inline ParamInfo octree_leaf_param(std::string help) {
  return ParamInfo{"leaf", "4", std::move(help), integer_in(1, 1000)};
}

inline ParamInfo octree_simd_param() {
  return ParamInfo{"simd", "1",
                   "1 = node lists as 4-wide SIMD triangle blocks (tri=watertight); 0 = scalar tests of the same lists "
                   "(same hits)",
                   boolean_flag()};
}

}  // namespace raylab
