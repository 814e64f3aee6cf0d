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
// in alternation with every cell (embree_mrays_per_s, embree_trace_s), so each
// repeat's time is divided by that same-cell Embree time: the test and the
// verdict are on the ratio to Embree, which a machine-wide slow-down moves
// far less than raw times. The reference cells themselves, and reports
// without an Embree time, are compared on raw times. Both changes are
// shown, in two labelled columns, since they can differ in sign.
//
// A change is reported only when it is significant AND at least the minimum
// effect: with five repeats per run, two runs whose repeats do not overlap
// give p = 0.0079 however small the shift. The minimum effect is raised to
// the noise floor the runs measured: Embree is timed with every structure,
// so each run shows how far the reference's own speed wandered.
#include <cstddef>
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

// The smallest two-sided p the exact test can give for samples of sizes m
// and n (complete separation): 2 / C(m + n, m), e.g. 0.0079 for 5 and 5,
// 0.1 for 3 and 3. Below alpha or not, it says whether a test is possible.
double mann_whitney_min_p(size_t m, size_t n);

struct CompareCell {
  std::string scene, accel, ray_set;
  int threads = 1;
  double mrays_a = 0, mrays_b = 0;
  double mrays_change_pct = 0;  // (B / A - 1) x 100 of Mrays/s: positive = faster, negative = slower
  // ratio_to_embree in A and B and the change of the ratio (positive = faster
  // relative to Embree: with per-repeat Embree times, of the median over
  // repeats of Embree's time over the structure's in the same repeat); none
  // for Embree's own cells and reports without Embree figures.
  std::optional<double> ratio_a, ratio_b, ratio_change_pct;
  bool normalized = false;  // the test and the verdict are on the ratio (times / same-cell Embree time)
  bool reference = false;   // an Embree cell: with normalisation, its change is the machine's drift (no verdict)
  double change_pct = 0;    // the tested change: ratio_change_pct when normalized, else mrays_change_pct
  double build_ms_a = 0, build_ms_b = 0, build_change_pct = 0;
  double bytes_a = 0, bytes_b = 0, bytes_change_pct = 0;
  size_t repeats_a = 0, repeats_b = 0;
  std::optional<double> p_value;  // none when either run lacks two or more per-repeat times
  bool testable = false;          // the repeats can reach p < alpha at all (mann_whitney_min_p)
  bool significant = false;       // p < alpha and |change_pct| >= the threshold (min effect or noise floor)
  bool regression = false;        // significant and slower by more than fail_above_pct
};

struct CompareOptions {
  double alpha = 0.05;
  // The minimum effect: a change smaller than this is never reported,
  // whatever p says. Runs of one binary on a shared machine differ by a few
  // percent (load, frequency, memory placement), and a rank test over five
  // repeats per run calls any such shift significant as soon as the two
  // runs' repeats do not overlap (p = 0.0079).
  double min_effect_pct = 3.0;
  // Raise the minimum effect to the noise floor the two runs measured
  // (CompareResult::noise_a_pct, noise_b_pct): on a loaded machine the
  // reference's own speed wanders by more than any minimum one would state.
  bool noise_floor = true;
  double fail_above_pct = -1;  // < 0: no regression threshold
  bool normalize_by_embree = true;  // see the drift note at the top
};

struct CompareResult {
  std::vector<CompareCell> cells;
  size_t only_in_a = 0, only_in_b = 0;
  size_t significant = 0, regressions = 0;
  size_t untestable = 0;  // cells whose repeats cannot reach p < alpha
  // The noise floor of each run: the median over (scene, ray set, threads)
  // of the spread of single-ray Embree's timings within the run (bench times
  // it in alternation with every structure); NaN when a run has none.
  double noise_a_pct = 0, noise_b_pct = 0;
  // The smallest change reported: min_effect_pct, or the larger noise floor.
  double threshold_pct = 0;
};

// Throws std::invalid_argument when a document is not a bench report.
CompareResult compare_bench_reports(const nlohmann::json& a, const nlohmann::json& b, const CompareOptions& options);

nlohmann::json compare_result_json(const CompareResult& r, const CompareOptions& options);

// Fixed-width table; `colour` adds ANSI colours (red slower, green faster,
// significant cells only); ends with what was tested and any warning.
std::string format_compare_table(const CompareResult& r, const CompareOptions& options, bool colour);

}  // namespace raylab
