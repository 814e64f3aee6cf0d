// `raylab report`: from a tiny bench / verify / stress run plus a cost
// sheet and a structure picture, the page carries every chart and table,
// embeds its pictures as data (no network), says where its numbers come
// from, rejects bad input; and headless Chromium (Debian's package,
// scripts/install-deps.sh) loads it without console messages and renders
// a non-blank screenshot.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <set>

#include <nlohmann/json.hpp>

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

#include "tests/test_util.h"

namespace raylab {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

class ReportPage : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new fs::path(test::temp_dir("report_page"));
    const fs::path d = *dir_ / "run";
    fs::create_directories(d / "heatmaps");  // output directories must exist (raylab creates none)
    fs::create_directories(d / "structures");
    const std::string q = " -q -t 1 ";
    const std::vector<std::string> runs = {
        "bench soup:n=300 --accel embree,bvh,kdtree,grid --ray-sets primary,random --size 16x16 --rays 400 "
        "--repeats 2 --min-time 0" + q + "-o " + (d / "bench.json").string(),
        "verify soup:n=300 --accel bvh,grid --rays 200" + q + "-o " + (d / "verify.json").string(),
        "stress --scenario single --accel bvh,grid" + q + "-o " + (d / "stress.json").string(),
        "render soup:n=300 --accel bvh,grid --aov tris --size 20x20 -o " + (d / "heatmaps" / "soup_tris.png").string(),
        "show soup:n=300 --accel bvh --size 24x24 -o " + (d / "structures" / "bvh.png").string(),
        "bench soup:n=300 --accel grid --sweep density=0.5,2 --ray-sets primary --size 16x16 --repeats 1 --min-time 0" + q +
            "-o " + (d / "sweep_density.json").string(),
        "PLOT",
        "report " + d.string() + " -o " + (*dir_ / "report.html").string(),
    };
    output_ = new std::string;
    for (const auto& args : runs) {
      if (args == "PLOT") {  // bench/plot.py's charts, which the report embeds from run/charts
        const std::string cmd = std::string("/usr/bin/python3 ") + RAYLAB_SOURCE_DIR + "/bench/plot.py --raylab " +
                                RAYLAB_BINARY + " --dir " + d.string() + " --out " + (d / "charts").string() + " > /dev/null";
        plot_exit_ = std::system(cmd.c_str());
        continue;
      }
      const auto r = test::run_raylab(args);
      *output_ += "$ raylab " + args + "\n" + r.output;
      if (r.exit_code != 0) {
        exit_code_ = r.exit_code;
        return;
      }
    }
    exit_code_ = 0;
  }
  static void TearDownTestSuite() {
    fs::remove_all(*dir_);
    delete dir_;
    delete output_;
  }
  static fs::path* dir_;
  static int exit_code_, plot_exit_;
  static std::string* output_;
};
int ReportPage::plot_exit_ = -1;
fs::path* ReportPage::dir_ = nullptr;
int ReportPage::exit_code_ = -1;
std::string* ReportPage::output_ = nullptr;

