// `raylab bench` reports: the JSON schema, consistency of a tiny run (every
// accelerator x every ray set, ratios against the same run's Embree, CSV rows),
// presets and --scale, incremental records and interruption, `render --timings`,
// and bench/plot.py on the tiny report.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <fstream>
#include <set>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "bench/bench_run.h"
#include "scenes/scene_registry.h"
#include "tests/report_test_util.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;
using test::read_json;
using test::read_lines;

// One tiny run shared by the schema and consistency tests.
class TinyBench : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(test::temp_dir("bench_tiny"));
    const auto r = test::run_raylab("bench --scene soup:n=300 --accel embree,bvh,grid --ray-sets primary,diffuse,shadow,random "
                                    "--size 24x24 --rays 1500 --repeats 2 --min-time 0 --threads 1 --quiet -o " +
                                    (*dir_ / "tiny.json").string());
    exit_code_ = r.exit_code;
    output_ = new std::string(r.output);
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
    delete output_;
  }
  static fs::path* dir_;
  static int exit_code_;
  static std::string* output_;
};
fs::path* TinyBench::dir_ = nullptr;
int TinyBench::exit_code_ = -1;
std::string* TinyBench::output_ = nullptr;

// RAYLAB_EMBREE_ISA caps Embree (its max_isa= setting) and the header names the capped ISA;
// an unknown name is a one-line error and exit 2, before anything is written.
TEST(BenchEmbreeIsa, TheCapIsNamedAndUnknownNamesAreRefused) {
  const auto dir = test::temp_dir("bench_embree_isa");
  const std::string args = std::string(RAYLAB_BINARY) +
                           " bench --scene soup:n=300 --accel embree,bvh --ray-sets primary --size 16x16 --repeats 1 "
                           "--threads 1 --quiet -o ";
  const auto capped = test::run_shell("RAYLAB_EMBREE_ISA=sse2 " + args + (dir / "sse2.json").string() + " 2>&1");
  ASSERT_EQ(capped.exit_code, 0) << capped.output;
  const auto j = read_json(dir / "sse2.json");
  EXPECT_EQ(j["embree_isa"], "SSE2");
  EXPECT_THAT(j["embree"].get<std::string>(), ::testing::HasSubstr("SSE2"));
  ASSERT_EQ(j["records"].size(), 2u);
  EXPECT_EQ(j["records"][1]["embree_agreement"], 1.0);
  const auto bad = test::run_shell("RAYLAB_EMBREE_ISA=avx3 " + args + (dir / "bad.json").string() + " 2>&1");
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_THAT(bad.output, ::testing::HasSubstr("RAYLAB_EMBREE_ISA must be sse2, sse4.2, avx, avx2 or avx512, got 'avx3'"));
  EXPECT_FALSE(fs::exists(dir / "bad.json"));
  fs::remove_all(dir);
}

