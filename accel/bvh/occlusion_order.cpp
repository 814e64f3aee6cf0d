#include "accel/bvh/occlusion_order.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace raylab {
namespace {

struct Estimate {
  double blocked = 0.0;  // o: chance a ray entering the box is blocked inside
  double cost = 0.0;     // c: expected cost of walking it
};

// A ray entering `box` meets a triangle of area `area` inside it with
// probability area / half_area(box); flat or empty boxes count as certain.
double hit_chance(double area, double box_half_area) {
  if (!(box_half_area > 0.0)) return area > 0.0 ? 1.0 : 0.0;
  return std::min(1.0, area / box_half_area);
}

double triangle_area(const TriangleMesh& mesh, uint32_t t) {
  const Eigen::Vector3d a = mesh.vertex(t, 0).cast<double>();
  const Eigen::Vector3d b = mesh.vertex(t, 1).cast<double>();
  const Eigen::Vector3d c = mesh.vertex(t, 2).cast<double>();
  return 0.5 * (b - a).cross(c - a).norm();
}

// Visit priority: blocked per unit cost, larger first.
double priority(const Estimate& e) { return e.cost > 0.0 ? e.blocked / e.cost : 0.0; }

}  // namespace

double order_children_for_occlusion(WideTree& tree, const TriangleMesh& mesh, const OcclusionOrderOptions& options) {
  const size_t leaves = tree.leaf_count();
  auto leaf_estimate = [&](size_t i, const Aabb& box) {
    const double h = box.half_area();
    double pass = 1.0;
    for (uint32_t k = tree.leaf_begin[i]; k < tree.leaf_begin[i + 1]; ++k)
      pass *= 1.0 - hit_chance(triangle_area(mesh, tree.leaf_prims[k]), h);
    const uint32_t blocks = (tree.leaf_size(i) + options.block_width - 1) / options.block_width;
    return Estimate{1.0 - pass, options.block_cost * static_cast<double>(blocks)};
  };
  if (tree.root_leaf >= 0) return leaves ? leaf_estimate(0, tree.root_box).blocked : 0.0;

  // Children have larger indices than their parents (the collapse expands
  // depth first and appends), so a reverse sweep sees children first.
  std::vector<Estimate> inner(tree.nodes.size());
  for (size_t n = tree.nodes.size(); n-- > 0;) {
    WideTree::Node& node = tree.nodes[n];
    Aabb box = Aabb::empty();
    for (int j = 0; j < node.count; ++j) box.extend(node.child[j].box);
    const double h = box.half_area();
    struct Slot {
      WideTree::Child child;
      Estimate e;
      double p;
    };
    Slot slots[kMaxWideWidth];
    for (int j = 0; j < node.count; ++j) {
      const WideTree::Child& c = node.child[j];
      const Estimate e = c.leaf ? leaf_estimate(c.index, c.box) : inner[c.index];
      slots[j] = {c, e, hit_chance(c.box.half_area(), h)};
    }
    // The walk takes hit leaves before inner children, then each group from
    // the highest slot down: store leaves above inner children, each group
    // in ascending priority. Ties keep the collapse's order (stable sort).
    std::stable_sort(slots, slots + node.count, [](const Slot& a, const Slot& b) {
      if (a.child.leaf != b.child.leaf) return !a.child.leaf;
      return priority(a.e) < priority(b.e);
    });
    double pass = 1.0, cost = options.node_cost;
    for (int j = node.count; j-- > 0;) {  // visit order
      cost += pass * slots[j].p * slots[j].e.cost;
      pass *= 1.0 - slots[j].p * slots[j].e.blocked;
    }
    for (int j = 0; j < node.count; ++j) node.child[j] = slots[j].child;
    inner[n] = {1.0 - pass, cost};
  }
  return inner.empty() ? 0.0 : inner[0].blocked;
}

}  // namespace raylab
