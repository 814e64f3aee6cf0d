#pragma once
// Packet traversal of the 8-wide BVH for coherent rays (`bvh:packet=16`):
// 16 rays from one origin walk the tree as one frustum. Each node's 8 child
// boxes are tested once for the whole packet by interval arithmetic over
// the rays' reciprocal directions (Wald, Boulos and Shirley, "Ray Tracing
// Deformable Scenes Using Dynamic Bounding Volume Hierarchies", ACM TOG
// 2007; Reshetov, Soupikov and Hurley, "Multi-Level Ray Tracing Algorithm",
// SIGGRAPH 2005, for the frustum idea), so an inner node costs about what it
// costs one ray. At a leaf every ray takes its own box test of the leaf (the
// single-ray test, lane by lane), and the rays that pass test the leaf's
// triangles one triangle at a time, 16 rays per vector; when only a few rays
// pass, each tests the leaf's blocks as a single ray does, a triangle per
// lane (fewer vector tests: one per block and ray instead of one per triangle).
//
// Only 16-ray chunks whose rays share one origin and one direction octant
// form a packet (pinhole camera rays); everything else is traced by the
// single-ray kernel (Benthin, Wald, Woop, Ernst and Mark, HPG 2012, combine
// packets and single rays the same way). Rays the fast kernel does not take (invalid, nearly axis-parallel,
// tmin < 0, origin far outside the scene) are traced singly. Rays from many
// points (shadow rays of a camera's hits) were measured slower as packets
// than as single rays (docs/structures/bvh.md), so diffuse, shadow and random
// sets pay only the common-origin test.
//
// Answers equal the single-ray walk's bit for bit: the frustum test culls a
// box only when every ray's own box test would cull it (see PacketFrustum),
// a leaf's triangles are tested only by rays whose own test enters the
// leaf's box, and each ray's triangle test computes, lane by lane, the
// values the single-ray block test computes. With the recorder's tie rule
// (least (t, prim), see HitRecorder) the visiting order does not matter.
// Closest hit only: occlusion stays single-ray.
#include <algorithm>
#include <cstdint>
#include <span>

#include "accel/bvh/traverse_wide.h"

namespace raylab {

inline constexpr int kPacketSize = 16;

// The watertight test's dominant axis of a direction (WatertightRay::kz).
inline int dominant_axis(const Vec3f& d) {
  const Vec3f ad = d.cwiseAbs();
  return (ad.x() >= ad.y()) ? (ad.x() >= ad.z() ? 0 : 2) : (ad.y() >= ad.z() ? 1 : 2);
}

// Least (kMax false) or greatest lane of a 16-lane vector.
template <bool kMax>
inline float lanes_extreme(simd::vfloat<kPacketSize> x) {
#if defined(RAYLAB_SIMD_AVX512)
  // Halving (zero-masking extracts: see vfloat<16> on GCC 12's warnings).
  const auto pick = [](auto a, auto b) {
    if constexpr (sizeof(a) == 32) return kMax ? _mm256_max_ps(a, b) : _mm256_min_ps(a, b);
    else return kMax ? _mm_max_ps(a, b) : _mm_min_ps(a, b);
  };
  const __m256 h = pick(_mm512_maskz_extractf32x8_ps(0xFF, x.v, 0), _mm512_maskz_extractf32x8_ps(0xFF, x.v, 1));
  const __m128 q = pick(_mm256_castps256_ps128(h), _mm256_extractf128_ps(h, 1));
  const __m128 e = pick(q, _mm_movehl_ps(q, q));
  return _mm_cvtss_f32(pick(e, _mm_movehdup_ps(e)));
#else
  alignas(64) float f[kPacketSize];
  x.store(f);
  return kMax ? *std::max_element(f, f + kPacketSize) : *std::min_element(f, f + kPacketSize);
#endif
}
inline float lanes_min(simd::vfloat<kPacketSize> x) { return lanes_extreme<false>(x); }
inline float lanes_max(simd::vfloat<kPacketSize> x) { return lanes_extreme<true>(x); }

// 16 rays in structure-of-arrays form.
struct PacketInput {
  alignas(64) float org[3][kPacketSize];
  alignas(64) float dir[3][kPacketSize];
  alignas(64) float tmin[kPacketSize];
  alignas(64) float tmax[kPacketSize];

