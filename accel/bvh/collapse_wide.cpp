#include "accel/bvh/collapse_wide.h"

#include "accel/core/huge_page_allocator.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

#include <tbb/parallel_invoke.h>

#include "accel/bvh/build_common.h"

namespace raylab {

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();
constexpr uint32_t kParallelDpSize = 8192;  // subtrees with this many references recurse as tasks

class Collapser {
 public:
  Collapser(const BinaryBvh& tree, const CollapseOptions& o) : tree_(tree), opt_(o), n_(o.width) {
    if (n_ != 2 && n_ != 4 && n_ != 8 && n_ != kMaxWideWidth)
      throw std::invalid_argument("collapse: width must be 2, 4, 8 or 16");
    opt_.block_width = std::max(1, opt_.block_width);
    opt_.max_leaf = std::max(1, opt_.max_leaf);
    counts_ = subtree_ref_counts(tree.nodes);
    // Not initialised: solve() writes every entry of every node it reaches
    // before any is read (N per node: filling them first was a measurable
    // share of a 16-wide collapse); on huge pages, as first touching them
    // page by page was another.
    cost_ = HugePageBuffer<float>(tree.nodes.size() * n_);
    choice_ = HugePageBuffer<uint8_t>(tree.nodes.size() * n_);
    inner_split_.assign(tree.nodes.size(), 0);
    slots_.assign(tree.nodes.size(), 1);
    thick_area_ = opt_.thick_leaf_area > 0.0f && opt_.thick_leaf_limit > 0.0f && opt_.mesh && !tree.nodes.empty()
                      ? opt_.thick_leaf_area * tree.nodes[0].bounds().half_area()
                      : kInf;
  }

  WideTree run() {
    WideTree out;
    const auto& nodes = tree_.nodes;
    if (nodes.empty() || (is_leaf(0) && nodes[0].count == 0)) {
      out.root_leaf = 0;
      out.leaf_begin = {0, 0};
      out.root_box = Aabb::empty();
      return out;
    }
    solve(0);
    out.root_box = nodes[0].bounds();
    const float root_area = out.root_box.half_area();
    if (is_leaf(0) || choice_[0] == 0) {
      out.root_leaf = 0;
      out.leaf_begin.push_back(0);
      gather_leaf(0, out);
      out.dp_cost = root_area > 0.0f ? cost_[0] / root_area : 0.0;
      return out;
    }
    out.dp_cost = root_area > 0.0f ? cost_[0] / root_area : 0.0;
    out.leaf_begin.push_back(0);
    out.nodes.emplace_back();
    // (binary node, wide node) pairs to expand, depth first.
    std::vector<std::pair<uint32_t, uint32_t>> stack{{0u, 0u}};
    std::vector<uint32_t> slots;
    while (!stack.empty()) {
      const auto [bnode, wnode] = stack.back();
      stack.pop_back();
      slots.clear();
      const uint32_t l = nodes[bnode].index;
      const int k = inner_split_[bnode];
      collect(l, k, slots);
      collect(l + 1, n_ - k, slots);
      const size_t first_inner = out.nodes.size();
      size_t inner = 0;
      for (uint32_t s : slots) inner += !(is_leaf(s) || choice_[s * n_] == 0);
      out.nodes.resize(first_inner + inner);
      WideTree::Node& w = out.nodes[wnode];
      w.count = static_cast<int>(slots.size());
      size_t next_inner = first_inner;
      for (size_t c = 0; c < slots.size(); ++c) {
        const uint32_t s = slots[c];
        WideTree::Child& ch = w.child[c];
        ch.box = nodes[s].bounds();
        if (is_leaf(s) || choice_[s * n_] == 0) {
          ch.leaf = true;
          ch.index = static_cast<uint32_t>(out.leaf_begin.size() - 1);
          gather_leaf(s, out);
        } else {
          ch.leaf = false;
          ch.index = static_cast<uint32_t>(next_inner++);
        }
      }
      // Push inner children in reverse so the first is expanded first.
      for (size_t c = slots.size(); c-- > 0;) {
        const WideTree::Child& ch = out.nodes[wnode].child[c];
        if (!ch.leaf) stack.push_back({slots[c], ch.index});
      }
    }
    return out;
  }

 private:
  bool is_leaf(uint32_t n) const { return tree_.nodes[n].count != 0 || tree_.nodes[n].index == 0; }

