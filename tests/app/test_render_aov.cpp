// `raylab render --aov`: per-pixel cost pictures. Brute force tests every
// triangle for every ray, so its triangle-test picture is known exactly;
// a BVH must do far less; the PNG carries a legend band below the image;
// a contact sheet writes one raw PFM per structure on one shared scale.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <map>

#include "tests/test_util.h"
#include "tracer/image.h"

namespace raylab {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;

// Width and height from a PNG's IHDR chunk.
std::pair<uint32_t, uint32_t> png_size(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  unsigned char b[24] = {};
  in.read(reinterpret_cast<char*>(b), 24);
  if (std::string(reinterpret_cast<char*>(b), 8) != std::string("\x89PNG\r\n\x1a\n", 8)) return {0, 0};
  auto be = [&](int o) { return (uint32_t(b[o]) << 24) | (uint32_t(b[o + 1]) << 16) | (uint32_t(b[o + 2]) << 8) | b[o + 3]; };
  return {be(16), be(20)};
}

double mean_red(const Image& img) {
  double s = 0.0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) s += img.pixel(x, y).x();
  return s / (img.width * img.height);
}

TEST(RenderAov, BruteTestsEveryTriangleAndBvhFarFewer) {
  const auto dir = test::temp_dir("aov_one");
  const auto r = test::run_raylab("render soup:n=200 --accel brute --aov tris --size 32x24 -t 1 -o " + (dir / "b.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const Image raw = read_pfm((dir / "b.pfm").string());
  ASSERT_EQ(raw.width, 32);
  ASSERT_EQ(raw.height, 24);
  for (int y = 0; y < raw.height; ++y)
    for (int x = 0; x < raw.width; ++x) ASSERT_EQ(raw.pixel(x, y).x(), 200.0f) << x << "," << y;
  const auto [w, h] = png_size(dir / "b.png");
  EXPECT_EQ(w, 32u);
  EXPECT_GT(h, 24u + 20u);  // the legend band below the picture

  const auto v = test::run_raylab("render soup:n=200 --accel bvh --aov tris --size 32x24 -o " + (dir / "v.pfm").string());
  ASSERT_EQ(v.exit_code, 0) << v.output;
  EXPECT_FALSE(fs::exists(dir / "v.png"));  // .pfm: raw values only
  const double bvh_mean = mean_red(read_pfm((dir / "v.pfm").string()));
  EXPECT_GT(bvh_mean, 0.0);
  EXPECT_LT(bvh_mean, 100.0);
}

TEST(RenderAov, ContactSheetOverSeveralStructures) {
  const auto dir = test::temp_dir("aov_sheet");
  const auto r = test::run_raylab("render soup:n=100 --accel embree,brute,kdtree,grid --aov nodes --size 24x16 -o " +
                                  (dir / "s.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("embree has no per-ray counters"));
  EXPECT_FALSE(fs::exists(dir / "s.embree.pfm"));
  for (const std::string name : {"brute", "kdtree", "grid"}) {
    const Image raw = read_pfm((dir / ("s." + name + ".pfm")).string());
    EXPECT_EQ(raw.width, 24) << name;
    if (name == "brute") EXPECT_EQ(mean_red(raw), 0.0);  // one leaf, no nodes to visit
    else EXPECT_GT(mean_red(raw), 0.0) << name;
  }
  const auto [w, h] = png_size(dir / "s.png");
  EXPECT_GT(w, 2u * 24u);  // 2 x 2 tiles
  EXPECT_GT(h, 2u * 16u);

  const auto t = test::run_raylab("render soup:n=100 --accel embree,bvh --aov time --size 16x8 -o " + (dir / "t.png").string());
  ASSERT_EQ(t.exit_code, 0) << t.output;
  const Image te = read_pfm((dir / "t.embree.pfm").string());
  for (int x = 0; x < te.width; ++x) EXPECT_GT(te.pixel(x, 0).x(), 0.0f);
}

TEST(RenderAov, ASheetSharesALogScaleUnlessEachTileGetsItsOwn) {
  // One structure's costs (brute tests all 300 triangles per ray) would
  // saturate a shared linear scale for the others: a sheet defaults to one
  // log scale, and --aov-scale each gives every tile its own.
  const auto dir = test::temp_dir("aov_scale");
  std::map<std::string, std::string> png;  // scale option -> the sheet's bytes
  for (const auto& [option, says] : std::vector<std::pair<std::string, std::string>>{
           {"", "(colours: one log scale, 0 to 300)"},
           {"--aov-scale each", "(colours: each tile its own linear scale)"},
           {"--aov-scale linear", "(colours: one linear scale, 0 to 300)"}}) {
    const fs::path out = dir / ("sheet" + std::to_string(png.size()) + ".png");
    const auto r = test::run_raylab("render soup:n=300 --accel brute,bvh --aov tris --size 24x16 " + option + " -o " +
                                    out.string());
    ASSERT_EQ(r.exit_code, 0) << option << "\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr(says)) << option;
    std::ifstream in(out, std::ios::binary);
    png[option] = std::string(std::istreambuf_iterator<char>(in), {});
  }
  EXPECT_NE(png[""], png["--aov-scale each"]);
  EXPECT_NE(png[""], png["--aov-scale linear"]);
  for (const auto& [args, message] : std::vector<std::pair<std::string, std::string>>{
           {"render soup:n=30 --accel bvh --aov tris --aov-scale wide -o " + (dir / "x.png").string(),
            "use auto, log, linear or each"},
           {"render soup:n=30 --aov-scale log -o " + (dir / "y.png").string(), "--aov pictures only"}}) {
    const auto r = test::run_raylab(args);
    EXPECT_EQ(r.exit_code, 2) << args;
    EXPECT_THAT(r.output, HasSubstr(message)) << args;
  }
}

TEST(RenderAov, BadInput) {
  const auto dir = test::temp_dir("aov_bad");
  const auto a = test::run_raylab("render soup:n=10 --aov depth -o " + (dir / "a.png").string());
  EXPECT_EQ(a.exit_code, 2);
  EXPECT_THAT(a.output, HasSubstr("use nodes, tris or time"));
  const auto b = test::run_raylab("render soup:n=10 --aov tris -o " + (dir / "a.exr").string());
  EXPECT_EQ(b.exit_code, 2);
  EXPECT_THAT(b.output, HasSubstr("--aov writes a .png"));
  EXPECT_TRUE(fs::is_empty(dir));
}

}  // namespace
}  // namespace raylab
