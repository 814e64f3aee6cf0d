// Embree 3 adapter: one device per accelerator (so its memory monitor counts
// exactly this structure's bytes), one triangle geometry whose vertex and
// index buffers are our own memory (shared buffers).
//
// Timed = traversal only. prepare() converts a ray set into Embree's own
// layout once, outside the timed region: an RTCRayHit / RTCRay array (api
// single and stream) or SOA packets RTCRayHit4/8/16 / RTCRay4/8/16 with
// their valid masks (the partial last packet masked with valid[k] = 0).
// Rays Embree cannot take as they are (negative tmin, huge or denormal
// directions, far origins, invalid rays) are mapped during preparation and
// listed in a side list, so the traced loop is a plain rtcIntersect1 /
// rtcOccluded1 (or packet / stream) loop plus writing our Hit; only listed
// rays get their distances mapped back afterwards.
#include "accel/embree/embree_accel.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <cfloat>
#include <cmath>
#include <chrono>
#include <cstring>
#include <mutex>
#include <stdexcept>

#include <fmt/format.h>

namespace raylab {

namespace {

class EmbreeError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

const char* error_name(RTCError e) {
  switch (e) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_UNKNOWN: return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
  }
  return "unrecognised error";
}

enum class Api { single, packet4, packet8, packet16, stream };

// Embree's valid ray (asserted in its debug builds, undefined otherwise):
// 0 <= tnear, and every origin and direction component within FLT_LARGE =
// 1.844e18 in magnitude. Our rays are wider, so map_ray converts them: a
// segment that starts behind the origin (tmin < 0) is traced from the point
// at tmin (rounded to float, so distances can differ in the last bits from a
// structure that keeps the original origin), and a direction beyond
// FLT_LARGE is scaled by a power of two (exact), distances by the inverse;
// denormal components become zeros. Hit distances map back as
// t = t_embree * scale + shift (a NaN distance from Embree is a miss). Rays
// whose origin (after the shift) is beyond FLT_LARGE cannot be given to
// Embree at all: the adapter reports them as misses (a documented limit of
// the reference; no scene of ours reaches 1e18). tmin = -inf cannot be
// shifted: Embree then sees only the part t >= 0.
constexpr float kEmbreeLarge = 1.8e18f;  // just below Embree's FLT_LARGE

// Side-list entry for a ray that needed mapping (see map_ray).
struct RayFix {
  size_t index = 0;  // position in the prepared set
  float shift = 0.0f, scale = 1.0f;
  float tmin = 0.0f, tmax = 0.0f;  // the ray's own range: mapped hits are clamped to it
  bool traced = true;  // false: a miss without asking Embree (masked in packets; a dummy ray otherwise)
};

void set_embree_ray(RTCRay& ray, const float org[3], const float dir[3], float tnear, float tfar) {
  ray.org_x = org[0];
  ray.org_y = org[1];
  ray.org_z = org[2];
  ray.tnear = tnear;
  ray.dir_x = dir[0];
  ray.dir_y = dir[1];
  ray.dir_z = dir[2];
  ray.time = 0.0f;
  ray.tfar = tfar;  // tmax = +inf stays +inf
  ray.mask = 0xFFFFFFFFu;
  ray.id = 0;
  ray.flags = 0;
}

// An empty segment at the origin: what untraced rays give Embree.
void set_dummy_ray(RTCRay& ray) {
  const float zero[3] = {0.0f, 0.0f, 0.0f}, up[3] = {0.0f, 0.0f, 1.0f};
  set_embree_ray(ray, zero, up, 0.0f, 0.0f);
}

// The common case, tested cheaply: a valid ray Embree takes unchanged.
bool embree_takes_as_is(const Ray& r) {
  if (!(r.tmin >= 0.0f && r.tmin <= r.tmax)) return false;  // also rejects NaN
  for (int a = 0; a < 3; ++a) {
    const float o = std::fabs(r.org[a]), d = std::fabs(r.dir[a]);
    if (!(o <= kEmbreeLarge) || !(d <= kEmbreeLarge) || (d != 0.0f && d < FLT_MIN)) return false;
  }
  return r.dir[0] != 0.0f || r.dir[1] != 0.0f || r.dir[2] != 0.0f;
}

// Converts one ray; returns true when it needed mapping (`fix` then filled in).
bool map_ray(const Ray& r, RTCRay& ray, RayFix& fix) {
  if (embree_takes_as_is(r)) {
    const float org[3] = {r.org.x(), r.org.y(), r.org.z()};
    const float dir[3] = {r.dir.x(), r.dir.y(), r.dir.z()};
    set_embree_ray(ray, org, dir, r.tmin, r.tmax);
    return false;
  }
  fix = RayFix{};
  fix.tmin = r.tmin;
  fix.tmax = r.tmax;
  if (!ray_is_valid(r) || !(r.tmin <= r.tmax)) {
    set_dummy_ray(ray);
    fix.traced = false;
    return true;
  }
  float org[3] = {r.org.x(), r.org.y(), r.org.z()};
  float dir[3] = {r.dir.x(), r.dir.y(), r.dir.z()};
  float tmin = r.tmin, tmax = r.tmax;
  if (tmin < 0.0f && std::isfinite(tmin)) {
    fix.shift = tmin;
    for (int a = 0; a < 3; ++a)
      org[a] = static_cast<float>(static_cast<double>(r.org[a]) + static_cast<double>(tmin) * r.dir[a]);
    tmax -= tmin;
    tmin = 0.0f;
  }
  // Denormal components become signed zeros: Embree's kernels run with
  // denormals flushed and return NaN distances for them (found by fuzz_rays).
  for (float& d : dir)
    if (std::fabs(d) < FLT_MIN) d = std::copysign(0.0f, d);
  const float dmax = std::max({std::fabs(dir[0]), std::fabs(dir[1]), std::fabs(dir[2])});
  if (dmax > kEmbreeLarge) {
    int e = 0;
    std::frexp(dmax / kEmbreeLarge, &e);  // 2^e > dmax / large
    for (float& d : dir) d = std::ldexp(d, -e);
    tmin = std::ldexp(tmin, e);
    tmax = std::ldexp(tmax, e);
    fix.scale = std::ldexp(1.0f, -e);
  }
  for (float o : org) fix.traced &= std::fabs(o) <= kEmbreeLarge;
  if (!fix.traced) set_dummy_ray(ray);
  else set_embree_ray(ray, org, dir, std::max(0.0f, tmin), tmax);
  return true;
}

void reset_hit(RTCHit& hit) {
  hit.geomID = RTC_INVALID_GEOMETRY_ID;
  hit.primID = RTC_INVALID_GEOMETRY_ID;
  hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

// Our hit from Embree's answer (distance still in Embree's parametrisation).
inline void write_hit(const RTCRayHit& rh, Hit& h) {
  if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
    h.t = rh.ray.tfar;
    h.u = rh.hit.u;
    h.v = rh.hit.v;
    h.prim = rh.hit.primID;
  } else {
    h = Hit{};
  }
}

// The mapping back for a listed ray, after its answer was written as usual.
inline void fix_hit(const RayFix& f, Hit& h) {
  if (!f.traced || (h.valid() && std::isnan(h.t))) {
    h = Hit{};
    return;
  }
  // Clamped to the ray's range: the mapping back may round just outside it.
  if (h.valid()) h.t = std::clamp(h.t * f.scale + f.shift, f.tmin, f.tmax);
}

// SOA packet types and calls per width.
template <int N>
struct PacketApi;
template <>
struct PacketApi<4> {
  using RayHitN = RTCRayHit4;
  using RayN = RTCRay4;
  static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, RayHitN* r) { rtcIntersect4(v, s, c, r); }
  static void occluded(const int* v, RTCScene s, RTCIntersectContext* c, RayN* r) { rtcOccluded4(v, s, c, r); }
};
template <>
struct PacketApi<8> {
  using RayHitN = RTCRayHit8;
  using RayN = RTCRay8;
  static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, RayHitN* r) { rtcIntersect8(v, s, c, r); }
  static void occluded(const int* v, RTCScene s, RTCIntersectContext* c, RayN* r) { rtcOccluded8(v, s, c, r); }
};
template <>
struct PacketApi<16> {
  using RayHitN = RTCRayHit16;
  using RayN = RTCRay16;
  static void intersect(const int* v, RTCScene s, RTCIntersectContext* c, RayHitN* r) { rtcIntersect16(v, s, c, r); }
  static void occluded(const int* v, RTCScene s, RTCIntersectContext* c, RayN* r) { rtcOccluded16(v, s, c, r); }
};

