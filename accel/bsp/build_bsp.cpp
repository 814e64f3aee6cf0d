#include "accel/bsp/build_bsp.h"

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

#include <fmt/format.h>

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>
#include <tbb/task_arena.h>

#include "accel/bsp/convex_polytope.h"
#include "accel/core/sah_report.h"
#include "accel/core/clip_triangle.h"  // kd_detail::next_down / next_up

namespace raylab {

namespace {

constexpr uint32_t kKindKdop = 5;  // a fixed non-axis direction (stored as kBspFixed)
constexpr uint32_t kKindTriangle = 6;  // build-time only: a triangle's plane (stored as general)

// Candidates whose SAH cost is estimated (not on an axis of a box region)
// get exact polytope areas only if they are among the cheapest this many.
constexpr size_t kExactlyPricedCandidates = 4;
// Nodes from which the two subtrees are built as parallel tasks.
constexpr size_t kParallelTaskSize = 1024;
// Nodes whose event lists are split direction by direction in parallel.
constexpr size_t kParallelEventSplit = 65536;

struct TmpNode {
  uint32_t kind = kBspLeaf;
  uint32_t direction = 0;  // kKindKdop: index in bsp_fixed_directions()
  Vec3f n = Vec3f::Zero();
  float d = 0;
  double area = 0;
  std::unique_ptr<TmpNode> child[2];
  std::vector<uint32_t> ids;  // leaves
};

struct Candidate {
  double cost = std::numeric_limits<double>::infinity();
  uint32_t kind = kBspLeaf;
  Vec3f n = Vec3f::Zero();
  float d = 0;
  size_t nl = 0, nr = 0;
  uint32_t direction = 0;  // kKindKdop: index in bsp_fixed_directions()
  // References lying in the plane go above it (else below). Both sides are
  // priced, as in the k-d tree (Wald & Havran 2006): a floor's triangles
  // belong with the room above it, a ceiling's with the room below.
  bool planar_above = false;
};

// The node's triangle references, each with the part of its triangle that
// lies in the node's region (the triangle clipped by the planes above it,
// Sutherland-Hodgman), so counts and assignments see only what is really in
// the region (the BSP form of the k-d tree's perfect splits).
struct RefSet {
  std::vector<uint32_t> ids;
  std::vector<uint32_t> start{0};  // polygon i = pts[start[i] .. start[i + 1])
  std::vector<Vec3d> pts;

  size_t size() const { return ids.size(); }
  void add(uint32_t id, const Vec3d* p, size_t k) {
    ids.push_back(id);
    pts.insert(pts.end(), p, p + k);
    start.push_back(static_cast<uint32_t>(pts.size()));
  }
};

// A node's region: a box while every plane above it is axis-aligned (then
// the k-d tree's closed-form SAH areas are exact), a general convex polytope
// below the first slanted plane.
struct Region {
  bool is_box = true;
  Vec3d lo = Vec3d::Zero(), hi = Vec3d::Zero();
  ConvexPolytope poly;  // when !is_box

  double area() const {
    if (!is_box) return poly.surface_area();
    const Vec3d e = hi - lo;
    return 2.0 * (e.x() * e.y() + e.y() * e.z() + e.z() * e.x());
  }
  ConvexPolytope polytope() const { return is_box ? ConvexPolytope::box(lo, hi) : poly; }
  // Exact areas of the parts below and above n . x = d.
  std::pair<double, double> split_areas(const Vec3d& n, double d) const {
    return is_box ? ConvexPolytope::box(lo, hi).split_areas(n, d) : poly.split_areas(n, d);
  }
  std::pair<Region, Region> split(uint32_t kind, const Vec3f& n, float d) const {
    std::pair<Region, Region> out;
    if (is_box && kind <= 2) {
      out.first = out.second = *this;
      out.first.hi[kind] = d;
      out.second.lo[kind] = d;
      return out;
    }
    auto parts = polytope().split(n.cast<double>(), static_cast<double>(d));
    out.first.is_box = out.second.is_box = false;
    out.first.poly = std::move(parts.first);
    out.second.poly = std::move(parts.second);
    return out;
  }
  // Vertices whose projections bound the region along any direction.
  void corners(std::vector<Vec3d>& out) const {
    out.clear();
    if (is_box) {
      for (int i = 0; i < 8; ++i)
        out.emplace_back(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z());
      return;
    }
    for (const auto& f : poly.faces) out.insert(out.end(), f.begin(), f.end());
  }
};

// Rounds a double to a float no larger (down) or no smaller (up) than it.
inline float float_down(double x) {
  const float f = static_cast<float>(x);
  return static_cast<double>(f) > x ? kd_detail::next_down(f) : f;
}
inline float float_up(double x) {
  const float f = static_cast<float>(x);
  return static_cast<double>(f) < x ? kd_detail::next_up(f) : f;
}

// A plane direction u with two unit vectors v, w orthogonal to it and each
// other: the region's extents along the three give the box in that frame
// whose closed-form areas estimate the child areas (exact for a box region
// and an axis direction).
struct Frame {
  Vec3d u, v, w;
};

Frame frame_of(const Vec3d& u) {
  const Vec3d helper = std::fabs(u.x()) < 0.9 ? Vec3d::UnitX() : Vec3d::UnitY();
  const Vec3d v = helper.cross(u).normalized();
  return Frame{u, v, u.cross(v)};
}

// Estimated fractions of the node's area below and above u . x = p, from
// the region's box in the plane's frame (the k-d tree's SAH formula).
struct AreaEstimate {
  double lo = 0, hi = 0, cross = 0, perimeter = 0, inv_total = 0;

