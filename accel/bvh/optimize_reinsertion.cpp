#include "accel/bvh/optimize_reinsertion.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include "accel/core/huge_page_allocator.h"
#include "base/timer.h"

namespace raylab {

namespace {

constexpr uint32_t kNone = 0xFFFFFFFFu;

// A non-negative float's bits order like the float (NaN and negatives, which
// the measure never gives, map to 0: never a candidate).
uint32_t order_key(float v) {
  if (!(v > 0.0f)) return 0;
  uint32_t bits;
  std::memcpy(&bits, &v, sizeof bits);
  return bits;
}

struct Move {
  uint32_t node = kNone, target = kNone, parent = kNone;
  float gain = 0.0f;
};

class Reinserter {
 public:
  Reinserter(const BinaryBvh& t, const ReinsertionOptions& o) : in_(t), opt_(o) {
    const size_t m = t.nodes.size();
    parent_.assign(m, kNone);
    child_[0].assign(m, kNone);
    child_[1].assign(m, kNone);
    box_ = HugePageBuffer<Box4>(m);  // every entry written below
    area_.resize(m);
    weight_.resize(m);
    touched_.assign(m, 0);
    is_dirty_.assign(m, 0);
    for (size_t i = 0; i < m; ++i) {
      const Bvh2Node& n = t.nodes[i];
      box_[i] = Box4::from(n.bounds());
      area_[i] = box_[i].half_area();
      // A node stays a leaf or an inner node through every move, so its
      // weight in the SAH sum is fixed.
      weight_[i] = n.count != 0 || n.index == 0 ? kSahReportIntersectionCost * n.count : kSahReportTraversalCost;
      if (n.count == 0 && n.index != 0) {
        child_[0][i] = n.index;
        child_[1][i] = n.index + 1;
        parent_[n.index] = parent_[n.index + 1] = static_cast<uint32_t>(i);
      }
    }
  }

  BinaryBvh run(ReinsertionStats* stats) {
    Timer timer;
    const size_t m = in_.nodes.size();
    double cost = sah();
    const double before = cost;
    int rounds = 0;
    size_t moves = 0;
    if (m >= 7) {
      const size_t batch = std::max<size_t>(64, static_cast<size_t>(opt_.batch_fraction * static_cast<double>(m)));
      std::vector<uint32_t> measure(m), worst;
      std::vector<Move> found;
      for (; rounds < opt_.max_rounds; ++rounds) {
        // Candidates: the worst nodes by Bittner's combined measure, all of
        // them in the first round (or after the root moved), then only the
        // ones the last round's moves changed: a light pass's rounds touch
        // a few thousand of the nodes, and measuring all of them every round
        // cost as much as the searches.
        if (all_dirty_ || opt_.remeasure_all) {
          tbb::parallel_for(tbb::blocked_range<size_t>(0, m, 4096), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i < r.end(); ++i) measure[i] = order_key(inefficiency(static_cast<uint32_t>(i)));
          });
          all_dirty_ = false;
        } else {
          for (uint32_t v : dirty_) measure[v] = order_key(inefficiency(v));
        }
        for (uint32_t v : dirty_) is_dirty_[v] = 0;
        dirty_.clear();
        select_largest_keys(measure, std::min(batch, m), worst);
        found.assign(worst.size(), Move{});
        tbb::parallel_for(tbb::blocked_range<size_t>(0, worst.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
          Scratch& sc = scratch_.local();
          for (size_t i = r.begin(); i < r.end(); ++i) found[i] = search(worst[i], sc);
        });
        found.erase(std::remove_if(found.begin(), found.end(), [](const Move& mv) { return !(mv.gain > 0.0f); }),
                    found.end());
        std::sort(found.begin(), found.end(),
                  [](const Move& a, const Move& b) { return a.gain != b.gain ? a.gain > b.gain : a.node < b.node; });
        std::fill(touched_.begin(), touched_.end(), 0);
        size_t applied = 0;
        for (const Move& mv : found) applied += apply(mv);
        moves += applied;
        const double next = sah();
        const bool converged = applied == 0 || cost - next < opt_.min_gain * cost;
        cost = next;
        if (converged) {
          ++rounds;
          break;
        }
      }
    }
    BinaryBvh out;
    const bool ok = relayout(out);
    if (stats) {
      stats->sah_before = before;
      stats->sah_after = ok ? cost : before;
      stats->rounds = rounds;
      stats->moves = ok ? moves : 0;
      stats->ms = timer.ms();
    }
    if (!ok) return in_;
    return out;
  }

