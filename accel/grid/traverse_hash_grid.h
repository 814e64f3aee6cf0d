#pragma once
// The hashed grid as its walk sees it: each visited cell is looked up in the
// hash table by its linear index; a cell that is not stored is empty.
#include <cstdint>

#include "accel/grid/traverse_single_level_grid.h"
#include "accel/grid/hash_grid.h"

namespace raylab {

struct HashedCells {
  const CellHashTable* table = nullptr;

  [[gnu::always_inline]] bool find(int64_t cell, uint32_t& begin, uint32_t& count) const {
    const CellSlot* slot = table->find(static_cast<uint64_t>(cell));
    if (!slot) return false;
    begin = slot->begin;
    count = slot->count;
    return true;
  }
};

using HashGridView = SingleLevelGridView<HashedCells>;

inline HashGridView grid_view(const HashGrid& g) {
  return HashGridView{g.dda,   HashedCells{&g.table}, g.refs.data(), g.tris.data(), g.blocks.empty() ? nullptr : g.blocks.data(),
                      nullptr, g.empty};
}

}  // namespace raylab
