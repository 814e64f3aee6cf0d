// The honest yardstick: Embree's modes answer like single-ray
// Embree, the adapter answers bit-identically to a plain rtcIntersect1 loop,
// the prepare step changes no answer, best-Embree ratios in bench records,
// the ray file's round trip and its bad-input errors.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <bit>
#include <cfloat>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>

#include <nlohmann/json.hpp>

#include "accel/embree/embree_accel.h"
#include "accel/registry.h"
#include "bench/embree_selfcheck.h"
#include "bench/ray_file.h"
#include "tracer/ray_sets.h"
#include "tracer/trace.h"
#include "scenes/procedural.h"
#include "scenes/scene_registry.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;

bool same_bits(const std::vector<Hit>& a, const std::vector<Hit>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Hit)) == 0;
}

std::unique_ptr<Accelerator> built(const std::string& spec, const Scene& scene) {
  auto a = make_accelerator(spec);
  a->build(scene.mesh);
  return a;
}

// Ray sets of a small scene, with counts that leave partial last packets.
struct Sets {
  Scene scene;
  std::vector<RaySet> sets;
};
const Sets& test_sets() {
  static const Sets s = [] {
    Sets out{load_scene("cornell"), {}};
    auto reference = built("embree", out.scene);
    RaySetOptions o;
    o.width = 37;  // 37 x 23 = 851 primary rays: not a multiple of 4, 8 or 16
    o.height = 23;
    o.random_count = 1001;
    out.sets = make_ray_sets(out.scene, {"primary", "diffuse", "shadow", "random"}, *reference, o);
    return out;
  }();
  return s;
}

// Rays Embree cannot take as they are, plus ordinary ones between them.
RaySet special_rays(bool occlusion) {
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  RaySet set{"special", occlusion, {}};
  const Vec3f o(278.0f, 273.0f, -800.0f), d(0.01f, 0.02f, 1.0f);  // the Cornell box camera
  set.rays.emplace_back(o, d);
  set.rays.emplace_back(o + 2.0f * d, d, -2.5f, inf);                            // negative tmin
  set.rays.emplace_back(o, d * 1e20f, 0.0f, inf);                                // huge direction
  set.rays.emplace_back(o, Vec3f(1e-40f, 1e-41f, 1.0f), 0.0f, inf);              // denormal components
  set.rays.emplace_back(Vec3f(nan, 0, 0), d);                                    // NaN origin
  set.rays.emplace_back(o, Vec3f(0, 0, 0));                                      // zero direction
  set.rays.emplace_back(o, d, 5.0f, 1.0f);                                       // tmin > tmax
  set.rays.emplace_back(Vec3f(1e19f, 0.5f, 0.5f), Vec3f(-1, 0, 0), 0.0f, inf);  // origin beyond Embree's range
  set.rays.emplace_back(o, d, nan, inf);                                         // NaN tmin
  set.rays.emplace_back(o, d, -inf, inf);                                        // tmin = -inf
  for (int i = 0; i < 23; ++i) set.rays.emplace_back(o + Vec3f(3.0f * i, 0, 0), d);
  // 33: a direction shorter than 2^-40, which embree_ray_map.h scales up
  // (left that short, Embree missed it, and its stream API could abort:
  // EmbreeModes.TinyDirectionBesideAFarRayInOneStream); it hits where ray 0
  // does, at t / 2^-82.
  set.rays.emplace_back(o, d * 0x1p-82f, 0.0f, inf);
  return set;
}

TraceOutput trace(const Accelerator& a, const RaySet& set, bool prepared) {
  TraceOutput out;
  if (!prepared) {
    trace_set(a, set, 1, out);
    return out;
  }
  const PreparedSet p = prepare_set(a, set);
  trace_set(a, set, 1, out, nullptr, p.rays.get());
  return out;
}

