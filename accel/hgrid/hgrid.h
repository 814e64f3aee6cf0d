#pragma once
// `hgrid`: the hierarchical grid of Ericson, Real-Time Collision Detection,
// 7.2.5 (after Mirtich's multi-level grids): levels of cubic cells of side
// r_0 < r_1 = ratio r_0 < ... , every triangle inserted once, at the
// finest level whose cell side is at least the triangle's largest extent,
// so it reaches into at most two cells per axis there (8 cells).
//
// Storage: one hash table shared by all levels, keyed by (level, cell) —
// the level is the key's top 6 bits, the cell's linear index within the
// level's occupied box the rest (accel/grid/cell_hash_table.h) — and a
// 64-bit mask of the levels that hold triangles. Each occupied level keeps
// the box of its occupied cells as a DdaGrid, so a ray walks a level only
// where it has triangles.
//
// Neighbourhoods (a triangle stored by its centre reaches into adjacent
// cells), two choices, measured in docs/structures/hgrid.md:
//  - neighbours=store (default): the triangle is listed in every cell of its
//    level its (margin-enlarged) bounds overlap, at most 8 (27 when it
//    touches cell faces within the margin); a plain 3D-DDA per level;
//  - neighbours=pad: the triangle is listed once, in the cell of its
//    centre, and the walk looks up the 3x3x3 neighbourhood of every cell it
//    enters (each triangle tested once per ray thanks to the mailbox).
#include <cstdint>
#include <vector>

#include "accel/core/leaf_triangle.h"
#include "accel/core/grid/cell_hash_table.h"
#include "accel/core/grid/dda_grid.h"

namespace raylab {

inline constexpr int kHgridMaxLevels = 63;
inline constexpr int kHgridKeyShift = 57;  // level << 57 | local cell index (< 2^57)

enum class HgridNeighbours : uint8_t { Store, Pad };

struct HgridLevel {
  int level = 0;
  DdaGrid grid;  // the occupied box of the level (cells of side r_level)
};

struct Hgrid {
  std::vector<HgridLevel> levels;  // occupied levels, finest first
  uint64_t level_mask = 0;         // bit l: level l holds triangles
  double finest_cell = 0.0, ratio = 2.0;
  CellHashTable cells;
  std::vector<uint32_t> refs;  // cell lists: indices into tris
  std::vector<LeafTriangle> tris;
  HgridNeighbours neighbours = HgridNeighbours::Store;
  // The levels' common box: where a ray from far away is rebased (dda.h, dda_line).
  double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
  bool empty = true;
};

inline uint64_t hgrid_key(int level, int64_t local_index) {
  return static_cast<uint64_t>(level) << kHgridKeyShift | static_cast<uint64_t>(local_index);
}

}  // namespace raylab
