#pragma once
// Linear RGB float image and its outputs: 8-bit sRGB PNG (stb_image_write),
// linear float OpenEXR (tinyexr) and PFM (float, for numerical comparison).
// All written atomically.
#include <cstdint>
#include <string>
#include <vector>

#include "accel/core/vec.h"

namespace raylab {

struct Image {
  int width = 0, height = 0;
  std::vector<float> rgb;  // row-major from the top row, 3 floats per pixel

  Image() = default;
  Image(int w, int h) : width(w), height(h), rgb(static_cast<size_t>(w) * h * 3, 0.0f) {}

  Vec3f pixel(int x, int y) const {
    const size_t i = 3 * (static_cast<size_t>(y) * width + x);
    return Vec3f(rgb[i], rgb[i + 1], rgb[i + 2]);
  }
  void set(int x, int y, const Vec3f& c) {
    const size_t i = 3 * (static_cast<size_t>(y) * width + x);
    rgb[i] = c.x();
    rgb[i + 1] = c.y();
    rgb[i + 2] = c.z();
  }
  Vec3f mean() const;
};

// Linear value to an 8-bit sRGB code (IEC 61966-2-1 transfer curve, clamped).
uint8_t linear_to_srgb8(float v);

std::vector<uint8_t> to_srgb8(const Image& img);

// Writes by extension, in any letter case: .png (8-bit sRGB), .exr or .pfm
// (linear float). Throws OutputError for other extensions or I/O failures.
void write_image(const Image& img, const std::string& path);

// Reads a PFM written by write_image (for tests and comparisons).
Image read_pfm(const std::string& path);

// Reads an OpenEXR file's RGB channels (for tests and comparisons).
Image read_exr(const std::string& path);

// ".PNG" -> ".png"; "" without an extension.
std::string lower_case_extension(const std::string& path);

// Root mean square difference over all channels (images of equal size).
double rmse(const Image& a, const Image& b);

}  // namespace raylab