// One test (the tiny run behind it is set up once per process, and ctest runs
// every test in its own process): the page, plot.py's charts, the browser.
TEST_F(ReportPage, ChartsTablesPlotsAndHeadlessChromium) {
  {  // every chart and table is present
  ASSERT_EQ(exit_code_, 0) << *output_;
  const std::string html = slurp(*dir_ / "report.html");
  for (const char* id : {"chart-leaderboard-primary", "chart-leaderboard-random", "table-leaderboard-primary",
                         "chart-memory", "chart-build", "table-memory", "table-accuracy", "table-stress",
                         "chart-nodes-per-ray", "chart-tris-per-ray", "table-why", "provenance"})
    EXPECT_THAT(html, HasSubstr(std::string("id=\"") + id + "\"")) << id;
  // Every structure of the run is on the leaderboard, in its own colour.
  for (const char* accel : {">embree<", ">bvh<", ">kdtree<", ">grid<"}) EXPECT_THAT(html, HasSubstr(accel));
  EXPECT_THAT(html, HasSubstr("fill=\"#1f77b4\""));  // bvh's colour (app/cmd_report_palette.h)
  EXPECT_THAT(html, HasSubstr("fill=\"#d62728\""));  // kdtree's
  // The pictures are embedded, nothing is fetched.
  size_t images = 0;
  for (size_t p = 0; (p = html.find("src=\"data:image/png;base64,", p)) != std::string::npos; ++p) ++images;
  EXPECT_EQ(images, 2u);  // the cost sheet and the structure picture
  EXPECT_THAT(html, Not(HasSubstr("src=\"http")));
  EXPECT_THAT(html, Not(HasSubstr("href=\"http")));
  EXPECT_THAT(html, Not(HasSubstr("<script")));
  // The footer carries the binary's revision and the machine, as the bench report says.
  const auto bench = nlohmann::json::parse(slurp(*dir_ / "run" / "bench.json"));
  EXPECT_THAT(html, HasSubstr(bench["revision"].get<std::string>()));
  EXPECT_THAT(html, HasSubstr(bench["embree_version"].get<std::string>()));
  // Bars grow from zero on linear axes: every bar of the report's own charts
  // starts at the axis (x = 190), none on a log scale; no column repeats
  // another (no other Embree mode ran, so no "ratio to best Embree mode");
  // honest labels; no placeholder in the footer.
  for (size_t p = 0; (p = html.find("<svg xmlns=\"http://www.w3.org/2000/svg\" id=\"chart-", p)) != std::string::npos; ++p) {
    const std::string svg = html.substr(p, html.find("</svg>", p) - p);
    EXPECT_THAT(svg, Not(HasSubstr("log scale"))) << svg.substr(0, 120);
    for (size_t q = 0; (q = svg.find("<rect x=\"", q)) != std::string::npos; ++q) {
      const std::string x = svg.substr(q + 9, svg.find('"', q + 9) - q - 9);
      EXPECT_EQ(x, "190.0") << svg.substr(q, 120);
    }
  }
  EXPECT_THAT(html, Not(HasSubstr("ratio to best Embree mode")));
  EXPECT_THAT(html, HasSubstr("max relative distance difference from Embree"));
  EXPECT_THAT(html, Not(HasSubstr("max relative distance error")));
  const std::string footer = html.substr(html.find("<footer"));
  EXPECT_THAT(footer, Not(HasSubstr("unknown")));
  EXPECT_THAT(footer, Not(HasSubstr("?")));
  EXPECT_THAT(footer, HasSubstr("Machine: "));
  // The files it read, listed.
  EXPECT_THAT(html, HasSubstr("id=\"table-files\""));
  for (const char* f : {"<td>bench.json</td>", "<td>verify.json</td>", "<td>stress.json</td>", "<td>sweep_density.json</td>"})
    EXPECT_THAT(html, HasSubstr(f)) << f;
  // The Markdown version with its headline block and chart files.
  const std::string md = slurp(*dir_ / "report.md");
  EXPECT_THAT(md, HasSubstr("<!-- headline:begin -->"));
  EXPECT_THAT(md, HasSubstr("<!-- headline:end -->"));
  EXPECT_THAT(md, HasSubstr("| bvh |"));
  EXPECT_TRUE(fs::exists(*dir_ / "report_files" / "chart-leaderboard-primary.svg"));
  }
  {  // plot.py: one chart per swept parameter, and speed against memory
  ASSERT_EQ(exit_code_, 0) << *output_;
  ASSERT_EQ(plot_exit_, 0);
  const fs::path charts = *dir_ / "run" / "charts";
  for (const char* name : {"speed_vs_accuracy", "build_vs_trace", "speed_vs_memory", "sweep_density"}) {
    EXPECT_TRUE(fs::exists(charts / (std::string(name) + ".png"))) << name;
    EXPECT_TRUE(fs::exists(charts / (std::string(name) + ".svg"))) << name;
  }
  // No sweep chart for a parameter nobody swept.
  EXPECT_FALSE(fs::exists(charts / "sweep_leaf.png"));
  // The report embeds every plot.py chart inline.
  const std::string html = slurp(*dir_ / "report.html");
  size_t plots = 0;
  for (size_t p = 0; (p = html.find("<figure class=\"plot\"><svg", p)) != std::string::npos; ++p) ++plots;
  EXPECT_EQ(plots, 4u);
  }
  {  // headless Chromium loads the page without console messages; the screenshot is not blank
  ASSERT_EQ(exit_code_, 0) << *output_;
  ASSERT_EQ(std::system("command -v chromium > /dev/null 2>&1"), 0)
      << "chromium is missing: run scripts/install-deps.sh (Debian package chromium)";
  const fs::path shot = *dir_ / "shot.png", log = *dir_ / "chromium.log";
  const std::string cmd = "timeout 120 chromium --headless --no-sandbox --disable-gpu --no-first-run "
                          "--user-data-dir=" + (*dir_ / "profile").string() +
                          " --enable-logging=stderr --v=0 --window-size=1000,2400 --screenshot=" + shot.string() +
                          " file://" + (*dir_ / "report.html").string() + " > " + log.string() + " 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << slurp(log);
  const std::string messages = slurp(log);
  EXPECT_THAT(messages, Not(HasSubstr(":CONSOLE"))) << messages;
  int w = 0, h = 0, n = 0;
  unsigned char* px = stbi_load(shot.string().c_str(), &w, &h, &n, 3);
  ASSERT_NE(px, nullptr) << "screenshot not readable";
  EXPECT_EQ(w, 1000);
  // Non-blank: many pixels differ from the white background, and the bar colours are there.
  size_t inked = 0;
  std::set<uint32_t> colours;
  for (int i = 0; i < w * h; ++i) {
    const unsigned char* p = px + 3 * i;
    inked += p[0] < 200 || p[1] < 200 || p[2] < 200;
    colours.insert((uint32_t(p[0]) << 16) | (uint32_t(p[1]) << 8) | p[2]);
  }
  stbi_image_free(px);
  EXPECT_GT(inked, static_cast<size_t>(w * h / 100)) << "screenshot looks blank";
  EXPECT_GT(colours.size(), 20u);
  EXPECT_TRUE(colours.count(0x1f77b4)) << "bvh's bar colour not on screen";
  }
}

