#include "bench/memory_estimate.h"

#include <algorithm>

#include "accel/registry.h"

namespace raylab {

double build_peak_bytes_per_triangle(const std::string& accel_spec) {
  // Each structure declares its figure in its registry line
  // (AcceleratorInfo::build_peak_bytes_per_triangle); undeclared or unknown
  // structures get the largest declared one. A spec naming the structure's
  // scalar variant (e.g. grid:simd=0) gets the scalar figure when declared.
  const size_t colon = accel_spec.find(':');
  const std::string name = accel_spec.substr(0, colon);
  const std::string params = colon == std::string::npos ? "" : "," + accel_spec.substr(colon + 1) + ",";
  double largest = 0;
  for (const AcceleratorInfo& info : accelerator_registry()) {
    if (info.name == name && info.scalar_build_peak_bytes_per_triangle > 0 && !info.caps.scalar_variant.empty() &&
        params.find("," + info.caps.scalar_variant + ",") != std::string::npos)
      return info.scalar_build_peak_bytes_per_triangle;
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
