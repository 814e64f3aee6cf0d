#include "app/label_font.h"

#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>

#include <ft2build.h>
#include FT_FREETYPE_H

// The font file's bytes, embedded at build time (CMakeLists.txt finds
// DejaVuSans.ttf and passes its path): the binary draws the same labels
// wherever it runs, font package or not.
#ifndef RAYLAB_LABEL_FONT_PATH
#error "RAYLAB_LABEL_FONT_PATH (DejaVuSans.ttf) must be defined by the build"
#endif
asm(".section .rodata\n"
    ".balign 16\n"
    ".global raylab_label_font_begin\n"
    ".hidden raylab_label_font_begin\n"
    "raylab_label_font_begin:\n"
    ".incbin \"" RAYLAB_LABEL_FONT_PATH "\"\n"
    ".global raylab_label_font_end\n"
    ".hidden raylab_label_font_end\n"
    "raylab_label_font_end:\n"
    ".previous\n");
extern "C" const unsigned char raylab_label_font_begin[];
extern "C" const unsigned char raylab_label_font_end[];

namespace raylab::cli {

namespace {

// One FreeType face for the process; FreeType faces are not thread-safe, so
// every use holds the lock.
class Face {
 public:
  static Face& get() {
    static Face face;
    return face;
  }
  std::mutex& lock() { return mutex_; }
  FT_Face at(int px) {
    if (px != size_) {
      FT_Set_Pixel_Sizes(face_, 0, static_cast<FT_UInt>(std::max(1, px)));
      size_ = px;
    }
    return face_;
  }

 private:
  Face() {
    if (FT_Init_FreeType(&library_) != 0) throw std::runtime_error("FreeType: cannot initialise");
    const auto bytes = static_cast<FT_Long>(raylab_label_font_end - raylab_label_font_begin);
    if (FT_New_Memory_Face(library_, raylab_label_font_begin, bytes, 0, &face_) != 0)
      throw std::runtime_error("FreeType: the embedded label font does not load");
  }
  FT_Library library_ = nullptr;
  FT_Face face_ = nullptr;
  int size_ = 0;
  std::mutex mutex_;
};

float to_srgb(float v) {
  v = std::clamp(v, 0.0f, 1.0f);
  return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}
float to_linear(float s) { return s <= 0.04045f ? s / 12.92f : std::pow((s + 0.055f) / 1.055f, 2.4f); }

int ascender(FT_Face f) { return static_cast<int>(f->size->metrics.ascender >> 6); }
int descender(FT_Face f) { return static_cast<int>(-(f->size->metrics.descender >> 6)); }

// Lays `text` out glyph by glyph (kerning included): loads each glyph with
// `load_flags` and calls at(glyph slot, pen x from the start); returns the
// advance width. draw_text and text_width share it, so widths match drawings.
template <class At>
int lay_out(FT_Face f, const std::string& text, FT_Int32 load_flags, At&& at) {
  int pen = 0;
  FT_UInt previous = 0;
  for (unsigned char ch : text) {
    const FT_UInt glyph = FT_Get_Char_Index(f, ch);
    if (previous && glyph && FT_HAS_KERNING(f)) {
      FT_Vector k;
      FT_Get_Kerning(f, previous, glyph, FT_KERNING_DEFAULT, &k);
      pen += static_cast<int>(k.x >> 6);
    }
    previous = glyph;
    if (FT_Load_Glyph(f, glyph, load_flags) != 0) continue;
    at(f->glyph, pen);
    pen += static_cast<int>(f->glyph->advance.x >> 6);
  }
  return pen;
}

}  // namespace

void draw_text(Image& img, int x, int y, const std::string& text, const Vec3f& colour, int px) {
  Face& face = Face::get();
  std::lock_guard<std::mutex> guard(face.lock());
  FT_Face f = face.at(px);
  const int baseline = y + ascender(f);
  lay_out(f, text, FT_LOAD_RENDER, [&](FT_GlyphSlot g, int pen) {
    const FT_Bitmap& bm = g->bitmap;
    const int left = x + pen + g->bitmap_left, top = baseline - g->bitmap_top;
    for (unsigned row = 0; row < bm.rows; ++row)
      for (unsigned col = 0; col < bm.width; ++col) {
        const int px_x = left + static_cast<int>(col), px_y = top + static_cast<int>(row);
        if (px_x < 0 || px_y < 0 || px_x >= img.width || px_y >= img.height) continue;
        const float a = bm.buffer[row * bm.pitch + col] / 255.0f;
        if (a <= 0.0f) continue;
        const Vec3f under = img.pixel(px_x, px_y);
        Vec3f out;
        for (int c = 0; c < 3; ++c) out[c] = to_linear((1.0f - a) * to_srgb(under[c]) + a * to_srgb(colour[c]));
        img.set(px_x, px_y, out);
      }
  });
}

int text_width(const std::string& text, int px) {
  Face& face = Face::get();
  std::lock_guard<std::mutex> guard(face.lock());
  return lay_out(face.at(px), text, FT_LOAD_DEFAULT, [](FT_GlyphSlot, int) {});
}

int text_height(int px) {
  Face& face = Face::get();
  std::lock_guard<std::mutex> guard(face.lock());
  FT_Face f = face.at(px);
  return ascender(f) + descender(f);
}

int fitting_text_size(const std::string& text, int width, int min_px, int max_px) {
  for (int px = max_px; px > min_px; --px)
    if (text_width(text, px) <= width) return px;
  return min_px;
}

}  // namespace raylab::cli
