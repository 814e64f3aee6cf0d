// `raylab report DIR [-o report.html]`: one self-contained page (charts as
// inline SVG, pictures as PNG data URIs, no scripts, no network) and the
// same content as Markdown, from the JSON that bench, verify and stress
// write (the files `make bench` leaves in out/bench). It leads with the
// answer: a leaderboard per ray set, then memory and build time, accuracy,
// where each structure fails (stress), why (nodes and triangle tests per
// ray), the pictures (cost images, structure pictures), and the machine.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "app/cmd_report_palette.h"
#include "app/cmd_report_svg.h"
#include "app/commands.h"
#include "base/atomic_file.h"

namespace raylab::cli {

namespace {

// A bar chart with its element id, title and axis label (rows added later).
BarChart bar_chart(std::string id, std::string title, std::string x_label) {
  BarChart c;
  c.id = std::move(id);
  c.title = std::move(title);
  c.x_label = std::move(x_label);
  return c;
}

namespace fs = std::filesystem;
using nlohmann::json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

json read_report(const fs::path& p) {
  std::ifstream in(p);
  if (!in) throw std::invalid_argument(fmt::format("cannot read {}", p.string()));
  try {
    json j = json::parse(in);
    if (!j.is_object() || !j.contains("records") || !j["records"].is_array())
      throw std::invalid_argument(fmt::format("{}: not a raylab JSON report (no \"records\" array)", p.string()));
    return j;
  } catch (const json::parse_error& e) {
    throw std::invalid_argument(fmt::format("{}: not valid JSON ({})", p.string(), e.what()));
  }
}

double num(const json& r, const char* key) {
  const auto it = r.find(key);
  return it != r.end() && it->is_number() ? it->get<double>() : kNaN;
}
std::string str(const json& r, const char* key) {
  const auto it = r.find(key);
  return it != r.end() && it->is_string() ? it->get<std::string>() : std::string();
}

double geomean(const std::vector<double>& v) {
  double s = 0.0;
  int n = 0;
  for (double x : v)
    if (std::isfinite(x) && x > 0) s += std::log(x), ++n;
  return n ? std::exp(s / n) : kNaN;
}

std::string base64(const std::string& bytes) {
  static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  size_t i = 0;
  for (; i + 2 < bytes.size(); i += 3) {
    const uint32_t v = (uint8_t(bytes[i]) << 16) | (uint8_t(bytes[i + 1]) << 8) | uint8_t(bytes[i + 2]);
    out += {t[v >> 18], t[(v >> 12) & 63], t[(v >> 6) & 63], t[v & 63]};
  }
  if (i + 1 == bytes.size()) {
    const uint32_t v = uint8_t(bytes[i]) << 16;
    out += {t[v >> 18], t[(v >> 12) & 63], '=', '='};
  } else if (i + 2 == bytes.size()) {
    const uint32_t v = (uint8_t(bytes[i]) << 16) | (uint8_t(bytes[i + 1]) << 8);
    out += {t[v >> 18], t[(v >> 12) & 63], t[(v >> 6) & 63], '='};
  }
  return out;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Both outputs at once: the HTML page and the Markdown text.
struct Doc {
  std::string html, md;
  std::vector<std::pair<std::string, std::string>> md_charts;  // (file name, svg) written next to the Markdown
  std::vector<std::string> chart_ids;

  void heading(const std::string& id, const std::string& text) {
    html += fmt::format("<h2 id=\"{}\">{}</h2>\n", id, html_escape(text));
    md += "\n## " + text + "\n\n";
  }
  void para(const std::string& text) {
    html += "<p>" + html_escape(text) + "</p>\n";
    md += text + "\n\n";
  }
  void chart(const BarChart& c) {
    if (c.rows.empty()) return;
    html += "<figure>" + svg_bar_chart(c) + "</figure>\n";
    md_charts.push_back({c.id + ".svg", svg_bar_chart(c)});
    md += fmt::format("![{}](MDDIR/{}.svg)\n\n", c.title, c.id);
    chart_ids.push_back(c.id);
  }
  // A table: header cells, rows of cells; `colours` (optional) tints a cell's background.
  void table(const std::string& id, const std::vector<std::string>& head, const std::vector<std::vector<std::string>>& rows,
             const std::vector<std::vector<std::string>>& colours = {}) {
    html += fmt::format("<table id=\"{}\"><thead><tr>", id);
    for (const auto& h : head) html += "<th>" + html_escape(h) + "</th>";
    html += "</tr></thead><tbody>\n";
    md += "|";
    for (const auto& h : head) md += " " + h + " |";
    md += "\n|";
    for (size_t i = 0; i < head.size(); ++i) md += i == 0 ? "---|" : "---:|";
    md += "\n";
    for (size_t r = 0; r < rows.size(); ++r) {
      html += "<tr>";
      md += "|";
      for (size_t c = 0; c < rows[r].size(); ++c) {
        const std::string bg = r < colours.size() && c < colours[r].size() ? colours[r][c] : "";
        html += (bg.empty() ? "<td>" : "<td style=\"background:" + bg + "\">") + html_escape(rows[r][c]) + "</td>";
        md += " " + rows[r][c] + " |";
      }
      html += "</tr>\n";
      md += "\n";
    }
    html += "</tbody></table>\n";
    md += "\n";
  }
};

// One JSON file of the folder and what the page did with it.
struct SourceFile {
  std::string path;     // relative to the folder
  std::string command;  // the report's "command"
  size_t records = 0;
  std::string use;      // what the page did with it
};

// The header fields that name the binary and the machine behind a report;
// records whose fields differ are not put on one page unless --mix.
std::string binary_of(const json& h) {
  auto f = [&](const char* k) { return h.contains(k) && h[k].is_string() ? h[k].get<std::string>() : std::string(); };
  return fmt::format("revision {}, {}, flags {}", f("revision").empty() ? "not recorded" : f("revision"),
                     f("compiler"), f("flags"));
}
std::string machine_of(const json& h) {
  const std::string cpu = h.contains("cpu") && h["cpu"].is_string() ? h["cpu"].get<std::string>() : "";
  return fmt::format("{} ({} hardware threads)", cpu, h.contains("hardware_threads") ? h["hardware_threads"].dump() : "");
}

struct Inputs {
  json bench_header;  // the first leaderboard file's header (the machine and binary: all files agree unless mixed)
  std::vector<json> bench, verify, stress;
  std::vector<SourceFile> files;
  // Distinct binaries and machines among the files used, each with the files it made.
  std::vector<std::pair<std::string, std::vector<std::string>>> binaries, machines;
  std::vector<fs::path> heatmaps, structures, extra_charts;
  bool mixed() const { return binaries.size() > 1 || machines.size() > 1; }
};

void note_origin(std::vector<std::pair<std::string, std::vector<std::string>>>& list, const std::string& key,
                 const std::string& file) {
  for (auto& [k, files] : list)
    if (k == key) {
      files.push_back(file);
      return;
    }
  list.push_back({key, {file}});
}

// Every JSON report under `dir`, sub-folders included (the study writes
// cells/ and equal_time/); hidden folders are skipped.
std::vector<fs::path> json_files_under(const fs::path& dir) {
  std::vector<fs::path> files;
  for (auto it = fs::recursive_directory_iterator(dir); it != fs::recursive_directory_iterator(); ++it) {
    const std::string name = it->path().filename().string();
    if (it->is_directory() && !name.empty() && name[0] == '.') {
      it.disable_recursion_pending();
      continue;
    }
    if (it->is_regular_file() && it->path().extension() == ".json") files.push_back(it->path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

// A bench report charted by bench/plot.py rather than put on the leaderboard:
// parameter sweeps and scaling series (their scenes and variants would skew
// the geometric means).
bool is_series_file(const fs::path& p) {
  const std::string stem = p.stem().string();
  return stem.rfind("sweep", 0) == 0 || stem.rfind("scaling", 0) == 0;
}

Inputs read_inputs(const fs::path& dir, bool mix) {
  if (!fs::is_directory(dir)) throw std::invalid_argument(fmt::format("{}: not a directory", dir.string()));
  Inputs in;
  std::vector<std::pair<fs::path, json>> docs;
  for (const auto& f : json_files_under(dir)) docs.push_back({f, read_report(f)});
  auto rel = [&](const fs::path& p) { return fs::relative(p, dir).lexically_normal().string(); };
  // Cell files a merged report holds (merge_records.py's "merged_from"): read once, through the merged file.
  std::map<std::string, std::string> merged_into;
  for (const auto& [f, j] : docs)
    if (j.contains("merged_from") && j["merged_from"].is_array())
      for (const auto& m : j["merged_from"])
        if (m.is_string()) merged_into[rel(f.parent_path() / m.get<std::string>())] = rel(f);
  std::map<std::tuple<std::string, std::string, std::string, double>, std::string> cell_file;  // bench cell -> file
  for (const auto& doc : docs) {
    const fs::path& f = doc.first;  // not a structured binding: the lambdas below capture these
    const json& j = doc.second;
    SourceFile sf{rel(f), str(j, "command"), j["records"].size(), ""};
    const auto merged = merged_into.find(sf.path);
    auto origin = [&] {
      note_origin(in.binaries, binary_of(j), sf.path);
      note_origin(in.machines, machine_of(j), sf.path);
    };
    if (merged != merged_into.end()) {
      sf.use = "merged into " + merged->second + " (read there)";
    } else if (sf.command == "bench" && is_series_file(f)) {
      sf.use = "a sweep or scaling series: charted by bench/plot.py (charts/), not on the leaderboard";
      origin();
    } else if (sf.command == "bench") {
      for (const auto& r : j["records"]) {
        const auto key = std::make_tuple(str(r, "scene"), str(r, "accel"), str(r, "ray_set"), num(r, "threads"));
        const auto [it, fresh] = cell_file.emplace(key, sf.path);
        if (!fresh)
          throw std::invalid_argument(fmt::format(
              "{} and {} both time {} on {} ({} rays, {} threads): keep one of them in the folder",
              it->second, sf.path, std::get<1>(key), std::get<0>(key), std::get<2>(key), std::get<3>(key)));
        in.bench.push_back(r);
      }
      if (in.bench_header.is_null()) {
        in.bench_header = j;
        in.bench_header.erase("records");
      }
      sf.use = "leaderboard, memory, work per ray";
      origin();
    } else if (sf.command == "verify" || sf.command == "stress") {
      for (const auto& r : j["records"]) (sf.command == "verify" ? in.verify : in.stress).push_back(r);
      sf.use = sf.command == "verify" ? "accuracy" : "accuracy, stress scenarios";
      origin();
    } else {
      sf.use = fmt::format("not used (a '{}' report)", sf.command.empty() ? "?" : sf.command);
    }
    in.files.push_back(sf);
  }
  if (in.bench.empty())
    throw std::invalid_argument(fmt::format("{}: no bench report (bench.json or another `raylab bench -o` file)", dir.string()));
  if (in.mixed() && !mix) {
    auto describe = [](const auto& list) {
      std::vector<std::string> parts;
      for (const auto& [k, files] : list) parts.push_back(fmt::format("{} ({})", k, files.front()));
      return fmt::format("{}", fmt::join(parts, " vs "));
    };
    throw std::invalid_argument(fmt::format(
        "{}: the reports come from different {}: {}; their figures do not compare (give --mix to put them on one "
        "page anyway, which the page then says)",
        dir.string(), in.binaries.size() > 1 ? "binaries" : "machines",
        in.binaries.size() > 1 ? describe(in.binaries) : describe(in.machines)));
  }
  auto pngs = [&](const char* sub, std::vector<fs::path>& to) {
    if (!fs::is_directory(dir / sub)) return;
    for (const auto& e : fs::directory_iterator(dir / sub))
      if (e.path().extension() == ".png") to.push_back(e.path());
    std::sort(to.begin(), to.end());
  };
  pngs("heatmaps", in.heatmaps);
  pngs("structures", in.structures);
  if (fs::is_directory(dir / "charts"))
    for (const auto& e : fs::directory_iterator(dir / "charts"))
      if (e.path().extension() == ".svg") in.extra_charts.push_back(e.path());
  std::sort(in.extra_charts.begin(), in.extra_charts.end());
  return in;
}

// The files the page was made from: the merged cell files and the unused
// files of one top-level folder are one row each.
void files_read(Doc& doc, const Inputs& in) {
  std::vector<std::vector<std::string>> rows;
  std::vector<size_t> counts;                // files per row
  std::vector<std::string> firsts;           // a row's first file
  std::map<std::string, size_t> group_row;   // "use|top folder" -> row
  for (const auto& f : in.files) {
    const bool grouped = f.use.rfind("merged into", 0) == 0 || f.use.rfind("not used", 0) == 0;
    const std::string top = fs::path(f.path).begin()->string();
    const std::string key = f.use + "|" + top;
    const auto it = grouped ? group_row.find(key) : group_row.end();
    if (it == group_row.end()) {
      if (grouped) group_row[key] = rows.size();
      rows.push_back({f.path, f.command, fmt::format("{}", f.records), f.use});
      counts.push_back(1);
      firsts.push_back(f.path);
      continue;
    }
    auto& row = rows[it->second];
    row[0] = fmt::format("{} files under {}/", ++counts[it->second], top);
    row[2] = fmt::format("{}", std::stoul(row[2]) + f.records);
  }
  doc.heading("files", "Files read");
  doc.para(fmt::format("Every JSON report under the folder, sub-folders included ({} files): bench, verify and stress "
                       "records all count, and a cell timed in two files is refused.",
                       in.files.size()));
  doc.table("table-files", {"file", "command", "records", "used for"}, rows);
}

// Records at one thread (the per-ray comparison); all when there are none.
std::vector<json> single_thread(const std::vector<json>& recs) {
  std::vector<json> one;
  for (const auto& r : recs)
    if (num(r, "threads") == 1) one.push_back(r);
  return one.empty() ? recs : one;
}

template <typename T>
void push_unique(std::vector<T>& v, const T& x) {
  if (std::find(v.begin(), v.end(), x) == v.end()) v.push_back(x);
}

// Where the numbers come from, without placeholders: a field the reports
// do not carry is left out, not printed as "unknown" or "?".
std::string provenance(const Inputs& in) {
  const json& h = in.bench_header;
  auto field = [&](const char* k) {
    const auto it = h.find(k);
    if (it == h.end() || it->is_null()) return std::string();
    const std::string v = it->is_string() ? it->get<std::string>() : it->dump();
    return v == "unknown" || v == "?" ? std::string() : v;
  };
  std::vector<std::string> parts;
  if (in.mixed()) {
    auto list = [](const auto& origins) {
      std::vector<std::string> out;
      for (const auto& [k, files] : origins) out.push_back(fmt::format("{} ({})", k, fmt::join(files, ", ")));
      return fmt::format("{}", fmt::join(out, "; "));
    };
    auto origins = [&](const auto& o, const char* one, const char* many) {
      return o.size() == 1 ? fmt::format("on one {}: {}", one, o.front().first)
                           : fmt::format("{} {}: {}", o.size(), many, list(o));
    };
    parts.push_back(fmt::format("Mixed on request (--mix): {}; {}.", origins(in.binaries, "binary", "binaries"),
                                origins(in.machines, "machine", "machines")));
  } else {
    if (!field("cpu").empty())
      parts.push_back(fmt::format("Machine: {}{}.", field("cpu"),
                                  field("hardware_threads").empty() ? "" : " (" + field("hardware_threads") + " hardware threads)"));
    if (!field("compiler").empty()) parts.push_back(fmt::format("Compiler: {}; flags: {}.", field("compiler"), field("flags")));
    if (!field("revision").empty()) parts.push_back(fmt::format("Revision of the binary: {}.", field("revision")));
  }
  if (!field("embree_version").empty())
    parts.push_back(fmt::format("Embree {}{}.", field("embree_version"),
                                field("embree_isa").empty() ? "" : " (ISA " + field("embree_isa") + ")"));
  std::string run = field("date").empty() ? "" : "Run: " + field("date");
  if (!field("preset").empty()) run += (run.empty() ? "Preset " : ", preset ") + field("preset");
  if (!run.empty()) parts.push_back(run + ".");
  return fmt::format("{}", fmt::join(parts, " "));
}

// Which scenes each structure was measured on: structures measured on fewer
// scenes than the most get their own charts, since their means are over
// other scenes and do not compare with the rest.
struct Coverage {
  std::vector<std::string> scenes;                        // every scene, in order
  std::map<std::string, std::set<std::string>> scenes_of;  // accel -> its scenes
  explicit Coverage(const std::vector<json>& recs) {
    for (const auto& r : recs) {
      push_unique(scenes, str(r, "scene"));
      scenes_of[str(r, "accel")].insert(str(r, "scene"));
    }
  }
  bool full(const std::string& accel) const {
    const auto it = scenes_of.find(accel);
    return it != scenes_of.end() && it->second.size() == scenes.size();
  }
  std::string note(const std::string& accel) const {
    const auto it = scenes_of.find(accel);
    const size_t n = it == scenes_of.end() ? 0 : it->second.size();
    return full(accel) ? std::string() : fmt::format(" ({} of {} scenes)", n, scenes.size());
  }
};

// A chart of the structures measured on every scene, then (when any) one of
// those measured on fewer, on its own axis.
void charts_by_coverage(Doc& doc, const BarChart& chart, const Coverage& cover) {
  BarChart full = chart, fewer = chart;
  full.rows.clear();
  fewer.rows.clear();
  for (const auto& r : chart.rows) (cover.full(r.label) ? full.rows : fewer.rows).push_back(r);
  doc.chart(full);
  if (fewer.rows.empty()) return;
  fewer.id += "-fewer-scenes";
  fewer.title += ": measured on fewer scenes";
  fewer.subtitle = "each mean is over that structure's own scenes (right), so it does not compare with the chart above";
  doc.chart(fewer);
}

// True when an Embree mode other than the reference ran, so the ratio to the
// best Embree mode can differ from the ratio to Embree.
bool other_embree_modes(const std::vector<json>& recs) {
  for (const auto& r : recs)
    if (!str(r, "best_embree").empty() && str(r, "best_embree") != "embree") return true;
  return false;
}

void leaderboard(Doc& doc, const std::vector<json>& recs, const std::string& prov) {
  std::vector<std::string> sets, accels;
  for (const auto& r : recs) {
    push_unique(sets, str(r, "ray_set"));
    push_unique(accels, str(r, "accel"));
  }
  const Coverage cover(recs);
  const bool best_column = other_embree_modes(recs);
  doc.heading("leaderboard", "Leaderboard: speed relative to Embree");
  doc.para(fmt::format(
      "Per ray set, one thread: each structure's rays per second divided by single-ray Embree's (embree) on the same "
      "rays, timed in alternation with it, repeat by repeat, in the same run (ratio_to_embree), geometric mean over "
      "the {} benchmark scene(s) ({}). Bars from zero: median of the repeats; whiskers: the slowest and fastest repeat (geometric mean of each "
      "over the scenes); the dashed line is Embree.{} Structures measured on fewer scenes are charted apart: their "
      "means are over those scenes only.",
      cover.scenes.size(), fmt::join(cover.scenes, ", "),
      best_column ? " 'ratio to best Embree mode' divides by the fastest Embree mode of the run instead." : ""));
  for (const auto& set : sets) {
    struct Row {
      std::string accel;
      double ratio, lo, hi, best;
      size_t n;
    };
    std::vector<Row> rows;
    for (const auto& a : accels) {
      std::vector<double> ratio, lo, hi, best;
      for (const auto& r : recs) {
        if (str(r, "ray_set") != set || str(r, "accel") != a) continue;
        const double e = num(r, "embree_mrays_per_s");
        ratio.push_back(num(r, "ratio_to_embree"));
        lo.push_back(num(r, "mrays_min") / e);
        hi.push_back(num(r, "mrays_max") / e);
        best.push_back(num(r, "ratio_to_best_embree"));
      }
      if (!ratio.empty()) rows.push_back({a, geomean(ratio), geomean(lo), geomean(hi), geomean(best), ratio.size()});
    }
    // Full coverage first, each group fastest first.
    std::stable_sort(rows.begin(), rows.end(), [&](const Row& x, const Row& y) {
      if (cover.full(x.accel) != cover.full(y.accel)) return cover.full(x.accel);
      return x.ratio > y.ratio;
    });
    BarChart c;
    c.id = "chart-leaderboard-" + set;
    c.title = fmt::format("{} rays: speed relative to Embree (1 thread)", set);
    c.x_label = "ratio_to_embree: Mrays/s over single-ray Embree's (1 = as fast; geometric mean over scenes)";
    c.reference = 1.0;
    c.reference_label = "Embree";
    std::vector<std::vector<std::string>> table;
    for (const auto& r : rows) {
      c.rows.push_back({r.accel, structure_colour(r.accel), r.ratio, r.lo, r.hi,
                        fmt::format("{}x{}", short_number(r.ratio), cover.note(r.accel))});
      std::vector<std::string> row = {r.accel, short_number(r.ratio)};
      if (best_column) row.push_back(short_number(r.best));
      row.push_back(fmt::format("{} - {}", short_number(r.lo), short_number(r.hi)));
      row.push_back(fmt::format("{} of {}", r.n, cover.scenes.size()));
      table.push_back(row);
    }
    std::vector<std::string> head = {"structure", "ratio to Embree"};
    if (best_column) head.push_back("ratio to best Embree mode");
    head.push_back("min - max over repeats");
    head.push_back("scenes");
    // The first ray set's chart and table are the README's headline (scripts/update-readme-results.py).
    const bool headline = set == sets.front();
    if (headline) doc.md += "<!-- headline:begin -->\n";
    charts_by_coverage(doc, c, cover);
    doc.table("table-leaderboard-" + set, head, table);
    if (headline) doc.md += prov + "\n<!-- headline:end -->\n\n";
  }
}

void memory_and_build(Doc& doc, const std::vector<json>& recs) {
  // One record per (scene, accel) is enough: memory and build do not depend on the ray set.
  std::map<std::string, std::map<std::string, json>> by;  // accel -> scene -> record
  std::vector<std::string> accels;
  for (const auto& r : recs) {
    push_unique(accels, str(r, "accel"));
    by[str(r, "accel")].emplace(str(r, "scene"), r);
  }
  const Coverage cover(recs);
  doc.heading("memory", "Memory, build time and break-even");
  doc.para("Bytes per triangle held by the structure and build time per triangle, geometric mean over the scenes "
           "(bars from zero); break-even: how many rays (of the first ray set, one thread) a structure must trace "
           "before its build plus trace time is below Embree's, on the largest scene (a model from the measured build "
           "time and speed, t = build + rays / speed, not a measurement).");
  BarChart mem = bar_chart("chart-memory", "Memory: bytes per triangle",
                           "bytes per triangle (geometric mean over scenes)");
  BarChart build = bar_chart("chart-build", "Build time per triangle",
                             "ns per triangle (median build, geometric mean over scenes)");
  // The largest scene and the first ray set, for the break-even.
  std::string largest;
  double most = -1;
  for (const auto& r : recs)
    if (num(r, "triangles") > most) most = num(r, "triangles"), largest = str(r, "scene");
  const std::string first_set = recs.empty() ? "" : str(recs.front(), "ray_set");
  const json* embree = nullptr;
  for (const auto& r : recs)
    if (str(r, "accel") == "embree" && str(r, "scene") == largest && str(r, "ray_set") == first_set) embree = &r;
  std::vector<std::vector<std::string>> table;
  for (const auto& a : accels) {
    std::vector<double> bpt, npt;
    for (const auto& [scene, r] : by[a]) {
      bpt.push_back(num(r, "bytes_per_triangle"));
      npt.push_back(num(r, "build_ms") * 1e6 / std::max(1.0, num(r, "triangles")));
    }
    // A structure holding nothing (brute) has 0 bytes: its mean is 0, not n/a.
    bool all_zero = true;
    for (double v : bpt) all_zero &= v == 0.0;
    const double b = all_zero ? 0.0 : geomean(bpt), n = geomean(npt);
    mem.rows.push_back({a, structure_colour(a), b, kNaN, kNaN, short_number(b) + " B" + cover.note(a)});
    build.rows.push_back({a, structure_colour(a), n, kNaN, kNaN, short_number(n) + " ns" + cover.note(a)});
    std::string breakeven = "n/a";
    for (const auto& r : recs) {
      if (str(r, "accel") != a || str(r, "scene") != largest || str(r, "ray_set") != first_set || !embree) continue;
      // Embree's speed as timed back to back with this structure (the record's own
      // embree_mrays_per_s), its build time from Embree's record.
      const double be = num(*embree, "build_ms") * 1e-3, se = num(r, "embree_mrays_per_s") * 1e6;
      const double ba = num(r, "build_ms") * 1e-3, sa = num(r, "mrays_per_s") * 1e6;
      if (a == "embree") breakeven = "-";
      else if (!(se > 0 && sa > 0)) breakeven = "n/a";
      else if (ba <= be && sa >= se) breakeven = "always ahead";
      else if (ba >= be && sa <= se) breakeven = "never";
      else {
        const double rays = (ba - be) / (1.0 / se - 1.0 / sa);
        breakeven = sa > se ? fmt::format("ahead after {} rays", short_number(rays))
                            : fmt::format("ahead below {} rays", short_number(rays));
      }
    }
    table.push_back({a, short_number(b), short_number(n), breakeven, fmt::format("{} of {}", by[a].size(), cover.scenes.size())});
  }
  charts_by_coverage(doc, mem, cover);
  charts_by_coverage(doc, build, cover);
  doc.table("table-memory",
            {"structure", "bytes / triangle", "build ns / triangle", fmt::format("vs Embree on {}", largest), "scenes"},
            table);
}

void accuracy(Doc& doc, const std::vector<json>& verify, const std::vector<json>& stress) {
  doc.heading("accuracy", "Accuracy");
  if (verify.empty() && stress.empty()) {
    doc.para("No verify or stress reports in this directory.");
    return;
  }
  doc.para("From raylab verify (hits compared with robust Embree, embree:robust=1; every disagreement decided by the "
           "exact oracle: 'wrong' = the structure erred; the distance column is the largest relative difference from "
           "Embree's distance where both hit, Embree's own rounding included) and raylab stress (rays aimed at closed meshes from outside: a leak passes through).");
  struct Acc {
    double rays = 0, wrong = 0, disagree = 0, ties = 0, embree_wrong = 0, occl = 0, terr = 0, leak_rays = 0, leaks = 0;
  };
  std::map<std::string, Acc> acc;
  std::vector<std::string> order;
  for (const auto& r : verify) {
    Acc& a = acc[str(r, "accel")];
    push_unique(order, str(r, "accel"));
    auto add = [&](double& to, const char* k) { if (std::isfinite(num(r, k))) to += num(r, k); };
    add(a.rays, "rays");
    add(a.wrong, "raylab_wrong");
    add(a.disagree, "hit_miss_disagree");
    add(a.disagree, "prim_disagree");
    add(a.ties, "ties");
    add(a.embree_wrong, "embree_wrong");
    add(a.occl, "occlusion_disagree");
    if (std::isfinite(num(r, "max_rel_t_err"))) a.terr = std::max(a.terr, num(r, "max_rel_t_err"));
  }
  for (const auto& r : stress) {
    Acc& a = acc[str(r, "accel")];
    push_unique(order, str(r, "accel"));
    if (std::isfinite(num(r, "leak_rays"))) a.leak_rays += num(r, "leak_rays");
    if (std::isfinite(num(r, "leaks"))) a.leaks += num(r, "leaks");
  }
  std::vector<std::vector<std::string>> rows, colours;
  for (const auto& name : order) {
    const Acc& a = acc[name];
    const std::string lpm = a.leak_rays > 0 ? short_number(a.leaks / a.leak_rays * 1e6) : "n/a";
    rows.push_back({name, a.rays > 0 ? fmt::format("{:.0f}", a.rays) : "n/a", fmt::format("{:.0f}", a.wrong),
                    fmt::format("{:.0f}", a.disagree), fmt::format("{:.0f}", a.ties), fmt::format("{:.0f}", a.occl),
                    a.rays > 0 ? short_number(a.terr) : "n/a", lpm});
    const std::string bad = "#f4c7c3", good = "";
    colours.push_back({"", "", a.wrong > 0 ? bad : good, "", "", a.occl > 0 ? bad : good, "", a.leaks > 0 ? bad : good});
  }
  doc.table("table-accuracy", {"structure", "rays verified", "wrong hits", "disagreements", "ties", "occlusion contradictions",
                               "max relative distance difference from Embree", "leaks per million"},
            rows, colours);
}

void failures(Doc& doc, const std::vector<json>& stress) {
  doc.heading("failures", "Where each structure fails: stress scenarios");
  if (stress.empty()) {
    doc.para("No stress report in this directory (raylab stress -o DIR/stress.json).");
    return;
  }
  std::vector<std::string> scenarios, accels;
  std::map<std::pair<std::string, std::string>, json> cell;
  for (const auto& r : stress) {
    const std::string sc = str(r, "scenario").empty() ? str(r, "scene") : str(r, "scenario");
    push_unique(scenarios, sc);
    push_unique(accels, str(r, "accel"));
    cell[{str(r, "accel"), sc}] = r;
  }
  doc.para("Status of every structure on every scenario (ok; slow = slower than its budget; anything else is a "
           "failure), with leaks per million where the scenario counts leaks.");
  std::vector<std::string> head = {"structure"};
  head.insert(head.end(), scenarios.begin(), scenarios.end());
  std::vector<std::vector<std::string>> rows, colours;
  for (const auto& a : accels) {
    std::vector<std::string> row = {a}, col = {""};
    for (const auto& sc : scenarios) {
      const auto it = cell.find({a, sc});
      if (it == cell.end()) {
        row.push_back("");
        col.push_back("");
        continue;
      }
      const json& r = it->second;
      std::string status = str(r, "status");
      if (status.empty()) status = r.value("ok", false) ? "ok" : "failed";
      const double leaks = num(r, "leaks_per_million");
      if (std::isfinite(leaks) && leaks > 0) status += fmt::format(" ({} ppm)", short_number(leaks));
      row.push_back(status);
      col.push_back(status == "ok" ? "#d5f0d5" : status.rfind("slow", 0) == 0 ? "#fbe7b5" : "#f4c7c3");
    }
    rows.push_back(row);
    colours.push_back(col);
  }
  doc.table("table-stress", head, rows, colours);
}

void why(Doc& doc, const std::vector<json>& recs) {
  doc.heading("why", "Why: work per ray");
  doc.para("Nodes (or grid cells) visited and triangle tests per ray from the instrumented kernels, next to the time "
           "per ray; geometric mean over scenes and ray sets, one thread, bars from zero. Embree exposes no per-ray "
           "counters (n/a).");
  const Coverage cover(recs);
  std::vector<std::string> accels;
  std::map<std::string, std::vector<double>> nodes, tris, ns;
  for (const auto& r : recs) {
    const std::string a = str(r, "accel");
    push_unique(accels, a);
    nodes[a].push_back(num(r, "nodes_per_ray"));
    tris[a].push_back(num(r, "tris_per_ray"));
    ns[a].push_back(1e3 / num(r, "mrays_per_s"));
  }
  BarChart cn = bar_chart("chart-nodes-per-ray", "Nodes or cells visited per ray", "per ray (geometric mean)");
  BarChart ct = bar_chart("chart-tris-per-ray", "Triangle tests per ray", "per ray (geometric mean)");
  std::vector<std::vector<std::string>> table;
  for (const auto& a : accels) {
    // Counted zero everywhere (brute visits no node) is 0, not a missing figure.
    bool zero_nodes = true;
    for (double v : nodes[a]) zero_nodes &= v == 0.0;
    const double n = zero_nodes ? 0.0 : geomean(nodes[a]), t = geomean(tris[a]), time = geomean(ns[a]);
    cn.rows.push_back({a, structure_colour(a), n, kNaN, kNaN, short_number(n) + cover.note(a)});
    ct.rows.push_back({a, structure_colour(a), t, kNaN, kNaN, short_number(t) + cover.note(a)});
    table.push_back({a, short_number(time), short_number(n), short_number(t)});
  }
  charts_by_coverage(doc, cn, cover);
  charts_by_coverage(doc, ct, cover);
  doc.table("table-why", {"structure", "ns per ray", "nodes per ray", "triangle tests per ray"}, table);
}

void pictures(Doc& doc, const Inputs& in, const fs::path& md_dir, const fs::path& dir) {
  if (in.heatmaps.empty() && in.structures.empty() && in.extra_charts.empty()) return;
  doc.heading("pictures", "Pictures");
  auto images = [&](const std::vector<fs::path>& files, const char* cls) {
    for (const auto& f : files) {
      doc.html += fmt::format("<figure class=\"{}\"><img alt=\"{}\" src=\"data:image/png;base64,{}\"/><figcaption>{}</figcaption></figure>\n",
                              cls, html_escape(f.stem().string()), base64(slurp(f)), html_escape(f.stem().string()));
      doc.md += fmt::format("![{}]({})\n\n", f.stem().string(), fs::relative(f, md_dir).string());
    }
  };
  if (!in.heatmaps.empty()) {
    doc.para("Per-pixel cost (raylab render --aov): where each structure spends its work; each sheet's legend says "
             "its colour scale (by default one log scale for all its tiles, so one costly structure does not wash "
             "out the others).");
    images(in.heatmaps, "heatmap");
  }
  if (!in.structures.empty()) {
    doc.para("The structures themselves (raylab show): boxes, split planes and occupied cells over the scene, "
             "coloured by depth (each picture's legend gives the colours).");
    images(in.structures, "structure");
  }
  if (!in.extra_charts.empty()) {
    doc.para(fmt::format("Charts from bench/plot.py ({}/charts): sweeps, scaling, speed against memory.", dir.string()));
    for (const auto& f : in.extra_charts) {
      std::string svg = slurp(f);
      const auto at = svg.find("<svg");
      if (at == std::string::npos) continue;
      doc.html += "<figure class=\"plot\">" + svg.substr(at) + "</figure>\n";
      doc.md += fmt::format("![{}]({})\n\n", f.stem().string(), fs::relative(f, md_dir).string());
    }
  }
}

const char* kStyle = R"(body{font-family:sans-serif;max-width:980px;margin:2em auto;padding:0 1em;color:#222}
h1{font-size:1.6em}h2{margin-top:2em;border-bottom:1px solid #ddd}
table{border-collapse:collapse;margin:1em 0;font-size:0.9em}td,th{border:1px solid #ccc;padding:3px 8px;text-align:right}
td:first-child,th:first-child{text-align:left}figure{margin:1em 0}img{max-width:100%}
figure svg{max-width:100%;height:auto}figure.structure{display:inline-block;width:46%;margin:0.5em 1%;vertical-align:top}
footer{margin-top:3em;font-size:0.8em;color:#555;border-top:1px solid #ddd;padding-top:1em}
.mixed{background:#fbe7b5;border:1px solid #d9a400;padding:0.6em 1em;font-weight:bold})";

}  // namespace

Runner add_report(CLI::App& app) {
  struct Opts {
    std::string dir, out = "report.html", md;
    bool mix = false;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "report", "one self-contained HTML page (and Markdown) from every bench / verify / stress JSON report in a folder");
  cmd->add_option("dir", o->dir, "folder with the JSON reports, read recursively (bench, verify and stress records all "
                                 "count), plus heatmaps/, structures/, charts/ (what make bench writes to out/bench)")
      ->required();
  cmd->add_option("-o,--out", o->out, "the HTML page (its directory must exist)")->capture_default_str();
  cmd->add_option("--md", o->md, "the Markdown version (default: the page's name with .md); its charts are written "
                                 "as SVG files into <name>_files/ next to it (that folder is created)");
  cmd->add_flag("--mix", o->mix,
                "put reports from different binaries or machines on one page (refused otherwise); the page says so");
  return [o]() {
    if (lower_extension_of(o->out) != ".html")
      throw std::invalid_argument(fmt::format("-o {}: the page is written as .html", o->out));
    check_output_path(o->out);
    const fs::path md = o->md.empty() ? fs::path(o->out).replace_extension(".md") : fs::path(o->md);
    if (lower_extension_of(md.string()) != ".md")
      throw std::invalid_argument(fmt::format("--md {}: use a .md file name", md.string()));
    check_output_path(md.string(), "--md");
    const fs::path dir(o->dir);
    const Inputs in = read_inputs(dir, o->mix);
    const std::vector<json> recs = single_thread(in.bench);
    const fs::path md_dir = fs::absolute(md).parent_path();
    const std::string files_name = md.stem().string() + "_files";

    Doc doc;
    doc.html = "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>raylab report</title>"
               "<style>" + std::string(kStyle) + "</style></head><body>\n"
               "<h1>raylab: which spatial partitioning wins, by how much, where it fails, and why</h1>\n";
    doc.md = "# raylab report\n\n";
    const std::string prov = provenance(in);
    if (in.mixed()) {
      doc.html += "<p class=\"mixed\" id=\"mixed\">" + html_escape(prov) + "</p>\n";
      doc.md += "**" + prov + "**\n\n";
    }
    std::set<std::string> scenes;
    for (const auto& r : recs) scenes.insert(fmt::format("{} ({} triangles)", str(r, "scene"), num(r, "triangles")));
    doc.para(fmt::format("From {}: {} bench records at one thread, {} verify and {} stress records, from {} JSON "
                         "file(s) listed at the end. Scenes: {}.",
                         dir.string(), recs.size(), in.verify.size(), in.stress.size(), in.files.size(),
                         fmt::join(scenes, "; ")));
    leaderboard(doc, recs, prov);
    memory_and_build(doc, recs);
    accuracy(doc, in.verify, in.stress);
    failures(doc, in.stress);
    why(doc, recs);
    pictures(doc, in, md_dir, dir);
    files_read(doc, in);
    doc.html += "<footer id=\"provenance\">" + html_escape(prov) + "</footer>\n</body></html>\n";
    doc.md += "\n---\n\n" + prov + "\n";
    // Markdown charts live next to the Markdown file, in <name>_files/ (created: documented).
    std::string md_text = doc.md;
    for (size_t p = 0; (p = md_text.find("MDDIR", p)) != std::string::npos;) md_text.replace(p, 5, files_name);
    if (!doc.md_charts.empty()) {
      std::error_code ec;
      fs::create_directory(md_dir / files_name, ec);
    }
    for (const auto& [name, svg] : doc.md_charts) write_file_atomically((md_dir / files_name / name).string(), svg);
    write_file_atomically(md.string(), md_text);
    write_file_atomically(o->out, doc.html);
    std::printf("report: %zu files read, %zu charts, %zu pictures -> %s, %s\n", in.files.size(), doc.chart_ids.size(),
                in.heatmaps.size() + in.structures.size(), o->out.c_str(), md.string().c_str());
    return 0;
  };
}

}  // namespace raylab::cli
