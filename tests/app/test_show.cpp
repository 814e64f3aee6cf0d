// `raylab show`: wireframes whose element counts match the structure's
// outline, an overlay that actually draws coloured lines over the grey
// shading, and bad input rejected before anything is written.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <regex>

#define STB_IMAGE_STATIC
#define STB_IMAGE_IMPLEMENTATION
#include <stb/stb_image.h>

#include "tests/test_util.h"
#include "tracer/image.h"

namespace raylab {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// "N boxes, M planes" from show's summary line.
std::pair<long, long> counts(const std::string& output) {
  std::smatch m;
  const std::regex re("([0-9]+) boxes, ([0-9]+) planes");
  if (!std::regex_search(output, m, re)) return {-1, -1};
  return {std::stol(m[1]), std::stol(m[2])};
}

long header_count(const std::string& ply, const std::string& element) {
  std::smatch m;
  const std::regex re("element " + element + " ([0-9]+)");
  return std::regex_search(ply, m, re) ? std::stol(m[1]) : -1;
}

// Pixels whose colour is clearly not grey: the drawn structure lines.
size_t coloured_pixels(const Image& img) {
  size_t n = 0;
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x) {
      const Vec3f c = img.pixel(x, y);
      n += c.maxCoeff() - c.minCoeff() > 0.15f;
    }
  return n;
}

TEST(Show, BvhWireframeAndOverlay) {
  const auto dir = test::temp_dir("show_bvh");
  const auto r = test::run_raylab("show soup:n=200 --accel bvh:layout=bvh2 --depth 3 --size 64x48 -o " +
                                  (dir / "b.ply").string() + " -o " + (dir / "b.obj").string() + " -o " +
                                  (dir / "b.pfm").string() + " -o " + (dir / "b.png").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto [boxes, planes] = counts(r.output);
  // A binary tree down to depth 3 over 200 triangles: 1 + 2 + 4 + 8 boxes.
  EXPECT_EQ(boxes, 15) << r.output;
  EXPECT_EQ(planes, 0);
  const std::string ply = slurp(dir / "b.ply");
  EXPECT_EQ(ply.rfind("ply\nformat ascii 1.0\n", 0), 0u);
  EXPECT_EQ(header_count(ply, "vertex"), 8 * boxes);
  EXPECT_EQ(header_count(ply, "edge"), 12 * boxes);
  const std::string obj = slurp(dir / "b.obj");
  size_t lines = 0, verts = 0;
  for (size_t p = 0; (p = obj.find("\nl ", p)) != std::string::npos; ++p) ++lines;
  for (size_t p = 0; (p = obj.find("\nv ", p)) != std::string::npos; ++p) ++verts;
  EXPECT_EQ(static_cast<long>(lines), 12 * boxes);
  EXPECT_EQ(static_cast<long>(verts), 8 * boxes);
  EXPECT_EQ(slurp(dir / "b.png").substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
  const Image overlay = read_pfm((dir / "b.pfm").string());
  EXPECT_EQ(overlay.width, 64);
  EXPECT_EQ(overlay.height, 48);
  EXPECT_GT(coloured_pixels(overlay), 50u);
}

TEST(Show, EveryStructureHasAPicture) {
  const auto dir = test::temp_dir("show_all");
  for (const std::string accel : {"kdtree", "grid", "hashgrid", "grid2", "brute", "embree", "bvh"}) {
    const fs::path ply = dir / (accel + ".ply");
    const auto r = test::run_raylab("show soup:n=100 --accel " + accel + " --depth 2 --size 32x32 -o " + ply.string() +
                                    " -o " + (dir / (accel + ".pfm")).string());
    ASSERT_EQ(r.exit_code, 0) << accel << "\n" << r.output;
    const auto [boxes, planes] = counts(r.output);
    EXPECT_GE(boxes + planes, 1) << accel;
    EXPECT_GT(header_count(slurp(ply), "edge"), 0) << accel;
    if (accel == "kdtree") {
      EXPECT_GT(planes, 1) << r.output;
    }
    if (accel == "embree") {
      EXPECT_THAT(r.output, HasSubstr("does not expose its structure"));
    }
    EXPECT_GT(coloured_pixels(read_pfm((dir / (accel + ".pfm")).string())), 0u) << accel;
  }
}

TEST(Show, ThePngHasATitleAndADepthLegendAtAReadableDefaultSize) {
  // The PNG reads at its default size: a title that fits (not cut to "k-d sp"),
  // a legend for the depth colours, and depth 4 by default, as the docs use.
  const auto dir = test::temp_dir("show_legend");
  const auto r = test::run_raylab("show soup:n=200 --accel kdtree -o " + (dir / "k.png").string() + " -o " +
                                  (dir / "k.pfm").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_THAT(r.output, HasSubstr("(depth <= 4)"));
  const Image overlay = read_pfm((dir / "k.pfm").string());
  EXPECT_GE(overlay.width, 480);
  int w = 0, h = 0, n = 0;
  unsigned char* px = stbi_load((dir / "k.png").string().c_str(), &w, &h, &n, 3);
  ASSERT_NE(px, nullptr);
  EXPECT_EQ(w, overlay.width);
  EXPECT_GT(h, overlay.height + 30) << "the title above and the legend below";
  // The legend band below the overlay holds the depth colours: yellow (depth 0) to blue (deepest).
  const int band = h - 30;
  bool yellow = false, blue = false;
  for (int y = band; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const unsigned char* p = px + 3 * (static_cast<size_t>(y) * w + x);
      yellow |= p[0] > 200 && p[1] > 180 && p[2] < 120;
      blue |= p[2] > 200 && p[0] < 120;
    }
  stbi_image_free(px);
  EXPECT_TRUE(yellow) << "no depth-0 swatch";
  EXPECT_TRUE(blue) << "no deepest-level swatch";
}

TEST(Show, BadInputIsRejectedBeforeWriting) {
  const auto dir = test::temp_dir("show_bad");
  const std::string out = (dir / "x.ply").string();
  struct Case {
    std::string args, message;
  };
  const std::vector<Case> cases = {
      {"show soup:n=10 --accel bvh -o " + (dir / "x.txt").string(), "use a .png or .pfm"},
      {"show soup:n=10 --accel no_such_accel -o " + out, "unknown accelerator"},
      {"show soup:n=10 --accel all -o " + out, "one accelerator"},
      {"show soup:n=10 --accel bvh --depth -1 -o " + out, "depth"},
      {"show no_such_scene_file.ply --accel bvh -o " + out, "no_such_scene_file"},
      {"show soup:n=10 --accel bvh", "--out"},
      {"show soup:n=10 --accel bvh -o " + (dir / "missing" / "x.png").string(), "does not exist"},
  };
  for (const auto& c : cases) {
    const auto r = test::run_raylab(c.args);
    EXPECT_EQ(r.exit_code, 2) << c.args << "\n" << r.output;
    EXPECT_THAT(r.output, HasSubstr(c.message)) << c.args;
    EXPECT_FALSE(fs::exists(out)) << c.args;
  }
  EXPECT_TRUE(fs::is_empty(dir));
}

}  // namespace
}  // namespace raylab