  explicit PacketInput(std::span<const Ray> rays) {
    for (int i = 0; i < kPacketSize; ++i) {
      const Ray& r = rays[i];
      for (int a = 0; a < 3; ++a) org[a][i] = r.org[a], dir[a][i] = r.dir[a];
      tmin[i] = r.tmin;
      tmax[i] = std::min(r.tmax, std::numeric_limits<float>::max());  // as HitRecorder: finite hits only
    }
  }

  // True when the rays form a packet: one origin, one direction octant, and
  // each ray one the fast single-ray kernel takes (valid, not nearly
  // axis-parallel, tmin >= 0, origin within fma_origin_limit: see
  // traverse_wide), lane by lane.
  bool coherent(float fma_origin_limit) const {
    using V = simd::vfloat<kPacketSize>;
    constexpr uint32_t kAll = (1u << kPacketSize) - 1u;
    const V zero = V::broadcast(0.0f), sign = V::broadcast(-0.0f);
    bool ok = true;
    for (int a = 0; a < 3; ++a) {
      const float o = org[a][0];
      ok &= (o - o == 0.0f) & !(std::fabs(o) > fma_origin_limit);  // finite, near enough
      ok &= cmp_eq(V::load(org[a]), V::broadcast(o)) == kAll;
      const V d = V::load(dir[a]);
      ok &= cmp_ge(andnot(sign, d), V::broadcast(1e-30f)) == kAll;  // not (nearly) axis-parallel, not NaN
      ok &= cmp_eq(d - d, zero) == kAll;                    // finite
      const uint32_t neg = cmp_lt(d, zero);
      ok &= neg == 0 || neg == kAll;  // one octant
    }
    const V t0 = V::load(tmin);
    ok &= (cmp_ge(t0, zero) & cmp_le(t0, V::load(tmax))) == kAll;
    return ok;
  }
};

// Per-ray constants of a packet, one lane per ray: the single-ray box test's
// reciprocals and plane shifts (the values init_node_ray computes, in vector
// form), and the watertight test's shear (WatertightRay). The shear's axis
// permutation follows the ray's dominant axis kz (kx, ky then follow from kz
// and the packet's octant), so the lanes fall into up to three groups, each
// tested with its own permutation (lanes_of_kz). Vector division is correctly
// rounded, so every value equals the scalar one.
struct PacketRays {
  using V = simd::vfloat<kPacketSize>;
  V inv[3], near_shift[3], far_shift[3];
  V tmin;
  alignas(64) float sx[kPacketSize], sy[kPacketSize], sz[kPacketSize], tmin_lane[kPacketSize];
  float org[3];
  int near_row[3], far_row[3];  // rows of WideNode::bounds: the octant's near / far plane per axis
  uint32_t lanes_of_kz[3];       // the lanes whose dominant axis is kz
  int axes[3][3];                // for each kz: the permuted axes kx, ky, kz
};

// The packet's frustum in interval form (Wald, Boulos and Shirley 2007):
// per axis the range [inv_lo, inv_hi] of the rays' reciprocals (one sign: one
// octant), the least near shift and the greatest far shift. For a plane x,
// every ray's computed near distance fl(x * inv_i + near_shift_i) is at least
// fl(min(x * inv_lo, x * inv_hi) + least shift): x * inv is monotonic in inv
// and rounding is monotonic; the test computes that bound exactly as the min
// of two FMAs. The far side is the mirror image. So a box the frustum test
// culls is culled by every ray's own test. N: the node width (8 or 16), one
// child per lane.
template <int N = 8>
struct PacketFrustum {
  using V = simd::vfloat<N>;
  V inv_lo[3], inv_hi[3], near_shift[3], far_shift[3];
  V tmin;  // least tmin of the packet (>= +0)
  int near_off[3], far_off[3];  // float offsets of the near / far plane rows in a node
};

// Closest hits of a packet, one lane per ray; t starts at the ray's tmax,
// prim at kInvalidPrim.
struct PacketHits {
  alignas(64) float t[kPacketSize];
  alignas(64) float u[kPacketSize];
  alignas(64) float v[kPacketSize];
  alignas(64) uint32_t prim[kPacketSize];

