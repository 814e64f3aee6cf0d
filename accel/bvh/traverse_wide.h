#pragma once
// Single-ray traversal of the N-wide BVH (N = 4, 8 or 16) with W-wide triangle
// blocks. One routine serves closest hit and any hit (kAnyHit, which returns
// at the first hit) and the instrumented variant (kCount); both are template
// parameters, so the uninstrumented kernels pay nothing.
//
// Per node: all N child boxes are tested at once with a conservative slab
// test. With FMA hardware each plane distance is one fused multiply-add,
// t = x * inv_d - (o * inv_d), where the per-ray product o * inv_d is rounded
// up for near planes and down for far planes. Rounding is monotonic, so the
// computed near distance never exceeds round((x - o) * inv_d) and the far one
// never falls below it: each is at least as accurate as the subtract-then-
// multiply form of Ize ("Robust BVH Ray Traversal", JCGT 2013), whose far
// scaling by 1 + 2*gamma(3) therefore still guarantees that no box the ray
// really crosses is missed. The reductions use integer min/max on the float
// bits (valid for tmin >= 0, see intersect_children), and the far padding is
// applied on the bits too: 6 ulps added as an integer, never less than the
// scaling (kSlabFarPadUlps, slab_test.h), and the hit mask an integer
// comparison, so no float operation sits between the planes' FMAs and the
// mask. Rays with a (nearly)
// zero direction component or a negative tmin take the exact kernel: Ize's
// form with exact reciprocals and NaN-ignoring min/max. Without FMA every ray
// takes that form.
//
// Closest hit: one hit child is entered directly, two are ordered by one
// comparison, three or more are sorted by a short sorting network
// (sort_network.h) and pushed so the nearest is on top. Any hit: leaves
// first, then descending slot order, no sorting. Pushed children are
// prefetched. Stack entries are 64-bit keys (distance, child reference) in a
// fixed array; popped entries farther than the current closest hit are
// skipped. The triangle test's per-ray constants: closest hit computes them
// at the first leaf (many rays never reach one), any hit at the start, where
// their latency (dominant axis, a division) overlaps the first node
// tests instead of delaying the first leaf test: shadow rays leave after a
// few nodes, and this measured 1.5-3 % faster on them (2026-11-27), while
// closest hit lost 2-4 % with it (more state live through the node loop).
#include <algorithm>
#include <cfloat>
#include <cstddef>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <span>
#include <type_traits>

#include "accel/bvh/bvh_wide_node.h"
#include "accel/core/hit_recorder.h"
#include "accel/bvh/sort_network.h"
#include "accel/core/simd/triangle_block.h"
#include "accel/core/slab_test.h"

namespace raylab {

#if defined(RAYLAB_SIMD_FMA)
#define RAYLAB_HAS_FMA 1
#else
#define RAYLAB_HAS_FMA 0
#endif

// Stack capacity in entries; builds whose depth could exceed it are rejected
// (see wide_stack_fits).
inline constexpr int kWideStackSize = 1024;

template <int N>
inline bool wide_stack_fits(int max_depth) {
  return max_depth * (N - 1) + 2 * N <= kWideStackSize;
}

template <int N, int W>
struct WideView {
  const WideNode<N>* nodes = nullptr;
  const TriangleBlock<W>* blocks = nullptr;
  uint32_t root_ref = wide_ref::kEmpty;
  // Rays whose origin has a coordinate above this in magnitude take the exact
  // kernel (fma_origin_limit below).
  float fma_origin_limit = FLT_MAX;
};

// The FMA box test bounds o * inv by |o * inv| * 2^-22, so its distances are
// only as exact as 2^-22 |o| in space: for a mesh of extent 2 at 3e5 from the
// origin that is 0.07, larger than the nodes near the leaves, and every ray
// entered far more boxes than it crosses (118 triangle tests per primary ray
// instead of 3; 0.08x Embree). Ize's subtract-then-multiply form computes
// x - o exactly when both are close (Sterbenz), so its error is relative to the
// distance, not to the coordinates. Rays whose origin is more than 64 scene
// extents from the coordinate origin (2^-22 |o| > 2^-16 of the extent) take it.
inline float wide_fma_origin_limit(const Aabb& root_box) {
  if (root_box.is_empty()) return FLT_MAX;
  const Vec3f extent = root_box.hi - root_box.lo;
  const float side = std::max(extent.x(), std::max(extent.y(), extent.z()));
  // At most FLT_MAX, so that an origin within the limit is finite (ray_takes_fma_kernel).
  return side > 0.0f ? std::min(64.0f * side, FLT_MAX) : 0.0f;
}

inline bool origin_beyond(const Ray& r, float limit) {
  return std::fabs(r.org.x()) > limit || std::fabs(r.org.y()) > limit || std::fabs(r.org.z()) > limit;
}

// Per-ray constants of the child-box test.
template <int N>
struct WideNodeRay {
  using V = simd::vfloat<N>;
  V inv[3];
#if defined(RAYLAB_SIMD_FMA)
  V near_shift[3], far_shift[3];  // -(o * inv) rounded so near shrinks and far grows
#endif
  V org[3];
  int near_off[3], far_off[3];  // float offsets of the near / far plane arrays in a node
};

// True when some direction component is (nearly) zero. Such a ray can lie
// exactly in a box's face plane, where (hi - o) * (1 / tiny) = 0 would end
// the slab at t = 0; these rays take the exact-reciprocal kernel instead:
// 1 / +-0 = +-inf, and the 0 * inf = NaN of a ray in a face plane is dropped
// by NaN-ignoring min/max, which leaves that slab unbounded, as it should be.
inline bool ray_is_axis_parallel(const Ray& r) {
  constexpr float kTiny = 1e-30f;  // as the clamp of init_node_ray
  return std::fabs(r.dir.x()) < kTiny || std::fabs(r.dir.y()) < kTiny || std::fabs(r.dir.z()) < kTiny;
}

// True when a ray may take the FMA kernel: every direction component at
// least 1e-30 and finite (so not axis-parallel, see ray_is_axis_parallel, and
// not zero), every origin component within `limit` (at most FLT_MAX, so
// finite; origin_beyond), 0 <= tmin <= tmax and tmin finite. That is
// ray_is_valid && !ray_is_axis_parallel && tmin >= 0 && !origin_beyond, with
// NaN failing every comparison. It is the prologue of every ray, so with SSE4.1
// it is three vector comparisons on the ray's two halves and one branch
// instead of a dozen scalar ones: on rays that leave the scene after one
// node, the scalar checks were about a quarter of the time. Rays that fail
// it take the checks one by one.
inline bool ray_takes_fma_kernel(const Ray& r, float limit) {
#if defined(__SSE4_1__)
  const RayLanes l(r);
  // |ox| |oy| |oz| tmin <= limit limit limit tmax
  const __m128 ok_org = _mm_cmple_ps(l.abs_org_tmin, _mm_blend_ps(_mm_set1_ps(limit), l.dir_tmax, 8));
  // |dx| |dy| |dz| tmin >= 1e-30 1e-30 1e-30 0, and <= FLT_MAX
  const __m128 ok_lo = _mm_cmpge_ps(l.abs_dir_tmin, _mm_setr_ps(1e-30f, 1e-30f, 1e-30f, 0.0f));
  const __m128 ok_hi = _mm_cmple_ps(l.abs_dir_tmin, _mm_set1_ps(FLT_MAX));
  return RayLanes::all(_mm_and_ps(_mm_and_ps(ok_org, ok_lo), ok_hi));
#else
  return ray_is_valid(r) && !ray_is_axis_parallel(r) && r.tmin >= 0.0f && !origin_beyond(r, limit);
#endif
}

#if defined(__AVX__)
// The box test's per-ray scalars in lanes x, y, z: reciprocals and the
// bounds of o * inv (init_node_ray). A batch computes the next ray's while
// the current one walks (trace_rays_ahead): the division and the three
// dependent operations after it were otherwise the first thing each walk
// waited for, after the mispredicted exit of the walk before.
struct NodeRayScalars {
  __m128 inv, up, down;
};

[[gnu::always_inline]] inline NodeRayScalars node_ray_scalars(const Ray& r, bool axis_parallel) {
  const __m128 d = _mm_setr_ps(r.dir.x(), r.dir.y(), r.dir.z(), 1.0f);
  const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7FFFFFFF));
  // Safe reciprocals: components below 1e-30 in magnitude become +-1e-30.
  const __m128 tiny = _mm_set1_ps(1e-30f);
  const __m128 small = _mm_cmplt_ps(_mm_and_ps(d, abs_mask), tiny);
  const __m128 signed_tiny = _mm_or_ps(tiny, _mm_andnot_ps(abs_mask, d));
  const __m128 inv4 = _mm_div_ps(_mm_set1_ps(1.0f), axis_parallel ? d : _mm_blendv_ps(d, signed_tiny, small));
  // o * inv bounded from above and below: |oi| * 2^-22 exceeds one ulp, and
  // FLT_MIN keeps the bounds off zero and out of the denormals. Overflow to
  // infinity is kept (up) or clamped to FLT_MAX (down) by NaN-first min/max.
  const __m128 o = _mm_setr_ps(r.org.x(), r.org.y(), r.org.z(), 0.0f);
  const __m128 oi = _mm_mul_ps(o, inv4);
  const __m128 delta = _mm_add_ps(_mm_mul_ps(_mm_and_ps(oi, abs_mask), _mm_set1_ps(0x1p-22f)), _mm_set1_ps(FLT_MIN));
  const __m128 up = _mm_max_ps(_mm_add_ps(oi, delta), _mm_set1_ps(-FLT_MAX));
  const __m128 down = _mm_min_ps(_mm_sub_ps(oi, delta), _mm_set1_ps(FLT_MAX));
  return {inv4, up, down};
}
#else
struct NodeRayScalars {};
#endif

