#include "checks/oracle_index.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

namespace raylab {

namespace {

// Below this the subtrees are built on the calling thread.
constexpr size_t kParallelBuildTriangles = size_t{1} << 15;
// Smallest altitude, relative to the longest edge, of a triangle whose
// normal is trusted (its direction from double arithmetic is then good to
// ~1e-12 rad); thinner ones are tested on every ray.
constexpr double kMinAltitudeRatio = 1e-4;
// Angle added to every cone: the computed normals' error, with margin.
constexpr double kConeSlack = 1e-9;

struct SortKey {
  float centroid[3];
  uint32_t id;
};

float round_up(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) < x) f = std::nextafter(f, std::numeric_limits<float>::infinity());
  return f;
}
float round_down(double x) {
  float f = static_cast<float>(x);
  if (static_cast<double>(f) > x) f = std::nextafter(f, -std::numeric_limits<float>::infinity());
  return f;
}

Vec3d axis_of(const OracleIndexNode& n) {
  const Vec3d a(n.axis[0], n.axis[1], n.axis[2]);
  const double len = a.norm();
  return len > 0 ? Vec3d(a / len) : Vec3d(0, 0, 1);
}

// Angle between two lines (directions up to sign), in [0, pi/2].
double line_angle(const Vec3d& a, const Vec3d& b) { return std::atan2(a.cross(b).norm(), std::fabs(a.dot(b))); }

// Stores `axis` (rounded to float) and the half-angle that covers
// `angle_to(stored axis)` for everything below.
template <typename AngleTo>
void set_cone(OracleIndexNode& node, const Vec3d& axis, AngleTo angle_to) {
  for (int k = 0; k < 3; ++k) node.axis[k] = static_cast<float>(axis[k]);
  const Vec3d stored = axis_of(node);
  const double beta = angle_to(stored) + kConeSlack;
  node.cone_sin = beta >= 0.5 * M_PI - 1e-6 ? 2.0f : round_up(std::sin(beta));
}

double cone_angle(const OracleIndexNode& n) { return n.cone_sin >= 1.0f ? 0.5 * M_PI : std::asin(static_cast<double>(n.cone_sin)); }

class Builder {
 public:
  Builder(const TriangleMesh& mesh, std::vector<SortKey>& keys, std::vector<OracleIndexNode>& nodes,
          std::vector<uint32_t>& ids)
      : mesh_(mesh), keys_(keys), nodes_(nodes), ids_(ids) {}

  // Nodes of the subtree over n triangles (the shape depends on n alone:
  // leaves of up to kMaxLeaf, halves split at n / 2).
  size_t count_nodes(size_t n) {
    if (n <= OracleIndex::kMaxLeaf) return 1;
    auto it = memo_.find(n);
    if (it != memo_.end()) return it->second;
    const size_t c = 1 + count_nodes(n / 2) + count_nodes(n - n / 2);
    memo_[n] = c;
    return c;
  }

  void prepare(size_t n) {
    // Every subtree size is counted before the parallel build reads the memo.
    nodes_.resize(count_nodes(n));
  }

  void build(size_t node, size_t begin, size_t end) {
    OracleIndexNode& out = nodes_[node];
    const size_t n = end - begin;
    if (n <= OracleIndex::kMaxLeaf) {
      make_leaf(out, begin, end);
      return;
    }
    float lo[3], hi[3];
    for (int a = 0; a < 3; ++a) lo[a] = std::numeric_limits<float>::infinity(), hi[a] = -lo[a];
    for (size_t k = begin; k < end; ++k)
      for (int a = 0; a < 3; ++a) lo[a] = std::min(lo[a], keys_[k].centroid[a]), hi[a] = std::max(hi[a], keys_[k].centroid[a]);
    int axis = 0;
    for (int a = 1; a < 3; ++a)
      if (hi[a] - lo[a] > hi[axis] - lo[axis]) axis = a;
    const size_t mid = begin + n / 2;
    std::nth_element(keys_.begin() + static_cast<std::ptrdiff_t>(begin), keys_.begin() + static_cast<std::ptrdiff_t>(mid),
                     keys_.begin() + static_cast<std::ptrdiff_t>(end),
                     [axis](const SortKey& x, const SortKey& y) { return x.centroid[axis] < y.centroid[axis]; });
    const size_t left = node + 1, right = node + 1 + count_nodes(n / 2);
    if (n >= kParallelBuildTriangles)
      tbb::parallel_invoke([&] { build(left, begin, mid); }, [&] { build(right, mid, end); });
    else
      build(left, begin, mid), build(right, mid, end);
    merge(out, nodes_[left], nodes_[right]);
    out.payload = static_cast<uint32_t>(right);
  }

