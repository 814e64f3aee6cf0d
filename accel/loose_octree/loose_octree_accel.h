#pragma once
// `loose_octree`: Ulrich's loose octree (looseness k), each triangle stored once.
#include "accel/registry.h"

namespace raylab {

AcceleratorInfo loose_octree_accelerator_info();

}  // namespace raylab