  // The greatest closest-hit bound over the lanes.
  float greatest_t() const { return lanes_max(simd::vfloat<kPacketSize>::load(t)); }
};

// L lanes of a packet's hits from lane `first` on (L = 16, or 8 when a leaf
// is entered by rays of one half only), in registers while a leaf is tested.
template <int L>
struct HitLanes {
  using V = simd::vfloat<L>;
  V t, u, v;
  uint32_t* prim;

  HitLanes(const PacketHits& h, int first)
      : t(V::load(h.t + first)), u(V::load(h.u + first)), v(V::load(h.v + first)),
        prim(const_cast<uint32_t*>(h.prim) + first) {}
  void store(PacketHits& h, int first) const { t.store(h.t + first), u.store(h.u + first), v.store(h.v + first); }

  // Offers candidate hits (t, u, v) of triangle `cprim` in the lanes of
  // `mask` (which hold tmin <= ct <= t): kept by the recorder's rule,
  // strictly nearer, or as near with a lower primitive id (HitRecorder).
  void record(uint32_t mask, V ct, V cu, V cv, uint32_t cprim) {
#if defined(RAYLAB_SIMD_AVX512)
    if constexpr (L == 16) {
      const __m512i p = _mm512_load_si512(prim);
      const __m512i cp = _mm512_set1_epi32(static_cast<int>(cprim));
      const __mmask16 keep = static_cast<__mmask16>(mask & (cmp_lt(ct, t) | _mm512_cmpgt_epu32_mask(p, cp)));
      t.v = _mm512_mask_mov_ps(t.v, keep, ct.v);
      u.v = _mm512_mask_mov_ps(u.v, keep, cu.v);
      v.v = _mm512_mask_mov_ps(v.v, keep, cv.v);
      _mm512_store_si512(prim, _mm512_mask_mov_epi32(p, keep, cp));
      return;
    } else if constexpr (L == 8) {
      const __m256i p = _mm256_load_si256(reinterpret_cast<const __m256i*>(prim));
      const __m256i cp = _mm256_set1_epi32(static_cast<int>(cprim));
      const __mmask8 keep = static_cast<__mmask8>(mask & (cmp_lt(ct, t) | _mm256_cmpgt_epu32_mask(p, cp)));
      t.v = _mm256_mask_mov_ps(t.v, keep, ct.v);
      u.v = _mm256_mask_mov_ps(u.v, keep, cu.v);
      v.v = _mm256_mask_mov_ps(v.v, keep, cv.v);
      _mm256_store_si256(reinterpret_cast<__m256i*>(prim), _mm256_mask_mov_epi32(p, keep, cp));
      return;
    }
#endif
    alignas(64) float ft[L], fu[L], fv[L], bt[L], bu[L], bv[L];
    ct.store(ft), cu.store(fu), cv.store(fv), t.store(bt), u.store(bu), v.store(bv);
    for (uint32_t m = mask; m != 0; m &= m - 1) {
      const uint32_t i = simd::ctz(m);
      if (ft[i] < bt[i] || cprim < prim[i]) bt[i] = ft[i], bu[i] = fu[i], bv[i] = fv[i], prim[i] = cprim;
    }
    t = V::load(bt), u = V::load(bu), v = V::load(bv);
  }
};

// The lanes' constants and the frustum, from 16 coherent rays.
template <int N>
inline void make_packet(const PacketInput& in, PacketRays& pr, PacketFrustum<N>& fr, PacketHits& ph) {
  using V = simd::vfloat<kPacketSize>;
  using VN = simd::vfloat<N>;
  const V zero = V::broadcast(0.0f), one = V::broadcast(1.0f);
  // -0 as +0, as the single-ray kernel (tmin >= 0 here).
  const V tmin = max(V::load(in.tmin), zero);
  tmin.store(pr.tmin_lane);
  pr.tmin = tmin;
  std::copy(in.tmax, in.tmax + kPacketSize, ph.t);
  std::fill(ph.u, ph.u + kPacketSize, 0.0f);
  std::fill(ph.v, ph.v + kPacketSize, 0.0f);
  std::fill(ph.prim, ph.prim + kPacketSize, kInvalidPrim);
  int octant = 0;
  for (int a = 0; a < 3; ++a) {
    pr.org[a] = in.org[a][0];
    const int neg = std::signbit(in.dir[a][0]) ? 1 : 0;
    octant |= neg << a;
    pr.near_row[a] = 2 * a + neg;
    pr.far_row[a] = 2 * a + 1 - neg;
    // As init_node_ray: o * inv bounded from above and below by |o * inv| *
    // 2^-22 + FLT_MIN; max/min against -+FLT_MAX turn NaN (inf - inf) into
    // the clamp, as there.
    pr.inv[a] = one / V::load(in.dir[a]);
    const V oi = V::broadcast(pr.org[a]) * pr.inv[a];
    const V delta = andnot(V::broadcast(-0.0f), oi) * V::broadcast(0x1p-22f) + V::broadcast(FLT_MIN);
    pr.near_shift[a] = max(oi + delta, V::broadcast(-FLT_MAX)) * V::broadcast(-1.0f);
    pr.far_shift[a] = min(oi - delta, V::broadcast(FLT_MAX)) * V::broadcast(-1.0f);
    // The frustum: extremes over the lanes.
    fr.inv_lo[a] = VN::broadcast(lanes_min(pr.inv[a]));
    fr.inv_hi[a] = VN::broadcast(lanes_max(pr.inv[a]));
    fr.near_shift[a] = VN::broadcast(lanes_min(pr.near_shift[a]));
    fr.far_shift[a] = VN::broadcast(lanes_max(pr.far_shift[a]));
    fr.near_off[a] = pr.near_row[a] * N;
    fr.far_off[a] = pr.far_row[a] * N;
  }
  fr.tmin = VN::broadcast(lanes_min(tmin));
  // The watertight shear, as WatertightRay, for each dominant axis present.
  const V sign = V::broadcast(-0.0f);
  const V ax = andnot(sign, V::load(in.dir[0])), ay = andnot(sign, V::load(in.dir[1])),
          az = andnot(sign, V::load(in.dir[2]));
  const uint32_t x_ge_y = cmp_ge(ax, ay), x_ge_z = cmp_ge(ax, az), y_ge_z = cmp_ge(ay, az);
  pr.lanes_of_kz[0] = x_ge_y & x_ge_z;
  pr.lanes_of_kz[1] = ~x_ge_y & y_ge_z & 0xFFFFu;
  pr.lanes_of_kz[2] = ~(pr.lanes_of_kz[0] | pr.lanes_of_kz[1]) & 0xFFFFu;
  for (int kz = 0; kz < 3; ++kz) {
    int kx = kz == 2 ? 0 : kz + 1, ky = kx == 2 ? 0 : kx + 1;
    if (((octant >> kz) & 1) != 0) std::swap(kx, ky);  // keep the winding, as WatertightRay
    pr.axes[kz][0] = kx, pr.axes[kz][1] = ky, pr.axes[kz][2] = kz;
    const uint32_t lanes = pr.lanes_of_kz[kz];
    if (lanes == 0) continue;
    // 1 / dz is the slab test's reciprocal (correctly rounded either way).
    const V inv_dz = pr.inv[kz];
    if (lanes == 0xFFFFu) {  // the common case: one dominant axis for the packet
      (V::load(in.dir[kx]) * inv_dz).store(pr.sx);
      (V::load(in.dir[ky]) * inv_dz).store(pr.sy);
      inv_dz.store(pr.sz);
      continue;
    }
    alignas(64) float sx[kPacketSize], sy[kPacketSize], sz[kPacketSize];
    (V::load(in.dir[kx]) * inv_dz).store(sx);
    (V::load(in.dir[ky]) * inv_dz).store(sy);
    inv_dz.store(sz);
    for (uint32_t m = lanes; m != 0; m &= m - 1) {
      const uint32_t i = simd::ctz(m);
      pr.sx[i] = sx[i], pr.sy[i] = sy[i], pr.sz[i] = sz[i];
    }
  }
}

// The N child boxes against the frustum: the mask of children some ray may
// enter before tmax_hi (the packet's greatest closest hit so far), and
// lower bounds of the rays' entry distances (for the visiting order).
template <int N>
inline uint32_t frustum_children(const WideNode<N>& node, const PacketFrustum<N>& f, simd::vfloat<N> tmax_hi,
                                 simd::vfloat<N>& tnear) {
  using VN = simd::vfloat<N>;
  const float* b = &node.bounds[0][0];
  VN lo[3], hi[3];
  for (int a = 0; a < 3; ++a) {
    const VN pn = VN::load(b + f.near_off[a]);
    const VN pf = VN::load(b + f.far_off[a]);
    lo[a] = min(fmadd(pn, f.inv_lo[a], f.near_shift[a]), fmadd(pn, f.inv_hi[a], f.near_shift[a]));
    hi[a] = max(fmadd(pf, f.inv_lo[a], f.far_shift[a]), fmadd(pf, f.inv_hi[a], f.far_shift[a]));
  }
  // Integer-order min/max as in intersect_children (tmin >= +0).
  tnear = max_bits(max_bits(lo[0], lo[1]), max_bits(lo[2], f.tmin));
  // The far padding on the bits (kSlabFarPadUlps) is monotonic in the
  // integer order, so the frustum's padded far bound stays above every ray's.
  return padded_slab_mask(tnear, min_bits(min_bits(hi[0], hi[1]), min_bits(hi[2], tmax_hi)));
}

// The rays whose own box test (the single-ray FMA slab test, lane by lane)
// enters child `slot` of `node` before their closest hit.
template <int N>
inline uint32_t rays_entering(const WideNode<N>& node, uint32_t slot, const PacketRays& pr,
                              simd::vfloat<kPacketSize> tmax) {
  using V = simd::vfloat<kPacketSize>;
  V near[3], far[3];
  for (int a = 0; a < 3; ++a) {
    near[a] = fmadd(V::broadcast(node.bounds[pr.near_row[a]][slot]), pr.inv[a], pr.near_shift[a]);
    far[a] = fmadd(V::broadcast(node.bounds[pr.far_row[a]][slot]), pr.inv[a], pr.far_shift[a]);
  }
  const V tnear = max_bits(max_bits(near[0], near[1]), max_bits(near[2], pr.tmin));
  return padded_slab_mask(tnear, min_bits(min_bits(far[0], far[1]), min_bits(far[2], tmax)));
}

// N: node width, 8 or 16 (a frustum test of all children in one vector of
// N lanes); W: triangles per block.
template <int N, int W>
class PacketTracer {
 public:
  static_assert(N == 8 || N == 16);
  using V = simd::vfloat<kPacketSize>;
  using VN = simd::vfloat<N>;