TEST_F(TinyBench, HeaderAndRecordsHaveTheSchema) {
  ASSERT_EQ(exit_code_, 0) << *output_;
  const auto j = read_json(*dir_ / "tiny.json");
  for (const char* key : {"command", "cpu", "embree", "embree_isa", "compiler", "flags", "revision", "date"}) {
    ASSERT_TRUE(j.contains(key)) << key;
    EXPECT_TRUE(j[key].is_string()) << key;
    EXPECT_FALSE(j[key].get<std::string>().empty()) << key;
  }
  EXPECT_EQ(j["command"], "bench");
  EXPECT_THAT(j["embree_isa"].get<std::string>(), ::testing::AnyOf("SSE", "AVX2", "AVX512"));
  ASSERT_TRUE(j["complete"].is_boolean());
  EXPECT_TRUE(j["complete"].get<bool>());
  ASSERT_TRUE(j["options"].is_object());
  ASSERT_TRUE(j["records"].is_array());
  ASSERT_FALSE(j["records"].empty());
  for (const auto& rec : j["records"]) {
    for (const char* key : {"scene", "accel", "ray_set"}) EXPECT_TRUE(rec.at(key).is_string()) << key;
    for (const char* key : {"triangles", "threads", "rays", "bytes"}) EXPECT_TRUE(rec.at(key).is_number_integer()) << key;
    for (const char* key : {"build_ms", "bytes_per_triangle", "mrays_per_s", "mrays_min", "mrays_max",
                            "embree_mrays_per_s", "ratio_to_embree", "embree_agreement"})
      EXPECT_TRUE(rec.at(key).is_number()) << key;
    // Figures that do not apply are null: Embree has no traversal counters
    // and reports no tree shape.
    for (const char* key : {"nodes", "leaves", "max_depth", "nodes_per_ray", "tris_per_ray", "steps_per_ray",
                            "leaves_per_ray", "empty_leaves_per_ray"}) {
      if (rec["accel"] == "embree") EXPECT_TRUE(rec.at(key).is_null()) << key << " " << rec.dump();
      else EXPECT_TRUE(rec.at(key).is_number()) << key << " " << rec.dump();
    }
    ASSERT_TRUE(rec.at("trace_s").is_array());
    EXPECT_EQ(rec["trace_s"].size(), 2u);  // --repeats 2 --min-time 0
    for (const auto& t : rec["trace_s"]) EXPECT_GT(t.get<double>(), 0.0);
    // Embree's repeats, timed in alternation with the structure's.
    ASSERT_TRUE(rec.at("embree_trace_s").is_array());
    EXPECT_EQ(rec["embree_trace_s"].size(), 2u);
    EXPECT_EQ(rec["trace_passes"], 1);  // --min-time 0: one trace per repeat
    EXPECT_TRUE(rec.at("sah_cost").is_number() || rec.at("sah_cost").is_null());
    EXPECT_EQ(rec["triangles"], 300);
    EXPECT_EQ(rec["threads"], 1);
    EXPECT_LE(rec["mrays_min"].get<double>(), rec["mrays_per_s"].get<double>());
    EXPECT_LE(rec["mrays_per_s"].get<double>(), rec["mrays_max"].get<double>());
    EXPECT_NEAR(rec["bytes_per_triangle"].get<double>(), rec["bytes"].get<double>() / 300.0, 1e-9);
    if (rec["accel"] != "embree") {
      EXPECT_GT(rec["nodes_per_ray"].get<double>(), 0.0) << rec.dump();
      EXPECT_GT(rec["bytes"].get<double>(), 0.0) << rec.dump();
    }
  }
}

TEST_F(TinyBench, EveryAcceleratorAndRaySetWithRatiosFromTheSameRun) {
  ASSERT_EQ(exit_code_, 0) << *output_;
  const auto j = read_json(*dir_ / "tiny.json");
  std::set<std::pair<std::string, std::string>> cells;
  std::map<std::string, std::set<double>> embree_speed_per_set;
  for (const auto& rec : j["records"]) {
    const std::string accel = rec["accel"], set = rec["ray_set"];
    EXPECT_TRUE(cells.emplace(accel, set).second) << "duplicate cell " << accel << " " << set;
    const double ratio = rec["ratio_to_embree"], m = rec["mrays_per_s"], e = rec["embree_mrays_per_s"];
    ASSERT_GT(e, 0.0);
    EXPECT_NEAR(ratio, m / e, 1e-12 * std::max(1.0, ratio)) << rec.dump();
    if (accel == "embree") {
      EXPECT_EQ(ratio, 1.0);
      EXPECT_EQ(m, e);
    }
    EXPECT_GT(rec["rays"].get<size_t>(), 0u) << rec.dump();
  }
  for (const char* accel : {"embree", "bvh", "grid"})
    for (const char* set : {"primary", "diffuse", "shadow", "random"})
      EXPECT_TRUE(cells.count({accel, set})) << accel << " " << set;
  EXPECT_EQ(cells.size(), 12u);
  // The same rays for every accelerator: one ray count per ray set.
  std::map<std::string, std::set<size_t>> rays;
  for (const auto& rec : j["records"]) rays[rec["ray_set"]].insert(rec["rays"].get<size_t>());
  for (const auto& [set, counts] : rays) EXPECT_EQ(counts.size(), 1u) << set;
  EXPECT_EQ(*rays["primary"].begin(), 24u * 24u);
  EXPECT_EQ(*rays["random"].begin(), 1500u);
}

