#pragma once
// Construction of the irregular grid (irgrid.h): top grid, octree
// subdivision of each top cell, then the merge and expand passes of
// Perard-Gayot, Kalojanov & Slusallek (Eurographics 2017).
#include "accel/accelerator.h"
#include "accel/irgrid/irgrid.h"

namespace raylab {

struct IrgridOptions {
  double top_density = 0.25;   // lambda_1: top cells ~ top_density * triangles
  double sub_density = 0.1;    // lambda_2: a node with n triangles may split when sub_density * n > 8
  double step_cost = 1.0;      // cost of entering a cell, in triangle tests (octree splits, merges)
  int max_depth = 12;          // deepest octree level of a top cell
  bool merge = true;
  bool expand = true;
  bool leaf_blocks = false;  // cells' triangles as 8-wide SIMD blocks (irgrid.h; watertight test only)
};

// Builds the grid over `mesh`; fills `stats` (cells, references, passes).
Irgrid build_irgrid(const TriangleMesh& mesh, const IrgridOptions& opt, BuildStats& stats);

}  // namespace raylab