// Embree requires the valid mask aligned like the packet.
template <int N>
struct alignas(4 * N) ValidMask {
  int v[N] = {};
};

template <class RayN>
void put_ray(RayN& p, int k, const RTCRay& r) {
  p.org_x[k] = r.org_x;
  p.org_y[k] = r.org_y;
  p.org_z[k] = r.org_z;
  p.tnear[k] = r.tnear;
  p.dir_x[k] = r.dir_x;
  p.dir_y[k] = r.dir_y;
  p.dir_z[k] = r.dir_z;
  p.time[k] = r.time;
  p.tfar[k] = r.tfar;
  p.mask[k] = r.mask;
  p.id[k] = r.id;
  p.flags[k] = r.flags;
}

template <int N>
struct Packets {
  std::vector<typename PacketApi<N>::RayHitN> hit;  // closest-hit sets
  std::vector<typename PacketApi<N>::RayN> ray;     // occlusion sets
  std::vector<ValidMask<N>> valid;
};

struct EmbreePrepared final : PreparedRays {
  const void* owner = nullptr;  // the accelerator that prepared it
  bool occlusion = false;
  size_t count = 0;
  std::vector<RTCRayHit> rayhits;  // api single / stream, closest hit
  std::vector<RTCRay> rays;        // api single / stream, occlusion
  Packets<4> p4;
  Packets<8> p8;
  Packets<16> p16;
  std::vector<RayFix> fixes;  // sorted by index

