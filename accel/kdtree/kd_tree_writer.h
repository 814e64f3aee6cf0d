#pragma once
// Where the parallel k-d builders put their nodes while subtrees are built as
// concurrent tasks: nodes and leaf triangle ids are appended to concurrent
// vectors (the order depends on scheduling), and finish() copies them into
// one deterministic depth-first layout.
#include <cstdint>
#include <span>

#include <tbb/concurrent_vector.h>

#include "accel/kdtree/kdtree_node.h"

namespace raylab {

class KdTreeWriter {
 public:
  KdTreeWriter();  // holds the root, node 0

  // Two consecutive new nodes (below, above); returns the first index.
  uint32_t allocate_pair();
  void set_inner(uint32_t node, int axis, float split, uint32_t child_pair);
  void set_leaf(uint32_t node, std::span<const uint32_t> prims);

  // Depth-first relayout: each child pair follows the subtree of the pair
  // before it, and leaf ranges are in the same order.
  KdTree finish(const Aabb& bounds) const;

 private:
  tbb::concurrent_vector<KdNode> nodes_;
  tbb::concurrent_vector<uint32_t> prims_;
};

}  // namespace raylab
