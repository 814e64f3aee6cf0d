#include "bench/memory_estimate.h"

#include <algorithm>
#include <map>

namespace raylab {

double build_peak_bytes_per_triangle(const std::string& accel_spec) {
  // Peak resident bytes per triangle above the loaded scene, measured on
  // soup:n=10^7 with the default parameters (embree 130, bvh 164, grid 68,
  // hashgrid 131, grid2 145), rounded up. kdtree and brute: not measured at
  // 10^7 (build time), conservative figures from their layouts.
  static const std::map<std::string, double> kPerTriangle = {
      {"embree", 135}, {"brute", 20}, {"bvh", 170}, {"kdtree", 300}, {"grid", 75}, {"hashgrid", 140}, {"grid2", 150},
  };
  const std::string family = accel_spec.substr(0, accel_spec.find(':'));
  const auto it = kPerTriangle.find(family);
  if (it != kPerTriangle.end()) return it->second;
  double largest = 0;
  for (const auto& [name, bytes] : kPerTriangle) largest = std::max(largest, bytes);
  return largest;
}

size_t estimate_build_peak_bytes(const std::string& accel_spec, size_t triangles) {
  constexpr double kFixed = 64.0 * 1024 * 1024;
  return static_cast<size_t>(kFixed + build_peak_bytes_per_triangle(accel_spec) * static_cast<double>(triangles));
}

}  // namespace raylab
