#include "accel/kdtree/kd_cache_layout.h"

#include <algorithm>
#include <stdexcept>
#include <vector>

namespace raylab {

namespace {

// A child pair waiting for its place: its first node in the builder's tree,
// the (new) index of the inner node that points at it, the cells of its two
// nodes, and how likely a ray that reaches the treelet needs it (the surface
// area of its parent's cell).
struct PendingPair {
  uint32_t src;
  uint32_t parent;
  Aabb cell[2];
  float weight;
};

// How far down the pending stack a subtree small enough for the rest of a
// line is looked for.
constexpr size_t kKdLayoutSearch = 16;

PendingPair children_of(const KdNode& n, uint32_t parent, const Aabb& cell) {
  PendingPair p{n.child(), parent, {cell, cell}, cell.half_area()};
  p.cell[0].hi[n.axis()] = n.split();
  p.cell[1].lo[n.axis()] = n.split();
  return p;
}

// Pairs in the subtree below each node (0 for a leaf).
std::vector<uint32_t> pairs_below(const std::vector<KdNode>& nodes) {
  std::vector<uint32_t> pairs(nodes.size(), 0);
  // Children come after their parents in the builder's order.
  for (size_t i = nodes.size(); i-- > 0;) {
    const KdNode& n = nodes[i];
    if (!n.is_leaf()) pairs[i] = 1 + pairs[n.child()] + pairs[n.child() + 1];
  }
  return pairs;
}

}  // namespace

KdTree cluster_kd_nodes(const KdTree& tree) {
  KdTree out;
  out.bounds = tree.bounds;
  out.prim_ids = tree.prim_ids;
  if (tree.nodes.empty()) return out;
  out.nodes.reserve(tree.nodes.size() + tree.nodes.size() / 8);
  out.nodes.push_back(tree.nodes[0]);
  if (tree.nodes[0].is_leaf()) return out;
  out.nodes.push_back(KdNode::leaf(0, 0));  // unused: pairs start at even indices

  const std::vector<uint32_t> pairs = pairs_below(tree.nodes);
  auto subtree_pairs = [&](const PendingPair& p) { return 1 + pairs[p.src] + pairs[p.src + 1]; };
  constexpr uint32_t kLinePairs = kKdNodesPerLine / 2;
  std::vector<PendingPair> pending{children_of(tree.nodes[0], 0, tree.bounds)};
  std::vector<PendingPair> treelet_front;  // candidates of the treelet being grown
  while (!pending.empty()) {
    // A treelet starts a fresh line, unless a whole pending subtree fits in
    // what is left of the current one (then no ray changes lines inside it);
    // otherwise the rest of the line stays unused.
    uint32_t capacity = (kKdNodesPerLine - static_cast<uint32_t>(out.nodes.size()) % kKdNodesPerLine) / 2;
    size_t take = pending.size() - 1;
    if (capacity < kLinePairs) {
      size_t j = pending.size();
      const size_t stop = pending.size() > kKdLayoutSearch ? pending.size() - kKdLayoutSearch : 0;
      while (j > stop && subtree_pairs(pending[j - 1]) > capacity) --j;
      if (j > stop) {
        take = j - 1;
      } else {
        out.nodes.resize(out.nodes.size() + 2 * capacity, KdNode::leaf(0, 0));
        capacity = kLinePairs;
      }
    }
    treelet_front.assign(1, pending[take]);
    pending.erase(pending.begin() + static_cast<std::ptrdiff_t>(take));
    while (capacity > 0 && !treelet_front.empty()) {
      const auto likeliest = std::max_element(treelet_front.begin(), treelet_front.end(),
                                              [](const PendingPair& a, const PendingPair& b) { return a.weight < b.weight; });
      const PendingPair p = *likeliest;
      treelet_front.erase(likeliest);
      const auto dst = static_cast<uint32_t>(out.nodes.size());
      const KdNode parent = out.nodes[p.parent];
      out.nodes[p.parent] = KdNode::inner(parent.axis(), parent.split(), dst);
      for (uint32_t side = 0; side < 2; ++side) {
        const KdNode n = tree.nodes[p.src + side];
        out.nodes.push_back(n);
        if (!n.is_leaf()) treelet_front.push_back(children_of(n, dst + side, p.cell[side]));
      }
      --capacity;
    }
    // What did not fit starts treelets of its own, the likeliest next.
    std::stable_sort(treelet_front.begin(), treelet_front.end(),
                     [](const PendingPair& a, const PendingPair& b) { return a.weight < b.weight; });
    pending.insert(pending.end(), treelet_front.begin(), treelet_front.end());
  }
  if (out.nodes.size() - 1 > kKdMaxIndex) throw std::length_error("kdtree: too many nodes for the cache-line layout");
  return out;
}

}  // namespace raylab