  explicit PacketTracer(const WideView<N, W>& bvh) : bvh_(bvh) {}

  // Closest hits of rays (any count), 16 at a time in the order given; the
  // runs of rays that form no packet go to single(rays, hits), the kernel's
  // own single-ray batch loop.
  template <typename Single>
  void intersect(std::span<const Ray> rays, std::span<Hit> hits, Single&& single) const {
    size_t run = 0;  // first ray of the current run of rays traced singly
    for (size_t b = 0; b < rays.size(); b += kPacketSize) {
      const size_t n = std::min<size_t>(kPacketSize, rays.size() - b);
      // First and last ray from one point (cheap, and false for most
      // incoherent chunks), then the whole test on the gathered lanes.
      if (n == kPacketSize && !wide_ref::is_leaf(bvh_.root_ref) && rays[b].org == rays[b + n - 1].org) {
        const PacketInput in(rays.subspan(b, n));
        if (in.coherent(bvh_.fma_origin_limit)) {
          if (run < b) single(rays.subspan(run, b - run), hits.subspan(run, b - run));
          trace_packet(in, rays.subspan(b, n), hits.subspan(b, n));
          run = b + n;
        }
      }
    }
    if (run < rays.size()) single(rays.subspan(run), hits.subspan(run));
  }

 private:
  // Children are pushed as (parent node, slot) (WideKernel checks that node
  // indices fit).
  static constexpr int kSlotBits = N == 16 ? 4 : 3;

