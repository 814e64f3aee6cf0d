// `raylab stress`: its JSON records and its exit codes.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include <nlohmann/json.hpp>

#include "tests/test_util.h"

namespace raylab {
namespace {

TEST(StressCommand, WritesJsonWithVerifyKeysAndExitsZero) {
  const auto dir = test::temp_dir("cli_stress");
  const auto json = dir / "s.json";
  const auto r = test::run_raylab("stress --scenario single,empty,watertight_box --accel bvh,brute --ray-scale 0.05 -o " +
                                  json.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("watertight_box"), std::string::npos);
  std::ifstream in(json);
  const auto j = nlohmann::json::parse(in);
  ASSERT_TRUE(j.contains("records"));
  // single and empty: 2 each; watertight_box: bvh, bvh:tri=mt, brute, brute:tri=mt.
  ASSERT_EQ(j["records"].size(), 8u);
  for (const auto& rec : j["records"]) {
    for (const char* key : {"scene", "accel", "ray_set", "rays", "hit_miss_disagree", "prim_disagree", "max_rel_t_err",
                            "raylab_wrong", "embree_wrong", "ties", "occlusion_disagree", "scenario", "status",
                            "build_ms", "bytes", "mrays_per_s", "embree_robust_mrays_per_s", "ratio_to_embree_robust",
                            "leaks"})
      EXPECT_TRUE(rec.contains(key)) << key;
    // The reference is robust Embree: the ratio says so, and bench's name (to default Embree) is not used.
    EXPECT_FALSE(rec.contains("ratio_to_embree")) << rec.dump();
    EXPECT_FALSE(rec.contains("embree_mrays_per_s")) << rec.dump();
    EXPECT_EQ(rec["raylab_wrong"], 0);
  }
  for (const char* key : {"cpu", "revision", "date", "embree", "compiler"}) EXPECT_TRUE(j.contains(key)) << key;
}

TEST(StressCommand, BadArgumentsExitTwo) {
  const auto dir = test::temp_dir("cli_stress_bad");
  const auto json = dir / "s.json";
  const auto r = test::run_raylab("stress --scenario nosuch -o " + json.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("unknown stress scenario 'nosuch'"), std::string::npos) << r.output;
  EXPECT_FALSE(std::filesystem::exists(json));
  EXPECT_EQ(test::run_raylab("stress --accel nosuch --scenario single").exit_code, 2);
  const auto list = test::run_raylab("stress --list");
  EXPECT_EQ(list.exit_code, 0);
  EXPECT_NE(list.output.find("watertight_torus"), std::string::npos);
}

}  // namespace
}  // namespace raylab
