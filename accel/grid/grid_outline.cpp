#include "accel/grid/grid_outline.h"

namespace raylab {

namespace {

Aabb grid_box(const DdaGrid& g) {
  return Aabb(Vec3f(static_cast<float>(g.lo[0]), static_cast<float>(g.lo[1]), static_cast<float>(g.lo[2])),
              Vec3f(static_cast<float>(g.hi[0]), static_cast<float>(g.hi[1]), static_cast<float>(g.hi[2])));
}

// The box of cell (x, y, z) of `g`, from the same boundaries the DDA uses.
Aabb cell_box(const DdaGrid& g, int64_t x, int64_t y, int64_t z) {
  const int64_t c[3] = {x, y, z};
  Aabb b;
  for (int a = 0; a < 3; ++a) {
    b.lo[a] = static_cast<float>(g.boundary(a, c[a]));
    b.hi[a] = static_cast<float>(g.boundary(a, c[a] + 1));
  }
  return b;
}

// Linear index (x + rx * (y + ry * z)) to its cell box.
Aabb cell_box_of_index(const DdaGrid& g, uint64_t index) {
  const uint64_t rx = static_cast<uint64_t>(g.res[0]), ry = static_cast<uint64_t>(g.res[1]);
  return cell_box(g, static_cast<int64_t>(index % rx), static_cast<int64_t>((index / rx) % ry),
                  static_cast<int64_t>(index / (rx * ry)));
}

// Occupied cells of a compressed-row cell list (offsets[c] < offsets[c + 1]).
bool add_occupied_cells(const DdaGrid& g, const uint32_t* offsets, int depth, StructureOutline& out) {
  const uint64_t cells = g.cells();
  for (uint64_t c = 0; c < cells; ++c)
    if (offsets[c + 1] > offsets[c] && !out.add(OutlineBox{cell_box_of_index(g, c), depth, true})) return false;
  return true;
}

}  // namespace

void grid_outline(const UniformGrid& grid, int max_depth, StructureOutline& out) {
  out.what = "occupied grid cells";
  if (grid.empty || !out.add(OutlineBox{grid_box(grid.dda), 0, false}) || max_depth < 1) return;
  add_occupied_cells(grid.dda, grid.lists.offsets.data(), 1, out);
}

void grid_outline(const HashGrid& grid, int max_depth, StructureOutline& out) {
  out.what = "occupied grid cells (hashed)";
  if (grid.empty || !out.add(OutlineBox{grid_box(grid.dda), 0, false}) || max_depth < 1) return;
  for (const CellSlot& slot : grid.table.slots())
    if (slot.key != CellHashTable::kEmptyKey && slot.count > 0 &&
        !out.add(OutlineBox{cell_box_of_index(grid.dda, slot.key), 1, true}))
      return;
}

void grid_outline(const TwoLevelGrid& grid, int max_depth, StructureOutline& out) {
  out.what = "occupied top cells and sub-grid cells";
  if (grid.empty || !out.add(OutlineBox{grid_box(grid.top), 0, false}) || max_depth < 1) return;
  const uint64_t cells = grid.top.cells();
  for (uint64_t c = 0; c < cells; ++c) {
    const uint32_t k = grid.top_cells[c];
    if (k == kEmptyTopCell) continue;
    const TopCellContent& content = grid.contents[k];
    if (!out.add(OutlineBox{cell_box_of_index(grid.top, c), 1, !content.has_subgrid()})) return;
    if (max_depth < 2 || !content.has_subgrid()) continue;
    if (!add_occupied_cells(content.dda(), grid.offsets.data() + content.offsets_base, 2, out)) return;
  }
}

}  // namespace raylab
