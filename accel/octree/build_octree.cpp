#include "accel/octree/build_octree.h"

#include <array>
#include <bit>
#include <cmath>
#include <memory>
#include <vector>

#include <tbb/parallel_for.h>

#include "accel/core/tri_box_overlap.h"
#include "accel/core/sah_report.h"

#include "accel/octree/octree_tmp_tree.h"

namespace raylab {

namespace {

// Subtrees with at least this many references are built in parallel.
constexpr size_t kParallelRefs = 2048;
// The cost model counts triangle tests in blocks of the SIMD lists' width
// (octree_leaf_blocks.h): 1..4 triangles cost one vector test.
constexpr size_t kSahBlock = 4;

class OctreeBuilder {
 public:
  OctreeBuilder(const TriangleMesh& mesh, const OctreeBuildOptions& opt, const OctreeCube& cube,
                const std::vector<Aabb>& boxes)
      : mesh_(mesh), opt_(opt), cube_(cube), boxes_(boxes) {}

  void build(OctTmpNode& n, std::vector<uint32_t> ids, int level, const uint32_t c[3]) const {
    if (keep_as_leaf(n, ids, level, opt_.leaf, opt_.max_depth)) return;
    const uint32_t half = OctreeCube::span(level + 1);
    std::array<std::vector<uint32_t>, 8> child_ids;
    std::vector<uint32_t> stay;
    distribute(ids, c, half, child_ids, stay);
    const size_t total = ids.size();
    if (!split_pays(child_ids, stay, total)) {
      n.nonempty = true;
      n.refs = std::move(ids);
      return;
    }
    std::vector<uint32_t>().swap(ids);
    n.refs = std::move(stay);
    n.kids = std::make_unique<std::array<OctTmpNode, 8>>();
    auto build_child = [&](uint32_t ch) {
      const uint32_t cc[3] = {c[0] + ((ch & 1u) ? half : 0u), c[1] + ((ch & 2u) ? half : 0u),
                              c[2] + ((ch & 4u) ? half : 0u)};
      build((*n.kids)[ch], std::move(child_ids[ch]), level + 1, cc);
    };
    if (total >= kParallelRefs) {
      tbb::parallel_for(0u, 8u, [&](uint32_t ch) { build_child(ch); });
    } else {
      for (uint32_t ch = 0; ch < 8; ++ch) build_child(ch);
    }
    n.nonempty = !n.refs.empty();
    for (const OctTmpNode& k : *n.kids) n.nonempty = n.nonempty || k.nonempty;
  }

 private:
  // Sorts the node's triangles (cube corner c, children of side `half`) into
  // the children they overlap (exact triangle-box test), or, with
  // assign=straddle, keeps those that straddle a dividing plane in `stay`.
  void distribute(const std::vector<uint32_t>& ids, const uint32_t c[3], uint32_t half,
                  std::array<std::vector<uint32_t>, 8>& child_ids, std::vector<uint32_t>& stay) const {
    float mid[3];
    double lo[3][3];  // [axis][0 = low plane, 1 = mid plane, 2 = high plane]
    for (int k = 0; k < 3; ++k) {
      mid[k] = cube_.plane(k, c[k] + half);
      lo[k][0] = cube_.plane(k, c[k]);
      lo[k][1] = mid[k];
      lo[k][2] = cube_.plane(k, c[k] + 2 * half);
    }
    for (const uint32_t id : ids) {
      const Aabb& b = boxes_[id];
      // Sides of each dividing plane the box touches (closed cells: a box
      // touching the plane belongs to both sides).
      uint32_t sides[3];
      for (int k = 0; k < 3; ++k) sides[k] = (b.lo[k] <= mid[k] ? 1u : 0u) | (b.hi[k] >= mid[k] ? 2u : 0u);
      uint32_t candidates = 0;
      for (uint32_t ch = 0; ch < 8; ++ch) {
        bool ok = true;
        for (int k = 0; k < 3; ++k) ok = ok && (sides[k] & ((ch >> k & 1u) ? 2u : 1u));
        if (ok) candidates |= 1u << ch;
      }
      if (std::popcount(candidates) == 1) {
        child_ids[std::countr_zero(candidates)].push_back(id);
        continue;
      }
      if (opt_.assign == OctreeAssign::Straddle) {
        stay.push_back(id);
        continue;
      }
      const Vec3d v0 = mesh_.vertex(id, 0).cast<double>(), v1 = mesh_.vertex(id, 1).cast<double>(),
                  v2 = mesh_.vertex(id, 2).cast<double>();
      uint32_t hits = 0;
      for (uint32_t ch = 0; ch < 8; ++ch) {
        if (!(candidates >> ch & 1u)) continue;
        Vec3d box_lo, box_hi;
        for (int k = 0; k < 3; ++k) {
          const int s = (ch >> k) & 1;
          box_lo[k] = lo[k][s];
          box_hi[k] = lo[k][s + 1];
        }
        if (triangle_box_overlap(box_lo, box_hi, v0, v1, v2)) hits |= 1u << ch;
      }
      // The children tile the parent, so some child overlaps a triangle that
      // overlaps the parent; should double rounding say none, keep all
      // candidates (conservative).
      if (hits == 0) hits = candidates;
      for (uint32_t ch = 0; ch < 8; ++ch)
        if (hits >> ch & 1u) child_ids[ch].push_back(id);
    }
  }

