#include <algorithm>

#include "accel/core/sah_report.h"
#include "accel/kdtree/kdtree_node.h"

namespace raylab {

KdTreeShape measure_kdtree(const Aabb& bounds, std::span<const KdNode> nodes) {
  KdTreeShape s;
  if (nodes.empty()) return s;
  const double root_area = bounds.half_area();
  struct Item {
    uint32_t node;
    int depth;
    Aabb cell;
  };
  std::vector<Item> stack{{0, 0, bounds}};
  SahTally tally;
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    const KdNode& n = nodes[it.node];
    s.nodes++;
    s.max_depth = std::max(s.max_depth, it.depth);
    const double area = it.cell.half_area();
    if (n.is_leaf()) {
      s.leaves++;
      if (n.count() == 0) s.empty_leaves++;
      s.references += n.count();
      s.max_leaf_size = std::max<size_t>(s.max_leaf_size, n.count());
      tally.leaf(area, n.count(), it.depth);
    } else {
      s.inner++;
      tally.inner(area);
      Aabb below = it.cell, above = it.cell;
      below.hi[n.axis()] = n.split();
      above.lo[n.axis()] = n.split();
      stack.push_back({n.child(), it.depth + 1, below});
      stack.push_back({n.child() + 1, it.depth + 1, above});
    }
  }
  s.avg_leaf_depth = tally.avg_leaf_depth();
  s.sah_cost = tally.sah_cost(root_area);
  return s;
}

}  // namespace raylab