  AreaEstimate(const std::vector<Vec3d>& corners, const Frame& f) {
    double vlo = std::numeric_limits<double>::infinity(), vhi = -vlo, wlo = vlo, whi = -vlo;
    lo = vlo, hi = -vlo;
    for (const Vec3d& c : corners) {
      const double su = f.u.dot(c), sv = f.v.dot(c), sw = f.w.dot(c);
      lo = std::min(lo, su), hi = std::max(hi, su);
      vlo = std::min(vlo, sv), vhi = std::max(vhi, sv);
      wlo = std::min(wlo, sw), whi = std::max(whi, sw);
    }
    const double dv = vhi - vlo, dw = whi - wlo;
    cross = dv * dw;
    perimeter = dv + dw;
    const double total = cross + (hi - lo) * perimeter;
    inv_total = total > 0 ? 1.0 / total : 0.0;
  }
  double below(double p) const { return (cross + (p - lo) * perimeter) * inv_total; }
  // Whether a plane at float position p cuts the region. The region's
  // extent is rounded inward to float first: vertices made by an earlier
  // plane lie on it only up to double rounding, and without this the same
  // float plane could cut off a sliver of empty space again and again (each
  // time earning the empty-space bonus) until the depth limit.
  bool cuts(float p) const { return p > float_up(lo) && p < float_down(hi); }
  double above(double p) const { return (cross + (hi - p) * perimeter) * inv_total; }
};

// Sweep events along one direction, in the k-d tree's order at equal
// positions (Wald & Havran 2006): ends, then planar, then starts. An event
// is one integer: the float's bits mapped to an order-preserving unsigned
// key (upper 32 bits), the type (2 bits), and the index of its reference in
// the node's RefSet (30 bits), so sorting compares integers.
constexpr uint32_t kEnd = 0, kPlanar = 1, kStart = 2;
constexpr int kRefBits = 30;
constexpr uint64_t kRefMask = (uint64_t{1} << kRefBits) - 1;
inline uint64_t make_event(float pos, uint32_t type, uint32_t ref) {
  const uint32_t b = std::bit_cast<uint32_t>(pos == 0.0f ? 0.0f : pos);  // -0 sorts as +0
  const uint32_t key = (b & 0x80000000u) ? ~b : (b | 0x80000000u);
  return (static_cast<uint64_t>(key) << 32) | (static_cast<uint64_t>(type) << kRefBits) | ref;
}
inline uint64_t event_group(uint64_t e) { return e >> 32; }  // events at one position
inline float event_pos(uint64_t e) {
  const uint32_t key = static_cast<uint32_t>(e >> 32);
  return std::bit_cast<float>((key & 0x80000000u) ? (key & 0x7fffffffu) : ~key);
}
inline uint32_t event_type(uint64_t e) { return static_cast<uint32_t>(e >> kRefBits) & 3u; }
inline uint32_t event_ref(uint64_t e) { return static_cast<uint32_t>(e & kRefMask); }

// A reference's events along one direction, from its projected extent
// rounded outward to float, so that a plane at an event's position has the
// reference exactly on the side the sweep counts it.
inline void push_extent_events(std::vector<uint64_t>& ev, double lo, double hi, uint32_t ref) {
  const float flo = float_down(lo), fhi = float_up(hi);
  if (flo == fhi) {
    ev.push_back(make_event(flo, kPlanar, ref));
  } else {
    ev.push_back(make_event(flo, kStart, ref));
    ev.push_back(make_event(fhi, kEnd, ref));
  }
}

// The sorted events of a node's references along each fixed direction (the
// first `directions` are used). Computed and sorted once at the root, then
// split in order between the children, as the k-d tree's builder does with
// its three axes (Wald & Havran 2006): only references cut by a plane get
// new events, sorted and merged in, so no node sorts all its events and the
// build is O(N log N) for a tree of bounded straddling.
using EventLists = std::array<std::vector<uint64_t>, 13>;

// Per-thread working memory of find_split (no task switch happens inside).
struct Scratch {
  std::vector<double> lo_s, hi_s;  // per direction and reference: projected extent
  std::vector<uint32_t> hist_min, hist_max;
  std::vector<Vec3d> corners;
};

// Per-thread working memory of partition.
struct PartitionScratch {
  std::vector<uint8_t> side;
  std::vector<uint32_t> new_index;
  EventLists fresh_left, fresh_right;
};

// Clipped polygons longer than this keep their parent's polygon (unclipped,
// conservative); a triangle in a convex region rarely has more than 8.
constexpr size_t kMaxClippedVertices = 24;

class Builder {
 public:
  Builder(const TriangleMesh& mesh, const BspBuildOptions& opt) : opt_(opt) {
    v_.resize(mesh.num_triangles());
    double mag = 0;
    for (size_t i = 0; i < v_.size(); ++i)
      for (int k = 0; k < 3; ++k) {
        v_[i][k] = mesh.vertex(i, k).cast<double>();
        mag = std::max(mag, v_[i][k].cwiseAbs().maxCoeff());
      }
    tol_ = 1e-12 * mag;
    const Vec3f* dirs = bsp_fixed_directions();
    for (int i = 0; i < 13; ++i) {
      const Vec3d u = dirs[i].cast<double>();
      frames_[i] = i < 3 ? Frame{u, Vec3d::Unit((i + 1) % 3), Vec3d::Unit((i + 2) % 3)} : frame_of(u);
    }
  }

