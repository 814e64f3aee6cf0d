#pragma once
// `hashgrid`: the uniform grid of `grid` (same resolution rule, same
// assignment, same 3D-DDA) with only the occupied cells stored, in a hash
// table keyed by the cell's integer coordinates (cell_hash_table.h). Memory
// grows with the occupied cells and the references, not with the
// resolution, so large densities stay affordable.
//
// Build (parallel, TBB): count the cells of each triangle, prefix-sum the
// counts over the triangles, fill (cell key, triangle id) pairs, sort them
// by key; each run of equal keys becomes one occupied cell (a contiguous
// range of triangle ids) and one hash table entry.
#include <vector>

#include "accel/accelerator.h"
#include "accel/core/grid/cell_hash_table.h"
#include "accel/core/grid/dda_grid.h"
#include "accel/grid/grid_options.h"
#include "accel/core/leaf_triangle.h"
#include "accel/core/huge_page_allocator.h"
#include "accel/grid/cell_blocks.h"

namespace raylab {

struct HashGrid {
  DdaGrid dda;
  // With SIMD blocks (options.leaf_blocks()) a slot's begin and count are in
  // blocks, and refs and tris are empty.
  CellHashTable table;
  std::vector<uint32_t> refs;  // triangle ids, grouped by occupied cell
  std::vector<LeafTriangle> tris;
  HugePageVector<CellTriangleBlock> blocks;  // on huge pages (huge_page_allocator.h)
  bool empty = true;
};

// The budget bounds the build's peak (the (key, id) pairs, the references
// and the table); an excess lowers the density with one warning. Fills `stats` except build_ms.
HashGrid build_hash_grid(const TriangleMesh& mesh, const GridOptions& options, BuildStats& stats);

}  // namespace raylab
