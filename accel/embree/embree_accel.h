#pragma once
// `embree`: adapter over Embree 3, the reference for hits and speed.
#include "accel/registry.h"

namespace raylab {

AcceleratorInfo embree_accelerator_info();

// Version and the ISA Embree selected on this machine ({"version", "3.13.5"},
// {"isa", "AVX512"}): the registry's description hook.
Description embree_description();

}  // namespace raylab
