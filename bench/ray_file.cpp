#include "bench/ray_file.h"

#include <bit>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include <fmt/format.h>

#include "accel/util/atomic_file.h"

namespace raylab {

namespace {

// Explicit little-endian encoding, whatever the host's byte order.
void put_u32(std::string& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFFu));
}
void put_u64(std::string& out, uint64_t v) {
  for (int i = 0; i < 8; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xFFu));
}
void put_f32(std::string& out, float f) { put_u32(out, std::bit_cast<uint32_t>(f)); }

uint32_t get_u32(const char* p) {
  uint32_t v = 0;
  for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(static_cast<unsigned char>(p[i])) << (8 * i);
  return v;
}
uint64_t get_u64(const char* p) {
  uint64_t v = 0;
  for (int i = 0; i < 8; ++i) v |= static_cast<uint64_t>(static_cast<unsigned char>(p[i])) << (8 * i);
  return v;
}
float get_f32(const char* p) { return std::bit_cast<float>(get_u32(p)); }

}  // namespace

std::string encode_ray_file(const RaySet& set, const std::vector<Hit>* hits, const std::vector<uint8_t>* occluded) {
  const size_t n = set.rays.size();
  const bool has_hits = set.occlusion ? occluded != nullptr : hits != nullptr;
  if (has_hits && (set.occlusion ? occluded->size() : hits->size()) != n)
    throw std::invalid_argument("ray file: hits do not match the rays");
  if (set.name.size() > 16) throw std::invalid_argument(fmt::format("ray file: set name '{}' longer than 16 bytes", set.name));
  std::string out;
  out.reserve(kRayFileHeaderBytes + n * kRayFileRayBytes + (has_hits ? n * 16 : 0));
  out.append(kRayFileMagic, sizeof kRayFileMagic);
  put_u32(out, kRayFileVersion);
  put_u32(out, (set.occlusion ? kRayFileOcclusion : 0u) | (has_hits ? kRayFileHasHits : 0u));
  put_u64(out, n);
  std::string name = set.name;
  name.resize(16, '\0');
  out += name;
  for (const Ray& r : set.rays) {
    for (int a = 0; a < 3; ++a) put_f32(out, r.org[a]);
    for (int a = 0; a < 3; ++a) put_f32(out, r.dir[a]);
    put_f32(out, r.tmin);
    put_f32(out, r.tmax);
  }
  if (has_hits) {
    if (set.occlusion) {
      for (uint8_t o : *occluded) out.push_back(static_cast<char>(o ? 1 : 0));
    } else {
      for (const Hit& h : *hits) {
        put_f32(out, h.t);
        put_f32(out, h.u);
        put_f32(out, h.v);
        put_u32(out, h.prim);
      }
    }
  }
  return out;
}

void write_ray_file(const std::string& path, const RaySet& set, const std::vector<Hit>* hits,
                    const std::vector<uint8_t>* occluded) {
  write_file_atomically(path, encode_ray_file(set, hits, occluded));
}

RayFile decode_ray_file(const std::string& bytes, const std::string& what) {
  if (bytes.size() < kRayFileHeaderBytes)
    throw RayFileError(fmt::format("{}: truncated header ({} bytes, a ray file starts with {})", what, bytes.size(),
                                   kRayFileHeaderBytes));
  const char* p = bytes.data();
  if (std::memcmp(p, kRayFileMagic, sizeof kRayFileMagic) != 0)
    throw RayFileError(fmt::format("{}: not a ray file (wrong magic; expected \"RAYLABRF\")", what));
  const uint32_t version = get_u32(p + 8);
  if (version != kRayFileVersion)
    throw RayFileError(fmt::format("{}: unsupported ray file version {} (this raylab reads version {})", what, version,
                                   kRayFileVersion));
  const uint32_t flags = get_u32(p + 12);
  if (flags & ~(kRayFileOcclusion | kRayFileHasHits))
    throw RayFileError(fmt::format("{}: unknown flags 0x{:x}", what, flags));
  const uint64_t count = get_u64(p + 16);
  RayFile f;
  f.set.occlusion = (flags & kRayFileOcclusion) != 0;
  f.has_hits = (flags & kRayFileHasHits) != 0;
  const char* name = p + 24;
  f.set.name.assign(name, strnlen(name, 16));
  for (char c : f.set.name)
    if (c < 0x20 || c > 0x7e) throw RayFileError(fmt::format("{}: set name is not printable ASCII", what));
  if (f.set.name.empty()) f.set.name = "file";
  // Size check before any allocation, without overflow: the count must match
  // the bytes that follow the header exactly.
  const uint64_t per_ray = kRayFileRayBytes + (f.has_hits ? (f.set.occlusion ? 1 : 16) : 0);
  const uint64_t body = bytes.size() - kRayFileHeaderBytes;
  if (count > body / per_ray || count * per_ray != body) {
    if (count > body / per_ray)
      throw RayFileError(fmt::format("{}: truncated: header says {} rays ({} bytes each), {} bytes follow", what, count,
                                     per_ray, body));
    throw RayFileError(fmt::format("{}: {} trailing bytes after {} rays", what, body - count * per_ray, count));
  }
  const size_t n = static_cast<size_t>(count);
  f.set.rays.resize(n);
  const char* r = p + kRayFileHeaderBytes;
  for (size_t i = 0; i < n; ++i, r += kRayFileRayBytes) {
    Ray& ray = f.set.rays[i];
    ray.org = Vec3f(get_f32(r), get_f32(r + 4), get_f32(r + 8));
    ray.dir = Vec3f(get_f32(r + 12), get_f32(r + 16), get_f32(r + 20));
    ray.tmin = get_f32(r + 24);
    ray.tmax = get_f32(r + 28);
  }
  if (f.has_hits) {
    if (f.set.occlusion) {
      f.occluded.resize(n);
      for (size_t i = 0; i < n; ++i) f.occluded[i] = r[i] != 0 ? 1 : 0;
    } else {
      f.hits.resize(n);
      for (size_t i = 0; i < n; ++i, r += 16) f.hits[i] = Hit{get_f32(r), get_f32(r + 4), get_f32(r + 8), get_u32(r + 12)};
    }
  }
  return f;
}

RayFile read_ray_file(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw RayFileError(fmt::format("{}: no such file", path));
  std::ifstream in(path, std::ios::binary);
  if (!in) throw RayFileError(fmt::format("{}: cannot open", path));
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (in.bad()) throw RayFileError(fmt::format("{}: read error", path));
  return decode_ray_file(bytes, path);
}

}  // namespace raylab
