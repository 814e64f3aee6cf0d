#include "accel/grid/grid_options.h"

#include "accel/core/any_hit_order.h"
#include "accel/core/simd_param.h"
#include "accel/core/triangle_test_param.h"

#include <cmath>
#include <cstdio>

#include <fmt/format.h>

namespace raylab {

std::vector<ParamInfo> grid_param_infos(bool with_res, bool with_top) {
  std::vector<ParamInfo> p;
  p.push_back({"density", "1", with_top ? "lambda of the sub-grids: cells ~ density * triangles of the top cell"
                                        : "lambda of the n^(1/3) rule: cells ~ density * triangles (0 < density <= 1e4)",
               real_in(0, 1e4, Ends::OpenLow)});
  if (with_top) {
    p.push_back({"top", "0.0625", "lambda of the top-level grid (0 < top <= 1e4)", real_in(0, 1e4, Ends::OpenLow)});
    p.push_back({"sub", "fit",
                 "sub-grids: fit (over the bounds of the top cell's small triangles, large ones in a list of the cell) "
                 "or cell (the published rule of Kalojanov, Billeter & Slusallek 2011: over the whole top cell, every "
                 "triangle, resolution by the n^(1/3) rule for the cell's references; density defaults to their 1.2)",
                 one_of({"fit", "cell"})});
  }
  if (with_res) p.push_back({"res", "auto", "explicit resolution AxBxC (overrides density)"});
  p.push_back({"budget", "1024", "memory budget in MiB; exceeding it lowers density (warning)",
               real_in(0, 1024.0 * 1024.0, Ends::OpenLow)});
  p.push_back({"assign", "exact", "triangle-to-cell assignment: exact (SAT, Akenine-Moller 2001) or bbox",
               one_of({"exact", "bbox"})});
  p.push_back(triangle_test_param());
  p.push_back(simd_param("cells' triangles as 4-wide SIMD blocks (tri=watertight)"));
  p.push_back(any_hit_order_param());
  return p;
}

GridOptions parse_grid_options(const Params& p, bool with_res, bool with_top) {
  GridOptions o;
  o.density = p.real("density");
  if (with_top) {
    o.top_density = p.real("top");
    o.whole_cell_subgrids = p.str("sub") == "cell";
    // The published leaf-level density (lambda_2 = 1.2) unless one is given.
    if (o.whole_cell_subgrids && !p.given("density")) o.density = 1.2;
  }
  if (with_res && p.str("res") != "auto") o.res = parse_grid_resolution(p.str("res"));
  o.budget_mib = p.real("budget");
  o.assign = p.str("assign") == "bbox" ? AssignMode::Bbox : AssignMode::Exact;
  o.test = parse_triangle_test(p);
  o.simd = parse_simd(p);
  o.any_hit_order = parse_any_hit_order(p);
  return o;
}

void warn_budget_capped(const std::string& owner, const std::string& requested, const std::string& used,
                        double budget_mib) {
  std::fprintf(stderr, "%s", fmt::format("raylab: warning: {}: {} exceeds the memory budget of {} MiB; using {}\n",
                                         owner, requested, budget_mib, used).c_str());
}

void complete_grid_info(AcceleratorInfo& info) {
  const bool two_level = info.name == "grid2";
  info.caps.mt_variant = "tri=mt";
  info.caps.scalar_variant = "simd=0";
  info.caps.outline = true;
  info.cover = {info.name + ":tri=mt", info.name + ":assign=bbox", info.name + ":simd=0", info.name + ":anyhit=front",
                info.name + ":anyhit=back"};
  info.stats = {{"cells", two_level ? "sub-grid cells" : "cells"},
                {"nonempty_cells", "cells holding at least one triangle"},
                {"empty_fraction", "fraction of empty cells"},
                {"refs", "triangle references in cells"},
                {"refs_per_triangle", "references per triangle"},
                {"mean_tris_per_nonempty_cell", "mean references per non-empty cell"},
                {"max_tris_per_cell", "largest cell, in references"},
                {"lambda", "density used (after the memory cap)"},
                {"lambda_requested", "density asked for"},
                {"budget_capped", "1 when the memory budget lowered the density"},
                {"cell_blocks", "4-wide SIMD triangle blocks of the cells (0 with simd=0 or tri=mt)"}};
  if (!two_level)
    info.stats.insert(info.stats.end(), {{"res_x", "cells along x"}, {"res_y", "cells along y"}, {"res_z", "cells along z"}});
  if (info.name == "hashgrid")
    info.stats.insert(info.stats.end(), {{"hash_capacity", "hash table slots"},
                                         {"hash_load", "occupied slots over capacity"},
                                         {"hash_mean_probes", "mean probes to find a stored cell"},
                                         {"hash_max_probes", "longest probe sequence"}});
  if (two_level) info.cover.push_back(info.name + ":sub=cell");
  if (two_level)
    info.stats.insert(info.stats.end(), {{"top_cells", "top-level cells"},
                                         {"top_res_x", "top cells along x"},
                                         {"top_res_y", "top cells along y"},
                                         {"top_res_z", "top cells along z"},
                                         {"top_lambda", "density of the top grid"},
                                         {"top_refs_per_triangle", "top-level references per triangle"},
                                         {"subgrids", "top cells with a sub-grid"},
                                         {"large_refs", "references kept at the top level (large triangles)"},
                                         {"sub_cells", "cells of all sub-grids"}});
}

}  // namespace raylab