// Per-ray constants of the box test: the reciprocals of the slab test (as
// SlabRay: safe reciprocals, or exact ones for axis_parallel rays, see
// ray_is_axis_parallel) and the bounds of o * inv. Division is correctly
// rounded in vector or scalar form, so the values are the scalar code's.
// Built without branches when AVX is available: setup is a large share of a
// short ray's cost. (The triangle test's constants: see the top of this file.)
// inv_out (optional, 4 floats): the scalar reciprocals, for the triangle test's set-up.
// ahead (optional, AVX, rays that are not axis-parallel): the ray's
// node_ray_scalars, computed before (trace_rays_ahead).
template <int N>
[[gnu::always_inline]] inline void init_node_ray(WideNodeRay<N>& node, const Ray& r, bool axis_parallel,
                                                 float* inv_out = nullptr,
                                                 [[maybe_unused]] const NodeRayScalars* ahead = nullptr) {
  float inv[3], shift_up[3], shift_down[3];
#if defined(__AVX__)
  const NodeRayScalars sc = ahead && !axis_parallel ? *ahead : node_ray_scalars(r, axis_parallel);
  const __m128 inv4 = sc.inv, up = sc.up, down = sc.down;
  const __m128 d = _mm_setr_ps(r.dir.x(), r.dir.y(), r.dir.z(), 1.0f);
  alignas(16) float invv[4], upv[4], downv[4];
  _mm_store_ps(invv, inv4);
  if (inv_out) _mm_storeu_ps(inv_out, inv4);
  // Exact reciprocals of components below 2^-128 overflow: NaN, as SlabRay.
  if (axis_parallel)
    for (int a = 0; a < 3; ++a) invv[a] = safe_slab_reciprocal(r.dir[a]);
  _mm_store_ps(upv, up);
  _mm_store_ps(downv, down);
  for (int a = 0; a < 3; ++a) inv[a] = invv[a], shift_up[a] = upv[a], shift_down[a] = downv[a];
  const int neg_mask = _mm_movemask_ps(d);
#else
  // Exact reciprocals for every ray (SlabRay): what axis-parallel rays need,
  // and without AVX there is no FMA kernel that would want the clamped ones.
  (void)axis_parallel;
  (void)inv_out;  // the triangle set-up divides for itself (kShareReciprocal)
  const SlabRay sr(r);
  int neg_mask = 0;
  for (int a = 0; a < 3; ++a) {
    inv[a] = sr.inv_dir[a];
    neg_mask |= sr.neg[a] << a;
    const float oi = r.org[a] * inv[a];
    const float delta = std::fabs(oi) * 0x1p-22f + FLT_MIN;
    const float u = oi + delta, dn = oi - delta;
    shift_up[a] = u == u ? u : -FLT_MAX;
    shift_down[a] = dn == dn ? dn : FLT_MAX;
  }
#endif
  using V = simd::vfloat<N>;
  for (int a = 0; a < 3; ++a) {
    const int neg = (neg_mask >> a) & 1;
    node.inv[a] = V::broadcast(inv[a]);
    node.near_off[a] = (2 * a + neg) * N;
    node.far_off[a] = (2 * a + 1 - neg) * N;
#if defined(RAYLAB_SIMD_FMA)
    node.near_shift[a] = V::broadcast(-shift_up[a]);
    node.far_shift[a] = V::broadcast(-shift_down[a]);
#else
    (void)shift_up;
    (void)shift_down;
#endif
    node.org[a] = V::broadcast(r.org[a]);
  }
}

