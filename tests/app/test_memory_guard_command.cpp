// The memory rule seen from the command line: with RAYLAB_MEMORY_LIMIT below
// what a step needs, verify, stress and render stop before that step with
// exit 2 and a message naming the estimate, the memory available and what
// would fit, and the records finished before it are written. The limit stands
// in for a machine too small for the scene (the same guard reads MemAvailable
// and the cgroup's memory.max otherwise), so the checks run on a small scene.
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include <nlohmann/json.hpp>

#include "tests/test_util.h"

namespace raylab {
namespace {

// A soup of 10^5 triangles: the reference (embree:robust=1, 140 bytes per
// triangle by its registry line) and bvh (170) need about 14 and 17 MB, bsp
// (2,000) about 200 MB; a 100 MB limit lets the first two through and not bsp.
constexpr const char* kScene = "soup:n=100000";

// Sets RAYLAB_MEMORY_LIMIT for the raylab processes started while it lives.
class MemoryLimit {
 public:
  explicit MemoryLimit(const char* limit) { ::setenv("RAYLAB_MEMORY_LIMIT", limit, 1); }
  ~MemoryLimit() { ::unsetenv("RAYLAB_MEMORY_LIMIT"); }
  MemoryLimit(const MemoryLimit&) = delete;
  MemoryLimit& operator=(const MemoryLimit&) = delete;
};

nlohmann::json read_json(const std::filesystem::path& p) {
  std::ifstream f(p);
  return nlohmann::json::parse(f);
}

TEST(MemoryGuardCommand, VerifySkipsTheStructureThatDoesNotFitAfterWritingTheOnesBeforeIt) {
  const auto dir = test::temp_dir("guard_verify_skip");
  const MemoryLimit limit("100M");
  const auto r = test::run_raylab(std::string("verify ") + kScene + " --accel 'bvh;bsp' --ray-sets random --rays 2000 -t 1 -q -o " +
                                  (dir / "v.json").string() + " 2>&1");
  EXPECT_EQ(r.exit_code, 2) << r.output;  // a structure left out: the run did not check everything asked
  EXPECT_NE(r.output.find("bsp skipped"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("by its estimate"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("RAYLAB_MEMORY_LIMIT"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("would fit"), std::string::npos) << r.output;
  const nlohmann::json j = read_json(dir / "v.json");
  ASSERT_EQ(j.at("records").size(), 1u) << j.dump(1);
  EXPECT_EQ(j["records"][0].at("accel").get<std::string>().rfind("bvh", 0), 0u);
  EXPECT_EQ(j["records"][0].at("raylab_wrong"), 0);
  ASSERT_EQ(j.at("skipped").size(), 1u);
  EXPECT_EQ(j["skipped"][0].at("accel").get<std::string>().rfind("bsp", 0), 0u);
  std::filesystem::remove_all(dir);
}

TEST(MemoryGuardCommand, VerifyStopsBeforeAReferenceThatDoesNotFit) {
  const auto dir = test::temp_dir("guard_verify_stop");
  const MemoryLimit limit("4M");
  const auto r = test::run_raylab(std::string("verify ") + kScene + " --accel bvh --ray-sets random --rays 2000 -t 1 -q -o " +
                                  (dir / "v.json").string() + " 2>&1");
  EXPECT_EQ(r.exit_code, 2) << r.output;  // never 137: the guard stops first
  EXPECT_NE(r.output.find("the reference embree:robust=1"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("available (RAYLAB_MEMORY_LIMIT"), std::string::npos) << r.output;
  const nlohmann::json j = read_json(dir / "v.json");
  EXPECT_TRUE(j.at("records").empty());
  EXPECT_FALSE(j.at("complete").get<bool>());
  EXPECT_NE(j.at("stopped").get<std::string>().find("the reference"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(MemoryGuardCommand, StressOnASceneSkipsWhatDoesNotFit) {
  const auto dir = test::temp_dir("guard_stress");
  const MemoryLimit limit("100M");
  const auto r = test::run_raylab(std::string("stress far_1e3 --scene ") + kScene +
                                  " --accel 'bvh;bsp' --ray-scale 0.05 --budget 0.2 -t 1 -q -o " + (dir / "s.json").string() +
                                  " 2>&1");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("bsp skipped"), std::string::npos) << r.output;
  const nlohmann::json j = read_json(dir / "s.json");
  ASSERT_EQ(j.at("records").size(), 1u) << j.dump(1);
  EXPECT_EQ(j["records"][0].at("raylab_wrong"), 0);
  ASSERT_EQ(j.at("skipped").size(), 1u);
  std::filesystem::remove_all(dir);
}

TEST(MemoryGuardCommand, RenderRefusesAStructureThatDoesNotFitAndWritesNoImage) {
  const auto dir = test::temp_dir("guard_render");
  const MemoryLimit limit("100M");
  const auto png = dir / "x.png";
  const auto r = test::run_raylab(std::string("render ") + kScene + " --accel bsp -s 1 --size 16x16 -t 1 -q -o " +
                                  png.string() + " 2>&1");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("bsp needs"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(png));
  // The same command with room for it renders.
  const auto ok = test::run_raylab(std::string("render ") + kScene + " --accel bvh -s 1 --size 16x16 -t 1 -q -o " +
                                   png.string() + " 2>&1");
  EXPECT_EQ(ok.exit_code, 0) << ok.output;
  EXPECT_TRUE(std::filesystem::exists(png));
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace raylab