 public:
  // The most nodes a tree may have for those child references.
  static constexpr size_t kMaxNodes = size_t{wide_ref::kLeafBit} >> kSlotBits;

 private:

  void trace_packet(const PacketInput& in, std::span<const Ray> rays, std::span<Hit> hits) const {
    PacketRays pr;
    PacketFrustum<N> fr;
    PacketHits ph;
    make_packet(in, pr, fr, ph);
    walk(rays, pr, fr, ph);
    for (int i = 0; i < kPacketSize; ++i)
      hits[i] = ph.prim[i] == kInvalidPrim ? Hit{} : Hit{ph.t[i], ph.u[i], ph.v[i], ph.prim[i]};
  }

  // The frustum walk: each inner node's children are culled and ordered for
  // the whole packet by the frustum test, and pushed as (parent, slot). When
  // one is taken, every ray first runs its own test of the child's box
  // (rays_entering): a child no ray enters is skipped, a leaf is tested by the
  // rays that enter it, and a subtree entered by one ray is finished by that
  // ray's single-ray walk (Benthin et al. 2012), which continues from its
  // closest hit so far.
  void walk(std::span<const Ray> rays, const PacketRays& pr, const PacketFrustum<N>& fr, PacketHits& ph) const {
    float tmax_hi = ph.greatest_t();
    alignas(64) uint64_t stack[kWideStackSize];
    uint64_t* top = stack;
    uint32_t node_index = bvh_.root_ref;
    while (true) {
      // The packet visits an inner node: the children the frustum keeps go
      // on the stack (the nearest, if several, straight to `next`).
      const WideNode<N>& node = bvh_.nodes[node_index];
      VN tnear;
      const uint32_t mask = frustum_children(node, fr, VN::broadcast(tmax_hi), tnear);
      uint32_t next = 0;
      bool have_next = false;
      if (mask != 0) {
        alignas(64) uint32_t refs[N];
        for (uint32_t c = 0; c < N; ++c) refs[c] = child_visit_ref(node_index, c, node.child[c]);
        const auto prefetch = [&](uint32_t i) __attribute__((always_inline)) { prefetch_child(bvh_, node.child[i]); };
        if ((mask & (mask - 1)) == 0) {
          next = refs[simd::ctz(mask)];
        } else {
          next = push_by_distance<N>(refs, mask, tnear, top, prefetch);
        }
        have_next = true;
      }
      // Entries until the next inner node the packet visits together.
      while (true) {
        if (!have_next) {
          // Next entry some ray can still enter before its closest hit (the
          // single-ray walk culls the same way, see walk_wide's pop).
          const uint64_t limit = key_cull_limit(tmax_hi);
          while (top != stack && top[-1] > limit) --top;
          if (top == stack) return;
          next = key_ref(*--top);
        }
        have_next = false;
        const WideNode<N>& parent = bvh_.nodes[(next & ~wide_ref::kLeafBit) >> kSlotBits];
        const uint32_t slot = next & ((1u << kSlotBits) - 1u);
        const uint32_t active = rays_entering(parent, slot, pr, V::load(ph.t));
        if (active == 0) continue;
        const uint32_t child = parent.child[slot];
        // The packet's far bound shrinks only when some ray finds a hit.
        if (wide_ref::is_leaf(child)) {
          if (intersect_leaf(child, pr, active, ph)) tmax_hi = ph.greatest_t();
        } else if (simd::popcount(active) <= kSingleRayAtMost) {
          for (uint32_t m = active; m != 0; m &= m - 1) finish_single(rays, simd::ctz(m), child, ph);
          tmax_hi = ph.greatest_t();
        } else {
          node_index = child;
          break;
        }
      }
    }
  }

