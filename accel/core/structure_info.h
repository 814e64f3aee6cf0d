#pragma once
// The start of a registry line for a structure that offers both triangle
// tests and draws its outline (every structure but Embree and the BVH's
// layouts): the `tri` parameter (listed last), its Moller-Trumbore variant
// and the outline capability, declared together so they cannot disagree.
#include <string>
#include <utility>
#include <vector>

#include "accel/core/triangle_test_param.h"
#include "accel/registry.h"

namespace raylab {

inline AcceleratorInfo structure_info(std::string name, std::string help, std::vector<ParamInfo> params,
                                      std::function<std::unique_ptr<Accelerator>(const Params&)> make) {
  params.push_back(triangle_test_param());
  AcceleratorInfo info{std::move(name), std::move(help), std::move(params), std::move(make)};
  info.caps.mt_variant = "tri=mt";
  info.caps.outline = true;
  return info;
}

}  // namespace raylab
