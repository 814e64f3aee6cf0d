#pragma once
// The spec parameters the octree family (octree, loose_octree) declares alike:
// the leaf size (`simd` is the core's simd_param).
#include <string>

#include "base/spec.h"

namespace raylab {

inline ParamInfo octree_leaf_param(std::string help) {
  return ParamInfo{"leaf", "4", std::move(help), integer_in(1, 1000)};
}

}  // namespace raylab
