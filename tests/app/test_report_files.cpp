// `raylab report` reads every bench, verify and stress record of a folder,
// sub-folders included, and lists the files on the page: two bench files
// (a_bunny.json, b_sponza.json) give one page over both scenes, not one
// file's scenes with the other dropped. Reports of different binaries or
// machines are refused unless --mix, and then the page says so; a merged
// report's cell files are read once.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <fstream>

#include <nlohmann/json.hpp>

#include "tests/test_util.h"

namespace raylab {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
namespace fs = std::filesystem;

std::string q(const fs::path& p) { return fmt::format("'{}'", p.string()); }
std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}
nlohmann::json load(const fs::path& p) { return nlohmann::json::parse(slurp(p)); }
void save(const fs::path& p, const nlohmann::json& j) { std::ofstream(p) << j.dump(1); }

// One small bench run per scene, into `dir`.
void bench(const fs::path& file, const std::string& scene, const std::string& accel = "embree,bvh") {
  const auto r = test::run_raylab("bench " + scene + " --accel " + accel +
                                  " --ray-sets random --rays 200 --repeats 2 --min-time 0 -t 1 -q -o " + q(file));
  ASSERT_EQ(r.exit_code, 0) << r.output;
}

// `raylab report DIR ARGS -o DIR/page.html`: the page (empty when the command failed, with the failure recorded).
std::string report_page(const fs::path& dir, const std::string& args = "") {
  const auto r = test::run_raylab("report " + q(dir) + args + " -o " + q(dir / "page.html"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  return r.exit_code == 0 ? slurp(dir / "page.html") : std::string();
}

TEST(ReportFiles, EveryBenchFileIsReadAndListed) {
  const auto dir = test::temp_dir("report_files");
  const fs::path run = dir / "run";
  fs::create_directories(run / "more");
  bench(run / "a_bunny.json", "soup:n=100");
  bench(run / "b_sponza.json", "soup:n=300");
  bench(run / "more" / "c_terrain.json", "terrain:n=4");
  ASSERT_EQ(test::run_raylab("verify soup:n=100 --accel bvh --rays 100 -q -o " + q(run / "more" / "v.json")).exit_code, 0);
  const auto r = test::run_raylab("report " + q(run) + " -o " + q(dir / "page.html"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("4 files read"));
  const std::string html = slurp(dir / "page.html");
  // Every scene is on the page, and every file in the list with what it gave.
  for (const char* scene : {"soup:n=100 (100 triangles)", "soup:n=300 (300 triangles)", "terrain:n=4"})
    EXPECT_THAT(html, HasSubstr(scene)) << scene;
  ASSERT_THAT(html, HasSubstr("id=\"table-files\""));
  const std::string files = html.substr(html.find("id=\"table-files\""));
  for (const char* f : {"a_bunny.json", "b_sponza.json", "more/c_terrain.json", "more/v.json"})
    EXPECT_THAT(files, HasSubstr(std::string("<td>") + f + "</td>")) << f;
  EXPECT_THAT(files, HasSubstr("leaderboard"));
  EXPECT_THAT(files, HasSubstr("accuracy"));
  // The leaderboard's mean is over all three scenes.
  EXPECT_THAT(html, HasSubstr("3 of 3"));
}

TEST(ReportFiles, StructuresMeasuredOnFewerScenesAreChartedApart) {
  // brute on one scene of two: its mean is over that scene only, so it is
  // not drawn among the means over both.
  const auto dir = test::temp_dir("report_fewer");
  bench(dir / "a.json", "soup:n=100", "embree,bvh,brute");
  bench(dir / "b.json", "soup:n=300", "embree,bvh");
  const std::string html = report_page(dir);
  auto chart = [&](const std::string& id) {
    const size_t p = html.find("id=\"" + id + "\"");
    return p == std::string::npos ? std::string() : html.substr(p, html.find("</svg>", p) - p);
  };
  const std::string full = chart("chart-leaderboard-random"), fewer = chart("chart-leaderboard-random-fewer-scenes");
  EXPECT_THAT(full, HasSubstr(">bvh<"));
  EXPECT_THAT(full, Not(HasSubstr(">brute<")));
  ASSERT_FALSE(fewer.empty()) << "no chart for the structures measured on fewer scenes";
  EXPECT_THAT(fewer, HasSubstr(">brute<"));
  EXPECT_THAT(fewer, HasSubstr("1 of 2 scenes"));
  EXPECT_THAT(fewer, HasSubstr("does not compare with the chart above"));
  EXPECT_THAT(chart("chart-memory-fewer-scenes"), HasSubstr(">brute<"));
}

TEST(ReportFiles, ACellTimedInTwoFilesIsRefused) {
  const auto dir = test::temp_dir("report_dup");
  bench(dir / "one.json", "soup:n=100");
  bench(dir / "two.json", "soup:n=100");
  const auto r = test::run_raylab("report " + q(dir) + " -o " + q(dir / "page.html"));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_THAT(r.output, HasSubstr("one.json and two.json both time"));
  EXPECT_FALSE(fs::exists(dir / "page.html"));
}

TEST(ReportFiles, OtherBinariesOrMachinesOnlyWithMixAndThePageSaysSo) {
  const auto dir = test::temp_dir("report_mix");
  bench(dir / "a.json", "soup:n=100");
  bench(dir / "b.json", "soup:n=300");
  auto other = load(dir / "b.json");
  other["revision"] = "0123abc-other";
  save(dir / "b.json", other);
  const auto refused = test::run_raylab("report " + q(dir) + " -o " + q(dir / "page.html"));
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_THAT(refused.output, HasSubstr("different binaries"));
  EXPECT_THAT(refused.output, HasSubstr("0123abc-other"));
  EXPECT_THAT(refused.output, HasSubstr("--mix"));
  EXPECT_FALSE(fs::exists(dir / "page.html"));
  const std::string html = report_page(dir, " --mix");
  EXPECT_THAT(html, HasSubstr("id=\"mixed\""));
  EXPECT_THAT(html, HasSubstr("Mixed on request (--mix): 2 binaries"));
  EXPECT_THAT(html, HasSubstr("revision 0123abc-other"));
  EXPECT_THAT(html, HasSubstr("(b.json)"));
  EXPECT_THAT(html, HasSubstr("on one machine"));
  // A different machine is refused as well.
  other["revision"] = load(dir / "a.json")["revision"];
  other["cpu"] = "Some Other CPU";
  save(dir / "b.json", other);
  const auto machine = test::run_raylab("report " + q(dir) + " -o " + q(dir / "page2.html"));
  EXPECT_EQ(machine.exit_code, 2) << machine.output;
  EXPECT_THAT(machine.output, HasSubstr("different machines"));
}

TEST(ReportFiles, MergedCellFilesAreReadOnceThroughTheMergedReport) {
  const auto dir = test::temp_dir("report_merged");
  fs::create_directories(dir / "cells");
  bench(dir / "cells" / "embree.json", "soup:n=100", "embree");
  bench(dir / "cells" / "bvh.json", "soup:n=100", "bvh");
  const auto m = test::run_shell("/usr/bin/python3 " + std::string(RAYLAB_SOURCE_DIR) +
                                 "/workflow/scripts/merge_records.py --out " + q(dir / "bench.json") + " " +
                                 q(dir / "cells" / "embree.json") + " " + q(dir / "cells" / "bvh.json") + " 2>&1");
  ASSERT_EQ(m.exit_code, 0) << m.output;
  // A render record in a sub-folder is listed as not used.
  fs::create_directories(dir / "equal_time");
  ASSERT_EQ(test::run_raylab("render soup:n=20 -s 1 --size 8x8 -q -o " + q(dir / "equal_time" / "r.pfm") + " --timings " +
                             q(dir / "equal_time" / "r.json"))
                .exit_code,
            0);
  const std::string html = report_page(dir);
  EXPECT_THAT(html, HasSubstr("2 files under cells/"));
  EXPECT_THAT(html, HasSubstr("merged into bench.json"));
  EXPECT_THAT(html, HasSubstr("not used (a 'render' report)"));
  EXPECT_THAT(html, HasSubstr("2 bench records at one thread"));
}

}  // namespace
}  // namespace raylab
