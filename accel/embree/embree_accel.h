#pragma once
// `embree`: adapter over Embree 3, the reference for hits and speed.
#include "accel/registry.h"

namespace raylab {

AcceleratorInfo embree_accelerator_info();

// Version and the ISA Embree selected on this machine (e.g. "3.13.5 AVX512").
std::string embree_version_string();

}  // namespace raylab
