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

struct Inputs {
  json bench_header;
  std::vector<json> bench, verify, stress;
  std::vector<fs::path> heatmaps, structures, extra_charts;
};

Inputs read_inputs(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw std::invalid_argument(fmt::format("{}: not a directory", dir.string()));
  Inputs in;
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir))
    if (e.is_regular_file() && e.path().extension() == ".json") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  for (const auto& f : files) {
    const json j = read_report(f);
    const std::string cmd = str(j, "command");
    const std::string stem = f.stem().string();
    auto add = [&](std::vector<json>& to) {
      for (const auto& r : j["records"]) to.push_back(r);
    };
    // The matrix is bench.json (make bench) or any bench report when there is no such file;
    // sweeps and scaling are charted by bench/plot.py, not mixed into the leaderboard.
    if (cmd == "bench" && (stem == "bench" || (stem.rfind("sweep", 0) != 0 && stem.rfind("scaling", 0) != 0))) {
      if (in.bench.empty() || stem == "bench") {
        if (stem == "bench") in.bench.clear();
        in.bench_header = j;
        in.bench_header.erase("records");
        add(in.bench);
      }
    } else if (cmd == "verify") {
      add(in.verify);
    } else if (cmd == "stress") {
      add(in.stress);
    }
  }
  if (in.bench.empty())
    throw std::invalid_argument(fmt::format("{}: no bench report (bench.json or another `raylab bench -o` file)", dir.string()));
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

std::string provenance(const json& h) {
  auto field = [&](const char* k) {
    const auto it = h.find(k);
    if (it == h.end() || it->is_null()) return std::string("?");
    return it->is_string() ? it->get<std::string>() : it->dump();
  };
  return fmt::format("Machine: {} ({} hardware threads). Embree {} (ISA {}). Compiler: {}; flags: {}. Revision of the "
                     "binary: {}. Run: {}, preset {}.",
                     field("cpu"), field("hardware_threads"), field("embree_version"), field("embree_isa"),
                     field("compiler"), field("flags"), field("revision"), field("date"), field("preset"));
}

void leaderboard(Doc& doc, const std::vector<json>& recs, const std::string& prov) {
  std::vector<std::string> sets, scenes, accels;
  for (const auto& r : recs) {
    push_unique(sets, str(r, "ray_set"));
    push_unique(scenes, str(r, "scene"));
    push_unique(accels, str(r, "accel"));
  }
  doc.heading("leaderboard", "Leaderboard: speed relative to Embree");
  doc.para(fmt::format(
      "Per ray set, one thread: each structure's rays per second divided by single-ray Embree's on the same rays in "
      "the same run, geometric mean over the {} benchmark scene(s) ({}). Bars: median of the repeats; whiskers: the "
      "slowest and fastest repeat (geometric mean of each over the scenes). 'best Embree' divides by the fastest "
      "Embree mode of the run instead. Structures measured on fewer scenes are marked; their mean is over those only.",
      scenes.size(), fmt::join(scenes, ", ")));
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
      if ((x.n == scenes.size()) != (y.n == scenes.size())) return x.n == scenes.size();
      return x.ratio > y.ratio;
    });
    BarChart c;
    c.id = "chart-leaderboard-" + set;
    c.title = fmt::format("{} rays: speed relative to Embree (1 thread)", set);
    c.x_label = "ratio to single-ray Embree (1 = as fast; geometric mean over scenes)";
    c.reference = 1.0;
    c.reference_label = "Embree";
    std::vector<std::vector<std::string>> table;
    for (const auto& r : rows) {
      const std::string cover = r.n == scenes.size() ? "" : fmt::format(", {} of {} scenes", r.n, scenes.size());
      c.rows.push_back({r.accel, structure_colour(r.accel), r.ratio, r.lo, r.hi,
                        fmt::format("{}x{}", short_number(r.ratio), cover)});
      table.push_back({r.accel, short_number(r.ratio), short_number(r.best),
                       fmt::format("{} - {}", short_number(r.lo), short_number(r.hi)),
                       fmt::format("{} of {}", r.n, scenes.size())});
    }
    // The first ray set's chart and table are the README's headline (scripts/update-readme-results.py).
    const bool headline = set == sets.front();
    if (headline) doc.md += "<!-- headline:begin -->\n";
    doc.chart(c);
    doc.table("table-leaderboard-" + set, {"structure", "ratio to Embree", "ratio to best Embree mode", "min - max over repeats", "scenes"},
              table);
    if (headline) doc.md += prov + "\n<!-- headline:end -->\n\n";
  }
}

void memory_and_build(Doc& doc, const std::vector<json>& recs) {
  // One record per (scene, accel) is enough: memory and build do not depend on the ray set.
  std::map<std::string, std::map<std::string, json>> by;  // accel -> scene -> record
  std::vector<std::string> accels, scenes;
  for (const auto& r : recs) {
    push_unique(accels, str(r, "accel"));
    push_unique(scenes, str(r, "scene"));
    by[str(r, "accel")].emplace(str(r, "scene"), r);
  }
  doc.heading("memory", "Memory, build time and break-even");
  doc.para("Bytes per triangle held by the structure and build time per triangle, geometric mean over the scenes; "
           "break-even: how many rays (of the first ray set, one thread) a structure must trace before its build plus "
           "trace time is below Embree's, on the largest scene (a model from the measured build time and speed, "
           "t = build + rays / speed, not a measurement).");
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
    const double b = geomean(bpt), n = geomean(npt);
    mem.rows.push_back({a, structure_colour(a), b, kNaN, kNaN, short_number(b) + " B"});
    build.rows.push_back({a, structure_colour(a), n, kNaN, kNaN, short_number(n) + " ns"});
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
    table.push_back({a, short_number(b), short_number(n), breakeven});
  }
  doc.chart(mem);
  doc.chart(build);
  doc.table("table-memory", {"structure", "bytes / triangle", "build ns / triangle", fmt::format("vs Embree on {}", largest)},
            table);
}

