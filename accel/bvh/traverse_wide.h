#pragma once
// Single-ray traversal of the N-wide BVH (N = 4 or 8) with W-wide triangle
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
// really crosses is missed. Without FMA the kernel uses Ize's form directly.
//
// Hit children: one is entered directly, two are ordered by one comparison,
// three or more are sorted by a short sorting network (sort_network.h) and
// pushed so the nearest is on top. Stack entries are 64-bit keys (distance,
// child reference) in a fixed array; popped entries farther than the current
// closest hit are skipped.
#include <cfloat>
#include <cstdint>

#include "accel/accelerator.h"
#include "accel/bvh/bvh_wide_node.h"
#include "accel/bvh/sort_network.h"
#include "accel/bvh/triangle_block.h"
#include "accel/core/slab_test.h"

namespace raylab {

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
};

// Per-ray constants of the child-box test.
template <int N>
struct WideNodeRay {
  using V = simd::vfloat<N>;
  V inv[3];
#if defined(RAYLAB_SIMD_FMA)
  V near_shift[3], far_shift[3];  // -(o * inv) rounded so near shrinks and far grows
#else
  V org[3];
#endif
  int near_off[3], far_off[3];  // float offsets of the near / far plane arrays in a node

  explicit WideNodeRay(const Ray& r) {
    const SlabRay s(r);
    for (int a = 0; a < 3; ++a) {
      inv[a] = V::broadcast(s.inv_dir[a]);
      near_off[a] = (2 * a + s.neg[a]) * N;
      far_off[a] = (2 * a + 1 - s.neg[a]) * N;
#if defined(RAYLAB_SIMD_FMA)
      const float oi = r.org[a] * s.inv_dir[a];
      float up = std::nextafter(oi, std::numeric_limits<float>::infinity());
      float down = std::nextafter(oi, -std::numeric_limits<float>::infinity());
      // Keep denormals out of the hot loop: a wider bound is still a bound.
      if (std::fabs(up) < FLT_MIN) up = FLT_MIN;
      if (std::fabs(down) < FLT_MIN) down = -FLT_MIN;
      near_shift[a] = V::broadcast(-up);
      far_shift[a] = V::broadcast(-down);
#else
      org[a] = V::broadcast(r.org[a]);
#endif
    }
  }
};

// Tests the N child boxes of a node; returns the mask of children whose
// (padded) slab interval overlaps [tmin, tmax], and their entry distances.
template <int N>
inline uint32_t intersect_children(const WideNode<N>& node, const WideNodeRay<N>& r, simd::vfloat<N> tmin,
                                   simd::vfloat<N> tmax, simd::vfloat<N>& tnear) {
  using V = simd::vfloat<N>;
  const float* b = &node.bounds[0][0];
#if defined(RAYLAB_SIMD_FMA)
  const V nx = fmadd(V::load(b + r.near_off[0]), r.inv[0], r.near_shift[0]);
  const V ny = fmadd(V::load(b + r.near_off[1]), r.inv[1], r.near_shift[1]);
  const V nz = fmadd(V::load(b + r.near_off[2]), r.inv[2], r.near_shift[2]);
  const V fx = fmadd(V::load(b + r.far_off[0]), r.inv[0], r.far_shift[0]);
  const V fy = fmadd(V::load(b + r.far_off[1]), r.inv[1], r.far_shift[1]);
  const V fz = fmadd(V::load(b + r.far_off[2]), r.inv[2], r.far_shift[2]);
#else
  const V nx = (V::load(b + r.near_off[0]) - r.org[0]) * r.inv[0];
  const V ny = (V::load(b + r.near_off[1]) - r.org[1]) * r.inv[1];
  const V nz = (V::load(b + r.near_off[2]) - r.org[2]) * r.inv[2];
  const V fx = (V::load(b + r.far_off[0]) - r.org[0]) * r.inv[0];
  const V fy = (V::load(b + r.far_off[1]) - r.org[1]) * r.inv[1];
  const V fz = (V::load(b + r.far_off[2]) - r.org[2]) * r.inv[2];
#endif
  tnear = max(max(nx, ny), max(nz, tmin));
  const V tfar = min(min(min(fx, fy), fz) * V::broadcast(kSlabFarScale), tmax);
  return cmp_le(tnear, tfar);
}