TEST_F(TinyBench, CsvNextToTheJsonHasOneRowPerRecord) {
  ASSERT_EQ(exit_code_, 0) << *output_;
  const auto j = read_json(*dir_ / "tiny.json");
  const auto lines = read_lines(*dir_ / "tiny.csv");
  ASSERT_EQ(lines.size(), j["records"].size() + 1);
  EXPECT_EQ(lines[0].rfind("scene,triangles,accel,ray_set,threads,rays,build_ms,bytes,bytes_per_triangle,mrays_per_s,", 0), 0u)
      << lines[0];
  const auto columns = std::count(lines[0].begin(), lines[0].end(), ',');
  for (size_t i = 1; i < lines.size(); ++i) {
    // Scene names hold commas inside quotes ("soup:n=300,seed=1").
    std::string unquoted;
    bool in_quotes = false;
    for (char c : lines[i]) {
      if (c == '"') in_quotes = !in_quotes;
      else if (!in_quotes) unquoted += c;
    }
    EXPECT_EQ(std::count(unquoted.begin(), unquoted.end(), ','), columns) << lines[i];
    EXPECT_EQ(lines[i].rfind("soup:n=300,300,", 0), 0u) << lines[i];
  }
}

TEST_F(TinyBench, PlotScriptWritesThePngs) {
  ASSERT_EQ(exit_code_, 0) << *output_;
  if (std::system("/usr/bin/python3 -c 'import matplotlib' > /dev/null 2>&1") != 0)
    GTEST_SKIP() << "matplotlib not available to /usr/bin/python3";
  const auto charts = *dir_ / "charts";
  const auto table = *dir_ / "summary.md";
  const std::string cmd = std::string("/usr/bin/python3 ") + RAYLAB_SOURCE_DIR + "/bench/plot.py --bench " +
                          (*dir_ / "tiny.json").string() + " --out " + charts.string() + " --table " + table.string() +
                          " > /dev/null 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  for (const char* name : {"speed_vs_accuracy", "build_vs_trace"}) {
    std::ifstream png(charts / (std::string(name) + ".png"), std::ios::binary);
    ASSERT_TRUE(png.good()) << name;
    char magic[8] = {};
    png.read(magic, 8);
    EXPECT_EQ(std::string(magic + 1, 3), "PNG") << name;
    EXPECT_TRUE(fs::exists(charts / (std::string(name) + ".svg"))) << name;
  }
  std::ifstream t(table);
  std::stringstream ss;
  ss << t.rdbuf();
  EXPECT_THAT(ss.str(), HasSubstr("| soup:n=300 | 300 | bvh |"));
}

