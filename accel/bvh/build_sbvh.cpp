#include "accel/bvh/build_sbvh.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_reduce.h>

#include "accel/bvh/build_binned_sah.h"
#include "accel/bvh/sah_binning.h"

namespace raylab {

namespace {

// Neighbouring floats without libm calls (x finite).
inline float next_up(float x) {
  if (x == 0.0f) return std::numeric_limits<float>::denorm_min();
  uint32_t u;
  std::memcpy(&u, &x, sizeof u);
  u = x > 0.0f ? u + 1 : u - 1;
  std::memcpy(&x, &u, sizeof u);
  return x;
}
inline float next_down(float x) { return -next_up(-x); }

}  // namespace

void TriangleSplitter::split(uint32_t prim, const Aabb& box, int axis, float pos, bool conservative, Aabb& left,
                             Aabb& right) const {
  float llo[3], lhi[3], rlo[3], rhi[3];
  for (int a = 0; a < 3; ++a) {
    llo[a] = rlo[a] = std::numeric_limits<float>::infinity();
    lhi[a] = rhi[a] = -std::numeric_limits<float>::infinity();
  }
  auto add = [](float* lo, float* hi, const float* p) {
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::min(lo[a], p[a]);
      hi[a] = std::max(hi[a], p[a]);
    }
  };
  float v[3][3];
  for (int c = 0; c < 3; ++c)
    for (int a = 0; a < 3; ++a) v[c][a] = mesh_.vertex(prim, c)[a];
  for (int i = 0; i < 3; ++i) {
    const float* p = v[i];
    const float* q = v[i == 2 ? 0 : i + 1];
    const float pa = p[axis], qa = q[axis];
    if (pa <= pos) add(llo, lhi, p);
    if (pa >= pos) add(rlo, rhi, p);
    if ((pa < pos && qa > pos) || (pa > pos && qa < pos)) {
      float lo[3], hi[3];
      if (conservative) {
        // Crossing point in double, widened by one float step each way so
        // the boxes enclose the exact crossing.
        const double t = (static_cast<double>(pos) - pa) / (static_cast<double>(qa) - pa);
        for (int a = 0; a < 3; ++a) {
          if (a == axis) {
            lo[a] = hi[a] = pos;
            continue;
          }
          const float f = static_cast<float>(static_cast<double>(p[a]) + t * (static_cast<double>(q[a]) - p[a]));
          lo[a] = next_down(f);
          hi[a] = next_up(f);
        }
      } else {
        const float t = (pos - pa) / (qa - pa);
        for (int a = 0; a < 3; ++a) lo[a] = hi[a] = a == axis ? pos : p[a] + t * (q[a] - p[a]);
      }
      add(llo, lhi, lo), add(llo, lhi, hi);
      add(rlo, rhi, lo), add(rlo, rhi, hi);
    }
  }
  // Keep each part inside the reference's box and on its side of the plane.
  auto finish = [&](const float* lo, const float* hi, bool is_left, Aabb& out) {
    Vec3f l, h;
    for (int a = 0; a < 3; ++a) {
      l[a] = std::max(lo[a], box.lo[a]);
      h[a] = std::min(hi[a], box.hi[a]);
    }
    if (is_left) h[axis] = std::min(h[axis], pos);
    else l[axis] = std::max(l[axis], pos);
    out = Aabb(l, h);
    if (out.is_empty()) out = Aabb::empty();
  };
  finish(llo, lhi, true, left);
  finish(rlo, rhi, false, right);
}

namespace {

using sah::Binning;
using sah::Split;

constexpr int kMaxSpatialBins = 256;
constexpr size_t kParallelTaskSize = 4096;
constexpr size_t kParallelBinSize = 16384;

// Spatial bins of all three axes: clipped boxes, and how many references
// start (enter) and end (exit) in each bin.
struct SpatialBins : sah::BinBoxes<kMaxSpatialBins> {
  uint32_t enter[3][kMaxSpatialBins];
  uint32_t exit[3][kMaxSpatialBins];

  static std::unique_ptr<SpatialBins> make(int bins) {
    std::unique_ptr<SpatialBins> s(new SpatialBins);
    s->reset(bins);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < bins; ++b) s->enter[a][b] = s->exit[a][b] = 0;
    return s;
  }
  void add(int a, int b, const Box4& box) { grow(a, b, box); }
  void merge_from(const SpatialBins& o, int bins) {
    merge_boxes(o, bins);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < bins; ++b) {
        enter[a][b] += o.enter[a][b];
        exit[a][b] += o.exit[a][b];
      }
  }
};