  // The listed rays within [begin, end).
  std::span<const RayFix> fixes_in(size_t begin, size_t end) const {
    const auto by_index = [](const RayFix& f, size_t i) { return f.index < i; };
    const auto lo = std::lower_bound(fixes.begin(), fixes.end(), begin, by_index);
    const auto hi = std::lower_bound(lo, fixes.end(), end, by_index);
    return {fixes.data() + (lo - fixes.begin()), static_cast<size_t>(hi - lo)};
  }
};

constexpr size_t kStreamBlock = 256;  // rays per rtcIntersect1M call

// Rays grouped into packets in the order given; the partial last packet and
// the rays the side list marks as untraced are masked out (valid = 0).
template <int N>
void fill_packets(const std::vector<RTCRayHit>& aos, const std::vector<RayFix>& fixes, bool occlusion,
                  Packets<N>& out) {
  const size_t n = aos.size(), np = (n + N - 1) / N;
  out.valid.assign(np, ValidMask<N>{});
  if (occlusion) out.ray.resize(np);
  else out.hit.resize(np);
  RTCRay dummy;
  set_dummy_ray(dummy);
  for (size_t p = 0; p < np; ++p) {
    for (int k = 0; k < N; ++k) {
      const size_t i = p * N + k;
      const RTCRay& r = i < n ? aos[i].ray : dummy;
      out.valid[p].v[k] = i < n ? -1 : 0;
      if (occlusion) {
        put_ray(out.ray[p], k, r);
      } else {
        put_ray(out.hit[p].ray, k, r);
        out.hit[p].hit.geomID[k] = RTC_INVALID_GEOMETRY_ID;
        out.hit[p].hit.primID[k] = RTC_INVALID_GEOMETRY_ID;
        out.hit[p].hit.instID[0][k] = RTC_INVALID_GEOMETRY_ID;
      }
    }
  }
  for (const RayFix& f : fixes)
    if (!f.traced) out.valid[f.index / N].v[f.index % N] = 0;
}

// Valid mask of packet p restricted to [begin, end).
template <int N>
const int* packet_mask(const Packets<N>& pk, size_t p, size_t begin, size_t end, ValidMask<N>& local) {
  const size_t base = p * N;
  if (base >= begin && base + N <= end) return pk.valid[p].v;
  for (int k = 0; k < N; ++k) local.v[k] = (base + k >= begin && base + k < end) ? pk.valid[p].v[k] : 0;
  return local.v;
}

