// `raylab compare`: the Mann–Whitney U test against SciPy's values, and the
// command on synthetic bench reports: same-distribution runs are not flagged,
// a deliberately slowed structure is, and --fail-above turns it into exit 1.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include <nlohmann/json.hpp>

#include "bench/compare.h"
#include "tests/test_util.h"
#include "base/pcg.h"

namespace raylab {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
namespace fs = std::filesystem;

TEST(MannWhitney, MatchesScipy) {
  // scipy.stats.mannwhitneyu(a, b, method=...).pvalue (SciPy 1.10, two-sided).
  EXPECT_NEAR(mann_whitney_p({1, 3, 5, 7, 9}, {2, 4, 6, 8, 10}), 0.6904761904761905, 1e-12);  // exact
  EXPECT_NEAR(mann_whitney_p({1, 2, 3, 4, 5}, {6, 7, 8, 9, 10}), 0.007936507936507936, 1e-12);  // exact, 2/252
  EXPECT_NEAR(mann_whitney_p({6, 7, 8, 9, 10}, {1, 2, 3, 4, 5}), 0.007936507936507936, 1e-12);  // symmetric
  // Ties: normal approximation with tie and continuity correction ('asymptotic').
  EXPECT_NEAR(mann_whitney_p({1, 2, 2, 3, 4, 5}, {3, 6, 7, 8, 9, 10, 11}), 0.009922392930798569, 1e-9);
  std::vector<double> a, b;
  for (int i = 0; i < 30; ++i) {
    a.push_back(i);
    b.push_back(i + 7.5);
  }
  EXPECT_NEAR(mann_whitney_p(a, b), 0.003670893392450653, 1e-9);  // beyond the exact table: 'asymptotic'
  EXPECT_EQ(mann_whitney_p({}, {1, 2}), 1.0);
  EXPECT_EQ(mann_whitney_p({1, 1, 1}, {1, 1, 1}), 1.0);
}

// A bench report with one cell per accelerator; trace times around `seconds`
// with +-2 % noise.
// `machine` scales every time, Embree's too: a machine-wide slow-down between runs.
nlohmann::json synthetic_report(const std::map<std::string, double>& seconds, uint64_t seed, int repeats = 7,
                                double machine = 1.0) {
  Pcg32 rng(seed, 7);
  nlohmann::json recs = nlohmann::json::array();
  for (const auto& [accel, s] : seconds) {
    std::vector<double> t;
    for (int i = 0; i < repeats; ++i) t.push_back(machine * s * (1.0 + 0.04 * (rng.uniform() - 0.5)));
    std::vector<double> sorted = t;
    std::sort(sorted.begin(), sorted.end());
    const double median = sorted[sorted.size() / 2];
    const double embree_s = machine * 0.008 * (1.0 + 0.01 * (rng.uniform() - 0.5));
    recs.push_back({{"scene", "soup:n=1000"}, {"accel", accel}, {"ray_set", "primary"}, {"threads", 1},
                    {"rays", 100000}, {"mrays_per_s", 0.1 / median}, {"build_ms", 10.0}, {"bytes", 1000},
                    {"embree_mrays_per_s", 0.1 / embree_s}, {"ratio_to_embree", embree_s / median},
                    {"trace_s", t}});
  }
  return {{"schema_version", 2}, {"command", "bench"}, {"records", recs}};
}

std::string write(const fs::path& dir, const std::string& name, const nlohmann::json& j) {
  std::ofstream(dir / name) << j.dump();
  return (dir / name).string();
}

TEST(Compare, SameDistributionIsNotFlaggedASlowedStructureIs) {
  const auto dir = test::temp_dir("compare_cli");
  const auto a = write(dir, "a.json", synthetic_report({{"bvh", 0.010}, {"kdtree", 0.020}}, 1));
  const auto same = write(dir, "same.json", synthetic_report({{"bvh", 0.010}, {"kdtree", 0.020}}, 2));
  const auto slow = write(dir, "slow.json", synthetic_report({{"bvh", 0.010}, {"kdtree", 0.026}}, 3));  // kdtree 30 % slower

  const auto r1 = test::run_raylab("compare " + a + " " + same + " --fail-above 5");
  EXPECT_EQ(r1.exit_code, 0) << r1.output;
  EXPECT_THAT(r1.output, Not(HasSubstr("REGRESSION")));
  EXPECT_THAT(r1.output, HasSubstr("2 matching cells"));

  const auto r2 = test::run_raylab("compare " + a + " " + slow + " --fail-above 5");
  EXPECT_EQ(r2.exit_code, 1) << r2.output;
  EXPECT_THAT(r2.output, HasSubstr("REGRESSION"));
  EXPECT_THAT(r2.output, HasSubstr("1 regression "));

  // Without a threshold the slow-down is reported but the exit code stays 0.
  const auto r3 = test::run_raylab("compare " + a + " " + slow + " --json -");
  EXPECT_EQ(r3.exit_code, 0) << r3.output;
  const auto j = nlohmann::json::parse(r3.output);
  EXPECT_EQ(j["schema_version"], 2);
  ASSERT_EQ(j["cells"].size(), 2u);
  for (const auto& c : j["cells"]) {
    if (c["accel"] == "kdtree") {
      EXPECT_TRUE(c["significant"].get<bool>()) << c.dump();
      EXPECT_LT(c["p_value"].get<double>(), 0.01);
      EXPECT_NEAR(c["speed_change_pct"].get<double>(), -23.0, 3.0);
    } else {
      EXPECT_FALSE(c["significant"].get<bool>()) << c.dump();
    }
    EXPECT_FALSE(c["regression"].get<bool>());
  }
}

TEST(Compare, MachineWideDriftIsCancelledByTheSameCellEmbreeTime) {
  // Run B on a machine 12 % slower throughout (Embree too): by default nothing
  // is significant, because each repeat is divided by its cell's Embree time;
  // --raw sees the drift as a slow-down of every structure.
  const auto dir = test::temp_dir("compare_drift");
  const auto a = write(dir, "a.json", synthetic_report({{"bvh", 0.010}, {"kdtree", 0.020}}, 1));
  const auto b = write(dir, "b.json", synthetic_report({{"bvh", 0.010}, {"kdtree", 0.020}}, 2, 7, 1.12));
  const auto normalized = test::run_raylab("compare " + a + " " + b + " --fail-above 5 --json -");
  ASSERT_EQ(normalized.exit_code, 0) << normalized.output;
  const auto j = nlohmann::json::parse(normalized.output);
  EXPECT_TRUE(j["normalize_by_embree"].get<bool>());
  for (const auto& c : j["cells"]) {
    EXPECT_TRUE(c["normalized_by_embree"].get<bool>()) << c.dump();
    EXPECT_FALSE(c["significant"].get<bool>()) << c.dump();
    EXPECT_LT(std::abs(c["speed_change_pct"].get<double>()), 4.0) << c.dump();
  }
  const auto raw = test::run_raylab("compare " + a + " " + b + " --fail-above 5 --raw");
  EXPECT_EQ(raw.exit_code, 1) << raw.output;
  EXPECT_THAT(raw.output, HasSubstr("2 regressions "));
  // A real slow-down of one structure still shows through the normalisation.
  const auto slow = write(dir, "slow.json", synthetic_report({{"bvh", 0.010}, {"kdtree", 0.026}}, 3, 7, 1.12));
  const auto r = test::run_raylab("compare " + a + " " + slow + " --fail-above 5");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_THAT(r.output, HasSubstr("1 regression "));
}

TEST(Compare, CellsMatchOnSceneAccelRaySetAndThreads) {
  const auto dir = test::temp_dir("compare_match");
  const auto a = write(dir, "a.json", synthetic_report({{"bvh", 0.01}, {"grid", 0.02}}, 1));
  const auto b = write(dir, "b.json", synthetic_report({{"bvh", 0.01}, {"kdtree", 0.02}, {"brute", 1.0}}, 2));
  const auto r = test::run_raylab("compare " + a + " " + b + " --json -");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  EXPECT_EQ(j["cells"].size(), 1u);
  EXPECT_EQ(j["only_in_a"], 1);
  EXPECT_EQ(j["only_in_b"], 2);
}

TEST(Compare, BadInputExitsWith2) {
  const auto dir = test::temp_dir("compare_bad");
  const auto a = write(dir, "a.json", synthetic_report({{"bvh", 0.01}}, 1));
  const auto verify = write(dir, "v.json", nlohmann::json{{"command", "verify"}, {"records", nlohmann::json::array()}});
  const auto other = write(dir, "o.json", synthetic_report({{"grid", 0.01}}, 1));
  std::ofstream(dir / "junk.json") << "{not json";
  for (const auto& [args, message] : std::vector<std::pair<std::string, std::string>>{
           {a + " " + verify, "bench reports"},
           {a + " " + (dir / "junk.json").string(), "not JSON"},
           {a + " " + (dir / "missing.json").string(), "cannot open"},
           {a + " " + other, "no cell"},
           {a, "required"}}) {
    const auto r = test::run_raylab("compare " + args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr(message)) << args;
  }
}

}  // namespace
}  // namespace raylab