void expect_same(const TraceOutput& a, const TraceOutput& b, const RaySet& set, const std::string& what) {
  if (set.occlusion) {
    EXPECT_EQ(a.occluded, b.occluded) << what << " " << set.name;
  } else {
    ASSERT_EQ(a.hits.size(), b.hits.size());
    size_t differ = 0;
    for (size_t i = 0; i < a.hits.size(); ++i)
      differ += std::memcmp(&a.hits[i], &b.hits[i], sizeof(Hit)) != 0;
    EXPECT_EQ(differ, 0u) << what << " " << set.name;
  }
}

const std::vector<std::string>& embree_modes() {
  static const std::vector<std::string> modes = {
      "embree:coherent=1",         "embree:api=packet4", "embree:api=packet8",
      "embree:api=packet16",       "embree:api=stream",  "embree:api=packet16,coherent=1",
      "embree:api=stream,coherent=1"};
  return modes;
}

TEST(EmbreeModes, EveryModeAnswersLikeSingleRayEmbree) {
  const Sets& s = test_sets();
  auto single = built("embree", s.scene);
  for (const auto& spec : embree_modes()) {
    auto mode = built(spec, s.scene);
    for (const auto& set : s.sets) {
      const TraceOutput want = trace(*single, set, true);
      size_t hits = 0;
      for (const auto& h : want.hits) hits += h.valid();
      for (uint8_t o : want.occluded) hits += o;
      EXPECT_GT(hits, set.rays.size() / 10) << set.name << ": the test needs hits";
      expect_same(trace(*mode, set, true), want, set, spec + " prepared");
      expect_same(trace(*mode, set, false), want, set, spec + " unprepared");
    }
  }
}

TEST(EmbreeModes, SpecialRaysAreMappedTheSameWayInEveryModeAndWithoutPreparation) {
  const Sets& s = test_sets();
  auto single = built("embree", s.scene);
  for (bool occlusion : {false, true}) {
    const RaySet set = special_rays(occlusion);
    const TraceOutput want = trace(*single, set, false);
    // Invalid rays and rays beyond Embree's range: misses.
    for (size_t i : {4u, 5u, 6u, 7u, 8u}) {
      if (occlusion) EXPECT_EQ(want.occluded[i], 0) << i;
      else EXPECT_FALSE(want.hits[i].valid()) << i;
    }
    if (!occlusion) {
      // The ordinary ray and the mapped ones hit the same triangle (the
      // Cornell box's back wall) at the distance in their own units.
      ASSERT_TRUE(want.hits[0].valid());
      for (size_t i : {1u, 2u, 3u, 9u}) ASSERT_TRUE(want.hits[i].valid()) << i;
      EXPECT_NEAR(want.hits[1].t, want.hits[0].t - 2.0f, 1e-4f * want.hits[0].t);
      EXPECT_NEAR(want.hits[2].t * 1e20f, want.hits[0].t, 1e-4f * want.hits[0].t);
      ASSERT_TRUE(want.hits[33].valid());
      EXPECT_NEAR(want.hits[33].t * 0x1p-82f, want.hits[0].t, 1e-4f * want.hits[0].t);
      EXPECT_EQ(want.hits[33].prim, want.hits[0].prim);
    }
    expect_same(trace(*single, set, true), want, set, "embree prepared");
    for (const auto& spec : embree_modes()) {
      auto mode = built(spec, s.scene);
      expect_same(trace(*mode, set, true), want, set, spec + " prepared");
      expect_same(trace(*mode, set, false), want, set, spec + " unprepared");
    }
  }
}

