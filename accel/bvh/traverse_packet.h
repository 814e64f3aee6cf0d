#pragma once
// Packet traversal of the 8-wide BVH for coherent rays (`bvh:packet=16`):
// 16 rays walk the tree together, one child box at a time against all 16
// rays in one 16-lane vector (Wald, Slusallek, Benthin and Wagner, "Interactive
// Rendering with Coherent Ray Tracing", EG 2001; the wide-node form as in
// Embree's hybrid traversal). A node's 8 boxes are fetched once for the
// packet instead of once per ray, which is where coherent camera rays gain.
//
// Divergence (Benthin, Wald, Woop, Ernst and Mark, "Combining Single and
// Packet-Ray Tracing for Arbitrary Ray Distributions on the Intel MIC
// Architecture", HPG 2012): a subtree entered by few rays of the packet is
// finished by the single-ray walk (walk_wide) for each of them, and a
// packet whose rays do not share one origin and one direction octant is
// traced as single rays from the start. Packets pay on rays from one point
// (pinhole camera rays); rays from many points towards similar targets
// (shadow rays of a camera's hits) spread over the tree after a few levels
// and were measured slower as packets than as single rays (docs/bvh-speed.md),
// so diffuse, shadow and random sets pay only this test.
//
// Answers equal the single-ray walk's bit for bit: per ray the box test is
// the single-ray FMA slab test on the same values (near plane by the sign of
// the direction, far plane scaled by kSlabFarScale), culling only boxes the
// ray cannot hit within its current closest hit, and leaves run the same
// per-ray block test (intersect_block_leaf); with the recorder's tie rule
// (least (t, prim), see HitRecorder) the visiting order does not matter.
// Rays the fast kernel does not take (invalid, nearly axis-parallel, tmin <
// 0) are traced singly. Closest hit only: occlusion stays single-ray.
#include <cstdint>
#include <span>

#include "accel/bvh/traverse_wide.h"

namespace raylab {

inline constexpr int kPacketSize = 16;

// Per-ray constants of the packet box test, one lane per ray: the values
// init_node_ray gives the single-ray kernel (the near plane gets -(o * inv)
// rounded up, the far plane -(o * inv) rounded down). The rays of a packet
// share one octant, so the near and far plane of each axis are the same for
// all of them (near_row / far_row: the rows of WideNode::bounds).
struct PacketNodeRays {
  using V = simd::vfloat<kPacketSize>;
  V inv[3], near_shift[3], far_shift[3];
  V tmin;
  int near_row[3], far_row[3];
};

// Slab constants of one ray, as the scalar branch of init_node_ray.
inline void packet_ray_constants(const Ray& r, float inv[3], float near_shift[3], float far_shift[3]) {
  const SlabRay sr(r);
  for (int a = 0; a < 3; ++a) {
    inv[a] = sr.inv_dir[a];
    const float oi = r.org[a] * inv[a];
    const float delta = std::fabs(oi) * 0x1p-22f + FLT_MIN;
    const float u = oi + delta, dn = oi - delta;
    near_shift[a] = -(u == u ? u : -FLT_MAX);
    far_shift[a] = -(dn == dn ? dn : FLT_MAX);
  }
}

// Per-ray constants of the packet triangle test, one lane per ray: the
// WatertightRay values (translated origin along the permuted axes, shear).
// Used when every ray of the packet has the same axis permutation (camera
// rays nearly always do), so one triangle's vertices are read once for all
// lanes.
struct PacketTriangleRays {
  using V = simd::vfloat<kPacketSize>;
  V ox, oy, oz, sx, sy, sz, tmin;
  int kx = 0, ky = 1, kz = 2;
};

// True when the ray may join a packet: what the fast single-ray kernel takes.
inline bool packet_ray_ok(const Ray& r, float fma_origin_limit) {
  return ray_is_valid(r) && !ray_is_axis_parallel(r) && r.tmin >= 0.0f && !origin_beyond(r, fma_origin_limit);
}

// Direction octant (bit a = sign of component a).
inline int ray_octant(const Ray& r) {
  return static_cast<int>(std::signbit(r.dir.x())) | static_cast<int>(std::signbit(r.dir.y())) << 1 |
         static_cast<int>(std::signbit(r.dir.z())) << 2;
}

template <int W>
class PacketTracer {
 public:
  using V = simd::vfloat<kPacketSize>;
  using Rec = HitRecorder<false, false>;
  static constexpr int N = 8;

