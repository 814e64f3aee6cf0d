#include "accel/bvh/build_common.h"

#include <algorithm>

#include <functional>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

namespace raylab {

std::vector<BuildRef> make_build_refs(std::span<const Aabb> boxes, std::span<const Vec3f> centroids) {
  std::vector<BuildRef> refs(boxes.size());
  tbb::parallel_for(tbb::blocked_range<size_t>(0, boxes.size(), 8192), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i)
      refs[i] = BuildRef::make(boxes[i], centroids[i], static_cast<uint32_t>(i));
  });
  return refs;
}

std::vector<BuildRef> triangle_build_refs(const TriangleMesh& mesh) {
  const size_t n = mesh.num_triangles();
  std::vector<BuildRef> refs(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const Aabb b = mesh.triangle_bounds(i);
      refs[i] = BuildRef::make(b, b.center(), static_cast<uint32_t>(i));
    }
  });
  return refs;
}

std::vector<uint32_t> subtree_ref_counts(std::span<const Bvh2Node> nodes) {
  std::vector<uint32_t> counts(nodes.size(), 0);
  for (size_t i = nodes.size(); i-- > 0;) {
    const Bvh2Node& n = nodes[i];
    if (n.count != 0 || n.index == 0) counts[i] = n.count;
    else counts[i] = counts[n.index] + counts[n.index + 1];
  }
  return counts;
}

BinaryBvh relayout_depth_first(const BinaryBvh& in) {
  BinaryBvh out;
  out.prim_ids.reserve(in.prim_ids.size());
  out.nodes.reserve(in.nodes.size());
  if (in.nodes.empty()) return out;
  out.nodes.push_back(in.nodes[0]);
  // (old node, new slot) pairs still to be expanded.
  std::vector<std::pair<uint32_t, uint32_t>> stack{{0u, 0u}};
  while (!stack.empty()) {
    const auto [old_id, new_id] = stack.back();
    stack.pop_back();
    const Bvh2Node& n = in.nodes[old_id];
    Bvh2Node& m = out.nodes[new_id];
    m = n;
    if (n.count != 0 || n.index == 0) {
      m.index = static_cast<uint32_t>(out.prim_ids.size());
      out.prim_ids.insert(out.prim_ids.end(), in.prim_ids.begin() + n.index, in.prim_ids.begin() + n.index + n.count);
      continue;
    }
    const uint32_t left = static_cast<uint32_t>(out.nodes.size());
    out.nodes.resize(out.nodes.size() + 2);
    out.nodes[new_id].index = left;
    // Right pushed first so the left subtree is laid out first.
    stack.push_back({n.index + 1, left + 1});
    stack.push_back({n.index, left});
  }
  return out;
}

Bvh2Shape measure_tree(std::span<const Bvh2Node> nodes) {
  Bvh2Shape s;
  if (nodes.empty()) return s;
  const double root_area = nodes[0].bounds().half_area();
  struct Item {
    uint32_t node;
    int depth;
  };
  SahTally tally;
  walk_depth_first(Item{0, 0}, [&](const Item& it, auto&& push) {
    const Bvh2Node& n = nodes[it.node];
    tally.node(it.depth);
    const double area = n.bounds().half_area();
    if (n.is_leaf() || n.index == 0) {
      tally.leaf(area, n.count, it.depth);
    } else {
      tally.inner(area);
      push({n.index, it.depth + 1});
      push({n.index + 1, it.depth + 1});
    }
  });
  tally.fill(s, root_area);
  return s;
}

double tree_sah_cost(std::span<const Bvh2Node> nodes) {
  if (nodes.empty()) return 0.0;
  const double total = tbb::parallel_reduce(
      tbb::blocked_range<size_t>(0, nodes.size(), 16384), 0.0,
      [&](const tbb::blocked_range<size_t>& r, double acc) {
        for (size_t i = r.begin(); i < r.end(); ++i) {
          const Bvh2Node& n = nodes[i];
          const double area = n.bounds().half_area();
          acc += (n.is_leaf() || n.index == 0) ? kSahReportIntersectionCost * area * n.count : kSahReportTraversalCost * area;
        }
        return acc;
      },
      std::plus<double>());
  const double root_area = nodes[0].bounds().half_area();
  return root_area > 0.0 ? total / root_area : 0.0;
}

}  // namespace raylab