  RefSet root_refs() const {
    RefSet r;
    r.ids.reserve(v_.size());
    r.pts.reserve(3 * v_.size());
    for (size_t i = 0; i < v_.size(); ++i) r.add(static_cast<uint32_t>(i), v_[i].data(), 3);
    return r;
  }

  // The root's sorted event lists (none with `bins`: the binned search
  // projects each node's references instead).
  EventLists root_events(const RefSet& refs) const {
    EventLists ev;
    if (!sweeps()) return ev;
    for (int di = 0; di < opt_.directions; ++di) ev[di].reserve(2 * refs.size());
    for (size_t i = 0; i < refs.size(); ++i) add_ref_events(refs, i, static_cast<uint32_t>(i), ev);
    tbb::parallel_for(0, opt_.directions, [&](int di) { tbb::parallel_sort(ev[di].begin(), ev[di].end()); });
    return ev;
  }

  std::unique_ptr<TmpNode> build(RefSet refs, EventLists ev, Region region, int depth) const {
    auto node = std::make_unique<TmpNode>();
    node->area = region.area();
    const size_t n = refs.size();
    // Wald & Havran's termination: a leaf when no split is cheaper than
    // testing every triangle, at the depth limit, or in a region without area.
    const double leaf_cost = opt_.intersection_cost * static_cast<double>(n);
    Candidate best;
    if (n > 0 && depth < depth_limit_ && node->area > 0) best = find_split(refs, ev, region, node->area, leaf_cost);
    if (!(best.cost < leaf_cost)) {
      node->ids = std::move(refs.ids);
      return node;
    }
    RefSet left, right;
    EventLists left_ev, right_ev;
    partition(refs, ev, best, left, right, left_ev, right_ev);
    if (left.size() == n && right.size() == n) {  // no progress (cannot happen with a counted candidate)
      node->ids = std::move(refs.ids);
      return node;
    }
    refs = RefSet{};
    ev = EventLists{};
    node->kind = best.kind;
    node->direction = best.direction;
    node->n = best.n;
    node->d = best.d;
    auto parts = region.split(best.kind, best.n, best.d);
    region = Region{};
    if (n >= kParallelTaskSize) {
      tbb::parallel_invoke(
          [&] { node->child[0] = build(std::move(left), std::move(left_ev), std::move(parts.first), depth + 1); },
          [&] { node->child[1] = build(std::move(right), std::move(right_ev), std::move(parts.second), depth + 1); });
    } else {
      node->child[0] = build(std::move(left), std::move(left_ev), std::move(parts.first), depth + 1);
      node->child[1] = build(std::move(right), std::move(right_ev), std::move(parts.second), depth + 1);
    }
    return node;
  }

  int depth_limit_ = 0;