template <int N>
void intersect_packets(const Packets<N>& pk, RTCScene s, RTCIntersectContext& ctx, size_t begin, size_t end,
                       std::span<Hit> hits) {
  ValidMask<N> local;
  for (size_t p = begin / N; p * N < end; ++p) {
    typename PacketApi<N>::RayHitN rh = pk.hit[p];
    PacketApi<N>::intersect(packet_mask(pk, p, begin, end, local), s, &ctx, &rh);
    const size_t base = p * N;
    for (int k = 0; k < N; ++k) {
      const size_t i = base + k;
      if (i < begin || i >= end) continue;
      Hit& h = hits[i - begin];
      if (rh.hit.geomID[k] != RTC_INVALID_GEOMETRY_ID) {
        h.t = rh.ray.tfar[k];
        h.u = rh.hit.u[k];
        h.v = rh.hit.v[k];
        h.prim = rh.hit.primID[k];
      } else {
        h = Hit{};
      }
    }
  }
}

template <int N>
void occluded_packets(const Packets<N>& pk, RTCScene s, RTCIntersectContext& ctx, size_t begin, size_t end,
                      std::span<uint8_t> occ) {
  ValidMask<N> local;
  for (size_t p = begin / N; p * N < end; ++p) {
    typename PacketApi<N>::RayN r = pk.ray[p];
    PacketApi<N>::occluded(packet_mask(pk, p, begin, end, local), s, &ctx, &r);
    const size_t base = p * N;
    for (int k = 0; k < N; ++k) {
      const size_t i = base + k;
      if (i >= begin && i < end) occ[i - begin] = r.tfar[k] < 0.0f ? 1 : 0;  // tfar = -inf on a hit
    }
  }
}

class EmbreeAccel final : public Accelerator {
 public:
  EmbreeAccel(RTCBuildQuality quality, bool robust, bool compact, Api api, bool coherent)
      : quality_(quality), robust_(robust), compact_(compact), api_(api), coherent_(coherent) {
    device_ = rtcNewDevice(nullptr);
    if (!device_) throw EmbreeError(fmt::format("embree: cannot create device: {}", error_name(rtcGetDeviceError(nullptr))));
    rtcSetDeviceErrorFunction(device_, &EmbreeAccel::on_error, this);
    rtcSetDeviceMemoryMonitorFunction(device_, &EmbreeAccel::on_memory, this);
  }

  ~EmbreeAccel() override {
    if (scene_) rtcReleaseScene(scene_);
    if (device_) rtcReleaseDevice(device_);
  }

  RTCScene scene() const {
    if (!scene_) throw EmbreeError("embree: tracing before build");
    return scene_;
  }
  bool coherent() const { return coherent_; }

