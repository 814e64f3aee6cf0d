#pragma once
// `bsp`: general BSP tree with free split planes (axes, 26-DOP directions and
// the triangles' own planes), SAH on exact polytope areas, after Ize, Wald &
// Parker 2008; k-d fast path for axis-aligned nodes in the traversal.
#include "accel/registry.h"

namespace raylab {

AcceleratorInfo bsp_accelerator_info();

}  // namespace raylab