 private:
  void side_range(const RefSet& r, size_t i, const Vec3d& n, double d, double& smin, double& smax) const {
    smin = std::numeric_limits<double>::infinity();
    smax = -smin;
    for (uint32_t k = r.start[i]; k < r.start[i + 1]; ++k) {
      const double s = n.dot(r.pts[k]) - d;
      smin = std::min(smin, s);
      smax = std::max(smax, s);
    }
  }
  // Exact side rule (see build_bsp.h), on the clipped polygon: below when it
  // reaches below the plane, above when it reaches above; one lying in the
  // plane goes to the side the split chose (Candidate::planar_above).
  bool lies_in(double smin, double smax) const { return smin >= -tol_ && smax <= tol_; }
  bool goes_below(double smin, double smax, bool planar_above) const {
    return smin < -tol_ || (!planar_above && lies_in(smin, smax));
  }
  bool goes_above(double smin, double smax, bool planar_above) const {
    return smax > tol_ || (planar_above && lies_in(smin, smax));
  }

  // Splits the references by the plane (a straddling one gets its part on
  // each side) and, when sweeping, the event lists (see EventLists): events
  // of references kept whole are copied in order with their new indices
  // (which grow in the parent's order, so the order is kept), and the parts
  // of straddling references get fresh events, sorted and merged in.
  void partition(const RefSet& refs, const EventLists& ev, const Candidate& split, RefSet& left, RefSet& right,
                 EventLists& left_ev, EventLists& right_ev) const {
    const Vec3d n = split.n.cast<double>();
    const double d = split.d;
    Vec3d below[kMaxClippedVertices], above[kMaxClippedVertices];
    // Per reference: the side it goes to whole (kBoth: cut) and its index
    // there. Per-thread working memory: no task switch happens in here (the
    // parallel split below is isolated).
    constexpr uint8_t kBoth = 0, kLeftOnly = 1, kRightOnly = 2;
    static thread_local PartitionScratch sc;
    std::vector<uint8_t>& side = sc.side;
    std::vector<uint32_t>& new_index = sc.new_index;
    EventLists& fresh_left = sc.fresh_left;
    EventLists& fresh_right = sc.fresh_right;
    side.resize(refs.size());
    new_index.resize(refs.size());
    for (int di = 0; di < opt_.directions; ++di) fresh_left[di].clear(), fresh_right[di].clear();
    for (size_t i = 0; i < refs.size(); ++i) {
      double smin, smax;
      side_range(refs, i, n, d, smin, smax);
      const uint32_t id = refs.ids[i];
      const Vec3d* p = refs.pts.data() + refs.start[i];
      const size_t k = refs.start[i + 1] - refs.start[i];
      const bool b = goes_below(smin, smax, split.planar_above), a = goes_above(smin, smax, split.planar_above);
      if (b && !a) {
        side[i] = kLeftOnly, new_index[i] = static_cast<uint32_t>(left.size());
        left.add(id, p, k);
      } else if (a && !b) {
        side[i] = kRightOnly, new_index[i] = static_cast<uint32_t>(right.size());
        right.add(id, p, k);
      } else {
        side[i] = kBoth;
        // Straddles: each side gets its part (vertices within tol count as on the plane).
        size_t nb = 0, na = 0;
        bool overflow = false;
        for (size_t j = 0; j < k && !overflow; ++j) {
          const Vec3d& u = p[j];
          const Vec3d& w = p[(j + 1) % k];
          const double su = n.dot(u) - d, sw = n.dot(w) - d;
          const bool u_on = std::fabs(su) <= tol_;
          if (nb + 2 > kMaxClippedVertices || na + 2 > kMaxClippedVertices) overflow = true;
          if (overflow) break;
          if (su <= tol_) below[nb++] = u;
          if (su >= -tol_) above[na++] = u;
          if (!u_on && std::fabs(sw) > tol_ && ((su < 0) != (sw < 0))) {
            const Vec3d x = u + (su / (su - sw)) * (w - u);
            below[nb++] = x;
            above[na++] = x;
          }
        }
        if (overflow || nb == 0 || na == 0) {
          left.add(id, p, k);
          right.add(id, p, k);
        } else {
          left.add(id, below, nb);
          right.add(id, above, na);
        }
        if (sweeps()) {
          add_ref_events(left, left.size() - 1, static_cast<uint32_t>(left.size() - 1), fresh_left);
          add_ref_events(right, right.size() - 1, static_cast<uint32_t>(right.size() - 1), fresh_right);
        }
      }
    }
    if (!sweeps()) return;
    auto split_direction = [&](int di) {
      std::vector<uint64_t>& l = left_ev[di];
      std::vector<uint64_t>& r = right_ev[di];
      l.reserve(2 * left.size());  // at most two events per reference
      r.reserve(2 * right.size());
      for (const uint64_t e : ev[di]) {
        const uint32_t ref = event_ref(e);
        const uint64_t renamed = (e & ~kRefMask) | new_index[ref];
        if (side[ref] == kLeftOnly) l.push_back(renamed);
        else if (side[ref] == kRightOnly) r.push_back(renamed);
      }
      for (auto [dst, fresh] : {std::pair{&l, &fresh_left[di]}, std::pair{&r, &fresh_right[di]}}) {
        std::sort(fresh->begin(), fresh->end());
        const auto mid = static_cast<std::ptrdiff_t>(dst->size());
        dst->insert(dst->end(), fresh->begin(), fresh->end());
        std::inplace_merge(dst->begin(), dst->begin() + mid, dst->end());
      }
    };
    if (refs.size() >= kParallelEventSplit) {
      tbb::this_task_arena::isolate([&] { tbb::parallel_for(0, opt_.directions, split_direction); });
    } else {
      for (int di = 0; di < opt_.directions; ++di) split_direction(di);
    }
  }