// The rays fuzz_rays found, in its scene (the unit Cornell box, a sphere,
// degenerate triangles): a direction of 2^-82 whose range [tmin, tmax] lies
// behind its origin, and one whose negative tmin moves its origin 7e14
// away. In one call to the stream API Embree aborted the process on its own
// assertion (`cur != BVH::emptyNode`, bvh_intersector_stream.cpp); with the
// tiny direction scaled up (embree_ray_map.h) every mode gives the
// single-ray answers.
TEST(EmbreeModes, TinyDirectionBesideAFarRayInOneStream) {
  TriangleMesh mesh = make_cornell_box().mesh;
  for (auto& v : mesh.vertices) v *= 1.0f / 550.0f;
  mesh.append(make_uv_sphere(12, 6, Vec3f(0.5f, 0.5f, 0.5f), 0.2f));
  TriangleMesh odd;
  odd.vertices = {Vec3f(0.1f, 0.1f, 0.1f), Vec3f(0.1f, 0.1f, 0.1f), Vec3f(0.9f, 0.9f, 0.9f),
                  Vec3f(0.2f, 0.2f, 0.2f), Vec3f(0.9f, 0.1f, 0.5f), Vec3f(0.9f, 0.1f, 0.5001f)};
  odd.triangles = {{0, 1, 2}, {0, 3, 2}, {4, 5, 2}};
  mesh.append(odd);
  const float m = -0x1.2d2d2cp-82f, big = -0x1.979796p+24f;
  const std::vector<Ray> rays = {Ray(Vec3f(m, m, m), Vec3f(m, m, m), m, m),
                                 Ray(Vec3f(big, big, big), Vec3f(big, big, big), big, 0x1.00658p-132f),
                                 Ray(Vec3f(0.3f, 0.3f, 0.3f), Vec3f(-0x1p-82f, -0x1p-82f, -0x1p-82f))};
  auto single = make_accelerator("embree");
  single->build(mesh);
  std::vector<Hit> want(rays.size());
  std::vector<uint8_t> want_occ(rays.size());
  single->intersect(rays, want);
  single->occluded(rays, want_occ);
  // (The far ray's triangles collapse to points at its origin's ulp of 2^26:
  // Embree misses them; only the agreement of the modes is checked.)
  EXPECT_TRUE(want[2].valid());  // the tiny direction from inside the box
  for (const auto& spec : embree_modes()) {
    auto a = make_accelerator(spec);
    a->build(mesh);
    std::vector<Hit> hits(rays.size());
    std::vector<uint8_t> occ(rays.size());
    a->intersect(rays, hits);
    a->occluded(rays, occ);
    EXPECT_EQ(std::memcmp(hits.data(), want.data(), rays.size() * sizeof(Hit)), 0) << spec;
    EXPECT_EQ(occ, want_occ) << spec;
  }
}

TEST(EmbreeModes, SubRangesStartingInsideAPacket) {
  const Sets& s = test_sets();
  const RaySet& set = s.sets[3];  // random
  auto single = built("embree", s.scene);
  const TraceOutput want = trace(*single, set, false);
  for (const char* spec : {"embree:api=packet16", "embree:api=packet8", "embree:api=stream", "embree"}) {
    auto a = built(spec, s.scene);
    const auto prepared = a->prepare(set.rays, false);
    for (auto [begin, len] : {std::pair<size_t, size_t>{5, 37}, {16, 16}, {990, 11}, {0, 1}, {17, 300}}) {
      std::vector<Hit> hits(len);
      a->intersect_prepared(prepared.get(), begin, std::span<const Ray>(set.rays.data() + begin, len), hits);
      EXPECT_EQ(std::memcmp(hits.data(), want.hits.data() + begin, len * sizeof(Hit)), 0)
          << spec << " [" << begin << ", +" << len << ")";
    }
  }
}

TEST(EmbreeAdapter, BitIdenticalToThePlainRtcIntersect1Loop) {
  const Sets& s = test_sets();
  auto embree = built("embree", s.scene);
  for (const auto& set : s.sets) {
    const PreparedSet p = prepare_set(*embree, set);
    ASSERT_NE(p.rays, nullptr);
    TraceOutput adapter;
    trace_set(*embree, set, 1, adapter, nullptr, p.rays.get());
    if (set.occlusion) {
      std::vector<uint8_t> direct(set.rays.size());
      embree_direct_occluded(*embree, *p.rays, direct);
      EXPECT_EQ(adapter.occluded, direct) << set.name;
    } else {
      std::vector<Hit> direct(set.rays.size());
      embree_direct_intersect(*embree, *p.rays, direct);
      EXPECT_TRUE(same_bits(adapter.hits, direct)) << set.name;
    }
  }
  // The direct loop refuses what it cannot trace plainly.
  auto packets = built("embree:api=packet16", s.scene);
  const auto pp = packets->prepare(s.sets[0].rays, false);
  std::vector<Hit> hits(s.sets[0].rays.size());
  EXPECT_THROW(embree_direct_intersect(*packets, *pp, hits), std::invalid_argument);
  const auto occ_prepared = embree->prepare(s.sets[0].rays, true);
  EXPECT_THROW(embree_direct_intersect(*embree, *occ_prepared, hits), std::invalid_argument);
}

