#include "accel/grid/grid_outline.h"

#include <algorithm>

namespace raylab {

namespace {

Aabb grid_box(const DdaGrid& g) {
  return Aabb(Vec3f(static_cast<float>(g.lo[0]), static_cast<float>(g.lo[1]), static_cast<float>(g.lo[2])),
              Vec3f(static_cast<float>(g.hi[0]), static_cast<float>(g.hi[1]), static_cast<float>(g.hi[2])));
}

// Occupied cells of a compressed-row cell list (offsets[c] < offsets[c + 1]).
bool add_occupied_cells(const DdaGrid& g, const uint32_t* offsets, int depth, StructureOutline& out) {
  const uint64_t cells = g.cells();
  for (uint64_t c = 0; c < cells; ++c)
    if (offsets[c + 1] > offsets[c] && !out.add(OutlineBox{g.cell_box_of_index(c), depth, true})) return false;
  return true;
}

}  // namespace

void grid_outline(const UniformGrid& grid, int max_depth, StructureOutline& out) {
  if (!out.begin("occupied grid cells", grid.empty, grid_box(grid.dda), max_depth)) return;
  add_occupied_cells(grid.dda, grid.lists.offsets.data(), 1, out);
}

void grid_outline(const HashGrid& grid, int max_depth, StructureOutline& out) {
  if (!out.begin("occupied grid cells (hashed)", grid.empty, grid_box(grid.dda), max_depth)) return;
  for (const CellSlot& slot : grid.table.slots())
    if (slot.key != CellHashTable::kEmptyKey && slot.count > 0 &&
        !out.add(OutlineBox{grid.dda.cell_box_of_index(slot.key), 1, true}))
      return;
}

void grid_outline(const TwoLevelGrid& grid, int max_depth, StructureOutline& out) {
  if (!out.begin("occupied top cells and sub-grid cells", grid.empty, grid_box(grid.top), max_depth)) return;
  const uint64_t cells = grid.top.cells();
  for (uint64_t c = 0; c < cells; ++c) {
    const uint32_t k = grid.top_cells[c];
    if (k == kEmptyTopCell) continue;
    const TopCellContent& content = grid.contents[k];
    if (!out.add(OutlineBox{grid.top.cell_box_of_index(c), 1, !content.has_subgrid()})) return;
    if (max_depth < 2 || !content.has_subgrid()) continue;
    if (!add_occupied_cells(content.dda(), grid.offsets.data() + content.offsets_base, 2, out)) return;
  }
}

// The implicit grid: a cell is occupied when the AND of its three slabs has a bit.
void grid_outline(const ImplicitGrid& grid, int max_depth, StructureOutline& out) {
  if (!out.begin("occupied grid cells (implicit: AND of slab bit arrays)", grid.empty, grid_box(grid.dda), max_depth)) return;
  for (int32_t z = 0; z < grid.dda.res[2]; ++z)
    for (int32_t y = 0; y < grid.dda.res[1]; ++y)
      for (int32_t x = 0; x < grid.dda.res[0]; ++x) {
        const size_t s[3] = {grid.slab(0, x), grid.slab(1, y), grid.slab(2, z)};
        const uint32_t lo = std::max({grid.word_lo[s[0]], grid.word_lo[s[1]], grid.word_lo[s[2]]});
        const uint32_t hi = std::min({grid.word_hi[s[0]], grid.word_hi[s[1]], grid.word_hi[s[2]]});
        bool any = false;
        for (uint32_t w = lo; w < hi && !any; ++w)
          any = (grid.bits[s[0] * grid.words + w] & grid.bits[s[1] * grid.words + w] & grid.bits[s[2] * grid.words + w]) != 0;
        if (any && !out.add(OutlineBox{grid.dda.cell_box_of_index(grid.dda.index(x, y, z)), 1, true})) return;
      }
}

}  // namespace raylab