TEST(ReportInput, BadInputIsRejected) {
  const auto dir = test::temp_dir("report_bad");
  const auto none = test::run_raylab("report " + (dir / "missing").string() + " -o " + (dir / "r.html").string());
  EXPECT_EQ(none.exit_code, 2);
  EXPECT_THAT(none.output, HasSubstr("not a directory"));
  const auto empty = test::run_raylab("report " + dir.string() + " -o " + (dir / "r.html").string());
  EXPECT_EQ(empty.exit_code, 2);
  EXPECT_THAT(empty.output, HasSubstr("no bench report"));
  std::ofstream(dir / "broken.json") << "{\"records\": [";
  const auto broken = test::run_raylab("report " + dir.string() + " -o " + (dir / "r.html").string());
  EXPECT_EQ(broken.exit_code, 2);
  EXPECT_THAT(broken.output, HasSubstr("broken.json"));
  const auto ext = test::run_raylab("report " + dir.string() + " -o " + (dir / "r.txt").string());
  EXPECT_EQ(ext.exit_code, 2);
  EXPECT_THAT(ext.output, HasSubstr(".html"));
  EXPECT_FALSE(fs::exists(dir / "r.html"));
  EXPECT_FALSE(fs::exists(dir / "r.md"));
}

}  // namespace
}  // namespace raylab