  // Subtrees entered by at most this many rays are finished ray by ray.
  static constexpr int kSingleRayBelow = 3;
  // Leaves reached by at least this many rays test triangles packet-wise.
  static constexpr int kPacketLeafFrom = 4;

  explicit PacketTracer(const WideView<N, W>& bvh) : bvh_(bvh) {}

  // Closest hits of rays (any count), 16 at a time in the order given.
  void intersect(std::span<const Ray> rays, std::span<Hit> hits) const {
    for (size_t b = 0; b < rays.size(); b += kPacketSize) {
      const size_t n = std::min<size_t>(kPacketSize, rays.size() - b);
      if (shares_origin(rays.subspan(b, n))) {
        trace_group(rays.subspan(b, n), hits.subspan(b, n));
      } else {
        // The common incoherent case first, in the plain single-ray loop.
        for (size_t i = b; i < b + n; ++i) trace_single(rays[i], hits[i]);
      }
    }
  }

 private:
  static bool shares_origin(std::span<const Ray> rays) {
    bool same = true;
    for (const Ray& r : rays) same &= r.org == rays[0].org;
    return same;
  }

  void trace_single(const Ray& r, Hit& h) const { h = traverse_wide<N, W, false, false>(bvh_, r, nullptr); }

  // Up to 16 rays: the packet if they share an octant, else one by one.
  void trace_group(std::span<const Ray> rays, std::span<Hit> hits) const {
    uint32_t members = 0;
    int octant = -1;
    bool coherent = true;
    const Ray* first = nullptr;
    for (size_t i = 0; i < rays.size(); ++i) {
      if (!packet_ray_ok(rays[i], bvh_.fma_origin_limit)) {
        trace_single(rays[i], hits[i]);
        continue;
      }
      const int o = ray_octant(rays[i]);
      if (!first) first = &rays[i];
      coherent &= (octant < 0 || o == octant) && rays[i].org == first->org;
      octant = o;
      members |= 1u << i;
    }
    if (!coherent || simd::popcount(members) <= kSingleRayBelow) {
      for (uint32_t m = members; m != 0; m &= m - 1) trace_single(rays[simd::ctz(m)], hits[simd::ctz(m)]);
      return;
    }
    trace_packet(rays, hits, members, octant);
  }