 private:
  void make_leaf(OracleIndexNode& out, size_t begin, size_t end) {
    for (int a = 0; a < 3; ++a) out.lo[a] = std::numeric_limits<float>::infinity(), out.hi[a] = -out.lo[a];
    double min_alt = std::numeric_limits<double>::infinity();
    Vec3d sum = Vec3d::Zero();
    Vec3d normals[OracleIndex::kMaxLeaf];
    size_t count = 0;
    for (size_t k = begin; k < end; ++k) {
      const uint32_t id = keys_[k].id;
      ids_[k] = id;
      for (int c = 0; c < 3; ++c) {
        const Vec3f& p = mesh_.vertex(id, c);
        for (int a = 0; a < 3; ++a) out.lo[a] = std::min(out.lo[a], p[a]), out.hi[a] = std::max(out.hi[a], p[a]);
      }
      const Vec3d p0 = mesh_.vertex(id, 0).cast<double>(), p1 = mesh_.vertex(id, 1).cast<double>(),
                  p2 = mesh_.vertex(id, 2).cast<double>();
      const Vec3d n = (p1 - p0).cross(p2 - p0);
      const double longest = std::max({(p1 - p0).norm(), (p2 - p1).norm(), (p0 - p2).norm()});
      min_alt = std::min(min_alt, n.norm() / longest);
      Vec3d unit = n / n.norm();
      if (count > 0 && unit.dot(normals[0]) < 0) unit = -unit;
      normals[count++] = unit;
      sum += unit;
    }
    // 2A / L_max is exact up to a few ulps; the margin is generous.
    out.min_altitude = round_down(min_alt * (1.0 - 1e-9));
    set_cone(out, sum / sum.norm(), [&](const Vec3d& axis) {
      double worst = 0;
      for (size_t k = 0; k < count; ++k) worst = std::max(worst, line_angle(normals[k], axis));
      return worst;
    });
    out.payload = OracleIndex::kLeafFlag | (static_cast<uint32_t>(end - begin - 1) << OracleIndex::kCountShift) |
                  static_cast<uint32_t>(begin);
  }

  static void merge(OracleIndexNode& out, const OracleIndexNode& l, const OracleIndexNode& r) {
    for (int a = 0; a < 3; ++a) out.lo[a] = std::min(l.lo[a], r.lo[a]), out.hi[a] = std::max(l.hi[a], r.hi[a]);
    out.min_altitude = std::min(l.min_altitude, r.min_altitude);
    if (l.cone_sin >= 1.0f || r.cone_sin >= 1.0f) {
      for (float& v : out.axis) v = 0.0f;
      out.axis[2] = 1.0f;
      out.cone_sin = 2.0f;
      return;
    }
    const Vec3d al = axis_of(l);
    Vec3d ar = axis_of(r);
    if (al.dot(ar) < 0) ar = -ar;
    const double bl = cone_angle(l), br = cone_angle(r);
    set_cone(out, (al + ar).normalized(), [&](const Vec3d& axis) {
      return std::max(line_angle(al, axis) + bl, line_angle(ar, axis) + br);
    });
  }

  const TriangleMesh& mesh_;
  std::vector<SortKey>& keys_;
  std::vector<OracleIndexNode>& nodes_;
  std::vector<uint32_t>& ids_;
  std::map<size_t, size_t> memo_;
};

}  // namespace