template <int N, int W, bool kAnyHit, bool kCount>
inline Hit traverse_wide(const WideView<N, W>& bvh, const Ray& ray, TraversalStats* stats) {
  using V = simd::vfloat<N>;
  Hit hit;
  if constexpr (kCount) stats->rays++;
  if (!ray_is_valid(ray) || !(ray.tmin <= ray.tmax)) return hit;

  const WideNodeRay<N> nr(ray);
  const BlockRay<W> br(ray);
  const float tmin = ray.tmin;
  float tmax = ray.tmax;
  const V tmin_v = V::broadcast(tmin);

  alignas(64) uint64_t stack[kWideStackSize];
  int sp = 0;
  uint32_t cur = bvh.root_ref;

  // Next subtree from the stack that can still hold a closer hit.
  auto pop = [&]() -> bool {
    while (sp > 0) {
      const uint64_t e = stack[--sp];
      if constexpr (!kAnyHit) {
        if (key_dist(e) > tmax) continue;
      }
      cur = key_ref(e);
      return true;
    }
    return false;
  };

  while (true) {
    if (!wide_ref::is_leaf(cur)) {
      if constexpr (kCount) stats->nodes_visited++;
      const WideNode<N>& node = bvh.nodes[cur];
      V tnear;
      uint32_t mask = intersect_children(node, nr, tmin_v, V::broadcast(tmax), tnear);
      if (mask == 0) {
        if (!pop()) return hit;
        continue;
      }
      const uint32_t* child = node.child;
      const uint32_t i0 = simd::ctz(mask);
      const uint32_t rest = mask & (mask - 1);
      if (rest == 0) {
        cur = child[i0];
        continue;
      }
      alignas(64) float dist[N];
      tnear.store(dist);
      const uint32_t i1 = simd::ctz(rest);
      if ((rest & (rest - 1)) == 0) {
        uint32_t near = child[i0], far = child[i1];
        float dfar = dist[i1];
        if (dist[i1] < dist[i0]) {
          near = child[i1];
          far = child[i0];
          dfar = dist[i0];
        }
        stack[sp++] = child_key(dfar, far);
        cur = near;
        continue;
      }
      // Three or more: sort by distance, push all but the nearest.
      const int k = simd::popcount(mask);
#if defined(RAYLAB_SIMD_AVX512)
      if constexpr (N == 8) {
        const __m256i bits = _mm256_max_epi32(_mm256_castps_si256(tnear.v), _mm256_setzero_si256());
        // Zero-masking forms: see sort_network.h on GCC 12's -Wuninitialized.
        const __m512i keys = _mm512_or_si512(
            _mm512_maskz_slli_epi64(0xFF, _mm512_maskz_cvtepu32_epi64(0xFF, bits), 32),
            _mm512_maskz_cvtepu32_epi64(0xFF, _mm256_load_si256(reinterpret_cast<const __m256i*>(child))));
        __m512i sorted = _mm512_maskz_compress_epi64(static_cast<__mmask8>(mask), keys);
        sorted = k <= 4 ? sort4x2_descending(sorted) : sort8_descending(sorted);
        _mm512_storeu_si512(stack + sp, sorted);
        sp += k - 1;
        cur = key_ref(stack[sp]);
        continue;
      }
#endif
      uint64_t* keys = stack + sp;
      int n = 0;
      for (uint32_t m = mask; m != 0; m &= m - 1) {
        const uint32_t i = simd::ctz(m);
        keys[n++] = child_key(dist[i], child[i]);
      }
      sort8_keys_descending(keys, n);
      sp += k - 1;
      cur = key_ref(stack[sp]);
      continue;
    }

    // Leaf: test its triangle blocks.
    const uint32_t nblocks = wide_ref::leaf_blocks(cur);
    const TriangleBlock<W>* blk = bvh.blocks + wide_ref::leaf_first(cur);
    if constexpr (kCount) stats->nodes_visited += nblocks != 0;
    for (uint32_t b = 0; b < nblocks; ++b) {
      if constexpr (kCount) stats->triangle_tests += static_cast<uint64_t>(blk[b].count());
      BlockHits<W> bh;
      uint32_t m = intersect_block<W>(blk[b], br, tmin, tmax, bh);
      if (m == 0) continue;
      uint32_t best = simd::ctz(m);
      if constexpr (kAnyHit) return Hit{bh.t[best], bh.u[best], bh.v[best], blk[b].prim[best]};
      float bt = bh.t[best];
      for (m &= m - 1; m != 0; m &= m - 1) {
        const uint32_t i = simd::ctz(m);
        if (bh.t[i] < bt) {
          bt = bh.t[i];
          best = i;
        }
      }
      if (bt < tmax || !hit.valid()) {
        hit = Hit{bt, bh.u[best], bh.v[best], blk[b].prim[best]};
        tmax = bt;
      }
    }
    if (!pop()) return hit;
  }
}

}  // namespace raylab
