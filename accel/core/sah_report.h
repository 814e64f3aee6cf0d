#pragma once
// The SAH cost every structure *reports* (BuildStats::sah_cost), with one
// pair of constants so the column compares structures: cost = (C_T * sum of
// inner-node areas + C_I * sum over leaves of area * triangle references) /
// root area (MacDonald & Booth 1990), with C_T = C_I = 1. The builders'
// own constants (kdtree ct/ci, bvh collapse ct/ci) steer construction only.
#include <cstddef>
#include <vector>

namespace raylab {

inline constexpr double kSahReportTraversalCost = 1.0;
inline constexpr double kSahReportIntersectionCost = 1.0;

// Sums a tree's reported SAH cost and its leaf depths, node by node.
struct SahTally {
  double cost = 0.0, leaf_depth_sum = 0.0;
  size_t leaves = 0, nodes = 0;
  int max_depth = 0;

  // Every node visited, inner or leaf, with its depth (root = 0).
  void node(int depth) {
    ++nodes;
    max_depth = depth > max_depth ? depth : max_depth;
  }

  void inner(double area) { cost += kSahReportTraversalCost * area; }
  void leaf(double area, size_t references, int depth) {
    cost += kSahReportIntersectionCost * area * static_cast<double>(references);
    leaf_depth_sum += depth;
    ++leaves;
  }
  double sah_cost(double root_area) const { return root_area > 0.0 ? cost / root_area : 0.0; }
  double avg_leaf_depth() const { return leaves ? leaf_depth_sum / static_cast<double>(leaves) : 0.0; }

  // A tree shape's tallied figures (fields nodes, leaves, max_depth,
  // avg_leaf_depth, sah_cost).
  template <typename Shape>
  void fill(Shape& s, double root_area) const {
    s.nodes = nodes;
    s.leaves = leaves;
    s.max_depth = max_depth;
    s.avg_leaf_depth = avg_leaf_depth();
    s.sah_cost = sah_cost(root_area);
  }
};

// Walks a tree depth first from `root` with an explicit stack (no recursion
// depth limit): visit(item, push) handles one node and pushes its children.
template <typename Item, typename Visit>
void walk_depth_first(const Item& root, Visit&& visit) {
  std::vector<Item> stack{root};
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    visit(it, [&](const Item& child) { stack.push_back(child); });
  }
}

}  // namespace raylab
