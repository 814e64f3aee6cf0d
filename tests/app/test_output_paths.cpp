// Output files go where they are asked and nowhere else: an output in a
// missing directory is bad input (exit 2, a message naming the directory)
// for every command, and nothing is created, neither the directory nor a
// temporary file (`render cornell -o /nonexistent_dir/x.png` exits 2 and
// leaves no /nonexistent_dir). The documented exceptions make only their own
// folder: render's default out/, report's <name>_files/.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <fstream>

#include "tests/test_util.h"

namespace raylab {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;

std::string q(const fs::path& p) { return fmt::format("'{}'", p.string()); }

TEST(OutputPaths, AMissingDirectoryIsAnErrorAndNothingIsCreated) {
  const auto dir = test::temp_dir("out_missing");
  const fs::path missing = dir / "no_such_dir";
  // A bench report to feed compare and report.
  const fs::path run = dir / "run";
  fs::create_directories(run);
  ASSERT_EQ(test::run_raylab("bench soup:n=50 --accel embree --ray-sets random --rays 100 --repeats 2 --min-time 0 -t 1 "
                             "-q -o " + q(run / "bench.json"))
                .exit_code,
            0);
  const std::string b = q(run / "bench.json");
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"render cornell -s 1 --size 8x8 -q -o " + q(missing / "x.png"), "-o"},
      {"render cornell -s 1 --size 8x8 -q -o " + q(dir / "ok.png") + " --timings " + q(missing / "t.json"), "--timings"},
      {"render soup:n=20 --aov tris --size 8x8 -o " + q(missing / "a.png"), "-o"},
      {"verify soup:n=20 --accel bvh --rays 50 -q -o " + q(missing / "v.json"), "-o"},
      {"stress single --accel bvh --ray-scale 0.01 -q -o " + q(missing / "s.json"), "-o"},
      {"bench soup:n=20 --accel embree --ray-sets random --rays 50 --repeats 1 --min-time 0 -t 1 -q -o " + q(missing / "b.json"), "-o"},
      {"bench soup:n=20 --accel embree --ray-sets random --rays 50 --repeats 1 --min-time 0 -t 1 -q --csv " + q(missing / "b.csv"),
       "--csv"},
      {"compare " + b + " " + b + " -o " + q(missing / "c.json"), "-o"},
      {"rays soup:n=20 --ray-sets random --rays 10 -o " + q(missing / "r.rays"), "-o"},
      {"show soup:n=20 --accel bvh --size 8x8 -o " + q(missing / "s.png"), "-o"},
      {"report " + q(run) + " -o " + q(missing / "r.html"), "-o"},
      {"report " + q(run) + " -o " + q(dir / "r.html") + " --md " + q(missing / "r.md"), "--md"},
  };
  for (const auto& [args, option] : cases) {
    const auto r = test::run_raylab(args);
    EXPECT_EQ(r.exit_code, 2) << args << "\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr(option + " ")) << args;
    EXPECT_THAT(r.output, HasSubstr("directory " + missing.string() + " does not exist")) << args;
    EXPECT_FALSE(fs::exists(missing)) << args;
  }
  // Nothing else appeared: not the files of the cases that had a good -o, not a temporary file.
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir)) left.push_back(e.path().filename().string());
  EXPECT_THAT(left, ::testing::UnorderedElementsAre("run")) << "files written before the error";
  // A directory where a file is expected is refused too.
  fs::create_directories(dir / "taken.png");
  const auto d = test::run_raylab("render cornell -s 1 --size 8x8 -q -o " + q(dir / "taken.png"));
  EXPECT_EQ(d.exit_code, 2) << d.output;
  EXPECT_THAT(d.output, HasSubstr("is a directory"));
}

TEST(OutputPaths, RenderMakesItsDefaultFolderAndReportItsChartFolder) {
  const auto dir = test::temp_dir("out_documented");
  const auto r = test::run_raylab_in(dir, "render soup:n=20 -s 1 --size 8x8 -q");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(dir / "out" / "soup_n_20.png")) << r.output;
  ASSERT_EQ(test::run_raylab("bench soup:n=50 --accel embree,bvh --ray-sets random --rays 100 --repeats 2 --min-time 0 "
                             "-t 1 -q -o " + q(dir / "bench.json"))
                .exit_code,
            0);
  const auto p = test::run_raylab("report " + q(dir) + " -o " + q(dir / "page.html"));
  ASSERT_EQ(p.exit_code, 0) << p.output;
  EXPECT_TRUE(fs::exists(dir / "page_files" / "chart-leaderboard-random.svg"));
}

}  // namespace
}  // namespace raylab