TEST(EmbreeAdapter, SelfCheckReportsIdenticalAnswersAndARatio) {
  const Scene scene = load_scene("soup:n=500");
  RaySetOptions o;
  o.width = o.height = 16;
  o.random_count = 500;
  const auto rows = embree_selfcheck(scene, {"primary", "shadow", "random"}, o, 1);
  ASSERT_EQ(rows.size(), 3u);
  for (const auto& r : rows) {
    EXPECT_TRUE(r.identical) << r.ray_set;
    EXPECT_GT(r.adapter_mrays_per_s, 0.0);
    EXPECT_GT(r.direct_mrays_per_s, 0.0);
    EXPECT_NEAR(r.ratio, r.adapter_mrays_per_s / r.direct_mrays_per_s, 1e-9 * r.ratio);
  }
}

TEST(PrepareStep, StructuresWithoutOneAnswerAsBefore) {
  const Sets& s = test_sets();
  for (const char* spec : {"bvh", "kdtree", "grid"}) {
    auto a = built(spec, s.scene);
    EXPECT_EQ(a->prepare(s.sets[0].rays, false), nullptr) << spec;
    for (const auto& set : s.sets) expect_same(trace(*a, set, true), trace(*a, set, false), set, spec);
  }
}

TEST(PrepareStep, TimeTraceReportsPreparationSeparately) {
  const Sets& s = test_sets();
  auto embree = built("embree:api=packet16", s.scene);
  const TraceTiming t = time_trace(*embree, s.sets[0], 1, 3);
  EXPECT_GT(t.median_s, 0.0);
  EXPECT_GT(t.prepare_s, 0.0);
  const PreparedSet p = prepare_set(*embree, s.sets[0]);
  EXPECT_EQ(time_trace(*embree, s.sets[0], 1, 1, p.rays.get()).prepare_s, 0.0);
}

// ------------------------------------------------------------- ray files

TEST(RayFile, EncodeDecodeIsExactForEverySet) {
  const Sets& s = test_sets();
  auto embree = built("embree", s.scene);
  for (const auto& set : s.sets) {
    const TraceOutput out = trace(*embree, set, false);
    const RayFile f = decode_ray_file(encode_ray_file(set, set.occlusion ? nullptr : &out.hits,
                                                      set.occlusion ? &out.occluded : nullptr));
    EXPECT_EQ(f.set.name, set.name);
    EXPECT_EQ(f.set.occlusion, set.occlusion);
    ASSERT_EQ(f.set.rays.size(), set.rays.size());
    EXPECT_EQ(std::memcmp(f.set.rays.data(), set.rays.data(), set.rays.size() * sizeof(Ray)), 0) << set.name;
    EXPECT_TRUE(f.has_hits);
    if (set.occlusion) EXPECT_EQ(f.occluded, out.occluded);
    else EXPECT_TRUE(same_bits(f.hits, out.hits)) << set.name;
    // Without hits: rays only, and the size says so.
    const std::string bare = encode_ray_file(set, nullptr, nullptr);
    EXPECT_EQ(bare.size(), kRayFileHeaderBytes + set.rays.size() * kRayFileRayBytes);
    EXPECT_FALSE(decode_ray_file(bare).has_hits);
  }
}

