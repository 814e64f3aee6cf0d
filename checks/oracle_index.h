#pragma once
// A bounding-volume hierarchy over a mesh's triangles that lets the exact
// oracle (checks/oracle.h) test only the triangles that can change its
// answer, with the same answer as the loop over every triangle: the same
// valid, prim, t (bitwise), grazing, robust_hit and exact_tie. Only
// exact_used may differ: it says whether exact arithmetic decided one of the
// triangles looked at, and fewer are looked at.
//
// What must be looked at. The answer's crossings, robust_hit and exact_tie
// come from the triangles the ray exactly crosses within [tmin, tmax]; they
// lie in the boxes the segment meets. `grazing` is an or over all triangles,
// so once it is set nothing more is needed for it; until then every triangle
// that could set it must be tested. A triangle sets it (oracle.cpp) when
//  (G1) the ray lies within rounding of its plane and the segment comes
//       within 1e-6 of the coordinates of its bounds: again local to the
//       segment, or
//  (G2, G3) its line-plane distance t is "near range" (within t_slack =
//       tol max(|t|, s/|d|) of [tmin, tmax], s the largest coordinate) and
//       every relative edge function s E_k / (|d| |v_i| |v_j|) >= -tol
//       (v: vertices relative to the origin, E_k = d.(v_i x v_j), s the sign
//       of det = E_0 + E_1 + E_2).
// The second is not local to the ray. For a far triangle seen edge-on (its
// plane passing near the origin and nearly containing d) all three relative
// edge functions are small wherever the triangle lies in its plane, so the
// region that can be grazing is not a tube around the ray; the index keeps a
// cone of normals per node to bound it. The bound (per node: box B, normal
// cone of axis n0 and half-angle beta, smallest altitude h of the triangles
// below, R the farthest distance from the origin to B):
//
//   The point P = o + t d where the line meets the plane has barycentric
//   coordinates lambda_k = E_k / det, so s E_k >= -tol |d| R^2 gives
//   lambda_k >= -tol R^2 / (2 A c), with A the area and c = |cos| of the
//   angle between d and the normal (|det| = |d| 2A c). At most two are
//   negative, and P lies within sum(lambda_k^-) L_max of the triangle, so
//     dist(P, triangle) <= 2 tol R^2 / (h c),   h = 2A / L_max,
//   the smallest altitude. (For a triangle of size L at distance t facing
//   the ray that is the tube of radius ~ tol t^2 / L; it grows as the ray
//   turns parallel to the plane.) c >= c_lo = cos(angle(d, n0) + beta) over
//   the cone. And t = n.(X - o) / n.d for any X in the plane: with n in the
//   cone and X in B this gives an interval of t for the node.
//
//   Nearly parallel rays (c small) are bounded by the plane's distance H
//   from the origin instead. Write v_k = H n + w_k (w_k in the plane); then
//   E_k = H |d_par| (m.e_k) + (d.n) n.(w_i x w_j), e_k the edge, m the unit
//   in-plane direction across d's projection. The first terms sum to zero
//   and the largest is at least H |d_par| W with W >= h the triangle's width
//   across m, so one of them, whatever s, is <= -H |d_par| h / 2; the second
//   is at most |d| c R^2. So margin >= -tol needs
//     |H| sqrt(1 - c^2) h / 2 <= R^2 (c + tol),
//   and with H >= H_lo over the cone and the box, every triangle with c below
//   c_edge ~ H_lo h / (2 R^2) - tol is ruled out.
//
//   So a node is skipped when, with c_min = max(c_lo, c_edge) > 0, no c in the
//   cone is at least c_min, or for each sign of n.d the t interval misses the
//   near range of [tmin, tmax], or the segment of those t values stays
//   farther than 2 tol R^2 / (h c_min) from B. Otherwise it is visited. The
//   traversal first visits the nodes the segment meets (the crossings, and
//   for most rays a grazing triangle), then, if `grazing` is still unset, the
//   others the bound keeps.
// The bound is evaluated in double with generous margins: tol is taken 1.001
// times larger (the relative edge functions are computed with errors of
// ~1e-15), the near range with twice the slack, the t interval widened by
// twice the computed det's relative error (its rounding, < 1e-14 |d| R^2,
// over |det| >= |d| h^2 c_min; no bound is used where that exceeds 1%),
// boxes padded by 1e-6 relative. Triangles without a reliable normal
// (smallest altitude below 1e-4 of the longest edge, which includes the
// degenerate ones, whose computed t is noise) are not in the tree: they are
// tested on every ray, like the brute loop does; for those whose vertices are
// exactly collinear only the grazing conditions are evaluated (they cannot be
// crossed), without exact arithmetic. A scene far from the origin whose
// vertices collapse on the float grid (terrain:n=7072 translated by 1e5) is
// mostly such triangles, and then every call still tests them all.
//
// Memory: 48-byte nodes (float box, float cone axis and sine, altitude, one
// index) over leaves of up to 16 triangles (N/6 to N/10 nodes, 5 to 10 bytes
// per triangle) and 4 bytes of triangle id per triangle: measured 10.3 bytes
// per triangle held on 2M triangles, 12.1 on 10^8, 13.8 on 5,000 to 80,000;
// ~28 while building (16 bytes per triangle of sort keys besides).
#include <cstddef>
#include <cstdint>
#include <vector>