  // Subtrees entered by at most this many rays are finished ray by ray (1
  // measured 2-3 % faster than 2, and than 0, since leaves entered by few
  // rays are tested ray by ray).
  static constexpr int kSingleRayAtMost = 1;
  // Leaves entered by at most this many rays are tested ray by ray, a
  // triangle per lane (intersect_leaf_per_ray): measured against 0, 2, 6 and
  // 8 on the five interior views' camera rays.
  static constexpr int kPerRayLeafAtMost = 4;

  // A child as the packet walk pushes it: (parent node, slot), with the leaf
  // bit of the child (so that leaves keep their place in the key order).
  static uint32_t child_visit_ref(uint32_t node, uint32_t slot, uint32_t child) {
    return (child & wide_ref::kLeafBit) | node << kSlotBits | slot;
  }

  // Ray i finishes subtree `start` alone, from its closest hit so far.
  void finish_single(std::span<const Ray> rays, uint32_t i, uint32_t start, PacketHits& ph) const {
    HitRecorder<false, false> rec(rays[i], nullptr);
    if (ph.prim[i] != kInvalidPrim) rec.record(ph.t[i], ph.u[i], ph.v[i], ph.prim[i]);
    walk_wide<N, W, false, false, false>(bvh_, rays[i], start, rec);
    if (rec.found()) {
      const Hit& h = rec.hit();
      ph.t[i] = h.t, ph.u[i] = h.u, ph.v[i] = h.v, ph.prim[i] = h.prim;
    }
  }