TEST(RayFile, HeaderLayoutIsLittleEndianAsDocumented) {
  RaySet set{"random", true, {Ray(Vec3f(1, 2, 3), Vec3f(0, 0, 1), 0.5f, 2.0f)}};
  const std::string b = encode_ray_file(set, nullptr, nullptr);
  ASSERT_EQ(b.size(), 72u);
  EXPECT_EQ(b.substr(0, 8), "RAYLABRF");
  EXPECT_EQ(b.substr(8, 4), std::string("\x01\x00\x00\x00", 4));   // version 1
  EXPECT_EQ(b.substr(12, 4), std::string("\x01\x00\x00\x00", 4));  // flags: occlusion
  EXPECT_EQ(b.substr(16, 8), std::string("\x01\x00\x00\x00\x00\x00\x00\x00", 8));
  EXPECT_EQ(b.substr(24, 16), std::string("random\0\0\0\0\0\0\0\0\0\0", 16));
  EXPECT_EQ(b.substr(40, 4), std::string("\x00\x00\x80\x3f", 4));  // 1.0f
  EXPECT_EQ(b.substr(64, 4), std::string("\x00\x00\x00\x3f", 4));  // tmin 0.5f
}

TEST(RayFile, BadFilesGiveClearErrors) {
  RaySet set{"primary", false, {}};
  for (int i = 0; i < 10; ++i) set.rays.emplace_back(Vec3f(0, 0, -5), Vec3f(0, 0.01f * i, 1));
  const std::string good = encode_ray_file(set, nullptr, nullptr);
  auto error_of = [](const std::string& bytes) {
    try {
      decode_ray_file(bytes, "f");
    } catch (const RayFileError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_THAT(error_of(good.substr(0, 20)), HasSubstr("truncated header"));
  EXPECT_THAT(error_of(good.substr(0, good.size() - 1)), HasSubstr("truncated"));
  EXPECT_THAT(error_of(good + "x"), HasSubstr("trailing bytes"));
  std::string magic = good;
  magic[0] = 'X';
  EXPECT_THAT(error_of(magic), HasSubstr("wrong magic"));
  std::string version = good;
  version[8] = 2;
  EXPECT_THAT(error_of(version), HasSubstr("unsupported ray file version 2"));
  std::string flags = good;
  flags[12] = 8;
  EXPECT_THAT(error_of(flags), HasSubstr("unknown flags"));
  // A count whose byte size overflows 64 bits must not wrap around to a match.
  for (uint64_t count : {uint64_t{1} << 59, (uint64_t{1} << 63) + 10, ~uint64_t{0}}) {
    std::string huge = good;
    for (int i = 0; i < 8; ++i) huge[16 + i] = static_cast<char>((count >> (8 * i)) & 0xFF);
    EXPECT_THAT(error_of(huge), HasSubstr("truncated")) << count;
  }
  EXPECT_THROW(read_ray_file("/nonexistent/rays.bin"), RayFileError);
}

TEST(RayFile, NanFieldsAreInvalidRaysThatMissEverywhere) {
  const Sets& s = test_sets();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  RaySet set{"primary", false, {}};
  const Ray good(Vec3f(278.0f, 273.0f, -800.0f), Vec3f(0.01f, 0.02f, 1.0f));
  for (int field = 0; field < 8; ++field) {
    Ray r = good;
    if (field < 3) r.org[field] = nan;
    else if (field < 6) r.dir[field - 3] = nan;
    else if (field == 6) r.tmin = nan;
    else r.tmax = nan;
    set.rays.push_back(r);
  }
  set.rays.push_back(good);
  const RayFile f = decode_ray_file(encode_ray_file(set, nullptr, nullptr));
  for (const char* spec : {"embree", "embree:api=packet16", "bvh", "kdtree", "grid", "brute"}) {
    auto a = built(spec, s.scene);
    for (bool occlusion : {false, true}) {
      RaySet traced = f.set;
      traced.occlusion = occlusion;
      const TraceOutput out = trace(*a, traced, true);
      for (size_t i = 0; i < 8; ++i) {
        if (occlusion) EXPECT_EQ(out.occluded[i], 0) << spec << " field " << i;
        else EXPECT_FALSE(out.hits[i].valid()) << spec << " field " << i;
      }
      if (occlusion) EXPECT_EQ(out.occluded[8], 1) << spec;
      else EXPECT_TRUE(out.hits[8].valid()) << spec;
    }
  }
}

TEST(RayFile, CommandLineRoundTripGivesTheSameHits) {
  const fs::path dir = test::temp_dir("rayfile");
  for (const char* set : {"primary", "diffuse", "shadow", "random"}) {
    const std::string file = (dir / (std::string(set) + ".rays")).string();
    const auto r = test::run_raylab(std::string("rays --scene cornell --ray-sets ") + set +
                                    " --size 20x12 --rays 700 --hits --out " + file);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const RayFile f = read_ray_file(file);
    // The same rays as the generator makes for bench, and the same answers when traced again.
    const Scene scene = load_scene("cornell");
    auto embree = built("embree", scene);
    RaySetOptions o;
    o.width = 20;
    o.height = 12;
    o.random_count = 700;
    const RaySet want = make_ray_sets(scene, {set}, *embree, o).front();
    ASSERT_EQ(f.set.rays.size(), want.rays.size()) << set;
    EXPECT_EQ(std::memcmp(f.set.rays.data(), want.rays.data(), want.rays.size() * sizeof(Ray)), 0) << set;
    EXPECT_EQ(f.set.occlusion, want.occlusion);
    ASSERT_TRUE(f.has_hits);
    const TraceOutput again = trace(*embree, f.set, true);
    if (f.set.occlusion) EXPECT_EQ(again.occluded, f.occluded) << set;
    else EXPECT_TRUE(same_bits(again.hits, f.hits)) << set;

    const std::string json = (dir / (std::string(set) + ".json")).string();
    const auto b = test::run_raylab("bench --scene cornell --ray-file " + file +
                                    " --accel embree,bvh --threads 1 --repeats 1 --min-time 0 --quiet -o " + json);
    ASSERT_EQ(b.exit_code, 0) << b.output;
    std::ifstream in(json);
    const auto j = nlohmann::json::parse(in);
    ASSERT_EQ(j["records"].size(), 2u);
    for (const auto& rec : j["records"]) {
      EXPECT_EQ(rec["ray_set"], set);
      EXPECT_EQ(rec["rays"].get<size_t>(), want.rays.size());
      EXPECT_EQ(rec["embree_agreement"].get<double>(), 1.0) << rec.dump();
    }
  }
  fs::remove_all(dir);
}

TEST(RayFile, CommandLineErrorsExitWith2) {
  const fs::path dir = test::temp_dir("rayfile_bad");
  const std::string bad = (dir / "bad.rays").string();
  {
    std::ofstream out(bad, std::ios::binary);
    out << "RAYLABRF\x09";
  }
  auto r = test::run_raylab("bench --scene cornell --ray-file " + bad + " --quiet");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("truncated header"));
  r = test::run_raylab("bench --scene cornell --ray-file " + (dir / "missing.rays").string() + " --quiet");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("no such file"));
  r = test::run_raylab("rays --scene cornell --ray-sets sideways --out " + (dir / "x.rays").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_THAT(r.output, HasSubstr("unknown ray set"));
  EXPECT_FALSE(fs::exists(dir / "x.rays"));
  fs::remove_all(dir);
}

// ------------------------------------------------------------- bench

TEST(BenchBestEmbree, RatiosToSingleRayAndToTheBestEmbreeMode) {
  const fs::path dir = test::temp_dir("bench_best");
  const std::string json = (dir / "b.json").string();
  const auto r = test::run_raylab(
      "bench --scene soup:n=400 --accel \"embree;embree:api=packet16;embree:api=packet16,coherent=1;bvh\" "
      "--ray-sets primary,shadow --size 24x24 --threads 1 --repeats 2 --min-time 0 --quiet -o " + json);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::ifstream in(json);
  const auto j = nlohmann::json::parse(in);
  std::map<std::string, std::map<std::string, nlohmann::json>> by;  // set -> accel -> record
  bool best_differs = false;
  for (const auto& rec : j["records"]) {
    by[rec["ray_set"]][rec["accel"]] = rec;
    best_differs |= rec["best_embree"] != "embree";
  }
  // The table's best-Embree columns are shown only when they differ from the ratio to Embree.
  EXPECT_EQ(r.output.find("best embree") != std::string::npos, best_differs) << r.output;
  ASSERT_EQ(by.size(), 2u);
  for (auto& [set, recs] : by) {
    ASSERT_EQ(recs.size(), 4u) << set;
    double best_ratio = 0;
    std::string best_spec;
    for (auto& [accel, rec] : recs)
      if (is_embree_spec(accel) && rec["ratio_to_embree"].get<double>() > best_ratio) {
        best_ratio = rec["ratio_to_embree"];
        best_spec = accel;
      }
    for (auto& [accel, rec] : recs) {
      EXPECT_EQ(rec["best_embree"], best_spec) << rec.dump();
      EXPECT_NEAR(rec["ratio_to_best_embree"].get<double>(), rec["ratio_to_embree"].get<double>() / best_ratio, 1e-9)
          << rec.dump();
      EXPECT_GE(rec["prepare_ms"].get<double>(), 0.0);
      EXPECT_EQ(rec["embree_agreement"].get<double>(), 1.0) << accel << " " << set;
    }
    EXPECT_GT(recs["embree:api=packet16"]["prepare_ms"].get<double>(), 0.0);
  }
  const auto lines = [&] {
    std::ifstream c(dir / "b.csv");
    std::string header;
    std::getline(c, header);
    return header;
  }();
  EXPECT_THAT(lines, HasSubstr("ratio_to_best_embree"));
  fs::remove_all(dir);
}

TEST(BenchBestEmbree, SelfCheckCommand) {
  const auto r = test::run_raylab("bench --embree-selfcheck --scene soup:n=300 --ray-sets primary,shadow --size 16x16 "
                                  "--repeats 1 --min-time 0 --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("adapter"));
  EXPECT_THAT(r.output, HasSubstr("yes"));
  EXPECT_THAT(r.output, ::testing::Not(HasSubstr(" NO ")));
}

}  // namespace
}  // namespace raylab