 private:
  struct Scratch {
    std::vector<uint32_t> stamp, alt;
    std::vector<Box4> boxes;
    uint32_t id = 0;
    std::vector<std::pair<float, uint32_t>> heap;
  };

  bool is_leaf(uint32_t n) const { return child_[0][n] == kNone; }
  uint32_t sibling(uint32_t n) const {
    const uint32_t p = parent_[n];
    return child_[0][p] == n ? child_[1][p] : child_[0][p];
  }

  float inefficiency(uint32_t n) const {
    const uint32_t p = parent_[n];
    if (p == kNone || p == root_) return 0.0f;
    const float a = area_[n];
    if (is_leaf(n)) return a;
    const float al = area_[child_[0][n]], ar = area_[child_[1][n]];
    const float mean = std::max(0.5f * (al + ar), 1e-30f), mn = std::max(std::min(al, ar), 1e-30f);
    return a * (a / mean) * (a / mn);
  }

  double sah() const {
    const size_t m = in_.nodes.size();
    const double total = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, m, 8192), 0.0,
        [&](const tbb::blocked_range<size_t>& r, double acc) {
          for (size_t i = r.begin(); i < r.end(); ++i) acc += static_cast<double>(area_[i]) * weight_[i];
          return acc;
        },
        std::plus<double>());
    const double root_area = area_[root_];
    return root_area > 0.0 ? total / root_area : 0.0;
  }

  // Best place to reinsert n's subtree (as the sibling of `target`).
  Move search(uint32_t n, Scratch& sc) const {
    Move mv;
    const uint32_t p = parent_[n];
    if (p == kNone || p == root_) return mv;
    const uint32_t s = sibling(n);
    const size_t m = in_.nodes.size();
    if (sc.stamp.size() != m) {
      sc.stamp.assign(m, 0);
      sc.alt.assign(m, 0);
      sc.id = 0;
    }
    if (++sc.id == 0) {
      std::fill(sc.stamp.begin(), sc.stamp.end(), 0);
      sc.id = 1;
    }
    // Removing n and p: p's ancestors shrink to the boxes they would have.
    sc.boxes.clear();
    float removed = area_[p];
    Box4 cb = box_[s];
    uint32_t prev = p;
    for (uint32_t y = parent_[p]; y != kNone; prev = y, y = parent_[y]) {
      const uint32_t other = child_[0][y] == prev ? child_[1][y] : child_[0][y];
      const Box4 nb = merge(cb, box_[other]);
      removed += area_[y] - nb.half_area();
      sc.stamp[y] = sc.id;
      sc.alt[y] = static_cast<uint32_t>(sc.boxes.size());
      sc.boxes.push_back(nb);
      cb = nb;
    }
    // Branch and bound over insertion positions; the induced cost of a
    // position is the growth of its ancestors' areas.
    const Box4& nbox = box_[n];
    const float an = nbox.half_area();
    float best = std::numeric_limits<float>::infinity();
    uint32_t best_x = kNone;
    auto cmp = [](const std::pair<float, uint32_t>& a, const std::pair<float, uint32_t>& b) { return a.first > b.first; };
    std::vector<std::pair<float, uint32_t>>& heap = sc.heap;
    heap.clear();
    heap.push_back({0.0f, root_});
    while (!heap.empty()) {
      std::pop_heap(heap.begin(), heap.end(), cmp);
      const auto [ci, x] = heap.back();
      heap.pop_back();
      if (ci + an >= best) break;
      const Box4& bx = sc.stamp[x] == sc.id ? sc.boxes[sc.alt[x]] : box_[x];
      const float direct = merge(bx, nbox).half_area();
      if (ci + direct < best) {
        best = ci + direct;
        best_x = x;
      }
      if (is_leaf(x)) continue;
      const float induced = ci + direct - bx.half_area();
      if (induced + an >= best) continue;
      for (int c = 0; c < 2; ++c) {
        uint32_t y = child_[c][x];
        if (y == p) y = s;  // p is gone: s has taken its place
        heap.push_back({induced, y});
        std::push_heap(heap.begin(), heap.end(), cmp);
      }
    }
    mv.node = n;
    mv.target = best_x;
    mv.parent = p;
    mv.gain = removed - best;
    return mv;
  }

  void replace_child(uint32_t parent, uint32_t old_child, uint32_t new_child) {
    if (child_[0][parent] == old_child) child_[0][parent] = new_child;
    else child_[1][parent] = new_child;
  }
  void refit(uint32_t y) {
    for (; y != kNone; y = parent_[y]) {
      box_[y] = merge(box_[child_[0][y]], box_[child_[1][y]]);
      area_[y] = box_[y].half_area();
      mark_dirty(y);
    }
  }
  // A node's measure depends on its area, its children's areas and whether
  // its parent is the root: a move changes it for the nodes it relinks and
  // for those refit (whose parents are refit too), or for all when the root changes.
  void mark_dirty(uint32_t v) {
    if (v != kNone && !is_dirty_[v]) {
      is_dirty_[v] = 1;
      dirty_.push_back(v);
    }
  }

  bool apply(const Move& mv) {
    const uint32_t n = mv.node, x = mv.target, p = parent_[n];
    if (x == kNone || p != mv.parent || p == kNone || p == root_ || x == p || x == n) return false;
    const uint32_t s = sibling(n), g = parent_[p], q = parent_[x];
    if (x == s) return false;
    for (uint32_t v : {n, p, s, g, x, q})
      if (v != kNone && touched_[v]) return false;
    for (uint32_t y = x; y != kNone; y = parent_[y])
      if (y == n) return false;  // the target lies inside the moved subtree
    // Remove: s takes p's place under g.
    replace_child(g, p, s);
    parent_[s] = g;
    refit(g);
    // Insert: p becomes the parent of x and n, in x's place.
    const uint32_t q2 = parent_[x];  // unchanged unless x's parent was p (excluded above)
    if (q2 == kNone) {
      root_ = p;
      parent_[p] = kNone;
      all_dirty_ = true;
    } else {
      replace_child(q2, x, p);
      parent_[p] = q2;
    }
    child_[0][p] = x;
    child_[1][p] = n;
    parent_[x] = p;
    parent_[n] = p;
    box_[p] = merge(box_[x], box_[n]);
    area_[p] = box_[p].half_area();
    refit(q2);
    for (uint32_t v : {n, p, s, g, x, q2})
      if (v != kNone) {
        touched_[v] = 1;
        mark_dirty(v);
      }
    return true;
  }

  // Depth-first re-layout into the canonical format; false when too deep.
  // Moves keep the node and reference counts, so both arrays are sized once
  // and filled by index (growing them node by node was most of the pass's
  // own time outside the searches on a light pass).
  bool relayout(BinaryBvh& out) const {
    out.nodes.resize(in_.nodes.size());
    out.prim_ids.resize(in_.prim_ids.size());
    struct Item {
      uint32_t node, slot;
      int depth;
    };
    std::vector<Item> stack;
    stack.reserve(2 * kMaxTreeDepth + 4);
    stack.push_back({root_, 0u, 0});
    uint32_t next = 1;
    size_t prims = 0;
    while (!stack.empty()) {
      const Item it = stack.back();
      stack.pop_back();
      if (it.depth > kMaxTreeDepth) return false;
      Bvh2Node& dst = out.nodes[it.slot];
      dst.set_bounds(box_[it.node].aabb());
      if (is_leaf(it.node)) {
        const Bvh2Node& src = in_.nodes[it.node];
        dst.index = static_cast<uint32_t>(prims);
        dst.count = src.count;
        std::copy_n(in_.prim_ids.begin() + src.index, src.count,
                    out.prim_ids.begin() + static_cast<std::ptrdiff_t>(prims));
        prims += src.count;
        continue;
      }
      dst.index = next;
      dst.count = 0;
      stack.push_back({child_[1][it.node], next + 1, it.depth + 1});
      stack.push_back({child_[0][it.node], next, it.depth + 1});
      next += 2;
    }
    out.nodes.resize(next);  // the same sizes unless the input held unreachable nodes
    out.prim_ids.resize(prims);
    return true;
  }

  const BinaryBvh& in_;
  ReinsertionOptions opt_;
  std::vector<uint32_t> parent_, child_[2];
  HugePageBuffer<Box4> box_;
  std::vector<float> area_;    // box_[i].half_area(), kept with the boxes
  std::vector<float> weight_;  // the node's factor in the SAH sum (leaf: Ci * count, inner: Ct)
  std::vector<uint8_t> touched_;
  std::vector<uint8_t> is_dirty_;  // per node: in dirty_
  std::vector<uint32_t> dirty_;    // nodes whose measure the last round's moves changed
  bool all_dirty_ = true;
  uint32_t root_ = 0;
  mutable tbb::enumerable_thread_specific<Scratch> scratch_;
};

}  // namespace