  // A leaf against the rays that enter it: half-width vectors when they are
  // all in one half of the packet. False when no ray's closest hit changed.
  bool intersect_leaf(uint32_t leaf, const PacketRays& pr, uint32_t active, PacketHits& ph) const {
    const TriangleBlock<W>* blocks = bvh_.blocks + wide_ref::leaf_first(leaf);
    const uint32_t nblocks = wide_ref::leaf_blocks(leaf);
    if (simd::popcount(active) <= kPerRayLeafAtMost) return intersect_leaf_per_ray(blocks, nblocks, pr, active, ph);
    if ((active >> 8) == 0) return intersect_lanes<8>(blocks, nblocks, pr, 0, active, ph);
    if ((active & 0xFFu) == 0) return intersect_lanes<8>(blocks, nblocks, pr, 8, active >> 8, ph);
    return intersect_lanes<16>(blocks, nblocks, pr, 0, active, ph);
  }

  // A lane's closest hit as a recorder for the single-ray block functions
  // (HitRecorder's rule; the lane starts at the ray's tmax or its hit so far).
  struct LaneRecorder {
    static constexpr bool kStopAtFirstHit = false;
    PacketHits& ph;
    uint32_t i;
    float tmax() const { return ph.t[i]; }
    void count_triangles(uint64_t) const {}
    bool record(float t, float u, float v, uint32_t prim) {
      if (t < ph.t[i] || (t == ph.t[i] && prim < ph.prim[i])) {
        ph.t[i] = t, ph.u[i] = u, ph.v[i] = v, ph.prim[i] = prim;
        return true;
      }
      return false;
    }
  };

  // A leaf entered by few rays: each ray takes the single-ray block test (a
  // triangle per lane), one vector test per block and ray instead of one per
  // triangle. Its values per ray and triangle are the lane-per-ray test's.
  static bool intersect_leaf_per_ray(const TriangleBlock<W>* blocks, uint32_t nblocks, const PacketRays& pr,
                                     uint32_t active, PacketHits& ph) {
    bool hit = false;
    for (uint32_t m = active; m != 0; m &= m - 1) {
      const uint32_t i = simd::ctz(m);
      // The lane's WatertightRay, from the values make_packet computed for it.
      const int kz = (pr.lanes_of_kz[0] >> i) & 1u ? 0 : (pr.lanes_of_kz[1] >> i) & 1u ? 1 : 2;
      WatertightRay w;
      w.org = Vec3f(pr.org[0], pr.org[1], pr.org[2]);
      w.kx = pr.axes[kz][0], w.ky = pr.axes[kz][1], w.kz = kz;
      w.sx = pr.sx[i], w.sy = pr.sy[i], w.sz = pr.sz[i];
      BlockRay<W> br;
      br.init(w);
      LaneRecorder rec{ph, i};
      hit |= intersect_block_leaf(blocks, nblocks, br, pr.tmin_lane[i], rec);
    }
    return hit;
  }

