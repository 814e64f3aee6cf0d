#pragma once
// Ray files (`raylab rays --out`, `raylab bench --ray-file`): a ray set, and
// optionally the reference's answers, in a small binary format any other
// system can read, so it can be fed exactly the same rays. The format is
// documented in docs/ray-file.md:
//   header, 40 bytes: magic "RAYLABRF", u32 version (1), u32 flags (bit 0:
//   occlusion set, bit 1: hits block follows; other bits 0), u64 count,
//   16-byte set name (ASCII, NUL padded);
//   count rays: origin xyz, direction xyz, tmin, tmax (8 x float32);
//   hits block (flag bit 1): closest-hit sets count x (float32 t, u, v,
//   uint32 prim; prim 0xFFFFFFFF = miss), occlusion sets count x uint8 (1 =
//   occluded).
// Everything little-endian. Rays are stored as they are: a NaN field makes
// the ray invalid, and every accelerator answers an invalid ray with a miss.
#include <cstdint>
#include <stdexcept>
#include <string>
#include <vector>

#include "accel/core/hit.h"
#include "bench/ray_sets.h"

namespace raylab {

class RayFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

inline constexpr char kRayFileMagic[8] = {'R', 'A', 'Y', 'L', 'A', 'B', 'R', 'F'};
inline constexpr uint32_t kRayFileVersion = 1;
inline constexpr size_t kRayFileHeaderBytes = 40;
inline constexpr size_t kRayFileRayBytes = 32;
inline constexpr uint32_t kRayFileOcclusion = 1u << 0;
inline constexpr uint32_t kRayFileHasHits = 1u << 1;

struct RayFile {
  RaySet set;
  bool has_hits = false;
  std::vector<Hit> hits;          // closest-hit sets with has_hits
  std::vector<uint8_t> occluded;  // occlusion sets with has_hits
};

// The file's bytes; `hits` (closest-hit sets) or `occluded` (occlusion sets)
// may be null (no hits block), else must have one entry per ray.
std::string encode_ray_file(const RaySet& set, const std::vector<Hit>* hits, const std::vector<uint8_t>* occluded);
// Written atomically (never a half-written file); throws OutputError.
void write_ray_file(const std::string& path, const RaySet& set, const std::vector<Hit>* hits,
                    const std::vector<uint8_t>* occluded);

// Throws RayFileError with a clear message for anything that is not a
// complete ray file of this version (wrong magic or version, unknown flags,
// a size that does not match the count: truncated or trailing bytes).
RayFile decode_ray_file(const std::string& bytes, const std::string& what = "ray file");
RayFile read_ray_file(const std::string& path);

}  // namespace raylab