  BuildStats build(const TriangleMesh& mesh) override {
    mesh.validate();
    const auto t0 = std::chrono::steady_clock::now();
    // Embree reads vertex buffers with 16-byte loads: pad the last vertex by one float.
    vertices_.assign(mesh.vertices.size() * 3 + 1, 0.0f);
    if (!mesh.vertices.empty()) std::memcpy(vertices_.data(), mesh.vertices.data(), mesh.vertices.size() * sizeof(Vec3f));

    scene_ = rtcNewScene(device_);
    check("rtcNewScene");
    int flags = RTC_SCENE_FLAG_NONE;
    if (robust_) flags |= RTC_SCENE_FLAG_ROBUST;
    if (compact_) flags |= RTC_SCENE_FLAG_COMPACT;
    rtcSetSceneFlags(scene_, static_cast<RTCSceneFlags>(flags));
    rtcSetSceneBuildQuality(scene_, quality_);
    if (mesh.num_triangles() > 0) {
      RTCGeometry geom = rtcNewGeometry(device_, RTC_GEOMETRY_TYPE_TRIANGLE);
      rtcSetGeometryBuildQuality(geom, quality_);
      rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, vertices_.data(), 0,
                                 3 * sizeof(float), mesh.vertices.size());
      rtcSetSharedGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, mesh.triangles.data(), 0,
                                 3 * sizeof(uint32_t), mesh.triangles.size());
      rtcCommitGeometry(geom);
      rtcAttachGeometry(scene_, geom);
      rtcReleaseGeometry(geom);
      check("geometry setup");
    }
    rtcCommitScene(scene_);
    check("rtcCommitScene");
    const auto t1 = std::chrono::steady_clock::now();

    BuildStats stats;
    stats.build_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();
    stats.bytes = static_cast<size_t>(std::max<int64_t>(0, bytes_.load())) + vertices_.size() * sizeof(float);
    stats.extra["robust"] = robust_ ? 1.0 : 0.0;
    return stats;
  }

  std::unique_ptr<PreparedRays> prepare(std::span<const Ray> rays, bool occlusion) const override {
    auto p = std::make_unique<EmbreePrepared>();
    p->owner = this;
    p->occlusion = occlusion;
    p->count = rays.size();
    const size_t n = rays.size();
    // Every ray in AOS form first (the single / stream layout); packets are
    // filled from it.
    std::vector<RTCRayHit> aos(n);
    for (size_t i = 0; i < n; ++i) {
      RayFix fix;
      reset_hit(aos[i].hit);
      if (map_ray(rays[i], aos[i].ray, fix)) {
        fix.index = i;
        p->fixes.push_back(fix);
      }
    }
    switch (api_) {
      case Api::single:
      case Api::stream:
        if (occlusion) {
          p->rays.resize(n);
          for (size_t i = 0; i < n; ++i) p->rays[i] = aos[i].ray;
        } else {
          p->rayhits = std::move(aos);
        }
        break;
      case Api::packet4: fill_packets(aos, p->fixes, occlusion, p->p4); break;
      case Api::packet8: fill_packets(aos, p->fixes, occlusion, p->p8); break;
      case Api::packet16: fill_packets(aos, p->fixes, occlusion, p->p16); break;
    }
    return p;
  }

  // The prepared set when this accelerator made it for this kind of query.
  const EmbreePrepared* mine(const PreparedRays* prepared, bool occlusion, size_t begin, size_t n) const {
    const auto* p = dynamic_cast<const EmbreePrepared*>(prepared);
    return p && p->owner == this && p->occlusion == occlusion && begin + n <= p->count ? p : nullptr;
  }

  void intersect_prepared(const PreparedRays* prepared, size_t begin, std::span<const Ray> rays, std::span<Hit> hits,
                          TraversalStats* stats) const override {
    const EmbreePrepared* p = mine(prepared, false, begin, rays.size());
    if (!p) {
      intersect(rays, hits, stats);
      return;
    }
    const size_t end = begin + rays.size();
    RTCIntersectContext ctx = context();
    RTCScene s = scene();
    switch (api_) {
      case Api::single:
        // The traced loop: Embree's call and writing our hit, nothing else.
        for (size_t i = begin; i < end; ++i) {
          RTCRayHit rh = p->rayhits[i];
          rtcIntersect1(s, &ctx, &rh);
          write_hit(rh, hits[i - begin]);
        }
        break;
      case Api::stream: {
        RTCRayHit block[kStreamBlock];
        for (size_t b = begin; b < end; b += kStreamBlock) {
          const size_t m = std::min(kStreamBlock, end - b);
          std::memcpy(static_cast<void*>(block), p->rayhits.data() + b, m * sizeof(RTCRayHit));
          rtcIntersect1M(s, &ctx, block, static_cast<unsigned>(m), sizeof(RTCRayHit));
          for (size_t k = 0; k < m; ++k) write_hit(block[k], hits[b + k - begin]);
        }
        break;
      }
      case Api::packet4: intersect_packets(p->p4, s, ctx, begin, end, hits); break;
      case Api::packet8: intersect_packets(p->p8, s, ctx, begin, end, hits); break;
      case Api::packet16: intersect_packets(p->p16, s, ctx, begin, end, hits); break;
    }
    for (const RayFix& f : p->fixes_in(begin, end)) fix_hit(f, hits[f.index - begin]);
    if (stats) stats->rays += rays.size();  // Embree exposes no per-ray counters
  }

  void occluded_prepared(const PreparedRays* prepared, size_t begin, std::span<const Ray> rays, std::span<uint8_t> occ,
                         TraversalStats* stats) const override {
    const EmbreePrepared* p = mine(prepared, true, begin, rays.size());
    if (!p) {
      occluded(rays, occ, stats);
      return;
    }
    const size_t end = begin + rays.size();
    RTCIntersectContext ctx = context();
    RTCScene s = scene();
    switch (api_) {
      case Api::single:
        for (size_t i = begin; i < end; ++i) {
          RTCRay ray = p->rays[i];
          rtcOccluded1(s, &ctx, &ray);
          occ[i - begin] = ray.tfar < 0.0f ? 1 : 0;  // Embree sets tfar = -inf on a hit
        }
        break;
      case Api::stream: {
        RTCRay block[kStreamBlock];
        for (size_t b = begin; b < end; b += kStreamBlock) {
          const size_t m = std::min(kStreamBlock, end - b);
          std::memcpy(static_cast<void*>(block), p->rays.data() + b, m * sizeof(RTCRay));
          rtcOccluded1M(s, &ctx, block, static_cast<unsigned>(m), sizeof(RTCRay));
          for (size_t k = 0; k < m; ++k) occ[b + k - begin] = block[k].tfar < 0.0f ? 1 : 0;
        }
        break;
      }
      case Api::packet4: occluded_packets(p->p4, s, ctx, begin, end, occ); break;
      case Api::packet8: occluded_packets(p->p8, s, ctx, begin, end, occ); break;
      case Api::packet16: occluded_packets(p->p16, s, ctx, begin, end, occ); break;
    }
    for (const RayFix& f : p->fixes_in(begin, end))
      if (!f.traced) occ[f.index - begin] = 0;
    if (stats) stats->rays += rays.size();
  }

  // Unprepared batches (the tracer, verify): single-ray mode converts ray by
  // ray on the stack (no allocation for one-ray calls); the other modes
  // prepare the batch first.
  void intersect(std::span<const Ray> rays, std::span<Hit> hits, TraversalStats* stats) const override {
    RTCScene s = scene();
    if (api_ != Api::single) {
      const auto p = prepare(rays, false);
      intersect_prepared(p.get(), 0, rays, hits, stats);
      return;
    }
    RTCIntersectContext ctx = context();
    for (size_t i = 0; i < rays.size(); ++i) {
      RTCRayHit rh;
      RayFix fix;
      reset_hit(rh.hit);
      const bool mapped = map_ray(rays[i], rh.ray, fix);
      if (mapped && !fix.traced) {
        hits[i] = Hit{};
        continue;
      }
      rtcIntersect1(s, &ctx, &rh);
      write_hit(rh, hits[i]);
      if (mapped) fix_hit(fix, hits[i]);
    }
    if (stats) stats->rays += rays.size();
  }

  void occluded(std::span<const Ray> rays, std::span<uint8_t> occ, TraversalStats* stats) const override {
    RTCScene s = scene();
    if (api_ != Api::single) {
      const auto p = prepare(rays, true);
      occluded_prepared(p.get(), 0, rays, occ, stats);
      return;
    }
    RTCIntersectContext ctx = context();
    for (size_t i = 0; i < rays.size(); ++i) {
      RTCRay ray;
      RayFix fix;
      if (map_ray(rays[i], ray, fix) && !fix.traced) {
        occ[i] = 0;
        continue;
      }
      rtcOccluded1(s, &ctx, &ray);
      occ[i] = ray.tfar < 0.0f ? 1 : 0;  // Embree sets tfar = -inf on a hit
    }
    if (stats) stats->rays += rays.size();
  }

  RTCIntersectContext context() const {
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    if (coherent_) ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    return ctx;
  }

  Api api() const { return api_; }

 private:
  static void on_error(void* user, RTCError code, const char* msg) {
    auto* self = static_cast<EmbreeAccel*>(user);
    std::lock_guard<std::mutex> lock(self->error_mutex_);
    if (self->error_message_.empty())
      self->error_message_ = fmt::format("{} ({})", msg ? msg : "", error_name(code));
  }

  static bool on_memory(void* user, ssize_t bytes, bool /*post*/) {
    static_cast<EmbreeAccel*>(user)->bytes_ += bytes;
    return true;
  }

  void check(const char* where) {
    const RTCError e = rtcGetDeviceError(device_);
    std::string msg;
    {
      std::lock_guard<std::mutex> lock(error_mutex_);
      msg.swap(error_message_);
    }
    if (e != RTC_ERROR_NONE || !msg.empty())
      throw EmbreeError(fmt::format("embree: {} failed: {}", where, msg.empty() ? error_name(e) : msg));
  }

  RTCBuildQuality quality_;
  bool robust_;
  bool compact_;
  Api api_;
  bool coherent_;
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  std::vector<float> vertices_;
  std::atomic<int64_t> bytes_{0};
  std::mutex error_mutex_;
  std::string error_message_;
};

}  // namespace