struct SpatialSplit {
  int axis = -1;
  float pos = 0.0f;
  float cost = std::numeric_limits<float>::infinity();
  Box4 left, right;
  uint32_t left_count = 0, right_count = 0;
};

// Uniform slabs over the node's bounds along each axis.
struct SlabGrid {
  float lo[3], width[3], inv_width[3];
  int bins;
  // Only the node's widest axis gets slabs: long nodes are where large
  // straddling triangles matter, and three axes triple the clipping work.
  SlabGrid(const Box4& bounds, int n) : bins(n) {
    int widest = 0;
    float widest_ext = -1.0f;
    for (int a = 0; a < 3; ++a) {
      lo[a] = bounds.lo_at(a);
      const float ext = bounds.hi_at(a) - lo[a];
      width[a] = ext / static_cast<float>(n);
      inv_width[a] = ext > 0.0f ? static_cast<float>(n) / ext : 0.0f;
      if (ext > widest_ext) widest_ext = ext, widest = a;
    }
    for (int a = 0; a < 3; ++a)
      if (a != widest) inv_width[a] = 0.0f;
  }
  int bin(int a, float x) const {
    const int b = static_cast<int>((x - lo[a]) * inv_width[a]);
    return std::clamp(b, 0, bins - 1);
  }
  // Plane between bins b-1 and b.
  float plane(int a, int b) const { return lo[a] + width[a] * static_cast<float>(b); }
};

class SbvhBuilder {
 public:
  SbvhBuilder(std::span<const Aabb> boxes, std::span<const Vec3f> centroids, const PrimitiveSplitter& splitter,
              const SbvhOptions& o)
      : boxes_(boxes), centroids_(centroids), splitter_(splitter), opt_(o) {
    opt_.base.bins = std::clamp(opt_.base.bins, 2, sah::kMaxBins);
    opt_.base.max_leaf = std::max(1, opt_.base.max_leaf);
    opt_.spatial_bins = std::clamp(opt_.spatial_bins, 2, kMaxSpatialBins);
    opt_.split_budget = std::max(0.0f, opt_.split_budget);
  }

  BinaryBvh run(SbvhStats* stats) {
    const size_t n = boxes_.size();
    BinaryBvh out;
    if (n == 0) {
      out.nodes.resize(1);
      set_leaf(out.nodes[0], Aabb::empty(), 0, 0);
      return out;
    }
    const size_t extra = static_cast<size_t>(static_cast<double>(opt_.split_budget) * static_cast<double>(n));
    budget_.store(static_cast<int64_t>(extra));
    const size_t max_refs = n + extra;
    nodes_.resize(2 * max_refs);
    prims_.resize(max_refs);
    std::vector<BuildRef> refs = make_build_refs(boxes_, centroids_);
    Box4 bounds, cbounds;
    for (const BuildRef& r : refs) {
      bounds.extend(r.box);
      cbounds.extend(r.centroid());
    }
    root_area_ = bounds.half_area();
    build(0, std::move(refs), bounds, cbounds, 0);
    nodes_.resize(next_node_.load());
    prims_.resize(next_prim_.load());
    out.nodes = std::move(nodes_);
    out.prim_ids = std::move(prims_);
    if (stats) {
      stats->references = out.prim_ids.size();
      stats->spatial_splits = spatial_splits_.load();
    }
    return out;
  }

 private:
  void make_leaf(uint32_t node, const std::vector<BuildRef>& refs, const Box4& bounds) {
    const uint32_t first = next_prim_.fetch_add(static_cast<uint32_t>(refs.size()));
    for (size_t i = 0; i < refs.size(); ++i) prims_[first + i] = refs[i].prim();
    set_leaf(nodes_[node], bounds.aabb(), first, static_cast<uint32_t>(refs.size()));
  }

