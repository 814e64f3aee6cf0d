#pragma once
// `bvh`: binary BVH built by binned SAH, traversed front to back.
#include "accel/registry.h"

namespace raylab {

AcceleratorInfo bvh_accelerator_info();

}  // namespace raylab