  // The watertight test of intersect_block with rays in the lanes instead of
  // triangles: for each lane the same operations in the same order on the
  // same values (translate, fused shear, edge functions, the double-precision
  // recomputation of an exactly-zero edge function, sign test, t = tt *
  // (1 / det)), so each ray gets bit for bit the t, u, v its single-ray test
  // gives. The rays share their origin, so a vertex's translation p - org is
  // one value for all lanes, computed once per block. (intersect_block's
  // early rejection of hits behind the origin only saves work: those lanes
  // fail t >= tmin here.) Hits are kept by the recorder's rule (HitRecorder).
  template <int L>
  static bool intersect_lanes(const TriangleBlock<W>* blocks, uint32_t nblocks, const PacketRays& r, int first,
                              uint32_t active, PacketHits& ph) {
    HitLanes<L> h(ph, first);
    bool hit = false;
    for (int kz = 0; kz < 3; ++kz) {
      const uint32_t lanes = active & (r.lanes_of_kz[kz] >> first);
      if (lanes == 0) continue;
      for (uint32_t b = 0; b < nblocks; ++b) hit |= intersect_block_packet<L>(blocks[b], r, r.axes[kz], first, lanes, h);
    }
    if (hit) h.store(ph, first);
    return hit;
  }

  template <int L>
  static bool intersect_block_packet(const TriangleBlock<W>& blk, const PacketRays& r, const int* axis, int first,
                                     uint32_t active, HitLanes<L>& h) {
    using VL = simd::vfloat<L>;
    using VW = simd::vfloat<W>;
    // Translated vertices: rel[corner][k][lane], k = 0, 1, 2 for kx, ky, kz (axis[k]).
    alignas(64) float rel[3][3][W];
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k)
        (VW::load(blk.v[c][axis[k]]) - VW::broadcast(r.org[axis[k]])).store(rel[c][k]);
    const VL sign = VL::broadcast(-0.0f);
    const VL nsx = xor_bits(VL::load(r.sx + first), sign), nsy = xor_bits(VL::load(r.sy + first), sign);
    const VL sz = VL::load(r.sz + first);
    const VL tmin = VL::load(r.tmin_lane + first);
    const int count = blk.count();  // padding lanes repeat the first triangle
    bool hit = false;
    for (int j = 0; j < count; ++j) {
      const VL az0 = VL::broadcast(rel[0][2][j]);
      const VL bz0 = VL::broadcast(rel[1][2][j]);
      const VL cz0 = VL::broadcast(rel[2][2][j]);
      const VL ax = fmadd(nsx, az0, VL::broadcast(rel[0][0][j]));
      const VL ay = fmadd(nsy, az0, VL::broadcast(rel[0][1][j]));
      const VL bx = fmadd(nsx, bz0, VL::broadcast(rel[1][0][j]));
      const VL by = fmadd(nsy, bz0, VL::broadcast(rel[1][1][j]));
      const VL cx = fmadd(nsx, cz0, VL::broadcast(rel[2][0][j]));
      const VL cy = fmadd(nsy, cz0, VL::broadcast(rel[2][1][j]));
      VL u, v, w, det;
      uint32_t mask = watertight_edges<L>(ax, ay, bx, by, cx, cy, active, u, v, w, det);
      if (mask == 0) continue;
      const VL tt = sz * fmadd(w, cz0, fmadd(v, bz0, u * az0));
      const VL inv_det = VL::broadcast(1.0f) / det;
      const VL t = tt * inv_det;
      mask &= cmp_ge(t, tmin) & cmp_le(t, h.t);
      if (mask != 0) h.record(mask, t, v * inv_det, w * inv_det, blk.prim[j]), hit = true;
    }
    return hit;
  }

  WideView<N, W> bvh_;
};

}  // namespace raylab