// The FMA kernels' hit mask: tnear <= tfar padded by kSlabFarPadUlps on the
// bits, computed as tnear < tfar + (kSlabFarPadUlps + 1) in the integer
// order: the same mask without the complement of a <= comparison, two
// instructions off every node's critical path (+1.6 % in raylab bench). tfar
// is at most the bits of +inf (no NaN: finite reciprocals and shifts), so
// the addition does not overflow.
template <typename V>
[[gnu::always_inline]] inline uint32_t padded_slab_mask(V tnear, V tfar) {
  return cmp_lt_bits(tnear, add_ulps(tfar, kSlabFarPadUlps + 1));
}

// The planes at float offset `off` of a node (off = plane * N, as
// WideNodeRay's offsets).
template <int N>
[[gnu::always_inline]] inline simd::vfloat<N> node_planes(const WideNode<N>& node, int off) {
  return simd::vfloat<N>::load(&node.bounds[0][0] + off);
}

// The float offset of axis a's near (or far) planes in a node: the ray's, or
// for a walk specialised to one direction octant a constant (the same value:
// init_node_ray's offsets from the direction's sign bits).
template <int N, int kOctant, bool kNear>
[[gnu::always_inline]] inline int wide_plane_offset(const WideNodeRay<N>& r, int a) {
  if constexpr (kOctant < 0) {
    return kNear ? r.near_off[a] : r.far_off[a];
  } else {
    const int neg = (kOctant >> a) & 1;
    return (2 * a + (kNear ? neg : 1 - neg)) * N;
  }
}

// Tests the N child boxes of a node; returns the mask of children whose
// (padded) slab interval overlaps [tmin, tmax], and their entry distances.
// kExact: Ize's subtract-then-multiply form, with every possibly-NaN operand
// first in min/max (x86 min/max return the second operand when one is NaN),
// for axis-parallel rays and builds without FMA.
// kOctant: -1, or the ray's direction octant (bit a set when dir[a] is
// negative, as init_node_ray's sign mask), which makes the plane offsets
// constants (traverse_wide_octant below).
template <int N, bool kExact, int kOctant = -1>
[[gnu::always_inline]] inline uint32_t intersect_children(const WideNode<N>& node, const WideNodeRay<N>& r,
                                                          simd::vfloat<N> tmin, simd::vfloat<N> tmax,
                                                          simd::vfloat<N>& tnear) {
  using V = simd::vfloat<N>;
  const auto plane = [&](int off) { return node_planes(node, off); };
  // tmax is padded like the far planes: the computed entry distance may
  // exceed the true one by a few ulps, and a box holding a hit closer than
  // the current one by less than that must not be culled.
#if defined(RAYLAB_SIMD_FMA)
  if constexpr (!kExact) {
    const V nx = fmadd(plane(wide_plane_offset<N, kOctant, true>(r, 0)), r.inv[0], r.near_shift[0]);
    const V ny = fmadd(plane(wide_plane_offset<N, kOctant, true>(r, 1)), r.inv[1], r.near_shift[1]);
    const V nz = fmadd(plane(wide_plane_offset<N, kOctant, true>(r, 2)), r.inv[2], r.near_shift[2]);
    const V fx = fmadd(plane(wide_plane_offset<N, kOctant, false>(r, 0)), r.inv[0], r.far_shift[0]);
    const V fy = fmadd(plane(wide_plane_offset<N, kOctant, false>(r, 1)), r.inv[1], r.far_shift[1]);
    const V fz = fmadd(plane(wide_plane_offset<N, kOctant, false>(r, 2)), r.inv[2], r.far_shift[2]);
    // Integer-order min/max (kernel precondition: tmin >= +0). The near
    // distance includes tmin, so its maximum is >= 0 and exact. A negative
    // far distance may not be the true minimum, but any negative one culls
    // the box exactly as the true minimum would. The FMA form never yields
    // -0 for a far plane (the shift is at least FLT_MIN away from o * inv).
    tnear = max_bits(max_bits(nx, ny), max_bits(nz, tmin));
    return padded_slab_mask(tnear, min_bits(min_bits(fx, fy), min_bits(fz, tmax)));
  }
#endif
  const V nx = (plane(wide_plane_offset<N, kOctant, true>(r, 0)) - r.org[0]) * r.inv[0];
  const V ny = (plane(wide_plane_offset<N, kOctant, true>(r, 1)) - r.org[1]) * r.inv[1];
  const V nz = (plane(wide_plane_offset<N, kOctant, true>(r, 2)) - r.org[2]) * r.inv[2];
  const V fx = (plane(wide_plane_offset<N, kOctant, false>(r, 0)) - r.org[0]) * r.inv[0];
  const V fy = (plane(wide_plane_offset<N, kOctant, false>(r, 1)) - r.org[1]) * r.inv[1];
  const V fz = (plane(wide_plane_offset<N, kOctant, false>(r, 2)) - r.org[2]) * r.inv[2];
  tnear = max(nx, max(ny, max(nz, tmin)));
  const V tfar0 = min(fx, min(fy, min(fz, tmax)));
  // Padded outward in both signs (negative far distances arise when tmin < 0).
  const V tfar = max(tfar0 * V::broadcast(kSlabFarScale), tfar0 * V::broadcast(kSlabFarScaleNeg));
  return cmp_le(tnear, tfar);
}

