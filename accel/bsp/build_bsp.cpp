#include "accel/bsp/build_bsp.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>

#include <tbb/task_group.h>

#include "accel/bsp/convex_polytope.h"
#include "accel/core/sah_report.h"

namespace raylab {

namespace {

constexpr uint32_t kKindKdop = 5;  // build-time only: a fixed non-axis direction (stored as general)
constexpr uint32_t kKindTriangle = 6;  // build-time only: a triangle's plane (stored as general)

struct TmpNode {
  uint32_t kind = kBspLeaf;
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
  }

  RefSet root_refs() const {
    RefSet r;
    r.ids.reserve(v_.size());
    r.pts.reserve(3 * v_.size());
    for (size_t i = 0; i < v_.size(); ++i) r.add(static_cast<uint32_t>(i), v_[i].data(), 3);
    return r;
  }

  std::unique_ptr<TmpNode> build(RefSet refs, ConvexPolytope poly, int depth) const {
    auto node = std::make_unique<TmpNode>();
    node->area = poly.surface_area();
    const size_t n = refs.size();
    const double leaf_cost = opt_.intersection_cost * static_cast<double>(n);
    Candidate best;
    if (n > 0 && depth < depth_limit_ && node->area > 0) best = find_split(refs, poly, node->area, leaf_cost);
    if (!(best.cost < leaf_cost)) {
      node->ids = std::move(refs.ids);
      return node;
    }
    RefSet left, right;
    partition(refs, best.n, best.d, left, right);
    if (left.size() == n && right.size() == n) {  // no progress (cannot happen with a counted candidate)
      node->ids = std::move(refs.ids);
      return node;
    }
    refs = RefSet{};
    node->kind = best.kind;
    node->n = best.n;
    node->d = best.d;
    auto parts = poly.split(best.n.cast<double>(), static_cast<double>(best.d));
    poly = ConvexPolytope{};
    if (n > 4096) {
      tbb::task_group g;
      g.run([&] { node->child[0] = build(std::move(left), std::move(parts.first), depth + 1); });
      node->child[1] = build(std::move(right), std::move(parts.second), depth + 1);
      g.wait();
    } else {
      node->child[0] = build(std::move(left), std::move(parts.first), depth + 1);
      node->child[1] = build(std::move(right), std::move(parts.second), depth + 1);
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
  // reaches below the plane or lies in it, above when it reaches above.
  bool goes_below(double smin, double smax) const { return smax <= tol_ || smin < -tol_; }
  bool goes_above(double, double smax) const { return smax > tol_; }

  void partition(const RefSet& refs, const Vec3f& nf, float df, RefSet& left, RefSet& right) const {
    const Vec3d n = nf.cast<double>();
    const double d = df;
    Vec3d below[kMaxClippedVertices], above[kMaxClippedVertices];
    for (size_t i = 0; i < refs.size(); ++i) {
      double smin, smax;
      side_range(refs, i, n, d, smin, smax);
      const uint32_t id = refs.ids[i];
      const Vec3d* p = refs.pts.data() + refs.start[i];
      const size_t k = refs.start[i + 1] - refs.start[i];
      const bool b = goes_below(smin, smax), a = goes_above(smin, smax);
      if (b && !a) {
        left.add(id, p, k);
      } else if (a && !b) {
        right.add(id, p, k);
      } else {
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
      }
    }
  }

  void consider(Candidate& best, const ConvexPolytope& poly, double area, uint32_t kind, const Vec3f& nf, float df,
                size_t nl, size_t nr, size_t n) const {
    if (nl == n && nr == n) return;
    // Lower bound without the areas: al + ar >= area (the cap counts twice),
    // so al nl + ar nr >= min(nl, nr) area. Skips most polytope clips.
    const double bonus = (nl == 0 || nr == 0) ? 1.0 - opt_.empty_bonus : 1.0;
    if ((opt_.traversal_cost + opt_.intersection_cost * static_cast<double>(std::min(nl, nr))) * bonus >= best.cost) return;
    const auto [al, ar] = poly.split_areas(nf.cast<double>(), static_cast<double>(df));
    double cost = opt_.traversal_cost +
                  opt_.intersection_cost * (al * static_cast<double>(nl) + ar * static_cast<double>(nr)) / area;
    cost *= bonus;
    if (cost < best.cost) best = Candidate{cost, kind, nf, df};
  }

  // The cheapest candidate, if any is cheaper than `leaf_cost`.
  Candidate find_split(const RefSet& refs, const ConvexPolytope& poly, double area, double leaf_cost) const {
    Candidate best;
    best.cost = leaf_cost;
    const size_t n = refs.size();
    const Vec3f* dirs = bsp_fixed_directions();
    const int bins = std::max(2, opt_.bins);
    std::vector<double> lo_s(n), hi_s(n);
    std::vector<uint32_t> hist_min(bins), hist_max(bins);
    for (int di = 0; di < opt_.directions; ++di) {
      const Vec3f& uf = dirs[di];
      const Vec3d u = uf.cast<double>();
      double tri_lo = std::numeric_limits<double>::infinity(), tri_hi = -tri_lo;
      for (size_t i = 0; i < n; ++i) {
        side_range(refs, i, u, 0.0, lo_s[i], hi_s[i]);
        tri_lo = std::min(tri_lo, lo_s[i]);
        tri_hi = std::max(tri_hi, hi_s[i]);
      }
      const auto [p_lo, p_hi] = poly.extent(u);
      const double lo = std::max(p_lo, tri_lo), hi = std::min(p_hi, tri_hi);
      if (!(hi > lo)) continue;
      std::fill(hist_min.begin(), hist_min.end(), 0u);
      std::fill(hist_max.begin(), hist_max.end(), 0u);
      const double scale = bins / (hi - lo);
      auto bin_of = [&](double s) { return std::clamp(static_cast<int>((s - lo) * scale), 0, bins - 1); };
      for (size_t i = 0; i < n; ++i) {
        hist_min[bin_of(lo_s[i])]++;
        hist_max[bin_of(hi_s[i])]++;
      }
      // (Planes at the ends of the triangles' extent, cutting off empty
      // space, were tried: on the bunny they used up the depth limit and
      // raised the SAH cost from 102 to 157, so they are not candidates.)
      const uint32_t kind = di < 3 ? static_cast<uint32_t>(di) : kKindKdop;
      // nl(b) = triangles starting below boundary b, nr(b) = ending above it.
      size_t below = 0, above = n;
      for (int b = 1; b < bins; ++b) {
        below += hist_min[b - 1];
        above -= hist_max[b - 1];
        const float df = static_cast<float>(lo + (hi - lo) * b / bins);
        consider(best, poly, area, kind, uf, df, below, above, n);
      }
    }
    // Planes of the node's own triangles, counted exactly.
    const size_t tries = std::min<size_t>(static_cast<size_t>(std::max(0, opt_.triangle_planes)), n);
    for (size_t k = 0; k < tries; ++k) {
      const uint32_t id = refs.ids[k * n / tries];
      const Vec3d nd = (v_[id][1] - v_[id][0]).cross(v_[id][2] - v_[id][0]);
      if (!(nd.squaredNorm() > 0) || !std::isfinite(nd.squaredNorm())) continue;
      const Vec3f nf = nd.normalized().cast<float>();
      const float df = static_cast<float>(nf.cast<double>().dot(v_[id][0]));
      const Vec3d nn = nf.cast<double>();
      size_t nl = 0, nr = 0;
      for (size_t j = 0; j < n; ++j) {
        double smin, smax;
        side_range(refs, j, nn, df, smin, smax);
        nl += goes_below(smin, smax);
        nr += goes_above(smin, smax);
      }
      consider(best, poly, area, kKindTriangle, nf, df, nl, nr, n);
    }
    return best;
  }

  BspBuildOptions opt_;
  std::vector<std::array<Vec3d, 3>> v_;
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
  const uint32_t stored = t.kind <= 2 ? t.kind : kBspGeneral;
  s.axis_nodes += t.kind <= 2;
  s.kdop_nodes += t.kind == kKindKdop;
  s.triangle_plane_nodes += t.kind == kKindTriangle;
  const float normal[3] = {t.n.x(), t.n.y(), t.n.z()};
  out.nodes[at] = BspNode::inner(stored, normal, t.d, pair);
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
  ConvexPolytope root;
  if (n > 0) root = ConvexPolytope::box(out.bounds.lo.cast<double>(), out.bounds.hi.cast<double>());
  // A flat scene box has zero volume; its faces still give the SAH an area.
  const std::unique_ptr<TmpNode> tree = b.build(b.root_refs(), std::move(root), 0);
  out.nodes.resize(1);
  flatten(*tree, 0, 0, out, s, tree->area > 0 ? tree->area : 1.0);
  if (stats) *stats = s;
  return out;
}

}  // namespace raylab
