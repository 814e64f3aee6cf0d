#pragma once
// `irgrid`: the irregular grid of Perard-Gayot, Kalojanov & Slusallek 2017 (irgrid.h).
#include "accel/registry.h"

namespace raylab {

AcceleratorInfo irgrid_accelerator_info();

}  // namespace raylab
