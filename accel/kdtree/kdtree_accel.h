#pragma once
// `kdtree`: k-d tree with the O(N log N) SAH build of Wald & Havran (2006),
// perfect splits, and front-to-back traversal (Havran 2000).
#include "accel/registry.h"

namespace raylab {

AcceleratorInfo kdtree_accelerator_info();

}  // namespace raylab