  // Clips one reference into the slabs it spans along axis a.
  void bin_spatial_ref(const BuildRef& r, const SlabGrid& g, SpatialBins& sb) const {
    const uint32_t prim = r.prim();
    for (int a = 0; a < 3; ++a) {
      if (g.inv_width[a] <= 0.0f) continue;
      const int b0 = g.bin(a, r.box.lo_at(a));
      const int b1 = g.bin(a, r.box.hi_at(a));
      sb.enter[a][b0]++;
      sb.exit[a][b1]++;
      if (b0 == b1) {
        sb.add(a, b0, r.box);
        continue;
      }
      Aabb rest = r.box.aabb();
      for (int b = b0; b < b1; ++b) {
        Aabb l, rr;
        splitter_.split(prim, rest, a, g.plane(a, b + 1), false, l, rr);
        if (!l.is_empty()) sb.add(a, b, Box4::from(l));
        rest = rr;
        if (rest.is_empty()) break;
      }
      if (!rest.is_empty()) sb.add(a, b1, Box4::from(rest));
    }
  }

  SpatialSplit find_spatial_split(const std::vector<BuildRef>& refs, const Box4& bounds) const {
    const int nb = opt_.spatial_bins;
    const SlabGrid g(bounds, nb);
    std::unique_ptr<SpatialBins> sb;
    if (refs.size() < kParallelBinSize) {
      sb = SpatialBins::make(nb);
      for (const BuildRef& r : refs) bin_spatial_ref(r, g, *sb);
    } else {
      struct Reducer {
        const SbvhBuilder* self;
        const std::vector<BuildRef>* refs;
        const SlabGrid* g;
        std::unique_ptr<SpatialBins> sb;
        Reducer(const SbvhBuilder* s, const std::vector<BuildRef>* r, const SlabGrid* gg)
            : self(s), refs(r), g(gg), sb(SpatialBins::make(gg->bins)) {}
        Reducer(Reducer& o, tbb::split) : Reducer(o.self, o.refs, o.g) {}
        void operator()(const tbb::blocked_range<size_t>& r) {
          for (size_t i = r.begin(); i < r.end(); ++i) self->bin_spatial_ref((*refs)[i], *g, *sb);
        }
        void join(const Reducer& o) { sb->merge_from(*o.sb, g->bins); }
      } red(this, &refs, &g);
      tbb::parallel_reduce(tbb::blocked_range<size_t>(0, refs.size(), 4096), red);
      sb = std::move(red.sb);
    }
    SpatialSplit best;
    static_assert(kMaxSpatialBins <= sah::kMaxBins);
    for (int a = 0; a < 3; ++a) {
      if (g.inv_width[a] <= 0.0f) continue;
      sah::sweep_bins(
          nb, best.cost, [&](int b) { return sb->box(a, b); }, [&](int b) { return sb->enter[a][b]; },
          [&](int b) { return sb->exit[a][b]; },
          [&](int b, const Box4& left, const Box4& right, uint32_t lc, uint32_t rc) {
            best.axis = a;
            best.pos = g.plane(a, b);
            best.left = left;
            best.right = right;
            best.left_count = lc;
            best.right_count = rc;
          });
    }
    return best;
  }

  // Distributes references over a spatial split plane, unsplitting
  // straddlers when sending them whole to one side is cheaper, and always
  // once max_dups references have been duplicated (the reserved budget).
  void partition_spatial(std::vector<BuildRef>& refs, const SpatialSplit& s, int64_t max_dups,
                         std::vector<BuildRef>& left, std::vector<BuildRef>& right) const {
    int64_t dups = 0;
    const int a = s.axis;
    Box4 lb = s.left, rb = s.right;
    float lc = static_cast<float>(s.left_count), rc = static_cast<float>(s.right_count);
    left.reserve(s.left_count);
    right.reserve(s.right_count);
    for (const BuildRef& r : refs) {
      const float lo = r.box.lo_at(a), hi = r.box.hi_at(a);
      if (hi <= s.pos) {
        left.push_back(r);
        continue;
      }
      if (lo >= s.pos) {
        right.push_back(r);
        continue;
      }
      const float la = lb.half_area(), ra = rb.half_area();
      const float c_split = la * lc + ra * rc;
      const float c_left = merge(lb, r.box).half_area() * lc + ra * (rc - 1.0f);
      const float c_right = la * (lc - 1.0f) + merge(rb, r.box).half_area() * rc;
      const bool may_split = dups < max_dups;
      if ((c_left < c_split || !may_split) && c_left <= c_right) {
        lb.extend(r.box);
        rc -= 1.0f;
        left.push_back(r);
        continue;
      }
      if (c_right < c_split || !may_split) {
        rb.extend(r.box);
        lc -= 1.0f;
        right.push_back(r);
        continue;
      }
      Aabb l, rr;
      splitter_.split(r.prim(), r.box.aabb(), a, s.pos, true, l, rr);
      const uint32_t prim = r.prim();
      if (!l.is_empty()) left.push_back(BuildRef::make(l, l.center(), prim));
      if (!rr.is_empty()) right.push_back(BuildRef::make(rr, rr.center(), prim));
      if (l.is_empty() && rr.is_empty()) left.push_back(r);  // cannot happen for a real crossing; keep it anyway
      dups += !l.is_empty() && !rr.is_empty();
    }
  }

