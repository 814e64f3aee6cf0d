#include "accel/kdtree/build_sah_events.h"

#include <algorithm>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include "accel/kdtree/kd_build_start.h"
#include "accel/core/clip_triangle.h"
#include "accel/kdtree/kd_tree_writer.h"

namespace raylab {

namespace {

// Event types in the order the sweep needs at equal positions: triangles
// ending at p leave the right side before p is evaluated, planar ones are
// counted at p, starting ones join the left side after p (the order of
// Wald & Havran: end < planar < start).
constexpr uint32_t kEnd = 0, kPlanar = 1, kStart = 2;
constexpr uint32_t kTriMask = (1u << 30) - 1;

struct Event {
  float pos;
  uint32_t key;  // type << 30 | triangle: one compare orders by type, then id

  uint32_t tri() const { return key & kTriMask; }
  uint32_t type() const { return key >> 30; }
};

inline bool operator<(const Event& a, const Event& b) { return a.pos < b.pos || (a.pos == b.pos && a.key < b.key); }

inline Event make_event(float pos, uint32_t type, uint32_t tri) { return Event{pos, (type << 30) | tri}; }

using EventList = std::vector<Event>;

struct NodeEvents {
  EventList axis[3];
  size_t triangles = 0;

  void release() {
    for (auto& e : axis) EventList().swap(e);
  }
};

// Events of one triangle whose part inside the cell has bounds b.
inline void add_events(uint32_t tri, const Aabb& b, EventList* out) {
  for (int k = 0; k < 3; ++k) {
    if (b.lo[k] == b.hi[k]) {
      out[k].push_back(make_event(b.lo[k], kPlanar, tri));
    } else {
      out[k].push_back(make_event(b.lo[k], kStart, tri));
      out[k].push_back(make_event(b.hi[k], kEnd, tri));
    }
  }
}

// Merges sorted `extra` into sorted `dst` in place, from the back.
void merge_into(EventList& dst, const EventList& extra) {
  if (extra.empty()) return;
  size_t i = dst.size(), j = extra.size(), w = dst.size() + extra.size();
  dst.resize(w);
  while (j > 0) {
    if (i > 0 && extra[j - 1] < dst[i - 1]) dst[--w] = dst[--i];
    else dst[--w] = extra[--j];
  }
}

enum Side : uint8_t { kBoth = 0, kLeftOnly = 1, kRightOnly = 2 };

struct SplitPlane {
  int axis = -1;
  float pos = 0.0f;
  bool planar_left = true;
  double cost = std::numeric_limits<double>::infinity();
};

// Candidate planes that leave more than half of a cell's triangles (plus one)
// straddling are not considered. The SAH alone does not stop there in flat or
// nearly flat cells: with no volume to cut, the child probabilities add up to
// about 1, so any plane that separates a few of many overlapping coplanar
// triangles looks profitable and every level copies the rest into both
// children (in a test with 2,000 large overlapping triangles in 8 parallel
// planes that made 496 references per triangle; with this rule, 24). In
// ordinary meshes the rule never applies (the bunny's tree is unchanged).
// Wald & Havran 2006 has no such rule; it is this implementation's guard.

// Triangles in a node from which its two subtrees are built as tasks.
// Triangles in a node from which its three axes are swept and split in parallel.
constexpr size_t kParallelNodeSize = 65536;

struct Scratch {
  std::vector<uint8_t> side;
  std::vector<uint32_t> straddling, prims;
  EventList new_left[3], new_right[3];
};

class SahEventBuilder : KdBuilderBase {
 public:
  using KdBuilderBase::KdBuilderBase;

  KdTree run() {
    return run_from_root(kTriMask, [&](const Aabb& bounds) {
      // The root's events come from the triangles' boxes (the root cell
      // holds them all), sorted once; from here on lists are only split and
      // merged.
      const size_t n = mesh_.num_triangles();
      NodeEvents root;
      root.triangles = n;
      for (int k = 0; k < 3; ++k) root.axis[k].reserve(2 * n);
      for (size_t i = 0; i < n; ++i) add_events(static_cast<uint32_t>(i), tri_boxes_[i], root.axis);
      for (int k = 0; k < 3; ++k) tbb::parallel_sort(root.axis[k].begin(), root.axis[k].end());
      build(0, bounds, std::move(root), 0);
    });
  }