namespace raylab {
namespace {

TEST(BenchScenes, SharedMeshesAreBenchmarkedFromTheirInteriorViews) {
  if (!test::have_shared_scenes()) GTEST_SKIP() << "../shared/scenes not present";
  const std::string cmd = std::string("cd '") + RAYLAB_SOURCE_DIR + "' && bash scripts/bench-scenes.sh --list";
  FILE* p = popen(cmd.c_str(), "r");
  ASSERT_NE(p, nullptr);
  std::string out;
  char buf[512];
  while (fgets(buf, sizeof buf, p)) out += buf;
  ASSERT_EQ(pclose(p), 0) << out;
  for (const char* view : {"scenes/shared/sponza.json\n", "scenes/shared/sponza_aisle.json\n",
                           "scenes/shared/conference.json\n", "scenes/shared/dragon_in_sponza.json\n",
                           "../shared/scenes/bunny.ply\n"})
    EXPECT_THAT(out, HasSubstr(view));
  // The outside framings of the interior scenes are not in the set.
  for (const char* outside : {"scenes/sponza.ply", "scenes/conference.ply", "scenes/dragon_in_sponza.ply"})
    EXPECT_THAT(out, ::testing::Not(HasSubstr(outside)));
  // Every interior view loads, with its camera inside the mesh's bounds and an emitter.
  for (const char* view : {"sponza.json", "sponza_aisle.json", "conference.json"}) {
    const Scene s = load_scene(std::string(RAYLAB_SOURCE_DIR) + "/scenes/shared/" + view);
    EXPECT_TRUE(s.has_emitters()) << view;
    const Aabb b = s.bounds();
    for (int a = 0; a < 3; ++a) {
      EXPECT_GT(s.view.from[a], b.lo[a]) << view;
      EXPECT_LT(s.view.from[a], b.hi[a]) << view;
    }
  }
}

}  // namespace
}  // namespace raylab
