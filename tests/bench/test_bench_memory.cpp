// Memory in `raylab bench`: the resident set read from the OS, the peak reset
// between structures, the estimate that decides a skip before building, and
// the skip reasons in the records (instead of an OOM kill).
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstring>
#include <fstream>
#include <memory>

#include <nlohmann/json.hpp>

#include "bench/bench_run.h"
#include "checks/memory_estimate.h"
#include "checks/process_memory.h"
#include "scenes/scene_registry.h"
#include "tests/report_test_util.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

using ::testing::HasSubstr;

TEST(ProcessMemory, PeakFollowsATouchedAllocationAndResets) {
  // The resident set first, then the peak: the set may grow between two reads (a sanitizer's
  // shadow pages do), and only a peak read later must be at least an earlier resident set.
  const size_t resident = resident_bytes();
  ASSERT_GT(resident, 0u);
  EXPECT_GE(peak_resident_bytes(), resident);
  // After a reset the peak is the current resident set (where supported).
  if (reset_peak_resident()) {
    EXPECT_LE(peak_resident_bytes(), resident_bytes() + (16u << 20));
  }
  const size_t before = resident_bytes();
  constexpr size_t kBytes = 96u << 20;
  {
    auto block = std::make_unique<char[]>(kBytes);
    std::memset(block.get(), 1, kBytes);  // touched, so resident
    EXPECT_GE(resident_bytes(), before + kBytes - (8u << 20));
  }
  // Freed or not (a sanitizer's quarantine keeps it), the peak saw it.
  EXPECT_GE(peak_resident_bytes(), before + kBytes - (8u << 20));
  EXPECT_GT(available_memory_bytes(), 0u);
}

TEST(MemoryEstimate, GrowsWithTrianglesAndKnowsEveryStructure) {
  for (const char* spec : {"embree", "bvh", "bvh:layout=bvh2", "kdtree", "grid", "hashgrid", "grid2", "brute"}) {
    EXPECT_GT(build_peak_bytes_per_triangle(spec), 0.0) << spec;
    EXPECT_GT(estimate_build_peak_bytes(spec, 100'000'000), estimate_build_peak_bytes(spec, 1'000'000)) << spec;
  }
  // 10^8 triangles of bvh need gigabytes, not megabytes.
  EXPECT_GT(estimate_build_peak_bytes("bvh", 100'000'000), size_t{4} << 30);
  // A scalar variant with its own, smaller figure (the grids' ids against SIMD blocks).
  EXPECT_LT(build_peak_bytes_per_triangle("grid:simd=0"), build_peak_bytes_per_triangle("grid"));
  EXPECT_LT(build_peak_bytes_per_triangle("grid2:density=2,simd=0"), build_peak_bytes_per_triangle("grid2:density=2"));
  EXPECT_EQ(build_peak_bytes_per_triangle("grid:simd=1"), build_peak_bytes_per_triangle("grid"));
}

BenchOptions tiny_options() {
  BenchOptions o;
  o.ray_sets = {"primary", "random"};
  o.width = o.height = 8;
  o.random_rays = 100;
  o.repeats = 1;
  return o;
}

TEST(BenchMemory, RecordsCarryTheResidentSetFromTheOs) {
  const Scene scene = load_scene("soup:n=2000");
  const auto records = run_bench(scene, {"embree", "bvh"}, tiny_options());
  ASSERT_EQ(records.size(), 4u);
  for (const auto& r : records) {
    EXPECT_GT(r.rss_before_build_bytes, 0u) << r.accel;
    EXPECT_GE(r.rss_peak_bytes, r.rss_before_build_bytes) << r.accel;
    const nlohmann::json j = r.to_json();
    EXPECT_EQ(j.at("rss_peak_bytes").get<size_t>(), r.rss_peak_bytes);
  }
  EXPECT_THAT(bench_csv(records), HasSubstr("rss_before_build_bytes,rss_peak_bytes"));
}

// With no room at all (headroom ~ 0) nothing is built: every structure is
// skipped with the estimate in its reason, and no record is invented.
TEST(BenchMemory, StructuresThatDoNotFitAreSkippedWithTheEstimate) {
  const Scene scene = load_scene("soup:n=2000");
  BenchOptions o = tiny_options();
  o.memory_headroom = 1e-12;
  std::vector<BenchSkip> skips;
  const auto records = run_bench(scene, {"embree", "bvh", "grid"}, o, {}, {},
                                 [&](const BenchSkip& s) { skips.push_back(s); });
  EXPECT_TRUE(records.empty());
  ASSERT_EQ(skips.size(), 3u);
  EXPECT_EQ(skips[1].accel, "bvh");
  EXPECT_EQ(skips[1].triangles, 2000u);
  EXPECT_THAT(skips[1].reason, HasSubstr("Embree reference needs ~"));
  EXPECT_THAT(skips[1].reason, HasSubstr("by its estimate"));
  EXPECT_GT(skips[1].estimated_bytes, 0u);
  EXPECT_EQ(skips[1].to_json().at("reason").get<std::string>(), skips[1].reason);
}

// A structure whose build fails on a valid scene (a grid whose memory budget
// cannot hold the references, as hashgrid's default 1 GiB at 10^8 triangles):
// a skip with the builder's message, and the structures after it still run.
TEST(BenchMemory, BuildFailureIsASkipAndTheMatrixGoesOn) {
  const Scene scene = load_scene("soup:n=2000");
  std::vector<BenchSkip> skips;
  const auto records = run_bench(scene, {"hashgrid:budget=0.001", "bvh"}, tiny_options(), {}, {},
                                 [&](const BenchSkip& s) { skips.push_back(s); });
  ASSERT_EQ(skips.size(), 1u);
  EXPECT_EQ(skips[0].accel, "hashgrid:budget=0.001");
  EXPECT_THAT(skips[0].reason, HasSubstr("build failed: hashgrid: a memory budget"));
  ASSERT_FALSE(records.empty());
  for (const auto& r : records) EXPECT_EQ(r.accel, "bvh");
}

// The same through the command line: exit 0, the skips in the JSON.
TEST(BenchMemory, CommandLineWritesSkipsToTheJson) {
  const auto [r, j] = test::run_raylab_json("bench_memory_skip", "bench --scene soup:n=500 --accel bvh --ray-sets "
                                            "random --rays 100 --repeats 1 --min-time 0 --threads 1 --memory-headroom 0.000000000001");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("bvh skipped: the Embree reference needs ~"));
  EXPECT_TRUE(j.at("records").empty());
  ASSERT_EQ(j.at("skipped").size(), 1u);
  EXPECT_EQ(j.at("skipped")[0].at("accel"), "bvh");
  EXPECT_THAT(j.at("skipped")[0].at("reason").get<std::string>(), HasSubstr("by its estimate"));
}

}  // namespace
}  // namespace raylab
