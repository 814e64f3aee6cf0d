#include "accel/registry.h"

#include <algorithm>
#include <stdexcept>

#include <fmt/format.h>

#include "accel/brute/brute_accel.h"
#include "accel/bsp/bsp_accel.h"
#include "accel/bvh/bvh_accel.h"
#include "accel/embree/embree_accel.h"
#include "accel/kdtree/kdtree_accel.h"
#include "accel/grid/grid_accels.h"
#include "accel/hgrid/hgrid_accel.h"
#include "accel/loose_octree/loose_octree_accel.h"
#include "accel/octree/octree_accel.h"
#include "accel/hybrid/hybrid_accel.h"
#include "accel/irgrid/irgrid_accel.h"

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
      octree_accelerator_info(),
      hgrid_accelerator_info(),
      loose_octree_accelerator_info(),
      hybrid_accelerator_info(),
      bsp_accelerator_info(),
      irgrid_accelerator_info(),
  };
  static const bool checked = [] {
    for (const auto& info : registry)
      if (info.name == kReservedUnknownAccelerator) throw std::logic_error("registry: reserved name registered");
    return true;
  }();
  (void)checked;
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

std::string unknown_name_message(const std::string& name) {
  return fmt::format("unknown accelerator '{}' (available: {}, or 'all')", name, known_names());
}

}  // namespace

std::string description_text(const Description& d) {
  std::string s;
  for (const auto& [key, value] : d) s += (s.empty() ? "" : " ") + value;
  return s;
}

const AcceleratorInfo& accelerator_info(const std::string& name) {
  const AcceleratorInfo* info = find_info(name);
  if (!info) throw SpecError(unknown_name_message(name));
  return *info;
}

bool is_reference_spec(const std::string& spec) {
  const AcceleratorInfo* info = find_info(Spec::parse(spec).name);
  return info && info->caps.reference;
}

std::vector<std::string> coverage_specs() {
  std::vector<std::string> out;
  for (const auto& info : accelerator_registry()) {
    out.push_back(info.name);
    for (const auto& c : info.cover) out.push_back(c);
  }
  return out;
}

std::unique_ptr<Accelerator> make_accelerator(const std::string& text) {
  const Spec spec = Spec::parse(text);
  const AcceleratorInfo& info = accelerator_info(spec.name);
  const Params params(spec.name, info.params, spec.params);
  auto accel = info.make(params);
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
    const AcceleratorInfo& info = accelerator_info(spec.name);
    // Construct once so unknown parameters and bad values fail now, before a
    // possibly long scene load.
    info.make(Params(spec.name, info.params, spec.params));
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
  // One column for "name=default" and "stat key" across all accelerators, so
  // the help texts line up.
  size_t width = 0;
  for (const auto& info : accelerator_registry()) {
    for (const auto& p : info.params) width = std::max(width, p.name.size() + 1 + p.default_value.size());
    for (const auto& st : info.stats) width = std::max(width, st.key.size() + 5);
  }
  std::string s;
  for (const auto& info : accelerator_registry()) {
    s += fmt::format("{:<10} {}", info.name, info.help);
    if (info.describe) s += fmt::format(" [{}]", description_text(info.describe()));
    s += "\n";
    for (const auto& p : info.params)
      s += fmt::format("    {:<{}}  {}\n", p.name + "=" + p.default_value, width, p.help);
    for (const auto& st : info.stats) s += fmt::format("    {:<{}}  {}\n", "stat " + st.key, width, st.help);
  }
  return s;
}

}  // namespace raylab
