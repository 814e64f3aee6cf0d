#pragma once
// SAH-optimal collapse of a binary BVH into an N-wide BVH (N = 2, 4, 8 or 16) by
// dynamic programming over the binary tree, after Ylitie, Karras & Laine,
// "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs"
// (HPG 2017). For every binary node n and slot budget i = 1..N:
//
//   C(n, 1) = min( leaf(n),  A(n)*C_node + D(n, N) )        n as one child slot
//   C(n, i) = min( C(n, i-1), D(n, i) )            i > 1    n opened into <= i slots
//   D(n, i) = min_{0<k<i} C(left, k) + C(right, i-k)
//   leaf(n) = A(n) * C_block * ceil(refs(n) / W)   if refs(n) <= max_leaf, else inf
//
// where A is the surface area and W the number of triangles a leaf tests at
// once. The root's wide node takes D(root, N). With N = 2 the same recursion
// chooses leaves optimally for the binary layout. Leaves gather every
// reference of their binary subtree; duplicates (SBVH) within a leaf are
// removed.
#include <cstdint>
#include <vector>

#include "accel/bvh/bvh2_node.h"
#include "base/triangle_mesh.h"

namespace raylab {

struct CollapseOptions {
  int width = 8;            // children per wide node: 2, 4, 8 or 16
  int block_width = 4;      // triangles tested together (leaf cost unit)
  int max_leaf = 8;         // references per leaf (after duplicates are removed: at most this)
  int max_leaf_blocks = 15; // hard cap from the child encoding
  float node_cost = 1.0f;   // C_node: cost of visiting one wide node
  float block_cost = 1.0f;  // C_block: cost of testing one block of block_width triangles
  // Thick leaves: a leaf gathering more than one binary leaf is not formed
  // when its box is large (surface area above thick_leaf_area of the root
  // box's) and thick (box_thickness above thick_leaf_limit) although its
  // triangles are flat (their own boxes' volumes sum to under a quarter of
  // its volume); the node is opened instead. 0 for either, or no mesh: no
  // limit. Why: the SAH prices a box by the chance that a ray from outside
  // crosses it, but camera rays and secondary rays start inside the scene,
  // and every ray starting inside a box tests it (Fabianowski, Fowler &
  // Dingliana, "A Cost Metric for Scene-Interior Ray Origins", EG 2009).
  // A leaf merging flat triangles of different
  // planes (the floor and a wall of a room, three walls of an alcove) has a
  // box with volume that none of its triangles' boxes has: the light-pass
  // trees of the Sponza scenes and conference held such leaves near the
  // root, entered by up to every camera ray (docs/structures/bvh.md).
  float thick_leaf_area = 0.0f;
  float thick_leaf_limit = 0.0f;
  const TriangleMesh* mesh = nullptr;  // the triangles the tree's prim_ids name
};

// A box's volume (0 for an empty box).
double box_volume(const Aabb& box);

// A box's volume relative to that of the cube with the same surface area:
// 1 for a cube, 0 for a flat box (3^(3/2) V / A^(3/2), A the half area).
float box_thickness(const Aabb& box);

inline constexpr int kMaxWideWidth = 16;

// The collapsed tree in a layout-neutral form; layouts convert it into their
// node formats. Node 0 is the root (unless root_leaf >= 0: the whole tree is one leaf).
struct WideTree {
  struct Child {
    Aabb box;
    bool leaf = false;
    uint32_t index = 0;  // inner: node index; leaf: leaf index
  };
  struct Node {
    Child child[kMaxWideWidth];
    int count = 0;
  };
  std::vector<Node> nodes;
  std::vector<uint32_t> leaf_begin;  // leaf i holds leaf_prims[leaf_begin[i], leaf_begin[i+1])
  std::vector<uint32_t> leaf_prims;
  int64_t root_leaf = -1;            // >= 0 when the tree is a single leaf
  Aabb root_box;
  double dp_cost = 0.0;              // the DP objective, normalised by the root area

  size_t leaf_count() const { return leaf_begin.empty() ? 0 : leaf_begin.size() - 1; }
  uint32_t leaf_size(size_t i) const { return leaf_begin[i + 1] - leaf_begin[i]; }
};

WideTree collapse_to_wide(const BinaryBvh& tree, const CollapseOptions& options);

struct WideShape {
  size_t nodes = 0, leaves = 0;
  int max_depth = 0;         // of leaves, counted in wide nodes from the root (root = 0)
  double avg_leaf_depth = 0.0;
  double sah_cost = 0.0;     // kSahReportTraversalCost per wide node, kSahReportIntersectionCost per reference
  double avg_leaf_size = 0.0;
  double child_fill = 0.0;   // mean children per wide node
};

WideShape measure_wide(const WideTree& t);

}  // namespace raylab