void accuracy(Doc& doc, const std::vector<json>& verify, const std::vector<json>& stress) {
  doc.heading("accuracy", "Accuracy");
  if (verify.empty() && stress.empty()) {
    doc.para("No verify or stress reports in this directory.");
    return;
  }
  doc.para("From raylab verify (every disagreement with Embree decided by the exact oracle: 'wrong' = the structure "
           "erred) and raylab stress (rays aimed at closed meshes from outside: a leak passes through).");
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
                               "max relative distance error", "leaks per million"},
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
           "per ray; geometric mean over scenes and ray sets, one thread. Embree exposes no per-ray counters.");
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
    const double n = geomean(nodes[a]), t = geomean(tris[a]), time = geomean(ns[a]);
    cn.rows.push_back({a, structure_colour(a), n, kNaN, kNaN, short_number(n)});
    ct.rows.push_back({a, structure_colour(a), t, kNaN, kNaN, short_number(t)});
    table.push_back({a, short_number(time), short_number(n), short_number(t)});
  }
  doc.chart(cn);
  doc.chart(ct);
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
    doc.para("Per-pixel cost (raylab render --aov): where each structure spends its work, one shared colour scale "
             "per sheet.");
    images(in.heatmaps, "heatmap");
  }
  if (!in.structures.empty()) {
    doc.para("The structures themselves (raylab show): boxes, split planes and occupied cells over the scene, "
             "coloured by depth.");
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
footer{margin-top:3em;font-size:0.8em;color:#555;border-top:1px solid #ddd;padding-top:1em})";

}  // namespace

Runner add_report(CLI::App& app) {
  struct Opts {
    std::string dir, out = "report.html", md;
  };
  auto o = std::make_shared<Opts>();
  CLI::App* cmd = app.add_subcommand(
      "report", "one self-contained HTML page (and Markdown) from the bench / verify / stress JSON in a directory");
  cmd->add_option("dir", o->dir, "directory with bench.json and optionally verify*.json, stress*.json, heatmaps/, "
                                 "structures/, charts/ (what make bench writes to out/bench)")
      ->required();
  cmd->add_option("-o,--out", o->out, "the HTML page")->capture_default_str();
  cmd->add_option("--md", o->md, "the Markdown version (default: the page's name with .md); its charts are written "
                                 "as SVG files into <name>_files/ next to it");
  return [o]() {
    if (lower_extension_of(o->out) != ".html")
      throw std::invalid_argument(fmt::format("--out {}: the page is written as .html", o->out));
    const fs::path md = o->md.empty() ? fs::path(o->out).replace_extension(".md") : fs::path(o->md);
    if (lower_extension_of(md.string()) != ".md")
      throw std::invalid_argument(fmt::format("--md {}: use a .md file name", md.string()));
    const fs::path dir(o->dir);
    const Inputs in = read_inputs(dir);
    const std::vector<json> recs = single_thread(in.bench);
    const fs::path md_dir = fs::absolute(md).parent_path();
    const std::string files_name = md.stem().string() + "_files";

    Doc doc;
    doc.html = "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>raylab report</title>"
               "<style>" + std::string(kStyle) + "</style></head><body>\n"
               "<h1>raylab: which spatial partitioning wins, by how much, where it fails, and why</h1>\n";
    doc.md = "# raylab report\n\n";
    std::set<std::string> scenes;
    for (const auto& r : recs) scenes.insert(fmt::format("{} ({} triangles)", str(r, "scene"), num(r, "triangles")));
    doc.para(fmt::format("From {} ({} bench records at one thread, {} verify and {} stress records). Scenes: {}.",
                         dir.string(), recs.size(), in.verify.size(), in.stress.size(), fmt::join(scenes, "; ")));
    const std::string prov = provenance(in.bench_header);
    leaderboard(doc, recs, prov);
    memory_and_build(doc, recs);
    accuracy(doc, in.verify, in.stress);
    failures(doc, in.stress);
    why(doc, recs);
    pictures(doc, in, md_dir, dir);
    doc.html += "<footer id=\"provenance\">" + html_escape(prov) + "</footer>\n</body></html>\n";
    doc.md += "\n---\n\n" + prov + "\n";
    // Markdown charts live next to the Markdown file.
    std::string md_text = doc.md;
    for (size_t p = 0; (p = md_text.find("MDDIR", p)) != std::string::npos;) md_text.replace(p, 5, files_name);
    for (const auto& [name, svg] : doc.md_charts) write_file_atomically((md_dir / files_name / name).string(), svg);
    write_file_atomically(md.string(), md_text);
    write_file_atomically(o->out, doc.html);
    std::printf("report: %zu charts, %zu pictures -> %s, %s\n", doc.chart_ids.size(),
                in.heatmaps.size() + in.structures.size(), o->out.c_str(), md.string().c_str());
    return 0;
  };
}

}  // namespace raylab::cli