// The scalar counterpart of intersect_children (`bvh:simd=0`, the
// algorithm-only comparison): the same tree and walk with one
// child box at a time, computing lane by lane what the vector test computes
// (the same FMA or subtract-then-multiply, the same integer-order or NaN-
// ignoring min/max, the same padding), so hits and counted work are equal.
// Writes the entry distances to tnear[0, N).
struct ScalarNodeRay {
  float inv[3], near_shift[3], far_shift[3], org[3];
  int near_off[3], far_off[3];

  ScalarNodeRay() = default;
  template <int N>
  explicit ScalarNodeRay(const WideNodeRay<N>& r) {
    alignas(64) float lanes[N];
    for (int a = 0; a < 3; ++a) {
      r.inv[a].store(lanes), inv[a] = lanes[0];
      r.org[a].store(lanes), org[a] = lanes[0];
#if defined(RAYLAB_SIMD_FMA)
      r.near_shift[a].store(lanes), near_shift[a] = lanes[0];
      r.far_shift[a].store(lanes), far_shift[a] = lanes[0];
#else
      near_shift[a] = far_shift[a] = 0.0f;
#endif
      near_off[a] = r.near_off[a];
      far_off[a] = r.far_off[a];
    }
  }
};

namespace scalar_detail {
inline int32_t bits_of(float x) {
  int32_t i;
  std::memcpy(&i, &x, sizeof i);
  return i;
}
// As the vector forms: integer order of the bits, and x86 min/max (the
// second operand when either is NaN).
inline float min_bits(float a, float b) { return bits_of(a) < bits_of(b) ? a : b; }
inline float max_bits(float a, float b) { return bits_of(a) > bits_of(b) ? a : b; }
inline float min_x86(float a, float b) { return a < b ? a : b; }
inline float max_x86(float a, float b) { return a > b ? a : b; }
}  // namespace scalar_detail

// GCC vectorises the loop over the children unless told not to: the scalar
// variant must stay scalar to mean anything.
#if defined(__GNUC__) && !defined(__clang__)
#define RAYLAB_NO_VECTORIZE [[gnu::optimize("no-tree-vectorize", "no-tree-slp-vectorize")]]
#else
#define RAYLAB_NO_VECTORIZE
#endif

template <int N, bool kExact>
RAYLAB_NO_VECTORIZE inline uint32_t intersect_children_scalar(const WideNode<N>& node, const ScalarNodeRay& r, float tmin, float tmax,
                                          float* tnear) {
  using namespace scalar_detail;
  const float* b = &node.bounds[0][0];
  uint32_t mask = 0;
  for (int i = 0; i < N; ++i) {
    float n[3], f[3];
    bool hit;
#if defined(RAYLAB_SIMD_FMA)
    if constexpr (!kExact) {
      for (int a = 0; a < 3; ++a) {
        n[a] = std::fma(b[r.near_off[a] + i], r.inv[a], r.near_shift[a]);
        f[a] = std::fma(b[r.far_off[a] + i], r.inv[a], r.far_shift[a]);
      }
      tnear[i] = max_bits(max_bits(n[0], n[1]), max_bits(n[2], tmin));
      const float tfar = min_bits(min_bits(f[0], f[1]), min_bits(f[2], tmax));
      hit = bits_of(tnear[i]) <= static_cast<int32_t>(static_cast<uint32_t>(bits_of(tfar)) + kSlabFarPadUlps);
      mask |= static_cast<uint32_t>(hit) << i;
      continue;
    }
#endif
    for (int a = 0; a < 3; ++a) {
      n[a] = (b[r.near_off[a] + i] - r.org[a]) * r.inv[a];
      f[a] = (b[r.far_off[a] + i] - r.org[a]) * r.inv[a];
    }
    tnear[i] = max_x86(n[0], max_x86(n[1], max_x86(n[2], tmin)));
    const float tfar0 = min_x86(f[0], min_x86(f[1], min_x86(f[2], tmax)));
    hit = tnear[i] <= max_x86(tfar0 * kSlabFarScale, tfar0 * kSlabFarScaleNeg);
    mask |= static_cast<uint32_t>(hit) << i;
  }
  return mask;
}

// The scalar leaf (`bvh:simd=0`): each distinct triangle of each block by
// the scalar watertight test, which gives what the block test gives lane by
// lane; the recorder's rule (least (t, prim)) makes the order irrelevant,
// and any hit stops at the block's lowest hit lane, as the block test does.
template <int W, typename Recorder>
RAYLAB_NO_VECTORIZE inline bool intersect_leaf_scalar(const TriangleBlock<W>* blk, uint32_t nblocks, const WatertightRay& w, float tmin,
                                  Recorder& rec) {
  bool kept = false;
  for (uint32_t b = 0; b < nblocks; ++b) {
    const int count = blk[b].count();  // lanes [0, count) hold the distinct triangles
    rec.count_triangles(static_cast<uint64_t>(count));
    for (int lane = 0; lane < count; ++lane) {
      const auto vertex = [&](int c) { return Vec3f(blk[b].v[c][0][lane], blk[b].v[c][1][lane], blk[b].v[c][2][lane]); };
      float t, u, v;
      if (!intersect_watertight(w, vertex(0), vertex(1), vertex(2), tmin, rec.tmax(), t, u, v)) continue;
      if (rec.record(t, u, v, blk[b].prim[lane])) {
        kept = true;
        if constexpr (Recorder::kStopAtFirstHit) return true;
      }
    }
  }
  return kept;
}

// Prefetches what visiting `ref` will read first: a node's plane arrays, or a
// leaf's first triangle block. Children are prefetched when pushed, so they
// are (more likely) in cache when popped.
inline constexpr int kPrefetchLeafLines = 5;  // an 8-wide triangle block (320 bytes)

template <int N, int W>
[[gnu::always_inline]] inline void prefetch_child(const WideView<N, W>& bvh, uint32_t ref) {
  // Four lines for a 256-byte 8-wide node (a 4-wide node and its neighbour), seven for a 448-byte 16-wide node.
  constexpr int kPrefetchNodeLines = N == 16 ? 7 : 4;
  const char* p = wide_ref::is_leaf(ref) ? reinterpret_cast<const char*>(bvh.blocks + wide_ref::leaf_first(ref))
                                         : reinterpret_cast<const char*>(bvh.nodes + ref);
  const int lines = wide_ref::is_leaf(ref) ? kPrefetchLeafLines : kPrefetchNodeLines;
  for (int i = 0; i < lines; ++i) _mm_prefetch(p + 64 * i, _MM_HINT_T0);
}

