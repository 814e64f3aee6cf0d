#include "tracer/image.h"

#include <stb_image_write.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "base/atomic_file.h"

namespace raylab {

Vec3f Image::mean() const {
  double s[3] = {0, 0, 0};
  for (size_t i = 0; i < rgb.size(); i += 3)
    for (int c = 0; c < 3; ++c) s[c] += rgb[i + c];
  const double n = std::max<double>(1.0, static_cast<double>(rgb.size() / 3));
  return Vec3f(static_cast<float>(s[0] / n), static_cast<float>(s[1] / n), static_cast<float>(s[2] / n));
}

uint8_t linear_to_srgb8(float v) {
  if (!(v > 0.0f)) return 0;  // also maps NaN to black
  if (v >= 1.0f) return 255;
  const float s = v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
  return static_cast<uint8_t>(std::lround(s * 255.0f));
}

std::vector<uint8_t> to_srgb8(const Image& img) {
  std::vector<uint8_t> out(img.rgb.size());
  for (size_t i = 0; i < img.rgb.size(); ++i) out[i] = linear_to_srgb8(img.rgb[i]);
  return out;
}

namespace {

void append_bytes(void* context, void* data, int size) {
  auto* buf = static_cast<std::string*>(context);
  buf->append(static_cast<const char*>(data), static_cast<size_t>(size));
}

}  // namespace

void write_image(const Image& img, const std::string& path) {
  const std::string ext = std::filesystem::path(path).extension().string();
  if (img.width <= 0 || img.height <= 0) throw OutputError(fmt::format("{}: empty image", path));
  if (ext == ".png") {
    const std::vector<uint8_t> px = to_srgb8(img);
    std::string bytes;
    if (!stbi_write_png_to_func(&append_bytes, &bytes, img.width, img.height, 3, px.data(), img.width * 3))
      throw OutputError(fmt::format("{}: PNG encoding failed", path));
    write_file_atomically(path, bytes);
  } else if (ext == ".pfm") {
    write_file_atomically(path, [&](std::ostream& out) {
      // Little-endian (negative scale); PFM stores rows bottom to top.
      out << "PF\n" << img.width << " " << img.height << "\n-1.0\n";
      for (int y = img.height - 1; y >= 0; --y)
        out.write(reinterpret_cast<const char*>(&img.rgb[3 * static_cast<size_t>(y) * img.width]),
                  static_cast<std::streamsize>(3 * sizeof(float) * img.width));
    });
  } else {
    throw OutputError(fmt::format("{}: unsupported image format '{}' (use .png or .pfm)", path, ext));
  }
}

Image read_pfm(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw OutputError(fmt::format("{}: cannot open", path));
  std::string magic;
  int w = 0, h = 0;
  float scale = 0;
  in >> magic >> w >> h >> scale;
  in.get();
  if (magic != "PF" || w <= 0 || h <= 0 || scale >= 0) throw OutputError(fmt::format("{}: not a little-endian RGB PFM", path));
  Image img(w, h);
  for (int y = h - 1; y >= 0; --y)
    in.read(reinterpret_cast<char*>(&img.rgb[3 * static_cast<size_t>(y) * w]), static_cast<std::streamsize>(3 * sizeof(float) * w));
  if (!in) throw OutputError(fmt::format("{}: truncated PFM", path));
  return img;
}

double rmse(const Image& a, const Image& b) {
  if (a.width != b.width || a.height != b.height) throw std::invalid_argument("rmse: image sizes differ");
  double s = 0;
  for (size_t i = 0; i < a.rgb.size(); ++i) {
    const double d = static_cast<double>(a.rgb[i]) - b.rgb[i];
    s += d * d;
  }
  return std::sqrt(s / std::max<double>(1.0, static_cast<double>(a.rgb.size())));
}

}  // namespace raylab
