#pragma once
// `raylab compare A.json B.json`: two bench reports cell by cell (scene,
// accelerator, ray set, threads), in the spirit of Google Benchmark's
// compare.py: the change in speed, build time and memory, and whether the
// speed change is significant by a two-sided Mann–Whitney U test over the
// per-repeat trace times both runs store (record field trace_s).
//
// Drift: runs of one revision on a shared machine differ by a few percent
// because the machine's load changes between them, and with seven repeats per
// run the U test calls such a shift significant. Bench times single-ray Embree
// back to back with every cell (embree_mrays_per_s), so by default each
// repeat's time is divided by that same-cell Embree time: the test and the
// speed change are on the ratio to Embree, which a machine-wide slow-down
// moves far less than raw times. The reference cells themselves, and reports
// without an Embree time, are compared on raw times.
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace raylab {

// Two-sided p-value of the Mann–Whitney U test (Mann & Whitney 1947) that
// samples a and b come from the same distribution. Exact (enumerating the
// rank sums) for samples without ties up to 25 values each; otherwise the
// normal approximation with tie correction and continuity correction.
// Empty samples give 1.
double mann_whitney_p(const std::vector<double>& a, const std::vector<double>& b);

struct CompareCell {
  std::string scene, accel, ray_set;
  int threads = 1;
  double mrays_a = 0, mrays_b = 0;
  double speed_change_pct = 0;  // (B / A - 1) x 100: negative = slower
  double build_ms_a = 0, build_ms_b = 0, build_change_pct = 0;
  double bytes_a = 0, bytes_b = 0, bytes_change_pct = 0;
  std::optional<double> p_value;  // none when either run lacks per-repeat times
  bool normalized = false;        // test and speed change on times / same-cell Embree time
  bool significant = false;       // p < alpha and |speed change| >= min_change_pct
  bool regression = false;        // slower by more than the threshold (and significant when testable)
};

struct CompareOptions {
  double alpha = 0.05;
  // Noise floor: smaller speed changes are never called significant. On a
  // shared machine runs of one revision drift by a few percent, and with
  // enough repeats the U test finds such drifts "significant".
  double min_change_pct = 5.0;
  double fail_above_pct = -1;  // < 0: no regression threshold
  bool normalize_by_embree = true;  // see the drift note at the top
};

struct CompareResult {
  std::vector<CompareCell> cells;
  size_t only_in_a = 0, only_in_b = 0;
  size_t regressions = 0;
};

// Throws std::invalid_argument when a document is not a bench report.
CompareResult compare_bench_reports(const nlohmann::json& a, const nlohmann::json& b, const CompareOptions& options);

nlohmann::json compare_result_json(const CompareResult& r, const CompareOptions& options);

// Fixed-width table; `colour` adds ANSI colours (red slower, green faster, significant cells only).
std::string format_compare_table(const CompareResult& r, const CompareOptions& options, bool colour);

}  // namespace raylab
