#pragma once
// `hgrid`: Ericson's hierarchical grid (hgrid.h).
#include "accel/registry.h"

namespace raylab {

AcceleratorInfo hgrid_accelerator_info();

}  // namespace raylab
