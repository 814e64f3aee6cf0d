#pragma once
// Pieces shared by the BVH builders: build references (box + centroid +
// primitive id, one per primitive or per SBVH split fragment), a 4-lane SSE
// box for fast binning, the builder options every builder understands, and
// the SAH cost constants used to report tree quality.
//
// Builders see only boxes and centroids (the primitive is an id), so the same
// builder serves triangles, synthetic boxes in tests, or any other primitive.
// The one exception is SBVH, which must clip a primitive to a plane; it takes
// that operation as a callback (see build_sbvh.h).
#include <xmmintrin.h>

#include <cstdint>
#include <cstring>
#include <limits>
#include <span>
#include <vector>

#include "accel/bvh/bvh2_node.h"
#include "base/triangle_mesh.h"

namespace raylab {

// Axis-aligned box in two SSE registers. Lane 3 of lo is kept at 0, lane 3
// of hi at 0 or a normal or infinite float (never a denormal or a NaN), so
// arithmetic on it never is slow or invalid. A build reference keeps its
// box's half area there (BuildRef::make), and every union of references'
// boxes (extend, merge, the bins) then carries the largest of them: the
// size split's test for free (build_binned_sah.cpp).
struct Box4 {
  __m128 lo = _mm_set1_ps(std::numeric_limits<float>::infinity());
  __m128 hi = _mm_set1_ps(-std::numeric_limits<float>::infinity());

  static Box4 from(const Aabb& b) {
    Box4 r;
    r.lo = _mm_setr_ps(b.lo.x(), b.lo.y(), b.lo.z(), 0.0f);
    r.hi = _mm_setr_ps(b.hi.x(), b.hi.y(), b.hi.z(), 0.0f);
    return r;
  }
  void extend(const Box4& b) {
    lo = _mm_min_ps(lo, b.lo);
    hi = _mm_max_ps(hi, b.hi);
  }
  void extend(__m128 p) {
    lo = _mm_min_ps(lo, p);
    hi = _mm_max_ps(hi, p);
  }
  bool empty() const { return (_mm_movemask_ps(_mm_cmpgt_ps(lo, hi)) & 7) != 0; }
  // Half the surface area (0 for an empty box), the SAH's measure.
  float half_area() const {
    if (empty()) return 0.0f;
    alignas(16) float d[4];
    _mm_store_ps(d, _mm_sub_ps(hi, lo));
    return d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
  }
  float lo_at(int a) const {
    alignas(16) float v[4];
    _mm_store_ps(v, lo);
    return v[a];
  }
  // Lane 3 of hi: the largest half area of the references whose boxes
  // were merged into this box (0 for boxes not made from references).
  float max_ref_half_area() const { return _mm_cvtss_f32(_mm_shuffle_ps(hi, hi, _MM_SHUFFLE(3, 3, 3, 3))); }
  float hi_at(int a) const {
    alignas(16) float v[4];
    _mm_store_ps(v, hi);
    return v[a];
  }
  Aabb aabb() const {
    alignas(16) float l[4], h[4];
    _mm_store_ps(l, lo);
    _mm_store_ps(h, hi);
    return Aabb(Vec3f(l[0], l[1], l[2]), Vec3f(h[0], h[1], h[2]));
  }
};

inline Box4 merge(const Box4& a, const Box4& b) {
  Box4 r = a;
  r.extend(b);
  return r;
}

// One build reference: the box of a primitive (or of the part of it a spatial
// split kept), its centroid, and the primitive id stored in the centroid's
// lane 3 (as raw bits; masked off before any arithmetic). Lane 3 of the
// box's hi holds the box's half area (Box4::max_ref_half_area).
struct BuildRef {
  Box4 box;
  __m128 c;