AcceleratorInfo embree_accelerator_info() {
  return AcceleratorInfo{
      "embree",
      "Embree 3 reference (rtcIntersect1/rtcOccluded1 per ray; packet and stream APIs with api=)",
      {{"quality", "medium", "build quality: low, medium (Embree's default) or high"},
       {"robust", "0", "1 = RTC_SCENE_FLAG_ROBUST (watertight-style robust traversal)"},
       {"compact", "0", "1 = RTC_SCENE_FLAG_COMPACT"},
       {"api", "single",
        "single (rtcIntersect1), packet4/packet8/packet16 (rtcIntersect4/8/16, rays packed in the order given), "
        "stream (rtcIntersect1M)"},
       {"coherent", "0", "1 = RTC_INTERSECT_CONTEXT_FLAG_COHERENT"}},
      [](const Params& p) -> std::unique_ptr<Accelerator> {
        const std::string& q = p.choice("quality", {"low", "medium", "high"});
        const RTCBuildQuality quality = q == "low"    ? RTC_BUILD_QUALITY_LOW
                                        : q == "high" ? RTC_BUILD_QUALITY_HIGH
                                                      : RTC_BUILD_QUALITY_MEDIUM;
        const std::string& a = p.choice("api", {"single", "packet4", "packet8", "packet16", "stream"});
        const Api api = a == "packet4"    ? Api::packet4
                        : a == "packet8"  ? Api::packet8
                        : a == "packet16" ? Api::packet16
                        : a == "stream"   ? Api::stream
                                          : Api::single;
        return std::make_unique<EmbreeAccel>(quality, p.boolean("robust"), p.boolean("compact"), api,
                                             p.boolean("coherent"));
      }};
}