  bool sweeps() const { return opt_.bins < 2; }

  // Projected extent of a polygon along the first `dirs` fixed directions.
  void extents(const Vec3d* p, size_t k, int dirs, double* lo, double* hi) const {
    std::fill(lo, lo + dirs, std::numeric_limits<double>::infinity());
    std::fill(hi, hi + dirs, -std::numeric_limits<double>::infinity());
    for (size_t j = 0; j < k; ++j)
      for (int di = 0; di < dirs; ++di) {
        const double x = frames_[di].u.dot(p[j]);
        lo[di] = std::min(lo[di], x);
        hi[di] = std::max(hi[di], x);
      }
  }

  // The events of reference i of `refs` (named `ref` in them) along every direction swept.
  void add_ref_events(const RefSet& refs, size_t i, uint32_t ref, EventLists& ev) const {
    double lo[13], hi[13];
    extents(refs.pts.data() + refs.start[i], refs.start[i + 1] - refs.start[i], opt_.directions, lo, hi);
    for (int di = 0; di < opt_.directions; ++di) push_extent_events(ev[di], lo[di], hi[di], ref);
  }

  // The candidates of one node: the best exactly priced one so far (axis
  // planes of a box region, and re-priced estimates) and the cheapest few
  // estimated ones, which get exact polytope areas at the end.
  struct Search {
    Candidate exact;
    std::array<Candidate, kExactlyPricedCandidates> estimated;
    size_t num_estimated = 0;
    size_t n = 0;
    double ct = 0, lambda_empty = 0;
    std::array<Candidate, kExactlyPricedCandidates>::iterator est_end() { return estimated.begin() + num_estimated; }
  };

  // The empty-space bonus (Wald & Havran's lambda) applies to axis planes
  // only. On slanted planes it made the builder shave empty corners off the
  // regions of box-like interiors level after level (each cut is rewarded
  // 20% however little it removes), using up the depth limit: on sponza the
  // tree's SAH cost was 91 with it and 79 without (k-d tree: 75), the
  // random rays' speed 0.34 and 0.40 x Embree.
  static double empty_lambda(const Search& s, uint32_t kind, size_t nl, size_t nr) {
    return (kind <= 2 && (nl == 0 || nr == 0)) ? s.lambda_empty : 1.0;
  }

  // Prices plane c (its cost field unset) with area fractions (pl, pr) and
  // keeps it if it can win.
  void offer(Search& s, bool is_exact, Candidate c, double pl, double pr) const {
    const size_t nl = c.nl, nr = c.nr;
    if (nl == s.n && nr == s.n) return;  // reduces neither side
    // More than half of the references straddling: the k-d tree's guard
    // against reference blow-up (see accel/kdtree/build_sah_events.cpp).
    if (2 * (nl + nr) > 3 * s.n + 2) return;
    const double lambda = empty_lambda(s, c.kind, nl, nr);
    // Lower bound with exact areas (al + ar >= area): skip hopeless planes.
    const double ci = opt_.intersection_cost;
    if (lambda * (s.ct + ci * static_cast<double>(std::min(nl, nr))) >= s.exact.cost) return;
    const double cost = lambda * (s.ct + ci * (pl * static_cast<double>(nl) + pr * static_cast<double>(nr)));
    c.cost = cost;
    if (is_exact) {
      if (cost < s.exact.cost) s.exact = c;
      return;
    }
    // Insertion into the short list, kept sorted by cost.
    size_t i = s.num_estimated;
    if (i < kExactlyPricedCandidates) {
      ++s.num_estimated;
    } else {
      i = kExactlyPricedCandidates - 1;  // replaces the dearest, if cheaper
      if (!(cost < s.estimated[i].cost)) return;
    }
    for (; i > 0 && cost < s.estimated[i - 1].cost; --i) s.estimated[i] = s.estimated[i - 1];
    s.estimated[i] = c;
  }

