#pragma once
// `embree`: adapter over Embree 3, the reference for hits and speed.
#include "accel/registry.h"

namespace raylab {

AcceleratorInfo embree_accelerator_info();

// True for "embree" and "embree:..." specs (every Embree mode).
bool is_embree_spec(const std::string& spec);

// The self-check's yardstick (`raylab bench --embree-selfcheck`, the
// micro-benchmarks and tests): a plain loop of rtcIntersect1 / rtcOccluded1
// over rays `embree` (an `embree` accelerator with api=single) prepared for
// the whole span, writing our Hit / occlusion byte. It applies no
// valid-range mapping, so it answers like the adapter only for rays Embree
// takes as they are (every generated ray set of the project). Throws
// std::invalid_argument for any other accelerator or prepared object.
void embree_direct_intersect(const Accelerator& embree, const PreparedRays& prepared, std::span<Hit> hits);
void embree_direct_occluded(const Accelerator& embree, const PreparedRays& prepared, std::span<uint8_t> occluded);

// Version and the ISA Embree selected on this machine (e.g. "3.13.5 AVX512").
std::string embree_version_string();

}  // namespace raylab
