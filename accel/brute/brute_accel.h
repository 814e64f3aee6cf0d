#pragma once
// `brute`: tests every triangle for every ray. Ground truth for small scenes.
#include "accel/registry.h"

namespace raylab {

AcceleratorInfo brute_accelerator_info();

}  // namespace raylab
