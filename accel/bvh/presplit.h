#pragma once
// Triangle pre-splitting before a binned SAH build, after the triangle
// splitting of Karras & Aila, "Fast Parallel Construction of High-Quality
// Bounding Volume Hierarchies" (HPG 2013), section 5. A long thin or diagonal
// triangle has a box far larger than itself; a tree that must place that box
// whole puts a large box deep in the tree or a small one high up, and every
// ray near it pays. Spatial splits (build_sbvh.h) fix this during the build at
// a high build cost; pre-splitting spends a fixed budget of extra references
// before it: each triangle gets a share of the budget by priority
//
//   p = (2^-L * (A_box - A_ideal))^(1/3),
//
// where A_box is the half surface area of its box, A_ideal the half area of
// the boxes it would need if cut finely (the sum of its three axis
// projections), and L the level of the coarsest plane of the scene's dyadic
// grid (the planes a median-like top-down build cuts first) crossing its box,
// so triangles that straddle the top of the tree come first. A triangle with
// s splits is cut s times, each time at the coarsest grid plane crossing the
// current piece's box, and the remaining splits go to the two pieces by
// size. Pieces keep conservative boxes (TriangleSplitter), so the references
// cover their triangles and the collapse removes duplicates within a leaf.
#include <cstddef>
#include <vector>

#include "accel/bvh/build_common.h"
#include "base/triangle_mesh.h"

namespace raylab {

struct PresplitOptions {
  float budget = 0.1f;          // extra references, a fraction of the triangle count
  int max_splits = 64;          // splits of one triangle at most
};

struct PresplitStats {
  size_t triangles_split = 0;   // triangles cut at least once
};

// One reference per triangle, plus the pieces of the triangles the budget
// splits (a triangle's pieces replace its own reference); with no budget,
// one reference per triangle with its whole box (the binned build's input).
// Deterministic: the same mesh and options give the same references in the
// same order. The mesh must be validated (finite vertices).
std::vector<BuildRef> presplit_references(const TriangleMesh& mesh, const PresplitOptions& options,
                                          PresplitStats* stats = nullptr);

}  // namespace raylab