  // Projected extents of every reference along the first `dirs` fixed
  // directions (the binned search's input): sc.lo_s[di * n + i], sc.hi_s[di * n + i].
  void project(Scratch& sc, const RefSet& refs, int dirs) const {
    const size_t n = refs.size();
    sc.lo_s.resize(dirs * n);
    sc.hi_s.resize(dirs * n);
    for (size_t i = 0; i < n; ++i) {
      double lo[13], hi[13];
      extents(refs.pts.data() + refs.start[i], refs.start[i + 1] - refs.start[i], dirs, lo, hi);
      for (int di = 0; di < dirs; ++di) sc.lo_s[di * n + i] = lo[di], sc.hi_s[di * n + i] = hi[di];
    }
  }

  // Exact sweep over one direction's sorted events (Wald & Havran 2006):
  // every position is priced with the references lying in the plane below
  // and above it. Planes strictly inside the region cut it; a plane on the
  // region's boundary is offered only to make a flat cell of the references
  // lying there (the k-d tree's rule), in box regions where its area is exact.
  void sweep_direction(Search& s, const std::vector<uint64_t>& ev, size_t n, int di, const AreaEstimate& est,
                       bool is_exact) const {
    const Vec3f uf = bsp_fixed_directions()[di];
    const uint32_t kind = di < 3 ? static_cast<uint32_t>(di) : kKindKdop;
    size_t nl = 0, nr = n;
    for (size_t i = 0; i < ev.size();) {
      const uint64_t group = event_group(ev[i]);
      const float p = event_pos(ev[i]);
      size_t count[3] = {0, 0, 0};
      for (; i < ev.size() && event_group(ev[i]) == group; ++i) ++count[event_type(ev[i])];
      const size_t planar = count[kPlanar];
      nr -= planar + count[kEnd];
      const Candidate below{
          .kind = kind, .n = uf, .d = p, .nl = nl + planar, .nr = nr, .direction = static_cast<uint32_t>(di)};
      Candidate above = below;
      above.nl = nl, above.nr = nr + planar, above.planar_above = true;
      const double pl = est.below(p), pr = est.above(p);
      if (est.cuts(p)) {
        offer(s, is_exact, below, pl, pr);
        if (planar > 0) offer(s, is_exact, above, pl, pr);
      } else if (is_exact && planar > 0) {
        if (static_cast<double>(p) == est.lo) offer(s, true, below, pl, pr);
        if (static_cast<double>(p) == est.hi) offer(s, true, above, pl, pr);
      }
      nl += planar + count[kStart];
    }
  }

  // The old binned search (`bins` >= 2): bins - 1 planes over the extent.
  void bin_direction(Search& s, Scratch& sc, size_t n, int di, const AreaEstimate& est, bool is_exact) const {
    const Vec3f uf = bsp_fixed_directions()[di];
    const uint32_t kind = di < 3 ? static_cast<uint32_t>(di) : kKindKdop;
    const int bins = opt_.bins;
    const double* lo_s = sc.lo_s.data() + di * n;
    const double* hi_s = sc.hi_s.data() + di * n;
    double tri_lo = std::numeric_limits<double>::infinity(), tri_hi = -tri_lo;
    for (size_t i = 0; i < n; ++i) {
      tri_lo = std::min(tri_lo, lo_s[i]);
      tri_hi = std::max(tri_hi, hi_s[i]);
    }
    const double lo = std::max(est.lo, tri_lo), hi = std::min(est.hi, tri_hi);
    if (!(hi > lo)) return;
    sc.hist_min.assign(bins, 0u);
    sc.hist_max.assign(bins, 0u);
    const double scale = bins / (hi - lo);
    auto bin_of = [&](double x) { return std::clamp(static_cast<int>((x - lo) * scale), 0, bins - 1); };
    for (size_t i = 0; i < n; ++i) {
      sc.hist_min[bin_of(lo_s[i])]++;
      sc.hist_max[bin_of(hi_s[i])]++;
    }
    size_t below = 0, above = n;
    for (int b = 1; b < bins; ++b) {
      below += sc.hist_min[b - 1];
      above -= sc.hist_max[b - 1];
      const float p = static_cast<float>(lo + (hi - lo) * b / bins);
      if (!est.cuts(p)) continue;
      const Candidate c{.kind = kind, .n = uf, .d = p, .nl = below, .nr = above, .direction = static_cast<uint32_t>(di)};
      offer(s, is_exact, c, est.below(p), est.above(p));
    }
  }

