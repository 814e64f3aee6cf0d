#pragma once
// `hybrid`: structures inside structures (the textbook's two hybrid kinds):
//   inner=bvh|kdtree  a coarse uniform grid whose non-empty cells hold their
//                     own small BVH or k-d tree (the grid of trees);
//   inner=entry       one k-d tree over the whole scene plus a grid of entry
//                     nodes where rays starting inside the scene begin.
#include "accel/registry.h"

namespace raylab {

AcceleratorInfo hybrid_accelerator_info();

}  // namespace raylab
