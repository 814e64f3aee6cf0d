#pragma once
// Empty-space skipping for the dense grid: per cell, its clearance, the
// Chebyshev (chessboard) distance in cells to the nearest occupied cell
// (0 for an occupied cell, capped at 255). A ray in a cell of clearance
// d >= 2 lies in a cube of (2d - 1)^3 empty cells and can leave it in one
// jump (dda.h, dda_walk_skipping): the "proximity clouds" of Cohen &
// Sheffer, "Proximity clouds - an acceleration technique for 3D grid
// traversal" (The Visual Computer 11(1), 1994), with cubes for the
// distance, which fit the grid's cells exactly.
//
// Computed by the two-pass chamfer transform with the 3x3x3 neighbourhood
// and unit weights (Rosenfeld & Pfaltz 1966, in 3D), which is exact for the
// chessboard distance: a forward raster pass takes the minimum over the 13
// neighbours already visited, plus one; a backward pass over the other 13.
#include <algorithm>
#include <cstdint>
#include <span>
#include <vector>

#include "accel/core/grid/dda_grid.h"

namespace raylab {

inline constexpr uint8_t kMaxClearance = 255;

// `occupied(index)`: whether the cell with that linear index holds triangles.
template <typename Occupied>
std::vector<uint8_t> cell_clearance(const DdaGrid& g, Occupied&& occupied) {
  const int32_t nx = g.res[0], ny = g.res[1], nz = g.res[2];
  std::vector<uint8_t> d(g.cells());
  for (uint64_t c = 0; c < d.size(); ++c) d[c] = occupied(static_cast<int64_t>(c)) ? 0 : kMaxClearance;
  // One pass: every neighbour (dx, dy, dz) that precedes the cell in the
  // pass's raster order (sign = -1 forward, +1 backward).
  const auto pass = [&](int sign) {
    const auto at = [&](int32_t x, int32_t y, int32_t z) -> uint8_t& { return d[g.index(x, y, z)]; };
    for (int32_t k = 0; k < nz; ++k) {
      const int32_t z = sign < 0 ? k : nz - 1 - k;
      for (int32_t j = 0; j < ny; ++j) {
        const int32_t y = sign < 0 ? j : ny - 1 - j;
        for (int32_t i = 0; i < nx; ++i) {
          const int32_t x = sign < 0 ? i : nx - 1 - i;
          uint8_t& here = at(x, y, z);
          if (here == 0) continue;
          int best = here;
          // Preceding neighbours: the previous slab (9), the previous row of
          // this slab (3), the previous cell of this row (1).
          for (int dz = -1; dz <= 1; ++dz)
            for (int dy = -1; dy <= 1; ++dy)
              for (int dx = -1; dx <= 1; ++dx) {
                const int order = dz != 0 ? dz : (dy != 0 ? dy : dx);
                if (order != sign) continue;
                const int32_t xx = x + dx, yy = y + dy, zz = z + dz;
                if (xx < 0 || yy < 0 || zz < 0 || xx >= nx || yy >= ny || zz >= nz) continue;
                best = std::min(best, at(xx, yy, zz) + 1);
              }
          here = static_cast<uint8_t>(std::min<int>(best, kMaxClearance));
        }
      }
    }
  };
  pass(-1);
  pass(+1);
  return d;
}

}  // namespace raylab
