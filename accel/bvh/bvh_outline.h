#pragma once
// Structure pictures of the BVH layouts (Accelerator::outline): the box of
// every node down to a depth, walked from the root of the traced layout.
// Depth counts nodes of that layout (a bvh8 level is three bvh2 levels).
#include "accel/bvh/bvh2_layout.h"
#include "accel/bvh/bvh_wide_node.h"
#include "accel/structure_outline.h"

namespace raylab {

void outline_bvh2(const Bvh2Layout& layout, int max_depth, StructureOutline& out);

template <int N, int W>
void outline_wide(const WideBvh<N, W>& bvh, int max_depth, StructureOutline& out) {
  out.what = "BVH" + std::to_string(N) + " node boxes";
  if (bvh.root_ref == wide_ref::kEmpty) return;
  if (!out.add(OutlineBox{bvh.root_box, 0, wide_ref::is_leaf(bvh.root_ref)})) return;
  if (wide_ref::is_leaf(bvh.root_ref)) return;
  // (node, depth of its children)
  std::vector<std::pair<uint32_t, int>> stack{{bvh.root_ref, 1}};
  while (!stack.empty()) {
    const auto [index, depth] = stack.back();
    stack.pop_back();
    if (depth > max_depth) continue;
    const WideNode<N>& node = bvh.nodes[index];
    for (int c = 0; c < N; ++c) {
      const uint32_t ref = node.child[c];
      if (ref == wide_ref::kEmpty) continue;
      const bool leaf = wide_ref::is_leaf(ref);
      if (!out.add(OutlineBox{node.child_box(c), depth, leaf})) return;
      if (!leaf) stack.push_back({ref, depth + 1});
    }
  }
}

}  // namespace raylab
