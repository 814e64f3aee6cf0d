#include "accel/kdtree/kd_tree_writer.h"

#include <stdexcept>

#include <fmt/format.h>

namespace raylab {

KdTreeWriter::KdTreeWriter() { nodes_.grow_by(1); }

uint32_t KdTreeWriter::allocate_pair() {
  const auto it = nodes_.grow_by(2);
  const size_t index = static_cast<size_t>(it - nodes_.begin());
  if (index + 1 > kKdMaxIndex)
    throw std::length_error(fmt::format("kdtree: more than {} nodes", kKdMaxIndex));
  return static_cast<uint32_t>(index);
}

void KdTreeWriter::set_inner(uint32_t node, int axis, float split, uint32_t child_pair) {
  nodes_[node] = KdNode::inner(axis, split, child_pair);
}

void KdTreeWriter::set_leaf(uint32_t node, std::span<const uint32_t> prims) {
  if (prims.size() > kKdMaxIndex)
    throw std::length_error(fmt::format("kdtree: a leaf with {} triangles", prims.size()));
  if (prims.empty()) {
    nodes_[node] = KdNode::leaf(0, 0);
    return;
  }
  const auto it = prims_.grow_by(prims.begin(), prims.end());
  nodes_[node] = KdNode::leaf(static_cast<uint32_t>(it - prims_.begin()), static_cast<uint32_t>(prims.size()));
}

KdTree KdTreeWriter::finish(const Aabb& bounds) const {
  if (prims_.size() > UINT32_MAX)
    throw std::length_error(fmt::format("kdtree: {} leaf references do not fit 32-bit offsets", prims_.size()));
  KdTree tree;
  tree.bounds = bounds;
  tree.nodes.reserve(nodes_.size());
  tree.prim_ids.reserve(prims_.size());
  tree.nodes.push_back(nodes_[0]);
  // Recursion depth is bounded by kKdMaxDepthLimit.
  auto place = [&](auto&& self, uint32_t out, uint32_t src) -> void {
    const KdNode n = nodes_[src];
    if (n.is_leaf()) {
      const auto offset = static_cast<uint32_t>(tree.prim_ids.size());
      for (uint32_t i = 0; i < n.count(); ++i) tree.prim_ids.push_back(prims_[n.offset() + i]);
      tree.nodes[out] = KdNode::leaf(n.count() ? offset : 0, n.count());
      return;
    }
    const auto pair = static_cast<uint32_t>(tree.nodes.size());
    tree.nodes.push_back(nodes_[n.child()]);
    tree.nodes.push_back(nodes_[n.child() + 1]);
    tree.nodes[out] = KdNode::inner(n.axis(), n.split(), pair);
    self(self, pair, n.child());
    self(self, pair + 1, n.child() + 1);
  };
  place(place, 0, 0);
  return tree;
}

}  // namespace raylab