  // The packet walk; `members` marks the lanes that hold rays of the packet.
  void trace_packet(std::span<const Ray> rays, std::span<Hit> hits, uint32_t members, int octant) const {
    PacketNodeRays pr;
    for (int a = 0; a < 3; ++a) {
      const int neg = (octant >> a) & 1;
      pr.near_row[a] = 2 * a + neg;
      pr.far_row[a] = 2 * a + 1 - neg;
    }
    {
      alignas(64) float inv[3][kPacketSize], lo[3][kPacketSize], hi[3][kPacketSize], tmin[kPacketSize];
      const uint32_t first = simd::ctz(members);
      for (int i = 0; i < kPacketSize; ++i) {
        // Lanes without a ray copy the first member (their mask bit stays 0).
        const Ray& r = rays[(members >> i) & 1u ? i : first];
        float iv[3], ls[3], hs[3];
        packet_ray_constants(r, iv, ls, hs);
        for (int a = 0; a < 3; ++a) inv[a][i] = iv[a], lo[a][i] = ls[a], hi[a][i] = hs[a];
        tmin[i] = r.tmin == 0.0f ? 0.0f : r.tmin;  // -0 as +0, as the single-ray kernel
      }
      for (int a = 0; a < 3; ++a) {
        pr.inv[a] = V::load(inv[a]);
        pr.near_shift[a] = V::load(lo[a]);
        pr.far_shift[a] = V::load(hi[a]);
      }
      pr.tmin = V::load(tmin);
    }
    // Triangle constants per lane, when all rays share the axis permutation.
    PacketTriangleRays pt;
    bool packet_leaves = true;
    {
      alignas(64) float ox[kPacketSize], oy[kPacketSize], oz[kPacketSize], sx[kPacketSize], sy[kPacketSize],
          sz[kPacketSize], tmin[kPacketSize];
      const WatertightRay w0(rays[simd::ctz(members)]);
      pt.kx = w0.kx, pt.ky = w0.ky, pt.kz = w0.kz;
      for (int i = 0; i < kPacketSize; ++i) {
        const Ray& r = rays[(members >> i) & 1u ? i : simd::ctz(members)];
        const WatertightRay w(r);
        packet_leaves &= w.kx == pt.kx && w.ky == pt.ky && w.kz == pt.kz;
        ox[i] = w.org[w.kx], oy[i] = w.org[w.ky], oz[i] = w.org[w.kz];
        sx[i] = w.sx, sy[i] = w.sy, sz[i] = w.sz;
        tmin[i] = r.tmin;
      }
      pt.ox = V::load(ox), pt.oy = V::load(oy), pt.oz = V::load(oz);
      pt.sx = V::load(sx), pt.sy = V::load(sy), pt.sz = V::load(sz);
      pt.tmin = V::load(tmin);
    }
    // Per-ray recorders (lanes without a ray: the first member's ray, never
    // used) and block-test constants (built at a ray's first leaf).
    const Ray& first_ray = rays[simd::ctz(members)];
    Rec rec[kPacketSize] = {Rec(first_ray, nullptr), Rec(first_ray, nullptr), Rec(first_ray, nullptr),
                            Rec(first_ray, nullptr), Rec(first_ray, nullptr), Rec(first_ray, nullptr),
                            Rec(first_ray, nullptr), Rec(first_ray, nullptr), Rec(first_ray, nullptr),
                            Rec(first_ray, nullptr), Rec(first_ray, nullptr), Rec(first_ray, nullptr),
                            Rec(first_ray, nullptr), Rec(first_ray, nullptr), Rec(first_ray, nullptr),
                            Rec(first_ray, nullptr)};
    static_assert(kPacketSize == 16, "one initialiser per lane above");
    alignas(64) float tmax[kPacketSize];
    for (int i = 0; i < kPacketSize; ++i) {
      if ((members >> i) & 1u) rec[i] = Rec(rays[i], nullptr);
      tmax[i] = rec[i].tmax();
    }
    BlockRay<W> br[kPacketSize];
    uint32_t br_ready = 0;
    V tmax_v = V::load(tmax);
    const V far_scale = V::broadcast(kSlabFarScale);

    // Stack: child reference, the rays that entered it and their entry distances.
    alignas(64) float stack_tnear[kWideStackSize][kPacketSize];
    uint32_t stack_ref[kWideStackSize];
    uint32_t stack_mask[kWideStackSize];
    int sp = 0;
    uint32_t cur = bvh_.root_ref;
    uint32_t active = members;

    while (true) {
      if (simd::popcount(active) <= kSingleRayBelow) {
        // Diverged: finish this subtree ray by ray with the single-ray walk.
        for (uint32_t m = active; m != 0; m &= m - 1) {
          const uint32_t i = simd::ctz(m);
          walk_wide<N, W, false, false, false>(bvh_, rays[i], cur, rec[i]);
          tmax[i] = rec[i].tmax();
        }
        tmax_v = V::load(tmax);
      } else if (!wide_ref::is_leaf(cur)) {
        const WideNode<N>& node = bvh_.nodes[cur];
        // Test each used child box against the packet; keep the hit ones in
        // slot order with their ray masks and distances.
        alignas(64) float tnear_of[N][kPacketSize];
        uint32_t ref_of[N], mask_of[N];
        float key_of[N];
        int hit_children = 0;
        const uint32_t leader = simd::ctz(active);
        for (int c = 0; c < N; ++c) {
          const uint32_t ref = node.child[c];
          if (ref == wide_ref::kEmpty) continue;
          // The single-ray FMA slab test (intersect_children), lane by lane;
          // an unused slot's empty box gives tnear = +inf and is culled.
          const V nx = fmadd(V::broadcast(node.bounds[pr.near_row[0]][c]), pr.inv[0], pr.near_shift[0]);
          const V ny = fmadd(V::broadcast(node.bounds[pr.near_row[1]][c]), pr.inv[1], pr.near_shift[1]);
          const V nz = fmadd(V::broadcast(node.bounds[pr.near_row[2]][c]), pr.inv[2], pr.near_shift[2]);
          const V fx = fmadd(V::broadcast(node.bounds[pr.far_row[0]][c]), pr.inv[0], pr.far_shift[0]);
          const V fy = fmadd(V::broadcast(node.bounds[pr.far_row[1]][c]), pr.inv[1], pr.far_shift[1]);
          const V fz = fmadd(V::broadcast(node.bounds[pr.far_row[2]][c]), pr.inv[2], pr.far_shift[2]);
          const V tnear = max_bits(max_bits(nx, ny), max_bits(nz, pr.tmin));
          const V tfar = min_bits(min_bits(fx, fy), min_bits(fz, tmax_v)) * far_scale;
          const uint32_t m = cmp_le(tnear, tfar) & active;
          if (m == 0) continue;
          tnear.store(tnear_of[hit_children]);
          ref_of[hit_children] = ref;
          mask_of[hit_children] = m;
          // Ordered by the first ray that enters it (the leader if it does).
          key_of[hit_children] = tnear_of[hit_children][(m >> leader) & 1u ? leader : simd::ctz(m)];
          ++hit_children;
        }
        if (hit_children == 0) {
          if (!pop(stack_tnear, stack_ref, stack_mask, sp, tmax_v, cur, active)) break;
          continue;
        }
        // Push all but the nearest, farthest first; visit the nearest.
        int order[N];
        for (int k = 0; k < hit_children; ++k) order[k] = k;
        for (int k = 1; k < hit_children; ++k)  // insertion sort, descending key
          for (int j = k; j > 0 && key_of[order[j]] > key_of[order[j - 1]]; --j) std::swap(order[j], order[j - 1]);
        for (int k = 0; k < hit_children - 1; ++k) {
          const int c = order[k];
          prefetch_child(bvh_, ref_of[c]);
          V::load(tnear_of[c]).store(stack_tnear[sp]);
          stack_ref[sp] = ref_of[c];
          stack_mask[sp] = mask_of[c];
          ++sp;
        }
        cur = ref_of[order[hit_children - 1]];
        active = mask_of[order[hit_children - 1]];
        continue;
      } else if (packet_leaves && simd::popcount(active) >= kPacketLeafFrom) {
        // Leaf, many rays: one triangle against all of them.
        const TriangleBlock<W>* blocks = bvh_.blocks + wide_ref::leaf_first(cur);
        const uint32_t nblocks = wide_ref::leaf_blocks(cur);
        for (uint32_t b = 0; b < nblocks; ++b) packet_block(blocks[b], pt, active, rec, tmax, tmax_v);
      } else {
        // Leaf, few rays: each runs the single-ray block test.
        const TriangleBlock<W>* blocks = bvh_.blocks + wide_ref::leaf_first(cur);
        const uint32_t nblocks = wide_ref::leaf_blocks(cur);
        for (uint32_t m = active; m != 0; m &= m - 1) {
          const uint32_t i = simd::ctz(m);
          if (!((br_ready >> i) & 1u)) {
            br[i].init(WatertightRay(rays[i]));
            br_ready |= 1u << i;
          }
          if (intersect_block_leaf<W>(blocks, nblocks, br[i], rays[i].tmin, rec[i])) tmax[i] = rec[i].tmax();
        }
        tmax_v = V::load(tmax);
      }
      if (!pop(stack_tnear, stack_ref, stack_mask, sp, tmax_v, cur, active)) break;
    }
    for (uint32_t m = members; m != 0; m &= m - 1) hits[simd::ctz(m)] = rec[simd::ctz(m)].hit();
  }