  // Planes of up to `triangle_planes` of the node's triangles (evenly spaced
  // in its list), counted exactly.
  void triangle_planes(Search& s, Scratch& sc, const RefSet& refs) const {
    const size_t n = refs.size();
    const size_t tries = std::min<size_t>(static_cast<size_t>(std::max(0, opt_.triangle_planes)), n);
    for (size_t k = 0; k < tries; ++k) {
      const uint32_t id = refs.ids[k * n / tries];
      const Vec3d nd = (v_[id][1] - v_[id][0]).cross(v_[id][2] - v_[id][0]);
      if (!(nd.squaredNorm() > 0) || !std::isfinite(nd.squaredNorm())) continue;
      const Vec3f nf = nd.normalized().cast<float>();
      const float df = static_cast<float>(nf.cast<double>().dot(v_[id][0]));
      const Vec3d nn = nf.cast<double>();
      const AreaEstimate est(sc.corners, frame_of(nn));
      if (!est.cuts(df)) continue;
      size_t nl = 0, nr = 0, planar = 0;
      for (size_t j = 0; j < n; ++j) {
        double smin, smax;
        side_range(refs, j, nn, df, smin, smax);
        planar += lies_in(smin, smax);
        nl += smin < -tol_;
        nr += smax > tol_;
      }
      const Candidate below{.kind = kKindTriangle, .n = nf, .d = df, .nl = nl + planar, .nr = nr};
      offer(s, false, below, est.below(df), est.above(df));
      if (planar > 0) {
        Candidate above = below;
        above.nl = nl, above.nr = nr + planar, above.planar_above = true;
        offer(s, false, above, est.below(df), est.above(df));
      }
    }
  }

  // The cheapest candidate, if any is cheaper than `leaf_cost`. Every
  // candidate is first priced with the areas of the region's box in the
  // plane's frame (exact for axis planes of a box region, as in the k-d
  // tree); the cheapest estimated ones are then priced with the exact areas
  // of the two child polytopes (Ize et al.'s SAH), one clip each.
  Candidate find_split(const RefSet& refs, const EventLists& ev, const Region& region, double area,
                       double leaf_cost) const {
    static thread_local Scratch sc;
    Search s;
    s.exact.cost = leaf_cost;
    s.n = refs.size();
    s.ct = opt_.traversal_cost;
    s.lambda_empty = 1.0 - static_cast<double>(opt_.empty_bonus);
    region.corners(sc.corners);
    if (!sweeps()) project(sc, refs, opt_.directions);
    // The 26-DOP diagonals are swept only where the region is no longer a
    // box, unless asked for (`diagonals_in_boxes`). In a box region a
    // diagonal competes with axis planes whose children stay boxes, and the
    // greedy cost, which prices both children as leaves, does not see what
    // the slanted face costs the subtree below: dragon_in_sponza's root went
    // to the diagonal x - y = -0.15 (2.85e6 against the best axis plane's
    // 3.04e6, both dominated by where the dragon's 202k triangles go), which
    // isolates the dragon in two cuts but slices the atrium's axis-aligned
    // architecture, and every region of the atrium below it is a polytope:
    // the tree's SAH cost was 143.5 with diagonals in box regions, 120.3
    // without (the axes alone: 116.9; docs/structures/bsp.md). Below a triangle
    // plane the region is a polytope already, and diagonals can follow it.
    const int swept = region.is_box && !opt_.diagonals_in_boxes ? std::min(opt_.directions, 3) : opt_.directions;
    for (int di = 0; di < swept; ++di) {
      const AreaEstimate est(sc.corners, frames_[di]);
      if (!(est.hi > est.lo)) continue;  // flat along this direction
      const bool is_exact = region.is_box && di < 3;
      if (sweeps()) sweep_direction(s, ev[di], s.n, di, est, is_exact);
      else bin_direction(s, sc, s.n, di, est, is_exact);
    }
    triangle_planes(s, sc, refs);
    const double ci = opt_.intersection_cost;
    for (auto it = s.estimated.begin(); it != s.est_end(); ++it) {
      const Candidate& c = *it;
      const double lambda = empty_lambda(s, c.kind, c.nl, c.nr);
      if (lambda * (s.ct + ci * static_cast<double>(std::min(c.nl, c.nr))) >= s.exact.cost) continue;
      const auto [al, ar] = region.split_areas(c.n.cast<double>(), static_cast<double>(c.d));
      const double cost =
          lambda * (s.ct + ci * (al * static_cast<double>(c.nl) + ar * static_cast<double>(c.nr)) / area);
      if (cost < s.exact.cost) s.exact = c, s.exact.cost = cost;
    }
    return s.exact;
  }