// An inner node with two or more hit children (mask), any hit: no ordering
// by distance. A ray leaving a surface starts just outside the leaf box of
// the triangle it will hit first, and every other box around its origin ties
// at distance 0, so distance order is a poor guess here. Leaf children go
// first (one test may end the ray), then children in descending slot order
// (as Embree's occlusion traversal); measured best on the benchmark scenes.
// Pushes all but one child (prefetched) and returns the one to visit next.
template <int N, bool kScalar, int W>
[[gnu::always_inline]] inline uint32_t descend_any_hit(const WideView<N, W>& bvh, const uint32_t* child, uint32_t mask,
                                                       uint64_t*& top) {
  uint32_t leaves = 0;
  if constexpr (kScalar) {
    for (int i = 0; i < N; ++i) leaves |= (child[i] >> 31) << i;
  } else {
    // The leaf flag is each reference's top bit: one sign-bit mask of the
    // references (the child array is aligned as the node's planes). GCC 12
    // compiled the loop above to eight loads, shifts and ors per node
    // (callgrind, sponza shadow rays: 7 % of the walk's instructions).
    leaves = sign_bits(simd::vfloat<N>::load(reinterpret_cast<const float*>(child)));
  }
  leaves &= mask;
  for (uint32_t m = mask & ~leaves; m != 0; m &= m - 1) {
    const uint32_t c = child[simd::ctz(m)];
    prefetch_child(bvh, c);
    *top++ = child_key(0.0f, c);
  }
  if (leaves == 0) return key_ref(*--top);
  while (true) {
    const uint32_t c = child[simd::ctz(leaves)];
    leaves &= leaves - 1;
    if (leaves == 0) return c;
    prefetch_child(bvh, c);
    *top++ = child_key(0.0f, c);
  }
}

#if defined(RAYLAB_SIMD_AVX512)
// The AVX-512 closest-hit step once the hit children's keys are packed into
// lanes [0, k) of one register in slot order (mask: the slots they came
// from, 2 <= k <= 8). The next node's reference comes out of registers (two
// packed lanes, or nearest(), a reduction beside the sorting network), never
// from a store and its reload, which sat on the path from one node to the
// next: +5 to +6 % closest-hit Mrays/s.
template <typename Nearest, typename Prefetch>
[[gnu::always_inline]] inline uint32_t push_packed_keys(__m512i packed, uint32_t mask, Nearest&& nearest,
                                                        uint64_t*& top, Prefetch&& prefetch) {
  const uint32_t rest = mask & (mask - 1);
  if ((rest & (rest - 1)) == 0) {
    // Two children: order their keys with min/max (no branch to mispredict).
    // Vector subscripts (GCC, Clang): _mm512_castsi512_si128 warns (sort_network.h).
    const uint64_t k0 = static_cast<uint64_t>(packed[0]);
    const uint64_t k1 = static_cast<uint64_t>(packed[1]);
    const uint32_t i0 = simd::ctz(mask), i1 = simd::ctz(rest);
    prefetch(k0 > k1 ? i0 : i1);
    *top++ = std::max(k0, k1);
    return key_ref(std::min(k0, k1));
  }
  // Three or more: sort by distance, push all but the nearest.
  const int k = simd::popcount(mask);
  const uint64_t least = nearest();
  packed = k <= 4 ? sort4x2_descending(packed) : sort8_descending(packed);
  _mm512_storeu_si512(top, packed);
  for (uint32_t m = mask; m != 0; m &= m - 1) prefetch(simd::ctz(m));
  top += k - 1;
  return key_ref(least);
}
#endif

