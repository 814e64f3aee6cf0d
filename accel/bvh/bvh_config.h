#pragma once
// `bvh`'s parameters, declared once. Each row of bvh_parameters() is a
// ParamInfo (name, default, accepted values, help) bound to the BvhConfig
// field it fills, so the registry's parameter list, the spec parser's checks
// and the config's defaults are one table. Presets (`preset=fast|default|
// quality|sbvh`) are assignments to those parameters: a parameter given in
// the spec wins over its preset's value, which wins over the declared
// default. Settings that follow from the parameters (the binary leaf size,
// the reinsertion work, the thick-leaf and size-split thresholds) are
// measured choices, not parameters: bvh_config() derives them.
#include <string>
#include <vector>

#include "accel/core/intersect_triangle.h"
#include "base/spec.h"

namespace raylab {

// Enumerators in the order of their parameter's words (the table maps a
// word to the enumerator of its index).
enum class BvhPreset { Fast, Default, Quality, Sbvh };
enum class BvhBuilder { Binned, Sweep, Sbvh, Lbvh };
enum class BvhOpt { None, Light, Reinsert };
enum class BvhLayout { Auto, Bvh2, Bvh4, Bvh8, Bvh16 };
enum class BvhBound { Box, Sphere };

struct BvhConfig {
  // Parameters (bvh_parameters(); every field is written from its row).
  BvhPreset preset{};
  BvhBuilder builder{};
  BvhOpt opt{};
  BvhLayout layout{};    // never Auto after bvh_config()
  int leaf = 0;          // references per leaf; never 0 (auto) after bvh_config()
  int bins = 0;          // SAH bins per axis for large nodes
  float split_budget = 0;  // sbvh: extra references / triangles
  int spatial_min = 0;   // sbvh: spatial splits tried at nodes of at least this many references
  float node_cost = 0;   // collapse: cost of a node visit
  float block_cost = 0;  // collapse: cost of one block (bvh2: one triangle) test
  TriangleTest tri{};
  int packet = 0;        // 16: closest-hit batches as 16-ray frustum packets
  BvhBound bound{};
  bool simd = false;     // false: wide layouts walked with scalar tests (same hits and counts)

  // Derived by bvh_config() from the parameters above.
  int binary_leaf = 0;       // ranges this small become binary leaves before the collapse
  int opt_rounds = 0;        // reinsertion rounds
  double opt_batch = 0;      // reinsertion: nodes considered per round, a fraction of all nodes
  float big_node = 0;        // binned: size split against the node's area (BuildOptions::big_node)
  float big_root = 0;        // binned: against the root's (BuildOptions::big_root)
  float thick_limit = 0;     // collapse: thick-leaf limit (CollapseOptions::thick_leaf_limit)

  int width() const;  // children per node: 2, 4, 8 or 16
  bool reinsert() const { return opt != BvhOpt::None; }
};

// Fixed settings (measured choices; docs/structures/bvh.md).
inline constexpr int kBvhBlockWidth = 8;             // triangles per SIMD block of the wide layouts
inline constexpr float kBvhSbvhAlpha = 1e-5f;        // sbvh overlap threshold (Stich et al. 2009)
inline constexpr int kBvhSpatialBins = 32;           // sbvh slabs per axis
inline constexpr int kBvhBigMin = 1024;              // size split at nodes of at least this many references
inline constexpr float kBvhThickLeafArea = 0.005f;   // thick leaves count from this fraction of the root's area

// One preset: a name users pick, its parameter assignments ("opt=reinsert"),
// and its measured trade-off against the default (help text).
struct BvhPresetInfo {
  const char* name;
  const char* params;
  const char* tradeoff;
};
const std::vector<BvhPresetInfo>& bvh_presets();

// The declared parameters, in the registry's order.
std::vector<ParamInfo> bvh_parameters();

// The configuration of a checked spec: presets applied, auto values and
// derived settings resolved, combinations checked (SpecError).
BvhConfig bvh_config(const Params& p);

}  // namespace raylab
