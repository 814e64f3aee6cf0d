#pragma once
// Factory: accelerators by spec string ("embree:robust=1", "bvh:leaf=4").
// The same strings are used by the command line, the tests and the benchmarks.
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "accel/accelerator.h"
#include "base/spec.h"

namespace raylab {

// What a structure can do, so that code above accel/ asks instead of
// recognising names.
struct Capabilities {
  // Spec parameters that select the Moller-Trumbore triangle test (e.g.
  // "tri=mt" or "tri=mt,layout=bvh2"); empty when the structure has none.
  std::string mt_variant;
  // Spec parameters of a robust mode ("robust=1"); empty when none.
  std::string robust_variant;
  // Spec parameters that run the structure with scalar kernels only
  // ("simd=0": no SIMD node or leaf tests, the same triangle test and the
  // same hits), for the algorithm-only comparison; empty when the structure
  // has no SIMD kernels.
  std::string scalar_variant;
  bool per_ray_counters = true;  // the instrumented kernels count nodes and triangle tests
  bool quadratic = false;        // cost grows with rays x triangles: benches skip large scenes
  bool reference = false;        // the reference the others are compared with (its failures do not count)
  bool outline = false;          // Accelerator::outline() draws the structure (raylab show)
};

using Description = std::vector<std::pair<std::string, std::string>>;

// The values of a description joined by spaces ("3.13.5 AVX512").
std::string description_text(const Description& d);

// A statistic a structure reports in BuildStats::extra.
struct StatInfo {
  std::string key;
  std::string help;
};

// One registry line: everything the rest of the program knows about a structure.
struct AcceleratorInfo {
  std::string name;
  std::string help;
  std::vector<ParamInfo> params;
  std::function<std::unique_ptr<Accelerator>(const Params&)> make;
  Capabilities caps{};
  // Specs that tests, stress and fuzzing must cover beyond the defaults
  // (each layout, builder or kernel with its own traversal code).
  std::vector<std::string> cover{};
  std::vector<StatInfo> stats{};
  // Run-time facts as (key, value) pairs, e.g. Embree's {version, isa};
  // reports record them as <name>_<key>. Empty function = none.
  std::function<Description()> describe{};
  // Peak resident bytes per triangle of building and holding the structure
  // with its default parameters, above the loaded scene: `raylab bench`
  // estimates a build's memory from it and skips what would not fit. Measure
  // with `raylab bench --scene soup:n=10000000 --accel NAME` (rss_peak_bytes -
  // rss_before_build_bytes) and round up. 0 = not declared: bench assumes the
  // largest figure any structure declares.
  double build_peak_bytes_per_triangle = 0;
  // The same for variants whose layout is much smaller: spec parameters
  // ("simd=0": the grids' ids against SIMD blocks; "compact=1": Embree's
  // indexed triangles) and their figure. A spec with all of a variant's
  // parameters gets its figure (the first that matches).
  struct VariantPeak {
    std::string params;
    double bytes_per_triangle = 0;
  };
  std::vector<VariantPeak> variant_build_peaks{};
};

// A name no structure may take: tests use it as "an unknown accelerator"
// (so adding a structure never breaks them; accelerator_registry() checks).
inline constexpr const char* kReservedUnknownAccelerator = "no_such_accel";

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

// The registry line of a name; throws SpecError for unknown names.
const AcceleratorInfo& accelerator_info(const std::string& name);

// True when the spec names the reference structure (capabilities.reference:
// Embree, in any of its modes).
bool is_reference_spec(const std::string& spec);

// Every registered spec worth covering: each name, then each name's `cover` specs.
std::vector<std::string> coverage_specs();

// Human-readable list of accelerators and their parameters.
std::string describe_accelerators();

}  // namespace raylab
