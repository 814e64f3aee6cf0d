// Embree 3 adapter: one device per accelerator (so its memory monitor counts
// exactly this structure's bytes), one triangle geometry whose vertex and
// index buffers are our own memory (shared buffers), rtcIntersect1 /
// rtcOccluded1 per ray inside the batch loop.
#include "accel/embree/embree_accel.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <cfloat>
#include <cmath>
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

class EmbreeAccel final : public Accelerator {
 public:
  EmbreeAccel(RTCBuildQuality quality, bool robust, bool compact)
      : quality_(quality), robust_(robust), compact_(compact) {
    device_ = rtcNewDevice(nullptr);
    if (!device_) throw EmbreeError(fmt::format("embree: cannot create device: {}", error_name(rtcGetDeviceError(nullptr))));
    rtcSetDeviceErrorFunction(device_, &EmbreeAccel::on_error, this);
    rtcSetDeviceMemoryMonitorFunction(device_, &EmbreeAccel::on_memory, this);
  }

  ~EmbreeAccel() override {
    if (scene_) rtcReleaseScene(scene_);
    if (device_) rtcReleaseDevice(device_);
  }

  BuildStats build_impl(const TriangleMesh& mesh) override {
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

    BuildStats stats;
    stats.bytes = static_cast<size_t>(std::max<int64_t>(0, bytes_.load())) + vertices_.size() * sizeof(float);
    stats.extra["robust"] = robust_ ? 1.0 : 0.0;
    return stats;
  }

  void intersect(std::span<const Ray> rays, std::span<Hit> hits, TraversalStats* stats) const override {
    if (!scene_) throw EmbreeError("embree: intersect before build");
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (size_t i = 0; i < rays.size(); ++i) {
      const Ray& r = rays[i];
      Hit& h = hits[i];
      h = Hit{};
      if (!ray_is_valid(r)) continue;
      RTCRayHit rh;
      const RayMap map = fill_ray(r, rh.ray);
      if (!map.ok) continue;
      rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.primID = RTC_INVALID_GEOMETRY_ID;
      rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
      rtcIntersect1(scene_, &ctx, &rh);
      if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID && !std::isnan(rh.ray.tfar)) {
        // Clamped to the ray's range: the mapping back may round just outside it.
        h.t = std::clamp(rh.ray.tfar * map.scale + map.shift, r.tmin, r.tmax);
        h.u = rh.hit.u;
        h.v = rh.hit.v;
        h.prim = rh.hit.primID;
      }
    }
    if (stats) stats->rays += rays.size();  // Embree exposes no per-ray counters
  }

  void occluded(std::span<const Ray> rays, std::span<uint8_t> occ, TraversalStats* stats) const override {
    if (!scene_) throw EmbreeError("embree: occluded before build");
    RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    for (size_t i = 0; i < rays.size(); ++i) {
      const Ray& r = rays[i];
      occ[i] = 0;
      if (!ray_is_valid(r)) continue;
      RTCRay ray;
      if (!fill_ray(r, ray).ok) continue;
      rtcOccluded1(scene_, &ctx, &ray);
      occ[i] = ray.tfar < 0.0f ? 1 : 0;  // Embree sets tfar = -inf on a hit
    }
    if (stats) stats->rays += rays.size();
  }

 private:
  // Embree's valid ray (asserted in its debug builds, undefined otherwise):
  // 0 <= tnear, and every origin and direction component within
  // FLT_LARGE = 1.844e18 in magnitude. Our rays are wider, so fill_ray maps
  // them: a segment that starts behind the origin (tmin < 0) is traced from
  // the point at tmin (rounded to float, so distances can differ in the last
  // bits from a structure that keeps the original origin), and a direction
  // beyond FLT_LARGE is scaled by a power of two (exact), distances by the
  // inverse, denormal components become zeros. Hit distances map back as
  // t = t_embree * scale + shift (a NaN distance from Embree is a miss). Rays
  // whose origin (after the shift) is beyond FLT_LARGE cannot be given to
  // Embree at all: the adapter reports them as misses (a documented limit of
  // the reference; no scene of ours reaches 1e18). tmin = -inf cannot be
  // shifted: Embree then sees only the part t >= 0.
  struct RayMap {
    float shift = 0.0f, scale = 1.0f;
    bool ok = true;
  };
  static constexpr float kEmbreeLarge = 1.8e18f;  // just below Embree's FLT_LARGE

  static RayMap fill_ray(const Ray& r, RTCRay& ray) {
    RayMap m;
    float org[3] = {r.org.x(), r.org.y(), r.org.z()};
    float dir[3] = {r.dir.x(), r.dir.y(), r.dir.z()};
    float tmin = r.tmin, tmax = r.tmax;
    if (tmin < 0.0f && std::isfinite(tmin)) {
      m.shift = tmin;
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
      m.scale = std::ldexp(1.0f, -e);
    }
    for (float o : org) m.ok &= std::fabs(o) <= kEmbreeLarge;
    ray.org_x = org[0];
    ray.org_y = org[1];
    ray.org_z = org[2];
    ray.tnear = std::max(0.0f, tmin);
    ray.dir_x = dir[0];
    ray.dir_y = dir[1];
    ray.dir_z = dir[2];
    ray.time = 0.0f;
    ray.tfar = tmax;  // tmax = +inf stays +inf
    ray.mask = 0xFFFFFFFFu;
    ray.id = 0;
    ray.flags = 0;
    return m;
  }

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
  RTCDevice device_ = nullptr;
  RTCScene scene_ = nullptr;
  std::vector<float> vertices_;
  std::atomic<int64_t> bytes_{0};
  std::mutex error_mutex_;
  std::string error_message_;
};

}  // namespace

AcceleratorInfo embree_accelerator_info() {
  AcceleratorInfo info{
      "embree",
      "Embree 3 reference (rtcIntersect1/rtcOccluded1 per ray)",
      {{"quality", "medium", "build quality: low, medium (Embree's default) or high"},
       {"robust", "0", "1 = RTC_SCENE_FLAG_ROBUST (watertight-style robust traversal)"},
       {"compact", "0", "1 = RTC_SCENE_FLAG_COMPACT"}},
      [](const Params& p) -> std::unique_ptr<Accelerator> {
        const std::string& q = p.choice("quality", {"low", "medium", "high"});
        const RTCBuildQuality quality = q == "low"    ? RTC_BUILD_QUALITY_LOW
                                        : q == "high" ? RTC_BUILD_QUALITY_HIGH
                                                      : RTC_BUILD_QUALITY_MEDIUM;
        return std::make_unique<EmbreeAccel>(quality, p.boolean("robust"), p.boolean("compact"));
      }};
  info.caps.robust_variant = "robust=1";
  info.caps.per_ray_counters = false;  // Embree exposes no per-ray counters
  info.caps.reference = true;
  info.cover = {"embree:robust=1"};
  info.describe = embree_description;
  info.stats = {{"robust", "1 when built with RTC_SCENE_FLAG_ROBUST"}};
  return info;
}

Description embree_description() {
  RTCDevice dev = rtcNewDevice(nullptr);
  if (!dev) return {{"version", "unknown"}, {"isa", "unknown"}};
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
  return {{"version", fmt::format("{}.{}.{}", version / 10000, (version / 100) % 100, version % 100)}, {"isa", isa}};
}

}  // namespace raylab