  BspBuildOptions opt_;
  std::vector<std::array<Vec3d, 3>> v_;
  std::array<Frame, 13> frames_;
  double tol_ = 0;
};
// Depth-first flattening into child pairs; gathers the statistics.
void flatten(const TmpNode& t, uint32_t at, int depth, BspTree& out, BspBuildStats& s, double root_area) {
  s.max_depth = std::max(s.max_depth, depth);
  if (t.kind == kBspLeaf) {
    out.nodes[at] = BspNode::leaf(static_cast<uint32_t>(out.prim_ids.size()), static_cast<uint32_t>(t.ids.size()));
    out.prim_ids.insert(out.prim_ids.end(), t.ids.begin(), t.ids.end());
    s.leaves++;
    s.empty_leaves += t.ids.empty();
    s.references += t.ids.size();
    s.max_leaf = std::max(s.max_leaf, t.ids.size());
    s.leaf_depth_sum += depth;
    s.sah_cost += kSahReportIntersectionCost * t.area * static_cast<double>(t.ids.size()) / root_area;
    return;
  }
  s.sah_cost += kSahReportTraversalCost * t.area / root_area;
  const uint32_t pair = static_cast<uint32_t>(out.nodes.size());
  out.nodes.resize(out.nodes.size() + 2);
  const uint32_t stored = t.kind <= 2 ? t.kind : t.kind == kKindKdop ? kBspFixed : kBspGeneral;
  s.axis_nodes += t.kind <= 2;
  s.kdop_nodes += t.kind == kKindKdop;
  s.triangle_plane_nodes += t.kind == kKindTriangle;
  const float normal[3] = {t.n.x(), t.n.y(), t.n.z()};
  out.nodes[at] = BspNode::inner(stored, normal, t.d, pair, stored == kBspFixed ? t.direction : 0);
  flatten(*t.child[0], pair, depth + 1, out, s, root_area);
  flatten(*t.child[1], pair + 1, depth + 1, out, s, root_area);
}

}  // namespace

const Vec3f* bsp_fixed_directions() {
  // The axes, then the 26-DOP's body diagonals and face diagonals.
  static const std::array<Vec3f, 13> table = [] {
    std::array<Vec3f, 13> d;
    d[0] = Vec3f::UnitX(), d[1] = Vec3f::UnitY(), d[2] = Vec3f::UnitZ();
    const Vec3d diag[10] = {{1, 1, 1}, {1, 1, -1}, {1, -1, 1}, {-1, 1, 1}, {1, 1, 0},
                            {1, -1, 0}, {1, 0, 1}, {1, 0, -1}, {0, 1, 1}, {0, 1, -1}};
    for (int i = 0; i < 10; ++i) d[3 + i] = diag[i].normalized().cast<float>();
    return d;
  }();
  return table.data();
}

BspTree build_bsp(const TriangleMesh& mesh, const BspBuildOptions& options, BspBuildStats* stats) {
  BspTree out;
  BspBuildStats s;
  out.bounds = mesh.bounds();
  const size_t n = mesh.num_triangles();
  Builder b(mesh, options);
  const int auto_depth = static_cast<int>(std::lround(8.0 + 1.3 * std::log2(static_cast<double>(std::max<size_t>(n, 1)))));
  b.depth_limit_ = std::min(kBspMaxDepthLimit, options.max_depth < 0 ? auto_depth : options.max_depth);
  s.depth_limit = b.depth_limit_;
  Region root;  // an empty mesh: a point (area 0, one leaf)
  if (n > 0) root.lo = out.bounds.lo.cast<double>(), root.hi = out.bounds.hi.cast<double>();
  // A flat scene box has zero volume; its faces still give the SAH an area.
  // Event entries name a node's references in 30 bits (a node holds at
  // most about 1.5 N references: see the straddling guard in offer()).
  if (n > (size_t{1} << 29)) throw std::length_error(fmt::format("bsp: {} triangles, at most 2^29 supported", n));
  RefSet refs = b.root_refs();
  EventLists events = b.root_events(refs);
  const std::unique_ptr<TmpNode> tree = b.build(std::move(refs), std::move(events), std::move(root), 0);
  out.nodes.resize(1);
  flatten(*tree, 0, 0, out, s, tree->area > 0 ? tree->area : 1.0);
  if (stats) *stats = s;
  return out;
}

}  // namespace raylab
