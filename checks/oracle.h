#pragma once
// Independent referee for disagreements between an accelerator and Embree:
// brute force over every triangle.
//
// Each triangle is first tested in double precision with the three signed
// volumes of the ray and the triangle's edges (Pluecker-style edge functions,
// U for the edge opposite p0, V opposite p1, W opposite p2): the line crosses
// the closed triangle iff they do not have opposite signs and are not all
// zero, and t = [a, b, c] / (U + V + W) with a, b, c the vertices relative to
// the origin. Where double precision cannot decide - an edge function within
// its error bound of zero (a ray through an edge or a vertex), or a distance
// that close to tmin, tmax or to another candidate's - the decision is made
// again with exact rational arithmetic (GMP) on the ray's exact float origin
// and direction and the triangle's exact float vertices. So the oracle says
// exactly whether the float ray crosses each triangle and which one is
// nearest.
//
// `grazing` marks rays whose answer float arithmetic may legitimately get
// either way: an edge function of the nearest crossing is within `graze_tol`
// of zero relative to its scale |dir| |b| |c| (the scale of its float
// rounding error: about 1e-7 of it), or the distance is within graze_tol
// (relative to t and to the coordinates' magnitude over |dir|) of tmin or
// tmax, or the ray passes that close to a triangle it does not cross, or lies
// in a triangle's plane.
#include <cstdint>
#include <memory>

#include "base/hit.h"
#include "base/ray.h"
#include "base/triangle_mesh.h"

namespace raylab {

struct OracleHit {
  bool valid = false;       // the ray exactly crosses some triangle within [tmin, tmax]
  double t = 0.0;           // nearest crossing (rounded to double)
  uint32_t prim = kInvalidPrim;
  bool grazing = false;     // some triangle is within graze_tol of being crossed or missed
  bool robust_hit = false;  // some crossing is not grazing: any correct answer hits something
  bool exact_used = false;  // exact arithmetic decided at least one triangle
  bool exact_tie = false;   // two triangles cross at exactly the same nearest distance
};

OracleHit oracle_closest_hit(const TriangleMesh& mesh, const Ray& ray, double graze_tol = 1e-5);

// The oracle's answer built one triangle at a time: oracle_closest_hit adds
// every triangle, a culled search (checks/oracle_index.h) only those that can
// matter. The answer does not depend on the order in which triangles are
// added (the crossings are ordered by id before the nearest is chosen), so it
// is the same for any set of triangles that holds every crossing and, unless
// `grazing` is already set, every triangle that can set it.
class OracleAccumulator {
 public:
  OracleAccumulator(const TriangleMesh& mesh, const Ray& ray, double graze_tol);
  ~OracleAccumulator();
  OracleAccumulator(const OracleAccumulator&) = delete;
  OracleAccumulator& operator=(const OracleAccumulator&) = delete;

  bool ray_valid() const { return ray_valid_; }
  // Tests one triangle (each at most once): a crossing becomes a candidate,
  // and `grazing`, `robust_hit` and `exact_used` are updated.
  void add(uint32_t prim);
  // The same for a triangle whose float vertices are exactly collinear
  // (oracle_triangle_is_exactly_degenerate): it is never crossed (its
  // determinant is exactly zero), so only `grazing` can change, and no
  // exact arithmetic is needed.
  void add_degenerate(uint32_t prim);
  bool grazing() const;
  // The answer over the triangles added.
  OracleHit finish();

 private:
  void add_triangle(uint32_t prim, bool never_crosses);

  struct State;
  std::unique_ptr<State> state_;
  bool ray_valid_ = false;
};

// One triangle against one ray, decided as by oracle_closest_hit.
struct OracleTriangle {
  bool crosses = false;  // crosses the closed triangle with t in [tmin, tmax] (exact)
  bool coplanar = false; // the ray lies in the triangle's plane
  double t = 0.0;        // crossing distance of the line (rounded), when not parallel
  double margin = 0.0;   // relative edge-function margin (approximate): > 0 inside, < 0 outside
  bool exact_used = false;
};
OracleTriangle oracle_triangle(const TriangleMesh& mesh, const Ray& ray, uint32_t prim);

// True when the triangle's float vertices are provably collinear (or
// repeated): the edge vectors and their cross product's terms are computed
// in double and checked to be exact, so "true" is certain; false when not
// collinear or when that could not be shown this way.
bool oracle_triangle_is_exactly_degenerate(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2);

// Exact decision alone (always GMP), for tests and for the leak test.
OracleTriangle oracle_triangle_exact(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Ray& ray);

// Relative distance under which two hits on different triangles are a tie
// (the one tolerance of verify, stress and bench, see classify.h).
inline constexpr double kTieTolerance = 1e-4;

// |a - b| within tol relative to the larger magnitude.
bool same_distance(double a, double b, double tol = kTieTolerance);

// A bound on |t - t_line| for the distance t that the float watertight test
// (accel/core/intersect_triangle.h) computes for this ray and triangle, t_line
// being the exact distance to the triangle's plane. First-order propagation of
// the test's roundings (u = 2^-24 each: the translated vertices, the shear,
// the edge-function products, their sums, the weighted sum and the division),
// doubled to cover the second-order terms. It is small for a well-shaped
// triangle (a few ulps of t) and large for a needle or a grazing ray, whose
// projected area (det) is a difference of nearly equal products. A worst
// case: on the needles scene a needle 1e-4 wide and 1 long, at t = 0.30,
// comes out 4.7e-5 nearer than it is, against a bound of 0.011 (its two close
// vertices round alike, which the bound cannot assume). Infinite when the
// bound exceeds half of det itself.
double watertight_distance_error(const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, const Ray& ray);

enum class Verdict : uint8_t { Correct, Tie, Wrong };

// Judges one closest-hit answer against the oracle's `truth` for the ray:
// Correct when it names the nearest triangle (or a miss when there is none);
// Tie when it differs only where float arithmetic may (a triangle at the same
// distance within `tie_tol` relative, or within the two triangles' float
// distance errors by watertight_distance_error - a float kernel orders two
// crossings by their computed distances and cannot order them closer than
// that -, or a grazing ray); Wrong otherwise.
Verdict oracle_judge(const TriangleMesh& mesh, const Ray& ray, const Hit& hit, const OracleHit& truth,
                     double tie_tol = kTieTolerance, double graze_tol = 1e-5);

// The same for an any-hit (occlusion) answer.
Verdict oracle_judge_occluded(const Ray& ray, bool occluded, const OracleHit& truth);

}  // namespace raylab
