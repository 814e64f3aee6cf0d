#include "bench/memory_estimate.h"

#include <algorithm>

#include "accel/registry.h"

namespace raylab {

double build_peak_bytes_per_triangle(const std::string& accel_spec) {
  // Each structure declares its figure in its registry line
  // (AcceleratorInfo::build_peak_bytes_per_triangle); undeclared or unknown
  // structures get the largest declared one.
  const std::string name = accel_spec.substr(0, accel_spec.find(':'));
  double largest = 0;
  for (const AcceleratorInfo& info : accelerator_registry()) {
    if (info.name == name && info.build_peak_bytes_per_triangle > 0) return info.build_peak_bytes_per_triangle;
    largest = std::max(largest, info.build_peak_bytes_per_triangle);
  }
  return largest;
}

size_t estimate_build_peak_bytes(const std::string& accel_spec, size_t triangles) {
  constexpr double kFixed = 64.0 * 1024 * 1024;
  return static_cast<size_t>(kFixed + build_peak_bytes_per_triangle(accel_spec) * static_cast<double>(triangles));
}

}  // namespace raylab
