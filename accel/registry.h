#pragma once
// Factory: accelerators by spec string ("embree:robust=1", "bvh:leaf=4").
// The same strings are used by the command line, the tests and the benchmarks.
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "accel/accelerator.h"
#include "accel/spec.h"

namespace raylab {

struct AcceleratorInfo {
  std::string name;
  std::string help;
  std::vector<ParamInfo> params;
  std::function<std::unique_ptr<Accelerator>(const Params&)> make;
};

// Every registered accelerator, in a fixed order (embree first).
const std::vector<AcceleratorInfo>& accelerator_registry();

// Creates an accelerator from one spec; throws SpecError for unknown names or
// parameters (the message lists what exists).
std::unique_ptr<Accelerator> make_accelerator(const std::string& spec);

// Expands a comma list ("bvh,brute", "all") into single specs, checking each.
std::vector<std::string> expand_accelerator_list(const std::string& list);

// Sweep: every spec whose accelerator declares `param` is replaced by one
// spec per value (param=value); other specs pass through unchanged.
// Throws SpecError when no spec in the list has the parameter.
std::vector<std::string> apply_sweep(const std::vector<std::string>& specs, const std::string& param,
                                     const std::vector<std::string>& values);

// Human-readable list of accelerators and their parameters.
std::string describe_accelerators();

}  // namespace raylab
