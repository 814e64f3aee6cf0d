#include "accel/bvh/bvh2_layout.h"

#include <stdexcept>

namespace raylab {

Bvh2Layout make_bvh2_layout(const WideTree& t, const TriangleMesh& mesh) {
  Bvh2Layout out;
  out.tris.reserve(t.leaf_prims.size());
  auto emit_leaf = [&](Bvh2Node& n, const Aabb& box, uint32_t leaf) {
    n.set_bounds(box);
    n.index = static_cast<uint32_t>(out.tris.size());
    n.count = t.leaf_size(leaf);
    for (uint32_t i = t.leaf_begin[leaf]; i < t.leaf_begin[leaf + 1]; ++i)
      out.tris.push_back(make_leaf_triangle(mesh, t.leaf_prims[i]));
  };
  out.nodes.resize(1);
  if (t.root_leaf >= 0) {
    if (t.leaf_count() == 0 || t.leaf_size(0) == 0) {
      out.nodes[0].set_bounds(Aabb::empty());
      out.nodes[0].index = 0;
      out.nodes[0].count = 0;
    } else {
      emit_leaf(out.nodes[0], t.root_box, 0);
    }
    return out;
  }
  out.nodes.reserve(2 * t.nodes.size() + 1);
  out.nodes[0].set_bounds(t.root_box);
  // (wide node, binary slot) pairs: the slot receives the wide node's children.
  std::vector<std::pair<uint32_t, uint32_t>> stack{{0u, 0u}};
  while (!stack.empty()) {
    const auto [w, slot] = stack.back();
    stack.pop_back();
    const WideTree::Node& n = t.nodes[w];
    if (n.count != 2) throw std::logic_error("bvh2 layout: expected binary nodes");
    const uint32_t first = static_cast<uint32_t>(out.nodes.size());
    out.nodes.resize(out.nodes.size() + 2);
    out.nodes[slot].index = first;
    out.nodes[slot].count = 0;
    for (int c = 1; c >= 0; --c) {
      const WideTree::Child& ch = n.child[c];
      Bvh2Node& dst = out.nodes[first + c];
      if (ch.leaf) {
        emit_leaf(dst, ch.box, ch.index);
      } else {
        dst.set_bounds(ch.box);
        stack.push_back({ch.index, first + static_cast<uint32_t>(c)});
      }
    }
  }
  return out;
}

}  // namespace raylab
