#pragma once
// `grid:storage=implicit`: the implicit grid (Ericson, Real-Time Collision
// Detection, 7.1.5): instead of a list per cell, one bit array over the
// triangles per x slab, per y slab and per z slab of the uniform grid (bit
// i of slab x_j set when triangle i's bounds, enlarged by the cells'
// assignment margin, reach into slab j). A cell's candidates are the AND of
// its three slabs' bit arrays. Memory (nx + ny + nz) * N bits, against the
// dense grid's cells + references; the candidates are those of bounding-box
// assignment (a triangle is in every cell of its bounds' slab product).
//
// Each slab also keeps the range of its non-zero 64-bit words, so a cell's
// AND runs only over the words where all three slabs have bits.
#include <cstdint>
#include <vector>

#include "accel/accelerator.h"
#include "accel/core/leaf_triangle.h"
#include "accel/core/grid/dda_grid.h"
#include "accel/grid/grid_options.h"

namespace raylab {

struct ImplicitGrid {
  DdaGrid dda;
  size_t words = 0;              // 64-bit words per slab: ceil(N / 64)
  std::vector<uint64_t> bits;    // slabs x_0..x_{nx-1}, y_0.., z_0.., `words` each
  std::vector<uint32_t> word_lo, word_hi;  // per slab: its non-zero words lie in [lo, hi)
  std::vector<LeafTriangle> tris;  // in id order
  bool empty = true;

  // First slab of axis a (x slabs, then y, then z).
  size_t slab(int a, int32_t c) const {
    return (a == 0 ? 0 : (a == 1 ? static_cast<size_t>(dda.res[0]) : static_cast<size_t>(dda.res[0]) + dda.res[1])) +
           static_cast<size_t>(c);
  }
};

// Builds the grid at the resolution the dense grid would choose (density,
// res), lowering it within the memory budget with the grids' warning.
ImplicitGrid build_implicit_grid(const TriangleMesh& mesh, const GridOptions& options, BuildStats& stats);

}  // namespace raylab
