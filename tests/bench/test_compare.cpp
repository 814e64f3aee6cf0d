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
  const auto r3 = test::run_raylab("compare " + a + " " + slow + " -o -");
  EXPECT_EQ(r3.exit_code, 0) << r3.output;
  const auto j = nlohmann::json::parse(r3.output);
  EXPECT_EQ(j["schema_version"], 3);
  ASSERT_EQ(j["cells"].size(), 2u);
  for (const auto& c : j["cells"]) {
    if (c["accel"] == "kdtree") {
      EXPECT_TRUE(c["significant"].get<bool>()) << c.dump();
      EXPECT_LT(c["p_value"].get<double>(), 0.01);
      EXPECT_NEAR(c["change_pct"].get<double>(), -23.0, 3.0);
      EXPECT_EQ(c["tested"], "ratio_to_embree");
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
  const auto normalized = test::run_raylab("compare " + a + " " + b + " --fail-above 5 -o -");
  ASSERT_EQ(normalized.exit_code, 0) << normalized.output;
  const auto j = nlohmann::json::parse(normalized.output);
  EXPECT_TRUE(j["normalize_by_embree"].get<bool>());
  for (const auto& c : j["cells"]) {
    EXPECT_EQ(c["tested"], "ratio_to_embree") << c.dump();
    EXPECT_FALSE(c["significant"].get<bool>()) << c.dump();
    EXPECT_LT(std::abs(c["change_pct"].get<double>()), 4.0) << c.dump();
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

TEST(MannWhitney, SmallestPossiblePIsTwoOverTheOrderings) {
  EXPECT_NEAR(mann_whitney_min_p(5, 5), 2.0 / 252.0, 1e-12);  // 0.0079: any complete separation
  EXPECT_NEAR(mann_whitney_min_p(3, 3), 0.1, 1e-12);          // never below 0.05
  EXPECT_NEAR(mann_whitney_min_p(7, 7), 2.0 / 3432.0, 1e-12);
  EXPECT_EQ(mann_whitney_min_p(0, 4), 1.0);
  // Complete separation of 5 and 5 values reaches it, whatever the size of the shift.
  EXPECT_NEAR(mann_whitney_p({1.000, 1.001, 1.002, 1.003, 1.004}, {1.005, 1.006, 1.007, 1.008, 1.009}),
              mann_whitney_min_p(5, 5), 1e-12);
}

// One cell of a bench report with the given speeds and per-repeat times.
nlohmann::json cell(const std::string& accel, double mrays, double embree_mrays, int repeats, double noise, uint64_t seed) {
  Pcg32 rng(seed, 3);
  const double rays = 100000, t = rays / (mrays * 1e6), e = rays / (embree_mrays * 1e6);
  std::vector<double> ts, es;
  for (int i = 0; i < repeats; ++i) {
    ts.push_back(t * (1.0 + noise * (rng.uniform() - 0.5)));
    es.push_back(e * (1.0 + noise * (rng.uniform() - 0.5)));
  }
  return {{"scene", "s"}, {"accel", accel}, {"ray_set", "primary"}, {"threads", 1}, {"rays", rays},
          {"mrays_per_s", mrays}, {"embree_mrays_per_s", embree_mrays}, {"ratio_to_embree", mrays / embree_mrays},
          {"trace_s", ts}, {"embree_trace_s", es}, {"build_ms", 1.0}, {"bytes", 100}};
}
nlohmann::json report_of(std::vector<nlohmann::json> records) {
  return {{"schema_version", 3}, {"command", "bench"}, {"records", records}};
}
// Reports A and B of these cells written to a fresh temp dir compare_NAME: "A B" for compare.
std::string report_pair(const std::string& name, std::vector<nlohmann::json> a, std::vector<nlohmann::json> b) {
  const auto dir = test::temp_dir("compare_" + name);
  return write(dir, "a.json", report_of(std::move(a))) + " " + write(dir, "b.json", report_of(std::move(b)));
}

TEST(Compare, MraysAndRatioChangesAreTwoColumnsWhoseSignsAgreeWithTheirHeaders) {
  // Embree ran 35 % slower in B and grid 19 % slower: grid's Mrays/s fell while
  // its ratio to Embree rose. A single "speed" column of the ratio's change
  // would call +24.6 % "faster" a structure whose speed fell.
  const auto ab = report_pair("drift", {cell("embree", 20.0, 20.0, 5, 0.0, 1), cell("grid", 10.0, 20.0, 5, 0.0, 2)},
                              {cell("embree", 13.0, 13.0, 5, 0.0, 3), cell("grid", 8.1, 13.0, 5, 0.0, 4)});
  const auto r = test::run_raylab("compare " + ab + " --no-noise-floor -o -");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = nlohmann::json::parse(r.output);
  for (const auto& c : j["cells"]) {
    if (c["accel"] == "grid") {
      EXPECT_NEAR(c["mrays_change_pct"].get<double>(), -19.0, 1e-9);
      EXPECT_NEAR(c["ratio_to_embree_change_pct"].get<double>(), (8.1 / 13.0) / 0.5 * 100 - 100, 1e-9);
      EXPECT_GT(c["ratio_to_embree_change_pct"].get<double>(), 0.0);
      EXPECT_EQ(c["tested"], "ratio_to_embree");
    } else {
      EXPECT_NEAR(c["mrays_change_pct"].get<double>(), -35.0, 1e-9);
      EXPECT_TRUE(c["ratio_to_embree_change_pct"].is_null());
      EXPECT_EQ(c["tested"], "none (the reference)");  // its change is the machine's drift
    }
  }
  const auto t = test::run_raylab("compare " + ab + " --no-noise-floor --colour never");
  ASSERT_EQ(t.exit_code, 0) << t.output;
  EXPECT_THAT(t.output, HasSubstr("Mrays/s chg"));
  EXPECT_THAT(t.output, HasSubstr("x embree chg"));
  EXPECT_THAT(t.output, ::testing::ContainsRegex("grid +primary +1 +10.00 +8.10 +-19.0% +\\+24.6%"));
  EXPECT_THAT(t.output, ::testing::ContainsRegex("embree +primary +1 +20.00 +13.00 +-35.0% +n/a .* reference"));
  EXPECT_THAT(t.output, HasSubstr("positive = faster"));
}

TEST(Compare, RepeatsThatCannotReachSignificanceAreNamed) {
  const auto ab = report_pair("few", {cell("embree", 20, 20, 3, 0.01, 1), cell("bvh", 10, 20, 3, 0.01, 2)},
                              {cell("embree", 20, 20, 3, 0.01, 3), cell("bvh", 5, 20, 3, 0.01, 4)});
  const auto r = test::run_raylab("compare " + ab + " --fail-above 5 --colour never");
  // Half the speed, but three repeats a side can never give p < 0.05: not reported, and said so.
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("warning: 2 cells cannot reach significance: with 3 and 3 repeats the smallest p"));
  EXPECT_THAT(r.output, HasSubstr("0.1"));
  EXPECT_THAT(r.output, HasSubstr("too few"));
}

TEST(Compare, TheMinimumEffectIsStatedAndRaisedToTheRunsNoiseFloor) {
  // A complete separation (p = 0.0079) of a 2 % shift is not reported: under --min-effect 3.
  const auto ab = report_pair("small", {cell("embree", 20, 20, 5, 0.001, 1), cell("bvh", 10.0, 20, 5, 0.001, 2)},
                              {cell("embree", 20, 20, 5, 0.001, 3), cell("bvh", 9.8, 20, 5, 0.001, 4)});
  auto j = nlohmann::json::parse(test::run_raylab("compare " + ab + " -o -").output);
  EXPECT_EQ(j["min_effect_pct"], 3.0);
  for (const auto& c : j["cells"])
    if (c["accel"] == "bvh") {
      EXPECT_LT(c["p_value"].get<double>(), 0.01);
      EXPECT_FALSE(c["significant"].get<bool>()) << c.dump();
    }
  EXPECT_THAT(test::run_raylab("compare " + ab + " --min-effect 1 -o -").output, HasSubstr("\"significant\": 1"));
  // A run whose Embree wandered by 20 % between cells: a 10 % change is within its noise.
  const auto noisy = report_pair(
      "noisy", {cell("embree", 20, 20, 5, 0.001, 1), cell("bvh", 10, 24, 5, 0.001, 2), cell("grid", 5, 20, 5, 0.001, 5)},
      {cell("embree", 20, 20, 5, 0.001, 3), cell("bvh", 9, 24, 5, 0.001, 4), cell("grid", 5, 20, 5, 0.001, 6)});
  j = nlohmann::json::parse(test::run_raylab("compare " + noisy + " -o -").output);
  EXPECT_NEAR(j["noise_a_pct"].get<double>(), 20.0, 0.5);
  EXPECT_NEAR(j["threshold_pct"].get<double>(), 20.0, 0.5);
  EXPECT_EQ(j["significant"], 0);
  EXPECT_THAT(test::run_raylab("compare " + noisy + " --colour never").output,
              HasSubstr("at least 20.0% (the noise floor, above --min-effect 3%)"));
  EXPECT_THAT(test::run_raylab("compare " + noisy + " --no-noise-floor -o -").output, HasSubstr("\"significant\": 1"));
}

TEST(Compare, CellsMatchOnSceneAccelRaySetAndThreads) {
  const auto dir = test::temp_dir("compare_match");
  const auto a = write(dir, "a.json", synthetic_report({{"bvh", 0.01}, {"grid", 0.02}}, 1));
  const auto b = write(dir, "b.json", synthetic_report({{"bvh", 0.01}, {"kdtree", 0.02}, {"brute", 1.0}}, 2));
  const auto r = test::run_raylab("compare " + a + " " + b + " -o -");
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

namespace raylab {
namespace {

// Ten pairs of bench runs of one binary on this shared VM
// (tests/data/compare_same_binary.json says how they were made).
std::vector<std::pair<nlohmann::json, nlohmann::json>> recorded_pairs() {
  std::ifstream in(std::string(RAYLAB_SOURCE_DIR) + "/tests/data/compare_same_binary.json");
  const auto doc = nlohmann::json::parse(in);
  std::vector<std::pair<nlohmann::json, nlohmann::json>> pairs;
  for (const auto& p : doc["pairs"]) pairs.push_back({p["a"], p["b"]});
  return pairs;
}

// B's `accel` made `factor` times slower in every repeat.
nlohmann::json slowed(nlohmann::json report, const std::string& accel, double factor) {
  for (auto& r : report["records"]) {
    if (r["accel"] != accel) continue;
    for (auto& t : r["trace_s"]) t = t.get<double>() * factor;
    r["mrays_per_s"] = r["mrays_per_s"].get<double>() / factor;
    r["ratio_to_embree"] = r["ratio_to_embree"].get<double>() / factor;
  }
  return report;
}

TEST(CompareRecorded, SameBinaryTwiceReportsNoChangeInNineOfTenPairs) {
  const auto pairs = recorded_pairs();
  ASSERT_EQ(pairs.size(), 10u);
  CompareOptions opt;
  opt.fail_above_pct = 5;
  size_t quiet = 0;
  for (const auto& [a, b] : pairs) {
    const CompareResult r = compare_bench_reports(a, b, opt);
    ASSERT_EQ(r.cells.size(), 10u);
    quiet += r.significant == 0 && r.regressions == 0;
  }
  EXPECT_GE(quiet, 9u) << "same binary, yet a change was reported in " << 10 - quiet << " of 10 pairs";
}

TEST(CompareRecorded, WithoutTheNoiseFloorTheSamePairsCryWolf) {
  // The minimum effect alone (3 %) is below this machine's drift: the same
  // pairs then report changes, which is what the noise floor prevents.
  CompareOptions opt;
  opt.fail_above_pct = 5;
  opt.noise_floor = false;
  size_t flagged = 0;
  for (const auto& [a, b] : recorded_pairs()) flagged += compare_bench_reports(a, b, opt).significant > 0;
  EXPECT_GE(flagged, 3u);
}

TEST(CompareRecorded, AStructureMadeTwiceAsSlowIsReportedInEveryPair) {
  CompareOptions opt;
  opt.fail_above_pct = 5;
  for (const char* accel : {"bvh", "kdtree", "grid", "octree"}) {
    size_t caught = 0, others = 0;
    for (const auto& [a, b] : recorded_pairs()) {
      const CompareResult r = compare_bench_reports(a, slowed(b, accel, 2.0), opt);
      size_t both = 0;
      for (const auto& c : r.cells) {
        if (c.accel == accel) both += c.regression && c.change_pct < -40;
        else others += c.significant;
      }
      caught += both == 2;  // primary and random
    }
    EXPECT_GE(caught, 9u) << accel;
    EXPECT_LE(others, 1u) << accel << ": the untouched structures were reported too";
  }
}

}  // namespace
}  // namespace raylab
