#pragma once
// Leaf triangles W at a time, for every structure with SIMD leaves (the wide
// BVH, the k-d tree and BSP tree, the grids, the octrees; leaf_blocks.h fills
// them): a TriangleBlock holds the vertices of up to W triangles in
// structure-of-arrays order, and intersect_block() runs the watertight test
// of Woop, Benthin & Wald (JCGT 2013) on all W lanes at once.
//
// The vector test computes exactly what the scalar intersect_watertight()
// computes, lane by lane: the same translation p - org, the same fused shear,
// the same edge functions cx*by - cy*bx etc. (never fused, so a shared edge
// gives exactly opposite values in its two triangles), the same
// double-precision recomputation when an edge function is exactly 0, and the
// same t = sz * fma(w, cz, fma(v, bz, u*az)) * (1/det). Watertightness
// therefore carries over unchanged, and tests compare the two bit for bit.
//
// Only the vertices are stored: precomputing edges (as Moller-Trumbore
// layouts do) would change the rounding of p - org and break the shared-edge
// argument. Lanes past a leaf's last triangle repeat its first triangle (same
// answer, no masking needed in the hot loop).
//
// The study option tri=mt of the wide BVH stores (p0, p1 - p0, p2 - p0)
// instead and tests with the intersect_block overload taking a BlockRayMT
// (Moller and Trumbore 1997, the form of the fastest CPU tracers): not
// watertight, there to measure what watertightness costs on the same tree
// and walk.
#include <cstdint>

#include "accel/core/simd/simd.h"
#include "accel/core/intersect_triangle.h"

namespace raylab {

template <int W>
struct alignas(W >= 8 ? 64 : 32) TriangleBlock {
  float v[3][3][W];   // v[corner][axis][lane]
  uint32_t prim[W];   // triangle ids; padding lanes repeat prim[0]

  // Number of distinct triangles (padding lanes excluded), for statistics.
  int count() const {
    int c = 1;
    for (int i = 1; i < W; ++i) c += prim[i] != prim[0];
    return c;
  }
};

// Blocks of width W that hold `count` triangles (the last one padded).
template <int W>
constexpr uint32_t triangle_blocks(uint32_t count) {
  return (count + W - 1) / W;
}

// Per-ray constants of the block test: the same values as WatertightRay
// (axis permutation, shear constants), broadcast to W lanes.
template <int W>
struct BlockRay {
  using V = simd::vfloat<W>;
  V ox, oy, oz;            // origin components along kx, ky, kz
  V nsx, nsy, sz;          // shear constants, the first two negated (x - sx*z is fmadd(-sx, z, x))
  int off_x, off_y, off_z; // kx*W, ky*W, kz*W: offsets of the permuted axes in a block