  // Whether splitting a node of `total` references into these children pays.
  // A split that multiplies the references (triangles meeting in a vertex or
  // an edge, large triangles over a small cluster) buys nothing: the node
  // stays a leaf. Isolating a cluster (all references in one child) is
  // progress and goes on. With term=sah the split must also lower the cost.
  bool split_pays(const std::array<std::vector<uint32_t>, 8>& child_ids, const std::vector<uint32_t>& stay,
                  size_t total) const {
    size_t child_refs = 0;
    for (const auto& c : child_ids) child_refs += c.size();
    if (opt_.assign == OctreeAssign::Exact && static_cast<double>(child_refs) > opt_.max_growth * static_cast<double>(total))
      return false;
    if (!opt_.sah) return true;
    auto blocks = [](size_t refs) { return static_cast<double>((refs + kSahBlock - 1) / kSahBlock); };
    double split_cost = 0.0;
    for (const auto& c : child_ids) split_cost += 0.25 * blocks(c.size());
    split_cost += opt_.ct + blocks(stay.size());
    return split_cost < blocks(total);
  }

  const TriangleMesh& mesh_;
  OctreeBuildOptions opt_;
  OctreeCube cube_;
  const std::vector<Aabb>& boxes_;
};


}  // namespace

OctreeTree build_octree(const TriangleMesh& mesh, const OctreeBuildOptions& opt) {
  return build_octree_tree(mesh, opt.max_depth, "octree",
                           [&](const OctreeCube& cube, const std::vector<Aabb>& boxes, OctTmpNode& root,
                               std::vector<uint32_t> ids) {
                             const uint32_t origin[3] = {0, 0, 0};
                             OctreeBuilder(mesh, opt, cube, boxes).build(root, std::move(ids), 0, origin);
                           });
}

OctreeShape measure_octree(const OctreeTree& tree) {
  OctreeShape s;
  SahTally tally;
  std::vector<std::pair<uint32_t, int>> stack{{0u, 0}};
  while (!stack.empty()) {
    const auto [i, level] = stack.back();
    stack.pop_back();
    const OctreeNode& n = tree.nodes[i];
    ++s.nodes;
    if (s.nodes_per_level.size() <= static_cast<size_t>(level)) s.nodes_per_level.resize(level + 1);
    ++s.nodes_per_level[level];
    s.max_depth = std::max(s.max_depth, level);
    s.references += n.count();
    const double area = std::ldexp(1.0, -2 * level);  // relative to the root cube
    const bool inner = n.first_child != 0 || (i == 0 && tree.nodes.size() > 1);
    if (n.count() || n.mask()) ++s.nonempty_nodes;
    if (inner) {
      ++s.inner;
      s.inner_references += n.count();
      tally.inner(area);
      tally.cost += kSahReportIntersectionCost * area * n.count();
      for (uint32_t ch = 0; ch < 8; ++ch) stack.emplace_back(n.first_child + ch, level + 1);
    } else {
      ++s.leaves;
      if (n.count() == 0) ++s.empty_leaves;
      s.max_leaf_size = std::max<size_t>(s.max_leaf_size, n.count());
      tally.leaf(area, n.count(), level);
    }
  }
  s.avg_leaf_depth = tally.avg_leaf_depth();
  s.sah_cost = tally.sah_cost(1.0);
  return s;
}

}  // namespace raylab