// The same for closest hit: two children are ordered by one comparison,
// three or more sorted by distance (sort_network.h) and pushed so the
// nearest is on top; returns the nearest. `refs` are the references pushed
// (the node's children, or what the packet walk pushes in their place);
// prefetch(slot) is called for every child pushed.
template <int N, bool kScalar = false, typename Prefetch>
[[gnu::always_inline]] inline uint32_t push_by_distance(const uint32_t* refs, uint32_t mask, simd::vfloat<N> tnear,
                                                        uint64_t*& top, Prefetch&& prefetch) {
#if defined(RAYLAB_SIMD_AVX512)
  if constexpr (N == 8 && !kScalar) {
    // All eight keys in one register; the nearest of three or more by the
    // reduction over them, beside the compression and the network.
    const __m256i bits = _mm256_max_epi32(_mm256_castps_si256(tnear.v), _mm256_setzero_si256());
    // Zero-masking forms: see sort_network.h on GCC 12's -Wuninitialized.
    const __m512i keys = _mm512_or_si512(
        _mm512_maskz_slli_epi64(0xFF, _mm512_maskz_cvtepu32_epi64(0xFF, bits), 32),
        _mm512_maskz_cvtepu32_epi64(0xFF, _mm256_xor_si256(_mm256_load_si256(reinterpret_cast<const __m256i*>(refs)),
                                                             _mm256_set1_epi32(static_cast<int>(kKeyRefFlip)))));
    return push_packed_keys(_mm512_maskz_compress_epi64(static_cast<__mmask8>(mask), keys), mask,
                            [&] { return min_key(keys, static_cast<__mmask8>(mask)); }, top, prefetch);
  }
  if constexpr (N == 16 && !kScalar) {
    // Sixteen keys in two registers (slots 0..7 and 8..15). Up to eight hit
    // children are packed into one register and take the 8-wide step; more
    // than eight: both halves stored and sorted in place.
    const __m512i bits = _mm512_maskz_max_epi32(0xFFFF, _mm512_castps_si512(tnear.v), _mm512_setzero_si512());
    const __m512i refx = _mm512_xor_si512(_mm512_loadu_si512(refs), _mm512_set1_epi32(static_cast<int>(kKeyRefFlip)));
    const auto keys_of = [](__m256i b, __m256i r) {  // 8 x (distance bits << 32 | flipped ref)
      return _mm512_or_si512(_mm512_maskz_slli_epi64(0xFF, _mm512_maskz_cvtepu32_epi64(0xFF, b), 32),
                             _mm512_maskz_cvtepu32_epi64(0xFF, r));
    };
    const __m512i klo = keys_of(_mm512_maskz_extracti64x4_epi64(0xF, bits, 0), _mm512_maskz_extracti64x4_epi64(0xF, refx, 0));
    const __m512i khi = keys_of(_mm512_maskz_extracti64x4_epi64(0xF, bits, 1), _mm512_maskz_extracti64x4_epi64(0xF, refx, 1));
    const __mmask8 mlo = static_cast<__mmask8>(mask & 0xFF), mhi = static_cast<__mmask8>(mask >> 8);
    const int nlo = simd::popcount(mlo);
    const int k = simd::popcount(mask);
    const __m512i clo = _mm512_maskz_compress_epi64(mlo, klo);
    const __m512i chi = _mm512_maskz_compress_epi64(mhi, khi);
    if (k <= 8) {
      // The hit keys of slots 8..15 into lanes nlo..k-1, after those of slots 0..7.
      const __mmask8 valid = static_cast<__mmask8>((1u << k) - 1u);
      const __m512i packed = _mm512_mask_expand_epi64(clo, static_cast<__mmask8>(valid & ~((1u << nlo) - 1u)), chi);
      return push_packed_keys(packed, mask, [&] { return min_key(packed, valid); }, top, prefetch);
    }
    _mm512_storeu_si512(top, clo);
    _mm512_storeu_si512(top + nlo, chi);
    sort_keys_descending(top, k);
    for (uint32_t m = mask; m != 0; m &= m - 1) prefetch(simd::ctz(m));
    top += k - 1;
    return key_ref(*top);
  }
#endif
  // The distances go through memory only on the paths that read them one by
  // one (two children; the portable sort), not on the AVX2 permutation's.
  alignas(64) float dist[N];
  const uint32_t rest = mask & (mask - 1);
  if ((rest & (rest - 1)) == 0) {
    // Two children. The next node is chosen by one comparison of the two
    // keys and a conditional move between the two references, so the path
    // from the node test to the next node's address is a shift, an or, a
    // compare and a move; the farther key, pushed, is off that path. The
    // distances are clamped at 0 (child_key) in the vector, before the mask
    // is known. (Ordering the keys by a mask and taking the nearer's
    // reference from the key instead puts about ten dependent
    // instructions and a reload of the child there in GCC 12's code.)
    max_bits(tnear, simd::vfloat<N>::broadcast(0.0f)).store(dist);
    const uint32_t i0 = simd::ctz(mask);
    const uint32_t i1 = simd::ctz(rest);
    uint32_t b0, b1;
    std::memcpy(&b0, &dist[i0], sizeof b0);
    std::memcpy(&b1, &dist[i1], sizeof b1);
    const uint32_t r0 = refs[i0], r1 = refs[i1];
    const uint64_t k0 = child_key_bits(b0, r0);
    const uint64_t k1 = child_key_bits(b1, r1);
    // A conditional move: GCC 12 branched on the plain comparison, which
    // mispredicts about half the time on incoherent rays.
    const uint32_t near_ref = simd::unpredictable(k0 > k1) ? r1 : r0;
    const uint64_t first_far = 0 - static_cast<uint64_t>(k0 > k1);  // all ones when k0 is the farther
    prefetch(i1 ^ ((i0 ^ i1) & static_cast<uint32_t>(first_far)));
    *top++ = k1 ^ ((k0 ^ k1) & first_far);
    return near_ref;
  }
#if defined(RAYLAB_SIMD_AVX2) && !defined(RAYLAB_SIMD_AVX512)
  if constexpr (N == 8 && !kScalar) {
    // Three or more with AVX2: the hit children's distances and references
    // packed to the front by one permutation (simd::compress_index8) and
    // interleaved into 64-bit keys in registers, so no loop over the
    // children (whose unpredictable trip count mispredicted); then sorted.
    const int k = simd::popcount(mask);
    const __m256i perm = simd::compress_index8(mask);
    const __m256i bits = _mm256_permutevar8x32_epi32(
        _mm256_max_epi32(_mm256_castps_si256(tnear.v), _mm256_setzero_si256()), perm);
    const __m256i refx = _mm256_permutevar8x32_epi32(
        _mm256_xor_si256(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(refs)),
                         _mm256_set1_epi32(static_cast<int>(kKeyRefFlip))),
        perm);
    const __m256i lo = _mm256_unpacklo_epi32(refx, bits);  // keys 0 1 | 4 5
    const __m256i hi = _mm256_unpackhi_epi32(refx, bits);  // keys 2 3 | 6 7
    uint64_t* keys = top;  // room for 8 (wide_stack_fits)
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(keys), _mm256_permute2x128_si256(lo, hi, 0x20));
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(keys + 4), _mm256_permute2x128_si256(lo, hi, 0x31));
    const uint64_t nearest = sort8_keys_descending(keys, k);
    for (uint32_t m = mask; m != 0; m &= m - 1) prefetch(simd::ctz(m));
    top += k - 1;
    return key_ref(nearest);
  }
#endif
  // Three or more: sort by distance, push all but the nearest.
  tnear.store(dist);
  const int k = simd::popcount(mask);
  uint64_t* keys = top;
  int n = 0;
  for (uint32_t m = mask; m != 0; m &= m - 1) {
    const uint32_t i = simd::ctz(m);
    keys[n++] = child_key(dist[i], refs[i]);
  }
  if constexpr (kScalar || N > 8) sort_keys_descending(keys, n);  // keys are unique: the same order
  else sort8_keys_descending(keys, n);
  for (uint32_t m = mask; m != 0; m &= m - 1) prefetch(simd::ctz(m));
  top += k - 1;
  return key_ref(*top);
}

template <int N, int W, bool kScalar = false>
[[gnu::always_inline]] inline uint32_t descend_closest(const WideView<N, W>& bvh, const uint32_t* child, uint32_t mask,
                                                       simd::vfloat<N> tnear, uint64_t*& top) {
  // always_inline: GCC 12 found this lambda free of side effects (a prefetch
  // is not one) and deleted its calls before inlining it, so closest-hit
  // walks prefetched nothing (any-hit walks, which call prefetch_child
  // directly, did).
  return push_by_distance<N, kScalar>(child, mask, tnear, top, [&](uint32_t i) __attribute__((always_inline)) {
    prefetch_child(bvh, child[i]);
  });
}

