#pragma once
// The dense uniform grid as its walk sees it: every cell's list in
// compressed rows (offsets[cell] .. offsets[cell + 1] in refs, or in blocks).
#include <cstdint>

#include "accel/grid/traverse_single_level_grid.h"
#include "accel/grid/uniform_grid.h"

namespace raylab {

struct DenseCells {
  const uint32_t* offsets = nullptr;

  [[gnu::always_inline]] bool find(int64_t cell, uint32_t& begin, uint32_t& count) const {
    begin = offsets[cell];
    count = offsets[cell + 1] - begin;
    return count != 0;
  }
};

using UniformGridView = SingleLevelGridView<DenseCells>;

inline UniformGridView grid_view(const UniformGrid& g) {
  return UniformGridView{g.dda,
                         DenseCells{g.lists.offsets.data()},
                         g.lists.refs.data(),
                         g.tris.data(),
                         g.blocks.empty() ? nullptr : g.blocks.data(),
                         g.clearance.empty() ? nullptr : g.clearance.data(),
                         g.empty};
}

}  // namespace raylab
