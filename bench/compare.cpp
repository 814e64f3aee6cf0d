#include "bench/compare.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>
#include <tuple>

#include <fmt/format.h>

#include "accel/registry.h"
#include "bench/report.h"

namespace raylab {

namespace {

// Midranks of the pooled sample; returns the rank sum of the first n_a values
// and the tie-correction term sum(t^3 - t) over groups of tied values.
std::pair<double, double> rank_sum(const std::vector<double>& a, const std::vector<double>& b) {
  std::vector<std::pair<double, int>> pooled;
  for (double v : a) pooled.push_back({v, 0});
  for (double v : b) pooled.push_back({v, 1});
  std::sort(pooled.begin(), pooled.end());
  double ra = 0, ties = 0;
  for (size_t i = 0; i < pooled.size();) {
    size_t j = i;
    while (j < pooled.size() && pooled[j].first == pooled[i].first) ++j;
    const double midrank = 0.5 * static_cast<double>(i + 1 + j);  // ranks i+1 .. j
    const double t = static_cast<double>(j - i);
    ties += t * t * t - t;
    for (size_t k = i; k < j; ++k)
      if (pooled[k].second == 0) ra += midrank;
    i = j;
  }
  return {ra, ties};
}

// Number of ways U = u for sample sizes (m, n), all u at once: the classic
// recurrence c(m, n, u) = c(m - 1, n, u - n) + c(m, n - 1, u).
std::vector<double> exact_u_distribution(size_t m, size_t n) {
  // table[j][u] for the current i (rows built from i = 0).
  const size_t umax = m * n;
  std::vector<std::vector<double>> prev(n + 1, std::vector<double>(umax + 1, 0.0)), cur = prev;
  for (size_t j = 0; j <= n; ++j) prev[j][0] = 1;  // i = 0: U = 0 in one way
  for (size_t i = 1; i <= m; ++i) {
    for (auto& row : cur) std::fill(row.begin(), row.end(), 0.0);
    cur[0][0] = 1;
    for (size_t j = 1; j <= n; ++j)
      for (size_t u = 0; u <= i * j; ++u) cur[j][u] = (u >= j ? prev[j][u - j] : 0.0) + cur[j - 1][u];
    std::swap(prev, cur);
  }
  return prev[n];
}

}  // namespace

double mann_whitney_p(const std::vector<double>& a, const std::vector<double>& b) {
  if (a.empty() || b.empty()) return 1.0;
  const double m = static_cast<double>(a.size()), n = static_cast<double>(b.size());
  const auto [ra, ties] = rank_sum(a, b);
  const double u = ra - m * (m + 1) / 2;  // U of sample a
  if (ties == 0 && a.size() <= 25 && b.size() <= 25) {
    const auto dist = exact_u_distribution(a.size(), b.size());
    double total = 0, le = 0, ge = 0;
    for (size_t k = 0; k < dist.size(); ++k) {
      total += dist[k];
      if (static_cast<double>(k) <= u + 1e-9) le += dist[k];
      if (static_cast<double>(k) >= u - 1e-9) ge += dist[k];
    }
    return std::min(1.0, 2.0 * std::min(le, ge) / total);
  }
  const double mean = m * n / 2;
  const double var = m * n / 12 * ((m + n + 1) - ties / ((m + n) * (m + n - 1)));
  if (!(var > 0)) return 1.0;
  const double z = (std::fabs(u - mean) - 0.5) / std::sqrt(var);
  return std::min(1.0, std::erfc(std::max(z, 0.0) / std::sqrt(2.0)));
}

double mann_whitney_min_p(size_t m, size_t n) {
  if (m == 0 || n == 0) return 1.0;
  // C(m + n, m) in floating point (exact for the sizes bench uses).
  double c = 1.0;
  for (size_t k = 1; k <= std::min(m, n); ++k) c = c * static_cast<double>(m + n - std::min(m, n) + k) / static_cast<double>(k);
  return std::min(1.0, 2.0 / c);
}

namespace {

using CellKey = std::tuple<std::string, std::string, std::string, int>;

std::map<CellKey, nlohmann::json> cells_of(const nlohmann::json& doc, const char* which) {
  if (!doc.is_object() || !doc.contains("records") || !doc["records"].is_array())
    throw std::invalid_argument(fmt::format("{}: not a raylab report (no \"records\" array)", which));
  if (doc.value("command", std::string("bench")) != "bench")
    throw std::invalid_argument(fmt::format("{}: a '{}' report; compare reads bench reports (raylab bench -o)", which,
                                            doc.value("command", std::string())));
  std::map<CellKey, nlohmann::json> out;
  for (const auto& r : doc["records"]) {
    for (const char* key : {"scene", "accel", "ray_set", "threads", "mrays_per_s"})
      if (!r.contains(key)) throw std::invalid_argument(fmt::format("{}: a record has no '{}' field", which, key));
    out[{r["scene"].get<std::string>(), r["accel"].get<std::string>(), r["ray_set"].get<std::string>(),
         r["threads"].get<int>()}] = r;
  }
  return out;
}

double number(const nlohmann::json& r, const char* key) {
  return r.contains(key) && r[key].is_number() ? r[key].get<double>() : 0.0;
}

double change_pct(double a, double b) { return a > 0 ? (b / a - 1.0) * 100.0 : 0.0; }

double median(std::vector<double> v) {
  if (v.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(v.begin(), v.end());
  return v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]);
}

// The run's noise floor: per (scene, ray set, threads), the spread (max - min)
// / median of the Embree speeds timed in alternation with each structure; the
// median of those spreads (NaN when no group has two timings).
double embree_noise_pct(const std::map<CellKey, nlohmann::json>& cells) {
  std::map<std::tuple<std::string, std::string, int>, std::vector<double>> groups;
  for (const auto& [key, r] : cells) {
    const double e = number(r, "embree_mrays_per_s");
    if (e > 0) groups[{std::get<0>(key), std::get<2>(key), std::get<3>(key)}].push_back(e);
  }
  std::vector<double> spreads;
  for (const auto& [g, v] : groups)
    if (v.size() >= 2) {
      const double m = median(v);
      spreads.push_back(100.0 * (*std::max_element(v.begin(), v.end()) - *std::min_element(v.begin(), v.end())) / m);
    }
  return median(spreads);
}

}  // namespace

