#pragma once
// Child slots ordered for occlusion (any-hit) rays, after Ize & Hansen,
// "RTSAH Traversal Order for Occlusion Rays" (Eurographics 2011). An any-hit
// walk may stop at the first triangle it hits, so the order in which it
// visits a node's children matters; the wide walk visits them in descending
// slot order (leaves first), and the slot order is free for closest hit,
// which sorts its children by distance. Visiting child i first and j next is
// cheaper than the reverse when
//
//   o_i / c_i  >  o_j / c_j
//
// (exchange argument), where o is the chance that a ray entering the child
// is blocked inside it and c the expected cost of walking it. For random
// lines a flat triangle of area a inside a box of half surface area H is hit
// with probability a / H (Cauchy's formula), and a child box of half area
// h_j inside a node of half area H with probability h_j / H; blocks are
// taken as independent:
//
//   leaf:  o = 1 - prod_t (1 - a_t / H),  c = C_block * blocks
//   inner: o = 1 - prod_j (1 - p_j o_j),  c = C_node + sum_i p_i c_i prod_{k before i} (1 - p_k o_k)
//
// computed bottom-up; each node's children are then stored so that the one
// to visit first sits in the highest slot.
#include "accel/bvh/collapse_wide.h"
#include "base/triangle_mesh.h"

namespace raylab {

struct OcclusionOrderOptions {
  float node_cost = 1.0f;   // C_node, as the collapse's
  float block_cost = 1.0f;  // C_block, as the collapse's
  int block_width = 8;      // triangles per leaf block
};

// Reorders every node's children in place (boxes and targets move
// together, so the tree's shape and closest hits are unchanged). Returns
// the root's estimated occlusion probability (for tests and statistics).
double order_children_for_occlusion(WideTree& tree, const TriangleMesh& mesh, const OcclusionOrderOptions& options);

}  // namespace raylab
