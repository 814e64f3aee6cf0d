#include "accel/kdtree/kdtree_outline.h"

#include <algorithm>
#include <vector>

namespace raylab {

void outline_kdtree(const Aabb& bounds, std::span<const KdNode> nodes, int max_depth, StructureOutline& out) {
  out.what = "k-d split planes";
  if (nodes.empty() || bounds.is_empty()) return;
  if (!out.add(OutlineBox{bounds, 0, nodes[0].is_leaf()})) return;
  struct Item {
    uint32_t node;
    Aabb cell;
    int depth;
  };
  std::vector<Item> stack{{0u, bounds, 0}};
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    const KdNode& n = nodes[it.node];
    if (n.is_leaf()) {
      if (it.depth > 0 && n.count() > 0 && !out.add(OutlineBox{it.cell, it.depth, true})) return;
      continue;
    }
    if (it.depth > max_depth) continue;
    const int axis = n.axis();
    // A split outside its cell (possible when the builder's cell was padded)
    // is drawn on the cell's face: the picture stays within the cell.
    const float pos = std::clamp(n.split(), it.cell.lo[axis], it.cell.hi[axis]);
    if (!out.add(StructureOutline::split_plane(it.cell, axis, pos, it.depth))) return;
    if (it.depth == max_depth) continue;
    Aabb below = it.cell, above = it.cell;
    below.hi[axis] = pos;
    above.lo[axis] = pos;
    stack.push_back({n.child() + 1, above, it.depth + 1});
    stack.push_back({n.child(), below, it.depth + 1});
  }
}

}  // namespace raylab
