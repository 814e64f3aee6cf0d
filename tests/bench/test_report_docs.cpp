// docs/json-reports.md lists every key the JSON reports carry and every
// `extra` statistic the accelerators report, and every report says which
// schema version it follows.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <regex>
#include <set>

#include <nlohmann/json.hpp>

#include "accel/registry.h"
#include "bench/report.h"
#include "scenes/scene_registry.h"
#include "tests/report_test_util.h"
#include "tests/test_util.h"

namespace raylab {
namespace {

namespace fs = std::filesystem;
using test::read_json;
using test::read_lines;

std::set<std::string> documented_keys() {
  std::ifstream in(std::string(RAYLAB_SOURCE_DIR) + "/docs/json-reports.md");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::set<std::string> keys;
  static const std::regex code("`([a-z_0-9]+)`");
  for (auto it = std::sregex_iterator(text.begin(), text.end(), code); it != std::sregex_iterator(); ++it)
    keys.insert((*it)[1].str());
  return keys;
}

TEST(ReportDocs, EveryReportHasTheSchemaVersionAndEveryKeyIsDocumented) {
  const auto docs = documented_keys();
  ASSERT_GT(docs.size(), 50u) << "docs/json-reports.md missing or empty";
  const auto dir = test::temp_dir("report_docs");
  const std::map<std::string, std::string> runs = {
      {"render", "render soup:n=50 -s 1 --size 8x8 -q -o " + (dir / "r.png").string() + " --timings " + (dir / "render.json").string()},
      {"verify", "verify soup:n=50 --accel bvh --rays 64 -q -o " + (dir / "verify.json").string()},
      {"stress", "stress --scenario single --accel bvh -q -o " + (dir / "stress.json").string()},
      {"bench", "bench soup:n=50 --accel embree,bvh --ray-sets random --rays 64 --repeats 2 --min-time 0 -t 1 -q -o " +
                    (dir / "bench.json").string()},
  };
  for (const auto& [command, args] : runs) {
    const auto r = test::run_raylab(args);
    ASSERT_EQ(r.exit_code, 0) << args << "\n" << r.output;
    const auto j = read_json(dir / (command + ".json"));
    EXPECT_EQ(j.at("schema_version"), kReportSchemaVersion) << command;
    EXPECT_EQ(j.at("command"), command);
    for (const auto& [key, value] : j.items()) EXPECT_TRUE(docs.count(key)) << command << " header key '" << key << "'";
    ASSERT_FALSE(j["records"].empty()) << command;
    for (const auto& rec : j["records"])
      for (const auto& [key, value] : rec.items())
        EXPECT_TRUE(docs.count(key)) << command << " record key '" << key << "' is not in docs/json-reports.md";
  }
  // compare's own report.
  const auto c = test::run_raylab("compare " + (dir / "bench.json").string() + " " + (dir / "bench.json").string() + " -o -");
  ASSERT_EQ(c.exit_code, 0) << c.output;
  const auto cj = nlohmann::json::parse(c.output);
  EXPECT_EQ(cj.at("schema_version"), kReportSchemaVersion);
  for (const auto& [key, value] : cj.items()) EXPECT_TRUE(docs.count(key)) << "compare key '" << key << "'";
  for (const auto& [key, value] : cj["cells"][0].items()) EXPECT_TRUE(docs.count(key)) << "compare cell key '" << key << "'";
}

TEST(ReportDocs, EveryExtraStatisticIsDocumented) {
  const auto docs = documented_keys();
  const Scene scene = load_scene("soup:n=400");
  // Every family, plus the variants that add statistics of their own.
  std::vector<std::string> specs = expand_accelerator_list("all");
  for (const char* s : {"bvh:builder=sbvh", "bvh:preset=quality", "bvh:layout=bvh2", "bvh:layout=bvh4",
                        "kdtree:builder=median", "embree:robust=1"})
    specs.push_back(s);
  size_t seen = 0;
  for (const auto& spec : specs) {
    auto accel = make_accelerator(spec);
    const BuildStats st = accel->build(scene.mesh);
    for (const auto& [key, value] : st.extra) {
      ++seen;
      EXPECT_TRUE(docs.count(key)) << spec << ": extra statistic '" << key << "' is not in docs/json-reports.md";
    }
  }
  EXPECT_GT(seen, 30u);
  // And every statistic key the registry declares (with its help text).
  for (const auto& info : accelerator_registry())
    for (const auto& st : info.stats)
      EXPECT_TRUE(docs.count(st.key)) << info.name << ": declared statistic '" << st.key << "' is not in docs/json-reports.md";
}

}  // namespace
}  // namespace raylab
