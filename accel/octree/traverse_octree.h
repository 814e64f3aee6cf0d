#pragma once
// Octree traversal by the parametric algorithm of Revelles, Urena & Lastra,
// "An Efficient Parametric Algorithm for Octree Traversal", WSCG 2000.
//
// Every node is entered with its parametric interval [t0, t1] (where the
// ray is inside it); the three dividing planes give one parameter each, and
// a child's interval is the node's cut by them: along axis k the child on
// the ray's entry side ends where the ray crosses the plane, the one beyond
// starts there. Negative direction components are handled by mirroring, as
// in the paper: with a = the mask of negative components, the child in ray
// order b (bit k = beyond the plane along k) is child b XOR a in memory.
// The first child is the one the entry plane leads into (its bits are the
// planes already crossed at t0), and each next child is reached through the
// exit plane of the previous one, i.e. the children in increasing entry
// parameter. octree_child_order() computes exactly that order from the
// intervals (a sort of at most eight entries), which is the paper's state
// table for ordinary rays and stays correct when inflated children overlap
// (below). Closest hit: children are pushed on a stack in reverse order, so
// they are walked front to back, and a walk ends once no pending node starts
// before the closest hit so far (early exit). Occlusion stops at the first
// hit; with kFarFirst (anyhit=back, accel/core/any_hit_order.h) it walks the
// children in the reverse order, from the segment's far end (the light of a
// shadow ray), as the k-d tree and the BSP do: the same answers, and fewer
// nodes when the origin lies on a dense surface.
//
// Robustness, as the k-d tree's (accel/kdtree/traverse_kdtree.h): every
// cell is treated as inflated by delta = 2^-20 M in space (M bounds
// |p - org| over the root cube), covering the rounding of the plane
// parameters and the watertight triangle test's resolution, and [tmin,
// tmax] is widened by delta / max|dir|. Plane parameters come from the
// lattice planes (octree_cube.h), never from averaging t0 and t1, so
// direction components of +-0 give exact +-inf parameters: a ray parallel
// to a plane stays on its side (or on both within delta), a ray lying in a
// plane gets NaN, which every comparison below treats as "visit", and a ray
// starting inside the cube starts with t0 = tmin in the child holding its
// origin. So the walk finds every hit brute force finds, bit for bit.
//
// Node lists: by default SIMD triangle blocks (octree_leaf_blocks.h), four
// triangles per vector test; `simd=0` (and tri=mt) test the same lists one
// triangle at a time. Neither uses a mailbox: a triangle listed in several
// leaves the ray crosses is tested in each, which on Sponza and the stadium
// cost less than the per-triangle lookups (docs/structures/octree.md), and it keeps
// the scalar variant's counted work equal to the blocks'.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

#if defined(__AVX__)
#include <immintrin.h>
#endif

#include "accel/core/hit_recorder.h"
#include "accel/core/leaf_triangle.h"
#include "accel/octree/octree_leaf_blocks.h"
#include "accel/octree/octree_layouts.h"

