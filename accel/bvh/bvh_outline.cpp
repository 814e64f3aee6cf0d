#include "accel/bvh/bvh_outline.h"

namespace raylab {

void outline_bvh2(const Bvh2Layout& layout, int max_depth, StructureOutline& out) {
  out.what = "BVH2 node boxes";
  if (layout.nodes.empty() || layout.nodes[0].bounds().is_empty()) return;
  // (node, its depth); siblings sit side by side at index and index + 1.
  std::vector<std::pair<uint32_t, int>> stack{{0u, 0}};
  while (!stack.empty()) {
    const auto [index, depth] = stack.back();
    stack.pop_back();
    const Bvh2Node& n = layout.nodes[index];
    if (!out.add(OutlineBox{n.bounds(), depth, n.is_leaf()})) return;
    if (n.is_leaf() || depth >= max_depth) continue;
    stack.push_back({n.index + 1, depth + 1});
    stack.push_back({n.index, depth + 1});
  }
}

}  // namespace raylab
