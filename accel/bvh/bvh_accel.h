#pragma once
// `bvh`: the BVH family (builders x optimisation x layouts), see bvh_accel.cpp.
#include <string>

#include "accel/registry.h"

namespace raylab {

AcceleratorInfo bvh_accelerator_info();

// Instruction set the wide traversal kernels were compiled for ("avx512", "avx2", ...).
std::string bvh_kernel_isa();

}  // namespace raylab