 private:
  void build(uint32_t node, const Aabb& cell, NodeEvents ev, int depth) {
    const size_t n = ev.triangles;
    if (n == 0) {
      writer_.set_leaf(node, {});
      return;
    }
    SplitPlane best;
    if (depth < max_depth_ && cell.half_area() > 0.0f) best = find_plane(cell, ev);
    // Wald & Havran's termination: a leaf when no split is cheaper than
    // testing every triangle.
    if (best.axis < 0 || !(best.cost < static_cast<double>(opt_.intersection_cost) * static_cast<double>(n)))
      return make_leaf(node, ev);

    Scratch& scratch = scratch_.local();
    std::vector<uint8_t>& side = scratch.side;
    if (side.size() < mesh_.num_triangles()) side.resize(mesh_.num_triangles());
    classify(ev.axis[best.axis], best, side.data());

    Aabb left_cell = cell, right_cell = cell;
    left_cell.hi[best.axis] = best.pos;
    right_cell.lo[best.axis] = best.pos;
    NodeEvents left, right;
    split_events(ev, best, scratch, left_cell, right_cell, left, right);
    // No progress on either side (possible only with degenerate costs):
    // stop rather than recurse on the same triangles.
    if (left.triangles >= n && right.triangles >= n) return make_leaf(node, ev);
    ev.release();

    const uint32_t pair = writer_.allocate_pair();
    writer_.set_inner(node, best.axis, best.pos, pair);
    build_children(
        n, [&] { build(pair, left_cell, std::move(left), depth + 1); },
        [&] { build(pair + 1, right_cell, std::move(right), depth + 1); });
  }

  void make_leaf(uint32_t node, const NodeEvents& ev) {
    std::vector<uint32_t>& prims = scratch_.local().prims;
    prims.clear();
    for (const Event& e : ev.axis[0])
      if (e.type() != kEnd) prims.push_back(e.tri());
    // Ascending ids: among hits at exactly the same distance the lowest id
    // wins within a leaf, as in the brute-force reference.
    std::sort(prims.begin(), prims.end());
    writer_.set_leaf(node, prims);
  }

  // One sweep over the sorted events of axis k (the incremental SAH sweep of Wald & Havran).
  SplitPlane sweep_axis(const Aabb& cell, const NodeEvents& ev, int k) const {
    SplitPlane best;
    const float lo = cell.lo[k], hi = cell.hi[k];
    if (!(hi > lo)) return best;  // a flat cell is never split along its flat axis
    const Vec3d d = (cell.hi - cell.lo).cast<double>();
    const double a = d[(k + 1) % 3], b = d[(k + 2) % 3];
    const double cross = a * b, perimeter = a + b;
    const double inv_half_area = 1.0 / (cross + d[k] * perimeter);
    const double ct = opt_.traversal_cost, ci = opt_.intersection_cost;
    const double lambda_empty = 1.0 - static_cast<double>(opt_.empty_bonus);
    const size_t n = ev.triangles;

    const EventList& e = ev.axis[k];
    size_t nl = 0, nr = n;
    for (size_t i = 0; i < e.size();) {
      const float p = e[i].pos;
      size_t ending = 0, planar = 0, starting = 0;
      while (i < e.size() && e[i].pos == p && e[i].type() == kEnd) ++ending, ++i;
      while (i < e.size() && e[i].pos == p && e[i].type() == kPlanar) ++planar, ++i;
      while (i < e.size() && e[i].pos == p && e[i].type() == kStart) ++starting, ++i;
      nr -= planar + ending;

      const double wl = static_cast<double>(p) - lo, wr = static_cast<double>(hi) - p;
      const double pl = (cross + wl * perimeter) * inv_half_area;
      const double pr = (cross + wr * perimeter) * inv_half_area;
      for (int planar_side = 0; planar_side < 2; ++planar_side) {
        const size_t cl = nl + (planar_side == 0 ? planar : 0);
        const size_t cr = nr + (planar_side == 1 ? planar : 0);
        // An empty flat cell cuts off nothing; a flat cell is only worth
        // making when it takes the planar triangles lying in it.
        if ((cl == 0 && wl <= 0.0) || (cr == 0 && wr <= 0.0)) continue;
        if (cl == n && cr == n) continue;  // reduces neither side
        if (2 * (cl + cr) > 3 * n + 2) continue;  // more than half straddling (see above)
        const double lambda = (cl == 0 || cr == 0) ? lambda_empty : 1.0;
        const double cost = lambda * (ct + ci * (pl * static_cast<double>(cl) + pr * static_cast<double>(cr)));
        if (cost < best.cost) best = SplitPlane{k, p, planar_side == 0, cost};
      }
      nl += starting + planar;
    }
    return best;
  }

