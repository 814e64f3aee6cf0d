#pragma once
// Ray-triangle intersection kernels.
//
// The default everywhere is the watertight test of Woop, Benthin & Wald,
// "Watertight Ray/Triangle Intersection", JCGT 2(1), 2013: the ray is sheared
// so that it points along +z of a permuted frame, and the 2D edge functions of
// the projected triangle decide the hit. A shared edge yields edge functions of
// exactly opposite sign in its two triangles, so a ray can never slip between
// them. That holds only if a*b - c*d is evaluated without fused multiply-adds
// (a fused form rounds one product and not the other, so the two triangles'
// values would no longer be exact negatives): the project compiles with
// -ffp-contract=off for this reason. When an edge function is exactly zero the
// three are recomputed in double precision, as the paper prescribes, so hits on
// edges and vertices are decided consistently.
//
// Fused multiply-adds are used where the argument allows them: the shear
// x - sx * z of a translated vertex is one fma (a vertex gets the same sheared
// coordinates in every triangle that shares it, which is all the argument
// needs), and so is the distance's weighted sum u*az + v*bz + w*cz. Both cut
// the vector block test's work (triangle_block.h), which computes the same
// values lane by lane.
//
// Moller-Trumbore (1997) is kept for the accuracy study (spec option tri=mt).
#include <cmath>
#include <cstdint>

#include "base/ray.h"
#include "base/vec.h"

namespace raylab {

enum class TriangleTest : uint8_t { Watertight, MollerTrumbore };

const char* triangle_test_name(TriangleTest t);

// Per-ray constants of the watertight test, computed once per ray.
struct WatertightRay {
  Vec3f org;
  int kx = 0, ky = 1, kz = 2;
  float sx = 0.0f, sy = 0.0f, sz = 1.0f;