#include "base/ray.h"
#include "base/triangle_mesh.h"
#include "checks/oracle.h"

namespace raylab {

struct OracleIndexNode {
  float lo[3], hi[3];
  float axis[3];       // normal cone axis (unit up to float rounding)
  float cone_sin;      // sine of the cone's half-angle, rounded up; 2 = no cone (normals in every direction)
  float min_altitude;  // smallest altitude of the triangles below, rounded down
  uint32_t payload;    // internal: index of the second child (the first follows the node); leaf: see below
};
static_assert(sizeof(OracleIndexNode) == 48);

class OracleIndex {
 public:
  // Builds over every triangle of `mesh` (in parallel); the mesh must outlive
  // the index and not change.
  explicit OracleIndex(const TriangleMesh& mesh);

  const std::vector<OracleIndexNode>& nodes() const { return nodes_; }
  const std::vector<uint32_t>& ids() const { return ids_; }
  // Triangles without a reliable normal, tested on every ray; those of them
  // that are exactly degenerate (never crossed: only grazing is tested).
  const std::vector<uint32_t>& unbounded() const { return unbounded_; }
  const std::vector<uint32_t>& degenerate() const { return degenerate_; }
  size_t num_triangles() const { return triangles_; }
  size_t memory_bytes() const;

  static bool is_leaf(const OracleIndexNode& n) { return (n.payload & kLeafFlag) != 0; }
  static uint32_t leaf_first(const OracleIndexNode& n) { return n.payload & kFirstMask; }
  static uint32_t leaf_count(const OracleIndexNode& n) { return ((n.payload >> kCountShift) & 15u) + 1; }

  static constexpr uint32_t kLeafFlag = 1u << 31;
  static constexpr int kCountShift = 27;
  static constexpr uint32_t kFirstMask = (1u << kCountShift) - 1;
  static constexpr uint32_t kMaxLeaf = 16;
  // Triangles addressable by a leaf (2^27 = 134,217,728).
  static constexpr size_t kMaxTriangles = size_t{1} << kCountShift;

 private:
  std::vector<OracleIndexNode> nodes_;
  std::vector<uint32_t> ids_;
  std::vector<uint32_t> unbounded_;
  std::vector<uint32_t> degenerate_;
  size_t triangles_ = 0;
};

// Bytes per triangle of building the index (the sort keys beside the result)
// and of holding it.
inline constexpr double kOracleIndexBuildBytesPerTriangle = 28.0;
inline constexpr double kOracleIndexBytesPerTriangle = 14.0;

// What a culled oracle call looked at.
struct OracleIndexStats {
  size_t nodes_visited = 0;
  size_t triangles_tested = 0;
};

// The oracle's answer (as oracle_closest_hit(mesh, ray, graze_tol)) testing
// only the triangles that can matter. `index` must have been built on `mesh`.
OracleHit oracle_closest_hit(const OracleIndex& index, const TriangleMesh& mesh, const Ray& ray,
                             double graze_tol = 1e-5, OracleIndexStats* stats = nullptr);

}  // namespace raylab