CompareResult compare_bench_reports(const nlohmann::json& a, const nlohmann::json& b, const CompareOptions& opt) {
  const auto ca = cells_of(a, "first report"), cb = cells_of(b, "second report");
  CompareResult res;
  res.noise_a_pct = embree_noise_pct(ca);
  res.noise_b_pct = embree_noise_pct(cb);
  // The threshold: the stated minimum effect, raised to the noise floor the
  // two runs measured (a change smaller than the spread of the reference's
  // own speed within a run cannot be told from the machine's drift).
  res.threshold_pct = opt.min_effect_pct;
  for (double n : {res.noise_a_pct, res.noise_b_pct})
    if (opt.noise_floor && std::isfinite(n)) res.threshold_pct = std::max(res.threshold_pct, n);
  for (const auto& [key, ra] : ca) {
    const auto it = cb.find(key);
    if (it == cb.end()) {
      ++res.only_in_a;
      continue;
    }
    const auto& rb = it->second;
    CompareCell c;
    std::tie(c.scene, c.accel, c.ray_set, c.threads) = key;
    c.mrays_a = number(ra, "mrays_per_s");
    c.mrays_b = number(rb, "mrays_per_s");
    c.mrays_change_pct = change_pct(c.mrays_a, c.mrays_b);
    c.build_ms_a = number(ra, "build_ms");
    c.build_ms_b = number(rb, "build_ms");
    c.build_change_pct = change_pct(c.build_ms_a, c.build_ms_b);
    c.bytes_a = number(ra, "bytes");
    c.bytes_b = number(rb, "bytes");
    c.bytes_change_pct = change_pct(c.bytes_a, c.bytes_b);
    // Seconds of Embree per ray set in the same cell (timed back to back with it).
    auto embree_s = [](const nlohmann::json& r) {
      const double mrays = number(r, "embree_mrays_per_s"), rays = number(r, "rays");
      return mrays > 0 && rays > 0 ? rays / (mrays * 1e6) : 0.0;
    };
    const double ea = embree_s(ra), eb = embree_s(rb);
    const bool has_ratio = ea > 0 && eb > 0 && !is_reference_spec(c.accel) && number(ra, "ratio_to_embree") > 0 &&
                           number(rb, "ratio_to_embree") > 0;
    c.reference = is_reference_spec(c.accel);
    c.normalized = opt.normalize_by_embree && has_ratio;
    // Per-repeat times, normalised: each repeat by Embree's repeat timed in
    // alternation with it (embree_trace_s), or by the cell's Embree median
    // in reports without those.
    auto times = [&](const nlohmann::json& r, double embree_seconds) {
      std::vector<double> t, e;
      if (r.contains("trace_s") && r["trace_s"].is_array())
        for (const auto& v : r["trace_s"])
          if (v.is_number()) t.push_back(v.get<double>());
      if (r.contains("embree_trace_s") && r["embree_trace_s"].is_array())
        for (const auto& v : r["embree_trace_s"])
          if (v.is_number() && v.get<double>() > 0) e.push_back(v.get<double>());
      if (c.normalized)
        for (size_t i = 0; i < t.size(); ++i) t[i] /= e.size() == t.size() ? e[i] : embree_seconds;
      return t;
    };
    const auto ta = times(ra, ea), tb = times(rb, eb);
    if (has_ratio) {
      c.ratio_a = number(ra, "ratio_to_embree");
      c.ratio_b = number(rb, "ratio_to_embree");
      // The change of the median per-repeat ratio when the repeats were paired
      // with Embree's (normalised times are Embree's speed over the
      // structure's), else of the records' ratio_to_embree.
      c.ratio_change_pct = c.normalized && !ta.empty() && !tb.empty() ? (median(ta) / median(tb) - 1.0) * 100.0
                                                                       : change_pct(*c.ratio_a, *c.ratio_b);
    }
    c.change_pct = c.normalized ? *c.ratio_change_pct : c.mrays_change_pct;
    c.repeats_a = ta.size();
    c.repeats_b = tb.size();
    if (ta.size() >= 2 && tb.size() >= 2) {
      c.p_value = mann_whitney_p(ta, tb);
      c.testable = mann_whitney_min_p(ta.size(), tb.size()) < opt.alpha;
      // Embree's own cells, when the others are tested against it, show the
      // machine's drift between the runs (it is the same code): no verdict.
      const bool judged = !(c.reference && opt.normalize_by_embree);
      c.significant = judged && *c.p_value < opt.alpha && std::fabs(c.change_pct) >= res.threshold_pct;
    }
    res.untestable += !c.testable;
    c.regression = opt.fail_above_pct >= 0 && c.significant && -c.change_pct > opt.fail_above_pct;
    res.significant += c.significant;
    res.regressions += c.regression;
    res.cells.push_back(c);
  }
  for (const auto& [key, rb] : cb) res.only_in_b += ca.count(key) == 0;
  return res;
}

