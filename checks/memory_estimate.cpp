#include "checks/memory_estimate.h"

#include <fmt/format.h>

#include <algorithm>

#include "accel/registry.h"

namespace raylab {

double build_peak_bytes_per_triangle(const std::string& accel_spec) {
  // Each structure declares its figure in its registry line
  // (AcceleratorInfo::build_peak_bytes_per_triangle); undeclared or unknown
  // structures get the largest declared one. A spec with all parameters of
  // a declared variant (grid:simd=0, embree:compact=1) gets its figure.
  const size_t colon = accel_spec.find(':');
  const std::string name = accel_spec.substr(0, colon);
  const std::string params = colon == std::string::npos ? std::string(",") : fmt::format(",{},", accel_spec.substr(colon + 1));
  auto has_all = [&](const std::string& variant) {
    if (variant.empty()) return false;
    size_t from = 0;
    while (from <= variant.size()) {
      const size_t comma = std::min(variant.find(',', from), variant.size());
      if (params.find(fmt::format(",{},", variant.substr(from, comma - from))) == std::string::npos) return false;
      from = comma + 1;
    }
    return true;
  };
  double largest = 0;
  for (const AcceleratorInfo& info : accelerator_registry()) {
    if (info.name == name) {
      for (const auto& v : info.variant_build_peaks)
        if (v.bytes_per_triangle > 0 && has_all(v.params)) return v.bytes_per_triangle;
      if (info.build_peak_bytes_per_triangle > 0) return info.build_peak_bytes_per_triangle;
    }
    largest = std::max(largest, info.build_peak_bytes_per_triangle);
  }
  return largest;
}

size_t estimate_build_peak_bytes(const std::string& accel_spec, size_t triangles) {
  return kBuildFixedBytes +
         static_cast<size_t>(build_peak_bytes_per_triangle(accel_spec) * static_cast<double>(triangles));
}

}  // namespace raylab