  WatertightRay() = default;
  explicit WatertightRay(const Ray& r) : WatertightRay(r, nullptr) {}
  // inv: the ray's correctly rounded reciprocals 1 / dir (as the wide BVH's
  // box test already divided them out), or null to divide here. The same
  // value either way: the division is one of the longest operations in a
  // short ray's set-up, and it is already done.
  WatertightRay(const Ray& r, const float* inv) : org(r.org) {
    // kz is the dominant axis; (kx, ky) follow it cyclically and swap when the
    // ray looks down -kz, which keeps the projected triangle's winding. Chosen
    // from packed tables, without branches: on incoherent rays the direction's
    // comparisons are coin flips, and the branches they became mispredicted
    // often enough to cost more than the rest of a short ray's setup (rays that
    // miss the root box: 45 -> 78 Mrays/s with any hit, which sets this up at
    // the start).
    const float ax = std::fabs(r.dir.x()), ay = std::fabs(r.dir.y()), az = std::fabs(r.dir.z());
    // code bit 0: ax >= ay, bit 1: ax >= az, bit 2: ay >= az; 2-bit entries
    // {2, 2, 2, 0, 1, 2, 1, 0}, ties going to the lower axis as x, then y.
    const unsigned code = unsigned(ax >= ay) | unsigned(ax >= az) << 1 | unsigned(ay >= az) << 2;
    kz = static_cast<int>((0x192Au >> (2 * code)) & 3u);
    const float dz = r.dir[kz];
    // (kx, ky) by 2 * kz + (dz < 0): (1,2) (2,1) (2,0) (0,2) (0,1) (1,0).
    const unsigned k = 2u * static_cast<unsigned>(kz) + unsigned(dz < 0.0f);
    kx = static_cast<int>((0x429u >> (2 * k)) & 3u);
    ky = static_cast<int>((0x186u >> (2 * k)) & 3u);
    // One division: the shear only has to be the same for every triangle a
    // ray meets, not the correctly rounded quotient.
    sz = inv ? inv[kz] : 1.0f / dz;
    sx = r.dir[kx] * sz;
    sy = r.dir[ky] * sz;
  }
};

// Watertight test. On a hit with tmin <= t <= tmax writes t, u, v and returns true.
inline bool intersect_watertight(const WatertightRay& w, const Vec3f& p0, const Vec3f& p1,
                                 const Vec3f& p2, float tmin, float tmax, float& t_out,
                                 float& u_out, float& v_out) {
  const Vec3f a = p0 - w.org;
  const Vec3f b = p1 - w.org;
  const Vec3f c = p2 - w.org;
  const float ax = std::fma(-w.sx, a[w.kz], a[w.kx]);
  const float ay = std::fma(-w.sy, a[w.kz], a[w.ky]);
  const float bx = std::fma(-w.sx, b[w.kz], b[w.kx]);
  const float by = std::fma(-w.sy, b[w.kz], b[w.ky]);
  const float cx = std::fma(-w.sx, c[w.kz], c[w.kx]);
  const float cy = std::fma(-w.sy, c[w.kz], c[w.ky]);

  // Edge functions: U is the weight of p0 (edge p1-p2), V of p1, W of p2.
  float u = cx * by - cy * bx;
  float v = ax * cy - ay * cx;
  float wgt = bx * ay - by * ax;
  if (u == 0.0f || v == 0.0f || wgt == 0.0f) {
    u = static_cast<float>(static_cast<double>(cx) * by - static_cast<double>(cy) * bx);
    v = static_cast<float>(static_cast<double>(ax) * cy - static_cast<double>(ay) * cx);
    wgt = static_cast<float>(static_cast<double>(bx) * ay - static_cast<double>(by) * ax);
  }
  if ((u < 0.0f || v < 0.0f || wgt < 0.0f) && (u > 0.0f || v > 0.0f || wgt > 0.0f)) return false;
  const float det = u + v + wgt;
  if (det == 0.0f) return false;

  // t = sz * (u*az + v*bz + w*cz) / det (az etc.: the translated vertices'
  // kz components), summed in det's order so that a triangle at a constant
  // depth gets tt = sz * az * det exactly.
  const float tt = w.sz * std::fma(wgt, c[w.kz], std::fma(v, b[w.kz], u * a[w.kz]));
  const float inv_det = 1.0f / det;
  const float t = tt * inv_det;
  // Also rejects NaN t (degenerate input) because the comparisons fail.
  if (!(t >= tmin && t <= tmax)) return false;
  t_out = t;
  u_out = v * inv_det;
  v_out = wgt * inv_det;
  return true;
}

// Moller & Trumbore, "Fast, Minimum Storage Ray/Triangle Intersection", 1997.
// Not watertight: rays through shared edges can pass between triangles.
inline bool intersect_moller_trumbore(const Ray& r, const Vec3f& p0, const Vec3f& p1,
                                      const Vec3f& p2, float tmin, float tmax, float& t_out,
                                      float& u_out, float& v_out) {
  const Vec3f e1 = p1 - p0;
  const Vec3f e2 = p2 - p0;
  const Vec3f pv = r.dir.cross(e2);
  const float det = e1.dot(pv);
  if (det == 0.0f) return false;
  const float inv_det = 1.0f / det;
  const Vec3f s = r.org - p0;
  const float u = s.dot(pv) * inv_det;
  if (!(u >= 0.0f && u <= 1.0f)) return false;
  const Vec3f q = s.cross(e1);
  const float v = r.dir.dot(q) * inv_det;
  if (!(v >= 0.0f && u + v <= 1.0f)) return false;
  const float t = e2.dot(q) * inv_det;
  if (!(t >= tmin && t <= tmax)) return false;
  t_out = t;
  u_out = u;
  v_out = v;
  return true;
}

// Per-ray data for either test, so kernels can be templated on the test.
template <TriangleTest kTest>
struct TrianglePrecompute;

template <>
struct TrianglePrecompute<TriangleTest::Watertight> {
  WatertightRay w;
  explicit TrianglePrecompute(const Ray& r) : w(r) {}
  bool intersect(const Ray&, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, float tmin,
                 float tmax, float& t, float& u, float& v) const {
    return intersect_watertight(w, p0, p1, p2, tmin, tmax, t, u, v);
  }
};

template <>
struct TrianglePrecompute<TriangleTest::MollerTrumbore> {
  explicit TrianglePrecompute(const Ray&) {}
  bool intersect(const Ray& r, const Vec3f& p0, const Vec3f& p1, const Vec3f& p2, float tmin,
                 float tmax, float& t, float& u, float& v) const {
    return intersect_moller_trumbore(r, p0, p1, p2, tmin, tmax, t, u, v);
  }
};

// Calls f.template operator()<kTest>() with the runtime choice as a template argument.
template <typename F>
decltype(auto) dispatch_triangle_test(TriangleTest t, F&& f) {
  if (t == TriangleTest::MollerTrumbore) return f.template operator()<TriangleTest::MollerTrumbore>();
  return f.template operator()<TriangleTest::Watertight>();
}

}  // namespace raylab
