#pragma once
// Cache-conscious node order for the k-d tree: subtrees clustered into
// 64-byte cache lines (Havran's thesis, 2000, ch. on memory layout; Wald's
// thesis, 2004, keeps its 8-byte nodes in cache-line-sized chunks for the
// same reason).
//
// The builder writes nodes depth first, each child pair after the subtree of
// the pair before it: a ray that keeps taking the lower child stays in one
// cache line, one that takes the upper child jumps past the whole lower
// subtree. And since the root is alone at index 0, every fourth pair
// straddled two cache lines.
//
// This layout keeps the pairs (a node's children side by side, so the walk
// is unchanged) but:
//  - puts an unused slot after the root, so every pair starts at an even
//    index: with the array aligned to 64 bytes (HugePageVector) a pair never
//    straddles a line;
//  - fills each line with a *treelet*: a pair, then greedily the child pairs
//    most likely to be needed next, i.e. those of the node with the largest
//    cell surface area among the treelet's inner nodes (the SAH's
//    probability that a ray crossing the treelet's cell enters that node),
//    up to the 4 pairs a line holds. A ray then crosses 2-3 levels per line
//    instead of 1-2;
//  - places treelets depth first (the likeliest child treelet right after
//    its parent's line), so whole subtrees stay close at page scale too. A
//    treelet starts a fresh line; what is left of a line is filled with a
//    whole pending subtree that fits (no ray changes lines inside it), else
//    left unused (about 16% more node slots).
// Leaf entries (offsets into prim_ids) are unchanged; the tree's cells and
// leaves are exactly the builder's (tests/accel/kdtree/test_kdtree.cpp compares them).
// Measured (docs/structures/kdtree.md): 3-4% faster on the deep trees of the
// published SAH constants (ct=15), no faster on the default tree (ct=200,
// 10x fewer nodes, which fit in the L2 cache): `layout=cluster`, not the
// default.
#include "accel/kdtree/kdtree_node.h"

namespace raylab {

// Nodes per 64-byte cache line.
inline constexpr uint32_t kKdNodesPerLine = 64 / sizeof(KdNode);

// The builder's tree with its nodes in the clustered order above (index 0 is
// still the root; unused slots are empty leaves no node points at).
KdTree cluster_kd_nodes(const KdTree& tree);

}  // namespace raylab