  BlockRay() = default;
  explicit BlockRay(const Ray& r) { init(WatertightRay(r)); }
  void init(const WatertightRay& w) {
    ox = V::broadcast(w.org[w.kx]);
    oy = V::broadcast(w.org[w.ky]);
    oz = V::broadcast(w.org[w.kz]);
    nsx = V::broadcast(-w.sx);
    nsy = V::broadcast(-w.sy);
    sz = V::broadcast(w.sz);
    off_x = w.kx * W;
    off_y = w.ky * W;
    off_z = w.kz * W;
  }
};

// Per-ray constants of the Moller-Trumbore block test: origin and direction.
template <int W>
struct BlockRayMT {
  using V = simd::vfloat<W>;
  V ox, oy, oz, dx, dy, dz;
  BlockRayMT() = default;
  explicit BlockRayMT(const Ray& r) { init(r); }
  void init(const Ray& r) {
    ox = V::broadcast(r.org.x()), oy = V::broadcast(r.org.y()), oz = V::broadcast(r.org.z());
    dx = V::broadcast(r.dir.x()), dy = V::broadcast(r.dir.y()), dz = V::broadcast(r.dir.z());
  }
};

template <int W>
struct BlockHits {
  alignas(64) float t[W];
  alignas(64) float u[W];
  alignas(64) float v[W];
};

// An edge function is exactly 0 in the lanes of `zeros`: recompute those
// lanes' three edge functions in double precision, as the scalar test does.
// Used by watertight_edges.
template <int L>
inline void recompute_edges_in_double(uint32_t zeros, simd::vfloat<L> ax, simd::vfloat<L> ay, simd::vfloat<L> bx,
                                      simd::vfloat<L> by, simd::vfloat<L> cx, simd::vfloat<L> cy,
                                      simd::vfloat<L>& u, simd::vfloat<L>& v, simd::vfloat<L>& w) {
  using V = simd::vfloat<L>;
  alignas(64) float fax[L], fay[L], fbx[L], fby[L], fcx[L], fcy[L], fu[L], fv[L], fw[L];
  ax.store(fax), ay.store(fay), bx.store(fbx), by.store(fby), cx.store(fcx), cy.store(fcy);
  u.store(fu), v.store(fv), w.store(fw);
  for (uint32_t m = zeros; m != 0; m &= m - 1) {
    const uint32_t i = simd::ctz(m);
    fu[i] = static_cast<float>(static_cast<double>(fcx[i]) * fby[i] - static_cast<double>(fcy[i]) * fbx[i]);
    fv[i] = static_cast<float>(static_cast<double>(fax[i]) * fcy[i] - static_cast<double>(fay[i]) * fcx[i]);
    fw[i] = static_cast<float>(static_cast<double>(fbx[i]) * fay[i] - static_cast<double>(fby[i]) * fax[i]);
  }
  u = V::load(fu), v = V::load(fv), w = V::load(fw);
}

// The watertight test's edge functions u, v, w and det = u + v + w from the
// sheared coordinates, L lanes at once (a triangle per lane in the block
// test, a ray per lane in the packet test, traverse_packet.h). Returns the
// lanes of `lanes` whose edge functions are not of mixed signs and whose det
// is not 0 (a lane with a NaN edge function may pass, as in the scalar test,
// and fails the caller's range test); u, v, w, det are set when that is not 0.
template <int L>
[[gnu::always_inline]] inline uint32_t watertight_edges(simd::vfloat<L> ax, simd::vfloat<L> ay, simd::vfloat<L> bx,
                                                        simd::vfloat<L> by, simd::vfloat<L> cx, simd::vfloat<L> cy,
                                                        uint32_t lanes, simd::vfloat<L>& u, simd::vfloat<L>& v,
                                                        simd::vfloat<L>& w, simd::vfloat<L>& det) {
  using V = simd::vfloat<L>;
  u = cx * by - cy * bx;
  v = ax * cy - ay * cx;
  w = bx * ay - by * ax;
  const V zero = V::broadcast(0.0f);
  const uint32_t zeros = (cmp_eq(u, zero) | cmp_eq(v, zero) | cmp_eq(w, zero)) & lanes;
  if (zeros == 0) [[likely]] {
    // No edge function is 0, so "not of mixed signs" is "the same sign bit"
    // (two xors instead of six comparisons). Terms of one sign, none 0,
    // never sum to 0, so det != 0 needs no test here.
    const uint32_t mask = ~(sign_bits(xor_bits(u, v)) | sign_bits(xor_bits(u, w))) & lanes;
    if (mask != 0) det = u + v + w;
    return mask;
  }
  recompute_edges_in_double(zeros, ax, ay, bx, by, cx, cy, u, v, w);
  const uint32_t neg = cmp_lt(u, zero) | cmp_lt(v, zero) | cmp_lt(w, zero);
  const uint32_t pos = cmp_gt(u, zero) | cmp_gt(v, zero) | cmp_gt(w, zero);
  uint32_t mask = ~(neg & pos) & lanes;
  if (mask == 0) return 0;
  det = u + v + w;
  return mask & cmp_neq(det, zero);
}

// Tests all W lanes; returns the mask of lanes hit with tmin <= t <= tmax and
// fills t, u, v for them.
template <int W>
[[gnu::always_inline]] inline uint32_t intersect_block(const TriangleBlock<W>& blk, const BlockRay<W>& r, float tmin, float tmax,
                                BlockHits<W>& out) {
  using V = simd::vfloat<W>;
  const float* p0 = &blk.v[0][0][0];
  const float* p1 = &blk.v[1][0][0];
  const float* p2 = &blk.v[2][0][0];
  // Translate (a = p - org), then shear along the dominant axis.
  const V az0 = V::load(p0 + r.off_z) - r.oz;
  const V bz0 = V::load(p1 + r.off_z) - r.oz;
  const V cz0 = V::load(p2 + r.off_z) - r.oz;
  const V ax = fmadd(r.nsx, az0, V::load(p0 + r.off_x) - r.ox);
  const V ay = fmadd(r.nsy, az0, V::load(p0 + r.off_y) - r.oy);
  const V bx = fmadd(r.nsx, bz0, V::load(p1 + r.off_x) - r.ox);
  const V by = fmadd(r.nsy, bz0, V::load(p1 + r.off_y) - r.oy);
  const V cx = fmadd(r.nsx, cz0, V::load(p2 + r.off_x) - r.ox);
  const V cy = fmadd(r.nsy, cz0, V::load(p2 + r.off_y) - r.oy);

  constexpr uint32_t kAll = W == 32 ? ~0u : (1u << W) - 1u;
  V u, v, w, det;
  uint32_t mask = watertight_edges<W>(ax, ay, bx, by, cx, cy, kAll, u, v, w, det);
  if (mask == 0) return 0;
  const V zero = V::broadcast(0.0f);
  const V tt = r.sz * fmadd(w, cz0, fmadd(v, bz0, u * az0));
  if (tmin >= 0.0f) {
    // Behind the origin without dividing: where tt and det have opposite
    // signs, t = tt * (1 / det) is negative, hence < tmin -- unless it
    // underflows to -0, which needs |tt| < |det| * 2^-100 (those lanes are
    // left to the full test). Rays leaving a surface meet their own
    // triangle this way in most leaves they visit.
    const uint32_t opposite = (cmp_lt(tt, zero) & cmp_gt(det, zero)) | (cmp_gt(tt, zero) & cmp_lt(det, zero));
    const V abs_mask = V::broadcast(-0.0f);
    const uint32_t large = cmp_ge(andnot(abs_mask, tt), andnot(abs_mask, det) * V::broadcast(0x1p-100f));
    mask &= ~(opposite & large);
    if (mask == 0) return 0;
  }
  const V inv_det = V::broadcast(1.0f) / det;
  const V t = tt * inv_det;
  mask &= cmp_ge(t, V::broadcast(tmin)) & cmp_le(t, V::broadcast(tmax));
  if (mask != 0) {
    t.store(out.t);
    (v * inv_det).store(out.u);
    (w * inv_det).store(out.v);
  }
  return mask;
}

// Moller-Trumbore on all W lanes of a block holding (p0, e1 = p1 - p0,
// e2 = p2 - p0) per lane, in the order of intersect_moller_trumbore: P = D x
// e2, det = e1 . P, S = O - p0, u = (S . P) / det, Q = S x e1, v = (D . Q) /
// det, t = (e2 . Q) / det; a hit when det != 0, u, v >= 0, u + v <= 1 and
// tmin <= t <= tmax. Dot products sum as Eigen's do for 3-vectors,
// x0 + (x1 + x2), so every lane equals the scalar test bit for bit. One
// exact division, once a conservative sign test (no division) has found a
// lane worth it.
template <int W>
[[gnu::always_inline]] inline uint32_t intersect_block(const TriangleBlock<W>& blk, const BlockRayMT<W>& r, float tmin,
                                                       float tmax, BlockHits<W>& out) {
  using V = simd::vfloat<W>;
  const auto at = [&](int corner, int axis) { return V::load(&blk.v[corner][axis][0]); };
  const V e1x = at(1, 0), e1y = at(1, 1), e1z = at(1, 2);
  const V e2x = at(2, 0), e2y = at(2, 1), e2z = at(2, 2);
  const V px = r.dy * e2z - r.dz * e2y;
  const V py = r.dz * e2x - r.dx * e2z;
  const V pz = r.dx * e2y - r.dy * e2x;
  const V det = e1x * px + (e1y * py + e1z * pz);
  const V sx = r.ox - at(0, 0), sy = r.oy - at(0, 1), sz = r.oz - at(0, 2);
  const V uu = sx * px + (sy * py + sz * pz);
  const V qx = sy * e1z - sz * e1y;
  const V qy = sz * e1x - sx * e1z;
  const V qz = sx * e1y - sy * e1x;
  const V vv = r.dx * qx + (r.dy * qy + r.dz * qz);
  const V tt = e2x * qx + (e2y * qy + e2z * qz);
  // u >= 0, v >= 0, u + v <= 1 before dividing: uu, vv and det - uu - vv
  // must not have the sign opposite to det's (det != 0).
  const V zero = V::broadcast(0.0f);
  const V sign = V::broadcast(-0.0f);
  // The test is conservative: a product that underflows to -0 passes u >= 0,
  // hence the floor -|det| 2^-100, and the divided sum rounds (a few ulps).
  const V det_sign = and_bits(det, sign);
  const V su = xor_bits(uu, det_sign), sv = xor_bits(vv, det_sign), adet = andnot(sign, det);
  const V floor = zero - adet * V::broadcast(0x1p-100f);
  uint32_t mask = cmp_neq(det, zero) & cmp_ge(su, floor) & cmp_ge(sv, floor) &
                  cmp_le(su + sv, adet * V::broadcast(1.0f + 0x1p-20f));
  if (mask == 0) return 0;
  const V inv_det = V::broadcast(1.0f) / det;
  const V u = uu * inv_det, v = vv * inv_det, t = tt * inv_det;
  // The scalar test's own range tests on the divided values.
  mask &= cmp_ge(u, zero) & cmp_le(u, V::broadcast(1.0f)) & cmp_ge(v, zero) & cmp_le(u + v, V::broadcast(1.0f));
  mask &= cmp_ge(t, V::broadcast(tmin)) & cmp_le(t, V::broadcast(tmax));
  if (mask != 0) {
    t.store(out.t);
    u.store(out.u);
    v.store(out.v);
  }
  return mask;
}

// One block tested on [tmin, rec.tmax()]: its nearest hit (any hit: the
// first lane hit) offered to the recorder; true when it was kept. The
// caller counts the block's triangle tests. BRay: BlockRay (watertight) or
// BlockRayMT (tri=mt).
template <int W, typename BRay, typename Recorder>
[[gnu::always_inline]] inline bool intersect_block_record(const TriangleBlock<W>& blk, const BRay& br, float tmin,
                                                          Recorder& rec) {
  BlockHits<W> bh;
  uint32_t m = intersect_block(blk, br, tmin, rec.tmax(), bh);
  if (m == 0) return false;
  uint32_t best = simd::ctz(m);
  float bt = bh.t[best];
  if constexpr (!Recorder::kStopAtFirstHit) {
    for (m &= m - 1; m != 0; m &= m - 1) {
      const uint32_t i = simd::ctz(m);
      if (bh.t[i] < bt || (bh.t[i] == bt && blk.prim[i] < blk.prim[best])) {  // ties: see HitRecorder
        bt = bh.t[i];
        best = i;
      }
    }
  }
  return rec.record(bt, bh.u[best], bh.v[best], blk.prim[best]);
}

// The wide BVH's leaf function: tests a leaf's blocks on [tmin, rec.tmax()]
// and offers each block's nearest hit to the recorder (any hit: the first
// lane hit). True when a hit was kept.
template <int W, typename BRay, typename Recorder>
[[gnu::always_inline]] inline bool intersect_block_leaf(const TriangleBlock<W>* blk, uint32_t nblocks,
                                                        const BRay& br, float tmin, Recorder& rec) {
  bool kept = false;
  for (uint32_t b = 0; b < nblocks; ++b) {
    rec.count_triangles(static_cast<uint64_t>(blk[b].count()));
    if (intersect_block_record(blk[b], br, tmin, rec)) {
      kept = true;
      if constexpr (Recorder::kStopAtFirstHit) return true;
    }
  }
  return kept;
}

// Fills a block from up to W triangles (ids and their three vertices);
// missing lanes repeat the first triangle.
template <int W, typename VertexFn>
inline void fill_block(TriangleBlock<W>& blk, const uint32_t* prims, int count, VertexFn&& vertex) {
  for (int lane = 0; lane < W; ++lane) {
    const uint32_t prim = prims[lane < count ? lane : 0];
    blk.prim[lane] = prim;
    for (int c = 0; c < 3; ++c) {
      const Vec3f& p = vertex(prim, c);
      for (int a = 0; a < 3; ++a) blk.v[c][a][lane] = p[a];
    }
  }
}

// The same for the Moller-Trumbore blocks (tri=mt): p0, p1 - p0, p2 - p0
// (the edges rounded as intersect_moller_trumbore rounds them).
template <int W, typename VertexFn>
inline void fill_block_mt(TriangleBlock<W>& blk, const uint32_t* prims, int count, VertexFn&& vertex) {
  for (int lane = 0; lane < W; ++lane) {
    const uint32_t prim = prims[lane < count ? lane : 0];
    blk.prim[lane] = prim;
    const Vec3f p0 = vertex(prim, 0);
    const Vec3f e1 = vertex(prim, 1) - p0;
    const Vec3f e2 = vertex(prim, 2) - p0;
    for (int a = 0; a < 3; ++a) blk.v[0][a][lane] = p0[a], blk.v[1][a][lane] = e1[a], blk.v[2][a][lane] = e2[a];
  }
}

}  // namespace raylab