nlohmann::json compare_result_json(const CompareResult& r, const CompareOptions& opt) {
  auto opt_number = [](const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); };
  auto finite_or_null = [](double v) { return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr); };
  // A figure of both runs: NAME_a and NAME_b.
  auto both = [](nlohmann::json& j, const std::string& name, nlohmann::json a, nlohmann::json b) {
    j[name + "_a"] = std::move(a);
    j[name + "_b"] = std::move(b);
  };
  nlohmann::json cells = nlohmann::json::array();
  for (const auto& c : r.cells) {
    nlohmann::json j = {{"scene", c.scene}, {"accel", c.accel}, {"ray_set", c.ray_set}, {"threads", c.threads}};
    both(j, "mrays_per_s", c.mrays_a, c.mrays_b);
    j["mrays_change_pct"] = c.mrays_change_pct;
    both(j, "ratio_to_embree", opt_number(c.ratio_a), opt_number(c.ratio_b));
    j["ratio_to_embree_change_pct"] = opt_number(c.ratio_change_pct);
    j["tested"] = c.normalized                               ? "ratio_to_embree"
                  : c.reference && opt.normalize_by_embree ? "none (the reference)"
                                                           : "mrays_per_s";
    j["change_pct"] = c.change_pct;
    both(j, "build_ms", c.build_ms_a, c.build_ms_b);
    j["build_change_pct"] = c.build_change_pct;
    both(j, "bytes", c.bytes_a, c.bytes_b);
    j["bytes_change_pct"] = c.bytes_change_pct;
    both(j, "repeats", c.repeats_a, c.repeats_b);
    j.update({{"p_value", opt_number(c.p_value)},
              {"testable", c.testable},
              {"significant", c.significant},
              {"regression", c.regression}});
    cells.push_back(std::move(j));
  }
  return {{"schema_version", kReportSchemaVersion},
          {"command", "compare"},
          {"alpha", opt.alpha},
          {"min_effect_pct", opt.min_effect_pct},
          {"noise_floor", opt.noise_floor},
          {"threshold_pct", r.threshold_pct},
          {"normalize_by_embree", opt.normalize_by_embree},
          {"fail_above_pct", opt.fail_above_pct >= 0 ? nlohmann::json(opt.fail_above_pct) : nlohmann::json(nullptr)},
          {"noise_a_pct", finite_or_null(r.noise_a_pct)},
          {"noise_b_pct", finite_or_null(r.noise_b_pct)},
          {"only_in_a", r.only_in_a},
          {"only_in_b", r.only_in_b},
          {"significant", r.significant},
          {"untestable", r.untestable},
          {"regressions", r.regressions},
          {"cells", cells}};
}

