#include "checks/oracle.h"

#include <gmpxx.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <utility>
#include <vector>

namespace raylab {

namespace {

// Relative error bound used to decide when double precision cannot be
// trusted. The double results carry a few rounding errors of 2^-53 each
// relative to the product of the operands' magnitudes (~1e-15); 1e-12 leaves
// three orders of magnitude of margin, so a double decision outside the bound
// is certain, and everything inside goes to GMP.
constexpr double kFilter = 1e-12;

struct V3q {
  mpq_class x, y, z;
};

V3q to_q(const Vec3f& v) { return {mpq_class(static_cast<double>(v.x())), mpq_class(static_cast<double>(v.y())), mpq_class(static_cast<double>(v.z()))}; }
V3q sub(const V3q& a, const V3q& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
V3q cross(const V3q& a, const V3q& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
mpq_class dot(const V3q& a, const V3q& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// Exact evaluation of one triangle; t_exact receives the exact line distance
// when the line is not parallel to the plane.
struct ExactEval {
  bool crosses_line = false;  // the line crosses the closed triangle
  bool coplanar = false;
  bool parallel = false;
  mpq_class t;
};

ExactEval exact_eval(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Ray& ray) {
  const V3q o = to_q(ray.org), d = to_q(ray.dir);
  const V3q a = sub(to_q(p0), o), b = sub(to_q(p1), o), c = sub(to_q(p2), o);
  const mpq_class U = dot(d, cross(b, c));
  const mpq_class V = dot(d, cross(c, a));
  const mpq_class W = dot(d, cross(a, b));
  ExactEval e;
  const int su = sgn(U), sv = sgn(V), sw = sgn(W);
  e.coplanar = su == 0 && sv == 0 && sw == 0;
  const mpq_class det = U + V + W;
  e.parallel = sgn(det) == 0;
  const bool neg = su < 0 || sv < 0 || sw < 0;
  const bool pos = su > 0 || sv > 0 || sw > 0;
  e.crosses_line = !(neg && pos) && !e.coplanar && !e.parallel;
  if (!e.parallel) e.t = dot(a, cross(b, c)) / det;
  return e;
}

// A hit's distance must be a finite float (accel/core/hit_recorder.h): the
// segment ends at FLT_MAX even when tmax = +inf.
double effective_tmax(const Ray& ray) {
  return std::min(static_cast<double>(ray.tmax), static_cast<double>(std::numeric_limits<float>::max()));
}

bool exact_in_range(const mpq_class& t, const Ray& ray) {
  if (std::isfinite(ray.tmin) && t < mpq_class(static_cast<double>(ray.tmin))) return false;
  if (ray.tmin == std::numeric_limits<float>::infinity()) return false;
  if (t > mpq_class(effective_tmax(ray))) return false;
  if (ray.tmax == -std::numeric_limits<float>::infinity()) return false;
  return true;
}

// The double evaluation of one triangle with its error bounds.
struct DoubleEval {
  double u, v, w, det, t, margin;
  double err_edge[3];
  double err_det, err_t;
  bool certain_miss = false;   // opposite signs beyond the error bounds
  bool uncertain = false;      // some edge function (or det) within its error bound
};

struct RayD {
  Vec3d o, d;
  double dn;
  explicit RayD(const Ray& r) : o(r.org.cast<double>()), d(r.dir.cast<double>()), dn(d.norm()) {}
};

DoubleEval double_eval(const RayD& r, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2) {
  const Vec3d a = p0.cast<double>() - r.o;
  const Vec3d b = p1.cast<double>() - r.o;
  const Vec3d c = p2.cast<double>() - r.o;
  const double na = a.norm(), nb = b.norm(), nc = c.norm();
  DoubleEval e;
  e.u = r.d.dot(b.cross(c));
  e.v = r.d.dot(c.cross(a));
  e.w = r.d.dot(a.cross(b));
  e.err_edge[0] = kFilter * r.dn * nb * nc;
  e.err_edge[1] = kFilter * r.dn * nc * na;
  e.err_edge[2] = kFilter * r.dn * na * nb;
  e.det = e.u + e.v + e.w;
  e.err_det = e.err_edge[0] + e.err_edge[1] + e.err_edge[2];
  const double T = a.dot(b.cross(c));
  const double err_T = kFilter * na * nb * nc;
  e.t = T / e.det;
  e.err_t = std::fabs(e.det) > e.err_det ? (err_T + std::fabs(e.t) * e.err_det) / (std::fabs(e.det) - e.err_det)
                                         : std::numeric_limits<double>::infinity();
  const double vals[3] = {e.u, e.v, e.w};
  bool pos = false, neg = false;
  for (int k = 0; k < 3; ++k) {
    if (vals[k] > e.err_edge[k]) pos = true;
    else if (vals[k] < -e.err_edge[k]) neg = true;
    else e.uncertain = true;
  }
  e.certain_miss = pos && neg;
  if (std::fabs(e.det) <= e.err_det) e.uncertain = true;
  // Margin, relative to each edge function's scale (the size of its float
  // rounding error): the distance to the nearest edge when the line crosses
  // (> 0), minus the distance to the farthest violated edge when it does not.
  const double s = e.det < 0 ? -1.0 : 1.0;
  double inside = std::numeric_limits<double>::infinity(), outside = 0.0;
  for (int k = 0; k < 3; ++k) {
    const double scale = e.err_edge[k] / kFilter;
    const double rel = scale > 0.0 ? s * vals[k] / scale : 0.0;
    if (rel >= 0.0) inside = std::min(inside, rel);
    else outside = std::max(outside, -rel);
  }
  e.margin = outside > 0.0 ? -outside : (std::isfinite(inside) ? inside : 0.0);
  return e;
}

// Range check with an uncertainty band; nullopt = undecided in double.
std::optional<bool> double_in_range(double t, double err, const Ray& ray) {
  const double lo = ray.tmin, hi = effective_tmax(ray);
  if (!(t - err >= lo || t + err < lo)) return std::nullopt;
  if (!(t + err <= hi || t - err > hi)) return std::nullopt;
  return t >= lo && t <= hi;
}

// Tolerance on a distance near tmin/tmax: relative to t, and to the
// coordinates' magnitude over |dir| (a float origin on a surface is off it by
// an ulp of its coordinates, so the distance to that surface is only known
// to about that).
double t_slack_for(double graze_tol, double t, const RayD& r, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2) {
  const double s = std::max({r.o.cwiseAbs().maxCoeff(), static_cast<double>(p0.cwiseAbs().maxCoeff()),
                             static_cast<double>(p1.cwiseAbs().maxCoeff()), static_cast<double>(p2.cwiseAbs().maxCoeff())});
  return graze_tol * std::max(std::fabs(t), s / r.dn);
}

struct Candidate {
  uint32_t prim;
  double t, err;
  std::optional<mpq_class> exact_t;
};

}  // namespace

bool oracle_triangle_is_exactly_degenerate(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2) {
  // Differences of floats in double, exact when their rounding error is zero
  // (Knuth's two-sum), then the cross product's products, exact when fma
  // finds no remainder: collinear iff the two products of every component
  // are equal.
  double e[2][3];
  const Vec3f* q[2] = {&p1, &p2};
  for (int k = 0; k < 2; ++k)
    for (int a = 0; a < 3; ++a) {
      const double x = (*q[k])[a], y = -static_cast<double>(p0[a]);
      const double s = x + y, bv = s - x, err = (x - (s - bv)) + (y - bv);
      if (err != 0.0) return false;
      e[k][a] = s;
    }
  for (int a = 0; a < 3; ++a) {
    const int b = (a + 1) % 3, c = (a + 2) % 3;
    const double l = e[0][b] * e[1][c], r = e[0][c] * e[1][b];
    if (std::fma(e[0][b], e[1][c], -l) != 0.0 || std::fma(e[0][c], e[1][b], -r) != 0.0) return false;
    if (l != r) return false;
  }
  return true;
}

OracleTriangle oracle_triangle_exact(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Ray& ray) {
  OracleTriangle out;
  out.exact_used = true;
  if (!ray_is_valid(ray)) return out;
  const ExactEval e = exact_eval(p0, p1, p2, ray);
  out.coplanar = e.coplanar;
  if (!e.parallel) out.t = e.t.get_d();
  out.crosses = e.crosses_line && exact_in_range(e.t, ray);
  const DoubleEval d = double_eval(RayD(ray), p0, p1, p2);
  out.margin = d.margin;
  return out;
}

OracleTriangle oracle_triangle(const TriangleMesh& mesh, const Ray& ray, uint32_t prim) {
  OracleTriangle out;
  if (!ray_is_valid(ray) || prim >= mesh.num_triangles()) return out;
  const Vec3f &p0 = mesh.vertex(prim, 0), &p1 = mesh.vertex(prim, 1), &p2 = mesh.vertex(prim, 2);
  const DoubleEval d = double_eval(RayD(ray), p0, p1, p2);
  if (!d.uncertain) {
    out.margin = d.margin;
    out.t = d.t;
    if (d.certain_miss) return out;
    const auto in = double_in_range(d.t, d.err_t, ray);
    if (in) {
      out.crosses = *in;
      return out;
    }
  }
  return oracle_triangle_exact(p0, p1, p2, ray);
}

namespace {

// Whether the segment [tmin, tmax] of a ray comes near `box` (padded by
// 1e-6 of its coordinates): a ray lying in (or within rounding of) a
// triangle's plane grazes the triangle when it does.
bool segment_near_box(const RayD& rd, double tmin, double tmax, const Aabb& box) {
  double t0 = tmin, t1 = tmax;
  for (int a = 0; a < 3; ++a) {
    const double pad = 1e-6 * std::max(1.0, std::fabs(static_cast<double>(box.hi[a])) + std::fabs(static_cast<double>(box.lo[a])));
    const double lo = box.lo[a] - pad, hi = box.hi[a] + pad;
    if (rd.d[a] == 0.0) {
      if (!(rd.o[a] >= lo && rd.o[a] <= hi)) return false;
    } else {
      double ta = (lo - rd.o[a]) / rd.d[a], tb = (hi - rd.o[a]) / rd.d[a];
      if (ta > tb) std::swap(ta, tb);
      t0 = std::max(t0, ta);
      t1 = std::min(t1, tb);
      if (!(t0 <= t1)) return false;
    }
  }
  return true;
}

// The nearest of the candidates: by the double distances, exactly where
// their error bands overlap (ties to the lower primitive id). Notes exact
// arithmetic and exact ties in `best`.
size_t nearest_candidate(const TriangleMesh& mesh, const Ray& ray, std::vector<Candidate>& cands, OracleHit& best) {
  auto exact_t = [&](Candidate& c) -> const mpq_class& {
    if (!c.exact_t) {
      best.exact_used = true;
      const uint32_t p = c.prim;
      c.exact_t = exact_eval(mesh.vertex(p, 0), mesh.vertex(p, 1), mesh.vertex(p, 2), ray).t;
    }
    return *c.exact_t;
  };
  size_t bi = 0;
  for (size_t k = 1; k < cands.size(); ++k)
    if (cands[k].t < cands[bi].t) bi = k;
  for (size_t k = 0; k < cands.size(); ++k) {
    if (k == bi) continue;
    Candidate& c = cands[k];
    Candidate& b = cands[bi];
    if (c.t - c.err > b.t + b.err) continue;
    const int order = ::cmp(exact_t(c), exact_t(b));
    if (order < 0) {
      bi = k;
      best.exact_tie = false;
    } else if (order == 0) {
      best.exact_tie = true;
      if (c.prim < b.prim) bi = k;
    }
  }
  return bi;
}

}  // namespace

struct OracleAccumulator::State {
  const TriangleMesh& mesh;
  const Ray ray;
  const double graze_tol;
  const RayD rd;
  const double tmin, tmax;
  OracleHit best;
  std::vector<Candidate> cands;
  State(const TriangleMesh& m, const Ray& r, double tol)
      : mesh(m), ray(r), graze_tol(tol), rd(r), tmin(r.tmin), tmax(effective_tmax(r)) {}
};

OracleAccumulator::OracleAccumulator(const TriangleMesh& mesh, const Ray& ray, double graze_tol)
    : state_(std::make_unique<State>(mesh, ray, graze_tol)), ray_valid_(ray_is_valid(ray)) {}

OracleAccumulator::~OracleAccumulator() = default;

bool OracleAccumulator::grazing() const { return state_->best.grazing; }

void OracleAccumulator::add(uint32_t i) { add_triangle(i, false); }

void OracleAccumulator::add_degenerate(uint32_t i) { add_triangle(i, true); }

void OracleAccumulator::add_triangle(uint32_t i, bool never_crosses) {
  State& st = *state_;
  const TriangleMesh& mesh = st.mesh;
  const Ray& ray = st.ray;
  const RayD& rd = st.rd;
  const double graze_tol = st.graze_tol, tmin = st.tmin, tmax = st.tmax;
  OracleHit& best = st.best;
  const Vec3f &p0 = mesh.vertex(i, 0), &p1 = mesh.vertex(i, 1), &p2 = mesh.vertex(i, 2);
  const DoubleEval d = double_eval(rd, p0, p1, p2);
  const double t_slack = t_slack_for(graze_tol, d.t, rd, p0, p1, p2);
  const bool near_range = d.t >= tmin - t_slack && d.t <= tmax + t_slack;
  // Grazing: within graze_tol of an edge, or of tmin/tmax, or in the plane.
  if (std::fabs(d.det) <= d.err_det) {
    const bool all_small = std::fabs(d.u) <= d.err_edge[0] * 1e3 && std::fabs(d.v) <= d.err_edge[1] * 1e3 &&
                           std::fabs(d.w) <= d.err_edge[2] * 1e3;
    if (all_small) {
      // Lying in (or within rounding of) the plane: grazing if the segment
      // comes near the triangle's bounds.
      if (segment_near_box(rd, tmin, tmax, mesh.triangle_bounds(i))) best.grazing = true;
    }
  }
  if (std::isfinite(d.t) && near_range && std::fabs(d.margin) < graze_tol) best.grazing = true;
  if (std::isfinite(d.t) && near_range && d.margin >= -graze_tol &&
      (std::fabs(d.t - tmin) < t_slack || std::fabs(d.t - tmax) < t_slack))
    best.grazing = true;

  if (d.certain_miss || never_crosses) return;
  Candidate c{i, d.t, d.err_t, std::nullopt};
  bool crosses;
  std::optional<bool> in = d.uncertain ? std::nullopt : double_in_range(d.t, d.err_t, ray);
  if (in) {
    crosses = *in;
  } else {
    best.exact_used = true;
    const ExactEval e = exact_eval(p0, p1, p2, ray);
    crosses = e.crosses_line && exact_in_range(e.t, ray);
    if (crosses) {
      c.exact_t = e.t;
      c.t = e.t.get_d();
      c.err = 0.0;
    }
  }
  if (!crosses) return;
  if (d.margin >= graze_tol && !(std::fabs(d.t - tmin) < t_slack || std::fabs(d.t - tmax) < t_slack))
    best.robust_hit = true;
  st.cands.push_back(std::move(c));
}

OracleHit OracleAccumulator::finish() {
  State& st = *state_;
  OracleHit best = st.best;
  if (!ray_valid_ || st.cands.empty()) return best;
  // In id order, as the loop over every triangle finds them.
  std::sort(st.cands.begin(), st.cands.end(), [](const Candidate& a, const Candidate& b) { return a.prim < b.prim; });
  const size_t bi = nearest_candidate(st.mesh, st.ray, st.cands, best);
  best.valid = true;
  best.t = st.cands[bi].t;
  best.prim = st.cands[bi].prim;
  return best;
}

double watertight_distance_error(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Ray& ray) {
  constexpr double u = 0x1p-24;  // float's unit roundoff
  const Vec3d o = ray.org.cast<double>(), d = ray.dir.cast<double>();
  // The kernel's frame: kz the dominant axis (which of two equal axes does not
  // change the bound's order), the shear S = d_kx / d_kz, d_ky / d_kz.
  int kz = 0;
  for (int k = 1; k < 3; ++k)
    if (std::fabs(d[k]) > std::fabs(d[kz])) kz = k;
  const int kx = (kz + 1) % 3, ky = (kz + 2) % 3;
  if (d[kz] == 0.0) return std::numeric_limits<double>::infinity();
  const double sz = 1.0 / d[kz], sx = d[kx] * sz, sy = d[ky] * sz;
  // Translated vertices (exact in double for float inputs of similar scale),
  // their sheared 2D coordinates and each coordinate's error: the
  // translation's rounding (u |a|), the fma's (u |X|) and the shear factor's
  // (two roundings, 2u |S a_z|).
  struct P2 {
    double x, y, z, ex, ey, ez;
  };
  auto shear = [&](const Vec3f& p) {
    const Vec3d a = p.cast<double>() - o;
    P2 q;
    q.x = a[kx] - sx * a[kz];
    q.y = a[ky] - sy * a[kz];
    q.z = a[kz];
    q.ex = u * (std::fabs(q.x) + std::fabs(a[kx]) + 3.0 * std::fabs(sx * a[kz]));
    q.ey = u * (std::fabs(q.y) + std::fabs(a[ky]) + 3.0 * std::fabs(sy * a[kz]));
    q.ez = u * std::fabs(a[kz]);
    return q;
  };
  const P2 A = shear(p0), B = shear(p1), C = shear(p2);
  // Edge function e = q.x r.y - q.y r.x: the inputs' errors times the other
  // factors, a rounding per product and one for the difference.
  auto edge = [&](const P2& q, const P2& r, double& err) {
    const double m1 = q.x * r.y, m2 = q.y * r.x, e = m1 - m2;
    err = std::fabs(r.y) * q.ex + std::fabs(q.x) * r.ey + std::fabs(r.x) * q.ey + std::fabs(q.y) * r.ex +
          u * (std::fabs(m1) + std::fabs(m2) + std::fabs(e));
    return e;
  };
  double eu, ev, ew;
  const double U = edge(C, B, eu), V = edge(A, C, ev), W = edge(B, A, ew);
  const double det = U + V + W;
  const double edet = eu + ev + ew + 2.0 * u * (std::fabs(U) + std::fabs(V) + std::fabs(W));
  const double T = U * A.z + V * B.z + W * C.z;
  const double eT = std::fabs(A.z) * eu + std::fabs(B.z) * ev + std::fabs(C.z) * ew +
                    std::fabs(U) * A.ez + std::fabs(V) * B.ez + std::fabs(W) * C.ez +
                    3.0 * u * (std::fabs(U * A.z) + std::fabs(V * B.z) + std::fabs(W * C.z));
  if (!(std::fabs(det) > 2.0 * edet) || T == 0.0) return std::numeric_limits<double>::infinity();
  const double t = sz * T / det;
  // Relative errors add: T's, det's, and the roundings of sz, the product
  // with sz, the reciprocal of det and the final product.
  const double rel = eT / std::fabs(T) + edet / std::fabs(det) + 4.0 * u;
  return 2.0 * std::fabs(t) * rel;
}

OracleHit oracle_closest_hit(const TriangleMesh& mesh, const Ray& ray, double graze_tol) {
  OracleAccumulator acc(mesh, ray, graze_tol);
  if (!acc.ray_valid()) return OracleHit{};
  for (size_t i = 0; i < mesh.num_triangles(); ++i) acc.add(static_cast<uint32_t>(i));
  return acc.finish();
}

bool same_distance(double a, double b, double tol) {
  return std::fabs(a - b) <= tol * std::max({std::fabs(a), std::fabs(b), 1e-30});
}

Verdict oracle_judge(const TriangleMesh& mesh, const Ray& ray, const Hit& hit, const OracleHit& truth, double tie_tol,
                     double graze_tol) {
  if (!hit.valid()) {
    if (!truth.valid) return Verdict::Correct;
    return truth.robust_hit ? Verdict::Wrong : Verdict::Tie;
  }
  if (truth.valid && hit.prim == truth.prim) return Verdict::Correct;
  if (hit.prim >= mesh.num_triangles()) return Verdict::Wrong;
  const OracleTriangle p = oracle_triangle(mesh, ray, hit.prim);
  if (p.crosses) {
    // A crossing triangle; right if it is (one of) the nearest, or nearer
    // than float arithmetic can tell apart.
    if (truth.valid && same_distance(p.t, truth.t, tie_tol)) return Verdict::Tie;
    if (truth.valid) {
      const double err = watertight_distance_error(mesh.vertex(hit.prim, 0), mesh.vertex(hit.prim, 1),
                                                   mesh.vertex(hit.prim, 2), ray) +
                         watertight_distance_error(mesh.vertex(truth.prim, 0), mesh.vertex(truth.prim, 1),
                                                   mesh.vertex(truth.prim, 2), ray);
      if (std::fabs(p.t - truth.t) <= err) return Verdict::Tie;
    }
    return truth.grazing ? Verdict::Tie : Verdict::Wrong;
  }
  // Not crossed exactly: a tie only if it is a near miss (edge or range) or in plane.
  if (p.coplanar) return Verdict::Tie;
  const double t_slack = t_slack_for(graze_tol, p.t, RayD(ray), mesh.vertex(hit.prim, 0), mesh.vertex(hit.prim, 1),
                                     mesh.vertex(hit.prim, 2));
  const bool near_range = p.t >= ray.tmin - t_slack && p.t <= ray.tmax + t_slack;
  if (near_range && p.margin > -graze_tol) return Verdict::Tie;
  return Verdict::Wrong;
}

Verdict oracle_judge_occluded(const Ray& /*ray*/, bool occluded, const OracleHit& truth) {
  if (occluded == truth.valid) return Verdict::Correct;
  if (!occluded) return truth.robust_hit ? Verdict::Wrong : Verdict::Tie;
  return truth.grazing ? Verdict::Tie : Verdict::Wrong;
}

}  // namespace raylab
