#include "tracer/image.h"

#include <stb_image_write.h>
#include <tinyexr.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fmt/format.h>

#include "accel/util/atomic_file.h"

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

// Linear float OpenEXR (tinyexr): three 32-bit float channels, stored in the
// B, G, R order most readers expect, ZIP compressed, rows from the top.
std::string encode_exr(const Image& img, const std::string& path) {
  const size_t n = static_cast<size_t>(img.width) * img.height;
  std::vector<float> planes[3];
  for (int c = 0; c < 3; ++c) {
    planes[c].resize(n);
    for (size_t i = 0; i < n; ++i) planes[c][i] = img.rgb[3 * i + c];
  }
  float* channel_ptrs[3] = {planes[2].data(), planes[1].data(), planes[0].data()};  // B, G, R
  EXRChannelInfo channels[3] = {};
  const char* names[3] = {"B", "G", "R"};
  int pixel_types[3], stored_types[3];
  for (int c = 0; c < 3; ++c) {
    std::strncpy(channels[c].name, names[c], sizeof channels[c].name - 1);
    pixel_types[c] = TINYEXR_PIXELTYPE_FLOAT;
    stored_types[c] = TINYEXR_PIXELTYPE_FLOAT;
  }
  EXRHeader header;
  InitEXRHeader(&header);
  header.num_channels = 3;
  header.channels = channels;
  header.pixel_types = pixel_types;
  header.requested_pixel_types = stored_types;
  header.compression_type = TINYEXR_COMPRESSIONTYPE_ZIP;
  EXRImage image;
  InitEXRImage(&image);
  image.num_channels = 3;
  image.width = img.width;
  image.height = img.height;
  image.images = reinterpret_cast<unsigned char**>(channel_ptrs);
  unsigned char* memory = nullptr;
  const char* err = nullptr;
  const size_t bytes = SaveEXRImageToMemory(&image, &header, &memory, &err);
  if (bytes == 0) {
    const std::string why = err ? err : "unknown error";
    if (err) FreeEXRErrorMessage(err);
    throw OutputError(fmt::format("{}: EXR encoding failed ({})", path, why));
  }
  std::string out(reinterpret_cast<const char*>(memory), bytes);
  std::free(memory);
  return out;
}

}  // namespace

std::string lower_case_extension(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

void write_image(const Image& img, const std::string& path) {
  const std::string ext = lower_case_extension(path);
  if (img.width <= 0 || img.height <= 0) throw OutputError(fmt::format("{}: empty image", path));
  if (ext == ".exr") {
    write_file_atomically(path, encode_exr(img, path));
    return;
  }
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
    throw OutputError(fmt::format("{}: unsupported image format '{}' (use .png, .exr or .pfm)", path, ext));
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

Image read_exr(const std::string& path) {
  float* rgba = nullptr;
  int w = 0, h = 0;
  const char* err = nullptr;
  if (LoadEXR(&rgba, &w, &h, path.c_str(), &err) != TINYEXR_SUCCESS) {
    const std::string why = err ? err : "unknown error";
    if (err) FreeEXRErrorMessage(err);
    throw OutputError(fmt::format("{}: cannot read EXR ({})", path, why));
  }
  Image img(w, h);
  for (size_t i = 0; i < static_cast<size_t>(w) * h; ++i)
    for (int c = 0; c < 3; ++c) img.rgb[3 * i + c] = rgba[4 * i + c];
  std::free(rgba);
  return img;
}

}  // namespace raylab
