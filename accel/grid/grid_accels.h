#pragma once
// The grid accelerators, for the registry:
//   grid      dense uniform grid (uniform_grid.h)
//   hashgrid  uniform grid storing only occupied cells in a hash table (hash_grid.h)
//   grid2     two-level grid (two_level_grid.h)
#include "accel/registry.h"

namespace raylab {

AcceleratorInfo grid_accelerator_info();
AcceleratorInfo hashgrid_accelerator_info();
AcceleratorInfo grid2_accelerator_info();

}  // namespace raylab