namespace {

const EmbreePrepared& direct_loop_input(const Accelerator& embree, const PreparedRays& prepared, bool occlusion,
                                        size_t n) {
  const auto* accel = dynamic_cast<const EmbreeAccel*>(&embree);
  const auto* p = dynamic_cast<const EmbreePrepared*>(&prepared);
  if (!accel || accel->api() != Api::single || !p || p->owner != accel || p->occlusion != occlusion || p->count != n)
    throw std::invalid_argument("embree direct loop: needs rays prepared by an 'embree' accelerator with api=single");
  return *p;
}

}  // namespace

void embree_direct_intersect(const Accelerator& embree, const PreparedRays& prepared, std::span<Hit> hits) {
  const EmbreePrepared& p = direct_loop_input(embree, prepared, false, hits.size());
  const auto& accel = static_cast<const EmbreeAccel&>(embree);
  RTCScene scene = accel.scene();
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  if (accel.coherent()) ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  const size_t n = hits.size();
  for (size_t i = 0; i < n; ++i) {
    RTCRayHit rh = p.rayhits[i];
    rtcIntersect1(scene, &ctx, &rh);
    Hit& h = hits[i];
    if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID) {
      h.t = rh.ray.tfar;
      h.u = rh.hit.u;
      h.v = rh.hit.v;
      h.prim = rh.hit.primID;
    } else {
      h = Hit{};
    }
  }
}

void embree_direct_occluded(const Accelerator& embree, const PreparedRays& prepared, std::span<uint8_t> occluded) {
  const EmbreePrepared& p = direct_loop_input(embree, prepared, true, occluded.size());
  const auto& accel = static_cast<const EmbreeAccel&>(embree);
  RTCScene scene = accel.scene();
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  if (accel.coherent()) ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  const size_t n = occluded.size();
  for (size_t i = 0; i < n; ++i) {
    RTCRay ray = p.rays[i];
    rtcOccluded1(scene, &ctx, &ray);
    occluded[i] = ray.tfar < 0.0f ? 1 : 0;
  }
}

bool is_embree_spec(const std::string& spec) { return spec == "embree" || spec.rfind("embree:", 0) == 0; }

std::string embree_version_string() {
  RTCDevice dev = rtcNewDevice(nullptr);
  if (!dev) return "embree (no device)";
  const ssize_t version = rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_VERSION);
  std::string isa = "unknown ISA";
  // Embree reports which traversal kernels it compiled in; the widest one that
  // the CPU supports is what runs.
  const bool native8 = rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_NATIVE_RAY8_SUPPORTED) != 0;
  const bool native16 = rtcGetDeviceProperty(dev, RTC_DEVICE_PROPERTY_NATIVE_RAY16_SUPPORTED) != 0;
  rtcReleaseDevice(dev);
  if (native16) isa = "AVX512";
  else if (native8) isa = "AVX2";
  else isa = "SSE";
  return fmt::format("{}.{}.{} {}", version / 10000, (version / 100) % 100, version % 100, isa);
}

}  // namespace raylab
