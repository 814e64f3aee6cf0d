#pragma once
// `octree`: regular octree (exact or straddle assignment; pointer, linear or
// hashed layout) with the parametric traversal of Revelles et al. (2000).
#include "accel/registry.h"

namespace raylab {

AcceleratorInfo octree_accelerator_info();

}  // namespace raylab
