#include <algorithm>

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
  double depth_sum = 0.0, cost = 0.0;
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
      depth_sum += it.depth;
      cost += area * n.count();  // C_i = 1
    } else {
      s.inner++;
      cost += area;  // C_t = 1
      Aabb below = it.cell, above = it.cell;
      below.hi[n.axis()] = n.split();
      above.lo[n.axis()] = n.split();
      stack.push_back({n.child(), it.depth + 1, below});
      stack.push_back({n.child() + 1, it.depth + 1, above});
    }
  }
  s.avg_leaf_depth = s.leaves ? depth_sum / static_cast<double>(s.leaves) : 0.0;
  s.sah_cost = root_area > 0.0 ? cost / root_area : 0.0;
  return s;
}

}  // namespace raylab