  float leaf_cost(uint32_t n, bool forced) const {
    const uint32_t c = counts_[n];
    const uint32_t blocks = (c + opt_.block_width - 1) / opt_.block_width;
    if (!forced && (c > static_cast<uint32_t>(opt_.max_leaf) || blocks > static_cast<uint32_t>(opt_.max_leaf_blocks)))
      return kInf;
    const Aabb box = tree_.nodes[n].bounds();
    const float area = box.half_area();
    // A binary leaf cannot be opened; larger thick leaves are not formed.
    if (!forced && area > thick_area_ && box_thickness(box) > opt_.thick_leaf_limit && holds_flat_triangles(n, box))
      return kInf;
    return area * opt_.block_cost * static_cast<float>(blocks);
  }

  // Whether the triangles below n (a leaf candidate: at most max_leaf
  // references) leave most of n's box empty: their own boxes' volumes sum to
  // under a quarter of its volume (a floor and walls: zero). Large triangles
  // of any orientation (a soup) fill their leaves' boxes and are left alone.
  bool holds_flat_triangles(uint32_t n, const Aabb& box) const {
    double sum = 0.0;
    std::array<uint32_t, 64> stack;
    size_t top = 0;
    stack[top++] = n;
    while (top > 0) {
      const uint32_t x = stack[--top];
      const Bvh2Node& node = tree_.nodes[x];
      if (is_leaf(x)) {
        for (uint32_t k = node.index; k < node.index + node.count; ++k)
          sum += box_volume(opt_.mesh->triangle_bounds(tree_.prim_ids[k]));
      } else {
        if (top + 2 > stack.size()) return false;
        stack[top++] = node.index;
        stack[top++] = node.index + 1;
      }
    }
    return 4.0 * sum < box_volume(box);
  }

  void solve(uint32_t n) {
    const Bvh2Node& node = tree_.nodes[n];
    float* c = &cost_[n * n_];
    uint8_t* ch = &choice_[n * n_];
    if (is_leaf(n)) {
      if (counts_[n] > static_cast<uint32_t>(opt_.max_leaf_blocks * opt_.block_width))
        throw std::logic_error("collapse: a binary leaf holds more references than a wide leaf can");
      const float lc = leaf_cost(n, true);
      for (int i = 0; i < n_; ++i) {
        c[i] = lc;
        ch[i] = 0;
      }
      return;
    }
    const uint32_t l = node.index, r = node.index + 1;
    if (counts_[n] >= kParallelDpSize) tbb::parallel_invoke([&] { solve(l); }, [&] { solve(r); });
    else {
      solve(l);
      solve(r);
    }
    const float* cl = &cost_[l * n_];
    const float* cr = &cost_[r * n_];
    // A subtree with s binary leaves never uses more than s slots: C(x, i) =
    // C(x, s) for i > s. So D(n, i) needs k only in [i - s(r), s(l)], and
    // D(n, i) = D(n, s(l) + s(r)) above that; the same optimum for a fraction
    // of the work at the many small subtrees near the leaves (what makes the
    // 16-wide collapse affordable).
    const int sl = slots_[l], sr = slots_[r];
    const int sn = std::min(n_, sl + sr);
    slots_[n] = static_cast<uint8_t>(sn);
    float d[kMaxWideWidth + 1];
    uint8_t dk[kMaxWideWidth + 1];
    for (int i = 2; i <= sn; ++i) {
      float best = kInf;
      uint8_t best_k = 1;
      for (int k = std::max(1, i - sr), k_end = std::min(i - 1, sl); k <= k_end; ++k) {
        const float v = cl[k - 1] + cr[i - k - 1];
        const bool better = v < best;
        best = better ? v : best;
        best_k = better ? static_cast<uint8_t>(k) : best_k;
      }
      d[i] = best;
      dk[i] = best_k;
    }
    // D(n, i) = D(n, sn) for i > sn, so C(n, i) = C(n, sn) there with the
    // choice "fewer slots" (0): a running minimum up to sn, then a fill.
    const float area = node.bounds().half_area();
    const float as_leaf = leaf_cost(n, false);
    const float as_inner = area * opt_.node_cost + d[sn];
    float run = std::min(as_leaf, as_inner);
    c[0] = run;
    ch[0] = as_leaf <= as_inner ? 0 : 1;
    for (int i = 2; i <= sn; ++i) {  // branch-free: the comparison is data-dependent
      const bool keep = run <= d[i];
      run = keep ? run : d[i];
      c[i - 1] = run;
      ch[i - 1] = keep ? uint8_t{0} : dk[i];
    }
    for (int i = sn; i < n_; ++i) {
      c[i] = run;
      ch[i] = 0;
    }
    inner_split_[n] = dk[sn];
  }