namespace raylab {

template <typename Layout>
struct OctreeView {
  Layout layout;
  OctreeCube cube;
  const LeafTriangle* tris = nullptr;  // once per triangle, in the order the nodes first refer to them
  const uint32_t* ids = nullptr;       // node ranges of indices into tris
  // SIMD node lists (simd=1, watertight): a node's first_ref is then its first block.
  const OctTriangleBlock* blocks = nullptr;
  bool empty = true;
};

inline constexpr float kOctMarginScale = 0x1p-20f;

// The per-ray constants of the walk.
struct OctRay {
  float org[3], inv[3], margin[3];
  uint32_t neg_mask = 0;  // Revelles' a: bit k set when dir[k] is negative (-0 included)
  float delta_t = 0.0f;
  float t0 = 0.0f, t1 = 0.0f;  // the widened interval clipped to the inflated root cube
};

// Fills `r`; false when the ray misses the inflated root cube.
inline bool oct_enter_root(const OctreeCube& cube, const Ray& ray, OctRay& r) {
  const uint32_t n = OctreeCube::span(0);
  float m = 0.0f, dir_max = 0.0f;
  for (int k = 0; k < 3; ++k) {
    r.org[k] = ray.org[k];
    m = std::max({m, std::fabs(cube.plane(k, 0) - ray.org[k]), std::fabs(cube.plane(k, n) - ray.org[k])});
    dir_max = std::max(dir_max, std::fabs(ray.dir[k]));
  }
  const float delta = std::max(kOctMarginScale * m, std::numeric_limits<float>::min());
  r.delta_t = delta / dir_max;
  float t0 = ray.tmin - r.delta_t, t1 = ray.tmax + r.delta_t;
  r.neg_mask = 0;
  for (int k = 0; k < 3; ++k) {
    const float d = ray.dir[k];
    r.inv[k] = 1.0f / d;
    // A denormal component whose reciprocal overflows: NaN = visit both sides.
    if (d != 0.0f && std::isinf(r.inv[k])) r.inv[k] = std::numeric_limits<float>::quiet_NaN();
    const bool neg = std::signbit(d);
    r.neg_mask |= neg ? 1u << k : 0u;
    r.margin[k] = neg ? -delta : delta;
    const float near_plane = cube.plane(k, neg ? n : 0), far_plane = cube.plane(k, neg ? 0 : n);
    const float tn = ((near_plane - r.org[k]) - r.margin[k]) * r.inv[k];
    const float tf = ((far_plane - r.org[k]) + r.margin[k]) * r.inv[k];
    t0 = tn > t0 ? tn : t0;
    t1 = tf < t1 ? tf : t1;
  }
  r.t0 = t0;
  r.t1 = t1;
  return t0 <= t1;
}

struct OctChild {
  uint32_t c;  // memory index 0..7
  float t0, t1;
};

// The children of a node with interval [t0, t1] that the ray enters, in the
// order it enters them. near_end[k]: where the ray leaves the (inflated)
// entry-side half along k; far_start[k]: where it enters the far half.
// `mask`: children that exist. Returns how many were written to out[].
// This is the scalar definition; octree_child_order() below computes the
// same with one 8-lane vector per quantity where AVX is available.
inline int octree_child_order_scalar(float t0, float t1, const float near_end[3], const float far_start[3],
                                     uint32_t neg_mask, uint32_t mask, OctChild out[8]) {
  // Entry of child b (ray order): the latest of t0 and the far_start of its
  // far axes; exit: the earliest of t1 and the near_end of its near axes.
  // Built up over the bits (each child from one with a bit fewer), 7 max
  // and 7 min for all eight; `x > y ? x : y` keeps y when x is NaN (visit).
  auto mx = [](float x, float y) { return x > y ? x : y; };
  auto mn = [](float x, float y) { return x < y ? x : y; };
  float enter[8], leave_c[8];  // leave_c[~b & 7] = exit of child b
  enter[0] = t0;
  leave_c[0] = t1;
  for (int k = 0; k < 3; ++k) {
    const int half = 1 << k;
    for (int i = 0; i < half; ++i) {
      enter[half + i] = mx(far_start[k], enter[i]);
      leave_c[half + i] = mn(near_end[k], leave_c[i]);
    }
  }
  int n = 0;
  for (uint32_t b = 0; b < 8; ++b) {  // b: child in ray order (bit k = beyond plane k)
    const uint32_t c = b ^ neg_mask;
    const float e0 = enter[b], e1 = leave_c[7 - b];
    if (!(mask >> c & 1u) || !(e0 <= e1)) continue;
    // Insertion by entry parameter; ties keep ray order (fewer planes crossed first).
    int i = n++;
    while (i > 0 && out[i - 1].t0 > e0) {
      out[i] = out[i - 1];
      --i;
    }
    out[i] = OctChild{c, e0, e1};
  }
  return n;
}

// The child mask in ray order: bit b = child b ^ neg_mask exists (Revelles'
// mirroring applied to the mask, one swap of bit groups per negative axis).
[[gnu::always_inline]] inline uint32_t oct_mask_in_ray_order(uint32_t mask, uint32_t neg_mask) {
  if (neg_mask & 1u) mask = ((mask & 0x55u) << 1) | ((mask >> 1) & 0x55u);
  if (neg_mask & 2u) mask = ((mask & 0x33u) << 2) | ((mask >> 2) & 0x33u);
  if (neg_mask & 4u) mask = ((mask & 0x0fu) << 4) | ((mask >> 4) & 0x0fu);
  return mask;
}

// octree_child_order_scalar() with the eight entries and exits as lanes of
// one vector each (lane b = child b in ray order). Same operations on the
// same values: max/min with the second operand winning on NaN are exactly
// `x > y ? x : y` and `x < y ? x : y`, and the -inf/+inf in lanes an axis
// does not apply to leave the lane unchanged. Profiling the scalar loop on
// the stadium showed the compiler's partial vectorisation of it stalling on
// store-to-load forwarding (~20% of the walk); this form has no such
// round trip. tests/accel/octree/test_octree.cpp compares the two on random and
// non-finite inputs.
[[gnu::always_inline]] inline int octree_child_order(float t0, float t1, const float near_end[3],
                                                    const float far_start[3], uint32_t neg_mask, uint32_t mask,
                                                    OctChild out[8]) {
#if defined(__AVX__)
  const __m256 neg_inf = _mm256_set1_ps(-std::numeric_limits<float>::infinity());
  const __m256 pos_inf = _mm256_set1_ps(std::numeric_limits<float>::infinity());
  // Lanes whose bit k is set: 0xaa (k = 0), 0xcc (k = 1), 0xf0 (k = 2).
  __m256 enter = _mm256_set1_ps(t0);
  enter = _mm256_max_ps(_mm256_blend_ps(neg_inf, _mm256_set1_ps(far_start[0]), 0xaa), enter);
  enter = _mm256_max_ps(_mm256_blend_ps(neg_inf, _mm256_set1_ps(far_start[1]), 0xcc), enter);
  enter = _mm256_max_ps(_mm256_blend_ps(neg_inf, _mm256_set1_ps(far_start[2]), 0xf0), enter);
  __m256 leave = _mm256_set1_ps(t1);
  leave = _mm256_min_ps(_mm256_blend_ps(_mm256_set1_ps(near_end[0]), pos_inf, 0xaa), leave);
  leave = _mm256_min_ps(_mm256_blend_ps(_mm256_set1_ps(near_end[1]), pos_inf, 0xcc), leave);
  leave = _mm256_min_ps(_mm256_blend_ps(_mm256_set1_ps(near_end[2]), pos_inf, 0xf0), leave);
  uint32_t visit = static_cast<uint32_t>(_mm256_movemask_ps(_mm256_cmp_ps(enter, leave, _CMP_LE_OQ))) &
                   oct_mask_in_ray_order(mask, neg_mask);
  int n = 0;
  for (; visit != 0; visit &= visit - 1) {
    const uint32_t b = static_cast<uint32_t>(__builtin_ctz(visit));
#if defined(__AVX2__)
    // Lane b by a register permute (a vector store and scalar reloads
    // waited on store forwarding in the profile).
    const __m256i lane = _mm256_set1_epi32(static_cast<int>(b));
    const float e0 = _mm256_cvtss_f32(_mm256_permutevar8x32_ps(enter, lane));
    const float e1 = _mm256_cvtss_f32(_mm256_permutevar8x32_ps(leave, lane));
#else
    alignas(32) float e0s[8], e1s[8];
    _mm256_store_ps(e0s, enter);
    _mm256_store_ps(e1s, leave);
    const float e0 = e0s[b], e1 = e1s[b];
#endif
    int i = n++;
    while (i > 0 && out[i - 1].t0 > e0) {
      out[i] = out[i - 1];
      --i;
    }
    out[i] = OctChild{b ^ neg_mask, e0, e1};
  }
  return n;
#else
  return octree_child_order_scalar(t0, t1, near_end, far_start, neg_mask, mask, out);
#endif
}

// kBlocks: node lists are SIMD triangle blocks (watertight test only).
// kFarFirst: occlusion walks back to front.
template <TriangleTest kTest, bool kAnyHit, bool kCount, bool kBlocks, typename Layout, bool kFarFirst = false>
inline Hit traverse_octree(const OctreeView<Layout>& tree, const Ray& ray, TraversalStats* stats) {
  static_assert(!kFarFirst || kAnyHit, "only an any-hit walk may change the order");
  HitRecorder<kAnyHit, kCount> rec(ray, stats);
  if (tree.empty || !ray_is_valid(ray)) return rec.hit();
  OctRay r;
  if (!oct_enter_root(tree.cube, ray, r)) return rec.hit();
  static_assert(!kBlocks || kTest == TriangleTest::Watertight, "the SIMD lists run the watertight test");
  using ListRay = std::conditional_t<kBlocks, BlockRay<kOctBlockWidth>, TrianglePrecompute<kTest>>;
  const ListRay pre(ray);

  struct Entry {
    uint64_t handle;
    uint32_t lattice[3];
    int level;
    float t0, t1;
  };
  // At most 7 siblings wait per level, plus the node being entered.
  Entry stack[8 * (kOctMaxLevel + 1)];
  int sp = 0;
  // The root: node 0 of the pointer and linear layouts, location code 1 of the hashed one.
  Entry cur{Layout::kRoot, {0, 0, 0}, 0, r.t0, r.t1};

  while (true) {
    rec.count_nodes(1);
    const OctNodeRec node = tree.layout.node(cur.handle, cur.level);
    const uint32_t count = node.meta >> 8;
    if (node.meta & 0xffu) rec.count_step();
    if (count || !(node.meta & 0xffu)) rec.count_leaf(count);
    if (count) {
      bool kept;
      if constexpr (kBlocks)
        kept = intersect_block_leaf<kOctBlockWidth>(tree.blocks + node.first_ref, oct_node_blocks(count), pre,
                                                    ray.tmin, rec);
      else
        kept = intersect_leaf_indexed(pre, ray, tree.tris, tree.ids + node.first_ref, count, rec);
      if constexpr (kAnyHit) {
        if (kept) return rec.hit();
      }
    }
    const float t_bound = rec.tmax() + r.delta_t;
    const uint32_t mask = node.meta & 0xffu;
    if (mask) {
      tree.layout.prefetch_children(node);
      const uint32_t half = OctreeCube::span(cur.level + 1);
      float near_end[3], far_start[3];
      for (int k = 0; k < 3; ++k) {
        const float rel = tree.cube.plane(k, cur.lattice[k] + half) - r.org[k];
        near_end[k] = (rel + r.margin[k]) * r.inv[k];
        far_start[k] = (rel - r.margin[k]) * r.inv[k];
      }
      OctChild kids[8];
      const int n = octree_child_order(cur.t0, cur.t1 < t_bound ? cur.t1 : t_bound, near_end, far_start, r.neg_mask,
                                       mask, kids);
      auto entry = [&](const OctChild& k) {
        const uint32_t c = k.c;
        return Entry{tree.layout.child(cur.handle, node, c),
                     {cur.lattice[0] + ((c & 1u) ? half : 0u), cur.lattice[1] + ((c & 2u) ? half : 0u),
                      cur.lattice[2] + ((c & 4u) ? half : 0u)},
                     cur.level + 1,
                     k.t0,
                     k.t1};
      };
      if constexpr (kFarFirst) {
        // Far to near: the farthest child at once, the others popped after it
        // (an occlusion walk keeps t_bound = tmax until it returns, so every
        // pending child is still visited when no hit is found).
        for (int i = 0; i < n - 1; ++i) stack[sp++] = entry(kids[i]);
        if (n > 0) {
          cur = entry(kids[n - 1]);
          continue;
        }
      } else {
        for (int i = n - 1; i >= 1; --i) stack[sp++] = entry(kids[i]);
        // The nearest child is entered at once (its entry is <= t_bound, as
        // the order was computed on [t0, min(t1, t_bound)]): no stack round trip.
        if (n > 0) {
          cur = entry(kids[0]);
          continue;
        }
      }
    }
    // Next node that can still hold a closer hit.
    while (true) {
      if (sp == 0) return rec.hit();
      const Entry& e = stack[--sp];
      if (e.t0 <= t_bound) {
        cur = e;
        break;
      }
    }
  }
}

}  // namespace raylab
