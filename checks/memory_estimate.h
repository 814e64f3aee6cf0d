#pragma once
// How much memory building a structure needs, estimated before building it,
// so every command that builds one can skip or refuse what does not fit with
// a reason ("needs ~31 GiB by its estimate", checks/memory_guard.h) instead of
// being killed by the kernel. The figures are peak resident bytes per
// triangle above the loaded scene, declared by each structure in its registry
// line (AcceleratorInfo::build_peak_bytes_per_triangle, accel/registry.h);
// docs/scale.md.
#include <cstddef>
#include <string>

namespace raylab {

// Peak bytes per triangle of building and holding `accel_spec` (its
// structure's declared figure; undeclared or unknown ones get the largest).
double build_peak_bytes_per_triangle(const std::string& accel_spec);

// The fixed allowance beside every build: per-thread buffers, allocator
// slack, a few small ray sets.
inline constexpr size_t kBuildFixedBytes = size_t{64} << 20;

// build_peak_bytes_per_triangle x triangles + kBuildFixedBytes.
size_t estimate_build_peak_bytes(const std::string& accel_spec, size_t triangles);

}  // namespace raylab