  // The binary nodes that become the child slots when n gets i slots.
  void collect(uint32_t n, int i, std::vector<uint32_t>& out) const {
    while (i > 1 && choice_[n * n_ + i - 1] == 0) --i;
    if (i == 1) {
      out.push_back(n);
      return;
    }
    const int k = choice_[n * n_ + i - 1];
    const uint32_t l = tree_.nodes[n].index;
    collect(l, k, out);
    collect(l + 1, i - k, out);
  }

  // Appends the references of binary subtree n (duplicates removed) as a new leaf.
  void gather_leaf(uint32_t n, WideTree& out) const {
    const size_t begin = out.leaf_prims.size();
    std::vector<uint32_t>& stack = gather_stack_;
    stack.assign(1, n);
    while (!stack.empty()) {
      const uint32_t x = stack.back();
      stack.pop_back();
      const Bvh2Node& node = tree_.nodes[x];
      if (is_leaf(x)) {
        out.leaf_prims.insert(out.leaf_prims.end(), tree_.prim_ids.begin() + node.index,
                              tree_.prim_ids.begin() + node.index + node.count);
      } else {
        stack.push_back(node.index + 1);
        stack.push_back(node.index);
      }
    }
    if (out.leaf_prims.size() - begin > 1) {
      std::sort(out.leaf_prims.begin() + begin, out.leaf_prims.end());
      out.leaf_prims.erase(std::unique(out.leaf_prims.begin() + begin, out.leaf_prims.end()), out.leaf_prims.end());
    }
    out.leaf_begin.push_back(static_cast<uint32_t>(out.leaf_prims.size()));
  }

  const BinaryBvh& tree_;
  CollapseOptions opt_;
  int n_;
  std::vector<uint32_t> counts_;
  float thick_area_ = kInf;          // half area above which thick merged leaves are not formed
  HugePageBuffer<float> cost_;
  HugePageBuffer<uint8_t> choice_;  // per (node, i): see file comment
  std::vector<uint8_t> inner_split_; // k of D(n, N)
  std::vector<uint8_t> slots_;       // min(N, binary leaves of the subtree): the most slots it can fill
  mutable std::vector<uint32_t> gather_stack_;
};

}  // namespace

double box_volume(const Aabb& box) {
  const Vec3f e = (box.hi - box.lo).cwiseMax(0.0f);
  return static_cast<double>(e.x()) * e.y() * e.z();
}

float box_thickness(const Aabb& box) {
  const Vec3f e = (box.hi - box.lo).cwiseMax(0.0f);
  const double area = static_cast<double>(e.x()) * e.y() + static_cast<double>(e.y()) * e.z() +
                      static_cast<double>(e.z()) * e.x();
  if (!(area > 0.0)) return 0.0f;
  return static_cast<float>(std::sqrt(27.0) * box_volume(box) / (area * std::sqrt(area)));
}

WideTree collapse_to_wide(const BinaryBvh& tree, const CollapseOptions& options) {
  return Collapser(tree, options).run();
}

WideShape measure_wide(const WideTree& t) {
  WideShape s;
  if (t.root_leaf >= 0) {
    s.leaves = t.leaf_count();
    s.avg_leaf_size = t.leaf_prims.size();
    s.sah_cost = kSahReportIntersectionCost * static_cast<double>(t.leaf_prims.size());
    return s;
  }
  const double root_area = t.root_box.half_area();
  struct Item {
    uint32_t node;
    int depth;
  };
  std::vector<Item> stack{{0u, 0}};
  double cost = 0.0, depth_sum = 0.0, children = 0.0;
  while (!stack.empty()) {
    const Item it = stack.back();
    stack.pop_back();
    const WideTree::Node& n = t.nodes[it.node];
    s.nodes++;
    Aabb box;
    for (int c = 0; c < n.count; ++c) box.extend(n.child[c].box);
    cost += kSahReportTraversalCost * box.half_area();
    children += n.count;
    for (int c = 0; c < n.count; ++c) {
      const WideTree::Child& ch = n.child[c];
      if (ch.leaf) {
        s.leaves++;
        s.max_depth = std::max(s.max_depth, it.depth + 1);
        depth_sum += it.depth + 1;
        cost += kSahReportIntersectionCost * ch.box.half_area() * t.leaf_size(ch.index);
      } else {
        stack.push_back({ch.index, it.depth + 1});
      }
    }
  }
  s.avg_leaf_depth = s.leaves ? depth_sum / static_cast<double>(s.leaves) : 0.0;
  s.avg_leaf_size = s.leaves ? static_cast<double>(t.leaf_prims.size()) / static_cast<double>(s.leaves) : 0.0;
  s.child_fill = s.nodes ? children / static_cast<double>(s.nodes) : 0.0;
  s.sah_cost = root_area > 0.0 ? cost / root_area : 0.0;
  return s;
}

}  // namespace raylab
