#pragma once
// Static compressed-row storage of a dense grid's cells: one contiguous
// array of triangle ids, and per cell the offset of its first id
// (offsets[c] .. offsets[c+1]). No linked lists, no per-cell vectors.
//
// Built in parallel (TBB) in three passes over the triangles:
//   1. count: every triangle adds one to each cell it is assigned to;
//   2. prefix sum of the counts gives the offsets;
//   3. fill: every triangle writes its id at a cursor of each of its cells.
// Ids within a cell are then sorted, so the layout (and tie-breaking between
// equally near triangles) does not depend on thread scheduling.
#include <cstdint>
#include <span>
#include <vector>

#include "accel/core/grid/cell_overlap.h"
#include "accel/core/leaf_triangle.h"

namespace raylab {

struct CellLists {
  std::vector<uint32_t> offsets;  // cells + 1 entries
  std::vector<uint32_t> refs;     // triangle ids, grouped by cell

  size_t bytes() const { return (offsets.capacity() + refs.capacity()) * sizeof(uint32_t); }
};

// Assigns the triangles `ids` (indices into `tris`) to the cells of `g`.
// Returns false, leaving `out` empty, when the references would exceed
// `max_refs` (checked after the count pass, before the fill allocates).
bool build_cell_lists(const DdaGrid& g, AssignMode mode, std::span<const LeafTriangle> tris,
                      std::span<const uint32_t> ids, uint64_t max_refs, CellLists& out);

// Figures about a cell list (cells, non-empty cells, references).
struct CellOccupancy {
  uint64_t cells = 0, nonempty = 0, refs = 0;
  uint32_t max_per_cell = 0;
};
CellOccupancy measure_occupancy(std::span<const uint32_t> offsets);

}  // namespace raylab
