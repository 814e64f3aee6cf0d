#pragma once
// Text for the picture commands (`raylab show`, `raylab render --aov`
// legends and titles): DejaVu Sans (Debian's fonts-dejavu-core, embedded in
// the binary at build time) rasterised by FreeType, so every printable
// character has its own glyph (a 5x7 bitmap font without descenders cannot
// tell "g" from "9") and labels keep their proportions at any size.
#include <string>

#include "base/vec.h"
#include "tracer/image.h"

namespace raylab::cli {

// Draws `text` with its line box's top-left corner at (x, y), `px` pixels
// tall (the font's em size), blended by coverage in sRGB (as the PNG is
// viewed) over what `img` holds. Clipped to the image.
void draw_text(Image& img, int x, int y, const std::string& text, const Vec3f& colour, int px);

// Advance width of `text` at `px` pixels, as draw_text lays it out.
int text_width(const std::string& text, int px);

// Height of draw_text's line box at `px` pixels (ascender to descender).
int text_height(int px);

// The largest size in [min_px, max_px] at which `text` fits in `width`
// pixels (min_px when none does).
int fitting_text_size(const std::string& text, int width, int min_px, int max_px);

}  // namespace raylab::cli