// A histogram of the keys' top bits finds the bucket holding the k-th
// largest, so only that bucket is ordered: two linear passes instead of a
// selection over all nodes, which dominated a light pass's time (perf:
// nth_element was most of optimize_reinsertion's own time).
void select_largest_keys(const std::vector<uint32_t>& keys, size_t k, std::vector<uint32_t>& out) {
  constexpr int kShift = 20;  // 2^12 buckets: sign, exponent, three mantissa bits
  constexpr size_t kBuckets = size_t{1} << (32 - kShift);
  out.clear();
  if (k == 0) return;
  std::vector<uint32_t> count(kBuckets, 0);
  for (uint32_t key : keys)
    if (key) ++count[key >> kShift];
  size_t above = 0, cut = 0;
  for (size_t b = kBuckets; b-- > 1;) {
    if (above + count[b] >= k) {
      cut = b;
      break;
    }
    above += count[b];
  }
  std::vector<uint32_t> tie;
  for (size_t i = 0; i < keys.size(); ++i) {
    const uint32_t key = keys[i];
    if (!key) continue;
    const size_t b = key >> kShift;
    if (b > cut) out.push_back(static_cast<uint32_t>(i));
    else if (b == cut) tie.push_back(static_cast<uint32_t>(i));
  }
  if (out.size() + tie.size() <= k) {  // no more than k non-zero keys: take them all
    out.insert(out.end(), tie.begin(), tie.end());
    return;
  }
  const size_t take = k - out.size();
  auto larger = [&](uint32_t a, uint32_t b) { return keys[a] != keys[b] ? keys[a] > keys[b] : a < b; };
  std::nth_element(tie.begin(), tie.begin() + static_cast<std::ptrdiff_t>(take - 1), tie.end(), larger);
  out.insert(out.end(), tie.begin(), tie.begin() + static_cast<std::ptrdiff_t>(take));
}


BinaryBvh optimize_reinsertion(const BinaryBvh& tree, const ReinsertionOptions& options, ReinsertionStats* stats) {
  if (tree.nodes.size() < 3) {
    if (stats) *stats = ReinsertionStats{};
    return tree;
  }
  return Reinserter(tree, options).run(stats);
}

}  // namespace raylab