// Counting (kCount): a node visited is a child box tested, so an inner node
// counts its non-empty child slots (accel/core/hit_recorder.h); the root's
// box is not tested.
template <int N>
inline uint64_t count_children(const WideNode<N>& node) {
  uint64_t c = 0;
  for (int i = 0; i < N; ++i) c += node.child[i] != wide_ref::kEmpty;
  return c;
}

// Walks the subtree `start` for one ray, offering hits to `rec` (which may
// already hold a hit from elsewhere in the tree: the packet traversal hands
// diverged rays over this way). Returns when the subtree is done or, any
// hit, at the first hit.
// kTest: the leaf test, watertight, or Moller-Trumbore on blocks holding
// edges (tri=mt, the non-watertight option; never with kScalar).
template <int N, int W, bool kAnyHit, bool kCount, bool kAxisParallel, bool kScalar = false,
          TriangleTest kTest = TriangleTest::Watertight, int kOctant = -1>
inline void walk_wide(const WideView<N, W>& view, const Ray& ray, uint32_t start, HitRecorder<kAnyHit, kCount>& rec,
                      const NodeRayScalars* ahead = nullptr) {
  static_assert(!(kScalar && kTest != TriangleTest::Watertight), "simd=0 tests watertight only");
  static_assert(kOctant < 0 || (!kScalar && !kAxisParallel), "octant walks: vector tests, rays that are not axis-parallel");
  // A copy: the stores of the walk (stack, hit) could alias the caller's
  // view, so GCC reloaded the node array's address through it at every node.
  const WideView<N, W> bvh = view;
  using V = simd::vfloat<N>;
  constexpr bool kExact = kAxisParallel || !RAYLAB_HAS_FMA;
  WideNodeRay<N> nr;
  // The FMA kernel's rays have no direction component below 1e-30, so the box
  // test's reciprocals are the correctly rounded 1 / dir: the triangle test's
  // set-up takes its 1 / dir[kz] from them instead of dividing again.
#if defined(__AVX__)
  constexpr bool kShareReciprocal = !kAxisParallel;
#else
  constexpr bool kShareReciprocal = false;
#endif
  alignas(16) float ray_inv[4];
  init_node_ray(nr, ray, kAxisParallel, kShareReciprocal ? ray_inv : nullptr, ahead);
  [[maybe_unused]] const ScalarNodeRay snr = [&] {
    if constexpr (kScalar) return ScalarNodeRay(nr);
    else return ScalarNodeRay{};
  }();
  using LeafRay = std::conditional_t<kTest == TriangleTest::MollerTrumbore, BlockRayMT<W>, BlockRay<W>>;
  LeafRay br{};  // closest hit: filled at the first leaf; any hit: here (see above)
  const auto init_leaf_ray = [&] {
    if constexpr (kTest == TriangleTest::MollerTrumbore) br.init(ray);
    else br.init(WatertightRay(ray, kShareReciprocal ? ray_inv : nullptr));
  };
  if constexpr (!kScalar && kAnyHit) init_leaf_ray();
  // The scalar leaf test's constants (kScalar only; the default ray's otherwise, unused).
  [[maybe_unused]] const WatertightRay wr = [&] {
    if constexpr (kScalar) return WatertightRay(ray);
    else return WatertightRay(Ray());
  }();
  bool br_ready = false;  // closest hit only
  const float tmin = ray.tmin;
  const float tmin0 = tmin == 0.0f ? 0.0f : tmin;  // -0 as +0 for the integer-order min/max
  const V tmin_v = V::broadcast(tmin0);

  alignas(64) uint64_t stack[kWideStackSize];
  // The next free entry: one pointer, not the array and an index (GCC 12
  // kept the index and the array's address in memory, two loads before
  // every pop's).
  uint64_t* top = stack;
  uint32_t cur = start;

  // Closest hit: entries whose entry distance exceeds the current bound,
  // padded as the box test pads it (kSlabFarPadUlps on the bits), are culled
  // when popped. Keys hold the distance's bits in their high half, so that
  // is one integer comparison of the whole key against cull_key, which
  // changes only when a hit is kept. Keys clamp negative entry distances
  // (tmin < 0) to 0: with a hit at t < 0 only the subtrees entered at t > 0
  // can be culled here (the others are culled, exactly, by the box test when
  // visited).
  [[maybe_unused]] uint64_t cull_key = kAnyHit ? 0 : key_cull_limit(rec.tmax());

  // Next subtree from the stack that can still hold a closer hit.
  auto pop = [&]() -> bool {
    while (top != stack) {
      const uint64_t e = *--top;
      if constexpr (!kAnyHit) {
        if (e > cull_key) continue;
      }
      cur = key_ref(e);
      return true;
    }
    return false;
  };

  while (true) {
    if (!wide_ref::is_leaf(cur)) {
      const WideNode<N>& node = bvh.nodes[cur];
      if constexpr (kCount) rec.count_inner(count_children<N>(node));
      V tnear;
      uint32_t mask;
      if constexpr (kScalar) {
        alignas(64) float tn[N];
        mask = intersect_children_scalar<N, kExact>(node, snr, tmin0, rec.tmax(), tn);
        tnear = V::load(tn);
      } else {
        mask = intersect_children<N, kExact, kOctant>(node, nr, tmin_v, V::broadcast(rec.tmax()), tnear);
      }
      if (mask == 0) {
        if (!pop()) return;
        continue;
      }
      const uint32_t* child = node.child;
      const uint32_t rest = mask & (mask - 1);
      if (rest == 0) {
        cur = child[simd::ctz_index(mask)];
        continue;
      }
      cur = kAnyHit ? descend_any_hit<N, kScalar>(bvh, child, mask, top)
                    : descend_closest<N, W, kScalar>(bvh, child, mask, tnear, top);
      continue;
    }

    // Leaf: test its triangle blocks.
    if (!kScalar && !kAnyHit && !br_ready) {
      init_leaf_ray();
      br_ready = true;
    }
    const TriangleBlock<W>* blocks = bvh.blocks + wide_ref::leaf_first(cur);
    rec.count_leaf(wide_ref::leaf_blocks(cur));
    const bool kept = kScalar ? intersect_leaf_scalar<W>(blocks, wide_ref::leaf_blocks(cur), wr, tmin, rec)
                              : intersect_block_leaf<W>(blocks, wide_ref::leaf_blocks(cur), br, tmin, rec);
    if (kept) {
      if constexpr (kAnyHit) return;
      else cull_key = key_cull_limit(rec.tmax());
    }
    if (!pop()) return;
  }
}