OracleIndex::OracleIndex(const TriangleMesh& mesh) : triangles_(mesh.num_triangles()) {
  if (triangles_ >= kMaxTriangles)
    throw std::length_error("the oracle's index addresses at most 2^27 triangles");
  const size_t n = triangles_;
  std::vector<uint8_t> bounded(n);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 14), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i < r.end(); ++i) {
      const Vec3d p0 = mesh.vertex(i, 0).cast<double>(), p1 = mesh.vertex(i, 1).cast<double>(),
                  p2 = mesh.vertex(i, 2).cast<double>();
      const double area2 = (p1 - p0).cross(p2 - p0).norm();
      const double longest = std::max({(p1 - p0).norm(), (p2 - p1).norm(), (p0 - p2).norm()});
      bounded[i] = area2 >= kMinAltitudeRatio * longest * longest && std::isfinite(area2);
    }
  });
  size_t count = 0;
  for (uint8_t b : bounded) count += b;
  std::vector<SortKey> keys;
  keys.reserve(count);
  for (size_t i = 0; i < n; ++i) {
    if (!bounded[i]) {
      const bool never_crossed = oracle_triangle_is_exactly_degenerate(mesh.vertex(i, 0), mesh.vertex(i, 1), mesh.vertex(i, 2));
      (never_crossed ? degenerate_ : unbounded_).push_back(static_cast<uint32_t>(i));
      continue;
    }
    SortKey k;
    for (int a = 0; a < 3; ++a)
      k.centroid[a] = (mesh.vertex(i, 0)[a] + mesh.vertex(i, 1)[a] + mesh.vertex(i, 2)[a]) * (1.0f / 3.0f);
    k.id = static_cast<uint32_t>(i);
    keys.push_back(k);
  }
  std::vector<uint8_t>().swap(bounded);
  if (keys.empty()) return;
  ids_.resize(keys.size());
  Builder builder(mesh, keys, nodes_, ids_);
  builder.prepare(keys.size());
  builder.build(0, 0, keys.size());
}

size_t OracleIndex::memory_bytes() const {
  return nodes_.capacity() * sizeof(OracleIndexNode) +
         (ids_.capacity() + unbounded_.capacity() + degenerate_.capacity()) * sizeof(uint32_t);
}

namespace {

// The ray as the node tests need it.
struct NodeQuery {
  Vec3d o, d, u;
  double dn, tmin, tmax, tol, org_max;

  NodeQuery(const Ray& ray, double graze_tol)
      : o(ray.org.cast<double>()), d(ray.dir.cast<double>()), dn(d.norm()), tmin(ray.tmin),
        tmax(std::min(static_cast<double>(ray.tmax), static_cast<double>(std::numeric_limits<float>::max()))),
        tol(graze_tol), org_max(o.cwiseAbs().maxCoeff()) {
    u = d / dn;
  }