  uint32_t prim() const {
    alignas(16) uint32_t v[4];
    _mm_store_ps(reinterpret_cast<float*>(v), c);
    return v[3];
  }
  // Centroid with lane 3 cleared.
  __m128 centroid() const { return _mm_and_ps(c, xyz_mask()); }
  static __m128 xyz_mask() {
    const __m128i m = _mm_setr_epi32(-1, -1, -1, 0);
    return _mm_castsi128_ps(m);
  }
  static BuildRef make(const Aabb& b, const Vec3f& centroid, uint32_t prim) {
    BuildRef r;
    r.box = Box4::from(b);
    // The same arithmetic as Box4::half_area, so that a comparison of the
    // stored value decides as one of half_area() would; denormals rounded up
    // to the smallest normal float (an upper bound stays an upper bound).
    const float area = r.box.half_area();
    alignas(16) float hi[4];
    _mm_store_ps(hi, r.box.hi);
    hi[3] = area > 0.0f && area < std::numeric_limits<float>::min() ? std::numeric_limits<float>::min() : area;
    r.box.hi = _mm_load_ps(hi);
    float bits;
    std::memcpy(&bits, &prim, sizeof bits);
    r.c = _mm_setr_ps(centroid.x(), centroid.y(), centroid.z(), bits);
    return r;
  }
};

// One reference per primitive, built in parallel.
std::vector<BuildRef> make_build_refs(std::span<const Aabb> boxes, std::span<const Vec3f> centroids);

// One reference per triangle, its box (centroid: the box's centre), built in
// parallel: the binned builder's input. The triangle boxes are computed here,
// not kept in an array of their own (fresh pages cost page faults).
std::vector<BuildRef> triangle_build_refs(const TriangleMesh& mesh);

// Options shared by the top-down builders.
struct BuildOptions {
  int bins = 64;          // bins per axis (binned SAH, SBVH; nodes under 1024 references use fewer, build_binned_sah.cpp)
  int max_leaf = 1;       // leaves never hold more references than this
  // Ranges of at most this many references always become leaves (no SAH
  // test): the SAH-optimal collapse merges small leaves anyway, so building
  // the last levels of single-reference leaves is mostly wasted time.
  int leaf_threshold = 1;
  int start_depth = 0;    // depth of the root (when building a subtree of a larger tree)
  float traversal_cost = 1.0f;     // C_t used for split decisions
  float intersection_cost = 1.0f;  // C_i used for split decisions (per reference)
  // Large references in a child of their own (binned builder only; 0 = off):
  // at a node of at least big_min references, those whose boxes' half areas
  // exceed big_node x the node's, or big_root x the root's, become one child
  // and the rest the other, when they are at least one and at most a quarter
  // of the node's references. Centroid splits never separate references by
  // size, so a floor or a wall otherwise stretches the box of every node on
  // its way down (build_binned_sah.cpp; measured in docs/structures/bvh.md).
  float big_node = 0.0f;
  float big_root = 0.0f;
  size_t big_min = 1024;
};

// Beyond this depth top-down builders split at the object median, so depth and
// traversal stacks stay bounded on pathological input.
inline constexpr int kForceMedianDepth = 96;
// Trees deeper than this are rejected by the traversal layouts (stack size).
inline constexpr int kMaxTreeDepth = 128;

// Fills a binary leaf node.
inline void set_leaf(Bvh2Node& n, const Aabb& b, uint32_t first, uint32_t count) {
  n.set_bounds(b);
  n.index = first;
  n.count = count;
}

// The start of the top-down builders: room for n references and the at most
// 2n - 1 nodes (plus one); an empty input becomes one empty leaf. Returns
// false when there is nothing to build.
inline bool start_binary_bvh(BinaryBvh& out, size_t n) {
  out.prim_ids.resize(n);
  if (n == 0) {
    out.nodes.resize(1);
    set_leaf(out.nodes[0], Aabb::empty(), 0, 0);
    return false;
  }
  out.nodes.resize(2 * n);
  return true;
}

// Number of references below each node (for inner nodes the sum over the
// subtree), indexed like nodes. Children must have larger indices than parents.
std::vector<uint32_t> subtree_ref_counts(std::span<const Bvh2Node> nodes);

// Re-lays a binary tree in depth-first order (left subtree right after its
// parent's sibling pair), which keeps the children-after-parent invariant.
BinaryBvh relayout_depth_first(const BinaryBvh& in);

}  // namespace raylab