std::string format_compare_table(const CompareResult& r, const CompareOptions& opt, bool colour) {
  // Both changes are "B against A, positive = faster": Mrays/s chg of the
  // speed itself, x embree chg of the ratio to the same cell's Embree.
  std::string s = fmt::format("{:<24} {:<24} {:<8} {:>3} {:>10} {:>10} {:>11} {:>12} {:>8}  {:<11} {:>9} {:>9}\n",
                              "scene", "accel", "rays", "thr", "Mrays/s A", "Mrays/s B", "Mrays/s chg", "x embree chg",
                              "p", "verdict", "build", "bytes");
  auto cut = [](const std::string& v, size_t n) { return v.size() > n ? v.substr(0, n - 1) + "~" : v; };
  auto pct = [](double v) { return fmt::format("{:+.1f}%", v); };
  for (const auto& c : r.cells) {
    std::string verdict = c.reference && opt.normalize_by_embree ? "reference"
                          : !c.p_value       ? "no repeats"
                          : !c.testable    ? "too few"
                          : !c.significant ? "~same"
                          : c.change_pct < 0 ? "slower"
                                             : "faster";
    if (c.regression) verdict = "REGRESSION";
    const char* on = "";
    if (colour && c.significant) on = c.change_pct < 0 ? "\033[31m" : "\033[32m";
    if (colour && c.regression) on = "\033[1;31m";
    const char* off = *on ? "\033[0m" : "";
    // The tested column carries the colour.
    const std::string mrays = pct(c.mrays_change_pct), ratio = c.ratio_change_pct ? pct(*c.ratio_change_pct) : "n/a";
    s += fmt::format("{:<24} {:<24} {:<8} {:>3} {:>10.2f} {:>10.2f} {}{:>11}{} {}{:>12}{} {:>8}  {}{:<11}{} {:>9} {:>9}\n",
                     cut(c.scene, 24), cut(c.accel, 24), c.ray_set, c.threads, c.mrays_a, c.mrays_b,
                     c.normalized ? "" : on, mrays, c.normalized ? "" : off, c.normalized ? on : "", ratio,
                     c.normalized ? off : "", c.p_value ? fmt::format("{:.3g}", *c.p_value) : "n/a", on, verdict, off,
                     pct(c.build_change_pct), pct(c.bytes_change_pct));
  }
  s += fmt::format("{} matching cells, {} only in A, {} only in B.\n", r.cells.size(), r.only_in_a, r.only_in_b);
  s += "Both changes are B against A, positive = faster. ";
  s += opt.normalize_by_embree
           ? "The verdict tests 'x embree chg' (the median over repeats of Embree's time over the structure's in the "
             "same repeat, timed in alternation, which cancels drift of the machine). Embree's own cells are the "
             "reference: their 'Mrays/s chg' is the machine's drift between the runs, not a verdict.\n"
           : "The verdict tests 'Mrays/s chg' (--raw).\n";
  s += fmt::format("Reported: p < {} (two-sided Mann-Whitney U over the per-repeat times) AND a change of at least "
                   "{:.1f}% ({}): {} cell{}",
                   opt.alpha, r.threshold_pct,
                   r.threshold_pct > opt.min_effect_pct
                       ? fmt::format("the noise floor, above --min-effect {}%", opt.min_effect_pct)
                       : std::string("--min-effect"),
                   r.significant, r.significant == 1 ? "" : "s");
  if (opt.fail_above_pct >= 0)
    s += fmt::format("; {} regression{} slower than {}%", r.regressions, r.regressions == 1 ? "" : "s", opt.fail_above_pct);
  s += ".\n";
  auto noise = [](double v) { return std::isfinite(v) ? fmt::format("{:.1f}%", v) : std::string("n/a"); };
  s += fmt::format("Noise floor (spread of Embree's own speed over its timings with each structure within a run, median "
                   "over scene x ray set x threads): A {}, B {}{}.\n",
                   noise(r.noise_a_pct), noise(r.noise_b_pct),
                   opt.noise_floor ? "" : " (not applied: --no-noise-floor)");
  if (r.untestable > 0) {
    size_t m = 0, n = 0;
    for (const auto& c : r.cells)
      if (!c.testable) m = c.repeats_a, n = c.repeats_b;
    s += fmt::format("warning: {} cell{} cannot reach significance: with {} and {} repeats the smallest p the test can "
                     "give is {:.3g} (not below alpha {}); bench with more --repeats (5 and 5 give 0.0079)\n",
                     r.untestable, r.untestable == 1 ? "" : "s", m, n, mann_whitney_min_p(m, n), opt.alpha);
  }
  return s;
}

}  // namespace raylab
