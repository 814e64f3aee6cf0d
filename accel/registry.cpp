#include "accel/registry.h"

#include <algorithm>

#include <fmt/format.h>

#include "accel/brute/brute_accel.h"
#include "accel/bvh/bvh_accel.h"
#include "accel/embree/embree_accel.h"
#include "accel/kdtree/kdtree_accel.h"
#include "accel/grid/grid_accels.h"

namespace raylab {

const std::vector<AcceleratorInfo>& accelerator_registry() {
  // One line per structure; order is the order of `all` and of reports.
  static const std::vector<AcceleratorInfo> registry = {
      embree_accelerator_info(),
      brute_accelerator_info(),
      bvh_accelerator_info(),
      kdtree_accelerator_info(),
      grid_accelerator_info(),
      hashgrid_accelerator_info(),
      grid2_accelerator_info(),
  };
  return registry;
}

namespace {

const AcceleratorInfo* find_info(const std::string& name) {
  for (const auto& info : accelerator_registry())
    if (info.name == name) return &info;
  return nullptr;
}

std::string known_names() {
  std::string s;
  for (const auto& info : accelerator_registry()) s += (s.empty() ? "" : ", ") + info.name;
  return s;
}

}  // namespace

std::unique_ptr<Accelerator> make_accelerator(const std::string& text) {
  const Spec spec = Spec::parse(text);
  const AcceleratorInfo* info = find_info(spec.name);
  if (!info)
    throw SpecError(fmt::format("unknown accelerator '{}' (available: {}, or 'all')", spec.name, known_names()));
  const Params params(spec.name, info->params, spec.params);
  auto accel = info->make(params);
  accel->set_spec(spec.to_string());
  return accel;
}

std::vector<std::string> expand_accelerator_list(const std::string& list) {
  std::vector<std::string> out;
  for (const auto& item : split_spec_list(list)) {
    if (item == "all") {
      for (const auto& info : accelerator_registry()) out.push_back(info.name);
      continue;
    }
    const Spec spec = Spec::parse(item);
    const AcceleratorInfo* info = find_info(spec.name);
    if (!info)
      throw SpecError(fmt::format("unknown accelerator '{}' (available: {}, or 'all')", spec.name, known_names()));
    // Construct once so unknown parameters and bad values fail now, before a
    // possibly long scene load.
    info->make(Params(spec.name, info->params, spec.params));
    out.push_back(spec.to_string());
  }
  if (out.empty()) throw SpecError("no accelerator given");
  return out;
}

std::vector<std::string> apply_sweep(const std::vector<std::string>& specs, const std::string& param,
                                     const std::vector<std::string>& values) {
  if (values.empty()) throw SpecError(fmt::format("sweep over '{}' has no values", param));
  std::vector<std::string> out;
  bool any = false;
  for (const auto& text : specs) {
    const Spec spec = Spec::parse(text);
    const AcceleratorInfo* info = find_info(spec.name);
    bool declared = false;
    if (info)
      for (const auto& p : info->params) declared |= (p.name == param);
    if (!declared) {
      out.push_back(text);
      continue;
    }
    any = true;
    for (const auto& v : values) {
      Spec s = spec;
      s.params[param] = v;
      info->make(Params(s.name, info->params, s.params));  // validates the value
      out.push_back(s.to_string());
    }
  }
  if (!any) throw SpecError(fmt::format("no accelerator in the list has a parameter '{}'", param));
  return out;
}

std::string describe_accelerators() {
  // One column for "name=default" across all accelerators, so the help texts line up.
  size_t width = 0;
  for (const auto& info : accelerator_registry())
    for (const auto& p : info.params) width = std::max(width, p.name.size() + 1 + p.default_value.size());
  std::string s;
  for (const auto& info : accelerator_registry()) {
    s += fmt::format("{:<10} {}\n", info.name, info.help);
    for (const auto& p : info.params)
      s += fmt::format("    {:<{}}  {}\n", p.name + "=" + p.default_value, width, p.help);
  }
  return s;
}

}  // namespace raylab
