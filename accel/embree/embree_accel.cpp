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

#include "accel/embree/embree_packets.h"
#include "accel/embree/embree_ray_map.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cfloat>
#include <cmath>
#include <cstdlib>
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

// The environment variable that caps the ISA of every Embree device of the
// process (Embree's own `max_isa=` device setting), so that a study built
// for a narrower ISA (docs/results.md, "another instruction set") times
// Embree on that ISA too. Unset or empty: Embree picks the widest the CPU has.
constexpr const char* kIsaCapVariable = "RAYLAB_EMBREE_ISA";

// The device configuration string: "max_isa=CAP" or "" (Embree's default).
std::string device_config() {
  const char* cap = std::getenv(kIsaCapVariable);
  if (!cap || !*cap) return "";
  static const char* const kIsas[] = {"sse2", "sse4.2", "avx", "avx2", "avx512"};
  for (const char* isa : kIsas)
    if (std::strcmp(cap, isa) == 0) return std::string("max_isa=") + isa;
  throw EmbreeError(fmt::format("{} must be sse2, sse4.2, avx, avx2 or avx512, got '{}'", kIsaCapVariable, cap));
}

using namespace embree_adapter;

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

class EmbreeAccel final : public Accelerator {
 public:
  EmbreeAccel(RTCBuildQuality quality, bool robust, bool compact, Api api, bool coherent)
      : quality_(quality), robust_(robust), compact_(compact), api_(api), coherent_(coherent) {
    device_ = rtcNewDevice(device_config().c_str());
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

  // Embree's BVH is opaque (no public node access): the picture is its root
  // box only, and Capabilities::outline stays false.
  void outline(int /*max_depth*/, StructureOutline& out) const override {
    out.what = "root box only (Embree's nodes are not exposed)";
    if (!scene_) return;
    RTCBounds b;
    rtcGetSceneBounds(scene_, &b);
    const Aabb box(Vec3f(b.lower_x, b.lower_y, b.lower_z), Vec3f(b.upper_x, b.upper_y, b.upper_z));
    if (!box.is_empty()) out.add(OutlineBox{box, 0, false});
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
    trace_prepared<false>(prepared, begin, rays, hits, stats);
  }

  void occluded_prepared(const PreparedRays* prepared, size_t begin, std::span<const Ray> rays, std::span<uint8_t> occ,
                         TraversalStats* stats) const override {
    trace_prepared<true>(prepared, begin, rays, occ, stats);
  }

  // Both queries, every API mode: the traced loops hold Embree's call and
  // writing our answer (a Hit, or an occlusion byte), nothing else.
  template <bool kOcclusion, class Out>
  void trace_prepared(const PreparedRays* prepared, size_t begin, std::span<const Ray> rays, std::span<Out> out,
                      TraversalStats* stats) const {
    const EmbreePrepared* p = mine(prepared, kOcclusion, begin, rays.size());
    if (!p) {
      trace_unprepared<kOcclusion>(rays, out, stats);
      return;
    }
    const auto& aos = [p]() -> const auto& {
      if constexpr (kOcclusion) return p->rays;  // RTCRay
      else return p->rayhits;                    // RTCRayHit
    }();
    using EmbreeRay = std::decay_t<decltype(aos[0])>;
    const size_t end = begin + rays.size();
    RTCIntersectContext ctx = context();
    RTCScene s = scene();
    switch (api_) {
      case Api::single:
        for (size_t i = begin; i < end; ++i) {
          EmbreeRay r = aos[i];
          trace1(s, ctx, r);
          write_answer(r, out[i - begin]);
        }
        break;
      case Api::stream: {
        EmbreeRay block[kStreamBlock];
        for (size_t b = begin; b < end; b += kStreamBlock) {
          const size_t m = std::min(kStreamBlock, end - b);
          std::memcpy(static_cast<void*>(block), aos.data() + b, m * sizeof(EmbreeRay));
          trace1m(s, ctx, block, m);
          for (size_t k = 0; k < m; ++k) write_answer(block[k], out[b + k - begin]);
        }
        break;
      }
      case Api::packet4: trace_packets(p->p4, s, ctx, begin, end, out); break;
      case Api::packet8: trace_packets(p->p8, s, ctx, begin, end, out); break;
      case Api::packet16: trace_packets(p->p16, s, ctx, begin, end, out); break;
    }
    for (const RayFix& f : p->fixes_in(begin, end)) fix_answer(f, out[f.index - begin]);
    if (stats) stats->rays += rays.size();  // Embree exposes no per-ray counters
  }

  // The two queries' calls and answers, chosen by overload.
  static void trace1(RTCScene s, RTCIntersectContext& ctx, RTCRayHit& r) { rtcIntersect1(s, &ctx, &r); }
  static void trace1(RTCScene s, RTCIntersectContext& ctx, RTCRay& r) { rtcOccluded1(s, &ctx, &r); }
  static void trace1m(RTCScene s, RTCIntersectContext& ctx, RTCRayHit* r, size_t m) {
    rtcIntersect1M(s, &ctx, r, static_cast<unsigned>(m), sizeof(RTCRayHit));
  }
  static void trace1m(RTCScene s, RTCIntersectContext& ctx, RTCRay* r, size_t m) {
    rtcOccluded1M(s, &ctx, r, static_cast<unsigned>(m), sizeof(RTCRay));
  }
  static void write_answer(const RTCRayHit& rh, Hit& h) { write_hit(rh, h); }
  static void write_answer(const RTCRay& r, uint8_t& occluded) {
    occluded = r.tfar < 0.0f ? 1 : 0;  // Embree sets tfar = -inf on a hit
  }
  static void fix_answer(const RayFix& f, Hit& h) { fix_hit(f, h); }
  static void fix_answer(const RayFix& f, uint8_t& occluded) {
    if (!f.traced) occluded = 0;
  }

  // Unprepared batches (the tracer, verify): single-ray mode converts ray by
  // ray on the stack (no allocation for one-ray calls); the other modes
  // prepare the batch first.
  void intersect(std::span<const Ray> rays, std::span<Hit> hits, TraversalStats* stats) const override {
    trace_unprepared<false>(rays, hits, stats);
  }

  void occluded(std::span<const Ray> rays, std::span<uint8_t> occ, TraversalStats* stats) const override {
    trace_unprepared<true>(rays, occ, stats);
  }

  template <bool kOcclusion, class Out>
  void trace_unprepared(std::span<const Ray> rays, std::span<Out> out, TraversalStats* stats) const {
    if (api_ != Api::single) {
      const auto p = prepare(rays, kOcclusion);
      trace_prepared<kOcclusion>(p.get(), 0, rays, out, stats);
      return;
    }
    RTCScene s = scene();
    RTCIntersectContext ctx = context();
    for (size_t i = 0; i < rays.size(); ++i) {
      RTCRayHit rh;
      RayFix fix;
      reset_hit(rh.hit);
      const bool mapped = map_ray(rays[i], rh.ray, fix);
      out[i] = Out{};  // a miss, not occluded
      if (mapped && !fix.traced) continue;  // invalid, or an empty window
      if constexpr (kOcclusion) {
        trace1(s, ctx, rh.ray);
        write_answer(rh.ray, out[i]);
      } else {
        trace1(s, ctx, rh);
        write_answer(rh, out[i]);
        if (mapped) fix_answer(fix, out[i]);
      }
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
  AcceleratorInfo info{
      "embree",
      "Embree 3 reference (rtcIntersect1/rtcOccluded1 per ray; packet and stream APIs with api=)",
      {{"quality", "medium", "build quality: low, medium (Embree's default) or high", one_of({"low", "medium", "high"})},
       {"robust", "0", "1 = RTC_SCENE_FLAG_ROBUST (watertight-style robust traversal)", boolean_flag()},
       {"compact", "0", "1 = RTC_SCENE_FLAG_COMPACT", boolean_flag()},
       {"api", "single",
        "single (rtcIntersect1), packet4/packet8/packet16 (rtcIntersect4/8/16, rays packed in the order given), "
        "stream (rtcIntersect1M)",
        one_of({"single", "packet4", "packet8", "packet16", "stream"})},
       {"coherent", "0", "1 = RTC_INTERSECT_CONTEXT_FLAG_COHERENT", boolean_flag()}},
      [](const Params& p) -> std::unique_ptr<Accelerator> {
        const std::string& q = p.str("quality");
        const RTCBuildQuality quality = q == "low"    ? RTC_BUILD_QUALITY_LOW
                                        : q == "high" ? RTC_BUILD_QUALITY_HIGH
                                                      : RTC_BUILD_QUALITY_MEDIUM;
        const std::string& a = p.str("api");
        const Api api = a == "packet4"    ? Api::packet4
                        : a == "packet8"  ? Api::packet8
                        : a == "packet16" ? Api::packet16
                        : a == "stream"   ? Api::stream
                                          : Api::single;
        return std::make_unique<EmbreeAccel>(quality, p.boolean("robust"), p.boolean("compact"), api,
                                             p.boolean("coherent"));
      }};
  info.caps.robust_variant = "robust=1";
  info.caps.per_ray_counters = false;  // Embree exposes no per-ray counters
  info.caps.reference = true;
  info.cover = {"embree:robust=1", "embree:api=packet8", "embree:api=stream"};
  info.describe = embree_description;
  info.stats = {{"robust", "1 when built with RTC_SCENE_FLAG_ROBUST"}};
  // Peak bytes per triangle: 137 on soup:n=10^6, 107 on terrain:n=707 (raylab
  // info under /usr/bin/time -v, the scene's own subtracted); compact=1
  // (indexed triangles): 75 and 77.
  info.build_peak_bytes_per_triangle = 140;
  info.variant_build_peaks.push_back({"compact=1", 80});
  return info;
}

namespace {

// What a direct loop runs on: the prepared rays (checked to belong to this
// accelerator, api=single, this kind of query and count), the scene and the
// intersect context.
struct DirectLoop {
  const EmbreePrepared& rays;
  RTCScene scene;
  RTCIntersectContext ctx;
};

DirectLoop direct_loop_input(const Accelerator& embree, const PreparedRays& prepared, bool occlusion, size_t n) {
  const auto* accel = dynamic_cast<const EmbreeAccel*>(&embree);
  const auto* p = dynamic_cast<const EmbreePrepared*>(&prepared);
  if (!accel || accel->api() != Api::single || !p || p->owner != accel || p->occlusion != occlusion || p->count != n)
    throw std::invalid_argument("embree direct loop: needs rays prepared by an 'embree' accelerator with api=single");
  DirectLoop loop{*p, accel->scene(), {}};
  rtcInitIntersectContext(&loop.ctx);
  if (accel->coherent()) loop.ctx.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
  return loop;
}

// One rtcIntersect1 (closest hit) or rtcOccluded1 (any hit) per prepared ray.
template <bool kOcclusion, typename Out>
void direct_loop(const Accelerator& embree, const PreparedRays& prepared, std::span<Out> out) {
  DirectLoop loop = direct_loop_input(embree, prepared, kOcclusion, out.size());
  const size_t n = out.size();
  for (size_t i = 0; i < n; ++i) {
    if constexpr (kOcclusion) {
      RTCRay ray = loop.rays.rays[i];
      rtcOccluded1(loop.scene, &loop.ctx, &ray);
      out[i] = ray.tfar < 0.0f ? 1 : 0;
    } else {
      RTCRayHit rh = loop.rays.rayhits[i];
      rtcIntersect1(loop.scene, &loop.ctx, &rh);
      write_hit(rh, out[i]);
    }
  }
}

}  // namespace

void embree_direct_intersect(const Accelerator& embree, const PreparedRays& prepared, std::span<Hit> hits) {
  direct_loop<false>(embree, prepared, hits);
}

void embree_direct_occluded(const Accelerator& embree, const PreparedRays& prepared, std::span<uint8_t> occluded) {
  direct_loop<true>(embree, prepared, occluded);
}

bool is_embree_spec(const std::string& spec) { return spec == "embree" || spec.rfind("embree:", 0) == 0; }

Description embree_description() {
  const std::string config = device_config();
  RTCDevice dev = rtcNewDevice(config.c_str());
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
  // Under a cap narrower than what the CPU offers, the cap is what runs.
  if (!config.empty()) {
    static const char* const kByWidth[] = {"SSE2", "SSE4.2", "AVX", "AVX2", "AVX512"};
    std::string cap = config.substr(config.find('=') + 1);
    std::transform(cap.begin(), cap.end(), cap.begin(), [](unsigned char c) { return static_cast<char>(std::toupper(c)); });
    const auto rank = [&](const std::string& name) {
      for (int i = 0; i < 5; ++i)
        if (name == kByWidth[i]) return i;
      return name == "SSE" ? 1 : 4;
    };
    if (rank(cap) <= rank(isa)) isa = cap;
  }
  return {{"version", fmt::format("{}.{}.{}", version / 10000, (version / 100) % 100, version % 100)}, {"isa", isa}};
}

}  // namespace raylab