  SplitPlane find_plane(const Aabb& cell, const NodeEvents& ev) const {
    SplitPlane per_axis[3];
    if (ev.triangles >= kParallelNodeSize) {
      // Isolated: a thread waiting here must not pick up another node's task,
      // which would reuse its classification array.
      tbb::this_task_arena::isolate([&] {
        tbb::parallel_invoke([&] { per_axis[0] = sweep_axis(cell, ev, 0); },
                             [&] { per_axis[1] = sweep_axis(cell, ev, 1); },
                             [&] { per_axis[2] = sweep_axis(cell, ev, 2); });
      });
    } else {
      for (int k = 0; k < 3; ++k) per_axis[k] = sweep_axis(cell, ev, k);
    }
    SplitPlane best;
    for (const auto& p : per_axis)
      if (p.cost < best.cost) best = p;
    return best;
  }

  // Marks every triangle of the node left only, right only or both, from the
  // events of the split axis alone (Wald & Havran's classification step).
  static void classify(const EventList& e, const SplitPlane& s, uint8_t* side) {
    for (const Event& x : e)
      if (x.type() != kEnd) side[x.tri()] = kBoth;
    const float p = s.pos;
    for (const Event& x : e) {
      switch (x.type()) {
        case kEnd:
          if (x.pos <= p) side[x.tri()] = kLeftOnly;
          break;
        case kStart:
          if (x.pos >= p) side[x.tri()] = kRightOnly;
          break;
        default:  // planar
          side[x.tri()] = (x.pos < p || (x.pos == p && s.planar_left)) ? kLeftOnly : kRightOnly;
      }
    }
  }

  bool clip_to(uint32_t tri, const Aabb& cell, Aabb& out) const {
    if (!opt_.perfect_splits) return clip_box_to_cell(tri_boxes_[tri], cell, out);
    return clip_triangle_to_cell(mesh_.vertex(tri, 0), mesh_.vertex(tri, 1), mesh_.vertex(tri, 2), cell, out);
  }

  void split_events(const NodeEvents& ev, const SplitPlane& s, Scratch& scratch, const Aabb& left_cell,
                    const Aabb& right_cell, NodeEvents& left, NodeEvents& right) const {
    const uint8_t* side = scratch.side.data();
    size_t left_only = 0, right_only = 0;
    std::vector<uint32_t>& straddling = scratch.straddling;
    straddling.clear();
    for (const Event& x : ev.axis[s.axis]) {
      if (x.type() == kEnd) continue;
      switch (side[x.tri()]) {
        case kLeftOnly: ++left_only; break;
        case kRightOnly: ++right_only; break;
        default: straddling.push_back(x.tri());
      }
    }
    // Straddling triangles get fresh events from their part in each child.
    EventList* new_left = scratch.new_left;
    EventList* new_right = scratch.new_right;
    for (int k = 0; k < 3; ++k) {
      new_left[k].clear();
      new_right[k].clear();
    }
    left.triangles = left_only;
    right.triangles = right_only;
    for (const uint32_t tri : straddling) {
      Aabb b;
      if (clip_to(tri, left_cell, b)) {
        add_events(tri, b, new_left);
        ++left.triangles;
      }
      if (clip_to(tri, right_cell, b)) {
        add_events(tri, b, new_right);
        ++right.triangles;
      }
    }
    auto split_axis = [&](int k) {
      const EventList& src = ev.axis[k];
      EventList& l = left.axis[k];
      EventList& r = right.axis[k];
      // At most two events per triangle on each side.
      l.reserve(std::min(src.size(), 2 * left_only) + new_left[k].size());
      r.reserve(std::min(src.size(), 2 * right_only) + new_right[k].size());
      for (const Event& x : src) {
        const uint8_t sd = side[x.tri()];
        if (sd == kLeftOnly) l.push_back(x);
        else if (sd == kRightOnly) r.push_back(x);
      }
      std::sort(new_left[k].begin(), new_left[k].end());
      std::sort(new_right[k].begin(), new_right[k].end());
      merge_into(l, new_left[k]);
      merge_into(r, new_right[k]);
    };
    if (ev.triangles >= kParallelNodeSize) {
      tbb::this_task_arena::isolate([&] {
        tbb::parallel_invoke([&] { split_axis(0); }, [&] { split_axis(1); }, [&] { split_axis(2); });
      });
    } else {
      for (int k = 0; k < 3; ++k) split_axis(k);
    }
  }

  // Per-thread working memory, reused from node to node: the classification
  // array indexed by triangle id (the paper's per-triangle flag) and the
  // lists of straddling triangles and their new events. Only touched between
  // classify and the end of split_events (or in make_leaf) of one node, with
  // no task switch in between (see the isolated regions).
  tbb::enumerable_thread_specific<Scratch> scratch_;
};

}  // namespace

KdTree build_kdtree_sah(const TriangleMesh& mesh, const KdBuildOptions& options) {
  return SahEventBuilder(mesh, options).run();
}

}  // namespace raylab
