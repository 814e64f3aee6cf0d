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
  SahTally tally;
  walk_depth_first(Item{0, 0, bounds}, [&](const Item& it, auto&& push) {
    const KdNode& n = nodes[it.node];
    tally.node(it.depth);
    const double area = it.cell.half_area();
    if (n.is_leaf()) {
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
      push({n.child(), it.depth + 1, below});
      push({n.child() + 1, it.depth + 1, above});
    }
  });
  tally.fill(s, root_area);
  return s;
}

}  // namespace raylab