  static void bounds_of(const std::vector<BuildRef>& refs, Box4& b, Box4& cb) {
    for (const BuildRef& r : refs) {
      b.extend(r.box);
      cb.extend(r.centroid());
    }
  }

  // Below min_spatial_refs no spatial split is tried: the subtree is built
  // by the binned builder and spliced in (node and reference ranges taken
  // from this tree's counters, indices shifted).
  void build_binned_subtree(uint32_t node, std::vector<BuildRef> refs, int depth) {
    BuildOptions bo = opt_.base;
    bo.start_depth = depth;
    const BinaryBvh sub = build_binned_sah(std::move(refs), bo);
    const uint32_t m = static_cast<uint32_t>(sub.nodes.size());
    const uint32_t node_base = m > 1 ? next_node_.fetch_add(m - 1) : 0;
    const uint32_t prim_base = next_prim_.fetch_add(static_cast<uint32_t>(sub.prim_ids.size()));
    std::copy(sub.prim_ids.begin(), sub.prim_ids.end(), prims_.begin() + prim_base);
    for (uint32_t k = 0; k < m; ++k) {
      Bvh2Node nd = sub.nodes[k];
      if (nd.count != 0 || nd.index == 0) nd.index += prim_base;  // leaf
      else nd.index = node_base + nd.index - 1;                   // inner: children k >= 1 move to node_base + k - 1
      nodes_[k == 0 ? node : node_base + k - 1] = nd;
    }
  }

  // Splits `refs` into two non-empty halves: the spatial split when it is
  // cheaper and the duplication budget allows it, else the object split, else
  // (identical centroids, or too deep) the object median of the widest axis.
  void partition_refs(std::vector<BuildRef>& refs, const Split& object, const SpatialSplit& spatial, const Binning* bn,
                      const float cext[4], int depth, std::vector<BuildRef>& left, std::vector<BuildRef>& right) {
    const size_t n = refs.size();
    bool done = false;
    if (depth < kForceMedianDepth && spatial.cost < object.cost) {
      // Reserve the worst-case number of duplicates from the budget.
      const int64_t dup = static_cast<int64_t>(spatial.left_count + spatial.right_count) - static_cast<int64_t>(n);
      if (budget_.fetch_sub(dup) >= dup) {
        partition_spatial(refs, spatial, dup, left, right);
        const int64_t used = static_cast<int64_t>(left.size() + right.size()) - static_cast<int64_t>(n);
        // Where no object split exists (every centroid the same: coincident
        // triangles), a spatial split that leaves every reference on both
        // sides separates nothing, and the children would be split the same
        // way until the budget is spent. Such nodes take the median split.
        // (Elsewhere such a split still shrinks the references' boxes, which
        // is what it is for: long triangles across a node.)
        const bool separates = object.axis >= 0 || left.size() < n || right.size() < n;
        done = !left.empty() && !right.empty() && separates;
        if (done) {
          budget_.fetch_add(dup - used);
          spatial_splits_.fetch_add(1, std::memory_order_relaxed);
        } else {
          budget_.fetch_add(dup);
          left.clear();
          right.clear();
        }
      } else {
        budget_.fetch_add(dup);
      }
    }
    if (!done && object.axis >= 0 && depth < kForceMedianDepth) {
      left.reserve(object.left_count);
      right.reserve(n - object.left_count);
      for (const BuildRef& r : refs) (bn->left_of(r, object.axis, object.pos) ? left : right).push_back(r);
      done = !left.empty() && !right.empty();
      if (!done) {
        left.clear();
        right.clear();
      }
    }
    if (!done) {
      // Identical centroids or too deep: object median of the widest axis.
      int axis = 0;
      if (cext[1] > cext[axis]) axis = 1;
      if (cext[2] > cext[axis]) axis = 2;
      std::nth_element(refs.begin(), refs.begin() + n / 2, refs.end(), [axis](const BuildRef& x, const BuildRef& y) {
        alignas(16) float cx[4], cy[4];
        _mm_store_ps(cx, x.centroid());
        _mm_store_ps(cy, y.centroid());
        return cx[axis] < cy[axis];
      });
      left.assign(refs.begin(), refs.begin() + n / 2);
      right.assign(refs.begin() + n / 2, refs.end());
    }
  }