  // The watertight test of intersect_block with rays in the lanes instead of
  // triangles: for each lane the same operations in the same order on the
  // same values (translate, shear, edge functions, the double-precision
  // recomputation of an exactly-zero edge function, sign test, t = tt *
  // (1 / det)), so each ray gets bit for bit the t, u, v its single-ray test
  // gives. (intersect_block's early rejection of hits behind the origin only
  // saves work: those lanes fail t >= tmin here.) Each hit is offered to the
  // ray's recorder, whose tie rule makes the order irrelevant.
  static void packet_block(const TriangleBlock<W>& blk, const PacketTriangleRays& r, uint32_t active, Rec* rec,
                           float* tmax, V& tmax_v) {
    const V zero = V::broadcast(0.0f);
    const int count = blk.count();  // padding lanes repeat the first triangle
    for (int j = 0; j < count; ++j) {
      const V az0 = V::broadcast(blk.v[0][r.kz][j]) - r.oz;
      const V bz0 = V::broadcast(blk.v[1][r.kz][j]) - r.oz;
      const V cz0 = V::broadcast(blk.v[2][r.kz][j]) - r.oz;
      const V ax = (V::broadcast(blk.v[0][r.kx][j]) - r.ox) - r.sx * az0;
      const V ay = (V::broadcast(blk.v[0][r.ky][j]) - r.oy) - r.sy * az0;
      const V bx = (V::broadcast(blk.v[1][r.kx][j]) - r.ox) - r.sx * bz0;
      const V by = (V::broadcast(blk.v[1][r.ky][j]) - r.oy) - r.sy * bz0;
      const V cx = (V::broadcast(blk.v[2][r.kx][j]) - r.ox) - r.sx * cz0;
      const V cy = (V::broadcast(blk.v[2][r.ky][j]) - r.oy) - r.sy * cz0;
      V u = cx * by - cy * bx;
      V v = ax * cy - ay * cx;
      V w = bx * ay - by * ax;
      const uint32_t zeros = (cmp_eq(u, zero) | cmp_eq(v, zero) | cmp_eq(w, zero)) & active;
      if (zeros != 0) [[unlikely]] recompute_edges_in_double(zeros, ax, ay, bx, by, cx, cy, u, v, w);
      const uint32_t neg = cmp_lt(u, zero) | cmp_lt(v, zero) | cmp_lt(w, zero);
      const uint32_t pos = cmp_gt(u, zero) | cmp_gt(v, zero) | cmp_gt(w, zero);
      uint32_t mask = ~(neg & pos) & active;
      if (mask == 0) continue;
      const V det = u + v + w;
      mask &= cmp_neq(det, zero);
      if (mask == 0) continue;
      const V tt = u * (r.sz * az0) + v * (r.sz * bz0) + w * (r.sz * cz0);
      const V inv_det = V::broadcast(1.0f) / det;
      const V t = tt * inv_det;
      mask &= cmp_ge(t, r.tmin) & cmp_le(t, tmax_v);
      if (mask == 0) continue;
      alignas(64) float ft[kPacketSize], fu[kPacketSize], fv[kPacketSize];
      t.store(ft);
      (v * inv_det).store(fu);
      (w * inv_det).store(fv);
      for (uint32_t m = mask; m != 0; m &= m - 1) {
        const uint32_t i = simd::ctz(m);
        if (rec[i].record(ft[i], fu[i], fv[i], blk.prim[j])) tmax[i] = ft[i];
      }
      tmax_v = V::load(tmax);
    }
  }

  // Next stack entry some ray of which can still find a closer hit there;
  // the rays whose entry distance is beyond their closest hit drop out (the
  // single-ray walk culls them the same way, see walk_wide's pop).
  static bool pop(const float (*stack_tnear)[kPacketSize], const uint32_t* stack_ref, const uint32_t* stack_mask,
                  int& sp, V tmax_v, uint32_t& cur, uint32_t& active) {
    const V limit = tmax_v * V::broadcast(kSlabFarScale);
    while (sp > 0) {
      --sp;
      const uint32_t m = stack_mask[sp] & cmp_le(V::load(stack_tnear[sp]), limit);
      if (m == 0) continue;
      cur = stack_ref[sp];
      active = m;
      return true;
    }
    return false;
  }

  WideView<N, W> bvh_;
};

}  // namespace raylab