template <int N, int W, bool kAnyHit, bool kCount, bool kAxisParallel, bool kScalar, TriangleTest kTest>
inline Hit traverse_wide_kernel(const WideView<N, W>& bvh, const Ray& ray, TraversalStats* stats,
                               const NodeRayScalars* ahead = nullptr) {
  HitRecorder<kAnyHit, kCount> rec(ray, stats);
  walk_wide<N, W, kAnyHit, kCount, kAxisParallel, kScalar, kTest>(bvh, ray, bvh.root_ref, rec, ahead);
  return rec.hit();
}

// The traversal entry point: validity check, then the kernel for the ray's
// kind. kScalar: the scalar tests of `bvh:simd=0`; kTest: see walk_wide.
// ahead (optional): the ray's node_ray_scalars, computed before (used when
// the ray takes the FMA kernel, whose rays are not axis-parallel).
template <int N, int W, bool kAnyHit, bool kCount, bool kScalar = false, TriangleTest kTest = TriangleTest::Watertight>
inline Hit traverse_wide(const WideView<N, W>& bvh, const Ray& ray, TraversalStats* stats,
                         const NodeRayScalars* ahead = nullptr) {
  // The fast kernel needs finite reciprocals, tmin >= 0 (see
  // intersect_children) and an origin not far beyond the scene
  // (wide_fma_origin_limit): one test for all of it and validity.
  if (ray_takes_fma_kernel(ray, bvh.fma_origin_limit)) [[likely]]
    return traverse_wide_kernel<N, W, kAnyHit, kCount, false, kScalar, kTest>(bvh, ray, stats, ahead);
  if (!ray_is_valid(ray)) return HitRecorder<kAnyHit, kCount>(ray, stats).hit();  // counts the ray
  return traverse_wide_kernel<N, W, kAnyHit, kCount, true, kScalar, kTest>(bvh, ray, stats);
}

// The direction octant of a ray: bit a set when dir[a]'s sign bit is (as
// init_node_ray's sign mask).
inline int ray_octant(const Ray& r) {
#if defined(__SSE2__)
  return _mm_movemask_ps(_mm_loadu_ps(r.dir.data())) & 7;  // dx dy dz tmax (base/ray.h), as init_node_ray
#else
  return static_cast<int>(std::signbit(r.dir.x())) | static_cast<int>(std::signbit(r.dir.y())) << 1 |
         static_cast<int>(std::signbit(r.dir.z())) << 2;
#endif
}

// A batch whose consecutive rays mostly share a direction octant (camera
// rays; shadow rays towards one light): each ray takes the walk specialised
// to its octant, whose node test reads its planes at constant offsets (with
// AVX2's 16 registers GCC otherwise keeps the six offsets on the stack and
// reloads one per plane). The choice is one switch per ray, predicted in such
// a batch; incoherent batches keep the general walk, where that switch
// mispredicts (on random rays every octant walk lost 4-6 %).
// Coherent: the octant changes between consecutive rays at most n / 8
// times. The scan stops at the first change past that, which incoherent
// batches (a change at 7 rays of 8) reach within about 40 rays.
inline bool batch_is_octant_coherent(std::span<const Ray> rays) {
  if (rays.empty()) return false;
  const size_t limit = rays.size() / 8;
  size_t changes = 0;
  int prev = ray_octant(rays[0]);
  for (size_t i = 1; i < rays.size(); ++i) {
    const int octant = ray_octant(rays[i]);
    changes += octant != prev;
    prev = octant;
    if (changes > limit) return false;
  }
  return true;
}

// ahead (optional): the ray's node_ray_scalars, computed before (used when
// the ray takes the FMA kernel, whose rays are not axis-parallel).
template <int N, int W, bool kAnyHit>
inline Hit traverse_wide_octant(const WideView<N, W>& bvh, const Ray& ray, const NodeRayScalars* ahead = nullptr) {
  if (!ray_takes_fma_kernel(ray, bvh.fma_origin_limit)) [[unlikely]]
    return traverse_wide<N, W, kAnyHit, false>(bvh, ray, nullptr);
  HitRecorder<kAnyHit, false> rec(ray, nullptr);
  const auto walk = [&]<int kOctant>() {
    walk_wide<N, W, kAnyHit, false, false, false, TriangleTest::Watertight, kOctant>(bvh, ray, bvh.root_ref, rec,
                                                                                      ahead);
  };
  switch (ray_octant(ray)) {
    case 0: walk.template operator()<0>(); break;
    case 1: walk.template operator()<1>(); break;
    case 2: walk.template operator()<2>(); break;
    case 3: walk.template operator()<3>(); break;
    case 4: walk.template operator()<4>(); break;
    case 5: walk.template operator()<5>(); break;
    case 6: walk.template operator()<6>(); break;
    default: walk.template operator()<7>(); break;
  }
  return rec.hit();
}

// Traces a batch one ray at a time, out(i, walk(rays[i], ahead)). With AVX
// each ray's node_ray_scalars (a division and three dependent operations)
// are computed before the ray ahead of it walks, so their latency hides
// behind that walk instead of delaying the first node test after the
// mispredicted end of the walk before: camera rays +2 to +5 % in three of
// five series, level in the two run on a quieter machine (docs/structures/bvh.md).
// Answers are the same: the scalars are the ones init_node_ray computes.
// ahead = false (incoherent batches): each ray's scalars when it starts.
template <typename Walk, typename Out>
inline void trace_rays_ahead(std::span<const Ray> rays, [[maybe_unused]] bool ahead, Walk&& walk, Out&& out) {
#if defined(__AVX__)
  if (ahead && !rays.empty()) {
    NodeRayScalars next = node_ray_scalars(rays[0], false);
    for (size_t i = 0; i < rays.size(); ++i) {
      const NodeRayScalars cur = next;
      if (i + 1 < rays.size()) next = node_ray_scalars(rays[i + 1], false);
      out(i, walk(rays[i], &cur));
    }
    return;
  }
#endif
  for (size_t i = 0; i < rays.size(); ++i) out(i, walk(rays[i], static_cast<const NodeRayScalars*>(nullptr)));
}

}  // namespace raylab
