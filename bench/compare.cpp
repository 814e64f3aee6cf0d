#include "bench/compare.h"

#include <algorithm>
#include <cmath>
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

namespace {

using CellKey = std::tuple<std::string, std::string, std::string, int>;

std::map<CellKey, nlohmann::json> cells_of(const nlohmann::json& doc, const char* which) {
  if (!doc.is_object() || !doc.contains("records") || !doc["records"].is_array())
    throw std::invalid_argument(fmt::format("{}: not a raylab report (no \"records\" array)", which));
  if (doc.value("command", std::string("bench")) != "bench")
    throw std::invalid_argument(fmt::format("{}: a '{}' report; compare reads bench reports (raylab bench --json)", which,
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

}  // namespace

CompareResult compare_bench_reports(const nlohmann::json& a, const nlohmann::json& b, const CompareOptions& opt) {
  const auto ca = cells_of(a, "first report"), cb = cells_of(b, "second report");
  CompareResult res;
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
    c.normalized = opt.normalize_by_embree && ea > 0 && eb > 0 && !is_reference_spec(c.accel);
    auto times = [&](const nlohmann::json& r, double embree_seconds) {
      std::vector<double> t;
      if (r.contains("trace_s") && r["trace_s"].is_array())
        for (const auto& v : r["trace_s"])
          if (v.is_number()) t.push_back(c.normalized ? v.get<double>() / embree_seconds : v.get<double>());
      return t;
    };
    // The speed change on the same footing as the test: ratio to Embree when normalised.
    c.speed_change_pct = c.normalized ? change_pct(number(ra, "ratio_to_embree"), number(rb, "ratio_to_embree"))
                                      : change_pct(c.mrays_a, c.mrays_b);
    const auto ta = times(ra, ea), tb = times(rb, eb);
    if (ta.size() >= 2 && tb.size() >= 2) {
      c.p_value = mann_whitney_p(ta, tb);
      c.significant = *c.p_value < opt.alpha && std::fabs(c.speed_change_pct) >= opt.min_change_pct;
    }
    const bool testable = c.p_value.has_value();
    c.regression = opt.fail_above_pct >= 0 && -c.speed_change_pct > opt.fail_above_pct && (!testable || c.significant);
    res.regressions += c.regression;
    res.cells.push_back(c);
  }
  for (const auto& [key, rb] : cb) res.only_in_b += ca.count(key) == 0;
  return res;
}

nlohmann::json compare_result_json(const CompareResult& r, const CompareOptions& opt) {
  nlohmann::json cells = nlohmann::json::array();
  for (const auto& c : r.cells)
    cells.push_back({{"scene", c.scene},
                     {"accel", c.accel},
                     {"ray_set", c.ray_set},
                     {"threads", c.threads},
                     {"mrays_per_s_a", c.mrays_a},
                     {"mrays_per_s_b", c.mrays_b},
                     {"speed_change_pct", c.speed_change_pct},
                     {"build_ms_a", c.build_ms_a},
                     {"build_ms_b", c.build_ms_b},
                     {"build_change_pct", c.build_change_pct},
                     {"bytes_a", c.bytes_a},
                     {"bytes_b", c.bytes_b},
                     {"bytes_change_pct", c.bytes_change_pct},
                     {"normalized_by_embree", c.normalized},
                     {"p_value", c.p_value ? nlohmann::json(*c.p_value) : nlohmann::json(nullptr)},
                     {"significant", c.significant},
                     {"regression", c.regression}});
  return {{"schema_version", kReportSchemaVersion},
          {"command", "compare"},
          {"alpha", opt.alpha},
          {"min_change_pct", opt.min_change_pct},
          {"normalize_by_embree", opt.normalize_by_embree},
          {"fail_above_pct", opt.fail_above_pct >= 0 ? nlohmann::json(opt.fail_above_pct) : nlohmann::json(nullptr)},
          {"only_in_a", r.only_in_a},
          {"only_in_b", r.only_in_b},
          {"regressions", r.regressions},
          {"cells", cells}};
}

std::string format_compare_table(const CompareResult& r, const CompareOptions& opt, bool colour) {
  std::string s = fmt::format("{:<24} {:<24} {:<8} {:>3} {:>10} {:>10} {:>8} {:>8}  {:<11} {:>9} {:>9}\n", "scene",
                              "accel", "rays", "thr", "Mrays/s A", "Mrays/s B", "speed", "p", "verdict", "build",
                              "bytes");
  auto cut = [](const std::string& v, size_t n) { return v.size() > n ? v.substr(0, n - 1) + "~" : v; };
  auto pct = [](double v) { return fmt::format("{:+.1f}%", v); };
  for (const auto& c : r.cells) {
    std::string verdict = !c.p_value ? "no repeats" : !c.significant ? "~same" : c.speed_change_pct < 0 ? "slower" : "faster";
    if (c.regression) verdict = "REGRESSION";
    const char* on = "";
    if (colour && c.significant) on = c.speed_change_pct < 0 ? "\033[31m" : "\033[32m";
    if (colour && c.regression) on = "\033[1;31m";
    s += fmt::format("{:<24} {:<24} {:<8} {:>3} {:>10.2f} {:>10.2f} {}{:>8}{} {:>8}  {}{:<11}{} {:>9} {:>9}\n",
                     cut(c.scene, 24), cut(c.accel, 24), c.ray_set, c.threads, c.mrays_a, c.mrays_b, on,
                     pct(c.speed_change_pct), *on ? "\033[0m" : "", c.p_value ? fmt::format("{:.3g}", *c.p_value) : "n/a",
                     on, verdict, *on ? "\033[0m" : "", pct(c.build_change_pct), pct(c.bytes_change_pct));
  }
  s += fmt::format("{} matching cells, {} only in A, {} only in B; significance: two-sided Mann-Whitney U over the "
                   "per-repeat trace times{}, alpha {}, changes under {}% ignored",
                   r.cells.size(), r.only_in_a, r.only_in_b,
                   opt.normalize_by_embree ? " divided by the same cell's Embree time (speed = change in ratio to Embree)" : "",
                   opt.alpha, opt.min_change_pct);
  if (opt.fail_above_pct >= 0)
    s += fmt::format("; {} regression{} slower than {}%", r.regressions, r.regressions == 1 ? "" : "s", opt.fail_above_pct);
  return s + "\n";
}

}  // namespace raylab