  void build(uint32_t node, std::vector<BuildRef> refs, const Box4& bounds, const Box4& cbounds, int depth) {
    const size_t n = refs.size();
    if (n < opt_.min_spatial_refs && n > static_cast<size_t>(std::max(1, opt_.base.leaf_threshold)))
      return build_binned_subtree(node, std::move(refs), depth);
    if (n <= static_cast<size_t>(std::max(1, opt_.base.leaf_threshold))) return make_leaf(node, refs, bounds);

    alignas(16) float cext[4];
    _mm_store_ps(cext, _mm_sub_ps(cbounds.hi, cbounds.lo));
    const bool flat = !(cext[0] > 0.0f || cext[1] > 0.0f || cext[2] > 0.0f);
    const float area = bounds.half_area();

    Split object;
    std::unique_ptr<Binning> bn;
    if (!flat) {
      bn = std::make_unique<Binning>(cbounds, opt_.base.bins);
      const auto bins = sah::bin_refs(refs.data(), 0, n, *bn, opt_.base.bins);
      object = sah::find_binned_split(*bins, *bn, opt_.base.bins);
    }
    SpatialSplit spatial;
    if (depth < kForceMedianDepth && n >= opt_.min_spatial_refs && budget_.load(std::memory_order_relaxed) > 0 &&
        root_area_ > 0.0f) {
      float overlap = 0.0f;
      if (object.axis >= 0) {
        Box4 inter;
        inter.lo = _mm_max_ps(object.left.lo, object.right.lo);
        inter.hi = _mm_min_ps(object.left.hi, object.right.hi);
        overlap = inter.half_area();
      }
      if (object.axis < 0 || overlap / root_area_ > opt_.alpha) spatial = find_spatial_split(refs, bounds);
    }
    const float best_cost = std::min(object.cost, spatial.cost);
    const float split_cost =
        opt_.base.traversal_cost + opt_.base.intersection_cost * (area > 0.0f ? best_cost / area : 0.0f);
    if (n <= static_cast<size_t>(opt_.base.max_leaf) &&
        (!std::isfinite(best_cost) || opt_.base.intersection_cost * static_cast<float>(n) <= split_cost))
      return make_leaf(node, refs, bounds);

    std::vector<BuildRef> left, right;
    partition_refs(refs, object, spatial, bn.get(), cext, depth, left, right);
    std::vector<BuildRef>().swap(refs);
    Box4 lb, lcb, rb, rcb;
    bounds_of(left, lb, lcb);
    bounds_of(right, rb, rcb);

    const uint32_t child = next_node_.fetch_add(2);
    Bvh2Node& nd = nodes_[node];
    nd.set_bounds(bounds.aabb());
    nd.index = child;
    nd.count = 0;
    if (n >= kParallelTaskSize) {
      tbb::parallel_invoke([&] { build(child, std::move(left), lb, lcb, depth + 1); },
                           [&] { build(child + 1, std::move(right), rb, rcb, depth + 1); });
    } else {
      build(child, std::move(left), lb, lcb, depth + 1);
      build(child + 1, std::move(right), rb, rcb, depth + 1);
    }
  }

  std::span<const Aabb> boxes_;
  std::span<const Vec3f> centroids_;
  const PrimitiveSplitter& splitter_;
  SbvhOptions opt_;
  UninitHugePageVector<Bvh2Node> nodes_;
  std::vector<uint32_t> prims_;
  float root_area_ = 0.0f;
  std::atomic<int64_t> budget_{0};
  std::atomic<uint32_t> next_node_{1};
  std::atomic<uint32_t> next_prim_{0};
  std::atomic<size_t> spatial_splits_{0};
};

}  // namespace

BinaryBvh build_sbvh(std::span<const Aabb> boxes, std::span<const Vec3f> centroids, const PrimitiveSplitter& splitter,
                     const SbvhOptions& options, SbvhStats* stats) {
  return SbvhBuilder(boxes, centroids, splitter, options).run(stats);
}

}  // namespace raylab