TEST(Bench, MinTimeRepeatsAShortSetUntilARepeatLastsLongEnough) {
  // 400 random rays on 200 triangles trace in well under a millisecond: with
  // --min-time 0.03 each timed repeat traces the set many times and lasts
  // about 30 ms; trace_s stays the time per trace (Mrays/s unchanged in meaning).
  const auto dir = test::temp_dir("bench_min_time");
  const auto r = test::run_raylab("bench soup:n=200 --accel embree,bvh --ray-sets random --rays 400 --repeats 3 "
                                  "--min-time 0.03 -t 1 -o " + (dir / "b.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_THAT(r.output, ::testing::Not(HasSubstr("warning:")));
  const auto j = read_json(dir / "b.json");
  EXPECT_EQ(j["options"]["min_time_s"], 0.03);
  for (const auto& rec : j["records"]) {
    const int passes = rec["trace_passes"];
    EXPECT_GT(passes, 5) << rec.dump();
    // Calibrated to last min_time (the clock is the thread's CPU time, so a loaded machine does not shorten it).
    EXPECT_GE(rec["shortest_repeat_s"].get<double>(), 0.5 * 0.03) << rec.dump();
    for (const auto& t : rec["trace_s"])
      EXPECT_NEAR(t.get<double>() * passes, rec["shortest_repeat_s"].get<double>(),
                  rec["shortest_repeat_s"].get<double>()) << rec.dump();
    EXPECT_NEAR(rec["mrays_per_s"].get<double>(), 400 / rec["trace_s"][1].get<double>() * 1e-6,
                0.5 * rec["mrays_per_s"].get<double>());
  }
  // The noise floor: Embree's speed over its timings with each structure.
  EXPECT_THAT(r.output, ::testing::ContainsRegex("noise floor: single-ray Embree timed"));
  EXPECT_THAT(r.output, ::testing::ContainsRegex("embree random +t1 +2 timings: .* spread [0-9.]+ %"));
}

TEST(Bench, RepeatsUnderTenMillisecondsAreNamedInAWarning) {
  const auto r = test::run_raylab("bench soup:n=200 --accel embree,bvh --ray-sets random --rays 400 --repeats 2 "
                                  "--min-time 0 -t 1 -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("warning: 2 cells timed in repeats under 10 ms"));
  EXPECT_THAT(r.output, ::testing::ContainsRegex("bvh random t1 \\([0-9.e-]+ ms\\)"));
  EXPECT_THAT(r.output, HasSubstr("raise --min-time"));
}

TEST(Bench, ScaleAndSeveralScenes) {
  const auto [r, j] = test::run_raylab_json("bench_scale", "bench --scale soup:n=100,400 --scene cornell --accel "
                                            "embree,bvh --ray-sets random --rays 500 --repeats 1 --min-time 0 --threads 1 --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::multiset<size_t> tris;
  for (const auto& rec : j["records"]) tris.insert(rec["triangles"].get<size_t>());
  EXPECT_EQ(tris, (std::multiset<size_t>{32, 32, 100, 100, 400, 400}));
  EXPECT_EQ(j["options"]["scenes"], nlohmann::json({"cornell", "soup:n=100", "soup:n=400"}));
}

TEST(Bench, BruteIsSkippedAboveItsTriangleLimit) {
  const auto [r, j] = test::run_raylab_json("bench_brute", "bench --scene soup:n=50 --scene soup:n=200 --accel "
                                            "brute,bvh --ray-sets random --rays 300 --repeats 1 --min-time 0 --threads 1 "
                                            "--brute-max-tris 100");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("brute skipped"));
  std::multiset<std::string> cells;
  for (const auto& rec : j["records"])
    cells.insert(rec["accel"].get<std::string>() + "@" + std::to_string(rec["triangles"].get<int>()));
  EXPECT_EQ(cells, (std::multiset<std::string>{"brute@50", "bvh@50", "bvh@200"}));
}

TEST(Bench, BadPresetsAndOptionsExitWith2) {
  const auto dir = test::temp_dir("bench_bad");
  const auto json = (dir / "x.json").string();
  struct Case {
    std::string args, message;
  };
  const std::vector<Case> cases = {
      {"bench --preset nope -o " + json, "unknown preset 'nope'"},
      {"bench --frobnicate -o " + json, "frobnicate"},
      {"bench --scale soup -o " + json, "expected FAMILY:PARAM=v1,v2"},
      {"bench --scale soup:n= -o " + json, "expected FAMILY:PARAM=v1,v2"},
      {"bench --scale soup:n=1x -o " + json, "not an integer"},
      {"bench --preset quick --repeats 0 --min-time 0 -o " + json, "repeats"},
      {"bench --build-repeats 0 -o " + json, "build-repeats"},
  };
  for (const auto& c : cases) {
    const auto r = test::run_raylab(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr(c.message)) << c.args;
  }
  EXPECT_FALSE(fs::exists(json));
  fs::remove_all(dir);
}

// run_bench hands each record over as soon as its cell is done and stops
// between cells when asked.
TEST(Bench, RecordsArriveOneByOneAndStopEndsTheRunBetweenCells) {
  const Scene scene = load_scene("soup:n=200");
  BenchOptions o;
  o.ray_sets = {"primary", "random"};
  o.width = o.height = 8;
  o.random_rays = 100;
  o.repeats = 1;
  std::atomic<bool> stop{false};
  o.stop = &stop;
  std::vector<std::string> seen;
  const auto records = run_bench(scene, {"embree", "bvh", "grid"}, o, {}, [&](const BenchRecord& r) {
    seen.push_back(r.accel + "/" + r.ray_set);
    if (seen.size() == 3) stop = true;
  });
  EXPECT_EQ(seen, (std::vector<std::string>{"embree/primary", "embree/random", "bvh/primary"}));
  ASSERT_EQ(records.size(), 3u);
  EXPECT_EQ(records[2].accel, "bvh");
}

// Ctrl-C: the process ends with 130 after the cell in progress, and the JSON
// holds the finished records (complete = false).
TEST(Bench, SigintKeepsTheFinishedRecords) {
  const auto dir = test::temp_dir("bench_sigint");
  const auto json = dir / "i.json";
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    const int devnull = ::open("/dev/null", O_WRONLY);
    dup2(devnull, 1);
    dup2(devnull, 2);
    execl(RAYLAB_BINARY, RAYLAB_BINARY, "bench", "--scene", "soup:n=500", "--accel", "embree,bvh,kdtree,grid,hashgrid,grid2",
          "--ray-sets", "primary,random", "--size", "32x32", "--rays", "2000", "--repeats", "200", "--min-time", "0", "--threads", "1",
          "-o", json.c_str(), static_cast<char*>(nullptr));
    _exit(127);
  }
  // Wait for the first finished record, then interrupt.
  bool have_record = false;
  for (int i = 0; i < 600 && !have_record; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (fs::exists(json)) {
      try {
        have_record = !read_json(json)["records"].empty();
      } catch (const std::exception&) {
        ADD_FAILURE() << "half-written JSON";  // the file is replaced atomically
      }
    }
  }
  ASSERT_TRUE(have_record);
  kill(pid, SIGINT);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130);
  const auto j = read_json(json);
  EXPECT_FALSE(j["complete"].get<bool>());
  const size_t n = j["records"].size();
  EXPECT_GE(n, 1u);
  EXPECT_LT(n, 12u);  // stopped before the end
  EXPECT_EQ(read_lines(dir / "i.csv").size(), n + 1);
  fs::remove_all(dir);
}

TEST(Bench, RenderTimingsRecordHasTheTimings) {
  const auto dir = test::temp_dir("render_json");
  const auto r = test::run_raylab("render --scene cornell --spp 1 --size 16x16 --quiet --out " + (dir / "c.pfm").string() +
                                  " --timings " + (dir / "c.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = read_json(dir / "c.json");
  ASSERT_EQ(j["records"].size(), 1u);
  const auto& rec = j["records"][0];
  EXPECT_EQ(rec["spp"], 1);
  EXPECT_EQ(rec["width"], 16);
  EXPECT_EQ(rec["accel"], "bvh");
  EXPECT_GT(rec["wall_s"].get<double>(), 0.0);
  EXPECT_GE(rec["wall_s"].get<double>(), rec["render_s"].get<double>());
  EXPECT_GT(rec["rays"].get<double>(), 0.0);
  EXPECT_EQ(rec["image"], (dir / "c.pfm").string());
  fs::remove_all(dir);
}

}  // namespace
}  // namespace raylab
