#pragma once
// The depth-first walk both octrees draw their outlines with (raylab show):
// nodes from the root (cell 0,0,0 at level 0) down to max_depth, a child's
// cell corner found from its parent's and its index (bit 0 = x, 1 = y, 2 = z).
#include <cstdint>
#include <vector>

#include "accel/octree/octree_cube.h"
#include "accel/structure_outline.h"

namespace raylab {

// Names the outline `what`; draws nothing for an empty tree. `draw(node,
// level, corner)` adds the node's box to `out` and returns its child mask
// (0: a leaf, its children are not walked), or -1 when the outline is full;
// `child(node, level, i)` is the handle of child i.
template <typename Handle, typename Draw, typename Child>
void walk_octree_outline(StructureOutline& out, const char* what, bool empty, Handle root, int max_depth, Draw&& draw,
                         Child&& child) {
  if (empty) return;
  out.what = what;
  struct Item {
    Handle node;
    uint32_t c[3];
    int level;
  };
  std::vector<Item> stack{{root, {0, 0, 0}, 0}};
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    const int mask = draw(it.node, it.level, it.c);
    if (mask < 0) return;
    if (it.level >= max_depth || mask == 0) continue;
    const uint32_t h = OctreeCube::span(it.level + 1);
    for (uint32_t i = 0; i < 8; ++i)
      if (mask >> i & 1)
        stack.push_back({child(it.node, it.level, i),
                         {it.c[0] + (i & 1u ? h : 0u), it.c[1] + (i & 2u ? h : 0u), it.c[2] + (i & 4u ? h : 0u)},
                         it.level + 1});
  }
}

}  // namespace raylab
