// The label font of the picture commands (app/label_font.h): every printable
// ASCII character draws a glyph of its own. A 5x7 bitmap font without
// descenders draws "g" like "9" ("9rid" for "grid"); a lower-case-only one
// draws capitals as small letters and [ ] # * ? not at all.
#include <gtest/gtest.h>

#include <map>
#include <set>
#include <string>
#include <vector>

#include "app/label_font.h"

namespace raylab::cli {
namespace {

constexpr int kPx = 16;

// The glyph of `text` drawn black on white, as a bitmap of inked pixels.
std::vector<bool> ink_of(const std::string& text, int* rows_inked_below_baseline = nullptr) {
  const int w = text_width(text, kPx) + 4, h = text_height(kPx) + 4;
  Image img(w, h);
  std::fill(img.rgb.begin(), img.rgb.end(), 1.0f);
  draw_text(img, 2, 2, text, Vec3f::Zero(), kPx);
  std::vector<bool> ink(static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) ink[static_cast<size_t>(y) * w + x] = img.pixel(x, y).x() < 0.5f;
  if (rows_inked_below_baseline) {
    // The baseline: the bottom of "x" drawn at the same place.
    Image ref(w, h);
    std::fill(ref.rgb.begin(), ref.rgb.end(), 1.0f);
    draw_text(ref, 2, 2, "x", Vec3f::Zero(), kPx);
    int base = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < ref.width; ++x)
        if (ref.pixel(x, y).x() < 0.5f) base = y;
    int below = 0;
    for (int y = base + 1; y < h; ++y)
      for (int x = 0; x < w; ++x)
        if (ink[static_cast<size_t>(y) * w + x]) {
          ++below;
          break;
        }
    *rows_inked_below_baseline = below;
  }
  return ink;
}

TEST(LabelFont, EveryPrintableCharacterHasItsOwnGlyph) {
  std::map<std::vector<bool>, char> seen;
  for (char c = '!'; c <= '~'; ++c) {
    const auto ink = ink_of(std::string(1, c));
    size_t inked = 0;
    for (bool b : ink) inked += b;
    EXPECT_GT(inked, 0u) << "'" << c << "' draws nothing";
    const auto [it, fresh] = seen.emplace(ink, c);
    EXPECT_TRUE(fresh) << "'" << c << "' draws the same pixels as '" << it->second << "'";
  }
  EXPECT_EQ(text_width(" ", kPx) > 0, true) << "a space advances";
}

TEST(LabelFont, GHasADescenderAndIsNotANine) {
  int g_below = 0, nine_below = 0;
  const auto g = ink_of("g", &g_below);
  const auto nine = ink_of("9", &nine_below);
  EXPECT_NE(g, nine);
  EXPECT_GE(g_below, 2) << "'g' should reach below the baseline";
  EXPECT_EQ(nine_below, 0) << "'9' sits on the baseline";
  EXPECT_NE(ink_of("grid"), ink_of("9rid"));
  EXPECT_NE(ink_of("BVH"), ink_of("bvh")) << "capitals are their own glyphs";
}

TEST(LabelFont, WidthGrowsWithTextAndSizeAndFittingPicksASizeThatFits) {
  EXPECT_LT(text_width("bvh", kPx), text_width("bvh8 node boxes", kPx));
  EXPECT_LT(text_width("kdtree", 10), text_width("kdtree", 20));
  EXPECT_LT(text_height(10), text_height(20));
  const std::string label = "kdtree: k-d split planes, depth 0 to 4";
  const int px = fitting_text_size(label, 160, 8, 16);
  EXPECT_LE(text_width(label, px), 160);
  EXPECT_GE(px, 8);
}

}  // namespace
}  // namespace raylab::cli