  // Whether the segment o + t d, t in [t0, t1], meets the box padded by pad[a].
  bool segment_meets(double t0, double t1, const OracleIndexNode& n, const double pad[3]) const {
    for (int a = 0; a < 3; ++a) {
      const double lo = static_cast<double>(n.lo[a]) - pad[a], hi = static_cast<double>(n.hi[a]) + pad[a];
      if (d[a] == 0.0) {
        if (!(o[a] >= lo && o[a] <= hi)) return false;
        continue;
      }
      double ta = (lo - o[a]) / d[a], tb = (hi - o[a]) / d[a];
      if (ta > tb) std::swap(ta, tb);
      // Division's rounding, with room to spare.
      ta -= 1e-12 * std::fabs(ta);
      tb += 1e-12 * std::fabs(tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      if (!(t0 <= t1)) return false;
    }
    return true;
  }

  // Can hold a crossing within [tmin, tmax] or a triangle the ray lies in
  // (within rounding) whose bounds the segment comes near (G1): the padding
  // covers oracle.cpp's segment_near_box (1e-6 of |lo| + |hi| of the
  // triangle's bounds, at most 2 max(|lo|, |hi|) of the node's).
  bool near_segment(const OracleIndexNode& n) const {
    double pad[3];
    for (int a = 0; a < 3; ++a) {
      const double m = std::max(std::fabs(static_cast<double>(n.lo[a])), std::fabs(static_cast<double>(n.hi[a])));
      pad[a] = 1.01e-6 * std::max(1.0, 2.0 * m) + 1e-12 * (m + std::fabs(o[a]));
    }
    return segment_meets(tmin - 1e-12 * std::fabs(tmin), tmax + 1e-12 * std::fabs(tmax), n, pad);
  }

  // x widened by the near-range slack (oracle.cpp's t_slack, doubled) on the
  // side `sign`; infinities stay.
  double slackened(double x, double sign, double scale_over_dn) const {
    if (!std::isfinite(x)) return x;
    const double widened = x + sign * 2.0 * tol * std::max(scale_over_dn, 2.0 * std::fabs(x));
    return widened + sign * (1e-6 * std::fabs(widened) + 1e-6 * scale_over_dn);
  }

  // Can hold a triangle with every relative edge function >= -tol and its
  // line-plane distance near [tmin, tmax] (G2, G3): the bound of the header.
  bool may_graze(const OracleIndexNode& n) const {
    if (n.cone_sin >= 1.0f || !(n.min_altitude > 0.0f)) return true;
    double r2 = 0, box_max = 0, a_lo = 0, a_hi = 0;
    const Vec3d n0 = axis_of(n);
    for (int a = 0; a < 3; ++a) {
      const double l = static_cast<double>(n.lo[a]) - o[a], h = static_cast<double>(n.hi[a]) - o[a];
      r2 += std::max(l * l, h * h);
      box_max = std::max({box_max, std::fabs(static_cast<double>(n.lo[a])), std::fabs(static_cast<double>(n.hi[a]))});
      a_lo += std::min(n0[a] * l, n0[a] * h);
      a_hi += std::max(n0[a] * l, n0[a] * h);
    }
    const double R = std::sqrt(r2) * (1 + 1e-12);
    const double alt = n.min_altitude;
    const double sin_b = n.cone_sin, cos_b = std::sqrt(std::max(0.0, 1.0 - sin_b * sin_b));
    const double n0u = n0.dot(u);
    const double cos_t = std::fabs(n0u), sin_t = std::sqrt(std::max(0.0, 1.0 - cos_t * cos_t));
    const double c_lo = cos_t * cos_b - sin_t * sin_b - 1e-9;  // cos(angle(u, n0) + beta)
    // cos(max(angle(u, n0) - beta, 0)): the largest |cos| in the cone
    const double c_hi = cos_t > cos_b ? 1.0 : std::min(1.0, cos_t * cos_b + sin_t * sin_b + 1e-9);
    const double tol_bound = 1.001 * tol;

    // The plane's distance from the origin, |n.(X - o)| >= h_plane, for n in
    // the cone (taken on n0's side) and X in the box.
    a_lo -= 1e-12 * 3 * R;
    a_hi += 1e-12 * 3 * R;
    const double num_lo = std::min(a_lo, cos_b * a_lo) - sin_b * R, num_hi = std::max(a_hi, cos_b * a_hi) + sin_b * R;
    const double h_plane = num_lo > 0 ? num_lo : num_hi < 0 ? -num_hi : 0.0;
    // Nearly parallel rays: |H| sqrt(1 - c^2) h / 2 <= R^2 (c + tol) (header),
    // so no triangle with c below c_edge can graze.
    const double k = h_plane * alt / (2.0 * R * R);
    const double c_edge = k < 1 ? (k * std::sqrt(1.0 - k * k) - tol_bound) * (1 - 1e-9) : -1.0;
    const double c_min = std::max(c_lo, c_edge);
    if (c_hi < c_min) return false;
    // No bound, or det too close to its rounding for the computed t to be trusted.
    if (c_min <= 0) return true;
    // The computed det's relative error: its rounding (< 1e-14 |d| R^2) over
    // |det| >= |d| 2A c >= |d| h^2 c.
    const double det_err = 1e-14 * R * R / (alt * alt * c_min);
    if (det_err > 0.01) return true;

    // t = n.(X - o) / n.d with |n.d| in [c_min |d|, |d|]: its sign is n0.d's
    // when the whole cone is on one side of the ray, else either.
    const double scale_over_dn = std::max(org_max, box_max) / dn;
    const double near_lo = slackened(tmin, -1.0, scale_over_dn), near_hi = slackened(tmax, +1.0, scale_over_dn);
    // Where the line meets the plane lies within 2 tol R^2 / (h c) of the triangle.
    const double reach = 2.0 * tol_bound * R * R / (alt * c_min) * (1 + 1e-6);
    double pad[3];
    for (int a = 0; a < 3; ++a) pad[a] = reach + 1e-6 * (box_max + std::fabs(o[a]));
    for (const double side : {1.0, -1.0}) {
      if (c_lo > 0 && side * n0u < 0) continue;
      // num / den with den in side * [c_min dn, dn]: as (side num) / [c_min dn, dn].
      const double nl = side > 0 ? num_lo : -num_hi, nh = side > 0 ? num_hi : -num_lo;
      const double den_lo = c_min * dn, den_hi = dn;
      double t_lo = nl / (nl >= 0 ? den_hi : den_lo), t_hi = nh / (nh >= 0 ? den_lo : den_hi);
      // The computed t = T / det: T's rounding is < 1e-14 R^3.
      const double t_err = 2 * det_err + 1e-9;
      t_lo -= t_err * (std::fabs(t_lo) + R / dn);
      t_hi += t_err * (std::fabs(t_hi) + R / dn);
      t_lo = std::max(t_lo, near_lo);
      t_hi = std::min(t_hi, near_hi);
      if (t_lo <= t_hi && segment_meets(t_lo, t_hi, n, pad)) return true;
    }
    return false;
  }
};

}  // namespace

OracleHit oracle_closest_hit(const OracleIndex& index, const TriangleMesh& mesh, const Ray& ray, double graze_tol,
                             OracleIndexStats* stats) {
  OracleAccumulator acc(mesh, ray, graze_tol);
  if (!acc.ray_valid()) return OracleHit{};
  OracleIndexStats local;
  for (uint32_t id : index.unbounded()) acc.add(id);
  for (uint32_t id : index.degenerate()) acc.add_degenerate(id);
  local.triangles_tested += index.unbounded().size() + index.degenerate().size();
  const auto& nodes = index.nodes();
  const auto& ids = index.ids();
  if (!nodes.empty()) {
    const NodeQuery q(ray, graze_tol);
    // First the nodes near the segment (every crossing, and the grazing
    // triangles most rays have), then, unless a triangle already set
    // `grazing`, the other nodes that could set it; a leaf near the segment
    // was tested in the first pass.
    for (const bool grazing_pass : {false, true}) {
      if (grazing_pass && acc.grazing()) break;
      uint32_t stack[128];
      int top = 0;
      stack[top++] = 0;
      while (top > 0) {
        const uint32_t ni = stack[--top];
        const OracleIndexNode& n = nodes[ni];
        const bool near = q.near_segment(n);
        if (!near && (!grazing_pass || acc.grazing() || !q.may_graze(n))) continue;
        ++local.nodes_visited;
        if (OracleIndex::is_leaf(n)) {
          if (grazing_pass && near) continue;
          const uint32_t first = OracleIndex::leaf_first(n), count = OracleIndex::leaf_count(n);
          for (uint32_t k = 0; k < count; ++k) acc.add(ids[first + k]);
          local.triangles_tested += count;
        } else {
          stack[top++] = n.payload;
          stack[top++] = ni + 1;
        }
      }
    }
  }
  if (stats) *stats = local;
  return acc.finish();
}

}  // namespace raylab
