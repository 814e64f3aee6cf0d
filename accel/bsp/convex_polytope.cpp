#include "accel/bsp/convex_polytope.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace raylab {

namespace {

// Clips one polygon by the plane: below part (s <= 0), above part (s >= 0),
// and the crossing points (on the plane) appended to `cap`.
template <typename Poly>
void clip_polygon(const std::vector<Vec3d>& poly, const Vec3d& n, double d, Poly& below, Poly& above,
                  std::vector<Vec3d>* cap) {
  const size_t k = poly.size();
  // A face lying in the plane belongs to neither part: the cap replaces it
  // on the side with volume (the other side is flat, area 0).
  bool in_plane = true;
  for (const Vec3d& p : poly) in_plane = in_plane && n.dot(p) - d == 0;
  if (in_plane) {
    if (cap) cap->insert(cap->end(), poly.begin(), poly.end());
    return;
  }
  for (size_t i = 0; i < k; ++i) {
    const Vec3d& a = poly[i];
    const Vec3d& b = poly[(i + 1) % k];
    const double sa = n.dot(a) - d, sb = n.dot(b) - d;
    if (sa <= 0) below.push_back(a);
    if (sa >= 0) above.push_back(a);
    if (sa == 0 && cap) cap->push_back(a);
    if ((sa < 0 && sb > 0) || (sa > 0 && sb < 0)) {
      const Vec3d p = a + (sa / (sa - sb)) * (b - a);
      below.push_back(p);
      above.push_back(p);
      if (cap) cap->push_back(p);
    }
  }
}

// The cap polygon: crossing points deduplicated and ordered by angle about
// their centroid in the plane.
std::vector<Vec3d> order_cap(std::vector<Vec3d> pts, const Vec3d& n) {
  if (pts.size() < 3) return {};
  Vec3d c = Vec3d::Zero();
  for (const auto& p : pts) c += p;
  c /= static_cast<double>(pts.size());
  const Vec3d u = (std::fabs(n.x()) < 0.9 ? Vec3d::UnitX() : Vec3d::UnitY()).cross(n).normalized();
  const Vec3d v = n.cross(u);
  std::sort(pts.begin(), pts.end(), [&](const Vec3d& a, const Vec3d& b) {
    return std::atan2((a - c).dot(v), (a - c).dot(u)) < std::atan2((b - c).dot(v), (b - c).dot(u));
  });
  double scale = 0;
  for (const auto& p : pts) scale = std::max(scale, (p - c).cwiseAbs().maxCoeff());
  std::vector<Vec3d> out;
  for (const auto& p : pts)
    if (out.empty() || (p - out.back()).cwiseAbs().maxCoeff() > 1e-12 * scale) out.push_back(p);
  while (out.size() > 1 && (out.front() - out.back()).cwiseAbs().maxCoeff() <= 1e-12 * scale) out.pop_back();
  if (out.size() < 3) return {};
  return out;
}

// A fixed-capacity polygon for split_areas (no allocation per candidate).
struct SmallPoly {
  Vec3d v[64];
  size_t size = 0;
  void push_back(const Vec3d& p) {
    if (size < 64) v[size++] = p;
  }
  Vec3d area_vector() const {
    Vec3d s = Vec3d::Zero();
    for (size_t i = 1; i + 1 < size; ++i) s += (v[i] - v[0]).cross(v[i + 1] - v[0]);
    return 0.5 * s;
  }
};

}  // namespace

Vec3d polygon_area_vector(const std::vector<Vec3d>& poly) {
  Vec3d s = Vec3d::Zero();
  if (poly.size() < 3) return s;
  // Relative to the first vertex: smaller products, less cancellation.
  for (size_t i = 1; i + 1 < poly.size(); ++i) s += (poly[i] - poly[0]).cross(poly[i + 1] - poly[0]);
  return 0.5 * s;
}

ConvexPolytope ConvexPolytope::box(const Vec3d& lo, const Vec3d& hi) {
  ConvexPolytope p;
  auto corner = [&](int i) { return Vec3d(i & 1 ? hi.x() : lo.x(), i & 2 ? hi.y() : lo.y(), i & 4 ? hi.z() : lo.z()); };
  // Six faces, each a quad of corner indices in order around the face.
  const int quads[6][4] = {{0, 2, 6, 4}, {1, 5, 7, 3}, {0, 4, 5, 1}, {2, 3, 7, 6}, {0, 1, 3, 2}, {4, 6, 7, 5}};
  for (const auto& q : quads) p.faces.push_back({corner(q[0]), corner(q[1]), corner(q[2]), corner(q[3])});
  return p;
}

double ConvexPolytope::surface_area() const {
  double a = 0;
  for (const auto& f : faces) a += polygon_area_vector(f).norm();
  return a;
}

std::pair<double, double> ConvexPolytope::extent(const Vec3d& u) const {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& f : faces)
    for (const auto& p : f) {
      const double s = u.dot(p);
      lo = std::min(lo, s);
      hi = std::max(hi, s);
    }
  return {lo, hi};
}

std::pair<ConvexPolytope, ConvexPolytope> ConvexPolytope::split(const Vec3d& n, double d) const {
  std::pair<ConvexPolytope, ConvexPolytope> out;
  std::vector<Vec3d> cap;
  for (const auto& f : faces) {
    std::vector<Vec3d> below, above;
    clip_polygon(f, n, d, below, above, &cap);
    if (below.size() >= 3 && polygon_area_vector(below).squaredNorm() > 0) out.first.faces.push_back(std::move(below));
    if (above.size() >= 3 && polygon_area_vector(above).squaredNorm() > 0) out.second.faces.push_back(std::move(above));
  }
  std::vector<Vec3d> c = order_cap(std::move(cap), n);
  if (!c.empty()) {
    // Faces keep one orientation (area vectors pointing inward, as box()
    // makes them) so the area vectors of a closed surface sum to zero, which
    // split_areas relies on: inward is -n for the part below, +n above.
    if (polygon_area_vector(c).dot(n) > 0) std::reverse(c.begin(), c.end());
    out.first.faces.push_back(c);
    std::reverse(c.begin(), c.end());
    out.second.faces.push_back(std::move(c));
  }
  if (out.first.empty()) out.first.faces.clear();
  if (out.second.empty()) out.second.faces.clear();
  return out;
}

std::pair<double, double> ConvexPolytope::split_areas(const Vec3d& n, double d) const {
  double area_below = 0, area_above = 0;
  Vec3d sum_below = Vec3d::Zero(), sum_above = Vec3d::Zero();
  for (const auto& f : faces) {
    if (f.size() > 60) {  // never for polytopes of a few dozen planes; keeps SmallPoly in bounds
      std::vector<Vec3d> below, above;
      clip_polygon(f, n, d, below, above, nullptr);
      const Vec3d ab = polygon_area_vector(below), aa = polygon_area_vector(above);
      area_below += ab.norm(), area_above += aa.norm(), sum_below += ab, sum_above += aa;
      continue;
    }
    SmallPoly below, above;
    clip_polygon(f, n, d, below, above, nullptr);
    const Vec3d ab = below.area_vector(), aa = above.area_vector();
    area_below += ab.norm();
    area_above += aa.norm();
    sum_below += ab;
    sum_above += aa;
  }
  // The cap closes each part: its area vector cancels the others' sum.
  return {area_below + sum_below.norm(), area_above + sum_above.norm()};
}

}  // namespace raylab
